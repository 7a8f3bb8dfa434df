//! Scene cost per run: an ensemble whose every run migrates to a spanning support and strikes it
//! (impact, column, checks), for each migration method and column model. The figure of interest
//! is the time per run (criterion's throughput in elements = runs).

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use gangue::calc::Calculation;
use gangue::calc::scene::Scene;
use gangue::physics::Control;
use gangue::physics::column::{ColumnCase, ColumnModel};
use gangue::physics::material::Column;
use gangue::physics::migration::{Method, MigrationCase, MonteCarlo};
use gangue::physics::scene::{DesignLimits, SceneCase, SceneDraws, SupportEntry};
use std::time::Duration;

/// The paper's rock dropped 3.27 m at the top of a 30 m face with a spanning support at its lower
/// end; the hertz_point law so that no run is past the contact capacity.
fn case(method: Method, model: ColumnModel, runs: u64) -> SceneCase {
    let mut m = MigrationCase {
        method,
        monte_carlo: Some(MonteCarlo {
            runs,
            seed: 42,
            ..MonteCarlo::default()
        }),
        ..MigrationCase::default()
    };
    m.face.length = 30.0;
    m.output.events = false;
    let mut column = ColumnCase {
        model,
        modes: Some(if model == ColumnModel::Coupled { 3 } else { 1 }),
        ..ColumnCase::default()
    };
    column.impact.contact.law = gangue::physics::material::ContactLaw::HertzPoint;
    SceneCase {
        migration: m,
        supports: vec![SupportEntry {
            support: 1,
            column_index: 0,
            along_dip: 30.0,
            across: None,
            column: Column::default(),
        }],
        column,
        impact_velocity: None,
        release_zones: None,
        draws: SceneDraws::default(),
        limits: DesignLimits::default(),
        compare_methods: false,
    }
}

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("scene_per_run_1_thread");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    for (method, mname, runs) in [
        (Method::LumpedMass, "lumped_mass", 64),
        (Method::RigidBlock, "rigid_block", 4),
    ] {
        for (model, cname) in [
            (ColumnModel::Decoupled, "decoupled"),
            (ColumnModel::Coupled, "coupled"),
        ] {
            let sc = case(method, model, runs);
            // every run reaches the support and is struck
            let r = Scene::solve(&sc, &Control::unlimited()).unwrap();
            let st = r.result.statistics.as_ref().unwrap();
            assert_eq!(st.entries[0].reached_fraction, 1.0, "{mname} {cname}");
            g.throughput(Throughput::Elements(runs));
            g.bench_with_input(BenchmarkId::new(mname, cname), &sc, |b, sc| {
                b.iter(|| pool.install(|| Scene::solve(sc, &Control::unlimited()).unwrap()))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! Scene cost per run: an ensemble whose every run migrates to a spanning support and strikes it
//! (impact, column, checks), for each migration method and column model; and the rigid block on
//! the paper's face with its 62 column supports against the same number of `/v1/migration` runs.
//! The figure of interest is the time per run (criterion's throughput in elements = runs).
//!
//! With `GANGUE_BENCH_PAPER_RUNS=N` set, the paper's face with its 62 columns is first solved once
//! with N rigid-block runs on 1 and on 2 solver threads (`GANGUE_BENCH_PAPER_THREADS=1` or `=2`:
//! on that many only; `GANGUE_BENCH_PAPER_CASE=spanning` or `=migration`: the face with one
//! spanning support, or the `/v1/migration` runs, instead) and the wall times printed
//! (`GANGUE_BENCH_PAPER_ONLY=1`: nothing else of this group).

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use gangue::calc::Calculation;
use gangue::calc::scene::Scene;
use gangue::physics::Control;
use gangue::physics::column::{ColumnCase, ColumnModel};
use gangue::physics::material::Column;
use gangue::physics::migration::{Distribution, Method, MigrationCase, MonteCarlo, run};
use gangue::physics::scene::{
    DesignLimits, ReleaseZone, SceneCase, SceneDraws, SupportEntry, TABLE1_SHARES, ensemble_part,
};
use std::time::{Duration, Instant};

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
    SceneCase::new(
        m,
        vec![SupportEntry {
            support: 1,
            column_index: 0,
            along_dip: 30.0,
            across: None,
            column: Column::default(),
        }],
        column,
    )
}

/// The rigid block on the paper's 120 m face: released in Table 1's thirds, across U[−1.5, 1.5] m,
/// `runs` runs; with `columns` the paper's 62 supports (#1 at 118.5 m, 1.5 m apart, one column
/// each at y = 0.9 m), else one spanning support at the lower end.
fn paper_face(runs: u64, columns: bool) -> SceneCase {
    let m = MigrationCase {
        method: Method::RigidBlock,
        monte_carlo: Some(MonteCarlo {
            runs,
            seed: 42,
            ..MonteCarlo::default()
        }),
        ..MigrationCase::default()
    };
    let length = m.face.length;
    let supports = if columns {
        (1..=62u32)
            .map(|k| SupportEntry {
                support: k,
                column_index: 0,
                along_dip: 118.5 - f64::from(k - 1) * 1.5,
                across: Some(0.9),
                column: Column::default(),
            })
            .collect()
    } else {
        vec![SupportEntry {
            support: 1,
            column_index: 0,
            along_dip: length,
            across: None,
            column: Column::default(),
        }]
    };
    let third = length / 3.0;
    let mut column = ColumnCase::default();
    column.impact.contact.law = gangue::physics::material::ContactLaw::HertzPoint;
    SceneCase {
        migration: m,
        supports,
        column,
        impact_velocity: None,
        release_zones: Some(
            [
                (0.0, third, TABLE1_SHARES[0]),
                (third, 2.0 * third, TABLE1_SHARES[1]),
                (2.0 * third, length, TABLE1_SHARES[2]),
            ]
            .map(|(from, to, weight)| ReleaseZone { from, to, weight })
            .to_vec(),
        ),
        draws: SceneDraws {
            release_across: Some(Distribution::Uniform {
                min: -1.5,
                max: 1.5,
            }),
            ..SceneDraws::default()
        },
        limits: DesignLimits::default(),
        compare_methods: false,
        allowed_impacts: false,
        release_rate: None,
        guards: Vec::new(),
        device_lines: Vec::new(),
        target: None,
        design: None,
    }
}

/// The rigid block's `/v1/migration` ensemble of `runs` runs (the defaults: released 3.27 m
/// above the top of the 120 m face).
fn migration_runs(runs: u64) -> MigrationCase {
    let mut m = MigrationCase {
        method: Method::RigidBlock,
        monte_carlo: Some(MonteCarlo {
            runs,
            seed: 42,
            ..MonteCarlo::default()
        }),
        ..MigrationCase::default()
    };
    m.output.events = false;
    m
}

/// One timing of `runs` runs on 1 and 2 threads (or `only_threads`), printed: the paper's face
/// with its 62 columns (`what` "columns", with the fraction of runs that reached a column), with
/// one spanning support ("spanning"), or the `/v1/migration` ensemble ("migration").
fn paper_face_timing(runs: u64, only_threads: Option<usize>, what: &str) {
    let sc = paper_face(runs, what != "spanning");
    let mig = migration_runs(runs);
    for threads in [1usize, 2]
        .into_iter()
        .filter(|&t| only_threads.is_none_or(|o| o == t))
    {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let t0 = Instant::now();
        let (reached, answer) = if what == "migration" {
            let r = pool.install(|| run(&mig, &Control::unlimited()).unwrap());
            (0.0, format!("{r:?}"))
        } else {
            let r = pool.install(|| Scene::solve(&sc, &Control::unlimited()).unwrap());
            let st = r.result.statistics.as_ref().unwrap();
            let reached = st.entries.iter().map(|e| e.reached_fraction).sum::<f64>();
            (reached, format!("{r:?}"))
        };
        let secs = t0.elapsed().as_secs_f64();
        // a digest of the whole answer, to compare builds bit for bit
        let mut h = std::hash::DefaultHasher::new();
        std::hash::Hash::hash(&answer, &mut h);
        println!(
            "{what}: {runs} rigid-block runs, {threads} thread(s): {secs:.2} s ({:.1} ms per \
             run), reached a support: {:.1} %, answer digest {:016x}",
            1e3 * secs / runs as f64,
            100.0 * reached,
            std::hash::Hasher::finish(&h)
        );
    }
}

/// The ten costliest of `runs` runs of the paper's face with its 62 columns, each timed alone
/// (`GANGUE_BENCH_PAPER_SLOWEST=1`), printed with how they ended.
fn slowest_runs(runs: u64, columns: bool) {
    let sc = paper_face(runs, columns);
    let mc = sc.migration.monte_carlo.unwrap();
    let (mut steps, mut time) = (0u64, 0.0);
    let mut timed: Vec<(f64, u64, String)> = (0..runs)
        .map(|i| {
            let t0 = Instant::now();
            let (r, _) = ensemble_part(&sc, &mc, i..i + 1, &Control::unlimited()).unwrap();
            let s = &r[0].summary;
            steps += s.steps;
            time += s.time;
            (
                t0.elapsed().as_secs_f64(),
                i,
                format!(
                    "{:?} after {:.2} s, {} steps, runout {:.1} m, {} impacts, speed {:.2} m/s",
                    s.stop_reason, s.time, s.steps, s.runout, s.impact_count, s.speed
                ),
            )
        })
        .collect();
    let total: f64 = timed.iter().map(|t| t.0).sum();
    timed.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!(
        "{runs} runs timed alone: {total:.2} s, {:.0} steps and {:.2} s simulated per run",
        steps as f64 / runs as f64,
        time / runs as f64
    );
    let mut mig = migration_runs(runs);
    mig.output.runs_csv = true;
    let r = run(&mig, &Control::unlimited()).unwrap();
    let rs = r.runs.unwrap();
    let steps: u64 = rs.iter().map(|s| s.steps).sum();
    let time: f64 = rs.iter().map(|s| s.time).sum();
    println!(
        "the same runs of /v1/migration: {:.0} steps and {:.2} s simulated per run",
        steps as f64 / runs as f64,
        time / runs as f64
    );
    for (secs, i, what) in timed.iter().take(10) {
        println!("run {i}: {:.1} ms, {what}", 1e3 * secs);
    }
}

/// The rigid block on the paper's face: 62 column supports, one spanning support, and the same
/// number of `/v1/migration` runs (1 thread).
fn paper_face_bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let runs = 20u64;
    let mut g = c.benchmark_group("rigid_block_paper_face_1_thread");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    g.throughput(Throughput::Elements(runs));
    let mig = migration_runs(runs);
    g.bench_with_input(BenchmarkId::new("migration", runs), &mig, |b, m| {
        b.iter(|| pool.install(|| run(m, &Control::unlimited()).unwrap()))
    });
    for (name, columns) in [("scene_spanning", false), ("scene_62_columns", true)] {
        let sc = paper_face(runs, columns);
        g.bench_with_input(BenchmarkId::new(name, runs), &sc, |b, sc| {
            b.iter(|| pool.install(|| Scene::solve(sc, &Control::unlimited()).unwrap()))
        });
    }
    g.finish();
}

fn bench(c: &mut Criterion) {
    if let Some(n) = std::env::var("GANGUE_BENCH_PAPER_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        let threads = std::env::var("GANGUE_BENCH_PAPER_THREADS")
            .ok()
            .and_then(|v| v.parse().ok());
        if std::env::var_os("GANGUE_BENCH_PAPER_SLOWEST").is_some() {
            slowest_runs(
                n,
                std::env::var("GANGUE_BENCH_PAPER_CASE").as_deref() != Ok("spanning"),
            );
        }
        let what = std::env::var("GANGUE_BENCH_PAPER_CASE").unwrap_or_else(|_| "columns".into());
        paper_face_timing(n, threads, &what);
        if std::env::var_os("GANGUE_BENCH_PAPER_ONLY").is_some() {
            return;
        }
    }
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

criterion_group!(benches, bench, paper_face_bench);
criterion_main!(benches);

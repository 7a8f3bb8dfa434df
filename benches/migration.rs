//! Lumped-mass migration throughput: Monte Carlo trajectories per second on the plane and on
//! gridded floors, on 1 and 2 threads, and the growth of the cost with face length and grid
//! resolution.

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use gangue::calc::Calculation;
use gangue::calc::migration::Migration;
use gangue::physics::Control;
use gangue::physics::migration::{FloorSpec, MigrationCase, MonteCarlo};
use std::time::Duration;

/// A grid of the face (0 ≤ x ≤ S cos θ + 2 m, |y| ≤ 5 m) about the plane, with a deterministic
/// roughness of amplitude `amp` m.
fn face_grid(length: f64, d: f64, amp: f64) -> FloorSpec {
    let th = 45f64.to_radians();
    let nx = ((length * th.cos() + 2.0) / d).ceil() as usize + 1;
    let ny = (10.0 / d).ceil() as usize + 1;
    let mut s = 1u64;
    let heights = (0..ny)
        .map(|_| {
            (0..nx)
                .map(|j| {
                    let r = gangue::physics::migration::monte_carlo::splitmix64(&mut s);
                    let u = (r >> 11) as f64 / 9_007_199_254_740_992.0;
                    -(j as f64 * d) * th.tan() + amp * (u - 0.5)
                })
                .collect()
        })
        .collect();
    FloorSpec::Grid {
        origin: [0.0, -5.0],
        spacing: d,
        heights,
    }
}

fn ensemble(runs: u64, floor: FloorSpec, length: f64) -> MigrationCase {
    let mut c = MigrationCase {
        monte_carlo: Some(MonteCarlo {
            runs,
            seed: 42,
            ..MonteCarlo::default()
        }),
        ..MigrationCase::default()
    };
    c.face.floor = floor;
    c.face.length = length;
    c.output.events = false;
    c
}

/// With `GANGUE_BENCH_PROBE=1`: the closed-form pieces and impacts per run of the first 2 000
/// runs of each floor of `migration_threads` (seed 42), printed before the timings, so that
/// ns per piece follows from a run rate (`RunSummary::steps`, `impact_count`).
fn probe() {
    if std::env::var_os("GANGUE_BENCH_PROBE").is_none() {
        return;
    }
    for (name, floor) in [
        ("plane", FloorSpec::Plane),
        ("grid_0.5m_flat", face_grid(120.0, 0.5, 0.0)),
        ("grid_0.5m_rough_0.1m", face_grid(120.0, 0.5, 0.1)),
    ] {
        let runs = 2_000u64;
        let mut case = ensemble(runs, floor, 120.0);
        case.output.runs_csv = true;
        let r = Migration::solve(&case, &Control::unlimited())
            .unwrap()
            .result;
        let rs = r.runs.expect("runs_csv asks for the runs");
        let pieces: u64 = rs.iter().map(|x| x.steps).sum();
        let impacts: u64 = rs.iter().map(|x| x.impact_count).sum();
        println!(
            "probe {name}: {:.2} pieces per run, {:.2} impacts per run ({runs} runs)",
            pieces as f64 / runs as f64,
            impacts as f64 / runs as f64
        );
    }
}

fn bench(c: &mut Criterion) {
    probe();
    let pools: Vec<_> = [1usize, 2]
        .iter()
        .map(|&n| {
            (
                n,
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap(),
            )
        })
        .collect();
    let ctl = Control::unlimited();

    let mut g = c.benchmark_group("migration_threads");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    for (name, floor, runs) in [
        ("plane", FloorSpec::Plane, 200_000u64),
        ("grid_0.5m_flat", face_grid(120.0, 0.5, 0.0), 20_000),
        ("grid_0.5m_rough_0.1m", face_grid(120.0, 0.5, 0.1), 20_000),
    ] {
        let case = ensemble(runs, floor, 120.0);
        g.throughput(Throughput::Elements(runs));
        for (n, pool) in &pools {
            g.bench_with_input(
                BenchmarkId::new(name, format!("{n}_threads")),
                &case,
                |b, case| b.iter(|| pool.install(|| Migration::solve(case, &ctl).unwrap())),
            );
        }
    }
    g.finish();

    let mut g = c.benchmark_group("migration_face_length");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for length in [30.0, 120.0, 480.0, 1920.0] {
        for (name, floor, runs) in [
            ("plane", FloorSpec::Plane, 100_000u64),
            ("grid_0.5m_rough", face_grid(length, 0.5, 0.1), 5_000),
        ] {
            let case = ensemble(runs, floor, length);
            g.throughput(Throughput::Elements(runs));
            g.bench_with_input(BenchmarkId::new(name, length), &case, |b, case| {
                b.iter(|| pools[0].1.install(|| Migration::solve(case, &ctl).unwrap()))
            });
        }
    }
    g.finish();

    let mut g = c.benchmark_group("migration_grid_spacing");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for d in [2.0, 1.0, 0.5, 0.25, 0.1] {
        let runs = 5_000u64;
        let case = ensemble(runs, face_grid(120.0, d, 0.1), 120.0);
        g.throughput(Throughput::Elements(runs));
        g.bench_with_input(BenchmarkId::new("rough_0.1m", d), &case, |b, case| {
            b.iter(|| pools[0].1.install(|| Migration::solve(case, &ctl).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

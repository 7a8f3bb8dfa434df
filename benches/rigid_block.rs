//! Rigid-block DEM throughput: the 1 s cube slide (P15) and the paper's full scene, contact
//! steps per second, Monte Carlo runs per second on 1 and 2 threads, and the growth of the cost
//! with face length, stiffness and grid resolution.

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use gangue::calc::Calculation;
use gangue::calc::migration::Migration;
use gangue::physics::Control;
use gangue::physics::migration::{Distribution, FloorSpec, Method, MigrationCase, MonteCarlo};
use std::time::Duration;

fn block(length: f64, drop: f64) -> MigrationCase {
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.face.length = length;
    c.release.drop_height = drop;
    c.output.events = false;
    c
}

/// A flat grid of the face plane (0 ≤ x ≤ S cos θ + 2 m, |y| ≤ 2 m) with spacing d.
fn plane_grid(length: f64, d: f64) -> FloorSpec {
    let th = 45f64.to_radians();
    let nx = ((length * th.cos() + 2.0) / d).ceil() as usize + 1;
    let ny = (4.0 / d).ceil() as usize + 1;
    FloorSpec::Grid {
        origin: [0.0, -2.0],
        spacing: d,
        heights: (0..ny)
            .map(|_| (0..nx).map(|j| -(j as f64 * d) * th.tan()).collect())
            .collect(),
    }
}

fn steps_of(c: &MigrationCase) -> u64 {
    Migration::solve(c, &Control::unlimited())
        .unwrap()
        .result
        .rigid_block
        .unwrap()
        .steps
}

/// Error against the analytic slide (physics.md §C.1) at several safety factors, printed before
/// the timings: v(1 s) and the speed at the lower end of the 120 m face, from rest on the floor.
fn accuracy_table() {
    let th = 45f64.to_radians();
    let a = 9.81 * (th.sin() - 0.2 * th.cos());
    let v_end = (2.0 * a * 120.0).sqrt();
    println!("safety | dt (s) | steps 1 s | rel. error v(1 s) | steps 120 m | rel. error v_S");
    for safety in [0.4, 0.2, 0.1, 0.05] {
        let mut c = block(120.0, 0.0);
        c.rigid_block.time_step_safety = safety;
        let full = Migration::solve(&c, &Control::unlimited()).unwrap().result;
        c.end_time = Some(1.0);
        let one = Migration::solve(&c, &Control::unlimited()).unwrap().result;
        let rb1 = one.rigid_block.unwrap();
        println!(
            "{safety} | {:.3e} | {} | {:.2e} | {} | {:.2e}",
            rb1.time_step,
            rb1.steps,
            (one.arrival.along_dip_velocity - a).abs() / a,
            full.rigid_block.unwrap().steps,
            (full.arrival.along_dip_velocity - v_end).abs() / v_end
        );
    }
}

fn bench(c: &mut Criterion) {
    accuracy_table();
    let ctl = Control::unlimited();
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

    // one run: throughput in contact steps
    let mut g = c.benchmark_group("rigid_block_run");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    let mut p15 = block(120.0, 0.0);
    p15.end_time = Some(1.0);
    for (name, case) in [
        ("cube_slide_1s", p15),
        ("paper_scene_120m", block(120.0, 3.27)),
    ] {
        g.throughput(Throughput::Elements(steps_of(&case)));
        g.bench_with_input(BenchmarkId::new(name, "plane"), &case, |b, case| {
            b.iter(|| Migration::solve(case, &ctl).unwrap())
        });
    }
    g.finish();

    // Monte Carlo over μ and β
    let mut g = c.benchmark_group("rigid_block_threads");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    let mut mc = block(120.0, 3.27);
    let runs = 16u64;
    mc.monte_carlo = Some(MonteCarlo {
        runs,
        seed: 42,
        friction_coefficient: Some(Distribution::Uniform {
            min: 0.15,
            max: 0.25,
        }),
        ..MonteCarlo::default()
    });
    mc.rigid_block.critical_damping_ratio_distribution =
        Some(Distribution::Uniform { min: 0.2, max: 0.5 });
    g.throughput(Throughput::Elements(runs));
    for (n, pool) in &pools {
        g.bench_with_input(
            BenchmarkId::new("paper_scene_mc", format!("{n}_threads")),
            &mc,
            |b, case| b.iter(|| pool.install(|| Migration::solve(case, &ctl).unwrap())),
        );
    }
    g.finish();

    // cost against face length, stiffness and grid spacing (1 thread, one run)
    let mut g = c.benchmark_group("rigid_block_face_length");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    for length in [30.0, 120.0, 480.0] {
        let case = block(length, 0.0);
        g.throughput(Throughput::Elements(steps_of(&case)));
        g.bench_with_input(BenchmarkId::new("plane", length), &case, |b, case| {
            b.iter(|| Migration::solve(case, &ctl).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group("rigid_block_stiffness");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    for kn in [1e7, 1e8, 1e9] {
        let mut case = block(120.0, 0.0);
        case.end_time = Some(1.0);
        case.rigid_block.normal_stiffness = kn;
        case.rigid_block.shear_stiffness = kn;
        g.throughput(Throughput::Elements(steps_of(&case)));
        g.bench_with_input(BenchmarkId::new("slide_1s", kn), &case, |b, case| {
            b.iter(|| Migration::solve(case, &ctl).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group("rigid_block_grid_spacing");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    for d in [2.0, 1.0, 0.5, 0.25] {
        let mut case = block(30.0, 0.0);
        case.end_time = Some(1.0);
        // 1 m down the grid, so that the block rests wholly on it (the grid starts at x = 0)
        case.release.along_dip = 1.0;
        case.face.floor = plane_grid(30.0, d);
        g.throughput(Throughput::Elements(steps_of(&case)));
        g.bench_with_input(BenchmarkId::new("flat_slide_1s", d), &case, |b, case| {
            b.iter(|| Migration::solve(case, &ctl).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! Peer benchmark: gangue's rigid-block DEM against rapier3d-f64 0.36 on the analytic sliding
//! cube (physics.md §C.1 and §C.3, P15).
//!
//! Scene: a 0.3 m cube (2500 kg/m³) released at rest face-down on a 45° floor with μ = 0.2 slides
//! down; the analytic answer is v(t) = g (sin θ − μ cos θ) t. Both engines run it in this one
//! process, each at several time steps, on the plane and on a flat triangulated grid of the same
//! plane (rapier: a trimesh with `FIX_INTERNAL_EDGES`). Printed: wall time (best of several
//! repeats), steps, steps/s, relative error of the down-dip speed at the end against the
//! analytic slide, and an energy audit: E_start − (KE + PE) − W_friction, W_friction =
//! μ m g cos θ × distance (the analytic Coulomb work), relative to the energy released
//! m g sin θ × distance. Then Monte Carlo runs/s on 1 and 2 threads and the cost against face
//! length, stiffness (ours) and floor resolution.
//!
//! Run from the repository root: `cargo run --release --manifest-path benches/peer-rapier/Cargo.toml`.

use std::time::{Duration, Instant};

use gangue::physics::Control;
use gangue::physics::migration::{
    Distribution, FloorSpec, Method, MigrationCase, MigrationResult, MonteCarlo, run,
};
use rapier3d_f64::parry::shape::TriMeshFlags;
use rapier3d_f64::prelude::*;
use rayon::prelude::*;

const G: f64 = 9.81;
const MU: f64 = 0.2;
const EDGE: f64 = 0.3;
const DENSITY: f64 = 2500.0;

fn theta() -> f64 {
    45f64.to_radians()
}

/// Analytic sliding acceleration g (sin θ − μ cos θ), m/s².
fn a_slide(mu: f64) -> f64 {
    G * (theta().sin() - mu * theta().cos())
}

/// One engine run: down-dip speed at the end, distance slid, steps, energy residual (relative).
#[derive(Clone, Copy)]
struct Outcome {
    v: f64,
    steps: u64,
    audit: f64,
}

/// Floor of a rapier run.
#[derive(Clone, Copy)]
enum RFloor {
    /// A box whose top face is the plane.
    Plane,
    /// A flat trimesh with this spacing, `FIX_INTERNAL_EDGES`.
    Grid(f64),
}

/// Rapier: the floor plane is y = 0 (x down-dip, y the floor normal) and gravity is tilted by θ,
/// which is the 45° face seen in the floor's frame.
fn rapier_slide(dt: f64, t_end: f64, floor: RFloor, mu: f64, length: f64) -> Outcome {
    let th = theta();
    let gravity = Vector::new(G * th.sin(), -G * th.cos(), 0.0);
    let mut w = PhysicsWorld {
        gravity,
        ..PhysicsWorld::default()
    };
    w.integration_parameters.dt = dt;
    let ground = match floor {
        RFloor::Plane => ColliderBuilder::cuboid(0.5 * length + 5.0, 0.5, 5.0)
            .translation(Vector::new(0.5 * length, -0.5, 0.0)),
        RFloor::Grid(d) => {
            let nx = ((length + 10.0) / d).ceil() as usize + 1;
            let nz = (6.0 / d).ceil() as usize + 1;
            let mut v = Vec::with_capacity(nx * nz);
            for i in 0..nz {
                for j in 0..nx {
                    v.push(Vector::new(-5.0 + j as f64 * d, 0.0, -3.0 + i as f64 * d));
                }
            }
            let mut idx = Vec::new();
            for i in 0..nz - 1 {
                for j in 0..nx - 1 {
                    let a = (i * nx + j) as u32;
                    let b = a + 1;
                    let c = a + nx as u32;
                    let e = c + 1;
                    // counter-clockwise seen from +y
                    idx.push([a, c, b]);
                    idx.push([b, c, e]);
                }
            }
            ColliderBuilder::trimesh_with_flags(v, idx, TriMeshFlags::FIX_INTERNAL_EDGES)
                .expect("a valid grid")
        }
    }
    .friction(mu)
    .restitution(0.0);
    w.insert(RigidBodyBuilder::fixed(), ground);
    let h = 0.5 * EDGE;
    let (cube, _) = w.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, h, 0.0))
            .can_sleep(false),
        ColliderBuilder::cuboid(h, h, h)
            .density(DENSITY)
            .friction(mu)
            .restitution(0.0),
    );
    let m = w.bodies[cube].mass();
    let pe = |p: Vector| -m * gravity.dot(p);
    let p0 = w.bodies[cube].translation();
    let e0 = pe(p0);
    let n = (t_end / dt).round() as u64;
    let mut steps = 0;
    let mut prev = (p0.x, 0.0);
    let mut v_end = None;
    for _ in 0..n {
        w.step();
        steps += 1;
        let b = &w.bodies[cube];
        let (x, v) = (b.translation().x, b.linvel().x);
        if x >= length {
            // the speed where the centre crosses the lower end, interpolated in the step
            let f = (length - prev.0) / (x - prev.0);
            v_end = Some(prev.1 + f * (v - prev.1));
            break;
        }
        prev = (x, v);
    }
    let b = &w.bodies[cube];
    let p = b.translation();
    let dist = p.x - p0.x;
    let e = b.kinetic_energy() + pe(p);
    let wf = mu * m * G * th.cos() * dist;
    let released = m * G * th.sin() * dist;
    Outcome {
        v: v_end.unwrap_or(b.linvel().x),
        steps,
        audit: (e0 - e - wf) / released,
    }
}

/// A flat grid of the face plane (0 ≤ x ≤ S cos θ + 2 m, |y| ≤ 2 m) with spacing d.
fn plane_grid(length: f64, d: f64) -> FloorSpec {
    let th = theta();
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

/// Our case: the cube at rest on the floor at the upper end, sliding until `t_end` (None: to
/// the lower end of a face of `length`).
fn ours_case(t_end: Option<f64>, grid: Option<f64>, length: f64, safety: f64) -> MigrationCase {
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.face.length = length;
    c.face.dip_deg = 45.0;
    c.face.friction_coefficient = MU;
    c.release.drop_height = 0.0;
    c.output.events = false;
    c.end_time = t_end;
    c.rigid_block.time_step_safety = safety;
    // 1 m down from the upper end, so that the block rests wholly on a grid starting there
    c.release.along_dip = 1.0;
    if let Some(d) = grid {
        c.face.floor = plane_grid(length, d);
    }
    c
}

fn ours_outcome(r: &MigrationResult) -> Outcome {
    let rb = r.rigid_block.expect("rigid block");
    let e = &r.energy;
    let dist = r.arrival.along_dip;
    let released = r.mass * G * theta().sin() * dist;
    Outcome {
        v: r.arrival.along_dip_velocity,
        steps: rb.steps,
        audit: e.residual / released,
    }
}

/// Best wall time of `reps` repeats (at least one; repeats until 0.3 s have been spent).
fn time_it<T>(mut f: impl FnMut() -> T) -> (Duration, T) {
    let mut best = Duration::MAX;
    let mut out = None;
    let start = Instant::now();
    let mut reps = 0;
    while reps < 3 || (start.elapsed() < Duration::from_millis(300) && reps < 50) {
        let t = Instant::now();
        let o = f();
        best = best.min(t.elapsed());
        out = Some(o);
        reps += 1;
    }
    (best, out.expect("at least one run"))
}

fn ms(d: Duration) -> String {
    format!("{:.3}", d.as_secs_f64() * 1e3)
}

fn row(engine: &str, floor: &str, dt: f64, wall: Duration, o: &Outcome, v_exact: f64) {
    println!(
        "| {engine} | {floor} | {dt:.3e} | {} | {} | {:.2} | {:.2e} | {:+.2e} |",
        o.steps,
        ms(wall),
        o.steps as f64 / wall.as_secs_f64() / 1e6,
        (o.v - v_exact).abs() / v_exact,
        o.audit
    );
}

fn main() {
    let ctl = Control::unlimited();
    let t_end = 1.0;
    let v1 = a_slide(MU) * t_end;
    println!("# Peer benchmark: sliding cube, 45°, μ = {MU}, 0.3 m, from rest");
    println!();
    println!("## Slide of 1 s (analytic v(1 s) = {v1:.6} m/s)");
    println!();
    println!(
        "| engine | floor | Δt (s) | steps | wall (ms) | M steps/s | rel. error v(1 s) | energy audit |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut best_ours = [Duration::ZERO; 2];
    for (fi, (fname, grid)) in [("plane", None), ("grid 1 m", Some(1.0))]
        .into_iter()
        .enumerate()
    {
        for safety in [0.2, 0.05] {
            let case = ours_case(Some(t_end), grid, 120.0, safety);
            let (wall, r) = time_it(|| run(&case, &ctl).expect("our run"));
            let o = ours_outcome(&r);
            if safety == 0.2 {
                best_ours[fi] = wall;
            }
            row(
                &format!("gangue (safety {safety})"),
                fname,
                r.rigid_block.unwrap().time_step,
                wall,
                &o,
                v1,
            );
        }
        let rf = match grid {
            None => RFloor::Plane,
            Some(d) => RFloor::Grid(d),
        };
        for dt in [1.0 / 60.0, 1.0 / 1000.0, 1.0 / 10000.0] {
            let (wall, o) = time_it(|| rapier_slide(dt, t_end, rf, MU, 120.0));
            row("rapier3d-f64", fname, dt, wall, &o, v1);
        }
    }
    println!();
    println!(
        "Speed ratio at the default safety 0.2 against rapier at Δt = 1/1000 s: see the rows above \
         (wall time of rapier / wall time of gangue)."
    );
    for (fi, (fname, rf)) in [("plane", RFloor::Plane), ("grid 1 m", RFloor::Grid(1.0))]
        .into_iter()
        .enumerate()
    {
        let (wall, _) = time_it(|| rapier_slide(1.0 / 1000.0, t_end, rf, MU, 120.0));
        println!(
            "- {fname}: rapier (1/1000) {} ms / gangue {} ms = {:.1}×",
            ms(wall),
            ms(best_ours[fi]),
            wall.as_secs_f64() / best_ours[fi].as_secs_f64()
        );
    }

    // the whole 120 m face from rest
    let s = 120.0;
    // released 1 m below the upper end: it slides S − 1
    let v_s = (2.0 * a_slide(MU) * (s - 1.0)).sqrt();
    let t_s = v_s / a_slide(MU);
    println!();
    println!(
        "## Slide down the 120 m face from 1 m below its upper end (analytic v = {v_s:.6} m/s at t = {t_s:.4} s)"
    );
    println!();
    println!(
        "| engine | floor | Δt (s) | steps | wall (ms) | M steps/s | rel. error v_S | energy audit |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    {
        let case = ours_case(None, None, s, 0.2);
        let (wall, r) = time_it(|| run(&case, &ctl).expect("our run"));
        row(
            "gangue (safety 0.2)",
            "plane",
            r.rigid_block.unwrap().time_step,
            wall,
            &ours_outcome(&r),
            v_s,
        );
        for dt in [1.0 / 60.0, 1.0 / 1000.0] {
            // rapier runs until the cube's centre has slid S
            let (wall, o) = time_it(|| rapier_slide(dt, 2.0 * t_s, RFloor::Plane, MU, s - 1.0));
            row("rapier3d-f64", "plane", dt, wall, &o, v_s);
        }
        // the same on a flat 1 m grid
        let case = ours_case(None, Some(1.0), s, 0.2);
        let (wall, r) = time_it(|| run(&case, &ctl).expect("our run"));
        row(
            "gangue (safety 0.2)",
            "grid 1 m",
            r.rigid_block.unwrap().time_step,
            wall,
            &ours_outcome(&r),
            v_s,
        );
        let dt = 1.0 / 1000.0;
        let (wall, o) = time_it(|| rapier_slide(dt, 2.0 * t_s, RFloor::Grid(1.0), MU, s - 1.0));
        row("rapier3d-f64", "grid 1 m", dt, wall, &o, v_s);
    }

    // Monte Carlo: μ ~ U[0.15, 0.25], 32 slides of 1 s on the plane
    let runs = 32u64;
    println!();
    println!("## Monte Carlo: {runs} slides of 1 s, μ ~ U[0.15, 0.25], plane");
    println!();
    println!("| engine | threads | wall (ms) | runs/s |");
    println!("|---|---|---|---|");
    let mut mc = ours_case(Some(t_end), None, 120.0, 0.2);
    mc.monte_carlo = Some(MonteCarlo {
        runs,
        seed: 42,
        friction_coefficient: Some(Distribution::Uniform {
            min: 0.15,
            max: 0.25,
        }),
        ..MonteCarlo::default()
    });
    let mus: Vec<f64> = (0..runs)
        .map(|i| 0.15 + 0.1 * (i as f64 + 0.5) / runs as f64)
        .collect();
    for n in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("a pool");
        let (wall, _) = time_it(|| pool.install(|| run(&mc, &ctl).expect("ensemble")));
        // the nominal run is part of an ensemble request: runs + 1
        println!(
            "| gangue (safety 0.2) | {n} | {} | {:.0} |",
            ms(wall),
            (runs + 1) as f64 / wall.as_secs_f64()
        );
        let (wall, _) = time_it(|| {
            pool.install(|| {
                mus.par_iter()
                    .map(|&mu| rapier_slide(1.0 / 1000.0, t_end, RFloor::Plane, mu, 120.0).v)
                    .sum::<f64>()
            })
        });
        println!(
            "| rapier3d-f64 (1/1000) | {n} | {} | {:.0} |",
            ms(wall),
            runs as f64 / wall.as_secs_f64()
        );
    }

    // growth of the cost
    println!();
    println!("## Cost against face length (slide from rest to the lower end, plane)");
    println!();
    println!("| face (m) | gangue steps | gangue (ms) | rapier 1/1000 steps | rapier (ms) |");
    println!("|---|---|---|---|---|");
    for s in [30.0, 120.0, 480.0] {
        let case = ours_case(None, None, s, 0.2);
        let (wall, r) = time_it(|| run(&case, &ctl).expect("our run"));
        let t_s = (2.0 * (s - 1.0) / a_slide(MU)).sqrt();
        let (rw, o) = time_it(|| rapier_slide(1.0 / 1000.0, 2.0 * t_s, RFloor::Plane, MU, s - 1.0));
        println!(
            "| {s} | {} | {} | {} | {} |",
            r.rigid_block.unwrap().steps,
            ms(wall),
            o.steps,
            ms(rw)
        );
    }
    println!();
    println!("## Cost against contact stiffness (gangue, slide of 1 s, plane, safety 0.2)");
    println!();
    println!("| kₙ = kₛ (N/m) | Δt (s) | steps | wall (ms) | rel. error v(1 s) |");
    println!("|---|---|---|---|---|");
    for k in [1e7, 1e8, 1e9] {
        let mut case = ours_case(Some(t_end), None, 120.0, 0.2);
        case.rigid_block.normal_stiffness = k;
        case.rigid_block.shear_stiffness = k;
        let (wall, r) = time_it(|| run(&case, &ctl).expect("our run"));
        let o = ours_outcome(&r);
        println!(
            "| {k:.0e} | {:.3e} | {} | {} | {:.2e} |",
            r.rigid_block.unwrap().time_step,
            o.steps,
            ms(wall),
            (o.v - v1).abs() / v1
        );
    }
    println!();
    println!("## Cost against floor resolution (slide of 1 s, flat grid)");
    println!();
    println!(
        "| spacing (m) | gangue steps | gangue (ms) | gangue error | rapier 1/1000 (ms) | rapier error |"
    );
    println!("|---|---|---|---|---|---|");
    for d in [2.0, 1.0, 0.5, 0.25] {
        let case = ours_case(Some(t_end), Some(d), 30.0, 0.2);
        let (wall, r) = time_it(|| run(&case, &ctl).expect("our run"));
        let o = ours_outcome(&r);
        let (rw, ro) = time_it(|| rapier_slide(1.0 / 1000.0, t_end, RFloor::Grid(d), MU, 30.0));
        println!(
            "| {d} | {} | {} | {:.2e} | {} | {:.2e} |",
            o.steps,
            ms(wall),
            (o.v - v1).abs() / v1,
            ms(rw),
            (ro.v - v1).abs() / v1
        );
    }
}

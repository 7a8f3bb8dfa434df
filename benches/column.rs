//! Column benchmarks: the decoupled closed-form history (10⁴ samples) and the coupled impact's
//! run time against its error over integrator tolerances 1e-4 … 1e-12 (3 modes, base case);
//! the coupled impact with 10 and 50 modes and with the largest damping, and the refusal of a run
//! needing twice its step limit (group `coupled_stiff`).

use std::f64::consts::{E, PI};
use std::hint::black_box;
use std::time::Instant;

use criterion::Criterion;
use gangue::physics::Control;
use gangue::physics::column::{
    ColumnCase, ColumnDetail, ColumnModel, HistoryRequest, solve_column_with_impact,
};
use gangue::physics::contact::{ImpactDetail, ImpactResult, LineImpact};
use gangue::physics::material::{ContactLaw, Damping, ModulusConvention};

/// The base-case rigid impact (paper law, paper E*; physics.md §A.8).
fn base_impact() -> ImpactResult {
    let estar = 5e9 / (1.0 - 0.28f64 * 0.28);
    let (l, r) = (0.3f64, 0.125f64);
    let k = PI * l * estar;
    let p_ref = E * PI * estar * l.powi(3) / r;
    ImpactResult {
        mass: 67.5,
        kinetic_energy: 843.75,
        effective_modulus: estar,
        contact_radius: r,
        law: ContactLaw::Paper,
        modulus: ModulusConvention::Paper,
        detail: ImpactDetail::Line(LineImpact {
            energy_parameter: 1.2732395e-6,
            lambert_w: -17.4322691,
            u: 16.4322691,
            max_deformation: 0.0017933266473674732,
            max_force: 994968.3372475737,
            half_width: 9.8637e-3,
            max_pressure: 214.06e6,
            energy_capacity: p_ref * p_ref / (4.0 * E * E * k),
            deformation_capacity: p_ref / (E * k),
            force_capacity: p_ref / E,
        }),
        contact_duration: 1.1081705e-3,
    }
}

fn coupled_case(tol: f64) -> ColumnCase {
    ColumnCase {
        model: ColumnModel::Coupled,
        modes: Some(3),
        tolerance: tol,
        ..ColumnCase::default()
    }
}

fn benches(c: &mut Criterion) {
    let imp = base_impact();
    let ctl = Control::unlimited();
    let dec = ColumnCase {
        output: HistoryRequest::Uniform {
            duration: Some(0.6),
            samples: Some(10_000),
        },
        ..ColumnCase::default()
    };
    c.bench_function("decoupled_history_1e4_samples", |b| {
        b.iter(|| solve_column_with_impact(black_box(&dec), &imp, &ctl).unwrap())
    });
    for tol in [1e-6, 1e-8] {
        let case = coupled_case(tol);
        c.bench_function(&format!("coupled_3_modes_tol_{tol:e}"), |b| {
            b.iter(|| solve_column_with_impact(black_box(&case), &imp, &ctl).unwrap())
        });
    }
    // Many modes and heavy damping (issue 14): few samples, each run is long.
    let mut g = c.benchmark_group("coupled_stiff");
    g.sample_size(10);
    for n in [10, 50] {
        let case = ColumnCase {
            modes: Some(n),
            ..coupled_case(1e-6)
        };
        g.bench_function(format!("modes_{n}_tol_1e-6"), |b| {
            b.iter(|| solve_column_with_impact(black_box(&case), &imp, &ctl).unwrap())
        });
    }
    // c = 1e9 N·s/m² (the largest accepted): answered or refused, the time until either.
    let mut damped = coupled_case(1e-6);
    damped.impact.column.damping = Damping::Coefficient(1e9);
    g.bench_function("damping_1e9_tol_1e-6", |b| {
        b.iter(|| solve_column_with_impact(black_box(&damped), &imp, &ctl).is_ok())
    });
    // A run needing about twice its step limit (10 modes, tolerance 1e-6): the time until it is
    // refused.
    let mut over = ColumnCase {
        modes: Some(10),
        ..coupled_case(1e-6)
    };
    let needed = match solve_column_with_impact(&over, &imp, &ctl).unwrap().detail {
        ColumnDetail::Coupled(d) => d.steps,
        ColumnDetail::Decoupled(_) => unreachable!(),
    };
    over.max_steps = needed / 2;
    g.bench_function("modes_10_limit_half_the_steps_needed", |b| {
        b.iter(|| solve_column_with_impact(black_box(&over), &imp, &ctl).is_err())
    });
    g.finish();
}

/// CPU time of this thread so far, s (Linux `/proc/thread-self/stat`, 100 ticks/s); `None`
/// elsewhere. The machine may be shared, so CPU time is a fairer measure than wall time.
fn thread_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// Largest relative error of the reported coupled quantities against a run at 1e-13.
fn tolerance_table() {
    let imp = base_impact();
    let ctl = Control::unlimited();
    let get = |tol: f64| {
        let r = solve_column_with_impact(&coupled_case(tol), &imp, &ctl).unwrap();
        match r.detail {
            ColumnDetail::Coupled(d) => d,
            ColumnDetail::Decoupled(_) => unreachable!(),
        }
    };
    let reference = get(1e-13);
    println!("\ncoupled impact, 3 modes, base case (window 50 t_c = 55.4 ms)");
    println!(
        "| tolerance | steps | rejected | wall (ms) | CPU (ms) | max rel. error | energy residual |"
    );
    println!("|---|---|---|---|---|---|---|");
    for tol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12] {
        let d = get(tol);
        // repeat for at least 1.5 s so that the 10 ms CPU-time ticks resolve to 1 %
        let cpu0 = thread_cpu_seconds();
        let start = Instant::now();
        let mut reps = 0usize;
        while reps < 5 || start.elapsed().as_secs_f64() < 1.5 {
            black_box(get(tol));
            reps += 1;
        }
        let ms = start.elapsed().as_secs_f64() * 1e3 / reps as f64;
        let cpu = match (cpu0, thread_cpu_seconds()) {
            (Some(a), Some(b)) => format!("{:.3}", (b - a) * 1e3 / reps as f64),
            _ => "–".into(),
        };
        let e = |a: f64, b: f64| ((a - b) / b).abs();
        let err = [
            e(d.max_force, reference.max_force),
            e(d.max_contact_deformation, reference.max_contact_deformation),
            e(
                d.max_midpoint_displacement,
                reference.max_midpoint_displacement,
            ),
            e(
                d.first_contact_duration.unwrap(),
                reference.first_contact_duration.unwrap(),
            ),
            e(d.rebound_velocity, reference.rebound_velocity),
            e(
                d.column_energy_after_contact,
                reference.column_energy_after_contact,
            ),
        ]
        .into_iter()
        .fold(0.0f64, f64::max);
        println!(
            "| {tol:.0e} | {} | {} | {ms:.3} | {cpu} | {err:.2e} | {:.2e} |",
            d.steps, d.rejected_steps, d.estimated_error
        );
    }
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    benches(&mut c);
    c.final_summary();
    tolerance_table();
}

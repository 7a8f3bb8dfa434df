//! The coupled column's measurements printed for BENCHMARKS.md (not checks): run time against
//! error over integrator tolerances for the heavily damped column (3 and 9 modes) and the
//! many-mode columns (10 and 50 modes, modal and dense flights), and single many-mode runs for a
//! profiler. `cargo bench --bench coupled_tables -- heavily_damped` (or `many_modes`, `profile`;
//! all three without an argument).

use std::f64::consts::{E, PI};

use gangue::physics::Control;
use gangue::physics::beam::Galerkin;
use gangue::physics::contact::ForceLaw;
use gangue::physics::coupled::{
    ContactIntegrator, CoupledInput, CoupledResult, FlightPropagator, solve_coupled,
    solve_coupled_with,
};
use gangue::physics::material::Column;

/// The paper law of the base case (physics.md §A.5): k = πLE*, P_ref = e·πE*L³/R.
fn paper_law() -> ForceLaw {
    let estar = 5e9 / (1.0 - 0.28f64 * 0.28);
    let (l, r) = (0.3, 0.125);
    ForceLaw::Log {
        k: PI * l * estar,
        p_ref: E * PI * estar * l.powi(3) / r,
    }
}

/// The base case (67.5 kg at 5 m/s, paper law, default column) with `n` modes at tolerance
/// `tol`, over 50 rigid contact durations.
fn base_input(n: usize, tol: f64) -> CoupledInput {
    let col = Column::default();
    CoupledInput {
        rock_mass: 67.5,
        velocity: 5.0,
        law: paper_law(),
        galerkin: Galerkin::new(&col, n, 1.0, true).unwrap(),
        column_length: col.length,
        end_time: 50.0 * 1.1081705e-3,
        time_scale: 1.1081705e-3,
        displacement_scale: 1.79332665e-3,
        tolerance: tol,
        sample_times: vec![],
        max_steps: 10_000_000,
    }
}

fn main() {
    // `cargo bench` passes `--bench`; the other arguments choose the tables.
    let chosen: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let wants = |name: &str| chosen.is_empty() || chosen.iter().any(|c| c == name);
    if wants("heavily_damped") {
        heavily_damped_time_against_error();
    }
    if wants("many_modes") {
        many_modes_time_against_error();
    }
    if wants("profile") {
        profile_many_mode_runs();
    }
}

/// Prints one row of a run-time-against-error table: `solve` run `reps` times at tolerance
/// `tol`, its mean time (ms) and the largest relative error of the quantities `key` picks
/// against `reference`, with the steps, rejections, passes and estimated error of the run.
fn print_time_and_error<const K: usize>(
    tol: f64,
    reps: usize,
    reference: &[f64; K],
    key: impl Fn(&CoupledResult) -> [f64; K],
    mut solve: impl FnMut() -> CoupledResult,
) {
    let t0 = std::time::Instant::now();
    let mut r = solve();
    for _ in 1..reps {
        r = solve();
    }
    let ms = t0.elapsed().as_secs_f64() * 1e3 / reps as f64;
    let err = key(&r)
        .iter()
        .zip(reference)
        .map(|(g, e)| ((g - e) / e).abs())
        .fold(0.0f64, f64::max);
    println!(
        "| {tol:e} | {} | {} | {} | {ms:.2} | {err:.2e} | {:.2e} |",
        r.steps, r.rejected_steps, r.passes, r.estimated_error
    );
}

/// Run time against error of the c = 1e9 N·s/m² column (3 and 9 modes, base case): the
/// largest relative error of Pmax, column energy after contact, first contact duration and
/// max |w_mid| against a run at tolerance 1e-12. A measurement printed for BENCHMARKS.md:
/// `cargo bench --bench coupled_tables -- heavily_damped`.
fn heavily_damped_time_against_error() {
    for n in [3usize, 9] {
        let input = |tol: f64| {
            let mut i = base_input(n, tol);
            i.galerkin = Galerkin::new(&Column::default(), n, 1e9, true).unwrap();
            i
        };
        let key = |r: &CoupledResult| {
            [
                r.max_force,
                r.column_energy_after_contact,
                r.first_contact_duration.unwrap(),
                r.max_midpoint_displacement,
            ]
        };
        let reference = key(&solve_coupled(&input(1e-12), &Control::unlimited()).unwrap());
        println!("{n} modes, c = 1e9 N·s/m²");
        for tol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10] {
            let inp = input(tol);
            print_time_and_error(tol, 5, &reference, key, || {
                solve_coupled(&inp, &Control::unlimited()).unwrap()
            });
        }
    }
}

/// Run time against error of the many-mode columns (10 and 50 modes, base case, light
/// damping), modal and dense flights: the largest relative error of Pmax, column energy after
/// contact, first contact duration, max |w_mid| and the clamp curvature against a run at
/// tolerance 1e-11. A measurement printed for BENCHMARKS.md:
/// `cargo bench --bench coupled_tables -- many_modes`.
fn many_modes_time_against_error() {
    for n in [10usize, 50] {
        let key = |r: &CoupledResult| {
            [
                r.max_force,
                r.column_energy_after_contact,
                r.first_contact_duration.unwrap(),
                r.max_midpoint_displacement,
                r.max_curvature_clamp,
            ]
        };
        let run = |tol: f64, flight| {
            solve_coupled_with(
                &base_input(n, tol),
                &Control::unlimited(),
                ContactIntegrator::Auto,
                flight,
            )
            .unwrap()
        };
        let reference = key(&run(1e-11, FlightPropagator::Dense));
        for (name, flight) in [
            ("modal", FlightPropagator::Auto),
            ("dense", FlightPropagator::Dense),
        ] {
            println!("{n} modes, {name} flight");
            for tol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9] {
                let reps = if n == 50 { 2 } else { 5 };
                print_time_and_error(tol, reps, &reference, key, || run(tol, flight));
            }
        }
    }
}

/// One run of 10 and of 50 modes at tolerance 1e-6 with the dense and with the modal flight,
/// for a profiler (`valgrind --tool=callgrind <coupled_tables bench binary> profile`): the inclusive costs of the flight (`free_flight`,
/// `modal_free_flight`) and of the contact phases (`explicit_step`) split the run.
/// `PROFILE_CASE=50-dense` (or `10-modal`, …) runs one case only.
fn profile_many_mode_runs() {
    let only = std::env::var("PROFILE_CASE").ok();
    for n in [10usize, 50] {
        for (name, flight) in [
            ("dense", FlightPropagator::Dense),
            ("modal", FlightPropagator::Auto),
        ] {
            if only.as_ref().is_some_and(|o| *o != format!("{n}-{name}")) {
                continue;
            }
            let r = solve_coupled_with(
                &base_input(n, 1e-6),
                &Control::unlimited(),
                ContactIntegrator::Auto,
                flight,
            )
            .unwrap();
            println!(
                "{n} modes, {flight:?}: {} steps, {} passes",
                r.steps, r.passes
            );
        }
    }
}

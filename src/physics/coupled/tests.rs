//! Unit tests of the coupled model: the free-flight propagator against integration and energy,
//! the exponential contact integrator against Dormand–Prince, the contact energy against
//! quadrature, the base case against physics.md's table, the step estimate against the steps
//! taken, and the state layout.

use std::f64::consts::{E, PI};

use nalgebra::{DMatrix, DVector};

use super::estimate::estimate_steps;
use super::flight::FreeFlight;
use super::system::{ROCK_DISPLACEMENT, ROCK_VELOCITY, StateLayout};
use super::*;
use crate::physics::material::Column;
use crate::physics::numeric::ode::{Dopri5, OdeSystem};

/// The paper law of the base case (physics.md §A.5): k = πLE*, P_ref = e·πE*L³/R.
pub(super) fn paper_law() -> ForceLaw {
    let estar = 5e9 / (1.0 - 0.28f64 * 0.28);
    let (l, r) = (0.3, 0.125);
    ForceLaw::Log {
        k: PI * l * estar,
        p_ref: E * PI * estar * l.powi(3) / r,
    }
}

pub(super) fn base_input(n: usize, tol: f64) -> CoupledInput {
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

/// The free flight of the symmetric (odd-numbered) modes among the first `modes` of `col`
/// with damping `c_coef`: their mass matrix, stiffnesses, dampings and propagator.
fn odd_mode_flight(
    col: &crate::physics::material::Column,
    modes: usize,
    c_coef: f64,
) -> (DMatrix<f64>, Vec<f64>, Vec<f64>, FreeFlight) {
    let g = Galerkin::new(col, modes, c_coef, true).unwrap();
    let act: Vec<usize> = (0..modes).step_by(2).collect();
    let n = act.len();
    let mass = DMatrix::from_fn(n, n, |i, j| g.mass[(act[i], act[j])]);
    let minv = mass.clone().cholesky().unwrap().inverse();
    let k: Vec<f64> = act.iter().map(|&i| g.stiffness[(i, i)]).collect();
    let c: Vec<f64> = act.iter().map(|&i| g.damping[(i, i)]).collect();
    let fmax = crate::physics::beam::generalized_frequencies(
        &mass,
        &DMatrix::from_diagonal(&DVector::from_column_slice(&k)),
    )[n - 1];
    let ff = FreeFlight::new(&minv, &k, &c, 2.0 * std::f64::consts::PI * fmax);
    (mass, k, c, ff)
}

/// The free-flight propagator: Φ and the Gramian against the Taylor series at τ = h, and
/// against a tight Dormand–Prince integration of the same linear system over 200 steps.
#[test]
fn free_flight_propagator_matches_integration() {
    use crate::physics::material::{Column, Damping};
    let col = Column {
        damping: Damping::Coefficient(2e4),
        ..Column::default()
    };
    let (_, _, c, ff) = odd_mode_flight(&col, 5, 2e4);
    let z0 = [1e-3, -2e-4, 5e-5, 0.3, 1.0, -2.0];
    let (zt, dt) = ff.taylor(&z0, ff.h, true);
    let zp = &ff.phi * DVector::from_column_slice(&z0);
    let d = DVector::from_column_slice(&z0).dot(&(&ff.gram * DVector::from_column_slice(&z0)));
    for i in 0..6 {
        assert!((zt[i] - zp[i]).abs() < 1e-13 * (zp[i].abs() + 1e-3), "{i}");
    }
    assert!(((dt - d) / d).abs() < 1e-12, "{dt} vs {d}");
    let (mut out, mut t1, mut t2) = ([0.0; 6], [0.0; 6], [0.0; 6]);
    ff.propagate_into(&z0, 0.37 * ff.h, &mut out, &mut t1, &mut t2);
    let (zq, _) = ff.taylor(&z0, 0.37 * ff.h, false);
    for i in 0..6 {
        assert!((out[i] - zq[i]).abs() < 1e-14 * (zq[i].abs() + 1e-3), "{i}");
    }
    // 200 exact steps against Dormand–Prince at 1e-13.
    struct Lin<'a>(&'a DMatrix<f64>, &'a [f64]);
    impl OdeSystem for Lin<'_> {
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> bool {
            let z = DVector::from_column_slice(&y[..6]);
            let az = self.0 * &z;
            dy[..6].copy_from_slice(az.as_slice());
            dy[6] = (0..3).map(|i| self.1[i] * y[3 + i] * y[3 + i]).sum();
            true
        }
    }
    let mut z = DVector::from_column_slice(&z0);
    let mut dis = 0.0;
    for _ in 0..200 {
        dis += z.dot(&(&ff.gram * &z));
        z = &ff.phi * &z;
    }
    let t_end = 200.0 * ff.h;
    let mut y = z0.to_vec();
    y.push(0.0);
    let mut atol = vec![1e-16; 3];
    atol.extend([1e-13; 3]);
    atol.push(1e-13);
    let mut st = Dopri5::new(1e-13, atol, ff.h / 10.0);
    let sys = Lin(&ff.a, &c);
    let mut t = 0.0;
    while t < t_end {
        t = st.step(&sys, t, &mut y, t_end).unwrap();
    }
    for i in 0..6 {
        assert!(
            (y[i] - z[i]).abs() < 1e-9 * (z[i].abs() + 1e-4),
            "{i}: {} vs {}",
            y[i],
            z[i]
        );
    }
    assert!(((y[6] - dis) / dis).abs() < 1e-9, "{} vs {dis}", y[6]);
}

/// The heavily damped free column (c = 1e9 N·s/m², damping rate·τ up to ~4e3): the doubled
/// propagator against a tight Dormand–Prince integration of the same linear system, and its
/// Gramian against the energy the free column loses (E(0) − E(τ), an independent balance).
#[test]
fn doubled_propagator_of_a_heavily_damped_column_matches_integration_and_energy() {
    use crate::physics::material::Column;
    let col = Column::default();
    for (c_coef, modes) in [(1e9, 3usize), (3e7, 5), (1e9, 9)] {
        let (mass, k, c, ff) = odd_mode_flight(&col, modes, c_coef);
        let n = k.len();
        assert!(ff.damping_rate * ff.h > 2.0, "{c_coef}: not heavily damped");
        let energy = |z: &DVector<f64>| {
            let w = z.rows(0, n);
            let wd = z.rows(n, n);
            0.5 * wd.dot(&(&mass * wd)) + (0..n).map(|j| 0.5 * k[j] * w[j] * w[j]).sum::<f64>()
        };
        let mut z0 = DVector::zeros(2 * n);
        for j in 0..n {
            z0[j] = 1e-4 / (j + 1) as f64;
            z0[n + j] = if j % 2 == 0 { 0.5 } else { -0.3 };
        }
        for tau in [ff.h, 0.37 * ff.h] {
            let (z1, d) = ff.taylor(z0.as_slice(), tau, true);
            let lost = energy(&z0) - energy(&z1);
            assert!(d > 0.0 && z1.iter().all(|v| v.is_finite()));
            assert!(((d - lost) / d).abs() < 1e-9, "{c_coef}: {d} vs {lost}");
            let mut out = vec![0.0; 2 * n];
            let (mut t1, mut t2) = (vec![0.0; 2 * n], vec![0.0; 2 * n]);
            ff.propagate_into(z0.as_slice(), tau, &mut out, &mut t1, &mut t2);
            for i in 0..2 * n {
                assert_eq!(out[i], z1[i]);
            }
            struct Lin<'a>(&'a DMatrix<f64>, &'a [f64], usize);
            impl OdeSystem for Lin<'_> {
                fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> bool {
                    let m = 2 * self.2;
                    let az = self.0 * DVector::from_column_slice(&y[..m]);
                    dy[..m].copy_from_slice(az.as_slice());
                    dy[m] = (0..self.2)
                        .map(|i| self.1[i] * y[self.2 + i] * y[self.2 + i])
                        .sum();
                    true
                }
            }
            let mut y: Vec<f64> = z0.iter().copied().collect();
            y.push(0.0);
            let mut atol = vec![1e-16; n];
            atol.extend(vec![1e-13; n]);
            atol.push(1e-13);
            let mut st = Dopri5::new(1e-12, atol, 1e-9);
            let sys = Lin(&ff.a, &c, n);
            let mut t = 0.0;
            while t < tau {
                t = st.step(&sys, t, &mut y, tau).unwrap();
            }
            for i in 0..2 * n {
                assert!(
                    (y[i] - z1[i]).abs() < 1e-8 * (z1[i].abs() + 1e-9),
                    "{c_coef} {i}: {} vs {}",
                    y[i],
                    z1[i]
                );
            }
            assert!(((y[2 * n] - d) / d).abs() < 1e-8, "{} vs {d}", y[2 * n]);
        }
    }
}

/// The exponential contact integrator against Dormand–Prince (the integrator it replaces)
/// run at a tolerance 1000 times tighter, on heavily damped columns where both finish:
/// c = 1e8 and 1e9 N·s/m², 3 and 9 modes, window 50 contact durations. Pmax, the column
/// energy after contact, the first contact duration, max |w_mid|, the clamp curvature and
/// the dissipated energy agree within 1e-5 relative at tolerance 1e-6 (the dissipated
/// energy, a global quadrature, is the furthest: 8e-6 at 9 modes) and within 1e-7 at
/// tolerance 1e-8 (convergence), and the same number of contacts is found. Physical
/// expectation: the integrator changes, the physics not.
#[test]
fn exponential_contact_matches_dormand_prince_on_heavily_damped_columns() {
    use crate::physics::material::Column;
    for (n, c) in [(3usize, 1e8), (3, 1e9), (9, 1e9)] {
        let input = |tol: f64| {
            let mut i = base_input(n, tol);
            i.galerkin = Galerkin::new(&Column::default(), n, c, true).unwrap();
            i
        };
        let key = |r: &CoupledResult| {
            [
                r.max_force,
                r.column_energy_after_contact,
                r.first_contact_duration.unwrap(),
                r.max_midpoint_displacement,
                r.max_curvature_clamp,
                r.damping_energy,
            ]
        };
        let reference = solve_coupled_with(
            &input(1e-9),
            &Control::unlimited(),
            ContactIntegrator::DormandPrince,
            FlightPropagator::Auto,
        )
        .unwrap();
        for (tol, bound) in [(1e-6, 1e-5), (1e-8, 1e-7)] {
            let exp = solve_coupled(&input(tol), &Control::unlimited()).unwrap();
            // the exponential integrator took the contact: fewer steps than the explicit
            // one (the flight's, 8 per period of the highest mode, are the same in both)
            assert!(
                exp.steps < reference.steps,
                "{n} modes, c = {c:e}: {} vs {} steps",
                exp.steps,
                reference.steps
            );
            assert_eq!(exp.contact_count, reference.contact_count);
            for (k, (g, e)) in key(&exp).iter().zip(key(&reference)).enumerate() {
                assert!(
                    ((g - e) / e).abs() < bound,
                    "{n} modes, c = {c:e}, tol {tol:e}, quantity {k}: {g} vs {e}"
                );
            }
            assert!(
                exp.estimated_error < ACCURACY_TARGET,
                "{}",
                exp.estimated_error
            );
        }
    }
}

/// Contact energy closed form against Gauss–Legendre quadrature of P(δ).
#[test]
fn contact_energy_matches_quadrature() {
    let law = paper_law();
    for dmax in [1e-6, 1e-4, 1.8e-3, 0.1] {
        let mut s = 0.0;
        let n = 4000;
        // midpoint rule on δ = dmax·x², dδ = 2dmax x dx (smooths the log singularity at 0)
        for i in 0..n {
            let x = (i as f64 + 0.5) / n as f64;
            s += law.force(dmax * x * x).unwrap() * 2.0 * dmax * x / n as f64;
        }
        let e = contact_energy(&law, dmax).unwrap();
        assert!(((e - s) / e).abs() < 1e-6, "{dmax}: {e} vs {s}");
    }
    let h = ForceLaw::Hertz { kappa: 1e10 };
    assert!((contact_energy(&h, 1e-3).unwrap() - 0.4 * 1e10 * 1e-3f64.powf(2.5)).abs() < 1e-9);
}

/// physics.md §B.7 table, n = 1 and 3 (P08), at 1e-5 relative; energy balance to tolerance.
#[test]
fn base_case_matches_reference_table() {
    let rows = [
        (
            1usize,
            [
                0.754774, 1.40118e-3, 1.24702e-3, 1.40732e-3, -4.70516, 96.571,
            ],
        ),
        (
            3,
            [
                0.749493, 1.39241e-3, 1.26031e-3, 1.41535e-3, -4.70578, 96.374,
            ],
        ),
    ];
    for (n, exp) in rows {
        let r = solve_coupled(&base_input(n, 1e-10), &Control::unlimited()).unwrap();
        let got = [
            r.max_force / 1e6,
            r.max_contact_deformation,
            r.max_midpoint_displacement,
            r.first_contact_duration.unwrap(),
            r.rebound_velocity,
            r.column_energy_after_contact,
        ];
        for (g, e) in got.iter().zip(exp) {
            // the table has 6 significant digits
            assert!(((g - e) / e).abs() < 1e-5, "n={n}: {got:?} vs {exp:?}");
        }
        assert_eq!(r.contact_count, 1);
        // global energy error of the integrator: within 1e3 × the local tolerance
        assert!(r.energy_residual < 1e-7, "{}", r.energy_residual);
        assert!(r.energy_residual > 0.0);
    }
}

/// The step estimate brackets what the integrator does: the lower bound is below the steps
/// of every pass, and the expected count is within a factor 2 of the last pass's, for 1 to
/// 50 modes (flight dominates the default window of 50 contact durations), and for heavily
/// damped columns (c = 1e7 and 1e9 N·s/m², where the damping rate bounds the contact steps).
#[test]
fn step_estimate_brackets_the_steps_taken() {
    use crate::physics::material::Column;
    for (n, c) in [
        (1usize, 1.0),
        (5, 1.0),
        (20, 1.0),
        (50, 1.0),
        (3, 1e9),
        (9, 1e9),
        (5, 1e7),
    ] {
        let mut input = base_input(n, 1e-9);
        input.galerkin = Galerkin::new(&Column::default(), n, c, true).unwrap();
        let e = estimate_steps(&input).unwrap();
        let r = solve_coupled(&input, &Control::unlimited()).unwrap();
        let steps = r.steps as f64;
        assert!(
            e.lower_bound <= steps,
            "{n} modes: bound {} > {steps}",
            e.lower_bound
        );
        assert!(
            (0.5..2.0).contains(&(steps / e.expected)),
            "{n} modes, c = {c:e}: {steps} steps, expected {}",
            e.expected
        );
    }
}

/// A limit below the lower bound is refused before any step (no `TimedOut` from an
/// expired deadline, which the first 1000 steps would meet): 50 lightly damped modes
/// (Dormand–Prince contacts) and 3 modes at c = 1e9 N·s/m² (exponential contacts, whose
/// bound no longer carries the ~3 700 stability-limited steps of the explicit integrator).
#[test]
fn step_limit_below_the_estimate_is_refused_at_once() {
    use crate::physics::material::Column;
    let mut damped = base_input(3, 1e-9);
    damped.galerkin = Galerkin::new(&Column::default(), 3, 1e9, true).unwrap();
    for mut input in [base_input(50, 1e-9), damped] {
        let e = estimate_steps(&input).unwrap();
        input.max_steps = (0.9 * e.lower_bound) as u64;
        let expired = Control::with_deadline(Some(std::time::Instant::now()));
        match solve_coupled(&input, &expired) {
            Err(PhysicsError::TooManySteps { estimated, limit }) => {
                assert_eq!(estimated, e.expected);
                assert_eq!(limit, input.max_steps as f64);
            }
            other => panic!("expected TooManySteps, got {other:?}"),
        }
    }
}

#[test]
fn state_layout_names_every_slot_once() {
    let layout = StateLayout { n: 3 };
    let mut slots = vec![ROCK_DISPLACEMENT, ROCK_VELOCITY];
    slots.extend((0..3).map(|j| layout.modal_displacement(j)));
    slots.extend((0..3).map(|j| layout.modal_velocity(j)));
    slots.push(layout.dissipated());
    slots.push(layout.work());
    slots.sort_unstable();
    assert_eq!(slots, (0..layout.len()).collect::<Vec<_>>());
    assert_eq!(layout.column(), 2..8);
}

/// The modal flight propagator against the dense exact one (Taylor series of e^{Aτ} and Van
/// Loan's Gramian): the state after τ = h and 0.37h and the dissipated energy, for an undamped
/// column (c = 0: every pair λᵢ + λⱼ = 0 goes through the series of the divided difference),
/// light, moderate and over-damped columns, 3 to 25 active modes. Physical expectation: both
/// are the exact solution of the same linear system.
#[test]
fn modal_propagator_matches_dense_propagator_and_gramian() {
    for (c_coef, modes) in [(0.0, 5usize), (1.0, 19), (2e4, 9), (1e6, 5), (1.0, 49)] {
        let (mass, k, c, ff) = odd_mode_flight(&Column::default(), modes, c_coef);
        let n = k.len();
        let minv = mass.clone().cholesky().unwrap().inverse();
        let diag: Vec<f64> = (0..n).map(|j| mass[(j, j)]).collect();
        let omega = 2.0 * PI / (8.0 * ff.h);
        let Some(mf) = super::modal::ModalFlight::new(&minv, &k, &c, &diag, omega) else {
            panic!("{c_coef}, {modes} modes: decomposition refused");
        };
        let mut z0 = vec![0.0; 2 * n];
        for j in 0..n {
            z0[j] = 1e-4 / ((j + 1) * (j + 1)) as f64;
            z0[n + j] = if j % 2 == 0 { 0.5 } else { -0.3 } / (j + 1) as f64;
        }
        let scale = |z: &[f64]| -> f64 {
            let wd = DVector::from_column_slice(&z[n..]);
            0.5 * wd.dot(&(&mass * &wd)) + (0..n).map(|j| 0.5 * k[j] * z[j] * z[j]).sum::<f64>()
        };
        let e0 = scale(&z0);
        for tau in [ff.h, 0.37 * ff.h, 17.0 * ff.h] {
            let (zd, dd) = if tau <= ff.h {
                ff.taylor(&z0, tau, true)
            } else {
                // 17 full steps of the dense propagator
                let mut z = DVector::from_column_slice(&z0);
                let mut d = 0.0;
                for _ in 0..17 {
                    d += z.dot(&(&ff.gram * &z));
                    z = &ff.phi * &z;
                }
                (z, d)
            };
            let (zm, dm) = mf.propagate(&z0, tau);
            // energy-norm difference relative to the initial energy
            let diff: Vec<f64> = (0..2 * n).map(|i| zm[i] - zd[i]).collect();
            let err = (scale(&diff) / e0).sqrt();
            assert!(err < 1e-10, "{c_coef}, {modes} modes, τ = {tau:e}: {err:e}");
            assert!(
                (dm - dd).abs() <= 1e-10 * e0 + 1e-8 * dd.abs(),
                "{c_coef}, {modes} modes, τ = {tau:e}: D {dm:e} vs {dd:e}"
            );
            // energy never created: E(τ) + D(τ) = E(0)
            assert!(
                ((scale(&zm) + dm - e0) / e0).abs() < 1e-10,
                "{c_coef}, {modes} modes: balance"
            );
        }
    }
}

/// The coupled run with the modal flight against the dense exact flight (the propagator it
/// replaces) and against a run at tolerance 1e-10: 10 and 50 modes (5 and 25 active), the
/// default light damping and a moderate one (c = 2e4 N·s/m²), tolerance 1e-6. Pmax, the
/// column energy after contact, the first contact duration, max |w_mid|, the two curvature
/// maxima and the column's energy plus the dissipated energy agree with the dense flight to 1e-8
/// relative (both exact in flight: only rounding differs) and are no further from the tight
/// run than the dense flight's (the clamp curvature maximum carries the contact phase's error
/// at this tolerance: 4e-5 for 10 modes, 1.2e-3 for 50, the same with either flight), with the
/// same steps and contacts, and the estimated error meets the target.
#[test]
fn modal_flight_matches_dense_flight_on_ten_and_fifty_modes() {
    for (n, c) in [(10usize, 1.0), (50, 1.0), (10, 2e4)] {
        let input = |tol: f64| {
            let mut i = base_input(n, tol);
            i.galerkin = Galerkin::new(&Column::default(), n, c, true).unwrap();
            i
        };
        let key = |r: &CoupledResult| {
            [
                r.max_force,
                r.column_energy_after_contact,
                r.first_contact_duration.unwrap(),
                r.max_midpoint_displacement,
                r.max_curvature_clamp,
                r.max_curvature_midpoint,
                r.column_energy_end + r.damping_energy,
            ]
        };
        let run = |tol: f64, flight| {
            solve_coupled_with(
                &input(tol),
                &Control::unlimited(),
                ContactIntegrator::Auto,
                flight,
            )
            .unwrap()
        };
        let modal = run(1e-6, FlightPropagator::Auto);
        let dense = run(1e-6, FlightPropagator::Dense);
        let tight = run(1e-10, FlightPropagator::Dense);
        assert_eq!(modal.steps, dense.steps, "{n} modes: same steps");
        assert_eq!(modal.contact_count, dense.contact_count);
        assert_eq!(modal.contact_count, tight.contact_count);
        for (q, ((m, d), e)) in key(&modal)
            .iter()
            .zip(key(&dense))
            .zip(key(&tight))
            .enumerate()
        {
            assert!(
                ((m - d) / d).abs() < 1e-8,
                "{n} modes, c {c}, quantity {q}: {m} vs {d}"
            );
            // no less accurate than the dense flight against the tight run
            assert!(
                (m - e).abs() <= (d - e).abs() + 1e-8 * e.abs(),
                "{n} modes, c {c}, quantity {q}: {m} vs {e} (dense {d})"
            );
        }
        assert!(
            modal.estimated_error < ACCURACY_TARGET,
            "{}",
            modal.estimated_error
        );
    }
}

/// A critically damped mode has a double eigenvalue and no basis of eigenvectors: the modal
/// decomposition refuses it (the pass then keeps the dense exact flight). Near it (c within
/// 1e-9 … 1e-3 of critical), and lightly and strongly damped, the decomposition is accepted
/// only where it is accurate: its state and dissipated energy after one step agree with the
/// dense propagator to 1e-9 of the initial energy. One active mode, m = 2 kg, k = 8e6 N/m.
#[test]
fn modal_decomposition_is_refused_for_a_critically_damped_mode() {
    let (m, k) = (2.0f64, 8e6f64);
    let minv = DMatrix::from_element(1, 1, 1.0 / m);
    let critical = 2.0 * (k * m).sqrt();
    let omega = (k / m).sqrt();
    let build = |c: f64| super::modal::ModalFlight::new(&minv, &[k], &[c], &[m], omega);
    assert!(build(critical).is_none(), "critical damping accepted");
    let mut accepted = 0;
    for ratio in [1e-3, 1.0 - 1e-3, 1.0 + 1e-9, 1.0 + 1e-6, 1.0 + 1e-3, 10.0] {
        let c = ratio * critical;
        let Some(mf) = build(c) else { continue };
        accepted += 1;
        let ff = FreeFlight::new(&minv, &[k], &[c], omega);
        let z0 = [1e-4, 0.3];
        let e0 = 0.5 * k * z0[0] * z0[0] + 0.5 * m * z0[1] * z0[1];
        let (zd, dd) = ff.taylor(&z0, ff.h, true);
        let (zm, dm) = mf.propagate(&z0, ff.h);
        let err = 0.5 * k * (zm[0] - zd[0]).powi(2) + 0.5 * m * (zm[1] - zd[1]).powi(2);
        assert!(err.sqrt() < 1e-9 * e0.sqrt(), "c/c_crit = {ratio}: state");
        assert!(
            (dm - dd).abs() < 1e-9 * e0,
            "c/c_crit = {ratio}: {dm} vs {dd}"
        );
    }
    assert!(accepted >= 4, "{accepted}");
}

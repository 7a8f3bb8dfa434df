//! Robustness of the column models over the whole api.md domain: finite results, energies that
//! never increase without a source, errors (not panics) for capacity, step limits, cancellation.

use std::f64::consts::{E, PI};

use gangue::physics::beam::{Galerkin, ModeShapes};
use gangue::physics::column::{
    ColumnCase, ColumnDetail, ColumnModel, ColumnResult, HistoryRequest, solve_column_with_impact,
};
use gangue::physics::contact::{ForceLaw, HertzImpact, ImpactDetail, ImpactResult, LineImpact};
use gangue::physics::coupled::{CoupledInput, solve_coupled};
use gangue::physics::material::{Column, ContactLaw, ContactModel, Damping, ImpactCase, Rock};
use gangue::physics::{Control, Param, PhysicsError};
use proptest::prelude::*;

/// Rigid-column impact of the paper line law (physics.md §A.5) or of the equivalent-radius
/// Hertz law (§A.7), computed here; `None` past the capacity (G > 1).
fn impact_of(case: &ImpactCase) -> Option<ImpactResult> {
    let m = case.rock.mass();
    let v = case.velocity;
    let ke = 0.5 * m * v * v;
    let estar = case.rock.elastic_modulus / (1.0 - case.rock.poisson_ratio.powi(2));
    let (l, r) = (case.rock.side_length, case.column.contact_radius);
    let (detail, tc) = match case.contact.law {
        ContactLaw::HertzPoint => {
            let rc = case.rock.corner_radius;
            let re = (rc * rc * r / (rc + r)).sqrt();
            let kappa = 4.0 / 3.0 * estar * re.sqrt();
            let d = (5.0 * m * v * v / (4.0 * kappa)).powf(0.4);
            let p = kappa * d.powf(1.5);
            (
                ImpactDetail::Hertz(HertzImpact {
                    max_deformation: d,
                    max_force: p,
                    stiffness: kappa,
                    equivalent_radius: re,
                    max_deformation_equivalent_radius: d,
                    axis_ratio: 1.0,
                    semi_axes: [0.0, 0.0],
                    max_pressure: 0.0,
                }),
                2.9432372 * d / v,
            )
        }
        _ => {
            let k = PI * l * estar;
            let p_ref = E * PI * estar * l.powi(3) / r;
            let e_cap = p_ref * p_ref / (4.0 * E * E * k);
            let g = ke / e_cap;
            if g > 1.0 {
                return None;
            }
            let u = -(1.0 + lambert_w::lambert_wm1(-g / E));
            if !u.is_finite() {
                return None;
            }
            let p = p_ref * (-1.0 - u / 2.0).exp();
            let d = p * (2.0 + u) / (2.0 * k);
            (
                ImpactDetail::Line(LineImpact {
                    energy_parameter: g,
                    lambert_w: -1.0 - u,
                    u,
                    max_deformation: d,
                    max_force: p,
                    half_width: 0.0,
                    max_pressure: 0.0,
                    energy_capacity: e_cap,
                    deformation_capacity: p_ref / (E * k),
                    force_capacity: p_ref / E,
                }),
                // rigid contact duration of a linear spring of the secant stiffness: a scale only
                PI * (m * d / p).sqrt(),
            )
        }
    };
    Some(ImpactResult {
        mass: m,
        kinetic_energy: ke,
        effective_modulus: estar,
        contact_radius: r,
        law: case.contact.law,
        modulus: case.contact.modulus,
        detail,
        contact_duration: tc,
    })
}

#[allow(clippy::too_many_arguments)]
fn impact_case(
    v: f64,
    side: f64,
    rho: f64,
    e_rock: f64,
    d1: f64,
    ratio_inner: f64,
    length: f64,
    e_col: f64,
    rho_col: f64,
    r: f64,
    damping: Damping,
    law: ContactLaw,
) -> ImpactCase {
    ImpactCase {
        velocity: v,
        rock: Rock {
            side_length: side,
            density: rho,
            elastic_modulus: e_rock,
            corner_radius: (side / 2.0).min(0.02),
            ..Rock::default()
        },
        column: Column {
            outer_diameter: d1,
            inner_diameter: d1 * ratio_inner,
            length: length.max(side),
            elastic_modulus: e_col,
            density: rho_col,
            contact_radius: r,
            damping,
            ..Column::default()
        },
        contact: ContactModel {
            law,
            ..ContactModel::default()
        },
    }
}

fn damping_strategy() -> impl Strategy<Value = Damping> {
    prop_oneof![
        (0.0f64..1.0).prop_map(|x| Damping::Coefficient(if x < 0.1 {
            0.0
        } else {
            10f64.powf(9.0 * x)
        })),
        (0.0f64..10.0).prop_map(Damping::Ratio),
        Just(Damping::Ratio(1.0)),
        Just(Damping::Coefficient(1e9)),
    ]
}

fn all_finite(r: &ColumnResult) -> bool {
    let mut xs = vec![
        r.damping_coefficient,
        r.modal_mass,
        r.modal_stiffness,
        r.modal_damping,
        r.midpoint_mode_value,
        r.decay_rate,
        r.midpoint_stiffness,
        r.midpoint_mass,
        r.kinetic_energy,
        r.max_bending_stress.clamp,
        r.max_bending_stress.midpoint,
        r.stress_utilisation,
    ];
    xs.extend(&r.natural_frequencies_hz);
    xs.extend(&r.damping_ratios);
    xs.extend(r.decay_time_1pct);
    if let Some(h) = &r.history {
        for a in [
            &h.time,
            &h.midpoint_displacement,
            &h.kinetic_energy,
            &h.strain_energy,
            &h.dissipated_energy,
        ] {
            xs.extend(a);
        }
    }
    match r.detail {
        ColumnDetail::Decoupled(d) => xs.extend([
            d.max_deformation,
            d.max_force,
            d.initial_modal_displacement,
            d.absorbed_energy,
            d.energy_ratio,
        ]),
        ColumnDetail::Coupled(d) => xs.extend([
            d.max_force,
            d.max_contact_deformation,
            d.max_midpoint_displacement,
            d.rebound_velocity,
            d.column_energy_after_contact,
            d.energy_ratio,
            d.rock_velocity_end,
            d.column_energy_end,
            d.damping_energy,
            d.estimated_error,
        ]),
    }
    xs.iter().all(|x| x.is_finite())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Decoupled over the whole domain: finite; T + U never increases, D never decreases,
    /// T + U + D = U₀ to 1e-9 relative.
    #[test]
    fn decoupled_is_finite_and_dissipative(
        v in 1e-3f64..1000.0, side in 0.01f64..5.0, rho in 100.0f64..20000.0,
        le in 7.0f64..12.0, d1 in 0.01f64..2.0, ri in 0.0f64..0.999, length in 0.1f64..20.0,
        lec in 9.0f64..12.0, rho_col in 100.0f64..20000.0, r in 0.001f64..10.0,
        damping in damping_strategy(), shapes in 0usize..3, rotary in any::<bool>(),
        w_init in prop::option::of(1e-9f64..1.0),
    ) {
        let case = impact_case(v, side, rho, 10f64.powf(le), d1, ri, length, 10f64.powf(lec),
                               rho_col, r, damping, ContactLaw::Paper);
        let Some(imp) = impact_of(&case) else { return Ok(()) };
        let shapes = [ModeShapes::Exact, ModeShapes::Paper, ModeShapes::Approx][shapes];
        let mut times: Vec<f64> = (0..60).map(|i| if i == 0 { 0.0 } else { 1e-8 * 1.6f64.powi(i) }).collect();
        times.push(1e6);
        let cc = ColumnCase {
            impact: case,
            mode_shapes: shapes,
            rotary_inertia: rotary,
            initial_midpoint_displacement: w_init,
            output: HistoryRequest::Times(times),
            ..ColumnCase::default()
        };
        let res = solve_column_with_impact(&cc, &imp, &Control::unlimited()).unwrap();
        prop_assert!(all_finite(&res));
        let ColumnDetail::Decoupled(d) = res.detail else { panic!() };
        let h = res.history.unwrap();
        let u0 = d.absorbed_energy;
        for i in 0..h.time.len() {
            let e = h.kinetic_energy[i] + h.strain_energy[i];
            prop_assert!(((e + h.dissipated_energy[i]) - u0).abs() <= 1e-9 * u0,
                         "t={} sum={} U0={}", h.time[i], e + h.dissipated_energy[i], u0);
            if i > 0 {
                let e_prev = h.kinetic_energy[i - 1] + h.strain_energy[i - 1];
                prop_assert!(e <= e_prev + 1e-12 * u0);
                prop_assert!(h.dissipated_energy[i] >= h.dissipated_energy[i - 1] - 1e-12 * u0);
            }
        }
        if let Some(t) = res.decay_time_1pct { prop_assert!(t > 0.0) }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Coupled over a wide domain (n ≤ 8 modes, 10 rigid contact durations): finite, the energy
    /// balance holds to the tolerance, the column never holds more than the rock brought and the
    /// force never exceeds the rigid-column maximum.
    #[test]
    fn coupled_is_finite_and_conservative(
        v in 0.1f64..50.0, side in 0.05f64..1.0, rho in 1000.0f64..5000.0,
        le in 8.0f64..11.0, d1 in 0.05f64..0.6, ri in 0.0f64..0.95, length in 0.5f64..5.0,
        r in 0.02f64..0.5, damping in damping_strategy(), n in 1usize..9,
        hertz in any::<bool>(),
    ) {
        let law = if hertz { ContactLaw::HertzPoint } else { ContactLaw::Paper };
        let case = impact_case(v, side, rho, 10f64.powf(le), d1, ri, length, 208e9, 7850.0, r,
                               damping, law);
        let Some(imp) = impact_of(&case) else { return Ok(()) };
        let cc = ColumnCase {
            impact: case,
            model: ColumnModel::Coupled,
            modes: Some(n),
            end_time: Some(10.0 * imp.contact_duration),
            output: HistoryRequest::Uniform { duration: None, samples: Some(50) },
            tolerance: 1e-8,
            ..ColumnCase::default()
        };
        let res = solve_column_with_impact(&cc, &imp, &Control::unlimited()).unwrap();
        prop_assert!(all_finite(&res));
        let ColumnDetail::Coupled(d) = res.detail else { panic!() };
        let ke = res.kinetic_energy;
        prop_assert!(d.estimated_error < 1e-5, "energy residual {}", d.estimated_error);
        prop_assert!(d.column_energy_after_contact <= ke * (1.0 + 1e-6));
        let rigid_p = match imp.detail {
            ImpactDetail::Line(l) => l.max_force,
            ImpactDetail::Hertz(h) => h.max_force,
        };
        prop_assert!(d.max_force <= rigid_p * (1.0 + 1e-6), "{} > {}", d.max_force, rigid_p);
        let h = res.history.unwrap();
        // The dissipated energy is an integrated state of an explicit integrator: on stiff, heavily
        // damped cases its stage weights can make it dip by rounding-level amounts, bounded by the
        // integrator tolerance (here 1e-8), never more.
        for w in h.dissipated_energy.windows(2) { prop_assert!(w[1] >= w[0] - 1e-8 * ke) }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// Energy is never created over the whole damping range, c from 0 to the 1e9 N·s/m²
    /// maximum (log-uniform, and both ends), 1 to 9 modes, a window of 20 rigid contact
    /// durations (mostly free flight, which heavily damped columns now cross by the exact
    /// propagator). Physical expectation: at every history sample the rock's kinetic energy, the
    /// contact energy, the column's kinetic and strain energies and the dissipated energy add up
    /// to at most the initial kinetic energy (within the integrator's tolerance), the dissipated
    /// energy never decreases, and the run's own error estimate (the rock's balance and the
    /// column's E_col + D = W) is within the 1e-5 accuracy target. Longer:
    /// `PROPTEST_CASES=500 cargo test --test stability_column energy_is_never_created`.
    #[test]
    fn energy_is_never_created_over_the_whole_damping_range(
        v in 0.5f64..20.0, x in 0.0f64..1.0, end in prop_oneof![Just(0usize), Just(1), 2usize..4],
        n in 1usize..10, hertz in any::<bool>(),
    ) {
        let c = match end { 0 => 0.0, 1 => 1e9, _ => 10f64.powf(9.0 * x) };
        let law = if hertz { ContactLaw::HertzPoint } else { ContactLaw::Paper };
        let case = impact_case(v, 0.3, 2500.0, 1e10, 0.25, 0.94, 1.31, 208e9, 7850.0, 0.125,
                               Damping::Coefficient(c), law);
        let Some(imp) = impact_of(&case) else { return Ok(()) };
        let cc = ColumnCase {
            impact: case,
            model: ColumnModel::Coupled,
            modes: Some(n),
            end_time: Some(20.0 * imp.contact_duration),
            output: HistoryRequest::Uniform { duration: None, samples: Some(200) },
            tolerance: 1e-7,
            ..ColumnCase::default()
        };
        let res = solve_column_with_impact(&cc, &imp, &Control::unlimited()).unwrap();
        prop_assert!(all_finite(&res));
        let ColumnDetail::Coupled(d) = res.detail else { panic!() };
        let ke = res.kinetic_energy;
        prop_assert!(d.estimated_error < 1e-5, "c = {c:e}: estimated error {}", d.estimated_error);
        let h = res.history.unwrap();
        let rock = h.rock.unwrap();
        for i in 0..h.time.len() {
            let total = rock.rock_kinetic_energy[i] + rock.contact_energy[i] + h.kinetic_energy[i]
                + h.strain_energy[i] + h.dissipated_energy[i];
            prop_assert!(total <= ke * (1.0 + 1e-5), "c = {c:e}, t = {}: {total} > {ke}", h.time[i]);
        }
        for w in h.dissipated_energy.windows(2) { prop_assert!(w[1] >= w[0] - 1e-7 * ke) }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Energy is never created and the balances close over random damping across the whole
    /// range (c log-uniform over 1..1e9 N·s/m², and both ends 0 and 1e9) and 1 to 50 modes,
    /// where heavily damped columns take their contacts with the exponential integrator. The
    /// window is 10 rigid contact durations (the free flight of 50 modes costs 8 steps per
    /// period of mode 49, O(n) each in modal coordinates, the dense propagator where the modal
    /// decomposition is refused), so flights and re-contacts are exercised. Physical expectation: at
    /// every history sample the rock's kinetic energy, the contact energy, the column's energies
    /// and the dissipated energy add up to at most the initial kinetic energy (within the
    /// integrator's tolerance), the dissipated energy never decreases, and the run's own error
    /// estimate (the rock's balance and the column's E_col + D = W) is within the 1e-5
    /// accuracy target. Longer:
    /// `PROPTEST_CASES=200 cargo test --test stability_column balances_close_for_up_to_fifty`.
    #[test]
    fn balances_close_for_up_to_fifty_modes_over_the_whole_damping_range(
        v in 0.5f64..20.0, x in 0.0f64..1.0, end in prop_oneof![Just(0usize), Just(1), 2usize..5],
        n in 1usize..=50, hertz in any::<bool>(),
    ) {
        let c = match end { 0 => 0.0, 1 => 1e9, _ => 10f64.powf(9.0 * x) };
        let law = if hertz { ContactLaw::HertzPoint } else { ContactLaw::Paper };
        let case = impact_case(v, 0.3, 2500.0, 1e10, 0.25, 0.94, 1.31, 208e9, 7850.0, 0.125,
                               Damping::Coefficient(c), law);
        let Some(imp) = impact_of(&case) else { return Ok(()) };
        let cc = ColumnCase {
            impact: case,
            model: ColumnModel::Coupled,
            modes: Some(n),
            end_time: Some(10.0 * imp.contact_duration),
            output: HistoryRequest::Uniform { duration: None, samples: Some(60) },
            tolerance: 1e-6,
            ..ColumnCase::default()
        };
        let res = solve_column_with_impact(&cc, &imp, &Control::unlimited()).unwrap();
        prop_assert!(all_finite(&res));
        let ColumnDetail::Coupled(d) = res.detail else { panic!() };
        let ke = res.kinetic_energy;
        prop_assert!(d.estimated_error < 1e-5, "c = {c:e}, {n} modes: estimated error {}",
                     d.estimated_error);
        prop_assert!(d.column_energy_after_contact <= ke * (1.0 + 1e-6));
        let h = res.history.unwrap();
        let rock = h.rock.unwrap();
        for i in 0..h.time.len() {
            let total = rock.rock_kinetic_energy[i] + rock.contact_energy[i] + h.kinetic_energy[i]
                + h.strain_energy[i] + h.dissipated_energy[i];
            prop_assert!(total <= ke * (1.0 + 1e-5),
                         "c = {c:e}, {n} modes, t = {}: {total} > {ke}", h.time[i]);
            prop_assert!(h.dissipated_energy[i] >= 0.0);
        }
        for w in h.dissipated_energy.windows(2) { prop_assert!(w[1] >= w[0] - 1e-6 * ke) }
    }
}

/// An approach that reaches δ_cap is `CapacityExceeded`, not a panic or a hang.
#[test]
fn coupled_capacity_is_an_error() {
    let estar = 5e9 / (1.0 - 0.28f64 * 0.28);
    let (l, r) = (0.3f64, 0.125f64);
    let k = PI * l * estar;
    let p_ref = E * PI * estar * l.powi(3) / r;
    let e_cap = p_ref * p_ref / (4.0 * E * E * k);
    let m = 67.5;
    let v = (2.0 * 1.5 * e_cap / m).sqrt(); // 1.5 × the storable energy
    // a massive, stiff column that barely yields
    let col = Column {
        outer_diameter: 2.0,
        inner_diameter: 0.0,
        length: 0.3,
        elastic_modulus: 1e12,
        density: 20000.0,
        ..Column::default()
    };
    let input = CoupledInput {
        rock_mass: m,
        velocity: v,
        law: ForceLaw::Log { k, p_ref },
        galerkin: Galerkin::new(&col, 3, 1.0, true).unwrap(),
        column_length: col.length,
        end_time: 0.05,
        time_scale: 1e-3,
        displacement_scale: 0.1,
        tolerance: 1e-8,
        sample_times: vec![],
        max_steps: 1_000_000,
    };
    match solve_coupled(&input, &Control::unlimited()) {
        Err(PhysicsError::CapacityExceeded {
            energy_parameter, ..
        }) => {
            assert!((energy_parameter - 1.5).abs() < 1e-12)
        }
        other => panic!("expected capacity_exceeded, got {other:?}"),
    }
}

fn base_coupled() -> (ColumnCase, ImpactResult) {
    let case = ColumnCase {
        model: ColumnModel::Coupled,
        ..ColumnCase::default()
    };
    let imp = impact_of(&case.impact).unwrap();
    (case, imp)
}

/// Step limit, cancellation and deadline are reported as errors.
#[test]
fn coupled_limits_and_control() {
    let (case, imp) = base_coupled();
    let limited = ColumnCase {
        max_steps: 100,
        ..case.clone()
    };
    assert!(matches!(
        solve_column_with_impact(&limited, &imp, &Control::unlimited()),
        Err(PhysicsError::TooManySteps { .. })
    ));
    let c = Control::unlimited();
    c.cancel();
    assert!(matches!(
        solve_column_with_impact(&case, &imp, &c),
        Err(PhysicsError::Cancelled)
    ));
    let past = Control::with_deadline(Some(std::time::Instant::now()));
    assert!(matches!(
        solve_column_with_impact(&case, &imp, &past),
        Err(PhysicsError::TimedOut)
    ));
}

/// Option combinations api.md rejects are `InvalidInput` at the right pointer.
#[test]
fn invalid_combinations() {
    let (case, imp) = base_coupled();
    let field = |c: &ColumnCase| match solve_column_with_impact(c, &imp, &Control::unlimited()) {
        Err(PhysicsError::InvalidInput { param, .. }) => param,
        other => panic!("expected invalid input, got {other:?}"),
    };
    let paper = ColumnCase {
        mode_shapes: ModeShapes::Paper,
        ..case.clone()
    };
    assert_eq!(field(&paper), Param::ModeShapes);
    let w = ColumnCase {
        initial_midpoint_displacement: Some(1e-3),
        ..case.clone()
    };
    assert_eq!(field(&w), Param::InitialMidpointDisplacement);
    let many = ColumnCase {
        modes: Some(51),
        ..case.clone()
    };
    assert_eq!(field(&many), Param::GalerkinModes);
    let late = ColumnCase {
        output: HistoryRequest::Times(vec![0.0, 1.0]),
        ..case.clone()
    };
    assert_eq!(field(&late), Param::HistoryTime(1));
    let dec = ColumnCase {
        model: ColumnModel::Decoupled,
        modes: Some(3),
        ..case.clone()
    };
    assert_eq!(field(&dec), Param::GalerkinModes);
    let dec_end = ColumnCase {
        model: ColumnModel::Decoupled,
        end_time: Some(0.1),
        ..case.clone()
    };
    assert_eq!(field(&dec_end), Param::CoupledWindow);
    let no_duration = ColumnCase {
        model: ColumnModel::Decoupled,
        output: HistoryRequest::Uniform {
            duration: None,
            samples: Some(10),
        },
        ..case
    };
    assert_eq!(field(&no_duration), Param::HistoryDuration);
}

/// 50 modes at a stubby, heavily damped column: finite, conservative.
#[test]
fn fifty_modes_heavy_damping() {
    let (mut case, imp) = base_coupled();
    case.modes = Some(50);
    case.impact.column.damping = Damping::Ratio(10.0);
    case.tolerance = 1e-7;
    case.end_time = Some(5.0 * imp.contact_duration);
    let r = solve_column_with_impact(&case, &imp, &Control::unlimited()).unwrap();
    assert!(all_finite(&r));
    assert_eq!(r.natural_frequencies_hz.len(), 50);
    let ColumnDetail::Coupled(d) = r.detail else {
        panic!()
    };
    assert!(d.estimated_error < 1e-5, "{}", d.estimated_error);
}

/// A coupled run needing about twice its step limit is refused with an honest count. Physical
/// expectation: once the rock has rebounded beyond the reach of the column's energy
/// (|w_mid| ≤ √(2·E_col·φᵀK⁻¹φ)), it never touches the column again, so the rest of the
/// window is the free propagator's fixed steps; the refusal names the pass's true step count
/// (within 2 %), not an extrapolation from a limit reached late in the window.
#[test]
fn coupled_run_needing_twice_the_step_limit_is_refused_with_its_true_count() {
    let (mut case, imp) = base_coupled();
    case.modes = Some(10);
    case.tolerance = 1e-6;
    let r = solve_column_with_impact(&case, &imp, &Control::unlimited()).unwrap();
    let ColumnDetail::Coupled(d) = r.detail else {
        panic!()
    };
    let needed = d.steps as f64;
    eprintln!("needed {needed} steps, {} contacts", d.contact_count);
    case.max_steps = (needed / 2.0) as u64;
    match solve_column_with_impact(&case, &imp, &Control::unlimited()) {
        Err(PhysicsError::TooManySteps { estimated, limit }) => {
            eprintln!("estimated {estimated}, limit {limit}");
            assert_eq!(limit, case.max_steps as f64);
            assert!(
                (estimated / needed - 1.0).abs() < 0.02,
                "estimated {estimated}, needed {needed}"
            );
        }
        other => panic!("expected TooManySteps, got {other:?}"),
    }
}

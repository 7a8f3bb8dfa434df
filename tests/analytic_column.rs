//! Column dynamics against independent references: the verification cases P05–P08, closed
//! forms, direct integration, the physics.md §B.7 convergence table and the 50-digit reference
//! implementation (`tests/data/column_reference.json`, produced by
//! `shared/reference/reference.py` for random inputs of kinds `decoupled` and `coupled`).

use std::f64::consts::{E, PI};

use gangue::physics::Control;
use gangue::physics::beam::{FreeVibration, ModeShapes};
use gangue::physics::column::{
    ColumnCase, ColumnDetail, ColumnModel, ColumnResult, HistoryRequest, solve_column_with_impact,
};
use gangue::physics::contact::{ImpactDetail, ImpactResult, LineImpact};
use gangue::physics::material::{
    Column, ContactLaw, ContactModel, Damping, ImpactCase, ModulusConvention, Rock,
};
use gangue::physics::numeric::ode::{Dopri5, OdeSystem};

fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}

fn close(name: &str, got: f64, want: f64, rtol: f64, atol: f64) {
    assert!(
        (got - want).abs() <= atol + rtol * want.abs(),
        "{name}: got {got:e}, want {want:e} (rel {:e})",
        rel(got, want)
    );
}

/// The rigid-column impact of a log line law, computed here independently of the contact module
/// (physics.md §A.5 with the `lambert_w` crate's W₋₁; t_c by Gauss–Legendre quadrature of §A.6).
fn line_impact(case: &ImpactCase) -> ImpactResult {
    let m = case.rock.mass();
    let v = case.velocity;
    let ke = 0.5 * m * v * v;
    let (er, nr) = (case.rock.elastic_modulus, case.rock.poisson_ratio);
    let estar = match case.contact.modulus {
        ModulusConvention::Paper => er / (1.0 - nr * nr),
        ModulusConvention::TwoBody => {
            let c = &case.column;
            1.0 / ((1.0 - nr * nr) / er + (1.0 - c.poisson_ratio.powi(2)) / c.elastic_modulus)
        }
    };
    let (l, r) = (case.rock.side_length, case.column.contact_radius);
    let k = PI * l * estar;
    let p_ref = match case.contact.law {
        ContactLaw::Paper => E * PI * estar * l.powi(3) / r,
        _ => 4.0 * PI * l * estar * r / E,
    };
    let e_cap = p_ref * p_ref / (4.0 * E * E * k);
    let g = ke / e_cap;
    let u_of = |g: f64| -(1.0 + lambert_w::lambert_wm1(-g / E));
    let u = u_of(g);
    let pmax = p_ref * (-1.0 - u / 2.0).exp();
    let dmax = pmax * (2.0 + u) / (2.0 * k);
    // t_c = 2mv ∫₀^{π/2} sinθ/P(θ) dθ, θ = (π/2)s², composite midpoint in s.
    let n = 4000;
    let mut tc = 0.0;
    for i in 0..n {
        let s = (i as f64 + 0.5) / n as f64;
        let th = 0.5 * PI * s * s;
        let p = p_ref * (-1.0 - u_of(g * th.sin().powi(2)) / 2.0).exp();
        tc += th.sin() / p * PI * s / n as f64;
    }
    tc *= 2.0 * m * v;
    ImpactResult {
        mass: m,
        kinetic_energy: ke,
        effective_modulus: estar,
        contact_radius: r,
        law: case.contact.law,
        modulus: case.contact.modulus,
        detail: ImpactDetail::Line(LineImpact {
            energy_parameter: g,
            lambert_w: -1.0 - u,
            u,
            max_deformation: dmax,
            max_force: pmax,
            half_width: 2.0 * (pmax * r / (PI * l * estar)).sqrt(),
            max_pressure: 0.0,
            energy_capacity: e_cap,
            deformation_capacity: p_ref / (E * k),
            force_capacity: p_ref / E,
        }),
        contact_duration: tc,
    }
}

fn run(case: &ColumnCase) -> ColumnResult {
    let imp = line_impact(&case.impact);
    solve_column_with_impact(case, &imp, &Control::unlimited()).unwrap()
}

/// P05 and P06 (exact and paper shapes), all expected values at 1e-9.
#[test]
fn p05_p06_mode_coefficients() {
    let cases: [(ModeShapes, [f64; 19]); 2] = [
        (
            ModeShapes::Exact,
            [
                61.85689848982988,
                1.31,
                1947065540.6183121,
                1.5881462620646052,
                1.0,
                12.302618622966003,
                500.5639017404326,
                0.005713771638716441,
                4.204086038549332e-05,
                44.85310736392407,
                0.3300207540261225,
                8744498.960182609,
                1.0,
                892.9278048201711,
                1.8873695512596619e-06,
                0.010588956381440478,
                434.9031217145899,
                771968495.960556,
                24.524894460827817,
            ],
        ),
        (
            ModeShapes::Paper,
            [
                61.85737793542303,
                1.31001128434,
                1947015218.4511666,
                1.588,
                1.000008614,
                12.30251267,
                500.5509646,
                0.005713771638716441,
                4.204086038549332e-05,
                44.85310736392407,
                0.3300207540261225,
                8744498.960182609,
                1.0,
                892.9128054021294,
                1.8874028848965903e-06,
                0.010588965520876157,
                434.90274634561735,
                772090750.8657368,
                24.52960250343533,
            ],
        ),
    ];
    for (shapes, want) in cases {
        let r = run(&ColumnCase {
            mode_shapes: shapes,
            ..ColumnCase::default()
        });
        let got = [
            r.modal_mass,
            r.modal_damping,
            r.modal_stiffness,
            r.midpoint_mode_value,
            r.mode_integrals.mass,
            r.mode_integrals.rotary,
            r.mode_integrals.stiffness,
            r.section.area,
            r.section.second_moment,
            r.section.mass_per_length,
            r.section.rotary_inertia,
            r.section.bending_stiffness,
            r.damping_coefficient,
            r.natural_frequencies_hz[0],
            r.damping_ratios[0],
            r.decay_rate,
            r.decay_time_1pct.unwrap(),
            r.midpoint_stiffness,
            r.midpoint_mass,
        ];
        for (i, (g, w)) in got.iter().zip(want).enumerate() {
            close(&format!("{shapes:?}[{i}]"), *g, w, 1e-9, 0.0);
        }
        assert!(r.warnings.iter().any(|w| w.code == "paper_damping"));
    }
}

/// P07: the decoupled base case with its history (closed forms 1e-9, history 1e-7 + 1e-9·U₀).
#[test]
fn p07_decoupled_base() {
    let r = run(&ColumnCase {
        output: HistoryRequest::Times(vec![0.0, 1e-4, 1e-3, 0.01, 0.6]),
        ..ColumnCase::default()
    });
    let ColumnDetail::Decoupled(d) = r.detail else {
        panic!("decoupled expected")
    };
    close("delta", d.max_deformation, 0.0017933266473674732, 1e-9, 0.0);
    close("P", d.max_force, 994968.3372475737, 1e-9, 0.0);
    close("KE", r.kinetic_energy, 843.7499999999999, 1e-9, 0.0);
    close(
        "w1_0",
        d.initial_modal_displacement,
        0.0011291948923118275,
        1e-9,
        0.0,
    );
    close("U0", d.absorbed_energy, 1241.3332403473112, 1e-9, 0.0);
    close("ratio", d.energy_ratio, 1.4712097663375543, 1e-9, 0.0);
    assert!(
        r.warnings
            .iter()
            .any(|w| w.code == "energy_ratio_above_one")
    );
    let h = r.history.unwrap();
    let want = [
        [0.0017933266473674732, 0.0, 1241.3332403473112, 0.0],
        [
            0.001518410900325557,
            351.4183781831888,
            889.9143442095088,
            0.0005179546136268578,
        ],
        [
            0.0014025585579771752,
            482.00783878633683,
            759.2968293935877,
            0.028572167386714285,
        ],
        [
            0.001618997248767227,
            229.34514253831864,
            1011.7234188856781,
            0.26467892331442816,
        ],
        [
            7.479925705297985e-05,
            1223.499974270523,
            2.159554406861936,
            15.673711669926378,
        ],
    ];
    for (i, w) in want.iter().enumerate() {
        close("w_mid", h.midpoint_displacement[i], w[0], 1e-7, 1.79e-12);
        close("T", h.kinetic_energy[i], w[1], 1e-7, 1.24e-5);
        close("U", h.strain_energy[i], w[2], 1e-7, 1.24e-5);
        close("D", h.dissipated_energy[i], w[3], 1e-7, 1.24e-5);
    }
    // Stress at the clamp from the closed form φ″(0) = 2λ²: σ = E_s(D₁/2)·w₀·2λ₁²/l².
    let lam = 4.730040744862704f64;
    let clamp = 208e9 * 0.125 * d.initial_modal_displacement * 2.0 * lam * lam / 1.31f64.powi(2);
    close(
        "clamp stress",
        r.max_bending_stress.clamp,
        clamp,
        1e-12,
        0.0,
    );
    assert!(r.max_bending_stress.midpoint < r.max_bending_stress.clamp);
    close(
        "utilisation",
        r.stress_utilisation,
        r.max_bending_stress.clamp / 345e6,
        1e-15,
        0.0,
    );
}

/// Uniform history: default sample count ⌈40·f₁·d⌉ + 1, capped by the limit; given count kept.
#[test]
fn uniform_history_sampling() {
    let base = ColumnCase {
        output: HistoryRequest::Uniform {
            duration: Some(0.01),
            samples: None,
        },
        ..ColumnCase::default()
    };
    let r = run(&base);
    let n = (40.0 * r.natural_frequencies_hz[0] * 0.01f64).ceil() as usize + 1;
    let h = r.history.unwrap();
    assert_eq!(h.time.len(), n);
    assert_eq!(*h.time.last().unwrap(), 0.01);
    let capped = run(&ColumnCase {
        max_samples: 50,
        ..base.clone()
    });
    assert_eq!(capped.history.unwrap().time.len(), 50);
    let given = run(&ColumnCase {
        output: HistoryRequest::Uniform {
            duration: Some(1e6),
            samples: Some(7),
        },
        ..base
    });
    let h = given.history.unwrap();
    assert_eq!(h.time.len(), 7);
    assert!(h.midpoint_displacement.iter().all(|x| x.is_finite()));
    // No history unless asked.
    assert!(run(&ColumnCase::default()).history.is_none());
}

fn oscillators() -> Vec<FreeVibration> {
    let (m, k) = (61.85689848982988f64, 1947065540.6183121f64);
    let cc = 2.0 * (k * m).sqrt();
    [
        0.0,
        1e-6,
        0.02,
        0.5,
        0.9,
        1.0 - 1e-9,
        1.0,
        1.0 + 1e-9,
        1.1,
        2.0,
        10.0,
        1e3,
        1e8,
    ]
    .iter()
    .map(|z| FreeVibration::new(m, z * cc, k, 1.1291948923118275e-3))
    .collect()
}

/// T + U + D = U₀ to 1e-9 relative at many times, in every damping regime.
#[test]
fn closed_form_energy_balance() {
    for fv in oscillators() {
        let u0 = fv.initial_energy();
        for i in 0..400 {
            let t = 1e-7 * 1.07f64.powi(i);
            let s = fv.sample(t);
            let sum = s.kinetic + s.strain + s.dissipated;
            assert!(
                rel(sum, u0) < 1e-9,
                "ζ={} t={t:e}: T+U+D = {sum} vs {u0}",
                fv.zeta
            );
            assert!(s.kinetic >= 0.0 && s.strain >= 0.0 && s.dissipated >= 0.0);
        }
    }
}

/// The closed forms are continuous across ζ = 1 (within 1e-6 of U₀ and w₀).
#[test]
fn continuity_across_critical_damping() {
    let (m, k, w0) = (61.85689848982988f64, 1947065540.6183121f64, 1e-3);
    let cc = 2.0 * (k * m).sqrt();
    let crit = FreeVibration::new(m, cc, k, w0);
    for eps in [1e-12, 1e-9, 1e-7] {
        for side in [-1.0, 1.0] {
            let fv = FreeVibration::new(m, cc * (1.0 + side * eps), k, w0);
            let u0 = fv.initial_energy();
            for t in [1e-6, 1e-4, 1e-3, 1e-2, 0.1] {
                let (a, b) = (fv.sample(t), crit.sample(t));
                assert!(
                    (a.displacement - b.displacement).abs() < 1e-6 * w0,
                    "ζ-1={eps}"
                );
                assert!((a.kinetic - b.kinetic).abs() < 1e-6 * u0);
                assert!((a.strain - b.strain).abs() < 1e-6 * u0);
                assert!((a.dissipated - b.dissipated).abs() < 1e-6 * u0);
            }
        }
    }
}

struct Osc {
    m: f64,
    c: f64,
    k: f64,
}
impl OdeSystem for Osc {
    fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) -> bool {
        dy[0] = y[1];
        dy[1] = -(self.c * y[1] + self.k * y[0]) / self.m;
        dy[2] = self.c * y[1] * y[1];
        true
    }
}

/// The closed forms (state and dissipated energy) against direct integration of M, C, K with
/// ∫Cẇ² as an extra state, at ζ = 0.05, 1 and 3.
#[test]
fn closed_forms_match_direct_integration() {
    let (m, k, w0) = (2.0f64, 800.0f64, 0.01);
    for zeta in [0.05, 1.0, 3.0] {
        let c = zeta * 2.0 * (k * m).sqrt();
        let fv = FreeVibration::new(m, c, k, w0);
        let sys = Osc { m, c, k };
        let u0 = fv.initial_energy();
        let mut st = Dopri5::new(1e-12, vec![1e-15, 1e-13, 1e-15 * u0], 1e-4);
        let mut y = [w0, 0.0, 0.0];
        let mut t = 0.0;
        while t < 2.0 {
            t = st.step(&sys, t, &mut y, 2.0).unwrap();
            let s = fv.sample(t);
            assert!((y[0] - s.displacement).abs() < 1e-9 * w0, "ζ={zeta} t={t}");
            assert!((y[2] - s.dissipated).abs() < 1e-9 * u0, "ζ={zeta} t={t}");
        }
    }
}

/// Decay time to 1 % of an under-damped mode from the plain envelope time ln(100)/σ: that time
/// for ζ ≤ 1/√2; above, blended by a smoothstep in ζ into the root of the response bound
/// e^{−σt}·min(1/√(1−ζ²), 1 + σt) = 0.01 (exact amplitude, bounded by the critically damped
/// solution so that it is continuous through ζ = 1), the root found independently by bisection.
fn envelope_decay_time(zeta: f64, omega_n: f64, plain: f64) -> f64 {
    let sigma = zeta * omega_n;
    let amp = plain + (1.0 / (1.0 - zeta * zeta).sqrt()).ln() / sigma;
    let (mut lo, mut hi) = (0.0f64, 200.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (1.0 + mid) * (-mid).exp() > 0.01 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let bound = amp.min(0.5 * (lo + hi) / sigma);
    let a = 0.5f64.sqrt();
    let x = ((zeta - a) / (1.0 - a)).clamp(0.0, 1.0);
    plain + x * x * (3.0 - 2.0 * x) * (bound - plain)
}

/// Decay times: ζ < 1 the envelope; ζ ≥ 1 the root of w = 0.01·w₀; c = 0 gives None.
#[test]
fn decay_times() {
    for fv in oscillators() {
        match fv.decay_time(0.01) {
            None => assert_eq!(fv.zeta, 0.0),
            Some(t) if fv.zeta < 1.0 => close(
                "envelope",
                t,
                envelope_decay_time(fv.zeta, fv.omega_n, 100f64.ln() / (fv.zeta * fv.omega_n)),
                1e-13,
                0.0,
            ),
            Some(t) => {
                let (w, _) = fv.state(t);
                close("root", w, 0.01 * fv.w0, 1e-9, 0.0);
            }
        }
    }
    let r = run(&ColumnCase {
        impact: ImpactCase {
            column: Column {
                damping: Damping::Coefficient(0.0),
                ..Column::default()
            },
            ..ImpactCase::default()
        },
        ..ColumnCase::default()
    });
    assert!(r.decay_time_1pct.is_none());
    assert!(r.warnings.iter().any(|w| w.code == "no_damping"));
}

fn coupled_case(n: usize) -> ColumnCase {
    ColumnCase {
        model: ColumnModel::Coupled,
        modes: Some(n),
        tolerance: 1e-10,
        ..ColumnCase::default()
    }
}

/// P08 (n = 3) and the §B.7 convergence table n = 1, 3, 5, 10, at 1e-5 relative.
#[test]
fn p08_and_convergence_in_modes() {
    let table = [
        (
            1usize,
            [
                0.754774e6, 1.40118e-3, 1.24702e-3, 1.40732e-3, -4.70516, 96.571, 0.114455,
            ],
        ),
        (
            3,
            [
                749493.3867374723,
                0.0013924112012874794,
                0.001260307275923841,
                0.001415347740063528,
                -4.705782663643899,
                96.37434621560254,
                0.11422144736664007,
            ],
        ),
        (
            5,
            [
                0.748442e6, 1.39066e-3, 1.26208e-3, 1.41682e-3, -4.70684, 96.037, 0.113822,
            ],
        ),
        (
            10,
            [
                0.748033e6, 1.38998e-3, 1.26275e-3, 1.41739e-3, -4.70701, 95.983, 0.113758,
            ],
        ),
    ];
    for (n, want) in table {
        let r = run(&coupled_case(n));
        let ColumnDetail::Coupled(d) = r.detail else {
            panic!()
        };
        let got = [
            d.max_force,
            d.max_contact_deformation,
            d.max_midpoint_displacement,
            d.first_contact_duration.unwrap(),
            d.rebound_velocity,
            d.column_energy_after_contact,
            d.energy_ratio,
        ];
        // the printed table has 6 digits: 1e-5 relative covers its rounding
        for (i, (g, w)) in got.iter().zip(want).enumerate() {
            close(&format!("n={n}[{i}]"), *g, w, 1e-5, 0.0);
        }
        assert_eq!(d.contact_count, 1);
        assert_eq!(r.natural_frequencies_hz.len(), n);
        assert!(d.estimated_error < 1e-7);
        if n == 3 {
            for (f, w) in r.natural_frequencies_hz.iter().zip([
                892.9026290343181,
                2307.892309001549,
                4151.338613669198,
            ]) {
                close("freq", *f, w, 1e-9, 0.0);
            }
        }
    }
}

/// Coupled history: rock KE + contact + column + dissipated = KE at every sample (to the
/// integrator tolerance); the contact force matches the law at the sampled approach.
#[test]
fn coupled_history_energy_balance() {
    let case = ColumnCase {
        impact: ImpactCase {
            column: Column {
                damping: Damping::Ratio(0.05),
                ..Column::default()
            },
            ..ImpactCase::default()
        },
        output: HistoryRequest::Uniform {
            duration: None,
            samples: Some(2001),
        },
        ..coupled_case(5)
    };
    let r = run(&case);
    let h = r.history.unwrap();
    let rock = h.rock.unwrap();
    assert_eq!(h.time.len(), 2001);
    let ke = r.kinetic_energy;
    let mut dmax: f64 = 0.0;
    for i in 0..h.time.len() {
        let sum = rock.rock_kinetic_energy[i]
            + rock.contact_energy[i]
            + h.kinetic_energy[i]
            + h.strain_energy[i]
            + h.dissipated_energy[i];
        assert!(rel(sum, ke) < 1e-7, "t={}: {sum} vs {ke}", h.time[i]);
        if i > 0 {
            assert!(h.dissipated_energy[i] >= h.dissipated_energy[i - 1]);
        }
        dmax = dmax.max(h.dissipated_energy[i]);
    }
    // With ζ₁ = 0.05 the column's energy is dissipated within the window.
    assert!(dmax > 10.0);
}

/// Random cases of the 50-digit reference (kinds `decoupled`, `coupled`).
#[test]
fn reference_implementation_cases() {
    let data: serde_json::Value =
        serde_json::from_str(include_str!("data/column_reference.json")).unwrap();
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k}"));
    let items = data.as_array().unwrap();
    assert_eq!(items.len(), 10);
    for item in items {
        let (i, o) = (&item["input"], &item["output"]);
        let law = match i["law"].as_str().unwrap() {
            "paper" => ContactLaw::Paper,
            _ => ContactLaw::Johnson,
        };
        let modulus = match i["estar"].as_str().unwrap() {
            "paper" => ModulusConvention::Paper,
            _ => ModulusConvention::TwoBody,
        };
        let damping = if i["zeta1"].is_number() {
            Damping::Ratio(f(i, "zeta1"))
        } else if i["c_damp"].is_number() {
            Damping::Coefficient(f(i, "c_damp"))
        } else {
            Damping::Coefficient(1.0)
        };
        let num = |k: &str, d: f64| i[k].as_f64().unwrap_or(d);
        let impact = ImpactCase {
            velocity: f(i, "v"),
            rock: Rock {
                side_length: f(i, "L"),
                density: f(i, "rho_rock"),
                elastic_modulus: f(i, "E_rock"),
                poisson_ratio: f(i, "nu_rock"),
                ..Rock::default()
            },
            column: Column {
                outer_diameter: f(i, "D_outer"),
                inner_diameter: f(i, "D_inner"),
                length: f(i, "l_col"),
                elastic_modulus: num("E_col", 208e9),
                density: num("rho_col", 7850.0),
                contact_radius: f(i, "R"),
                damping,
                ..Column::default()
            },
            contact: ContactModel {
                law,
                modulus,
                hertz_exact: true,
            },
        };
        let rotary = i["rotary_inertia"].as_bool().unwrap_or(true);
        if i["kind"] == "decoupled" {
            let shapes = match i["modes"].as_str().unwrap() {
                "exact" => ModeShapes::Exact,
                "paper" => ModeShapes::Paper,
                _ => ModeShapes::Approx,
            };
            let times: Vec<f64> = i["times"]
                .as_array()
                .unwrap()
                .iter()
                .map(|t| t.as_f64().unwrap())
                .collect();
            let r = run(&ColumnCase {
                impact,
                mode_shapes: shapes,
                rotary_inertia: rotary,
                output: HistoryRequest::Times(times),
                ..ColumnCase::default()
            });
            let ColumnDetail::Decoupled(d) = r.detail else {
                panic!()
            };
            close("delta", d.max_deformation, f(o, "delta_max"), 1e-9, 0.0);
            close(
                "w1_0",
                d.initial_modal_displacement,
                f(o, "w1_0"),
                1e-9,
                0.0,
            );
            close("U0", d.absorbed_energy, f(o, "absorbed_energy"), 1e-9, 0.0);
            close("ratio", d.energy_ratio, f(o, "energy_ratio"), 1e-9, 0.0);
            close(
                "omega",
                r.natural_frequencies_hz[0] * 2.0 * PI,
                f(o, "omega_n"),
                1e-9,
                0.0,
            );
            close("zeta", r.damping_ratios[0], f(o, "zeta"), 1e-9, 0.0);
            match r.decay_time_1pct {
                // The reference's plain envelope ln(100)/σ, with the amplitude factor of a
                // continuous decay time through ζ = 1 (beam.rs `decay_time`).
                Some(t) if f(o, "zeta") < 1.0 => close(
                    "t1%",
                    t,
                    envelope_decay_time(f(o, "zeta"), f(o, "omega_n"), f(o, "t_decay_1pct")),
                    1e-9,
                    0.0,
                ),
                Some(t) => close("t1%", t, f(o, "t_decay_1pct"), 1e-9, 0.0),
                None => {
                    assert!(!o["t_decay_1pct"].is_number() || f(o, "t_decay_1pct").is_infinite())
                }
            }
            let h = r.history.unwrap();
            let u0 = d.absorbed_energy;
            for (k, s) in o["history"].as_array().unwrap().iter().enumerate() {
                close(
                    "w_mid",
                    h.midpoint_displacement[k],
                    f(s, "w_mid"),
                    1e-7,
                    1e-9 * d.max_deformation,
                );
                close("T", h.kinetic_energy[k], f(s, "T"), 1e-7, 1e-8 * u0);
                close("U", h.strain_energy[k], f(s, "U"), 1e-7, 1e-8 * u0);
                close("D", h.dissipated_energy[k], f(s, "D"), 1e-7, 1e-8 * u0);
            }
        } else {
            let r = run(&ColumnCase {
                impact,
                model: ColumnModel::Coupled,
                modes: Some(i["n_modes"].as_u64().unwrap() as usize),
                rotary_inertia: rotary,
                end_time: Some(f(i, "t_window")),
                tolerance: 1e-10,
                ..ColumnCase::default()
            });
            let ColumnDetail::Coupled(d) = r.detail else {
                panic!()
            };
            let tol = 1e-5;
            close("P", d.max_force, f(o, "P_max"), tol, 0.0);
            close(
                "dc",
                d.max_contact_deformation,
                f(o, "delta_contact_max"),
                tol,
                0.0,
            );
            close(
                "wmid",
                d.max_midpoint_displacement,
                f(o, "w_mid_max"),
                tol,
                0.0,
            );
            close(
                "tc",
                d.first_contact_duration.unwrap(),
                f(o, "first_contact_duration"),
                tol,
                0.0,
            );
            close(
                "vr",
                d.rebound_velocity,
                f(o, "first_rebound_velocity"),
                tol,
                0.0,
            );
            close(
                "E1",
                d.column_energy_after_contact,
                f(o, "E_column_after_first_contact"),
                tol,
                0.0,
            );
            close(
                "vend",
                d.rock_velocity_end,
                f(o, "rock_velocity_end"),
                tol,
                0.0,
            );
            let ke = r.kinetic_energy;
            close(
                "Eend",
                d.column_energy_end,
                f(o, "E_column_end"),
                tol,
                1e-8 * ke,
            );
            close(
                "Ddamp",
                d.damping_energy,
                f(o, "energy_dissipated_damping"),
                tol,
                1e-6 * ke,
            );
            assert_eq!(d.contact_count as u64, o["n_contacts"].as_u64().unwrap());
            for (a, b) in r
                .natural_frequencies_hz
                .iter()
                .zip(o["modal_freqs_hz"].as_array().unwrap())
            {
                close("f", *a, b.as_f64().unwrap(), 1e-9, 0.0);
            }
        }
    }
}

/// P05–P08 end to end through `solve_column` (the contact module supplies the impact).
#[test]
fn verification_cases_through_solve_column() {
    use gangue::physics::column::solve_column;
    let ctl = Control::unlimited();
    let r = solve_column(&ColumnCase::default(), &ctl).unwrap();
    close("P05 M1", r.modal_mass, 61.85689848982988, 1e-9, 0.0);
    close(
        "P05 f",
        r.natural_frequencies_hz[0],
        892.9278048201711,
        1e-9,
        0.0,
    );
    let p06 = solve_column(
        &ColumnCase {
            mode_shapes: ModeShapes::Paper,
            ..ColumnCase::default()
        },
        &ctl,
    )
    .unwrap();
    close("P06 K1", p06.modal_stiffness, 1947015218.4511666, 1e-9, 0.0);
    let p07 = solve_column(
        &ColumnCase {
            output: HistoryRequest::Times(vec![0.0, 1e-4, 1e-3, 0.01, 0.6]),
            ..ColumnCase::default()
        },
        &ctl,
    )
    .unwrap();
    let ColumnDetail::Decoupled(d) = p07.detail else {
        panic!()
    };
    close(
        "P07 delta",
        d.max_deformation,
        0.0017933266473674732,
        1e-9,
        0.0,
    );
    close("P07 P", d.max_force, 994968.3372475737, 1e-9, 0.0);
    close("P07 U0", d.absorbed_energy, 1241.3332403473112, 1e-9, 0.0);
    close("P07 ratio", d.energy_ratio, 1.4712097663375543, 1e-9, 0.0);
    let h = p07.history.unwrap();
    close(
        "P07 D(0.6)",
        h.dissipated_energy[4],
        15.673711669926378,
        1e-7,
        1.24e-5,
    );
    close(
        "P07 w(0.6)",
        h.midpoint_displacement[4],
        7.479925705297985e-05,
        1e-7,
        1.79e-12,
    );
    let p08 = solve_column(
        &ColumnCase {
            model: ColumnModel::Coupled,
            modes: Some(3),
            ..ColumnCase::default()
        },
        &ctl,
    )
    .unwrap();
    let ColumnDetail::Coupled(c) = p08.detail else {
        panic!()
    };
    let want = [
        (c.max_force, 749493.3867374723),
        (c.max_contact_deformation, 0.0013924112012874794),
        (c.max_midpoint_displacement, 0.001260307275923841),
        (c.first_contact_duration.unwrap(), 0.001415347740063528),
        (c.rebound_velocity, -4.705782663643899),
        (c.column_energy_after_contact, 96.37434621560254),
        (c.energy_ratio, 0.11422144736664007),
        (p08.kinetic_energy, 843.7499999999999),
    ];
    for (i, (g, w)) in want.iter().enumerate() {
        close(&format!("P08[{i}]"), *g, *w, 1e-5, 0.0);
    }
    assert_eq!(c.contact_count, 1);
    // the default window is 50 × the rigid contact duration (1.1081705 ms)
    close("window", c.end_time, 50.0 * 1.1081705e-3, 1e-7, 0.0);
}

/// Re-contact: a slender column (D 0.15/0.12 m, l = 2.5 and 4 m) struck by a 81 kg rock
/// swings back into it; contact counts and all maxima against reference.py (`coupled`,
/// n_modes 3, zeta1 0.01, rho_rock 3000, R 0.075, t_window 0.03).
#[test]
fn multiple_contacts_match_reference() {
    let rows = [
        (
            2.5,
            5u32,
            [
                537860.6806225762,
                0.0010878741785311022,
                0.006211685033863703,
                0.0008719500959472883,
                1.89679686604717,
                857.662377386053,
                -4.350564329768802,
                120.78864862651581,
            ],
        ),
        (
            4.0,
            4,
            [
                619085.3027653979,
                0.0012351303631822955,
                0.012057917445353315,
                0.0007854518651571942,
                1.3389367568588613,
                936.3496470248072,
                -4.718483604461201,
                44.131179295919836,
            ],
        ),
    ];
    for (l, contacts, want) in rows {
        let case = ColumnCase {
            impact: ImpactCase {
                rock: Rock {
                    density: 3000.0,
                    ..Rock::default()
                },
                column: Column {
                    outer_diameter: 0.15,
                    inner_diameter: 0.12,
                    length: l,
                    contact_radius: 0.075,
                    damping: Damping::Ratio(0.01),
                    ..Column::default()
                },
                ..ImpactCase::default()
            },
            model: ColumnModel::Coupled,
            modes: Some(3),
            end_time: Some(0.03),
            tolerance: 1e-10,
            ..ColumnCase::default()
        };
        let r = run(&case);
        let ColumnDetail::Coupled(d) = r.detail else {
            panic!()
        };
        assert_eq!(d.contact_count, contacts, "l = {l}");
        let got = [
            d.max_force,
            d.max_contact_deformation,
            d.max_midpoint_displacement,
            d.first_contact_duration.unwrap(),
            d.rebound_velocity,
            d.column_energy_after_contact,
            d.rock_velocity_end,
            d.column_energy_end,
        ];
        for (i, (g, w)) in got.iter().zip(want).enumerate() {
            close(&format!("l={l}[{i}]"), *g, w, 1e-5, 0.0);
        }
    }
}

/// Johnson law with two-body E* and the Hertz corner (r_c = 0.02, exact elliptical κ), n = 3,
/// default window, end to end through `solve_column`, against reference.py (`coupled`).
#[test]
fn johnson_and_hertz_coupled_match_reference() {
    use gangue::physics::column::solve_column;
    let rows = [
        (
            ContactLaw::Johnson,
            [
                853041.3992321247,
                0.0011924363834180398,
                0.0013340691487332271,
                0.0013017234825012523,
                -4.617894417409472,
                124.03002863492566,
                123.9077012301608,
            ],
            0.04790780535598845,
        ),
        (
            ContactLaw::HertzPoint,
            [
                361906.2996703555,
                0.0052064939306911825,
                0.0005216430914639299,
                0.003387354080647496,
                -4.992074103099993,
                2.672631025400526,
                2.663767495750376,
            ],
            0.1603175802778307,
        ),
    ];
    for (law, want, window) in rows {
        let case = ColumnCase {
            impact: ImpactCase {
                contact: ContactModel {
                    law,
                    modulus: ModulusConvention::TwoBody,
                    hertz_exact: true,
                },
                ..ImpactCase::default()
            },
            model: ColumnModel::Coupled,
            modes: Some(3),
            tolerance: 1e-10,
            ..ColumnCase::default()
        };
        let r = solve_column(&case, &Control::unlimited()).unwrap();
        let ColumnDetail::Coupled(d) = r.detail else {
            panic!()
        };
        close("window", d.end_time, window, 1e-7, 0.0);
        assert_eq!(d.contact_count, 1);
        let got = [
            d.max_force,
            d.max_contact_deformation,
            d.max_midpoint_displacement,
            d.first_contact_duration.unwrap(),
            d.rebound_velocity,
            d.column_energy_after_contact,
            d.column_energy_end,
        ];
        for (i, (g, w)) in got.iter().zip(want).enumerate() {
            close(&format!("{law:?}[{i}]"), *g, w, 1e-5, 0.0);
        }
    }
}

/// Coupled stresses: with one mode the curvature is proportional to w_mid, so the located
/// curvature extrema must equal w_mid_max·φ₁″(x)/(φ₁(½)l²) (x = 0: φ₁″ = 2λ₁²).
#[test]
fn coupled_single_mode_stress_is_consistent() {
    use gangue::physics::beam::BeamMode;
    let r = run(&coupled_case(1));
    let ColumnDetail::Coupled(d) = r.detail else {
        panic!()
    };
    let m = BeamMode::clamped(1);
    let (l, es, d1) = (1.31f64, 208e9, 0.25);
    let f = es * d1 / 2.0 / (l * l) * d.max_midpoint_displacement / m.shape(0.5);
    let lam = m.lambda;
    close(
        "clamp",
        r.max_bending_stress.clamp,
        f * 2.0 * lam * lam,
        1e-9,
        0.0,
    );
    close(
        "mid",
        r.max_bending_stress.midpoint,
        f * m.curvature(0.5).abs(),
        1e-9,
        0.0,
    );
    close(
        "utilisation",
        r.stress_utilisation,
        r.max_bending_stress
            .clamp
            .max(r.max_bending_stress.midpoint)
            / 345e6,
        1e-15,
        0.0,
    );
}

//! Regressions of issue 7 on the column side, each named for its symptom.
//!
//! Physical expectations: (1) the coupled model's column energy is controlled relative to the
//! energy actually transferred, so a tiny transfer (1e-7 of the rock's energy) matches the
//! 50-digit reference (`../shared/reference/reference.py`, kind `coupled`, scipy DOP853) to the
//! coupled-ODE tolerance of physics.md §G (1e-5), and the integrator's own estimate either meets
//! that target or is reported in `warnings`; (2) the decay time to 1 % is continuous through
//! critical damping ζ = 1 (the critically damped root of (1 + s)e^{−s} = 0.01, s = ω_n t);
//! (3) values in range whose intermediate results leave double precision are answered with a
//! finite result or a 422 naming the field, never a 500; (4) a step-size underflow far from the
//! contact capacity is never reported as `capacity_exceeded`.
//!
//! The small-transfer oracle cases run the reference in Python (about 2 s each); the random ones
//! draw from a fixed seed (PROPTEST_RNG_SEED, default 20261122); set GANGUE_SMALL_TRANSFER_CASES
//! to run more of them (default 3).

mod common;

use std::io::Write;
use std::process::{Command, Stdio};

use serde_json::{Value, json};

/// Runs reference.py on coupled cases; returns transfer_ratio_first_contact of each.
fn reference_ratios(cases: &[Value]) -> Vec<f64> {
    let dir = common::shared_dir().join("reference");
    let driver = r#"
import json, sys
sys.path.insert(0, sys.argv[1])
import reference as ref
out = []
for c in json.load(sys.stdin):
    r = ref.run_case(c)
    out.append(float(r["output"]["transfer_ratio_first_contact"]))
json.dump(out, sys.stdout)
"#;
    let mut child = Command::new("python3")
        .arg("-c")
        .arg(driver)
        .arg(&dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("python3 must be installed for the reference oracle");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(serde_json::to_string(cases).unwrap().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "reference failed");
    serde_json::from_slice(&out.stdout).unwrap()
}

/// A small-transfer case as (API request, reference case).
#[allow(clippy::too_many_arguments)]
fn small_case(
    v: f64,
    side: f64,
    e_rock: f64,
    rho_rock: f64,
    d_outer: f64,
    length: f64,
    e_col: f64,
    modes: u32,
) -> (Value, Value) {
    let corner = (side / 2.0).min(0.02);
    let api = json!({"model":"coupled","velocity_m_s":v,
        "rock":{"side_length_m":side,"elastic_modulus_pa":e_rock,"poisson_ratio":0.4,
                "density_kg_m3":rho_rock,"corner_radius_m":corner},
        "column":{"outer_diameter_m":d_outer,"inner_diameter_m":0,"length_m":length,
                  "elastic_modulus_pa":e_col,"density_kg_m3":3000,"damping_coefficient_n_s_m2":0},
        "contact":{"law":"hertz_point"},"galerkin":{"modes":modes}});
    let reference = json!({"kind":"coupled","v":v,"L":side,"E_rock":e_rock,"nu_rock":0.4,
        "rho_rock":rho_rock,"corner_radius":corner,"D_outer":d_outer,"D_inner":0,"l_col":length,
        "E_col":e_col,"rho_col":3000,"c_damp":0,"R":d_outer/2.0,"law":"hertz_point",
        "n_modes":modes});
    (api, reference)
}

#[tokio::test]
async fn coupled_small_transfer_no_longer_creates_energy() {
    let app = common::app();
    // The issue's repro (890× too high before) with 1 and 3 modes, then random tiny soft rocks
    // on stiff thick columns (ratios about 1e-9 … 1e-5), 1–7 modes.
    let mut cases = vec![
        small_case(1.0, 0.03, 6.1e7, 520.0, 1.76, 1.13, 1.6e10, 1),
        small_case(1.0, 0.03, 6.1e7, 520.0, 1.76, 1.13, 1.6e10, 3),
    ];
    let seed: u64 = std::env::var("PROPTEST_RNG_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20261122);
    let extra: usize = std::env::var("GANGUE_SMALL_TRANSFER_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut uniform = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..extra {
        let lg = |lo: f64, hi: f64, u: f64| 10f64.powf(lo + (hi - lo) * u);
        let v = lg(-1.0, 1.0, uniform());
        let side = lg(-2.0, -1.0, uniform());
        let e_rock = lg(7.0, 8.5, uniform());
        let d = 0.5 + 1.5 * uniform();
        let length = 1.0 + 1.5 * uniform();
        let modes = 1 + (uniform() * 7.0) as u32;
        cases.push(small_case(v, side, e_rock, 520.0, d, length, 2e10, modes));
    }
    let refs = reference_ratios(&cases.iter().map(|c| c.1.clone()).collect::<Vec<_>>());
    for ((api, _), want) in cases.iter().zip(refs) {
        let r = common::post(&app, "/v1/column", api).await;
        assert_eq!(
            r.status.as_u16(),
            200,
            "{api}: {}",
            String::from_utf8_lossy(&r.body)
        );
        let b = r.json();
        let got = b["energy_ratio"].as_f64().unwrap();
        let err = common::rel(got, want);
        eprintln!(
            "small transfer: ratio {got:.6e} reference {want:.6e} rel {err:.1e} estimate {est:.1e}",
            est = b["integrator"]["estimated_error"].as_f64().unwrap()
        );
        let est = b["integrator"]["estimated_error"].as_f64().unwrap();
        let warned = b["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "integrator_error_above_target");
        assert!(
            est <= 1e-5 || warned,
            "{api}: estimate {est} without warning"
        );
        assert!(
            err <= 1e-5,
            "{api}: energy_ratio {got:e} against the reference {want:e} (rel {err:e})"
        );
    }
}

#[tokio::test]
async fn coupled_fifty_mode_repro_keeps_its_estimate_within_target() {
    // 50 modes: the reference takes minutes here, so check the self-consistency the fix relies
    // on (the estimate relative to the transferred energy) and agreement with 3 modes (the
    // higher modes add ~0.05 % for this stubby column, as for the base case in §B.7).
    let app = common::app();
    let (api50, _) = small_case(1.0, 0.03, 6.1e7, 520.0, 1.76, 1.13, 1.6e10, 50);
    let (api3, _) = small_case(1.0, 0.03, 6.1e7, 520.0, 1.76, 1.13, 1.6e10, 3);
    let b50 = common::post(&app, "/v1/column", &api50).await.json();
    let b3 = common::post(&app, "/v1/column", &api3).await.json();
    let r50 = b50["energy_ratio"].as_f64().unwrap();
    let r3 = b3["energy_ratio"].as_f64().unwrap();
    assert!(
        b50["integrator"]["estimated_error"].as_f64().unwrap() <= 1e-5,
        "{b50}"
    );
    assert!(
        common::rel(r50, r3) < 1e-2,
        "50 modes {r50:e}, 3 modes {r3:e}"
    );
}

/// The critically damped root: (1 + s)e^{−s} = x, s = ω_n t (independent bisection).
fn critical_root(x: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 100.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (1.0 + mid) * (-mid).exp() > x {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[tokio::test]
async fn critical_damping_decay_time_is_not_thirty_percent_low() {
    let app = common::app();
    let base = json!({"column":{"damping_ratio":1.0,"length_m":13,"outer_diameter_m":0.1,
                                "inner_diameter_m":0}});
    let b = common::post(&app, "/v1/column", &base).await.json();
    let omega = b["natural_frequencies_hz"][0].as_f64().unwrap() * 2.0 * std::f64::consts::PI;
    let want = critical_root(0.01) / omega;
    let t1 = b["decay_time_1pct_s"].as_f64().unwrap();
    assert!(common::rel(t1, want) < 1e-9, "{t1} against {want}");
    assert!((t1 - 0.3897).abs() < 1e-4, "{t1}");
    // ζ = 1 ± k ulp and 1 ± 1e-8: continuous to first order in ζ − 1.
    let one = 1.0f64;
    let mut zetas = vec![1.0 - 1e-8, 1.0 + 1e-8];
    for k in 1..=4u64 {
        zetas.push(f64::from_bits(one.to_bits() - k));
        zetas.push(f64::from_bits(one.to_bits() + k));
    }
    let history = |b: &Value, key: &str| -> Vec<f64> {
        b["history"][key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let mut hreq = base.clone();
    hreq["output"] = json!({"duration_s": 1.0, "samples": 101});
    let critical = common::post(&app, "/v1/column", &hreq).await.json();
    let w_crit = history(&critical, "midpoint_displacement_m");
    let u0 = critical["absorbed_energy_j"].as_f64().unwrap();
    for z in zetas {
        let mut req = base.clone();
        req["column"]["damping_ratio"] = json!(z);
        let r = common::post(&app, "/v1/column", &req).await;
        assert_eq!(r.status.as_u16(), 200, "ζ = {z}");
        let t = r.json()["decay_time_1pct_s"].as_f64().unwrap();
        assert!(common::rel(t, want) < 1e-6, "ζ = {z}: {t} against {want}");
        // Histories: the same motion to first order in ζ − 1, energy never created.
        req["output"] = hreq["output"].clone();
        let b = common::post(&app, "/v1/column", &req).await.json();
        let w = history(&b, "midpoint_displacement_m");
        let w0 = w_crit[0].abs();
        for (k, (a, c)) in w.iter().zip(&w_crit).enumerate() {
            assert!(
                (a - c).abs() <= 1e-7 * w0,
                "ζ = {z}, sample {k}: {a} against {c}"
            );
        }
        let (tk, uk, dk) = (
            history(&b, "kinetic_energy_j"),
            history(&b, "strain_energy_j"),
            history(&b, "dissipated_energy_j"),
        );
        for k in 0..tk.len() {
            let total = tk[k] + uk[k] + dk[k];
            assert!(
                total <= u0 * (1.0 + 1e-9),
                "ζ = {z}, sample {k}: {total} > U₀ {u0}"
            );
        }
    }
}

#[tokio::test]
async fn non_finite_intermediates_answer_422_or_a_finite_result_not_500() {
    let app = common::app();
    let cases = [
        (json!({"velocity_m_s":5e-324}), Some("/velocity_m_s")),
        (
            json!({"column":{"yield_stress_pa":5e-324}}),
            Some("/column/yield_stress_pa"),
        ),
        (
            json!({"column":{"damping_coefficient_n_s_m2":1e-308}}),
            None,
        ),
        (
            json!({"model":"coupled","end_time_s":1e-307}),
            Some("/end_time_s"),
        ),
        (
            json!({"model":"coupled","contact":{"law":"hertz_point"},"velocity_m_s":1e-300}),
            Some("/velocity_m_s"),
        ),
    ];
    for (body, field) in cases {
        let r = common::post(&app, "/v1/column", &body).await;
        match field {
            Some(f) => {
                let p = common::assert_problem(&r, 422, "invalid_input");
                assert!(
                    p["errors"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .any(|e| e["field"] == f),
                    "{body}: {p}"
                );
            }
            None => {
                assert_eq!(r.status.as_u16(), 200, "{body}");
                let b = r.json();
                assert!(b["decay_time_1pct_s"].is_null(), "{b}");
                assert!(
                    b["warnings"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .any(|w| w["code"] == "decay_time_unrepresentable"),
                    "{b}"
                );
            }
        }
    }
}

#[tokio::test]
async fn tiny_velocity_is_not_reported_as_capacity_exceeded() {
    let app = common::app();
    for v in [1e-162, 1e-200] {
        let r = common::post(
            &app,
            "/v1/column",
            &json!({"model":"coupled","velocity_m_s":v}),
        )
        .await;
        assert_ne!(r.status.as_u16(), 500, "v = {v}");
        let b = r.json();
        assert_ne!(b["type"], "/problems/capacity_exceeded", "v = {v}: {b}");
    }
    // The smallest accepted velocities give finite answers with the column energy balanced.
    let r = common::post(
        &app,
        "/v1/column",
        &json!({"model":"coupled","velocity_m_s":1e-140}),
    )
    .await;
    assert_eq!(r.status.as_u16(), 200);
    let b = r.json();
    assert!(b["energy_ratio"].as_f64().unwrap().is_finite());
    assert!(
        b["integrator"]["estimated_error"].as_f64().unwrap() <= 1e-5,
        "{b}"
    );
}

#[test]
fn coarse_integrator_refines_or_warns_never_reports_silently() {
    use gangue::physics::Control;
    use gangue::physics::column::{ColumnCase, ColumnDetail, ColumnModel, solve_column};
    // Loose tolerances on the base case (large transfer) and on a small transfer: the reported
    // estimate either meets the 1e-5 target after refinement or comes with the warning.
    let (mut any_warned, mut any_refined) = (false, false);
    for tolerance in [1e-3, 1e-5, 1e-7] {
        for modes in [1usize, 3, 9] {
            let case = ColumnCase {
                model: ColumnModel::Coupled,
                modes: Some(modes),
                tolerance,
                ..ColumnCase::default()
            };
            let r = solve_column(&case, &Control::unlimited()).unwrap();
            let ColumnDetail::Coupled(c) = &r.detail else {
                panic!("coupled expected")
            };
            let warned = r
                .warnings
                .iter()
                .any(|w| w.code == "integrator_error_above_target");
            assert!(
                c.estimated_error <= 1e-5 || warned,
                "tolerance {tolerance}, {modes} modes: estimate {} without warning",
                c.estimated_error
            );
            any_warned |= warned;
            any_refined |= c.tolerance < tolerance;
            assert!(c.estimated_error.is_finite());
        }
    }
    // Both paths are exercised: tolerance 1e-3 with one mode stays above the target.
    assert!(any_warned && any_refined);
}

/// Light damping keeps physics.md §B.5's envelope time ln(100)/σ exactly (the recommended
/// ζ₁ = 0.02 included); the blend towards the response bound starts only above ζ = 1/√2 and is
/// continuous there.
#[tokio::test]
async fn light_damping_decay_time_is_the_envelope_time() {
    let app = common::app();
    let decay = |z: f64| {
        let app = app.clone();
        async move {
            let req = json!({"column":{"damping_ratio": z}});
            let b = common::post(&app, "/v1/column", &req).await.json();
            let omega =
                b["natural_frequencies_hz"][0].as_f64().unwrap() * 2.0 * std::f64::consts::PI;
            let zeta = b["damping_ratios"][0].as_f64().unwrap();
            (
                b["decay_time_1pct_s"].as_f64().unwrap(),
                100f64.ln() / (zeta * omega),
            )
        }
    };
    for z in [1e-6, 0.02, 0.3, 0.7] {
        let (t, plain) = decay(z).await;
        assert!(
            common::rel(t, plain) < 1e-13,
            "ζ = {z}: {t} against {plain}"
        );
    }
    let a = std::f64::consts::FRAC_1_SQRT_2;
    let (below, _) = decay(a - 1e-9).await;
    let (above, _) = decay(a + 1e-9).await;
    assert!(common::rel(below, above) < 1e-7, "{below} against {above}");
}

/// A coupled history sampled 5e-324 s after the first touch stored NaN as the contact energy of
/// the log law (the force there is subnormal, P_ref/P overflowed and P²·∞ = NaN), answered 500;
/// found by the long Schemathesis run through `/v1/scene`. Every sample is finite now and the
/// contact energy at that instant is 0 (P² underflows).
#[tokio::test]
async fn a_coupled_history_sampled_at_a_subnormal_time_is_finite() {
    let app = common::app();
    let column = json!({"model": "coupled", "output": {"duration_s": 5e-324, "samples": 2}});
    let r = common::post(&app, "/v1/column", &column).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert_eq!(b["history"]["contact_energy_j"], json!([0.0, 0.0]), "{b}");
    let scene = json!({"column_model": "coupled",
                       "column_output": {"duration_s": 5e-324, "samples": 2}});
    let r = common::post(&app, "/v1/scene", &scene).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
}

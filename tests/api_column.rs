//! `POST /v1/column` through the router: both models, histories, warnings, bad input.

mod common;

use common::{assert_problem, post, rel};
use serde_json::{Value, json};

#[tokio::test]
async fn decoupled_default_warns_about_energy_and_damping() {
    let app = common::app();
    let r = post(&app, "/v1/column", &json!({})).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert_eq!(b["model"], "decoupled");
    assert!(rel(b["energy_ratio"].as_f64().unwrap(), 1.4712097663375543) < 1e-9);
    let codes: Vec<&str> = b["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["code"].as_str().unwrap())
        .collect();
    assert!(codes.contains(&"energy_ratio_above_one"), "{codes:?}");
    assert!(codes.contains(&"paper_damping"), "{codes:?}");
    assert!(b.get("history").is_none(), "no history unless asked");
    assert!(b.get("integrator").is_none());
    assert_eq!(b["inputs"]["galerkin"]["modes"], 1);
    assert!(b["stress_utilisation"].as_f64().unwrap() > 0.0);
}

#[tokio::test]
async fn decoupled_history_default_sampling_and_energy_balance() {
    let app = common::app();
    let r = post(&app, "/v1/column", &json!({"output": {"duration_s": 0.01}})).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let f1 = b["natural_frequencies_hz"][0].as_f64().unwrap();
    let h = &b["history"];
    let n = h["time_s"].as_array().unwrap().len();
    assert_eq!(n, (40.0 * f1 * 0.01_f64).ceil() as usize + 1);
    let u0 = b["absorbed_energy_j"].as_f64().unwrap();
    for i in 0..n {
        let t = h["kinetic_energy_j"][i].as_f64().unwrap()
            + h["strain_energy_j"][i].as_f64().unwrap()
            + h["dissipated_energy_j"][i].as_f64().unwrap();
        assert!(rel(t, u0) < 1e-9, "sample {i}: {t} vs {u0}");
    }
}

#[tokio::test]
async fn coupled_reports_integrator_and_balances_energy() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/column",
        &json!({"model": "coupled", "output": {"samples": 200}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert!(rel(b["energy_ratio"].as_f64().unwrap(), 0.11422144736664007) < 1e-5);
    assert_eq!(b["natural_frequencies_hz"].as_array().unwrap().len(), 3);
    assert!(b["integrator"]["steps"].as_u64().unwrap() > 10);
    assert_eq!(b["inputs"]["galerkin"]["modes"], 3);
    let h = &b["history"];
    let n = h["time_s"].as_array().unwrap().len();
    assert_eq!(n, 200);
    let ke = b["kinetic_energy_j"].as_f64().unwrap();
    for i in 0..n {
        let total: f64 = [
            "kinetic_energy_j",
            "strain_energy_j",
            "dissipated_energy_j",
            "rock_kinetic_energy_j",
            "contact_energy_j",
        ]
        .iter()
        .map(|k| h[k][i].as_f64().unwrap())
        .sum();
        assert!(rel(total, ke) < 1e-6, "sample {i}: {total} vs {ke}");
    }
    assert_eq!(
        h["time_s"][n - 1].as_f64().unwrap(),
        b["end_time_s"].as_f64().unwrap()
    );
}

#[tokio::test]
async fn zero_damping_gives_null_decay_time_with_warning() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/column",
        &json!({"column": {"damping_coefficient_n_s_m2": 0.0}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert!(b["decay_time_1pct_s"].is_null());
    assert!(!b["warnings"].as_array().unwrap().is_empty());
}

#[tokio::test]
async fn damping_ratio_converts_through_exact_mode_one() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/column",
        &json!({"column": {"damping_ratio": 0.02}}),
    )
    .await;
    assert_eq!(r.status, 200);
    let b = r.json();
    // physics.md §B.6: ζ₁ = 0.02 gives c = 10 597 N·s/m² and t_1% = 0.0410 s.
    assert!((b["damping_coefficient_n_s_m2"].as_f64().unwrap() - 10597.0).abs() < 1.0);
    assert!((b["decay_time_1pct_s"].as_f64().unwrap() - 0.0410).abs() < 1e-4);
    assert!(rel(b["damping_ratios"][0].as_f64().unwrap(), 0.02) < 1e-9);
}

#[tokio::test]
async fn invalid_combinations_name_the_field() {
    let app = common::app();
    let cases: Vec<(Value, &str, &str)> = vec![
        (
            json!({"galerkin": {"modes": 3}}),
            "/galerkin/modes",
            "invalid_input",
        ),
        (
            json!({"model": "coupled", "galerkin": {"modes": 51}}),
            "/galerkin/modes",
            "invalid_input",
        ),
        (
            json!({"model": "coupled", "galerkin": {"modes": 0}}),
            "/galerkin/modes",
            "invalid_input",
        ),
        (
            json!({"model": "coupled", "galerkin": {"mode_shapes": "paper"}}),
            "/galerkin/mode_shapes",
            "invalid_input",
        ),
        (json!({"end_time_s": 0.1}), "/end_time_s", "invalid_input"),
        (
            json!({"model": "coupled", "end_time_s": 0.0}),
            "/end_time_s",
            "invalid_input",
        ),
        (
            json!({"model": "coupled", "end_time_s": 1e4}),
            "/end_time_s",
            "invalid_input",
        ),
        (
            json!({"model": "coupled", "initial_midpoint_displacement_m": 0.001}),
            "/initial_midpoint_displacement_m",
            "invalid_input",
        ),
        (
            json!({"initial_midpoint_displacement_m": 2.0}),
            "/initial_midpoint_displacement_m",
            "invalid_input",
        ),
        (
            json!({"column": {"damping_coefficient_n_s_m2": 1.0, "damping_ratio": 0.02}}),
            "/column/damping_ratio",
            "invalid_input",
        ),
        (
            json!({"column": {"damping_ratio": 11.0}}),
            "/column/damping_ratio",
            "invalid_input",
        ),
        (
            json!({"column": {"damping_coefficient_n_s_m2": -1.0}}),
            "/column/damping_coefficient_n_s_m2",
            "invalid_input",
        ),
        (
            json!({"output": {"times_s": [0.0], "duration_s": 1.0}}),
            "/output/times_s",
            "invalid_input",
        ),
        (
            json!({"output": {"times_s": [-1.0]}}),
            "/output/times_s/0",
            "invalid_input",
        ),
        (
            json!({"output": {"duration_s": 0.0}}),
            "/output/duration_s",
            "invalid_input",
        ),
        (
            json!({"output": {"duration_s": 1.0, "samples": 1}}),
            "/output/samples",
            "invalid_input",
        ),
        (
            json!({"output": {"duration_s": 1.0, "samples": 2_000_000}}),
            "/output/samples",
            "invalid_input",
        ),
        (json!({"output": {}}), "/output/duration_s", "invalid_input"),
        (json!({"output": []}), "/output", "invalid_type"),
        (
            json!({"galerkin": {"modes": 1, "shapes": "exact"}}),
            "/galerkin/shapes",
            "unknown_field",
        ),
        (
            json!({"model": "decoupled_fast"}),
            "/model",
            "invalid_input",
        ),
    ];
    common::assert_rejections(&app, "/v1/column", cases).await;
}

#[tokio::test]
async fn capacity_is_checked_before_the_column() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/column",
        &json!({"velocity_m_s": 400, "rock": {"side_length_m": 0.05, "elastic_modulus_pa": 5e8}}),
    )
    .await;
    assert_problem(&r, 422, "capacity_exceeded");
    let r = post(&app, "/v1/column", &json!({"model": "coupled", "velocity_m_s": 400, "rock": {"side_length_m": 0.05, "elastic_modulus_pa": 5e8}})).await;
    assert_problem(&r, 422, "capacity_exceeded");
}

fn warning_codes(b: &Value) -> Vec<String> {
    b["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["code"].as_str().unwrap().to_owned())
        .collect()
}

/// Validity (issue 12): a stress utilisation above 1 is warned, exactly 1 is not; the bending
/// stress does not depend on the yield stress, so σ_y = σ_max gives a utilisation of exactly 1.
#[tokio::test]
async fn stress_utilisation_above_one_is_warned_on_both_sides_of_the_threshold() {
    let app = common::app();
    for model in ["decoupled", "coupled"] {
        let base = post(&app, "/v1/column", &json!({"model": model}))
            .await
            .json();
        let s = &base["max_bending_stress_pa"];
        let sigma = s["clamp"]
            .as_f64()
            .unwrap()
            .max(s["midpoint"].as_f64().unwrap());
        // The defaults are past yield (221.9 % decoupled): warned.
        assert!(base["stress_utilisation"].as_f64().unwrap() > 1.0);
        assert!(warning_codes(&base).contains(&"stress_utilisation_above_one".into()));
        for (yield_stress, warned) in [
            (sigma, false),
            (sigma * (1.0 + 1e-12), false),
            (sigma * (1.0 - 1e-12), true),
        ] {
            let b = post(
                &app,
                "/v1/column",
                &json!({"model": model, "column": {"yield_stress_pa": yield_stress}}),
            )
            .await
            .json();
            assert_eq!(
                warning_codes(&b).contains(&"stress_utilisation_above_one".into()),
                warned,
                "{model}, σ_y = {yield_stress}: utilisation {}",
                b["stress_utilisation"]
            );
        }
    }
}

/// Validity (issue 12): the column responses carry the contact's validity warnings too — a
/// Hertz corner at the defaults presses far above the yield stress of 16Mn steel.
#[tokio::test]
async fn column_responses_carry_the_contact_validity_warnings() {
    let app = common::app();
    for model in ["decoupled", "coupled"] {
        let hertz = post(
            &app,
            "/v1/column",
            &json!({"model": model, "contact": {"law": "hertz_point"}}),
        )
        .await
        .json();
        assert!(
            warning_codes(&hertz).contains(&"contact_pressure_above_yield".into()),
            "{model}: {}",
            hertz["warnings"]
        );
        let soft = post(
            &app,
            "/v1/column",
            &json!({"model": model, "contact": {"law": "hertz_point"},
                    "column": {"yield_stress_pa": 1e10}}),
        )
        .await
        .json();
        assert!(
            !warning_codes(&soft).contains(&"contact_pressure_above_yield".into()),
            "{model}: {}",
            soft["warnings"]
        );
    }
}

/// Issue 7: a thin-walled, short coupled column with 50 modes needs tens of millions of steps;
/// it used to integrate for seconds until the step limit and only then answer. The step count
/// is now estimated from the stiffest mode and the window before integrating, so the refusal
/// (422 `too_many_steps` with the estimate, naming `/end_time_s`) comes at once. A time limit
/// far below the old run time proves that no integration happened: the service would answer
/// 504 `timeout` if it integrated first.
#[tokio::test]
async fn thin_walled_coupled_column_is_refused_at_once_with_the_step_estimate() {
    let app = gangue::app(gangue::config::Config {
        compute_timeout_s: 0.5,
        ..gangue::config::Config::default()
    });
    let r = post(
        &app,
        "/v1/column",
        &json!({"model": "coupled", "galerkin": {"modes": 50}, "end_time_s": 10.0,
                "column": {"inner_diameter_m": 0.2499, "length_m": 0.3}}),
    )
    .await;
    let p = assert_problem(&r, 422, "too_many_steps");
    let estimated = p["estimated_steps"].as_f64().unwrap();
    let limit = p["limit"].as_f64().unwrap();
    assert!(
        estimated > 4.0 * limit,
        "estimate {estimated}, limit {limit}"
    );
    assert_eq!(p["errors"][0]["field"], "/end_time_s", "{p}");
}

//! `POST /v1/impact` through the router: results, conventions, and every class of bad input.

mod common;

use axum::http::Method;
use common::{assert_problem, post, rel, send};
use serde_json::{Value, json};

#[tokio::test]
async fn default_case_has_conventions_and_resolved_inputs() {
    let app = common::app();
    let r = post(&app, "/v1/impact", &json!({})).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    assert!(r.content_type().starts_with("application/json"));
    let b = r.json();
    assert!(
        rel(
            b["max_deformation_m"].as_f64().unwrap(),
            1.7933266473674732e-3
        ) < 1e-9
    );
    assert_eq!(b["model_version"], env!("CARGO_PKG_VERSION"));
    assert!(b["warnings"].is_array());
    assert_eq!(b["plan"][0]["stage"], "impact");
    assert_eq!(b["plan"][0]["status"], "ran");
    assert_eq!(b["plan"][1]["status"], "skipped");
    // Resolved inputs: derived defaults filled in.
    assert_eq!(b["inputs"]["velocity_m_s"], 5.0);
    assert_eq!(b["inputs"]["column"]["contact_radius_m"], 0.125);
    assert_eq!(b["inputs"]["rock"]["corner_radius_m"], 0.02);
    assert_eq!(b["inputs"]["column"]["damping_coefficient_n_s_m2"], 1.0);
    assert_eq!(b["inputs"]["contact"]["law"], "paper");
    // Optional outputs not asked for are omitted, never null.
    assert!(b.get("curve").is_none());
    assert!(b.get("hertz_stiffness_n_m1_5").is_none());
    // Replaying the resolved inputs gives the same bytes.
    let again = post(&app, "/v1/impact", &b["inputs"]).await;
    assert_eq!(again.body, r.body);
}

#[tokio::test]
async fn curve_runs_from_zero_to_the_maximum() {
    let app = common::app();
    for law in ["paper", "johnson", "hertz_point"] {
        let r = post(
            &app,
            "/v1/impact",
            &json!({"contact": {"law": law}, "output": {"curve_points": 50}}),
        )
        .await;
        assert_eq!(r.status, 200, "{law}");
        let b = r.json();
        let d = b["curve"]["deformation_m"].as_array().unwrap();
        let p = b["curve"]["force_n"].as_array().unwrap();
        assert_eq!(d.len(), 50);
        assert_eq!(p.len(), 50);
        assert_eq!(d[0], 0.0);
        assert_eq!(p[0], 0.0);
        assert!(
            rel(
                d[49].as_f64().unwrap(),
                b["max_deformation_m"].as_f64().unwrap()
            ) < 1e-12
        );
        assert!(
            rel(p[49].as_f64().unwrap(), b["max_force_n"].as_f64().unwrap()) < 1e-9,
            "{law}"
        );
        // Monotone force.
        assert!(p.windows(2).all(|w| w[1].as_f64() > w[0].as_f64()), "{law}");
        assert_eq!(b["plan"][1]["status"], "ran");
    }
}

#[tokio::test]
async fn capacity_exceeded_names_the_largest_speed_and_that_speed_works() {
    let app = common::app();
    let rock = json!({"side_length_m": 0.05, "elastic_modulus_pa": 5e8});
    let column = json!({"contact_radius_m": 1.0});
    let r = post(
        &app,
        "/v1/impact",
        &json!({"velocity_m_s": 40.0, "rock": rock, "column": column}),
    )
    .await;
    let p = assert_problem(&r, 422, "capacity_exceeded");
    let vmax = p["max_velocity_m_s"].as_f64().unwrap();
    // physics.md §A.5: R = 1 m, L = 0.05 m, E = 0.5 GPa reaches the branch point at v ≈ 29.19 m/s.
    assert!((vmax - 29.19).abs() < 0.01, "vmax {vmax}");
    let ok = post(
        &app,
        "/v1/impact",
        &json!({"velocity_m_s": vmax * (1.0 - 1e-9), "rock": rock, "column": column}),
    )
    .await;
    assert_eq!(ok.status, 200, "{}", String::from_utf8_lossy(&ok.body));
    let b = ok.json();
    assert!(b["energy_parameter"].as_f64().unwrap() <= 1.0);
    assert!(
        b["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "near_capacity")
    );
}

#[tokio::test]
async fn out_of_range_values_name_field_value_and_range() {
    let app = common::app();
    let cases: Vec<(Value, &str)> = vec![
        (json!({"velocity_m_s": 0.0}), "/velocity_m_s"),
        (json!({"velocity_m_s": -5.0}), "/velocity_m_s"),
        (json!({"velocity_m_s": 1000.5}), "/velocity_m_s"),
        (
            json!({"rock": {"density_kg_m3": -1.0}}),
            "/rock/density_kg_m3",
        ),
        (
            json!({"rock": {"side_length_m": 1e300}}),
            "/rock/side_length_m",
        ),
        (
            json!({"rock": {"elastic_modulus_pa": 1e6}}),
            "/rock/elastic_modulus_pa",
        ),
        (
            json!({"rock": {"poisson_ratio": 0.5}}),
            "/rock/poisson_ratio",
        ),
        (
            json!({"column": {"inner_diameter_m": 0.25}}),
            "/column/inner_diameter_m",
        ),
        (
            json!({"column": {"outer_diameter_m": 3.0}}),
            "/column/outer_diameter_m",
        ),
        (
            json!({"column": {"contact_radius_m": 0.0}}),
            "/column/contact_radius_m",
        ),
        (
            json!({"column": {"yield_stress_pa": 0.0}}),
            "/column/yield_stress_pa",
        ),
        (
            json!({"column": {"length_m": 0.2}, "rock": {"side_length_m": 0.3}}),
            "/column/length_m",
        ),
        (
            json!({"column": {"damping_coefficient_n_s_m2": 5.0, "damping_ratio": 0.02}}),
            "/column/damping_ratio",
        ),
        (
            json!({"contact": {"law": "hertz_point"}, "rock": {"corner_radius_m": 0.2}}),
            "/rock/corner_radius_m",
        ),
        (json!({"rock": {"shape": "sphere"}}), "/contact/law"),
        (
            json!({"rock": {"shape": "cuboid", "dimensions_m": [0.1, 0.2, 0.3]}}),
            "/rock/shape",
        ),
        (
            json!({"output": {"curve_points": 10001}}),
            "/output/curve_points",
        ),
    ];
    for (body, field) in cases {
        let r = post(&app, "/v1/impact", &body).await;
        let p = assert_problem(&r, 422, "invalid_input");
        let errs = p["errors"].as_array().unwrap();
        let e = errs
            .iter()
            .find(|e| e["field"] == field)
            .unwrap_or_else(|| panic!("{field} not named in {p}"));
        assert!(e["message"].as_str().unwrap().len() > 5, "{e}");
    }
    // The message names the range; the value is echoed.
    let r = post(
        &app,
        "/v1/impact",
        &json!({"rock": {"density_kg_m3": -1.0}}),
    )
    .await;
    let p = r.json();
    assert_eq!(p["errors"][0]["value"], -1.0);
    assert!(
        p["errors"][0]["message"]
            .as_str()
            .unwrap()
            .contains("[100, 20000]"),
        "{p}"
    );
    // Every bad field of one request is listed.
    let r = post(
        &app,
        "/v1/impact",
        &json!({"velocity_m_s": -1, "rock": {"density_kg_m3": 0}}),
    )
    .await;
    assert_eq!(
        assert_problem(&r, 422, "invalid_input")["errors"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
}

#[tokio::test]
async fn corner_radius_is_checked_only_for_hertz() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/impact",
        &json!({"rock": {"corner_radius_m": 0.2}}),
    )
    .await;
    assert_eq!(r.status, 200);
}

#[tokio::test]
async fn sphere_uses_its_radius_and_mass() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/impact",
        &json!({"rock": {"shape": "sphere", "radius_m": 0.1}, "contact": {"law": "hertz_point"}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let m = 4.0 / 3.0 * std::f64::consts::PI * 0.1f64.powi(3) * 2500.0;
    assert!(rel(b["mass_kg"].as_f64().unwrap(), m) < 1e-12);
}

#[tokio::test]
async fn type_and_shape_errors() {
    let app = common::app();
    // Not an object at the top or nested.
    for body in [json!([]), json!(null), json!("x"), json!(3)] {
        let r = post(&app, "/v1/impact", &body).await;
        assert_problem(&r, 422, "invalid_type");
    }
    let r = post(&app, "/v1/impact", &json!({"rock": [0.3, 2500]})).await;
    let p = assert_problem(&r, 422, "invalid_type");
    assert_eq!(p["errors"][0]["field"], "/rock");
    let r = post(&app, "/v1/impact", &json!({"rock": null})).await;
    assert_problem(&r, 422, "invalid_type");
    // Wrong scalar type, null where no null default.
    let r = post(&app, "/v1/impact", &json!({"velocity_m_s": "fast"})).await;
    assert_eq!(
        assert_problem(&r, 422, "invalid_type")["errors"][0]["field"],
        "/velocity_m_s"
    );
    let r = post(&app, "/v1/impact", &json!({"velocity_m_s": null})).await;
    assert_problem(&r, 422, "invalid_type");
    let r = post(
        &app,
        "/v1/impact",
        &json!({"output": {"curve_points": 2.5}}),
    )
    .await;
    assert_problem(&r, 422, "invalid_type");
    // A field shown with a null default may be null.
    let r = post(
        &app,
        "/v1/impact",
        &json!({"column": {"damping_ratio": null}}),
    )
    .await;
    assert_eq!(r.status, 200);
    // Unknown field, at depth: a typo never falls back to a default.
    let r = post(&app, "/v1/impact", &json!({"rock": {"densty_kg_m3": 3000}})).await;
    let p = assert_problem(&r, 422, "unknown_field");
    assert_eq!(p["errors"][0]["field"], "/rock/densty_kg_m3");
    let r = post(&app, "/v1/impact", &json!({"velocity": 5})).await;
    assert_problem(&r, 422, "unknown_field");
    // Unknown enum value.
    let r = post(&app, "/v1/impact", &json!({"contact": {"law": "lundberg"}})).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/contact/law");
}

#[tokio::test]
async fn malformed_bodies_media_types_and_sizes() {
    let app = common::app();
    for raw in [
        "{",
        "{\"velocity_m_s\": NaN}",
        "{\"velocity_m_s\": Infinity}",
        "{\"velocity_m_s\": 1e999}",
        "",
    ] {
        let r = send(
            &app,
            Method::POST,
            "/v1/impact",
            Some("application/json"),
            raw.as_bytes().to_vec(),
            None,
        )
        .await;
        assert_problem(&r, 400, "malformed_json");
    }
    let r = send(
        &app,
        Method::POST,
        "/v1/impact",
        Some("text/plain"),
        b"{}".to_vec(),
        None,
    )
    .await;
    assert_problem(&r, 415, "unsupported_media_type");
    let r = send(&app, Method::POST, "/v1/impact", None, b"{}".to_vec(), None).await;
    assert_problem(&r, 415, "unsupported_media_type");
    let small = gangue::app(gangue::config::Config {
        max_body_bytes: 2048,
        ..Default::default()
    });
    let big = format!("{{\"velocity_m_s\": 5{}}}", " ".repeat(4096));
    let r = send(
        &small,
        Method::POST,
        "/v1/impact",
        Some("application/json"),
        big.into_bytes(),
        None,
    )
    .await;
    assert_problem(&r, 413, "payload_too_large");
}

#[tokio::test]
async fn progress_stream_ends_with_one_result_line() {
    let app = common::app();
    let r = send(
        &app,
        Method::POST,
        "/v1/impact",
        Some("application/json"),
        b"{}".to_vec(),
        Some("application/x-ndjson"),
    )
    .await;
    assert_eq!(r.status, 200);
    assert!(r.content_type().starts_with("application/x-ndjson"));
    let text = String::from_utf8(r.body).unwrap();
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let last = lines.last().unwrap();
    assert!(
        rel(
            last["result"]["max_force_n"].as_f64().unwrap(),
            994968.3372475737
        ) < 1e-9
    );
    assert!(
        lines[..lines.len() - 1]
            .iter()
            .all(|l| l.get("progress").is_some())
    );
    // A problem also arrives as one line.
    let r = send(
        &app,
        Method::POST,
        "/v1/impact",
        Some("application/json"),
        br#"{"velocity_m_s": 400, "rock": {"side_length_m": 0.05, "elastic_modulus_pa": 5e8}}"#
            .to_vec(),
        Some("application/x-ndjson"),
    )
    .await;
    let text = String::from_utf8(r.body).unwrap();
    let last: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(last["problem"]["type"], "/problems/capacity_exceeded");
}

fn warning_codes(b: &Value) -> Vec<String> {
    b["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["code"].as_str().unwrap().to_owned())
        .collect()
}

/// Validity (issue 12): a contact pressure above the column's yield stress is warned; the
/// threshold is strict (p₀ equal to σ_y is not warned), and the pressure itself does not depend
/// on σ_y, so both sides are sent with the same impact.
#[tokio::test]
async fn contact_pressure_above_yield_is_warned_on_both_sides_of_the_threshold() {
    let app = common::app();
    let base = post(&app, "/v1/impact", &json!({})).await.json();
    let p0 = base["max_contact_pressure_pa"].as_f64().unwrap();
    assert!(!warning_codes(&base).contains(&"contact_pressure_above_yield".into()));
    for (yield_stress, warned) in [
        (p0, false),
        (p0 * (1.0 + 1e-12), false),
        (p0 * (1.0 - 1e-12), true),
        (p0 / 2.0, true),
    ] {
        let b = post(
            &app,
            "/v1/impact",
            &json!({"column": {"yield_stress_pa": yield_stress}}),
        )
        .await
        .json();
        assert_eq!(b["max_contact_pressure_pa"].as_f64().unwrap(), p0);
        assert_eq!(
            warning_codes(&b).contains(&"contact_pressure_above_yield".into()),
            warned,
            "σ_y = {yield_stress}: {b}"
        );
    }
    // The issue's case: a 1 m block at 50 m/s on a Hertz corner, far above 345 MPa.
    let b = post(
        &app,
        "/v1/impact",
        &json!({"velocity_m_s": 50.0, "rock": {"side_length_m": 1.0}, "column": {"length_m": 1.31},
                "contact": {"law": "hertz_point"}}),
    )
    .await
    .json();
    assert!(
        warning_codes(&b).contains(&"contact_pressure_above_yield".into()),
        "{b}"
    );
}

/// Validity (issue 12): an approach δmax above a tenth of the contact radius is warned, and
/// not at or below it, over radii on both sides of the threshold.
#[tokio::test]
async fn approach_above_a_tenth_of_the_radius_is_warned_on_both_sides_of_the_threshold() {
    let app = common::app();
    let (mut seen_warned, mut seen_quiet) = (false, false);
    for radius in [0.001, 0.003, 0.01, 0.0179, 0.018, 0.03, 0.125, 1.0] {
        let b = post(
            &app,
            "/v1/impact",
            &json!({"contact": {"law": "hertz_point"}, "column": {"contact_radius_m": radius}}),
        )
        .await
        .json();
        let d = b["max_deformation_m"].as_f64().unwrap();
        let warned = warning_codes(&b).contains(&"approach_above_tenth_of_radius".into());
        assert_eq!(warned, d > 0.1 * radius, "R = {radius}, δmax = {d}: {b}");
        seen_warned |= warned;
        seen_quiet |= !warned;
    }
    assert!(
        seen_warned && seen_quiet,
        "both sides of the threshold were sent"
    );
}

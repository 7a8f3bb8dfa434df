//! Tiny and huge in-range values on every numeric field of `/v1/impact` and `/v1/column`, one
//! at a time with the others at their defaults, for both column models and all three laws.
//!
//! Physical expectation: every such request is answered with finite numbers or a clear 422
//! (a problem naming a field, or `capacity_exceeded` whose `max_velocity_m_s` is below the
//! velocity sent); never a 5xx. Energy is never created: the coupled column never holds more
//! than the rock brought (E_col + D ≤ KE within the integrator's estimate) and the rock never
//! rebounds faster than it came.

mod common;

use serde_json::{Value, json};

/// The largest f64 below x.
fn below(x: f64) -> f64 {
    f64::from_bits(x.to_bits() - 1)
}

/// (JSON Pointer, values) of every numeric field shared by both endpoints.
fn shared_fields() -> Vec<(&'static str, Vec<f64>)> {
    vec![
        ("/velocity_m_s", vec![5e-324, 1e-150, 1e-6, 1000.0]),
        ("/rock/side_length_m", vec![0.01, 5.0]),
        ("/rock/density_kg_m3", vec![100.0, 20000.0]),
        ("/rock/elastic_modulus_pa", vec![1e7, 1e12]),
        ("/rock/poisson_ratio", vec![0.0, below(0.5)]),
        ("/rock/corner_radius_m", vec![5e-324, 0.15]),
        ("/column/outer_diameter_m", vec![0.01, 2.0]),
        ("/column/inner_diameter_m", vec![0.0, below(0.25)]),
        ("/column/length_m", vec![0.1, 20.0]),
        ("/column/elastic_modulus_pa", vec![1e9, 1e12]),
        ("/column/poisson_ratio", vec![0.0, below(0.5)]),
        ("/column/density_kg_m3", vec![100.0, 20000.0]),
        ("/column/yield_stress_pa", vec![5e-324, 1e10]),
        ("/column/contact_radius_m", vec![0.001, 10.0]),
        ("/column/damping_ratio", vec![0.0, 5e-324, 10.0]),
        ("/column/damping_coefficient_n_s_m2", vec![0.0, 5e-324, 1e9]),
    ]
}

/// Sets the value at a JSON Pointer, creating objects on the way.
#[allow(clippy::needless_pass_by_value, reason = "called with json! literals")]
fn set(body: &mut Value, pointer: &str, v: Value) {
    let mut cur = body;
    let parts: Vec<&str> = pointer.trim_start_matches('/').split('/').collect();
    for (i, p) in parts.iter().enumerate() {
        if i + 1 == parts.len() {
            cur[*p] = v.clone();
        } else {
            if cur.get(*p).is_none() {
                cur[*p] = json!({});
            }
            cur = &mut cur[*p];
        }
    }
}

/// Every number in a JSON value is finite (serde_json cannot hold NaN; a null where a number
/// belongs is checked by the caller's fields).
fn all_finite(v: &Value) -> bool {
    match v {
        Value::Number(n) => n.as_f64().is_some_and(f64::is_finite),
        Value::Array(a) => a.iter().all(all_finite),
        Value::Object(o) => o.values().all(all_finite),
        _ => true,
    }
}

fn check(body: &Value, r: &common::Reply, coupled: bool) {
    let status = r.status.as_u16();
    assert!(
        status < 500,
        "{body}: {status} {}",
        String::from_utf8_lossy(&r.body)
    );
    let b = r.json();
    if status == 422 {
        let code = b["type"].as_str().unwrap_or("");
        if code == "/problems/capacity_exceeded" {
            let vmax = b["max_velocity_m_s"].as_f64().unwrap();
            let v = body["velocity_m_s"].as_f64().unwrap_or(5.0);
            assert!(
                vmax < v,
                "{body}: capacity with max velocity {vmax} ≥ {v}: {b}"
            );
            assert!(b["energy_parameter"].as_f64().unwrap() > 1.0, "{body}: {b}");
        } else if code == "/problems/too_many_steps" {
            let est = b["estimated_steps"].as_f64().unwrap();
            assert!(est > b["limit"].as_f64().unwrap(), "{body}: {b}");
        } else {
            assert!(
                b["errors"].as_array().is_some_and(|e| !e.is_empty()),
                "{body}: 422 without a field: {b}"
            );
        }
        return;
    }
    assert_eq!(status, 200, "{body}: {b}");
    assert!(all_finite(&b), "{body}: non-finite number in {b}");
    if coupled {
        let ke = b["kinetic_energy_j"].as_f64().unwrap();
        let est = b["integrator"]["estimated_error"]
            .as_f64()
            .unwrap()
            .max(1e-9);
        let after = b["column_energy_after_contact_j"].as_f64().unwrap();
        let end =
            b["column_energy_end_j"].as_f64().unwrap() + b["damping_energy_j"].as_f64().unwrap();
        assert!(
            after <= ke * (1.0 + 10.0 * est),
            "{body}: column {after} > KE {ke}"
        );
        assert!(
            end <= ke * (1.0 + 10.0 * est),
            "{body}: column + D {end} > KE {ke}"
        );
        let v = body["velocity_m_s"].as_f64().unwrap_or(5.0);
        let vr = b["rebound_velocity_m_s"].as_f64().unwrap();
        assert!(
            vr.abs() <= v * (1.0 + 10.0 * est),
            "{body}: rebound {vr} faster than {v}"
        );
    }
}

#[tokio::test]
async fn extreme_in_range_values_answer_finite_or_422_never_5xx() {
    let app = common::app();
    let started = std::time::Instant::now();
    let mut slowest = (0.0f64, String::new());
    for law in ["paper", "johnson", "hertz_point"] {
        for (endpoint, model) in [
            ("/v1/impact", None),
            ("/v1/column", Some("decoupled")),
            ("/v1/column", Some("coupled")),
        ] {
            let mut fields = shared_fields();
            match model {
                Some("decoupled") => {
                    fields.push(("/initial_midpoint_displacement_m", vec![5e-324, 1.0]));
                }
                Some(_) => {
                    fields.push(("/end_time_s", vec![1e-9, 1.0]));
                    fields.push(("/galerkin/modes", vec![1.0, 50.0]));
                }
                None => fields.push(("/output/curve_points", vec![0.0, 10000.0])),
            }
            for (field, values) in fields {
                for x in values {
                    let mut body = json!({"contact": {"law": law}});
                    if let Some(m) = model {
                        body["model"] = json!(m);
                    }
                    let v = if field.ends_with("modes") || field.ends_with("points") {
                        json!(x as u64)
                    } else {
                        json!(x)
                    };
                    set(&mut body, field, v);
                    if field == "/column/damping_ratio" {
                        body["column"]["damping_coefficient_n_s_m2"] = Value::Null;
                        body["column"]
                            .as_object_mut()
                            .unwrap()
                            .remove("damping_coefficient_n_s_m2");
                    }
                    let t = std::time::Instant::now();
                    let r = common::post(&app, endpoint, &body).await;
                    let dt = t.elapsed().as_secs_f64();
                    if dt > slowest.0 {
                        slowest = (dt, body.to_string());
                    }
                    check(&body, &r, model == Some("coupled"));
                }
            }
        }
    }
    eprintln!(
        "extremes: {:.2} s in all, slowest {:.3} s: {}",
        started.elapsed().as_secs_f64(),
        slowest.0,
        slowest.1
    );
}

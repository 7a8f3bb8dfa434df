//! A scene's `allowed_impacts` through the router: the allowed speed of each support and limit
//! is where the forward chain (a scene struck at `impact_velocity_m_s`) reaches the limit — within
//! it at the allowed speed, past it a relative 1e-6 faster; the allowed energy is the rock's
//! ½mv²; the design utilisation is the support's design impact speed (its design value at the
//! design percentile) over the allowed speed;
//! supports with equal columns share one answer; a column of twice the yield stress takes a
//! faster rock for the stress limit and the same for force and energy (which do not depend on
//! it); asking for none changes nothing else of the answer.

mod common;
use common::ok;

use common::{post, rel};
use serde_json::{Value, json};

const ROCK: f64 = 0.25;
const DENSITY: f64 = 2700.0;

/// The default column with twice its yield stress.
fn strong() -> Value {
    json!({"yield_stress_pa": 2.0 * 345.0e6})
}

/// A face with three supports: two of the default column, one of twice its yield stress.
fn scene(extra: &Value) -> Value {
    let mut s = json!({
        "rock": {"side_length_m": ROCK, "density_kg_m3": DENSITY},
        "design_limits": {"stress_utilisation": 1.0, "max_force_n": 2.0e5, "absorbed_energy_j": 50.0},
        "supports": [
            {"along_dip_m": 40},
            {"along_dip_m": 80, "column": strong()},
            {"along_dip_m": 110},
        ],
    });
    for (k, v) in extra.as_object().unwrap() {
        s[k] = v.clone();
    }
    s
}

/// The checks of every support struck at `v`, by limit name: (value, exceeded).
async fn checks_at(app: &axum::Router, v: f64) -> Vec<Vec<(String, Option<f64>, bool)>> {
    let b = ok(&post(app, "/v1/scene", &scene(&json!({"impact_velocity_m_s": v}))).await);
    b["impacts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| {
            i["checks"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| {
                    (
                        c["limit"].as_str().unwrap().to_string(),
                        c["value"].as_f64(),
                        c["exceeded"].as_bool().unwrap(),
                    )
                })
                .collect()
        })
        .collect()
}

#[tokio::test]
async fn the_allowed_speed_is_where_the_forward_chain_reaches_each_limit() {
    let app = common::app();
    let b = ok(&post(&app, "/v1/scene", &scene(&json!({}))).await);
    let allowed = b["allowed_impacts"].as_array().unwrap();
    assert_eq!(allowed.len(), 3);
    let plan = b["plan"].as_array().unwrap();
    let stage = plan
        .iter()
        .find(|p| p["stage"] == "allowed_impacts")
        .unwrap();
    assert_eq!(stage["status"], "ran");
    assert!(
        stage["reason"]
            .as_str()
            .unwrap()
            .contains("2 distinct column"),
        "{stage}"
    );
    let mass = DENSITY * ROCK.powi(3);
    for (k, a) in allowed.iter().enumerate() {
        assert_eq!(a["support"], k as u64 + 1);
        // a single run: no design speed
        assert!(a.get("design_impact_velocity_m_s").is_none(), "{a}");
        let limits = a["limits"].as_array().unwrap();
        let names: Vec<&str> = limits
            .iter()
            .map(|l| l["limit"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            ["stress_utilisation", "max_force_n", "absorbed_energy_j"]
        );
        for l in limits {
            let v = l["impact_velocity_m_s"].as_f64().unwrap();
            assert_eq!(l["ended_by"], "limit", "{l}");
            assert!(v > 0.0 && v < 1000.0, "{l}");
            assert!(rel(l["kinetic_energy_j"].as_f64().unwrap(), 0.5 * mass * v * v) < 1e-12);
            // the check's value at the allowed speed is the limit (to the bracket's width)
            let value = l["value"].as_f64().unwrap();
            let limit = l["allowed"].as_f64().unwrap();
            assert!(value <= limit && rel(value, limit) < 1e-7, "{l}");
            assert!(l.get("design_utilisation").is_none());
        }
    }
    // equal columns share the answer; twice the yield stress: the stress utilisation halves at
    // every speed, so a faster rock is allowed; force and energy do not depend on it
    assert_eq!(allowed[0]["limits"], allowed[2]["limits"]);
    for (weak, strong) in allowed[0]["limits"]
        .as_array()
        .unwrap()
        .iter()
        .zip(allowed[1]["limits"].as_array().unwrap())
    {
        let (w, s) = (
            weak["impact_velocity_m_s"].as_f64().unwrap(),
            strong["impact_velocity_m_s"].as_f64().unwrap(),
        );
        if weak["limit"] == "stress_utilisation" {
            assert!(
                s > 1.05 * w,
                "twice the yield stress takes a faster rock: {w} vs {s}"
            );
        } else {
            assert_eq!(w, s, "{weak} vs {strong}");
        }
    }
    // the forward chain: within every limit at the allowed speed, past it just above
    for (k, a) in allowed.iter().enumerate() {
        for (j, l) in a["limits"].as_array().unwrap().iter().enumerate() {
            let v = l["impact_velocity_m_s"].as_f64().unwrap();
            let at = checks_at(&app, v).await;
            let above = checks_at(&app, v * (1.0 + 1e-6)).await;
            assert_eq!(at[k][j].0, l["limit"].as_str().unwrap());
            assert!(
                !at[k][j].2,
                "support {k} {l}: exceeded at the allowed speed: {:?}",
                at[k][j]
            );
            assert!(
                above[k][j].2,
                "support {k} {l}: not exceeded just above it: {:?}",
                above[k][j]
            );
        }
    }
}

#[tokio::test]
async fn an_ensemble_gives_each_support_its_design_speed_and_utilisation() {
    let app = common::app();
    let req = scene(&json!({"monte_carlo": {"runs": 300, "seed": 7}}));
    let b = ok(&post(&app, "/v1/scene", &req).await);
    let stats = b["statistics"]["supports"].as_array().unwrap();
    let allowed = b["allowed_impacts"].as_array().unwrap();
    let mut reached = 0;
    for (s, a) in stats.iter().zip(allowed) {
        match s["design_values"].get("impact_speed_m_s") {
            Some(d) => {
                reached += 1;
                let design = a["design_impact_velocity_m_s"].as_f64().unwrap();
                assert_eq!(design, d["design_value"].as_f64().unwrap());
                for l in a["limits"].as_array().unwrap() {
                    let v = l["impact_velocity_m_s"].as_f64().unwrap();
                    let u = l["design_utilisation"].as_f64().unwrap();
                    assert!(rel(u, design / v) < 1e-15, "{l}");
                }
            }
            None => assert!(a.get("design_impact_velocity_m_s").is_none(), "{a}"),
        }
    }
    assert!(
        reached > 0,
        "no support was reached: the test checks nothing"
    );
    // the allowed speeds themselves do not depend on the ensemble
    let single = ok(&post(&app, "/v1/scene", &scene(&json!({}))).await);
    for (a, s) in allowed
        .iter()
        .zip(single["allowed_impacts"].as_array().unwrap())
    {
        for (l, m) in a["limits"]
            .as_array()
            .unwrap()
            .iter()
            .zip(s["limits"].as_array().unwrap())
        {
            assert_eq!(l["impact_velocity_m_s"], m["impact_velocity_m_s"]);
        }
    }
}

#[tokio::test]
async fn asking_for_no_allowed_impacts_changes_nothing_else() {
    let app = common::app();
    for extra in [
        json!({}),
        json!({"monte_carlo": {"runs": 50}}),
        json!({"impact_velocity_m_s": 4.0}),
    ] {
        let mut with = ok(&post(&app, "/v1/scene", &scene(&extra)).await);
        let mut off = extra.clone();
        off["allowed_impacts"] = json!(false);
        let mut without = ok(&post(&app, "/v1/scene", &scene(&off)).await);
        assert!(without.get("allowed_impacts").is_none());
        with.as_object_mut().unwrap().remove("allowed_impacts");
        let plan = with["plan"].as_array_mut().unwrap();
        let k = plan
            .iter()
            .position(|p| p["stage"] == "allowed_impacts")
            .unwrap();
        plan.remove(k);
        for v in [&mut with, &mut without] {
            v.as_object_mut().unwrap().remove("inputs");
        }
        assert_eq!(with, without, "{extra}");
    }
}

#[tokio::test]
async fn without_design_limits_nothing_is_inverted() {
    let app = common::app();
    let mut req = scene(&json!({}));
    req["design_limits"] = json!({"stress_utilisation": null});
    let b = ok(&post(&app, "/v1/scene", &req).await);
    assert_eq!(b["allowed_impacts"], json!([]));
    let plan = b["plan"].as_array().unwrap();
    let stage = plan
        .iter()
        .find(|p| p["stage"] == "allowed_impacts")
        .unwrap();
    assert_eq!(stage["status"], "skipped");
}

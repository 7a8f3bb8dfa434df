//! `POST /v1/scene` through the router. Physical expectations: every stage of the chain gives
//! the same numbers as its own endpoint on the same inputs (impact and column bit for bit, the
//! migration up to a spanning support equal to a face ending there, the ensemble's migration run
//! for run); a rock reaching a column does so when its distance in the mean plane from the axis
//! falls to the column radius plus its bounding radius, at the time the closed-form motion gives;
//! outcome fractions sum to 1 and exceedance probabilities are counts over all runs.

mod common;

use common::{assert_rejections, post, rel};
use serde_json::{Value, json};

fn ok(r: &common::Reply) -> Value {
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    r.json()
}

/// Removes the members that legitimately differ between a nested and a standalone response.
fn strip_echo(mut v: Value) -> Value {
    if let Some(o) = v.as_object_mut() {
        o.remove("inputs");
        o.remove("model_version");
    }
    v
}

#[tokio::test]
async fn given_impact_velocity_the_impact_and_column_equal_their_endpoints_bit_for_bit() {
    let app = common::app();
    let column = json!({"outer_diameter_m": 0.3, "inner_diameter_m": 0.27, "length_m": 1.5});
    for (model, law) in [
        ("decoupled", "paper"),
        ("coupled", "paper"),
        ("decoupled", "hertz_point"),
    ] {
        let scene = json!({
            "impact_velocity_m_s": 6.5,
            "rock": {"side_length_m": 0.25, "density_kg_m3": 2700},
            "contact": {"law": law},
            "column_model": model,
            "supports": [{"along_dip_m": 60, "column": column}, {"along_dip_m": 100}],
        });
        let b = ok(&post(&app, "/v1/scene", &scene).await);
        assert!(b.get("migration").is_none());
        assert_eq!(b["plan"][1]["stage"], "migration");
        assert_eq!(b["plan"][1]["status"], "skipped");
        let impacts = b["impacts"].as_array().unwrap();
        assert_eq!(impacts.len(), 2);
        for (imp, col) in impacts.iter().zip([column.clone(), json!({})]) {
            let base = json!({
                "velocity_m_s": 6.5,
                "rock": {"side_length_m": 0.25, "density_kg_m3": 2700},
                "column": col,
                "contact": {"law": law},
            });
            let i = ok(&post(&app, "/v1/impact", &base).await);
            let mut creq = base.clone();
            creq["model"] = json!(model);
            let c = ok(&post(&app, "/v1/column", &creq).await);
            assert_eq!(
                strip_echo(imp["impact"].clone()),
                strip_echo(i),
                "{model} {law}"
            );
            assert_eq!(
                strip_echo(imp["column"].clone()),
                strip_echo(c),
                "{model} {law}"
            );
            assert_eq!(imp["impact_velocity_m_s"], 6.5);
        }
    }
}

#[tokio::test]
async fn a_single_run_to_a_spanning_support_equals_the_migration_of_a_face_ending_there() {
    let app = common::app();
    for (method, s) in [
        ("lumped_mass", 37.25),
        ("lumped_mass", 1.0),
        ("rigid_block", 12.5),
    ] {
        let mut scene = json!({
            "method": method,
            "supports": [{"along_dip_m": s}, {"along_dip_m": 110.0}],
            "design_limits": {"stress_utilisation": 1.0, "max_force_n": 1e6},
        });
        let mut mig = json!({"method": method, "face": {"length_m": s}});
        if method == "rigid_block" {
            scene["face"] = json!({"length_m": 20.0});
            scene["supports"][1]["along_dip_m"] = json!(19.0);
            scene["release"] = json!({"drop_height_m": 0.5});
            mig["release"] = json!({"drop_height_m": 0.5});
        }
        let b = ok(&post(&app, "/v1/scene", &scene).await);
        let m = ok(&post(&app, "/v1/migration", &mig).await);
        let a = &b["migration"]["arrival"];
        let am = &m["arrival"];
        assert_eq!(a["stop_reason"], "support", "{method} {s}");
        assert_eq!(am["stop_reason"], "lower_end");
        for k in [
            "time_s",
            "speed_m_s",
            "along_dip_velocity_m_s",
            "along_dip_m",
            "position_m",
        ] {
            assert_eq!(a[k], am[k], "{method} {s}: {k}");
        }
        assert_eq!(b["migration"]["impact_count"], m["impact_count"]);
        let imp = &b["impacts"][0];
        assert_eq!(imp["support"], 1);
        let v = imp["impact_velocity_m_s"].as_f64().unwrap();
        let vm = am["along_dip_velocity_m_s"].as_f64().unwrap();
        assert!(rel(v, vm) <= 1e-12, "{v} vs {vm}");
        // the struck support's impact is /v1/impact's at that speed
        let i = ok(&post(&app, "/v1/impact", &json!({"velocity_m_s": v})).await);
        assert_eq!(strip_echo(imp["impact"].clone()), strip_echo(i));
        let checks = imp["checks"].as_array().unwrap();
        assert_eq!(checks.len(), 2);
        let f = imp["column"]["max_force_n"].as_f64().unwrap();
        assert_eq!(checks[1]["value"].as_f64().unwrap(), f);
        assert_eq!(checks[1]["exceeded"], f > 1e6);
        let verdict = if checks.iter().any(|c| c["exceeded"] == true) {
            "exceeded"
        } else {
            "ok"
        };
        assert_eq!(imp["verdict"], verdict);
    }
}

#[tokio::test]
async fn a_bad_support_field_names_the_support_sent() {
    let app = common::app();
    let three = |col: Value| json!({"supports": [{"along_dip_m": 10}, {"along_dip_m": 20}, {"along_dip_m": 30, "column": col}]});
    assert_rejections(
        &app,
        "/v1/scene",
        vec![
            (
                three(json!({"outer_diameter_m": 5.0})),
                "/supports/2/column/outer_diameter_m",
                "invalid_input",
            ),
            (
                three(json!({"inner_diameter_m": 0.3})),
                "/supports/2/column/inner_diameter_m",
                "invalid_input",
            ),
            (
                three(json!({"length_m": 0.1})),
                "/supports/2/column/length_m",
                "invalid_input",
            ),
            (
                three(json!({"outer_diameter": 0.3})),
                "/supports/2/column/outer_diameter",
                "unknown_field",
            ),
            (
                json!({"supports": [{"along_dip_m": 500}]}),
                "/supports/0/along_dip_m",
                "invalid_input",
            ),
            (
                json!({"supports": [{}], "support_rows": {}}),
                "/support_rows",
                "invalid_input",
            ),
            (
                json!({"support_rows": {"count": 100}}),
                "/support_rows/count",
                "invalid_input",
            ),
            (
                json!({"migration_output": {"runs_csv": true}}),
                "/migration_output/runs_csv",
                "invalid_input",
            ),
            (
                json!({"impact_velocity_m_s": 0}),
                "/impact_velocity_m_s",
                "invalid_input",
            ),
            (
                json!({"design_limits": {"acceptable_probability": 2}}),
                "/design_limits/acceptable_probability",
                "invalid_input",
            ),
        ],
    )
    .await;
    // inside a batch, the pointer of the item's request
    let r = post(
        &app,
        "/v1/batch",
        &json!({"items": [{"kind": "spalling", "request": {}}, {"kind": "scene", "request": three(json!({"outer_diameter_m": 5.0}))}]}),
    )
    .await;
    assert_eq!(r.status, 200);
    let lines: Vec<Value> = String::from_utf8_lossy(&r.body)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines[1]["status"], 422);
    assert_eq!(
        lines[1]["problem"]["errors"][0]["field"],
        "/items/1/request/supports/2/column/outer_diameter_m"
    );
}

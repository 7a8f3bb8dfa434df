//! `POST /v1/scene` through the router. Physical expectations: every stage of the chain gives
//! the same numbers as its own endpoint on the same inputs (impact and column bit for bit, the
//! migration up to a spanning support equal to a face ending there, the ensemble's migration run
//! for run); a rock reaching a column does so when its distance in the mean plane from the axis
//! falls to the column radius plus its bounding radius, at the time the closed-form motion gives;
//! outcome fractions sum to 1 and exceedance probabilities are counts over all runs.

mod common;
use common::ok;

use common::{assert_rejections, post, rel};
use serde_json::{Value, json};

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

#[tokio::test]
async fn an_ensemble_to_a_spanning_support_at_the_lower_end_has_the_migration_along_dip_velocities()
{
    let app = common::app();
    let mc = json!({"runs": 300, "seed": 7, "friction_coefficient": {"distribution": "uniform", "min": 0.1, "max": 0.4}});
    // hertz_point has no capacity: every run that arrives is counted
    let scene = json!({"monte_carlo": mc, "contact": {"law": "hertz_point"},
                       "migration_output": {"runs_csv": true}});
    let b = ok(&post(&app, "/v1/scene", &scene).await);
    let m = ok(&post(
        &app,
        "/v1/migration",
        &json!({"monte_carlo": mc, "output": {"runs_csv": true}}),
    )
    .await);
    let st = &b["statistics"];
    let s0 = &st["supports"][0];
    assert_eq!(s0["along_dip_m"], 120.0);
    assert!(s0["across_m"].is_null());
    let mv = &m["statistics"]["along_dip_velocity_m_s"];
    assert!(mv["p50"].as_f64().unwrap() > 10.0);
    assert_eq!(
        s0["impact_velocity_m_s"], *mv,
        "the whole summary, bit for bit"
    );
    assert_eq!(s0["reached_fraction"], m["statistics"]["reached_fraction"]);
    let o = &st["outcomes"];
    assert_eq!(o["support"], m["statistics"]["reached_fraction"]);
    let sum: f64 = ["support", "lower_end", "at_rest", "left_floor", "end_time"]
        .iter()
        .map(|k| o[k].as_f64().unwrap())
        .sum();
    assert!((sum - 1.0).abs() < 1e-12);
    // the per-run CSV: /v1/migration's columns (with along_dip_velocity_m_s last) for the same
    // runs, then the scene's
    let csv = b["migration"]["runs_csv"].as_str().unwrap();
    let mcsv = m["runs_csv"].as_str().unwrap();
    let head = csv.lines().next().unwrap();
    // api.md's nine columns, the scene's seven, then the run columns both append and the
    // scene's passing height
    let mhead: Vec<&str> = mcsv.lines().next().unwrap().split(',').collect();
    assert_eq!(
        head,
        format!(
            "{},support,column_index,impact_velocity_m_s,max_force_n,absorbed_energy_j,stress_utilisation,capacity_exceeded,{},passing_height_m",
            mhead[..9].join(","),
            mhead[9..].join(",")
        )
    );
    assert!(
        mhead[..9]
            .join(",")
            .ends_with(",stop_reason,along_dip_velocity_m_s")
    );
    for (a, b) in csv.lines().skip(1).zip(mcsv.lines().skip(1)) {
        let a: Vec<&str> = a.split(',').collect();
        let b: Vec<&str> = b.split(',').collect();
        // same run, same numbers; only the stop reason names the support
        for k in [0, 1, 2, 3, 4, 5, 6, 8] {
            assert_eq!(a[k], b[k]);
        }
        assert_eq!(b[7] == "lower_end", a[7] == "support");
        if a[7] == "support" {
            assert_eq!(a[9], "1");
            assert_eq!(a[11], a[8], "impact speed = the down-dip velocity");
        }
    }
}

#[tokio::test]
async fn rocks_spread_across_the_face_pass_between_columns_and_outcomes_sum_to_one() {
    let app = common::app();
    // columns 1.5 m apart; a rock reaches one within 0.125 + √3·0.15 ≈ 0.385 m of its axis
    let scene = json!({
        "face": {"length_m": 60},
        "support_rows": {"lowest_along_dip_m": 50, "spacing_m": 10, "count": 2, "across_m": [-1.5, 0, 1.5]},
        "monte_carlo": {"runs": 400, "seed": 3,
                        "release_across_m": {"distribution": "uniform", "min": -2.25, "max": 2.25}},
        "contact": {"law": "hertz_point"},
        "migration_output": {"runs_csv": true},
    });
    let b = ok(&post(&app, "/v1/scene", &scene).await);
    let st = &b["statistics"];
    let o = &st["outcomes"];
    let sum: f64 = ["support", "lower_end", "at_rest", "left_floor", "end_time"]
        .iter()
        .map(|k| o[k].as_f64().unwrap())
        .sum();
    assert!((sum - 1.0).abs() < 1e-12, "{o}");
    let support = o["support"].as_f64().unwrap();
    let lower = o["lower_end"].as_f64().unwrap();
    // the covered fraction of [-2.25, 2.25] is 3 × 0.77 / 4.5 ≈ 0.51
    assert!(support > 0.35 && support < 0.67, "{o}");
    assert!(lower > 0.3, "some rocks pass between the columns: {o}");
    let entries = st["supports"].as_array().unwrap();
    assert_eq!(entries.len(), 6);
    let reached: f64 = entries
        .iter()
        .map(|e| e["reached_fraction"].as_f64().unwrap())
        .sum();
    assert!((reached - support).abs() < 1e-12);
    // a rock runs straight down the plane: the upper row (#2, at 40 m) catches it first, and the
    // lower row (#1) nothing
    for e in entries {
        let r = e["reached_fraction"].as_f64().unwrap();
        if e["support"] == 1 {
            assert_eq!(r, 0.0);
            assert!(
                e["impact_velocity_m_s"].is_null(),
                "never a 0 m/s median: {e}"
            );
        } else {
            assert!(r > 0.05, "{e}");
        }
    }
    let warned = b["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|w| w["code"] == "support_never_reached")
        .count();
    assert_eq!(warned, 3);
}

#[tokio::test]
async fn exceedance_probabilities_equal_a_count_of_the_per_run_csv() {
    let app = common::app();
    let limits = json!({"stress_utilisation": 0.5, "max_force_n": 3.0e5, "absorbed_energy_j": 2.0,
                        "acceptable_probability": 0.05});
    let scene = json!({
        "face": {"length_m": 40},
        "supports": [{"along_dip_m": 20, "across_m": 0.0}, {"along_dip_m": 30, "across_m": 0.6},
                     {"along_dip_m": 38}],
        "monte_carlo": {"runs": 300, "seed": 11,
                        "release_across_m": {"distribution": "uniform", "min": -1, "max": 1},
                        "side_length_m": {"distribution": "uniform", "min": 0.2, "max": 0.3},
                        "density_kg_m3": {"distribution": "uniform", "min": 2000, "max": 3000}},
        "release_zones": "table1",
        "design_limits": limits,
        "migration_output": {"runs_csv": true},
    });
    let b = ok(&post(&app, "/v1/scene", &scene).await);
    let st = &b["statistics"];
    let csv = b["migration"]["runs_csv"].as_str().unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 300);
    let n = rows.len() as f64;
    let mut any = 0usize;
    let mut tested = 0;
    for (k, e) in st["supports"].as_array().unwrap().iter().enumerate() {
        let mine: Vec<&Vec<String>> = rows
            .iter()
            .filter(|r| r[col("support")] == (k + 1).to_string())
            .collect();
        assert_eq!(
            e["reached_fraction"].as_f64().unwrap(),
            mine.len() as f64 / n
        );
        for (limit, allowed) in [
            ("stress_utilisation", 0.5),
            ("max_force_n", 3.0e5),
            ("absorbed_energy_j", 2.0),
        ] {
            let count = mine
                .iter()
                .filter(|r| {
                    r[col("capacity_exceeded")] == "true"
                        || r[col(limit)].parse::<f64>().unwrap() > allowed
                })
                .count();
            let p = &e["exceedance"][limit];
            assert_eq!(
                p["probability"].as_f64().unwrap(),
                count as f64 / n,
                "{k} {limit}"
            );
            let ci = p["ci95"].as_array().unwrap();
            let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
            assert!(lo <= count as f64 / n && count as f64 / n <= hi && hi > 0.0);
            if count > 0 && count < mine.len() {
                tested += 1;
            }
        }
        let p_max = ["stress_utilisation", "max_force_n", "absorbed_energy_j"]
            .iter()
            .map(|l| e["exceedance"][*l]["probability"].as_f64().unwrap())
            .fold(0.0, f64::max);
        assert_eq!(e["verdict"], if p_max > 0.05 { "exceeded" } else { "ok" });
    }
    for r in &rows {
        if r[col("support")].is_empty() {
            continue;
        }
        let ex = r[col("capacity_exceeded")] == "true"
            || r[col("stress_utilisation")].parse::<f64>().unwrap() > 0.5
            || r[col("max_force_n")].parse::<f64>().unwrap() > 3.0e5
            || r[col("absorbed_energy_j")].parse::<f64>().unwrap() > 2.0;
        any += usize::from(ex);
    }
    assert_eq!(
        st["any_exceeded"]["probability"].as_f64().unwrap(),
        any as f64 / n
    );
    assert!(tested >= 2, "the limits split the runs");
    assert_eq!(b["impacts"][0]["nominal"], true);
}

#[tokio::test]
async fn scene_ensembles_are_reproducible_whatever_the_thread_count() {
    let one = gangue::app(gangue::config::Config {
        solver_threads: Some(1),
        ..Default::default()
    });
    let two = gangue::app(gangue::config::Config {
        solver_threads: Some(2),
        ..Default::default()
    });
    let body = json!({
        "support_rows": {"lowest_along_dip_m": 110, "spacing_m": 20, "count": 5, "across_m": [-0.5, 0.5]},
        "monte_carlo": {"runs": 500, "seed": 5,
                        "release_across_m": {"distribution": "uniform", "min": -1, "max": 1}},
        "release_zones": "table1",
        "migration_output": {"runs_csv": true},
    });
    let a = post(&one, "/v1/scene", &body).await;
    let b = post(&two, "/v1/scene", &body).await;
    assert_eq!(a.status, 200, "{}", String::from_utf8_lossy(&a.body));
    assert_eq!(a.body, b.body, "same bytes with 1 and 2 threads");
}

#[tokio::test]
async fn a_sliding_rock_reaches_a_column_at_the_closed_form_time() {
    let app = common::app();
    // released on the plane at rest: s(t) = ½ a t², a = g (sin θ − μ cos θ), y = 0; the column
    // at (s_c, y_c) is reached where (s_c − s)² + y_c² = R², R = D/2 + √3 L/2
    let (g, dip, mu, l, d): (f64, f64, f64, f64, f64) = (9.81, 40.0, 0.3, 0.3, 0.25);
    let th = dip.to_radians();
    let a = g * (th.sin() - mu * th.cos());
    let r = d / 2.0 + 3f64.sqrt() * l / 2.0;
    for (sc, yc) in [(20.0, 0.0), (20.0, 0.3), (7.5, -0.38)] {
        let body = json!({
            "face": {"dip_deg": dip, "length_m": 50, "friction_coefficient": mu},
            "release": {"drop_height_m": 0},
            "supports": [{"along_dip_m": sc, "across_m": yc}],
            "contact": {"law": "hertz_point"},
        });
        let b = ok(&post(&app, "/v1/scene", &body).await);
        let arr = &b["migration"]["arrival"];
        assert_eq!(arr["stop_reason"], "support");
        let du = (r * r - yc * yc).sqrt();
        let s = sc - du;
        let t = (2.0 * s / a).sqrt();
        let v = a * t * du / r;
        let t_got = arr["time_s"].as_f64().unwrap();
        assert!(rel(t_got, t) < 1e-12, "t {t_got} vs {t}");
        assert!(rel(arr["along_dip_m"].as_f64().unwrap(), s) < 1e-12);
        let v_got = b["impacts"][0]["impact_velocity_m_s"].as_f64().unwrap();
        assert!(rel(v_got, v) < 1e-12, "v {v_got} vs {v}");
    }
    // a column just out of reach is passed
    let body = json!({
        "face": {"dip_deg": dip, "length_m": 50, "friction_coefficient": mu},
        "release": {"drop_height_m": 0},
        "supports": [{"along_dip_m": 20, "across_m": r * (1.0 + 1e-9)}],
    });
    let b = ok(&post(&app, "/v1/scene", &body).await);
    assert_eq!(b["migration"]["arrival"]["stop_reason"], "lower_end");
    assert!(b["impacts"].as_array().unwrap().is_empty());
    assert_eq!(b["plan"][2]["status"], "skipped");
}

#[tokio::test]
async fn a_rigid_block_stops_where_it_comes_within_reach_of_a_column() {
    let app = common::app();
    // the block's bounding radius is √3 L/2 (a cube), the column's radius D/2
    let r = 0.25 / 2.0 + 3f64.sqrt() * 0.3 / 2.0;
    let body = json!({
        "method": "rigid_block",
        "face": {"length_m": 20},
        "release": {"drop_height_m": 0.5},
        "supports": [{"along_dip_m": 10, "across_m": 0.1}],
        "contact": {"law": "hertz_point"},
    });
    let b = ok(&post(&app, "/v1/scene", &body).await);
    let a = &b["migration"]["arrival"];
    assert_eq!(a["stop_reason"], "support");
    let s = a["along_dip_m"].as_f64().unwrap();
    let y = a["position_m"][1].as_f64().unwrap();
    let d = (10.0 - s).hypot(y - 0.1);
    assert!(rel(d, r) < 1e-9, "distance {d} vs reach {r}");
    let v = b["impacts"][0]["impact_velocity_m_s"].as_f64().unwrap();
    assert!(v > 0.0 && v <= a["speed_m_s"].as_f64().unwrap());
}

#[tokio::test]
async fn compare_methods_puts_both_methods_side_by_side() {
    let app = common::app();
    let body = json!({
        "face": {"length_m": 15},
        "release": {"drop_height_m": 0.5},
        "supports": [{"along_dip_m": 15}],
        "monte_carlo": {"runs": 6, "seed": 1},
        "contact": {"law": "hertz_point"},
        "compare_methods": true,
    });
    let b = ok(&post(&app, "/v1/scene", &body).await);
    let c = b["comparison"].as_array().unwrap();
    assert_eq!(c.len(), 2);
    assert_eq!(c[0]["method"], "lumped_mass");
    assert_eq!(c[1]["method"], "rigid_block");
    for m in c {
        let o = &m["outcomes"];
        let sum: f64 = ["support", "lower_end", "at_rest", "left_floor", "end_time"]
            .iter()
            .map(|k| o[k].as_f64().unwrap())
            .sum();
        assert!((sum - 1.0).abs() < 1e-12);
        assert_eq!(m["supports"][0]["reached_fraction"], 1.0);
        assert!(
            m["supports"][0]["impact_velocity_median_m_s"]
                .as_f64()
                .unwrap()
                > 1.0
        );
    }
    // the request's own method is the ensemble of the statistics
    assert_eq!(
        c[0]["supports"][0]["impact_velocity_median_m_s"],
        b["statistics"]["supports"][0]["impact_velocity_m_s"]["p50"]
    );
}

#[tokio::test]
async fn a_scene_streams_progress_and_one_result() {
    let app = common::app();
    let body = json!({"monte_carlo": {"runs": 300, "seed": 2}, "face": {"length_m": 30}});
    let r = common::send(
        &app,
        axum::http::Method::POST,
        "/v1/scene",
        Some("application/json"),
        serde_json::to_vec(&body).unwrap(),
        Some("application/x-ndjson"),
    )
    .await;
    assert_eq!(r.status, 200);
    let lines: Vec<Value> = String::from_utf8_lossy(&r.body)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let last = lines.last().unwrap();
    assert_eq!(last["result"]["statistics"]["runs"], 300);
    // progress never runs past its total (the nominal run and the 300 of the ensemble)
    for l in &lines[..lines.len() - 1] {
        let p = &l["progress"];
        assert!(
            p["done"].as_u64().unwrap() <= p["total"].as_u64().unwrap(),
            "{p}"
        );
    }
    assert!(
        lines[..lines.len() - 1]
            .iter()
            .all(|l| l.get("progress").is_some())
    );
}

#[tokio::test]
async fn a_rock_released_within_reach_of_a_column_is_flagged_not_reported_as_a_normal_strike() {
    let app = common::app();
    // the release (along 5 m, across 0) lies 0.1 m from the column's axis, well inside its reach
    // (0.125 + √3·0.3/2 ≈ 0.385 m): the rock starts against the support, reached at t = 0 with
    // no impact; the answer must say so instead of presenting a 0 m/s strike as a result
    let body = json!({
        "face": {"dip_deg": 40, "length_m": 50},
        "release": {"drop_height_m": 0, "along_dip_m": 5},
        "supports": [{"along_dip_m": 5.1, "across_m": 0.0}],
    });
    let b = ok(&post(&app, "/v1/scene", &body).await);
    assert_eq!(b["migration"]["arrival"]["stop_reason"], "support");
    assert_eq!(b["migration"]["arrival"]["time_s"], 0.0);
    let w = b["warnings"].as_array().unwrap();
    assert!(
        w.iter().any(|w| w["code"] == "released_within_reach"),
        "{w:?}"
    );
    // released out of reach: no such warning
    let body = json!({
        "face": {"dip_deg": 40, "length_m": 50},
        "release": {"drop_height_m": 0, "along_dip_m": 5},
        "supports": [{"along_dip_m": 8, "across_m": 0.0}],
    });
    let b = ok(&post(&app, "/v1/scene", &body).await);
    assert_eq!(b["migration"]["arrival"]["stop_reason"], "support");
    let w = b["warnings"].as_array().unwrap();
    assert!(
        !w.iter().any(|w| w["code"] == "released_within_reach"),
        "{w:?}"
    );
}

/// A rule the column stage's physics checks (coupled history times within the window, which only
/// the solved impact fixes) names the scene's own `column_output`, not a column request's
/// `output` nor a field under a support.
#[tokio::test]
async fn a_physics_rule_broken_in_the_column_stage_names_the_scene_field() {
    let app = common::app();
    let scene = json!({
        "impact_velocity_m_s": 5.0,
        "column_model": "coupled",
        "column_output": {"times_s": [0.0, 10.0]},
        "supports": [{"along_dip_m": 10}, {"along_dip_m": 20}],
    });
    let r = post(&app, "/v1/scene", &scene).await;
    let p = common::assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/column_output/times_s/1", "{p}");
    // inside a batch item, under the item's request
    let r = post(
        &app,
        "/v1/batch",
        &json!({"items": [{"kind": "spalling", "request": {}}, {"kind": "scene", "request": scene}]}),
    )
    .await;
    let line: Value = String::from_utf8_lossy(&r.body)
        .lines()
        .nth(1)
        .map(|l| serde_json::from_str(l).unwrap())
        .unwrap();
    assert_eq!(
        line["problem"]["errors"][0]["field"], "/items/1/request/column_output/times_s/1",
        "{line}"
    );
}

/// A refused field of the scene's output objects is named where the scene holds it
/// (`/migration_output/…`, `/column_output/…`), never at a standalone request's `/output/…`, and
/// beside a refused support column each is named exactly.
#[tokio::test]
async fn a_refused_output_field_names_the_scene_output_object() {
    let app = common::app();
    let cases = [
        (
            json!({"migration_output": {"sample_interval_s": 0}}),
            vec!["/migration_output/sample_interval_s"],
        ),
        (
            json!({"column_output": {"duration_s": -1, "samples": 1}}),
            vec!["/column_output/duration_s", "/column_output/samples"],
        ),
        (
            json!({"column_output": {"times_s": [0.0, 2e6]}}),
            vec!["/column_output/times_s/1"],
        ),
        (
            json!({"column_output": {"times_s": [0.0], "duration_s": 1.0}}),
            vec!["/column_output/times_s"],
        ),
        (
            json!({"supports": [{"along_dip_m": 10}, {"along_dip_m": 20, "column": {"length_m": 0.1}}],
                   "column_output": {"duration_s": -1}}),
            vec!["/supports/1/column/length_m", "/column_output/duration_s"],
        ),
    ];
    for (body, fields) in cases {
        let r = post(&app, "/v1/scene", &body).await;
        let p = common::assert_problem(&r, 422, "invalid_input");
        let mut got: Vec<&str> = p["errors"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["field"].as_str().unwrap())
            .collect();
        got.sort_unstable();
        let mut want = fields.clone();
        want.sort_unstable();
        assert_eq!(got, want, "{body}: {p}");
    }
}

/// During the initial drop the rock's along-dip position runs from s₀ − h sin θ (the release
/// point lifted by h) to s₀, so a support standing in that interval, up-slope of the release
/// point, is reached in the fall by both kinds of support and both methods: on the plane the
/// rock (or the block's centre) moves as s(t) = s₀ − h sin θ + v₀ t + ½ g sin θ t², and a
/// spanning support at s_c is reached when s = s_c, a column on the rock's line when
/// s = s_c − R (R = D/2 + √3 L/2), both before the landing at t = √(2h/g).
#[tokio::test]
async fn a_support_between_the_lifted_start_and_the_release_point_is_reached_during_the_drop() {
    let app = common::app();
    let repro: Value = serde_json::from_str(
        &std::fs::read_to_string(
            common::shared_dir().join("repro/scene_support_above_release.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let req = &repro["request"];
    let th = req["face"]["dip_deg"].as_f64().unwrap().to_radians();
    let s0 = req["release"]["along_dip_m"].as_f64().unwrap();
    let h = req["release"]["drop_height_m"].as_f64().unwrap();
    let v0 = req["release"]["speed_m_s"].as_f64().unwrap();
    let sc = req["supports"][0]["along_dip_m"].as_f64().unwrap();
    let g = 9.81;
    let start = s0 - h * th.sin();
    assert!(start < sc && sc < s0);
    let t_land = (2.0 * h / g).sqrt();
    // the default rock (cube, L = 0.3 m) and column (D = 0.25 m)
    let reach = 0.25 / 2.0 + 3f64.sqrt() * 0.3 / 2.0;
    let a = g * th.sin();
    for method in ["lumped_mass", "rigid_block"] {
        for (across, s_reach) in [(Value::Null, sc), (json!(0.0), sc - reach)] {
            assert!(s_reach > start);
            let mut body = req.clone();
            body["method"] = json!(method);
            body["supports"][0]["across_m"] = across.clone();
            let b = ok(&post(&app, "/v1/scene", &body).await);
            let arr = &b["migration"]["arrival"];
            let what = format!("{method}, across {across}");
            assert_eq!(arr["stop_reason"], "support", "{what}: {arr}");
            // ½ a t² + v₀ t − (s_reach − start) = 0
            let t = 2.0 * (s_reach - start) / (v0 + (v0 * v0 + 2.0 * a * (s_reach - start)).sqrt());
            let t_got = arr["time_s"].as_f64().unwrap();
            assert!(
                t < t_land && rel(t_got, t) < 1e-9,
                "{what}: t {t_got} vs {t}"
            );
            assert!(
                arr["normal_offset_m"].as_f64().unwrap() > 1.0,
                "{what}: {arr}"
            );
            let v = b["impacts"][0]["impact_velocity_m_s"].as_f64().unwrap();
            assert!(rel(v, v0 + a * t) < 1e-9, "{what}: v {v} vs {}", v0 + a * t);
        }
    }
}

/// Release zones reaching where the block does not fit (the top 0.15 m of a grid, where a
/// 0.3 m cube overhangs its upper edge) are clipped to where it does, with a warning giving the
/// share clipped (0.1504/2 of a zone [0, 2] m); no run is lost off the floor (7 % were).
#[tokio::test]
async fn release_zones_are_clipped_to_where_the_block_fits_on_the_floor() {
    let app = common::app();
    let row: Vec<f64> = (0..18).map(|j| -f64::from(j)).collect();
    let body = json!({
        "method": "rigid_block",
        "face": {"dip_deg": 45, "length_m": 20,
                 "floor": {"kind": "grid", "origin_m": [0, -3], "spacing_m": 1,
                           "heights_m": vec![row; 7]}},
        "release": {"drop_height_m": 0},
        "release_zones": [{"from_along_dip_m": 0, "to_along_dip_m": 2, "weight": 1}],
        "monte_carlo": {"runs": 12, "seed": 7},
        "supports": [{"along_dip_m": 10}],
    });
    let b = ok(&post(&app, "/v1/scene", &body).await);
    let o = &b["statistics"]["outcomes"];
    assert_eq!(o["left_floor"], 0.0, "{o}");
    assert_eq!(o["support"], 1.0, "{o}");
    let w = b["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["code"] == "release_zones_clipped")
        .unwrap_or_else(|| panic!("{}", b["warnings"]));
    let m = w["message"].as_str().unwrap();
    let pct: f64 = m.split(" %").next().unwrap().parse().unwrap();
    let r_max = 3f64.sqrt() * 0.3 / 2.0;
    assert!(
        (7.5..=100.0 * (0.15 + 2e-3 * r_max) / 2.0 + 0.005).contains(&pct),
        "{m}"
    );
}

/// A density drawn from a truncated normal about 2 500 kg/m³ is taken (its mean lies in the
/// density's own range, beyond the ±1 000 other fields' means are held to), and every drawn
/// density lies in [min, max]; a mean outside the density's range is refused naming it.
#[tokio::test]
async fn a_truncated_normal_density_about_its_own_scale_is_taken() {
    let app = common::app();
    let body = json!({
        "monte_carlo": {"runs": 60, "density_kg_m3":
            {"distribution": "truncated_normal", "mean": 2500.0, "std": 300.0, "min": 2000.0, "max": 3000.0}},
        "migration_output": {"runs_csv": true},
    });
    let b = ok(&post(&app, "/v1/scene", &body).await);
    let csv = b["migration"]["runs_csv"].as_str().unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = head.iter().position(|h| *h == "density_kg_m3").unwrap();
    let d: Vec<f64> = lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect();
    assert_eq!(d.len(), 60);
    assert!(d.iter().all(|x| (2000.0..=3000.0).contains(x)), "{d:?}");
    assert!(d.iter().any(|&x| x != d[0]), "no density drawn");
    let mut bad = body.clone();
    bad["monte_carlo"]["density_kg_m3"]["mean"] = json!(30000.0);
    let r = post(&app, "/v1/scene", &bad).await;
    let p = common::assert_problem(&r, 422, "invalid_input");
    assert!(
        p["errors"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["field"] == "/monte_carlo/density_kg_m3/mean"),
        "{p}"
    );
}

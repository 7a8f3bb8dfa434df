//! Barriers and collectors through the router: a collector records each run's state at its
//! line (recomputed here from the runs CSV) and changes nothing else; a barrier at the release
//! line stops every rock below its height and within its rating; a barrier rated below a
//! sliding rock's energy takes exactly its rating (the closed form of a slide on the plane);
//! shares of stopped, broken through and overtopped runs are the CSV's counts; both migration
//! methods honour them; bad devices are refused naming the field.

mod common;
use common::ok;

use common::{assert_rejections, post};
use serde_json::{Value, json};

const RUNS: u64 = 300;

/// The runs CSV of a scene answer as rows of named cells.
fn csv_rows(answer: &Value) -> Vec<std::collections::HashMap<String, String>> {
    let text = answer["migration"]["runs_csv"].as_str().expect("runs CSV");
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

#[tokio::test]
async fn collectors_record_each_run_as_the_csv_says_and_change_nothing_else() {
    let app = common::app();
    let plain = ok(&post(&app, "/v1/scene", &common::risky_scene(RUNS, 7)).await);
    let mut s = common::risky_scene(RUNS, 7);
    s["collectors"] = json!([
        {"along_dip_m": 20.0},
        {"along_dip_m": 60.0, "across_m": [-0.5, 0.5]},
    ]);
    let with = ok(&post(&app, "/v1/scene", &s).await);
    // the supports' answer is the same (the lines cut the closed-form pieces: rounding only)
    let (a, b) = (&plain["statistics"], &with["statistics"]);
    assert_eq!(a["outcomes"], b["outcomes"]);
    assert_eq!(a["any_exceeded"], b["any_exceeded"]);
    for (x, y) in a["supports"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["supports"].as_array().unwrap())
    {
        assert_eq!(x["reached_fraction"], y["reached_fraction"]);
        assert_eq!(x["exceedance"], y["exceedance"]);
        if let (Some(p), Some(q)) = (
            x["impact_velocity_m_s"]["mean"].as_f64(),
            y["impact_velocity_m_s"]["mean"].as_f64(),
        ) {
            assert!(common::rel(p, q) < 1e-9, "{p} vs {q}");
        }
    }
    // each collector's statistics from the runs CSV
    let rows = csv_rows(&with);
    assert_eq!(rows.len() as u64, RUNS);
    let cols = b["collectors"].as_array().unwrap();
    assert_eq!(cols.len(), 2);
    for (i, c) in cols.iter().enumerate() {
        let name = format!("collector_{}", i + 1);
        let mut speeds: Vec<f64> = rows
            .iter()
            .filter_map(|r| r[&format!("{name}_speed_m_s")].parse().ok())
            .collect();
        let reached = speeds.len();
        assert!(reached > 0, "{name}: no run reached it");
        let p = c["reached"]["probability"].as_f64().unwrap();
        assert_eq!(p, reached as f64 / RUNS as f64, "{name}");
        for r in &rows {
            let action = &r[&format!("{name}_action")];
            assert!(action.is_empty() || action == "passed", "{action}");
        }
        speeds.sort_by(f64::total_cmp);
        let v = &c["values"];
        assert_eq!(v["speed_m_s"]["count"], reached);
        let dv = v["speed_m_s"]["design_value"].as_f64().unwrap();
        assert!(
            common::rel(dv, common::type7(&speeds, 0.95)) < 1e-12,
            "{dv}"
        );
        let mean = speeds.iter().sum::<f64>() / reached as f64;
        let m = v["speed_m_s"]["summary"]["mean"].as_f64().unwrap();
        assert!(common::rel(m, mean) < 1e-12, "{m} vs {mean}");
        // the kinetic energy is the sum of its parts, run by run
        for r in &rows {
            if let Ok(k) = r[&format!("{name}_kinetic_energy_j")].parse::<f64>() {
                let t: f64 = r[&format!("{name}_translational_energy_j")]
                    .parse()
                    .unwrap();
                let o: f64 = r[&format!("{name}_rotational_energy_j")].parse().unwrap();
                assert!(common::rel(k, t + o) < 1e-12);
                let h: f64 = r[&format!("{name}_passing_height_m")].parse().unwrap();
                assert!(h >= 0.0);
            }
        }
    }
    // the narrow collector sees only the runs crossing its range: fewer than the wide one at 20 m
    assert!(
        cols[1]["reached"]["probability"].as_f64().unwrap()
            < cols[0]["reached"]["probability"].as_f64().unwrap()
    );
    // a scene without devices carries no device fields
    assert!(a.get("collectors").is_none() && a.get("barriers").is_none());
    assert!(a["outcomes"].get("barrier").is_none());
}

#[tokio::test]
async fn a_barrier_at_the_release_line_stops_every_rock_below_its_height_and_rating() {
    let app = common::app();
    for method in ["lumped_mass", "rigid_block"] {
        let mut s = common::risky_scene(if method == "rigid_block" { 40 } else { RUNS }, 3);
        s["method"] = json!(method);
        s["barriers"] = json!([{"along_dip_m": 0.0, "height_m": 100.0, "energy_rating_j": 1e12}]);
        let a = ok(&post(&app, "/v1/scene", &s).await);
        let st = &a["statistics"];
        assert_eq!(st["outcomes"]["barrier"], 1.0, "{method}");
        let b = &st["barriers"][0];
        assert_eq!(b["reached"]["probability"], 1.0, "{method}");
        assert_eq!(b["outcomes"]["stopped"]["probability"], 1.0, "{method}");
        assert_eq!(st["any_exceeded"]["probability"], 0.0, "{method}");
        for sup in st["supports"].as_array().unwrap() {
            assert_eq!(sup["reached_fraction"], 0.0, "{method}");
        }
        // the nominal run ends at the barrier too, its energy account closed with it
        let m = &a["migration"];
        assert_eq!(m["arrival"]["stop_reason"], "barrier", "{method}");
        let e = &m["energy"];
        assert!(
            e["residual_j"].as_f64().unwrap().abs() < 1e-6 * e["total_start_j"].as_f64().unwrap(),
            "{method}: {e}"
        );
    }
}

#[tokio::test]
async fn a_barrier_takes_its_rating_from_a_sliding_rock() {
    let app = common::app();
    // a rock released at rest on the plane slides: friction work μ m g cos θ per metre at any
    // speed, so a barrier rated R leaves it R less at the lower end
    let base = json!({
        "release": {"drop_height_m": 0.0, "along_dip_m": 5.0},
        "supports": [{"along_dip_m": 110.0}],
        "migration_output": {"events": true},
    });
    let free = ok(&post(&app, "/v1/scene", &base).await);
    let ke_free = free["migration"]["arrival"]["kinetic_energy_j"]
        .as_f64()
        .unwrap();
    let m = free["migration"]["mass_kg"].as_f64().unwrap();
    let th = 45f64.to_radians();
    let at_line = m * 9.81 * (th.sin() - 0.2 * th.cos()) * 35.0;
    let rating = 0.4 * at_line;
    let mut s = base.clone();
    s["barriers"] = json!([{"along_dip_m": 40.0, "height_m": 0.5, "energy_rating_j": rating}]);
    let a = ok(&post(&app, "/v1/scene", &s).await);
    let ke = a["migration"]["arrival"]["kinetic_energy_j"]
        .as_f64()
        .unwrap();
    assert!(
        common::rel(ke, ke_free - rating) < 1e-9,
        "{ke} vs {}",
        ke_free - rating
    );
    let e = &a["migration"]["energy"];
    assert!(
        common::rel(e["barriers_j"].as_f64().unwrap(), rating) < 1e-9,
        "{e}"
    );
    let ev = a["migration"]["events"].as_array().unwrap();
    let b = ev
        .iter()
        .find(|e| e["kind"] == "barrier")
        .expect("a barrier event");
    assert!(common::rel(b["energy_lost_j"].as_f64().unwrap(), rating) < 1e-9);
    assert!((b["along_dip_m"].as_f64().unwrap() - 40.0).abs() < 1e-9);
    // the impact on the support is the slower rock's
    let v_free = free["impacts"][0]["impact_velocity_m_s"].as_f64().unwrap();
    let v = a["impacts"][0]["impact_velocity_m_s"].as_f64().unwrap();
    assert!(common::rel(0.5 * m * v * v, 0.5 * m * v_free * v_free - rating) < 1e-9);
}

#[tokio::test]
async fn barrier_shares_are_the_csv_counts_and_broken_through_is_warned() {
    let app = common::app();
    let mut s = common::risky_scene(RUNS, 11);
    // rated near the middle of what reaches it, high enough that some rocks pass over
    s["barriers"] = json!([{"along_dip_m": 30.0, "height_m": 0.3, "energy_rating_j": 600.0}]);
    s["collectors"] = json!([{"along_dip_m": 30.0}]);
    let a = ok(&post(&app, "/v1/scene", &s).await);
    let rows = csv_rows(&a);
    let count = |what: &str| {
        rows.iter()
            .filter(|r| r["barrier_1_action"] == what)
            .count() as f64
            / RUNS as f64
    };
    let b = &a["statistics"]["barriers"][0]["outcomes"];
    for what in ["stopped", "broken_through", "overtopped"] {
        assert_eq!(
            b[what]["probability"].as_f64().unwrap(),
            count(what),
            "{what}"
        );
    }
    assert!(
        count("stopped") > 0.0 && count("broken_through") > 0.0,
        "{b}"
    );
    assert_eq!(
        a["statistics"]["outcomes"]["barrier"].as_f64().unwrap(),
        count("stopped")
    );
    // the collector at the barrier's line sees the runs the barrier let through
    let through = 1.0 - count("stopped");
    let c = a["statistics"]["collectors"][0]["reached"]["probability"]
        .as_f64()
        .unwrap();
    assert!((c - through).abs() < 1e-12, "{c} vs {through}");
    let w = a["warnings"].as_array().unwrap();
    assert!(
        w.iter().any(|w| w["code"] == "barrier_broken_through"),
        "{w:?}"
    );
}

#[tokio::test]
async fn bad_devices_are_refused_naming_the_field() {
    let app = common::app();
    let with = |k: &str, v: Value| {
        let mut s = json!({"supports": [{"along_dip_m": 100.0}]});
        s[k] = v;
        s
    };
    let b = |along: f64, height: f64, rating: f64| json!({"along_dip_m": along, "height_m": height, "energy_rating_j": rating});
    assert_rejections(
        &app,
        "/v1/scene",
        vec![
            (with("barriers", json!([b(130.0, 1.0, 1.0)])), "/barriers/0/along_dip_m", "invalid_input"),
            (with("barriers", json!([b(10.0, 0.0, 1.0)])), "/barriers/0/height_m", "invalid_input"),
            (with("barriers", json!([b(10.0, 1.0, -1.0)])), "/barriers/0/energy_rating_j", "invalid_input"),
            (
                with("barriers", json!([b(10.0, 1.0, 1.0), b(10.0, 2.0, 5.0)])),
                "/barriers/1",
                "invalid_input",
            ),
            (
                with(
                    "barriers",
                    json!([{"along_dip_m": 10.0, "across_m": [1.0, -1.0], "height_m": 1.0, "energy_rating_j": 1.0}]),
                ),
                "/barriers/0/across_m/1",
                "invalid_input",
            ),
            (with("collectors", json!([{"along_dip_m": -1.0}])), "/collectors/0/along_dip_m", "invalid_input"),
        ],
    )
    .await;
    // barriers at one position with separate ranges are fine
    let s = with(
        "barriers",
        json!([
            {"along_dip_m": 10.0, "across_m": [-2.0, 0.0], "height_m": 1.0, "energy_rating_j": 1.0},
            {"along_dip_m": 10.0, "across_m": [0.5, 2.0], "height_m": 1.0, "energy_rating_j": 1.0},
        ]),
    );
    ok(&post(&app, "/v1/scene", &s).await);
}

/// The barrier search's answer checked by re-running the scene with the barriers it proposes:
/// each support's exceedance is the one it reported, bit for bit (the same seeded runs), and
/// when it says acceptable every upper bound is within the acceptable probability.
#[tokio::test]
async fn the_barrier_search_is_checked_by_rerunning_the_scene_with_its_barriers() {
    let app = common::app();
    let acceptable = 0.05;
    let mut s = common::risky_scene(RUNS, 5);
    s["migration_output"] = json!({});
    s["design"] = json!({
        "acceptable_probability": acceptable,
        "barriers": {"every_kth_support": 1},
    });
    let a = ok(&post(&app, "/v1/scene", &s).await);
    let d = &a["design"]["barriers"];
    let proposed = d["barriers"].as_array().unwrap();
    assert!(!proposed.is_empty(), "{d}");
    assert_eq!(d["candidates"].as_array().unwrap().len(), 3);
    assert!(
        a["plan"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["stage"] == "design_barriers")
    );
    // no guard searched when only barriers are asked for
    assert!(
        a["design"]["supports"]
            .as_array()
            .unwrap()
            .iter()
            .all(|e| e["guarded"] == false)
    );
    let mut check = common::risky_scene(RUNS, 5);
    check["migration_output"] = json!({});
    check["barriers"] = json!(
        proposed
            .iter()
            .map(|b| json!({
                "along_dip_m": b["along_dip_m"],
                "height_m": b["height_m"],
                "energy_rating_j": b["energy_rating_j"],
            }))
            .collect::<Vec<_>>()
    );
    let c = ok(&post(&app, "/v1/scene", &check).await);
    for (want, got) in d["supports"]
        .as_array()
        .unwrap()
        .iter()
        .zip(c["statistics"]["supports"].as_array().unwrap())
    {
        // one design limit: the support's exceedance is that limit's
        assert_eq!(
            want["exceedance"], got["exceedance"]["stress_utilisation"],
            "{want} {got}"
        );
        let upper = want["exceedance"]["ci95"][1].as_f64().unwrap();
        assert_eq!(want["acceptable"], json!(upper <= acceptable));
    }
    if d["all_acceptable"] == true {
        assert!(
            c["statistics"]["supports"]
                .as_array()
                .unwrap()
                .iter()
                .all(|s| s["exceedance"]["stress_utilisation"]["ci95"][1]
                    .as_f64()
                    .unwrap()
                    <= acceptable)
        );
    }
    // each proposed rating and height is the rounded-up design percentile: positive
    for b in proposed {
        assert!(b["energy_rating_j"].as_f64().unwrap() > 0.0);
        assert!(b["height_m"].as_f64().unwrap() >= 0.01);
    }
}

#[tokio::test]
async fn a_barrier_search_past_the_run_limit_or_malformed_is_refused() {
    let app = common::app();
    let mut s = common::risky_scene(400_000, 5);
    s["design"] = json!({"acceptable_probability": 0.05, "barriers": {"every_kth_support": 1}});
    assert_rejections(
        &app,
        "/v1/scene",
        vec![(s, "/design/barriers", "invalid_input")],
    )
    .await;
    let mut s = common::risky_scene(10, 5);
    s["design"] = json!({"acceptable_probability": 0.05, "barriers": {"every_kth_support": 0}});
    assert_rejections(
        &app,
        "/v1/scene",
        vec![(s, "/design/barriers/every_kth_support", "invalid_input")],
    )
    .await;
}

/// Barriers and collectors give the same bytes on 1 and 3 solver threads, in both methods.
#[tokio::test]
async fn devices_give_the_same_bytes_whatever_the_thread_count() {
    let app = |threads| {
        gangue::app(gangue::config::Config {
            solver_threads: Some(threads),
            ..Default::default()
        })
    };
    let (one, three) = (app(1), app(3));
    for (method, runs) in [("lumped_mass", 400), ("rigid_block", 12)] {
        let mut s = common::risky_scene(runs, 13);
        s["method"] = json!(method);
        s["barriers"] = json!([{"along_dip_m": 30.0, "height_m": 0.3, "energy_rating_j": 600.0}]);
        s["collectors"] = json!([{"along_dip_m": 20.0}, {"along_dip_m": 60.0}]);
        let a = post(&one, "/v1/scene", &s).await;
        let b = post(&three, "/v1/scene", &s).await;
        assert_eq!(a.status, 200, "{}", String::from_utf8_lossy(&a.body));
        assert!(
            a.body == b.body,
            "{method}: same bytes with 1 and 3 threads"
        );
        assert!(
            a.json()["statistics"]["collectors"][0]["reached"]["probability"]
                .as_f64()
                .unwrap()
                > 0.0
        );
    }
}

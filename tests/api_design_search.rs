//! The design search for guards through the router. Its answer is checked by re-running the
//! scene with the guards it proposes: every guarded column's exceedance upper bound is then
//! within the acceptable probability (and the probability the one the search reported), and
//! with any one proposed rating lowered by 1 % that column's bound goes above it (the ratings are
//! the smallest). Also: runs that never exceed need rating 0; too few runs are not achievable,
//! with the runs needed checked against the Wilson interval itself; drawn rock sizes and
//! densities (one inverse per run) are checked the same way; bad input is refused naming the
//! field; a sharded scene refuses `design`.

mod common;
use common::ok;

use common::{assert_problem, assert_rejections, post};
use gangue::physics::stats::interval::{Z_95, wilson_interval};
use serde_json::{Value, json};

const RUNS: u64 = 300;
const ACCEPTABLE: f64 = 0.05;

/// [`common::risky_scene`] without its CSV; `drawn`: the rock's side length (0.05–0.3 m) and
/// density (2000–3000 kg/m³) drawn per run, else the default 0.3 m cube of 2500 kg/m³.
fn scene(runs: u64, drawn: bool) -> Value {
    let mut s = common::risky_scene(runs, 5);
    s.as_object_mut().unwrap().remove("migration_output");
    let mc = s["monte_carlo"].as_object_mut().unwrap();
    if drawn {
        mc.insert(
            "density_kg_m3".into(),
            json!({"distribution": "uniform", "min": 2000, "max": 3000}),
        );
    } else {
        mc.remove("side_length_m");
    }
    s
}

/// The exceedance upper bound of support column `k` in a scene answer (one limit checked).
fn bound(answer: &Value, k: usize) -> f64 {
    answer["statistics"]["supports"][k]["exceedance"]["stress_utilisation"]["ci95"][1]
        .as_f64()
        .unwrap()
}

/// The guards of the proposed ratings, the rating of entry `lowered` (if any) times `factor`.
fn guards(design: &Value, lowered: Option<usize>, factor: f64) -> Value {
    let mut out = Vec::new();
    for (k, e) in design["supports"].as_array().unwrap().iter().enumerate() {
        if e["guarded"] == true {
            let r = e["rating_j"].as_f64().unwrap();
            out.push(json!({
                "support": e["support"],
                "column_index": e["column_index"],
                "energy_rating_j": if lowered == Some(k) { r * factor } else { r },
            }));
        }
    }
    json!(out)
}

/// Asks for the design, re-runs with its guards and with each positive rating lowered by 1 %;
/// returns the design.
async fn check_by_rerunning(app: &axum::Router, body: &Value) -> Value {
    let mut asked = body.clone();
    asked["design"] = json!({"acceptable_probability": ACCEPTABLE});
    let a = ok(&post(app, "/v1/scene", &asked).await);
    let d = a["design"].clone();
    assert_eq!(d["runs"], RUNS);
    assert_eq!(d["acceptable_probability"], ACCEPTABLE);
    assert!(d["method"].as_str().unwrap().contains("exact"), "{d}");
    assert!(
        a["plan"]
            .as_array()
            .unwrap()
            .iter()
            .any(|s| s["stage"] == "design" && s["status"] == "ran"),
        "{}",
        a["plan"]
    );
    let entries = d["supports"].as_array().unwrap();
    // the ensemble without guards: some column must need one, else the test proves nothing
    assert!(
        entries
            .iter()
            .enumerate()
            .any(|(k, _)| bound(&a, k) > ACCEPTABLE),
        "no column needs a guard"
    );
    let mut guarded_body = body.clone();
    guarded_body["guards"] = guards(&d, None, 1.0);
    let g = ok(&post(app, "/v1/scene", &guarded_body).await);
    for (k, e) in entries.iter().enumerate() {
        assert_eq!(e["guarded"], true);
        let got = bound(&g, k);
        assert!(got <= ACCEPTABLE, "column {k}: {got} with {e}");
        assert_eq!(e["acceptable"], true, "{e}");
        assert_eq!(
            g["statistics"]["supports"][k]["exceedance"]["stress_utilisation"], e["exceedance"],
            "column {k}: the search's exceedance is the re-run's"
        );
    }
    assert_eq!(d["all_acceptable"], true);
    let mut lowered_any = false;
    for (k, e) in entries.iter().enumerate() {
        if e["rating_j"].as_f64().unwrap() > 0.0 {
            lowered_any = true;
            let mut lower = body.clone();
            lower["guards"] = guards(&d, Some(k), 0.99);
            let l = ok(&post(app, "/v1/scene", &lower).await);
            let got = bound(&l, k);
            assert!(got > ACCEPTABLE, "column {k} rated 1 % lower: {got}");
        }
    }
    assert!(lowered_any, "no rating above 0: {d}");
    d
}

#[tokio::test]
async fn the_proposed_guards_make_every_column_acceptable_and_are_the_smallest() {
    let app = common::app();
    let d = check_by_rerunning(&app, &scene(RUNS, false)).await;
    // one rock, one column: one inverse for the one checked limit
    assert_eq!(d["inverses"], 1, "{d}");
}

#[tokio::test]
async fn drawn_rock_sizes_and_densities_get_an_inverse_per_run() {
    let app = common::app();
    let d = check_by_rerunning(&app, &scene(RUNS, true)).await;
    let reached: u64 = d["supports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["runs_needing_guard"].as_u64().unwrap())
        .sum();
    let inverses = d["inverses"].as_u64().unwrap();
    assert!(
        inverses >= reached && inverses <= RUNS,
        "{inverses} inverses"
    );
}

/// Two limits: a column exceeds when either is passed, so the rating holds the column within
/// both, and each limit's bound on re-running is within the acceptable probability; the
/// search's probability (either limit) is at least each limit's.
#[tokio::test]
async fn with_two_limits_the_rating_keeps_the_column_within_both() {
    let app = common::app();
    let mut body = scene(RUNS, true);
    body["design_limits"] = json!({"stress_utilisation": 5.0, "max_force_n": 4e5});
    let mut asked = body.clone();
    asked["design"] = json!({"acceptable_probability": ACCEPTABLE});
    let a = ok(&post(&app, "/v1/scene", &asked).await);
    let d = &a["design"];
    body["guards"] = guards(d, None, 1.0);
    let g = ok(&post(&app, "/v1/scene", &body).await);
    let mut binding = [false, false];
    for (k, e) in d["supports"].as_array().unwrap().iter().enumerate() {
        let p = e["exceedance"]["probability"].as_f64().unwrap();
        for (i, limit) in ["stress_utilisation", "max_force_n"].iter().enumerate() {
            let before = &a["statistics"]["supports"][k]["exceedance"][limit];
            binding[i] |= before["ci95"][1].as_f64().unwrap() > ACCEPTABLE;
            let after = &g["statistics"]["supports"][k]["exceedance"][limit];
            assert!(
                after["ci95"][1].as_f64().unwrap() <= ACCEPTABLE,
                "{k} {limit}: {after}"
            );
            assert!(
                after["probability"].as_f64().unwrap() <= p,
                "{k} {limit}: {after} vs {e}"
            );
        }
    }
    assert!(
        binding[0] && binding[1],
        "both limits must matter: {binding:?}"
    );
}

#[tokio::test]
async fn columns_not_guarded_keep_their_exceedance_and_are_named() {
    let app = common::app();
    let mut body = scene(RUNS, false);
    body["design"] = json!({"acceptable_probability": ACCEPTABLE, "guards": {"supports": [2]}});
    let a = ok(&post(&app, "/v1/scene", &body).await);
    let d = &a["design"];
    assert_eq!(a["inputs"]["design"]["guards"]["supports"], json!([2]));
    for (k, e) in d["supports"].as_array().unwrap().iter().enumerate() {
        assert_eq!(e["guarded"], k == 1, "{e}");
        if k != 1 {
            assert_eq!(e["rating_j"], Value::Null);
            assert_eq!(
                e["exceedance"],
                a["statistics"]["supports"][k]["exceedance"]["stress_utilisation"]
            );
            assert_eq!(e["acceptable"], bound(&a, k) <= ACCEPTABLE);
        }
    }
    let residual: Vec<&Value> = d["supports"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["acceptable"] == false)
        .collect();
    assert!(!residual.is_empty(), "no residual risk to name: {d}");
    assert_eq!(d["all_acceptable"], false);
    let w = a["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["code"] == "design_residual_risk")
        .unwrap_or_else(|| panic!("no residual risk warning: {}", a["warnings"]));
    for e in residual {
        let named = format!("support {} column 0 (not guarded", e["support"]);
        assert!(w["message"].as_str().unwrap().contains(&named), "{w}");
    }
}

#[tokio::test]
async fn runs_that_never_exceed_need_no_guard() {
    let app = common::app();
    let mut body = scene(RUNS, false);
    body["design_limits"] = json!({"stress_utilisation": 100.0});
    body["design"] = json!({"acceptable_probability": ACCEPTABLE});
    let a = ok(&post(&app, "/v1/scene", &body).await);
    assert_eq!(a["statistics"]["any_exceeded"]["probability"], 0.0);
    for e in a["design"]["supports"].as_array().unwrap() {
        assert_eq!(e["rating_j"], 0.0, "{e}");
        assert_eq!(e["runs_needing_guard"], 0);
        assert_eq!(e["acceptable"], true);
    }
    assert_eq!(a["design"]["all_acceptable"], true);
}

#[tokio::test]
async fn too_few_runs_are_not_achievable_and_say_how_many_are_needed() {
    let app = common::app();
    let acceptable = 0.01;
    let mut body = scene(20, false);
    body["design"] = json!({"acceptable_probability": acceptable});
    let a = ok(&post(&app, "/v1/scene", &body).await);
    let d = &a["design"];
    // the smallest n whose Wilson upper bound of 0 of n is within the acceptable probability
    let upper = |n: u64| wilson_interval(0.0, n as f64, Z_95).unwrap()[1];
    let needed = (1..).find(|&n| upper(n) <= acceptable).unwrap();
    assert_eq!(d["runs_needed"], needed, "{d}");
    let z2 = Z_95 * Z_95;
    assert_eq!(needed, (z2 * (1.0 - acceptable) / acceptable).ceil() as u64);
    assert!(upper(20) > acceptable);
    assert_eq!(d["all_acceptable"], false);
    for e in d["supports"].as_array().unwrap() {
        assert_eq!(e["acceptable"], false, "{e}");
    }
    // with enough runs the same request is achievable
    body["monte_carlo"]["runs"] = json!(needed);
    let a = ok(&post(&app, "/v1/scene", &body).await);
    assert!(a["design"].get("runs_needed").is_none(), "{}", a["design"]);
}

#[tokio::test]
async fn bad_design_requests_are_refused_naming_the_field() {
    let app = common::app();
    let with = |mut s: Value, d: Value| {
        s["design"] = d;
        s
    };
    let good = json!({"acceptable_probability": 0.01});
    assert_rejections(
        &app,
        "/v1/scene",
        vec![
            (with(json!({}), good.clone()), "/design", "invalid_input"),
            (
                with(json!({"impact_velocity_m_s": 5}), good.clone()),
                "/design",
                "invalid_input",
            ),
            (
                with(
                    scene(5, false),
                    json!({"acceptable_probability": 0.01, "guards": {"supports": [1, 9]}}),
                ),
                "/design/guards/supports/1",
                "invalid_input",
            ),
            (
                with(
                    scene(5, false),
                    json!({"acceptable_probability": 0.01, "guards": {"supports": [1, 2, 3, 1]}}),
                ),
                "/design/guards/supports",
                "invalid_input",
            ),
            (
                with(scene(5, false), json!({"acceptable_probability": 0})),
                "/design/acceptable_probability",
                "invalid_input",
            ),
            (
                with(scene(5, false), json!({"acceptable_probability": 1})),
                "/design/acceptable_probability",
                "invalid_input",
            ),
        ],
    )
    .await;
    // a required field left out, and one unknown
    let r = post(&app, "/v1/scene", &with(scene(5, false), json!({}))).await;
    assert_eq!(r.status, 422, "{}", String::from_utf8_lossy(&r.body));
    assert!(String::from_utf8_lossy(&r.body).contains("acceptable_probability"));
    let r = post(
        &app,
        "/v1/scene",
        &with(
            scene(5, false),
            json!({"acceptable_probability": 0.1, "rating": 1}),
        ),
    )
    .await;
    assert_eq!(r.status, 422);
    assert!(String::from_utf8_lossy(&r.body).contains("/design/rating"));
}

#[tokio::test]
async fn work_past_the_limit_is_refused_before_running() {
    let app = gangue::app(gangue::config::Config {
        max_design_evaluations: 10_000,
        ..Default::default()
    });
    // drawn rocks: one inverse per run, 100 runs × 120 evaluations > 10 000
    let mut body = scene(100, true);
    body["design"] = json!({"acceptable_probability": 0.05});
    let r = post(&app, "/v1/scene", &body).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/design", "{p}");
    assert_eq!(p["errors"][0]["value"], 12_000, "{p}");
    assert!(
        p["errors"][0]["message"]
            .as_str()
            .unwrap()
            .contains("10000"),
        "{p}"
    );
    // the same with a fixed rock: one inverse
    let mut body = scene(100, false);
    body["design"] = json!({"acceptable_probability": 0.05});
    ok(&post(&app, "/v1/scene", &body).await);
}

#[test]
fn a_sharded_scene_refuses_design_naming_the_field() {
    let mut body = scene(5, false);
    body["design"] = json!({"acceptable_probability": 0.05});
    let (ok, text) = common::scene_shard(&body, "design-shard");
    assert!(!ok, "design in a scene shard is refused");
    assert!(text.contains("/design"), "{text}");
    assert!(text.contains("sharded"), "{text}");
}

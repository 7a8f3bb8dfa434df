//! `POST /v1/migration` through the router: the deterministic run, trajectories, ensembles,
//! real floors, determinism across thread counts, and bad input.

mod common;

use common::{post, rel, send};
use serde_json::{Value, json};

#[tokio::test]
async fn default_run_is_the_paper_case_with_events_and_no_trajectory() {
    let app = common::app();
    let r = post(&app, "/v1/migration", &json!({})).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert!(
        rel(
            b["arrival"]["speed_m_s"].as_f64().unwrap(),
            36.35233409073599
        ) < 1e-9
    );
    assert_eq!(b["arrival"]["phase"], "slide");
    assert_eq!(b["arrival"]["stop_reason"], "lower_end");
    assert_eq!(b["impact_count"], 3);
    let ev = b["events"].as_array().unwrap();
    assert_eq!(ev.iter().filter(|e| e["kind"] == "impact").count(), 3);
    assert!(ev.iter().any(|e| e["kind"] == "slide_start"));
    assert!(b.get("trajectory").is_none());
    assert!(b.get("statistics").is_none());
    assert_eq!(b["plan"][1]["status"], "skipped");
    assert_eq!(b["inputs"]["face"]["floor"], json!({"kind": "plane"}));
    let e = &b["energy"];
    assert!(e["residual_j"].as_f64().unwrap().abs() < 1e-6);
}

#[tokio::test]
async fn trajectory_samples_conserve_energy() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"output": {"trajectory": true, "sample_interval_s": 0.05}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let t = &b["trajectory"];
    let n = t["time_s"].as_array().unwrap().len();
    assert!(n > 100);
    for k in [
        "position_m",
        "along_dip_m",
        "height_m",
        "velocity_m_s",
        "speed_m_s",
        "kinetic_energy_j",
        "potential_energy_j",
        "dissipated_energy_j",
    ] {
        assert_eq!(t[k].as_array().unwrap().len(), n, "{k}");
    }
    assert_eq!(t["time_s"][0], 0.0);
    assert!((t["time_s"][1].as_f64().unwrap() - 0.05).abs() < 1e-12);
    let total = b["energy"]["total_start_j"].as_f64().unwrap();
    for i in 0..n {
        let s = t["kinetic_energy_j"][i].as_f64().unwrap()
            + t["potential_energy_j"][i].as_f64().unwrap()
            + t["dissipated_energy_j"][i].as_f64().unwrap();
        assert!(rel(s, total) < 1e-9, "sample {i}: {s} vs {total}");
    }
}

fn mc(runs: u64, seed: u64) -> Value {
    json!({"monte_carlo": {"runs": runs, "seed": seed}, "output": {"runs_csv": true}})
}

#[tokio::test]
async fn ensembles_are_reproducible_whatever_the_thread_count() {
    let one = gangue::app(gangue::config::Config {
        solver_threads: Some(1),
        ..Default::default()
    });
    let two = gangue::app(gangue::config::Config {
        solver_threads: Some(2),
        ..Default::default()
    });
    let a = post(&one, "/v1/migration", &mc(3000, 9)).await;
    let b = post(&two, "/v1/migration", &mc(3000, 9)).await;
    assert_eq!(a.status, 200, "{}", String::from_utf8_lossy(&a.body));
    assert_eq!(a.body, b.body, "same bytes with 1 and 2 threads");
    let c = post(&two, "/v1/migration", &mc(3000, 10)).await;
    assert_ne!(a.body, c.body, "another seed, another ensemble");
    let s = a.json();
    let st = &s["statistics"];
    assert_eq!(st["runs"], 3000);
    let speed = &st["speed_m_s"];
    assert_eq!(speed["histogram"]["edges"].as_array().unwrap().len(), 21);
    let counts: u64 = speed["histogram"]["counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .sum();
    assert_eq!(
        counts as f64,
        (st["reached_fraction"].as_f64().unwrap() * 3000.0).round()
    );
    for k in ["min", "p05", "p50", "p95", "p99", "max"].windows(2) {
        assert!(speed[k[0]].as_f64().unwrap() <= speed[k[1]].as_f64().unwrap());
    }
    let csv = s["runs_csv"].as_str().unwrap();
    assert!(csv.starts_with("run,time_s,speed_m_s,kinetic_energy_j,impact_count,runout_m,max_bounce_height_m,stop_reason"));
    assert_eq!(csv.lines().count(), 3001);
}

#[tokio::test]
async fn grid_and_contour_floors_that_are_the_plane_reproduce_it() {
    let app = common::app();
    let plane = post(&app, "/v1/migration", &json!({})).await.json();
    let v0 = plane["arrival"]["speed_m_s"].as_f64().unwrap();
    // z = −x tan 45° on a 1 m grid over x ∈ [0, 90], y ∈ [−5, 5].
    let heights: Vec<Vec<f64>> = (0..11)
        .map(|_| (0..91).map(|j| -(j as f64)).collect())
        .collect();
    let grid = json!({"face": {"floor": {"kind": "grid", "origin_m": [0.0, -5.0], "spacing_m": 1.0, "heights_m": heights}}});
    let r = post(&app, "/v1/migration", &grid).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert!(rel(b["arrival"]["speed_m_s"].as_f64().unwrap(), v0) < 1e-9);
    let echo = &b["inputs"]["face"]["floor"];
    assert_eq!(echo["kind"], "grid");
    let sha = echo["sha256"].as_str().unwrap();
    assert_eq!(sha.len(), 64);
    assert!(
        echo.get("heights_m").is_none(),
        "the floor is echoed by its hash"
    );
    let contours: Vec<Value> = (0..=90)
        .step_by(5)
        .map(|x| json!({"elevation_m": -(x as f64), "points_m": [[x as f64, -5.0], [x as f64, 5.0]]}))
        .collect();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"face": {"floor": {"kind": "contours", "contours": contours}}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    assert!(rel(r.json()["arrival"]["speed_m_s"].as_f64().unwrap(), v0) < 1e-9);
}

#[tokio::test]
async fn progress_stream_for_an_ensemble() {
    let app = common::app();
    let body = serde_json::to_vec(&json!({"monte_carlo": {"runs": 2000}})).unwrap();
    let r = send(
        &app,
        axum::http::Method::POST,
        "/v1/migration",
        Some("application/json"),
        body,
        Some("application/x-ndjson"),
    )
    .await;
    assert_eq!(r.status, 200);
    let text = String::from_utf8(r.body).unwrap();
    let last: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(last["result"]["statistics"]["runs"], 2000);
}

#[tokio::test]
async fn bad_input_names_the_field() {
    let app = common::app();
    let ragged = json!({"face": {"floor": {"kind": "grid", "spacing_m": 1.0, "heights_m": [[0.0, -1.0], [0.0]]}}});
    let cases: Vec<(Value, &str, &str)> = vec![
        (
            json!({"face": {"dip_deg": 85}}),
            "/face/dip_deg",
            "invalid_input",
        ),
        (
            json!({"face": {"length_m": 0}}),
            "/face/length_m",
            "invalid_input",
        ),
        (
            json!({"face": {"friction_coefficient": -0.1}}),
            "/face/friction_coefficient",
            "invalid_input",
        ),
        (
            json!({"face": {"restitution_normal": 1.5}}),
            "/face/restitution_normal",
            "invalid_input",
        ),
        (json!({"gravity_m_s2": 0}), "/gravity_m_s2", "invalid_input"),
        (
            json!({"release": {"along_dip_m": 120}}),
            "/release/along_dip_m",
            "invalid_input",
        ),
        (
            json!({"release": {"drop_height_m": -1}}),
            "/release/drop_height_m",
            "invalid_input",
        ),
        (
            json!({"release": {"speed_m_s": 2000}}),
            "/release/speed_m_s",
            "invalid_input",
        ),
        (json!({"end_time_s": 0}), "/end_time_s", "invalid_input"),
        (
            json!({"lumped_mass": {"motion": "roll"}}),
            "/face/friction_coefficient",
            "invalid_input",
        ),
        (
            json!({"monte_carlo": {"runs": 0}}),
            "/monte_carlo/runs",
            "invalid_input",
        ),
        (
            json!({"monte_carlo": {"runs": 2_000_000}}),
            "/monte_carlo/runs",
            "invalid_input",
        ),
        (
            json!({"monte_carlo": {"restitution_normal": {"min": 0.5, "max": 0.4}}}),
            "/monte_carlo/restitution_normal/max",
            "invalid_input",
        ),
        (
            json!({"monte_carlo": {"restitution_normal": {"distribution": "normal", "mean": 0.3}}}),
            "/monte_carlo/restitution_normal/std",
            "invalid_input",
        ),
        (
            json!({"monte_carlo": {"friction_coefficient": {"distribution": "truncated_normal", "mean": 0.2, "std": 0.01, "min": 0.9, "max": 1.0}}}),
            "/monte_carlo/friction_coefficient/max",
            "invalid_input",
        ),
        (
            json!({"monte_carlo": {"restitution_normal": {"distribution": "gamma"}}}),
            "/monte_carlo/restitution_normal/distribution",
            "invalid_input",
        ),
        (
            json!({"output": {"runs_csv": true}}),
            "/output/runs_csv",
            "invalid_input",
        ),
        (
            json!({"output": {"sample_interval_s": 0}}),
            "/output/sample_interval_s",
            "invalid_input",
        ),
        (
            json!({"output": {"trajectory": true, "sample_interval_s": 1e-6}}),
            "/output/sample_interval_s",
            "invalid_input",
        ),
        (
            json!({"face": {"floor": {"kind": "grid", "heights_m": [[0.0, -1.0], [0.0, -1.0]]}}}),
            "/face/floor/spacing_m",
            "invalid_input",
        ),
        (ragged, "/face/floor/heights_m/1", "invalid_input"),
        (
            json!({"face": {"floor": {"kind": "plane", "spacing_m": 1.0}}}),
            "/face/floor/spacing_m",
            "invalid_input",
        ),
        (
            json!({"face": {"floor": {"kind": "contours", "contours": []}}}),
            "/face/floor/contours",
            "invalid_input",
        ),
        (
            json!({"face": {"floor": []}}),
            "/face/floor",
            "invalid_type",
        ),
        (
            json!({"face": {"floor": {"kind": "mesh"}}}),
            "/face/floor/kind",
            "invalid_input",
        ),
        (
            json!({"monte_carlo": {"runs": 10, "sed": 1}}),
            "/monte_carlo/sed",
            "unknown_field",
        ),
        (
            json!({"rock": {"shape": "polyhedron", "vertices_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]]}}),
            "/rock/shape",
            "invalid_input",
        ),
    ];
    common::assert_rejections(&app, "/v1/migration", cases).await;
}

/// api.md: restitution distributions given explicitly with the rigid block are 422, even when
/// they equal their defaults (which apply to the lumped mass only, so `"monte_carlo": {}` works
/// for both methods); a damping-ratio distribution with the lumped mass is 422. Each refusal
/// echoes the distribution sent as its value (it was null), also inside a scene.
#[tokio::test]
async fn distributions_of_the_other_method_are_refused_when_sent_even_at_their_defaults() {
    let app = common::app();
    let default_en = json!({"distribution": "uniform", "min": 0.2, "max": 0.4});
    for path in ["/v1/migration", "/v1/scene"] {
        let r = post(
            &app,
            path,
            &json!({"method": "rigid_block", "face": {"length_m": 3},
                    "monte_carlo": {"runs": 2, "restitution_normal": default_en}}),
        )
        .await;
        let p = common::assert_problem(&r, 422, "invalid_input");
        assert_eq!(
            p["errors"][0]["field"], "/monte_carlo/restitution_normal",
            "{p}"
        );
        assert_eq!(p["errors"][0]["value"], default_en, "{p}");

        let r = post(
            &app,
            path,
            &json!({"method": "rigid_block", "face": {"length_m": 3}, "monte_carlo": {"runs": 2}}),
        )
        .await;
        assert_eq!(
            r.status,
            200,
            "{path}: {}",
            String::from_utf8_lossy(&r.body)
        );

        let beta = json!({"distribution": "uniform", "min": 0.1, "max": 0.4});
        let r = post(
            &app,
            path,
            &json!({"face": {"length_m": 3},
                    "monte_carlo": {"runs": 2, "critical_damping_ratio": beta}}),
        )
        .await;
        let p = common::assert_problem(&r, 422, "invalid_input");
        assert_eq!(
            p["errors"][0]["field"], "/monte_carlo/critical_damping_ratio",
            "{p}"
        );
        assert_eq!(p["errors"][0]["value"], beta, "{p}");
    }
}

/// physics.md §C.3 (time step): a `time_step_safety` above 0.3 is used as 0.3, and the answer
/// says so (`time_step_safety_capped`, naming the safety asked and the one used, with the
/// step); at 0.3 or below, or with a given `time_step_s`, there is no such warning, and 0.5
/// answers what 0.3 answers.
#[tokio::test]
async fn a_rigid_block_safety_above_the_cap_is_used_as_the_cap_and_warned() {
    let app = common::app();
    let body = |safety: f64| {
        json!({"method": "rigid_block", "face": {"length_m": 3},
               "rigid_block": {"time_step_safety": safety}})
    };
    let capped = common::migrate_ok(&app, &body(0.5)).await;
    let at_cap = common::migrate_ok(&app, &body(0.3)).await;
    let warning = |b: &Value| {
        b["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|w| w["code"] == "time_step_safety_capped")
            .cloned()
    };
    let w = warning(&capped).expect("a capped safety warns");
    let msg = w["message"].as_str().unwrap();
    assert!(msg.contains("0.5") && msg.contains("0.3"), "{msg}");
    assert!(warning(&at_cap).is_none(), "{at_cap}");
    assert_eq!(capped["arrival"], at_cap["arrival"]);
    assert_eq!(capped["energy"], at_cap["energy"]);
    let dt = at_cap["rigid_block"]["time_step_s"].as_f64().unwrap();
    let given = common::migrate_ok(
        &app,
        &json!({"method": "rigid_block", "face": {"length_m": 3},
                "rigid_block": {"time_step_s": dt, "time_step_safety": 0.9}}),
    )
    .await;
    assert!(warning(&given).is_none(), "{given}");
}

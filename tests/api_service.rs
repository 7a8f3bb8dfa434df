//! Service endpoints: health, presets, problem pages, the page, docs, 404/405 as problems.

mod common;

use axum::http::Method;
use common::{assert_problem, get, send};

#[tokio::test]
async fn health_presets_and_problem_pages() {
    let app = common::app();
    let r = get(&app, "/healthz").await;
    assert_eq!(r.status, 200);
    assert_eq!(r.json()["status"], "ok");
    let p = get(&app, "/v1/presets").await.json();
    assert_eq!(p["column"]["support_type"], "ZZ6500/22/48");
    assert_eq!(p["rock"]["density_kg_m3"], 2500.0);
    assert_eq!(p["face"]["dip_deg"], 45.0);
    assert_eq!(p["limits"]["max_monte_carlo_runs"], 1_000_000);
    assert_eq!(p["limits"]["max_body_bytes"], 16 * 1024 * 1024);
    assert_eq!(p["limits"]["max_queue_wait_ms"], 100.0);
    assert_eq!(p["limits"]["header_timeout_s"], 10.0);
    assert_eq!(p["limits"]["body_timeout_s"], 30.0);
    assert_eq!(p["limits"]["body_budget_bytes"], 64 * 1024 * 1024);
    assert_eq!(p["study"]["parameters"].as_array().unwrap().len(), 4);
    for code in [
        "capacity_exceeded",
        "invalid_input",
        "unknown_field",
        "overloaded",
        "timeout",
    ] {
        let r = get(&app, &format!("/problems/{code}")).await;
        assert_eq!(r.status, 200, "{code}");
        assert!(r.content_type().starts_with("text/html"));
    }
    assert_problem(&get(&app, "/problems/nonsense").await, 404, "not_found");
}

#[tokio::test]
async fn unknown_paths_and_methods_are_problems() {
    let app = common::app();
    assert_problem(&get(&app, "/v1/nothing").await, 404, "not_found");
    let r = send(&app, Method::GET, "/v1/impact", None, vec![], None).await;
    assert_problem(&r, 405, "method_not_allowed");
}

#[tokio::test]
async fn page_docs_and_openapi_are_served() {
    let app = common::app();
    let r = get(&app, "/").await;
    assert_eq!(r.status, 200);
    assert!(r.content_type().starts_with("text/html"));
    assert!(String::from_utf8_lossy(&r.body).contains("gangue"));
    let r = get(&app, "/docs/").await;
    assert_eq!(r.status, 200, "swagger ui");
    let r = get(&app, "/openapi.json").await;
    assert_eq!(r.status, 200);
    let doc = r.json();
    assert!(doc["openapi"].as_str().unwrap().starts_with("3.1"));
    assert!(doc["paths"]["/v1/impact"]["post"].is_object());
}

/// A large ensemble keeps a solver slot busy long enough to observe saturation and timeouts.
fn big_ensemble() -> serde_json::Value {
    serde_json::json!({"monte_carlo": {"runs": 1_000_000, "seed": 1}})
}

#[tokio::test]
async fn a_request_that_cannot_get_a_slot_in_time_answers_503_with_retry_after() {
    let app = gangue::app(gangue::config::Config {
        max_concurrent: Some(1),
        max_queue_wait_ms: 5.0,
        ..Default::default()
    });
    let busy_app = app.clone();
    let busy =
        tokio::spawn(
            async move { common::post(&busy_app, "/v1/migration", &big_ensemble()).await },
        );
    tokio::time::sleep(std::time::Duration::from_millis(30)).await;
    let r = common::post(&app, "/v1/impact", &serde_json::json!({})).await;
    let p = assert_problem(&r, 503, "overloaded");
    assert!(p["detail"].as_str().unwrap().contains("busy"));
    let retry = r.headers.get("retry-after").expect("Retry-After header");
    assert!(retry.to_str().unwrap().parse::<u64>().unwrap() >= 1);
    // The busy request still completes normally.
    assert_eq!(busy.await.unwrap().status, 200);
}

#[tokio::test]
async fn past_the_time_limit_the_work_stops_with_504() {
    let app = gangue::app(gangue::config::Config {
        compute_timeout_s: 0.02,
        ..Default::default()
    });
    let t0 = std::time::Instant::now();
    let r = common::post(&app, "/v1/migration", &big_ensemble()).await;
    assert_problem(&r, 504, "timeout");
    assert!(
        t0.elapsed() < std::time::Duration::from_secs(2),
        "stopped promptly"
    );
}

/// An ensemble whose first runs show that it cannot finish within twice the time limit is
/// refused with 422 naming `/monte_carlo/runs`, the projection, the limit and the ways to run it
/// anyway, long before the limit; one that can finish is not.
#[tokio::test]
async fn an_ensemble_that_cannot_finish_in_time_is_refused_at_its_pace() {
    let app = gangue::app(gangue::config::Config {
        compute_timeout_s: 20.0,
        ..Default::default()
    });
    // rigid-block runs of a few ms each: 1 000 000 of them take hours
    let body = serde_json::json!({
        "method": "rigid_block",
        "monte_carlo": {"runs": 1_000_000},
    });
    let t0 = std::time::Instant::now();
    let r = common::post(&app, "/v1/migration", &body).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert!(
        t0.elapsed() < std::time::Duration::from_secs(10),
        "refused early"
    );
    let e = &p["errors"][0];
    assert_eq!(e["field"], "/monte_carlo/runs", "{p}");
    let m = e["message"].as_str().unwrap();
    assert!(
        m.contains("time limit of 20 s") && m.contains("gangue compute"),
        "{m}"
    );
    // the same in a scene
    let r = common::post(
        &app,
        "/v1/scene",
        &serde_json::json!({"method": "rigid_block", "monte_carlo": {"runs": 1_000_000}}),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/monte_carlo/runs", "{p}");
    // a lumped-mass ensemble of as many runs finishes
    let r = common::post(
        &app,
        "/v1/migration",
        &serde_json::json!({"monte_carlo": {"runs": 200_000}}),
    )
    .await;
    assert_eq!(r.status, 200);
}

//! `POST /v1/batch` through the router: one NDJSON line per item in input order, each the same
//! result as the item's own endpoint; a bad item (malformed line, unknown kind, out-of-range
//! field) gets its own problem line naming `/items/i/…` and never sinks the others; JSON and
//! NDJSON bodies give the same lines; a disconnected client stops the rest.

mod common;

use std::time::{Duration, Instant};

use axum::body::Body;
use axum::http::{Method, Request, header};
use http_body_util::BodyExt;
use serde_json::{Value, json};
use tower::ServiceExt;

use common::{assert_problem, post, send};
use gangue::config::Config;

fn lines(body: &[u8]) -> Vec<Value> {
    String::from_utf8_lossy(body)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

fn items() -> Vec<Value> {
    vec![
        json!({"kind": "impact", "request": {"velocity_m_s": 6.0}}),
        json!({"kind": "volcano", "request": {}}),
        json!({"kind": "column", "request": {"rock": {"density_kg_m3": -5}}}),
        json!({"kind": "spalling"}),
        json!({"kind": "column", "request": {}}),
    ]
}

#[tokio::test]
async fn bad_items_get_their_own_lines_and_json_equals_ndjson() {
    let app = common::app();
    let r = post(&app, "/v1/batch", &json!({"items": items()})).await;
    assert_eq!(r.status, 200);
    assert!(r.content_type().starts_with("application/x-ndjson"));
    let json_lines = lines(&r.body);
    assert_eq!(json_lines.len(), 5);
    for (i, l) in json_lines.iter().enumerate() {
        assert_eq!(l["index"], i);
    }
    assert_eq!(json_lines[0]["status"], 200);
    let own = post(&app, "/v1/impact", &json!({"velocity_m_s": 6.0}))
        .await
        .json();
    assert_eq!(json_lines[0]["result"], own);
    assert_eq!(json_lines[1]["status"], 422);
    assert_eq!(
        json_lines[1]["problem"]["errors"][0]["field"],
        "/items/1/kind"
    );
    assert_eq!(json_lines[2]["status"], 422);
    assert_eq!(
        json_lines[2]["problem"]["errors"][0]["field"],
        "/items/2/request/rock/density_kg_m3"
    );
    assert_eq!(json_lines[3]["status"], 200);
    assert_eq!(
        json_lines[3]["result"]["zones"][0]["spalling_given_high_pct"],
        62.5
    );
    assert_eq!(
        json_lines[4]["result"],
        post(&app, "/v1/column", &json!({})).await.json()
    );

    // The same items as NDJSON, with a blank line (skipped) and then a malformed line.
    let mut nd = String::new();
    for (k, it) in items().iter().enumerate() {
        nd.push_str(&it.to_string());
        nd.push('\n');
        if k == 1 {
            nd.push_str("   \n");
        }
    }
    nd.push_str("{\"kind\": \"impact\", \"request\": {\n");
    nd.push_str(&json!({"kind": "impact"}).to_string());
    let r = send(
        &app,
        Method::POST,
        "/v1/batch",
        Some("application/x-ndjson"),
        nd.into_bytes(),
        None,
    )
    .await;
    assert_eq!(r.status, 200);
    let nd_lines = lines(&r.body);
    assert_eq!(nd_lines.len(), 7);
    assert_eq!(&nd_lines[..5], &json_lines[..]);
    assert_eq!(nd_lines[5]["status"], 400);
    assert_eq!(nd_lines[5]["problem"]["type"], "/problems/malformed_json");
    assert_eq!(nd_lines[5]["problem"]["errors"][0]["field"], "/items/5");
    assert_eq!(nd_lines[6]["status"], 200);
    assert_eq!(nd_lines[6]["index"], 6);
}

#[tokio::test]
async fn envelope_problems_and_item_limit() {
    let app = gangue::app(Config {
        max_batch_items: 3,
        ..Config::default()
    });
    let r = post(&app, "/v1/batch", &json!({"items": [{}, {}, {}, {}]})).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/items");
    let r = post(&app, "/v1/batch", &json!({"items": {}})).await;
    assert_problem(&r, 422, "invalid_type");
    let r = post(&app, "/v1/batch", &json!({"itemz": []})).await;
    assert_problem(&r, 422, "unknown_field");
    let r = send(
        &app,
        Method::POST,
        "/v1/batch",
        Some("text/plain"),
        b"{}".to_vec(),
        None,
    )
    .await;
    assert_problem(&r, 415, "unsupported_media_type");
    let r = send(
        &app,
        Method::POST,
        "/v1/batch",
        Some("application/json"),
        b"{".to_vec(),
        None,
    )
    .await;
    assert_problem(&r, 400, "malformed_json");
    // An item that is not an object, and an item with an unknown key.
    let r = post(
        &app,
        "/v1/batch",
        &json!({"items": [[1], {"kind": "impact", "x": 1}]}),
    )
    .await;
    let l = lines(&r.body);
    assert_eq!(l[0]["problem"]["type"], "/problems/invalid_type");
    assert_eq!(l[0]["problem"]["errors"][0]["field"], "/items/0");
    assert_eq!(l[1]["problem"]["errors"][0]["field"], "/items/1/x");
}

/// A client that reads one line and disconnects stops the batch: with one computation slot,
/// the slot is free again within a generous bound (1 s) although the batch holds about 4 s of
/// work (sized from the measured time of one item, so the bound means something on any machine).
#[tokio::test]
async fn a_disconnected_client_stops_the_rest() {
    let request = json!({"model": "coupled", "end_time_s": 0.2, "galerkin": {"modes": 20}});
    let probe = common::app();
    let t = Instant::now();
    for _ in 0..3 {
        assert_eq!(post(&probe, "/v1/column", &request).await.status, 200);
    }
    let per_item = t.elapsed().as_secs_f64() / 3.0;
    let n = ((4.0 / per_item).ceil() as usize).clamp(20, 200_000);
    let app = gangue::app(Config {
        max_concurrent: Some(1),
        solver_threads: Some(1),
        max_batch_items: n as u64,
        ..Config::default()
    });
    let item = json!({"kind": "column", "request": request});
    let body = json!({"items": vec![item; n]});
    let req = Request::builder()
        .method(Method::POST)
        .uri("/v1/batch")
        .header(header::CONTENT_TYPE, "application/json")
        .body(Body::from(serde_json::to_vec(&body).unwrap()))
        .unwrap();
    let res = app.clone().oneshot(req).await.unwrap();
    assert_eq!(res.status(), 200);
    let mut body = res.into_body();
    let first = body.frame().await.expect("a first line").unwrap();
    let first = first.into_data().unwrap();
    assert!(first.starts_with(b"{\"index\":0,"));
    drop(body);
    let t0 = Instant::now();
    loop {
        let r = post(&app, "/v1/impact", &json!({})).await;
        if r.status == 200 {
            break;
        }
        assert_eq!(r.status, 503);
        assert!(
            t0.elapsed() < Duration::from_secs(1),
            "the batch ({n} items of {per_item:.4} s) still holds its slot {:?} after the client left",
            t0.elapsed()
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

/// A rule the physics checks (a roll needs μ ≥ (2/7) tan θ; coupled history times within the
/// window) names the field inside the item's request, not the root of the batch.
#[tokio::test]
async fn a_physics_rule_broken_inside_an_item_names_the_items_field() {
    let app = common::app();
    let roll = json!({"face": {"friction_coefficient": 0.01}, "lumped_mass": {"motion": "roll"}});
    let late = json!({"model": "coupled", "output": {"times_s": [0.0, 10.0]}});
    let r = post(
        &app,
        "/v1/batch",
        &json!({"items": [
            {"kind": "impact", "request": {}},
            {"kind": "spalling", "request": {}},
            {"kind": "column", "request": late},
            {"kind": "migration", "request": roll},
        ]}),
    )
    .await;
    assert_eq!(r.status, 200);
    let l = lines(&r.body);
    assert_eq!(l[2]["status"], 422, "{}", l[2]);
    assert_eq!(
        l[2]["problem"]["errors"][0]["field"],
        "/items/2/request/output/times_s/1"
    );
    assert_eq!(l[3]["status"], 422, "{}", l[3]);
    assert_eq!(
        l[3]["problem"]["errors"][0]["field"],
        "/items/3/request/face/friction_coefficient"
    );
    // the same requests alone name the same fields without the prefix
    for (path, body, field) in [
        ("/v1/column", late, "/output/times_s/1"),
        ("/v1/migration", roll, "/face/friction_coefficient"),
    ] {
        let p = assert_problem(&post(&app, path, &body).await, 422, "invalid_input");
        assert_eq!(p["errors"][0]["field"], field, "{p}");
    }
}

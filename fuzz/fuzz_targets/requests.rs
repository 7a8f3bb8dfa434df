//! Coverage-guided fuzzing of request parsing, validation and solver entry: the first byte picks a
//! route, the rest is the body, sent through the whole service (the same router as the server,
//! with small limits so that every accepted request stays cheap). Any 500 is a finding: bad input
//! must be a 4xx problem, good input a finite answer.

#![no_main]

use std::sync::OnceLock;

use axum::Router;
use axum::body::Body;
use axum::http::Request;
use http_body_util::BodyExt;
use libfuzzer_sys::fuzz_target;
use tower::ServiceExt;

const ROUTES: [&str; 7] = [
    "/v1/impact",
    "/v1/column",
    "/v1/migration",
    "/v1/scene",
    "/v1/spalling",
    "/v1/study",
    "/v1/batch",
];

fn service() -> &'static (tokio::runtime::Runtime, Router) {
    static APP: OnceLock<(tokio::runtime::Runtime, Router)> = OnceLock::new();
    APP.get_or_init(|| {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("a runtime");
        let config = <gangue::config::Config as clap::Parser>::parse_from([
            "gangue",
            "--max-runs",
            "20",
            "--max-samples",
            "2000",
            "--max-curve-points",
            "200",
            "--max-modes",
            "5",
            "--max-end-time-s",
            "1",
            "--compute-timeout-s",
            "2",
            "--max-rigid-steps",
            "20000",
            "--max-batch-items",
            "4",
            "--max-study-points",
            "4",
            "--max-floor-bytes",
            "4000000",
            "--max-body-bytes",
            "65536",
            "--solver-threads",
            "1",
            "--solver-nice",
            "0",
        ]);
        let app = rt.block_on(async { gangue::http::app(config) });
        (rt, app)
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let (rt, app) = service();
    let route = ROUTES[usize::from(pick) % ROUTES.len()];
    let mut req = Request::post(route).header("content-type", "application/json");
    if pick >= 128 {
        req = req.header("accept", "application/x-ndjson");
    }
    let req = req.body(Body::from(body.to_vec())).expect("a request");
    let (status, text) = rt.block_on(async {
        let res = app.clone().oneshot(req).await.expect("the router is infallible");
        let status = res.status();
        let bytes = res
            .into_body()
            .collect()
            .await
            .map(|b| b.to_bytes())
            .unwrap_or_default();
        (status, bytes)
    });
    let text = String::from_utf8_lossy(&text);
    assert!(
        status.as_u16() != 500,
        "{route} answered 500 to {:?}: {text}",
        String::from_utf8_lossy(body)
    );
    assert!(
        !text.contains("\"internal\"") && !text.contains("problems/internal"),
        "{route} answered an internal problem to {:?}: {text}",
        String::from_utf8_lossy(body)
    );
});

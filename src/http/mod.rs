//! The REST service: router, layers, error handling, DTOs and handlers.

pub mod dto;
pub mod error;
pub mod finite;
pub mod json;
pub mod openapi;
pub mod parts;
pub mod routes;
pub mod runner;
pub mod server;

use std::time::Duration;

use axum::Router;
use axum::body::Body;
use axum::error_handling::HandleErrorLayer;
use axum::extract::DefaultBodyLimit;
use axum::http::{Request, Response};
use axum::routing::{get, post};
use tower::ServiceBuilder;
use tower::timeout::TimeoutLayer;
use tower_http::compression::CompressionLayer;
use tower_http::trace::TraceLayer;
use tracing::Span;
use utoipa_swagger_ui::SwaggerUi;

pub use runner::AppState;

use crate::config::Config;

/// The whole service as a router (tests call it with `oneshot`, no socket needed).
pub fn app(config: Config) -> Router {
    let state = AppState::new(config);
    let body_limit = state.config.max_body_bytes;
    let state_config = state.config.clone();
    // The whole request (reading the body, queueing, solving, writing) gets the computation
    // limit plus a margin; solvers stop themselves at the computation limit.
    let request_limit = state.time_limit() + Duration::from_secs(30);
    let api = Router::new()
        .route("/", get(routes::meta::index))
        .route("/static/{*path}", get(routes::meta::static_file))
        .route("/healthz", get(routes::meta::healthz))
        .route("/v1/presets", get(routes::meta::presets))
        .route("/problems/{code}", get(routes::meta::problem))
        .route("/v1/impact", post(routes::impact::impact))
        .route("/v1/column", post(routes::column::column))
        .route("/v1/migration", post(routes::migration::migration))
        .route("/v1/scene", post(routes::scene::scene))
        .route("/v1/calibrate", post(routes::calibrate::calibrate))
        .route("/v1/spalling", post(routes::spalling::spalling))
        .route("/v1/study", post(routes::study::study))
        .route("/v1/batch", post(routes::batch::batch))
        .with_state(state);
    Router::new()
        .merge(SwaggerUi::new("/docs").external_url_unchecked("/openapi.json", openapi::openapi_value()))
        .merge(api)
        .fallback(error::not_found)
        .method_not_allowed_fallback(method_not_allowed)
        .layer(axum::middleware::from_fn_with_state(
            std::sync::Arc::new(json::BodyGuard::new(
                body_limit,
                state_config.body_timeout(),
                state_config.body_budget_bytes(),
                2 * state_config.max_queue_wait(),
            )),
            json::guard_body,
        ))
        .layer(axum::middleware::from_fn(problems_everywhere))
        .layer(DefaultBodyLimit::max(body_limit))
        .layer(
            ServiceBuilder::new()
                .layer(HandleErrorLayer::new(|_: tower::BoxError| async {
                    error::ApiError::new("timeout", "the request passed the time limit")
                }))
                .layer(TimeoutLayer::new(request_limit)),
        )
        .layer(CompressionLayer::new())
        .layer(
            TraceLayer::new_for_http()
                .make_span_with(|req: &Request<Body>| {
                    tracing::info_span!("request", method = %req.method(), path = %req.uri().path())
                })
                .on_request(|_req: &Request<Body>, _span: &Span| {})
                .on_response(|res: &Response<Body>, latency: Duration, _span: &Span| {
                    tracing::info!(
                        status = res.status().as_u16(),
                        duration_ms = latency.as_secs_f64() * 1e3,
                        "done"
                    );
                }),
        )
}

async fn method_not_allowed() -> error::ApiError {
    error::ApiError::new("method_not_allowed", "this path does not take this method")
}

/// Makes every 4xx/5xx an `application/problem+json` answer, whatever produced it (the
/// documentation routes' empty 404, axum's `text/plain` rejections such as a path that is not
/// valid UTF-8). Problems the service made itself pass unchanged.
async fn problems_everywhere(req: Request<Body>, next: axum::middleware::Next) -> Response<Body> {
    use axum::http::header;
    use axum::response::IntoResponse;
    let path_is_utf8 = percent_decoded_is_utf8(req.uri().path());
    let res = next.run(req).await;
    let status = res.status();
    if !(status.is_client_error() || status.is_server_error()) {
        return res;
    }
    let is_problem = res
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|ct| ct.starts_with(error::PROBLEM_JSON));
    if is_problem {
        return res;
    }
    let problem = match status.as_u16() {
        // No resource has a path that is not UTF-8 once percent-decoded.
        400 if !path_is_utf8 => error::ApiError::new(
            "not_found",
            "the path is not valid UTF-8 once percent-decoded; no resource has such a path",
        ),
        400 => error::ApiError::new("malformed_json", "the request could not be read"),
        404 => error::ApiError::new("not_found", "no resource at this path"),
        405 => error::ApiError::new("method_not_allowed", "this path does not take this method"),
        413 => error::ApiError::new(
            "payload_too_large",
            "the request body is larger than the limit (see /v1/presets)",
        ),
        415 => error::ApiError::new(
            "unsupported_media_type",
            "send the body as Content-Type: application/json",
        ),
        503 => error::ApiError::overloaded(1),
        504 => error::ApiError::new("timeout", "the request passed the time limit"),
        s if s < 500 => error::ApiError::new("malformed_json", "the request could not be read"),
        _ => error::ApiError::internal(format!("unexpected {status} without a problem body")),
    };
    let allow = res.headers().get(header::ALLOW).cloned();
    let mut out = problem.into_response();
    if let Some(allow) = allow {
        out.headers_mut().insert(header::ALLOW, allow);
    }
    out
}

/// True when the percent-decoded bytes of `path` are UTF-8.
fn percent_decoded_is_utf8(path: &str) -> bool {
    let b = path.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%'
            && i + 2 < b.len()
            && let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2]))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    std::str::from_utf8(&out).is_ok()
}

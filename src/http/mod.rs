//! The REST service: router, layers, error handling, DTOs and handlers.

pub mod dto;
pub mod error;
pub mod finite;
pub mod json;
pub mod openapi;
pub mod routes;
pub mod runner;

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
        .route("/v1/spalling", post(routes::spalling::spalling))
        .route("/v1/study", post(routes::study::study))
        .route("/v1/batch", post(routes::batch::batch))
        .with_state(state);
    Router::new()
        .merge(SwaggerUi::new("/docs").external_url_unchecked("/openapi.json", openapi::openapi_value()))
        .merge(api)
        .fallback(error::not_found)
        .method_not_allowed_fallback(method_not_allowed)
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

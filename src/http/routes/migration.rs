//! `POST /v1/migration`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};

use crate::http::dto::migration::{MigrationRequest, MigrationResponse};
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::migration;

/// Rockfall migration down the face: one trajectory, or a seeded Monte Carlo ensemble.
#[utoipa::path(
    post,
    path = "/v1/migration",
    tag = "migration",
    request_body = MigrationRequest,
    responses(
        (status = 200, description = "Arrival, energy bookkeeping, events, trajectory, statistics", body = MigrationResponse),
        (status = "4XX", description = "Invalid request (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded, timed out or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn migration(
    State(state): State<AppState>,
    headers: HeaderMap,
    AppJson(mut req): AppJson<MigrationRequest>,
) -> Response {
    let case = match req.resolve(&state.config) {
        Ok(c) => c,
        Err(e) => return e.into_response(),
    };
    respond(&state, &headers, move |control| {
        let r = migration::run(&case, control)?;
        Ok(MigrationResponse::new(r, req))
    })
    .await
}

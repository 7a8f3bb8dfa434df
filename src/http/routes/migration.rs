//! `POST /v1/migration`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};

use crate::calc::Calculation;
use crate::calc::migration::Migration;
use crate::http::dto::migration::{MigrationRequest, MigrationResponse};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::Control;
use crate::physics::migration::MigrationCase;

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
    respond(&state, &headers, move |control| solve(&case, req, control)).await
}

/// Solves a resolved migration request (also used by batch).
pub fn solve(
    case: &MigrationCase,
    req: MigrationRequest,
    control: &Control,
) -> Result<MigrationResponse, ApiError> {
    Ok(MigrationResponse::new(
        Migration::solve(case, control)?,
        req,
    ))
}

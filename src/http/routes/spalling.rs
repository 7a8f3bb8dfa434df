//! `POST /v1/spalling`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Response;

use crate::calc::Calculation;
use crate::calc::spalling::Spalling;
use crate::http::dto::spalling::{SpallingRequest, SpallingResponse};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::Control;

/// Coal-wall spalling statistics by face zone (paper Table 1).
#[utoipa::path(
    post,
    path = "/v1/spalling",
    tag = "spalling",
    request_body = SpallingRequest,
    responses(
        (status = 200, description = "Zone shares, P(A|B), P(A|C) and Wilson intervals", body = SpallingResponse),
        (status = "4XX", description = "Invalid request (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded, timed out or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn spalling(
    State(state): State<AppState>,
    headers: HeaderMap,
    AppJson(req): AppJson<SpallingRequest>,
) -> Response {
    respond(&state, &headers, move |control| solve(req, control)).await
}

/// Resolves and computes a spalling request (also used by batch).
pub fn solve(mut req: SpallingRequest, control: &Control) -> Result<SpallingResponse, ApiError> {
    let case = req.resolve()?;
    let report = Spalling::solve(&case, control)?;
    Ok(SpallingResponse::new(report, &case, req))
}

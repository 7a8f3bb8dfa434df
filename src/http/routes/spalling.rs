//! `POST /v1/spalling`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Response;

use crate::http::dto::spalling::{SpallingRequest, SpallingResponse};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};

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
    respond(&state, &headers, move |_control| solve(req)).await
}

/// Resolves and computes a spalling request (also used by batch).
pub fn solve(mut req: SpallingRequest) -> Result<SpallingResponse, ApiError> {
    let case = req.resolve()?;
    Ok(SpallingResponse::compute(&case, req))
}

//! `POST /v1/column`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};

use crate::calc::Calculation;
use crate::calc::column::Column;
use crate::http::dto::column::{ColumnRequest, ColumnResponse};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::Control;
use crate::physics::column::ColumnCase;

/// Column vibration after an impact: midpoint history, energies, absorbed energy, stress.
#[utoipa::path(
    post,
    path = "/v1/column",
    tag = "column",
    request_body = ColumnRequest,
    responses(
        (status = 200, description = "Modal data, energies, stresses, optional history", body = ColumnResponse),
        (status = "4XX", description = "Invalid request or capacity exceeded (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded, timed out or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn column(
    State(state): State<AppState>,
    headers: HeaderMap,
    AppJson(mut req): AppJson<ColumnRequest>,
) -> Response {
    let case = match req.resolve(&state.config) {
        Ok(c) => c,
        Err(e) => return e.into_response(),
    };
    respond(&state, &headers, move |control| solve(&case, req, control)).await
}

/// Solves a resolved column request (also used by batch and study).
pub fn solve(
    case: &ColumnCase,
    req: ColumnRequest,
    control: &Control,
) -> Result<ColumnResponse, ApiError> {
    let report = Column::solve(case, control).map_err(|e| {
        let e = ApiError::from(e).with_capacity_velocity(case.impact.velocity);
        match req.end_time_s {
            Some(t) => e.with_step_field("/end_time_s", t),
            None => e,
        }
    })?;
    Ok(ColumnResponse::new(report, req))
}

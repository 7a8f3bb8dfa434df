//! `POST /v1/calibrate`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};

use crate::calc::Calculation;
use crate::calc::calibrate::{Calibration, CalibrationCase};
use crate::http::dto::calibrate::{CalibrateRequest, CalibrateResponse, calibration_error};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::Control;

/// Back-analysis: the migration parameters (restitution, friction, damping) whose seeded
/// ensemble reproduces observed runouts, stopping points or horizontal runouts best, by a
/// refined grid search with common random numbers.
#[utoipa::path(
    post,
    path = "/v1/calibrate",
    tag = "calibrate",
    request_body = CalibrateRequest,
    responses(
        (status = 200, description = "Best values, the objective at the best and at the base, every evaluation, the sensitivity and the observed and computed distributions", body = CalibrateResponse),
        (status = "4XX", description = "Invalid request (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded, timed out or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn calibrate(
    State(state): State<AppState>,
    headers: HeaderMap,
    AppJson(mut req): AppJson<CalibrateRequest>,
) -> Response {
    let case = match req.resolve(&state.config) {
        Ok(c) => c,
        Err(e) => return e.into_response(),
    };
    respond(&state, &headers, move |control| solve(&case, req, control)).await
}

/// Solves a resolved calibration request (also used by batch).
pub fn solve(
    case: &CalibrationCase,
    req: CalibrateRequest,
    control: &Control,
) -> Result<CalibrateResponse, ApiError> {
    let report = Calibration::solve(case, control)
        .map_err(|e| calibration_error(e, &CalibrateResponse::own_rocks(&req)))?;
    Ok(CalibrateResponse::new(report, req))
}

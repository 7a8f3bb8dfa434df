//! `POST /v1/impact`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};

use crate::calc::impact::Impact;
use crate::calc::{self, Calculation};
use crate::http::dto::impact::{ImpactRequest, ImpactResponse};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::Control;

/// Hertz contact of a rock on a column: maximum deformation, force, contact stress.
#[utoipa::path(
    post,
    path = "/v1/impact",
    tag = "impact",
    request_body = ImpactRequest,
    responses(
        (status = 200, description = "Contact maxima, capacity and duration", body = ImpactResponse),
        (status = "4XX", description = "Invalid request or capacity exceeded (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded, timed out or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn impact(
    State(state): State<AppState>,
    headers: HeaderMap,
    AppJson(mut req): AppJson<ImpactRequest>,
) -> Response {
    let case = match req.resolve(&state.config) {
        Ok(c) => c,
        Err(e) => return e.into_response(),
    };
    let velocity = req.velocity_m_s;
    respond(&state, &headers, move |control| {
        solve(&case, req, control).map_err(|e| e.with_capacity_velocity(velocity))
    })
    .await
}

/// Solves a resolved impact request (also used by batch): the calculation's report rendered
/// with the resolved request as `inputs`.
pub fn solve(
    case: &calc::impact::Case,
    req: ImpactRequest,
    control: &Control,
) -> Result<ImpactResponse, ApiError> {
    let report = Impact::solve(case, control)?;
    Ok(ImpactResponse::new(report, req))
}

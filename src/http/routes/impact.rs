//! `POST /v1/impact`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};

use crate::http::dto::common::{Meta, PlanStep, Warning};
use crate::http::dto::impact::{CurveDto, ImpactRequest, ImpactResponse};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::material::ImpactCase;
use crate::physics::{contact, validity};

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
    respond(&state, &headers, move |_control| {
        solve(&case, req).map_err(|e| e.with_capacity_velocity(velocity))
    })
    .await
}

/// Solves a resolved impact request (also used by batch and scene): the physics runs the
/// impact, the curve and the validity checks; this only renders them.
pub fn solve(case: &ImpactCase, req: ImpactRequest) -> Result<ImpactResponse, ApiError> {
    let result = contact::solve_impact(case)?;
    let n = req.output.curve_points as usize;
    let mut plan = vec![PlanStep::ran(
        "impact",
        "closed-form maxima on the W₋₁ branch (log laws) or Hertz; duration t_c = (2mv/Pmax)·J(u₀)",
    )];
    let curve = if n > 0 {
        let c = contact::impact_force_curve(case, &result, n)?;
        plan.push(PlanStep::ran(
            "curve",
            format!("{n} points of P(δ) from 0 to δmax"),
        ));
        Some(CurveDto {
            deformation_m: c.deformation,
            force_n: c.force,
        })
    } else {
        plan.push(PlanStep::skipped("curve", "output.curve_points = 0"));
        None
    };
    let mut meta = Meta::new(plan);
    meta.warnings = validity::impact_warnings(case, &result)
        .into_iter()
        .map(Warning::from)
        .collect();
    Ok(ImpactResponse::new(&result, curve, req, meta))
}

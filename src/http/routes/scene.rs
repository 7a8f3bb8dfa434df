//! `POST /v1/scene`.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};

use crate::calc::Calculation;
use crate::calc::scene::Scene;
use crate::http::dto::scene::{SceneContext, SceneRequest, SceneResponse, scene_error};
use crate::http::error::ApiError;
use crate::http::json::AppJson;
use crate::http::runner::{AppState, respond};
use crate::physics::Control;
use crate::physics::scene::SceneCase;

/// The whole chain along the face: release → migration → impact on the first support reached →
/// column energy → design checks, for one run or a seeded Monte Carlo ensemble.
#[utoipa::path(
    post,
    path = "/v1/scene",
    tag = "scene",
    request_body = SceneRequest,
    responses(
        (status = 200, description = "Plan, migration, impacts with checks and verdicts, ensemble statistics per support", body = SceneResponse),
        (status = "4XX", description = "Invalid request (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded, timed out or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn scene(
    State(state): State<AppState>,
    headers: HeaderMap,
    AppJson(mut req): AppJson<SceneRequest>,
) -> Response {
    let (case, ctx) = match req.resolve(&state.config) {
        Ok(c) => c,
        Err(e) => return e.into_response(),
    };
    respond(&state, &headers, move |control| {
        solve(&case, ctx, req, control)
    })
    .await
}

/// Solves a resolved scene request (also used by batch).
pub fn solve(
    case: &SceneCase,
    ctx: SceneContext,
    req: SceneRequest,
    control: &Control,
) -> Result<SceneResponse, ApiError> {
    let r = Scene::solve(case, control).map_err(|e| scene_error(e, &ctx))?;
    Ok(SceneResponse::new(r, case, ctx, req))
}

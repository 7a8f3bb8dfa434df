//! `POST /v1/study`: parameter sweeps over the base column request, sensitivity measures and
//! orderings, energy proportions and the comparison with the paper's orderings.
//!
//! The route maps the wire to the calculation and back: each swept parameter's dotted path to
//! the request field it names ([`SweptField`]) and the quantity of the column case it sets
//! ([`calc::study::Parameter`]), each output name to the result it reads
//! ([`calc::study::Output`]). The base request is resolved once into its case; every swept
//! value is checked by setting it on the base request as sent and resolving that (so a value
//! the request's own validation refuses is refused with the same problem); a study point is the
//! base case with its values set ([`calc::study::StudyCase::point`]), solved by the same code as
//! `POST /v1/column`: a study value equals a separate `/v1/column` call bit for bit. Points run
//! in parallel on the solver pool and are collected in a fixed order, so the answer does not
//! depend on the thread count.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Response;
use rayon::prelude::*;
use serde_json::{Value, json};

use crate::calc;
use crate::calc::Calculation;
use crate::calc::column::Column;
use crate::calc::study::{Given, Output, StudyCase};
use crate::config::Config;
use crate::http::dto::column::{ColumnModelDto, ColumnRequest};
use crate::http::dto::common::{LawDto, Meta, ModulusDto, ShapeKind, Warning, plan_of};
use crate::http::dto::study::{
    CANONICAL, ENERGY_PROPORTION_UNDEFINED, EnergyProportionDto, MeasuresDto, OrderedMap,
    OrderingDto, OutputSensitivityDto, PaperComparisonDto, StudyGrid, StudyGridDto,
    StudyParameterDto, StudyRequest, StudyResponse, SweptField, default_outputs, output_of,
    pointer_of, set_pointer, study_outputs,
};
use crate::http::error::{ApiError, FieldError};
use crate::http::json::{AppJson, from_value};
use crate::http::runner::{AppState, respond};
use crate::physics::Control;
use crate::physics::column::ColumnCase;
use crate::physics::study::{
    ImpactParameter, TIE_REL, TIE_REL_NUMERIC, impact_elasticities, order_groups, ratio,
    richardson_elasticity, richardson_points, span_over_base,
};

/// Parameter sweeps, sensitivity measures and orderings, energy proportions.
#[utoipa::path(
    post,
    path = "/v1/study",
    tag = "study",
    request_body = StudyRequest,
    responses(
        (status = 200, description = "Curves, grids, sensitivity measures and orderings, energy proportions, paper comparison", body = StudyResponse),
        (status = "4XX", description = "Invalid request or capacity exceeded at a study point (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded, timed out or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn study(
    State(state): State<AppState>,
    headers: HeaderMap,
    AppJson(req): AppJson<StudyRequest>,
) -> Response {
    let config = state.config.clone();
    respond(&state, &headers, move |control| {
        solve(&config, req, control)
    })
    .await
}

/// Where a study point's outputs go.
#[derive(Debug, Clone, Copy)]
enum Slot {
    Base,
    Curve(usize, usize),
    Grid(usize, usize, usize),
    Proportion(usize, usize),
    Difference(usize, usize),
}

struct Param {
    name: String,
    /// The request field the name sets.
    field: SweptField,
    pointer: String,
    min: f64,
    max: f64,
    rank: usize,
    base: Option<f64>,
    /// The four central-difference points when a numerical elasticity is needed and possible.
    fd: Option<[f64; 4]>,
    /// For each x value: whether x·max is a valid column request (an energy-proportion point
    /// that is not is left out, `null`, with an `energy_proportion_undefined` warning).
    proportion_defined: Vec<bool>,
    analytic: Option<crate::physics::study::ImpactElasticities>,
}

mod assemble;
mod check;
mod points;
#[cfg(test)]
mod tests;

use assemble::*;
use check::*;
use points::*;

/// Checks and runs a study (also used by batch).
pub fn solve(
    config: &Config,
    req: StudyRequest,
    control: &Control,
) -> Result<StudyResponse, ApiError> {
    let plan = plan(config, req)?;
    control.set_total(plan.slots.len() as u64);
    let results: Vec<Vec<f64>> = (0..plan.slots.len())
        .into_par_iter()
        .map(|i| plan.eval(config, i, control))
        .collect::<Result<_, _>>()?;
    plan.finish(results)
}

/// A checked study: its parameters and its points (slot 0 the base, then the items in the order
/// the response lists them: curves, grids, energy proportions, central-difference points).
pub struct StudyPlan {
    req: StudyRequest,
    /// The base case and what it was given: each point's case is made from it.
    base: StudyCase,
    base_resolved: ColumnRequest,
    coupled: bool,
    outputs: Vec<String>,
    /// The outputs each point reads, then the energy ratio.
    reads: Vec<(String, Output)>,
    params: Vec<Param>,
    values: Vec<Vec<f64>>,
    pairs: Vec<(usize, usize)>,
    slots: Vec<Slot>,
    warnings: Vec<Warning>,
}

impl std::fmt::Debug for StudyPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StudyPlan")
            .field("points", &self.slots.len())
            .finish_non_exhaustive()
    }
}

/// Checks a study request and lists its points (no column is solved yet).
pub fn plan(config: &Config, mut req: StudyRequest) -> Result<StudyPlan, ApiError> {
    let mut warnings = Vec::new();
    if req.base.output.is_some() {
        return Err(ApiError::invalid(
            "/base/output",
            json!("…"),
            "a study takes no history: leave output null",
        ));
    }
    let base_json = serde_json::to_value(&req.base).map_err(ApiError::internal)?;
    let mut base_resolved = req.base.clone();
    let base_case = base_resolved.resolve(config).map_err(|e| e.nest("/base"))?;
    let coupled = base_resolved.model == ColumnModelDto::Coupled;
    let outputs = check_request(config, &mut req, coupled)?;
    let reads = outputs
        .iter()
        .chain(std::iter::once(&"energy_ratio".to_string()))
        .map(|o| {
            output_of(o)
                .map(|r| (o.clone(), r))
                .ok_or_else(|| ApiError::internal(format!("study output {o} unknown")))
        })
        .collect::<Result<Vec<_>, _>>()?;

    // Each parameter: its range ends must resolve, and its base value.
    let base = StudyBase {
        config,
        json: &base_json,
        sent: &req.base,
        resolved: &base_resolved,
        case: &base_case,
        coupled,
        corner_given: req.base.rock.corner_radius_m.is_some(),
        initial_given: req.base.initial_midpoint_displacement_m.is_some(),
    };
    let mut params = Vec::with_capacity(req.parameters.len());
    for (i, p) in req.parameters.iter().enumerate() {
        params.push(base.param(i, p, &req.x_values, &outputs, &mut warnings)?);
    }

    // The points.
    let n = req.points as usize;
    let np = params.len();
    let values = sweep_values(&params, n);
    let pairs: Vec<(usize, usize)> = if req.grid == StudyGrid::Pairs {
        (0..np)
            .flat_map(|a| ((a + 1)..np).map(move |b| (a, b)))
            .collect()
    } else {
        Vec::new()
    };
    let slots = study_slots(&params, pairs.len(), n, req.x_values.len());
    let given = Given {
        corner_radius: req.base.rock.corner_radius_m.is_some(),
        radius: req.base.rock.radius_m.is_some(),
        contact_radius: req.base.column.contact_radius_m.is_some(),
    };
    let plan = StudyPlan {
        req,
        base: StudyCase {
            case: base_case,
            given,
        },
        base_resolved,
        coupled,
        outputs,
        reads,
        params,
        values,
        pairs,
        slots,
        warnings,
    };
    plan.check_points(config)?;
    Ok(plan)
}

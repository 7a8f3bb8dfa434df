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

/// The base request as sent with each field of `sets` set, checked and resolved as a column
/// request: the case of the point, or the request's own refusal.
fn resolve_point(
    config: &Config,
    sent: &ColumnRequest,
    sets: &[(SweptField, f64)],
) -> Result<ColumnCase, ApiError> {
    let mut req = sent.clone();
    for &(f, x) in sets {
        f.set(&mut req, x);
    }
    req.resolve(config)
}

/// The refusal of a parameter whose dotted path names no numeric field of the base request
/// (`sent`, `json` its JSON): the path is set in the JSON and read as a column request, so the
/// problem is the request's own (an unknown field, a wrong type).
fn refuse_name(
    config: &Config,
    json: &Value,
    i: usize,
    p: &StudyParameterDto,
    pointer: &str,
) -> ApiError {
    let mut v = json.clone();
    set_pointer(&mut v, pointer, p.min);
    let refused = from_value::<ColumnRequest>(&v).and_then(|mut req| req.resolve(config));
    match refused {
        Err(e) => {
            let field = if matches!(e.code(), "unknown_field" | "invalid_type") {
                format!("/parameters/{i}/name")
            } else {
                format!("/parameters/{i}/min")
            };
            blame(
                &e,
                &field,
                &format!("{} = {} is not a valid column request", p.name, p.min),
            )
        }
        Ok(_) => ApiError::invalid(
            format!("/parameters/{i}/name"),
            json!(p.name),
            "is not a numeric field of the column request that a study can sweep",
        ),
    }
}

/// Maps an error of a trial point to the study field that caused it.
fn blame(e: &ApiError, field: &str, what: &str) -> ApiError {
    let code = match e.code() {
        "unknown_field" | "invalid_type" => "invalid_input",
        c => c,
    };
    let errors = e
        .errors()
        .iter()
        .map(|f| FieldError {
            field: field.to_string(),
            value: f.value.clone(),
            message: format!("{what}: {} {}", f.field, f.message),
        })
        .collect::<Vec<_>>();
    if errors.is_empty() {
        ApiError::invalid(field, Value::Null, format!("{what}: {e}"))
    } else {
        ApiError::from_field_errors(code, errors)
    }
}

/// The outputs `reads` (each with its name) of a point's result.
fn extract(
    r: &crate::physics::column::ColumnResult,
    reads: &[(String, Output)],
) -> Result<Vec<f64>, ApiError> {
    reads
        .iter()
        .map(|(name, o)| {
            o.of(r)
                .filter(|x| x.is_finite())
                .ok_or_else(|| ApiError::internal(format!("study output {name} missing")))
        })
        .collect()
}

fn ordering_names(groups: &[Vec<usize>], params: &[Param]) -> Vec<String> {
    groups
        .iter()
        .map(|g| {
            g.iter()
                .map(|&i| params[i].name.as_str())
                .collect::<Vec<_>>()
                .join("=")
        })
        .collect()
}

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

/// The study's own fields: points, parameters (distinct dotted paths, finite min < max),
/// x values in (0, 1], outputs of the column model (filled in by default); returns the
/// outputs.
fn check_request(
    config: &Config,
    req: &mut StudyRequest,
    coupled: bool,
) -> Result<Vec<String>, ApiError> {
    let mut ck = crate::http::dto::common::Checker::new();
    ck.count(
        "/points",
        u64::from(req.points),
        2,
        config.max_study_points,
        "points",
    );
    if req.parameters.is_empty() || req.parameters.len() > 16 {
        ck.push(
            "/parameters",
            json!(req.parameters.len()),
            "must list 1 to 16 parameters",
        );
    }
    if req.x_values.is_empty() || req.x_values.len() > 101 {
        ck.push(
            "/x_values",
            json!(req.x_values.len()),
            "must list 1 to 101 values",
        );
    }
    for (k, &x) in req.x_values.iter().enumerate() {
        ck.open_closed(&format!("/x_values/{k}"), x, 0.0, 1.0, "(x = p/p_max)");
    }
    let outputs = req
        .outputs
        .get_or_insert_with(|| default_outputs(coupled))
        .clone();
    let allowed = study_outputs(coupled);
    if outputs.is_empty() {
        ck.push("/outputs", json!([]), "must name at least one output");
    }
    for (k, o) in outputs.iter().enumerate() {
        if !allowed.contains(&o.as_str()) {
            ck.push(
                format!("/outputs/{k}"),
                json!(o),
                format!(
                    "is not a numeric output of the {} column model; one of {}",
                    if coupled { "coupled" } else { "decoupled" },
                    allowed.join(", ")
                ),
            );
        } else if outputs[..k].contains(o) {
            ck.push(format!("/outputs/{k}"), json!(o), "is listed twice");
        }
    }
    for (i, p) in req.parameters.iter().enumerate() {
        if req.parameters[..i].iter().any(|q| q.name == p.name) {
            ck.push(
                format!("/parameters/{i}/name"),
                json!(p.name),
                "is listed twice",
            );
        }
        if p.name.is_empty() || p.name.split('.').any(str::is_empty) {
            ck.push(
                format!("/parameters/{i}/name"),
                json!(p.name),
                "must be a dotted path such as rock.density_kg_m3",
            );
        }
        if !(p.min.is_finite() && p.max.is_finite() && p.min < p.max) {
            ck.push(
                format!("/parameters/{i}/max"),
                crate::http::error::num(p.max),
                format!("must be finite and larger than min = {}", p.min),
            );
        }
    }
    ck.finish()?;
    Ok(outputs)
}

/// What a study's parameters are resolved against: the base column request (as sent, as
/// resolved, its case) and what it left to its defaults.
struct StudyBase<'a> {
    config: &'a Config,
    /// The base request as sent, as JSON.
    json: &'a Value,
    /// The base request as sent.
    sent: &'a ColumnRequest,
    /// The base request as resolved (the parameters' base values).
    resolved: &'a ColumnRequest,
    /// The base case.
    case: &'a ColumnCase,
    /// The coupled column model.
    coupled: bool,
    /// The base request gave the rock's corner radius.
    corner_given: bool,
    /// The base request gave an initial midpoint displacement.
    initial_given: bool,
}

impl StudyBase<'_> {
    /// Parameter `i` (`p`): its range ends and x·max values checked, its base value, its
    /// rank in the canonical order, its analytic elasticities and, where an output needs
    /// them, its central-difference points (or a warning why there are none).
    fn param(
        &self,
        i: usize,
        p: &StudyParameterDto,
        x_values: &[f64],
        outputs: &[String],
        warnings: &mut Vec<Warning>,
    ) -> Result<Param, ApiError> {
        let pointer = pointer_of(&p.name);
        let field = SweptField::of(&p.name, self.sent, self.json)
            .ok_or_else(|| refuse_name(self.config, self.json, i, p, &pointer))?;
        let proportion_defined = self.check_sweep(i, p, field, x_values, warnings)?;
        let base = field.base(&p.name, self.resolved);
        let rank = CANONICAL
            .iter()
            .position(|c| *c == p.name)
            .unwrap_or(CANONICAL.len() + i);
        let analytic = self.analytic(field)?;
        let needs_fd = outputs.iter().any(|o| {
            analytic.is_none()
                || !matches!(
                    o.as_str(),
                    "max_deformation_m" | "max_force_n" | "absorbed_energy_j" | "energy_ratio"
                )
        });
        let fd = if needs_fd {
            let pts = base.and_then(richardson_points).filter(|pts| {
                pts.iter()
                    .all(|&x| resolve_point(self.config, self.sent, &[(field, x)]).is_ok())
            });
            if pts.is_none() {
                warnings.push(Warning::new(
                    "elasticity_undefined",
                    format!(
                        "{}: no elasticity (the base value is {} and p ± 1e-4·|p| must be valid inputs)",
                        p.name,
                        base.map_or("absent".to_string(), |b| b.to_string())
                    ),
                ));
            }
            pts
        } else {
            None
        };
        Ok(Param {
            name: p.name.clone(),
            field,
            pointer,
            min: p.min,
            max: p.max,
            rank,
            base,
            fd,
            analytic,
            proportion_defined,
        })
    }

    /// The base request with parameter `i` (`p`, setting `field`) set to its range ends must be a
    /// valid column request (else 422 naming that end); returns, for each x value, whether x·max
    /// is one too. An energy-proportion point that is not (x·max below the field's range, or
    /// against another field's bound, e.g. an outer diameter at or below the inner one) is not
    /// part of the requested sweep: it is left out with an `energy_proportion_undefined`
    /// warning naming the points and why.
    fn check_sweep(
        &self,
        i: usize,
        p: &StudyParameterDto,
        field: SweptField,
        x_values: &[f64],
        warnings: &mut Vec<Warning>,
    ) -> Result<Vec<bool>, ApiError> {
        for (end, x) in [("min", p.min), ("max", p.max)] {
            if let Err(e) = resolve_point(self.config, self.sent, &[(field, x)]) {
                let field = if matches!(e.code(), "unknown_field" | "invalid_type") {
                    format!("/parameters/{i}/name")
                } else {
                    format!("/parameters/{i}/{end}")
                };
                return Err(blame(
                    &e,
                    &field,
                    &format!("{} = {x} is not a valid column request", p.name),
                ));
            }
        }
        let mut defined = Vec::with_capacity(x_values.len());
        let mut left_out = Vec::new();
        let mut why = None;
        for &x in x_values {
            let v = x * p.max;
            match resolve_point(self.config, self.sent, &[(field, v)]) {
                Ok(_) => defined.push(true),
                Err(e) => {
                    defined.push(false);
                    left_out.push(format!("x = {x} ({} = {v})", p.name));
                    why.get_or_insert_with(|| {
                        e.errors()
                            .first()
                            .map_or_else(|| e.to_string(), |f| format!("{} {}", f.field, f.message))
                    });
                }
            }
        }
        if let Some(why) = why {
            warnings.push(Warning::new(
                ENERGY_PROPORTION_UNDEFINED,
                format!(
                    "energy_proportion.curves[\"{}\"] is null at {}: x·max is not a valid column \
                     request ({why}); the sweep from min to max is unaffected",
                    p.name,
                    left_out.join(", ")
                ),
            ));
        }
        Ok(defined)
    }

    /// The analytic elasticities of the impact (physics.md §D.2) for the parameter setting
    /// `field`: v, L, ρ or E of a cube on the decoupled model from rest (not L when it moves
    /// the Hertz corner radius), all finite; None otherwise.
    fn analytic(
        &self,
        field: SweptField,
    ) -> Result<Option<crate::physics::study::ImpactElasticities>, ApiError> {
        let which = match field {
            SweptField::Velocity => Some(ImpactParameter::Velocity),
            SweptField::RockSideLength => Some(ImpactParameter::SideLength),
            SweptField::RockDensity => Some(ImpactParameter::Density),
            SweptField::RockElasticModulus => Some(ImpactParameter::RockModulus),
            _ => None,
        };
        let resolved = self.resolved;
        let hertz = resolved.contact.law == LawDto::HertzPoint;
        let side_moves_corner = hertz
            && which == Some(ImpactParameter::SideLength)
            && !(self.corner_given || resolved.rock.side_length_m / 2.0 > 0.02);
        Ok(match which {
            Some(w)
                if !self.coupled
                    && resolved.initial_midpoint_displacement_m.is_none()
                    && !self.initial_given
                    && resolved.rock.shape == ShapeKind::Cube
                    && !side_moves_corner =>
            {
                impact_elasticities(&self.case.impact, w)?.filter(|e| {
                    [
                        e.max_deformation,
                        e.max_force,
                        e.absorbed_energy,
                        e.energy_ratio,
                    ]
                    .iter()
                    .all(|x| x.is_finite())
                })
            }
            _ => None,
        })
    }
}

/// The swept values of each parameter: `n` evenly spaced from min, the last exactly max.
fn sweep_values(params: &[Param], n: usize) -> Vec<Vec<f64>> {
    params
        .iter()
        .map(|p| {
            (0..n)
                .map(|k| {
                    if k + 1 == n {
                        p.max
                    } else {
                        p.min + (p.max - p.min) * (k as f64) / ((n - 1) as f64)
                    }
                })
                .collect()
        })
        .collect()
}

/// The study's points in response order: the base, each parameter's curve of `n`, each of
/// the `grids` pair grids of n × n, then per parameter its `nx` energy proportions and its
/// four central-difference points.
fn study_slots(params: &[Param], grids: usize, n: usize, nx: usize) -> Vec<Slot> {
    let mut slots = vec![Slot::Base];
    for i in 0..params.len() {
        slots.extend((0..n).map(|k| Slot::Curve(i, k)));
    }
    for g in 0..grids {
        for yi in 0..n {
            slots.extend((0..n).map(|xi| Slot::Grid(g, yi, xi)));
        }
    }
    for (i, p) in params.iter().enumerate() {
        slots.extend(
            (0..nx)
                .filter(|&k| p.proportion_defined[k])
                .map(|k| Slot::Proportion(i, k)),
        );
        if p.fd.is_some() {
            slots.extend((0..4).map(|j| Slot::Difference(i, j)));
        }
    }
    slots
}

impl StudyPlan {
    /// Number of points: the base (point 0) and the items (1 ..).
    #[must_use]
    pub fn points(&self) -> u64 {
        self.slots.len() as u64
    }

    /// The resolved request (the response's `inputs`).
    #[must_use]
    pub fn inputs(&self) -> StudyRequest {
        let mut req = self.req.clone();
        req.base = self.base_resolved.clone();
        req
    }

    /// The swept values of point `index`: (parameter index, value) of each.
    fn sets(&self, index: usize) -> Vec<(usize, f64)> {
        let (params, values) = (&self.params, &self.values);
        match self.slots[index] {
            Slot::Base => Vec::new(),
            Slot::Curve(i, k) => vec![(i, values[i][k])],
            Slot::Grid(g, yi, xi) => {
                let (a, b) = self.pairs[g];
                vec![(a, values[a][xi]), (b, values[b][yi])]
            }
            Slot::Proportion(i, k) => vec![(i, self.req.x_values[k] * params[i].max)],
            Slot::Difference(i, j) => vec![(i, params[i].fd.map_or(0.0, |f| f[j]))],
        }
    }

    /// A point's error names the swept parameter (of `sets`) that set the field, else the
    /// base's field.
    fn blame_point(&self, e: ApiError, sets: &[(usize, f64)]) -> ApiError {
        let params = &self.params;
        e.rename_fields(|f| {
            params
                .iter()
                .enumerate()
                .position(|(i, p)| p.pointer == f && sets.iter().any(|(s, _)| *s == i))
                .map_or_else(|| format!("/base{f}"), |i| format!("/parameters/{i}"))
        })
    }

    /// Every curve and grid point must be a valid column request (the range ends, energy
    /// proportions and central-difference points are checked with their parameter): the first
    /// point, in point order, that the request's own validation refuses is refused as such.
    fn check_points(&self, config: &Config) -> Result<(), ApiError> {
        let sent = &self.req.base;
        match (0..self.slots.len())
            .into_par_iter()
            .filter(|&k| matches!(self.slots[k], Slot::Curve(..) | Slot::Grid(..)))
            .find_map_first(|k| {
                let sets = self.sets(k);
                let fields: Vec<(SweptField, f64)> = sets
                    .iter()
                    .map(|&(i, x)| (self.params[i].field, x))
                    .collect();
                resolve_point(config, sent, &fields)
                    .err()
                    .map(|e| self.blame_point(e, &sets))
            }) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Solves point `index`: the listed outputs and then the energy ratio.
    pub fn eval(
        &self,
        _config: &Config,
        index: usize,
        control: &Control,
    ) -> Result<Vec<f64>, ApiError> {
        control.check()?;
        let sets = self.sets(index);
        let swept: Vec<(calc::study::Parameter, f64)> = sets
            .iter()
            .map(|&(i, x)| (self.params[i].field.parameter(), x))
            .collect();
        let case = self.base.point(&swept);
        let report = Column::solve(&case, control).map_err(|e| {
            let e = ApiError::from(e).with_capacity_velocity(case.impact.velocity);
            let e = match case.end_time {
                Some(t) => e.with_step_field("/end_time_s", t),
                None => e,
            };
            self.blame_point(e, &sets)
        })?;
        let out = extract(&report.result, &self.reads)?;
        control.add_done(1);
        Ok(out)
    }

    /// The response from the outputs of every point, in point order.
    pub fn finish(self, results: Vec<Vec<f64>>) -> Result<StudyResponse, ApiError> {
        if results.len() != self.slots.len() {
            return Err(ApiError::internal(format!(
                "{} study results for {} points",
                results.len(),
                self.slots.len()
            )));
        }
        finish_study(self, results)
    }
}

/// Each point's outputs, placed where the response lists them.
struct Assembled {
    /// The base point's outputs, then its energy ratio.
    base: Vec<f64>,
    /// The curves: [parameter][output][point].
    curves: Vec<Vec<Vec<f64>>>,
    /// The pair grids: [pair][output][y point][x point].
    grids: Vec<Vec<Vec<Vec<f64>>>>,
    /// The energy ratio at each x·max: [parameter][x] (`None` where x·max is not a valid
    /// column request).
    proportions: Vec<Vec<Option<f64>>>,
    /// The four central-difference points' outputs: [parameter][output].
    differences: Vec<Vec<[f64; 4]>>,
}

/// Places the outputs `results` of the points `slots` (`no` outputs then the energy ratio
/// each) for `np` parameters of `n` points, `n_pairs` pair grids and `nx` x values.
fn assemble(
    slots: &[Slot],
    results: Vec<Vec<f64>>,
    no: usize,
    np: usize,
    n: usize,
    n_pairs: usize,
    nx: usize,
) -> Assembled {
    let ie = no; // index of energy_ratio in each result
    let mut y = Assembled {
        base: Vec::new(),
        curves: vec![vec![vec![0.0; n]; no]; np],
        grids: vec![vec![vec![vec![0.0; n]; n]; no]; n_pairs],
        proportions: vec![vec![None; nx]; np],
        differences: vec![vec![[0.0; 4]; no]; np],
    };
    for (slot, r) in slots.iter().zip(results) {
        match *slot {
            Slot::Base => y.base = r,
            Slot::Curve(i, k) => (0..no).for_each(|o| y.curves[i][o][k] = r[o]),
            Slot::Grid(g, yi, xi) => (0..no).for_each(|o| y.grids[g][o][yi][xi] = r[o]),
            Slot::Proportion(i, k) => y.proportions[i][k] = Some(r[ie]),
            Slot::Difference(i, j) => (0..no).for_each(|o| y.differences[i][o][j] = r[o]),
        }
    }
    y
}

/// The response of a checked study `plan` from the outputs `results` of its points.
fn finish_study(plan: StudyPlan, results: Vec<Vec<f64>>) -> Result<StudyResponse, ApiError> {
    let StudyPlan {
        mut req,
        base_resolved,
        coupled,
        outputs,
        reads,
        params,
        values,
        pairs,
        slots,
        mut warnings,
        ..
    } = plan;
    let n = req.points as usize;
    let np = params.len();
    let no = outputs.len();
    let ie = no; // index of energy_ratio in each result
    let y = assemble(&slots, results, no, np, n, pairs.len(), req.x_values.len());
    let curves = OrderedMap(
        params
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let mut m = vec![("values".to_string(), values[i].clone())];
                m.extend(
                    outputs
                        .iter()
                        .enumerate()
                        .map(|(o, name)| (name.clone(), y.curves[i][o].clone())),
                );
                (p.name.clone(), OrderedMap(m))
            })
            .collect(),
    );
    let grids = (req.grid == StudyGrid::Pairs).then(|| {
        pairs
            .iter()
            .enumerate()
            .map(|(g, &(a, b))| StudyGridDto {
                x: params[a].name.clone(),
                y: params[b].name.clone(),
                x_values: values[a].clone(),
                y_values: values[b].clone(),
                outputs: OrderedMap(
                    outputs
                        .iter()
                        .enumerate()
                        .map(|(o, name)| (name.clone(), y.grids[g][o].clone()))
                        .collect(),
                ),
            })
            .collect()
    });
    let ranks: Vec<usize> = params.iter().map(|p| p.rank).collect();
    let mut sensitivity = Vec::new();
    let mut groups_by_output = Vec::new();
    for (o, name) in outputs.iter().enumerate() {
        let (dto, groups) = output_sensitivity(o, name, &params, &ranks, &y, n, &mut warnings);
        sensitivity.push((name.clone(), dto));
        groups_by_output.push((reads[o].1, groups));
    }
    let prop_groups: Vec<Vec<Vec<usize>>> = (0..req.x_values.len())
        .map(|k| {
            let m: Vec<Option<f64>> = (0..np).map(|i| y.proportions[i][k]).collect();
            order_groups(&m, &ranks, TIE_REL)
        })
        .collect();
    let energy_proportion = EnergyProportionDto {
        model: if coupled { "coupled" } else { "decoupled" }.into(),
        x: req.x_values.clone(),
        curves: OrderedMap(
            params
                .iter()
                .enumerate()
                .map(|(i, p)| (p.name.clone(), y.proportions[i].clone()))
                .collect(),
        ),
        orderings: prop_groups
            .iter()
            .map(|g| ordering_names(g, &params))
            .collect(),
    };
    let swept: Vec<(calc::study::Parameter, f64, f64)> = params
        .iter()
        .map(|p| (p.field.parameter(), p.min, p.max))
        .collect();
    let paper_comparison: Vec<PaperComparisonDto> = calc::study::compare_with_paper(
        &swept,
        req.base.contact.effective_modulus == ModulusDto::TwoBody,
        coupled,
        &groups_by_output,
        &req.x_values,
        &prop_groups,
        y.base[ie],
    )
    .into_iter()
    .map(|c| PaperComparisonDto {
        item: c.item,
        paper: c.paper,
        ours: c.ours,
        reproduced: c.reproduced,
        note: c.note,
    })
    .collect();
    if paper_comparison.is_empty() {
        warnings.push(Warning::new(
            "no_paper_comparison",
            "paper_comparison is empty: it needs the paper's four parameters with the paper's ranges (physics.md §D.1)",
        ));
    }
    let analytic: Vec<&str> = params
        .iter()
        .filter(|p| p.analytic.is_some())
        .map(|p| p.name.as_str())
        .collect();
    let mut meta = Meta::new(plan_of(&calc::study::plan(
        &analytic,
        slots.len(),
        coupled,
        pairs.len(),
        n,
    )));
    meta.warnings = warnings;
    req.base = base_resolved;
    Ok(StudyResponse {
        curves,
        grids,
        sensitivity: OrderedMap(sensitivity),
        energy_proportion,
        paper_comparison,
        warnings: meta.warnings,
        plan: meta.plan,
        inputs: req,
        model_version: meta.model_version,
    })
}

/// The sensitivity of output `o` (`name`) to each parameter: its measures (a warning for
/// each that is undefined) and its three orderings (span over base, ratio, elasticity).
fn output_sensitivity(
    o: usize,
    name: &str,
    params: &[Param],
    ranks: &[usize],
    y: &Assembled,
    n: usize,
    warnings: &mut Vec<Warning>,
) -> (OutputSensitivityDto, [Vec<Vec<usize>>; 3]) {
    let y0 = y.base[o];
    let mut any_numeric = false;
    let measures: Vec<MeasuresDto> = params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (low, high) = (y.curves[i][o][0], y.curves[i][o][n - 1]);
            let analytic = p.analytic.and_then(|e| match name {
                "max_deformation_m" => Some(e.max_deformation),
                "max_force_n" => Some(e.max_force),
                "absorbed_energy_j" => Some(e.absorbed_energy),
                "energy_ratio" => Some(e.energy_ratio),
                _ => None,
            });
            let elasticity = analytic.or_else(|| {
                any_numeric = true;
                match (p.base, p.fd) {
                    (Some(b), Some(x)) => richardson_elasticity(b, y0, x, y.differences[i][o]),
                    _ => None,
                }
            });
            MeasuresDto {
                low,
                high,
                span_over_base: span_over_base(low, high, y0),
                ratio: ratio(low, high),
                elasticity,
            }
        })
        .collect();
    for (p, m) in params.iter().zip(&measures) {
        for (what, v) in [
            ("span_over_base", m.span_over_base),
            ("ratio", m.ratio),
            ("elasticity", m.elasticity),
        ] {
            if v.is_none() && !(what == "elasticity" && p.fd.is_none() && p.analytic.is_none()) {
                warnings.push(Warning::new(
                    "measure_undefined",
                    format!(
                        "{name}, {}: {what} is null (zero base output, or outputs of opposite sign or zero at the range ends); left out of the ordering",
                        p.name
                    ),
                ));
            }
        }
    }
    let by = |f: fn(&MeasuresDto) -> Option<f64>, tol: f64| {
        order_groups(&measures.iter().map(f).collect::<Vec<_>>(), ranks, tol)
    };
    let g_span = by(|m| m.span_over_base, TIE_REL);
    let g_ratio = by(|m| m.ratio, TIE_REL);
    let g_el = by(
        |m| m.elasticity,
        if any_numeric {
            TIE_REL_NUMERIC
        } else {
            TIE_REL
        },
    );
    let dto = OutputSensitivityDto {
        base: y0,
        parameters: OrderedMap(
            params
                .iter()
                .zip(&measures)
                .map(|(p, m)| (p.name.clone(), *m))
                .collect(),
        ),
        ordering: OrderingDto {
            span_over_base: ordering_names(&g_span, params),
            ratio: ordering_names(&g_ratio, params),
            elasticity: ordering_names(&g_el, params),
        },
    };
    (dto, [g_span, g_ratio, g_el])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calc::study::Parameter;

    /// Bases a study may start from: each rule that derives one field from another (the corner
    /// radius from L, a sphere's radius from L, the contact radius from D₁), given or derived,
    /// on both models.
    fn bases() -> Vec<Value> {
        vec![
            json!({}),
            json!({"contact": {"law": "hertz_point"}}),
            json!({"contact": {"law": "hertz_point"}, "rock": {"corner_radius_m": 0.03}}),
            json!({"contact": {"law": "hertz_point"}, "rock": {"shape": "sphere"}}),
            json!({"contact": {"law": "hertz_point"}, "rock": {"shape": "sphere", "radius_m": 0.1}}),
            json!({"contact": {"law": "johnson", "effective_modulus": "two_body"},
                   "column": {"contact_radius_m": 0.2}}),
            json!({"column": {"damping_ratio": 0.02}}),
            json!({"model": "coupled", "end_time_s": 0.02}),
            json!({"rock": {"dimensions_m": [0.2, 0.3, 0.4],
                            "random": {"semi_axes_m": [0.1, 0.2, 0.3]},
                            "vertices_m": [[0, 0, 0], [0.3, 0, 0], [0, 0.3, 0], [0, 0, 0.3]]}}),
        ]
    }

    const NAMES: [&str; 26] = [
        "velocity_m_s",
        "rock.side_length_m",
        "rock.radius_m",
        "rock.dimensions_m.1",
        "rock.vertices_m.2.0",
        "rock.random.semi_axes_m.2",
        "rock.density_kg_m3",
        "rock.elastic_modulus_pa",
        "rock.poisson_ratio",
        "rock.corner_radius_m",
        "column.outer_diameter_m",
        "column.inner_diameter_m",
        "column.length_m",
        "column.elastic_modulus_pa",
        "column.poisson_ratio",
        "column.density_kg_m3",
        "column.yield_stress_pa",
        "column.contact_radius_m",
        "column.damping_coefficient_n_s_m2",
        "column.damping_ratio",
        "initial_midpoint_displacement_m",
        "end_time_s",
        "output.duration_s",
        "velocity_m_s.x",
        "rock.dimensions_m.9",
        "contact.law.x",
    ];

    /// The case of a study point made on the base case equals the case of the base request with
    /// the same values set and resolved, for every field a study sweeps, alone and two at a
    /// time (the pairs that move a derived field), at values across each field's range.
    #[test]
    fn a_point_case_is_the_resolved_request_with_its_values() {
        let config = Config::default();
        let mut compared = 0;
        for base in bases() {
            let sent: ColumnRequest = from_value(&base).unwrap();
            let sent_json = serde_json::to_value(&sent).unwrap();
            let mut resolved = sent.clone();
            let case = resolved.resolve(&config).unwrap();
            let study = StudyCase {
                case,
                given: Given {
                    corner_radius: sent.rock.corner_radius_m.is_some(),
                    radius: sent.rock.radius_m.is_some(),
                    contact_radius: sent.column.contact_radius_m.is_some(),
                },
            };
            assert_eq!(study.point(&[]), study.case, "{base}");
            let fields: Vec<(&str, SweptField)> = NAMES
                .iter()
                .filter_map(|n| SweptField::of(n, &sent, &sent_json).map(|f| (*n, f)))
                .collect();
            for &(name, f) in &fields {
                let b = f.get(&resolved).unwrap_or(0.1);
                for x in [
                    0.01,
                    0.05,
                    0.13,
                    0.3,
                    0.7,
                    0.5 * b,
                    0.9 * b,
                    1.1 * b,
                    2.0 * b,
                ] {
                    let mut sets = vec![(f, x)];
                    let mut cases = vec![sets.clone()];
                    for &(_, g) in &fields {
                        if g != f {
                            sets.push((g, 0.9 * g.get(&resolved).unwrap_or(0.1)));
                            cases.push(sets.clone());
                            sets.pop();
                        }
                    }
                    for sets in cases {
                        let Ok(want) = resolve_point(&config, &sent, &sets) else {
                            continue;
                        };
                        let params: Vec<(Parameter, f64)> =
                            sets.iter().map(|&(g, x)| (g.parameter(), x)).collect();
                        assert_eq!(study.point(&params), want, "{base}: {name} {sets:?}");
                        compared += 1;
                    }
                }
            }
        }
        assert!(compared > 2000, "{compared} points compared");
    }

    /// A path through a number or past an array's end sets nothing; a path the request does not
    /// have, or to a field that is not a number, names no field (the request's own refusal).
    #[test]
    fn swept_names_map_to_the_fields_they_set() {
        let sent: ColumnRequest =
            from_value(&json!({"rock": {"dimensions_m": [0.2, 0.3, 0.4]}})).unwrap();
        let v = serde_json::to_value(&sent).unwrap();
        let of = |n: &str| SweptField::of(n, &sent, &v);
        assert_eq!(of("rock.density_kg_m3"), Some(SweptField::RockDensity));
        assert_eq!(
            of("rock.dimensions_m.2"),
            Some(SweptField::RockDimension(2))
        );
        assert_eq!(
            of("rock.dimensions_m.+1"),
            Some(SweptField::RockDimension(1))
        );
        assert_eq!(of("rock.dimensions_m.3"), None);
        assert_eq!(of("velocity_m_s.x"), None);
        assert_eq!(of("rock.densty_kg_m3"), None);
        assert_eq!(of("galerkin.modes"), None);
        assert_eq!(of("rock.vertices_m.0.0"), None);
        // the base value as a JSON Pointer reads it
        let f = SweptField::RockDimension(1);
        assert_eq!(f.base("rock.dimensions_m.1", &sent), Some(0.3));
        assert_eq!(f.base("rock.dimensions_m.+1", &sent), None);
        assert_eq!(f.base("rock.dimensions_m.01", &sent), None);
    }
}

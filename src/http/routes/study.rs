//! `POST /v1/study`: parameter sweeps over the base column request, sensitivity measures and
//! orderings, energy proportions and the comparison with the paper's orderings.
//!
//! Every study point is a column request built by setting the swept values in the base
//! request's JSON, resolved through the column DTO (so the ranges are checked) and solved by the
//! same code as `POST /v1/column`: a study value equals a separate `/v1/column` call bit for
//! bit. Points run in parallel on the solver pool and are collected in a fixed order, so the
//! answer does not depend on the thread count.

use axum::extract::State;
use axum::http::HeaderMap;
use axum::response::Response;
use rayon::prelude::*;
use serde_json::{Value, json};

use crate::calc;
use crate::config::Config;
use crate::http::dto::column::{ColumnModelDto, ColumnRequest};
use crate::http::dto::common::{LawDto, Meta, ModulusDto, ShapeKind, Warning, plan_of};
use crate::http::dto::study::{
    CANONICAL, ENERGY_PROPORTION_UNDEFINED, EnergyProportionDto, MeasuresDto, OrderedMap,
    OrderingDto, OutputSensitivityDto, PaperComparisonDto, StudyGrid, StudyGridDto,
    StudyParameterDto, StudyRequest, StudyResponse, default_outputs, pointer_of, set_pointer,
    study_outputs,
};
use crate::http::error::{ApiError, FieldError};
use crate::http::json::{AppJson, from_value};
use crate::http::routes::column;
use crate::http::runner::{AppState, respond};
use crate::physics::Control;
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

/// A column request with the given values set at the given pointers.
fn point_json(base: &Value, sets: &[(&str, f64)]) -> Value {
    let mut v = base.clone();
    for (p, x) in sets {
        set_pointer(&mut v, p, *x);
    }
    v
}

fn resolve_point(
    config: &Config,
    v: &Value,
) -> Result<(ColumnRequest, crate::physics::column::ColumnCase), ApiError> {
    let mut req: ColumnRequest = from_value(v)?;
    let case = req.resolve(config)?;
    Ok((req, case))
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

fn extract(resp: &Value, outputs: &[String]) -> Result<Vec<f64>, ApiError> {
    outputs
        .iter()
        .map(|o| {
            resp.pointer(&pointer_of(o))
                .and_then(Value::as_f64)
                .filter(|x| x.is_finite())
                .ok_or_else(|| ApiError::internal(format!("study output {o} missing")))
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
    base_json: Value,
    base_resolved: ColumnRequest,
    coupled: bool,
    outputs: Vec<String>,
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
    let base_resolved_json = serde_json::to_value(&base_resolved).map_err(ApiError::internal)?;
    let coupled = base_resolved.model == ColumnModelDto::Coupled;
    let outputs = check_request(config, &mut req, coupled)?;

    // Each parameter: its range ends must resolve, and its base value.
    let base = StudyBase {
        config,
        json: &base_json,
        resolved: &base_resolved,
        resolved_json: &base_resolved_json,
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
    Ok(StudyPlan {
        req,
        base_json,
        base_resolved,
        coupled,
        outputs,
        params,
        values,
        pairs,
        slots,
        warnings,
    })
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
    /// The base request as sent.
    json: &'a Value,
    /// The base request as resolved.
    resolved: &'a ColumnRequest,
    /// The resolved base request as JSON (the parameters' base values).
    resolved_json: &'a Value,
    /// The base case.
    case: &'a crate::physics::column::ColumnCase,
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
        let proportion_defined = self.check_sweep(i, p, &pointer, x_values, warnings)?;
        let base = self.resolved_json.pointer(&pointer).and_then(Value::as_f64);
        let rank = CANONICAL
            .iter()
            .position(|c| *c == p.name)
            .unwrap_or(CANONICAL.len() + i);
        let analytic = self.analytic(&p.name)?;
        let needs_fd = outputs.iter().any(|o| {
            analytic.is_none()
                || !matches!(
                    o.as_str(),
                    "max_deformation_m" | "max_force_n" | "absorbed_energy_j" | "energy_ratio"
                )
        });
        let fd = if needs_fd {
            let pts = base.and_then(richardson_points).filter(|pts| {
                pts.iter().all(|&x| {
                    resolve_point(self.config, &point_json(self.json, &[(&pointer, x)])).is_ok()
                })
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

    /// The base request with parameter `i` (`p`, at `pointer`) set to its range ends must be a
    /// valid column request (else 422 naming that end); returns, for each x value, whether x·max
    /// is one too. An energy-proportion point that is not (x·max below the field's range, or
    /// against another field's bound, e.g. an outer diameter at or below the inner one) is not
    /// part of the requested sweep: it is left out with an `energy_proportion_undefined`
    /// warning naming the points and why.
    fn check_sweep(
        &self,
        i: usize,
        p: &StudyParameterDto,
        pointer: &str,
        x_values: &[f64],
        warnings: &mut Vec<Warning>,
    ) -> Result<Vec<bool>, ApiError> {
        for (end, x) in [("min", p.min), ("max", p.max)] {
            if let Err(e) = resolve_point(self.config, &point_json(self.json, &[(pointer, x)])) {
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
            match resolve_point(self.config, &point_json(self.json, &[(pointer, v)])) {
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

    /// The analytic elasticities of the impact (physics.md §D.2) for the parameter `name`:
    /// v, L, ρ or E of a cube on the decoupled model from rest (not L when it moves the
    /// Hertz corner radius), all finite; None otherwise.
    fn analytic(
        &self,
        name: &str,
    ) -> Result<Option<crate::physics::study::ImpactElasticities>, ApiError> {
        let which = match name {
            "velocity_m_s" => Some(ImpactParameter::Velocity),
            "rock.side_length_m" => Some(ImpactParameter::SideLength),
            "rock.density_kg_m3" => Some(ImpactParameter::Density),
            "rock.elastic_modulus_pa" => Some(ImpactParameter::RockModulus),
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

    /// Solves point `index`: the listed outputs and then the energy ratio.
    pub fn eval(
        &self,
        config: &Config,
        index: usize,
        control: &Control,
    ) -> Result<Vec<f64>, ApiError> {
        let (params, values, pairs) = (&self.params, &self.values, &self.pairs);
        let x_values = &self.req.x_values;
        let mut extract_names = self.outputs.clone();
        extract_names.push("energy_ratio".into());
        control.check()?;
        let sets: Vec<(&str, f64)> = match self.slots[index] {
            Slot::Base => Vec::new(),
            Slot::Curve(i, k) => vec![(params[i].pointer.as_str(), values[i][k])],
            Slot::Grid(g, yi, xi) => {
                let (a, b) = pairs[g];
                vec![
                    (params[a].pointer.as_str(), values[a][xi]),
                    (params[b].pointer.as_str(), values[b][yi]),
                ]
            }
            Slot::Proportion(i, k) => {
                vec![(params[i].pointer.as_str(), x_values[k] * params[i].max)]
            }
            Slot::Difference(i, j) => {
                vec![(
                    params[i].pointer.as_str(),
                    params[i].fd.map_or(0.0, |f| f[j]),
                )]
            }
        };
        // A point's error names the swept parameter that set the field, else the base's field.
        let blame_point = |e: ApiError| {
            e.rename_fields(|f| {
                params
                    .iter()
                    .position(|p| p.pointer == f && sets.iter().any(|(s, _)| *s == f))
                    .map_or_else(|| format!("/base{f}"), |i| format!("/parameters/{i}"))
            })
        };
        let (req, case) =
            resolve_point(config, &point_json(&self.base_json, &sets)).map_err(blame_point)?;
        let resp = column::solve(&case, req, control).map_err(blame_point)?;
        let v = serde_json::to_value(&resp).map_err(ApiError::internal)?;
        let out = extract(&v, &extract_names)?;
        control.add_done(1);
        Ok(out)
    }

    /// The response from the outputs of every point, in point order.
    pub fn finish(self, results: Vec<Vec<f64>>) -> Result<StudyResponse, ApiError> {
        let StudyPlan {
            req,
            base_resolved,
            coupled,
            outputs,
            params,
            values,
            pairs,
            slots,
            warnings,
            ..
        } = self;
        if results.len() != slots.len() {
            return Err(ApiError::internal(format!(
                "{} study results for {} points",
                results.len(),
                slots.len()
            )));
        }
        let n = req.points as usize;
        let np = params.len();
        finish_study(
            req,
            base_resolved,
            coupled,
            &outputs,
            &params,
            &values,
            &pairs,
            &slots,
            warnings,
            n,
            np,
            results,
        )
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

#[allow(clippy::too_many_arguments)]
fn finish_study(
    mut req: StudyRequest,
    base_resolved: ColumnRequest,
    coupled: bool,
    outputs: &[String],
    params: &[Param],
    values: &[Vec<f64>],
    pairs: &[(usize, usize)],
    slots: &[Slot],
    mut warnings: Vec<Warning>,
    n: usize,
    np: usize,
    results: Vec<Vec<f64>>,
) -> Result<StudyResponse, ApiError> {
    let no = outputs.len();
    let ie = no; // index of energy_ratio in each result
    let y = assemble(slots, results, no, np, n, pairs.len(), req.x_values.len());
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
        let (dto, groups) = output_sensitivity(o, name, params, &ranks, &y, n, &mut warnings);
        sensitivity.push((name.clone(), dto));
        groups_by_output.push((name.clone(), groups));
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
            .map(|g| ordering_names(g, params))
            .collect(),
    };
    let swept: Vec<(&str, f64, f64)> = params
        .iter()
        .map(|p| (p.name.as_str(), p.min, p.max))
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

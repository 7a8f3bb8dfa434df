//! A study's checks: each swept value set on the base request as sent and resolved, refused as
//! the request's own validation refuses it, naming the study's field.

use super::*;

/// The base request as sent with each field of `sets` set, checked and resolved as a column
/// request: the case of the point, or the request's own refusal.
pub(super) fn resolve_point(
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
pub(super) fn refuse_name(
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
pub(super) fn blame(e: &ApiError, field: &str, what: &str) -> ApiError {
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

/// The study's own fields: points, parameters (distinct dotted paths, finite min < max),
/// x values in (0, 1], outputs of the column model (filled in by default); returns the
/// outputs.
pub(super) fn check_request(
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
pub(super) struct StudyBase<'a> {
    pub(super) config: &'a Config,
    /// The base request as sent, as JSON.
    pub(super) json: &'a Value,
    /// The base request as sent.
    pub(super) sent: &'a ColumnRequest,
    /// The base request as resolved (the parameters' base values).
    pub(super) resolved: &'a ColumnRequest,
    /// The base case.
    pub(super) case: &'a ColumnCase,
    /// The coupled column model.
    pub(super) coupled: bool,
    /// The base request gave the rock's corner radius.
    pub(super) corner_given: bool,
    /// The base request gave an initial midpoint displacement.
    pub(super) initial_given: bool,
}

impl StudyBase<'_> {
    /// Parameter `i` (`p`): its range ends and x·max values checked, its base value, its
    /// rank in the canonical order, its analytic elasticities and, where an output needs
    /// them, its central-difference points (or a warning why there are none).
    pub(super) fn param(
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
    pub(super) fn check_sweep(
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
    pub(super) fn analytic(
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
            && !(self.corner_given
                || resolved.rock.side_length_m / 2.0
                    > crate::physics::material::defaults::ROCK_CORNER_RADIUS);
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

//! `POST /v1/impact`: request, response, validation.

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use super::common::{
    Checker, ColumnDto, ContactDto, LawDto, MODEL_VERSION, ModulusDto, RockDto, ShapeKind,
    VELOCITY, plan_of, velocity_schema, warnings_of,
};
use crate::calc::{self, Report};
use crate::config::Config;
use crate::http::error::ApiError;
use crate::physics::contact::ImpactDetail;
use crate::physics::material::ImpactCase;

/// Optional outputs of an impact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ImpactOutputDto {
    /// Points of the force–approach curve P(δ) from 0 to δmax (0: no curve).
    #[schema(default = 0, minimum = 0, maximum = 10000, example = 200)]
    pub curve_points: u32,
}

/// A normal impact of the rock on the column's midpoint, against a rigid column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ImpactRequest {
    /// Normal impact speed v, m/s, in (0, 1000].
    #[schema(schema_with = velocity_schema)]
    pub velocity_m_s: f64,
    /// The rock block.
    pub rock: RockDto,
    /// The struck column.
    pub column: ColumnDto,
    /// The contact model.
    pub contact: ContactDto,
    /// Optional outputs.
    pub output: ImpactOutputDto,
}

impl Default for ImpactRequest {
    fn default() -> Self {
        Self {
            velocity_m_s: VELOCITY.value(),
            rock: RockDto::default(),
            column: ColumnDto::default(),
            contact: ContactDto::default(),
            output: ImpactOutputDto::default(),
        }
    }
}

/// Checks the parts shared by impact and column requests and builds the physics case.
/// Fills derived defaults in place so that the request echoes as resolved `inputs`.
pub fn resolve_impact_case(
    velocity: f64,
    rock: &mut RockDto,
    column: &mut ColumnDto,
    contact: ContactDto,
    checker: &mut Checker,
) -> ImpactCase {
    VELOCITY.check(checker, "/velocity_m_s", velocity);
    let hertz = contact.law == LawDto::HertzPoint;
    let rock_p = rock.resolve("/rock", hertz, checker);
    let column_p = column.resolve("/column", checker);
    match rock.shape {
        ShapeKind::Cube => {
            if rock.side_length_m.is_finite()
                && column.length_m.is_finite()
                && column.length_m < rock.side_length_m
            {
                checker.push(
                    "/column/length_m",
                    crate::http::error::num(column.length_m),
                    format!(
                        "must be at least the contact length L = rock.side_length_m = {} m",
                        rock.side_length_m
                    ),
                );
            }
        }
        ShapeKind::Sphere => {
            let law = crate::physics::material::ContactModel::from(contact).law;
            if let Err(m) = crate::physics::contact::sphere_law_rule(true, law) {
                checker.push("/contact/law", serde_json::json!(contact.law), m);
            }
        }
        other => checker.push(
            "/rock/shape",
            serde_json::json!(other),
            "the impact is defined for a cube (line or point contact) or a sphere (hertz_point)",
        ),
    }
    ImpactCase {
        velocity,
        rock: rock_p,
        column: column_p,
        contact: contact.into(),
    }
}

impl ImpactRequest {
    /// Range checks, derived defaults and conversion; `self` becomes the resolved request.
    pub fn resolve(&mut self, config: &Config) -> Result<calc::impact::Case, ApiError> {
        let mut checker = Checker::new();
        checker.count(
            "/output/curve_points",
            u64::from(self.output.curve_points),
            0,
            config.max_curve_points,
            "points",
        );
        let case = resolve_impact_case(
            self.velocity_m_s,
            &mut self.rock,
            &mut self.column,
            self.contact,
            &mut checker,
        );
        checker.finish()?;
        Ok(calc::impact::Case {
            impact: case,
            curve_points: self.output.curve_points as usize,
        })
    }
}

/// The force–approach law P(δ) as equal-length arrays.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct CurveDto {
    /// Approach δ, m, from 0 to δmax.
    pub deformation_m: Vec<f64>,
    /// Force P(δ), N.
    pub force_n: Vec<f64>,
}

/// Result of an impact.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ImpactResponse {
    /// Rock mass m, kg.
    pub mass_kg: f64,
    /// Rock kinetic energy ½mv², J.
    pub kinetic_energy_j: f64,
    /// Effective modulus E*, Pa.
    pub effective_modulus_pa: f64,
    /// Contact radius R, m.
    pub contact_radius_m: f64,
    /// The law used.
    pub law: LawDto,
    /// The effective-modulus convention used.
    pub effective_modulus: ModulusDto,
    /// Whether the exact elliptical Hertz κ was used (`hertz_point`).
    pub hertz_exact: bool,
    /// Energy parameter G (log laws), dimensionless, ≤ 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_parameter: Option<f64>,
    /// W₋₁(−G/e) (log laws), ≤ −1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambert_w: Option<f64>,
    /// Maximum approach δmax, m.
    pub max_deformation_m: f64,
    /// Maximum contact force Pmax, N.
    pub max_force_n: f64,
    /// Contact half-width a at Pmax (log laws), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_half_width_m: Option<f64>,
    /// Maximum contact pressure p₀, Pa.
    pub max_contact_pressure_pa: f64,
    /// Largest energy the law can store (log laws), J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy_capacity_j: Option<f64>,
    /// Approach at the capacity (log laws), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deformation_capacity_m: Option<f64>,
    /// Force at the capacity (log laws), N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_capacity_n: Option<f64>,
    /// Hertz stiffness κ in P = κδ^{3/2} (`hertz_point`), N/m^1.5.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hertz_stiffness_n_m1_5: Option<f64>,
    /// Equivalent radius R_e = √(R′R″) (`hertz_point`), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equivalent_radius_m: Option<f64>,
    /// δmax by the equivalent-radius form (`hertz_point`), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_deformation_equivalent_radius_m: Option<f64>,
    /// Contact-ellipse axis ratio b/a (`hertz_point`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_ellipse_axis_ratio: Option<f64>,
    /// Contact-ellipse semi-axes [a, b] at Pmax (`hertz_point`), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_semi_axes_m: Option<[f64; 2]>,
    /// Contact duration against a rigid column, s.
    pub contact_duration_s: f64,
    /// The force–approach curve, when `output.curve_points` > 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub curve: Option<CurveDto>,
    /// Named warnings, each with a documented threshold (strict): `near_capacity` (log laws,
    /// G > 0.9), `contact_pressure_above_yield` (max_contact_pressure_pa > column.yield_stress_pa:
    /// the elastic contact law is outside its validity), `approach_above_tenth_of_radius`
    /// (max_deformation_m > 0.1 × contact_radius_m: the approach is not small against the radius).
    pub warnings: Vec<super::Warning>,
    /// Stages run or skipped.
    pub plan: Vec<super::PlanStep>,
    /// The fully resolved request.
    pub inputs: ImpactRequest,
    /// Version of the service and its models.
    pub model_version: String,
}

impl ImpactResponse {
    /// Builds the response from the calculation's report and the resolved request.
    #[must_use]
    pub fn new(report: Report<calc::impact::Outcome>, inputs: ImpactRequest) -> Self {
        let contact = inputs.contact;
        let r = &report.result.impact;
        let mut out = Self {
            mass_kg: r.mass,
            kinetic_energy_j: r.kinetic_energy,
            effective_modulus_pa: r.effective_modulus,
            contact_radius_m: r.contact_radius,
            law: contact.law,
            effective_modulus: contact.effective_modulus,
            hertz_exact: contact.hertz_exact,
            energy_parameter: None,
            lambert_w: None,
            max_deformation_m: 0.0,
            max_force_n: 0.0,
            contact_half_width_m: None,
            max_contact_pressure_pa: 0.0,
            energy_capacity_j: None,
            deformation_capacity_m: None,
            force_capacity_n: None,
            hertz_stiffness_n_m1_5: None,
            equivalent_radius_m: None,
            max_deformation_equivalent_radius_m: None,
            contact_ellipse_axis_ratio: None,
            contact_semi_axes_m: None,
            contact_duration_s: r.contact_duration,
            curve: report.result.curve.map(|c| CurveDto {
                deformation_m: c.deformation,
                force_n: c.force,
            }),
            warnings: warnings_of(&report.warnings),
            plan: plan_of(&report.plan),
            inputs,
            model_version: MODEL_VERSION.into(),
        };
        match &r.detail {
            ImpactDetail::Line(l) => {
                out.energy_parameter = Some(l.energy_parameter);
                out.lambert_w = Some(l.lambert_w);
                out.max_deformation_m = l.max_deformation;
                out.max_force_n = l.max_force;
                out.contact_half_width_m = Some(l.half_width);
                out.max_contact_pressure_pa = l.max_pressure;
                out.energy_capacity_j = Some(l.energy_capacity);
                out.deformation_capacity_m = Some(l.deformation_capacity);
                out.force_capacity_n = Some(l.force_capacity);
            }
            ImpactDetail::Hertz(h) => {
                out.max_deformation_m = h.max_deformation;
                out.max_force_n = h.max_force;
                out.max_contact_pressure_pa = h.max_pressure;
                out.hertz_stiffness_n_m1_5 = Some(h.stiffness);
                out.equivalent_radius_m = Some(h.equivalent_radius);
                out.max_deformation_equivalent_radius_m = Some(h.max_deformation_equivalent_radius);
                out.contact_ellipse_axis_ratio = Some(h.axis_ratio);
                out.contact_semi_axes_m = Some(h.semi_axes);
            }
        }
        out
    }
}

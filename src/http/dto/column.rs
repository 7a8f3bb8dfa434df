//! `POST /v1/column`: request, response, validation.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::common::{
    Bound, Checker, ColumnDto, ContactDto, FieldDefault, Meta, NumberField, PlanStep, RockDto,
    VELOCITY, Warning, non_null, number_schemas, velocity_schema,
};
use super::impact::resolve_impact_case;
use super::param::Layout;
use crate::calc::Report;
use crate::config::Config;
use crate::http::error::ApiError;
use crate::physics::Param;
use crate::physics::beam::{MAX_MODES, ModeShapes};
use crate::physics::column::{
    ColumnCase, ColumnDetail, ColumnHistory, ColumnModel, ColumnResult, HistoryRequest,
};

/// `initial_midpoint_displacement_m` (decoupled only; `null`: δmax).
pub const INITIAL_MIDPOINT_DISPLACEMENT: NumberField = NumberField {
    description: "Initial midpoint displacement, m, in (0, 1] (decoupled only; default δmax).",
    default: FieldDefault::Null,
    lo: Bound::Open(0.0),
    hi: Bound::Closed(1.0),
    unit: "m",
    example: 0.0018,
    nullable: true,
};

/// `end_time_s` (coupled only; `null`: 50 × the rigid contact duration). The documented maximum
/// is the default `--max-end-time-s`.
pub const END_TIME: NumberField = NumberField {
    description: "End of the coupled window, s, in [1e-9, 1e3] (coupled only; default 50 × the \
                  rigid contact duration; shorter windows resolve nothing of a contact; the \
                  maximum is the service's --max-end-time-s, 1e3 by default).",
    default: FieldDefault::Null,
    lo: Bound::Closed(crate::physics::column::MIN_END_TIME),
    hi: Bound::Closed(1000.0),
    unit: "s",
    example: 0.05,
    nullable: true,
};

number_schemas! {
    initial_midpoint_displacement_schema => INITIAL_MIDPOINT_DISPLACEMENT;
    end_time_schema => END_TIME;
}

/// Which column model to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum ColumnModelDto {
    /// The paper's method: mode 1 released from w_mid(0) = δmax (physics.md §B.5).
    #[default]
    Decoupled,
    /// Rock + contact law + n exact modes, integrated with events (physics.md §B.7).
    Coupled,
}

/// Mode shapes of mode 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum ModeShapesDto {
    /// Exact clamped–clamped modes.
    #[default]
    Exact,
    /// The paper's printed constants (λ = 4.73), mode 1 only.
    Paper,
    /// λ = (2i+1)π/2, mode 1 only.
    Approx,
}

/// Galerkin discretisation of the column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct GalerkinDto {
    /// Number of modes 1…n: decoupled 1 only; coupled up to 50 (default 1 decoupled, 3 coupled).
    #[schema(minimum = 1, maximum = 50, example = 3)]
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    pub modes: Option<u32>,
    /// Mode shapes (`paper` and `approx` are defined for mode 1 only: decoupled).
    #[schema(default = "exact", example = "exact")]
    pub mode_shapes: ModeShapesDto,
    /// Include the rotary inertia J₀ = ρ_s I.
    #[schema(default = true, example = true)]
    pub rotary_inertia: bool,
}

impl Default for GalerkinDto {
    fn default() -> Self {
        Self {
            modes: None,
            mode_shapes: ModeShapesDto::Exact,
            rotary_inertia: true,
        }
    }
}

/// History output: explicit times, or a duration with a number of samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ColumnOutputDto {
    /// Sample times, s, each in [0, 1e6] (coupled: within the window).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = json!([0.0, 0.0001, 0.001]))]
    pub times_s: Option<Vec<f64>>,
    /// Duration sampled from 0, s, in (0, 1e6] (coupled default: the whole window).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(exclusive_minimum = 0.0, maximum = 1e6, example = 0.01)]
    pub duration_s: Option<f64>,
    /// Number of samples ≥ 2 (default ⌈40·f₁·duration⌉ + 1, capped by the samples limit).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(minimum = 2, example = 401)]
    pub samples: Option<u64>,
}

/// Column vibration after an impact: the impact request plus the column model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ColumnRequest {
    /// Normal impact speed v, m/s, in (0, 1000].
    #[schema(schema_with = velocity_schema)]
    pub velocity_m_s: f64,
    /// The rock block.
    pub rock: RockDto,
    /// The struck column.
    pub column: ColumnDto,
    /// The contact model.
    pub contact: ContactDto,
    /// Decoupled (the paper's method) or coupled.
    #[schema(default = "decoupled", example = "decoupled")]
    pub model: ColumnModelDto,
    /// Galerkin modes.
    pub galerkin: GalerkinDto,
    /// Initial midpoint displacement, m, in (0, 1] (decoupled only; default δmax).
    #[schema(schema_with = initial_midpoint_displacement_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub initial_midpoint_displacement_m: Option<f64>,
    /// End of the coupled window, s, in [1e-9, 1e3] (coupled only; default 50 × the rigid contact
    /// duration; shorter windows resolve nothing of a contact).
    #[schema(schema_with = end_time_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end_time_s: Option<f64>,
    /// History output (null: no history).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<ColumnOutputDto>,
}

impl Default for ColumnRequest {
    fn default() -> Self {
        Self {
            velocity_m_s: VELOCITY.value(),
            rock: RockDto::default(),
            column: ColumnDto::default(),
            contact: ContactDto::default(),
            model: ColumnModelDto::Decoupled,
            galerkin: GalerkinDto::default(),
            initial_midpoint_displacement_m: None,
            end_time_s: None,
            output: None,
        }
    }
}

impl ColumnRequest {
    /// Range checks, derived defaults and conversion; `self` becomes the resolved request.
    pub fn resolve(&mut self, config: &Config) -> Result<ColumnCase, ApiError> {
        self.resolve_in(config, Layout::Request)
    }

    /// [`Self::resolve`] with the history fields named as in `layout` (a scene checks its
    /// `column_output` here).
    pub fn resolve_in(&mut self, config: &Config, layout: Layout) -> Result<ColumnCase, ApiError> {
        let mut checker = Checker::new();
        let impact = resolve_impact_case(
            self.velocity_m_s,
            &mut self.rock,
            &mut self.column,
            self.contact,
            &mut checker,
        );
        let coupled = self.model == ColumnModelDto::Coupled;
        let modes = *self
            .galerkin
            .modes
            .get_or_insert(if coupled { 3 } else { 1 });
        if coupled {
            checker.count(
                "/galerkin/modes",
                u64::from(modes),
                1,
                config.max_modes.min(MAX_MODES as u64),
                "modes",
            );
            if self.galerkin.mode_shapes != ModeShapesDto::Exact {
                checker.push(
                    "/galerkin/mode_shapes",
                    json!(self.galerkin.mode_shapes),
                    "the coupled model uses exact mode shapes (paper and approx are defined for mode 1 only)",
                );
            }
            if let Some(w) = self.initial_midpoint_displacement_m {
                checker.push(
                    "/initial_midpoint_displacement_m",
                    crate::http::error::num(w),
                    "applies to the decoupled model only",
                );
            }
            if let Some(t) = self.end_time_s {
                // The documented maximum is the default limit (--max-end-time-s).
                checker.range(
                    "/end_time_s",
                    t,
                    END_TIME.lo,
                    Bound::Closed(config.max_end_time_s),
                    END_TIME.unit,
                );
            }
        } else {
            if let Err(m) = crate::physics::column::decoupled_modes_rule(modes as usize) {
                checker.push("/galerkin/modes", json!(modes), m);
            }
            if let (Some(t), Err(m)) = (
                self.end_time_s,
                crate::physics::column::decoupled_window_rule(self.end_time_s),
            ) {
                checker.push("/end_time_s", crate::http::error::num(t), m);
            }
            if let Some(w) = self.initial_midpoint_displacement_m {
                INITIAL_MIDPOINT_DISPLACEMENT.check(
                    &mut checker,
                    "/initial_midpoint_displacement_m",
                    w,
                );
            }
        }
        let max_samples = config.max_samples;
        let output = match &self.output {
            None => HistoryRequest::None,
            Some(o) => {
                if let Some(d) = o.duration_s {
                    checker.open_closed(&layout.pointer(Param::HistoryDuration), d, 0.0, 1e6, "s");
                }
                if let Some(n) = o.samples {
                    checker.count(
                        &layout.pointer(Param::HistorySamples),
                        n,
                        2,
                        max_samples,
                        "samples",
                    );
                }
                match (&o.times_s, o.duration_s, o.samples) {
                    (Some(t), None, None) => {
                        if t.len() as u64 > max_samples {
                            checker.push(
                                layout.pointer(Param::HistoryTimes),
                                json!(t.len()),
                                format!("at most {max_samples} times"),
                            );
                        }
                        for (i, &ti) in t.iter().enumerate() {
                            checker.closed(
                                &layout.pointer(Param::HistoryTime(i)),
                                ti,
                                0.0,
                                1e6,
                                "s",
                            );
                        }
                        HistoryRequest::Times(t.clone())
                    }
                    (Some(_), _, _) => {
                        checker.push(
                            layout.pointer(Param::HistoryTimes),
                            Value::Null,
                            "give either times_s or duration_s (with samples), not both",
                        );
                        HistoryRequest::None
                    }
                    (None, None, _) if !coupled => {
                        checker.push(
                            layout.pointer(Param::HistoryDuration),
                            Value::Null,
                            "the decoupled history needs times_s or duration_s in (0, 1e6] s",
                        );
                        HistoryRequest::None
                    }
                    (None, duration, samples) => HistoryRequest::Uniform {
                        duration,
                        samples: samples.map(|n| n as usize),
                    },
                }
            }
        };
        checker.finish()?;
        Ok(ColumnCase {
            impact,
            model: if coupled {
                ColumnModel::Coupled
            } else {
                ColumnModel::Decoupled
            },
            modes: Some(modes as usize),
            mode_shapes: match self.galerkin.mode_shapes {
                ModeShapesDto::Exact => ModeShapes::Exact,
                ModeShapesDto::Paper => ModeShapes::Paper,
                ModeShapesDto::Approx => ModeShapes::Approx,
            },
            rotary_inertia: self.galerkin.rotary_inertia,
            initial_midpoint_displacement: self.initial_midpoint_displacement_m,
            end_time: self.end_time_s,
            output,
            max_samples: max_samples as usize,
            ..ColumnCase::default()
        })
    }
}

/// Mode-1 integrals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct ModeIntegralsDto {
    /// ∫φ².
    pub mass: f64,
    /// ∫φ′².
    pub rotary: f64,
    /// ∫φ″² (`paper`: the printed ∫φφ⁗).
    pub stiffness: f64,
}

/// Section properties of the column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct SectionDto {
    /// Area A, m².
    pub area_m2: f64,
    /// Second moment I, m⁴.
    pub second_moment_m4: f64,
    /// Mass per length μ, kg/m.
    pub mass_per_length_kg_m: f64,
    /// Rotary inertia per length J₀, kg·m.
    pub rotary_inertia_kg_m: f64,
    /// Bending stiffness EI, N·m².
    pub bending_stiffness_n_m2: f64,
}

/// Largest bending stresses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct StressDto {
    /// At the clamps, Pa.
    pub clamp: f64,
    /// At the midpoint, Pa.
    pub midpoint: f64,
}

/// Integrator report of the coupled model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct IntegratorDto {
    /// Accepted steps (of the last pass).
    pub steps: u64,
    /// Rejected steps (of the last pass).
    pub rejected_steps: u64,
    /// Relative tolerance (of the last pass).
    pub tolerance: f64,
    /// Estimated relative error at the end: the larger of the rock's energy balance relative to
    /// its kinetic energy and the column's balance (energy + dissipated = work of the contact
    /// force) relative to the transferred energy. Above 1e-5 the integrator refines, and
    /// warns (`integrator_error_above_target`) if it still is.
    pub estimated_error: f64,
}

/// Histories: equal-length arrays.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ColumnHistoryDto {
    /// Times, s.
    pub time_s: Vec<f64>,
    /// Midpoint deflection, m.
    pub midpoint_displacement_m: Vec<f64>,
    /// Column kinetic energy, J.
    pub kinetic_energy_j: Vec<f64>,
    /// Column strain energy, J.
    pub strain_energy_j: Vec<f64>,
    /// Energy dissipated by damping, ∫Cẇ²dt computed in its own right, J.
    pub dissipated_energy_j: Vec<f64>,
    /// Rock displacement towards the column (coupled), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rock_displacement_m: Option<Vec<f64>>,
    /// Rock kinetic energy (coupled), J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rock_kinetic_energy_j: Option<Vec<f64>>,
    /// Contact force (coupled), N.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_force_n: Option<Vec<f64>>,
    /// Energy stored in the contact (coupled), J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_energy_j: Option<Vec<f64>>,
}

impl From<ColumnHistory> for ColumnHistoryDto {
    fn from(h: ColumnHistory) -> Self {
        let (a, b, c, d) = match h.rock {
            Some(r) => (
                Some(r.rock_displacement),
                Some(r.rock_kinetic_energy),
                Some(r.contact_force),
                Some(r.contact_energy),
            ),
            None => (None, None, None, None),
        };
        Self {
            time_s: h.time,
            midpoint_displacement_m: h.midpoint_displacement,
            kinetic_energy_j: h.kinetic_energy,
            strain_energy_j: h.strain_energy,
            dissipated_energy_j: h.dissipated_energy,
            rock_displacement_m: a,
            rock_kinetic_energy_j: b,
            contact_force_n: c,
            contact_energy_j: d,
        }
    }
}

/// Result of a column calculation.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ColumnResponse {
    /// The model run.
    pub model: ColumnModelDto,
    /// Undamped natural frequencies, Hz (decoupled: mode 1).
    pub natural_frequencies_hz: Vec<f64>,
    /// Modal damping ratios ζᵢ = Cᵢᵢ/(2√(KᵢᵢMᵢᵢ)).
    pub damping_ratios: Vec<f64>,
    /// Damping coefficient c as used, N·s/m².
    pub damping_coefficient_n_s_m2: f64,
    /// Modal mass M₁, kg.
    pub modal_mass_kg: f64,
    /// Modal stiffness K₁, N/m.
    pub modal_stiffness_n_m: f64,
    /// Modal damping C₁, N·s/m.
    pub modal_damping_n_s_m: f64,
    /// φ₁(½).
    pub midpoint_mode_value: f64,
    /// Mode-1 integrals (`paper`: the printed constants).
    pub mode_integrals: ModeIntegralsDto,
    /// Envelope decay rate of mode 1, 1/s.
    pub decay_rate_1_s: f64,
    /// Time for mode 1 to fall to 1 % amplitude, s (null with a warning when undamped).
    pub decay_time_1pct_s: Option<f64>,
    /// Section properties.
    pub section: SectionDto,
    /// Midpoint stiffness K_mid = K₁/φ₁(½)², N/m.
    pub midpoint_stiffness_n_m: f64,
    /// Midpoint modal mass M_mid = M₁/φ₁(½)², kg.
    pub midpoint_mass_kg: f64,
    /// The rock's kinetic energy ½mv², J.
    pub kinetic_energy_j: f64,
    /// Largest bending stress σ = E_s·(D₁/2)·max|w″|, Pa.
    pub max_bending_stress_pa: StressDto,
    /// Largest stress / yield stress.
    pub stress_utilisation: f64,
    /// δmax of the rigid-column impact (decoupled), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_deformation_m: Option<f64>,
    /// Largest contact force: rigid-column Pmax (decoupled) or over all maxima of approach (coupled), N.
    pub max_force_n: f64,
    /// w₁(0) (decoupled), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub initial_modal_displacement_m: Option<f64>,
    /// Absorbed energy U₀ = ½K₁w₁(0)² (decoupled), J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub absorbed_energy_j: Option<f64>,
    /// Decoupled: U₀/KE; coupled: column energy at the first separation / KE.
    pub energy_ratio: f64,
    /// Largest approach over all maxima (coupled), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_contact_deformation_m: Option<f64>,
    /// max |w_mid| over the window (coupled), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_midpoint_displacement_m: Option<f64>,
    /// Number of contacts in the window (coupled).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact_count: Option<u32>,
    /// Duration of the first contact (coupled), s; null when it lasts past the window.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_contact_duration_s: Option<f64>,
    /// Rock velocity at the first separation, positive towards the column (coupled), m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rebound_velocity_m_s: Option<f64>,
    /// Column energy at the first separation (coupled), J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub column_energy_after_contact_j: Option<f64>,
    /// Rock velocity at the end of the window (coupled), m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rock_velocity_end_m_s: Option<f64>,
    /// Column energy at the end of the window (coupled), J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub column_energy_end_j: Option<f64>,
    /// Energy dissipated by the column's damping over the window (coupled), J.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_energy_j: Option<f64>,
    /// End of the window (coupled), s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end_time_s: Option<f64>,
    /// Integrator report (coupled).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integrator: Option<IntegratorDto>,
    /// Histories, when `output` asks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub history: Option<ColumnHistoryDto>,
    /// Named warnings. Besides the model's own (`energy_ratio_above_one`, `paper_damping`,
    /// `no_damping`, `decay_time_unrepresentable`, `integrator_error_above_target`,
    /// `contact_not_ended`), validity warnings with documented, strict thresholds:
    /// `contact_pressure_above_yield` (the contact pressure at the largest contact force >
    /// column.yield_stress_pa), `approach_above_tenth_of_radius` (the largest approach > 0.1 ×
    /// column.contact_radius_m), `stress_utilisation_above_one` (stress_utilisation > 1: the
    /// linear-elastic column yields).
    pub warnings: Vec<Warning>,
    /// Stages run or skipped.
    pub plan: Vec<PlanStep>,
    /// The fully resolved request.
    pub inputs: ColumnRequest,
    /// Version of the service and its models.
    pub model_version: String,
}

impl ColumnResponse {
    /// Builds the response from the calculation's report and the resolved request.
    pub fn new(report: Report<ColumnResult>, inputs: ColumnRequest) -> Self {
        let Report {
            result: r,
            plan,
            warnings,
        } = report;
        let meta = Meta::of(&plan, &warnings);
        let mut out = Self {
            model: inputs.model,
            natural_frequencies_hz: r.natural_frequencies_hz,
            damping_ratios: r.damping_ratios,
            damping_coefficient_n_s_m2: r.damping_coefficient,
            modal_mass_kg: r.modal_mass,
            modal_stiffness_n_m: r.modal_stiffness,
            modal_damping_n_s_m: r.modal_damping,
            midpoint_mode_value: r.midpoint_mode_value,
            mode_integrals: ModeIntegralsDto {
                mass: r.mode_integrals.mass,
                rotary: r.mode_integrals.rotary,
                stiffness: r.mode_integrals.stiffness,
            },
            decay_rate_1_s: r.decay_rate,
            decay_time_1pct_s: r.decay_time_1pct,
            section: SectionDto {
                area_m2: r.section.area,
                second_moment_m4: r.section.second_moment,
                mass_per_length_kg_m: r.section.mass_per_length,
                rotary_inertia_kg_m: r.section.rotary_inertia,
                bending_stiffness_n_m2: r.section.bending_stiffness,
            },
            midpoint_stiffness_n_m: r.midpoint_stiffness,
            midpoint_mass_kg: r.midpoint_mass,
            kinetic_energy_j: r.kinetic_energy,
            max_bending_stress_pa: StressDto {
                clamp: r.max_bending_stress.clamp,
                midpoint: r.max_bending_stress.midpoint,
            },
            stress_utilisation: r.stress_utilisation,
            max_deformation_m: None,
            max_force_n: 0.0,
            initial_modal_displacement_m: None,
            absorbed_energy_j: None,
            energy_ratio: 0.0,
            max_contact_deformation_m: None,
            max_midpoint_displacement_m: None,
            contact_count: None,
            first_contact_duration_s: None,
            rebound_velocity_m_s: None,
            column_energy_after_contact_j: None,
            rock_velocity_end_m_s: None,
            column_energy_end_j: None,
            damping_energy_j: None,
            end_time_s: None,
            integrator: None,
            history: r.history.map(Into::into),
            warnings: meta.warnings,
            plan: meta.plan,
            inputs,
            model_version: meta.model_version,
        };
        match r.detail {
            ColumnDetail::Decoupled(d) => {
                out.max_deformation_m = Some(d.max_deformation);
                out.max_force_n = d.max_force;
                out.initial_modal_displacement_m = Some(d.initial_modal_displacement);
                out.absorbed_energy_j = Some(d.absorbed_energy);
                out.energy_ratio = d.energy_ratio;
            }
            ColumnDetail::Coupled(c) => {
                out.max_force_n = c.max_force;
                out.max_contact_deformation_m = Some(c.max_contact_deformation);
                out.max_midpoint_displacement_m = Some(c.max_midpoint_displacement);
                out.contact_count = Some(c.contact_count);
                out.first_contact_duration_s = c.first_contact_duration;
                out.rebound_velocity_m_s = Some(c.rebound_velocity);
                out.column_energy_after_contact_j = Some(c.column_energy_after_contact);
                out.energy_ratio = c.energy_ratio;
                out.rock_velocity_end_m_s = Some(c.rock_velocity_end);
                out.column_energy_end_j = Some(c.column_energy_end);
                out.damping_energy_j = Some(c.damping_energy);
                out.end_time_s = Some(c.end_time);
                out.integrator = Some(IntegratorDto {
                    steps: c.steps,
                    rejected_steps: c.rejected_steps,
                    tolerance: c.tolerance,
                    estimated_error: c.estimated_error,
                });
            }
        }
        out
    }
}

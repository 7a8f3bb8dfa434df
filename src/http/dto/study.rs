//! `POST /v1/study`: request and response of parameter sweeps, sensitivity measures and energy
//! proportions (physics.md §D), and the ordered maps they are written in.

use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::column::{ColumnOutputDto, ColumnRequest};
use super::common::{PlanStep, Warning};
use crate::calc::study::{Output, Parameter};

/// The paper's swept parameters, in the canonical order of orderings (api.md).
pub const CANONICAL: [&str; 4] = [
    "velocity_m_s",
    "rock.side_length_m",
    "rock.density_kg_m3",
    "rock.elastic_modulus_pa",
];

/// A map that serializes its entries in insertion order (JSON object).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OrderedMap<V>(pub Vec<(String, V)>);

impl<V: Serialize> Serialize for OrderedMap<V> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// One swept parameter: a dotted path into the base column request and its range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct StudyParameterDto {
    /// Dotted path of a numeric field of the base request, e.g. `rock.density_kg_m3`.
    #[schema(example = "rock.density_kg_m3")]
    pub name: String,
    /// Lower end of the range, inside the field's own range.
    #[schema(example = 2000.0)]
    pub min: f64,
    /// Upper end of the range (> min), inside the field's own range.
    #[schema(example = 3000.0)]
    pub max: f64,
}

/// How the parameters are swept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum StudyGrid {
    /// One curve per parameter, the others at base.
    #[default]
    OneAtATime,
    /// The curves, plus a grid over every pair of parameters (the paper's Figures 12–20).
    Pairs,
}

/// The paper's study ranges (physics.md §D.1): each a ratio of 1.5.
#[must_use]
pub fn paper_parameters() -> Vec<StudyParameterDto> {
    crate::calc::study::PAPER_PARAMETERS
        .iter()
        .map(|&(p, min, max)| StudyParameterDto {
            name: paper_name(p).into(),
            min,
            max,
        })
        .collect()
}

/// The request field of a parameter of the paper's study (physics.md §D.1).
fn paper_name(p: Parameter) -> &'static str {
    match p {
        Parameter::Velocity => "velocity_m_s",
        Parameter::RockSideLength => "rock.side_length_m",
        Parameter::RockElasticModulus => "rock.elastic_modulus_pa",
        Parameter::RockDensity => "rock.density_kg_m3",
        _ => "",
    }
}

/// The paper's Figure 21 abscissae x = p/p_max: 2/3, 3/4, 5/6, 11/12, 1.
#[must_use]
pub fn paper_x_values() -> Vec<f64> {
    vec![2.0 / 3.0, 0.75, 5.0 / 6.0, 11.0 / 12.0, 1.0]
}

fn default_points() -> u32 {
    5
}

/// A parameter study over a base column request.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct StudyRequest {
    /// The base column request (default: the paper's base case); `output` must be null.
    pub base: ColumnRequest,
    /// Swept parameters, 1–16, distinct (default: the paper's v, L, E, ρ and ranges).
    #[schema(example = json!([{"name": "velocity_m_s", "min": 4.0, "max": 6.0}]))]
    pub parameters: Vec<StudyParameterDto>,
    /// Points per curve (and per grid axis), in [2, 101] (the limit is configurable).
    #[schema(default = 5, minimum = 2, maximum = 101, example = 5)]
    #[serde(default = "default_points")]
    pub points: u32,
    /// One-at-a-time curves, or curves plus pair grids.
    #[schema(default = "one_at_a_time", example = "one_at_a_time")]
    pub grid: StudyGrid,
    /// Numeric outputs of the column response for the base's model (default decoupled:
    /// max_deformation_m, max_force_n, absorbed_energy_j, energy_ratio; coupled:
    /// max_contact_deformation_m, max_force_n, column_energy_after_contact_j, energy_ratio).
    #[serde(
        skip_serializing_if = "Option::is_none",
        deserialize_with = "super::common::non_null"
    )]
    #[schema(example = json!(["max_force_n", "energy_ratio"]))]
    pub outputs: Option<Vec<String>>,
    /// Energy-proportion abscissae x = p/p_max, each in (0, 1] (default 2/3, 3/4, 5/6, 11/12, 1).
    #[schema(example = json!([0.6666666666666666, 0.75, 0.8333333333333334, 0.9166666666666666, 1.0]))]
    pub x_values: Vec<f64>,
}

impl Default for StudyRequest {
    fn default() -> Self {
        Self {
            base: ColumnRequest::default(),
            parameters: paper_parameters(),
            points: 5,
            grid: StudyGrid::OneAtATime,
            outputs: None,
            x_values: paper_x_values(),
        }
    }
}

/// The three sensitivity measures of one output to one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct MeasuresDto {
    /// Output at the parameter's min (others at base).
    pub low: f64,
    /// Output at the parameter's max.
    pub high: f64,
    /// |high − low| / |base output| (null when the base output is 0).
    pub span_over_base: Option<f64>,
    /// max/min of |high| and |low| (null when one is 0 or they differ in sign).
    pub ratio: Option<f64>,
    /// d ln y/d ln p at base: analytic for the log laws and Hertz (physics.md §D.2), else
    /// central differences with one Richardson step (null when undefined, with a warning).
    pub elasticity: Option<f64>,
}

/// Orderings of the parameters by each measure, largest |measure| first; a tie group is one
/// string joined by `=`.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct OrderingDto {
    /// By span over base.
    pub span_over_base: Vec<String>,
    /// By ratio.
    pub ratio: Vec<String>,
    /// By elasticity.
    pub elasticity: Vec<String>,
}

/// Sensitivity of one output.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct OutputSensitivityDto {
    /// The output at base.
    pub base: f64,
    /// Measures per parameter, in request order.
    #[schema(value_type = Object)]
    pub parameters: OrderedMap<MeasuresDto>,
    /// Orderings.
    pub ordering: OrderingDto,
}

/// One pair grid: rows follow `y_values`, columns `x_values`.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct StudyGridDto {
    /// Parameter along the columns.
    pub x: String,
    /// Parameter along the rows.
    pub y: String,
    /// Values of x.
    pub x_values: Vec<f64>,
    /// Values of y.
    pub y_values: Vec<f64>,
    /// `<output>`: `[[…], …]`, row `i` at `y_values[i]`.
    #[serde(flatten)]
    #[schema(value_type = Object)]
    pub outputs: OrderedMap<Vec<Vec<f64>>>,
}

/// Warning code: an energy-proportion point x·max of a parameter is not a valid column request
/// (e.g. an outer diameter at or below the inner one); its ratio is `null`.
pub const ENERGY_PROPORTION_UNDEFINED: &str = "energy_proportion_undefined";

/// Energy ratio against x = p/p_max, others at base (Figure 21, Table 5).
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct EnergyProportionDto {
    /// The column model of the ratio (decoupled U₀/KE, or coupled transfer at first separation).
    pub model: String,
    /// The abscissae.
    pub x: Vec<f64>,
    /// `<parameter>`: energy ratio at each x; `null` where x·max is not a valid column request
    /// (warning `energy_proportion_undefined`), and that parameter is left out of `orderings`
    /// there.
    #[schema(value_type = Object)]
    pub curves: OrderedMap<Vec<Option<f64>>>,
    /// `orderings[i]`: parameters by energy ratio at `x[i]`, highest first, ties joined by `=`
    /// (a parameter whose ratio is `null` there is not listed).
    pub orderings: Vec<Vec<String>>,
}

/// One ordering the paper states beside the one this study computes.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct PaperComparisonDto {
    /// Which figure or table and measure.
    pub item: String,
    /// The paper's statement.
    pub paper: String,
    /// This study's result in the same notation.
    pub ours: String,
    /// Whether they agree.
    pub reproduced: bool,
    /// Why (physics.md §D.3, §D.4).
    pub note: String,
}

/// Result of a study.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct StudyResponse {
    /// `<parameter>`: `{"values": […], "<output>": […]}`.
    #[schema(value_type = Object)]
    pub curves: OrderedMap<OrderedMap<Vec<f64>>>,
    /// Pair grids (with `grid: pairs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grids: Option<Vec<StudyGridDto>>,
    /// `<output>`: base value, measures per parameter, orderings.
    #[schema(value_type = Object)]
    pub sensitivity: OrderedMap<OutputSensitivityDto>,
    /// Figure 21 / Table 5.
    pub energy_proportion: EnergyProportionDto,
    /// The paper's orderings beside ours (when the parameters and ranges are the paper's).
    pub paper_comparison: Vec<PaperComparisonDto>,
    /// Named warnings: `elasticity_undefined` (p ± 1e-4·|p| not valid inputs, or the base value
    /// 0), `energy_proportion_undefined` (an x·max of a parameter is not a valid column request:
    /// that energy-proportion entry is `null`), `no_paper_comparison`, and those of the
    /// sensitivity measures.
    pub warnings: Vec<Warning>,
    /// Stages run or skipped.
    pub plan: Vec<PlanStep>,
    /// The fully resolved request (the base with every default filled in).
    pub inputs: StudyRequest,
    /// Version of the service and its models.
    pub model_version: String,
}

/// The column models a study output exists for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Models {
    /// Both models.
    Both,
    /// The decoupled model only.
    Decoupled,
    /// The coupled model only.
    Coupled,
}

/// Every study output, the models it exists for and the result it reads: numeric fields the
/// column response always has, in the order the error message lists them.
const OUTPUTS: [(&str, Models, Output); 25] = [
    (
        "damping_coefficient_n_s_m2",
        Models::Both,
        Output::DampingCoefficient,
    ),
    ("modal_mass_kg", Models::Both, Output::ModalMass),
    ("modal_stiffness_n_m", Models::Both, Output::ModalStiffness),
    ("modal_damping_n_s_m", Models::Both, Output::ModalDamping),
    (
        "midpoint_mode_value",
        Models::Both,
        Output::MidpointModeValue,
    ),
    ("decay_rate_1_s", Models::Both, Output::DecayRate),
    (
        "midpoint_stiffness_n_m",
        Models::Both,
        Output::MidpointStiffness,
    ),
    ("midpoint_mass_kg", Models::Both, Output::MidpointMass),
    ("kinetic_energy_j", Models::Both, Output::KineticEnergy),
    (
        "stress_utilisation",
        Models::Both,
        Output::StressUtilisation,
    ),
    ("max_force_n", Models::Both, Output::MaxForce),
    ("energy_ratio", Models::Both, Output::EnergyRatio),
    (
        "max_bending_stress_pa.clamp",
        Models::Both,
        Output::ClampStress,
    ),
    (
        "max_bending_stress_pa.midpoint",
        Models::Both,
        Output::MidpointStress,
    ),
    (
        "max_deformation_m",
        Models::Decoupled,
        Output::MaxDeformation,
    ),
    (
        "initial_modal_displacement_m",
        Models::Decoupled,
        Output::InitialModalDisplacement,
    ),
    (
        "absorbed_energy_j",
        Models::Decoupled,
        Output::AbsorbedEnergy,
    ),
    (
        "max_contact_deformation_m",
        Models::Coupled,
        Output::MaxContactDeformation,
    ),
    (
        "max_midpoint_displacement_m",
        Models::Coupled,
        Output::MaxMidpointDisplacement,
    ),
    ("contact_count", Models::Coupled, Output::ContactCount),
    (
        "rebound_velocity_m_s",
        Models::Coupled,
        Output::ReboundVelocity,
    ),
    (
        "column_energy_after_contact_j",
        Models::Coupled,
        Output::ColumnEnergyAfterContact,
    ),
    (
        "rock_velocity_end_m_s",
        Models::Coupled,
        Output::RockVelocityEnd,
    ),
    (
        "column_energy_end_j",
        Models::Coupled,
        Output::ColumnEnergyEnd,
    ),
    ("damping_energy_j", Models::Coupled, Output::DampingEnergy),
];

/// The result a study output (a name of [`study_outputs`]) reads.
#[must_use]
pub fn output_of(name: &str) -> Option<Output> {
    OUTPUTS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, _, o)| *o)
}

/// Outputs a study may ask for, by model: numeric fields the column response always has.
#[must_use]
pub fn study_outputs(coupled: bool) -> Vec<&'static str> {
    let own = if coupled {
        Models::Coupled
    } else {
        Models::Decoupled
    };
    OUTPUTS
        .iter()
        .filter(|(_, m, _)| *m == Models::Both || *m == own)
        .map(|(name, _, _)| *name)
        .collect()
}

/// The default outputs of a model (api.md).
#[must_use]
pub fn default_outputs(coupled: bool) -> Vec<String> {
    let v: [&str; 4] = if coupled {
        [
            "max_contact_deformation_m",
            "max_force_n",
            "column_energy_after_contact_j",
            "energy_ratio",
        ]
    } else {
        [
            "max_deformation_m",
            "max_force_n",
            "absorbed_energy_j",
            "energy_ratio",
        ]
    };
    v.iter().map(|s| (*s).to_string()).collect()
}

/// JSON Pointer of a dotted path (`rock.density_kg_m3` → `/rock/density_kg_m3`).
#[must_use]
pub fn pointer_of(dotted: &str) -> String {
    dotted
        .split('.')
        .map(|s| format!("/{}", s.replace('~', "~0").replace('/', "~1")))
        .collect()
}

/// Sets `x` at `pointer` in `v`, creating objects on the way (arrays must exist).
pub fn set_pointer(v: &mut Value, pointer: &str, x: f64) -> bool {
    let mut cur = v;
    let segs: Vec<String> = pointer
        .split('/')
        .skip(1)
        .map(|s| s.replace("~1", "/").replace("~0", "~"))
        .collect();
    for (k, seg) in segs.iter().enumerate() {
        let last = k + 1 == segs.len();
        cur = match cur {
            Value::Object(m) => {
                if last {
                    m.insert(seg.clone(), json!(x));
                    return true;
                }
                m.entry(seg.clone()).or_insert_with(|| json!({}))
            }
            Value::Array(a) => match seg.parse::<usize>().ok().and_then(|i| a.get_mut(i)) {
                Some(e) => {
                    if last {
                        *e = json!(x);
                        return true;
                    }
                    e
                }
                None => return false,
            },
            _ => return false,
        };
    }
    false
}

/// A numeric field of the column request a study parameter names (its dotted path), as the
/// request's own fields: set on a request it is checked by the request's resolution, and it
/// maps to the [`Parameter`] of the case it sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SweptField {
    /// `velocity_m_s`.
    Velocity,
    /// `rock.side_length_m`.
    RockSideLength,
    /// `rock.radius_m`.
    RockRadius,
    /// `rock.dimensions_m.i` (of a base that gives them).
    RockDimension(usize),
    /// `rock.vertices_m.i.j` (of a base that gives them).
    RockVertex(usize, usize),
    /// `rock.random.semi_axes_m.i` (of a base that gives them).
    RockRandomSemiAxis(usize),
    /// `rock.density_kg_m3`.
    RockDensity,
    /// `rock.elastic_modulus_pa`.
    RockElasticModulus,
    /// `rock.poisson_ratio`.
    RockPoissonRatio,
    /// `rock.corner_radius_m`.
    RockCornerRadius,
    /// `column.outer_diameter_m`.
    ColumnOuterDiameter,
    /// `column.inner_diameter_m`.
    ColumnInnerDiameter,
    /// `column.length_m`.
    ColumnLength,
    /// `column.elastic_modulus_pa`.
    ColumnElasticModulus,
    /// `column.poisson_ratio`.
    ColumnPoissonRatio,
    /// `column.density_kg_m3`.
    ColumnDensity,
    /// `column.yield_stress_pa`.
    ColumnYieldStress,
    /// `column.contact_radius_m`.
    ColumnContactRadius,
    /// `column.damping_coefficient_n_s_m2`.
    ColumnDampingCoefficient,
    /// `column.damping_ratio`.
    ColumnDampingRatio,
    /// `initial_midpoint_displacement_m`.
    InitialMidpointDisplacement,
    /// `end_time_s`.
    EndTime,
    /// `output.duration_s`.
    HistoryDuration,
}

impl SweptField {
    /// The field a study parameter's dotted path `name` sets in the base request `sent` (as
    /// sent, `sent_json` its JSON); `None` when the path does not name a numeric field of that
    /// request (its refusal is the request's own: see the route).
    #[must_use]
    pub fn of(name: &str, sent: &ColumnRequest, sent_json: &Value) -> Option<Self> {
        let mut probe = sent_json.clone();
        // a path through a number, string or boolean of the request, or past the end of one
        // of its arrays, sets nothing: refused as no numeric field
        if !set_pointer(&mut probe, &pointer_of(name), 0.0) {
            return None;
        }
        let segs: Vec<&str> = name.split('.').collect();
        let index = |s: &str| s.parse::<usize>().ok();
        let rock = &sent.rock;
        Some(match segs.as_slice() {
            ["velocity_m_s"] => Self::Velocity,
            ["rock", "side_length_m"] => Self::RockSideLength,
            ["rock", "radius_m"] => Self::RockRadius,
            ["rock", "dimensions_m", i] if rock.dimensions_m.is_some() => {
                Self::RockDimension(index(i)?)
            }
            ["rock", "vertices_m", i, j] if rock.vertices_m.is_some() => {
                Self::RockVertex(index(i)?, index(j)?)
            }
            ["rock", "random", "semi_axes_m", i] if rock.random.is_some() => {
                Self::RockRandomSemiAxis(index(i)?)
            }
            ["rock", "density_kg_m3"] => Self::RockDensity,
            ["rock", "elastic_modulus_pa"] => Self::RockElasticModulus,
            ["rock", "poisson_ratio"] => Self::RockPoissonRatio,
            ["rock", "corner_radius_m"] => Self::RockCornerRadius,
            ["column", "outer_diameter_m"] => Self::ColumnOuterDiameter,
            ["column", "inner_diameter_m"] => Self::ColumnInnerDiameter,
            ["column", "length_m"] => Self::ColumnLength,
            ["column", "elastic_modulus_pa"] => Self::ColumnElasticModulus,
            ["column", "poisson_ratio"] => Self::ColumnPoissonRatio,
            ["column", "density_kg_m3"] => Self::ColumnDensity,
            ["column", "yield_stress_pa"] => Self::ColumnYieldStress,
            ["column", "contact_radius_m"] => Self::ColumnContactRadius,
            ["column", "damping_coefficient_n_s_m2"] => Self::ColumnDampingCoefficient,
            ["column", "damping_ratio"] => Self::ColumnDampingRatio,
            ["initial_midpoint_displacement_m"] => Self::InitialMidpointDisplacement,
            ["end_time_s"] => Self::EndTime,
            ["output", "duration_s"] if sent.output.is_none() => Self::HistoryDuration,
            _ => return None,
        })
    }

    /// Sets the field to `x` in `req` (a request as sent: its resolution checks it).
    pub fn set(self, req: &mut ColumnRequest, x: f64) {
        let (rock, column) = (&mut req.rock, &mut req.column);
        match self {
            Self::Velocity => req.velocity_m_s = x,
            Self::RockSideLength => rock.side_length_m = x,
            Self::RockRadius => rock.radius_m = Some(x),
            Self::RockDimension(i) => {
                if let Some(v) = rock.dimensions_m.as_mut().and_then(|d| d.get_mut(i)) {
                    *v = x;
                }
            }
            Self::RockVertex(i, j) => {
                if let Some(v) = rock
                    .vertices_m
                    .as_mut()
                    .and_then(|v| v.get_mut(i))
                    .and_then(|p| p.get_mut(j))
                {
                    *v = x;
                }
            }
            Self::RockRandomSemiAxis(i) => {
                if let Some(v) = rock.random.as_mut().and_then(|r| r.semi_axes_m.get_mut(i)) {
                    *v = x;
                }
            }
            Self::RockDensity => rock.density_kg_m3 = x,
            Self::RockElasticModulus => rock.elastic_modulus_pa = x,
            Self::RockPoissonRatio => rock.poisson_ratio = x,
            Self::RockCornerRadius => rock.corner_radius_m = Some(x),
            Self::ColumnOuterDiameter => column.outer_diameter_m = x,
            Self::ColumnInnerDiameter => column.inner_diameter_m = x,
            Self::ColumnLength => column.length_m = x,
            Self::ColumnElasticModulus => column.elastic_modulus_pa = x,
            Self::ColumnPoissonRatio => column.poisson_ratio = x,
            Self::ColumnDensity => column.density_kg_m3 = x,
            Self::ColumnYieldStress => column.yield_stress_pa = x,
            Self::ColumnContactRadius => column.contact_radius_m = Some(x),
            Self::ColumnDampingCoefficient => column.damping_coefficient_n_s_m2 = Some(x),
            Self::ColumnDampingRatio => column.damping_ratio = Some(x),
            Self::InitialMidpointDisplacement => req.initial_midpoint_displacement_m = Some(x),
            Self::EndTime => req.end_time_s = Some(x),
            Self::HistoryDuration => {
                req.output
                    .get_or_insert_with(ColumnOutputDto::default)
                    .duration_s = Some(x);
            }
        }
    }

    /// The base value of the parameter `name` setting this field in `req` (the resolved base),
    /// if it has one. As a JSON Pointer reads it: an array index written with a sign or a
    /// leading zero (which the sweep sets) reads nothing.
    #[must_use]
    pub fn base(self, name: &str, req: &ColumnRequest) -> Option<f64> {
        let canonical = |s: &str| !(s.starts_with('+') || (s.starts_with('0') && s.len() != 1));
        let indexed = matches!(
            self,
            Self::RockDimension(_) | Self::RockVertex(..) | Self::RockRandomSemiAxis(_)
        );
        if indexed && !name.split('.').skip(2).all(canonical) {
            return None;
        }
        self.get(req)
    }

    /// The field's value in `req`, if it has one.
    #[must_use]
    pub fn get(self, req: &ColumnRequest) -> Option<f64> {
        let (rock, column) = (&req.rock, &req.column);
        match self {
            Self::Velocity => Some(req.velocity_m_s),
            Self::RockSideLength => Some(rock.side_length_m),
            Self::RockRadius => rock.radius_m,
            Self::RockDimension(i) => rock.dimensions_m.and_then(|d| d.get(i).copied()),
            Self::RockVertex(i, j) => rock
                .vertices_m
                .as_ref()
                .and_then(|v| v.get(i))
                .and_then(|p| p.get(j).copied()),
            Self::RockRandomSemiAxis(i) => rock
                .random
                .as_ref()
                .and_then(|r| r.semi_axes_m.get(i).copied()),
            Self::RockDensity => Some(rock.density_kg_m3),
            Self::RockElasticModulus => Some(rock.elastic_modulus_pa),
            Self::RockPoissonRatio => Some(rock.poisson_ratio),
            Self::RockCornerRadius => rock.corner_radius_m,
            Self::ColumnOuterDiameter => Some(column.outer_diameter_m),
            Self::ColumnInnerDiameter => Some(column.inner_diameter_m),
            Self::ColumnLength => Some(column.length_m),
            Self::ColumnElasticModulus => Some(column.elastic_modulus_pa),
            Self::ColumnPoissonRatio => Some(column.poisson_ratio),
            Self::ColumnDensity => Some(column.density_kg_m3),
            Self::ColumnYieldStress => Some(column.yield_stress_pa),
            Self::ColumnContactRadius => column.contact_radius_m,
            Self::ColumnDampingCoefficient => column.damping_coefficient_n_s_m2,
            Self::ColumnDampingRatio => column.damping_ratio,
            Self::InitialMidpointDisplacement => req.initial_midpoint_displacement_m,
            Self::EndTime => req.end_time_s,
            Self::HistoryDuration => req.output.as_ref().and_then(|o| o.duration_s),
        }
    }

    /// The quantity of the column case the field sets.
    #[must_use]
    pub fn parameter(self) -> Parameter {
        match self {
            Self::Velocity => Parameter::Velocity,
            Self::RockSideLength => Parameter::RockSideLength,
            Self::RockRadius => Parameter::RockRadius,
            Self::RockDimension(_) | Self::RockVertex(..) | Self::RockRandomSemiAxis(_) => {
                Parameter::Unused
            }
            Self::RockDensity => Parameter::RockDensity,
            Self::RockElasticModulus => Parameter::RockElasticModulus,
            Self::RockPoissonRatio => Parameter::RockPoissonRatio,
            Self::RockCornerRadius => Parameter::RockCornerRadius,
            Self::ColumnOuterDiameter => Parameter::ColumnOuterDiameter,
            Self::ColumnInnerDiameter => Parameter::ColumnInnerDiameter,
            Self::ColumnLength => Parameter::ColumnLength,
            Self::ColumnElasticModulus => Parameter::ColumnElasticModulus,
            Self::ColumnPoissonRatio => Parameter::ColumnPoissonRatio,
            Self::ColumnDensity => Parameter::ColumnDensity,
            Self::ColumnYieldStress => Parameter::ColumnYieldStress,
            Self::ColumnContactRadius => Parameter::ColumnContactRadius,
            Self::ColumnDampingCoefficient => Parameter::ColumnDampingCoefficient,
            Self::ColumnDampingRatio => Parameter::ColumnDampingRatio,
            Self::InitialMidpointDisplacement => Parameter::InitialMidpointDisplacement,
            Self::EndTime => Parameter::EndTime,
            Self::HistoryDuration => Parameter::HistoryDuration,
        }
    }
}

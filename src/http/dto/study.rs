//! `POST /v1/study`: request and response of parameter sweeps, sensitivity measures and energy
//! proportions (physics.md §D), and the ordered maps they are written in.

use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::column::ColumnRequest;
use super::common::{PlanStep, Warning};

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
        .map(|&(n, min, max)| StudyParameterDto {
            name: n.into(),
            min,
            max,
        })
        .collect()
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
        deserialize_with = "super::common::some"
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

/// Every study output and the models it exists for: numeric fields the column response always
/// has, in the order the error message lists them.
const OUTPUTS: [(&str, Models); 25] = [
    ("damping_coefficient_n_s_m2", Models::Both),
    ("modal_mass_kg", Models::Both),
    ("modal_stiffness_n_m", Models::Both),
    ("modal_damping_n_s_m", Models::Both),
    ("midpoint_mode_value", Models::Both),
    ("decay_rate_1_s", Models::Both),
    ("midpoint_stiffness_n_m", Models::Both),
    ("midpoint_mass_kg", Models::Both),
    ("kinetic_energy_j", Models::Both),
    ("stress_utilisation", Models::Both),
    ("max_force_n", Models::Both),
    ("energy_ratio", Models::Both),
    ("max_bending_stress_pa.clamp", Models::Both),
    ("max_bending_stress_pa.midpoint", Models::Both),
    ("max_deformation_m", Models::Decoupled),
    ("initial_modal_displacement_m", Models::Decoupled),
    ("absorbed_energy_j", Models::Decoupled),
    ("max_contact_deformation_m", Models::Coupled),
    ("max_midpoint_displacement_m", Models::Coupled),
    ("contact_count", Models::Coupled),
    ("rebound_velocity_m_s", Models::Coupled),
    ("column_energy_after_contact_j", Models::Coupled),
    ("rock_velocity_end_m_s", Models::Coupled),
    ("column_energy_end_j", Models::Coupled),
    ("damping_energy_j", Models::Coupled),
];

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
        .filter(|(_, m)| *m == Models::Both || *m == own)
        .map(|(name, _)| *name)
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

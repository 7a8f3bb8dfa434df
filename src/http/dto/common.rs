//! Shared request objects (`rock`, `column`, `contact`), range checks and response metadata.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use crate::http::error::{ApiError, FieldError};
use crate::physics::material::{
    Column, ContactLaw, ContactModel, Damping, ModulusConvention, Rock, RockShape,
};

/// The crate version, reported as `model_version` in every result.
pub const MODEL_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Deserializes an optional field that may be omitted but not sent as `null` (api.md: only fields
/// shown with a null default accept null). Use with `#[serde(default, deserialize_with = "some")]`.
pub fn some<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    T::deserialize(d).map(Some)
}

/// Collects range errors so that one answer names every bad field.
#[derive(Debug, Default)]
pub struct Checker {
    errors: Vec<FieldError>,
}

/// Bound of an interval: closed or open.
#[derive(Debug, Clone, Copy)]
pub enum Bound {
    /// Value included.
    Closed(f64),
    /// Value excluded.
    Open(f64),
}

fn fmt_num(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

impl Checker {
    /// A fresh checker.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records an error on `field` (a JSON Pointer).
    pub fn push(&mut self, field: impl Into<String>, value: Value, message: impl Into<String>) {
        self.errors.push(FieldError {
            field: field.into(),
            value,
            message: message.into(),
        });
    }

    /// Checks `lo ⋈ v ⋈ hi` (finite), with `unit` appended to the message.
    pub fn range(&mut self, field: &str, v: f64, lo: Bound, hi: Bound, unit: &str) -> bool {
        let ok_lo = match lo {
            Bound::Closed(a) => v >= a,
            Bound::Open(a) => v > a,
        };
        let ok_hi = match hi {
            Bound::Closed(b) => v <= b,
            Bound::Open(b) => v < b,
        };
        let ok = v.is_finite() && ok_lo && ok_hi;
        if !ok {
            let (l, lb) = match lo {
                Bound::Closed(a) => ('[', a),
                Bound::Open(a) => ('(', a),
            };
            let (h, hb) = match hi {
                Bound::Closed(b) => (']', b),
                Bound::Open(b) => (')', b),
            };
            let unit = if unit.is_empty() {
                String::new()
            } else {
                format!(" {unit}")
            };
            self.push(
                field,
                crate::http::error::num(v),
                format!("must be in {l}{}, {}{h}{unit}", fmt_num(lb), fmt_num(hb)),
            );
        }
        ok
    }

    /// Closed interval [lo, hi].
    pub fn closed(&mut self, field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> bool {
        self.range(field, v, Bound::Closed(lo), Bound::Closed(hi), unit)
    }

    /// Half-open interval (lo, hi].
    pub fn open_closed(&mut self, field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> bool {
        self.range(field, v, Bound::Open(lo), Bound::Closed(hi), unit)
    }

    /// Half-open interval [lo, hi).
    pub fn closed_open(&mut self, field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> bool {
        self.range(field, v, Bound::Closed(lo), Bound::Open(hi), unit)
    }

    /// Integer count in [lo, hi].
    pub fn count(&mut self, field: &str, v: u64, lo: u64, hi: u64, what: &str) -> bool {
        let ok = (lo..=hi).contains(&v);
        if !ok {
            self.push(field, json!(v), format!("must be in [{lo}, {hi}] {what}"));
        }
        ok
    }

    /// True when no error was recorded.
    pub fn is_ok(&self) -> bool {
        self.errors.is_empty()
    }

    /// `Ok(())` or a 422 `invalid_input` listing every recorded error.
    pub fn finish(self) -> Result<(), ApiError> {
        if self.errors.is_empty() {
            Ok(())
        } else {
            Err(ApiError::from_field_errors("invalid_input", self.errors))
        }
    }
}

/// Shape of the rock block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// Cube of side `side_length_m` (everywhere).
    #[default]
    Cube,
    /// Sphere of `radius_m` (migration; impact with `hertz_point` only).
    Sphere,
    /// Cuboid with edges `dimensions_m` (migration).
    Cuboid,
    /// Convex hull of `vertices_m` (rigid-block migration).
    Polyhedron,
    /// Random polyhedron by the ellipsoid method (rigid-block migration).
    RandomPolyhedron,
}

/// Parameters of a random polyhedron by the ellipsoid method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RandomShapeDto {
    /// Semi-axes of the ellipsoid [a, b, c], m, each in [0.005, 2.5].
    #[schema(example = json!([0.2, 0.15, 0.1]))]
    pub semi_axes_m: [f64; 3],
    /// Number of points drawn on the ellipsoid.
    #[schema(default = 20, minimum = 4, maximum = 1000, example = 20)]
    #[serde(default = "default_random_vertices")]
    pub vertices: u32,
    /// Seed of the shape generator.
    #[serde(default = "default_random_seed")]
    #[schema(default = 1, example = 1)]
    pub seed: u64,
}

fn default_random_vertices() -> u32 {
    20
}
fn default_random_seed() -> u64 {
    1
}

/// The falling rock block (paper Table 2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RockDto {
    /// Shape of the block.
    #[schema(default = "cube", example = "cube")]
    pub shape: ShapeKind,
    /// Cube side L, m; also the contact length on the column.
    #[schema(default = 0.3, minimum = 0.01, maximum = 5.0, example = 0.3)]
    pub side_length_m: f64,
    /// Sphere radius, m (default side_length_m / 2).
    #[schema(minimum = 0.005, maximum = 2.5, example = 0.15)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "some"
    )]
    pub radius_m: Option<f64>,
    /// Cuboid edges [a, b, c], m, each in [0.01, 5].
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "some"
    )]
    #[schema(example = json!([0.4, 0.3, 0.2]))]
    pub dimensions_m: Option<[f64; 3]>,
    /// Convex polyhedron vertices (4–1000 points [x, y, z], each coordinate in [-10, 10]), m.
    #[schema(example = json!([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.3]]))]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "some"
    )]
    pub vertices_m: Option<Vec<[f64; 3]>>,
    /// Random polyhedron parameters.
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "some"
    )]
    pub random: Option<RandomShapeDto>,
    /// Density ρ, kg/m³.
    #[schema(default = 2500.0, minimum = 100.0, maximum = 20000.0, example = 2500.0)]
    pub density_kg_m3: f64,
    /// Young's modulus E, Pa.
    #[schema(default = 5e9, minimum = 1e7, maximum = 1e12, example = 5e9)]
    pub elastic_modulus_pa: f64,
    /// Poisson ratio ν, in [0, 0.5).
    #[schema(default = 0.28, minimum = 0.0, exclusive_maximum = 0.5, example = 0.28)]
    pub poisson_ratio: f64,
    /// Rounded-corner radius r_c of `hertz_point`, m, in (0, 2.5]; where used (`hertz_point`, not a
    /// sphere) also at most L/2 = side_length_m/2 (default min(0.02, L/2)).
    #[schema(exclusive_minimum = 0.0, maximum = 2.5, example = 0.02)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "some"
    )]
    pub corner_radius_m: Option<f64>,
}

impl Default for RockDto {
    fn default() -> Self {
        Self {
            shape: ShapeKind::Cube,
            side_length_m: 0.3,
            radius_m: None,
            dimensions_m: None,
            vertices_m: None,
            random: None,
            density_kg_m3: 2500.0,
            elastic_modulus_pa: 5e9,
            poisson_ratio: 0.28,
            corner_radius_m: None,
        }
    }
}

impl RockDto {
    /// Checks ranges (under `base`, a JSON Pointer prefix), fills derived defaults, and converts.
    /// `corner_needed`: whether the Hertz corner radius is used (checked only then).
    pub fn resolve(&mut self, base: &str, corner_needed: bool, ck: &mut Checker) -> Rock {
        let p = |f: &str| format!("{base}/{f}");
        ck.closed(&p("side_length_m"), self.side_length_m, 0.01, 5.0, "m");
        ck.closed(
            &p("density_kg_m3"),
            self.density_kg_m3,
            100.0,
            20000.0,
            "kg/m³",
        );
        ck.closed(
            &p("elastic_modulus_pa"),
            self.elastic_modulus_pa,
            1e7,
            1e12,
            "Pa",
        );
        ck.closed_open(&p("poisson_ratio"), self.poisson_ratio, 0.0, 0.5, "");
        let l = self.side_length_m;
        // Every field that is sent is checked against its own range, whether the shape uses it
        // or not; rules relating two fields (r_c ≤ L/2) apply only where the field is used.
        if let Some(r) = self.radius_m {
            ck.closed(&p("radius_m"), r, 0.005, 2.5, "m");
        }
        if let Some(d) = self.dimensions_m {
            for (i, v) in d.iter().enumerate() {
                ck.closed(&p(&format!("dimensions_m/{i}")), *v, 0.01, 5.0, "m");
            }
        }
        if let Some(v) = &self.vertices_m {
            if !(4..=1000).contains(&v.len()) {
                ck.push(
                    p("vertices_m"),
                    json!(v),
                    format!("must hold 4 to 1000 points; {} were sent", v.len()),
                );
            }
            if let Some((i, j, c)) = v.iter().enumerate().find_map(|(i, pt)| {
                pt.iter()
                    .enumerate()
                    .find(|(_, c)| !c.is_finite() || c.abs() > 10.0)
                    .map(|(j, c)| (i, j, *c))
            }) {
                ck.closed(&p(&format!("vertices_m/{i}/{j}")), c, -10.0, 10.0, "m");
            }
        }
        if let Some(r) = &self.random {
            for (i, v) in r.semi_axes_m.iter().enumerate() {
                ck.closed(&p(&format!("random/semi_axes_m/{i}")), *v, 0.005, 2.5, "m");
            }
            ck.count(
                &p("random/vertices"),
                u64::from(r.vertices),
                4,
                1000,
                "points",
            );
        }
        if let Some(rc) = self.corner_radius_m {
            ck.range(
                &p("corner_radius_m"),
                rc,
                Bound::Open(0.0),
                Bound::Closed(2.5),
                "m",
            );
        }
        let shape = match self.shape {
            ShapeKind::Cube => RockShape::Cube,
            ShapeKind::Sphere => {
                let r = *self.radius_m.get_or_insert(l / 2.0);
                RockShape::Sphere { radius: r }
            }
            ShapeKind::Cuboid => match self.dimensions_m {
                Some(d) => RockShape::Cuboid { dimensions: d },
                None => {
                    ck.push(
                        p("dimensions_m"),
                        Value::Null,
                        "a cuboid needs dimensions_m [a, b, c] in m",
                    );
                    RockShape::Cube
                }
            },
            ShapeKind::Polyhedron => match &self.vertices_m {
                Some(v) => RockShape::Polyhedron {
                    vertices: v.clone(),
                },
                None => {
                    ck.push(
                        p("vertices_m"),
                        Value::Null,
                        "a polyhedron needs vertices_m (4 to 1000 points, m)",
                    );
                    RockShape::Cube
                }
            },
            ShapeKind::RandomPolyhedron => match &self.random {
                Some(r) => RockShape::RandomPolyhedron {
                    semi_axes: r.semi_axes_m,
                    vertices: r.vertices as usize,
                    seed: r.seed,
                },
                None => {
                    ck.push(
                        p("random"),
                        Value::Null,
                        "a random polyhedron needs `random` {semi_axes_m, vertices, seed}",
                    );
                    RockShape::Cube
                }
            },
        };
        let corner = match shape {
            RockShape::Sphere { radius } => radius,
            _ => *self.corner_radius_m.get_or_insert(0.02f64.min(l / 2.0)),
        };
        if corner_needed && !matches!(shape, RockShape::Sphere { .. }) {
            ck.range(
                &p("corner_radius_m"),
                corner,
                Bound::Open(0.0),
                Bound::Closed(l / 2.0),
                "m (0 < r_c ≤ L/2)",
            );
        }
        Rock {
            shape,
            side_length: l,
            density: self.density_kg_m3,
            elastic_modulus: self.elastic_modulus_pa,
            poisson_ratio: self.poisson_ratio,
            corner_radius: corner,
        }
    }
}

/// The struck hydraulic-support column: clamped–clamped tube (paper Table 4, first stage).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ColumnDto {
    /// Outer diameter D₁, m.
    #[schema(default = 0.25, minimum = 0.01, maximum = 2.0, example = 0.25)]
    pub outer_diameter_m: f64,
    /// Inner diameter D₂, m, in [0, D₁) (0 = solid).
    #[schema(default = 0.235, minimum = 0.0, maximum = 2.0, example = 0.235)]
    pub inner_diameter_m: f64,
    /// Length between the clamps l, m; at least the contact length L of a cube.
    #[schema(default = 1.31, minimum = 0.1, maximum = 20.0, example = 1.31)]
    pub length_m: f64,
    /// Young's modulus E_s, Pa.
    #[schema(default = 208e9, minimum = 1e9, maximum = 1e12, example = 208e9)]
    pub elastic_modulus_pa: f64,
    /// Poisson ratio ν_s, in [0, 0.5).
    #[schema(default = 0.3, minimum = 0.0, exclusive_maximum = 0.5, example = 0.3)]
    pub poisson_ratio: f64,
    /// Density ρ_s, kg/m³.
    #[schema(default = 7850.0, minimum = 100.0, maximum = 20000.0, example = 7850.0)]
    pub density_kg_m3: f64,
    /// Yield stress, Pa (16Mn steel), for the stress utilisation.
    #[schema(
        default = 345e6,
        exclusive_minimum = 0.0,
        maximum = 1e10,
        example = 345e6
    )]
    pub yield_stress_pa: f64,
    /// Radius R of the cylinder at the contact, m (default D₁/2).
    #[schema(minimum = 0.001, maximum = 10.0, example = 0.125)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "some"
    )]
    pub contact_radius_m: Option<f64>,
    /// Viscous damping per unit length c, N·s/m² (default 1.0, the paper's value).
    #[schema(default = 1.0, minimum = 0.0, maximum = 1e9, example = 1.0)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "some"
    )]
    pub damping_coefficient_n_s_m2: Option<f64>,
    /// Damping ratio ζ₁ of mode 1 instead of c (recommended 0.02); giving both is 422.
    #[schema(minimum = 0.0, maximum = 10.0, example = 0.02)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_ratio: Option<f64>,
}

impl Default for ColumnDto {
    fn default() -> Self {
        Self {
            outer_diameter_m: 0.25,
            inner_diameter_m: 0.235,
            length_m: 1.31,
            elastic_modulus_pa: 208e9,
            poisson_ratio: 0.3,
            density_kg_m3: 7850.0,
            yield_stress_pa: 345e6,
            contact_radius_m: None,
            damping_coefficient_n_s_m2: None,
            damping_ratio: None,
        }
    }
}

impl ColumnDto {
    /// Checks ranges (under `base`), fills derived defaults, and converts.
    pub fn resolve(&mut self, base: &str, ck: &mut Checker) -> Column {
        let p = |f: &str| format!("{base}/{f}");
        let d1 = self.outer_diameter_m;
        ck.closed(&p("outer_diameter_m"), d1, 0.01, 2.0, "m");
        ck.closed_open(
            &p("inner_diameter_m"),
            self.inner_diameter_m,
            0.0,
            d1,
            "m (0 ≤ D₂ < D₁)",
        );
        ck.closed(&p("length_m"), self.length_m, 0.1, 20.0, "m");
        ck.closed(
            &p("elastic_modulus_pa"),
            self.elastic_modulus_pa,
            1e9,
            1e12,
            "Pa",
        );
        ck.closed_open(&p("poisson_ratio"), self.poisson_ratio, 0.0, 0.5, "");
        ck.closed(
            &p("density_kg_m3"),
            self.density_kg_m3,
            100.0,
            20000.0,
            "kg/m³",
        );
        ck.open_closed(&p("yield_stress_pa"), self.yield_stress_pa, 0.0, 1e10, "Pa");
        let r = *self.contact_radius_m.get_or_insert(d1 / 2.0);
        ck.closed(&p("contact_radius_m"), r, 0.001, 10.0, "m");
        let damping = match (self.damping_coefficient_n_s_m2, self.damping_ratio) {
            (Some(c), Some(z)) => {
                ck.push(
                    p("damping_ratio"),
                    crate::http::error::num(z),
                    format!(
                        "give either damping_coefficient_n_s_m2 ({c}) or damping_ratio, not both"
                    ),
                );
                Damping::Coefficient(c)
            }
            (None, Some(z)) => {
                ck.closed(&p("damping_ratio"), z, 0.0, 10.0, "");
                Damping::Ratio(z)
            }
            (c, None) => {
                let c = *self
                    .damping_coefficient_n_s_m2
                    .get_or_insert(c.unwrap_or(1.0));
                ck.closed(&p("damping_coefficient_n_s_m2"), c, 0.0, 1e9, "N·s/m²");
                Damping::Coefficient(c)
            }
        };
        Column {
            outer_diameter: d1,
            inner_diameter: self.inner_diameter_m,
            length: self.length_m,
            elastic_modulus: self.elastic_modulus_pa,
            poisson_ratio: self.poisson_ratio,
            density: self.density_kg_m3,
            yield_stress: self.yield_stress_pa,
            contact_radius: r,
            damping,
        }
    }
}

/// Force–approach law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum LawDto {
    /// The paper's logarithmic line contact (physics.md §A.3), W₋₁ branch.
    #[default]
    Paper,
    /// Johnson's cylinder compliance (recommended).
    Johnson,
    /// Hertz point contact of a rounded corner.
    HertzPoint,
}

/// Effective-modulus convention.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum ModulusDto {
    /// E/(1 − ν²) of the rock only (the paper).
    #[default]
    Paper,
    /// 1/E* = (1 − ν²)/E + (1 − ν_s²)/E_s (recommended).
    TwoBody,
}

/// How the contact is modelled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ContactDto {
    /// Force–approach law.
    #[schema(default = "paper", example = "paper")]
    pub law: LawDto,
    /// Effective-modulus convention.
    #[schema(default = "paper", example = "paper")]
    pub effective_modulus: ModulusDto,
    /// Exact elliptical Hertz κ (`hertz_point`); false: the equivalent-radius form.
    #[schema(default = true, example = true)]
    pub hertz_exact: bool,
}

impl Default for ContactDto {
    fn default() -> Self {
        Self {
            law: LawDto::Paper,
            effective_modulus: ModulusDto::Paper,
            hertz_exact: true,
        }
    }
}

impl From<ContactDto> for ContactModel {
    fn from(c: ContactDto) -> Self {
        ContactModel {
            law: match c.law {
                LawDto::Paper => ContactLaw::Paper,
                LawDto::Johnson => ContactLaw::Johnson,
                LawDto::HertzPoint => ContactLaw::HertzPoint,
            },
            modulus: match c.effective_modulus {
                ModulusDto::Paper => ModulusConvention::Paper,
                ModulusDto::TwoBody => ModulusConvention::TwoBody,
            },
            hertz_exact: c.hertz_exact,
        }
    }
}

/// A named warning in a result.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct Warning {
    /// Machine-readable code, e.g. `energy_ratio_above_one`.
    pub code: String,
    /// What it means for the result.
    pub message: String,
}

impl Warning {
    /// A warning with the given code and message.
    pub fn new(code: &str, message: impl Into<String>) -> Self {
        Self {
            code: code.into(),
            message: message.into(),
        }
    }
}

impl From<crate::physics::validity::Warning> for Warning {
    fn from(w: crate::physics::validity::Warning) -> Self {
        Self {
            code: w.code.into(),
            message: w.message,
        }
    }
}

/// Whether a stage of the calculation ran.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum StageStatus {
    /// The stage was computed.
    Ran,
    /// The stage was not needed and not computed.
    Skipped,
}

/// One stage of the calculation plan.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct PlanStep {
    /// Stage name, e.g. `impact`, `curve`, `migration`.
    pub stage: String,
    /// Ran or skipped.
    pub status: StageStatus,
    /// Why it ran or was skipped.
    pub reason: String,
}

impl PlanStep {
    /// A stage that ran.
    pub fn ran(stage: &str, reason: impl Into<String>) -> Self {
        Self {
            stage: stage.into(),
            status: StageStatus::Ran,
            reason: reason.into(),
        }
    }

    /// A stage that was skipped.
    pub fn skipped(stage: &str, reason: impl Into<String>) -> Self {
        Self {
            stage: stage.into(),
            status: StageStatus::Skipped,
            reason: reason.into(),
        }
    }
}

/// Metadata every result carries: version, plan, warnings.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema, Default)]
pub struct Meta {
    /// Version of the service and its models.
    pub model_version: String,
    /// Stages run or skipped.
    pub plan: Vec<PlanStep>,
    /// Named warnings about the result.
    pub warnings: Vec<Warning>,
}

impl Meta {
    /// Metadata with the crate version and the given plan.
    pub fn new(plan: Vec<PlanStep>) -> Self {
        Self {
            model_version: MODEL_VERSION.into(),
            plan,
            warnings: Vec::new(),
        }
    }
}

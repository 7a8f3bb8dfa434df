//! Shared request objects (`rock`, `column`, `contact`), range checks and response metadata.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use crate::http::error::{ApiError, FieldError};
use crate::physics::material::defaults;
use crate::physics::material::{
    Column, ContactLaw, ContactModel, Damping, ModulusConvention, Rock, RockShape,
};

/// The crate version, reported as `model_version` in every result.
pub const MODEL_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Deserializes an optional field that may be omitted but not sent as `null` (api.md: only fields
/// shown with a null default accept null). Use with
/// `#[serde(default, deserialize_with = "non_null")]`.
pub fn non_null<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
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
    #[must_use]
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
    #[must_use]
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

/// The default of a request field, as the OpenAPI document shows it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FieldDefault {
    /// A fixed value, filled into `inputs` when the field is absent.
    Value(f64),
    /// Derived from other fields (the description says how); no `default` in the schema.
    Derived,
    /// `null`: the field is unused unless sent (the schema shows `"default": null`).
    Null,
    /// None: the field must be sent where it is used (a grid's spacing); no `default` in the
    /// schema.
    Required,
}

/// One numeric request field, written once: its description, default, documented interval,
/// unit and example. Validation ([`NumberField::check`]), the OpenAPI schema
/// ([`NumberField::schema`]), the DTO `Default`s and `/v1/presets` all read it.
#[derive(Debug, Clone, Copy)]
pub struct NumberField {
    /// The schema's description.
    pub description: &'static str,
    /// The default.
    pub default: FieldDefault,
    /// Lower end of the documented interval.
    pub lo: Bound,
    /// Upper end of the documented interval.
    pub hi: Bound,
    /// Unit named in range messages (empty for dimensionless).
    pub unit: &'static str,
    /// The schema's example.
    pub example: f64,
    /// Whether `null` is accepted (only fields with a `null` default, api.md).
    pub nullable: bool,
}

impl NumberField {
    /// The fixed default (the field's [`FieldDefault::Value`]).
    ///
    /// # Panics
    /// On a field without a fixed default (a programming error caught by the unit tests).
    #[track_caller]
    #[must_use]
    #[expect(
        clippy::panic,
        reason = "a const fn on constant fields: misuse fails the unit tests"
    )]
    pub const fn value(&self) -> f64 {
        match self.default {
            FieldDefault::Value(v) => v,
            _ => panic!("field without a fixed default"),
        }
    }

    /// Checks `v` against the documented interval, naming `field` (a JSON Pointer).
    pub fn check(&self, checker: &mut Checker, field: &str, v: f64) -> bool {
        checker.range(field, v, self.lo, self.hi, self.unit)
    }

    /// The OpenAPI schema of the field: number (double), description, default, example and the
    /// documented bounds.
    #[allow(deprecated)] // `example`: the document keeps the single example of its other fields
    #[must_use]
    pub fn schema(&self) -> utoipa::openapi::schema::Object {
        use utoipa::openapi::schema::{KnownFormat, ObjectBuilder, SchemaFormat, SchemaType, Type};
        let ty = if self.nullable {
            SchemaType::from_iter([Type::Number, Type::Null])
        } else {
            SchemaType::Type(Type::Number)
        };
        let mut b = ObjectBuilder::new()
            .schema_type(ty)
            .format(Some(SchemaFormat::KnownFormat(KnownFormat::Double)))
            .description(Some(self.description))
            .example(Some(json!(self.example)));
        b = match self.default {
            FieldDefault::Value(v) => b.default(Some(json!(v))),
            FieldDefault::Null => b.default(Some(Value::Null)),
            FieldDefault::Derived | FieldDefault::Required => b,
        };
        b = match self.lo {
            Bound::Closed(x) => b.minimum(Some(x)),
            Bound::Open(x) => b.exclusive_minimum(Some(x)),
        };
        b = match self.hi {
            Bound::Closed(x) => b.maximum(Some(x)),
            Bound::Open(x) => b.exclusive_maximum(Some(x)),
        };
        b.build()
    }
}

/// Declares a schema function per [`NumberField`] for `#[schema(schema_with = …)]`.
macro_rules! number_schemas {
    ($($name:ident => $field:path;)*) => {
        $(
            #[doc = concat!("OpenAPI schema of [`", stringify!($field), "`].")]
            pub fn $name() -> utoipa::openapi::schema::Object {
                $field.schema()
            }
        )*
    };
}
pub(crate) use number_schemas;

/// The impact speed `velocity_m_s` (impact and column requests).
pub const VELOCITY: NumberField = NumberField {
    description: "Normal impact speed v, m/s, in (0, 1000].",
    default: FieldDefault::Value(defaults::VELOCITY),
    lo: Bound::Open(0.0),
    hi: Bound::Closed(1000.0),
    unit: "m/s",
    example: 5.0,
    nullable: false,
};

/// `rock.side_length_m`.
pub const ROCK_SIDE_LENGTH: NumberField = NumberField {
    description: "Cube side L, m; also the contact length on the column.",
    default: FieldDefault::Value(defaults::ROCK_SIDE_LENGTH),
    lo: Bound::Closed(0.01),
    hi: Bound::Closed(5.0),
    unit: "m",
    example: 0.3,
    nullable: false,
};

/// `rock.radius_m` (derived default: side_length_m / 2).
pub const ROCK_RADIUS: NumberField = NumberField {
    description: "Sphere radius, m (default side_length_m / 2).",
    default: FieldDefault::Derived,
    lo: Bound::Closed(0.005),
    hi: Bound::Closed(2.5),
    unit: "m",
    example: 0.15,
    nullable: false,
};

/// `rock.density_kg_m3`.
pub const ROCK_DENSITY: NumberField = NumberField {
    description: "Density ρ, kg/m³.",
    default: FieldDefault::Value(defaults::ROCK_DENSITY),
    lo: Bound::Closed(100.0),
    hi: Bound::Closed(20000.0),
    unit: "kg/m³",
    example: 2500.0,
    nullable: false,
};

/// `rock.elastic_modulus_pa`.
pub const ROCK_ELASTIC_MODULUS: NumberField = NumberField {
    description: "Young's modulus E, Pa.",
    default: FieldDefault::Value(defaults::ROCK_ELASTIC_MODULUS),
    lo: Bound::Closed(1e7),
    hi: Bound::Closed(1e12),
    unit: "Pa",
    example: 5e9,
    nullable: false,
};

/// `rock.poisson_ratio`.
pub const ROCK_POISSON_RATIO: NumberField = NumberField {
    description: "Poisson ratio ν, in [0, 0.5).",
    default: FieldDefault::Value(defaults::ROCK_POISSON_RATIO),
    lo: Bound::Closed(0.0),
    hi: Bound::Open(0.5),
    unit: "",
    example: 0.28,
    nullable: false,
};

/// `rock.corner_radius_m` (derived default min(0.02, L/2); cross-field bound r_c ≤ L/2 where
/// used).
pub const ROCK_CORNER_RADIUS: NumberField = NumberField {
    description: "Rounded-corner radius r_c of `hertz_point`, m, in (0, 2.5]; where used \
                  (`hertz_point`, not a sphere) also at most L/2 = side_length_m/2 (default \
                  min(0.02, L/2)).",
    default: FieldDefault::Derived,
    lo: Bound::Open(0.0),
    hi: Bound::Closed(2.5),
    unit: "m",
    example: 0.02,
    nullable: false,
};

/// `column.outer_diameter_m`.
pub const COLUMN_OUTER_DIAMETER: NumberField = NumberField {
    description: "Outer diameter D₁, m.",
    default: FieldDefault::Value(defaults::COLUMN_OUTER_DIAMETER),
    lo: Bound::Closed(0.01),
    hi: Bound::Closed(2.0),
    unit: "m",
    example: 0.25,
    nullable: false,
};

/// `column.inner_diameter_m` (cross-field bound D₂ < D₁; the documented maximum is D₁'s).
pub const COLUMN_INNER_DIAMETER: NumberField = NumberField {
    description: "Inner diameter D₂, m, in [0, D₁) (0 = solid).",
    default: FieldDefault::Value(defaults::COLUMN_INNER_DIAMETER),
    lo: Bound::Closed(0.0),
    hi: Bound::Closed(2.0),
    unit: "m (0 ≤ D₂ < D₁)",
    example: 0.235,
    nullable: false,
};

/// `column.length_m` (cross-field bound: at least a cube's contact length L).
pub const COLUMN_LENGTH: NumberField = NumberField {
    description: "Length between the clamps l, m; at least the contact length L of a cube.",
    default: FieldDefault::Value(defaults::COLUMN_LENGTH),
    lo: Bound::Closed(0.1),
    hi: Bound::Closed(20.0),
    unit: "m",
    example: 1.31,
    nullable: false,
};

/// `column.elastic_modulus_pa`.
pub const COLUMN_ELASTIC_MODULUS: NumberField = NumberField {
    description: "Young's modulus E_s, Pa.",
    default: FieldDefault::Value(defaults::COLUMN_ELASTIC_MODULUS),
    lo: Bound::Closed(1e9),
    hi: Bound::Closed(1e12),
    unit: "Pa",
    example: 208e9,
    nullable: false,
};

/// `column.poisson_ratio`.
pub const COLUMN_POISSON_RATIO: NumberField = NumberField {
    description: "Poisson ratio ν_s, in [0, 0.5).",
    default: FieldDefault::Value(defaults::COLUMN_POISSON_RATIO),
    lo: Bound::Closed(0.0),
    hi: Bound::Open(0.5),
    unit: "",
    example: 0.3,
    nullable: false,
};

/// `column.density_kg_m3`.
pub const COLUMN_DENSITY: NumberField = NumberField {
    description: "Density ρ_s, kg/m³.",
    default: FieldDefault::Value(defaults::COLUMN_DENSITY),
    lo: Bound::Closed(100.0),
    hi: Bound::Closed(20000.0),
    unit: "kg/m³",
    example: 7850.0,
    nullable: false,
};

/// `column.yield_stress_pa`.
pub const COLUMN_YIELD_STRESS: NumberField = NumberField {
    description: "Yield stress, Pa (16Mn steel), for the stress utilisation and the validity \
                  warnings (contact_pressure_above_yield, stress_utilisation_above_one).",
    default: FieldDefault::Value(defaults::COLUMN_YIELD_STRESS),
    lo: Bound::Open(0.0),
    hi: Bound::Closed(1e10),
    unit: "Pa",
    example: 345e6,
    nullable: false,
};

/// `column.contact_radius_m` (derived default D₁/2).
pub const COLUMN_CONTACT_RADIUS: NumberField = NumberField {
    description: "Radius R of the cylinder at the contact, m (default D₁/2).",
    default: FieldDefault::Derived,
    lo: Bound::Closed(0.001),
    hi: Bound::Closed(10.0),
    unit: "m",
    example: 0.125,
    nullable: false,
};

/// `column.damping_coefficient_n_s_m2` (default 1.0 unless `damping_ratio` is given).
pub const COLUMN_DAMPING_COEFFICIENT: NumberField = NumberField {
    description: "Viscous damping per unit length c, N·s/m² (default 1.0, the paper's value; \
                  not filled in when damping_ratio is given).",
    default: FieldDefault::Value(defaults::COLUMN_DAMPING_COEFFICIENT),
    lo: Bound::Closed(0.0),
    hi: Bound::Closed(1e9),
    unit: "N·s/m²",
    example: 1.0,
    nullable: false,
};

/// `column.damping_ratio`.
pub const COLUMN_DAMPING_RATIO: NumberField = NumberField {
    description: "Damping ratio ζ₁ of mode 1 instead of c (recommended 0.02); giving both is 422.",
    default: FieldDefault::Null,
    lo: Bound::Closed(0.0),
    hi: Bound::Closed(10.0),
    unit: "",
    example: 0.02,
    nullable: true,
};

/// The numeric fields shared by `/v1/impact` and `/v1/column`, by JSON Pointer in those requests
/// (what `/v1/presets` lists under `fields`).
pub const IMPACT_FIELDS: &[(&str, NumberField)] = &[
    ("/velocity_m_s", VELOCITY),
    ("/rock/side_length_m", ROCK_SIDE_LENGTH),
    ("/rock/radius_m", ROCK_RADIUS),
    ("/rock/density_kg_m3", ROCK_DENSITY),
    ("/rock/elastic_modulus_pa", ROCK_ELASTIC_MODULUS),
    ("/rock/poisson_ratio", ROCK_POISSON_RATIO),
    ("/rock/corner_radius_m", ROCK_CORNER_RADIUS),
    ("/column/outer_diameter_m", COLUMN_OUTER_DIAMETER),
    ("/column/inner_diameter_m", COLUMN_INNER_DIAMETER),
    ("/column/length_m", COLUMN_LENGTH),
    ("/column/elastic_modulus_pa", COLUMN_ELASTIC_MODULUS),
    ("/column/poisson_ratio", COLUMN_POISSON_RATIO),
    ("/column/density_kg_m3", COLUMN_DENSITY),
    ("/column/yield_stress_pa", COLUMN_YIELD_STRESS),
    ("/column/contact_radius_m", COLUMN_CONTACT_RADIUS),
    (
        "/column/damping_coefficient_n_s_m2",
        COLUMN_DAMPING_COEFFICIENT,
    ),
    ("/column/damping_ratio", COLUMN_DAMPING_RATIO),
];

impl NumberField {
    /// The field as `/v1/presets` lists it: default (number, `null`, `"derived"` or `"required"`), the bounds
    /// under their JSON Schema names, the unit and the description.
    #[must_use]
    pub fn preset(&self) -> Value {
        let mut o = serde_json::Map::new();
        o.insert(
            "default".into(),
            match self.default {
                FieldDefault::Value(v) => json!(v),
                FieldDefault::Null => Value::Null,
                FieldDefault::Derived => json!("derived"),
                FieldDefault::Required => json!("required"),
            },
        );
        match self.lo {
            Bound::Closed(x) => o.insert("minimum".into(), json!(x)),
            Bound::Open(x) => o.insert("exclusiveMinimum".into(), json!(x)),
        };
        match self.hi {
            Bound::Closed(x) => o.insert("maximum".into(), json!(x)),
            Bound::Open(x) => o.insert("exclusiveMaximum".into(), json!(x)),
        };
        o.insert("unit".into(), json!(self.unit));
        o.insert("description".into(), json!(self.description));
        Value::Object(o)
    }
}

number_schemas! {
    velocity_schema => VELOCITY;
    rock_side_length_schema => ROCK_SIDE_LENGTH;
    rock_radius_schema => ROCK_RADIUS;
    rock_density_schema => ROCK_DENSITY;
    rock_elastic_modulus_schema => ROCK_ELASTIC_MODULUS;
    rock_poisson_ratio_schema => ROCK_POISSON_RATIO;
    rock_corner_radius_schema => ROCK_CORNER_RADIUS;
    column_outer_diameter_schema => COLUMN_OUTER_DIAMETER;
    column_inner_diameter_schema => COLUMN_INNER_DIAMETER;
    column_length_schema => COLUMN_LENGTH;
    column_elastic_modulus_schema => COLUMN_ELASTIC_MODULUS;
    column_poisson_ratio_schema => COLUMN_POISSON_RATIO;
    column_density_schema => COLUMN_DENSITY;
    column_yield_stress_schema => COLUMN_YIELD_STRESS;
    column_contact_radius_schema => COLUMN_CONTACT_RADIUS;
    column_damping_coefficient_schema => COLUMN_DAMPING_COEFFICIENT;
    column_damping_ratio_schema => COLUMN_DAMPING_RATIO;
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
    /// Polyhedron of the ellipsoid with full axes `dimensions_m` (the block's measured
    /// dimensions): 64 points of a Fibonacci lattice on it, scaled to its volume π a b c / 6
    /// (migration).
    Ellipsoid,
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
    #[schema(schema_with = rock_side_length_schema)]
    pub side_length_m: f64,
    /// Sphere radius, m (default side_length_m / 2).
    #[schema(schema_with = rock_radius_schema)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "non_null"
    )]
    pub radius_m: Option<f64>,
    /// Cuboid edges [a, b, c], m, each in [0.01, 5].
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "non_null"
    )]
    #[schema(example = json!([0.4, 0.3, 0.2]))]
    pub dimensions_m: Option<[f64; 3]>,
    /// Convex polyhedron vertices (4–1000 points [x, y, z], each coordinate in [-10, 10]), m.
    #[schema(example = json!([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.3]]))]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "non_null"
    )]
    pub vertices_m: Option<Vec<[f64; 3]>>,
    /// Random polyhedron parameters.
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "non_null"
    )]
    pub random: Option<RandomShapeDto>,
    /// Density ρ, kg/m³.
    #[schema(schema_with = rock_density_schema)]
    pub density_kg_m3: f64,
    /// Young's modulus E, Pa.
    #[schema(schema_with = rock_elastic_modulus_schema)]
    pub elastic_modulus_pa: f64,
    /// Poisson ratio ν, in [0, 0.5).
    #[schema(schema_with = rock_poisson_ratio_schema)]
    pub poisson_ratio: f64,
    /// Rounded-corner radius r_c of `hertz_point`, m, in (0, 2.5]; where used (`hertz_point`, not a
    /// sphere) also at most L/2 = side_length_m/2 (default min(0.02, L/2)).
    #[schema(schema_with = rock_corner_radius_schema)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "non_null"
    )]
    pub corner_radius_m: Option<f64>,
}

impl Default for RockDto {
    fn default() -> Self {
        Self {
            shape: ShapeKind::Cube,
            side_length_m: ROCK_SIDE_LENGTH.value(),
            radius_m: None,
            dimensions_m: None,
            vertices_m: None,
            random: None,
            density_kg_m3: ROCK_DENSITY.value(),
            elastic_modulus_pa: ROCK_ELASTIC_MODULUS.value(),
            poisson_ratio: ROCK_POISSON_RATIO.value(),
            corner_radius_m: None,
        }
    }
}

impl RockDto {
    /// Checks ranges (under `base`, a JSON Pointer prefix), fills derived defaults, and converts.
    /// `corner_needed`: whether the Hertz corner radius is used (checked only then).
    pub fn resolve(&mut self, base: &str, corner_needed: bool, checker: &mut Checker) -> Rock {
        let p = |f: &str| format!("{base}/{f}");
        ROCK_SIDE_LENGTH.check(checker, &p("side_length_m"), self.side_length_m);
        ROCK_DENSITY.check(checker, &p("density_kg_m3"), self.density_kg_m3);
        ROCK_ELASTIC_MODULUS.check(checker, &p("elastic_modulus_pa"), self.elastic_modulus_pa);
        ROCK_POISSON_RATIO.check(checker, &p("poisson_ratio"), self.poisson_ratio);
        let l = self.side_length_m;
        // Every field that is sent is checked against its own range, whether the shape uses it
        // or not; rules relating two fields (r_c ≤ L/2) apply only where the field is used.
        if let Some(r) = self.radius_m {
            ROCK_RADIUS.check(checker, &p("radius_m"), r);
        }
        if let Some(d) = self.dimensions_m {
            for (i, v) in d.iter().enumerate() {
                checker.closed(&p(&format!("dimensions_m/{i}")), *v, 0.01, 5.0, "m");
            }
        }
        if let Some(v) = &self.vertices_m {
            if !(4..=1000).contains(&v.len()) {
                checker.push(
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
                checker.closed(&p(&format!("vertices_m/{i}/{j}")), c, -10.0, 10.0, "m");
            }
        }
        if let Some(r) = &self.random {
            for (i, v) in r.semi_axes_m.iter().enumerate() {
                checker.closed(&p(&format!("random/semi_axes_m/{i}")), *v, 0.005, 2.5, "m");
            }
            checker.count(
                &p("random/vertices"),
                u64::from(r.vertices),
                4,
                1000,
                "points",
            );
        }
        if let Some(rc) = self.corner_radius_m {
            ROCK_CORNER_RADIUS.check(checker, &p("corner_radius_m"), rc);
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
                    checker.push(
                        p("dimensions_m"),
                        Value::Null,
                        "a cuboid needs dimensions_m [a, b, c] in m",
                    );
                    RockShape::Cube
                }
            },
            ShapeKind::Ellipsoid => match self.dimensions_m {
                Some(d) => RockShape::Ellipsoid { dimensions: d },
                None => {
                    checker.push(
                        p("dimensions_m"),
                        Value::Null,
                        "an ellipsoid needs dimensions_m [a, b, c] (its full axes) in m",
                    );
                    RockShape::Cube
                }
            },
            ShapeKind::Polyhedron => match &self.vertices_m {
                Some(v) => RockShape::Polyhedron {
                    vertices: v.clone(),
                },
                None => {
                    checker.push(
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
                    checker.push(
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
            _ => *self
                .corner_radius_m
                .get_or_insert(crate::physics::material::defaults::corner_radius(l)),
        };
        if corner_needed && !matches!(shape, RockShape::Sphere { .. }) {
            checker.range(
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
    #[schema(schema_with = column_outer_diameter_schema)]
    pub outer_diameter_m: f64,
    /// Inner diameter D₂, m, in [0, D₁) (0 = solid).
    #[schema(schema_with = column_inner_diameter_schema)]
    pub inner_diameter_m: f64,
    /// Length between the clamps l, m; at least the contact length L of a cube.
    #[schema(schema_with = column_length_schema)]
    pub length_m: f64,
    /// Young's modulus E_s, Pa.
    #[schema(schema_with = column_elastic_modulus_schema)]
    pub elastic_modulus_pa: f64,
    /// Poisson ratio ν_s, in [0, 0.5).
    #[schema(schema_with = column_poisson_ratio_schema)]
    pub poisson_ratio: f64,
    /// Density ρ_s, kg/m³.
    #[schema(schema_with = column_density_schema)]
    pub density_kg_m3: f64,
    /// Yield stress, Pa (16Mn steel), for the stress utilisation.
    #[schema(schema_with = column_yield_stress_schema)]
    pub yield_stress_pa: f64,
    /// Radius R of the cylinder at the contact, m (default D₁/2).
    #[schema(schema_with = column_contact_radius_schema)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "non_null"
    )]
    pub contact_radius_m: Option<f64>,
    /// Viscous damping per unit length c, N·s/m² (default 1.0, the paper's value).
    #[schema(schema_with = column_damping_coefficient_schema)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "non_null"
    )]
    pub damping_coefficient_n_s_m2: Option<f64>,
    /// Damping ratio ζ₁ of mode 1 instead of c (recommended 0.02); giving both is 422.
    #[schema(schema_with = column_damping_ratio_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_ratio: Option<f64>,
}

impl Default for ColumnDto {
    fn default() -> Self {
        Self {
            outer_diameter_m: COLUMN_OUTER_DIAMETER.value(),
            inner_diameter_m: COLUMN_INNER_DIAMETER.value(),
            length_m: COLUMN_LENGTH.value(),
            elastic_modulus_pa: COLUMN_ELASTIC_MODULUS.value(),
            poisson_ratio: COLUMN_POISSON_RATIO.value(),
            density_kg_m3: COLUMN_DENSITY.value(),
            yield_stress_pa: COLUMN_YIELD_STRESS.value(),
            contact_radius_m: None,
            damping_coefficient_n_s_m2: None,
            damping_ratio: None,
        }
    }
}

impl ColumnDto {
    /// Checks ranges (under `base`), fills derived defaults, and converts.
    pub fn resolve(&mut self, base: &str, checker: &mut Checker) -> Column {
        let p = |f: &str| format!("{base}/{f}");
        let d1 = self.outer_diameter_m;
        COLUMN_OUTER_DIAMETER.check(checker, &p("outer_diameter_m"), d1);
        // The documented maximum of D₂ is D₁'s; the bound enforced is the cross-field D₂ < D₁.
        checker.range(
            &p("inner_diameter_m"),
            self.inner_diameter_m,
            COLUMN_INNER_DIAMETER.lo,
            Bound::Open(d1),
            COLUMN_INNER_DIAMETER.unit,
        );
        COLUMN_LENGTH.check(checker, &p("length_m"), self.length_m);
        COLUMN_ELASTIC_MODULUS.check(checker, &p("elastic_modulus_pa"), self.elastic_modulus_pa);
        COLUMN_POISSON_RATIO.check(checker, &p("poisson_ratio"), self.poisson_ratio);
        COLUMN_DENSITY.check(checker, &p("density_kg_m3"), self.density_kg_m3);
        COLUMN_YIELD_STRESS.check(checker, &p("yield_stress_pa"), self.yield_stress_pa);
        let r = *self.contact_radius_m.get_or_insert(d1 / 2.0);
        COLUMN_CONTACT_RADIUS.check(checker, &p("contact_radius_m"), r);
        let damping = match (self.damping_coefficient_n_s_m2, self.damping_ratio) {
            (Some(c), Some(z)) => {
                COLUMN_DAMPING_COEFFICIENT.check(checker, &p("damping_coefficient_n_s_m2"), c);
                COLUMN_DAMPING_RATIO.check(checker, &p("damping_ratio"), z);
                checker.push(
                    p("damping_ratio"),
                    crate::http::error::num(z),
                    format!(
                        "give either damping_coefficient_n_s_m2 ({c}) or damping_ratio, not both"
                    ),
                );
                Damping::Coefficient(c)
            }
            (None, Some(z)) => {
                COLUMN_DAMPING_RATIO.check(checker, &p("damping_ratio"), z);
                Damping::Ratio(z)
            }
            (c, None) => {
                let c = *self
                    .damping_coefficient_n_s_m2
                    .get_or_insert(c.unwrap_or(COLUMN_DAMPING_COEFFICIENT.value()));
                COLUMN_DAMPING_COEFFICIENT.check(checker, &p("damping_coefficient_n_s_m2"), c);
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

impl From<&crate::physics::validity::Warning> for Warning {
    fn from(w: &crate::physics::validity::Warning) -> Self {
        Self {
            code: w.code.into(),
            message: w.message.clone(),
        }
    }
}

/// The wire form of physics warnings, in their order.
#[must_use]
pub fn warnings_of(w: &[crate::physics::validity::Warning]) -> Vec<Warning> {
    w.iter().map(Warning::from).collect()
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

impl From<&crate::physics::plan::Stage> for PlanStep {
    fn from(s: &crate::physics::plan::Stage) -> Self {
        Self {
            stage: s.stage.into(),
            status: if s.ran {
                StageStatus::Ran
            } else {
                StageStatus::Skipped
            },
            reason: s.reason.clone(),
        }
    }
}

/// The wire form of a plan, in its order.
#[must_use]
pub fn plan_of(plan: &[crate::physics::plan::Stage]) -> Vec<PlanStep> {
    plan.iter().map(PlanStep::from).collect()
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
    #[must_use]
    pub fn new(plan: Vec<PlanStep>) -> Self {
        Self {
            model_version: MODEL_VERSION.into(),
            plan,
            warnings: Vec::new(),
        }
    }

    /// Metadata with the crate version and a calculation report's plan and warnings.
    #[must_use]
    pub fn of(plan: &[crate::calc::Stage], warnings: &[crate::calc::Warning]) -> Self {
        Self {
            model_version: MODEL_VERSION.into(),
            plan: plan_of(plan),
            warnings: warnings_of(warnings),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dto_defaults_are_the_field_defaults() {
        let (rock, column) = (RockDto::default(), ColumnDto::default());
        for (pointer, field) in IMPACT_FIELDS {
            let Some(name) = pointer
                .strip_prefix("/rock/")
                .or(pointer.strip_prefix("/column/"))
            else {
                continue;
            };
            let object = if pointer.starts_with("/rock/") {
                serde_json::to_value(&rock).unwrap()
            } else {
                serde_json::to_value(&column).unwrap()
            };
            match field.default {
                FieldDefault::Value(v) if name != "damping_coefficient_n_s_m2" => {
                    assert_eq!(object[name].as_f64(), Some(v), "{pointer}");
                }
                _ => assert!(object.get(name).is_none(), "{pointer}: filled at resolve"),
            }
        }
    }

    #[test]
    fn check_enforces_exactly_the_documented_interval() {
        for (pointer, field) in IMPACT_FIELDS {
            let (lo, lo_in) = match field.lo {
                Bound::Closed(x) => (x, true),
                Bound::Open(x) => (x, false),
            };
            let (hi, hi_in) = match field.hi {
                Bound::Closed(x) => (x, true),
                Bound::Open(x) => (x, false),
            };
            for (v, ok) in [
                (lo, lo_in),
                (lo.next_down(), false),
                (lo.next_up(), true),
                (hi, hi_in),
                (hi.next_up(), false),
                (hi.next_down(), true),
                (f64::NAN, false),
            ] {
                let mut checker = Checker::new();
                assert_eq!(
                    field.check(&mut checker, pointer, v),
                    ok,
                    "{pointer} = {v:e}"
                );
                assert_eq!(checker.is_ok(), ok);
            }
        }
    }

    #[test]
    fn schema_and_preset_show_the_same_bounds_and_default() {
        let schema = serde_json::to_value(COLUMN_YIELD_STRESS.schema()).unwrap();
        assert_eq!(schema["exclusiveMinimum"].as_f64(), Some(0.0));
        assert_eq!(schema["maximum"].as_f64(), Some(1e10));
        assert_eq!(schema["default"].as_f64(), Some(345e6));
        assert_eq!(schema["type"], "number");
        let preset = COLUMN_YIELD_STRESS.preset();
        for key in ["exclusiveMinimum", "maximum", "default"] {
            assert_eq!(preset[key].as_f64(), schema[key].as_f64(), "{key}");
        }
        let ratio = serde_json::to_value(COLUMN_DAMPING_RATIO.schema()).unwrap();
        assert_eq!(ratio["type"], json!(["number", "null"]));
        assert!(ratio["default"].is_null() && ratio.get("default").is_some());
        let radius = serde_json::to_value(COLUMN_CONTACT_RADIUS.schema()).unwrap();
        assert!(radius.get("default").is_none(), "derived: no default");
        assert_eq!(COLUMN_CONTACT_RADIUS.preset()["default"], "derived");
    }
}

/// A field's value and whether the request carried it (its default fills in when not); it reads
/// and writes as the value alone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sent<T> {
    /// The value sent, or the field's default.
    pub value: T,
    /// Whether the request carried the field.
    pub sent: bool,
}

impl<T> Sent<T> {
    /// The field's default, not sent.
    pub const fn default_value(value: T) -> Self {
        Self { value, sent: false }
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Sent<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(Self {
            value: T::deserialize(d)?,
            sent: true,
        })
    }
}

impl<T: Serialize> Serialize for Sent<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.value.serialize(s)
    }
}

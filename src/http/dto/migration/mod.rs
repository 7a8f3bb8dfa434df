//! `POST /v1/migration`: request, response, validation.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use sha2::{Digest, Sha256};
use utoipa::ToSchema;

use super::common::Bound::{Closed, Open};
use super::common::{
    Checker, FieldDefault, Meta, NumberField, PlanStep, RockDto, Warning, non_null, number_schemas,
};
use super::floor::{self as formats, Sorted};
use super::param::Layout;
use crate::config::Config;
use crate::http::error::{ApiError, num};
use crate::physics::Param;
use crate::physics::migration::defaults;
use crate::physics::migration::{
    self, ContactModel, ContourLine, Distribution, EventKind, Face, FloorMaterial, FloorSpec,
    LumpedMassOptions, MapFrame, Method, MigrationCase, MigrationResult, MonteCarlo, Motion,
    OutputOptions, Phase, Release, RigidBlockOptions, RunSummary, StopReason, Summary,
};

mod compare;
mod floor_check;
mod response;

pub use compare::{MethodArrivalDto, MethodComparisonDto};
use floor_check::resolve_floor;
pub use response::*;

/// Declares the numeric fields of a request as [`NumberField`]s, each with its schema function.
macro_rules! number_fields {
    ($(
        $(#[$meta:meta])*
        $name:ident, $schema:ident: $description:expr, $default:expr, $lo:expr, $hi:expr,
        $unit:expr, $example:expr;
    )*) => {
        $(
            $(#[$meta])*
            pub const $name: NumberField = NumberField {
                description: $description,
                default: $default,
                lo: $lo,
                hi: $hi,
                unit: $unit,
                example: $example,
                nullable: matches!($default, FieldDefault::Null),
            };
        )*
        number_schemas! { $( $schema => $name; )* }
    };
}

number_fields! {
    /// `gravity_m_s2` (migration and scene).
    GRAVITY, gravity_schema: "Gravity g, m/s², in [0.1, 100].",
        FieldDefault::Value(9.81), Closed(0.1), Closed(100.0), "m/s²", 9.81;
    /// `face.dip_deg`.
    FACE_DIP, face_dip_schema: "Dip θ, degrees, in [5, 80].",
        FieldDefault::Value(defaults::DIP_DEG), Closed(5.0), Closed(80.0), "°", 45.0;
    /// `face.length_m`.
    FACE_LENGTH, face_length_schema: "Face length along dip S, m, in (0, 10000].",
        FieldDefault::Value(defaults::FACE_LENGTH), Open(0.0), Closed(10000.0), "m", 120.0;
    /// `face.friction_coefficient`.
    FACE_FRICTION, face_friction_schema: "Coulomb friction μ, in [0, 2].",
        FieldDefault::Value(defaults::FRICTION_COEFFICIENT), Closed(0.0), Closed(2.0), "", 0.2;
    /// `face.restitution_normal`.
    FACE_RESTITUTION_NORMAL, face_restitution_normal_schema: "Normal restitution e_n, in [0, 1].",
        FieldDefault::Value(defaults::RESTITUTION_NORMAL), Closed(0.0), Closed(1.0), "", 0.3;
    /// `face.restitution_tangential`.
    FACE_RESTITUTION_TANGENTIAL, face_restitution_tangential_schema:
        "Tangential restitution e_t, in [0, 1].",
        FieldDefault::Value(defaults::RESTITUTION_TANGENTIAL), Closed(0.0), Closed(1.0), "", 0.8;
    /// `face.normal_stiffness_n_m` (rigid block).
    FACE_NORMAL_STIFFNESS, face_normal_stiffness_schema:
        "Normal contact stiffness k_n (rigid block), N/m, in [1e3, 1e12].",
        FieldDefault::Value(1e8), Closed(1e3), Closed(1e12), "N/m", 1e8;
    /// `face.shear_stiffness_n_m` (rigid block).
    FACE_SHEAR_STIFFNESS, face_shear_stiffness_schema:
        "Shear contact stiffness k_s (rigid block), N/m, in [1e3, 1e12].",
        FieldDefault::Value(1e8), Closed(1e3), Closed(1e12), "N/m", 1e8;
    /// `face.critical_damping_ratio` (rigid block).
    FACE_CRITICAL_DAMPING, face_critical_damping_schema:
        "Critical damping ratio β of the contact dashpot (rigid block), in [0, 1).",
        FieldDefault::Value(0.35), Closed(0.0), Open(1.0), "", 0.35;
    /// `face.floor_material.elastic_modulus_pa` (rigid block, Hertz; required in `floor_material`).
    FLOOR_MATERIAL_MODULUS, floor_material_modulus_schema:
        "Young's modulus of the floor E_f in the Hertz law's E* (rigid block), Pa, in [1e7, 1e12].",
        FieldDefault::Required, Closed(1e7), Closed(1e12), "Pa", 4.38e9;
    /// `face.floor_material.poisson_ratio` (rigid block, Hertz; required in `floor_material`).
    FLOOR_MATERIAL_POISSON, floor_material_poisson_schema:
        "Poisson ratio of the floor ν_f in the Hertz law's E* (rigid block), in [0, 0.5).",
        FieldDefault::Required, Closed(0.0), Open(0.5), "", 0.3;
    /// `face.local_damping` (rigid block).
    FACE_LOCAL_DAMPING, face_local_damping_schema: "PFC local damping α (rigid block), in [0, 1).",
        FieldDefault::Value(0.0), Closed(0.0), Open(1.0), "", 0.0;
    /// `face.floor.resolution_m` (contour floors).
    FLOOR_RESOLUTION, floor_resolution_schema:
        "Largest spacing of resampled contour points, m, in [0.01, 100] (default 1).",
        FieldDefault::Value(1.0), Closed(0.01), Closed(100.0), "m", 1.0;
    /// `release.drop_height_m`.
    RELEASE_DROP_HEIGHT, release_drop_height_schema:
        "Vertical lift above the floor point, m, in [0, 1000] (0: starts on the floor).",
        FieldDefault::Value(3.27), Closed(0.0), Closed(1000.0), "m", 3.27;
    /// `release.along_dip_m` (cross-field bound: below `face.length_m`; the documented maximum
    /// is the longest face's).
    RELEASE_ALONG_DIP, release_along_dip_schema:
        "Along-dip position of the floor point, m, in [0, length_m): the upper bound depends on\n\
         `face.length_m` (at most 10 000 m). On a grid or contour floor the point must be on the\n\
         floor at `across_m` (a point up the dip of the floor's upper edge starts on that edge;\n\
         past its lower edge or over a hole is 422 naming this field). The rigid block rests\n\
         face-down with every corner over the floor: a block overhanging the floor's edge is\n\
         moved to the nearest position where it fits, at most two bounding radii away (warning\n\
         `release_moved` with the shift; so the default release runs on every floor), farther is\n\
         422 naming `along_dip_m` or `across_m` with the interval where it fits.",
        FieldDefault::Value(0.0), Closed(0.0), Open(10000.0), "m (below length_m)", 0.0;
    /// `release.across_m`.
    RELEASE_ACROSS, release_across_schema: "Across-face position y, m, in [−1000, 1000].",
        FieldDefault::Value(0.0), Closed(-1000.0), Closed(1000.0), "m", 0.0;
    /// `release.speed_m_s`.
    RELEASE_SPEED, release_speed_schema:
        "Initial speed along the floor's down-dip direction, m/s, in [0, 1000].",
        FieldDefault::Value(0.0), Closed(0.0), Closed(1000.0), "m/s", 0.0;
    /// `lumped_mass.stop_normal_speed_m_s`.
    STOP_NORMAL_SPEED, stop_normal_speed_schema:
        "Normal rebound speed below which the ground phase starts, m/s, in [0, 100].",
        FieldDefault::Value(0.5), Closed(0.0), Closed(100.0), "m/s", 0.5;
    /// `rigid_block.time_step_s` (`null`: safety × Δt_crit).
    TIME_STEP, time_step_schema: "Time step, s, in (0, 1] (default: safety × Δt_crit).",
        FieldDefault::Null, Open(0.0), Closed(1.0), "s", 1e-5;
    /// `rigid_block.time_step_safety`.
    TIME_STEP_SAFETY, time_step_safety_schema:
        "Safety factor on the critical time step, in (0, 1]. One above 0.3 is used as 0.3, the\n\
         largest whose impacts keep the energy account within its bound (warning\n\
         `time_step_safety_capped` with the safety used).",
        FieldDefault::Value(0.2), Open(0.0), Closed(1.0), "", 0.2;
    /// `end_time_s` of a migration (`null`: run to the lower end).
    MIGRATION_END_TIME, migration_end_time_schema:
        "Stop at this time instead of the lower end, s, in (0, 1e5].",
        FieldDefault::Null, Open(0.0), Closed(1e5), "s", 2.0;
    /// `end_time_s` of a scene (`null`: no time limit); the migration's interval.
    SCENE_END_TIME, scene_end_time_schema:
        "Stop at this time, s, in (0, 1e5] (null: no time limit).",
        FieldDefault::Null, MIGRATION_END_TIME.lo, MIGRATION_END_TIME.hi, "s", 20.0;
    /// `face.floor.spacing_m` (grid floors; required there).
    FLOOR_SPACING, floor_spacing_schema: "Grid spacing d, m, in [0.01, 100].",
        FieldDefault::Required, Closed(0.01), Closed(100.0), "m", 0.5;
    /// `face.floor.map.dip_direction_deg` (required in `map`).
    MAP_DIP_DIRECTION, map_dip_direction_schema:
        "Azimuth of the face's down-dip x axis, degrees clockwise from north, in [0, 360); y is x\n\
         turned 90° anticlockwise seen from above.",
        FieldDefault::Required, Closed(0.0), Open(360.0), "° (clockwise from north)", 135.0;
    /// `output.sample_interval_s` (`migration_output` in a scene).
    SAMPLE_INTERVAL, sample_interval_schema: "Trajectory sample interval, s, in [1e-6, 100].",
        FieldDefault::Value(0.01), Closed(1e-6), Closed(100.0), "s", 0.01;
}

/// The numeric fields of `/v1/migration` with a documented default or bound, by JSON Pointer
/// (what `/v1/presets` lists under `migration_fields`; the rock's are in `fields`).
pub const MIGRATION_FIELDS: &[(&str, NumberField)] = &[
    ("/gravity_m_s2", GRAVITY),
    ("/face/dip_deg", FACE_DIP),
    ("/face/length_m", FACE_LENGTH),
    ("/face/friction_coefficient", FACE_FRICTION),
    ("/face/restitution_normal", FACE_RESTITUTION_NORMAL),
    ("/face/restitution_tangential", FACE_RESTITUTION_TANGENTIAL),
    ("/face/normal_stiffness_n_m", FACE_NORMAL_STIFFNESS),
    ("/face/shear_stiffness_n_m", FACE_SHEAR_STIFFNESS),
    ("/face/critical_damping_ratio", FACE_CRITICAL_DAMPING),
    ("/face/local_damping", FACE_LOCAL_DAMPING),
    (
        "/face/floor_material/elastic_modulus_pa",
        FLOOR_MATERIAL_MODULUS,
    ),
    ("/face/floor_material/poisson_ratio", FLOOR_MATERIAL_POISSON),
    ("/face/floor/spacing_m", FLOOR_SPACING),
    ("/face/floor/resolution_m", FLOOR_RESOLUTION),
    ("/face/floor/map/dip_direction_deg", MAP_DIP_DIRECTION),
    ("/release/drop_height_m", RELEASE_DROP_HEIGHT),
    ("/release/along_dip_m", RELEASE_ALONG_DIP),
    ("/release/across_m", RELEASE_ACROSS),
    ("/release/speed_m_s", RELEASE_SPEED),
    ("/lumped_mass/stop_normal_speed_m_s", STOP_NORMAL_SPEED),
    ("/rigid_block/time_step_s", TIME_STEP),
    ("/rigid_block/time_step_safety", TIME_STEP_SAFETY),
    ("/end_time_s", MIGRATION_END_TIME),
    ("/output/sample_interval_s", SAMPLE_INTERVAL),
];

/// The default `face.floor.elevation_property` of GeoJSON contours.
pub const ELEVATION_PROPERTY: &str = "elevation";

/// Migration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum MethodDto {
    /// Point mass, energy tracking method (physics.md §C.2).
    #[default]
    LumpedMass,
    /// Rigid polyhedral block, DEM (physics.md §C.3).
    RigidBlock,
}

/// Kind of floor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum FloorKind {
    /// The plane z = −x·tan θ.
    #[default]
    Plane,
    /// A height grid.
    Grid,
    /// Contour polylines, triangulated.
    Contours,
}

/// One contour line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ContourDto {
    /// Elevation z of the line, m.
    #[schema(example = -10.0)]
    pub elevation_m: f64,
    /// Plan points [x, y] of the polyline, m.
    #[schema(example = json!([[10.0, -5.0], [10.0, 5.0]]))]
    pub points_m: Vec<[f64; 2]>,
}

/// Placement of a floor given in map coordinates (easting, northing) on the face.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct MapDto {
    /// Azimuth of the face's down-dip x axis, degrees clockwise from north, in [0, 360); y is x
    /// turned 90° anticlockwise seen from above.
    #[schema(schema_with = map_dip_direction_schema)]
    pub dip_direction_deg: f64,
    /// Map coordinates [E, N] of the face's origin (`along_dip_m` = 0), m, each in [−1e8, 1e8].
    #[schema(example = json!([500000.0, 4200000.0]))]
    pub origin_m: [f64; 2],
}

/// The floor of the face. In `inputs` a grid or contour floor is echoed as
/// `{"kind", "sha256", "map"}`: the SHA-256 of the `esri_ascii` text as sent, or of the floor
/// object re-serialized as compact JSON with its object keys sorted (defaults filled in).
#[derive(Debug, Clone, PartialEq, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct FloorDto {
    /// Kind of floor.
    #[schema(default = "plane", example = "plane")]
    pub kind: FloorKind,
    /// Grid origin [x₀, y₀], m (default [0, 0]).
    #[serde(deserialize_with = "non_null")]
    #[schema(default = json!([0.0, 0.0]), example = json!([0.0, -5.0]))]
    pub origin_m: Option<[f64; 2]>,
    /// Grid spacing d, m, in [0.01, 100].
    #[serde(deserialize_with = "non_null")]
    #[schema(schema_with = floor_spacing_schema)]
    pub spacing_m: Option<f64>,
    /// Grid heights: `heights_m[i][j]` is z at (x₀ + j·d, y₀ + i·d), m; at most 4096 × 4096.
    #[serde(deserialize_with = "non_null")]
    #[schema(example = json!([[0.0, -1.0, -2.0], [0.0, -1.0, -2.0]]))]
    pub heights_m: Option<Vec<Vec<f64>>>,
    /// A grid as the text of an ESRI ASCII file (`ncols …`), instead of `origin_m`, `spacing_m`
    /// and `heights_m`: square cells, heights at the cells' centres, the first data row the
    /// northernmost, one row per line, NODATA cells are holes in the floor.
    #[serde(deserialize_with = "non_null")]
    #[schema(
        example = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n0 -1 -2\n0 -1 -2\n"
    )]
    pub esri_ascii: Option<String>,
    /// Contour polylines with elevations.
    #[serde(deserialize_with = "non_null")]
    #[schema(example = json!([{"elevation_m": 0.0, "points_m": [[0.0, -5.0], [0.0, 5.0]]}, {"elevation_m": -10.0, "points_m": [[10.0, -5.0], [10.0, 5.0]]}]))]
    pub contours: Option<Vec<ContourDto>>,
    /// Contours as a GeoJSON FeatureCollection of LineString / MultiLineString features in
    /// projected metres, instead of `contours`.
    #[serde(deserialize_with = "non_null")]
    #[schema(schema_with = geojson_schema)]
    pub geojson: Option<Value>,
    /// Property of a GeoJSON feature holding its elevation, m (default "elevation"; without
    /// it, the third coordinate).
    #[serde(deserialize_with = "non_null")]
    #[schema(default = "elevation", example = "elevation")]
    pub elevation_property: Option<String>,
    /// Largest spacing of resampled contour points, m, in [0.01, 100] (default 1).
    #[serde(deserialize_with = "non_null")]
    #[schema(schema_with = floor_resolution_schema)]
    pub resolution_m: Option<f64>,
    /// Map coordinates: the grid or contours are given in (E, N) and placed on the face by a
    /// rigid transform.
    #[serde(deserialize_with = "non_null")]
    pub map: Option<MapDto>,
    /// SHA-256 of the floor as received (set when resolved; echoed in `inputs`).
    #[serde(skip)]
    #[schema(ignore)]
    pub sha256: Option<String>,
    /// Whether GeoJSON contours without `map` look like longitude/latitude: within ±180 × ±90 and
    /// far steeper than any face in metres (set when resolved).
    #[serde(skip)]
    #[schema(ignore)]
    pub geographic: bool,
}

/// Schema of the `geojson` field: a GeoJSON object (RFC 7946), with an example.
/// `face.zones`: null, the zones (`ZonesDto`), or in `inputs` their echo `{"kind", "sha256"}`.
fn zones_schema() -> utoipa::openapi::schema::Schema {
    use utoipa::openapi::schema::{ObjectBuilder, OneOfBuilder, Type};
    use utoipa::openapi::{Ref, RefOr};
    let echo = ObjectBuilder::new()
        .schema_type(Type::Object)
        .description(Some(
            "The zones as echoed in `inputs`: the kind of the zone map and the SHA-256 of the \
             zones object re-serialized as compact JSON with its keys sorted (never sent).",
        ))
        .property(
            "kind",
            ObjectBuilder::new()
                .schema_type(Type::String)
                .enum_values(Some(["esri_ascii", "polygons"])),
        )
        .property("sha256", ObjectBuilder::new().schema_type(Type::String))
        .required("kind")
        .required("sha256")
        .additional_properties(Some(
            utoipa::openapi::schema::AdditionalProperties::FreeForm(false),
        ));
    OneOfBuilder::new()
        .item(ObjectBuilder::new().schema_type(Type::Null))
        .item(RefOr::Ref(Ref::from_schema_name("ZonesDto")))
        .item(echo)
        .description(Some(
            "Materials of the floor by zone: integer codes over the floor (an ESRI ASCII grid or \
             polygons, in the floor's own frame) and a material per code, each field defaulting \
             to the face's (null: one material, the fields above). Echoed in `inputs` as \
             `{\"kind\", \"sha256\"}`.",
        ))
        .default(Some(Value::Null))
        .build()
        .into()
}

#[allow(deprecated)] // `example`, as the derived schemas have it (not `examples`)
fn geojson_schema() -> utoipa::openapi::schema::Object {
    utoipa::openapi::schema::ObjectBuilder::new()
        .schema_type(utoipa::openapi::schema::Type::Object)
        .description(Some(
            "Contours as a GeoJSON FeatureCollection of LineString / MultiLineString features \
             in projected metres, instead of `contours`.",
        ))
        .example(Some(json!({"type": "FeatureCollection", "features": [
            {"type": "Feature", "properties": {"elevation": 0.0},
             "geometry": {"type": "LineString", "coordinates": [[0.0, -5.0], [0.0, 5.0]]}},
            {"type": "Feature", "properties": {"elevation": -10.0},
             "geometry": {"type": "LineString", "coordinates": [[10.0, -5.0], [10.0, 5.0]]}}]})))
        .build()
}

/// The floor object with its fields in sorted order, for the hash.
#[derive(Serialize)]
struct FloorFull<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    contours: &'a Option<Vec<ContourDto>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    elevation_property: &'a Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    geojson: Option<Sorted<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    heights_m: &'a Option<Vec<Vec<f64>>>,
    kind: FloorKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    map: &'a Option<MapDto>,
    #[serde(skip_serializing_if = "Option::is_none")]
    origin_m: &'a Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    resolution_m: &'a Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    spacing_m: &'a Option<f64>,
}

fn hex_sha256(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

impl FloorDto {
    fn digest(&self) -> String {
        if let Some(t) = &self.esri_ascii {
            return hex_sha256(t.as_bytes());
        }
        let full = FloorFull {
            contours: &self.contours,
            elevation_property: &self.elevation_property,
            geojson: self.geojson.as_ref().map(Sorted),
            heights_m: &self.heights_m,
            kind: self.kind,
            map: &self.map,
            origin_m: &self.origin_m,
            resolution_m: &self.resolution_m,
            spacing_m: &self.spacing_m,
        };
        hex_sha256(&serde_json::to_vec(&full).unwrap_or_default())
    }
}

impl Serialize for FloorDto {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("kind", &self.kind)?;
        if self.kind != FloorKind::Plane {
            let d = self.sha256.clone().unwrap_or_else(|| self.digest());
            m.serialize_entry("sha256", &d)?;
            if let Some(map) = &self.map {
                m.serialize_entry("map", map)?;
            }
        }
        m.end()
    }
}

/// Normal contact law of the rigid block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum ContactModelDto {
    /// Linear spring–dashpot (PFC linear model).
    #[default]
    Linear,
    /// Hertz normal law from the moduli of rock and floor.
    Hertz,
}

/// The floor's elastic constants in the rigid block's Hertz contact (physics.md §C.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct FloorMaterialDto {
    /// Young's modulus of the floor E_f, Pa, in [1e7, 1e12].
    #[schema(schema_with = floor_material_modulus_schema)]
    pub elastic_modulus_pa: f64,
    /// Poisson ratio of the floor ν_f, in [0, 0.5).
    #[schema(schema_with = floor_material_poisson_schema)]
    pub poisson_ratio: f64,
}

/// The working face (paper Table 3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct FaceDto {
    /// Dip θ, degrees, in [5, 80].
    #[schema(schema_with = face_dip_schema)]
    pub dip_deg: f64,
    /// Face length along dip S, m, in (0, 10000].
    #[schema(schema_with = face_length_schema)]
    pub length_m: f64,
    /// Floor: plane, grid or contours.
    pub floor: FloorDto,
    /// Coulomb friction μ, in [0, 2].
    #[schema(schema_with = face_friction_schema)]
    pub friction_coefficient: f64,
    /// Normal restitution e_n, in [0, 1].
    #[schema(schema_with = face_restitution_normal_schema)]
    pub restitution_normal: f64,
    /// Tangential restitution e_t, in [0, 1].
    #[schema(schema_with = face_restitution_tangential_schema)]
    pub restitution_tangential: f64,
    /// Normal contact stiffness k_n (rigid block), N/m, in [1e3, 1e12].
    #[schema(schema_with = face_normal_stiffness_schema)]
    pub normal_stiffness_n_m: f64,
    /// Shear contact stiffness k_s (rigid block), N/m, in [1e3, 1e12].
    #[schema(schema_with = face_shear_stiffness_schema)]
    pub shear_stiffness_n_m: f64,
    /// Critical damping ratio β of the contact dashpot (rigid block), in [0, 1).
    #[schema(schema_with = face_critical_damping_schema)]
    pub critical_damping_ratio: f64,
    /// PFC local damping α (rigid block), in [0, 1).
    #[schema(schema_with = face_local_damping_schema)]
    pub local_damping: f64,
    /// Normal contact law (rigid block).
    #[schema(default = "linear", example = "linear")]
    pub contact_model: ContactModelDto,
    /// The floor's elastic constants in the Hertz law's two-body E* (rigid block,
    /// `contact_model` hertz; null: the coal floor, E_f = 4.38e9 Pa, ν_f = 0.3). The shear
    /// stiffness keeps the rock's ratio 2(1 − ν)/(2 − ν) to the normal tangent stiffness.
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floor_material: Option<FloorMaterialDto>,
    /// Materials of the floor by zone: integer codes over the floor (an ESRI ASCII grid or
    /// polygons, in the floor's own frame) and a material per code, each field defaulting to
    /// the face's (null: one material, the fields above). Echoed in `inputs` as
    /// `{"kind", "sha256"}`.
    #[schema(schema_with = zones_schema)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "super::zones::echo"
    )]
    pub zones: Option<super::zones::ZonesDto>,
}

impl Default for FaceDto {
    fn default() -> Self {
        Self {
            dip_deg: FACE_DIP.value(),
            length_m: FACE_LENGTH.value(),
            floor: FloorDto::default(),
            friction_coefficient: FACE_FRICTION.value(),
            restitution_normal: FACE_RESTITUTION_NORMAL.value(),
            restitution_tangential: FACE_RESTITUTION_TANGENTIAL.value(),
            normal_stiffness_n_m: FACE_NORMAL_STIFFNESS.value(),
            shear_stiffness_n_m: FACE_SHEAR_STIFFNESS.value(),
            critical_damping_ratio: FACE_CRITICAL_DAMPING.value(),
            local_damping: FACE_LOCAL_DAMPING.value(),
            contact_model: ContactModelDto::Linear,
            floor_material: None,
            zones: None,
        }
    }
}

/// Where and how the rock is released.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ReleaseDto {
    /// Vertical lift above the floor point, m, in [0, 1000] (0: starts on the floor).
    #[schema(schema_with = release_drop_height_schema)]
    pub drop_height_m: f64,
    /// Along-dip position of the floor point, m, in [0, length_m): the upper bound depends on
    /// `face.length_m` (at most 10 000 m).
    #[schema(schema_with = release_along_dip_schema)]
    pub along_dip_m: f64,
    /// Across-face position y, m, in [−1000, 1000].
    #[schema(schema_with = release_across_schema)]
    pub across_m: f64,
    /// Initial speed along the floor's down-dip direction, m/s, in [0, 1000].
    #[schema(schema_with = release_speed_schema)]
    pub speed_m_s: f64,
    /// The floor point in plan [x, y], m, instead of `along_dip_m`/`across_m`: in the floor's
    /// own coordinates (map [E, N] on a floor with `map`, face [x, y] otherwise); each in
    /// [−1e7, 1e7]; 422 when it is not over the floor (null: `along_dip_m`, `across_m`).
    #[schema(default = json!(null), example = json!([12.0, 0.5]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position_m: Option<[f64; 2]>,
    /// Initial velocity [vx, vy, vz] in the face frame (x down the dip, y across, z up), m/s,
    /// instead of `speed_m_s`, each in [−1000, 1000]. A rock released on the floor
    /// (`drop_height_m` 0) keeps its component along the floor (warning
    /// `release_velocity_projected` when there was another) (null: `speed_m_s` down the dip).
    #[schema(default = json!(null), example = json!([1.0, 0.0, -0.5]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity_m_s: Option<[f64; 3]>,
    /// Rigid block: orientation [w, x, y, z], the unit quaternion (norm within 1e-6 of 1, then
    /// normalised) turning the block's own axes — those its shape is given in (`dimensions_m`,
    /// `vertices_m`, the ellipsoid's axes) — into the face frame. The block is placed with its
    /// lowest point on the floor's facet under the release point, then lifted by
    /// `drop_height_m` (null: resting face-down on its largest face).
    #[schema(default = json!(null), example = json!([1.0, 0.0, 0.0, 0.0]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientation_wxyz: Option<[f64; 4]>,
    /// Rigid block: initial angular velocity [ωx, ωy, ωz] in the face frame, rad/s, each in
    /// [−1e4, 1e4] (null: not spinning).
    #[schema(default = json!(null), example = json!([0.0, 5.0, 0.0]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angular_velocity_rad_s: Option<[f64; 3]>,
}

impl Default for ReleaseDto {
    fn default() -> Self {
        Self {
            drop_height_m: RELEASE_DROP_HEIGHT.value(),
            along_dip_m: RELEASE_ALONG_DIP.value(),
            across_m: RELEASE_ACROSS.value(),
            speed_m_s: RELEASE_SPEED.value(),
            position_m: None,
            velocity_m_s: None,
            orientation_wxyz: None,
            angular_velocity_rad_s: None,
        }
    }
}

/// Ground motion of the point mass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum MotionDto {
    /// Coulomb sliding.
    #[default]
    Slide,
    /// Rolling without slip as a sphere (needs μ ≥ (2/7) tan θ).
    Roll,
}

/// Options of the lumped-mass method.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LumpedMassDto {
    /// Ground motion.
    #[schema(default = "slide", example = "slide")]
    pub motion: MotionDto,
    /// Normal rebound speed below which the ground phase starts, m/s, in [0, 100].
    #[schema(schema_with = stop_normal_speed_schema)]
    pub stop_normal_speed_m_s: f64,
}

impl Default for LumpedMassDto {
    fn default() -> Self {
        Self {
            motion: MotionDto::Slide,
            stop_normal_speed_m_s: STOP_NORMAL_SPEED.value(),
        }
    }
}

/// Options of the rigid-block method.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RigidBlockDto {
    /// Time step, s, in (0, 1] (default: safety × Δt_crit).
    #[schema(schema_with = time_step_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_step_s: Option<f64>,
    /// Safety factor on the critical time step, in (0, 1] (one above 0.3 is used as 0.3, with
    /// the warning `time_step_safety_capped`).
    #[schema(schema_with = time_step_safety_schema)]
    pub time_step_safety: f64,
}

impl Default for RigidBlockDto {
    fn default() -> Self {
        Self {
            time_step_s: None,
            time_step_safety: TIME_STEP_SAFETY.value(),
        }
    }
}

/// Kind of distribution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum DistributionKind {
    /// Uniform on [min, max].
    #[default]
    Uniform,
    /// Normal {mean, std}.
    Normal,
    /// Normal {mean, std} resampled until inside [min, max].
    TruncatedNormal,
}

/// A distribution of an uncertain parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct DistributionDto {
    /// Kind of distribution.
    #[schema(default = "uniform", example = "uniform")]
    pub distribution: DistributionKind,
    /// Lower bound (uniform, truncated_normal), inside the parameter's own range: restitution
    /// [0, 1], friction [0, 2], damping ratio [0, 1).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = 0.2)]
    pub min: Option<f64>,
    /// Upper bound (uniform, truncated_normal), at least `min` and inside the parameter's own
    /// range: restitution [0, 1], friction [0, 2], damping ratio [0, 1).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = 0.4)]
    pub max: Option<f64>,
    /// Mean (normal, truncated_normal), in [−1000, 1000], or in the field's own range where that
    /// is wider (`density_kg_m3`: up to 20 000).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = 0.3)]
    pub mean: Option<f64>,
    /// Standard deviation, in [0, 1000], or up to the width of the field's own range where that
    /// is wider (normal, truncated_normal).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    #[schema(example = 0.05)]
    pub std: Option<f64>,
}

impl DistributionDto {
    pub(crate) fn uniform(min: f64, max: f64) -> Self {
        Self {
            distribution: DistributionKind::Uniform,
            min: Some(min),
            max: Some(max),
            mean: None,
            std: None,
        }
    }

    /// Checks the fields the kind needs (bounds within [lo, hi]) and converts.
    pub(crate) fn resolve(&self, base: &str, lo: f64, hi: f64, ck: &mut Checker) -> Distribution {
        let p = |f: &str| format!("{base}/{f}");
        let need = |v: Option<f64>, f: &str, ck: &mut Checker| -> f64 {
            match v {
                Some(x) => x,
                None => {
                    ck.push(
                        p(f),
                        Value::Null,
                        format!("a {:?} distribution needs `{f}`", self.distribution)
                            .to_lowercase(),
                    );
                    0.0
                }
            }
        };
        let bounds = |ck: &mut Checker| {
            let a = need(self.min, "min", ck);
            let b = need(self.max, "max", ck);
            let ok_a = ck.closed(&p("min"), a, lo, hi, "");
            let ok_b = ck.closed(&p("max"), b, lo, hi, "");
            if ok_a && ok_b && a > b {
                ck.push(p("max"), num(b), format!("must be at least min = {a}"));
            }
            (a, b)
        };
        let normal = |ck: &mut Checker| {
            let m = need(self.mean, "mean", ck);
            let s = need(self.std, "std", ck);
            // a field whose own range is wider (a density) takes a mean and spread of its size
            ck.closed(&p("mean"), m, lo.min(-1e3), hi.max(1e3), "");
            ck.closed(&p("std"), s, 0.0, (hi - lo).max(1e3), "");
            (m, s)
        };
        match self.distribution {
            DistributionKind::Uniform => {
                let (min, max) = bounds(ck);
                Distribution::Uniform { min, max }
            }
            DistributionKind::Normal => {
                let (mean, std) = normal(ck);
                Distribution::Normal { mean, std }
            }
            DistributionKind::TruncatedNormal => {
                let (mean, std) = normal(ck);
                let (min, max) = bounds(ck);
                // Resampling must terminate: the interval has to carry real probability.
                if ck.is_ok() {
                    let reachable = if std == 0.0 {
                        (min..=max).contains(&mean)
                    } else {
                        (min - mean) / std < 6.0 && (max - mean) / std > -6.0 && max > min
                    };
                    if !reachable {
                        ck.push(
                            p("max"),
                            num(max),
                            "the interval [min, max] must lie within 6 standard deviations of the mean (resampling would not end)",
                        );
                    }
                }
                Distribution::TruncatedNormal {
                    mean,
                    std,
                    min,
                    max,
                }
            }
        }
    }
}

/// Declares a Monte Carlo request object: the draws of every ensemble (runs, seed, e_n, e_t, μ,
/// β), then the object's own optional draws; its `Default` (200 runs, seed 42, U[0.2, 0.4],
/// U[0.7, 0.9], the rest null) and its [`MonteCarloDto`] part. One declaration for `/v1/migration`
/// and `/v1/scene` (serde's `flatten` cannot be combined with `deny_unknown_fields`).
macro_rules! monte_carlo_dto {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $( $(#[$fmeta:meta])* pub $field:ident: Option<$ty:ty>, )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
        #[serde(deny_unknown_fields, default)]
        pub struct $name {
            /// Number of runs, in [1, limit]: the server's `max_monte_carlo_runs` (/v1/presets
            /// `limits`), by default 1 000 000, the maximum shown here.
            #[schema(default = 200, minimum = 1, maximum = 1000000, example = 200)]
            pub runs: u64,
            /// Seed (any u64); the same request and seed give the same bytes.
            #[schema(default = 42, example = 42)]
            pub seed: u64,
            /// e_n, drawn at every impact, clipped to [0, 1] (default U[0.2, 0.4]; lumped mass
            /// only: refused when sent with the rigid block).
            #[schema(value_type = DistributionDto)]
            pub restitution_normal: $crate::http::dto::common::Sent<DistributionDto>,
            /// e_t, drawn at every impact after e_n, clipped to [0, 1] (default U[0.7, 0.9];
            /// lumped mass only: refused when sent with the rigid block).
            #[schema(value_type = DistributionDto)]
            pub restitution_tangential: $crate::http::dto::common::Sent<DistributionDto>,
            /// μ, drawn once per run (null: the face's μ for every run).
            #[schema(default = json!(null))]
            #[serde(skip_serializing_if = "Option::is_none")]
            pub friction_coefficient: Option<DistributionDto>,
            /// β of the contact dashpot, drawn once per run after μ, in [0, 1) (rigid block only;
            /// null: the face's β for every run).
            #[schema(default = json!(null))]
            #[serde(skip_serializing_if = "Option::is_none")]
            pub critical_damping_ratio: Option<DistributionDto>,
            /// The release velocity [vx, vy, vz] in the face frame, m/s, drawn once per run,
            /// each component from its distribution within [−1000, 1000], from a stream of the
            /// run's own apart from its friction and restitution draws (null: the release's
            /// velocity for every run). A release on the floor keeps the drawn velocity's
            /// component along the floor.
            #[schema(default = json!(null), example = json!([
                {"distribution": "uniform", "min": 0.0, "max": 1.0},
                {"distribution": "uniform", "min": -0.5, "max": 0.5},
                {"distribution": "uniform", "min": 0.0, "max": 0.0}
            ]))]
            #[serde(skip_serializing_if = "Option::is_none")]
            pub release_velocity_m_s: Option<[DistributionDto; 3]>,
            /// Rigid block: the release orientation of every run, `fixed` (the release's) or
            /// `uniform` (a uniformly random rotation per run, drawn after the release velocity
            /// from the same stream).
            #[schema(default = "fixed", example = "fixed")]
            pub release_orientation: $crate::http::dto::migration::ReleaseOrientationDto,
            $(
                $(#[$fmeta])*
                #[schema(default = json!(null))]
                #[serde(skip_serializing_if = "Option::is_none")]
                pub $field: Option<$ty>,
            )*
        }

        impl Default for $name {
            fn default() -> Self {
                Self {
                    runs: $crate::physics::migration::defaults::RUNS,
                    seed: $crate::physics::migration::defaults::SEED,
                    restitution_normal: $crate::http::dto::common::Sent::default_value(
                        DistributionDto::uniform(0.2, 0.4),
                    ),
                    restitution_tangential: $crate::http::dto::common::Sent::default_value(
                        DistributionDto::uniform(0.7, 0.9),
                    ),
                    friction_coefficient: None,
                    critical_damping_ratio: None,
                    release_velocity_m_s: None,
                    release_orientation: $crate::http::dto::migration::ReleaseOrientationDto::Fixed,
                    $( $field: None, )*
                }
            }
        }

        impl From<&$name> for MonteCarloDto {
            #[allow(clippy::needless_update)]
            fn from(m: &$name) -> Self {
                Self {
                    runs: m.runs,
                    seed: m.seed,
                    restitution_normal: m.restitution_normal,
                    restitution_tangential: m.restitution_tangential,
                    friction_coefficient: m.friction_coefficient,
                    critical_damping_ratio: m.critical_damping_ratio,
                    release_velocity_m_s: m.release_velocity_m_s,
                    release_orientation: m.release_orientation,
                    // a scene's own fields (its target among them) stay with the scene
                    ..MonteCarloDto::default()
                }
            }
        }
    };
}
pub(crate) use monte_carlo_dto;

/// How the release orientation varies between the runs of an ensemble.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum ReleaseOrientationDto {
    /// The release's orientation for every run.
    #[default]
    Fixed,
    /// A uniformly random rotation per run (rigid block).
    Uniform,
}

impl ReleaseDto {
    /// The physics release (checked by [`MigrationRequest`]'s checks); the orientation
    /// normalised.
    pub(crate) fn resolve(&self) -> Release {
        Release {
            drop_height: self.drop_height_m,
            along_dip: self.along_dip_m,
            across: self.across_m,
            speed: self.speed_m_s,
            point: self.position_m,
            velocity: self.velocity_m_s,
            orientation: self.orientation_wxyz.map(|q| {
                let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
                q.map(|c| c / n)
            }),
            angular_velocity: self.angular_velocity_rad_s,
        }
    }

    /// The release's own checks under `base` ("/release"): the vectors' components in their
    /// ranges, a unit quaternion, one of each pair of alternatives; the orientation and spin
    /// for the rigid block only.
    pub(crate) fn check(&self, base: &str, rigid: bool, ck: &mut Checker) {
        let p = |f: &str| format!("{base}/{f}");
        if let Some(pt) = self.position_m {
            for (k, v) in pt.iter().enumerate() {
                ck.closed(&format!("{base}/position_m/{k}"), *v, -1e7, 1e7, "m");
            }
            for (name, v) in [
                ("along_dip_m", self.along_dip_m),
                ("across_m", self.across_m),
            ] {
                if v != 0.0 {
                    ck.push(
                        p(name),
                        num(v),
                        "give the release point either as position_m or as along_dip_m and \
                         across_m, not both",
                    );
                }
            }
        }
        if let Some(v) = self.velocity_m_s {
            for (k, c) in v.iter().enumerate() {
                ck.closed(
                    &format!("{base}/velocity_m_s/{k}"),
                    *c,
                    -1000.0,
                    1000.0,
                    "m/s",
                );
            }
            if self.speed_m_s != 0.0 {
                ck.push(
                    p("speed_m_s"),
                    num(self.speed_m_s),
                    "give the release velocity either as velocity_m_s or as speed_m_s, not both",
                );
            }
        }
        if let Some(q) = self.orientation_wxyz {
            let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
            let mut inside = true;
            for (k, c) in q.iter().enumerate() {
                inside &= ck.closed(
                    &format!("{base}/orientation_wxyz/{k}"),
                    *c,
                    -1.000_001,
                    1.000_001,
                    "",
                );
            }
            // A component out of range is named already; only a whole in-range orientation is
            // checked further.
            if inside && !rigid {
                ck.push(
                    p("orientation_wxyz"),
                    json!(q),
                    "an orientation belongs to the rigid-block method (a point mass has none)",
                );
            } else if inside && !(n.is_finite() && (n - 1.0).abs() <= 1e-6) {
                ck.push(
                    p("orientation_wxyz"),
                    json!(q),
                    format!("must be a unit quaternion [w, x, y, z]: its norm {n} is not within 1e-6 of 1"),
                );
            }
        }
        if let Some(w) = self.angular_velocity_rad_s {
            let mut inside = true;
            for (k, c) in w.iter().enumerate() {
                inside &= ck.closed(
                    &format!("{base}/angular_velocity_rad_s/{k}"),
                    *c,
                    -1e4,
                    1e4,
                    "rad/s",
                );
            }
            if inside && !rigid {
                ck.push(
                    p("angular_velocity_rad_s"),
                    json!(w),
                    "an initial spin belongs to the rigid-block method (the lumped mass's spin \
                     follows from its motion)",
                );
            }
        }
    }
}

monte_carlo_dto! {
    /// A seeded Monte Carlo ensemble.
    pub struct MonteCarloDto {
        /// Stop when a percentile of the arrival speed is precise enough: checked at 1000,
        /// 2000, 4000, … runs and at `runs`, which is then the most runs allowed (null: run
        /// every run).
        pub target: Option<super::target::ArrivalTargetDto>,
    }
}

/// What to report besides the arrival.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MigrationOutputDto {
    /// Sample the (nominal) trajectory.
    #[schema(default = false, example = false)]
    pub trajectory: bool,
    /// Trajectory sample interval, s, in [1e-6, 100].
    #[schema(schema_with = sample_interval_schema)]
    pub sample_interval_s: f64,
    /// Report the events of the (nominal) run.
    #[schema(default = true, example = true)]
    pub events: bool,
    /// Per-run summaries as CSV (Monte Carlo).
    #[schema(default = false, example = false)]
    pub runs_csv: bool,
    /// Per-cell maps of the ensemble (Monte Carlo; null: none, and no work spent on them).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub maps: Option<super::maps::MapsDto>,
    /// Run the other method on the same case and ensemble too and say whether the two agree,
    /// and where they do not, why and which to trust (`method_comparison`; a migration
    /// request's only: a scene compares with its own `compare_methods`).
    #[schema(default = false, example = false)]
    pub compare_methods: bool,
}

impl Default for MigrationOutputDto {
    fn default() -> Self {
        Self {
            trajectory: false,
            sample_interval_s: SAMPLE_INTERVAL.value(),
            events: true,
            runs_csv: false,
            maps: None,
            compare_methods: false,
        }
    }
}

/// Rockfall migration down the face: one trajectory, or a seeded Monte Carlo ensemble.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MigrationRequest {
    /// Method.
    #[schema(default = "lumped_mass", example = "lumped_mass")]
    pub method: MethodDto,
    /// Gravity g, m/s², in [0.1, 100].
    #[schema(schema_with = gravity_schema)]
    pub gravity_m_s2: f64,
    /// The working face.
    pub face: FaceDto,
    /// The rock block (its shape's own mass is used).
    pub rock: RockDto,
    /// The release.
    pub release: ReleaseDto,
    /// Lumped-mass options.
    pub lumped_mass: LumpedMassDto,
    /// Rigid-block options.
    pub rigid_block: RigidBlockDto,
    /// Stop at this time instead of the lower end, s, in (0, 1e5].
    #[schema(schema_with = migration_end_time_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub end_time_s: Option<f64>,
    /// Monte Carlo ensemble (null: one deterministic run).
    #[schema(default = json!(null))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<MonteCarloDto>,
    /// Optional outputs.
    pub output: MigrationOutputDto,
}

impl Default for MigrationRequest {
    fn default() -> Self {
        Self {
            method: MethodDto::LumpedMass,
            gravity_m_s2: GRAVITY.value(),
            face: FaceDto::default(),
            rock: RockDto::default(),
            release: ReleaseDto::default(),
            lumped_mass: LumpedMassDto::default(),
            rigid_block: RigidBlockDto::default(),
            end_time_s: None,
            monte_carlo: None,
            output: MigrationOutputDto::default(),
        }
    }
}

impl MigrationRequest {
    /// Range checks, derived defaults and conversion; `self` becomes the resolved request.
    pub fn resolve(&mut self, config: &Config) -> Result<MigrationCase, ApiError> {
        self.resolve_in(config, Layout::Request)
    }

    /// [`Self::resolve`] with the output fields named as in `layout` (a scene checks its
    /// `migration_output` here).
    pub fn resolve_in(
        &mut self,
        config: &Config,
        layout: Layout,
    ) -> Result<MigrationCase, ApiError> {
        let mut ck = Checker::new();
        let rigid = self.method == MethodDto::RigidBlock;
        GRAVITY.check(&mut ck, "/gravity_m_s2", self.gravity_m_s2);
        self.check_face(&mut ck);
        let floor = resolve_floor(&mut self.face.floor, &mut ck, config.max_floor_bytes);
        let rock = self.rock.resolve("/rock", false, &mut ck);
        self.check_motion(rigid, layout, &mut ck);
        let (monte_carlo, damping_distribution) = self.resolve_monte_carlo(config, rigid, &mut ck);
        let zones = super::zones::resolve_zones(
            &self.face,
            monte_carlo.as_ref(),
            damping_distribution,
            &mut ck,
        );
        if self.output.compare_methods && layout == Layout::Scene {
            ck.push(
                layout.migration_output("compare_methods"),
                json!(true),
                "a scene compares the methods with its own compare_methods",
            );
        }
        if self.output.runs_csv && monte_carlo.is_none() {
            ck.push(
                layout.migration_output("runs_csv"),
                json!(true),
                "per-run summaries need monte_carlo",
            );
        }
        let maps = self.resolve_maps(config, layout, monte_carlo.as_ref(), &mut ck);
        let target = self
            .monte_carlo
            .as_ref()
            .and_then(|m| m.target.as_ref())
            .and_then(|t| t.resolve("/monte_carlo/target", &mut ck));
        ck.finish()?;
        let f = &self.face;
        let rigid_block = RigidBlockOptions {
            time_step: self.rigid_block.time_step_s,
            time_step_safety: self.rigid_block.time_step_safety,
            normal_stiffness: f.normal_stiffness_n_m,
            shear_stiffness: f.shear_stiffness_n_m,
            critical_damping_ratio: f.critical_damping_ratio,
            local_damping: f.local_damping,
            contact_model: match f.contact_model {
                ContactModelDto::Linear => ContactModel::Linear,
                ContactModelDto::Hertz => ContactModel::Hertz,
            },
            floor_material: f.floor_material.map(|m| FloorMaterial {
                elastic_modulus: m.elastic_modulus_pa,
                poisson_ratio: m.poisson_ratio,
            }),
            critical_damping_ratio_distribution: damping_distribution,
            max_steps: config.max_rigid_steps,
        };
        let o = &self.output;
        Ok(MigrationCase {
            method: if rigid {
                Method::RigidBlock
            } else {
                Method::LumpedMass
            },
            rigid_block,
            gravity: self.gravity_m_s2,
            face: Face {
                dip_deg: self.face.dip_deg,
                length: self.face.length_m,
                floor,
                friction_coefficient: self.face.friction_coefficient,
                restitution_normal: self.face.restitution_normal,
                restitution_tangential: self.face.restitution_tangential,
                zones,
            },
            rock,
            release: self.release.resolve(),
            lumped_mass: LumpedMassOptions {
                motion: match self.lumped_mass.motion {
                    MotionDto::Slide => Motion::Slide,
                    MotionDto::Roll => Motion::Roll,
                },
                stop_normal_speed: self.lumped_mass.stop_normal_speed_m_s,
            },
            end_time: self.end_time_s,
            monte_carlo,
            output: OutputOptions {
                trajectory: o.trajectory,
                sample_interval: o.sample_interval_s,
                events: o.events,
                runs_csv: o.runs_csv,
                max_samples: config.max_samples as usize,
                maps,
                compare_methods: o.compare_methods,
            },
            target,
            ..MigrationCase::default()
        })
    }

    /// The face's numbers, each in its documented range.
    fn check_face(&self, ck: &mut Checker) {
        let f = &self.face;
        for (field, pointer, v) in [
            (FACE_DIP, "/face/dip_deg", f.dip_deg),
            (FACE_LENGTH, "/face/length_m", f.length_m),
            (
                FACE_FRICTION,
                "/face/friction_coefficient",
                f.friction_coefficient,
            ),
            (
                FACE_RESTITUTION_NORMAL,
                "/face/restitution_normal",
                f.restitution_normal,
            ),
            (
                FACE_RESTITUTION_TANGENTIAL,
                "/face/restitution_tangential",
                f.restitution_tangential,
            ),
            (
                FACE_NORMAL_STIFFNESS,
                "/face/normal_stiffness_n_m",
                f.normal_stiffness_n_m,
            ),
            (
                FACE_SHEAR_STIFFNESS,
                "/face/shear_stiffness_n_m",
                f.shear_stiffness_n_m,
            ),
            (
                FACE_CRITICAL_DAMPING,
                "/face/critical_damping_ratio",
                f.critical_damping_ratio,
            ),
            (FACE_LOCAL_DAMPING, "/face/local_damping", f.local_damping),
        ] {
            field.check(ck, pointer, v);
        }
        if let Some(m) = f.floor_material {
            FLOOR_MATERIAL_MODULUS.check(
                ck,
                "/face/floor_material/elastic_modulus_pa",
                m.elastic_modulus_pa,
            );
            FLOOR_MATERIAL_POISSON.check(ck, "/face/floor_material/poisson_ratio", m.poisson_ratio);
        }
    }

    /// The rock's shape for the method, the release (its along-dip position below the face
    /// length), the methods' options, the end time and the trajectory's sample interval.
    fn check_motion(&self, rigid: bool, layout: Layout, ck: &mut Checker) {
        if !rigid
            && matches!(
                self.rock.shape,
                super::common::ShapeKind::Polyhedron | super::common::ShapeKind::RandomPolyhedron
            )
        {
            ck.push(
                "/rock/shape",
                json!(self.rock.shape),
                "polyhedra belong to the rigid-block method; the lumped mass takes cube, sphere, cuboid or ellipsoid",
            );
        }
        let r = &self.release;
        RELEASE_DROP_HEIGHT.check(ck, "/release/drop_height_m", r.drop_height_m);
        // The documented maximum is the longest face's; the bound enforced is below length_m.
        ck.range(
            "/release/along_dip_m",
            r.along_dip_m,
            RELEASE_ALONG_DIP.lo,
            Open(self.face.length_m),
            RELEASE_ALONG_DIP.unit,
        );
        RELEASE_ACROSS.check(ck, "/release/across_m", r.across_m);
        RELEASE_SPEED.check(ck, "/release/speed_m_s", r.speed_m_s);
        r.check("/release", rigid, ck);
        STOP_NORMAL_SPEED.check(
            ck,
            "/lumped_mass/stop_normal_speed_m_s",
            self.lumped_mass.stop_normal_speed_m_s,
        );
        if let Some(dt) = self.rigid_block.time_step_s {
            TIME_STEP.check(ck, "/rigid_block/time_step_s", dt);
        }
        TIME_STEP_SAFETY.check(
            ck,
            "/rigid_block/time_step_safety",
            self.rigid_block.time_step_safety,
        );
        if let Some(t) = self.end_time_s {
            MIGRATION_END_TIME.check(ck, "/end_time_s", t);
        }
        SAMPLE_INTERVAL.check(
            ck,
            &layout.pointer(Param::TrajectorySampleInterval),
            self.output.sample_interval_s,
        );
    }

    /// The ensemble (runs, seed, the lumped mass's restitution draws, friction) and the rigid
    /// block's damping-ratio draw; each method refuses the other's draws.
    fn resolve_monte_carlo(
        &self,
        config: &Config,
        rigid: bool,
        ck: &mut Checker,
    ) -> (Option<MonteCarlo>, Option<Distribution>) {
        let Some(mc) = &self.monte_carlo else {
            return (None, None);
        };
        ck.count("/monte_carlo/runs", mc.runs, 1, config.max_runs, "runs");
        let monte_carlo = MonteCarlo {
            runs: mc.runs,
            seed: mc.seed,
            restitution_normal: mc.restitution_normal.value.resolve(
                "/monte_carlo/restitution_normal",
                0.0,
                1.0,
                ck,
            ),
            restitution_tangential: mc.restitution_tangential.value.resolve(
                "/monte_carlo/restitution_tangential",
                0.0,
                1.0,
                ck,
            ),
            friction_coefficient: mc
                .friction_coefficient
                .map(|d| d.resolve("/monte_carlo/friction_coefficient", 0.0, 2.0, ck)),
            release_velocity: mc.release_velocity_m_s.map(|ds| {
                [0, 1, 2].map(|k| {
                    ds[k].resolve(
                        &format!("/monte_carlo/release_velocity_m_s/{k}"),
                        -1000.0,
                        1000.0,
                        ck,
                    )
                })
            }),
            random_orientation: mc.release_orientation == ReleaseOrientationDto::Uniform,
        };
        if mc.release_orientation == ReleaseOrientationDto::Uniform {
            if !rigid {
                ck.push(
                    "/monte_carlo/release_orientation",
                    json!("uniform"),
                    "a random orientation belongs to the rigid-block method",
                );
            } else if self.release.orientation_wxyz.is_some() {
                ck.push(
                    "/monte_carlo/release_orientation",
                    json!("uniform"),
                    "release.orientation_wxyz fixes the orientation that `uniform` would draw: \
                     give one of them",
                );
            }
        }
        let damping_distribution = mc.critical_damping_ratio.as_ref().map(|d| {
            if !rigid {
                ck.push(
                    "/monte_carlo/critical_damping_ratio",
                    serde_json::to_value(d).unwrap_or(Value::Null),
                    "the critical damping ratio belongs to the rigid-block method",
                );
            }
            d.resolve("/monte_carlo/critical_damping_ratio", 0.0, 0.999, ck)
        });
        if rigid {
            // api.md: restitution distributions given explicitly with the rigid block are 422,
            // even when equal to their defaults (which apply to the lumped mass only)
            for (name, d) in [
                ("restitution_normal", &mc.restitution_normal),
                ("restitution_tangential", &mc.restitution_tangential),
            ] {
                if d.sent {
                    ck.push(
                        format!("/monte_carlo/{name}"),
                        serde_json::to_value(d.value).unwrap_or(Value::Null),
                        "the rigid block has no restitution: its ensemble varies friction_coefficient and critical_damping_ratio",
                    );
                }
            }
        }
        (Some(monte_carlo), damping_distribution)
    }
}

impl MigrationRequest {
    /// The map grid of `output.maps` (None when not asked for), checked against the limits.
    fn resolve_maps(
        &mut self,
        config: &Config,
        layout: Layout,
        monte_carlo: Option<&MonteCarlo>,
        ck: &mut Checker,
    ) -> Option<migration::maps::MapGrid> {
        let length = self.face.length_m;
        self.output
            .maps
            .as_mut()
            .and_then(|m| m.resolve(config, layout, length, monte_carlo.map(|mc| mc.runs), ck))
    }
}

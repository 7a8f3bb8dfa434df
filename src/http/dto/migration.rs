//! `POST /v1/migration`: request, response, validation.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use sha2::{Digest, Sha256};
use utoipa::ToSchema;

use super::common::Bound::{Closed, Open};
use super::common::{
    Checker, FieldDefault, Meta, NumberField, PlanStep, RockDto, Warning, number_schemas, some,
};
use super::floor::{self as formats, Sorted};
use super::param::Layout;
use crate::config::Config;
use crate::http::error::{ApiError, num};
use crate::physics::Param;
use crate::physics::migration::{
    self, ContactModel, ContourLine, Distribution, EventKind, Face, FloorSpec, LumpedMassOptions,
    MapFrame, Method, MigrationCase, MigrationResult, MonteCarlo, Motion, OutputOptions, Phase,
    Release, RigidBlockOptions, RunSummary, StopReason, Summary,
};

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
        FieldDefault::Value(45.0), Closed(5.0), Closed(80.0), "°", 45.0;
    /// `face.length_m`.
    FACE_LENGTH, face_length_schema: "Face length along dip S, m, in (0, 10000].",
        FieldDefault::Value(120.0), Open(0.0), Closed(10000.0), "m", 120.0;
    /// `face.friction_coefficient`.
    FACE_FRICTION, face_friction_schema: "Coulomb friction μ, in [0, 2].",
        FieldDefault::Value(0.2), Closed(0.0), Closed(2.0), "", 0.2;
    /// `face.restitution_normal`.
    FACE_RESTITUTION_NORMAL, face_restitution_normal_schema: "Normal restitution e_n, in [0, 1].",
        FieldDefault::Value(0.3), Closed(0.0), Closed(1.0), "", 0.3;
    /// `face.restitution_tangential`.
    FACE_RESTITUTION_TANGENTIAL, face_restitution_tangential_schema:
        "Tangential restitution e_t, in [0, 1].",
        FieldDefault::Value(0.8), Closed(0.0), Closed(1.0), "", 0.8;
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
         `face.length_m` (at most 10 000 m).",
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
        "Safety factor on the critical time step, in (0, 1].",
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
    #[serde(deserialize_with = "some")]
    #[schema(default = json!([0.0, 0.0]), example = json!([0.0, -5.0]))]
    pub origin_m: Option<[f64; 2]>,
    /// Grid spacing d, m, in [0.01, 100].
    #[serde(deserialize_with = "some")]
    #[schema(schema_with = floor_spacing_schema)]
    pub spacing_m: Option<f64>,
    /// Grid heights: `heights_m[i][j]` is z at (x₀ + j·d, y₀ + i·d), m; at most 4096 × 4096.
    #[serde(deserialize_with = "some")]
    #[schema(example = json!([[0.0, -1.0, -2.0], [0.0, -1.0, -2.0]]))]
    pub heights_m: Option<Vec<Vec<f64>>>,
    /// A grid as the text of an ESRI ASCII file (`ncols …`), instead of `origin_m`, `spacing_m`
    /// and `heights_m`: square cells, heights at the cells' centres, the first data row the
    /// northernmost, one row per line, NODATA cells are holes in the floor.
    #[serde(deserialize_with = "some")]
    #[schema(
        example = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n0 -1 -2\n0 -1 -2\n"
    )]
    pub esri_ascii: Option<String>,
    /// Contour polylines with elevations.
    #[serde(deserialize_with = "some")]
    #[schema(example = json!([{"elevation_m": 0.0, "points_m": [[0.0, -5.0], [0.0, 5.0]]}, {"elevation_m": -10.0, "points_m": [[10.0, -5.0], [10.0, 5.0]]}]))]
    pub contours: Option<Vec<ContourDto>>,
    /// Contours as a GeoJSON FeatureCollection of LineString / MultiLineString features in
    /// projected metres, instead of `contours`.
    #[serde(deserialize_with = "some")]
    #[schema(schema_with = geojson_schema)]
    pub geojson: Option<Value>,
    /// Property of a GeoJSON feature holding its elevation, m (default "elevation"; without
    /// it, the third coordinate).
    #[serde(deserialize_with = "some")]
    #[schema(default = "elevation", example = "elevation")]
    pub elevation_property: Option<String>,
    /// Largest spacing of resampled contour points, m, in [0.01, 100] (default 1).
    #[serde(deserialize_with = "some")]
    #[schema(schema_with = floor_resolution_schema)]
    pub resolution_m: Option<f64>,
    /// Map coordinates: the grid or contours are given in (E, N) and placed on the face by a
    /// rigid transform.
    #[serde(deserialize_with = "some")]
    pub map: Option<MapDto>,
    /// SHA-256 of the floor as received (set when resolved; echoed in `inputs`).
    #[serde(skip)]
    #[schema(ignore)]
    pub sha256: Option<String>,
    /// Whether GeoJSON contours without `map` lie within ±180 × ±90 (set when resolved).
    #[serde(skip)]
    #[schema(ignore)]
    pub geographic: bool,
}

/// Schema of the `geojson` field: a GeoJSON object (RFC 7946), with an example.
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
}

impl Default for ReleaseDto {
    fn default() -> Self {
        Self {
            drop_height_m: RELEASE_DROP_HEIGHT.value(),
            along_dip_m: RELEASE_ALONG_DIP.value(),
            across_m: RELEASE_ACROSS.value(),
            speed_m_s: RELEASE_SPEED.value(),
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
    /// Safety factor on the critical time step, in (0, 1].
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
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "some")]
    #[schema(example = 0.2)]
    pub min: Option<f64>,
    /// Upper bound (uniform, truncated_normal), at least `min` and inside the parameter's own
    /// range: restitution [0, 1], friction [0, 2], damping ratio [0, 1).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "some")]
    #[schema(example = 0.4)]
    pub max: Option<f64>,
    /// Mean (normal, truncated_normal), in [−1000, 1000].
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "some")]
    #[schema(example = 0.3)]
    pub mean: Option<f64>,
    /// Standard deviation, in [0, 1000] (normal, truncated_normal).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "some")]
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
            ck.closed(&p("mean"), m, -1e3, 1e3, "");
            ck.closed(&p("std"), s, 0.0, 1e3, "");
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
                    runs: 200,
                    seed: 42,
                    restitution_normal: $crate::http::dto::common::Sent::default_value(
                        DistributionDto::uniform(0.2, 0.4),
                    ),
                    restitution_tangential: $crate::http::dto::common::Sent::default_value(
                        DistributionDto::uniform(0.7, 0.9),
                    ),
                    friction_coefficient: None,
                    critical_damping_ratio: None,
                    $( $field: None, )*
                }
            }
        }

        impl From<&$name> for MonteCarloDto {
            fn from(m: &$name) -> Self {
                Self {
                    runs: m.runs,
                    seed: m.seed,
                    restitution_normal: m.restitution_normal,
                    restitution_tangential: m.restitution_tangential,
                    friction_coefficient: m.friction_coefficient,
                    critical_damping_ratio: m.critical_damping_ratio,
                }
            }
        }
    };
}
pub(crate) use monte_carlo_dto;

monte_carlo_dto! {
    /// A seeded Monte Carlo ensemble.
    pub struct MonteCarloDto {}
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
}

impl Default for MigrationOutputDto {
    fn default() -> Self {
        Self {
            trajectory: false,
            sample_interval_s: SAMPLE_INTERVAL.value(),
            events: true,
            runs_csv: false,
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

/// Refuses a floor whose estimated memory exceeds the configured limit, naming `field`.
fn check_floor_memory(
    ck: &mut Checker,
    field: String,
    value: Value,
    what: &str,
    bytes: f64,
    limit: u64,
) {
    if bytes > limit as f64 {
        ck.push(
            field,
            value,
            format!(
                "{what} would need about {:.0} MB, more than the limit of {:.0} MB \
                 (--max-floor-bytes, GANGUE_MAX_FLOOR_BYTES; see /v1/presets limits)",
                bytes / 1e6,
                limit as f64 / 1e6
            ),
        );
    }
}

/// JSON Pointer of the floor's field `name`.
fn floor_pointer(name: &str) -> String {
    format!("/face/floor/{name}")
}

/// The values a floor request sent, as an error echoes them (a grid's heights as
/// [rows, columns], contours as their count, long texts as their length).
struct SentFloor {
    origin: Option<Value>,
    spacing: Option<Value>,
    heights: Option<Value>,
    contours: Option<Value>,
    resolution: Option<Value>,
    esri: Option<Value>,
    geojson: Option<Value>,
    property: Option<Value>,
    map: Option<Value>,
}

impl SentFloor {
    /// The echoes of the fields `f` sent.
    fn of(f: &FloorDto) -> Self {
        Self {
            origin: f.origin_m.map(|o| json!(o)),
            spacing: f.spacing_m.map(num),
            heights: f
                .heights_m
                .as_ref()
                .map(|h| json!([h.len(), h.first().map_or(0, Vec::len)])),
            contours: f.contours.as_ref().map(|c| json!(c.len())),
            resolution: f.resolution_m.map(num),
            esri: f
                .esri_ascii
                .as_ref()
                .map(|t| json!(format!("{} characters", t.len()))),
            geojson: f.geojson.as_ref().map(|_| json!("a GeoJSON object")),
            property: f.elevation_property.as_ref().map(|s| json!(s)),
            map: f.map.map(|m| json!(m)),
        }
    }
}

/// The checks of one floor request: its checker, what it sent, its map frame (map
/// coordinates) and the memory limit, bytes.
struct FloorCheck<'a> {
    ck: &'a mut Checker,
    sent: SentFloor,
    map: Option<MapFrame>,
    max_floor_bytes: u64,
}

/// Contour lines with the pointers to each one's points and elevation.
type PointedLines = (Vec<ContourDto>, Vec<(String, String)>);

impl FloorCheck<'_> {
    /// Refuses a field `name` that the floor's kind does not take.
    fn stray(&mut self, name: &str, sent: Option<Value>, kind: &str) {
        if let Some(v) = sent {
            self.ck
                .push(floor_pointer(name), v, format!("not a field of {kind}"));
        }
    }

    /// Offset (m) of the map frame's origin from the floor's coordinates' origin.
    fn shift(&self) -> [f64; 2] {
        self.map.map_or([0.0, 0.0], |m| m.origin)
    }

    /// The floor in map coordinates, when a map frame was given.
    fn wrap(&self, spec: FloorSpec) -> FloorSpec {
        match self.map {
            Some(map) => FloorSpec::Mapped {
                floor: Box::new(spec),
                map,
            },
            None => spec,
        }
    }

    /// The plane: no other field allowed.
    fn plane(&mut self) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("origin_m", s.origin.take()),
            ("spacing_m", s.spacing.take()),
            ("heights_m", s.heights.take()),
            ("esri_ascii", s.esri.take()),
            ("contours", s.contours.take()),
            ("geojson", s.geojson.take()),
            ("elevation_property", s.property.take()),
            ("resolution_m", s.resolution.take()),
            ("map", s.map.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "a plane floor");
        }
        FloorSpec::Plane
    }

    /// A grid floor, from an ESRI ASCII text or from its heights.
    fn grid(&mut self, f: &mut FloorDto) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("contours", s.contours.take()),
            ("geojson", s.geojson.take()),
            ("elevation_property", s.property.take()),
            ("resolution_m", s.resolution.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "a grid floor");
        }
        if f.esri_ascii.is_some() {
            self.esri_grid(f)
        } else {
            self.heights_grid(f)
        }
    }

    /// Estimated memory of a grid of `rows` × `cols` nodes, bytes: a rotated grid becomes a
    /// mesh, with its nodes, triangles and buckets besides the grid.
    fn grid_bytes(&self, rows: usize, cols: usize) -> f64 {
        let rotated = self.map.is_some_and(|m| m.dip_direction_deg != 90.0);
        migration::grid_bytes(rows, cols)
            + if rotated {
                rows as f64 * cols as f64 * migration::CONTOUR_BYTES_PER_POINT
            } else {
                0.0
            }
    }

    /// A grid given as an ESRI ASCII text: its header gives origin and spacing; the work and
    /// memory are estimated from the header before the data are read.
    fn esri_grid(&mut self, f: &mut FloorDto) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("origin_m", s.origin.take()),
            ("spacing_m", s.spacing.take()),
            ("heights_m", s.heights.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "an ESRI ASCII grid (its header gives them)");
        }
        f.sha256 = Some(f.digest());
        let Some(text) = &f.esri_ascii else {
            return FloorSpec::Plane;
        };
        let field = floor_pointer("esri_ascii");
        let line_v = |line: usize| {
            let l = text.lines().nth(line.saturating_sub(1)).unwrap_or("");
            json!(l.chars().take(80).collect::<String>())
        };
        let header = match formats::esri_header(text) {
            Ok(h) => h,
            Err(e) => {
                self.ck.push(field, line_v(e.line), e.message);
                return FloorSpec::Plane;
            }
        };
        let origin = [header.x_center, header.y_center];
        let shift = self.shift();
        for (i, o) in origin.iter().enumerate() {
            let rel = o - shift[i];
            if !(-1e6..=1e6).contains(&rel) {
                self.ck.push(
                    field,
                    num(*o),
                    format!(
                        "the grid's first cell centre {} = {o} m{} must lie in [−1e6, 1e6] m",
                        ["x", "y"][i],
                        if self.map.is_some() {
                            " minus map.origin_m"
                        } else {
                            " (give map.origin_m for map coordinates)"
                        }
                    ),
                );
                return FloorSpec::Plane;
            }
        }
        let (rows, cols) = (header.nrows, header.ncols);
        let need = self.grid_bytes(rows, cols);
        if need > self.max_floor_bytes as f64 {
            check_floor_memory(
                self.ck,
                field,
                json!([rows, cols]),
                &format!("an ESRI ASCII grid of {rows} × {cols} cells"),
                need,
                self.max_floor_bytes,
            );
            return FloorSpec::Plane;
        }
        let heights = match formats::esri_heights(text, &header, 1e6) {
            Ok((z, nodata)) => {
                if nodata == rows * cols {
                    self.ck.push(field, json!(nodata), "every cell is NODATA");
                    return FloorSpec::Plane;
                }
                z
            }
            Err(e) => {
                self.ck.push(field, line_v(e.line), e.message);
                return FloorSpec::Plane;
            }
        };
        self.wrap(FloorSpec::Grid {
            origin,
            spacing: header.cellsize,
            heights,
        })
    }

    /// A grid given by its origin, spacing and rows of heights.
    fn heights_grid(&mut self, f: &mut FloorDto) -> FloorSpec {
        let origin = *f.origin_m.get_or_insert([0.0, 0.0]);
        let shift = self.shift();
        for (i, o) in origin.iter().enumerate() {
            if self.map.is_some() {
                let rel = o - shift[i];
                if !(-1e6..=1e6).contains(&rel) {
                    self.ck.push(
                        floor_pointer(&format!("origin_m/{i}")),
                        num(*o),
                        "must lie within 1e6 m of map.origin_m",
                    );
                }
            } else if !(-1e6..=1e6).contains(o) {
                self.ck.push(
                    floor_pointer(&format!("origin_m/{i}")),
                    num(*o),
                    "must be in [−1e6, 1e6] m (give map.origin_m for map coordinates such \
                     as UTM)",
                );
            }
        }
        let spacing = match f.spacing_m {
            Some(d) => {
                FLOOR_SPACING.check(self.ck, &floor_pointer("spacing_m"), d);
                d
            }
            None => {
                self.ck.push(
                    floor_pointer("spacing_m"),
                    Value::Null,
                    "a grid floor needs spacing_m in [0.01, 100] m",
                );
                1.0
            }
        };
        // The echo needs only the hash: hash the floor as received, then move its heights
        // into the case rather than copying up to 16 M values.
        f.sha256 = Some(f.digest());
        let heights = f.heights_m.take().unwrap_or_default();
        self.check_heights(&heights);
        self.wrap(FloorSpec::Grid {
            origin,
            spacing,
            heights,
        })
    }

    /// A grid's rows of heights: 2 to 4096 rows of as many heights each, within 1e6 m, and
    /// within the memory limit.
    fn check_heights(&mut self, heights: &[Vec<f64>]) {
        let rows = heights.len();
        let cols = heights.first().map_or(0, Vec::len);
        if !(2..=4096).contains(&rows) || !(2..=4096).contains(&cols) {
            self.ck.push(
                floor_pointer("heights_m"),
                json!([rows, cols]),
                "needs 2 to 4096 rows of 2 to 4096 heights each",
            );
        } else if let Some(i) = heights.iter().position(|r| r.len() != cols) {
            self.ck.push(
                floor_pointer(&format!("heights_m/{i}")),
                json!(heights[i].len()),
                format!("every row needs {cols} heights, like row 0"),
            );
        } else if let Some((i, j)) = heights
            .iter()
            .enumerate()
            .find_map(|(i, r)| r.iter().position(|z| z.abs() > 1e6).map(|j| (i, j)))
        {
            self.ck.push(
                floor_pointer(&format!("heights_m/{i}/{j}")),
                num(heights[i][j]),
                "heights must lie in [−1e6, 1e6] m",
            );
        } else {
            check_floor_memory(
                self.ck,
                floor_pointer("heights_m"),
                json!([rows, cols]),
                &format!("a grid of {rows} × {cols} heights"),
                self.grid_bytes(rows, cols),
                self.max_floor_bytes,
            );
        }
    }

    /// A contour floor, from GeoJSON or from contour lines: the lines' points and elevations,
    /// one elevation per plan point, no crossing, and the resampled floor's memory.
    fn contours(&mut self, f: &mut FloorDto) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("origin_m", s.origin.take()),
            ("spacing_m", s.spacing.take()),
            ("heights_m", s.heights.take()),
            ("esri_ascii", s.esri.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "a contour floor");
        }
        let resolution = *f.resolution_m.get_or_insert(FLOOR_RESOLUTION.value());
        let resolution_ok =
            FLOOR_RESOLUTION.check(self.ck, &floor_pointer("resolution_m"), resolution);
        let Some((lines, paths)) = self.contour_lines(f) else {
            return FloorSpec::Plane;
        };
        if f.geojson.is_some() {
            // the lines hold their own copy: the GeoJSON is not needed any more
            f.geojson = Some(Value::Null);
        }
        if lines.is_empty() {
            self.ck.push(
                if f.geojson.is_some() {
                    floor_pointer("geojson/features")
                } else {
                    floor_pointer("contours")
                },
                Value::Null,
                "a contour floor needs at least one contour line",
            );
        }
        let total = self.check_contour_points(&lines, &paths);
        if total > 4_000_000 {
            self.ck.push(
                floor_pointer("contours"),
                json!(total),
                "at most 4 000 000 points in all",
            );
        }
        let dup = self.check_one_elevation_per_point(&lines, &paths);
        if !dup && total <= 4_000_000 {
            self.check_crossing(&lines, &paths);
        }
        let contours: Vec<ContourLine> = lines
            .into_iter()
            .map(|c| ContourLine {
                elevation: c.elevation_m,
                points: c.points_m,
            })
            .collect();
        if total <= 4_000_000 && resolution_ok {
            // estimated before resampling: the work and memory grow with length / resolution
            let points = migration::contour_points(&contours, resolution);
            check_floor_memory(
                self.ck,
                floor_pointer("resolution_m"),
                num(resolution),
                &format!(
                    "the contours resampled every {resolution} m have about {points:.3e} \
                     points and"
                ),
                points * migration::CONTOUR_BYTES_PER_POINT,
                self.max_floor_bytes,
            );
        }
        self.wrap(FloorSpec::Contours {
            contours,
            resolution,
        })
    }

    /// The contour lines with the pointers to each one's points and elevation: read from the
    /// GeoJSON (None when it is malformed) or moved out of `contours`.
    fn contour_lines(&mut self, f: &mut FloorDto) -> Option<PointedLines> {
        let Some(g) = &f.geojson else {
            let sent = self.sent.property.take();
            self.stray(
                "elevation_property",
                sent,
                "contours given as contours (it names a GeoJSON property)",
            );
            f.sha256 = Some(f.digest());
            let lines = f.contours.take().unwrap_or_default();
            let paths = (0..lines.len())
                .map(|i| {
                    (
                        floor_pointer(&format!("contours/{i}/points_m")),
                        floor_pointer(&format!("contours/{i}/elevation_m")),
                    )
                })
                .collect();
            return Some((lines, paths));
        };
        let sent = self.sent.contours.take();
        self.stray("contours", sent, "GeoJSON contours (give one or the other)");
        let prop = f
            .elevation_property
            .get_or_insert_with(|| ELEVATION_PROPERTY.into())
            .clone();
        f.sha256 = Some(f.digest());
        let gp = floor_pointer("geojson");
        match formats::geojson_lines(g, &prop) {
            Ok(ls) => {
                f.geographic = self.map.is_none()
                    && ls.iter().all(|l| {
                        l.points
                            .iter()
                            .all(|q| q[0].abs() <= 180.0 && q[1].abs() <= 90.0)
                    });
                Some(
                    ls.into_iter()
                        .map(|l| {
                            (
                                ContourDto {
                                    elevation_m: l.elevation,
                                    points_m: l.points,
                                },
                                (
                                    format!("{gp}{}", l.points_pointer),
                                    format!("{gp}{}", l.elevation_pointer),
                                ),
                            )
                        })
                        .unzip(),
                )
            }
            Err(e) => {
                self.ck
                    .push(format!("{gp}{}", e.pointer), e.value, e.message);
                None
            }
        }
    }

    /// Each line's elevation within 1e6 m and its points (one at least) within 1e6 m of the
    /// origin (the map's, in map coordinates); returns the number of points in all.
    fn check_contour_points(&mut self, lines: &[ContourDto], paths: &[(String, String)]) -> usize {
        let shift = self.shift();
        let mut total = 0usize;
        for (c, (pts, elev)) in lines.iter().zip(paths) {
            self.ck.closed(elev, c.elevation_m, -1e6, 1e6, "m");
            if c.points_m.is_empty() {
                self.ck
                    .push(pts.clone(), json!(0), "needs at least one point");
            }
            if let Some(j) = c
                .points_m
                .iter()
                .position(|q| !((q[0] - shift[0]).abs() <= 1e6 && (q[1] - shift[1]).abs() <= 1e6))
            {
                self.ck.push(
                    format!("{pts}/{j}"),
                    json!(c.points_m[j]),
                    if self.map.is_some() {
                        "coordinates must lie within 1e6 m of map.origin_m"
                    } else {
                        "coordinates must lie in [−1e6, 1e6] m (give map.origin_m for map \
                         coordinates)"
                    },
                );
            }
            total += c.points_m.len();
        }
        total
    }

    /// One plan point on two elevations would make the floor a vertical wall there: refuses
    /// the first such point; true if there was one.
    fn check_one_elevation_per_point(
        &mut self,
        lines: &[ContourDto],
        paths: &[(String, String)],
    ) -> bool {
        let mut seen: std::collections::HashMap<(u64, u64), (usize, f64)> =
            std::collections::HashMap::new();
        for (i, c) in lines.iter().enumerate() {
            for (j, q) in c.points_m.iter().enumerate() {
                let key = ((q[0] + 0.0).to_bits(), (q[1] + 0.0).to_bits());
                match seen.get(&key) {
                    Some(&(k, z)) if z != c.elevation_m => {
                        self.ck.push(
                            format!("{}/{j}", paths[i].0),
                            json!(q),
                            format!(
                                "this point also lies on the line at {} (elevation {z} m): \
                                 one point cannot have two elevations",
                                paths[k].0
                            ),
                        );
                        return true;
                    }
                    Some(_) => {}
                    None => {
                        seen.insert(key, (i, c.elevation_m));
                    }
                }
            }
        }
        false
    }

    /// Crossing contours have no single height where they cross: refuses the first crossing.
    fn check_crossing(&mut self, lines: &[ContourDto], paths: &[(String, String)]) {
        let Some(x) = find_crossing(lines) else {
            return;
        };
        let (i, k) = x.later;
        let (i2, k2) = x.earlier;
        let what = if lines[i].elevation_m == lines[i2].elevation_m {
            "crosses"
        } else {
            "meets"
        };
        self.ck.push(
            format!("{}/{k}", paths[i].0),
            json!(lines[i].points_m[k]),
            format!(
                "the segment from this point to point {} {what} the segment {}/{k2}–{} \
                 (elevation {} m) near [{}, {}]: contours must not cross (touching at a \
                 point at the same elevation is allowed)",
                k + 1,
                paths[i2].0,
                k2 + 1,
                lines[i2].elevation_m,
                x.at[0],
                x.at[1]
            ),
        );
    }
}

/// The floor case of a request's `face.floor`, its fields checked into `ck` (the floor's
/// hash set for the echo; large inputs moved, not copied); the map frame first, as the
/// floor's own ranges are relative to it.
fn resolve_floor(f: &mut FloorDto, ck: &mut Checker, max_floor_bytes: u64) -> FloorSpec {
    let sent = SentFloor::of(f);
    // map coordinates: checked first, the floor's own ranges are checked relative to them
    let map = f.map.map(|m| {
        for (i, o) in m.origin_m.iter().enumerate() {
            ck.closed(
                &floor_pointer(&format!("map/origin_m/{i}")),
                *o,
                -1e8,
                1e8,
                "m",
            );
        }
        MAP_DIP_DIRECTION.check(
            ck,
            &floor_pointer("map/dip_direction_deg"),
            m.dip_direction_deg,
        );
        MapFrame {
            origin: m.origin_m,
            dip_direction_deg: m.dip_direction_deg,
        }
    });
    let mut check = FloorCheck {
        ck,
        sent,
        map,
        max_floor_bytes,
    };
    match f.kind {
        FloorKind::Plane => check.plane(),
        FloorKind::Grid => check.grid(f),
        FloorKind::Contours => check.contours(f),
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
        if self.output.runs_csv && monte_carlo.is_none() {
            ck.push(
                layout.migration_output("runs_csv"),
                json!(true),
                "per-run summaries need monte_carlo",
            );
        }
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
            },
            rock,
            release: Release {
                drop_height: self.release.drop_height_m,
                along_dip: self.release.along_dip_m,
                across: self.release.across_m,
                speed: self.release.speed_m_s,
            },
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
            },
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
                "polyhedra belong to the rigid-block method; the lumped mass takes cube, sphere or cuboid",
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
        };
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

/// The state at the end of the (nominal) run.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ArrivalDto {
    /// Motion at the end: flight, slide, roll or stopped.
    pub phase: String,
    /// Why the run ended: lower_end, at_rest, end_time or left_floor (in a scene also support).
    pub stop_reason: String,
    /// Time since release, s.
    pub time_s: f64,
    /// Speed, m/s.
    pub speed_m_s: f64,
    /// Velocity along the (mean) plane's down-dip direction, m/s.
    pub along_dip_velocity_m_s: f64,
    /// Velocity along the (mean) plane's outward normal, m/s.
    pub normal_velocity_m_s: f64,
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Height of the centre above its resting height, m.
    pub normal_offset_m: f64,
    /// Position [x, y, z], m.
    pub position_m: [f64; 3],
    /// Angular speed, rad/s.
    pub angular_speed_rad_s: f64,
    /// Kinetic energy, translation + rotation, J.
    pub kinetic_energy_j: f64,
    /// Rotational kinetic energy, J.
    pub rotational_energy_j: f64,
}

/// Energy bookkeeping of the (nominal) run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct EnergyDto {
    /// Kinetic + potential energy at release (potential zero at the lower end), J.
    pub total_start_j: f64,
    /// Lost in impacts, J.
    pub impacts_j: f64,
    /// Lost to friction, J.
    pub friction_j: f64,
    /// Lost at transitions (start of sliding or rolling, edges), J.
    pub transition_j: f64,
    /// Lost to contact and local damping (rigid block), J.
    pub damping_j: f64,
    /// Elastic energy still in the contact springs at the end (rigid block; else 0), J.
    pub stored_j: f64,
    /// KE + PE + losses − total at start (rounding only), J.
    pub residual_j: f64,
}

/// An event of the (nominal) run.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct EventDto {
    /// Time, s.
    pub time_s: f64,
    /// impact, slide_start, roll_start, take_off or stop.
    pub kind: String,
    /// Position [x, y, z], m.
    pub position_m: [f64; 3],
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Speed before, m/s.
    pub speed_before_m_s: f64,
    /// Speed after, m/s.
    pub speed_after_m_s: f64,
    /// Energy lost in the event, J.
    pub energy_lost_j: f64,
    /// Largest total normal contact force during the contact, N (rigid-block impacts).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_contact_force_n: Option<f64>,
}

/// Sampled trajectory: equal-length arrays.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct TrajectoryDto {
    /// Times, s.
    pub time_s: Vec<f64>,
    /// Positions [x, y, z], m.
    pub position_m: Vec<[f64; 3]>,
    /// Along-dip positions, m.
    pub along_dip_m: Vec<f64>,
    /// Heights above the floor along its normal, m.
    pub height_m: Vec<f64>,
    /// Velocities [vx, vy, vz], m/s.
    pub velocity_m_s: Vec<[f64; 3]>,
    /// Speeds, m/s.
    pub speed_m_s: Vec<f64>,
    /// Angular velocities, rad/s.
    pub angular_velocity_rad_s: Vec<[f64; 3]>,
    /// Orientation quaternions [w, x, y, z], body to world (rigid block).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientation_wxyz: Option<Vec<[f64; 4]>>,
    /// Kinetic energies (translation + rotation), J.
    pub kinetic_energy_j: Vec<f64>,
    /// Rotational energies, J.
    pub rotational_energy_j: Vec<f64>,
    /// Potential energies (zero at the lower end), J.
    pub potential_energy_j: Vec<f64>,
    /// Energy dissipated so far (impacts, friction, transitions, damping), J.
    pub dissipated_energy_j: Vec<f64>,
}

/// Histogram: 21 edges, 20 equal bins from min to max.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct HistogramDto {
    /// Bin edges.
    pub edges: Vec<f64>,
    /// Counts per bin.
    pub counts: Vec<u64>,
}

/// Summary statistics of one quantity over an ensemble.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct SummaryDto {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (N − 1); null for one value.
    pub std: Option<f64>,
    /// Minimum.
    pub min: f64,
    /// 5th percentile (Hyndman–Fan type 7).
    pub p05: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
    /// Histogram.
    pub histogram: HistogramDto,
}

impl From<&Summary> for SummaryDto {
    fn from(s: &Summary) -> Self {
        Self {
            mean: s.mean,
            std: s.std,
            min: s.min,
            p05: s.p05,
            p50: s.p50,
            p95: s.p95,
            p99: s.p99,
            max: s.max,
            histogram: HistogramDto {
                edges: s.histogram.edges.clone(),
                counts: s.histogram.counts.clone(),
            },
        }
    }
}

/// Monte Carlo statistics.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct StatisticsDto {
    /// Number of runs.
    pub runs: u64,
    /// Seed.
    pub seed: u64,
    /// Fraction of runs that reached the lower end.
    pub reached_fraction: f64,
    /// Arrival speed over the runs that reached the lower end (null if none did), m/s.
    pub speed_m_s: Option<SummaryDto>,
    /// Arrival down-dip velocity over the runs that reached the lower end (null if none did),
    /// m/s.
    pub along_dip_velocity_m_s: Option<SummaryDto>,
    /// Arrival kinetic energy over the runs that reached the lower end, J.
    pub kinetic_energy_j: Option<SummaryDto>,
    /// Arrival time over the runs that reached the lower end, s.
    pub time_s: Option<SummaryDto>,
    /// Number of impacts over all runs.
    pub impact_count: SummaryDto,
    /// Final along-dip position minus the release's, over all runs, m.
    pub runout_m: SummaryDto,
    /// Largest bounce height over all runs, m.
    pub max_bounce_height_m: SummaryDto,
}

/// What the rigid-block method reports besides the common outputs.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct RigidBlockOutDto {
    /// Time step used, s.
    pub time_step_s: f64,
    /// Critical time step Δt_crit, s.
    pub critical_time_step_s: f64,
    /// Time steps of the nominal run (closed-form free flights count as none).
    pub steps: u64,
    /// Block mass, kg.
    pub mass_kg: f64,
    /// Principal moments of inertia, ascending, kg·m².
    pub principal_inertia_kg_m2: [f64; 3],
}

/// Result of a migration.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct MigrationResponse {
    /// The method run.
    pub method: MethodDto,
    /// Rock mass, kg.
    pub mass_kg: f64,
    /// State at the end of the (nominal) run.
    pub arrival: ArrivalDto,
    /// Number of impacts.
    pub impact_count: u64,
    /// Where the ground phase (slide or roll) began, m (null: it never did).
    pub slide_start_along_dip_m: Option<f64>,
    /// Where the rock stopped, m (null: it did not stop).
    pub stop_along_dip_m: Option<f64>,
    /// Largest apex above the struck floor after the first impact, m: only apexes the rock reached
    /// before its flight or run ended (a flight cut short by the lower end has none).
    pub max_bounce_height_m: f64,
    /// Energy bookkeeping.
    pub energy: EnergyDto,
    /// Events of the (nominal) run (when `output.events`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events: Option<Vec<EventDto>>,
    /// Sampled trajectory (when `output.trajectory`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<TrajectoryDto>,
    /// Monte Carlo statistics.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub statistics: Option<StatisticsDto>,
    /// Per-run summaries as CSV (when `output.runs_csv`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_csv: Option<String>,
    /// Time step, steps and mass properties (rigid block).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rigid_block: Option<RigidBlockOutDto>,
    /// Named warnings.
    pub warnings: Vec<Warning>,
    /// Stages run or skipped.
    pub plan: Vec<PlanStep>,
    /// The fully resolved request.
    pub inputs: MigrationRequest,
    /// Version of the service and its models.
    pub model_version: String,
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Flight => "flight",
        Phase::Slide => "slide",
        Phase::Roll => "roll",
        Phase::Stopped => "stopped",
    }
}

fn event_name(k: EventKind) -> &'static str {
    match k {
        EventKind::Impact => "impact",
        EventKind::SlideStart => "slide_start",
        EventKind::RollStart => "roll_start",
        EventKind::TakeOff => "take_off",
        EventKind::Stop => "stop",
    }
}

fn rigid_plan(mc: bool, trajectory: bool) -> Vec<PlanStep> {
    vec![
        PlanStep::ran(
            "migration",
            if mc {
                "rigid-block DEM, seeded Monte Carlo ensemble (contact steps, closed-form free flights)"
            } else {
                "rigid-block DEM, one deterministic run (contact steps, closed-form free flights)"
            },
        ),
        if trajectory {
            PlanStep::ran("trajectory", "sampled during the run")
        } else {
            PlanStep::skipped("trajectory", "output.trajectory is false")
        },
    ]
}

/// The api.md name of a stop reason.
#[must_use]
pub fn stop_name(s: StopReason) -> &'static str {
    match s {
        StopReason::LowerEnd => "lower_end",
        StopReason::AtRest => "at_rest",
        StopReason::EndTime => "end_time",
        StopReason::LeftFloor => "left_floor",
        StopReason::Support => "support",
    }
}

/// CSV of per-run summaries with api.md's header; numbers in shortest round-trip form, runs
/// numbered from 0 (the run index of the random stream).
#[must_use]
pub fn runs_csv(runs: &[RunSummary]) -> String {
    let mut s = String::from(
        "run,time_s,speed_m_s,kinetic_energy_j,impact_count,runout_m,max_bounce_height_m,stop_reason,along_dip_velocity_m_s\n",
    );
    for (i, r) in runs.iter().enumerate() {
        s.push_str(&format!(
            "{i},{},{},{},{},{},{},{},{}\n",
            r.time,
            r.speed,
            r.kinetic_energy,
            r.impact_count,
            r.runout,
            r.max_bounce_height,
            stop_name(r.stop_reason),
            r.along_dip_velocity
        ));
    }
    s
}

impl MigrationResponse {
    /// Builds the response from the physics result and the resolved request.
    pub fn new(r: MigrationResult, inputs: MigrationRequest) -> Self {
        let mc = inputs.monte_carlo.is_some();
        let plan = vec![
            PlanStep::ran(
                "migration",
                if mc {
                    "energy tracking method, seeded Monte Carlo ensemble (closed-form flights and slides)"
                } else {
                    "energy tracking method, one deterministic run (closed-form flights and slides)"
                },
            ),
            if r.trajectory.is_some() {
                PlanStep::ran("trajectory", "sampled from the closed forms")
            } else {
                PlanStep::skipped("trajectory", "output.trajectory is false")
            },
        ];
        let rigid = r.rigid_block.is_some();
        let plan = if rigid {
            rigid_plan(mc, r.trajectory.is_some())
        } else {
            plan
        };
        let mut meta = Meta::new(plan);
        meta.warnings = r
            .warnings
            .iter()
            .map(|w| Warning::new(w.code, w.message.clone()))
            .collect();
        if inputs.face.floor.geographic {
            meta.warnings.push(Warning::new(
                "geographic_coordinates",
                "every coordinate of the GeoJSON contours lies within ±180 × ±90: they look like \
                 longitude/latitude (RFC 7946), which are not metres; the floor was taken in \
                 metres as sent. Project it (e.g. to UTM) and give map.origin_m",
            ));
        }
        let a = &r.arrival;
        Self {
            method: if rigid {
                MethodDto::RigidBlock
            } else {
                MethodDto::LumpedMass
            },
            mass_kg: r.mass,
            arrival: ArrivalDto {
                phase: phase_name(a.phase).into(),
                stop_reason: stop_name(a.stop_reason).into(),
                time_s: a.time,
                speed_m_s: a.speed,
                along_dip_velocity_m_s: a.along_dip_velocity,
                normal_velocity_m_s: a.normal_velocity,
                along_dip_m: a.along_dip,
                normal_offset_m: a.normal_offset,
                position_m: a.position,
                angular_speed_rad_s: a.angular_speed,
                kinetic_energy_j: a.kinetic_energy,
                rotational_energy_j: a.rotational_energy,
            },
            impact_count: r.impact_count,
            slide_start_along_dip_m: r.slide_start_along_dip,
            stop_along_dip_m: r.stop_along_dip,
            max_bounce_height_m: r.max_bounce_height,
            energy: EnergyDto {
                total_start_j: r.energy.total_start,
                impacts_j: r.energy.impacts,
                friction_j: r.energy.friction,
                transition_j: r.energy.transition,
                damping_j: r.energy.damping,
                stored_j: r.energy.stored,
                residual_j: r.energy.residual,
            },
            events: r.events.map(|ev| {
                ev.iter()
                    .map(|e| EventDto {
                        time_s: e.time,
                        kind: event_name(e.kind).into(),
                        position_m: e.position,
                        along_dip_m: e.along_dip,
                        speed_before_m_s: e.speed_before,
                        speed_after_m_s: e.speed_after,
                        energy_lost_j: e.energy_lost,
                        peak_contact_force_n: e.peak_contact_force,
                    })
                    .collect()
            }),
            trajectory: r.trajectory.map(|t| TrajectoryDto {
                time_s: t.time,
                position_m: t.position,
                along_dip_m: t.along_dip,
                height_m: t.height,
                velocity_m_s: t.velocity,
                speed_m_s: t.speed,
                angular_velocity_rad_s: t.angular_velocity,
                orientation_wxyz: (!t.orientation.is_empty()).then_some(t.orientation),
                kinetic_energy_j: t.kinetic_energy,
                rotational_energy_j: t.rotational_energy,
                potential_energy_j: t.potential_energy,
                dissipated_energy_j: t.dissipated_energy,
            }),
            statistics: r.statistics.as_ref().map(|s| StatisticsDto {
                runs: s.runs,
                seed: s.seed,
                reached_fraction: s.reached_fraction,
                speed_m_s: s.speed.as_ref().map(Into::into),
                along_dip_velocity_m_s: s.along_dip_velocity.as_ref().map(Into::into),
                kinetic_energy_j: s.kinetic_energy.as_ref().map(Into::into),
                time_s: s.time.as_ref().map(Into::into),
                impact_count: (&s.impact_count).into(),
                runout_m: (&s.runout).into(),
                max_bounce_height_m: (&s.max_bounce_height).into(),
            }),
            runs_csv: r.runs.as_deref().map(runs_csv),
            rigid_block: r.rigid_block.map(|b| RigidBlockOutDto {
                time_step_s: b.time_step,
                critical_time_step_s: b.critical_time_step,
                steps: b.steps,
                mass_kg: b.mass,
                principal_inertia_kg_m2: b.principal_inertia,
            }),
            warnings: meta.warnings,
            plan: meta.plan,
            inputs,
            model_version: meta.model_version,
        }
    }
}

/// A place where contour polylines cross: the later segment (contour, first point index), the
/// earlier one, and a plan point of the contact, m.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Crossing {
    later: (usize, usize),
    earlier: (usize, usize),
    at: [f64; 2],
}

/// Sign of the orientation of (a, b, c): +1 left turn, −1 right turn, 0 collinear within the
/// rounding error of the determinant.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let l = (b[0] - a[0]) * (c[1] - a[1]);
    let r = (b[1] - a[1]) * (c[0] - a[0]);
    let det = l - r;
    let bound = 8.0 * f64::EPSILON * (l.abs() + r.abs());
    if det > bound {
        1
    } else if det < -bound {
        -1
    } else {
        0
    }
}

/// Whether c (collinear with a–b) lies within the bounding box of a–b.
fn on_segment(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    c[0] >= a[0].min(b[0])
        && c[0] <= a[0].max(b[0])
        && c[1] >= a[1].min(b[1])
        && c[1] <= a[1].max(b[1])
}

/// How two plan segments meet: `None` apart, `Some(true)` crossing through each other's
/// interiors, `Some(false)` touching (an end on the other segment, or collinear overlap);
/// with a point of the contact.
fn contact(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<(bool, [f64; 2])> {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if o1 * o2 < 0 && o3 * o4 < 0 {
        // the crossing point, for the message only
        let r = [b[0] - a[0], b[1] - a[1]];
        let s = [d[0] - c[0], d[1] - c[1]];
        let den = r[0] * s[1] - r[1] * s[0];
        let t = ((c[0] - a[0]) * s[1] - (c[1] - a[1]) * s[0]) / den;
        return Some((true, [a[0] + t * r[0], a[1] + t * r[1]]));
    }
    if o1 == 0 && on_segment(a, b, c) {
        return Some((false, c));
    }
    if o2 == 0 && on_segment(a, b, d) {
        return Some((false, d));
    }
    if o3 == 0 && on_segment(c, d, a) {
        return Some((false, a));
    }
    if o4 == 0 && on_segment(c, d, b) {
        return Some((false, b));
    }
    None
}

/// Finds contour segments that give the floor no single height: two contours of different
/// elevations that meet anywhere, or segments (of one polyline or of two at the same elevation)
/// that cross through each other. Touching at a point at the same elevation is allowed. Uses a
/// uniform grid of at most n + 16 cells (n segments), each segment entered in the cells it
/// passes, so the work is about linear for contours spread over their extent. Reports the
/// crossing whose later segment comes first in the request.
fn find_crossing(lines: &[ContourDto]) -> Option<Crossing> {
    // segments as (contour, first point index)
    let mut segs: Vec<(u32, u32)> = Vec::new();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut total_len = 0.0;
    for (i, c) in lines.iter().enumerate() {
        for q in &c.points_m {
            for a in 0..2 {
                lo[a] = lo[a].min(q[a]);
                hi[a] = hi[a].max(q[a]);
            }
        }
        for k in 0..c.points_m.len().saturating_sub(1) {
            let (p, q) = (c.points_m[k], c.points_m[k + 1]);
            total_len += (q[0] - p[0]).abs().max((q[1] - p[1]).abs());
            segs.push((i as u32, k as u32));
        }
    }
    let n = segs.len();
    if n < 2 {
        return None;
    }
    let (w, h) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
    let mut cell = (total_len / n as f64)
        .max((w * h / n as f64).sqrt())
        .max(w.max(h) * 1e-9)
        .max(f64::MIN_POSITIVE);
    let max_cells = n as f64 + 16.0;
    let dims = |cell: f64| ((w / cell).floor() + 1.0, (h / cell).floor() + 1.0);
    while {
        let (a, b) = dims(cell);
        a * b > max_cells
    } {
        cell *= 2.0;
    }
    let (ncx, ncy) = dims(cell);
    let (ncx, ncy) = (ncx as usize, ncy as usize);
    let col = |x: f64| (((x - lo[0]) / cell).floor().max(0.0) as usize).min(ncx - 1);
    let row = |y: f64| (((y - lo[1]) / cell).floor().max(0.0) as usize).min(ncy - 1);
    let ends = |s: (u32, u32)| {
        let pts = &lines[s.0 as usize].points_m;
        (pts[s.1 as usize], pts[s.1 as usize + 1])
    };
    // the cells a segment passes: per column strip, the rows its y spans there (widened by one
    // rounding step so that no cell it touches is missed)
    let cells_of = |s: (u32, u32), f: &mut dyn FnMut(usize)| {
        let (a, b) = ends(s);
        let (i0, i1) = (col(a[0].min(b[0])), col(a[0].max(b[0])));
        for i in i0..=i1 {
            let (y0, y1) = if i0 == i1 || a[0] == b[0] {
                (a[1].min(b[1]), a[1].max(b[1]))
            } else {
                let xl = (lo[0] + i as f64 * cell).max(a[0].min(b[0]));
                let xr = (lo[0] + (i + 1) as f64 * cell).min(a[0].max(b[0]));
                let y = |x: f64| a[1] + (x - a[0]) / (b[0] - a[0]) * (b[1] - a[1]);
                let (ya, yb) = (y(xl), y(xr));
                let slack = 1e-9 * cell;
                (
                    (ya.min(yb) - slack).max(a[1].min(b[1])),
                    (ya.max(yb) + slack).min(a[1].max(b[1])),
                )
            };
            for j in row(y0)..=row(y1) {
                f(j * ncx + i);
            }
        }
    };
    let mut start = vec![0u32; ncx * ncy + 1];
    for &s in &segs {
        cells_of(s, &mut |c| start[c + 1] += 1);
    }
    for c in 1..start.len() {
        start[c] += start[c - 1];
    }
    let mut fill = start.clone();
    let mut items = vec![0u32; start[ncx * ncy] as usize];
    for (id, &s) in segs.iter().enumerate() {
        cells_of(s, &mut |c| {
            items[fill[c] as usize] = id as u32;
            fill[c] += 1;
        });
    }
    drop(fill);
    let mut best: Option<Crossing> = None;
    for c in 0..ncx * ncy {
        let bucket = &items[start[c] as usize..start[c + 1] as usize];
        for (u, &s1) in bucket.iter().enumerate() {
            for &s2 in &bucket[u + 1..] {
                let (e, l) = (segs[s1.min(s2) as usize], segs[s1.max(s2) as usize]);
                if best.is_some_and(|b| (l.0 as usize, l.1 as usize) >= b.later) {
                    continue;
                }
                // neighbours on one polyline share a point by construction
                if e.0 == l.0 && l.1 == e.1 + 1 {
                    continue;
                }
                let ((a, b), (p, q)) = (ends(e), ends(l));
                let Some((cross, at)) = contact(a, b, p, q) else {
                    continue;
                };
                let same = lines[e.0 as usize].elevation_m == lines[l.0 as usize].elevation_m;
                if cross || !same {
                    best = Some(Crossing {
                        later: (l.0 as usize, l.1 as usize),
                        earlier: (e.0 as usize, e.1 as usize),
                        at,
                    });
                }
            }
        }
    }
    best
}

//! `face.zones`: a floor of several materials (api.md `POST /v1/migration`, Zones) — the zone
//! map (an ESRI ASCII grid of integer codes, or polygons), the materials by code, their checks
//! and their resolution into [`Zones`]. In `inputs` the map is echoed as `{"kind", "sha256"}`
//! like a floor.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use sha2::{Digest, Sha256};
use utoipa::ToSchema;

use super::common::{Checker, FieldDefault, NumberField, number_schemas};
use super::floor::{self as formats, Sorted};
use super::migration::{
    DistributionDto, FACE_CRITICAL_DAMPING, FACE_FRICTION, FACE_NORMAL_STIFFNESS,
    FACE_RESTITUTION_NORMAL, FACE_RESTITUTION_TANGENTIAL, FACE_SHEAR_STIFFNESS, FaceDto,
};
use crate::physics::migration::{
    BlockContact, Distribution, MAX_CODE_CELLS, MAX_MATERIALS, MAX_POLYGON_VERTICES, MAX_POLYGONS,
    MapFrame, Material, MonteCarlo, ZonePolygon, ZoneShape, Zones, ZonesSpec, self_intersection,
};

/// Largest length of a material's name, characters.
pub const MAX_NAME_CHARS: usize = 200;
/// Largest |coordinate| of a polygon vertex, m (map coordinates included).
pub const MAX_ZONE_COORDINATE: f64 = 1e8;

/// A material's field: the face-level field's interval and unit, its default the face's.
const fn per_zone(field: NumberField, description: &'static str) -> NumberField {
    NumberField {
        description,
        default: FieldDefault::Derived,
        nullable: true,
        ..field
    }
}

/// `face.zones.materials[].friction_coefficient` (and the block's).
pub const ZONE_FRICTION: NumberField = per_zone(
    FACE_FRICTION,
    "Coulomb friction μ of the material, in [0, 2] (default: face.friction_coefficient).",
);
/// `face.zones.materials[].restitution_normal`.
pub const ZONE_RESTITUTION_NORMAL: NumberField = per_zone(
    FACE_RESTITUTION_NORMAL,
    "Normal restitution e_n of the material, in [0, 1] (default: face.restitution_normal).",
);
/// `face.zones.materials[].restitution_tangential`.
pub const ZONE_RESTITUTION_TANGENTIAL: NumberField = per_zone(
    FACE_RESTITUTION_TANGENTIAL,
    "Tangential restitution e_t of the material, in [0, 1] (default: \
     face.restitution_tangential).",
);
/// `face.zones.materials[].rigid_block.normal_stiffness_n_m`.
pub const ZONE_NORMAL_STIFFNESS: NumberField = per_zone(
    FACE_NORMAL_STIFFNESS,
    "Normal contact stiffness k_n on the material, N/m, in [1e3, 1e12] (default: \
     face.normal_stiffness_n_m).",
);
/// `face.zones.materials[].rigid_block.shear_stiffness_n_m`.
pub const ZONE_SHEAR_STIFFNESS: NumberField = per_zone(
    FACE_SHEAR_STIFFNESS,
    "Shear contact stiffness k_s on the material, N/m, in [1e3, 1e12] (default: \
     face.shear_stiffness_n_m).",
);
/// `face.zones.materials[].rigid_block.critical_damping_ratio`.
pub const ZONE_CRITICAL_DAMPING: NumberField = per_zone(
    FACE_CRITICAL_DAMPING,
    "Critical damping ratio β on the material, in [0, 1) (default: \
     face.critical_damping_ratio).",
);

number_schemas! {
    zone_friction_schema => ZONE_FRICTION;
    zone_restitution_normal_schema => ZONE_RESTITUTION_NORMAL;
    zone_restitution_tangential_schema => ZONE_RESTITUTION_TANGENTIAL;
    zone_normal_stiffness_schema => ZONE_NORMAL_STIFFNESS;
    zone_shear_stiffness_schema => ZONE_SHEAR_STIFFNESS;
    zone_critical_damping_schema => ZONE_CRITICAL_DAMPING;
}

/// One polygon of a zone map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ZonePolygonDto {
    /// The material code inside the polygon.
    #[schema(example = 2)]
    pub code: i64,
    /// Vertices [x, y], m, in the floor's frame (map coordinates when the floor has `map`):
    /// at least 3, closed implicitly, not self-intersecting.
    #[schema(example = json!([[40.0, -20.0], [80.0, -20.0], [80.0, 20.0], [40.0, 20.0]]))]
    pub points_m: Vec<[f64; 2]>,
}

/// The rigid block's contact parameters on one material (each null: the face's).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ZoneBlockDto {
    /// Normal contact stiffness k_n, N/m, in [1e3, 1e12] (default: `face.normal_stiffness_n_m`).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = zone_normal_stiffness_schema)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub normal_stiffness_n_m: Option<f64>,
    /// Shear contact stiffness k_s, N/m, in [1e3, 1e12] (default: `face.shear_stiffness_n_m`).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = zone_shear_stiffness_schema)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub shear_stiffness_n_m: Option<f64>,
    /// Critical damping ratio β, in [0, 1) (default: `face.critical_damping_ratio`, drawn from
    /// `monte_carlo.critical_damping_ratio` in an ensemble; given here, it is not drawn).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = zone_critical_damping_schema)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub critical_damping_ratio: Option<f64>,
    /// Coulomb friction μ of the block's contacts, in [0, 2] (default: the material's μ and
    /// its draw; given here, it is not drawn).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = zone_friction_schema)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub friction_coefficient: Option<f64>,
}

/// One material of the floor: its code and contact parameters. Every field but `code` is
/// optional and defaults to the face's (`face.*`, `monte_carlo.*`): a material that names
/// nothing is the face's material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ZoneMaterialDto {
    /// The code that marks the material on the zone map.
    #[schema(example = 1)]
    pub code: i64,
    /// A name for people (at most 200 characters; not used in the calculation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(example = "scree")]
    #[serde(deserialize_with = "super::common::non_null")]
    pub name: Option<String>,
    /// Coulomb friction μ, in [0, 2] (default: `face.friction_coefficient`; given without a
    /// distribution, it is μ in every run of an ensemble too).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = zone_friction_schema)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub friction_coefficient: Option<f64>,
    /// Normal restitution e_n, in [0, 1] (default: `face.restitution_normal`; given without a
    /// distribution, it is e_n at every impact of an ensemble too).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = zone_restitution_normal_schema)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub restitution_normal: Option<f64>,
    /// Tangential restitution e_t, in [0, 1] (default: `face.restitution_tangential`; as
    /// `restitution_normal`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = zone_restitution_tangential_schema)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub restitution_tangential: Option<f64>,
    /// e_n drawn at every impact on this material in an ensemble, bounds in [0, 1] (default:
    /// `monte_carlo.restitution_normal`, unless `restitution_normal` is given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "super::common::non_null")]
    pub restitution_normal_distribution: Option<DistributionDto>,
    /// e_t drawn at every impact on this material in an ensemble, bounds in [0, 1] (default:
    /// `monte_carlo.restitution_tangential`, unless `restitution_tangential` is given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "super::common::non_null")]
    pub restitution_tangential_distribution: Option<DistributionDto>,
    /// μ drawn once per run in an ensemble, bounds in [0, 2] (default:
    /// `monte_carlo.friction_coefficient`, unless `friction_coefficient` is given). Equal
    /// distributions share one draw.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "super::common::non_null")]
    pub friction_coefficient_distribution: Option<DistributionDto>,
    /// The rigid block's contact parameters on this material (default: the face's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[serde(deserialize_with = "super::common::non_null")]
    pub rigid_block: Option<ZoneBlockDto>,
}

/// A floor of several materials: integer codes over the floor (an ESRI ASCII grid or polygons,
/// in the floor's own frame: map coordinates when the floor has `map`, face coordinates
/// otherwise) and a material per code. At most 64 materials, 1000 polygons, 10 000 polygon
/// vertices in all, 2^20 grid cells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ZonesDto {
    /// Integer codes as the text of an ESRI ASCII grid (`ncols …`), instead of `polygons`;
    /// NODATA cells take `outside_code`.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(example = "ncols 2\nnrows 1\nxllcorner 0\nyllcorner -50\ncellsize 100\n1 2\n")]
    #[serde(deserialize_with = "super::common::non_null")]
    pub esri_ascii: Option<String>,
    /// Polygons with codes, instead of `esri_ascii`; later polygons win where they overlap.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(example = json!([{"code": 2, "points_m": [[40.0, -20.0], [80.0, -20.0], [80.0, 20.0], [40.0, 20.0]]}]))]
    #[serde(deserialize_with = "super::common::non_null")]
    pub polygons: Option<Vec<ZonePolygonDto>>,
    /// Code outside every polygon, on NODATA cells and off the code grid (default: the first
    /// material's).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(example = 1)]
    #[serde(deserialize_with = "super::common::non_null")]
    pub outside_code: Option<i64>,
    /// The materials, one per code (1 to 64).
    #[schema(example = json!([{"code": 1, "name": "scree"},
                              {"code": 2, "name": "meadow", "friction_coefficient": 0.5}]))]
    #[serde(default)]
    pub materials: Vec<ZoneMaterialDto>,
}

/// Serializes `face.zones` as its echo in `inputs`: `{"kind", "sha256"}`, the SHA-256 of the
/// zones object re-serialized as compact JSON with its keys sorted.
pub(crate) fn echo<S: serde::Serializer>(z: &Option<ZonesDto>, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let Some(z) = z else {
        return s.serialize_none();
    };
    let mut m = s.serialize_map(Some(2))?;
    m.serialize_entry(
        "kind",
        if z.esri_ascii.is_some() {
            "esri_ascii"
        } else {
            "polygons"
        },
    )?;
    m.serialize_entry("sha256", &z.digest())?;
    m.end()
}

impl ZonesDto {
    /// SHA-256 of the object as sent (keys sorted, compact).
    #[must_use]
    pub fn digest(&self) -> String {
        let v = serde_json::to_value(self).unwrap_or(Value::Null);
        let bytes = serde_json::to_vec(&Sorted(&v)).unwrap_or_default();
        Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    }
}

/// Each field of a material: its value or the face's, in range (`ck` names the pointer).
fn value(
    ck: &mut Checker,
    base: &str,
    name: &str,
    given: Option<f64>,
    field: super::common::NumberField,
    face: f64,
) -> f64 {
    match given {
        Some(v) => {
            field.check(ck, &format!("{base}/{name}"), v);
            v
        }
        None => face,
    }
}

/// The zones of `face` checked and built (None without zones). `mc` is the resolved ensemble
/// (its draws are the materials' defaults), `damping` the rigid block's β draw.
pub(crate) fn resolve_zones(
    face: &FaceDto,
    mc: Option<&MonteCarlo>,
    damping: Option<Distribution>,
    ck: &mut Checker,
) -> Option<Zones> {
    let z = face.zones.as_ref()?;
    let base = "/face/zones";
    let before = ck.is_ok();
    let n = z.materials.len();
    if n == 0 || n > MAX_MATERIALS {
        ck.push(
            format!("{base}/materials"),
            json!(n),
            format!("must hold 1 to {MAX_MATERIALS} materials"),
        );
    }
    let defaults = MonteCarlo::default();
    let mc_rn = mc.map_or(defaults.restitution_normal, |m| m.restitution_normal);
    let mc_rt = mc.map_or(defaults.restitution_tangential, |m| {
        m.restitution_tangential
    });
    let mc_mu = mc.and_then(|m| m.friction_coefficient);
    let mut materials = Vec::with_capacity(n);
    for (i, m) in z.materials.iter().enumerate() {
        let b = format!("{base}/materials/{i}");
        if z.materials[..i].iter().any(|o| o.code == m.code) {
            ck.push(
                format!("{b}/code"),
                json!(m.code),
                "duplicate code: each code names one material",
            );
        }
        if let Some(name) = &m.name
            && name.chars().count() > MAX_NAME_CHARS
        {
            ck.push(
                format!("{b}/name"),
                json!(name.chars().take(40).collect::<String>()),
                format!("must be at most {MAX_NAME_CHARS} characters"),
            );
        }
        let mu = value(
            ck,
            &b,
            "friction_coefficient",
            m.friction_coefficient,
            ZONE_FRICTION,
            face.friction_coefficient,
        );
        let rn = value(
            ck,
            &b,
            "restitution_normal",
            m.restitution_normal,
            ZONE_RESTITUTION_NORMAL,
            face.restitution_normal,
        );
        let rt = value(
            ck,
            &b,
            "restitution_tangential",
            m.restitution_tangential,
            ZONE_RESTITUTION_TANGENTIAL,
            face.restitution_tangential,
        );
        let dist = |d: &Option<DistributionDto>,
                    name: &str,
                    hi: f64,
                    given: Option<f64>,
                    default: Option<Distribution>,
                    ck: &mut Checker| {
            match (d, given) {
                (Some(d), _) => Some(d.resolve(&format!("{b}/{name}"), 0.0, hi, ck)),
                // a value given without a distribution holds in every run and impact
                (None, Some(v)) => Some(Distribution::Uniform { min: v, max: v }),
                (None, None) => default,
            }
        };
        let rn_d = dist(
            &m.restitution_normal_distribution,
            "restitution_normal_distribution",
            1.0,
            m.restitution_normal,
            Some(mc_rn),
            ck,
        )
        .unwrap_or(mc_rn);
        let rt_d = dist(
            &m.restitution_tangential_distribution,
            "restitution_tangential_distribution",
            1.0,
            m.restitution_tangential,
            Some(mc_rt),
            ck,
        )
        .unwrap_or(mc_rt);
        let mu_d = match (&m.friction_coefficient_distribution, m.friction_coefficient) {
            (Some(d), _) => Some(d.resolve(
                &format!("{b}/friction_coefficient_distribution"),
                0.0,
                2.0,
                ck,
            )),
            (None, Some(_)) => None,
            (None, None) => mc_mu,
        };
        let rb = m.rigid_block.unwrap_or_default();
        let bb = format!("{b}/rigid_block");
        let block = BlockContact {
            normal_stiffness: value(
                ck,
                &bb,
                "normal_stiffness_n_m",
                rb.normal_stiffness_n_m,
                ZONE_NORMAL_STIFFNESS,
                face.normal_stiffness_n_m,
            ),
            shear_stiffness: value(
                ck,
                &bb,
                "shear_stiffness_n_m",
                rb.shear_stiffness_n_m,
                ZONE_SHEAR_STIFFNESS,
                face.shear_stiffness_n_m,
            ),
            critical_damping_ratio: value(
                ck,
                &bb,
                "critical_damping_ratio",
                rb.critical_damping_ratio,
                ZONE_CRITICAL_DAMPING,
                face.critical_damping_ratio,
            ),
            critical_damping_ratio_distribution: if rb.critical_damping_ratio.is_some() {
                None
            } else {
                damping
            },
            friction_coefficient: value(
                ck,
                &bb,
                "friction_coefficient",
                rb.friction_coefficient,
                ZONE_FRICTION,
                mu,
            ),
            friction_coefficient_distribution: if rb.friction_coefficient.is_some() {
                None
            } else {
                mu_d
            },
        };
        // without an ensemble the draws are not used: a material is its nominal values (so two
        // materials with equal values are one, whichever way they were given)
        let (rn_d, rt_d, mu_d, block) = if mc.is_some() {
            (rn_d, rt_d, mu_d, block)
        } else {
            (
                Distribution::Uniform { min: rn, max: rn },
                Distribution::Uniform { min: rt, max: rt },
                None,
                BlockContact {
                    critical_damping_ratio_distribution: None,
                    friction_coefficient_distribution: None,
                    ..block
                },
            )
        };
        materials.push(Material {
            code: m.code,
            name: m.name.clone(),
            friction_coefficient: mu,
            friction_coefficient_distribution: mu_d,
            restitution_normal: rn,
            restitution_tangential: rt,
            restitution_normal_distribution: rn_d,
            restitution_tangential_distribution: rt_d,
            block,
        });
    }
    let known = |c: i64| z.materials.iter().any(|m| m.code == c);
    let outside_code = match z.outside_code {
        Some(c) => {
            if !known(c) {
                ck.push(
                    format!("{base}/outside_code"),
                    json!(c),
                    format!("code {c} has no material (codes: {})", codes(z)),
                );
            }
            c
        }
        None => z.materials.first().map_or(0, |m| m.code),
    };
    let shape = match (&z.esri_ascii, &z.polygons) {
        (Some(_), Some(_)) | (None, None) => {
            ck.push(
                base,
                json!(null),
                "give the zone map as one of `esri_ascii` (a grid of codes) or `polygons`",
            );
            None
        }
        (Some(text), None) => code_grid(text, z, ck),
        (None, Some(polys)) => polygons(polys, z, ck),
    };
    if !before || !ck.is_ok() {
        return None;
    }
    let spec = ZonesSpec {
        shape: shape?,
        outside_code,
        materials,
    };
    let map = face.floor.map.map(|m| MapFrame {
        origin: m.origin_m,
        dip_direction_deg: m.dip_direction_deg,
    });
    match Zones::new(spec, map) {
        Ok(zones) => Some(zones),
        Err(e) => {
            ck.push(base, json!(null), e.to_string());
            None
        }
    }
}

/// The codes of the materials, for messages.
fn codes(z: &ZonesDto) -> String {
    z.materials
        .iter()
        .map(|m| m.code.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The ESRI ASCII code grid, every code with a material.
fn code_grid(text: &str, z: &ZonesDto, ck: &mut Checker) -> Option<ZoneShape> {
    let field = "/face/zones/esri_ascii";
    let line_v = |line: usize| {
        let l = text.lines().nth(line.saturating_sub(1)).unwrap_or("");
        json!(l.chars().take(80).collect::<String>())
    };
    let h = match formats::esri_header(text) {
        Ok(h) => h,
        Err(e) => {
            ck.push(field, line_v(e.line), e.message);
            return None;
        }
    };
    if h.nrows * h.ncols > MAX_CODE_CELLS {
        ck.push(
            field,
            json!([h.nrows, h.ncols]),
            format!(
                "a code grid of {} × {} cells is more than {MAX_CODE_CELLS} cells",
                h.nrows, h.ncols
            ),
        );
        return None;
    }
    let rows = match formats::esri_codes(text, &h) {
        Ok(r) => r,
        Err(e) => {
            ck.push(field, line_v(e.line), e.message);
            return None;
        }
    };
    let mut codes_out = Vec::with_capacity(h.nrows * h.ncols);
    for row in rows {
        for c in row {
            if let Some(c) = c
                && !z.materials.iter().any(|m| m.code == c)
            {
                ck.push(
                    field,
                    json!(c),
                    format!("code {c} on the grid has no material (codes: {})", codes(z)),
                );
                return None;
            }
            codes_out.push(c);
        }
    }
    Some(ZoneShape::CodeGrid {
        x_center: h.x_center,
        y_center: h.y_center,
        cell: h.cellsize,
        ncols: h.ncols,
        nrows: h.nrows,
        codes: codes_out,
    })
}

/// The polygons: at least 3 finite points each, not self-intersecting, codes with materials,
/// within the limits.
fn polygons(polys: &[ZonePolygonDto], z: &ZonesDto, ck: &mut Checker) -> Option<ZoneShape> {
    let base = "/face/zones/polygons";
    if polys.is_empty() || polys.len() > MAX_POLYGONS {
        ck.push(
            base,
            json!(polys.len()),
            format!("must hold 1 to {MAX_POLYGONS} polygons"),
        );
        return None;
    }
    let total: usize = polys.iter().map(|p| p.points_m.len()).sum();
    if total > MAX_POLYGON_VERTICES {
        ck.push(
            base,
            json!(total),
            format!("{total} vertices in all is more than {MAX_POLYGON_VERTICES}"),
        );
        return None;
    }
    let mut out = Vec::with_capacity(polys.len());
    for (i, p) in polys.iter().enumerate() {
        let b = format!("{base}/{i}");
        if !z.materials.iter().any(|m| m.code == p.code) {
            ck.push(
                format!("{b}/code"),
                json!(p.code),
                format!("code {} has no material (codes: {})", p.code, codes(z)),
            );
        }
        if p.points_m.len() < 3 {
            ck.push(
                format!("{b}/points_m"),
                json!(p.points_m.len()),
                "a polygon needs at least 3 points",
            );
            continue;
        }
        let mut finite = true;
        for (k, q) in p.points_m.iter().enumerate() {
            for (c, v) in q.iter().enumerate() {
                if !ck.closed(
                    &format!("{b}/points_m/{k}/{c}"),
                    *v,
                    -MAX_ZONE_COORDINATE,
                    MAX_ZONE_COORDINATE,
                    "m",
                ) {
                    finite = false;
                }
            }
        }
        if !finite {
            continue;
        }
        if let Some((e1, e2)) = self_intersection(&p.points_m) {
            let n = p.points_m.len();
            ck.push(
                format!("{b}/points_m"),
                json!([p.points_m[e1], p.points_m[(e1 + 1) % n]]),
                format!(
                    "the polygon intersects itself: its edge from point {e1} meets its edge from \
                     point {e2}"
                ),
            );
            continue;
        }
        out.push(ZonePolygon {
            code: p.code,
            points: p.points_m.clone(),
        });
    }
    Some(ZoneShape::Polygons(out))
}

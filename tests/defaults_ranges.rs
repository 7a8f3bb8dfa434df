//! The OpenAPI document tells the truth about defaults and ranges.
//!
//! Expectation: for every route's request schema, (1) each documented `default` is what the
//! server fills into the echoed `inputs` for `{}` (a documented `null` default: the field is
//! absent or null), and every field the server fills in has a documented default unless it is a
//! documented derived default (listed in [`DERIVED`]); (2) each documented `minimum`/`maximum`
//! (or exclusive bound) is what validation enforces: the value just inside is not refused naming
//! the field, the value just outside is 422 naming exactly that field by its JSON Pointer.
//! Bounds that depend on another field are documented as such and listed in [`CROSS_FIELD`].
//!
//! Routes: impact, column, migration, spalling, study and calibrate (the study's and the
//! calibration's own fields; their `base` is a column or migration request, checked on
//! `/v1/column` and `/v1/migration`). A calibration needs observations and parameters, so its
//! "empty" request is the smallest one that has them ([`context`]).

mod common;
#[path = "common/openapi.rs"]
mod openapi;

use openapi::{Leaf, Walk, has_type, leaves, resolve};
use serde_json::{Map, Value, json};

/// Routes checked strictly: (path, request schema).
const ROUTES: &[(&str, &str)] = &[
    ("/v1/impact", "ImpactRequest"),
    ("/v1/column", "ColumnRequest"),
    ("/v1/migration", "MigrationRequest"),
    ("/v1/spalling", "SpallingRequest"),
    ("/v1/study", "StudyRequest"),
    ("/v1/calibrate", "CalibrateRequest"),
];

/// Documented derived defaults (filled from other fields; the description says how), by the
/// field's name within its object.
const DERIVED: &[&str] = &[
    "radius_m",         // side_length_m / 2
    "corner_radius_m",  // min(0.02, L/2)
    "contact_radius_m", // D₁/2
    "modes",            // 1 decoupled, 3 coupled
    "outputs",          // the study's outputs follow the base's model
    "zones",            // spalling: Table 1 unless `events` is given
];

/// Bounds that depend on another field: (pointer, which bound). Documented in the field's
/// description; the schema shows the widest value.
const CROSS_FIELD: &[(&str, &str)] = &[
    // l ≥ L (a cube's contact length): the documented minimum 0.1 is below the default L = 0.3,
    // so the value just inside is refused naming l by that rule (not by its range).
    ("/column/length_m", "min"),
    // D₂ < D₁: the documented maximum 2 is D₁'s.
    ("/column/inner_diameter_m", "max"),
    ("/base/column/inner_diameter_m", "max"),
    // The column at least the contact length L of a cube: L ≥ 0.01 < l's minimum, but L = 5 m
    // needs a longer column than the default.
    ("/rock/side_length_m", "max"),
    // spalling: low ≤ high.
    ("/low_resistance_n", "max"),
    // migration: the release lies on the face, below length_m; the documented maximum is the
    // longest face's.
    ("/release/along_dip_m", "max"),
];

/// Objects echoed by their hash rather than field by field (api.md: a grid or contour floor is
/// echoed as `{"kind", "sha256"}`): their own defaults are checked by
/// [`floor_defaults_are_those_the_floor_is_hashed_with`].
const HASHED: &[&str] = &["/face/floor", "/face/zones"];

/// A base request in which a field is used rather than refused as not applicable: (path,
/// pointer prefix, base body).
fn context(path: &str, pointer: &str) -> Value {
    // A 45° floor under the release (across 50 m on the grid, which starts at y = 0).
    let grid =
        json!({"kind": "grid", "spacing_m": 100.0, "heights_m": [[0.0, -100.0], [0.0, -100.0]]});
    let contours = json!({"kind": "contours", "contours": [
        {"elevation_m": 1.0, "points_m": [[-1.0, -50.0], [-1.0, 50.0]]},
        {"elevation_m": -130.0, "points_m": [[130.0, -50.0], [130.0, 50.0]]}]});
    let mut mapped = grid.clone();
    mapped["map"] = json!({"origin_m": [0.0, 0.0], "dip_direction_deg": 90.0});
    let table: &[(&str, &str, Value)] = &[
        ("/v1/column", "/galerkin/", json!({"model": "coupled"})),
        // A floor's own fields are used by the kinds that have them.
        (
            "/v1/migration",
            "/face/floor/resolution_m",
            json!({"face": {"floor": contours}}),
        ),
        (
            "/v1/migration",
            "/face/floor/map/",
            json!({"face": {"floor": mapped}, "release": {"across_m": 50.0}}),
        ),
        (
            "/v1/migration",
            "/face/floor/",
            json!({"face": {"floor": grid}, "release": {"across_m": 50.0}}),
        ),
        // The floor material's fields are required together.
        (
            "/v1/migration",
            "/face/floor_material/",
            json!({"face": {"floor_material": {"elastic_modulus_pa": 4.38e9, "poisson_ratio": 0.3}}}),
        ),
        // A zone map's materials need their codes and a map.
        (
            "/v1/migration",
            "/face/zones/",
            json!({"face": {"zones": {"polygons": [{"code": 1, "points_m": [[0.0, -1.0], [1.0, -1.0], [1.0, 1.0]]}],
                                      "materials": [{"code": 1}]}}}),
        ),
        ("/v1/column", "/end_time_s", json!({"model": "coupled"})),
        // A target's fields are required together.
        (
            "/v1/migration",
            "/monte_carlo/target/",
            json!({"monte_carlo": {"runs": 5, "target": {"percentile": 0.5, "relative_half_width": 0.1}}}),
        ),
        (
            "/v1/spalling",
            "/",
            json!({"events": [{"support": 1, "resistance_n": 5e6, "spalling": true}]}),
        ),
        // A calibration's required fields: two observed runouts, one parameter, a small search.
        (
            "/v1/calibrate",
            "",
            json!({"base": {"monte_carlo": {"runs": 10}},
                   "observed": {"runout_m": [100.0, 110.0]},
                   "parameters": [{"name": "friction_coefficient", "min": 0.1, "max": 0.3}]}),
        ),
    ];
    table
        .iter()
        .find(|(p, prefix, _)| *p == path && pointer.starts_with(prefix))
        .map(|(_, _, base)| base.clone())
        .unwrap_or_else(|| json!({}))
}

/// Compares a documented default with the filled-in value (numbers as f64, objects by the keys
/// the default names).
fn default_matches(documented: &Value, filled: Option<&Value>) -> bool {
    match (documented, filled) {
        (Value::Null, None | Some(Value::Null)) => true,
        (Value::Number(a), Some(Value::Number(b))) => a.as_f64() == b.as_f64(),
        (Value::Object(a), Some(Value::Object(b))) => {
            a.iter().all(|(k, v)| default_matches(v, b.get(k)))
        }
        (Value::Array(a), Some(Value::Array(b))) => {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| default_matches(x, Some(y)))
        }
        (a, Some(b)) => a == b,
        _ => false,
    }
}

/// Walks an object schema against the filled-in object, collecting default mismatches.
fn check_defaults(doc: &Value, schema: &Value, filled: &Value, at: &str, out: &mut Vec<String>) {
    let Some(props) = schema.get("properties").and_then(Value::as_object) else {
        return;
    };
    for (name, prop) in props {
        let pointer = format!("{at}/{name}");
        let (s, _) = resolve(doc, prop);
        let value = filled.get(name);
        let documented =
            (prop.get("default").or_else(|| prop.get("x-default"))).or_else(|| s.get("default"));
        match documented {
            Some(d) => {
                if !default_matches(d, value) {
                    out.push(format!(
                        "{pointer}: documented default {d}, filled in {}",
                        value.map_or("nothing".into(), Value::to_string)
                    ));
                }
            }
            None => {
                if let Some(v) = value
                    && !DERIVED.contains(&name.as_str())
                    && !has_type(s, "object")
                {
                    out.push(format!(
                        "{pointer}: filled in {v} without a documented default"
                    ));
                }
            }
        }
        if has_type(s, "object")
            && !HASHED.contains(&pointer.as_str())
            && let Some(v) = value
        {
            check_defaults(doc, s, v, &pointer, out);
        }
    }
}

fn set(body: &mut Value, pointer: &str, v: Value) {
    let mut parts: Vec<&str> = pointer.trim_start_matches('/').split('/').collect();
    let last = parts.pop().unwrap();
    let mut cur = body;
    for p in parts {
        let obj = cur.as_object_mut().unwrap();
        cur = obj
            .entry(p.to_string())
            .or_insert_with(|| Value::Object(Map::new()));
    }
    cur.as_object_mut().unwrap().insert(last.to_string(), v);
}

fn request(path: &str, leaf: &Leaf, v: f64) -> Value {
    let mut body = context(path, &leaf.pointer);
    for (p, base) in &leaf.parents {
        if body.pointer(p).is_none() {
            set(&mut body, p, base.clone());
        }
    }
    let value = if leaf.integer {
        json!(v as i64)
    } else {
        json!(v)
    };
    set(&mut body, &leaf.pointer, value);
    body
}

/// Whether validation refused `pointer` for its range (the range checker's "must be in …").
/// Refusals for another documented reason (a cross-field rule, a model limit such as an energy
/// below what double precision resolves, a step-count estimate) are not range refusals.
fn refused_for_range(r: &common::Reply, pointer: &str) -> bool {
    if r.status.as_u16() != 422 {
        return false;
    }
    let p = r.json();
    p["errors"].as_array().is_some_and(|e| {
        e.iter().any(|x| {
            x["field"] == pointer
                && x["message"]
                    .as_str()
                    .is_some_and(|m| m.starts_with("must be in"))
        })
    })
}

/// Whether the answer refuses the request naming `pointer`.
fn names_field(r: &common::Reply, pointer: &str) -> bool {
    if r.status.as_u16() != 422 {
        return false;
    }
    let p = r.json();
    p["errors"]
        .as_array()
        .is_some_and(|e| e.iter().any(|x| x["field"] == pointer))
}

fn inward(bound: f64, closed: bool, up: bool, integer: bool) -> f64 {
    if closed {
        bound
    } else if integer {
        if up { bound + 1.0 } else { bound - 1.0 }
    } else if up {
        bound.next_up()
    } else {
        bound.next_down()
    }
}

fn outward(bound: f64, closed: bool, up: bool, integer: bool) -> f64 {
    if !closed {
        bound
    } else if integer {
        if up { bound + 1.0 } else { bound - 1.0 }
    } else if up {
        bound.next_up()
    } else {
        bound.next_down()
    }
}

async fn mismatches(app: &axum::Router, doc: &Value, path: &str, schema: &str) -> Vec<String> {
    let mut out = Vec::new();
    let s = &doc["components"]["schemas"][schema];
    // (1) Defaults: documented == filled in for `{}` (a calibration: its smallest request).
    let empty = context(path, "");
    let r = common::post(app, path, &empty).await;
    assert_eq!(
        r.status,
        200,
        "{path} {empty}: {}",
        String::from_utf8_lossy(&r.body)
    );
    // What was sent is not a default (a calibration's base is checked on /v1/migration).
    let mut unsent = s.clone();
    if let (Some(props), Some(sent)) = (
        unsent.get_mut("properties").and_then(Value::as_object_mut),
        empty.as_object(),
    ) {
        for k in sent.keys() {
            props.remove(k);
        }
    }
    check_defaults(doc, &unsent, &r.json()["inputs"], "", &mut out);
    // (2) Ranges: documented == enforced.
    let mut all = Vec::new();
    let walk = Walk {
        arrays: false,
        object_arrays: false,
        // The study's base is a column request, checked on /v1/column.
        skip: &["/base"],
    };
    leaves(doc, s, "", &[], &walk, &mut all);
    for leaf in &all {
        for (bound, up, which) in [(leaf.min, false, "min"), (leaf.max, true, "max")] {
            let Some((b, closed)) = bound else { continue };
            if CROSS_FIELD.contains(&(leaf.pointer.as_str(), which)) {
                continue;
            }
            // A u64/u32 field cannot go below 0 in JSON: that is a type error, still 422.
            let inside = inward(b, closed, !up, leaf.integer);
            let outside = outward(b, closed, up, leaf.integer);
            let body = request(path, leaf, inside);
            let r = common::post(app, path, &body).await;
            if !refused_for_range(&r, &leaf.pointer) && names_field(&r, &leaf.pointer) {
                eprintln!(
                    "note: {path} {} = {inside:e} passes validation and is refused for another \
                     documented reason: {}",
                    leaf.pointer,
                    String::from_utf8_lossy(&r.body)
                );
            }
            if refused_for_range(&r, &leaf.pointer) || r.status.is_server_error() {
                out.push(format!(
                    "{} = {inside:e} (just inside the documented {which}): {} {}",
                    leaf.pointer,
                    r.status,
                    String::from_utf8_lossy(&r.body)
                ));
            }
            let body = request(path, leaf, outside);
            let r = common::post(app, path, &body).await;
            if !names_field(&r, &leaf.pointer) {
                out.push(format!(
                    "{} = {outside:e} (just outside the documented {which}): {} {}",
                    leaf.pointer,
                    r.status,
                    String::from_utf8_lossy(&r.body)
                ));
            }
        }
    }
    out
}

#[tokio::test]
async fn documented_defaults_and_ranges_are_what_the_server_does() {
    let app = common::app();
    let doc: Value = serde_json::from_str(&gangue::http::openapi::openapi_json()).unwrap();
    let mut failures = Vec::new();
    for (path, schema) in ROUTES {
        for m in mismatches(&app, &doc, path, schema).await {
            failures.push(format!("{path} {m}"));
        }
    }
    for m in &failures {
        eprintln!("{m}");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Asserts that each field listed by `/v1/presets` (pointer → bounds and default) has the same
/// bounds and default in the OpenAPI schema `request`; a default given as a string (one of
/// `kinds`, e.g. "derived") has none in the document.
fn assert_fields_are_documented(
    doc: &Value,
    request: &str,
    fields: &serde_json::Map<String, Value>,
    kinds: &[&str],
) {
    let request = &doc["components"]["schemas"][request];
    for (pointer, f) in fields {
        let mut s = request;
        for part in pointer.trim_start_matches('/').split('/') {
            let (obj, _) = resolve(doc, s);
            s = &obj["properties"][part];
            assert!(!s.is_null(), "{pointer}: no schema for {part}");
        }
        let (s, _) = resolve(doc, s);
        for key in ["minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"] {
            assert_eq!(
                s.get(key).and_then(Value::as_f64),
                f.get(key).and_then(Value::as_f64),
                "{pointer} {key}"
            );
        }
        match &f["default"] {
            Value::String(d) => {
                assert!(kinds.contains(&d.as_str()), "{pointer}: {d}");
                assert!(s.get("default").is_none(), "{pointer}");
            }
            d => assert_eq!(s.get("default"), Some(d), "{pointer}"),
        }
    }
}

/// The schema of the shared rock and column fields, their validation and `/v1/presets` come
/// from one definition: the presets' `fields` equal the OpenAPI bounds and defaults.
#[tokio::test]
async fn presets_list_the_documented_fields() {
    let app = common::app();
    let doc: Value = serde_json::from_str(&gangue::http::openapi::openapi_json()).unwrap();
    let presets = common::get(&app, "/v1/presets").await.json();
    let fields = presets["fields"].as_object().expect("presets list fields");
    assert!(fields.len() >= 17, "{}", fields.len());
    assert_fields_are_documented(&doc, "ImpactRequest", fields, &["derived"]);
    // The paper's tables in the presets are the request defaults.
    let column = &presets["column"];
    assert_eq!(
        column["first_stage"]["outer_diameter_m"],
        fields["/column/outer_diameter_m"]["default"]
    );
    assert_eq!(
        presets["rock"]["density_kg_m3"],
        fields["/rock/density_kg_m3"]["default"]
    );
}

/// The migration's numeric fields in `/v1/presets` (`migration_fields`) are the OpenAPI
/// document's: same bounds, same default (or none where derived or required).
#[tokio::test]
async fn presets_list_the_documented_migration_fields() {
    let app = common::app();
    let doc: Value = serde_json::from_str(&gangue::http::openapi::openapi_json()).unwrap();
    let presets = common::get(&app, "/v1/presets").await.json();
    let fields = presets["migration_fields"]
        .as_object()
        .expect("presets list the migration's fields");
    assert!(fields.len() >= 20, "{}", fields.len());
    assert_fields_are_documented(&doc, "MigrationRequest", fields, &["derived", "required"]);
}

/// What the page fills its forms from: `/v1/presets` `defaults` holds, for each route, the
/// request that `{}` means. Each of its values is what the server fills into `inputs` for `{}`
/// (derived fields are left out of the preset and filled by the server), and the optional
/// objects' defaults are what the server fills in when the object is sent empty.
#[tokio::test]
async fn preset_default_requests_are_what_the_server_fills_in_for_an_empty_request() {
    let app = common::app();
    let presets = common::get(&app, "/v1/presets").await.json();
    let defaults = &presets["defaults"];
    for route in [
        "impact",
        "column",
        "migration",
        "scene",
        "study",
        "spalling",
    ] {
        let preset = &defaults[route];
        assert!(preset.is_object(), "{route}: {preset}");
        let r = common::post(&app, &format!("/v1/{route}"), &json!({})).await;
        assert_eq!(
            r.status,
            200,
            "{route}: {}",
            String::from_utf8_lossy(&r.body)
        );
        let body = r.json();
        // The spalling answer echoes its zones in `inputs` too.
        let filled = &body["inputs"];
        let mut out = Vec::new();
        same_defaults(preset, filled, &format!("/v1/{route}"), &mut out);
        assert!(out.is_empty(), "{}", out.join("\n"));
        // Sending the preset itself changes nothing.
        let again = common::post(&app, &format!("/v1/{route}"), preset).await;
        assert_eq!(
            again.status,
            200,
            "{route} preset: {}",
            String::from_utf8_lossy(&again.body)
        );
        assert_eq!(again.json()["inputs"], body["inputs"], "{route}");
    }
    // Objects used only when sent: an empty one is filled with the preset's values.
    let objects = &defaults["objects"];
    for (route, body, at, preset) in [
        (
            "migration",
            json!({"monte_carlo": {"runs": 20}}),
            "/monte_carlo",
            &objects["monte_carlo"],
        ),
        (
            "scene",
            json!({"monte_carlo": {"runs": 20}}),
            "/monte_carlo",
            &objects["scene_monte_carlo"],
        ),
        (
            "scene",
            json!({"support_rows": {}}),
            "/support_rows",
            &objects["support_rows"],
        ),
    ] {
        let r = common::post(&app, &format!("/v1/{route}"), &body).await;
        assert_eq!(
            r.status,
            200,
            "{route} {body}: {}",
            String::from_utf8_lossy(&r.body)
        );
        let filled = r.json()["inputs"]
            .pointer(at)
            .cloned()
            .unwrap_or(Value::Null);
        let mut preset = preset.clone();
        preset["runs"] = json!(20);
        if at == "/support_rows" {
            preset.as_object_mut().unwrap().remove("runs");
        }
        let mut out = Vec::new();
        same_defaults(&preset, &filled, at, &mut out);
        assert!(out.is_empty(), "{route}: {}", out.join("\n"));
    }
    let floor = &objects["floor"];
    assert_eq!(floor["elevation_property"], "elevation");
    assert_eq!(
        floor["resolution_m"],
        presets["migration_fields"]["/face/floor/resolution_m"]["default"]
    );
}

/// Every value of `preset` equals the filled-in one (numbers as f64; objects by the preset's
/// keys; a floor by its kind).
fn same_defaults(preset: &Value, filled: &Value, at: &str, out: &mut Vec<String>) {
    match (preset, filled) {
        (Value::Object(p), Value::Object(f)) => {
            for (k, v) in p {
                same_defaults(
                    v,
                    f.get(k).unwrap_or(&Value::Null),
                    &format!("{at}/{k}"),
                    out,
                );
            }
        }
        (Value::Array(p), Value::Array(f)) if p.len() == f.len() => {
            for (i, (a, b)) in p.iter().zip(f).enumerate() {
                same_defaults(a, b, &format!("{at}/{i}"), out);
            }
        }
        (Value::Number(a), Value::Number(b)) if a.as_f64() == b.as_f64() => {}
        (a, b) if a == b => {}
        (a, b) => out.push(format!("{at}: preset {a}, filled in {b}")),
    }
}

/// A grid or contour floor is echoed by the SHA-256 of the floor object with its defaults filled
/// in (api.md), so a floor sent without a defaulted field and one sent with its documented
/// default hash alike, and one sent with another value does not.
#[tokio::test]
async fn floor_defaults_are_those_the_floor_is_hashed_with() {
    let app = common::app();
    let doc: Value = serde_json::from_str(&gangue::http::openapi::openapi_json()).unwrap();
    let floor = &doc["components"]["schemas"]["FloorDto"]["properties"];
    // 45° floors under the release (across 50 m on the grid, which starts at y = 0).
    let geojson = json!({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"elevation": 1.0},
         "geometry": {"type": "LineString", "coordinates": [[-1.0, -50.0], [-1.0, 50.0]]}},
        {"type": "Feature", "properties": {"elevation": -130.0},
         "geometry": {"type": "LineString", "coordinates": [[130.0, -50.0], [130.0, 50.0]]}}]});
    let bases = [
        (
            "origin_m",
            json!({"kind": "grid", "spacing_m": 100.0, "heights_m": [[0.0, -100.0], [0.0, -100.0]]}),
            json!([0.5, 0.0]),
        ),
        (
            "resolution_m",
            json!({"kind": "contours", "geojson": geojson.clone()}),
            json!(0.5),
        ),
        (
            "elevation_property",
            json!({"kind": "contours", "geojson": geojson}),
            json!("z"),
        ),
    ];
    let hash = |r: &common::Reply| r.json()["inputs"]["face"]["floor"]["sha256"].clone();
    for (name, base, other) in bases {
        let documented = floor[name]["default"].clone();
        assert!(!documented.is_null(), "{name}: no documented default");
        let mut with = base.clone();
        with[name] = documented.clone();
        let mut changed = base.clone();
        changed[name] = other;
        let mut hashes = Vec::new();
        for f in [&base, &with, &changed] {
            let body = json!({"face": {"floor": f}, "release": {"across_m": 50.0}});
            let r = common::post(&app, "/v1/migration", &body).await;
            // A different elevation property finds no elevation: refused, no hash to compare.
            if r.status != 200 {
                hashes.push(Value::Null);
                continue;
            }
            hashes.push(hash(&r));
        }
        assert!(hashes[0].is_string(), "{name}: {base} refused");
        assert_eq!(
            hashes[0], hashes[1],
            "{name}: sent as {documented} hashes differently"
        );
        assert_ne!(hashes[0], hashes[2], "{name}: another value hashes alike");
    }
}

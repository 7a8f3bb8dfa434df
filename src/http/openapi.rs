//! The OpenAPI 3.1 document, generated from the handlers and DTOs by utoipa.

use serde::Serialize;
use utoipa::{OpenApi, ToSchema};

use crate::http::dto;
use crate::http::dto::calibrate;
use crate::http::error::FieldError;
use crate::http::routes;

/// RFC 9457 problem details, as every 4xx/5xx answers them (`application/problem+json`).
#[derive(Debug, Serialize, ToSchema)]
pub struct Problem {
    /// `/problems/<code>`, e.g. `/problems/invalid_input`.
    #[serde(rename = "type")]
    #[schema(example = "/problems/invalid_input")]
    pub type_: String,
    /// Short title of the problem type.
    pub title: String,
    /// HTTP status.
    pub status: u16,
    /// What went wrong in this request.
    pub detail: String,
    /// Offending fields: JSON Pointer, value, message naming the valid range; always present,
    /// `[]` when no field is at fault (`capacity_exceeded` names `/velocity_m_s`).
    #[schema(value_type = Vec<FieldErrorDoc>)]
    pub errors: Vec<FieldError>,
    /// `capacity_exceeded` only: the largest impact speed the law can take, m/s.
    pub max_velocity_m_s: Option<f64>,
}

/// One offending field of a request.
#[derive(Debug, Serialize, ToSchema)]
pub struct FieldErrorDoc {
    /// JSON Pointer into the request, e.g. `/rock/density_kg_m3`.
    pub field: String,
    /// The offending value.
    pub value: serde_json::Value,
    /// What is wrong, naming the valid range.
    pub message: String,
}

/// `GET /healthz`: the service is up.
#[derive(Debug, Serialize, ToSchema)]
pub struct Health {
    /// Always `ok`.
    #[schema(example = "ok")]
    pub status: String,
    /// Version of the models behind the answers (the `model_version` of every result).
    #[schema(example = "0.1.0")]
    pub version: String,
}

/// `GET /v1/presets`: named defaults, presets, study ranges and limits, one object per section
/// (what each holds: the description of `/v1/presets`).
#[derive(Debug, Serialize, ToSchema)]
pub struct Presets {
    /// The rock block's named defaults (paper Table 2).
    #[schema(value_type = Object)]
    pub rock: serde_json::Map<String, serde_json::Value>,
    /// The support column's named defaults (paper Table 4).
    #[schema(value_type = Object)]
    pub column: serde_json::Map<String, serde_json::Value>,
    /// The face's named defaults (paper Table 3).
    #[schema(value_type = Object)]
    pub face: serde_json::Map<String, serde_json::Value>,
    /// Named presets.
    #[schema(value_type = Object)]
    pub presets: serde_json::Map<String, serde_json::Value>,
    /// The study's parameter ranges.
    #[schema(value_type = Object)]
    pub study: serde_json::Map<String, serde_json::Value>,
    /// The service's limits.
    #[schema(value_type = Object)]
    pub limits: serde_json::Map<String, serde_json::Value>,
    /// Numeric request fields by JSON Pointer: default and valid range.
    #[schema(value_type = Object)]
    pub fields: serde_json::Map<String, serde_json::Value>,
    /// Numeric migration fields by JSON Pointer: default and valid range.
    #[schema(value_type = Object)]
    pub migration_fields: serde_json::Map<String, serde_json::Value>,
    /// Each route's default request (what `{}` means).
    #[schema(value_type = Object)]
    pub defaults: serde_json::Map<String, serde_json::Value>,
}

/// The service's API document.
#[derive(OpenApi)]
#[openapi(
    info(
        title = "gangue",
        description = "Flying-gangue (rockfall) hazard calculations for longwall faces in steeply \
                       dipping coal seams: migration down the face, Hertz impact on a support \
                       column, column energy. SI units throughout; every unit is named in the \
                       field. Errors are RFC 9457 problem+json.",
        license(name = "MIT OR Apache-2.0")
    ),
    paths(
        routes::meta::healthz,
        routes::meta::presets,
        routes::meta::problem,
        routes::impact::impact,
        routes::column::column,
        routes::migration::migration,
        routes::scene::scene,
        routes::calibrate::calibrate,
        routes::spalling::spalling,
        routes::study::study,
        routes::batch::batch,
    ),
    components(schemas(Problem, FieldErrorDoc, dto::common::Warning, dto::common::PlanStep, dto::zones::ZonesDto)),
    tags(
        (name = "impact", description = "Contact of the rock on the column"),
        (name = "column", description = "Column vibration and energy after an impact"),
        (name = "migration", description = "Rockfall migration down the face"),
        (name = "scene", description = "The whole chain along the face, support by support"),
        (name = "calibrate", description = "Back-analysis: migration parameters from field observations"),
        (name = "spalling", description = "Coal-wall spalling statistics by face zone (Table 1)"),
        (name = "study", description = "Parameter sweeps, sensitivity measures and orderings, energy proportions"),
        (name = "batch", description = "Many requests in one call, answered as NDJSON"),
        (name = "service", description = "Health, presets, problem types"),
    )
)]
pub struct ApiDoc;

/// Request fields whose documented default is `null` (they accept `null`); every other optional
/// field may be omitted but not sent as null, and its default is described in words. A name
/// holds in every schema; `Schema.name` in that schema alone (`zones` is also spalling's).
const NULL_DEFAULTS: &[&str] = &[
    "damping_ratio",
    "initial_midpoint_displacement_m",
    "end_time_s",
    "output",
    "monte_carlo",
    "friction_coefficient",
    "impact_velocity_m_s",
    "release_zones",
    "design_limits",
    "supports",
    "support_rows",
    "across_m",
    "column_output",
    "side_length_m",
    "density_kg_m3",
    "release_across_m",
    "max_force_n",
    "absorbed_energy_j",
    "time_step_s",
    "floor_material",
    "release_rate",
    "guards",
    "column_index",
    "rocks_per_year",
    "observed_events",
    "observed_period_years",
    "maps",
    "design",
    "barriers",
    "collectors",
    "target",
    "rocks_per_year_by_zone",
    "position_m",
    "velocity_m_s",
    "orientation_wxyz",
    "angular_velocity_rad_s",
    "release_velocity_m_s",
    "releases",
    "rock",
    "FaceDto.zones",
];

/// Array-valued request fields whose length and item bounds the server enforces but utoipa cannot
/// express from the Rust type: (schema, property, minItems, maxItems, item minimum, item maximum).
/// For `vertices_m` the item is a point, an array of three coordinates each in the bounds.
const ARRAY_BOUNDS: &[(&str, &str, u64, u64, f64, f64)] = &[
    ("RockDto", "dimensions_m", 3, 3, 0.01, 5.0),
    ("RandomShapeDto", "semi_axes_m", 3, 3, 0.005, 2.5),
    ("RockDto", "vertices_m", 4, 1000, -10.0, 10.0),
    ("ReleaseDto", "position_m", 2, 2, -1e7, 1e7),
    ("ReleaseDto", "velocity_m_s", 3, 3, -1000.0, 1000.0),
    ("ReleaseDto", "orientation_wxyz", 4, 4, -1.000001, 1.000001),
    ("ReleaseDto", "angular_velocity_rad_s", 3, 3, -1e4, 1e4),
    (
        "ObservedDto",
        "runout_m",
        1,
        OBS,
        -calibrate::MAX_OBSERVED_M,
        calibrate::MAX_OBSERVED_M,
    ),
    (
        "ObservedDto",
        "horizontal_runout_m",
        1,
        OBS,
        0.0,
        calibrate::MAX_OBSERVED_M,
    ),
    (
        "CollectorObservationDto",
        "speed_m_s",
        0,
        OBS,
        0.0,
        calibrate::MAX_COLLECTOR_VALUE,
    ),
    (
        "CollectorObservationDto",
        "passing_height_m",
        0,
        OBS,
        0.0,
        calibrate::MAX_COLLECTOR_VALUE,
    ),
];

/// Most values of an observed array of a calibration.
const OBS: u64 = calibrate::MAX_OBSERVATIONS as u64;

/// Adds the documented array lengths and item bounds of [`ARRAY_BOUNDS`].
fn add_array_bounds(doc: &mut serde_json::Value) {
    use serde_json::json;
    for &(schema, prop, min_items, max_items, lo, hi) in ARRAY_BOUNDS {
        let Some(p) = doc
            .pointer_mut(&format!("/components/schemas/{schema}/properties/{prop}"))
            .and_then(|p| p.as_object_mut())
        else {
            continue;
        };
        p.insert("minItems".into(), json!(min_items));
        p.insert("maxItems".into(), json!(max_items));
        let Some(mut item) = p.get_mut("items") else {
            continue;
        };
        if prop == "vertices_m" {
            let Some(point) = item.as_object_mut() else {
                continue;
            };
            point.insert("minItems".into(), json!(3));
            point.insert("maxItems".into(), json!(3));
            let Some(coordinate) = point.get_mut("items") else {
                continue;
            };
            item = coordinate;
        }
        if let Some(item) = item.as_object_mut() {
            item.insert("minimum".into(), json!(lo));
            item.insert("maximum".into(), json!(hi));
        }
    }
}

/// How a POST answers when the client accepts NDJSON, appended to each POST's description.
pub const NDJSON_POLICY: &str = "With `Accept: application/x-ndjson` (q > 0 and at least the \
    q-value of application/json) the answer is 200 `application/x-ndjson`: `{\"progress\": \
    {\"done\", \"total\"}}` lines while the solver reports a known amount of work (runs or steps; \
    none otherwise, never a repeated line), then exactly one `{\"result\": …}` or \
    `{\"problem\": …}` line. A request refused before the computation starts (unreadable body, \
    wrong media type, invalid fields, all slots busy) is answered as plain \
    `application/problem+json` with its own status (400, 413, 415, 422, 503), not as a stream; \
    failures after the stream has started (capacity exceeded, too many steps, time limit) are its \
    problem line.";

/// The explicit error answers of every POST (problem+json), besides the 4XX/5XX ranges.
const POST_PROBLEMS: &[(&str, &str)] = &[
    ("400", "`malformed_json`: the body is not JSON"),
    (
        "413",
        "`payload_too_large`: the body is over the limit (see /v1/presets)",
    ),
    (
        "415",
        "`unsupported_media_type`: the content type is not application/json",
    ),
    (
        "422",
        "`invalid_type`, `unknown_field`, `invalid_input` (each naming the field's JSON Pointer, \
         the value and the valid range), `capacity_exceeded` (naming `/velocity_m_s`, with \
         `max_velocity_m_s`) or `too_many_steps`",
    ),
    (
        "500",
        "`internal`: always a bug; details logged, not returned",
    ),
    (
        "503",
        "`overloaded`: all computation slots are busy; retry after `Retry-After` seconds",
    ),
    (
        "504",
        "`timeout`: the computation passed the time limit and was stopped",
    ),
];

/// Documents on every POST the NDJSON answer, the explicit problem statuses and `Retry-After`.
fn add_post_responses(doc: &mut serde_json::Value) {
    use serde_json::json;
    if let Some(schemas) = doc
        .pointer_mut("/components/schemas")
        .and_then(|s| s.as_object_mut())
    {
        // Each line shape is a named component, so that client generators name its model once.
        schemas.insert(
            "NdjsonProgress".into(),
            json!({
                "description": "Work done so far of a streamed computation.",
                "type": "object",
                "required": ["done", "total"],
                "properties": {
                    "done": {"type": "integer", "minimum": 0,
                             "description": "Work units done (runs or steps)."},
                    "total": {"type": "integer", "minimum": 1,
                              "description": "Work units in all."},
                    "elapsed_s": {"type": "number", "format": "double", "minimum": 0,
                                  "description": "Seconds since the computation started."},
                    "remaining_s": {"type": "number", "format": "double", "minimum": 0,
                                    "description": "Estimated seconds left at the rate so far: \
                                        elapsed_s · (total − done) / done (omitted before any \
                                        work is done and when all is)."}
                }
            }),
        );
        schemas.insert(
            "NdjsonProgressLine".into(),
            json!({
                "description": "A progress line of an `application/x-ndjson` answer.",
                "type": "object",
                "required": ["progress"],
                "properties": {"progress": {"$ref": "#/components/schemas/NdjsonProgress"}}
            }),
        );
        schemas.insert(
            "NdjsonResultLine".into(),
            json!({
                "description": "The result line of an `application/x-ndjson` answer.",
                "type": "object",
                "required": ["result"],
                "properties": {"result": {
                    "type": "object",
                    "description": "The endpoint's 200 JSON result."
                }}
            }),
        );
        schemas.insert(
            "NdjsonProblemLine".into(),
            json!({
                "description": "The problem line of an `application/x-ndjson` answer.",
                "type": "object",
                "required": ["problem"],
                "properties": {"problem": {"$ref": "#/components/schemas/Problem"}}
            }),
        );
        schemas.insert(
            "NdjsonLine".into(),
            json!({
                "description": "One line of an `application/x-ndjson` answer: progress, then \
                                exactly one result or problem line.",
                "oneOf": [
                    {"$ref": "#/components/schemas/NdjsonProgressLine"},
                    {"$ref": "#/components/schemas/NdjsonResultLine"},
                    {"$ref": "#/components/schemas/NdjsonProblemLine"}
                ]
            }),
        );
    }
    let Some(paths) = doc.get_mut("paths").and_then(|p| p.as_object_mut()) else {
        return;
    };
    for item in paths.values_mut() {
        let Some(post) = item.get_mut("post").and_then(|p| p.as_object_mut()) else {
            continue;
        };
        let description = post
            .get("description")
            .and_then(|d| d.as_str())
            .map_or(String::new(), |d| format!("{d}\n\n"));
        post.insert(
            "description".into(),
            json!(format!("{description}{NDJSON_POLICY}")),
        );
        let Some(responses) = post.get_mut("responses").and_then(|r| r.as_object_mut()) else {
            continue;
        };
        if let Some(content) = responses
            .get_mut("200")
            .and_then(|r| r.get_mut("content"))
            .and_then(|c| c.as_object_mut())
        {
            // An endpoint that documents its own NDJSON lines (batch) keeps them.
            content
                .entry(crate::http::runner::NDJSON)
                .or_insert_with(|| json!({"schema": {"$ref": "#/components/schemas/NdjsonLine"}}));
        }
        for &(status, description) in POST_PROBLEMS {
            let mut r = json!({
                "description": description,
                "content": {super::error::PROBLEM_JSON: {
                    "schema": {"$ref": "#/components/schemas/Problem"}
                }}
            });
            if status == "503" {
                r["headers"] = json!({"Retry-After": {
                    "description": "Seconds to wait before retrying.",
                    "schema": {"type": "integer", "minimum": 1}
                }});
            }
            responses.insert(status.into(), r);
        }
    }
}

/// The served document: utoipa's, with derived defaults (which have no constant value) tidied,
/// array bounds and the POST answers (NDJSON, explicit problem statuses) added.
#[must_use]
pub fn openapi_value() -> serde_json::Value {
    // utoipa's document is plain data with string keys; should it ever fail to serialize, the
    // served document says so (and the committed-document test fails) instead of the server.
    let mut doc = serde_json::to_value(ApiDoc::openapi()).unwrap_or_else(|e| {
        serde_json::json!({
            "openapi": "3.1.0",
            "info": {"title": "gangue", "version": env!("CARGO_PKG_VERSION"),
                     "description": format!("the API document failed to serialize: {e}")},
            "paths": {}
        })
    });
    add_array_bounds(&mut doc);
    add_post_responses(&mut doc);
    if let Some(schemas) = doc
        .pointer_mut("/components/schemas")
        .and_then(|s| s.as_object_mut())
    {
        for (schema_name, schema) in schemas.iter_mut() {
            let Some(props) = schema.get_mut("properties").and_then(|p| p.as_object_mut()) else {
                continue;
            };
            for (name, prop) in props.iter_mut() {
                let Some(obj) = prop.as_object_mut() else {
                    continue;
                };
                if obj.get("default") != Some(&serde_json::Value::Null)
                    || NULL_DEFAULTS.contains(&name.as_str())
                    || NULL_DEFAULTS.contains(&format!("{schema_name}.{name}").as_str())
                {
                    continue;
                }
                obj.remove("default");
                if let Some(types) = obj.get_mut("type").and_then(|t| t.as_array_mut()) {
                    types.retain(|t| t != "null");
                    if types.len() == 1 {
                        let t = types[0].clone();
                        obj.insert("type".into(), t);
                    }
                }
                if let Some(one_of) = obj.get_mut("oneOf").and_then(|t| t.as_array_mut()) {
                    one_of.retain(|t| t.get("type") != Some(&serde_json::json!("null")));
                }
            }
        }
    }
    move_object_defaults(&mut doc);
    open_free_form_objects(&mut doc);
    doc
}

/// Writes `"additionalProperties": true` on every object schema that names no properties (a
/// batch item's `request`, the sections of `/v1/presets`, a streamed `result`). JSON Schema reads
/// the two alike; client generators type the explicit form as a map of any values
/// (openapi-typescript's `{ [key: string]: unknown }`) where the bare one becomes an object that
/// accepts no key (`Record<string, never>`).
fn open_free_form_objects(value: &mut serde_json::Value) {
    match value {
        serde_json::Value::Object(obj) => {
            let is_object = match obj.get("type") {
                Some(serde_json::Value::String(t)) => t == "object",
                Some(serde_json::Value::Array(ts)) => ts.iter().any(|t| t == "object"),
                _ => false,
            };
            if is_object
                && !obj.contains_key("properties")
                && !obj.contains_key("additionalProperties")
            {
                obj.insert("additionalProperties".into(), serde_json::Value::Bool(true));
            }
            obj.values_mut().for_each(open_free_form_objects);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(open_free_form_objects),
        _ => {}
    }
}

/// Extension keyword that carries the default of an object-valued request field: generators
/// cannot give a typed model a `default`, so the document moves it here and into the description.
pub const OBJECT_DEFAULT: &str = "x-default";

/// Moves the non-null object defaults of `$ref` properties (an omitted `column` is the paper's
/// column, `{"density_kg_m3": 7850.0, …}`) from `default` to [`OBJECT_DEFAULT`] and appends them
/// to the property's description. OpenAPI 3.1 allows `default` beside `$ref`, but client
/// generators cannot give a typed model a default value and drop the whole request model
/// (openapi-python-client: "ModelProperty cannot have a default value"); the value stays
/// machine-readable under the extension and readable in the generated docstrings. Scalar and
/// enum defaults (`"decoupled"`) and null defaults stay under `default`.
fn move_object_defaults(doc: &mut serde_json::Value) {
    let Some(schemas) = doc
        .pointer_mut("/components/schemas")
        .and_then(|s| s.as_object_mut())
    else {
        return;
    };
    for schema in schemas.values_mut() {
        let Some(props) = schema.get_mut("properties").and_then(|p| p.as_object_mut()) else {
            continue;
        };
        for prop in props.values_mut() {
            let Some(obj) = prop.as_object_mut() else {
                continue;
            };
            if !obj.get("default").is_some_and(serde_json::Value::is_object) {
                continue;
            }
            let Some(default) = obj.remove("default") else {
                continue;
            };
            let sentence = format!("Omitted: `{default}`.");
            // utoipa writes the description beside the `$ref`, inside its one-member `oneOf`.
            let described = match obj.get_mut("oneOf").and_then(|o| o.as_array_mut()) {
                Some(members) => members
                    .iter_mut()
                    .find_map(|m| m.get_mut("description").filter(|d| d.is_string())),
                None => obj.get_mut("description").filter(|d| d.is_string()),
            };
            match described {
                Some(d) => {
                    let text = d.as_str().unwrap_or_default();
                    *d = serde_json::json!(format!("{text} {sentence}"));
                }
                None => {
                    obj.insert("description".into(), serde_json::json!(sentence));
                }
            }
            obj.insert(OBJECT_DEFAULT.into(), default);
        }
    }
}

/// The document as pretty JSON with a trailing newline (the committed `openapi/openapi.json`).
#[must_use]
pub fn openapi_json() -> String {
    // `{:#}` is serde_json's pretty printer (two-space indent), infallible on a `Value`.
    format!("{:#}\n", openapi_value())
}

//! The OpenAPI 3.1 document, generated from the handlers and DTOs by utoipa.

use serde::Serialize;
use utoipa::{OpenApi, ToSchema};

use crate::http::dto;
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
    /// Offending fields: JSON Pointer, value, message naming the valid range.
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
        routes::spalling::spalling,
        routes::study::study,
        routes::batch::batch,
    ),
    components(schemas(Problem, FieldErrorDoc, dto::common::Warning, dto::common::PlanStep)),
    tags(
        (name = "impact", description = "Contact of the rock on the column"),
        (name = "column", description = "Column vibration and energy after an impact"),
        (name = "migration", description = "Rockfall migration down the face"),
        (name = "spalling", description = "Coal-wall spalling statistics by face zone (Table 1)"),
        (name = "study", description = "Parameter sweeps, sensitivity measures and orderings, energy proportions"),
        (name = "batch", description = "Many requests in one call, answered as NDJSON"),
        (name = "service", description = "Health, presets, problem types"),
    )
)]
pub struct ApiDoc;

/// Request fields whose documented default is `null` (they accept `null`); every other optional
/// field may be omitted but not sent as null, and its default is described in words.
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
    "time_step_s",
];

/// The served document: utoipa's, with derived defaults (which have no constant value) tidied.
pub fn openapi_value() -> serde_json::Value {
    let mut doc = serde_json::to_value(ApiDoc::openapi()).expect("the OpenAPI document serializes");
    if let Some(schemas) = doc
        .pointer_mut("/components/schemas")
        .and_then(|s| s.as_object_mut())
    {
        for schema in schemas.values_mut() {
            let Some(props) = schema.get_mut("properties").and_then(|p| p.as_object_mut()) else {
                continue;
            };
            for (name, prop) in props.iter_mut() {
                let Some(obj) = prop.as_object_mut() else {
                    continue;
                };
                if obj.get("default") != Some(&serde_json::Value::Null)
                    || NULL_DEFAULTS.contains(&name.as_str())
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
    doc
}

/// The document as pretty JSON with a trailing newline (the committed `openapi/openapi.json`).
pub fn openapi_json() -> String {
    let mut s = serde_json::to_string_pretty(&openapi_value()).expect("the document serializes");
    s.push('\n');
    s
}

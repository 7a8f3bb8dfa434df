//! `POST /v1/batch`: items of the other kinds in one call, answered as NDJSON lines.

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value, json};
use utoipa::ToSchema;

use crate::http::error::{ApiError, FieldError};

/// The kinds of request a batch item can be.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum BatchKind {
    /// `POST /v1/impact`.
    Impact,
    /// `POST /v1/column`.
    Column,
    /// `POST /v1/migration`.
    Migration,
    /// `POST /v1/scene`.
    Scene,
    /// `POST /v1/study`.
    Study,
    /// `POST /v1/spalling`.
    Spalling,
    /// `POST /v1/calibrate`.
    Calibrate,
}

impl BatchKind {
    /// Every kind, as named on the wire.
    pub const NAMES: [&'static str; 7] = [
        "impact",
        "column",
        "migration",
        "scene",
        "study",
        "spalling",
        "calibrate",
    ];

    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "impact" => Self::Impact,
            "column" => Self::Column,
            "migration" => Self::Migration,
            "scene" => Self::Scene,
            "study" => Self::Study,
            "spalling" => Self::Spalling,
            "calibrate" => Self::Calibrate,
            _ => return None,
        })
    }
}

/// One item of a batch (documentation schema; items are checked one by one, so a bad item gets
/// its own problem line).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct BatchItemDto {
    /// Which endpoint's request this is.
    pub kind: BatchKind,
    /// The request body of that endpoint (default `{}`: its defaults).
    #[schema(schema_with = request_schema)]
    #[serde(default)]
    pub request: Value,
}

/// Schema of an item's `request`: any JSON object (the item's endpoint checks it).
#[allow(deprecated)] // `example` is what the rest of the document uses
fn request_schema() -> utoipa::openapi::schema::Object {
    utoipa::openapi::schema::ObjectBuilder::new()
        .schema_type(utoipa::openapi::schema::Type::Object)
        .description(Some(
            "The request body of that endpoint (default `{}`: its defaults).",
        ))
        .example(Some(json!({"velocity_m_s": 6.0})))
        .build()
}

/// A batch as JSON (or send `application/x-ndjson`: one item object per line).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct BatchRequest {
    /// The items, at most the configured limit (default 1000).
    #[schema(example = json!([{"kind": "impact", "request": {"velocity_m_s": 6.0}}, {"kind": "spalling", "request": {}}]))]
    pub items: Vec<BatchItemDto>,
}

/// One line of the NDJSON answer (documentation schema).
#[derive(Debug, Serialize, ToSchema)]
pub struct BatchLine {
    /// Index of the item (NDJSON body: counting non-empty lines from 0).
    pub index: u64,
    /// HTTP status the item would have had on its own endpoint.
    pub status: u16,
    /// The item's result (status 200).
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>)]
    pub result: Option<Value>,
    /// The item's problem (other statuses), naming fields as `/items/{index}/request/…`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub problem: Option<crate::http::openapi::Problem>,
}

/// A checked item: its kind and request body.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchItem {
    /// Kind of request.
    pub kind: BatchKind,
    /// The request body.
    pub request: Value,
}

/// Checks the envelope of item `index`: an object with a known `kind` and an object `request`.
/// Problems name `/items/{index}/…`.
pub fn check_item(index: usize, v: &Value) -> Result<BatchItem, ApiError> {
    let at = format!("/items/{index}");
    let Some(obj) = v.as_object() else {
        return Err(ApiError::from_field_errors(
            "invalid_type",
            vec![FieldError {
                field: at,
                value: v.clone(),
                message: "an item must be a JSON object {\"kind\", \"request\"}".into(),
            }],
        ));
    };
    if let Some(k) = obj.keys().find(|k| *k != "kind" && *k != "request") {
        return Err(ApiError::from_field_errors(
            "unknown_field",
            vec![FieldError {
                field: format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")),
                value: obj[k].clone(),
                message: format!("unknown field `{k}`, expected `kind` or `request`"),
            }],
        ));
    }
    let kind = match obj.get("kind") {
        Some(Value::String(s)) => BatchKind::parse(s).ok_or_else(|| {
            ApiError::invalid(
                format!("{at}/kind"),
                json!(s),
                format!("must be one of {}", BatchKind::NAMES.join(", ")),
            )
        })?,
        Some(other) => {
            return Err(ApiError::from_field_errors(
                "invalid_type",
                vec![FieldError {
                    field: format!("{at}/kind"),
                    value: other.clone(),
                    message: "must be a string".into(),
                }],
            ));
        }
        None => {
            return Err(ApiError::invalid(
                format!("{at}/kind"),
                Value::Null,
                format!("is required: one of {}", BatchKind::NAMES.join(", ")),
            ));
        }
    };
    let request = match obj.get("request") {
        None => Value::Object(Map::new()),
        Some(r @ Value::Object(_)) => r.clone(),
        Some(other) => {
            return Err(ApiError::from_field_errors(
                "invalid_type",
                vec![FieldError {
                    field: format!("{at}/request"),
                    value: other.clone(),
                    message: "must be a JSON object".into(),
                }],
            ));
        }
    };
    Ok(BatchItem { kind, request })
}

/// Splits a JSON batch body into its items; envelope problems reject the whole request.
pub fn json_items(body: &Value) -> Result<Vec<Value>, ApiError> {
    let Some(obj) = body.as_object() else {
        return Err(ApiError::from_field_errors(
            "invalid_type",
            vec![FieldError {
                field: "/".into(),
                value: Value::Null,
                message: "the body must be a JSON object {\"items\": […]}".into(),
            }],
        ));
    };
    if let Some(k) = obj.keys().find(|k| *k != "items") {
        return Err(ApiError::from_field_errors(
            "unknown_field",
            vec![FieldError {
                field: format!("/{k}"),
                value: obj[k].clone(),
                message: format!("unknown field `{k}`, expected `items`"),
            }],
        ));
    }
    match obj.get("items") {
        Some(Value::Array(a)) => Ok(a.clone()),
        Some(other) => Err(ApiError::from_field_errors(
            "invalid_type",
            vec![FieldError {
                field: "/items".into(),
                value: other.clone(),
                message: "must be an array of items".into(),
            }],
        )),
        None => Err(ApiError::invalid(
            "/items",
            Value::Null,
            "is required: an array of {\"kind\", \"request\"} items",
        )),
    }
}

/// Splits an NDJSON body into items: one per non-empty line; a line that is not JSON becomes
/// that item's 400 `malformed_json` problem naming `/items/{index}`.
#[must_use]
pub fn ndjson_items(body: &[u8]) -> Vec<Result<Value, ApiError>> {
    body.split(|&b| b == b'\n')
        .filter(|line| line.iter().any(|b| !b.is_ascii_whitespace()))
        .enumerate()
        .map(|(i, line)| {
            serde_json::from_slice::<Value>(line).map_err(|e| {
                ApiError::from_field_errors(
                    "malformed_json",
                    vec![FieldError {
                        field: format!("/items/{i}"),
                        value: json!(
                            String::from_utf8_lossy(line)
                                .chars()
                                .take(200)
                                .collect::<String>()
                        ),
                        message: format!("the line of item {i} is not valid JSON: {e}"),
                    }],
                )
            })
        })
        .collect()
}

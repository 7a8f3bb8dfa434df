//! One error type for the whole service, rendered as RFC 9457 `application/problem+json`.

use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;
use serde_json::{Map, Value, json};

use crate::http::dto::param::request_pointer;
use crate::physics::{Param, PhysicsError};

/// Media type of problem responses.
pub const PROBLEM_JSON: &str = "application/problem+json";

/// A problem type: its code (the last segment of `type`), HTTP status, title and explanation.
#[derive(Debug, Clone, Copy)]
pub struct ProblemType {
    /// Code, e.g. `invalid_input`; `type` is `/problems/<code>`.
    pub code: &'static str,
    /// HTTP status.
    pub status: u16,
    /// Short title.
    pub title: &'static str,
    /// What it means and what to do, served at `/problems/<code>`.
    pub explanation: &'static str,
}

/// Every problem type the service returns (api.md, "Errors").
pub const PROBLEM_TYPES: &[ProblemType] = &[
    ProblemType {
        code: "malformed_json",
        status: 400,
        title: "Malformed JSON",
        explanation: "The request body is not valid JSON. Check quoting, commas and brackets; \
                      numbers must be plain JSON numbers (no NaN or Infinity).",
    },
    ProblemType {
        code: "payload_too_large",
        status: 413,
        title: "Payload too large",
        explanation: "The request body is larger than the service's body limit \
                      (see `limits` in GET /v1/presets). Split a batch or send a coarser floor.",
    },
    ProblemType {
        code: "unsupported_media_type",
        status: 415,
        title: "Unsupported media type",
        explanation: "Send `Content-Type: application/json` (or `application/x-ndjson` for a \
                      batch).",
    },
    ProblemType {
        code: "invalid_type",
        status: 422,
        title: "Invalid type",
        explanation: "A field has the wrong JSON type, e.g. a string where a number is expected, \
                      or an array or null where an object is expected. `errors[].field` is a JSON \
                      Pointer to it.",
    },
    ProblemType {
        code: "unknown_field",
        status: 422,
        title: "Unknown field",
        explanation: "The request names a field the schema does not have. A misspelt field would \
                      otherwise silently fall back to its default, so it is rejected. See \
                      /openapi.json for the field names.",
    },
    ProblemType {
        code: "invalid_input",
        status: 422,
        title: "Invalid input",
        explanation: "A value is out of its documented range, inconsistent with another, or a \
                      combination the models do not define. Each entry of `errors` names the \
                      field, the value and the valid range.",
    },
    ProblemType {
        code: "capacity_exceeded",
        status: 422,
        title: "Contact capacity exceeded",
        explanation: "The impact energy is larger than the largest energy the logarithmic \
                      line-contact law can store (G > 1): past that point the law has no \
                      monotone solution, and the service neither clamps nor falls back to \
                      another branch. `max_velocity_m_s` is the largest impact speed the law \
                      takes with the other inputs unchanged. Use a different law (e.g. \
                      hertz_point) or check the inputs.",
    },
    ProblemType {
        code: "too_many_steps",
        status: 422,
        title: "Too many time steps",
        explanation: "A time-stepping run would need more steps than the configured limit. \
                      Shorten the face or the end time, or raise the limit.",
    },
    ProblemType {
        code: "not_found",
        status: 404,
        title: "Not found",
        explanation: "No resource at this path. GET /openapi.json lists the endpoints.",
    },
    ProblemType {
        code: "method_not_allowed",
        status: 405,
        title: "Method not allowed",
        explanation: "The path exists but not with this HTTP method.",
    },
    ProblemType {
        code: "request_timeout",
        status: 408,
        title: "Request timeout",
        explanation: "The request body did not arrive within the body timeout (see `limits` in \
                      GET /v1/presets). Send the whole body promptly once the headers are sent.",
    },
    ProblemType {
        code: "overloaded",
        status: 503,
        title: "Overloaded",
        explanation: "All computation slots are busy. Retry after the number of seconds in the \
                      `Retry-After` header.",
    },
    ProblemType {
        code: "timeout",
        status: 504,
        title: "Computation timed out",
        explanation: "The computation passed the service's time limit and was stopped. Ask for \
                      less (fewer runs, a shorter window, fewer samples) or raise the limit.",
    },
    ProblemType {
        code: "internal",
        status: 500,
        title: "Internal error",
        explanation: "An unexpected failure inside the service; it is always a bug. The details \
                      are logged, not returned.",
    },
];

/// Looks up a problem type by code.
#[must_use]
pub fn problem_type(code: &str) -> Option<&'static ProblemType> {
    PROBLEM_TYPES.iter().find(|p| p.code == code)
}

/// One offending field of a request.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldError {
    /// JSON Pointer into the request, e.g. `/rock/density_kg_m3`.
    pub field: String,
    /// The offending value as sent (null when absent or unrepresentable).
    pub value: Value,
    /// What is wrong, naming the valid range.
    pub message: String,
}

/// An error answer of the service.
#[derive(Debug, Clone)]
pub struct ApiError {
    problem: &'static ProblemType,
    detail: String,
    errors: Vec<FieldError>,
    extensions: Map<String, Value>,
    retry_after_s: Option<u64>,
}

impl ApiError {
    /// An error of the given problem code (must be one of [`PROBLEM_TYPES`]).
    pub fn new(code: &str, detail: impl Into<String>) -> Self {
        let problem = problem_type(code).unwrap_or_else(|| {
            tracing::error!(code, "unknown problem code");
            problem_type("internal").unwrap_or(&PROBLEM_TYPES[PROBLEM_TYPES.len() - 1]) // the last is internal
        });
        Self {
            problem,
            detail: detail.into(),
            errors: Vec::new(),
            extensions: Map::new(),
            retry_after_s: None,
        }
    }

    /// `invalid_input` naming one field.
    pub fn invalid(field: impl Into<String>, value: Value, message: impl Into<String>) -> Self {
        Self::from_field_errors(
            "invalid_input",
            vec![FieldError {
                field: field.into(),
                value,
                message: message.into(),
            }],
        )
    }

    /// An error of `code` listing several offending fields; the detail summarises them.
    #[must_use]
    pub fn from_field_errors(code: &str, errors: Vec<FieldError>) -> Self {
        let detail = match errors.as_slice() {
            [] => "invalid request".to_string(),
            [one] => format!("{}: {}", one.field, one.message),
            [first, rest @ ..] => {
                format!(
                    "{}: {} (and {} more)",
                    first.field,
                    first.message,
                    rest.len()
                )
            }
        };
        let mut e = Self::new(code, detail);
        e.errors = errors;
        e
    }

    /// 503 `overloaded` with a Retry-After.
    #[must_use]
    pub fn overloaded(retry_after_s: u64) -> Self {
        let mut e = Self::new(
            "overloaded",
            "all computation slots are busy; retry shortly",
        );
        e.retry_after_s = Some(retry_after_s);
        e
    }

    /// 500 `internal`: logs `cause`, returns a generic detail.
    pub fn internal(cause: impl std::fmt::Display) -> Self {
        tracing::error!(%cause, "internal error");
        Self::new("internal", "an internal error occurred; it has been logged")
    }

    /// Fills the value of the `/velocity_m_s` entry of a `capacity_exceeded` problem with the speed
    /// that was sent, m/s (the physics error does not carry it); other problems are unchanged.
    #[must_use]
    pub fn with_capacity_velocity(mut self, velocity_m_s: f64) -> Self {
        if self.problem.code == "capacity_exceeded" {
            for e in &mut self.errors {
                if e.field == CAPACITY_FIELD {
                    e.value = num(velocity_m_s);
                }
            }
        }
        self
    }

    /// Names the field whose value drives the step count of a `too_many_steps` problem (e.g. the
    /// coupled window `/end_time_s`), with the value used; other problems are unchanged.
    #[must_use]
    pub fn with_step_field(mut self, field: &str, value: f64) -> Self {
        if self.problem.code == "too_many_steps" && self.errors.is_empty() {
            self.errors.push(FieldError {
                field: field.into(),
                value: num(value),
                message: format!("{}; shorten this window", self.detail),
            });
        }
        self
    }

    /// Adds an extension member to the problem object.
    #[must_use]
    pub fn with_extension(mut self, key: &str, value: Value) -> Self {
        self.extensions.insert(key.to_string(), value);
        self
    }

    /// The problem code, e.g. `invalid_input`.
    #[must_use]
    pub fn code(&self) -> &'static str {
        self.problem.code
    }

    /// The HTTP status.
    #[must_use]
    pub fn status(&self) -> StatusCode {
        StatusCode::from_u16(self.problem.status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR)
    }

    /// The offending fields.
    #[must_use]
    pub fn errors(&self) -> &[FieldError] {
        &self.errors
    }

    /// Prefixes every field pointer (used when a request is nested, e.g. in a batch or study).
    #[must_use]
    pub fn nest(self, prefix: &str) -> Self {
        self.rename_fields(|f| format!("{prefix}{f}"))
    }

    /// Renames every field pointer by `rename`, and the first field where the detail names it.
    #[must_use]
    pub fn rename_fields(mut self, rename: impl Fn(&str) -> String) -> Self {
        if let Some(first) = self.errors.first()
            && let Some(rest) = self.detail.strip_prefix(&format!("{}:", first.field))
        {
            self.detail = format!("{}:{rest}", rename(&first.field));
        }
        for e in &mut self.errors {
            e.field = rename(&e.field);
        }
        self
    }

    /// The problem object as JSON (also used inside batch and streaming lines).
    #[must_use]
    pub fn to_problem(&self) -> Value {
        let mut body = Map::new();
        body.insert(
            "type".into(),
            json!(format!("/problems/{}", self.problem.code)),
        );
        body.insert("title".into(), json!(self.problem.title));
        body.insert("status".into(), json!(self.problem.status));
        body.insert("detail".into(), json!(self.detail));
        // api.md: every problem carries `errors`, empty when no field is at fault.
        body.insert("errors".into(), json!(self.errors));
        for (k, v) in &self.extensions {
            body.insert(k.clone(), v.clone());
        }
        Value::Object(body)
    }
}

impl std::fmt::Display for ApiError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.problem.code, self.detail)
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = serde_json::to_vec(&self.to_problem()).unwrap_or_default();
        let mut res = (self.status(), body).into_response();
        res.headers_mut()
            .insert(header::CONTENT_TYPE, HeaderValue::from_static(PROBLEM_JSON));
        if let Some(s) = self.retry_after_s {
            res.headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(s));
        }
        res
    }
}

/// The field a `capacity_exceeded` problem names: the impact speed of the request.
pub const CAPACITY_FIELD: &str = "/velocity_m_s";

/// A finite f64 as JSON, else null.
pub fn num(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

impl From<PhysicsError> for ApiError {
    /// The problem for a physics error of a standalone request (`/v1/impact`, `/v1/column`,
    /// `/v1/migration`; a batch item nests it).
    fn from(e: PhysicsError) -> Self {
        ApiError::from_physics(e, request_pointer)
    }
}

impl ApiError {
    /// The problem for a physics error, naming a parameter at fault by `pointer(param)`: the JSON
    /// Pointer of that parameter in the request actually sent.
    pub fn from_physics(e: PhysicsError, pointer: impl Fn(Param) -> String) -> Self {
        match e {
            PhysicsError::InvalidInput {
                param,
                value,
                message,
            } => ApiError::invalid(pointer(param), num(value), message),
            PhysicsError::CapacityExceeded {
                energy_parameter,
                max_velocity_m_s,
                message,
            } => {
                let mut e = ApiError::from_field_errors(
                    "capacity_exceeded",
                    vec![FieldError {
                        field: CAPACITY_FIELD.into(),
                        value: Value::Null,
                        message: format!(
                            "must be at most {max_velocity_m_s:.6e} m/s for this law with the \
                             other inputs unchanged"
                        ),
                    }],
                );
                e.detail = message;
                e.with_extension("max_velocity_m_s", num(max_velocity_m_s))
                    .with_extension("energy_parameter", num(energy_parameter))
            }
            PhysicsError::TooManySteps { estimated, limit } => ApiError::new(
                "too_many_steps",
                format!("the run needs about {estimated:.3e} time steps; the limit is {limit:.3e}"),
            )
            .with_extension("estimated_steps", num(estimated))
            .with_extension("limit", num(limit)),
            PhysicsError::TimedOut | PhysicsError::Cancelled => ApiError::new(
                "timeout",
                "the computation passed the time limit and was stopped",
            ),
            PhysicsError::Numerical(m) => ApiError::internal(format!("numerical failure: {m}")),
        }
    }
}

/// Fallback for unknown paths: 404 problem.
pub async fn not_found() -> ApiError {
    ApiError::new("not_found", "no resource at this path")
}

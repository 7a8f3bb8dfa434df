//! `AppJson<T>`: the JSON body extractor. Malformed JSON, wrong types, unknown fields, a body that
//! is too large and a wrong media type all become problem+json, each naming the field.
//!
//! A body is parsed without a generic JSON tree, in two passes over the bytes: the first checks
//! the syntax and refuses repeated keys (keeping only the keys of the objects open at the moment),
//! the second deserializes straight into the request type through `Strict`, which refuses an
//! array where an object belongs and surplus array items at every depth. Only when the second pass
//! fails is the one value it failed at read again from the bytes, for `errors[].value`. So a body
//! takes its own bytes plus the request type it becomes, not a `Value` per number (a grid floor's
//! heights are 8 bytes each, not a tree node of 32 bytes or more).

use std::sync::Arc;
use std::time::Duration;

use axum::body::{Body, Bytes};
use axum::extract::{FromRequest, Request, State};
use axum::http::{StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use http_body_util::BodyExt;
use serde::Deserialize;
use serde::de::{self, DeserializeOwned, IntoDeserializer, Unexpected, Visitor};
use serde_json::Value;
use tokio::sync::Semaphore;

use super::error::{ApiError, FieldError};

mod check;
mod strict;
#[cfg(test)]
mod tests;

use check::*;
pub use strict::from_value;
use strict::*;

/// JSON body extractor whose rejections are problems (400/413/415/422).
#[derive(Debug, Clone, Copy, Default)]
pub struct AppJson<T>(pub T);

impl<S: Send + Sync, T: DeserializeOwned> FromRequest<S> for AppJson<T> {
    type Rejection = ApiError;

    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        if !is_json(req.headers().get(header::CONTENT_TYPE)) {
            return Err(ApiError::new(
                "unsupported_media_type",
                "send the body as Content-Type: application/json",
            ));
        }
        let bytes = read_body(req, state).await?;
        parse_body(&bytes).map(AppJson)
    }
}

/// True when the content type is `application/json` or `…+json` (parameters ignored).
#[must_use]
pub fn is_json(ct: Option<&header::HeaderValue>) -> bool {
    let Some(ct) = ct.and_then(|v| v.to_str().ok()) else {
        return false;
    };
    let essence = ct
        .split(';')
        .next()
        .unwrap_or("")
        .trim()
        .to_ascii_lowercase();
    essence == "application/json"
        || (essence.starts_with("application/") && essence.ends_with("+json"))
}

/// Reads the whole body, mapping the body limit to 413.
pub async fn read_body<S: Send + Sync>(req: Request, state: &S) -> Result<Bytes, ApiError> {
    Bytes::from_request(req, state).await.map_err(|rej| {
        if rej.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::new(
                "payload_too_large",
                "the request body is larger than the limit (see /v1/presets)",
            )
        } else {
            ApiError::new("malformed_json", format!("could not read the body: {rej}"))
        }
    })
}

/// Guards request bodies before any handler sees them: a declared `Content-Length` over the body
/// limit is refused with 413 at once (before reading, so `Expect: 100-continue` gets 413, not
/// 100); the body is admitted against a byte budget shared by all requests (its declared length,
/// or the body limit when not declared; 503 when that budget is not free within `admit_wait`),
/// then read whole within the body timeout (408 past it,
/// 413 past the limit) and handed on in memory. The budget is held until the answer is made.
#[derive(Debug)]
pub struct BodyGuard {
    /// Largest body, bytes.
    limit: usize,
    /// Time to read a body once its head is in.
    timeout: Duration,
    /// Longest wait for the budget.
    admit_wait: Duration,
    /// Budget of body bytes held at once, in KiB units.
    budget: Arc<Semaphore>,
    /// The budget's size, KiB.
    budget_kib: u32,
}

impl BodyGuard {
    /// A guard with a body limit (bytes), a read timeout, a budget (bytes) and the longest wait
    /// for the budget.
    #[must_use]
    pub fn new(limit: usize, timeout: Duration, budget_bytes: usize, admit_wait: Duration) -> Self {
        let budget_kib = u32::try_from(budget_bytes.div_ceil(1024))
            .unwrap_or(Semaphore::MAX_PERMITS as u32)
            .min(Semaphore::MAX_PERMITS as u32)
            .max(1);
        Self {
            limit,
            timeout,
            admit_wait,
            budget: Arc::new(Semaphore::new(budget_kib as usize)),
            budget_kib,
        }
    }

    /// Budget bytes not held by a body now.
    #[must_use]
    pub fn available_bytes(&self) -> usize {
        self.budget.available_permits() * 1024
    }

    /// KiB charged for a body of `bytes` (at least 1, at most the whole budget).
    fn charge_kib(&self, bytes: usize) -> u32 {
        u32::try_from(bytes.div_ceil(1024))
            .unwrap_or(u32::MAX)
            .clamp(1, self.budget_kib)
    }
}

fn too_large() -> ApiError {
    ApiError::new(
        "payload_too_large",
        "the request body is larger than the limit (see /v1/presets)",
    )
}

/// The middleware of [`BodyGuard`].
pub async fn guard_body(State(g): State<Arc<BodyGuard>>, req: Request, next: Next) -> Response {
    use axum::body::HttpBody as _;
    let hint = req.body().size_hint();
    if hint.exact() == Some(0) {
        return next.run(req).await;
    }
    let declared = req
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok())
        .or(hint.exact());
    if declared.is_some_and(|n| n > g.limit as u64) {
        return too_large().into_response();
    }
    let expected = declared.map_or(g.limit, |n| n as usize);
    let permit = match tokio::time::timeout(
        g.admit_wait,
        g.budget.clone().acquire_many_owned(g.charge_kib(expected)),
    )
    .await
    {
        Ok(Ok(p)) => p,
        _ => return ApiError::overloaded(1).into_response(),
    };
    let (parts, body) = req.into_parts();
    let bytes = match tokio::time::timeout(g.timeout, read_limited(body, g.limit, expected)).await {
        Ok(Ok(b)) => b,
        Ok(Err(e)) => return e.into_response(),
        Err(_) => {
            return ApiError::new(
                "request_timeout",
                format!(
                    "the body did not arrive within {} s",
                    g.timeout.as_secs_f64()
                ),
            )
            .into_response();
        }
    };
    let res = next
        .run(Request::from_parts(parts, Body::from(bytes)))
        .await;
    drop(permit);
    res
}

/// Reads a body into one buffer of `expected` capacity, refusing more than `limit` bytes.
async fn read_limited(mut body: Body, limit: usize, expected: usize) -> Result<Bytes, ApiError> {
    let mut buf = Vec::with_capacity(expected.min(limit));
    while let Some(frame) = body.frame().await {
        let frame = frame.map_err(|e| {
            ApiError::new("malformed_json", format!("could not read the body: {e}"))
        })?;
        if let Ok(data) = frame.into_data() {
            if buf.len() + data.len() > limit {
                return Err(too_large());
            }
            buf.extend_from_slice(&data);
        }
    }
    Ok(Bytes::from(buf))
}

/// Parses bytes as JSON, mapping failures to 400 `malformed_json` with line and column. An object
/// with the same key twice is 422 `invalid_input` naming the repeated key's JSON Pointer (JSON
/// parsers disagree on which one wins, so the request is ambiguous).
pub fn parse_json(bytes: &[u8]) -> Result<Value, ApiError> {
    let dup = std::cell::RefCell::new(None);
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let parsed = de::DeserializeSeed::deserialize(
        NoDuplicates {
            path: &Path::Root,
            dup: &dup,
        },
        &mut de,
    )
    .and_then(|v| de.end().map(|()| v));
    match parsed {
        Ok(v) => Ok(v),
        Err(e) => match dup.into_inner() {
            Some((field, value)) => Err(ApiError::from_field_errors(
                "invalid_input",
                vec![FieldError {
                    message: "this key appears more than once in its object; send it once".into(),
                    field,
                    value,
                }],
            )),
            None => Err(ApiError::new(
                "malformed_json",
                format!("the body is not valid JSON: {e}"),
            )),
        },
    }
}

/// Parses a JSON body straight into `T` (module documentation): 400 `malformed_json` for bad
/// syntax, 422 naming a repeated key, then 422 `invalid_type`/`unknown_field`/`invalid_input`
/// naming the JSON Pointer of the field, with the value sent there, exactly as
/// [`parse_json`] followed by [`from_value`] would answer.
pub fn parse_body<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, ApiError> {
    check_json(bytes)?;
    let mut de = serde_json::Deserializer::from_slice(bytes);
    match serde_path_to_error::deserialize(Strict(&mut de)) {
        Ok(v) => Ok(v),
        Err(err) => Err(field_problem(&err, |pointer| {
            value_at(bytes, pointer).unwrap_or(Value::Null)
        })),
    }
}

/// Checks that `bytes` are one JSON value and that no object repeats a key, building nothing:
/// the same answers as [`parse_json`] without its tree.
pub fn check_json(bytes: &[u8]) -> Result<(), ApiError> {
    let dup = std::cell::RefCell::new(None);
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let checked = de::DeserializeSeed::deserialize(
        CheckOnly {
            path: &Path::Root,
            dup: &dup,
        },
        &mut de,
    )
    .and_then(|()| de.end());
    checked.map_err(|e| parse_problem(&e, dup.into_inner()))
}

/// The problem for a failed first pass: the repeated key when one was found, else bad syntax.
fn parse_problem(e: &serde_json::Error, dup: Option<(String, Value)>) -> ApiError {
    match dup {
        Some((field, value)) => ApiError::from_field_errors(
            "invalid_input",
            vec![FieldError {
                message: "this key appears more than once in its object; send it once".into(),
                field,
                value,
            }],
        ),
        None => ApiError::new("malformed_json", format!("the body is not valid JSON: {e}")),
    }
}

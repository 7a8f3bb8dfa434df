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

/// Walks a JSON document like [`NoDuplicates`] but keeps nothing except, per open object, its
/// keys; a repeated key's value is read (as a tree) only to report it.
struct CheckOnly<'a> {
    path: &'a Path<'a>,
    dup: &'a std::cell::RefCell<Option<(String, Value)>>,
}

impl<'de> de::DeserializeSeed<'de> for CheckOnly<'_> {
    type Value = ();

    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for CheckOnly<'_> {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }

    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }

    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        Ok(())
    }

    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }

    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }

    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }

    fn visit_none<E>(self) -> Result<(), E> {
        Ok(())
    }

    fn visit_some<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let mut i = 0usize;
        loop {
            let path = Path::Index(self.path, i);
            let seed = CheckOnly {
                path: &path,
                dup: self.dup,
            };
            match seq.next_element_seed(seed)? {
                Some(()) => i += 1,
                None => return Ok(()),
            }
        }
    }

    fn visit_map<A: de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let mut seen = std::collections::HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            let path = Path::Key(self.path, &key);
            if seen.contains(&key) {
                // Read the repeated value as NoDuplicates does (a repeat inside it is named first).
                let value = map.next_value_seed(NoDuplicates {
                    path: &path,
                    dup: self.dup,
                })?;
                let pointer = path.pointer();
                *self.dup.borrow_mut() = Some((pointer.clone(), value));
                return Err(de::Error::custom(format_args!(
                    "duplicate key at {pointer}"
                )));
            }
            map.next_value_seed(CheckOnly {
                path: &path,
                dup: self.dup,
            })?;
            seen.insert(key);
        }
        Ok(())
    }
}

/// The value at JSON Pointer `pointer` of the document `bytes` (already checked), read without
/// building the rest of the document; `None` when nothing is there.
fn value_at(bytes: &[u8], pointer: &str) -> Option<Value> {
    let segments: Vec<String> = if pointer.is_empty() {
        Vec::new()
    } else {
        pointer
            .strip_prefix('/')?
            .split('/')
            .map(|s| s.replace("~1", "/").replace("~0", "~"))
            .collect()
    };
    let mut de = serde_json::Deserializer::from_slice(bytes);
    de::DeserializeSeed::deserialize(Pick(&segments), &mut de).ok()?
}

/// Reads the value at a path of object keys and array indexes (as strings), skipping the rest.
struct Pick<'a>(&'a [String]);

impl<'de> de::DeserializeSeed<'de> for Pick<'_> {
    type Value = Option<Value>;

    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Option<Value>, D::Error> {
        if self.0.is_empty() {
            return Value::deserialize(d).map(Some);
        }
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Pick<'_> {
    type Value = Option<Value>;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_bool<E>(self, _: bool) -> Result<Option<Value>, E> {
        Ok(None)
    }

    fn visit_i64<E>(self, _: i64) -> Result<Option<Value>, E> {
        Ok(None)
    }

    fn visit_u64<E>(self, _: u64) -> Result<Option<Value>, E> {
        Ok(None)
    }

    fn visit_f64<E>(self, _: f64) -> Result<Option<Value>, E> {
        Ok(None)
    }

    fn visit_str<E>(self, _: &str) -> Result<Option<Value>, E> {
        Ok(None)
    }

    fn visit_unit<E>(self) -> Result<Option<Value>, E> {
        Ok(None)
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Option<Value>, A::Error> {
        let want = self.0[0].parse::<usize>().ok();
        let mut found = None;
        let mut i = 0usize;
        loop {
            if found.is_none() && want == Some(i) {
                match seq.next_element_seed(Pick(&self.0[1..]))? {
                    Some(v) => found = v,
                    None => break,
                }
            } else if seq.next_element::<de::IgnoredAny>()?.is_none() {
                break;
            }
            i += 1;
        }
        Ok(found)
    }

    fn visit_map<A: de::MapAccess<'de>>(self, mut map: A) -> Result<Option<Value>, A::Error> {
        let mut found = None;
        while let Some(key) = map.next_key::<String>()? {
            if found.is_none() && key == self.0[0] {
                found = map.next_value_seed(Pick(&self.0[1..]))?;
            } else {
                map.next_value::<de::IgnoredAny>()?;
            }
        }
        Ok(found)
    }
}

/// Where a value sits in the document, rendered as a JSON Pointer only when a duplicate is found
/// (so that parsing a large floor allocates no path strings).
enum Path<'a> {
    Root,
    Key(&'a Path<'a>, &'a str),
    Index(&'a Path<'a>, usize),
}

impl Path<'_> {
    fn pointer(&self) -> String {
        match self {
            Path::Root => String::new(),
            Path::Key(parent, k) => format!("{}/{}", parent.pointer(), escape(k)),
            Path::Index(parent, i) => format!("{}/{i}", parent.pointer()),
        }
    }
}

/// Builds a [`Value`] like serde_json's own, but stops at the first repeated key of an object,
/// recording its pointer and the repeated value in `dup`.
struct NoDuplicates<'a> {
    path: &'a Path<'a>,
    dup: &'a std::cell::RefCell<Option<(String, Value)>>,
}

impl<'de> de::DeserializeSeed<'de> for NoDuplicates<'_> {
    type Value = Value;

    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for NoDuplicates<'_> {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }

    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number))
    }

    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_owned()))
    }

    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }

    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_some<D: de::Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(self)
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        loop {
            let path = Path::Index(self.path, out.len());
            let seed = NoDuplicates {
                path: &path,
                dup: self.dup,
            };
            match seq.next_element_seed(seed)? {
                Some(v) => out.push(v),
                None => break,
            }
        }
        Ok(Value::Array(out))
    }

    fn visit_map<A: de::MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut out = serde_json::Map::new();
        while let Some(key) = map.next_key::<String>()? {
            let path = Path::Key(self.path, &key);
            let seed = NoDuplicates {
                path: &path,
                dup: self.dup,
            };
            let value = map.next_value_seed(seed)?;
            if out.contains_key(&key) {
                let pointer = path.pointer();
                *self.dup.borrow_mut() = Some((pointer.clone(), value));
                return Err(de::Error::custom(format_args!(
                    "duplicate key at {pointer}"
                )));
            }
            out.insert(key, value);
        }
        Ok(Value::Object(out))
    }
}

/// Deserializes a parsed JSON value strictly: every object in the schema must be a JSON object,
/// unknown fields and wrong types are problems naming the JSON Pointer of the field.
pub fn from_value<T: DeserializeOwned>(value: &Value) -> Result<T, ApiError> {
    serde_path_to_error::deserialize(StrictValue(value)).map_err(|err| {
        field_problem(&err, |pointer| {
            value.pointer(pointer).cloned().unwrap_or(Value::Null)
        })
    })
}

/// The 422 problem of a failed strict deserialization: the JSON Pointer of the field (of the key
/// itself for an unknown field), the code and serde's message, with the value sent there
/// (`value_at` reads it for a pointer).
fn field_problem(
    err: &serde_path_to_error::Error<serde_json::Error>,
    value_at: impl FnOnce(&str) -> Value,
) -> ApiError {
    let inner = err.inner();
    let mut msg = inner.to_string();
    // A streaming parse appends the position; the pointer says where, the position is noise.
    if inner.line() > 0 {
        let suffix = format!(" at line {} column {}", inner.line(), inner.column());
        if let Some(stripped) = msg.strip_suffix(&suffix) {
            msg = stripped.to_owned();
        }
    }
    let mut pointer = path_to_pointer(err.path());
    let code = if msg.starts_with("unknown field") {
        // The path ends at the object holding the unknown key; point at the key itself.
        if let Some(name) = msg.split('`').nth(1)
            && !pointer.ends_with(&format!("/{}", escape(name)))
        {
            pointer = format!("{pointer}/{}", escape(name));
        }
        "unknown_field"
    } else if msg.starts_with("invalid type") || msg.starts_with("invalid length") {
        "invalid_type"
    } else {
        "invalid_input"
    };
    let value = value_at(&pointer);
    ApiError::from_field_errors(
        code,
        vec![FieldError {
            field: if pointer.is_empty() {
                "/".into()
            } else {
                pointer
            },
            value,
            message: msg,
        }],
    )
}

fn escape(seg: &str) -> String {
    seg.replace('~', "~0").replace('/', "~1")
}

fn path_to_pointer(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    for seg in path.iter() {
        match seg {
            Segment::Map { key } => {
                out.push('/');
                out.push_str(&escape(key));
            }
            Segment::Seq { index } => {
                out.push('/');
                out.push_str(&index.to_string());
            }
            Segment::Enum { .. } | Segment::Unknown => {}
        }
    }
    out
}

fn unexpected(v: &Value) -> Unexpected<'_> {
    match v {
        Value::Null => Unexpected::Unit,
        Value::Bool(b) => Unexpected::Bool(*b),
        Value::Number(n) => n
            .as_u64()
            .map(Unexpected::Unsigned)
            .or_else(|| n.as_i64().map(Unexpected::Signed))
            .unwrap_or_else(|| Unexpected::Float(n.as_f64().unwrap_or(0.0))),
        Value::String(s) => Unexpected::Str(s),
        Value::Array(_) => Unexpected::Seq,
        Value::Object(_) => Unexpected::Map,
    }
}

/// A deserializer over a borrowed [`Value`] that, unlike serde_json's, refuses an array where a
/// struct is expected (serde's derived structs accept sequences) and applies that at every depth.
struct StrictValue<'a>(&'a Value);

impl<'de> de::Deserializer<'de> for StrictValue<'_> {
    type Error = serde_json::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Null => visitor.visit_unit(),
            Value::Bool(b) => visitor.visit_bool(*b),
            Value::Number(n) => {
                if let Some(u) = n.as_u64() {
                    visitor.visit_u64(u)
                } else if let Some(i) = n.as_i64() {
                    visitor.visit_i64(i)
                } else {
                    visitor.visit_f64(n.as_f64().unwrap_or(f64::NAN))
                }
            }
            Value::String(s) => visitor.visit_str(s),
            Value::Array(items) => {
                let mut seq = SeqAccess(items.iter());
                let out = visitor.visit_seq(&mut seq)?;
                if seq.0.len() > 0 {
                    return Err(de::Error::invalid_length(items.len(), &"fewer elements"));
                }
                Ok(out)
            }
            Value::Object(map) => visitor.visit_map(MapAccess {
                iter: map.iter(),
                value: None,
            }),
        }
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Null => visitor.visit_none(),
            _ => visitor.visit_some(self),
        }
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        self.deserialize_map(visitor)
    }

    fn deserialize_map<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Object(_) => self.deserialize_any(visitor),
            other => Err(de::Error::invalid_type(unexpected(other), &"a JSON object")),
        }
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::String(s) => visitor.visit_enum(s.as_str().into_deserializer()),
            other => Err(de::Error::invalid_type(unexpected(other), &"a string")),
        }
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        visitor.visit_newtype_struct(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf unit
        unit_struct seq tuple tuple_struct identifier ignored_any
    }
}

struct SeqAccess<'a>(std::slice::Iter<'a, Value>);

impl<'de> de::SeqAccess<'de> for SeqAccess<'_> {
    type Error = serde_json::Error;

    fn next_element_seed<T: de::DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, Self::Error> {
        self.0
            .next()
            .map(|v| seed.deserialize(StrictValue(v)))
            .transpose()
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.0.len())
    }
}

struct MapAccess<'a> {
    iter: serde_json::map::Iter<'a>,
    value: Option<&'a Value>,
}

impl<'de> de::MapAccess<'de> for MapAccess<'_> {
    type Error = serde_json::Error;

    fn next_key_seed<K: de::DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Self::Error> {
        match self.iter.next() {
            Some((k, v)) => {
                self.value = Some(v);
                seed.deserialize(k.as_str().into_deserializer()).map(Some)
            }
            None => Ok(None),
        }
    }

    fn next_value_seed<V: de::DeserializeSeed<'de>>(
        &mut self,
        seed: V,
    ) -> Result<V::Value, Self::Error> {
        let v = self
            .value
            .take()
            .ok_or_else(|| <serde_json::Error as de::Error>::custom("value without a key"))?;
        seed.deserialize(StrictValue(v))
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.iter.len())
    }
}

/// A wrapper around any JSON deserializer (here serde_json's streaming one) that answers like
/// [`StrictValue`] over a tree: an object is required where a struct or map is expected, an enum
/// is a string, and an array longer than its type is refused ("invalid length N, expected fewer
/// elements"), at every depth.
struct Strict<D>(D);

/// Forwards `deserialize_*` methods to the inner deserializer with the visitor wrapped.
macro_rules! strict_forward {
    ($($method:ident)*) => {
        $(
            fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
                self.0.$method(Wrap { v: visitor, object: false })
            }
        )*
    };
}

impl<'de, D: de::Deserializer<'de>> de::Deserializer<'de> for Strict<D> {
    type Error = D::Error;

    strict_forward! {
        deserialize_any deserialize_bool deserialize_i8 deserialize_i16 deserialize_i32
        deserialize_i64 deserialize_i128 deserialize_u8 deserialize_u16 deserialize_u32
        deserialize_u64 deserialize_u128 deserialize_f32 deserialize_f64 deserialize_char
        deserialize_str deserialize_string deserialize_bytes deserialize_byte_buf
        deserialize_option deserialize_unit deserialize_seq deserialize_identifier
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
        self.0.deserialize_ignored_any(visitor)
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_unit_struct(
            name,
            Wrap {
                v: visitor,
                object: false,
            },
        )
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_newtype_struct(
            name,
            Wrap {
                v: visitor,
                object: false,
            },
        )
    }

    fn deserialize_tuple<V: Visitor<'de>>(
        self,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_tuple(
            len,
            Wrap {
                v: visitor,
                object: false,
            },
        )
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_tuple_struct(
            name,
            len,
            Wrap {
                v: visitor,
                object: false,
            },
        )
    }

    fn deserialize_map<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
        self.0.deserialize_map(Wrap {
            v: visitor,
            object: true,
        })
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.deserialize_map(visitor)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_any(EnumFromString(visitor))
    }

    fn is_human_readable(&self) -> bool {
        self.0.is_human_readable()
    }
}

/// A visitor whose nested values go through [`Strict`]; `object` makes it expect a JSON object
/// (its message then says so).
struct Wrap<V> {
    v: V,
    object: bool,
}

/// Forwards `visit_*` methods of plain values to the inner visitor.
macro_rules! wrap_forward {
    ($($method:ident: $ty:ty)*) => {
        $(
            fn $method<E: de::Error>(self, x: $ty) -> Result<Self::Value, E> {
                self.v.$method(x)
            }
        )*
    };
}

impl<'de, V: Visitor<'de>> Visitor<'de> for Wrap<V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.object {
            f.write_str("a JSON object")
        } else {
            self.v.expecting(f)
        }
    }

    wrap_forward! {
        visit_bool: bool visit_i8: i8 visit_i16: i16 visit_i32: i32 visit_i64: i64
        visit_i128: i128 visit_u8: u8 visit_u16: u16 visit_u32: u32 visit_u64: u64
        visit_u128: u128 visit_f32: f32 visit_f64: f64 visit_char: char visit_str: &str
        visit_borrowed_str: &'de str visit_string: String visit_bytes: &[u8]
        visit_borrowed_bytes: &'de [u8] visit_byte_buf: Vec<u8>
    }

    fn visit_none<E: de::Error>(self) -> Result<V::Value, E> {
        self.v.visit_none()
    }

    fn visit_unit<E: de::Error>(self) -> Result<V::Value, E> {
        self.v.visit_unit()
    }

    fn visit_some<D: de::Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
        self.v.visit_some(Strict(d))
    }

    fn visit_newtype_struct<D: de::Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
        self.v.visit_newtype_struct(Strict(d))
    }

    fn visit_seq<A: de::SeqAccess<'de>>(self, seq: A) -> Result<V::Value, A::Error> {
        let mut wrapped = StrictSeq { seq, taken: 0 };
        let out = self.v.visit_seq(&mut wrapped)?;
        let mut extra = 0usize;
        while wrapped.seq.next_element::<de::IgnoredAny>()?.is_some() {
            extra += 1;
        }
        if extra > 0 {
            return Err(de::Error::invalid_length(
                wrapped.taken + extra,
                &"fewer elements",
            ));
        }
        Ok(out)
    }

    fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<V::Value, A::Error> {
        self.v.visit_map(StrictMap(map))
    }

    fn visit_enum<A: de::EnumAccess<'de>>(self, data: A) -> Result<V::Value, A::Error> {
        self.v.visit_enum(data)
    }
}

/// The elements of a sequence, each through [`Strict`], counted.
struct StrictSeq<A> {
    seq: A,
    taken: usize,
}

impl<'de, A: de::SeqAccess<'de>> de::SeqAccess<'de> for StrictSeq<A> {
    type Error = A::Error;

    fn next_element_seed<T: de::DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, A::Error> {
        let out = self.seq.next_element_seed(StrictSeed(seed))?;
        if out.is_some() {
            self.taken += 1;
        }
        Ok(out)
    }

    fn size_hint(&self) -> Option<usize> {
        self.seq.size_hint()
    }
}

/// The values of a map, each through [`Strict`] (keys as they are).
struct StrictMap<A>(A);

impl<'de, A: de::MapAccess<'de>> de::MapAccess<'de> for StrictMap<A> {
    type Error = A::Error;

    fn next_key_seed<K: de::DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        self.0.next_key_seed(seed)
    }

    fn next_value_seed<T: de::DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<T::Value, A::Error> {
        self.0.next_value_seed(StrictSeed(seed))
    }

    fn size_hint(&self) -> Option<usize> {
        self.0.size_hint()
    }
}

/// A seed deserialized through [`Strict`].
struct StrictSeed<T>(T);

impl<'de, T: de::DeserializeSeed<'de>> de::DeserializeSeed<'de> for StrictSeed<T> {
    type Value = T::Value;

    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<T::Value, D::Error> {
        self.0.deserialize(Strict(d))
    }
}

/// An enum from a JSON string only (as [`StrictValue`]): anything else is "invalid type …,
/// expected a string".
struct EnumFromString<V>(V);

impl<'de, V: Visitor<'de>> Visitor<'de> for EnumFromString<V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a string")
    }

    fn visit_str<E: de::Error>(self, s: &str) -> Result<V::Value, E> {
        self.0.visit_enum(s.into_deserializer())
    }

    fn visit_borrowed_str<E: de::Error>(self, s: &'de str) -> Result<V::Value, E> {
        self.visit_str(s)
    }

    fn visit_string<E: de::Error>(self, s: String) -> Result<V::Value, E> {
        self.visit_str(&s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;
    use serde_json::json;

    #[derive(Debug, Deserialize, PartialEq, Default)]
    #[serde(deny_unknown_fields, default)]
    struct Inner {
        a: f64,
    }

    #[derive(Debug, Deserialize, PartialEq, Default)]
    #[serde(deny_unknown_fields, default)]
    struct Outer {
        inner: Inner,
        list: Vec<f64>,
        opt: Option<f64>,
    }

    #[allow(clippy::needless_pass_by_value, reason = "called with json! literals")]
    fn err(v: Value) -> ApiError {
        from_value::<Outer>(&v).unwrap_err()
    }

    #[test]
    fn accepts_objects_and_defaults() {
        let o: Outer = from_value(&json!({"inner": {"a": 2}, "opt": null})).unwrap();
        assert_eq!(o.inner.a, 2.0);
        assert_eq!(o.opt, None);
    }

    #[test]
    fn rejects_arrays_where_objects_belong_at_every_depth() {
        let e = err(json!([]));
        assert_eq!(e.code(), "invalid_type");
        let e = err(json!({"inner": [1.0]}));
        assert_eq!(e.code(), "invalid_type");
        assert_eq!(e.errors()[0].field, "/inner");
    }

    #[test]
    fn unknown_field_points_at_the_key() {
        let e = err(json!({"inner": {"b": 1}}));
        assert_eq!(e.code(), "unknown_field");
        assert_eq!(e.errors()[0].field, "/inner/b");
        assert_eq!(e.errors()[0].value, json!(1));
    }

    #[test]
    fn wrong_type_and_null_are_invalid_type() {
        let e = err(json!({"inner": {"a": "x"}}));
        assert_eq!(e.code(), "invalid_type");
        assert_eq!(e.errors()[0].field, "/inner/a");
        let e = err(json!({"inner": {"a": null}}));
        assert_eq!(e.code(), "invalid_type");
        let e = err(json!({"list": [1, "x"]}));
        assert_eq!(e.errors()[0].field, "/list/1");
    }

    #[test]
    fn duplicate_keys_are_refused_naming_the_key() {
        let e = parse_json(br#"{"a": 1, "a": 2}"#).unwrap_err();
        assert_eq!(e.code(), "invalid_input");
        assert_eq!(e.errors()[0].field, "/a");
        assert_eq!(e.errors()[0].value, json!(2));
        let e = parse_json(br#"{"x": [{"k": 1}, {"k/~": 1, "k/~": {"z": 3}}]}"#).unwrap_err();
        assert_eq!(e.errors()[0].field, "/x/1/k~1~0");
        assert_eq!(e.errors()[0].value, json!({"z": 3}));
        // Same key in sibling objects is fine; the value equals serde_json's parse.
        let text = br#"{"a": {"k": 1}, "b": {"k": [1.5, -2, 1e300, null, true, "s"]}}"#;
        let v = parse_json(text).unwrap();
        assert_eq!(v, serde_json::from_slice::<Value>(text).unwrap());
    }

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    enum Kind {
        #[serde(rename = "one")]
        One,
        #[serde(rename = "two")]
        Two,
    }

    #[derive(Debug, Deserialize, PartialEq, Default)]
    #[serde(deny_unknown_fields, default)]
    struct Wide {
        inner: Inner,
        list: Vec<f64>,
        opt: Option<f64>,
        three: Option<[f64; 3]>,
        rows: Vec<Vec<f64>>,
        kind: Option<Kind>,
        n: u32,
        name: String,
        flag: bool,
        any: Option<Value>,
        items: Vec<Inner>,
    }

    /// The streaming parse answers exactly what the tree parse did (code, pointer, message and
    /// value), for good bodies and for every kind of refusal, at several depths.
    #[test]
    fn streaming_parse_answers_like_the_tree_parse() {
        let bodies: &[&str] = &[
            r#"{}"#,
            r#"{"inner": {"a": 2}, "opt": null, "list": [1, 2.5, -3e-300]}"#,
            r#"[]"#,
            r#"null"#,
            r#"3"#,
            r#"{"inner": [1.0]}"#,
            r#"{"inner": null}"#,
            r#"{"inner": {"b": 1}}"#,
            r#"{"inner": {"a": "x"}}"#,
            r#"{"inner": {"a": null}}"#,
            r#"{"list": [1, "x"]}"#,
            r#"{"list": {"a": 1}}"#,
            r#"{"three": [1, 2, 3]}"#,
            r#"{"three": [1, 2]}"#,
            r#"{"three": [1, 2, 3, 4, 5]}"#,
            r#"{"three": null}"#,
            r#"{"rows": [[1, 2], [3, "4"]]}"#,
            r#"{"rows": [[1, 2], 3]}"#,
            r#"{"kind": "one"}"#,
            r#"{"kind": "three"}"#,
            r#"{"kind": {"one": null}}"#,
            r#"{"kind": 1}"#,
            r#"{"n": -1}"#,
            r#"{"n": 1.5}"#,
            r#"{"n": 5000000000}"#,
            r#"{"n": 1e3}"#,
            r#"{"name": 1}"#,
            r#"{"name": "é\u00e9\n"}"#,
            r#"{"flag": "true"}"#,
            r#"{"any": {"x": [1, {"y": null}]}}"#,
            r#"{"items": [{"a": 1}, {"a": 2, "c": [1]}]}"#,
            r#"{"items": [{"a": 1}, [2]]}"#,
            r#"{"items/x~y": 1}"#,
            r#"{"a": 1, "a": 2}"#,
            r#"{"inner": {"a": 1, "a": {"k": 1, "k": 2}}}"#,
            r#"{"inner": {"a": 1}"#,
            r#"{"list": [1, 2,]}"#,
            r#"{"list": [1e400]}"#,
            r#"{"name": "x"} trailing"#,
            "",
        ];
        for body in bodies {
            let tree = parse_json(body.as_bytes()).and_then(|v| from_value::<Wide>(&v));
            let stream = parse_body::<Wide>(body.as_bytes());
            match (tree, stream) {
                (Ok(a), Ok(b)) => assert_eq!(a, b, "{body}"),
                (Err(a), Err(b)) => {
                    let (mut pa, mut pb) = (a.to_problem(), b.to_problem());
                    if a.code() == "malformed_json" {
                        // serde_json's syntax message is the same; only ensure both are 400.
                        pa["detail"] = Value::Null;
                        pb["detail"] = Value::Null;
                    }
                    assert_eq!(pa, pb, "{body}");
                }
                (a, b) => panic!("{body}: tree {a:?}, streaming {b:?}"),
            }
        }
    }

    #[test]
    fn value_at_reads_one_value_of_the_document() {
        let doc = br#"{"a": [1, {"b/c": [true, "x"]}], "d~e": null, "f": 2}"#;
        assert_eq!(value_at(doc, "/a/1/b~1c/1"), Some(json!("x")));
        assert_eq!(value_at(doc, "/a/0"), Some(json!(1)));
        assert_eq!(value_at(doc, "/d~0e"), Some(Value::Null));
        assert_eq!(value_at(doc, "/f"), Some(json!(2)));
        assert_eq!(value_at(doc, "/a/2"), None);
        assert_eq!(value_at(doc, "/zz"), None);
        assert_eq!(
            value_at(doc, ""),
            Some(serde_json::from_slice::<Value>(doc).unwrap())
        );
    }

    #[test]
    fn malformed_json_stays_400() {
        for text in [&b"{"[..], b"{\"a\": 1} x", b"", b"{\"a\": NaN}", b"[1,]"] {
            let e = parse_json(text).unwrap_err();
            assert_eq!(
                e.code(),
                "malformed_json",
                "{}",
                String::from_utf8_lossy(text)
            );
        }
    }

    #[test]
    fn media_type_check() {
        let h = |s: &'static str| header::HeaderValue::from_static(s);
        assert!(is_json(Some(&h("application/json"))));
        assert!(is_json(Some(&h("application/json; charset=utf-8"))));
        assert!(is_json(Some(&h("application/problem+json"))));
        assert!(!is_json(Some(&h("text/plain"))));
        assert!(!is_json(None));
    }
}

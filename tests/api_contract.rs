//! The wire contract beyond single endpoints: every problem the service can produce matches the
//! committed OpenAPI `Problem` schema (api.md "Errors": `errors` always present, `[]` when no field
//! is at fault); every field that is sent is checked against its own range whether the case uses
//! it or not; duplicate keys are refused; `Accept` negotiation honours q-values and case; NDJSON
//! progress never sends empty lines; the OpenAPI document states what the server enforces.

mod common;

use std::collections::BTreeSet;

use axum::http::Method;
use common::{assert_problem, get, post, send};
use serde_json::{Value, json};

/// The committed OpenAPI document (what clients read).
fn committed_doc() -> Value {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("openapi/openapi.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A small JSON-Schema (2020-12 subset used by the document) check: `$ref`, `type` (string or
/// list), `required`, `properties`, `items`, `oneOf`, `minimum`/`maximum`, `minItems`/`maxItems`,
/// `enum`. Returns the violations, each with the instance path.
fn violations(doc: &Value, schema: &Value, v: &Value, at: &str, out: &mut Vec<String>) {
    if let Some(r) = schema.get("$ref").and_then(Value::as_str) {
        let target = doc
            .pointer(r.trim_start_matches('#'))
            .unwrap_or_else(|| panic!("dangling $ref {r}"));
        violations(doc, target, v, at, out);
    }
    if let Some(t) = schema.get("type") {
        let types: Vec<&str> = match t {
            Value::String(s) => vec![s.as_str()],
            Value::Array(a) => a.iter().filter_map(Value::as_str).collect(),
            _ => vec![],
        };
        let ok = types.iter().any(|t| match *t {
            "object" => v.is_object(),
            "array" => v.is_array(),
            "string" => v.is_string(),
            "number" => v.is_number(),
            "integer" => v.is_i64() || v.is_u64(),
            "boolean" => v.is_boolean(),
            "null" => v.is_null(),
            _ => false,
        });
        if !ok {
            out.push(format!("{at}: {v} is not of type {t}"));
            return;
        }
    }
    if let Some(e) = schema.get("enum").and_then(Value::as_array)
        && !e.contains(v)
    {
        out.push(format!("{at}: {v} not in {e:?}"));
    }
    if let (Some(min), Some(x)) = (schema.get("minimum").and_then(Value::as_f64), v.as_f64())
        && x < min
    {
        out.push(format!("{at}: {x} < minimum {min}"));
    }
    if let (Some(max), Some(x)) = (schema.get("maximum").and_then(Value::as_f64), v.as_f64())
        && x > max
    {
        out.push(format!("{at}: {x} > maximum {max}"));
    }
    if let Some(obj) = v.as_object() {
        for req in schema
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            let name = req.as_str().unwrap();
            if !obj.contains_key(name) {
                out.push(format!("{at}: required member `{name}` is missing"));
            }
        }
        if let Some(props) = schema.get("properties").and_then(Value::as_object) {
            for (k, sub) in props {
                if let Some(x) = obj.get(k) {
                    violations(doc, sub, x, &format!("{at}/{k}"), out);
                }
            }
        }
    }
    if let Some(arr) = v.as_array() {
        if let Some(n) = schema.get("minItems").and_then(Value::as_u64)
            && (arr.len() as u64) < n
        {
            out.push(format!("{at}: fewer than {n} items"));
        }
        if let Some(n) = schema.get("maxItems").and_then(Value::as_u64)
            && (arr.len() as u64) > n
        {
            out.push(format!("{at}: more than {n} items"));
        }
        if let Some(items) = schema.get("items") {
            for (i, x) in arr.iter().enumerate() {
                violations(doc, items, x, &format!("{at}/{i}"), out);
            }
        }
    }
    if let Some(one_of) = schema.get("oneOf").and_then(Value::as_array) {
        let matching = one_of
            .iter()
            .filter(|s| {
                let mut o = Vec::new();
                violations(doc, s, v, at, &mut o);
                o.is_empty()
            })
            .count();
        if matching != 1 {
            out.push(format!(
                "{at}: matches {matching} of oneOf, not exactly one"
            ));
        }
    }
}

/// Asserts that `problem` validates against the committed `Problem` schema and has `errors`.
fn assert_matches_problem_schema(doc: &Value, problem: &Value) {
    let mut out = Vec::new();
    violations(
        doc,
        &json!({"$ref": "#/components/schemas/Problem"}),
        problem,
        "",
        &mut out,
    );
    assert!(out.is_empty(), "{problem} violates Problem: {out:?}");
    assert!(problem["errors"].is_array(), "{problem}: errors");
}

#[test]
fn the_schema_check_itself_catches_a_missing_errors_member() {
    let doc = committed_doc();
    let mut out = Vec::new();
    let bad = json!({"type": "/problems/not_found", "title": "t", "status": 404, "detail": "d"});
    violations(
        &doc,
        &json!({"$ref": "#/components/schemas/Problem"}),
        &bad,
        "",
        &mut out,
    );
    assert!(out.iter().any(|m| m.contains("errors")), "{out:?}");
    let mut out = Vec::new();
    let bad = json!({"type": "x", "title": "t", "status": "404", "detail": "d", "errors": [{}]});
    violations(
        &doc,
        &json!({"$ref": "#/components/schemas/Problem"}),
        &bad,
        "",
        &mut out,
    );
    assert!(out.len() >= 2, "status type and error members: {out:?}");
}

/// A large ensemble keeps a solver slot busy long enough to observe saturation and timeouts.
fn big_ensemble() -> Value {
    json!({"monte_carlo": {"runs": 1_000_000, "seed": 1}})
}

#[tokio::test]
async fn every_problem_the_service_produces_matches_the_openapi_problem_schema() {
    let doc = committed_doc();
    let app = common::app();
    let mut seen = BTreeSet::new();
    let mut check = |r: &common::Reply, status: u16, code: &str| {
        let p = assert_problem(r, status, code);
        assert_matches_problem_schema(&doc, &p);
        seen.insert(code.to_string());
        p
    };
    let post_raw = |ct: Option<&'static str>, body: &'static [u8]| {
        let app = app.clone();
        async move { send(&app, Method::POST, "/v1/impact", ct, body.to_vec(), None).await }
    };
    let p = check(
        &post_raw(Some("application/json"), b"{").await,
        400,
        "malformed_json",
    );
    assert_eq!(p["errors"], json!([]));
    check(
        &post_raw(Some("text/plain"), b"{}").await,
        415,
        "unsupported_media_type",
    );
    check(
        &post(&app, "/v1/impact", &json!({"velocity_m_s": "fast"})).await,
        422,
        "invalid_type",
    );
    check(
        &post(&app, "/v1/impact", &json!({"velocity": 5})).await,
        422,
        "unknown_field",
    );
    check(
        &post(&app, "/v1/impact", &json!({"velocity_m_s": -1})).await,
        422,
        "invalid_input",
    );
    let p = check(
        &post(
            &app,
            "/v1/impact",
            &json!({"velocity_m_s": 400, "rock": {"side_length_m": 0.05, "elastic_modulus_pa": 5e8}}),
        )
        .await,
        422,
        "capacity_exceeded",
    );
    assert_eq!(p["errors"][0]["field"], "/velocity_m_s", "{p}");
    assert_eq!(p["errors"][0]["value"], json!(400.0), "{p}");
    let vmax = p["max_velocity_m_s"].as_f64().unwrap();
    assert!(vmax > 0.0 && vmax < 400.0, "{p}");
    assert!(
        p["errors"][0]["message"].as_str().unwrap().contains("m/s"),
        "{p}"
    );
    check(&get(&app, "/v1/nothing").await, 404, "not_found");
    check(&get(&app, "/docs/nonexistent").await, 404, "not_found");
    check(&get(&app, "/static/%FF%FE").await, 404, "not_found");
    check(&get(&app, "/problems/%C3%28").await, 404, "not_found");
    check(
        &send(&app, Method::GET, "/v1/impact", None, vec![], None).await,
        405,
        "method_not_allowed",
    );
    let small = gangue::app(gangue::config::Config {
        max_body_bytes: 64,
        ..Default::default()
    });
    let big = format!("{{\"velocity_m_s\": 5.0{}}}", " ".repeat(200));
    check(
        &send(
            &small,
            Method::POST,
            "/v1/impact",
            Some("application/json"),
            big.into_bytes(),
            None,
        )
        .await,
        413,
        "payload_too_large",
    );
    // 503: one slot, held by a large ensemble.
    let one = gangue::app(gangue::config::Config {
        max_concurrent: Some(1),
        compute_timeout_s: 5.0,
        ..Default::default()
    });
    let busy_app = one.clone();
    let busy = tokio::spawn(async move { post(&busy_app, "/v1/migration", &big_ensemble()).await });
    tokio::time::sleep(std::time::Duration::from_millis(30)).await;
    check(
        &post(&one, "/v1/impact", &json!({})).await,
        503,
        "overloaded",
    );
    busy.abort();
    // 504: a time limit the ensemble cannot meet.
    let quick = gangue::app(gangue::config::Config {
        compute_timeout_s: 0.02,
        ..Default::default()
    });
    check(
        &post(&quick, "/v1/migration", &big_ensemble()).await,
        504,
        "timeout",
    );
    // Problems no single request reaches here (a step limit of 2e7, a bug) are checked as the
    // router would render them.
    let too_many: gangue::http::error::ApiError = gangue::physics::PhysicsError::TooManySteps {
        estimated: 3e7,
        limit: 2e7,
    }
    .into();
    assert_matches_problem_schema(&doc, &too_many.to_problem());
    seen.insert(too_many.code().to_string());
    // A body that does not arrive in time (needs a socket; tests/api_limits.rs sends one).
    let slow = gangue::http::error::ApiError::new("request_timeout", "the body did not arrive");
    assert_matches_problem_schema(&doc, &slow.to_problem());
    seen.insert(slow.code().to_string());
    let internal = gangue::http::error::ApiError::internal("test");
    assert_matches_problem_schema(&doc, &internal.to_problem());
    seen.insert(internal.code().to_string());
    let all: BTreeSet<String> = gangue::http::error::PROBLEM_TYPES
        .iter()
        .map(|p| p.code.to_string())
        .collect();
    assert_eq!(seen, all, "every problem type is covered");
}

/// Equal JSON with numbers compared by value (`100` and `100.0` are the same number).
fn same_json(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same_json(x, y))
        }
        _ => a == b,
    }
}

#[tokio::test]
async fn out_of_range_values_in_unused_fields_are_refused_on_every_endpoint() {
    let app = common::app();
    let cases = [
        (
            json!({"rock": {"radius_m": 100}}),
            "/rock/radius_m",
            json!(100),
        ),
        (
            json!({"rock": {"random": {"semi_axes_m": [0.2, 0.15, 0.1], "vertices": 3, "seed": 1}}}),
            "/rock/random/vertices",
            json!(3),
        ),
        (
            json!({"rock": {"random": {"semi_axes_m": [0.2, 0.0, 0.1]}}}),
            "/rock/random/semi_axes_m/1",
            json!(0.0),
        ),
        (
            json!({"rock": {"dimensions_m": [0.4, 5.5, 0.2]}}),
            "/rock/dimensions_m/1",
            json!(5.5),
        ),
        (
            json!({"rock": {"vertices_m": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}}),
            "/rock/vertices_m",
            json!([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        ),
        (
            json!({"rock": {"vertices_m": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 11]]}}),
            "/rock/vertices_m/3/2",
            json!(11.0),
        ),
        (
            json!({"rock": {"corner_radius_m": 3}}),
            "/rock/corner_radius_m",
            json!(3.0),
        ),
        (
            json!({"rock": {"corner_radius_m": 0}}),
            "/rock/corner_radius_m",
            json!(0.0),
        ),
    ];
    for path in ["/v1/impact", "/v1/column", "/v1/migration"] {
        for (body, field, value) in &cases {
            let r = post(&app, path, body).await;
            let p = assert_problem(&r, 422, "invalid_input");
            let e = p["errors"]
                .as_array()
                .unwrap()
                .iter()
                .find(|e| e["field"] == *field)
                .unwrap_or_else(|| panic!("{path} {body}: {field} not named in {p}"));
            assert!(
                same_json(&e["value"], value),
                "{path} {body}: value echoed, got {}",
                e["value"]
            );
        }
    }
    // A wrong-length triple is a type error naming the array.
    let r = post(
        &app,
        "/v1/impact",
        &json!({"rock": {"dimensions_m": [0.4, 0.3]}}),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_type");
    assert_eq!(p["errors"][0]["field"], "/rock/dimensions_m", "{p}");
    // In range but unused: accepted; the relation r_c ≤ L/2 applies only where r_c is used.
    let r = post(
        &app,
        "/v1/impact",
        &json!({"rock": {"radius_m": 2.5, "corner_radius_m": 2.5, "dimensions_m": [5, 5, 5],
            "random": {"semi_axes_m": [2.5, 0.005, 1], "vertices": 1000, "seed": 18446744073709551615u64}}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let r = post(
        &app,
        "/v1/impact",
        &json!({"rock": {"corner_radius_m": 2.5}, "contact": {"law": "hertz_point"}}),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/rock/corner_radius_m", "{p}");
}

#[tokio::test]
async fn duplicate_json_keys_are_refused_naming_the_key() {
    let app = common::app();
    for (body, field) in [
        (
            &br#"{"velocity_m_s": 5, "velocity_m_s": 6}"#[..],
            "/velocity_m_s",
        ),
        (
            br#"{"rock": {"density_kg_m3": 2500, "density_kg_m3": 1e9}}"#,
            "/rock/density_kg_m3",
        ),
    ] {
        let r = send(
            &app,
            Method::POST,
            "/v1/impact",
            Some("application/json"),
            body.to_vec(),
            None,
        )
        .await;
        let p = assert_problem(&r, 422, "invalid_input");
        assert_eq!(p["errors"][0]["field"], field, "{p}");
        assert!(!p["errors"][0]["value"].is_null(), "{p}");
    }
}

fn ndjson_lines(r: &common::Reply) -> Vec<Value> {
    String::from_utf8_lossy(&r.body)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[tokio::test]
async fn accept_negotiation_honours_q_values_and_case() {
    let app = common::app();
    let ask = |accept: &'static str| {
        let app = app.clone();
        async move {
            send(
                &app,
                Method::POST,
                "/v1/impact",
                Some("application/json"),
                b"{}".to_vec(),
                Some(accept),
            )
            .await
        }
    };
    for a in [
        "application/x-ndjson;q=0",
        "application/x-ndjson;q=0.1, application/json",
        "*/*",
    ] {
        let r = ask(a).await;
        assert_eq!(r.status, 200);
        assert_eq!(r.content_type(), "application/json", "{a}");
    }
    for a in [
        "Application/X-NDJSON",
        "application/json;q=0.5, application/x-ndjson",
    ] {
        let r = ask(a).await;
        assert_eq!(r.status, 200);
        assert!(r.content_type().starts_with("application/x-ndjson"), "{a}");
        // A fast closed form has no work count to report: exactly one result line.
        let lines = ndjson_lines(&r);
        assert_eq!(lines.len(), 1, "{a}: {lines:?}");
        assert!(lines[0]["result"].is_object());
    }
}

#[tokio::test]
async fn ndjson_progress_never_sends_an_empty_count() {
    // The column's closed form reports no work units; a stream of it must not carry
    // `{"done":0,"total":0}` lines (the migration ensemble, which counts runs, may).
    let app = common::app();
    for (path, body) in [
        ("/v1/column", json!({})),
        (
            "/v1/migration",
            json!({"monte_carlo": {"runs": 2000, "seed": 1}}),
        ),
    ] {
        let r = send(
            &app,
            Method::POST,
            path,
            Some("application/json"),
            serde_json::to_vec(&body).unwrap(),
            Some("application/x-ndjson"),
        )
        .await;
        assert_eq!(r.status, 200);
        let lines = ndjson_lines(&r);
        let (last, progress) = lines.split_last().unwrap();
        assert!(last.get("result").is_some(), "{path}: {last}");
        let mut prev = None;
        for l in progress {
            let (done, total) = (
                l["progress"]["done"].as_u64().unwrap(),
                l["progress"]["total"].as_u64().unwrap(),
            );
            assert!(total > 0 && done <= total, "{path}: {l}");
            // the time so far, and the time left at that rate while some is done and some left
            assert!(
                l["progress"]["elapsed_s"].as_f64().unwrap() >= 0.0,
                "{path}: {l}"
            );
            let left = l["progress"].get("remaining_s");
            assert_eq!(left.is_some(), done > 0 && done < total, "{path}: {l}");
            assert_ne!(prev, Some((done, total)), "{path}: repeated {l}");
            prev = Some((done, total));
        }
    }
}

#[tokio::test]
async fn invalid_body_with_ndjson_accept_is_a_plain_problem_as_documented() {
    let app = common::app();
    let r = send(
        &app,
        Method::POST,
        "/v1/impact",
        Some("application/json"),
        br#"{"velocity_m_s": -1}"#.to_vec(),
        Some("application/x-ndjson"),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/velocity_m_s");
    let doc = committed_doc();
    let description = doc["paths"]["/v1/impact"]["post"]["description"]
        .as_str()
        .unwrap();
    assert!(description.contains("not as a stream"), "{description}");
}

#[test]
fn openapi_documents_ndjson_statuses_and_array_bounds() {
    let doc = committed_doc();
    for path in ["/v1/impact", "/v1/column", "/v1/migration"] {
        let responses = &doc["paths"][path]["post"]["responses"];
        assert!(
            responses["200"]["content"]["application/x-ndjson"].is_object(),
            "{path}: NDJSON"
        );
        for status in ["400", "413", "415", "422", "500", "503", "504"] {
            assert_eq!(
                responses[status]["content"]["application/problem+json"]["schema"]["$ref"],
                "#/components/schemas/Problem",
                "{path} {status}"
            );
        }
        assert!(responses["503"]["headers"]["Retry-After"].is_object());
    }
    let rock = &doc["components"]["schemas"]["RockDto"]["properties"];
    assert_eq!(rock["dimensions_m"]["minItems"], 3);
    assert_eq!(rock["dimensions_m"]["maxItems"], 3);
    assert_eq!(rock["dimensions_m"]["items"]["minimum"], 0.01);
    assert_eq!(rock["vertices_m"]["minItems"], 4);
    assert_eq!(rock["vertices_m"]["maxItems"], 1000);
    assert_eq!(rock["vertices_m"]["items"]["maxItems"], 3);
    assert_eq!(rock["vertices_m"]["items"]["items"]["maximum"], 10.0);
    let random = &doc["components"]["schemas"]["RandomShapeDto"]["properties"];
    assert_eq!(random["semi_axes_m"]["minItems"], 3);
    assert_eq!(random["semi_axes_m"]["items"]["maximum"], 2.5);
    assert_eq!(random["vertices"]["minimum"], 4);
    assert_eq!(random["vertices"]["maximum"], 1000);
}

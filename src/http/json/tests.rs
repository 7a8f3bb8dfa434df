//! Tests of the body extractor, the two passes and the problems they name.

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

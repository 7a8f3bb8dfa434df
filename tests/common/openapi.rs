//! Walking the OpenAPI document: the schema behind a `$ref` or a nullable `oneOf`, and the
//! numeric fields of a request schema that carry a documented bound.
#![allow(dead_code, unreachable_pub)]

use serde_json::{Value, json};

/// A documented bound: (value, closed).
pub type Bound = Option<(f64, bool)>;

/// A numeric field with a documented bound.
#[derive(Debug, Clone)]
pub struct Leaf {
    /// JSON Pointer of the field in the request.
    pub pointer: String,
    /// Parent objects to create on the way (pointer, base object).
    pub parents: Vec<(String, Value)>,
    /// Whether the field is an integer.
    pub integer: bool,
    /// Documented lower bound.
    pub min: Bound,
    /// Documented upper bound.
    pub max: Bound,
    /// For an item of a fixed-length array: the array's example and the item index.
    pub array: Option<(Value, usize)>,
}

/// What to walk.
pub struct Walk<'a> {
    /// Also list the items of fixed-length arrays with bounded items.
    pub arrays: bool,
    /// Also descend into the first item of arrays of objects (given the array's example).
    pub object_arrays: bool,
    /// Pointers not to descend into (checked on another route).
    pub skip: &'a [&'a str],
}

/// Objects that must carry members before their fields can be varied: (schema name, base).
/// `monte_carlo` uses 20 runs so that an ensemble stays cheap.
pub fn base_object(schema: &str) -> Value {
    match schema {
        "MonteCarloDto" | "SceneMonteCarloDto" => json!({"runs": 20}),
        "RandomShapeDto" => json!({"semi_axes_m": [0.2, 0.15, 0.1]}),
        // A decoupled history needs a window; 10 ms as in the README.
        "ColumnOutputDto" => json!({"duration_s": 0.01}),
        _ => json!({}),
    }
}

/// The schema behind `$ref`s and nullable `oneOf`s, with the name of the last schema referred to.
pub fn resolve<'a>(doc: &'a Value, mut s: &'a Value) -> (&'a Value, Option<String>) {
    let mut name = None;
    loop {
        if let Some(r) = s.get("$ref").and_then(Value::as_str) {
            name = r.rsplit('/').next().map(str::to_string);
            s = doc.pointer(r.trim_start_matches('#')).unwrap();
        } else if let Some(alts) = s.get("oneOf").and_then(Value::as_array) {
            match alts.iter().find(|a| a.get("type") != Some(&json!("null"))) {
                Some(a) => s = a,
                None => return (s, name),
            }
        } else {
            return (s, name);
        }
    }
}

/// Whether the schema's `type` is or includes `t`.
pub fn has_type(s: &Value, t: &str) -> bool {
    match s.get("type") {
        Some(Value::String(x)) => x == t,
        Some(Value::Array(a)) => a.iter().any(|x| x == t),
        _ => false,
    }
}

/// The documented lower and upper bound of a numeric schema.
pub fn bounds(s: &Value) -> (Bound, Bound) {
    let f = |k: &str| s.get(k).and_then(Value::as_f64);
    let min = f("minimum")
        .map(|v| (v, true))
        .or(f("exclusiveMinimum").map(|v| (v, false)));
    let max = f("maximum")
        .map(|v| (v, true))
        .or(f("exclusiveMaximum").map(|v| (v, false)));
    (min, max)
}

/// Appends to `out` every bounded numeric field below `schema` (at pointer `at`).
pub fn leaves(
    doc: &Value,
    schema: &Value,
    at: &str,
    parents: &[(String, Value)],
    walk: &Walk<'_>,
    out: &mut Vec<Leaf>,
) {
    let Some(props) = schema.get("properties").and_then(Value::as_object) else {
        return;
    };
    for (name, prop) in props {
        let pointer = format!("{at}/{name}");
        if walk.skip.contains(&pointer.as_str()) {
            continue;
        }
        let (s, ref_name) = resolve(doc, prop);
        let integer = has_type(s, "integer");
        if integer || has_type(s, "number") {
            let (min, max) = bounds(s);
            if min.is_some() || max.is_some() {
                out.push(Leaf {
                    pointer,
                    parents: parents.to_vec(),
                    integer,
                    min,
                    max,
                    array: None,
                });
            }
        } else if has_type(s, "array") {
            if !walk.arrays {
                continue;
            }
            let fixed = s.get("minItems").is_some() && s.get("minItems") == s.get("maxItems");
            let items = s.get("items").unwrap_or(&Value::Null);
            let (item_schema, _) = resolve(doc, items);
            if walk.object_arrays && item_schema.get("properties").is_some() {
                let example = prop
                    .get("example")
                    .or(s.get("example"))
                    .cloned()
                    .expect("an array of objects has an example");
                let mut p = parents.to_vec();
                p.push((pointer.clone(), example));
                leaves(doc, item_schema, &format!("{pointer}/0"), &p, walk, out);
                continue;
            }
            let (min, max) = bounds(items);
            if fixed && (min.is_some() || max.is_some()) {
                let example = prop
                    .get("example")
                    .or(s.get("example"))
                    .cloned()
                    .expect("a fixed-length array has an example");
                out.push(Leaf {
                    pointer: format!("{pointer}/0"),
                    parents: parents.to_vec(),
                    integer: false,
                    min,
                    max,
                    array: Some((example, 0)),
                });
            }
        } else if s.get("properties").is_some() {
            let mut p = parents.to_vec();
            p.push((
                pointer.clone(),
                base_object(ref_name.as_deref().unwrap_or("")),
            ));
            leaves(doc, s, &pointer, &p, walk, out);
        }
    }
}

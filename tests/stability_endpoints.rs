//! Property tests of the composite endpoints over their documented domain, through the router:
//! `/v1/scene`, `/v1/study`, `/v1/spalling` and `/v1/batch`.
//!
//! Physical expectations:
//! - a scene never answers 5xx; a support is never struck faster than the frictionless bound
//!   √(v₀² + 2g(h + Δs·sin θ)) allows (energy is never created between release and impact); each
//!   design check's `exceeded` is `value > allowed` and its utilisation `value / allowed`; an
//!   ensemble's outcome fractions sum to 1, every probability lies inside its Wilson interval and
//!   in [0, 1], a support's verdict follows its exceedance probabilities against
//!   `acceptable_probability`, and the probability that any entry exceeds lies between the
//!   largest single one and their sum;
//! - a study point is the column response for that input, bit for bit;
//! - spalling shares and conditional frequencies are the count ratios (to 1e-12) and lie in
//!   [0, 100] %; a count that breaks |A∩B| ≤ min(|A|, |B|) is refused naming that field;
//! - a batch line is its item's own endpoint answer, byte for byte, in input order.
//!
//! Cases run with the fixed seed of the test command; `GANGUE_ENDPOINT_CASES=K` multiplies every
//! property's case count by K for a longer run
//! (e.g. `PROPTEST_RNG_SEED=20261122 GANGUE_ENDPOINT_CASES=20 cargo test --test stability_endpoints`).

mod common;

use proptest::prelude::*;
use serde_json::{Value, json};

/// `n` cases, times `GANGUE_ENDPOINT_CASES` when set.
fn cases(n: u32) -> u32 {
    n * std::env::var("GANGUE_ENDPOINT_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1)
}

/// POSTs `body` and returns the status and the body's bytes.
fn post(path: &str, body: &Value) -> (u16, Vec<u8>) {
    let (rt, app) = common::service();
    let r = rt.block_on(common::post(app, path, body));
    (r.status.as_u16(), r.body.to_vec())
}

/// Parses an answer; a 5xx or a body that is not JSON fails the property.
fn answer(path: &str, body: &Value) -> Result<(u16, Value), TestCaseError> {
    let (status, bytes) = post(path, body);
    let text = String::from_utf8_lossy(&bytes);
    prop_assert!(status < 500, "{path} {status}: {body} -> {text}");
    let v: Value = serde_json::from_slice(&bytes)
        .map_err(|e| TestCaseError::fail(format!("{path}: not JSON ({e}): {text}")))?;
    Ok((status, v))
}

/// A refusal names at least one field, and every named field is a JSON Pointer.
fn check_refusal(path: &str, body: &Value, p: &Value) -> Result<(), TestCaseError> {
    let errors = p["errors"].as_array();
    prop_assert!(
        errors.is_some(),
        "{path}: problem without errors: {body} -> {p}"
    );
    for e in errors.unwrap() {
        prop_assert!(
            e["field"]
                .as_str()
                .is_some_and(|f| f.is_empty() || f.starts_with('/')),
            "{path}: field is not a pointer: {p}"
        );
    }
    Ok(())
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

// ---------------------------------------------------------------------------------------------
// Scenes

prop_compose! {
    /// A plane face with 1–4 spanning supports below the release point, the lumped mass or (on
    /// short faces) the rigid block, a single run or a small ensemble.
    fn scene()(
        dip in 5.0..=80.0f64,
        length in prop_oneof![1.0..=30.0f64, 30.0..=500.0f64],
        mu in 0.0..=1.5f64,
        en in 0.0..=0.95f64,
        et in 0.0..=1.0f64,
        drop in prop_oneof![Just(0.0), 0.0..=60.0f64],
        release_frac in 0.0..0.6f64,
        speed in prop_oneof![Just(0.0), 0.0..=30.0f64],
        fracs in prop::collection::vec(0.0..=1.0f64, 1..=4),
        roll in any::<bool>(),
        rigid in prop::bool::weighted(0.1),
        runs in prop_oneof![Just(0u32), 2u32..=24],
        seed in any::<u32>(),
        stress in prop_oneof![Just(None), (0.01..=5.0f64).prop_map(Some)],
        force in prop_oneof![Just(None), (1e3..=1e8f64).prop_map(Some)],
        acceptable in 0.0..=1.0f64,
        side in 0.05..=0.6f64,
    ) -> (Value, f64) {
        // The rigid block steps every contact: keep its faces short.
        let length = if rigid { length.min(8.0) } else { length };
        let release = release_frac * length;
        let supports: Vec<Value> = fracs
            .iter()
            .map(|&q| json!({"along_dip_m": release + (length - release) * q}))
            .collect();
        let mut body = json!({
            "face": {"dip_deg": dip, "length_m": length, "friction_coefficient": mu,
                     "restitution_normal": en, "restitution_tangential": et},
            "rock": {"side_length_m": side},
            "release": {"along_dip_m": release, "drop_height_m": drop, "speed_m_s": speed},
            "supports": supports,
            "design_limits": {"stress_utilisation": stress, "max_force_n": force,
                              "acceptable_probability": acceptable},
            "end_time_s": 200.0,
        });
        if roll && !rigid {
            body["lumped_mass"] = json!({"motion": "roll"});
            // Rolling without slip needs μ ≥ (2/7) tan θ.
            body["face"]["friction_coefficient"] = json!(mu.max(0.3 * dip.to_radians().tan()).min(2.0));
        }
        if rigid {
            body["method"] = json!("rigid_block");
        }
        if runs > 0 {
            body["monte_carlo"] = json!({"runs": runs, "seed": seed});
        }
        (body, release)
    }
}

/// The bound on any speed the rock can have `ds` further down the dip: no loss at all.
fn frictionless_speed(g: f64, dip_deg: f64, drop: f64, speed: f64, ds: f64) -> f64 {
    (speed * speed + 2.0 * g * (drop + ds.max(0.0) * dip_deg.to_radians().sin())).sqrt()
}

fn check_impacts(body: &Value, release: f64, b: &Value) -> Result<(), TestCaseError> {
    let dip = f(&body["face"]["dip_deg"]);
    let drop = f(&body["release"]["drop_height_m"]);
    let v0 = f(&body["release"]["speed_m_s"]);
    for imp in b["impacts"].as_array().into_iter().flatten() {
        let v = f(&imp["impact_velocity_m_s"]);
        let s = f(&imp["along_dip_m"]);
        let bound = frictionless_speed(9.81, dip, drop, v0, s - release);
        prop_assert!(
            v.is_finite() && v >= 0.0 && v <= bound * (1.0 + 1e-9) + 1e-12,
            "support at {s} m struck at {v} m/s above the frictionless bound {bound}: {body}"
        );
        let mut any = false;
        for c in imp["checks"].as_array().into_iter().flatten() {
            let (value, allowed) = (f(&c["value"]), f(&c["allowed"]));
            let exceeded = c["exceeded"].as_bool().unwrap_or(false);
            any |= exceeded;
            if value.is_finite() {
                prop_assert_eq!(exceeded, value > allowed, "{}", c);
                let u = f(&c["utilisation"]);
                prop_assert!(
                    (u - value / allowed).abs() <= 1e-12 * (value / allowed).abs(),
                    "{c}"
                );
            }
        }
        let verdict = imp["verdict"].as_str().unwrap_or("");
        prop_assert_eq!(verdict, if any { "exceeded" } else { "ok" }, "{}", imp);
    }
    Ok(())
}

fn check_statistics(body: &Value, st: &Value) -> Result<(), TestCaseError> {
    let outcomes = st["outcomes"].as_object().unwrap();
    let sum: f64 = outcomes.values().map(f).sum();
    prop_assert!((sum - 1.0).abs() <= 1e-12, "outcomes sum to {sum}: {st}");
    let acceptable = f(&body["design_limits"]["acceptable_probability"]);
    let in_interval = |p: &Value| {
        let (q, lo, hi) = (f(&p["probability"]), f(&p["ci95"][0]), f(&p["ci95"][1]));
        (0.0..=1.0).contains(&q) && lo <= q && q <= hi && lo >= 0.0 && hi <= 1.0
    };
    let (mut largest, mut total) = (0.0f64, 0.0f64);
    for s in st["supports"].as_array().unwrap() {
        let reached = f(&s["reached_fraction"]);
        prop_assert!((0.0..=1.0).contains(&reached), "{s}");
        let mut over = false;
        for (limit, p) in s["exceedance"].as_object().into_iter().flatten() {
            prop_assert!(in_interval(p), "{limit}: {p}");
            let q = f(&p["probability"]);
            prop_assert!(q <= reached + 1e-15, "exceeds more often than reached: {s}");
            over |= q > acceptable;
            largest = largest.max(q);
            total += q;
        }
        prop_assert_eq!(
            s["verdict"].as_str().unwrap_or(""),
            if over { "exceeded" } else { "ok" },
            "{}",
            s
        );
    }
    if let Some(any) = st.get("any_exceeded").filter(|a| !a.is_null()) {
        prop_assert!(in_interval(any), "{any}");
        let q = f(&any["probability"]);
        prop_assert!(
            q + 1e-12 >= largest && q <= total + 1e-12,
            "any_exceeded {q} outside [{largest}, {total}]"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(96), ..ProptestConfig::default() })]

    /// A scene never answers 5xx, never strikes a support faster than a lossless descent would,
    /// and its checks, verdicts and ensemble statistics agree with their own numbers.
    #[test]
    fn a_scene_is_answered_within_the_energy_bound_with_consistent_verdicts((body, release) in scene()) {
        let (status, b) = answer("/v1/scene", &body)?;
        if status != 200 {
            return check_refusal("/v1/scene", &body, &b);
        }
        check_impacts(&body, release, &b)?;
        if body.get("monte_carlo").is_some() {
            check_statistics(&body, &b["statistics"])?;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Studies

/// Parameters a study may sweep, with a range inside their own documented range.
const SWEEPABLE: &[(&str, f64, f64)] = &[
    ("velocity_m_s", 0.1, 40.0),
    ("rock.side_length_m", 0.05, 1.0),
    ("rock.density_kg_m3", 500.0, 5000.0),
    ("rock.elastic_modulus_pa", 1e8, 1e11),
    ("rock.poisson_ratio", 0.05, 0.45),
    ("column.length_m", 1.0, 6.0),
    ("column.elastic_modulus_pa", 1e10, 4e11),
    ("column.damping_ratio", 0.0, 0.5),
];

prop_compose! {
    fn study()(
        picks in prop::sample::subsequence((0..SWEEPABLE.len()).collect::<Vec<_>>(), 1..=3),
        ends in prop::collection::vec((0.0..=1.0f64, 0.0..=1.0f64), 3),
        points in 2u32..=5,
        pairs in any::<bool>(),
        law in prop::sample::select(vec!["paper", "johnson", "hertz_point"]),
    ) -> Value {
        let parameters: Vec<Value> = picks
            .iter()
            .zip(&ends)
            .map(|(&i, &(a, b))| {
                let (name, lo, hi) = SWEEPABLE[i];
                let (a, b) = (a.min(b), a.max(b).max(a.min(b) + 1e-3));
                let at = |t: f64| lo + (hi - lo) * t.min(1.0);
                json!({"name": name, "min": at(a), "max": at(b)})
            })
            .collect();
        json!({"base": {"contact": {"law": law}}, "parameters": parameters, "points": points,
               "grid": if pairs { "pairs" } else { "one_at_a_time" }})
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(48), ..ProptestConfig::default() })]

    /// Every point of a study curve is the column answer for that input, bit for bit.
    #[test]
    fn a_study_curve_is_the_column_answer_at_each_point(body in study()) {
        let (status, b) = answer("/v1/study", &body)?;
        if status != 200 {
            return check_refusal("/v1/study", &body, &b);
        }
        let outputs: Vec<String> = b["inputs"]["outputs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|o| o.as_str().unwrap().to_string())
            .collect();
        for p in body["parameters"].as_array().unwrap() {
            let name = p["name"].as_str().unwrap();
            let curve = &b["curves"][name];
            let xs = curve["values"].as_array().or(curve["x"].as_array());
            let n = body["points"].as_u64().unwrap() as usize;
            let (lo, hi) = (f(&p["min"]), f(&p["max"]));
            for k in [0, n - 1] {
                let x = xs.map_or(lo + (hi - lo) * k as f64 / (n - 1) as f64, |xs| f(&xs[k]));
                let mut req = body["base"].clone();
                let mut parts: Vec<&str> = name.split('.').collect();
                let last = parts.pop().unwrap();
                let mut obj = &mut req;
                for part in parts {
                    if obj.get(part).is_none() {
                        obj[part] = json!({});
                    }
                    obj = &mut obj[part];
                }
                obj[last] = json!(x);
                let (cs, col) = answer("/v1/column", &req)?;
                for o in &outputs {
                    let got = &curve[o.as_str()][k];
                    if cs == 200 {
                        prop_assert_eq!(
                            f(got).to_bits(),
                            f(&col[o.as_str()]).to_bits(),
                            "{} at {} = {}: study {} column {}", o, name, x, got, col[o.as_str()]
                        );
                    } else {
                        prop_assert!(got.is_null(), "{o} at {name} = {x}: study {got}, column {cs}");
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Spalling

prop_compose! {
    fn zone()(
        a in 0.0..=1e6f64,
        b in 0.0..=1e6f64,
        c in 0.0..=1e6f64,
        tab in 0.0..=1.0f64,
        tac in 0.0..=1.0f64,
        whole in any::<bool>(),
    ) -> [f64; 5] {
        let r = |x: f64| if whole { x.round() } else { x };
        let (a, b, c) = (r(a), r(b), r(c));
        [a, b, c, (tab * a.min(b)).min(a.min(b)), (tac * a.min(c)).min(a.min(c))]
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(400), ..ProptestConfig::default() })]

    /// Shares and conditional frequencies are the count ratios in [0, 100] %; a zone whose
    /// |A∩B| exceeds min(|A|, |B|) is refused naming that count.
    #[test]
    fn spalling_frequencies_are_the_count_ratios(zones in prop::collection::vec(zone(), 1..=5), spoil in prop::option::of(0usize..5)) {
        let mut body_zones: Vec<Value> = zones
            .iter()
            .enumerate()
            .map(|(i, z)| json!({"name": format!("z{i}"), "spalling": z[0], "high_resistance": z[1],
                                 "low_resistance": z[2], "spalling_and_high": z[3], "spalling_and_low": z[4]}))
            .collect();
        let spoilt = spoil.filter(|&i| i < zones.len());
        if let Some(i) = spoilt {
            body_zones[i]["spalling_and_high"] = json!(zones[i][0].min(zones[i][1]) * 1.5 + 1.0);
        }
        let body = json!({"zones": body_zones});
        let (status, b) = answer("/v1/spalling", &body)?;
        if let Some(i) = spoilt {
            prop_assert_eq!(status, 422, "{}", b);
            let want = format!("/zones/{i}/spalling_and_high");
            prop_assert!(
                b["errors"].as_array().unwrap().iter().any(|e| e["field"] == want.as_str()),
                "{b}"
            );
            return Ok(());
        }
        if status != 200 {
            return check_refusal("/v1/spalling", &body, &b);
        }
        let total = |k: usize| zones.iter().map(|z| z[k]).sum::<f64>();
        for (i, z) in zones.iter().enumerate() {
            let out = &b["zones"][i];
            let ratio = |num: f64, den: f64| if den > 0.0 { Some(100.0 * num / den) } else { None };
            for (field, want) in [
                ("spalling_share_pct", ratio(z[0], total(0))),
                ("high_share_pct", ratio(z[1], total(1))),
                ("low_share_pct", ratio(z[2], total(2))),
                ("spalling_given_high_pct", ratio(z[3], z[1])),
                ("spalling_given_low_pct", ratio(z[4], z[2])),
                ("high_given_spalling_pct", ratio(z[3], z[0])),
                ("low_given_spalling_pct", ratio(z[4], z[0])),
            ] {
                let got = &out[field];
                match want {
                    Some(w) => {
                        let g = f(got);
                        prop_assert!(
                            (g - w).abs() <= 1e-12 * w.abs().max(1e-300) && (0.0..=100.0).contains(&g),
                            "zone {i} {field}: {got} against {w}: {body}"
                        );
                    }
                    None => prop_assert!(got.is_null(), "zone {i} {field}: {got} with a zero count"),
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Batches

prop_compose! {
    /// A batch item: a request of any kind, sometimes with an out-of-range field.
    fn item()(
        kind in 0usize..6,
        v in 0.1..=40.0f64,
        bad in prop::bool::weighted(0.25),
        seed in any::<u32>(),
    ) -> Value {
        let (kind, request) = match kind {
            0 => ("impact", json!({"velocity_m_s": v})),
            1 => ("column", json!({"velocity_m_s": v, "column": {"damping_ratio": 0.02}})),
            2 => ("migration", json!({"release": {"speed_m_s": v}, "monte_carlo": {"runs": 5, "seed": seed}})),
            3 => ("scene", json!({"impact_velocity_m_s": v})),
            4 => ("study", json!({"points": 2, "parameters": [{"name": "velocity_m_s", "min": v, "max": v + 1.0}]})),
            _ => ("spalling", json!({})),
        };
        let mut request = request;
        if bad {
            request["rock"] = json!({"density_kg_m3": -v});
        }
        json!({"kind": kind, "request": request})
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(24), ..ProptestConfig::default() })]

    /// Each line of a batch is its item's own answer, byte for byte, in input order; a bad
    /// item's problem names its field under `/items/i/request`.
    #[test]
    fn a_batch_line_is_its_items_own_answer(items in prop::collection::vec(item(), 1..=6)) {
        let (status, bytes) = post("/v1/batch", &json!({"items": items}));
        prop_assert_eq!(status, 200);
        let text = String::from_utf8(bytes).unwrap();
        let lines: Vec<Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        prop_assert_eq!(lines.len(), items.len());
        for (i, (item, line)) in items.iter().zip(&lines).enumerate() {
            prop_assert_eq!(&line["index"], &json!(i));
            let path = format!("/v1/{}", item["kind"].as_str().unwrap());
            let (s, own) = answer(&path, &item["request"])?;
            prop_assert_eq!(&line["status"], &json!(s), "{}", line);
            if s == 200 {
                prop_assert_eq!(&line["result"], &own, "item {}", i);
            } else {
                let mut want = own.clone();
                for e in want["errors"].as_array_mut().into_iter().flatten() {
                    e["field"] = json!(format!("/items/{i}/request{}", e["field"].as_str().unwrap()));
                }
                prop_assert_eq!(&line["problem"]["errors"], &want["errors"], "item {}", i);
                prop_assert_eq!(&line["problem"]["type"], &want["type"]);
            }
        }
    }
}

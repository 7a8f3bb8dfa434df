//! A scene's `release_rate` through the router: each support's expected overloads per year are
//! the rate × the share of runs that struck it past a limit — recounted here from the per-run
//! CSV — with the Wilson 95 % interval (recomputed here from its formula) times a known rate; an
//! observed count gives the same point value with a wider interval; the return period is the
//! reciprocal; bad rates are refused naming the field.

mod common;
use common::ok;

use common::{assert_problem, post, rel};
use serde_json::{Value, json};

const RUNS: u64 = 400;

/// [`common::risky_scene`] with the release rate `rate`.
fn scene(rate: &Value) -> Value {
    let mut s = common::risky_scene(RUNS, 3);
    s["release_rate"] = rate.clone();
    s
}

/// Wilson score interval, written from its formula (Wilson 1927).
fn wilson(k: f64, n: f64, z: f64) -> [f64; 2] {
    let p = k / n;
    let d = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / d;
    let h = z / d * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    [
        if k == 0.0 { 0.0 } else { c - h },
        if k == n { 1.0 } else { c + h },
    ]
}

/// Per support (by number), the runs of the CSV that struck it past the limit (utilisation
/// above 5, or past the contact capacity).
fn overloads_from_csv(csv: &str) -> std::collections::BTreeMap<u64, u64> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (support, util, cap) = (
        col("support"),
        col("stress_utilisation"),
        col("capacity_exceeded"),
    );
    let mut out = std::collections::BTreeMap::new();
    let mut rows = 0;
    for line in lines {
        rows += 1;
        let f: Vec<&str> = line.split(',').collect();
        if f[support].is_empty() {
            continue;
        }
        let over = f[cap] == "true" || f[util].parse::<f64>().unwrap() > 5.0;
        *out.entry(f[support].parse().unwrap()).or_insert(0) += u64::from(over);
    }
    assert_eq!(rows, RUNS);
    out
}

#[tokio::test]
async fn overloads_per_year_are_the_rate_times_the_recounted_share_with_its_wilson_interval() {
    let app = common::app();
    let rate = 120.0;
    let b = ok(&post(&app, "/v1/scene", &scene(&json!({"rocks_per_year": rate}))).await);
    let counts = overloads_from_csv(b["migration"]["runs_csv"].as_str().unwrap());
    let n = RUNS as f64;
    let mut between = 0;
    for s in b["statistics"]["supports"].as_array().unwrap() {
        let k = *counts.get(&s["support"].as_u64().unwrap()).unwrap_or(&0) as f64;
        between += usize::from(k > 0.0 && k < n);
        let f = &s["overloads_per_year"];
        assert_eq!(f["per_year"].as_f64().unwrap(), rate * (k / n), "{s}");
        let [lo, hi] = wilson(k, n, 1.959_963_984_540_054);
        let ci = &f["ci95_per_year"];
        assert!(
            rel(ci[0].as_f64().unwrap(), rate * lo) < 1e-12 || (lo == 0.0 && ci[0] == 0.0),
            "{f}"
        );
        assert!(rel(ci[1].as_f64().unwrap(), rate * hi) < 1e-12, "{f}");
        match f["return_period_years"].as_f64() {
            Some(t) => assert!(rel(t, 1.0 / (rate * k / n)) < 1e-15),
            None => assert_eq!(k, 0.0),
        }
        assert!(
            rel(
                f["return_period_ci95_years"][0].as_f64().unwrap(),
                1.0 / (rate * hi)
            ) < 1e-12
        );
    }
    assert!(
        between >= 2,
        "supports with 0 < P < 1: {between}; the test checks too little"
    );
    // the face as a whole: some support overloaded
    let any = b["statistics"]["any_exceeded"]["probability"]
        .as_f64()
        .unwrap();
    let f = &b["statistics"]["any_overloads_per_year"];
    assert!(
        rel(f["per_year"].as_f64().unwrap(), rate * any) < 1e-15,
        "{f}"
    );
}

#[tokio::test]
async fn an_observed_count_gives_the_rate_and_a_wider_interval() {
    let app = common::app();
    // the paper's Table 1: 643 spalling events in nine months
    let observed = ok(&post(
        &app,
        "/v1/scene",
        &scene(&json!({"observed_events": 643, "observed_period_years": 0.75})),
    )
    .await);
    let known = ok(&post(
        &app,
        "/v1/scene",
        &scene(&json!({"rocks_per_year": 643.0 / 0.75})),
    )
    .await);
    for (o, k) in observed["statistics"]["supports"]
        .as_array()
        .unwrap()
        .iter()
        .zip(known["statistics"]["supports"].as_array().unwrap())
    {
        let (o, k) = (&o["overloads_per_year"], &k["overloads_per_year"]);
        assert_eq!(o["per_year"], k["per_year"]);
        if k["per_year"].as_f64().unwrap() > 0.0 {
            assert!(
                o["ci95_per_year"][0].as_f64() < k["ci95_per_year"][0].as_f64(),
                "{o} {k}"
            );
        }
        assert!(
            o["ci95_per_year"][1].as_f64() > k["ci95_per_year"][1].as_f64(),
            "{o} {k}"
        );
    }
    // nothing else of the answer depends on the rate
    let strip = |mut v: Value| {
        v.as_object_mut().unwrap().remove("inputs");
        let st = v["statistics"].as_object_mut().unwrap();
        st.remove("any_overloads_per_year");
        for s in st["supports"].as_array_mut().unwrap() {
            s.as_object_mut().unwrap().remove("overloads_per_year");
        }
        v
    };
    let mut none = scene(&json!({}));
    none.as_object_mut().unwrap().remove("release_rate");
    let plain = ok(&post(&app, "/v1/scene", &none).await);
    assert!(plain["statistics"].get("any_overloads_per_year").is_none());
    assert_eq!(strip(observed), strip(plain));
}

#[tokio::test]
async fn bad_release_rates_are_refused_naming_the_field() {
    let app = common::app();
    let with = |rate: Value| scene(&rate);
    let mut single = with(json!({"rocks_per_year": 10.0}));
    single.as_object_mut().unwrap().remove("monte_carlo");
    single.as_object_mut().unwrap().remove("migration_output");
    let mut given_speed = with(json!({"rocks_per_year": 10.0}));
    given_speed["impact_velocity_m_s"] = json!(4.0);
    for (body, field, words) in [
        (
            with(json!({"rocks_per_year": 0.0})),
            "/release_rate/rocks_per_year",
            "[1e-6, 1e9]",
        ),
        (
            with(json!({"rocks_per_year": 2e9})),
            "/release_rate/rocks_per_year",
            "[1e-6, 1e9]",
        ),
        (
            with(json!({"observed_events": 10, "observed_period_years": 0.0})),
            "/release_rate/observed_period_years",
            "[0.001, 1000]",
        ),
        (
            with(json!({"observed_events": 10})),
            "/release_rate",
            "one form only",
        ),
        (
            with(
                json!({"rocks_per_year": 5.0, "observed_events": 10, "observed_period_years": 1.0}),
            ),
            "/release_rate",
            "one form only",
        ),
        (with(json!({})), "/release_rate", "one form only"),
        (single, "/release_rate", "needs an ensemble"),
        (given_speed, "/release_rate", "needs an ensemble"),
    ] {
        let p = assert_problem(&post(&app, "/v1/scene", &body).await, 422, "invalid_input");
        let e = p["errors"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["field"] == field);
        let e = e.unwrap_or_else(|| panic!("{body}: {field} not named in {p}"));
        assert!(e["message"].as_str().unwrap().contains(words), "{e}");
    }
}

/// Rates per release zone: the zones are drawn in proportion to their rates, so the answer is
/// that of the same zones weighted by the rates with their sum as the face's rate, bit for bit;
/// a count of rates other than the zones', or rates without zones, is refused naming the field.
#[tokio::test]
async fn rates_per_zone_weight_the_zones_and_add_up() {
    let app = common::app();
    let rates = [100.0, 300.0, 200.0];
    let mut by_zone = common::risky_scene(300, 9);
    by_zone["release_zones"] = json!("table1");
    by_zone["release_rate"] = json!({"rocks_per_year_by_zone": rates});
    let a = post(&app, "/v1/scene", &by_zone).await;
    assert_eq!(a.status, 200, "{}", String::from_utf8_lossy(&a.body));
    let a = a.json();
    let length = 120.0;
    let third = length / 3.0;
    let mut weighted = common::risky_scene(300, 9);
    weighted["release_zones"] = json!([
        {"from_along_dip_m": 0.0, "to_along_dip_m": third, "weight": rates[0]},
        {"from_along_dip_m": third, "to_along_dip_m": 2.0 * third, "weight": rates[1]},
        {"from_along_dip_m": 2.0 * third, "to_along_dip_m": length, "weight": rates[2]},
    ]);
    weighted["release_rate"] = json!({"rocks_per_year": 600.0});
    let b = post(&app, "/v1/scene", &weighted).await.json();
    assert_eq!(a["statistics"], b["statistics"]);
    assert!(
        a["statistics"]["any_overloads_per_year"]["per_year"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    let mut wrong = by_zone.clone();
    wrong["release_rate"] = json!({"rocks_per_year_by_zone": [1.0, 2.0]});
    let mut no_zones = common::risky_scene(10, 9);
    no_zones["release_rate"] = json!({"rocks_per_year_by_zone": [1.0]});
    let mut negative = by_zone.clone();
    negative["release_rate"] = json!({"rocks_per_year_by_zone": [1.0, -2.0, 3.0]});
    common::assert_rejections(
        &app,
        "/v1/scene",
        vec![
            (
                wrong,
                "/release_rate/rocks_per_year_by_zone",
                "invalid_input",
            ),
            (
                no_zones,
                "/release_rate/rocks_per_year_by_zone",
                "invalid_input",
            ),
            (
                negative,
                "/release_rate/rocks_per_year_by_zone/1",
                "invalid_input",
            ),
        ],
    )
    .await;
}

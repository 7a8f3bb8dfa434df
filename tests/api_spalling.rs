//! `POST /v1/spalling` through the router: the paper's Table 1 is reproduced exactly (P₁ = |A∩B|/|B|,
//! P₂ = |A∩C|/|C|, fractional A∩C counts as printed), Wilson intervals bracket each proportion and
//! solve the score equation, an undefined percentage is null with a warning, and an
//! intersection larger than its events is 422 naming the field.

mod common;

use common::{assert_problem, assert_rejections, post, rel};
use serde_json::{Value, json};

fn pct(b: &Value, ptr: &str) -> f64 {
    b.pointer(ptr)
        .and_then(Value::as_f64)
        .unwrap_or_else(|| panic!("{ptr} missing in {b}"))
}

#[tokio::test]
async fn default_request_reproduces_table1() {
    let app = common::app();
    let r = post(&app, "/v1/spalling", &json!({})).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    // physics.md §E, exact ratios of the printed counts.
    let (a, bb, c) = ([118.0, 375.0, 150.0], [8.0, 65.0, 14.0], [22.0, 17.0, 8.0]);
    let (ab, ac) = ([5.0, 32.0, 9.0], [4.5, 10.5, 2.0]);
    for i in 0..3 {
        let z = |f: &str| pct(&b, &format!("/zones/{i}/{f}"));
        assert!(rel(z("spalling_share_pct"), 100.0 * a[i] / 643.0) <= 1e-12);
        assert!(rel(z("high_share_pct"), 100.0 * bb[i] / 87.0) <= 1e-12);
        assert!(rel(z("low_share_pct"), 100.0 * c[i] / 47.0) <= 1e-12);
        assert!(rel(z("spalling_given_high_pct"), 100.0 * ab[i] / bb[i]) <= 1e-12);
        assert!(rel(z("spalling_given_low_pct"), 100.0 * ac[i] / c[i]) <= 1e-12);
        assert!(rel(z("high_given_spalling_pct"), 100.0 * ab[i] / a[i]) <= 1e-12);
        assert!(rel(z("low_given_spalling_pct"), 100.0 * ac[i] / a[i]) <= 1e-12);
    }
    // The printed one-decimal values of the paper.
    let printed = [
        ("/zones/0/spalling_given_high_pct", 62.5),
        ("/zones/1/spalling_given_high_pct", 49.2),
        ("/zones/2/spalling_given_high_pct", 64.3),
        ("/zones/0/spalling_given_low_pct", 20.5),
        ("/zones/1/spalling_given_low_pct", 61.8),
        ("/zones/2/spalling_given_low_pct", 25.0),
        ("/zones/0/spalling_share_pct", 18.4),
        ("/zones/1/spalling_share_pct", 58.3),
        ("/zones/2/spalling_share_pct", 23.3),
    ];
    for (ptr, p) in printed {
        assert!((pct(&b, ptr) - p).abs() <= 0.05, "{ptr}");
    }
    assert_eq!(b["total"]["name"], "total");
    assert_eq!(b["total"]["spalling"], 643.0);
    assert_eq!(b["total"]["spalling_and_low"], 17.0);
    assert!(
        rel(
            pct(&b, "/total/spalling_given_high_pct"),
            100.0 * 46.0 / 87.0
        ) <= 1e-12
    );
    assert!(
        rel(
            pct(&b, "/total/spalling_given_low_pct"),
            100.0 * 17.0 / 47.0
        ) <= 1e-12
    );
    assert_eq!(b["zones"][1]["name"], "middle");
    assert_eq!(b["warnings"], json!([]));
    assert_eq!(b["inputs"]["zones"].as_array().unwrap().len(), 3);
}

/// The Wilson bounds are the two roots of (p̂ − p)² = z²p(1 − p)/n and bracket p̂.
#[tokio::test]
async fn wilson_intervals_solve_the_score_equation() {
    let app = common::app();
    let b = post(&app, "/v1/spalling", &json!({})).await.json();
    let z: f64 = 1.959_963_984_540_054;
    for zone in b["zones"].as_array().unwrap().iter().chain([&b["total"]]) {
        for (x, n, p, ci) in [
            (
                "spalling_and_high",
                "high_resistance",
                "spalling_given_high_pct",
                "spalling_given_high_ci95_pct",
            ),
            (
                "spalling_and_low",
                "low_resistance",
                "spalling_given_low_pct",
                "spalling_given_low_ci95_pct",
            ),
        ] {
            let (x, n) = (zone[x].as_f64().unwrap(), zone[n].as_f64().unwrap());
            let ph = x / n;
            let lo = zone[ci][0].as_f64().unwrap() / 100.0;
            let hi = zone[ci][1].as_f64().unwrap() / 100.0;
            assert!(lo < ph && ph < hi, "{zone}");
            assert!((zone[p].as_f64().unwrap() / 100.0 - ph).abs() < 1e-15);
            for q in [lo, hi] {
                let lhs = (ph - q).powi(2);
                let rhs = z * z * q * (1.0 - q) / n;
                assert!((lhs - rhs).abs() <= 1e-12 * rhs, "{zone}: {lhs} vs {rhs}");
            }
        }
    }
}

#[tokio::test]
async fn zero_denominator_is_null_with_a_warning() {
    let app = common::app();
    let body = json!({"zones": [
        {"name": "a", "spalling": 3, "high_resistance": 0, "low_resistance": 2,
         "spalling_and_high": 0, "spalling_and_low": 1},
        {"name": "b", "spalling": 0, "high_resistance": 0, "low_resistance": 0,
         "spalling_and_high": 0, "spalling_and_low": 0}]});
    let r = post(&app, "/v1/spalling", &body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert_eq!(b["zones"][0]["spalling_given_high_pct"], Value::Null);
    assert_eq!(b["zones"][0]["spalling_given_high_ci95_pct"], Value::Null);
    assert_eq!(b["zones"][0]["high_share_pct"], Value::Null);
    assert_eq!(b["zones"][1]["high_given_spalling_pct"], Value::Null);
    assert_eq!(b["zones"][0]["spalling_given_low_pct"], 50.0);
    let warnings = b["warnings"].as_array().unwrap();
    assert!(warnings.iter().all(|w| w["code"] == "zero_denominator"));
    assert!(
        warnings
            .iter()
            .any(|w| w["message"].as_str().unwrap().contains("zone `b`"))
    );
    assert!(!String::from_utf8_lossy(&r.body).contains("NaN"));
}

#[tokio::test]
async fn inconsistent_counts_are_422_naming_the_field() {
    let app = common::app();
    let zone = |ab: f64, ac: f64| {
        json!({"zones": [{"name": "x", "spalling": 10, "high_resistance": 4, "low_resistance": 6,
                          "spalling_and_high": ab, "spalling_and_low": ac}]})
    };
    assert_rejections(
        &app,
        "/v1/spalling",
        vec![
            (
                zone(5.0, 1.0),
                "/zones/0/spalling_and_high",
                "invalid_input",
            ),
            (zone(1.0, 6.5), "/zones/0/spalling_and_low", "invalid_input"),
            (
                zone(-1.0, 1.0),
                "/zones/0/spalling_and_high",
                "invalid_input",
            ),
            (json!({"zones": []}), "/zones", "invalid_input"),
            (
                json!({"zones": [{"name": "x"}]}),
                "/zones/0",
                "invalid_input",
            ),
            (
                json!({"zones": [{"name": "x", "spalling": 1, "high_resistance": 1,
                    "low_resistance": 1, "spalling_and_high": 1, "spalling_and_low": 1,
                    "extra": 1}]}),
                "/zones/0/extra",
                "unknown_field",
            ),
            (json!({"zones": {}}), "/zones", "invalid_type"),
            (json!({"zones": null}), "/zones", "invalid_type"),
            (
                json!({"high_resistance_n": 5e6}),
                "/high_resistance_n",
                "invalid_input",
            ),
        ],
    )
    .await;
}

/// An event log counted into zones gives the same statistics as its counts given directly.
#[tokio::test]
async fn event_log_equals_its_counts() {
    let app = common::app();
    let mut events = Vec::new();
    // Zone lower: 4 spalling, 2 high (1 with spalling), 3 low (2 with spalling).
    for (support, spalling, r) in [
        (3, true, 7e6),
        (4, true, 0.5e6),
        (5, true, 0.2e6),
        (6, true, 3e6),
        (7, false, 6.5e6),
        (8, false, 0.1e6),
        // Middle: 1 spalling at high resistance, 1 low without spalling.
        (30, true, 9e6),
        (31, false, 0.9e6),
        // Upper: nothing at high or low resistance; resistance exactly at a threshold is neither.
        (50, true, 6e6),
        (51, false, 1e6),
    ] {
        events.push(json!({"support": support, "spalling": spalling, "resistance_n": r}));
    }
    let r = post(&app, "/v1/spalling", &json!({"events": events})).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let from_log = r.json();
    let counts = json!({"zones": [
        {"name": "lower", "spalling": 4, "high_resistance": 2, "low_resistance": 3,
         "spalling_and_high": 1, "spalling_and_low": 2},
        {"name": "middle", "spalling": 1, "high_resistance": 1, "low_resistance": 1,
         "spalling_and_high": 1, "spalling_and_low": 0},
        {"name": "upper", "spalling": 1, "high_resistance": 0, "low_resistance": 0,
         "spalling_and_high": 0, "spalling_and_low": 0}]});
    let from_counts = post(&app, "/v1/spalling", &counts).await.json();
    assert_eq!(from_log["zones"], from_counts["zones"]);
    assert_eq!(from_log["total"], from_counts["total"]);
    assert_eq!(from_log["inputs"]["high_resistance_n"], 6e6);
    assert_eq!(from_log["inputs"]["zone_supports"][2]["last"], 62);

    let bad = json!({"events": [{"support": 99, "spalling": true, "resistance_n": 1.0}]});
    let p = assert_problem(
        &post(&app, "/v1/spalling", &bad).await,
        422,
        "invalid_input",
    );
    assert_eq!(p["errors"][0]["field"], "/events/0/support");
    let both = json!({"events": [], "zones": []});
    assert_problem(
        &post(&app, "/v1/spalling", &both).await,
        422,
        "invalid_input",
    );
    let overlap = json!({"events": [], "zone_supports": [
        {"name": "a", "first": 1, "last": 10}, {"name": "b", "first": 10, "last": 20}]});
    let p = assert_problem(
        &post(&app, "/v1/spalling", &overlap).await,
        422,
        "invalid_input",
    );
    assert_eq!(p["errors"][0]["field"], "/zone_supports/1");
    let crossed = json!({"events": [], "high_resistance_n": 1e6, "low_resistance_n": 2e6});
    let p = assert_problem(
        &post(&app, "/v1/spalling", &crossed).await,
        422,
        "invalid_input",
    );
    assert_eq!(p["errors"][0]["field"], "/low_resistance_n");
}

mod properties {
    //! Property: for any consistent counts over the documented range (0 to 1e12, fractional
    //! allowed), every percentage lies in [0, 100], the zone shares of each event sum to 100 %,
    //! each Wilson interval lies in [0, 100] and contains its proportion, and the total's P₁ is
    //! |ΣA∩B|/|ΣB|. Run longer with PROPTEST_CASES=100000.

    use gangue::physics::spalling::{ZoneCounts, check_counts, spalling_statistics};
    use proptest::prelude::*;

    fn zone() -> impl Strategy<Value = ZoneCounts> {
        (
            0.0f64..1.0,
            0.0f64..1.0,
            0.0f64..1.0,
            0.0f64..=1.0,
            0.0f64..=1.0,
            -12.0f64..12.0,
        )
            .prop_map(|(a, b, c, fab, fac, scale)| {
                let s = 10f64.powf(scale);
                let (a, b, c) = (a * s, b * s, c * s);
                ZoneCounts {
                    spalling: a,
                    high: b,
                    low: c,
                    spalling_and_high: fab * a.min(b),
                    spalling_and_low: fac * a.min(c),
                }
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]
        #[test]
        fn percentages_and_intervals_stay_in_range(zones in proptest::collection::vec(zone(), 1..12)) {
            prop_assert!(check_counts(&zones).is_empty());
            let r = spalling_statistics(&zones);
            let mut share_sum = 0.0;
            for z in r.zones.iter().chain([&r.total]) {
                for p in [z.spalling_share, z.high_share, z.low_share, z.spalling_given_high,
                          z.spalling_given_low, z.high_given_spalling, z.low_given_spalling]
                    .into_iter()
                    .flatten()
                {
                    prop_assert!((0.0..=100.0 + 1e-9).contains(&p), "{p}");
                }
                for (ci, p) in [(z.spalling_given_high_ci95, z.spalling_given_high),
                                (z.spalling_given_low_ci95, z.spalling_given_low)] {
                    prop_assert_eq!(ci.is_some(), p.is_some());
                    if let (Some([lo, hi]), Some(p)) = (ci, p) {
                        prop_assert!(0.0 <= lo && lo <= p + 1e-9 && p <= hi + 1e-9 && hi <= 100.0);
                    }
                }
            }
            for z in &r.zones {
                share_sum += z.spalling_share.unwrap_or(0.0);
            }
            if r.total.counts.spalling > 0.0 {
                prop_assert!((share_sum - 100.0).abs() <= 1e-9, "{share_sum}");
            }
            if let Some(p1) = r.total.spalling_given_high {
                let ab: f64 = zones.iter().map(|z| z.spalling_and_high).sum();
                let b: f64 = zones.iter().map(|z| z.high).sum();
                prop_assert!((p1 - 100.0 * ab / b).abs() <= 1e-9 * p1.max(1.0));
            }
        }
    }
}

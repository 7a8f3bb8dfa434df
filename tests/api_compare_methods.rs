//! `output.compare_methods` of `POST /v1/migration`: the other method on the same case and
//! ensemble, whether the two agree within their intervals, the floor's relief at the rock's
//! scale and its class, and the documented reason and advice; the requested method's own answer
//! unchanged; refused in a scene's `migration_output` and in a sharded computation.

mod common;

use common::{assert_rejections, ok, post, rel};
use serde_json::{Value, json};

/// A 45° face of 40 m, a 60-run ensemble (μ drawn per run), the release dropped 0.5 m at 2 m/s;
/// the floor given, or the plane.
fn case(method: &str, floor: Option<Value>) -> Value {
    let mut face = json!({"dip_deg": 45, "length_m": 40});
    if let Some(f) = floor {
        face["floor"] = f;
    }
    json!({"method": method, "face": face,
           "release": {"drop_height_m": 0.5, "speed_m_s": 2.0},
           "monte_carlo": {"runs": 60, "seed": 1,
                           "friction_coefficient": {"min": 0.15, "max": 0.25}},
           "output": {"compare_methods": true}})
}

/// The face as a grid of spacing `d` (m), 10 m wide, with uniform noise of ±`amp` m.
fn noisy(d: f64, amp: f64) -> Value {
    let tan = 45f64.to_radians().tan();
    let nx = ((1.3 * 40.0 * 45f64.to_radians().cos() + 4.0) / d).ceil() as usize + 1;
    let ny = (10.0 / d).ceil() as usize + 1;
    let mut s = 99u64;
    let heights: Vec<Vec<f64>> = (0..ny)
        .map(|_| {
            (0..nx)
                .map(|j| {
                    let u = (gangue::physics::migration::monte_carlo::splitmix64(&mut s) >> 11)
                        as f64
                        / 9_007_199_254_740_992.0;
                    -(j as f64 * d) * tan + amp * (2.0 * u - 1.0)
                })
                .collect()
        })
        .collect();
    json!({"kind": "grid", "origin_m": [0.0, -5.0], "spacing_m": d, "heights_m": heights})
}

#[tokio::test]
async fn both_methods_agree_on_the_plane_and_the_answer_is_otherwise_unchanged() {
    let app = common::app();
    let a = ok(&post(&app, "/v1/migration", &case("lumped_mass", None)).await);
    let c = &a["method_comparison"];
    assert_eq!(c["floor"], "plane", "{c}");
    assert_eq!(c["reason"], "shape", "{c}");
    assert_eq!(c["floor_relief_m"], 0.0);
    assert_eq!(c["agree"], true, "{c}");
    let m = c["methods"].as_array().unwrap();
    assert_eq!(m[0]["method"], "lumped_mass");
    assert_eq!(m[1]["method"], "rigid_block");
    for x in m {
        assert_eq!(x["runs"], 60);
        let mean = x["speed_mean_m_s"].as_f64().unwrap();
        let ci: Vec<f64> = x["speed_ci95_m_s"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert!(ci[0] < mean && mean < ci[1], "{x}");
    }
    // the requested method's part is its own answer, and the other's is the other request's
    let mut plain = case("lumped_mass", None);
    plain["output"] = json!({});
    let p = ok(&post(&app, "/v1/migration", &plain).await);
    assert_eq!(a["statistics"], p["statistics"]);
    assert_eq!(m[0]["speed_mean_m_s"], p["statistics"]["speed_m_s"]["mean"]);
    let mut other = plain.clone();
    other["method"] = json!("rigid_block");
    let o = ok(&post(&app, "/v1/migration", &other).await);
    assert_eq!(m[1]["speed_mean_m_s"], o["statistics"]["speed_m_s"]["mean"]);
    let d = c["speed_difference"].as_f64().unwrap();
    let (x, y) = (
        m[0]["speed_mean_m_s"].as_f64().unwrap(),
        m[1]["speed_mean_m_s"].as_f64().unwrap(),
    );
    assert!(rel(d, y / x - 1.0) < 1e-12, "{d}");
    // the plan says it ran, and a request without it says why not
    let stage = |b: &Value| {
        b["plan"]
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["stage"] == "comparison")
            .cloned()
            .unwrap()
    };
    assert_eq!(stage(&a)["status"], "ran");
    assert_eq!(stage(&p)["status"], "skipped");
    assert!(p.get("method_comparison").is_none());
}

#[tokio::test]
async fn the_floor_is_classed_by_its_relief_at_the_rocks_scale() {
    let app = common::app();
    // the default cube, 0.3 m: 0.372 m the sphere of its volume
    for (d, amp, class) in [
        (0.5, 0.01, "smooth"),
        (0.5, 0.05, "relief_below_rock_size"),
        (1.0, 0.5, "relief_above_rock_size"),
    ] {
        let mut req = case("lumped_mass", Some(noisy(d, amp)));
        req["monte_carlo"]["runs"] = json!(8);
        let a = ok(&post(&app, "/v1/migration", &req).await);
        let c = &a["method_comparison"];
        assert_eq!(c["floor"], class, "±{amp} m on {d} m: {c}");
        assert!(rel(c["rock_size_m"].as_f64().unwrap(), 0.372_210_294_5) < 1e-6);
        // uniform noise of ±a has an RMS of a/√3; the surface between the nodes is smoother
        let relief = c["floor_relief_m"].as_f64().unwrap();
        assert!(
            relief > 0.2 * amp && relief < amp / 3f64.sqrt(),
            "±{amp} m: relief {relief}"
        );
        let note = c["note"].as_str().unwrap();
        assert!(
            note.contains("trust") || note.contains("Use either"),
            "{note}"
        );
    }
}

#[tokio::test]
async fn a_single_run_compares_the_two_runs() {
    let app = common::app();
    let mut req = case("rigid_block", None);
    req.as_object_mut().unwrap().remove("monte_carlo");
    let a = ok(&post(&app, "/v1/migration", &req).await);
    let c = &a["method_comparison"];
    let m = c["methods"].as_array().unwrap();
    assert_eq!(m[0]["method"], "rigid_block");
    assert_eq!(m[0]["runs"], 1);
    assert_eq!(m[0]["speed_ci95_m_s"], Value::Null);
    assert_eq!(m[0]["speed_mean_m_s"], a["arrival"]["speed_m_s"]);
    // agreement of single runs: within the speed tolerance and the same outcome
    let d = c["speed_difference"].as_f64().unwrap();
    assert_eq!(
        c["agree"],
        json!(d.abs() <= 0.05 / (1.0 + d.max(0.0))),
        "{c}"
    );
}

#[tokio::test]
async fn compare_methods_belongs_to_the_migration_request() {
    let app = common::app();
    assert_rejections(
        &app,
        "/v1/scene",
        vec![(
            json!({"migration_output": {"compare_methods": true}}),
            "/migration_output/compare_methods",
            "invalid_input",
        )],
    )
    .await;
}

/// A sharded migration runs the requested method's runs only: `compare_methods` is refused
/// naming the field.
#[test]
fn a_sharded_migration_refuses_compare_methods_naming_the_field() {
    let body = json!({"monte_carlo": {"runs": 5}, "output": {"compare_methods": true}});
    let (ok, text) = common::shard_0_of_2(&body, "migration", "compare-shard");
    assert!(!ok, "{text}");
    assert!(
        text.contains("/output/compare_methods") && text.contains("sharded"),
        "{text}"
    );
}

/// Where rocks come to rest (a 32° face, μ ~ U[0.6, 0.8] about tan 32° = 0.62) the sliding
/// point stops where the rigid sphere rolls on: the shares reaching the lower end differ, and the
/// reason is how the rock moves (`stopping`), whatever the floor.
#[tokio::test]
async fn where_rocks_stop_the_reason_is_how_they_move() {
    let app = common::app();
    let mut req = case("lumped_mass", None);
    req["face"]["dip_deg"] = json!(32);
    req["rock"] = json!({"shape": "sphere", "radius_m": 0.2});
    req["monte_carlo"]["runs"] = json!(30);
    req["monte_carlo"]["friction_coefficient"] = json!({"min": 0.6, "max": 0.8});
    let a = ok(&post(&app, "/v1/migration", &req).await);
    let c = &a["method_comparison"];
    let m = c["methods"].as_array().unwrap();
    let (lm, rb) = (
        m[0]["reached_fraction"].as_f64().unwrap(),
        m[1]["reached_fraction"].as_f64().unwrap(),
    );
    assert!(lm < 0.5 && rb > 0.9, "{c}");
    assert_eq!(c["agree"], false, "{c}");
    assert_eq!(c["reason"], "stopping", "{c}");
    assert_eq!(c["floor"], "plane", "{c}");
    assert!(c["note"].as_str().unwrap().contains("rolls on"), "{c}");
}

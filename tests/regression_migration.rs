//! Regressions of `POST /v1/migration` found against independent references (issue 7).
//!
//! Physical expectations: a point mass on a triangulated floor never goes below it; caught in a
//! pit (every neighbouring node higher) it comes to rest; a rock released from any height just
//! above the lower end strikes the floor once before it arrives, with the closed-form speed of
//! physics.md §C.1; a vanishing face length gives a finite (limit) answer.

mod common;

use common::{post, rel};
use serde_json::{Value, json};

fn load(name: &str) -> Value {
    let p = common::shared_dir().join("repro").join(name);
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// Height of a grid floor (cells split along the (j, i)–(j+1, i+1) diagonal), m.
fn grid_height(floor: &Value, x: f64, y: f64) -> Option<f64> {
    let d = floor["spacing_m"].as_f64().unwrap();
    let o = [
        floor["origin_m"][0].as_f64().unwrap(),
        floor["origin_m"][1].as_f64().unwrap(),
    ];
    let h: Vec<Vec<f64>> = serde_json::from_value(floor["heights_m"].clone()).unwrap();
    let (u, w) = ((x - o[0]) / d, (y - o[1]) / d);
    let (nx, ny) = (h[0].len(), h.len());
    if !(u >= 0.0 && w >= 0.0 && u <= (nx - 1) as f64 && w <= (ny - 1) as f64) {
        return None;
    }
    let j = (u.floor() as usize).min(nx - 2);
    let i = (w.floor() as usize).min(ny - 2);
    let (fx, fy) = (u - j as f64, w - i as f64);
    let (z00, z10, z01, z11) = (h[i][j], h[i][j + 1], h[i + 1][j], h[i + 1][j + 1]);
    Some(if fx >= fy {
        z00 + fx * (z10 - z00) + fy * (z11 - z10)
    } else {
        z00 + fy * (z01 - z00) + fx * (z11 - z01)
    })
}

#[tokio::test]
async fn rock_in_a_grid_pit_comes_to_rest_instead_of_falling_through_and_arriving() {
    let app = common::app();
    let mut req = load("grid_tunnel.json");
    req["output"] = json!({"trajectory": true, "sample_interval_s": 0.001});
    let r = post(&app, "/v1/migration", &req).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let floor = &req["face"]["floor"];
    let below = |p: &Value| -> f64 {
        let p: Vec<f64> = serde_json::from_value(p.clone()).unwrap();
        grid_height(floor, p[0], p[1]).map_or(0.0, |z| z - p[2])
    };
    // the node (2.2, 0.2) is a pit: all six neighbours are higher
    assert_eq!(b["arrival"]["phase"], "stopped", "{}", b["arrival"]);
    assert_eq!(b["arrival"]["stop_reason"], "at_rest");
    let pos = &b["arrival"]["position_m"];
    assert!((pos[0].as_f64().unwrap() - 2.2).abs() < 1e-9);
    assert!((pos[1].as_f64().unwrap() - 0.2).abs() < 1e-9);
    assert!(below(pos).abs() < 1e-9);
    for e in b["events"].as_array().unwrap() {
        assert!(below(&e["position_m"]) < 1e-9, "event below the floor: {e}");
    }
    let tr = &b["trajectory"]["position_m"];
    let n = tr.as_array().unwrap().len();
    assert!(n > 1000);
    for p in tr.as_array().unwrap() {
        assert!(below(p) < 1e-9, "sample below the floor: {p}");
    }
    let e = &b["energy"];
    assert!(e["residual_j"].as_f64().unwrap().abs() < 1e-9 * e["total_start_j"].as_f64().unwrap());
}

/// Closed form (physics.md §C.1–C.2) of a vertical drop h onto the 45° plane at s0 < S, one
/// impact (e_n = 0.3, e_t = 0.8), then flight (or, below the stop speed 0.5 m/s, the slide)
/// to the lower end: the arrival speed.
fn one_impact_arrival(h: f64, s0: f64, s: f64) -> f64 {
    let g = 9.81;
    let (c, sn) = (45f64.to_radians().cos(), 45f64.to_radians().sin());
    let v0 = (2.0 * g * h).sqrt();
    let (vx, vy) = (0.8 * v0 * sn, 0.3 * v0 * c);
    let d = s - s0;
    if vy < 0.5 {
        // below the stop speed: the slide (μ = 0.2) from vx
        let a = g * (sn - 0.2 * c);
        return (vx * vx + 2.0 * a * d).sqrt();
    }
    let a = g * sn;
    let tau = 2.0 * d / (vx + (vx * vx + 2.0 * a * d).sqrt());
    let (ux, uy) = (vx + a * tau, vy - g * c * tau);
    ux.hypot(uy)
}

#[tokio::test]
async fn release_a_hair_above_the_lower_end_strikes_once_before_arriving() {
    let app = common::app();
    let s = 120.0f64;
    let mut along = vec![119.99999999999999, s - 1e-12, s - 1e-9, s - 1e-6, s - 1e-3];
    // 1 to 8 ulps below the end
    let mut a = s;
    for _ in 0..8 {
        a = f64::from_bits(a.to_bits() - 1);
        along.push(a);
    }
    for h in [1000.0, 3.27, 0.01] {
        for &s0 in &along {
            let r = post(
                &app,
                "/v1/migration",
                &json!({"release": {"drop_height_m": h, "along_dip_m": s0}}),
            )
            .await;
            assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
            let b = r.json();
            assert_eq!(b["impact_count"], 1, "h {h}, s0 {s0}: {}", b["arrival"]);
            let v = b["arrival"]["speed_m_s"].as_f64().unwrap();
            let exact = one_impact_arrival(h, s0, s);
            assert!(rel(v, exact) < 1e-9, "h {h}, s0 {s0}: {v} vs {exact}");
        }
    }
    // the figure: 84.6 m/s after one impact from 1000 m
    assert!((one_impact_arrival(1000.0, 119.99999999999999, s) - 84.63).abs() < 0.01);
}

/// A face 5e-324 m long (g = 0.1, dip 5°, μ = 0, e_t = 0): the rock falls 3.27 m in
/// √(2·3.27/0.1) = 8.0870 s, strikes, and slides the subnormal length with a = g sin θ, arriving
/// at the lower end with speed √(2 a L) ≈ 2.93e-163 m/s: a finite answer whose speed, along-dip
/// velocity and time agree with the closed form (no underflow to 0, no 500).
#[tokio::test]
async fn subnormal_face_length_without_friction_gives_the_closed_form_answer_not_500() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"face": {"dip_deg": 5, "friction_coefficient": 0, "length_m": 5e-324,
                "restitution_tangential": 0}, "gravity_m_s2": 0.1}),
    )
    .await;
    let b = r.json();
    assert_eq!(r.status, 200, "{b}");
    let a = &b["arrival"];
    assert_eq!(a["stop_reason"], "lower_end", "{b}");
    let t = a["time_s"].as_f64().unwrap();
    assert!(rel(t, (2.0 * 3.27 / 0.1f64).sqrt()) < 1e-12, "{t}");
    // v = √(2 a L), a = g sin 5°: formed as √(2a)·√L so that it does not underflow
    let acc = 0.1 * 5f64.to_radians().sin();
    let v = (2.0 * acc).sqrt() * 5e-324f64.sqrt();
    // L is one subnormal ulp: the solver's result is exact only to the subnormal's resolution
    let speed = a["speed_m_s"].as_f64().unwrap();
    let along = a["along_dip_velocity_m_s"].as_f64().unwrap();
    assert!(rel(speed, v) < 1e-6, "speed {speed} vs {v}: {b}");
    assert!(
        rel(along, v) < 1e-6,
        "along-dip velocity {along} vs {v}: {b}"
    );
}

#[tokio::test]
async fn one_run_ensemble_warns_that_its_std_is_null() {
    let app = common::app();
    // Both methods share the ensemble's warnings (the rigid block on a short face to stay cheap).
    for req in [
        json!({"monte_carlo": {"runs": 1, "seed": 7}}),
        json!({"method": "rigid_block", "face": {"length_m": 2.0},
               "release": {"drop_height_m": 0.0},
               "monte_carlo": {"runs": 1, "seed": 7,
                   "friction_coefficient": {"distribution": "normal", "mean": 1.9, "std": 0.5}}}),
    ] {
        let r = post(&app, "/v1/migration", &req).await;
        assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
        let b = r.json();
        let w = b["warnings"].as_array().unwrap();
        assert!(w.iter().any(|w| w["code"] == "single_run"), "{b}");
        for run in b["statistics"]["impact_count"]["max"].as_f64().into_iter() {
            assert!(run.is_finite());
        }
    }
}

/// Contours `[[x, ±10000]]` every 10 m resampled at 1 cm would be 3.2e7 points (7 GB, 60 s):
/// the floor's memory is estimated before it is built and the request refused at once, naming
/// resolution_m, the estimate and the limit.
#[tokio::test]
async fn contours_resampled_to_millions_of_points_are_refused_before_they_are_built() {
    let app = common::app();
    let req = load("contour_memory.json");
    let t = std::time::Instant::now();
    let r = post(&app, "/v1/migration", &req).await;
    let b = r.json();
    assert_eq!(r.status, 422, "{b}");
    assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
    let e = &b["errors"][0];
    assert_eq!(e["field"], "/face/floor/resolution_m", "{b}");
    assert_eq!(e["value"], 0.01, "{b}");
    let m = e["message"].as_str().unwrap();
    // 16 lines of 2e6 cm-steps: 3.2e7 points; the limit in MB (512 MiB)
    assert!(m.contains("3.200e7 points"), "{m}");
    assert!(m.contains("537 MB"), "{m}");
    assert!(m.contains("GANGUE_MAX_FLOOR_BYTES"), "{m}");
    // the limit is published
    let p = common::get(&app, "/v1/presets").await.json();
    assert_eq!(p["limits"]["max_floor_bytes"], 512 * 1024 * 1024);
}

/// A contour floor whose estimate lies just under the configured limit is built and run; one
/// point more of resampling (a finer resolution) is refused.
#[tokio::test]
async fn contour_floor_just_under_the_memory_limit_runs() {
    use gangue::physics::migration::{CONTOUR_BYTES_PER_POINT, ContourLine, contour_points};
    let lines: Vec<ContourLine> = (0..4)
        .map(|k| ContourLine {
            elevation: -10.0 * k as f64,
            points: vec![[10.0 * k as f64, -50.0], [10.0 * k as f64, 50.0]],
        })
        .collect();
    let n = contour_points(&lines, 0.5);
    // 4 lines of 200 half-metre steps: 201 points each
    assert_eq!(n, 804.0);
    let limit = (n * CONTOUR_BYTES_PER_POINT) as u64;
    let cfg = gangue::config::Config {
        max_floor_bytes: limit,
        ..gangue::config::Config::default()
    };
    let app = gangue::app(cfg);
    let req = |res: f64| {
        json!({"face": {"length_m": 20, "floor": {"kind": "contours", "resolution_m": res,
            "contours": lines.iter().map(|c| json!({"elevation_m": c.elevation, "points_m": c.points})).collect::<Vec<_>>()}},
            "release": {"along_dip_m": 1}})
    };
    let r = post(&app, "/v1/migration", &req(0.5)).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let r = post(&app, "/v1/migration", &req(0.49)).await;
    let b = r.json();
    assert_eq!(r.status, 422, "{b}");
    assert_eq!(b["errors"][0]["field"], "/face/floor/resolution_m", "{b}");
}

/// A floor field the floor kind does not have, and a contour point out of range, are refused
/// with the value that was sent (not null).
#[tokio::test]
async fn refused_floor_fields_echo_the_value_sent() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"face": {"floor": {"kind": "plane", "spacing_m": 0.5, "origin_m": [1, 2]}}}),
    )
    .await;
    assert_eq!(r.status, 422);
    let b = r.json();
    let errs = b["errors"].as_array().unwrap();
    let get = |f: &str| {
        errs.iter()
            .find(|e| e["field"] == f)
            .unwrap_or_else(|| panic!("{b}"))
    };
    assert_eq!(get("/face/floor/spacing_m")["value"], 0.5);
    assert_eq!(get("/face/floor/origin_m")["value"], json!([1.0, 2.0]));
    let r = post(
        &app,
        "/v1/migration",
        &json!({"face": {"floor": {"kind": "contours", "contours": [
            {"elevation_m": 0, "points_m": [[0, 0], [0, 10]]},
            {"elevation_m": -5, "points_m": [[5, 0], [2e6, 10]]}]}}}),
    )
    .await;
    assert_eq!(r.status, 422);
    let b = r.json();
    let e = &b["errors"][0];
    assert_eq!(e["field"], "/face/floor/contours/1/points_m/1", "{b}");
    assert_eq!(e["value"], json!([2e6, 10.0]), "{b}");
}

/// On a 0.5 m face the first rebound reaches the lower end long before its apex: the largest
/// bounce height is 0 (no apex reached), not the apex of a flight that ended first. On the
/// default face the reported height is an apex the closed form of physics.md §C.1 gives.
#[tokio::test]
async fn max_bounce_height_counts_only_apexes_reached_before_the_run_ends() {
    let app = common::app();
    let r = post(&app, "/v1/migration", &json!({"face": {"length_m": 0.5}})).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert_eq!(b["impact_count"], 1, "{b}");
    assert_eq!(b["max_bounce_height_m"], 0.0, "{b}");
    // a long face: the rock flies through its apex; the apex of a rebound with normal speed r is
    // r² / (2 g cos θ), and the reported height is one of those reached
    let r = post(&app, "/v1/migration", &json!({"output": {"events": true}})).await;
    let b = r.json();
    let h = b["max_bounce_height_m"].as_f64().unwrap();
    assert!(h > 0.0, "{b}");
}

/// Friction drawn from a normal distribution (mean 0.2, std 1) has draws below 0 and above 2:
/// they are clipped to the face's range [0, 2] and a `friction_clipped` warning counts them
/// (the count is checked against an independent count of the standard normal's tails).
#[tokio::test]
async fn friction_drawn_outside_its_range_is_clipped_with_a_warning() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"monte_carlo": {"runs": 400, "seed": 3,
            "friction_coefficient": {"distribution": "normal", "mean": 0.2, "std": 1.0}}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let w = b["warnings"].as_array().unwrap();
    let c = w
        .iter()
        .find(|w| w["code"] == "friction_clipped")
        .unwrap_or_else(|| panic!("{b}"));
    let m = c["message"].as_str().unwrap();
    let n: f64 = m.split(' ').next().unwrap().parse().unwrap();
    // P(x < 0) + P(x > 2) = Φ(−0.2) + Φ(−1.8) = 0.4207 + 0.0359 = 0.4566: 183 of 400 expected,
    // binomial std 10
    assert!((n - 182.6).abs() < 5.0 * 10.0, "{n}: {m}");
    // without tails to clip, no warning
    let r = post(
        &app,
        "/v1/migration",
        &json!({"monte_carlo": {"runs": 50, "seed": 3,
            "friction_coefficient": {"distribution": "uniform", "min": 0.1, "max": 0.3}}}),
    )
    .await;
    let b = r.json();
    assert!(
        !b["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "friction_clipped"),
        "{b}"
    );
}

/// `stop_normal_speed_m_s: 0` on the plane: the rebounds r, e r, e² r, … never fall below a
/// zero stop speed, so the series ends at the documented 1e-6 m/s cutoff and a
/// `rebound_cutoff` warning says so; the number of impacts is the closed form's: the first
/// k with e_n^k v_n0 < 1e-6 (e_n = 0.3 fixed, vertical drop of 3.27 m on 45°).
#[tokio::test]
async fn zero_stop_speed_ends_the_bounce_series_at_the_documented_cutoff_with_a_warning() {
    let app = common::app();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"lumped_mass": {"stop_normal_speed_m_s": 0}, "face": {"restitution_normal": 0.3,
            "restitution_tangential": 0.0, "friction_coefficient": 0.9}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let w = b["warnings"].as_array().unwrap();
    assert!(w.iter().any(|w| w["code"] == "rebound_cutoff"), "{b}");
    // e_t = 0: every rebound is normal to the plane, r_k = 0.3^k · 0.3 v0 cos 45°
    let v0 = (2.0f64 * 9.81 * 3.27).sqrt();
    let mut r0 = 0.3 * v0 * 45f64.to_radians().cos();
    let mut k = 1;
    while r0 >= 1e-6 {
        r0 *= 0.3;
        k += 1;
    }
    assert_eq!(b["impact_count"], k, "{}", b["arrival"]);
    // the default stop speed 0.5 m/s gives no such warning
    let r = post(&app, "/v1/migration", &json!({})).await;
    let b = r.json();
    assert!(
        !b["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "rebound_cutoff")
    );
}

/// One plan point given on two contours of different elevations (a vertical wall) is refused
/// with 422 naming the second occurrence and echoing the point; the same point on two contours
/// of one elevation is accepted.
#[tokio::test]
async fn one_point_at_two_elevations_is_refused_naming_the_point() {
    let app = common::app();
    let floor = |z2: f64| {
        json!({"face": {"length_m": 10, "floor": {"kind": "contours", "contours": [
            {"elevation_m": 0, "points_m": [[0, -5], [0, 5]]},
            {"elevation_m": z2, "points_m": [[10, -5], [0, 5], [10, 5]]}]}},
            "release": {"along_dip_m": 1}})
    };
    let r = post(&app, "/v1/migration", &floor(-10.0)).await;
    let b = r.json();
    assert_eq!(r.status, 422, "{b}");
    assert_eq!(
        b["errors"][0]["field"], "/face/floor/contours/1/points_m/1",
        "{b}"
    );
    assert_eq!(b["errors"][0]["value"], json!([0.0, 5.0]), "{b}");
    let r = post(&app, "/v1/migration", &floor(0.0)).await;
    assert_ne!(r.status, 422, "{}", String::from_utf8_lossy(&r.body));
}

/// Rolling a cube: the motion is a solid sphere's (a = 5/7 g sin θ on the plane, independent of
/// the radius) and the angular speed is v / (side_length_m / 2); a `roll_as_sphere` warning says
/// which radius was used. A sphere rolls with its own radius and gets no warning.
#[tokio::test]
async fn rolling_a_cube_uses_the_inscribed_sphere_and_says_so() {
    let app = common::app();
    let body = json!({"lumped_mass": {"motion": "roll"}, "release": {"drop_height_m": 0},
        "face": {"friction_coefficient": 0.5}, "rock": {"side_length_m": 0.4}});
    let r = post(&app, "/v1/migration", &body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let w = b["warnings"].as_array().unwrap();
    let m = w
        .iter()
        .find(|w| w["code"] == "roll_as_sphere")
        .unwrap_or_else(|| panic!("{b}"))["message"]
        .as_str()
        .unwrap();
    assert!(m.contains("0.2 m"), "{m}");
    let a = &b["arrival"];
    let v = a["speed_m_s"].as_f64().unwrap();
    // from rest on the 45° plane over 120 m: v = √(2 · 5/7 g sin θ · 120)
    let exact = (2.0 * 5.0 / 7.0 * 9.81 * 45f64.to_radians().sin() * 120.0).sqrt();
    assert!(rel(v, exact) < 1e-9, "{v} vs {exact}");
    let w_rad = a["angular_speed_rad_s"].as_f64().unwrap();
    assert!(rel(w_rad, v / 0.2) < 1e-9, "{w_rad} vs {}", v / 0.2);
}

/// Crossing contours have no single height where they cross: contours of different elevations
/// that cross, and one polyline crossing itself, are 422 naming the later crossing segment by
/// its first point and echoing that point; contours meeting at a shared point at one elevation
/// (a closed ring, a contour ending on another) are accepted.
#[tokio::test]
async fn crossing_contours_are_refused_naming_the_crossing_segment() {
    let app = common::app();
    let floor = |extra: Value| {
        let mut lines = vec![
            json!({"elevation_m": 0, "points_m": [[0, -5], [0, 5]]}),
            json!({"elevation_m": -10, "points_m": [[10, -5], [10, 5]]}),
        ];
        lines.push(extra);
        json!({"face": {"length_m": 8, "floor": {"kind": "contours", "contours": lines}},
            "release": {"along_dip_m": 1}})
    };
    // contour 2 at −5 m runs from x = 5 back across contour 0 at x = 0
    let r = post(
        &app,
        "/v1/migration",
        &floor(json!({"elevation_m": -5, "points_m": [[5, -5], [5, 0], [-1, 3]]})),
    )
    .await;
    let b = r.json();
    assert_eq!(r.status, 422, "{b}");
    assert_eq!(
        b["errors"][0]["field"], "/face/floor/contours/2/points_m/1",
        "{b}"
    );
    assert_eq!(b["errors"][0]["value"], json!([5.0, 0.0]), "{b}");
    assert_eq!(b["errors"].as_array().unwrap().len(), 1, "{b}");
    // contour 2 at −5 m crosses itself at (5, 0)
    let r = post(
        &app,
        "/v1/migration",
        &floor(json!({"elevation_m": -5, "points_m": [[5, -5], [5, 4], [3, 0], [7, 0]]})),
    )
    .await;
    let b = r.json();
    assert_eq!(r.status, 422, "{b}");
    assert_eq!(
        b["errors"][0]["field"], "/face/floor/contours/2/points_m/2",
        "{b}"
    );
    assert_eq!(b["errors"][0]["value"], json!([3.0, 0.0]), "{b}");
    // a contour of another elevation ending on contour 1 (a point at two heights)
    let r = post(
        &app,
        "/v1/migration",
        &floor(json!({"elevation_m": -5, "points_m": [[5, -5], [10, 1]]})),
    )
    .await;
    let b = r.json();
    assert_eq!(r.status, 422, "{b}");
    assert_eq!(
        b["errors"][0]["field"], "/face/floor/contours/2/points_m/0",
        "{b}"
    );
    // touching at one elevation is fine: a closed ring, and a contour ending on contour 1
    for ok in [
        json!({"elevation_m": -5, "points_m": [[4, -2], [6, -2], [6, 2], [4, 2], [4, -2]]}),
        json!({"elevation_m": -10, "points_m": [[12, -5], [10, 1]]}),
    ] {
        let r = post(&app, "/v1/migration", &floor(ok.clone())).await;
        assert_eq!(r.status, 200, "{ok}: {}", String::from_utf8_lossy(&r.body));
    }
}

/// A drop height of a few ulps or less (down to the subnormal 5e-324 m) cannot lift the rock off
/// the floor: it starts on the floor and slides as with no drop, instead of falling vertically
/// through the floor and "arriving" 170 m below it in flight.
#[tokio::test]
async fn vanishing_drop_height_starts_on_the_floor_instead_of_falling_through_it() {
    let app = common::app();
    let on_floor = post(
        &app,
        "/v1/migration",
        &json!({"release": {"drop_height_m": 0.0}}),
    )
    .await;
    assert_eq!(on_floor.status, 200);
    let want = on_floor.json()["arrival"]["speed_m_s"].as_f64().unwrap();
    for h in [5e-324, 1e-300, 1e-20, 1e-16] {
        let r = post(
            &app,
            "/v1/migration",
            &json!({"release": {"drop_height_m": h}}),
        )
        .await;
        let b = r.json();
        assert_eq!(r.status, 200, "h = {h}: {b}");
        assert_eq!(b["arrival"]["phase"], "slide", "h = {h}: {b}");
        let v = b["arrival"]["speed_m_s"].as_f64().unwrap();
        assert!(common::rel(v, want) < 1e-9, "h = {h}: {v} against {want}");
    }
    // A small but resolvable drop still lands: one impact.
    let r = post(
        &app,
        "/v1/migration",
        &json!({"release": {"drop_height_m": 1e-9}}),
    )
    .await;
    let b = r.json();
    assert_eq!(r.status, 200, "{b}");
    assert_eq!(b["impact_count"], 1, "{b}");
}

/// A small cube dropped 9 m onto a gentle (8.9°), very rough (μ 1.45) face stops within a few
/// seconds, but its stuck shear springs (which carry no dashpot) keep a torsional vibration of
/// about 0.008 rad/s: the instantaneous speed test never passed, the run stepped 1e7 times to its
/// 200 s end time and reported a "slide", and a scene ensemble of such runs timed out (504;
/// found by tests/stability_endpoints.rs). A block that goes nowhere over the rest window is at
/// rest now.
#[tokio::test]
async fn a_block_vibrating_on_its_stuck_shear_springs_comes_to_rest() {
    let app = common::app();
    let body = json!({"method": "rigid_block", "end_time_s": 200,
        "face": {"dip_deg": 8.9171938278325, "friction_coefficient": 1.4462019341130112,
                 "length_m": 8.0, "restitution_normal": 0.0, "restitution_tangential": 0.0},
        "release": {"along_dip_m": 4.418877164262054, "drop_height_m": 9.015941685193296},
        "rock": {"side_length_m": 0.1915043140300795}, "output": {"events": false}});
    let r = post(&app, "/v1/migration", &body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert_eq!(b["arrival"]["stop_reason"], "at_rest", "{}", b["arrival"]);
    assert!(
        b["arrival"]["time_s"].as_f64().unwrap() < 5.0,
        "{}",
        b["arrival"]
    );
    assert!(
        b["rigid_block"]["steps"].as_u64().unwrap() < 200_000,
        "{}",
        b["rigid_block"]
    );
    // It rests near where it landed: 0.33–0.35 m down the dip of its release point once the
    // step is converged (safety 0.1 to 0.025), 0.21 m at the default step (the coarser step
    // of the undamped rule rested it 0.09 m above).
    let along = b["arrival"]["along_dip_m"].as_f64().unwrap();
    assert!((along - 4.418877164262054).abs() < 0.5, "{along}");
}

/// The 40° face as a grid z = −x tan 40° over x in [0, 45] m, y in [−6, 6] m, spacing 1 m: its
/// upper edge is the line x = 0, where a release at the default `along_dip_m` 0 is placed.
fn plane_grid_40() -> Value {
    let t = 40f64.to_radians().tan();
    let heights: Vec<Vec<f64>> = (0..=12)
        .map(|_| (0..=45).map(|j| -(j as f64) * t).collect())
        .collect();
    json!({"kind": "grid", "origin_m": [0.0, -6.0], "spacing_m": 1.0, "heights_m": heights})
}

/// A rigid block dropped (3.27 m, the default) onto a grid floor at `along_dip_m` 0 landed
/// across the floor's upper edge: the corners beyond the edge had no floor under them. They
/// must never come back onto the floor already deep (their spring energy ½kₙU² created from
/// nothing: the block was thrown off at 143 m/s with 2.4 MJ from a 14.9 kJ start). Physical
/// expectation: no speed above the lossless bound √(v₀² + 2g·drop) for the centre's drop, the
/// energy account closed (no energy created). Released at the edge, the block is now placed
/// with every corner over the floor, so it lands on the floor and runs on.
#[tokio::test]
async fn rigid_block_landing_across_a_grid_edge_is_not_thrown_off_at_140_m_s() {
    let app = common::app();
    let req = json!({"method": "rigid_block",
        "face": {"length_m": 30, "dip_deg": 40, "floor": plane_grid_40()},
        "output": {"trajectory": true, "sample_interval_s": 0.002, "events": true}});
    let r = post(&app, "/v1/migration", &req).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let g = 9.81;
    let z0 = b["trajectory"]["position_m"][0][2].as_f64().unwrap();
    let e = &b["energy"];
    let start = e["total_start_j"].as_f64().unwrap();
    let residual = e["residual_j"].as_f64().unwrap();
    // energy in play: m g (drop of the centre + the fall) at most; the residual is second order
    assert!(residual.abs() <= 2e-3 * start, "{e}");
    for (p, v) in b["trajectory"]["position_m"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["trajectory"]["speed_m_s"].as_array().unwrap())
    {
        let drop = (z0 - p[2].as_f64().unwrap()).max(0.0);
        let bound = (2.0 * g * drop).sqrt();
        let v = v.as_f64().unwrap();
        assert!(
            v <= bound * 1.001 + 1e-6,
            "speed {v} above the free-fall bound {bound} at {p}"
        );
    }
    for ev in b["events"].as_array().unwrap() {
        let drop = (z0 - ev["position_m"][2].as_f64().unwrap()).max(0.0);
        let before = ev["speed_before_m_s"].as_f64().unwrap_or(0.0);
        assert!(before <= (2.0 * g * drop).sqrt() * 1.001 + 1e-6, "{ev}");
    }
    // released at the upper edge, half the block would overhang it: the block is placed where
    // every corner is over the floor (half its side, 0.15 m, down the dip; warning
    // release_moved), lands on the floor, not across its edge, and runs to the lower end
    let a = &b["arrival"];
    assert_eq!(a["stop_reason"], "lower_end", "{a}");
    assert!(
        b["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "release_moved"),
        "{}",
        b["warnings"]
    );

    // released 3 m down the face, clear of the edge, the same block slides to the lower end
    let mut req = req;
    req["release"] = json!({"along_dip_m": 3.0});
    let r = post(&app, "/v1/migration", &req).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let a = &b["arrival"];
    let e = &b["energy"];
    assert_eq!(a["stop_reason"], "lower_end", "{a}");
    let start = e["total_start_j"].as_f64().unwrap();
    assert!(
        e["residual_j"].as_f64().unwrap().abs() <= 2e-3 * start,
        "{e}"
    );
    // no faster than a lossless descent of 27 m down the 40° face after the 3.27 m drop
    let bound = (2.0 * g * (3.27 + 27.0 * 40f64.to_radians().sin())).sqrt();
    assert!(
        a["speed_m_s"].as_f64().unwrap() < bound,
        "{a} bound {bound}"
    );
}

//! Releases as they happen (api.md `POST /v1/migration`, Release): a velocity vector, a plan
//! point in the floor's own coordinates, the rigid block's orientation and spin, and ensembles
//! over the release velocity and over uniformly random orientations; the ellipsoid block.
//! Physical expectations: a thrown point mass follows the parabola to its first impact on the
//! plane (closed form); a top-spun sphere on a 45° plane slips, its friction pulling it down the
//! dip while its spin falls, until it rolls (closed form of the slip and roll phases); a block
//! given an orientation starts with its lowest point on the floor; the release draws leave the
//! friction and restitution draws as they were (common random numbers).

mod common;
use common::migrate_ok as ok;

use common::{assert_problem, post, rel};
use serde_json::{Value, json};

const G: f64 = 9.81;

fn has_warning(b: &Value, code: &str) -> bool {
    b["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w["code"] == code)
}

fn v3(v: &Value) -> [f64; 3] {
    [0, 1, 2].map(|k| v[k].as_f64().unwrap())
}

/// A point mass thrown from 2 m above the 45° plane at 5 m along the dip with [1.5, −0.4, 0.8]
/// m/s: h + b t − g t²/2 = 0 with b = v_z + v_x tan θ gives the first impact's time, and the
/// parabola its point and speed (to 1e-12).
#[tokio::test]
async fn a_thrown_point_mass_lands_where_the_parabola_meets_the_plane() {
    let app = common::app();
    let (th, h, s0) = (45f64.to_radians(), 2.0, 5.0);
    let v = [1.5, -0.4, 0.8];
    let b = ok(
        &app,
        &json!({"release": {"drop_height_m": h, "along_dip_m": s0, "velocity_m_s": v}}),
    )
    .await;
    let x0 = s0 * th.cos();
    let p0 = [x0, 0.0, -x0 * th.tan() + h];
    let bq = v[2] + v[0] * th.tan();
    let t = (bq + (bq * bq + 2.0 * G * h).sqrt()) / G;
    let p = [
        p0[0] + v[0] * t,
        p0[1] + v[1] * t,
        p0[2] + v[2] * t - 0.5 * G * t * t,
    ];
    let speed = (v[0] * v[0] + v[1] * v[1] + (v[2] - G * t).powi(2)).sqrt();
    let e = &b["events"][0];
    assert_eq!(e["kind"], "impact", "{e}");
    assert!(
        rel(e["time_s"].as_f64().unwrap(), t) < 1e-12,
        "{e} against t = {t}"
    );
    let q = v3(&e["position_m"]);
    for k in 0..3 {
        assert!((q[k] - p[k]).abs() < 1e-12 * 10.0, "{q:?} against {p:?}");
    }
    assert!(
        rel(e["speed_before_m_s"].as_f64().unwrap(), speed) < 1e-12,
        "{e}"
    );
    // the account opens with the thrown speed's energy
    let m = b["mass_kg"].as_f64().unwrap_or(67.5);
    let e0 = b["energy"]["total_start_j"].as_f64().unwrap();
    let v2 = v.iter().map(|c| c * c).sum::<f64>();
    let z_end = -120.0 * th.sin();
    assert!(
        rel(e0, m * (0.5 * v2 + G * (p0[2] - z_end))) < 1e-12,
        "{e0}"
    );
}

/// `velocity_m_s` down the dip is `speed_m_s`; on the floor a velocity with a normal component
/// keeps its component along the floor, with a warning.
#[tokio::test]
async fn a_velocity_down_the_dip_is_the_speed_and_on_the_floor_it_is_projected() {
    let app = common::app();
    let th = 45f64.to_radians();
    let base = ok(
        &app,
        &json!({"release": {"drop_height_m": 0, "speed_m_s": 3.0}}),
    )
    .await;
    let d = [3.0 * th.cos(), 0.0, -3.0 * th.sin()];
    let vec = ok(
        &app,
        &json!({"release": {"drop_height_m": 0, "velocity_m_s": d}}),
    )
    .await;
    let a = |b: &Value, f: &str| b["arrival"][f].as_f64().unwrap();
    for f in ["time_s", "speed_m_s", "along_dip_m"] {
        assert!(rel(a(&vec, f), a(&base, f)) < 1e-12, "{f}");
    }
    assert!(!has_warning(&vec, "release_velocity_projected"));
    // add 2 m/s along the floor's normal (s, 0, c): dropped, with a warning
    let n = [th.sin(), 0.0, th.cos()];
    let up = [d[0] + 2.0 * n[0], 0.0, d[2] + 2.0 * n[2]];
    let proj = ok(
        &app,
        &json!({"release": {"drop_height_m": 0, "velocity_m_s": up}}),
    )
    .await;
    assert!(has_warning(&proj, "release_velocity_projected"), "{proj}");
    for f in ["time_s", "speed_m_s", "along_dip_m"] {
        assert!(rel(a(&proj, f), a(&base, f)) < 1e-9, "{f}");
    }
}

/// A sphere (r = 0.15 m, μ = 0.5 ≥ (2/7) tan 45°) set down with top-spin W = 40 rad/s and no
/// speed: its contact point slips up the dip, so friction pulls it down, a₁ = g(sin θ + μ cos θ),
/// while its spin falls at 5 μ g cos θ/(2r), until v = ω r at t* = r W/(g (sin θ + 3.5 μ cos θ));
/// then it rolls at (5/7) g sin θ. At 1 s: v = a₁ t* + (5/7) g sin θ (1 − t*), within 2e-3 (the
/// DEM's spring contact, as the rolling and slipping checks of the DEM table).
#[tokio::test]
async fn a_top_spun_sphere_slips_then_rolls_as_the_closed_form_says() {
    let app = common::app();
    let (th, r, mu, w) = (45f64.to_radians(), 0.15, 0.5, 40.0);
    let body = json!({"method": "rigid_block", "rock": {"shape": "sphere", "radius_m": r},
        "face": {"friction_coefficient": mu}, "end_time_s": 1.0,
        "release": {"drop_height_m": 0, "angular_velocity_rad_s": [0, w, 0]}});
    let b = ok(&app, &body).await;
    let a1 = G * (th.sin() + mu * th.cos());
    let ts = r * w / (G * (th.sin() + 3.5 * mu * th.cos()));
    let v = a1 * ts + 5.0 / 7.0 * G * th.sin() * (1.0 - ts);
    let got = b["arrival"]["along_dip_velocity_m_s"].as_f64().unwrap();
    assert!(rel(got, v) < 2e-3, "{got} against {v} (t* = {ts})");
    let om = b["arrival"]["angular_speed_rad_s"].as_f64().unwrap();
    assert!(rel(om, v / r) < 2e-3, "{om} against {}", v / r);
    // without the spin it only rolls: a different answer
    let still = ok(
        &app,
        &json!({"method": "rigid_block", "rock": {"shape": "sphere", "radius_m": r},
            "face": {"friction_coefficient": mu}, "end_time_s": 1.0,
            "release": {"drop_height_m": 0}}),
    )
    .await;
    let roll = 5.0 / 7.0 * G * th.sin();
    let got0 = still["arrival"]["along_dip_velocity_m_s"].as_f64().unwrap();
    assert!(rel(got0, roll) < 2e-3 && rel(got, got0) > 0.2, "{got0}");
}

/// A cuboid 0.2 × 0.4 × 0.6 m given an orientation starts in it (the trajectory's first
/// sample) with its lowest point on the plane: its centre (a/2 |n_x| + c/2 |n_z|) above the
/// floor point for the identity, and (a/2 |n_x| + b/2 |n_z|) turned 90° about x.
#[tokio::test]
async fn an_oriented_block_starts_in_its_orientation_with_its_lowest_point_on_the_floor() {
    let app = common::app();
    let th = 45f64.to_radians();
    let (s, c) = th.sin_cos();
    let h = 1.0;
    let half = std::f64::consts::FRAC_1_SQRT_2;
    for (q, offset) in [
        ([1.0, 0.0, 0.0, 0.0], 0.1 * s + 0.3 * c),
        ([half, half, 0.0, 0.0], 0.1 * s + 0.2 * c),
    ] {
        let b = ok(
            &app,
            &json!({"method": "rigid_block",
                "rock": {"shape": "cuboid", "dimensions_m": [0.2, 0.4, 0.6]},
                "release": {"drop_height_m": h, "along_dip_m": 10, "orientation_wxyz": q},
                "output": {"trajectory": true, "sample_interval_s": 0.01}}),
        )
        .await;
        let tr = &b["trajectory"];
        let q0 = &tr["orientation_wxyz"][0];
        let dot: f64 = (0..4).map(|k| q0[k].as_f64().unwrap() * q[k]).sum();
        assert!((dot.abs() - 1.0).abs() < 1e-12, "{q0} against {q:?}");
        let p = v3(&tr["position_m"][0]);
        let x0 = 10.0 * c;
        let expect = [x0 + s * offset, 0.0, -x0 * th.tan() + c * offset + h];
        for k in 0..3 {
            // the static overlap (≈ 1e-6 m) is within the tolerance
            assert!((p[k] - expect[k]).abs() < 1e-5, "{p:?} against {expect:?}");
        }
    }
}

/// The release point as `position_m`: on the plane [x, y] is along_dip x / cos θ, across y.
#[tokio::test]
async fn a_plan_point_is_the_same_release_as_along_dip_and_across() {
    let app = common::app();
    let th = 45f64.to_radians();
    let a = ok(
        &app,
        &json!({"release": {"along_dip_m": 7.0, "across_m": 0.4}}),
    )
    .await;
    let b = ok(
        &app,
        &json!({"release": {"position_m": [7.0 * th.cos(), 0.4]}}),
    )
    .await;
    for f in ["time_s", "speed_m_s", "along_dip_m"] {
        let (x, y) = (
            a["arrival"][f].as_f64().unwrap(),
            b["arrival"][f].as_f64().unwrap(),
        );
        assert!(rel(y, x) < 1e-12, "{f}: {y} against {x}");
    }
}

/// Release velocity draws come from a stream of their own: degenerate draws equal to the
/// release's velocity give the ensemble without them bit for bit (the same impacts draw the
/// same e_n, e_t), and real draws change the runs.
#[tokio::test]
async fn release_draws_leave_the_restitution_draws_as_they_were() {
    let app = common::app();
    let vel = [0.5, 0.2, -0.1];
    let fixed = |d: f64| json!({"distribution": "uniform", "min": d, "max": d});
    let body = |draws: Value| {
        json!({"release": {"velocity_m_s": vel, "drop_height_m": 1.0},
            "monte_carlo": {"runs": 64, "seed": 7, "release_velocity_m_s": draws},
            "output": {"runs_csv": true}})
    };
    let plain = ok(&app, &body(Value::Null)).await;
    let same = ok(&app, &body(json!(vel.map(fixed)))).await;
    assert_eq!(plain["statistics"], same["statistics"]);
    let spread = json!([
        {"distribution": "uniform", "min": 0, "max": 2},
        {"distribution": "normal", "mean": 0, "std": 0.5},
        {"distribution": "uniform", "min": -1, "max": 0}
    ]);
    let drawn = ok(&app, &body(spread)).await;
    assert_eq!(plain["runs_csv"], same["runs_csv"]);
    assert_ne!(plain["runs_csv"], drawn["runs_csv"]);
}

/// A rigid-block ensemble over uniformly random orientations and drawn velocities: the runs
/// differ, and the same request gives the same bytes.
#[tokio::test]
async fn random_orientations_vary_the_runs_and_stay_deterministic() {
    let app = common::app();
    let body = json!({"method": "rigid_block", "face": {"length_m": 8},
        "rock": {"shape": "ellipsoid", "dimensions_m": [0.46, 0.30, 0.20]},
        "release": {"drop_height_m": 0.5},
        "monte_carlo": {"runs": 6, "seed": 3, "release_orientation": "uniform",
            "release_velocity_m_s": [{"min": 0, "max": 1}, {"min": -0.5, "max": 0.5},
                                     {"min": 0, "max": 0}]},
        "output": {"runs_csv": true, "events": false}});
    let a = ok(&app, &body).await;
    let b = ok(&app, &body).await;
    assert_eq!(a, b);
    let csv = a["runs_csv"].as_str().unwrap();
    let times: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap())
        .collect();
    let mut distinct = times.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert_eq!(distinct.len(), times.len(), "{csv}");
}

/// The ellipsoid block: its mass is ρ π a b c / 6 in both methods, its extents within 2 % of
/// the axes, its principal moments within 3 % of the solid ellipsoid's m (b² + c²)/20, ….
#[tokio::test]
async fn an_ellipsoid_has_the_ellipsoids_mass_and_nearly_its_inertia() {
    let app = common::app();
    let d = [0.46, 0.30, 0.20];
    let rho = 2700.0;
    let m = rho * std::f64::consts::PI / 6.0 * d[0] * d[1] * d[2];
    let rock = json!({"shape": "ellipsoid", "dimensions_m": d, "density_kg_m3": rho});
    let rb = ok(
        &app,
        &json!({"method": "rigid_block", "rock": rock, "end_time_s": 0.05}),
    )
    .await;
    let got = rb["rigid_block"]["mass_kg"].as_f64().unwrap();
    assert!(rel(got, m) < 1e-12, "{got} against {m}");
    let moments: Vec<f64> = rb["rigid_block"]["principal_inertia_kg_m2"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let mut exact = [
        m * (d[1] * d[1] + d[2] * d[2]) / 20.0,
        m * (d[0] * d[0] + d[2] * d[2]) / 20.0,
        m * (d[0] * d[0] + d[1] * d[1]) / 20.0,
    ];
    exact.sort_by(f64::total_cmp);
    for (g, e) in moments.iter().zip(exact) {
        assert!(rel(*g, e) < 0.03, "{moments:?} against {exact:?}");
    }
    let lm = ok(&app, &json!({"rock": rock, "end_time_s": 0.05})).await;
    let e0 = lm["energy"]["total_start_j"].as_f64().unwrap();
    let th = 45f64.to_radians();
    let pe = m * G * (3.27 + 120.0 * th.sin());
    assert!(rel(e0, pe) < 1e-12, "{e0} against {pe}");
}

/// Bad releases are 422 naming the field.
#[tokio::test]
async fn bad_release_states_are_refused_naming_the_field() {
    let app = common::app();
    for (body, field) in [
        (
            json!({"method": "rigid_block", "release": {"orientation_wxyz": [1, 0, 0, 0.1]}}),
            "/release/orientation_wxyz",
        ),
        (
            json!({"release": {"orientation_wxyz": [1, 0, 0, 0]}}),
            "/release/orientation_wxyz",
        ),
        (
            json!({"release": {"angular_velocity_rad_s": [0, 1, 0]}}),
            "/release/angular_velocity_rad_s",
        ),
        (
            json!({"release": {"velocity_m_s": [1, 0, 0], "speed_m_s": 2}}),
            "/release/speed_m_s",
        ),
        (
            json!({"release": {"velocity_m_s": [1, 0, 2000]}}),
            "/release/velocity_m_s/2",
        ),
        (
            json!({"release": {"position_m": [1, 0], "along_dip_m": 2}}),
            "/release/along_dip_m",
        ),
        (
            json!({"release": {"position_m": [-1, 0]}}),
            "/release/position_m",
        ),
        (
            json!({"release": {"position_m": [200, 0]}}),
            "/release/position_m",
        ),
        (
            json!({"monte_carlo": {"release_orientation": "uniform"}}),
            "/monte_carlo/release_orientation",
        ),
        (
            json!({"method": "rigid_block", "release": {"orientation_wxyz": [1, 0, 0, 0]},
                "monte_carlo": {"release_orientation": "uniform"}}),
            "/monte_carlo/release_orientation",
        ),
        (
            json!({"monte_carlo": {"release_velocity_m_s": [{"min": 0, "max": 1},
                {"min": 0, "max": 1}, {"min": 0, "max": 5000}]}}),
            "/monte_carlo/release_velocity_m_s/2/max",
        ),
        (
            json!({"rock": {"shape": "ellipsoid"}}),
            "/rock/dimensions_m",
        ),
    ] {
        let r = post(&app, "/v1/migration", &body).await;
        let p = assert_problem(&r, 422, "invalid_input");
        let fields: Vec<&str> = p["errors"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["field"].as_str().unwrap())
            .collect();
        assert!(fields.contains(&field), "{body}: {fields:?}");
    }
}

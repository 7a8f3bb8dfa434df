//! The DEM community's impact benchmarks, Chung & Ooi (2011) tests 2 and 4, through the HTTP API
//! (VALIDATION.md states the setup, our figures, the references and the deviations).
//!
//! The inputs and the digitised reference curves are read at run time from
//! `../shared/validation/chung_ooi/` (`params.json` and the CSVs); nothing is copied here.
//!
//! * Test 2, an elastic sphere on a rigid plane, through `POST /v1/impact` (`hertz_point`, the
//!   rock-only modulus, i.e. a rigid target, on the widest column the service takes, 10 m).
//! * Test 4, oblique impacts at 5–85° through the rigid block (`POST /v1/migration`, a sphere,
//!   `contact_model: hertz`, a floor of the sphere's own material, μ = 0.092, e_n = 0.98 through
//!   the dashpot's β derived here from the Hertz dashpot's equation of motion).

mod common;

use std::path::PathBuf;

use serde_json::{Value, json};

use gangue::config::Config;

/// Where the benchmark's files live.
fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/validation/chung_ooi")
}

/// `params.json`.
fn params() -> Value {
    let path = dir().join("params.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// The rows of a CSV file as (header → field) pairs, quotes stripped.
fn csv(name: &str) -> Vec<Vec<(String, String)>> {
    let path = dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|h| h.trim().to_string())
        .collect();
    lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(
                    l.split(',')
                        .map(|f| f.trim().trim_matches('\'').to_string()),
                )
                .collect()
        })
        .collect()
}

/// Column `col` of a CSV row as a number.
fn num(row: &[(String, String)], col: &str) -> f64 {
    row.iter()
        .find(|(h, _)| h == col)
        .unwrap_or_else(|| panic!("no column {col}"))
        .1
        .parse()
        .unwrap()
}

/// (x, y) pairs of two columns of a CSV, optionally only the rows whose `source` is `source`.
fn curve(name: &str, x: &str, y: &str, source: Option<&str>) -> Vec<(f64, f64)> {
    csv(name)
        .iter()
        .filter(|r| source.is_none_or(|s| r.iter().any(|(h, v)| h == "source" && v == s)))
        .map(|r| (num(r, x), num(r, y)))
        .collect()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// (4/5)·B(2/5, 1/2): t_c = this × δmax / v for a Hertz impact (physics.md §A.7).
const HERTZ_DURATION: f64 = 2.943_237_2;

/// Largest force and the time it returns to zero of the digitised test 2 force–time curve
/// (the zero by linear interpolation across the last sign change), (N, s).
fn digitised_peak_and_zero() -> (f64, f64) {
    let c = curve(
        "test2_force_vs_time.csv",
        "time_us",
        "normal_force_kN",
        None,
    );
    let peak = c.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let k = c
        .windows(2)
        .rposition(|w| w[0].1 > 0.0 && w[1].1 <= 0.0)
        .expect("the force returns to zero");
    let (a, b) = (c[k], c[k + 1]);
    let t0 = a.0 + (b.0 - a.0) * a.1 / (a.1 - b.1);
    (peak * 1e3, t0 * 1e-6)
}

#[tokio::test]
async fn sphere_on_a_rigid_plane_peaks_and_parts_as_chung_ooi_test_2() {
    let p = &params()["test2_elastic_normal_impact_sphere_rigid_plane"]["aluminium_alloy"];
    let (r, rho, e, nu, v) = (
        f(&p["radius_m"]),
        f(&p["density_kg_m3"]),
        f(&p["elastic_modulus_pa"]),
        f(&p["poisson_ratio"]),
        f(&p["velocity_m_s"]),
    );
    let body = json!({
        "velocity_m_s": v,
        "rock": {"shape": "sphere", "radius_m": r, "density_kg_m3": rho,
                 "elastic_modulus_pa": e, "poisson_ratio": nu},
        // the widest column the service takes: B/A = 1 + r/R = 1.01, 0.1 % from a flat
        "column": {"contact_radius_m": 10.0},
        // the rock-only modulus E/(1 − ν²): a rigid target
        "contact": {"law": "hertz_point", "effective_modulus": "paper"},
        "output": {"curve_points": 2001}
    });
    let reply = common::post(&common::app(), "/v1/impact", &body).await;
    assert_eq!(
        reply.status,
        200,
        "{}",
        String::from_utf8_lossy(&reply.body)
    );
    let out = reply.json();
    let (fmax, tc) = (f(&out["max_force_n"]), f(&out["contact_duration_s"]));

    // closed form for a sphere on a rigid flat (README of the benchmark)
    let estar = e / (1.0 - nu * nu);
    let m = rho * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let dmax = (15.0 * m * v * v / (16.0 * estar * r.sqrt())).powf(0.4);
    let f_closed = 4.0 / 3.0 * estar * r.sqrt() * dmax.powf(1.5);
    let t_closed = HERTZ_DURATION * dmax / v;
    let (f_dig, t_dig) = digitised_peak_and_zero();

    // the force–overlap curve at the digitised overlaps (up to δmax): against the Hertz law on a
    // flat point by point, and against the digitised curve by Kratos' measure (for information:
    // the digitised points themselves lie 1.3 % from the Hertz law by that measure)
    let curve_out = &out["curve"];
    let (d, p): (Vec<f64>, Vec<f64>) = (
        curve_out["deformation_m"]
            .as_array()
            .unwrap()
            .iter()
            .map(f)
            .collect(),
        curve_out["force_n"]
            .as_array()
            .unwrap()
            .iter()
            .map(f)
            .collect(),
    );
    let (mut dev, mut size) = (0.0, 0.0);
    for (delta_um, force_kn) in curve(
        "test2_force_vs_overlap.csv",
        "overlap_um",
        "normal_force_kN",
        None,
    ) {
        let delta = delta_um * 1e-6;
        if delta <= 0.0 || delta > d[d.len() - 1] {
            continue;
        }
        let k = d.partition_point(|x| *x < delta).max(1);
        let ours = p[k - 1] + (delta - d[k - 1]) * (p[k] - p[k - 1]) / (d[k] - d[k - 1]);
        let hertz = 4.0 / 3.0 * estar * r.sqrt() * delta.powf(1.5);
        assert!(
            (ours / hertz - 1.0).abs() < 5e-3,
            "P({delta:.3e} m) = {ours} N against the Hertz law's {hertz} N"
        );
        dev += (ours - force_kn * 1e3).abs();
        size += force_kn * 1e3;
    }
    eprintln!(
        "test 2 force–overlap curve against the digitised one: Σ|ours − ref|/Σ|ref| = {:.2} %",
        100.0 * dev / size
    );
    for (what, ours, reference, tol) in [
        ("Fmax against the closed form", fmax, f_closed, 5e-3),
        ("Fmax against the digitised curve", fmax, f_dig, 5e-3),
        ("t_c against the closed form", tc, t_closed, 1e-2),
        ("t_c against the digitised curve", tc, t_dig, 1e-2),
    ] {
        let rel = ours / reference - 1.0;
        eprintln!(
            "test 2 {what}: {ours:.6e} against {reference:.6e} ({:+.3} %)",
            100.0 * rel
        );
        assert!(
            rel.abs() <= tol,
            "{what}: {ours:.6e} against {reference:.6e}, {:+.3} % (allowed {} %)",
            100.0 * rel,
            100.0 * tol
        );
    }
}

/// Test 4's material and impact (params.json).
#[derive(Debug, Clone, Copy)]
struct Test4 {
    radius: f64,
    density: f64,
    modulus: f64,
    poisson: f64,
    mu: f64,
    e_n: f64,
    speed: f64,
}

fn test4() -> Test4 {
    let p = &params()["test4_oblique_impact_sphere_rigid_plane"]["aluminium_oxide"];
    Test4 {
        // The service's smallest sphere (5 mm; the benchmark's is 2.5 mm): without gravity the
        // Hertz–Mindlin ratios below do not depend on the size.
        radius: 0.005f64.max(f(&p["radius_m"])),
        density: f(&p["density_kg_m3"]),
        modulus: f(&p["elastic_modulus_pa"]),
        poisson: f(&p["poisson_ratio"]),
        mu: f(&p["friction_coefficient"]),
        e_n: f(&p["normal_restitution"]),
        speed: f(&p["speed_m_s"]),
    }
}

/// Restitution of the service's Hertz dashpot, Fₙ = max(0, k U^{3/2} + 2β√(m k_t) U̇) with
/// k_t = (3/2) k U^{1/2} (physics.md §C.3): in units where m = k = v = 1 the overlap obeys
/// ÿ = −max(0, y^{3/2} + 2β √(3/2) y^{1/4} ẏ) (the ratio does not depend on m, k or v). RK4 at
/// 1e-4 of a contact time of about 3.2, until the force returns to zero.
fn hertz_dashpot_restitution(beta: f64) -> f64 {
    let c = 2.0 * beta * 1.5f64.sqrt();
    let force = |y: f64, yd: f64| {
        if y <= 0.0 {
            0.0
        } else {
            (y * y.sqrt() + c * y.sqrt().sqrt() * yd).max(0.0)
        }
    };
    let h = 1e-4;
    let (mut y, mut yd) = (0.0f64, 1.0f64);
    let mut t = 0.0;
    loop {
        let a1 = -force(y, yd);
        let (y2, v2) = (y + 0.5 * h * yd, yd + 0.5 * h * a1);
        let a2 = -force(y2, v2);
        let (y3, v3) = (y + 0.5 * h * v2, yd + 0.5 * h * a2);
        let a3 = -force(y3, v3);
        let (y4, v4) = (y + h * v3, yd + h * a3);
        let a4 = -force(y4, v4);
        y += h / 6.0 * (yd + 2.0 * v2 + 2.0 * v3 + v4);
        yd += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
        t += h;
        if t > 0.5 && force(y, yd) <= 0.0 {
            return -yd;
        }
    }
}

/// β of the service's Hertz dashpot giving the restitution `e` (bisection, 1e-9).
fn beta_for_restitution(e: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 0.5);
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if hertz_dashpot_restitution(mid) > e {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The rebound of one oblique impact, measured on the sphere right after its single contact.
#[derive(Debug, Clone, Copy)]
struct Rebound {
    /// Incident angle from the normal, degrees.
    theta: f64,
    /// v_n′/v_n of the centre.
    e_n: f64,
    /// v_t′/v_t of the centre.
    e_t: f64,
    /// ω r / v, signed as the reference (negative: the spin slows the contact point).
    omega_r_over_v: f64,
    /// Contact-patch rebound angle atan((v_t′ + ω r)/v_n′), degrees.
    rebound_deg: f64,
}

/// Gravity of the test 4 runs, m/s² (the default; g t_c/v ≈ 4e-5).
const G: f64 = 9.81;
/// Time step of the test 4 runs, s: about 1 600 steps per contact (1e-9 s moves the ratios by
/// less than 5e-4).
const DT: f64 = 1e-8;

/// The service with a step-count limit that admits the test 4 runs: the estimate counts the
/// 0.4 s fall at Δt = 1e-8 s (4e7 steps) although the fall is flown in closed form and about
/// 3 200 steps are taken.
fn test4_app() -> axum::Router {
    gangue::app(Config {
        max_rigid_steps: 1e8,
        ..Config::default()
    })
}

/// Drops the sphere onto a plane of dip min(θ, 80°) (above 80°, the face's steepest dip, a
/// down-dip release speed turns the incidence to θ; below 5°, its shallowest, the run is at 5°)
/// so that it meets the floor at `speed` and θ from the normal, and measures the rebound at
/// the end time, two Hertz contact times after the touch.
async fn rebound(app: &axum::Router, t4: &Test4, beta: f64, theta: f64) -> Rebound {
    let th = theta.max(5.0).to_radians();
    let dip = theta.clamp(5.0, 80.0).to_radians();
    let v = t4.speed;
    // the fall gives the normal speed (g's normal component over the fall); the release speed
    // the rest of the tangential one
    let vz = v * th.cos() / dip.cos();
    let s = (v * th.sin() - vz * dip.sin()).max(0.0);
    let drop = vz * vz / (2.0 * G);
    let t_touch = vz / G;
    // the Hertz contact time with the two-body E* of sphere and floor (the same material)
    let estar = t4.modulus / (2.0 * (1.0 - t4.poisson * t4.poisson));
    let m = t4.density * 4.0 / 3.0 * std::f64::consts::PI * t4.radius.powi(3);
    let dmax = (15.0 * m * v * v / (16.0 * estar * t4.radius.sqrt())).powf(0.4);
    let tc = HERTZ_DURATION * dmax / v;
    let body = json!({
        "method": "rigid_block",
        "gravity_m_s2": G,
        "face": {
            "dip_deg": dip.to_degrees(), "length_m": 10.0,
            "friction_coefficient": t4.mu, "critical_damping_ratio": beta,
            "contact_model": "hertz",
            "floor_material": {"elastic_modulus_pa": t4.modulus, "poisson_ratio": t4.poisson}
        },
        "rock": {"shape": "sphere", "radius_m": t4.radius, "density_kg_m3": t4.density,
                 "elastic_modulus_pa": t4.modulus, "poisson_ratio": t4.poisson},
        "release": {"drop_height_m": drop, "along_dip_m": 1.0, "speed_m_s": s},
        "rigid_block": {"time_step_s": DT},
        "end_time_s": t_touch + 2.0 * tc,
        "output": {"trajectory": true, "sample_interval_s": 100.0, "events": true}
    });
    let reply = common::post(app, "/v1/migration", &body).await;
    assert_eq!(
        reply.status,
        200,
        "θ = {theta}: {}",
        String::from_utf8_lossy(&reply.body)
    );
    let out = reply.json();
    assert_eq!(out["impact_count"], 1, "θ = {theta}: one contact");
    assert_eq!(out["arrival"]["stop_reason"], "end_time");
    assert_eq!(
        out["arrival"]["phase"], "flight",
        "θ = {theta}: the contact is over"
    );
    let tr = &out["trajectory"];
    let last = |k: &str| -> [f64; 3] {
        let a = tr[k].as_array().unwrap().last().unwrap();
        [f(&a[0]), f(&a[1]), f(&a[2])]
    };
    let (vel, w) = (last("velocity_m_s"), last("angular_velocity_rad_s"));
    // the plane z = −x tan θ_d: normal (sin, 0, cos), down-dip (cos, 0, −sin)
    let n = [dip.sin(), 0.0, dip.cos()];
    let t = [dip.cos(), 0.0, -dip.sin()];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (vt, vn) = (dot(vel, t), dot(vel, n));
    // the contact point's velocity from the spin: ω × (−r n), along the down-dip direction
    let arm = [-t4.radius * n[0], -t4.radius * n[1], -t4.radius * n[2]];
    let spin = [
        w[1] * arm[2] - w[2] * arm[1],
        w[2] * arm[0] - w[0] * arm[2],
        w[0] * arm[1] - w[1] * arm[0],
    ];
    let wr = dot(spin, t);
    Rebound {
        theta: th.to_degrees(),
        e_n: vn / (v * th.cos()),
        e_t: vt / (v * th.sin()),
        omega_r_over_v: wr / v,
        rebound_deg: (vt + wr).atan2(vn).to_degrees(),
    }
}

#[test]
fn hertz_dashpot_restitution_is_one_undamped_and_falls_with_beta() {
    // the undamped Hertz impact is elastic; the derived β is small and gives e back
    assert!((hertz_dashpot_restitution(0.0) - 1.0).abs() < 1e-9);
    let beta = beta_for_restitution(0.98);
    assert!((hertz_dashpot_restitution(beta) - 0.98).abs() < 1e-6);
    assert!(
        (0.005..0.007).contains(&beta),
        "β = {beta} for e_n = 0.98 (the linear law's would be 0.0064)"
    );
}

#[tokio::test]
async fn hertz_dashpot_beta_gives_the_benchmark_normal_restitution() {
    let t4 = test4();
    let beta = beta_for_restitution(t4.e_n);
    let app = test4_app();
    for theta in [5.0, 45.0, 85.0] {
        let r = rebound(&app, &t4, beta, theta).await;
        eprintln!("θ = {theta}: β = {beta:.6}, e_n = {:.6}", r.e_n);
        assert!(
            (r.e_n / t4.e_n - 1.0).abs() < 1e-3,
            "θ = {theta}: e_n = {} against {}",
            r.e_n,
            t4.e_n
        );
    }
}

#[tokio::test]
async fn gross_sliding_rebounds_follow_the_rigid_body_closed_form() {
    // Above ≈ 32.5° (tan θ > 3.5 μ (1 + e_n)) the sphere slides throughout the contact:
    // e_t = 1 − μ(1+e_n) cot θ, ω r/v = −2.5 μ(1+e_n) cos θ and the rebound angle
    // atan((tan θ − 3.5 μ(1+e_n))/e_n) hold exactly for a solid sphere whatever the compliance.
    let t4 = test4();
    let beta = beta_for_restitution(t4.e_n);
    let app = test4_app();
    let k = t4.mu * (1.0 + t4.e_n);
    for theta in [35.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0] {
        let r = rebound(&app, &t4, beta, theta).await;
        let th = theta.to_radians();
        let e_t = 1.0 - k / th.tan();
        let wr = -2.5 * k * th.cos();
        let reb = ((th.tan() - 3.5 * k) / t4.e_n).atan().to_degrees();
        eprintln!(
            "θ = {theta}: e_t {:.5} ({e_t:.5}), ωr/v {:.5} ({wr:.5}), rebound {:.4}° ({reb:.4}°)",
            r.e_t, r.omega_r_over_v, r.rebound_deg
        );
        assert!(
            (r.e_t / e_t - 1.0).abs() < 1e-3,
            "θ = {theta}: e_t {}",
            r.e_t
        );
        assert!(
            (r.omega_r_over_v / wr - 1.0).abs() < 2e-3,
            "θ = {theta}: ωr/v {}",
            r.omega_r_over_v
        );
        // the rebound angle crosses zero near 32.5°: compared in degrees
        assert!(
            (r.rebound_deg - reb).abs() < 0.05,
            "θ = {theta}: rebound {}°",
            r.rebound_deg
        );
    }
}

/// One reference curve of test 4.
struct Reference {
    name: &'static str,
    points: Vec<(f64, f64)>,
    /// Kratos' gate on Σ|ours − ref| / Σ|ref| over the curve (params.json).
    curve_gate: f64,
    value: fn(&Rebound) -> f64,
}

/// The value of a reference curve at `theta` (linear between its points): the runs below 5°,
/// the face's shallowest dip, are at 5° and compared with the curve there.
fn at(points: &[(f64, f64)], theta: f64) -> f64 {
    let k = points
        .windows(2)
        .position(|w| w[0].0 <= theta && theta <= w[1].0)
        .unwrap_or_else(|| {
            if theta < points[0].0 {
                0
            } else {
                points.len() - 2
            }
        });
    let ((a, ya), (b, yb)) = (points[k], points[k + 1]);
    ya + (theta - a) * (yb - ya) / (b - a)
}

/// Angles at which the incremental Hertz–Mindlin shear spring misses the digitised DEM
/// reference by more than 2.5 %, with the largest relative deviation asserted there
/// (VALIDATION.md explains each: the stick regime's shear-spring law below 25°, rebound angles
/// near their zero crossings, and ωr/v at 80–85° where the reference departs from its own
/// closed form, which we meet to 1e-4).
const KNOWN_MISSES: &[(&str, f64, f64)] = &[
    ("tangential restitution", 5.168, 0.065),
    ("tangential restitution", 10.158, 0.035),
    ("omega r / v", 4.951, 0.70),
    ("omega r / v", 10.079, 0.08),
    ("omega r / v", 80.059, 0.035),
    ("omega r / v", 85.030, 0.03),
    ("rebound angle", 4.901, 0.12),
    ("rebound angle", 9.959, 1.05),
    ("rebound angle", 14.935, 0.17),
    ("rebound angle", 19.988, 0.035),
    ("rebound angle", 24.958, 0.10),
    ("rebound angle", 34.962, 0.06),
];

#[tokio::test]
async fn tangential_restitution_spin_and_rebound_angle_follow_chung_ooi_test_4() {
    let t4 = test4();
    let beta = beta_for_restitution(t4.e_n);
    let gates = &params()["test4_oblique_impact_sphere_rigid_plane"]["kratos_test_tolerances"];
    let refs = [
        Reference {
            name: "tangential restitution",
            points: curve(
                "test4_tangential_restitution.csv",
                "incident_angle_deg",
                "tangential_restitution",
                None,
            ),
            curve_gate: f(&gates["tangential_restitution_rel_error"]),
            value: |r| r.e_t,
        },
        Reference {
            name: "omega r / v",
            points: curve(
                "test4_angular_velocity.csv",
                "incident_angle_deg",
                "omega_r_over_v_in",
                None,
            ),
            curve_gate: f(&gates["angular_velocity_rel_error"]),
            value: |r| r.omega_r_over_v,
        },
        Reference {
            name: "rebound angle",
            points: curve(
                "test4_rebound_angle.csv",
                "incident_angle_deg",
                "contact_patch_rebound_angle_deg",
                Some("dem_reference_al_oxide"),
            ),
            curve_gate: f(&gates["rebound_angle_rel_error"]),
            value: |r| r.rebound_deg,
        },
    ];
    let app = test4_app();
    let mut failures = Vec::new();
    for reference in &refs {
        assert_eq!(reference.points.len(), 13, "{}", reference.name);
        let (mut dev, mut size) = (0.0, 0.0);
        for &(theta, y) in &reference.points {
            let r = rebound(&app, &t4, beta, theta).await;
            // the reference where the run is (5° for the points just below it)
            let y_ref = if r.theta == theta {
                y
            } else {
                at(&reference.points, r.theta)
            };
            let ours = (reference.value)(&r);
            let rel = (ours - y_ref) / y_ref.abs();
            dev += (ours - y_ref).abs();
            size += y_ref.abs();
            let known = KNOWN_MISSES
                .iter()
                .find(|(n, a, _)| *n == reference.name && (a - theta).abs() < 1e-3);
            eprintln!(
                "{} at {theta:.3}° (run at {:.3}°): ours {ours:.5}, reference {y_ref:.5}, {:+.2} %{}",
                reference.name,
                r.theta,
                100.0 * rel,
                if known.is_some() { " (known miss)" } else { "" }
            );
            match known {
                None if rel.abs() > 0.025 => failures.push(format!(
                    "{} at {theta}°: {ours:.5} against {y_ref:.5} ({:+.2} %)",
                    reference.name,
                    100.0 * rel
                )),
                Some((_, _, bound)) if rel.abs() > *bound => failures.push(format!(
                    "{} at {theta}°: {:+.2} %, beyond the known miss's {} %",
                    reference.name,
                    100.0 * rel,
                    100.0 * bound
                )),
                Some(_) if rel.abs() <= 0.025 => failures.push(format!(
                    "{} at {theta}°: now within 2.5 % ({:+.2} %): drop it from KNOWN_MISSES",
                    reference.name,
                    100.0 * rel
                )),
                _ => {}
            }
        }
        let curve_error = dev / size;
        eprintln!(
            "{}: Σ|ours − ref|/Σ|ref| = {:.3} % (Kratos gates its DEM at {:.1} %)",
            reference.name,
            100.0 * curve_error,
            100.0 * reference.curve_gate
        );
        if curve_error > reference.curve_gate.min(0.025) {
            failures.push(format!(
                "{}: curve error {:.3} % above {:.1} %",
                reference.name,
                100.0 * curve_error,
                100.0 * reference.curve_gate
            ));
        }
    }
    // Kharaz et al.'s measured rebound angles, for information (VALIDATION.md): the runs at
    // the measured angles from 5° up
    let measured = curve(
        "test4_rebound_angle.csv",
        "incident_angle_deg",
        "contact_patch_rebound_angle_deg",
        Some("experiment_kharaz_2001"),
    );
    for &(theta, y) in measured.iter().filter(|p| p.0 >= 5.0) {
        let r = rebound(&app, &t4, beta, theta).await;
        eprintln!(
            "measured rebound angle at {theta:.3}°: ours {:.3}°, measured {y:.3}°",
            r.rebound_deg
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A sphere dropped straight onto the plane (friction 0, no damping): its peak contact force is
/// the Hertz law's with the two-body E* of rock and floor, at the overlap where the spring holds
/// the normal kinetic energy and gravity's work, (2/5) k δ^{5/2} = ½ m vₙ² + m g cos θ δ.
async fn peak_force_of_a_drop(floor: Option<(f64, f64)>) -> (f64, f64) {
    let (r, rho, e, nu, v): (f64, f64, f64, f64, f64) = (0.05, 2500.0, 5e9, 0.28, 2.0);
    let dip = 5.0f64.to_radians();
    let mut face = json!({"dip_deg": 5.0, "length_m": 10.0, "friction_coefficient": 0.0,
                          "critical_damping_ratio": 0.0, "contact_model": "hertz"});
    if let Some((ef, nf)) = floor {
        face["floor_material"] = json!({"elastic_modulus_pa": ef, "poisson_ratio": nf});
    }
    let body = json!({
        "method": "rigid_block",
        "face": face,
        "rock": {"shape": "sphere", "radius_m": r, "density_kg_m3": rho,
                 "elastic_modulus_pa": e, "poisson_ratio": nu},
        "release": {"drop_height_m": v * v / (2.0 * G), "along_dip_m": 1.0},
        "rigid_block": {"time_step_s": 1e-7},
        "end_time_s": v / G + 0.01,
        "output": {"events": true}
    });
    let reply = common::post(&test4_app(), "/v1/migration", &body).await;
    assert_eq!(
        reply.status,
        200,
        "{}",
        String::from_utf8_lossy(&reply.body)
    );
    let out = reply.json();
    let impact = out["events"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "impact")
        .expect("an impact event")
        .clone();
    let (ef, nf) = floor.unwrap_or((4.38e9, 0.3));
    let estar = 1.0 / ((1.0 - nu * nu) / e + (1.0 - nf * nf) / ef);
    let m = rho * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let vn = v * dip.cos();
    let k = 4.0 / 3.0 * estar * r.sqrt();
    let excess = |d: f64| 0.4 * k * d * d * d.sqrt() - 0.5 * m * vn * vn - m * G * dip.cos() * d;
    let (mut lo, mut hi) = (0.0, r);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if excess(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let closed = k * hi * hi.sqrt();
    (f(&impact["peak_contact_force_n"]), closed)
}

#[tokio::test]
async fn floor_material_sets_the_hertz_peak_force_of_a_drop() {
    for floor in [
        None,
        Some((4.38e9, 0.3)),
        Some((200e9, 0.3)),
        Some((1e7, 0.45)),
    ] {
        let (peak, closed) = peak_force_of_a_drop(floor).await;
        eprintln!("floor {floor:?}: peak {peak:.6e} N, closed form {closed:.6e} N");
        assert!(
            (peak / closed - 1.0).abs() < 5e-3,
            "floor {floor:?}: peak {peak} N against {closed} N"
        );
    }
}

#[tokio::test]
async fn floor_material_given_as_the_default_answers_bit_identically() {
    let body = |floor: Option<Value>| {
        let mut b = json!({"method": "rigid_block", "face": {"contact_model": "hertz"},
                           "rock": {"shape": "sphere", "radius_m": 0.15},
                           "end_time_s": 1.0, "output": {"trajectory": true}});
        if let Some(m) = floor {
            b["face"]["floor_material"] = m;
        }
        b
    };
    let app = common::app();
    let plain = common::post(&app, "/v1/migration", &body(None)).await;
    let given = common::post(
        &app,
        "/v1/migration",
        &body(Some(
            json!({"elastic_modulus_pa": 4.38e9, "poisson_ratio": 0.3}),
        )),
    )
    .await;
    assert_eq!(
        plain.status,
        200,
        "{}",
        String::from_utf8_lossy(&plain.body)
    );
    assert_eq!(given.status, 200);
    let (mut a, mut b) = (plain.json(), given.json());
    assert!(a["inputs"]["face"].get("floor_material").is_none());
    assert_eq!(
        b["inputs"]["face"]["floor_material"]["elastic_modulus_pa"],
        4.38e9
    );
    a.as_object_mut().unwrap().remove("inputs");
    b.as_object_mut().unwrap().remove("inputs");
    assert_eq!(a, b);
}

#[tokio::test]
async fn floor_material_out_of_range_is_422_naming_the_field() {
    let app = common::app();
    for (material, pointer) in [
        (
            json!({"elastic_modulus_pa": 1e6, "poisson_ratio": 0.3}),
            "/face/floor_material/elastic_modulus_pa",
        ),
        (
            json!({"elastic_modulus_pa": 1e13, "poisson_ratio": 0.3}),
            "/face/floor_material/elastic_modulus_pa",
        ),
        (
            json!({"elastic_modulus_pa": 4.38e9, "poisson_ratio": 0.5}),
            "/face/floor_material/poisson_ratio",
        ),
        (
            json!({"elastic_modulus_pa": 4.38e9, "poisson_ratio": -0.1}),
            "/face/floor_material/poisson_ratio",
        ),
        (
            json!({"elastic_modulus_pa": 4.38e9}),
            "/face/floor_material",
        ),
    ] {
        let body = json!({"method": "rigid_block",
                          "face": {"contact_model": "hertz", "floor_material": material}});
        let reply = common::post(&app, "/v1/migration", &body).await;
        assert_eq!(reply.status, 422, "{material}");
        assert!(
            reply.content_type().starts_with("application/problem+json"),
            "{}",
            reply.content_type()
        );
        let text = String::from_utf8_lossy(&reply.body).to_string();
        assert!(text.contains(pointer), "{material}: {text}");
    }
}

#[tokio::test]
async fn a_hertz_contact_too_soft_for_the_block_is_422_naming_the_softer_body() {
    // A 1 m cube (2.5 t) on its 0.02 m corners: on a 1e7 Pa floor it would sink 16 mm, more than
    // 1 % of its side; the floor is the soft body. On a stiff floor a 1e7 Pa rock is.
    let app = common::app();
    for (floor, rock_modulus, pointer) in [
        (1e7, 5e9, "/face/floor_material/elastic_modulus_pa"),
        (1e12, 1e7, "/rock/elastic_modulus_pa"),
    ] {
        let body = json!({
            "method": "rigid_block",
            "face": {"contact_model": "hertz",
                     "floor_material": {"elastic_modulus_pa": floor, "poisson_ratio": 0.3}},
            "rock": {"side_length_m": 1.0, "elastic_modulus_pa": rock_modulus}
        });
        let reply = common::post(&app, "/v1/migration", &body).await;
        assert_eq!(
            reply.status,
            422,
            "{}",
            String::from_utf8_lossy(&reply.body)
        );
        let p = reply.json();
        assert_eq!(p["errors"][0]["field"], pointer, "{p}");
        assert!(p["detail"].as_str().unwrap().contains("too soft"), "{p}");
    }
}

//! Lumped-mass migration against physics.md §C.1–C.2: the verification cases P09, P10, P11, the
//! 50-digit reference (`kind: etm`), closed forms and plane-equivalent grid and contour floors.

use gangue::physics::Control;
use gangue::physics::migration::{
    ContourLine, Distribution, EventKind, FloorSpec, MigrationCase, MigrationResult, MonteCarlo,
    Motion, Phase, StopReason, run,
};
use serde_json::Value;

/// Directory of the shared specification files: `GANGUE_SHARED`, else `../shared` beside the crate.
fn shared_dir() -> std::path::PathBuf {
    std::env::var_os("GANGUE_SHARED")
        .map(Into::into)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared"))
}

fn cases() -> Value {
    let path = shared_dir().join("verification/cases.json");
    serde_json::from_str(&std::fs::read_to_string(&path).expect("cases.json")).unwrap()
}

fn case_by_id(id: &str) -> Value {
    cases()["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["id"] == id)
        .cloned()
        .unwrap_or_else(|| panic!("no case {id}"))
}

fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}

fn solve(c: &MigrationCase) -> MigrationResult {
    run(c, &Control::unlimited()).unwrap()
}

/// Reads a response pointer of api.md from a result (the fields P10/P11 use).
fn pointer(r: &MigrationResult, p: &str) -> f64 {
    let st = r.statistics.as_ref();
    match p {
        "/arrival/time_s" => r.arrival.time,
        "/arrival/speed_m_s" => r.arrival.speed,
        "/slide_start_along_dip_m" => r.slide_start_along_dip.unwrap(),
        "/impact_count" => r.impact_count as f64,
        "/energy/impacts_j" => r.energy.impacts,
        "/energy/friction_j" => r.energy.friction,
        "/energy/transition_j" => r.energy.transition,
        "/arrival/kinetic_energy_j" => r.arrival.kinetic_energy,
        "/energy/residual_j" => r.energy.residual,
        "/statistics/speed_m_s/mean" => st.unwrap().speed.as_ref().unwrap().mean,
        "/statistics/speed_m_s/std" => st.unwrap().speed.as_ref().unwrap().std.unwrap(),
        "/statistics/time_s/mean" => st.unwrap().time.as_ref().unwrap().mean,
        "/statistics/impact_count/mean" => st.unwrap().impact_count.mean,
        _ => panic!("pointer {p} not mapped"),
    }
}

fn check_expected(case: &Value, r: &MigrationResult) {
    for (p, want) in case["expected"].as_object().unwrap() {
        let got = pointer(r, p);
        let want = want.as_f64().unwrap();
        match &case["tolerance"][p] {
            Value::String(s) if s == "exact" => assert_eq!(got, want, "{p}"),
            t => {
                let tol = t["abs"].as_f64().unwrap() + t["rel"].as_f64().unwrap() * want.abs();
                assert!(
                    (got - want).abs() <= tol,
                    "{p}: got {got}, want {want} ± {tol}"
                );
            }
        }
    }
}

/// P10: the deterministic ETM of physics.md §C.2 with every default, to 1e-9.
#[test]
fn p10_etm_deterministic() {
    let c = case_by_id("P10_etm_deterministic");
    let r = solve(&MigrationCase::default());
    check_expected(&c, &r);
    assert_eq!(r.arrival.phase, Phase::Slide);
    assert_eq!(r.arrival.stop_reason, StopReason::LowerEnd);
    assert!(rel(r.energy.total_start, 58352.72) < 1e-6);
    assert!(rel(r.arrival.along_dip, 120.0) < 1e-12);
    // three impacts and one slide start among the events
    let ev = r.events.as_ref().unwrap();
    assert_eq!(ev.iter().filter(|e| e.kind == EventKind::Impact).count(), 3);
    assert_eq!(
        ev.iter()
            .filter(|e| e.kind == EventKind::SlideStart)
            .count(),
        1
    );
    let lost: f64 = ev.iter().map(|e| e.energy_lost).sum();
    assert!(rel(lost, r.energy.impacts + r.energy.transition) < 1e-12);
}

/// P11: 20 000-run ensemble with U[0.2, 0.4], U[0.7, 0.9]; tolerances of cases.json (≈ 5 SE).
#[test]
fn p11_monte_carlo_statistics() {
    let c = case_by_id("P11_lumped_mass_monte_carlo");
    let case = MigrationCase {
        monte_carlo: Some(MonteCarlo {
            runs: 20_000,
            seed: 7,
            ..MonteCarlo::default()
        }),
        ..MigrationCase::default()
    };
    let r = solve(&case);
    check_expected(&c, &r);
    let st = r.statistics.unwrap();
    assert_eq!(st.runs, 20_000);
    assert_eq!(st.reached_fraction, 1.0);
    let sp = st.speed.unwrap();
    assert!(sp.min <= sp.p05 && sp.p05 <= sp.p50 && sp.p50 <= sp.p95 && sp.p95 <= sp.max);
    assert_eq!(sp.histogram.counts.iter().sum::<u64>(), 20_000);
}

/// P09: the closed forms of §C.1 come out of the solver itself.
#[test]
fn p09_analytic_numbers_through_the_solver() {
    let c = case_by_id("P09_migration_analytic");
    let e = &c["expected"];
    let x = |k: &str| e[k].as_f64().unwrap();
    let g = 9.81;
    let th = 45f64.to_radians();
    // slide from rest on the floor over the full face
    let slide = MigrationCase {
        release: gangue::physics::migration::Release {
            drop_height: 0.0,
            ..Default::default()
        },
        ..MigrationCase::default()
    };
    let r = solve(&slide);
    assert!(rel(r.arrival.speed, x("slide_full_face_v")) < 1e-9);
    assert!(rel(r.arrival.time, x("slide_full_face_t")) < 1e-9);
    assert_eq!(r.impact_count, 0);
    // a_slide = v²/(2S)
    assert!(rel(r.arrival.speed.powi(2) / 240.0, x("a_slide")) < 1e-9);
    // roll from rest (μ must allow it): v = √(2 · 5/7 g sin θ · S)
    let mut roll = slide;
    roll.lumped_mass.motion = Motion::Roll;
    roll.face.friction_coefficient = x("mu_min_for_rolling");
    let r = solve(&roll);
    assert!(rel(r.arrival.speed, x("roll_full_face_v")) < 1e-9);
    assert!(rel(r.arrival.speed.powi(2) / 240.0, x("a_roll_sphere")) < 1e-9);
    assert!(
        rel(
            r.arrival.kinetic_energy,
            0.7 * r.mass * r.arrival.speed.powi(2)
        ) < 1e-12
    );
    assert_eq!(r.arrival.phase, Phase::Roll);
    // free fall of 3.27 m: the first impact event
    let r = solve(&MigrationCase::default());
    let ev = r.events.as_ref().unwrap();
    let first = ev.iter().find(|e| e.kind == EventKind::Impact).unwrap();
    assert!(rel(first.time, x("free_fall_time")) < 1e-9);
    assert!(rel(first.speed_before, x("free_fall_speed")) < 1e-9);
    // bounce: after the first impact the velocity is (e_t v_t, e_n v_n)
    let vn = x("impact_vn");
    let after = (x("bounce_vn_after").powi(2) + x("bounce_vt_after").powi(2)).sqrt();
    assert!(rel(first.speed_after, after) < 1e-9);
    assert!(rel(vn, x("free_fall_speed") * th.cos()) < 1e-12);
    // apex of the first bounce: v_n'²/(2 g cos θ)
    let apex = x("bounce_vn_after").powi(2) / (2.0 * g * th.cos());
    assert!(r.max_bounce_height >= apex * (1.0 - 1e-9));
    // projectile from the floor with (v_x0, v_y0) = (3, 2): the second flight of a drop whose
    // restitution turns the first impact's velocity into (3, 2)
    let proj = projectile_flight(3.0, 2.0);
    assert!(rel(proj.0, x("proj_flight_time")) < 1e-9);
    assert!(rel(proj.1, x("proj_range")) < 1e-9);
    assert!(rel(proj.2, x("proj_land_vx")) < 1e-9);
    assert!(rel(proj.3, x("proj_apex_height")) < 1e-9);
}

/// Flight time, range, landing along-floor speed and apex of a flight from the floor with
/// along-floor and normal speeds (vx0, vy0) on the 45° plane, read from the solver's events.
fn projectile_flight(vx0: f64, vy0: f64) -> (f64, f64, f64, f64) {
    let g: f64 = 9.81;
    let th = 45f64.to_radians();
    let (s, c) = th.sin_cos();
    // A vertical drop from h lands with (v s, −v c), v = √(2gh). With e_n = vy0/(v c) and
    // e_t = vx0/(v s) the rebound is (vx0, vy0).
    let h: f64 = 3.27;
    let v = (2.0 * g * h).sqrt();
    let mut case = MigrationCase::default();
    case.face.restitution_normal = vy0 / (v * c);
    case.face.restitution_tangential = vx0 / (v * s);
    case.lumped_mass.stop_normal_speed = 0.0;
    let r = solve(&case);
    let ev: Vec<_> = r
        .events
        .unwrap()
        .into_iter()
        .filter(|e| e.kind == EventKind::Impact)
        .collect();
    let t_f = ev[1].time - ev[0].time;
    let range = ev[1].along_dip - ev[0].along_dip;
    // landing along-floor speed: |v|² = vx² + vy0² on landing (|vy| = vy0)
    let land_vx = (ev[1].speed_before.powi(2) - vy0 * vy0).sqrt();
    // the apex after the first impact, v_y0²/(2 g cos θ)
    let apex = r.max_bounce_height;
    let _ = (s, c);
    (t_f, range, land_vx, apex)
}

/// Deterministic runs against `reference.py` kind `etm` (cases computed with the reference and
/// pinned here; regenerate with `echo '{…}' | python3 reference.py -`).
#[test]
fn random_cases_against_reference_etm() {
    // The oracle is part of the test command (scripts/test installs mpmath and scipy): a missing
    // python3 or reference fails the test instead of skipping it.
    let out = std::process::Command::new("python3")
        .arg("--version")
        .output()
        .expect("python3 runs");
    assert!(out.status.success(), "python3 --version failed");
    let script = shared_dir().join("reference/reference.py");
    assert!(script.exists(), "{} is missing", script.display());
    // a fixed pseudo-random sample of valid cases (dip, μ, S, h, e_n, e_t, v_stop, mode)
    let mut state = 0x1234_5678_u64;
    let mut u = || {
        let v = gangue::physics::migration::monte_carlo::splitmix64(&mut state);
        (v >> 11) as f64 / 9_007_199_254_740_992.0
    };
    for _ in 0..12 {
        let dip = 5.0 + 75.0 * u();
        let tan = dip.to_radians().tan();
        let roll = u() < 0.3;
        let mu = if roll {
            2.0 / 7.0 * tan + 0.5 * u()
        } else {
            1.2 * u()
        };
        let s_len = 1.0 + 300.0 * u();
        let h = 0.05 + 20.0 * u();
        let (en, et, vs) = (u(), u(), 0.05 + 2.0 * u());
        let mode = if roll { "roll" } else { "slide" };
        let req = format!(
            r#"{{"kind":"etm","dip_deg":{dip},"mu":{mu},"face_length":{s_len},"drop_height":{h},"e_n":{en},"e_t":{et},"v_stop":{vs},"mode":"{mode}"}}"#
        );
        let out = std::process::Command::new("python3")
            .arg(&script)
            .arg("-")
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .and_then(|mut ch| {
                use std::io::Write;
                ch.stdin.take().unwrap().write_all(req.as_bytes())?;
                ch.wait_with_output()
            })
            .expect("run reference");
        let v: Value = serde_json::from_slice(&out.stdout).expect("reference JSON");
        let o = &v["output"];
        let mut case = MigrationCase::default();
        case.face.dip_deg = dip;
        case.face.friction_coefficient = mu;
        case.face.length = s_len;
        case.release.drop_height = h;
        case.face.restitution_normal = en;
        case.face.restitution_tangential = et;
        case.lumped_mass.stop_normal_speed = vs;
        case.lumped_mass.motion = if roll { Motion::Roll } else { Motion::Slide };
        let r = solve(&case);
        let ctx = format!("{req} -> {o}");
        assert_eq!(
            r.impact_count as f64,
            o["n_impacts"].as_f64().unwrap(),
            "{ctx}"
        );
        let phase = o["phase"].as_str().unwrap();
        let want_phase = match r.arrival.phase {
            Phase::Flight => "flight",
            Phase::Slide => "slide",
            Phase::Roll => "roll",
            Phase::Stopped => "stopped",
        };
        assert_eq!(phase, want_phase, "{ctx}");
        let tol = 1e-9;
        let close = |a: f64, b: f64, what: &str| {
            assert!(
                (a - b).abs() <= tol * b.abs().max(1e-6),
                "{what}: {a} vs {b}; {ctx}"
            )
        };
        if phase == "stopped" {
            close(
                r.stop_along_dip.unwrap(),
                o["x_stop"].as_f64().unwrap(),
                "x_stop",
            );
            close(r.arrival.time, o["t"].as_f64().unwrap(), "t");
        } else {
            close(r.arrival.time, o["t"].as_f64().unwrap(), "t");
            close(r.arrival.speed, o["speed"].as_f64().unwrap(), "speed");
            close(
                r.arrival.kinetic_energy,
                o["KE_end"].as_f64().unwrap(),
                "KE_end",
            );
        }
        close(
            r.energy.impacts,
            o["E_impacts"].as_f64().unwrap(),
            "E_impacts",
        );
        if o["E_friction"].as_f64().unwrap() > 0.0 {
            close(
                r.energy.friction,
                o["E_friction"].as_f64().unwrap(),
                "E_friction",
            );
        }
        if o["E_transition"].as_f64().unwrap() > 1e-9 {
            close(
                r.energy.transition,
                o["E_transition"].as_f64().unwrap(),
                "E_transition",
            );
        }
        assert!(
            r.energy.residual.abs() <= 1e-9 * r.energy.total_start,
            "{ctx}"
        );
    }
}

fn plane_grid(dip_deg: f64, d: f64, x0: f64, y0: f64, nx: usize, ny: usize) -> FloorSpec {
    let tan = dip_deg.to_radians().tan();
    let heights = (0..ny)
        .map(|_| (0..nx).map(|j| -(x0 + j as f64 * d) * tan).collect())
        .collect();
    FloorSpec::Grid {
        origin: [x0, y0],
        spacing: d,
        heights,
    }
}

fn assert_same(a: &MigrationResult, b: &MigrationResult, tol: f64) {
    let close = |x: f64, y: f64, what: &str| {
        assert!(
            (x - y).abs() <= tol * y.abs().max(1.0),
            "{what}: {x} vs {y}"
        )
    };
    assert_eq!(a.impact_count, b.impact_count);
    assert_eq!(a.arrival.phase, b.arrival.phase);
    assert_eq!(a.arrival.stop_reason, b.arrival.stop_reason);
    close(a.arrival.time, b.arrival.time, "time");
    close(a.arrival.speed, b.arrival.speed, "speed");
    close(a.arrival.along_dip, b.arrival.along_dip, "along");
    for k in 0..3 {
        close(a.arrival.position[k], b.arrival.position[k], "position");
    }
    close(a.energy.impacts, b.energy.impacts, "impacts");
    close(a.energy.friction, b.energy.friction, "friction");
    close(a.energy.transition, b.energy.transition, "transition");
    close(a.energy.total_start, b.energy.total_start, "total");
    match (a.slide_start_along_dip, b.slide_start_along_dip) {
        (Some(x), Some(y)) => close(x, y, "slide start"),
        (x, y) => assert_eq!(x, y),
    }
    match (a.stop_along_dip, b.stop_along_dip) {
        (Some(x), Some(y)) => close(x, y, "stop"),
        (x, y) => assert_eq!(x, y),
    }
}

/// A grid that is exactly the plane reproduces the plane's answer to 1e-9, for the default case
/// and for releases across and along the face, with an initial speed and with a stop.
#[test]
fn plane_equivalent_grid_reproduces_the_plane() {
    for (dip, mu, h, along, across, speed, d) in [
        (45.0, 0.2, 3.27, 0.0, 0.0, 0.0, 0.5),
        (45.0, 0.2, 3.27, 0.0, 0.3, 0.0, 0.5),
        (30.0, 0.3, 1.0, 17.3, -2.21, 4.0, 0.37),
        (60.0, 0.5, 0.0, 5.0, 1.0, 2.0, 1.0),
        (20.0, 0.6, 2.0, 3.0, 0.25, 1.0, 0.5),
    ] {
        let mut plane = MigrationCase::default();
        plane.face.dip_deg = dip;
        plane.face.friction_coefficient = mu;
        plane.release.drop_height = h;
        plane.release.along_dip = along;
        plane.release.across = across;
        plane.release.speed = speed;
        let a = solve(&plane);
        let mut grid = plane.clone();
        let xlen = 121.0 * dip.to_radians().cos() + 2.0;
        grid.face.floor = plane_grid(
            dip,
            d,
            0.0,
            -5.0,
            (xlen / d) as usize + 2,
            (10.0 / d) as usize + 2,
        );
        let b = solve(&grid);
        assert_same(&b, &a, 1e-9);
    }
}

/// Contours of the plane (lines of constant x) triangulate to the plane and reproduce it.
#[test]
fn plane_equivalent_contours_reproduce_the_plane() {
    let dip: f64 = 45.0;
    let tan = dip.to_radians().tan();
    let contours: Vec<ContourLine> = (0..=43)
        .map(|k| {
            let x = 2.0 * k as f64;
            ContourLine {
                elevation: -x * tan,
                points: vec![[x, -4.0], [x, 4.0]],
            }
        })
        .collect();
    let mut plane = MigrationCase::default();
    plane.release.across = 0.37;
    let a = solve(&plane);
    let mut c = plane;
    c.face.floor = FloorSpec::Contours {
        contours,
        resolution: 1.0,
    };
    let b = solve(&c);
    assert_same(&b, &a, 1e-9);
}

/// Roll mode with μ below (2/7) tan θ is invalid on /face/friction_coefficient.
#[test]
fn roll_needs_enough_friction() {
    let mut c = MigrationCase::default();
    c.lumped_mass.motion = Motion::Roll;
    let e = run(&c, &Control::unlimited()).unwrap_err();
    match e {
        gangue::physics::PhysicsError::InvalidInput { param, .. } => {
            assert_eq!(param, gangue::physics::Param::FaceFriction)
        }
        e => panic!("{e:?}"),
    }
}

/// A slide with a < 0 stops at v²/(2|a|) (closed form) and reports at_rest.
#[test]
fn slide_stops_at_the_closed_form_distance() {
    let mut c = MigrationCase::default();
    c.face.dip_deg = 20.0;
    c.face.friction_coefficient = 0.6;
    c.release.drop_height = 0.0;
    c.release.speed = 5.0;
    c.release.along_dip = 10.0;
    let r = solve(&c);
    let th = 20f64.to_radians();
    let a = 9.81 * (th.sin() - 0.6 * th.cos());
    assert_eq!(r.arrival.stop_reason, StopReason::AtRest);
    assert_eq!(r.arrival.phase, Phase::Stopped);
    assert!(rel(r.stop_along_dip.unwrap(), 10.0 + 25.0 / (2.0 * -a)) < 1e-12);
    assert!(rel(r.arrival.time, 5.0 / -a) < 1e-12);
    assert!(r.energy.residual.abs() < 1e-9 * r.energy.total_start);
    // with end_time before the stop the state is the closed form at that time
    c.end_time = Some(0.5);
    let r = solve(&c);
    assert_eq!(r.arrival.stop_reason, StopReason::EndTime);
    assert!(rel(r.arrival.speed, 5.0 + a * 0.5) < 1e-12);
    assert!(rel(r.arrival.along_dip, 10.0 + 5.0 * 0.5 + 0.5 * a * 0.25) < 1e-12);
    // a = 0, v = 0: at rest at once
    c.end_time = None;
    c.release.speed = 0.0;
    c.face.friction_coefficient = th.tan();
    let r = solve(&c);
    assert_eq!(r.arrival.stop_reason, StopReason::AtRest);
    assert_eq!(r.arrival.time, 0.0);
}

/// A flight that passes the lower end stops in flight with the closed-form time.
#[test]
fn flight_past_the_lower_end() {
    let mut c = MigrationCase::default();
    c.face.length = 3.0;
    c.face.restitution_normal = 0.9;
    c.face.restitution_tangential = 1.0;
    let r = solve(&c);
    assert_eq!(r.arrival.phase, Phase::Flight);
    assert_eq!(r.arrival.stop_reason, StopReason::LowerEnd);
    assert!(rel(r.arrival.along_dip, 3.0) < 1e-12);
    assert!(r.arrival.normal_offset > 0.0);
    assert!(r.energy.residual.abs() < 1e-9 * r.energy.total_start);
}

/// Trajectory samples follow the closed forms and conserve energy sample by sample.
#[test]
fn trajectory_samples_balance_energy() {
    let mut c = MigrationCase::default();
    c.output.trajectory = true;
    c.output.sample_interval = 0.001;
    let r = solve(&c);
    let tr = r.trajectory.as_ref().unwrap();
    let n = tr.time.len();
    assert_eq!(n, (r.arrival.time / 0.001).floor() as usize + 2);
    for k in 0..n {
        let e = tr.kinetic_energy[k] + tr.potential_energy[k] + tr.dissipated_energy[k];
        assert!(
            (e - r.energy.total_start).abs() < 1e-9 * r.energy.total_start,
            "sample {k}"
        );
        assert!(tr.height[k] >= -1e-9);
    }
    // free fall: z(t) = h − ½ g t² before the first impact
    let z = tr.position[100][2];
    assert!((z - (3.27 - 0.5 * 9.81 * 0.1 * 0.1)).abs() < 1e-12);
    // too many samples
    c.output.sample_interval = 1e-6;
    c.output.max_samples = 1000;
    match run(&c, &Control::unlimited()).unwrap_err() {
        gangue::physics::PhysicsError::InvalidInput { param, .. } => {
            assert_eq!(param, gangue::physics::Param::TrajectorySampleInterval)
        }
        e => panic!("{e:?}"),
    }
}

/// Identical bits with 1 and 2 threads.
#[test]
fn ensemble_is_thread_count_independent() {
    let case = MigrationCase {
        monte_carlo: Some(MonteCarlo {
            runs: 3000,
            seed: 99,
            friction_coefficient: Some(Distribution::TruncatedNormal {
                mean: 0.2,
                std: 0.02,
                min: 0.0,
                max: 1.0,
            }),
            restitution_normal: Distribution::Normal {
                mean: 0.3,
                std: 0.1,
            },
            ..MonteCarlo::default()
        }),
        output: gangue::physics::migration::OutputOptions {
            runs_csv: true,
            ..Default::default()
        },
        ..MigrationCase::default()
    };
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let a = pool(1).install(|| solve(&case));
    let b = pool(2).install(|| solve(&case));
    assert_eq!(a, b);
    assert_eq!(a.runs.map(|r| r.len()), Some(3000));
}

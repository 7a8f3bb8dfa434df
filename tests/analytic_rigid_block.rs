//! Rigid-block DEM against physics.md §C.1 and §C.3: the DEM checks table (cube sliding, sphere
//! rolling, sphere slipping with spin-up) within 2e-3 of the analytic answers, the spring–dashpot
//! restitution of P16 (closed form and one DEM impact), the paper's full scene staying below the
//! frictionless bound, a flat grid floor giving the plane's answer, and the energy account.

use gangue::physics::Control;
use gangue::physics::material::RockShape;
use gangue::physics::migration::{
    ContourLine, Distribution, Event, EventKind, FloorSpec, Method, MigrationCase, MigrationResult,
    MonteCarlo, Phase, StopReason, bounce_restitution, run,
};
use serde_json::Value;

const G: f64 = 9.81;

fn cases() -> Value {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/verification/cases.json");
    serde_json::from_str(&std::fs::read_to_string(path).expect("cases.json")).unwrap()
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
    ((a - b) / b).abs()
}

/// The rigid block on the default 45°, 120 m plane, released at rest on the floor.
fn block() -> MigrationCase {
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.release.drop_height = 0.0;
    c.output.events = true;
    c
}

fn solve(c: &MigrationCase) -> MigrationResult {
    run(c, &Control::unlimited()).unwrap()
}

fn slide_accel(mu: f64) -> f64 {
    let t = 45f64.to_radians();
    G * (t.sin() - mu * t.cos())
}

#[test]
fn cube_slides_one_second_at_the_coulomb_acceleration() {
    // physics.md §C.3 table: v(1 s) = 5.549374, s = a/2
    let mut c = block();
    c.end_time = Some(1.0);
    let r = solve(&c);
    let a = slide_accel(0.2);
    assert!((a - 5.549374).abs() < 1e-6);
    assert_eq!(r.arrival.stop_reason, StopReason::EndTime);
    assert_eq!(r.arrival.phase, Phase::Slide);
    assert!((r.arrival.time - 1.0).abs() < 1e-12);
    let v = r.arrival.along_dip_velocity;
    assert!(rel(v, a) < 2e-3, "v = {v}");
    assert!(
        rel(r.arrival.along_dip, 0.5 * a) < 2e-3,
        "{}",
        r.arrival.along_dip
    );
    // no rotation, no impact while sliding face-down
    assert_eq!(r.impact_count, 0);
    assert!(
        r.arrival.angular_speed < 1e-6,
        "{}",
        r.arrival.angular_speed
    );
    let rb = r.rigid_block.unwrap();
    assert!(rel(rb.mass, 67.5) < 1e-12);
    for i in rb.principal_inertia {
        assert!(rel(i, 67.5 * 0.09 / 6.0) < 1e-12);
    }
    // Δt_crit = √(I/(3 kₙ L²)) for the cube; Δt = 1/⌈1/(0.2 min(Δt_crit, the damped bound))⌉:
    // whole steps to the end time, within 0.2 Δt_crit (the damped bound, half the stability
    // limit of the face's four dashpots at β = 0.35, is 8.497e-5 s)
    let dtc = (1.0125f64 / (3.0 * 1e8 * 0.09)).sqrt();
    assert!(rel(rb.critical_time_step, dtc) < 1e-12);
    let n = 1.0 / rb.time_step;
    assert!((n - n.round()).abs() < 1e-6, "{n} steps");
    assert!(
        rel(n.round(), (1.0 / (0.2 * 8.497e-5f64)).ceil()) < 1e-4,
        "{n} steps"
    );
}

#[test]
fn cube_slides_the_full_face_at_the_analytic_speed_and_time() {
    // physics.md §C.1: from rest v_S = 36.494517 m/s, t = 6.576330 s
    let r = solve(&block());
    assert_eq!(r.arrival.stop_reason, StopReason::LowerEnd);
    assert!(
        rel(r.arrival.along_dip_velocity, 36.494517) < 2e-3,
        "{:?}",
        r.arrival
    );
    assert!(rel(r.arrival.time, 6.576330) < 2e-3, "{:?}", r.arrival);
    assert!((r.arrival.along_dip - 120.0).abs() < 1e-6);
    // friction work μ m g cos θ S and the account
    let wf = 0.2 * 67.5 * G * 45f64.to_radians().cos() * 120.0;
    assert!(
        rel(r.energy.friction, wf) < 2e-3,
        "{} vs {wf}",
        r.energy.friction
    );
    assert!(
        r.energy.residual.abs() < 1e-4 * r.energy.total_start,
        "{:?}",
        r.energy
    );
}

fn sphere(mu: f64) -> MigrationCase {
    let mut c = block();
    c.rock.shape = RockShape::Sphere { radius: 0.15 };
    c.face.friction_coefficient = mu;
    c.end_time = Some(1.0);
    c
}

#[test]
fn sphere_rolls_at_five_sevenths_g_sin_theta() {
    // μ = 0.35 ≥ (2/7) tan θ: a = (5/7) g sin θ, v(1 s) = 4.954798
    let r = solve(&sphere(0.35));
    let a = 5.0 / 7.0 * G * 45f64.to_radians().sin();
    assert!((a - 4.954798).abs() < 1e-6);
    assert!(
        rel(r.arrival.along_dip_velocity, a) < 2e-3,
        "{:?}",
        r.arrival
    );
    assert!(
        rel(r.arrival.angular_speed, a / 0.15) < 2e-3,
        "{:?}",
        r.arrival
    );
    assert_eq!(r.arrival.phase, Phase::Roll);
}

#[test]
fn sphere_slips_and_spins_up_with_low_friction() {
    // μ = 0.2 < (2/7) tan θ: v = g(sin θ − μ cos θ) t, ω = 5 μ g cos θ t/(2 r)
    let r = solve(&sphere(0.2));
    let w = 5.0 * 0.2 * G * 45f64.to_radians().cos() / (2.0 * 0.15);
    assert!((w - 23.1224).abs() < 1e-3);
    assert!(
        rel(r.arrival.along_dip_velocity, slide_accel(0.2)) < 2e-3,
        "{:?}",
        r.arrival
    );
    assert!(rel(r.arrival.angular_speed, w) < 2e-3, "{:?}", r.arrival);
    assert_eq!(r.arrival.phase, Phase::Slide);
}

#[test]
fn p16_spring_dashpot_restitution_closed_form() {
    let c = case_by_id("P16_bounce_restitution");
    let inp = &c["input"];
    let e = &c["expected"];
    let (m, k, beta) = (
        inp["mass"].as_f64().unwrap(),
        inp["kn"].as_f64().unwrap(),
        inp["beta"].as_f64().unwrap(),
    );
    let (e0, t0) = bounce_restitution(m, k, beta, false);
    let (e1, _) = bounce_restitution(m, k, beta, true);
    assert!(rel(e0, e["e_noclip"].as_f64().unwrap()) < 1e-9, "{e0}");
    assert!(rel(e0, e["e_formula"].as_f64().unwrap()) < 1e-9);
    assert!(
        rel(t0, e["t_contact_formula"].as_f64().unwrap()) < 1e-9,
        "{t0}"
    );
    assert!(rel(t0, e["t_contact_noclip"].as_f64().unwrap()) < 1e-7);
    assert!(rel(e1, e["e_clip"].as_f64().unwrap()) < 1e-7, "{e1}");
    // e = exp(−πβ/√(1−β²))
    let ef = (-std::f64::consts::PI * beta / (1.0 - beta * beta).sqrt()).exp();
    assert!(rel(e0, ef) < 1e-12);
}

#[test]
fn p16_one_dem_impact_has_the_clipped_restitution() {
    // A frictionless sphere (one contact, contact mass = its mass) under weak gravity strikes
    // the 45° plane: its normal rebound is e_clip times its normal approach speed.
    let mut c = sphere(0.0);
    let g = 0.1;
    c.gravity = g;
    c.release.drop_height = 100.0;
    c.rock.shape = RockShape::Sphere { radius: 0.1 };
    c.rock.density = 67.5 / (4.0 / 3.0 * std::f64::consts::PI * 1e-3);
    let t_fall = (2.0 * 100.0 / g).sqrt();
    c.end_time = Some(t_fall + 0.02);
    let th = 45f64.to_radians();
    let vn0 = (2.0 * g * 100.0).sqrt() * th.cos();
    let (e, tc) = bounce_restitution(67.5, 1e8, 0.35, true);
    // second order in Δt: 5e-3 at the default safety 0.2, 4e-4 at 0.05
    for (safety, tol) in [(0.2, 6e-3), (0.05, 1e-3)] {
        c.rigid_block.time_step_safety = safety;
        let r = solve(&c);
        let ev = r.events.as_ref().unwrap();
        let imp = ev.iter().find(|e| e.kind == EventKind::Impact).unwrap();
        assert!(rel(imp.speed_before, (2.0 * g * 100.0).sqrt()) < 1e-4);
        // back out the gravity acting since separation
        let t_sep = imp.time + tc;
        let vn = r.arrival.normal_velocity + g * th.cos() * (r.arrival.time - t_sep);
        assert_eq!(r.impact_count, 1);
        assert!(
            rel(vn, e * vn0) < tol,
            "safety {safety}: {vn} vs {}",
            e * vn0
        );
    }
    let r = solve(&c);
    let imp = r.events.as_ref().unwrap()[0].clone();
    // peak force of the clipped law: between k x_max·e^… bounds; at least m v ω e^{-…}
    let peak = imp.peak_contact_force.unwrap();
    assert!(peak > 0.5 * vn0 * (67.5f64 * 1e8).sqrt() && peak < 1.5 * vn0 * (67.5f64 * 1e8).sqrt());
}

#[test]
fn paper_scene_arrives_below_the_frictionless_bound() {
    // 0.3 m cube dropped 3.27 m on the 45°, 120 m face: √(2g(h + S sin θ)) = 41.6 m/s bounds
    // the speed; once it slides it follows the Coulomb slide to the lower end.
    let mut c = block();
    c.release.drop_height = 3.27;
    c.output.trajectory = true;
    c.output.sample_interval = 0.05;
    let r = solve(&c);
    let th = 45f64.to_radians();
    let bound = (2.0 * G * (3.27 + 120.0 * th.sin())).sqrt();
    assert!((bound - 41.6).abs() < 0.05);
    assert_eq!(r.arrival.stop_reason, StopReason::LowerEnd);
    assert!(r.arrival.speed < bound, "{:?}", r.arrival);
    assert!(r.impact_count >= 1);
    let x_s = r.slide_start_along_dip.expect("it slides");
    // the slide from x_s at the speed it had there
    let tr = r.trajectory.as_ref().unwrap();
    let k = tr.along_dip.iter().position(|&s| s >= x_s + 5.0).unwrap();
    let (s_k, v_k) = (tr.along_dip[k], tr.velocity[k]);
    let vk = v_k[0] * th.cos() - v_k[2] * th.sin();
    let v_slide = (vk * vk + 2.0 * slide_accel(0.2) * (120.0 - s_k)).sqrt();
    assert!(
        rel(r.arrival.along_dip_velocity, v_slide) < 2e-3,
        "{} vs {v_slide}",
        r.arrival.along_dip_velocity
    );
    // energy: nothing created, account closed
    let e = &r.energy;
    assert!(e.damping > 0.0 && e.friction > 0.0 && e.stored >= 0.0);
    assert!(e.residual.abs() < 1e-3 * e.total_start, "{e:?}");
    assert!(tr.orientation.len() == tr.time.len());
    eprintln!(
        "paper scene: v = {:.6} m/s, t = {:.6} s, impacts {}, slide from {:.4} m, steps {}",
        r.arrival.speed,
        r.arrival.time,
        r.impact_count,
        x_s,
        r.rigid_block.unwrap().steps
    );
}

fn plane_grid(spacing: f64, nx: usize, ny: usize) -> FloorSpec {
    let t = 45f64.to_radians().tan();
    let y0 = -(ny as f64 - 1.0) * spacing / 2.0;
    FloorSpec::Grid {
        origin: [0.0, y0],
        spacing,
        heights: (0..ny)
            .map(|_| (0..nx).map(|j| -(j as f64) * spacing * t).collect())
            .collect(),
    }
}

#[test]
fn flat_grid_and_contour_floors_give_the_planes_answer() {
    let mut c = block();
    c.end_time = Some(1.0);
    c.face.length = 20.0;
    c.release.along_dip = 1.0;
    let p = solve(&c);
    // 0.25 m cells: the cube's vertices cross facets and keep their springs
    c.face.floor = plane_grid(0.25, 60, 9);
    let g = solve(&c);
    assert!(
        rel(g.arrival.along_dip_velocity, p.arrival.along_dip_velocity) < 1e-6,
        "{:?} vs {:?}",
        g.arrival,
        p.arrival
    );
    assert!(rel(g.arrival.along_dip, p.arrival.along_dip) < 1e-6);
    assert!(g.arrival.angular_speed < 1e-4);
    // contour lines of the plane, Delaunay-triangulated: a flat mesh as well
    let t = 45f64.to_radians().tan();
    c.face.floor = FloorSpec::Contours {
        contours: (0..=16)
            .map(|k| ContourLine {
                elevation: -(k as f64) * t,
                points: vec![[k as f64, -2.0], [k as f64, 2.0]],
            })
            .collect(),
        resolution: 0.5,
    };
    let m = solve(&c);
    assert!(
        rel(m.arrival.along_dip_velocity, p.arrival.along_dip_velocity) < 1e-6,
        "{:?} vs {:?}",
        m.arrival,
        p.arrival
    );
    assert!(rel(m.arrival.along_dip, p.arrival.along_dip) < 1e-6);
    // dropped from 1 m with bounces
    c.end_time = Some(2.0);
    c.release.drop_height = 1.0;
    c.face.floor = FloorSpec::Plane;
    let p = solve(&c);
    c.face.floor = plane_grid(0.5, 40, 9);
    let g = solve(&c);
    assert_eq!(g.impact_count, p.impact_count);
    assert!(
        rel(g.arrival.speed, p.arrival.speed) < 1e-4,
        "{:?} vs {:?}",
        g.arrival,
        p.arrival
    );
}

#[test]
fn monte_carlo_over_friction_and_damping_is_bit_identical_across_threads() {
    let mut c = block();
    c.face.length = 5.0;
    c.release.drop_height = 0.5;
    c.output.events = false;
    c.monte_carlo = Some(MonteCarlo {
        runs: 24,
        seed: 9,
        friction_coefficient: Some(Distribution::Uniform {
            min: 0.15,
            max: 0.3,
        }),
        ..MonteCarlo::default()
    });
    c.rigid_block.critical_damping_ratio_distribution =
        Some(Distribution::Uniform { min: 0.2, max: 0.5 });
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let a = one.install(|| solve(&c));
    let b = two.install(|| solve(&c));
    assert_eq!(a.statistics, b.statistics);
    let s = a.statistics.unwrap();
    assert_eq!(s.runs, 24);
    assert!(s.reached_fraction > 0.0);
    // a slower ensemble than the frictionless bound, faster than the slowest slide
    let sp = s.speed.unwrap();
    let th = 45f64.to_radians();
    assert!(sp.max < (2.0 * G * (0.5 + 5.0 * th.sin())).sqrt());
    assert!(sp.std.unwrap() > 0.0);
}

mod common;

#[tokio::test]
async fn rigid_block_over_http_reports_its_block_and_refuses_bad_input() {
    use serde_json::json;
    let app = common::app();
    // the tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1) m: V = 1/6 m³
    let r = common::post(
        &app,
        "/v1/migration",
        &json!({"method": "rigid_block", "face": {"length_m": 2},
                "rock": {"shape": "polyhedron", "density_kg_m3": 600,
                         "vertices_m": [[0,0,0],[0.3,0,0],[0,0.3,0],[0,0,0.3]]},
                "release": {"drop_height_m": 0.2}, "output": {"trajectory": true}}),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    assert_eq!(b["method"], "rigid_block");
    let m = 600.0 * 0.027 / 6.0;
    assert!(common::rel(b["rigid_block"]["mass_kg"].as_f64().unwrap(), m) < 1e-12);
    assert!(common::rel(b["mass_kg"].as_f64().unwrap(), m) < 1e-12);
    assert!(b["energy"]["stored_j"].is_number());
    assert!(
        b["trajectory"]["orientation_wxyz"]
            .as_array()
            .unwrap()
            .len()
            > 1
    );
    let imp = &b["events"].as_array().unwrap()[0];
    assert_eq!(imp["kind"], "impact");
    assert!(imp["peak_contact_force_n"].as_f64().unwrap() > 0.0);
    common::assert_rejections(
        &app,
        "/v1/migration",
        vec![
            (
                json!({"method": "rigid_block", "rigid_block": {"time_step_s": 1e-3}}),
                "/rigid_block/time_step_s",
                "invalid_input",
            ),
            (
                json!({"method": "rigid_block", "face": {"normal_stiffness_n_m": 1e3}}),
                "/face/normal_stiffness_n_m",
                "invalid_input",
            ),
            (
                json!({"method": "rigid_block", "monte_carlo": {"restitution_normal": {"min": 0.1, "max": 0.2}}}),
                "/monte_carlo/restitution_normal",
                "invalid_input",
            ),
            (
                json!({"monte_carlo": {"critical_damping_ratio": {"min": 0.1, "max": 0.2}}}),
                "/monte_carlo/critical_damping_ratio",
                "invalid_input",
            ),
            (
                json!({"method": "rigid_block", "rock": {"shape": "polyhedron", "vertices_m": [[0,0,0],[1,0,0],[0,1,0],[1,1,0]]}}),
                "/rock/vertices_m",
                "invalid_input",
            ),
        ],
    )
    .await;
    // a stiff sphere rolling down a long face (every step of the roll is stepped): the
    // estimate is over the limit
    let r = common::post(
        &app,
        "/v1/migration",
        &json!({"method": "rigid_block", "rock": {"shape": "sphere"},
                "face": {"length_m": 10000, "normal_stiffness_n_m": 1e12}}),
    )
    .await;
    let p = common::assert_problem(&r, 422, "too_many_steps");
    assert!(p["estimated_steps"].as_f64().unwrap() > 2e7, "{p}");
}

/// The 45° plane as a grid (spacing d, across |y| ≤ 1 m) with node heights raised by `bump(i, j)`.
fn bumpy_grid(d: f64, nx: usize, bump: impl Fn(usize, usize) -> f64) -> FloorSpec {
    let t = 45f64.to_radians().tan();
    let ny = (2.0 / d).round() as usize + 1;
    FloorSpec::Grid {
        origin: [0.0, -1.0],
        spacing: d,
        heights: (0..ny)
            .map(|i| (0..nx).map(|j| -(j as f64) * d * t + bump(i, j)).collect())
            .collect(),
    }
}

#[test]
fn a_floor_spike_and_a_ridge_lift_the_block_instead_of_piercing_it() {
    // A 2 cm spike (one raised node: face–vertex contacts) and a 2 cm ridge across the slope
    // (a row of raised nodes: edge–edge contacts on its convex creases) under the sliding
    // cube's path. The block must ride over them: no contact deeper than a few millimetres
    // (a 1 cm-deep pierce would mean the floor feature passed through the block's face), and
    // the energy account closes.
    let d = 0.1;
    let nx = 80;
    let (ji, ii) = (25usize, 10usize); // x = 2.5 m, y = 0
    for (name, floor) in [
        (
            "spike",
            bumpy_grid(d, nx, |i, j| if i == ii && j == ji { 0.02 } else { 0.0 }),
        ),
        (
            "ridge",
            bumpy_grid(d, nx, |_, j| if j == ji { 0.02 } else { 0.0 }),
        ),
    ] {
        let mut c = block();
        c.face.length = 8.0;
        c.release.along_dip = 1.0;
        c.end_time = Some(1.2);
        c.face.floor = floor;
        let r = solve(&c);
        let rb = r.rigid_block.unwrap();
        assert!(rb.max_overlap < 3e-3, "{name}: overlap {}", rb.max_overlap);
        // it passed the feature (x = 2.5 m is along ≈ 3.54 m)
        assert!(r.arrival.along_dip > 3.8, "{name}: {:?}", r.arrival);
        let e = &r.energy;
        assert!(e.residual.abs() < 2e-3 * 67.5 * G * 3.0, "{name}: {e:?}");
        assert!(e.damping >= 0.0 && e.friction > 0.0, "{name}: {e:?}");
    }
}

/// A V-groove down the 45° face: z = −x tan θ + |y| tan ψ on a grid of spacing d whose line
/// y = 0 is the groove's bottom.
fn v_groove(psi_deg: f64, d: f64, nx: usize, half: usize) -> FloorSpec {
    let (t, s) = (45f64.to_radians().tan(), psi_deg.to_radians().tan());
    FloorSpec::Grid {
        origin: [0.0, -(half as f64) * d],
        spacing: d,
        heights: (0..=2 * half)
            .map(|i| {
                let y = (i as f64 - half as f64) * d;
                (0..nx).map(|j| -(j as f64) * d * t + y.abs() * s).collect()
            })
            .collect(),
    }
}

#[test]
fn sphere_rolls_down_a_v_groove_on_both_walls() {
    // A sphere in a V-groove touches both walls (neither is the facet under its centre) and
    // rolls about the across-groove axis at the rolling radius ρ = r √(1 − n_y²), n the walls'
    // unit normals ∝ (tan θ, ∓tan ψ, 1): a = g sin θ / (1 + (2/5) r²/ρ²) (0.6818 g sin θ at
    // ψ = 30°, against 5/7 = 0.7143 on the plane). μ = 0.5 is above the 0.295 rolling needs.
    let r_s = 0.15;
    let mut c = sphere(0.5);
    c.face.length = 20.0;
    c.release.along_dip = 1.0;
    c.release.drop_height = 0.1;
    c.end_time = Some(2.0);
    c.output.events = false;
    c.output.trajectory = true;
    c.output.sample_interval = 0.01;
    c.face.floor = v_groove(30.0, 0.1, 160, 6);
    let r = solve(&c);
    let tr = r.trajectory.as_ref().unwrap();
    let (t, s) = (45f64.to_radians().tan(), 30f64.to_radians().tan());
    let ny2 = s * s / (t * t + s * s + 1.0);
    let a = G * 45f64.to_radians().sin() / (1.0 + 0.4 / (1.0 - ny2));
    assert!((a / (G * 45f64.to_radians().sin()) - 0.68182).abs() < 1e-4);
    let d = [45f64.to_radians().cos(), 0.0, -45f64.to_radians().sin()];
    let v_at = |time: f64| {
        let k = tr.time.iter().position(|&x| x >= time - 1e-9).unwrap();
        let v = tr.velocity[k];
        (tr.time[k], v[0] * d[0] + v[2] * d[2])
    };
    let ((t1, v1), (t2, v2)) = (v_at(1.0), v_at(1.9));
    let a_dem = (v2 - v1) / (t2 - t1);
    // measured 5.5e-3 below (the plane's 5/7 g sin θ is 4.8 % above): 1e-2
    assert!(rel(a_dem, a) < 1e-2, "a = {a_dem} against {a}");
    // in the groove, and never deeper into either wall than a few static overlaps once
    // the drop's impacts have died out (distance to the floor = the nearer wall's plane)
    let n_a = nalgebra::Vector3::new(t, -s, 1.0).normalize();
    let n_b = nalgebra::Vector3::new(t, s, 1.0).normalize();
    let static_overlap = r.mass * G * 45f64.to_radians().cos() / c.rigid_block.normal_stiffness;
    for (k, p) in tr.position.iter().enumerate() {
        if tr.time[k] < 1.0 {
            continue;
        }
        let p = nalgebra::Vector3::new(p[0], p[1], p[2]);
        // (it still rocks across the groove by about 1 cm at t = 1 s)
        assert!(p.y.abs() < 0.03, "off-centre at t = {}: {p:?}", tr.time[k]);
        let depth = r_s - n_a.dot(&p).min(n_b.dot(&p));
        assert!(
            // measured: 5.4 static overlaps while it still rocks across the groove
            depth < 10.0 * static_overlap,
            "{depth:e} m deep at t = {}",
            tr.time[k]
        );
    }
}

#[test]
fn sphere_on_a_flat_grid_gives_the_planes_answer() {
    // every facet within reach is tested: the grid's seams (edges, corners) must not add
    // contacts of their own on a flat floor
    for mu in [0.35, 0.2] {
        let mut c = sphere(mu);
        c.face.length = 20.0;
        c.release.along_dip = 1.0;
        let p = solve(&c);
        c.face.floor = plane_grid(0.1, 160, 9);
        let g = solve(&c);
        assert!(
            rel(g.arrival.along_dip_velocity, p.arrival.along_dip_velocity) < 1e-6,
            "{:?} vs {:?}",
            g.arrival,
            p.arrival
        );
        assert!(rel(g.arrival.angular_speed, p.arrival.angular_speed) < 1e-6);
        assert_eq!(g.arrival.phase, p.arrival.phase);
    }
}

/// The 1-D oracle of a normal impact (physics.md §C.3's linear law): `n_c` equal contacts
/// under a block of mass `m` (kg) striking at the normal speed `vn0` (m/s) with gravity `gn`
/// (m/s², its normal component) pressing it on: m U'' = m gₙ − N_c max(0, kU + c U'),
/// c = 2β√(m k), from the touch (U = 0) until the overlap returns to zero. Integrated by RK4
/// with 20 000 steps per undamped half period. Returns (peak total normal force N, energy
/// dissipated J: the mechanical energy lost between the touch and the separation).
fn normal_impact_oracle(m: f64, k: f64, beta: f64, n_c: f64, vn0: f64, gn: f64) -> (f64, f64) {
    let c = 2.0 * beta * (m * k).sqrt();
    let force = |u: f64, du: f64| n_c * (k * u + c * du).max(0.0);
    let acc = |u: f64, du: f64| gn - force(u, du) / m;
    let h = std::f64::consts::PI * (m / (n_c * k)).sqrt() / 20_000.0;
    let (mut u, mut du, mut peak) = (0.0f64, vn0, force(0.0, vn0));
    loop {
        let (k1u, k1v) = (du, acc(u, du));
        let (k2u, k2v) = (
            du + 0.5 * h * k1v,
            acc(u + 0.5 * h * k1u, du + 0.5 * h * k1v),
        );
        let (k3u, k3v) = (
            du + 0.5 * h * k2v,
            acc(u + 0.5 * h * k2u, du + 0.5 * h * k2v),
        );
        let (k4u, k4v) = (du + h * k3v, acc(u + h * k3u, du + h * k3v));
        let un = u + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
        let dun = du + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if un <= 0.0 {
            // back to zero overlap: the rest of the step is free flight (U'' = gₙ)
            let tau = u / (u - un) * h;
            let du_end = du + gn * tau;
            return (peak, 0.5 * m * (vn0 * vn0 - du_end * du_end));
        }
        (u, du) = (un, dun);
        peak = peak.max(force(u, du));
    }
}

/// A block dropped `drop` m onto the default 45° plane, its first impact event and the run
/// (ending in the bounce's flight, before the next contact).
fn first_impact(shape: RockShape, mu: f64, beta: f64, safety: f64) -> (MigrationResult, Event) {
    let mut c = block();
    c.rock.shape = shape;
    c.face.friction_coefficient = mu;
    c.rigid_block.critical_damping_ratio = beta;
    c.rigid_block.time_step_safety = safety;
    c.release.drop_height = 1.0;
    c.end_time = Some((2.0 / G).sqrt() + 0.05);
    let r = solve(&c);
    let imp = r.events.as_ref().unwrap()[0].clone();
    assert_eq!((imp.kind, r.impact_count), (EventKind::Impact, 1), "{r:?}");
    (r, imp)
}

/// An impact's `peak_contact_force_n` and `energy_lost_j` are those of its own contact's force
/// history (the 1-D oracle above): a sphere (one contact) at β 0.35 and 0.9, whose peak lies
/// inside the contact or at the touch, and a cube landing on its face (four contacts), within
/// 1 % at the default step and 0.1 % at a fifth of it (seen: 2.2e-3 and 1.1e-4). With friction
/// the normal history is the same (the sphere's shear force has no normal part; the cube's
/// peak is at the touch, before it tilts), and the event's loss is the run's whole
/// dissipation (nothing else dissipates in a run that ends in the bounce's flight). Before, the
/// first contact step reported the impulse of the dashpot's onset spread over the step as a
/// force (up to 1.5 c vₙ: +42 % for the sphere, +27–50 % at any step), and the loss left out
/// that first step (−14 % to −29 %).
#[test]
fn an_impact_reports_the_peak_force_and_the_loss_of_its_own_contact() {
    let th = 45f64.to_radians();
    let vn0 = (2.0 * G * 1.0f64).sqrt() * th.cos();
    let cases = [
        (RockShape::Sphere { radius: 0.15 }, 1.0, 0.35),
        (RockShape::Sphere { radius: 0.15 }, 1.0, 0.9),
        (RockShape::Cube, 4.0, 0.35),
    ];
    for (shape, n_c, beta) in cases {
        for (safety, tol) in [(0.2, 1e-2), (0.04, 1e-3)] {
            for mu in [0.0, 0.3] {
                let (r, imp) = first_impact(shape.clone(), mu, beta, safety);
                let (peak, lost) = normal_impact_oracle(r.mass, 1e8, beta, n_c, vn0, G * th.cos());
                let label = format!("{shape:?} β {beta} safety {safety} μ {mu}");
                let got = imp.peak_contact_force.unwrap();
                println!(
                    "{label}: peak {got:.1} oracle {peak:.1} ({:+.2e}); lost {:.3} oracle {lost:.3} ({:+.2e}); run {:.3}",
                    got / peak - 1.0,
                    imp.energy_lost,
                    imp.energy_lost / lost - 1.0,
                    r.energy.damping + r.energy.friction
                );
                assert!(rel(got, peak) < tol, "{label}: peak {got} vs {peak}");
                if mu == 0.0 {
                    assert!(
                        rel(imp.energy_lost, lost) < tol,
                        "{label}: lost {} vs {lost}",
                        imp.energy_lost
                    );
                }
                // the whole contact's loss, the shear springs' too
                let run_loss = r.energy.damping + r.energy.friction;
                assert!(
                    rel(imp.energy_lost, run_loss) < 1e-9,
                    "{label}: lost {} of the run's {run_loss}",
                    imp.energy_lost
                );
            }
        }
    }
}

/// A 0.5 m cube released 2 m above a 45° grid (0.5 m spacing) with a one-node valley across
/// it (one column of nodes 0.8 m lower than the plane): it strikes the valley's far flank and
/// slides over the convex crease below it, its corners measured against two facets.
fn valley_case(safety: f64) -> MigrationCase {
    let heights: Vec<Vec<f64>> = (0..9)
        .map(|_| {
            (0..30)
                .map(|j| if j == 8 { -4.3 } else { -0.5 * j as f64 })
                .collect()
        })
        .collect();
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.rock.side_length = 0.5;
    c.face.dip_deg = 45.0;
    c.face.length = 10.0;
    c.face.floor = FloorSpec::Grid {
        origin: [0.0, -2.0],
        spacing: 0.5,
        heights,
    };
    c.release.drop_height = 2.0;
    c.release.speed = 5.0;
    c.release.along_dip = 1.0;
    c.rigid_block.time_step_safety = safety;
    c
}

/// Energy does not vanish where a block's corner passes a crease: its overlap is its depth
/// below the floor's surface, continuous from facet to facet, and the switch of its normal
/// inside a step is placed where it happens. The account's residual of the valley run is
/// below 1e-3 of the energy at release at the default step and shrinks with the step (seen:
/// −9.96, −1.16, −0.185 J of 29 547 J at safety 0.2, 0.05, 0.01: order about 1.5), without
/// the `energy_unaccounted` warning. Before, each corner's overlap was measured against the
/// plane of the facet under it, jumping by the ratio of the two facets' normals' z as it
/// crossed the crease in plan: −353, −360, −371 J at those steps (1.2 %, independent of Δt).
#[test]
fn a_block_sliding_over_a_crease_keeps_its_energy_account() {
    let mut prev: Option<f64> = None;
    for (safety, shrink) in [(0.2, 0.0), (0.05, 4.0), (0.01, 3.0)] {
        let r = solve(&valley_case(safety));
        let e = &r.energy;
        println!(
            "safety {safety}: residual {:+.4e} J of {:.4e} J",
            e.residual, e.total_start
        );
        assert!(r.impact_count >= 2, "{r:?}");
        assert!(r.warnings.is_empty(), "safety {safety}: {:?}", r.warnings);
        if safety == 0.2 {
            assert!(e.residual.abs() < 1e-3 * e.total_start, "{e:?}");
        }
        if let Some(p) = prev {
            assert!(
                e.residual.abs() * shrink < p.abs(),
                "safety {safety}: {} after {p}",
                e.residual
            );
        }
        prev = Some(e.residual);
    }
}

/// An impact that turns into a ground phase is reported as it becomes one: its speed after is
/// the speed a few contact times after the touch, never the speed at the end of a long slide
/// (a landing at 7 m/s was once reported as leaving at 17 m/s, after the slide that followed).
/// Ridges across a 45° grid throw the sliding cube up again and again, so the run has several
/// ground phases after the first; every impact's speed after is at most its speed before plus
/// what gravity adds over ten contact times, and every ground phase has its `slide_start`.
#[test]
fn an_impact_that_becomes_a_slide_reports_its_own_speed_after() {
    let mut c = block();
    c.release.drop_height = 1.0;
    c.face.length = 60.0;
    c.face.floor = bumpy_grid(0.5, 100, |_, j| if j % 16 == 8 { 0.06 } else { 0.0 });
    let r = solve(&c);
    let ev = r.events.as_ref().expect("asked for");
    let impacts: Vec<_> = ev.iter().filter(|e| e.kind == EventKind::Impact).collect();
    let slides = ev
        .iter()
        .filter(|e| e.kind == EventKind::SlideStart)
        .count();
    assert!(impacts.len() >= 3, "{} impacts: {ev:?}", impacts.len());
    assert!(slides >= 2, "{slides} ground phases: {ev:?}");
    // one contact time of the default cube, π √(m / (4 kₙ)) ≈ 1.3 ms: ten of them are 13 ms
    let gain = 9.81 * 0.013;
    for e in &impacts {
        assert!(
            e.speed_after <= e.speed_before + gain,
            "impact at {} s: {} → {} m/s",
            e.time,
            e.speed_before,
            e.speed_after
        );
    }
}

//! The contact solver (physics.md §A) against independent references: the verification cases,
//! a direct integration of m δ″ = −P(δ), the energy balance by quadrature, and the 50-digit
//! reference implementation (reference.py, run through python3 + mpmath).

#![allow(clippy::field_reassign_with_default)] // cases read as "the default, except …"

mod common_oracle;

use std::f64::consts::{E, PI};

use gangue::physics::contact::{
    HERTZ_DURATION_FACTOR, ImpactDetail, force_law, impact_maxima, solve_impact,
};
use gangue::physics::material::{
    ContactLaw, ContactModel, ImpactCase, ModulusConvention, Rock, RockShape,
};
use gangue::physics::numeric::lambert::branch_u;
use gangue::physics::numeric::quadrature::{QuadOptions, integrate};
use gangue::physics::{PhysicsError, contact::ForceLaw};
use rand::{Rng, SeedableRng};
use serde_json::{Value, json};

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn case(law: ContactLaw, modulus: ModulusConvention) -> ImpactCase {
    ImpactCase {
        contact: ContactModel {
            law,
            modulus,
            hertz_exact: true,
        },
        ..Default::default()
    }
}

/// δmax, Pmax of a result.
fn maxima(d: &ImpactDetail) -> (f64, f64) {
    match d {
        ImpactDetail::Line(l) => (l.max_deformation, l.max_force),
        ImpactDetail::Hertz(h) => (h.max_deformation, h.max_force),
    }
}

// ---------------------------------------------------------------------------------------------
// Verification cases P01–P04, P14 (cases.json), at the physics level.

fn verification_cases() -> Vec<Value> {
    let dir = common_oracle::reference_dir();
    let path = dir.join("../verification/cases.json");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let v: Value = serde_json::from_str(&text).unwrap();
    v["cases"].as_array().unwrap().clone()
}

/// Builds the physics case from an /v1/impact request body (the fields P01–P04, P14 use).
fn from_request(req: &Value) -> ImpactCase {
    let mut c = ImpactCase::default();
    let f = |p: &str| req.pointer(p).and_then(Value::as_f64);
    if let Some(v) = f("/velocity_m_s") {
        c.velocity = v;
    }
    if let Some(v) = f("/rock/side_length_m") {
        c.rock.side_length = v;
    }
    if let Some(v) = f("/rock/elastic_modulus_pa") {
        c.rock.elastic_modulus = v;
    }
    if let Some(v) = f("/rock/density_kg_m3") {
        c.rock.density = v;
    }
    if let Some(v) = f("/rock/corner_radius_m") {
        c.rock.corner_radius = v;
    }
    if let Some(v) = f("/column/contact_radius_m") {
        c.column.contact_radius = v;
    }
    match req.pointer("/contact/law").and_then(Value::as_str) {
        Some("johnson") => c.contact.law = ContactLaw::Johnson,
        Some("hertz_point") => c.contact.law = ContactLaw::HertzPoint,
        Some("paper") | None => {}
        Some(other) => panic!("unexpected law {other}"),
    }
    if req
        .pointer("/contact/effective_modulus")
        .and_then(Value::as_str)
        == Some("two_body")
    {
        c.contact.modulus = ModulusConvention::TwoBody;
    }
    c
}

/// The response value named by an api.md JSON Pointer.
fn field(r: &gangue::physics::contact::ImpactResult, pointer: &str) -> f64 {
    let common = match pointer {
        "/mass_kg" => Some(r.mass),
        "/kinetic_energy_j" => Some(r.kinetic_energy),
        "/effective_modulus_pa" => Some(r.effective_modulus),
        "/contact_duration_s" => Some(r.contact_duration),
        _ => None,
    };
    if let Some(x) = common {
        return x;
    }
    match (&r.detail, pointer) {
        (ImpactDetail::Line(l), p) => match p {
            "/energy_parameter" => l.energy_parameter,
            "/lambert_w" => l.lambert_w,
            "/max_deformation_m" => l.max_deformation,
            "/max_force_n" => l.max_force,
            "/contact_half_width_m" => l.half_width,
            "/max_contact_pressure_pa" => l.max_pressure,
            "/energy_capacity_j" => l.energy_capacity,
            "/deformation_capacity_m" => l.deformation_capacity,
            "/force_capacity_n" => l.force_capacity,
            _ => panic!("unknown pointer {p}"),
        },
        (ImpactDetail::Hertz(h), p) => match p {
            "/hertz_stiffness_n_m1_5" => h.stiffness,
            "/max_deformation_m" => h.max_deformation,
            "/max_force_n" => h.max_force,
            "/equivalent_radius_m" => h.equivalent_radius,
            "/max_deformation_equivalent_radius_m" => h.max_deformation_equivalent_radius,
            "/contact_ellipse_axis_ratio" => h.axis_ratio,
            _ => panic!("unknown pointer {p}"),
        },
    }
}

#[test]
fn verification_cases_p01_to_p04_and_p14() {
    let mut seen = 0;
    for c in verification_cases() {
        let id = c["id"].as_str().unwrap();
        if !["P01", "P02", "P03", "P04", "P14"]
            .iter()
            .any(|p| id.starts_with(p))
        {
            continue;
        }
        seen += 1;
        let case = from_request(&c["request"]);
        if c.get("expect_error").is_some() {
            assert!(
                matches!(
                    solve_impact(&case),
                    Err(PhysicsError::CapacityExceeded { .. })
                ),
                "{id}"
            );
            continue;
        }
        let r = solve_impact(&case).unwrap();
        for (pointer, expected) in c["expected"].as_object().unwrap() {
            let tol = &c["tolerance"][pointer];
            let (rt, at) = (tol["rel"].as_f64().unwrap(), tol["abs"].as_f64().unwrap());
            let expected = expected.as_f64().unwrap();
            let got = field(&r, pointer);
            assert!(
                (got - expected).abs() <= at + rt * expected.abs(),
                "{id} {pointer}: {got} vs {expected}"
            );
        }
    }
    assert_eq!(seen, 5, "P01–P04 and P14 must all be present in cases.json");
}

// ---------------------------------------------------------------------------------------------
// Direct integration of m δ″ = −P(δ).

/// P(δ) of the log law by inverting δ(P) = P/k·ln(P_ref/P) with a bracketed Newton iteration
/// (independent of the Lambert W code).
fn log_force_independent(k: f64, p_ref: f64, delta: f64) -> f64 {
    if delta <= 0.0 {
        return 0.0;
    }
    let p_cap = p_ref / E;
    let (mut lo, mut hi) = (0.0, p_cap);
    let mut p = (k * delta).min(0.5 * p_cap);
    for _ in 0..200 {
        let f = p / k * (p_ref / p).ln() - delta;
        if f > 0.0 {
            hi = p;
        } else {
            lo = p;
        }
        let d = ((p_ref / p).ln() - 1.0) / k;
        let mut next = p - f / d;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - p).abs() <= 1e-16 * p {
            return next;
        }
        p = next;
    }
    p
}

/// Classical RK4 on (δ, δ̇) until δ̇ = 0; the event is located by re-stepping from the last
/// state with the sub-step found by bisection. Returns (δmax, P(δmax), time of the maximum).
fn integrate_to_maximum(
    mass: f64,
    v: f64,
    force: &dyn Fn(f64) -> f64,
    t_est: f64,
) -> (f64, f64, f64) {
    let n = 200_000;
    let h = 2.0 * t_est / n as f64;
    let acc = |d: f64| -force(d) / mass;
    let step = |d: f64, w: f64, h: f64| {
        let (k1d, k1w) = (w, acc(d));
        let (k2d, k2w) = (w + 0.5 * h * k1w, acc(d + 0.5 * h * k1d));
        let (k3d, k3w) = (w + 0.5 * h * k2w, acc(d + 0.5 * h * k2d));
        let (k4d, k4w) = (w + h * k3w, acc(d + h * k3d));
        (
            d + h / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d),
            w + h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w),
        )
    };
    let (mut d, mut w, mut t) = (0.0, v, 0.0);
    for _ in 0..n {
        let (d1, w1) = step(d, w, h);
        if w1 <= 0.0 {
            let (mut lo, mut hi) = (0.0, h);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if step(d, w, mid).1 > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let hs = 0.5 * (lo + hi);
            let dm = step(d, w, hs).0;
            return (dm, force(dm), t + hs);
        }
        d = d1;
        w = w1;
        t += h;
    }
    panic!("no maximum within the integration window");
}

#[test]
fn ode_integration_matches_closed_form() {
    let mut cases = vec![
        case(ContactLaw::Paper, ModulusConvention::Paper),
        case(ContactLaw::Johnson, ModulusConvention::TwoBody),
        case(ContactLaw::HertzPoint, ModulusConvention::TwoBody),
    ];
    // Near the capacity (G ≈ 0.98) and at tiny G (≈ 1e-13).
    let mut near = case(ContactLaw::Paper, ModulusConvention::Paper);
    near.column.contact_radius = 1.0;
    near.rock.side_length = 0.05;
    near.rock.elastic_modulus = 0.5e9;
    near.velocity = 28.9;
    cases.push(near);
    let mut tiny = case(ContactLaw::Johnson, ModulusConvention::Paper);
    tiny.velocity = 1e-3;
    tiny.column.contact_radius = 0.01;
    cases.push(tiny);
    for c in cases {
        let r = solve_impact(&c).unwrap();
        let (dmax, pmax) = maxima(&r.detail);
        let law = force_law(&c).unwrap();
        let force: Box<dyn Fn(f64) -> f64> = match law {
            ForceLaw::Log { k, p_ref } => Box::new(move |d| log_force_independent(k, p_ref, d)),
            ForceLaw::Hertz { kappa } => Box::new(move |d: f64| kappa * d.max(0.0).powf(1.5)),
        };
        let (d_ode, p_ode, t_half) =
            integrate_to_maximum(r.mass, c.velocity, &*force, 0.5 * r.contact_duration);
        assert!(rel(d_ode, dmax) < 1e-9, "{c:?}: δ {d_ode} vs {dmax}");
        assert!(rel(p_ode, pmax) < 1e-9, "{c:?}: P {p_ode} vs {pmax}");
        // The rigid-column contact is symmetric: the maximum comes at half the duration.
        assert!(rel(2.0 * t_half, r.contact_duration) < 1e-7, "{c:?}: t_c");
    }
}

// ---------------------------------------------------------------------------------------------
// Energy balance ½mv² = ∫₀^δmax P dδ.

#[test]
fn energy_balance_by_quadrature() {
    let opts = QuadOptions {
        rel_tol: 1e-13,
        ..Default::default()
    };
    for law in [
        ContactLaw::Paper,
        ContactLaw::Johnson,
        ContactLaw::HertzPoint,
    ] {
        for modulus in [ModulusConvention::Paper, ModulusConvention::TwoBody] {
            for v in [0.01, 5.0, 60.0] {
                let mut c = case(law, modulus);
                c.velocity = v;
                let r = solve_impact(&c).unwrap();
                let (dmax, pmax) = maxima(&r.detail);
                let f = force_law(&c).unwrap();
                // ∫ P(δ) dδ through the library's W₋₁ inverse …
                let w1 = integrate(|d| f.force(d).unwrap(), &[0.0, dmax], opts);
                assert!(
                    rel(w1.value, r.kinetic_energy) < 1e-11,
                    "{law:?} {v}: {w1:?}"
                );
                // … and ∫ P δ′(P) dP from the explicit law, independent of W.
                if let ForceLaw::Log { k, p_ref } = f {
                    let w2 = integrate(
                        |p: f64| p * ((p_ref / p).ln() - 1.0) / k,
                        &[0.0, 1e-6 * pmax, pmax],
                        opts,
                    );
                    assert!(rel(w2.value, r.kinetic_energy) < 1e-12, "{law:?} {v}");
                }
            }
        }
    }
}

/// t_c·v/δmax = 2∫₀¹ dx/√(1 − x^{5/2}) for P = κδ^{3/2} (substitute x = 1 − s² at the root).
#[test]
fn hertz_duration_factor_by_quadrature() {
    let r = integrate(
        |s: f64| {
            // 1 − x^{5/2} with x = 1 − s², without cancellation at small s.
            let one_minus = -(2.5 * (-s * s).ln_1p()).exp_m1();
            2.0 * s / one_minus.sqrt()
        },
        &[0.0, 0.5, 1.0],
        QuadOptions {
            rel_tol: 1e-14,
            ..Default::default()
        },
    );
    assert!(rel(2.0 * r.value, HERTZ_DURATION_FACTOR) < 1e-13, "{r:?}");
}

// ---------------------------------------------------------------------------------------------
// Against reference.py.

/// u(G), W, and the δ and P factors fed G directly: near the branch point ([1 − 1e-3, 1]) and
/// over the rest of (0, 1].
#[test]
fn branch_point_u_against_reference() {
    let mut gs: Vec<f64> = vec![1.0, 1.0 - 1e-12, 1.0 - 1e-15, 1.0 - f64::EPSILON / 2.0];
    for k in 0..=90 {
        gs.push(1.0 - 1e-3 * 10f64.powf(-(k as f64) / 10.0));
    }
    gs.extend([0.999, 0.9995, 1.0 - 2e-3 + 1e-9, 1.0 - 1e-12 + 1e-16]);
    // And over the whole range G ∈ [1e-300, 0.999) (both initial guesses of §A.5).
    for k in 0..=150 {
        gs.push(10f64.powf(-2.0 * k as f64));
    }
    gs.extend([0.5, 0.3, 0.1, 0.36787944117144233, 0.9, 0.99, 0.998]);
    let out = common_oracle::run(&json!({ "u": gs }));
    let rows = out["u"].as_array().unwrap();
    assert_eq!(rows.len(), gs.len());
    for (g, row) in gs.iter().zip(rows) {
        let (u_ref, w_ref, p_ref, d_ref) = (
            common_oracle::num(&row[0]),
            common_oracle::num(&row[1]),
            common_oracle::num(&row[2]),
            common_oracle::num(&row[3]),
        );
        let u = branch_u(*g).unwrap();
        let w = -1.0 - u;
        // G is fed exactly, so u itself is well determined: a few ulp.
        assert!(
            (u - u_ref).abs() <= 1e-14 * u_ref + 1e-300,
            "G = {g}: u {u} vs {u_ref}"
        );
        assert!((w - w_ref).abs() <= 1e-8, "G = {g}: W");
        assert!(
            (w - w_ref).abs() <= 4e-16 * w_ref.abs(),
            "G = {g}: W {w} vs {w_ref}"
        );
        // e^{−u/2} turns the last-bit error of u (≈ uε) into ≈ uε/2 relative.
        let tol = (u + 4.0) * f64::EPSILON;
        let (pf, df) = ((-0.5 * u).exp(), (-0.5 * u).exp() * (2.0 + u));
        assert!(rel(pf, p_ref) < tol, "G = {g}: P factor {}", rel(pf, p_ref));
        assert!(rel(df, d_ref) < tol, "G = {g}: δ factor {}", rel(df, d_ref));
    }
}

/// From physical inputs near the branch point: δmax to 1e-12 and Pmax to the conditioning bound.
#[test]
fn near_capacity_from_physical_inputs_against_reference() {
    let mut cases = Vec::new();
    // G = 1 is reached near v ≈ 29.19 m/s for R = 1, L = 0.05, E = 0.5 GPa (physics.md §A.5).
    let mut base = case(ContactLaw::Paper, ModulusConvention::Paper);
    base.column.contact_radius = 1.0;
    base.rock.side_length = 0.05;
    base.rock.elastic_modulus = 0.5e9;
    base.velocity = 29.0;
    let ImpactDetail::Line(l) = impact_maxima(&base).unwrap() else {
        panic!()
    };
    let v1 = base.velocity / l.energy_parameter.sqrt();
    for eps in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
        let mut c = base.clone();
        c.velocity = v1 * (1.0 - eps);
        cases.push(c);
    }
    let mut j = base;
    j.contact.law = ContactLaw::Johnson;
    j.contact.modulus = ModulusConvention::TwoBody;
    j.column.contact_radius = 0.01;
    j.rock.side_length = 1.0;
    j.velocity = 1.0;
    let ImpactDetail::Line(lj) = impact_maxima(&j).unwrap() else {
        panic!()
    };
    let vj = j.velocity / lj.energy_parameter.sqrt();
    for eps in [1e-3, 1e-7, 1e-11, 1e-13] {
        let mut c = j.clone();
        c.velocity = vj * (1.0 - eps);
        cases.push(c);
    }
    let req: Vec<Value> = cases.iter().map(common_oracle::to_reference).collect();
    let out = common_oracle::run(&json!({ "cases": req }));
    for (c, o) in cases.iter().zip(out["cases"].as_array().unwrap()) {
        if o.get("error").is_some() {
            // The reference put G above 1: so must we (or G rounds to exactly 1).
            match impact_maxima(c) {
                Err(PhysicsError::CapacityExceeded { .. }) => continue,
                Ok(ImpactDetail::Line(l)) => assert!(l.u == 0.0, "{c:?}"),
                other => panic!("{other:?}"),
            }
            continue;
        }
        let ImpactDetail::Line(l) = impact_maxima(c).unwrap_or_else(|e| panic!("{c:?}: {e}"))
        else {
            panic!()
        };
        let u = o["u"].as_f64().unwrap();
        let d = o["delta_max"].as_f64().unwrap();
        let p = o["P_max"].as_f64().unwrap();
        assert!(
            rel(l.max_deformation, d) < 1e-12,
            "{c:?}: δ {} vs {d}",
            l.max_deformation
        );
        let bound = (1.0 + u) / (2.0 * u) * 4.0 * f64::EPSILON + 1e-15;
        assert!(
            rel(l.max_force, p) < bound,
            "{c:?}: P {} vs {p} (bound {bound})",
            l.max_force
        );
        assert!((l.lambert_w - o["W"].as_f64().unwrap()).abs() < 1e-8);
    }
}

/// 60 random cases over the valid domain, all three laws and both moduli, against reference.py.
#[test]
fn random_cases_against_reference() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(20_231_122);
    let log_uniform = |rng: &mut rand_pcg::Pcg64, lo: f64, hi: f64| {
        (lo.ln() + rng.random::<f64>() * (hi / lo).ln()).exp()
    };
    let mut cases = Vec::new();
    for i in 0..60 {
        let law = [
            ContactLaw::Paper,
            ContactLaw::Johnson,
            ContactLaw::HertzPoint,
        ][i % 3];
        let modulus = [ModulusConvention::Paper, ModulusConvention::TwoBody][(i / 3) % 2];
        let side = log_uniform(&mut rng, 0.01, 5.0);
        let mut c = ImpactCase {
            velocity: log_uniform(&mut rng, 1e-3, 1000.0),
            rock: Rock {
                shape: RockShape::Cube,
                side_length: side,
                density: log_uniform(&mut rng, 100.0, 20000.0),
                elastic_modulus: log_uniform(&mut rng, 1e7, 1e12),
                poisson_ratio: 0.499 * rng.random::<f64>(),
                corner_radius: side / 2.0 * log_uniform(&mut rng, 1e-3, 1.0),
            },
            contact: ContactModel {
                law,
                modulus,
                hertz_exact: i % 7 != 0,
            },
            ..Default::default()
        };
        c.column.elastic_modulus = log_uniform(&mut rng, 1e9, 1e12);
        c.column.poisson_ratio = 0.499 * rng.random::<f64>();
        c.column.contact_radius = log_uniform(&mut rng, 1e-3, 10.0);
        cases.push(c);
    }
    let req: Vec<Value> = cases.iter().map(common_oracle::to_reference).collect();
    let out = common_oracle::run(&json!({ "cases": req }));
    let mut solved = 0;
    let worst = std::cell::RefCell::new(std::collections::BTreeMap::new());
    for (c, o) in cases.iter().zip(out["cases"].as_array().unwrap()) {
        let got = solve_impact(c);
        if let Some(code) = o.get("error") {
            assert_eq!(code, "capacity_exceeded");
            assert!(
                matches!(got, Err(PhysicsError::CapacityExceeded { .. })),
                "{c:?}"
            );
            continue;
        }
        let r = got.unwrap_or_else(|e| panic!("{c:?}: {e}"));
        solved += 1;
        let f = |k: &str| o[k].as_f64().unwrap();
        let chk = |name: &str, got: f64, want: f64, tol: f64| {
            assert!(rel(got, want) <= tol, "{name}: {got} vs {want} in {c:?}");
            let mut w = worst.borrow_mut();
            let e = w.entry(name.to_string()).or_insert(0.0f64);
            *e = e.max(rel(got, want));
        };
        chk("mass", r.mass, f("mass"), 1e-14);
        chk("E*", r.effective_modulus, f("Estar"), 1e-14);
        chk("t_c", r.contact_duration, f("contact_duration_rigid"), 1e-6);
        match &r.detail {
            ImpactDetail::Line(l) => {
                chk("G", l.energy_parameter, f("G"), 1e-9);
                chk("W", l.lambert_w, f("W"), 1e-9);
                chk("δ", l.max_deformation, f("delta_max"), 1e-9);
                chk("P", l.max_force, f("P_max"), 1e-9);
                chk("a", l.half_width, f("half_width"), 1e-9);
                chk("p0", l.max_pressure, f("p0"), 1e-9);
                chk("E_cap", l.energy_capacity, f("E_capacity"), 1e-9);
                chk("δ_cap", l.deformation_capacity, f("delta_capacity"), 1e-9);
                chk("P_cap", l.force_capacity, f("P_capacity"), 1e-9);
            }
            ImpactDetail::Hertz(h) => {
                chk("κ", h.stiffness, f("kappa"), 1e-9);
                chk("δ", h.max_deformation, f("delta_max"), 1e-9);
                chk("P", h.max_force, f("P_max"), 1e-9);
                chk("R_e", h.equivalent_radius, f("Re"), 1e-9);
                chk(
                    "δ_eq",
                    h.max_deformation_equivalent_radius,
                    f("delta_max_equiv_radius"),
                    1e-9,
                );
                chk("b/a", h.axis_ratio, f("axis_ratio_b_over_a"), 1e-9);
            }
        }
    }
    assert!(solved >= 30, "too few solvable random cases: {solved}");
    eprintln!(
        "{solved} solved; worst relative errors: {:?}",
        worst.borrow()
    );
}

/// Exact elliptical Hertz κ over the whole r_c/R range of the API (1e-12 … 2500), against a
/// 60-digit solve in log space.
#[test]
fn hertz_exact_kappa_over_the_ratio_range() {
    let pairs: Vec<(f64, f64)> = [
        (1e-12, 1.0),
        (1e-9, 1.0),
        (1e-6, 1.0),
        (1e-4, 1.0),
        (1e-3, 0.1),
        (0.02, 0.125),
        (0.3, 0.3),
        (1.0, 0.05),
        (2.5, 0.01),
        (2.5, 0.001),
    ]
    .into_iter()
    // and 24 ratios spread over every piece of the fitted starting value (ln ratio −27.6 … 7.8)
    .chain((0..24).map(|i| (1e-12 * 2.5e15f64.powf((i as f64 + 0.37) / 24.0), 1.0)))
    .collect();
    let out = common_oracle::run(&json!({ "hertz": pairs }));
    for ((rc, r), row) in pairs.iter().zip(out["hertz"].as_array().unwrap()) {
        let m_ref = common_oracle::num(&row[0]);
        let kappa_ref = common_oracle::num(&row[3]);
        let h = gangue::physics::contact::hertz_geometry(1.0, *rc, *r, true);
        assert!(
            rel(h.stiffness, kappa_ref) < 1e-13,
            "rc {rc} R {r}: κ/E* {} vs {kappa_ref}",
            h.stiffness
        );
        assert!(
            rel(h.eccentricity_squared, m_ref) < 1e-12,
            "rc {rc} R {r}: m"
        );
        assert!(
            rel(h.axis_ratio, (1.0 - m_ref).sqrt()) < 1e-12,
            "rc {rc} R {r}: b/a"
        );
    }
    // Below r_c/R = 1e-12: the circular limit κ → (4/3)E*√R_e.
    for rc in [1e-20, 1e-100, 1e-300, 5e-324] {
        let h = gangue::physics::contact::hertz_geometry(1.0, rc, 10.0, true);
        assert!(
            rel(h.stiffness, h.stiffness_equivalent_radius) < 1e-15,
            "rc {rc}"
        );
        assert!(h.axis_ratio <= 1.0 && h.axis_ratio > 1.0 - 1e-12);
    }
    let _ = PI;
}

//! The contact solver over the whole valid domain of api.md: no panic, no NaN or infinity, the
//! capacity decision exactly at G = 1, monotone maxima in v, and correct answers where G
//! underflows (v down to 1e-300).

mod common_oracle;

use gangue::physics::PhysicsError;
use gangue::physics::contact::{
    ForceLaw, ImpactDetail, force_curve, force_law, impact_maxima, solve_impact,
};
use gangue::physics::material::{
    ContactLaw, ContactModel, ImpactCase, ModulusConvention, Rock, RockShape,
};
use proptest::prelude::*;
use serde_json::{Value, json};

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn log_range(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..=hi.ln()).prop_map(f64::exp)
}

fn law() -> impl Strategy<Value = ContactLaw> {
    prop_oneof![
        Just(ContactLaw::Paper),
        Just(ContactLaw::Johnson),
        Just(ContactLaw::HertzPoint)
    ]
}

fn modulus() -> impl Strategy<Value = ModulusConvention> {
    prop_oneof![
        Just(ModulusConvention::Paper),
        Just(ModulusConvention::TwoBody)
    ]
}

/// Any case of the valid domain (velocity drawn separately), v in (0, 1000].
fn any_case() -> impl Strategy<Value = ImpactCase> {
    (
        (
            log_range(0.01, 5.0),
            log_range(100.0, 20000.0),
            log_range(1e7, 1e12),
            0.0..0.5f64,
            log_range(1e-300, 1.0),
        ),
        (log_range(1e9, 1e12), 0.0..0.5f64, log_range(1e-3, 10.0)),
        (law(), modulus(), any::<bool>(), log_range(1e-300, 1000.0)),
    )
        .prop_map(
            |((side, density, e, nu, rc_frac), (es, nus, r), (law, modulus, exact, v))| {
                let mut c = ImpactCase {
                    velocity: v,
                    rock: Rock {
                        shape: RockShape::Cube,
                        side_length: side,
                        density,
                        elastic_modulus: e,
                        poisson_ratio: nu,
                        corner_radius: (side / 2.0 * rc_frac).min(side / 2.0),
                    },
                    contact: ContactModel {
                        law,
                        modulus,
                        hertz_exact: exact,
                    },
                    ..Default::default()
                };
                c.column.elastic_modulus = es;
                c.column.poisson_ratio = nus;
                c.column.contact_radius = r;
                c
            },
        )
}

fn check_finite(c: &ImpactCase) -> Result<(), TestCaseError> {
    match solve_impact(c) {
        Ok(r) => {
            prop_assert!(r.mass > 0.0 && r.mass.is_finite());
            prop_assert!(r.kinetic_energy >= 0.0 && r.kinetic_energy.is_finite());
            prop_assert!(r.effective_modulus > 0.0 && r.effective_modulus.is_finite());
            prop_assert!(
                r.contact_duration > 0.0 && r.contact_duration.is_finite(),
                "t_c = {}",
                r.contact_duration
            );
            match r.detail {
                ImpactDetail::Line(l) => {
                    for x in [
                        l.max_deformation,
                        l.max_force,
                        l.half_width,
                        l.max_pressure,
                        l.energy_capacity,
                        l.deformation_capacity,
                        l.force_capacity,
                    ] {
                        prop_assert!(x >= 0.0 && x.is_finite(), "{l:?}");
                    }
                    // δ, P ∝ v (log-corrected): positive unless v is within 1e-15 of the
                    // subnormal floor, where their true values are below 5e-324.
                    if c.velocity > 1e-300 {
                        prop_assert!(l.max_deformation > 0.0 && l.max_force > 0.0, "{l:?}");
                    }
                    prop_assert!(l.energy_parameter >= 0.0 && l.energy_parameter <= 1.0);
                    prop_assert!(l.u >= 0.0 && l.u.is_finite() && l.lambert_w <= -1.0);
                    prop_assert!(l.max_deformation <= l.deformation_capacity);
                    prop_assert!(l.max_force <= l.force_capacity);
                }
                ImpactDetail::Hertz(h) => {
                    for x in [
                        h.max_deformation,
                        h.stiffness,
                        h.equivalent_radius,
                        h.max_deformation_equivalent_radius,
                        h.axis_ratio,
                        h.semi_axes[0],
                        h.semi_axes[1],
                        h.max_pressure,
                    ] {
                        prop_assert!(x >= 0.0 && x.is_finite(), "{h:?}");
                    }
                    prop_assert!(h.max_deformation > 0.0 && h.stiffness > 0.0, "{h:?}");
                    // Pmax ∝ v^{6/5} may underflow to 0 at v ~ 1e-300; never negative or NaN.
                    prop_assert!(h.max_force >= 0.0 && h.max_force.is_finite());
                    prop_assert!(h.axis_ratio <= 1.0);
                }
            }
        }
        Err(PhysicsError::CapacityExceeded {
            energy_parameter,
            max_velocity_m_s,
            ..
        }) => {
            prop_assert!(c.contact.law != ContactLaw::HertzPoint);
            prop_assert!(energy_parameter > 1.0 && energy_parameter.is_finite());
            prop_assert!(max_velocity_m_s > 0.0 && max_velocity_m_s < c.velocity);
        }
        Err(e) => prop_assert!(false, "unexpected error {e}"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Every valid case gives finite, positive numbers or capacity_exceeded.
    #[test]
    fn finite_everywhere(c in any_case()) {
        check_finite(&c)?;
    }

    /// G ≤ 1 never errors, G > 1 always does; the reported speed is where G = 1.
    #[test]
    fn capacity_decision(c in any_case()) {
        prop_assume!(c.contact.law != ContactLaw::HertzPoint);
        // G from the formulas of physics.md §A.5, in plain f64.
        let es = gangue::physics::contact::effective_modulus(&c.rock, &c.column, c.contact.modulus);
        let (l, r, m) = (c.rock.side_length, c.column.contact_radius, c.rock.mass());
        let g_over_v2 = match c.contact.law {
            ContactLaw::Paper => 2.0 * m * r * r / (std::f64::consts::PI * es * l.powi(5)),
            _ => std::f64::consts::E.powi(4) * m / (8.0 * std::f64::consts::PI * l * es * r * r),
        };
        let g = g_over_v2 * c.velocity * c.velocity;
        match impact_maxima(&c) {
            Ok(ImpactDetail::Line(line)) => {
                prop_assert!(g <= 1.0 + 1e-13, "solved with G = {g}");
                prop_assert!(line.energy_parameter <= 1.0);
                if g > 1e-290 {
                    prop_assert!(rel(line.energy_parameter, g) < 1e-13);
                }
            }
            Err(PhysicsError::CapacityExceeded { energy_parameter, max_velocity_m_s, .. }) => {
                prop_assert!(g > 1.0 - 1e-13, "refused G = {g}");
                prop_assert!(rel(energy_parameter, g) < 1e-13);
                let mut below = c.clone();
                below.velocity = max_velocity_m_s * (1.0 - 1e-9);
                prop_assert!(impact_maxima(&below).is_ok());
                let mut above = c.clone();
                above.velocity = max_velocity_m_s * (1.0 + 1e-9);
                let refused = matches!(
                    impact_maxima(&above),
                    Err(PhysicsError::CapacityExceeded { .. })
                );
                prop_assert!(refused);
            }
            other => prop_assert!(false, "{other:?}"),
        }
    }

    /// δmax and Pmax grow with v (the other inputs fixed).
    #[test]
    fn monotone_in_velocity(c in any_case(), f in 1.0001..3.0f64) {
        let mut c2 = c.clone();
        c2.velocity = (c.velocity * f).min(1000.0);
        prop_assume!(c2.velocity > c.velocity);
        if let (Ok(a), Ok(b)) = (impact_maxima(&c), impact_maxima(&c2)) {
            let (da, pa, db, pb) = match (a, b) {
                (ImpactDetail::Line(a), ImpactDetail::Line(b)) =>
                    (a.max_deformation, a.max_force, b.max_deformation, b.max_force),
                (ImpactDetail::Hertz(a), ImpactDetail::Hertz(b)) =>
                    (a.max_deformation, a.max_force, b.max_deformation, b.max_force),
                _ => unreachable!(),
            };
            prop_assert!(db > da, "δ {da} → {db}");
            prop_assert!(pb >= pa, "P {pa} → {pb}");
        }
    }

    /// The force law is finite and increasing on [0, δ_cap] and its curve is finite.
    #[test]
    fn force_law_finite_and_monotone(c in any_case(), n in 2usize..50) {
        let law = force_law(&c).unwrap();
        let dmax = match impact_maxima(&c) {
            Ok(ImpactDetail::Line(l)) => l.max_deformation,
            Ok(ImpactDetail::Hertz(h)) => h.max_deformation,
            Err(_) => law.deformation_capacity().unwrap(),
        };
        let (d, p) = force_curve(&law, dmax, n);
        prop_assert_eq!(d.len(), n);
        for w in p.windows(2) {
            prop_assert!(w[1].is_finite() && w[1] >= w[0]);
        }
        if let ForceLaw::Log { .. } = law {
            let cap = law.deformation_capacity().unwrap();
            prop_assert!(law.force(cap).is_some_and(|x| x.is_finite() && x > 0.0));
        }
    }
}

/// Corners of the domain, every law and modulus: all finite.
#[test]
fn domain_corners() {
    let mut n = 0;
    for v in [1e-300, 5e-324, 1e-150, 1.0, 1000.0] {
        for side in [0.01, 5.0] {
            for density in [100.0, 20000.0] {
                for e in [1e7, 1e12] {
                    for r in [1e-3, 10.0] {
                        for rc in [5e-324, 1e-300, 1e-3 * side, side / 2.0] {
                            for law in [
                                ContactLaw::Paper,
                                ContactLaw::Johnson,
                                ContactLaw::HertzPoint,
                            ] {
                                for modulus in
                                    [ModulusConvention::Paper, ModulusConvention::TwoBody]
                                {
                                    for (nu, es) in [(0.0, 1e9), (0.4999999, 1e12)] {
                                        let mut c = ImpactCase::default();
                                        c.velocity = v;
                                        c.rock.side_length = side;
                                        c.rock.density = density;
                                        c.rock.elastic_modulus = e;
                                        c.rock.poisson_ratio = nu;
                                        c.rock.corner_radius = rc;
                                        c.column.contact_radius = r;
                                        c.column.elastic_modulus = es;
                                        c.column.poisson_ratio = nu;
                                        c.contact.law = law;
                                        c.contact.modulus = modulus;
                                        c.contact.hertz_exact = rc != 1e-300;
                                        if let Err(e) = check_finite(&c) {
                                            panic!("{c:?}: {e}");
                                        }
                                        n += 1;
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    assert_eq!(n, 3840);
    // A sphere of the API's radius range with the Hertz law.
    for radius in [0.005, 2.5] {
        let mut c = ImpactCase::default();
        c.rock.shape = RockShape::Sphere { radius };
        c.contact.law = ContactLaw::HertzPoint;
        for r in [1e-3, 10.0] {
            c.column.contact_radius = r;
            check_finite(&c).unwrap();
        }
    }
}

/// Where G itself underflows (v → 1e-300), δ, P and t_c still match the 50-digit reference.
#[test]
fn underflowing_energy_parameter_against_reference() {
    let mut cases = Vec::new();
    for v in [1e-300, 1e-200, 1e-160, 1e-100, 1e-20] {
        for law in [
            ContactLaw::Paper,
            ContactLaw::Johnson,
            ContactLaw::HertzPoint,
        ] {
            for modulus in [ModulusConvention::Paper, ModulusConvention::TwoBody] {
                let mut c = ImpactCase::default();
                c.velocity = v;
                c.contact.law = law;
                c.contact.modulus = modulus;
                cases.push(c);
            }
        }
    }
    let req: Vec<Value> = cases.iter().map(common_oracle::to_reference).collect();
    let out = common_oracle::run(&json!({ "cases": req }));
    for (c, o) in cases.iter().zip(out["cases"].as_array().unwrap()) {
        let r = solve_impact(c).unwrap();
        let f = |k: &str| o[k].as_f64().unwrap();
        let (d, p) = match &r.detail {
            ImpactDetail::Line(l) => {
                assert!(rel(l.lambert_w, f("W")) < 1e-14, "{c:?}: W");
                (l.max_deformation, l.max_force)
            }
            ImpactDetail::Hertz(h) => (h.max_deformation, h.max_force),
        };
        assert!(
            rel(d, f("delta_max")) < 1e-12,
            "{c:?}: δ {d} vs {}",
            f("delta_max")
        );
        let p_ref = f("P_max");
        if p_ref >= f64::MIN_POSITIVE {
            assert!(rel(p, p_ref) < 1e-12, "{c:?}: P {p} vs {p_ref}");
        } else {
            assert!(p <= 2.0 * f64::MIN_POSITIVE, "{c:?}: P {p} vs {p_ref}");
        }
        assert!(
            rel(r.contact_duration, f("contact_duration_rigid")) < 1e-8,
            "{c:?}: t_c {} vs {}",
            r.contact_duration,
            f("contact_duration_rigid")
        );
    }
}

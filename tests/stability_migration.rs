//! Property tests over api.md's whole migration domain: every valid case gives finite numbers
//! and an energy balance closed to 1e-9 of the starting energy, on the plane and on rough grids.

use gangue::physics::Control;
use gangue::physics::PhysicsError;
use gangue::physics::migration::{FloorSpec, MigrationCase, MigrationResult, Motion, run};
use proptest::prelude::*;

fn finite(r: &MigrationResult) -> bool {
    let a = &r.arrival;
    let e = &r.energy;
    [
        a.time,
        a.speed,
        a.along_dip_velocity,
        a.normal_velocity,
        a.along_dip,
        a.normal_offset,
        a.angular_speed,
        a.kinetic_energy,
        a.rotational_energy,
        e.total_start,
        e.impacts,
        e.friction,
        e.transition,
        e.residual,
        r.max_bounce_height,
    ]
    .iter()
    .chain(a.position.iter())
    .all(|x| x.is_finite())
        && r.slide_start_along_dip.is_none_or(f64::is_finite)
        && r.stop_along_dip.is_none_or(f64::is_finite)
}

fn check_balance(r: &MigrationResult) -> Result<(), TestCaseError> {
    prop_assert!(finite(r), "non-finite output {r:?}");
    let e = &r.energy;
    prop_assert!(
        e.residual.abs() <= 1e-9 * e.total_start.abs().max(1e-300),
        "residual {} of {}",
        e.residual,
        e.total_start
    );
    prop_assert!(e.impacts >= 0.0 && e.friction >= -1e-9 * e.total_start && e.transition >= 0.0);
    Ok(())
}

prop_compose! {
    fn plane_case()(
        dip in 5.0..=80.0f64,
        length in prop_oneof![0.01..=10.0f64, 10.0..=10000.0f64],
        mu in 0.0..=2.0f64,
        en in 0.0..=1.0f64,
        et in 0.0..=1.0f64,
        h in prop_oneof![Just(0.0), 0.0..=1000.0f64],
        along_frac in 0.0..1.0f64,
        across in -1000.0..=1000.0f64,
        speed in prop_oneof![Just(0.0), 0.0..=1000.0f64],
        v_stop in prop_oneof![Just(0.0), 0.0..=100.0f64],
        g in 0.1..=100.0f64,
        roll in any::<bool>(),
        end_time in prop_oneof![Just(None), (0.001..=1e5f64).prop_map(Some)],
        side in 0.01..=5.0f64,
        rho in 100.0..=20000.0f64,
    ) -> MigrationCase {
        let mut c = MigrationCase::default();
        c.face.dip_deg = dip;
        c.face.length = length;
        let mu_roll = 2.0 / 7.0 * dip.to_radians().tan();
        c.face.friction_coefficient = if roll { mu.max(mu_roll) } else { mu };
        c.face.restitution_normal = en;
        c.face.restitution_tangential = et;
        c.release.drop_height = h;
        c.release.along_dip = along_frac * length;
        c.release.across = across;
        c.release.speed = speed;
        c.lumped_mass.stop_normal_speed = v_stop;
        c.lumped_mass.motion = if roll && c.face.friction_coefficient <= 2.0 { Motion::Roll } else { Motion::Slide };
        c.gravity = g;
        c.end_time = end_time;
        c.rock.side_length = side;
        c.rock.density = rho;
        c
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Plane floor, whole domain: finite, balanced, and a stop reason consistent with the state.
    #[test]
    fn plane_cases_are_finite_and_balanced(c in plane_case()) {
        let r = run(&c, &Control::unlimited());
        let r = match r {
            Ok(r) => r,
            Err(PhysicsError::TooManySteps { .. }) => return Ok(()),
            Err(e) => return Err(TestCaseError::fail(format!("{e:?}"))),
        };
        check_balance(&r)?;
        prop_assert!(r.arrival.along_dip <= c.face.length * (1.0 + 1e-12) + 1e-9);
    }
}

fn rough_grid(seed: u64, dip: f64, d: f64, amp: f64) -> FloorSpec {
    let tan = dip.to_radians().tan();
    let mut s = seed;
    let nx = (40.0 / d) as usize + 2;
    let ny = (12.0 / d) as usize + 2;
    let heights = (0..ny)
        .map(|_| {
            (0..nx)
                .map(|j| {
                    let r = gangue::physics::migration::monte_carlo::splitmix64(&mut s);
                    let u = (r >> 11) as f64 / 9_007_199_254_740_992.0;
                    -(j as f64 * d) * tan + amp * (u - 0.5)
                })
                .collect()
        })
        .collect();
    FloorSpec::Grid {
        origin: [0.0, -6.0],
        spacing: d,
        heights,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Rough grids (random heights about a plane): edges, take-offs, projections and rest on
    /// facets keep the balance and stay finite.
    #[test]
    fn rough_grid_cases_are_finite_and_balanced(
        seed in any::<u64>(),
        dip in 10.0..=60.0f64,
        d in 0.2..=2.0f64,
        amp in 0.0..=0.5f64,
        mu in 0.0..=1.0f64,
        en in 0.0..=0.9f64,
        et in 0.0..=1.0f64,
        h in 0.0..=5.0f64,
        across in -4.0..=4.0f64,
        speed in 0.0..=10.0f64,
        roll in any::<bool>(),
    ) {
        let mut c = MigrationCase::default();
        c.face.dip_deg = dip;
        c.face.length = 40.0;
        c.face.floor = rough_grid(seed, dip, d, amp);
        let mu_roll = 2.0 / 7.0 * dip.to_radians().tan();
        c.face.friction_coefficient = if roll { mu.max(mu_roll) } else { mu };
        c.lumped_mass.motion = if roll { Motion::Roll } else { Motion::Slide };
        c.face.restitution_normal = en;
        c.face.restitution_tangential = et;
        c.release.drop_height = h;
        c.release.along_dip = 1.0;
        c.release.across = across;
        c.release.speed = speed;
        c.end_time = Some(60.0);
        c.max_steps_per_run = 2_000_000;
        match run(&c, &Control::unlimited()) {
            Ok(r) => check_balance(&r)?,
            Err(PhysicsError::TooManySteps { .. }) => {}
            Err(e) => return Err(TestCaseError::fail(format!("{e:?}"))),
        }
    }
}

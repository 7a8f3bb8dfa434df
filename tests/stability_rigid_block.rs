//! Property tests of the rigid-block DEM over shapes, stiffness, damping, friction, dip, gravity
//! and release across api.md's ranges: every run either answers with finite numbers or refuses
//! with a named 422 (too soft, too many steps); no energy is gained without a source (damping and
//! friction never negative, KE + PE + stored never above the energy at release beyond the
//! scheme's error), the energy account closes to the scheme's accuracy, and a block never sinks
//! deeper than its impact energy allows (nor, when released at rest on the floor, more than a
//! few static overlaps).
//!
//! On grid floors, released anywhere up to and across the floor's edges (the upper edge, the
//! lateral ones) and next to holes, over valleys and ridges, a block never gains energy either,
//! and over valleys and ridges it loses none unbooked (no `energy_unaccounted`; random relief,
//! whose floor peaks may still switch off while compressed, is exempt): a corner that goes off
//! the floor below its level ends the run (`left_floor`) instead of coming back over the floor
//! already deep, and the run's own invariant (energy never created) never fires.
//!
//! Runs are capped at a few thousand steps so that the suite stays fast; run longer with
//! `PROPTEST_CASES=2000 cargo test --release --test stability_rigid_block`.

use gangue::physics::Control;
use gangue::physics::material::RockShape;
use gangue::physics::migration::{
    ContactModel, FloorSpec, Method, MigrationCase, MigrationResult, StopReason, run,
};
use gangue::physics::{Param, PhysicsError};
use proptest::prelude::*;

fn shape() -> impl Strategy<Value = RockShape> {
    prop_oneof![
        Just(RockShape::Cube),
        (0.005..=2.5f64).prop_map(|radius| RockShape::Sphere { radius }),
        prop::array::uniform3(0.01..=5.0f64)
            .prop_map(|dimensions| RockShape::Cuboid { dimensions }),
        (
            prop::array::uniform3(0.005..=2.5f64),
            4usize..=60,
            any::<u64>()
        )
            .prop_map(|(semi_axes, vertices, seed)| RockShape::RandomPolyhedron {
                semi_axes,
                vertices,
                seed,
            }),
    ]
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![Just(lo), Just(hi), (lo.ln()..=hi.ln()).prop_map(f64::exp)]
}

prop_compose! {
    fn case()(
        shape in shape(),
        side in 0.01..=5.0f64,
        rho in 100.0..=20000.0f64,
        dip in 5.0..=80.0f64,
        mu in 0.0..=2.0f64,
        kn in log_uniform(1e3, 1e12),
        ks in log_uniform(1e3, 1e12),
        beta in prop_oneof![Just(0.0), 0.0..0.999f64],
        alpha in prop_oneof![Just(0.0), Just(0.0), 0.0..0.99f64],
        hertz in prop::bool::weighted(0.2),
        e_rock in log_uniform(1e7, 1e12),
        h in prop_oneof![Just(0.0), 0.0..=3.0f64],
        speed in prop_oneof![Just(0.0), 0.0..=20.0f64],
        g in prop_oneof![Just(9.81), 0.1..=100.0f64],
        end_time in 0.01..=0.5f64,
    ) -> MigrationCase {
        let mut c = MigrationCase { method: Method::RigidBlock, ..MigrationCase::default() };
        c.rock.shape = shape;
        c.rock.side_length = side;
        c.rock.density = rho;
        c.rock.elastic_modulus = e_rock;
        c.rock.corner_radius = 0.02f64.min(side / 2.0);
        c.face.dip_deg = dip;
        c.face.friction_coefficient = mu;
        c.face.length = 50.0;
        c.gravity = g;
        c.release.drop_height = h;
        c.release.speed = speed;
        c.end_time = Some(end_time);
        c.rigid_block.normal_stiffness = kn;
        c.rigid_block.shear_stiffness = ks;
        c.rigid_block.critical_damping_ratio = beta;
        c.rigid_block.local_damping = alpha;
        c.rigid_block.contact_model = if hertz { ContactModel::Hertz } else { ContactModel::Linear };
        c.rigid_block.max_steps = 20_000.0;
        c.output.events = true;
        c
    }
}

fn check(c: &MigrationCase, r: &MigrationResult) -> Result<(), TestCaseError> {
    check_within(c, r, 1.0)
}

/// [`check`] with the energy tolerances multiplied by `factor`.
fn check_within(c: &MigrationCase, r: &MigrationResult, factor: f64) -> Result<(), TestCaseError> {
    let a = &r.arrival;
    let e = &r.energy;
    let rb = r.rigid_block.unwrap();
    let all = [
        a.time,
        a.speed,
        a.along_dip,
        a.normal_offset,
        a.angular_speed,
        a.kinetic_energy,
        e.total_start,
        e.friction,
        e.damping,
        e.stored,
        e.residual,
        r.max_bounce_height,
    ];
    prop_assert!(all.iter().all(|x| x.is_finite()), "{r:?}");
    // the energy the block can spend: its potential drop over its travel plus its start energy
    let m = rb.mass;
    // (with the springs' own scale: ten static overlaps and ten static shear displacements)
    let shear = match c.rigid_block.contact_model {
        ContactModel::Linear => m * c.gravity / c.rigid_block.shear_stiffness,
        ContactModel::Hertz => rb.static_overlap,
    };
    let travel = a.along_dip.abs() + c.release.drop_height + 10.0 * (rb.static_overlap + shear);
    let scale = m * c.gravity * travel + 0.5 * m * c.release.speed.powi(2) + 1e-12;
    // dissipation is booked with the step's mean velocities: it can dip below zero by the
    // scheme's error where a slip reverses within a step (a rolling sphere's micro-slip)
    let tiny = -1e-4 * scale;
    prop_assert!(
        e.damping >= tiny && e.friction >= tiny && e.stored >= 0.0,
        "{e:?} scale {scale}"
    );
    // Mid-contact (a run may end there) the leapfrog's shadow energy differs from the true one
    // by O(ω Δt) of the elastic energy in the springs: half of it is allowed on top.
    let mid = 0.5 * e.stored;
    // the account closes to the scheme's accuracy: 0.2 % of the energy in play with the linear
    // law (the largest seen over 364 cases of this seed: 6.6e-4); the Hertz law's step is set
    // by the static load (physics.md §C.3), so hard impacts, which stiffen the contact further,
    // are resolved more coarsely: 1 % (largest seen beyond the mid-contact allowance: 3.0e-3).
    // (Before the shear springs' work was booked over their drifts and the change of
    // |Fₛ|²/2kₛ with kₛ was booked, these were 2 % and 10 %.)
    let tol = factor
        * match c.rigid_block.contact_model {
            ContactModel::Linear => 2e-3,
            ContactModel::Hertz => 1e-2,
        };
    // no energy gained: what remains (KE + PE + stored, whatever the bookkeeping) never exceeds
    // the start beyond the scheme's error
    let remaining = e.total_start - e.damping - e.friction + e.residual;
    prop_assert!(
        remaining <= e.total_start + tol * scale + mid,
        "{e:?} scale {scale}"
    );

    // a loss the account cannot book (a contact switched off on the floor's relief while
    // compressed), or a gain beyond the step's error, is answered with the
    // `energy_unaccounted` warning, and only such a residual is
    let warned = r.warnings.iter().any(|w| w.code == "energy_unaccounted");
    prop_assert!(!warned || e.residual != 0.0, "{:?} {e:?}", r.warnings);
    prop_assert!(
        e.residual <= tol * scale + mid && (warned || e.residual >= -(tol * scale + mid)),
        "residual {} of scale {scale}: {e:?}",
        e.residual
    );
    // depth: the elastic energy of one spring cannot exceed the energy available
    let kn = c.rigid_block.normal_stiffness;
    let depth_bound = match c.rigid_block.contact_model {
        ContactModel::Linear => (2.0 * scale / kn).sqrt(),
        // Hertz: (8/15) E*√r U^{5/2} ≤ scale, with E* ≥ 1/(1/E + 1/4.38e9)·(some factor ≥ 0.5)
        ContactModel::Hertz => f64::INFINITY,
    };
    prop_assert!(
        rb.max_overlap <= 2.0 * depth_bound + 5.0 * rb.static_overlap,
        "overlap {} bound {depth_bound} static {}",
        rb.max_overlap,
        rb.static_overlap
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn rigid_block_runs_are_finite_and_gain_no_energy(c in case()) {
        match run(&c, &Control::unlimited()) {
            Ok(r) => check(&c, &r)?,
            Err(PhysicsError::InvalidInput { param, .. }) => {
                prop_assert!(
                    matches!(param, Param::FaceNormalStiffness | Param::RockElasticModulus),
                    "{param:?}"
                );
            }
            Err(PhysicsError::TooManySteps { estimated, limit }) => {
                prop_assert!(estimated > 0.0 && limit == 20_000.0);
            }
            Err(e) => prop_assert!(false, "unexpected error {e:?}"),
        }
    }

    #[test]
    fn a_cube_released_on_its_face_sinks_only_its_static_overlap(
        dip in 5.0..=40.0f64,
        mu in 0.0..=2.0f64,
        kn in log_uniform(1e5, 1e12),
        beta in 0.05..0.999f64,
        side in 0.05..=5.0f64,
    ) {
        let mut c = MigrationCase { method: Method::RigidBlock, ..MigrationCase::default() };
        c.rock.side_length = side;
        c.face.dip_deg = dip;
        c.face.friction_coefficient = mu;
        c.release.drop_height = 0.0;
        c.end_time = Some(0.05);
        c.rigid_block.normal_stiffness = kn;
        c.rigid_block.shear_stiffness = kn;
        c.rigid_block.critical_damping_ratio = beta;
        c.rigid_block.max_steps = 20_000.0;
        match run(&c, &Control::unlimited()) {
            Ok(r) => {
                let rb = r.rigid_block.unwrap();
                // the down-dip load on the shear springs tips the contact forces towards the
                // lower edge: (1 + tan θ) times the mean per contact, at most twice that while
                // the suddenly applied shear load overshoots
                let bound = 2.0 * (1.0 + dip.to_radians().tan()) * rb.static_overlap;
                prop_assert!(
                    rb.max_overlap <= bound,
                    "{} vs {} (static {})",
                    rb.max_overlap,
                    bound,
                    rb.static_overlap
                );
            }
            Err(PhysicsError::InvalidInput { .. }) | Err(PhysicsError::TooManySteps { .. }) => {}
            Err(e) => prop_assert!(false, "unexpected error {e:?}"),
        }
    }
}

/// A pseudo-random number in [−1, 1) from (seed, i, j) (SplitMix64): a node's roughness.
fn noise(seed: u64, i: usize, j: usize) -> f64 {
    let mut z = seed
        .wrapping_add((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
        .wrapping_add((j as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_133F_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 * 2f64.powi(-52) - 1.0
}

prop_compose! {
    /// A rigid-block case on a grid floor of dip θ: x in [0, X], y in [−W, W], spacing d, node
    /// heights −x tan θ + roughness·d·noise, valleys or ridges across the dip (a column of
    /// nodes in every few lowered or lifted), a few nodes without data (holes); the
    /// block released at (along, across) anywhere from the upper edge (along 0) and up to the
    /// lateral edges (|across| up to W), dropped or placed on the floor.
    fn grid_case()(
        shape in prop_oneof![
            Just(RockShape::Cube),
            prop::array::uniform3(0.05..=2.0f64)
                .prop_map(|dimensions| RockShape::Cuboid { dimensions }),
            (prop::array::uniform3(0.05..=1.0f64), 4usize..=30, any::<u64>())
                .prop_map(|(semi_axes, vertices, seed)| RockShape::RandomPolyhedron {
                    semi_axes,
                    vertices,
                    seed,
                }),
            (0.05..=1.0f64).prop_map(|radius| RockShape::Sphere { radius }),
        ],
        side in 0.05..=2.0f64,
        dip in 15.0..=60.0f64,
        mu in 0.0..=1.0f64,
        d in prop_oneof![Just(1.0), 0.2..=2.0f64],
        x_len in 4.0..=16.0f64,
        half_width in 1.0..=6.0f64,
        // relief up to ±5 % of the spacing (±2.5 cm on the 0.5 m grid)
        rough in prop_oneof![Just(0.0), 0.0..=0.1f64],
        // valleys (< 0) or ridges (> 0) across the dip: every `every`-th column of nodes
        // lifted by `crease` times the spacing
        crease in prop_oneof![Just(0.0), -0.6..=0.6f64],
        every in 2usize..=6,
        hole_rate in prop_oneof![Just(0.0), 0.0..=0.05f64],
        seed in any::<u64>(),
        along_frac in prop_oneof![Just(0.0), 0.0..=0.05f64, 0.0..=1.0f64],
        across_frac in prop_oneof![Just(0.0), Just(1.0), Just(-1.0), -1.0..=1.0f64],
        h in prop_oneof![Just(0.0), 0.0..=3.0f64],
        speed in prop_oneof![Just(0.0), 0.0..=5.0f64],
        beta in 0.05..0.9f64,
        end_time in 0.2..=1.0f64,
    ) -> (MigrationCase, bool) {
        let t = dip.to_radians().tan();
        let nx = (x_len / d).ceil() as usize + 1;
        let ny = (2.0 * half_width / d).ceil() as usize + 1;
        let heights: Vec<Vec<f64>> = (0..ny)
            .map(|i| {
                (0..nx)
                    .map(|j| {
                        let hole = hole_rate > 0.0
                            && noise(seed ^ 0x55, i, j) * 0.5 + 0.5 < hole_rate;
                        if hole {
                            f64::NAN
                        } else {
                            let lift = if j % every == every / 2 { crease * d } else { 0.0 };
                            -(j as f64) * d * t + rough * d * noise(seed, i, j) + lift
                        }
                    })
                    .collect()
            })
            .collect();
        let (x_max, y_half) = ((nx - 1) as f64 * d, (ny - 1) as f64 * d / 2.0);
        let mut c = MigrationCase { method: Method::RigidBlock, ..MigrationCase::default() };
        c.rock.shape = shape;
        c.rock.side_length = side;
        c.face.dip_deg = dip;
        c.face.friction_coefficient = mu;
        c.face.length = x_max / dip.to_radians().cos();
        c.face.floor = FloorSpec::Grid { origin: [0.0, -y_half], spacing: d, heights };
        c.release.along_dip = along_frac * 0.9 * c.face.length;
        c.release.across = across_frac * y_half;
        // dropped or placed: placed on a rough floor, it is lifted onto the relief around it
        c.release.drop_height = h;
        c.release.speed = speed;
        c.end_time = Some(end_time);
        c.rigid_block.critical_damping_ratio = beta;
        c.rigid_block.max_steps = 20_000.0;
        c.output.events = true;
        (c, rough > 0.0 || hole_rate > 0.0)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Grid floors with their edges, holes, valleys and ridges: no energy gained (none lost
    /// unbooked but on random relief), never sunk deeper than the
    /// energy in play allows, the run's invariant never fired; a block that goes over an edge
    /// or into a hole stops with `left_floor`.
    #[test]
    fn rigid_block_on_grid_floors_gains_no_energy_at_their_edges(
        (c, random_relief) in grid_case()
    ) {
        match run(&c, &Control::unlimited()) {
            Ok(r) => {
                // the plane's tolerances × 2.5: runs that stop on landing across an edge end
                // mid-contact more often (largest seen with this seed: 4.0e-3 of the energy in
                // play, the mid-contact allowance included)
                check_within(&c, &r, 2.5)?;
                // nothing lost unbooked over valleys and ridges: a corner's overlap is its
                // depth below the surface, continuous across creases (before, a block striking
                // a valley's flank lost about 1 % of its energy there, dt-independent)
                prop_assert!(
                    random_relief || r.warnings.iter().all(|w| w.code != "energy_unaccounted"),
                    "{:?} {:?}",
                    r.warnings,
                    r.energy
                );
                prop_assert!(
                    matches!(
                        r.arrival.stop_reason,
                        StopReason::EndTime | StopReason::LeftFloor | StopReason::AtRest
                            | StopReason::LowerEnd
                    ),
                    "{:?}",
                    r.arrival
                );
            }
            Err(PhysicsError::InvalidInput { param, .. }) => {
                prop_assert!(
                    matches!(
                        param,
                        Param::FaceNormalStiffness | Param::RockElasticModulus
                            | Param::ReleaseAlongDip | Param::ReleaseAcross
                    ),
                    "{param:?}"
                );
            }
            Err(PhysicsError::TooManySteps { estimated, limit }) => {
                prop_assert!(estimated > 0.0 && limit == 20_000.0);
            }
            Err(e) => prop_assert!(false, "unexpected error {e:?}"),
        }
    }
}

/// A rough grid of the benchmark kind: 0.5 m spacing, dip 45°, node heights ±5 cm
/// around the plane (seeded), 40 m along the dip and 10 m across.
fn rough_grid_case(shape: RockShape, seed: u64) -> MigrationCase {
    let (d, dip) = (0.5, 45.0f64);
    let t = dip.to_radians().tan();
    let heights: Vec<Vec<f64>> = (0..21)
        .map(|i| {
            (0..81)
                .map(|j| -(j as f64) * d * t + 0.05 * noise(seed, i, j))
                .collect()
        })
        .collect();
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.rock.shape = shape;
    c.rock.side_length = 0.4;
    c.face.dip_deg = dip;
    c.face.length = 40.0 / dip.to_radians().cos();
    c.face.floor = FloorSpec::Grid {
        origin: [0.0, -5.0],
        spacing: d,
        heights,
    };
    c.release.along_dip = 2.0;
    c.end_time = Some(1.5);
    c.rigid_block.max_steps = 200_000.0;
    c.output.events = true;
    c.output.trajectory = true;
    c
}

/// A block placed on a rough grid (drop 0, the default release) starts resting on the relief
/// around its release point, not inside it, and slides and tumbles down without gaining
/// energy. Before onset offsets, floor peaks and creases switched on inside the block as it
/// tipped over the relief and created their ½kₙU² (for example 1.06 kJ of 30.5 kJ for a
/// 0.95 m cube), which the run's invariant refused with a 500; and a placed block started
/// inside the nodes around it, launched by their springs.
#[test]
fn rigid_blocks_placed_on_a_rough_grid_start_on_the_relief_and_gain_no_energy() {
    let shapes = [
        RockShape::Cube,
        RockShape::Cuboid {
            dimensions: [0.6, 0.3, 0.2],
        },
        RockShape::RandomPolyhedron {
            semi_axes: [0.3, 0.2, 0.25],
            vertices: 14,
            seed: 7,
        },
        RockShape::Sphere { radius: 0.2 },
    ];
    for (k, shape) in shapes.into_iter().enumerate() {
        for seed in 0..3u64 {
            let c = rough_grid_case(shape.clone(), 1000 * k as u64 + seed);
            let r = run(&c, &Control::unlimited())
                .unwrap_or_else(|e| panic!("{shape:?} seed {seed}: {e:?}"));
            check_within(&c, &r, 2.5).unwrap_or_else(|e| panic!("{shape:?} seed {seed}: {e}"));
            // released at rest on the floor, the springs hold no more than eight contacts at
            // the rest overlap: the energy at release less the first sample's KE + PE
            let rb = r.rigid_block.unwrap();
            let tr = r.trajectory.as_ref().unwrap();
            let stored0 = r.energy.total_start - tr.kinetic_energy[0] - tr.potential_energy[0];
            let rest = 8.0 * 0.5 * rb.mass * c.gravity * rb.static_overlap;
            assert!(
                tr.time[0] == 0.0 && stored0 <= rest * (1.0 + 1e-9) + 1e-9,
                "{shape:?} seed {seed}: {stored0} J stored at release, rest {rest} J"
            );
            assert!(
                r.arrival.along_dip > c.release.along_dip,
                "{shape:?} seed {seed}: {:?}",
                r.arrival
            );
        }
    }
}

/// A block dropped beside a step of relief higher than the drop starts on the relief, not
/// inside it. Before, a 1.85 m cube dropped 0.22 m beside a 0.5 m step (a grid of 1 m spacing
/// on a 15° face) started 0.3 m inside the step; its springs held 0.4 MJ and threw the 15.7 t
/// block off at 9.4 m/s within 0.2 s. Now it starts resting on the step's edge with no spring
/// loaded beyond its rest overlap: 0.2 s later it moves slower than a free fall (g·t), has
/// stored at most its weight's rest energy, and the account closes.
#[test]
fn a_block_dropped_beside_a_step_of_relief_starts_clear_of_it() {
    let heights = vec![
        vec![
            0.060_215_847,
            -0.464_612_946,
            -0.514_376_331,
            -1.011_344_058,
            -1.041_303_448,
        ],
        vec![
            0.043_048_928,
            -0.474_626_119,
            -0.468_638_255,
            -1.075_879_243,
            -1.073_660_801,
        ],
        vec![
            0.045_634_169,
            -0.503_795_527,
            -0.474_554_947,
            -0.999_581_604,
            -1.006_439_235,
        ],
    ];
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.rock.shape = RockShape::Cube;
    c.rock.side_length = 1.845_320_097;
    c.face.dip_deg = 15.0;
    c.face.friction_coefficient = 0.0;
    c.face.length = 4.141_104_722;
    c.face.floor = FloorSpec::Grid {
        origin: [0.0, -1.0],
        spacing: 1.0,
        heights,
    };
    c.rigid_block.critical_damping_ratio = 0.05;
    c.release.drop_height = 0.220_731_68;
    c.end_time = Some(0.2);
    let r = run(&c, &Control::unlimited()).unwrap();
    let g = c.gravity;
    let rb = r.rigid_block.unwrap();
    assert!(r.arrival.speed <= g * 0.2, "{:?}", r.arrival);
    assert!(
        r.arrival.kinetic_energy <= 0.5 * rb.mass * (g * 0.2).powi(2),
        "{:?}",
        r.arrival
    );
    // a rest overlap under the whole weight on the stiffness, ten times over
    let rest = 10.0 * 0.5 * (rb.mass * g).powi(2) / c.rigid_block.normal_stiffness;
    assert!(r.energy.stored <= rest, "{:?}", r.energy);
    // and the depth and the account within the bounds of the property tests above
    check_within(&c, &r, 1.0).unwrap();
    assert!(
        r.energy.residual.abs() <= 2e-3 * r.energy.total_start,
        "{:?}",
        r.energy
    );
}

/// Cases of the sweep of valid requests: `GANGUE_RIGID_BLOCK_CASES` (default 24; run the
/// documented 1 000 or more with e.g. `GANGUE_RIGID_BLOCK_CASES=1000 cargo test --release
/// --test stability_rigid_block valid_request`).
fn sweep_cases() -> u32 {
    std::env::var("GANGUE_RIGID_BLOCK_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(24)
}

/// The sweep's grid floors of dip `dip` (degrees), 12 m along the face and 8 m across, node
/// spacing `d` (m): `floor` 1 flat, 2 a valley every third column of nodes (`relief` × d
/// deep), 3 wavy (`relief` × d high).
fn sweep_floor(floor: usize, d: f64, relief: f64, dip: f64) -> FloorSpec {
    let t = dip.to_radians().tan();
    let nx = (12.0 * dip.to_radians().cos() / d).ceil() as usize + 2;
    let ny = (8.0 / d).round() as usize + 1;
    let heights = (0..ny)
        .map(|i| {
            (0..nx)
                .map(|j| {
                    let x = j as f64 * d;
                    let bump = match floor {
                        // a valley (or a ridge) across the dip every third column
                        2 if j % 3 == 1 => -relief * d,
                        3 => relief * d * (x * 2.0).sin() * (i as f64).cos(),
                        _ => 0.0,
                    };
                    -x * t + bump
                })
                .collect()
        })
        .collect();
    FloorSpec::Grid {
        origin: [0.0, -4.0],
        spacing: d,
        heights,
    }
}

prop_compose! {
    /// A valid rigid-block request anywhere in the documented domain of the step and the
    /// contact: every shape, the plane or a grid (flat, with valleys or ridges, wavy), β from 0
    /// to 0.999, safety up to 1, linear or Hertz, dropped or placed, with a release speed and
    /// spin.
    fn sweep_case()(
        shape in prop_oneof![
            Just(RockShape::Cube),
            (0.05..=1.0f64).prop_map(|radius| RockShape::Sphere { radius }),
            prop::array::uniform3(0.1..=2.0f64)
                .prop_map(|dimensions| RockShape::Cuboid { dimensions }),
            prop::array::uniform3(0.1..=2.0f64)
                .prop_map(|dimensions| RockShape::Ellipsoid { dimensions }),
            (prop::array::uniform3(0.05..=1.0f64), 4usize..=40, any::<u64>())
                .prop_map(|(semi_axes, vertices, seed)| RockShape::RandomPolyhedron {
                    semi_axes,
                    vertices,
                    seed,
                }),
        ],
        floor in 0usize..4,
        d in 0.25..=1.0f64,
        relief in 0.05..=0.3f64,
        dip in 10.0..=60.0f64,
        mu in 0.0..=1.0f64,
        beta in prop_oneof![Just(0.0), Just(0.999), 0.0..=0.999f64],
        safety in prop_oneof![Just(1.0), 0.8..=1.0f64, 0.01..=1.0f64],
        hertz in prop::bool::weighted(0.2),
        h in prop_oneof![Just(0.0), 0.0..=10.0f64],
        speed in prop_oneof![Just(0.0), 0.0..=10.0f64],
        spin in prop_oneof![Just([0.0; 3]), prop::array::uniform3(-20.0..=20.0f64)],
        end_time in 0.05..=0.5f64,
    ) -> MigrationCase {
        let mut c = MigrationCase { method: Method::RigidBlock, ..MigrationCase::default() };
        c.rock.shape = shape;
        c.face.dip_deg = dip;
        c.face.friction_coefficient = mu;
        c.face.length = 12.0;
        if floor > 0 {
            c.face.floor = sweep_floor(floor, d, relief, dip);
            c.release.along_dip = 1.0;
        }
        c.release.drop_height = h;
        c.release.speed = speed;
        c.release.angular_velocity = Some(spin);
        c.end_time = Some(end_time);
        c.rigid_block.critical_damping_ratio = beta;
        c.rigid_block.time_step_safety = safety;
        c.rigid_block.contact_model = if hertz { ContactModel::Hertz } else { ContactModel::Linear };
        c.rigid_block.max_steps = 20_000.0;
        c
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: sweep_cases(), ..ProptestConfig::default() })]

    /// A valid request is answered or refused naming its field, never a numerical failure (the
    /// run's own invariant, energy never created beyond five times the bound, is what would
    /// fail it): at β 0 and safety 1 too, whose impacts the step must resolve; and a residual
    /// beyond the documented bound (0.2 % of the energy in play, Hertz 1 %) is never silent.
    #[test]
    fn a_valid_request_never_fails_and_no_residual_beyond_the_bound_is_silent(c in sweep_case()) {
        match run(&c, &Control::unlimited()) {
            Ok(r) => {
                check_finite(&r)?;
                let e = &r.energy;
                // the energy in play (the run's scale: the start's kinetic energy and m g
                // times the travel) is at most twice the energy at release above the lower end
                let scale = 2.0 * e.total_start.abs();
                let tol = match c.rigid_block.contact_model {
                    ContactModel::Linear => 2e-3,
                    ContactModel::Hertz => 1e-2,
                };
                let warned = r.warnings.iter().any(|w| w.code == "energy_unaccounted");
                prop_assert!(
                    warned || e.residual.abs() <= tol * scale + e.stored,
                    "residual {} of about {scale} J in play, not warned: {e:?}",
                    e.residual
                );
            }
            Err(PhysicsError::InvalidInput { param, .. }) => {
                prop_assert!(
                    matches!(param, Param::FaceNormalStiffness | Param::RockElasticModulus),
                    "{param:?}"
                );
            }
            Err(PhysicsError::TooManySteps { .. }) => {}
            Err(e) => prop_assert!(false, "a valid request failed: {e:?}"),
        }
    }
}

fn check_finite(r: &MigrationResult) -> Result<(), TestCaseError> {
    let a = &r.arrival;
    let e = &r.energy;
    prop_assert!(
        [
            a.time,
            a.speed,
            a.along_dip,
            a.kinetic_energy,
            e.total_start,
            e.residual
        ]
        .iter()
        .all(|x| x.is_finite()),
        "{r:?}"
    );
    Ok(())
}

/// The default sphere without damping on a 20 m face at a high safety factor: at 0.9 its
/// impacts created more than 1 % of the energy and the run failed (500); at 1.0, dropped
/// 10 m, it created 0.98 % silently. Every accepted safety answers within the bound.
#[test]
fn an_undamped_sphere_at_a_high_safety_answers_within_the_energy_bound() {
    for (drop, safety) in [
        (0.0, 0.9),
        (3.27, 0.9),
        (10.0, 0.9),
        (10.0, 1.0),
        (3.27, 1.0),
    ] {
        let mut c = MigrationCase {
            method: Method::RigidBlock,
            ..MigrationCase::default()
        };
        c.rock.shape = RockShape::Sphere {
            radius: c.rock.side_length / 2.0,
        };
        c.rigid_block.critical_damping_ratio = 0.0;
        c.face.length = 20.0;
        c.release.drop_height = drop;
        c.rigid_block.time_step_safety = safety;
        let r = run(&c, &Control::unlimited()).unwrap_or_else(|e| panic!("{drop} {safety}: {e:?}"));
        let e = &r.energy;
        assert!(
            e.residual.abs() <= 2e-3 * e.total_start,
            "drop {drop} safety {safety}: residual {} of {} J",
            e.residual,
            e.total_start
        );
    }
}

/// A sweep case (seed 4411) as the sweep builds it: `shape` placed 1 m down a face of 12 m at
/// `dip` on sweep floor `floor` of spacing `d` (relief 0.05 m), μ `mu`, no spin, to `end_time`
/// at safety 1 with damping `beta` and the contact law `model`; run, its numbers finite.
#[allow(clippy::too_many_arguments)]
fn placed_on_a_sweep_floor(
    shape: RockShape,
    dip: f64,
    mu: f64,
    floor: usize,
    d: f64,
    end_time: f64,
    beta: f64,
    model: ContactModel,
) -> (MigrationCase, MigrationResult) {
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.rock.shape = shape;
    c.face.dip_deg = dip;
    c.face.length = 12.0;
    c.face.friction_coefficient = mu;
    c.face.floor = sweep_floor(floor, d, 0.05, dip);
    c.release.along_dip = 1.0;
    c.release.drop_height = 0.0;
    c.release.angular_velocity = Some([0.0; 3]);
    c.end_time = Some(end_time);
    c.rigid_block.critical_damping_ratio = beta;
    c.rigid_block.time_step_safety = 1.0;
    c.rigid_block.contact_model = model;
    c.rigid_block.max_steps = 20_000.0;
    let r = run(&c, &Control::unlimited()).unwrap_or_else(|e| panic!("{e:?}"));
    check_finite(&r).unwrap();
    (c, r)
}

/// A case of the sweep (seed 4411): the default cube placed on the wavy grid at β 0.999 and
/// safety 1 (run at 0.3), μ 0.96, so that it barely moves (0.055 J in play). Resting on the
/// relief it rocks by micro-radians, and a crease contact under it switched on at the rest
/// overlap and off again every few milliseconds, each switch creating that overlap's ½kₙU²:
/// 1.03e-3 J by 0.1 s at any step, beyond the run's guard of 1.0e-3 J (a 500).
#[test]
fn a_cube_placed_on_a_wavy_grid_at_high_damping_answers() {
    let (c, r) = placed_on_a_sweep_floor(
        RockShape::Cube,
        25.566418259358816,
        0.9566295850917984,
        3,
        0.5343073763815036,
        0.3064343244837477,
        0.999,
        ContactModel::Linear,
    );
    // the account closes well within one switch's ½kₙU² at the rest overlap (1.1e-4 J)
    let e = &r.energy;
    let rest = r.rigid_block.unwrap().static_overlap;
    let one = 0.5 * c.rigid_block.normal_stiffness * rest * rest;
    assert!(e.residual.abs() <= 0.2 * one, "{e:?} {one}");
    assert!(
        r.warnings.iter().all(|w| w.code != "energy_unaccounted"),
        "{:?}",
        r.warnings
    );
}

/// A case of the sweep (seed 4411): a Hertz stick (0.1 × 0.1 × 1.42 m cuboid) placed on the
/// wavy grid at 10°, β 0, safety 1, its edge rocking on a crease of the relief (a crease
/// contact's overlap is its depth across its cone, or the stick gains energy: capped towards
/// the cone's sides, it created 3.06 J of 54 J in play).
#[test]
fn a_stick_placed_on_a_wavy_grid_without_damping_answers() {
    let (_, r) = placed_on_a_sweep_floor(
        RockShape::Cuboid {
            dimensions: [0.1, 0.1, 1.4191004726055625],
        },
        10.0,
        0.0,
        3,
        0.3055378890036565,
        0.38400114683986114,
        0.0,
        ContactModel::Hertz,
    );
    let e = &r.energy;
    assert!(e.residual.abs() <= 1e-2 * e.total_start, "{e:?}");
}

/// A case of the sweep (seed 4411): a flat Hertz polyhedron (semi-axes 0.55, 0.24, 0.05 m,
/// 20 vertices) placed on the grid with valleys at 10°, β 0, safety 1, μ 0.93 (a crease
/// contact held open beyond its cone's side created 4.4e-2 J of 0.50 J in play).
#[test]
fn a_flat_polyhedron_placed_over_valleys_without_damping_answers() {
    let (_, r) = placed_on_a_sweep_floor(
        RockShape::RandomPolyhedron {
            semi_axes: [0.5459303902499156, 0.2444249181262188, 0.05],
            vertices: 20,
            seed: 985254917854911726,
        },
        10.0,
        0.9317564552894072,
        2,
        0.4741254746929891,
        0.21277191194039255,
        0.0,
        ContactModel::Hertz,
    );
    let e = &r.energy;
    assert!(e.residual.abs() <= 1e-2 * e.total_start, "{e:?}");
}

/// physics.md §C.3 (shear springs): a flat grid must give the plane's answer. The default
/// sphere dropped 1.19 m with a spin of 14.56 rad/s about the vertical rolls down 27.65° along
/// the seam line y = 0 of a flat 0.5 m grid. Its touch there was seen from both facets at
/// points a fraction of a micrometre apart, counted twice and switched off at full depth:
/// 19.6 J of 1 935 J (1 %) lost unbooked at any step, damping 303.1 J against the plane's
/// 323.7 J. Now the grid's run is the plane's (energy terms and arrival) and its residual
/// shrinks with the step.
#[test]
fn a_spinning_sphere_along_a_flat_grids_seam_answers_what_the_plane_does() {
    let at = |grid: bool, safety: f64| {
        let mut c = MigrationCase {
            method: Method::RigidBlock,
            ..MigrationCase::default()
        };
        let dip = 27.65;
        c.rock.shape = RockShape::Sphere {
            radius: c.rock.side_length / 2.0,
        };
        c.face.dip_deg = dip;
        c.face.length = 12.0;
        c.face.friction_coefficient = 0.02;
        if grid {
            c.face.floor = sweep_floor(1, 0.5, 0.0, dip);
        }
        c.release.drop_height = 1.19;
        c.release.along_dip = 2.75;
        c.release.angular_velocity = Some([0.0, 0.0, -14.56]);
        c.rigid_block.time_step_safety = safety;
        run(&c, &Control::unlimited()).unwrap_or_else(|e| panic!("{e:?}"))
    };
    let (plane, grid) = (at(false, 0.2), at(true, 0.2));
    let (p, g) = (&plane.energy, &grid.energy);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(rel(g.damping, p.damping) < 1e-2, "{g:?} {p:?}");
    assert!(rel(g.friction, p.friction) < 1e-2, "{g:?} {p:?}");
    assert!(rel(grid.arrival.speed, plane.arrival.speed) < 1e-4);
    assert!(rel(grid.arrival.time, plane.arrival.time) < 1e-4);
    assert!(g.residual.abs() <= 1e-3 * g.total_start, "{g:?}");
    assert!(
        grid.warnings.iter().all(|w| w.code != "energy_unaccounted"),
        "{:?}",
        grid.warnings
    );
    // the residual is the scheme's error: it shrinks with the step (-0.82 J at safety 0.2,
    // -0.036 J at 0.05)
    let fine = at(true, 0.05);
    assert!(
        fine.energy.residual.abs() <= 0.25 * g.residual.abs(),
        "{:?} against {g:?}",
        fine.energy
    );
    assert!(rel(fine.energy.damping, at(false, 0.05).energy.damping) < 1e-3);
}

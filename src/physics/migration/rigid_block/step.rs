//! The rigid block's time step (physics.md §C.3, "5. Time step" and its Amendment).
//!
//! The leapfrog's dashpot takes the contact velocity at x(t) predicted from the half step,
//! v(t) ≈ v(t − Δt/2) + a(t − Δt) Δt/2. For one spring k and dashpot c = 2ζ√(mk) on a mass m
//! (ω = √(k/m)) the step's amplification matrix on (x, v, a) has spectral radius ≤ 1 for
//! ωΔt < 2(√(1 + 4ζ²) − 2ζ): the lagged velocity's limit 2(√(1 + ζ²) − ζ) with ζ doubled, since
//! the prediction doubles the dashpot's gain at the highest frequency ([`single_limit`]).
//!
//! With the PFC contact-mass convention (every contact's dashpot c = 2β√(m k) with the body
//! mass m) the dashpots of N contacts of equal stiffness are proportional to their springs,
//! C = 2β√(m/k) K, so each normal mode j of the contact set has ζⱼ = β ωⱼ √(m/k): the ratio
//! grows with the mode's frequency. Four contacts of a cube's face give ζ = 2β in heave
//! (ω² = 4k/m) and √6 β in rocking (ω² = 6k/m); N contacts in heave give √N β, and a thin
//! plate's rocking up to √12 β. The shear springs (undamped) couple with the normal ones, so
//! the limit is computed for the whole set ([`stable_step`]): the contacts of the resting face
//! (a sphere: its lowest point) with their normal springs and dashpots and their two shear
//! springs each, linearised about rest, the step's amplification matrix in the set's modal
//! coordinates, and the largest step whose spectral radius stays ≤ 1, by bisection.

use nalgebra::{DMatrix, Matrix6, SymmetricEigen, Vector3, Vector6};

use super::super::MigrationCase;
use super::super::Prepared;
use super::super::monte_carlo::Distribution;
use super::super::shape::BlockShape;
use super::{Hertz, RigidBlockOptions};
use crate::physics::error::{Param, PhysicsError, PhysicsResult};

/// ω_peak × (duration of a Hertz impact): an elastic Hertz impact lasts 2.9432 δmax/v and its
/// tangent stiffness at δmax gives ω = √(15/8) v/δmax, so T_c ω = 4.03 at any speed.
const HERTZ_CONTACT_TIME_OMEGA: f64 = 4.03;
/// Steps per Hertz impact at safety 1 (the default safety 0.2 gives 100 steps per impact: the
/// impact's restitution, bounce height and peak force converged within 1 % at β ≤ 0.6).
pub(super) const HERTZ_STEPS_PER_IMPACT: f64 = 20.0;
/// Largest safety factor the step is taken with (a larger one is used as this one): the
/// leapfrog's energy error at the impacts grows about linearly with the step (a sphere without
/// damping dropped 10 m on the plane created 0.06 % of its energy at safety 0.2, 0.21 % at 0.4,
/// 0.98 % at 1, and beyond 1 % at 0.9, where the run's own invariant failed it), so every
/// accepted safety is kept within the documented bound of 0.2 %.
pub(super) const ACCURATE_SAFETY: f64 = 0.3;
/// Largest impact overlap, as a fraction of the block's smallest dimension, for which the
/// contact law is accepted.
pub(super) const MAX_IMPACT_OVERLAP_FRACTION: f64 = 0.1;

/// Largest stable ωΔt of the leapfrog with the predicted-velocity dashpot for one spring–dashpot
/// of damping ratio ζ: 2(√(1 + 4ζ²) − 2ζ) (2 without damping).
#[cfg(test)]
#[must_use]
pub(super) fn single_limit(zeta: f64) -> f64 {
    2.0 * ((1.0 + 4.0 * zeta * zeta).sqrt() - 2.0 * zeta)
}

/// Largest damping ratio β a run of the case can take: the nominal one, or the top of the
/// ensemble's draw (clamped to 0.999 as the runs clamp it).
#[must_use]
pub(super) fn largest_beta(nominal: f64, draw: Option<&Distribution>) -> f64 {
    let top = match draw {
        None => return nominal,
        Some(Distribution::Uniform { max, .. } | Distribution::TruncatedNormal { max, .. }) => *max,
        Some(Distribution::Normal { mean, std }) if *std == 0.0 => *mean,
        Some(Distribution::Normal { .. }) => f64::INFINITY,
    };
    nominal.max(top.clamp(0.0, 0.999))
}

/// The contact set the step is designed for: the resting face's vertices relative to the centre
/// (body frame, m; a sphere: its lowest point) and the face's outward normal.
fn resting_set(shape: &BlockShape) -> (Vec<Vector3<f64>>, Vector3<f64>) {
    let n = shape.rest_normal();
    match shape.sphere_radius {
        Some(r) => (vec![n * r], n),
        None => (
            shape.faces[shape.largest_face]
                .vertices
                .iter()
                .map(|&i| shape.vertices[i])
                .collect(),
            n,
        ),
    }
}

/// Largest stable step (s) of the leapfrog for the block `shape` (mass m kg, principal inertia
/// in the body frame kg·m²) resting on its contact set with normal stiffness `k` (N/m per
/// contact; Hertz: the tangent stiffness), shear stiffness `ks` (N/m) and dashpots of critical
/// damping ratio `beta` (c = 2β√(m k)). See the module's notes.
#[must_use]
pub(super) fn stable_step(shape: &BlockShape, k: f64, ks: f64, beta: f64) -> f64 {
    let (points, normal) = resting_set(shape);
    // every input of the limit, bit for bit: the contact set, the mass, the inertia and the
    // three coefficients
    let mut key = Vec::with_capacity(3 * points.len() + 10);
    for v in points.iter().chain(std::iter::once(&normal)) {
        key.extend(v.iter().map(|x| x.to_bits()));
    }
    key.extend(shape.inertia.iter().map(|x| x.to_bits()));
    key.extend([shape.mass, k, ks, beta].map(f64::to_bits));
    if let Some(h) = LAST_STABLE_STEP
        .with_borrow(|last| last.as_ref().and_then(|(kk, h)| (*kk == key).then_some(*h)))
    {
        return h;
    }
    let h = stable_step_of(&points, normal, shape, k, ks, beta);
    LAST_STABLE_STEP.with_borrow_mut(|last| *last = Some((key, h)));
    h
}

thread_local! {
    /// The last stable step computed on this thread and the bits of its inputs: the runs of an
    /// ensemble whose draws leave the block and its contacts unchanged (the release point, the
    /// friction; a scene's release across the face) build their model with the same inputs, and
    /// the limit (some 50 eigenvalue problems) is a pure function of them.
    static LAST_STABLE_STEP: std::cell::RefCell<Option<(Vec<u64>, f64)>> =
        const { std::cell::RefCell::new(None) };
}

/// [`stable_step`] computed, for the resting contact set `points` (body frame, m) with the
/// outward normal `normal`.
fn stable_step_of(
    points: &[Vector3<f64>],
    normal: Vector3<f64>,
    shape: &BlockShape,
    k: f64,
    ks: f64,
    beta: f64,
) -> f64 {
    let m = shape.mass;
    let inertia = shape.inertia;
    // tangent directions of the face
    let t1 = {
        let a = if normal.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        normal.cross(&a).normalize()
    };
    let t2 = normal.cross(&t1);
    // mass-normalised coordinates: q = M^{1/2} (x, θ)
    let scale = Vector6::new(
        1.0 / m.sqrt(),
        1.0 / m.sqrt(),
        1.0 / m.sqrt(),
        1.0 / inertia.x.sqrt(),
        1.0 / inertia.y.sqrt(),
        1.0 / inertia.z.sqrt(),
    );
    let c = 2.0 * beta * (m * k).sqrt();
    let mut kk = Matrix6::<f64>::zeros();
    let mut cc = Matrix6::<f64>::zeros();
    for r in points {
        for (d, kd, cd) in [(normal, k, c), (t1, ks, 0.0), (t2, ks, 0.0)] {
            let rd = r.cross(&d);
            let j = Vector6::new(d.x, d.y, d.z, rd.x, rd.y, rd.z).component_mul(&scale);
            kk += j * j.transpose() * kd;
            cc += j * j.transpose() * cd;
        }
    }
    let eig = SymmetricEigen::new(kk);
    let lmax = eig.eigenvalues.max();
    if lmax <= 0.0 {
        return f64::INFINITY;
    }
    // the modes the contacts hold (a sphere's roll and spin are free; the dashpots' range lies
    // in the springs', so the free modes decouple)
    let modes: Vec<usize> = (0..6)
        .filter(|&j| eig.eigenvalues[j] > 1e-10 * lmax)
        .collect();
    let nm = modes.len();
    let phi = DMatrix::from_fn(6, nm, |i, j| eig.eigenvectors[(i, modes[j])]);
    let lam: Vec<f64> = modes.iter().map(|&j| eig.eigenvalues[j]).collect();
    let cm = phi.transpose() * DMatrix::from_fn(6, 6, |i, j| cc[(i, j)]) * &phi;
    let w_max = lmax.sqrt();
    let stable = |h: f64| spectral_radius(&lam, &cm, h) <= 1.0 + 1e-7;
    // no step beyond 2/ω_max is stable; bisect between a stable and an unstable step
    let (mut lo, mut hi) = (1e-3 / w_max, 2.0 / w_max * (1.0 + 1e-6));
    if !stable(lo) {
        return lo;
    }
    for _ in 0..48 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Spectral radius of one leapfrog step of h (s) for modes of squared frequencies `lam` (1/s²)
/// and modal damping matrix `cm` (1/s), state (x, h v, h² a) with the dashpot's predicted
/// velocity: a = −Λx − C(v + a₋ h/2), v ← v + h a, x ← x + h v. ∞ when the eigenvalues are
/// not found.
fn spectral_radius(lam: &[f64], cm: &DMatrix<f64>, h: f64) -> f64 {
    let n = lam.len();
    let mut a = DMatrix::<f64>::zeros(3 * n, 3 * n);
    for i in 0..n {
        // acceleration row (times h²) on (x, h v, h² a₋)
        a[(2 * n + i, i)] = -h * h * lam[i];
        for j in 0..n {
            a[(2 * n + i, n + j)] = -h * cm[(i, j)];
            a[(2 * n + i, 2 * n + j)] = -0.5 * h * cm[(i, j)];
        }
    }
    for i in 0..n {
        for col in 0..3 * n {
            let acc = a[(2 * n + i, col)];
            // v ← v + a; x ← x + v(new)
            let v = acc + if col == n + i { 1.0 } else { 0.0 };
            a[(n + i, col)] = v;
            a[(i, col)] = v + if col == i { 1.0 } else { 0.0 };
        }
    }
    match nalgebra::linalg::Schur::try_new(a, 1e-14, 10_000) {
        Some(s) => s
            .complex_eigenvalues()
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max),
        None => f64::INFINITY,
    }
}

/// The Hertz overlap (m) whose elastic energy (2/5) k U^{5/2} (k = (4/3)E*√r, N/m^{3/2}) is the
/// kinetic energy ½ m v² of mass m (kg) at speed v (m/s): the deepest an impact at v can press.
#[must_use]
pub(super) fn hertz_impact_overlap(k: f64, m: f64, v: f64) -> f64 {
    (1.25 * m * v * v / k).powf(0.4)
}

/// The duration of a Hertz impact (s) whose tangent stiffness at the deepest overlap is
/// `kt_peak` (N/m), on a mass m (kg): 4.03/ω with ω = √(k_t/m).
#[must_use]
pub(super) fn hertz_contact_time(kt_peak: f64, m: f64) -> f64 {
    HERTZ_CONTACT_TIME_OMEGA / (kt_peak / m).sqrt()
}

/// The speeds of the fastest impacts a run can make, from its energy at release.
#[derive(Debug, Clone, Copy)]
pub(super) struct ImpactBounds {
    /// Largest speed of the block, m/s: √(v₀² + 2 g Δz) with Δz the fall from the release to
    /// the lower end of the face (the drop and the slide down it). Energy is never created, so no
    /// contact point of the block meets the floor with more kinetic energy than ½ m of this².
    pub(super) speed: f64,
    /// Normal speed of the drop's landing, m/s: √(2 g h) times the cosine of the mean dip.
    pub(super) drop_normal_speed: f64,
}

impl ImpactBounds {
    /// The bounds of `case` with its release `pr` and gravity `g` (m/s²).
    pub(super) fn of(case: &MigrationCase, pr: &Prepared, g: f64) -> Self {
        let fall = (pr.p0.z - pr.z_end).max(case.release.drop_height).max(0.0);
        ImpactBounds {
            speed: (pr.v0.norm_squared() + 2.0 * g * fall).sqrt(),
            drop_normal_speed: (2.0 * g * case.release.drop_height).sqrt()
                * pr.floor.mean.normal().z,
        }
    }

    /// Refuses a linear contact stiffness `kn` (N/m) that the drop's landing would press more
    /// than [`MAX_IMPACT_OVERLAP_FRACTION`] of the block's smallest dimension: the impact
    /// overlap of N_c contacts sharing the mass, vₙ √(m/(N_c kₙ)).
    pub(super) fn check_overlap(&self, shape: &BlockShape, kn: f64) -> PhysicsResult<()> {
        let nc = shape.resting_contacts() as f64;
        let m = shape.mass;
        let vn = self.drop_normal_speed;
        let overlap = vn * (m / (nc * kn)).sqrt();
        let limit = MAX_IMPACT_OVERLAP_FRACTION * shape.smallest_dimension;
        if overlap > limit {
            let needed = m * vn * vn / (nc * limit * limit);
            return Err(PhysicsError::invalid(
                Param::FaceNormalStiffness,
                kn,
                format!(
                    "too soft for the drop: landing at {vn:.4} m/s normal to the floor, the \
                     block would sink {overlap:.3e} m (vₙ √(m/(N_c kₙ)), N_c = {nc}), more than \
                     {:.0} % of its smallest dimension {:.3e} m; valid for this block and drop: \
                     kₙ ≥ {needed:.3e} N/m",
                    100.0 * MAX_IMPACT_OVERLAP_FRACTION,
                    shape.smallest_dimension
                ),
            ));
        }
        Ok(())
    }
}

/// The time steps of the options `o` for the block `shape` (s): PFC's Δt_crit, the bound the
/// damping and the Hertz impacts set, and, for the ground phase's contact time, the resting
/// stiffness per contact (N/m). The step is safety × the smaller of the two.
///
/// Δt_crit is PFC's √(m/k_tran), √(I/k_rot) (physics.md §C.3: the linear law's kₙ, or kₛ if
/// stiffer; the Hertz law's k_t at the overlap of a contact carrying m g). The bound is half the
/// largest stable step of the resting contact set with the largest damping ratio a run can take
/// ([`stable_step`]): safety ≤ 1 keeps every step within half the damped limit (PFC's 1/ω
/// against the undamped 2/ω). For the Hertz law its stiffness is the tangent stiffness at the
/// deepest overlap the fastest impact can press, [`hertz_impact_overlap`] at
/// [`ImpactBounds::speed`] with the whole mass on one contact, and the bound also resolves that
/// impact by [`HERTZ_STEPS_PER_IMPACT`] steps.
pub(super) fn critical_step(
    o: &RigidBlockOptions,
    shape: &BlockShape,
    hertz: Option<Hertz>,
    impact: &ImpactBounds,
    g: f64,
) -> (f64, f64, f64) {
    let m = shape.mass;
    let nc = shape.resting_contacts() as f64;
    let beta = largest_beta(
        o.critical_damping_ratio,
        o.critical_damping_ratio_distribution.as_ref(),
    );
    let (k_rest, k, ks, resolve) = match hertz {
        None => (
            o.normal_stiffness.max(o.shear_stiffness),
            o.normal_stiffness,
            o.shear_stiffness,
            f64::INFINITY,
        ),
        Some(h) => {
            // a contact carrying m g alone (the static rule), and the fastest impact's
            let ug = (m * g / h.k).powf(2.0 / 3.0);
            let u = ug.max(hertz_impact_overlap(h.k, m, impact.speed));
            let kt = h.kt * u.sqrt();
            (
                h.kt * ug.sqrt(),
                kt,
                kt * h.shear_ratio,
                hertz_contact_time(kt, m) / HERTZ_STEPS_PER_IMPACT,
            )
        }
    };
    let pfc = (m / (nc * k_rest))
        .sqrt()
        .min((shape.inertia.min() / (k_rest * shape.resting_r2())).sqrt());
    let damped = 0.5 * stable_step(shape, k, ks, beta);
    (pfc, damped.min(resolve), k_rest)
}

#[cfg(test)]
mod tests {
    //! The step's stability limit against the scheme it bounds: a single spring–dashpot stepped
    //! as the run steps it grows at the limit and decays below it, and the contact set's limit
    //! reduces to the closed form where the set is one mode.
    use super::*;

    /// Steps a mass on a spring–dashpot (ω = 1, ratio ζ) with the run's scheme for n steps of
    /// h from x = 1; returns the largest |x| of the last 100 steps.
    fn stepped(zeta: f64, h: f64, n: usize) -> f64 {
        let (mut x, mut v, mut a_prev) = (1.0f64, 0.0f64, 0.0f64);
        let mut late = 0.0f64;
        for i in 0..n {
            let vt = v + 0.5 * h * a_prev;
            let a = -x - 2.0 * zeta * vt;
            v += h * a;
            x += h * v;
            a_prev = a;
            if i + 100 >= n {
                late = late.max(x.abs());
            }
        }
        late
    }

    #[test]
    fn a_spring_dashpot_stepped_just_inside_the_damped_limit_decays_and_just_outside_grows() {
        for zeta in [0.1, 0.35, 0.7, 1.0, 2.0, 2.5] {
            let lim = single_limit(zeta);
            assert!(stepped(zeta, 0.98 * lim, 2_000) < 1e-6, "ζ {zeta}");
            assert!(stepped(zeta, 1.02 * lim, 2_000) > 1e6, "ζ {zeta}");
        }
    }

    #[test]
    fn a_sphere_limit_is_the_single_spring_dashpot_limit_or_its_shear_mode() {
        // a sphere's normal spring is one mode (ω² = k/m, ζ = β); its shear springs load a
        // mode of ω² = 3.5 kₛ/m (the contact point's effective mass m/3.5), undamped
        let s = BlockShape::sphere(0.15, 2500.0);
        let (k, m) = (1e8, s.mass);
        for beta in [0.0, 0.35, 0.9, 0.999] {
            for ks in [1e6, 1e8, 1e10] {
                let normal = single_limit(beta) / (k / m).sqrt();
                let shear = 2.0 / (3.5 * ks / m).sqrt();
                let want = normal.min(shear);
                let got = stable_step(&s, k, ks, beta);
                assert!(
                    (got / want - 1.0).abs() < 1e-6,
                    "β {beta} kₛ {ks}: {got} against {want}"
                );
            }
        }
    }

    #[test]
    fn the_remembered_limit_is_the_limit_of_the_inputs_asked() {
        // alternating blocks and coefficients on one thread: every answer is the one computed
        // afresh for its own inputs, bit for bit (a repeated question is answered from memory)
        let cube = BlockShape::cuboid([0.3; 3], 2500.0).unwrap();
        let slab = BlockShape::cuboid([0.6, 0.4, 0.2], 2500.0).unwrap();
        let fresh = |s: &BlockShape, k: f64, beta: f64| {
            let (points, normal) = resting_set(s);
            stable_step_of(&points, normal, s, k, k, beta)
        };
        for (s, k, beta) in [
            (&cube, 1e8, 0.35),
            (&cube, 1e8, 0.35),
            (&slab, 1e8, 0.35),
            (&cube, 1e8, 0.35),
            (&cube, 1e9, 0.35),
            (&cube, 1e9, 0.5),
            (&cube, 1e9, 0.5),
        ] {
            assert_eq!(
                stable_step(s, k, k, beta).to_bits(),
                fresh(s, k, beta).to_bits(),
                "k {k} β {beta}"
            );
        }
        assert_ne!(fresh(&cube, 1e8, 0.35), fresh(&slab, 1e8, 0.35));
        assert_ne!(fresh(&cube, 1e9, 0.35), fresh(&cube, 1e9, 0.5));
    }

    #[test]
    fn a_cube_face_limit_without_shear_is_its_rocking_mode_at_damping_root_six_beta() {
        // four contacts with negligible shear springs: heave ω² = 4k/m with ζ = 2β, rocking
        // ω² = 6k/m with ζ = √6 β; the set's limit is the smaller of the two
        let s = BlockShape::cuboid([0.3; 3], 2500.0).unwrap();
        let (k, m) = (1e8, s.mass);
        for beta in [0.0, 0.35, 0.9] {
            let heave = single_limit(2.0 * beta) / (4.0 * k / m).sqrt();
            let rock = single_limit(6f64.sqrt() * beta) / (6.0 * k / m).sqrt();
            let got = stable_step(&s, k, 1e-6 * k, beta);
            let want = heave.min(rock);
            assert!(
                (got / want - 1.0).abs() < 1e-5,
                "β {beta}: {got} against {want}"
            );
        }
    }

    #[test]
    fn an_ensemble_drawing_damping_ratios_steps_for_the_largest_it_can_draw() {
        let dt = |beta: f64, draw: Option<Distribution>| {
            let mut c = super::super::super::MigrationCase {
                method: super::super::super::Method::RigidBlock,
                ..Default::default()
            };
            c.rigid_block.critical_damping_ratio = beta;
            c.rigid_block.critical_damping_ratio_distribution = draw;
            let pr = super::super::super::prepare(&c).unwrap();
            super::super::Model::new(&c, &pr).unwrap().dt
        };
        let draw = Distribution::Uniform { min: 0.1, max: 0.9 };
        assert_eq!(dt(0.35, Some(draw)), dt(0.9, None));
        assert!(dt(0.9, None) < 0.6 * dt(0.35, None));
        // an unbounded normal draw is clamped at 0.999, as the runs clamp it
        let normal = Distribution::Normal {
            mean: 0.3,
            std: 0.1,
        };
        assert_eq!(dt(0.35, Some(normal)), dt(0.999, None));
    }
}

//! Lumped-mass energy tracking method (physics.md §C.2), event driven with closed-form phases.
//!
//! The rock is a point mass. Flights are parabolas whose first strike of the floor is a root of a
//! quadratic; an impact applies the normal and tangential restitution in the struck facet's frame;
//! a rebound slower than the stop speed starts the ground phase (slide, or roll as a sphere). A
//! rock in its ground phase that leaves the floor at a convex edge stays in that phase: its
//! landing is a re-contact ([`Run::recontact`]) whose normal speed is restituted with e_n and
//! whose tangential change is the Coulomb impulse of a rigid-body impact (bounded by the paper's
//! e_t), so its loss is continuous in the landing's normal speed and tends to 0 with it; a
//! concave edge met on the ground is the plastic limit of the same rule ([`Run::reattach`]). A
//! floor within centimetres of a plane gives the plane's answer and a finer grid of a curve
//! converges to the continuous slide. On a
//! facet the acceleration is constant while the friction direction is fixed, so a slide moves in
//! closed form from event to event: a facet edge, the lower end, the end time, the moment the
//! speed along the friction direction reaches zero, or — only when gravity's in-plane part is not
//! parallel to the velocity — a turn of the velocity by [`MAX_TURN`] rad, after which the friction
//! direction is renewed. On a plane and on any slide straight down a facet the friction direction
//! never turns, and the method is exact. Every energy term is computed in its own right (work of
//! friction as μ g_n f̂·Δp, impact and transition losses from the velocity jumps), so the balance
//! KE + PE + losses − E_start is a genuine check.
//!
//! Energies here are per unit mass (J/kg); the caller multiplies by the rock's mass.

use nalgebra::Vector3;

use super::lines::{Crossing, Line, LineAction, act, first_reachable};
use super::terrain::{
    Facet, FacetPlane, FlightEnd, Floor, FloorKind, MeanPlane, RunZones, inside_tri,
};
use crate::physics::control::Control;
use crate::physics::error::{PhysicsError, PhysicsResult};

mod flight;
mod ground;
mod plane;
mod trap;

use trap::trap_length;

/// Largest turn of the velocity, rad, over which the friction direction is held fixed on a facet.
pub const MAX_TURN: f64 = 0.02;
/// Normal rebound speed, m/s, below which bouncing ends even when the stop speed is 0: with a
/// stop speed of 0 the rebounds r, e r, e² r, … would never end, though their flights (total
/// time 2 r / (g cos θ (1 − e)) on a plane) do; the run says so in a `rebound_cutoff` warning.
pub const MIN_REBOUND: f64 = 1e-6;
/// Speed, m/s, below which a sliding rock counts as momentarily at rest.
const REST_SPEED: f64 = 1e-9;

/// Motion on the floor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// Coulomb sliding, a = g(sin θ − μ cos θ) on a plane.
    Slide,
    /// Rolling without slip as a sphere: spin-up ×5/7, a = 5/7 g sin θ, KE = 0.7 m v².
    Roll,
}

/// Motion at the end of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// In the air.
    Flight,
    /// Sliding on the floor.
    Slide,
    /// Rolling on the floor.
    Roll,
    /// At rest.
    Stopped,
}

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// `along_dip_m` reached the face length.
    LowerEnd,
    /// The rock came to rest.
    AtRest,
    /// `end_time_s` was reached.
    EndTime,
    /// The rock left the floor's extent.
    LeftFloor,
    /// The rock reached a support (api.md `POST /v1/scene`).
    Support,
    /// A barrier stopped the rock (api.md `POST /v1/scene`, `barriers`).
    Barrier,
}

/// Kind of a recorded event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// A strike on the floor with restitution.
    Impact,
    /// Start of sliding.
    SlideStart,
    /// Start of rolling (with the spin-up).
    RollStart,
    /// Take-off at a convex edge.
    TakeOff,
    /// The rock came to rest.
    Stop,
    /// A barrier stopped the rock or took its rating of the rock's kinetic energy.
    Barrier,
}

/// One event of a run (energies per kg until scaled by the caller).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct EventRec {
    pub(crate) t: f64,
    pub(crate) kind: EventKind,
    pub(crate) p: Vector3<f64>,
    pub(crate) speed_before: f64,
    pub(crate) speed_after: f64,
    pub(crate) lost: f64,
}

/// A closed-form piece of the trajectory: p(τ) = p₀ + v₀ τ + ½ a τ² for τ in [0, dt].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Segment {
    pub(crate) t0: f64,
    pub(crate) dt: f64,
    pub(crate) p0: Vector3<f64>,
    pub(crate) v0: Vector3<f64>,
    pub(crate) a: Vector3<f64>,
    /// Friction force per kg (μ g_n f̂); its dot with the displacement is the friction work.
    pub(crate) fric: Vector3<f64>,
    /// Energy dissipated per kg before the segment.
    pub(crate) diss0: f64,
    /// Rolling on a facet with this unit normal (rotation follows the velocity).
    pub(crate) rolling: Option<Vector3<f64>>,
    /// Constant rotational energy per kg and angular velocity in flight.
    pub(crate) spin: (f64, Vector3<f64>),
    /// On the floor (slide, roll or crease) rather than in flight.
    pub(crate) on_floor: bool,
}

/// What a recorded run keeps for events and trajectories.
#[derive(Debug, Clone, Default)]
pub(crate) struct Recording {
    pub(crate) segments: Vec<Segment>,
    pub(crate) events: Vec<EventRec>,
}

/// Fixed inputs of a run.
#[derive(Debug, Clone)]
pub(crate) struct Setup<'a> {
    pub(crate) floor: &'a Floor,
    pub(crate) g: f64,
    pub(crate) motion: Motion,
    pub(crate) v_stop: f64,
    pub(crate) radius: f64,
    pub(crate) length: f64,
    /// The spanning support standing at `length`, if the run ends there rather than at the face's
    /// lower end.
    pub(crate) span_support: Option<usize>,
    /// Supports of a scene; columns among them are checked along every piece.
    pub(crate) supports: &'a [super::SupportStop],
    /// Lines across the face (collectors and barriers), sorted along the dip.
    pub(crate) lines: &'a [Line],
    /// The rock's mass, kg (a barrier's rating is in J).
    pub(crate) mass: f64,
    pub(crate) end_time: Option<f64>,
    pub(crate) max_steps: u64,
    /// Release point (lifted), velocity and, for a release on the floor, its facet.
    pub(crate) p0: Vector3<f64>,
    pub(crate) v0: Vector3<f64>,
    pub(crate) on_floor: Option<Facet>,
    /// The floor point under the release, m, and its `along_dip`, m (exact for the plane): the
    /// distance to the lower end is measured from floor points like it, never from p₀.
    pub(crate) base: (Vector3<f64>, f64),
}

/// Outcome of a run; energies per kg.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RunOut {
    pub(crate) t: f64,
    pub(crate) p: Vector3<f64>,
    pub(crate) v: Vector3<f64>,
    pub(crate) omega: Vector3<f64>,
    pub(crate) phase: Phase,
    pub(crate) reason: StopReason,
    pub(crate) impacts: u64,
    pub(crate) slide_start: Option<f64>,
    pub(crate) stop_along: Option<f64>,
    pub(crate) max_bounce: f64,
    pub(crate) e_imp: f64,
    pub(crate) e_fric: f64,
    pub(crate) e_trans: f64,
    pub(crate) e_rot: f64,
    /// Number of closed-form pieces (flights, slide pieces, edge crossings).
    pub(crate) steps: u64,
    /// True when the last ground phase had no deceleration (a ≥ 0 along the motion) at the end.
    pub(crate) undecelerated: bool,
    /// True when a bounce series was ended by [`MIN_REBOUND`] rather than by the stop speed.
    pub(crate) rebound_cutoff: bool,
    /// The support reached, when the run ended there.
    pub(crate) support: Option<usize>,
    /// Kinetic energy per kg taken by barriers.
    pub(crate) e_barrier: f64,
    /// Per line of the setup, the rock's state where it reached it (None: not reached).
    pub(crate) crossings: Vec<Option<Crossing>>,
}

struct St {
    t: f64,
    p: Vector3<f64>,
    v: Vector3<f64>,
    ground: Option<Facet>,
    impacts: u64,
    slide_start: Option<f64>,
    max_bounce: f64,
    /// The last rebound's apex height above the struck facet (m) and the time it is reached (s):
    /// it counts towards `max_bounce` only once the flight has lasted that long.
    apex: Option<(f64, f64)>,
    e_imp: f64,
    e_fric: f64,
    e_trans: f64,
    /// Kinetic energy per kg taken by barriers.
    e_barrier: f64,
    spin: (f64, Vector3<f64>),
    undecelerated: bool,
    rebound_cutoff: bool,
    crease: Option<Crease>,
    /// A floor point (m) and its `along_dip` (m): the last point where the rock was on the floor.
    r: Vector3<f64>,
    s_r: f64,
    /// How the current (or last) flight began: its landing's rule depends on it.
    flight_from: FlightFrom,
    /// The last position (m) put on or above the floor's surface ([`floor_surface_above`]):
    /// the check at a flight's start is skipped there (the floor does not change, so it would
    /// find nothing to correct).
    on_surface: Option<Vector3<f64>>,
}

impl St {
    /// The rock at time 0 at `p` (m) with velocity `v` (m/s), in flight, nothing booked yet;
    /// `base` is the floor point under it and its `along_dip` (m).
    fn start(p: Vector3<f64>, v: Vector3<f64>, base: (Vector3<f64>, f64)) -> Self {
        St {
            t: 0.0,
            p,
            v,
            ground: None,
            impacts: 0,
            slide_start: None,
            max_bounce: 0.0,
            apex: None,
            e_imp: 0.0,
            e_fric: 0.0,
            e_trans: 0.0,
            e_barrier: 0.0,
            spin: (0.0, Vector3::zeros()),
            undecelerated: false,
            rebound_cutoff: false,
            crease: None,
            r: base.0,
            s_r: base.1,
            flight_from: FlightFrom::Release,
            on_surface: None,
        }
    }
}

/// How a flight began, which decides what its landing is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FlightFrom {
    /// The release's fall: its landing is the procedure's first impact (§C.2 step 2).
    Release,
    /// A rebound of the bouncing phase: its landing is an impact with the paper's e_t.
    Rebound,
    /// A flight of the ground phase (a take-off at a convex edge, or the rebound of a landing
    /// after one): the rock stays in its sliding (rolling) phase and its landing is a re-contact
    /// ([`Run::recontact`]).
    TakeOff,
}

/// A concave edge (V-shaped crease) that holds the rock: it slides along the edge line.
#[derive(Debug, Clone, Copy)]
struct Crease {
    /// Edge end points (3-D).
    ends: [Vector3<f64>; 2],
    /// Unit direction from ends[0] to ends[1].
    e: Vector3<f64>,
    /// Total normal force per kg of the two faces, N_A + N_B.
    n_tot: f64,
}

/// Largest time, s, for the rock to ride up the far face of a concave edge and come back, below
/// which it is taken to slide along the edge (the alternative is an endless zig-zag across it).
const CREASE_RETURN_TIME: f64 = 1e-4;

/// The crease at the concave edge `ends` between facets with normals na (the one the rock
/// comes from) and nb, when both faces slope down towards the edge and the rock, moving into b
/// with in-plane speed w across the edge, would come back within [`CREASE_RETURN_TIME`].
fn crease_of(
    ends: [Vector3<f64>; 2],
    na: &Vector3<f64>,
    nb: &Vector3<f64>,
    out_a: &Vector3<f64>,
    v: &Vector3<f64>,
    g: f64,
) -> Option<Crease> {
    let c = na.cross(nb);
    // |kink| ≤ |n_a × n_b|: (nearly) coplanar facets need no edge direction
    if c.norm_squared() < 1e-12 {
        return None;
    }
    let e = (ends[1] - ends[0]).try_normalize(0.0)?;
    let kink = c.dot(&e);
    if kink.abs() < 1e-6 {
        return None;
    }
    let gv = Vector3::new(0.0, 0.0, -g);
    let mut mb = nb.cross(&e);
    if mb.dot(out_a) < 0.0 {
        mb = -mb;
    }
    let mut ma = na.cross(&e);
    if ma.dot(out_a) > 0.0 {
        ma = -ma;
    }
    let gb = gv.dot(&mb); // gravity along b, away from the edge
    let ga = gv.dot(&ma); // gravity along a, away from the edge
    if !(gb < -1e-9 * g && ga < -1e-9 * g) {
        return None;
    }
    let w = v.dot(&mb).max(0.0);
    if 2.0 * w / -gb > CREASE_RETURN_TIME {
        return None;
    }
    // N_A n_A + N_B n_B = −g_⊥ in the plane normal to e
    let gp = gv - e * gv.dot(&e);
    let n_a = -(gp.cross(nb)).dot(&e) / kink;
    let n_b = -(na.cross(&gp)).dot(&e) / kink;
    Some(Crease {
        ends,
        e,
        n_tot: n_a.max(0.0) + n_b.max(0.0),
    })
}

/// Unit vector normal to the crease direction e in the vertical plane through e, pointing up:
/// the normal about which a sphere rolling along the crease turns.
fn crease_up(e: &Vector3<f64>) -> Vector3<f64> {
    let z = Vector3::z();
    (z - e * e.z).try_normalize(0.0).unwrap_or(z)
}

/// Moves the rock to height `z` (a rounding-level correction onto a facet or edge) and keeps
/// KE + PE unchanged by rescaling the speed; what the kinetic energy cannot cover is booked as a
/// (signed) transition term, so the balance stays exact.
fn set_height(s: &mut St, z: f64, g: f64, ke_factor: f64) {
    let dpe = g * (z - s.p.z);
    s.p.z = z;
    if dpe == 0.0 {
        return;
    }
    let ke = 0.5 * ke_factor * s.v.norm_squared();
    if ke > 0.0 && ke >= dpe {
        s.v *= ((ke - dpe) / ke).sqrt();
    } else {
        s.e_trans -= dpe - ke;
        s.v = Vector3::zeros();
    }
}

/// Height, m, of the floor's surface at p when p is under it by more than rounding: the
/// highest plane among the facets whose triangles come within 2e-9 of a cell of p in plan
/// (at a node or an edge, the highest of the planes meeting there). A flight starts there,
/// and a strike puts the rock there: from a point under a neighbour's plane a slow rock never
/// rises through it, so no strike on it is found and the rock falls through the floor (a rock
/// rolling through a node at 3e-4 m/s took off 2e-9 m under a steeper facet's plane and fell
/// 10 m). None when p is on or above that surface (to the flight search's own rounding
/// allowance, 1e-12 of its coordinates).
fn floor_surface_above(floor: &Floor, p: &Vector3<f64>) -> Option<f64> {
    let h_round = 1e-12 * (1.0 + p.x.abs().max(p.y.abs()).max(p.z.abs()));
    floor
        .top_height_near(p.x, p.y, 2e-9 * floor.cell_size())
        .filter(|&top| top - p.z > h_round)
}

/// Puts the rock on the plane of the facet it moves onto, at height `z` (see [`set_height`]),
/// then onto the floor's surface where that is higher ([`floor_surface_above`]): near a node
/// the rock may lie over a third facet whose plane is higher (3e-9 m for a rock rolling along
/// a valley through a node of a very rough grid).
fn set_floor_height(s: &mut St, floor: &Floor, z: f64, g: f64, ke_factor: f64) {
    set_height(s, z, g, ke_factor);
    if let Some(top) = floor_surface_above(floor, &s.p) {
        set_height(s, top, g, ke_factor);
    }
    s.on_surface = Some(s.p);
}

/// Smallest positive root of ½ c t² + b t − s = 0 (s > 0), or +∞.
fn reach_time(s: f64, b: f64, c: f64) -> f64 {
    if s <= 0.0 {
        return 0.0;
    }
    if c == 0.0 {
        return if b > 0.0 { s / b } else { f64::INFINITY };
    }
    let sq = if c > 0.0 {
        let q = 2.0 * c * s;
        let d = b * b + q;
        if q >= f64::MIN_POSITIVE && d.is_finite() {
            // 2cs normal: √(b² + 2cs) is within its rounding of the exact value, and a sum
            // and a square root (correctly rounded, the same bits on every machine) instead of
            // the library's hypot, which took a tenth of a plane run's time
            d.sqrt()
        } else {
            // 2cs underflows (s may be subnormal) or b² overflows: the hypot form
            b.hypot((2.0 * c).sqrt() * s.sqrt())
        }
    } else {
        let disc = b * b + 2.0 * c * s;
        if disc < 0.0 {
            return f64::INFINITY;
        }
        disc.sqrt()
    };
    if b >= 0.0 {
        // the smallest positive root, in the form without cancellation for b ≥ 0
        if b + sq > 0.0 {
            2.0 * s / (b + sq)
        } else {
            f64::INFINITY
        }
    } else if c > 0.0 {
        // moving away (b < 0), turned back: the positive root (√(b² + 2cs) − b)/c, a sum of
        // two positive terms (2s/(b + √…) cancels: with s = 1e-12, b = −48 it gave 140.7 s for
        // 161.6 s)
        (sq - b) / c
    } else {
        f64::INFINITY
    }
}

/// Invariant: the rock is never below its floor. A point more than a rounding-level tolerance
/// (1e-9 of its coordinates' magnitude) under the floor is a solver defect, reported as a
/// numerical failure rather than as an answer.
pub(crate) fn check_above_floor(floor: &Floor, p: &Vector3<f64>, t: f64) -> PhysicsResult<()> {
    check_above_height(floor.height_at(p.x, p.y), p, t)
}

/// [`check_above_floor`] with the floor's height under p (None: off the floor) given.
#[inline]
fn check_above_height(z: Option<f64>, p: &Vector3<f64>, t: f64) -> PhysicsResult<()> {
    if let Some(z) = z {
        let tol = 1e-9 * (1.0 + p.x.abs().max(p.y.abs()).max(p.z.abs()).max(z.abs()));
        if p.z < z - tol || p.z.is_nan() {
            return Err(below_floor(z, p, t));
        }
    }
    Ok(())
}

/// The error of a rock found `z − p.z` m below the floor (height `z`, m) at `p` at time `t`, s:
/// out of line, so that the checks that never fail stay a few instructions.
#[cold]
#[inline(never)]
fn below_floor(z: f64, p: &Vector3<f64>, t: f64) -> PhysicsError {
    PhysicsError::Numerical(format!(
        "lumped mass: the rock is {:.3e} m below the floor at t = {t} s, \
         ({}, {}, {}): invariant violated",
        z - p.z,
        p.x,
        p.y,
        p.z
    ))
}

/// The error of a run that took more than its step limit `limit` (`steps` taken), out of line
/// (see [`below_floor`]).
#[cold]
#[inline(never)]
fn too_many_steps(steps: u64, limit: u64) -> PhysicsError {
    PhysicsError::TooManySteps {
        estimated: steps as f64,
        limit: limit as f64,
    }
}

/// The error of a rock on the ground off the floor at time `t`, s (out of line, see
/// [`below_floor`]).
#[cold]
#[inline(never)]
fn on_ground_off_floor(t: f64) -> PhysicsError {
    PhysicsError::Numerical(format!(
        "lumped mass: the rock is on the ground off the floor at t = {t} s: invariant violated"
    ))
}

/// Plan direction along which the material at a rock with velocity `v` (m/s) is read: its
/// velocity's, or down the dip (`dip`, the mean plane's down-dip unit vector) at rest.
fn zone_dir(v: &Vector3<f64>, dip: &Vector3<f64>) -> [f64; 2] {
    if v.x != 0.0 || v.y != 0.0 {
        [v.x, v.y]
    } else {
        [dip.x, dip.y]
    }
}

/// The end of the piece p + v t + ½ a t² (t ≤ `t_max`, s) of a rock at `p` (m) moving with
/// `v_now` (m/s) at the first boundary between materials it crosses, so that no piece carries
/// one μ into another zone; `t_max` without zones.
fn zone_cut(
    zones: Option<&RunZones<'_>>,
    p: &Vector3<f64>,
    v_now: &Vector3<f64>,
    dip: &Vector3<f64>,
    (v, a): (&Vector3<f64>, &Vector3<f64>),
    t_max: f64,
) -> f64 {
    match zones {
        Some(z) => {
            let p = [p.x, p.y];
            let probe = super::terrain::Zones::probe(p, zone_dir(v_now, dip));
            z.zones
                .cut(p, [v.x, v.y], [a.x, a.y], probe, t_max)
                .unwrap_or(t_max)
        }
        None => t_max,
    }
}

/// Runs one trajectory. `draw` gives (e_n, e_t) at each impact, e_n first; on a floor of
/// several materials (`zones`) μ is the material's under the rock and `draw` reads the struck
/// material from [`RunZones::current`], set before each call.
pub(crate) fn simulate(
    su: &Setup<'_>,
    mu: f64,
    zones: Option<&RunZones<'_>>,
    draw: &mut impl FnMut() -> (f64, f64),
    rec: Option<&mut Recording>,
    control: Option<&Control>,
) -> PhysicsResult<RunOut> {
    simulate_on(su, mu, zones, draw, rec, control, plane_loop_allowed())
}

/// Whether runs may take the plane loop: always, but in the tests that compare whole answers
/// through both loops ([`plane`]'s tests), which turn it off for a while.
#[cfg(not(test))]
#[inline(always)]
fn plane_loop_allowed() -> bool {
    true
}

/// Set by [`plane`]'s tests to send every run through the general loop.
#[cfg(test)]
static GENERAL_LOOP_ONLY: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether runs may take the plane loop (not while [`GENERAL_LOOP_ONLY`] is set).
#[cfg(test)]
fn plane_loop_allowed() -> bool {
    !GENERAL_LOOP_ONLY.load(std::sync::atomic::Ordering::SeqCst)
}

/// [`simulate`], through the plane loop ([`Run::step_plane`]) when `plane_loop` is set and the
/// case allows it ([`Run::plane_only`]), through the general loop otherwise: the same answer
/// either way, to the bit.
fn simulate_on(
    su: &Setup<'_>,
    mu: f64,
    zones: Option<&RunZones<'_>>,
    draw: &mut impl FnMut() -> (f64, f64),
    rec: Option<&mut Recording>,
    control: Option<&Control>,
    plane_loop: bool,
) -> PhysicsResult<RunOut> {
    let mut run = Run::new(su, mu, rec);
    run.zones = zones;
    let (phase, reason) = match run.plane_only().filter(|_| plane_loop) {
        Some(pl) => loop {
            if let Some(end) = run.step_plane(&pl, draw, control)? {
                break end;
            }
        },
        None => loop {
            if let Some(end) = run.step(draw, control)? {
                break end;
            }
        },
    };
    run.finish(phase, reason)
}

/// Counters that tell a rock caught in place (a Zeno series of hops or slides at a node or
/// crease) from one that moves on.
struct Catch {
    /// Length, m, below which a flight is a hop in place ([`trap_length`]).
    len: f64,
    /// Consecutive hops in place.
    hops: u32,
    /// Consecutive pieces within 1000 hop lengths of `still_at`.
    still: u32,
    /// Where the rock was last caught, m.
    anchor: Vector3<f64>,
    /// The point the rock has stayed near, m.
    still_at: Vector3<f64>,
    /// Times caught at `anchor` in a row.
    caught: u32,
    /// Position at the start of the previous piece, m.
    p_last: Vector3<f64>,
}

/// A run in progress: its fixed inputs, the rock's state and energy account, the recording of
/// events and trajectory pieces, and the counters of steps and of a rock caught in place.
struct Run<'a, 'r> {
    su: &'a Setup<'a>,
    floor: &'a Floor,
    mean: MeanPlane,
    /// Gravity, m/s², and its vector.
    g: f64,
    gv: Vector3<f64>,
    /// Down-dip unit vector of the mean plane.
    dip: Vector3<f64>,
    /// Coulomb friction coefficient of this run (on a floor of several materials: of the
    /// material under the rock, renewed at every step).
    mu: f64,
    /// The floor's materials in this run (None: one material).
    zones: Option<&'r RunZones<'r>>,
    /// Rolling (spin-up ×5/7, KE = 0.7 v²) rather than sliding.
    roll: bool,
    /// Kinetic energy per kg on the ground over ½ v²: 1.4 rolling, 1 sliding.
    ke_factor: f64,
    /// Whether any support is a column (checked along every piece).
    has_columns: bool,
    s: St,
    rec: Option<&'r mut Recording>,
    /// Closed-form pieces so far.
    steps: u64,
    /// Consecutive slide pieces of zero length (stuck on a vertex by rounding).
    zero_steps: u32,
    catch: Catch,
    /// The support reached.
    hit: Option<usize>,
    /// The next line the rock can reach (index into the setup's lines).
    next_line: usize,
    /// Per line, the rock's state where it reached it.
    crossings: Vec<Option<Crossing>>,
}

/// How one step of a run ends: the run goes on (`None`) or ends in this phase for this reason.
type StepEnd = Option<(Phase, StopReason)>;

impl<'a, 'r> Run<'a, 'r> {
    /// The run at its release: in flight, or on the ground for a release on the floor.
    fn new(su: &'a Setup<'a>, mu: f64, rec: Option<&'r mut Recording>) -> Self {
        let floor = su.floor;
        let mean = floor.mean;
        let g = su.g;
        let roll = su.motion == Motion::Roll;
        let s = St::start(su.p0, su.v0, su.base);
        let p = s.p;
        let mut run = Run {
            su,
            floor,
            mean,
            g,
            gv: Vector3::new(0.0, 0.0, -g),
            dip: mean.dip_dir(),
            mu,
            zones: None,
            roll,
            ke_factor: if roll { 1.4 } else { 1.0 },
            has_columns: su.supports.iter().any(|c| c.across.is_some()),
            s,
            rec,
            steps: 0,
            zero_steps: 0,
            catch: Catch {
                len: trap_length(floor),
                hops: 0,
                still: 0,
                anchor: p,
                still_at: p,
                caught: 0,
                p_last: p,
            },
            hit: None,
            next_line: first_reachable(
                su.lines,
                su.base.1 + (su.p0 - su.base.0).dot(&mean.dip_dir()),
            ),
            crossings: vec![None; su.lines.len()],
        };
        if let Some(f) = su.on_floor {
            run.s.flight_from = FlightFrom::TakeOff;
            run.enter_ground(f);
        }
        run
    }

    /// Records the event `ev` makes of the rock's state when the run is recorded (an ensemble's
    /// runs, unrecorded, neither build nor compute it).
    #[inline]
    fn push_event(&mut self, ev: impl FnOnce(&St) -> EventRec) {
        if let Some(r) = self.rec.as_deref_mut() {
            r.events.push(ev(&self.s));
        }
    }

    /// Records the trajectory piece `seg` makes of the rock's state (at the piece's start) when
    /// the run is recorded.
    #[inline]
    fn push_segment(&mut self, seg: impl FnOnce(&St) -> Segment) {
        if let Some(r) = self.rec.as_deref_mut() {
            r.segments.push(seg(&self.s));
        }
    }

    /// Starts the ground phase on facet f (slide, or roll with the spin-up ×5/7).
    fn enter_ground(&mut self, f: Facet) {
        let s = &mut self.s;
        let v2 = s.v.norm_squared();
        let mut lost = 0.0;
        if self.roll {
            lost = 0.5 * v2 * (2.0 / 7.0);
            s.e_trans += lost;
            s.v *= 5.0 / 7.0;
        }
        self.ground_phase(f, v2.sqrt(), lost);
    }

    /// The rock is on facet f from now on, its velocity set: the spin of a flight dropped,
    /// the run's slide start set if it is the first, and the `slide_start` (`roll_start`)
    /// event recorded with the speed before (m/s) and the energy lost per kg.
    fn ground_phase(&mut self, f: Facet, speed_before: f64, lost: f64) {
        let s = &mut self.s;
        s.ground = Some(f);
        s.spin = (0.0, Vector3::zeros());
        if s.slide_start.is_none() {
            s.slide_start = Some(self.mean.along(&s.p));
        }
        let roll = self.roll;
        self.push_event(|s| EventRec {
            t: s.t,
            kind: if roll {
                EventKind::RollStart
            } else {
                EventKind::SlideStart
            },
            p: s.p,
            speed_before,
            speed_after: s.v.norm(),
            lost,
        });
    }

    /// Moves onto facet `fb` at a facet change. Where the new facet falls away faster than the
    /// free parabola (the velocity points out of it: a convex edge) the rock takes off, a
    /// rolling one keeping its spin about `spin_normal` (the new facet's normal when `None`);
    /// otherwise the velocity is projected onto the facet and the lost normal energy booked as
    /// transition. Returns the new facet's plane when the rock stays on the ground, `None` on
    /// take-off.
    fn change_facet(&mut self, fb: Facet, spin_normal: Option<Vector3<f64>>) -> Option<FacetPlane> {
        let plb = self.floor.facet_plane(fb);
        let nb = plb.normal();
        let z = plb.z(self.s.p.x, self.s.p.y);
        set_floor_height(&mut self.s, self.floor, z, self.g, self.ke_factor);
        let s = &mut self.s;
        let vn = s.v.dot(&nb);
        let sp = s.v.norm();
        if vn > 1e-9 * sp + 1e-12 {
            s.ground = None;
            s.flight_from = FlightFrom::TakeOff;
            if self.roll {
                s.spin = (
                    0.2 * sp * sp,
                    spin_normal.unwrap_or(nb).cross(&s.v) / self.su.radius,
                );
            }
            self.push_event(|s| EventRec {
                t: s.t,
                kind: EventKind::TakeOff,
                p: s.p,
                speed_before: sp,
                speed_after: sp,
                lost: 0.0,
            });
            None
        } else {
            self.reattach(&nb, vn.min(0.0));
            self.s.ground = Some(fb);
            Some(plb)
        }
    }

    /// Puts the velocity into a plane of unit normal `n` that the sliding (rolling) rock meets at
    /// normal speed `vn` (m/s, ≤ 0) at a concave edge; returns the energy lost per kg. The
    /// meeting is a plastic impact with Coulomb friction: the normal speed is lost (booked as
    /// transition, ½ vₙ²: second order in the kink's angle) and a sliding rock loses the friction
    /// impulse μ|vₙ| along its motion (booked as friction; a rolling one has no slip). Summed over
    /// the kinks of a curve that is μ v² κ per metre, the work of the centripetal part of the
    /// normal force, so a finer floor converges to the continuous slide; the loss is continuous
    /// in vₙ and tends to 0 with it (the plastic limit of [`Run::recontact`], without a rebound).
    fn reattach(&mut self, n: &Vector3<f64>, vn: f64) -> f64 {
        let kf = self.ke_factor;
        let mu = self.mu_here();
        let s = &mut self.s;
        let sp = s.v.norm();
        let vt = s.v - n * vn;
        let vtn = vt.norm();
        let Some(dir) = vt.try_normalize(0.0) else {
            let lost = 0.5 * kf * sp * sp;
            s.e_trans += lost;
            s.v = Vector3::zeros();
            return lost;
        };
        let l_normal = 0.5 * kf * (sp * sp - vtn * vtn);
        s.e_trans += l_normal;
        let after = if self.roll {
            vtn
        } else {
            (vtn - mu * -vn).max(0.0)
        };
        let l = 0.5 * kf * (vtn * vtn - after * after);
        s.e_fric += l;
        s.v = dir * after;
        l_normal + l
    }

    /// μ of the floor under the rock, moving as it moves (the material's on a floor of several
    /// materials, the run's otherwise).
    fn mu_here(&self) -> f64 {
        match self.zones {
            Some(z) => z.mu_at([self.s.p.x, self.s.p.y], self.zone_dir()),
            None => self.mu,
        }
    }

    /// Plan direction along which the material at the rock is read ([`zone_dir`]).
    fn zone_dir(&self) -> [f64; 2] {
        zone_dir(&self.s.v, &self.dip)
    }

    /// The first column reached by the piece p + v τ + ½ a τ² within τ ≤ dt: its time and index.
    fn column_reach(&self, v: &Vector3<f64>, a: &Vector3<f64>, dt: f64) -> Option<(f64, usize)> {
        if self.has_columns {
            super::first_column_reach(&self.mean, self.su.supports, &self.s.p, v, a, dt)
        } else {
            None
        }
    }

    /// One step: the invariants, then a rock caught in place sent on (or to rest), or one
    /// closed-form piece of flight, crease or facet motion.
    fn step(
        &mut self,
        draw: &mut impl FnMut() -> (f64, f64),
        control: Option<&Control>,
    ) -> PhysicsResult<StepEnd> {
        self.steps += 1;
        if self.steps.is_multiple_of(4096)
            && let Some(c) = control
        {
            c.check()?;
        }
        if self.steps > self.su.max_steps {
            return Err(too_many_steps(self.steps, self.su.max_steps));
        }
        self.check_invariants()?;
        if let Some(z) = self.zones {
            self.mu = z.mu_at([self.s.p.x, self.s.p.y], self.zone_dir());
        }
        if self.is_caught_in_place() {
            return Ok(self.leave_trap());
        }
        let (s, dip) = (&mut self.s, self.dip);
        if s.ground.is_some() {
            // measure along the dip from the last floor point (local terms)
            s.s_r += (s.p - s.r).dot(&dip);
            s.r = s.p;
        }
        // a flight starts on or above every plane it could strike
        if s.ground.is_none()
            && s.on_surface != Some(s.p)
            && let Some(top) = floor_surface_above(self.floor, &s.p)
        {
            set_height(s, top, self.g, 1.0);
        }
        let t_left = self.su.end_time.map_or(f64::INFINITY, |te| te - s.t);
        let along = s.s_r + (s.p - s.r).dot(&dip);
        let mut s_left = self.su.length - along;
        let moving = match s.ground {
            None => Phase::Flight,
            Some(_) if self.roll => Phase::Roll,
            Some(_) => Phase::Slide,
        };
        // the next line cuts the pieces as the lower end does; one at or above the end is
        // reached before the run ends there (a barrier stands in front of its support)
        let mut to_line = false;
        if let Some(line) = self.su.lines.get(self.next_line)
            && line.along_dip <= self.su.length
        {
            let d = line.along_dip - along;
            if d <= 0.0 {
                return Ok(self.cross_line());
            }
            to_line = d <= s_left;
            s_left = s_left.min(d);
        }
        let s = &mut self.s;
        if s_left <= 0.0 {
            return Ok(Some((moving, StopReason::LowerEnd)));
        }
        if t_left <= 0.0 {
            return Ok(Some((moving, StopReason::EndTime)));
        }
        let diss0 = s.e_imp + s.e_fric + s.e_trans + s.e_barrier;
        let end = match (s.ground, s.crease) {
            (None, _) => self.flight_step(draw, t_left, s_left, diss0),
            (Some(_), Some(c)) => self.crease_step(c, t_left, s_left, moving),
            (Some(f), None) => self.ground_step(f, t_left, s_left, diss0, moving),
        };
        // a piece that reached the distance left reached the line when the line cut it
        Ok(match end {
            Some((_, StopReason::LowerEnd)) if to_line => self.cross_line(),
            e => e,
        })
    }

    /// The rock reached the next line: its state recorded, the
    /// barrier's action applied (see [`super::lines`]). Ends the run when a barrier stopped it.
    fn cross_line(&mut self) -> StepEnd {
        let k = self.next_line;
        self.next_line += 1;
        let line = self.su.lines[k];
        let s = &mut self.s;
        if !line.spans(s.p.y) {
            return None;
        }
        let m = self.su.mass;
        let v2 = s.v.norm_squared();
        let (trans, rot, height) = match s.ground {
            // on the floor: a rolling rock's spin is 0.2 v² per kg
            Some(_) => (0.5 * v2, (self.ke_factor - 1.0) * 0.5 * v2, 0.0),
            None => (
                0.5 * v2,
                s.spin.0,
                super::trajectory::height_above_floor(self.floor, &s.p, &s.v).max(0.0),
            ),
        };
        let energy = m * (trans + rot);
        let (action, f) = act(&line, height, energy);
        self.crossings[k] = Some(Crossing {
            time: s.t,
            across: s.p.y,
            speed: v2.sqrt(),
            translational_energy: m * trans,
            rotational_energy: m * rot,
            passing_height: height,
            action,
        });
        if !matches!(action, LineAction::Stopped | LineAction::BrokenThrough) {
            return None;
        }
        let before = v2.sqrt();
        // every velocity scales by f: the kinetic energy (per kg) by f². What is booked is the
        // rating itself (or all of the energy when stopped), not E(1 − f²), whose cancellation
        // would book a small rating with the rounding of a large energy
        let lost = match (action, line.barrier) {
            (LineAction::BrokenThrough, Some(b)) => b.rating / m,
            _ => trans + rot,
        };
        s.v *= f;
        s.spin = (s.spin.0 * f * f, s.spin.1 * f);
        s.e_barrier += lost;
        self.push_event(|s| EventRec {
            t: s.t,
            kind: EventKind::Barrier,
            p: s.p,
            speed_before: before,
            speed_after: s.v.norm(),
            lost,
        });
        // a stopped rock is at rest against the barrier
        (action == LineAction::Stopped).then_some((Phase::Stopped, StopReason::Barrier))
    }

    /// Invariants checked at every event and piece end: never below the floor, never on the
    /// ground off the floor.
    #[inline]
    fn check_invariants(&self) -> PhysicsResult<()> {
        let s = &self.s;
        let z = self.floor.height_at(s.p.x, s.p.y);
        check_above_height(z, &s.p, s.t)?;
        if s.ground.is_some() && z.is_none() {
            return Err(on_ground_off_floor(s.t));
        }
        Ok(())
    }

    /// The outcome of a run that ended in `phase` for `reason`: the last invariant check, the
    /// stop event, the rotation and the account.
    fn finish(&mut self, phase: Phase, reason: StopReason) -> PhysicsResult<RunOut> {
        let (floor, su) = (self.floor, self.su);
        // invariant: the state the run ends in is above the floor too (the last piece is not
        // checked inside the loop)
        check_above_floor(floor, &self.s.p, self.s.t)?;
        // the lower end of this run is a spanning support's position when one stands there
        let reason = match (reason, su.span_support) {
            (StopReason::LowerEnd, Some(k)) => {
                self.hit = Some(k);
                StopReason::Support
            }
            (r, _) => r,
        };
        let stopped = phase == Phase::Stopped;
        if stopped {
            self.push_event(|s| EventRec {
                t: s.t,
                kind: EventKind::Stop,
                p: s.p,
                speed_before: 0.0,
                speed_after: 0.0,
                lost: 0.0,
            });
        }
        let s = &self.s;
        let (e_rot, omega) = match (phase, s.ground) {
            (Phase::Roll, Some(f)) => {
                let n = floor.facet_plane(f).normal();
                (0.2 * s.v.norm_squared(), n.cross(&s.v) / su.radius)
            }
            (Phase::Flight, _) => s.spin,
            _ => (0.0, Vector3::zeros()),
        };
        Ok(RunOut {
            t: s.t,
            p: s.p,
            v: s.v,
            omega,
            phase,
            reason,
            impacts: s.impacts,
            slide_start: s.slide_start,
            stop_along: stopped.then(|| self.mean.along(&s.p)),
            max_bounce: s.max_bounce,
            e_imp: s.e_imp,
            e_fric: s.e_fric,
            e_trans: s.e_trans,
            e_rot,
            undecelerated: !stopped && s.ground.is_some() && s.undecelerated,
            rebound_cutoff: s.rebound_cutoff,
            steps: self.steps,
            support: self.hit,
            e_barrier: s.e_barrier,
            crossings: std::mem::take(&mut self.crossings),
        })
    }
}

#[cfg(test)]
mod tests {
    //! The lumped mass's closed-form pieces against their definitions: the reach time is the
    //! smallest positive root of ½ct² + bt − s (or +∞ when none is), and a height correction
    //! keeps KE + PE + the transition term unchanged whether or not the kinetic energy pays.
    use super::*;
    use proptest::prelude::*;

    const G: f64 = 9.81;

    /// A sliding rock's fixed inputs on `floor`: released at `p0` with velocity `v0`, on the
    /// floor's facet `on_floor` (None: in flight), stop speed 0.1 m/s, no support, no end time.
    fn setup(
        floor: &Floor,
        p0: Vector3<f64>,
        v0: Vector3<f64>,
        on_floor: Option<Facet>,
    ) -> Setup<'_> {
        let z = floor.height_at(p0.x, p0.y).expect("release over the floor");
        let base = Vector3::new(p0.x, p0.y, z);
        Setup {
            floor,
            g: G,
            motion: Motion::Slide,
            v_stop: 0.1,
            radius: 0.1,
            length: 1e3,
            span_support: None,
            supports: &[],
            lines: &[],
            mass: 1.0,
            end_time: None,
            max_steps: 1000,
            p0,
            v0,
            on_floor,
            base: (base, floor.mean.along(&base)),
        }
    }

    /// KE + PE + the losses of the run so far, J/kg (sliding: KE = ½ v²).
    fn energy(run: &Run<'_, '_>) -> f64 {
        let s = &run.s;
        0.5 * s.v.norm_squared() + G * s.p.z + s.e_imp + s.e_fric + s.e_trans
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1.0)
    }

    /// One flight step on the plane of dip 30°: the parabola's strike is the root of the
    /// height above the plane, h₀ + ḣ t − ½ g t² = 0 (vertical height, ḣ = v_z − v_x tan θ);
    /// the impact applies e_n to the normal and e_t to the tangential velocity and books
    /// ½[(1 − e_n²) v_n² + (1 − e_t²) |v_t|²]; KE + PE + losses is unchanged.
    #[test]
    fn flight_step_strikes_the_plane_at_the_root_and_applies_the_restitution() {
        let th = 30f64.to_radians();
        let floor = Floor::plane(th);
        let (p0, v0) = (Vector3::new(1.0, 0.5, 2.0), Vector3::new(1.5, -0.4, 0.8));
        let su = setup(&floor, p0, v0, None);
        let mut run = Run::new(&su, 0.3, None);
        let e0 = energy(&run);
        let (en, et) = (0.35, 0.8);
        let end = run.step(&mut || (en, et), None).unwrap();
        assert_eq!(end, None);
        let h0 = p0.z + p0.x * th.tan();
        let hd = v0.z + v0.x * th.tan();
        let t = (hd + (hd * hd + 2.0 * G * h0).sqrt()) / G;
        assert!(close(run.s.t, t, 1e-14), "{} vs {t}", run.s.t);
        let q = p0 + v0 * t + Vector3::new(0.0, 0.0, -0.5 * G * t * t);
        assert!(
            (run.s.p - q).norm() <= 1e-13 * q.norm(),
            "{:?} vs {q:?}",
            run.s.p
        );
        assert!((run.s.p.z + run.s.p.x * th.tan()).abs() <= 1e-14 * q.norm());
        let vs = v0 + Vector3::new(0.0, 0.0, -G * t);
        let n = Vector3::new(th.sin(), 0.0, th.cos());
        let (vn, vt) = (vs.dot(&n), vs - n * vs.dot(&n));
        let rebound = vt * et - n * (en * vn);
        assert!(
            (run.s.v - rebound).norm() <= 1e-13 * vs.norm(),
            "{:?}",
            run.s.v
        );
        let lost = 0.5 * ((1.0 - en * en) * vn * vn + (1.0 - et * et) * vt.norm_squared());
        assert!(close(run.s.e_imp, lost, 1e-13), "{} vs {lost}", run.s.e_imp);
        assert_eq!(run.s.impacts, 1);
        assert_eq!(run.s.ground, None);
        assert!(close(energy(&run), e0, 1e-13));
    }

    /// A rebound slower than the stop speed starts the ground phase on the struck facet, its
    /// normal energy ½ r² booked as a transition loss.
    #[test]
    fn flight_step_with_a_rebound_below_the_stop_speed_lands() {
        let th = 30f64.to_radians();
        let floor = Floor::plane(th);
        let (p0, v0) = (Vector3::new(0.0, 0.0, 0.2), Vector3::zeros());
        let su = setup(&floor, p0, v0, None);
        let mut run = Run::new(&su, 0.3, None);
        let e0 = energy(&run);
        // r = e_n |v_n| = 1e-3 · √(2 g 0.2) cos θ < 0.1 m/s
        assert_eq!(run.step(&mut || (1e-3, 0.8), None).unwrap(), None);
        assert_eq!(run.s.ground, Some(0));
        let n = Vector3::new(th.sin(), 0.0, th.cos());
        assert!(run.s.v.dot(&n).abs() <= 1e-15);
        assert!(run.s.e_trans > 0.0);
        assert!(close(energy(&run), e0, 1e-13));
    }

    /// One ground step from rest straight down the plane (the friction direction never turns)
    /// reaches the lower end in closed form: t = √(2L/a), a = g(sin θ − μ cos θ), speed a t,
    /// friction work μ g cos θ L.
    #[test]
    fn ground_step_down_the_plane_reaches_the_lower_end_in_one_piece() {
        let (th, mu) = (40f64.to_radians(), 0.3);
        let floor = Floor::plane(th);
        let p0 = Vector3::new(0.0, 0.0, 0.0);
        let su = setup(&floor, p0, Vector3::zeros(), Some(0));
        let mut run = Run::new(&su, mu, None);
        let e0 = energy(&run);
        let end = run.step(&mut || unreachable!("no impact"), None).unwrap();
        assert_eq!(end, Some((Phase::Slide, StopReason::LowerEnd)));
        assert_eq!(run.steps, 1);
        let l = su.length;
        let a = G * (th.sin() - mu * th.cos());
        let t = (2.0 * l / a).sqrt();
        assert!(close(run.s.t, t, 1e-13), "{} vs {t}", run.s.t);
        assert!(close(run.s.v.norm(), a * t, 1e-13));
        assert!(close(run.s.e_fric, mu * G * th.cos() * l, 1e-13));
        assert!(close(floor.mean.along(&run.s.p), l, 1e-13));
        assert!(close(energy(&run), e0, 1e-12));
    }

    /// Sliding up the plane, the rock decelerates at g(sin θ + μ cos θ) and the piece ends
    /// where the speed is zero: t = v₀/a, distance v₀²/(2a).
    #[test]
    fn ground_step_up_the_plane_stops_at_the_closed_form_point() {
        let (th, mu) = (20f64.to_radians(), 0.5);
        let floor = Floor::plane(th);
        let v0 = 3.0;
        let p0 = Vector3::new(10.0 * th.cos(), 0.0, -10.0 * th.sin());
        let up = Vector3::new(-th.cos(), 0.0, th.sin());
        let su = setup(&floor, p0, up * v0, Some(0));
        let mut run = Run::new(&su, mu, None);
        let e0 = energy(&run);
        assert_eq!(run.step(&mut || unreachable!(), None).unwrap(), None);
        let a = G * (th.sin() + mu * th.cos());
        assert!(close(run.s.t, v0 / a, 1e-13), "{}", run.s.t);
        assert!(run.s.v.norm() <= 1e-13 * v0, "{:?}", run.s.v);
        let moved = (run.s.p - p0).dot(&up);
        assert!(close(moved, v0 * v0 / (2.0 * a), 1e-13), "{moved}");
        assert!(close(energy(&run), e0, 1e-12));
        // μ ≥ tan θ: the next step leaves it at rest
        assert_eq!(
            run.step(&mut || unreachable!(), None).unwrap(),
            Some((Phase::Stopped, StopReason::AtRest))
        );
    }

    /// A grid folded along x = 1 (slope tan θ₁ for x < 1, tan θ₂ beyond) with the rock
    /// sliding down the upper part without friction.
    fn folded(t1: f64, t2: f64) -> Floor {
        let z = |x: f64| {
            if x <= 1.0 {
                -x * t1
            } else {
                -t1 - (x - 1.0) * t2
            }
        };
        let heights = vec![vec![z(0.0), z(1.0), z(2.0)]; 3];
        Floor::grid(t1.atan(), [0.0, -1.0], 1.0, &heights).unwrap()
    }

    /// The speed at the fold after sliding from x = 0.5 with speed v₀, without friction:
    /// √(v₀² + 2 g · 0.5 tan θ₁), along (cos θ₁, 0, −sin θ₁).
    fn velocity_at_the_fold(th1: f64, v0: f64) -> Vector3<f64> {
        let sp = (v0 * v0 + 2.0 * G * 0.5 * th1.tan()).sqrt();
        Vector3::new(th1.cos(), 0.0, -th1.sin()) * sp
    }

    /// At a concave fold (the lower part less steep) the rock stays on the floor: its velocity
    /// is projected onto the new facet and the normal part's energy ½ (v·n₂)² is booked as a
    /// transition loss; the facets of the upper part are crossed in one piece.
    #[test]
    fn edge_transition_at_a_concave_fold_projects_the_velocity() {
        let (th1, th2) = (40f64.to_radians(), 15f64.to_radians());
        let floor = folded(th1.tan(), th2.tan());
        let v0 = 1.2;
        let p0 = Vector3::new(0.5, -0.3, -0.5 * th1.tan());
        let vel = Vector3::new(th1.cos(), 0.0, -th1.sin()) * v0;
        let f0 = floor.locate(p0.x, p0.y, 1.0, 0.0).unwrap();
        let su = setup(&floor, p0, vel, Some(f0));
        let mut run = Run::new(&su, 0.0, None);
        let e0 = energy(&run);
        assert_eq!(run.step(&mut || unreachable!(), None).unwrap(), None);
        let fb = run.s.ground.expect("stays on the floor");
        assert!(
            floor
                .facet_corners(fb)
                .unwrap()
                .0
                .iter()
                .all(|c| c[0] >= 1.0)
        );
        assert!((run.s.p.x - 1.0).abs() <= 1e-14, "{:?}", run.s.p);
        let v = velocity_at_the_fold(th1, v0);
        let n2 = Vector3::new(th2.sin(), 0.0, th2.cos());
        let vp = v - n2 * v.dot(&n2);
        assert!(
            (run.s.v - vp).norm() <= 1e-13 * v.norm(),
            "{:?} vs {vp:?}",
            run.s.v
        );
        let lost = 0.5 * v.dot(&n2).powi(2);
        assert!(
            close(run.s.e_trans, lost, 1e-12),
            "{} vs {lost}",
            run.s.e_trans
        );
        assert!(close(energy(&run), e0, 1e-13));
        assert_eq!(run.steps, 1);
    }

    /// At a convex fold (the lower part steeper) the rock takes off with its velocity
    /// unchanged, nothing booked.
    #[test]
    fn edge_transition_at_a_convex_fold_takes_off() {
        let (th1, th2) = (20f64.to_radians(), 50f64.to_radians());
        let floor = folded(th1.tan(), th2.tan());
        let v0 = 0.7;
        let p0 = Vector3::new(0.5, -0.3, -0.5 * th1.tan());
        let vel = Vector3::new(th1.cos(), 0.0, -th1.sin()) * v0;
        let f0 = floor.locate(p0.x, p0.y, 1.0, 0.0).unwrap();
        let su = setup(&floor, p0, vel, Some(f0));
        let mut run = Run::new(&su, 0.0, None);
        let e0 = energy(&run);
        assert_eq!(run.step(&mut || unreachable!(), None).unwrap(), None);
        assert_eq!(run.s.ground, None);
        let v = velocity_at_the_fold(th1, v0);
        assert!(
            (run.s.v - v).norm() <= 1e-13 * v.norm(),
            "{:?} vs {v:?}",
            run.s.v
        );
        assert!(run.s.e_trans.abs() <= 1e-15, "{}", run.s.e_trans);
        assert!(close(energy(&run), e0, 1e-13));
    }

    #[test]
    fn reach_time_limits() {
        assert_eq!(reach_time(0.0, 1.0, 1.0), 0.0);
        assert_eq!(reach_time(2.0, 4.0, 0.0), 0.5);
        assert_eq!(reach_time(2.0, 0.0, 0.0), f64::INFINITY);
        assert_eq!(reach_time(2.0, -1.0, 0.0), f64::INFINITY);
        // decelerating short of the distance: ½·(−1)t² + t reaches at most ½
        assert_eq!(reach_time(0.6, 1.0, -1.0), f64::INFINITY);
        assert!((reach_time(0.5, 1.0, -1.0) - 1.0).abs() < 1e-7);
        // moving away from a point 1e-12 ahead, turned back by c: about 2|b|/c, not a
        // cancelled 2s/(b + √(b² + 2cs))
        let t = reach_time(1e-12, -47.973_241_626_730_555, 0.593_719_326_964_338_2);
        assert!((t / (2.0 * 47.973_241_626_730_555 / 0.593_719_326_964_338_2) - 1.0).abs() < 1e-12);
        // a subnormal distance from rest: t = √(2s/c), with no underflow to 0
        let t = reach_time(5e-324, 0.0, 9.81);
        assert!(
            t > 0.0 && ((0.5 * 9.81 * t * t) / 5e-324 - 1.0).abs() < 0.5,
            "{t}"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// t solves ½ct² + bt = s to rounding, and no smaller positive time does (the motion
        /// covers less than s at every earlier time).
        #[test]
        fn reach_time_is_the_first_root(
            s in prop_oneof![1e-12..1.0f64, 1.0..1e4f64],
            b in -50.0..50.0f64,
            c in prop_oneof![-50.0..50.0f64, Just(0.0)],
        ) {
            let t = reach_time(s, b, c);
            let x = |t: f64| 0.5 * c * t * t + b * t;
            if t.is_finite() {
                prop_assert!(t > 0.0);
                let scale = (0.5 * c * t * t).abs() + (b * t).abs() + s;
                prop_assert!((x(t) - s).abs() <= 1e-12 * scale, "x({t}) = {} for s {s}", x(t));
                for k in 1..8 {
                    let tk = t * f64::from(k) / 8.0;
                    prop_assert!(x(tk) < s + 1e-12 * scale, "reached s earlier, at {tk}");
                }
            } else {
                // never reached: the farthest point of the motion falls short of s
                let farthest = if c < 0.0 && b > 0.0 { -b * b / (2.0 * c) } else if c < 0.0 || (c == 0.0 && b <= 0.0) { 0.0 } else { f64::INFINITY };
                prop_assert!(farthest < s * (1.0 + 1e-12), "b {b} c {c} s {s}");
            }
        }

        /// Moving the rock to another height keeps KE + PE + the transition term: the speed pays
        /// for a rise it can afford, and what it cannot is booked (the speed is then 0).
        #[test]
        fn a_height_correction_keeps_the_energy_account(
            v in prop::array::uniform3(-20.0..20.0f64),
            z0 in -100.0..100.0f64,
            dz in prop_oneof![-1e-6..1e-6f64, -10.0..10.0f64],
            kf in prop_oneof![Just(1.0), Just(1.4)],
        ) {
            let g = 9.81;
            let p = Vector3::new(1.0, 2.0, z0);
            let mut s = St::start(p, Vector3::from(v), (p, 0.0));
            let total = |s: &St| 0.5 * kf * s.v.norm_squared() + g * s.p.z + s.e_trans;
            let before = total(&s);
            set_height(&mut s, z0 + dz, g, kf);
            prop_assert_eq!(s.p.z, z0 + dz);
            let scale = 0.5 * kf * v.iter().map(|x| x * x).sum::<f64>() + g * (z0.abs() + dz.abs()) + 1.0;
            prop_assert!((total(&s) - before).abs() <= 1e-13 * scale, "{} against {before}", total(&s));
            // only a rise the speed cannot pay for is booked (as a negative transition loss)
            let ke = 0.5 * kf * v.iter().map(|x| x * x).sum::<f64>();
            if ke >= g * dz {
                prop_assert_eq!(s.e_trans, 0.0);
            } else {
                prop_assert!(s.e_trans < 0.0 && s.v == Vector3::zeros(), "{}", s.e_trans);
            }
        }
    }
}

//! Lumped-mass energy tracking method (physics.md §C.2), event driven with closed-form phases.
//!
//! The rock is a point mass. Flights are parabolas whose first strike of the floor is a root of a
//! quadratic; an impact applies the normal and tangential restitution in the struck facet's frame;
//! a rebound slower than the stop speed starts the ground phase (slide, or roll as a sphere). On a
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

use super::terrain::{Facet, FacetPlane, FlightEnd, Floor, MeanPlane, inside_tri};
use crate::physics::control::Control;
use crate::physics::error::{PhysicsError, PhysicsResult};

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
    spin: (f64, Vector3<f64>),
    undecelerated: bool,
    rebound_cutoff: bool,
    crease: Option<Crease>,
    /// A floor point (m) and its `along_dip` (m): the last point where the rock was on the floor.
    r: Vector3<f64>,
    s_r: f64,
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
            spin: (0.0, Vector3::zeros()),
            undecelerated: false,
            rebound_cutoff: false,
            crease: None,
            r: base.0,
            s_r: base.1,
            on_surface: None,
        }
    }
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
        // √(b² + 2cs) without underflow of 2cs (s may be subnormal)
        b.hypot((2.0 * c).sqrt() * s.sqrt())
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

/// Number of consecutive flights shorter than [`trap_length`] after which the rock is taken to
/// be caught at a concave node or crease (a Zeno series of ever smaller hops at one point).
const TRAP_HOPS: u32 = 3;

/// Number of consecutive pieces of any kind that keep the rock within 1000 × [`trap_length`]
/// (1e-6 of the facet size) of one point after which it is taken to be caught (a Zeno series
/// of ever shorter slides or swings about a node).
const TRAP_STILL: u32 = 64;

/// Number of times a rock may be caught at one point and sent on before it is taken to be at
/// rest there (every way out has led back to it, with ever less energy).
const TRAP_RETURNS: u32 = 4;

/// Length, m, below which a flight is a hop in place: 1e-9 of the floor's facet size.
fn trap_length(floor: &Floor) -> f64 {
    1e-9 * floor.cell_size()
}

/// Invariant: the rock is never below its floor. A point more than a rounding-level tolerance
/// (1e-9 of its coordinates' magnitude) under the floor is a solver defect, reported as a
/// numerical failure rather than as an answer.
pub(crate) fn check_above_floor(floor: &Floor, p: &Vector3<f64>, t: f64) -> PhysicsResult<()> {
    check_above_height(floor.height_at(p.x, p.y), p, t)
}

/// [`check_above_floor`] with the floor's height under p (None: off the floor) given.
fn check_above_height(z: Option<f64>, p: &Vector3<f64>, t: f64) -> PhysicsResult<()> {
    if let Some(z) = z {
        let tol = 1e-9 * (1.0 + p.x.abs().max(p.y.abs()).max(p.z.abs()).max(z.abs()));
        if p.z < z - tol || p.z.is_nan() {
            return Err(PhysicsError::Numerical(format!(
                "lumped mass: the rock is {:.3e} m below the floor at t = {t} s, \
                 ({}, {}, {}): invariant violated",
                z - p.z,
                p.x,
                p.y,
                p.z
            )));
        }
    }
    Ok(())
}

/// How a rock caught at a point (a node, an edge or a facet) goes on.
#[derive(Debug, Clone, Copy)]
enum TrapExit {
    /// No facet or crease around the point lets gravity overcome friction: at rest.
    Rest(Option<Facet>),
    /// Slides (rolls) onto this facet along the unit direction of gravity's in-plane part.
    Facet(Facet, Vector3<f64>),
    /// Slides (rolls) along this crease (a concave edge both faces slope down to).
    Crease(Facet, Crease),
}

/// Decides how a rock caught at p (on the floor) leaves: onto the facet or along the crease
/// with the largest driving acceleration (gravity's part along the motion less friction), or
/// at rest when none is positive. A point mass in a V-shaped crease moves along the crease line.
fn resolve_trap(floor: &Floor, p: &Vector3<f64>, g: f64, mu: f64, roll: bool) -> TrapExit {
    let gv = Vector3::new(0.0, 0.0, -g);
    let tol = 1e-7 * floor.cell_size();
    let mut facets: Vec<Facet> = Vec::new();
    for k in 0..24 {
        let a = std::f64::consts::TAU * k as f64 / 24.0;
        if let Some(f) = floor.locate(p.x, p.y, a.cos(), a.sin())
            && !facets.contains(&f)
        {
            facets.push(f);
        }
    }
    let mut best: Option<(f64, TrapExit)> = None;
    let mut consider = |drive: f64, ex: TrapExit| {
        if drive > 1e-12 * g && best.is_none_or(|b| drive > b.0) {
            best = Some((drive, ex));
        }
    };
    for &f in &facets {
        let pl = floor.facet_plane(f);
        let n = pl.normal();
        let gt = gv + n * (g * n.z);
        let gtn = gt.norm();
        let corners = floor.facet_corners(f);
        if gtn > 1e-12 * g {
            let into = match &corners {
                None => true,
                Some((c, _)) => {
                    let size = (0..3)
                        .map(|k| {
                            let (a, b) = (c[k], c[(k + 1) % 3]);
                            (b[0] - a[0]).hypot(b[1] - a[1])
                        })
                        .fold(f64::INFINITY, f64::min);
                    let h = gt.x.hypot(gt.y);
                    h > 0.0 && {
                        let eps = 1e-6 * size;
                        inside_tri(c, p.x + eps * gt.x / h, p.y + eps * gt.y / h, 0.0)
                    }
                }
            };
            let drive = if roll {
                gtn * (5.0 / 7.0)
            } else {
                gtn - mu * g * n.z
            };
            if into {
                consider(drive, TrapExit::Facet(f, gt / gtn));
            }
        }
        let Some((c, z)) = corners else { continue };
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let len = ex.hypot(ey);
            if len == 0.0 {
                continue;
            }
            let off = (ex * (p.y - a[1]) - ey * (p.x - a[0])) / len;
            let u = ((p.x - a[0]) * ex + (p.y - a[1]) * ey) / len;
            if off.abs() > tol || u < -tol || u > len + tol {
                continue;
            }
            // horizontal normal of the edge pointing out of f
            let third = c[(k + 2) % 3];
            let mut out = Vector3::new(ey, -ex, 0.0);
            if out.x * (third[0] - a[0]) + out.y * (third[1] - a[1]) > 0.0 {
                out = -out;
            }
            let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            let Some(fb) = floor.locate(mid[0], mid[1], out.x, out.y) else {
                continue;
            };
            if fb == f {
                continue;
            }
            let nb = floor.facet_plane(fb).normal();
            let p3 = Vector3::new(p.x, p.y, pl.z(p.x, p.y));
            for (q, qz) in [(a, z[k]), (b, z[(k + 1) % 3])] {
                if (q[0] - p.x).hypot(q[1] - p.y) <= tol {
                    continue;
                }
                let q3 = Vector3::new(q[0], q[1], qz);
                if let Some(cr) = crease_of([p3, q3], &n, &nb, &out, &Vector3::zeros(), g) {
                    let ge = gv.dot(&cr.e);
                    let drive = if roll {
                        ge * (5.0 / 7.0)
                    } else {
                        ge - mu * cr.n_tot
                    };
                    consider(drive, TrapExit::Crease(f, cr));
                }
            }
        }
    }
    match best {
        Some((_, ex)) => ex,
        None => TrapExit::Rest(facets.first().copied()),
    }
}

/// Runs one trajectory. `draw` gives (e_n, e_t) at each impact, e_n first.
pub(crate) fn simulate(
    su: &Setup<'_>,
    mu: f64,
    draw: &mut impl FnMut() -> (f64, f64),
    rec: Option<&mut Recording>,
    control: Option<&Control>,
) -> PhysicsResult<RunOut> {
    let mut run = Run::new(su, mu, rec);
    let (phase, reason) = loop {
        if let Some(end) = run.step(draw, control)? {
            break end;
        }
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
    /// Coulomb friction coefficient of this run.
    mu: f64,
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
        };
        if let Some(f) = su.on_floor {
            run.enter_ground(f);
        }
        run
    }

    /// Records an event when the run is recorded.
    fn push_event(&mut self, ev: EventRec) {
        if let Some(r) = self.rec.as_deref_mut() {
            r.events.push(ev);
        }
    }

    /// Records a trajectory piece when the run is recorded.
    fn push_segment(&mut self, seg: Segment) {
        if let Some(r) = self.rec.as_deref_mut() {
            r.segments.push(seg);
        }
    }

    /// Starts the ground phase on facet f (slide, or roll with the spin-up ×5/7).
    fn enter_ground(&mut self, f: Facet) {
        let roll = self.roll;
        let s = &mut self.s;
        s.ground = Some(f);
        if s.slide_start.is_none() {
            s.slide_start = Some(self.mean.along(&s.p));
        }
        let v2 = s.v.norm_squared();
        let mut lost = 0.0;
        if roll {
            lost = 0.5 * v2 * (2.0 / 7.0);
            s.e_trans += lost;
            s.v *= 5.0 / 7.0;
        }
        s.spin = (0.0, Vector3::zeros());
        let ev = EventRec {
            t: s.t,
            kind: if roll {
                EventKind::RollStart
            } else {
                EventKind::SlideStart
            },
            p: s.p,
            speed_before: v2.sqrt(),
            speed_after: s.v.norm(),
            lost,
        };
        self.push_event(ev);
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
            if self.roll {
                s.spin = (
                    0.2 * sp * sp,
                    spin_normal.unwrap_or(nb).cross(&s.v) / self.su.radius,
                );
            }
            let ev = EventRec {
                t: s.t,
                kind: EventKind::TakeOff,
                p: s.p,
                speed_before: sp,
                speed_after: sp,
                lost: 0.0,
            };
            self.push_event(ev);
            None
        } else {
            let vp = s.v - nb * vn;
            s.e_trans += 0.5 * self.ke_factor * (sp * sp - vp.norm_squared());
            s.v = vp;
            s.ground = Some(fb);
            Some(plb)
        }
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
            return Err(PhysicsError::TooManySteps {
                estimated: self.steps as f64,
                limit: self.su.max_steps as f64,
            });
        }
        self.check_invariants()?;
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
        let s_left = self.su.length - (s.s_r + (s.p - s.r).dot(&dip));
        let moving = match s.ground {
            None => Phase::Flight,
            Some(_) if self.roll => Phase::Roll,
            Some(_) => Phase::Slide,
        };
        if s_left <= 0.0 {
            return Ok(Some((moving, StopReason::LowerEnd)));
        }
        if t_left <= 0.0 {
            return Ok(Some((moving, StopReason::EndTime)));
        }
        let diss0 = s.e_imp + s.e_fric + s.e_trans;
        Ok(match (s.ground, s.crease) {
            (None, _) => self.flight_step(draw, t_left, s_left, diss0),
            (Some(_), Some(c)) => self.crease_step(c, t_left, s_left, moving),
            (Some(f), None) => self.ground_step(f, t_left, s_left, diss0, moving),
        })
    }

    /// Invariants checked at every event and piece end: never below the floor, never on the
    /// ground off the floor.
    fn check_invariants(&self) -> PhysicsResult<()> {
        let s = &self.s;
        let z = self.floor.height_at(s.p.x, s.p.y);
        check_above_height(z, &s.p, s.t)?;
        if s.ground.is_some() && z.is_none() {
            return Err(PhysicsError::Numerical(format!(
                "lumped mass: the rock is on the ground off the floor at t = {} s: invariant \
                 violated",
                s.t
            )));
        }
        Ok(())
    }

    /// Updates the counters of hops and pieces in place; true when the rock is caught (hops or
    /// slides in place shrink geometrically and would never end).
    fn is_caught_in_place(&mut self) -> bool {
        let (c, p) = (&mut self.catch, self.s.p);
        // squared distances against squared lengths: no square roots
        if (p - c.p_last).norm_squared() > c.len * c.len {
            c.hops = 0;
        }
        if (p - c.still_at).norm_squared() > (1e3 * c.len) * (1e3 * c.len) {
            c.still = 0;
            c.still_at = p;
        } else {
            c.still += 1;
        }
        c.p_last = p;
        c.hops >= TRAP_HOPS || c.still >= TRAP_STILL
    }

    /// Sends a rock caught at a node or crease on along the best way out ([`resolve_trap`]),
    /// keeping only its speed along it, or ends the run at rest there when there is none or
    /// every way out has led back to the same point.
    fn leave_trap(&mut self) -> StepEnd {
        let (floor, g, mu, roll) = (self.floor, self.g, self.mu, self.roll);
        let ke_factor = self.ke_factor;
        let c = &mut self.catch;
        let s = &mut self.s;
        c.still = 0;
        // caught at a node or crease: hops or slides in place shrink geometrically and never end
        c.hops = 0;
        let kf = if s.ground.is_some() { ke_factor } else { 1.0 };
        let before = 0.5 * kf * s.v.norm_squared() + s.spin.0;
        s.spin = (0.0, Vector3::zeros());
        // caught again and again at the same point: every way out leads back to it
        if (s.p - c.anchor).norm() <= 1e-7 * floor.cell_size() {
            c.caught += 1;
        } else {
            c.anchor = s.p;
            c.caught = 1;
        }
        let exit = if c.caught > TRAP_RETURNS {
            let f = s.ground.or_else(|| floor.locate(s.p.x, s.p.y, 0.0, 0.0));
            TrapExit::Rest(f)
        } else {
            resolve_trap(floor, &s.p, g, mu, roll)
        };
        let (f, dir) = match exit {
            TrapExit::Rest(f) => {
                s.e_trans += before;
                s.v = Vector3::zeros();
                s.crease = None;
                if s.ground.is_none() {
                    s.ground = f;
                }
                return Some((Phase::Stopped, StopReason::AtRest));
            }
            TrapExit::Facet(f, dir) => {
                s.crease = None;
                (f, dir)
            }
            TrapExit::Crease(f, c) => {
                s.p = c.ends[0];
                s.crease = Some(c);
                (f, c.e)
            }
        };
        let vd = s.v.dot(&dir).max(0.0);
        s.v = dir * vd;
        s.e_trans += before - 0.5 * kf * vd * vd;
        let z = floor.facet_plane(f).z(s.p.x, s.p.y);
        set_floor_height(s, floor, z, g, kf);
        if s.ground.is_none() {
            self.enter_ground(f);
        } else {
            s.ground = Some(f);
        }
        None
    }

    /// One flight: the parabola up to its first strike of the floor, the lower end, the end
    /// time, a column or the floor's edge; a strike is an impact.
    fn flight_step(
        &mut self,
        draw: &mut impl FnMut() -> (f64, f64),
        t_left: f64,
        s_left: f64,
        diss0: f64,
    ) -> StepEnd {
        let (floor, g, gv, dip, su) = (self.floor, self.g, self.gv, self.dip, self.su);
        let s = &self.s;
        let t_s = reach_time(s_left, s.v.dot(&dip), gv.dot(&dip));
        let t_lim = t_s.min(t_left);
        // t_s is formed from the whole flight; whether a strike comes before the lower
        // end is decided by its point, measured from the last floor point (local terms)
        let t_q = if t_s < t_left {
            (t_s * (1.0 + 1e-9)).min(t_left)
        } else {
            t_lim
        };
        let mut past_end = None;
        let end = match floor.flight(&s.p, &s.v, g, t_q) {
            FlightEnd::Hit { t, facet } => {
                let q = s.p + s.v * t + gv * (0.5 * t * t);
                let zq = floor.facet_plane(facet).z(q.x, q.y);
                let dq = Vector3::new(q.x - s.r.x, q.y - s.r.y, zq - s.r.z);
                if s.s_r + dq.dot(&dip) < su.length {
                    FlightEnd::Hit { t, facet }
                } else {
                    past_end = Some(t);
                    FlightEnd::Clear
                }
            }
            FlightEnd::Leaves { t } if t > t_lim => FlightEnd::Clear,
            e => e,
        };
        let dt = match end {
            FlightEnd::Hit { t, .. } | FlightEnd::Leaves { t } => t,
            FlightEnd::Clear => past_end.map_or(t_lim, |t| t.min(t_lim)),
        };
        // a column reached inside the flight ends it there
        let col = self.column_reach(&s.v, &gv, dt);
        let dt = col.map_or(dt, |c| c.0);
        let p_start = s.p;
        self.push_segment(Segment {
            t0: s.t,
            dt,
            p0: s.p,
            v0: s.v,
            a: gv,
            fric: Vector3::zeros(),
            diss0,
            rolling: None,
            spin: s.spin,
            on_floor: false,
        });
        let s = &mut self.s;
        s.p += s.v * dt + gv * (0.5 * dt * dt);
        s.v += gv * dt;
        s.t += dt;
        // the rebound's apex counts only when this flight lasted until it
        if let Some((h, t_apex)) = s.apex.take()
            && s.t >= t_apex
        {
            s.max_bounce = s.max_bounce.max(h);
        }
        if let Some((_, k)) = col {
            self.hit = Some(k);
            return Some((Phase::Flight, StopReason::Support));
        }
        match end {
            FlightEnd::Leaves { .. } => Some((Phase::Flight, StopReason::LeftFloor)),
            FlightEnd::Clear => {
                if t_s <= t_left || past_end.is_some() {
                    return Some((Phase::Flight, StopReason::LowerEnd));
                }
                Some((Phase::Flight, StopReason::EndTime))
            }
            FlightEnd::Hit { facet, .. } => {
                self.impact(facet, p_start, draw);
                None
            }
        }
    }

    /// An impact on `facet` at the end of a flight from `p_start`: the rock is put on the floor,
    /// the restitution (e_n, e_t) drawn and applied in the facet's frame, and a rebound slower
    /// than the stop speed starts the ground phase.
    fn impact(
        &mut self,
        facet: Facet,
        p_start: Vector3<f64>,
        draw: &mut impl FnMut() -> (f64, f64),
    ) {
        let (floor, g, dip, su) = (self.floor, self.g, self.dip, self.su);
        let s = &mut self.s;
        let pl = floor.facet_plane(facet);
        let n = pl.normal();
        let z = pl.z(s.p.x, s.p.y);
        set_height(s, z, g, 1.0);
        // on the floor's surface itself: a strike accepted a rounding
        // tolerance outside the struck facet may lie under a neighbour's plane
        if let Some(top) = floor_surface_above(floor, &s.p) {
            set_height(s, top, g, 1.0);
        }
        s.on_surface = Some(s.p);
        if (s.p - p_start).norm() <= self.catch.len {
            self.catch.hops += 1;
        } else {
            self.catch.hops = 0;
        }
        s.s_r += (s.p - s.r).dot(&dip);
        s.r = s.p;
        let vn = s.v.dot(&n);
        let vt = s.v - n * vn;
        let (en, et) = draw();
        s.impacts += 1;
        let speed_before = s.v.norm();
        let lost =
            0.5 * ((1.0 - en * en) * vn * vn + (1.0 - et * et) * vt.norm_squared()) + s.spin.0;
        s.e_imp += lost;
        s.spin = (0.0, Vector3::zeros());
        let r = -en * vn;
        let rebound = vt * et + n * r;
        let ev = EventRec {
            t: s.t,
            kind: EventKind::Impact,
            p: s.p,
            speed_before,
            speed_after: rebound.norm(),
            lost,
        };
        self.push_event(ev);
        let s = &mut self.s;
        if r < su.v_stop || r < MIN_REBOUND {
            s.rebound_cutoff |= r >= su.v_stop;
            s.e_trans += 0.5 * r * r;
            s.v = vt * et;
            let ke_before = rebound.norm();
            self.enter_ground(facet);
            if let Some(rr) = self.rec.as_deref_mut()
                && let Some(ev) = rr.events.last_mut()
            {
                ev.speed_before = ke_before;
                ev.lost += 0.5 * r * r;
            }
        } else {
            s.v = rebound;
            s.apex = Some((r * r / (2.0 * g * n.z), s.t + r / (g * n.z)));
        }
    }

    /// One piece along the crease `c` (a concave edge holding the rock): constant acceleration
    /// along the edge line up to its end, the lower end, the end time, a column or a stop.
    fn crease_step(&mut self, c: Crease, t_left: f64, s_left: f64, moving: Phase) -> StepEnd {
        let (floor, gv, dip, mu, roll) = (self.floor, self.gv, self.dip, self.mu, self.roll);
        let g = self.g;
        let ke_factor = self.ke_factor;
        let s = &mut self.s;
        let ve = s.v.dot(&c.e);
        // the motion is along the crease line: a velocity part across it (left by a
        // correction at a vertex) is removed as a booked transition, never dropped
        let across = s.v.norm_squared() - ve * ve;
        if across > 0.0 {
            s.e_trans += 0.5 * ke_factor * across;
            s.v = c.e * ve;
        }
        let ge = gv.dot(&c.e);
        let (ae, dir) = if roll {
            (ge * (5.0 / 7.0), 0.0)
        } else {
            let dir = if ve.abs() <= REST_SPEED {
                s.e_fric += 0.5 * s.v.norm_squared();
                s.v = Vector3::zeros();
                if ge.abs() <= mu * c.n_tot * (1.0 + 1e-12) || ge.abs() <= 1e-12 * g {
                    return Some((Phase::Stopped, StopReason::AtRest));
                }
                ge.signum()
            } else {
                ve.signum()
            };
            (ge - dir * mu * c.n_tot, dir)
        };
        let ve = s.v.dot(&c.e);
        let t_s = reach_time(s_left, ve * c.e.dot(&dip), ae * c.e.dot(&dip));
        let mut t_max = t_s.min(t_left);
        let mut stop_at = f64::INFINITY;
        if !roll && ae * dir < 0.0 {
            stop_at = ve.abs() / ae.abs();
        }
        t_max = t_max.min(stop_at);
        let len = (c.ends[1] - c.ends[0]).dot(&c.e);
        // on the edge: a rounding error past an end would never cross it again
        let u0 = (s.p - c.ends[0]).dot(&c.e).clamp(0.0, len);
        let t_end_edge = super::terrain::outward_root(u0 - len, ve, ae)
            .into_iter()
            .chain(super::terrain::outward_root(-u0, -ve, -ae))
            .fold(f64::INFINITY, f64::min);
        let mut at_vertex = t_end_edge <= t_max;
        let mut dt = if at_vertex { t_end_edge } else { t_max };
        let col = self.column_reach(&(c.e * ve), &(c.e * ae), dt);
        if let Some((tc, _)) = col {
            dt = tc;
            at_vertex = false;
        }
        let du = ve * dt + 0.5 * ae * dt * dt;
        self.s.undecelerated = ae * ve >= 0.0;
        let s = &self.s;
        self.push_segment(Segment {
            t0: s.t,
            dt,
            p0: s.p,
            v0: c.e * ve,
            a: c.e * ae,
            fric: c.e * (dir * mu * c.n_tot),
            // what this branch booked before the piece (a removed velocity part,
            // a rest) is part of its start
            diss0: s.e_imp + s.e_fric + s.e_trans,
            // rolling along the crease: the spin axis is horizontal-most normal to it
            rolling: roll.then(|| crease_up(&c.e)),
            spin: (0.0, Vector3::zeros()),
            on_floor: true,
        });
        let s = &mut self.s;
        s.p += c.e * du;
        s.v = c.e * (ve + ae * dt);
        s.t += dt;
        if !roll {
            s.e_fric += dir * mu * c.n_tot * du;
        }
        if let Some((_, k)) = col {
            self.hit = Some(k);
            return Some((moving, StopReason::Support));
        }
        if at_vertex {
            s.crease = None;
            let d3 = if s.v.norm() > 0.0 { s.v } else { c.e * ae };
            match floor.locate(s.p.x, s.p.y, d3.x, d3.y) {
                None => return Some((moving, StopReason::LeftFloor)),
                Some(fb) => {
                    self.change_facet(fb, None);
                }
            }
            return None;
        }
        if dt == t_s && t_s <= t_left {
            return Some((moving, StopReason::LowerEnd));
        }
        if dt == t_left {
            return Some((moving, StopReason::EndTime));
        }
        if dt == stop_at {
            s.e_fric += 0.5 * s.v.norm_squared();
            s.v = Vector3::zeros();
        }
        None
    }

    /// One closed-form piece of sliding or rolling on facet f: constant acceleration up to a
    /// facet edge (then [`Run::edge_transition`]), the lower end, the end time, a column, the
    /// stop of the speed along the friction direction or a turn of [`MAX_TURN`].
    fn ground_step(
        &mut self,
        f: Facet,
        t_left: f64,
        s_left: f64,
        diss0: f64,
        moving: Phase,
    ) -> StepEnd {
        let (floor, g, gv, dip, mu, roll) =
            (self.floor, self.g, self.gv, self.dip, self.mu, self.roll);
        let ke_factor = self.ke_factor;
        let s = &mut self.s;
        let pl = floor.facet_plane(f);
        let n = pl.normal();
        let gn = g * n.z;
        let gt = gv + n * (g * n.z);
        // the closed-form piece moves in the facet's plane: a velocity part along its
        // normal beyond rounding is removed as a booked transition (energy is never
        // lost without being counted, nor the rock carried off the facet)
        let vn = s.v.dot(&n);
        if vn.abs() > 1e-9 * s.v.norm() {
            s.e_trans += 0.5 * ke_factor * vn * vn;
            s.v -= n * vn;
        }
        let speed = s.v.norm();
        let (a, fdir) = if roll {
            if speed <= REST_SPEED && gt.norm() <= 1e-12 * g {
                s.v = Vector3::zeros();
                return Some((Phase::Stopped, StopReason::AtRest));
            }
            (gt * (5.0 / 7.0), Vector3::zeros())
        } else {
            let fdir = if speed <= REST_SPEED {
                s.e_fric += 0.5 * speed * speed;
                s.v = Vector3::zeros();
                let gtn = gt.norm();
                if gtn <= mu * gn * (1.0 + 1e-12) || gtn <= 1e-12 * g {
                    return Some((Phase::Stopped, StopReason::AtRest));
                }
                gt / gtn
            } else {
                s.v / speed
            };
            (gt - fdir * (mu * gn), fdir)
        };
        // candidate ends of this constant-acceleration piece
        let t_s = reach_time(s_left, s.v.dot(&dip), a.dot(&dip));
        let mut t_max = t_s.min(t_left);
        let mut stop_at = f64::INFINITY;
        let mut turn_at = f64::INFINITY;
        if !roll {
            let ad = a.dot(&fdir);
            if ad < 0.0 {
                stop_at = s.v.dot(&fdir) / -ad;
            }
            let aperp = (a - fdir * ad).norm();
            if aperp > 1e-12 * g {
                // |v| is `speed`, or 0 after a rest above (both give REST_SPEED here)
                turn_at = MAX_TURN * speed.max(REST_SPEED) / aperp;
            }
            s.undecelerated = ad >= 0.0;
        } else {
            s.undecelerated = a.dot(&s.v) >= 0.0;
        }
        t_max = t_max.min(stop_at).min(turn_at);
        // on a coplanar patch of a grid, one piece to the patch's boundary
        let mut exit = floor.slide_exit_merged(f, &s.p, &s.v, &a, t_max);
        let mut dt = exit.map_or(t_max, |e| e.0);
        let col = self.column_reach(&self.s.v, &a, dt);
        if let Some((tc, _)) = col {
            dt = tc;
            exit = None;
        }
        let fric = fdir * (mu * gn);
        let s = &self.s;
        self.push_segment(Segment {
            t0: s.t,
            dt,
            p0: s.p,
            v0: s.v,
            a,
            fric,
            diss0,
            rolling: roll.then_some(n),
            spin: (0.0, Vector3::zeros()),
            on_floor: true,
        });
        let s = &mut self.s;
        let dp = s.v * dt + a * (0.5 * dt * dt);
        s.p += dp;
        s.v += a * dt;
        s.t += dt;
        if !roll {
            s.e_fric += fric.dot(&dp);
        }
        if dt == 0.0 {
            self.zero_steps += 1;
        } else {
            self.zero_steps = 0;
        }
        if exit.is_none() && floor.in_patch(f) {
            // a piece across a coplanar patch that ends inside it: on the facet under the rock
            // (to rounding, its plane is f's)
            if let Some(fq) = floor.locate(s.p.x, s.p.y, s.v.x, s.v.y)
                && fq != f
            {
                s.ground = Some(fq);
                let z = floor.facet_plane(fq).z(s.p.x, s.p.y);
                set_floor_height(s, floor, z, g, ke_factor);
            }
        }
        if let Some((_, k)) = col {
            self.hit = Some(k);
            return Some((moving, StopReason::Support));
        }
        if let Some((_, next, edge)) = exit {
            return self.edge_transition(n, a, next, edge, moving);
        }
        if dt == t_s && t_s <= t_left {
            return Some((moving, StopReason::LowerEnd));
        }
        if dt == t_left {
            return Some((moving, StopReason::EndTime));
        }
        if dt == stop_at {
            // the speed along the friction direction is zero: keep the rest
            let vd = s.v.dot(&fdir);
            let before = s.v.norm_squared();
            s.v -= fdir * vd;
            s.e_fric += 0.5 * (before - s.v.norm_squared());
        }
        None
    }

    /// The rock sliding (rolling) with acceleration `a` on a facet with normal `n` reached its
    /// edge `edge` towards facet `next` (None: off the floor): onto the next facet (projected
    /// onto it, or taking off at a convex edge), into the crease when the edge is a concave one
    /// that holds it, and — stuck on a vertex by rounding — moved on a hair.
    fn edge_transition(
        &mut self,
        n: Vector3<f64>,
        a: Vector3<f64>,
        next: Option<Facet>,
        edge: [[f64; 2]; 2],
        moving: Phase,
    ) -> StepEnd {
        let g = self.g;
        let ke_factor = self.ke_factor;
        let Some(fb) = next else {
            return Some((moving, StopReason::LeftFloor));
        };
        if let Some(plb) = self.change_facet(fb, Some(n)) {
            let s = &mut self.s;
            let nb = plb.normal();
            let ends = edge.map(|q| Vector3::new(q[0], q[1], plb.z(q[0], q[1])));
            let d = ends[1] - ends[0];
            let out_a = Vector3::new(d.y, -d.x, 0.0);
            if let Some(c) = crease_of(ends, &n, &nb, &out_a, &s.v, g) {
                let ve = s.v.dot(&c.e);
                let before = s.v.norm_squared();
                s.v = c.e * ve;
                s.e_trans += 0.5 * ke_factor * (before - ve * ve);
                // on the edge line through the crossing point
                let u = (s.p - c.ends[0]).dot(&c.e);
                let q = c.ends[0] + c.e * u;
                s.p.x = q.x;
                s.p.y = q.y;
                set_height(s, q.z, g, ke_factor);
                s.crease = Some(c);
            }
        }
        if self.zero_steps > 16
            && let Some(c) = self.s.crease
        {
            return self.unstick_along_crease(c, n, moving);
        } else if self.zero_steps > 16 {
            return self.unstick_at_vertex(n, a, moving);
        }
        None
    }

    /// Stuck at a vertex on the crease `c` (the old facet's normal `n`): moves a hair along the
    /// crease line itself, or — a rise the rock cannot pay for — ends the run at rest there.
    fn unstick_along_crease(&mut self, c: Crease, n: Vector3<f64>, moving: Phase) -> StepEnd {
        let (floor, g, gv, ke_factor) = (self.floor, self.g, self.gv, self.ke_factor);
        let s = &mut self.s;
        // stuck at a vertex on a crease: move a hair along the crease line
        // itself. Moved along the old facet's slope instead, a rock 1e-8 m
        // beside a steep crease ran parallel to it under the facet rising from
        // it (1.7e-8 m below the floor).
        let ve = s.v.dot(&c.e);
        let ext = floor.extent();
        let eps = 1e-9 * (ext[1] - ext[0]).abs().clamp(1e-3, 1e3);
        let len = (c.ends[1] - c.ends[0]).dot(&c.e);
        let along = (s.p - c.ends[0]).dot(&c.e);
        let ke = 0.5 * ke_factor * s.v.norm_squared();
        // along the motion (at rest: downhill)
        let sgn = if ve != 0.0 { ve } else { gv.dot(&c.e) }.signum();
        let rise = |sg: f64| g * ((c.ends[0] + c.e * (along + sg * eps)).z - s.p.z);
        let u = along + sgn * eps;
        let q = c.ends[0] + c.e * u;
        if (0.0..=len).contains(&u) && rise(sgn) > ke {
            // a rise it cannot pay for: trapped at the bottom of the crease,
            // at rest where it is (moved, it would book a negative
            // loss: 2.3e-5 J for a 3.4e-8 m lift)
            s.e_trans += ke;
            s.v = Vector3::zeros();
            return Some((Phase::Stopped, StopReason::AtRest));
        }
        s.p.x = q.x;
        s.p.y = q.y;
        if (0.0..=len).contains(&u) {
            set_height(s, q.z, g, ke_factor);
        } else {
            // past the crease's end: onto the facet beyond it
            s.crease = None;
            let dir = c.e * sgn;
            match floor.locate(s.p.x, s.p.y, dir.x, dir.y) {
                Some(fc) => {
                    self.change_facet(fc, Some(n));
                }
                None => return Some((moving, StopReason::LeftFloor)),
            }
        }
        self.zero_steps = 0;
        None
    }

    /// Stuck on a vertex by rounding (on a facet with normal `n`, acceleration `a`): moves a
    /// hair along the motion onto the facet there.
    fn unstick_at_vertex(&mut self, n: Vector3<f64>, a: Vector3<f64>, moving: Phase) -> StepEnd {
        let (floor, g, ke_factor) = (self.floor, self.g, self.ke_factor);
        let s = &mut self.s;
        // stuck on a vertex by rounding: move a hair along the motion
        let dir = if s.v.norm() > 0.0 { s.v } else { a };
        let h = (dir.x * dir.x + dir.y * dir.y).sqrt();
        if h > 0.0 {
            let ext = floor.extent();
            let eps = 1e-9 * (ext[1] - ext[0]).abs().clamp(1e-3, 1e3);
            s.p.x += eps * dir.x / h;
            s.p.y += eps * dir.y / h;
        }
        match floor.locate(s.p.x, s.p.y, dir.x, dir.y) {
            Some(fc) if s.ground.is_some() && s.crease.is_none() => {
                // onto the new facet like at an edge: the velocity is projected
                // onto its plane (or the rock takes off), the loss booked
                self.change_facet(fc, Some(n));
            }
            Some(fc) => {
                if s.ground.is_some() {
                    s.ground = Some(fc);
                }
                let kf = if s.ground.is_some() { ke_factor } else { 1.0 };
                let z = floor.facet_plane(fc).z(s.p.x, s.p.y);
                set_floor_height(s, floor, z, g, kf);
            }
            None => return Some((moving, StopReason::LeftFloor)),
        }
        self.zero_steps = 0;
        None
    }

    /// The outcome of a run that ended in `phase` for `reason`: the last invariant check, the
    /// stop event, the rotation and the account.
    fn finish(mut self, phase: Phase, reason: StopReason) -> PhysicsResult<RunOut> {
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
            let ev = EventRec {
                t: self.s.t,
                kind: EventKind::Stop,
                p: self.s.p,
                speed_before: 0.0,
                speed_after: 0.0,
                lost: 0.0,
            };
            self.push_event(ev);
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

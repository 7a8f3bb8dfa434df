//! Both migration methods on one case: do they agree within their intervals, and, where they do
//! not, on what kind of floor (the reason and which one to trust depend on it).
//!
//! The floor is classed by its **relief at the rock's scale**: the root-mean-square height of
//! the floor above or below the least-squares plane of each [`RELIEF_TILE_M`] tile, sampled on a
//! lattice finer than the floor's cells, over the face's extent; compared with the rock's size
//! (the diameter of the sphere of its volume). A curved face is no relief (each tile takes its
//! own plane); survey noise of a centimetre is about 1 % of a 0.3 m cube (0.37 m the sphere of
//! its volume); bumps and steps of decimetres are of the rock's size or above.

use super::shape::BlockShape;
use super::terrain::{Floor, FloorKind};
use super::{Method, MigrationCase, MigrationResult, StopReason};
use crate::physics::error::PhysicsResult;
use crate::physics::stats::interval::{Z_95, wilson_interval};

/// Side of the plan tiles over which the floor's relief is measured, m.
pub const RELIEF_TILE_M: f64 = 5.0;
/// Relief (RMS) below this share of the rock's size is a smooth floor (survey noise, rounding):
/// uniform noise of ±1 cm on 0.5 m cells measures 0.004 m, 1 % of a 0.37 m block.
pub const SMOOTH_RELIEF: f64 = 0.02;
/// Relief (RMS) from this share of the rock's size up is relief of the rock's size or above
/// (bumps from trough to crest about 2√2 times the RMS: over half the rock's size).
pub const LARGE_RELIEF: f64 = 0.2;
/// Relative difference of the mean arrival speeds within which the two methods agree even
/// where their intervals are narrower (a difference no engineering decision turns on).
pub const SPEED_TOLERANCE: f64 = 0.05;
/// Difference of the shares of runs reaching the lower end within which the methods agree even
/// where their intervals are narrower.
pub const REACHED_TOLERANCE: f64 = 0.05;
/// Largest number of floor samples the relief is measured on.
const MAX_RELIEF_SAMPLES: f64 = 400_000.0;

/// What kind of floor the comparison was made on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FloorClass {
    /// The face's plane.
    Plane,
    /// Relief below [`SMOOTH_RELIEF`] of the rock's size: survey noise, rounding, a smooth curve.
    Smooth,
    /// Relief between [`SMOOTH_RELIEF`] and [`LARGE_RELIEF`] of the rock's size: bumps the rock
    /// is larger than.
    ReliefBelowRockSize,
    /// Relief of at least [`LARGE_RELIEF`] of the rock's size: bumps, steps and benches of the
    /// rock's size or above.
    ReliefAboveRockSize,
}

/// What the two methods differ by on a case (or would, where they agree).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reason {
    /// The rock's shape and rotation on a smooth floor: the rigid block's corners bounce and it
    /// turns, the lumped mass's bounces follow e_n, e_t.
    Shape,
    /// Relief smaller than the rock: the rigid block bridges it, the point mass lands on it.
    ReliefBelowRockSize,
    /// Relief of the rock's size or larger: the paths part where the shape decides the way.
    ReliefAboveRockSize,
    /// The shares of runs reaching the lower end differ: where rocks come to rest, the way the
    /// rock moves (the lumped mass slides or rolls as told; the rigid block slides, tumbles or
    /// rolls as its shape lets it) decides whether it stops.
    Stopping,
}

/// One method's arrival over the compared runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MethodArrival {
    /// The method.
    pub method: Method,
    /// Runs compared (1 without an ensemble).
    pub runs: u64,
    /// Mean arrival speed of the runs that reached the lower end, m/s (None: none did).
    pub speed_mean: Option<f64>,
    /// 95 % interval of that mean, m/s (mean ± 1.96 s/√n; None for a single run or one arrival).
    pub speed_interval: Option<[f64; 2]>,
    /// Share of the runs that reached the lower end.
    pub reached_fraction: f64,
    /// 95 % Wilson interval of that share (None for a single run).
    pub reached_interval: Option<[f64; 2]>,
}

/// Both methods on one case.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodComparison {
    /// The requested method's arrival, then the other's.
    pub methods: [MethodArrival; 2],
    /// (other − requested) / requested mean arrival speed (None: one of them never arrived).
    pub speed_difference: Option<f64>,
    /// The mean arrival speeds agree (their difference is within its own 95 % interval or
    /// [`SPEED_TOLERANCE`]) and so do the shares reaching the lower end (within their combined
    /// interval or [`REACHED_TOLERANCE`]).
    pub agree: bool,
    /// The floor's relief at the rock's scale, m.
    pub relief: f64,
    /// The rock's size (diameter of the sphere of its volume), m.
    pub rock_size: f64,
    /// The floor's class.
    pub floor: FloorClass,
    /// What the two differ by on this case.
    pub reason: Reason,
}

/// The other migration method.
#[must_use]
pub fn other_method(m: Method) -> Method {
    match m {
        Method::LumpedMass => Method::RigidBlock,
        Method::RigidBlock => Method::LumpedMass,
    }
}

/// `case` with the other method, the same ensemble (`runs` of it: the runs the requested method
/// used) and none of the optional outputs: the run whose answer a comparison is made against.
#[must_use]
pub fn other_case(case: &MigrationCase, runs: Option<u64>) -> MigrationCase {
    let mut c = case.clone();
    c.method = other_method(case.method);
    c.output.compare_methods = false;
    c.output.trajectory = false;
    c.output.events = false;
    c.output.runs_csv = false;
    c.output.maps = None;
    c.target = None;
    if let (Some(mc), Some(n)) = (c.monte_carlo.as_mut(), runs) {
        mc.runs = n;
    }
    c
}

/// The comparison of `this` (the requested method's answer) with `other` (the other method's
/// on the same case), on `floor` for the rock of `case`.
///
/// # Errors
/// Those of building the rock's shape.
pub(crate) fn compare(
    case: &MigrationCase,
    floor: &Floor,
    this: &MigrationResult,
    other: &MigrationResult,
) -> PhysicsResult<MethodComparison> {
    let shape = BlockShape::of_rock(&case.rock)?;
    let rock_size = 2.0 * (3.0 * shape.volume / (4.0 * std::f64::consts::PI)).cbrt();
    let relief = floor_relief(floor, case.face.length);
    let class = match floor.kind {
        FloorKind::Plane(_) => FloorClass::Plane,
        _ if relief < SMOOTH_RELIEF * rock_size => FloorClass::Smooth,
        _ if relief < LARGE_RELIEF * rock_size => FloorClass::ReliefBelowRockSize,
        _ => FloorClass::ReliefAboveRockSize,
    };
    let (a, b) = (arrival_of(this), arrival_of(other));
    let speed_difference = match (a.speed_mean, b.speed_mean) {
        (Some(x), Some(y)) if x > 0.0 => Some(y / x - 1.0),
        _ => None,
    };
    let reached = reached_agree(&a, &b);
    let agree = speeds_agree(&a, &b) && reached;
    let reason = match class {
        _ if !reached => Reason::Stopping,
        FloorClass::Plane | FloorClass::Smooth => Reason::Shape,
        FloorClass::ReliefBelowRockSize => Reason::ReliefBelowRockSize,
        FloorClass::ReliefAboveRockSize => Reason::ReliefAboveRockSize,
    };
    Ok(MethodComparison {
        methods: [a, b],
        speed_difference,
        agree,
        relief,
        rock_size,
        floor: class,
        reason,
    })
}

/// One method's arrival from its answer: the ensemble's statistics, or the single run.
fn arrival_of(r: &MigrationResult) -> MethodArrival {
    match &r.statistics {
        Some(st) => {
            let (speed_mean, speed_interval) = match &st.speed {
                Some(s) if s.count > 0 => {
                    let iv = s.std.filter(|_| s.count > 1).map(|sd| {
                        let h = Z_95 * sd / (s.count as f64).sqrt();
                        [s.mean - h, s.mean + h]
                    });
                    (Some(s.mean), iv)
                }
                _ => (None, None),
            };
            let n = st.runs as f64;
            MethodArrival {
                method: r.method,
                runs: st.runs,
                speed_mean,
                speed_interval,
                reached_fraction: st.reached_fraction,
                reached_interval: wilson_interval(st.reached_fraction * n, n, Z_95),
            }
        }
        None => {
            let reached = r.arrival.stop_reason == StopReason::LowerEnd;
            MethodArrival {
                method: r.method,
                runs: 1,
                speed_mean: reached.then_some(r.arrival.speed),
                speed_interval: None,
                reached_fraction: if reached { 1.0 } else { 0.0 },
                reached_interval: None,
            }
        }
    }
}

/// Half-width of an interval (0 without one).
fn half(iv: Option<[f64; 2]>) -> f64 {
    iv.map_or(0.0, |[lo, hi]| 0.5 * (hi - lo))
}

/// The mean arrival speeds agree: both absent, or their difference within its own 95 %
/// interval (the two half-widths combined) or within [`SPEED_TOLERANCE`] of the larger.
fn speeds_agree(a: &MethodArrival, b: &MethodArrival) -> bool {
    match (a.speed_mean, b.speed_mean) {
        (None, None) => true,
        (Some(x), Some(y)) => {
            let d = (x - y).abs();
            let h = half(a.speed_interval).hypot(half(b.speed_interval));
            d <= h || d <= SPEED_TOLERANCE * x.max(y)
        }
        _ => false,
    }
}

/// The shares reaching the lower end agree: within their combined 95 % interval or within
/// [`REACHED_TOLERANCE`].
fn reached_agree(a: &MethodArrival, b: &MethodArrival) -> bool {
    let d = (a.reached_fraction - b.reached_fraction).abs();
    let h = half(a.reached_interval).hypot(half(b.reached_interval));
    d <= h || d <= REACHED_TOLERANCE
}

/// The floor's relief at the rock's scale over the face of length `length` (m): the RMS
/// height of the floor's surface about the least-squares plane of each [`RELIEF_TILE_M`]
/// plan tile, sampled on a lattice of half the floor's cell (coarser where that would exceed
/// [`MAX_RELIEF_SAMPLES`]); 0 on the plane. Holes are skipped.
#[must_use]
pub(crate) fn floor_relief(floor: &Floor, length: f64) -> f64 {
    if matches!(floor.kind, FloorKind::Plane(_)) {
        return 0.0;
    }
    let m = floor.mean;
    let ext = floor.extent();
    // the face's plan extent: the mean plane's x over [0, length] (a little more for the
    // curvature of the floor), within the floor
    let x0 = ext[0].max(m.x0 - 1.0);
    let x1 = ext[1].min(m.x0 + length * m.cos + 1.0);
    let (y0, y1) = (ext[2], ext[3]);
    if !(x1 > x0 && y1 > y0) {
        return 0.0;
    }
    let area = (x1 - x0) * (y1 - y0);
    let h = (0.5 * floor.cell_size()).max((area / MAX_RELIEF_SAMPLES).sqrt());
    let nx_tiles = ((x1 - x0) / RELIEF_TILE_M).ceil().max(1.0) as usize;
    let ny_tiles = ((y1 - y0) / RELIEF_TILE_M).ceil().max(1.0) as usize;
    let (tw, th) = ((x1 - x0) / nx_tiles as f64, (y1 - y0) / ny_tiles as f64);
    let (mut sum, mut count) = (0.0f64, 0usize);
    for i in 0..nx_tiles {
        for j in 0..ny_tiles {
            let (ax, ay) = (x0 + i as f64 * tw, y0 + j as f64 * th);
            let (kx, ky) = (
                ((tw / h).ceil() as usize).max(2),
                ((th / h).ceil() as usize).max(2),
            );
            let mut pts = Vec::with_capacity(kx * ky);
            for u in 0..kx {
                for v in 0..ky {
                    let x = ax + (u as f64 + 0.5) * tw / kx as f64;
                    let y = ay + (v as f64 + 0.5) * th / ky as f64;
                    if let Some(z) = floor.height_at(x, y) {
                        pts.push([x - ax, y - ay, z]);
                    }
                }
            }
            if let Some(ss) = plane_fit_residual(&pts) {
                sum += ss;
                count += pts.len();
            }
        }
    }
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).sqrt()
    }
}

/// Sum of squared residuals of the least-squares plane z = a + b x + c y through `pts`
/// (None with fewer than 3 points or a degenerate layout).
fn plane_fit_residual(pts: &[[f64; 3]]) -> Option<f64> {
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let mean = |k: usize| pts.iter().map(|p| p[k]).sum::<f64>() / n;
    let (mx, my, mz) = (mean(0), mean(1), mean(2));
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let (dx, dy, dz) = (p[0] - mx, p[1] - my, p[2] - mz);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
        sxz += dx * dz;
        syz += dy * dz;
    }
    let det = sxx * syy - sxy * sxy;
    if det.is_nan() || det.abs() <= 1e-12 * (sxx * syy).max(f64::MIN_POSITIVE) {
        return None;
    }
    let b = (sxz * syy - syz * sxy) / det;
    let c = (syz * sxx - sxz * sxy) / det;
    Some(
        pts.iter()
            .map(|p| {
                let r = p[2] - mz - b * (p[0] - mx) - c * (p[1] - my);
                r * r
            })
            .sum(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::migration::FloorSpec;
    use crate::physics::migration::build_floor;

    fn grid_case(f: impl Fn(f64, f64) -> f64, d: f64) -> MigrationCase {
        let mut c = MigrationCase::default();
        let (nx, ny) = ((40.0 / d) as usize + 1, (8.0 / d) as usize + 1);
        let heights = (0..ny)
            .map(|i| {
                (0..nx)
                    .map(|j| f(j as f64 * d, -4.0 + i as f64 * d))
                    .collect()
            })
            .collect();
        c.face.length = 40.0;
        c.face.floor = FloorSpec::Grid {
            origin: [0.0, -4.0],
            spacing: d,
            heights,
        };
        c
    }

    #[test]
    fn a_tilted_or_curved_floor_has_no_relief_and_bumps_have_their_height() {
        let tan = 45f64.to_radians().tan();
        // a plane as a grid: no relief
        let c = grid_case(move |x: f64, _| -x * tan, 0.5);
        let r = floor_relief(&build_floor(&c).unwrap(), c.face.length);
        assert!(r < 1e-9, "{r}");
        // a face curved over its length (z'' = 0.004 /m): each tile's plane takes the curve out
        // but for c L²/√180 ≈ 4 mm over a 5 m tile, 1 % of a 0.37 m block (smooth)
        let c = grid_case(move |x: f64, _| -x * tan - 0.002 * x * x, 0.5);
        let r = floor_relief(&build_floor(&c).unwrap(), c.face.length);
        assert!(r < 0.0045, "{r}");
        // a sine of amplitude A along the dip, wavelength 2 m: RMS A/√2 about each tile's plane
        let a = 0.1;
        let c = grid_case(
            move |x, _| -x * tan + a * (std::f64::consts::PI * x).sin(),
            0.05,
        );
        let r = floor_relief(&build_floor(&c).unwrap(), c.face.length);
        assert!((r / (a / 2f64.sqrt()) - 1.0).abs() < 0.05, "{r}");
    }

    #[test]
    fn the_mean_speeds_agree_within_their_interval_or_the_tolerance() {
        let arr = |m: f64, h: f64, reached: f64| MethodArrival {
            method: Method::LumpedMass,
            runs: 100,
            speed_mean: Some(m),
            speed_interval: Some([m - h, m + h]),
            reached_fraction: reached,
            reached_interval: Some([reached - 0.01, reached + 0.01]),
        };
        // 4.9 % apart with tight intervals: within the tolerance
        assert!(speeds_agree(&arr(20.0, 0.01, 1.0), &arr(20.98, 0.01, 1.0)));
        // 10 % apart, intervals of ± 1.5 each (the difference's ± 2.12): no
        assert!(!speeds_agree(&arr(20.0, 1.5, 1.0), &arr(22.2, 1.5, 1.0)));
        // 10 % apart, intervals of ± 2 each (the difference's ± 2.83): yes
        assert!(speeds_agree(&arr(20.0, 2.0, 1.0), &arr(22.0, 2.0, 1.0)));
        // the shares reaching the end: 0.7 against 1.0 differ, 0.97 against 1.0 agree
        assert!(!reached_agree(&arr(20.0, 1.0, 0.7), &arr(20.0, 1.0, 1.0)));
        assert!(reached_agree(&arr(20.0, 1.0, 0.97), &arr(20.0, 1.0, 1.0)));
    }
}

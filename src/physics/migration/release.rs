//! The release: everything a run needs that the Monte Carlo draws do not change (the floor, the
//! start on or above it, the mass and the energy at the start), built once per case.

use std::sync::Arc;

use nalgebra::Vector3;

use super::lumped_mass::Setup;
use super::shape::BlockShape;
use super::terrain::{Facet, Floor};
use super::{FloorSpec, Method, MigrationCase, MigrationResult, StopReason, Warning};
use crate::physics::error::{Param, PhysicsError, PhysicsResult};
use crate::physics::material::{Rock, RockShape};

/// Everything a run needs that does not change between Monte Carlo runs.
pub(super) struct Prepared {
    pub(super) floor: Arc<Floor>,
    pub(super) mass: f64,
    pub(super) g: f64,
    pub(super) p0: Vector3<f64>,
    pub(super) v0: Vector3<f64>,
    pub(super) on_floor: Option<u32>,
    pub(super) release_along: f64,
    /// Floor point under the release, m.
    pub(super) base: Vector3<f64>,
    pub(super) z_end: f64,
    pub(super) e0: f64,
    /// The resting block overhung the floor at the release point and was moved onto it by
    /// this much: [along the dip, across], m (see [`place_block`]).
    pub(super) moved: Option<[f64; 2]>,
    /// Unit normal of the floor's facet under the release point.
    pub(super) normal: Vector3<f64>,
    /// Unit down-dip direction of that facet.
    pub(super) down_dip: Vector3<f64>,
    /// A release on the floor whose velocity had a component normal to the floor: that
    /// component, m/s (removed: see [`start_velocity`]).
    pub(super) projected: Option<f64>,
}

/// The velocity at the start, m/s, of `rel` on a floor of unit normal `normal` and down-dip
/// direction `down_dip` there: `velocity` as given, else `speed` down the dip. A rock released
/// on the floor (`on_floor`) keeps only the velocity's component along the floor: into the floor
/// the floor holds it, out of it a release must be lifted (`drop_height_m` > 0). The component
/// removed is returned when it is more than rounding.
pub(super) fn start_velocity(
    rel: &super::Release,
    down_dip: &Vector3<f64>,
    normal: &Vector3<f64>,
    on_floor: bool,
) -> (Vector3<f64>, Option<f64>) {
    let v = rel
        .velocity
        .map_or_else(|| down_dip * rel.speed, Vector3::from);
    on_floor_velocity(v, normal, on_floor)
}

/// `v` (m/s) with its component along the unit `normal` removed when `on_floor`, and that
/// component when it is more than rounding (see [`start_velocity`]).
pub(super) fn on_floor_velocity(
    v: Vector3<f64>,
    normal: &Vector3<f64>,
    on_floor: bool,
) -> (Vector3<f64>, Option<f64>) {
    let vn = v.dot(normal);
    if !on_floor || vn == 0.0 {
        return (v, None);
    }
    let big = vn.abs() > 1e-12 * v.norm();
    (v - normal * vn, big.then_some(vn))
}

pub(super) fn prepare(case: &MigrationCase) -> PhysicsResult<Prepared> {
    prepare_on(case, build_floor(case)?)
}

/// The floor of `case.face`, built once: it depends on the face only, so the runs of an
/// ensemble whose release or rock vary share it (see [`ensemble_run`]).
///
/// Errors: those of building the floor (memory, crossing contours, map origin off the floor).
pub(crate) fn build_floor(case: &MigrationCase) -> PhysicsResult<Arc<Floor>> {
    let face = &case.face;
    let dip = face.dip_deg.to_radians();
    Ok(Arc::new(match &face.floor {
        FloorSpec::Plane => Floor::plane(dip),
        FloorSpec::Grid {
            origin,
            spacing,
            heights,
        } => Floor::grid(dip, *origin, *spacing, heights)?,
        FloorSpec::Contours {
            contours,
            resolution,
        } => Floor::contours(dip, contours, *resolution)?,
        FloorSpec::Mapped { floor, map } => match &**floor {
            FloorSpec::Grid {
                origin,
                spacing,
                heights,
            } => Floor::grid_in_map(dip, *origin, *spacing, heights, map)?,
            FloorSpec::Contours {
                contours,
                resolution,
            } => Floor::contours_in_map(dip, contours, *resolution, map)?,
            _ => {
                return Err(PhysicsError::invalid(
                    Param::FloorMap,
                    0.0,
                    "map coordinates apply to grid and contour floors",
                ));
            }
        },
    }))
}

/// [`prepare`] on a floor built by [`build_floor`] from the same face.
pub(super) fn prepare_on(case: &MigrationCase, floor: Arc<Floor>) -> PhysicsResult<Prepared> {
    let face = &case.face;
    let rel = &case.release;
    let mean = floor.mean;
    let mut y = rel.across;
    let mut moved = None;
    let (mut x, mut facet) = match (rel.point, &face.floor) {
        (Some(pt), spec) => {
            let [px, py] = match spec {
                FloorSpec::Mapped { map, .. } => map.to_face(pt),
                _ => pt,
            };
            y = py;
            let f = floor
                .locate(px, py, 1.0, 0.0)
                .or_else(|| floor.locate(px, py, 0.0, 0.0))
                .filter(|_| !matches!(spec, FloorSpec::Plane) || px >= 0.0)
                .ok_or_else(|| {
                    let ext = floor.extent();
                    PhysicsError::invalid(
                        Param::ReleasePoint,
                        pt[0],
                        format!(
                            "the release point [{}, {}] (face coordinates [{px:.4}, {py:.4}] m) is \
                             not over the floor (x in [{:.4}, {:.4}], y in [{:.4}, {:.4}] m in \
                             face coordinates, holes excepted)",
                            pt[0], pt[1], ext[0], ext[1], ext[2], ext[3]
                        ),
                    )
                })?;
            (px, f)
        }
        (None, FloorSpec::Plane) => (rel.along_dip * mean.cos, 0),
        (None, _) => {
            let ext = floor.extent();
            if !(y >= ext[2] && y <= ext[3]) {
                return Err(PhysicsError::invalid(
                    Param::ReleaseAcross,
                    y,
                    format!(
                        "the release must be over the floor: y in [{}, {}] m",
                        ext[2], ext[3]
                    ),
                ));
            }
            let along_at = |x: f64| -> Option<f64> {
                let f = floor.locate(x, y, 0.0, 0.0)?;
                let z = floor.facet_plane(f).z(x, y);
                Some(mean.along(&Vector3::new(x, y, z)))
            };
            let off = || {
                let span = along_span(&floor, None, y).map_or_else(
                    || "the floor is nowhere along the dip at this across_m".to_string(),
                    |(a, b)| {
                        format!(
                            "at across_m = {y} m the floor spans along_dip_m in [{a:.4}, {b:.4}] m, \
                             holes excepted"
                        )
                    },
                );
                PhysicsError::invalid(
                    Param::ReleaseAlongDip,
                    rel.along_dip,
                    format!(
                        "the release point is not on the floor at this across-dip position \
                         (outside it or over a hole): {span}"
                    ),
                )
            };
            // the part of the line y = across that lies over the floor (a contour set's hull
            // need not reach its bounding box)
            const SCAN: usize = 4096;
            let xs = |k: usize| ext[0] + (ext[1] - ext[0]) * k as f64 / SCAN as f64;
            let first = (0..=SCAN)
                .find(|&k| along_at(xs(k)).is_some())
                .ok_or_else(off)?;
            let last = (first..=SCAN)
                .rev()
                .find(|&k| along_at(xs(k)).is_some())
                .ok_or_else(off)?;
            let (mut lo, mut hi) = (xs(first), xs(last));
            let (flo, fhi) = (along_at(lo).ok_or_else(off)?, along_at(hi).ok_or_else(off)?);
            if rel.along_dip > fhi {
                return Err(PhysicsError::invalid(
                    Param::ReleaseAlongDip,
                    rel.along_dip,
                    format!(
                        "the release point is past the floor's lower edge at across_m = {y} m: \
                         along_dip_m must be at most {fhi} m there"
                    ),
                ));
            }
            if rel.along_dip <= flo {
                // above the floor's upper edge at this across_m: start on that edge
                hi = lo;
            }
            // bisection for along = along_dip; None when it meets a point off the floor
            let bisect = |mut lo: f64, mut hi: f64| -> Option<(f64, f64)> {
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if hi == lo || mid <= lo || mid >= hi {
                        break;
                    }
                    match along_at(mid) {
                        Some(a) if a < rel.along_dip => lo = mid,
                        Some(_) => hi = mid,
                        None => return None,
                    }
                }
                Some((lo, hi))
            };
            (lo, hi) = match bisect(lo, hi) {
                Some(b) => b,
                None => {
                    // a hole lies on the line: bisect between the last sample on the floor
                    // before along_dip and the first after it
                    let mut a = None;
                    let mut b = None;
                    for k in first..=last {
                        match along_at(xs(k)) {
                            Some(s) if s < rel.along_dip => a = Some(k),
                            Some(_) => {
                                b = Some(k);
                                break;
                            }
                            None => {}
                        }
                    }
                    let (Some(a), Some(b)) = (a, b) else {
                        return Err(off());
                    };
                    bisect(xs(a), xs(b)).ok_or_else(off)?
                }
            };
            let x = if along_at(hi).is_some_and(|a| a == rel.along_dip) {
                hi
            } else {
                lo
            };
            let f = floor
                .locate(x, y, 1.0, 0.0)
                .or_else(|| floor.locate(x, y, 0.0, 0.0));
            (x, f.ok_or_else(off)?)
        }
    };
    if !matches!(face.floor, FloorSpec::Plane) && case.method == Method::RigidBlock {
        let shape = BlockShape::of_rock(&case.rock)?;
        if fits(&floor, Some(&shape), x, y).is_none() {
            let (x2, y2, f2) = place_block(&floor, &shape, x, y)
                .ok_or_else(|| not_on_floor(&floor, &shape, rel.along_dip, x, y))?;
            let along = |x: f64, y: f64| {
                let z = floor
                    .facet_plane(floor.locate(x, y, 0.0, 0.0).unwrap_or(f2))
                    .z(x, y);
                mean.along(&Vector3::new(x, y, z))
            };
            moved = Some([along(x2, y2) - along(x, y), y2 - y]);
            (x, y, facet) = (x2, y2, f2);
        }
    }
    let pl = floor.facet_plane(facet);
    let z_floor = pl.z(x, y);
    // A drop too small to lift the rock by more than a few ulps of its coordinates (down to the
    // subnormal 5e-324 m) releases it on the floor: its flight would end within rounding of its
    // start, where no landing can be resolved.
    let lifted =
        rel.drop_height > 8.0 * f64::EPSILON * (1.0 + x.abs().max(y.abs()).max(z_floor.abs()));
    let drop = if lifted { rel.drop_height } else { 0.0 };
    let p0 = Vector3::new(x, y, z_floor + drop);
    let normal = pl.normal();
    let down_dip = pl.down_dip();
    let (v0, projected) = start_velocity(rel, &down_dip, &normal, drop == 0.0);
    let g = case.gravity;
    let z_end = mean.z_at(face.length);
    let e0 = 0.5 * v0.norm_squared() + g * (p0.z - z_end);
    // on the plane the release's along_dip is exact; a floor's (or a plan point's) is measured
    let release_along = match (&face.floor, rel.point) {
        (FloorSpec::Plane, None) => rel.along_dip,
        _ => mean.along(&Vector3::new(x, y, z_floor)),
    };
    if rel.point.is_some()
        && release_along.partial_cmp(&face.length) != Some(std::cmp::Ordering::Less)
    {
        return Err(PhysicsError::invalid(
            Param::ReleasePoint,
            rel.point.map_or(0.0, |p| p[0]),
            format!(
                "the release point lies {release_along:.4} m along the dip, not above the face's \
                 lower end at length_m = {} m",
                face.length
            ),
        ));
    }
    Ok(Prepared {
        release_along,
        normal,
        down_dip,
        projected,
        base: Vector3::new(x, y, z_floor),
        on_floor: (drop == 0.0).then_some(facet),
        floor,
        mass: case.rock.mass(),
        g,
        p0,
        v0,
        z_end,
        e0,
        moved,
    })
}

/// Warnings about where the nominal run `r` started and ended on its floor: a block moved
/// onto the floor at the release (`release_moved`, by how much), a run that left the floor
/// (`left_floor`: where, and past which boundary).
pub(super) fn start_and_end_warnings(pr: &Prepared, r: &mut MigrationResult) {
    if let Some(vn) = pr.projected {
        r.warnings.push(Warning {
            code: "release_velocity_projected",
            message: format!(
                "the rock starts on the floor (drop_height_m 0) and its release velocity had a \
                 component of {vn:.4} m/s normal to the floor ({}): it starts with the \
                 component along the floor only; lift it (drop_height_m > 0) to start in flight",
                if vn < 0.0 { "into it" } else { "away from it" }
            ),
        });
    }
    if let Some([ds, dy]) = pr.moved {
        r.warnings.push(Warning {
            code: "release_moved",
            message: format!(
                "the block resting face-down at the release point overhung the floor's edge (or \
                 a hole): it was placed at the nearest position where every corner is over the \
                 floor, {ds:.4} m down the dip and {dy:.4} m across from the point asked for"
            ),
        });
    }
    if r.arrival.stop_reason != StopReason::LeftFloor {
        return;
    }
    let a = &r.arrival;
    let [x, y, _] = a.position;
    let floor = &pr.floor;
    let ext = floor.extent();
    // the floor's extent's edges and the rock's distance to each, m
    let edges = [
        ("upper edge", x - ext[0]),
        ("lower edge", ext[1] - x),
        ("side edge at the smallest across_m", y - ext[2]),
        ("side edge at the largest across_m", ext[3] - y),
    ];
    let (edge, dist) = edges
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or(("edge", 0.0));
    let tol = 1e-6 * (1.0 + x.abs().max(y.abs()));
    let on_floor = floor.locate(x, y, 0.0, 0.0).is_some();
    let why = if dist <= tol {
        format!("it passed the floor's {edge}, where the floor's data end")
    } else if on_floor && r.method == Method::RigidBlock {
        format!(
            "its centre is still over the floor, but a corner of the block passed the floor's \
             boundary (its edge or a hole) below the floor's level there, where no floor holds \
             it (the nearest edge of the floor's extent, its {edge}, is {dist:.4} m away)"
        )
    } else {
        "it came over a hole in the floor (nodes without data) or past the edge of the area \
         the floor's data cover"
            .to_string()
    };
    r.warnings.push(Warning {
        code: "left_floor",
        message: format!(
            "the rock left the floor at {:.4} m along the dip, {y:.4} m across, t = {:.4} s: \
             {why}; the run ends there (stop_reason left_floor), its motion beyond the floor's \
             data unknown",
            a.along_dip, a.time
        ),
    });
}

/// Plan offsets (m) from the floor point a block rests on to the points that must lie over the
/// floor: a polyhedron's vertices, resting face-down on a facet of unit normal `nf` (a block
/// stops once a vertex is off the floor below its level); a sphere's centre (it stops when its
/// centre leaves the floor).
fn footprint(shape: &BlockShape, nf: &Vector3<f64>) -> Vec<[f64; 2]> {
    let c = nf * shape.rest_height();
    if shape.sphere_radius.is_some() {
        return vec![[c.x, c.y]];
    }
    let r = shape.resting_orientation(nf);
    shape
        .vertices
        .iter()
        .map(|v| {
            let p = c + r * v;
            [p.x, p.y]
        })
        .collect()
}

/// The facet under (x, y) when the rock resting there lies over the floor: the point, and for
/// a block (`shape`) every point of its [`footprint`], on the floor (not beyond its edge, not
/// over a hole).
fn fits(floor: &Floor, shape: Option<&BlockShape>, x: f64, y: f64) -> Option<Facet> {
    let f = floor
        .locate(x, y, 1.0, 0.0)
        .or_else(|| floor.locate(x, y, 0.0, 0.0))?;
    let Some(shape) = shape else { return Some(f) };
    footprint(shape, &floor.facet_plane(f).normal())
        .iter()
        .all(|d| floor.locate(x + d[0], y + d[1], 0.0, 0.0).is_some())
        .then_some(f)
}

/// The along-dip interval, m, where the rock (a point mass; a block: `shape`) fits on the floor
/// at across position `y`: the first and last of 1024 samples over the floor's extent where it
/// fits, each refined by bisection against its outer neighbour to 1e-9 of the extent. `None`
/// when it fits nowhere on that line.
fn along_span(floor: &Floor, shape: Option<&BlockShape>, y: f64) -> Option<(f64, f64)> {
    const SCAN: usize = 1024;
    let ext = floor.extent();
    let xs = |k: usize| ext[0] + (ext[1] - ext[0]) * k as f64 / SCAN as f64;
    let ok = |x: f64| fits(floor, shape, x, y);
    let first = (0..=SCAN).find(|&k| ok(xs(k)).is_some())?;
    let last = (first..=SCAN).rev().find(|&k| ok(xs(k)).is_some())?;
    let refine = |mut inside: f64, mut outside: f64| {
        while (inside - outside).abs() > 1e-9 * (ext[1] - ext[0]) {
            let mid = 0.5 * (inside + outside);
            if ok(mid).is_some() {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        inside
    };
    let lo = if first > 0 {
        refine(xs(first), xs(first - 1))
    } else {
        xs(first)
    };
    let hi = if last < SCAN {
        refine(xs(last), xs(last + 1))
    } else {
        xs(last)
    };
    let along = |x: f64| {
        let f = ok(x)?;
        Some(
            floor
                .mean
                .along(&Vector3::new(x, y, floor.facet_plane(f).z(x, y))),
        )
    };
    Some((along(lo)?, along(hi)?))
}

/// The along-dip interval, m, where a release of `case` fits on `floor` (built from its face) at
/// its across position: the point over the floor, and for the rigid block the resting block
/// with every corner over it (the rule [`prepare_on`] applies to each release). `None` on the
/// plane, which every along-dip position fits.
///
/// Errors: a rock shape that makes no block.
pub(crate) fn release_span(
    case: &MigrationCase,
    floor: &Floor,
) -> PhysicsResult<Option<(f64, f64)>> {
    if matches!(case.face.floor, FloorSpec::Plane) {
        return Ok(None);
    }
    let shape = match case.method {
        Method::RigidBlock => Some(BlockShape::of_rock(&case.rock)?),
        Method::LumpedMass => None,
    };
    Ok(along_span(floor, shape.as_ref(), case.release.across))
}

/// Largest distance in plan, as a multiple of the block's bounding radius r_max, by which a
/// release is moved to where the resting block fits on the floor: a block whose centre is over
/// the floor overhangs its edge by less than r_max, and a corner needs √2 of that.
pub(crate) const RELEASE_MOVE_RADII: f64 = 2.0;

/// The plan position nearest to (x, y), within [`RELEASE_MOVE_RADII`] r_max, where the resting
/// block fits on the floor, with the facet under it: candidates on a grid of r_max/16 by
/// increasing distance (down the dip first, then across, at equal distance), the first that fits
/// refined by bisection towards (x, y) to 1e-6 r_max and kept 1e-3 r_max inside the boundary
/// found. `None` when none fits so near.
fn place_block(floor: &Floor, shape: &BlockShape, x: f64, y: f64) -> Option<(f64, f64, Facet)> {
    const N: i32 = 32;
    let step = RELEASE_MOVE_RADII * shape.r_max / f64::from(N);
    let mut cand: Vec<(i32, i32)> = (-N..=N)
        .flat_map(|i| (-N..=N).map(move |j| (i, j)))
        .filter(|&(i, j)| i * i + j * j <= N * N && (i, j) != (0, 0))
        .collect();
    cand.sort_by_key(|&(i, j)| (i * i + j * j, -i, j.abs(), j));
    let (i, j) = cand.into_iter().find(|&(i, j)| {
        fits(
            floor,
            Some(shape),
            x + f64::from(i) * step,
            y + f64::from(j) * step,
        )
        .is_some()
    })?;
    let (dx, dy) = (f64::from(i) * step, f64::from(j) * step);
    let at = |t: f64| (x + t * dx, y + t * dy);
    let fits_at = |t: f64| {
        let (a, b) = at(t);
        fits(floor, Some(shape), a, b)
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    let len = dx.hypot(dy);
    while (hi - lo) * len > 1e-6 * shape.r_max {
        let mid = 0.5 * (lo + hi);
        if fits_at(mid).is_some() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let t = [(hi + 1e-3 * shape.r_max / len).min(1.0), hi, 1.0]
        .into_iter()
        .find(|&t| fits_at(t).is_some())?;
    let (a, b) = at(t);
    Some((a, b, fits_at(t)?))
}

/// The 422 for a resting block that does not fit on the floor near the release point: the
/// along-dip interval at this across position where it fits (naming `along_dip_m`), else the
/// across interval at this along-dip position (naming `across_m`), scanned in 1024 steps over
/// the floor's extent.
fn not_on_floor(floor: &Floor, shape: &BlockShape, along: f64, x: f64, y: f64) -> PhysicsError {
    const SCAN: usize = 1024;
    let ext = floor.extent();
    let span = |lo: f64, hi: f64, at: &dyn Fn(f64) -> Option<f64>| {
        let vals: Vec<f64> = (0..=SCAN)
            .filter_map(|k| at(lo + (hi - lo) * k as f64 / SCAN as f64))
            .collect();
        let min = vals.iter().copied().fold(f64::INFINITY, f64::min);
        let max = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (min <= max).then_some((min, max))
    };
    let what = format!(
        "the resting block (bounding radius {:.4} m) is not on the floor at the release point: \
         a block is placed face-down with every corner over the floor, moved at most {} \
         bounding radii",
        shape.r_max, RELEASE_MOVE_RADII
    );
    if let Some((a, b)) = along_span(floor, Some(shape), y) {
        return PhysicsError::invalid(
            Param::ReleaseAlongDip,
            along,
            format!("{what}; at across_m = {y} m it fits for along_dip_m in [{a:.4}, {b:.4}] m"),
        );
    }
    let across_at = |yv: f64| fits(floor, Some(shape), x, yv).map(|_| yv);
    match span(ext[2], ext[3], &across_at) {
        Some((a, b)) => PhysicsError::invalid(
            Param::ReleaseAcross,
            y,
            format!(
                "{what}; at along_dip_m = {along} m it fits for across_m in [{a:.4}, {b:.4}] m, \
                 and nowhere along the dip at across_m = {y} m"
            ),
        ),
        None => PhysicsError::invalid(
            Param::ReleaseAlongDip,
            along,
            format!(
                "{what}; it fits nowhere along the dip at across_m = {y} m nor across the face at along_dip_m = {along} m"
            ),
        ),
    }
}

/// Radius of the rolling sphere, m: a sphere's own radius; any other shape rolls as the sphere
/// inscribed in its cube, side_length / 2. Rolling uses a solid sphere's inertia (spin-up ×5/7,
/// KE 0.7 m v²) whatever the radius, so the radius sets only the reported angular speed v / R;
/// a `roll_as_sphere` warning says so for non-spherical rocks.
pub(super) fn roll_radius(rock: &Rock) -> f64 {
    match rock.shape {
        RockShape::Sphere { radius } => radius,
        _ => rock.side_length / 2.0,
    }
}

/// The lumped-mass run's fixed inputs: the case's options on the prepared release.
pub(super) fn lumped_mass_setup<'a>(case: &'a MigrationCase, pr: &'a Prepared) -> Setup<'a> {
    Setup {
        floor: &pr.floor,
        g: pr.g,
        motion: case.lumped_mass.motion,
        v_stop: case.lumped_mass.stop_normal_speed,
        radius: roll_radius(&case.rock),
        length: case.stop_length().0,
        span_support: case.stop_length().1,
        supports: &case.supports,
        lines: &case.lines,
        mass: pr.mass,
        end_time: case.end_time,
        max_steps: case.max_steps_per_run,
        p0: pr.p0,
        v0: pr.v0,
        on_floor: pr.on_floor,
        base: (pr.base, pr.release_along),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over a 45° grid (x in [0, 17], y in [−3, 3] m), a 0.3 × 0.2 × 0.5 m block: where every
    /// corner of the resting block is over the floor it is placed as asked (and everywhere at
    /// least r_max inside the edges it is); elsewhere it is placed where every corner is, at most
    /// two bounding radii away, and never where the stop rule would end the run at once.
    #[test]
    fn a_placed_block_rests_with_every_corner_over_the_floor() {
        let dip = 45f64.to_radians();
        let heights: Vec<Vec<f64>> = (0..7)
            .map(|_| (0..18).map(|j| -f64::from(j)).collect())
            .collect();
        let floor = Floor::grid(dip, [0.0, -3.0], 1.0, &heights).unwrap();
        let shape = BlockShape::cuboid([0.3, 0.2, 0.5], 2700.0).unwrap();
        let r = shape.r_max;
        let (mut moved, mut kept) = (0, 0);
        for i in 0..=60 {
            for j in 0..=40 {
                let x = -0.2 + 17.4 * f64::from(i) / 60.0;
                let y = -3.2 + 6.4 * f64::from(j) / 40.0;
                if floor.locate(x, y, 0.0, 0.0).is_none() {
                    continue;
                }
                let inside = x >= r && x <= 17.0 - r && y.abs() <= 3.0 - r;
                if fits(&floor, Some(&shape), x, y).is_some() {
                    kept += 1;
                    continue;
                }
                assert!(
                    !inside,
                    "({x}, {y}) is {r} m inside the edges and does not fit"
                );
                let (x2, y2, f) = place_block(&floor, &shape, x, y)
                    .unwrap_or_else(|| panic!("({x}, {y}) not placed"));
                assert!((x2 - x).hypot(y2 - y) <= RELEASE_MOVE_RADII * r * (1.0 + 1e-12));
                assert_eq!(fits(&floor, Some(&shape), x2, y2), Some(f));
                for d in footprint(&shape, &floor.facet_plane(f).normal()) {
                    assert!(floor.locate(x2 + d[0], y2 + d[1], 0.0, 0.0).is_some());
                }
                moved += 1;
            }
        }
        assert!(moved > 100 && kept > 1000, "{moved} moved, {kept} kept");
    }

    /// The along-dip interval where the 0.3 m cube fits at y = 0 on that grid starts half its
    /// side down the dip from the upper edge and ends half its side (plus the rest height's
    /// reach down the dip of the top face) above the lower edge; a point mass fits on all of it.
    #[test]
    fn the_release_span_is_where_the_block_fits() {
        let mut case = MigrationCase::default();
        let row: Vec<f64> = (0..18).map(|j| -f64::from(j)).collect();
        case.face.floor = FloorSpec::Grid {
            origin: [0.0, -3.0],
            spacing: 1.0,
            heights: vec![row; 7],
        };
        let floor = build_floor(&case).unwrap();
        let end = 17.0 * 2f64.sqrt();
        let (a, b) = release_span(&case, &floor).unwrap().unwrap();
        assert!(a.abs() < 1e-9 && (b - end).abs() < 1e-9, "[{a}, {b}]");
        case.method = Method::RigidBlock;
        let (a, b) = release_span(&case, &floor).unwrap().unwrap();
        // the cube's faces are ±0.15 m along the dip about its centre, whose foot is the point;
        // the top face lies 0.3 m up the normal, which leans down the dip in plan
        assert!((a - 0.15).abs() < 1e-6, "{a}");
        assert!(b < end - 0.15 && b > end - 0.5, "{b}");
    }
}

//! The release: everything a run needs that the Monte Carlo draws do not change (the floor, the
//! start on or above it, the mass and the energy at the start), built once per case.

use std::sync::Arc;

use nalgebra::Vector3;

use super::lumped_mass::Setup;
use super::terrain::Floor;
use super::{FloorSpec, MigrationCase};
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
    let y = rel.across;
    let (x, facet) = match face.floor {
        FloorSpec::Plane => (rel.along_dip * mean.cos, 0),
        _ => {
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
                PhysicsError::invalid(
                    Param::ReleaseAlongDip,
                    rel.along_dip,
                    "the release point is not on the floor at this across-dip position (outside it or over a hole)",
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
                return Err(off());
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
    let pl = floor.facet_plane(facet);
    let z_floor = pl.z(x, y);
    // A drop too small to lift the rock by more than a few ulps of its coordinates (down to the
    // subnormal 5e-324 m) releases it on the floor: its flight would end within rounding of its
    // start, where no landing can be resolved.
    let lifted =
        rel.drop_height > 8.0 * f64::EPSILON * (1.0 + x.abs().max(y.abs()).max(z_floor.abs()));
    let drop = if lifted { rel.drop_height } else { 0.0 };
    let p0 = Vector3::new(x, y, z_floor + drop);
    let v0 = pl.down_dip() * rel.speed;
    let g = case.gravity;
    let z_end = mean.z_at(face.length);
    let e0 = 0.5 * rel.speed * rel.speed + g * (p0.z - z_end);
    Ok(Prepared {
        // on the plane the release's along_dip is exact; a floor's is measured
        release_along: match face.floor {
            FloorSpec::Plane => rel.along_dip,
            _ => mean.along(&Vector3::new(x, y, z_floor)),
        },
        base: Vector3::new(x, y, z_floor),
        on_floor: (drop == 0.0).then_some(facet),
        floor,
        mass: case.rock.mass(),
        g,
        p0,
        v0,
        z_end,
        e0,
    })
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
        end_time: case.end_time,
        max_steps: case.max_steps_per_run,
        p0: pr.p0,
        v0: pr.v0,
        on_floor: pr.on_floor,
        base: (pr.base, pr.release_along),
    }
}

//! Rockfall migration down the face (physics.md §C, api.md `POST /v1/migration`).
//!
//! [`run`] is the single entry: it builds the floor, runs the nominal trajectory (with events and
//! a sampled trajectory when asked) and, with [`MigrationCase::monte_carlo`], a seeded ensemble
//! with its statistics. Only the lumped-mass energy tracking method exists so far; the rigid-block
//! DEM (physics.md §C.3) is named in [`Method`] so that it can be added beside it.
//!
//! Coordinates (api.md): x horizontal down-dip, y along strike, z up; the plane floor is
//! z = −x tan θ; `along_dip` is measured in the face's mean plane from its upper end; potential
//! energy is m g (z − z_end) with z_end the mean plane's height at `along_dip` = length.

mod case;
pub mod compare;
mod ensemble;
pub mod lines;
mod lumped_mass;
pub mod maps;
pub mod monte_carlo;
mod release;
mod report;
mod rigid_block;
pub mod shape;
mod terrain;
mod trajectory;

pub use self::case::*;
pub use self::ensemble::Crossings;
pub use self::ensemble::{Columns, RunRecords, STATISTICS_COLUMNS, attach_ensemble, run_columns};
use self::ensemble::{MU_MAX, Polled, ensemble, ensemble_mapped};
pub(crate) use self::ensemble::{ensemble_run, run_in_chunks};
pub use self::lines::{Barrier, Crossing, Line, LineAction};
use self::release::{
    Prepared, lumped_mass_setup, prepare, prepare_on, roll_radius, start_and_end_warnings,
};
pub(crate) use self::release::{build_floor, release_span};
pub use self::report::*;
/// The built floor of a face, shared by the runs of an ensemble (see [`build_floor`]).
pub(crate) use self::terrain::Floor;
use self::trajectory::{arrival_of, sample_trajectory, xyz};
pub(crate) use self::trajectory::{first_column_reach, support_impact_speed};
pub use crate::physics::stats::{Histogram, Summary};
pub use lumped_mass::{EventKind, MAX_TURN, MIN_REBOUND, Motion, Phase, StopReason};
pub use monte_carlo::Distribution;
pub use rigid_block::{
    ContactModel, FLOOR_MODULUS_PA, FLOOR_POISSON, FloorMaterial, REST_SPEED_M_S, REST_TIME_S,
    RigidBlockOptions, RigidBlockReport, bounce_restitution,
};
pub use terrain::{
    BlockContact, CONTOUR_BYTES_PER_POINT, ContourLine, GRID_BYTES_PER_POINT, MAX_CODE_CELLS,
    MAX_MATERIALS, MAX_POLYGON_VERTICES, MAX_POLYGONS, MapFrame, Material, ZonePolygon, ZoneShape,
    Zones, ZonesSpec, contour_points, grid_bytes, self_intersection,
};

use self::lumped_mass::{Recording, simulate};
use self::terrain::RunZones;
use super::control::Control;
use super::error::{Param, PhysicsError, PhysicsResult};
use super::material::RockShape;
use super::stats::precision;

/// Runs a migration case: the nominal trajectory and, when asked, the Monte Carlo ensemble.
///
/// Errors: `InvalidInput` for a roll with μ < (2/7) tan θ ([`Param::FaceFriction`], or
/// [`Param::DrawnFriction`] when the drawn μ can fall below it), a release off a grid
/// or contour floor, a malformed floor, too many trajectory samples ([`Param::TrajectorySampleInterval`])
/// or the rigid-block method (not available yet); `TooManySteps` past
/// `max_steps_per_run`; `Cancelled`/`TimedOut` from the control.
///
/// # Special cases
/// A drop height of 0 starts the ground phase at once (no impact). A slide with zero acceleration
/// and zero speed is at rest at once. Normal rebounds slower than max(v_stop, [`MIN_REBOUND`])
/// end the bouncing.
///
/// # References
/// physics.md §C.1–C.2; api.md `POST /v1/migration`.
///
/// # Examples
/// ```
/// use gangue::physics::{Control, migration::{run, MigrationCase}};
/// let r = run(&MigrationCase::default(), &Control::unlimited()).unwrap();
/// assert_eq!(r.impact_count, 3);
/// assert!((r.arrival.speed - 36.35233409073599).abs() < 1e-8);
/// ```
pub fn run(case: &MigrationCase, control: &Control) -> PhysicsResult<MigrationResult> {
    if let (Some(mc), Some(t)) = (&case.monte_carlo, &case.target) {
        return run_until_precise(case, mc, t, control);
    }
    let n = case.monte_carlo.map_or(0, |mc| mc.runs);
    let grid = case.output.maps.as_ref().filter(|_| n > 0);
    let (r, runs, cells) = run_part_mapped(case, 0..n, true, grid, control)?;
    let mut r =
        r.ok_or_else(|| PhysicsError::Numerical("the nominal run was not returned".into()))?;
    if let Some(mc) = &case.monte_carlo {
        let records = Polled {
            runs: &runs,
            control,
        };
        attach_ensemble(&mut r, mc, case.output.runs_csv, &records)?;
        if let Some(g) = grid {
            control.check()?;
            r.maps = Some(maps::build_maps(g, &cells));
        }
    }
    Ok(r)
}

/// [`run`] with a target: the runs in prefixes ([`precision::checkpoints`]) until the arrival
/// speed's percentile is precise enough or every run ran; the answer is that of the runs used
/// (bit for bit the answer of that many runs), with what the target gave.
fn run_until_precise(
    case: &MigrationCase,
    mc: &MonteCarlo,
    t: &ArrivalTarget,
    control: &Control,
) -> PhysicsResult<MigrationResult> {
    let (r, _, _) = run_part_mapped(case, 0..0, true, None, control)?;
    let mut r =
        r.ok_or_else(|| PhysicsError::Numerical("the nominal run was not returned".into()))?;
    let mut runs: Vec<RunSummary> = Vec::new();
    let mut checked_at = Vec::new();
    let mut width = None;
    for n in precision::checkpoints(mc.runs) {
        let (_, more, _) = run_part_mapped(case, runs.len() as u64..n, false, None, control)?;
        runs.extend(more);
        checked_at.push(n);
        let mut speeds: Vec<f64> = runs
            .iter()
            .filter(|s| s.stop_reason == StopReason::LowerEnd)
            .map(|s| s.speed)
            .collect();
        speeds.sort_by(f64::total_cmp);
        width = precision::percentile_relative_half_width(&speeds, t.percentile);
        if width.is_some_and(|w| w <= t.relative_half_width) {
            break;
        }
    }
    let used = MonteCarlo {
        runs: runs.len() as u64,
        ..*mc
    };
    let records = Polled {
        runs: &runs,
        control,
    };
    attach_ensemble(&mut r, &used, case.output.runs_csv, &records)?;
    if let Some(g) = &case.output.maps {
        // the maps of the runs used, their paths run again
        let mut c = case.clone();
        c.monte_carlo = Some(used);
        let (_, _, cells) = run_part_mapped(&c, 0..used.runs, false, Some(g), control)?;
        control.check()?;
        r.maps = Some(maps::build_maps(g, &cells));
    }
    if let Some(st) = r.statistics.as_mut() {
        st.target = Some(ArrivalTargetOutcome {
            target: *t,
            relative_half_width: width,
            met: width.is_some_and(|w| w <= t.relative_half_width),
            runs: used.runs,
            max_runs: mc.runs,
            checked_at,
        });
    }
    Ok(r)
}

/// What a part of a case gives: the nominal run (when asked), the runs' summaries and, with a
/// map grid, the cells each run entered (both in run order).
pub(crate) type Part = (
    Option<MigrationResult>,
    Vec<RunSummary>,
    Vec<maps::RunCells>,
);

/// Runs part of a migration case: the nominal run when `nominal` (its result without ensemble
/// statistics) and the Monte Carlo runs with global indices in `range`, in run order. Run i is
/// seeded by (seed, i) whatever the range, so the runs of any split of 0..runs are the runs of
/// [`run`]; [`attach_ensemble`] makes the statistics from them. The case is checked as by [`run`]
/// whatever the part.
///
/// Errors: as [`run`].
pub fn run_part(
    case: &MigrationCase,
    range: std::ops::Range<u64>,
    nominal: bool,
    control: &Control,
) -> PhysicsResult<(Option<MigrationResult>, Vec<RunSummary>)> {
    let (r, runs, _) = run_part_mapped(case, range, nominal, None, control)?;
    Ok((r, runs))
}

/// [`run_part`], with the cells each run entered on `grid` when given (see [`maps`]).
///
/// Errors: as [`run`].
pub(crate) fn run_part_mapped(
    case: &MigrationCase,
    range: std::ops::Range<u64>,
    nominal: bool,
    grid: Option<&maps::MapGrid>,
    control: &Control,
) -> PhysicsResult<Part> {
    if case.method == Method::RigidBlock {
        let mut part = rigid_block::run_part(case, range, nominal, grid, control)?;
        if let (Some(r), Some(z)) = (part.0.as_mut(), case.face.zones.as_ref())
            && let Some(events) = r.events.as_mut()
        {
            for e in events {
                e.zone = Some(z.code_at(e.position[0], e.position[1]));
            }
        }
        return Ok(part);
    }
    let face = &case.face;
    let dip = face.dip_deg.to_radians();
    let mu_roll = 2.0 / 7.0 * dip.tan();
    if case.lumped_mass.motion == Motion::Roll {
        if face.friction_coefficient < mu_roll {
            return Err(PhysicsError::invalid(
                Param::FaceFriction,
                face.friction_coefficient,
                format!("rolling without slip needs μ ≥ (2/7) tan θ = {mu_roll:.6}"),
            ));
        }
        if let Some(z) = &face.zones
            && let Some(m) = z.materials().iter().find(|m| {
                m.friction_coefficient < mu_roll
                    || m.friction_coefficient_distribution
                        .is_some_and(|d| case.monte_carlo.is_some() && d.lower_bound() < mu_roll)
            })
        {
            return Err(PhysicsError::invalid(
                Param::FaceZones,
                m.friction_coefficient,
                format!(
                    "rolling without slip needs μ ≥ (2/7) tan θ = {mu_roll:.6} on every \
                     material (code {}, drawn ones included)",
                    m.code
                ),
            ));
        }
        if let Some(d) = case.monte_carlo.and_then(|m| m.friction_coefficient)
            && d.lower_bound() < mu_roll
        {
            return Err(PhysicsError::invalid(
                Param::DrawnFriction,
                d.lower_bound(),
                format!("rolling without slip needs every drawn μ ≥ (2/7) tan θ = {mu_roll:.6}"),
            ));
        }
    }
    control.check()?;
    let pr = prepare(case)?;
    control.check()?;
    let r = if nominal {
        let mut r = nominal_run(case, &pr, control)?;
        start_and_end_warnings(&pr, &mut r);
        Some(r)
    } else {
        None
    };
    let (runs, cells) = match (&case.monte_carlo, grid) {
        (Some(mc), None) if !range.is_empty() => {
            (ensemble(case, &pr, mc, range, control)?, Vec::new())
        }
        (Some(mc), Some(g)) if !range.is_empty() => {
            ensemble_mapped(case, &pr, mc, range, g, control)?
        }
        _ => (Vec::new(), Vec::new()),
    };
    Ok((r, runs, cells))
}

/// The nominal run of a lumped-mass case, without ensemble statistics.
fn nominal_run(
    case: &MigrationCase,
    pr: &Prepared,
    control: &Control,
) -> PhysicsResult<MigrationResult> {
    let face = &case.face;
    let setup = lumped_mass_setup(case, pr);
    let m = pr.mass;
    let (en, et) = (face.restitution_normal, face.restitution_tangential);
    let mut rec = Recording::default();
    let want_rec = case.output.events || case.output.trajectory;
    let zones = face.zones.as_ref().map(|z| {
        RunZones::new(
            z,
            z.materials()
                .iter()
                .map(|m| m.friction_coefficient)
                .collect(),
        )
    });
    let out = simulate(
        &setup,
        face.friction_coefficient,
        zones.as_ref(),
        &mut || match &zones {
            None => (en, et),
            Some(z) => {
                let m = &z.zones.materials()[z.current.get()];
                (m.restitution_normal, m.restitution_tangential)
            }
        },
        want_rec.then_some(&mut rec),
        Some(control),
    )?;
    let mean = pr.floor.mean;
    let mut warnings = Vec::new();
    let trajectory = if case.output.trajectory {
        Some(sample_trajectory(case, pr, &out, &rec.segments)?)
    } else {
        None
    };
    let arrival = arrival_of(case, pr, &out);
    let (imp, fric, trans) = (out.e_imp * m, out.e_fric * m, out.e_trans * m);
    let taken = out.e_barrier * m;
    let pe = m * pr.g * (out.p.z - pr.z_end);
    let total_start = m * pr.e0;
    let residual = arrival.kinetic_energy + pe + imp + fric + trans + taken - total_start;
    if case.lumped_mass.motion == Motion::Roll
        && !matches!(case.rock.shape, RockShape::Sphere { .. })
    {
        warnings.push(Warning {
            code: "roll_as_sphere",
            message: format!(
                "rolling treats the rock as a solid sphere of radius half its side length, {} m \
                 (the sphere inscribed in its cube): the motion and energies are a rolling \
                 sphere's whatever the shape, and the radius sets only the angular speed",
                roll_radius(&case.rock)
            ),
        });
    }
    if out.rebound_cutoff {
        warnings.push(Warning {
            code: "rebound_cutoff",
            message: format!(
                "the bounces ended at a normal rebound speed below {MIN_REBOUND:e} m/s (the \
                 stop speed asked for is lower): an infinite series of ever smaller bounces, \
                 whose total flight time is finite, is taken to end there and the rock to slide"
            ),
        });
    }
    if out.reason == StopReason::EndTime && out.undecelerated {
        warnings.push(Warning {
            code: "stop_distance_infinite",
            message: "the rock was still on the floor without deceleration at end_time: it would \
                      not stop, so its stop position is left undefined (null)"
                .into(),
        });
    }
    let events = case.output.events.then(|| {
        rec.events
            .iter()
            .map(|e| Event {
                time: e.t,
                kind: e.kind,
                position: xyz(&e.p),
                along_dip: mean.along(&e.p),
                speed_before: e.speed_before,
                speed_after: e.speed_after,
                energy_lost: e.lost * m,
                peak_contact_force: None,
                zone: face.zones.as_ref().map(|z| z.code_at(e.p.x, e.p.y)),
            })
            .collect()
    });
    if case.monte_carlo.is_none() {
        control.set_total(1);
        control.add_done(1);
    }
    Ok(MigrationResult {
        method: case.method,
        mass: m,
        arrival,
        impact_count: out.impacts,
        slide_start_along_dip: out.slide_start,
        stop_along_dip: out.stop_along,
        max_bounce_height: out.max_bounce,
        energy: EnergyBudget {
            total_start,
            impacts: imp,
            friction: fric,
            transition: trans,
            damping: 0.0,
            stored: 0.0,
            barriers: taken,
            residual,
        },
        events,
        trajectory,
        runs: None,
        statistics: None,
        warnings,
        rigid_block: None,
        maps: None,
        comparison: None,
    })
}

//! The ensemble runner: the runs of a Monte Carlo ensemble on the thread pool, in run order,
//! generic over the per-run function (a lumped-mass run, a rigid-block run, a scene's migration
//! and strike), so a method plugs in without touching it.
//!
//! Cancellation: the [`Control`] is polled before anything is allocated and before every run, so
//! a cancelled or timed-out ensemble stops within one run per thread of the flag. The records
//! are allocated after that first poll: per chunk as the runs are done ([`run_in_chunks`]), or
//! once for the whole range and written in place by the chunks ([`run_in_chunks_in_place`],
//! the lumped-mass ensemble's summaries: no copy of the chunks into the whole record).

use std::ops::Range;
use std::sync::Arc;

use rayon::prelude::*;

use nalgebra::Vector3;

use super::lumped_mass::{Phase, Recording, Setup, simulate};
use super::maps::{CellTrack, MapGrid, RunCells};
use super::release::{Prepared, lumped_mass_setup, prepare_on};
use super::terrain::{Floor, RunZones, per_run_values};
use super::trajectory::{height_above_floor, robust_norm, support_impact_speed};
use super::{
    Method, MigrationCase, MigrationResult, MonteCarlo, RunSummary, Statistics, StopReason,
    Warning, monte_carlo, rigid_block,
};
use crate::physics::control::Control;
use crate::physics::error::{PhysicsError, PhysicsResult};
use crate::physics::stats;

/// Runs `one(i)` for the global run indices i in `range` on the thread pool, `chunk` runs at a
/// time (each chunk on one thread), and returns the results in run order.
///
/// `control` is checked first (a cancelled ensemble allocates nothing) and before every run;
/// progress is reported after each chunk. The first error in run order among the chunks that
/// ran wins, so the result does not depend on the thread count, nor on how 0..runs is split into
/// ranges (shards). Shared by every migration method's ensemble and by the scene's.
///
/// Errors: [`PhysicsError::Cancelled`] or [`PhysicsError::TimedOut`] from `control`, or the
/// first error of `one`.
pub(crate) fn run_in_chunks<T, E>(
    range: Range<u64>,
    chunk: usize,
    control: &Control,
    one: impl Fn(u64) -> Result<T, E> + Sync,
) -> Result<Vec<T>, E>
where
    T: Send,
    E: From<PhysicsError> + Send,
{
    control.check()?;
    let runs = range.end.saturating_sub(range.start);
    let chunk = chunk.max(1) as u64;
    let chunks = usize::try_from(runs.div_ceil(chunk)).map_err(|_| {
        E::from(PhysicsError::Numerical(
            "more chunks than usize counts".into(),
        ))
    })?;
    let parts: Vec<Result<Vec<T>, E>> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let start = range.start + c as u64 * chunk;
            let end = (start + chunk).min(range.end);
            // a chunk's length is known: one allocation, no growth by copying
            let mut out = Vec::with_capacity(usize::try_from(end - start).unwrap_or(0));
            for i in start..end {
                control.check()?;
                out.push(one(i)?);
            }
            control.add_done(end - start);
            control.check_pace()?;
            Ok(out)
        })
        .collect();
    // every chunk ran: only now is the whole record allocated, each part freed as it is copied
    let mut all = Vec::new();
    for part in parts {
        let part = part?;
        if all.is_empty() {
            all.reserve_exact(runs as usize);
        }
        all.extend(part);
    }
    Ok(all)
}

/// [`run_in_chunks`] writing each run's result into its slot of the whole record, allocated
/// once (filled with `fill`, every slot overwritten when no run fails): the same chunks, checks,
/// progress and first error in run order, without the copy of the chunks' records into the
/// whole one.
///
/// Errors: as [`run_in_chunks`].
pub(crate) fn run_in_chunks_in_place<T, E>(
    range: Range<u64>,
    chunk: usize,
    control: &Control,
    fill: T,
    one: impl Fn(u64) -> Result<T, E> + Sync,
) -> Result<Vec<T>, E>
where
    T: Copy + Send + Sync,
    E: From<PhysicsError> + Send,
{
    control.check()?;
    let runs = range.end.saturating_sub(range.start);
    let chunk = chunk.max(1);
    let runs = usize::try_from(runs).map_err(|_| {
        E::from(PhysicsError::Numerical(
            "more runs than usize counts".into(),
        ))
    })?;
    let mut all = vec![fill; runs];
    let done: Vec<Result<(), E>> = all
        .par_chunks_mut(chunk)
        .enumerate()
        .map(|(c, out)| {
            let start = range.start + (c * chunk) as u64;
            for (slot, i) in out.iter_mut().zip(start..) {
                control.check()?;
                *slot = one(i)?;
            }
            control.add_done(out.len() as u64);
            control.check_pace()?;
            Ok(())
        })
        .collect();
    for d in done {
        d?;
    }
    Ok(all)
}

/// Largest friction coefficient of the face's range [0, 2]; drawn values are clipped to it.
pub(super) const MU_MAX: f64 = 2.0;

pub(super) fn ensemble(
    case: &MigrationCase,
    pr: &Prepared,
    mc: &MonteCarlo,
    range: std::ops::Range<u64>,
    control: &Control,
) -> PhysicsResult<Vec<RunSummary>> {
    const CHUNK: u64 = 256;
    let setup = lumped_mass_setup(case, pr);
    control.announce(range.end - range.start);
    let one = |i: u64| lumped_one(case, pr, &setup, mc, i, control);
    run_in_chunks_in_place(range, CHUNK as usize, control, UNSET, one)
}

/// The value of a summary's slot before its run is written into it (never returned: a slot
/// stays unset only when a run failed, and then the ensemble fails).
const UNSET: RunSummary = RunSummary {
    time: 0.0,
    speed: 0.0,
    kinetic_energy: 0.0,
    impact_count: 0,
    runout: 0.0,
    max_bounce_height: 0.0,
    stop_reason: StopReason::AtRest,
    steps: 0,
    along_dip_velocity: 0.0,
    support: None,
    impact_speed: 0.0,
    release_along_dip: 0.0,
    release_across: 0.0,
    side_length: 0.0,
    density: 0.0,
    stop_along_dip: 0.0,
    stop_across: 0.0,
    translational_energy: 0.0,
    rotational_energy: 0.0,
    passing_height: 0.0,
};

/// [`ensemble`] with the cells each run entered on `grid` (see [`super::maps`]).
pub(super) fn ensemble_mapped(
    case: &MigrationCase,
    pr: &Prepared,
    mc: &MonteCarlo,
    range: std::ops::Range<u64>,
    grid: &MapGrid,
    control: &Control,
) -> PhysicsResult<(Vec<RunSummary>, Vec<RunCells>)> {
    const CHUNK: u64 = 256;
    let setup = lumped_mass_setup(case, pr);
    control.announce(range.end - range.start);
    let one =
        |i: u64| lumped_one_mapped(case, pr, &setup, mc, i, grid, control).map(|r| (r.0, r.1));
    Ok(run_in_chunks(range, CHUNK as usize, control, one)?
        .into_iter()
        .unzip())
}

/// [`lumped_one`] recorded, with the cells its path entered on `grid`: every closed-form piece
/// sampled at most half a cell apart.
fn lumped_one_mapped(
    case: &MigrationCase,
    pr: &Prepared,
    setup: &Setup<'_>,
    mc: &MonteCarlo,
    i: u64,
    grid: &MapGrid,
    control: &Control,
) -> PhysicsResult<(RunSummary, RunCells, Crossings)> {
    let mut rec = Recording::default();
    let (summary, crossings) = lumped_run(case, pr, setup, mc, i, Some(&mut rec), control)?;
    let m = pr.mass;
    let mut track = CellTrack::new(grid, pr.floor.mean);
    for s in &rec.segments {
        let ke = |v: &Vector3<f64>| {
            let rot = match s.rolling {
                Some(_) => 0.2 * v.norm_squared(),
                None => s.spin.0,
            };
            m * (0.5 * v.norm_squared() + rot)
        };
        track.piece(&s.p0, &s.v0, &s.a, s.dt, &ke);
    }
    Ok((summary, track.finish(), crossings))
}

/// Run `i` of a lumped-mass ensemble: μ then (e_n, e_t) at every impact from the run's stream.
pub(super) fn lumped_one(
    case: &MigrationCase,
    pr: &Prepared,
    setup: &Setup<'_>,
    mc: &MonteCarlo,
    i: u64,
    control: &Control,
) -> PhysicsResult<RunSummary> {
    Ok(lumped_run(case, pr, setup, mc, i, None, control)?.0)
}

/// [`lumped_one`], recorded into `rec` when given.
fn lumped_run(
    case: &MigrationCase,
    pr: &Prepared,
    setup: &Setup<'_>,
    mc: &MonteCarlo,
    i: u64,
    rec: Option<&mut Recording>,
    control: &Control,
) -> PhysicsResult<(RunSummary, Crossings)> {
    let mean = pr.floor.mean;
    let m = pr.mass;
    let mut rng = monte_carlo::run_stream(mc.seed, i);
    // on a floor of several materials, μ is drawn once per distinct distribution in material
    // order (the first where today's single draw is), and (e_n, e_t) from the struck material's
    let zones = case.face.zones.as_ref().map(|z| {
        let mu = per_run_values(
            z.materials()
                .iter()
                .map(|m| (m.friction_coefficient, m.friction_coefficient_distribution)),
            MU_MAX,
            |d| monte_carlo::sample(d, &mut rng),
        );
        RunZones::new(z, mu)
    });
    let mu = match (&zones, &mc.friction_coefficient) {
        (None, Some(d)) => monte_carlo::sample(d, &mut rng).clamp(0.0, MU_MAX),
        _ => case.face.friction_coefficient,
    };
    let mut draw = || {
        let (dn, dt) = match &zones {
            None => (&mc.restitution_normal, &mc.restitution_tangential),
            Some(z) => {
                let m = &z.zones.materials()[z.current.get()];
                (
                    &m.restitution_normal_distribution,
                    &m.restitution_tangential_distribution,
                )
            }
        };
        let en = monte_carlo::sample(dn, &mut rng).clamp(0.0, 1.0);
        let et = monte_carlo::sample(dt, &mut rng).clamp(0.0, 1.0);
        (en, et)
    };
    let drawn = monte_carlo::drawn_release(mc, i, &case.release).map(|rel| Setup {
        v0: super::release::start_velocity(&rel, &pr.down_dip, &pr.normal, pr.on_floor.is_some()).0,
        ..*setup
    });
    let mut o = simulate(
        drawn.as_ref().unwrap_or(setup),
        mu,
        zones.as_ref(),
        &mut draw,
        rec,
        Some(control),
    )?;
    let on_floor = matches!(o.phase, Phase::Slide | Phase::Roll | Phase::Stopped);
    let crossings = std::mem::take(&mut o.crossings);
    let summary = RunSummary {
        time: o.t,
        speed: robust_norm(&o.v),
        kinetic_energy: m * (0.5 * o.v.norm_squared() + o.e_rot),
        impact_count: o.impacts,
        runout: mean.along(&o.p) - pr.release_along,
        max_bounce_height: o.max_bounce,
        stop_reason: o.reason,
        steps: o.steps,
        along_dip_velocity: o.v.dot(&mean.dip_dir()),
        support: o.support,
        impact_speed: o.support.map_or(0.0, |k| {
            support_impact_speed(&mean, &case.supports[k], &o.p, &o.v)
        }),
        release_along_dip: match case.release.point {
            None => case.release.along_dip,
            Some(_) => pr.release_along,
        },
        release_across: match case.release.point {
            None => case.release.across,
            Some(_) => pr.base.y,
        },
        side_length: case.rock.side_length,
        density: case.rock.density,
        stop_along_dip: mean.along(&o.p),
        stop_across: o.p.y,
        translational_energy: 0.5 * m * o.v.norm_squared(),
        rotational_energy: m * o.e_rot,
        passing_height: if on_floor {
            0.0
        } else {
            height_above_floor(&pr.floor, &o.p, &o.v).max(0.0)
        },
    };
    Ok((summary, crossings))
}

/// Per line of a case ([`MigrationCase::lines`]), the rock's state where a run reached it
/// (None: not reached).
pub type Crossings = Vec<Option<super::Crossing>>;

/// Run `index` of the ensemble `mc` of `case`, alone: the summary `/v1/migration`'s ensemble of
/// the same case gives for that run (same streams), the cells the run's path entered on `grid`
/// when given (see [`super::maps`]) and the run's line crossings. A caller may change the
/// release, the rock, the supports or the lines between runs (api.md `POST /v1/scene`), never
/// the face: `floor` is [`build_floor`] of the case's face, built once for all runs.
///
/// Errors: as [`run`].
pub(crate) fn ensemble_run(
    case: &MigrationCase,
    floor: &Arc<Floor>,
    mc: &MonteCarlo,
    index: u64,
    grid: Option<&MapGrid>,
    control: &Control,
) -> PhysicsResult<(RunSummary, Option<RunCells>, Crossings)> {
    if case.method == Method::RigidBlock {
        return rigid_block::ensemble_run(case, floor, mc, index, grid, control);
    }
    let pr = prepare_on(case, Arc::clone(floor))?;
    let setup = lumped_mass_setup(case, &pr);
    match grid {
        None => {
            let (r, x) = lumped_run(case, &pr, &setup, mc, index, None, control)?;
            Ok((r, None, x))
        }
        Some(g) => {
            let (r, c, x) = lumped_one_mapped(case, &pr, &setup, mc, index, g, control)?;
            Ok((r, Some(c), x))
        }
    }
}

/// Warnings of an ensemble, whatever the method: friction draws clipped to [0, 2] (μ is the first
/// draw of each run's stream), a single run (no standard deviation), no run at the lower end.
pub(super) fn ensemble_warnings(mc: &MonteCarlo, runs: u64, st: &Statistics) -> Vec<Warning> {
    let mut warnings = Vec::new();
    if let Some(d) = &mc.friction_coefficient {
        // μ is the first draw of each run's stream: count the draws outside [0, 2]
        let clipped = (0..mc.runs)
            .filter(|&i| {
                let mu = monte_carlo::sample(d, &mut monte_carlo::run_stream(mc.seed, i));
                !(0.0..=MU_MAX).contains(&mu)
            })
            .count();
        if clipped > 0 {
            warnings.push(Warning {
                code: "friction_clipped",
                message: format!(
                    "{clipped} of {} drawn friction coefficients fell outside [0, 2] and \
                     were clipped to it (a normal distribution has unbounded tails; use \
                     truncated_normal to resample instead)",
                    mc.runs
                ),
            });
        }
    }
    if runs < 2 {
        warnings.push(Warning {
            code: "single_run",
            message: "an ensemble of one run has no sample standard deviation: every \
                      std is null; ask for runs ≥ 2"
                .into(),
        });
    }
    if st.speed.is_none() {
        warnings.push(Warning {
            code: "no_run_reached_lower_end",
            message: "no run reached the lower end: speed, kinetic energy and time \
                      statistics are null"
                .into(),
        });
    }
    warnings
}

/// Number of statistics columns of an ensemble (see [`run_columns`]).
pub const STATISTICS_COLUMNS: usize = 7;

/// The statistics columns of one run, in the order of [`Statistics`]: arrival speed, down-dip
/// velocity, kinetic energy and time (None for a run that did not reach the lower end), impact count, runout, largest
/// bounce height.
#[must_use]
pub fn run_columns(r: &RunSummary) -> [Option<f64>; STATISTICS_COLUMNS] {
    let reached = r.stop_reason == StopReason::LowerEnd;
    [
        reached.then_some(r.speed),
        reached.then_some(r.along_dip_velocity),
        reached.then_some(r.kinetic_energy),
        reached.then_some(r.time),
        Some(r.impact_count as f64),
        Some(r.runout),
        Some(r.max_bounce_height),
    ]
}

/// An ensemble's run records: readable in run order as often as needed (sums are taken in run
/// order, the summation order of the contract), with the order statistics of each column. Held
/// in memory by the service; read from part files by a sharded computation's merge.
pub trait RunRecords {
    /// Error of reading the records (none in memory).
    type Error;
    /// Number of runs.
    fn runs(&self) -> u64;
    /// Calls `f` with every run record in run order.
    fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), Self::Error>;
    /// The values at the 0-based `ranks` (ascending) of column `col` of [`run_columns`] (its
    /// present values only) sorted by `f64::total_cmp`.
    fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, Self::Error>;
    /// Every column's present values in run order and the number of runs that reached the
    /// lower end, taken in one pass, when the records are in memory: the statistics then read
    /// the compact columns instead of passing over the whole records once per statistic. None
    /// (the default) where the records are read from files and may not fit in memory.
    fn columns(&self) -> Result<Option<Columns>, Self::Error> {
        Ok(None)
    }
    /// Called before each column's order statistics: reading in memory stops there at a
    /// cancel (nothing by default).
    fn poll(&self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// The statistics columns of an ensemble's records in memory ([`RunRecords::columns`]).
#[derive(Debug, Default)]
pub struct Columns {
    /// Each column's present values, in run order.
    values: [Vec<f64>; STATISTICS_COLUMNS],
    /// Each column's first pass, taken while the values are gathered.
    first: [stats::FirstPass; STATISTICS_COLUMNS],
    /// Runs that reached the lower end.
    reached: u64,
}

impl Columns {
    /// Empty columns with room for `runs` values each, taken at once.
    fn with_capacity(runs: usize) -> Self {
        Columns {
            values: std::array::from_fn(|_| Vec::with_capacity(runs)),
            first: [stats::FirstPass::default(); STATISTICS_COLUMNS],
            reached: 0,
        }
    }

    /// The columns of `runs`.
    fn of(runs: &[RunSummary]) -> Self {
        let mut c = Columns::with_capacity(runs.len());
        c.extend(runs);
        c
    }

    /// Appends the columns of `runs`.
    fn extend(&mut self, runs: &[RunSummary]) {
        for r in runs {
            self.reached += u64::from(r.stop_reason == StopReason::LowerEnd);
            for ((v, p), x) in self
                .values
                .iter_mut()
                .zip(&mut self.first)
                .zip(run_columns(r))
            {
                if let Some(x) = x {
                    v.push(x);
                    p.push(x);
                }
            }
        }
    }
}

/// The summary of one column's values in run order given their first pass (None for no
/// values): the second pass in that order, then the order statistics by selection over the
/// values' order keys, the same bits as the passes over the records and
/// [`RunRecords::order_values`].
fn column_summary(values: Vec<f64>, first: &stats::FirstPass) -> Option<stats::Summary> {
    let mut second = first.second_pass()?;
    second.push_all(&values);
    let mut keys: Vec<u64> = values.into_iter().map(stats::order_key).collect();
    let order = stats::select_ranks(&mut keys, &stats::order_ranks(first.count()));
    Some(second.finish(&order))
}

impl RunRecords for [RunSummary] {
    type Error = std::convert::Infallible;

    fn runs(&self) -> u64 {
        self.len() as u64
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), Self::Error> {
        self.iter().for_each(f);
        Ok(())
    }

    fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, Self::Error> {
        // the column's present values as order keys, the room for all of them taken at once
        fn keys<const C: usize>(runs: &[RunSummary]) -> Vec<u64> {
            let mut keys = Vec::with_capacity(runs.len());
            keys.extend(
                runs.iter()
                    .filter_map(|r| run_columns(r)[C].map(stats::order_key)),
            );
            keys
        }
        let mut work = match col {
            0 => keys::<0>(self),
            1 => keys::<1>(self),
            2 => keys::<2>(self),
            3 => keys::<3>(self),
            4 => keys::<4>(self),
            5 => keys::<5>(self),
            6 => keys::<6>(self),
            // no such column: no values
            _ => Vec::new(),
        };
        Ok(stats::select_ranks(&mut work, ranks))
    }

    fn columns(&self) -> Result<Option<Columns>, Self::Error> {
        Ok(Some(Columns::of(self)))
    }
}

/// Completes a nominal result (from [`run_part`](super::run_part)) with the ensemble's statistics, warnings and,
/// when `runs_csv`, the per-run summaries: two passes over the records in run order and the
/// order statistics of each column. The one way ensemble results are made, whether the records
/// come from threads or from the parts of a sharded computation.
///
/// Errors: those of reading the records.
pub fn attach_ensemble<R: RunRecords + ?Sized>(
    r: &mut MigrationResult,
    mc: &MonteCarlo,
    runs_csv: bool,
    records: &R,
) -> Result<(), R::Error> {
    let st = statistics_of(mc, records)?;
    if let Some(st) = &st {
        r.warnings.extend(ensemble_warnings(mc, records.runs(), st));
    }
    if runs_csv {
        let mut runs = Vec::with_capacity(records.runs() as usize);
        records.for_each_run(&mut |x| runs.push(*x))?;
        r.runs = Some(runs);
    }
    r.statistics = st;
    Ok(())
}

/// The statistics of the records; `None` for records of no run (an ensemble has at least one:
/// every run has an impact count, a runout and a bounce height).
pub(super) fn statistics_of<R: RunRecords + ?Sized>(
    mc: &MonteCarlo,
    records: &R,
) -> Result<Option<Statistics>, R::Error> {
    let n = records.runs();
    if let Some(Columns {
        values,
        first,
        reached,
    }) = records.columns()?
    {
        let mut summaries = Vec::with_capacity(STATISTICS_COLUMNS);
        for (v, f) in values.into_iter().zip(&first) {
            records.poll()?;
            summaries.push(column_summary(v, f));
        }
        return Ok(statistics(mc, n, reached, summaries));
    }
    let mut first = [stats::FirstPass::default(); STATISTICS_COLUMNS];
    let mut reached = 0u64;
    records.for_each_run(&mut |r| {
        reached += u64::from(r.stop_reason == StopReason::LowerEnd);
        for (p, x) in first.iter_mut().zip(run_columns(r)) {
            if let Some(x) = x {
                p.push(x);
            }
        }
    })?;
    let mut second = first.map(|p| p.second_pass());
    records.for_each_run(&mut |r| {
        for (p, x) in second.iter_mut().zip(run_columns(r)) {
            if let (Some(p), Some(x)) = (p, x) {
                p.push(x);
            }
        }
    })?;
    let mut summaries = Vec::with_capacity(STATISTICS_COLUMNS);
    for (col, (p, f)) in second.iter().zip(&first).enumerate() {
        summaries.push(match p {
            Some(p) => Some(p.finish(&records.order_values(col, &stats::order_ranks(f.count()))?)),
            None => None,
        });
    }
    Ok(statistics(mc, n, reached, summaries))
}

/// The statistics of `n` runs of which `reached` reached the lower end, from the summaries of
/// the columns of [`run_columns`] in its order; None when a column every run has is empty (no
/// run).
fn statistics(
    mc: &MonteCarlo,
    n: u64,
    reached: u64,
    summaries: Vec<Option<stats::Summary>>,
) -> Option<Statistics> {
    let mut s = summaries.into_iter();
    let mut next = || s.next().flatten();
    let (speed, along_dip_velocity, kinetic_energy, time) = (next(), next(), next(), next());
    let (Some(impact_count), Some(runout), Some(max_bounce_height)) = (next(), next(), next())
    else {
        return None;
    };
    Some(Statistics {
        runs: n,
        seed: mc.seed,
        reached_fraction: reached as f64 / n.max(1) as f64,
        speed,
        along_dip_velocity,
        kinetic_energy,
        time,
        impact_count,
        runout,
        max_bounce_height,
        target: None,
    })
}

/// An ensemble's records in memory, read under a [`Control`]: the statistics of a large
/// ensemble (two passes and a selection per column) stop at a cancel or timeout like its runs.
pub(super) struct Polled<'a> {
    /// The records, in run order.
    pub(super) runs: &'a [RunSummary],
    /// Polled every 4096 records and before each selection.
    pub(super) control: &'a Control,
}

impl RunRecords for Polled<'_> {
    type Error = PhysicsError;

    fn runs(&self) -> u64 {
        self.runs.runs()
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), PhysicsError> {
        for block in self.runs.chunks(4096) {
            self.control.check()?;
            block.iter().for_each(&mut *f);
        }
        Ok(())
    }

    fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, PhysicsError> {
        self.control.check()?;
        let Ok(values) = self.runs.order_values(col, ranks);
        Ok(values)
    }

    fn columns(&self) -> Result<Option<Columns>, PhysicsError> {
        let mut c = Columns::with_capacity(self.runs.len());
        for block in self.runs.chunks(4096) {
            self.control.check()?;
            c.extend(block);
        }
        Ok(Some(c))
    }

    fn poll(&self) -> Result<(), PhysicsError> {
        self.control.check()
    }
}

#[cfg(test)]
mod tests {
    //! The runner stops at its control's flag: nothing runs (and nothing is allocated for the
    //! records) when the control is cancelled before it starts, and no run starts after the flag
    //! is seen, however long the chunks.

    use std::sync::atomic::{AtomicU64, Ordering};

    use super::*;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a test pool")
    }

    #[test]
    fn an_ensemble_cancelled_before_it_starts_runs_nothing() {
        let control = Control::unlimited();
        control.cancel();
        let ran = AtomicU64::new(0);
        let out = run_in_chunks(0..1_000_000, 256, &control, |i| {
            ran.fetch_add(1, Ordering::Relaxed);
            Ok::<u64, PhysicsError>(i)
        });
        assert!(matches!(out, Err(PhysicsError::Cancelled)));
        assert_eq!(ran.load(Ordering::Relaxed), 0);
        assert_eq!(control.progress().0, 0);
    }

    #[test]
    fn no_run_starts_after_the_cancel_flag_inside_a_long_chunk() {
        // one chunk of the whole range per thread: the old per-chunk check would finish it
        for threads in [1, 2, 4] {
            let control = Control::unlimited();
            let (ran, after) = (AtomicU64::new(0), AtomicU64::new(0));
            let out = pool(threads).install(|| {
                run_in_chunks(0..100_000, 50_000, &control, |i| {
                    if control.is_cancelled() {
                        after.fetch_add(1, Ordering::Relaxed);
                    }
                    if ran.fetch_add(1, Ordering::Relaxed) == 1_000 {
                        control.cancel();
                    }
                    Ok::<u64, PhysicsError>(i)
                })
            });
            assert!(
                matches!(out, Err(PhysicsError::Cancelled)),
                "{threads} threads"
            );
            // a run that passed its check just before the flag was set may still start
            let after = after.load(Ordering::Relaxed);
            assert!(
                after < threads as u64,
                "{after} runs started after the cancel"
            );
            // the old check before each chunk finished at least one chunk of 50 000 runs
            assert!(ran.load(Ordering::Relaxed) < 50_000);
        }
    }

    #[test]
    fn a_cancelled_migration_of_a_million_runs_runs_none_of_them() {
        use crate::physics::migration::{run, run_part};
        let case = MigrationCase {
            monte_carlo: Some(MonteCarlo {
                runs: 1_000_000,
                ..MonteCarlo::default()
            }),
            ..MigrationCase::default()
        };
        let control = Control::unlimited();
        control.cancel();
        assert!(matches!(run(&case, &control), Err(PhysicsError::Cancelled)));
        assert_eq!(control.progress().0, 0);
        // the ensemble part alone (a shard's): stopped before its first run
        let out = run_part(&case, 0..1_000_000, false, &control);
        assert!(matches!(out, Err(PhysicsError::Cancelled)));
        assert_eq!(control.progress().0, 0);
    }

    /// Records read as a file is: run by run, without columns in memory.
    struct Streamed<'a>(&'a [RunSummary]);

    impl RunRecords for Streamed<'_> {
        type Error = std::convert::Infallible;
        fn runs(&self) -> u64 {
            self.0.runs()
        }
        fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), Self::Error> {
            self.0.for_each_run(f)
        }
        fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, Self::Error> {
            self.0.order_values(col, ranks)
        }
    }

    /// The statistics from the columns in memory (one pass, the second pass by four tallies,
    /// the order statistics through buckets) are those of the passes over the records, bit for
    /// bit: ensembles above and below the bucketed selection's size, with runs that stop short
    /// of the lower end (absent values), one run, and a floor where most runs stop.
    #[test]
    fn statistics_from_columns_are_those_of_the_passes_over_the_records() {
        use crate::physics::migration::{Distribution, FloorSpec, run};
        let mut cases = Vec::new();
        for (runs, end_time, mu) in [
            (20_000u64, None, 1.1),
            (20_000, Some(7.0), 0.5),
            (3_001, None, 1.5),
            (1, None, 0.3),
        ] {
            let mut c = MigrationCase {
                monte_carlo: Some(MonteCarlo {
                    runs,
                    seed: runs + 7,
                    // rocks with μ above tan 45° slow down and some stop short
                    friction_coefficient: Some(Distribution::Uniform { min: 0.1, max: mu }),
                    ..MonteCarlo::default()
                }),
                ..MigrationCase::default()
            };
            c.output.events = false;
            c.output.runs_csv = true;
            c.end_time = end_time;
            c.face.friction_coefficient = mu;
            cases.push(c);
        }
        let mut rough = cases[2].clone();
        rough.face.floor = FloorSpec::Grid {
            origin: [0.0, -5.0],
            spacing: 1.0,
            heights: (0..11)
                .map(|i| {
                    (0..90)
                        .map(|j| -(j as f64) + 0.1 * ((i * j) % 3) as f64)
                        .collect()
                })
                .collect(),
        };
        cases.push(rough);
        let mut partly_reached = 0;
        for c in &cases {
            let r = run(c, &Control::unlimited()).expect("an ensemble");
            let runs = r.runs.expect("runs_csv asks for the runs");
            let mc = c.monte_carlo.as_ref().expect("an ensemble");
            let Ok(from_columns) = statistics_of(mc, &runs[..]);
            let Ok(streamed) = statistics_of(mc, &Streamed(&runs));
            let f = from_columns.as_ref().expect("statistics").reached_fraction;
            partly_reached += usize::from(f > 0.0 && f < 1.0);
            assert_eq!(
                format!("{from_columns:?}"),
                format!("{streamed:?}"),
                "{} runs",
                runs.len()
            );
        }
        // columns with absent values (runs that stopped short) are among them
        assert!(partly_reached >= 2, "{partly_reached}");
    }

    #[test]
    fn a_timed_out_ensemble_stops_like_a_cancelled_one() {
        let past = std::time::Instant::now() - std::time::Duration::from_millis(1);
        let control = Control::with_deadline(Some(past));
        let ran = AtomicU64::new(0);
        let out = run_in_chunks(0..10_000, 256, &control, |i| {
            ran.fetch_add(1, Ordering::Relaxed);
            Ok::<u64, PhysicsError>(i)
        });
        assert!(matches!(out, Err(PhysicsError::TimedOut)));
        assert_eq!(ran.load(Ordering::Relaxed), 0);
    }

    #[test]
    fn results_come_in_run_order_and_the_first_error_in_run_order_wins() {
        let control = Control::unlimited();
        for threads in [1, 3] {
            let out = pool(threads)
                .install(|| run_in_chunks(10..1_010, 7, &control, Ok::<u64, PhysicsError>));
            assert_eq!(out.ok(), Some((10..1_010).collect::<Vec<_>>()));
            let out = pool(threads).install(|| {
                run_in_chunks(0..1_000, 7, &Control::unlimited(), |i| {
                    if i == 500 || i == 900 {
                        Err(PhysicsError::TooManySteps {
                            estimated: i as f64,
                            limit: 0.0,
                        })
                    } else {
                        Ok(i)
                    }
                })
            });
            assert!(
                matches!(out, Err(PhysicsError::TooManySteps { estimated, .. }) if estimated == 500.0)
            );
        }
        assert_eq!(
            run_in_chunks(5..5, 7, &control, Ok::<u64, PhysicsError>).ok(),
            Some(vec![])
        );
    }
}

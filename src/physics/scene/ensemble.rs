//! A scene's ensemble: the runs of an index range, their records (in memory or from the parts
//! of a sharded computation) and the statistics, outcomes and comparison built from them.

use super::*;
use crate::physics::migration::maps::{MapGrid, Maps, RunCells};

/// The method a comparison runs besides the case's own.
fn other_method(m: Method) -> Method {
    match m {
        Method::LumpedMass => Method::RigidBlock,
        Method::RigidBlock => Method::LumpedMass,
    }
}

/// The runs with global indices in `range` of the ensemble `mc` of `case`, in run order, and
/// with `compare_methods` those of the other migration method. Run i is seeded by (seed, i)
/// whatever the range, so the runs of any split of 0..runs are those of `calc::scene::Scene::solve`.
///
/// Errors: as `calc::scene::Scene::solve` (the first error in run order).
pub fn ensemble_part(
    case: &SceneCase,
    mc: &MonteCarlo,
    range: std::ops::Range<u64>,
    control: &Control,
) -> SceneResult<(Vec<SceneRun>, Option<Vec<SceneRun>>)> {
    let runs = ensemble(case, mc, range.clone(), control)?;
    let other = if case.compare_methods {
        let mut sc = case.clone();
        sc.migration.method = other_method(case.migration.method);
        sc.compare_methods = false;
        Some(ensemble(&sc, mc, range, control)?)
    } else {
        None
    };
    Ok((runs, other))
}

/// [`ensemble_part`] over all runs, with the maps of the case's own method on `grid` (the
/// cells each run's migration entered, to its stop; see [`migration::maps`]).
///
/// Errors: as `calc::scene::Scene::solve`.
pub fn ensemble_part_mapped(
    case: &SceneCase,
    mc: &MonteCarlo,
    grid: &MapGrid,
    control: &Control,
) -> SceneResult<(Vec<SceneRun>, Option<Vec<SceneRun>>, Maps)> {
    let pairs = ensemble_with(case, mc, 0..mc.runs, Some(grid), control, |r, c| {
        (r, c.unwrap_or_default())
    })?;
    let (runs, cells): (Vec<SceneRun>, Vec<RunCells>) = pairs.into_iter().unzip();
    control.check()?;
    let maps = migration::maps::build_maps(grid, &cells);
    drop(cells);
    let other = if case.compare_methods {
        let mut sc = case.clone();
        sc.migration.method = other_method(case.migration.method);
        sc.compare_methods = false;
        Some(ensemble(&sc, mc, 0..mc.runs, control)?)
    } else {
        None
    };
    Ok((runs, other, maps))
}

/// The runs of `range` of the case's own method with the cells each entered on `grid` (see
/// [`migration::maps`]), in run order: the prefixes of an ensemble with a target and maps.
///
/// Errors: as `calc::scene::Scene::solve`.
pub fn ensemble_cells(
    case: &SceneCase,
    mc: &MonteCarlo,
    range: std::ops::Range<u64>,
    grid: &MapGrid,
    control: &Control,
) -> SceneResult<(Vec<SceneRun>, Vec<RunCells>)> {
    let pairs = ensemble_with(case, mc, range, Some(grid), control, |r, c| {
        (r, c.unwrap_or_default())
    })?;
    Ok(pairs.into_iter().unzip())
}

/// Runs the runs of `range`: the migration of each run (the `/v1/migration` streams), then its
/// strike.
fn ensemble(
    case: &SceneCase,
    mc: &MonteCarlo,
    range: std::ops::Range<u64>,
    control: &Control,
) -> SceneResult<Vec<SceneRun>> {
    ensemble_with(case, mc, range, None, control, |r, _| r)
}

/// [`ensemble`], each run's record made by `wrap` from its run and, on `grid`, its cells.
fn ensemble_with<T: Send>(
    case: &SceneCase,
    mc: &MonteCarlo,
    range: std::ops::Range<u64>,
    grid: Option<&MapGrid>,
    control: &Control,
    wrap: impl Fn(SceneRun, Option<RunCells>) -> T + Sync,
) -> SceneResult<Vec<T>> {
    const CHUNK: usize = 64;
    let n = (range.end - range.start) as usize;
    let limits = case.limits.active();
    if n == 0 {
        return Ok(Vec::new());
    }
    // the floor depends on the face only, which no draw changes: built once for every run
    control.check()?;
    let floor = migration::build_floor(&case.migration)?;
    let zones = match &case.release_zones {
        Some(z) => Some(clip_zones(z, migration::release_span(&case.migration, &floor)?)?.0),
        None => None,
    };
    let one = |i: u64| -> SceneResult<T> {
        let (mut m, rock, _, mass) = run_case(case, zones.as_deref(), mc.seed, i)?;
        m.monte_carlo = None;
        let (summary, cells, crossings) =
            migration::ensemble_run(&m, &floor, mc, i, grid, control)?;
        let Some(k) = summary.support else {
            return Ok(wrap(
                SceneRun {
                    summary,
                    values: None,
                    capacity_exceeded: false,
                    exceeded: vec![false; limits.len()],
                    guard: Guard::None,
                    crossings,
                },
                cells,
            ));
        };
        let rock = impact_rock(&rock, mass);
        let (guard, _, s) = guarded_strike(case, k, &rock, mass, summary.impact_speed, control)?;
        let ch = checks(&case.limits, &s);
        Ok(wrap(
            SceneRun {
                summary,
                values: s.values(),
                capacity_exceeded: matches!(s, Strike::CapacityExceeded { .. }),
                exceeded: ch.iter().map(|c| c.exceeded).collect(),
                guard,
                crossings,
            },
            cells,
        ))
    };
    migration::run_in_chunks(range, CHUNK, control, one)
}

/// The outcomes of runs.
#[must_use]
pub fn outcomes_of(runs: &[RunSummary]) -> Outcomes {
    let n = runs.len().max(1) as f64;
    let f = |r: StopReason| runs.iter().filter(|s| s.stop_reason == r).count() as f64 / n;
    Outcomes {
        support: f(StopReason::Support),
        lower_end: f(StopReason::LowerEnd),
        barrier: f(StopReason::Barrier),
        at_rest: f(StopReason::AtRest),
        left_floor: f(StopReason::LeftFloor),
        end_time: f(StopReason::EndTime),
    }
}

/// Number of statistics columns of a support entry (see [`entry_columns`]).
pub const ENTRY_COLUMNS: usize = 5;

/// The support entry a run struck within the contact capacity and its statistics columns, in
/// the order of [`EntryStatistics`]: impact speed (m/s), δmax (m), Pmax (N), absorbed energy (J),
/// stress utilisation. None when the run reached no support or went past the capacity.
#[must_use]
pub fn entry_columns(r: &SceneRun) -> Option<(usize, [f64; ENTRY_COLUMNS])> {
    let k = r.summary.support?;
    if r.capacity_exceeded {
        return None;
    }
    let v = r.values.unwrap_or_default();
    Some((
        k,
        [
            r.summary.impact_speed,
            v.max_deformation,
            v.max_force,
            v.absorbed_energy,
            v.stress_utilisation,
        ],
    ))
}

/// A scene ensemble's run records: readable in run order as often as needed (sums are taken in
/// run order, the summation order of the contract), with the order statistics of each entry's
/// columns. Held in memory by the service; read from part files by a sharded computation's merge.
pub trait SceneRecords {
    /// Error of reading the records (none in memory).
    type Error;
    /// Number of runs.
    fn runs(&self) -> u64;
    /// Calls `f` with every run record in run order.
    fn for_each_run(&self, f: &mut dyn FnMut(&SceneRun)) -> Result<(), Self::Error>;
    /// The values at the 0-based `ranks` (ascending) of column `col` of [`entry_columns`] over
    /// the runs that struck entry `entry` within capacity, sorted by `f64::total_cmp`.
    fn order_values(
        &self,
        entry: usize,
        col: usize,
        ranks: &[u64],
    ) -> Result<Vec<f64>, Self::Error>;
    /// The values at the 0-based `ranks` (ascending) of column `col` of [`reach_columns`] over
    /// the runs that reached entry `entry`, sorted by `f64::total_cmp`.
    fn reach_order_values(
        &self,
        entry: usize,
        col: usize,
        ranks: &[u64],
    ) -> Result<Vec<f64>, Self::Error>;
}

/// The values at the 0-based ascending `ranks` of `work` sorted by `f64::total_cmp`, found by
/// [`stats::select_ranks`] over the values' order keys (the migration's selection).
fn select_ranks(work: Vec<f64>, ranks: &[u64]) -> Vec<f64> {
    let mut keys: Vec<u64> = work.into_iter().map(stats::order_key).collect();
    stats::select_ranks(&mut keys, ranks)
}

impl SceneRecords for [SceneRun] {
    type Error = std::convert::Infallible;

    fn runs(&self) -> u64 {
        self.len() as u64
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&SceneRun)) -> Result<(), Self::Error> {
        self.iter().for_each(f);
        Ok(())
    }

    fn order_values(
        &self,
        entry: usize,
        col: usize,
        ranks: &[u64],
    ) -> Result<Vec<f64>, Self::Error> {
        let mut work: Vec<f64> = self
            .iter()
            .filter_map(entry_columns)
            .filter(|(k, _)| *k == entry)
            .map(|(_, x)| x[col])
            .collect();
        // selection (O(n)) of the ranks asked for, in ascending order
        let mut start = 0;
        for &k in ranks {
            work[start..].select_nth_unstable_by(k as usize - start, f64::total_cmp);
            start = k as usize + 1;
        }
        Ok(ranks.iter().map(|&k| work[k as usize]).collect())
    }

    fn reach_order_values(
        &self,
        entry: usize,
        col: usize,
        ranks: &[u64],
    ) -> Result<Vec<f64>, Self::Error> {
        let work: Vec<f64> = self
            .iter()
            .filter_map(reach_columns)
            .filter(|(k, _)| *k == entry)
            .map(|(_, x)| x[col])
            .collect();
        Ok(select_ranks(work, ranks))
    }
}

/// What an ensemble adds to a scene's report ([`SceneReport::attach`]).
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleReport {
    /// The impact, column and checks stages of the plan.
    pub plan: Vec<Stage>,
    /// The statistics.
    pub statistics: SceneStatistics,
    /// The runs (when asked for, for the CSV).
    pub runs: Option<Vec<SceneRun>>,
    /// Both methods side by side (`compare_methods`).
    pub comparison: Option<Vec<MethodSummary>>,
    /// The ensemble's warnings.
    pub warnings: Vec<Warning>,
}

/// Counts of an ensemble besides its statistics.
struct Counts {
    /// Runs that reached a support.
    struck: u64,
    /// Runs that reached a support at t = 0.
    at_start: u64,
}

/// The ensemble's part of a scene's report from its run records (and, with `compare_methods`,
/// the other method's as `other`): statistics, warnings, the strike stages of the plan
/// (`nominal_capacity`: the nominal impact went past the capacity), the comparison and, when
/// `keep_runs`, the runs. Two passes over the records in run order and the order statistics of
/// each entry's columns: the one way ensemble statistics are made, whether the records come from
/// threads or from the parts of a sharded computation.
///
/// Errors: those of reading the records.
pub fn ensemble_report<R: SceneRecords + ?Sized>(
    case: &SceneCase,
    mc: &MonteCarlo,
    nominal_capacity: bool,
    records: &R,
    other: Option<&R>,
    keep_runs: bool,
) -> Result<EnsembleReport, R::Error> {
    let (mut statistics, counts) = statistics_of(case, mc, records)?;
    statistics.devices = devices::device_statistics(case, records)?;
    let mut warnings = draw_warnings(mc);
    for (k, e) in statistics.entries.iter().enumerate() {
        if e.impact_velocity.is_none() {
            let s = &case.supports[k];
            warnings.push(Warning {
                code: "support_never_reached",
                message: format!(
                    "support {} column {} at {} m: no run reached it within the contact \
                     capacity; its distributions are null",
                    s.support, s.column_index, s.along_dip
                ),
            });
        }
    }
    if counts.at_start > 0 {
        warnings.push(within_reach_warning(counts.at_start, records.runs()));
    }
    let through: Vec<String> = statistics
        .devices
        .iter()
        .zip(&case.device_lines)
        .filter_map(|(d, &k)| {
            let b = d.barrier?;
            let n = b.broken_through_runs;
            (n > 0).then(|| format!("{n} at {} m", case.migration.lines[k].along_dip))
        })
        .collect();
    if !through.is_empty() {
        warnings.push(Warning {
            code: "barrier_broken_through",
            message: format!(
                "rocks broke through barriers (past their energy rating, below their height): \
                 {}; each passed with the rating taken from its kinetic energy",
                through.join(", ")
            ),
        });
    }
    let mut plan = Vec::new();
    push_strike_plan(case, &mut plan, counts.struck, nominal_capacity);
    let comparison = match other {
        Some(other) => {
            let mut out = Vec::with_capacity(2);
            for method in [Method::LumpedMass, Method::RigidBlock] {
                let st = if method == case.migration.method {
                    statistics.clone()
                } else {
                    statistics_of(case, mc, other)?.0
                };
                out.push(MethodSummary {
                    method,
                    outcomes: st.outcomes,
                    entries: st
                        .entries
                        .iter()
                        .map(|e| {
                            (
                                e.reached_fraction,
                                e.impact_velocity.as_ref().map(|s| s.p50),
                                e.exceedance
                                    .iter()
                                    .map(|(l, p)| (*l, p.probability))
                                    .collect(),
                            )
                        })
                        .collect(),
                });
            }
            Some(out)
        }
        None => None,
    };
    let runs = if keep_runs {
        let mut v = Vec::with_capacity(records.runs() as usize);
        records.for_each_run(&mut |r| v.push(r.clone()))?;
        Some(v)
    } else {
        None
    };
    Ok(EnsembleReport {
        plan,
        statistics,
        runs,
        comparison,
        warnings,
    })
}

fn statistics_of<R: SceneRecords + ?Sized>(
    case: &SceneCase,
    mc: &MonteCarlo,
    records: &R,
) -> Result<(SceneStatistics, Counts), R::Error> {
    let n = records.runs();
    let e = case.supports.len();
    let limits = case.limits.active();
    // first pass: counts, and count, sum, min and max of each entry's columns, in run order
    let mut stops = [0u64; 6];
    let mut at = vec![0u64; e];
    let mut exceeded = vec![vec![0u64; limits.len()]; e];
    let mut overloaded = vec![0u64; e];
    let mut held = vec![0u64; e];
    let mut through = vec![0u64; e];
    let mut any = 0u64;
    let mut counts = Counts {
        struck: 0,
        at_start: 0,
    };
    let mut first = vec![[stats::FirstPass::default(); ENTRY_COLUMNS]; e];
    let mut reach_first = vec![[stats::FirstPass::default(); REACH_COLUMNS]; e];
    records.for_each_run(&mut |r| {
        stops[stop_index(r.summary.stop_reason)] += 1;
        if let Some(k) = r.summary.support {
            at[k] += 1;
            counts.struck += 1;
            counts.at_start += u64::from(r.summary.time == 0.0);
            for (c, &x) in exceeded[k].iter_mut().zip(&r.exceeded) {
                *c += u64::from(x);
            }
            overloaded[k] += u64::from(r.overloaded());
            held[k] += u64::from(r.guard == Guard::Held);
            through[k] += u64::from(r.guard == Guard::BrokenThrough);
        }
        any += u64::from(r.overloaded());
        if let Some((k, x)) = entry_columns(r) {
            for (p, x) in first[k].iter_mut().zip(x) {
                p.push(x);
            }
        }
        if let Some((k, x)) = reach_columns(r) {
            for (p, x) in reach_first[k].iter_mut().zip(x) {
                p.push(x);
            }
        }
    })?;
    // second pass: squared deviations from the mean and histogram counts, in run order
    let mut second: Vec<[Option<stats::SecondPass>; ENTRY_COLUMNS]> =
        first.iter().map(|f| f.map(|p| p.second_pass())).collect();
    let mut reach_second: Vec<[Option<stats::SecondPass>; REACH_COLUMNS]> = reach_first
        .iter()
        .map(|f| f.map(|p| p.second_pass()))
        .collect();
    if reach_first.iter().any(|f| f[0].count() > 0) {
        records.for_each_run(&mut |r| {
            if let Some((k, x)) = entry_columns(r) {
                for (p, x) in second[k].iter_mut().zip(x) {
                    if let Some(p) = p {
                        p.push(x);
                    }
                }
            }
            if let Some((k, x)) = reach_columns(r) {
                for (p, x) in reach_second[k].iter_mut().zip(x) {
                    if let Some(p) = p {
                        p.push(x);
                    }
                }
            }
        })?;
    }
    let frac = |k: u64| k as f64 / n.max(1) as f64;
    let mut entries = Vec::with_capacity(e);
    for k in 0..e {
        let within = first[k][0].count();
        let mut summaries = Vec::with_capacity(ENTRY_COLUMNS);
        for (col, p) in second[k].iter().enumerate() {
            summaries.push(match p {
                Some(p) => Some(p.finish(&records.order_values(
                    k,
                    col,
                    &stats::order_ranks(first[k][col].count()),
                )?)),
                None => None,
            });
        }
        let exceedance: Vec<(Limit, Probability)> = limits
            .iter()
            .zip(&exceeded[k])
            .map(|((l, _), &c)| (*l, probability(c, n)))
            .collect();
        let design_values = design_values_of(
            records,
            k,
            case.limits.design_percentile,
            &reach_first[k],
            &reach_second[k],
        )?;
        let mut s = summaries.into_iter();
        let mut next = || s.next().flatten();
        entries.push(EntryStatistics {
            reached_fraction: frac(at[k]),
            capacity_exceeded_fraction: frac(at[k] - within),
            impact_velocity: next(),
            max_deformation: next(),
            max_force: next(),
            absorbed_energy: next(),
            stress_utilisation: next(),
            design_values,
            exceeded: exceedance
                .iter()
                .any(|(_, p)| p.probability > case.limits.acceptable_probability),
            exceedance,
            overloads_per_year: case.release_rate.map(|r| frequency(overloaded[k], n, r)),
            guard: case
                .guards
                .get(k)
                .copied()
                .flatten()
                .map(|rating| GuardStatistics {
                    rating,
                    held: probability(held[k], n),
                    broken_through: probability(through[k], n),
                }),
        });
    }
    let statistics = SceneStatistics {
        runs: n,
        seed: mc.seed,
        outcomes: Outcomes {
            support: frac(stops[stop_index(StopReason::Support)]),
            lower_end: frac(stops[stop_index(StopReason::LowerEnd)]),
            at_rest: frac(stops[stop_index(StopReason::AtRest)]),
            left_floor: frac(stops[stop_index(StopReason::LeftFloor)]),
            end_time: frac(stops[stop_index(StopReason::EndTime)]),
            barrier: frac(stops[stop_index(StopReason::Barrier)]),
        },
        entries,
        any_exceeded: probability(any, n),
        any_overloads_per_year: case.release_rate.map(|r| frequency(any, n, r)),
        devices: Vec::new(),
        target: None,
    };
    Ok((statistics, counts))
}

/// The design values of entry `k` at percentile `p` from the two passes over its
/// [`reach_columns`] and their order statistics; None when no run reached the entry.
fn design_values_of<R: SceneRecords + ?Sized>(
    records: &R,
    k: usize,
    p: f64,
    first: &[stats::FirstPass; REACH_COLUMNS],
    second: &[Option<stats::SecondPass>; REACH_COLUMNS],
) -> Result<Option<DesignValues>, R::Error> {
    let n = first[0].count();
    if n == 0 {
        return Ok(None);
    }
    // every column of the entry has the same n: the ranks once
    let ranks = design_ranks(n, p);
    let mut values = Vec::with_capacity(REACH_COLUMNS);
    for (col, pass) in second.iter().enumerate() {
        let Some(pass) = pass else {
            return Ok(None);
        };
        let order = records.reach_order_values(k, col, &ranks.all)?;
        values.push(design_value(pass, n, p, &ranks, &order));
    }
    let mut v = values.into_iter();
    let (
        Some(impact_speed),
        Some(kinetic_energy),
        Some(translational_energy),
        Some(rotational_energy),
        Some(passing_height),
    ) = (v.next(), v.next(), v.next(), v.next(), v.next())
    else {
        return Ok(None);
    };
    Ok(Some(DesignValues {
        percentile: p,
        impact_speed,
        kinetic_energy,
        translational_energy,
        rotational_energy,
        passing_height,
    }))
}

fn stop_index(r: StopReason) -> usize {
    match r {
        StopReason::Support => 0,
        StopReason::LowerEnd => 1,
        StopReason::AtRest => 2,
        StopReason::LeftFloor => 3,
        StopReason::EndTime => 4,
        StopReason::Barrier => 5,
    }
}

/// Both methods on a case without an ensemble: the outcome, the support reached, its impact
/// speed and whether it exceeded each limit.
pub(super) fn compare_single(
    case: &SceneCase,
    nominal_case: &MigrationCase,
    control: &Control,
    total: u64,
) -> SceneResult<Vec<MethodSummary>> {
    let mut out = Vec::new();
    for method in [Method::LumpedMass, Method::RigidBlock] {
        let mut sc = case.clone();
        sc.migration.method = method;
        sc.compare_methods = false;
        let mut m = nominal_case.clone();
        m.method = method;
        m.output.events = false;
        m.output.trajectory = false;
        let r = migration::run(&m, control)?;
        // the run announces a total of its own (and counts itself done): restore the scene's
        control.set_total(total);
        let a = &r.arrival;
        let summary = RunSummary {
            time: a.time,
            speed: a.speed,
            kinetic_energy: a.kinetic_energy,
            impact_count: r.impact_count,
            runout: 0.0,
            max_bounce_height: r.max_bounce_height,
            stop_reason: a.stop_reason,
            steps: 0,
            along_dip_velocity: a.along_dip_velocity,
            support: a.support,
            impact_speed: a.impact_speed.unwrap_or(0.0),
            release_along_dip: m.release.along_dip,
            release_across: m.release.across,
            side_length: m.rock.side_length,
            density: m.rock.density,
            stop_along_dip: a.along_dip,
            stop_across: a.position[1],
            translational_energy: a.kinetic_energy - a.rotational_energy,
            rotational_energy: a.rotational_energy,
            // only the outcome and the impact speed of this summary are read: the centre's
            // offset stands in for the lowest point's height
            passing_height: a.normal_offset.max(0.0),
        };
        let (_, mass) = rock_extent(&m.rock)?;
        let rock = impact_rock(&m.rock, mass);
        let exceeded: Vec<(usize, Vec<(Limit, bool)>)> = match a.support {
            Some(k) => {
                let (_, _, s) = guarded_strike(&sc, k, &rock, mass, summary.impact_speed, control)?;
                vec![(
                    k,
                    checks(&sc.limits, &s)
                        .iter()
                        .map(|c| (c.limit, c.exceeded))
                        .collect(),
                )]
            }
            None => Vec::new(),
        };
        let limits = sc.limits.active();
        out.push(MethodSummary {
            method,
            outcomes: outcomes_of(&[summary]),
            entries: (0..sc.supports.len())
                .map(|k| {
                    let hit = a.support == Some(k);
                    let ex = exceeded.iter().find(|(j, _)| *j == k);
                    (
                        if hit { 1.0 } else { 0.0 },
                        hit.then_some(summary.impact_speed),
                        limits
                            .iter()
                            .map(|(l, _)| {
                                let e =
                                    ex.is_some_and(|(_, v)| v.iter().any(|(m, x)| m == l && *x));
                                (*l, if e { 1.0 } else { 0.0 })
                            })
                            .collect(),
                    )
                })
                .collect(),
        });
    }
    Ok(out)
}

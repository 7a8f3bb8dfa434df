//! Barriers and collectors of a scene (api.md `POST /v1/scene`, `barriers` and `collectors`):
//! lines across the face that the migration honours ([`migration::lines`]), and what each did
//! over an ensemble — the share of runs that reached it, for a barrier the shares it stopped,
//! that broke through and that overtopped it, and the rock's state at the line (speed, kinetic
//! energy, passing height) as design values, like a support's.

use super::collectors::{DesignValues, REACH_COLUMNS, design_ranks, design_value};
use super::{Probability, SceneCase, SceneRecords, probability};
use crate::physics::migration::{Crossing, Line, LineAction};
use crate::physics::stats;

/// The lines of a scene's migration from its barriers and collectors (each in request order),
/// sorted along the dip (barriers first at equal positions, so a collector there sees the rock
/// the barrier let through), and per device (barriers, then collectors) the index of its line.
#[must_use]
pub fn scene_lines(barriers: &[Line], collectors: &[Line]) -> (Vec<Line>, Vec<usize>) {
    let all: Vec<Line> = barriers.iter().chain(collectors).copied().collect();
    let mut order: Vec<usize> = (0..all.len()).collect();
    // stable: request order among lines at one position
    order.sort_by(|&a, &b| all[a].along_dip.total_cmp(&all[b].along_dip));
    let mut line_of = vec![0; all.len()];
    for (line, &device) in order.iter().enumerate() {
        line_of[device] = line;
    }
    (order.iter().map(|&d| all[d]).collect(), line_of)
}

/// What one barrier or collector saw over an ensemble.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceStatistics {
    /// Runs that reached the line (within its across range), over all runs.
    pub reached: Probability,
    /// A barrier's shares over all runs: stopped, broken through, overtopped (None: a
    /// collector).
    pub barrier: Option<BarrierStatistics>,
    /// The rock's state at the line over the runs that reached it (None: none did).
    pub values: Option<DesignValues>,
}

/// What a barrier did over all runs of an ensemble.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarrierStatistics {
    /// Rocks it stopped (kinetic energy within its rating, below its height).
    pub stopped: Probability,
    /// Rocks that broke through it (past its rating, below its height).
    pub broken_through: Probability,
    /// Number of runs that broke through it.
    pub broken_through_runs: u64,
    /// Rocks that passed over it (lowest point at or above its height).
    pub overtopped: Probability,
}

/// The design-value columns of a crossing, in the order of [`DesignValues`]: speed (m/s),
/// kinetic energy (J), translational and rotational kinetic energy (J), passing height (m).
#[must_use]
pub fn crossing_columns(c: &Crossing) -> [f64; REACH_COLUMNS] {
    [
        c.speed,
        c.kinetic_energy(),
        c.translational_energy,
        c.rotational_energy,
        c.passing_height,
    ]
}

/// The statistics of every device of `case` (barriers, then collectors) over `records`, at
/// the case's design percentile. Sums run in run order.
///
/// Errors: those of reading the records.
pub(super) fn device_statistics<R: SceneRecords + ?Sized>(
    case: &SceneCase,
    records: &R,
) -> Result<Vec<DeviceStatistics>, R::Error> {
    let devices = case.device_lines.len();
    if devices == 0 {
        return Ok(Vec::new());
    }
    let n = records.runs();
    let mut reached = vec![0u64; devices];
    let mut acted = vec![[0u64; 3]; devices];
    let mut columns: Vec<[Vec<f64>; REACH_COLUMNS]> = vec![Default::default(); devices];
    records.for_each_run(&mut |r| {
        for (d, &line) in case.device_lines.iter().enumerate() {
            let Some(c) = r.crossings.get(line).copied().flatten() else {
                continue;
            };
            reached[d] += 1;
            match c.action {
                LineAction::Stopped => acted[d][0] += 1,
                LineAction::BrokenThrough => acted[d][1] += 1,
                LineAction::Overtopped => acted[d][2] += 1,
                LineAction::Passed => {}
            }
            for (col, x) in columns[d].iter_mut().zip(crossing_columns(&c)) {
                col.push(x);
            }
        }
    })?;
    let p = case.limits.design_percentile;
    Ok((0..devices)
        .map(|d| {
            let is_barrier = case.migration.lines[case.device_lines[d]].barrier.is_some();
            DeviceStatistics {
                reached: probability(reached[d], n),
                barrier: is_barrier.then(|| BarrierStatistics {
                    stopped: probability(acted[d][0], n),
                    broken_through: probability(acted[d][1], n),
                    broken_through_runs: acted[d][1],
                    overtopped: probability(acted[d][2], n),
                }),
                values: values_of(&columns[d], p),
            }
        })
        .collect())
}

/// The design values of the columns (each in run order) at percentile `p` (None: empty).
fn values_of(columns: &[Vec<f64>; REACH_COLUMNS], p: f64) -> Option<DesignValues> {
    let n = columns[0].len() as u64;
    if n == 0 {
        return None;
    }
    let ranks = design_ranks(n, p);
    let mut v = columns.iter().map(|col| {
        let mut first = stats::FirstPass::default();
        col.iter().for_each(|&x| first.push(x));
        let mut second = first.second_pass()?;
        col.iter().for_each(|&x| second.push(x));
        let mut sorted = col.clone();
        sorted.sort_unstable_by(f64::total_cmp);
        let at: Vec<f64> = ranks.all.iter().map(|&k| sorted[k as usize]).collect();
        Some(design_value(&second, n, p, &ranks, &at))
    });
    Some(DesignValues {
        percentile: p,
        impact_speed: v.next()??,
        kinetic_energy: v.next()??,
        translational_energy: v.next()??,
        rotational_energy: v.next()??,
        passing_height: v.next()??,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(s: f64, barrier: bool) -> Line {
        Line {
            along_dip: s,
            across: None,
            barrier: barrier.then_some(crate::physics::migration::Barrier {
                height: 1.0,
                rating: 1.0,
            }),
        }
    }

    #[test]
    fn lines_are_sorted_along_the_dip_with_barriers_first_at_one_position() {
        let (lines, of) = scene_lines(&[at(30.0, true), at(10.0, true)], &[at(30.0, false)]);
        let s: Vec<f64> = lines.iter().map(|l| l.along_dip).collect();
        assert_eq!(s, [10.0, 30.0, 30.0]);
        assert_eq!(of, [1, 0, 2]);
        assert!(lines[1].barrier.is_some() && lines[2].barrier.is_none());
    }
}

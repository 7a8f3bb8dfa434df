//! The fewest barriers that make a face acceptable (api.md `POST /v1/scene`, `design.barriers`):
//! a greedy search over candidate positions in front of every k-th support, on the scene's own
//! seeded runs (common random numbers: every configuration is judged on the same draws).
//!
//! Each round runs the ensemble with the barriers chosen so far and a collector at every
//! candidate left; a candidate's barrier gets the design percentile of what reaches its line
//! (kinetic energy for the rating, passing height for the height, each rounded up: the rating to
//! three significant digits, the height to the next centimetre, at least 1 cm); then each
//! candidate so sized is tried alone with the chosen ones, and the one that leaves the fewest
//! supports above the acceptable probability (then the lowest summed exceedance) is kept. The
//! search stops when every support's exceedance has its Wilson 95 % upper bound at or below the
//! acceptable probability, or when no candidate is left. Greedy, so not proven the fewest: the
//! answer states it, and gives each support's residual exceedance with the barriers in place.

use super::devices::scene_lines;
use super::{Probability, SceneCase, SceneResult, ensemble_part, overloads, probability};
use crate::physics::control::Control;
use crate::physics::migration::{Barrier, Line, MonteCarlo};
use crate::physics::stats::percentile_sorted;

/// The method, in words (the answer's `design.barriers.method`).
pub const METHOD: &str = "greedy over the candidates on the ensemble's own seeded runs (common \
    random numbers): each round sizes every candidate left at the design percentile of what \
    reaches its line (kinetic energy for the rating, passing height for the height), tries each \
    with the barriers chosen so far and keeps the one that leaves the fewest supports above the \
    acceptable probability (then the least summed exceedance); it stops when every support's \
    Wilson 95 % upper bound is within it or no candidate is left. Greedy: not proven the fewest.";

/// What the search is asked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarrierSearch {
    /// Largest exceedance probability a support may have (on its Wilson upper bound).
    pub acceptable: f64,
    /// A candidate in front of every k-th support (counted from the top of the face).
    pub every: usize,
    /// How far up-slope of its support a candidate stands, m.
    pub offset: f64,
}

/// A barrier the search proposes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProposedBarrier {
    /// The support it stands in front of (number from 1).
    pub support: u32,
    /// Along-dip position, m.
    pub along_dip: f64,
    /// Height, m: the design percentile of the passing height at its line, rounded up.
    pub height: f64,
    /// Energy rating, J: the design percentile of the kinetic energy at its line, rounded up.
    pub rating: f64,
}

/// The search's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct BarrierDesign {
    /// The candidates: support number and along-dip position, m.
    pub candidates: Vec<(u32, f64)>,
    /// The barriers proposed, in the order they were chosen.
    pub barriers: Vec<ProposedBarrier>,
    /// Per support entry, its exceedance (some design limit, or the capacity) with the proposed
    /// barriers in place.
    pub residual: Vec<Probability>,
    /// Every support's upper bound is at or below the acceptable probability.
    pub acceptable: bool,
    /// Ensembles run.
    pub ensembles: u64,
}

/// The candidate positions: in front (`offset` m up-slope) of every `every`-th distinct support
/// position from the top of the face, on the face.
#[must_use]
pub fn candidates(case: &SceneCase, every: usize, offset: f64) -> Vec<(u32, f64)> {
    let mut at: Vec<(u32, f64)> = case
        .supports
        .iter()
        .map(|e| (e.support, e.along_dip))
        .collect();
    at.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    at.dedup_by(|a, b| a.1 == b.1);
    at.into_iter()
        .step_by(every.max(1))
        .map(|(s, u)| (s, (u - offset).max(0.0)))
        .collect()
}

/// Runs the search may simulate at most for `candidates` candidates of an ensemble of `runs`:
/// round r (from 0, at most one per candidate and a last) runs one ensemble with collectors and
/// one per candidate left, c − r: (c + 1)(c + 2)/2 ensembles in all.
#[must_use]
pub fn search_runs(candidates: usize, runs: u64) -> f64 {
    let c = candidates as f64;
    (c + 1.0) * (c + 2.0) / 2.0 * runs as f64
}

/// `x` rounded up to three significant digits.
fn ceil_3(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x.max(0.0);
    }
    let scale = 10f64.powf(x.log10().floor() - 2.0);
    let up = (x / scale).ceil() * scale;
    // the division can round below x: never propose less than what was measured
    if up < x { up + scale } else { up }
}

/// The scene `case` with `barriers` and `collectors` as its only devices.
fn with_lines(case: &SceneCase, barriers: &[Line], collectors: &[Line]) -> SceneCase {
    let (lines, device_lines) = scene_lines(barriers, collectors);
    let mut c = case.clone();
    c.migration.lines = lines;
    c.device_lines = device_lines;
    c.compare_methods = false;
    c
}

/// (entries above acceptable, summed exceedance) of a configuration's counts: lower is better.
fn score(counts: &[u64], n: u64, acceptable: f64) -> (usize, u64) {
    let above = counts
        .iter()
        .filter(|&&c| probability(c, n).ci95[1] > acceptable)
        .count();
    (above, counts.iter().sum())
}

/// The greedy search (see the module doc) on the ensemble `mc` of `case` (its own barriers kept
/// as they are; its collectors left out).
///
/// Errors: the scene's own.
pub fn design_barriers(
    case: &SceneCase,
    mc: &MonteCarlo,
    search: &BarrierSearch,
    control: &Control,
) -> SceneResult<BarrierDesign> {
    let n = mc.runs;
    let own: Vec<Line> = case
        .migration
        .lines
        .iter()
        .filter(|l| l.barrier.is_some())
        .copied()
        .collect();
    let cands = candidates(case, search.every, search.offset);
    let mut left: Vec<usize> = (0..cands.len())
        .filter(|&i| !own.iter().any(|l| l.along_dip == cands[i].1))
        .collect();
    let mut chosen: Vec<(usize, Line)> = Vec::new();
    let mut ensembles = 0u64;
    let p = case.limits.design_percentile;
    let lines_of = |chosen: &[(usize, Line)]| -> Vec<Line> {
        own.iter()
            .copied()
            .chain(chosen.iter().map(|c| c.1))
            .collect()
    };
    let whole = |along: f64| Line {
        along_dip: along,
        across: None,
        barrier: None,
    };
    let counts = loop {
        // the current configuration, a collector at each candidate left
        let collectors: Vec<Line> = left.iter().map(|&i| whole(cands[i].1)).collect();
        let c = with_lines(case, &lines_of(&chosen), &collectors);
        let (runs, _) = ensemble_part(&c, mc, 0..n, control)?;
        ensembles += 1;
        let counts = overloads(case, &runs);
        if score(&counts, n, search.acceptable).0 == 0 || left.is_empty() {
            break counts;
        }
        // size each candidate left from what reaches its collector
        let nb = own.len() + chosen.len();
        let mut best: Option<((usize, u64), usize, Line)> = None;
        for (j, &i) in left.iter().enumerate() {
            let line = c.device_lines[nb + j];
            let (mut ke, mut h): (Vec<f64>, Vec<f64>) = runs
                .iter()
                .filter_map(|r| r.crossings.get(line).copied().flatten())
                .map(|x| (x.kinetic_energy(), x.passing_height))
                .unzip();
            if ke.is_empty() {
                continue;
            }
            ke.sort_by(f64::total_cmp);
            h.sort_by(f64::total_cmp);
            let height = ((percentile_sorted(&h, p) * 100.0).ceil() / 100.0).max(0.01);
            let barrier = Line {
                barrier: Some(Barrier {
                    height,
                    rating: ceil_3(percentile_sorted(&ke, p)),
                }),
                ..whole(cands[i].1)
            };
            let mut trial = chosen.clone();
            trial.push((i, barrier));
            let t = with_lines(case, &lines_of(&trial), &[]);
            let (runs, _) = ensemble_part(&t, mc, 0..n, control)?;
            ensembles += 1;
            let s = score(&overloads(case, &runs), n, search.acceptable);
            if best.as_ref().is_none_or(|b| s < b.0) {
                best = Some((s, i, barrier));
            }
        }
        let Some((_, i, barrier)) = best else {
            // no run reaches any candidate left: nothing more a barrier can do
            break counts;
        };
        chosen.push((i, barrier));
        left.retain(|&x| x != i);
    };
    let residual: Vec<Probability> = counts.iter().map(|&c| probability(c, n)).collect();
    Ok(BarrierDesign {
        acceptable: residual.iter().all(|p| p.ci95[1] <= search.acceptable),
        residual,
        barriers: chosen
            .iter()
            .map(|(i, l)| {
                let b = l.barrier.unwrap_or(Barrier {
                    height: 0.0,
                    rating: 0.0,
                });
                ProposedBarrier {
                    support: cands[*i].0,
                    along_dip: l.along_dip,
                    height: b.height,
                    rating: b.rating,
                }
            })
            .collect(),
        candidates: cands,
        ensembles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratings_round_up_to_three_significant_digits() {
        assert_eq!(ceil_3(12_345.0), 12_400.0);
        assert_eq!(ceil_3(12_300.0), 12_300.0);
        assert_eq!(ceil_3(0.0), 0.0);
        for x in [1.0001, 999.1, 7.3e-3, 123_456_789.0] {
            let c = ceil_3(x);
            assert!(c >= x && c <= x * 1.01, "{x} → {c}");
        }
    }

    #[test]
    fn the_search_is_bounded_by_its_rounds() {
        // 0 candidates: one ensemble; 3: rounds of 4, 3, 2 and 1
        assert_eq!(search_runs(0, 100), 100.0);
        assert_eq!(search_runs(3, 10), 100.0);
    }
}

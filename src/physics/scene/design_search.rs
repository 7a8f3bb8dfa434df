//! The design search for guards: per guarded support entry, the smallest energy rating R of a
//! guard on its column such that, on the ensemble's own runs (common random numbers), the
//! entry's exceedance probability has a Wilson 95 % upper bound within the acceptable one.
//!
//! Exact, no search: run i reaching the entry at impact speed vᵢ with a rock of mass mᵢ needs
//! the rating rᵢ = ½mᵢ(vᵢ² − v_a,ᵢ²)⁺, where v_a,ᵢ is the largest column speed within every
//! active design limit (and the contact capacity) for that run's rock — the inverse of the chain
//! ([`allowed_impact`], the smallest over the active limits) — since a guard of rating R leaves
//! the column the speed √(v² − 2R/m) ([`behind_guard`]). The entry's exceedance count behind a
//! guard of rating R is c(R) = #{i : rᵢ > R}; with c* the largest count whose Wilson upper bound
//! over all n runs is within the acceptable probability, R is the (c* + 1)-th largest rᵢ (0 when
//! fewer runs need a guard). The inverse depends on the run only through its rock and the entry's
//! column: it is computed once per distinct (column, rock) pair.

use rayon::prelude::*;

use super::*;
use crate::physics::design::{AllowedBy, allowed_impact};

/// The method of the search, in words.
pub const METHOD: &str =
    "exact over the ensemble's runs: the rating each run needs, sorted, common random numbers";

/// Chain evaluations counted per inverse in the work estimate made before running: the scan
/// (49 points) and the regula falsi to a relative 1e-9 take 50–90 (BENCHMARKS.md), fewer than
/// 120 in every tested case.
pub const EVALUATIONS_PER_INVERSE: u64 = 120;

/// What the design search is asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignAsk {
    /// Largest exceedance probability an entry may have, judged on the upper bound of its
    /// Wilson 95 % interval, in (0, 1).
    pub acceptable_probability: f64,
    /// Per entry of [`SceneCase::supports`], whether it gets a guard.
    pub guarded: Vec<bool>,
    /// The barrier search, when asked ([`super::barrier_design`]).
    pub barriers: Option<super::barrier_design::BarrierSearch>,
}

/// The answer for one support entry.
#[derive(Debug, Clone, PartialEq)]
pub struct EntryDesign {
    /// Index into [`SceneCase::supports`].
    pub entry: usize,
    /// The entry gets a guard.
    pub guarded: bool,
    /// The smallest rating that makes the entry acceptable, J (None: not guarded); when not
    /// achievable with the ensemble's runs, the rating that holds every run (c = 0).
    pub rating: Option<f64>,
    /// Runs that reached the entry needing a guard (rᵢ > 0; for an entry not guarded, the runs
    /// that exceeded at it).
    pub needing: u64,
    /// The exceedance probability over all runs with that rating in place, with its Wilson
    /// 95 % interval.
    pub exceedance: Probability,
    /// The upper bound of the interval is within the acceptable probability.
    pub acceptable: bool,
}

/// The result of the design search.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSearch {
    /// The acceptable probability asked for.
    pub acceptable_probability: f64,
    /// Runs of the ensemble.
    pub runs: u64,
    /// Per support entry, in the order of [`SceneCase::supports`].
    pub entries: Vec<EntryDesign>,
    /// Every entry acceptable.
    pub all_acceptable: bool,
    /// Runs needed for even a count of 0 to be acceptable (None: the ensemble's runs suffice).
    pub runs_needed: Option<u64>,
    /// Inverses of the chain computed (distinct (column, rock) pairs × active limits).
    pub inverses: u64,
    /// Chain evaluations the inverses took.
    pub evaluations: u64,
}

/// The upper bound of the Wilson 95 % interval of `c` exceedances in `n` runs.
#[must_use]
pub fn upper_bound(c: u64, n: u64) -> f64 {
    probability(c, n).ci95[1]
}

/// The largest count c in [0, n] whose Wilson 95 % upper bound over `n` runs is within
/// `acceptable` (None: not even 0). The bound grows with c.
#[must_use]
pub fn largest_acceptable_count(n: u64, acceptable: f64) -> Option<u64> {
    if upper_bound(0, n) > acceptable {
        return None;
    }
    // invariant: bound(lo) ≤ acceptable, and bound(hi) > acceptable when hi ≤ n
    let (mut lo, mut hi) = (0_u64, n + 1);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if upper_bound(mid, n) <= acceptable {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// The fewest runs n whose Wilson 95 % upper bound of 0 exceedances, z²/(n + z²), is within
/// `acceptable` (in (0, 1)): ⌈z²(1 − a)/a⌉, adjusted by the interval's own rounding where n is
/// an exact double (below 2⁵³); saturating at `u64::MAX` for an acceptable probability below
/// about 2e-19.
#[must_use]
pub fn runs_needed_for_zero(acceptable: f64) -> u64 {
    const EXACT: u64 = 1 << 53;
    let z2 = Z_95 * Z_95;
    // `as` saturates: an n past u64 is u64::MAX
    let mut n = (z2 * (1.0 - acceptable) / acceptable).ceil().max(1.0) as u64;
    if n >= EXACT {
        return n;
    }
    while n > 1 && upper_bound(0, n - 1) <= acceptable {
        n -= 1;
    }
    while n < EXACT && upper_bound(0, n) > acceptable {
        n += 1;
    }
    n
}

/// The rating a rock of mass `mass` (kg) reaching a column at `v` (m/s) needs so that the column
/// is struck at no more than `allowed` (m/s): ½m(v² − allowed²)⁺, raised by the few ulps that
/// make [`behind_guard`]'s own arithmetic leave at most `allowed`, J.
#[must_use]
pub fn needed_rating(v: f64, allowed: f64, mass: f64) -> f64 {
    if v.is_nan() || v < NO_IMPACT_SPEED || v <= allowed {
        return 0.0;
    }
    let leaves = |r: f64| {
        let left = v * v - 2.0 * r / mass;
        left <= 0.0 || left.sqrt() <= allowed
    };
    let mut r = 0.5 * mass * (v * v - allowed * allowed);
    // an ulp of v² in rating: the difference can round to 0 when v is just above `allowed`
    let mut step = r.max(0.5 * mass * v * v) * f64::EPSILON;
    for _ in 0..200 {
        if leaves(r) {
            break;
        }
        r += step;
        step *= 2.0;
    }
    r
}

/// The largest column speed within every active limit of `case` for `rock` (a cube, of mass
/// `mass`) on entry `k`'s column, m/s (infinite without an active limit), and the evaluations.
fn allowed_speed(
    case: &SceneCase,
    k: usize,
    rock: &Rock,
    mass: f64,
    control: &Control,
) -> SceneResult<(f64, u64)> {
    let mut speed = f64::INFINITY;
    let mut evaluations = 0;
    for l in case.limits.active() {
        let a = allowed_impact(case, k, rock, mass, l, control)?;
        evaluations += u64::from(a.evaluations);
        speed = speed.min(match a.by {
            AllowedBy::Nothing => 0.0,
            _ => a.speed,
        });
    }
    Ok((speed, evaluations))
}

/// The rock of a run (its drawn side length and density, as the run drew them) and its mass.
fn run_rock(case: &SceneCase, run: &SceneRun) -> Result<(Rock, f64), PhysicsError> {
    let mut rock = case.migration.rock.clone();
    if case.draws.side_length.is_some() {
        scale_rock(&mut rock, run.summary.side_length);
    }
    if case.draws.density.is_some() {
        rock.density = run.summary.density;
    }
    let (_, mass) = rock_extent(&rock)?;
    Ok((impact_rock(&rock, mass), mass))
}

/// Upper bound of the chain evaluations of a design search over `runs` runs, made before
/// running: inverses (per active limit, one per distinct guarded column, or one per run when
/// the rock is drawn — a run reaches one entry) × [`EVALUATIONS_PER_INVERSE`].
#[must_use]
pub fn estimated_evaluations(case: &SceneCase, guarded: &[bool], runs: u64) -> u64 {
    let mut columns: Vec<&Column> = Vec::new();
    for (e, _) in case.supports.iter().zip(guarded).filter(|(_, g)| **g) {
        if !columns.contains(&&e.column) {
            columns.push(&e.column);
        }
    }
    let columns = columns.len() as u64;
    let pairs = if case.draws.side_length.is_some() || case.draws.density.is_some() {
        runs.min(columns.saturating_mul(runs))
    } else {
        columns
    };
    pairs
        .saturating_mul(case.limits.active().len() as u64)
        .saturating_mul(EVALUATIONS_PER_INVERSE)
}

/// The design search over the ensemble's `runs` of `case` (see the module).
///
/// Errors: the chain's ([`allowed_impact`]: a column shorter than the contact length, the
/// column stage's step limit, cancel or time limit), tagged with the entry.
pub fn design_search(
    case: &SceneCase,
    ask: &DesignAsk,
    runs: &[SceneRun],
    control: &Control,
) -> SceneResult<DesignSearch> {
    let n = runs.len() as u64;
    let e = case.supports.len();
    let guarded = |k: usize| ask.guarded.get(k).copied().unwrap_or(false);
    // the distinct columns of the guarded entries, each with its first entry
    let mut columns: Vec<usize> = Vec::new();
    let column_of: Vec<Option<usize>> = (0..e)
        .map(|k| {
            guarded(k).then(|| {
                let c = &case.supports[k].column;
                match columns.iter().position(|&j| case.supports[j].column == *c) {
                    Some(i) => i,
                    None => {
                        columns.push(k);
                        columns.len() - 1
                    }
                }
            })
        })
        .collect();
    // the distinct (column, rock) pairs of the runs that reached a guarded entry
    let mut keys: Vec<(usize, u64, u64)> = Vec::new();
    let mut index: std::collections::HashMap<(usize, u64, u64), usize> = Default::default();
    let mut rocks: Vec<(Rock, f64)> = Vec::new();
    let mut run_key: Vec<Option<usize>> = Vec::with_capacity(runs.len());
    for r in runs {
        let key = r
            .summary
            .support
            .and_then(|k| column_of.get(k).copied().flatten())
            .map(|c| {
                (
                    c,
                    r.summary.side_length.to_bits(),
                    r.summary.density.to_bits(),
                )
            });
        run_key.push(match key {
            None => None,
            Some(key) => Some(match index.get(&key) {
                Some(&i) => i,
                None => {
                    index.insert(key, keys.len());
                    keys.push(key);
                    rocks.push(run_rock(case, r)?);
                    keys.len() - 1
                }
            }),
        });
    }
    control.check()?;
    // one inverse per pair and active limit, in parallel (each is deterministic)
    let allowed: Vec<(f64, u64)> = keys
        .par_iter()
        .zip(&rocks)
        .map(|(&(c, _, _), (rock, mass))| {
            control.check()?;
            allowed_speed(case, columns[c], rock, *mass, control)
        })
        .collect::<SceneResult<_>>()?;
    // per guarded entry, the rating each run reaching it needs (> 0 only)
    let mut needs: Vec<Vec<f64>> = vec![Vec::new(); e];
    let mut exceeded = vec![0_u64; e];
    for (r, key) in runs.iter().zip(&run_key) {
        let Some(k) = r.summary.support else {
            continue;
        };
        match key {
            Some(i) => {
                let rating = needed_rating(r.summary.impact_speed, allowed[*i].0, rocks[*i].1);
                if rating > 0.0 {
                    needs[k].push(rating);
                }
            }
            None => exceeded[k] += u64::from(r.overloaded()),
        }
    }
    let c_star = largest_acceptable_count(n, ask.acceptable_probability);
    let entries: Vec<EntryDesign> = (0..e)
        .map(|k| {
            let (rating, count, needing) = if guarded(k) {
                let mut r = std::mem::take(&mut needs[k]);
                r.sort_unstable_by(|a, b| b.total_cmp(a));
                let rating = match c_star {
                    Some(c) => r.get(c as usize).copied().unwrap_or(0.0),
                    None => r.first().copied().unwrap_or(0.0),
                };
                let count = r.iter().filter(|&&x| x > rating).count() as u64;
                (Some(rating), count, r.len() as u64)
            } else {
                (None, exceeded[k], exceeded[k])
            };
            let exceedance = probability(count, n);
            EntryDesign {
                entry: k,
                guarded: guarded(k),
                rating,
                needing,
                acceptable: exceedance.ci95[1] <= ask.acceptable_probability,
                exceedance,
            }
        })
        .collect();
    let limits = case.limits.active().len() as u64;
    Ok(DesignSearch {
        acceptable_probability: ask.acceptable_probability,
        runs: n,
        all_acceptable: entries.iter().all(|x| x.acceptable),
        entries,
        runs_needed: c_star
            .is_none()
            .then(|| runs_needed_for_zero(ask.acceptable_probability)),
        inverses: keys.len() as u64 * limits,
        evaluations: allowed.iter().map(|a| a.1).sum(),
    })
}

/// The plan's stage of a design search.
#[must_use]
pub fn design_stage(d: &DesignSearch) -> Stage {
    let guarded = d.entries.iter().filter(|x| x.guarded).count();
    Stage::ran(
        "design",
        format!(
            "{METHOD}: {guarded} guarded support column(s) over {} runs, {} inverse(s) of the \
             chain ({} evaluations); each entry judged on the Wilson 95 % upper bound against \
             {}{}",
            d.runs,
            d.inverses,
            d.evaluations,
            d.acceptable_probability,
            match d.runs_needed {
                Some(m) => format!("; not achievable with {} runs: {m} needed", d.runs),
                None => String::new(),
            }
        ),
    )
}

/// The warning naming the support columns whose exceedance stays above the acceptable
/// probability (None: every one is acceptable): columns not guarded, or every column when the
/// ensemble has too few runs.
#[must_use]
pub fn residual_risk_warning(case: &SceneCase, d: &DesignSearch) -> Option<Warning> {
    const NAMED: usize = 20;
    let above: Vec<&EntryDesign> = d.entries.iter().filter(|x| !x.acceptable).collect();
    if above.is_empty() {
        return None;
    }
    let mut names: Vec<String> = above
        .iter()
        .take(NAMED)
        .map(|x| {
            let e = &case.supports[x.entry];
            format!(
                "support {} column {} ({}, upper bound {:.4})",
                e.support,
                e.column_index,
                if x.guarded { "guarded" } else { "not guarded" },
                x.exceedance.ci95[1]
            )
        })
        .collect();
    if above.len() > NAMED {
        names.push(format!("and {} more", above.len() - NAMED));
    }
    Some(Warning {
        code: "design_residual_risk",
        message: format!(
            "{} support column(s) stay above the acceptable probability {}{}: {}",
            above.len(),
            d.acceptable_probability,
            match d.runs_needed {
                Some(m) => format!(" (the ensemble's {} runs are too few: {m} needed)", d.runs),
                None => String::new(),
            },
            names.join(", ")
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count limit against the Wilson interval itself: within at c*, above at c* + 1.
    #[test]
    fn largest_acceptable_count_is_where_the_bound_crosses() {
        for (n, a) in [
            (300, 0.05),
            (1000, 0.01),
            (5000, 0.001),
            (50, 0.5),
            (7, 0.9),
        ] {
            let c = largest_acceptable_count(n, a).unwrap();
            assert!(upper_bound(c, n) <= a, "{n} {a}");
            assert!(c == n || upper_bound(c + 1, n) > a, "{n} {a}");
        }
        assert_eq!(largest_acceptable_count(20, 0.01), None);
    }

    /// Wilson's upper bound of 0 of n is z²/(n + z²): the runs needed solve it.
    #[test]
    fn runs_needed_is_the_first_n_with_a_bound_of_zero_within() {
        assert_eq!(runs_needed_for_zero(5e-324), u64::MAX);
        assert_eq!(runs_needed_for_zero(1e-300), u64::MAX);
        for a in [0.5, 0.1, 0.05, 0.01, 1e-3, 1e-5, 1e-12, 0.123_456] {
            let n = runs_needed_for_zero(a);
            let z2 = Z_95 * Z_95;
            assert!(upper_bound(0, n) <= a && (n == 1 || upper_bound(0, n - 1) > a));
            assert!((z2 / (n as f64 + z2) - upper_bound(0, n)).abs() < 1e-15);
            assert_eq!(n, (z2 * (1.0 - a) / a).ceil() as u64, "{a}");
        }
    }

    /// The rating leaves the column exactly the allowed speed or less, by behind_guard's own
    /// arithmetic, and is within a relative 1e-12 of ½m(v² − v_a²).
    #[test]
    fn needed_rating_leaves_at_most_the_allowed_speed() {
        let case = SceneCase {
            guards: vec![Some(0.0)],
            ..SceneCase::new(
                MigrationCase::default(),
                vec![SupportEntry {
                    support: 1,
                    column_index: 0,
                    along_dip: 30.0,
                    across: None,
                    column: Column::default(),
                }],
                ColumnCase::default(),
            )
        };
        for (v, a, m) in [
            (10.0, 3.0, 40.5),
            (1000.0, 1e-3, 1.0),
            (3.0, 2.999_999_999, 7.0),
            (5.0, 0.0, 2.0),
            (3.0, 3.0_f64.next_down(), 1.0),
            (3.0_f64.next_up(), 3.0, 0.7),
        ] {
            let r = needed_rating(v, a, m);
            let exact = 0.5 * m * (v * v - a * a);
            assert!(
                (r - exact).abs() <= 1e-12 * exact + 1e-300,
                "{v} {a} {m}: {r}"
            );
            let c = SceneCase {
                guards: vec![Some(r)],
                ..case.clone()
            };
            let (_, left) = behind_guard(&c, 0, m, v);
            assert!(left <= a, "{v} {a} {m}: {left}");
        }
        assert_eq!(needed_rating(2.0, 3.0, 1.0), 0.0);
        assert_eq!(needed_rating(1e-7, 0.0, 1.0), 0.0);
    }
}

//! What a support's column can take: the inverse of the chain. For a support entry, the case's
//! rock and one design limit, the impact speed at which the check reaches exactly its limit —
//! the largest speed the column takes without exceeding it — and the kinetic energy at that
//! speed.
//!
//! The check's value (stress utilisation, contact force or absorbed energy) grows with the impact
//! speed, and past the contact law's capacity every check counts as exceeded, so "exceeded at v"
//! is monotone in v. The allowed speed is found in two steps: a geometric scan of the speed range
//! brackets the first speed that exceeds, then a safeguarded regula falsi (Illinois) on the
//! check's margin — bisection where a side is past the capacity — narrows the bracket to
//! [`RELATIVE_TOLERANCE`]. The answer is the bracket's lower end: the forward chain at that speed
//! does not exceed the limit, and at the upper end (at most a relative 1e-9 faster) it does.

use super::control::Control;
use super::error::PhysicsError;
use super::material::Rock;
use super::scene::{
    self, DesignLimits, Limit, MAX_IMPACT_SPEED, NO_IMPACT_SPEED, SceneCase, SceneResult, Strike,
};

/// Relative width to which the allowed speed is bracketed.
pub const RELATIVE_TOLERANCE: f64 = 1e-9;
/// Points of the geometric scan from [`NO_IMPACT_SPEED`] to [`MAX_IMPACT_SPEED`] that brackets
/// the first exceeding speed (ratio (1e9)^(1/48) ≈ 1.54 between neighbours).
const SCAN_POINTS: usize = 49;

/// What ends the allowed speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AllowedBy {
    /// The check reaches its limit at the speed.
    Limit,
    /// The contact law's capacity is passed just above the speed, before the check's limit.
    Capacity,
    /// The check stays within its limit over the whole speed range `/v1/impact` takes.
    SpeedRange,
    /// Even the slowest impact exceeds the limit: nothing is allowed.
    Nothing,
}

/// The allowed impact of one support entry for one design limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllowedImpact {
    /// The design limit.
    pub limit: Limit,
    /// The allowed value of the check (in the limit's unit).
    pub allowed: f64,
    /// Largest impact speed that does not exceed the limit, m/s (0 with [`AllowedBy::Nothing`]).
    pub speed: f64,
    /// Translational kinetic energy of the case's rock at that speed, J.
    pub energy: f64,
    /// The check's value at that speed (None: none, with [`AllowedBy::Nothing`]).
    pub value: Option<f64>,
    /// What ends the allowed speed.
    pub by: AllowedBy,
    /// Forward chain evaluations used.
    pub evaluations: u32,
}

/// The check's value at `speed` for `limit`, or None past the capacity.
fn value_at(
    case: &SceneCase,
    entry: usize,
    rock: &Rock,
    limit: Limit,
    speed: f64,
    control: &Control,
) -> SceneResult<Option<f64>> {
    let strike = scene::strike(case, entry, rock, speed, control)?;
    Ok(match strike {
        Strike::CapacityExceeded { .. } => None,
        s => s.values().map(|v| match limit {
            Limit::StressUtilisation => v.stress_utilisation,
            Limit::MaxForce => v.max_force,
            Limit::AbsorbedEnergy => v.absorbed_energy,
        }),
    })
}

/// The allowed impact of support `entry` for `limit` at `allowed`, for `rock` (already the cube
/// the impact takes, [`scene::impact_rock`]) of mass `mass` (kg).
///
/// Errors are the chain's own (a column shorter than the contact length, the column stage's
/// step limit, cancel or time limit), tagged with the entry.
pub fn allowed_impact(
    case: &SceneCase,
    entry: usize,
    rock: &Rock,
    mass: f64,
    (limit, allowed): (Limit, f64),
    control: &Control,
) -> SceneResult<AllowedImpact> {
    let mut evaluations = 0_u32;
    let mut eval = |v: f64| -> SceneResult<Option<f64>> {
        evaluations += 1;
        value_at(case, entry, rock, limit, v, control)
    };
    let exceeds = |x: Option<f64>| x.is_none_or(|x| x > allowed);
    let ratio = (MAX_IMPACT_SPEED / NO_IMPACT_SPEED).powf(1.0 / (SCAN_POINTS - 1) as f64);
    // scan: (lo, f(lo)) within the limit, (hi, f(hi)) exceeding it
    let mut lo: Option<(f64, f64)> = None;
    let mut hi: Option<(f64, Option<f64>)> = None;
    for k in 0..SCAN_POINTS {
        let v = if k + 1 == SCAN_POINTS {
            MAX_IMPACT_SPEED
        } else {
            NO_IMPACT_SPEED * ratio.powi(k as i32)
        };
        let x = eval(v)?;
        if exceeds(x) {
            hi = Some((v, x));
            break;
        }
        lo = x.map(|x| (v, x));
    }
    let energy = |v: f64| 0.5 * mass * v * v;
    let Some((mut b, mut fb)) = hi else {
        let (v, x) = lo.unwrap_or((MAX_IMPACT_SPEED, f64::NAN));
        return Ok(AllowedImpact {
            limit,
            allowed,
            speed: v,
            energy: energy(v),
            value: Some(x),
            by: AllowedBy::SpeedRange,
            evaluations,
        });
    };
    let Some((mut a, mut fa)) = lo else {
        return Ok(AllowedImpact {
            limit,
            allowed,
            speed: 0.0,
            energy: 0.0,
            value: None,
            by: AllowedBy::Nothing,
            evaluations,
        });
    };
    // Illinois on g = value − allowed (g(a) ≤ 0 < g(b)); bisection while b is past the capacity
    let mut side = 0_i8;
    let mut step = 0_u32;
    while b - a > RELATIVE_TOLERANCE * b {
        step += 1;
        let m = match fb {
            // every fourth step bisects, so the bracket halves at least that often
            Some(xb) if !step.is_multiple_of(4) => {
                let (ga, gb) = (fa - allowed, xb - allowed);
                let m = a - ga * (b - a) / (gb - ga);
                // keep the new point strictly inside, away from the ends by a little
                let guard = 0.5 * RELATIVE_TOLERANCE * b;
                if m.is_finite() {
                    m.clamp(a + guard, b - guard)
                } else {
                    0.5 * (a + b)
                }
            }
            _ => 0.5 * (a + b),
        };
        let x = eval(m)?;
        if exceeds(x) {
            (b, fb) = (m, x);
            if side == 1 {
                // Illinois: halve the stale end's margin so the bracket closes from both sides
                fa = allowed + 0.5 * (fa - allowed);
            }
            side = 1;
        } else if let Some(x) = x {
            (a, fa) = (m, x);
            if side == -1
                && let Some(xb) = fb
            {
                fb = Some(allowed + 0.5 * (xb - allowed));
            }
            side = -1;
        }
    }
    // the margin may have been scaled by the Illinois step: evaluate the answer itself
    let value = eval(a)?;
    let by = if fb.is_none() {
        AllowedBy::Capacity
    } else {
        AllowedBy::Limit
    };
    Ok(AllowedImpact {
        limit,
        allowed,
        speed: a,
        energy: energy(a),
        value,
        by,
        evaluations,
    })
}

/// The allowed impacts of support `entry` for every active design limit of `limits`, in
/// api.md order.
pub fn allowed_impacts(
    case: &SceneCase,
    entry: usize,
    rock: &Rock,
    mass: f64,
    limits: &DesignLimits,
    control: &Control,
) -> SceneResult<Vec<AllowedImpact>> {
    limits
        .active()
        .into_iter()
        .map(|l| allowed_impact(case, entry, rock, mass, l, control))
        .collect()
}

/// The allowed impacts of one support entry, and (for an ensemble) the margin of its design
/// impact speed against each.
#[derive(Debug, Clone, PartialEq)]
pub struct EntryAllowed {
    /// Per active design limit, in api.md order.
    pub limits: Vec<AllowedImpact>,
    /// The design impact speed of the runs that reached the entry (its design value at the
    /// design percentile), m/s (None: no ensemble, or no run reached it).
    pub design_speed: Option<f64>,
    /// The entry's guard (None: no guard).
    pub guard: Option<GuardAllowance>,
}

/// A guard in front of an entry's column, for the allowed speed behind it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuardAllowance {
    /// Energy rating, J.
    pub rating: f64,
    /// Mass of the case's rock, kg.
    pub mass: f64,
}

impl EntryAllowed {
    /// Per limit, the fastest approach of the case's rock the column takes behind the entry's
    /// guard, m/s: the guard takes R of ½mv², so √(v_a² + 2R/m) (None: no guard).
    #[must_use]
    pub fn behind_guard(&self) -> Vec<Option<f64>> {
        self.limits
            .iter()
            .map(|a| {
                self.guard
                    .map(|g| (a.speed * a.speed + 2.0 * g.rating / g.mass).sqrt())
            })
            .collect()
    }

    /// Design impact speed ÷ allowed speed per limit — behind the guard where there is one
    /// (≤ 1: within; None without a design speed, or where nothing is allowed).
    #[must_use]
    pub fn utilisation(&self) -> Vec<Option<f64>> {
        self.limits
            .iter()
            .zip(self.behind_guard())
            .map(|(a, g)| {
                let allowed = g.unwrap_or(a.speed);
                self.design_speed
                    .filter(|_| allowed > 0.0)
                    .map(|v| v / allowed)
            })
            .collect()
    }
}

/// Per entry of `case`, its guard for [`EntryAllowed::guard`] (None: no guard).
///
/// Errors: the rock's (its extent).
pub fn guard_allowances(case: &SceneCase) -> Result<Vec<Option<GuardAllowance>>, PhysicsError> {
    let (_, mass) = scene::rock_extent(&case.migration.rock)?;
    Ok((0..case.supports.len())
        .map(|k| {
            case.guards
                .get(k)
                .copied()
                .flatten()
                .map(|rating| GuardAllowance { rating, mass })
        })
        .collect())
}

/// The allowed impacts of every support entry of `case` for its active design limits, for the
/// case's nominal rock (as the impact takes it). Entries whose columns are equal share one
/// computation (the chain depends on the entry only through its column).
///
/// Errors: the chain's, tagged with the first entry of the column concerned.
pub fn allowed_for_entries(case: &SceneCase, control: &Control) -> SceneResult<Vec<EntryAllowed>> {
    let (_, mass) = scene::rock_extent(&case.migration.rock)?;
    let rock = scene::impact_rock(&case.migration.rock, mass);
    let mut out: Vec<EntryAllowed> = Vec::with_capacity(case.supports.len());
    // the distinct columns met so far, with the first entry of each: O(entries × distinct)
    let mut seen: Vec<usize> = Vec::new();
    for (k, e) in case.supports.iter().enumerate() {
        control.check()?;
        let same = seen
            .iter()
            .copied()
            .find(|&j| case.supports[j].column == e.column);
        let limits = match same {
            Some(j) => out[j].limits.clone(),
            None => {
                seen.push(k);
                allowed_impacts(case, k, &rock, mass, &case.limits, control)?
            }
        };
        out.push(EntryAllowed {
            limits,
            design_speed: None,
            guard: None,
        });
    }
    for (a, g) in out.iter_mut().zip(guard_allowances(case)?) {
        a.guard = g;
    }
    Ok(out)
}

/// The distinct columns among the support entries of `case` (the columns
/// [`allowed_for_entries`] computes).
#[must_use]
pub fn distinct_columns(case: &SceneCase) -> usize {
    let mut seen: Vec<&super::material::Column> = Vec::new();
    for e in &case.supports {
        if !seen.contains(&&e.column) {
            seen.push(&e.column);
        }
    }
    seen.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::column::{ColumnCase, ColumnModel};
    use crate::physics::material::{Column, ContactLaw};
    use crate::physics::migration::MigrationCase;
    use crate::physics::scene::{SupportEntry, rock_extent};

    fn case(model: ColumnModel, law: ContactLaw) -> SceneCase {
        let mut column = ColumnCase {
            model,
            modes: Some(if model == ColumnModel::Coupled { 3 } else { 1 }),
            ..ColumnCase::default()
        };
        column.impact.contact.law = law;
        SceneCase::new(
            MigrationCase::default(),
            vec![SupportEntry {
                support: 1,
                column_index: 0,
                along_dip: 30.0,
                across: None,
                column: Column::default(),
            }],
            column,
        )
    }

    fn rock_of(case: &SceneCase) -> (Rock, f64) {
        let rock = &case.migration.rock;
        let (_, mass) = rock_extent(rock).unwrap();
        (scene::impact_rock(rock, mass), mass)
    }

    /// The forward chain at the allowed speed is within the limit, and a relative 2e-9 faster
    /// it exceeds it; where the limit (not the capacity) ends it, the value equals the limit.
    fn check_against_forward_chain(case: &SceneCase, limit: (Limit, f64), value_tol: f64) {
        let (rock, mass) = rock_of(case);
        let control = Control::default();
        let a = allowed_impact(case, 0, &rock, mass, limit, &control).unwrap();
        assert_eq!(a.by, AllowedBy::Limit, "{a:?}");
        let at = value_at(case, 0, &rock, limit.0, a.speed, &control).unwrap();
        let above = value_at(case, 0, &rock, limit.0, a.speed * (1.0 + 2e-9), &control).unwrap();
        assert!(at.is_some_and(|x| x <= limit.1), "{a:?}: at {at:?}");
        assert!(above.is_none_or(|x| x > limit.1), "{a:?}: above {above:?}");
        let x = at.unwrap();
        assert!((x / limit.1 - 1.0).abs() < value_tol, "{a:?}: {x}");
        assert!((a.energy - 0.5 * mass * a.speed * a.speed).abs() <= 1e-12 * a.energy);
        assert!(a.evaluations < 120, "{a:?}");
    }

    #[test]
    fn decoupled_allowed_speeds_are_where_the_forward_chain_reaches_the_limit() {
        for law in [
            ContactLaw::HertzPoint,
            ContactLaw::Johnson,
            ContactLaw::Paper,
        ] {
            let c = case(ColumnModel::Decoupled, law);
            check_against_forward_chain(&c, (Limit::StressUtilisation, 1.0), 1e-7);
            check_against_forward_chain(&c, (Limit::MaxForce, 2.0e5), 1e-7);
            check_against_forward_chain(&c, (Limit::AbsorbedEnergy, 50.0), 1e-7);
        }
    }

    #[test]
    fn coupled_allowed_speed_is_where_the_forward_chain_reaches_the_limit() {
        let c = case(ColumnModel::Coupled, ContactLaw::HertzPoint);
        check_against_forward_chain(&c, (Limit::StressUtilisation, 1.0), 1e-5);
    }

    /// Hertz point contact (decoupled): Pmax ∝ v^(6/5), so the speed at which the force reaches
    /// P* is v₁·(P*/P(v₁))^(5/6) from any one forward evaluation — an independent inverse.
    #[test]
    fn hertz_force_limit_matches_the_six_fifths_power_law() {
        let c = case(ColumnModel::Decoupled, ContactLaw::HertzPoint);
        let (rock, mass) = rock_of(&c);
        let control = Control::default();
        let v1 = 3.0;
        let p1 = value_at(&c, 0, &rock, Limit::MaxForce, v1, &control)
            .unwrap()
            .unwrap();
        for p_star in [1e3, 5e4, 3e5] {
            let a =
                allowed_impact(&c, 0, &rock, mass, (Limit::MaxForce, p_star), &control).unwrap();
            let expected = v1 * (p_star / p1).powf(5.0 / 6.0);
            assert!(
                (a.speed / expected - 1.0).abs() < 1e-8,
                "P* {p_star}: {} vs {expected}",
                a.speed
            );
        }
    }

    #[test]
    fn limits_out_of_reach_and_below_every_impact() {
        let c = case(ColumnModel::Decoupled, ContactLaw::HertzPoint);
        let (rock, mass) = rock_of(&c);
        let control = Control::default();
        let a = allowed_impact(&c, 0, &rock, mass, (Limit::MaxForce, 1e300), &control).unwrap();
        assert_eq!((a.by, a.speed), (AllowedBy::SpeedRange, MAX_IMPACT_SPEED));
        let a = allowed_impact(&c, 0, &rock, mass, (Limit::MaxForce, 1e-300), &control).unwrap();
        assert_eq!((a.by, a.speed, a.energy), (AllowedBy::Nothing, 0.0, 0.0));
    }

    /// With a limit the column never reaches, the paper's log law's capacity ends the
    /// allowed speed (a small, soft rock: the law's G reaches 1 below the speed range): just
    /// above it the chain reports the capacity exceeded, at the capacity speed the impact
    /// module reports itself.
    #[test]
    fn the_contact_capacity_ends_the_allowed_speed() {
        let mut c = case(ColumnModel::Decoupled, ContactLaw::Paper);
        c.migration.rock.side_length = 0.05;
        c.migration.rock.elastic_modulus = 5e8;
        let (rock, mass) = rock_of(&c);
        let control = Control::default();
        let a = allowed_impact(&c, 0, &rock, mass, (Limit::MaxForce, 1e300), &control).unwrap();
        assert_eq!(a.by, AllowedBy::Capacity, "{a:?}");
        let Strike::CapacityExceeded {
            max_velocity: Some(v_cap),
        } = scene::strike(&c, 0, &rock, MAX_IMPACT_SPEED, &control).unwrap()
        else {
            panic!("no capacity at the top of the range")
        };
        assert!(
            (a.speed / v_cap - 1.0).abs() < 2e-9,
            "{} vs {v_cap}",
            a.speed
        );
        let above = scene::strike(&c, 0, &rock, a.speed * (1.0 + 2e-9), &control).unwrap();
        assert!(
            matches!(above, Strike::CapacityExceeded { .. }),
            "{above:?}"
        );
        let at = scene::strike(&c, 0, &rock, a.speed, &control).unwrap();
        assert!(matches!(at, Strike::Solved { .. }), "{at:?}");
    }
}

//! What protection must take, in a scene's answer: each support's allowed impact per design
//! limit and the margin of the ensemble's design impact speed against it; and from probability
//! to frequency: the release rate and the overloads per year.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::common::{Bound, Checker, FieldDefault, NumberField, number_schemas};
use crate::physics::design::{AllowedBy, AllowedImpact, EntryAllowed};
use crate::physics::scene::{GuardStatistics, Limit, SceneCase};
use crate::physics::stats::rate::{Frequency, ReleaseRate};

/// The name of a design limit on the wire.
#[must_use]
pub fn limit_name(l: Limit) -> &'static str {
    match l {
        Limit::StressUtilisation => "stress_utilisation",
        Limit::MaxForce => "max_force_n",
        Limit::AbsorbedEnergy => "absorbed_energy_j",
    }
}

/// The allowed impact of a support for one design limit: the largest impact speed of the case's
/// rock at which the check does not exceed its limit (to a relative 1e-9).
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct AllowedLimitDto {
    /// `stress_utilisation`, `max_force_n` or `absorbed_energy_j`.
    pub limit: String,
    /// The limit's allowed value (its unit: 1, N or J).
    pub allowed: f64,
    /// Largest impact speed that does not exceed the limit, m/s (0 when `ended_by` is
    /// `nothing`).
    pub impact_velocity_m_s: f64,
    /// Translational kinetic energy of the case's rock at that speed, J.
    pub kinetic_energy_j: f64,
    /// The check's value at that speed (omitted when `ended_by` is `nothing`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// What ends the allowed speed: `limit` (the check reaches its limit), `capacity` (the
    /// contact law's capacity is passed first), `speed_range` (within the limit up to 1000 m/s,
    /// the fastest impact computed) or `nothing` (even 1e-6 m/s exceeds it).
    pub ended_by: String,
    /// The fastest approach of the case's rock the column takes behind the support's guard, m/s:
    /// the guard takes its rating R of ½mv², so √(v² + 2R/m) with v the allowed speed above
    /// (omitted without a guard).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub behind_guard_impact_velocity_m_s: Option<f64>,
    /// The design impact speed ÷ the allowed speed (behind the guard where there is one; ≤ 1: the
    /// design impact is within the limit; omitted without a design speed or when nothing is
    /// allowed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub design_utilisation: Option<f64>,
}

/// One support entry's allowed impacts.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct AllowedImpactsDto {
    /// Support number (from 1).
    pub support: u32,
    /// Column of that support (from 0).
    pub column_index: u32,
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Across position of the column, m (null: the support spans the face).
    pub across_m: Option<f64>,
    /// The design impact speed: the support's design value of the impact speed
    /// (`statistics.supports[].design_values.impact_speed_m_s.design_value`, at
    /// `design_percentile` over every run that reached it), m/s (omitted without an ensemble, or
    /// when no run reached it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub design_impact_velocity_m_s: Option<f64>,
    /// Per checked design limit, in the order of `design_limits`.
    pub limits: Vec<AllowedLimitDto>,
}

/// The allowed impacts of every support entry of `case`.
#[must_use]
pub fn allowed_dto(case: &SceneCase, allowed: &[EntryAllowed]) -> Vec<AllowedImpactsDto> {
    allowed
        .iter()
        .zip(&case.supports)
        .map(|(a, e)| AllowedImpactsDto {
            support: e.support,
            column_index: e.column_index,
            along_dip_m: e.along_dip,
            across_m: e.across,
            design_impact_velocity_m_s: a.design_speed,
            limits: a
                .limits
                .iter()
                .zip(a.utilisation())
                .zip(a.behind_guard())
                .map(|((l, u), g)| AllowedLimitDto {
                    limit: limit_name(l.limit).into(),
                    allowed: l.allowed,
                    impact_velocity_m_s: l.speed,
                    kinetic_energy_j: l.energy,
                    value: l.value,
                    ended_by: by_name(l.by).into(),
                    behind_guard_impact_velocity_m_s: g,
                    design_utilisation: u,
                })
                .collect(),
        })
        .collect()
}

/// One limit's allowed impact as a sharded computation's part 0 stores it: limit, allowed
/// value, speed (m/s), energy (J), the check's value, what ends it.
pub type StoredLimit = (String, f64, f64, f64, Option<f64>, String);

/// The allowed impacts as part 0 stores them (design speeds are the merge's).
#[must_use]
pub fn store(allowed: &[EntryAllowed]) -> Vec<Vec<StoredLimit>> {
    allowed
        .iter()
        .map(|a| {
            a.limits
                .iter()
                .map(|l| {
                    (
                        limit_name(l.limit).to_string(),
                        l.allowed,
                        l.speed,
                        l.energy,
                        l.value,
                        by_name(l.by).to_string(),
                    )
                })
                .collect()
        })
        .collect()
}

/// The allowed impacts from part 0's record ([`store`]); errors name what does not parse.
pub fn restore(stored: &[Vec<StoredLimit>]) -> Result<Vec<EntryAllowed>, String> {
    stored
        .iter()
        .map(|limits| {
            let limits = limits
                .iter()
                .map(|(limit, allowed, speed, energy, value, by)| {
                    Ok(AllowedImpact {
                        limit: [
                            Limit::StressUtilisation,
                            Limit::MaxForce,
                            Limit::AbsorbedEnergy,
                        ]
                        .into_iter()
                        .find(|l| limit_name(*l) == limit)
                        .ok_or_else(|| format!("unknown design limit {limit:?}"))?,
                        allowed: *allowed,
                        speed: *speed,
                        energy: *energy,
                        value: *value,
                        by: [
                            AllowedBy::Limit,
                            AllowedBy::Capacity,
                            AllowedBy::SpeedRange,
                            AllowedBy::Nothing,
                        ]
                        .into_iter()
                        .find(|b| by_name(*b) == by)
                        .ok_or_else(|| format!("unknown end of an allowed speed {by:?}"))?,
                        evaluations: 0,
                    })
                })
                .collect::<Result<Vec<_>, String>>()?;
            Ok(EntryAllowed {
                limits,
                design_speed: None,
                guard: None,
            })
        })
        .collect()
}

/// The wire name of what ends an allowed speed.
fn by_name(by: AllowedBy) -> &'static str {
    match by {
        AllowedBy::Limit => "limit",
        AllowedBy::Capacity => "capacity",
        AllowedBy::SpeedRange => "speed_range",
        AllowedBy::Nothing => "nothing",
    }
}

/// `release_rate.rocks_per_year`.
pub const ROCKS_PER_YEAR: NumberField = NumberField {
    description: "Rocks released per year on the face, 1/year, in [1e-6, 1e9] (null: give \
                  observed_events and observed_period_years instead).",
    default: FieldDefault::Null,
    lo: Bound::Closed(1e-6),
    hi: Bound::Closed(1e9),
    unit: "1/year",
    example: 850.0,
    nullable: true,
};

/// `release_rate.observed_period_years`.
pub const OBSERVED_PERIOD: NumberField = NumberField {
    description: "Period over which observed_events were counted, years, in [0.001, 1000] (the \
                  paper's Table 1: 643 spalling events in 9 months, 0.75; a shorter count than \
                  about nine hours says nothing of a yearly rate).",
    default: FieldDefault::Null,
    lo: Bound::Closed(1e-3),
    hi: Bound::Closed(1000.0),
    unit: "years",
    example: 0.75,
    nullable: true,
};

/// Most events `release_rate.observed_events` takes.
pub const MAX_OBSERVED_EVENTS: u64 = 1_000_000_000;

number_schemas! {
    rocks_per_year_schema => ROCKS_PER_YEAR;
    observed_period_schema => OBSERVED_PERIOD;
}

/// How many rocks are released on the face: a rate, a rate per release zone, or events counted
/// over a period. Give `rocks_per_year`, or `rocks_per_year_by_zone`, or `observed_events` with
/// `observed_period_years` (the rate is then estimated from the count, and its own uncertainty
/// widens the intervals).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ReleaseRateDto {
    /// Rocks released per year, 1/year.
    #[schema(schema_with = rocks_per_year_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rocks_per_year: Option<f64>,
    /// Rocks released per year in each release zone, 1/year, each in [0, 1e9] and their sum in
    /// [1e-6, 1e9], one per zone of `release_zones` (needed): the ensemble draws the zones in
    /// proportion to these rates (they replace the zones' weights), so each support's overloads
    /// per year are Σ rate × probability over the zones.
    #[schema(default = json!(null), example = json!([150.0, 375.0, 118.0]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rocks_per_year_by_zone: Option<Vec<f64>>,
    /// Release events counted (e.g. the Spalling tab's spalling count), in [0, 1e9].
    #[schema(default = json!(null), minimum = 0, maximum = 1_000_000_000, example = 643)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observed_events: Option<u64>,
    /// Period of the count, years.
    #[schema(schema_with = observed_period_schema)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observed_period_years: Option<f64>,
}

impl ReleaseRateDto {
    /// The release rate, its fields checked against their ranges and against each other
    /// (`base`: the object's JSON Pointer).
    pub fn resolve(&self, base: &str, ck: &mut Checker) -> Option<ReleaseRate> {
        if let Some(rates) = &self.rocks_per_year_by_zone {
            if self.rocks_per_year.is_some()
                || self.observed_events.is_some()
                || self.observed_period_years.is_some()
            {
                ck.push(
                    base,
                    serde_json::to_value(self).unwrap_or(Value::Null),
                    "give rocks_per_year, rocks_per_year_by_zone, or observed_events with \
                     observed_period_years (one form only)",
                );
                return None;
            }
            let mut ok = true;
            for (i, &r) in rates.iter().enumerate() {
                ok &= ck.closed(
                    &format!("{base}/rocks_per_year_by_zone/{i}"),
                    r,
                    0.0,
                    1e9,
                    "1/year",
                );
            }
            let total: f64 = rates.iter().sum();
            if ok {
                ok = ROCKS_PER_YEAR.check(ck, &format!("{base}/rocks_per_year_by_zone"), total);
            }
            return ok.then_some(ReleaseRate::PerYear(total));
        }
        match (
            self.rocks_per_year,
            self.observed_events,
            self.observed_period_years,
        ) {
            (Some(r), None, None) => ROCKS_PER_YEAR
                .check(ck, &format!("{base}/rocks_per_year"), r)
                .then_some(ReleaseRate::PerYear(r)),
            (None, Some(events), Some(years)) => {
                let ok =
                    ck.count(
                        &format!("{base}/observed_events"),
                        events,
                        0,
                        MAX_OBSERVED_EVENTS,
                        "events",
                    ) & OBSERVED_PERIOD.check(ck, &format!("{base}/observed_period_years"), years);
                ok.then_some(ReleaseRate::Observed { events, years })
            }
            _ => {
                ck.push(
                    base,
                    serde_json::to_value(self).unwrap_or(Value::Null),
                    "give rocks_per_year, or observed_events with observed_period_years (one \
                     form only)",
                );
                None
            }
        }
    }
}

/// Expected overloads per year, with a 95 % interval and the return period.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct FrequencyDto {
    /// Expected overloads per year: the release rate × the probability per released rock,
    /// 1/year.
    pub per_year: f64,
    /// Its interval, 1/year: the Wilson 95 % interval of the probability times a given rate;
    /// with an observed count, the exact Poisson (Garwood) 97.5 % interval of the rate times the
    /// Wilson 97.5 % interval of the probability (at least 95 % jointly).
    pub ci95_per_year: [f64; 2],
    /// Mean time between overloads, years (null: none expected).
    pub return_period_years: Option<f64>,
    /// Its interval, years: [1 / upper, 1 / lower] (null: unbounded).
    pub return_period_ci95_years: [Option<f64>; 2],
}

impl From<&Frequency> for FrequencyDto {
    fn from(f: &Frequency) -> Self {
        Self {
            per_year: f.per_year,
            ci95_per_year: f.ci95,
            return_period_years: f.return_period,
            return_period_ci95_years: f.return_period_ci95,
        }
    }
}

/// Largest guard energy rating, J.
pub const MAX_GUARD_RATING: f64 = 1e12;

/// A guard on a support's column: it takes up to its energy rating of a striking rock's impact
/// energy ½mv² (v the speed towards the column); the column takes the impact at the speed left,
/// and a rock within the rating never loads it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct GuardDto {
    /// Support number (from 1).
    #[schema(minimum = 1, example = 1)]
    pub support: u32,
    /// Column of that support (from 0; null: every column of the support).
    #[schema(default = json!(null), example = json!(null))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub column_index: Option<u32>,
    /// Energy rating, J, in [0, 1e12] (0: the guard takes nothing).
    #[schema(minimum = 0.0, maximum = 1e12, example = 500.0)]
    pub energy_rating_j: f64,
}

/// The guards of a scene as one rating per support entry (None: no guard), checked: each names
/// an existing support (and column), its rating in [0, 1e12] J, and no entry guarded twice.
pub fn resolve_guards(
    guards: &[GuardDto],
    entries: &[crate::physics::scene::SupportEntry],
    ck: &mut Checker,
) -> Vec<Option<f64>> {
    let mut out: Vec<Option<f64>> = vec![None; entries.len()];
    let mut by: Vec<Option<usize>> = vec![None; entries.len()];
    let last = entries.iter().map(|e| e.support).max().unwrap_or(0);
    if guards.len() > entries.len() {
        ck.push(
            "/guards",
            json!(guards.len()),
            format!(
                "at most one guard per support column: {} guards for {} columns",
                guards.len(),
                entries.len()
            ),
        );
        return out;
    }
    // the entries of each support number, found once
    let mut of: std::collections::HashMap<u32, Vec<usize>> = std::collections::HashMap::new();
    for (k, e) in entries.iter().enumerate() {
        of.entry(e.support).or_default().push(k);
    }
    for (i, g) in guards.iter().enumerate() {
        let at = format!("/guards/{i}");
        let rating_ok = ck.closed(
            &format!("{at}/energy_rating_j"),
            g.energy_rating_j,
            0.0,
            MAX_GUARD_RATING,
            "J",
        );
        let hit: Vec<usize> = of
            .get(&g.support)
            .map(|ks| {
                ks.iter()
                    .copied()
                    .filter(|&k| g.column_index.is_none_or(|c| c == entries[k].column_index))
                    .collect()
            })
            .unwrap_or_default();
        if hit.is_empty() {
            let (field, value, message) = if of.contains_key(&g.support) {
                (
                    format!("{at}/column_index"),
                    json!(g.column_index),
                    format!("support {} has no column with this index", g.support),
                )
            } else {
                (
                    format!("{at}/support"),
                    json!(g.support),
                    format!("no such support: the supports are numbered 1 to {last}"),
                )
            };
            ck.push(field, value, message);
            continue;
        }
        for k in hit {
            if let Some(j) = by[k] {
                ck.push(
                    at.clone(),
                    serde_json::to_value(g).unwrap_or(Value::Null),
                    format!(
                        "support {} column {} is already guarded by /guards/{j}",
                        entries[k].support, entries[k].column_index
                    ),
                );
                break;
            }
            by[k] = Some(i);
            if rating_ok {
                out[k] = Some(g.energy_rating_j);
            }
        }
    }
    out
}

/// What a support's guard did over all runs of the ensemble.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct GuardStatisticsDto {
    /// The guard's energy rating, J.
    pub energy_rating_j: f64,
    /// Share of all runs whose rock the guard held (impact energy within the rating), with its
    /// Wilson 95 % interval.
    pub held: super::scene::ProbabilityDto,
    /// Share of all runs whose rock broke through the guard (the column struck at the speed left).
    pub broken_through: super::scene::ProbabilityDto,
}

impl From<&GuardStatistics> for GuardStatisticsDto {
    fn from(g: &GuardStatistics) -> Self {
        Self {
            energy_rating_j: g.rating,
            held: (&g.held).into(),
            broken_through: (&g.broken_through).into(),
        }
    }
}

//! `POST /v1/spalling`: zone counts or an event log in, Table 1 statistics out.

use serde::{Deserialize, Serialize};
use serde_json::json;
use utoipa::ToSchema;

use super::common::{Checker, Meta, PlanStep, Warning, non_null};
use crate::calc::Report;
use crate::calc::spalling::Case as SpallingCase;
use crate::http::error::{ApiError, num};
use crate::physics::spalling::{
    CountError, Event, EventError, SpallingResult, ZoneCounts, ZoneRange, ZoneStatistics,
    check_counts, count_events,
};

/// Largest count of one event in one zone.
const MAX_COUNT: f64 = 1e12;
/// Most zones in one request.
const MAX_ZONES: usize = 1000;

/// Event counts of one face zone (counts may be fractional, as Table 1 prints them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ZoneCountsDto {
    /// Zone name, e.g. `lower`.
    #[schema(example = "lower")]
    pub name: String,
    /// |A|: spalling events, in [0, 1e12].
    #[schema(minimum = 0.0, maximum = 1e12, example = 118)]
    pub spalling: f64,
    /// |B|: high-resistance events, in [0, 1e12].
    #[schema(minimum = 0.0, maximum = 1e12, example = 8)]
    pub high_resistance: f64,
    /// |C|: low-resistance events, in [0, 1e12].
    #[schema(minimum = 0.0, maximum = 1e12, example = 22)]
    pub low_resistance: f64,
    /// |A∩B|, in [0, min(|A|, |B|)].
    #[schema(minimum = 0.0, example = 5)]
    pub spalling_and_high: f64,
    /// |A∩C|, in [0, min(|A|, |C|)].
    #[schema(minimum = 0.0, example = 4.5)]
    pub spalling_and_low: f64,
}

/// One observation in an event log.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SpallingEventDto {
    /// Support number (must fall in one of `zone_supports`).
    #[schema(example = 12)]
    pub support: i64,
    /// Spalling observed at the support (event A).
    #[schema(example = true)]
    pub spalling: bool,
    /// Support resistance, N, in [0, 1e12].
    #[schema(minimum = 0.0, maximum = 1e12, example = 6.2e6)]
    pub resistance_n: f64,
}

/// A zone of the face as an inclusive range of support numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct ZoneSupportsDto {
    /// Zone name.
    #[schema(example = "lower")]
    pub name: String,
    /// First support of the zone.
    #[schema(example = 1)]
    pub first: i64,
    /// Last support of the zone (≥ first).
    #[schema(example = 21)]
    pub last: i64,
}

/// Zone counts (default: the paper's Table 1) or an event log with zones and thresholds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SpallingRequest {
    /// Counts per zone, 1–1000 zones (default: Table 1, unless `events` is given).
    #[schema(example = json!([{"name": "lower", "spalling": 118, "high_resistance": 8, "low_resistance": 22, "spalling_and_high": 5, "spalling_and_low": 4.5}]))]
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    pub zones: Option<Vec<ZoneCountsDto>>,
    /// Event log (instead of `zones`).
    #[schema(example = json!([{"support": 12, "spalling": true, "resistance_n": 6.2e6}]))]
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    pub events: Option<Vec<SpallingEventDto>>,
    #[schema(example = json!([{"name": "lower", "first": 1, "last": 21}, {"name": "middle", "first": 22, "last": 42}, {"name": "upper", "first": 43, "last": 62}]))]
    /// Zones of the event log as support ranges (default: the paper's lower 1–21, middle 22–42, upper 43–62).
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    pub zone_supports: Option<Vec<ZoneSupportsDto>>,
    /// Event B: resistance above this, N, in (0, 1e12] (default 6e6, event log only).
    #[schema(exclusive_minimum = 0.0, maximum = 1e12, example = 6.0e6)]
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    pub high_resistance_n: Option<f64>,
    /// Event C: resistance below this, N, in (0, high_resistance_n] (default 1e6, event log only).
    #[schema(exclusive_minimum = 0.0, maximum = 1e12, example = 1.0e6)]
    #[serde(skip_serializing_if = "Option::is_none", deserialize_with = "non_null")]
    pub low_resistance_n: Option<f64>,
}

/// The paper's Table 1 as zone counts (the default `zones`).
#[must_use]
pub fn table1_zones() -> Vec<ZoneCountsDto> {
    ["lower", "middle", "upper"]
        .iter()
        .zip(ZoneCounts::table1())
        .map(|(n, c)| ZoneCountsDto {
            name: (*n).to_string(),
            spalling: c.spalling,
            high_resistance: c.high,
            low_resistance: c.low,
            spalling_and_high: c.spalling_and_high,
            spalling_and_low: c.spalling_and_low,
        })
        .collect()
}

fn paper_zone_supports() -> Vec<ZoneSupportsDto> {
    [("lower", 1, 21), ("middle", 22, 42), ("upper", 43, 62)]
        .iter()
        .map(|&(n, first, last)| ZoneSupportsDto {
            name: n.to_string(),
            first,
            last,
        })
        .collect()
}

impl ZoneCountsDto {
    fn counts(&self) -> ZoneCounts {
        ZoneCounts {
            spalling: self.spalling,
            high: self.high_resistance,
            low: self.low_resistance,
            spalling_and_high: self.spalling_and_high,
            spalling_and_low: self.spalling_and_low,
        }
    }
}

impl SpallingRequest {
    /// Range and consistency checks; fills the defaults so that `self` echoes as `inputs`.
    pub fn resolve(&mut self) -> Result<SpallingCase, ApiError> {
        let mut ck = Checker::new();
        if let Some(events) = &self.events {
            if self.zones.is_some() {
                return Err(ApiError::invalid(
                    "/zones",
                    json!("…"),
                    "give either zones (counts) or events (a log), not both",
                ));
            }
            let zones = self.zone_supports.get_or_insert_with(paper_zone_supports);
            let high = *self.high_resistance_n.get_or_insert(6e6);
            let low = *self.low_resistance_n.get_or_insert(1e6);
            if zones.is_empty() || zones.len() > MAX_ZONES {
                ck.push(
                    "/zone_supports",
                    json!(zones.len()),
                    format!("must list 1 to {MAX_ZONES} zones"),
                );
            }
            for (i, z) in zones.iter().enumerate() {
                if z.last < z.first {
                    ck.push(
                        format!("/zone_supports/{i}/last"),
                        json!(z.last),
                        format!("must be at least first = {}", z.first),
                    );
                }
            }
            ck.open_closed("/high_resistance_n", high, 0.0, MAX_COUNT, "N");
            if ck.open_closed("/low_resistance_n", low, 0.0, MAX_COUNT, "N") && low > high {
                ck.push(
                    "/low_resistance_n",
                    num(low),
                    format!("must not exceed high_resistance_n = {high} N (B and C would overlap)"),
                );
            }
            for (i, e) in events.iter().enumerate() {
                ck.closed(
                    &format!("/events/{i}/resistance_n"),
                    e.resistance_n,
                    0.0,
                    MAX_COUNT,
                    "N",
                );
            }
            ck.finish()?;
            let ranges: Vec<ZoneRange> = zones
                .iter()
                .map(|z| ZoneRange {
                    first: z.first,
                    last: z.last,
                })
                .collect();
            let evs: Vec<Event> = events
                .iter()
                .map(|e| Event {
                    support: e.support,
                    spalling: e.spalling,
                    resistance: e.resistance_n,
                })
                .collect();
            let counts = count_events(&evs, &ranges, high, low).map_err(|e| match e {
                EventError::OutsideZones(i) => ApiError::invalid(
                    format!("/events/{i}/support"),
                    json!(events[i].support),
                    "is in no zone of zone_supports",
                ),
                EventError::Overlap(i) => ApiError::invalid(
                    format!("/zone_supports/{i}"),
                    json!(zones[i]),
                    "overlaps an earlier zone",
                ),
            })?;
            return Ok(SpallingCase {
                names: zones.iter().map(|z| z.name.clone()).collect(),
                counts,
                from_events: true,
            });
        }
        for (f, present) in [
            ("/zone_supports", self.zone_supports.is_some()),
            ("/high_resistance_n", self.high_resistance_n.is_some()),
            ("/low_resistance_n", self.low_resistance_n.is_some()),
        ] {
            if present {
                ck.push(f, json!("…"), "applies to an event log (events) only");
            }
        }
        let zones = self.zones.get_or_insert_with(table1_zones);
        if zones.is_empty() || zones.len() > MAX_ZONES {
            ck.push(
                "/zones",
                json!(zones.len()),
                format!("must list 1 to {MAX_ZONES} zones"),
            );
        }
        for (i, z) in zones.iter().enumerate() {
            for (name, v) in [
                ("spalling", z.spalling),
                ("high_resistance", z.high_resistance),
                ("low_resistance", z.low_resistance),
                ("spalling_and_high", z.spalling_and_high),
                ("spalling_and_low", z.spalling_and_low),
            ] {
                ck.closed(&format!("/zones/{i}/{name}"), v, 0.0, MAX_COUNT, "");
            }
        }
        ck.finish()?;
        let mut ck = Checker::new();
        let counts: Vec<ZoneCounts> = zones.iter().map(ZoneCountsDto::counts).collect();
        for e in check_counts(&counts) {
            match e {
                CountError::NotCount(i, name) => ck.push(
                    format!("/zones/{i}/{name}"),
                    json!(null),
                    "must be a count ≥ 0",
                ),
                CountError::SpallingAndHigh(i) => {
                    let z = &zones[i];
                    ck.push(
                        format!("/zones/{i}/spalling_and_high"),
                        num(z.spalling_and_high),
                        format!(
                            "A∩B cannot exceed min(A, B) = min({}, {})",
                            z.spalling, z.high_resistance
                        ),
                    );
                }
                CountError::SpallingAndLow(i) => {
                    let z = &zones[i];
                    ck.push(
                        format!("/zones/{i}/spalling_and_low"),
                        num(z.spalling_and_low),
                        format!(
                            "A∩C cannot exceed min(A, C) = min({}, {})",
                            z.spalling, z.low_resistance
                        ),
                    );
                }
            }
        }
        ck.finish()?;
        Ok(SpallingCase {
            names: zones.iter().map(|z| z.name.clone()).collect(),
            counts,
            from_events: false,
        })
    }
}

/// Statistics of one zone (or of the total); percentages in %, `null` when the denominator is 0.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct ZoneStatisticsDto {
    /// Zone name (`total` for the sum).
    pub name: String,
    /// |A|.
    pub spalling: f64,
    /// |B|.
    pub high_resistance: f64,
    /// |C|.
    pub low_resistance: f64,
    /// |A∩B|.
    pub spalling_and_high: f64,
    /// |A∩C|.
    pub spalling_and_low: f64,
    /// The zone's share of all A, %.
    pub spalling_share_pct: Option<f64>,
    /// The zone's share of all B, %.
    pub high_share_pct: Option<f64>,
    /// The zone's share of all C, %.
    pub low_share_pct: Option<f64>,
    /// P₁ = P(A|B) = |A∩B|/|B|, %.
    pub spalling_given_high_pct: Option<f64>,
    /// P₂ = P(A|C) = |A∩C|/|C|, %.
    pub spalling_given_low_pct: Option<f64>,
    /// P(B|A) = |A∩B|/|A|, %.
    pub high_given_spalling_pct: Option<f64>,
    /// P(C|A) = |A∩C|/|A|, %.
    pub low_given_spalling_pct: Option<f64>,
    /// Wilson 95 % interval of P₁, % [low, high].
    pub spalling_given_high_ci95_pct: Option<[f64; 2]>,
    /// Wilson 95 % interval of P₂, % [low, high].
    pub spalling_given_low_ci95_pct: Option<[f64; 2]>,
}

impl ZoneStatisticsDto {
    fn new(name: String, s: &ZoneStatistics) -> Self {
        Self {
            name,
            spalling: s.counts.spalling,
            high_resistance: s.counts.high,
            low_resistance: s.counts.low,
            spalling_and_high: s.counts.spalling_and_high,
            spalling_and_low: s.counts.spalling_and_low,
            spalling_share_pct: s.spalling_share,
            high_share_pct: s.high_share,
            low_share_pct: s.low_share,
            spalling_given_high_pct: s.spalling_given_high,
            spalling_given_low_pct: s.spalling_given_low,
            high_given_spalling_pct: s.high_given_spalling,
            low_given_spalling_pct: s.low_given_spalling,
            spalling_given_high_ci95_pct: s.spalling_given_high_ci95,
            spalling_given_low_ci95_pct: s.spalling_given_low_ci95,
        }
    }
}

/// Table 1 statistics by zone, in request order, and their total.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct SpallingResponse {
    /// One entry per zone, in request order.
    pub zones: Vec<ZoneStatisticsDto>,
    /// The zones summed (shares 100 %).
    pub total: ZoneStatisticsDto,
    /// Named warnings (e.g. `zero_denominator`).
    pub warnings: Vec<Warning>,
    /// Stages run or skipped.
    pub plan: Vec<PlanStep>,
    /// The fully resolved request.
    pub inputs: SpallingRequest,
    /// Version of the service and its models.
    pub model_version: String,
}

impl SpallingResponse {
    /// Builds the response from the calculation's report, the case's zone names and the
    /// resolved request.
    #[must_use]
    pub fn new(
        report: Report<SpallingResult>,
        case: &SpallingCase,
        inputs: SpallingRequest,
    ) -> Self {
        let Report {
            result: r,
            plan,
            warnings,
        } = report;
        let meta = Meta::of(&plan, &warnings);
        Self {
            zones: r
                .zones
                .iter()
                .zip(&case.names)
                .map(|(s, n)| ZoneStatisticsDto::new(n.clone(), s))
                .collect(),
            total: ZoneStatisticsDto::new("total".into(), &r.total),
            warnings: meta.warnings,
            plan: meta.plan,
            inputs,
            model_version: meta.model_version,
        }
    }
}

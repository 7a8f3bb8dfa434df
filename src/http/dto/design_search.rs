//! A scene's `design`: the smallest guard ratings that make a face acceptable — the request's
//! field, its checks and work limit, and the answer.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::common::Checker;
use super::scene::{ProbabilityDto, SceneRequest};
use crate::config::Config;
use crate::http::error::ApiError;
use crate::physics::scene::barrier_design::{self, BarrierDesign, BarrierSearch};
use crate::physics::scene::design_search::{self, DesignAsk, DesignSearch};
use crate::physics::scene::{SceneCase, SupportEntry};

/// The supports that get a guard.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, ToSchema, Default)]
#[serde(deny_unknown_fields, default)]
pub struct DesignGuardsDto {
    /// Support numbers (from 1) that get a guard on every column, at most as many as the face
    /// has support columns (null: every support).
    #[schema(default = json!(null), example = json!([1, 2]))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub supports: Option<Vec<u32>>,
}

/// The design search for guards: for each guarded support column, the smallest energy rating
/// whose exceedance probability over the ensemble's own runs has a Wilson 95 % upper bound within
/// `acceptable_probability` (needs `monte_carlo`, not with `impact_velocity_m_s`). A support
/// column exceeds when its strike passes some checked limit or the contact capacity; on a column
/// the search guards, a guard of `guards` is replaced by the search's (the statistics keep it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignSearchDto {
    /// Largest exceedance probability a support column may have, judged on the upper bound of
    /// its Wilson 95 % interval (as `statistics.supports[].exceedance` reports it), in (0, 1).
    #[schema(exclusive_minimum = 0.0, exclusive_maximum = 1.0, example = 0.01)]
    pub acceptable_probability: f64,
    /// The supports that get a guard (null: every support, unless `barriers` is given).
    #[schema(default = json!(null), example = json!({"supports": [1, 2]}))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guards: Option<DesignGuardsDto>,
    /// Search for the fewest barriers across the face, in front of every k-th support (null:
    /// no barrier search).
    #[schema(default = json!(null), example = json!({"every_kth_support": 10}))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub barriers: Option<DesignBarriersDto>,
}

/// Where barriers may stand: candidates in front of every k-th support.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct DesignBarriersDto {
    /// A candidate in front of every k-th distinct support position from the top of the face
    /// (1: every support), in [1, 1000].
    #[schema(minimum = 1, maximum = 1000, example = 10)]
    pub every_kth_support: u32,
    /// How far up-slope of its support a candidate stands, m, in [0, 10] (default 1).
    #[schema(default = 1.0, minimum = 0.0, maximum = 10.0, example = 1.0)]
    #[serde(default = "default_offset")]
    pub offset_m: f64,
}

fn default_offset() -> f64 {
    1.0
}

/// The design search of `req` over the support `entries`, checked (`/design`): an ensemble
/// without `impact_velocity_m_s`, the acceptable probability in (0, 1), each listed support
/// existing; the echoed request lists the guarded supports. None when not asked for.
pub fn resolve(
    req: &mut SceneRequest,
    entries: &[SupportEntry],
    ck: &mut Checker,
) -> Option<DesignAsk> {
    let no_ensemble = req.monte_carlo.is_none() || req.impact_velocity_m_s.is_some();
    let d = req.design.as_mut()?;
    if no_ensemble {
        ck.push(
            "/design",
            serde_json::to_value(&*d).unwrap_or(Value::Null),
            "the design search runs over an ensemble's runs: it needs monte_carlo, without \
             impact_velocity_m_s",
        );
    }
    let a = d.acceptable_probability;
    let ok = ck.range(
        "/design/acceptable_probability",
        a,
        super::common::Bound::Open(0.0),
        super::common::Bound::Open(1.0),
        "",
    );
    let last = entries.iter().map(|e| e.support).max().unwrap_or(0);
    let barriers = d.barriers.map(|b| {
        let ok = ck.count(
            "/design/barriers/every_kth_support",
            u64::from(b.every_kth_support),
            1,
            1000,
            "",
        ) & ck.closed("/design/barriers/offset_m", b.offset_m, 0.0, 10.0, "m");
        (
            ok,
            BarrierSearch {
                acceptable: a,
                every: b.every_kth_support as usize,
                offset: b.offset_m,
            },
        )
    });
    // with a barrier search and no guards listed, no guard is searched for
    let no_guards = barriers.is_some() && d.guards.is_none();
    let listed = d.guards.get_or_insert_with(Default::default);
    let supports = listed.supports.get_or_insert_with(|| {
        if no_guards {
            return Vec::new();
        }
        let mut all: Vec<u32> = entries.iter().map(|e| e.support).collect();
        all.dedup();
        all
    });
    if supports.len() > entries.len() {
        ck.push(
            "/design/guards/supports",
            json!(supports.len()),
            format!(
                "lists {} supports, more than the {} support columns of the face",
                supports.len(),
                entries.len()
            ),
        );
        return None;
    }
    // sets: a list and a face of thousands each stay O(n log n)
    let existing: std::collections::BTreeSet<u32> = entries.iter().map(|e| e.support).collect();
    for (i, s) in supports.iter().enumerate() {
        if !existing.contains(s) {
            ck.push(
                format!("/design/guards/supports/{i}"),
                json!(s),
                format!("no such support: the supports are numbered 1 to {last}"),
            );
        }
    }
    let listed: std::collections::BTreeSet<u32> = supports.iter().copied().collect();
    let guarded = entries
        .iter()
        .map(|e| listed.contains(&e.support))
        .collect();
    let barriers_ok = barriers.is_none_or(|b| b.0);
    (ok && barriers_ok && !no_ensemble).then_some(DesignAsk {
        acceptable_probability: a,
        guarded,
        barriers: barriers.map(|b| b.1),
    })
}

/// Refuses (422 naming `/design`) a design search whose work, estimated before running
/// ([`design_search::estimated_evaluations`]), passes `max_design_evaluations`; and (naming
/// `/design/barriers`) a barrier search whose runs, (c + 1)(c + 2)/2 ensembles for c candidates
/// ([`barrier_design::search_runs`]), pass `max_runs`.
pub fn check_work(case: &SceneCase, config: &Config) -> Result<(), ApiError> {
    let (Some(ask), Some(mc)) = (&case.design, &case.migration.monte_carlo) else {
        return Ok(());
    };
    if let Some(b) = &ask.barriers {
        let c = barrier_design::candidates(case, b.every, b.offset).len();
        let runs = barrier_design::search_runs(c, mc.runs);
        if runs > config.max_runs as f64 {
            let mut ck = Checker::new();
            ck.push(
                "/design/barriers",
                json!(runs),
                format!(
                    "the barrier search would run up to {runs} runs ({c} candidates: up to \
                     (c + 1)(c + 2)/2 ensembles of {} runs), more than the limit {} (max_runs): \
                     take every k-th support with a larger k, or fewer runs",
                    mc.runs, config.max_runs
                ),
            );
            return ck.finish();
        }
    }
    let work = design_search::estimated_evaluations(case, &ask.guarded, mc.runs);
    if work <= config.max_design_evaluations {
        return Ok(());
    }
    let mut ck = Checker::new();
    ck.push(
        "/design",
        json!(work),
        format!(
            "the design search would take up to {work} chain evaluations ({} per inverse; one \
             inverse per active limit and distinct guarded column, or per run when the rock's \
             size or density is drawn), more than the limit {} (max_design_evaluations): guard \
             fewer supports, draw fewer runs or fix the rock",
            design_search::EVALUATIONS_PER_INVERSE,
            config.max_design_evaluations
        ),
    );
    ck.finish()
}

/// One support column in the design search's answer.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct DesignEntryDto {
    /// Support number (from 1).
    pub support: u32,
    /// Column of that support (from 0).
    pub column_index: u32,
    /// The column gets a guard.
    pub guarded: bool,
    /// The smallest guard energy rating that makes the column acceptable, J (null: not
    /// guarded; 0: no guard needed). When not achievable with the ensemble's runs, the rating
    /// that holds every run that reached the column.
    pub rating_j: Option<f64>,
    /// Runs that reached the column needing a guard (faster than the column takes within every
    /// checked limit); for a column not guarded, the runs that exceeded at it.
    pub runs_needing_guard: u64,
    /// Probability over all runs of striking this column past some checked limit (or past the
    /// contact capacity) with that rating in place, with its Wilson 95 % interval.
    pub exceedance: ProbabilityDto,
    /// The interval's upper bound is within `acceptable_probability`.
    pub acceptable: bool,
}

/// The design search's answer.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct DesignSearchOutDto {
    /// How the ratings were found, in words.
    pub method: String,
    /// The acceptable probability asked for.
    pub acceptable_probability: f64,
    /// Runs of the ensemble.
    pub runs: u64,
    /// Every column acceptable (guarded ones with their ratings; the others as they are).
    pub all_acceptable: bool,
    /// Runs the ensemble would need for even 0 exceedances to be acceptable (omitted when its
    /// runs suffice): the smallest n with z²/(n + z²) ≤ acceptable_probability (at most
    /// 18446744073709551615, which it reaches below about 2e-19).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_needed: Option<u64>,
    /// Inverses of the chain computed: one per active limit and distinct (column, rock) pair.
    pub inverses: u64,
    /// Chain evaluations those inverses took.
    pub chain_evaluations: u64,
    /// Per support column, in the order of `statistics.supports`.
    pub supports: Vec<DesignEntryDto>,
    /// The barrier search (with `design.barriers`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub barriers: Option<BarrierDesignOutDto>,
}

/// The answer of a design search on `case`.
#[must_use]
pub fn design_dto(
    case: &SceneCase,
    d: &DesignSearch,
    barriers: Option<&BarrierDesign>,
) -> DesignSearchOutDto {
    DesignSearchOutDto {
        barriers: barriers.map(|b| barrier_design_dto(case, b, d.acceptable_probability)),
        method: design_search::METHOD.into(),
        acceptable_probability: d.acceptable_probability,
        runs: d.runs,
        all_acceptable: d.all_acceptable,
        runs_needed: d.runs_needed,
        inverses: d.inverses,
        chain_evaluations: d.evaluations,
        supports: d
            .entries
            .iter()
            .map(|x| {
                let e = &case.supports[x.entry];
                DesignEntryDto {
                    support: e.support,
                    column_index: e.column_index,
                    guarded: x.guarded,
                    rating_j: x.rating,
                    runs_needing_guard: x.needing,
                    exceedance: (&x.exceedance).into(),
                    acceptable: x.acceptable,
                }
            })
            .collect(),
    }
}

/// A barrier the search proposes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct ProposedBarrierDto {
    /// The support it stands in front of (number from 1).
    pub support: u32,
    /// Along-dip position, m.
    pub along_dip_m: f64,
    /// Height, m: the design percentile of the passing height at its line when it was chosen,
    /// rounded up to the centimetre (at least 1 cm).
    pub height_m: f64,
    /// Energy rating, J: the design percentile of the kinetic energy at its line when it was
    /// chosen, rounded up to three significant digits.
    pub energy_rating_j: f64,
}

/// A support column with the proposed barriers in place.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct BarrierResidualDto {
    /// Support number (from 1).
    pub support: u32,
    /// Column of that support (from 0).
    pub column_index: u32,
    /// Probability over all runs of striking it past some checked limit (or the capacity) with
    /// the barriers in place, with its Wilson 95 % interval.
    pub exceedance: ProbabilityDto,
    /// The interval's upper bound is within `acceptable_probability`.
    pub acceptable: bool,
}

/// The barrier search's answer.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct BarrierDesignOutDto {
    /// How the barriers were found, in words.
    pub method: String,
    /// The candidates: support number and along-dip position, m.
    pub candidates: Vec<ProposedBarrierSpotDto>,
    /// The barriers proposed, in the order chosen (send them as `barriers` to check them).
    pub barriers: Vec<ProposedBarrierDto>,
    /// Per support column, in the order of `statistics.supports`.
    pub supports: Vec<BarrierResidualDto>,
    /// Every column acceptable with the barriers in place.
    pub all_acceptable: bool,
    /// Ensembles run by the search.
    pub ensembles: u64,
}

/// A candidate position of the barrier search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, ToSchema)]
pub struct ProposedBarrierSpotDto {
    /// The support it stands in front of (number from 1).
    pub support: u32,
    /// Along-dip position, m.
    pub along_dip_m: f64,
}

/// The barrier search's answer on `case`.
#[must_use]
pub fn barrier_design_dto(
    case: &SceneCase,
    d: &BarrierDesign,
    acceptable: f64,
) -> BarrierDesignOutDto {
    BarrierDesignOutDto {
        method: barrier_design::METHOD.into(),
        candidates: d
            .candidates
            .iter()
            .map(|&(support, along_dip_m)| ProposedBarrierSpotDto {
                support,
                along_dip_m,
            })
            .collect(),
        barriers: d
            .barriers
            .iter()
            .map(|b| ProposedBarrierDto {
                support: b.support,
                along_dip_m: b.along_dip,
                height_m: b.height,
                energy_rating_j: b.rating,
            })
            .collect(),
        supports: d
            .residual
            .iter()
            .zip(&case.supports)
            .map(|(p, e)| BarrierResidualDto {
                support: e.support,
                column_index: e.column_index,
                exceedance: p.into(),
                acceptable: p.ci95[1] <= acceptable,
            })
            .collect(),
        all_acceptable: d.acceptable,
        ensembles: d.ensembles,
    }
}

//! A scene's `design`: the smallest guard ratings that make a face acceptable — the request's
//! field, its checks and work limit, and the answer.

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use utoipa::ToSchema;

use super::common::Checker;
use super::scene::{ProbabilityDto, SceneRequest};
use crate::config::Config;
use crate::http::error::ApiError;
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
    /// The supports that get a guard (null: every support).
    #[schema(default = json!(null), example = json!({"supports": [1, 2]}))]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guards: Option<DesignGuardsDto>,
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
    let listed = d.guards.get_or_insert_with(Default::default);
    let supports = listed.supports.get_or_insert_with(|| {
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
    (ok && !no_ensemble).then_some(DesignAsk {
        acceptable_probability: a,
        guarded,
    })
}

/// Refuses (422 naming `/design`) a design search whose work, estimated before running
/// ([`design_search::estimated_evaluations`]), passes `max_design_evaluations`.
pub fn check_work(case: &SceneCase, config: &Config) -> Result<(), ApiError> {
    let (Some(ask), Some(mc)) = (&case.design, &case.migration.monte_carlo) else {
        return Ok(());
    };
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
}

/// The answer of a design search on `case`.
#[must_use]
pub fn design_dto(case: &SceneCase, d: &DesignSearch) -> DesignSearchOutDto {
    DesignSearchOutDto {
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

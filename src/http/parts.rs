//! The service's wire for sharded computations: [`HttpWire`] reads the requests of each kind as
//! the endpoints read them and writes the bytes the endpoints answer.

use bytes::Bytes;
use serde_json::Value;

use crate::calc::Report;
use crate::config::Config;
use crate::http::dto::batch::{json_items, ndjson_items};
use crate::http::dto::common::Checker;
use crate::http::dto::maps::MapsDto;
use crate::http::dto::migration::{MigrationRequest, MigrationResponse};
use crate::http::dto::scene::{SceneContext, SceneHead, SceneRequest, scene_error};
use crate::http::error::ApiError;
use crate::http::json::{from_value, parse_json};
use crate::http::routes::{batch, study};
use crate::http::runner::to_json_bytes;
use crate::physics::migration::{MigrationCase, MigrationResult};
use crate::physics::scene::{EnsembleReport, SceneCase, SceneError, SceneReport};
use crate::physics::{Control, PhysicsError};
use crate::shard::{Failure, Wire};

/// A scene's per-cell maps are not carried through part files: a shard request asking for them
/// (at `pointer`) is refused with 422 before any work (a migration's are).
fn refuse_maps(maps: Option<&MapsDto>, pointer: &str) -> Result<(), ApiError> {
    let Some(m) = maps else { return Ok(()) };
    let mut ck = Checker::new();
    ck.push(
        pointer,
        serde_json::to_value(m).unwrap_or_default(),
        "a scene's per-cell maps are not carried through the part files of a sharded \
         computation (gangue compute/merge): leave maps out, or send the request to the service",
    );
    ck.finish()
}

/// Refuses a sharded scene with barriers or collectors (the part files do not carry the runs'
/// crossings of their lines) or with a target (the runs are split before any ran).
fn refuse_lines(req: &SceneRequest) -> Result<(), ApiError> {
    let mut ck = Checker::new();
    for (pointer, given) in [
        ("/barriers", req.barriers.as_ref().map(Vec::len)),
        ("/collectors", req.collectors.as_ref().map(Vec::len)),
    ] {
        if let Some(n) = given.filter(|&n| n > 0) {
            ck.push(
                pointer,
                serde_json::json!(n),
                "a scene's barriers and collectors are not carried through the part files of a \
                 sharded computation (gangue compute/merge): leave them out, or send the request \
                 to the service",
            );
        }
    }
    refuse_target(
        &mut ck,
        req.monte_carlo
            .as_ref()
            .and_then(|m| m.target)
            .map(serde_json::to_value),
    );
    ck.finish()
}

/// A scene's design search runs over all of the ensemble's runs at once, which a sharded
/// computation never holds: a shard request asking for it is refused with 422 before any work.
fn refuse_design(req: &SceneRequest) -> Result<(), ApiError> {
    let Some(d) = &req.design else { return Ok(()) };
    let mut ck = Checker::new();
    ck.push(
        "/design",
        serde_json::to_value(d).unwrap_or_default(),
        "the design search is not carried through the part files of a sharded computation \
         (gangue compute/merge): leave design out, or send the request to the service",
    );
    ck.finish()
}

/// Records the refusal of a sharded ensemble with a target (given as its JSON value): the runs
/// are split between the shards before any ran, so none can stop early.
fn refuse_target(ck: &mut Checker, target: Option<serde_json::Result<Value>>) {
    if let Some(t) = target {
        ck.push(
            "/monte_carlo/target",
            t.unwrap_or_default(),
            "a sharded computation splits all the runs between its shards before any runs: it \
             cannot stop early; leave the target out (monte_carlo.runs is then the runs), or send \
             the request to the service",
        );
    }
}

/// The service's wire: requests and answers as the endpoints read and write them.
#[derive(Debug, Clone, Copy, Default)]
pub struct HttpWire;

impl From<ApiError> for Failure {
    fn from(e: ApiError) -> Self {
        Self::refused(&e, e.to_problem())
    }
}

impl Wire for HttpWire {
    type Migration = MigrationRequest;
    type Scene = (SceneContext, SceneRequest);
    type SceneHead = SceneHead;
    type Study = study::StudyPlan;
    type Item = Result<Value, ApiError>;

    fn migration(
        &self,
        request: &[u8],
        config: &Config,
    ) -> Result<(MigrationCase, MigrationRequest, Vec<u8>), Failure> {
        let v = parse_json(request)?;
        let mut req: MigrationRequest = from_value(&v)?;
        let case = req.resolve(config)?;
        let mut ck = Checker::new();
        refuse_target(
            &mut ck,
            req.monte_carlo
                .as_ref()
                .and_then(|m| m.target)
                .map(serde_json::to_value),
        );
        if req.output.compare_methods {
            ck.push(
                "/output/compare_methods",
                serde_json::json!(true),
                "a sharded computation runs the requested method's runs only; send the other \
                 method as a sharded computation of its own, or the request to the service",
            );
        }
        ck.finish()?;
        let inputs = serde_json::to_vec(&req).map_err(ApiError::internal)?;
        Ok((case, req, inputs))
    }

    fn migration_answer(
        &self,
        report: Report<MigrationResult>,
        req: MigrationRequest,
    ) -> Result<Vec<u8>, Failure> {
        Ok(to_json_bytes(&MigrationResponse::new(report, req))?)
    }

    fn physics_failure(&self, e: PhysicsError) -> Failure {
        Failure::from(ApiError::from(e))
    }

    fn scene(
        &self,
        request: &[u8],
        config: &Config,
    ) -> Result<(SceneCase, Self::Scene, Vec<u8>), Failure> {
        let v = parse_json(request)?;
        let mut req: SceneRequest = from_value(&v)?;
        let (case, ctx) = req.resolve(config)?;
        refuse_maps(req.migration_output.maps.as_ref(), "/migration_output/maps")?;
        refuse_lines(&req)?;
        refuse_design(&req)?;
        let inputs = serde_json::to_vec(&req).map_err(ApiError::internal)?;
        Ok((case, (ctx, req), inputs))
    }

    fn scene_failure(&self, e: SceneError, (ctx, _): &Self::Scene) -> Failure {
        Failure::from(scene_error(e, ctx))
    }

    fn scene_head(
        &self,
        report: &Report<SceneReport>,
        ensemble: bool,
        case: &SceneCase,
        (ctx, req): &Self::Scene,
    ) -> Result<SceneHead, Failure> {
        Ok(SceneHead::new(report, ensemble, case, ctx, req)?)
    }

    fn nominal_capacity(head: &SceneHead) -> bool {
        head.nominal_capacity
    }

    fn keep_runs((_, req): &Self::Scene) -> bool {
        req.migration_output.runs_csv
    }

    fn scene_answer(
        &self,
        head: SceneHead,
        tail: Option<EnsembleReport>,
        case: &SceneCase,
        (_, req): Self::Scene,
    ) -> Result<Vec<u8>, Failure> {
        Ok(head.finish(tail, case, req)?)
    }

    fn study(
        &self,
        request: &[u8],
        config: &Config,
    ) -> Result<(study::StudyPlan, Vec<u8>), Failure> {
        let v = parse_json(request)?;
        let plan = study::plan(config, from_value(&v)?)?;
        let inputs = serde_json::to_vec(&plan.inputs()).map_err(ApiError::internal)?;
        Ok((plan, inputs))
    }

    fn study_points(plan: &study::StudyPlan) -> u64 {
        plan.points()
    }

    fn study_point(
        &self,
        plan: &study::StudyPlan,
        config: &Config,
        index: usize,
        control: &Control,
    ) -> Result<Vec<f64>, Failure> {
        Ok(plan.eval(config, index, control)?)
    }

    fn study_answer(
        &self,
        plan: study::StudyPlan,
        results: Vec<Vec<f64>>,
    ) -> Result<Vec<u8>, Failure> {
        Ok(to_json_bytes(&plan.finish(results)?)?)
    }

    fn batch(
        &self,
        request: &[u8],
        config: &Config,
    ) -> Result<(Vec<Self::Item>, Vec<u8>), Failure> {
        // a JSON envelope {"items": [...]}, or one item per line (NDJSON)
        let items: Vec<Self::Item> = match parse_json(request) {
            Ok(body) if body.is_object() => json_items(&body)?.into_iter().map(Ok).collect(),
            _ => ndjson_items(request),
        };
        let limit = config.max_batch_items;
        if items.len() as u64 > limit {
            return Err(ApiError::invalid(
                "/items",
                serde_json::json!(items.len()),
                format!("at most {limit} items in one batch (see limits in /v1/presets)"),
            )
            .into());
        }
        let canon: Vec<Value> = items
            .iter()
            .map(|r| match r {
                Ok(v) => v.clone(),
                Err(e) => e.to_problem(),
            })
            .collect();
        let inputs = serde_json::to_vec(&canon).map_err(ApiError::internal)?;
        Ok((items, inputs))
    }

    fn batch_line(
        &self,
        index: usize,
        item: &Self::Item,
        config: &Config,
        control: &Control,
    ) -> Bytes {
        let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            batch::run_item(index, item, config, control)
        }))
        .unwrap_or_else(|_| Err(ApiError::internal(format!("batch item {index} panicked"))));
        batch::line(index, out)
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;
    use crate::config::{ComputeArgs, Kind, MergeArgs};

    /// More shards than runs leaves some parts empty (and sorted columns of zero or one value);
    /// every split of a five-run ensemble merges to the service's bytes.
    #[test]
    fn any_split_including_empty_parts_gives_the_service_bytes() {
        let dir = std::env::temp_dir().join(format!("gangue-shard-unit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let body = serde_json::json!({
            "face": {"dip_deg": 35.0, "length_m": 60.0, "friction_coefficient": 0.45},
            "monte_carlo": {"runs": 5, "seed": 3,
                "friction_coefficient": {"distribution": "normal", "mean": 0.45, "std": 0.2}},
            "output": {"runs_csv": true, "events": false}
        });
        let request = dir.join("case.json");
        std::fs::write(&request, serde_json::to_vec(&body).unwrap()).unwrap();
        let config = Config::default();
        let mut req: MigrationRequest = from_value(&body).unwrap();
        let case = req.resolve(&config).unwrap();
        let want = to_json_bytes(
            &crate::http::routes::migration::solve(&case, req, &Control::unlimited()).unwrap(),
        )
        .unwrap();
        for k in [1u64, 2, 5, 7, 13] {
            let parts: Vec<PathBuf> = (0..k)
                .map(|i| {
                    let a = ComputeArgs {
                        request: request.clone(),
                        kind: Kind::Migration,
                        shard: Some(format!("{i}/{k}")),
                        shards: None,
                        index_offset: 0,
                        out: dir
                            .join(format!("k{k}-part-{{shard}}"))
                            .display()
                            .to_string(),
                        time_limit_s: None,
                        limits: Config::default(),
                    };
                    crate::shard::compute(&a, &HttpWire)
                        .map_err(|e| e.message)
                        .unwrap()
                })
                .collect();
            let mut out = Vec::new();
            let m = MergeArgs {
                parts,
                time_limit_s: None,
                limits: Config::default(),
            };
            crate::shard::merge(&m, &HttpWire, &mut out)
                .map_err(|e| e.message)
                .unwrap();
            assert_eq!(
                String::from_utf8(out).unwrap(),
                String::from_utf8(want.clone()).unwrap(),
                "{k} shards"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

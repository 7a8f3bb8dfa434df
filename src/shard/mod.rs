//! Sharded computations: `gangue compute` runs the work items of one request with global
//! indices ⌊I·N/K⌋ … ⌊(I+1)·N/K⌋ − 1 into a part file, `gangue merge` turns the parts into the
//! bytes `POST` of the same request answers (README "Beyond one machine").
//!
//! Items: the Monte Carlo runs of a migration or a scene (N = runs), the points of a study after
//! its base (N = points − 1, in the order the response lists them: curves, grids, energy
//! proportions, central-difference points), the items of a batch. What is not an item is
//! computed once, by shard 0, and stored in its part: a scene's nominal run with its strikes
//! (the migration response and the impacts as the answer serializes them, the plan's first
//! stages, the scene's own warnings; for a scene without an ensemble, the whole answer) and a
//! study's base point. The merge runs no solver for them. A migration's nominal run (one run) is
//! still computed by the merge from the request the parts carry.
//!
//! Part file (format version 4): one JSON header line ([`Header`]: kind, build id, SHA-256 of the
//! resolved inputs, the request, the item range, section sizes), then a little-endian binary
//! body of sections: a migration's run records (153 bytes each) followed by its seven statistics
//! columns, each sorted by `f64::total_cmp`; a scene's run records (186 bytes each: the
//! migration record, the strike's four values, a flag byte) followed by five columns per support
//! entry (the runs that struck it within capacity, sorted) and five design-value columns per
//! entry (the runs that reached it, sorted), repeated for the other method with
//! `compare_methods`, then the stored nominal part (JSON, empty but in part 0); a study's point
//! outputs (each a length, u64, then f64 values) and then its base point (part 0 only); a
//! batch's answer lines, each preceded by its length (u64). A part is written to a temporary name
//! in the same directory and renamed, so a shard run twice leaves one whole part.
//!
//! The merge checks that the parts come from one request and one build and that their ranges
//! tile 0..N exactly (no index missing, none twice), then feeds the records to the same response
//! builder as the service ([`calc::migration::merge`], [`calc::scene::merge`],
//! [`Wire::study_answer`]): sums stream the records in index order (run order, the
//! summation order of the contract) and order statistics come from a k-way merge of the per-part
//! sorted columns, so the merge holds O(parts) records, not O(runs) (a `runs_csv` answer is
//! itself O(runs)).
//!
//! Here: the header, the build id, the shard index and range, the request resolved through
//! [`Wire`]; `compute` and `merge` the two commands, `record` the binary run records, `part` the
//! part files read back and checked, `wire` what the commands need of the wire.

use std::collections::BinaryHeap;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::calc::migration::{MergeError, Migration};
use crate::calc::scene::Scene;
use crate::calc::{self, Ensemble};
use crate::config::{ComputeArgs, Config, Kind, MergeArgs};
use crate::physics::Control;
use crate::physics::migration::{
    MigrationCase, RunRecords, RunSummary, STATISTICS_COLUMNS, StopReason, run_columns,
};
use crate::physics::scene::{
    ENTRY_COLUMNS, Guard, REACH_COLUMNS, SceneCase, SceneError, SceneRecords, SceneRun,
    StrikeValues, entry_columns, reach_columns,
};

mod compute;
mod merge;
mod part;
mod record;
#[cfg(test)]
mod tests;
mod wire;

pub use compute::compute;
pub use merge::merge;
use record::{decode_run, decode_scene_run, encode_run, encode_scene_run};
pub use wire::Wire;

/// Name of the part file format.
pub const FORMAT: &str = "gangue-part";
/// Version of the part file format.
pub const FORMAT_VERSION: u32 = 4;
/// Bytes of one migration run record.
const RUN_RECORD_BYTES: u64 = 153;
/// Bytes of one scene run record: the migration record, four strike values, a flag byte.
const SCENE_RECORD_BYTES: u64 = RUN_RECORD_BYTES + 33;

/// Header line of a part file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Header {
    /// Always [`FORMAT`].
    pub format: String,
    /// [`FORMAT_VERSION`].
    pub version: u32,
    /// Request kind: migration, scene, study or batch.
    pub kind: String,
    /// Build id of the binary that computed the part ([`build_id`]).
    pub build: String,
    /// SHA-256 (hex) of the kind and the resolved inputs.
    pub inputs_sha256: String,
    /// The request as given (UTF-8 JSON or NDJSON), from which the merge computes the non-items.
    pub request: String,
    /// Number of items N of the whole request.
    pub items: u64,
    /// Shard index I (0-based) and count K this part was computed as.
    pub shard: u64,
    /// Shard count K.
    pub shards: u64,
    /// First global item index of the part.
    pub start: u64,
    /// One past the last global item index of the part.
    pub end: u64,
    /// Sizes of the body's sections in bytes (see the module's documentation).
    pub sections: Vec<u64>,
}

/// The build id: the crate version and the git commit it was built from when the sources were
/// exactly that commit, else the crate version and a SHA-256 of the running binary.
pub fn build_id() -> String {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        let version = env!("CARGO_PKG_VERSION");
        match option_env!("GANGUE_GIT_HASH") {
            Some(h) if !h.is_empty() => format!("{version}+git.{h}"),
            _ => {
                let digest = std::env::current_exe()
                    .and_then(|p| {
                        // streamed: the binary is never held in memory
                        let mut r = BufReader::with_capacity(1 << 16, File::open(p)?);
                        let mut h = Sha256::new();
                        std::io::copy(&mut r, &mut h)?;
                        Ok(hex(&h.finalize())[..16].to_string())
                    })
                    .unwrap_or_else(|_: std::io::Error| "unknown".into());
                format!("{version}+bin.{digest}")
            }
        }
    })
    .clone()
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

fn inputs_hash(kind: Kind, inputs: &[u8]) -> String {
    let mut h = Sha256::new();
    h.update(kind.name().as_bytes());
    h.update(b"\n");
    h.update(inputs);
    hex(&h.finalize())
}

/// The global item range of shard `i` of `k` over `n` items: ⌊i·n/k⌋ .. ⌊(i+1)·n/k⌋.
#[must_use]
pub fn shard_range(i: u64, k: u64, n: u64) -> std::ops::Range<u64> {
    let at = |j: u64| (u128::from(j) * u128::from(n) / u128::from(k)) as u64;
    at(i)..at(i + 1)
}

/// The shard index and count: `--shard I/K`, or an array index from the environment
/// (`JOB_COMPLETION_INDEX`, `SLURM_ARRAY_TASK_ID`, `AWS_BATCH_JOB_ARRAY_INDEX`) with `--shards K`
/// (Slurm: `SLURM_ARRAY_TASK_COUNT` when `--shards` is not given), plus `--index-offset`; 0/1
/// when none is given.
pub fn shard_of(
    args: &ComputeArgs,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(u64, u64), String> {
    let num = |name: &str, v: &str| -> Result<u64, String> {
        v.trim()
            .parse::<u64>()
            .map_err(|_| format!("{name} must be a whole number ≥ 0, got {v:?}"))
    };
    let (i, k) = if let Some(s) = &args.shard {
        let (i, k) = s
            .split_once('/')
            .ok_or_else(|| format!("--shard must be I/K (for example 0/3), got {s:?}"))?;
        (num("--shard I", i)?, num("--shard K", k)?)
    } else {
        let from_env = [
            "JOB_COMPLETION_INDEX",
            "SLURM_ARRAY_TASK_ID",
            "AWS_BATCH_JOB_ARRAY_INDEX",
        ]
        .iter()
        .find_map(|name| env(name).map(|v| (*name, v)));
        match from_env {
            Some((name, v)) => {
                let i = num(name, &v)?;
                let k = match (args.shards, name) {
                    (Some(k), _) => k,
                    (None, "SLURM_ARRAY_TASK_ID") => match env("SLURM_ARRAY_TASK_COUNT") {
                        Some(c) => num("SLURM_ARRAY_TASK_COUNT", &c)?,
                        None => return Err("--shards K is needed with SLURM_ARRAY_TASK_ID".into()),
                    },
                    (None, _) => return Err(format!("--shards K is needed with {name}")),
                };
                (i, k)
            }
            None => (0, args.shards.unwrap_or(1)),
        }
    };
    let i = i
        .checked_add(args.index_offset)
        .ok_or("--index-offset is too large")?;
    if k == 0 {
        return Err("the shard count K must be at least 1".into());
    }
    if i >= k {
        return Err(format!(
            "shard index {i} (with --index-offset {}) is not below the shard count {k}",
            args.index_offset
        ));
    }
    Ok((i, k))
}

/// A failure of `compute` or `merge`: the message, and the problem of a refused request.
#[derive(Debug)]
pub struct Failure {
    /// What went wrong, for a person.
    pub message: String,
    /// The problem+json body the service would answer, when the request itself was refused.
    pub problem: Option<Value>,
}

impl From<String> for Failure {
    fn from(message: String) -> Self {
        Self {
            message,
            problem: None,
        }
    }
}

impl From<&str> for Failure {
    fn from(message: &str) -> Self {
        Self::from(message.to_string())
    }
}

impl Failure {
    /// The failure of a refused request: `message` (the refusal) and its problem+json body.
    #[must_use]
    pub fn refused(message: impl std::fmt::Display, problem: Value) -> Self {
        Self {
            message: format!("the request was refused: {message}"),
            problem: Some(problem),
        }
    }
}

#[allow(clippy::needless_pass_by_value, reason = "used as a map_err closure")]
fn io_err(path: &Path, e: std::io::Error) -> Failure {
    Failure::from(format!("{}: {e}", path.display()))
}

/// The request of a part: parsed, resolved and counted.
enum Prepared<W: Wire> {
    Migration {
        case: Box<MigrationCase>,
        req: Box<W::Migration>,
    },
    Scene {
        case: Box<SceneCase>,
        req: Box<W::Scene>,
    },
    Study(Box<W::Study>),
    Batch(Vec<W::Item>),
}

struct Resolved<W: Wire> {
    prepared: Prepared<W>,
    items: u64,
    hash: String,
}

fn resolve<W: Wire>(
    wire: &W,
    kind: Kind,
    request: &[u8],
    config: &Config,
) -> Result<Resolved<W>, Failure> {
    match kind {
        Kind::Migration => {
            let (case, req, inputs) = wire.migration(request, config)?;
            Ok(Resolved {
                items: Migration::items(&case),
                prepared: Prepared::Migration {
                    case: Box::new(case),
                    req: Box::new(req),
                },
                hash: inputs_hash(kind, &inputs),
            })
        }
        Kind::Scene => {
            let (case, req, inputs) = wire.scene(request, config)?;
            Ok(Resolved {
                items: Scene::items(&case),
                prepared: Prepared::Scene {
                    case: Box::new(case),
                    req: Box::new(req),
                },
                hash: inputs_hash(kind, &inputs),
            })
        }
        Kind::Study => {
            let (plan, inputs) = wire.study(request, config)?;
            Ok(Resolved {
                items: W::study_points(&plan) - 1,
                hash: inputs_hash(kind, &inputs),
                prepared: Prepared::Study(Box::new(plan)),
            })
        }
        Kind::Batch => {
            let (items, inputs) = wire.batch(request, config)?;
            Ok(Resolved {
                items: items.len() as u64,
                prepared: Prepared::Batch(items),
                hash: inputs_hash(kind, &inputs),
            })
        }
    }
}

fn control(limit: Option<f64>) -> Control {
    Control::with_deadline(limit.map(|s| Instant::now() + Duration::from_secs_f64(s)))
}

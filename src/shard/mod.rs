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
//! Part file (format version 3): one JSON header line ([`Header`]: kind, build id, SHA-256 of the
//! resolved inputs, the request, the item range, section sizes), then a little-endian binary
//! body of sections: a migration's run records (81 bytes each) followed by its seven statistics
//! columns, each sorted by `f64::total_cmp`; a scene's run records (114 bytes each: the
//! migration record, the strike's four values, a flag byte) followed by five columns per support
//! entry (the runs that struck it within capacity, sorted), repeated for the other method with
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
    ENTRY_COLUMNS, SceneCase, SceneError, SceneRecords, SceneRun, StrikeValues, entry_columns,
};

mod wire;
pub use wire::Wire;

/// Name of the part file format.
pub const FORMAT: &str = "gangue-part";
/// Version of the part file format.
pub const FORMAT_VERSION: u32 = 3;
/// Bytes of one migration run record.
const RUN_RECORD_BYTES: u64 = 81;
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

/// `gangue compute`: computes the items of one shard and writes its part file. Returns the path
/// written. `wire` reads the request and writes the answer pieces part 0 stores.
pub fn compute<W: Wire>(args: &ComputeArgs, wire: &W) -> Result<PathBuf, Failure> {
    args.limits.validate()?;
    let (i, k) = shard_of(args, &|n| std::env::var(n).ok())?;
    let request = std::fs::read(&args.request).map_err(|e| io_err(&args.request, e))?;
    let request_text = String::from_utf8(request.clone())
        .map_err(|_| format!("{}: the request is not UTF-8", args.request.display()))?;
    let config = &args.limits;
    let r = resolve(wire, args.kind, &request, config)?;
    let range = shard_range(i, k, r.items);
    let mut sections = Vec::new();
    let mut body: Vec<u8> = Vec::new();
    match &r.prepared {
        Prepared::Migration { case, .. } => {
            let ctl = control(args.time_limit_s);
            let runs =
                Migration::part(case, range.clone(), &ctl).map_err(|e| wire.physics_failure(e))?;
            for run in &runs {
                encode_run(run, &mut body);
            }
            sections.push(body.len() as u64);
            for col in 0..STATISTICS_COLUMNS {
                let mut v: Vec<f64> = runs.iter().filter_map(|r| run_columns(r)[col]).collect();
                v.sort_unstable_by(f64::total_cmp);
                let before = body.len();
                v.iter()
                    .for_each(|x| body.extend_from_slice(&x.to_le_bytes()));
                sections.push((body.len() - before) as u64);
            }
        }
        Prepared::Scene { case, req } => {
            let ctl = control(args.time_limit_s);
            let fail = |e: SceneError| wire.scene_failure(e, req);
            // part 0: what is not an item, computed first (a refused request fails here)
            let ensemble = calc::scene::ensemble(case).is_some();
            let head = if i == 0 {
                let report = calc::scene::nominal(case, &ctl).map_err(fail)?;
                Some(wire.scene_head(&report, ensemble, case, req)?)
            } else {
                None
            };
            if ensemble {
                let (runs, other) = Scene::part(case, range.clone(), &ctl).map_err(fail)?;
                for stream in std::iter::once(&runs).chain(other.as_ref()) {
                    let before = body.len();
                    stream.iter().for_each(|r| encode_scene_run(r, &mut body));
                    sections.push((body.len() - before) as u64);
                    let mut columns = vec![vec![Vec::new(); ENTRY_COLUMNS]; case.supports.len()];
                    for (k, x) in stream.iter().filter_map(entry_columns) {
                        for (c, x) in columns[k].iter_mut().zip(x) {
                            c.push(x);
                        }
                    }
                    for mut v in columns.into_iter().flatten() {
                        v.sort_unstable_by(f64::total_cmp);
                        let before = body.len();
                        v.iter()
                            .for_each(|x| body.extend_from_slice(&x.to_le_bytes()));
                        sections.push((body.len() - before) as u64);
                    }
                }
            }
            let before = body.len();
            if let Some(h) = &head {
                serde_json::to_writer(&mut body, h).map_err(|e| format!("storing part 0: {e}"))?;
            }
            sections.push((body.len() - before) as u64);
        }
        Prepared::Study(plan) => {
            let ctl = control(args.time_limit_s);
            let out: Vec<Vec<f64>> = (range.start..range.end)
                .into_par_iter()
                .map(|g| wire.study_point(plan, config, g as usize + 1, &ctl))
                .collect::<Result<_, _>>()?;
            let values = |v: &[f64], body: &mut Vec<u8>| {
                body.extend_from_slice(&(v.len() as u64).to_le_bytes());
                v.iter()
                    .for_each(|x| body.extend_from_slice(&x.to_le_bytes()));
            };
            for v in &out {
                values(v, &mut body);
            }
            sections.push(body.len() as u64);
            // part 0: the base point, not an item
            let before = body.len();
            if i == 0 {
                values(&wire.study_point(plan, config, 0, &ctl)?, &mut body);
            }
            sections.push((body.len() - before) as u64);
        }
        Prepared::Batch(items) => {
            // each item has a time limit of its own (api.md), here none unless asked for
            let lines: Vec<bytes::Bytes> = (range.start..range.end)
                .into_par_iter()
                .map(|g| {
                    let g = g as usize;
                    let ctl = control(args.time_limit_s);
                    wire.batch_line(g, &items[g], config, &ctl)
                })
                .collect();
            for l in &lines {
                body.extend_from_slice(&(l.len() as u64).to_le_bytes());
                body.extend_from_slice(l);
            }
            sections.push(body.len() as u64);
        }
    }
    let header = Header {
        format: FORMAT.into(),
        version: FORMAT_VERSION,
        kind: args.kind.name().into(),
        build: build_id(),
        inputs_sha256: r.hash,
        request: request_text,
        items: r.items,
        shard: i,
        shards: k,
        start: range.start,
        end: range.end,
        sections,
    };
    let out = PathBuf::from(args.out.replace("{shard}", &i.to_string()));
    write_part(&out, &header, &body)?;
    Ok(out)
}

fn write_part(out: &Path, header: &Header, body: &[u8]) -> Result<(), Failure> {
    let name = out
        .file_name()
        .ok_or_else(|| format!("--out {}: not a file name", out.display()))?;
    let tmp = out.with_file_name(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let write = || -> std::io::Result<()> {
        let mut w = BufWriter::new(File::create(&tmp)?);
        serde_json::to_writer(&mut w, header)?;
        w.write_all(b"\n")?;
        w.write_all(body)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, out)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_err(out, e)
    })
}

fn encode_run(r: &RunSummary, out: &mut Vec<u8>) {
    // every field, so that a new one fails to compile here
    let RunSummary {
        time,
        speed,
        kinetic_energy,
        impact_count,
        runout,
        max_bounce_height,
        stop_reason,
        steps,
        along_dip_velocity,
        support,
        impact_speed,
    } = *r;
    for x in [
        time,
        speed,
        kinetic_energy,
        runout,
        max_bounce_height,
        along_dip_velocity,
        impact_speed,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend_from_slice(&impact_count.to_le_bytes());
    out.extend_from_slice(&steps.to_le_bytes());
    out.extend_from_slice(&support.map_or(u64::MAX, |k| k as u64).to_le_bytes());
    out.push(match stop_reason {
        StopReason::LowerEnd => 0,
        StopReason::AtRest => 1,
        StopReason::EndTime => 2,
        StopReason::LeftFloor => 3,
        StopReason::Support => 4,
    });
}

fn decode_run(b: &[u8; RUN_RECORD_BYTES as usize]) -> Result<RunSummary, String> {
    let f = |k: usize| f64::from_le_bytes(std::array::from_fn(|i| b[8 * k + i]));
    let u = |k: usize| u64::from_le_bytes(std::array::from_fn(|i| b[8 * k + i]));
    Ok(RunSummary {
        time: f(0),
        speed: f(1),
        kinetic_energy: f(2),
        runout: f(3),
        max_bounce_height: f(4),
        along_dip_velocity: f(5),
        impact_speed: f(6),
        impact_count: u(7),
        steps: u(8),
        support: match u(9) {
            u64::MAX => None,
            k => Some(usize::try_from(k).map_err(|_| format!("support index {k} out of range"))?),
        },
        stop_reason: match b[80] {
            0 => StopReason::LowerEnd,
            1 => StopReason::AtRest,
            2 => StopReason::EndTime,
            3 => StopReason::LeftFloor,
            4 => StopReason::Support,
            x => return Err(format!("unknown stop reason code {x}")),
        },
    })
}

fn encode_scene_run(r: &SceneRun, out: &mut Vec<u8>) {
    // every field, so that a new one fails to compile here
    let SceneRun {
        summary,
        values,
        capacity_exceeded,
        exceeded,
    } = r;
    encode_run(summary, out);
    let StrikeValues {
        max_deformation,
        max_force,
        absorbed_energy,
        stress_utilisation,
    } = values.unwrap_or_default();
    for x in [
        max_deformation,
        max_force,
        absorbed_energy,
        stress_utilisation,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    // bit 0: values present, bit 1: past the capacity, bits 2…: exceeded per active limit (≤ 3)
    debug_assert!(exceeded.len() <= 6);
    let mut flags = u8::from(values.is_some()) | (u8::from(*capacity_exceeded) << 1);
    for (j, &e) in exceeded.iter().enumerate() {
        flags |= u8::from(e) << (2 + j);
    }
    out.push(flags);
}

fn decode_scene_run(
    b: &[u8; SCENE_RECORD_BYTES as usize],
    limits: usize,
) -> Result<SceneRun, String> {
    let summary = decode_run(
        b[..RUN_RECORD_BYTES as usize]
            .try_into()
            .map_err(|_| "a scene record shorter than a run record".to_string())?,
    )?;
    let at = RUN_RECORD_BYTES as usize;
    let f = |k: usize| f64::from_le_bytes(std::array::from_fn(|i| b[at + 8 * k + i]));
    let flags = b[at + 32];
    if flags >> (2 + limits) != 0 {
        return Err(format!(
            "scene record flags {flags:#04x} do not fit {limits} limits"
        ));
    }
    Ok(SceneRun {
        summary,
        values: (flags & 1 != 0).then(|| StrikeValues {
            max_deformation: f(0),
            max_force: f(1),
            absorbed_energy: f(2),
            stress_utilisation: f(3),
        }),
        capacity_exceeded: flags & 2 != 0,
        exceeded: (0..limits).map(|j| flags & (4 << j) != 0).collect(),
    })
}

/// One part file, its header read.
#[derive(Debug)]
struct Part {
    path: PathBuf,
    header: Header,
    body_offset: u64,
}

fn read_part(path: &Path) -> Result<Part, Failure> {
    let f = File::open(path).map_err(|e| io_err(path, e))?;
    let len = f.metadata().map_err(|e| io_err(path, e))?.len();
    let mut r = BufReader::new(f);
    let mut line = Vec::new();
    r.read_until(b'\n', &mut line)
        .map_err(|e| io_err(path, e))?;
    let not_part = || {
        Failure::from(format!(
            "{}: not a gangue part file (no {FORMAT} header line)",
            path.display()
        ))
    };
    if line.last() != Some(&b'\n') {
        return Err(not_part());
    }
    let v: Value = serde_json::from_slice(&line).map_err(|_| not_part())?;
    if v.get("format").and_then(Value::as_str) != Some(FORMAT) {
        return Err(not_part());
    }
    if v.get("version").and_then(Value::as_u64) != Some(u64::from(FORMAT_VERSION)) {
        return Err(Failure::from(format!(
            "{}: part format version {} cannot be read by this build (it reads version {FORMAT_VERSION})",
            path.display(),
            v.get("version").unwrap_or(&Value::Null)
        )));
    }
    let header: Header = serde_json::from_value(v)
        .map_err(|e| format!("{}: malformed part header: {e}", path.display()))?;
    let body_offset = line.len() as u64;
    let body: u64 = header.sections.iter().sum();
    if len != body_offset + body {
        return Err(Failure::from(format!(
            "{}: the part is {len} bytes, its header says {} (truncated or damaged)",
            path.display(),
            body_offset + body
        )));
    }
    if header.start > header.end || header.end > header.items {
        return Err(Failure::from(format!(
            "{}: item range {}..{} is not within 0..{}",
            path.display(),
            header.start,
            header.end,
            header.items
        )));
    }
    Ok(Part {
        path: path.to_path_buf(),
        header,
        body_offset,
    })
}

/// Checks that the parts come from one request and one build and tile 0..N; sorts them by start.
fn check_parts(parts: &mut [Part]) -> Result<(), Failure> {
    let first = parts.first().ok_or("no part files given")?;
    let (h0, p0) = (first.header.clone(), first.path.clone());
    for p in parts.iter() {
        let h = &p.header;
        if h.kind != h0.kind {
            return Err(Failure::from(format!(
                "parts of different kinds of request: {} is {}, {} is {}",
                p0.display(),
                h0.kind,
                p.path.display(),
                h.kind
            )));
        }
        if h.inputs_sha256 != h0.inputs_sha256 || h.items != h0.items {
            return Err(Failure::from(format!(
                "parts of different requests: {} and {} were computed from different inputs \
                 (SHA-256 {} and {}); compute every part from the same request file",
                p0.display(),
                p.path.display(),
                &h0.inputs_sha256[..16.min(h0.inputs_sha256.len())],
                &h.inputs_sha256[..16.min(h.inputs_sha256.len())]
            )));
        }
        if h.build != h0.build {
            return Err(Failure::from(format!(
                "parts of different builds: {} was computed by {}, {} by {}; compute every part \
                 with the same gangue binary",
                p0.display(),
                h0.build,
                p.path.display(),
                h.build
            )));
        }
    }
    parts.sort_by_key(|p| (p.header.start, p.header.end));
    let n = h0.items;
    let mut next = 0u64;
    let mut prev: Option<&Part> = None;
    for p in parts.iter() {
        let h = &p.header;
        if h.start > next {
            return Err(Failure::from(format!(
                "items {next} to {} are missing: no part holds them (the next part, shard {} of \
                 {}, starts at item {}; was a part not computed or not given?)",
                h.start - 1,
                h.shard,
                h.shards,
                h.start
            )));
        }
        if h.start < next && h.end > h.start {
            let q = prev.ok_or_else(|| Failure::from("a part after no part".to_string()))?;
            return Err(Failure::from(format!(
                "items {} to {} are in two parts, {} and {} (a part given twice, or parts of \
                 different splits)",
                h.start,
                next.min(h.end) - 1,
                q.path.display(),
                p.path.display()
            )));
        }
        if h.end > next {
            next = h.end;
            prev = Some(p);
        }
    }
    if next < n {
        return Err(Failure::from(format!(
            "items {next} to {} of {n} are missing: no part holds them",
            n - 1
        )));
    }
    // empty parts (more shards than items) are harmless, but the same part twice is not
    for w in parts.windows(2) {
        let (a, b) = (&w[0].header, &w[1].header);
        if a.start == a.end && a.shard == b.shard && a.shards == b.shards && a.start == b.start {
            return Err(Failure::from(format!(
                "shard {} of {} is given twice: {} and {}",
                a.shard,
                a.shards,
                w[0].path.display(),
                w[1].path.display()
            )));
        }
    }
    Ok(())
}

/// A reader of part `p`'s body from byte `offset` on.
fn reader(p: &Part, offset: u64) -> Result<BufReader<File>, String> {
    let mut f = File::open(&p.path).map_err(|e| format!("{}: {e}", p.path.display()))?;
    f.seek(SeekFrom::Start(p.body_offset + offset))
        .map_err(|e| format!("{}: {e}", p.path.display()))?;
    Ok(BufReader::with_capacity(1 << 16, f))
}

/// Byte offset of section `k` in part `p`'s body.
fn section_offset(p: &Part, k: usize) -> u64 {
    p.header.sections[..k].iter().sum()
}

/// The whole section `k` of part `p` (a small one: a stored nominal part, a study's base).
fn read_section(p: &Part, k: usize) -> Result<Vec<u8>, String> {
    let mut b = vec![0u8; p.header.sections[k] as usize];
    reader(p, section_offset(p, k))?
        .read_exact(&mut b)
        .map_err(|e| format!("{}: {e}", p.path.display()))?;
    Ok(b)
}

/// Checks that every part has `n` sections, the first of `record` bytes per item when given.
fn check_sections(parts: &[Part], n: usize, record: Option<u64>) -> Result<(), String> {
    for p in parts {
        let h = &p.header;
        let records_ok =
            record.is_none_or(|b| h.sections.first() == Some(&((h.end - h.start) * b)));
        if h.sections.len() != n || !records_ok {
            return Err(format!(
                "{}: the part's sections do not fit its request (damaged, or written by another \
                 build)",
                p.path.display()
            ));
        }
    }
    Ok(())
}

/// The part of shard 0, which carries what is not an item (`what`).
fn part_zero<'a>(parts: &'a [Part], what: &str) -> Result<&'a Part, String> {
    parts.iter().find(|p| p.header.shard == 0).ok_or_else(|| {
        format!(
            "part 0 (shard 0 of {}) is missing: it carries {what}; compute shard 0 too",
            parts[0].header.shards
        )
    })
}

/// The values at the 0-based `ranks` (ascending) of the column made of section `section` of
/// every part (each sorted by `f64::total_cmp`): one reader per part, merged through a heap, so
/// O(parts) memory.
fn merged_order_values(parts: &[Part], section: usize, ranks: &[u64]) -> Result<Vec<f64>, String> {
    let mut readers = Vec::with_capacity(parts.len());
    let mut left = Vec::with_capacity(parts.len());
    let mut heap = BinaryHeap::with_capacity(parts.len());
    let read = |r: &mut BufReader<File>, p: &Part| -> Result<f64, String> {
        let mut b = [0u8; 8];
        r.read_exact(&mut b)
            .map_err(|e| format!("{}: {e}", p.path.display()))?;
        Ok(f64::from_le_bytes(b))
    };
    for (k, p) in parts.iter().enumerate() {
        let mut r = reader(p, section_offset(p, section))?;
        let count = p.header.sections[section] / 8;
        if count > 0 {
            heap.push(Next(read(&mut r, p)?, k));
        }
        readers.push(r);
        left.push(count.saturating_sub(1));
    }
    let mut out = Vec::with_capacity(ranks.len());
    let mut want = ranks.iter().peekable();
    let mut rank = 0u64;
    while let Some(&&w) = want.peek() {
        let Next(x, k) = heap
            .pop()
            .ok_or_else(|| format!("section {section} has fewer than {} values", w + 1))?;
        while want.peek() == Some(&&rank) {
            out.push(x);
            want.next();
        }
        rank += 1;
        if left[k] > 0 {
            left[k] -= 1;
            heap.push(Next(read(&mut readers[k], &parts[k])?, k));
        }
    }
    Ok(out)
}

/// The run records of a migration's parts (sorted by start, tiling 0..N).
struct PartRuns<'a>(&'a [Part]);

/// A key ordered by `f64::total_cmp`, smallest first in a max-heap.
struct Next(f64, usize);

impl PartialEq for Next {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == std::cmp::Ordering::Equal
    }
}
impl Eq for Next {}
impl PartialOrd for Next {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Next {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl RunRecords for PartRuns<'_> {
    type Error = String;

    fn runs(&self) -> u64 {
        self.0.first().map_or(0, |p| p.header.items)
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&RunSummary)) -> Result<(), String> {
        let mut buf = [0u8; RUN_RECORD_BYTES as usize];
        for p in self.0 {
            let mut r = reader(p, 0)?;
            for _ in p.header.start..p.header.end {
                r.read_exact(&mut buf)
                    .map_err(|e| format!("{}: {e}", p.path.display()))?;
                f(&decode_run(&buf).map_err(|e| format!("{}: {e}", p.path.display()))?);
            }
        }
        Ok(())
    }

    fn order_values(&self, col: usize, ranks: &[u64]) -> Result<Vec<f64>, String> {
        merged_order_values(self.0, col + 1, ranks)
    }
}

/// The run records of one method of a scene's parts (sorted by start, tiling 0..N): its records
/// in section `first`, then five sorted columns per support entry.
struct SceneRuns<'a> {
    parts: &'a [Part],
    first: usize,
    limits: usize,
}

impl SceneRecords for SceneRuns<'_> {
    type Error = String;

    fn runs(&self) -> u64 {
        self.parts.first().map_or(0, |p| p.header.items)
    }

    fn for_each_run(&self, f: &mut dyn FnMut(&SceneRun)) -> Result<(), String> {
        let mut buf = [0u8; SCENE_RECORD_BYTES as usize];
        for p in self.parts {
            let mut r = reader(p, section_offset(p, self.first))?;
            for _ in p.header.start..p.header.end {
                r.read_exact(&mut buf)
                    .map_err(|e| format!("{}: {e}", p.path.display()))?;
                f(&decode_scene_run(&buf, self.limits)
                    .map_err(|e| format!("{}: {e}", p.path.display()))?);
            }
        }
        Ok(())
    }

    fn order_values(&self, entry: usize, col: usize, ranks: &[u64]) -> Result<Vec<f64>, String> {
        merged_order_values(
            self.parts,
            self.first + 1 + entry * ENTRY_COLUMNS + col,
            ranks,
        )
    }
}

/// `gangue merge`: checks the parts and writes the response body to `out`; `wire` reads the
/// request and writes the answer.
pub fn merge<W: Wire>(args: &MergeArgs, wire: &W, out: &mut dyn Write) -> Result<(), Failure> {
    args.limits.validate()?;
    let mut parts = args
        .parts
        .iter()
        .map(|p| read_part(p))
        .collect::<Result<Vec<_>, _>>()?;
    check_parts(&mut parts)?;
    let h = parts[0].header.clone();
    let kind = Kind::from_name(&h.kind).ok_or_else(|| format!("unknown kind {:?}", h.kind))?;
    if h.build != build_id() {
        return Err(Failure::from(format!(
            "the parts were computed by {}, this merge is {}: merge with the same gangue binary",
            h.build,
            build_id()
        )));
    }
    let config = &args.limits;
    let r = resolve(wire, kind, h.request.as_bytes(), config)?;
    if r.hash != h.inputs_sha256 {
        return Err(Failure::from(
            "the request resolves to other inputs under this merge's limits than under the \
             parts': give the merge the same limit flags as the computation"
                .to_string(),
        ));
    }
    let ctl = control(args.time_limit_s);
    let bytes = match r.prepared {
        Prepared::Migration { case, req } => {
            let report =
                calc::migration::merge(&case, &PartRuns(&parts), &ctl).map_err(|e| match e {
                    MergeError::Physics(e) => wire.physics_failure(e),
                    MergeError::Records(e) => Failure::from(e),
                })?;
            wire.migration_answer(report, *req)?
        }
        Prepared::Scene { case, req, .. } => {
            let ensemble = calc::scene::ensemble(&case);
            let per = 1 + case.supports.len() * ENTRY_COLUMNS;
            let streams = match ensemble {
                Some(_) => 1 + usize::from(case.compare_methods),
                None => 0,
            };
            check_sections(
                &parts,
                streams * per + 1,
                ensemble.map(|_| SCENE_RECORD_BYTES),
            )?;
            let p0 = part_zero(&parts, "the nominal run and its impacts")?;
            let head: W::SceneHead = serde_json::from_slice(&read_section(p0, streams * per)?)
                .map_err(|e| {
                    format!(
                        "{}: the stored nominal part is damaged: {e}",
                        p0.path.display()
                    )
                })?;
            let limits = case.limits.active().len();
            let main = SceneRuns {
                parts: &parts,
                first: 0,
                limits,
            };
            let other = case.compare_methods.then_some(SceneRuns {
                parts: &parts,
                first: per,
                limits,
            });
            let tail = calc::scene::merge(
                &case,
                W::nominal_capacity(&head),
                &main,
                other.as_ref(),
                W::keep_runs(&req),
            )?;
            wire.scene_answer(head, tail, &case, *req)?
        }
        Prepared::Study(plan) => {
            check_sections(&parts, 2, None)?;
            let mut results = Vec::with_capacity(W::study_points(&plan) as usize);
            let p0 = part_zero(&parts, "the study's base point")?;
            let base = read_section(p0, 1)?;
            let (len, values) = base.split_first_chunk::<8>().ok_or_else(|| {
                format!("{}: the stored base point is damaged", p0.path.display())
            })?;
            let len = u64::from_le_bytes(*len);
            if values.len() as u64 != len * 8 {
                return Err(Failure::from(format!(
                    "{}: the stored base point is damaged",
                    p0.path.display()
                )));
            }
            results.push(
                values
                    .chunks_exact(8)
                    .map(|b| f64::from_le_bytes(std::array::from_fn(|i| b[i])))
                    .collect(),
            );
            for p in &parts {
                let mut r = reader(p, 0)?;
                for _ in p.header.start..p.header.end {
                    let len = read_u64(&mut r, p)?;
                    let mut v = Vec::with_capacity(len.min(1 << 16) as usize);
                    for _ in 0..len {
                        v.push(f64::from_bits(read_u64(&mut r, p)?));
                    }
                    results.push(v);
                }
            }
            wire.study_answer(*plan, results)?
        }
        Prepared::Batch(_) => {
            // the answer lines, streamed in index order
            for p in &parts {
                let mut r = reader(p, 0)?;
                for _ in p.header.start..p.header.end {
                    let len = read_u64(&mut r, p)?;
                    let mut l = vec![0u8; len as usize];
                    r.read_exact(&mut l)
                        .map_err(|e| format!("{}: {e}", p.path.display()))?;
                    out.write_all(&l)
                        .map_err(|e| format!("writing the answer: {e}"))?;
                }
            }
            Vec::new()
        }
    };
    out.write_all(&bytes)
        .and_then(|()| out.flush())
        .map_err(|e| Failure::from(format!("writing the answer: {e}")))
}

fn read_u64(r: &mut BufReader<File>, p: &Part) -> Result<u64, String> {
    let mut b = [0u8; 8];
    r.read_exact(&mut b)
        .map_err(|e| format!("{}: {e}", p.path.display()))?;
    Ok(u64::from_le_bytes(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_ranges_tile_the_items() {
        for n in [0u64, 1, 2, 7, 100, 1_000_003] {
            for k in [1u64, 2, 3, 7, 64] {
                let mut next = 0;
                for i in 0..k {
                    let r = shard_range(i, k, n);
                    assert_eq!(r.start, next);
                    next = r.end;
                }
                assert_eq!(next, n);
            }
        }
        assert_eq!(shard_range(1, 3, 10), 3..6);
    }

    #[test]
    fn run_records_round_trip() {
        let r = RunSummary {
            time: 1.5,
            speed: -0.0,
            kinetic_energy: 3e300,
            impact_count: 7,
            runout: 5e-324,
            max_bounce_height: 0.25,
            stop_reason: StopReason::LeftFloor,
            steps: u64::MAX,
            along_dip_velocity: -2.5,
            support: Some(3),
            impact_speed: 1.25,
        };
        let mut b = Vec::new();
        encode_run(&r, &mut b);
        assert_eq!(b.len() as u64, RUN_RECORD_BYTES);
        let back = decode_run(b.as_slice().try_into().unwrap()).unwrap();
        assert_eq!(back.speed.to_bits(), r.speed.to_bits());
        assert_eq!(back, r);
    }

    #[test]
    fn scene_run_records_round_trip() {
        let summary = RunSummary {
            time: 0.0,
            speed: 4.5,
            kinetic_energy: 12.0,
            impact_count: 2,
            runout: 7.25,
            max_bounce_height: 0.125,
            stop_reason: StopReason::Support,
            steps: 99,
            along_dip_velocity: 4.0,
            support: Some(2),
            impact_speed: 3.75,
        };
        let runs = [
            SceneRun {
                summary,
                values: Some(StrikeValues {
                    max_deformation: 1e-3,
                    max_force: -0.0,
                    absorbed_energy: 5e-324,
                    stress_utilisation: 1.5,
                }),
                capacity_exceeded: false,
                exceeded: vec![true, false, true],
            },
            SceneRun {
                summary,
                values: None,
                capacity_exceeded: true,
                exceeded: vec![true, true, true],
            },
            SceneRun {
                summary: RunSummary {
                    support: None,
                    stop_reason: StopReason::AtRest,
                    ..summary
                },
                values: None,
                capacity_exceeded: false,
                exceeded: vec![false, false, false],
            },
        ];
        for r in &runs {
            let mut b = Vec::new();
            encode_scene_run(r, &mut b);
            assert_eq!(b.len() as u64, SCENE_RECORD_BYTES);
            let back = decode_scene_run(b.as_slice().try_into().unwrap(), 3).unwrap();
            assert_eq!(&back, r);
            if let (Some(a), Some(b)) = (back.values, r.values) {
                assert_eq!(a.max_force.to_bits(), b.max_force.to_bits());
            }
            // a record of more limits than the request has is refused
            assert!(
                decode_scene_run(b.as_slice().try_into().unwrap(), 1).is_err()
                    || r.exceeded[1..].iter().all(|e| !e)
            );
        }
    }

    fn args(shard: Option<&str>, shards: Option<u64>, offset: u64) -> ComputeArgs {
        ComputeArgs {
            request: "case.json".into(),
            kind: Kind::Migration,
            shard: shard.map(Into::into),
            shards,
            index_offset: offset,
            out: "part-{shard}".into(),
            time_limit_s: None,
            limits: Config::default(),
        }
    }

    #[test]
    fn shard_index_from_flags_and_schedulers() {
        let none = |_: &str| None;
        assert_eq!(shard_of(&args(Some("2/5"), None, 0), &none), Ok((2, 5)));
        assert_eq!(shard_of(&args(None, None, 0), &none), Ok((0, 1)));
        let k8s = |n: &str| (n == "JOB_COMPLETION_INDEX").then(|| "3".to_string());
        assert_eq!(shard_of(&args(None, Some(8), 0), &k8s), Ok((3, 8)));
        assert!(
            shard_of(&args(None, None, 0), &k8s)
                .unwrap_err()
                .contains("--shards")
        );
        let slurm = |n: &str| match n {
            "SLURM_ARRAY_TASK_ID" => Some("1".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("4".to_string()),
            _ => None,
        };
        assert_eq!(shard_of(&args(None, None, 0), &slurm), Ok((1, 4)));
        // a second array of a split: offset 4, 7 shards in all
        assert_eq!(shard_of(&args(None, Some(7), 4), &slurm), Ok((5, 7)));
        let aws = |n: &str| (n == "AWS_BATCH_JOB_ARRAY_INDEX").then(|| "0".to_string());
        assert_eq!(shard_of(&args(None, Some(2), 0), &aws), Ok((0, 2)));
        for bad in ["3", "1/0", "a/3", "3/3"] {
            assert!(shard_of(&args(Some(bad), None, 0), &none).is_err(), "{bad}");
        }
    }
}

//! Server settings and limits: one struct, documented defaults, settable by flags or environment.

use std::net::SocketAddr;
use std::time::Duration;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// Settings of the service. Every field has a flag and an environment variable; `--help` lists them.
#[derive(Debug, Clone, Parser, PartialEq)]
#[command(
    name = "gangue",
    version,
    about = "Flying-gangue (rockfall) hazard calculation service"
)]
pub struct Config {
    /// Address to listen on (default 127.0.0.1:8080).
    #[arg(long, env = "GANGUE_BIND", default_value = "127.0.0.1:8080")]
    pub bind: SocketAddr,

    /// Threads for parallel ensembles (default: the number of cores; results do not depend on it).
    #[arg(long, env = "GANGUE_SOLVER_THREADS")]
    pub solver_threads: Option<usize>,

    /// Niceness of the solver threads, 0–19 (default 0, the normal priority): above 0 the
    /// computations run below the threads that accept connections and answer `/healthz` (Linux:
    /// `setpriority` per solver thread; elsewhere ignored). Only for a host or container of its
    /// own: niceness also ranks the solvers below every other process (BENCHMARKS.md).
    #[arg(long, env = "GANGUE_SOLVER_NICE", default_value_t = 0)]
    pub solver_nice: i32,

    /// Computations (solver slots) at once; more queue for a slot (default 2 × cores, at least 4).
    #[arg(long, env = "GANGUE_MAX_CONCURRENT")]
    pub max_concurrent: Option<usize>,

    /// Longest expected queue wait for a solver slot, ms (default 100); past it 503 + Retry-After.
    /// Expected wait = mean recent solve time × (queued + 1) / slots; a queued request waits at
    /// most twice this.
    #[arg(long, env = "GANGUE_MAX_QUEUE_WAIT_MS", default_value_t = 100.0)]
    pub max_queue_wait_ms: f64,

    /// Time to receive a request's head, s (default 10); also the idle keep-alive timeout (from
    /// the end of one answer to the head of the next). Past it the connection is closed.
    #[arg(long, env = "GANGUE_HEADER_TIMEOUT_S", default_value_t = 10.0)]
    pub header_timeout_s: f64,

    /// Time to receive a request's whole body once its head is in, s (default 30); past it 408.
    #[arg(long, env = "GANGUE_BODY_TIMEOUT_S", default_value_t = 30.0)]
    pub body_timeout_s: f64,

    /// Request body bytes held at once across all requests (default 4 × the body limit); a body
    /// is admitted against it by its declared length (the body limit when not declared) before it
    /// is read and released when the answer is done; a body that cannot be admitted within twice
    /// the longest queue wait gets 503 + Retry-After.
    #[arg(long, env = "GANGUE_BODY_BUDGET_BYTES")]
    pub body_budget_bytes: Option<usize>,

    /// Largest request body, bytes (default 16 MiB).
    #[arg(long, env = "GANGUE_MAX_BODY_BYTES", default_value_t = 16 * 1024 * 1024)]
    pub max_body_bytes: usize,

    /// Time limit of one computation, s (default 60); past it the work is stopped and 504 returned.
    #[arg(long, env = "GANGUE_COMPUTE_TIMEOUT_S", default_value_t = 60.0)]
    pub compute_timeout_s: f64,

    /// Most Monte Carlo runs in one request (default 1 000 000).
    #[arg(long, env = "GANGUE_MAX_RUNS", default_value_t = 1_000_000)]
    pub max_runs: u64,

    /// Most history or trajectory samples in one response (default 1 000 000).
    #[arg(long, env = "GANGUE_MAX_SAMPLES", default_value_t = 1_000_000)]
    pub max_samples: u64,

    /// Most points of a force–approach curve (default 10 000).
    #[arg(long, env = "GANGUE_MAX_CURVE_POINTS", default_value_t = 10_000)]
    pub max_curve_points: u64,

    /// Most Galerkin modes of the coupled column model (default 50).
    #[arg(long, env = "GANGUE_MAX_MODES", default_value_t = 50)]
    pub max_modes: u64,

    /// Longest simulated end time of the coupled column model, s (default 1000).
    #[arg(long, env = "GANGUE_MAX_END_TIME_S", default_value_t = 1e3)]
    pub max_end_time_s: f64,

    /// Most points per study curve (default 101).
    #[arg(long, env = "GANGUE_MAX_STUDY_POINTS", default_value_t = 101)]
    pub max_study_points: u64,

    /// Most items in one batch (default 1000).
    #[arg(long, env = "GANGUE_MAX_BATCH_ITEMS", default_value_t = 1000)]
    pub max_batch_items: u64,

    /// Largest estimated memory of one floor (grid or resampled contours), bytes (default 512 MiB);
    /// the estimate is made before the floor is built (README "Limits").
    #[arg(long, env = "GANGUE_MAX_FLOOR_BYTES", default_value_t = 512 * 1024 * 1024)]
    pub max_floor_bytes: u64,

    /// Most cells of an ensemble's per-cell maps (default 250 000).
    #[arg(long, env = "GANGUE_MAX_MAP_CELLS", default_value_t = 250_000)]
    pub max_map_cells: u64,

    /// Largest cells × runs of an ensemble's per-cell maps (default 5e7): the work and memory
    /// bound of the maps, 40 bytes per run entering a cell (README "Limits").
    #[arg(long, env = "GANGUE_MAX_MAP_CELL_RUNS", default_value_t = 50_000_000)]
    pub max_map_cell_runs: u64,

    /// Most time steps of one rigid-block run (default 2e7).
    #[arg(long, env = "GANGUE_MAX_RIGID_STEPS", default_value_t = 2e7)]
    pub max_rigid_steps: f64,

    /// Largest estimated work of a scene's design search for guards, in chain evaluations
    /// (default 4e6): inverses × 120 evaluations each, the inverses being one per active limit
    /// and distinct guarded column, or per run when the rock is drawn (README "Limits").
    #[arg(
        long,
        env = "GANGUE_MAX_DESIGN_EVALUATIONS",
        default_value_t = 4_000_000
    )]
    pub max_design_evaluations: u64,
}

/// The command line: the server (no subcommand, or `serve`), or a sharded computation.
#[derive(Debug, Clone, Parser)]
#[command(
    name = "gangue",
    version,
    about = "Flying-gangue (rockfall) hazard calculation service",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    /// What to do (default: serve).
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Server settings when no subcommand is given.
    #[command(flatten)]
    pub config: Config,
}

/// Subcommands.
#[derive(Debug, Clone, Subcommand)]
pub enum Command {
    /// Start the HTTP service (the default).
    Serve(Config),
    /// Compute one shard of a request's work items into a part file.
    Compute(ComputeArgs),
    /// Merge part files into the response `POST` of the request returns (to standard output).
    Merge(MergeArgs),
}

/// Kind of request of a sharded computation (the `POST /v1/{kind}` route).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Kind {
    /// `POST /v1/migration` (items: Monte Carlo runs).
    Migration,
    /// `POST /v1/scene` (items: Monte Carlo runs).
    Scene,
    /// `POST /v1/study` (items: study points after the base).
    Study,
    /// `POST /v1/batch` (items: batch items).
    Batch,
}

impl Kind {
    /// The route's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Kind::Migration => "migration",
            Kind::Scene => "scene",
            Kind::Study => "study",
            Kind::Batch => "batch",
        }
    }

    /// The kind of a route name.
    #[must_use]
    pub fn from_name(s: &str) -> Option<Self> {
        [Kind::Migration, Kind::Scene, Kind::Study, Kind::Batch]
            .into_iter()
            .find(|k| k.name() == s)
    }
}

/// `gangue compute`: one shard of a request.
#[derive(Debug, Clone, Args)]
pub struct ComputeArgs {
    /// The request body (JSON; a batch may also be NDJSON), as it would be POSTed.
    #[arg(long)]
    pub request: std::path::PathBuf,
    /// The route the request is for.
    #[arg(long, value_enum)]
    pub kind: Kind,
    /// Shard I of K (0-based), for example 0/3; otherwise from JOB_COMPLETION_INDEX,
    /// SLURM_ARRAY_TASK_ID or AWS_BATCH_JOB_ARRAY_INDEX with --shards (default 0/1).
    #[arg(long)]
    pub shard: Option<String>,
    /// Shard count K when the index comes from the environment (Slurm: default
    /// SLURM_ARRAY_TASK_COUNT).
    #[arg(long)]
    pub shards: Option<u64>,
    /// Added to the shard index from the environment or --shard (arrays split past the
    /// scheduler's size limit), default 0.
    #[arg(long, default_value_t = 0)]
    pub index_offset: u64,
    /// Part file to write; `{shard}` is replaced by the shard index.
    #[arg(long)]
    pub out: String,
    /// Time limit of the computation (of each item for a batch), s (default: none).
    #[arg(long)]
    pub time_limit_s: Option<f64>,
    /// The service's limits (the same flags and environment variables).
    #[command(flatten)]
    pub limits: Config,
}

/// `gangue merge`: part files to one response.
#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// The part files of every shard, in any order.
    #[arg(required = true)]
    pub parts: Vec<std::path::PathBuf>,
    /// Time limit of the merge's own computation (the nominal run or the study base), s (default:
    /// none).
    #[arg(long)]
    pub time_limit_s: Option<f64>,
    /// The service's limits (the same flags and environment variables as the computation).
    #[command(flatten)]
    pub limits: Config,
}

impl Default for Config {
    fn default() -> Self {
        Self::parse_from(["gangue"])
    }
}

impl Config {
    /// Threads for parallel ensembles: the setting, or the number of cores.
    pub fn solver_threads(&self) -> usize {
        self.solver_threads.unwrap_or_else(cores).max(1)
    }

    /// Computations allowed at once: the setting, or max(4, 2 × cores).
    #[must_use]
    pub fn max_concurrent(&self) -> usize {
        self.max_concurrent
            .unwrap_or_else(|| (2 * cores()).max(4))
            .max(1)
    }

    /// Longest expected queue wait admitted (`max_queue_wait_ms`).
    #[must_use]
    pub fn max_queue_wait(&self) -> Duration {
        Duration::from_secs_f64(self.max_queue_wait_ms / 1e3)
    }

    /// Time to receive a request head, also the idle keep-alive timeout.
    #[must_use]
    pub fn header_timeout(&self) -> Duration {
        Duration::from_secs_f64(self.header_timeout_s)
    }

    /// Time to receive a request body.
    #[must_use]
    pub fn body_timeout(&self) -> Duration {
        Duration::from_secs_f64(self.body_timeout_s)
    }

    /// Request body bytes held at once: the setting, or 4 × the body limit (at least the limit).
    #[must_use]
    pub fn body_budget_bytes(&self) -> usize {
        self.body_budget_bytes
            .unwrap_or(self.max_body_bytes.saturating_mul(4))
            .max(self.max_body_bytes)
    }

    /// Checks the settings for values that cannot work; the message names the flag.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.compute_timeout_s.is_finite() && self.compute_timeout_s > 0.0) {
            return Err(format!(
                "--compute-timeout-s must be a positive number of seconds, got {}",
                self.compute_timeout_s
            ));
        }
        if !(self.max_end_time_s.is_finite() && self.max_end_time_s > 0.0) {
            return Err("--max-end-time-s must be positive".into());
        }
        if !(self.max_rigid_steps.is_finite() && self.max_rigid_steps >= 1.0) {
            return Err("--max-rigid-steps must be at least 1".into());
        }
        for (flag, v, max) in [
            ("--max-queue-wait-ms", self.max_queue_wait_ms, 3.6e6),
            ("--header-timeout-s", self.header_timeout_s, 3600.0),
            ("--body-timeout-s", self.body_timeout_s, 3600.0),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= max) {
                return Err(format!("{flag} must be in (0, {max}], got {v}"));
            }
        }
        if !(0..=19).contains(&self.solver_nice) {
            return Err(format!(
                "--solver-nice must be in [0, 19], got {}",
                self.solver_nice
            ));
        }
        if self.max_body_bytes < 1024 {
            return Err("--max-body-bytes must be at least 1024".into());
        }
        Ok(())
    }
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_documented_ones() {
        let c = Config::default();
        assert_eq!(c.bind.to_string(), "127.0.0.1:8080");
        assert_eq!(c.max_body_bytes, 16 * 1024 * 1024);
        assert_eq!(c.compute_timeout_s, 60.0);
        assert_eq!(c.max_runs, 1_000_000);
        assert_eq!(c.max_samples, 1_000_000);
        assert_eq!(c.max_study_points, 101);
        assert_eq!(c.max_batch_items, 1000);
        assert_eq!(c.max_rigid_steps, 2e7);
        assert_eq!(c.max_queue_wait(), Duration::from_millis(100));
        assert_eq!(c.header_timeout(), Duration::from_secs(10));
        assert_eq!(c.body_timeout(), Duration::from_secs(30));
        assert_eq!(c.body_budget_bytes(), 64 * 1024 * 1024);
        assert!(c.validate().is_ok());
    }

    #[test]
    fn flags_override_defaults_and_bad_values_are_named() {
        let c = Config::parse_from([
            "gangue",
            "--bind",
            "0.0.0.0:9000",
            "--compute-timeout-s",
            "0",
        ]);
        assert_eq!(c.bind.port(), 9000);
        assert!(c.validate().unwrap_err().contains("--compute-timeout-s"));
        for flag in [
            "--max-queue-wait-ms",
            "--header-timeout-s",
            "--body-timeout-s",
        ] {
            let c = Config::parse_from(["gangue", flag, "0"]);
            assert!(c.validate().unwrap_err().contains(flag), "{flag}");
        }
    }

    #[test]
    fn no_subcommand_or_serve_starts_the_server_with_the_same_flags() {
        let c = Cli::parse_from(["gangue", "--bind", "0.0.0.0:9000", "--max-runs", "7"]);
        assert!(c.command.is_none());
        assert_eq!((c.config.bind.port(), c.config.max_runs), (9000, 7));
        let c = Cli::parse_from(["gangue", "serve", "--bind", "0.0.0.0:9001"]);
        match c.command {
            Some(Command::Serve(s)) => assert_eq!(s.bind.port(), 9001),
            other => panic!("{other:?}"),
        }
        let c = Cli::parse_from([
            "gangue",
            "compute",
            "--request",
            "case.json",
            "--kind",
            "study",
            "--shard",
            "1/3",
            "--out",
            "part-1",
            "--max-study-points",
            "11",
        ]);
        match c.command {
            Some(Command::Compute(a)) => {
                assert_eq!(a.kind, Kind::Study);
                assert_eq!(a.shard.as_deref(), Some("1/3"));
                assert_eq!(a.limits.max_study_points, 11);
                assert_eq!(a.time_limit_s, None, "no time limit by default");
            }
            other => panic!("{other:?}"),
        }
        assert!(
            Cli::try_parse_from(["gangue", "merge"]).is_err(),
            "parts are required"
        );
    }
}

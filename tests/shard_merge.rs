//! Sharded computations (`gangue compute` + `gangue merge`) against the service. Expectation:
//! whatever the number of shards, the merged answer is the bytes `POST` of the same request
//! returns through the router with the same limits — statistics, exact percentiles, histograms
//! and runs_csv included — because run i is seeded by (seed, i) whatever the shard and the merge
//! sums in run order. Parts of different requests, a missing index range or one given twice are
//! refused with a message naming the problem; a shard computed twice is harmless.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicU32, Ordering};

use serde_json::{Value, json};

const BIN: &str = env!("CARGO_BIN_EXE_gangue");

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    static N: AtomicU32 = AtomicU32::new(0);
    let d = std::env::temp_dir().join(format!(
        "gangue-shard-{}-{name}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> Output {
    // the shard index must come from the flags here, not from a scheduler's environment
    Command::new(BIN)
        .args(args)
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_COUNT")
        .env_remove("AWS_BATCH_JOB_ARRAY_INDEX")
        .env("GANGUE_SOLVER_THREADS", "2")
        .output()
        .expect("the gangue binary runs")
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Computes shard i of k of `request` into `dir/part-i`.
fn compute(dir: &Path, request: &Path, kind: &str, i: u64, k: u64) -> PathBuf {
    let out = dir.join(format!("part-{i}"));
    let o = run(&[
        "compute",
        "--request",
        request.to_str().unwrap(),
        "--kind",
        kind,
        "--shard",
        &format!("{i}/{k}"),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "compute {i}/{k}: {}", text(&o));
    out
}

fn merge(parts: &[PathBuf]) -> Output {
    let mut args = vec!["merge".to_string()];
    args.extend(parts.iter().map(|p| p.to_str().unwrap().to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    run(&args)
}

fn write_request(dir: &Path, body: &Value) -> PathBuf {
    let p = dir.join("case.json");
    std::fs::write(&p, serde_json::to_vec_pretty(body).unwrap()).unwrap();
    p
}

async fn http_body(path: &str, body: &Value) -> Vec<u8> {
    let r = common::post(&common::app(), path, body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    r.body
}

/// 1, 3 and 7 shards of `body` merge to the HTTP answer, byte for byte.
async fn same_bytes_for_any_split(name: &str, kind: &str, body: &Value) {
    let want = http_body(&format!("/v1/{kind}"), body).await;
    for k in [1u64, 3, 7] {
        let dir = scratch(&format!("{name}-{k}"));
        let req = write_request(&dir, body);
        // computed in reverse order: the merge sorts the parts by their item ranges
        let parts: Vec<PathBuf> = (0..k)
            .rev()
            .map(|i| compute(&dir, &req, kind, i, k))
            .collect();
        let o = merge(&parts);
        assert!(o.status.success(), "merge of {k}: {}", text(&o));
        if o.stdout != want {
            let got: Value = serde_json::from_slice(&o.stdout).unwrap_or(Value::Null);
            let want: Value = serde_json::from_slice(&want).unwrap_or(Value::Null);
            panic!("{name}, {k} shards: merged answer differs\n got {got}\nwant {want}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

fn migration_request() -> Value {
    json!({
        "face": {"dip_deg": 35.0, "length_m": 60.0, "friction_coefficient": 0.45},
        "release": {"drop_height_m": 2.0},
        "monte_carlo": {"runs": 1001, "seed": 7,
            "friction_coefficient": {"distribution": "normal", "mean": 0.45, "std": 0.2}},
        "output": {"runs_csv": true, "events": false}
    })
}

#[tokio::test]
async fn migration_ensemble_shards_merge_to_the_http_answer() {
    let body = migration_request();
    // the ensemble must exercise both kinds of runs: some reach the lower end, some stop
    let v: Value = serde_json::from_slice(&http_body("/v1/migration", &body).await).unwrap();
    let f = v["statistics"]["reached_fraction"].as_f64().unwrap();
    assert!(f > 0.05 && f < 0.95, "reached fraction {f}");
    same_bytes_for_any_split("migration", "migration", &body).await;
}

#[tokio::test]
async fn rigid_block_ensemble_shards_merge_to_the_http_answer() {
    let body = json!({
        "method": "rigid_block",
        "face": {"dip_deg": 40.0, "length_m": 6.0},
        "release": {"drop_height_m": 0.5},
        "monte_carlo": {"runs": 9, "seed": 3}
    });
    same_bytes_for_any_split("rigid", "migration", &body).await;
}

#[tokio::test]
async fn study_shards_merge_to_the_http_answer() {
    let body = json!({
        "base": {"contact": {"effective_modulus": "two_body"}},
        "points": 4,
        "grid": "pairs",
        "parameters": [
            {"name": "velocity_m_s", "min": 3.0, "max": 7.0},
            {"name": "rock.side_length_m", "min": 0.2, "max": 0.5},
            {"name": "column.length_m", "min": 1.0, "max": 2.0}
        ]
    });
    same_bytes_for_any_split("study", "study", &body).await;
}

#[tokio::test]
async fn batch_shards_merge_to_the_http_answer() {
    let body = json!({"items": [
        {"kind": "impact", "request": {}},
        {"kind": "migration", "request": {"monte_carlo": {"runs": 20}}},
        {"kind": "impact", "request": {"velocity_m_s": -1.0}},
        {"kind": "column", "request": {}}
    ]});
    same_bytes_for_any_split("batch", "batch", &body).await;
}

/// Three parts of the migration request in `dir`.
fn three_parts(dir: &Path, body: &Value) -> Vec<PathBuf> {
    let req = write_request(dir, body);
    (0..3)
        .map(|i| compute(dir, &req, "migration", i, 3))
        .collect()
}

#[test]
fn a_missing_part_is_refused() {
    let dir = scratch("missing");
    let p = three_parts(&dir, &migration_request());
    let o = merge(&[p[0].clone(), p[2].clone()]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty(), "nothing written on a refusal");
    let e = text(&o);
    assert!(e.contains("items 333 to 666 are missing"), "{e}");
    let o = merge(&[p[0].clone(), p[1].clone()]);
    assert!(
        text(&o).contains("items 667 to 1000 of 1001 are missing"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_duplicated_part_is_refused() {
    let dir = scratch("dup");
    let p = three_parts(&dir, &migration_request());
    let copy = dir.join("copy-of-part-1");
    std::fs::copy(&p[1], &copy).unwrap();
    let o = merge(&[p[0].clone(), p[1].clone(), copy, p[2].clone()]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty());
    let e = text(&o);
    assert!(e.contains("items 333 to 666 are in two parts"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn parts_of_different_requests_are_refused() {
    let a = scratch("req-a");
    let b = scratch("req-b");
    let pa = three_parts(&a, &migration_request());
    let mut other = migration_request();
    other["monte_carlo"]["seed"] = json!(8);
    let pb = three_parts(&b, &other);
    let o = merge(&[pa[0].clone(), pb[1].clone(), pb[2].clone()]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty());
    assert!(
        text(&o).contains("parts of different requests"),
        "{}",
        text(&o)
    );
    // and a file that is not a part at all
    let o = merge(&[a.join("case.json")]);
    assert!(text(&o).contains("not a gangue part file"), "{}", text(&o));
    // a truncated part
    let bytes = std::fs::read(&pa[1]).unwrap();
    std::fs::write(&pa[1], &bytes[..bytes.len() - 3]).unwrap();
    let o = merge(&pa);
    assert!(text(&o).contains("truncated or damaged"), "{}", text(&o));
    std::fs::remove_dir_all(&a).unwrap();
    std::fs::remove_dir_all(&b).unwrap();
}

#[tokio::test]
async fn a_shard_run_twice_is_harmless() {
    let dir = scratch("twice");
    let body = migration_request();
    let req = write_request(&dir, &body);
    let parts: Vec<PathBuf> = (0..3)
        .map(|i| compute(&dir, &req, "migration", i, 3))
        .collect();
    let first = std::fs::read(&parts[1]).unwrap();
    compute(&dir, &req, "migration", 1, 3);
    assert_eq!(
        std::fs::read(&parts[1]).unwrap(),
        first,
        "the same part again"
    );
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 4, "no temporary file left behind: {names:?}");
    let o = merge(&parts);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(o.stdout, http_body("/v1/migration", &body).await);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn shard_index_from_a_scheduler_with_an_offset() {
    let dir = scratch("env");
    let req = write_request(&dir, &migration_request());
    let out = dir.join("part-{shard}");
    // Slurm array task 1 of a second array of 2 (offset 1) of 3 shards in all: shard 2
    let o = Command::new(BIN)
        .args([
            "compute",
            "--request",
            req.to_str().unwrap(),
            "--kind",
            "migration",
            "--shards",
            "3",
            "--index-offset",
            "1",
            "--out",
            out.to_str().unwrap(),
        ])
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("AWS_BATCH_JOB_ARRAY_INDEX")
        .env("SLURM_ARRAY_TASK_ID", "1")
        .env("SLURM_ARRAY_TASK_COUNT", "2")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let part = std::fs::read(dir.join("part-2")).unwrap();
    let header: Value =
        serde_json::from_slice(&part[..part.iter().position(|&b| b == b'\n').unwrap()]).unwrap();
    assert_eq!(
        (header["shard"].as_u64(), header["shards"].as_u64()),
        (Some(2), Some(3))
    );
    assert_eq!(
        (header["start"].as_u64(), header["end"].as_u64()),
        (Some(667), Some(1001))
    );
    // an index past the count is refused
    let o = run(&[
        "compute",
        "--request",
        req.to_str().unwrap(),
        "--kind",
        "migration",
        "--shard",
        "3/3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("not below the shard count 3"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

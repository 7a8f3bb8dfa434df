//! Sharded computations (`gangue compute` + `gangue merge`) against the service. Expectation:
//! whatever the number of shards, the merged answer is the bytes `POST` of the same request
//! returns through the router with the same limits — statistics, exact percentiles, histograms
//! and runs_csv included — because run i is seeded by (seed, i) whatever the shard and the merge
//! sums in run order. Parts of different requests, a missing index range or one given twice are
//! refused with a message naming the problem; a shard computed twice is harmless.

mod common;

use common::gangue_cli as run;

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

/// A scene ensemble over a few supports: columns across the face that some runs pass by, a
/// spanning support lower down, friction and the release across the face drawn, so that some
/// runs reach no support (they stop or pass the columns) and the others end at one of several.
fn scene_request(runs: u64) -> Value {
    json!({
        "face": {"dip_deg": 35.0, "length_m": 40.0, "friction_coefficient": 0.45},
        "release": {"drop_height_m": 1.0},
        "supports": [
            {"along_dip_m": 10.0, "across_m": 0.0},
            {"along_dip_m": 18.0, "across_m": 0.8},
            {"along_dip_m": 26.0, "across_m": 30.0},
            {"along_dip_m": 34.0}
        ],
        "monte_carlo": {"runs": runs, "seed": 11,
            "friction_coefficient": {"distribution": "normal", "mean": 0.6, "std": 0.2},
            "release_across_m": {"distribution": "uniform", "min": -1.5, "max": 1.5},
            "side_length_m": {"distribution": "uniform", "min": 0.15, "max": 0.3}},
        "design_limits": {"stress_utilisation": 1.5, "max_force_n": 800000.0},
        "migration_output": {"runs_csv": true}
    })
}

#[tokio::test]
async fn scene_ensemble_shards_merge_to_the_http_answer() {
    let body = scene_request(61);
    // the ensemble must exercise every kind of run: no support, several supports reached, one
    // support never reached (null distributions), exceedances
    let v: Value = serde_json::from_slice(&http_body("/v1/scene", &body).await).unwrap();
    let st = &v["statistics"];
    let reached = st["outcomes"]["support"].as_f64().unwrap();
    assert!(
        reached > 0.05 && reached < 0.95,
        "support fraction {reached}"
    );
    let hit: Vec<f64> = st["supports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["reached_fraction"].as_f64().unwrap())
        .collect();
    assert!(hit.iter().filter(|&&f| f > 0.0).count() >= 2, "{hit:?}");
    assert!(hit.contains(&0.0), "a support nobody reaches: {hit:?}");
    let ex = st["any_exceeded"]["probability"].as_f64().unwrap();
    assert!(ex > 0.0 && ex < reached, "exceedance {ex}");
    assert!(v["migration"]["runs_csv"].as_str().unwrap().lines().count() == 62);
    // the allowed impacts (part 0's) with the design speeds (the merge's) are in the answer
    let allowed = v["allowed_impacts"].as_array().unwrap();
    assert!(
        allowed
            .iter()
            .any(|a| a["design_impact_velocity_m_s"].is_number()),
        "{allowed:?}"
    );
    // the per-run draws, stop positions and design values are part of what must merge to the
    // same bytes: present in the answer compared
    let head = v["migration"]["runs_csv"]
        .as_str()
        .unwrap()
        .lines()
        .next()
        .unwrap();
    assert!(
        head.ends_with(",release_along_dip_m,release_across_m,side_length_m,density_kg_m3,stop_along_dip_m,stop_across_m,translational_energy_j,rotational_energy_j,passing_height_m"),
        "{head}"
    );
    for (s, &f) in st["supports"].as_array().unwrap().iter().zip(&hit) {
        assert_eq!(s["design_values"].is_null(), f == 0.0, "{s}");
    }
    same_bytes_for_any_split("scene", "scene", &body).await;
    // and the frequencies of a release rate observed as a count
    let mut counted = body.clone();
    counted["release_rate"] = json!({"observed_events": 643, "observed_period_years": 0.75});
    // and guards, whose held / broken-through flags ride in the run records
    counted["guards"] =
        json!([{"support": 1, "energy_rating_j": 40.0}, {"support": 4, "energy_rating_j": 0.0}]);
    same_bytes_for_any_split("scene-rate", "scene", &counted).await;
}

#[test]
fn a_part_of_an_older_format_version_is_refused() {
    let dir = scratch("old-version");
    let req = write_request(&dir, &scene_request(4));
    let part = compute(&dir, &req, "scene", 0, 1);
    // the same part as version 3 wrote it would say so in its header line (the records of
    // version 3 were shorter: the release, rock, stop position and design values were not there)
    let bytes = std::fs::read(&part).unwrap();
    let header = String::from_utf8_lossy(&bytes);
    assert!(header.contains("\"version\":4"), "a version-4 header");
    let old = dir.join("part-old");
    let mut b = bytes.clone();
    let at = header.find("\"version\":4").unwrap() + "\"version\":".len();
    b[at] = b'3';
    std::fs::write(&old, &b).unwrap();
    let o = merge(&[old]);
    assert!(!o.status.success());
    let e = text(&o);
    assert!(
        e.contains("part format version 3 cannot be read by this build (it reads version 4)"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[tokio::test]
async fn scene_comparison_of_methods_shards_merge_to_the_http_answer() {
    let body = json!({
        "face": {"length_m": 15},
        "release": {"drop_height_m": 0.5},
        "supports": [{"along_dip_m": 8, "across_m": 0.3}, {"along_dip_m": 15}],
        "monte_carlo": {"runs": 6, "seed": 1,
            "release_across_m": {"distribution": "uniform", "min": -1.0, "max": 1.0}},
        "contact": {"law": "hertz_point"},
        "compare_methods": true,
    });
    let v: Value = serde_json::from_slice(&http_body("/v1/scene", &body).await).unwrap();
    assert_eq!(v["comparison"].as_array().unwrap().len(), 2);
    same_bytes_for_any_split("scene-compare", "scene", &body).await;
}

/// Scenes without an ensemble have no items: part 0 holds the whole answer, the other parts
/// are empty.
#[tokio::test]
async fn scenes_without_an_ensemble_shards_merge_to_the_http_answer() {
    let column = json!({"outer_diameter_m": 0.3, "inner_diameter_m": 0.27, "length_m": 1.5});
    let given_speed = json!({
        "impact_velocity_m_s": 6.5,
        "column_model": "coupled",
        "supports": [{"along_dip_m": 60, "column": column}, {"along_dip_m": 100}],
    });
    same_bytes_for_any_split("scene-speed", "scene", &given_speed).await;
    let single = json!({"face": {"length_m": 20}, "supports": [{"along_dip_m": 12}]});
    same_bytes_for_any_split("scene-single", "scene", &single).await;
}

/// The merge runs no solver for the nominal run and its strikes: part 0 stores them. Under a
/// time limit that has passed before it starts, the nominal run fails (computing part 0 is
/// refused), while the merge of the parts computed without a limit gives the service's answer.
#[tokio::test]
async fn the_merge_does_not_run_the_nominal_scene_again() {
    let mut body = scene_request(9);
    body["column_model"] = json!("coupled");
    body["release"] = json!({"drop_height_m": 1.0, "along_dip_m": 5.0});
    let want = http_body("/v1/scene", &body).await;
    let v: Value = serde_json::from_slice(&want).unwrap();
    assert!(
        v["impacts"][0]["column"].is_object(),
        "the nominal run strikes a coupled column: {}",
        v["impacts"]
    );
    let dir = scratch("scene-nominal");
    let req = write_request(&dir, &body);
    let parts: Vec<PathBuf> = (0..3).map(|i| compute(&dir, &req, "scene", i, 3)).collect();
    let expired = ["--time-limit-s", "1e-9"];
    let mut args = vec!["merge"];
    args.extend(expired);
    let names: Vec<String> = parts.iter().map(|p| p.display().to_string()).collect();
    args.extend(names.iter().map(String::as_str));
    let o = run(&args);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(o.stdout, want);
    let out = dir.join("again");
    let o = run(&[
        "compute",
        "--request",
        req.to_str().unwrap(),
        "--kind",
        "scene",
        "--shard",
        "0/3",
        "--time-limit-s",
        "1e-9",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success(),
        "part 0 under an expired limit must fail"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_scene_part_with_a_migration_part_is_refused() {
    let dir = scratch("scene-mixed");
    let req = write_request(&dir, &scene_request(6));
    let scene0 = compute(&dir, &req, "scene", 0, 2);
    let mdir = scratch("scene-mixed-m");
    let m = three_parts(&mdir, &migration_request());
    let o = merge(&[scene0, m[1].clone()]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty());
    assert!(
        text(&o).contains("parts of different kinds of request"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&mdir).unwrap();
}

/// Two runs in three shards: shard 0 has no run but carries the nominal run; without it the runs
/// still tile 0..2, and the merge refuses for the nominal part.
#[test]
fn a_scene_without_part_zero_is_refused() {
    let dir = scratch("scene-no-zero");
    let req = write_request(&dir, &scene_request(2));
    let p: Vec<PathBuf> = (0..3).map(|i| compute(&dir, &req, "scene", i, 3)).collect();
    let o = merge(&p[1..]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("part 0 (shard 0 of 3) is missing"),
        "{}",
        text(&o)
    );
    assert!(merge(&p).status.success());
    std::fs::remove_dir_all(&dir).unwrap();
}

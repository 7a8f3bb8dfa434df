//! Helpers shared by the integration tests: the router without a socket, JSON requests.
#![allow(dead_code, unreachable_pub)]

use axum::Router;
use axum::body::Body;
use axum::http::{HeaderMap, Method, Request, StatusCode, header};
use http_body_util::BodyExt;
use serde_json::Value;
use tower::ServiceExt;

use gangue::config::Config;

/// The service with default settings.
pub fn app() -> Router {
    gangue::app(Config::default())
}

/// The router and a runtime to drive it from synchronous code (a property test), made once
/// per test binary.
pub fn service() -> &'static (tokio::runtime::Runtime, Router) {
    static APP: std::sync::OnceLock<(tokio::runtime::Runtime, Router)> = std::sync::OnceLock::new();
    APP.get_or_init(|| {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        let app = rt.block_on(async { app() });
        (rt, app)
    })
}

/// A response: status, headers, body bytes.
pub struct Reply {
    pub status: StatusCode,
    pub headers: HeaderMap,
    pub body: Vec<u8>,
}

impl Reply {
    /// The body as JSON (panics with the body text when it is not JSON).
    pub fn json(&self) -> Value {
        serde_json::from_slice(&self.body)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&self.body)))
    }

    /// The content type.
    pub fn content_type(&self) -> String {
        self.headers
            .get(header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .unwrap_or("")
            .to_string()
    }
}

/// Sends one request through the router.
pub async fn send(
    app: &Router,
    method: Method,
    path: &str,
    ct: Option<&str>,
    body: Vec<u8>,
    accept: Option<&str>,
) -> Reply {
    let mut req = Request::builder().method(method).uri(path);
    if let Some(ct) = ct {
        req = req.header(header::CONTENT_TYPE, ct);
    }
    if let Some(a) = accept {
        req = req.header(header::ACCEPT, a);
    }
    let res = app
        .clone()
        .oneshot(req.body(Body::from(body)).unwrap())
        .await
        .unwrap();
    let status = res.status();
    let headers = res.headers().clone();
    let body = res.into_body().collect().await.unwrap().to_bytes().to_vec();
    Reply {
        status,
        headers,
        body,
    }
}

/// POSTs JSON.
pub async fn post(app: &Router, path: &str, body: &Value) -> Reply {
    send(
        app,
        Method::POST,
        path,
        Some("application/json"),
        serde_json::to_vec(body).unwrap(),
        None,
    )
    .await
}

/// The body of a 200 answer as JSON (panics with the body text for any other status).
pub fn ok(r: &Reply) -> Value {
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    r.json()
}

/// POSTs a migration request and returns its 200 answer as JSON (panics with the request and
/// the body text for any other status).
pub async fn migrate_ok(app: &Router, body: &Value) -> Value {
    let r = post(app, "/v1/migration", body).await;
    assert_eq!(
        r.status,
        200,
        "{body}: {}",
        String::from_utf8_lossy(&r.body)
    );
    r.json()
}

/// GETs a path.
pub async fn get(app: &Router, path: &str) -> Reply {
    send(app, Method::GET, path, None, Vec::new(), None).await
}

/// Asserts a problem+json answer with the given status and code; returns the problem.
pub fn assert_problem(r: &Reply, status: u16, code: &str) -> Value {
    assert_eq!(
        r.status.as_u16(),
        status,
        "body: {}",
        String::from_utf8_lossy(&r.body)
    );
    assert!(
        r.content_type().starts_with("application/problem+json"),
        "content type {}",
        r.content_type()
    );
    let p = r.json();
    assert_eq!(p["type"], format!("/problems/{code}"), "problem {p}");
    assert_eq!(p["status"], status);
    assert!(p["title"].is_string() && p["detail"].is_string());
    p
}

/// Relative difference |a − b| / |b| (absolute when b = 0).
pub fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}

/// Directory of the shared specification and verification files.
pub fn shared_dir() -> std::path::PathBuf {
    std::env::var_os("GANGUE_SHARED")
        .map(Into::into)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared"))
}

/// Sends each body and asserts a 422 of the given code naming the given field.
pub async fn assert_rejections(app: &Router, path: &str, cases: Vec<(Value, &str, &str)>) {
    for (body, field, code) in cases {
        let r = post(app, path, &body).await;
        let p = assert_problem(&r, 422, code);
        assert!(
            p["errors"]
                .as_array()
                .unwrap()
                .iter()
                .any(|e| e["field"] == field),
            "{body}: {field} not named in {p}"
        );
    }
}

/// A scene ensemble of `runs` runs (seed `seed`) on three supports — two columns beside the
/// path and a spanning one — that rocks of 0.05–0.3 m strike past a stress utilisation of 5 with
/// probabilities between 0 and 1; with the runs CSV.
pub fn risky_scene(runs: u64, seed: u64) -> Value {
    serde_json::json!({
        "design_limits": {"stress_utilisation": 5.0},
        "supports": [
            {"along_dip_m": 40, "across_m": -0.5},
            {"along_dip_m": 80, "across_m": 0.5},
            {"along_dip_m": 110},
        ],
        "monte_carlo": {
            "runs": runs, "seed": seed,
            "side_length_m": {"distribution": "uniform", "min": 0.05, "max": 0.3},
            "release_across_m": {"distribution": "uniform", "min": -1.5, "max": 1.5},
        },
        "migration_output": {"runs_csv": true},
    })
}

/// Runs the `gangue` binary with `args` (a shard's `compute` or a `merge`): the shard index from
/// the flags only, not from a scheduler's environment; two solver threads.
pub fn gangue_cli(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_gangue"))
        .args(args)
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SLURM_ARRAY_TASK_COUNT")
        .env_remove("AWS_BATCH_JOB_ARRAY_INDEX")
        .env("GANGUE_SOLVER_THREADS", "2")
        .output()
        .expect("the gangue binary runs")
}

/// Type-7 percentile (Hyndman–Fan) of ascending values: the service's definition.
pub fn type7(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    if lo + 1 >= sorted.len() {
        return sorted[sorted.len() - 1];
    }
    sorted[lo] + (h - lo as f64) * (sorted[lo + 1] - sorted[lo])
}

/// `gangue compute` of shard 0 of 2 of the scene request `body`, in a scratch folder named by
/// `tag`: whether it succeeded, and what it printed (stderr, then stdout).
pub fn scene_shard(body: &Value, tag: &str) -> (bool, String) {
    shard_0_of_2(body, "scene", tag)
}

/// Shard 0 of 2 of a computation of `kind` on the request `body` through `gangue compute`
/// (`tag` names its scratch directory): whether it succeeded, and what it printed.
pub fn shard_0_of_2(body: &Value, kind: &str, tag: &str) -> (bool, String) {
    let dir = std::env::temp_dir().join(format!("gangue-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let req = dir.join("request.json");
    std::fs::write(&req, serde_json::to_vec(body).unwrap()).unwrap();
    let out = gangue_cli(&[
        "compute",
        "--request",
        req.to_str().unwrap(),
        "--kind",
        kind,
        "--shard",
        "0/2",
        "--out",
        dir.join("part").to_str().unwrap(),
    ]);
    let text =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    let _ = std::fs::remove_dir_all(&dir);
    (out.status.success(), text)
}

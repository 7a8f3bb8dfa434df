//! `POST /v1/batch`: many requests of the other kinds, answered as NDJSON in input order.
//!
//! Items run in parallel on the solver pool under one computation slot, each with a time limit
//! of its own; the answer streams one line per item as soon as it and its predecessors are
//! done. A client that disconnects stops the items not yet started and cancels the running ones.

use std::collections::{BTreeMap, HashMap};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde_json::Value;

use crate::config::Config;
use crate::http::dto::batch::{BatchKind, check_item, json_items, ndjson_items};
use crate::http::dto::calibrate::CalibrateRequest;
use crate::http::dto::column::ColumnRequest;
use crate::http::dto::impact::ImpactRequest;
use crate::http::dto::migration::MigrationRequest;
use crate::http::dto::scene::SceneRequest;
use crate::http::dto::spalling::SpallingRequest;
use crate::http::dto::study::StudyRequest;
use crate::http::error::ApiError;
use crate::http::json::{from_value, is_json, parse_json, read_body};
use crate::http::routes::{calibrate, column, impact, migration, scene, spalling, study};
use crate::http::runner::{AppState, NDJSON, run_solver_without_deadline, to_json_bytes};
use crate::physics::Control;

/// Many requests of the kinds above in one call, answered as NDJSON.
#[utoipa::path(
    post,
    path = "/v1/batch",
    tag = "batch",
    request_body(
        content(
            (crate::http::dto::batch::BatchRequest = "application/json"),
            (crate::http::dto::batch::BatchItemDto = "application/x-ndjson"),
        ),
        description = "`{\"items\": [...]}` as JSON, or one item object per line as NDJSON"
    ),
    responses(
        (status = 200, description = "One line per item, in input order", body = crate::http::dto::batch::BatchLine, content_type = "application/x-ndjson"),
        (status = "4XX", description = "Bad envelope, too many items or wrong media type (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
        (status = "5XX", description = "Overloaded or internal (problem+json)", body = crate::http::openapi::Problem, content_type = "application/problem+json"),
    )
)]
pub async fn batch(State(state): State<AppState>, req: Request) -> Response {
    match start(state, req).await {
        Ok(r) | Err(r) => r,
    }
}

fn is_ndjson(ct: Option<&HeaderValue>) -> bool {
    ct.and_then(|v| v.to_str().ok())
        .and_then(|s| s.split(';').next())
        .is_some_and(|e| e.trim().eq_ignore_ascii_case(NDJSON))
}

async fn start(state: AppState, req: Request) -> Result<Response, Response> {
    let ct = req.headers().get(header::CONTENT_TYPE).cloned();
    let ndjson = is_ndjson(ct.as_ref());
    if !ndjson && !is_json(ct.as_ref()) {
        return Err(ApiError::new(
            "unsupported_media_type",
            "send the batch as application/json ({\"items\": […]}) or application/x-ndjson",
        )
        .into_response());
    }
    let bytes = read_body(req, &state)
        .await
        .map_err(IntoResponse::into_response)?;
    let items: Vec<Result<Value, ApiError>> = if ndjson {
        ndjson_items(&bytes)
    } else {
        let body = parse_json(&bytes).map_err(IntoResponse::into_response)?;
        json_items(&body)
            .map_err(IntoResponse::into_response)?
            .into_iter()
            .map(Ok)
            .collect()
    };
    let limit = state.config.max_batch_items;
    if items.len() as u64 > limit {
        return Err(ApiError::invalid(
            "/items",
            serde_json::json!(items.len()),
            format!("at most {limit} items in one batch (see limits in /v1/presets)"),
        )
        .into_response());
    }
    Ok(stream(state, items).await)
}

/// Item controls of the running items, cancelled together when the client goes away.
type Registry = Arc<Mutex<HashMap<usize, Control>>>;

fn cancel_all(reg: &Registry) {
    if let Ok(m) = reg.lock() {
        for c in m.values() {
            c.cancel();
        }
    }
}

struct CancelItemsOnDrop(Registry);

impl Drop for CancelItemsOnDrop {
    fn drop(&mut self) {
        cancel_all(&self.0);
    }
}

/// The NDJSON answer line of item `index`: its result or its problem.
#[must_use]
pub fn line(index: usize, r: Result<Vec<u8>, ApiError>) -> bytes::Bytes {
    let mut l = format!("{{\"index\":{index},").into_bytes();
    match r {
        Ok(b) => {
            l.extend_from_slice(b"\"status\":200,\"result\":");
            l.extend_from_slice(&b);
        }
        Err(e) => {
            l.extend_from_slice(
                format!("\"status\":{},\"problem\":", e.status().as_u16()).as_bytes(),
            );
            l.extend_from_slice(&serde_json::to_vec(&e.to_problem()).unwrap_or_default());
        }
    }
    l.extend_from_slice(b"}\n");
    bytes::Bytes::from(l)
}

async fn stream(state: AppState, items: Vec<Result<Value, ApiError>>) -> Response {
    let n = items.len();
    let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel::<(usize, bytes::Bytes)>();
    let registry: Registry = Arc::new(Mutex::new(HashMap::new()));
    let reg = registry.clone();
    let config = state.config.clone();
    let item_limit = state.time_limit();
    let work = move |batch: &Control| -> Result<(), ApiError> {
        let next = AtomicUsize::new(0);
        let workers = rayon::current_num_threads().clamp(1, n.max(1));
        rayon::scope(|s| {
            for _ in 0..workers {
                s.spawn(|_| {
                    loop {
                        if batch.is_cancelled() {
                            break;
                        }
                        let i = next.fetch_add(1, Ordering::SeqCst);
                        if i >= n {
                            break;
                        }
                        let ctl = Control::with_deadline(Some(Instant::now() + item_limit));
                        if let Ok(mut m) = reg.lock() {
                            m.insert(i, ctl.clone());
                        }
                        if batch.is_cancelled() {
                            ctl.cancel();
                        }
                        let out = catch_unwind(AssertUnwindSafe(|| {
                            run_item(i, &items[i], &config, &ctl)
                        }))
                        .unwrap_or_else(|_| {
                            Err(ApiError::internal(format!("batch item {i} panicked")))
                        });
                        if let Ok(mut m) = reg.lock() {
                            m.remove(&i);
                        }
                        if tx.send((i, line(i, out))).is_err() {
                            batch.cancel();
                            break;
                        }
                    }
                });
            }
        });
        Ok(())
    };
    let st = state.clone();
    let mut fut = Box::pin(async move { run_solver_without_deadline(&st, work).await });
    // Poll once: a batch that finds every slot busy is a plain 503, not a stream of them.
    let first = tokio::select! {
        biased;
        r = &mut fut => Some(r),
        () = std::future::ready(()) => None,
    };
    if let Some(Err(e)) = first {
        return e.into_response();
    }
    let mut finished = first;
    let body = async_stream::stream! {
        let _guard = CancelItemsOnDrop(registry.clone());
        let mut pending: BTreeMap<usize, bytes::Bytes> = BTreeMap::new();
        let mut next = 0usize;
        while next < n {
            tokio::select! {
                msg = rx.recv() => match msg {
                    Some((i, l)) => {
                        pending.insert(i, l);
                        while let Some(l) = pending.remove(&next) {
                            next += 1;
                            yield Ok::<_, std::convert::Infallible>(l);
                        }
                    }
                    None => break,
                },
                r = &mut fut, if finished.is_none() => {
                    if r.is_err() {
                        cancel_all(&registry);
                    }
                    finished = Some(r);
                }
            }
        }
        // Items never answered (the batch as a whole passed the time limit, or failed).
        if next < n {
            let e = match finished {
                Some(Err(e)) => e,
                _ => ApiError::new("timeout", "the batch passed the time limit and was stopped"),
            };
            for i in next..n {
                yield Ok(line(i, Err(e.clone())));
            }
        }
    };
    (
        StatusCode::OK,
        [(header::CONTENT_TYPE, HeaderValue::from_static(NDJSON))],
        Body::from_stream(body),
    )
        .into_response()
}

/// Runs one item with its own control; problems name `/items/{index}/…`.
pub fn run_item(
    index: usize,
    item: &Result<Value, ApiError>,
    config: &Config,
    control: &Control,
) -> Result<Vec<u8>, ApiError> {
    let value = item.as_ref().map_err(Clone::clone)?;
    let item = check_item(index, value)?;
    let prefix = format!("/items/{index}/request");
    let nest = |e: ApiError| e.nest(&prefix);
    match item.kind {
        BatchKind::Impact => {
            let mut req: ImpactRequest = from_value(&item.request).map_err(nest)?;
            let case = req.resolve(config).map_err(nest)?;
            to_json_bytes(&impact::solve(&case, req, control).map_err(nest)?)
        }
        BatchKind::Column => {
            let mut req: ColumnRequest = from_value(&item.request).map_err(nest)?;
            let case = req.resolve(config).map_err(nest)?;
            to_json_bytes(&column::solve(&case, req, control).map_err(nest)?)
        }
        BatchKind::Migration => {
            let mut req: MigrationRequest = from_value(&item.request).map_err(nest)?;
            let case = req.resolve(config).map_err(nest)?;
            to_json_bytes(&migration::solve(&case, req, control).map_err(nest)?)
        }
        BatchKind::Spalling => {
            let req: SpallingRequest = from_value(&item.request).map_err(nest)?;
            to_json_bytes(&spalling::solve(req, control).map_err(nest)?)
        }
        BatchKind::Study => {
            let req: StudyRequest = from_value(&item.request).map_err(nest)?;
            to_json_bytes(&study::solve(config, req, control).map_err(nest)?)
        }
        BatchKind::Scene => {
            let mut req: SceneRequest = from_value(&item.request).map_err(nest)?;
            let (case, ctx) = req.resolve(config).map_err(nest)?;
            to_json_bytes(&scene::solve(&case, ctx, req, control).map_err(nest)?)
        }
        BatchKind::Calibrate => {
            let mut req: CalibrateRequest = from_value(&item.request).map_err(nest)?;
            let case = req.resolve(config).map_err(nest)?;
            to_json_bytes(&calibrate::solve(&case, req, control).map_err(nest)?)
        }
    }
}

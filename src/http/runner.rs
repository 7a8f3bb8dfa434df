//! Runs solvers off the async workers: a solver slot (admission below), a job on the solver thread
//! pool (which also runs the ensembles' parallel parts), and a [`Control`] whose deadline and
//! cancel flag the solver polls.
//! Dropping the request (client gone) or passing the time limit stops the work.
//!
//! Admission: a request that finds every slot busy queues for one instead of being refused. It is
//! refused (503 `overloaded` with `Retry-After`) only when the expected wait passes the bound
//! (`--max-queue-wait-ms`): expected wait = mean recent solve time × (requests queued ahead + 1)
//! / slots, the mean being an exponential moving average (weight 1/8) of the time each finished
//! computation held its slot. A queued request waits at most twice the bound (the estimate can be
//! wrong when solve times vary), then gets the same 503.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use axum::body::Body;
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

use super::error::ApiError;
use super::finite::ensure_finite;
use crate::config::Config;
use crate::physics::Control;

/// Media type of streamed progress answers and batch lines.
pub const NDJSON: &str = "application/x-ndjson";

/// Shared state of the service: settings, solver slots, the ensemble thread pool.
#[derive(Clone)]
pub struct AppState {
    /// Settings and limits.
    pub config: Arc<Config>,
    admission: Arc<Admission>,
    pool: Arc<rayon::ThreadPool>,
}

/// Solver slots with a queue whose expected wait is bounded (see the module documentation).
#[derive(Debug)]
pub struct Admission {
    slots: usize,
    permits: Arc<Semaphore>,
    /// Requests waiting for a slot.
    queued: AtomicUsize,
    /// Moving average of the time a computation holds its slot, ns.
    mean_solve_ns: AtomicU64,
    /// Largest expected wait admitted to the queue.
    bound: Duration,
}

/// Weight of the newest solve time in the moving average (1/8).
const MEAN_WEIGHT_SHIFT: u32 = 3;

impl Admission {
    /// `slots` solver slots; queue while the expected wait is at most `bound`.
    #[must_use]
    pub fn new(slots: usize, bound: Duration) -> Self {
        Self {
            slots: slots.max(1),
            permits: Arc::new(Semaphore::new(slots.max(1))),
            queued: AtomicUsize::new(0),
            // Until something has been measured, assume a short (1 ms) computation.
            mean_solve_ns: AtomicU64::new(1_000_000),
            bound,
        }
    }

    /// Expected wait of a request that would queue behind `ahead` others.
    pub fn expected_wait(&self, ahead: usize) -> Duration {
        let mean = self.mean_solve_ns.load(Ordering::Relaxed) as f64;
        Duration::from_nanos((mean * (ahead + 1) as f64 / self.slots as f64) as u64)
    }

    /// Requests waiting for a slot now.
    pub fn queued(&self) -> usize {
        self.queued.load(Ordering::Relaxed)
    }

    /// Folds one measured slot holding time into the moving average.
    pub fn record(&self, held: Duration) {
        let new = u64::try_from(held.as_nanos()).unwrap_or(u64::MAX);
        let _ = self
            .mean_solve_ns
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |old| {
                let (o, n) = (old as i128, new as i128);
                Some((o + ((n - o) >> MEAN_WEIGHT_SHIFT)).max(0) as u64)
            });
    }

    /// A slot at once, or after a wait the estimate admits; 503 `overloaded` otherwise.
    pub async fn acquire(&self) -> Result<OwnedSemaphorePermit, ApiError> {
        if let Ok(p) = self.permits.clone().try_acquire_owned() {
            return Ok(p);
        }
        let ahead = self.queued.fetch_add(1, Ordering::SeqCst);
        let _leave = LeaveQueue(&self.queued);
        let expected = self.expected_wait(ahead);
        if expected > self.bound {
            return Err(ApiError::overloaded(retry_after_s(expected)));
        }
        match tokio::time::timeout(2 * self.bound, self.permits.clone().acquire_owned()).await {
            Ok(Ok(p)) => Ok(p),
            _ => Err(ApiError::overloaded(retry_after_s(
                self.expected_wait(self.queued()),
            ))),
        }
    }
}

/// Whole seconds to suggest in `Retry-After` for an expected wait (at least 1).
fn retry_after_s(expected: Duration) -> u64 {
    expected.as_secs_f64().ceil().clamp(1.0, 3600.0) as u64
}

/// Leaves the admission queue when dropped (admitted, refused or the client gone).
struct LeaveQueue<'a>(&'a AtomicUsize);

impl Drop for LeaveQueue<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

impl std::fmt::Debug for AppState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AppState")
            .field("config", &self.config)
            .finish_non_exhaustive()
    }
}

impl AppState {
    /// Builds the state: `max_concurrent` permits and a rayon pool of `solver_threads` threads.
    #[must_use]
    pub fn new(config: Config) -> Self {
        let nice = config.solver_nice;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(config.solver_threads())
            .thread_name(|i| format!("gangue-solver-{i}"))
            .start_handler(move |_| lower_priority(nice))
            .build()
            .unwrap_or_else(|e| {
                tracing::error!(%e, "cannot start the solver threads");
                std::process::exit(71)
            }); // EX_OSERR
        Self {
            admission: Arc::new(Admission::new(
                config.max_concurrent(),
                config.max_queue_wait(),
            )),
            pool: Arc::new(pool),
            config: Arc::new(config),
        }
    }

    /// The time limit of one computation.
    #[must_use]
    pub fn time_limit(&self) -> Duration {
        Duration::from_secs_f64(self.config.compute_timeout_s)
    }

    /// The solver slots and their queue.
    #[must_use]
    pub fn admission(&self) -> &Admission {
        &self.admission
    }
}

/// Lowers the calling thread's scheduling priority to niceness `nice` (Linux: `setpriority` on
/// the thread id, which affects that thread only). Solver threads run below the async workers so
/// that `/healthz` and admission answer promptly while every core computes. A failure (a
/// sandbox refusing it) only loses that preference, so it is logged, not fatal.
fn lower_priority(nice: i32) {
    if nice <= 0 {
        return;
    }
    #[cfg(target_os = "linux")]
    {
        let tid = rustix::thread::gettid();
        if let Err(e) = rustix::process::setpriority_process(Some(tid), nice) {
            tracing::warn!(error = %e, nice, "could not lower the solver thread's priority");
        }
    }
}

/// Sets the cancel flag when dropped unless disarmed: a dropped request future stops its solver.
struct CancelOnDrop(Option<Control>);

impl CancelOnDrop {
    fn disarm(mut self) {
        self.0 = None;
    }
}

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        if let Some(c) = self.0.take() {
            c.cancel();
        }
    }
}

/// A started computation: its control handle and the channel its answer comes back on.
struct Running<T> {
    control: Control,
    answer: tokio::sync::oneshot::Receiver<Result<T, ApiError>>,
}

async fn start<T, F>(
    state: &AppState,
    limit: Option<Duration>,
    solve: F,
) -> Result<Running<T>, ApiError>
where
    T: Send + 'static,
    F: FnOnce(&Control) -> Result<T, ApiError> + Send + 'static,
{
    let permit = state.admission.acquire().await?;
    // The time limit counts from admission: time queued is bounded separately.
    let control = Control::with_deadline(limit.map(|l| Instant::now() + l));
    let c = control.clone();
    let pool = state.pool.clone();
    let admission = state.admission.clone();
    let (send, answer) = tokio::sync::oneshot::channel();
    // The solve runs as a job of the solver pool itself (one hand-over each way, no blocking-pool
    // thread in between); its parallel parts (ensembles) run on the same pool.
    pool.spawn(move || {
        let t0 = Instant::now();
        let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| solve(&c)))
            .unwrap_or_else(|panic| Err(ApiError::internal(panic_message(panic.as_ref()))));
        admission.record(t0.elapsed());
        // The slot is free before the answer is seen, as a finished task's would be.
        drop(permit);
        // The receiver is gone when the request was dropped; the answer is then not needed.
        let _ = send.send(out);
    });
    Ok(Running { control, answer })
}

/// The text of a solver's panic, for the 500 `internal` problem.
fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    let text = panic
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".to_owned());
    format!("solver task failed: {text}")
}

async fn finish<T>(limit: Option<Duration>, run: Running<T>) -> Result<T, ApiError> {
    let guard = CancelOnDrop(Some(run.control.clone()));
    // The solver polls its deadline; the outer timeout is a backstop for one that does not.
    let grace = Duration::from_secs(2);
    let backstop = limit.map_or(Duration::MAX, |l| l.saturating_add(grace));
    let out = match tokio::time::timeout(backstop, run.answer).await {
        Ok(Ok(result)) => result,
        Ok(Err(_)) => Err(ApiError::internal("solver task ended without an answer")),
        Err(_) => {
            run.control.cancel();
            Err(ApiError::new(
                "timeout",
                "the computation passed the time limit and was stopped",
            ))
        }
    };
    guard.disarm();
    out
}

/// Runs `solve` on the blocking pool under a permit and a deadline; returns its value.
pub async fn run_solver<T, F>(state: &AppState, solve: F) -> Result<T, ApiError>
where
    T: Send + 'static,
    F: FnOnce(&Control) -> Result<T, ApiError> + Send + 'static,
{
    let limit = Some(state.time_limit());
    let run = start(state, limit, solve).await?;
    finish(limit, run).await
}

/// Runs `solve` like [`run_solver`] but without an overall deadline: for a batch, whose items
/// each carry the compute time limit of their own (api.md), so the whole is bounded by the item
/// limit × the time limit. A dropped request still cancels it.
pub async fn run_solver_without_deadline<T, F>(state: &AppState, solve: F) -> Result<T, ApiError>
where
    T: Send + 'static,
    F: FnOnce(&Control) -> Result<T, ApiError> + Send + 'static,
{
    let run = start(state, None, solve).await?;
    finish(None, run).await
}

/// True when the client asked for streamed progress: `Accept` names `application/x-ndjson`
/// (media types compared case-insensitively) with a q-value above 0 and at least as high as the
/// q-value that applies to `application/json` (its own, `application/*` or `*/*`, the most
/// specific one counting). `application/x-ndjson;q=0` refuses NDJSON; no `Accept` means JSON.
pub fn wants_progress(headers: &HeaderMap) -> bool {
    // (specificity, q) of the most specific range matching each type: 2 exact, 1 type/*, 0 */*.
    let mut ndjson: Option<(u8, f64)> = None;
    let mut json: Option<(u8, f64)> = None;
    let keep = |slot: &mut Option<(u8, f64)>, spec: u8, q: f64| {
        if slot.is_none_or(|(s, _)| spec > s) {
            *slot = Some((spec, q));
        }
    };
    for value in headers.get_all(header::ACCEPT).iter() {
        let Ok(value) = value.to_str() else { continue };
        for range in value.split(',') {
            let mut parts = range.split(';');
            let media = parts.next().unwrap_or("").trim().to_ascii_lowercase();
            let mut q = 1.0;
            for param in parts {
                let mut kv = param.splitn(2, '=');
                let key = kv.next().unwrap_or("").trim();
                if key.eq_ignore_ascii_case("q") {
                    // RFC 9110 §12.4.2: a weight in [0, 1]; an unreadable one counts as 0.
                    q = kv
                        .next()
                        .and_then(|v| v.trim().parse::<f64>().ok())
                        .filter(|v| (0.0..=1.0).contains(v))
                        .unwrap_or(0.0);
                }
            }
            match media.as_str() {
                "application/x-ndjson" => keep(&mut ndjson, 2, q),
                "application/json" => keep(&mut json, 2, q),
                "application/*" => {
                    keep(&mut ndjson, 1, q);
                    keep(&mut json, 1, q);
                }
                "*/*" => {
                    keep(&mut ndjson, 0, q);
                    keep(&mut json, 0, q);
                }
                _ => {}
            }
        }
    }
    // Only an explicit request streams: wildcards alone keep the plain JSON answer.
    match ndjson {
        Some((2, qn)) if qn > 0.0 => qn >= json.map_or(0.0, |(_, qj)| qj),
        _ => false,
    }
}

/// Serializes a result to JSON bytes, refusing non-finite numbers (a bug, never sent as null).
pub fn to_json_bytes<T: Serialize>(value: &T) -> Result<Vec<u8>, ApiError> {
    ensure_finite(value).map_err(ApiError::internal)?;
    serde_json::to_vec(value).map_err(ApiError::internal)
}

/// A 200 JSON response from bytes produced by [`to_json_bytes`].
#[must_use]
pub fn json_response(bytes: Vec<u8>) -> Response {
    (
        StatusCode::OK,
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/json"),
        )],
        bytes,
    )
        .into_response()
}

/// Runs a solver and answers either plain JSON or, when the client accepts NDJSON, a stream of
/// `{"progress": {"done", "total"}}` lines followed by one `{"result": …}` or `{"problem": …}`.
///
/// The result is serialized on the blocking pool, not on the async workers.
pub async fn respond<T, F>(state: &AppState, headers: &HeaderMap, solve: F) -> Response
where
    T: Serialize + Send + 'static,
    F: FnOnce(&Control) -> Result<T, ApiError> + Send + 'static,
{
    let solve_bytes = move |c: &Control| solve(c).and_then(|v| to_json_bytes(&v));
    if !wants_progress(headers) {
        return match run_solver(state, solve_bytes).await {
            Ok(bytes) => json_response(bytes),
            Err(e) => e.into_response(),
        };
    }
    let limit = Some(state.time_limit());
    let run = match start(state, limit, solve_bytes).await {
        Ok(r) => r,
        Err(e) => return e.into_response(),
    };
    let control = run.control.clone();
    let stream = async_stream::stream! {
        let guard = CancelOnDrop(Some(control.clone()));
        let mut fut = Box::pin(finish(limit, run));
        let mut tick = tokio::time::interval(Duration::from_millis(250));
        tick.tick().await;
        // A progress line is sent only when the solver announced a total and the count moved:
        // `{"done":0,"total":0}` or a repeated line says nothing.
        let mut last: Option<(u64, u64)> = None;
        let started = std::time::Instant::now();
        let result = loop {
            tokio::select! {
                r = &mut fut => break r,
                _ = tick.tick() => {
                    let (done, total) = control.progress();
                    let elapsed = started.elapsed().as_secs_f64();
                    if let Some(line) = progress_line(done, total, elapsed, &mut last) {
                        yield Ok::<_, std::convert::Infallible>(bytes::Bytes::from(line));
                    }
                }
            }
        };
        let mut line = match result {
            Ok(bytes) => {
                let mut l = b"{\"result\":".to_vec();
                l.extend_from_slice(&bytes);
                l.push(b'}');
                l
            }
            Err(e) => {
                let mut l = b"{\"problem\":".to_vec();
                l.extend_from_slice(&serde_json::to_vec(&e.to_problem()).unwrap_or_default());
                l.push(b'}');
                l
            }
        };
        line.push(b'\n');
        guard.disarm();
        yield Ok(bytes::Bytes::from(line));
    };
    (
        StatusCode::OK,
        [(header::CONTENT_TYPE, HeaderValue::from_static(NDJSON))],
        Body::from_stream(stream),
    )
        .into_response()
}

/// The NDJSON progress line for (done, total) after `elapsed` seconds, or `None` when it would say
/// nothing new: no total announced (total 0) or the same counts as the last line sent (`last`,
/// updated when sent). Once some work is done and some is left, the line carries the time left
/// at the rate so far, `elapsed · (total − done) / done` (s, to the millisecond).
fn progress_line(
    done: u64,
    total: u64,
    elapsed: f64,
    last: &mut Option<(u64, u64)>,
) -> Option<String> {
    if total == 0 || *last == Some((done, total)) {
        return None;
    }
    *last = Some((done, total));
    let done = done.min(total);
    let ms = |s: f64| (s * 1e3).round() / 1e3;
    let left = if done > 0 && done < total {
        format!(
            ",\"remaining_s\":{}",
            ms(elapsed * (total - done) as f64 / done as f64)
        )
    } else {
        String::new()
    };
    Some(format!(
        "{{\"progress\":{{\"done\":{done},\"total\":{total},\"elapsed_s\":{}{left}}}}}\n",
        ms(elapsed)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::PhysicsError;
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

    fn state(timeout_s: f64, slots: usize) -> AppState {
        AppState::new(Config {
            compute_timeout_s: timeout_s,
            max_concurrent: Some(slots),
            solver_threads: Some(1),
            ..Config::default()
        })
    }

    /// A deliberately slow solver: spins until cancelled, counting its polls.
    fn slow(
        polls: Arc<AtomicU64>,
        stopped: Arc<AtomicBool>,
    ) -> impl FnOnce(&Control) -> Result<u8, ApiError> {
        move |c: &Control| loop {
            polls.fetch_add(1, Ordering::Relaxed);
            if let Err(e) = c.check() {
                stopped.store(true, Ordering::SeqCst);
                return Err(ApiError::from(e));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    #[tokio::test]
    async fn deadline_stops_the_blocking_work() {
        let s = state(0.2, 2);
        let polls = Arc::new(AtomicU64::new(0));
        let stopped = Arc::new(AtomicBool::new(false));
        let t0 = Instant::now();
        let r = run_solver(&s, slow(polls.clone(), stopped.clone())).await;
        assert_eq!(r.unwrap_err().code(), "timeout");
        assert!(stopped.load(Ordering::SeqCst), "the solver itself stopped");
        assert!(t0.elapsed() < Duration::from_secs(2));
        // No more polling after it returned.
        let n = polls.load(Ordering::Relaxed);
        tokio::time::sleep(Duration::from_millis(50)).await;
        assert_eq!(n, polls.load(Ordering::Relaxed));
    }

    #[tokio::test]
    async fn dropping_the_request_cancels_the_work() {
        let s = state(60.0, 2);
        let polls = Arc::new(AtomicU64::new(0));
        let stopped = Arc::new(AtomicBool::new(false));
        let fut = run_solver(&s, slow(polls.clone(), stopped.clone()));
        // Poll the request for a while, then drop it as a disconnecting client would.
        let _ = tokio::time::timeout(Duration::from_millis(100), fut).await;
        for _ in 0..100 {
            if stopped.load(Ordering::SeqCst) {
                break;
            }
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        assert!(
            stopped.load(Ordering::SeqCst),
            "a dropped request stops its solver"
        );
    }

    #[tokio::test]
    async fn saturated_slots_answer_overloaded_after_the_longest_wait() {
        let s = state(60.0, 1);
        let polls = Arc::new(AtomicU64::new(0));
        let stopped = Arc::new(AtomicBool::new(false));
        let s2 = s.clone();
        let busy = tokio::spawn(async move { run_solver(&s2, slow(polls, stopped)).await });
        tokio::time::sleep(Duration::from_millis(50)).await;
        let r = run_solver(&s, |_c: &Control| Ok::<_, ApiError>(1u8)).await;
        let e = r.unwrap_err();
        assert_eq!(e.code(), "overloaded");
        assert_eq!(e.status(), StatusCode::SERVICE_UNAVAILABLE);
        busy.abort();
    }

    /// A solver that holds its slot until `release` is set (or it is cancelled).
    fn held(release: Arc<AtomicBool>) -> impl FnOnce(&Control) -> Result<u8, ApiError> {
        move |c: &Control| {
            while !release.load(Ordering::SeqCst) {
                c.check().map_err(ApiError::from)?;
                std::thread::sleep(Duration::from_millis(1));
            }
            Ok(7)
        }
    }

    #[tokio::test]
    async fn a_short_request_waits_for_a_busy_slot_instead_of_being_shed() {
        let s = state(60.0, 1);
        let release = Arc::new(AtomicBool::new(false));
        let s1 = s.clone();
        let r1 = release.clone();
        let busy = tokio::spawn(async move { run_solver(&s1, held(r1)).await });
        while s.admission().permits.available_permits() > 0 {
            tokio::task::yield_now().await;
        }
        let s2 = s.clone();
        let short =
            tokio::spawn(
                async move { run_solver(&s2, |_c: &Control| Ok::<_, ApiError>(1u8)).await },
            );
        while s.admission().queued() == 0 {
            tokio::task::yield_now().await;
        }
        // Queued behind the busy slot, not refused; it runs once the slot is free.
        release.store(true, Ordering::SeqCst);
        assert_eq!(short.await.unwrap().unwrap(), 1);
        assert_eq!(busy.await.unwrap().unwrap(), 7);
        assert_eq!(s.admission().queued(), 0, "the queue is left on admission");
    }

    #[tokio::test]
    async fn shed_only_when_the_expected_wait_passes_the_bound() {
        let a = Admission::new(2, Duration::from_millis(100));
        // A mean solve time of 80 ms: one queued request expects 40 ms, three expect 120 ms.
        for _ in 0..200 {
            a.record(Duration::from_millis(80));
        }
        let near = a.expected_wait(0).as_secs_f64();
        assert!((near - 0.040).abs() < 1e-3, "{near}");
        assert!(a.expected_wait(2) > Duration::from_millis(100));
        let _p1 = a.acquire().await.unwrap();
        let _p2 = a.acquire().await.unwrap();
        // Two more wait in the queue (expected 40 and 80 ms) ...
        let (q1, q2) = (a.acquire(), a.acquire());
        let mut q1 = Box::pin(q1);
        let mut q2 = Box::pin(q2);
        assert!(futures_util::poll!(&mut q1).is_pending());
        assert!(futures_util::poll!(&mut q2).is_pending());
        assert_eq!(a.queued(), 2);
        // ... the next one would expect 120 ms: refused at once with a Retry-After.
        let e = a.acquire().await.unwrap_err();
        assert_eq!(e.code(), "overloaded");
        assert_eq!(e.status(), StatusCode::SERVICE_UNAVAILABLE);
        drop(q1);
        assert_eq!(a.queued(), 1, "a dropped waiter leaves the queue");
        drop(q2);
        assert_eq!(a.queued(), 0);
    }

    #[test]
    fn the_mean_solve_time_follows_recent_solves() {
        let a = Admission::new(1, Duration::from_millis(100));
        for _ in 0..100 {
            a.record(Duration::from_millis(10));
        }
        let m = a.expected_wait(0).as_secs_f64();
        assert!((m - 0.010).abs() < 1e-4, "{m}");
        for _ in 0..100 {
            a.record(Duration::from_micros(300));
        }
        let m = a.expected_wait(0).as_secs_f64();
        assert!((m - 0.0003).abs() < 1e-5, "{m}");
        assert_eq!(retry_after_s(Duration::from_millis(1)), 1);
        assert_eq!(retry_after_s(Duration::from_millis(2500)), 3);
    }

    fn accept(values: &[&'static str]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for v in values {
            h.append(header::ACCEPT, HeaderValue::from_static(v));
        }
        h
    }

    #[test]
    fn accept_negotiation_honours_q_values_and_case() {
        let yes = [
            &["application/x-ndjson"][..],
            &["Application/X-NDJSON"],
            &["application/json;q=0.5, application/x-ndjson"],
            &["application/x-ndjson;q=0.9, */*;q=0.1"],
            &["text/html", "application/x-ndjson; Q=0.3"],
            &["application/x-ndjson, application/json"],
        ];
        for h in yes {
            assert!(wants_progress(&accept(h)), "{h:?} asks for NDJSON");
        }
        let no = [
            &[][..],
            &["application/json"],
            &["*/*"],
            &["application/*"],
            &["application/x-ndjson;q=0"],
            &["application/x-ndjson;q=0.000"],
            &["application/x-ndjson;q=0.2, application/json"],
            &["application/x-ndjson;q=0.5, */*;q=0.9"],
            &["application/x-ndjsonfoo"],
            &["application/x-ndjson;q=banana"],
        ];
        for h in no {
            assert!(!wants_progress(&accept(h)), "{h:?} does not ask for NDJSON");
        }
    }

    #[test]
    fn progress_lines_only_when_they_say_something() {
        let mut last = None;
        assert_eq!(
            progress_line(0, 0, 0.1, &mut last),
            None,
            "no total announced"
        );
        assert_eq!(progress_line(5, 0, 0.2, &mut last), None);
        assert_eq!(
            progress_line(0, 10, 0.25, &mut last).as_deref(),
            Some("{\"progress\":{\"done\":0,\"total\":10,\"elapsed_s\":0.25}}\n"),
            "nothing done: no estimate of the time left"
        );
        assert_eq!(progress_line(0, 10, 0.5, &mut last), None, "repeated");
        // 3 of 10 in 1.5 s: 7 left at 0.5 s each
        assert_eq!(
            progress_line(3, 10, 1.5, &mut last).as_deref(),
            Some(
                "{\"progress\":{\"done\":3,\"total\":10,\"elapsed_s\":1.5,\"remaining_s\":3.5}}\n"
            )
        );
        assert_eq!(
            progress_line(10, 10, 4.0, &mut last).as_deref(),
            Some("{\"progress\":{\"done\":10,\"total\":10,\"elapsed_s\":4}}\n"),
            "all done: nothing left to estimate"
        );
    }

    #[tokio::test]
    async fn a_panicking_solver_answers_internal_and_frees_its_slot() {
        let s = state(60.0, 1);
        let r = run_solver(&s, |_c: &Control| -> Result<u8, ApiError> {
            panic!("deliberate panic of a solver")
        })
        .await;
        assert_eq!(r.unwrap_err().code(), "internal");
        // the only slot is free again and the pool still answers
        let r = run_solver(&s, |_c: &Control| -> Result<u8, ApiError> { Ok(7) }).await;
        assert_eq!(r.unwrap(), 7);
    }

    #[tokio::test]
    async fn physics_errors_pass_through() {
        let s = state(60.0, 2);
        let r = run_solver(&s, |_c: &Control| -> Result<u8, ApiError> {
            Err(PhysicsError::invalid(crate::physics::Param::RockDensity, 1.0, "bad").into())
        })
        .await;
        assert_eq!(r.unwrap_err().code(), "invalid_input");
    }
}

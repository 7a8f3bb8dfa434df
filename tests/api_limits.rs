//! Slow and oversized clients over a real socket: a declared body over the limit is refused at
//! once (413, never `100 Continue`), a head or body that does not arrive in time and an idle
//! keep-alive connection are ended, body bytes are admitted against a budget that is separate
//! from the solver slots. Each waits for an outcome, never for a duration; the timeouts are
//! set short so that the outcomes come quickly.

use std::net::SocketAddr;
use std::time::Duration;

use gangue::config::Config;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};

/// A server on 127.0.0.1 with short timeouts; stopped when the sender is dropped.
async fn server(config: Config) -> (SocketAddr, tokio::sync::oneshot::Sender<()>) {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    tokio::spawn(gangue::http::server::serve(listener, config, async {
        let _ = rx.await;
    }));
    (addr, tx)
}

fn short_timeouts() -> Config {
    Config {
        max_body_bytes: 4096,
        header_timeout_s: 0.3,
        body_timeout_s: 0.3,
        ..Config::default()
    }
}

/// Reads until the peer closes (or 10 s, a hang): everything the server sent.
async fn read_to_close(s: &mut TcpStream) -> String {
    let mut out = Vec::new();
    let _ = tokio::time::timeout(Duration::from_secs(10), s.read_to_end(&mut out))
        .await
        .expect("the server ends the connection");
    String::from_utf8_lossy(&out).into_owned()
}

/// Reads one answer's head and (by Content-Length) body.
async fn read_answer(s: &mut TcpStream) -> String {
    let mut out = Vec::new();
    let mut buf = [0u8; 4096];
    tokio::time::timeout(Duration::from_secs(10), async {
        loop {
            let n = s.read(&mut buf).await.unwrap();
            if n == 0 {
                break;
            }
            out.extend_from_slice(&buf[..n]);
            let text = String::from_utf8_lossy(&out);
            if let Some(end) = text.find("\r\n\r\n") {
                let len = text[..end]
                    .lines()
                    .find_map(|l| {
                        let (k, v) = l.split_once(':')?;
                        k.eq_ignore_ascii_case("content-length")
                            .then(|| v.trim().parse::<usize>().ok())?
                    })
                    .unwrap_or(0);
                if out.len() >= end + 4 + len {
                    break;
                }
            }
        }
    })
    .await
    .expect("an answer arrives");
    String::from_utf8_lossy(&out).into_owned()
}

#[tokio::test]
async fn declared_length_over_the_limit_is_refused_before_reading_and_never_continued() {
    let (addr, _stop) = server(short_timeouts()).await;
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(
        b"POST /v1/impact HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
          Content-Length: 20000000\r\nExpect: 100-continue\r\n\r\n",
    )
    .await
    .unwrap();
    // Nothing of the body is sent: the answer must come from the declared length alone.
    let answer = read_answer(&mut s).await;
    assert!(answer.starts_with("HTTP/1.1 413"), "{answer}");
    assert!(!answer.contains("100 Continue"), "{answer}");
    assert!(answer.contains("application/problem+json"), "{answer}");
    assert!(answer.contains("payload_too_large"), "{answer}");
}

#[tokio::test]
async fn expect_continue_within_the_limit_is_continued_and_answered() {
    let (addr, _stop) = server(short_timeouts()).await;
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(
        b"POST /v1/impact HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
          Content-Length: 2\r\nExpect: 100-continue\r\n\r\n",
    )
    .await
    .unwrap();
    let mut buf = [0u8; 64];
    let n = tokio::time::timeout(Duration::from_secs(10), s.read(&mut buf))
        .await
        .unwrap()
        .unwrap();
    assert!(String::from_utf8_lossy(&buf[..n]).starts_with("HTTP/1.1 100"));
    s.write_all(b"{}").await.unwrap();
    let answer = read_answer(&mut s).await;
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
}

#[tokio::test]
async fn a_head_that_never_completes_is_closed() {
    let (addr, _stop) = server(short_timeouts()).await;
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(b"POST /v1/impact HTTP/1.1\r\nHost: x\r\n")
        .await
        .unwrap();
    // The head stays incomplete: the server closes the connection (no answer is owed).
    let rest = read_to_close(&mut s).await;
    assert!(!rest.contains("200 OK"), "{rest}");
}

#[tokio::test]
async fn a_stalled_body_gets_408_and_the_connection_ends() {
    let (addr, _stop) = server(short_timeouts()).await;
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(
        b"POST /v1/impact HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
          Content-Length: 100\r\n\r\n{\"velocity_m_s\":",
    )
    .await
    .unwrap();
    let answer = read_to_close(&mut s).await;
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer}");
    assert!(answer.contains("request_timeout"), "{answer}");
}

#[tokio::test]
async fn an_idle_keep_alive_connection_is_closed() {
    let (addr, _stop) = server(short_timeouts()).await;
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
        .await
        .unwrap();
    let answer = read_answer(&mut s).await;
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    // Then nothing: the connection is ended rather than kept forever.
    let rest = read_to_close(&mut s).await;
    assert!(rest.is_empty(), "{rest}");
}

#[tokio::test]
async fn a_chunked_body_over_the_limit_is_413() {
    let (addr, _stop) = server(short_timeouts()).await;
    let mut s = TcpStream::connect(addr).await.unwrap();
    let mut req = b"POST /v1/impact HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
          Transfer-Encoding: chunked\r\n\r\n"
        .to_vec();
    for _ in 0..3 {
        req.extend_from_slice(b"800\r\n");
        req.extend_from_slice(&[b' '; 0x800]);
        req.extend_from_slice(b"\r\n");
    }
    req.extend_from_slice(b"0\r\n\r\n");
    s.write_all(&req).await.unwrap();
    let answer = read_answer(&mut s).await;
    assert!(answer.starts_with("HTTP/1.1 413"), "{answer}");
}

/// Opens a connection and sends a head declaring `len` body bytes plus the first `sent` of them.
async fn upload(addr: SocketAddr, len: usize, body: &[u8]) -> TcpStream {
    let mut s = TcpStream::connect(addr).await.unwrap();
    let head = format!(
        "POST /v1/impact HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
         Content-Length: {len}\r\n\r\n"
    );
    s.write_all(head.as_bytes()).await.unwrap();
    s.write_all(body).await.unwrap();
    s
}

#[tokio::test]
async fn slow_uploads_hold_the_body_budget_not_the_solver_slots() {
    let (addr, _stop) = server(Config {
        max_concurrent: Some(1),
        max_body_bytes: 4096,
        body_budget_bytes: Some(8192),
        body_timeout_s: 2.0,
        header_timeout_s: 5.0,
        ..Config::default()
    })
    .await;
    // One upload declares 4000 bytes and stalls.
    let mut slow1 = upload(addr, 4000, b"{").await;
    // A short request still computes on the only solver slot.
    let mut s = upload(addr, 2, b"{}").await;
    let answer = read_answer(&mut s).await;
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    // A second stalled upload takes the rest of the budget ...
    let mut slow2 = upload(addr, 4000, b"{").await;
    tokio::time::sleep(Duration::from_millis(100)).await;
    // ... so a third body cannot be admitted: 503 with Retry-After, not a pile-up in memory.
    let mut other = upload(addr, 2, b"{}").await;
    let answer = read_answer(&mut other).await;
    assert!(answer.starts_with("HTTP/1.1 503"), "{answer}");
    assert!(
        answer.to_ascii_lowercase().contains("retry-after"),
        "{answer}"
    );
    // The stalled uploads are ended by the body timeout and the budget returns.
    assert!(read_to_close(&mut slow1).await.starts_with("HTTP/1.1 408"));
    assert!(read_to_close(&mut slow2).await.starts_with("HTTP/1.1 408"));
    let mut again = upload(addr, 2, b"{}").await;
    let answer = read_answer(&mut again).await;
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
}

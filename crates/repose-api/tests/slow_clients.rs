//! Clients that send their headers a line at a time cannot hold the
//! server: 200 of them on loopback, and `/api/health` still answers well
//! before their time for headers runs out, when each loses its connection.
//! Nor can clients that connect and say nothing, stop inside a request
//! line, open with HTTP/2's preface, or keep a connection idle after an
//! answer.

use repose_api::server::{serve, Limits};
use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

/// A server on a free loopback port with `header_read` for headers; its
/// address, and a future that stops it and waits until it has.
async fn start(
    header_read: Duration,
) -> (std::net::SocketAddr, impl std::future::Future<Output = ()>) {
    let store = repose_testkit::sqlite("repose-slow").await;
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let limits = Limits {
        header_read,
        ..Default::default()
    };
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let server = tokio::spawn(serve(
        listener,
        repose_api::app(store),
        limits,
        async move {
            let _ = stopped.await;
        },
    ));
    let stop = async move {
        let _ = stop.send(());
        tokio::time::timeout(Duration::from_secs(15), server)
            .await
            .expect("the server stops")
            .unwrap();
    };
    (addr, stop)
}

async fn health(addr: std::net::SocketAddr) -> String {
    let mut s = TcpStream::connect(addr).await.unwrap();
    s.write_all(b"GET /api/health HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n")
        .await
        .unwrap();
    let mut answer = String::new();
    s.read_to_string(&mut answer).await.unwrap();
    answer
}

/// Sends header lines slowly, forever; returns when the server closes.
async fn trickle(addr: std::net::SocketAddr) -> Duration {
    let start = Instant::now();
    let mut s = TcpStream::connect(addr).await.unwrap();
    if s.write_all(b"GET /api/health HTTP/1.1\r\nHost: t\r\n")
        .await
        .is_err()
    {
        return start.elapsed();
    }
    let mut buf = [0u8; 256];
    loop {
        tokio::select! {
            read = s.read(&mut buf) => match read {
                Ok(0) | Err(_) => return start.elapsed(),
                Ok(_) => {}
            },
            () = tokio::time::sleep(Duration::from_millis(200)) => {
                if s.write_all(b"X-Slow: 1\r\n").await.is_err() {
                    return start.elapsed();
                }
            }
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_hundred_slow_clients_do_not_stop_health_answering() {
    let (addr, stop) = start(Duration::from_secs(4)).await;
    let slow: Vec<_> = (0..200).map(|_| tokio::spawn(trickle(addr))).collect();
    tokio::time::sleep(Duration::from_millis(500)).await;
    let asked = Instant::now();
    // Answered while the slow clients still hold their connections (they
    // have 4 s), not once the server has dropped them.
    let answer = tokio::time::timeout(Duration::from_secs(3), health(addr))
        .await
        .expect("health answers while 200 clients trickle their headers");
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    let answered = asked.elapsed();
    for s in slow {
        let held = tokio::time::timeout(Duration::from_secs(15), s)
            .await
            .expect("the server drops a client whose headers never end")
            .unwrap();
        assert!(held > answered, "{held:?} against {answered:?}");
        assert!(held >= Duration::from_secs(3), "{held:?}");
    }
    stop.await;
}

/// Sends `first` (maybe nothing), then stays silent; returns how long the
/// server kept the connection, or `None` if it still held it after `limit`.
async fn silent_after(
    addr: std::net::SocketAddr,
    first: &[u8],
    limit: Duration,
) -> Option<Duration> {
    let start = Instant::now();
    let mut s = TcpStream::connect(addr).await.unwrap();
    if !first.is_empty() && s.write_all(first).await.is_err() {
        return Some(start.elapsed());
    }
    let mut buf = [0u8; 4096];
    let read_until_closed = async {
        loop {
            match s.read(&mut buf).await {
                Ok(0) | Err(_) => return start.elapsed(),
                Ok(_) => {}
            }
        }
    };
    tokio::time::timeout(limit, read_until_closed).await.ok()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn clients_that_go_silent_lose_their_connections() {
    let (addr, stop) = start(Duration::from_secs(1)).await;
    let cases: [(&str, &[u8]); 4] = [
        ("connects and sends nothing", b""),
        ("sends part of a request line", b"GET /api/he"),
        (
            "sends HTTP/2's preface and stops",
            b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n",
        ),
        (
            "keeps a connection open after its answer",
            b"GET /api/health HTTP/1.1\r\nHost: t\r\n\r\n",
        ),
    ];
    for (what, first) in cases {
        let held = silent_after(addr, first, Duration::from_secs(8)).await;
        assert!(held.is_some(), "a client that {what} held its connection");
    }
    stop.await;
}

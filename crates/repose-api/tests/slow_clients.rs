//! Clients that send their headers a byte at a time cannot hold the server:
//! 200 of them on loopback, and `/api/health` still answers at once; each
//! loses its connection when its time for headers runs out.

use repose_api::server::{serve, Limits};
use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

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
    let store = repose_testkit::sqlite("repose-slow").await;
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let limits = Limits {
        header_read: Duration::from_secs(2),
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
    let slow: Vec<_> = (0..200).map(|_| tokio::spawn(trickle(addr))).collect();
    tokio::time::sleep(Duration::from_millis(500)).await;
    let asked = Instant::now();
    let answer = tokio::time::timeout(Duration::from_secs(5), health(addr))
        .await
        .expect("health answers while 200 clients trickle their headers");
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    assert!(
        asked.elapsed() < Duration::from_secs(1),
        "{:?}",
        asked.elapsed()
    );
    for s in slow {
        let held = tokio::time::timeout(Duration::from_secs(10), s)
            .await
            .expect("the server drops a client whose headers never end")
            .unwrap();
        assert!(
            held >= Duration::from_millis(1500) && held < Duration::from_secs(6),
            "{held:?}"
        );
    }
    let _ = stop.send(());
    tokio::time::timeout(Duration::from_secs(15), server)
        .await
        .expect("the server stops")
        .unwrap();
}

//! What the end-to-end tests share: the binary, scratch folders, and a
//! `repose serve` on an ephemeral port.
#![allow(dead_code)]

use repose_store::{Created, ScratchDatabase, Store};
use repose_sweeps::{JobSpec, SweepSpec};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub const BIN: &str = env!("CARGO_BIN_EXE_repose");

/// A path `name` in a new scratch folder.
pub fn scratch(name: &str) -> std::path::PathBuf {
    repose_testkit::scratch_dir("repose-e2e").join(name)
}

/// `repose serve` on an ephemeral port.
pub struct Server {
    child: Child,
    pub url: String,
}

impl Server {
    pub fn start(database: &str, workers: usize) -> Server {
        Server::start_with(database, workers, &[])
    }

    /// With extra environment variables (e.g. an access token).
    pub fn start_with(database: &str, workers: usize, env: &[(&str, &str)]) -> Server {
        let mut child = Command::new(BIN)
            .args([
                "serve",
                "--listen",
                "127.0.0.1:0",
                "--database",
                database,
                "--workers",
                &workers.to_string(),
            ])
            .envs(env.iter().copied())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("repose serve starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let url = line
            .split_whitespace()
            .find(|w| w.starts_with("http://"))
            .unwrap_or_else(|| panic!("no address in {line:?}"))
            .trim_end_matches('/')
            .to_string();
        Server { child, url }
    }
}

impl Server {
    /// Kills the server outright (SIGKILL), as a crash would.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub async fn get(url: &str) -> Value {
    reqwest::get(url).await.unwrap().json().await.unwrap()
}

pub async fn wait_until<F: Fn(&Value) -> bool>(
    url: &str,
    what: &str,
    limit: Duration,
    done: F,
) -> Value {
    let start = Instant::now();
    loop {
        let v = get(url).await;
        if done(&v) {
            return v;
        }
        assert!(start.elapsed() < limit, "timed out waiting for {what}: {v}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

pub fn finished(sweep: &Value) -> bool {
    let p = &sweep["progress"];
    p["queued"] == 0 && p["running"] == 0
}

/// POSTs a JSON body and returns the JSON answer.
pub async fn post(url: &str, body: &Value) -> Value {
    reqwest::Client::new()
        .post(url)
        .json(body)
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap()
}

/// Queues a sweep on the server and waits until none of its jobs is left.
pub async fn run_sweep(server: &Server, spec: &Value) -> String {
    let created = post(&format!("{}/api/sweeps", server.url), spec).await;
    let id = created["id"]
        .as_str()
        .unwrap_or_else(|| panic!("{created}"))
        .to_string();
    wait_until(
        &format!("{}/api/sweeps/{id}", server.url),
        "the sweep",
        Duration::from_secs(180),
        finished,
    )
    .await;
    id
}

/// Expands a sweep and stores it with its jobs, as the API does.
pub async fn create(store: &Store, spec: &SweepSpec, max_attempts: i64) -> (Created, Vec<JobSpec>) {
    let jobs = spec.expand().unwrap();
    let new: Vec<_> = jobs.iter().map(JobSpec::to_new_job).collect();
    let created = store
        .create_sweep(&spec.new_sweep(), &new, max_attempts)
        .await
        .unwrap();
    (created, jobs)
}

/// A `repose worker` process on `database`, its stderr piped.
pub fn worker(database: &str, extra: &[&str]) -> Child {
    Command::new(BIN)
        .args(["worker", "--database", database])
        .args(extra)
        // Warnings (a locked database, a failed write) are what tests read.
        .env("REPOSE_LOG", "warn")
        .stderr(Stdio::piped())
        .spawn()
        .expect("repose worker starts")
}

/// Sends a signal (`TERM`, `KILL`) to a child process.
pub fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args(["-s", name, &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success(), "kill -s {name} failed");
}

/// A fresh database on the test PostgreSQL server; none when there is no
/// server, except in CI.
pub async fn postgres() -> Option<ScratchDatabase> {
    repose_testkit::postgres("repose_e2e").await
}

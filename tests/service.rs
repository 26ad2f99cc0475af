//! End-to-end tests of the sweep service: the real `repose` binary, real
//! SQLite files and a real PostgreSQL server (127.0.0.1:5432, or
//! `REPOSE_TEST_POSTGRES`). With `CI=true` the PostgreSQL tests fail when
//! the server is unreachable; elsewhere they skip with a message.

use repose_store::Store;
use repose_sweeps::{JobSpec, SweepSpec};
use serde_json::{json, Value};
use std::process::{Child, Command};
use std::time::{Duration, Instant};

#[path = "common/mod.rs"]
mod common;

use common::{create, finished, get, postgres, scratch, signal, wait_until, worker, Server, BIN};

/// Starts `count` worker processes that leave when the queue is empty,
/// waits for all of them, and returns what each wrote to stderr.
fn run_workers_until_idle(database: &str, count: usize) -> Vec<String> {
    let workers: Vec<Child> = (0..count)
        .map(|_| worker(database, &["--exit-when-idle"]))
        .collect();
    workers
        .into_iter()
        .map(|w| {
            let out = w.wait_with_output().unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
            assert!(out.status.success(), "{stderr}");
            stderr
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sweep_runs_end_to_end_and_its_points_match_its_samples() {
    let db = format!("sqlite://{}", scratch("e2e.db").display());
    let server = Server::start(&db, 2);
    let spec = json!({
        "name": "θ_R against μ, 2 × 2 box",
        "protocol": "fill_release",
        "base": {"box": {"width": 2.0, "height": 2.0}},
        "axes": {"contact.mu": [0.05, 0.3]},
        "samples": 3,
        "fidelity": "quick"
    });
    let client = reqwest::Client::new();
    let resp = client
        .post(format!("{}/api/sweeps", server.url))
        .json(&spec)
        .send()
        .await
        .unwrap();
    assert_eq!(resp.status(), 201);
    let created: Value = resp.json().await.unwrap();
    let id = created["id"].as_str().unwrap().to_string();
    let sweep = wait_until(
        &format!("{}/api/sweeps/{id}", server.url),
        "the sweep",
        Duration::from_secs(120),
        finished,
    )
    .await;
    assert_eq!(sweep["progress"]["done"], 6, "{sweep}");
    assert_eq!(sweep["eta_seconds"], 0.0);

    let samples = get(&format!("{}/api/sweeps/{id}/samples", server.url)).await;
    let samples = samples["samples"].as_array().unwrap().clone();
    assert_eq!(samples.len(), 6);
    let points = get(&format!("{}/api/sweeps/{id}/points", server.url)).await;
    let fig = get(&format!("{}/api/sweeps/{id}/figures/lh93/3", server.url)).await;
    assert_eq!(fig["x"], "contact.mu");
    let measured = fig["series"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["kind"] == "measured")
        .unwrap();
    let series = measured["points"].as_array().unwrap();
    assert_eq!(series.len(), 2);
    let points = points["points"].as_array().unwrap();
    assert_eq!(points.len(), 2, "{points:?}");
    for p in points {
        point_matches_its_samples(p, &samples, series);
    }
    // the physics came through: more friction, steeper pile
    assert!(
        series[1]["y"].as_f64().unwrap() > series[0]["y"].as_f64().unwrap() + 5.0,
        "{fig}"
    );
    // every sample's full report is there, with its seed and engine
    let hash = samples[0]["sample_hash"].as_str().unwrap();
    let report = get(&format!("{}/api/samples/{hash}", server.url)).await;
    assert_eq!(report["seed"], samples[0]["seed"]);
    assert!(report["final_state"]["grains"].as_array().unwrap().len() > 5);
    // CSV exports through the CLI
    let out = Command::new(BIN)
        .args(["export", &id, "--what", "points", "--server", &server.url])
        .output()
        .unwrap();
    assert!(out.status.success());
    let csv = String::from_utf8(out.stdout).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    assert!(csv.starts_with("axis:contact.mu,samples,failures,theta_r_n,theta_r_mean"));
    // Asking again reuses every sample.
    let again: Value = client
        .post(format!("{}/api/sweeps", server.url))
        .json(&spec)
        .send()
        .await
        .unwrap()
        .json()
        .await
        .unwrap();
    assert_eq!(again["reused"], 6, "{again}");
}

/// A point's statistics recomputed from its stored samples, and the same
/// numbers (with the single samples) on the figure.
fn point_matches_its_samples(p: &Value, samples: &[Value], series: &[Value]) {
    let values: Vec<f64> = samples
        .iter()
        .filter(|s| s["point"] == p["point"])
        .filter_map(|s| s["metrics"]["theta_r"].as_f64())
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let m = &p["metrics"]["theta_r"];
    assert_eq!(m["n"].as_f64().unwrap(), n);
    assert!((m["mean"].as_f64().unwrap() - mean).abs() < 1e-9, "{p}");
    assert!((m["sd"].as_f64().unwrap() - sd).abs() < 1e-9, "{p}");
    assert!(
        (m["sem"].as_f64().unwrap() - sd / n.sqrt()).abs() < 1e-9,
        "{p}"
    );
    let on_figure = series
        .iter()
        .find(|s| s["x"] == p["point"]["contact.mu"])
        .unwrap();
    assert_eq!(on_figure["y"], m["mean"]);
    assert_eq!(on_figure["sd"], m["sd"]);
    let mut drawn: Vec<f64> = on_figure["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let mut stored = values;
    drawn.sort_by(f64::total_cmp);
    stored.sort_by(f64::total_cmp);
    assert_eq!(drawn, stored);
}

/// Cheap jobs: one grain dropped on a floor for a few milliseconds.
fn cheap_sweep(samples: u32) -> SweepSpec {
    sweep_lasting(samples, 0.02)
}

/// One grain dropped on a floor for `duration` simulated seconds, `samples` times.
fn sweep_lasting(samples: u32, duration: f64) -> SweepSpec {
    serde_json::from_value(json!({
        "protocol": "free_run",
        "base": {
            "duration": duration,
            "particles": [{"position": [0.0, 0.3], "radius": 0.1}],
            "walls": [{"point": [0.0, 0.0], "normal": [0.0, 1.0]}]
        },
        "samples": samples
    }))
    .unwrap()
}

async fn assert_every_job_done_once(store: &Store, sweep: &str, jobs: &[JobSpec]) {
    let p = store.progress(sweep).await.unwrap();
    assert_eq!(
        (p.done, p.queued, p.running, p.failed),
        (jobs.len() as i64, 0, 0, 0),
        "{p:?}"
    );
    for j in jobs {
        assert_eq!(store.result_count(&j.sample_hash).await.unwrap(), 1);
    }
    let total: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM results")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert_eq!(total, jobs.len() as i64);
}

/// A worker's closing tally: results written and leases lost.
fn tally(stderr: &str) -> (u64, u64) {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("repose worker:"))
        .unwrap_or_else(|| panic!("no tally in {stderr}"));
    let count = |what: &str| -> u64 {
        let before = line.split(what).next().unwrap_or_default();
        let n = before
            .trim_end()
            .rsplit([' ', ','])
            .next()
            .unwrap_or_default();
        n.parse().unwrap_or_else(|_| panic!("{what} in {line}"))
    };
    (count(" results written"), count(" lost leases"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn worker_processes_on_postgres_share_the_jobs_and_do_each_once() {
    let Some(db) = postgres().await else { return };
    let url = db.url().to_string();
    let store = Store::open(&url).await.unwrap();
    // The workers wait on the empty queue first, so that all of them are
    // there to claim when the sweep arrives.
    let workers: Vec<Child> = (0..4).map(|_| worker(&url, &[])).collect();
    tokio::time::sleep(Duration::from_secs(1)).await;
    // Long enough (some 50 ms a job) that the sweep outlasts the idle
    // workers' 0.5 s between looks at the queue: with the cheapest jobs the
    // first worker to look could finish all 60 before the others wake.
    let spec = sweep_lasting(60, 5.0);
    let (created, jobs) = create(&store, &spec, 3).await;
    let start = Instant::now();
    while store.progress(&created.id).await.unwrap().done < 60 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "the sweep never finished"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let mut written = Vec::new();
    for w in workers {
        signal(&w, "TERM");
        let out = w.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{stderr}");
        let (n, lost) = tally(&stderr);
        assert_eq!(lost, 0, "{stderr}");
        written.push(n);
    }
    assert_every_job_done_once(&store, &created.id, &jobs).await;
    // Every result written once, by more than one worker, each job claimed once.
    assert_eq!(written.iter().sum::<u64>(), 60, "{written:?}");
    assert!(
        written.iter().filter(|n| **n > 0).count() >= 2,
        "{written:?}"
    );
    let attempts: i64 = sqlx::query_scalar("SELECT MAX(attempts) FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert_eq!(attempts, 1);
    repose_testkit::drop_postgres(db, store).await;
}

/// `url` with its user replaced.
fn as_user(url: &str, user: &str) -> String {
    let (scheme, rest) = url.split_once("://").unwrap();
    let host = rest.split_once('@').map_or(rest, |(_, h)| h);
    format!("{scheme}://{user}@{host}")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_with_the_least_privilege_role_finishes_a_sweep_on_postgres() {
    let Some(db) = postgres().await else { return };
    let store = Store::open(db.url()).await.unwrap();
    let (created, jobs) = create(&store, &cheap_sweep(12), 3).await;
    let roles = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/postgres/roles.sql"),
    )
    .unwrap();
    sqlx::raw_sql(&roles).execute(store.pool()).await.unwrap();
    let url = as_user(db.url(), "repose_worker");
    for stderr in run_workers_until_idle(&url, 2) {
        assert!(
            !stderr.contains("could not") && !stderr.contains("failed"),
            "{stderr}"
        );
    }
    assert_every_job_done_once(&store, &created.id, &jobs).await;
    // The role can do a worker's work and nothing else.
    let worker = sqlx::AnyPool::connect(&url).await.unwrap();
    for statement in [
        "DELETE FROM results",
        "DELETE FROM result_reports",
        "UPDATE sweeps SET state = 'cancelled'",
        "INSERT INTO sweeps (id) VALUES ('x')",
        "DROP TABLE metric_values",
        "CREATE TABLE intruder (x INTEGER)",
    ] {
        let err = sqlx::query(statement)
            .execute(&worker)
            .await
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("permission denied") || err.contains("must be owner"),
            "{statement}: {err}"
        );
    }
    worker.close().await;
    repose_testkit::drop_postgres(db, store).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn four_workers_on_one_sqlite_file_never_see_a_locked_database() {
    let url = format!("sqlite://{}", scratch("busy.db").display());
    let store = Store::open(&url).await.unwrap();
    let spec = cheap_sweep(120);
    let (created, jobs) = create(&store, &spec, 3).await;
    for stderr in run_workers_until_idle(&url, 4) {
        assert!(!stderr.contains("locked"), "{stderr}");
        assert_eq!(tally(&stderr).1, 0, "{stderr}");
    }
    assert_every_job_done_once(&store, &created.id, &jobs).await;
}

/// One real pile (about two seconds of work) on the given database.
async fn one_long_job(url: &str) -> (Store, String, Vec<JobSpec>) {
    let store = Store::open(url).await.unwrap();
    let spec: SweepSpec =
        serde_json::from_value(json!({"protocol": "fill_release", "samples": 1})).unwrap();
    let (created, jobs) = create(&store, &spec, 3).await;
    (store, created.id, jobs)
}

/// The lines a child writes to its stderr, as they come.
fn stderr_lines(child: &mut Child) -> std::sync::mpsc::Receiver<String> {
    use std::io::BufRead;
    let stderr = child.stderr.take().expect("stderr is piped");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stderr).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

async fn wait_running(store: &Store, sweep: &str) {
    let start = Instant::now();
    while store.progress(sweep).await.unwrap().running == 0 {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "the job never started"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_keeps_its_result_through_a_database_outage_and_writes_it_after() {
    let Some(db) = postgres().await else { return };
    let (store, sweep, jobs) = one_long_job(db.url()).await;
    let mut w = worker(
        db.url(),
        &["--exit-when-idle", "--lease", "30", "--heartbeat", "1"],
    );
    let lines = stderr_lines(&mut w);
    wait_running(&store, &sweep).await;
    // The database goes away: no new connections, every open one cut.
    let admin = |sql: String| {
        let pool = db.admin().clone();
        async move { sqlx::query(&sql).execute(&pool).await.unwrap() }
    };
    admin(format!(
        "ALTER DATABASE {} ALLOW_CONNECTIONS false",
        db.name()
    ))
    .await;
    admin(format!(
        "SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE datname = '{}'",
        db.name()
    ))
    .await;
    // Down until the run has ended and a write of its result has failed,
    // however long the run takes on a busy machine.
    let mut stderr = String::new();
    while !stderr.contains("could not store the result") {
        let line = lines
            .recv_timeout(Duration::from_secs(120))
            .unwrap_or_else(|_| panic!("no failed write while the database was down: {stderr}"));
        stderr.push_str(&line);
        stderr.push('\n');
    }
    admin(format!(
        "ALTER DATABASE {} ALLOW_CONNECTIONS true",
        db.name()
    ))
    .await;
    let status = w.wait().unwrap();
    stderr.extend(lines.iter().map(|l| l + "\n"));
    assert!(status.success(), "{stderr}");
    assert!(stderr.contains("1 results written"), "{stderr}");
    assert!(
        !stderr.contains("lease lost") && !stderr.contains("lease ran out"),
        "the lease ran out: {stderr}"
    );
    assert_every_job_done_once(&store, &sweep, &jobs).await;
    let attempts: i64 = sqlx::query_scalar("SELECT MAX(attempts) FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert_eq!(attempts, 1, "the job ran twice");
    repose_testkit::drop_postgres(db, store).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_worker_loses_its_lease_and_another_finishes_the_job() {
    let Some(db) = postgres().await else { return };
    let url = db.url().to_string();
    let (store, sweep, jobs) = one_long_job(&url).await;
    let mut doomed = worker(&url, &["--lease", "1.5", "--heartbeat", "0.3"]);
    wait_running(&store, &sweep).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    signal(&doomed, "KILL");
    doomed.wait().unwrap();
    let rescuer = worker(&url, &["--lease", "1.5", "--heartbeat", "0.3"]);
    let start = Instant::now();
    while store.progress(&sweep).await.unwrap().done == 0 {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the job was never finished"
        );
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    signal(&rescuer, "TERM");
    let out = rescuer.wait_with_output().unwrap();
    assert!(out.status.success());
    assert_every_job_done_once(&store, &sweep, &jobs).await;
    let attempts: i64 = sqlx::query_scalar("SELECT attempts FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert_eq!(attempts, 2, "the first attempt died with its worker");
    repose_testkit::drop_postgres(db, store).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sigterm_hands_the_running_job_back_unwritten() {
    let url = format!("sqlite://{}", scratch("term.db").display());
    let (store, sweep, _) = one_long_job(&url).await;
    let w = worker(&url, &[]);
    wait_running(&store, &sweep).await;
    signal(&w, "TERM");
    let out = w.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("1 jobs handed back"), "{stderr}");
    let p = store.progress(&sweep).await.unwrap();
    assert_eq!((p.queued, p.running, p.done), (1, 0, 0));
    let results: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM results")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert_eq!(results, 0);
    let attempts: i64 = sqlx::query_scalar("SELECT attempts FROM jobs")
        .fetch_one(store.pool())
        .await
        .unwrap();
    assert_eq!(attempts, 0, "a handed-back job does not use up an attempt");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn submit_refuses_a_bad_spec_naming_the_field() {
    let db = format!("sqlite://{}", scratch("submit.db").display());
    let server = Server::start(&db, 0);
    let spec = scratch("bad.toml");
    std::fs::write(
        &spec,
        "protocol = \"tilt\"\n[axes]\n\"contact.mu\" = [0.2, -0.5]\n",
    )
    .unwrap();
    let out = Command::new(BIN)
        .args(["submit", spec.to_str().unwrap(), "--server", &server.url])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("axes.contact.mu"), "{stderr}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sample_that_fails_is_stored_with_its_reason_and_no_angle() {
    let db = format!("sqlite://{}", scratch("failing.db").display());
    let server = Server::start(&db, 2);
    // t_c = 7.1e-4 s for these grains: t_c/50 runs, 0.3 t_c is accepted by
    // validation but cannot resolve a contact, and a guard stops the fill.
    let spec = json!({
        "name": "a time step too coarse for the contacts",
        "protocol": "fill_release",
        "base": {"box": {"width": 1.6, "height": 1.6}},
        "axes": {"numerics.dt": [1.4e-5, 2.1e-4]},
        "samples": 2,
        "fidelity": "quick"
    });
    let id = common::run_sweep(&server, &spec).await;
    let sweep = get(&format!("{}/api/sweeps/{id}", server.url)).await;
    // The job itself ran to the end: its sample is a result, a failed one.
    assert_eq!(sweep["progress"]["done"], 4, "{sweep}");

    let samples = get(&format!("{}/api/sweeps/{id}/samples", server.url)).await;
    let samples = samples["samples"].as_array().unwrap().clone();
    assert_eq!(samples.len(), 4);
    for s in &samples {
        let coarse = s["point"]["numerics.dt"] == json!(2.1e-4);
        if coarse {
            assert_eq!(s["outcome"], "failed", "{s}");
            let reason = s["reason"].as_str().unwrap_or_default();
            assert!(reason.contains("time step"), "{s}");
            assert!(
                s["metrics"]["theta_r"].is_null(),
                "a failed run reports no angle: {s}"
            );
            // The full report carries the same reason.
            let hash = s["sample_hash"].as_str().unwrap();
            let report = get(&format!("{}/api/samples/{hash}", server.url)).await;
            let outcome = &report["outcome"];
            assert_eq!(outcome["status"], "failed");
            assert_eq!(
                format!(
                    "{}: {}",
                    outcome["phase"].as_str().unwrap(),
                    outcome["reason"].as_str().unwrap()
                ),
                reason
            );
        } else {
            assert_eq!(s["outcome"], "completed", "{s}");
            assert!(s["metrics"]["theta_r"].as_f64().is_some(), "{s}");
        }
    }
    let points = get(&format!("{}/api/sweeps/{id}/points", server.url)).await;
    let points = points["points"].as_array().unwrap();
    assert_eq!(points.len(), 2, "{points:?}");
    for p in points {
        let coarse = p["point"]["numerics.dt"] == json!(2.1e-4);
        let expected = if coarse { (2, 0) } else { (0, 2) };
        let got = (
            p["failures"].as_u64().unwrap(),
            p["metrics"]["theta_r"]["n"].as_u64().unwrap(),
        );
        assert_eq!(got, expected, "{p}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn retry_runs_failed_jobs_again_and_backup_copies_a_live_store() {
    let db = format!("sqlite://{}", scratch("retry.db").display());
    let store = Store::open(&db).await.unwrap();
    let (created, jobs) = create(&store, &cheap_sweep(6), 3).await;
    // Lost workers used up the attempts of three jobs.
    for _ in 0..3 {
        let job = store
            .claim("lost", Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert!(store
            .fail(&job.job_id, "lost", "lease lost three times")
            .await
            .unwrap());
    }
    let token = "retry-test-token-0123456789";
    let server = Server::start_with(&db, 2, &[("REPOSE_TOKEN", token)]);
    let sweep_url = format!("{}/api/sweeps/{}", server.url, created.id);
    wait_until(&sweep_url, "the other jobs", Duration::from_secs(60), |s| {
        s["progress"]["done"] == 3 && s["progress"]["failed"] == 3
    })
    .await;
    let retry = |with_token: bool| {
        let mut c = Command::new(BIN);
        c.args(["retry", &created.id, "--server", &server.url])
            .env_remove("REPOSE_TOKEN")
            .env_remove("REPOSE_TOKEN_FILE");
        if with_token {
            c.env("REPOSE_TOKEN", token);
        }
        c.output().unwrap()
    };
    let refused = retry(false);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("401"));
    let out = retry(true);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("3 failed jobs queued again"), "{stdout}");
    wait_until(
        &sweep_url,
        "the retried jobs",
        Duration::from_secs(60),
        finished,
    )
    .await;
    assert_every_job_done_once(&store, &created.id, &jobs).await;
    // A consistent copy of the store while the server has it open.
    let copy = scratch("copy.db");
    let backup = |to: &std::path::Path| {
        Command::new(BIN)
            .args(["backup", "--database", &db, to.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let out = backup(&copy);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("1 sweeps, 6 jobs, 6 results"), "{stdout}");
    let copied = Store::open(&format!("sqlite://{}", copy.display()))
        .await
        .unwrap();
    assert_every_job_done_once(&copied, &created.id, &jobs).await;
    let again = backup(&copy);
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("exists already"));
    // A store that is not there is named, not created empty and copied.
    let missing = scratch("missing.db");
    let out = Command::new(BIN)
        .args(["backup", "--database"])
        .arg(format!("sqlite://{}", missing.display()))
        .arg(scratch("copy-of-missing.db"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--database") && stderr.contains("no store"),
        "{stderr}"
    );
    assert!(!missing.exists());
}

//! `repose bench-service`: what the service itself costs.
//!
//! 1. Queue overhead: claim + complete of no-op jobs per second, with
//!    several claimers at once, on SQLite and on PostgreSQL.
//! 2. Query latency: the points and figure queries over sweeps of 10⁵ and
//!    10⁶ stored samples (the rows are bulk-loaded and their running
//!    aggregates built; only the queries are timed).
//! 3. End-to-end speed-up of a real sweep of one-second jobs with one
//!    worker against two.

use anyhow::Context;
use repose_physics::{run, Quiet, Scene};
use repose_store::{now_ms, Backend, NewJob, ResultRecord, ScratchDatabase, Store};
use repose_sweeps::SweepSpec;
use repose_worker::{record, run_worker, WorkerConfig};
use serde_json::json;
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct BenchServiceArgs {
    /// PostgreSQL server to measure too (a scratch database is created and dropped).
    #[arg(long, default_value = "postgres://postgres@127.0.0.1:5432")]
    postgres: String,
    /// Skip PostgreSQL.
    #[arg(long)]
    no_postgres: bool,
    /// No-op jobs for the queue measurement.
    #[arg(long, default_value_t = 2000)]
    jobs: u32,
    /// Concurrent claimers.
    #[arg(long, default_value_t = 4)]
    claimers: usize,
    /// Stored samples of the sweeps the queries are timed on.
    #[arg(long, num_args = 1.., default_values_t = [100_000, 1_000_000])]
    samples: Vec<usize>,
    /// Samples of the end-to-end sweep (each about a second of work).
    #[arg(long, default_value_t = 40)]
    sweep_samples: u32,
}

/// The stored result of a tiny free run, written for every no-op job.
fn tiny_record() -> anyhow::Result<ResultRecord> {
    let scene = Scene::from_toml(
        "protocol = \"free_run\"\nduration = 0.0001\n[[particles]]\nposition = [0.0, 0.0]\nradius = 0.1",
        &[],
    )?;
    let mut r = run(&scene, &mut Quiet)?;
    r.final_state = None;
    r.energy_trace.clear();
    Ok(record(&r)?)
}

/// Stores a sweep and its jobs.
async fn store_sweep(store: &Store, spec: &SweepSpec) -> anyhow::Result<()> {
    let jobs: Vec<NewJob> = spec.expand()?.iter().map(|j| j.to_new_job()).collect();
    store.create_sweep(&spec.new_sweep(), &jobs, 3).await?;
    Ok(())
}

fn noop_sweep(samples: u32) -> SweepSpec {
    serde_json::from_value(json!({
        "protocol": "free_run",
        "base": { "duration": 0.0001, "particles": [{"position": [0.0, 0.0], "radius": 0.1}] },
        "samples": samples
    }))
    .unwrap_or_else(|e| panic!("the benchmark's own sweep is valid: {e}"))
}

/// Claim + complete throughput with `claimers` concurrent tasks.
async fn queue_overhead(store: &Store, jobs: u32, claimers: usize) -> anyhow::Result<f64> {
    store_sweep(store, &noop_sweep(jobs)).await?;
    let report = tiny_record()?;
    let clock = Instant::now();
    let mut tasks = Vec::new();
    for k in 0..claimers {
        let store = store.clone();
        let report = report.clone();
        tasks.push(tokio::spawn(async move {
            let owner = format!("bench-{k}");
            let mut n = 0u32;
            while let Some(c) = store.claim(&owner, Duration::from_secs(60)).await? {
                store
                    .complete(&c.job_id, &owner, &c.sample_hash, &report)
                    .await?;
                n += 1;
            }
            Ok::<_, repose_store::StoreError>(n)
        }));
    }
    let mut done = 0;
    for t in tasks {
        done += t.await??;
    }
    anyhow::ensure!(done == jobs, "{done} of {jobs} jobs done");
    Ok(jobs as f64 / clock.elapsed().as_secs_f64())
}

/// Bulk-loads a sweep of `samples` results over 100 points (10 μ × 10 W)
/// with plausible angles; returns the sweep id.
async fn load_samples(store: &Store, samples: usize) -> anyhow::Result<String> {
    let id = uuid::Uuid::new_v4().to_string();
    let now = now_ms();
    let spec =
        json!({"protocol": "fill_release", "axes": {"contact.mu": [0.0], "box.width": [0.0]}});
    sqlx::query(&format!(
        "INSERT INTO sweeps (id, name, protocol, spec, priority, state, created_at) \
         VALUES ('{id}', 'benchmark', 'fill_release', '{spec}', 0, 'active', {now})"
    ))
    .execute(store.pool())
    .await?;
    let per_point = samples.div_ceil(100);
    let batch = 250;
    let mut tx = store.pool().begin().await?;
    let (mut jobs, mut results) = (Vec::with_capacity(batch), Vec::with_capacity(batch));
    let mut reports = Vec::with_capacity(batch);
    let mut metrics = Vec::with_capacity(4 * batch);
    for k in 0..samples {
        let point = k / per_point;
        let (mu, width) = (0.05 * (point % 10) as f64, 1.0 + (point / 10) as f64);
        let seed = (k % per_point) as i64;
        let hash = format!("{id}-{k}");
        let theta = 10.0 + 60.0 * mu + ((k * 7919) % 1000) as f64 / 250.0;
        jobs.push(format!(
            "('{id}-j{k}', '{id}', {k}, '{{\"box.width\":{width},\"contact.mu\":{mu}}}', {seed}, {seed}, '{hash}', '{{}}', 'done', 1, 3, {now}, {now})"
        ));
        results.push(format!(
            "('{hash}', '{id}-j{k}', 'bench', {seed}, 'completed', NULL, 400, 100, 300, 150000, 2.0, 1.5, {now})"
        ));
        reports.push(format!("('{hash}', '{{}}')"));
        for (metric, v) in [
            ("theta_r", theta),
            ("theta_r_line", theta + 1.0),
            ("theta_r_endpoints", theta + 2.0),
            ("theta_t", 4.0 + mu),
        ] {
            metrics.push(format!("('{hash}', '{metric}', {v})"));
        }
        if jobs.len() == batch || k + 1 == samples {
            sqlx::query(&format!(
                "INSERT INTO jobs (id, sweep_id, seq, point, sample, seed, sample_hash, scene, state, attempts, max_attempts, created_at, updated_at) VALUES {}",
                jobs.join(",")
            ))
            .execute(&mut *tx)
            .await?;
            sqlx::query(&format!(
                "INSERT INTO results (sample_hash, job_id, engine, seed, outcome, reason, grains_initial, grains_final, \
                 grains_lost, iterations, simulated_time, wall_time, created_at) VALUES {}",
                results.join(",")
            ))
            .execute(&mut *tx)
            .await?;
            sqlx::query(&format!(
                "INSERT INTO result_reports (sample_hash, report) VALUES {}",
                reports.join(",")
            ))
            .execute(&mut *tx)
            .await?;
            sqlx::query(&format!(
                "INSERT INTO metric_values (sample_hash, metric, value) VALUES {}",
                metrics.join(",")
            ))
            .execute(&mut *tx)
            .await?;
            jobs.clear();
            results.clear();
            reports.clear();
            metrics.clear();
        }
    }
    tx.commit().await?;
    store.rebuild_aggregates(&id).await?;
    Ok(id)
}

/// Median and fastest of five timings of `f`, in milliseconds.
async fn time_ms<F, Fut, T>(mut f: F) -> anyhow::Result<(f64, f64)>
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = anyhow::Result<T>>,
{
    let mut times = Vec::new();
    for _ in 0..5 {
        let clock = Instant::now();
        f().await?;
        times.push(clock.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    Ok((times[2], times[0]))
}

async fn measure(label: &str, store: &Store, args: &BenchServiceArgs) -> anyhow::Result<()> {
    let rate = queue_overhead(store, args.jobs, args.claimers).await?;
    outln!(
        "{label:<10} queue: {rate:8.0} claim+complete per second ({} no-op jobs, {} claimers)",
        args.jobs,
        args.claimers
    )?;
    for &samples in &args.samples {
        query_latency(label, store, samples).await?;
    }
    Ok(())
}

/// Times the points query and a figure series over a sweep of `samples`.
async fn query_latency(label: &str, store: &Store, samples: usize) -> anyhow::Result<()> {
    let clock = Instant::now();
    let sweep = load_samples(store, samples).await?;
    let load = clock.elapsed().as_secs_f64();
    let (points_med, points_min) = time_ms(|| async { Ok(store.points(&sweep).await?) }).await?;
    let (fig_med, fig_min) = time_ms(|| async {
        let points = store.points(&sweep).await?;
        Ok(repose_store::series(
            &points,
            "contact.mu",
            Some("box.width"),
            "theta_r",
        )?)
    })
    .await?;
    let n = store.points(&sweep).await?.len();
    outln!(
        "{label:<10} query over {samples} samples ({n} points; loaded in {load:.1} s): points {points_med:.2} ms (min {points_min:.2}), figure series {fig_med:.2} ms (min {fig_min:.2})"
    )?;
    Ok(())
}

async fn sweep_time(workers: usize, samples: u32) -> anyhow::Result<f64> {
    let dir = std::env::temp_dir().join(format!(
        "repose-bench-{}-{}",
        std::process::id(),
        uuid::Uuid::new_v4()
    ));
    std::fs::create_dir_all(&dir)?;
    let store = Store::open(&format!("sqlite://{}", dir.join("e2e.db").display())).await?;
    let spec: SweepSpec = serde_json::from_value(json!({
        "protocol": "fill_release",
        "base": {"box": {"width": 4.0, "height": 4.0}},
        "samples": samples,
        "fidelity": "standard"
    }))?;
    store_sweep(&store, &spec).await?;
    let (_tx, rx) = tokio::sync::watch::channel(false);
    let clock = Instant::now();
    let tasks: Vec<_> = (0..workers)
        .map(|k| {
            let mut config = WorkerConfig::new(format!("bench-{k}"));
            config.exit_when_idle = true;
            tokio::spawn(run_worker(store.clone(), config, rx.clone()))
        })
        .collect();
    let mut done = 0;
    for t in tasks {
        done += t.await?.completed;
    }
    anyhow::ensure!(done == samples as u64, "{done} of {samples} samples done");
    let _ = std::fs::remove_dir_all(dir);
    Ok(clock.elapsed().as_secs_f64())
}

pub fn run_bench(args: BenchServiceArgs) -> anyhow::Result<ExitCode> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?;
    rt.block_on(async {
        let dir = std::env::temp_dir().join(format!("repose-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let sqlite = Store::open(&format!("sqlite://{}", dir.join("queue.db").display())).await?;
        measure("SQLite", &sqlite, &args).await?;
        drop(sqlite);
        let _ = std::fs::remove_dir_all(&dir);

        if !args.no_postgres {
            let db = ScratchDatabase::create(&args.postgres, "repose_bench")
                .await
                .with_context(|| format!("cannot reach PostgreSQL at {} (use --no-postgres to skip)", args.postgres))?;
            let pg = db.open().await?;
            assert_eq!(pg.backend(), Backend::Postgres);
            let result = measure("PostgreSQL", &pg, &args).await;
            pg.pool().close().await;
            db.drop_database().await?;
            result?;
        }

        let one = sweep_time(1, args.sweep_samples).await?;
        let two = sweep_time(2, args.sweep_samples).await?;
        outln!(
            "sweep      {} fill-and-release samples (4 × 4 box): 1 worker {one:.2} s, 2 workers {two:.2} s, speed-up {:.2}×",
            args.sweep_samples,
            one / two
        )?;
        Ok(ExitCode::SUCCESS)
    })
}

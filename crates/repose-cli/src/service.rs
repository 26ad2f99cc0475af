//! The service commands: `serve` (API plus embedded workers), `worker`
//! (headless, for cluster nodes), and the clients `submit`, `status` and
//! `export`, which talk to a running server over its HTTP API.

use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressStyle};
use repose_store::Store;
use repose_worker::{run_worker, shutdown_on_signals, Cores, Tally, WorkerConfig};
use serde_json::Value;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// The embedded default database: a file beside where `repose serve` runs.
pub const DEFAULT_DATABASE: &str = "sqlite://repose.db";
pub(crate) const DEFAULT_SERVER: &str = "http://127.0.0.1:8080";

#[derive(clap::Args)]
pub struct ServeArgs {
    /// Database URL: sqlite://FILE (created on first start) or postgres://...
    #[arg(long, default_value = DEFAULT_DATABASE, env = "REPOSE_DATABASE")]
    database: String,
    /// Address to listen on (port 0 picks a free one).
    #[arg(long, default_value = "127.0.0.1:8080")]
    listen: String,
    /// Embedded workers (default: one per core; 0 for an API-only server).
    #[arg(long)]
    workers: Option<usize>,
    /// Folder of generated reports to serve at /docs/ (falls back to the
    /// copies compiled into the binary).
    #[arg(long, default_value = "docs")]
    docs: PathBuf,
    /// File holding the access token that creating, queueing, cancelling
    /// and retrying sweeps require (or set REPOSE_TOKEN). Required to
    /// listen beyond loopback.
    #[arg(long, env = "REPOSE_TOKEN_FILE")]
    token_file: Option<PathBuf>,
    /// Reading results needs the token too (the page asks for it).
    #[arg(long)]
    private: bool,
    /// Listen beyond loopback without a token: anyone who reaches the port
    /// can queue and cancel sweeps.
    #[arg(long)]
    insecure_open: bool,
    /// Seconds a client has to send a request's headers.
    #[arg(long, default_value_t = 10.0)]
    header_timeout: f64,
    /// Seconds a request may take from its headers to its answer.
    #[arg(long, default_value_t = 60.0)]
    request_timeout: f64,
    #[command(flatten)]
    lease: LeaseArgs,
}

impl ServeArgs {
    /// The token from `--token-file` or `REPOSE_TOKEN`, checked.
    fn token(&self) -> anyhow::Result<Option<repose_api::Token>> {
        let secret = match (&self.token_file, std::env::var("REPOSE_TOKEN")) {
            (Some(path), _) => std::fs::read_to_string(path)
                .with_context(|| format!("cannot read the token file {}", path.display()))?,
            (None, Ok(secret)) => secret,
            (None, Err(_)) => return Ok(None),
        };
        repose_api::Token::new(&secret)
            .map(Some)
            .map_err(|e| anyhow::anyhow!("--token-file: {e}"))
    }

    /// Who may do what, refusing an open server beyond loopback.
    fn access(&self, addr: std::net::SocketAddr) -> anyhow::Result<repose_api::Access> {
        let token = self.token()?;
        if token.is_none() && self.private {
            bail!("--private needs an access token (--token-file or REPOSE_TOKEN)");
        }
        if token.is_none() && !addr.ip().is_loopback() && !self.insecure_open {
            bail!(
                "refusing to listen on {addr} without an access token: anyone who reaches it \
                 could queue and cancel sweeps. Give --token-file FILE (or REPOSE_TOKEN), or \
                 --insecure-open to accept that"
            );
        }
        Ok(repose_api::Access {
            token,
            private: self.private,
        })
    }

    fn options(&self, access: repose_api::Access) -> anyhow::Result<repose_api::Options> {
        Ok(repose_api::Options {
            docs: self.docs.is_dir().then(|| self.docs.clone()),
            access,
            request_timeout: seconds("--request-timeout", self.request_timeout)?,
        })
    }
}

/// Longest lease and checkpoint interval a worker takes: a day.
const MAX_INTERVAL: Duration = Duration::from_secs(86_400);

/// Shortest heartbeat a worker takes.
const MIN_HEARTBEAT: Duration = Duration::from_millis(1);

fn seconds(flag: &str, value: f64) -> anyhow::Result<Duration> {
    Duration::try_from_secs_f64(value)
        .ok()
        .filter(|d| !d.is_zero())
        .with_context(|| format!("{flag} must be a positive number of seconds"))
}

#[derive(clap::Args)]
pub struct WorkerArgs {
    /// Database URL shared with the server and the other workers.
    #[arg(long, env = "REPOSE_DATABASE")]
    database: String,
    /// Jobs to run at once in this process (default 1; one per core fills a node).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Stop when the queue is empty instead of waiting for more work
    /// (for batch-scheduler jobs).
    #[arg(long)]
    exit_when_idle: bool,
    #[command(flatten)]
    lease: LeaseArgs,
}

#[derive(clap::Args, Clone)]
pub struct LeaseArgs {
    /// Lease length in seconds: a job whose worker stops renewing returns to the queue after this long.
    #[arg(long, default_value_t = 60.0)]
    lease: f64,
    /// Heartbeat period in seconds.
    #[arg(long, default_value_t = 10.0)]
    heartbeat: f64,
    /// Seconds between checkpoints of a long sample (heap and packing), so
    /// that a worker taking the job over continues from the latest one; 0: never.
    #[arg(long, default_value_t = 600.0)]
    checkpoint_every: f64,
}

impl Default for LeaseArgs {
    fn default() -> Self {
        LeaseArgs {
            lease: 60.0,
            heartbeat: 10.0,
            checkpoint_every: 600.0,
        }
    }
}

impl LeaseArgs {
    pub(crate) fn config(&self, owner: String) -> anyhow::Result<WorkerConfig> {
        let lease = seconds("--lease", self.lease)?;
        let heartbeat = seconds("--heartbeat", self.heartbeat)?;
        if lease > MAX_INTERVAL {
            bail!("--lease must be at most {} s", MAX_INTERVAL.as_secs());
        }
        if heartbeat < MIN_HEARTBEAT || heartbeat >= lease {
            bail!(
                "--heartbeat must be at least {} s and shorter than --lease",
                MIN_HEARTBEAT.as_secs_f64()
            );
        }
        let checkpoint_every = if self.checkpoint_every == 0.0 {
            None
        } else {
            Some(seconds("--checkpoint-every", self.checkpoint_every)?)
        };
        if checkpoint_every.is_some_and(|every| every > MAX_INTERVAL) {
            bail!(
                "--checkpoint-every must be 0 (never) or at most {} s",
                MAX_INTERVAL.as_secs()
            );
        }
        let mut c = WorkerConfig::new(owner);
        c.lease = lease;
        c.heartbeat = heartbeat;
        c.checkpoint_every = checkpoint_every;
        Ok(c)
    }
}

#[derive(clap::Args)]
pub struct SubmitArgs {
    /// Sweep spec, TOML or JSON (see docs/service.md).
    spec: PathBuf,
    /// URL of the running server.
    #[arg(long, default_value = DEFAULT_SERVER, env = "REPOSE_SERVER")]
    server: String,
    /// Wait for the sweep to finish, with a progress bar.
    #[arg(long)]
    wait: bool,
}

#[derive(clap::Args)]
pub struct StatusArgs {
    /// A sweep id for its points; none for the list of sweeps.
    sweep: Option<String>,
    #[arg(long, default_value = DEFAULT_SERVER, env = "REPOSE_SERVER")]
    server: String,
}

#[derive(clap::Args)]
pub struct ExportArgs {
    /// The sweep to export.
    sweep: String,
    /// What to export: samples (one row per sample) or points (statistics per point).
    #[arg(long, value_parser = ["samples", "points"], default_value = "points")]
    what: String,
    /// Write to this file instead of standard output.
    #[arg(long, short)]
    output: Option<PathBuf>,
    #[arg(long, default_value = DEFAULT_SERVER, env = "REPOSE_SERVER")]
    server: String,
}

pub(crate) fn runtime() -> anyhow::Result<tokio::runtime::Runtime> {
    Ok(tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?)
}

pub(crate) fn init_logging() {
    let filter = tracing_subscriber::EnvFilter::try_from_env("REPOSE_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn"));
    // Colours only on a terminal: logs written to files stay plain text.
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(ansi)
        .with_writer(std::io::stderr)
        .try_init();
}

fn owner_prefix() -> String {
    let host = std::fs::read_to_string("/etc/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|_| "host".into());
    format!("{host}-{}", std::process::id())
}

/// Starts `count` workers on `store`, each with the lease settings of
/// `base` (checked by [`LeaseArgs::config`]) under an owner name of its own.
pub(crate) fn spawn_workers(
    store: &Store,
    count: usize,
    base: &WorkerConfig,
    exit_when_idle: bool,
    shutdown: &tokio::sync::watch::Receiver<bool>,
) -> Vec<tokio::task::JoinHandle<Tally>> {
    let prefix = owner_prefix();
    // One core a worker; one waiting for work lends its core to the others' samples.
    let cores = Cores::new(count);
    (0..count)
        .map(|k| {
            let mut config = base.clone();
            config.owner = format!("{prefix}-{k}");
            config.exit_when_idle = exit_when_idle;
            config.cores = Some(cores.clone());
            tokio::spawn(run_worker(store.clone(), config, shutdown.clone()))
        })
        .collect()
}

pub fn serve(args: ServeArgs) -> anyhow::Result<ExitCode> {
    init_logging();
    let limits = repose_api::server::Limits {
        header_read: seconds("--header-timeout", args.header_timeout)?,
        ..Default::default()
    };
    let lease = args.lease.config(String::new())?;
    runtime()?.block_on(async {
        let listener = tokio::net::TcpListener::bind(&args.listen)
            .await
            .with_context(|| format!("cannot listen on {}", args.listen))?;
        let addr = listener.local_addr()?;
        let options = args.options(args.access(addr)?)?;
        let store = Store::open(&args.database)
            .await
            .with_context(|| format!("cannot open the database {}", args.database))?;
        let workers = args.workers.unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        });
        let shutdown = shutdown_on_signals();
        let handles = spawn_workers(&store, workers, &lease, false, &shutdown);
        let guarded = if options.access.token.is_some() {
            ", token required to change"
        } else {
            ""
        };
        // A server whose reader has gone keeps serving: the line is news,
        // not its work.
        let _ = outln!(
            "repose: serving http://{addr}/ ({}, {workers} workers{guarded})",
            args.database
        );
        let mut stop = shutdown.clone();
        let app = repose_api::app_with(store, options);
        repose_api::server::serve(listener, app, limits, async move {
            let _ = stop.wait_for(|s| *s).await;
        })
        .await;
        for h in handles {
            let _ = h.await;
        }
        Ok(ExitCode::SUCCESS)
    })
}

pub fn worker(args: WorkerArgs) -> anyhow::Result<ExitCode> {
    init_logging();
    if args.threads == 0 {
        bail!("--threads must be at least 1");
    }
    let lease = args.lease.config(String::new())?;
    runtime()?.block_on(async {
        let store = Store::open_existing(&args.database)
            .await
            .with_context(|| format!("cannot open the database {}", args.database))?;
        let shutdown = shutdown_on_signals();
        let handles = spawn_workers(&store, args.threads, &lease, args.exit_when_idle, &shutdown);
        let mut total = Tally::default();
        for h in handles {
            let t = h.await?;
            total.completed += t.completed;
            total.released += t.released;
            total.lost += t.lost;
            total.failed += t.failed;
        }
        eprintln!(
            "repose worker: {} results written, {} jobs handed back, {} lost leases, {} unreadable",
            total.completed, total.released, total.lost, total.failed
        );
        Ok(ExitCode::SUCCESS)
    })
}

/// Reads a sweep spec from TOML or JSON (the scene documents' reader).
fn read_spec(path: &PathBuf) -> anyhow::Result<Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let doc = repose_physics::doc::parse(&text)
        .map_err(|e| anyhow::anyhow!("{}: {}: {}", path.display(), e.field, e.message))?;
    Ok(Value::Object(doc))
}

/// Posts a sweep spec; returns the answer's status and JSON body.
pub(crate) async fn post_sweep(
    client: &reqwest::Client,
    server: &str,
    spec: &Value,
) -> anyhow::Result<(reqwest::StatusCode, Value)> {
    let resp = client
        .post(format!("{server}/api/sweeps"))
        .json(spec)
        .send()
        .await
        .with_context(|| {
            format!("cannot reach the server at {server} (is `repose serve` running?)")
        })?;
    let status = resp.status();
    Ok((status, resp.json().await.unwrap_or(Value::Null)))
}

pub(crate) async fn get_json(client: &reqwest::Client, url: &str) -> anyhow::Result<Value> {
    let resp = client
        .get(url)
        .send()
        .await
        .with_context(|| format!("cannot reach {url}"))?;
    let status = resp.status();
    let body: Value = resp.json().await.unwrap_or(Value::Null);
    if !status.is_success() {
        bail!(
            "{url}: {} {}",
            status.as_u16(),
            body["error"].as_str().unwrap_or("")
        );
    }
    Ok(body)
}

pub fn submit(args: SubmitArgs) -> anyhow::Result<ExitCode> {
    let spec = read_spec(&args.spec)?;
    let server = args.server.trim_end_matches('/').to_string();
    runtime()?.block_on(async {
        let client = crate::client::http()?;
        let (status, body) = post_sweep(&client, &server, &spec).await?;
        if !status.is_success() {
            eprintln!("error: the server refused the sweep ({})", status.as_u16());
            for e in body["errors"].as_array().into_iter().flatten() {
                eprintln!(
                    "  {}: {}",
                    e["field"].as_str().unwrap_or("?"),
                    e["message"].as_str().unwrap_or("")
                );
            }
            return Ok(ExitCode::from(2));
        }
        let id = body["id"].as_str().unwrap_or_default().to_string();
        crate::emit(&format!(
            "sweep {id}: {}\n",
            body["message"].as_str().unwrap_or("")
        ))?;
        if !args.wait {
            return Ok(ExitCode::SUCCESS);
        }
        let total = body["jobs"].as_u64().unwrap_or(0);
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} samples  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        loop {
            let sweep = get_json(&client, &format!("{server}/api/sweeps/{id}")).await?;
            let p = &sweep["progress"];
            let n = |k: &str| p[k].as_u64().unwrap_or(0);
            bar.set_position(n("done") + n("failed") + n("cancelled"));
            let eta = sweep["eta_seconds"]
                .as_f64()
                .map(|s| format!("ETA {s:.0} s"))
                .unwrap_or_default();
            bar.set_message(format!(
                "{} running, {} failed  {eta}",
                n("running"),
                n("failed")
            ));
            if n("queued") + n("running") == 0 {
                bar.finish();
                break;
            }
            tokio::time::sleep(Duration::from_millis(500)).await;
        }
        let points = get_json(&client, &format!("{server}/api/sweeps/{id}/points")).await?;
        let protocol = spec["protocol"].as_str().unwrap_or_default();
        crate::emit(&points_table(&points, protocol))?;
        Ok(ExitCode::SUCCESS)
    })
}

/// Each point's sample counts and the two leading metrics of the protocol.
fn points_table(points: &Value, protocol: &str) -> String {
    use std::fmt::Write;
    let metrics: Vec<(&str, String)> = repose_physics::registry::find_protocol(protocol)
        .map(|p| p.metrics())
        .unwrap_or_default()
        .iter()
        .filter(|m| {
            // The leading metrics that some point measured.
            points["points"]
                .as_array()
                .into_iter()
                .flatten()
                .any(|p| p["metrics"][m.name]["n"].as_i64().unwrap_or(0) > 0)
        })
        .take(2)
        .map(|m| (m.name, format!("{} ± sd", m.label)))
        .collect();
    let mut s = String::new();
    let _ = write!(s, "{:<40} {:>4} {:>5}", "point", "n", "fail");
    for (_, head) in &metrics {
        let _ = write!(s, "  {head:>16}");
    }
    s.push('\n');
    for p in points["points"].as_array().into_iter().flatten() {
        let stat = |m: &str| {
            let a = &p["metrics"][m];
            match (a["mean"].as_f64(), a["sd"].as_f64()) {
                (Some(mean), Some(sd)) => format!("{mean:7.2} ± {sd:5.2}"),
                (Some(mean), None) => format!("{mean:7.2}"),
                _ => "-".into(),
            }
        };
        let _ = write!(
            s,
            "{:<40} {:>4} {:>5}",
            p["point"].to_string(),
            p["samples"].as_i64().unwrap_or(0),
            p["failures"].as_i64().unwrap_or(0),
        );
        for (m, _) in &metrics {
            let _ = write!(s, "  {:>16}", stat(m));
        }
        s.push('\n');
    }
    s
}

/// One line for each running job's latest checkpoint: how far it has come.
fn running_lines(running: &Value) -> String {
    let now_ms = repose_store::now_ms();
    let mut s = String::new();
    for r in running.as_array().into_iter().flatten() {
        let ago = (now_ms - r["saved_at"].as_i64().unwrap_or(now_ms)).max(0) / 1000;
        s += &format!(
            "running {}: checkpoint at {:.4} s simulated, step {}, saved {} min {} s ago\n",
            r["job_id"].as_str().unwrap_or(""),
            r["sim_time"].as_f64().unwrap_or(f64::NAN),
            r["iteration"].as_i64().unwrap_or(0),
            ago / 60,
            ago % 60
        );
    }
    s
}

pub fn status(args: StatusArgs) -> anyhow::Result<ExitCode> {
    let server = args.server.trim_end_matches('/').to_string();
    runtime()?.block_on(async {
        let client = crate::client::http()?;
        let text = match args.sweep {
            None => sweeps_table(&get_json(&client, &format!("{server}/api/sweeps")).await?),
            Some(id) => {
                let sweep = get_json(&client, &format!("{server}/api/sweeps/{id}")).await?;
                let points = get_json(&client, &format!("{server}/api/sweeps/{id}/points")).await?;
                format!(
                    "{} ({}): {}\n{}{}",
                    sweep["name"].as_str().unwrap_or(""),
                    sweep["state"].as_str().unwrap_or(""),
                    sweep["progress"],
                    running_lines(&sweep["running"]),
                    points_table(&points, sweep["protocol"].as_str().unwrap_or_default())
                )
            }
        };
        crate::emit(&text)?;
        Ok(ExitCode::SUCCESS)
    })
}

/// One line a sweep: its id, state, job counts and name.
fn sweeps_table(list: &Value) -> String {
    use std::fmt::Write;
    let mut s = format!(
        "{:<36}  {:<9} {:>6} {:>7} {:>6} {:>6}  name\n",
        "id", "state", "queued", "running", "done", "failed"
    );
    for sw in list["sweeps"].as_array().into_iter().flatten() {
        let p = &sw["progress"];
        let n = |k: &str| p[k].as_i64().unwrap_or(0);
        let _ = writeln!(
            s,
            "{:<36}  {:<9} {:>6} {:>7} {:>6} {:>6}  {}",
            sw["id"].as_str().unwrap_or(""),
            sw["state"].as_str().unwrap_or(""),
            n("queued"),
            n("running"),
            n("done"),
            n("failed"),
            sw["name"].as_str().unwrap_or("")
        );
    }
    s
}

pub fn export(args: ExportArgs) -> anyhow::Result<ExitCode> {
    let server = args.server.trim_end_matches('/');
    let url = format!(
        "{server}/api/sweeps/{}/{}?format=csv",
        args.sweep, args.what
    );
    fetch_to(
        &url,
        "the server refused the export",
        args.output.as_deref(),
    )
}

#[derive(clap::Args)]
pub struct GrainsArgs {
    /// The job (its id, as `repose status SWEEP` lists the running ones).
    job: String,
    /// Write to this file instead of standard output.
    #[arg(long, short)]
    output: Option<PathBuf>,
    #[arg(long, default_value = DEFAULT_SERVER, env = "REPOSE_SERVER")]
    server: String,
}

/// Writes where a running sample's grains are, from its latest checkpoint.
pub fn grains(args: GrainsArgs) -> anyhow::Result<ExitCode> {
    let server = args.server.trim_end_matches('/');
    let url = format!("{server}/api/jobs/{}/grains", args.job);
    fetch_to(
        &url,
        "the server has no grains for that job",
        args.output.as_deref(),
    )
}

/// Fetches a text answer and writes it to `output` or standard output; a
/// refusal becomes the server's own message (or `refused`).
fn fetch_to(
    url: &str,
    refused: &str,
    output: Option<&std::path::Path>,
) -> anyhow::Result<ExitCode> {
    runtime()?.block_on(async {
        let resp = reqwest::get(url)
            .await
            .with_context(|| format!("cannot reach {url}"))?;
        if !resp.status().is_success() {
            let body: Value = resp.json().await.unwrap_or(Value::Null);
            bail!("{}", body["error"].as_str().unwrap_or(refused));
        }
        let text = resp.text().await?;
        match output {
            Some(path) => std::fs::write(path, text)
                .with_context(|| format!("cannot write {}", path.display()))?,
            None => crate::emit(&text)?,
        }
        Ok(ExitCode::SUCCESS)
    })
}

//! `repose reproduce`: queue every sweep behind a paper's figures through
//! the service's HTTP API (a running server, or one started for the run with
//! embedded workers), wait for them, and write the report from what the API
//! serves: the same figure data the results page draws.

use crate::service::{get_json, init_logging, runtime, spawn_workers, LeaseArgs, DEFAULT_DATABASE};
use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressStyle};
use repose_physics::{registry, Preset, ENGINE};
use repose_store::Store;
use repose_studies::data::{StudyData, SweepData};
use repose_studies::paper::{variant_label, Paper};
use repose_studies::papers;
use repose_studies::remaining::{Costed, Remaining, Took};
use repose_studies::reproduction::{DoneSweep, Reproduction};
use repose_sweeps::{Order, SweepSpec};
use repose_worker::shutdown_on_signals;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct ReproduceArgs {
    /// Use this running server (its workers do the runs). Without it, a
    /// server with embedded workers is started on --database for the run.
    #[arg(long)]
    server: Option<String>,
    /// Database of the server started for the run.
    #[arg(long, default_value = DEFAULT_DATABASE)]
    database: String,
    /// Embedded workers (default: one per core).
    #[arg(long)]
    workers: Option<usize>,
    #[command(flatten)]
    lease: LeaseArgs,
    /// The paper to reproduce (its study key), or `all` for every paper.
    #[arg(long, default_value = "lh93")]
    paper: String,
    /// Fidelity preset of every sweep.
    #[arg(long, default_value = "standard")]
    preset: Preset,
    /// Samples (seeds) per point; by default the paper's count.
    #[arg(long)]
    samples: Option<u32>,
    /// Raise the claim priority of every sweep by this much over the
    /// study's own (keeping their order among themselves), e.g. to run
    /// them ahead of sweeps already queued in the store.
    #[arg(long, default_value_t = 0)]
    raise_priority: i64,
    /// `listed` (point by point) or `cheapest` (the samples estimated
    /// cheapest first, so that an interrupted run has finished the most points).
    #[arg(long, default_value = "listed")]
    order: Order,
    /// Run these points ahead of the rest, `axis=value` (repeatable; JSON
    /// values, several values of one axis allowed), e.g. `--first
    /// 'gravity=[0,0,-9.81]'`: each sweep with those axes first queues that
    /// slice above every sweep of the run, then itself whole (the whole
    /// sweep takes the slice's samples).
    #[arg(long = "first", value_name = "AXIS=VALUE")]
    first: Vec<String>,
    /// A variant of the model, `key=value` (repeatable): every scene of
    /// every sweep takes it, e.g. `--set material.limit_load=net`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// The Markdown report of one paper; figures (SVG) and the numbers
    /// (JSON) go beside it. By default the paper's own report file in
    /// --out-dir (`reproduction.md` for lh93, `reproduction-ep21.md` for ep21).
    #[arg(long)]
    out: Option<PathBuf>,
    /// The folder of the reports when --out names none.
    #[arg(long, default_value = "docs")]
    out_dir: PathBuf,
    /// A small version for tests: fewer points in smaller boxes.
    #[arg(long)]
    reduced: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Write the report from the samples finished so far and stop, without
    /// running any (its own server starts no worker): an interim report of
    /// a reproduction that runs in pieces. It says how many samples are left.
    #[arg(long)]
    interim: bool,
    /// Write a report again from the numbers it saved (its JSON), with the
    /// current comparison of the paper's results and the preset's bias as
    /// the speed/accuracy study beside it now measures it; nothing is run.
    #[arg(long, value_name = "REPORT.json")]
    rewrite: Option<PathBuf>,
}

pub fn run(args: ReproduceArgs) -> anyhow::Result<ExitCode> {
    init_logging();
    if args.samples == Some(0) {
        bail!("--samples must be at least 1");
    }
    variant(&args)?;
    if let Some(json) = &args.rewrite {
        return rewrite(json);
    }
    let chosen: Vec<&'static Paper> = if args.paper == "all" {
        papers::PAPERS.to_vec()
    } else {
        match papers::find(&args.paper) {
            Some(p) => vec![p],
            None => {
                let keys: Vec<&str> = papers::PAPERS.iter().map(|p| p.key).collect();
                bail!(
                    "--paper: no study `{}` (studies are {}, or all)",
                    args.paper,
                    keys.join(", ")
                );
            }
        }
    };
    check_first(&args, &chosen)?;
    if chosen.len() > 1 && args.out.is_some() {
        bail!("--out names one report: with --paper all, give --out-dir");
    }
    runtime()?.block_on(async {
        let Some(url) = args.server.clone() else {
            return with_own_server(&args, &chosen).await;
        };
        let (queued, _) = tokio::sync::watch::channel(false);
        reproduce_all(&args, &chosen, url.trim_end_matches('/'), &queued).await
    })
}

/// Writes the Markdown (and the JSON) of a saved report again, its
/// comparison recomputed from the saved points.
fn rewrite(json: &Path) -> anyhow::Result<ExitCode> {
    let text = std::fs::read_to_string(json)
        .with_context(|| format!("--rewrite: cannot read {}", json.display()))?;
    let mut report: Reproduction = serde_json::from_str(&text)
        .with_context(|| format!("--rewrite: {} is not a reproduction's JSON", json.display()))?;
    let Some(paper) = papers::find(&report.paper) else {
        bail!(
            "--rewrite: the report is of an unknown paper `{}`",
            report.paper
        );
    };
    let mut data = StudyData::default();
    for d in &report.sweeps {
        let sweep = SweepData {
            id: d.id.clone(),
            points: d.points.clone(),
            samples: Vec::new(),
            report: None,
        };
        data.sweeps.insert(d.key.clone(), sweep);
    }
    report.comparison = (paper.compare)(&data);
    // The preset's bias is read from the speed/accuracy study beside the
    // report, which may have been measured again since the run.
    if let Some(preset) = Preset::ALL.into_iter().find(|p| p.name() == report.preset) {
        report.preset_accuracy =
            (paper.accuracy)(json.parent().unwrap_or_else(|| Path::new(".")), preset);
    }
    let out = json.with_extension("md");
    report
        .write(&out)
        .with_context(|| format!("cannot write the report {}", out.display()))?;
    eprintln!("rewrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

/// Reproduces each paper in turn; each report states its own time.
/// `queued` turns true once the first paper's sweeps are queued.
async fn reproduce_all(
    args: &ReproduceArgs,
    papers: &[&Paper],
    server: &str,
    queued: &tokio::sync::watch::Sender<bool>,
) -> anyhow::Result<ExitCode> {
    for paper in papers {
        reproduce(args, paper, server, Instant::now(), queued).await?;
    }
    Ok(ExitCode::SUCCESS)
}

/// Where a paper's report goes.
fn out_of(args: &ReproduceArgs, paper: &Paper) -> PathBuf {
    args.out
        .clone()
        .unwrap_or_else(|| args.out_dir.join(format!("{}.md", paper.report)))
}

/// Starts a server with embedded workers on `--database`, reproduces, stops it.
async fn with_own_server(args: &ReproduceArgs, papers: &[&Paper]) -> anyhow::Result<ExitCode> {
    let store = Store::open(&args.database)
        .await
        .with_context(|| format!("cannot open the database {}", args.database))?;
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?;
    let (tx, rx) = tokio::sync::watch::channel(false);
    let workers = match args.workers {
        _ if args.interim => 0,
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    // The workers start once this run's sweeps are queued, so that they
    // claim its samples by its priority and order, not what an earlier
    // run left in the queue.
    let lease = args.lease.config(String::new())?;
    let (queued, mut queued_rx) = tokio::sync::watch::channel(false);
    let starter = {
        let (store, rx) = (store.clone(), rx.clone());
        tokio::spawn(async move {
            match queued_rx.wait_for(|q| *q).await {
                Ok(_) => spawn_workers(&store, workers, &lease, false, &rx),
                Err(_) => Vec::new(),
            }
        })
    };
    let mut stop_rx = rx.clone();
    let app = repose_api::app(store);
    let task = tokio::spawn(async move {
        axum::serve(listener, app)
            .with_graceful_shutdown(async move {
                let _ = stop_rx.wait_for(|s| *s).await;
            })
            .await
    });
    eprintln!(
        "repose: reproducing on http://{addr}/ ({}, {workers} workers)",
        args.database
    );
    // SIGTERM or Ctrl-C hands the running samples back with the store;
    // the same command on the same database goes on from there.
    let mut signalled = shutdown_on_signals();
    let url = format!("http://{addr}");
    let result = tokio::select! {
        r = reproduce_all(args, papers, &url, &queued) => r,
        _ = signalled.wait_for(|s| *s) => Err(anyhow::anyhow!(
            "stopped: the running samples go back to the queue in {}; the same \
             command goes on from their latest checkpoints",
            args.database
        )),
    };
    let _ = tx.send(true);
    drop(queued);
    for h in starter.await?.into_iter() {
        let _ = h.await;
    }
    let _ = task.await;
    result
}

/// Queues each study sweep; returns `(key, title, answer)` for each.
async fn queue_all(
    client: &reqwest::Client,
    args: &ReproduceArgs,
    paper: &Paper,
    set: &[(String, Value)],
    server: &str,
) -> anyhow::Result<Vec<(String, String, Value)>> {
    let set: serde_json::Map<String, Value> = set.iter().cloned().collect();
    queue_first(client, args, paper, &set, server).await?;
    let mut out = Vec::new();
    for st in (paper.sweeps)() {
        let body = json!({"fidelity": args.preset, "samples": args.samples, "reduced": args.reduced,
            "set": set, "priority": st.priority + args.raise_priority, "order": args.order});
        let url = format!("{server}/api/studies/{}/sweeps/{}", paper.key, st.key);
        let resp = client
            .post(&url)
            .json(&body)
            .send()
            .await
            .with_context(|| {
                format!("cannot reach the server at {server} (is `repose serve` running?)")
            })?;
        let status = resp.status();
        let answer: Value = resp.json().await.unwrap_or(Value::Null);
        if !status.is_success() {
            bail!(
                "the server refused the {} sweep: {}",
                st.key,
                answer["error"].as_str().unwrap_or("")
            );
        }
        out.push((st.key.to_string(), st.title.to_string(), answer));
    }
    Ok(out)
}

/// The `--first` assignments, as axis → values.
fn first(args: &ReproduceArgs) -> anyhow::Result<BTreeMap<String, Vec<Value>>> {
    let mut wanted: BTreeMap<String, Vec<Value>> = BTreeMap::new();
    for a in &args.first {
        let (axis, value) = repose_physics::doc::parse_assignment(a)
            .map_err(|e| anyhow::anyhow!("--first {}: {}", e.field, e.message))?;
        wanted.entry(axis).or_default().push(value);
    }
    Ok(wanted)
}

/// Fails where a `--first` value is on no axis of the chosen papers' sweeps.
fn check_first(args: &ReproduceArgs, papers: &[&Paper]) -> anyhow::Result<()> {
    for (axis, values) in &first(args)? {
        for v in values {
            let one = BTreeMap::from([(axis.clone(), vec![v.clone()])]);
            let held = papers
                .iter()
                .flat_map(|p| (p.sweeps)())
                .any(|st| st.slice_of(args.reduced, &one).is_some());
            if !held {
                bail!("--first {axis}={v}: no sweep of the study has this value on such an axis");
            }
        }
    }
    Ok(())
}

/// Queues the `--first` slice of each sweep that has one, above every
/// sweep of the run.
async fn queue_first(
    client: &reqwest::Client,
    args: &ReproduceArgs,
    paper: &Paper,
    set: &serde_json::Map<String, Value>,
    server: &str,
) -> anyhow::Result<()> {
    let wanted = first(args)?;
    if wanted.is_empty() {
        return Ok(());
    }
    let sweeps = (paper.sweeps)();
    let top = sweeps.iter().map(|st| st.priority).max().unwrap_or(0) + args.raise_priority + 1;
    for st in &sweeps {
        let Some(only) = st.slice_of(args.reduced, &wanted) else {
            continue;
        };
        let body = json!({"fidelity": args.preset, "samples": args.samples, "reduced": args.reduced,
            "set": set, "priority": top, "order": args.order, "only": only});
        let url = format!("{server}/api/studies/{}/sweeps/{}", paper.key, st.key);
        let resp = client.post(&url).json(&body).send().await?;
        if !resp.status().is_success() {
            let answer: Value = resp.json().await.unwrap_or(Value::Null);
            bail!(
                "the server refused the first slice of the {} sweep: {}",
                st.key,
                answer["error"].as_str().unwrap_or("")
            );
        }
    }
    Ok(())
}

/// What the unfinished samples of `sweeps` (id and spec) are estimated
/// to cost: each spec expanded into its samples as the service expands
/// it, each sample estimated by its protocol, against what the sweep's
/// finished samples took.
async fn remaining(
    client: &reqwest::Client,
    server: &str,
    sweeps: &[(String, Value)],
) -> anyhow::Result<Option<Remaining>> {
    let mut costed = Vec::new();
    for (id, spec) in sweeps {
        let spec: SweepSpec = serde_json::from_value(spec.clone())?;
        let jobs = spec.expand()?;
        let done = get_json(client, &format!("{server}/api/sweeps/{id}/samples")).await?;
        let took = took_by_hash(&done["samples"]);
        costed.push(
            jobs.iter()
                .map(|j| Costed {
                    point: j.point.clone(),
                    estimate: j.estimated_cost().unwrap_or(f64::NAN),
                    took: took.get(j.sample_hash.as_str()).copied(),
                })
                .collect(),
        );
    }
    Ok(Remaining::of(&costed))
}

/// What each finished sample of a sweep's sample listing took, by its hash.
fn took_by_hash(samples: &Value) -> BTreeMap<&str, Took> {
    let listed = samples.as_array().into_iter().flatten();
    listed
        .filter_map(|s| {
            let took = Took {
                particle_steps: s["particle_steps"].as_f64()?,
                cpu_s: s["wall_time"].as_f64()?,
                completed: s["outcome"] == "completed",
            };
            Some((s["sample_hash"].as_str()?, took))
        })
        .collect()
}

/// Waits until no queued sweep has jobs left, with a progress bar.
async fn wait(
    client: &reqwest::Client,
    server: &str,
    queued: &[(String, String, Value)],
    quiet: bool,
) -> anyhow::Result<()> {
    let total: u64 = queued
        .iter()
        .map(|q| q.2["jobs"].as_u64().unwrap_or(0))
        .sum();
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template("[{elapsed_precise}] {bar:40} {pos}/{len} samples  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    };
    loop {
        let (mut finished, mut open, mut running) = (0, 0, Vec::new());
        for (key, _, q) in queued {
            let id = q["id"].as_str().unwrap_or_default();
            let sw = get_json(client, &format!("{server}/api/sweeps/{id}")).await?;
            let n = |k: &str| sw["progress"][k].as_u64().unwrap_or(0);
            finished += n("done") + n("failed") + n("cancelled");
            open += n("queued") + n("running");
            if n("running") > 0 {
                running.push(key.as_str());
            }
        }
        bar.set_position(finished);
        bar.set_message(format!("running: {}", running.join(", ")));
        if open == 0 {
            bar.finish_and_clear();
            return Ok(());
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
}

async fn reproduce(
    args: &ReproduceArgs,
    paper: &Paper,
    server: &str,
    clock: Instant,
    started: &tokio::sync::watch::Sender<bool>,
) -> anyhow::Result<ExitCode> {
    let client = crate::client::http()?;
    let out = out_of(args, paper);
    let set = variant(args)?;
    let queued = queue_all(&client, args, paper, &set, server).await?;
    started.send_replace(true);
    if !args.interim {
        wait(&client, server, &queued, args.quiet).await?;
    }
    let elapsed = clock.elapsed().as_secs_f64();
    let bindings = queued
        .iter()
        .map(|(k, _, q)| format!("{k}:{}", q["id"].as_str().unwrap_or_default()))
        .collect::<Vec<_>>()
        .join(",");
    let (mut sweeps, mut pending, mut specs) = (Vec::new(), 0, Vec::new());
    for (key, title, q) in &queued {
        let id = q["id"].as_str().unwrap_or_default().to_string();
        let sw = get_json(&client, &format!("{server}/api/sweeps/{id}")).await?;
        let open = |k: &str| sw["progress"][k].as_u64().unwrap_or(0);
        pending += open("queued") + open("running");
        specs.push((id.clone(), sw["spec"].clone()));
        let pts = get_json(&client, &format!("{server}/api/sweeps/{id}/points")).await?;
        sweeps.push(DoneSweep {
            key: key.clone(),
            title: title.clone(),
            jobs: q["jobs"].as_u64().unwrap_or(0),
            reused: q["reused"].as_u64().unwrap_or(0),
            cost: serde_json::from_value(sw["cost"].clone()).unwrap_or_default(),
            points: serde_json::from_value(pts["points"].clone()).unwrap_or_default(),
            id,
        });
    }
    let mut figures = Vec::new();
    for f in (paper.figures)() {
        let url = format!(
            "{server}/api/studies/{}/figures/{}?sweeps={bindings}",
            paper.key, f.key
        );
        figures.push(serde_json::from_value(get_json(&client, &url).await?)?);
    }
    let url = format!(
        "{server}/api/studies/{}/comparison?sweeps={bindings}",
        paper.key
    );
    let comparison = serde_json::from_value(get_json(&client, &url).await?["comparison"].clone())?;
    let remaining = match pending {
        0 => None,
        _ => remaining(&client, server, &specs)
            .await
            .unwrap_or_else(|e| {
                eprintln!("no estimate of what is left: {e:#}");
                None
            }),
    };
    let report = Reproduction {
        paper: paper.key.into(),
        title: paper.title.into(),
        command: command(args, paper),
        engine: ENGINE.into(),
        preset: args.preset.name().into(),
        preset_settings: preset_settings(paper, args.preset),
        reduced: args.reduced,
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        wall_time_s: elapsed,
        sweeps,
        figures,
        comparison,
        preset_accuracy: (paper.accuracy)(
            out.parent().unwrap_or_else(|| Path::new(".")),
            args.preset,
        ),
        metric_labels: metric_labels(paper),
        variant: variant_label(&set),
        pending,
        remaining,
    };
    report
        .write(&out)
        .with_context(|| format!("cannot write the report {}", out.display()))?;
    crate::emit(&report.breakdown())?;
    eprintln!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

/// The `--set` assignments, read as the scene's own overrides are.
fn variant(args: &ReproduceArgs) -> anyhow::Result<Vec<(String, Value)>> {
    args.set
        .iter()
        .map(|a| {
            repose_physics::doc::parse_assignment(a)
                .map_err(|e| anyhow::anyhow!("--set {}: {}", e.field, e.message))
        })
        .collect()
}

fn command(args: &ReproduceArgs, paper: &Paper) -> String {
    let mut c = format!(
        "repose reproduce --paper {} --preset {}",
        paper.key, args.preset
    );
    for a in &args.set {
        c.push_str(&format!(" --set {a}"));
    }
    if let Some(n) = args.samples {
        c.push_str(&format!(" --samples {n}"));
    }
    if args.reduced {
        c.push_str(" --reduced");
    }
    if args.interim {
        c.push_str(" --interim");
    }
    c
}

/// What the preset sets in the paper's protocols: one line where they all
/// take the same settings, else one part a protocol (`heap: …; packing: …`).
fn preset_settings(paper: &Paper, preset: Preset) -> String {
    let mut lines: Vec<(&str, String)> = Vec::new();
    for s in (paper.sweeps)() {
        let known = lines.iter().any(|(name, _)| *name == s.protocol);
        if let Some(p) = registry::find_protocol(s.protocol).filter(|_| !known) {
            lines.push((s.protocol, p.preset_line(preset)));
        }
    }
    if lines.windows(2).all(|w| w[0].1 == w[1].1) {
        return lines.pop().map(|(_, line)| line).unwrap_or_default();
    }
    let parts: Vec<String> = lines
        .iter()
        .map(|(name, line)| format!("{name}: {line}"))
        .collect();
    parts.join("; ")
}

/// The labels of every metric the paper's protocols measure.
fn metric_labels(paper: &Paper) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for s in (paper.sweeps)() {
        for m in registry::find_protocol(s.protocol)
            .map(|p| p.metrics())
            .unwrap_or_default()
        {
            if !out.iter().any(|(n, _)| n == m.name) {
                out.push((m.name.into(), format!("{} ({})", m.label, m.unit)));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use repose_store::{RunCounts, Sample};

    #[test]
    fn what_a_sample_took_is_read_from_the_stores_own_listing() {
        let sample = |hash: &str, outcome: &str| Sample {
            job_id: "job".into(),
            sample_hash: hash.into(),
            point: Default::default(),
            sample: 0,
            seed: 0,
            outcome: outcome.into(),
            reason: None,
            metrics: Default::default(),
            counts: RunCounts {
                grains_initial: 10,
                grains_final: 10,
                grains_lost: 0,
                iterations: 100,
                simulated_time: 1.0,
                wall_time: 2.5,
                particle_steps: 1000,
            },
            engine: "e".into(),
        };
        let listing =
            serde_json::to_value(vec![sample("a", "completed"), sample("b", "unmeasurable")])
                .unwrap();
        let took = took_by_hash(&listing);
        let a = took["a"];
        assert_eq!(
            (a.particle_steps, a.cpu_s, a.completed),
            (1000.0, 2.5, true)
        );
        assert!(!took["b"].completed);
        assert_eq!(took.len(), 2);
    }
}

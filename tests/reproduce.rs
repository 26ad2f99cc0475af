//! `repose reproduce --reduced` through a real server on SQLite, for each
//! paper: the report is written, every number in it equals statistics
//! recomputed from the stored samples, its figures and fits are the ones
//! the API serves, and (first paper) θ_R rises with μ.

use serde_json::Value;
use std::collections::BTreeMap;
use std::process::Command;

#[path = "common/mod.rs"]
mod common;

use common::{get, scratch, Server, BIN};

/// `repose reproduce` of the second paper's reduced study at `quick`,
/// `samples` a point, quietly.
fn reduced_ep21(samples: &str) -> Command {
    let mut c = Command::new(BIN);
    c.args([
        "reproduce",
        "--paper",
        "ep21",
        "--reduced",
        "--samples",
        samples,
    ])
    .args(["--preset", "quick", "-q"]);
    c
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_reduced_reproduction_reports_the_stored_aggregates() {
    let db = format!("sqlite://{}", scratch("repro.db").display());
    let server = Server::start(&db, 2);
    let out = scratch("report").with_file_name("reproduction.md");
    let run = Command::new(BIN)
        .args([
            "reproduce",
            "--reduced",
            "--preset",
            "quick",
            "-q",
            "--server",
        ])
        .arg(&server.url)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("repose reproduce runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(stdout.contains("Wall time of this run"), "{stdout}");

    let markdown = std::fs::read_to_string(&out).expect("the report is written");
    let numbers: Value = serde_json::from_str(
        &std::fs::read_to_string(out.with_file_name("reproduction.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(numbers["preset"], "quick");
    for fig in [
        "fig2a", "fig2b", "fig3", "fig4", "fig5", "fig7a", "fig7b", "k_n", "gamma_n",
    ] {
        let svg = std::fs::read_to_string(out.with_file_name(format!("reproduction-{fig}.svg")))
            .unwrap_or_else(|_| panic!("no SVG for {fig}"));
        assert!(svg.starts_with("<svg") && !svg.contains("NaN"), "{fig}");
        assert!(
            markdown.contains(&format!("reproduction-{fig}.svg")),
            "{fig} not linked"
        );
    }

    let sweeps = numbers["sweeps"].as_array().unwrap();
    assert_eq!(sweeps.len(), 6);
    let metrics = ["theta_r", "theta_r_line", "theta_r_endpoints", "theta_t"];
    let checked = points_match_samples(&server, sweeps, &markdown, &metrics).await;
    assert!(checked >= 20, "only {checked} aggregates checked");

    // The comparison table quotes the same aggregates it names.
    let fig347 = sweeps.iter().find(|s| s["key"] == "fig347").unwrap();
    let at = |mu: f64| {
        fig347["points"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| (p["point"]["contact.mu"].as_f64().unwrap() - mu).abs() < 1e-9)
            .unwrap()["metrics"]["theta_r"]["mean"]
            .as_f64()
            .unwrap()
    };
    let row = numbers["comparison"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["quantity"].as_str().unwrap().starts_with("θ_R method 3"))
        .unwrap();
    assert_eq!(row["ours"]["mean"].as_f64().unwrap(), at(0.2));

    // θ_R rises with μ.
    let (low, mid, high) = (at(0.1), at(0.2), at(0.3));
    println!("θ_R: μ 0.1 {low:.2}°, 0.2 {mid:.2}°, 0.3 {high:.2}°");
    assert!(high > low + 5.0, "θ_R does not rise with μ: {low} → {high}");

    figures_are_the_served_ones(&server, &numbers, "lh93", 9).await;

    // The page can open the report the server carries.
    let resp = reqwest::get(format!("{}/docs/reproduction.md", server.url))
        .await
        .unwrap();
    assert!(resp.status().is_success());
    assert!(resp.text().await.unwrap().starts_with("# Reproduction"));
}

/// Every point in the report against the samples the server stored, and
/// the Markdown showing the same numbers; returns how many were checked.
async fn points_match_samples(
    server: &Server,
    sweeps: &[Value],
    markdown: &str,
    metrics: &[&str],
) -> usize {
    // Every point in the report against the samples the server stored.
    let mut checked = 0;
    for sweep in sweeps {
        let id = sweep["id"].as_str().unwrap();
        let samples = get(&format!("{}/api/sweeps/{id}/samples", server.url)).await;
        let mut by_point: BTreeMap<String, Vec<&Value>> = BTreeMap::new();
        for s in samples["samples"].as_array().unwrap() {
            by_point.entry(s["point"].to_string()).or_default().push(s);
        }
        let points = sweep["points"].as_array().unwrap();
        assert_eq!(points.len(), by_point.len(), "{id}");
        for p in points {
            let stored = &by_point[&p["point"].to_string()];
            for metric in metrics.iter().copied() {
                let values: Vec<f64> = stored
                    .iter()
                    .filter_map(|s| s["metrics"][metric].as_f64())
                    .collect();
                let reported = &p["metrics"][metric];
                if reported.is_null() {
                    // Not a metric of this sweep's protocol.
                    assert!(values.is_empty(), "{id} {metric}");
                    continue;
                }
                assert_eq!(reported["n"].as_u64().unwrap() as usize, values.len());
                if values.len() < 2 {
                    continue;
                }
                let (mean, sd) = mean_sd(&values);
                let (rm, rs) = (
                    reported["mean"].as_f64().unwrap(),
                    reported["sd"].as_f64().unwrap(),
                );
                assert!(
                    (rm - mean).abs() < 1e-9 && (rs - sd).abs() < 1e-6,
                    "{id} {metric}: {rm} {rs} vs {mean} {sd}"
                );
                // …and the Markdown shows the same numbers.
                let cell = format!("{mean:.2} ± {sd:.2} (n={})", values.len());
                assert!(markdown.contains(&cell), "{cell} missing from the report");
                checked += 1;
            }
        }
    }

    checked
}

/// Each figure in the report is the figure data the API serves the page
/// for the same sweeps.
async fn figures_are_the_served_ones(server: &Server, numbers: &Value, paper: &str, count: usize) {
    let sweeps = numbers["sweeps"].as_array().unwrap();
    let bindings: Vec<String> = sweeps
        .iter()
        .map(|s| {
            format!(
                "{}:{}",
                s["key"].as_str().unwrap(),
                s["id"].as_str().unwrap()
            )
        })
        .collect();
    let figures = numbers["figures"].as_array().unwrap();
    assert_eq!(figures.len(), count);
    for f in figures {
        let key = f["figure"].as_str().unwrap();
        let served = get(&format!(
            "{}/api/studies/{paper}/figures/{key}?sweeps={}",
            server.url,
            bindings.join(",")
        ))
        .await;
        assert_eq!(&served, f, "figure {key}");
        assert!(f["missing"].as_array().unwrap().is_empty(), "{key}: {f}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_reduced_reproduction_of_the_second_paper_reports_the_stored_aggregates() {
    let db = format!("sqlite://{}", scratch("repro-ep21.db").display());
    let server = Server::start(&db, 2);
    let out = scratch("report").with_file_name("reproduction-ep21.md");
    let run = reduced_ep21("2")
        .args(["--server", &server.url])
        // A variant of the model: the limits on the size of the net force,
        // as LIGGGHTS 3.3 reads it (the reduced heaps' base sets `contact`).
        .args(["--set", "material.limit_load=liggghts"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("repose reproduce runs");
    assert!(
        run.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let markdown = std::fs::read_to_string(&out).expect("the report is written");
    let numbers: Value = serde_json::from_str(
        &std::fs::read_to_string(out.with_file_name("reproduction-ep21.json")).unwrap(),
    )
    .unwrap();
    for fig in ["fig2", "fig3a", "fig3b", "fig3c", "fig4", "fig5", "regime"] {
        let name = format!("reproduction-ep21-{fig}.svg");
        let svg = std::fs::read_to_string(out.with_file_name(&name))
            .unwrap_or_else(|_| panic!("no SVG for {fig}"));
        assert!(svg.starts_with("<svg") && !svg.contains("NaN"), "{fig}");
        assert!(markdown.contains(&name), "{fig} not linked");
    }
    let sweeps = numbers["sweeps"].as_array().unwrap();
    assert_eq!(sweeps.len(), 3);
    assert_eq!(numbers["variant"], r#"material.limit_load = "liggghts""#);
    assert!(markdown.contains(r#"a variant of the model: material.limit_load = "liggghts""#));
    for sweep in sweeps {
        let id = sweep["id"].as_str().unwrap();
        let stored = get(&format!("{}/api/sweeps/{id}", server.url)).await;
        assert_eq!(stored["spec"]["base"]["material"]["limit_load"], "liggghts");
    }
    let metrics = ["theta_r", "surface_roughness", "packing_fraction"];
    let checked = points_match_samples(&server, sweeps, &markdown, &metrics).await;
    assert!(checked >= 8, "only {checked} aggregates checked");
    figures_are_the_served_ones(&server, &numbers, "ep21", 7).await;

    // The fitted constants in the comparison are the fits the API draws.
    let figure2 = numbers["figures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["figure"] == "2")
        .unwrap();
    let row = |q: &str| {
        numbers["comparison"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["quantity"].as_str().unwrap().starts_with(q))
            .unwrap_or_else(|| panic!("no row {q}"))
            .clone()
    };
    let mu = row("μ_∞ (eq. 1");
    match figure2["fits"][0]["fit"]["params"][0]["value"].as_f64() {
        Some(fitted) => assert_eq!(mu["ours"]["mean"].as_f64(), Some(fitted)),
        None => assert_eq!(mu["verdict"], "no result"),
    }
    assert!(markdown.contains("## Fits"), "no fits section");
    assert!(markdown.contains("θ_r,nc"), "no θ_r,nc row");
    assert!(markdown.contains("regime boundary"), "no regime row");
    println!(
        "ep21 reduced reproduction: {:.1} s",
        numbers["wall_time_s"].as_f64().unwrap()
    );
}

/// The count a one-number query gives on the store.
async fn count(store: &repose_store::Store, sql: &str) -> i64 {
    sqlx::query_scalar(sql)
        .fetch_one(store.pool())
        .await
        .unwrap()
}

/// Stopped by SIGTERM, a reproduction with its own workers hands its
/// running samples back to its database; the same command goes on from
/// their checkpoints, and every sample runs once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stopped_reproduction_goes_on_where_it_stopped() {
    let db = format!("sqlite://{}", scratch("repro-stopped.db").display());
    let store = repose_store::Store::open(&db).await.unwrap();
    let out = scratch("stopped").with_file_name("reproduction-ep21.md");
    let command = |extra: &[&str]| {
        let mut c = reduced_ep21("1");
        c.args(["--workers", "2"])
            .args(["--checkpoint-every", "0.2", "--database", &db])
            .arg("--out")
            .arg(&out)
            .args(extra)
            .env("REPOSE_LOG", "info")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped());
        c
    };
    stop_at_the_first_checkpoint(&store, command(&[])).await;

    // An interim report runs nothing and says what is left.
    let results = count(&store, "SELECT COUNT(*) FROM results").await;
    let interim = command(&["--interim"]).output().expect("an interim report");
    let said = String::from_utf8_lossy(&interim.stderr);
    assert!(interim.status.success(), "{said}");
    assert!(!said.contains(" claimed "), "{said}");
    assert_eq!(count(&store, "SELECT COUNT(*) FROM results").await, results);
    let report = std::fs::read_to_string(&out).expect("the interim report is written");
    let samples = count(&store, "SELECT COUNT(DISTINCT sample_hash) FROM jobs").await;
    let line = format!("{results} of its {samples} samples are finished");
    assert!(report.contains("**Interim report:**"), "{report}");
    assert!(report.contains(&line), "{line}\n{report}");
    assert!(report.contains("--interim"), "{report}");
    // Run again ahead of what the first run left queued, cheapest first.
    let again = command(&["--raise-priority", "1", "--order", "cheapest"])
        .output()
        .expect("repose reproduce runs again");
    let said = String::from_utf8_lossy(&again.stderr);
    assert!(again.status.success(), "{said}");
    assert!(said.contains("continuing from the checkpoint"), "{said}");
    first_claims_are_the_new_runs_cheapest(&store, &said).await;
    let open = "SELECT COUNT(*) FROM jobs WHERE state <> 'done'";
    assert_eq!(count(&store, open).await, 0);
    let samples = count(&store, "SELECT COUNT(DISTINCT sample_hash) FROM jobs").await;
    assert_eq!(count(&store, "SELECT COUNT(*) FROM results").await, samples);
    assert_eq!(count(&store, "SELECT COUNT(*) FROM checkpoints").await, 0);
    let report = std::fs::read_to_string(&out).expect("the report is written");
    assert!(report.contains("Wall time of this run"), "{report}");
    assert!(!report.contains("Interim report"), "{report}");
}

/// Starts `command`, stops it with SIGTERM once it has saved a checkpoint,
/// and checks that it handed its running samples back.
async fn stop_at_the_first_checkpoint(store: &repose_store::Store, mut command: Command) {
    let first = command.spawn().expect("repose reproduce starts");
    let start = std::time::Instant::now();
    while count(store, "SELECT COUNT(*) FROM checkpoints").await == 0 {
        assert!(start.elapsed().as_secs() < 120, "no checkpoint");
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    common::signal(&first, "TERM");
    let stopped = tokio::task::spawn_blocking(|| first.wait_with_output())
        .await
        .unwrap()
        .unwrap();
    let said = String::from_utf8_lossy(&stopped.stderr);
    assert!(!stopped.status.success(), "{said}");
    assert!(
        said.contains("stopped: the running samples go back"),
        "{said}"
    );
    let running = "SELECT COUNT(*) FROM jobs WHERE state = 'running'";
    assert_eq!(count(store, running).await, 0, "handed back: {said}");
    assert!(count(store, "SELECT COUNT(*) FROM checkpoints").await > 0);
}

/// The workers of a run started once its sweeps were queued: the first
/// samples they claimed (in the log `said`) are its cheapest, none of what
/// an earlier run left.
async fn first_claims_are_the_new_runs_cheapest(store: &repose_store::Store, said: &str) {
    let claims: Vec<String> = said
        .lines()
        .filter(|l| l.contains(" claimed "))
        .filter_map(|l| {
            Some(
                l.split(" job=")
                    .nth(1)?
                    .split_whitespace()
                    .next()?
                    .to_string(),
            )
        })
        .take(2)
        .collect();
    assert_eq!(claims.len(), 2, "{said}");
    let mut first = Vec::new();
    for job in &claims {
        let (seq, priority, spec, sweep, study): (i64, i64, String, String, String) = sqlx::query_as(
            "SELECT j.seq, s.priority, s.spec, s.id, s.study FROM jobs j JOIN sweeps s ON s.id = j.sweep_id WHERE j.id = ?",
        )
        .bind(job)
        .fetch_one(store.pool())
        .await
        .unwrap();
        // The study's own priority (the cohesive heaps 0, the cheap dry
        // heaps and columns 1), raised by 1.
        let own = i64::from(study != "ep21/heaps");
        assert_eq!(priority, own + 1, "{study}: {said}");
        assert!(spec.contains(r#""order":"cheapest""#), "{spec}");
        let lowest: i64 =
            sqlx::query_scalar("SELECT MIN(seq) FROM jobs WHERE sweep_id = ? AND attempts > 0")
                .bind(&sweep)
                .fetch_one(store.pool())
                .await
                .unwrap();
        first.push(seq == lowest);
    }
    assert!(first.contains(&true), "{said}");
}

/// `--first` queues the named points of each sweep that has them as a
/// slice above every sweep of the run, then the sweeps whole: the report
/// reads the whole sweeps, which share the slices' samples.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn first_points_are_queued_as_slices_ahead_of_the_whole_study() {
    let db = format!("sqlite://{}", scratch("repro-first.db").display());
    let store = repose_store::Store::open(&db).await.unwrap();
    let out = scratch("first").with_file_name("reproduction-ep21.md");
    let run = |first: &str| {
        reduced_ep21("1")
            .args(["--interim", "--database", &db])
            .args(["--first", first, "--out"])
            .arg(&out)
            .output()
            .expect("repose reproduce runs")
    };
    let bad = run("gravity=[0,0,-1]");
    let said = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success(), "{said}");
    assert!(said.contains("--first gravity=[0,0,-1]"), "{said}");
    assert_eq!(
        count(&store, "SELECT COUNT(*) FROM sweeps").await,
        0,
        "{said}"
    );

    let ok = run("gravity=[0,0,-9.81]");
    let said = String::from_utf8_lossy(&ok.stderr);
    assert!(ok.status.success(), "{said}");
    let sweeps: Vec<(String, i64, Option<String>)> =
        sqlx::query_as("SELECT id, priority, study FROM sweeps ORDER BY created_at")
            .fetch_all(store.pool())
            .await
            .unwrap();
    // The reduced heaps (g̃ = 0.165 and 1) and columns (Earth only) have
    // Earth's points; the reduced dry heaps (g̃ = 0.165 and 10) have none.
    let slices: Vec<_> = sweeps.iter().filter(|s| s.2.is_none()).collect();
    assert_eq!(slices.len(), 2, "{sweeps:?}");
    assert_eq!(sweeps.len(), 5, "{sweeps:?}");
    // Above every sweep of the study (its highest own priority is 1).
    assert!(slices.iter().all(|s| s.1 == 2), "{sweeps:?}");
    assert!(sweeps.iter().filter(|s| s.2.is_some()).all(|s| s.1 < 2));
    for (id, _, _) in slices {
        let gravities: Vec<String> = sqlx::query_scalar(
            "SELECT DISTINCT json_extract(point, '$.gravity') FROM jobs WHERE sweep_id = ?",
        )
        .bind(id)
        .fetch_all(store.pool())
        .await
        .unwrap();
        assert_eq!(gravities, ["[0.0,0.0,-9.81]"], "{id}");
        let shared: i64 = sqlx::query_scalar(
            "SELECT COUNT(*) FROM jobs a WHERE a.sweep_id = ? AND EXISTS (SELECT 1 FROM jobs b \
             JOIN sweeps s ON s.id = b.sweep_id WHERE s.study IS NOT NULL AND b.sample_hash = a.sample_hash)",
        )
        .bind(id)
        .fetch_one(store.pool())
        .await
        .unwrap();
        let all: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE sweep_id = ?")
            .bind(id)
            .fetch_one(store.pool())
            .await
            .unwrap();
        assert_eq!(
            (shared, all > 0),
            (all, true),
            "every sample of a slice is the whole sweep's"
        );
    }
    let report = std::fs::read_to_string(&out).expect("the interim report is written");
    let samples = count(&store, "SELECT COUNT(DISTINCT sample_hash) FROM jobs").await;
    assert!(
        report.contains(&format!("0 of its {samples} samples")),
        "{report}"
    );
}

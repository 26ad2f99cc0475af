//! Keeping a service running: `repose retry` (failed jobs back in the
//! queue, through the server) and `repose backup` (a consistent copy of a
//! live SQLite store).

use crate::client::http;
use crate::service::runtime;
use anyhow::{bail, Context};
use serde_json::Value;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct RetryArgs {
    /// The sweep whose failed jobs to run again.
    sweep: String,
    #[arg(long, default_value = crate::service::DEFAULT_SERVER, env = "REPOSE_SERVER")]
    server: String,
}

/// Queues a sweep's failed jobs again; finished ones are not rerun.
pub fn retry(args: RetryArgs) -> anyhow::Result<ExitCode> {
    let server = args.server.trim_end_matches('/');
    runtime()?.block_on(async {
        let url = format!("{server}/api/sweeps/{}/retry", args.sweep);
        let resp = http()?.post(&url).send().await.with_context(|| {
            format!("cannot reach the server at {server} (is `repose serve` running?)")
        })?;
        let status = resp.status();
        let body: Value = resp.json().await.unwrap_or(Value::Null);
        if !status.is_success() {
            bail!(
                "{} {}",
                status.as_u16(),
                body["error"].as_str().unwrap_or("")
            );
        }
        let p = &body["sweep"]["progress"];
        crate::emit(&format!(
            "sweep {}: {} failed jobs queued again ({} queued, {} done)\n",
            args.sweep, body["retried"], p["queued"], p["done"]
        ))?;
        Ok(ExitCode::SUCCESS)
    })
}

#[derive(clap::Args)]
pub struct BackupArgs {
    /// The SQLite store to copy (it may be in use).
    #[arg(long, default_value = crate::service::DEFAULT_DATABASE, env = "REPOSE_DATABASE")]
    database: String,
    /// The copy to write (must not exist yet).
    output: PathBuf,
}

/// A consistent copy of a live SQLite store (`VACUUM INTO`: one read
/// transaction, so writers go on and the copy is a single moment).
pub fn backup(args: BackupArgs) -> anyhow::Result<ExitCode> {
    if !args.database.starts_with("sqlite:") {
        bail!(
            "--database: `repose backup` copies SQLite stores; back up PostgreSQL with \
             pg_dump (docs/service.md)"
        );
    }
    let source = args.database["sqlite:".len()..].trim_start_matches("//");
    let source = source.split('?').next().unwrap_or(source);
    if !std::path::Path::new(source).exists() {
        bail!("--database: there is no store at {source}");
    }
    if args.output.exists() {
        bail!("{} exists already; name a new file", args.output.display());
    }
    let target = args
        .output
        .to_str()
        .context("the output path must be valid UTF-8")?
        .to_string();
    runtime()?.block_on(async {
        // Not `open`: a store served by another build keeps its schema.
        let store = repose_store::Store::connect(&args.database)
            .await
            .with_context(|| format!("cannot open the database {}", args.database))?;
        let counts = store.backup_into(&target).await?;
        crate::emit(&format!(
            "backup of {} written to {target}: {} sweeps, {} jobs, {} results\n",
            args.database, counts.0, counts.1, counts.2
        ))?;
        Ok(ExitCode::SUCCESS)
    })
}

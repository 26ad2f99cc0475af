//! Headless workers on a real (one-node) SLURM cluster: a sweep queued on
//! PostgreSQL completes through `deploy/slurm/repose-workers.sbatch`
//! submitted as a job array. `.ci/run` starts the cluster with
//! `deploy/slurm/local-cluster.sh`; with `CI=true` the test fails when
//! SLURM is not there, elsewhere it skips.

use repose_store::Store;
use serde_json::json;
use std::path::Path;
use std::process::Command;

#[path = "common/mod.rs"]
mod common;

use common::{post, scratch, Server, BIN};

fn slurm_is_up() -> bool {
    Command::new("sinfo")
        .args(["-h", "-o", "%T"])
        .output()
        .is_ok_and(|o| o.status.success() && String::from_utf8_lossy(&o.stdout).contains("idle"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sweep_completes_through_a_slurm_job_array() {
    let how = "deploy/slurm/local-cluster.sh starts one";
    if !repose_testkit::needs(slurm_is_up(), "SLURM cluster", how) {
        return;
    }
    let scratch_db = common::postgres()
        .await
        .expect("PostgreSQL for the SLURM test");
    let db = scratch_db.url().to_string();
    let api = Server::start(&db, 0);
    let spec = json!({
        "protocol": "free_run",
        "base": {"duration": 0.02, "particles": [{"position": [0.0, 0.3], "radius": 0.1}],
                 "walls": [{"point": [0.0, 0.0], "normal": [0.0, 1.0]}]},
        "samples": 20
    });
    let created = post(&format!("{}/api/sweeps", api.url), &spec).await;
    let id = created["id"].as_str().expect("sweep queued").to_string();
    let logs = scratch("slurm");
    std::fs::create_dir_all(&logs).unwrap();
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = Command::new("sbatch")
        .args([
            "--wait",
            "--array=1-2",
            "--cpus-per-task=1",
            "--time=00:05:00",
            &format!("--output={}/worker-%A_%a.log", logs.display()),
            "deploy/slurm/repose-workers.sbatch",
        ])
        .env("REPOSE_DATABASE", &db)
        .env("REPOSE", BIN)
        .env("REPOSE_LEASE", "30")
        .env("REPOSE_HEARTBEAT", "5")
        .current_dir(&workspace)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "sbatch: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    // Both array tasks ran a worker, and together they wrote every result.
    let mut written = 0;
    let mut tasks = 0;
    for entry in std::fs::read_dir(&logs).unwrap() {
        let log = std::fs::read_to_string(entry.unwrap().path()).unwrap();
        let n: u64 = log
            .split("repose worker: ")
            .nth(1)
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no worker summary in {log}"));
        written += n;
        tasks += 1;
    }
    assert_eq!((tasks, written), (2, 20));
    let store = Store::open(&db).await.unwrap();
    let p = store.progress(&id).await.unwrap();
    assert_eq!(
        (p.done, p.queued, p.running, p.failed),
        (20, 0, 0, 0),
        "{p:?}"
    );
    println!("SLURM: 2 array tasks wrote {written} results of sweep {id}");
    drop(api);
    repose_testkit::drop_postgres(scratch_db, store).await;
}

//! Workers of one process share their cores: the last sample of a sweep,
//! run while the other worker has nothing to claim, takes its core as a
//! second thread, and stores the numbers it would have on one thread.

use repose_physics::{run, Quiet, RunReport, Scene};
use repose_sweeps::SweepSpec;
use repose_worker::{run_worker, Cores, WorkerConfig};
use serde_json::{json, Value};

/// The narrow cohesive column of `examples/packing.toml` (about a thousand
/// grains: enough listed pairs for its steps to be shared).
fn spec() -> SweepSpec {
    serde_json::from_value(json!({
        "protocol": "packing",
        "fidelity": "quick",
        "base": {
            "material": {"surface_energy": 0.05},
            "packing": {"height": 40}
        },
        "axes": {"packing.width": [8]},
        "samples": 1
    }))
    .unwrap()
}

/// What a run simulated: its metrics and the final state of every grain.
fn numbers(report: &Value) -> (Value, Value) {
    (report["metrics"].clone(), report["final_state"].clone())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
async fn the_last_sample_takes_an_idle_workers_core_and_keeps_its_numbers() {
    let store = repose_testkit::sqlite("repose-lending").await;
    let s = spec();
    let expanded = s.expand().unwrap();
    assert_eq!(expanded.len(), 1);
    let jobs: Vec<_> = expanded.iter().map(|j| j.to_new_job()).collect();
    store.create_sweep(&s.new_sweep(), &jobs, 3).await.unwrap();
    let cores = Cores::new(2);
    let (_stop, rx) = tokio::sync::watch::channel(false);
    let workers: Vec<_> = (0..2)
        .map(|k| {
            let mut c = WorkerConfig::new(format!("w{k}"));
            c.exit_when_idle = true;
            c.cores = Some(cores.clone());
            tokio::spawn(run_worker(store.clone(), c, rx.clone()))
        })
        .collect();
    let mut completed = 0;
    for w in workers {
        completed += w.await.unwrap().completed;
    }
    assert_eq!(completed, 1);
    assert_eq!(
        cores.most_threads(),
        2,
        "the sample never got the idle core"
    );
    let stored = store
        .report(&expanded[0].sample_hash)
        .await
        .unwrap()
        .unwrap();
    // The second core did share the sample's steps.
    let shared = stored["counters"]["shared_steps"].as_u64().unwrap_or(0);
    assert!(shared > 0, "{}", stored["counters"]);
    let scene: &Scene = &expanded[0].scene;
    assert_eq!(scene.numerics.threads, 1);
    let alone: RunReport = run(scene, &mut Quiet).unwrap();
    assert!(alone.outcome.is_completed(), "{:?}", alone.outcome);
    assert_eq!(
        numbers(&stored),
        numbers(&serde_json::to_value(&alone).unwrap())
    );
}

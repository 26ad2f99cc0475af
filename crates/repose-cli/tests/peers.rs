//! The peer engines' versions of repose's scenes, run as their scripts run
//! them: LIGGGHTS pours the second paper's dry heap on repose's protocol
//! (`bench/liggghts-dry-heap.sh`) and `repose measure-heap` reads it.
//! `.ci/run` installs Debian's `liggghts`; with `CI=true` the test fails
//! when it is not there, elsewhere it skips.

use std::path::PathBuf;
use std::process::Command;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn liggghts_is_there() -> bool {
    Command::new("sh")
        .args(["-c", "command -v liggghts"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The CSV of the script's heaps: header names to values, one map a row.
fn rows(csv: &str) -> Vec<std::collections::HashMap<String, String>> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, v)| (h.to_string(), v.to_string()))
                .collect()
        })
        .collect()
}

#[test]
fn liggghts_pours_the_dry_heap_on_repose_protocol_and_repose_reads_it() {
    let how = "apt-get install liggghts; .ci/run installs it";
    if !repose_testkit::needs(liggghts_is_there(), "LIGGGHTS", how) {
        return;
    }
    // A small heap of soft grains: a few seconds.
    let out = repose_testkit::scratch_dir("liggghts-dry");
    let (y, grains) = ("6.3e7", "800");
    let run = Command::new("bash")
        .arg(workspace().join("bench/liggghts-dry-heap.sh"))
        .env("REPOSE", env!("CARGO_BIN_EXE_repose"))
        .env("OUT", &out)
        .env("SEEDS", "0")
        .env("Y", y)
        .env("GRAINS", grains)
        .output()
        .expect("the script runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let csv = std::fs::read_to_string(out.join("heaps.csv")).unwrap();
    let rows = rows(&csv);
    assert_eq!(rows.len(), 1, "{csv}");
    let row = &rows[0];
    let num = |k: &str| -> f64 { row[k].parse().unwrap_or_else(|_| panic!("{k} in {csv}")) };
    // Every grain the cap allows was poured, and the heap keeps some.
    assert_eq!(row["grains_poured"], grains);
    let kept = num("heap_grains");
    assert!(kept > 10.0 && kept < 800.0, "{csv}");
    let theta = num("theta_r");
    assert!(theta > 3.0 && theta < 45.0, "{csv}");
    assert!(num("theta_r_silhouette") < theta, "{csv}");

    // The same scene in repose steps with the same time step: the input
    // mirrors the protocol's numerics, not only its geometry.
    let scene = Command::new(env!("CARGO_BIN_EXE_repose"))
        .current_dir(workspace())
        .args([
            "run",
            "examples/heap.toml",
            "--preset",
            "paper",
            "--json",
            "-q",
        ])
        .args(["--set", &format!("material.youngs_modulus={y}")])
        .args(["--set", "heap.plate=20", "--set", "heap.max_grains=1"])
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&scene.stdout).unwrap();
    let dt = report["options"]["dt"].as_f64().unwrap();
    let summary = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| std::fs::read_to_string(e.ok()?.path().join("summary.txt")).ok())
        .next()
        .expect("a summary of the LIGGGHTS run");
    let words: Vec<&str> = summary.split_whitespace().collect();
    let at = words.iter().position(|w| *w == "dt").unwrap();
    let liggghts_dt: f64 = words[at + 1].parse().unwrap();
    assert!(
        (liggghts_dt / dt - 1.0).abs() < 1e-9,
        "LIGGGHTS steps {liggghts_dt} s, repose {dt} s"
    );
}

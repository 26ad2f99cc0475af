//! `repose bench --heap`: particle-steps per second of the 3D heap of the
//! LIGGGHTS peer run, pouring and settled, single thread by default, with
//! the time of each stage; `--liggghts FILE` reads that run's CSV and
//! prints the ratio. `--heap --options`: the cost of each 3D physics
//! option on the same scene.

use crate::bench::{
    against_base, medians, peer_rows, throughput_cells, throughput_header, BenchArgs, AGAINST_BASE,
};
use repose_physics::bench::heap::{heap_throughput, HeapSteps, LIGGGHTS_HEAP};
use repose_physics::Scene;
use std::collections::HashMap;
use std::path::Path;
use std::process::ExitCode;

/// The 3D options a scene can switch, each measured against the baseline.
const OPTIONS: &[(&str, &[&str])] = &[
    ("baseline: rotation, epsd2 rolling, no cohesion", &[]),
    ("no rolling resistance", &["material.rolling=\"none\""]),
    (
        "no rotation (and so no rolling resistance)",
        &["material.rotation=false", "material.rolling=\"none\""],
    ),
    (
        "van der Waals cohesion (γ = 0.05 J/m²)",
        &["material.surface_energy=0.05"],
    ),
    (
        "Coulomb cap on spring and damper (the paper's)",
        &["material.tangential_cap=\"total\""],
    ),
];

fn scene(args: &BenchArgs, extra: &[&str]) -> anyhow::Result<Scene> {
    let mut o: Vec<String> = args.set.clone();
    o.extend(extra.iter().map(|s| s.to_string()));
    o.push(format!("numerics.threads={}", args.threads));
    Scene::from_toml(LIGGGHTS_HEAP, &o).map_err(|e| anyhow::anyhow!("{e}"))
}

fn steps(args: &BenchArgs) -> HeapSteps {
    let scale = |n: u64| ((n as f64 * args.scale).round() as u64).max(1);
    let full = HeapSteps::default();
    HeapSteps {
        pour: scale(full.pour),
        settle: scale(full.settle),
        settled: scale(full.settled),
    }
}

/// The heap benchmark against the peer run.
pub fn heap(args: &BenchArgs) -> anyhow::Result<ExitCode> {
    if args.options {
        return options(args);
    }
    let peer = match &args.liggghts {
        Some(p) => read_liggghts(p)?,
        None => HashMap::new(),
    };
    eprintln!("pouring and settling the 2000-sphere heap ...");
    let phases = heap_throughput(&scene(args, &[])?, steps(args))?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&phases)?)?;
        return Ok(ExitCode::SUCCESS);
    }
    outln!("{:<9} {}", "phase", throughput_header("LIGGGHTS"))?;
    outln!("{:<41}   {:^31}", "", "ns per particle-step, by stage")?;
    for p in &phases {
        outln!("{:<9} {}", p.phase, throughput_cells(p, peer.get(p.phase)))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// Particle-steps per second of each 3D option, pouring and settled.
fn options(args: &BenchArgs) -> anyhow::Result<ExitCode> {
    outln!(
        "{:<50} {:>12} {:>8} {:>12} {:>8} {:>9}",
        "option (2000-sphere heap)",
        "pour M/s",
        "× base",
        "settled M/s",
        "× base",
        "contacts"
    )?;
    let mut base: Option<(f64, f64)> = None;
    for (label, overrides) in OPTIONS {
        let phases = heap_throughput(&scene(args, overrides)?, steps(args))?;
        let contacts = 2.0 * phases[1].touching_end as f64 / phases[1].grains_end as f64;
        let costs = against_base(&phases, &mut base);
        outln!("{label:<50} {costs} {contacts:>9.2}")?;
    }
    outln!("({AGAINST_BASE};")?;
    outln!(
        " contacts: grain-grain contacts per grain in the settled heap, which each option shapes)"
    )?;
    Ok(ExitCode::SUCCESS)
}

/// One row of the LIGGGHTS peer CSV (the columns this benchmark reads).
#[derive(serde::Deserialize)]
struct LiggghtsRow {
    rolling: String,
    phase: String,
    psteps_per_s_loop: f64,
}

/// Median particle-steps/s over LIGGGHTS's own loop time, per phase, of
/// the `epsd2` rows (the rolling model of the paper and of this engine).
fn read_liggghts(path: &Path) -> anyhow::Result<HashMap<&'static str, f64>> {
    let rows: Vec<LiggghtsRow> = peer_rows(path, "rolling, phase and psteps_per_s_loop")?;
    let mut groups: HashMap<&'static str, Vec<f64>> = HashMap::new();
    for row in rows {
        let phase = match row.phase.as_str() {
            "pour" => "pour",
            "settled" => "settled",
            _ => continue,
        };
        if row.rolling == "epsd2" {
            groups.entry(phase).or_default().push(row.psteps_per_s_loop);
        }
    }
    Ok(medians(groups))
}

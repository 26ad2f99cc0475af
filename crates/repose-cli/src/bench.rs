//! `repose bench`: particle-steps per second of the fill-and-release scene,
//! single thread, settled and flowing, for each integrator, with the time
//! of each stage. The scenes and step counts match the LAMMPS peer runs of
//! `bench/lammps-pile.sh` (dt = 1e-5 s, N = 25·W·H), so the two can be
//! compared side by side; `--lammps FILE` reads that run's CSV and prints
//! the ratio.

use anyhow::Context;
use repose_engine::integrate::Scheme;
use repose_physics::bench::{throughput, PhaseThroughput};
use repose_physics::Scene;
use std::collections::HashMap;
use std::hash::Hash;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Box sizes W = H to measure.
    #[arg(long, value_delimiter = ',', default_values_t = vec![4.0, 8.0])]
    pub sizes: Vec<f64>,
    /// Integrators to measure.
    #[arg(long, value_delimiter = ',', default_values = ["verlet", "gear5"])]
    pub integrators: Vec<String>,
    /// Time step, s (LAMMPS peer runs use 1e-5).
    #[arg(long, default_value_t = 1e-5)]
    pub dt: f64,
    /// Scale the step counts (1 = the LAMMPS runs' counts).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Extra scene overrides, e.g. --set contact.shear_spring=truncated.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// CSV written by the LAMMPS peer benchmark (throughput_lammps.csv).
    #[arg(long)]
    pub lammps: Option<PathBuf>,
    /// Print JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Instead: the cost of each physics option, per particle-step, on the
    /// W = H = 4 scene with Verlet (each option against the same baseline);
    /// with --heap, of each 3D option on the heap.
    #[arg(long)]
    pub options: bool,
    /// Instead: the 3D heap of the LIGGGHTS peer run (2000 spheres, poured
    /// then settled).
    #[arg(long)]
    pub heap: bool,
    /// CSV written by the LIGGGHTS peer benchmark (throughput_liggghts.csv).
    #[arg(long)]
    pub liggghts: Option<PathBuf>,
    /// Threads per simulation (results are the same for any number).
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
}

/// The physics options a scene can switch, each measured against the baseline.
const OPTIONS: &[(&str, &[&str])] = &[
    ("baseline: Verlet, paper spring, floored F_n", &[]),
    (
        "frictionless (μ = 0, γ_s = 0: no shear history)",
        &["contact.mu=0", "contact.gamma_s=0"],
    ),
    (
        "truncated shear spring",
        &["contact.shear_spring=\"truncated\""],
    ),
    (
        "raw normal force (no floor)",
        &["contact.normal_force=\"raw\""],
    ),
    ("Gear-5 integrator", &["numerics.integrator=\"gear5\""]),
];

/// What the `× base` columns of an option table mean.
pub(crate) const AGAINST_BASE: &str =
    "× base: cost per particle-step relative to the baseline; above 1 is slower";

/// An option's rates in its two phases (M particle-steps/s), each with its
/// cost against the first option's (`base`, set by the first call).
pub(crate) fn against_base(phases: &[PhaseThroughput], base: &mut Option<(f64, f64)>) -> String {
    let rates = (
        phases[0].particle_steps_per_second,
        phases[1].particle_steps_per_second,
    );
    let (a, b) = *base.get_or_insert(rates);
    format!(
        "{:>12.2} {:>8.2} {:>12.2} {:>8.2}",
        rates.0 / 1e6,
        a / rates.0,
        rates.1 / 1e6,
        b / rates.1
    )
}

/// Particle-steps per second of each option, settled and flowing.
fn option_costs(args: &BenchArgs) -> anyhow::Result<ExitCode> {
    outln!(
        "{:<52} {:>12} {:>8} {:>12} {:>8}",
        "option (W = H = 4)",
        "settled M/s",
        "× base",
        "flow M/s",
        "× base"
    )?;
    let mut base: Option<(f64, f64)> = None;
    for (label, overrides) in OPTIONS {
        let mut o = vec![
            "box.width=4".to_string(),
            "box.height=4".to_string(),
            format!("numerics.dt={}", args.dt),
            "numerics.integrator=\"verlet\"".to_string(),
        ];
        o.extend(overrides.iter().map(|s| s.to_string()));
        let scene = Scene::from_toml("protocol = \"fill_release\"\nseed = 1", &o)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let scale = |n: u64| ((n as f64 * args.scale).round() as u64).max(1);
        let phases = throughput(&scene, scale(50_000), scale(20_000))?;
        outln!("{label:<52} {}", against_base(&phases, &mut base))?;
    }
    outln!("({AGAINST_BASE})")?;
    Ok(ExitCode::SUCCESS)
}

/// Step counts of the LAMMPS peer runs (settled, flow) for a box size.
fn steps_for(size: f64) -> (u64, u64) {
    if size <= 4.0 {
        (50_000, 20_000)
    } else {
        (20_000, 20_000)
    }
}

pub fn run(args: BenchArgs) -> anyhow::Result<ExitCode> {
    if args.options {
        return option_costs(&args);
    }
    let lammps = match &args.lammps {
        Some(p) => read_lammps(p)?,
        None => HashMap::new(),
    };
    let rows = match measure_sizes(&args)? {
        Ok(rows) => rows,
        Err(message) => {
            eprintln!("error: {message}");
            return Ok(ExitCode::from(2));
        }
    };
    if args.json {
        let out: Vec<_> = rows
            .iter()
            .map(|(size, scheme, p)| serde_json::json!({ "size": size, "integrator": scheme, "result": p }))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&out)?)?;
    } else {
        print_table(&rows, &lammps)?;
        print_scheme_ratios(&rows)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// One measured phase: box size, integrator name, its throughput.
type Row = (f64, &'static str, PhaseThroughput);

/// Measures every size with every integrator; the inner error is a scene
/// the options make invalid.
fn measure_sizes(args: &BenchArgs) -> anyhow::Result<Result<Vec<Row>, String>> {
    let mut rows = Vec::new();
    for &size in &args.sizes {
        for integrator in &args.integrators {
            let scheme: Scheme =
                serde_json::from_value(serde_json::Value::String(integrator.clone()))
                    .with_context(|| {
                        format!("unknown integrator `{integrator}` (gear5 or verlet)")
                    })?;
            let mut overrides = vec![
                format!("box.width={size}"),
                format!("box.height={size}"),
                format!("numerics.dt={}", args.dt),
                format!("numerics.integrator=\"{}\"", scheme.name()),
            ];
            overrides.extend(args.set.iter().cloned());
            let scene = match Scene::from_toml("protocol = \"fill_release\"\nseed = 1", &overrides)
            {
                Ok(s) => s,
                Err(e) => return Ok(Err(e.to_string())),
            };
            let (settled, flow) = steps_for(size);
            let scale = |n: u64| ((n as f64 * args.scale).round() as u64).max(1);
            eprintln!("measuring W = H = {size}, {} ...", scheme.name());
            for p in throughput(&scene, scale(settled), scale(flow))? {
                rows.push((size, scheme.name(), p));
            }
        }
    }
    Ok(Ok(rows))
}

fn print_table(rows: &[Row], lammps: &HashMap<(String, String), f64>) -> std::io::Result<()> {
    outln!(
        "{:<8} {:<7} {:<8} {}",
        "scene",
        "scheme",
        "phase",
        throughput_header("LAMMPS")
    )?;
    outln!("{:<53}   {:^31}", "", "ns per particle-step, by stage")?;
    for (size, scheme, p) in rows {
        let key = (format!("{size:.0}"), p.phase.to_string());
        outln!(
            "{:<8} {:<7} {:<8} {}",
            format!("W=H={size}"),
            scheme,
            p.phase,
            throughput_cells(p, lammps.get(&key))
        )?;
    }
    Ok(())
}

/// The heads of the columns of [`throughput_cells`], the peer named.
pub(crate) fn throughput_header(peer: &str) -> String {
    format!(
        "{:>11} {:>7} {:>10}   {:>7} {:>7} {:>7} {:>7}  {:>9} {:>7}",
        "grains", "steps", "Mpsteps/s", "neigh", "contact", "walls", "integr", peer, "ratio"
    )
}

/// The columns a throughput row shares in the 2D and 3D tables: grains,
/// steps, million particle-steps a second, nanoseconds a particle-step in
/// each stage, and the peer's throughput with the ratio to it.
pub(crate) fn throughput_cells(p: &PhaseThroughput, peer: Option<&f64>) -> String {
    let c = &p.counters;
    let per = |t: f64| 1e9 * t / p.particle_steps.max(1) as f64;
    let (peer, ratio) = match peer {
        Some(v) => (
            format!("{:.2}", v / 1e6),
            format!("{:.2}×", p.particle_steps_per_second / v),
        ),
        None => ("-".into(), "-".into()),
    };
    format!(
        "{:>11} {:>7} {:>10.2}   {:>7.1} {:>7.1} {:>7.1} {:>7.1}  {:>9} {:>7}",
        format!("{}→{}", p.grains_start, p.grains_end),
        p.steps,
        p.particle_steps_per_second / 1e6,
        per(c.neighbours),
        per(c.contacts),
        per(c.walls),
        per(c.integrate),
        peer,
        ratio
    )
}

/// Gear-5 against Verlet for each size and phase measured with both.
fn print_scheme_ratios(rows: &[Row]) -> std::io::Result<()> {
    let find = |size: f64, scheme: &str, phase: &str| {
        rows.iter()
            .find(|(s, sc, p)| *s == size && *sc == scheme && p.phase == phase)
            .map(|(_, _, p)| p.particle_steps_per_second)
    };
    for (size, _, p) in rows.iter().filter(|(_, s, _)| *s == "gear5") {
        if let (Some(g), Some(v)) = (
            find(*size, "gear5", p.phase),
            find(*size, "verlet", p.phase),
        ) {
            outln!(
                "W=H={size} {}: Gear-5 costs {:.2}× Verlet per particle-step",
                p.phase,
                v / g
            )?;
        }
    }
    Ok(())
}

/// One row of the LAMMPS peer CSV (the columns this benchmark reads).
#[derive(serde::Deserialize)]
struct LammpsRow {
    #[serde(rename = "W")]
    w: String,
    phase: String,
    psteps_per_s_real: f64,
}

/// Median particle-steps/s (wall time of the whole process) per (size, phase)
/// from the LAMMPS peer CSV.
fn read_lammps(path: &Path) -> anyhow::Result<HashMap<(String, String), f64>> {
    let rows: Vec<LammpsRow> = peer_rows(path, "W, phase and psteps_per_s_real")?;
    let mut groups: HashMap<(String, String), Vec<f64>> = HashMap::new();
    for row in rows {
        groups
            .entry((row.w, row.phase))
            .or_default()
            .push(row.psteps_per_s_real);
    }
    Ok(medians(groups))
}

/// The rows of a peer benchmark's CSV; `columns` names what a row needs.
pub(crate) fn peer_rows<R: serde::de::DeserializeOwned>(
    path: &Path,
    columns: &str,
) -> anyhow::Result<Vec<R>> {
    let mut reader =
        csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
    reader
        .deserialize::<R>()
        .map(|row| row.with_context(|| format!("{} lacks the {columns} columns", path.display())))
        .collect()
}

/// The median of each group of rates.
pub(crate) fn medians<K: Eq + Hash>(groups: HashMap<K, Vec<f64>>) -> HashMap<K, f64> {
    groups
        .into_iter()
        .map(|(k, mut v)| {
            v.sort_by(f64::total_cmp);
            (k, v[v.len() / 2])
        })
        .collect()
}

//! `repose`: run granular-pile scenes, benchmark the engine, serve and
//! drive the sweep service, and reproduce the papers.
//!
//! ```text
//! repose run examples/fill_release.toml
//! repose run examples/tilt.toml --set contact.mu=0.3 --json
//! repose run examples/fill_release.toml --snapshot pile.svg --trace ke.csv
//! repose bench
//! repose serve                      # API + workers on sqlite://repose.db
//! repose submit sweeps/smoke.toml --wait
//! repose worker --database postgres://host/db
//! repose reproduce --preset quick
//! ```

/// `println!` through [`emit`]: a reader that has closed the pipe comes
/// back as an error to pass on with `?`, where `println!` would panic.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::emit(&format!("{}\n", format_args!($($arg)*)))
    };
}

mod admin;
mod bench;
mod bench3d;
mod bench_service;
mod client;
mod measure_heap;
mod output;
mod reproduce;
mod service;
mod side_views;
mod tradeoff;

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use repose_physics::report::Phase;
use repose_physics::{registry, Observer, Progress, RunReport, Scene};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "repose",
    version,
    about = "Parameter studies of granular piles: the angle of repose, simulated and served"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one sample of a scene and print what it measured.
    Run(RunArgs),
    /// Measure engine throughput (particle-steps per second, single thread).
    Bench(bench::BenchArgs),
    /// Measure the service: queue overhead, query latency, worker speed-up.
    BenchService(bench_service::BenchServiceArgs),
    /// Measure what each fidelity preset and knob costs and how far it moves θ_R and θ_T.
    Tradeoff(tradeoff::TradeoffArgs),
    /// Queue every sweep behind the paper's figures through the service and write a report.
    Reproduce(reproduce::ReproduceArgs),
    /// Run the API and embedded workers (SQLite file by default).
    Serve(service::ServeArgs),
    /// Run headless workers against a shared database (cluster nodes).
    Worker(service::WorkerArgs),
    /// Queue a sweep on a running server.
    Submit(service::SubmitArgs),
    /// List sweeps, or show one sweep's points.
    Status(service::StatusArgs),
    /// Export a sweep's samples or points as CSV.
    Export(service::ExportArgs),
    /// Write where a running sample's grains are, from its latest checkpoint.
    Grains(service::GrainsArgs),
    /// Run a sweep's failed jobs again (finished samples are kept).
    Retry(admin::RetryArgs),
    /// Copy a live SQLite store to a new file, consistently.
    Backup(admin::BackupArgs),
    /// Read a heap poured by another engine as the heap protocol reads its own.
    MeasureHeap(measure_heap::MeasureHeapArgs),
}

#[derive(clap::Args)]
struct RunArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Override a scene value, e.g. --set contact.mu=0.3 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Fidelity preset (quick, standard, paper): fills the numerical
    /// settings the scene does not set; same as --set preset=NAME.
    #[arg(long, value_name = "NAME")]
    preset: Option<repose_physics::Preset>,
    /// Print one JSON document instead of the summary.
    #[arg(long)]
    json: bool,
    /// Include the final state of every grain in the JSON output.
    #[arg(long)]
    state: bool,
    /// Draw the final pile with force chains to this SVG file.
    #[arg(long, value_name = "FILE.svg")]
    snapshot: Option<PathBuf>,
    /// Write kinetic energy per grain against iteration to this CSV file.
    #[arg(long, value_name = "FILE.csv")]
    trace: Option<PathBuf>,
    /// Write the final grains as a legacy VTK file (ParaView).
    #[arg(long, value_name = "FILE.vtk")]
    vtk: Option<PathBuf>,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run(args),
        Command::Bench(args) if args.heap => bench3d::heap(&args),
        Command::Bench(args) => bench::run(args),
        Command::BenchService(args) => bench_service::run_bench(args),
        Command::Tradeoff(args) => tradeoff::run(args),
        Command::Reproduce(args) => reproduce::run(args),
        Command::Serve(args) => service::serve(args),
        Command::Worker(args) => service::worker(args),
        Command::Submit(args) => service::submit(args),
        Command::Status(args) => service::status(args),
        Command::Export(args) => service::export(args),
        Command::Grains(args) => service::grains(args),
        Command::Retry(args) => admin::retry(args),
        Command::Backup(args) => admin::backup(args),
        Command::MeasureHeap(args) => measure_heap::run(args),
    };
    match result {
        Ok(code) => code,
        // The reader of the output went away (`repose status | head -1`):
        // what it wanted it has, so leave quietly, as Unix tools do.
        Err(e) if reader_gone(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// Writes `text` to standard output, returning the failure instead of
/// panicking as `print!` does when the reader has closed the pipe.
pub(crate) fn emit(text: &str) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()
}

/// Whether `e` is standard output's reader having closed the pipe.
fn reader_gone(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Progress bar over simulated time, shown on a terminal only.
struct Bar {
    bar: Option<ProgressBar>,
    phase: Option<Phase>,
}

impl Bar {
    fn new(enabled: bool) -> Self {
        let bar = enabled.then(|| {
            let b = ProgressBar::new_spinner();
            b.set_style(
                ProgressStyle::with_template("{spinner} [{elapsed_precise}] {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            b
        });
        Bar { bar, phase: None }
    }
}

impl Observer for Bar {
    fn progress(&mut self, u: &Progress) -> bool {
        if let Some(bar) = &self.bar {
            if self.phase != Some(u.phase) {
                self.phase = Some(u.phase);
            }
            bar.set_message(format!(
                "{:<5} t = {:7.3} s  step {:>9}  grains {:>5}  KE/grain {:9.3e} erg  v_max {:8.3} cm/s",
                u.phase.name(),
                u.time,
                u.iteration,
                u.grains,
                u.kinetic_energy,
                u.max_speed
            ));
            bar.tick();
        }
        true
    }
}

fn run(args: RunArgs) -> anyhow::Result<ExitCode> {
    let text = std::fs::read_to_string(&args.scene)
        .with_context(|| format!("cannot read scene file {}", args.scene.display()))?;
    let mut overrides = args.set.clone();
    if let Some(p) = args.preset {
        overrides.insert(0, format!("preset={p}"));
    }
    let scene = match Scene::from_toml(&text, &overrides) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: invalid scene {}", args.scene.display());
            for f in &e.errors {
                eprintln!("  {}: {}", f.field, f.message);
            }
            return Ok(ExitCode::from(2));
        }
    };
    let mut bar = Bar::new(!args.quiet && std::io::stderr().is_terminal());
    let mut report = repose_physics::run(&scene, &mut bar)?;
    if let Some(b) = &bar.bar {
        b.finish_and_clear();
    }

    if let Some(path) = &args.snapshot {
        std::fs::write(path, output::snapshot_svg(&report))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(path) = &args.trace {
        std::fs::write(path, output::trace_csv(&report))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if let Some(path) = &args.vtk {
        std::fs::write(path, output::vtk(&report))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }

    if args.json {
        if !args.state {
            report.final_state = None;
        }
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        emit(&summary(&report))?;
    }
    Ok(if report.outcome.is_completed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// A metric with its unit: counts as integers, angles with the degree
/// sign against the number, other units after a space.
fn with_unit(v: f64, unit: &str) -> String {
    match unit {
        "grains" => format!("{v:.0} grains"),
        "°" => format!("{v:.2}°"),
        "" => format!("{v:.3}"),
        u => format!("{v:.2} {u}"),
    }
}

fn summary(r: &RunReport) -> String {
    let mut lines: Vec<(String, String)> = vec![
        (
            "protocol".into(),
            format!(
                "{} ({}D, model {}, seed {}, {:?})",
                r.protocol, r.dimension, r.model, r.seed, r.rng
            ),
        ),
        ("outcome".into(), r.outcome.status().into()),
    ];
    if let Some(reason) = r.outcome.reason() {
        lines.push(("reason".into(), reason));
    }
    let declared = registry::find_protocol(&r.protocol)
        .map(|p| p.metrics())
        .unwrap_or_default();
    for m in declared {
        if let Some(v) = r.metric(m.name) {
            lines.push((
                m.label.into(),
                format!("{}   ({})", with_unit(v, m.unit), m.name),
            ));
        }
    }
    for (k, q) in r.theory.iter().enumerate() {
        let head = if k == 0 { "theory" } else { "" };
        lines.push((head.into(), format!("{} = {:.2}°", q.label, q.value)));
    }
    let g = r.grains;
    lines.push((
        "grains".into(),
        format!(
            "{} at start, {} added, {} lost, {} at end",
            g.initial, g.inserted, g.lost, g.remaining
        ),
    ));
    lines.push((
        "time".into(),
        format!(
            "{} steps of {:.3e} s = {:.3} s simulated in {:.2} s ({:.2} M particle-steps/s)",
            r.iterations,
            r.options.dt,
            r.simulated_time,
            r.wall_time,
            r.particle_steps_per_second / 1e6
        ),
    ));
    let c = &r.counters;
    if c.resting_steps > 0 {
        lines.push((
            "at rest".into(),
            format!(
                "{:.1} % of the particle-steps (grains put to rest: [rest])",
                100.0 * c.resting_steps as f64 / c.particle_steps.max(1) as f64
            ),
        ));
    }
    let mut options = format!(
        "preset {}, integrator {}",
        r.options.preset.as_deref().unwrap_or("none"),
        r.options.integrator
    );
    for (k, v) in &r.options.physics {
        options.push_str(&format!(", {} {v}", k.replace('_', " ")));
    }
    lines.push(("options".into(), options));
    let width = lines
        .iter()
        .map(|(h, _)| h.chars().count())
        .max()
        .unwrap_or(0)
        + 2;
    lines
        .into_iter()
        .map(|(h, text)| format!("{h:<width$}{text}\n"))
        .collect()
}

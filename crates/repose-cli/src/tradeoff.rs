//! `repose tradeoff`: runs a speed/accuracy study in this process (see
//! `repose_studies::tradeoff`): of Lee & Herrmann's pile, written to
//! `docs/speed-vs-accuracy.*`, or with `--study heap` of the 3D poured
//! heap, written to `docs/tradeoff-heap.*`.

use indicatif::{ProgressBar, ProgressStyle};
use repose_studies::tradeoff::{self, Config, Group, TradeoffError};
use std::path::PathBuf;
use std::process::ExitCode;

/// Which scene the study runs.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Study {
    /// Lee & Herrmann's tilted pile (θ_R and θ_T).
    Pile,
    /// Elekes & Parteli's poured heap (θ_r).
    Heap,
}

#[derive(clap::Args)]
pub struct TradeoffArgs {
    /// The scene studied.
    #[arg(long, value_enum, default_value = "pile")]
    study: Study,
    /// Seeds (samples) per setting.
    #[arg(long, default_value_t = 30)]
    seeds: u32,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    seed_base: u64,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// The Markdown report to write; its SVG plots and the per-sample CSV
    /// go beside it with the same stem (default: docs/speed-vs-accuracy.md,
    /// or docs/tradeoff-heap.md for the heap).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override a scene value in every setting (e.g. box.width=2 for a
    /// smaller, faster study).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Run only these groups (presets, knobs, paper); the reference always runs.
    #[arg(long, value_delimiter = ',')]
    only: Vec<Group>,
    /// Keep the samples already in the CSV beside --out (same setting
    /// name and seed, and the same scene as the setting now makes) and run
    /// only the others, e.g. after an interruption or after changing one
    /// setting (its rows run again).
    #[arg(long)]
    resume: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(args: TradeoffArgs) -> anyhow::Result<ExitCode> {
    if args.seeds == 0 {
        eprintln!("error: --seeds must be at least 1");
        return Ok(ExitCode::from(2));
    }
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from(match args.study {
            Study::Pile => "docs/speed-vs-accuracy.md",
            Study::Heap => "docs/tradeoff-heap.md",
        })
    });
    let config = Config {
        seeds: args.seeds,
        seed_base: args.seed_base,
        threads: args
            .threads
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        out: out.clone(),
        set: args.set.clone(),
        only: args.only.clone(),
        resume: args.resume,
    };
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(0);
        b.set_style(
            ProgressStyle::with_template(
                "[{elapsed_precise}] {bar:40} {pos}/{len} runs (eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    };
    let tick = |n: usize| {
        if n > 0 {
            bar.set_length(n as u64);
        } else {
            bar.inc(1);
        }
    };
    let written = match args.study {
        Study::Pile => tradeoff::run(&config, &tick).and_then(|r| {
            r.write()?;
            Ok(r.summary())
        }),
        Study::Heap => tradeoff::heap::run(&config, &tick).and_then(|r| {
            r.write()?;
            Ok(r.summary())
        }),
    };
    bar.finish_and_clear();
    match written {
        Ok(summary) => crate::emit(&summary)?,
        Err(TradeoffError::Scene { setting, error }) => {
            eprintln!("error: setting `{setting}` is not a valid scene");
            for f in &error.errors {
                eprintln!("  {}: {}", f.field, f.message);
            }
            return Ok(ExitCode::from(2));
        }
        Err(e) => return Err(e.into()),
    }
    eprintln!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

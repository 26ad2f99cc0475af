//! `repose tradeoff`: what each fidelity preset and each numerical knob
//! costs, and how far it moves θ_R and θ_T from the most accurate settings.
//!
//! Every setting runs the same tilt scene (μ = 0.2, W = H = 4; the tilt
//! protocol first releases the pile, so one run gives both θ_R and θ_T)
//! over the same seeds. Piles are chaotic, so a change of numerics gives a
//! different pile for the same seed: shifts are compared with their
//! standard error (Welch), never read off single runs.

use crate::chart::{Chart, Series, Style};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use repose_physics::measure::Stats;
use repose_physics::{Preset, Quiet, RunReport, Scene, ENGINE};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct TradeoffArgs {
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
    /// go beside it with the same stem.
    #[arg(long, default_value = "docs/speed-vs-accuracy.md")]
    out: PathBuf,
    /// Override a scene value in every setting (e.g. box.width=2 for a
    /// smaller, faster study).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Run only these groups (presets, knobs, paper); the reference always runs.
    #[arg(long, value_delimiter = ',')]
    only: Vec<Group>,
    /// Keep the samples already in the CSV beside --out (same setting
    /// name and seed) and run only the missing ones, e.g. after an
    /// interruption or after changing one setting (delete its rows first).
    #[arg(long)]
    resume: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Group {
    Reference,
    Presets,
    Knobs,
    Paper,
}

/// The scene every setting runs.
const BASE: &str = r#"
protocol = "tilt"
[contact]
mu = 0.2
[box]
width = 4.0
height = 4.0
"#;

/// The most accurate settings: Gear-5 at a quarter of the default step,
/// with twice the default equilibrium window.
const REFERENCE: [&str; 3] = [
    "numerics.integrator=gear5",
    "numerics.dt_factor=0.005",
    "equilibrium.hold=0.2",
];

/// The paper's θ_R at μ = 0.2 for its stiffness and damping sensitivities
/// (section 4): (key, value, mean, sd).
const PAPER_SENSITIVITY: [(&str, f64, f64, f64); 6] = [
    ("contact.k_n", 1e4, 16.53, 0.73),
    ("contact.k_n", 1e5, 18.65, 0.70),
    ("contact.k_n", 1e6, 17.99, 0.64),
    ("contact.gamma_n", 50.0, 16.47, 0.75),
    ("contact.gamma_n", 100.0, 17.15, 0.62),
    ("contact.gamma_n", 500.0, 17.99, 0.64),
];

/// The paper's θ_R by the three slope methods (400 grains, μ = 0.2, 10 samples).
const PAPER_METHODS: [(f64, f64); 3] = [(20.14, 2.15), (18.90, 1.49), (17.88, 1.76)];

/// The overlap guard for the softest grains of the sensitivity study.
const SOFT_MAX_OVERLAP: f64 = 1.5;

struct Case {
    group: Group,
    name: String,
    what: String,
    overrides: Vec<String>,
}

impl Case {
    fn new(group: Group, name: &str, what: &str, overrides: &[&str]) -> Self {
        Case {
            group,
            name: name.into(),
            what: what.into(),
            overrides: overrides.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// A knob: the reference with one setting changed.
    fn knob(name: &str, what: &str, setting: &str) -> Self {
        let key = setting.split('=').next().unwrap_or_default();
        let mut o: Vec<String> = REFERENCE
            .iter()
            .filter(|r| !r.starts_with(&format!("{key}=")))
            .map(|s| s.to_string())
            .collect();
        o.push(setting.into());
        Case {
            group: Group::Knobs,
            name: name.into(),
            what: what.into(),
            overrides: o,
        }
    }
}

fn cases() -> Vec<Case> {
    let mut v = vec![Case::new(
        Group::Reference,
        "reference",
        "Gear-5, dt = t_c/200, equilibrium window 0.2 s",
        &REFERENCE,
    )];
    for p in Preset::ALL {
        let setting = format!("preset={}", p.name());
        v.push(Case {
            group: Group::Presets,
            name: p.name().into(),
            what: p
                .settings()
                .iter()
                .map(|(k, val)| format!("{k} = {val}"))
                .collect::<Vec<_>>()
                .join(", "),
            overrides: vec![setting],
        });
    }
    v.extend([
        Case::knob(
            "Verlet",
            "velocity Verlet instead of Gear-5",
            "numerics.integrator=verlet",
        ),
        Case::knob("t_c/100", "dt = t_c/100", "numerics.dt_factor=0.01"),
        Case::knob(
            "t_c/50",
            "dt = t_c/50 (the default)",
            "numerics.dt_factor=0.02",
        ),
        Case::knob("t_c/25", "dt = t_c/25", "numerics.dt_factor=0.04"),
        Case::knob(
            "hold 0.1 s",
            "equilibrium window 0.1 s (the default)",
            "equilibrium.hold=0.1",
        ),
        Case::knob(
            "hold 0.05 s",
            "equilibrium window 0.05 s",
            "equilibrium.hold=0.05",
        ),
        Case::knob(
            "still 0.05 d",
            "a settled grain may move 0.05 diameters per window (default 0.02)",
            "equilibrium.max_displacement=0.05",
        ),
        Case::knob(
            "skin 0.02",
            "Verlet-list skin 0.02 cm (default 0.04)",
            "numerics.skin=0.02",
        ),
        Case::knob("skin 0.1", "Verlet-list skin 0.1 cm", "numerics.skin=0.1"),
        Case::knob(
            "truncated",
            "shear spring truncated at the Coulomb limit",
            "contact.shear_spring=truncated",
        ),
        Case::knob(
            "tilt 2°/s",
            "tilt rate 2°/s (default 10°/s)",
            "tilt.rate=2.0",
        ),
        Case::knob("tilt 50°/s", "tilt rate 50°/s", "tilt.rate=50.0"),
        Case::knob(
            "onset 5 %",
            "the pile moves once 5 % of its grains have (default 2 %)",
            "tilt.onset_fraction=0.05",
        ),
    ]);
    for (key, value, _, _) in PAPER_SENSITIVITY {
        // The defaults (k_n = 10⁶, γ_n = 500) are the `paper` preset's own runs.
        if (key == "contact.k_n" && value == 1e6) || (key == "contact.gamma_n" && value == 500.0) {
            continue;
        }
        let setting = format!("{key}={value}");
        let mut overrides = vec!["preset=paper".to_string(), setting.clone()];
        let mut what = format!("{key} = {value} at the paper preset");
        if key == "contact.k_n" && value < 1e6 {
            // Soft grains falling from the filling column overlap by more
            // than the default guard (half a radius) on impact.
            overrides.push(format!("numerics.max_overlap={SOFT_MAX_OVERLAP}"));
            what.push_str(&format!(", overlap guard {SOFT_MAX_OVERLAP} radius"));
        }
        v.push(Case {
            group: Group::Paper,
            name: setting,
            what,
            overrides,
        });
    }
    v
}

/// One sample's numbers.
#[derive(Debug, Clone)]
struct Sample {
    case: usize,
    seed: u64,
    status: String,
    reason: String,
    methods: Option<[f64; 3]>,
    tilt: Option<f64>,
    wall_time: f64,
    particle_steps: u64,
}

fn run_one(case: usize, scene: &Scene) -> Sample {
    let r: RunReport = repose_physics::run(scene, &mut Quiet).expect("validated scenes run");
    Sample {
        case,
        seed: scene.seed,
        status: r.outcome.status().to_string(),
        reason: r.outcome.reason().unwrap_or_default().to_string(),
        methods: r
            .repose
            .map(|a| [a.endpoints, a.line_fit, a.cumulative_fit]),
        tilt: r.tilt.map(|t| t.angle),
        wall_time: r.wall_time,
        particle_steps: r.particle_steps,
    }
}

/// What one setting measured.
struct Summary {
    repose: Option<Stats>,
    methods: [Option<Stats>; 3],
    tilt: Option<Stats>,
    wall_time: f64,
    particle_steps: f64,
    runs: usize,
    failed: Vec<String>,
}

fn summarise(samples: &[&Sample]) -> Summary {
    let of = |f: &dyn Fn(&Sample) -> Option<f64>| {
        let v: Vec<f64> = samples.iter().filter_map(|s| f(s)).collect();
        Stats::of(&v)
    };
    let n = samples.len().max(1) as f64;
    Summary {
        repose: of(&|s| s.methods.map(|m| m[2])),
        methods: [
            of(&|s| s.methods.map(|m| m[0])),
            of(&|s| s.methods.map(|m| m[1])),
            of(&|s| s.methods.map(|m| m[2])),
        ],
        tilt: of(&|s| s.tilt),
        wall_time: samples.iter().map(|s| s.wall_time).sum::<f64>() / n,
        particle_steps: samples.iter().map(|s| s.particle_steps as f64).sum::<f64>() / n,
        runs: samples.len(),
        failed: samples
            .iter()
            .filter(|s| s.status != "completed")
            .map(|s| format!("seed {}: {} ({})", s.seed, s.status, s.reason))
            .collect(),
    }
}

/// A shift from the reference with its standard error.
#[derive(Clone, Copy)]
struct Shift {
    delta: f64,
    se: f64,
}

impl Shift {
    fn between(a: Option<Stats>, reference: Option<Stats>) -> Option<Shift> {
        let (a, r) = (a?, reference?);
        Some(Shift {
            delta: a.mean - r.mean,
            se: (a.sem * a.sem + r.sem * r.sem).sqrt(),
        })
    }
    /// Beyond two standard errors counts as a real change of the answer.
    fn significant(self) -> bool {
        self.delta.abs() > 2.0 * self.se
    }
    fn cell(s: Option<Shift>) -> String {
        match s {
            Some(s) => format!("{:+.2} ± {:.2}", s.delta, s.se),
            None => "—".into(),
        }
    }
}

fn stats_cell(s: Option<Stats>) -> String {
    match s {
        Some(s) => format!("{:.2} ± {:.2} (n={})", s.mean, s.sd, s.n),
        None => "—".into(),
    }
}

pub fn run(args: TradeoffArgs) -> anyhow::Result<ExitCode> {
    if args.seeds == 0 {
        anyhow::bail!("--seeds must be at least 1");
    }
    let all = cases();
    let chosen: Vec<usize> = (0..all.len())
        .filter(|&k| {
            all[k].group == Group::Reference
                || args.only.is_empty()
                || args.only.contains(&all[k].group)
        })
        .collect();

    // Build and validate every scene before running anything.
    let mut jobs: Vec<(usize, Scene)> = Vec::new();
    for &k in &chosen {
        for s in 0..args.seeds as u64 {
            let mut o = args.set.clone();
            o.extend(all[k].overrides.iter().cloned());
            o.push(format!("seed={}", args.seed_base + s));
            let scene = match Scene::from_toml(BASE, &o) {
                Ok(sc) => sc.resolved(),
                Err(e) => {
                    eprintln!("error: setting `{}` is not a valid scene", all[k].name);
                    for f in &e.errors {
                        eprintln!("  {}: {}", f.field, f.message);
                    }
                    return Ok(ExitCode::from(2));
                }
            };
            jobs.push((k, scene));
        }
    }
    let first = jobs[0].1.clone();
    let mut kept: Vec<Sample> = Vec::new();
    if args.resume {
        let csv = args.out.with_extension("csv");
        if let Ok(text) = std::fs::read_to_string(&csv) {
            for line in text.lines().skip(1) {
                if let Some(s) = parse_row(line, &all) {
                    if jobs.iter().any(|(k, sc)| *k == s.case && sc.seed == s.seed) {
                        kept.push(s);
                    }
                }
            }
        }
        jobs.retain(|(k, sc)| !kept.iter().any(|s| s.case == *k && s.seed == sc.seed));
        eprintln!(
            "resuming: {} samples kept from {}, {} to run",
            kept.len(),
            csv.display(),
            jobs.len()
        );
    }
    // Seed by seed, every setting in turn: anything else running on the
    // machine slows all settings alike, so the cost ratios stay fair.
    jobs.sort_by_key(|(k, scene)| (scene.seed, *k));

    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start the worker threads")?;
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(jobs.len() as u64);
        b.set_style(
            ProgressStyle::with_template(
                "[{elapsed_precise}] {bar:40} {pos}/{len} runs (eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    };
    let clock = std::time::Instant::now();
    let box_size = format!("{} × {}", first.container.width, first.container.height);
    let grains = first.grain_count();
    let mut samples: Vec<Sample> = pool.install(|| {
        jobs.par_iter()
            .map(|(k, scene)| {
                let s = run_one(*k, scene);
                bar.inc(1);
                s
            })
            .collect()
    });
    bar.finish_and_clear();
    let elapsed = clock.elapsed().as_secs_f64();
    let fresh = samples.len();
    samples.extend(kept);
    samples.sort_by_key(|s| (s.case, s.seed));

    let summaries: Vec<Option<Summary>> = (0..all.len())
        .map(|k| {
            let mine: Vec<&Sample> = samples.iter().filter(|s| s.case == k).collect();
            (!mine.is_empty()).then(|| summarise(&mine))
        })
        .collect();
    let report = Report {
        cases: &all,
        summaries: &summaries,
        args: &args,
        threads,
        elapsed,
        runs: samples.len(),
        box_size,
        grains,
        fresh,
    };
    write_outputs(&args.out, &report, &samples)?;
    print!("{}", report.console());
    eprintln!("wrote {}", args.out.display());
    Ok(ExitCode::SUCCESS)
}

struct Report<'a> {
    cases: &'a [Case],
    summaries: &'a [Option<Summary>],
    args: &'a TradeoffArgs,
    threads: usize,
    elapsed: f64,
    runs: usize,
    box_size: String,
    grains: usize,
    /// Runs made now (the rest came from an earlier run's CSV).
    fresh: usize,
}

impl Report<'_> {
    fn reference(&self) -> &Summary {
        self.summaries[0]
            .as_ref()
            .expect("the reference always runs")
    }

    fn rows(&self, group: Group) -> impl Iterator<Item = (&Case, &Summary)> {
        self.cases
            .iter()
            .zip(self.summaries)
            .filter(move |(c, s)| c.group == group && s.is_some())
            .map(|(c, s)| (c, s.as_ref().unwrap()))
    }

    fn find(&self, name: &str) -> Option<&Summary> {
        self.cases
            .iter()
            .zip(self.summaries)
            .find(|(c, _)| c.name == name)
            .and_then(|(_, s)| s.as_ref())
    }

    /// The presets and knobs table.
    fn table(&self, group: Group) -> String {
        let r = self.reference();
        let mut s = String::from(
            "| setting | what | wall time | particle-steps | θ_R (°) | Δθ_R | θ_T (°) | Δθ_T | failed | verdict |\n|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for (c, m) in std::iter::once((&self.cases[0], r)).chain(self.rows(group)) {
            let dr = Shift::between(m.repose, r.repose);
            let dt = Shift::between(m.tilt, r.tilt);
            let verdict = if c.group == Group::Reference {
                "reference".to_string()
            } else {
                verdict(dr, dt)
            };
            let _ = writeln!(
                s,
                "| {} | {} | {:.2}× ({:.2} s) | {:.2}× | {} | {} | {} | {} | {}/{} | {} |",
                c.name,
                c.what,
                m.wall_time / r.wall_time,
                m.wall_time,
                m.particle_steps / r.particle_steps,
                stats_cell(m.repose),
                Shift::cell(dr),
                stats_cell(m.tilt),
                Shift::cell(dt),
                m.failed.len(),
                m.runs,
                verdict
            );
        }
        s
    }

    fn shifting(&self, group: Group) -> Vec<String> {
        let r = self.reference();
        self.rows(group)
            .filter(|(_, m)| {
                Shift::between(m.repose, r.repose).is_some_and(Shift::significant)
                    || Shift::between(m.tilt, r.tilt).is_some_and(Shift::significant)
            })
            .map(|(c, _)| format!("`{}`", c.name))
            .collect()
    }

    fn chart(&self, tilt: bool) -> Chart {
        let r = self.reference();
        let (title, y) = if tilt {
            ("Shift of θ_T from the reference", "Δθ_T (°)")
        } else {
            ("Shift of θ_R from the reference", "Δθ_R (°)")
        };
        let mut chart = Chart::new(title, "wall time relative to the reference", y);
        chart.log_x = true;
        chart.y_rule = Some(0.0);
        for (group, name) in [(Group::Presets, "presets"), (Group::Knobs, "knobs")] {
            let mut series = Series::new(name, Style::Points);
            for (c, m) in self.rows(group) {
                let shift = if tilt {
                    Shift::between(m.tilt, r.tilt)
                } else {
                    Shift::between(m.repose, r.repose)
                };
                // Settings that leave the angle bit-identical (the skin for
                // both angles, the tilt knobs for θ_R) have nothing to show.
                if let Some(sh) = shift.filter(|sh| sh.delta != 0.0) {
                    series = series.labelled(m.wall_time / r.wall_time, sh.delta, sh.se, &c.name);
                }
            }
            chart.series.push(series);
        }
        chart
    }

    fn markdown(&self, stem: &str) -> String {
        let r = self.reference();
        let mut s = String::new();
        let _ = writeln!(s, "# Speed against accuracy\n");
        let _ = writeln!(
            s,
            "Generated by `repose tradeoff --seeds {}{}` (engine {ENGINE}): {} runs on {} threads of a {}-core machine{}. \
             Every setting runs the tilt scene at μ = 0.2 in a {} box ({} grains) over seeds {}–{}. \
             The tilt protocol releases the pile first, so each run gives θ_R (method 3) and then θ_T. \
             Piles are chaotic: any change of numerics gives a different pile for the same seed. \
             A shift is therefore the difference of two means with its standard error, \
             √(sem² + sem_ref²). A setting **changes the answer** when a shift exceeds two standard errors.\n",
            self.args.seeds,
            if self.args.set.is_empty() {
                String::new()
            } else {
                format!(" --set {}", self.args.set.join(" --set "))
            },
            self.runs,
            self.threads,
            cores(),
            if self.fresh == self.runs {
                format!(" in {:.0} s", self.elapsed)
            } else {
                format!(
                    " ({} of them in a resumed run of {:.0} s, the others kept from the previous run's CSV)",
                    self.fresh, self.elapsed
                )
            },
            self.box_size,
            self.grains,
            self.args.seed_base,
            self.args.seed_base + self.args.seeds as u64 - 1,
        );
        let _ = writeln!(
            s,
            "Cost is the mean wall time of a sample relative to the reference (both measured in the same run, so the ratio holds across machines) \
             and the mean number of particle-steps (grains × steps), which does not depend on the machine at all. \
             Cells are mean ± sd (n completed runs); shifts are Δ ± standard error.\n"
        );
        let _ = writeln!(
            s,
            "The reference: {} — θ_R = {}, θ_T = {}, {:.2} s and {:.3e} particle-steps a sample.\n",
            self.cases[0].what,
            stats_cell(r.repose),
            stats_cell(r.tilt),
            r.wall_time,
            r.particle_steps
        );
        if self.rows(Group::Presets).next().is_some() {
            let _ = writeln!(s, "## Presets\n");
            let _ = writeln!(
                s,
                "A sweep's `fidelity` (or `repose run --preset`) names one of these; the resolved scene stored with every result carries the preset's name and each concrete value.\n"
            );
            s.push_str(&self.table(Group::Presets));
            let shifting = self.shifting(Group::Presets);
            let _ = writeln!(
                s,
                "\n{}\n",
                if shifting.is_empty() {
                    "**No preset changes θ_R or θ_T beyond two standard errors of the reference.**"
                        .to_string()
                } else {
                    format!(
                        "**Presets that change the answer beyond two standard errors: {}.** The others agree with the reference within their error.",
                        shifting.join(", ")
                    )
                }
            );
        }
        if self.rows(Group::Knobs).next().is_some() {
            let _ = writeln!(s, "## Each knob on its own\n");
            let _ = writeln!(s, "Each row is the reference with one setting changed.\n");
            s.push_str(&self.table(Group::Knobs));
            let shifting = self.shifting(Group::Knobs);
            let _ = writeln!(
                s,
                "\n{}\n",
                if shifting.is_empty() {
                    "No single knob moves θ_R or θ_T beyond two standard errors.".to_string()
                } else {
                    format!(
                        "Knobs that move θ_R or θ_T beyond two standard errors: {}.",
                        shifting.join(", ")
                    )
                }
            );
        }
        let _ = writeln!(
            s,
            "![shift of θ_R against cost]({stem}-repose.svg)\n\n![shift of θ_T against cost]({stem}-tilt.svg)\n\n\
             Settings that leave an angle bit-identical are not drawn: the Verlet-list skin changes only the cost, and the tilt knobs only θ_T.\n"
        );

        // Samples per point: the error bar from the reference's scatter.
        if let (Some(rr), Some(rt)) = (r.repose, r.tilt) {
            let _ = writeln!(s, "## Samples per point\n");
            let _ = writeln!(
                s,
                "The error of a point's mean falls as sd/√n while its cost grows as n. With the reference's scatter (sd θ_R = {:.2}°, sd θ_T = {:.2}°):\n",
                rr.sd, rt.sd
            );
            s.push_str("| samples | sem θ_R (°) | sem θ_T (°) | cost |\n|---|---|---|---|\n");
            for n in [5u32, 10, 20, 40, 80] {
                let q = (n as f64).sqrt();
                let _ = writeln!(
                    s,
                    "| {n} | {:.2} | {:.2} | {n}× a sample |",
                    rr.sd / q,
                    rt.sd / q
                );
            }
            s.push('\n');
        }

        if self.rows(Group::Paper).next().is_some() {
            let paper_preset = self.find("paper");
            let _ = writeln!(s, "## The paper's sensitivities (θ_R at μ = 0.2)\n");
            let _ = writeln!(
                s,
                "Lee & Herrmann report θ_R for three stiffnesses and three dampings (section 4). Ours run at the `paper` preset; γ_s stays γ_n/100. \
                 The last column is the difference in units of the combined standard error (ours sem and the paper's sd/√20).\n"
            );
            s.push_str("| setting | paper | ours | difference | shift from the default: paper | shift: ours | wall time |\n|---|---|---|---|---|---|---|\n");
            let default_mean = paper_preset.and_then(|p| p.repose);
            for (key, value, mean, sd) in PAPER_SENSITIVITY {
                let name = format!("{key}={value}");
                let ours = if (key == "contact.k_n" && value == 1e6)
                    || (key == "contact.gamma_n" && value == 500.0)
                {
                    paper_preset
                } else {
                    self.find(&name)
                };
                let Some(o) = ours else { continue };
                let diff = o.repose.map(|st| {
                    let se = (st.sem * st.sem + sd * sd / 20.0).sqrt();
                    format!("{:+.1}σ", (st.mean - mean) / se)
                });
                // The paper's default (k_n = 10⁶, γ_n = 500) is 17.99 ± 0.64.
                let paper_shift = mean - 17.99;
                let our_shift = match (o.repose, default_mean) {
                    (Some(a), Some(d)) => {
                        let se = if std::ptr::eq(o, paper_preset.unwrap()) {
                            0.0
                        } else {
                            (a.sem * a.sem + d.sem * d.sem).sqrt()
                        };
                        format!("{:+.2} ± {se:.2}", a.mean - d.mean)
                    }
                    _ => "—".into(),
                };
                let _ = writeln!(
                    s,
                    "| {key} = {value:e} | {mean:.2} ± {sd:.2} | {} | {} | {paper_shift:+.2} | {our_shift} | {:.2} s |",
                    stats_cell(o.repose),
                    diff.unwrap_or_else(|| "—".into()),
                    o.wall_time
                );
            }
            let _ = writeln!(
                s,
                "\nThe stiffness study raises the overlap guard to {SOFT_MAX_OVERLAP} radii for k_n < 10⁶: softer grains landing from the filling column overlap by more than the default half radius, and the guard fails the run otherwise."
            );
            s.push('\n');
        }

        let _ = writeln!(s, "## The three slope methods\n");
        let _ = writeln!(
            s,
            "The paper's values come from 10 samples of a 400-grain pile at μ = 0.2: (1) joins h(0) and h(W), (2) fits a line to h(x), (3) fits a parabola to the cumulative sum of h.\n"
        );
        let names: Vec<&str> = ["reference", "quick", "standard", "paper"]
            .into_iter()
            .filter(|n| self.find(n).is_some())
            .collect();
        let _ = write!(s, "| method | paper |");
        for n in &names {
            let _ = write!(s, " {n} |");
        }
        let _ = write!(s, "\n|---|---|");
        for _ in &names {
            s.push_str("---|");
        }
        s.push('\n');
        for (m, (pm, psd)) in PAPER_METHODS.iter().enumerate() {
            let _ = write!(s, "| ({}) | {pm:.2} ± {psd:.2} |", m + 1);
            for n in &names {
                let _ = write!(
                    s,
                    " {} |",
                    stats_cell(self.find(n).and_then(|x| x.methods[m]))
                );
            }
            s.push('\n');
        }
        s.push('\n');

        let failures: Vec<String> = self
            .cases
            .iter()
            .zip(self.summaries)
            .filter_map(|(c, m)| m.as_ref().map(|m| (c, m)))
            .flat_map(|(c, m)| m.failed.iter().map(move |f| format!("- `{}` {f}", c.name)))
            .collect();
        let _ = writeln!(s, "## Runs without a result\n");
        if failures.is_empty() {
            let _ = writeln!(s, "Every run completed.\n");
        } else {
            let _ = writeln!(
                s,
                "These runs recorded an outcome other than `completed` and are left out of the means above:\n"
            );
            for f in failures {
                let _ = writeln!(s, "{f}");
            }
            s.push('\n');
        }
        let _ = writeln!(
            s,
            "Every sample is in [`{stem}.csv`]({stem}.csv). Regenerate this page with `repose tradeoff`."
        );
        s
    }

    fn console(&self) -> String {
        let r = self.reference();
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{:<16} {:>7} {:>8} {:>22} {:>15} {:>22} {:>15}",
            "setting", "time×", "steps×", "θ_R", "Δθ_R", "θ_T", "Δθ_T"
        );
        for (c, m) in self.cases.iter().zip(self.summaries) {
            let Some(m) = m else { continue };
            let _ = writeln!(
                s,
                "{:<16} {:>7.2} {:>8.2} {:>22} {:>15} {:>22} {:>15}",
                c.name,
                m.wall_time / r.wall_time,
                m.particle_steps / r.particle_steps,
                stats_cell(m.repose),
                Shift::cell(Shift::between(m.repose, r.repose)),
                stats_cell(m.tilt),
                Shift::cell(Shift::between(m.tilt, r.tilt)),
            );
        }
        s
    }
}

fn verdict(dr: Option<Shift>, dt: Option<Shift>) -> String {
    match (dr, dt) {
        (None, _) | (_, None) => "no result".into(),
        (Some(a), Some(b)) => match (a.significant(), b.significant()) {
            (false, false) => "within error".into(),
            (true, false) => "**shifts θ_R**".into(),
            (false, true) => "**shifts θ_T**".into(),
            (true, true) => "**shifts θ_R and θ_T**".into(),
        },
    }
}

/// Reads one row of the per-sample CSV back (see [`write_outputs`]).
fn parse_row(line: &str, cases: &[Case]) -> Option<Sample> {
    let f: Vec<&str> = line.splitn(11, ',').collect();
    if f.len() < 11 {
        return None;
    }
    let case = cases.iter().position(|c| c.name == f[0])?;
    let num = |s: &str| s.parse::<f64>().ok();
    let methods = match (num(f[4]), num(f[5]), num(f[6])) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    Some(Sample {
        case,
        seed: f[2].parse().ok()?,
        status: f[3].to_string(),
        reason: f[10].trim_matches('"').to_string(),
        methods,
        tilt: num(f[7]),
        wall_time: num(f[8])?,
        particle_steps: f[9].parse().ok()?,
    })
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

fn write_outputs(out: &Path, report: &Report, samples: &[Sample]) -> anyhow::Result<()> {
    let dir = out.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(d) = dir {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    let stem = out
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("speed-vs-accuracy")
        .to_string();
    let beside = |suffix: &str| out.with_file_name(format!("{stem}{suffix}"));
    let write = |path: PathBuf, text: String| {
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))
    };
    write(out.to_path_buf(), report.markdown(&stem))?;
    write(beside("-repose.svg"), report.chart(false).svg())?;
    write(beside("-tilt.svg"), report.chart(true).svg())?;
    let mut csv = String::from(
        "setting,group,seed,status,theta_r_method1,theta_r_method2,theta_r_method3,theta_t,wall_time_s,particle_steps,reason\n",
    );
    let num = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.4}"));
    for smp in samples {
        let c = &report.cases[smp.case];
        let m = smp.methods;
        let _ = writeln!(
            csv,
            "{},{:?},{},{},{},{},{},{},{:.4},{},\"{}\"",
            c.name,
            c.group,
            smp.seed,
            smp.status,
            num(m.map(|m| m[0])),
            num(m.map(|m| m[1])),
            num(m.map(|m| m[2])),
            num(smp.tilt),
            smp.wall_time,
            smp.particle_steps,
            smp.reason.replace('"', "'")
        );
    }
    write(beside(".csv"), csv)?;
    Ok(())
}

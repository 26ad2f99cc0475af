//! The speed/accuracy study: what each fidelity preset and each numerical
//! knob costs, and how far it moves θ_R and θ_T from the most accurate
//! settings (`repose tradeoff`, written up in `docs/speed-vs-accuracy.md`).
//!
//! Every setting runs the same tilt scene (μ = 0.2, W = H = 4; the tilt
//! protocol first releases the pile, so one run gives both θ_R and θ_T)
//! over the same seeds. Piles are chaotic, so a change of numerics gives a
//! different pile for the same seed: shifts are compared with their
//! standard error (Welch), never read off single runs. The same study of
//! the 3D poured heap is in [`heap`].

pub mod heap;
mod tally;

use crate::chart::Chart;
use rayon::prelude::*;
use repose_physics::measure::Stats;
use repose_physics::{registry, Preset, Scene, SceneError, ENGINE};
use repose_sweeps::spec::sample_hash;
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use tally::{costed, failure_lines, shift_chart, stats_over, Costed, Ran, Tally};

/// What to run and where to write it.
#[derive(Debug, Clone)]
pub struct Config {
    /// Seeds (samples) per setting.
    pub seeds: u32,
    /// First seed.
    pub seed_base: u64,
    /// Worker threads.
    pub threads: usize,
    /// The Markdown report; its SVG plots and the per-sample CSV go beside
    /// it with the same stem.
    pub out: PathBuf,
    /// Scene overrides applied to every setting.
    pub set: Vec<String>,
    /// Groups to run (all if empty); the reference always runs.
    pub only: Vec<Group>,
    /// Keep the samples already in the CSV beside `out` and run only the missing ones.
    pub resume: bool,
}

/// Why the study cannot run.
#[derive(Debug, thiserror::Error)]
pub enum TradeoffError {
    #[error("setting `{setting}` is not a valid scene: {error}")]
    Scene { setting: String, error: SceneError },
    #[error("cannot start the worker threads: {0}")]
    Threads(String),
    #[error("cannot write {path}: {error}")]
    Write { path: String, error: std::io::Error },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Group {
    #[serde(alias = "Reference")]
    Reference,
    #[serde(alias = "Presets")]
    Presets,
    #[serde(alias = "Knobs")]
    Knobs,
    #[serde(alias = "Paper")]
    Paper,
}

impl std::str::FromStr for Group {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "reference" => Ok(Group::Reference),
            "presets" => Ok(Group::Presets),
            "knobs" => Ok(Group::Knobs),
            "paper" => Ok(Group::Paper),
            other => Err(format!(
                "unknown group `{other}` (reference, presets, knobs or paper)"
            )),
        }
    }
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

pub(crate) struct Case {
    pub group: Group,
    pub name: String,
    pub what: String,
    pub overrides: Vec<String>,
}

impl Case {
    pub(crate) fn new(group: Group, name: &str, what: &str, overrides: &[&str]) -> Self {
        Case {
            group,
            name: name.into(),
            what: what.into(),
            overrides: overrides.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// A knob: the reference with one setting changed.
    fn knob(name: &str, what: &str, setting: &str) -> Self {
        Case::knob_over(&REFERENCE, name, what, &[setting])
    }

    /// A knob of a study: its `reference` overrides with the keys of
    /// `settings` replaced by them.
    pub(crate) fn knob_over(reference: &[&str], name: &str, what: &str, settings: &[&str]) -> Self {
        let keys: Vec<&str> = settings
            .iter()
            .filter_map(|s| s.split('=').next())
            .collect();
        let mut o: Vec<String> = reference
            .iter()
            .filter(|r| !keys.iter().any(|k| r.starts_with(&format!("{k}="))))
            .map(|s| s.to_string())
            .collect();
        o.extend(settings.iter().map(|s| s.to_string()));
        Case {
            group: Group::Knobs,
            name: name.into(),
            what: what.into(),
            overrides: o,
        }
    }
}

/// A study's first cases: the reference (`what` it is, the `reference`
/// settings), then one case per fidelity preset, described by what it
/// sets in `protocol`.
pub(crate) fn reference_and_presets(protocol: &str, what: &str, reference: &[&str]) -> Vec<Case> {
    let found = registry::find_protocol(protocol);
    let presets = Preset::ALL.into_iter().map(|p| Case {
        group: Group::Presets,
        name: p.name().into(),
        what: found.map(|f| f.preset_line(p)).unwrap_or_default(),
        overrides: vec![format!("preset={}", p.name())],
    });
    std::iter::once(Case::new(Group::Reference, "reference", what, reference))
        .chain(presets)
        .collect()
}

fn cases() -> Vec<Case> {
    let mut v = reference_and_presets(
        "tilt",
        "Gear-5, dt = t_c/200, equilibrium window 0.2 s",
        &REFERENCE,
    );
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

/// One sample's numbers: a row of the per-sample CSV.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Sample {
    setting: String,
    group: Group,
    seed: u64,
    status: String,
    theta_r_method1: Option<f64>,
    theta_r_method2: Option<f64>,
    theta_r_method3: Option<f64>,
    theta_t: Option<f64>,
    wall_time_s: f64,
    particle_steps: u64,
    reason: String,
    /// The identity of the scene that ran (empty in older CSVs).
    #[serde(default)]
    scene: String,
}

costed!(Sample);

fn run_one(case: &Case, scene: &Scene) -> Sample {
    let ran = Ran::of(scene);
    Sample {
        setting: case.name.clone(),
        group: case.group,
        seed: scene.seed,
        theta_r_method1: ran.metric("theta_r_endpoints"),
        theta_r_method2: ran.metric("theta_r_line"),
        theta_r_method3: ran.metric("theta_r"),
        theta_t: ran.metric("theta_t"),
        wall_time_s: ran.wall_time,
        particle_steps: ran.particle_steps,
        status: ran.status,
        reason: ran.reason,
        scene: sample_hash(scene),
    }
}

/// What one setting measured.
struct Summary {
    repose: Option<Stats>,
    methods: [Option<Stats>; 3],
    tilt: Option<Stats>,
    cost: Tally,
}

fn summarise(samples: &[&Sample]) -> Summary {
    Summary {
        repose: stats_over(samples, |s| s.theta_r_method3),
        methods: [
            stats_over(samples, |s| s.theta_r_method1),
            stats_over(samples, |s| s.theta_r_method2),
            stats_over(samples, |s| s.theta_r_method3),
        ],
        tilt: stats_over(samples, |s| s.theta_t),
        cost: Tally::of(samples),
    }
}

/// A shift from the reference with its standard error.
#[derive(Clone, Copy)]
pub(crate) struct Shift {
    pub delta: f64,
    pub se: f64,
}

impl Shift {
    pub(crate) fn between(a: Option<Stats>, reference: Option<Stats>) -> Option<Shift> {
        let (a, r) = (a?, reference?);
        Some(Shift {
            delta: a.mean - r.mean,
            se: (a.sem * a.sem + r.sem * r.sem).sqrt(),
        })
    }
    /// Beyond two standard errors counts as a real change of the answer.
    pub(crate) fn significant(self) -> bool {
        self.delta.abs() > 2.0 * self.se
    }
    pub(crate) fn cell(s: Option<Shift>) -> String {
        match s {
            Some(s) => format!("{:+.2} ± {:.2}", s.delta, s.se),
            None => "—".into(),
        }
    }
}

pub(crate) fn stats_cell(s: Option<Stats>) -> String {
    match s {
        Some(s) => format!("{:.2} ± {:.2} (n={})", s.mean, s.sd, s.n),
        None => "—".into(),
    }
}

/// Builds and validates every scene before anything runs: `(case, scene)`.
pub(crate) fn plan(
    config: &Config,
    all: &[Case],
    base: &str,
) -> Result<Vec<(usize, Scene)>, TradeoffError> {
    let mut jobs = Vec::new();
    for (k, case) in all.iter().enumerate() {
        let wanted = case.group == Group::Reference
            || config.only.is_empty()
            || config.only.contains(&case.group);
        if !wanted {
            continue;
        }
        for s in 0..config.seeds as u64 {
            let mut o = config.set.clone();
            o.extend(case.overrides.iter().cloned());
            o.push(format!("seed={}", config.seed_base + s));
            let scene = Scene::from_toml(base, &o).map_err(|error| TradeoffError::Scene {
                setting: case.name.clone(),
                error,
            })?;
            jobs.push((k, scene.resolved()));
        }
    }
    Ok(jobs)
}

/// The samples of a study, each setting's summary, and what running them
/// took.
pub(crate) struct Gathered<S, M> {
    /// Every sample, in setting then seed order.
    pub samples: Vec<S>,
    /// Each setting's summary, in the settings' order (`None` for a
    /// setting that did not run).
    pub summaries: Vec<Option<M>>,
    /// How many samples ran now (the rest were kept from the CSV).
    pub fresh: usize,
    /// How many of those are another setting's run of the same scene.
    pub shared: usize,
    pub elapsed: f64,
}

/// Plans every setting over the seeds, keeps the samples of the CSV beside
/// `--out` with `--resume`, runs the rest with `one`, orders them all and
/// summarises each setting's with `summarise`.
pub(crate) fn gather<S: Costed + serde::de::DeserializeOwned + Send, M>(
    config: &Config,
    all: &[Case],
    base: &str,
    tick: &(dyn Fn(usize) + Sync),
    one: impl Fn(&Case, &Scene) -> S + Sync,
    summarise: impl Fn(&[&S]) -> M,
) -> Result<Gathered<S, M>, TradeoffError> {
    let mut jobs = plan(config, all, base)?;
    let names: Vec<String> = all.iter().map(|c| c.name.clone()).collect();
    let kept: Vec<S> = if config.resume {
        kept(&config.out.with_extension("csv"), &names, &jobs)
    } else {
        Vec::new()
    };
    jobs.retain(|(k, sc)| {
        !kept
            .iter()
            .any(|s| (s.setting(), s.seed()) == (all[*k].name.as_str(), sc.seed))
    });
    let twins = twins(&mut jobs);
    let (mut samples, elapsed) = run_jobs(config, &mut jobs, tick, |k, scene| one(&all[k], scene))?;
    let copies: Vec<S> = twins
        .iter()
        .filter_map(|(k, seed, of, scene)| {
            let ran = samples
                .iter()
                .find(|s| s.setting() == all[*of].name && s.seed() == *seed)?;
            Some(ran.renamed(&all[*k]).with_scene(scene.clone()))
        })
        .collect();
    let shared = copies.len();
    samples.extend(copies);
    let fresh = samples.len();
    samples.extend(kept);
    let index = |s: &S| all.iter().position(|c| c.name == s.setting()).unwrap_or(0);
    samples.sort_by_key(|s| (index(s), s.seed()));
    let summaries = all
        .iter()
        .map(|c| {
            let mine: Vec<&S> = samples.iter().filter(|s| s.setting() == c.name).collect();
            (!mine.is_empty()).then(|| summarise(&mine))
        })
        .collect();
    Ok(Gathered {
        samples,
        summaries,
        fresh,
        shared,
        elapsed,
    })
}

/// Takes out of `jobs` every scene that an earlier job runs too (two
/// settings that resolve to one scene, as presets that set the same
/// numerics, or a knob that sets a default): each scene runs once, and the
/// twin's sample is the first one's filed under its own setting. Returns
/// the twins as (setting, seed, setting that runs it, the twin's own scene
/// identity).
fn twins(jobs: &mut Vec<(usize, Scene)>) -> Vec<(usize, u64, usize, String)> {
    let mut seen: Vec<(String, usize)> = Vec::new();
    let mut twins = Vec::new();
    jobs.retain(|(k, scene)| {
        let key = numbers_of(scene);
        match seen.iter().find(|(s, _)| *s == key) {
            Some((_, of)) => {
                twins.push((*k, scene.seed, *of, sample_hash(scene)));
                false
            }
            None => {
                seen.push((key, *k));
                true
            }
        }
    });
    twins
}

/// What decides a resolved scene's numbers, as text: its canonical form
/// (the sample's identity, which leaves out the thread count) without the
/// name of the preset that filled it in, whose settings are in the scene.
fn numbers_of(scene: &Scene) -> String {
    let mut v = repose_sweeps::spec::canonical(scene);
    if let Some(scene) = v.as_object_mut() {
        scene.remove("preset");
    }
    v.to_string()
}

/// The samples of an earlier run's CSV for settings and seeds still
/// planned whose setting still resolves to the scene that made them (a
/// setting changed since runs again). A row written before rows carried
/// their scene is taken to be its planned scene's, and carries it from now
/// on.
pub(crate) fn kept<S: Costed + serde::de::DeserializeOwned>(
    csv: &Path,
    names: &[String],
    jobs: &[(usize, Scene)],
) -> Vec<S> {
    let Ok(mut reader) = csv::Reader::from_path(csv) else {
        return Vec::new();
    };
    reader
        .deserialize::<S>()
        .filter_map(Result::ok)
        .filter_map(|s| {
            let (_, planned) = jobs
                .iter()
                .find(|(k, sc)| names[*k] == s.setting() && sc.seed == s.seed())?;
            let hash = sample_hash(planned);
            match s.scene() {
                "" => Some(s.with_scene(hash)),
                made if made == hash => Some(s),
                _ => None,
            }
        })
        .collect()
}

/// Runs every job on `config.threads` threads, seed by seed and every
/// setting in turn (anything else running on the machine then slows all
/// settings alike, so the cost ratios stay fair); returns the samples and
/// the wall time. `tick` as for [`run`].
pub(crate) fn run_jobs<S: Send>(
    config: &Config,
    jobs: &mut [(usize, Scene)],
    tick: &(dyn Fn(usize) + Sync),
    one: impl Fn(usize, &Scene) -> S + Sync,
) -> Result<(Vec<S>, f64), TradeoffError> {
    jobs.sort_by_key(|(k, scene)| (scene.seed, *k));
    tick(jobs.len());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(config.threads)
        .build()
        .map_err(|e| TradeoffError::Threads(e.to_string()))?;
    let clock = std::time::Instant::now();
    let samples = pool.install(|| {
        jobs.par_iter()
            .map(|(k, scene)| {
                let s = one(*k, scene);
                tick(0);
                s
            })
            .collect()
    });
    Ok((samples, clock.elapsed().as_secs_f64()))
}

/// Writes a study's Markdown report at `out` (made by `markdown` from the
/// file stem, `default_stem` if `out` has none), its charts beside it (the
/// stem and each suffix) and its per-sample CSV.
pub(crate) fn write_files<S: Serialize>(
    out: &Path,
    default_stem: &str,
    markdown: impl FnOnce(&str) -> String,
    charts: Vec<(&str, Chart)>,
    samples: &[S],
) -> Result<(), TradeoffError> {
    let io = |path: &Path| {
        let path = path.display().to_string();
        move |error| TradeoffError::Write { path, error }
    };
    if let Some(d) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(io(d))?;
    }
    let stem = out
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(default_stem)
        .to_string();
    let beside = |suffix: &str| out.with_file_name(format!("{stem}{suffix}"));
    let write = |path: PathBuf, text: String| std::fs::write(&path, text).map_err(io(&path));
    write(out.to_path_buf(), markdown(&stem))?;
    for (suffix, chart) in charts {
        write(beside(suffix), chart.svg())?;
    }
    write_csv(&beside(".csv"), samples)
}

/// Writes the samples as CSV.
pub(crate) fn write_csv<S: Serialize>(path: &Path, samples: &[S]) -> Result<(), TradeoffError> {
    let err = |error: std::io::Error| TradeoffError::Write {
        path: path.display().to_string(),
        error,
    };
    let mut w = csv::Writer::from_path(path).map_err(|e| err(e.into()))?;
    for s in samples {
        w.serialize(s).map_err(|e| err(e.into()))?;
    }
    w.flush().map_err(err)
}

/// Runs the study (each setting over the same seeds, on `config.threads`
/// threads) and returns its report. `tick(n)` is called once with the
/// number of runs to make, then with 0 after each run.
pub fn run(config: &Config, tick: &(dyn Fn(usize) + Sync)) -> Result<Report, TradeoffError> {
    let all = cases();
    let Gathered {
        samples,
        summaries,
        fresh,
        elapsed,
        ..
    } = gather(config, &all, BASE, tick, run_one, summarise)?;
    let base = Scene::from_toml(BASE, &config.set)
        .map_err(|error| TradeoffError::Scene {
            setting: "base".into(),
            error,
        })?
        .resolved();
    let cell = base.sections.value("box").unwrap_or_default();
    Ok(Report {
        cases: all,
        summaries,
        config: config.clone(),
        elapsed,
        runs: samples.len(),
        box_size: format!("{} × {}", cell["width"], cell["height"]),
        grains: cell["grains"].as_u64().unwrap_or(0) as usize,
        fresh,
        samples,
    })
}

/// The study's results, ready to be written.
pub struct Report {
    cases: Vec<Case>,
    summaries: Vec<Option<Summary>>,
    config: Config,
    elapsed: f64,
    runs: usize,
    box_size: String,
    grains: usize,
    /// Runs made now (the rest came from an earlier run's CSV).
    fresh: usize,
    samples: Vec<Sample>,
}

/// Reported for a setting that did not run.
static NOTHING: Summary = Summary {
    repose: None,
    methods: [None, None, None],
    tilt: None,
    cost: Tally::NONE,
};

impl Report {
    /// The reference setting's summary (it always runs).
    fn reference(&self) -> &Summary {
        self.summaries[0].as_ref().unwrap_or(&NOTHING)
    }

    fn rows(&self, group: Group) -> impl Iterator<Item = (&Case, &Summary)> {
        self.cases
            .iter()
            .zip(&self.summaries)
            .filter(move |(c, _)| c.group == group)
            .filter_map(|(c, s)| Some((c, s.as_ref()?)))
    }

    fn find(&self, name: &str) -> Option<&Summary> {
        self.cases
            .iter()
            .zip(&self.summaries)
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
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                c.name,
                c.what,
                m.cost.cost_cells(&r.cost, 2),
                stats_cell(m.repose),
                Shift::cell(dr),
                stats_cell(m.tilt),
                Shift::cell(dt),
                m.cost.failed_cell(),
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
        let rows = self
            .cases
            .iter()
            .zip(&self.summaries)
            .filter_map(|(c, s)| Some((c, s.as_ref()?)));
        shift_chart(title, y, rows, |m: &Summary| {
            let shift = if tilt {
                Shift::between(m.tilt, r.tilt)
            } else {
                Shift::between(m.repose, r.repose)
            };
            // Settings that leave the angle bit-identical (the skin for
            // both angles, the tilt knobs for θ_R) have nothing to show.
            let sh = shift.filter(|sh| sh.delta != 0.0)?;
            Some((m.cost.wall_time / r.cost.wall_time, sh))
        })
    }

    fn markdown(&self, stem: &str) -> String {
        let mut s = self.intro();
        s.push_str(&self.group_section(Group::Presets));
        s.push_str(&self.group_section(Group::Knobs));
        let _ = writeln!(
            s,
            "![shift of θ_R against cost]({stem}-repose.svg)\n\n![shift of θ_T against cost]({stem}-tilt.svg)\n\n\
             Settings that leave an angle bit-identical are not drawn: the Verlet-list skin changes only the cost, and the tilt knobs only θ_T.\n"
        );

        s.push_str(&self.samples_per_point());
        s.push_str(&self.sensitivities());
        s.push_str(&self.slope_methods());
        s.push_str(&self.failures());
        let _ = writeln!(
            s,
            "Every sample is in [`{stem}.csv`]({stem}.csv). Regenerate this page with `repose tradeoff`."
        );
        s
    }

    fn intro(&self) -> String {
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
            self.config.seeds,
            if self.config.set.is_empty() {
                String::new()
            } else {
                format!(" --set {}", self.config.set.join(" --set "))
            },
            self.runs,
            self.config.threads,
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
            self.config.seed_base,
            self.config.seed_base + self.config.seeds as u64 - 1,
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
            r.cost.wall_time,
            r.cost.particle_steps
        );
        s
    }

    /// The presets' or the knobs' table with the settings that shift an angle.
    fn group_section(&self, group: Group) -> String {
        let mut s = String::new();
        if self.rows(group).next().is_none() {
            return s;
        }
        let shifting = self.shifting(group);
        let (title, lead, verdict) = match group {
            Group::Presets => (
                "## Presets\n",
                "A sweep's `fidelity` (or `repose run --preset`) names one of these; the resolved scene stored with every result carries the preset's name and each concrete value.\n",
                if shifting.is_empty() {
                    "**No preset changes θ_R or θ_T beyond two standard errors of the reference.**".to_string()
                } else {
                    format!(
                        "**Presets that change the answer beyond two standard errors: {}.** The others agree with the reference within their error.",
                        shifting.join(", ")
                    )
                },
            ),
            _ => (
                "## Each knob on its own\n",
                "Each row is the reference with one setting changed.\n",
                if shifting.is_empty() {
                    "No single knob moves θ_R or θ_T beyond two standard errors.".to_string()
                } else {
                    format!(
                        "Knobs that move θ_R or θ_T beyond two standard errors: {}.",
                        shifting.join(", ")
                    )
                },
            ),
        };
        let _ = writeln!(s, "{title}");
        let _ = writeln!(s, "{lead}");
        s.push_str(&self.table(group));
        let _ = writeln!(s, "\n{verdict}\n");
        s
    }

    fn samples_per_point(&self) -> String {
        let r = self.reference();
        let mut s = String::new();
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

        s
    }

    fn sensitivities(&self) -> String {
        let mut s = String::new();
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
                        let se = if paper_preset.is_some_and(|p| std::ptr::eq(o, p)) {
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
                    o.cost.wall_time
                );
            }
            let _ = writeln!(
                s,
                "\nThe stiffness study raises the overlap guard to {SOFT_MAX_OVERLAP} radii for k_n < 10⁶: softer grains landing from the filling column overlap by more than the default half radius, and the guard fails the run otherwise."
            );
            s.push('\n');
        }

        s
    }

    fn slope_methods(&self) -> String {
        let mut s = String::new();
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

        s
    }

    fn failures(&self) -> String {
        let mut s = String::new();
        let failures = failure_lines(
            self.cases
                .iter()
                .zip(&self.summaries)
                .filter_map(|(c, m)| Some((c, &m.as_ref()?.cost))),
        );
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
        for (c, m) in self.cases.iter().zip(&self.summaries) {
            let Some(m) = m else { continue };
            let _ = writeln!(
                s,
                "{:<16} {:>7.2} {:>8.2} {:>22} {:>15} {:>22} {:>15}",
                c.name,
                m.cost.wall_time / r.cost.wall_time,
                m.cost.particle_steps / r.cost.particle_steps,
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

pub(crate) fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// What a preset gives up against the reference, from a study's CSV.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PresetShift {
    /// Samples of the preset that completed.
    pub n: usize,
    /// Shift of θ_R and its standard error.
    pub theta_r: (f64, f64),
    /// Shift of θ_T and its standard error.
    pub theta_t: (f64, f64),
    /// Mean wall time of a sample relative to the reference.
    pub cost: f64,
}

/// The shifts of `preset` from the reference in the per-sample CSV of an
/// earlier study, if it has both.
pub fn preset_shift(csv: &Path, preset: &str) -> Option<PresetShift> {
    let rows: Vec<Sample> = completed_rows(csv, |s: &Sample| s.status == "completed")?;
    let of = |setting: &str, f: fn(&Sample) -> Option<f64>| {
        setting_stats(&rows, |s| s.setting == setting, f)
    };
    let shift = |f: fn(&Sample) -> Option<f64>| {
        let (a, r) = (of(preset, f)?, of("reference", f)?);
        Some((
            (a.mean - r.mean),
            (a.sem * a.sem + r.sem * r.sem).sqrt(),
            a.n,
        ))
    };
    let (dr, ser, n) = shift(|s| s.theta_r_method3)?;
    let (dt, set, _) = shift(|s| s.theta_t)?;
    let cost =
        of(preset, |s| Some(s.wall_time_s))?.mean / of("reference", |s| Some(s.wall_time_s))?.mean;
    Some(PresetShift {
        n,
        theta_r: (dr, ser),
        theta_t: (dt, set),
        cost,
    })
}

/// The rows of a study's per-sample CSV that `keep` accepts (completed
/// runs), or none if the file cannot be read.
pub(crate) fn completed_rows<T: serde::de::DeserializeOwned>(
    csv: &Path,
    keep: fn(&T) -> bool,
) -> Option<Vec<T>> {
    let mut reader = csv::Reader::from_path(csv).ok()?;
    Some(
        reader
            .deserialize::<T>()
            .filter_map(Result::ok)
            .filter(keep)
            .collect(),
    )
}

/// Statistics of `f` over the rows of one setting.
pub(crate) fn setting_stats<T>(
    rows: &[T],
    of_setting: impl Fn(&T) -> bool,
    f: fn(&T) -> Option<f64>,
) -> Option<Stats> {
    let v: Vec<f64> = rows
        .iter()
        .filter(|r| of_setting(r))
        .filter_map(f)
        .collect();
    Stats::of(&v)
}

impl Report {
    /// Writes the Markdown report, its two SVG charts and the per-sample
    /// CSV beside it.
    pub fn write(&self) -> Result<(), TradeoffError> {
        write_files(
            &self.config.out,
            "speed-vs-accuracy",
            |stem| self.markdown(stem),
            vec![
                ("-repose.svg", self.chart(false)),
                ("-tilt.svg", self.chart(true)),
            ],
            &self.samples,
        )
    }

    /// A table of every setting's cost and shifts, for the terminal.
    pub fn summary(&self) -> String {
        self.console()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A study of `seeds` seeds from 1, on one thread, only planned.
    fn planning(seeds: u32, resume: bool) -> Config {
        Config {
            seeds,
            seed_base: 1,
            threads: 1,
            out: PathBuf::from("unused.md"),
            set: Vec::new(),
            only: Vec::new(),
            resume,
        }
    }

    /// The twins as (setting, seed, setting that runs it).
    fn ran_by(twins: Vec<(usize, u64, usize, String)>) -> Vec<(usize, u64, usize)> {
        twins
            .into_iter()
            .map(|(k, seed, of, _)| (k, seed, of))
            .collect()
    }

    #[test]
    fn a_resumed_study_keeps_a_row_only_while_its_setting_makes_the_same_scene() {
        let config = planning(1, true);
        let all = [
            Case::new(Group::Knobs, "same", "", &["box.width=1.2"]),
            Case::new(Group::Knobs, "changed", "", &["box.width=1.5"]),
            Case::new(Group::Knobs, "older", "", &["box.width=1.3"]),
        ];
        let jobs = plan(&config, &all, BASE).unwrap();
        let names: Vec<String> = all.iter().map(|c| c.name.clone()).collect();
        // `changed` ran at another width; `older` was written before rows
        // carried their scene; `gone` is no longer planned.
        let row = |setting: &str, scene: &str| {
            format!("{setting},knobs,1,completed,30.0,30.0,30.0,20.0,1.0,1000,,{scene}\n")
        };
        let other = plan(
            &config,
            &[Case::new(Group::Knobs, "changed", "", &["box.width=1.4"])],
            BASE,
        )
        .unwrap();
        let csv = [
            "setting,group,seed,status,theta_r_method1,theta_r_method2,theta_r_method3,theta_t,wall_time_s,particle_steps,reason,scene\n".to_string(),
            row("same", &sample_hash(&jobs[0].1)),
            row("changed", &sample_hash(&other[0].1)),
            row("older", ""),
            row("gone", &sample_hash(&jobs[0].1)),
        ]
        .concat();
        let path = std::env::temp_dir().join(format!("repose-kept-{}.csv", std::process::id()));
        std::fs::write(&path, csv).unwrap();
        let rows: Vec<Sample> = kept(&path, &names, &jobs);
        std::fs::remove_file(&path).ok();
        let found: Vec<(&str, &str)> = rows.iter().map(|r| (r.setting(), r.scene())).collect();
        assert_eq!(
            found,
            [
                ("same", sample_hash(&jobs[0].1).as_str()),
                ("older", sample_hash(&jobs[2].1).as_str())
            ]
        );
    }

    #[test]
    fn settings_that_resolve_to_one_scene_run_it_once() {
        let config = planning(2, false);
        // `b` sets the width `a` sets; `c` another; `d` sets `a`'s width and
        // a seed, which the plan's own seed overrides.
        let all = [
            Case::new(Group::Knobs, "a", "", &["box.width=1.2"]),
            Case::new(Group::Knobs, "b", "", &["box.width=1.2"]),
            Case::new(Group::Knobs, "c", "", &["box.width=1.5"]),
            Case::new(Group::Knobs, "d", "", &["box.width=1.2", "seed=9"]),
        ];
        let mut jobs = plan(&config, &all, BASE).unwrap();
        assert_eq!(jobs.len(), 8);
        let found = ran_by(twins(&mut jobs));
        // So `b` and `d` are `a`'s scenes; `c` runs on its own.
        assert_eq!(found, [(1, 1, 0), (1, 2, 0), (3, 1, 0), (3, 2, 0)]);
        let left: Vec<(usize, u64)> = jobs.iter().map(|(k, s)| (*k, s.seed)).collect();
        assert_eq!(left, [(0, 1), (0, 2), (2, 1), (2, 2)]);

        // The thread count changes no number: one scene. On a heap
        // `standard` softens to a tenth of the true modulus and `quick`
        // further, so each is a scene of its own.
        let heap = "protocol = \"heap\"\n[material]\nsurface_energy = 0.05\n";
        let all = [
            Case::new(Group::Presets, "paper", "", &["preset=paper"]),
            Case::new(
                Group::Presets,
                "paper, 2 threads",
                "",
                &["preset=paper", "numerics.threads=2"],
            ),
            Case::new(Group::Presets, "standard", "", &["preset=standard"]),
            Case::new(Group::Presets, "quick", "", &["preset=quick"]),
        ];
        let mut jobs = plan(&config, &all, heap).unwrap();
        let twins = twins(&mut jobs);
        assert_eq!(ran_by(twins.clone()), [(1, 1, 0), (1, 2, 0)]);
        // A twin's sample carries its own scene's identity, of which the
        // thread count is no part.
        assert_eq!(twins[0].3, sample_hash(&jobs[0].1));
        assert_eq!(jobs.len(), 6);
    }
}

//! The speed/accuracy study of the 3D poured heap (`repose tradeoff
//! --study heap`, written up in `docs/tradeoff-heap.md`): how far a
//! softened Young's modulus — with and without rescaling the cohesion —,
//! the time step, the heap's size and the settling criterion move θ_r,
//! against what they cost.
//!
//! Glass at the paper's 63 GPa costs 10¹¹–10¹² particle-steps on the
//! paper's heap, so the knobs are turned on the stiffest heap affordable
//! many times over: 630 MPa, a hundredth of glass. Softer grains are
//! compared with it; the `sticking` rescaling of the surface energy is
//! taken relative to the reference's modulus, so that it maps each
//! softened heap onto the reference's collisions. The presets resolve
//! against glass's own modulus, as they do in a study, and their bias is
//! read against the glass row. Every row is in the default contact form
//! (net limits, the attraction fading in contact) but the rows of the
//! other forms, each run at the reference's modulus and at glass's.

use super::tally::{costed, failure_lines, shift_chart, stats_over, Ran, Tally};
use super::{
    cores, gather, reference_and_presets, stats_cell, write_files, Case, Config, Group, Shift,
    TradeoffError,
};
use crate::chart::Chart;
use repose_physics::measure::Stats;
use repose_physics::models::elekes_parteli::Material;
use repose_physics::{Scene, ENGINE};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::Path;

/// The heap every setting pours: 1 mm glass beads with glass's surface
/// energy on Earth, 1500 grains on a 20 d plate.
const BASE: &str = r#"
protocol = "heap"
[material]
surface_energy = 0.05
[heap]
plate = 20
max_grains = 1500
"#;

/// The reference: a hundredth of glass's modulus, Verlet at a tenth of the
/// collision time; its modulus is also the one `sticking` rescales from.
const REFERENCE: [&str; 4] = [
    "material.youngs_modulus=6.3e8",
    "material.true_modulus=6.3e8",
    "numerics.integrator=verlet",
    "numerics.dt_factor=0.1",
];

/// The row of glass's own modulus, which the presets' bias is read against.
const GLASS: &str = "Y 63 GPa (glass)";

/// The dry heap at glass's modulus, which the presets' dry bias is read
/// against.
const DRY_GLASS: &str = "no cohesion, glass";

fn knob(name: &str, what: &str, settings: &[&str]) -> Case {
    Case::knob_over(&REFERENCE, name, what, settings)
}

/// The contact forms beside the default (limits on the net normal force,
/// the attraction fading in contact): name, what it is, and its settings.
const FORMS: [(&str, &str, &[&str]); 2] = [
    (
        "as printed",
        "limits on the repulsion and the attraction constant in contact, as eqs. 11, 13 and 15 print them",
        &[
            "material.limit_load=contact",
            "material.contact_attraction=constant",
        ],
    ),
    (
        "constant attraction",
        "net limits with the attraction constant in contact",
        &["material.contact_attraction=constant"],
    ),
];

fn cases() -> Vec<Case> {
    let mut v = reference_and_presets("heap", "Y = 630 MPa, Verlet, dt = T_col/10", &REFERENCE);
    for preset in ["quick", "standard"] {
        v.push(Case {
            group: Group::Presets,
            name: format!("{preset}, no cohesion"),
            what: format!(
                "the {preset} preset with γ = 0: its bias on a dry heap (against `{DRY_GLASS}`)"
            ),
            overrides: vec![
                format!("preset={preset}"),
                "material.surface_energy=0".into(),
            ],
        });
    }
    // The softest preset under the other contact forms, against glass
    // under the same form.
    for (form, what, settings) in FORMS {
        let mut overrides = vec!["preset=quick".to_string()];
        overrides.extend(settings.iter().map(|s| s.to_string()));
        v.push(Case {
            group: Group::Presets,
            name: format!("quick, {form}"),
            what: format!("the quick preset with {what} (against `{form}, glass`)"),
            overrides,
        });
    }
    v.extend(knobs());
    v
}

/// Each contact form beside the default at the reference's modulus and at
/// glass's.
fn forms() -> Vec<Case> {
    let mut v = Vec::new();
    for (form, what, settings) in FORMS {
        v.push(knob(form, what, settings));
        let mut glass = vec!["material.youngs_modulus=6.3e10"];
        glass.extend_from_slice(settings);
        v.push(knob(
            &format!("{form}, glass"),
            &format!("Y = 63 GPa with {what}"),
            &glass,
        ));
    }
    v
}

/// The reference with one setting changed.
fn knobs() -> Vec<Case> {
    let mut v = vec![
        knob(
            GLASS,
            "Y = 63 GPa, the paper's glass",
            &["material.youngs_modulus=6.3e10"],
        ),
        knob(
            "Y 6.3 GPa",
            "Y = 6.3 GPa, γ unchanged",
            &["material.youngs_modulus=6.3e9"],
        ),
        knob(
            "no cohesion",
            "γ = 0: the dry heap",
            &["material.surface_energy=0"],
        ),
        knob(
            DRY_GLASS,
            "γ = 0 at Y = 63 GPa: the dry heap of glass",
            &[
                "material.surface_energy=0",
                "material.youngs_modulus=6.3e10",
            ],
        ),
        knob(
            "Y 63 MPa",
            "Y = 63 MPa, γ unchanged",
            &["material.youngs_modulus=6.3e7"],
        ),
        knob(
            "Y 63 MPa, γ scaled",
            "Y = 63 MPa, γ × (Y/630 MPa)^{2/5}",
            &[
                "material.youngs_modulus=6.3e7",
                "material.cohesion_scaling=sticking",
            ],
        ),
        knob(
            "Y 6.3 MPa",
            "Y = 6.3 MPa, γ unchanged",
            &["material.youngs_modulus=6.3e6"],
        ),
        knob(
            "Y 6.3 MPa, γ scaled",
            "Y = 6.3 MPa, γ × (Y/630 MPa)^{2/5}",
            &[
                "material.youngs_modulus=6.3e6",
                "material.cohesion_scaling=sticking",
            ],
        ),
    ];
    v.extend(forms());
    v.extend([
        knob("T_col/20", "dt = T_col/20", &["numerics.dt_factor=0.05"]),
        knob("T_col/5", "dt = T_col/5", &["numerics.dt_factor=0.2"]),
        knob(
            "3000 grains",
            "twice the grains poured",
            &["heap.max_grains=3000"],
        ),
        knob(
            "rest 1e-5",
            "at rest below 10⁻⁵ m g d per grain (default 10⁻⁶)",
            &["heap.rest_energy=1e-5"],
        ),
        knob(
            "rest 1e-7",
            "at rest below 10⁻⁷ m g d per grain",
            &["heap.rest_energy=1e-7"],
        ),
    ]);
    v
}

/// One sample's numbers: a row of the per-sample CSV.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Sample {
    setting: String,
    group: Group,
    seed: u64,
    status: String,
    theta_r: Option<f64>,
    theta_r_footprint: Option<f64>,
    heap_grains: Option<f64>,
    surface_roughness: Option<f64>,
    youngs_modulus: f64,
    wall_time_s: f64,
    particle_steps: u64,
    reason: String,
    /// The identity of the scene that ran (empty in older CSVs).
    #[serde(default)]
    scene: String,
}

costed!(Sample);

fn run_one(case: &Case, scene: &Scene) -> Sample {
    let modulus = scene
        .section::<Material>()
        .ok()
        .and_then(|m| m.youngs_modulus)
        .unwrap_or(f64::NAN);
    let ran = Ran::of(scene);
    Sample {
        setting: case.name.clone(),
        group: case.group,
        seed: scene.seed,
        theta_r: ran.metric("theta_r"),
        theta_r_footprint: ran.metric("theta_r_footprint"),
        heap_grains: ran.metric("heap_grains"),
        surface_roughness: ran.metric("surface_roughness"),
        youngs_modulus: modulus,
        wall_time_s: ran.wall_time,
        particle_steps: ran.particle_steps,
        status: ran.status,
        reason: ran.reason,
        scene: repose_sweeps::spec::sample_hash(scene),
    }
}

/// What one setting measured.
struct Summary {
    theta: Option<Stats>,
    footprint: Option<Stats>,
    grains: Option<Stats>,
    roughness: Option<Stats>,
    modulus: f64,
    cost: Tally,
}

fn summarise(samples: &[&Sample]) -> Summary {
    Summary {
        theta: stats_over(samples, |s| s.theta_r),
        footprint: stats_over(samples, |s| s.theta_r_footprint),
        grains: stats_over(samples, |s| s.heap_grains),
        roughness: stats_over(samples, |s| s.surface_roughness),
        modulus: samples.first().map_or(f64::NAN, |s| s.youngs_modulus),
        cost: Tally::of(samples),
    }
}

/// Runs the heap study and returns its report (`tick` as for [`super::run`]).
pub fn run(config: &Config, tick: &(dyn Fn(usize) + Sync)) -> Result<HeapReport, TradeoffError> {
    let all = cases();
    let g = gather(config, &all, BASE, tick, run_one, summarise)?;
    Ok(HeapReport {
        cases: all,
        summaries: g.summaries,
        config: config.clone(),
        elapsed: g.elapsed,
        fresh: g.fresh,
        shared: g.shared,
        samples: g.samples,
    })
}

/// The heap study's results, ready to be written.
pub struct HeapReport {
    cases: Vec<Case>,
    summaries: Vec<Option<Summary>>,
    config: Config,
    elapsed: f64,
    fresh: usize,
    shared: usize,
    samples: Vec<Sample>,
}

impl HeapReport {
    fn reference(&self) -> Option<&Summary> {
        self.summaries.first().and_then(Option::as_ref)
    }

    fn rows(&self) -> impl Iterator<Item = (&Case, &Summary)> + Clone {
        self.cases
            .iter()
            .zip(&self.summaries)
            .filter_map(|(c, s)| Some((c, s.as_ref()?)))
    }

    fn table(&self, groups: &[Group]) -> String {
        let Some(r) = self.reference() else {
            return String::new();
        };
        let mut s = String::from(
            "| setting | what | Y (Pa) | wall time | particle-steps | θ_r (°) | Δθ_r | θ_r footprint (°) | grains in heap | roughness (d) | failed | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for (c, m) in self
            .rows()
            .filter(|(c, _)| c.group == Group::Reference || groups.contains(&c.group))
        {
            let shift = Shift::between(m.theta, r.theta);
            let verdict = match (c.group, shift) {
                (Group::Reference, _) => "reference".to_string(),
                (_, None) => "no result".to_string(),
                (_, Some(sh)) if sh.significant() => "**shifts θ_r**".to_string(),
                _ => "within error".to_string(),
            };
            let _ = writeln!(
                s,
                "| {} | {} | {:.2e} | {} | {} | {} | {} | {} | {} | {} | {verdict} |",
                c.name,
                c.what,
                m.modulus,
                m.cost.cost_cells(&r.cost, 1),
                stats_cell(m.theta),
                Shift::cell(shift),
                stats_cell(m.footprint),
                stats_cell(m.grains),
                stats_cell(m.roughness),
                m.cost.failed_cell(),
            );
        }
        s
    }

    fn chart(&self) -> Chart {
        let r = self.reference();
        shift_chart(
            "Shift of θ_r from the reference heap",
            "Δθ_r (°)",
            self.rows(),
            |m: &Summary| {
                let r = r?;
                let shift = Shift::between(m.theta, r.theta)?;
                Some((m.cost.wall_time / r.cost.wall_time, shift))
            },
        )
    }

    /// How the samples were made: all now, or some read back from the CSV
    /// of earlier runs, whose wall times need not be this machine's.
    fn provenance(&self) -> String {
        const MIXED: &str = "a row's wall time is that of the run that made it, perhaps on \
             another machine, so between rows of different runs compare particle-steps";
        let busy: f64 = self.samples.iter().map(|s| s.wall_time_s).sum();
        let shared = match self.shared {
            0 => String::new(),
            n => format!(
                "; {n} of them share their scene with another setting's run (the presets that \
                 resolve to glass's own numerics), which ran once and counts for both"
            ),
        };
        let made = match self.fresh {
            n if n == self.samples.len() => {
                format!(" in {:.0} s ({busy:.0} s of run time)", self.elapsed)
            }
            0 => format!(
                ", {busy:.0} s of run time in all (read back from the per-sample CSV; {MIXED})"
            ),
            n => format!(
                " ({n} of them now, in {:.0} s; {busy:.0} s of run time in all; {MIXED})",
                self.elapsed
            ),
        };
        made + &shared
    }

    fn markdown(&self, stem: &str) -> String {
        let mut s = String::from("# Speed against accuracy: the poured heap\n\n");
        let _ = writeln!(
            s,
            "Generated by `repose tradeoff --study heap --seeds {}` (engine {ENGINE}): {} runs on {} threads of a {}-core machine{}. \
             Every setting pours 1 mm glass beads (γ = 0.05 J/m², Bond number 24) on Earth onto a 20 d plate until 1500 grains have fallen, over seeds {}–{}. \
             Glass's 63 GPa costs 10¹¹–10¹² particle-steps on the paper's heap; the knobs are turned on a hundredth of it, the reference's 630 MPa, and the `sticking` rescaling of γ is taken from there. \
             The presets take glass's 63 GPa as the true modulus, as in a study. \
             Contacts take the default form — sliding and rolling limits on the net normal force, the attraction fading in contact — but in the rows named after another form. \
             A shift is the difference of two means with its standard error; beyond two standard errors a setting **shifts θ_r**.\n",
            self.config.seeds,
            self.samples.len(),
            self.config.threads,
            cores(),
            self.provenance(),
            self.config.seed_base,
            self.config.seed_base + self.config.seeds as u64 - 1,
        );
        let _ = writeln!(s, "## Presets\n\n{}", self.table(&[Group::Presets]));
        let _ = writeln!(
            s,
            "## Each knob on its own\n\nEach row is the reference with one setting changed.\n\n{}",
            self.table(&[Group::Knobs])
        );
        let _ = writeln!(s, "![shift of θ_r against cost]({stem}.svg)\n");
        s.push_str(&self.reading());
        s.push_str(&self.failures());
        let _ = writeln!(s, "Every sample is in [`{stem}.csv`]({stem}.csv).");
        s
    }

    /// The summary of the setting named `name`, if it ran.
    fn setting(&self, name: &str) -> Option<&Summary> {
        self.rows().find(|(c, _)| c.name == name).map(|(_, m)| m)
    }

    fn theta(&self, name: &str) -> Option<Stats> {
        self.setting(name).and_then(|m| m.theta)
    }

    /// `a − b` in θ_r as "+1.23° ± 0.45°", or a dash when either is missing.
    fn shift(&self, a: &str, b: &str) -> String {
        match Shift::between(self.theta(a), self.theta(b)) {
            Some(sh) => format!("{:+.1}° ± {:.1}°", sh.delta, sh.se),
            None => "—".into(),
        }
    }

    /// `a`'s particle-steps a heap over `b`'s, as "1.00×", or a dash.
    fn steps_ratio(&self, a: &str, b: &str) -> String {
        let steps = |name: &str| self.setting(name).map(|m| m.cost.particle_steps);
        match (steps(a), steps(b)) {
            (Some(x), Some(y)) if y > 0.0 => format!("{:.2}×", x / y),
            _ => "—".into(),
        }
    }

    /// What the tables say, in numbers taken from them.
    fn reading(&self) -> String {
        let g = GLASS;
        let mut s = String::from(
            "## Reading the tables

",
        );
        let _ = writeln!(
            s,
            "* **Stiffness moves a cohesive heap.** Against glass (63 GPa) the reference \
             (630 MPa) stands {}, 6.3 GPa {}; 63 MPa {} and 6.3 MPa {}. The attraction \
             fades with the overlap, and softer grains press deeper into each contact, so \
             they keep less of it; as printed, with the attraction constant in contact, \
             softer grains keep all of it and stick where stiff ones bounce (the reference \
             as printed stands {} against glass as printed).",
            self.shift("reference", g),
            self.shift("Y 6.3 GPa", g),
            self.shift("Y 63 MPa", g),
            self.shift("Y 6.3 MPa", g),
            self.shift("as printed", "as printed, glass"),
        );
        let _ = writeln!(
            s,
            "* **Rescaling γ** by (Y/Y_ref)^{{2/5}} (`cohesion_scaling = \"sticking\"`) \
             moves 63 MPa by {} from the reference and 6.3 MPa by {}, where unscaled they \
             sit {} and {}. The presets keep γ, and bound the softening by the cohesion \
             number (`kappa_cohesion`).",
            self.shift("Y 63 MPa, γ scaled", "reference"),
            self.shift("Y 6.3 MPa, γ scaled", "reference"),
            self.shift("Y 63 MPa", "reference"),
            self.shift("Y 6.3 MPa", "reference"),
        );
        let _ = writeln!(
            s,
            "* **Presets, labelled by their bias.** On this cohesive heap (Bond number 24) \
             `standard` (a tenth of glass's modulus) stands {} against glass at {} of its \
             particle-steps, `quick` {} at {}, and `paper` (glass) {}. On the dry heap \
             against dry glass: `standard` {}, `quick` {}. A hundredth of glass's modulus \
             (the reference) stands {} at {}.",
            self.shift("standard", g),
            self.steps_ratio("standard", g),
            self.shift("quick", g),
            self.steps_ratio("quick", g),
            self.shift("paper", g),
            self.shift("standard, no cohesion", DRY_GLASS),
            self.shift("quick, no cohesion", DRY_GLASS),
            self.shift("reference", g),
            self.steps_ratio("reference", g),
        );
        s.push_str(&self.reading_forms());
        s.push_str(&self.reading_numerics());
        s
    }

    /// The bullet on the time step, the settling threshold and the heap's
    /// size.
    fn reading_numerics(&self) -> String {
        let mut s = String::new();
        let numerics = ["T_col/20", "T_col/5", "rest 1e-5", "rest 1e-7"];
        let moved: Vec<&str> = numerics
            .into_iter()
            .filter(|n| {
                Shift::between(self.theta(n), self.theta("reference"))
                    .is_some_and(Shift::significant)
            })
            .collect();
        let verdict = match moved.as_slice() {
            [] => "none beyond two standard errors".to_string(),
            some => format!("beyond two standard errors: {}", some.join(", ")),
        };
        let _ = writeln!(
            s,
            "* **Numerics.** The time step moves θ_r by {} (T_col/20) and {} (T_col/5); the \
             settling threshold by {} and {} ({verdict}); twice the grains poured stand {} \
             against the reference.\n",
            self.shift("T_col/20", "reference"),
            self.shift("T_col/5", "reference"),
            self.shift("rest 1e-5", "reference"),
            self.shift("rest 1e-7", "reference"),
            self.shift("3000 grains", "reference"),
        );
        s
    }

    /// The bullet on the contact forms: the default against the dry heap,
    /// the other forms against it, and `quick` under each.
    fn reading_forms(&self) -> String {
        let g = GLASS;
        format!(
            "* **The contact form.** In the default form (limits on the net normal force, \
             the attraction fading in contact) glass stands {} above dry glass. As eqs. 11, \
             13 and 15 print it — limits on the repulsion, which the attraction raises by \
             π γ d, twelve weights here, and the attraction constant in contact — glass stands {} against the default; with net limits and a constant \
             attraction {}. `quick` stands {} against glass in the default form, {} as \
             printed and {} with a constant attraction, each against glass in its own form; \
             in the default form it stands {} from `quick` without cohesion.\n",
            self.shift(g, DRY_GLASS),
            self.shift("as printed, glass", g),
            self.shift("constant attraction, glass", g),
            self.shift("quick", g),
            self.shift("quick, as printed", "as printed, glass"),
            self.shift("quick, constant attraction", "constant attraction, glass"),
            self.shift("quick", "quick, no cohesion"),
        )
    }

    fn failures(&self) -> String {
        let lines = failure_lines(self.rows().map(|(c, m)| (c, &m.cost)));
        if lines.is_empty() {
            return "Every run completed.\n\n".into();
        }
        format!(
            "## Runs without a result\n\nLeft out of the means above:\n\n{}\n\n",
            lines.join("\n")
        )
    }

    /// Writes the Markdown report, its chart and the per-sample CSV beside it.
    pub fn write(&self) -> Result<(), TradeoffError> {
        write_files(
            &self.config.out,
            "tradeoff-heap",
            |stem| self.markdown(stem),
            vec![(".svg", self.chart())],
            &self.samples,
        )
    }

    /// Every setting's cost and shift, for the terminal.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let Some(r) = self.reference() else {
            return s;
        };
        for (c, m) in self.rows() {
            let _ = writeln!(
                s,
                "{:<22} {:>7.2}× {:>24} {:>15}",
                c.name,
                m.cost.wall_time / r.cost.wall_time,
                stats_cell(m.theta),
                Shift::cell(Shift::between(m.theta, r.theta))
            );
        }
        s
    }
}

/// What a preset costs a cohesive heap's θ_r against glass's modulus, and
/// a dry heap's against dry glass where the study ran it dry, from the
/// per-sample CSV of an earlier heap study; in words, for the reports.
pub fn preset_bias(csv: &Path, preset: &str) -> Option<String> {
    let rows: Vec<Sample> = super::completed_rows(csv, |s: &Sample| s.status == "completed")?;
    let stats = |setting: &str, f: fn(&Sample) -> Option<f64>| {
        super::setting_stats(&rows, |s| s.setting == setting, f)
    };
    let glass = GLASS;
    let cohesive = Shift::between(stats(preset, |s| s.theta_r), stats(glass, |s| s.theta_r))?;
    let steps = |setting: &str| stats(setting, |s| Some(s.particle_steps as f64));
    let cost = steps(preset)?.mean / steps(glass)?.mean;
    let mut text = format!(
        "On a cohesive heap of 1 mm glass beads (Bo = 24, 20 d plate, 1500 grains) the `{preset}` preset stands {:+.1}° ± {:.1}° from glass's 63 GPa at {cost:.2}× its particle-steps per heap",
        cohesive.delta, cohesive.se
    );
    let dry = Shift::between(
        stats(&format!("{preset}, no cohesion"), |s| s.theta_r),
        stats(DRY_GLASS, |s| s.theta_r),
    );
    if let Some(d) = dry {
        text.push_str(&format!(
            "; on the same heap without cohesion {:+.1}° ± {:.1}°",
            d.delta, d.se
        ));
    }
    text.push_str(" ([speed against accuracy: the poured heap](tradeoff-heap.md)).");
    Some(text)
}

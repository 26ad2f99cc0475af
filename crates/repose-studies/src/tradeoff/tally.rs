//! What both speed/accuracy studies read off their samples: a run's
//! outcome and cost, a setting's cost and failures, the statistics of one
//! column, and the chart of shifts against cost.

use super::{Case, Group, Shift};
use crate::chart::{Chart, Series, Style};
use repose_physics::measure::Stats;
use repose_physics::{Quiet, Scene};
use std::collections::BTreeMap;

/// What running one setting's scene gave, whatever its protocol.
pub(crate) struct Ran {
    pub status: String,
    pub reason: String,
    pub metrics: BTreeMap<String, f64>,
    pub wall_time: f64,
    pub particle_steps: u64,
}

impl Ran {
    /// Runs the scene; a scene the engine refuses is an `invalid` run.
    pub(crate) fn of(scene: &Scene) -> Ran {
        match repose_physics::run(scene, &mut Quiet) {
            Ok(r) => Ran {
                status: r.outcome.status().to_string(),
                reason: r.outcome.reason().unwrap_or_default(),
                metrics: r.metrics,
                wall_time: r.wall_time,
                particle_steps: r.particle_steps,
            },
            Err(e) => Ran {
                status: "invalid".into(),
                reason: e.to_string(),
                metrics: BTreeMap::new(),
                wall_time: 0.0,
                particle_steps: 0,
            },
        }
    }

    pub(crate) fn metric(&self, name: &str) -> Option<f64> {
        self.metrics.get(name).copied()
    }
}

/// A per-sample row's setting, seed, outcome and cost.
pub(crate) trait Costed {
    fn setting(&self) -> &str;
    fn seed(&self) -> u64;
    fn status(&self) -> &str;
    fn reason(&self) -> &str;
    fn wall_time(&self) -> f64;
    fn particle_steps(&self) -> u64;
    /// The identity of the scene that made it (`repose_sweeps::spec::sample_hash`);
    /// empty in rows written before rows carried it.
    fn scene(&self) -> &str;
    /// The same sample filed under another setting (one whose scene runs
    /// the same numbers).
    fn renamed(&self, case: &Case) -> Self;
    /// The same sample with the identity of its scene written in.
    fn with_scene(self, scene: String) -> Self;
}

/// Implements [`Costed`] for a per-sample row with the fields `setting`,
/// `seed`, `status`, `reason`, `wall_time_s`, `particle_steps` and `scene`
/// (the columns both studies' CSVs share).
macro_rules! costed {
    ($row:ty) => {
        impl $crate::tradeoff::tally::Costed for $row {
            fn setting(&self) -> &str {
                &self.setting
            }
            fn seed(&self) -> u64 {
                self.seed
            }
            fn status(&self) -> &str {
                &self.status
            }
            fn reason(&self) -> &str {
                &self.reason
            }
            fn wall_time(&self) -> f64 {
                self.wall_time_s
            }
            fn particle_steps(&self) -> u64 {
                self.particle_steps
            }
            fn scene(&self) -> &str {
                &self.scene
            }
            fn renamed(&self, case: &$crate::tradeoff::Case) -> Self {
                Self {
                    setting: case.name.clone(),
                    group: case.group,
                    ..self.clone()
                }
            }
            fn with_scene(self, scene: String) -> Self {
                Self { scene, ..self }
            }
        }
    };
}
pub(crate) use costed;

/// One setting's mean cost a sample and the runs without a result.
pub(crate) struct Tally {
    pub wall_time: f64,
    pub particle_steps: f64,
    pub runs: usize,
    pub failed: Vec<String>,
}

impl Tally {
    /// For a setting that did not run.
    pub(crate) const NONE: Tally = Tally {
        wall_time: f64::NAN,
        particle_steps: f64::NAN,
        runs: 0,
        failed: Vec::new(),
    };

    pub(crate) fn of<S: Costed>(samples: &[&S]) -> Tally {
        let n = samples.len().max(1) as f64;
        Tally {
            wall_time: samples.iter().map(|s| s.wall_time()).sum::<f64>() / n,
            particle_steps: samples
                .iter()
                .map(|s| s.particle_steps() as f64)
                .sum::<f64>()
                / n,
            runs: samples.len(),
            failed: samples
                .iter()
                .filter(|s| s.status() != "completed")
                .map(|s| format!("seed {}: {} ({})", s.seed(), s.status(), s.reason()))
                .collect(),
        }
    }

    /// The cost cells of a table row against the reference:
    /// `1.23× (4.5 s) | 0.98×`, the wall time given to `digits` decimals.
    pub(crate) fn cost_cells(&self, reference: &Tally, digits: usize) -> String {
        format!(
            "{:.2}× ({:.digits$} s) | {:.2}×",
            self.wall_time / reference.wall_time,
            self.wall_time,
            self.particle_steps / reference.particle_steps,
        )
    }

    /// The `failed` cell of a table row: runs without a result of all.
    pub(crate) fn failed_cell(&self) -> String {
        format!("{}/{}", self.failed.len(), self.runs)
    }
}

/// The statistics of one column over the samples that have it.
pub(crate) fn stats_over<S>(samples: &[&S], f: impl Fn(&S) -> Option<f64>) -> Option<Stats> {
    let v: Vec<f64> = samples.iter().filter_map(|s| f(s)).collect();
    Stats::of(&v)
}

/// The lines naming every run without a result, setting by setting.
pub(crate) fn failure_lines<'a>(rows: impl Iterator<Item = (&'a Case, &'a Tally)>) -> Vec<String> {
    rows.flat_map(|(c, t)| t.failed.iter().map(move |f| format!("- `{}` {f}", c.name)))
        .collect()
}

/// The chart of each preset's and knob's shift against its cost relative
/// to the reference; `shift` gives a row's shift and cost ratio, if any.
pub(crate) fn shift_chart<'a, M: 'a>(
    title: &str,
    y: &str,
    rows: impl Iterator<Item = (&'a Case, &'a M)> + Clone,
    shift: impl Fn(&M) -> Option<(f64, Shift)>,
) -> Chart {
    let mut chart = Chart::new(title, "wall time relative to the reference", y);
    chart.log_x = true;
    chart.y_rule = Some(0.0);
    for (group, name) in [(Group::Presets, "presets"), (Group::Knobs, "knobs")] {
        let mut series = Series::new(name, Style::Points);
        for (c, m) in rows.clone().filter(|(c, _)| c.group == group) {
            if let Some((cost, sh)) = shift(m) {
                series = series.labelled(cost, sh.delta, sh.se, &c.name);
            }
        }
        chart.series.push(series);
    }
    chart
}

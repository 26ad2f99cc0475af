//! The reproduction report of a paper: its figures from our sweeps (drawn
//! from the same figure data the API serves the page), the comparison of
//! its stated results with ours, what each sweep cost, and every number
//! in a JSON file beside it.

use crate::chart::{Chart, Series, Style};
use crate::compare::{fmt_agg, Comparison};
use crate::figure::{FigureData, Kind};
use crate::remaining::Remaining;
use repose_store::{Cost, Point};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// One sweep of the reproduction, as the service reported it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DoneSweep {
    /// The study key (`fig347`).
    pub key: String,
    pub title: String,
    pub id: String,
    pub jobs: u64,
    pub reused: u64,
    pub cost: Cost,
    pub points: Vec<Point>,
}

/// Everything the report says, gathered from the service.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Reproduction {
    /// The paper's key and title.
    pub paper: String,
    pub title: String,
    /// The command that made it.
    pub command: String,
    pub engine: String,
    /// The fidelity preset and what it sets.
    pub preset: String,
    pub preset_settings: String,
    pub reduced: bool,
    pub cores: usize,
    /// Wall time of the run that wrote it, s.
    pub wall_time_s: f64,
    pub sweeps: Vec<DoneSweep>,
    pub figures: Vec<FigureData>,
    pub comparison: Vec<Comparison>,
    /// What the preset gives up, from the speed/accuracy study, if known.
    #[serde(default)]
    pub preset_accuracy: Option<String>,
    /// Labels of the metrics the tables show, by name.
    #[serde(default)]
    pub metric_labels: Vec<(String, String)>,
    /// The variant of the model every scene ran with (`--set`), empty for
    /// the paper's own.
    #[serde(default)]
    pub variant: String,
    /// Samples not finished when it was written (an interim report).
    #[serde(default)]
    pub pending: u64,
    /// What those samples are estimated to cost, where it can be told.
    #[serde(default)]
    pub remaining: Option<Remaining>,
}

/// A static chart of a figure's data.
pub fn chart(fig: &FigureData) -> Chart {
    let mut c = Chart::new(
        &format!("Fig. {}: {}", fig.figure, fig.title),
        &fig.x_label,
        &fig.y_label,
    );
    c.log_x = fig.log_x;
    for s in &fig.series {
        let style = match s.kind {
            Kind::Measured => Style::Points,
            Kind::Theory | Kind::Recorded | Kind::Fit => Style::Line,
            Kind::Quoted => Style::Open,
            Kind::Level => Style::Dashed,
        };
        let mut series = Series::new(&s.name, style);
        for p in &s.points {
            if let Some(y) = p.y {
                series = series.point(p.x, y, p.sd.unwrap_or(0.0));
            }
        }
        let (lo, hi) = s
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.x), b.max(p.x))
            });
        c.series.push(series);
        if let Some(b) = s.band.filter(|_| lo.is_finite()) {
            for (name, y) in [("steady mean + sd", b.hi), ("steady mean − sd", b.lo)] {
                c.series.push(
                    Series::new(name, Style::Dashed)
                        .point(lo, y, 0.0)
                        .point(hi, y, 0.0),
                );
            }
        }
    }
    c
}

/// The samples a sweep's points have: one count, or the range.
fn per_point(d: &DoneSweep) -> String {
    let counts = d.points.iter().map(|p| p.samples);
    match (counts.clone().min(), counts.max()) {
        (Some(a), Some(b)) if a == b => a.to_string(),
        (Some(a), Some(b)) => format!("{a}–{b}"),
        _ => "—".into(),
    }
}

impl Reproduction {
    /// Writes `out` (Markdown), one SVG per figure and the JSON beside it.
    pub fn write(&self, out: &Path) -> std::io::Result<()> {
        if let Some(d) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(d)?;
        }
        let stem = stem(out);
        let beside = |suffix: &str| -> PathBuf { out.with_file_name(format!("{stem}{suffix}")) };
        std::fs::write(out, self.markdown(&stem))?;
        for f in &self.figures {
            std::fs::write(
                beside(&format!("-{}.svg", file_key(&f.figure))),
                chart(f).svg(),
            )?;
        }
        let json = serde_json::to_string_pretty(self).map_err(std::io::Error::other)?;
        std::fs::write(beside(".json"), json)
    }

    /// The cost of each sweep, as a Markdown table.
    pub fn breakdown(&self) -> String {
        let mut s = String::from("| sweep | points | samples a point | samples | reused | failed | CPU time (s) | particle-steps |\n|---|---|---|---|---|---|---|---|\n");
        let (mut cpu, mut steps) = (0.0, 0i64);
        for d in &self.sweeps {
            cpu += d.cost.wall_time;
            steps += d.cost.particle_steps;
            let failed: i64 = d.points.iter().map(|p| p.failures).sum();
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {failed} | {:.1} | {:.3e} |",
                d.title,
                d.points.len(),
                per_point(d),
                d.jobs,
                d.reused,
                d.cost.wall_time,
                d.cost.particle_steps as f64
            );
        }
        let failed: i64 = self
            .sweeps
            .iter()
            .flat_map(|d| &d.points)
            .map(|p| p.failures)
            .sum();
        let _ = writeln!(
            s,
            "| **all** | {} | | {} | {} | {failed} | {cpu:.1} | {:.3e} |",
            self.sweeps.iter().map(|d| d.points.len()).sum::<usize>(),
            self.sweeps.iter().map(|d| d.jobs).sum::<u64>(),
            self.sweeps.iter().map(|d| d.reused).sum::<u64>(),
            steps as f64
        );
        let _ = writeln!(
            s,
            "\nWall time of this run: {:.1} s ({:.1} min); samples reused from an earlier run, or resumed from its checkpoints, ran before it.",
            self.wall_time_s,
            self.wall_time_s / 60.0
        );
        s
    }

    fn markdown(&self, stem: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Reproduction of {}\n", self.title);
        let _ = writeln!(
            s,
            "Generated by `{}`: every sweep below went through the service's HTTP API and its workers, like any user's sweep, \
             and every figure is drawn from the figure data the API serves the results page. \
             Engine {}, fidelity preset `{}` ({}), samples a point as the cost table lists them, on a {}-core machine. \
             Error bars are the sample standard deviation, as in the paper.\n",
            self.command, self.engine, self.preset, self.preset_settings, self.cores
        );
        if !self.variant.is_empty() {
            let _ = writeln!(
                s,
                "Every scene ran a variant of the model: {}, over the paper's own settings. \
                 The causes the comparison below quotes were measured on the paper's own model; \
                 where they name it, they are not this variant's.\n",
                self.variant
            );
        }
        if self.pending > 0 {
            let total: u64 = self.sweeps.iter().map(|d| d.jobs).sum();
            let _ = writeln!(
                s,
                "**Interim report:** {} of its {total} samples are finished and {} are still queued; \
                 every number below is of the finished samples alone, and a point without one is missing.{}\n",
                total.saturating_sub(self.pending),
                self.pending,
                self.remaining.map(|r| format!(" {}", r.sentence())).unwrap_or_default()
            );
        }
        let _ = writeln!(s, "## Cost\n");
        s.push_str(&self.breakdown());
        let _ = writeln!(
            s,
            "\nCPU time sums the run time of every sample (one core each); samples reused from earlier sweeps cost nothing in this run.\n"
        );
        let accuracy = self.preset_accuracy.clone().unwrap_or_else(|| {
            "The accuracy each preset gives up is measured in [speed against accuracy](speed-vs-accuracy.md).".into()
        });
        let _ = writeln!(s, "{accuracy}\n");
        s.push_str(&self.comparison_table());
        let _ = writeln!(s, "## Figures\n");
        for f in &self.figures {
            let _ = writeln!(
                s,
                "![{}]({stem}-{}.svg)\n\n{}\n",
                f.caption,
                file_key(&f.figure),
                f.caption
            );
        }
        s.push_str(&self.fits_table());
        s.push_str(&self.points_tables());
        let _ = writeln!(s, "Every number above is in [`{stem}.json`]({stem}.json). Regenerate with `repose reproduce`.");
        s
    }

    fn comparison_table(&self) -> String {
        let mut s = String::from("## The paper's numbers against ours\n\n");
        let _ = writeln!(
            s,
            "For a measured value the difference is (ours − paper) / √(sem_ours² + sd_paper²/n_paper), and |difference| ≤ 2 agrees; \
             where the paper does not say how many samples a value rests on, its usual count is assumed. \
             For a fitted constant it is (ours − paper) / (our standard error), and the constant agrees when the paper's value lies in our 95 % interval.\n"
        );
        s.push_str("| quantity | paper | ours (mean ± sd, n) | difference | verdict | likely reason |\n|---|---|---|---|---|---|\n");
        for r in &self.comparison {
            let verdict = if r.verdict == "differs" {
                "**differs**".to_string()
            } else {
                r.verdict.clone()
            };
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {verdict} | {} |",
                r.quantity,
                r.paper,
                fmt_agg(r.ours),
                r.sigma.map_or("—".into(), |x| format!("{x:+.1}σ")),
                r.reason
            );
        }
        s.push('\n');
        s
    }

    /// Every fit drawn on the figures, with its constants.
    fn fits_table(&self) -> String {
        let fits: Vec<(&str, &crate::figure::FitData)> = self
            .figures
            .iter()
            .flat_map(|f| f.fits.iter().map(move |x| (f.figure.as_str(), x)))
            .collect();
        if fits.is_empty() {
            return String::new();
        }
        let mut s = String::from("## Fits\n\nEach constant with its standard error and 95 % interval (Student's t); R² of the unweighted means.\n\n| figure | fit | constants | R² | points |\n|---|---|---|---|---|\n");
        for (figure, f) in fits {
            let (constants, r2, points) = match &f.fit {
                Some(fit) => (
                    fit.params
                        .iter()
                        .map(|p| {
                            format!(
                                "{} = {:.4} ± {:.4} [{:.4}, {:.4}]",
                                p.name, p.value, p.se, p.lo, p.hi
                            )
                        })
                        .collect::<Vec<_>>()
                        .join("; "),
                    format!("{:.4}", fit.r2),
                    fit.points.to_string(),
                ),
                None => (
                    format!("no fit: {}", f.error.as_deref().unwrap_or("")),
                    "—".into(),
                    "—".into(),
                ),
            };
            let _ = writeln!(
                s,
                "| {figure} | {} | {constants} | {r2} | {points} |",
                f.label
            );
        }
        s.push('\n');
        s
    }

    fn points_tables(&self) -> String {
        let mut s = String::from("## Points\n\n");
        for d in &self.sweeps {
            let _ = writeln!(s, "### {}\n\nSweep `{}`.\n", d.title, d.id);
            let shown: Vec<&(String, String)> = self
                .metric_labels
                .iter()
                .filter(|(m, _)| {
                    d.points
                        .iter()
                        .any(|p| p.metrics.get(m).is_some_and(|a| a.n > 0))
                })
                .collect();
            let _ = write!(s, "| point | samples | failed |");
            for (_, label) in &shown {
                let _ = write!(s, " {label} |");
            }
            let _ = writeln!(s, "\n|---|---|---|{}", "---|".repeat(shown.len()));
            let named = crate::papers::find(&self.paper).map(|paper| paper.point_label);
            for p in &d.points {
                let label = named
                    .and_then(|f| f(&p.point))
                    .unwrap_or_else(|| point_label(p));
                let _ = write!(s, "| {label} | {} | {} |", p.samples, p.failures);
                for (m, _) in &shown {
                    let _ = write!(s, " {} |", fmt_agg(p.metrics.get(m).copied()));
                }
                s.push('\n');
            }
            s.push('\n');
        }
        s
    }
}

fn stem(out: &Path) -> String {
    out.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("reproduction")
        .to_string()
}

/// A figure key as it appears in file names (`3` → `fig3`, `k_n` stays).
pub fn file_key(figure: &str) -> String {
    if figure.starts_with(|c: char| c.is_ascii_digit()) {
        format!("fig{figure}")
    } else {
        figure.to_string()
    }
}

fn point_label(p: &Point) -> String {
    if p.point.is_empty() {
        return "(single point)".into();
    }
    p.point
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

//! What an unfinished run has left: the queued samples' particle-steps by
//! their protocols' estimates, each scaled by what its nearest finished
//! samples took against theirs, and the CPU time that costs at the
//! finished samples' own rate.
//!
//! A protocol's estimate follows the run's scales (its time step, its
//! √(d/g)), but not how long a heap of a given cohesion takes to stop: on
//! the glass reproduction the finished samples took 0.3–1.6 times their
//! estimates, yet a size kept its ratio within some 15 % from one gravity
//! to the next. So a queued sample is scaled by the finished samples of
//! its sweep that share the most axis values with it (its size, say), of
//! those that ran their whole course: a heap stopped early because its
//! crest reached the top says nothing of what a whole heap costs.

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// One sample of a sweep, as the estimate reads it.
#[derive(Debug, Clone, PartialEq)]
pub struct Costed {
    /// The axis values of its point.
    pub point: Map<String, Value>,
    /// Its protocol's estimate of its particle-steps.
    pub estimate: f64,
    /// What it took, if it has finished.
    pub took: Option<Took>,
}

/// What a finished sample took.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Took {
    pub particle_steps: f64,
    /// CPU time, s.
    pub cpu_s: f64,
    /// Whether it ran its whole course (not stopped early by its protocol).
    pub completed: bool,
}

impl Costed {
    fn estimated(&self) -> bool {
        self.estimate.is_finite() && self.estimate > 0.0
    }

    /// Took over estimate, for a finished sample that ran its whole course.
    fn ratio(&self) -> Option<f64> {
        let t = self.took?;
        (t.completed && self.estimated()).then(|| t.particle_steps / self.estimate)
    }

    /// How many axis values it shares with `other`.
    fn shared(&self, other: &Costed) -> usize {
        let same = |(k, v): (&String, &Value)| other.point.get(k) == Some(v);
        self.point.iter().filter(|e| same(*e)).count()
    }
}

/// The estimate of what is left.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Remaining {
    /// Samples still to run.
    pub samples: u64,
    /// Their particle-steps, scaled.
    pub particle_steps: f64,
    /// The CPU time they take at `rate`, s.
    pub cpu_s: f64,
    /// Particle-steps per CPU-second of the finished samples.
    pub rate: f64,
    /// The least and the largest ratio of took to estimate of a finished
    /// sample that ran its whole course.
    pub spread: [f64; 2],
}

impl Remaining {
    /// The estimate over `sweeps` (each its samples), or `None` if nothing
    /// is left, or no finished sample ran its whole course to scale by.
    pub fn of(sweeps: &[Vec<Costed>]) -> Option<Remaining> {
        let all = || sweeps.iter().flatten();
        let (steps, cpu) = all()
            .filter_map(|c| c.took)
            .fold((0.0, 0.0), |(s, t), took| {
                (s + took.particle_steps, t + took.cpu_s)
            });
        let ratios = || all().filter_map(Costed::ratio);
        let spread = ratios().fold([f64::INFINITY, 0.0], |[lo, hi], r| [lo.min(r), hi.max(r)]);
        let overall = scale(all())?;
        let (mut samples, mut left) = (0, 0.0);
        for sweep in sweeps {
            for c in sweep.iter().filter(|c| c.estimated() && c.took.is_none()) {
                samples += 1;
                left += c.estimate * nearest(c, sweep).unwrap_or(overall);
            }
        }
        (samples > 0 && cpu > 0.0).then(|| Remaining {
            samples,
            particle_steps: left,
            cpu_s: left * cpu / steps,
            rate: steps / cpu,
            spread,
        })
    }

    /// One sentence for a report.
    pub fn sentence(&self) -> String {
        format!(
            "The {} samples left are estimated at {:.2e} particle-steps, about {:.1} core-hours \
             at the finished samples' {:.1} M particle-steps per CPU-second: each sample's \
             estimate by its protocol, scaled by what the whole runs of its sweep that share the \
             most axis values with it took against theirs ({:.2}–{:.2} times, run by run; a run \
             its protocol stopped early scales nothing); a sample resumed from a checkpoint \
             counts whole.",
            self.samples,
            self.particle_steps,
            self.cpu_s / 3600.0,
            self.rate / 1e6,
            self.spread[0],
            self.spread[1]
        )
    }
}

/// The scale of the samples of `sweep` that ran their whole course and
/// share the most axis values with `queued`.
fn nearest(queued: &Costed, sweep: &[Costed]) -> Option<f64> {
    let whole = || sweep.iter().filter(|c| c.ratio().is_some());
    let most = whole().map(|c| queued.shared(c)).max()?;
    scale(whole().filter(|c| queued.shared(c) == most))
}

/// Took over estimate, summed over the samples among `samples` that ran
/// their whole course.
fn scale<'a>(samples: impl Iterator<Item = &'a Costed>) -> Option<f64> {
    let (took, estimated) = samples
        .filter(|c| c.ratio().is_some())
        .filter_map(|c| Some((c.took?.particle_steps, c.estimate)))
        .fold((0.0, 0.0), |(a, b), (t, e)| (a + t, b + e));
    (estimated > 0.0).then_some(took / estimated)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn at(d: f64, g: f64, estimate: f64, took: Option<(f64, f64, bool)>) -> Costed {
        let point = json!({"d": d, "g": g}).as_object().cloned().unwrap();
        let took = took.map(|(particle_steps, cpu_s, completed)| Took {
            particle_steps,
            cpu_s,
            completed,
        });
        Costed {
            point,
            estimate,
            took,
        }
    }

    #[test]
    fn a_queued_sample_is_scaled_by_the_whole_runs_nearest_it() {
        // Size 1 took twice its estimate, size 2 half of its; a tower of
        // size 4 at g 0.1, stopped early, calibrates nothing but counts
        // for the rate. A queued size 1 at g 0.1 takes size 1's ratio, a
        // queued size 3 at the same gravity as both takes theirs together,
        // (200 + 50) / (100 + 100), and so does a sweep with none finished.
        let sweeps = vec![
            vec![
                at(1.0, 1.0, 100.0, Some((200.0, 2.0, true))),
                at(2.0, 1.0, 100.0, Some((50.0, 0.5, true))),
                at(4.0, 0.1, 100.0, Some((10.0, 0.1, false))),
                at(1.0, 0.1, 10.0, None),
                at(3.0, 1.0, 8.0, None),
            ],
            vec![at(1.0, 1.0, 4.0, None)],
        ];
        let r = Remaining::of(&sweeps).unwrap();
        assert_eq!(r.samples, 3);
        let left = 2.0 * 10.0 + 1.25 * 8.0 + 1.25 * 4.0;
        assert!((r.particle_steps - left).abs() < 1e-12, "{r:?}");
        assert!((r.rate - 100.0).abs() < 1e-12);
        assert!((r.cpu_s - left / 100.0).abs() < 1e-12);
        assert_eq!(r.spread, [0.5, 2.0]);
        let said = r.sentence();
        assert!(
            said.starts_with("The 3 samples left are estimated at 3.50e1"),
            "{said}"
        );
        assert!(said.contains("(0.50–2.00 times"), "{said}");
    }

    #[test]
    fn nothing_left_or_nothing_to_scale_by_gives_no_estimate() {
        let done = at(1.0, 1.0, 1.0, Some((2.0, 1.0, true)));
        let queued = at(2.0, 1.0, 1.0, None);
        assert_eq!(Remaining::of(&[vec![done.clone()]]), None);
        assert_eq!(Remaining::of(&[vec![queued.clone()]]), None);
        // Neither a sample its protocol cannot estimate nor one stopped
        // early scales the queue.
        let unestimated = Costed {
            estimate: f64::NAN,
            ..done.clone()
        };
        assert_eq!(Remaining::of(&[vec![unestimated, queued.clone()]]), None);
        let stopped = at(1.0, 1.0, 1.0, Some((2.0, 1.0, false)));
        assert_eq!(Remaining::of(&[vec![stopped, queued]]), None);
        assert_eq!(Remaining::of(&[]), None);
    }
}

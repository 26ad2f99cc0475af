//! Sweep specifications and their expansion into jobs.
//!
//! A sweep names a protocol, a base scene, axes (lists of values for any
//! scene key, written as dotted paths such as `contact.mu`), the number of
//! samples per point, a fidelity preset and a seed base. Expansion builds
//! one fully resolved scene per (point, sample) and validates each with the
//! physics crate's own checks, so a sweep is refused exactly when one of
//! its scenes would be.

use repose_physics::doc;
use repose_physics::preset::Preset;
use repose_physics::scene::{FieldError, Scene, SceneError};
use repose_physics::{registry, ENGINE};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;

/// The largest number of jobs one sweep may expand into.
pub const MAX_JOBS: usize = 100_000;

/// The fidelity preset of a sweep (the physics crate's [`Preset`]).
pub type Fidelity = Preset;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// A name to show; defaults to the protocol and the axes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A registered protocol.
    pub protocol: String,
    /// Scene values shared by every job (any key of the scene document
    /// except `protocol` and `seed`).
    #[serde(default)]
    #[schema(value_type = Object)]
    pub base: Map<String, Value>,
    /// Values to sweep, by dotted scene key.
    #[serde(default)]
    #[schema(value_type = HashMap<String, Vec<Object>>)]
    pub axes: BTreeMap<String, Vec<Value>>,
    /// Samples (seeds) per point; with `target_sem`, the least a point gets.
    #[serde(default = "one")]
    pub samples: u32,
    /// Add samples to each point until the standard error of
    /// `target_metric` there is at most this (in the metric's unit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_sem: Option<f64>,
    /// The metric `target_sem` is for (default: the protocol's headline metric).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_metric: Option<String>,
    /// The most samples a point gets while it chases `target_sem`
    /// (default: ten times `samples`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_samples: Option<u32>,
    #[serde(default)]
    #[schema(value_type = String, example = "standard")]
    pub fidelity: Fidelity,
    /// Sample `k` of every point runs with seed `seed_base + k`.
    #[serde(default)]
    pub seed_base: u64,
    /// Higher runs first.
    #[serde(default)]
    pub priority: i64,
    /// The order of the sweep's jobs in the queue.
    #[serde(default, skip_serializing_if = "Order::is_listed")]
    pub order: Order,
    /// The study sweep this one queues (`paper/sweep`, e.g. `lh93/fig347`),
    /// if it was queued from a paper's figures. Set by the server: a sweep
    /// posted with it is refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(read_only)]
    pub study: Option<String>,
}

fn one() -> u32 {
    1
}

/// The order in which a sweep's jobs are queued.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// Point by point, in the order of the axes' values, each point's
    /// samples together.
    #[default]
    Listed,
    /// The cheapest samples first, by the protocol's estimate of their
    /// particle-steps (in listed order where it makes none, after those it
    /// ranks): an interrupted sweep has then finished as many points as
    /// its time allowed.
    Cheapest,
}

impl Order {
    fn is_listed(&self) -> bool {
        *self == Order::Listed
    }
}

impl std::str::FromStr for Order {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "listed" => Ok(Order::Listed),
            "cheapest" => Ok(Order::Cheapest),
            other => Err(format!("`{other}` is no order: `listed` or `cheapest`")),
        }
    }
}

/// One job of an expanded sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct JobSpec {
    /// The axis values of this job's point.
    pub point: Map<String, Value>,
    pub sample: u32,
    pub seed: u64,
    /// The fully resolved scene, as stored and run.
    pub scene: Scene,
    /// Identity of the sample: SHA-256 of the canonical scene and the engine version.
    pub sample_hash: String,
}

impl JobSpec {
    /// Its protocol's estimate of the sample's particle-steps, if the
    /// protocol makes one: good for ranking samples and, scaled by what
    /// finished samples took against theirs, for what a queue has left.
    pub fn estimated_cost(&self) -> Option<f64> {
        self.scene.protocol().ok()?.cost(&self.scene)
    }
}

fn field_error(field: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError {
        errors: vec![FieldError {
            field: field.into(),
            message: message.into(),
        }],
    }
}

impl SweepSpec {
    /// A display name: the given one, or the protocol and the swept keys.
    pub fn display_name(&self) -> String {
        self.name.clone().unwrap_or_else(|| {
            let axes: Vec<&str> = self.axes.keys().map(|k| k.as_str()).collect();
            if axes.is_empty() {
                self.protocol.clone()
            } else {
                format!("{} over {}", self.protocol, axes.join(" × "))
            }
        })
    }

    /// Number of jobs the sweep expands into (saturating).
    pub fn job_count(&self) -> usize {
        self.axes
            .values()
            .fold(self.samples as usize, |n, v| n.saturating_mul(v.len()))
    }

    /// Validates the spec and builds every job, in (point, sample) order or,
    /// with [`Order::Cheapest`], ranked by the estimated cost.
    pub fn expand(&self) -> Result<Vec<JobSpec>, SceneError> {
        self.check()?;
        let mut jobs = Vec::with_capacity(self.job_count());
        for (point, doc) in self.point_docs()? {
            for sample in 0..self.samples {
                jobs.push(job(&point, &doc, self.seed_base, sample)?);
            }
        }
        if self.order == Order::Cheapest {
            let mut ranked: Vec<(Option<f64>, JobSpec)> =
                jobs.into_iter().map(|j| (j.estimated_cost(), j)).collect();
            // Stable: equal costs keep their listed order; unranked go last.
            ranked.sort_by(|(a, _), (b, _)| {
                let ranked_first = a.is_none().cmp(&b.is_none());
                ranked_first.then(a.unwrap_or(0.0).total_cmp(&b.unwrap_or(0.0)))
            });
            jobs = ranked.into_iter().map(|(_, j)| j).collect();
        }
        Ok(jobs)
    }

    /// Jobs for samples `from..from + count` of one point of the sweep
    /// (the samples `target_sem` adds).
    pub fn more_samples(
        &self,
        point: &Map<String, Value>,
        from: u32,
        count: u32,
    ) -> Result<Vec<JobSpec>, SceneError> {
        let (_, doc) = self
            .point_docs()?
            .into_iter()
            .find(|(p, _)| p == point)
            .ok_or_else(|| field_error("axes", "no such point in the sweep"))?;
        (from..from.saturating_add(count))
            .map(|sample| job(point, &doc, self.seed_base, sample))
            .collect()
    }

    /// The largest number of samples a point may get, and whether it
    /// chases a standard error at all.
    pub fn max_samples_per_point(&self) -> u32 {
        match self.target_sem {
            Some(_) => self
                .max_samples
                .unwrap_or_else(|| self.samples.saturating_mul(10)),
            None => self.samples,
        }
    }

    /// The metric `target_sem` is for.
    pub fn target_metric(&self) -> Option<String> {
        self.target_sem?;
        self.target_metric.clone().or_else(|| {
            registry::find_protocol(&self.protocol)
                .and_then(|p| p.metrics().first().map(|m| m.name.to_string()))
        })
    }

    /// Checks everything but the scenes themselves.
    fn check(&self) -> Result<(), SceneError> {
        if registry::find_protocol(&self.protocol).is_none() {
            return Err(field_error(
                "protocol",
                format!(
                    "unknown protocol `{}`: expected one of {}",
                    self.protocol,
                    registry::protocol_names().join(", ")
                ),
            ));
        }
        if self.samples == 0 {
            return Err(field_error("samples", "must be at least 1"));
        }
        for key in ["protocol", "seed", "preset"] {
            if self.base.contains_key(key) {
                return Err(field_error(
                    format!("base.{key}"),
                    format!("`{key}` is set by the sweep itself"),
                ));
            }
        }
        for (key, values) in &self.axes {
            if values.is_empty() {
                return Err(field_error(
                    format!("axes.{key}"),
                    "an axis needs at least one value",
                ));
            }
            if key == "protocol" || key == "seed" || key == "preset" {
                return Err(field_error(format!("axes.{key}"), "cannot be swept"));
            }
        }
        self.check_target()?;
        let points = self.job_count() / self.samples as usize;
        let total = points.saturating_mul(self.max_samples_per_point() as usize);
        if total > MAX_JOBS {
            return Err(field_error(
                "axes",
                format!(
                    "the sweep may expand into {total} jobs, more than the limit of {MAX_JOBS}"
                ),
            ));
        }
        if self
            .seed_base
            .checked_add(self.max_samples_per_point() as u64)
            .is_none_or(|s| s > i64::MAX as u64)
        {
            return Err(field_error(
                "seed_base",
                "seed_base + samples must stay below 2^63",
            ));
        }
        Ok(())
    }

    /// `target_sem`, `target_metric` and `max_samples` agree.
    fn check_target(&self) -> Result<(), SceneError> {
        let Some(target) = self.target_sem else {
            if self.target_metric.is_some() || self.max_samples.is_some() {
                return Err(field_error(
                    "target_sem",
                    "target_metric and max_samples go with target_sem",
                ));
            }
            return Ok(());
        };
        if !(target.is_finite() && target > 0.0) {
            return Err(field_error("target_sem", "must be a positive number"));
        }
        let metric = self.target_metric().unwrap_or_default();
        let known = registry::find_protocol(&self.protocol)
            .map(|p| {
                p.metrics()
                    .iter()
                    .map(|m| m.name.to_string())
                    .collect::<Vec<_>>()
            })
            .unwrap_or_default();
        if !known.contains(&metric) {
            return Err(field_error(
                "target_metric",
                format!(
                    "`{metric}` is not a metric of {}: expected one of {}",
                    self.protocol,
                    known.join(", ")
                ),
            ));
        }
        if self.max_samples_per_point() < self.samples.max(2) {
            return Err(field_error(
                "max_samples",
                "must be at least samples, and at least 2 for a standard error",
            ));
        }
        Ok(())
    }

    /// Every point of the sweep with its scene document (without seed).
    fn point_docs(&self) -> Result<Vec<PointDoc>, SceneError> {
        let mut base = self.base.clone();
        base.insert("protocol".into(), Value::from(self.protocol.clone()));
        base.insert("preset".into(), Value::from(self.fidelity.name()));
        let keys: Vec<&String> = self.axes.keys().collect();
        let mut out = Vec::new();
        let mut index = vec![0usize; keys.len()];
        loop {
            let mut point = Map::new();
            let mut doc = base.clone();
            for (k, key) in keys.iter().enumerate() {
                let value = self.axes[*key][index[k]].clone();
                doc::set(&mut doc, key, value.clone())
                    .map_err(|e| field_error(format!("axes.{key}"), e.message))?;
                point.insert((*key).clone(), value);
            }
            out.push((point, doc));
            // Next point: odometer over the axes, last key fastest.
            let mut k = keys.len();
            loop {
                if k == 0 {
                    return Ok(out);
                }
                k -= 1;
                index[k] += 1;
                if index[k] < self.axes[keys[k]].len() {
                    break;
                }
                index[k] = 0;
            }
        }
    }
}

/// A point's axis values and its scene document (without the seed).
type PointDoc = (Map<String, Value>, Map<String, Value>);

/// Sample `sample` of a point: its resolved, validated scene and hash.
fn job(
    point: &Map<String, Value>,
    doc: &Map<String, Value>,
    seed_base: u64,
    sample: u32,
) -> Result<JobSpec, SceneError> {
    let seed = seed_base + sample as u64;
    let mut scene_doc = doc.clone();
    scene_doc.insert("seed".into(), Value::from(seed));
    let scene = Scene::from_json(Value::Object(scene_doc)).map_err(|e| locate(e, point))?;
    let scene = scene.resolved();
    let sample_hash = sample_hash(&scene);
    Ok(JobSpec {
        point: point.clone(),
        sample,
        seed,
        scene,
        sample_hash,
    })
}

impl SweepSpec {
    /// The sweep as the store keeps it.
    pub fn new_sweep(&self) -> repose_store::NewSweep {
        repose_store::NewSweep {
            name: self.display_name(),
            protocol: self.protocol.clone(),
            spec: serde_json::to_value(self).unwrap_or(Value::Null),
            priority: self.priority,
            study: self.study.clone(),
        }
    }
}

impl JobSpec {
    /// The job as the store keeps it.
    pub fn to_new_job(&self) -> repose_store::NewJob {
        repose_store::NewJob {
            point: self.point.clone(),
            sample: self.sample,
            seed: self.seed,
            sample_hash: self.sample_hash.clone(),
            scene: serde_json::to_string(&self.scene).unwrap_or_else(|_| "null".into()),
        }
    }
}

/// Points a scene error at the sweep's own fields: a key set by an axis is
/// reported as `axes.<key>`, anything else as `base.<key>`.
fn locate(mut err: SceneError, point: &Map<String, Value>) -> SceneError {
    for e in &mut err.errors {
        let swept = point
            .keys()
            .any(|k| e.field == *k || e.field.starts_with(&format!("{k}.")));
        e.field = if swept {
            format!("axes.{}", e.field)
        } else {
            format!("base.{}", e.field)
        };
        if !point.is_empty() {
            e.message = format!("{} (at {})", e.message, Value::Object(point.clone()));
        }
    }
    err
}

/// Scene settings that change how fast a sample runs and never its
/// numbers (`section.key`): a sample's identity leaves them out.
pub const SPEED_ONLY: [&str; 1] = ["numerics.threads"];

/// Whether setting `key` (`section.key`) changes a sample's speed alone.
pub fn speed_only(key: &str) -> bool {
    SPEED_ONLY.contains(&key)
}

/// A resolved scene as JSON (keys sorted) without the settings that
/// change its speed alone ([`SPEED_ONLY`]): threads change the speed of a
/// sample, never its numbers.
pub fn canonical(scene: &Scene) -> Value {
    let mut canonical = serde_json::to_value(scene).unwrap_or(Value::Null);
    for key in SPEED_ONLY {
        let Some((section, name)) = key.split_once('.') else {
            continue;
        };
        if let Some(table) = canonical.get_mut(section).and_then(Value::as_object_mut) {
            table.remove(name);
        }
    }
    canonical
}

/// SHA-256 of the [`canonical`] JSON of a resolved scene and the engine
/// version: the identity of a sample.
pub fn sample_hash(scene: &Scene) -> String {
    let mut h = Sha256::new();
    h.update(ENGINE.as_bytes());
    h.update([0u8]);
    h.update(canonical(scene).to_string().as_bytes());
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn spec(v: Value) -> SweepSpec {
        serde_json::from_value(v).unwrap()
    }

    #[test]
    fn cheapest_order_queues_large_grains_under_strong_gravity_first() {
        let sweep = |order: &str| {
            spec(json!({
                "protocol": "heap",
                "base": {"heap": {"plate": 20, "max_grains": 1500}},
                "axes": {"grains.diameter": [1e-4, 1e-3],
                         "gravity": [[0.0, 0.0, -1.62], [0.0, 0.0, -9.81]]},
                "samples": 2, "order": order
            }))
        };
        let listed = sweep("listed").expand().unwrap();
        let cheapest = sweep("cheapest").expand().unwrap();
        let cost = |j: &JobSpec| j.scene.protocol().unwrap().cost(&j.scene).unwrap();
        // The same samples, ranked by the estimate, each point's samples together.
        let hashes = |jobs: &[JobSpec]| {
            let mut h: Vec<String> = jobs.iter().map(|j| j.sample_hash.clone()).collect();
            h.sort();
            h
        };
        assert_eq!(hashes(&listed), hashes(&cheapest));
        assert!(cheapest.windows(2).all(|w| cost(&w[0]) <= cost(&w[1])));
        assert_eq!(cheapest[0].point, cheapest[1].point);
        assert_eq!(cheapest[0].point["grains.diameter"], json!(1e-3));
        assert_eq!(cheapest[0].point["gravity"], json!([0.0, 0.0, -9.81]));
        assert_eq!(cheapest[7].point["grains.diameter"], json!(1e-4));
        assert_eq!(cheapest[7].point["gravity"], json!([0.0, 0.0, -1.62]));
        // Smaller grains and weaker gravity take more steps a grain.
        assert!(cost(&cheapest[7]) > 3.0 * cost(&cheapest[0]));
        // Listed order is the axes' order, and the spec keeps no order field for it.
        assert_eq!(listed[0].point["grains.diameter"], json!(1e-4));
        assert!(serde_json::to_value(sweep("listed"))
            .unwrap()
            .get("order")
            .is_none());
        assert_eq!(
            serde_json::to_value(sweep("cheapest")).unwrap()["order"],
            "cheapest"
        );
    }

    #[test]
    fn a_sample_on_more_threads_is_the_same_sample_and_other_numerics_are_not() {
        let sweep = |numerics: Value| {
            spec(json!({
                "protocol": "heap",
                "base": {"heap": {"plate": 20, "max_grains": 1500}, "numerics": numerics},
                "axes": {"grains.diameter": [1e-4, 1e-3]},
                "samples": 2
            }))
            .expand()
            .unwrap()
        };
        let hashes = |jobs: &[JobSpec]| -> Vec<String> {
            jobs.iter().map(|j| j.sample_hash.clone()).collect()
        };
        let one = sweep(json!({"threads": 1}));
        let two = sweep(json!({"threads": 2}));
        assert_eq!(hashes(&one), hashes(&two));
        // The thread count still reaches the engine.
        assert_eq!(two[0].scene.numerics.threads, 2);
        assert_eq!(one[0].scene.numerics.threads, 1);
        // A setting that changes the numbers makes other samples.
        let finer = sweep(json!({"threads": 2, "dt_factor": 0.05}));
        assert!(hashes(&finer).iter().all(|h| !hashes(&one).contains(h)));
        assert!(SPEED_ONLY.iter().all(|k| speed_only(k)));
        assert!(!speed_only("numerics.dt_factor"));
    }

    #[test]
    fn a_scene_read_back_from_its_stored_text_is_the_same_sample() {
        // A step whose decimal text a best-effort parser reads one unit in
        // the last place off (…693e-8): the worker must run the scene stored.
        let dt: f64 = 1.869933361786569e-8;
        let jobs = spec(json!({
            "protocol": "heap",
            "base": {"heap": {"plate": 20, "max_grains": 1500}, "numerics": {"dt": dt}},
            "axes": {"grains.diameter": [6e-5, 1e-3]},
            "samples": 1
        }))
        .expand()
        .unwrap();
        for job in &jobs {
            let text = serde_json::to_string(&job.scene).unwrap();
            assert!(text.contains("1.869933361786569e-8"), "{text}");
            let back = Scene::from_stored(serde_json::from_str(&text).unwrap()).unwrap();
            assert_eq!(back.numerics.dt.map(f64::to_bits), Some(dt.to_bits()));
            assert_eq!(sample_hash(&back), job.sample_hash);
        }
    }

    #[test]
    fn cheapest_order_keeps_listed_order_where_the_protocol_estimates_nothing() {
        let s = spec(json!({
            "protocol": "fill_release",
            "base": {"box": {"width": 2.0, "height": 2.0}},
            "axes": {"box.width": [3.0, 2.0]},
            "samples": 2, "order": "cheapest"
        }));
        let jobs = s.expand().unwrap();
        let widths: Vec<f64> = jobs
            .iter()
            .map(|j| {
                j.scene.sections.value("box").unwrap()["width"]
                    .as_f64()
                    .unwrap()
            })
            .collect();
        assert_eq!(widths, [3.0, 3.0, 2.0, 2.0]);
        let bad =
            serde_json::from_value::<SweepSpec>(json!({"protocol": "heap", "order": "fastest"}));
        assert!(bad.unwrap_err().to_string().contains("fastest"));
        assert!("fastest"
            .parse::<Order>()
            .unwrap_err()
            .contains("`listed` or `cheapest`"));
    }

    #[test]
    fn expands_points_times_samples_with_seeds() {
        let s = spec(json!({
            "protocol": "fill_release",
            "base": {"box": {"width": 2.0, "height": 2.0}},
            "axes": {"contact.mu": [0.1, 0.2, 0.3], "box.width": [2.0, 3.0]},
            "samples": 4, "seed_base": 100
        }));
        let jobs = s.expand().unwrap();
        assert_eq!(jobs.len(), 24);
        assert_eq!(
            jobs[0].point,
            json!({"box.width": 2.0, "contact.mu": 0.1})
                .as_object()
                .unwrap()
                .clone()
        );
        assert_eq!(jobs[0].seed, 100);
        assert_eq!(jobs[3].seed, 103);
        // standard preset: Verlet; the resolved scene carries its time step
        assert_eq!(jobs[0].scene.numerics.integrator.name(), "verlet");
        assert_eq!(jobs[4].scene.sections.value("contact").unwrap()["mu"], 0.2);
        assert_eq!(jobs[23].scene.sections.value("box").unwrap()["width"], 3.0);
        assert_eq!(jobs[23].scene.sections.value("box").unwrap()["height"], 2.0);
        assert!(jobs[0].scene.numerics.dt.is_some());
        let hashes: std::collections::HashSet<_> = jobs.iter().map(|j| &j.sample_hash).collect();
        assert_eq!(hashes.len(), 24);
    }

    #[test]
    fn same_scene_and_seed_hash_alike_across_sweeps() {
        let a = spec(json!({"protocol": "tilt", "axes": {"contact.mu": [0.2]}, "samples": 2}));
        let b = spec(json!({"protocol": "tilt", "base": {"contact": {"mu": 0.2}}, "samples": 3}));
        let (ja, jb) = (a.expand().unwrap(), b.expand().unwrap());
        assert_eq!(ja[1].sample_hash, jb[1].sample_hash);
        assert_ne!(ja[0].sample_hash, ja[1].sample_hash);
    }

    #[test]
    fn bad_sweeps_name_the_field() {
        let cases = [
            (
                json!({"protocol": "tilt", "axes": {"contact.mu": []}}),
                "axes.contact.mu",
            ),
            (
                json!({"protocol": "tilt", "axes": {"contact.mu": [0.1, -0.2]}}),
                "axes.contact.mu",
            ),
            (
                json!({"protocol": "tilt", "axes": {"contact.mu": ["x"]}}),
                "axes.contact.mu",
            ),
            (
                json!({"protocol": "tilt", "base": {"box": {"width": -1}}}),
                "base.box.width",
            ),
            (json!({"protocol": "tilt", "samples": 0}), "samples"),
            (
                json!({"protocol": "tilt", "axes": {"contact.mu": vec![0.1; 1000], "box.width": vec![4.0; 1000]}}),
                "axes",
            ),
            (
                json!({"protocol": "tilt", "base": {"seed": 3}}),
                "base.seed",
            ),
            (
                json!({"protocol": "flux", "base": {"numerics": 1}}),
                "base.numerics",
            ),
            (json!({"protocol": "sideways"}), "protocol"),
        ];
        for (v, field) in cases {
            let err = spec(v.clone()).expand().unwrap_err();
            assert_eq!(err.errors[0].field, field, "{v}: {err}");
        }
    }
}

//! The packing column of Elekes & Parteli's fig. 5: grains released from
//! rest at a low solid fraction in a tall column, periodic sideways, settle
//! on a plate; the packing fraction is read in the middle of the bed.

use super::pour::{self, Placer, PourJob, Region};
use super::runner::Findings;
use super::{Metric, Observer, Protocol};
use crate::models::elekes_parteli::{Grains, Material};
use crate::models::{self, EngineJob, Laws};
use crate::preset::Preset;
use crate::report::{Curve, Outcome, Phase, RunReport};
use crate::scene::{Checks, Scene, SceneError, Section, MAX_GRAINS};
use crate::setup::Stream;
use repose_engine::contact::ContactLaw;
use repose_engine::dim::Vector;
use repose_engine::integrate::Integrator;
use repose_engine::particles::Particles;
use repose_engine::simulation::Simulation;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

pub struct Packing;

pub const SETTLE: Phase = Phase("settle");

/// The column, lengths in grain diameters `d` and times in `√(d/g)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PackingSpec {
    /// Side of the square cross-section (periodic), d.
    pub width: f64,
    /// Height of the column the grains start in, d.
    pub height: f64,
    /// Solid fraction of the grains released.
    pub fill_fraction: f64,
    /// The bed is at rest when the translational kinetic energy per grain
    /// is below this, in m g d ...
    pub rest_energy: f64,
    /// ... leaving out this fraction of its grains, the most energetic
    /// (rounded up to whole grains): pairs that spin about a lone
    /// contact, which the contact model does not resist, never stop.
    pub rest_exempt: f64,
    /// Least time to settle, √(d/g).
    pub settle_min: f64,
    /// Most time to settle, √(d/g).
    pub settle_max: f64,
    /// The part of the bed measured, as fractions of the highest centre.
    pub slab: [f64; 2],
}

impl Default for PackingSpec {
    fn default() -> Self {
        PackingSpec {
            width: 17.0,
            height: 100.0,
            fill_fraction: 0.2,
            rest_energy: 1e-6,
            rest_exempt: 0.005,
            settle_min: 20.0,
            settle_max: 400.0,
            slab: [0.3, 0.7],
        }
    }
}

impl PackingSpec {
    /// The number of grains of diameter `d` the column holds at the fill fraction.
    pub fn grain_count(&self) -> usize {
        let volume = self.width * self.width * self.height;
        (self.fill_fraction * volume / pour::GRAIN_VOLUME).round() as usize
    }
}

impl pour::Budget for PackingSpec {
    /// Every grain, from the release through the fall of the column's
    /// height (from rest, √(2 h) in √(d/g)) to the least settling time.
    fn grain_time(&self) -> f64 {
        self.grain_count() as f64 * ((2.0 * self.height).sqrt() + self.settle_min)
    }
}

impl Section for PackingSpec {
    const KEY: &'static str = "packing";
    const ABOUT: &'static str =
        "the column: periodic cross-section, height, release fraction, settling, measured slab (lengths in d, times in √(d/g))";

    fn check(&self, scene: &Scene, c: &mut Checks) {
        c.positive("packing.width", self.width);
        c.positive("packing.height", self.height);
        let settle = [
            self.rest_energy,
            self.rest_exempt,
            self.settle_min,
            self.settle_max,
        ];
        pour::check_fill_and_settling(c, "packing", self.fill_fraction, settle);
        let [lo, hi] = self.slab;
        if !(0.0 <= lo && lo < hi && hi <= 1.0) {
            c.fail("packing.slab", "needs 0 ≤ lower < upper ≤ 1");
        }
        if self.grain_count() > MAX_GRAINS {
            c.fail(
                "packing.height",
                format!("the column would hold more than {MAX_GRAINS} grains"),
            );
        }
        let (Ok(grains), Ok(m)) = (scene.section::<Grains>(), scene.section::<Material>()) else {
            return;
        };
        // A grain must meet at most one image of another across the faces.
        let range = if m.coheres() { m.d_max } else { 0.0 };
        let reach = 2.0 * grains.diameter_range().1 + scene.numerics.skin + range;
        if self.width * grains.diameter <= 2.0 * reach {
            c.fail(
                "packing.width",
                format!(
                    "{} d is too narrow for a periodic column: it must exceed {:.2} d",
                    self.width,
                    2.0 * reach / grains.diameter
                ),
            );
        }
    }
}

static METRICS: [Metric; 3] = [
    Metric {
        name: "packing_fraction",
        label: "φ",
        unit: "",
        description:
            "solid fraction of the grains centred between 0.3 and 0.7 of the highest centre",
        phase: "settle",
    },
    Metric {
        name: "packing_fraction_sd",
        label: "sd φ",
        unit: "",
        description: "standard deviation of the solid fraction over the four quarter columns",
        phase: "settle",
    },
    Metric {
        name: "bed_height",
        label: "bed",
        unit: "d",
        description: "height of the highest grain centre of the settled bed",
        phase: "settle",
    },
];

/// The column's presets: the pour's (`pour::preset`). Softening loosens a
/// cohesive column as it steepens a cohesive heap: at κ = 10⁶ 400 µm to
/// 100 µm glass beads on Earth pack 0.03–0.06 looser than at glass's
/// 63 GPa, and the packing fit's D_φ grows from 146 µm to 323 µm
/// (`docs/model-3d.md`, "Packed columns at glass stiffness"); `standard`
/// packs at the true modulus and `quick` keeps its softening and its bias.
///
/// The column's height moves φ too: a cohesive bed released from the
/// paper's 100 d packs denser than one released from 40 d (glass, 200 µm
/// on Earth: 0.529 against 0.496); its grains land faster and carry more
/// weight above them. Where a scene gives no height, `quick` releases its grains
/// from 40 d, at under half the particle-steps, and carries that bias too.
pub fn preset(preset: Preset) -> Vec<(&'static str, Value)> {
    match preset {
        Preset::Standard | Preset::Paper => pour::preset(preset),
        Preset::Quick => {
            let mut v = pour::preset(Preset::Quick);
            v.push(("packing.height", Value::from(QUICK_HEIGHT)));
            v
        }
    }
}

/// The column `quick` releases its grains from, in d.
pub const QUICK_HEIGHT: f64 = 40.0;

impl Protocol for Packing {
    pour::poured_protocol!(
        name: "packing",
        about: "release spheres from rest in a periodic column and measure the packing fraction φ of the settled bed",
        spec: PackingSpec,
        metrics: METRICS,
        presets: preset
    );

    fn run(&self, scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
        models::with_engine::<3, _>(scene, PourJob::<'_, PackingSpec>::of(scene, observer)?)?
    }
}

impl EngineJob<3> for PourJob<'_, PackingSpec> {
    type Output = Result<RunReport, SceneError>;

    fn run<L: ContactLaw<3>, I: Integrator<3>>(self, laws: Laws<L>) -> Self::Output {
        let s = self.scales;
        let sim = column::<L, I>(self.scene, &self.spec, &self.grains, s.d, laws)?;
        let mut run = pour::runner(self.scene, &s, self.observer, sim, self.spec.height);
        let rest = pour::Rest {
            energy: s.rest_energy(self.spec.rest_energy),
            exempt: self.spec.rest_exempt,
        };
        let window = (self.spec.settle_min * s.time, self.spec.settle_max * s.time);
        let mut findings = Findings::default();
        // Settling is the whole run: the engine is all its state.
        run.resume::<()>(&[SETTLE]);
        let outcome = match pour::settle(&mut run, SETTLE, 0.0, window, rest, &()) {
            Ok(()) => measure(&run.sim, &self.spec, s.d, &mut findings),
            Err(stop) => stop.outcome(SETTLE, || {
                format!(
                    "the bed still moved after {:.0} √(d/g) (kinetic energy per grain above {:.0e} m g d, leaving out the {} % most energetic grains)",
                    self.spec.settle_max, self.spec.rest_energy, 100.0 * self.spec.rest_exempt
                )
            }),
        };
        Ok(run.report(outcome, findings))
    }
}

/// The plate, the periodic cross-section and the grains released at rest.
fn column<L: ContactLaw<3>, I: Integrator<3>>(
    scene: &Scene,
    spec: &PackingSpec,
    grains: &Grains,
    d: f64,
    laws: Laws<L>,
) -> Result<Simulation<3, L, I>, SceneError> {
    let w = spec.width * d;
    let region = Region {
        lo: Vector::<3>::zeros(),
        hi: Vector::<3>::new(w, w, spec.height * d),
        straddle: [false; 3],
    };
    let mut placer = Placer::new(grains.diameter_range().1, Vector::<3>::zeros(), [w, w, 0.0]);
    let mut stream = Stream::new(scene.seed);
    let placed = pour::fill(
        &region,
        spec.fill_fraction,
        &mut placer,
        0.0,
        grains,
        &mut stream,
        spec.grain_count().max(1) * 2,
    );
    let mut particles = Particles::<3>::new(L::ROTATES);
    for (x, dia) in placed {
        particles.push(x, Vector::<3>::zeros(), 0.5 * dia, grains.mass(dia));
    }
    let mut sim = pour::on_floor(scene, particles, laws);
    sim.set_periodic(Vector::<3>::zeros(), [w, w, 0.0])
        .map_err(|e| SceneError::single("packing.width", e))?;
    Ok(sim)
}

/// Solid fraction of the slab, over the whole cross-section and each quarter.
fn measure<L: ContactLaw<3>, I: Integrator<3>>(
    sim: &Simulation<3, L, I>,
    spec: &PackingSpec,
    d: f64,
    findings: &mut Findings,
) -> Outcome {
    let p = &sim.particles;
    let top = p.pos.iter().map(|x| x.z).fold(0.0, f64::max);
    let (lo, hi) = (spec.slab[0] * top, spec.slab[1] * top);
    if p.len() < 8 || hi - lo < d {
        return Outcome::Unmeasurable {
            reason: format!(
                "the bed is {:.1} d high: too low to measure a packing fraction between {} and {} of it",
                top / d,
                spec.slab[0],
                spec.slab[1]
            ),
        };
    }
    let w = spec.width * d;
    let mut quarters = [0.0f64; 4];
    for i in 0..p.len() {
        let mut x = p.pos[i];
        if let Some(per) = &sim.periodic {
            per.wrap(&mut x);
        }
        if x.z >= lo && x.z < hi {
            let q = usize::from(x.x >= 0.5 * w) + 2 * usize::from(x.y >= 0.5 * w);
            quarters[q] += 4.0 / 3.0 * std::f64::consts::PI * p.radius[i].powi(3);
        }
    }
    let cell = 0.25 * w * w * (hi - lo);
    let phi: Vec<f64> = quarters.iter().map(|v| v / cell).collect();
    let mean = phi.iter().sum::<f64>() / 4.0;
    let sd = (phi.iter().map(|f| (f - mean).powi(2)).sum::<f64>() / 3.0).sqrt();
    findings.series.push(phi_of_height(sim, w, d, top));
    findings.metric("packing_fraction", mean);
    findings.metric("packing_fraction_sd", sd);
    findings.metric("bed_height", top / d);
    findings.details = json!({ "quarters": phi, "slab": [lo / d, hi / d] });
    Outcome::Completed
}

/// The packing fraction in horizontal slices half a diameter thick, from
/// the plate to above the highest grain: each sphere counted with the part
/// of its volume inside the slice.
fn phi_of_height<L: ContactLaw<3>, I: Integrator<3>>(
    sim: &Simulation<3, L, I>,
    w: f64,
    d: f64,
    top: f64,
) -> Curve {
    let dz = 0.5 * d;
    let slices = ((top + d) / dz).ceil().max(1.0) as usize;
    let mut volume = vec![0.0f64; slices];
    let p = &sim.particles;
    for i in 0..p.len() {
        let (zc, r) = (p.pos[i].z, p.radius[i]);
        let first = ((zc - r) / dz).floor().max(0.0) as usize;
        let last = (((zc + r) / dz).floor() as usize).min(slices - 1);
        for (k, v) in volume.iter_mut().enumerate().take(last + 1).skip(first) {
            *v += sphere_slice(zc, r, k as f64 * dz, (k + 1) as f64 * dz);
        }
    }
    let cell = w * w * dz;
    Curve {
        name: "phi_z".into(),
        title: "packing fraction against height".into(),
        x_label: "height (d)".into(),
        y_label: "packing fraction φ".into(),
        points: volume
            .iter()
            .enumerate()
            .map(|(k, v)| [(k as f64 + 0.5) * dz / d, v / cell])
            .collect(),
        band: None,
    }
}

/// The volume of a sphere (centre height `zc`, radius `r`) between the
/// heights `z1` and `z2`.
fn sphere_slice(zc: f64, r: f64, z1: f64, z2: f64) -> f64 {
    let a = (z1 - zc).max(-r);
    let b = (z2 - zc).min(r);
    if b <= a {
        return 0.0;
    }
    let cap = |z: f64| r * r * z - z * z * z / 3.0;
    std::f64::consts::PI * (cap(b) - cap(a))
}

#[cfg(test)]
mod tests {
    use super::sphere_slice;
    use crate::models::elekes_parteli::{Grains, Material};
    use crate::scene::Scene;

    /// The modulus a protocol's scene of 100 µm glass beads on Earth
    /// simulates under a preset.
    fn modulus(protocol: &str, preset: &str) -> f64 {
        let scene = Scene::from_toml(
            &format!(
                "protocol = \"{protocol}\"\npreset = \"{preset}\"\n\
                 [grains]\ndiameter = 1e-4\ndensity = 2500.0\n[material]\nsurface_energy = 0.05"
            ),
            &[],
        )
        .unwrap();
        let material: &Material = scene.section().unwrap();
        material.modulus(scene.section::<Grains>().unwrap(), 9.81)
    }

    #[test]
    fn a_bed_or_heap_that_would_exempt_half_its_grains_from_rest_is_refused() {
        for protocol in ["packing", "heap"] {
            for bad in ["0.5", "-0.1", "nan"] {
                let err = Scene::from_toml(
                    &format!("protocol = \"{protocol}\""),
                    &[format!("{protocol}.rest_exempt={bad}")],
                )
                .unwrap_err();
                let fields: Vec<&str> = err.errors.iter().map(|e| e.field.as_str()).collect();
                assert_eq!(fields, [format!("{protocol}.rest_exempt")], "{bad}: {err}");
            }
        }
    }

    #[test]
    fn standard_columns_are_glass_standard_heaps_a_tenth_of_it_and_quick_ones_softer() {
        let glass = modulus("packing", "paper");
        assert_eq!(glass, 6.3e10);
        assert_eq!(modulus("packing", "standard"), glass);
        assert!((modulus("heap", "standard") / glass - 0.1).abs() < 1e-12);
        for protocol in ["packing", "heap"] {
            assert_eq!(modulus(protocol, "paper"), glass, "{protocol}");
            assert!(modulus(protocol, "quick") < glass / 10.0, "{protocol}");
        }
    }

    #[test]
    fn quick_releases_a_column_from_40_d_unless_the_scene_says_otherwise() {
        let height = |preset: &str, set: &[String]| {
            let scene = Scene::from_toml(
                &format!("protocol = \"packing\"\npreset = \"{preset}\""),
                set,
            )
            .unwrap();
            scene.section::<super::PackingSpec>().unwrap().height
        };
        assert_eq!(height("quick", &[]), super::QUICK_HEIGHT);
        assert_eq!(height("standard", &[]), 100.0);
        assert_eq!(height("paper", &[]), 100.0);
        assert_eq!(height("quick", &["packing.height=70".into()]), 70.0);
    }

    #[test]
    fn slices_of_a_sphere_add_up_to_the_sphere() {
        let r = 0.7;
        let whole = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        let sum: f64 = (0..40)
            .map(|k| sphere_slice(1.0, r, 0.05 * k as f64, 0.05 * (k + 1) as f64))
            .sum();
        assert!((sum - whole).abs() < 1e-12 * whole);
        // The half below the centre is half the sphere; outside, nothing.
        assert!((sphere_slice(1.0, r, 0.0, 1.0) - 0.5 * whole).abs() < 1e-12);
        assert_eq!(sphere_slice(1.0, r, 2.0, 3.0), 0.0);
    }
}

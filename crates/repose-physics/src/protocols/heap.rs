//! The poured heap of Elekes & Parteli: grains rain from a narrow prism
//! onto a square plate with open edges, and the angle of repose is read off
//! the two side views of the settled heap.

use super::pour::{self, Placer, PourJob, Region, Scales};
use super::resume::SavedProtocol;
use super::runner::{Findings, Runner, Stop};
use super::{Metric, Observer, Protocol};
use crate::measure::Profile;
use crate::models::elekes_parteli::Grains;
use crate::models::{self, EngineJob, Laws};
use crate::preset::Preset;
use crate::report::{Curve, Outcome, Phase, RunReport};
use crate::scene::{Checks, Scene, SceneError, Section, MAX_GRAINS};
use crate::setup::Stream;
use repose_engine::contact::ContactLaw;
use repose_engine::dim::Vector;
use repose_engine::integrate::Integrator;
use repose_engine::particles::Particles;
use repose_engine::simulation::{Outlet, Simulation};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// Longest side of the plate and the domain's height, in diameters: the
/// heap's surface is measured on a grid of one column a diameter over the
/// plate, so a side of a thousand makes a million columns (the paper's
/// plate is 40).
const MAX_SIDE: f64 = 1000.0;

pub struct Heap;

pub const POUR: Phase = Phase("pour");
pub const SETTLE: Phase = Phase("settle");

/// The pouring protocol, lengths in grain diameters `d` and times in `√(d/g)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HeapSpec {
    /// Side of the square plate, d.
    pub plate: f64,
    /// Height of the domain above the plate, d.
    pub height: f64,
    /// Side of the square insertion prism, d.
    pub inlet_width: f64,
    /// Bottom of the insertion prism above the plate, d; once the heap is
    /// taller, only the space above its crest is used.
    pub inlet_floor: f64,
    /// Solid fraction the prism is filled to at each insertion.
    pub fill_fraction: f64,
    /// Where in the prism a new grain may lie (left out of a scene's
    /// stored form when `inside`, so that scenes written before it keep
    /// their identity).
    #[serde(skip_serializing_if = "InletFill::is_inside")]
    pub inlet_fill: InletFill,
    /// Time between insertions, √(d/g).
    pub interval: f64,
    /// Grains poured at most.
    pub max_grains: usize,
    /// The heap is at rest when the translational kinetic energy per grain
    /// is below this, in m g d ...
    pub rest_energy: f64,
    /// ... leaving out this fraction of its grains, the most energetic
    /// (rounded up to whole grains; 0, the default, leaves out none).
    pub rest_exempt: f64,
    /// Least time to settle after the last insertion, √(d/g).
    pub settle_min: f64,
    /// Most time to settle after the last insertion, √(d/g).
    pub settle_max: f64,
    /// Every this many grains poured, read the angle of the grains at rest
    /// and stop pouring once it has risen by no more than
    /// `steady_tolerance` since the last reading (0: pour `max_grains`).
    pub steady_every: usize,
    /// The rise of the angle between two readings below which the heap is
    /// at its angle of repose, °.
    pub steady_tolerance: f64,
}

impl Default for HeapSpec {
    fn default() -> Self {
        HeapSpec {
            plate: 40.0,
            height: 30.0,
            inlet_width: 4.4,
            inlet_floor: 20.0,
            fill_fraction: 0.2,
            inlet_fill: InletFill::Inside,
            interval: 3.5,
            max_grains: 25_000,
            rest_energy: 1e-6,
            rest_exempt: 0.0,
            settle_min: 20.0,
            settle_max: 400.0,
            steady_every: 0,
            steady_tolerance: 0.5,
        }
    }
}

/// Where the insertion prism places its grains across the stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InletFill {
    /// Every grain wholly inside the prism: centres at least a radius in
    /// from its sides, so the stream is a diameter narrower than the inlet.
    #[default]
    Inside,
    /// Centres anywhere in the prism's square, grains reaching up to a
    /// radius past its sides: the stream is as wide as the inlet, as
    /// LIGGGHTS's `fix insert/pack` fills its region by default
    /// (`all_in no`). Along the height grains stay wholly inside.
    Centres,
}

impl InletFill {
    fn is_inside(&self) -> bool {
        *self == InletFill::Inside
    }
}

impl pour::Budget for HeapSpec {
    /// The grain cap poured at the spec's rate (the prism filled to its
    /// fraction each interval), the heap growing evenly, then every grain
    /// through the least settling time.
    fn grain_time(&self) -> f64 {
        let prism = self.inlet_width * self.inlet_width * (self.height - self.inlet_floor).max(1.0);
        let per_insert = (self.fill_fraction * prism / pour::GRAIN_VOLUME).max(1.0);
        let grains = self.max_grains as f64;
        let pour_time = (grains / per_insert).ceil() * self.interval;
        grains * (0.5 * pour_time + self.settle_min)
    }
}

impl Section for HeapSpec {
    const KEY: &'static str = "heap";
    const ABOUT: &'static str =
        "the pour: plate, domain, insertion prism and rate, grain cap, settling (lengths in d, times in √(d/g))";

    fn check(&self, scene: &Scene, c: &mut Checks) {
        c.positive("heap.plate", self.plate);
        c.positive("heap.height", self.height);
        for (field, value) in [("heap.plate", self.plate), ("heap.height", self.height)] {
            if value > MAX_SIDE {
                c.fail(
                    field,
                    format!("{value} d is more than the limit of {MAX_SIDE} d"),
                );
            }
        }
        c.positive("heap.inlet_width", self.inlet_width);
        c.non_negative("heap.inlet_floor", self.inlet_floor);
        c.positive("heap.interval", self.interval);
        let settle = [
            self.rest_energy,
            self.rest_exempt,
            self.settle_min,
            self.settle_max,
        ];
        pour::check_fill_and_settling(c, "heap", self.fill_fraction, settle);
        if self.max_grains == 0 || self.max_grains > MAX_GRAINS {
            c.fail(
                "heap.max_grains",
                format!("must lie between 1 and {MAX_GRAINS}"),
            );
        }
        if self.inlet_width > self.plate {
            c.fail("heap.inlet_width", "must not exceed the plate");
        }
        c.positive("heap.steady_tolerance", self.steady_tolerance);
        let largest = scene
            .section::<Grains>()
            .map(|g| g.diameter_range().1 / g.diameter)
            .unwrap_or(1.0);
        if self.inlet_width < largest || self.height < self.inlet_floor + largest {
            c.fail(
                "heap.inlet_width",
                "the insertion prism must hold the largest grain (check heap.inlet_width, heap.inlet_floor and heap.height)",
            );
        }
    }
}

static METRICS: [Metric; 10] = [
    Metric {
        name: "theta_r",
        label: "θ_r",
        unit: "°",
        description: "angle of repose: mean over the two side views of atan(4A/b²), A the area under the heap's outline and b the plate",
        phase: "settle",
    },
    Metric {
        name: "theta_r_sd",
        label: "sd θ_r",
        unit: "°",
        description: "standard deviation of the angle between the two side views",
        phase: "settle",
    },
    Metric {
        name: "theta_r_footprint",
        label: "θ_r (footprint)",
        unit: "°",
        description: "the same angle with b the heap's own footprint in each view, for heaps that do not cover the plate",
        phase: "settle",
    },
    Metric {
        name: "theta_r_silhouette",
        label: "θ_r (silhouette)",
        unit: "°",
        description: "the angle with the plate as base read from the silhouette of the grains in each view (the upper boundary of their projection, sampled at d/20) instead of columns one diameter wide filled to their highest grain's top",
        phase: "settle",
    },
    Metric {
        name: "heap_grains",
        label: "N",
        unit: "grains",
        description: "grains in the settled heap",
        phase: "settle",
    },
    Metric {
        name: "heap_height",
        label: "H",
        unit: "d",
        description: "height of the settled heap's top",
        phase: "settle",
    },
    Metric {
        name: "surface_roughness",
        label: "roughness",
        unit: "d",
        description: "rms distance of the side views' outlines from their fitted triangles: small for a regular cone (regime II), large for an irregular heap (regime I)",
        phase: "settle",
    },
    Metric {
        name: "edge_height",
        label: "edge",
        unit: "d",
        description: "height of the outline at the plate's edges: grains that stay there in a layer add to the area under the outline, and so to θ_r, without steepening the heap's slope",
        phase: "settle",
    },
    Metric {
        name: "grains_poured",
        label: "poured",
        unit: "grains",
        description: "grains poured before the pour stopped",
        phase: "pour",
    },
    Metric {
        name: "pour_steady",
        label: "steady",
        unit: "",
        description: "1 if the pour stopped because the angle had stopped rising (heap.steady_every), else 0",
        phase: "pour",
    },
];

/// The fraction of the true modulus a `standard` heap is poured at.
pub const STANDARD_MODULUS_FRACTION: f64 = 0.1;

/// The heap's presets: the pour's (`pour::preset`), with `standard`
/// softened to a tenth of the true modulus at every grain size and gravity.
/// In the default contact form (the attraction fading in contact) a tenth
/// of glass's modulus holds a cohesive heap's angle: on the reduced heap it
/// stands within 1° of glass at 1 mm, 250 µm and 100 µm on Earth and at
/// 1 mm on the Moon and at g̃ = 10, for about a third of the
/// particle-steps; a hundredth stands 1.7° below glass at 1 mm
/// (`docs/model-3d.md`, "Softening, and its limits"). `paper` keeps the
/// true modulus. `standard` bounds the attraction's kick per
/// step to half of `√(g d)`: the step, and with it the kick, grows as
/// `Y^{−2/5}`, so the study's finest heap at its lowest gravity (60 µm,
/// g̃ = 0.063: 0.20 at glass) reaches the bound at a tenth; every heap
/// measured above stays far below it.
pub fn preset(preset: Preset) -> Vec<(&'static str, Value)> {
    let mut v = pour::preset(preset);
    if preset == Preset::Standard {
        v.push((
            "material.modulus_fraction",
            Value::from(STANDARD_MODULUS_FRACTION),
        ));
        v.push((
            "numerics.attraction_kick",
            Value::from(pour::ATTRACTION_KICK),
        ));
    }
    v
}

impl Protocol for Heap {
    pour::poured_protocol!(
        name: "heap",
        about: "pour spheres onto a plate with open edges and measure the settled heap's angle of repose θ_r",
        spec: HeapSpec,
        metrics: METRICS,
        presets: preset
    );

    fn run(&self, scene: &Scene, observer: &mut dyn Observer) -> Result<RunReport, SceneError> {
        models::with_engine::<3, _>(scene, PourJob::<'_, HeapSpec>::of(scene, observer)?)
    }
}

impl EngineJob<3> for PourJob<'_, HeapSpec> {
    type Output = RunReport;

    fn run<L: ContactLaw<3>, I: Integrator<3>>(self, laws: Laws<L>) -> RunReport {
        let sim = plate::<L, I>(self.scene, &self.spec, self.scales.d, laws);
        let s = self.scales;
        let mut run = pour::runner(self.scene, &s, self.observer, sim, self.spec.height);
        let (state, left) = run
            .resume::<(PourState, u64)>(&[POUR, SETTLE])
            .unwrap_or_else(|| (PourState::new(self.scene.seed), 0));
        let mut pour = Pour {
            spec: &self.spec,
            scales: s,
            grains: &self.grains,
            state,
            left,
        };
        let mut findings = Findings::default();
        let outcome = match pour.pour_and_settle(&mut run) {
            Ok(()) => measure(&run.sim.particles, &self.spec, s.d, &mut findings),
            Err(outcome) => outcome,
        };
        findings.inserted = pour.state.inserted;
        if outcome.is_completed() {
            findings.metric("grains_poured", pour.state.inserted as f64);
            findings.metric("pour_steady", f64::from(u8::from(pour.state.steady)));
        }
        findings.series.extend(pour.history());
        run.report(outcome, findings)
    }
}

/// The plate at z = 0 with the grains' material, and outlets at its edges.
fn plate<L: ContactLaw<3>, I: Integrator<3>>(
    scene: &Scene,
    spec: &HeapSpec,
    d: f64,
    laws: Laws<L>,
) -> Simulation<3, L, I> {
    let mut sim = pour::on_floor(scene, Particles::<3>::new(L::ROTATES), laws);
    let half = 0.5 * spec.plate * d;
    for axis in 0..2 {
        for sign in [-1.0, 1.0] {
            let mut normal = Vector::<3>::zeros();
            normal[axis] = sign;
            sim.outlets.push(Outlet {
                point: normal * half,
                normal,
            });
        }
    }
    sim
}

/// The pour.
struct Pour<'a> {
    spec: &'a HeapSpec,
    scales: Scales,
    grains: &'a Grains,
    state: PourState,
    /// Steps still to run before the next insertion: a checkpoint taken
    /// between two insertions saves them beside the state.
    left: u64,
}

/// What the pour carries from one insertion to the next besides the
/// engine: all a checkpoint needs of it.
#[derive(Serialize, Deserialize)]
struct PourState {
    stream: Stream,
    inserted: usize,
    /// `[time, crest]` before each insertion, in √(d/g) and d.
    crest: Vec<[f64; 2]>,
    /// `[time, grains]` at rest on the plate before each insertion.
    heap: Vec<[f64; 2]>,
    /// Simulated time of the last insertion that added grains, s.
    last_insertion: f64,
    /// `[grains poured, θ of the grains at rest]` at each reading of
    /// `steady_every`, °.
    #[serde(default)]
    readings: Vec<[f64; 2]>,
    /// Whether the pour stopped because the angle stopped rising.
    #[serde(default)]
    steady: bool,
}

impl PourState {
    fn new(seed: u64) -> PourState {
        PourState {
            stream: Stream::new(seed),
            inserted: 0,
            crest: Vec::new(),
            heap: Vec::new(),
            last_insertion: 0.0,
            readings: Vec::new(),
            steady: false,
        }
    }
}

/// The pour's state as a checkpoint holds it: the state at the last
/// insertion and the steps left before the next (formats 2 and 3 saved
/// only at insertions, so the state alone).
impl SavedProtocol for (PourState, u64) {
    type Format3 = PourState;
    fn upgrade(state: PourState) -> Self {
        (state, 0)
    }
}

impl Pour<'_> {
    fn pour_and_settle<L: ContactLaw<3>, I: Integrator<3>>(
        &mut self,
        run: &mut Runner<'_, 3, L, I>,
    ) -> Result<(), Outcome> {
        let s = self.scales;
        let steps = ((self.spec.interval * s.time / run.sim.dt).round() as u64).max(1);
        loop {
            if self.left == 0 {
                if !self.insert_next(run)? {
                    break;
                }
                self.left = steps;
            }
            self.pour_for(run)?;
        }
        let rest = pour::Rest {
            energy: s.rest_energy(self.spec.rest_energy),
            exempt: self.spec.rest_exempt,
        };
        let window = (self.spec.settle_min * s.time, self.spec.settle_max * s.time);
        let since = self.state.last_insertion;
        let saved = (&self.state, self.left);
        pour::settle(run, SETTLE, since, window, rest, &saved).map_err(|stop: Stop| {
            stop.outcome(SETTLE, || {
                let exempt = match self.spec.rest_exempt {
                    0.0 => String::new(),
                    x => format!(", leaving out the {} % most energetic grains", 100.0 * x),
                };
                format!(
                    "the heap still moved {:.0} √(d/g) after the last insertion (kinetic energy per grain above {:.0e} m g d{exempt})",
                    self.spec.settle_max, self.spec.rest_energy
                )
            })
        })
    }

    /// At an insertion, a resumable point: reads the angle if due, stops
    /// a heap whose crest reached the top and inserts the next grains.
    /// False once the pour is over (all grains poured, or the angle steady).
    fn insert_next<L: ContactLaw<3>, I: Integrator<3>>(
        &mut self,
        run: &mut Runner<'_, 3, L, I>,
    ) -> Result<bool, Outcome> {
        if self.state.inserted >= self.spec.max_grains || self.state.steady {
            return Ok(false);
        }
        run.checkpoint(&(&self.state, self.left));
        self.read_angle(&run.sim.particles);
        if self.state.steady {
            return Ok(false);
        }
        let s = self.scales;
        let (crest, resting) = crest(&run.sim.particles, 0.5 * (s.g * s.d).sqrt());
        let t = run.sim.time / s.time;
        self.state.crest.push([t, crest / s.d]);
        self.state.heap.push([t, resting as f64]);
        let top = self.spec.height * s.d;
        if crest > top - s.d {
            return Err(Outcome::Unmeasurable {
                reason: format!(
                    "the heap's crest reached the top of the domain ({:.1} d) after {} grains: no heap forms at this cohesion (regime I of Elekes & Parteli)",
                    self.spec.height, self.state.inserted
                ),
            });
        }
        let added = self.insert(&mut run.sim, crest.max(self.spec.inlet_floor * s.d));
        if added > 0 {
            self.state.last_insertion = run.sim.time;
        }
        Ok(true)
    }

    /// Runs the steps left before the next insertion a check at a time,
    /// each check a resumable point, so that a run asked to stop saves
    /// within a check instead of an interval between insertions (the
    /// same steps and samples as one stretch: every number is the same).
    fn pour_for<L: ContactLaw<3>, I: Integrator<3>>(
        &mut self,
        run: &mut Runner<'_, 3, L, I>,
    ) -> Result<(), Outcome> {
        while self.left > 0 {
            let chunk = run.check_steps.min(self.left);
            run.advance(POUR, chunk)
                .map_err(|stop| stop.outcome(POUR, String::new))?;
            self.left -= chunk;
            if self.left > 0 {
                run.checkpoint(&(&self.state, self.left));
            }
        }
        Ok(())
    }

    /// At each multiple of `steady_every` grains poured, reads the angle of
    /// the grains at rest and marks the pour steady if it has not risen by
    /// more than `steady_tolerance` since the last reading.
    fn read_angle(&mut self, p: &Particles<3>) {
        let every = self.spec.steady_every;
        let due = (self.state.readings.len() + 1) * every;
        if every == 0 || self.state.inserted < due {
            return;
        }
        let s = self.scales;
        let slow = 0.5 * (s.g * s.d).sqrt();
        let resting: Vec<usize> = (0..p.len())
            .filter(|&i| p.vel[i].norm_squared() < slow * slow)
            .collect();
        let pos: Vec<Vector<3>> = resting.iter().map(|&i| p.pos[i]).collect();
        let radius: Vec<f64> = resting.iter().map(|&i| p.radius[i]).collect();
        let half = 0.5 * self.spec.plate * s.d;
        let theta = (0..2)
            .filter_map(|axis| {
                let profile = Profile::measure(&pos, &radius, axis, -half, half);
                SideView::of(&profile, s.d, self.spec.plate)
            })
            .map(|v| 0.5 * v.theta_plate)
            .sum::<f64>();
        if let Some(&[_, last]) = self.state.readings.last() {
            self.state.steady = theta - last <= self.spec.steady_tolerance;
        }
        self.state
            .readings
            .push([self.state.inserted as f64, theta]);
    }

    /// Fills the insertion prism above `floor` to its solid fraction.
    fn insert<L: ContactLaw<3>, I: Integrator<3>>(
        &mut self,
        sim: &mut Simulation<3, L, I>,
        floor: f64,
    ) -> usize {
        let d = self.scales.d;
        let half = 0.5 * self.spec.inlet_width * d;
        let across = self.spec.inlet_fill == InletFill::Centres;
        let region = Region {
            lo: Vector::<3>::new(-half, -half, floor),
            hi: Vector::<3>::new(half, half, self.spec.height * d),
            straddle: [across, across, false],
        };
        let largest = self.grains.diameter_range().1;
        let mut placer = Placer::new(largest, Vector::<3>::zeros(), [0.0; 3]);
        let mut inside = 0.0;
        let p = &sim.particles;
        for i in 0..p.len() {
            let x = p.pos[i];
            let near =
                (0..3).all(|a| x[a] > region.lo[a] - largest && x[a] < region.hi[a] + largest);
            if near {
                placer.add(x, p.radius[i]);
            }
            if region.contains(&x) {
                inside += 4.0 / 3.0 * std::f64::consts::PI * p.radius[i].powi(3);
            }
        }
        let budget = self.spec.max_grains - self.state.inserted;
        let fraction = self.spec.fill_fraction;
        let new = pour::fill(
            &region,
            fraction,
            &mut placer,
            inside,
            self.grains,
            &mut self.state.stream,
            budget,
        );
        for (x, dia) in &new {
            sim.insert(*x, Vector::<3>::zeros(), 0.5 * dia, self.grains.mass(*dia));
        }
        self.state.inserted += new.len();
        new.len()
    }

    /// The pour history: the crest and the grains at rest before each
    /// insertion, and the angle at each reading.
    fn history(&self) -> [Curve; 3] {
        let curve = |name: &str, title: &str, y_label: &str, points: &[[f64; 2]]| Curve {
            name: name.into(),
            title: title.into(),
            x_label: "time (√(d/g))".into(),
            y_label: y_label.into(),
            points: points.to_vec(),
            band: None,
        };
        [
            curve(
                "crest",
                "height of the heap's crest before each insertion",
                "crest (d)",
                &self.state.crest,
            ),
            curve(
                "heap_grains",
                "pour history: grains at rest in the heap before each insertion",
                "grains in the heap",
                &self.state.heap,
            ),
            Curve {
                x_label: "grains poured".into(),
                ..curve(
                    "pour_angle",
                    "angle of the grains at rest while pouring (heap.steady_every)",
                    "θ_r (°)",
                    &self.state.readings,
                )
            },
        ]
    }
}

/// The highest grain top among grains slower than `slow` (grains still
/// falling from the prism do not count), m, and how many grains are that slow.
fn crest(p: &Particles<3>, slow: f64) -> (f64, usize) {
    let mut top = 0.0f64;
    let mut resting = 0;
    for i in 0..p.len() {
        if p.vel[i].norm_squared() < slow * slow {
            top = top.max(p.pos[i].z + p.radius[i]);
            resting += 1;
        }
    }
    (top, resting)
}

/// The least height of the outline, in grain diameters, at which a column
/// belongs to a heap's footprint: one grain resting on the plate reaches
/// exactly one diameter, a grain on a lower neighbour less.
pub const FOOTPRINT_HEIGHT: f64 = 1.5;

/// One side view of a heap.
#[derive(Debug, Clone, Serialize)]
pub struct SideView {
    /// Area under the outline, d².
    pub area: f64,
    /// Angle with the plate as base, °.
    pub theta_plate: f64,
    /// The extent along the view of the outline at least
    /// [`FOOTPRINT_HEIGHT`] high, d.
    pub footprint: f64,
    /// The height the footprint is read at, [`FOOTPRINT_HEIGHT`], d.
    pub footprint_height: f64,
    /// Angle of the mound above [`FOOTPRINT_HEIGHT`] with the footprint as base, °.
    pub theta_footprint: f64,
    /// Rms distance of the outline from its fitted triangle, d.
    pub roughness: f64,
    /// Mean height of the outline in the outermost column at either end of
    /// the plate, d: a layer of grains there raises `theta_plate` by
    /// `atan` of about `4 × edge/plate` over the mound's own angle.
    pub edge: f64,
}

impl SideView {
    /// Reads a profile (lengths in m) with plate side `plate` (d). The
    /// footprint spans the columns whose outline stands at least
    /// [`FOOTPRINT_HEIGHT`] high, so that a grain or a chain of single
    /// grains rolled out to the plate's edge does not widen it; its angle is
    /// that of the mound above that height (a triangle cut by a line parallel
    /// to its base is a triangle of the same angles).
    pub fn of(profile: &Profile, d: f64, plate: f64) -> Option<SideView> {
        let w = profile.cell_width / d;
        let h: Vec<f64> = profile.h.iter().map(|v| v / d).collect();
        let x: Vec<f64> = profile.x.iter().map(|v| v / d).collect();
        let first = h.iter().position(|v| *v >= FOOTPRINT_HEIGHT)?;
        let last = h.iter().rposition(|v| *v >= FOOTPRINT_HEIGHT)?;
        let area: f64 = h.iter().sum::<f64>() * w;
        let mound: f64 = h[first..=last]
            .iter()
            .map(|v| (v - FOOTPRINT_HEIGHT).max(0.0))
            .sum::<f64>()
            * w;
        let footprint = (last - first + 1) as f64 * w;
        let angle = |a: f64, b: f64| (4.0 * a / (b * b)).atan().to_degrees();
        let theta_footprint = angle(mound, footprint);
        let lift = |k: usize| (h[k] - FOOTPRINT_HEIGHT).max(0.0);
        let centre = (first..=last).map(|k| lift(k) * x[k]).sum::<f64>()
            / (first..=last).map(lift).sum::<f64>().max(f64::MIN_POSITIVE);
        let slope = theta_footprint.to_radians().tan();
        let rms = (first..=last)
            .map(|k| {
                let tri = FOOTPRINT_HEIGHT + slope * (0.5 * footprint - (x[k] - centre).abs());
                (h[k] - tri.max(0.0)).powi(2)
            })
            .sum::<f64>()
            / (last - first + 1) as f64;
        Some(SideView {
            area,
            theta_plate: angle(area, plate),
            footprint,
            footprint_height: FOOTPRINT_HEIGHT,
            theta_footprint,
            roughness: rms.sqrt(),
            edge: 0.5 * (h[0] + h[h.len() - 1]),
        })
    }
}

/// Samples per grain diameter of the silhouette a heap's angle is also read from.
pub const SILHOUETTE_SAMPLES: usize = 20;

/// The angle with the plate as base (`plate` in d), mean of the two views,
/// read from the silhouette of the grains rather than from their columns.
fn silhouette_angle(pos: &[Vector<3>], radius: &[f64], plate: f64, d: f64) -> f64 {
    let half = 0.5 * plate * d;
    let views: Vec<f64> = (0..2)
        .map(|axis| Profile::silhouette(pos, radius, axis, -half, half, SILHOUETTE_SAMPLES))
        .filter_map(|pr| SideView::of(&pr, d, plate))
        .map(|v| v.theta_plate)
        .collect();
    views.iter().sum::<f64>() / views.len().max(1) as f64
}

/// What a settled heap's two side views read: the heap protocol's metrics
/// in the order it reports them, the views and the column profiles.
#[derive(Debug, Clone)]
pub struct HeapReading {
    pub metrics: Vec<(&'static str, f64)>,
    pub views: [SideView; 2],
    pub profiles: Vec<Profile>,
}

/// Reads a heap of grains (centres and radii in m, the plate at z = 0 and
/// centred on the vertical axis, `plate` diameters `d` wide) as the heap
/// protocol reads its own: the same metrics whatever engine poured it. Too
/// few grains to make a heap is an error that says so.
pub fn read_heap(
    pos: &[Vector<3>],
    radius: &[f64],
    plate: f64,
    d: f64,
) -> Result<HeapReading, String> {
    let half = 0.5 * plate * d;
    let profiles: Vec<Profile> = (0..2)
        .map(|axis| Profile::measure(pos, radius, axis, -half, half))
        .collect();
    let views: Vec<SideView> = profiles
        .iter()
        .filter_map(|pr| SideView::of(pr, d, plate))
        .collect();
    let occupied = profiles[0].h.iter().filter(|h| **h > 0.0).count();
    let [xz, yz]: [SideView; 2] = match views.try_into() {
        Ok(pair) if occupied >= 3 => pair,
        _ => {
            return Err(format!(
            "{} grains stayed on the plate, covering {occupied} columns: too few to measure a heap",
            pos.len()
        ))
        }
    };
    let mean_sd = |f: &dyn Fn(&SideView) -> f64| {
        let (a, b) = (f(&xz), f(&yz));
        (0.5 * (a + b), (a - b).abs() / std::f64::consts::SQRT_2)
    };
    let (theta, sd) = mean_sd(&|v| v.theta_plate);
    let top = pos
        .iter()
        .zip(radius)
        .map(|(x, r)| x.z + r)
        .fold(0.0, f64::max);
    let metrics = vec![
        ("theta_r", theta),
        ("theta_r_sd", sd),
        ("theta_r_footprint", mean_sd(&|v| v.theta_footprint).0),
        (
            "theta_r_silhouette",
            silhouette_angle(pos, radius, plate, d),
        ),
        ("heap_grains", pos.len() as f64),
        ("heap_height", top / d),
        ("surface_roughness", mean_sd(&|v| v.roughness).0),
        ("edge_height", mean_sd(&|v| v.edge).0),
    ];
    Ok(HeapReading {
        metrics,
        views: [xz, yz],
        profiles,
    })
}

/// The metrics of the settled heap, or why it cannot be measured.
fn measure(p: &Particles<3>, spec: &HeapSpec, d: f64, findings: &mut Findings) -> Outcome {
    let reading = match read_heap(&p.pos, &p.radius, spec.plate, d) {
        Ok(reading) => reading,
        Err(reason) => return Outcome::Unmeasurable { reason },
    };
    for (name, value) in reading.metrics {
        findings.metric(name, value);
    }
    let [xz, yz] = reading.views;
    findings.details = json!({ "side_views": { "xz": xz, "yz": yz } });
    findings.profiles = reading.profiles;
    Outcome::Completed
}

//! What the three pile protocols of Lee & Herrmann share: the box and the
//! equilibrium test (their scene sections), the grains that fill the box,
//! settling, removing the right wall, and measuring the surface.

use super::runner::{Findings, Runner, Stop};
use super::Observer;
use crate::measure::{Profile, SlopeAngles};
use crate::models::lee_herrmann::GrainSpec;
use crate::models::{self, EngineJob, Laws};
use crate::preset::Preset;
use crate::report::{Outcome, Phase, Quantity, RunReport};
use crate::scene::{
    Checks, Scene, SceneError, Section, SectionDecl, MAX_EXTENT, MAX_GRAINS, MAX_PACKING,
};
use crate::setup::{random_column, sphere_mass, Stream};
use crate::theory;
use repose_engine::contact::ContactLaw;
use repose_engine::dim::Vector;
use repose_engine::integrate::Integrator;
use repose_engine::particles::{vector_from, Particles};
use repose_engine::simulation::{Outlet, Simulation};
use repose_engine::walls::{Limit, Wall};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::HashMap;

pub const FILL: Phase = Phase("fill");
pub const FLOW: Phase = Phase("flow");

/// The box of the fill-and-release and tilt protocols, and the floor of the flux protocol.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BoxSpec {
    /// Width W, cm.
    pub width: f64,
    /// Height H to fill, cm.
    pub height: f64,
    /// If set, H = aspect · W and `height` is ignored (for sweeps over W at
    /// a fixed aspect ratio, the paper's fig. 2b).
    pub aspect: Option<f64>,
    /// Number of grains; by default enough to fill W×H (`grains_per_area · W · H`).
    pub grains: Option<usize>,
    /// Grains per cm² of box when `grains` is not given (25 fills the box
    /// with the default radii at a packing fraction of about 0.82).
    pub grains_per_area: f64,
    /// Packing fraction of the random loose placement before settling.
    pub placement_fraction: f64,
}

impl Default for BoxSpec {
    fn default() -> Self {
        BoxSpec {
            width: 4.0,
            height: 4.0,
            aspect: None,
            grains: None,
            grains_per_area: 25.0,
            placement_fraction: 0.35,
        }
    }
}

impl BoxSpec {
    /// The height to fill: `aspect · width` when an aspect ratio is set.
    pub fn fill_height(&self) -> f64 {
        self.aspect.map_or(self.height, |a| a * self.width)
    }

    /// Number of grains the box starts with (listed grains, if any, count instead).
    pub fn grain_count(&self, scene: &Scene) -> usize {
        if !scene.particles.is_empty() {
            return scene.particles.len();
        }
        self.grains.unwrap_or_else(|| {
            (self.grains_per_area * self.width * self.fill_height()).round() as usize
        })
    }

    /// Refuses boxes that cannot hold their grains. `filled`: the grains
    /// must fit in W × H (not so for the flux protocol's open pile).
    pub fn check_capacity(&self, scene: &Scene, grains: &GrainSpec, filled: bool, c: &mut Checks) {
        let largest = 2.0 * grains.largest();
        if self.width < largest {
            c.fail(
                "box.width",
                format!(
                    "{} cm is narrower than the largest grain ({largest} cm)",
                    self.width
                ),
            );
            return;
        }
        if self.width > MAX_EXTENT * largest {
            c.fail(
                "box.width",
                format!(
                    "{} cm is wider than {MAX_EXTENT} of the largest grains ({largest} cm)",
                    self.width
                ),
            );
            return;
        }
        let n = self.grain_count(scene);
        if n == 0 {
            c.fail("box.grains", "must be at least 1");
            return;
        }
        if n > MAX_GRAINS {
            c.fail(
                "box.grains",
                format!("{n} grains is more than the limit of {MAX_GRAINS}"),
            );
            return;
        }
        if filled {
            let need = n as f64 * grains.mean_disc_area();
            let room = MAX_PACKING * self.width * self.fill_height();
            if need > room {
                c.fail(
                    "box.grains",
                    format!(
                        "{n} grains cover {need:.3} cm², more than a {} × {} box holds at a packing fraction of {MAX_PACKING} ({room:.3} cm²)",
                        self.width,
                        self.fill_height()
                    ),
                );
            }
        }
    }
}

impl Section for BoxSpec {
    const KEY: &'static str = "box";
    const ABOUT: &'static str =
        "the box: width, height (or aspect ratio) and how many grains fill it";

    fn check(&self, scene: &Scene, c: &mut Checks) {
        super::check_gravity_down(scene, c);
        c.positive("box.width", self.width);
        c.positive("box.height", self.height);
        if let Some(a) = self.aspect {
            c.positive("box.aspect", a);
        }
        c.positive("box.grains_per_area", self.grains_per_area);
        c.fraction("box.placement_fraction", self.placement_fraction, true);
    }
}

/// When a pile counts as settled ("no significant motion").
///
/// All three conditions must hold over one window of `hold` seconds. The
/// displacement condition is what makes the test robust: with the paper's
/// ever-growing shear spring, contacts that slid far press with a constant
/// `μ F_n` and sustain a faint vibration (grain speeds of a few mm/s at
/// amplitudes of 10⁻⁴ cm) that no speed threshold alone can tell from creep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Equilibrium {
    /// Largest grain speed allowed at every check of the window, cm/s.
    pub max_speed: f64,
    /// Largest mean kinetic energy per grain allowed at every check, erg.
    pub kinetic_energy: f64,
    /// Largest distance any grain may move over the window, in mean diameters.
    pub max_displacement: f64,
    /// Length of the window, s.
    pub hold: f64,
    /// How often the criterion is checked, s.
    pub check_interval: f64,
    /// Cap on the simulated time of the fill's settling, s.
    pub max_fill_time: f64,
    /// Cap on the simulated time of the flow after release, s.
    pub max_flow_time: f64,
}

impl Default for Equilibrium {
    fn default() -> Self {
        Equilibrium {
            max_speed: 5.0,
            kinetic_energy: 1e-3,
            max_displacement: 0.02,
            hold: 0.1,
            check_interval: 0.005,
            max_fill_time: 5.0,
            max_flow_time: 15.0,
        }
    }
}

impl Section for Equilibrium {
    const KEY: &'static str = "equilibrium";
    const ABOUT: &'static str = "when a pile counts as settled, and how long to wait for it";

    fn check(&self, _scene: &Scene, c: &mut Checks) {
        c.positive("equilibrium.max_speed", self.max_speed);
        c.positive("equilibrium.kinetic_energy", self.kinetic_energy);
        c.positive("equilibrium.max_displacement", self.max_displacement);
        c.non_negative("equilibrium.hold", self.hold);
        c.positive("equilibrium.check_interval", self.check_interval);
        c.positive("equilibrium.max_fill_time", self.max_fill_time);
        c.positive("equilibrium.max_flow_time", self.max_flow_time);
        let cap = self.max_fill_time.min(self.max_flow_time);
        if self.check_interval > cap {
            c.fail(
                "equilibrium.check_interval",
                format!(
                    "{} s is longer than the shorter time cap ({cap} s): the pile is checked at least once before it",
                    self.check_interval
                ),
            );
        }
    }
}

/// The methods the three pile protocols share: 2D, Lee & Herrmann's model,
/// the pile presets, the box checks (`filled`: the grains must fit in the
/// box) and the resolved grain count and height.
macro_rules! pile_protocol {
    (filled: $filled:expr) => {
        fn dimensions(&self) -> &'static [usize] {
            &[2]
        }

        fn models(&self) -> &'static [&'static str] {
            &[$crate::models::lee_herrmann::NAME]
        }

        fn preset(&self, preset: $crate::preset::Preset) -> Vec<(&'static str, serde_json::Value)> {
            $crate::protocols::pile::preset(preset)
        }

        fn check(&self, scene: &$crate::scene::Scene, c: &mut $crate::scene::Checks) {
            $crate::protocols::pile::check(scene, $filled, c);
        }

        fn resolve(&self, scene: &mut $crate::scene::Scene) {
            $crate::protocols::pile::resolve(scene);
        }
    };
}
pub(crate) use pile_protocol;

/// The settings the fidelity presets give the pile protocols.
pub fn preset(preset: Preset) -> Vec<(&'static str, Value)> {
    let mut v = super::numeric_preset(preset);
    if preset == Preset::Quick {
        v.push(("equilibrium.hold", Value::from(0.05)));
        v.push(("equilibrium.check_interval", Value::from(0.01)));
    }
    v
}

/// The checks of a pile protocol beyond its sections.
pub fn check(scene: &Scene, filled: bool, c: &mut Checks) {
    if scene.duration.is_some() {
        c.fail("duration", "only a free_run takes a fixed duration");
    }
    if !scene.walls.is_empty() {
        c.fail(
            "walls",
            "only a free_run takes explicit walls; the box is built from [box]",
        );
    }
    if !c.is_empty() {
        return;
    }
    if let (Ok(b), Ok(g)) = (scene.section::<BoxSpec>(), scene.section::<GrainSpec>()) {
        b.check_capacity(scene, g, filled, c);
    }
}

/// Writes out the grain count and the height an aspect ratio gives.
pub fn resolve(scene: &mut Scene) {
    let Ok(b) = scene.section::<BoxSpec>() else {
        return;
    };
    let mut b = b.clone();
    if scene.particles.is_empty() {
        b.grains = Some(b.grain_count(scene));
    }
    b.height = b.fill_height();
    scene.set_section(b);
}

/// The sections a pile scene is read from, once.
pub struct PileSpec {
    pub cell: BoxSpec,
    pub eq: Equilibrium,
    pub grains: GrainSpec,
    pub mu: f64,
}

impl PileSpec {
    pub fn of(scene: &Scene) -> Result<PileSpec, SceneError> {
        let contact: &models::lee_herrmann::ContactSpec = scene.section()?;
        Ok(PileSpec {
            cell: scene.section::<BoxSpec>()?.clone(),
            eq: scene.section::<Equilibrium>()?.clone(),
            grains: scene.section::<GrainSpec>()?.clone(),
            mu: contact.mu,
        })
    }
}

/// The listed grains of a scene, or none, each with its load (the scene's
/// checks have refused a vector of the wrong length; the grains of these
/// protocols do not turn, so an angular velocity is not theirs).
pub fn listed_grains(scene: &Scene, density: f64) -> Particles<2> {
    let mut particles = Particles::<2>::default();
    for g in &scene.particles {
        let (Some(x), Some(v)) = (g.position_in::<2>(), g.velocity_in::<2>()) else {
            continue;
        };
        particles.push_with_id(g.id, x, v, g.radius, sphere_mass(density, g.radius));
        if let Some(load) = vector_from::<2>(&g.load) {
            particles.set_load(particles.len() - 1, load);
        }
    }
    particles.make_ids_unique();
    particles
}

/// The grains that fill the box: listed, or drawn and placed at random.
pub fn box_grains(scene: &Scene, spec: &PileSpec, stream: &mut Stream) -> Particles<2> {
    let rho = spec.grains.density;
    if !scene.particles.is_empty() {
        return listed_grains(scene, rho);
    }
    let mut particles = Particles::<2>::default();
    let n = spec.cell.grain_count(scene);
    let radii: Vec<f64> = (0..n).map(|_| spec.grains.draw_radius(stream)).collect();
    let pos = random_column(
        stream,
        &radii,
        spec.cell.width,
        spec.cell.placement_fraction,
    );
    for (x, r) in pos.into_iter().zip(radii) {
        particles.push(x, Vector::zeros(), r, sphere_mass(rho, r));
    }
    particles
}

/// The floor of the box: it ends at `x = W`, so grains past the open side fall.
pub fn floor(width: f64) -> Wall<2> {
    Wall {
        limits: vec![Limit {
            axis: 0,
            min: Some(0.0),
            max: Some(width),
        }],
        ..plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(0.0, 1.0))
    }
}

/// An unbounded wall.
pub fn plane(point: Vector<2>, normal: Vector<2>) -> Wall<2> {
    Wall {
        point,
        normal: normal.normalize(),
        limits: Vec::new(),
    }
}

/// Grains leave past `x = W` once the right wall is gone.
pub fn open_side(width: f64) -> Outlet<2> {
    Outlet {
        point: Vector::<2>::new(width, 0.0),
        normal: Vector::<2>::new(1.0, 0.0),
    }
}

/// Index of the right wall in the box protocols.
const RIGHT_WALL: usize = 2;

/// The engine for a closed box: floor, left and right walls.
pub fn closed_box<L: ContactLaw<2>, I: Integrator<2>>(
    scene: &Scene,
    spec: &PileSpec,
    laws: Laws<L>,
) -> Simulation<2, L, I> {
    let mut stream = Stream::new(scene.seed);
    let particles = box_grains(scene, spec, &mut stream);
    let width = spec.cell.width;
    let walls = vec![
        (floor(width), laws.wall),
        (
            plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(1.0, 0.0)),
            laws.wall,
        ),
        (
            plane(Vector::<2>::new(width, 0.0), Vector::<2>::new(-1.0, 0.0)),
            laws.wall,
        ),
    ];
    engine(scene, particles, walls, laws)
}

/// An engine with the scene's gravity, time step and guards.
pub fn engine<L: ContactLaw<2>, I: Integrator<2>>(
    scene: &Scene,
    particles: Particles<2>,
    walls: Vec<(Wall<2>, L)>,
    laws: Laws<L>,
) -> Simulation<2, L, I> {
    let gravity = Vector::<2>::new(scene.gravity[0], scene.gravity[1]);
    super::runner::engine(scene, particles, walls, gravity, laws.pair)
}

/// What a box protocol does once its pile is released and has come to
/// rest: nothing more (`()`, fill and release) or a stage of its own (the
/// tilt).
pub trait AfterRelease {
    /// Runs the stage on the released pile, recording what it measures.
    fn run<L: ContactLaw<2>, I: Integrator<2>>(
        &self,
        pile: &mut Pile<'_, L, I>,
        findings: &mut Findings,
    ) -> Outcome;
}

impl AfterRelease for () {
    fn run<L: ContactLaw<2>, I: Integrator<2>>(
        &self,
        _pile: &mut Pile<'_, L, I>,
        _findings: &mut Findings,
    ) -> Outcome {
        Outcome::Completed
    }
}

/// Fills the closed box of a (resolved) scene, releases the pile and runs
/// the protocol's own stage `after` on it.
pub fn fill_and_release<A: AfterRelease>(
    scene: &Scene,
    observer: &mut dyn Observer,
    after: A,
) -> Result<RunReport, SceneError> {
    let job = ReleaseJob {
        scene,
        spec: PileSpec::of(scene)?,
        observer,
        after,
    };
    models::with_engine::<2, _>(scene, job)
}

/// The sections of a protocol that releases a pile from the box, then its own.
pub fn release_sections(own: Vec<SectionDecl>) -> Vec<SectionDecl> {
    let mut v = vec![
        SectionDecl::of::<BoxSpec>(),
        SectionDecl::of::<Equilibrium>(),
    ];
    v.extend(own);
    v
}

/// The run of a box protocol: fill the closed box, release the pile
/// (θ_R by the three methods), then the protocol's own stage `after`.
pub struct ReleaseJob<'a, A> {
    pub scene: &'a Scene,
    pub spec: PileSpec,
    pub observer: &'a mut dyn Observer,
    pub after: A,
}

impl<A: AfterRelease> EngineJob<2> for ReleaseJob<'_, A> {
    type Output = RunReport;

    fn run<L: ContactLaw<2>, I: Integrator<2>>(self, laws: Laws<L>) -> RunReport {
        let sim = closed_box::<L, I>(self.scene, &self.spec, laws);
        let mut pile = Pile::new(sim, self.scene, self.spec, self.observer);
        let mut findings = Findings::default();
        let outcome = match pile.released_pile(&mut findings) {
            Ok(_) => self.after.run(&mut pile, &mut findings),
            Err(outcome) => outcome,
        };
        pile.run.report(outcome, findings)
    }
}

/// A pile protocol in progress.
pub struct Pile<'a, L: ContactLaw<2>, I: Integrator<2>> {
    pub run: Runner<'a, 2, L, I>,
    pub spec: PileSpec,
}

impl<'a, L: ContactLaw<2>, I: Integrator<2>> Pile<'a, L, I> {
    pub fn new(
        sim: Simulation<2, L, I>,
        scene: &'a Scene,
        spec: PileSpec,
        observer: &'a mut dyn Observer,
    ) -> Self {
        let p = &sim.particles;
        let size = Vector::<2>::new(spec.cell.width, spec.cell.fill_height());
        let extent = super::runner::extent(&p.pos, &p.radius, size);
        let check = spec.eq.check_interval;
        Pile {
            run: Runner::new(sim, scene, observer, check, extent),
            spec,
        }
    }

    /// Steps until the equilibrium criterion has held over one window of
    /// `hold` seconds (speed and energy low at every check, no grain moved
    /// more than `max_displacement` diameters), or `max_time` has passed.
    pub fn settle(&mut self, phase: Phase, max_time: f64) -> Result<(), Stop> {
        let start = self.run.sim.time;
        let mut window = StillWindow::default();
        loop {
            let point = self.run.sample(phase)?;
            let eq = &self.spec.eq;
            let calm = calm(point.max_speed, point.kinetic_energy, eq);
            if window.settled(&self.run.sim.particles, self.run.sim.time, calm, eq) {
                return Ok(());
            }
            if self.run.sim.time - start >= max_time {
                return Err(Stop::TimedOut);
            }
            self.run.sim.run(self.run.check_steps)?;
        }
    }

    /// The surface over the box.
    pub fn surface(&self) -> Profile {
        let p = &self.run.sim.particles;
        Profile::measure(&p.pos, &p.radius, 0, 0.0, self.spec.cell.width)
    }

    /// Fill the closed box, settle, remove the right wall, settle again.
    pub fn fill_and_release(&mut self) -> Result<(), (Phase, Stop)> {
        let fill_cap = self.spec.eq.max_fill_time;
        self.settle(FILL, fill_cap).map_err(|s| (FILL, s))?;
        self.open_right_side();
        let flow_cap = self.spec.eq.max_flow_time;
        self.settle(FLOW, flow_cap).map_err(|s| (FLOW, s))
    }

    pub fn open_right_side(&mut self) {
        self.run.sim.remove_wall(RIGHT_WALL);
        self.run.sim.outlets = vec![open_side(self.spec.cell.width)];
    }

    /// The outcome of a settling phase that stopped early.
    pub fn stopped(&self, phase: Phase, stop: Stop) -> Outcome {
        let cap = if phase == FILL {
            self.spec.eq.max_fill_time
        } else {
            self.spec.eq.max_flow_time
        };
        stop.outcome(phase, || {
            format!(
                "did not settle (max speed and kinetic energy below their thresholds) within {cap} s of simulated time"
            )
        })
    }

    /// Fills, releases and measures θ_R by the three methods. On success
    /// the findings hold the angles; otherwise the outcome says why.
    pub fn released_pile(&mut self, findings: &mut Findings) -> Result<SlopeAngles, Outcome> {
        findings.theory.push(Quantity {
            name: "theta_ms_eq3".into(),
            label: "θ_MS = atan(3μ), eq. (3)".into(),
            value: theory::marginal_stability_angle(self.spec.mu),
        });
        if let Err((phase, stop)) = self.fill_and_release() {
            return Err(self.stopped(phase, stop));
        }
        let s = self.surface();
        let angles = s.slope_angles();
        let checked = s.check(&angles);
        findings.profiles.push(s);
        if let Err(reason) = checked {
            return Err(Outcome::Unmeasurable { reason });
        }
        findings.metric("theta_r", angles.cumulative_fit);
        findings.metric("theta_r_line", angles.line_fit);
        findings.metric("theta_r_endpoints", angles.endpoints);
        findings.details = serde_json::json!({ "slopes": angles });
        if let Some(t) = theory::tilting_angle(self.spec.mu, angles.cumulative_fit) {
            findings.theory.push(Quantity {
                name: "theta_t_eq4".into(),
                label: "θ_T by eq. (4)".into(),
                value: t,
            });
        }
        Ok(angles)
    }
}

/// The speed and energy half of the equilibrium test, at one check.
pub fn calm(max_speed: f64, kinetic_energy: f64, eq: &Equilibrium) -> bool {
    max_speed < eq.max_speed && kinetic_energy < eq.kinetic_energy
}

/// The displacement half of the equilibrium test: a window opens when the
/// pile is calm, and the pile is settled once it has stayed calm for `hold`
/// seconds with no grain moved more than `max_displacement` mean diameters
/// from where it was when the window opened (grains that left count as
/// moved). A window that fails is replaced by a new one.
#[derive(Default)]
pub struct StillWindow {
    open: Option<(f64, HashMap<u32, Vector<2>>)>,
}

impl StillWindow {
    pub fn settled(&mut self, p: &Particles<2>, time: f64, calm: bool, eq: &Equilibrium) -> bool {
        if !calm {
            self.open = None;
            return false;
        }
        if let Some((since, anchor)) = &self.open {
            if time - since < eq.hold {
                return false;
            }
            let limit = eq.max_displacement * 2.0 * p.mean_radius();
            let still =
                p.id.iter()
                    .zip(&p.pos)
                    .all(|(id, x)| anchor.get(id).is_some_and(|x0| (x - x0).norm() <= limit));
            if still {
                return true;
            }
        }
        let anchor = p.id.iter().copied().zip(p.pos.iter().copied()).collect();
        self.open = Some((time, anchor));
        false
    }
}

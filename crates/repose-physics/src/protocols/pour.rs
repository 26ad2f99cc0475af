//! What the 3D protocols of Elekes & Parteli share: grains of the scene's
//! sizes placed at random without overlap in a region (across periodic
//! faces where there are some), the grain scales `d` and `√(d/g)`, and the
//! settling criterion.

use super::runner::{Runner, Stop};
use super::Observer;
use crate::models::elekes_parteli::Grains;
use crate::models::Laws;
use crate::preset::Preset;
use crate::report::Phase;
use crate::scene::{Checks, Scene, SceneError, Section};
use crate::setup::Stream;
use repose_engine::contact::ContactLaw;
use repose_engine::dim::Vector;
use repose_engine::integrate::{Integrator, Scheme};
use repose_engine::particles::Particles;
use repose_engine::simulation::{RestRule, Simulation};
use repose_engine::walls::Wall;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::HashMap;

/// The methods the poured protocols (heap, packing) share: their name and
/// line, 3D spheres of Elekes & Parteli's model, their own section and the
/// grains at rest, their metrics, their presets, the pour checks, and the
/// fastest impact, a grain falling the domain's height (`spec`'s `height`,
/// in diameters), and the estimate of a sample's cost from its [`Budget`].
macro_rules! poured_protocol {
    (name: $name:literal, about: $about:literal, spec: $spec:ty, metrics: $metrics:expr, presets: $presets:path) => {
        fn name(&self) -> &'static str {
            $name
        }

        fn about(&self) -> &'static str {
            $about
        }

        fn sections(&self) -> Vec<$crate::scene::SectionDecl> {
            vec![
                $crate::scene::SectionDecl::of::<$spec>(),
                $crate::scene::SectionDecl::of::<$crate::protocols::pour::RestSpec>(),
            ]
        }

        fn metrics(&self) -> &'static [$crate::protocols::Metric] {
            &$metrics
        }

        fn dimensions(&self) -> &'static [usize] {
            &[3]
        }

        fn models(&self) -> &'static [&'static str] {
            &[$crate::models::elekes_parteli::NAME]
        }

        fn preset(&self, preset: $crate::preset::Preset) -> Vec<(&'static str, serde_json::Value)> {
            $presets(preset)
        }

        fn check(&self, scene: &$crate::scene::Scene, c: &mut $crate::scene::Checks) {
            $crate::protocols::pour::check_scene(scene, c);
        }

        fn impact_speed(&self, scene: &$crate::scene::Scene) -> Option<f64> {
            let spec: &$spec = scene.section().ok()?;
            let grains: &$crate::models::elekes_parteli::Grains = scene.section().ok()?;
            $crate::protocols::pour::fall_speed(scene, spec.height * grains.diameter)
        }

        fn cost(&self, scene: &$crate::scene::Scene) -> Option<f64> {
            let spec: &$spec = scene.section().ok()?;
            $crate::protocols::pour::cost(scene, $crate::protocols::pour::Budget::grain_time(spec))
        }
    };
}
pub(crate) use poured_protocol;

/// What a poured protocol's sample asks of the engine, before it runs.
pub trait Budget {
    /// The grains it holds summed over the time it runs, in grains · √(d/g),
    /// at its grain cap and its least settling time: the run's particle-steps
    /// are this over the time step in √(d/g).
    fn grain_time(&self) -> f64;
}

/// The estimated particle-steps of a poured sample: its [`Budget`] over
/// the scene's time step, both in √(d/g).
pub fn cost(scene: &Scene, grain_time: f64) -> Option<f64> {
    let scales = Scales::of(scene).ok()?;
    let steps = scales.time / scene.time_step();
    let cost = grain_time * steps;
    (cost.is_finite() && cost > 0.0).then_some(cost)
}

/// Volume of a sphere of diameter 1.
pub(crate) const GRAIN_VOLUME: f64 = std::f64::consts::PI / 6.0;

/// A poured protocol's run, handed to the engine: its scene, its own
/// section `spec`, the scales, the grains and the observer.
pub struct PourJob<'a, S> {
    pub scene: &'a Scene,
    pub spec: S,
    pub scales: Scales,
    pub grains: Grains,
    pub observer: &'a mut dyn Observer,
}

impl<'a, S: Section> PourJob<'a, S> {
    /// Reads the sections the run needs from a validated scene.
    pub fn of(scene: &'a Scene, observer: &'a mut dyn Observer) -> Result<Self, SceneError> {
        Ok(PourJob {
            scene,
            spec: scene.section::<S>()?.clone(),
            scales: Scales::of(scene)?,
            grains: scene.section::<Grains>()?.clone(),
            observer,
        })
    }
}

/// The length and time scales of a scene: the reference diameter `d`, the
/// gravity `g` and `√(d/g)`.
#[derive(Debug, Clone, Copy)]
pub struct Scales {
    pub d: f64,
    pub g: f64,
    pub time: f64,
    /// Mass of a grain of diameter `d`.
    pub mass: f64,
}

impl Scales {
    pub fn of(scene: &Scene) -> Result<Scales, SceneError> {
        let grains: &Grains = scene.section()?;
        let d = grains.diameter;
        let g = scene.gravity_magnitude();
        Ok(Scales {
            d,
            g,
            time: (d / g).sqrt(),
            mass: grains.mass(d),
        })
    }

    /// The translational kinetic energy per grain below which a pile is at rest.
    pub fn rest_energy(&self, per_mgd: f64) -> f64 {
        per_mgd * self.mass * self.g * self.d
    }
}

/// Grains at rest (`repose_engine::simulation::RestRule`): a grain that has
/// stayed slower than `speed` for `time` is no longer integrated until a
/// faster grain touches it. Off unless `speed` is above zero.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RestSpec {
    /// Speed below which a grain is still, √(g d); 0 puts no grain to rest.
    pub speed: f64,
    /// How long a grain must stay still before it is put to rest, √(d/g).
    pub time: f64,
}

impl Default for RestSpec {
    fn default() -> Self {
        RestSpec {
            speed: 0.0,
            time: 1.0,
        }
    }
}

impl Section for RestSpec {
    const KEY: &'static str = "rest";
    const ABOUT: &'static str =
        "grains at rest: stop integrating grains still for a while until a moving grain touches them (speed in √(g d), time in √(d/g); speed 0 = off)";

    fn check(&self, scene: &Scene, c: &mut Checks) {
        c.non_negative("rest.speed", self.speed);
        c.positive("rest.time", self.time);
        if self.speed > 0.0 && self.time < 2.0 * self.speed {
            // A grain in flight is that slow for 2 speed/g at the top of its
            // arc (or as it starts to fall): it must not be put to rest there.
            c.fail(
                "rest.time",
                format!(
                    "must be at least twice rest.speed ({}): a grain in flight is slower than rest.speed for up to that long",
                    2.0 * self.speed
                ),
            );
        }
        if self.speed > 0.0 && scene.numerics.integrator != Scheme::Verlet {
            c.fail(
                "rest.speed",
                "grains are put to rest only with numerics.integrator = \"verlet\"",
            );
        }
    }
}

impl RestSpec {
    /// Puts the scene's rule on a simulation stepping by `sim.dt`.
    pub fn apply<L: ContactLaw<3>, I: Integrator<3>>(
        scene: &Scene,
        scales: &Scales,
        sim: &mut Simulation<3, L, I>,
    ) {
        let spec = scene.section::<RestSpec>().cloned().unwrap_or_default();
        if spec.speed > 0.0 {
            let steps = (spec.time * scales.time / sim.dt)
                .ceil()
                .clamp(1.0, u32::MAX as f64);
            sim.set_rest(Some(RestRule {
                speed: spec.speed * (scales.g * scales.d).sqrt(),
                steps: steps as u32,
            }));
        }
    }
}

/// An engine for a poured scene: `particles` above a floor of the grains'
/// material at z = 0, under the scene's gravity.
pub fn on_floor<L: ContactLaw<3>, I: Integrator<3>>(
    scene: &Scene,
    particles: Particles<3>,
    laws: Laws<L>,
) -> Simulation<3, L, I> {
    let floor = Wall::<3>::plane(Vector::<3>::zeros(), Vector::<3>::new(0.0, 0.0, 1.0));
    let gravity = Vector::<3>::from_column_slice(&scene.gravity);
    super::runner::engine(
        scene,
        particles,
        vec![(floor, laws.wall)],
        gravity,
        laws.pair,
    )
}

/// The run of a poured scene on its engine: the scene's rule for grains at
/// rest put on, checks every quarter √(d/g), and the energy guard sized for
/// a domain `height` diameters high.
pub fn runner<'a, L: ContactLaw<3>, I: Integrator<3>>(
    scene: &'a Scene,
    scales: &Scales,
    observer: &'a mut dyn Observer,
    mut sim: Simulation<3, L, I>,
    height: f64,
) -> Runner<'a, 3, L, I> {
    RestSpec::apply(scene, scales, &mut sim);
    Runner::new(sim, scene, observer, 0.25 * scales.time, height * scales.d)
}

/// The speed of a grain that falls `height` (m) under the scene's gravity.
pub fn fall_speed(scene: &Scene, height: f64) -> Option<f64> {
    let scales = Scales::of(scene).ok()?;
    Some((2.0 * scales.g * height).sqrt())
}

/// Random placement of spheres without overlap, with a hash grid of cells
/// at least one largest diameter wide. Along periodic axes cells wrap, and
/// distances are taken to the nearest image.
pub struct Placer {
    cell: [f64; 3],
    /// Cells along each periodic axis; 0 for an open axis.
    wrap: [i64; 3],
    origin: Vector<3>,
    periods: [f64; 3],
    cells: HashMap<[i64; 3], Vec<(Vector<3>, f64)>>,
}

impl Placer {
    /// A placer for grains up to `largest` in diameter; `periods` gives the
    /// period of each axis from `origin` (0 for an open axis).
    pub fn new(largest: f64, origin: Vector<3>, periods: [f64; 3]) -> Placer {
        let mut cell = [largest; 3];
        let mut wrap = [0i64; 3];
        for a in 0..3 {
            if periods[a] > 0.0 {
                let n = ((periods[a] / largest).floor() as i64).max(1);
                wrap[a] = n;
                cell[a] = periods[a] / n as f64;
            }
        }
        Placer {
            cell,
            wrap,
            origin,
            periods,
            cells: HashMap::new(),
        }
    }

    fn key(&self, x: &Vector<3>) -> [i64; 3] {
        let mut k = [0i64; 3];
        for a in 0..3 {
            let c = ((x[a] - self.origin[a]) / self.cell[a]).floor() as i64;
            k[a] = if self.wrap[a] > 0 {
                c.rem_euclid(self.wrap[a])
            } else {
                c
            };
        }
        k
    }

    /// Records a grain already there.
    pub fn add(&mut self, x: Vector<3>, radius: f64) {
        let k = self.key(&x);
        self.cells.entry(k).or_default().push((x, radius));
    }

    /// Whether a sphere at `x` of `radius` overlaps nothing recorded.
    pub fn fits(&self, x: &Vector<3>, radius: f64) -> bool {
        let k = self.key(x);
        for code in 0..27 {
            let mut c = k;
            let mut rest = code;
            for (slot, wrap) in c.iter_mut().zip(self.wrap) {
                *slot += (rest % 3) as i64 - 1;
                rest /= 3;
                if wrap > 0 {
                    *slot = slot.rem_euclid(wrap);
                }
            }
            let Some(list) = self.cells.get(&c) else {
                continue;
            };
            for (y, ry) in list {
                let mut r = x - y;
                for a in 0..3 {
                    if self.periods[a] > 0.0 {
                        r[a] -= self.periods[a] * (r[a] / self.periods[a]).round();
                    }
                }
                let reach = radius + ry;
                if r.norm_squared() < reach * reach {
                    return false;
                }
            }
        }
        true
    }
}

/// A box region for grain centres.
#[derive(Debug, Clone, Copy)]
pub struct Region {
    pub lo: Vector<3>,
    pub hi: Vector<3>,
    /// Along the axes marked, a grain filled in may reach past the faces
    /// (its centre anywhere between them); along the others it lies wholly
    /// inside, unless the axis is periodic.
    pub straddle: [bool; 3],
}

impl Region {
    pub fn volume(&self) -> f64 {
        (self.hi - self.lo).iter().map(|x| x.max(0.0)).product()
    }

    pub fn contains(&self, x: &Vector<3>) -> bool {
        (0..3).all(|a| x[a] >= self.lo[a] && x[a] < self.hi[a])
    }

    /// A uniform point of the region shrunk by `margin[a]` on both sides of axis `a`.
    fn draw(&self, stream: &mut Stream, margin: [f64; 3]) -> Vector<3> {
        Vector::<3>::from_fn(|a, _| {
            let m = margin[a].min(0.5 * (self.hi[a] - self.lo[a]));
            let (lo, hi) = (self.lo[a] + m, self.hi[a] - m);
            lo + (hi - lo) * stream.uniform()
        })
    }
}

/// Draws diameters from the scene's grains: one size, or the mixture's
/// sizes by their number fractions.
pub fn draw_diameter(grains: &Grains, stream: &mut Stream) -> f64 {
    if grains.mix.is_empty() {
        return grains.diameter;
    }
    let mut u = stream.uniform();
    for s in &grains.mix {
        if u < s.fraction {
            return s.diameter;
        }
        u -= s.fraction;
    }
    grains.mix[grains.mix.len() - 1].diameter
}

/// Adds grains at random points of `region` (wholly inside it along the
/// open axes it does not let them straddle) until their volume, with that
/// of the grains already centred there, reaches `fraction` of the region,
/// or `budget` grains were added.
/// Returns the new grains' centres and diameters. A grain that finds no
/// room after many tries ends the fill.
pub fn fill(
    region: &Region,
    fraction: f64,
    placer: &mut Placer,
    existing_volume: f64,
    grains: &Grains,
    stream: &mut Stream,
    budget: usize,
) -> Vec<(Vector<3>, f64)> {
    let sphere = |d: f64| std::f64::consts::PI / 6.0 * d * d * d;
    let target = fraction * region.volume();
    let mut volume = existing_volume;
    let mut out = Vec::new();
    'grains: while volume < target && out.len() < budget {
        let d = draw_diameter(grains, stream);
        // Along a periodic axis, or one the region lets grains straddle, a
        // grain may reach past the face.
        let margin: [f64; 3] = std::array::from_fn(|a| {
            if placer.periods[a] > 0.0 || region.straddle[a] {
                0.0
            } else {
                0.5 * d
            }
        });
        for _ in 0..1000 {
            let x = region.draw(stream, margin);
            if placer.fits(&x, 0.5 * d) {
                placer.add(x, 0.5 * d);
                out.push((x, d));
                volume += sphere(d);
                continue 'grains;
            }
        }
        break;
    }
    out
}

/// When a bed is at rest: its translational kinetic energy per grain is
/// below `energy`, leaving out the most energetic `exempt` fraction of its
/// grains (rounded up; none when zero). The exemption is for motion this
/// contact model never stops: it has no resistance to twisting, so a pair
/// of grains hanging from one contact can spin about it, the outer grain
/// circling, for as long as the run lasts (`docs/model-3d.md`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rest {
    pub energy: f64,
    pub exempt: f64,
}

impl Rest {
    /// Whether grains whose mean translational kinetic energy is `mean`
    /// are at rest.
    pub fn holds(&self, p: &Particles<3>, mean: f64) -> bool {
        let skip = (self.exempt * p.len() as f64).ceil() as usize;
        if mean < self.energy || skip == 0 || skip >= p.len() {
            return mean < self.energy;
        }
        let mut energy: Vec<f64> = p.kinetic_energies().collect();
        // The `skip` largest first, in any order.
        energy.select_nth_unstable_by(skip, |a, b| b.total_cmp(a));
        let rest = &energy[skip..];
        rest.iter().sum::<f64>() / (rest.len() as f64) < self.energy
    }
}

/// Runs until the grains are at `rest` and at least `min_time` has passed
/// since `since`; fails with
/// [`Stop::TimedOut`] once `max_time` has passed since then. Every check
/// is a resumable point, where the protocol's own state is `state`.
pub fn settle<L: ContactLaw<3>, I: Integrator<3>>(
    run: &mut Runner<'_, 3, L, I>,
    phase: Phase,
    since: f64,
    (min_time, max_time): (f64, f64),
    rest: Rest,
    state: &impl Serialize,
) -> Result<(), Stop> {
    loop {
        run.checkpoint(state);
        let point = run.sample(phase)?;
        let waited = run.sim.time - since;
        if waited >= min_time && rest.holds(&run.sim.particles, point.kinetic_energy) {
            return Ok(());
        }
        if waited >= max_time {
            return Err(Stop::TimedOut);
        }
        let steps = run.check_steps;
        run.sim.run(steps)?;
    }
}

/// The fill and settling keys both poured sections carry (`key.fill_fraction`,
/// `key.rest_energy`, `key.rest_exempt`, `key.settle_min`, `key.settle_max`),
/// checked alike.
pub(super) fn check_fill_and_settling(c: &mut Checks, key: &str, fill: f64, settle: [f64; 4]) {
    let [rest_energy, rest_exempt, settle_min, settle_max] = settle;
    c.positive(&format!("{key}.fill_fraction"), fill);
    c.positive(&format!("{key}.rest_energy"), rest_energy);
    if !(0.0..0.5).contains(&rest_exempt) {
        c.fail(&format!("{key}.rest_exempt"), "needs 0 ≤ rest_exempt < 0.5");
    }
    c.non_negative(&format!("{key}.settle_min"), settle_min);
    c.positive(&format!("{key}.settle_max"), settle_max);
    if fill > 0.5 {
        c.fail(
            &format!("{key}.fill_fraction"),
            "a random fill reaches at most 0.5",
        );
    }
    if settle_max < settle_min {
        c.fail(
            &format!("{key}.settle_max"),
            format!("must not be below {key}.settle_min"),
        );
    }
}

/// The checks every 3D pouring protocol shares.
pub fn check_scene(scene: &Scene, c: &mut Checks) {
    super::check_gravity_down(scene, c);
    if scene.duration.is_some() {
        c.fail("duration", "only a free_run takes a fixed duration");
    }
    if !scene.walls.is_empty() {
        c.fail(
            "walls",
            "this protocol builds its own plate; walls are for a free_run",
        );
    }
    if !scene.particles.is_empty() {
        c.fail(
            "particles",
            "this protocol pours its own grains; particles are for a free_run",
        );
    }
}

/// The largest kick of the contact attraction per step, in `√(g d)`, that
/// the heap's `standard` preset allows (`numerics.attraction_kick`).
pub const ATTRACTION_KICK: f64 = 0.5;

/// The settings the fidelity presets give the 3D protocols. `quick`
/// softens the modulus by its stiffness number `κ = Y/(ρ g d)`, kept stiff
/// enough for cohesion by `κ_c = Y d/(π γ)` (where the scene gives no
/// modulus); `standard` and `paper` keep the true modulus (glass's 63 GPa),
/// which the heap's `standard` softens to a tenth (`heap::preset`).
/// Softer grains stick where glass bounces and pack measurably looser, so
/// the softer `quick` is labelled by its bias (`docs/tradeoff-heap.md`,
/// `docs/model-3d.md`, "Softening, and its limits"). At `quick`'s step
/// the contact attraction, read at a pair's gap, kicked fine grains by
/// more than their own speed scale `√(g d)` each time a contact opened or
/// closed, until they flew off the plate; `quick` averages it over the gaps
/// each step sweeps instead (`numerics.attraction_step = "swept"`), which
/// gives the impulse the law asks at its own step (`docs/model-3d.md`,
/// "The attraction's kick").
pub fn preset(preset: Preset) -> Vec<(&'static str, Value)> {
    match preset {
        Preset::Quick => vec![
            ("numerics.integrator", Value::from("verlet")),
            ("numerics.dt_factor", Value::from(0.1)),
            ("numerics.attraction_step", Value::from("swept")),
            ("material.kappa", Value::from(1e5)),
            ("material.kappa_cohesion", Value::from(1e4)),
        ],
        Preset::Standard | Preset::Paper => vec![
            ("numerics.integrator", Value::from("verlet")),
            ("numerics.dt_factor", Value::from(0.1)),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::{fill, Grains, Placer, Region, Rest, Stream};
    use crate::scene::Scene;
    use repose_engine::dim::Vector;
    use repose_engine::particles::Particles;

    /// 200 grains of unit mass, `fast` of them at speed 1 and the others at
    /// 10⁻³, with the rule's verdict for a threshold of 10⁻⁵ per grain.
    fn at_rest(fast: usize, exempt: f64) -> bool {
        let mut p = Particles::<3>::new(true);
        for k in 0..200 {
            let speed = if k % 50 == 7 && k / 50 < fast {
                1.0
            } else {
                1e-3
            };
            p.push(
                Vector::<3>::zeros(),
                Vector::<3>::new(0.0, speed, 0.0),
                0.5,
                1.0,
            );
        }
        let mean = p.kinetic_energy() / p.len() as f64;
        Rest {
            energy: 1e-5,
            exempt,
        }
        .holds(&p, mean)
    }

    /// Unit grains filled into a 6 × 6 × 10 box to a fifth of its volume,
    /// letting them straddle its sides across or not: the grains placed
    /// and the largest distance of a centre from the axis and from the
    /// box's mid-height.
    fn filled(straddle: bool) -> (usize, f64, f64) {
        let region = Region {
            lo: Vector::<3>::new(-3.0, -3.0, 0.0),
            hi: Vector::<3>::new(3.0, 3.0, 10.0),
            straddle: [straddle, straddle, false],
        };
        let grains = Grains {
            diameter: 1.0,
            ..Grains::default()
        };
        let mut placer = Placer::new(1.0, Vector::<3>::zeros(), [0.0; 3]);
        let mut stream = Stream::new(7);
        let new = fill(&region, 0.2, &mut placer, 0.0, &grains, &mut stream, 1000);
        let across = new.iter().map(|(x, _)| x[0].abs().max(x[1].abs()));
        let along = new.iter().map(|(x, _)| (x[2] - 5.0).abs());
        (
            new.len(),
            across.fold(0.0, f64::max),
            along.fold(0.0, f64::max),
        )
    }

    #[test]
    fn an_inlet_fills_grains_wholly_inside_or_with_centres_anywhere_across() {
        // A fifth of 360 is 72 unit volumes, π/6 each: 138 grains either way.
        let wanted = (0.2 * 360.0 / (std::f64::consts::PI / 6.0)).ceil() as usize;
        let (n_inside, across_inside, along_inside) = filled(false);
        let (n_centres, across_centres, along_centres) = filled(true);
        assert_eq!((n_inside, n_centres), (wanted, wanted));
        // Wholly inside: every centre a radius in from the sides.
        assert!(across_inside <= 2.5, "{across_inside}");
        // Centres anywhere: some within the outer half diameter (138 draws
        // over the 6 × 6 square leave none there with odds of 10⁻²²).
        assert!(
            across_centres > 2.5 && across_centres <= 3.0,
            "{across_centres}"
        );
        // Along the height both stay wholly inside.
        assert!(along_inside <= 4.5 && along_centres <= 4.5);
    }

    #[test]
    fn a_bed_is_at_rest_but_for_its_exempt_grains() {
        // The slow grains alone hold 5·10⁻⁷ each, below the threshold; one
        // fast grain raises the mean to 3·10⁻³.
        assert!(at_rest(0, 0.0));
        assert!(!at_rest(1, 0.0));
        // 0.5 % of 200 is one grain: one fast grain is left out, two are not.
        assert!(at_rest(1, 0.005));
        assert!(!at_rest(2, 0.005));
        // 1 % is two.
        assert!(at_rest(2, 0.01));
        assert!(!at_rest(3, 0.01));
    }

    /// The fields a scene names as refused.
    fn refused(protocol: &str, overrides: &[&str]) -> Vec<String> {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Scene::from_toml(&format!("protocol = \"{protocol}\""), &overrides)
            .expect_err("the scene is refused")
            .errors
            .into_iter()
            .map(|e| e.field)
            .collect()
    }

    #[test]
    fn both_pours_refuse_a_dense_fill_and_a_settling_window_upside_down() {
        for key in ["heap", "packing"] {
            let fill = refused(key, &[&format!("{key}.fill_fraction=0.6")]);
            assert_eq!(fill, [format!("{key}.fill_fraction")]);
            let window = [
                format!("{key}.settle_min=50"),
                format!("{key}.settle_max=40"),
            ];
            let window: Vec<&str> = window.iter().map(String::as_str).collect();
            assert_eq!(refused(key, &window), [format!("{key}.settle_max")]);
            let rest = refused(key, &[&format!("{key}.rest_energy=0")]);
            assert_eq!(rest, [format!("{key}.rest_energy")]);
        }
    }
}

//! The model of Elekes & Parteli (2021): spheres with rotation, viscoelastic
//! Hertz normal contacts (eq. 10), a Mindlin tangential spring capped by
//! Coulomb friction (eq. 11), elastic–plastic rolling resistance (eq. 15,
//! `epsd2`) and van der Waals cohesion (eqs. 13–14), in SI units. The bottom
//! plate is made of the grains' material but has no cohesion. Every gap the
//! paper leaves open is pinned in `docs/model.md`.

use super::{assemble, select, Build, EngineJob, Laws, Model};
use crate::doc::Doc;
use crate::scene::{AttractionStep, Checks, Scene, SceneError, Section, SectionDecl};
use repose_engine::contact::{
    restitution, Cap, CohesionLaw, Cohesive, Epsd2, Limits, MindlinSpring, NoCohesion, NoRolling,
    Pairwise, RollingLaw, VanDerWaals, ViscoelasticHertz,
};
use repose_engine::integrate::{Gear5, Integrator, Scheme, VelocityVerlet};
use repose_engine::simulation::Units;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::collections::BTreeMap;
use std::marker::PhantomData;

pub const NAME: &str = "elekes_parteli";

/// Collision time of a Hertz contact as a multiple of `(m_eff/k_n)^{2/5} v^{-1/5}`.
pub const HERTZ_TIME: f64 = 3.21;

/// The model's entry in the registry.
pub struct ElekesParteli;

/// One size of a mixture of grains.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SizeFraction {
    /// Diameter, m.
    pub diameter: f64,
    /// Share of the grains (by number) with this diameter.
    pub fraction: f64,
}

/// The grains: one size (the paper's), or a mixture of sizes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Grains {
    /// Diameter `d`, m.
    pub diameter: f64,
    /// Density `ρ`, kg/m³.
    pub density: f64,
    /// Sizes of a mixture by number fraction; when given, it replaces
    /// `diameter` for the grains drawn (the contact damping is set for
    /// `diameter`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub mix: Vec<SizeFraction>,
}

impl Default for Grains {
    fn default() -> Self {
        Grains {
            diameter: 1e-3,
            density: 2500.0,
            mix: Vec::new(),
        }
    }
}

impl Grains {
    /// The smallest and largest diameters a grain can have.
    pub fn diameter_range(&self) -> (f64, f64) {
        if self.mix.is_empty() {
            return (self.diameter, self.diameter);
        }
        self.mix
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
                (lo.min(s.diameter), hi.max(s.diameter))
            })
    }

    /// Mass of a grain of diameter `d`, kg.
    pub fn mass(&self, d: f64) -> f64 {
        std::f64::consts::PI / 6.0 * self.density * d * d * d
    }
}

impl Section for Grains {
    const KEY: &'static str = "grains";
    const ABOUT: &'static str = "sphere diameter (or a mixture of sizes) and density, SI units";

    fn check(&self, _scene: &Scene, c: &mut Checks) {
        c.positive("grains.diameter", self.diameter);
        c.positive("grains.density", self.density);
        for (k, s) in self.mix.iter().enumerate() {
            c.positive(&format!("grains.mix[{k}].diameter"), s.diameter);
            c.positive(&format!("grains.mix[{k}].fraction"), s.fraction);
        }
        let total: f64 = self.mix.iter().map(|s| s.fraction).sum();
        if !self.mix.is_empty() && (total - 1.0).abs() > 1e-6 {
            c.fail(
                "grains.mix",
                format!("the fractions add up to {total}, not 1"),
            );
        }
    }
}

/// How `A_n` is found from the restitution coefficient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Damping {
    /// Solved on the collision as the scene's integrator steps it at the
    /// scene's step (velocity Verlet; Gear-5 runs at a step fine enough to
    /// be exact): a collision at the impact speed rebounds, on average over
    /// the instant of first contact, with the asked restitution.
    #[default]
    Solved,
    /// Solved on the exactly integrated collision, whatever the step:
    /// velocity Verlet at a tenth of the collision time then rebounds with
    /// 0.188 for an asked 0.2.
    Exact,
    /// The Müller–Pöschel Padé approximant the paper used (a few per cent
    /// less restitution than asked).
    Pade,
}

/// Rolling resistance model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Rolling {
    /// Elastic–plastic spring, eq. (15) (LIGGGHTS `epsd2`).
    #[default]
    Epsd2,
    None,
}

/// The cohesion laws the model offers, one line each: the option's value
/// (`material.cohesion`), its variant of [`Cohesion`] and the engine's law,
/// which builds itself from the material's [`Cohesive`] quantities. The
/// first is the default; `none` must stay.
macro_rules! cohesion_laws {
    ($($(#[doc = $doc:literal])* $name:literal => $variant:ident($law:ty),)+) => {
        /// Cohesion model.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
        pub enum Cohesion {
            $($(#[doc = $doc])* #[serde(rename = $name)] $variant,)+
        }

        impl Default for Cohesion {
            fn default() -> Self {
                [$(Cohesion::$variant),+][0]
            }
        }

        $(impl Build<Parts> for $law {
            fn build(p: &Parts) -> Self {
                <$law as CohesionLaw<3>>::of(&p.cohesion)
            }
        })+

        /// Runs `job` with the law `cohesion` names as its type.
        fn with_cohesion<J: CohesionJob>(cohesion: Cohesion, job: J) -> J::Output {
            match cohesion {
                $(Cohesion::$variant => job.run::<$law>(),)+
            }
        }
    };
}

cohesion_laws! {
    /// Van der Waals attraction, eqs. (13)–(14).
    "vdw" => Vdw(VanDerWaals),
    /// No attraction.
    "none" => None(NoCohesion),
}

/// Something to do with the cohesion law a scene selects, as a type.
trait CohesionJob {
    type Output;
    fn run<C: CohesionLaw<3> + Build<Parts>>(self) -> Self::Output;
}

/// The attraction of two surfaces `surfaces` of effective radius `r_eff`
/// just touching, by the cohesion law a scene selects.
struct PullAtContact {
    surfaces: Cohesive,
    r_eff: f64,
}

impl CohesionJob for PullAtContact {
    type Output = f64;

    fn run<C: CohesionLaw<3> + Build<Parts>>(self) -> f64 {
        C::of(&self.surfaces).at_contact(self.r_eff)
    }
}

/// What the Coulomb limit caps while a contact slides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TangentialCap {
    /// Spring and damper together (the paper's eq. 11).
    #[default]
    Total,
    /// The spring alone, damper dropped while sliding (LIGGGHTS).
    Spring,
}

/// The normal force that bounds sliding (eq. 11) and rolling (eq. 15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum LimitLoad {
    /// The contact's repulsion `|F_n^c|` of eq. 10, as eqs. 11 and 15 print
    /// it (and LIGGGHTS's default): the attraction presses a cohesive contact
    /// harder and so raises both limits.
    Contact,
    /// The net normal force, repulsion less attraction (never below zero):
    /// the attraction then holds contacts together without making them
    /// rougher. The default: with the fading attraction, the form whose
    /// glass-stiff heaps fit the paper's eq. 1 (docs/model-3d.md).
    #[default]
    Net,
    /// The size of the net normal force, `|F_n − F_vdW|`, damping included
    /// and not floored (LIGGGHTS 2.x–3.3.1, which adds the cohesive force
    /// into the force both caps read): like `net` at rest, but a contact
    /// under tension keeps friction in proportion to the tension.
    Liggghts,
}

impl LimitLoad {
    fn limits(self) -> Limits {
        match self {
            LimitLoad::Contact => Limits::Repulsion,
            LimitLoad::Net => Limits::Net,
            LimitLoad::Liggghts => Limits::NetAbsolute,
        }
    }
}

/// The van der Waals attraction of two touching grains.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ContactAttraction {
    /// Its value at zero gap, whatever the overlap (eq. 13 as printed).
    Constant,
    /// The Hamaker law continued into contact with the overlap as the
    /// distance, `A_H R_eff / (6 (δ + D_min)²)`: it falls as the grains
    /// press into each other, so stiff grains hold harder than soft ones.
    /// The default, with net limits.
    #[default]
    Fading,
}

/// How the surface energy follows a softened Young's modulus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum CohesionScaling {
    /// `γ` unchanged: the cohesive force, and so its ratio to the weight
    /// (the Bond number), stay those of the real material.
    #[default]
    None,
    /// `γ (Y/Y_true)^{2/5}`: a collision keeps the sticking speed of the
    /// real material (Chen, Liu & Li 2018), at the cost of a weaker cohesive force.
    Sticking,
    /// `γ` unchanged and the restitution raised to `ε (Y_true/Y)^{1/5}`
    /// (cohesive materials only): the attraction holds as hard as the real
    /// material's, and the raised restitution takes back most of the rise
    /// of the speed below which colliding grains stick (not all of it, and
    /// at the cost of bouncier collisions: measured in docs/model-3d.md).
    /// Possible while that restitution stays below 1.
    Restitution,
}

/// Young's modulus of glass beads (Table 1), Pa.
pub const GLASS_MODULUS: f64 = 63e9;

/// The grains' material (Table 1 of the paper: glass beads) and the
/// contact model's options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Material {
    /// Young's modulus `Y`, Pa; the true modulus unless `modulus_fraction`,
    /// `kappa` or `kappa_cohesion` soften it.
    pub youngs_modulus: Option<f64>,
    /// Softening by a fixed fraction of the true modulus: where
    /// `youngs_modulus` is not given, `Y = fraction × true_modulus`, the same
    /// at every grain size and gravity. (Left out of the written scene when
    /// unset, so scenes without it keep their sample hashes.)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub modulus_fraction: Option<f64>,
    /// Softening by the stiffness number `κ = Y/(ρ g d)`: where
    /// `youngs_modulus` is not given, `Y = κ ρ g d`. Two scenes with the
    /// same `κ` (and no cohesion) are one scene on another clock.
    pub kappa: Option<f64>,
    /// The least cohesion number `κ_c = Y d/(π γ)` a softened modulus keeps:
    /// cohesion presses contacts to an overlap of about `(2.8/κ_c)^{2/3} d`,
    /// so softening stops where that would be too deep.
    pub kappa_cohesion: Option<f64>,
    /// How `γ` follows a softened modulus.
    pub cohesion_scaling: CohesionScaling,
    /// The real material's modulus (glass's by default), the reference of
    /// softening and of `cohesion_scaling`, Pa.
    pub true_modulus: f64,
    /// Poisson's ratio `ν`.
    pub poisson_ratio: f64,
    /// Normal restitution coefficient `ε` at `impact_speed`.
    pub restitution: f64,
    /// The impact speed at which `restitution` holds, m/s.
    pub impact_speed: f64,
    /// Sliding friction `μ_s`.
    pub friction: f64,
    /// Rolling friction `μ_r`.
    pub rolling_friction: f64,
    /// Surface energy `γ`, J/m².
    pub surface_energy: f64,
    /// Van der Waals cut-off at contact `D_min`, m.
    pub d_min: f64,
    /// Largest gap of the attraction `D_max`, m.
    pub d_max: f64,
    pub damping: Damping,
    pub rolling: Rolling,
    pub cohesion: Cohesion,
    pub tangential_cap: TangentialCap,
    pub limit_load: LimitLoad,
    pub contact_attraction: ContactAttraction,
    /// Whether grains rotate (rolling resistance needs it).
    pub rotation: bool,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            youngs_modulus: None,
            modulus_fraction: None,
            kappa: None,
            kappa_cohesion: None,
            cohesion_scaling: CohesionScaling::None,
            true_modulus: GLASS_MODULUS,
            poisson_ratio: 0.24,
            restitution: 0.2,
            impact_speed: 1.0,
            friction: 0.5,
            rolling_friction: 0.05,
            surface_energy: 0.05,
            d_min: 1.65e-10,
            d_max: 1e-6,
            damping: Damping::Solved,
            rolling: Rolling::Epsd2,
            cohesion: Cohesion::Vdw,
            tangential_cap: TangentialCap::Total,
            limit_load: LimitLoad::Net,
            contact_attraction: ContactAttraction::Fading,
            rotation: true,
        }
    }
}

impl Section for Material {
    const KEY: &'static str = "material";
    const ABOUT: &'static str =
        "elastic constants, restitution, friction, rolling friction, surface energy and the model options";

    fn check(&self, scene: &Scene, c: &mut Checks) {
        if let Some(y) = self.youngs_modulus {
            c.positive("material.youngs_modulus", y);
        }
        if let Some(f) = self.modulus_fraction {
            c.positive("material.modulus_fraction", f);
            if f > 1.0 {
                c.fail(
                    "material.modulus_fraction",
                    "must not exceed 1 (the true modulus)",
                );
            }
        }
        if let Some(k) = self.kappa {
            c.positive("material.kappa", k);
        }
        if let Some(k) = self.kappa_cohesion {
            c.positive("material.kappa_cohesion", k);
        }
        c.positive("material.true_modulus", self.true_modulus);
        c.finite("material.poisson_ratio", self.poisson_ratio);
        if !(0.0..0.5).contains(&self.poisson_ratio) {
            c.fail("material.poisson_ratio", "must lie in [0, 0.5)");
        }
        c.positive("material.restitution", self.restitution);
        if self.restitution > 1.0 {
            c.fail("material.restitution", "must not exceed 1");
        }
        self.check_scaled_restitution(scene, c);
        c.positive("material.impact_speed", self.impact_speed);
        c.non_negative("material.friction", self.friction);
        c.non_negative("material.rolling_friction", self.rolling_friction);
        c.non_negative("material.surface_energy", self.surface_energy);
        c.positive("material.d_min", self.d_min);
        c.non_negative("material.d_max", self.d_max);
        if !self.rotation && self.rolls() {
            c.fail(
                "material.rotation",
                "rolling resistance acts on rotating grains: set rotation = true, or rolling = \"none\"",
            );
        }
    }
}

impl Material {
    /// A restitution raised by `cohesion_scaling = "restitution"` must stay
    /// below 1: softer than that, no collision dissipates enough.
    fn check_scaled_restitution(&self, scene: &Scene, c: &mut Checks) {
        if self.cohesion_scaling != CohesionScaling::Restitution || !self.coheres() {
            return;
        }
        let Ok(grains) = scene.section::<Grains>() else {
            return;
        };
        let g = scene.gravity_magnitude();
        let y = self.modulus(grains, g);
        let e = self.restitution_at(y);
        if y > 0.0 && e >= 1.0 {
            c.fail(
                "material.cohesion_scaling",
                format!(
                    "\"restitution\" would raise the restitution to {e:.2} at Y = {y:.3e} Pa: soften less (at most {:.0}× for ε = {})",
                    self.restitution.powf(-5.0),
                    self.restitution
                ),
            );
        }
    }

    /// The modulus simulated: the given one; or softened to the largest of
    /// `fraction × Y_true`, `κ ρ g d` and `κ_c π γ / d` (those set), never
    /// stiffer than the true modulus; or the true modulus.
    pub fn modulus(&self, grains: &Grains, g: f64) -> f64 {
        if let Some(y) = self.youngs_modulus {
            return y;
        }
        let d = grains.diameter;
        let gravity = self.kappa.map(|k| k * grains.density * g * d);
        let cohesion = self
            .kappa_cohesion
            .map(|k| k * std::f64::consts::PI * self.surface_energy / d);
        let fraction = self.modulus_fraction.map(|f| f * self.true_modulus);
        match [fraction, gravity, cohesion]
            .into_iter()
            .flatten()
            .filter(|y| *y > 0.0)
            .reduce(f64::max)
        {
            Some(y) => y.min(self.true_modulus),
            None => self.true_modulus,
        }
    }

    /// The material as simulated: its modulus written out and its surface
    /// energy scaled as `cohesion_scaling` asks.
    pub fn effective(&self, grains: &Grains, g: f64) -> Material {
        let y = self.modulus(grains, g);
        let gamma = match self.cohesion_scaling {
            CohesionScaling::None | CohesionScaling::Restitution => self.surface_energy,
            CohesionScaling::Sticking => self.surface_energy * (y / self.true_modulus).powf(0.4),
        };
        Material {
            youngs_modulus: Some(y),
            modulus_fraction: None,
            kappa: None,
            kappa_cohesion: None,
            cohesion_scaling: CohesionScaling::None,
            surface_energy: gamma,
            restitution: self.restitution_at(y),
            ..self.clone()
        }
    }

    /// The restitution simulated at modulus `y`: the asked one, unless
    /// `cohesion_scaling = "restitution"` raises it for a softened cohesive
    /// material.
    pub fn restitution_at(&self, y: f64) -> f64 {
        if self.cohesion_scaling == CohesionScaling::Restitution && self.coheres() {
            self.restitution * (self.true_modulus / y).powf(0.2)
        } else {
            self.restitution
        }
    }

    fn youngs(&self) -> f64 {
        self.youngs_modulus.unwrap_or(self.true_modulus)
    }

    /// `2Y / (3(1 − ν²))`: the normal stiffness per `√R_eff`.
    pub fn normal_modulus(&self) -> f64 {
        let nu = self.poisson_ratio;
        2.0 * self.youngs() / (3.0 * (1.0 - nu * nu))
    }

    /// `4G / (2 − ν)` with `G = Y / (2(1 + ν))`: the tangential stiffness per `√(R_eff δ)`.
    pub fn tangential_modulus(&self) -> f64 {
        let nu = self.poisson_ratio;
        let shear = self.youngs() / (2.0 + 2.0 * nu);
        4.0 * shear / (2.0 - nu)
    }

    /// Whether the scene has rolling resistance at all.
    pub fn rolls(&self) -> bool {
        self.rolling == Rolling::Epsd2 && self.rolling_friction > 0.0
    }

    /// The cohesion law simulated: the one asked for, none without surface energy.
    pub fn cohesion_law(&self) -> Cohesion {
        if self.surface_energy > 0.0 {
            self.cohesion
        } else {
            Cohesion::None
        }
    }

    /// Whether the scene has cohesion at all.
    pub fn coheres(&self) -> bool {
        self.cohesion_law() != Cohesion::None
    }

    /// The collision's dimensionless damping for the restitution asked,
    /// for a contact stepped by velocity Verlet at `verlet_step` (in units
    /// of the collision, [`Kind::unit`]) if it is.
    fn damping_number(&self, verlet_step: Option<f64>) -> f64 {
        match (self.damping, verlet_step) {
            (Damping::Solved, Some(h)) => restitution::solved_verlet(self.restitution, h),
            (Damping::Solved | Damping::Exact, _) => restitution::solved(self.restitution),
            (Damping::Pade, _) => restitution::pade(self.restitution),
        }
    }
}

/// The contact between two grains of diameter `d`, or a grain and the plate.
#[derive(Debug, Clone, Copy)]
pub struct Kind {
    pub r_eff: f64,
    pub m_eff: f64,
}

impl Kind {
    pub fn pair(grains: &Grains, d: f64) -> Kind {
        Kind {
            r_eff: 0.25 * d,
            m_eff: 0.5 * grains.mass(d),
        }
    }

    pub fn plate(grains: &Grains, d: f64) -> Kind {
        Kind {
            r_eff: 0.5 * d,
            m_eff: grains.mass(d),
        }
    }

    /// `k_n` of this kind of contact.
    pub fn stiffness(&self, m: &Material) -> f64 {
        m.normal_modulus() * self.r_eff.sqrt()
    }

    /// The collision's unit of time at `speed`, `(m_eff/k_n)^{2/5} v^{−1/5}`, s.
    pub fn unit(&self, m: &Material, speed: f64) -> f64 {
        (self.m_eff / self.stiffness(m)).powf(0.4) * speed.powf(-0.2)
    }

    /// Hertz collision time at `speed`, s.
    pub fn collision_time(&self, m: &Material, speed: f64) -> f64 {
        HERTZ_TIME * self.unit(m, speed)
    }

    /// `A_n` for this kind from the dimensionless damping `a`, s.
    pub fn damping(&self, m: &Material, a: f64) -> f64 {
        restitution::damping_constant(a, self.stiffness(m), self.m_eff, m.impact_speed)
    }
}

/// The components of one kind of contact.
#[derive(Debug, Clone, Copy)]
pub struct Parts {
    pub normal: ViscoelasticHertz,
    pub tangential: MindlinSpring,
    pub rolling: Epsd2,
    pub cohesion: Cohesive,
}

impl Parts {
    /// Grain–grain (`cohesive`) or grain–plate contacts with damping constant `a_n`.
    pub fn new(m: &Material, a_n: f64, cohesive: bool) -> Parts {
        Parts {
            normal: ViscoelasticHertz {
                modulus: m.normal_modulus(),
                damping: a_n,
            },
            tangential: MindlinSpring {
                modulus: m.tangential_modulus(),
                damping: 1.5 * a_n * m.normal_modulus(),
                mu: m.friction,
                cap: match m.tangential_cap {
                    TangentialCap::Total => Cap::Total,
                    TangentialCap::Spring => Cap::Spring,
                },
            },
            rolling: Epsd2 {
                modulus: m.tangential_modulus(),
                mu: m.rolling_friction,
            },
            cohesion: Cohesive {
                surface_energy: if cohesive { m.surface_energy } else { 0.0 },
                d_min: m.d_min,
                d_max: m.d_max,
                limits: m.limit_load.limits(),
                fades_in_contact: m.contact_attraction == ContactAttraction::Fading,
                sweep: 0.0,
            },
        }
    }
}

impl Build<Parts> for ViscoelasticHertz {
    fn build(p: &Parts) -> Self {
        p.normal
    }
}

impl Build<Parts> for MindlinSpring {
    fn build(p: &Parts) -> Self {
        p.tangential
    }
}

impl Build<Parts> for Epsd2 {
    fn build(p: &Parts) -> Self {
        p.rolling
    }
}

/// The contact law of the model with rolling law `R`, cohesion `C` and rotation `ROT`.
pub type Law<R, C, const ROT: bool> = Pairwise<ViscoelasticHertz, MindlinSpring, R, C, ROT>;

/// The law with rolling law `R`, cohesion `C` and rotation `ROT` from its parts.
pub fn law<R: Build<Parts>, C: Build<Parts>, const ROT: bool>(p: &Parts) -> Law<R, C, ROT> {
    assemble(p)
}

/// The grains and the material as simulated.
pub fn material(scene: &Scene) -> Result<(Grains, Material), SceneError> {
    let grains: &Grains = scene.section()?;
    let m: &Material = scene.section()?;
    let g = scene.gravity_magnitude();
    Ok((grains.clone(), m.effective(grains, g)))
}

/// The grain–grain and grain–plate parts of a scene, each kind of contact
/// damped for the restitution asked at the scene's step.
pub fn parts(scene: &Scene) -> Result<(Parts, Parts), SceneError> {
    let (grains, m) = material(scene)?;
    Ok(parts_of(scene, &grains, &m))
}

/// [`parts`] of the grains and the material as simulated.
fn parts_of(scene: &Scene, grains: &Grains, m: &Material) -> (Parts, Parts) {
    let d = grains.diameter;
    let dt = scene.time_step();
    let verlet = scene.numerics.integrator == Scheme::Verlet && dt.is_finite() && dt > 0.0;
    let damped = |kind: Kind| {
        let step = verlet.then(|| dt / kind.unit(m, m.impact_speed));
        kind.damping(m, m.damping_number(step))
    };
    let mut pair = Parts::new(m, damped(Kind::pair(grains, d)), true);
    if scene.numerics.attraction_step == AttractionStep::Swept {
        pair.cohesion.sweep = dt;
    }
    let plate = Parts::new(m, damped(Kind::plate(grains, d)), false);
    (pair, plate)
}

/// Runs `job` on the engine for the scene's integrator and options.
pub fn with_engine<J: EngineJob<3>>(scene: &Scene, job: J) -> Result<J::Output, SceneError> {
    let (grains, m) = material(scene)?;
    let (pair, plate) = parts_of(scene, &grains, &m);
    select! {
        I = scene.numerics.integrator => {
            Scheme::Gear5 => Gear5,
            Scheme::Verlet => VelocityVerlet,
        };
        T = (m.rotation, m.rolls()) => {
            (true, true) => Turning<Epsd2, true>,
            (true, false) => Turning<NoRolling, true>,
            (false, _) => Turning<NoRolling, false>,
        };
        => {
            let engine = Engine::<J, I, T> { job, pair, plate, types: PhantomData };
            Ok(with_cohesion(m.cohesion_law(), engine))
        }
    }
}

/// Rolling law `R`, and whether the grains turn (`ROT`).
struct Turning<R, const ROT: bool>(PhantomData<R>);

/// A job on integrator `I` with the rolling and rotation `T`, and the parts
/// of its contacts, waiting for the cohesion law.
struct Engine<J, I, T> {
    job: J,
    pair: Parts,
    plate: Parts,
    types: PhantomData<(I, T)>,
}

impl<J, I, R, const ROT: bool> CohesionJob for Engine<J, I, Turning<R, ROT>>
where
    J: EngineJob<3>,
    I: Integrator<3>,
    R: RollingLaw<3> + Build<Parts>,
{
    type Output = J::Output;

    fn run<C: CohesionLaw<3> + Build<Parts>>(self) -> J::Output {
        let laws = Laws {
            pair: law::<R, C, ROT>(&self.pair),
            wall: law::<R, C, ROT>(&self.plate),
        };
        self.job.run::<Law<R, C, ROT>, I>(laws)
    }
}

impl Model for ElekesParteli {
    fn name(&self) -> &'static str {
        NAME
    }

    fn about(&self) -> &'static str {
        "Elekes & Parteli (2021): rotating spheres, viscoelastic Hertz–Mindlin contacts, rolling resistance and van der Waals cohesion, SI units"
    }

    fn dimensions(&self) -> &'static [usize] {
        &[3]
    }

    fn units(&self) -> Units {
        Units::SI
    }

    fn sections(&self) -> Vec<SectionDecl> {
        vec![SectionDecl::of::<Grains>(), SectionDecl::of::<Material>()]
    }

    /// Earth's gravity, velocity Verlet with a step of a tenth of the
    /// collision time (the paper's; Gear-5 needs a hundredth: at a tenth it
    /// adds energy to a damped Hertz collision), and a neighbour skin of a
    /// fifth of the largest grain.
    fn defaults(&self, _dimension: usize, d: &Doc) -> Doc {
        let grains: Grains = d
            .get(Grains::KEY)
            .and_then(|v| serde_json::from_value(v.clone()).ok())
            .unwrap_or_default();
        let gear = d
            .get("numerics")
            .and_then(|n| n.get("integrator"))
            .and_then(|v| v.as_str())
            == Some("gear5");
        let largest = grains.diameter_range().1;
        let mut numerics = Doc::new();
        numerics.insert("integrator".into(), json!("verlet"));
        numerics.insert("dt_factor".into(), json!(if gear { 0.01 } else { 0.1 }));
        if largest.is_finite() && largest > 0.0 {
            numerics.insert("skin".into(), json!(0.2 * largest));
        }
        let mut out = Doc::new();
        out.insert("gravity".into(), json!([0.0, 0.0, -9.81]));
        out.insert("numerics".into(), serde_json::Value::Object(numerics));
        out
    }

    fn check(&self, scene: &Scene, c: &mut Checks) {
        if let Ok(grains) = scene.section::<Grains>() {
            super::check_skin(scene, grains.diameter_range().1, c);
        }
        let Ok(m) = scene.section::<Material>() else {
            return;
        };
        let g = scene.gravity_magnitude();
        if m.youngs_modulus.is_none() && m.kappa.is_some() && g == 0.0 {
            c.fail(
                "material.kappa",
                "sets Y = κ ρ g d, which needs gravity; give material.youngs_modulus instead",
            );
        }
    }

    /// Writes out the modulus simulated.
    fn resolve(&self, scene: &mut Scene) {
        let (Ok(grains), Ok(m)) = (scene.section::<Grains>(), scene.section::<Material>()) else {
            return;
        };
        let g = scene.gravity_magnitude();
        let m = Material {
            youngs_modulus: Some(m.modulus(grains, g)),
            ..m.clone()
        };
        scene.set_section(m);
    }

    /// The shorter of the grain–grain and grain–plate Hertz collision times
    /// of the smallest grain at the reference speed, s.
    fn contact_time(&self, scene: &Scene) -> f64 {
        let Ok((grains, m)) = material(scene) else {
            return f64::NAN;
        };
        let d = grains.diameter_range().0;
        let v = scene.impact_speed();
        let pair = Kind::pair(&grains, d).collision_time(&m, v);
        let plate = Kind::plate(&grains, d).collision_time(&m, v);
        pair.min(plate)
    }

    /// `m_eff √(g d) / F_0` of the smallest grains, with `F_0` the
    /// attraction of two of them touching (`π γ d` for van der Waals as
    /// simulated), read off the law the scene selects.
    fn attraction_time(&self, scene: &Scene) -> Option<f64> {
        let (grains, m) = material(scene).ok()?;
        let g = scene.gravity_magnitude();
        if !m.coheres() || g <= 0.0 {
            return None;
        }
        let d = grains.diameter_range().0;
        let pair = Kind::pair(&grains, d);
        let surfaces = Parts::new(&m, 0.0, true).cohesion;
        let pull = with_cohesion(
            m.cohesion_law(),
            PullAtContact {
                surfaces,
                r_eff: pair.r_eff,
            },
        );
        (pull > 0.0).then(|| pair.m_eff * (g * d).sqrt() / pull)
    }

    fn density(&self, scene: &Scene) -> f64 {
        scene.section::<Grains>().map_or(f64::NAN, |g| g.density)
    }

    /// Heaps and columns of thousands of spheres: ordering them in space
    /// keeps the pair loop in cache and lets threads share the work.
    fn sort_every(&self) -> u64 {
        1000
    }

    fn options(&self, scene: &Scene) -> BTreeMap<String, String> {
        let m = scene.section::<Material>().cloned().unwrap_or_default();
        let name = |v: serde_json::Value| v.as_str().unwrap_or_default().to_string();
        let on = |b: bool, what: &str| {
            if b {
                what.to_string()
            } else {
                "none".to_string()
            }
        };
        BTreeMap::from([
            ("damping".to_string(), name(json!(m.damping))),
            ("rolling".to_string(), on(m.rolls(), "epsd2")),
            ("cohesion".to_string(), name(json!(m.cohesion_law()))),
            ("tangential_cap".to_string(), name(json!(m.tangential_cap))),
            ("limit_load".to_string(), name(json!(m.limit_load))),
            (
                "contact_attraction".to_string(),
                name(json!(m.contact_attraction)),
            ),
            ("rotation".to_string(), m.rotation.to_string()),
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::{Grains, Material, GLASS_MODULUS};
    use crate::scene::Scene;

    fn grains(d: f64) -> Grains {
        Grains {
            diameter: d,
            ..Grains::default()
        }
    }

    #[test]
    fn a_fraction_of_the_true_modulus_softens_every_size_and_gravity_alike() {
        let m = Material {
            modulus_fraction: Some(0.1),
            ..Material::default()
        };
        for d in [1e-4, 1e-3] {
            for g in [1.61865, 9.81, 98.1] {
                assert_eq!(m.modulus(&grains(d), g), 0.1 * GLASS_MODULUS, "{d} {g}");
            }
        }
        // A given modulus wins; the largest of the softenings set holds.
        let given = Material {
            youngs_modulus: Some(1e8),
            ..m.clone()
        };
        assert_eq!(given.modulus(&grains(1e-3), 9.81), 1e8);
        let stiffer = Material {
            kappa: Some(1e9),
            ..m.clone()
        };
        let by_kappa = 1e9 * 2500.0 * 9.81 * 1e-3;
        assert!(by_kappa > 0.1 * GLASS_MODULUS);
        assert_eq!(stiffer.modulus(&grains(1e-3), 9.81), by_kappa);
        // The softened material as simulated carries the modulus alone.
        let simulated = m.effective(&grains(1e-3), 9.81);
        assert_eq!(simulated.youngs_modulus, Some(0.1 * GLASS_MODULUS));
        assert_eq!(simulated.modulus_fraction, None);
    }

    #[test]
    fn a_fraction_outside_zero_to_one_is_refused_by_name() {
        for bad in ["0", "-0.1", "1.5"] {
            let err = Scene::from_toml(
                "protocol = \"heap\"",
                &[format!("material.modulus_fraction={bad}")],
            )
            .unwrap_err();
            let fields: Vec<&str> = err.errors.iter().map(|e| e.field.as_str()).collect();
            assert_eq!(fields, ["material.modulus_fraction"], "{bad}: {err}");
        }
        assert!(Scene::from_toml(
            "protocol = \"heap\"",
            &["material.modulus_fraction=1".into()]
        )
        .is_ok());
    }

    #[test]
    fn a_scene_without_a_fraction_writes_none() {
        let v = serde_json::to_value(Material::default()).unwrap();
        assert!(v.get("modulus_fraction").is_none(), "{v}");
        assert!(v.get("kappa").is_some(), "{v}");
    }
}

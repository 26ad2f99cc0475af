//! The model of Lee & Herrmann (1993): grains of sphere mass with damped
//! Hertz normal contacts (eq. 2a) and Cundall–Strack static friction (eq.
//! 2b), without rotation, in CGS units. Walls use the same law with their
//! own stiffness. The law is written for any dimension: discs in the paper's
//! plane, and spheres in space.

use super::{assemble, select, Build, EngineJob, Laws, Model};
use crate::doc::Doc;
use crate::scene::{Checks, Scene, SceneError, Section, SectionDecl};
use crate::setup::{sphere_mass, Stream};
use repose_engine::contact::{CundallStrack, Frictionless, HertzDamped, NoCohesion, Pairwise};
use repose_engine::dim::{Dim, Space};
use repose_engine::integrate::{Gear5, Scheme, VelocityVerlet};
use repose_engine::simulation::Units;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::collections::BTreeMap;

pub const NAME: &str = "lee_herrmann";

/// The model's entry in the registry.
pub struct LeeHerrmann;

/// Grain material and size distribution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GrainSpec {
    /// Density, g/cm³; a grain of radius a has the sphere mass 4/3 π ρ a³.
    pub density: f64,
    /// Mean of the Gaussian radius distribution, cm.
    pub radius_mean: f64,
    /// Its standard deviation, cm (0 for equal grains).
    pub radius_sd: f64,
    /// Smallest radius kept (draws outside [min, max] are drawn again), cm.
    pub radius_min: f64,
    /// Largest radius kept, cm.
    pub radius_max: f64,
}

impl Default for GrainSpec {
    fn default() -> Self {
        GrainSpec {
            density: 1.0,
            radius_mean: 0.1,
            radius_sd: 0.02,
            radius_min: 0.07,
            radius_max: 0.13,
        }
    }
}

impl GrainSpec {
    /// Mean disc area of the radius distribution (cm²), for capacity checks.
    pub fn mean_disc_area(&self) -> f64 {
        std::f64::consts::PI
            * (self.radius_mean * self.radius_mean + self.radius_sd * self.radius_sd)
    }

    /// The largest radius a draw can give.
    pub fn largest(&self) -> f64 {
        self.radius_max.max(self.radius_mean)
    }

    /// A radius from the cut Gaussian, drawn from `stream`.
    pub fn draw_radius(&self, stream: &mut Stream) -> f64 {
        stream.cut_normal(
            self.radius_mean,
            self.radius_sd,
            self.radius_min,
            self.radius_max,
        )
    }
}

impl Section for GrainSpec {
    const KEY: &'static str = "grains";
    const ABOUT: &'static str = "grain density and the cut Gaussian of radii";

    fn check(&self, _scene: &Scene, c: &mut Checks) {
        c.positive("grains.density", self.density);
        c.positive("grains.radius_mean", self.radius_mean);
        c.non_negative("grains.radius_sd", self.radius_sd);
        c.positive("grains.radius_min", self.radius_min);
        c.positive("grains.radius_max", self.radius_max);
        let (min, max, mean) = (self.radius_min, self.radius_max, self.radius_mean);
        if !(min.is_finite() && max.is_finite() && mean.is_finite()) {
            return;
        }
        if min > max {
            c.fail(
                "grains.radius_min",
                format!("must not exceed grains.radius_max ({max})"),
            );
        } else if self.radius_sd > 0.0 && (mean < min || mean > max) {
            c.fail(
                "grains.radius_mean",
                format!("must lie within [radius_min, radius_max] = [{min}, {max}]"),
            );
        } else if self.radius_sd > 0.0 && max - min < 0.01 * self.radius_sd {
            // Draws outside the window are repeated; a window this narrow
            // would almost never be hit.
            c.fail(
                "grains.radius_sd",
                "the window [radius_min, radius_max] is too narrow for this spread; set radius_sd = 0 for equal grains",
            );
        }
    }
}

/// How the normal force behaves when damping would make it attractive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum NormalForce {
    /// `F_n` floored at zero: contacts only push.
    #[default]
    Floored,
    /// The paper's raw expression, which may pull briefly at separation.
    Raw,
}

/// What the shear spring does while a contact slides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShearSpringMode {
    /// The paper's form: the spring keeps growing while the contact slips.
    #[default]
    Paper,
    /// The spring is cut back to the Coulomb limit while it slips.
    Truncated,
}

/// Grain–grain contact law, eqs. (2a) and (2b).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSpec {
    /// Hertz constant, dyn/cm^{3/2}.
    pub k_n: f64,
    /// Normal damping, 1/s.
    pub gamma_n: f64,
    /// Shear spring constant, dyn/cm.
    pub k_s: f64,
    /// Shear damping, 1/s (the paper uses γ_n / 100).
    pub gamma_s: Option<f64>,
    /// Coulomb friction coefficient.
    pub mu: f64,
    pub normal_force: NormalForce,
    pub shear_spring: ShearSpringMode,
}

impl Default for ContactSpec {
    fn default() -> Self {
        ContactSpec {
            k_n: 1e6,
            gamma_n: 500.0,
            k_s: 1e4,
            gamma_s: None,
            mu: 0.2,
            normal_force: NormalForce::Floored,
            shear_spring: ShearSpringMode::Paper,
        }
    }
}

impl ContactSpec {
    pub fn gamma_s(&self) -> f64 {
        self.gamma_s.unwrap_or(self.gamma_n / 100.0)
    }
}

impl Section for ContactSpec {
    const KEY: &'static str = "contact";
    const ABOUT: &'static str =
        "grain–grain contacts: Hertz stiffness and damping, shear spring, friction";

    fn check(&self, _scene: &Scene, c: &mut Checks) {
        c.positive("contact.k_n", self.k_n);
        c.non_negative("contact.gamma_n", self.gamma_n);
        c.non_negative("contact.k_s", self.k_s);
        if let Some(gs) = self.gamma_s {
            c.non_negative("contact.gamma_s", gs);
        }
        c.non_negative("contact.mu", self.mu);
    }
}

/// Grain–wall contact: the same law with `a_j = 0` and `m_j = ∞`. Unset
/// values are taken from `[contact]`, except `k_n` (2·10⁶ in the paper).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WallContactSpec {
    pub k_n: f64,
    pub gamma_n: Option<f64>,
    pub k_s: Option<f64>,
    pub gamma_s: Option<f64>,
    pub mu: Option<f64>,
}

impl Default for WallContactSpec {
    fn default() -> Self {
        WallContactSpec {
            k_n: 2e6,
            gamma_n: None,
            k_s: None,
            gamma_s: None,
            mu: None,
        }
    }
}

impl Section for WallContactSpec {
    const KEY: &'static str = "wall_contact";
    const ABOUT: &'static str = "grain–wall contacts; unset values are the grain–grain ones";

    fn check(&self, _scene: &Scene, c: &mut Checks) {
        c.positive("wall_contact.k_n", self.k_n);
        for (name, v) in [
            ("wall_contact.gamma_n", self.gamma_n),
            ("wall_contact.k_s", self.k_s),
            ("wall_contact.gamma_s", self.gamma_s),
            ("wall_contact.mu", self.mu),
        ] {
            if let Some(v) = v {
                c.non_negative(name, v);
            }
        }
    }
}

/// The three sections of a scene.
struct Material<'a> {
    grains: &'a GrainSpec,
    contact: &'a ContactSpec,
    wall: &'a WallContactSpec,
}

impl Material<'_> {
    fn of(scene: &Scene) -> Result<Material<'_>, SceneError> {
        Ok(Material {
            grains: scene.section()?,
            contact: scene.section()?,
            wall: scene.section()?,
        })
    }

    /// Parameters of grain–grain contacts.
    fn pair(&self) -> Params {
        let c = &self.contact;
        Params {
            k_n: c.k_n,
            gamma_n: c.gamma_n,
            k_s: c.k_s,
            gamma_s: c.gamma_s(),
            mu: c.mu,
        }
    }

    /// Parameters of grain–wall contacts.
    fn wall(&self) -> Params {
        let (c, w) = (&self.contact, &self.wall);
        Params {
            k_n: w.k_n,
            gamma_n: w.gamma_n.unwrap_or(c.gamma_n),
            k_s: w.k_s.unwrap_or(c.k_s),
            gamma_s: w.gamma_s.unwrap_or(c.gamma_s()),
            mu: w.mu.unwrap_or(c.mu),
        }
    }

    /// Smallest radius any grain of the scene can have.
    fn smallest_radius(&self, scene: &Scene) -> f64 {
        let listed = scene
            .particles
            .iter()
            .map(|g| g.radius)
            .fold(f64::INFINITY, f64::min);
        let draws = scene.protocol().map(|p| p.draws_grains()).unwrap_or(true);
        if !draws {
            return listed;
        }
        if !scene.particles.is_empty() {
            return listed.min(self.grains.radius_min);
        }
        if self.grains.radius_sd == 0.0 {
            self.grains.radius_mean
        } else {
            self.grains.radius_min
        }
    }
}

/// The parameters of one kind of contact.
#[derive(Debug, Clone, Copy)]
struct Params {
    k_n: f64,
    gamma_n: f64,
    k_s: f64,
    gamma_s: f64,
    mu: f64,
}

impl<const FLOOR: bool> Build<Params> for HertzDamped<FLOOR> {
    fn build(p: &Params) -> Self {
        HertzDamped {
            k_n: p.k_n,
            gamma_n: p.gamma_n,
        }
    }
}

impl<const TRUNCATE: bool> Build<Params> for CundallStrack<TRUNCATE> {
    fn build(p: &Params) -> Self {
        CundallStrack {
            k_s: p.k_s,
            gamma_s: p.gamma_s,
            mu: p.mu,
        }
    }
}

/// The paper's grains do not cohere.
impl Build<Params> for NoCohesion {
    fn build(_: &Params) -> Self {
        NoCohesion
    }
}

/// Which tangential law a scene needs.
enum Friction {
    /// No friction and no shear damping anywhere: no shear history at all.
    None,
    Paper,
    Truncated,
}

/// The pair and wall laws from the chosen components.
fn laws<N: Build<Params>, T: Build<Params>>(m: &Material) -> Laws<Pairwise<N, T>> {
    Laws {
        pair: assemble(&m.pair()),
        wall: assemble(&m.wall()),
    }
}

/// Runs `job` on the engine for the scene's integrator and contact options.
pub fn with_engine<const D: usize, J: EngineJob<D>>(
    scene: &Scene,
    job: J,
) -> Result<J::Output, SceneError>
where
    Dim<D>: Space<D>,
{
    let m = Material::of(scene)?;
    let (pair, wall) = (m.pair(), m.wall());
    let friction = if pair.mu == 0.0 && pair.gamma_s == 0.0 && wall.mu == 0.0 && wall.gamma_s == 0.0
    {
        Friction::None
    } else {
        match m.contact.shear_spring {
            ShearSpringMode::Paper => Friction::Paper,
            ShearSpringMode::Truncated => Friction::Truncated,
        }
    };
    Ok(select! {
        I = scene.numerics.integrator => {
            Scheme::Gear5 => Gear5,
            Scheme::Verlet => VelocityVerlet,
        };
        N = m.contact.normal_force => {
            NormalForce::Floored => HertzDamped<true>,
            NormalForce::Raw => HertzDamped<false>,
        };
        T = friction => {
            Friction::None => Frictionless,
            Friction::Paper => CundallStrack<false>,
            Friction::Truncated => CundallStrack<true>,
        };
        => job.run::<Pairwise<N, T>, I>(laws::<N, T>(&m))
    })
}

impl Model for LeeHerrmann {
    fn name(&self) -> &'static str {
        NAME
    }

    fn about(&self) -> &'static str {
        "Lee & Herrmann (1993): damped Hertz contacts with Cundall–Strack friction, no rotation, CGS units"
    }

    fn dimensions(&self) -> &'static [usize] {
        &[2, 3]
    }

    fn sections(&self) -> Vec<SectionDecl> {
        vec![
            SectionDecl::of::<GrainSpec>(),
            SectionDecl::of::<ContactSpec>(),
            SectionDecl::of::<WallContactSpec>(),
        ]
    }

    fn units(&self) -> Units {
        Units::CGS
    }

    fn defaults(&self, dimension: usize, _doc: &Doc) -> Doc {
        let gravity = if dimension == 3 {
            json!([0.0, 0.0, -981.0])
        } else {
            json!([0.0, -981.0])
        };
        let mut d = Doc::new();
        d.insert("gravity".into(), gravity);
        d
    }

    fn check(&self, scene: &Scene, c: &mut Checks) {
        if let Ok(grains) = scene.section::<GrainSpec>() {
            super::check_skin(scene, 2.0 * grains.largest(), c);
        }
    }

    fn resolve(&self, scene: &mut Scene) {
        let (Ok(contact), Ok(wall)) = (
            scene.section::<ContactSpec>(),
            scene.section::<WallContactSpec>(),
        ) else {
            return;
        };
        let (mut contact, mut wall) = (contact.clone(), wall.clone());
        let gamma_s = contact.gamma_s();
        wall.gamma_n = Some(wall.gamma_n.unwrap_or(contact.gamma_n));
        wall.k_s = Some(wall.k_s.unwrap_or(contact.k_s));
        wall.gamma_s = Some(wall.gamma_s.unwrap_or(gamma_s));
        wall.mu = Some(wall.mu.unwrap_or(contact.mu));
        contact.gamma_s = Some(gamma_s);
        scene.set_section(contact);
        scene.set_section(wall);
    }

    /// Shortest contact duration among grain–grain and grain–wall contacts
    /// at the reference speed (Hertz, undamped), or the half period of the
    /// shear spring if that is shorter, s.
    fn contact_time(&self, scene: &Scene) -> f64 {
        let Ok(m) = Material::of(scene) else {
            return f64::NAN;
        };
        let a = m.smallest_radius(scene);
        let mass = sphere_mass(m.grains.density, a);
        let v = scene.numerics.reference_speed;
        let pair = crate::theory::hertz_contact_time(m.contact.k_n, 0.5 * mass, v);
        let wall = crate::theory::hertz_contact_time(m.wall.k_n, mass, v);
        let mut t = pair.min(wall);
        if m.contact.k_s > 0.0 {
            t = t.min(std::f64::consts::PI * (0.5 * mass / m.contact.k_s).sqrt());
        }
        let k_s = m.wall.k_s.unwrap_or(m.contact.k_s);
        if k_s > 0.0 {
            t = t.min(std::f64::consts::PI * (mass / k_s).sqrt());
        }
        t
    }

    fn density(&self, scene: &Scene) -> f64 {
        scene.section::<GrainSpec>().map_or(f64::NAN, |g| g.density)
    }

    fn options(&self, scene: &Scene) -> BTreeMap<String, String> {
        let c = scene.section::<ContactSpec>().cloned().unwrap_or_default();
        let name = |v: serde_json::Value| v.as_str().unwrap_or_default().to_string();
        BTreeMap::from([
            ("normal_force".to_string(), name(json!(c.normal_force))),
            ("shear_spring".to_string(), name(json!(c.shear_spring))),
        ])
    }
}

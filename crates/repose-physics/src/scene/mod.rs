//! The scene document: one declarative description of a sample.
//!
//! A scene is written as TOML (or the same structure as JSON). It names a
//! protocol (what experiment to run); the protocol names its dimension and
//! its contact model unless the scene does. The document then has two kinds
//! of parts:
//!
//! * the **core**, which every scene shares: `protocol`, `model`,
//!   `dimension`, `preset`, `seed`, `rng`, `gravity`, `[numerics]`, explicit
//!   `[[particles]]` and `[[walls]]`, and a `duration`;
//! * **sections**, each owned by the protocol (`[box]`, `[tilt]`, …) or by
//!   the contact model (`[grains]`, `[contact]`, …) and declared by it as a
//!   [`Section`] type with its defaults and its checks.
//!
//! Every value has a default — the paper's, or where the paper is silent,
//! the design notes' — so the smallest scene is `protocol = "fill_release"`.
//! Unknown keys and sections are refused, and validation names every field
//! it rejects, so the command line, the service and the workers share one
//! validation path. [`Scene::resolved`] writes out every derived value (the
//! wall friction, the number of grains, the time step); results store the
//! resolved scene, so a sample can be rerun from its record alone.

pub(crate) mod checks;

pub use checks::{Checks, FieldError, SceneError};

use crate::doc::Doc;
use crate::preset::Preset;
use repose_engine::integrate::Scheme;
use repose_engine::particles::Grain;
use repose_engine::walls::WallSpec;
use serde::de::DeserializeOwned;
use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize, Serializer};
use serde_json::Value;
use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

/// The pseudo-random generator behind placement and radii.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RngKind {
    /// ChaCha with 8 rounds (`rand_chacha::ChaCha8Rng`), seeded by `seed_from_u64`.
    #[default]
    Chacha8,
}

/// One sample, fully described.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// The registered protocol that runs this scene.
    pub protocol: String,
    /// The registered contact model (its sections hold the material).
    pub model: String,
    /// 2 (discs in a plane) or 3 (spheres in space).
    pub dimension: usize,
    /// Named fidelity preset; it fills the numerical settings the scene
    /// leaves unset (see [`crate::preset`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<Preset>,
    /// Seed of the random generator.
    pub seed: u64,
    pub rng: RngKind,
    /// Gravity vector (one component per dimension).
    pub gravity: Vec<f64>,
    pub numerics: Numerics,
    /// Explicit grains. For `free_run` they are the whole system; for the
    /// other protocols they replace the random filling.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub particles: Vec<Grain>,
    /// Explicit walls (`free_run` only).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<WallSpec>,
    /// Simulated time of a `free_run`, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// The protocol's and the model's sections, each complete with its
    /// defaults and parsed into its own type once, when the scene is built.
    #[serde(flatten)]
    pub sections: Sections,
}

/// The core of a scene document, as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Core {
    #[allow(dead_code)] // read before the core is parsed
    pub(crate) protocol: String,
    #[serde(default)]
    #[allow(dead_code)] // read before the core is parsed
    pub(crate) model: Option<String>,
    #[serde(default)]
    #[allow(dead_code)] // read before the core is parsed
    pub(crate) dimension: Option<usize>,
    #[serde(default)]
    pub(crate) preset: Option<Preset>,
    #[serde(default)]
    pub(crate) seed: u64,
    #[serde(default)]
    pub(crate) rng: RngKind,
    #[serde(default)]
    pub(crate) gravity: Option<Vec<f64>>,
    #[serde(default)]
    pub(crate) numerics: Numerics,
    #[serde(default)]
    pub(crate) particles: Vec<Grain>,
    #[serde(default)]
    pub(crate) walls: Vec<WallSpec>,
    #[serde(default)]
    pub(crate) duration: Option<f64>,
}

/// The keys of the core; every other top-level key is a section.
pub(crate) const CORE_KEYS: [&str; 11] = [
    "protocol",
    "model",
    "dimension",
    "preset",
    "seed",
    "rng",
    "gravity",
    "numerics",
    "particles",
    "walls",
    "duration",
];

/// Time stepping and neighbour search: the speed/accuracy knobs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Numerics {
    pub integrator: Scheme,
    /// Time step as a fraction of the contact time of the stiffest pair.
    pub dt_factor: f64,
    /// Impact speed at which that contact time is taken (or the protocol's
    /// fastest impact, if higher: see [`Scene::impact_speed`]).
    pub reference_speed: f64,
    /// Explicit time step, s; overrides `dt_factor`.
    pub dt: Option<f64>,
    /// Most speed, in `√(g d)` of the smallest grain, that the attraction of
    /// two touching grains may give them in one step: the step is shortened
    /// where `dt_factor` would allow more (none: no bound; ignored where
    /// grains do not attract). A step that crosses the attraction's edge
    /// (it falls from its contact value to nothing within a few `D_min`)
    /// applies it for a whole step or not at all, a random kick of up to
    /// this size each time a contact opens or closes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub attraction_kick: Option<f64>,
    /// How a pair feels the contact attraction through a step: at its gap
    /// (`point`), or as the mean over the gaps it sweeps in the step
    /// (`swept`), which gives a pair crossing the attraction's edge the
    /// impulse the law asks whatever the step, and so needs no
    /// `attraction_kick`. (Left out of the written scene at its default,
    /// so scenes without it keep their sample hashes.)
    #[serde(skip_serializing_if = "AttractionStep::is_point")]
    pub attraction_step: AttractionStep,
    /// Verlet-list skin.
    pub skin: f64,
    /// Largest overlap allowed, as a fraction of the smaller radius, before a run is failed.
    pub max_overlap: f64,
    /// Threads computing the forces of one sample. Results are
    /// bit-identical for any number, so it is not part of a sample's identity.
    #[serde(skip_serializing_if = "is_one")]
    pub threads: usize,
}

/// How a pair feels the contact attraction through a step
/// (`numerics.attraction_step`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum AttractionStep {
    /// The attraction at the pair's gap at the step's instant.
    #[default]
    Point,
    /// The mean of the attraction over the gaps the pair sweeps in the
    /// step (`repose_engine::contact::VanDerWaals::swept`).
    Swept,
}

impl AttractionStep {
    pub fn is_point(&self) -> bool {
        *self == AttractionStep::Point
    }
}

fn is_one(n: &usize) -> bool {
    *n == 1
}

/// Most threads one sample may ask for.
pub const MAX_THREADS: usize = 256;

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            integrator: Scheme::Gear5,
            dt_factor: 0.02,
            reference_speed: 1.0,
            dt: None,
            attraction_kick: None,
            attraction_step: AttractionStep::Point,
            skin: 0.04,
            max_overlap: 0.5,
            threads: 1,
        }
    }
}

/// A part of the scene document owned by a protocol or a model: its own
/// table (`[tilt]`, `[contact]`, …) with defaults for every key and checks
/// that name the fields they reject.
pub trait Section:
    Serialize + DeserializeOwned + Default + Clone + fmt::Debug + Send + Sync + 'static
{
    /// The table's key in the scene document.
    const KEY: &'static str;
    /// One line on what the section holds.
    const ABOUT: &'static str;
    /// Checks the values (with the rest of the scene at hand).
    fn check(&self, scene: &Scene, c: &mut Checks);
}

/// A section's value as a scene holds it, whatever its type.
trait Held: Any + Send + Sync + fmt::Debug {
    fn to_value(&self) -> Value;
    fn as_any(&self) -> &dyn Any;
}

impl<T: Section> Held for T {
    fn to_value(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// A scene's sections, each held as its own type under its key. Cloning a
/// scene shares them; replacing one ([`Scene::set_section`]) leaves the
/// other clones as they were.
#[derive(Clone, Default)]
pub struct Sections(BTreeMap<&'static str, Arc<dyn Held>>);

impl Sections {
    /// Whether the scene has the section `key`.
    pub fn contains_key(&self, key: &str) -> bool {
        self.0.contains_key(key)
    }

    /// The keys of the sections held, in order.
    pub fn keys(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.0.keys().copied()
    }

    /// The section `key` as a document (for reading by name, as the
    /// command line's tables do).
    pub fn value(&self, key: &str) -> Option<Value> {
        self.0.get(key).map(|s| s.to_value())
    }

    fn get<T: Section>(&self) -> Option<&T> {
        self.0.get(T::KEY)?.as_any().downcast_ref()
    }
}

impl Serialize for Sections {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (key, section) in &self.0 {
            map.serialize_entry(key, &section.to_value())?;
        }
        map.end()
    }
}

impl PartialEq for Sections {
    fn eq(&self, other: &Self) -> bool {
        self.0.len() == other.0.len()
            && self.0.iter().zip(&other.0).all(|((k, a), (l, b))| {
                k == l && (Arc::ptr_eq(a, b) || a.to_value() == b.to_value())
            })
    }
}

impl fmt::Debug for Sections {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_map().entries(&self.0).finish()
    }
}

/// Parses a section's table (under its key) into its own type.
type Parse = fn(&str, Value) -> Result<Arc<dyn Held>, SceneError>;

/// A section as the registry sees it, whatever its type.
#[derive(Clone, Copy)]
pub struct SectionDecl {
    pub key: &'static str,
    pub about: &'static str,
    parse: Parse,
    pub(crate) check: fn(&Scene, &mut Checks),
}

impl SectionDecl {
    pub fn of<T: Section>() -> Self {
        SectionDecl {
            key: T::KEY,
            about: T::ABOUT,
            parse: |key, value| {
                let typed: T = serde_path_to_error::deserialize(value).map_err(|e| {
                    let inner = e.path().to_string();
                    let field = if inner.is_empty() || inner == "." {
                        key.to_string()
                    } else {
                        format!("{key}.{inner}")
                    };
                    SceneError::single(field, e.inner().to_string())
                })?;
                Ok(Arc::new(typed))
            },
            check: |scene, c| match scene.section::<T>() {
                Ok(section) => section.check(scene, c),
                Err(e) => c.extend(e),
            },
        }
    }

    /// The section with every default filled in.
    pub fn defaults(&self) -> Value {
        (self.parse)(self.key, Value::Object(Doc::new())).map_or(Value::Null, |s| s.to_value())
    }

    /// Parses the section from its table in a document (missing keys take
    /// their defaults) into `into`; the error names the field it rejects.
    pub(crate) fn parse_into(&self, value: Value, into: &mut Sections) -> Result<(), SceneError> {
        into.0.insert(self.key, (self.parse)(self.key, value)?);
        Ok(())
    }
}

/// The densest packing fraction of discs a box may be asked to hold.
pub const MAX_PACKING: f64 = 0.9;

/// Hard ceiling on grains per sample, to refuse absurd requests early.
pub const MAX_GRAINS: usize = 1_000_000;

/// Widest box of the pile protocols, in diameters of its largest grain:
/// its surface and placement grids are one cell a grain across it.
pub const MAX_EXTENT: f64 = 100_000.0;

/// Shortest time step as a fraction of the stiffest contact's duration: a
/// finer step buys no accuracy (the integrators converge well above it)
/// and would make a run's steps unbounded.
pub const MIN_DT_FACTOR: f64 = 1e-4;

/// The largest time step accepted, as a fraction of the contact time. At
/// half a contact time no integrator resolves a collision; steps between
/// this and a few hundredths still run, and the engine's guards fail them
/// if they go unstable (which they do for falling grains above ~t_c/10).
pub const MAX_DT_FACTOR: f64 = 0.5;

impl Scene {
    /// The size of the gravity vector, m/s² (or the scene's units).
    pub fn gravity_magnitude(&self) -> f64 {
        self.gravity.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    /// One section, as parsed when the scene was built. A scene holds
    /// every section its protocol and model declare, so the error is for a
    /// section neither does.
    pub fn section<T: Section>(&self) -> Result<&T, SceneError> {
        self.sections.get::<T>().ok_or_else(|| {
            SceneError::single(
                T::KEY,
                format!(
                    "protocol {} with model {} has no [{}] section",
                    self.protocol,
                    self.model,
                    T::KEY
                ),
            )
        })
    }

    /// Replaces one section.
    pub fn set_section<T: Section>(&mut self, section: T) {
        self.sections.0.insert(T::KEY, Arc::new(section));
    }

    /// Checks the core: gravity, numerics and the listed grains and walls.
    pub(crate) fn check_core(&self, c: &mut Checks) {
        let d = self.dimension;
        if self.gravity.len() != d {
            c.fail(
                "gravity",
                format!("needs {d} components in {d}D, found {}", self.gravity.len()),
            );
        }
        for (k, v) in self.gravity.iter().enumerate() {
            c.finite(&format!("gravity[{k}]"), *v);
        }
        let n = &self.numerics;
        c.positive("numerics.dt_factor", n.dt_factor);
        if n.dt_factor.is_finite() && n.dt_factor > MAX_DT_FACTOR {
            c.fail(
                "numerics.dt_factor",
                format!(
                    "{} is above the stability limit of {MAX_DT_FACTOR}: a step must be \
                     well under the contact time (0.02 by default)",
                    n.dt_factor
                ),
            );
        }
        c.positive("numerics.reference_speed", n.reference_speed);
        if let Some(dt) = n.dt {
            c.positive("numerics.dt", dt);
        }
        if let Some(kick) = n.attraction_kick {
            c.positive("numerics.attraction_kick", kick);
        }
        c.positive("numerics.skin", n.skin);
        c.positive("numerics.max_overlap", n.max_overlap);
        if n.threads == 0 || n.threads > MAX_THREADS {
            c.fail(
                "numerics.threads",
                format!("must lie between 1 and {MAX_THREADS}"),
            );
        }
        self.check_listed(c);
    }

    /// The explicit grains and walls have the scene's dimension and finite values.
    fn check_listed(&self, c: &mut Checks) {
        let d = self.dimension;
        let vector = |c: &mut Checks, field: String, v: &[f64], optional: bool| {
            if optional && v.is_empty() {
                return;
            }
            if v.len() != d {
                c.fail(&field, format!("needs {d} components, found {}", v.len()));
            }
            for (k, x) in v.iter().enumerate() {
                c.finite(&format!("{field}[{k}]"), *x);
            }
        };
        for (i, p) in self.particles.iter().enumerate() {
            c.positive(&format!("particles[{i}].radius"), p.radius);
            if p.id as usize >= MAX_GRAINS {
                c.fail(
                    &format!("particles[{i}].id"),
                    format!("must be below the grain limit of {MAX_GRAINS}"),
                );
            }
            vector(c, format!("particles[{i}].position"), &p.position, false);
            vector(c, format!("particles[{i}].velocity"), &p.velocity, true);
            vector(c, format!("particles[{i}].load"), &p.load, true);
            let spin = if d == 2 { 1 } else { 3 };
            if !p.angular_velocity.is_empty() && p.angular_velocity.len() != spin {
                c.fail(
                    &format!("particles[{i}].angular_velocity"),
                    format!("needs {spin} component(s) in {d}D"),
                );
            }
            for (k, x) in p.angular_velocity.iter().enumerate() {
                c.finite(&format!("particles[{i}].angular_velocity[{k}]"), *x);
            }
        }
        for (i, wall) in self.walls.iter().enumerate() {
            vector(c, format!("walls[{i}].point"), &wall.point, false);
            vector(c, format!("walls[{i}].normal"), &wall.normal, false);
            if wall.normal.iter().all(|x| *x == 0.0) {
                c.fail(&format!("walls[{i}].normal"), "must not be the zero vector");
            }
            if !wall.normal.iter().map(|x| x * x).sum::<f64>().is_finite() {
                c.fail(
                    &format!("walls[{i}].normal"),
                    "its length overflows: scale it down",
                );
            }
            for (k, limit) in wall.limits.iter().enumerate() {
                if limit.axis >= d {
                    c.fail(
                        &format!("walls[{i}].limits[{k}].axis"),
                        format!("must name an axis below {d} (0 = x, 1 = y, 2 = z)"),
                    );
                }
                for (name, v) in [("min", limit.min), ("max", limit.max)] {
                    if let Some(v) = v {
                        c.finite(&format!("walls[{i}].limits[{k}].{name}"), v);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::elekes_parteli::Material;
    use crate::models::lee_herrmann::ContactSpec;

    fn pile(mu: f64) -> Scene {
        Scene::from_toml("protocol = \"fill_release\"", &[format!("contact.mu={mu}")]).unwrap()
    }

    #[test]
    fn a_section_is_held_typed_and_written_as_its_table() {
        let s = pile(0.3);
        assert_eq!(s.section::<ContactSpec>().unwrap().mu, 0.3);
        let written = serde_json::to_value(&s).unwrap();
        assert_eq!(written["contact"]["mu"], 0.3);
        assert_eq!(
            s.sections.value("contact"),
            Some(written["contact"].clone())
        );
        let keys: Vec<&str> = s.sections.keys().collect();
        assert_eq!(
            keys,
            ["box", "contact", "equilibrium", "grains", "wall_contact"]
        );
        assert_eq!(Scene::from_json(written).unwrap(), s);
    }

    #[test]
    fn replacing_a_section_leaves_the_clones_of_a_scene_alone() {
        let s = pile(0.3);
        let mut t = s.clone();
        assert_eq!(t, s);
        let contact = ContactSpec {
            mu: 0.1,
            ..t.section::<ContactSpec>().unwrap().clone()
        };
        t.set_section(contact);
        assert_eq!(t.section::<ContactSpec>().unwrap().mu, 0.1);
        assert_eq!(s.section::<ContactSpec>().unwrap().mu, 0.3);
        assert_ne!(t, s);
        assert_eq!(t, pile(0.1));
    }

    #[test]
    fn a_section_the_scene_does_not_declare_is_an_error_that_names_it() {
        let e = pile(0.3).section::<Material>().unwrap_err();
        assert_eq!(e.errors[0].field, "material");
        assert!(e.errors[0].message.contains("fill_release"), "{e}");
    }
}

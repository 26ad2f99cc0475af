//! The scene document: one declarative description of a sample.
//!
//! A scene is written as TOML (or the same structure as JSON). Every field
//! has a default taken from Lee & Herrmann (1993) or, where the paper is
//! silent, from the project's design notes, so the smallest scene is
//! `protocol = "fill_release"`. Unknown keys are refused, and
//! [`Scene::validate`] names every field it rejects, so the command line,
//! the service and the workers share one validation path.
//!
//! [`Scene::resolved`] fills in every value that is derived from others
//! (the wall friction, the number of grains, the time step); results store
//! the resolved scene, so a sample can be rerun from its record alone.

use crate::contact::{NormalForce, ShearSpringMode};
use crate::integrate::Scheme;
use crate::particles::Grain;
use crate::preset::Preset;
use crate::walls::Wall;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Which experiment a scene runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Protocol {
    /// Fill a box, remove its right wall, measure the angle of repose θ_R.
    FillRelease,
    /// Fill and release, then tilt the pile until it moves: the tilting angle θ_T.
    Tilt,
    /// Add grains one at a time to an open pile: the angle of marginal stability θ_MS.
    Flux,
    /// Integrate the listed grains and walls for a fixed duration.
    FreeRun,
}

impl Protocol {
    pub fn name(self) -> &'static str {
        match self {
            Protocol::FillRelease => "fill_release",
            Protocol::Tilt => "tilt",
            Protocol::Flux => "flux",
            Protocol::FreeRun => "free_run",
        }
    }
}

/// The pseudo-random generator behind placement and radii.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RngKind {
    /// ChaCha with 8 rounds (`rand_chacha::ChaCha8Rng`), seeded by `seed_from_u64`.
    #[default]
    Chacha8,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub protocol: Protocol,
    /// Named fidelity preset; it fills the numerical settings the scene
    /// leaves unset (see [`crate::preset`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<Preset>,
    /// Seed of the random generator (placement and radii).
    #[serde(default)]
    pub seed: u64,
    #[serde(default)]
    pub rng: RngKind,
    #[serde(default)]
    pub grains: GrainSpec,
    #[serde(default)]
    pub contact: ContactSpec,
    #[serde(default)]
    pub wall_contact: WallContactSpec,
    #[serde(default, rename = "box")]
    pub container: BoxSpec,
    /// Gravity vector, cm/s².
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 2],
    #[serde(default)]
    pub numerics: Numerics,
    #[serde(default)]
    pub equilibrium: Equilibrium,
    #[serde(default)]
    pub tilt: TiltSpec,
    #[serde(default)]
    pub flux: FluxSpec,
    /// Explicit grains. For `free_run` they are the whole system; for the
    /// other protocols they replace the random filling of the box.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub particles: Vec<Grain<2>>,
    /// Explicit walls for `free_run` (none if empty). The other protocols
    /// build their box from `[box]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<Wall<2>>,
    /// Simulated time of a `free_run`, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
}

fn default_gravity() -> [f64; 2] {
    [0.0, -981.0]
}

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

impl BoxSpec {
    /// The height to fill: `aspect · width` when an aspect ratio is set.
    pub fn fill_height(&self) -> f64 {
        self.aspect.map_or(self.height, |a| a * self.width)
    }
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

/// Time stepping and neighbour search: the speed/accuracy knobs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Numerics {
    pub integrator: Scheme,
    /// Time step as a fraction of the contact time of the stiffest pair.
    pub dt_factor: f64,
    /// Impact speed at which that contact time is taken, cm/s.
    pub reference_speed: f64,
    /// Explicit time step, s; overrides `dt_factor`.
    pub dt: Option<f64>,
    /// Verlet-list skin, cm.
    pub skin: f64,
    /// Largest overlap allowed, as a fraction of the smaller radius, before a run is failed.
    pub max_overlap: f64,
}

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            integrator: Scheme::Gear5,
            dt_factor: 0.02,
            reference_speed: 1.0,
            dt: None,
            skin: 0.04,
            max_overlap: 0.5,
        }
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

/// The tilt protocol: gravity turns at a constant rate until the pile moves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TiltSpec {
    /// Rotation rate of the box, degrees per simulated second (clockwise).
    pub rate: f64,
    /// A grain counts as moved once it is this many mean diameters from
    /// where it was when tilting began.
    pub onset_displacement: f64,
    /// The pile "starts to move" once this fraction of grains has moved.
    pub onset_fraction: f64,
    /// Give up (outcome `no_onset`) past this tilt, degrees.
    pub max_angle: f64,
}

impl Default for TiltSpec {
    fn default() -> Self {
        TiltSpec {
            rate: 10.0,
            onset_displacement: 0.5,
            onset_fraction: 0.02,
            max_angle: 45.0,
        }
    }
}

/// The constant-flux protocol of section 5.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FluxSpec {
    /// A new grain is added once the fastest grain is slower than this, cm/s.
    pub v_cut: f64,
    /// How many grains to add.
    pub insertions: usize,
    /// Cap on the simulated time spent waiting after one insertion, s.
    pub max_wait: f64,
    /// Leading fraction of the series left out of the steady-state statistics.
    pub discard_fraction: f64,
}

impl Default for FluxSpec {
    fn default() -> Self {
        FluxSpec {
            v_cut: 0.1,
            insertions: 300,
            max_wait: 2.0,
            discard_fraction: 0.5,
        }
    }
}

/// One rejected field and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FieldError {
    /// Dotted path of the field, e.g. `contact.mu`.
    pub field: String,
    pub message: String,
}

impl fmt::Display for FieldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// Every problem found in a scene document.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
pub struct SceneError {
    pub errors: Vec<FieldError>,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lines: Vec<String> = self.errors.iter().map(|e| e.to_string()).collect();
        write!(f, "invalid scene: {}", lines.join("; "))
    }
}

impl SceneError {
    pub fn single(field: impl Into<String>, message: impl Into<String>) -> Self {
        SceneError {
            errors: vec![FieldError {
                field: field.into(),
                message: message.into(),
            }],
        }
    }
}

/// Collects field errors during validation.
#[derive(Default)]
struct Checks(Vec<FieldError>);

impl Checks {
    fn fail(&mut self, field: &str, message: impl Into<String>) {
        self.0.push(FieldError {
            field: field.to_string(),
            message: message.into(),
        });
    }

    fn finite(&mut self, field: &str, v: f64) -> bool {
        if !v.is_finite() {
            self.fail(field, format!("must be a finite number, got {v}"));
            return false;
        }
        true
    }

    fn positive(&mut self, field: &str, v: f64) {
        if self.finite(field, v) && v <= 0.0 {
            self.fail(field, format!("must be greater than 0, got {v}"));
        }
    }

    fn non_negative(&mut self, field: &str, v: f64) {
        if self.finite(field, v) && v < 0.0 {
            self.fail(field, format!("must be 0 or more, got {v}"));
        }
    }

    fn fraction(&mut self, field: &str, v: f64, open_top: bool) {
        if self.finite(field, v) && (v <= 0.0 || v > 1.0 || (open_top && v == 1.0)) {
            let range = if open_top { "(0, 1)" } else { "(0, 1]" };
            self.fail(field, format!("must lie in {range}, got {v}"));
        }
    }
}

/// The densest packing fraction of discs a box may be asked to hold.
const MAX_PACKING: f64 = 0.9;

/// Hard ceiling on grains per sample, to refuse absurd requests early.
pub const MAX_GRAINS: usize = 1_000_000;

/// The largest time step accepted, as a fraction of the contact time. At
/// half a contact time no integrator resolves a collision; steps between
/// this and a few hundredths still run, and the engine's guards fail them
/// if they go unstable (which they do for falling grains above ~t_c/10).
pub const MAX_DT_FACTOR: f64 = 0.5;

impl Scene {
    /// Parses a TOML document — or a JSON one (text starting with `{`, as
    /// results store their scenes) — applies `key=value` overrides (dotted
    /// keys, TOML values; a bare word is taken as a string) and validates.
    pub fn from_toml(text: &str, overrides: &[String]) -> Result<Scene, SceneError> {
        let mut doc: toml::Table = if text.trim_start().starts_with('{') {
            let json: serde_json::Value = serde_json::from_str(text)
                .map_err(|e| SceneError::single("(document)", format!("not valid JSON: {e}")))?;
            toml::Table::try_from(drop_nulls(json))
                .map_err(|e| SceneError::single("(document)", e.to_string()))?
        } else {
            text.parse()
                .map_err(|e: toml::de::Error| SceneError::single("(document)", e.to_string()))?
        };
        for o in overrides {
            apply_override(&mut doc, o)?;
        }
        let json = serde_json::to_value(&doc)
            .map_err(|e| SceneError::single("(document)", e.to_string()))?;
        Scene::from_json(json)
    }

    /// Reads the same structure from JSON, fills in the named preset's
    /// settings and validates.
    pub fn from_json(mut value: serde_json::Value) -> Result<Scene, SceneError> {
        if let Some(doc) = value.as_object_mut() {
            if let Some(name) = doc.get("preset").filter(|v| !v.is_null()) {
                let preset: Preset = name
                    .as_str()
                    .ok_or_else(|| "a preset is named by a string".to_string())
                    .and_then(str::parse)
                    .map_err(|m| SceneError::single("preset", m))?;
                preset.fill(doc);
            }
        }
        let scene: Scene = serde_path_to_error::deserialize(value)
            .map_err(|e| path_error(e.path().to_string(), e.inner().to_string()))?;
        scene.validate()?;
        Ok(scene)
    }

    /// The smallest radius any grain of this scene can have.
    pub fn smallest_radius(&self) -> f64 {
        if self.protocol == Protocol::FreeRun || !self.particles.is_empty() {
            let listed = self
                .particles
                .iter()
                .map(|g| g.radius)
                .fold(f64::INFINITY, f64::min);
            if self.protocol == Protocol::FreeRun {
                return listed;
            }
            return listed.min(self.grains.radius_min);
        }
        if self.grains.radius_sd == 0.0 {
            self.grains.radius_mean
        } else {
            self.grains.radius_min
        }
    }

    /// Number of grains the box protocols start with.
    pub fn grain_count(&self) -> usize {
        if !self.particles.is_empty() {
            return self.particles.len();
        }
        self.container.grains.unwrap_or_else(|| {
            (self.container.grains_per_area * self.container.width * self.container.fill_height())
                .round() as usize
        })
    }

    /// Mean disc area of the radius distribution (cm²), used for capacity checks.
    fn mean_disc_area(&self) -> f64 {
        let g = &self.grains;
        std::f64::consts::PI * (g.radius_mean * g.radius_mean + g.radius_sd * g.radius_sd)
    }

    /// The time step this scene runs with: the explicit one, or
    /// `dt_factor` times the contact time of the stiffest pair.
    pub fn time_step(&self) -> f64 {
        if let Some(dt) = self.numerics.dt {
            return dt;
        }
        self.numerics.dt_factor * self.contact_time()
    }

    /// Shortest contact duration among grain–grain and grain–wall contacts
    /// at the reference speed (Hertz, undamped), or the half period of the
    /// shear spring if that is shorter, s.
    pub fn contact_time(&self) -> f64 {
        let a = self.smallest_radius();
        let m = 4.0 / 3.0 * std::f64::consts::PI * self.grains.density * a * a * a;
        let v = self.numerics.reference_speed;
        let pair = crate::theory::hertz_contact_time(self.contact.k_n, 0.5 * m, v);
        let wall = crate::theory::hertz_contact_time(self.wall_contact.k_n, m, v);
        let mut t = pair.min(wall);
        if self.contact.k_s > 0.0 {
            t = t.min(std::f64::consts::PI * (0.5 * m / self.contact.k_s).sqrt());
        }
        if let Some(k_s) = self.wall_contact.k_s.or(Some(self.contact.k_s)) {
            if k_s > 0.0 {
                t = t.min(std::f64::consts::PI * (m / k_s).sqrt());
            }
        }
        t
    }

    /// The scene with every derived value written out.
    pub fn resolved(&self) -> Scene {
        let mut s = self.clone();
        s.contact.gamma_s = Some(self.contact.gamma_s());
        let w = &mut s.wall_contact;
        w.gamma_n = Some(w.gamma_n.unwrap_or(self.contact.gamma_n));
        w.k_s = Some(w.k_s.unwrap_or(self.contact.k_s));
        w.gamma_s = Some(w.gamma_s.unwrap_or(self.contact.gamma_s()));
        w.mu = Some(w.mu.unwrap_or(self.contact.mu));
        if self.protocol != Protocol::FreeRun && self.particles.is_empty() {
            s.container.grains = Some(self.grain_count());
        }
        s.container.height = self.container.fill_height();
        s.numerics.dt = Some(self.time_step());
        s
    }

    /// Checks every field; returns all problems at once.
    pub fn validate(&self) -> Result<(), SceneError> {
        let mut c = Checks::default();

        let g = &self.grains;
        c.positive("grains.density", g.density);
        c.positive("grains.radius_mean", g.radius_mean);
        c.non_negative("grains.radius_sd", g.radius_sd);
        c.positive("grains.radius_min", g.radius_min);
        c.positive("grains.radius_max", g.radius_max);
        if g.radius_min.is_finite() && g.radius_max.is_finite() && g.radius_mean.is_finite() {
            if g.radius_min > g.radius_max {
                c.fail(
                    "grains.radius_min",
                    format!("must not exceed grains.radius_max ({})", g.radius_max),
                );
            } else if g.radius_sd > 0.0
                && (g.radius_mean < g.radius_min || g.radius_mean > g.radius_max)
            {
                c.fail(
                    "grains.radius_mean",
                    format!(
                        "must lie within [radius_min, radius_max] = [{}, {}]",
                        g.radius_min, g.radius_max
                    ),
                );
            } else if g.radius_sd > 0.0 && g.radius_max - g.radius_min < 0.01 * g.radius_sd {
                // Draws outside the window are repeated; a window this narrow
                // would almost never be hit.
                c.fail(
                    "grains.radius_sd",
                    "the window [radius_min, radius_max] is too narrow for this spread; set radius_sd = 0 for equal grains",
                );
            }
        }

        let k = &self.contact;
        c.positive("contact.k_n", k.k_n);
        c.non_negative("contact.gamma_n", k.gamma_n);
        c.non_negative("contact.k_s", k.k_s);
        if let Some(gs) = k.gamma_s {
            c.non_negative("contact.gamma_s", gs);
        }
        c.non_negative("contact.mu", k.mu);

        let w = &self.wall_contact;
        c.positive("wall_contact.k_n", w.k_n);
        for (name, v) in [
            ("wall_contact.gamma_n", w.gamma_n),
            ("wall_contact.k_s", w.k_s),
            ("wall_contact.gamma_s", w.gamma_s),
            ("wall_contact.mu", w.mu),
        ] {
            if let Some(v) = v {
                c.non_negative(name, v);
            }
        }

        for (d, v) in self.gravity.iter().enumerate() {
            c.finite(&format!("gravity[{d}]"), *v);
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
        c.positive("numerics.skin", n.skin);
        c.positive("numerics.max_overlap", n.max_overlap);

        let e = &self.equilibrium;
        c.positive("equilibrium.max_speed", e.max_speed);
        c.positive("equilibrium.kinetic_energy", e.kinetic_energy);
        c.positive("equilibrium.max_displacement", e.max_displacement);
        c.non_negative("equilibrium.hold", e.hold);
        c.positive("equilibrium.check_interval", e.check_interval);
        c.positive("equilibrium.max_fill_time", e.max_fill_time);
        c.positive("equilibrium.max_flow_time", e.max_flow_time);

        if self.protocol == Protocol::Tilt {
            let t = &self.tilt;
            c.positive("tilt.rate", t.rate);
            c.positive("tilt.onset_displacement", t.onset_displacement);
            c.fraction("tilt.onset_fraction", t.onset_fraction, false);
            c.positive("tilt.max_angle", t.max_angle);
            if t.max_angle.is_finite() && t.max_angle >= 90.0 {
                c.fail("tilt.max_angle", "must be below 90 degrees");
            }
        }
        if self.protocol == Protocol::Flux {
            let f = &self.flux;
            c.positive("flux.v_cut", f.v_cut);
            if f.insertions == 0 {
                c.fail("flux.insertions", "must be at least 1");
            }
            if f.insertions > MAX_GRAINS {
                c.fail("flux.insertions", format!("must be at most {MAX_GRAINS}"));
            }
            c.positive("flux.max_wait", f.max_wait);
            if c.finite("flux.discard_fraction", f.discard_fraction)
                && !(0.0..1.0).contains(&f.discard_fraction)
            {
                c.fail("flux.discard_fraction", "must lie in [0, 1)");
            }
        }

        for (i, p) in self.particles.iter().enumerate() {
            c.positive(&format!("particles[{i}].radius"), p.radius);
            for d in 0..2 {
                c.finite(&format!("particles[{i}].position[{d}]"), p.position[d]);
                c.finite(&format!("particles[{i}].velocity[{d}]"), p.velocity[d]);
            }
        }
        for (i, wall) in self.walls.iter().enumerate() {
            for d in 0..2 {
                c.finite(&format!("walls[{i}].point[{d}]"), wall.point[d]);
                c.finite(&format!("walls[{i}].normal[{d}]"), wall.normal[d]);
            }
            if wall.normal.norm() == 0.0 {
                c.fail(&format!("walls[{i}].normal"), "must not be the zero vector");
            }
            for (k, limit) in wall.limits.iter().enumerate() {
                if limit.axis >= 2 {
                    c.fail(
                        &format!("walls[{i}].limits[{k}].axis"),
                        "must be 0 (x) or 1 (y)",
                    );
                }
                for (name, v) in [("min", limit.min), ("max", limit.max)] {
                    if let Some(v) = v {
                        c.finite(&format!("walls[{i}].limits[{k}].{name}"), v);
                    }
                }
            }
        }

        match self.protocol {
            Protocol::FreeRun => {
                if self.particles.is_empty() {
                    c.fail("particles", "a free_run needs at least one listed grain");
                }
                match self.duration {
                    None => c.fail("duration", "a free_run needs a duration (s)"),
                    Some(d) => c.positive("duration", d),
                }
            }
            _ => {
                if self.duration.is_some() {
                    c.fail("duration", "only a free_run takes a fixed duration");
                }
                if !self.walls.is_empty() {
                    c.fail(
                        "walls",
                        "only a free_run takes explicit walls; the box is built from [box]",
                    );
                }
                self.check_box(&mut c);
            }
        }

        if c.0.is_empty() && !(self.time_step().is_finite() && self.time_step() > 0.0) {
            c.fail(
                "numerics.dt",
                "the derived time step is not a positive finite number",
            );
        }
        if let (true, Some(dt)) = (c.0.is_empty(), n.dt) {
            let t_c = self.contact_time();
            if dt > MAX_DT_FACTOR * t_c {
                c.fail(
                    "numerics.dt",
                    format!(
                        "{dt:.3e} s is above the stability limit: the stiffest contact lasts \
                         t_c = {t_c:.3e} s at the reference speed, so a step may be at most \
                         {:.3e} s (t_c/50 = {:.3e} s by default)",
                        MAX_DT_FACTOR * t_c,
                        t_c / 50.0
                    ),
                );
            }
        }

        if c.0.is_empty() {
            Ok(())
        } else {
            Err(SceneError { errors: c.0 })
        }
    }

    fn check_box(&self, c: &mut Checks) {
        let b = &self.container;
        c.positive("box.width", b.width);
        c.positive("box.height", b.height);
        if let Some(a) = b.aspect {
            c.positive("box.aspect", a);
        }
        c.positive("box.grains_per_area", b.grains_per_area);
        c.fraction("box.placement_fraction", b.placement_fraction, true);
        if !c.0.is_empty() {
            return;
        }
        let largest = 2.0 * self.grains.radius_max.max(self.grains.radius_mean);
        if b.width < largest {
            c.fail(
                "box.width",
                format!(
                    "{} cm is narrower than the largest grain ({largest} cm)",
                    b.width
                ),
            );
            return;
        }
        let n = self.grain_count();
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
        if self.protocol != Protocol::Flux {
            let need = n as f64 * self.mean_disc_area();
            let room = MAX_PACKING * b.width * b.fill_height();
            if need > room {
                c.fail(
                    "box.grains",
                    format!(
                        "{n} grains cover {need:.3} cm², more than a {} × {} box holds at a packing fraction of {MAX_PACKING} ({room:.3} cm²)",
                        b.width,
                        b.fill_height()
                    ),
                );
            }
        }
    }
}

/// JSON `null` means "not set"; TOML has no null, so such keys are dropped.
fn drop_nulls(v: serde_json::Value) -> serde_json::Value {
    match v {
        serde_json::Value::Object(m) => serde_json::Value::Object(
            m.into_iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| (k, drop_nulls(v)))
                .collect(),
        ),
        serde_json::Value::Array(a) => {
            serde_json::Value::Array(a.into_iter().map(drop_nulls).collect())
        }
        other => other,
    }
}

fn path_error(path: String, message: String) -> SceneError {
    let field = if path.is_empty() || path == "." {
        "(document)".to_string()
    } else {
        path
    };
    SceneError::single(field, message)
}

/// Sets `a.b.c = value` in a TOML table. The value is read as a TOML value
/// (`0.3`, `true`, `"gear5"`, `[0, -981]`), or taken as a plain string.
fn apply_override(doc: &mut toml::Table, assignment: &str) -> Result<(), SceneError> {
    let Some((key, raw)) = assignment.split_once('=') else {
        return Err(SceneError::single(
            assignment,
            "an override is written key=value, e.g. contact.mu=0.3",
        ));
    };
    let key = key.trim();
    let raw = raw.trim();
    let value: toml::Value = match format!("v = {raw}").parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    };
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(SceneError::single(key, "empty segment in the key"));
    }
    let mut table = doc;
    for part in &parts[..parts.len() - 1] {
        let entry = table
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        table = match entry {
            toml::Value::Table(t) => t,
            _ => return Err(SceneError::single(key, format!("`{part}` is not a table"))),
        };
    }
    table.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(err: SceneError) -> Vec<String> {
        err.errors.into_iter().map(|e| e.field).collect()
    }

    #[test]
    fn smallest_scene_takes_the_papers_defaults() {
        let s = Scene::from_toml("protocol = \"fill_release\"", &[]).unwrap();
        assert_eq!(s.contact.k_n, 1e6);
        assert_eq!(s.contact.gamma_s(), 5.0);
        assert_eq!(s.wall_contact.k_n, 2e6);
        assert_eq!(s.grain_count(), 400);
        let r = s.resolved();
        assert_eq!(r.wall_contact.mu, Some(0.2));
        // Hertz contact of two smallest grains (or grain and wall) at 1 cm/s is ~7e-4 s
        let dt = r.numerics.dt.unwrap();
        assert!(dt > 1.0e-5 && dt < 2.0e-5, "dt = {dt}");
    }

    #[test]
    fn overrides_set_nested_values() {
        let s = Scene::from_toml(
            "protocol = \"tilt\"",
            &[
                "contact.mu=0.3".into(),
                "numerics.integrator=verlet".into(),
                "box.width=2".into(),
            ],
        )
        .unwrap();
        assert_eq!(s.contact.mu, 0.3);
        assert_eq!(s.numerics.integrator, Scheme::Verlet);
        assert_eq!(s.container.width, 2.0);
    }

    #[test]
    fn bad_values_are_refused_with_the_field_named() {
        let cases: &[(&str, &str)] = &[
            ("contact.mu=-0.1", "contact.mu"),
            ("grains.radius_mean=0", "grains.radius_mean"),
            ("grains.radius_min=-0.01", "grains.radius_min"),
            ("box.width=0.1", "box.width"),
            ("box.grains=100000", "box.grains"),
            ("contact.k_n=nan", "contact.k_n"),
            ("numerics.dt_factor=0", "numerics.dt_factor"),
            ("numerics.dt_factor=-1", "numerics.dt_factor"),
            ("grains.radius_sd=10", "grains.radius_sd"),
        ];
        for (o, field) in cases {
            let err =
                Scene::from_toml("protocol = \"fill_release\"", &[o.to_string()]).unwrap_err();
            assert!(
                fields(err.clone()).contains(&field.to_string()),
                "{o}: {err}"
            );
        }
    }

    #[test]
    fn unknown_keys_and_wrong_types_name_the_field() {
        let err =
            Scene::from_toml("protocol = \"fill_release\"\n[contact]\nmuu = 0.2", &[]).unwrap_err();
        assert_eq!(err.errors[0].field, "contact.muu");
        assert!(err.errors[0].message.contains("unknown field"), "{err}");
        let err = Scene::from_toml("protocol = \"fill_release\"\n[contact]\nmu = \"high\"", &[])
            .unwrap_err();
        assert_eq!(err.errors[0].field, "contact.mu");
        let err = Scene::from_toml("protocol = \"sideways\"", &[]).unwrap_err();
        assert_eq!(err.errors[0].field, "protocol");
    }

    #[test]
    fn a_resolved_scene_stored_as_json_reads_back_the_same() {
        let s = Scene::from_toml("protocol = \"tilt\"\nseed = 7", &[])
            .unwrap()
            .resolved();
        let text = serde_json::to_string_pretty(&s).unwrap();
        let back = Scene::from_toml(&text, &[]).unwrap();
        assert_eq!(back, s);
        let changed = Scene::from_toml(&text, &["contact.mu=0.3".into()]).unwrap();
        assert_eq!(changed.contact.mu, 0.3);
    }

    #[test]
    fn free_run_needs_grains_and_a_duration() {
        let err = Scene::from_toml("protocol = \"free_run\"", &[]).unwrap_err();
        let f = fields(err);
        assert!(f.contains(&"particles".to_string()) && f.contains(&"duration".to_string()));
    }
}

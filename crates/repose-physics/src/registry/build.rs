//! Building a scene from a document: the protocol, dimension and model it
//! names, the preset's settings and the model's defaults where it is
//! silent, the core and every declared section, and one validation that
//! names every field it rejects. Needs every protocol and model, so it
//! lives with the registry.

use super::{find_model, find_protocol, model_names, protocol_names, protocols};
use crate::doc::{self, Doc};
use crate::models::Model;
use crate::preset::Preset;
use crate::protocols::Protocol;
use crate::scene::checks::path_error;
use crate::scene::{
    Checks, Core, Scene, SceneError, SectionDecl, Sections, CORE_KEYS, MAX_DT_FACTOR, MIN_DT_FACTOR,
};
use serde_json::Value;

impl Scene {
    /// Parses a TOML document — or a JSON one (text starting with `{`) —
    /// applies `key=value` overrides (dotted keys, TOML values; a bare word
    /// is taken as a string) and validates.
    pub fn from_toml(text: &str, overrides: &[String]) -> Result<Scene, SceneError> {
        let mut d = doc::parse(text)?;
        for o in overrides {
            let (key, value) = doc::parse_assignment(o)?;
            doc::set(&mut d, &key, value)?;
        }
        Scene::from_doc(d)
    }

    /// Reads a scene from JSON (a document as results store it) and validates.
    pub fn from_json(value: Value) -> Result<Scene, SceneError> {
        match doc::drop_nulls(value) {
            Value::Object(d) => Scene::from_doc(d),
            _ => Err(SceneError::single(
                "(document)",
                "a scene is a table of keys",
            )),
        }
    }

    /// Reads a scene stored by this or an earlier version of the engine.
    /// Earlier versions wrote every protocol's section into every scene;
    /// those of other protocols are dropped.
    pub fn from_stored(value: Value) -> Result<Scene, SceneError> {
        Scene::from_json(upgrade_stored(value))
    }

    /// Reads a scene from the JSON text a store keeps with each job.
    pub fn from_stored_text(text: &str) -> Result<Scene, SceneError> {
        let value = serde_json::from_str(text)
            .map_err(|e| SceneError::single("(document)", format!("not JSON: {e}")))?;
        Scene::from_stored(value)
    }

    /// Builds a scene from a document: protocol, model and dimension first,
    /// then the preset's settings and the model's defaults where the
    /// document is silent, then the core and each section; validates.
    pub fn from_doc(mut d: Doc) -> Result<Scene, SceneError> {
        let protocol = protocol_of(&d)?;
        let dimension = dimension_of(&d, protocol)?;
        let model = model_of(&d, protocol, dimension)?;
        if let Some(name) = d.get("preset") {
            let preset: Preset = name
                .as_str()
                .ok_or_else(|| "a preset is named by a string".to_string())
                .and_then(str::parse)
                .map_err(|m| SceneError::single("preset", m))?;
            for (key, value) in protocol.preset(preset) {
                if !doc::has(&d, key) {
                    doc::set(&mut d, key, value)?;
                }
            }
        }
        let defaults = model.defaults(dimension, &d);
        doc::merge_defaults(&mut d, &defaults);
        let mut core_doc = Doc::new();
        for key in CORE_KEYS {
            if let Some(v) = d.remove(key) {
                core_doc.insert(key.to_string(), v);
            }
        }
        let core: Core = serde_path_to_error::deserialize(Value::Object(core_doc))
            .map_err(|e| path_error(e.path().to_string(), e.inner().to_string()))?;
        let sections = sections_of(d, protocol, model)?;
        let scene = Scene {
            protocol: protocol.name().to_string(),
            model: model.name().to_string(),
            dimension,
            preset: core.preset,
            seed: core.seed,
            rng: core.rng,
            gravity: core.gravity.unwrap_or_default(),
            numerics: core.numerics,
            particles: core.particles,
            walls: core.walls,
            duration: core.duration,
            sections,
        };
        scene.validate()?;
        Ok(scene)
    }

    /// The protocol this scene names.
    pub fn protocol(&self) -> Result<&'static dyn Protocol, SceneError> {
        find_protocol(&self.protocol).ok_or_else(|| unknown_protocol(&self.protocol))
    }

    /// The contact model this scene names.
    pub fn model(&self) -> Result<&'static dyn Model, SceneError> {
        find_model(&self.model).ok_or_else(|| unknown_model(&self.model))
    }

    /// Checks every field; returns all problems at once.
    pub fn validate(&self) -> Result<(), SceneError> {
        let protocol = self.protocol()?;
        let model = self.model()?;
        let mut c = Checks::default();
        self.check_core(&mut c);
        for decl in model.sections().iter().chain(&protocol.sections()) {
            (decl.check)(self, &mut c);
        }
        model.check(self, &mut c);
        protocol.check(self, &mut c);
        if c.is_empty() {
            self.check_time_step(&mut c);
        }
        c.into_result()
    }

    fn check_time_step(&self, c: &mut Checks) {
        let step = self.time_step();
        if !(step.is_finite() && step > 0.0) {
            c.fail(
                "numerics.dt",
                "the derived time step is not a positive finite number",
            );
            return;
        }
        let t_c = self.contact_time();
        if step < MIN_DT_FACTOR * t_c {
            let field = if self.numerics.dt.is_some() {
                "numerics.dt"
            } else if self.numerics.dt_factor < MIN_DT_FACTOR {
                "numerics.dt_factor"
            } else {
                "numerics.attraction_kick"
            };
            c.fail(
                field,
                format!(
                    "the step of {step:.3e} s is below {MIN_DT_FACTOR} of the stiffest contact's \
                     duration t_c = {t_c:.3e} s: no finer step is needed, and its runs would not end"
                ),
            );
        }
        if let Some(dt) = self.numerics.dt {
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
    }

    /// The time step this scene runs with: the explicit one, or
    /// `dt_factor` times the contact time of the stiffest pair, shortened
    /// where the contact attraction would kick a pair by more than
    /// `attraction_kick` in one step.
    pub fn time_step(&self) -> f64 {
        if let Some(dt) = self.numerics.dt {
            return dt;
        }
        let step = self.numerics.dt_factor * self.contact_time();
        let kick = self.numerics.attraction_kick.filter(|k| *k > 0.0);
        let bound = kick.and_then(|kick| Some(kick * self.model().ok()?.attraction_time(self)?));
        bound.map_or(step, |bound| bound.min(step))
    }

    /// The speed at which the contact time is taken: the reference speed,
    /// or the fastest impact the protocol makes happen if that is higher.
    pub fn impact_speed(&self) -> f64 {
        let v = self.numerics.reference_speed;
        match self.protocol().ok().and_then(|p| p.impact_speed(self)) {
            Some(fast) if fast > v => fast,
            _ => v,
        }
    }

    /// Shortest contact duration of this scene's grains at the impact
    /// speed, as the model defines it.
    pub fn contact_time(&self) -> f64 {
        match self.model() {
            Ok(m) => m.contact_time(self),
            Err(_) => f64::NAN,
        }
    }

    /// The scene with every derived value written out.
    pub fn resolved(&self) -> Scene {
        let mut s = self.clone();
        if let Ok(m) = self.model() {
            m.resolve(&mut s);
        }
        if let Ok(p) = self.protocol() {
            p.resolve(&mut s);
        }
        s.numerics.dt = Some(self.time_step());
        s
    }
}

/// The registered protocol a document names.
fn protocol_of(d: &Doc) -> Result<&'static dyn Protocol, SceneError> {
    match d.get("protocol") {
        None => Err(SceneError::single(
            "protocol",
            format!("missing: name one of {}", protocol_names().join(", ")),
        )),
        Some(Value::String(name)) => find_protocol(name).ok_or_else(|| unknown_protocol(name)),
        Some(other) => Err(SceneError::single(
            "protocol",
            format!("is {}, not the name of a protocol", doc::kind(other)),
        )),
    }
}

fn unknown_protocol(name: &str) -> SceneError {
    SceneError::single(
        "protocol",
        format!(
            "unknown protocol `{name}`: expected one of {}",
            protocol_names().join(", ")
        ),
    )
}

fn unknown_model(name: &str) -> SceneError {
    SceneError::single(
        "model",
        format!(
            "unknown model `{name}`: expected one of {}",
            model_names().join(", ")
        ),
    )
}

/// The dimension a document asks for, or its protocol's first.
fn dimension_of(d: &Doc, protocol: &dyn Protocol) -> Result<usize, SceneError> {
    let allowed = protocol.dimensions();
    let Some(v) = d.get("dimension") else {
        return Ok(allowed[0]);
    };
    let dim = v.as_u64().map(|x| x as usize);
    match dim {
        Some(x) if allowed.contains(&x) => Ok(x),
        _ => Err(SceneError::single(
            "dimension",
            format!(
                "protocol {} runs in {} dimensions, not {v}",
                protocol.name(),
                allowed
                    .iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(" or ")
            ),
        )),
    }
}

/// The model a document asks for, or its protocol's default for the dimension.
fn model_of(
    d: &Doc,
    protocol: &dyn Protocol,
    dimension: usize,
) -> Result<&'static dyn Model, SceneError> {
    let name = match d.get("model") {
        None => protocol.default_model(dimension),
        Some(Value::String(s)) => s.as_str(),
        Some(other) => {
            return Err(SceneError::single(
                "model",
                format!("is {}, not the name of a model", doc::kind(other)),
            ))
        }
    };
    let model = find_model(name).ok_or_else(|| unknown_model(name))?;
    if !protocol.models().contains(&model.name()) {
        return Err(SceneError::single(
            "model",
            format!(
                "protocol {} runs with {}, not {name}",
                protocol.name(),
                protocol.models().join(" or ")
            ),
        ));
    }
    if !model.dimensions().contains(&dimension) {
        return Err(SceneError::single(
            "model",
            format!("model {name} has no {dimension}D form"),
        ));
    }
    Ok(model)
}

/// Splits the non-core keys into the sections the protocol and the model
/// declare, each normalised with its defaults; anything else is refused.
fn sections_of(
    mut rest: Doc,
    protocol: &dyn Protocol,
    model: &dyn Model,
) -> Result<Sections, SceneError> {
    let decls: Vec<SectionDecl> = model
        .sections()
        .into_iter()
        .chain(protocol.sections())
        .collect();
    let mut errors = Checks::default();
    let mut out = Sections::default();
    for decl in &decls {
        let value = rest
            .remove(decl.key)
            .unwrap_or_else(|| Value::Object(Doc::new()));
        if let Err(e) = decl.parse_into(value, &mut out) {
            errors.extend(e);
        }
    }
    for key in rest.keys() {
        let known: Vec<&str> = decls.iter().map(|d| d.key).collect();
        let owner = protocols()
            .iter()
            .find(|p| p.sections().iter().any(|s| s.key == key))
            .map(|p| format!(" (it belongs to protocol {})", p.name()))
            .unwrap_or_default();
        errors.fail(
            key,
            format!(
                "unknown field `{key}`{owner}: protocol {} with model {} takes the sections {}",
                protocol.name(),
                model.name(),
                known.join(", ")
            ),
        );
    }
    errors.into_result().map(|()| out)
}

/// Documents stored by version 0.1 carried every protocol's section in every
/// scene and no model or dimension; keep only what the protocol reads.
fn upgrade_stored(value: Value) -> Value {
    let Value::Object(mut d) = value else {
        return value;
    };
    if d.contains_key("model") {
        return Value::Object(d);
    }
    if let Some(protocol) = d
        .get("protocol")
        .and_then(Value::as_str)
        .and_then(find_protocol)
    {
        let own: Vec<&str> = protocol.sections().iter().map(|s| s.key).collect();
        d.retain(|key, _| {
            CORE_KEYS.contains(&key.as_str())
                || own.contains(&key.as_str())
                || !protocols()
                    .iter()
                    .any(|p| p.sections().iter().any(|s| s.key == key))
        });
    }
    Value::Object(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::lee_herrmann::{ContactSpec, WallContactSpec};
    use crate::protocols::pile::BoxSpec;
    use repose_engine::integrate::Scheme;

    fn fields(err: SceneError) -> Vec<String> {
        err.errors.into_iter().map(|e| e.field).collect()
    }

    #[test]
    fn smallest_scene_takes_the_papers_defaults() {
        let s = Scene::from_toml("protocol = \"fill_release\"", &[]).unwrap();
        assert_eq!((s.model.as_str(), s.dimension), ("lee_herrmann", 2));
        let contact: &ContactSpec = s.section().unwrap();
        assert_eq!(contact.k_n, 1e6);
        assert_eq!(contact.gamma_s(), 5.0);
        let r = s.resolved();
        let wall: &WallContactSpec = r.section().unwrap();
        assert_eq!((wall.k_n, wall.mu), (2e6, Some(0.2)));
        assert_eq!(r.section::<BoxSpec>().unwrap().grains, Some(400));
        assert_eq!(r.gravity, vec![0.0, -981.0]);
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
        assert_eq!(s.section::<ContactSpec>().unwrap().mu, 0.3);
        assert_eq!(s.numerics.integrator, Scheme::Verlet);
        assert_eq!(s.section::<BoxSpec>().unwrap().width, 2.0);
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
            ("gravity=[0, 0, -981]", "gravity"),
            ("dimension=3", "dimension"),
            ("model=none", "model"),
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
        let err = Scene::from_toml("protocol = \"fill_release\"\ncolour = 3", &[]).unwrap_err();
        assert_eq!(err.errors[0].field, "colour");
    }

    #[test]
    fn a_section_of_another_protocol_is_refused_naming_its_owner() {
        let err =
            Scene::from_toml("protocol = \"fill_release\"\n[tilt]\nrate = 5.0", &[]).unwrap_err();
        assert_eq!(err.errors[0].field, "tilt");
        assert!(err.errors[0].message.contains("protocol tilt"), "{err}");
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
        assert_eq!(changed.section::<ContactSpec>().unwrap().mu, 0.3);
    }

    #[test]
    fn scenes_stored_by_version_0_1_still_read() {
        // 0.1 wrote every protocol's section into every resolved scene.
        let stored = serde_json::json!({
            "protocol": "fill_release", "seed": 3, "rng": "chacha8",
            "gravity": [0.0, -981.0],
            "box": {"width": 2.0, "height": 2.0, "aspect": null, "grains": 100,
                    "grains_per_area": 25.0, "placement_fraction": 0.35},
            "tilt": {"rate": 10.0, "onset_displacement": 0.5, "onset_fraction": 0.02, "max_angle": 45.0},
            "flux": {"v_cut": 0.1, "insertions": 300, "max_wait": 2.0, "discard_fraction": 0.5},
            "contact": {"mu": 0.3}
        });
        assert!(Scene::from_json(stored.clone()).is_err());
        let s = Scene::from_stored(stored.clone()).unwrap();
        assert_eq!(s.seed, 3);
        assert_eq!(s.section::<BoxSpec>().unwrap().grains, Some(100));
        assert!(!s.sections.contains_key("tilt"));
        // As a store keeps it: the same scene from its text; text that is
        // not JSON is refused as a document.
        assert_eq!(Scene::from_stored_text(&stored.to_string()).unwrap(), s);
        let f = fields(Scene::from_stored_text("{\"protocol\": ").unwrap_err());
        assert_eq!(f, ["(document)"]);
    }

    #[test]
    fn a_free_run_takes_grains_and_walls_in_either_dimension() {
        let err = Scene::from_toml("protocol = \"free_run\"", &[]).unwrap_err();
        let f = fields(err);
        assert!(f.contains(&"particles".to_string()) && f.contains(&"duration".to_string()));
        let three = "protocol = \"free_run\"\ndimension = 3\nduration = 0.01\n\
                     [[particles]]\nposition = [0.0, 0.0, 0.2]\nradius = 0.1\n\
                     [[walls]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n";
        // In 3D a free run takes Elekes & Parteli's spheres (SI), or Lee &
        // Herrmann's law (CGS) when named.
        let s = Scene::from_toml(three, &[]).unwrap();
        assert_eq!(s.model, "elekes_parteli");
        assert_eq!(s.gravity, vec![0.0, 0.0, -9.81]);
        let s = Scene::from_toml(three, &["model=\"lee_herrmann\"".into()]).unwrap();
        assert_eq!(s.gravity, vec![0.0, 0.0, -981.0]);
        let err = Scene::from_toml(
            three,
            &["particles=[{position = [0.0, 0.2], radius = 0.1}]".into()],
        )
        .unwrap_err();
        assert_eq!(err.errors[0].field, "particles[0].position", "{err}");
        let err = Scene::from_toml(three, &["dimension=4".into()]).unwrap_err();
        assert_eq!(err.errors[0].field, "dimension");
    }
}

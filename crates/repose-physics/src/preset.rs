//! Named fidelity presets: concrete numerics for a chosen speed/accuracy trade.
//!
//! A scene names a preset with `preset = "quick"`; the preset then fills in
//! every setting it owns that the scene does not set itself, so an explicit
//! value always wins. The resolved scene (what results store) carries both
//! the preset's name and every concrete value it stood for.
//!
//! What each preset costs and how far it moves θ_R and θ_T from the most
//! accurate settings is measured by `repose tradeoff` and written up in
//! `docs/speed-vs-accuracy.md`.

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use std::fmt;
use std::str::FromStr;

/// A named set of numerical settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// Velocity Verlet, a coarser step and a shorter equilibrium window:
    /// several times faster, for previews and tests.
    Quick,
    /// Velocity Verlet at the default step: the working default of sweeps.
    #[default]
    Standard,
    /// The paper's Gear-5 integrator at the default step: the reference.
    Paper,
}

impl Preset {
    pub const ALL: [Preset; 3] = [Preset::Quick, Preset::Standard, Preset::Paper];

    pub fn name(self) -> &'static str {
        match self {
            Preset::Quick => "quick",
            Preset::Standard => "standard",
            Preset::Paper => "paper",
        }
    }

    /// The scene values this preset sets, as dotted keys.
    pub fn settings(self) -> Vec<(&'static str, Value)> {
        match self {
            Preset::Quick => vec![
                ("numerics.integrator", Value::from("verlet")),
                ("numerics.dt_factor", Value::from(0.05)),
                ("equilibrium.hold", Value::from(0.05)),
                ("equilibrium.check_interval", Value::from(0.01)),
            ],
            Preset::Standard => vec![
                ("numerics.integrator", Value::from("verlet")),
                ("numerics.dt_factor", Value::from(0.02)),
            ],
            Preset::Paper => vec![
                ("numerics.integrator", Value::from("gear5")),
                ("numerics.dt_factor", Value::from(0.02)),
            ],
        }
    }

    /// One line for help texts.
    pub fn describe(self) -> String {
        let parts: Vec<String> = self
            .settings()
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect();
        format!("{}: {}", self.name(), parts.join(", "))
    }

    /// Writes this preset's settings into a scene document wherever the
    /// document leaves them unset.
    pub fn fill(self, doc: &mut Map<String, Value>) {
        for (key, value) in self.settings() {
            if !has_path(doc, key) {
                set_path(doc, key, value).expect("preset keys are well formed");
            }
        }
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown preset `{s}` (expected quick, standard or paper)"))
    }
}

/// Sets a dotted key in a JSON object, creating tables on the way.
pub fn set_path(doc: &mut Map<String, Value>, key: &str, value: Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("empty segment in the key".into());
    }
    let mut table = doc;
    for part in &parts[..parts.len() - 1] {
        let entry = table
            .entry(part.to_string())
            .or_insert_with(|| Value::Object(Map::new()));
        table = match entry {
            Value::Object(t) => t,
            _ => return Err(format!("`{part}` is not a table")),
        };
    }
    table.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

/// Whether a dotted key is set (to anything but null) in a JSON object.
pub fn has_path(doc: &Map<String, Value>, key: &str) -> bool {
    let mut table = doc;
    let parts: Vec<&str> = key.split('.').collect();
    for (k, part) in parts.iter().enumerate() {
        match table.get(*part) {
            None | Some(Value::Null) => return false,
            Some(Value::Object(t)) if k + 1 < parts.len() => table = t,
            Some(_) => return k + 1 == parts.len(),
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn fills_only_what_the_document_leaves_unset() {
        let mut doc = json!({"numerics": {"integrator": "gear5"}})
            .as_object()
            .unwrap()
            .clone();
        Preset::Quick.fill(&mut doc);
        assert_eq!(doc["numerics"]["integrator"], "gear5");
        assert_eq!(doc["numerics"]["dt_factor"], 0.05);
        assert_eq!(doc["equilibrium"]["hold"], 0.05);
    }

    #[test]
    fn names_round_trip() {
        for p in Preset::ALL {
            assert_eq!(p.name().parse::<Preset>().unwrap(), p);
            assert_eq!(serde_json::to_value(p).unwrap(), json!(p.name()));
        }
        assert!("fast".parse::<Preset>().unwrap_err().contains("fast"));
    }
}

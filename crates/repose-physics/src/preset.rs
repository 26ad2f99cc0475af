//! Named fidelity presets: concrete numerics for a chosen speed/accuracy trade.
//!
//! A scene names a preset with `preset = "quick"`; its protocol then fills
//! in every setting the preset stands for that the scene does not set itself
//! ([`crate::protocols::Protocol::preset`]), so an explicit value always
//! wins. The resolved scene (what results store) carries both the preset's
//! name and every concrete value it stood for.
//!
//! What each preset costs and how far it moves the measured angles from the
//! most accurate settings is measured by `repose tradeoff` and written up in
//! `docs/speed-vs-accuracy.md`.

use serde::{Deserialize, Serialize};
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    #[test]
    fn fills_only_what_the_document_leaves_unset() {
        let s = Scene::from_toml(
            "protocol = \"fill_release\"\npreset = \"quick\"\n[numerics]\nintegrator = \"gear5\"",
            &[],
        )
        .unwrap();
        assert_eq!(s.numerics.integrator.name(), "gear5");
        assert_eq!(s.numerics.dt_factor, 0.05);
        assert_eq!(s.sections.value("equilibrium").unwrap()["hold"], 0.05);
    }

    #[test]
    fn a_preset_over_a_value_that_is_not_a_table_names_the_field() {
        let err = Scene::from_toml(
            "protocol = \"flux\"\nnumerics = 1",
            &["preset=quick".into()],
        )
        .unwrap_err();
        assert_eq!(err.errors[0].field, "numerics", "{err}");
    }

    #[test]
    fn names_round_trip() {
        for p in Preset::ALL {
            assert_eq!(p.name().parse::<Preset>().unwrap(), p);
            assert_eq!(
                serde_json::to_value(p).unwrap(),
                serde_json::json!(p.name())
            );
        }
        assert!("fast".parse::<Preset>().unwrap_err().contains("fast"));
    }
}

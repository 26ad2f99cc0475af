//! Checkpoints: a run saved at one of its protocol's resumable points and
//! continued from there, bit for bit.
//!
//! A resumable protocol calls [`Runner::checkpoint`](super::runner::Runner::checkpoint)
//! at the top of its loops, where its whole state is the engine, the
//! runner's trace and a few values of its own (the pour's random stream
//! and counters, say). The observer decides when a checkpoint is due and
//! keeps it; a later run of the same scene handed that checkpoint by its
//! observer restores everything and goes on from the same point, so its
//! report equals the uninterrupted run's in every simulated number.
//!
//! The bytes are [postcard](https://docs.rs/postcard) (floats as their
//! eight bytes, so nothing is rounded) with a header naming the format,
//! the engine build, the engine variant (contact law and integrator, by
//! their type names without module paths, so that moving a type to another
//! module keeps its checkpoints), the protocol and the seed. A checkpoint
//! whose header does not match is set aside and the run starts over.

use crate::report::{Phase, TracePoint};
use serde::{Deserialize, Serialize};

/// A saved run, as an observer keeps it.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// Simulated time at the save, s.
    pub time: f64,
    /// Steps taken at the save.
    pub iteration: u64,
    /// The encoded state.
    pub state: Vec<u8>,
}

/// Version of the encoding; bump when a saved field changes.
const FORMAT: u32 = 2;

/// What must agree between the run that saved and the run that resumes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Header {
    format: u32,
    engine: String,
    variant: String,
    protocol: String,
    seed: u64,
}

impl Header {
    pub(super) fn new(variant: &str, protocol: &str, seed: u64) -> Header {
        Header {
            format: FORMAT,
            engine: crate::report::ENGINE.to_string(),
            variant: bare(variant),
            protocol: protocol.to_string(),
            seed,
        }
    }
}

/// One trace point with its phase by name.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct SavedPoint {
    iteration: u64,
    time: f64,
    kinetic_energy: f64,
    max_speed: f64,
    phase: String,
}

impl SavedPoint {
    pub(super) fn of(p: &TracePoint) -> SavedPoint {
        SavedPoint {
            iteration: p.iteration,
            time: p.time,
            kinetic_energy: p.kinetic_energy,
            max_speed: p.max_speed,
            phase: p.phase.name().to_string(),
        }
    }

    /// The point back, with its phase found among `phases`.
    pub(super) fn point(&self, phases: &[Phase]) -> Result<TracePoint, String> {
        let phase = phases
            .iter()
            .copied()
            .find(|p| p.name() == self.phase)
            .ok_or_else(|| format!("the saved trace names an unknown phase {:?}", self.phase))?;
        Ok(TracePoint {
            iteration: self.iteration,
            time: self.time,
            kinetic_energy: self.kinetic_energy,
            max_speed: self.max_speed,
            phase,
        })
    }
}

/// A whole saved run: engine state `E` and protocol state `P`.
#[derive(Serialize, Deserialize)]
pub(super) struct Saved<E, P> {
    pub header: Header,
    pub engine: E,
    pub trace: Vec<SavedPoint>,
    /// Wall-clock seconds spent before the save.
    pub wall_time: f64,
    pub protocol: P,
}

/// Encodes a saved run.
pub(super) fn encode<E: Serialize, P: Serialize>(saved: &Saved<E, P>) -> Result<Vec<u8>, String> {
    postcard::to_stdvec(saved).map_err(|e| e.to_string())
}

/// Decodes a saved run written by a run with the same `header`.
pub(super) fn decode<E, P>(bytes: &[u8], header: &Header) -> Result<Saved<E, P>, String>
where
    E: serde::de::DeserializeOwned,
    P: serde::de::DeserializeOwned,
{
    let (found, _): (Header, _) =
        postcard::take_from_bytes(bytes).map_err(|e| format!("unreadable checkpoint: {e}"))?;
    let found = Header {
        variant: bare(&found.variant),
        ..found
    };
    if &found != header {
        return Err(format!(
            "the checkpoint was written by another build or scene ({} {} {} seed {}, format {})",
            found.engine, found.variant, found.protocol, found.seed, found.format
        ));
    }
    postcard::from_bytes(bytes).map_err(|e| format!("unreadable checkpoint: {e}"))
}

/// A type name without its module paths: `a::b::Law<c::N, true>` becomes
/// `Law<N, true>`.
fn bare(type_name: &str) -> String {
    let parts: Vec<&str> = type_name.split("::").collect();
    let Some((last, paths)) = parts.split_last() else {
        return String::new();
    };
    // Each part before a `::` ends with the module it names: drop it.
    let kept = paths
        .iter()
        .map(|p| p.trim_end_matches(|c: char| c.is_alphanumeric() || c == '_'));
    kept.chain([*last]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_variant_is_named_without_module_paths() {
        let old = "repose_physics::contact::Pairwise<repose_physics::contact::viscoelastic::\
                   ViscoelasticHertz, repose_physics::contact::rolling::Epsd2, true>, \
                   repose_physics::integrate::VelocityVerlet";
        let moved = "repose_engine::contact::Pairwise<repose_engine::contact::viscoelastic::\
                     ViscoelasticHertz, repose_engine::contact::rolling::Epsd2, true>, \
                     repose_engine::integrate::VelocityVerlet";
        let bare_old = bare(old);
        assert_eq!(
            bare_old,
            "Pairwise<ViscoelasticHertz, Epsd2, true>, VelocityVerlet"
        );
        assert_eq!(bare(moved), bare_old);
        let other = "repose_engine::contact::Pairwise<repose_engine::contact::viscoelastic::\
                     ViscoelasticHertz, repose_engine::contact::NoRolling, true>, \
                     repose_engine::integrate::VelocityVerlet";
        assert_ne!(bare(other), bare_old);
    }

    #[test]
    fn a_checkpoint_of_a_moved_law_is_read_and_one_of_another_law_is_not() {
        let saved = |variant: &str| Saved {
            header: Header {
                format: FORMAT,
                engine: crate::report::ENGINE.to_string(),
                variant: variant.to_string(),
                protocol: "heap".into(),
                seed: 3,
            },
            engine: 1.5f64,
            trace: Vec::new(),
            wall_time: 0.0,
            protocol: 7u32,
        };
        let bytes = encode(&saved("old::path::Law<old::A>, old::Verlet")).unwrap();
        let here = Header::new("new::path::Law<new::A>, new::Verlet", "heap", 3);
        let back: Saved<f64, u32> = decode(&bytes, &here).unwrap();
        assert_eq!((back.engine, back.protocol), (1.5, 7));
        let elsewhere = Header::new("new::path::Law<new::B>, new::Verlet", "heap", 3);
        assert!(decode::<f64, u32>(&bytes, &elsewhere).is_err());
    }
}

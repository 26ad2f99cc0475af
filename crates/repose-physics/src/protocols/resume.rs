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
//!
//! Format 3 keeps the engine's counters as text, so that a counter added
//! later does not make saved runs unreadable. Format 2 (the counters field
//! by field) is still read, its engine state upgraded on the way.

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

/// Version of the encoding; bump when a saved field changes, and keep
/// reading the previous one (see [`decode`]).
const FORMAT: u32 = 3;

/// The earlier format still read: the engine's counters field by field.
const FORMAT_2: u32 = 2;

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

/// Decodes a saved run written by a run with the same `header`, in this
/// format or in format 2, whose engine state `Old` is turned into today's
/// by `upgrade`.
pub(super) fn decode<E, Old, P>(
    bytes: &[u8],
    header: &Header,
    upgrade: impl FnOnce(Old) -> E,
) -> Result<Saved<E, P>, String>
where
    E: serde::de::DeserializeOwned,
    Old: serde::de::DeserializeOwned,
    P: serde::de::DeserializeOwned,
{
    let (found, _): (Header, _) =
        postcard::take_from_bytes(bytes).map_err(|e| format!("unreadable checkpoint: {e}"))?;
    let found = Header {
        variant: bare(&found.variant),
        ..found
    };
    let format = found.format;
    if (Header {
        format,
        ..header.clone()
    }) != found
        || ![FORMAT, FORMAT_2].contains(&format)
    {
        return Err(format!(
            "the checkpoint was written by another build or scene ({} {} {} seed {}, format {})",
            found.engine, found.variant, found.protocol, found.seed, found.format
        ));
    }
    let unreadable = |e: postcard::Error| format!("unreadable checkpoint (format {format}): {e}");
    if format == FORMAT {
        return postcard::from_bytes(bytes).map_err(unreadable);
    }
    let old: Saved<Old, P> = postcard::from_bytes(bytes).map_err(unreadable)?;
    Ok(Saved {
        header: header.clone(),
        engine: upgrade(old.engine),
        trace: old.trace,
        wall_time: old.wall_time,
        protocol: old.protocol,
    })
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

    /// A save with engine state `E` under a header of format `format`.
    fn saved_in<E>(format: u32, engine: E) -> Saved<E, u32> {
        Saved {
            header: Header {
                format,
                ..Header::new("Law<A>, Verlet", "heap", 3)
            },
            engine,
            trace: vec![SavedPoint {
                iteration: 4,
                time: 0.5,
                kinetic_energy: 2.0,
                max_speed: 1.0,
                phase: "pour".into(),
            }],
            wall_time: 9.0,
            protocol: 7,
        }
    }

    #[test]
    fn a_format_2_checkpoint_is_upgraded_and_other_formats_are_set_aside() {
        let here = Header::new("Law<A>, Verlet", "heap", 3);
        // Format 2's engine state (here a pair) becomes today's (a triple).
        let bytes = encode(&saved_in(FORMAT_2, (1u8, 2u64))).unwrap();
        let back: Saved<(u8, u64, u64), u32> =
            decode(&bytes, &here, |(a, b): (u8, u64)| (a, b, 0)).unwrap();
        assert_eq!(back.engine, (1, 2, 0));
        assert_eq!(
            (back.protocol, back.wall_time, back.trace.len()),
            (7, 9.0, 1)
        );
        assert_eq!(back.header, here);
        // Today's format is read as it is, never through the upgrade.
        let bytes = encode(&saved_in(FORMAT, (1u8, 2u64, 3u64))).unwrap();
        let back: Saved<(u8, u64, u64), u32> =
            decode(&bytes, &here, |_: (u8, u64)| panic!("not an old save")).unwrap();
        assert_eq!(back.engine, (1, 2, 3));
        for other in [1, FORMAT + 1] {
            let bytes = encode(&saved_in(other, (1u8, 2u64, 3u64))).unwrap();
            let why = decode::<(u8, u64, u64), (u8, u64), u32>(&bytes, &here, |(a, b)| (a, b, 0))
                .err()
                .unwrap();
            assert!(why.contains(&format!("format {other}")), "{why}");
        }
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
        let back: Saved<f64, u32> = decode(&bytes, &here, |old: f64| old).unwrap();
        assert_eq!((back.engine, back.protocol), (1.5, 7));
        let elsewhere = Header::new("new::path::Law<new::B>, new::Verlet", "heap", 3);
        assert!(decode::<f64, f64, u32>(&bytes, &elsewhere, |old| old).is_err());
    }
}

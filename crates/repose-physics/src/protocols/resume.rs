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
//! Format 4 lets a protocol's own state grow (the pour saves how far it
//! is through the interval between two insertions, so that it can stop
//! between them). Format 3 (the protocol's state as it was) and format 2
//! (the engine's counters field by field) are still read, upgraded on the
//! way; since format 3 the counters are text, so that a counter added
//! later does not make saved runs unreadable.

use crate::report::{Phase, TracePoint};
use repose_engine::dim::{Dim, Space, Vector};
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
const FORMAT: u32 = 4;

/// The format before: the protocols' own states as they were.
const FORMAT_3: u32 = 3;

/// The format before that: the engine's counters field by field as well.
const FORMAT_2: u32 = 2;

/// The formats this build reads.
const READABLE: [u32; 3] = [FORMAT, FORMAT_3, FORMAT_2];

/// A protocol's own state in a checkpoint, and how formats 2 and 3 held it.
pub trait SavedProtocol: Serialize + serde::de::DeserializeOwned {
    /// The state as formats 2 and 3 laid it out.
    type Format3: serde::de::DeserializeOwned;
    /// Today's state of a run saved in format 2 or 3.
    fn upgrade(old: Self::Format3) -> Self;
}

/// The state of a protocol that keeps none of its own.
impl SavedProtocol for () {
    type Format3 = ();
    fn upgrade(_: ()) {}
}

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
/// format or in formats 3 and 2: their protocol state is upgraded by
/// [`SavedProtocol::upgrade`], and format 2's engine state `Old` turned
/// into today's by `upgrade`.
pub(super) fn decode<E, Old, P>(
    bytes: &[u8],
    header: &Header,
    upgrade: impl FnOnce(Old) -> E,
) -> Result<Saved<E, P>, String>
where
    E: serde::de::DeserializeOwned,
    Old: serde::de::DeserializeOwned,
    P: SavedProtocol,
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
        || !READABLE.contains(&format)
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
    if format == FORMAT_3 {
        let old: Saved<E, P::Format3> = postcard::from_bytes(bytes).map_err(unreadable)?;
        return Ok(old.upgraded(header, |engine| engine));
    }
    let old: Saved<Old, P::Format3> = postcard::from_bytes(bytes).map_err(unreadable)?;
    Ok(old.upgraded(header, upgrade))
}

/// The front of a saved run: its header and the first fields of the
/// engine's state, its grains (`EngineState` begins with `Particles`,
/// whose ids, positions, velocities, forces and radii come first; a
/// change there is a change of format).
#[derive(Deserialize)]
#[serde(bound = "")]
struct Front<const D: usize>
where
    Dim<D>: Space<D>,
{
    _header: Header,
    ids: Vec<u32>,
    positions: Vec<Vector<D>>,
    _velocities: Vec<Vector<D>>,
    _forces: Vec<Vector<D>>,
    radii: Vec<f64>,
}

/// Where the grains of a saved run of `dimension` (2 or 3) were at the
/// save, as `(centre, radius)` in m: what a running sample looks like,
/// read without resuming it (nor knowing its contact law).
pub fn saved_grains(bytes: &[u8], dimension: usize) -> Result<Vec<(Vec<f64>, f64)>, String> {
    match dimension {
        2 => grains_of::<2>(bytes),
        3 => grains_of::<3>(bytes),
        _ => Err(format!("no saved run has {dimension} dimensions")),
    }
}

fn grains_of<const D: usize>(bytes: &[u8]) -> Result<Vec<(Vec<f64>, f64)>, String>
where
    Dim<D>: Space<D>,
{
    let (header, _): (Header, _) =
        postcard::take_from_bytes(bytes).map_err(|e| format!("unreadable checkpoint: {e}"))?;
    if !READABLE.contains(&header.format) {
        return Err(format!(
            "the checkpoint's format {} is not one this build reads",
            header.format
        ));
    }
    let (front, _): (Front<D>, _) = postcard::take_from_bytes(bytes)
        .map_err(|e| format!("unreadable checkpoint (format {}): {e}", header.format))?;
    let n = front.ids.len();
    if front.positions.len() != n || front.radii.len() != n {
        return Err(format!(
            "unreadable checkpoint: {n} grains, {} positions and {} radii \
             (is it a run in {D} dimensions?)",
            front.positions.len(),
            front.radii.len()
        ));
    }
    Ok(front
        .positions
        .iter()
        .zip(&front.radii)
        .map(|(p, &r)| (p.iter().copied().collect(), r))
        .collect())
}

impl<E, P> Saved<E, P> {
    /// The run in today's format, under `header`.
    fn upgraded<F, Q: SavedProtocol<Format3 = P>>(
        self,
        header: &Header,
        engine: impl FnOnce(E) -> F,
    ) -> Saved<F, Q> {
        Saved {
            header: header.clone(),
            engine: engine(self.engine),
            trace: self.trace,
            wall_time: self.wall_time,
            protocol: Q::upgrade(self.protocol),
        }
    }
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

    /// A protocol state that gained a field in format 4.
    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Grown {
        kept: u32,
        added: u64,
    }

    impl SavedProtocol for Grown {
        type Format3 = u32;
        fn upgrade(kept: u32) -> Grown {
            Grown { kept, added: 0 }
        }
    }

    /// A save with engine state `E` and protocol state `P` under a header
    /// of format `format`.
    fn saved_in<E, P>(format: u32, engine: E, protocol: P) -> Saved<E, P> {
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
            protocol,
        }
    }

    type Today = Saved<(u8, u64, u64), Grown>;

    #[test]
    fn formats_2_and_3_are_upgraded_and_other_formats_are_set_aside() {
        let here = Header::new("Law<A>, Verlet", "heap", 3);
        let not_old = |_: (u8, u64)| -> (u8, u64, u64) { panic!("not a format-2 save") };
        // Format 2: the engine state (here a pair) becomes today's (a
        // triple), and the protocol's state gains its field.
        let bytes = encode(&saved_in(FORMAT_2, (1u8, 2u64), 7u32)).unwrap();
        let back: Today = decode(&bytes, &here, |(a, b): (u8, u64)| (a, b, 0)).unwrap();
        assert_eq!(back.engine, (1, 2, 0));
        assert_eq!(back.protocol, Grown { kept: 7, added: 0 });
        assert_eq!((back.wall_time, back.trace.len()), (9.0, 1));
        assert_eq!(back.header, here);
        // Format 3: today's engine state, the protocol's upgraded.
        let bytes = encode(&saved_in(FORMAT_3, (1u8, 2u64, 3u64), 7u32)).unwrap();
        let back: Today = decode(&bytes, &here, not_old).unwrap();
        assert_eq!(back.engine, (1, 2, 3));
        assert_eq!(back.protocol, Grown { kept: 7, added: 0 });
        assert_eq!(back.header, here);
        // Today's format is read as it is, never through an upgrade.
        let grown = Grown { kept: 7, added: 9 };
        let bytes = encode(&saved_in(FORMAT, (1u8, 2u64, 3u64), grown)).unwrap();
        let back: Today = decode(&bytes, &here, not_old).unwrap();
        assert_eq!((back.engine, back.protocol.added), ((1, 2, 3), 9));
        for other in [1, FORMAT + 1] {
            let bytes = encode(&saved_in(other, (1u8, 2u64, 3u64), 7u32)).unwrap();
            let why = decode::<_, _, Grown>(&bytes, &here, |(a, b): (u8, u64)| (a, b, 0u64))
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
            protocol: (),
        };
        let bytes = encode(&saved("old::path::Law<old::A>, old::Verlet")).unwrap();
        let here = Header::new("new::path::Law<new::A>, new::Verlet", "heap", 3);
        let back: Saved<f64, ()> = decode(&bytes, &here, |old: f64| old).unwrap();
        assert_eq!(back.engine, 1.5);
        let elsewhere = Header::new("new::path::Law<new::B>, new::Verlet", "heap", 3);
        assert!(decode::<f64, f64, ()>(&bytes, &elsewhere, |old| old).is_err());
    }

    #[test]
    fn the_grains_of_a_saved_engine_are_read_without_its_law() {
        use repose_engine::contact::{Frictionless, HertzDamped, Pairwise};
        use repose_engine::integrate::VelocityVerlet;
        use repose_engine::particles::Particles;
        use repose_engine::simulation::Simulation;
        let mut grains = Particles::<3>::new(false);
        let placed = [
            ([0.0, 0.0, 1.0e-3], 5.0e-4),
            ([2.0e-3, -1.0e-3, 0.5e-3], 4.0e-4),
        ];
        for (p, r) in placed {
            grains.push(Vector::<3>::from(p), Vector::<3>::zeros(), r, 1e-6);
        }
        let law = Pairwise::new(
            HertzDamped::<true> {
                k_n: 1e6,
                gamma_n: 0.0,
            },
            Frictionless,
        );
        let gravity = Vector::<3>::new(0.0, 0.0, -9.81);
        let mut sim: Simulation<3, _, VelocityVerlet> =
            Simulation::new(grains, Vec::new(), gravity, law, 1e-6, 1e-4);
        for _ in 0..10 {
            sim.step().unwrap();
        }
        let saved = Saved {
            header: Header::new("Law, Verlet", "heap", 3),
            engine: sim.save_state(),
            trace: Vec::new(),
            wall_time: 1.0,
            protocol: (),
        };
        let bytes = encode(&saved).unwrap();
        let read = saved_grains(&bytes, 3).unwrap();
        let want: Vec<(Vec<f64>, f64)> = (sim.particles.pos.iter().zip(&sim.particles.radius))
            .map(|(p, &r)| (p.iter().copied().collect(), r))
            .collect();
        assert_eq!(read, want);
        // Ten steps of free fall moved the grains off their places.
        assert!(read[0].0[2] < 1.0e-3 && read[1].1 == 4.0e-4, "{read:?}");
        assert!(saved_grains(&bytes, 4)
            .unwrap_err()
            .contains("4 dimensions"));
        let mut other = saved;
        other.header.format = FORMAT + 1;
        let why = saved_grains(&encode(&other).unwrap(), 3).unwrap_err();
        assert!(why.contains(&format!("format {}", FORMAT + 1)), "{why}");
    }
}

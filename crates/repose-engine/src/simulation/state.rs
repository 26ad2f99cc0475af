//! A running simulation saved and restored bit for bit.
//!
//! What evolves — the grains, the integrator's history, the pair list with
//! its contact springs, the wall contacts, the clock and the counters — is
//! the state. What the scene fixes — the laws, the walls, outlets and the
//! periodic cell, the time step — is built again from the scene, and a
//! restored engine then takes exactly the steps the saved one would have.
//!
//! The counters are kept as JSON text ([`SavedCounters`]): they are
//! bookkeeping that grows a field now and then, and as text a counter added
//! later neither breaks an older save nor is broken by it. Saves from
//! before that ([`CountersFormat2`]) are read through
//! [`EngineState::upgrade`].

use super::{Guards, Simulation, StageCounters};
use crate::contact::ContactLaw;
use crate::dim::{Dim, Space};
use crate::integrate::Integrator;
use crate::neighbors::NeighborList;
use crate::particles::Particles;
use crate::walls::WallContacts;
use serde::{Deserialize, Serialize};

/// The evolving part of a [`Simulation`] with contact histories `H` and
/// integrator `I`; its counters are encoded as `C`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct EngineState<const D: usize, H, I, C = SavedCounters>
where
    Dim<D>: Space<D>,
    H: Copy + Default + std::fmt::Debug + Serialize + serde::de::DeserializeOwned,
    I: Serialize + serde::de::DeserializeOwned,
    C: Serialize + serde::de::DeserializeOwned,
{
    particles: Particles<D>,
    integrator: I,
    neighbors: NeighborList<D, H>,
    wall_contacts: WallContacts<H>,
    walls: usize,
    dt: f64,
    guards: Guards,
    time: f64,
    iteration: u64,
    removed: usize,
    counters: C,
    max_overlap_seen: f64,
    primed: bool,
    sorted_at: Option<u64>,
}

/// [`StageCounters`] as JSON text inside a saved state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SavedCounters(pub StageCounters);

impl Serialize for SavedCounters {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let text = serde_json::to_string(&self.0).map_err(serde::ser::Error::custom)?;
        s.serialize_str(&text)
    }
}

impl<'de> Deserialize<'de> for SavedCounters {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        let text = String::deserialize(d)?;
        let counters = serde_json::from_str(&text).map_err(serde::de::Error::custom)?;
        Ok(SavedCounters(counters))
    }
}

/// The counters as saves of format 2 laid them out, field by field (before
/// the shared steps were counted).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CountersFormat2 {
    integrate: f64,
    neighbours: f64,
    contacts: f64,
    walls: f64,
    list_builds: u64,
    particle_steps: u64,
    resting_steps: u64,
    steps: u64,
}

impl From<CountersFormat2> for SavedCounters {
    fn from(c: CountersFormat2) -> SavedCounters {
        SavedCounters(StageCounters {
            integrate: c.integrate,
            neighbours: c.neighbours,
            contacts: c.contacts,
            walls: c.walls,
            list_builds: c.list_builds,
            particle_steps: c.particle_steps,
            resting_steps: c.resting_steps,
            steps: c.steps,
            shared_steps: 0,
        })
    }
}

impl<const D: usize, H, I, C> EngineState<D, H, I, C>
where
    Dim<D>: Space<D>,
    H: Copy + Default + std::fmt::Debug + Serialize + serde::de::DeserializeOwned,
    I: Serialize + serde::de::DeserializeOwned,
    C: Serialize + serde::de::DeserializeOwned,
{
    /// The state with its counters in today's encoding.
    pub fn upgrade(self) -> EngineState<D, H, I>
    where
        C: Into<SavedCounters>,
    {
        self.with_counters(Into::into)
    }

    /// The same state with its counters re-encoded by `f`.
    pub fn with_counters<C2>(self, f: impl FnOnce(C) -> C2) -> EngineState<D, H, I, C2>
    where
        C2: Serialize + serde::de::DeserializeOwned,
    {
        EngineState {
            particles: self.particles,
            integrator: self.integrator,
            neighbors: self.neighbors,
            wall_contacts: self.wall_contacts,
            walls: self.walls,
            dt: self.dt,
            guards: self.guards,
            time: self.time,
            iteration: self.iteration,
            removed: self.removed,
            counters: f(self.counters),
            max_overlap_seen: self.max_overlap_seen,
            primed: self.primed,
            sorted_at: self.sorted_at,
        }
    }
}

/// The state of a simulation with law `L` and integrator `I`.
pub type StateOf<const D: usize, L, I> = EngineState<D, <L as ContactLaw<D>>::History, I>;

/// The same state as saves of format 2 encoded it.
pub type StateFormat2Of<const D: usize, L, I> =
    EngineState<D, <L as ContactLaw<D>>::History, I, CountersFormat2>;

impl<const D: usize, L: ContactLaw<D>, I: Integrator<D>> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    /// A copy of everything that evolves.
    pub fn save_state(&self) -> StateOf<D, L, I> {
        EngineState {
            particles: self.particles.clone(),
            integrator: self.integrator.clone(),
            neighbors: self.neighbors.clone(),
            wall_contacts: self.wall_contacts.clone(),
            walls: self.walls.len(),
            dt: self.dt,
            guards: self.guards,
            time: self.time,
            iteration: self.iteration,
            removed: self.removed,
            counters: SavedCounters(self.counters),
            max_overlap_seen: self.max_overlap_seen,
            primed: self.primed,
            sorted_at: self.sorted_at,
        }
    }

    /// Puts a saved state into an engine built from the same scene. Fails
    /// (changing nothing) when the engine's walls or time step differ from
    /// the saved one's.
    pub fn restore_state(&mut self, state: StateOf<D, L, I>) -> Result<(), String> {
        if state.walls != self.walls.len() || state.wall_contacts.history.len() != state.walls {
            return Err(format!(
                "the saved run has {} walls, this engine {}",
                state.walls,
                self.walls.len()
            ));
        }
        if state.dt.to_bits() != self.dt.to_bits() {
            return Err(format!(
                "the saved run steps by {:e} s, this engine by {:e} s",
                state.dt, self.dt
            ));
        }
        if state.particles.rotating() != L::ROTATES {
            return Err("the saved grains and this contact law differ in rotation".into());
        }
        self.particles = state.particles;
        self.integrator = state.integrator;
        self.neighbors = state.neighbors;
        self.wall_contacts = state.wall_contacts;
        self.guards = state.guards;
        self.time = state.time;
        self.iteration = state.iteration;
        self.removed = state.removed;
        self.counters = state.counters.0;
        self.max_overlap_seen = state.max_overlap_seen;
        self.primed = state.primed;
        self.sorted_at = state.sorted_at;
        self.shares = Default::default();
        Ok(())
    }
}

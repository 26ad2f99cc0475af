//! A running simulation saved and restored bit for bit.
//!
//! What evolves — the grains, the integrator's history, the pair list with
//! its contact springs, the wall contacts, the clock and the counters — is
//! the state. What the scene fixes — the laws, the walls, outlets and the
//! periodic cell, the time step — is built again from the scene, and a
//! restored engine then takes exactly the steps the saved one would have.

use super::{Guards, Simulation, StageCounters};
use crate::contact::ContactLaw;
use crate::dim::{Dim, Space};
use crate::integrate::Integrator;
use crate::neighbors::NeighborList;
use crate::particles::Particles;
use crate::walls::WallContacts;
use serde::{Deserialize, Serialize};

/// The evolving part of a [`Simulation`] with contact histories `H` and
/// integrator `I`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct EngineState<const D: usize, H, I>
where
    Dim<D>: Space<D>,
    H: Copy + Default + std::fmt::Debug + Serialize + serde::de::DeserializeOwned,
    I: Serialize + serde::de::DeserializeOwned,
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
    counters: StageCounters,
    max_overlap_seen: f64,
    primed: bool,
    sorted_at: Option<u64>,
}

/// The state of a simulation with law `L` and integrator `I`.
pub type StateOf<const D: usize, L, I> = EngineState<D, <L as ContactLaw<D>>::History, I>;

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
            counters: self.counters,
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
        self.counters = state.counters;
        self.max_overlap_seen = state.max_overlap_seen;
        self.primed = state.primed;
        self.sorted_at = state.sorted_at;
        self.shares = Default::default();
        Ok(())
    }
}

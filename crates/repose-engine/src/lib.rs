//! # repose-engine
//!
//! The discrete-element engine under every repose scene: grains (discs in a
//! plane or spheres in space), the contact laws between them built from
//! components, the integrators, the neighbour list, the walls, and a
//! [`Simulation`] that steps them and saves and restores its state bit for
//! bit. It knows nothing of scenes, protocols, papers or storage; the
//! `repose-physics` crate builds simulations from scene documents.
//!
//! * **Generic over the dimension** ([`dim::Space`]), **the contact law**
//!   ([`contact::ContactLaw`]: normal, tangential, rolling and cohesion
//!   components combined by [`contact::Pairwise`], with or without
//!   rotation) and **the integrator** ([`integrate::Integrator`]), so that
//!   an option a scene leaves off is a type that compiles to nothing.
//! * **A visible pipeline.** [`Simulation::step`] runs predict →
//!   neighbours → contacts → walls → correct, and
//!   [`simulation::StageCounters`] times each stage.
//! * **Contact history is data of the pair list.** Springs live beside the
//!   pairs of the Verlet list and move to the new list at each rebuild
//!   ([`neighbors`]), so they survive rebuilds and vanish when contacts open.
//! * **Deterministic on any number of threads.** A simulation may share its
//!   pair and wall contacts among the threads of a pool; every sum runs in
//!   the order of one thread, so the result does not change by a bit.
//! * **Failures are values.** A step that finds grains overlapping beyond
//!   the guard, a grain through a wall, a runaway grain or energy that gravity cannot supply returns a
//!   [`simulation::Blowup`] naming the grains and the time.

pub mod contact;
pub mod dim;
pub mod integrate;
pub mod neighbors;
pub mod particles;
pub mod simulation;
pub mod walls;

pub use simulation::Simulation;

//! # repose-physics
//!
//! A discrete-element engine for granular piles: grains with contact laws
//! built from components, integrators, neighbour search, walls, and the
//! protocols that measure a pile, with the theory they are compared with:
//! Lee & Herrmann's (1993) 2D piles (the angle of repose θ_R, the tilting
//! angle θ_T and the angle of marginal stability θ_MS) and Elekes &
//! Parteli's (2021) poured 3D heaps of cohesive spheres (θ_r) and packed
//! columns (the packing fraction φ).
//!
//! ## Design
//!
//! * **Pure.** This crate knows nothing of databases, HTTP, files or
//!   async. A [`Scene`] goes in, a [`RunReport`] comes out; the same scene,
//!   seed and build give the same numbers. The only threads it starts are
//!   a sample's own (`numerics.threads`), which share the pair and wall
//!   contacts without changing a bit of the result.
//! * **Plug-ins at the seams.** A protocol ([`protocols::Protocol`]) and a
//!   contact model ([`models::Model`]) each live in one module and declare
//!   what the rest of the project needs: their scene sections with defaults
//!   and checks, and the protocol's metrics. Registering one is one line.
//! * **Generic over the dimension** ([`dim::Space`]: discs in a plane,
//!   spheres in space) and **over the contact law** ([`contact::ContactLaw`],
//!   built from normal, tangential, rolling and cohesion components, with or
//!   without rotation) and the **integrator** ([`integrate::Integrator`]).
//!   A model picks the compiled engine for a scene's options from one flat
//!   list ([`models::lee_herrmann::with_engine`]), so an option that is off
//!   costs nothing.
//! * **A visible pipeline.** [`engine::Simulation::step`] runs predict →
//!   neighbours → contacts → walls → correct, and
//!   [`engine::StageCounters`] times each stage.
//! * **Contact history is data of the pair list.** Springs live beside the
//!   pairs of the Verlet list and move to the new list at each rebuild
//!   ([`neighbors`]), so they survive rebuilds and vanish when contacts open.
//! * **Failures are outcomes.** A blow-up, a pile that never settles or a
//!   tilt that never starts ends the run with an [`report::Outcome`] that
//!   says why, never with a silent number.

pub mod bench;
pub mod contact;
pub mod dim;
pub mod doc;
pub mod engine;
pub mod integrate;
pub mod measure;
pub mod models;
pub mod neighbors;
pub mod particles;
pub mod preset;
pub mod protocols;
pub mod report;
pub mod scene;
pub mod setup;
pub mod theory;
pub mod walls;

pub use preset::Preset;
pub use protocols::{run, Checkpoint, Metric, Observer, Progress, Protocol, Quiet};
pub use report::{Outcome, RunReport, ENGINE};
pub use scene::{FieldError, Scene, SceneError};

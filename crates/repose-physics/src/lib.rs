//! # repose-physics
//!
//! Scenes, contact models, protocols and measurements over the
//! discrete-element engine of `repose-engine`: Lee & Herrmann's (1993) 2D
//! piles (the angle of repose θ_R, the tilting angle θ_T and the angle of
//! marginal stability θ_MS) and Elekes & Parteli's (2021) poured 3D heaps of
//! cohesive spheres (θ_r) and packed columns (the packing fraction φ), with
//! the theory they are compared with.
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
//! * **The engine below.** A model picks the compiled engine
//!   ([`repose_engine::Simulation`], generic over the dimension, the contact
//!   law and the integrator) for a scene's options from one flat list
//!   ([`models::lee_herrmann::with_engine`]), so an option that is off
//!   costs nothing.
//! * **Failures are outcomes.** A blow-up, a pile that never settles or a
//!   tilt that never starts ends the run with an [`report::Outcome`] that
//!   says why, never with a silent number.

pub mod bench;
pub mod doc;
pub mod measure;
pub mod models;
pub mod preset;
pub mod protocols;
pub mod registry;
pub mod report;
pub mod scene;
pub mod setup;
pub mod theory;

pub use preset::Preset;
pub use protocols::{run, Checkpoint, Metric, Observer, Progress, Protocol, Quiet};
pub use report::{Outcome, RunReport, ENGINE};
pub use scene::{FieldError, Scene, SceneError};

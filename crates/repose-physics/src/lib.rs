//! # repose-physics
//!
//! A discrete-element engine for the granular piles of Lee & Herrmann
//! (1993): discs with Hertz normal contacts and Cundall–Strack static
//! friction, the three protocols that measure the angle of repose θ_R, the
//! tilting angle θ_T and the angle of marginal stability θ_MS, and the
//! theory they are compared with.
//!
//! ## Design
//!
//! * **Pure.** This crate knows nothing of databases, HTTP, threads or
//!   async. A [`Scene`] goes in, a [`RunReport`] comes out; the same scene
//!   and seed give the same numbers.
//! * **Generic over the dimension** ([`dim::Space`]) and **over the contact
//!   law** ([`contact::ContactLaw`], built from a normal and a tangential
//!   component) and the **integrator** ([`integrate::Integrator`]). Each
//!   run-time option of a scene selects a compiled variant in
//!   [`protocol::with_engine`], so an option that is off costs nothing.
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
pub mod engine;
pub mod integrate;
pub mod measure;
pub mod neighbors;
pub mod particles;
pub mod preset;
pub mod protocol;
pub mod report;
pub mod scene;
pub mod setup;
pub mod theory;
pub mod walls;

pub use preset::Preset;
pub use protocol::{run, Observer, Progress, Quiet};
pub use report::{Outcome, RunReport, ENGINE};
pub use scene::{Protocol, Scene, SceneError};

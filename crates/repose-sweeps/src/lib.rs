//! # repose-sweeps
//!
//! What the queue needs to know about a sweep, and nothing of papers:
//!
//! * [`spec`] — a sweep: protocol, base scene, axes, samples, fidelity,
//!   seed base, priority; its expansion into one validated, resolved scene
//!   per job with the sample hash that names its result.
//! * [`topup`] — more samples for the points of a `target_sem` sweep whose
//!   error bar is still too wide, added by whoever stores a result.
//!
//! The API queues sweeps with it and the worker tops them up; the papers'
//! studies (`repose-studies`) describe their sweeps in the same terms.

pub mod spec;
pub mod topup;

pub use spec::{JobSpec, Order, SweepSpec};

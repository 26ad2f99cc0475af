//! # repose-studies
//!
//! The papers' studies as data, and the reports written from them. A
//! study's sweeps are `repose-sweeps` specifications.
//!
//! * [`papers`] — each paper's study sweeps and figures (which metric
//!   against which axis, theory curves, the values the paper quotes) and the
//!   comparison of its stated results with ours, and [`PAPERS`], the
//!   registry. Papers are written in the terms of [`paper`], [`figure`],
//!   [`quantity`], [`data`] and [`compare`], which import no paper.
//! * [`draw`] — a figure's data from the stored points and samples of
//!   its sweeps: what the API serves, the page draws and the reports print.
//! * [`reproduction`] and [`tradeoff`] — the two reports: a paper reproduced
//!   through the service, and what each fidelity setting costs and changes.
//! * [`fit`] and [`fitted`] — least squares with confidence intervals, and
//!   the papers' fits drawn on figures.
//! * [`chart`] — static SVG charts for the reports.
//!
//! **Architecture Invariant:** theory is evaluated here, in Rust, once. The
//! page draws the curves the API serves; it has no copy of an equation.

pub mod chart;
pub mod compare;
pub mod data;
pub mod draw;
pub mod figure;
pub mod fit;
pub mod fitted;
pub mod paper;
pub mod papers;
pub mod quantity;
pub mod remaining;
pub mod reproduction;
pub mod tradeoff;

pub use figure::FigureData;
pub use paper::Paper;
pub use papers::PAPERS;

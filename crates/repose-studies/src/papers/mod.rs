//! Each paper's study as data: the sweeps behind its figures, the figures
//! (which metric against which axis, the theory curves, the values the
//! paper quotes) and the comparison of its stated results with ours.
//!
//! A figure names the sweeps it draws from by their key within the paper;
//! [`crate::figure`] turns a figure and the data of those sweeps into what
//! the API serves, the page draws and the reproduction report prints, so
//! all three show the same thing. Adding a figure is one entry in its
//! paper's list; adding a paper is a module and one line in [`PAPERS`]. The
//! types a paper is written in live below the papers ([`crate::paper`],
//! [`crate::figure`], [`crate::quantity`]), so no paper imports this list.

pub mod ep21;
pub mod lh93;

use crate::paper::Paper;

/// Every paper. Registering one is one line here.
pub static PAPERS: &[&Paper] = &[&lh93::PAPER, &ep21::PAPER];

/// The paper of this key.
pub fn find(key: &str) -> Option<&'static Paper> {
    PAPERS.iter().copied().find(|p| p.key == key)
}

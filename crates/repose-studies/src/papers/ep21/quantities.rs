//! The constants of the paper's glass and gravity levels, and the
//! quantities its figures compute from a point's axes: d in µm, g̃, the
//! Bond number and d√g̃.

use crate::quantity::Quantity;
use serde_json::{Map, Value};

/// Earth's gravity, m/s²: g̃ = g / G_EARTH.
pub const G_EARTH: f64 = 9.81;
/// The gravity levels of the paper by g̃: Pluto, Moon, Mars, Earth, 10 g, 100 g.
pub const GRAVITIES: [f64; 6] = [0.063, 0.165, 0.378, 1.0, 10.0, 100.0];
/// Glass (Table 1): density and surface energy, the values of every
/// study sweep's base (the Bond number is computed with them).
pub const DENSITY: f64 = 2500.0;
pub const SURFACE_ENERGY: f64 = 0.05;
/// The Bond number above which the paper sees irregular heaps (regime I).
pub const BOND_REGIME_I: f64 = 1e4;

/// A heap's angle read from columns one diameter wide, each filled to its
/// highest grain's top: the headline metric of every committed heap.
pub const THETA_COLUMNS: &str = "theta_r";
/// The same heap's angle read from the upper boundary of its projection,
/// as the paper reads its images.
pub const THETA_SILHOUETTE: &str = "theta_r_silhouette";

pub static QUANTITIES: [Quantity; 4] = [
    Quantity {
        name: "ep21.d_um",
        symbol: "d",
        f: d_um,
    },
    Quantity {
        name: "ep21.g_tilde",
        symbol: "g̃",
        f: g_tilde,
    },
    Quantity {
        name: "ep21.bond",
        symbol: "Bo",
        f: bond,
    },
    Quantity {
        name: "ep21.d_sqrt_g_um",
        symbol: "d√g̃",
        f: |p| Some(d_um(p)? * g_tilde(p)?.sqrt()),
    },
];

/// `x` to nine significant digits: a value set as 0.165 g reads back as
/// 0.165, not 0.16499999999999998, in labels and series keys.
pub(super) fn rounded(x: f64) -> f64 {
    format!("{x:.8e}").parse().unwrap_or(x)
}

/// The grain diameter of a point, µm.
pub fn d_um(point: &Map<String, Value>) -> Option<f64> {
    Some(rounded(point.get("grains.diameter")?.as_f64()? * 1e6))
}

/// The gravity of a point in Earth's: g̃ = |g| / 9.81 m/s².
pub fn g_tilde(point: &Map<String, Value>) -> Option<f64> {
    let g = point.get("gravity")?.as_array()?;
    let g2: f64 = g
        .iter()
        .map(|c| c.as_f64().map(|c| c * c))
        .sum::<Option<f64>>()?;
    Some(rounded(g2.sqrt() / G_EARTH))
}

/// The Bond number of a point, Bo = 12 γ / (d² g ρ), with the paper's
/// factor 12 (the pair force πγd against the weight is half of it).
pub fn bond(point: &Map<String, Value>) -> Option<f64> {
    let d = point.get("grains.diameter")?.as_f64()?;
    let g = g_tilde(point)? * G_EARTH;
    Some(12.0 * SURFACE_ENERGY / (d * d * g * DENSITY))
}

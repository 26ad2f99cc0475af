//! Van der Waals attraction between spheres, Elekes & Parteli's eqs. (13)
//! and (14).

use super::{CohesionLaw, Touch};
use crate::dim::{Dim, Space};

/// `F = A_H R_eff / (6 (s + D_min)²)` across a gap `s` up to `D_max`,
/// and while the spheres touch either its value at `s = 0` (eq. 13 as
/// printed: the attraction does not grow with the overlap) or, with
/// `fades_in_contact`, the same law with the overlap `δ` as the distance,
/// `A_H R_eff / (6 (δ + D_min)²)`. `A_H = 24π D_min² γ` for a surface
/// energy `γ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VanDerWaals {
    /// The normal force the sliding and rolling limits scale with.
    pub limits: Limits,
    /// Whether the attraction of touching spheres falls with their overlap.
    pub fades_in_contact: bool,
    /// Hamaker constant `A_H`, J.
    pub hamaker: f64,
    /// Cut-off of the attraction at contact, `D_min`, m.
    pub d_min: f64,
    /// Largest gap across which it acts, `D_max`, m.
    pub d_max: f64,
}

/// What a cohesion law may ask of a pair of surfaces: the material's
/// quantities and the model's options, whichever law is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cohesive {
    /// Surface energy `γ`, J/m² (zero for surfaces that do not cohere).
    pub surface_energy: f64,
    /// Cut-off of the attraction at contact, `D_min`, m.
    pub d_min: f64,
    /// Largest gap across which the attraction acts, `D_max`, m.
    pub d_max: f64,
    /// The normal force the sliding and rolling limits scale with.
    pub limits: Limits,
    /// Whether the attraction of touching surfaces falls with their overlap.
    pub fades_in_contact: bool,
}

/// The normal force that bounds sliding and rolling in a cohesive contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limits {
    /// The contact's normal force `F_n` alone (eqs. 11 and 15 as printed).
    Repulsion,
    /// `max(0, F_n − F_vdW)`: the attraction holds, but adds no friction.
    Net,
    /// `|F_n − F_vdW|`: LIGGGHTS 2.x–3.3.1, whose caps read the normal
    /// force with the cohesive force added; friction acts under tension too.
    NetAbsolute,
}

impl VanDerWaals {
    /// The Hamaker constant of a surface energy `γ` (J/m²) with the cut-off `d_min`.
    pub fn hamaker_of(surface_energy: f64, d_min: f64) -> f64 {
        24.0 * std::f64::consts::PI * d_min * d_min * surface_energy
    }

    /// The attraction of two spheres of effective radius `r_eff` at a gap
    /// `gap` (zero or negative while they touch), N.
    #[inline(always)]
    pub fn at(&self, r_eff: f64, gap: f64) -> f64 {
        if gap > self.d_max {
            return 0.0;
        }
        let distance = if self.fades_in_contact {
            gap.abs()
        } else {
            gap.max(0.0)
        };
        let s = distance + self.d_min;
        self.hamaker * r_eff / (6.0 * s * s)
    }
}

impl<const D: usize> CohesionLaw<D> for VanDerWaals
where
    Dim<D>: Space<D>,
{
    const ACTIVE: bool = true;

    fn of(surfaces: &Cohesive) -> Self {
        VanDerWaals {
            limits: surfaces.limits,
            fades_in_contact: surfaces.fades_in_contact,
            hamaker: VanDerWaals::hamaker_of(surfaces.surface_energy, surfaces.d_min),
            d_min: surfaces.d_min,
            d_max: surfaces.d_max,
        }
    }

    fn range(&self) -> f64 {
        self.d_max
    }

    #[inline(always)]
    fn attraction(&self, touch: &Touch<D>) -> f64 {
        self.at(touch.r_eff, -touch.overlap)
    }

    fn at_contact(&self, r_eff: f64) -> f64 {
        self.at(r_eff, 0.0)
    }

    #[inline(always)]
    fn limit_load(&self, attraction: f64, repulsion: f64) -> f64 {
        match self.limits {
            Limits::Repulsion => repulsion,
            Limits::Net => (repulsion - attraction).max(0.0),
            Limits::NetAbsolute => (repulsion - attraction).abs(),
        }
    }

    /// `∫ F ds` across the gap, `A_H R (1/D_min − 1/(D_max + D_min)) / 6`,
    /// plus its work over the depth: the contact value times the depth, or
    /// `A_H R (1/D_min − 1/(depth + D_min)) / 6` where it fades.
    fn work(&self, r_eff: f64, depth: f64) -> f64 {
        let scale = self.hamaker * r_eff / 6.0;
        let across = scale * (1.0 / self.d_min - 1.0 / (self.d_max + self.d_min));
        let depth = depth.max(0.0);
        let inside = if self.fades_in_contact {
            scale * (1.0 / self.d_min - 1.0 / (depth + self.d_min))
        } else {
            self.at(r_eff, 0.0) * depth
        };
        across + inside
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attraction_is_flat_in_contact_and_falls_as_the_inverse_square_of_the_gap() {
        let a = VanDerWaals::hamaker_of(0.05, 1.65e-10);
        assert!((a - 1.026e-19).abs() < 1e-22, "{a}");
        let law = VanDerWaals {
            limits: Limits::Repulsion,
            fades_in_contact: false,
            hamaker: a,
            d_min: 1.65e-10,
            d_max: 1e-6,
        };
        let touching = law.at(2.5e-4, -1e-7);
        assert_eq!(touching, law.at(2.5e-4, 0.0));
        // π γ d for two spheres of diameter d (R_eff = d/4)
        assert!((touching - std::f64::consts::PI * 0.05 * 1e-3).abs() < 1e-12);
        let s = 1e-8;
        let ratio = law.at(2.5e-4, s) / touching;
        let expected = (1.65e-10 / (s + 1.65e-10)).powi(2);
        assert!((ratio - expected).abs() < 1e-12 * expected.max(1e-30));
        assert_eq!(law.at(2.5e-4, 1.1e-6), 0.0);
    }
}

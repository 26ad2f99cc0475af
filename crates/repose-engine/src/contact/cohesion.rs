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
///
/// The attraction falls from its contact value to a quarter of it within
/// one `D_min` (1.65 Å for glass), far less than a pair moves in a step.
/// Read at the pair's gap alone, a step that opens or closes a contact
/// applies it for the whole step or hardly at all. With a `sweep` step the
/// pair feels instead the mean of the attraction over the gaps it sweeps
/// in that step, `gap ± (v·n) Δt / 2`: the impulse the law gives a pair
/// crossing the well at a steady speed, whatever the step.
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
    /// The step over which the attraction is averaged along the gap a pair
    /// sweeps, s; 0 reads it at the pair's gap.
    pub sweep: f64,
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
    /// The step over which a pair's attraction is averaged along the gap it
    /// sweeps, s ([`VanDerWaals::sweep`]); 0 reads it at the pair's gap.
    pub sweep: f64,
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

    /// The mean of [`VanDerWaals::at`] over the gaps a pair at `gap`,
    /// opening at `rate` (m/s; negative while closing), sweeps in a step of
    /// [`VanDerWaals::sweep`] centred on now: the integral of the
    /// attraction over `gap ± rate Δt / 2`, piece by piece (in contact,
    /// across the gap, beyond `D_max`), over the window's width. Each piece
    /// of `A_H R / (6 (s + D_min)²)` integrates to a product of its ends,
    /// so no difference of large numbers is taken; a pair at rest feels
    /// [`VanDerWaals::at`].
    #[inline(always)]
    pub fn swept(&self, r_eff: f64, gap: f64, rate: f64) -> f64 {
        let half = 0.5 * (rate * self.sweep).abs();
        let (lo, hi) = (gap - half, gap + half);
        if hi <= lo {
            return self.at(r_eff, gap);
        }
        if lo > self.d_max {
            return 0.0;
        }
        let scale = self.hamaker * r_eff / 6.0;
        // The mean over [a, b] of each piece, a product of its ends.
        let inside = |a: f64, b: f64| {
            if self.fades_in_contact {
                scale / ((self.d_min - a) * (self.d_min - b))
            } else {
                scale / (self.d_min * self.d_min)
            }
        };
        let across = |a: f64, b: f64| scale / ((a + self.d_min) * (b + self.d_min));
        if hi <= 0.0 {
            return inside(lo, hi);
        }
        if lo >= 0.0 && hi <= self.d_max {
            return across(lo, hi);
        }
        // The window straddles the surface or D_max: its pieces, weighed
        // by their widths.
        let mut integral = 0.0;
        if lo < 0.0 {
            integral += -lo * inside(lo, 0.0);
        }
        let (start, end) = (lo.max(0.0), hi.min(self.d_max));
        if end > start {
            integral += (end - start) * across(start, end);
        }
        integral / (hi - lo)
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
            sweep: surfaces.sweep,
        }
    }

    fn range(&self) -> f64 {
        self.d_max
    }

    #[inline(always)]
    fn sweeps(&self) -> bool {
        self.sweep > 0.0
    }

    /// `D_max`, and with a sweep the half of the gap a step sweeps beyond it.
    #[inline(always)]
    fn reach(&self, rate: f64) -> f64 {
        self.d_max + 0.5 * (rate * self.sweep).abs()
    }

    /// The gap opens at `(V_i − V_j)·n`: the spin moves the contact
    /// points across the normal, not along it.
    #[inline(always)]
    fn attraction(&self, touch: &Touch<D>) -> f64 {
        if self.sweep > 0.0 {
            let rate = touch.velocity.dot(&touch.normal);
            self.swept(touch.r_eff, -touch.overlap, rate)
        } else {
            self.at(touch.r_eff, -touch.overlap)
        }
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
            sweep: 0.0,
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

    /// The mean of the attraction over `[lo, hi]` by the midpoint rule on
    /// a fine grid: an independent reading of what `swept` integrates.
    fn quadrature(law: &VanDerWaals, r_eff: f64, lo: f64, hi: f64) -> f64 {
        let n = 200_000;
        let h = (hi - lo) / n as f64;
        let sum: f64 = (0..n)
            .map(|k| law.at(r_eff, lo + (k as f64 + 0.5) * h))
            .sum();
        sum / n as f64
    }

    #[test]
    fn the_swept_attraction_is_the_mean_over_the_gaps_a_step_sweeps() {
        let (d_min, d_max, r_eff, dt) = (1.65e-10, 1e-6, 2.5e-4, 1e-7);
        for fades in [true, false] {
            let law = VanDerWaals {
                limits: Limits::Net,
                fades_in_contact: fades,
                hamaker: VanDerWaals::hamaker_of(0.05, d_min),
                d_min,
                d_max,
                sweep: dt,
            };
            // At rest the pair feels the law at its gap.
            for gap in [-3e-9, 0.0, 2e-10, 5e-7] {
                assert_eq!(law.swept(r_eff, gap, 0.0), law.at(r_eff, gap));
            }
            // Windows within the gap, across contact, in contact, across
            // D_max and beyond it; closing and opening alike.
            let cases = [
                (4e-8, 1e-3),
                (1e-10, 1e-2),
                (-2e-9, 5e-2),
                (-3e-9, 1e-2),
                (9.998e-7, 1e-2),
                (1.2e-6, 1e-3),
            ];
            for (gap, speed) in cases {
                for rate in [speed, -speed] {
                    let half = 0.5 * speed * dt;
                    let want = quadrature(&law, r_eff, gap - half, gap + half);
                    let got = law.swept(r_eff, gap, rate);
                    let tolerance = 1e-5 * want.abs().max(1e-3 * law.at(r_eff, 0.0));
                    assert!(
                        (got - want).abs() <= tolerance,
                        "fades {fades}, gap {gap:e}, rate {rate}: {got:e} against {want:e}"
                    );
                }
            }
            // A window from an overlap of 1 nm to past D_max: the mean
            // times the width is the work of bringing the pair from out of
            // range to that overlap (`work`, integrated in closed form).
            let (depth, speed) = (1e-9, 30.0);
            let half = 0.5 * speed * dt;
            let gap = half - depth;
            let impulse = law.swept(r_eff, gap, -speed) * 2.0 * half;
            let work = CohesionLaw::<3>::work(&law, r_eff, depth);
            assert!(
                (impulse / work - 1.0).abs() < 1e-9,
                "fades {fades}: {impulse:e} against {work:e}"
            );
        }
    }
}

//! The normal force of Lee & Herrmann's eq. (2a).

use super::{NormalLaw, Touch};
use crate::dim::{Dim, Space};

/// `F_n = k_n δ^{3/2} − γ_n m_e (v·n)`, eq. (2a) of Lee & Herrmann.
///
/// With `FLOOR = true` the force is never attractive: at the end of a damped
/// contact the raw law pulls the grains together for a moment, which no dry
/// grain does. The paper's raw law is `FLOOR = false`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzDamped<const FLOOR: bool> {
    /// Elastic constant, dyn/cm^{3/2}.
    pub k_n: f64,
    /// Normal damping rate, 1/s.
    pub gamma_n: f64,
}

impl<const FLOOR: bool> HertzDamped<FLOOR> {
    /// The force for an overlap, a normal relative speed `v·n` and an effective mass.
    #[inline(always)]
    pub fn magnitude(&self, overlap: f64, normal_speed: f64, m_eff: f64) -> f64 {
        let f = self.k_n * overlap * overlap.sqrt() - self.gamma_n * m_eff * normal_speed;
        if FLOOR {
            f.max(0.0)
        } else {
            f
        }
    }
}

impl<const FLOOR: bool> NormalLaw for HertzDamped<FLOOR> {
    #[inline(always)]
    fn force<const D: usize>(&self, touch: &Touch<D>, normal_speed: f64) -> f64
    where
        Dim<D>: Space<D>,
    {
        self.magnitude(touch.overlap, normal_speed, touch.m_eff)
    }

    fn elastic_energy(&self, overlap: f64, _r_eff: f64) -> f64 {
        0.4 * self.k_n * overlap * overlap * overlap.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hertz_force_grows_as_overlap_to_the_three_halves() {
        let hertz = HertzDamped::<true> {
            k_n: 1e6,
            gamma_n: 0.0,
        };
        let f1 = hertz.magnitude(1e-4, 0.0, 1.0);
        let f2 = hertz.magnitude(4e-4, 0.0, 1.0);
        assert!((f2 / f1 - 8.0).abs() < 1e-12);
        assert!((f1 - 1e6 * 1e-6).abs() < 1e-12);
    }

    #[test]
    fn floored_normal_force_never_pulls_but_the_raw_law_does() {
        let floored = HertzDamped::<true> {
            k_n: 1e6,
            gamma_n: 500.0,
        };
        let raw = HertzDamped::<false> {
            k_n: 1e6,
            gamma_n: 500.0,
        };
        // separating fast at a tiny overlap: damping dominates
        assert_eq!(floored.magnitude(1e-8, 10.0, 1e-3), 0.0);
        assert!(raw.magnitude(1e-8, 10.0, 1e-3) < 0.0);
    }
}

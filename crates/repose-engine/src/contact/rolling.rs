//! Rolling resistance: the elastic–plastic spring–dashpot-free model of
//! Elekes & Parteli's eq. (15), LIGGGHTS's `epsd2`.

use super::{Angular, RollingLaw, Touch};
use crate::dim::{Dim, Space};
use serde::{Deserialize, Serialize};

/// A torque that builds up with the relative rolling of a pair,
/// `M_r ← M_r − k_r ω_rel Δt` with `k_r = k_t √δ R_eff²`, and slips at
/// `|M_r| = μ_r R_eff F_n`. The relative angular velocity `ω_i − ω_j` has
/// its twist (the part along the normal) removed: a point contact resists
/// rolling but not spinning about its normal, and has no dashpot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Epsd2 {
    /// `4G / (2 − ν)`, Pa: the tangential spring's modulus, whose
    /// stiffness `k_t √δ` the rolling spring takes times `R_eff²`.
    pub modulus: f64,
    /// Rolling friction coefficient `μ_r`.
    pub mu: f64,
}

/// The rolling torque held by one contact (on grain `i`), N·m.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RollingSpring<A> {
    pub torque: A,
}

impl<const D: usize> RollingLaw<D> for Epsd2
where
    Dim<D>: Space<D>,
{
    const ACTIVE: bool = true;
    type History = RollingSpring<Angular<D>>;

    #[inline(always)]
    fn torque(
        &self,
        history: &mut Self::History,
        touch: &Touch<D>,
        normal_force: f64,
        dt: f64,
    ) -> Angular<D> {
        let n = &touch.normal;
        let r = touch.r_eff;
        let k = self.modulus * super::viscoelastic::contact_radius(touch) * r * r;
        let rolling = <Dim<D> as Space<D>>::without_twist(touch.omega_i - touch.omega_j, n);
        let held = <Dim<D> as Space<D>>::without_twist(history.torque, n);
        let m = held + rolling * (-k * dt);
        let limit = self.mu * r * normal_force;
        let size2 = <Dim<D> as Space<D>>::angular_norm_squared(m);
        history.torque = if size2 > limit * limit {
            m * (limit / size2.sqrt())
        } else {
            m
        };
        history.torque
    }

    /// The torque on the other grain is the opposite.
    fn flip(history: &mut Self::History) {
        history.torque = history.torque * -1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::Vector;

    #[test]
    fn rolling_torque_builds_up_opposes_the_rolling_and_slips_at_the_limit() {
        let law = Epsd2 {
            modulus: 1e9,
            mu: 0.1,
        };
        let mut t = Touch::<3> {
            normal: Vector::<3>::new(0.0, 0.0, 1.0),
            overlap: 1e-6,
            velocity: Vector::<3>::zeros(),
            m_eff: 1e-6,
            r_eff: 5e-4,
            radius_i: 5e-4,
            radius_j: 0.0,
            omega_i: Vector::<3>::new(2.0, 0.0, 7.0),
            omega_j: Vector::<3>::zeros(),
        };
        let mut h = RollingSpring::default();
        let m = law.torque(&mut h, &t, 1.0, 1e-6);
        let k = 1e9 * (5e-4f64 * 1e-6).sqrt() * 25e-8;
        // only the rolling part (x) is resisted, the twist (z) is free
        assert!((m.x + k * 2.0 * 1e-6).abs() < 1e-9 * k * 2e-6, "{m:?}");
        assert_eq!(m.z, 0.0);
        t.omega_i = Vector::<3>::new(1e9, 0.0, 0.0);
        let m = law.torque(&mut h, &t, 1.0, 1e-6);
        assert!((m.norm() - 0.1 * 5e-4).abs() < 1e-15);
    }
}

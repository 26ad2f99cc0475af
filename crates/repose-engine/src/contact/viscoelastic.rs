//! Viscoelastic Hertz–Mindlin contacts of Elekes & Parteli (2021), eqs.
//! (10) and (11): stiffness and damping that grow with the contact area,
//! `√(R_eff δ)`, so a collision's restitution depends on its speed as it
//! does for real viscoelastic spheres.

use super::spring::{self, TangentialSpring};
use super::{NormalLaw, Shear, TangentialLaw, Touch};
use crate::dim::{Dim, Space};

/// `F_n = max(0, k_n δ^{3/2} + (3/2) A_n k_n √δ δ̇)` with
/// `k_n = (2Y / (3(1 − ν²))) √R_eff` (eq. 10): never attractive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViscoelasticHertz {
    /// `2Y / (3(1 − ν²))`, Pa; times `√R_eff` it is `k_n`.
    pub modulus: f64,
    /// The dissipative constant `A_n`, s.
    pub damping: f64,
}

impl ViscoelasticHertz {
    /// `k_n` of a pair with effective radius `r_eff`, Pa·m^{1/2}.
    #[inline(always)]
    pub fn stiffness(&self, r_eff: f64) -> f64 {
        self.modulus * r_eff.sqrt()
    }
}

impl NormalLaw for ViscoelasticHertz {
    #[inline(always)]
    fn force<const D: usize>(&self, touch: &Touch<D>, normal_speed: f64) -> f64
    where
        Dim<D>: Space<D>,
    {
        // The overlap grows at δ̇ = −v·n (n points from j to i, v = V_i − V_j).
        // k_n √δ = modulus √(R_eff δ): the contact radius every component shares.
        let delta = touch.overlap;
        let k = self.modulus * contact_radius(touch);
        (k * (delta - 1.5 * self.damping * normal_speed)).max(0.0)
    }

    fn elastic_energy(&self, overlap: f64, r_eff: f64) -> f64 {
        0.4 * self.stiffness(r_eff) * overlap * overlap * overlap.sqrt()
    }
}

/// `√(R_eff δ)`, the radius of the contact area (up to a factor): the
/// stiffness of every component grows with it. Written once so that the
/// components of a law share one square root.
#[inline(always)]
pub fn contact_radius<const D: usize>(touch: &Touch<D>) -> f64
where
    Dim<D>: Space<D>,
{
    (touch.r_eff * touch.overlap.max(0.0)).sqrt()
}

/// How the Coulomb limit caps the tangential force while a contact slides.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cap {
    /// Spring and damper together (the paper's eq. 11).
    Total,
    /// The spring alone, the damper dropped while sliding (LIGGGHTS).
    Spring,
}

/// Cundall–Strack tangential spring with Mindlin's stiffness, eq. (11):
/// the trial force `F_t* = −(k_t √δ ξ + A_t √δ v_t)` with
/// `k_t = 4G √R_eff / (2 − ν)` and `A_t = (3/2) A_n k_n`, capped at
/// `μ_s F_n`. The displacement `ξ` follows the tangent plane as the pair
/// turns and, while the contact slides, is set back so that the trial force
/// equals the cap (Luding 2008).
///
/// [`Cap::Total`] caps spring and damper together (the paper);
/// [`Cap::Spring`] caps the spring alone and drops the damper while
/// sliding (LIGGGHTS). The choice is a run-time value: a branch that goes
/// the same way for a whole run costs nothing measurable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MindlinSpring {
    /// `4G / (2 − ν)`, Pa; times `√(R_eff δ)` it is the spring's stiffness.
    pub modulus: f64,
    /// `(3/2) A_n · 2Y / (3(1 − ν²))`, Pa·s; times `√(R_eff δ)` it is the
    /// damping coefficient.
    pub damping: f64,
    /// Sliding friction coefficient `μ_s`.
    pub mu: f64,
    pub cap: Cap,
}

impl<const D: usize> TangentialLaw<D> for MindlinSpring
where
    Dim<D>: Space<D>,
{
    /// The tangential displacement `ξ`, m.
    type History = TangentialSpring<Shear<D>>;

    #[inline(always)]
    fn force(
        &self,
        history: &mut Self::History,
        tangential_velocity: Shear<D>,
        touch: &Touch<D>,
        normal_force: f64,
        dt: f64,
    ) -> Shear<D> {
        let a = contact_radius(touch);
        let (k, c) = (self.modulus * a, self.damping * a);
        let xi = spring::stretched(history, tangential_velocity, touch, dt);
        let spring = xi * -k;
        let damper = tangential_velocity * -c;
        let limit = self.mu * normal_force;
        let over = |f: Shear<D>| {
            let size2 = <Dim<D> as Space<D>>::magnitude_squared(f);
            (size2 > limit * limit && k > 0.0).then(|| limit / size2.sqrt())
        };
        if self.cap == Cap::Total {
            let trial = spring + damper;
            if let Some(scale) = over(trial) {
                let capped = trial * scale;
                // ξ such that −(k ξ + c v_t) is exactly the capped force.
                history.displacement = (capped - damper) * (-1.0 / k);
                return capped;
            }
            history.displacement = xi;
            trial
        } else {
            if let Some(scale) = over(spring) {
                let capped = spring * scale;
                history.displacement = capped * (-1.0 / k);
                return capped;
            }
            history.displacement = xi;
            spring + damper
        }
    }

    fn elastic_energy(&self, history: &Self::History, touch: &Touch<D>) -> f64 {
        spring::energy(history, self.modulus * contact_radius(touch))
    }

    fn flip(history: &mut Self::History) {
        spring::flip(history);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::Vector;

    fn touch(overlap: f64, velocity: Vector<3>) -> Touch<3> {
        Touch {
            normal: Vector::<3>::new(0.0, 0.0, 1.0),
            overlap,
            velocity,
            m_eff: 1e-6,
            r_eff: 2.5e-4,
            radius_i: 5e-4,
            radius_j: 5e-4,
            omega_i: Vector::<3>::zeros(),
            omega_j: Vector::<3>::zeros(),
        }
    }

    #[test]
    fn normal_force_is_hertz_at_rest_and_damped_in_motion() {
        let law = ViscoelasticHertz {
            modulus: 1e9,
            damping: 1e-5,
        };
        let t = touch(1e-6, Vector::<3>::zeros());
        let k = 1e9 * 2.5e-4f64.sqrt();
        let at_rest = law.force(&t, 0.0);
        assert!((at_rest - k * 1e-9).abs() < 1e-12 * at_rest);
        // approaching (v·n < 0) adds (3/2) A_n k_n √δ δ̇
        let approaching = law.force(&t, -0.1);
        let extra = 1.5 * 1e-5 * k * 1e-3 * 0.1;
        assert!((approaching - at_rest - extra).abs() < 1e-9 * approaching);
        // separating fast: the damper would pull, the law never does
        assert_eq!(law.force(&t, 10.0), 0.0);
    }

    #[test]
    fn both_caps_hold_the_coulomb_limit_and_reset_the_spring() {
        let slide = Vector::<3>::new(1.0, 0.0, 0.0);
        let t = touch(1e-6, slide);
        for cap in [Cap::Total, Cap::Spring] {
            let mut h = TangentialSpring::default();
            let law = MindlinSpring {
                modulus: 1e9,
                damping: 1e3,
                mu: 0.5,
                cap,
            };
            let f = law.force(&mut h, slide, &t, 1e-3, 1e-6);
            assert!((f.norm() - 0.5e-3).abs() < 1e-15, "{f:?}");
            assert!(f.x < 0.0);
            // the next step with the same sliding speed starts from the cap
            let area = (2.5e-4f64 * 1e-6).sqrt();
            let spring = -1e9 * area * h.displacement.x;
            let expected = if cap == Cap::Total {
                -0.5e-3 + 1e3 * area
            } else {
                -0.5e-3
            };
            assert!((spring - expected).abs() < 1e-12, "{spring} {expected}");
        }
    }
}

//! Tangential forces of Lee & Herrmann's eq. (2b).

use super::spring::{self, TangentialSpring};
use super::{Shear, TangentialLaw, Touch};
use crate::dim::{Dim, Space};

/// No tangential force at all.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Frictionless;

impl<const D: usize> TangentialLaw<D> for Frictionless
where
    Dim<D>: Space<D>,
{
    type History = ();

    #[inline(always)]
    fn force(&self, _: &mut (), _: Shear<D>, _: &Touch<D>, _: f64, _: f64) -> Shear<D> {
        Default::default()
    }

    fn elastic_energy(&self, _history: &(), _touch: &Touch<D>) -> f64 {
        0.0
    }

    fn flip(_: &mut ()) {}
}

/// Cundall–Strack static friction, eq. (2b) of Lee & Herrmann:
/// `F_s = −γ_s m_e (v·s) − sign(δs) min(k_s |δs|, μ F_n)`, where `δs` is the
/// total shear displacement since the contact began.
///
/// With `TRUNCATE = false` (the paper's form) the spring keeps stretching
/// while the contact slides, so a sliding contact must first travel back the
/// whole excess before it sticks again. With `TRUNCATE = true` (the usual
/// modern choice) the spring is cut to the Coulomb length `μ F_n / k_s`
/// whenever it exceeds it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CundallStrack<const TRUNCATE: bool> {
    /// Shear spring constant, dyn/cm.
    pub k_s: f64,
    /// Shear damping rate, 1/s.
    pub gamma_s: f64,
    /// Coulomb friction coefficient.
    pub mu: f64,
}

impl<const D: usize, const TRUNCATE: bool> TangentialLaw<D> for CundallStrack<TRUNCATE>
where
    Dim<D>: Space<D>,
{
    /// The Cundall–Strack spring: the total shear displacement, cm.
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
        let ds = spring::stretched(history, tangential_velocity, touch, dt);
        let stretch = <Dim<D> as Space<D>>::magnitude(ds);
        // The Coulomb limit: an attractive (raw-law) normal force gives no grip.
        let limit = self.mu * normal_force.max(0.0);
        let spring = self.k_s * stretch;
        let static_force = if stretch > 0.0 {
            ds * (-spring.min(limit) / stretch)
        } else {
            ds
        };
        history.displacement = if TRUNCATE && spring > limit {
            ds * (limit / spring)
        } else {
            ds
        };
        static_force + tangential_velocity * (-self.gamma_s * touch.m_eff)
    }

    fn elastic_energy(&self, history: &Self::History, _touch: &Touch<D>) -> f64 {
        spring::energy(history, self.k_s)
    }

    fn flip(history: &mut Self::History) {
        spring::flip(history);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::tests::touch;
    use crate::contact::{ContactLaw, HertzDamped, Pairwise};
    use crate::dim::Vector;

    fn law<const T: bool>() -> Pairwise<HertzDamped<true>, CundallStrack<T>> {
        Pairwise::new(
            HertzDamped {
                k_n: 1e6,
                gamma_n: 500.0,
            },
            CundallStrack {
                k_s: 1e4,
                gamma_s: 5.0,
                mu: 0.2,
            },
        )
    }

    #[test]
    fn shear_spring_sticks_below_the_coulomb_limit() {
        // n = +y, s = +x: sliding i to the right stretches the spring, which pulls back (−x).
        let law = law::<false>();
        let mut h = Default::default();
        let f = law
            .force(&touch(1e-4, Vector::<2>::new(1e-3, 0.0)), &mut h, 1e-3)
            .force;
        assert!((h.0.displacement - 1e-6).abs() < 1e-18);
        let expected = -1e4 * 1e-6 - 5.0 * 1e-3 * 1e-3;
        assert!((f.x - expected).abs() < 1e-12, "{f:?}");
        assert!((f.y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn paper_spring_keeps_stretching_while_truncated_spring_is_cut_at_coulomb() {
        let big = Vector::<2>::new(1.0, 0.0);
        let mut paper = Default::default();
        let mut cut = Default::default();
        let fp = law::<false>()
            .force(&touch(1e-4, big), &mut paper, 1e-3)
            .force;
        let fc = law::<true>().force(&touch(1e-4, big), &mut cut, 1e-3).force;
        // both forces are capped at mu F_n = 0.2 dyn (plus the same damping)
        assert!((fp.x - fc.x).abs() < 1e-12);
        assert!((fp.x - (-0.2 - 5.0 * 1e-3 * 1.0)).abs() < 1e-12);
        assert!((paper.0.displacement - 1e-3).abs() < 1e-15);
        assert!((cut.0.displacement - 0.2 / 1e4).abs() < 1e-15);
    }
}

//! Contact laws, built from components.
//!
//! A contact law is a [`Pairwise`] combination of a [`NormalLaw`] and a
//! [`TangentialLaw`]. Each component is a type, and each choice a scene can
//! make (floor the normal force or not, truncate the shear spring or not, no
//! friction at all) is a different type, so the force loop is compiled once
//! per combination and a scene pays only for what it switches on: a
//! frictionless run carries no shear history (`History = ()`) and computes no
//! tangential velocity.
//!
//! Sign conventions follow Lee & Herrmann (1993): for grains `i` and `j`,
//! `n` is the unit vector from `j` to `i`, `v = V_i − V_j`, and the returned
//! force acts on `i` (its opposite acts on `j`). A wall is a grain `j` of zero
//! radius and infinite mass, so `m_e = m_i`.

use crate::dim::{Dim, Space, Vector};
use serde::{Deserialize, Serialize};
use std::fmt::Debug;

/// Geometry and kinematics of one touching pair, seen from grain `i`.
#[derive(Debug, Clone, Copy)]
pub struct Touch<const D: usize> {
    /// Unit normal from `j` to `i`.
    pub normal: Vector<D>,
    /// Overlap `a_i + a_j − r` (> 0 while touching), cm.
    pub overlap: f64,
    /// Relative velocity `V_i − V_j`, cm/s.
    pub velocity: Vector<D>,
    /// Effective mass `m_i m_j / (m_i + m_j)`, g.
    pub m_eff: f64,
}

/// The normal-force component: repulsion plus dissipation along `n`.
pub trait NormalLaw: Copy + Send + Sync + Debug {
    /// Normal force (dyn) for the overlap (cm) and the normal relative speed `v·n` (cm/s).
    fn force(&self, overlap: f64, normal_speed: f64, m_eff: f64) -> f64;
    /// Elastic energy stored at this overlap (erg).
    fn elastic_energy(&self, overlap: f64) -> f64;
}

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

impl<const FLOOR: bool> NormalLaw for HertzDamped<FLOOR> {
    #[inline(always)]
    fn force(&self, overlap: f64, normal_speed: f64, m_eff: f64) -> f64 {
        let f = self.k_n * overlap * overlap.sqrt() - self.gamma_n * m_eff * normal_speed;
        if FLOOR {
            f.max(0.0)
        } else {
            f
        }
    }

    fn elastic_energy(&self, overlap: f64) -> f64 {
        0.4 * self.k_n * overlap * overlap * overlap.sqrt()
    }
}

/// The tangential component, with whatever per-contact memory it needs.
pub trait TangentialLaw<const D: usize>: Copy + Send + Sync + Debug
where
    Dim<D>: Space<D>,
{
    /// Per-contact state; `Default` is a fresh contact.
    type History: Copy + Default + Debug + PartialEq + Send + Sync;

    /// Advances the history by one step of length `dt` and returns the
    /// tangential force on `i`, given the tangential relative velocity and the
    /// normal force of this step.
    fn force(
        &self,
        history: &mut Self::History,
        tangential_velocity: <Dim<D> as Space<D>>::Shear,
        normal: &Vector<D>,
        normal_force: f64,
        m_eff: f64,
        dt: f64,
    ) -> <Dim<D> as Space<D>>::Shear;

    /// Energy stored in the contact's spring (erg).
    fn elastic_energy(&self, history: &Self::History) -> f64;
}

/// No tangential force at all.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Frictionless;

impl<const D: usize> TangentialLaw<D> for Frictionless
where
    Dim<D>: Space<D>,
{
    type History = ();

    #[inline(always)]
    fn force(
        &self,
        _history: &mut (),
        _tangential_velocity: <Dim<D> as Space<D>>::Shear,
        _normal: &Vector<D>,
        _normal_force: f64,
        _m_eff: f64,
        _dt: f64,
    ) -> <Dim<D> as Space<D>>::Shear {
        Default::default()
    }

    fn elastic_energy(&self, _history: &()) -> f64 {
        0.0
    }
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

/// The Cundall–Strack spring of one contact: total shear displacement, cm.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShearSpring<S> {
    pub displacement: S,
}

impl<const D: usize, const TRUNCATE: bool> TangentialLaw<D> for CundallStrack<TRUNCATE>
where
    Dim<D>: Space<D>,
{
    type History = ShearSpring<<Dim<D> as Space<D>>::Shear>;

    #[inline(always)]
    fn force(
        &self,
        history: &mut Self::History,
        tangential_velocity: <Dim<D> as Space<D>>::Shear,
        normal: &Vector<D>,
        normal_force: f64,
        m_eff: f64,
        dt: f64,
    ) -> <Dim<D> as Space<D>>::Shear {
        let ds = <Dim<D> as Space<D>>::follow_normal(history.displacement, normal)
            + tangential_velocity * dt;
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
        static_force + tangential_velocity * (-self.gamma_s * m_eff)
    }

    fn elastic_energy(&self, history: &Self::History) -> f64 {
        let s = <Dim<D> as Space<D>>::magnitude(history.displacement);
        0.5 * self.k_s * s * s
    }
}

/// A full contact law: force on `i` and per-contact history.
pub trait ContactLaw<const D: usize>: Copy + Send + Sync + Debug
where
    Dim<D>: Space<D>,
{
    type History: Copy + Default + Debug + PartialEq + Send + Sync;

    fn force(&self, touch: &Touch<D>, history: &mut Self::History, dt: f64) -> Vector<D>;

    /// Elastic energy held by one contact (erg).
    fn elastic_energy(&self, overlap: f64, history: &Self::History) -> f64;
}

/// A normal law and a tangential law acting together.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pairwise<N, T> {
    pub normal: N,
    pub tangential: T,
}

impl<const D: usize, N: NormalLaw, T: TangentialLaw<D>> ContactLaw<D> for Pairwise<N, T>
where
    Dim<D>: Space<D>,
{
    type History = T::History;

    #[inline(always)]
    fn force(&self, touch: &Touch<D>, history: &mut T::History, dt: f64) -> Vector<D> {
        let vn = touch.velocity.dot(&touch.normal);
        let fn_ = self.normal.force(touch.overlap, vn, touch.m_eff);
        let vt = <Dim<D> as Space<D>>::tangential(&touch.velocity, &touch.normal);
        let ft = self
            .tangential
            .force(history, vt, &touch.normal, fn_, touch.m_eff, dt);
        touch.normal * fn_ + <Dim<D> as Space<D>>::to_vector(ft, &touch.normal)
    }

    fn elastic_energy(&self, overlap: f64, history: &T::History) -> f64 {
        self.normal.elastic_energy(overlap) + self.tangential.elastic_energy(history)
    }
}

/// How the normal force behaves when damping would make it attractive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum NormalForce {
    /// `F_n` floored at zero: contacts only push.
    #[default]
    Floored,
    /// The paper's raw expression, which may pull briefly at separation.
    Raw,
}

/// What the shear spring does while a contact slides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShearSpringMode {
    /// The paper's form: the spring keeps growing while the contact slips.
    #[default]
    Paper,
    /// The spring is cut back to the Coulomb limit while it slips.
    Truncated,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law<const T: bool>() -> Pairwise<HertzDamped<true>, CundallStrack<T>> {
        Pairwise {
            normal: HertzDamped {
                k_n: 1e6,
                gamma_n: 500.0,
            },
            tangential: CundallStrack {
                k_s: 1e4,
                gamma_s: 5.0,
                mu: 0.2,
            },
        }
    }

    fn touch(overlap: f64, velocity: Vector<2>) -> Touch<2> {
        Touch {
            normal: Vector::<2>::new(0.0, 1.0),
            overlap,
            velocity,
            m_eff: 1e-3,
        }
    }

    #[test]
    fn hertz_force_grows_as_overlap_to_the_three_halves() {
        let hertz = HertzDamped::<true> {
            k_n: 1e6,
            gamma_n: 0.0,
        };
        let f1 = hertz.force(1e-4, 0.0, 1.0);
        let f2 = hertz.force(4e-4, 0.0, 1.0);
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
        assert_eq!(floored.force(1e-8, 10.0, 1e-3), 0.0);
        assert!(raw.force(1e-8, 10.0, 1e-3) < 0.0);
    }

    #[test]
    fn shear_spring_sticks_below_the_coulomb_limit() {
        // n = +y, s = +x: sliding i to the right stretches the spring, which pulls back (−x).
        let law = law::<false>();
        let mut h = ShearSpring::default();
        let f = law.force(&touch(1e-4, Vector::<2>::new(1e-3, 0.0)), &mut h, 1e-3);
        assert!((h.displacement - 1e-6).abs() < 1e-18);
        let expected = -1e4 * 1e-6 - 5.0 * 1e-3 * 1e-3;
        assert!((f.x - expected).abs() < 1e-12, "{f:?}");
        assert!((f.y - 1.0).abs() < 1e-12);
    }

    #[test]
    fn paper_spring_keeps_stretching_while_truncated_spring_is_cut_at_coulomb() {
        let big = Vector::<2>::new(1.0, 0.0);
        let mut paper = ShearSpring::default();
        let mut cut = ShearSpring::default();
        let fp = law::<false>().force(&touch(1e-4, big), &mut paper, 1e-3);
        let fc = law::<true>().force(&touch(1e-4, big), &mut cut, 1e-3);
        // both forces are capped at mu F_n = 0.2 dyn (plus the same damping)
        assert!((fp.x - fc.x).abs() < 1e-12);
        assert!((fp.x - (-0.2 - 5.0 * 1e-3 * 1.0)).abs() < 1e-12);
        assert!((paper.displacement - 1e-3).abs() < 1e-15);
        assert!((cut.displacement - 0.2 / 1e4).abs() < 1e-15);
    }
}

//! Contact laws, built from components.
//!
//! A contact law is a [`Pairwise`] combination of up to four components: a
//! [`NormalLaw`], a [`TangentialLaw`], a [`RollingLaw`] and a
//! [`CohesionLaw`], and a switch for rotation. Each choice a scene can make
//! (floor the normal force or not, truncate the shear spring or not, no
//! friction at all, rolling resistance, cohesion) is a different type, so the
//! force loop is compiled once per combination and a scene pays only for what
//! it switches on: a frictionless run carries no shear history and computes
//! no tangential velocity, a law without rotation never reads an angular
//! velocity, and a law without cohesion never looks beyond touching pairs.
//!
//! Sign conventions follow Lee & Herrmann (1993): for grains `i` and `j`,
//! `n` is the unit vector from `j` to `i`, `v = V_i − V_j`, and the returned
//! force acts on `i` (its opposite acts on `j`). A wall is a grain `j` of zero
//! radius, infinite mass and no rotation, so `m_e = m_i`.

mod cohesion;
mod friction;
mod hertz;
pub mod restitution;
mod rolling;
mod spring;
mod viscoelastic;

pub use cohesion::{Cohesive, Limits, VanDerWaals};
pub use friction::{CundallStrack, Frictionless};
pub use hertz::HertzDamped;
pub use rolling::{Epsd2, RollingSpring};
pub use spring::TangentialSpring;
pub use viscoelastic::{Cap, MindlinSpring, ViscoelasticHertz};

use crate::dim::{Dim, Space, Vector};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;

type Angular<const D: usize> = <Dim<D> as Space<D>>::Angular;
type Shear<const D: usize> = <Dim<D> as Space<D>>::Shear;

/// Geometry and kinematics of one pair (touching, or across a gap for
/// laws with a range), seen from grain `i`.
#[derive(Debug, Clone, Copy)]
pub struct Touch<const D: usize>
where
    Dim<D>: Space<D>,
{
    /// Unit normal from `j` to `i`.
    pub normal: Vector<D>,
    /// Overlap `a_i + a_j − r`: positive while touching, minus the gap across one.
    pub overlap: f64,
    /// Relative velocity of the centres, `V_i − V_j`.
    pub velocity: Vector<D>,
    /// Effective mass `m_i m_j / (m_i + m_j)` (`m_i` against a wall).
    pub m_eff: f64,
    /// Effective radius `a_i a_j / (a_i + a_j)` (`a_i` against a wall).
    pub r_eff: f64,
    /// Radius of `i`.
    pub radius_i: f64,
    /// Radius of `j` (0 for a wall).
    pub radius_j: f64,
    /// Angular velocity of `i` (zero unless the grains rotate).
    pub omega_i: Angular<D>,
    /// Angular velocity of `j` (zero for a wall or without rotation).
    pub omega_j: Angular<D>,
}

impl<const D: usize> Touch<D>
where
    Dim<D>: Space<D>,
{
    /// Distances from the centres of `i` and `j` to the contact point
    /// (each radius less half the overlap).
    #[inline(always)]
    pub fn levers(&self) -> (f64, f64) {
        let half = 0.5 * self.overlap;
        (self.radius_i - half, (self.radius_j - half).max(0.0))
    }
}

/// What a contact does to its two grains.
#[derive(Debug, Clone, Copy)]
pub struct Response<const D: usize>
where
    Dim<D>: Space<D>,
{
    /// Force on `i`; `j` feels its opposite.
    pub force: Vector<D>,
    /// Torque on `i`.
    pub torque_i: Angular<D>,
    /// Torque on `j`.
    pub torque_j: Angular<D>,
}

impl<const D: usize> Response<D>
where
    Dim<D>: Space<D>,
{
    #[inline(always)]
    pub fn force(force: Vector<D>) -> Self {
        Response {
            force,
            torque_i: Default::default(),
            torque_j: Default::default(),
        }
    }
}

/// The normal-force component: repulsion plus dissipation along `n`.
pub trait NormalLaw: Copy + Send + Sync + Debug {
    /// Normal force for the pair, given the normal relative speed `v·n`.
    fn force<const D: usize>(&self, touch: &Touch<D>, normal_speed: f64) -> f64
    where
        Dim<D>: Space<D>;
    /// Elastic energy stored at this overlap, for a pair of effective radius `r_eff`.
    fn elastic_energy(&self, overlap: f64, r_eff: f64) -> f64;
}

/// The tangential component, with whatever per-contact memory it needs.
pub trait TangentialLaw<const D: usize>: Copy + Send + Sync + Debug
where
    Dim<D>: Space<D>,
{
    /// Per-contact state; `Default` is a fresh contact.
    type History: Copy + Default + Debug + PartialEq + Send + Sync + Serialize + DeserializeOwned;

    /// Advances the history by one step of length `dt` and returns the
    /// tangential force on `i`, given the tangential relative velocity of
    /// the contact point and the normal force of this step.
    fn force(
        &self,
        history: &mut Self::History,
        tangential_velocity: Shear<D>,
        touch: &Touch<D>,
        normal_force: f64,
        dt: f64,
    ) -> Shear<D>;

    /// Energy stored in the contact's spring.
    fn elastic_energy(&self, history: &Self::History, touch: &Touch<D>) -> f64;

    /// The history seen from the other grain of the pair.
    fn flip(history: &mut Self::History);
}

/// Resistance to rolling: a torque opposing the relative rotation.
pub trait RollingLaw<const D: usize>: Copy + Send + Sync + Debug
where
    Dim<D>: Space<D>,
{
    /// Whether this component acts at all (false for [`NoRolling`]).
    const ACTIVE: bool;
    /// Per-contact state; `Default` is a fresh contact.
    type History: Copy + Default + Debug + PartialEq + Send + Sync + Serialize + DeserializeOwned;

    /// Advances the history and returns the rolling torque on `i` (`j`
    /// feels its opposite).
    fn torque(
        &self,
        history: &mut Self::History,
        touch: &Touch<D>,
        normal_force: f64,
        dt: f64,
    ) -> Angular<D>;

    /// The history seen from the other grain of the pair.
    fn flip(history: &mut Self::History);
}

/// Attraction between grains, in contact and across a gap.
pub trait CohesionLaw<const D: usize>: Copy + Send + Sync + Debug
where
    Dim<D>: Space<D>,
{
    /// Whether this component acts at all (false for [`NoCohesion`]).
    const ACTIVE: bool;
    /// The law for a pair of surfaces described by `surfaces`: each law
    /// takes what it needs of them.
    fn of(surfaces: &Cohesive) -> Self;
    /// Largest gap across which the attraction acts.
    fn range(&self) -> f64;

    /// Whether the law averages the attraction over the gaps a pair sweeps
    /// in a step, so that a pair opening at `rate` feels it out to
    /// [`CohesionLaw::reach`] rather than [`CohesionLaw::range`].
    #[inline(always)]
    fn sweeps(&self) -> bool {
        false
    }

    /// The largest gap at which a pair whose gap opens at `rate` feels the
    /// attraction in a step.
    #[inline(always)]
    fn reach(&self, _rate: f64) -> f64 {
        self.range()
    }
    /// Size of the attraction (pulling `i` towards `j`) for this pair.
    fn attraction(&self, touch: &Touch<D>) -> f64;

    /// The attraction of a pair of effective radius `r_eff` just touching
    /// (no gap, no overlap), N: what sets the time an attraction takes to
    /// kick a pair, which bounds the time step of a cohesive scene.
    fn at_contact(&self, r_eff: f64) -> f64;

    /// Work the attraction does on a pair of effective radius `r_eff`
    /// brought from out of its range to an overlap `depth`.
    fn work(&self, r_eff: f64, depth: f64) -> f64;

    /// The normal force that bounds sliding and rolling (the Coulomb and
    /// the rolling limit) for a contact whose repulsive force is `repulsion`
    /// and whose attraction ([`CohesionLaw::attraction`]) is `attraction`:
    /// the repulsion itself unless the law says otherwise.
    #[inline(always)]
    fn limit_load(&self, _attraction: f64, repulsion: f64) -> f64 {
        repulsion
    }
}

/// No rolling resistance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NoRolling;

impl<const D: usize> RollingLaw<D> for NoRolling
where
    Dim<D>: Space<D>,
{
    const ACTIVE: bool = false;
    type History = ();

    #[inline(always)]
    fn torque(&self, _: &mut (), _: &Touch<D>, _: f64, _: f64) -> Angular<D> {
        Default::default()
    }

    fn flip(_: &mut ()) {}
}

/// No cohesion.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NoCohesion;

impl<const D: usize> CohesionLaw<D> for NoCohesion
where
    Dim<D>: Space<D>,
{
    const ACTIVE: bool = false;

    fn of(_: &Cohesive) -> Self {
        NoCohesion
    }

    fn range(&self) -> f64 {
        0.0
    }

    #[inline(always)]
    fn attraction(&self, _: &Touch<D>) -> f64 {
        0.0
    }

    fn at_contact(&self, _: f64) -> f64 {
        0.0
    }

    fn work(&self, _: f64, _: f64) -> f64 {
        0.0
    }
}

/// A full contact law: force and torques on a pair, and per-contact history.
pub trait ContactLaw<const D: usize>: Copy + Send + Sync + Debug
where
    Dim<D>: Space<D>,
{
    type History: Copy + Default + Debug + PartialEq + Send + Sync + Serialize + DeserializeOwned;

    /// Whether the law exerts torques: the grains then carry angular
    /// velocity, and the engine passes it in and integrates it.
    const ROTATES: bool;

    /// Whether the law acts across gaps up to [`ContactLaw::range`]: the
    /// neighbour search then reaches that far, and
    /// [`ContactLaw::gap_force`] is called for pairs that do not touch.
    const ACTS_ACROSS_GAPS: bool;

    /// The response of a touching pair; advances its history by `dt`.
    fn force(&self, touch: &Touch<D>, history: &mut Self::History, dt: f64) -> Response<D>;

    /// The response of a pair separated by a gap within [`ContactLaw::range`]
    /// (`touch.overlap` is minus the gap). Such a pair has no history.
    fn gap_force(&self, touch: &Touch<D>) -> Response<D>;

    /// Largest gap across which the law acts (0 for contact-only laws).
    fn range(&self) -> f64;

    /// Whether a pair beyond [`ContactLaw::range`] may still feel the law
    /// in a step, out to [`ContactLaw::gap_reach`] (an attraction averaged
    /// over the gaps the step sweeps).
    fn sweeps(&self) -> bool;

    /// The largest gap at which a pair whose gap opens at `rate` feels the
    /// law in a step.
    fn gap_reach(&self, rate: f64) -> f64;

    /// Work an attraction does on a pair of effective radius `r_eff`
    /// pulled from out of range to an overlap `depth` (0 without one).
    fn bond_work(&self, r_eff: f64, depth: f64) -> f64;

    /// Elastic energy held by one touching pair.
    fn elastic_energy(&self, touch: &Touch<D>, history: &Self::History) -> f64;

    /// The history of a pair seen from its other grain (when the pair's
    /// grains swap places in the list).
    fn flip(history: &mut Self::History);
}

/// Components acting together: normal, tangential, rolling and cohesion,
/// with or without rotation of the grains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pairwise<N, T, R = NoRolling, C = NoCohesion, const ROTATION: bool = false> {
    pub normal: N,
    pub tangential: T,
    pub rolling: R,
    pub cohesion: C,
}

impl<N, T> Pairwise<N, T> {
    /// A normal and a tangential law without rotation, rolling resistance or cohesion.
    pub fn new(normal: N, tangential: T) -> Self {
        Pairwise {
            normal,
            tangential,
            rolling: NoRolling,
            cohesion: NoCohesion,
        }
    }
}

impl<const D: usize, N, T, R, C, const ROTATION: bool> ContactLaw<D>
    for Pairwise<N, T, R, C, ROTATION>
where
    Dim<D>: Space<D>,
    N: NormalLaw,
    T: TangentialLaw<D>,
    R: RollingLaw<D>,
    C: CohesionLaw<D>,
{
    type History = (T::History, R::History);
    const ROTATES: bool = ROTATION;
    const ACTS_ACROSS_GAPS: bool = C::ACTIVE;

    #[inline(always)]
    fn force(&self, touch: &Touch<D>, history: &mut Self::History, dt: f64) -> Response<D> {
        let n = touch.normal;
        let (lever_i, lever_j) = touch.levers();
        // Velocity of i's contact point relative to j's: the centres'
        // relative velocity less what the rotations add, (a_i ω_i + a_j ω_j) × n.
        let v = if ROTATION {
            let spin = touch.omega_i * lever_i + touch.omega_j * lever_j;
            touch.velocity - <Dim<D> as Space<D>>::spin_velocity(spin, &n)
        } else {
            touch.velocity
        };
        let vn = v.dot(&n);
        let fn_ = self.normal.force(touch, vn);
        let vt = <Dim<D> as Space<D>>::tangential(&v, &n);
        // The attraction, once: the limits may read it, and it pulls.
        let attraction = self.cohesion.attraction(touch);
        let load = self.cohesion.limit_load(attraction, fn_);
        let ft = self.tangential.force(&mut history.0, vt, touch, load, dt);
        let ft = <Dim<D> as Space<D>>::to_vector(ft, &n);
        let mut response = Response::force(n * fn_ + ft);
        if C::ACTIVE {
            response.force -= n * attraction;
        }
        if ROTATION {
            // The tangential force acts at the contact point, −lever_i n from
            // the centre of i; its opposite acts on j at +lever_j n.
            let turn = <Dim<D> as Space<D>>::moment(&n, &ft);
            response.torque_i = turn * -lever_i;
            response.torque_j = turn * -lever_j;
        }
        if R::ACTIVE {
            let m = self.rolling.torque(&mut history.1, touch, load, dt);
            response.torque_i += m;
            response.torque_j += -m;
        }
        response
    }

    #[inline(always)]
    fn gap_force(&self, touch: &Touch<D>) -> Response<D> {
        Response::force(touch.normal * -self.cohesion.attraction(touch))
    }

    fn range(&self) -> f64 {
        if C::ACTIVE {
            self.cohesion.range()
        } else {
            0.0
        }
    }

    #[inline(always)]
    fn sweeps(&self) -> bool {
        C::ACTIVE && self.cohesion.sweeps()
    }

    #[inline(always)]
    fn gap_reach(&self, rate: f64) -> f64 {
        if C::ACTIVE {
            self.cohesion.reach(rate)
        } else {
            0.0
        }
    }

    fn bond_work(&self, r_eff: f64, depth: f64) -> f64 {
        self.cohesion.work(r_eff, depth)
    }

    fn elastic_energy(&self, touch: &Touch<D>, history: &Self::History) -> f64 {
        self.normal.elastic_energy(touch.overlap, touch.r_eff)
            + self.tangential.elastic_energy(&history.0, touch)
    }

    fn flip(history: &mut Self::History) {
        T::flip(&mut history.0);
        R::flip(&mut history.1);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A touch along +y between equal grains (no rotation).
    pub fn touch(overlap: f64, velocity: Vector<2>) -> Touch<2> {
        Touch {
            normal: Vector::<2>::new(0.0, 1.0),
            overlap,
            velocity,
            m_eff: 1e-3,
            r_eff: 0.05,
            radius_i: 0.1,
            radius_j: 0.1,
            omega_i: 0.0,
            omega_j: 0.0,
        }
    }

    #[test]
    fn torques_of_a_rotating_law_follow_the_tangential_force() {
        // Grain i rests on j (n = +y) and slides to +x: friction on i points
        // to −x at i's bottom, which turns i clockwise (negative about z),
        // and j, pushed to +x at its top, clockwise as well.
        let law: Pairwise<HertzDamped<true>, CundallStrack<true>, NoRolling, NoCohesion, true> =
            Pairwise {
                normal: HertzDamped {
                    k_n: 1e6,
                    gamma_n: 0.0,
                },
                tangential: CundallStrack {
                    k_s: 1e4,
                    gamma_s: 0.0,
                    mu: 0.5,
                },
                rolling: NoRolling,
                cohesion: NoCohesion,
            };
        let mut h = Default::default();
        let r = law.force(&touch(1e-4, Vector::<2>::new(1.0, 0.0)), &mut h, 1e-4);
        assert!(r.force.x < 0.0);
        assert!(r.torque_i < 0.0 && r.torque_j < 0.0, "{r:?}");
        let lever = 0.1 - 0.5e-4;
        assert!((r.torque_i - r.force.x * lever).abs() < 1e-12);
    }

    #[test]
    fn a_contact_point_moving_with_the_rotation_feels_no_friction() {
        // i rolls on j: its centre moves at +v while it spins so that its
        // bottom point stays put (ω = −v / lever about z).
        let law: Pairwise<HertzDamped<true>, CundallStrack<true>, NoRolling, NoCohesion, true> =
            Pairwise {
                normal: HertzDamped {
                    k_n: 1e6,
                    gamma_n: 0.0,
                },
                tangential: CundallStrack {
                    k_s: 1e4,
                    gamma_s: 1.0,
                    mu: 0.5,
                },
                rolling: NoRolling,
                cohesion: NoCohesion,
            };
        let mut t = touch(1e-4, Vector::<2>::new(2.0, 0.0));
        t.omega_i = -2.0 / t.levers().0;
        let mut h = Default::default();
        let r = law.force(&t, &mut h, 1e-4);
        assert!(r.force.x.abs() < 1e-12, "{r:?}");
    }
}

//! Grains stored as a structure of arrays, so the hot loops stream through
//! contiguous positions, velocities and forces.
//!
//! Rotation is optional: a simulation whose contact law exerts no torque
//! keeps the angular arrays empty, and no loop touches them.

use crate::dim::{Dim, Space, Vector};
use serde::{Deserialize, Serialize};

/// One grain as a document: how scenes list grains and how reports give
/// the final state, in any dimension (vectors are plain lists).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grain {
    /// Stable identity, kept through removals and insertions.
    #[serde(default)]
    pub id: u32,
    /// Centre position.
    pub position: Vec<f64>,
    /// Velocity (zero if not given).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub velocity: Vec<f64>,
    /// Angular velocity: one value (about the out-of-plane axis) in 2D,
    /// three in 3D; zero if not given. Only simulations with rotation use it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub angular_velocity: Vec<f64>,
    /// A constant external force on the grain besides gravity (a load to
    /// pull or press with); none if not given.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub load: Vec<f64>,
    pub radius: f64,
}

impl Grain {
    /// The position as a vector of dimension `D`, if it has `D` components.
    pub fn position_in<const D: usize>(&self) -> Option<Vector<D>> {
        vector_from(&self.position)
    }

    /// The velocity as a vector of dimension `D` (zero when not given).
    pub fn velocity_in<const D: usize>(&self) -> Option<Vector<D>> {
        if self.velocity.is_empty() {
            return Some(Vector::zeros());
        }
        vector_from(&self.velocity)
    }
}

/// A vector of dimension `D` from a plain list, if the lengths agree.
pub fn vector_from<const D: usize>(values: &[f64]) -> Option<Vector<D>> {
    (values.len() == D).then(|| Vector::<D>::from_iterator(values.iter().copied()))
}

/// All grains of a simulation. Index `i` is an array slot and may change when
/// grains leave; `id[i]` is the grain's stable name.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Particles<const D: usize>
where
    Dim<D>: Space<D>,
{
    pub id: Vec<u32>,
    pub pos: Vec<Vector<D>>,
    pub vel: Vec<Vector<D>>,
    /// Total force of the current step, gravity included.
    pub force: Vec<Vector<D>>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inv_mass: Vec<f64>,
    /// Angular velocity (empty unless the grains rotate).
    pub omega: Vec<<Dim<D> as Space<D>>::Angular>,
    /// Torque of the current step (empty unless the grains rotate).
    pub torque: Vec<<Dim<D> as Space<D>>::Angular>,
    /// `1 / I` with the sphere's `I = 2/5 m a²` (empty unless the grains rotate).
    pub inv_inertia: Vec<f64>,
    /// Constant external force on each grain besides gravity (empty unless
    /// some grain carries one: see [`Particles::set_load`]).
    pub load: Vec<Vector<D>>,
    /// Whether each grain is at rest: neither integrated nor pushed by its
    /// resting neighbours until something wakes it (empty unless the
    /// simulation puts grains to rest: see `Simulation::set_rest`).
    #[serde(default)]
    pub resting: Vec<bool>,
    /// Steps each awake grain has been still in a row (empty likewise).
    #[serde(default)]
    pub still: Vec<u32>,
    #[serde(default)]
    rest_tracked: bool,
    rotating: bool,
    next_id: u32,
}

/// An angular quantity of the grains (spin, torque) in `D` dimensions.
type Angular<const D: usize> = <Dim<D> as Space<D>>::Angular;

/// What a contact reads of the grains, every slice cut to the grains'
/// count: indexing one of them checks an index against the same length as
/// all the others, so the compiler checks each index once.
#[derive(Debug, Clone, Copy)]
pub struct Grains<'a, const D: usize>
where
    Dim<D>: Space<D>,
{
    pub pos: &'a [Vector<D>],
    pub vel: &'a [Vector<D>],
    pub radius: &'a [f64],
    pub mass: &'a [f64],
    /// Empty unless the view was taken for rotating grains.
    pub omega: &'a [Angular<D>],
    /// Empty unless the view was taken with the grains' rest flags.
    pub resting: &'a [bool],
}

impl<'a, const D: usize> Grains<'a, D>
where
    Dim<D>: Space<D>,
{
    /// Every array of the grains, as long as each is.
    #[inline(always)]
    fn whole(
        pos: &'a [Vector<D>],
        vel: &'a [Vector<D>],
        (radius, mass): (&'a [f64], &'a [f64]),
        omega: &'a [Angular<D>],
        resting: &'a [bool],
    ) -> Self {
        Grains {
            pos,
            vel,
            radius,
            mass,
            omega,
            resting,
        }
    }

    /// Every slice cut to the length of `pos`; `omega` and `resting`
    /// emptied unless asked for.
    #[inline(always)]
    fn cut(self, rotating: bool, resting: bool) -> Self {
        let n = self.pos.len();
        Grains {
            pos: self.pos,
            vel: &self.vel[..n],
            radius: &self.radius[..n],
            mass: &self.mass[..n],
            omega: if rotating { &self.omega[..n] } else { &[] },
            resting: if resting { &self.resting[..n] } else { &[] },
        }
    }
}

/// Where a step's contacts add their forces and torques, each cut to the
/// grains' count (`torque` empty unless the grains rotate).
#[derive(Debug)]
pub struct Loads<'a, const D: usize>
where
    Dim<D>: Space<D>,
{
    pub force: &'a mut [Vector<D>],
    pub torque: &'a mut [Angular<D>],
}

impl<const D: usize> Default for Particles<D>
where
    Dim<D>: Space<D>,
{
    fn default() -> Self {
        Particles::new(false)
    }
}

impl<const D: usize> Particles<D>
where
    Dim<D>: Space<D>,
{
    /// No grains yet; `rotating` says whether they carry angular state.
    pub fn new(rotating: bool) -> Self {
        Particles {
            id: Vec::new(),
            pos: Vec::new(),
            vel: Vec::new(),
            force: Vec::new(),
            radius: Vec::new(),
            mass: Vec::new(),
            inv_mass: Vec::new(),
            omega: Vec::new(),
            torque: Vec::new(),
            inv_inertia: Vec::new(),
            load: Vec::new(),
            resting: Vec::new(),
            still: Vec::new(),
            rest_tracked: false,
            rotating,
            next_id: 0,
        }
    }

    /// Whether the grains carry angular velocity and torque.
    pub fn rotating(&self) -> bool {
        self.rotating
    }

    /// Gives every grain angular state (at rest) or takes it away.
    pub fn set_rotating(&mut self, rotating: bool) {
        self.rotating = rotating;
        self.omega.clear();
        self.torque.clear();
        self.inv_inertia.clear();
        if rotating {
            let n = self.len();
            self.omega.resize(n, Default::default());
            self.torque.resize(n, Default::default());
            self.inv_inertia.extend(
                self.mass
                    .iter()
                    .zip(&self.radius)
                    .map(|(m, a)| 1.0 / (0.4 * m * a * a)),
            );
        }
    }

    /// Starts or stops keeping track of which grains are at rest (every
    /// grain starts awake).
    pub fn track_rest(&mut self, on: bool) {
        self.rest_tracked = on;
        self.resting.clear();
        self.still.clear();
        if on {
            self.resting.resize(self.len(), false);
            self.still.resize(self.len(), 0);
        }
    }

    /// Whether the grains' rest is tracked.
    pub fn tracks_rest(&self) -> bool {
        self.rest_tracked
    }

    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// The grains as contacts read them: with their spins if `rotating`
    /// (they must rotate), with their rest flags if `resting` (they must be tracked).
    #[inline(always)]
    pub fn contact_view(&self, rotating: bool, resting: bool) -> Grains<'_, D> {
        let (pos, vel, omega) = (&self.pos, &self.vel, &self.omega);
        let grains = Grains::whole(pos, vel, (&self.radius, &self.mass), omega, &self.resting);
        grains.cut(rotating, resting)
    }

    /// [`Particles::contact_view`] beside the forces and torques the contacts
    /// add to.
    #[inline(always)]
    pub fn split(&mut self, rotating: bool, resting: bool) -> (Grains<'_, D>, Loads<'_, D>) {
        let n = self.pos.len();
        let (pos, vel, omega) = (&self.pos, &self.vel, &self.omega);
        let grains = Grains::whole(pos, vel, (&self.radius, &self.mass), omega, &self.resting);
        let (force, torque) = (&mut self.force, &mut self.torque);
        let torque: &mut [Angular<D>] = if rotating { &mut torque[..n] } else { &mut [] };
        let loads = Loads {
            force: &mut force[..n],
            torque,
        };
        (grains.cut(rotating, resting), loads)
    }

    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Adds a grain of the given mass; returns its stable id.
    pub fn push(&mut self, pos: Vector<D>, vel: Vector<D>, radius: f64, mass: f64) -> u32 {
        let id = self.next_id;
        self.push_with_id(id, pos, vel, radius, mass);
        id
    }

    pub fn push_with_id(
        &mut self,
        id: u32,
        pos: Vector<D>,
        vel: Vector<D>,
        radius: f64,
        mass: f64,
    ) {
        self.id.push(id);
        self.pos.push(pos);
        self.vel.push(vel);
        self.force.push(Vector::zeros());
        self.radius.push(radius);
        self.mass.push(mass);
        self.inv_mass.push(1.0 / mass);
        if self.rotating {
            self.omega.push(Default::default());
            self.torque.push(Default::default());
            self.inv_inertia.push(1.0 / (0.4 * mass * radius * radius));
        }
        if !self.load.is_empty() {
            self.load.push(Vector::zeros());
        }
        if self.rest_tracked {
            self.resting.push(false);
            self.still.push(0);
        }
        self.next_id = self.next_id.max(id + 1);
    }

    /// Puts a constant external force on grain `i`.
    pub fn set_load(&mut self, i: usize, force: Vector<D>) {
        if self.load.is_empty() {
            self.load.resize(self.len(), Vector::zeros());
        }
        self.load[i] = force;
    }

    /// Numbers the grains 0, 1, 2, … unless their ids are already unique
    /// (listed grains may all leave `id` at its default).
    pub fn make_ids_unique(&mut self) {
        let mut ids = self.id.clone();
        ids.sort_unstable();
        ids.dedup();
        if ids.len() != self.len() {
            for (k, id) in self.id.iter_mut().enumerate() {
                *id = k as u32;
            }
            self.next_id = self.len() as u32;
        }
    }

    /// Removes every grain whose flag is set, keeping the order of the rest
    /// (order matters: pair lists sorted by index stay sorted after remapping).
    pub fn retain(&mut self, keep: &[bool]) {
        fn filter<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
            let mut k = 0;
            v.retain(|_| {
                let r = keep[k];
                k += 1;
                r
            });
        }
        filter(&mut self.id, keep);
        filter(&mut self.pos, keep);
        filter(&mut self.vel, keep);
        filter(&mut self.force, keep);
        filter(&mut self.radius, keep);
        filter(&mut self.mass, keep);
        filter(&mut self.inv_mass, keep);
        if self.rotating {
            filter(&mut self.omega, keep);
            filter(&mut self.torque, keep);
            filter(&mut self.inv_inertia, keep);
        }
        if !self.load.is_empty() {
            filter(&mut self.load, keep);
        }
        if self.rest_tracked {
            filter(&mut self.resting, keep);
            filter(&mut self.still, keep);
        }
    }

    /// Reorders the grains: the grain at new index `k` is the one that was
    /// at `order[k]`.
    pub fn permute(&mut self, order: &[usize]) {
        fn apply<T: Copy>(v: &mut Vec<T>, order: &[usize]) {
            if !v.is_empty() {
                *v = order.iter().map(|&i| v[i]).collect();
            }
        }
        apply(&mut self.id, order);
        apply(&mut self.pos, order);
        apply(&mut self.vel, order);
        apply(&mut self.force, order);
        apply(&mut self.radius, order);
        apply(&mut self.mass, order);
        apply(&mut self.inv_mass, order);
        apply(&mut self.omega, order);
        apply(&mut self.torque, order);
        apply(&mut self.inv_inertia, order);
        apply(&mut self.load, order);
        apply(&mut self.resting, order);
        apply(&mut self.still, order);
    }

    /// Translational kinetic energy.
    pub fn kinetic_energy(&self) -> f64 {
        self.kinetic_energies().sum()
    }

    /// The translational kinetic energy of each grain, in grain order.
    pub fn kinetic_energies(&self) -> impl Iterator<Item = f64> + '_ {
        self.vel
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| 0.5 * m * v.norm_squared())
    }

    /// Rotational kinetic energy (zero without rotation).
    pub fn rotational_energy(&self) -> f64 {
        self.omega
            .iter()
            .zip(&self.inv_inertia)
            .map(|(w, inv_i)| 0.5 * <Dim<D> as Space<D>>::angular_norm_squared(*w) / inv_i)
            .sum()
    }

    pub fn max_speed(&self) -> f64 {
        self.vel
            .iter()
            .map(|v| v.norm_squared())
            .fold(0.0, f64::max)
            .sqrt()
    }

    pub fn mean_radius(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        self.radius.iter().sum::<f64>() / self.len() as f64
    }

    /// The grains as documents, in the order of their ids (grains renumbered
    /// in space keep their ids).
    pub fn grains(&self) -> Vec<Grain> {
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.sort_by_key(|&i| self.id[i]);
        order
            .into_iter()
            .map(|i| Grain {
                id: self.id[i],
                position: self.pos[i].iter().copied().collect(),
                velocity: self.vel[i].iter().copied().collect(),
                angular_velocity: self
                    .omega
                    .get(i)
                    .map(|w| <Dim<D> as Space<D>>::angular_components(*w))
                    .unwrap_or_default(),
                load: self
                    .load
                    .get(i)
                    .map(|f| f.iter().copied().collect())
                    .unwrap_or_default(),
                radius: self.radius[i],
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_contact_view_cuts_every_slice_to_the_grain_count() {
        let mut p = Particles::<3>::new(true);
        for k in 0..3 {
            let x = Vector::<3>::new(k as f64, 0.0, 0.0);
            p.push(x, Vector::<3>::zeros(), 0.5, 1.0);
        }
        let g = p.contact_view(true, false);
        let lengths = [g.pos, g.vel].map(<[_]>::len);
        assert_eq!(lengths, [3, 3]);
        assert_eq!((g.radius.len(), g.mass.len()), (3, 3));
        assert_eq!((g.omega.len(), g.resting.len()), (3, 0));
        assert!(p.contact_view(false, false).omega.is_empty());

        p.track_rest(true);
        let (g, loads) = p.split(true, true);
        assert_eq!(g.resting.len(), 3);
        assert_eq!((loads.force.len(), loads.torque.len()), (3, 3));
        loads.force[2] = Vector::<3>::new(1.0, 2.0, 3.0);
        assert_eq!(p.force[2], Vector::<3>::new(1.0, 2.0, 3.0));
        let (_, loads) = p.split(false, false);
        assert!(loads.torque.is_empty());
    }
}

//! Grains stored as a structure of arrays, so the hot loops stream through
//! contiguous positions, velocities and forces.

use crate::dim::Vector;
use serde::{Deserialize, Serialize};

/// One grain as it enters or leaves a simulation (input and output format).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grain<const D: usize> {
    /// Stable identity, kept through removals and insertions.
    #[serde(default)]
    pub id: u32,
    /// Centre position (cm).
    #[serde(with = "array_vec")]
    pub position: Vector<D>,
    /// Velocity (cm/s).
    #[serde(default = "Vector::zeros", with = "array_vec")]
    pub velocity: Vector<D>,
    /// Radius (cm).
    pub radius: f64,
}

/// Serialise a nalgebra vector as a plain JSON/TOML array `[x, y]`.
pub(crate) mod array_vec {
    use super::Vector;
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer, const D: usize>(
        v: &Vector<D>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter())
    }

    pub fn deserialize<'de, De: Deserializer<'de>, const D: usize>(
        d: De,
    ) -> Result<Vector<D>, De::Error> {
        let values = Vec::<f64>::deserialize(d)?;
        if values.len() != D {
            return Err(De::Error::custom(format!(
                "expected {D} components, found {}",
                values.len()
            )));
        }
        Ok(Vector::<D>::from_iterator(values))
    }
}

/// All grains of a simulation. Index `i` is an array slot and may change when
/// grains leave; `id[i]` is the grain's stable name.
#[derive(Debug, Clone, Default)]
pub struct Particles<const D: usize> {
    pub id: Vec<u32>,
    pub pos: Vec<Vector<D>>,
    pub vel: Vec<Vector<D>>,
    /// Total force of the current step, gravity included.
    pub force: Vec<Vector<D>>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inv_mass: Vec<f64>,
    next_id: u32,
}

impl<const D: usize> Particles<D> {
    pub fn len(&self) -> usize {
        self.pos.len()
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
        self.next_id = self.next_id.max(id + 1);
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
    }

    pub fn kinetic_energy(&self) -> f64 {
        self.vel
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| 0.5 * m * v.norm_squared())
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

    pub fn grains(&self) -> Vec<Grain<D>> {
        (0..self.len())
            .map(|i| Grain {
                id: self.id[i],
                position: self.pos[i],
                velocity: self.vel[i],
                radius: self.radius[i],
            })
            .collect()
    }
}

//! Energies of a simulation and the guard that fails a run whose kinetic
//! energy could only have come from the integrator.

use super::{Blowup, Simulation};
use crate::contact::ContactLaw;
use crate::dim::{Dim, Space};
use crate::integrate::Integrator;

impl<const D: usize, L: ContactLaw<D>, I: Integrator<D>> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    /// Kinetic (translation and rotation) plus elastic energy plus
    /// gravitational potential, the zero of height at the origin.
    pub fn total_energy(&self) -> f64 {
        let p = &self.particles;
        let mut e = self.kinetic_energy() + self.elastic_energy();
        for i in 0..p.len() {
            e -= p.mass[i] * self.gravity.dot(&p.pos[i]);
        }
        e
    }

    /// Energy stored in the contact springs (normal and tangential).
    pub fn elastic_energy(&self) -> f64 {
        let p = &self.particles;
        let g = p.contact_view(L::ROTATES, false);
        let mut e = 0.0;
        for (k, [i, j]) in self.neighbors.pairs.iter().enumerate() {
            let (i, j) = (*i as usize, *j as usize);
            let r = self.separation(k, i, j);
            let dist = r.norm();
            if p.radius[i] + p.radius[j] - dist > 0.0 {
                let touch = super::forces::pair_touch(&g, i, j, r, dist, L::ROTATES);
                e += self
                    .pair_law
                    .elastic_energy(&touch, &self.neighbors.history[k]);
            }
        }
        for (w, wall) in self.walls.iter().enumerate() {
            for (k, &i) in self.wall_contacts.candidates[w].iter().enumerate() {
                let i = i as usize;
                let overlap = p.radius[i] - wall.distance(&p.pos[i]);
                if overlap > 0.0 && wall.covers(&p.pos[i]) {
                    let touch = super::forces::wall_touch(&g, i, wall.normal, overlap, L::ROTATES);
                    e +=
                        self.wall_laws[w].elastic_energy(&touch, &self.wall_contacts.history[w][k]);
                }
            }
        }
        e
    }

    /// Arms the energy guard. A grain that moves within a region of size
    /// `extent` under gravity can gain at most `|g|·extent` per unit mass;
    /// cohesion can give it at most the work of pulling its neighbours (at
    /// most twelve) from out of range to the deepest overlap the guards
    /// allow; and the stored kinetic and elastic energy can only be released
    /// once. A kinetic energy above twice that budget can only come from the
    /// integrator itself, so [`Simulation::check_energy`] fails the run.
    pub fn set_energy_budget(&mut self, extent: f64) {
        self.rebuild_lists();
        let stored = self.particles.kinetic_energy() + self.elastic_energy();
        self.guards.energy_per_mass = 2.0 * self.gravity.norm() * extent;
        self.guards.energy_offset = 2.0 * stored;
    }

    /// What cohesion can give the grains there are now: six bonds per
    /// grain (twelve neighbours, each bond shared), each pulled from out of
    /// range to the deepest overlap the guards allow.
    fn bond_allowance(&self) -> f64 {
        if !L::ACTS_ACROSS_GAPS {
            return 0.0;
        }
        let p = &self.particles;
        let depth = self.guards.max_overlap;
        (0..p.len())
            .map(|i| {
                6.0 * self
                    .pair_law
                    .bond_work(0.5 * p.radius[i], depth * p.radius[i])
            })
            .sum()
    }

    /// Fails with [`Blowup::Energy`] when the kinetic energy exceeds the budget.
    pub fn check_energy(&self) -> Result<(), Blowup> {
        let p = &self.particles;
        let kinetic = p.kinetic_energy();
        let mass: f64 = p.mass.iter().sum();
        let mut limit = self.guards.energy_per_mass * mass + self.guards.energy_offset;
        if L::ACTS_ACROSS_GAPS {
            limit += 2.0 * self.bond_allowance();
        }
        // A budget of zero (no gravity, nothing moving) still allows rounding.
        if kinetic > limit * (1.0 + 1e-9) + f64::MIN_POSITIVE || kinetic.is_nan() {
            return Err(Blowup::Energy {
                kinetic,
                limit,
                time: self.time,
                units: self.units,
            });
        }
        Ok(())
    }
}

//! Spatial ordering of the grains: every so many steps the grains are
//! renumbered cell by cell (z slowest), so that grains near each other sit
//! near each other in memory, the pair loop reads memory in order, and a
//! split of the grains into index ranges is a split of space into slabs
//! with few pairs across (see `share.rs`).

use super::Simulation;
use crate::contact::ContactLaw;
use crate::dim::{Dim, Space};
use crate::integrate::Integrator;

impl<const D: usize, L: ContactLaw<D>, I: Integrator<D>> Simulation<D, L, I>
where
    Dim<D>: Space<D>,
{
    /// Renumbers the grains in the order of the cells they lie in, one
    /// cell two largest diameters wide; grains in one cell keep their order.
    pub fn sort_spatially(&mut self) {
        let p = &self.particles;
        let n = p.len();
        if n < 2 {
            return;
        }
        let largest = p.radius.iter().copied().fold(0.0, f64::max);
        let size = 4.0 * largest + self.neighbors.skin;
        let mut lo = p.pos[0];
        for x in &p.pos {
            lo = lo.inf(x);
        }
        let cell = |x: &crate::dim::Vector<D>| -> [u64; D] {
            let mut c = [0u64; D];
            // Slowest axis first: the last (vertical) one.
            for (a, slot) in c.iter_mut().enumerate() {
                let axis = D - 1 - a;
                *slot = ((x[axis] - lo[axis]) / size).max(0.0) as u64;
            }
            c
        };
        let mut order: Vec<usize> = (0..n).collect();
        let keys: Vec<[u64; D]> = p.pos.iter().map(cell).collect();
        order.sort_by_key(|&i| keys[i]);
        if order.iter().enumerate().all(|(k, &i)| k == i) {
            return;
        }
        let mut new_index = vec![0u32; n];
        for (k, &i) in order.iter().enumerate() {
            new_index[i] = k as u32;
        }
        self.particles.permute(&order);
        self.integrator.on_permute(&order);
        self.neighbors.permute(&new_index, L::flip);
        self.wall_contacts.permute(&new_index);
    }
}

//! Neighbour search: a cell list builds a Verlet list with a skin, and the
//! list carries each pair's contact history.
//!
//! The list holds every pair `i < j` whose gap was below `skin` at build
//! time, sorted by `(i, j)`. It stays valid until some grain has moved more
//! than `skin / 2` since the build: only then can a pair outside the list
//! have come into contact. Because a touching pair is always in the list, a
//! rebuild can hand every live spring to the new list by a merge of two
//! sorted sequences; nothing is lost, nothing is looked up by hashing.
//! A spring is reset to its default the moment its contact opens.
//!
//! A contact law that acts across gaps (cohesion) has a range: pairs whose
//! gap is below `range + skin` enter the list, so every pair within range
//! is always listed.
//!
//! With periodic axes the grains near a face are also binned as images
//! shifted by one period, and a pair found through an image keeps that
//! shift: the pair's separation is `x_i − x_j − shift`.

use crate::dim::{Dim, Space, Vector};
use crate::particles::Particles;
use crate::simulation::boundary::Periodic;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// Below this many grains the search stays on one thread: a build then
/// takes less than sharing it costs.
const SHARED_SEARCH: usize = 1024;

/// Pairs found by a search, their image shifts (with periodic axes), and
/// the search's scratch space.
#[derive(Debug, Default)]
struct Found<const D: usize> {
    pairs: Vec<[u32; 2]>,
    shifts: Vec<Vector<D>>,
    scratch: Vec<(u32, Vector<D>)>,
}

/// Verlet pair list with one contact-history slot per pair.
/// Everything but the scratch space of the search is state: a restored
/// list goes on exactly as the saved one would have.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct NeighborList<const D: usize, H> {
    /// Extra distance beyond touching for a pair to enter the list, cm.
    pub skin: f64,
    /// Candidate pairs `(i, j)`, `i < j`, sorted.
    pub pairs: Vec<[u32; 2]>,
    /// Contact history of each pair; `H::default()` when not touching.
    pub history: Vec<H>,
    /// Image shift of each pair across periodic faces (empty without them).
    pub shifts: Vec<Vector<D>>,
    /// How many times the list was built.
    pub builds: u64,
    anchor: Vec<Vector<D>>,
    #[serde(skip)]
    grid: CellGrid<D>,
    #[serde(skip)]
    scratch: Vec<(u32, Vector<D>)>,
    #[serde(skip)]
    merged: Vec<([u32; 2], H)>,
    #[serde(skip)]
    images: Vec<Vector<D>>,
    #[serde(skip)]
    image_of: Vec<(u32, Vector<D>)>,
}

impl<const D: usize, H: Copy + Default + PartialEq> NeighborList<D, H> {
    pub fn new(skin: f64) -> Self {
        NeighborList {
            skin,
            pairs: Vec::new(),
            history: Vec::new(),
            shifts: Vec::new(),
            builds: 0,
            anchor: Vec::new(),
            grid: CellGrid::default(),
            scratch: Vec::new(),
            merged: Vec::new(),
            images: Vec::new(),
            image_of: Vec::new(),
        }
    }

    /// True once a grain has moved more than half the skin since the last
    /// build (or the number of grains changed).
    pub fn is_stale(&self, p: &Particles<D>) -> bool
    where
        Dim<D>: Space<D>,
    {
        if self.anchor.len() != p.len() {
            return true;
        }
        let limit = 0.25 * self.skin * self.skin;
        p.pos
            .iter()
            .zip(&self.anchor)
            .any(|(x, x0)| (x - x0).norm_squared() > limit)
    }

    /// Renumbers the stored pairs after grains were removed: `new_index[i]`
    /// is the new index of old grain `i`, or `u32::MAX` if it is gone.
    /// Removal preserves order, so the list stays sorted.
    pub fn renumber(&mut self, new_index: &[u32]) {
        let mut out = 0;
        let periodic = !self.shifts.is_empty();
        for k in 0..self.pairs.len() {
            let [i, j] = self.pairs[k];
            let (ni, nj) = (new_index[i as usize], new_index[j as usize]);
            if ni != u32::MAX && nj != u32::MAX {
                self.pairs[out] = [ni, nj];
                self.history[out] = self.history[k];
                if periodic {
                    self.shifts[out] = self.shifts[k];
                }
                out += 1;
            }
        }
        self.pairs.truncate(out);
        self.history.truncate(out);
        self.shifts.truncate(out.min(self.shifts.len()));
        self.anchor.clear();
    }

    /// Rebuilds the list from the current positions, keeping every live
    /// contact history. `range` is the largest gap across which the
    /// contact law acts (0 for contact-only laws); `periodic` the periodic
    /// axes, whose positions must already be wrapped into the cell. On a
    /// `pool` the search is shared out by ranges of first grains and the
    /// pieces joined in order: the list is the one a single thread builds.
    pub fn rebuild(
        &mut self,
        p: &Particles<D>,
        range: f64,
        periodic: Option<&Periodic<D>>,
        pool: Option<&rayon::ThreadPool>,
    ) where
        Dim<D>: Space<D>,
        H: Sync,
    {
        // Live springs, already sorted by pair.
        self.merged.clear();
        for (pair, h) in self.pairs.iter().zip(&self.history) {
            if *h != H::default() {
                self.merged.push((*pair, *h));
            }
        }

        let max_radius = p.radius.iter().copied().fold(0.0, f64::max);
        let cell = 2.0 * max_radius + range + self.skin;
        self.collect_images(p, periodic, cell);
        let mut found = Found {
            pairs: std::mem::take(&mut self.pairs),
            shifts: std::mem::take(&mut self.shifts),
            scratch: std::mem::take(&mut self.scratch),
        };
        found.pairs.clear();
        found.shifts.clear();
        let n = p.len();
        match pool {
            Some(pool) if n >= SHARED_SEARCH => {
                // More pieces than threads: a dense bed and falling grains
                // above cost unequally.
                let pieces = pool.current_num_threads() * 4;
                let parts: Vec<Found<D>> = pool.install(|| {
                    (0..pieces)
                        .into_par_iter()
                        .map(|k| {
                            let mut part = Found::default();
                            let grains = k * n / pieces..(k + 1) * n / pieces;
                            self.search(p, range, periodic.is_some(), grains, &mut part);
                            part
                        })
                        .collect()
                });
                for part in parts {
                    found.pairs.extend_from_slice(&part.pairs);
                    found.shifts.extend_from_slice(&part.shifts);
                }
            }
            _ => self.search(p, range, periodic.is_some(), 0..n, &mut found),
        }
        self.pairs = found.pairs;
        self.shifts = found.shifts;
        self.scratch = found.scratch;
        self.hand_over_springs();
        self.anchor.clear();
        self.anchor.extend_from_slice(&p.pos);
        self.builds += 1;
    }

    /// The listed pairs of the first grains `grains`, in order, appended to
    /// `out`, with their image shifts when the axes are `periodic`.
    fn search(
        &self,
        p: &Particles<D>,
        range: f64,
        periodic: bool,
        grains: Range<usize>,
        out: &mut Found<D>,
    ) where
        Dim<D>: Space<D>,
    {
        for i in grains {
            self.near_pairs(p, i, range, &mut out.scratch);
            out.scratch.sort_unstable_by_key(|e| e.0);
            out.pairs
                .extend(out.scratch.iter().map(|&(j, _)| [i as u32, j]));
            if periodic {
                out.shifts.extend(out.scratch.iter().map(|e| e.1));
            }
        }
    }

    /// Bins the grains, and with periodic axes their images near the faces.
    fn collect_images(&mut self, p: &Particles<D>, periodic: Option<&Periodic<D>>, cell: f64)
    where
        Dim<D>: Space<D>,
    {
        self.images.clear();
        self.image_of.clear();
        let Some(per) = periodic else {
            self.grid.bin(&p.pos, cell);
            return;
        };
        self.images.extend_from_slice(&p.pos);
        for (j, x) in p.pos.iter().enumerate() {
            per.for_each_image(x, cell, |shift| {
                self.images.push(x + shift);
                self.image_of.push((j as u32, shift));
            });
        }
        self.grid.bin(&self.images, cell);
    }

    /// Fills `scratch` with the partners `j > i` of grain `i` within reach,
    /// each with the shift of the image it was found through.
    fn near_pairs(
        &self,
        p: &Particles<D>,
        i: usize,
        range: f64,
        scratch: &mut Vec<(u32, Vector<D>)>,
    ) where
        Dim<D>: Space<D>,
    {
        scratch.clear();
        let n = p.len();
        let xi = p.pos[i];
        let ri = p.radius[i];
        let skin = self.skin;
        let image_of = &self.image_of;
        let images = &self.images;
        self.grid.for_each_near(i, |e| {
            let e = e as usize;
            let (j, shift, xj) = if e < n {
                (e, Vector::<D>::zeros(), p.pos[e])
            } else {
                let (j, shift) = image_of[e - n];
                (j as usize, shift, images[e])
            };
            if j > i {
                let reach = ri + p.radius[j] + range + skin;
                if (xi - xj).norm_squared() < reach * reach {
                    scratch.push((j as u32, shift));
                }
            }
        });
    }

    /// Hands the live springs to the new list (both sequences are sorted).
    fn hand_over_springs(&mut self) {
        self.history.clear();
        self.history.resize(self.pairs.len(), H::default());
        let mut k = 0;
        for (pair, h) in &self.merged {
            while k < self.pairs.len() && self.pairs[k] < *pair {
                k += 1;
            }
            if k < self.pairs.len() && self.pairs[k] == *pair {
                self.history[k] = *h;
            }
        }
    }

    /// Renumbers after the grains were reordered (`new_index[old]` is the
    /// new index of every grain). A pair whose grains swap order is stored
    /// the other way round, its history seen from the other grain (`flip`)
    /// and its image shift reversed; the list is sorted again.
    pub fn permute(&mut self, new_index: &[u32], flip: fn(&mut H)) {
        let periodic = !self.shifts.is_empty();
        let mut all: Vec<([u32; 2], H, Vector<D>)> = Vec::with_capacity(self.pairs.len());
        for k in 0..self.pairs.len() {
            let [i, j] = self.pairs[k];
            let (ni, nj) = (new_index[i as usize], new_index[j as usize]);
            let mut h = self.history[k];
            let mut shift = if periodic {
                self.shifts[k]
            } else {
                Vector::<D>::zeros()
            };
            let pair = if ni < nj {
                [ni, nj]
            } else {
                flip(&mut h);
                shift = -shift;
                [nj, ni]
            };
            all.push((pair, h, shift));
        }
        all.sort_unstable_by_key(|e| e.0);
        self.pairs = all.iter().map(|e| e.0).collect();
        self.history = all.iter().map(|e| e.1).collect();
        if periodic {
            self.shifts = all.iter().map(|e| e.2).collect();
        }
        self.anchor.clear();
    }
}

/// A uniform grid of cells at least one interaction range wide, padded by
/// one empty cell on every side so the 3^D stencil never leaves the grid.
#[derive(Debug, Clone)]
struct CellGrid<const D: usize> {
    dims: [usize; D],
    origin: [f64; D],
    inv_size: f64,
    /// Grain indices sorted by cell.
    order: Vec<u32>,
    /// `start[c]..start[c + 1]` indexes `order` for cell `c`.
    start: Vec<u32>,
    cell_of: Vec<u32>,
    stencil: Vec<isize>,
}

impl<const D: usize> Default for CellGrid<D> {
    fn default() -> Self {
        CellGrid {
            dims: [0; D],
            origin: [0.0; D],
            inv_size: 0.0,
            order: Vec::new(),
            start: Vec::new(),
            cell_of: Vec::new(),
            stencil: Vec::new(),
        }
    }
}

impl<const D: usize> CellGrid<D> {
    fn bin(&mut self, pos: &[Vector<D>], min_size: f64) {
        let n = pos.len();
        let mut lo = [f64::INFINITY; D];
        let mut hi = [f64::NEG_INFINITY; D];
        for x in pos {
            for d in 0..D {
                lo[d] = lo[d].min(x[d]);
                hi[d] = hi[d].max(x[d]);
            }
        }
        if n == 0 {
            lo = [0.0; D];
            hi = [0.0; D];
        }
        // Grains far apart (a few falling away) must not make the grid huge:
        // widen the cells until the grid has at most a few cells per grain.
        let budget = (8 * n).max(64) as f64;
        let mut size = min_size.max(f64::MIN_POSITIVE);
        for _ in 0..4096 {
            let cells: f64 = (0..D)
                .map(|d| ((hi[d] - lo[d]) / size).floor() + 3.0)
                .product();
            if cells <= budget {
                break;
            }
            size *= 1.5;
        }
        self.inv_size = 1.0 / size;
        for d in 0..D {
            self.origin[d] = lo[d] - size;
            self.dims[d] = ((hi[d] - lo[d]) / size).floor() as usize + 3;
        }
        let total: usize = self.dims.iter().product();

        self.cell_of.clear();
        self.cell_of.extend(pos.iter().map(|x| {
            let mut c = 0usize;
            for d in (0..D).rev() {
                let k = ((x[d] - self.origin[d]) * self.inv_size) as usize;
                c = c * self.dims[d] + k.clamp(1, self.dims[d] - 2);
            }
            c as u32
        }));

        // Counting sort of grains by cell.
        self.start.clear();
        self.start.resize(total + 1, 0);
        for &c in &self.cell_of {
            self.start[c as usize + 1] += 1;
        }
        for c in 0..total {
            self.start[c + 1] += self.start[c];
        }
        self.order.resize(n, 0);
        let mut fill = self.start.clone();
        for (i, &c) in self.cell_of.iter().enumerate() {
            self.order[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }

        // Flattened offsets of the 3^D neighbouring cells.
        self.stencil.clear();
        let mut strides = [0isize; D];
        let mut s = 1isize;
        for (stride, dim) in strides.iter_mut().zip(&self.dims) {
            *stride = s;
            s *= *dim as isize;
        }
        for code in 0..3usize.pow(D as u32) {
            let mut off = 0isize;
            let mut rest = code;
            for stride in strides.iter() {
                off += ((rest % 3) as isize - 1) * stride;
                rest /= 3;
            }
            self.stencil.push(off);
        }
    }

    #[inline]
    fn for_each_near(&self, i: usize, mut f: impl FnMut(u32)) {
        let c = self.cell_of[i] as isize;
        for off in &self.stencil {
            let cell = (c + off) as usize;
            let (a, b) = (self.start[cell] as usize, self.start[cell + 1] as usize);
            for &j in &self.order[a..b] {
                f(j);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1500 grains of two sizes scattered through a box, with some
    /// overlapping and many within the skin.
    fn scattered() -> Particles<3> {
        let mut p = Particles::<3>::new(false);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..1500 {
            let x = Vector::<3>::new(next(), next(), next()) * 12.0;
            let radius = if next() < 0.5 { 0.5 } else { 0.4 };
            p.push(x, Vector::<3>::zeros(), radius, 1.0);
        }
        p
    }

    #[test]
    fn the_shared_search_lists_every_pair_within_reach_as_one_thread_does() {
        let p = scattered();
        let (skin, range) = (0.1, 0.05);
        let mut one = NeighborList::<3, u8>::new(skin);
        one.rebuild(&p, range, None, None);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let mut two = NeighborList::<3, u8>::new(skin);
        two.rebuild(&p, range, None, Some(&pool));
        assert_eq!(one.pairs, two.pairs);
        // Against every pair by brute force.
        let mut all = Vec::new();
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let reach = p.radius[i] + p.radius[j] + range + skin;
                if (p.pos[i] - p.pos[j]).norm_squared() < reach * reach {
                    all.push([i as u32, j as u32]);
                }
            }
        }
        assert!(all.len() > 1000, "{} pairs", all.len());
        assert_eq!(one.pairs, all);
    }
}

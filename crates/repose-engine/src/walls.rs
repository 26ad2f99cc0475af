//! Flat walls. A wall is a plane with a unit normal pointing to the side
//! where grains live, optionally bounded: a grain touches it only while the
//! foot of its centre on the plane lies inside `[lo, hi]` (componentwise).
//! A bounded floor is how the fill-and-release box ends at `x = W`.

use crate::dim::{Dim, Space, Vector};
use crate::particles::{vector_from, Particles};
use serde::{Deserialize, Serialize};

/// A wall in the engine.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall<const D: usize> {
    /// Any point of the plane.
    pub point: Vector<D>,
    /// Unit normal towards the grains (normalised on construction).
    pub normal: Vector<D>,
    /// Bounds of the wall's extent, if any (empty: an infinite plane).
    pub limits: Vec<Limit>,
}

/// A wall as a document: how scenes list walls and reports give them back,
/// in any dimension (vectors are plain lists).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Any point of the plane.
    pub point: Vec<f64>,
    /// Normal towards the grains (need not be of unit length).
    pub normal: Vec<f64>,
    /// Bounds of the wall's extent, if any (empty: an infinite plane).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub limits: Vec<Limit>,
}

impl WallSpec {
    /// The engine's wall, if the vectors have `D` components and the normal
    /// has a length that is neither zero nor overflows.
    pub fn to_wall<const D: usize>(&self) -> Option<Wall<D>> {
        let point = vector_from::<D>(&self.point)?;
        let normal = vector_from::<D>(&self.normal)?;
        let length = normal.norm();
        (length > 0.0 && length.is_finite()).then(|| Wall {
            point,
            normal: normal.normalize(),
            limits: self.limits.clone(),
        })
    }
}

impl<const D: usize> From<&Wall<D>> for WallSpec {
    fn from(w: &Wall<D>) -> Self {
        WallSpec {
            point: w.point.iter().copied().collect(),
            normal: w.normal.iter().copied().collect(),
            limits: w.limits.clone(),
        }
    }
}

/// The foot of a grain on a wall must satisfy `min ≤ foot[axis] ≤ max`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limit {
    /// Coordinate axis (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
}

impl<const D: usize> Wall<D> {
    /// An unbounded plane through `point` facing `normal`.
    pub fn plane(point: Vector<D>, normal: Vector<D>) -> Self {
        Wall {
            point,
            normal: normal.normalize(),
            limits: Vec::new(),
        }
    }

    /// Signed distance of `x` from the plane (positive on the grains' side).
    #[inline(always)]
    pub fn distance(&self, x: &Vector<D>) -> f64 {
        (x - self.point).dot(&self.normal)
    }

    /// Whether the foot of `x` on the plane lies within the wall's extent.
    #[inline(always)]
    pub fn covers(&self, x: &Vector<D>) -> bool {
        if self.limits.is_empty() {
            return true;
        }
        let foot = x - self.normal * self.distance(x);
        self.limits.iter().all(|l| {
            let v = foot[l.axis.min(D - 1)];
            l.min.is_none_or(|m| v >= m) && l.max.is_none_or(|m| v <= m)
        })
    }
}

/// Grains near each wall (within their radius plus the skin at the last
/// neighbour build) and the contact history of each.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WallContacts<H> {
    /// For each wall, candidate grain indices, ascending.
    pub candidates: Vec<Vec<u32>>,
    /// For each wall, one history slot per candidate.
    pub history: Vec<Vec<H>>,
}

impl<H: Copy + Default + PartialEq> WallContacts<H> {
    pub fn new(walls: usize) -> Self {
        WallContacts {
            candidates: vec![Vec::new(); walls],
            history: vec![Vec::new(); walls],
        }
    }

    /// Same meaning as [`crate::neighbors::NeighborList::renumber`].
    pub fn renumber(&mut self, new_index: &[u32]) {
        for (cands, hist) in self.candidates.iter_mut().zip(&mut self.history) {
            let mut out = 0;
            for k in 0..cands.len() {
                let ni = new_index[cands[k] as usize];
                if ni != u32::MAX {
                    cands[out] = ni;
                    hist[out] = hist[k];
                    out += 1;
                }
            }
            cands.truncate(out);
            hist.truncate(out);
        }
    }

    /// Renumbers after the grains were reordered (`new_index[old]` is the
    /// new index of every grain), keeping each wall's candidates ascending.
    pub fn permute(&mut self, new_index: &[u32]) {
        self.renumber(new_index);
        for (cands, hist) in self.candidates.iter_mut().zip(&mut self.history) {
            let mut both: Vec<(u32, H)> = cands.iter().copied().zip(hist.iter().copied()).collect();
            both.sort_unstable_by_key(|e| e.0);
            (*cands, *hist) = both.into_iter().unzip();
        }
    }

    /// Re-selects the candidates of every wall, keeping live histories.
    pub fn rebuild<const D: usize>(&mut self, walls: &[Wall<D>], p: &Particles<D>, skin: f64)
    where
        Dim<D>: Space<D>,
    {
        self.candidates.resize(walls.len(), Vec::new());
        self.history.resize(walls.len(), Vec::new());
        for (w, wall) in walls.iter().enumerate() {
            let old: Vec<(u32, H)> = self.candidates[w]
                .iter()
                .zip(&self.history[w])
                .filter(|(_, h)| **h != H::default())
                .map(|(i, h)| (*i, *h))
                .collect();
            let cands = &mut self.candidates[w];
            cands.clear();
            for i in 0..p.len() {
                if wall.distance(&p.pos[i]) < p.radius[i] + skin {
                    cands.push(i as u32);
                }
            }
            let hist = &mut self.history[w];
            hist.clear();
            hist.resize(cands.len(), H::default());
            let mut k = 0;
            for (i, h) in old {
                while k < cands.len() && cands[k] < i {
                    k += 1;
                }
                if k < cands.len() && cands[k] == i {
                    hist[k] = h;
                }
            }
        }
    }
}

//! Open and periodic boundaries of the simulated region.

use crate::dim::Vector;

/// Grains whose centre lies beyond this plane leave the simulation (the
/// open side of a box after its wall is removed, the edges of a heap's plate).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outlet<const D: usize> {
    pub point: Vector<D>,
    /// Unit normal pointing out of the region grains may stay in.
    pub normal: Vector<D>,
}

impl<const D: usize> Outlet<D> {
    /// Whether a centre at `x` has left through this plane.
    #[inline]
    pub fn passed(&self, x: &Vector<D>) -> bool {
        (x - self.point).dot(&self.normal) > 0.0
    }
}

/// Periodic axes: along each axis with a positive length, a grain leaving
/// `[origin, origin + length)` on one side comes back on the other, and
/// grains near opposite faces touch across them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Periodic<const D: usize> {
    pub origin: Vector<D>,
    /// Period along each axis; zero for an axis that is not periodic.
    pub lengths: [f64; D],
}

impl<const D: usize> Periodic<D> {
    /// Puts a position back into the periodic cell.
    #[inline]
    pub fn wrap(&self, x: &mut Vector<D>) {
        for d in 0..D {
            let l = self.lengths[d];
            if l > 0.0 {
                let offset = ((x[d] - self.origin[d]) / l).floor();
                if offset != 0.0 {
                    x[d] -= offset * l;
                }
            }
        }
    }

    /// The shortest period, for checking that a pair can meet only one
    /// image of the other grain.
    pub fn shortest(&self) -> f64 {
        self.lengths
            .iter()
            .copied()
            .filter(|l| *l > 0.0)
            .fold(f64::INFINITY, f64::min)
    }

    /// Calls `f` with every shift `s ≠ 0` for which the image `x + s` of a
    /// grain at (wrapped) `x` lies within `reach` of the periodic cell.
    pub fn for_each_image(&self, x: &Vector<D>, reach: f64, mut f: impl FnMut(Vector<D>)) {
        // Per axis: the shifts worth trying (0 always, ±L near a face).
        let mut options = [[0.0f64; 2]; D];
        let mut count = [1usize; D];
        for d in 0..D {
            let l = self.lengths[d];
            if l <= 0.0 {
                continue;
            }
            let u = x[d] - self.origin[d];
            if u < reach {
                options[d][0] = l;
                count[d] = 2;
            } else if u > l - reach {
                options[d][0] = -l;
                count[d] = 2;
            }
        }
        let combos: usize = count.iter().product();
        for code in 1..combos {
            let mut shift = Vector::<D>::zeros();
            let mut rest = code;
            for d in 0..D {
                if count[d] == 2 {
                    if rest % 2 == 1 {
                        shift[d] = options[d][0];
                    }
                    rest /= 2;
                }
            }
            f(shift);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping_and_images_across_the_faces() {
        let p = Periodic::<3> {
            origin: Vector::<3>::zeros(),
            lengths: [1.0, 2.0, 0.0],
        };
        let mut x = Vector::<3>::new(1.25, -0.5, 7.0);
        p.wrap(&mut x);
        assert!((x - Vector::<3>::new(0.25, 1.5, 7.0)).norm() < 1e-15);
        // near the lower x face and the upper y face: three images
        let mut shifts = Vec::new();
        p.for_each_image(&Vector::<3>::new(0.1, 1.95, 0.0), 0.2, |s| shifts.push(s));
        assert_eq!(shifts.len(), 3);
        assert!(shifts.contains(&Vector::<3>::new(1.0, -2.0, 0.0)));
        // in the middle: none
        let mut none = 0;
        p.for_each_image(&Vector::<3>::new(0.5, 1.0, 0.0), 0.2, |_| none += 1);
        assert_eq!(none, 0);
        assert_eq!(p.shortest(), 1.0);
    }
}

//! The dimension seam: everything that differs between discs in a plane and
//! spheres in space lives behind [`Space`].
//!
//! Positions, velocities and forces are plain `nalgebra` vectors of length `D`;
//! nalgebra implements their arithmetic for every `D`. What does *not* carry
//! over is the tangent space of a contact: in 2D it is one line, so the
//! Cundall–Strack spring is a signed scalar along `s` (the normal turned a
//! quarter turn clockwise, as Lee & Herrmann define it); in 3D it is a plane,
//! and the spring is a vector that must be turned with the contact.

use nalgebra::SVector;
use std::fmt::Debug;
use std::ops::{Add, Mul};

/// A position, velocity or force in `D` dimensions (CGS units).
pub type Vector<const D: usize> = SVector<f64, D>;

/// Marker type naming a dimension; [`Space`] is implemented for `Dim<2>` and `Dim<3>`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Dim<const D: usize>;

/// Dimension-specific geometry of a contact's tangent space.
pub trait Space<const D: usize>: 'static {
    /// The shear state of one contact (displacement or force along the tangent space).
    type Shear: Copy
        + Default
        + Debug
        + PartialEq
        + Send
        + Sync
        + Add<Output = Self::Shear>
        + Mul<f64, Output = Self::Shear>;

    /// The tangential part of `v` for a contact with unit normal `n`.
    fn tangential(v: &Vector<D>, n: &Vector<D>) -> Self::Shear;

    /// The shear quantity `s` as a vector in space for the contact normal `n`.
    fn to_vector(s: Self::Shear, n: &Vector<D>) -> Vector<D>;

    /// Turns a spring stored for an earlier normal into the current tangent
    /// space, keeping its length.
    fn follow_normal(s: Self::Shear, n: &Vector<D>) -> Self::Shear;

    /// Length of a shear quantity.
    fn magnitude(s: Self::Shear) -> f64;
}

/// The clockwise unit tangent `s` of Lee & Herrmann for the normal `n`.
#[inline(always)]
pub fn clockwise_tangent(n: &Vector<2>) -> Vector<2> {
    Vector::<2>::new(n.y, -n.x)
}

impl Space<2> for Dim<2> {
    type Shear = f64;

    #[inline(always)]
    fn tangential(v: &Vector<2>, n: &Vector<2>) -> f64 {
        v.dot(&clockwise_tangent(n))
    }

    #[inline(always)]
    fn to_vector(s: f64, n: &Vector<2>) -> Vector<2> {
        clockwise_tangent(n) * s
    }

    #[inline(always)]
    fn follow_normal(s: f64, _n: &Vector<2>) -> f64 {
        // A scalar along `s` turns with the contact by construction.
        s
    }

    #[inline(always)]
    fn magnitude(s: f64) -> f64 {
        s.abs()
    }
}

impl Space<3> for Dim<3> {
    type Shear = Vector<3>;

    #[inline(always)]
    fn tangential(v: &Vector<3>, n: &Vector<3>) -> Vector<3> {
        v - n * v.dot(n)
    }

    #[inline(always)]
    fn to_vector(s: Vector<3>, _n: &Vector<3>) -> Vector<3> {
        s
    }

    #[inline(always)]
    fn follow_normal(s: Vector<3>, n: &Vector<3>) -> Vector<3> {
        let len = s.norm();
        if len == 0.0 {
            return s;
        }
        let projected = s - n * s.dot(n);
        let plen = projected.norm();
        if plen == 0.0 {
            Vector::<3>::zeros()
        } else {
            projected * (len / plen)
        }
    }

    #[inline(always)]
    fn magnitude(s: Vector<3>) -> f64 {
        s.norm()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clockwise_tangent_is_a_quarter_turn_clockwise() {
        let n = Vector::<2>::new(1.0, 0.0);
        assert_eq!(clockwise_tangent(&n), Vector::<2>::new(0.0, -1.0));
        let n = Vector::<2>::new(0.0, 1.0);
        assert_eq!(clockwise_tangent(&n), Vector::<2>::new(1.0, 0.0));
    }

    #[test]
    fn spring_in_3d_follows_a_turning_normal_with_its_length() {
        let s = Vector::<3>::new(0.0, 2.0, 0.0);
        let n = Vector::<3>::new(0.0, 0.6, 0.8);
        let turned = <Dim<3> as Space<3>>::follow_normal(s, &n);
        assert!((turned.norm() - 2.0).abs() < 1e-12);
        assert!(turned.dot(&n).abs() < 1e-12);
    }
}

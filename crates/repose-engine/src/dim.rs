//! The dimension seam: everything that differs between discs in a plane and
//! spheres in space lives behind [`Space`].
//!
//! Positions, velocities and forces are plain `nalgebra` vectors of length `D`;
//! nalgebra implements their arithmetic for every `D`. What does *not* carry
//! over is the tangent space of a contact: in 2D it is one line, so the
//! Cundall–Strack spring is a signed scalar along `s` (the normal turned a
//! quarter turn clockwise, as Lee & Herrmann define it); in 3D it is a plane,
//! and the spring is a vector that must be turned with the contact.
//!
//! Rotation differs the same way: an angular velocity or a torque is a
//! scalar about the axis normal to the plane in 2D and a vector in 3D
//! ([`Space::Angular`]).

use nalgebra::SVector;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Mul, Neg, Sub};

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
        + Serialize
        + DeserializeOwned
        + Debug
        + PartialEq
        + Send
        + Sync
        + Add<Output = Self::Shear>
        + Sub<Output = Self::Shear>
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

    /// Squared length of a shear quantity.
    fn magnitude_squared(s: Self::Shear) -> f64;

    /// The shear quantity of a pair seen from its other grain (whose
    /// normal is the opposite).
    fn shear_flip(s: Self::Shear) -> Self::Shear;

    /// An angular velocity or torque: a scalar about the out-of-plane axis
    /// in 2D, a vector in 3D.
    type Angular: Copy
        + Default
        + Serialize
        + DeserializeOwned
        + Debug
        + PartialEq
        + Send
        + Sync
        + Add<Output = Self::Angular>
        + Sub<Output = Self::Angular>
        + Neg<Output = Self::Angular>
        + AddAssign
        + Mul<f64, Output = Self::Angular>;

    /// `ω × r`: the velocity a rotation `ω` gives a point at offset `r`.
    fn spin_velocity(omega: Self::Angular, r: &Vector<D>) -> Vector<D>;

    /// `r × F`: the torque of a force `F` applied at offset `r`.
    fn moment(r: &Vector<D>, force: &Vector<D>) -> Self::Angular;

    /// The part of an angular velocity that is not a twist about `n`.
    fn without_twist(omega: Self::Angular, n: &Vector<D>) -> Self::Angular;

    /// Squared length of an angular quantity.
    fn angular_norm_squared(w: Self::Angular) -> f64;

    /// The angular quantity as a plain list (one value in 2D, three in 3D).
    fn angular_components(w: Self::Angular) -> Vec<f64>;

    /// Reads an angular quantity from a plain list; `None` if its length is wrong.
    fn angular_from(values: &[f64]) -> Option<Self::Angular>;

    /// The angular quantity as three numbers (2D: the value, then zeros).
    fn angular_array(w: Self::Angular) -> [f64; 3];

    /// The inverse of [`Space::angular_array`].
    fn angular_from_array(a: [f64; 3]) -> Self::Angular;
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
    fn magnitude_squared(s: f64) -> f64 {
        s * s
    }

    /// A scalar along the clockwise tangent of `n`: seen from the other
    /// grain both the displacement and the tangent turn round, the scalar stays.
    fn shear_flip(s: f64) -> f64 {
        s
    }

    #[inline(always)]
    fn magnitude(s: f64) -> f64 {
        s.abs()
    }

    type Angular = f64;

    #[inline(always)]
    fn spin_velocity(omega: f64, r: &Vector<2>) -> Vector<2> {
        Vector::<2>::new(-omega * r.y, omega * r.x)
    }

    #[inline(always)]
    fn moment(r: &Vector<2>, force: &Vector<2>) -> f64 {
        r.x * force.y - r.y * force.x
    }

    #[inline(always)]
    fn without_twist(omega: f64, _n: &Vector<2>) -> f64 {
        // In the plane every rotation rolls; there is no twist about n.
        omega
    }

    #[inline(always)]
    fn angular_norm_squared(w: f64) -> f64 {
        w * w
    }

    fn angular_components(w: f64) -> Vec<f64> {
        vec![w]
    }

    fn angular_from(values: &[f64]) -> Option<f64> {
        match values {
            [w] => Some(*w),
            _ => None,
        }
    }

    #[inline(always)]
    fn angular_array(w: f64) -> [f64; 3] {
        [w, 0.0, 0.0]
    }

    #[inline(always)]
    fn angular_from_array(a: [f64; 3]) -> f64 {
        a[0]
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
        let along = s.dot(n);
        if along == 0.0 {
            return s;
        }
        // |s − (s·n) n|² = |s|² − (s·n)²: one square root rescales it.
        let len2 = s.norm_squared();
        let plen2 = len2 - along * along;
        if plen2 <= 0.0 {
            return Vector::<3>::zeros();
        }
        (s - n * along) * (len2 / plen2).sqrt()
    }

    #[inline(always)]
    fn magnitude_squared(s: Vector<3>) -> f64 {
        s.norm_squared()
    }

    fn shear_flip(s: Vector<3>) -> Vector<3> {
        -s
    }

    #[inline(always)]
    fn magnitude(s: Vector<3>) -> f64 {
        s.norm()
    }

    type Angular = Vector<3>;

    #[inline(always)]
    fn spin_velocity(omega: Vector<3>, r: &Vector<3>) -> Vector<3> {
        omega.cross(r)
    }

    #[inline(always)]
    fn moment(r: &Vector<3>, force: &Vector<3>) -> Vector<3> {
        r.cross(force)
    }

    #[inline(always)]
    fn without_twist(omega: Vector<3>, n: &Vector<3>) -> Vector<3> {
        omega - n * omega.dot(n)
    }

    #[inline(always)]
    fn angular_norm_squared(w: Vector<3>) -> f64 {
        w.norm_squared()
    }

    fn angular_components(w: Vector<3>) -> Vec<f64> {
        w.iter().copied().collect()
    }

    fn angular_from(values: &[f64]) -> Option<Vector<3>> {
        match values {
            [x, y, z] => Some(Vector::<3>::new(*x, *y, *z)),
            _ => None,
        }
    }

    #[inline(always)]
    fn angular_array(w: Vector<3>) -> [f64; 3] {
        [w.x, w.y, w.z]
    }

    #[inline(always)]
    fn angular_from_array(a: [f64; 3]) -> Vector<3> {
        Vector::<3>::new(a[0], a[1], a[2])
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
    fn rotation_in_the_plane_matches_the_z_component_of_the_3d_products() {
        let r2 = Vector::<2>::new(0.3, -0.2);
        let f2 = Vector::<2>::new(1.5, 0.7);
        let r3 = Vector::<3>::new(0.3, -0.2, 0.0);
        let f3 = Vector::<3>::new(1.5, 0.7, 0.0);
        let w = 2.0;
        let m2 = <Dim<2> as Space<2>>::moment(&r2, &f2);
        let m3 = <Dim<3> as Space<3>>::moment(&r3, &f3);
        assert!((m2 - m3.z).abs() < 1e-15);
        let v2 = <Dim<2> as Space<2>>::spin_velocity(w, &r2);
        let v3 = <Dim<3> as Space<3>>::spin_velocity(Vector::<3>::new(0.0, 0.0, w), &r3);
        assert!((v2.x - v3.x).abs() < 1e-15 && (v2.y - v3.y).abs() < 1e-15);
    }

    #[test]
    fn twist_about_the_normal_is_removed() {
        let n = Vector::<3>::new(0.0, 0.0, 1.0);
        let w = Vector::<3>::new(1.0, 2.0, 3.0);
        assert_eq!(
            <Dim<3> as Space<3>>::without_twist(w, &n),
            Vector::<3>::new(1.0, 2.0, 0.0)
        );
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

//! The tangential spring both friction laws carry per contact: its
//! displacement, turned with the contact's tangent plane as the pair moves.

use super::{Shear, Touch};
use crate::dim::{Dim, Space};
use serde::{Deserialize, Serialize};

/// The tangential displacement of one contact (cm in 2D Lee & Herrmann
/// units, m in 3D).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct TangentialSpring<S> {
    pub displacement: S,
}

/// The displacement after a step of length `dt` under the tangential
/// velocity `v`: the stored one turned into the current tangent plane, plus
/// `v dt`.
#[inline(always)]
pub(crate) fn stretched<const D: usize>(
    spring: &TangentialSpring<Shear<D>>,
    v: Shear<D>,
    touch: &Touch<D>,
    dt: f64,
) -> Shear<D>
where
    Dim<D>: Space<D>,
{
    <Dim<D> as Space<D>>::follow_normal(spring.displacement, &touch.normal) + v * dt
}

/// `k |ξ|² / 2`: the energy in the spring at stiffness `k`.
pub(crate) fn energy<const D: usize>(spring: &TangentialSpring<Shear<D>>, k: f64) -> f64
where
    Dim<D>: Space<D>,
{
    let s = <Dim<D> as Space<D>>::magnitude(spring.displacement);
    0.5 * k * s * s
}

/// The spring as the other grain of the pair sees it.
pub(crate) fn flip<const D: usize>(spring: &mut TangentialSpring<Shear<D>>)
where
    Dim<D>: Space<D>,
{
    spring.displacement = <Dim<D> as Space<D>>::shear_flip(spring.displacement);
}

//! Time integrators.
//!
//! Every step is split in two halves around the force evaluation:
//! [`Integrator::predict`] moves positions and velocities to the values at
//! which forces are evaluated, and [`Integrator::correct`] uses the new
//! forces to finish the step. Both schemes below fit that seam.
//!
//! Grains that rotate (see [`Particles::rotating`]) have their angular
//! velocity advanced by the same scheme from their torques; for grains that
//! do not, the angular arrays are empty and no loop visits them.

use crate::dim::{Dim, Space, Vector};
use crate::particles::Particles;
use serde::{Deserialize, Serialize};

pub trait Integrator<const D: usize>:
    Send + std::fmt::Debug + Clone + Serialize + serde::de::DeserializeOwned
where
    Dim<D>: Space<D>,
{
    /// Which scheme this is.
    const SCHEME: Scheme;

    fn new(particles: &Particles<D>, dt: f64) -> Self;

    /// Positions and velocities at which this step's forces are evaluated.
    fn predict(&mut self, particles: &mut Particles<D>, dt: f64);

    /// Finishes the step from the forces (and torques) in `particles`.
    fn correct(&mut self, particles: &mut Particles<D>, dt: f64);

    /// A grain was appended at the end of `particles` with its force set.
    fn on_insert(&mut self, particles: &Particles<D>, dt: f64);

    /// Grains were removed; `keep` says which survived (order preserved).
    fn on_retain(&mut self, keep: &[bool]);

    /// Grains were reordered (see [`Particles::permute`]).
    fn on_permute(&mut self, order: &[usize]);

    /// Velocities or positions were changed from outside: restart the history.
    fn restart(&mut self, particles: &Particles<D>, dt: f64);
}

/// The integration scheme a scene asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// Fifth-order Gear predictor–corrector (the paper's integrator; the reference).
    #[default]
    Gear5,
    /// Velocity Verlet (second order, one force evaluation, the fast option).
    Verlet,
}

impl Scheme {
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Gear5 => "gear5",
            Scheme::Verlet => "verlet",
        }
    }
}

/// Velocity Verlet in kick–drift–kick form. Velocity-dependent forces
/// (damping) are evaluated with the half-step velocity, as most DEM codes
/// (LAMMPS among them) do. That makes the scheme first order once damping
/// acts (second order without it; measured in `tests/convergence.rs`).
/// Evaluating the damping with the predicted end-of-step velocity restores
/// second order, but it also removes the numerical dissipation that lets
/// piles built with the paper's shear spring come to rest: more of them end
/// "not settled". This is the conventional scheme.
#[derive(Debug, Default, Clone, Serialize, Deserialize)]
pub struct VelocityVerlet;

impl VelocityVerlet {
    /// Half a kick of the angular velocities from the torques.
    fn spin_kick<const D: usize>(p: &mut Particles<D>, half: f64)
    where
        Dim<D>: Space<D>,
    {
        // Zipped rather than indexed: no bounds checks, and a loop the
        // compiler can vectorise.
        let spins = p.omega.iter_mut().zip(&p.torque).zip(&p.inv_inertia);
        if p.resting.is_empty() {
            for ((omega, torque), inv_inertia) in spins {
                *omega += *torque * (half * inv_inertia);
            }
        } else {
            for (((omega, torque), inv_inertia), _) in spins.zip(&p.resting).filter(|s| !s.1) {
                *omega += *torque * (half * inv_inertia);
            }
        }
    }

    /// Half a kick of the velocities, and with `dt` a drift of the
    /// positions; grains at rest stay where they are.
    fn kick_drift<const D: usize>(p: &mut Particles<D>, half: f64, dt: Option<f64>)
    where
        Dim<D>: Space<D>,
    {
        type Grain<'a, const D: usize> = (
            ((&'a mut Vector<D>, &'a mut Vector<D>), &'a Vector<D>),
            &'a f64,
        );
        let kick = |(((pos, vel), force), inv_mass): Grain<'_, D>| {
            *vel += *force * (half * inv_mass);
            if let Some(dt) = dt {
                *pos += *vel * dt;
            }
        };
        let grains = p
            .pos
            .iter_mut()
            .zip(&mut p.vel)
            .zip(&p.force)
            .zip(&p.inv_mass);
        if p.resting.is_empty() {
            grains.for_each(kick);
        } else {
            let awake = grains.zip(&p.resting).filter(|g| !g.1);
            awake.for_each(|(grain, _)| kick(grain));
        }
    }
}

impl<const D: usize> Integrator<D> for VelocityVerlet
where
    Dim<D>: Space<D>,
{
    const SCHEME: Scheme = Scheme::Verlet;

    fn new(_particles: &Particles<D>, _dt: f64) -> Self {
        VelocityVerlet
    }

    #[inline]
    fn predict(&mut self, p: &mut Particles<D>, dt: f64) {
        let half = 0.5 * dt;
        Self::kick_drift(p, half, Some(dt));
        if p.rotating() {
            Self::spin_kick(p, half);
        }
    }

    #[inline]
    fn correct(&mut self, p: &mut Particles<D>, dt: f64) {
        let half = 0.5 * dt;
        Self::kick_drift(p, half, None);
        if p.rotating() {
            Self::spin_kick(p, half);
        }
    }

    fn on_insert(&mut self, _particles: &Particles<D>, _dt: f64) {}

    fn on_retain(&mut self, _keep: &[bool]) {}

    fn on_permute(&mut self, _order: &[usize]) {}

    fn restart(&mut self, _particles: &Particles<D>, _dt: f64) {}
}

/// Removes the `width`-wide blocks of `data` whose `keep` flag is false.
fn compact<T: Copy>(data: &mut Vec<T>, keep: &[bool], width: usize) {
    let mut out = 0;
    for (i, &k) in keep.iter().enumerate() {
        if k && (i + 1) * width <= data.len() {
            data.copy_within(i * width..(i + 1) * width, out * width);
            out += 1;
        }
    }
    data.truncate(out * width);
}

/// Gear's corrector coefficients for a second-order equation with six
/// stored derivatives. The first is 3/20 rather than the textbook 3/16
/// because the forces here depend on velocities (damping), the case for
/// which Gear recommends 3/20.
const GEAR5: [f64; 6] = [
    3.0 / 20.0,
    251.0 / 360.0,
    1.0,
    11.0 / 18.0,
    1.0 / 6.0,
    1.0 / 60.0,
];

/// Fifth-order Gear predictor–corrector. Positions and velocities live in
/// [`Particles`]; the scaled higher derivatives `r_k = dt^k/k! d^k x/dt^k`
/// for k = 2..5 live here.
///
/// Rotation runs through the same scheme: the angular velocity is the
/// velocity of an angle that nothing reads (the orientation of a sphere
/// plays no part in its contacts), so `dω/dt = τ/I` is integrated with
/// the coefficients of the translation. That angle and its scaled
/// derivatives, three components each, live in `spin`.
#[derive(Debug, Default, Clone, Serialize, Deserialize)]
pub struct Gear5 {
    /// `[r2 (D values), r3, r4, r5]` for each grain, flattened.
    derivs: Vec<f64>,
    /// `[angle, r2, r3, r4, r5]` of the rotation of each grain (rotating grains only).
    spin: Vec<[[f64; 3]; 5]>,
}

impl Gear5 {
    fn slot<const D: usize>(&mut self, i: usize) -> &mut [f64] {
        &mut self.derivs[i * 4 * D..(i + 1) * 4 * D]
    }

    fn predict_spin<const D: usize>(&mut self, p: &mut Particles<D>, dt: f64)
    where
        Dim<D>: Space<D>,
    {
        let inv_dt = 1.0 / dt;
        for (i, s) in self.spin.iter_mut().enumerate() {
            let mut w = <Dim<D> as Space<D>>::angular_array(p.omega[i]);
            for c in 0..3 {
                let (r2, r3, r4, r5) = (s[1][c], s[2][c], s[3][c], s[4][c]);
                let r1 = w[c] * dt;
                s[0][c] += r1 + r2 + r3 + r4 + r5;
                w[c] = (r1 + 2.0 * r2 + 3.0 * r3 + 4.0 * r4 + 5.0 * r5) * inv_dt;
                s[1][c] = r2 + 3.0 * r3 + 6.0 * r4 + 10.0 * r5;
                s[2][c] = r3 + 4.0 * r4 + 10.0 * r5;
                s[3][c] = r4 + 5.0 * r5;
            }
            p.omega[i] = <Dim<D> as Space<D>>::angular_from_array(w);
        }
    }

    fn correct_spin<const D: usize>(&mut self, p: &mut Particles<D>, dt: f64)
    where
        Dim<D>: Space<D>,
    {
        let half_dt2 = 0.5 * dt * dt;
        let inv_dt = 1.0 / dt;
        for (i, s) in self.spin.iter_mut().enumerate() {
            let scale = half_dt2 * p.inv_inertia[i];
            let tau = <Dim<D> as Space<D>>::angular_array(p.torque[i]);
            let mut w = <Dim<D> as Space<D>>::angular_array(p.omega[i]);
            for c in 0..3 {
                let delta = tau[c] * scale - s[1][c];
                s[0][c] += GEAR5[0] * delta;
                w[c] += GEAR5[1] * delta * inv_dt;
                for k in 1..5 {
                    s[k][c] += GEAR5[k + 1] * delta;
                }
            }
            p.omega[i] = <Dim<D> as Space<D>>::angular_from_array(w);
        }
    }

    /// The spin state of grain `i` started from its current torque.
    fn spin_from_torque<const D: usize>(p: &Particles<D>, i: usize, dt: f64) -> [[f64; 3]; 5]
    where
        Dim<D>: Space<D>,
    {
        let scale = 0.5 * dt * dt * p.inv_inertia[i];
        let tau = <Dim<D> as Space<D>>::angular_array(p.torque[i]);
        let mut s = [[0.0; 3]; 5];
        for c in 0..3 {
            s[1][c] = tau[c] * scale;
        }
        s
    }
}

impl<const D: usize> Integrator<D> for Gear5
where
    Dim<D>: Space<D>,
{
    const SCHEME: Scheme = Scheme::Gear5;

    fn new(particles: &Particles<D>, dt: f64) -> Self {
        let mut g = Gear5::default();
        <Self as Integrator<D>>::restart(&mut g, particles, dt);
        g
    }

    #[inline]
    #[allow(clippy::needless_range_loop)] // r holds D-strided blocks
    fn predict(&mut self, p: &mut Particles<D>, dt: f64) {
        let inv_dt = 1.0 / dt;
        for i in 0..p.len() {
            let r = self.slot::<D>(i);
            for d in 0..D {
                let (r2, r3, r4, r5) = (r[d], r[D + d], r[2 * D + d], r[3 * D + d]);
                let r1 = p.vel[i][d] * dt;
                p.pos[i][d] += r1 + r2 + r3 + r4 + r5;
                p.vel[i][d] = (r1 + 2.0 * r2 + 3.0 * r3 + 4.0 * r4 + 5.0 * r5) * inv_dt;
                r[d] = r2 + 3.0 * r3 + 6.0 * r4 + 10.0 * r5;
                r[D + d] = r3 + 4.0 * r4 + 10.0 * r5;
                r[2 * D + d] = r4 + 5.0 * r5;
            }
        }
        if p.rotating() {
            self.predict_spin(p, dt);
        }
    }

    #[inline]
    #[allow(clippy::needless_range_loop)]
    fn correct(&mut self, p: &mut Particles<D>, dt: f64) {
        let half_dt2 = 0.5 * dt * dt;
        let inv_dt = 1.0 / dt;
        for i in 0..p.len() {
            let scale = half_dt2 * p.inv_mass[i];
            let r = self.slot::<D>(i);
            for d in 0..D {
                let delta = p.force[i][d] * scale - r[d];
                p.pos[i][d] += GEAR5[0] * delta;
                p.vel[i][d] += GEAR5[1] * delta * inv_dt;
                r[d] += GEAR5[2] * delta;
                r[D + d] += GEAR5[3] * delta;
                r[2 * D + d] += GEAR5[4] * delta;
                r[3 * D + d] += GEAR5[5] * delta;
            }
        }
        if p.rotating() {
            self.correct_spin(p, dt);
        }
    }

    fn on_insert(&mut self, p: &Particles<D>, dt: f64) {
        let i = p.len() - 1;
        self.derivs.resize(p.len() * 4 * D, 0.0);
        let r = self.slot::<D>(i);
        r.fill(0.0);
        start_from_force(r, p, i, dt);
        if p.rotating() {
            self.spin.push(Self::spin_from_torque(p, i, dt));
        }
    }

    fn on_retain(&mut self, keep: &[bool]) {
        compact(&mut self.derivs, keep, 4 * D);
        if !self.spin.is_empty() {
            compact(&mut self.spin, keep, 1);
        }
    }

    fn on_permute(&mut self, order: &[usize]) {
        let width = 4 * D;
        let old = std::mem::take(&mut self.derivs);
        self.derivs = order
            .iter()
            .flat_map(|&i| old[i * width..(i + 1) * width].iter().copied())
            .collect();
        if !self.spin.is_empty() {
            self.spin = order.iter().map(|&i| self.spin[i]).collect();
        }
    }

    fn restart(&mut self, p: &Particles<D>, dt: f64) {
        self.derivs.clear();
        self.derivs.resize(p.len() * 4 * D, 0.0);
        for i in 0..p.len() {
            start_from_force(self.slot::<D>(i), p, i, dt);
        }
        self.spin.clear();
        if p.rotating() {
            self.spin
                .extend((0..p.len()).map(|i| Self::spin_from_torque(p, i, dt)));
        }
    }
}

/// Sets `r2 = dt²/2 · F/m` from the current force; higher derivatives stay as they are.
fn start_from_force<const D: usize>(r: &mut [f64], p: &Particles<D>, i: usize, dt: f64)
where
    Dim<D>: Space<D>,
{
    let scale = 0.5 * dt * dt * p.inv_mass[i];
    for (r2, f) in r[..D].iter_mut().zip(p.force[i].iter()) {
        *r2 = f * scale;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::Vector;

    /// One grain under a constant torque: ω grows as τ t / I with both schemes.
    fn spin_up<I: Integrator<3>>() -> f64 {
        let mut p = Particles::<3>::new(true);
        p.push(Vector::<3>::zeros(), Vector::<3>::zeros(), 0.5, 2.0);
        let tau = Vector::<3>::new(0.0, 0.3, -0.1);
        p.torque[0] = tau;
        let dt = 1e-3;
        let mut integ = I::new(&p, dt);
        for _ in 0..1000 {
            integ.predict(&mut p, dt);
            p.torque[0] = tau;
            integ.correct(&mut p, dt);
        }
        let inertia = 0.4 * 2.0 * 0.25;
        (p.omega[0] - tau * (1.0 / inertia)).norm()
    }

    #[test]
    fn a_constant_torque_spins_a_grain_up_linearly() {
        assert!(spin_up::<VelocityVerlet>() < 1e-12);
        assert!(spin_up::<Gear5>() < 1e-12);
    }

    #[test]
    fn grains_without_rotation_carry_no_angular_state() {
        let mut p = Particles::<2>::default();
        p.push(Vector::<2>::zeros(), Vector::<2>::zeros(), 0.1, 1.0);
        let g = <Gear5 as Integrator<2>>::new(&p, 1e-4);
        assert!(p.omega.is_empty() && g.spin.is_empty());
    }
}

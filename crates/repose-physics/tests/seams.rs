//! The contact seam beyond Lee & Herrmann's model: a law that turns the
//! grains and a law that pulls across a gap, run through the engine and
//! checked against mechanics worked out by hand.

use repose_engine::contact::{
    CohesionLaw, Cohesive, ContactLaw, CundallStrack, HertzDamped, NoCohesion, NoRolling, Pairwise,
    Touch,
};
use repose_engine::dim::{Dim, Space, Vector};
use repose_engine::integrate::{Gear5, Integrator, VelocityVerlet};
use repose_engine::particles::Particles;
use repose_engine::simulation::Simulation;
use repose_engine::walls::Wall;
use repose_physics::setup::sphere_mass;

/// Hertz contacts with Coulomb friction whose torques turn the grains.
type Rolling = Pairwise<HertzDamped<true>, CundallStrack<true>, NoRolling, NoCohesion, true>;

fn rolling_law(k_n: f64) -> Rolling {
    Pairwise {
        normal: HertzDamped {
            k_n,
            gamma_n: 200.0,
        },
        tangential: CundallStrack {
            k_s: 2e4,
            gamma_s: 20.0,
            mu: 0.3,
        },
        rolling: NoRolling,
        cohesion: NoCohesion,
    }
}

/// A sphere set sliding without spin on a rough floor: friction slows it
/// and spins it up until it rolls, at 5/7 of its first speed whatever the
/// friction (angular momentum about the contact point is conserved).
fn slide_into_rolling<I: Integrator<3>>() -> (f64, f64) {
    let a = 0.1;
    let m = sphere_mass(1.0, a);
    let g = 981.0;
    // Resting on the floor: the Hertz overlap that carries the weight.
    let k_wall = 2e6;
    let rest = (m * g / k_wall).powf(2.0 / 3.0);
    let mut p = Particles::<3>::new(true);
    let v0 = 20.0;
    p.push(
        Vector::<3>::new(0.0, 0.0, a - rest),
        Vector::<3>::new(v0, 0.0, 0.0),
        a,
        m,
    );
    let floor = Wall::plane(Vector::<3>::zeros(), Vector::<3>::new(0.0, 0.0, 1.0));
    let mut sim: Simulation<3, Rolling, I> = Simulation::new(
        p,
        vec![(floor, rolling_law(k_wall))],
        Vector::<3>::new(0.0, 0.0, -g),
        rolling_law(1e6),
        2e-6,
        0.04,
    );
    // Sliding lasts 2 v0 / (7 μ g) ≈ 0.02 s; run well past it.
    sim.run(40_000).unwrap();
    let v = sim.particles.vel[0].x;
    let spin = sim.particles.omega[0];
    // Rolling without slipping: v = −ω_y a (the sphere turns about +y as it moves to +x).
    (v / v0, spin.y * a / v)
}

#[test]
fn a_sliding_sphere_ends_rolling_at_five_sevenths_of_its_speed() {
    for (name, (ratio, roll)) in [
        ("Gear-5", slide_into_rolling::<Gear5>()),
        ("Verlet", slide_into_rolling::<VelocityVerlet>()),
    ] {
        println!("{name}: v/v0 = {ratio:.5}, ω a / v = {roll:.5}");
        assert!((ratio - 5.0 / 7.0).abs() < 0.005, "{name}: v/v0 = {ratio}");
        assert!((roll - 1.0).abs() < 0.005, "{name}: ω a / v = {roll}");
    }
}

/// A toy attraction: a constant pull within `range` of touching.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ConstantPull {
    force: f64,
    range: f64,
}

impl<const D: usize> CohesionLaw<D> for ConstantPull
where
    Dim<D>: Space<D>,
{
    const ACTIVE: bool = true;

    /// A toy reading of the surfaces: the surface energy's number as the
    /// pull (N), across the attraction's range.
    fn of(surfaces: &Cohesive) -> Self {
        ConstantPull {
            force: surfaces.surface_energy,
            range: surfaces.d_max,
        }
    }

    fn range(&self) -> f64 {
        self.range
    }

    fn attraction(&self, touch: &Touch<D>) -> f64 {
        if touch.overlap >= -self.range {
            self.force
        } else {
            0.0
        }
    }

    fn at_contact(&self, _r_eff: f64) -> f64 {
        self.force
    }

    fn work(&self, _r_eff: f64, depth: f64) -> f64 {
        self.force * (self.range + depth)
    }
}

type Sticky = Pairwise<HertzDamped<true>, CundallStrack<true>, NoRolling, ConstantPull>;

/// Two grains at rest `gap` apart, no gravity; the velocity each has after one step.
fn pulled(gap: f64) -> (f64, f64, usize) {
    let a = 0.1;
    let m = sphere_mass(1.0, a);
    let law: Sticky = Pairwise {
        normal: HertzDamped {
            k_n: 1e6,
            gamma_n: 0.0,
        },
        tangential: CundallStrack {
            k_s: 1e4,
            gamma_s: 0.0,
            mu: 0.3,
        },
        rolling: NoRolling,
        cohesion: ConstantPull {
            force: 2.0,
            range: 0.05,
        },
    };
    let mut p = Particles::<2>::default();
    p.push(Vector::<2>::new(0.0, 0.0), Vector::<2>::zeros(), a, m);
    p.push(
        Vector::<2>::new(2.0 * a + gap, 0.0),
        Vector::<2>::zeros(),
        a,
        m,
    );
    let dt = 1e-5;
    let mut sim: Simulation<2, Sticky, VelocityVerlet> =
        Simulation::new(p, Vec::new(), Vector::<2>::zeros(), law, dt, 0.01);
    sim.step().unwrap();
    let pairs = sim.neighbors.pairs.len();
    (sim.particles.vel[0].x, sim.particles.vel[1].x, pairs)
}

#[test]
fn a_law_with_a_range_pulls_across_a_gap_and_no_further() {
    let m = sphere_mass(1.0, 0.1);
    // 0.03 apart, inside the range: listed, and pulled together by F = 2.
    let (v0, v1, pairs) = pulled(0.03);
    assert_eq!(pairs, 1);
    let dv = 2.0 / m * 1e-5;
    assert!(
        (v0 - dv).abs() < 1e-12 * dv.max(1.0) && (v1 + dv).abs() < 1e-12,
        "{v0} {v1}"
    );
    // 0.055 apart: beyond the range but within range + skin, listed, not pulled.
    let (v0, v1, pairs) = pulled(0.055);
    assert_eq!((pairs, v0, v1), (1, 0.0, 0.0));
    // Far apart: not even listed.
    let (_, _, pairs) = pulled(0.5);
    assert_eq!(pairs, 0);
    // A law without cohesion never looks across a gap.
    const { assert!(!<Rolling as ContactLaw<3>>::ACTS_ACROSS_GAPS) };
    const { assert!(<Sticky as ContactLaw<2>>::ACTS_ACROSS_GAPS) };
}

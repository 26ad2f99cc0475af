//! Order of convergence of the integrators, measured against an independent
//! high-accuracy solution.
//!
//! Smooth case: a grain resting on a floor, started off its equilibrium
//! overlap, rings on its damped Hertz contact without ever leaving it; the
//! force is smooth along the whole path, so each scheme shows its own order.
//! (Head-on collisions are a different matter: the damping force switches
//! on between two steps, a first-order error in the restitution; see
//! `contact_physics.rs`.)

mod common;

use common::rk4_step;
use repose_engine::contact::{Frictionless, HertzDamped, Pairwise};
use repose_engine::dim::Vector;
use repose_engine::integrate::{Gear5, Integrator, VelocityVerlet};
use repose_engine::particles::Particles;
use repose_engine::simulation::Simulation;
use repose_engine::walls::Wall;
use repose_physics::setup::sphere_mass;

const K_WALL: f64 = 2e6;
const G: f64 = 981.0;
const RADIUS: f64 = 0.1;
const DURATION: f64 = 0.01;

fn mass() -> f64 {
    sphere_mass(1.0, RADIUS)
}

/// Height of the grain's centre at `DURATION` by classical RK4 with a tiny step.
fn reference_height(y0: f64, gamma: f64) -> f64 {
    let m = mass();
    let accel = |y: f64, v: f64| {
        let overlap = (RADIUS - y).max(0.0);
        let f = (K_WALL * overlap.powf(1.5) - gamma * m * v).max(0.0);
        f / m - G
    };
    let steps = 2_000_000;
    let h = DURATION / steps as f64;
    let (mut y, mut v) = (y0, 0.0);
    for _ in 0..steps {
        (y, v) = rk4_step(accel, y, v, h);
    }
    y
}

fn engine_height<I: Integrator<2>>(y0: f64, gamma: f64, steps: u64) -> f64 {
    let law = Pairwise::new(
        HertzDamped::<true> {
            k_n: K_WALL,
            gamma_n: gamma,
        },
        Frictionless,
    );
    let mut p = Particles::<2>::default();
    p.push(
        Vector::<2>::new(0.0, y0),
        Vector::<2>::zeros(),
        RADIUS,
        mass(),
    );
    let floor = Wall::plane(Vector::<2>::zeros(), Vector::<2>::new(0.0, 1.0));
    let dt = DURATION / steps as f64;
    let mut sim: Simulation<2, _, I> = Simulation::new(
        p,
        vec![(floor, law)],
        Vector::<2>::new(0.0, -G),
        law,
        dt,
        0.04,
    );
    sim.run(steps).unwrap();
    sim.particles.pos[0].y
}

/// Errors for step counts doubling from `first`, and the observed orders.
fn orders<I: Integrator<2>>(gamma: f64, first: u64, levels: u32) -> (Vec<f64>, Vec<f64>) {
    // Start at half the equilibrium overlap: the grain rings but never leaves the floor.
    let equilibrium = (mass() * G / K_WALL).powf(2.0 / 3.0);
    let y0 = RADIUS - 0.5 * equilibrium;
    let reference = reference_height(y0, gamma);
    let errors: Vec<f64> = (0..levels)
        .map(|k| (engine_height::<I>(y0, gamma, first << k) - reference).abs())
        .collect();
    let orders = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    (errors, orders)
}

fn report(label: &str, errors: &[f64], orders: &[f64]) {
    let sci: Vec<String> = errors.iter().map(|e| format!("{e:.2e}")).collect();
    println!(
        "{label}: errors {} (100 to 1600 steps), orders {orders:.2?}",
        sci.join(" ")
    );
}

#[test]
fn undamped_contact_converges_at_second_order_for_verlet_and_fifth_for_gear() {
    let (ev, ov) = orders::<VelocityVerlet>(0.0, 100, 5);
    let (eg, og) = orders::<Gear5>(0.0, 100, 5);
    report("Verlet, γ_n = 0", &ev, &ov);
    report("Gear-5, γ_n = 0", &eg, &og);
    assert!(
        ov.iter().all(|o| (1.9..2.1).contains(o)),
        "Verlet orders {ov:?}"
    );
    assert!(og[..3].iter().all(|o| *o > 4.5), "Gear-5 orders {og:?}");
}

#[test]
fn damped_contact_drops_both_schemes_to_lower_order_with_gear_far_ahead() {
    // Velocity-dependent forces: Verlet evaluates the damping with the
    // half-step velocity (the conventional choice), which makes it first
    // order; Gear-5's single corrector pass evaluates it with the predicted
    // velocity, which makes it second order asymptotically, still far more
    // accurate than Verlet at the same step.
    let (ev, ov) = orders::<VelocityVerlet>(500.0, 100, 5);
    let (eg, og) = orders::<Gear5>(500.0, 100, 5);
    report("Verlet, γ_n = 500", &ev, &ov);
    report("Gear-5, γ_n = 500", &eg, &og);
    assert!(
        ov.iter().all(|o| (0.9..1.3).contains(o)),
        "Verlet orders {ov:?}"
    );
    assert!(og.iter().all(|o| *o > 1.8), "Gear-5 orders {og:?}");
    assert!(
        eg.iter().zip(&ev).all(|(g, v)| *g < 0.02 * v),
        "Gear-5 {eg:?} against Verlet {ev:?}"
    );
}

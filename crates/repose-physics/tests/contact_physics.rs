//! Contact-level physics checked against independent solutions: binary
//! collisions, energy conservation, friction on an incline, and the
//! bookkeeping of the shear spring.

mod common;

use common::rk4_step;
use repose_engine::contact::{CundallStrack, Frictionless, HertzDamped, Pairwise};
use repose_engine::dim::Vector;
use repose_engine::integrate::{Gear5, Integrator, VelocityVerlet};
use repose_engine::particles::Particles;
use repose_engine::simulation::Simulation;
use repose_engine::walls::Wall;
use repose_physics::setup::{sphere_mass, Stream};
use repose_physics::theory::hertz_contact_time;
use repose_physics::{run, Quiet, Scene};

/// Restitution of a head-on collision from an independent integration of
/// the 1D contact equation `m_e δ'' = −max(0, k δ^{3/2} + γ m_e δ')`, by
/// classical RK4 with 200 000 steps per contact time. The contact ends when
/// the overlap closes or when the (floored) force first vanishes; from then
/// on the grains separate at constant speed.
fn reference_restitution(k: f64, gamma: f64, m_eff: f64, v0: f64) -> f64 {
    let h = hertz_contact_time(k, m_eff, v0) / 200_000.0;
    let accel =
        |d: f64, dv: f64| -((k * d.max(0.0).powf(1.5) + gamma * m_eff * dv).max(0.0)) / m_eff;
    let (mut d, mut dv) = (0.0f64, v0);
    let mut touched = false;
    for _ in 0..10_000_000 {
        (d, dv) = rk4_step(accel, d, dv, h);
        if d > 0.0 {
            touched = true;
        }
        let force_gone = dv < 0.0 && k * d.max(0.0).powf(1.5) + gamma * m_eff * dv <= 0.0;
        if touched && (d <= 0.0 || force_gone) {
            return -dv / v0;
        }
    }
    panic!("reference collision did not end");
}

/// Two equal grains meeting head-on at relative speed `v`, run as a
/// `free_run` scene; returns the measured restitution.
fn scene_restitution(integrator: &str, dt_factor: f64, k_n: f64, gamma_n: f64, v: f64) -> f64 {
    let a = 0.1;
    let m = sphere_mass(1.0, a);
    let t_c = hertz_contact_time(k_n, 0.5 * m, v);
    let scene_text = format!(
        r#"
protocol = "free_run"
gravity = [0.0, 0.0]
duration = {duration}
[contact]
k_n = {k_n}
gamma_n = {gamma_n}
mu = 0.0
gamma_s = 0.0
[numerics]
integrator = "{integrator}"
dt_factor = {dt_factor}
max_overlap = 0.95
[[particles]]
position = [{x1}, 0.0]
velocity = [{v1}, 0.0]
radius = {a}
[[particles]]
position = [{x2}, 0.0]
velocity = [{v2}, 0.0]
radius = {a}
"#,
        duration = 4.0 * t_c,
        x1 = -a - 0.25 * v * t_c,
        x2 = a + 0.25 * v * t_c,
        v1 = 0.5 * v,
        v2 = -0.5 * v,
    );
    let scene = Scene::from_toml(&scene_text, &[]).expect("valid collision scene");
    let report = run(&scene, &mut Quiet).expect("runs");
    assert!(report.outcome.is_completed(), "{:?}", report.outcome);
    let g = report.final_state.expect("final state").grains;
    (g[1].velocity[0] - g[0].velocity[0]) / v
}

/// The damping force jumps from zero to `γ_n m_e v` when a contact opens,
/// between two steps; its impulse is then off by up to `γ_n m_e v dt`, a
/// first-order error of order `γ_n dt`. At the default `dt = t_c / 50` that
/// is 0.6 % for γ_n = 500; at `t_c / 100` it stays below 0.5 % over the
/// paper's range γ_n ≤ 500 (γ_n = 1000 would need `t_c / 200`).
const DT_FACTOR: f64 = 0.01;

#[test]
fn head_on_collision_restitution_matches_the_contact_equation() {
    let a = 0.1;
    let m_eff = 0.5 * sphere_mass(1.0, a);
    let mut worst = [0.0f64; 2];
    let mut failures = Vec::new();
    let all: &[f64] = &[1.0, 10.0, 100.0];
    // The softest grains at 100 cm/s would overlap by more than a radius,
    // which the overlap guard refuses (see tests/extremes.rs).
    let slow: &[f64] = &[1.0, 10.0];
    // The damping error grows as γ_n·dt, and soft contacts last long: at
    // k_n = 10³ the step is set to t_c/200 to keep it under 0.5 %.
    for &(k_n, gamma_n, speeds, dt_factor) in &[
        (1e5, 100.0, all, DT_FACTOR),
        (1e6, 500.0, all, DT_FACTOR),
        (1e6, 50.0, all, DT_FACTOR),
        (1e8, 500.0, all, DT_FACTOR),
        (1e4, 500.0, all, DT_FACTOR),
        (1e3, 500.0, slow, DT_FACTOR / 2.0),
        (1e10, 500.0, all, DT_FACTOR),
        (1e10, 0.0, all, DT_FACTOR),
    ] {
        for &v in speeds {
            let reference = reference_restitution(k_n, gamma_n, m_eff, v);
            for (k, integrator) in ["gear5", "verlet"].into_iter().enumerate() {
                let e = scene_restitution(integrator, dt_factor, k_n, gamma_n, v);
                let rel = (e - reference).abs() / reference;
                worst[k] = worst[k].max(rel);
                let line = format!(
                    "{integrator}: k_n {k_n:e}, γ_n {gamma_n}, v {v}: e = {e:.5}, reference {reference:.5} ({:.3} %)",
                    100.0 * rel
                );
                println!("{line}");
                if rel >= 0.005 {
                    failures.push(line);
                }
            }
        }
    }
    println!(
        "largest restitution error: Gear-5 {:.3} %, Verlet {:.3} %",
        100.0 * worst[0],
        100.0 * worst[1]
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Grains bouncing in a closed box without dissipation or gravity.
fn elastic_gas<I: Integrator<2>>() -> Simulation<2, Pairwise<HertzDamped<true>, Frictionless>, I> {
    let law = Pairwise::new(
        HertzDamped::<true> {
            k_n: 1e6,
            gamma_n: 0.0,
        },
        Frictionless,
    );
    let wall_law = Pairwise::new(
        HertzDamped::<true> {
            k_n: 2e6,
            gamma_n: 0.0,
        },
        Frictionless,
    );
    let mut stream = Stream::new(5);
    let mut p = Particles::<2>::default();
    for row in 0..6 {
        for col in 0..6 {
            let r = 0.08 + 0.04 * stream.uniform();
            let x = Vector::<2>::new(0.2 + 0.3 * col as f64, 0.2 + 0.3 * row as f64);
            let v = Vector::<2>::new(stream.uniform() - 0.5, stream.uniform() - 0.5) * 40.0;
            p.push(x, v, r, sphere_mass(1.0, r));
        }
    }
    let walls = vec![
        (
            Wall::plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(0.0, 1.0)),
            wall_law,
        ),
        (
            Wall::plane(Vector::<2>::new(0.0, 0.0), Vector::<2>::new(1.0, 0.0)),
            wall_law,
        ),
        (
            Wall::plane(Vector::<2>::new(1.9, 1.9), Vector::<2>::new(0.0, -1.0)),
            wall_law,
        ),
        (
            Wall::plane(Vector::<2>::new(1.9, 1.9), Vector::<2>::new(-1.0, 0.0)),
            wall_law,
        ),
    ];
    // dt = t_c / 50 for the stiffest contact at the fastest speed present
    let dt = hertz_contact_time(2e6, sphere_mass(1.0, 0.08), 40.0) / 50.0;
    Simulation::new(p, walls, Vector::<2>::zeros(), law, dt, 0.04)
}

fn energy_drift<I: Integrator<2>>() -> (f64, u64) {
    let mut sim = elastic_gas::<I>();
    sim.step().unwrap();
    let e0 = sim.total_energy();
    let mut worst = 0.0f64;
    let steps = 40_000;
    for _ in 0..steps {
        sim.step().unwrap();
        worst = worst.max((sim.total_energy() - e0).abs() / e0);
    }
    (worst, sim.neighbors.builds)
}

#[test]
fn undamped_collisions_conserve_energy() {
    let (gear, builds) = energy_drift::<Gear5>();
    let (verlet, _) = energy_drift::<VelocityVerlet>();
    println!("largest relative energy error over 40 000 steps: Gear-5 {gear:.2e}, Verlet {verlet:.2e} ({builds} list builds)");
    // Many collisions happened: the grains cross the box several times.
    assert!(builds > 50, "only {builds} list builds");
    assert!(gear < 1e-4, "Gear-5 energy error {gear:e}");
    assert!(verlet < 1e-3, "Verlet energy error {verlet:e}");
}

/// A grain resting on a floor under gravity tilted by `alpha` degrees.
fn grain_on_incline(
    alpha: f64,
    mu: f64,
    gamma_s: f64,
    integrator: &str,
    duration: f64,
) -> (f64, f64) {
    let g = 981.0;
    let (s, c) = alpha.to_radians().sin_cos();
    let a = 0.1;
    let m = sphere_mass(1.0, a);
    // start at the static overlap of the floor contact
    let overlap = (m * g * c / 2e6).powf(2.0 / 3.0);
    let scene_text = format!(
        r#"
protocol = "free_run"
gravity = [{gx}, {gy}]
duration = {duration}
[contact]
mu = {mu}
gamma_s = {gamma_s}
[numerics]
integrator = "{integrator}"
[[particles]]
position = [0.0, {y}]
radius = {a}
[[walls]]
point = [0.0, 0.0]
normal = [0.0, 1.0]
"#,
        gx = g * s,
        gy = -g * c,
        y = a - overlap,
    );
    let scene = Scene::from_toml(&scene_text, &[]).expect("valid incline scene");
    let report = run(&scene, &mut Quiet).expect("runs");
    assert!(report.outcome.is_completed(), "{:?}", report.outcome);
    let grain = &report.final_state.unwrap().grains[0];
    (grain.position[0], grain.velocity[0])
}

#[test]
fn grain_on_a_tilted_floor_sticks_below_the_friction_angle() {
    for integrator in ["gear5", "verlet"] {
        // tan 10° = 0.18 < μ = 0.3: the spring holds the grain after a stretch of m g sin α / k_s
        let (x, v) = grain_on_incline(10.0, 0.3, 5.0, integrator, 0.5);
        let m = sphere_mass(1.0, 0.1);
        let stretch = m * 981.0 * 10f64.to_radians().sin() / 1e4;
        // At most the spring's own (lightly damped) oscillation about that stretch.
        let omega = (1e4 / m).sqrt();
        assert!(
            x.abs() < 2.0 * stretch,
            "{integrator}: moved {x} cm (spring stretch {stretch})"
        );
        assert!(
            v.abs() < 2.0 * stretch * omega,
            "{integrator}: sliding at {v} cm/s"
        );
    }
}

#[test]
fn grain_on_a_tilted_floor_slides_above_the_friction_angle_at_the_damped_speed() {
    // tan 25° = 0.47 > μ = 0.3. Sliding: dv/dt = g (sin α − μ cos α) − γ_s v,
    // so v(t) = v∞ (1 − e^{−γ_s t}) with v∞ = g (sin α − μ cos α) / γ_s.
    let (alpha, mu, gamma_s, t) = (25.0f64, 0.3, 20.0, 0.2);
    let (s, c) = alpha.to_radians().sin_cos();
    let v_inf = 981.0 * (s - mu * c) / gamma_s;
    let expected_v = v_inf * (1.0 - (-gamma_s * t).exp());
    let expected_x = v_inf * (t - (1.0 - (-gamma_s * t).exp()) / gamma_s);
    for integrator in ["gear5", "verlet"] {
        let (x, v) = grain_on_incline(alpha, mu, gamma_s, integrator, t);
        assert!(
            (v - expected_v).abs() / expected_v < 0.01,
            "{integrator}: v = {v}, expected {expected_v}"
        );
        assert!(
            (x - expected_x).abs() / expected_x < 0.01,
            "{integrator}: x = {x}, expected {expected_x}"
        );
    }
}

type Strack = Pairwise<HertzDamped<true>, CundallStrack<false>>;

/// Two grains pressed together by their approach, sliding past each other.
fn glancing_pair<I: Integrator<2>>() -> Simulation<2, Strack, I> {
    let law = Pairwise::new(
        HertzDamped::<true> {
            k_n: 1e6,
            gamma_n: 500.0,
        },
        CundallStrack::<false> {
            k_s: 1e4,
            gamma_s: 5.0,
            mu: 0.5,
        },
    );
    let mut p = Particles::<2>::default();
    let m = sphere_mass(1.0, 0.1);
    p.push(
        Vector::<2>::new(0.0, 0.0),
        Vector::<2>::new(1.0, 0.5),
        0.1,
        m,
    );
    p.push(
        Vector::<2>::new(0.2 - 1e-4, 0.0),
        Vector::<2>::new(-1.0, -0.5),
        0.1,
        m,
    );
    Simulation::new(p, Vec::new(), Vector::<2>::zeros(), law, 1e-5, 0.04)
}

#[test]
fn shear_spring_survives_list_rebuilds_and_is_removed_on_separation() {
    let mut plain = glancing_pair::<Gear5>();
    let mut rebuilt = glancing_pair::<Gear5>();
    let mut saw_spring = false;
    for _ in 0..2_000 {
        plain.step().unwrap();
        rebuilt.step().unwrap();
        rebuilt.rebuild_lists();
        let spring = plain.neighbors.history[0].0.displacement;
        assert_eq!(
            spring.to_bits(),
            rebuilt.neighbors.history[0].0.displacement.to_bits()
        );
        assert_eq!(plain.particles.pos, rebuilt.particles.pos);
        saw_spring |= spring != 0.0;
    }
    assert!(saw_spring, "the contact never loaded its spring");
    assert!(rebuilt.neighbors.builds > 1000 && plain.neighbors.builds < 10);
    // The grains have bounced apart: the contact is open and its spring is gone.
    let gap = (plain.particles.pos[0] - plain.particles.pos[1]).norm() - 0.2;
    assert!(gap > 0.0, "still touching");
    if let Some(h) = plain.neighbors.history.first() {
        assert_eq!(h.0.displacement, 0.0);
    }
}

#[test]
fn spheres_in_3d_rebound_like_discs_in_2d() {
    // The engine is generic over the dimension: the same head-on collision
    // along x in 3D gives the same restitution as in 2D.
    let law = Pairwise::new(
        HertzDamped::<true> {
            k_n: 1e6,
            gamma_n: 500.0,
        },
        CundallStrack::<false> {
            k_s: 1e4,
            gamma_s: 5.0,
            mu: 0.2,
        },
    );
    let m = sphere_mass(1.0, 0.1);
    let mut p3 = Particles::<3>::default();
    p3.push(
        Vector::<3>::new(-0.101, 0.0, 0.0),
        Vector::<3>::new(5.0, 0.0, 0.0),
        0.1,
        m,
    );
    p3.push(
        Vector::<3>::new(0.101, 0.0, 0.0),
        Vector::<3>::new(-5.0, 0.0, 0.0),
        0.1,
        m,
    );
    let mut s3: Simulation<3, _, Gear5> =
        Simulation::new(p3, Vec::new(), Vector::<3>::zeros(), law, 1e-5, 0.04);
    let mut p2 = Particles::<2>::default();
    p2.push(
        Vector::<2>::new(-0.101, 0.0),
        Vector::<2>::new(5.0, 0.0),
        0.1,
        m,
    );
    p2.push(
        Vector::<2>::new(0.101, 0.0),
        Vector::<2>::new(-5.0, 0.0),
        0.1,
        m,
    );
    let mut s2: Simulation<2, _, Gear5> =
        Simulation::new(p2, Vec::new(), Vector::<2>::zeros(), law, 1e-5, 0.04);
    s3.run(1_000).unwrap();
    s2.run(1_000).unwrap();
    let e3 = (s3.particles.vel[1].x - s3.particles.vel[0].x) / 10.0;
    let e2 = (s2.particles.vel[1].x - s2.particles.vel[0].x) / 10.0;
    assert!(e2 > 0.3 && e2 < 1.0, "{e2}");
    assert_eq!(e3.to_bits(), e2.to_bits());
}

//! The 3D contact model of Elekes & Parteli against independent solutions:
//! restitution of head-on collisions (an ODE integrated here), rolling and
//! sliding on an incline (Newton's laws for a rigid sphere), rolling
//! resistance, van der Waals forces across a gap, pull-off and capture,
//! conservation of energy and angular momentum, and the order of
//! convergence of both integrators.

mod common;

use common::rk4_step;
use repose_engine::contact::{
    CohesionLaw, ContactLaw, Epsd2, NoCohesion, NoRolling, RollingLaw, VanDerWaals,
};
use repose_engine::dim::Vector;
use repose_engine::integrate::{Gear5, Integrator, VelocityVerlet};
use repose_engine::particles::Particles;
use repose_engine::simulation::Simulation;
use repose_engine::walls::Wall;
use repose_physics::models::elekes_parteli::{self, law, Kind, Law, Parts};
use repose_physics::models::Build;
use repose_physics::Scene;

const D: f64 = 1e-3;
const RHO: f64 = 2500.0;

fn mass() -> f64 {
    std::f64::consts::PI / 6.0 * RHO * D * D * D
}

/// Grain–grain and grain–plate parts for a material given as overrides
/// (glass beads of 1 mm otherwise), for a scene stepped finely (Gear-5):
/// the tests below step their collisions themselves.
fn parts(material: &[&str]) -> (Parts, Parts) {
    let mut o = vec!["numerics.integrator=\"gear5\""];
    o.extend_from_slice(material);
    scene_parts(&o)
}

/// A one-grain scene with the given overrides, in the contact form as the
/// paper prints it (limits on the repulsion, the attraction constant in
/// contact), for which the closed forms below are written; a test of
/// another form says so in its overrides.
fn scene(overrides: &[&str]) -> Scene {
    let base = "protocol = \"free_run\"\ndimension = 3\nduration = 1.0\n\
                [material]\nlimit_load = \"contact\"\ncontact_attraction = \"constant\"\n\
                [[particles]]\nposition = [0.0, 0.0, 0.0]\nradius = 0.0005\n";
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml(base, &o).unwrap()
}

/// The parts of a one-grain scene with the given overrides.
fn scene_parts(overrides: &[&str]) -> (Parts, Parts) {
    elekes_parteli::parts(&scene(overrides)).unwrap()
}

/// A simulation of the given grains (position, velocity), no gravity unless
/// given, with the plate `walls` and the law built from `parts`.
fn sim<R, C, const ROT: bool, I: Integrator<3>>(
    (pair, plate): (Parts, Parts),
    grains: &[(Vector<3>, Vector<3>)],
    walls: Vec<Wall<3>>,
    gravity: Vector<3>,
    dt: f64,
) -> Simulation<3, Law<R, C, ROT>, I>
where
    R: Build<Parts> + RollingLaw<3>,
    C: Build<Parts> + CohesionLaw<3>,
{
    let mut p = Particles::<3>::new(ROT);
    for (x, v) in grains {
        p.push(*x, *v, 0.5 * D, mass());
    }
    let wall_law = law::<R, C, ROT>(&plate);
    let walls = walls.into_iter().map(|w| (w, wall_law)).collect();
    Simulation::new(p, walls, gravity, law::<R, C, ROT>(&pair), dt, 0.1 * D)
}

/// Collision time of a grain–grain contact at `speed` for the parts' stiffness.
fn collision_time(p: &Parts, speed: f64) -> f64 {
    let k = p.normal.modulus * (0.25 * D).sqrt();
    3.21 * (0.5 * mass() / k).powf(0.4) * speed.powf(-0.2)
}

/// Two grains `gap` apart closing head-on at relative speed `v`.
fn head_on(v: f64, gap: f64) -> [(Vector<3>, Vector<3>); 2] {
    [
        (
            Vector::<3>::new(-0.5 * (D + gap), 0.0, 0.0),
            Vector::<3>::new(0.5 * v, 0.0, 0.0),
        ),
        (
            Vector::<3>::new(0.5 * (D + gap), 0.0, 0.0),
            Vector::<3>::new(-0.5 * v, 0.0, 0.0),
        ),
    ]
}

/// Restitution of a head-on collision at relative speed `v` stepped by
/// velocity Verlet at `dt`, averaged over eight instants of first contact
/// within a step.
fn verlet_restitution(parts: (Parts, Parts), v: f64, dt: f64) -> f64 {
    let phases = 8;
    let t = collision_time(&parts.0, v);
    let mean = (0..phases)
        .map(|k| {
            let gap = 1e-3 * D + (k as f64 + 0.5) / phases as f64 * v * dt;
            let grains = head_on(v, gap);
            let mut s: Simulation<3, Law<NoRolling, NoCohesion, true>, VelocityVerlet> =
                sim(parts, &grains, vec![], Vector::<3>::zeros(), dt);
            s.run(((gap / v + 2.0 * t) / dt) as u64).unwrap();
            (s.particles.vel[1].x - s.particles.vel[0].x) / v
        })
        .sum::<f64>();
    mean / phases as f64
}

#[test]
fn velocity_verlet_at_the_scenes_own_step_rebounds_with_the_restitution_asked_for() {
    // The default: Verlet at a tenth of the collision time, A_n solved for it.
    let stepped = scene_parts(&["material.surface_energy=0"]);
    let dt = collision_time(&stepped.0, 1.0) / 10.0;
    let e = verlet_restitution(stepped, 1.0, dt);
    // A_n solved on the exact collision rebounds less at that step.
    let exact = parts(&["material.surface_energy=0"]);
    let e_exact = verlet_restitution(exact, 1.0, dt);
    println!("ε at 1 m/s, Verlet at T_col/10: {e:.4} (A_n for the step), {e_exact:.4} (exact A_n)");
    assert!((e - 0.2).abs() < 2e-3, "{e}");
    assert!(e_exact < 0.195, "{e_exact}");
}

/// Restitution of a head-on collision at relative speed `v` in the engine.
fn engine_restitution(parts: (Parts, Parts), v: f64) -> f64 {
    let t = collision_time(&parts.0, v);
    let gap = 1e-3 * D;
    let grains = head_on(v, gap);
    let mut s: Simulation<3, Law<NoRolling, NoCohesion, true>, Gear5> =
        sim(parts, &grains, vec![], Vector::<3>::zeros(), t / 2000.0);
    let steps = ((gap / v + 2.0 * t) / s.dt) as u64;
    s.run(steps).unwrap();
    (s.particles.vel[1].x - s.particles.vel[0].x) / v
}

/// Restitution of the same collision integrated here:
/// `m_eff δ'' = −k_n √δ (δ + (3/2) A_n δ')` while the force pushes.
fn ode_restitution(p: &Parts, v: f64) -> f64 {
    let k = p.normal.modulus * (0.25 * D).sqrt();
    let (m, a) = (0.5 * mass(), p.normal.damping);
    let accel = |d: f64, dd: f64| {
        if d <= 0.0 {
            return 0.0;
        }
        -(k * d.sqrt() * (d + 1.5 * a * dd)).max(0.0) / m
    };
    let h = collision_time(p, v) / 200_000.0;
    let (mut d, mut dd) = (0.0, v);
    loop {
        (d, dd) = rk4_step(accel, d, dd, h);
        if d <= 0.0 || (dd < 0.0 && d + 1.5 * a * dd <= 0.0) {
            return -dd / v;
        }
    }
}

#[test]
fn a_head_on_collision_at_the_impact_speed_has_the_restitution_asked_for() {
    let solved = parts(&["material.surface_energy=0"]);
    let e = engine_restitution(solved, 1.0);
    println!("ε at 1 m/s, solved A_n: {e:.5}");
    assert!((e - 0.2).abs() < 1e-3, "{e}");
    // The Padé form the paper used gives a little less (0.192 in the paper).
    let pade = parts(&["material.surface_energy=0", "material.damping=\"pade\""]);
    let e = engine_restitution(pade, 1.0);
    println!("ε at 1 m/s, Padé A_n: {e:.5}");
    assert!((e - 0.192).abs() < 3e-3, "{e}");
    // Both kinds of contact get their own A_n, so a grain bouncing on the
    // plate has the same restitution: the dimensionless damping is shared.
    let (pair, plate) = parts(&["material.surface_energy=0"]);
    let m: elekes_parteli::Material = Default::default();
    let g = elekes_parteli::Grains::default();
    let number = |kind: Kind, a: f64| a / kind.damping(&m, 1.0);
    let ratio = number(Kind::pair(&g, D), pair.normal.damping)
        / number(Kind::plate(&g, D), plate.normal.damping);
    assert!((ratio - 1.0).abs() < 1e-12, "{ratio}");
}

#[test]
fn restitution_at_other_speeds_and_stiffnesses_follows_the_integrated_collision() {
    for y in ["1e7", "63e9"] {
        let p = parts(&[
            "material.surface_energy=0",
            &format!("material.youngs_modulus={y}"),
        ]);
        let mut last = 1.0;
        for v in [0.1, 1.0, 3.0] {
            let engine = engine_restitution(p, v);
            let ode = ode_restitution(&p.0, v);
            println!("Y = {y}, v = {v}: engine {engine:.5}, ODE {ode:.5}");
            assert!(
                (engine - ode).abs() < 2e-3 * ode.max(0.05),
                "{engine} {ode}"
            );
            // Viscoelastic: faster collisions lose more.
            assert!(engine < last);
            last = engine;
        }
    }
}

/// A sphere released on a plane sloping down along +x at `alpha`;
/// returns its acceleration along the slope and its slip speed at the end.
fn incline<R: Build<Parts> + RollingLaw<3>>(
    parts: (Parts, Parts),
    alpha: f64,
    duration: f64,
) -> (f64, f64, f64) {
    let g = 9.81;
    let n = Vector::<3>::new(alpha.sin(), 0.0, alpha.cos());
    let k = parts.1.normal.modulus * (0.5 * D).sqrt();
    let rest = (mass() * g * alpha.cos() / k).powf(2.0 / 3.0);
    let start = n * (0.5 * D - rest);
    let floor = Wall::plane(Vector::<3>::zeros(), n);
    let dt = collision_time(&parts.0, 1.0) / 50.0;
    let mut s: Simulation<3, Law<R, NoCohesion, true>, VelocityVerlet> = sim(
        parts,
        &[(start, Vector::<3>::zeros())],
        vec![floor],
        Vector::<3>::new(0.0, 0.0, -g),
        dt,
    );
    s.run((duration / dt) as u64).unwrap();
    let p = &s.particles;
    let down = Vector::<3>::new(alpha.cos(), 0.0, -alpha.sin());
    let travel = (p.pos[0] - start).dot(&down);
    let speed = p.vel[0].dot(&down);
    // The contact point moves at v + ω × (−a n); rolling without slip keeps it still.
    let slip = (p.vel[0] + p.omega[0].cross(&(n * (-0.5 * D)))).dot(&down);
    (2.0 * travel / (duration * duration), speed, slip)
}

#[test]
fn a_sphere_rolls_without_slipping_below_the_friction_limit_and_slides_above_it() {
    let g = 9.81;
    let soft = [
        "material.youngs_modulus=1e7",
        "material.surface_energy=0",
        "material.restitution=0.5",
    ];
    let p = parts(&soft);
    // tan α < (7/2) μ_s = 1.75: rolling, a = (5/7) g sin α.
    for degrees in [10.0f64, 30.0, 55.0] {
        let alpha = degrees.to_radians();
        let (a, _, slip) = incline::<NoRolling>(p, alpha, 0.05);
        let expected = 5.0 / 7.0 * g * alpha.sin();
        println!("α = {degrees}°: a = {a:.4} (rolling {expected:.4}), slip speed {slip:.2e}");
        assert!((a - expected).abs() < 0.01 * expected, "{a} {expected}");
        assert!(slip.abs() < 1e-3 * g * 0.05, "{slip}");
    }
    // tan α > 1.75: sliding, a = g (sin α − μ_s cos α), and the contact slips.
    let alpha = 65f64.to_radians();
    let (a, speed, slip) = incline::<NoRolling>(p, alpha, 0.05);
    let expected = g * (alpha.sin() - 0.5 * alpha.cos());
    // Friction spins the sphere up at 5/2 μ_s g cos α (rim speed): the
    // contact slips at the difference.
    let slipping = (expected - 2.5 * 0.5 * g * alpha.cos()) * 0.05;
    println!("α = 65°: a = {a:.4} (sliding {expected:.4}), speed {speed:.4}, slip {slip:.4} (expected {slipping:.4})");
    assert!((a - expected).abs() < 0.01 * expected, "{a} {expected}");
    assert!(
        (slip - slipping).abs() < 0.02 * slipping,
        "{slip} {slipping}"
    );
}

#[test]
fn rolling_resistance_holds_a_sphere_below_its_angle_and_slows_it_above() {
    let g = 9.81;
    let p = parts(&[
        "material.youngs_modulus=1e7",
        "material.surface_energy=0",
        "material.restitution=0.5",
        "material.rolling_friction=0.1",
    ]);
    // tan α < μ_r: the plastic torque never yields, the sphere stays put.
    let (_, speed, _) = incline::<Epsd2>(p, 0.08f64.atan(), 0.1);
    println!("tan α = 0.08: speed after 0.1 s {speed:.2e} m/s");
    assert!(speed.abs() < 1e-4, "{speed}");
    // Above: it rolls with a = (5/7) g (sin α − μ_r cos α).
    let alpha = 0.25f64.atan();
    let (a, _, _) = incline::<Epsd2>(p, alpha, 0.1);
    let expected = 5.0 / 7.0 * g * (alpha.sin() - 0.1 * alpha.cos());
    println!("tan α = 0.25: a = {a:.4} (expected {expected:.4})");
    assert!((a - expected).abs() < 0.03 * expected, "{a} {expected}");
}

/// Two spheres at rest `gap` apart (negative: overlapping), no gravity,
/// each pulled away from the other by `pull`; after `duration`, their gap
/// and the force on the right one (for no duration: the force where they
/// start, after one vanishing step).
fn pair_after(gap: f64, pull: f64, duration: f64) -> (f64, f64) {
    let p = parts(&["material.youngs_modulus=1e8"]);
    let x = 0.5 * (D + gap);
    let grains = [
        (Vector::<3>::new(-x, 0.0, 0.0), Vector::<3>::zeros()),
        (Vector::<3>::new(x, 0.0, 0.0), Vector::<3>::zeros()),
    ];
    let dt = if duration > 0.0 {
        collision_time(&p.0, 0.1) / 100.0
    } else {
        1e-15
    };
    let mut s: Simulation<3, Law<Epsd2, VanDerWaals, true>, VelocityVerlet> =
        sim(p, &grains, vec![], Vector::<3>::zeros(), dt);
    s.particles.set_load(0, Vector::<3>::new(-pull, 0.0, 0.0));
    s.particles.set_load(1, Vector::<3>::new(pull, 0.0, 0.0));
    s.run((duration / dt).max(1.0) as u64).unwrap();
    let q = &s.particles;
    ((q.pos[1].x - q.pos[0].x) - D, s.particles.force[1].x)
}

#[test]
fn van_der_waals_force_across_a_gap_is_the_formula_and_vanishes_beyond_d_max() {
    let (d_min, d_max) = (1.65e-10, 1e-6);
    let hamaker = 24.0 * std::f64::consts::PI * d_min * d_min * 0.05;
    for gap in [1e-9, 1e-8, 1e-7, 9e-7] {
        let (_, force) = pair_after(gap, 0.0, 0.0);
        let expected = hamaker * 0.25 * D / (6.0 * (gap + d_min).powi(2));
        println!(
            "gap {gap:.0e} m: force on the right sphere {force:.4e} N, formula {expected:.4e} N"
        );
        assert!(
            (force + expected).abs() < 1e-9 * expected,
            "{force} {expected}"
        );
    }
    assert_eq!(pair_after(1.1 * d_max, 0.0, 0.0).1, 0.0);
}

#[test]
fn touching_spheres_come_apart_only_under_the_pull_off_force() {
    // A_H R_eff / (6 D_min²) = π γ d for two spheres of diameter d.
    let pull_off = std::f64::consts::PI * 0.05 * D;
    let (gap, _) = pair_after(0.0, 0.95 * pull_off, 2e-3);
    println!("pulled with 0.95 F_po: gap {gap:.3e} m");
    assert!(gap < 0.0, "{gap}");
    let (gap, _) = pair_after(0.0, 1.05 * pull_off, 2e-3);
    println!("pulled with 1.05 F_po: gap {gap:.3e} m");
    assert!(gap > 1e-6, "{gap}");
}

#[test]
fn spheres_released_just_inside_the_range_close_the_gap_and_stick() {
    // The attraction there is a millionth of the contact value: closing
    // the gap takes the better part of a second.
    let (gap, _) = pair_after(0.9e-6, 0.0, 2.0);
    println!("released 0.9 µm apart: gap after 2 s {gap:.3e} m");
    assert!(gap < 0.0, "{gap}");
}

/// Two cohesive spheres of Y = 100 MPa that do not rotate, touching at rest
/// (one more material override given), and the step they run with.
fn touching_pair(
    material: &str,
) -> (
    Simulation<3, Law<NoRolling, VanDerWaals, false>, VelocityVerlet>,
    f64,
) {
    let p = parts(&["material.youngs_modulus=1e8", material]);
    let grains = [
        (Vector::<3>::new(-0.5 * D, 0.0, 0.0), Vector::<3>::zeros()),
        (Vector::<3>::new(0.5 * D, 0.0, 0.0), Vector::<3>::zeros()),
    ];
    let dt = collision_time(&p.0, 0.1) / 100.0;
    (sim(p, &grains, vec![], Vector::<3>::zeros(), dt), dt)
}

/// The overlap two free spheres settle at under their own attraction
/// (`contact_attraction` as given), started touching at rest.
fn resting_overlap(attraction: &str) -> f64 {
    let mode = format!("material.contact_attraction=\"{attraction}\"");
    let (mut s, dt) = touching_pair(&mode);
    s.run((0.02 / dt) as u64).unwrap();
    D - (s.particles.pos[1].x - s.particles.pos[0].x)
}

#[test]
fn a_fading_contact_attraction_rests_where_hertz_balances_the_hamaker_law_at_the_overlap() {
    // k_n δ^{3/2} = F_0 for the constant attraction F_0 = π γ d;
    // k_n δ^{3/2} = F_0 (D_min / (δ + D_min))² where it fades.
    let p = parts(&["material.youngs_modulus=1e8"]);
    let k = p.0.normal.modulus * (0.25 * D).sqrt();
    let f0 = std::f64::consts::PI * 0.05 * D;
    let d_min = 1.65e-10;
    let constant = (f0 / k).powf(2.0 / 3.0);
    let (mut lo, mut hi) = (0.0, constant);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        let excess = k * mid.powf(1.5) - f0 * (d_min / (mid + d_min)).powi(2);
        if excess > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let fading = 0.5 * (lo + hi);
    let (got_constant, got_fading) = (resting_overlap("constant"), resting_overlap("fading"));
    println!(
        "resting overlap: constant {got_constant:.4e} m (closed form {constant:.4e}), \
         fading {got_fading:.4e} m (closed form {fading:.4e})"
    );
    assert!((got_constant / constant - 1.0).abs() < 1e-3);
    assert!((got_fading / fading - 1.0).abs() < 1e-3);
    assert!(fading < 0.5 * constant);
}

/// Two touching spheres that do not rotate, pressed together by `press`
/// and sheared sideways by `shear` (opposite on each); how far they have
/// slid past each other after `duration`.
fn sheared_pair(limit_load: &str, press: f64, shear: f64, duration: f64) -> f64 {
    let load = format!("material.limit_load=\"{limit_load}\"");
    let (mut s, dt) = touching_pair(&load);
    s.particles
        .set_load(0, Vector::<3>::new(press, -shear, 0.0));
    s.particles
        .set_load(1, Vector::<3>::new(-press, shear, 0.0));
    s.run((duration / dt) as u64).unwrap();
    s.particles.pos[1].y - s.particles.pos[0].y
}

#[test]
fn the_attraction_raises_the_sliding_limit_unless_the_limits_see_the_net_force() {
    // In contact the attraction is π γ d; at rest the repulsion balances it
    // plus whatever presses the pair together.
    let attraction = std::f64::consts::PI * 0.05 * D;
    let mu = 0.5;
    let held = |load: &str, press: f64, shear: f64| {
        let slid = sheared_pair(load, press, shear, 5e-3);
        println!("limits on the {load} force, pressed {press:.2e} N, sheared {shear:.2e} N: slid {slid:.2e} m");
        slid.abs() < 1e-3 * D
    };
    // Eq. 11 as printed: the limit is μ (π γ d + press).
    assert!(held("contact", 0.0, 0.9 * mu * attraction));
    assert!(!held("contact", 0.0, 1.1 * mu * attraction));
    // Net force: the attraction holds the pair together but adds no
    // friction; only the outer pressure does, μ press.
    let press = 0.2 * attraction;
    assert!(!held("net", 0.0, 0.1 * mu * attraction));
    assert!(held("net", press, 0.9 * mu * press));
    assert!(!held("net", press, 1.1 * mu * press));
    // |F_n − F_vdW| (LIGGGHTS ≤ 3.3.1): pressed, as `net`.
    assert!(held("liggghts", press, 0.9 * mu * press));
    assert!(!held("liggghts", press, 1.1 * mu * press));
}

#[test]
fn a_pair_hanging_under_tension_keeps_friction_only_with_the_absolute_net_force() {
    // Pulled apart by a tension T below the pull-off force, the pair rests
    // with the repulsion π γ d − T. As printed the limit is μ (π γ d − T);
    // on the net force floored at zero there is none; on its size, μ T.
    let attraction = std::f64::consts::PI * 0.05 * D;
    let mu = 0.5;
    let tension = 0.3 * attraction;
    let held = |load: &str, shear: f64| {
        let slid = sheared_pair(load, -tension, shear, 5e-3);
        println!("limits on the {load} force, pulled {tension:.2e} N, sheared {shear:.2e} N: slid {slid:.2e} m");
        slid.abs() < 1e-3 * D
    };
    let printed = mu * (attraction - tension);
    assert!(held("contact", 0.9 * printed));
    assert!(!held("contact", 1.1 * printed));
    assert!(!held("net", 0.05 * mu * tension));
    assert!(held("liggghts", 0.9 * mu * tension));
    assert!(!held("liggghts", 1.1 * mu * tension));
}

/// Eight spheres in free space with random velocities and spins, colliding.
fn cloud<R: Build<Parts> + RollingLaw<3>, const ROT: bool>(
    parts: (Parts, Parts),
) -> Simulation<3, Law<R, NoCohesion, ROT>, VelocityVerlet> {
    let mut grains = Vec::new();
    let mut seed = 12345u64;
    let mut uniform = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for k in 0..8 {
        let corner = Vector::<3>::new((k & 1) as f64, ((k >> 1) & 1) as f64, (k >> 2) as f64);
        let x = corner * 1.2 * D + Vector::<3>::new(uniform(), uniform(), uniform()) * 0.1 * D;
        let v = (Vector::<3>::new(0.6, 0.6, 0.6) - corner) * 0.5
            + Vector::<3>::new(uniform(), uniform(), uniform()) * 0.2;
        grains.push((x, v));
    }
    let dt = collision_time(&parts.0, 1.0) / 200.0;
    let mut s = sim(parts, &grains, vec![], Vector::<3>::zeros(), dt);
    if ROT {
        for i in 0..8 {
            s.particles.omega[i] = Vector::<3>::new(uniform(), uniform(), uniform()) * 2000.0;
        }
    }
    s
}

fn angular_momentum<L: ContactLaw<3>>(s: &Simulation<3, L, VelocityVerlet>) -> Vector<3> {
    let p = &s.particles;
    (0..p.len())
        .map(|i| p.pos[i].cross(&p.vel[i]) * p.mass[i] + p.omega[i] / p.inv_inertia[i])
        .sum()
}

#[test]
fn frictional_collisions_without_damping_conserve_energy_and_angular_momentum() {
    // ε = 1: no normal or tangential damping; μ_s = 10: the contacts stick,
    // so the tangential spring stores and returns its energy.
    let p = parts(&[
        "material.youngs_modulus=1e8",
        "material.restitution=1",
        "material.friction=10",
        "material.surface_energy=0",
    ]);
    let mut s = cloud::<NoRolling, true>(p);
    let (e0, l0) = (s.kinetic_energy(), angular_momentum(&s));
    s.run(20_000).unwrap();
    let touching = s.contact_forces().len();
    let (e1, l1) = (s.total_energy(), angular_momentum(&s));
    let rotational = s.particles.rotational_energy();
    println!(
        "energy {e0:.6e} → {e1:.6e} J ({:+.2e}), rotational now {rotational:.3e}, {touching} contacts; |ΔL|/|L| {:.2e}",
        e1 / e0 - 1.0,
        (l1 - l0).norm() / l0.norm()
    );
    assert!((e1 / e0 - 1.0).abs() < 2e-3, "{e0} {e1}");
    assert!(rotational > 1e-3 * e0);
    assert!((l1 - l0).norm() < 1e-10 * l0.norm());
    // Sliding and rolling resistance dissipate energy but no angular momentum.
    let p = parts(&[
        "material.youngs_modulus=1e8",
        "material.restitution=1",
        "material.rolling_friction=0.3",
        "material.surface_energy=0",
    ]);
    let mut s = cloud::<Epsd2, true>(p);
    let (e0, l0) = (s.kinetic_energy(), angular_momentum(&s));
    s.run(20_000).unwrap();
    let (e1, l1) = (s.total_energy(), angular_momentum(&s));
    println!(
        "with sliding and rolling resistance: energy {:+.2e}, |ΔL|/|L| {:.2e}",
        e1 / e0 - 1.0,
        (l1 - l0).norm() / l0.norm()
    );
    assert!(e1 < e0);
    assert!((l1 - l0).norm() < 1e-10 * l0.norm());
}

/// Height of a sphere ringing on the plate (never leaving it) after `t`.
fn plate_height<I: Integrator<3>>(p: (Parts, Parts), z0: f64, t: f64, steps: u64) -> f64 {
    let floor = Wall::plane(Vector::<3>::zeros(), Vector::<3>::new(0.0, 0.0, 1.0));
    let mut s: Simulation<3, Law<NoRolling, NoCohesion, true>, I> = sim(
        p,
        &[(Vector::<3>::new(0.0, 0.0, z0), Vector::<3>::zeros())],
        vec![floor],
        Vector::<3>::new(0.0, 0.0, -9.81),
        t / steps as f64,
    );
    s.run(steps).unwrap();
    s.particles.pos[0].z
}

/// The same by RK4 with a tiny step.
fn plate_reference(p: &Parts, z0: f64, t: f64) -> f64 {
    let k = p.normal.modulus * (0.5 * D).sqrt();
    let (m, a) = (mass(), p.normal.damping);
    let accel = |z: f64, v: f64| {
        let d = (0.5 * D - z).max(0.0);
        (k * d.sqrt() * (d - 1.5 * a * v)).max(0.0) / m - 9.81
    };
    let steps = 400_000;
    let h = t / steps as f64;
    let (mut z, mut v) = (z0, 0.0);
    for _ in 0..steps {
        (z, v) = rk4_step(accel, z, v, h);
    }
    z
}

fn orders<I: Integrator<3>>(restitution: &str) -> Vec<f64> {
    let p = parts(&[
        "material.youngs_modulus=1e7",
        "material.surface_energy=0",
        restitution,
    ]);
    let k = p.1.normal.modulus * (0.5 * D).sqrt();
    let rest = (mass() * 9.81 / k).powf(2.0 / 3.0);
    let z0 = 0.5 * D - 0.5 * rest;
    let t = 5.0 * collision_time(&p.0, 0.01);
    let reference = plate_reference(&p.1, z0, t);
    let errors: Vec<f64> = (0..5)
        .map(|k| (plate_height::<I>(p, z0, t, 100 << k) - reference).abs())
        .collect();
    let sci: Vec<String> = errors.iter().map(|e| format!("{e:.2e}")).collect();
    println!("{restitution}: errors {}", sci.join(" "));
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

#[test]
fn both_integrators_converge_at_their_order_on_a_smooth_contact() {
    let verlet = orders::<VelocityVerlet>("material.restitution=1");
    let gear = orders::<Gear5>("material.restitution=1");
    println!("undamped: Verlet orders {verlet:.2?}, Gear-5 orders {gear:.2?}");
    assert!(verlet.iter().all(|o| (1.9..2.1).contains(o)), "{verlet:?}");
    // (Gear-5 reaches rounding error after two halvings.)
    assert!(gear[..2].iter().all(|o| *o > 4.5), "{gear:?}");
    let verlet = orders::<VelocityVerlet>("material.restitution=0.3");
    let gear = orders::<Gear5>("material.restitution=0.3");
    println!("damped: Verlet orders {verlet:.2?}, Gear-5 orders {gear:.2?}");
    assert!(verlet.iter().all(|o| (0.9..1.3).contains(o)), "{verlet:?}");
    assert!(gear.iter().all(|o| *o > 1.8), "{gear:?}");
}

/// Whether two cohesive spheres of the material given (glass beads of
/// 1 mm otherwise) meeting head-on at `v` stay together.
fn sticks(material: &[&str], v: f64) -> bool {
    let p = parts(material);
    let d_max = 1e-6;
    let gap = 1.05 * d_max;
    let t = collision_time(&p.0, v);
    let dt = t / 200.0;
    let grains = head_on(v, gap);
    let mut s: Simulation<3, Law<NoRolling, VanDerWaals, false>, VelocityVerlet> =
        sim(p, &grains, vec![], Vector::<3>::zeros(), dt);
    // Long enough to meet, part at a twentieth of the speed, and pass D_max.
    let steps = ((gap + 20.0 * d_max) / v / dt + 10.0 * t / dt) as u64;
    s.run(steps).unwrap();
    let q = &s.particles;
    (q.pos[1].x - q.pos[0].x) - D < d_max
}

/// The speed below which head-on collisions stick, by bisection in log v.
fn sticking_speed(material: &[&str]) -> f64 {
    let (mut lo, mut hi) = (1e-6f64, 10.0f64);
    assert!(sticks(material, lo) && !sticks(material, hi));
    for _ in 0..24 {
        let mid = (lo * hi).sqrt();
        if sticks(material, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo * hi).sqrt()
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn softening_raises_the_sticking_speed_and_the_restitution_rule_lowers_it_again() {
    let glass = sticking_speed(&[]);
    let soft = sticking_speed(&["material.youngs_modulus=6.3e7"]);
    let ruled = sticking_speed(&[
        "material.youngs_modulus=6.3e7",
        "material.cohesion_scaling=\"restitution\"",
    ]);
    println!(
        "sticking speed of 1 mm glass: {glass:.3e} m/s; at 63 MPa {soft:.3e} m/s, \
         with ε (Y_true/Y)^(1/5) {ruled:.3e} m/s"
    );
    // Softening a thousandfold deepens the cohesive well: collisions stick
    // at speeds more than ten times glass's (measured 19×) ...
    assert!(soft > 10.0 * glass, "{soft} {glass}");
    // ... and the raised restitution (0.80) brings most of that back, not
    // all of it (measured 2.2× glass's): the collision's damping time
    // grows with the softening too (docs/model-3d.md).
    assert!(
        ruled < soft / 5.0 && ruled > glass,
        "{ruled} {soft} {glass}"
    );
}

/// Two touching cohesive spheres, the right one spinning at 100 rad/s about
/// `axis`, after `duration`: the spin of each.
fn spinning_pair(axis: Vector<3>, duration: f64) -> (Vector<3>, Vector<3>) {
    let p = parts(&["material.youngs_modulus=1e8"]);
    let grains = [
        (Vector::<3>::new(-0.5 * D, 0.0, 0.0), Vector::<3>::zeros()),
        (Vector::<3>::new(0.5 * D, 0.0, 0.0), Vector::<3>::zeros()),
    ];
    let dt = collision_time(&p.0, 0.1) / 100.0;
    let mut s: Simulation<3, Law<Epsd2, VanDerWaals, true>, VelocityVerlet> =
        sim(p, &grains, vec![], Vector::<3>::zeros(), dt);
    s.particles.omega[1] = 100.0 * axis;
    s.run((duration / dt) as u64).unwrap();
    (s.particles.omega[0], s.particles.omega[1])
}

#[test]
fn nothing_resists_a_twist_about_the_contact_normal() {
    // Eqs. 11 and 15 act on the sliding and the rolling of a contact, not on
    // its twist: a grain spinning about the line of centres keeps its spin,
    // as the grains of a settled column that hang from one contact do.
    let (still, twisting) = spinning_pair(Vector::<3>::x(), 0.05);
    println!("twist: ω = {still:?}, {twisting:?}");
    assert!((twisting.x - 100.0).abs() < 1e-9, "{twisting:?}");
    assert!(still.norm() < 1e-9, "{still:?}");
    // The same spin across the contact is taken up by friction and rolling
    // resistance: the pair turns as one body, whose spin keeps the angular
    // momentum (2/5) m r² · 100 on the dimer's 2 (2/5 + 1) m r², 100/7 rad/s
    // (each grain rocking about it on the undamped rolling spring).
    let (a, b) = spinning_pair(Vector::<3>::z(), 0.05);
    println!("across: ω = {a:?}, {b:?}");
    for w in [a, b] {
        assert!((w.z / (100.0 / 7.0) - 1.0).abs() < 0.05, "{a:?} {b:?}");
    }
}

/// How far the speed at which two grains part after an undamped cohesive
/// head-on collision at `v`, stepped by Verlet at `dt`, misses `v` (root
/// mean square over `phases` instants of first contact within a step).
/// They start and end beyond the attraction's reach and nothing
/// dissipates, so energy conservation asks for no difference at all.
fn cohesive_rebound_error(parts: (Parts, Parts), v: f64, dt: f64, phases: usize) -> f64 {
    let d_max = 1e-6;
    let t = collision_time(&parts.0, v);
    let squares: f64 = (0..phases)
        .map(|k| {
            let gap = 1.05 * d_max + (k as f64 + 0.5) / phases as f64 * v * dt;
            let mut s: Simulation<3, Law<NoRolling, VanDerWaals, false>, VelocityVerlet> =
                sim(parts, &head_on(v, gap), vec![], Vector::<3>::zeros(), dt);
            s.run(((gap + 2.0 * d_max) / v / dt + 3.0 * t / dt) as u64)
                .unwrap();
            let parting = s.particles.vel[1].x - s.particles.vel[0].x;
            (parting - v).powi(2)
        })
        .sum();
    (squares / phases as f64).sqrt()
}

#[test]
fn the_attraction_kick_per_step_is_the_energy_error_of_a_cohesive_collision() {
    // Softened glass under a low gravity, so that the default step lets the
    // contact attraction kick a pair by more than √(g d) in one step.
    let material = [
        "material.youngs_modulus=1e6",
        "material.restitution=1",
        "gravity=[0.0, 0.0, -9.81e-4]",
    ];
    let coarse = scene(&material);
    let bounded = scene(&[&material[..], &["numerics.attraction_kick=0.5"][..]].concat());
    let scale = (9.81e-4 * D).sqrt();
    let kick = |dt: f64| std::f64::consts::PI * 0.05 * D * dt / (0.5 * mass()) / scale;
    let (dt0, dt1) = (coarse.time_step(), bounded.time_step());
    assert!(kick(dt0) > 1.0, "the default step kicks by {}", kick(dt0));
    assert!((kick(dt1) - 0.5).abs() < 1e-9, "{}", kick(dt1));
    let p = elekes_parteli::parts(&bounded).unwrap();
    let v = 0.5;
    let (e0, e1) = (
        cohesive_rebound_error(p, v, dt0, 8),
        cohesive_rebound_error(p, v, dt1, 8),
    );
    let dry = parts(&[&material[..], &["material.surface_energy=0"][..]].concat());
    let e_dry = cohesive_rebound_error(dry, v, dt0, 8);
    println!(
        "steps {dt0:.3e} / {dt1:.3e} s (kicks {:.3} / {:.3} √(gd)); parting speed off by {:.3e} / {:.3e} √(gd), {:.3e} without cohesion",
        kick(dt0),
        kick(dt1),
        e0 / scale,
        e1 / scale,
        e_dry / scale
    );
    // The error is the attraction's, of the kick's size, and first order in the step.
    assert!(e0 > 3.0 * e_dry, "{e_dry} {e0}");
    assert!(e1 < 0.5 * scale && e0 < kick(dt0) * scale);
    let order = (e0 / e1).ln() / (dt0 / dt1).ln();
    assert!((0.6..1.4).contains(&order), "order {order}");
}

#[test]
fn a_swept_attraction_keeps_a_cohesive_collision_s_energy_at_the_coarse_step() {
    // The collision above at the step that kicks by more than √(g d), the
    // attraction read at the gap (`point`) and averaged over the gaps each
    // step sweeps (`swept`), in both forms of the attraction in contact.
    // Constant in contact, the attraction switches on at the surface: met
    // at 0.5 m/s, eight instants of first contact show it. Fading, it is a
    // spike a few D_min wide that a step of 78 nm (met at 3 mm/s, above
    // the speed at which the pair would stick) lands in at one instant in
    // a few hundred: 4000 instants find those.
    let cases = [("constant", 0.5, 8), ("fading", 3e-3, 4000)];
    let mut results = Vec::new();
    for (form, v, phases) in cases {
        let form = format!("material.contact_attraction=\"{form}\"");
        let material = [
            "material.youngs_modulus=1e6",
            "material.restitution=1",
            "gravity=[0.0, 0.0, -9.81e-4]",
            &form,
        ];
        let point = scene(&material);
        let swept_step = "numerics.attraction_step=\"swept\"";
        let swept = scene(&[&material[..], &[swept_step][..]].concat());
        let dt = point.time_step();
        assert_eq!(swept.time_step(), dt);
        let (p, s) = (
            elekes_parteli::parts(&point).unwrap(),
            elekes_parteli::parts(&swept).unwrap(),
        );
        assert_eq!((p.0.cohesion.sweep, s.0.cohesion.sweep), (0.0, dt));
        assert_eq!(s.1.cohesion.sweep, 0.0, "the plate does not attract");
        let scale = (9.81e-4 * D).sqrt();
        let (e_point, e_swept) = (
            cohesive_rebound_error(p, v, dt, phases),
            cohesive_rebound_error(s, v, dt, phases),
        );
        let dry = parts(&[&material[..], &["material.surface_energy=0"][..]].concat());
        let e_dry = cohesive_rebound_error(dry, v, dt, phases);
        println!(
            "{form}, met at {v} m/s, step {dt:.3e} s: parting speed off by {:.3e} √(gd) \
             at the gap, {:.3e} swept, {:.3e} without cohesion",
            e_point / scale,
            e_swept / scale,
            e_dry / scale
        );
        results.push((form, e_point, e_swept, e_dry));
    }
    // Measured: constant 2.40 at the gap, 1.00 swept, 0.52 dry (the rest
    // is the Hertz onset's own error, which the attraction deepens);
    // fading 0.25, 7.6·10⁻⁴ swept, 2.5·10⁻⁴ dry.
    let (constant, fading) = (&results[0], &results[1]);
    assert!(constant.2 < 0.5 * constant.1, "{constant:?}");
    assert!(constant.2 < 2.5 * constant.3, "{constant:?}");
    assert!(fading.2 < 0.01 * fading.1, "{fading:?}");
    assert!(fading.1 > 100.0 * fading.3, "{fading:?}");
}

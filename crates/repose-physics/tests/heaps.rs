//! Poured heaps and packed columns of spheres (Elekes & Parteli): the
//! protocols end in a measured heap or a recorded outcome, periodic faces
//! are seamless, neither threads nor the spatial renumbering of grains
//! changes what a scene computes, and grains put to rest stay put until a
//! moving grain reaches them. Small, softened scenes: a paper-stiff
//! heap costs 10¹¹ particle-steps.

use repose_engine::contact::{Epsd2, NoCohesion};
use repose_engine::dim::Vector;
use repose_engine::integrate::VelocityVerlet;
use repose_engine::particles::Particles;
use repose_engine::simulation::{Blowup, RestRule, Simulation};
use repose_engine::walls::Wall;
use repose_physics::models::elekes_parteli::{self, law, Law, Parts};
use repose_physics::protocols::heap::{SideView, FOOTPRINT_HEIGHT};
use repose_physics::report::Profile;
use repose_physics::{run, Outcome, Quiet, RunReport, Scene};

/// A small heap of 1 mm glass beads softened to κ = 10⁵ (Y ≈ 2.5 MPa).
const SMALL_HEAP: &str = r#"
protocol = "heap"
preset = "quick"
[material]
surface_energy = 0.0
[heap]
plate = 20
max_grains = 1500
"#;

fn heap(extra: &[&str]) -> RunReport {
    let o: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    let scene = Scene::from_toml(SMALL_HEAP, &o).unwrap();
    run(&scene, &mut Quiet).unwrap()
}

/// The ratio of a run's particle-steps to the protocol's estimate of them.
fn cost_ratio(base: &str, extra: &[&str], report: &RunReport) -> f64 {
    let o: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    let scene = Scene::from_toml(base, &o).unwrap().resolved();
    let estimate = scene.protocol().unwrap().cost(&scene).unwrap();
    report.particle_steps as f64 / estimate
}

/// The outline of a triangle of base `base` and angle `theta` (°) centred on
/// a plate of side `plate` in columns of width `w` (all in d, with d = 1),
/// and a chain of single grains (one diameter high) from its right toe to
/// the plate's edge if `chain`.
fn triangle_profile(plate: f64, base: f64, theta: f64, w: f64, chain: bool) -> Profile {
    let n = (plate / w).round() as usize;
    let x: Vec<f64> = (0..n)
        .map(|k| -0.5 * plate + (k as f64 + 0.5) * w)
        .collect();
    let slope = theta.to_radians().tan();
    let h = x
        .iter()
        .map(|x| {
            let cone = slope * (0.5 * base - x.abs());
            if cone > 0.0 {
                cone
            } else if chain && *x > 0.0 {
                0.98
            } else {
                0.0
            }
        })
        .collect();
    Profile {
        axis: 0,
        cell_width: w,
        x,
        h,
    }
}

#[test]
fn the_footprint_is_the_mound_and_not_a_chain_of_grains_rolled_to_the_edge() {
    let (plate, base, theta, w) = (40.0, 20.0, 30.0, 0.25);
    let bare = SideView::of(&triangle_profile(plate, base, theta, w, false), 1.0, plate).unwrap();
    let chained = SideView::of(&triangle_profile(plate, base, theta, w, true), 1.0, plate).unwrap();
    println!("bare {bare:?}\nwith a chain {chained:?}");
    // The mound above the footprint's height is the triangle's own.
    let cut = base - 2.0 * FOOTPRINT_HEIGHT / theta.to_radians().tan();
    for v in [&bare, &chained] {
        assert!((v.theta_footprint - theta).abs() < 1.0, "{v:?}");
        assert!((v.footprint - cut).abs() <= 2.0 * w, "{v:?}");
        assert!(v.roughness < 0.2, "{v:?}");
    }
    // On the plate the triangle covers a quarter of the square's area.
    let expected = (base * base / (plate * plate) * theta.to_radians().tan()).atan();
    assert!((bare.theta_plate - expected.to_degrees()).abs() < 0.1);
    assert!(chained.theta_plate > bare.theta_plate);
    assert_eq!(bare.edge, 0.0);
    assert!((chained.edge - 0.49).abs() < 1e-9);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_pour_asked_to_stop_at_a_steady_angle_stops_once_the_angle_no_longer_rises() {
    let r = heap(&[
        "seed=2",
        "heap.max_grains=8000",
        "heap.steady_every=500",
        "heap.steady_tolerance=0.5",
    ]);
    assert!(r.outcome.is_completed(), "{:?}", r.outcome);
    let m = |k: &str| r.metric(k).unwrap();
    let readings = &r
        .series
        .iter()
        .find(|c| c.name == "pour_angle")
        .unwrap()
        .points;
    println!(
        "poured {}, θ_r {:.2}°, readings {readings:?}",
        m("grains_poured"),
        m("theta_r")
    );
    assert_eq!(m("pour_steady"), 1.0);
    assert!(m("grains_poured") < 8000.0);
    assert_eq!(r.grains.inserted as f64, m("grains_poured"));
    // It stopped at the first reading that rose by no more than the tolerance.
    let n = readings.len();
    assert!(n >= 2);
    assert!(readings[n - 1][1] - readings[n - 2][1] <= 0.5);
    for w in readings[..n - 1].windows(2) {
        assert!(w[1][1] - w[0][1] > 0.5, "{w:?}");
    }
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_small_cohesionless_heap_stands_at_a_finite_angle_and_repeats_bit_for_bit() {
    let r = heap(&["seed=3"]);
    assert!(r.outcome.is_completed(), "{:?}", r.outcome);
    let m = |k: &str| r.metric(k).unwrap();
    println!(
        "θ_r {:.2}° ± {:.2}°, footprint {:.2}°, {} grains, height {:.1} d, roughness {:.2} d",
        m("theta_r"),
        m("theta_r_sd"),
        m("theta_r_footprint"),
        m("heap_grains"),
        m("heap_height"),
        m("surface_roughness")
    );
    assert!((15.0..35.0).contains(&m("theta_r")));
    assert!(m("theta_r_sd") < 3.0);
    // A heap this small is a low mound on a layer of grains: its footprint
    // angle reads the mound above that layer.
    assert!((0.0..40.0).contains(&m("theta_r_footprint")));
    // The silhouette lies under the columns filled to their highest top by
    // a fraction of a grain over the plate: a fraction of a degree.
    let below = m("theta_r") - m("theta_r_silhouette");
    assert!((0.1..2.0).contains(&below), "silhouette {below:.2}° below");
    assert!(m("edge_height") < 3.0);
    assert_eq!(m("grains_poured"), 1500.0);
    assert_eq!(m("pour_steady"), 0.0);
    assert!(m("heap_grains") > 200.0);
    let g = &r.grains;
    assert_eq!(g.inserted, 1500);
    assert_eq!(g.lost + g.remaining, g.inserted);
    assert_eq!(r.profiles.len(), 2);
    // The estimate a queue ranks samples by is the run's cost within a
    // factor 3 (it cannot know the grains that fall off the plate).
    let ratio = cost_ratio(SMALL_HEAP, &["seed=3"], &r);
    println!("particle-steps / estimate: {ratio:.2}");
    assert!((0.33..3.0).contains(&ratio), "{ratio}");
    // The same scene and seed run again: the same numbers. (A heap this
    // small lists too few pairs for a second thread to share its steps;
    // the tests below share every step of their scenes.)
    let again = heap(&["seed=3"]);
    assert_eq!(again.metrics, r.metrics);
    assert_eq!(again.iterations, r.iterations);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn the_outcomes_of_a_heap_that_cannot_be_measured_say_why() {
    // Softened grains with the full surface energy, in the contact form as
    // eqs. 11, 13 and 15 print it, stick on first touch: they build a tower
    // under the inlet that reaches the top.
    let r = heap(&[
        "material.surface_energy=0.05",
        "material.youngs_modulus=6.3e6",
        "material.contact_attraction=\"constant\"",
        "material.limit_load=\"contact\"",
        "heap.height=16",
        "heap.inlet_floor=8",
        "heap.max_grains=3000",
    ]);
    match &r.outcome {
        Outcome::Unmeasurable { reason } => {
            assert!(reason.contains("crest reached the top"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    assert!(r.metrics.is_empty());
    // A pour given no time to settle.
    let r = heap(&[
        "heap.max_grains=300",
        "heap.settle_min=0",
        "heap.settle_max=0.5",
    ]);
    match &r.outcome {
        Outcome::NotSettled { phase, reason } => {
            assert_eq!(phase, "settle");
            assert!(reason.contains("still moved"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // A step far above the stability limit of Gear-5.
    let r = heap(&["numerics.integrator=\"gear5\"", "numerics.dt_factor=0.4"]);
    match &r.outcome {
        Outcome::Failed { phase, reason } => {
            assert_eq!(phase, "pour");
            assert!(!reason.is_empty());
        }
        other => panic!("{other:?}"),
    }
}

const SMALL_COLUMN: &str =
    "protocol = \"packing\"\npreset = \"quick\"\n[packing]\nwidth = 6\nheight = 30\n";

fn packing(extra: &[&str]) -> RunReport {
    let o: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    run(&Scene::from_toml(SMALL_COLUMN, &o).unwrap(), &mut Quiet).unwrap()
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn spheres_released_in_a_periodic_column_pack_randomly_and_cohesion_loosens_them() {
    let dry = packing(&["material.surface_energy=0"]);
    assert!(dry.outcome.is_completed(), "{:?}", dry.outcome);
    let phi = dry.metric("packing_fraction").unwrap();
    println!(
        "dry: φ = {phi:.3} ± {:.3}",
        dry.metric("packing_fraction_sd").unwrap()
    );
    // Between random loose and random close packing of frictional spheres.
    assert!((0.54..0.66).contains(&phi), "{phi}");
    assert_eq!(dry.grains.lost, 0);
    let ratio = cost_ratio(SMALL_COLUMN, &["material.surface_energy=0"], &dry);
    println!("particle-steps / estimate: {ratio:.2}");
    assert!((0.33..3.0).contains(&ratio), "{ratio}");
    // Softened grains keep their attraction in contact only in the form as
    // printed: the default fades it with the overlap they press into.
    let sticky = packing(&[
        "material.youngs_modulus=6.3e6",
        "grains.diameter=5e-4",
        "material.contact_attraction=\"constant\"",
        "material.limit_load=\"contact\"",
    ]);
    assert!(sticky.outcome.is_completed(), "{:?}", sticky.outcome);
    let loose = sticky.metric("packing_fraction").unwrap();
    println!("cohesive (0.5 mm, γ = 0.05): φ = {loose:.3}");
    assert!(loose < phi - 0.05, "{loose} {phi}");
}

fn parts(extra: &[&str]) -> (Parts, Parts) {
    let base = "protocol = \"free_run\"\ndimension = 3\nduration = 1.0\n\
                [material]\nyoungs_modulus = 1e7\nsurface_energy = 0.0\n\
                [[particles]]\nposition = [0.0, 0.0, 0.0]\nradius = 0.0005\n";
    let o: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    elekes_parteli::parts(&Scene::from_toml(base, &o).unwrap()).unwrap()
}

type Engine = Simulation<3, Law<Epsd2, NoCohesion, true>, VelocityVerlet>;

fn engine(grains: &[(Vector<3>, Vector<3>)], gravity: f64, floor: bool) -> Engine {
    let (pair, plate) = parts(&[]);
    let d = 1e-3;
    let mass = std::f64::consts::PI / 6.0 * 2500.0 * d * d * d;
    let mut p = Particles::<3>::new(true);
    for (x, v) in grains {
        p.push(*x, *v, 0.5 * d, mass);
    }
    let walls = if floor {
        let w = Wall::plane(Vector::<3>::zeros(), Vector::<3>::new(0.0, 0.0, 1.0));
        vec![(w, law(&plate))]
    } else {
        Vec::new()
    };
    let g = Vector::<3>::new(0.0, 0.0, -gravity);
    Simulation::new(p, walls, g, law(&pair), 2e-6, 2e-4)
}

#[test]
fn a_collision_across_a_periodic_face_is_the_same_collision() {
    let v = Vector::<3>::new(0.3, 0.05, 0.0);
    let x = 0.55e-3;
    // Two spheres meeting in the middle of open space ...
    let mut open = engine(
        &[
            (Vector::<3>::new(-x, 0.0, 0.0), v),
            (Vector::<3>::new(x, 0.0, 0.0), -v),
        ],
        0.0,
        false,
    );
    // ... and the same two at the faces of a periodic cell, moving out of it.
    let l = 0.01;
    let mut cell = engine(
        &[
            (Vector::<3>::new(x, 0.005, 0.0), -v),
            (Vector::<3>::new(l - x, 0.005, 0.0), v),
        ],
        0.0,
        false,
    );
    cell.set_periodic(Vector::<3>::zeros(), [l, l, 0.0])
        .unwrap();
    open.run(2000).unwrap();
    cell.run(2000).unwrap();
    let rel = |s: &Engine, a: usize, b: usize| s.particles.vel[a] - s.particles.vel[b];
    let (o, c) = (rel(&open, 1, 0), rel(&cell, 0, 1));
    println!("after: open {o:?}, across the face {c:?}");
    assert!((o - c).norm() < 1e-9 * v.norm(), "{o:?} {c:?}");
    assert!(o.x > 0.0, "they bounced");
    let spin = |s: &Engine, i: usize| s.particles.omega[i];
    assert!((spin(&open, 0) - spin(&cell, 1)).norm() < 1e-6 * spin(&open, 0).norm());
}

/// A bed of spheres on a floor, periodic sideways, settling for a while.
fn bed() -> Engine {
    let d = 1e-3;
    let mut grains = Vec::new();
    for k in 0..1200 {
        let (ix, iy, iz) = (k % 10, (k / 10) % 10, k / 100);
        let jitter = ((k * 7919) % 13) as f64 * 0.01 * d;
        let x = Vector::<3>::new(
            (ix as f64 + 0.5) * 1.2 * d + jitter,
            (iy as f64 + 0.5) * 1.2 * d,
            (iz as f64 + 0.6) * 1.2 * d,
        );
        grains.push((x, Vector::<3>::new(0.0, 0.0, -0.5)));
    }
    let mut s = engine(&grains, 9.81, true);
    s.set_periodic(Vector::<3>::zeros(), [12.0 * d, 12.0 * d, 0.0])
        .unwrap();
    s
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn threads_share_the_pair_and_wall_contacts_without_changing_a_bit() {
    let mut one = bed();
    let mut two = bed();
    two.set_threads(2).unwrap();
    two.min_shared_pairs = 0;
    for s in [&mut one, &mut two] {
        s.sort_every = 500;
        s.run(8000).unwrap();
    }
    let touching = one.contact_forces().len();
    println!("{touching} contacts");
    assert!(touching > 500);
    assert!(
        two.counters.shared_steps >= two.counters.steps,
        "{:?}",
        two.counters
    );
    assert_eq!(one.counters.shared_steps, 0);
    assert_eq!(one.particles.pos, two.particles.pos);
    assert_eq!(one.particles.vel, two.particles.vel);
    assert_eq!(one.particles.omega, two.particles.omega);
    // The list's search is shared too (1200 grains), images included.
    assert_eq!(one.neighbors.pairs, two.neighbors.pairs);
    assert_eq!(one.neighbors.shifts, two.neighbors.shifts);
    assert!(!one.neighbors.shifts.is_empty());
    assert_eq!(one.neighbors.history, two.neighbors.history);
    // The floor's contacts are shared too, each grain with its own share.
    let on_floor = |s: &Engine| {
        s.wall_contacts.history[0]
            .iter()
            .filter(|h| **h != Default::default())
            .count()
    };
    println!("{} grains on the floor", on_floor(&one));
    assert!(on_floor(&one) > 50);
    assert_eq!(one.wall_contacts.history, two.wall_contacts.history);
}

/// A run handed a second thread partway, and a third, then back to one,
/// ends with every bit of the run that kept one thread all along.
#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_run_whose_threads_change_between_steps_keeps_every_bit() {
    let mut one = bed();
    let mut changing = bed();
    changing.min_shared_pairs = 0;
    for s in [&mut one, &mut changing] {
        s.sort_every = 500;
    }
    for threads in [1, 2, 3, 1, 2] {
        changing.set_threads(threads).unwrap();
        assert_eq!(changing.threads(), threads);
        one.run(1500).unwrap();
        changing.run(1500).unwrap();
    }
    assert!(one.contact_forces().len() > 500);
    assert_eq!(one.particles.pos, changing.particles.pos);
    assert_eq!(one.particles.vel, changing.particles.vel);
    assert_eq!(one.particles.omega, changing.particles.omega);
    assert_eq!(one.neighbors.history, changing.neighbors.history);
    assert_eq!(one.wall_contacts.history, changing.wall_contacts.history);
}

/// A grain driven through the floor fails the run with the same grain,
/// wall and time on two threads as on one.
#[test]
fn a_grain_through_the_floor_fails_alike_on_two_threads() {
    let failure = |threads: usize| {
        let mut s = bed();
        s.set_threads(threads).unwrap();
        s.min_shared_pairs = 0;
        s.guards.max_overlap = f64::INFINITY;
        s.run(10).unwrap();
        let last = s.particles.len() - 1;
        s.particles.pos[0].z = -0.1e-3;
        s.particles.pos[last].z = -0.1e-3;
        s.run(5).unwrap_err()
    };
    let one = failure(1);
    assert!(matches!(one, Blowup::ThroughWall { wall: 0, .. }), "{one}");
    assert_eq!(one, failure(2));
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn renumbering_grains_in_space_keeps_every_contact_and_its_springs() {
    let mut s = bed();
    s.run(6000).unwrap();
    s.rebuild_lists();
    let before = (s.elastic_energy(), s.contact_forces().len());
    let ids = s.particles.id.clone();
    s.sort_spatially();
    s.rebuild_lists();
    let after = (s.elastic_energy(), s.contact_forces().len());
    assert_ne!(s.particles.id, ids, "the order changed");
    assert_eq!(before.1, after.1);
    assert!(
        (before.0 - after.0).abs() < 1e-12 * before.0,
        "{before:?} {after:?}"
    );
    // and the run goes on from there
    s.run(100).unwrap();
}

/// A grain on the floor comes to rest after the rule's still steps; at rest
/// it does not move by a bit, a grain that lands on it fast wakes it, and a
/// grain that creeps onto it below the rule's speed does not.
#[test]
fn a_grain_at_rest_stays_put_until_a_moving_grain_wakes_it() {
    let d = 1e-3;
    // A tenth of √(g d): a grain settling into its contact with the one
    // below (by the overlap its weight presses, 0.2 µm here) is slower.
    // Still for 4 ms, twice as long as a grain in flight is that slow.
    let rule = RestRule {
        speed: 1e-2,
        steps: 2000,
    };
    let on_floor = Vector::<3>::new(0.0, 0.0, 0.5 * d);
    let mut s = engine(&[(on_floor, Vector::<3>::zeros())], 9.81, true);
    s.set_rest(Some(rule));
    let mut steps = 0;
    while s.resting() == 0 {
        s.run(1).unwrap();
        steps += 1;
        assert!(steps < 50_000, "never came to rest");
    }
    assert!(steps >= rule.steps as usize, "at rest after {steps} steps");
    let rested = s.particles.pos[0];
    s.run(5000).unwrap();
    assert_eq!(s.particles.pos[0], rested, "a grain at rest does not move");
    assert_eq!(s.particles.vel[0], Vector::<3>::zeros());

    // A grain set down beside it on the floor, creeping towards it at a
    // hundredth of the rule's speed: the resting grain is not woken.
    let side = rested - Vector::<3>::new(d, 0.0, 0.0);
    s.insert(
        side,
        Vector::<3>::new(1e-4, 0.0, 0.0),
        0.5 * d,
        s.particles.mass[0],
    );
    s.run(2000).unwrap();
    assert!(s.particles.resting[0], "woken by a creeping grain");
    assert_eq!(s.particles.pos[0], rested);

    // A third grain dropped from three diameters up lands on its
    // shoulder at about 0.2 m/s.
    let high = rested + Vector::<3>::new(0.9 * d, 0.0, 3.0 * d);
    s.insert(high, Vector::<3>::zeros(), 0.5 * d, s.particles.mass[0]);
    let mut woken = false;
    for _ in 0..20_000 {
        s.run(1).unwrap();
        woken |= !s.particles.resting[0];
    }
    assert!(woken, "the impact woke the grain it struck");
    assert_ne!(s.particles.pos[0], rested, "and they moved");
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn grains_at_rest_change_nothing_between_one_thread_and_two() {
    let rule = RestRule {
        speed: 0.01,
        steps: 200,
    };
    let mut one = bed();
    let mut two = bed();
    two.set_threads(2).unwrap();
    two.min_shared_pairs = 0;
    for s in [&mut one, &mut two] {
        s.set_rest(Some(rule));
        s.sort_every = 500;
        s.run(12_000).unwrap();
    }
    println!("{} of 1200 grains at rest", one.resting());
    assert!(one.resting() > 100);
    assert_eq!(one.particles.resting, two.particles.resting);
    assert_eq!(one.particles.pos, two.particles.pos);
    assert_eq!(one.particles.vel, two.particles.vel);
    assert_eq!(one.particles.omega, two.particles.omega);
    assert_eq!(one.neighbors.history, two.neighbors.history);
}

/// The inlet's fill is part of a scene's identity only when it is not the
/// default, so that every heap stored before the option keeps its hash;
/// an unknown fill is refused by its field; and a pour whose grains
/// straddle the prism's sides pours all it is asked for into a heap.
#[test]
fn the_inlet_fill_is_stored_only_when_asked_for() {
    let stored = |extra: &[&str]| {
        let o: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
        let scene = Scene::from_toml(SMALL_HEAP, &o).unwrap().resolved();
        serde_json::to_value(&scene).unwrap()["heap"].clone()
    };
    assert!(stored(&[]).get("inlet_fill").is_none());
    assert!(stored(&["heap.inlet_fill=\"inside\""])
        .get("inlet_fill")
        .is_none());
    assert_eq!(
        stored(&["heap.inlet_fill=\"centres\""])["inlet_fill"],
        "centres"
    );
    let o = ["heap.inlet_fill=\"edges\"".to_string()];
    let err = Scene::from_toml(SMALL_HEAP, &o).unwrap_err();
    let fields: Vec<&str> = err.errors.iter().map(|e| e.field.as_str()).collect();
    assert_eq!(fields, ["heap.inlet_fill"], "{err:?}");
    let r = heap(&["heap.inlet_fill=\"centres\"", "heap.max_grains=600"]);
    assert_eq!(r.grains.inserted, 600);
    assert!(r.outcome.is_completed(), "{:?}", r.outcome);
}

/// The options that cannot hold are refused, naming the field: grains at
/// rest on the Gear integrator or put to rest in mid-flight, a
/// restitution raised past 1 by softening too far, and a bound on the
/// attraction's kick that is not a positive number or bounds the step below
/// t_c/10⁴, and a plate or a domain too large to grid.
#[test]
fn options_that_cannot_hold_are_refused_by_field() {
    let refused = |extra: &[&str]| {
        let o: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
        let err = Scene::from_toml(SMALL_HEAP, &o).unwrap_err();
        err.errors
            .iter()
            .map(|e| e.field.clone())
            .collect::<Vec<_>>()
    };
    let gear = refused(&["rest.speed=0.01", "numerics.integrator=\"gear5\""]);
    assert!(gear.contains(&"rest.speed".to_string()), "{gear:?}");
    let short = refused(&["rest.speed=0.1", "rest.time=0.1"]);
    assert_eq!(short, vec!["rest.time".to_string()]);
    // Y = 6.3 MPa with glass's γ: ε 0.2 × 10000^{1/5} = 1.26.
    let bouncy = refused(&[
        "material.surface_energy=0.05",
        "material.youngs_modulus=6.3e6",
        "material.cohesion_scaling=\"restitution\"",
    ]);
    assert_eq!(bouncy, vec!["material.cohesion_scaling".to_string()]);
    // A thousandfold is still below 1: accepted.
    let o = [
        "material.surface_energy=0.05",
        "material.youngs_modulus=6.3e7",
        "material.cohesion_scaling=\"restitution\"",
    ]
    .map(String::from);
    assert!(Scene::from_toml(SMALL_HEAP, &o).is_ok());
    for kick in ["0", "-0.5"] {
        let bad = refused(&[&format!("numerics.attraction_kick={kick}")]);
        assert_eq!(bad, vec!["numerics.attraction_kick".to_string()], "{kick}");
    }
    // A kick so small that the step it bounds falls below t_c/10⁴.
    let tiny = refused(&[
        "material.surface_energy=0.05",
        "numerics.attraction_kick=1e-9",
    ]);
    assert_eq!(tiny, vec!["numerics.attraction_kick".to_string()]);
    // A plate or a domain of more than a thousand diameters.
    assert_eq!(
        refused(&["heap.plate=1e12"]),
        vec!["heap.plate".to_string()]
    );
    assert_eq!(
        refused(&["heap.height=1001"]),
        vec!["heap.height".to_string()]
    );
    let skin = refused(&["numerics.skin=1"]);
    assert_eq!(skin, vec!["numerics.skin".to_string()]);
}

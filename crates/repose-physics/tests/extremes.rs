//! The edges of the parameter space: every scene here must either run to a
//! finite answer or end with a clear, recorded reason (or be refused at
//! validation, naming the field). None may panic or report a number from a
//! run that went wrong.

use repose_engine::contact::ContactLaw;
use repose_engine::integrate::Integrator;
use repose_engine::simulation::{Blowup, Simulation};
use repose_physics::models::{with_engine, EngineJob, Laws};
use repose_physics::protocols::pile::{closed_box, BoxSpec, PileSpec};
use repose_physics::protocols::tilt::TiltSpec;
use repose_physics::report::Outcome;
use repose_physics::{run, Quiet, RunReport, Scene};

/// A 1.6 × 1.6 cm box: about 64 grains, well under a second a run.
const SMALL: &str = r#"
protocol = "fill_release"
seed = 1
[box]
width = 1.6
height = 1.6
"#;

fn scene(text: &str, overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml(text, &o).unwrap_or_else(|e| panic!("{overrides:?}: {e}"))
}

fn run_scene(text: &str, overrides: &[&str]) -> RunReport {
    run(&scene(text, overrides), &mut Quiet).expect("validated scenes run")
}

/// A completed run reports finite angles for what its protocol measures; any
/// other outcome carries a reason and no angle from the phase that failed.
fn assert_clean(r: &RunReport, what: &str) {
    match &r.outcome {
        Outcome::Completed => {
            for m in ["theta_r_endpoints", "theta_r_line", "theta_r"] {
                let v = r
                    .metric(m)
                    .unwrap_or_else(|| panic!("{what}: completed without {m}"));
                assert!(v.is_finite() && v.abs() <= 90.0, "{what}: {m} = {v}");
            }
            if let Some(t) = r.metric("theta_t") {
                assert!(t.is_finite() && t >= 0.0, "{what}: θ_T = {t}");
            }
        }
        other => {
            let reason = other.reason().unwrap_or_default();
            assert!(!reason.is_empty(), "{what}: {other:?} without a reason");
            let in_tilt = matches!(other, Outcome::Failed { phase, .. } | Outcome::NotSettled { phase, .. } if phase == "tilt");
            if !in_tilt && !matches!(other, Outcome::NoOnset { .. }) {
                assert!(
                    r.metric("theta_r").is_none(),
                    "{what}: θ_R reported from a failed run"
                );
            }
            assert!(
                r.metric("theta_t").is_none(),
                "{what}: θ_T reported from a failed run"
            );
        }
    }
}

#[test]
fn stiffness_from_1e3_to_1e10_runs_or_fails_with_a_reason() {
    let stiff = run_scene(SMALL, &["contact.k_n=1e10"]);
    assert!(stiff.outcome.is_completed(), "{:?}", stiff.outcome);
    assert_clean(&stiff, "k_n = 1e10");
    let default = scene(SMALL, &[]).time_step();
    // t_c ∝ k^(−2/5): ten thousand times stiffer is about 40 times shorter.
    let ratio = default / stiff.options.dt;
    assert!((30.0..50.0).contains(&ratio), "dt ratio {ratio}");

    // Grains this soft, falling from the filling column, overlap by more than
    // half a radius: the default guard stops the run and says why…
    let soft = run_scene(SMALL, &["contact.k_n=1e3"]);
    assert_clean(&soft, "k_n = 1e3");
    assert_eq!(soft.outcome.status(), "failed", "{:?}", soft.outcome);
    let reason = soft.outcome.reason().unwrap_or_default();
    assert!(reason.contains("overlap"), "{reason}");
    // …and it is the guard that stops it: raised past any overlap, the
    // same grains are not stopped for overlapping.
    let unguarded = run_scene(SMALL, &["contact.k_n=1e3", "numerics.max_overlap=2"]);
    assert_clean(&unguarded, "k_n = 1e3, guard 2");
    let reason = unguarded.outcome.reason().unwrap_or_default();
    assert!(!reason.contains("overlap"), "{reason}");
    // …and k_n = 10⁴ with the guard raised to 1.5 radii (as the stiffness
    // study does) gets its pile.
    let soft = run_scene(SMALL, &["contact.k_n=1e4", "numerics.max_overlap=1.5"]);
    assert_clean(&soft, "k_n = 1e4, guard 1.5");
    assert!(soft.outcome.is_completed(), "{:?}", soft.outcome);
}

#[test]
fn undamped_grains_settle_by_friction_or_say_they_did_not() {
    let r = run_scene(
        SMALL,
        &[
            "contact.gamma_n=0",
            "contact.gamma_s=0",
            "equilibrium.max_fill_time=1.0",
        ],
    );
    assert_clean(&r, "γ_n = 0");
    if !r.outcome.is_completed() {
        assert_eq!(r.outcome.status(), "not_settled", "{:?}", r.outcome);
    }
}

#[test]
fn friction_from_zero_to_five() {
    let flat = run_scene(SMALL, &["contact.mu=0"]);
    assert_clean(&flat, "μ = 0");
    let flat = flat
        .metric("theta_r")
        .expect("a frictionless pile is measured");
    // Frictionless discs flow out flat (a slope of at most a grain per box width).
    assert!(flat.abs() < (0.2f64 / 1.6).atan().to_degrees(), "{flat}");
    let mut unmeasurable = 0;
    for mu in ["contact.mu=1", "contact.mu=5"] {
        let r = run_scene(SMALL, &[mu]);
        assert_clean(&r, mu);
        println!(
            "{mu}: {} {:?} {:?}",
            r.outcome.status(),
            r.metric("theta_r"),
            r.outcome.reason()
        );
        match r.outcome {
            Outcome::Completed => {}
            // In a box this small a rough fill may stand as a block; a
            // surface rising towards the open side is said so, with no angle.
            Outcome::Unmeasurable { reason } => {
                assert!(reason.contains("rises towards the open side"), "{reason}");
                unmeasurable += 1;
            }
            other => panic!("{mu}: {other:?}"),
        }
    }
    println!("{unmeasurable} of 2 rough fills stood as blocks");
}

#[test]
fn narrow_tall_and_flat_boxes() {
    for (w, h) in [(0.4, 4.0), (1.0, 10.0), (8.0, 0.5)] {
        let (ws, hs) = (format!("box.width={w}"), format!("box.height={h}"));
        let r = run_scene(SMALL, &[&ws, &hs]);
        println!(
            "{w} × {h}: {} {:?} {:?}",
            r.outcome.status(),
            r.metric("theta_r"),
            r.outcome.reason()
        );
        assert_clean(&r, &format!("{w} × {h}"));
        if w < 0.5 {
            // Two grains wide: the column empties through the open side and
            // what is left is too little to call a pile.
            assert_eq!(r.outcome.status(), "unmeasurable", "{:?}", r.outcome);
        }
    }
    // Narrower than a grain: refused, naming the field.
    let err = Scene::from_toml(SMALL, &["box.width=0.1".into()]).unwrap_err();
    assert_eq!(err.errors[0].field, "box.width");
}

#[test]
fn monodisperse_grains() {
    let r = run_scene(SMALL, &["grains.radius_sd=0"]);
    assert_clean(&r, "monodisperse");
    assert!(r.outcome.is_completed(), "{:?}", r.outcome);
    let grains = r.final_state.unwrap().grains;
    assert!(grains.iter().all(|g| g.radius == 0.1));
}

#[test]
fn a_single_grain() {
    let r = run_scene(SMALL, &["box.grains=1"]);
    assert_clean(&r, "one grain");
    assert_eq!(r.grains.initial, 1);
}

#[test]
fn tilt_rates_fast_and_slow() {
    for rate in ["tilt.rate=1", "tilt.rate=100"] {
        let r = run_scene(SMALL, &["protocol=tilt", rate]);
        assert_clean(&r, rate);
        let tilt: &TiltSpec = r.scene.section().unwrap();
        if let Some(t) = r.metric("theta_t") {
            assert!(t <= tilt.max_angle + 1.0, "{t}");
        }
        println!(
            "{rate}: {} θ_T {:?}",
            r.outcome.status(),
            r.metric("theta_t")
        );
    }
}

#[test]
fn a_forced_step_above_the_stability_limit_is_refused_or_caught() {
    let t_c = scene(SMALL, &[]).contact_time();
    let too_long = format!("numerics.dt={}", 0.6 * t_c);
    let err = Scene::from_toml(SMALL, &[too_long]).unwrap_err();
    assert_eq!(err.errors[0].field, "numerics.dt");
    assert!(err.errors[0].message.contains("stability limit"), "{err}");
    let err = Scene::from_toml(SMALL, &["numerics.dt_factor=0.7".into()]).unwrap_err();
    assert_eq!(err.errors[0].field, "numerics.dt_factor");

    // Accepted but far too coarse for grains falling at tens of cm/s: a
    // guard fails the run, and no angle is reported.
    let coarse = format!("numerics.dt={}", 0.3 * t_c);
    let r = run_scene(SMALL, &[&coarse]);
    assert_clean(&r, "dt = 0.3 t_c");
    assert_eq!(r.outcome.status(), "failed", "{:?}", r.outcome);
    let reason = r.outcome.reason().unwrap_or_default();
    assert!(reason.contains("time step"), "{reason}");
}

/// Runs a closure on the closed, filled box the engine builds for a scene.
struct Probe<'a, F>(&'a Scene, F);

impl<T, F: FnOnce(&mut dyn ProbeSim) -> T> EngineJob<2> for Probe<'_, F> {
    type Output = T;
    fn run<L: ContactLaw<2>, I: Integrator<2>>(self, laws: Laws<L>) -> T {
        let spec = PileSpec::of(self.0).unwrap();
        let mut sim = closed_box::<L, I>(self.0, &spec, laws);
        (self.1)(&mut sim)
    }
}

/// What the tests read from a simulation, independent of its contact law.
trait ProbeSim {
    fn step(&mut self, n: u64) -> Result<(), Blowup>;
    fn len(&self) -> usize;
    fn pairs(&self) -> usize;
    fn all_finite(&self) -> bool;
    fn arm_energy_guard(&mut self, extent: f64);
    fn check_energy(&self) -> Result<(), Blowup>;
    fn scale_velocities(&mut self, f: f64);
}

impl<L: ContactLaw<2>, I: Integrator<2>> ProbeSim for Simulation<2, L, I> {
    fn step(&mut self, n: u64) -> Result<(), Blowup> {
        self.run(n)
    }
    fn len(&self) -> usize {
        self.particles.len()
    }
    fn pairs(&self) -> usize {
        self.neighbors.pairs.len()
    }
    fn all_finite(&self) -> bool {
        let p = &self.particles;
        p.pos
            .iter()
            .chain(&p.vel)
            .all(|v| v.iter().all(|c| c.is_finite()))
    }
    fn arm_energy_guard(&mut self, extent: f64) {
        self.set_energy_budget(extent);
    }
    fn check_energy(&self) -> Result<(), Blowup> {
        Simulation::check_energy(self)
    }
    fn scale_velocities(&mut self, f: f64) {
        for v in &mut self.particles.vel {
            *v *= f;
        }
    }
}

#[test]
fn tens_of_thousands_of_grains() {
    // 40 × 20 cm at the default packing: 20 000 grains.
    let big = scene(SMALL, &["box.width=40", "box.height=20"]).resolved();
    let cell: &BoxSpec = big.section().unwrap();
    assert_eq!(cell.grain_count(&big), 20_000);
    let (n, pairs, finite) = with_engine(
        &big,
        Probe(&big, |sim: &mut dyn ProbeSim| {
            sim.step(300).expect("a falling column steps cleanly");
            (sim.len(), sim.pairs(), sim.all_finite())
        }),
    )
    .unwrap();
    assert_eq!(n, 20_000);
    assert!(finite);
    // The neighbour list stays linear in N: a handful of candidates per grain.
    assert!(pairs < 6 * n, "{pairs} pairs for {n} grains");
}

#[test]
fn the_energy_guard_fails_a_run_that_gains_energy_from_nowhere() {
    let s = scene(SMALL, &[]).resolved();
    let cell: &BoxSpec = s.section().unwrap();
    let extent = 2.0 * (cell.width + cell.fill_height());
    let outcome = with_engine(
        &s,
        Probe(&s, |sim: &mut dyn ProbeSim| {
            sim.arm_energy_guard(extent);
            sim.step(2000).expect("the fill starts cleanly");
            let before = sim.check_energy();
            // Grains falling under gravity are inside the budget; the same
            // grains suddenly fifty times faster are not.
            sim.scale_velocities(50.0);
            (before, sim.check_energy())
        }),
    )
    .unwrap();
    assert!(outcome.0.is_ok(), "{:?}", outcome.0);
    match outcome.1 {
        Err(Blowup::Energy { kinetic, limit, .. }) => assert!(kinetic > limit),
        other => panic!("expected an energy blow-up, got {other:?}"),
    }
    let message = Blowup::Energy {
        kinetic: 2.0,
        limit: 1.0,
        time: 0.5,
        units: repose_engine::simulation::Units::CGS,
    }
    .to_string();
    assert!(message.contains("energy blow-up"), "{message}");
    assert!(message.contains("2.000e0 erg"), "{message}");
}

/// The fields a scene is refused for.
fn refused_fields(text: &str, overrides: &[&str]) -> Vec<String> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let err = Scene::from_toml(text, &o).expect_err("refused");
    err.errors.iter().map(|e| e.field.clone()).collect()
}

#[test]
fn steps_far_below_the_contact_time_and_unbounded_domains_are_refused() {
    let t_c = scene(SMALL, &[]).contact_time();
    // The finest step taken is t_c/10⁴: just above it runs, just below is refused.
    assert!(Scene::from_toml(SMALL, &[format!("numerics.dt={}", 1.01e-4 * t_c)]).is_ok());
    let fine = format!("numerics.dt={}", 0.99e-4 * t_c);
    assert_eq!(refused_fields(SMALL, &[&fine]), ["numerics.dt"]);
    assert_eq!(
        refused_fields(SMALL, &["numerics.dt_factor=1e-6"]),
        ["numerics.dt_factor"]
    );
    // A box a hundred thousand of its largest grains wide (0.26 cm here) at most.
    let wide = Scene::from_toml(SMALL, &["box.width=25000.0".into(), "box.grains=10".into()]);
    assert!(wide.is_ok(), "{:?}", wide.err());
    assert_eq!(
        refused_fields(SMALL, &["box.width=1e9", "box.grains=10"]),
        ["box.width"]
    );
    // Checks at least once within the fill's and the flow's time caps.
    assert_eq!(
        refused_fields(SMALL, &["equilibrium.check_interval=1e9"]),
        ["equilibrium.check_interval"]
    );
    // A Verlet skin of at most ten of the largest grains' diameters, the
    // listed grains' too.
    assert!(Scene::from_toml(SMALL, &["numerics.skin=2.5".into()]).is_ok());
    assert_eq!(
        refused_fields(SMALL, &["numerics.skin=2.7"]),
        ["numerics.skin"]
    );
    let big = "protocol = \"free_run\"\nduration = 0.01\n\
               [numerics]\nskin = 15.0\n[[particles]]\nposition = [0.0, 0.0]\nradius = 1.0\n";
    assert!(Scene::from_toml(big, &[]).is_ok());
    assert_eq!(
        refused_fields(big, &["numerics.skin=25.0"]),
        ["numerics.skin"]
    );
    // Listed grains: ids below the grain limit, walls whose length is a number.
    let listed = "protocol = \"free_run\"\nduration = 0.01\n\
                  [[particles]]\nid = 4000000000\nposition = [0.8, 0.2]\nradius = 0.1\n\
                  [[walls]]\npoint = [0.0, 0.0]\nnormal = [1e200, 1e200]\n";
    assert_eq!(
        refused_fields(listed, &[]),
        ["particles[0].id", "walls[0].normal"]
    );
}

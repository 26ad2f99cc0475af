//! Checkpoints: a run continued from any of its saved points ends with the
//! same numbers, bit for bit, as the run that never stopped — for the
//! poured heap (engine, pour stream and counters), the packed column
//! (engine only, on the Gear integrator) and a 2D free run with friction, across a change of thread count, and a checkpoint that
//! does not belong to the scene is set aside rather than trusted. A run
//! handed more threads partway (a worker lending an idle core) ends with
//! the same numbers too. Checkpoints written by an earlier build (a kept
//! one, and the previous format's engine state) are still read.

use repose_physics::report::simulated_numbers;
use repose_physics::{run, Checkpoint, Observer, Progress, RunReport, Scene};
use serde_json::Value;

/// Saves at every resumable point, or hands over one checkpoint.
#[derive(Default)]
struct Recorder {
    every: bool,
    kept: Vec<Checkpoint>,
    /// The phase of the check before each save.
    kept_in: Vec<&'static str>,
    phase: &'static str,
    give: Option<Checkpoint>,
    resumed: Vec<Result<u64, String>>,
}

impl Observer for Recorder {
    fn progress(&mut self, update: &Progress) -> bool {
        self.phase = update.phase.name();
        true
    }
    fn checkpoint_due(&mut self) -> bool {
        self.every
    }
    fn save(&mut self, checkpoint: Checkpoint) {
        self.kept.push(checkpoint);
        self.kept_in.push(self.phase);
    }
    fn saved(&mut self) -> Option<Checkpoint> {
        self.give.take()
    }
    fn resumed(&mut self, result: Result<u64, String>) {
        self.resumed.push(result);
    }
}

/// A small cohesive heap with rolling resistance: every kind of contact
/// history (tangential spring, rolling torque, cohesive capture) is live.
/// Its attraction is read at the pair's gap with the step bounded by its
/// kick, as `quick` read it before it swept it: so its grains stay on this
/// small plate, and the kept checkpoint below stays its own.
const HEAP: &str = r#"
protocol = "heap"
preset = "quick"
seed = 5
[numerics]
attraction_kick = 0.5
attraction_step = "point"
[material]
surface_energy = 0.01
[heap]
plate = 12
height = 16
inlet_floor = 8
max_grains = 240
interval = 2.0
settle_min = 5
settle_max = 60
"#;

/// A small column on the Gear predictor-corrector, whose history of
/// higher derivatives is state too.
const PACKING: &str = r#"
protocol = "packing"
preset = "standard"
seed = 2
[numerics]
integrator = "gear5"
dt_factor = 0.02
[packing]
width = 5
height = 12
"#;

/// Three 2D grains with friction falling onto a floor and onto each other.
const FREE_RUN: &str = r#"
protocol = "free_run"
gravity = [0.0, -981.0]
duration = 0.3
[contact]
mu = 0.3
[[particles]]
position = [0.0, 0.12]
radius = 0.1
[[particles]]
position = [0.15, 0.35]
radius = 0.1
[[particles]]
position = [-0.12, 0.6]
velocity = [20.0, 0.0]
radius = 0.1
[[walls]]
point = [0.0, 0.0]
normal = [0.0, 1.0]
"#;

/// The narrow cohesive column of the examples: about a thousand grains,
/// enough listed pairs for a step to be shared.
const COLUMN: &str = include_str!("../../../examples/packing.toml");

/// Hands the run `threads` threads from its third check on, as a worker
/// lends it the core of another that has nothing to run.
struct Lender {
    checks: usize,
    threads: usize,
}

impl Observer for Lender {
    fn progress(&mut self, _update: &Progress) -> bool {
        self.checks += 1;
        true
    }
    fn threads(&mut self) -> Option<usize> {
        (self.checks >= 3).then_some(self.threads)
    }
}

fn scene(text: &str, extra: &[&str]) -> Scene {
    let o: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    Scene::from_toml(text, &o).unwrap()
}

/// Every simulated number of a report: all but how it was computed, and
/// the scene it ran.
fn numbers(r: &RunReport) -> Value {
    let mut v = simulated_numbers(serde_json::to_value(r).unwrap());
    v.as_object_mut().unwrap().remove("scene");
    v
}

fn resumed_from(scene: &Scene, checkpoint: &Checkpoint) -> (RunReport, Recorder) {
    let mut obs = Recorder {
        give: Some(checkpoint.clone()),
        ..Recorder::default()
    };
    let report = run(scene, &mut obs).unwrap();
    (report, obs)
}

/// The whole run of `scene`, saved at every resumable point.
fn saving_everywhere(scene: &Scene) -> (RunReport, Recorder) {
    let mut all = Recorder {
        every: true,
        ..Recorder::default()
    };
    let whole = run(scene, &mut all).unwrap();
    assert!(whole.outcome.is_completed(), "{:?}", whole.outcome);
    (whole, all)
}

/// Runs once saving at every point, then resumes from a spread of them.
fn resumes_bit_for_bit(text: &str, picks: usize) {
    let base = scene(text, &[]);
    let (whole, all) = saving_everywhere(&base);
    let n = all.kept.len();
    assert!(n > picks, "only {n} checkpoints");
    let bytes: usize = all.kept.iter().map(|c| c.state.len()).sum::<usize>() / n;
    println!("{n} checkpoints, {bytes} bytes each on average");
    let expected = numbers(&whole);
    for k in 0..picks {
        let cp = &all.kept[1 + k * (n - 2) / (picks - 1).max(1)];
        let (again, obs) = resumed_from(&base, cp);
        assert_eq!(obs.resumed, vec![Ok(cp.iteration)]);
        assert!(cp.iteration <= whole.iterations);
        assert!(
            numbers(&again) == expected,
            "resumed at step {} of {}: the numbers differ",
            cp.iteration,
            whole.iterations
        );
    }
    // Resumed on two threads: still the same numbers.
    let two = scene(text, &["numerics.threads=2"]);
    let (again, _) = resumed_from(&two, &all.kept[n / 2]);
    assert_eq!(again.metrics, whole.metrics);
    assert_eq!(again.final_state, whole.final_state);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_heap_resumed_from_any_checkpoint_ends_bit_for_bit_as_the_whole_run() {
    resumes_bit_for_bit(HEAP, 4);
}

/// A pour saves between two insertions too, at every check, so that a run
/// asked to stop saves within a check rather than waiting out the interval
/// (at glass stiffness minutes of one core for fine grains); resumed from
/// there, it ends as the run that never stopped.
#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_heap_saved_between_two_insertions_ends_bit_for_bit_as_the_whole_run() {
    let base = scene(HEAP, &[]);
    let (whole, all) = saving_everywhere(&base);
    let insertions = whole
        .series
        .iter()
        .find(|c| c.name == "crest")
        .map_or(0, |c| c.points.len());
    let pouring: Vec<&Checkpoint> = (all.kept.iter().zip(&all.kept_in))
        .filter(|(_, phase)| **phase == "pour")
        .map(|(c, _)| c)
        .collect();
    // An insertion every 2 √(d/g), a check every 0.25: eight saves an
    // interval, one of them at the insertion.
    assert!(
        insertions >= 5 && pouring.len() >= 4 * insertions,
        "{} saves while pouring, {insertions} insertions",
        pouring.len()
    );
    // Of three saves in a row, at most one is at an insertion.
    let middle = pouring.len() / 2;
    for cp in &pouring[middle..middle + 3] {
        let (again, obs) = resumed_from(&base, cp);
        assert_eq!(obs.resumed, vec![Ok(cp.iteration)]);
        assert!(
            numbers(&again) == numbers(&whole),
            "resumed at step {} of {}: the numbers differ",
            cp.iteration,
            whole.iterations
        );
    }
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_packing_resumed_from_a_checkpoint_ends_bit_for_bit_as_the_whole_run() {
    resumes_bit_for_bit(PACKING, 2);
}

#[test]
fn a_free_run_resumed_from_a_checkpoint_ends_bit_for_bit_as_the_whole_run() {
    resumes_bit_for_bit(FREE_RUN, 3);
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_column_handed_more_threads_midway_ends_with_the_same_numbers() {
    let base = scene(COLUMN, &[]);
    let whole = run(&base, &mut Recorder::default()).unwrap();
    assert!(whole.outcome.is_completed(), "{:?}", whole.outcome);
    let mut lender = Lender {
        checks: 0,
        threads: 2,
    };
    let lent = run(&base, &mut lender).unwrap();
    assert!(lender.checks > 10, "{} checks", lender.checks);
    assert!(lent.counters.shared_steps > 0, "{:?}", lent.counters);
    assert_eq!(whole.counters.shared_steps, 0);
    assert_eq!(numbers(&lent), numbers(&whole));
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_checkpoint_of_another_scene_or_damaged_is_set_aside() {
    let base = scene(HEAP, &["heap.max_grains=60", "heap.settle_max=20"]);
    let mut all = Recorder {
        every: true,
        ..Recorder::default()
    };
    let whole = run(&base, &mut all).unwrap();
    let cp = all.kept[all.kept.len() / 2].clone();
    // Another seed: the header differs, the run starts over.
    let other = scene(
        HEAP,
        &["heap.max_grains=60", "heap.settle_max=20", "seed=6"],
    );
    let (r, obs) = resumed_from(&other, &cp);
    let reason = obs.resumed[0].as_ref().unwrap_err();
    assert!(reason.contains("another build or scene"), "{reason}");
    let fresh = run(&other, &mut Recorder::default()).unwrap();
    assert_eq!(numbers(&r), numbers(&fresh));
    // Damaged bytes: unreadable, the run starts over.
    let mut broken = cp.clone();
    let cut = broken.state.len() / 2;
    broken.state.truncate(cut);
    let (r, obs) = resumed_from(&base, &broken);
    assert!(obs.resumed[0].as_ref().unwrap_err().contains("unreadable"));
    assert_eq!(numbers(&r), numbers(&whole));
}

#[test]
#[cfg_attr(debug_assertions, ignore = "long: run with --release")]
fn a_heap_with_grains_at_rest_resumes_bit_for_bit_with_their_rest() {
    resumes_bit_for_bit(&format!("{HEAP}[rest]\nspeed = 0.05\ntime = 0.5\n"), 3);
}

/// An engine state saved before the counters were kept as text (format 2,
/// every counter a field) is read into today's state and goes on bit for bit
/// as the run that never stopped: cohesive, rolling spheres settling in a
/// column on a plate, with every contact history live.
#[test]
fn an_engine_state_saved_in_format_2_goes_on_bit_for_bit() {
    use repose_engine::contact::{Epsd2, VanDerWaals};
    use repose_engine::dim::Vector;
    use repose_engine::integrate::VelocityVerlet;
    use repose_engine::particles::Particles;
    use repose_engine::simulation::{CountersFormat2, EngineState, Simulation, StateFormat2Of};
    use repose_engine::walls::Wall;
    use repose_physics::models::elekes_parteli::{self, law, Law};
    type Column = Simulation<3, Law<Epsd2, VanDerWaals, true>, VelocityVerlet>;

    let scene = scene(
        HEAP,
        &[
            "material.youngs_modulus=1e7",
            "material.surface_energy=0.05",
        ],
    );
    let (pair, plate) = elekes_parteli::parts(&scene).unwrap();
    let d = 1e-3;
    let build = || -> Column {
        let mut p = Particles::<3>::new(true);
        for k in 0..8 {
            // A leaning column, so that the grains roll and slide apart.
            let x = Vector::<3>::new(
                0.3 * d * k as f64,
                0.1 * d * k as f64,
                (0.5 + 1.05 * k as f64) * d,
            );
            p.push(x, Vector::<3>::zeros(), 0.5 * d, 1.3e-6);
        }
        let floor = Wall::plane(Vector::<3>::zeros(), Vector::<3>::new(0.0, 0.0, 1.0));
        let walls = vec![(floor, law(&plate))];
        Simulation::new(
            p,
            walls,
            Vector::<3>::new(0.0, 0.0, -9.81),
            law(&pair),
            2e-6,
            0.1 * d,
        )
    };
    let mut whole = build();
    whole.run(6000).unwrap();
    let mut first = build();
    first.run(3000).unwrap();
    let halfway = first.counters;
    // The same state as a format-2 save laid it out: every counter but the
    // shared steps.
    let old: StateFormat2Of<3, Law<Epsd2, VanDerWaals, true>, VelocityVerlet> =
        first.save_state().with_counters(|c| {
            let fields = serde_json::to_value(c.0).unwrap();
            serde_json::from_value::<CountersFormat2>(fields).unwrap()
        });
    let bytes = postcard::to_stdvec(&old).unwrap();
    let read: StateFormat2Of<3, Law<Epsd2, VanDerWaals, true>, VelocityVerlet> =
        postcard::from_bytes(&bytes).unwrap();
    let mut second = build();
    second.restore_state(EngineState::upgrade(read)).unwrap();
    assert_eq!(second.counters.steps, halfway.steps);
    assert_eq!(second.counters.particle_steps, halfway.particle_steps);
    second.run(3000).unwrap();
    let bits = |s: &Column| -> Vec<u64> {
        let p = &s.particles;
        (p.pos.iter().chain(&p.vel).chain(&p.omega))
            .flat_map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
            .collect()
    };
    assert!(whole.particles.vel.iter().any(|v| v.norm() > 0.0));
    assert_eq!(bits(&second), bits(&whole));
    assert_eq!(second.counters.steps, whole.counters.steps);
}

/// A checkpoint of a small cohesive heap written by an earlier build of
/// this engine version (format 3, saved at an insertion), kept as
/// `tests/fixtures/heap-checkpoint.bin`.
const FIXTURE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/heap-checkpoint.bin"
);

/// What a checkpoint holds can change without the engine's numbers
/// changing (a counter added, say), and a build that cannot read the
/// checkpoints of the one before sets aside hours of saved heaps. So a
/// checkpoint written by an earlier build is kept here and must still be
/// read and go on to the numbers of the uninterrupted run: a change to a
/// saved field bumps `resume`'s format and keeps reading the previous one.
/// A new engine version (whose checkpoints are set aside by design) writes
/// the fixture anew: `REPOSE_WRITE_FIXTURES=1 cargo test --test resume`.
#[test]
fn a_checkpoint_written_by_an_earlier_build_is_still_read() {
    let base = scene(HEAP, &[]);
    let (whole, all) = saving_everywhere(&base);
    if std::env::var_os("REPOSE_WRITE_FIXTURES").is_some() {
        let middle = &all.kept[all.kept.len() / 2];
        std::fs::write(FIXTURE, &middle.state).unwrap();
    }
    let state = std::fs::read(FIXTURE).expect("the kept checkpoint");
    let kept = Checkpoint {
        time: 0.0,
        iteration: 0,
        state,
    };
    let (again, obs) = resumed_from(&base, &kept);
    let step = match obs.resumed.as_slice() {
        [Ok(step)] => *step,
        other => panic!(
            "the kept checkpoint was not read ({other:?}): a change to what checkpoints hold \
             needs a new format that still reads the old; a new engine version, the fixture \
             written anew"
        ),
    };
    assert!(step > 0 && step < whole.iterations, "{step}");
    assert!(
        numbers(&again) == numbers(&whole),
        "resumed at step {step}: the numbers differ"
    );
}

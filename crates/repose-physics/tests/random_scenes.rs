//! Property: any valid scene, however extreme its parameters, either runs
//! to a completed outcome with finite numbers or ends with a clean outcome
//! that says why — never a panic, never a silent NaN.

use proptest::prelude::*;
use repose_physics::report::Outcome;
use repose_physics::{run, Quiet, Scene};

/// A small random scene: tiny boxes keep each case well under a second.
fn scene() -> impl Strategy<Value = Vec<String>> {
    (
        prop_oneof![Just("fill_release"), Just("tilt"), Just("flux")],
        0.6f64..1.6,
        0.4f64..1.4,
        0.0f64..1.5,
        3.0f64..8.0,
        0.0f64..1000.0,
        prop_oneof![Just("gear5"), Just("verlet")],
        0.005f64..0.1,
        0.0f64..0.03,
        prop_oneof![Just("floored"), Just("raw")],
        prop_oneof![Just("paper"), Just("truncated")],
        0u64..1000,
    )
        .prop_map(
            |(protocol, w, h, mu, log_kn, gamma, integrator, dtf, sd, normal, spring, seed)| {
                let mut o = vec![
                    format!("protocol={protocol}"),
                    format!("seed={seed}"),
                    format!("box.width={w}"),
                    format!("box.height={h}"),
                    format!("contact.mu={mu}"),
                    format!("contact.k_n={}", 10f64.powf(log_kn)),
                    format!("contact.gamma_n={gamma}"),
                    format!("numerics.integrator={integrator}"),
                    format!("numerics.dt_factor={dtf}"),
                    format!("grains.radius_sd={sd}"),
                    format!("contact.normal_force={normal}"),
                    format!("contact.shear_spring={spring}"),
                    "equilibrium.max_fill_time=1.5".into(),
                    "equilibrium.max_flow_time=1.5".into(),
                ];
                // Each protocol takes its own section only.
                match protocol {
                    "tilt" => o.push("tilt.rate=90".into()),
                    "flux" => o.extend(["flux.insertions=5".into(), "flux.max_wait=0.2".into()]),
                    _ => {}
                }
                o
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    #[cfg_attr(debug_assertions, ignore = "long: run with --release")]
    fn any_valid_scene_ends_in_finite_numbers_or_a_clean_outcome(overrides in scene()) {
        let scene = Scene::from_toml("protocol = \"fill_release\"", &overrides)
            .expect("the generated scenes are valid");
        let report = run(&scene, &mut Quiet).expect("a valid scene runs");
        eprintln!("{} {:?}: {}", scene.protocol, report.metric("theta_r"), report.outcome.status());
        if report.outcome.is_completed() {
            for (name, v) in &report.metrics {
                prop_assert!(v.is_finite(), "{name} = {v}");
            }
            for g in &report.final_state.as_ref().unwrap().grains {
                prop_assert!(g.position.iter().chain(g.velocity.iter()).all(|v| v.is_finite()), "{g:?}");
            }
        } else {
            let reason = report.outcome.reason().unwrap_or_default();
            prop_assert!(!reason.is_empty(), "{:?}", report.outcome);
            // What a run that went wrong still reports is finite, and no
            // angle comes from it.
            for (name, v) in &report.metrics {
                prop_assert!(v.is_finite(), "{name} = {v} from {:?}", report.outcome);
            }
            // A tilted pile that never slid, or failed while tilting,
            // still has the angle it was built with.
            let tilting = matches!(&report.outcome,
                Outcome::Failed { phase, .. } | Outcome::NotSettled { phase, .. } if phase == "tilt")
                || matches!(report.outcome, Outcome::NoOnset { .. });
            prop_assert!(tilting || report.metric("theta_r").is_none(), "θ_R from {:?}", report.outcome);
        }
        prop_assert!(report.simulated_time.is_finite() && report.wall_time.is_finite());
    }
}

//! The registries are the one source of the protocols, models and metrics:
//! every metric a protocol records is one it declares (the store, the API,
//! the page and the reports learn a protocol's metrics from that list, so an
//! undeclared name would be stored but never shown; checked on a small
//! version of each protocol's example scene), and the tables of
//! docs/scene.md name exactly what the registries hold.

use repose_physics::protocols::Quiet;
use repose_physics::registry;
use repose_physics::{run, Scene};
use std::collections::BTreeSet;

/// The example scene of each protocol, made small.
fn small_scene(protocol: &str) -> (&'static str, Vec<&'static str>) {
    match protocol {
        "fill_release" => ("fill_release.toml", vec!["box.width=2.0", "box.height=2.0"]),
        "tilt" => (
            "tilt.toml",
            vec!["box.width=2.0", "box.height=2.0", "tilt.rate=40.0"],
        ),
        "flux" => ("flux.toml", vec!["box.width=2.0", "flux.insertions=40"]),
        "free_run" => ("incline.toml", vec![]),
        "heap" => (
            "heap.toml",
            vec![
                "heap.plate=12",
                "heap.max_grains=500",
                "material.rolling_friction=0.3",
            ],
        ),
        "packing" => ("packing.toml", vec!["packing.width=5", "packing.height=8"]),
        other => panic!("protocol `{other}` has no small scene here: add one"),
    }
}

#[test]
fn every_metric_a_protocol_records_is_declared() {
    let examples = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/");
    for protocol in registry::protocols() {
        let name = protocol.name();
        let (file, overrides) = small_scene(name);
        let text = std::fs::read_to_string(format!("{examples}{file}")).unwrap();
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        let scene = Scene::from_toml(&text, &overrides).unwrap();
        assert_eq!(scene.protocol().unwrap().name(), name, "{file}");
        let report = run(&scene, &mut Quiet).unwrap_or_else(|e| panic!("{name}: {e}"));
        let declared: BTreeSet<&str> = protocol.metrics().iter().map(|m| m.name).collect();
        let recorded: BTreeSet<&str> = report.metrics.keys().map(String::as_str).collect();
        let undeclared: Vec<_> = recorded.difference(&declared).collect();
        assert!(
            undeclared.is_empty(),
            "{name} records {undeclared:?}, undeclared"
        );
        assert!(
            report.outcome.is_completed(),
            "{name}: {:?}",
            report.outcome
        );
        assert!(
            declared.is_empty() || recorded.contains(protocol.metrics()[0].name),
            "{name} completed without its headline metric"
        );
    }
}

/// The backticked names of `cell`.
fn quoted(cell: &str) -> BTreeSet<&str> {
    cell.split('`').skip(1).step_by(2).collect()
}

#[test]
fn the_metric_table_of_the_scene_docs_lists_every_protocols_metrics() {
    let doc = include_str!("../../../docs/scene.md");
    let table = doc
        .split("## Metrics")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("docs/scene.md has a Metrics section");
    for protocol in registry::protocols() {
        let name = protocol.name();
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("| `{name}` |")))
            .unwrap_or_else(|| panic!("docs/scene.md lists no metrics of `{name}`"));
        let mut cells = row.split('|').skip(2);
        let listed: BTreeSet<&str> = quoted(cells.next().unwrap_or(""))
            .into_iter()
            .filter(|n| !registry::protocols().iter().any(|p| p.name() == *n))
            .collect();
        let declared: BTreeSet<&str> = protocol.metrics().iter().map(|m| m.name).collect();
        assert_eq!(listed, declared, "docs/scene.md's row of `{name}`");
    }
}

/// The row of the scene key `key` in docs/scene.md's key tables.
fn key_row(key: &str) -> &'static str {
    include_str!("../../../docs/scene.md")
        .lines()
        .find(|l| l.starts_with(&format!("| `{key}` |")))
        .unwrap_or_else(|| panic!("docs/scene.md has no row for `{key}`"))
}

#[test]
fn the_scene_docs_name_every_registered_protocol_and_model() {
    let protocol_cell = key_row("protocol").rsplit('|').nth(1).unwrap();
    let listed = quoted(protocol_cell);
    let registered: BTreeSet<&str> = registry::protocol_names().into_iter().collect();
    assert_eq!(listed, registered, "the `protocol` row of docs/scene.md");
    let model_cell = key_row("model").rsplit('|').nth(1).unwrap();
    let listed: BTreeSet<&str> = quoted(model_cell)
        .into_iter()
        .filter(|n| !registered.contains(n))
        .collect();
    let models: BTreeSet<&str> = registry::model_names().into_iter().collect();
    assert_eq!(listed, models, "the `model` row of docs/scene.md");
}

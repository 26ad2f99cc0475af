//! A store written by repose 0.1 (`tests/fixtures/store-0.1`) upgraded by
//! the current migrations, on SQLite and PostgreSQL: every sweep, sample,
//! point, figure and report is served as 0.1 served it.
//!
//! The rows are loaded into a database brought to schema 0002 by the 0.1
//! migrations alone; `Store::open` then applies the rest, as it would on a
//! lab's existing database.

use axum::body::Body;
use axum::http::{Request, StatusCode};
use http_body_util::BodyExt;
use repose_store::Store;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};
use tower::ServiceExt;

fn fixture(name: &str) -> Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/fixtures/store-0.1")
        .join(name);
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn scratch() -> PathBuf {
    repose_testkit::scratch_dir("repose-migration")
}

/// How each column is bound: 't' text, 'i' integer, 'f' real.
fn kind(table: &str, column: &str) -> char {
    match (table, column) {
        (
            _,
            "priority" | "created_at" | "seq" | "sample" | "seed" | "attempts" | "max_attempts"
            | "lease_expires" | "updated_at" | "grains_initial" | "grains_final" | "grains_lost"
            | "iterations" | "particle_steps",
        ) => 'i',
        ("results", c) if c.starts_with("theta") || c.ends_with("_time") => 'f',
        _ => 't',
    }
}

/// Loads the fixture's rows into a database at schema 0002.
async fn load(url: &str, dir: &Path) {
    sqlx::any::install_default_drivers();
    let pool = sqlx::AnyPool::connect(url).await.unwrap();
    // The migrations 0.1 had.
    repose_testkit::migrations_up_to(2, dir)
        .await
        .run(&pool)
        .await
        .unwrap();
    let rows = fixture("rows.json");
    for table in ["sweeps", "jobs", "results"] {
        for row in rows[table].as_array().unwrap() {
            let row = row.as_object().unwrap();
            let cols: Vec<&String> = row.keys().collect();
            let marks: Vec<String> = (1..=cols.len()).map(|k| format!("${k}")).collect();
            let mut sql = format!(
                "INSERT INTO {table} ({}) VALUES ({})",
                cols.iter()
                    .map(|c| c.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                marks.join(", ")
            );
            if url.starts_with("sqlite") {
                sql = sql.replace('$', "?");
            }
            let mut q = sqlx::query(&sql).persistent(false);
            for c in &cols {
                let v = &row[c.as_str()];
                q = match kind(table, c) {
                    'i' => q.bind(v.as_i64()),
                    'f' => q.bind(v.as_f64()),
                    _ => q.bind(v.as_str().map(String::from)),
                };
            }
            q.execute(&pool).await.unwrap();
        }
    }
    pool.close().await;
}

async fn get(store: &Store, uri: &str) -> (StatusCode, Value) {
    let req = Request::builder().uri(uri).body(Body::empty()).unwrap();
    let resp = repose_api::app(store.clone()).oneshot(req).await.unwrap();
    let status = resp.status();
    let bytes = resp.into_body().collect().await.unwrap().to_bytes();
    (
        status,
        serde_json::from_slice(&bytes).unwrap_or(Value::Null),
    )
}

/// Two numbers the same, or both absent.
fn same(a: &Value, b: &Value, what: &str) {
    match (a.as_f64(), b.as_f64()) {
        (Some(x), Some(y)) => {
            // Sums taken in another order may differ in the last bits.
            let tol = 1e-12 * x.abs().max(1.0);
            assert!((x - y).abs() <= tol, "{what}: {a} then, {b} now");
        }
        _ => assert_eq!(a.is_null(), b.is_null(), "{what}: {a} then, {b} now"),
    }
}

/// The old points against the new: samples, failures and every metric
/// the old store had numbers for.
fn check_points(old: &Value, new: &Value, id: &str) {
    let (old, new) = (
        old["points"].as_array().unwrap(),
        new["points"].as_array().unwrap(),
    );
    assert_eq!(old.len(), new.len(), "{id}");
    for (o, n) in old.iter().zip(new) {
        assert_eq!(o["point"], n["point"], "{id}");
        assert_eq!(o["samples"], n["samples"], "{id}");
        assert_eq!(o["failures"], n["failures"], "{id}");
        for (metric, agg) in o["metrics"].as_object().unwrap() {
            if agg["n"] == 0 {
                let now = &n["metrics"][metric];
                assert!(now.is_null() || now["n"] == 0, "{id} {metric}");
                continue;
            }
            let now = &n["metrics"][metric];
            assert_eq!(agg["n"], now["n"], "{id} {metric}");
            for stat in ["mean", "sd", "sem"] {
                same(&agg[stat], &now[stat], &format!("{id} {metric} {stat}"));
            }
        }
    }
}

/// The old samples against the new: same rows, each old angle column now a metric.
fn check_samples(old: &Value, new: &Value, id: &str) {
    let (old, new) = (
        old["samples"].as_array().unwrap(),
        new["samples"].as_array().unwrap(),
    );
    assert_eq!(old.len(), new.len(), "{id}");
    for (o, n) in old.iter().zip(new) {
        for key in [
            "sample_hash",
            "seed",
            "outcome",
            "reason",
            "point",
            "iterations",
            "grains_final",
            "particle_steps",
            "engine",
        ] {
            assert_eq!(o[key], n[key], "{id} {key}");
        }
        let metrics = n["metrics"].as_object().unwrap();
        let mut old_metrics = 0;
        for (key, v) in o.as_object().unwrap() {
            if key.starts_with("theta") && !v.is_null() {
                old_metrics += 1;
                assert_eq!(metrics.get(key), Some(v), "{id} {key}");
            }
        }
        assert_eq!(metrics.len(), old_metrics, "{id}: {n}");
    }
}

/// A figure the old API drew from a sweep, against the sweep drawn as the
/// same figure of the paper's study now.
fn check_figure(old: &Value, new: &Value, id: &str, fig: &str) {
    let measured: Vec<&Value> = new["series"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["kind"] == "measured")
        .collect();
    let mut now = Vec::new();
    for s in measured {
        for p in s["points"].as_array().unwrap() {
            now.push((s["series_value"].clone(), p));
        }
    }
    let then = old["points"].as_array().unwrap();
    assert_eq!(then.len(), now.len(), "{id} {fig}");
    for (o, (series, n)) in then.iter().zip(now) {
        assert_eq!(o["x"].as_f64(), n["x"].as_f64(), "{id} {fig}");
        assert_eq!(o["series"], series, "{id} {fig}");
        assert_eq!(o["n"], n["n"], "{id} {fig}");
        assert_eq!(o["failures"], n["failures"], "{id} {fig}");
        same(&o["mean"], &n["y"], &format!("{id} {fig} mean"));
        same(&o["sd"], &n["sd"], &format!("{id} {fig} sd"));
        same(&o["sem"], &n["sem"], &format!("{id} {fig} sem"));
    }
}

/// Every answer of the 0.1 API, asked again of the upgraded store.
async fn served_as_before(store: &Store) {
    let answers = fixture("answers.json");
    let (status, list) = get(store, "/api/sweeps").await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(
        list["sweeps"].as_array().unwrap().len(),
        answers["sweeps"].as_object().unwrap().len()
    );
    let rows = fixture("rows.json");
    let stored: Map<String, Value> = rows["results"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| (r["sample_hash"].as_str().unwrap().to_string(), r.clone()))
        .collect();
    for (id, old) in answers["sweeps"].as_object().unwrap() {
        let (_, sweep) = get(store, &format!("/api/sweeps/{id}")).await;
        for key in [
            "name",
            "protocol",
            "state",
            "progress",
            "spec",
            "priority",
            "created_at",
        ] {
            assert_eq!(old["sweep"][key], sweep[key], "{id} {key}");
        }
        // The cost's wall time is a sum the database takes in its own order.
        let (was, now) = (&old["sweep"]["cost"], &sweep["cost"]);
        assert_eq!(was["samples"], now["samples"], "{id} cost");
        assert_eq!(was["particle_steps"], now["particle_steps"], "{id} cost");
        same(&was["wall_time"], &now["wall_time"], &format!("{id} cost"));
        let (_, points) = get(store, &format!("/api/sweeps/{id}/points")).await;
        check_points(&old["points"], &points, id);
        let (_, samples) = get(store, &format!("/api/sweeps/{id}/samples")).await;
        check_samples(&old["samples"], &samples, id);
        for fig in ["2a", "2b", "3", "4"] {
            let (status, new) = get(store, &format!("/api/sweeps/{id}/figures/lh93/{fig}")).await;
            let measures_theta_t = sweep["protocol"] == "tilt";
            match old["figures"].get(fig) {
                // 0.1 drew figure 4 (θ_T) from fill-and-release sweeps too,
                // with no θ_T at any point; a protocol that does not measure
                // θ_T has no figure 4 now.
                Some(f) if fig == "4" && !measures_theta_t => {
                    assert!(f["points"].as_array().unwrap().iter().all(|p| p["n"] == 0));
                    assert_eq!(
                        status,
                        StatusCode::UNPROCESSABLE_ENTITY,
                        "{id} {fig}: {new}"
                    )
                }
                Some(f) => {
                    assert_eq!(status, StatusCode::OK, "{id} {fig}: {new}");
                    check_figure(f, &new, id, fig);
                }
                None => assert_ne!(status, StatusCode::OK, "{id} {fig}: {new}"),
            }
        }
        for s in samples["samples"].as_array().unwrap() {
            let hash = s["sample_hash"].as_str().unwrap();
            let (status, report) = get(store, &format!("/api/samples/{hash}")).await;
            assert_eq!(status, StatusCode::OK);
            assert_eq!(&report["metrics"], &s["metrics"], "{hash}");
            let then: Value =
                serde_json::from_str(stored[hash]["report"].as_str().unwrap()).unwrap();
            assert_eq!(report["final_state"], then["final_state"], "{hash}");
            assert_eq!(report["scene"], then["scene"], "{hash}");
            assert_eq!(report["outcome"], then["outcome"], "{hash}");
        }
    }
}

#[tokio::test]
async fn a_sqlite_store_of_version_0_1_is_served_as_before_after_the_upgrade() {
    let dir = scratch();
    let url = format!("sqlite://{}?mode=rwc", dir.join("old.db").display());
    load(&url, &dir).await;
    let store = Store::open(&url).await.unwrap();
    served_as_before(&store).await;
}

#[tokio::test]
async fn a_postgres_store_of_version_0_1_is_served_as_before_after_the_upgrade() {
    let Some(db) = repose_testkit::postgres("repose_migration").await else {
        return;
    };
    load(db.url(), &scratch()).await;
    let store = db.open().await.unwrap();
    served_as_before(&store).await;
    repose_testkit::drop_postgres(db, store).await;
}

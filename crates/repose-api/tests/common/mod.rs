//! A store for the generated-request tests: SQLite in a temporary folder,
//! holding one finished sweep computed here by the engine itself.

use axum::body::Body;
use axum::http::{Request, StatusCode};
use http_body_util::BodyExt;
use repose_store::Store;
use serde_json::{json, Value};
use tower::ServiceExt;

/// A sweep small enough to run in a test: two points along `contact.mu`
/// of a one-by-one box, one sample each, at the quick fidelity.
pub fn small_sweep() -> Value {
    json!({"protocol": "fill_release", "base": {"box": {"width": 1.0, "height": 1.0}},
        "axes": {"contact.mu": [0.1, 0.2]}, "samples": 1, "fidelity": "quick"})
}

/// One request through a fresh router; the status and the body's bytes.
pub async fn call(store: &Store, req: Request<Body>) -> (StatusCode, Vec<u8>) {
    let resp = repose_api::app(store.clone())
        .oneshot(req)
        .await
        .expect("the router is infallible");
    let status = resp.status();
    let bytes = resp.into_body().collect().await.unwrap().to_bytes();
    (status, bytes.to_vec())
}

pub async fn get_json(store: &Store, uri: &str) -> Value {
    let (status, bytes) = call(store, Request::get(uri).body(Body::empty()).unwrap()).await;
    assert!(status.is_success(), "GET {uri}: {status}");
    serde_json::from_slice(&bytes).unwrap()
}

/// The sample hashes of a sweep, read through the API.
pub async fn sample_hashes(store: &Store, sweep: &str) -> Vec<String> {
    let samples = get_json(store, &format!("/api/sweeps/{sweep}/samples")).await;
    samples["samples"]
        .as_array()
        .expect("a sweep's samples are a list")
        .iter()
        .filter_map(|s| s["sample_hash"].as_str().map(String::from))
        .collect()
}

/// A new SQLite store in a scratch folder named after `name`, holding
/// `spec` queued through the API and run to the end; the store and the
/// sweep's id.
pub async fn store_with_finished_sweep(name: &str, spec: &Value) -> (Store, String) {
    let store = repose_testkit::sqlite(&format!("repose-{name}")).await;
    let req = Request::post("/api/sweeps")
        .header("content-type", "application/json")
        .body(Body::from(spec.to_string()))
        .unwrap();
    let (status, bytes) = call(&store, req).await;
    assert_eq!(status, StatusCode::CREATED);
    let id = serde_json::from_slice::<Value>(&bytes).unwrap()["id"]
        .as_str()
        .unwrap()
        .to_string();
    while let Some(job) = store
        .claim(name, std::time::Duration::from_secs(60))
        .await
        .unwrap()
    {
        let scene = repose_physics::Scene::from_toml(&job.scene, &[]).unwrap();
        let report = repose_physics::run(&scene, &mut repose_physics::Quiet).unwrap();
        let record = repose_worker::record(&report).unwrap();
        store
            .complete(&job.job_id, name, &job.sample_hash, &record)
            .await
            .unwrap();
    }
    (store, id)
}

/// Percent-encodes everything but unreserved characters.
pub fn encode(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'a'..=b'z' | b'A'..=b'Z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

//! The router driven without a network (`tower::ServiceExt::oneshot`) over
//! a real SQLite store: validation answers, 404s, sweep lifecycle.

use axum::body::Body;
use axum::http::{Request, StatusCode};
use http_body_util::BodyExt;
use repose_store::Store;
use serde_json::{json, Value};
use tower::ServiceExt;

async fn store() -> Store {
    repose_testkit::sqlite("repose-api").await
}

async fn call(
    store: &Store,
    method: &str,
    uri: &str,
    body: Option<&str>,
) -> (StatusCode, Value, String) {
    send(
        store,
        method,
        uri,
        &[("content-type", "application/json")],
        body,
    )
    .await
}

/// Sends a request with the given headers; returns the status, the body
/// as JSON (null if it is none) and as text.
async fn send(
    store: &Store,
    method: &str,
    uri: &str,
    headers: &[(&str, &str)],
    body: Option<&str>,
) -> (StatusCode, Value, String) {
    let mut req = Request::builder().method(method).uri(uri);
    for (k, v) in headers {
        req = req.header(*k, *v);
    }
    let req = req
        .body(
            body.map(|b| Body::from(b.to_string()))
                .unwrap_or_else(Body::empty),
        )
        .unwrap();
    let resp = repose_api::app(store.clone()).oneshot(req).await.unwrap();
    let status = resp.status();
    let bytes = resp.into_body().collect().await.unwrap().to_bytes();
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let json = serde_json::from_str(&text).unwrap_or(Value::Null);
    (status, json, text)
}

#[tokio::test]
async fn invalid_sweeps_get_a_4xx_naming_the_field() {
    let s = store().await;
    let cases: Vec<(String, StatusCode, &str)> = vec![
        ("{not json".into(), StatusCode::BAD_REQUEST, "(body)"),
        (json!({"protocol": "fill_release", "axes": {"contact.mu": []}}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "axes.contact.mu"),
        (json!({"protocol": "fill_release", "axes": {"contact.mu": [0.2, -0.1]}}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "axes.contact.mu"),
        (json!({"protocol": "fill_release", "samples": "many"}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "samples"),
        (json!({"protocol": "fill_release", "samples": -3}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "samples"),
        (json!({"protocol": "sideways"}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "protocol"),
        (json!({"protocol": "fill_release", "colour": "red"}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "colour"),
        (json!({"protocol": "fill_release", "base": {"contact": {"k_n": "stiff"}}}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "base.contact.k_n"),
        (json!({"protocol": "fill_release", "axes": {"box.width": [0.05]}}).to_string(), StatusCode::UNPROCESSABLE_ENTITY, "axes.box.width"),
        (
            json!({"protocol": "fill_release", "samples": 1000, "axes": {"contact.mu": vec![0.2; 1000]}}).to_string(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "axes",
        ),
    ];
    for (body, status, field) in cases {
        let (got, json, text) = call(&s, "POST", "/api/sweeps", Some(&body)).await;
        assert_eq!(got, status, "{body}: {text}");
        assert!(
            json["errors"]
                .as_array()
                .unwrap()
                .iter()
                .any(|e| e["field"] == field),
            "{body}: {text}"
        );
        assert!(json["error"].as_str().unwrap().len() > 5);
    }
    // nothing was stored
    let (_, list, _) = call(&s, "GET", "/api/sweeps", None).await;
    assert_eq!(list["sweeps"].as_array().unwrap().len(), 0);
}

#[tokio::test]
async fn unknown_things_are_404() {
    let s = store().await;
    for uri in [
        "/api/sweeps/no-such-id",
        "/api/sweeps/no-such-id/points",
        "/api/sweeps/no-such-id/samples?format=csv",
        "/api/sweeps/no-such-id/figures/lh93/3",
        "/api/studies/xx99",
        "/api/studies/xx99/figures/3",
        "/api/studies/lh93/figures/99",
        "/api/samples/abc",
        "/api/nothing-here",
    ] {
        let (status, json, text) = call(&s, "GET", uri, None).await;
        assert_eq!(status, StatusCode::NOT_FOUND, "{uri}: {text}");
        assert!(json["error"].is_string(), "{uri}: {text}");
    }
    let (status, _, _) = call(&s, "POST", "/api/sweeps/no-such-id/cancel", None).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
}

#[tokio::test]
async fn a_sweep_is_created_listed_shown_and_cancelled() {
    let s = store().await;
    let spec = json!({"protocol": "tilt", "axes": {"contact.mu": [0.1, 0.2]}, "samples": 3, "priority": 2});
    let (status, created, text) = call(&s, "POST", "/api/sweeps", Some(&spec.to_string())).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    assert_eq!(created["jobs"], 6);
    let id = created["id"].as_str().unwrap().to_string();
    let (_, shown, _) = call(&s, "GET", &format!("/api/sweeps/{id}"), None).await;
    assert_eq!(shown["progress"]["queued"], 6);
    assert_eq!(shown["priority"], 2);
    assert_eq!(shown["name"], "tilt over contact.mu");
    let (_, list, _) = call(&s, "GET", "/api/sweeps", None).await;
    assert_eq!(list["sweeps"][0]["id"], id.as_str());
    // No results yet: points are empty, a figure over an axis not swept is refused.
    let (status, points, _) = call(&s, "GET", &format!("/api/sweeps/{id}/points"), None).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(points["points"].as_array().unwrap().len(), 0);
    let (status, err, _) = call(
        &s,
        "GET",
        &format!("/api/sweeps/{id}/series?y=theta_r"),
        None,
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert_eq!(err["errors"][0]["field"], "x");
    let (status, _, _) = call(&s, "GET", &format!("/api/sweeps/{id}/figures/lh93/9"), None).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    let (status, _, _) = call(
        &s,
        "GET",
        &format!("/api/sweeps/{id}/points?format=xml"),
        None,
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    let (status, cancelled, _) = call(&s, "POST", &format!("/api/sweeps/{id}/cancel"), None).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(cancelled["state"], "cancelled");
    assert_eq!(cancelled["progress"]["cancelled"], 6);
    // Nothing is left to cancel: 409, and the sweep as it was.
    let (status, err, _) = call(&s, "POST", &format!("/api/sweeps/{id}/cancel"), None).await;
    assert_eq!(status, StatusCode::CONFLICT, "{err}");
    let (_, shown, _) = call(&s, "GET", &format!("/api/sweeps/{id}"), None).await;
    assert_eq!(shown["progress"]["cancelled"], 6);
}

#[tokio::test]
async fn health_and_the_openapi_document_are_served() {
    let s = store().await;
    let (status, health, _) = call(&s, "GET", "/api/health", None).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(health["database"], "sqlite");
    let (status, doc, _) = call(&s, "GET", "/api/openapi.json", None).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(doc["openapi"], "3.1.0");
    for path in [
        "/api/sweeps",
        "/api/sweeps/{id}/points",
        "/api/sweeps/{id}/figures/{paper}/{figure}",
        "/api/protocols",
        "/api/studies/{paper}/sweeps/{key}",
        "/api/studies/{paper}/figures/{figure}",
    ] {
        assert!(doc["paths"][path].is_object(), "{path}");
    }
    // The schemas come from the handlers' types: a sweep spec's fields and
    // a figure's series are described, and every reference resolves.
    let schemas = &doc["components"]["schemas"];
    for field in ["protocol", "base", "axes", "samples", "fidelity", "study"] {
        assert!(
            schemas["SweepSpec"]["properties"][field].is_object(),
            "{field}"
        );
    }
    assert!(schemas["FigureData"]["properties"]["series"].is_object());
    let text = doc.to_string();
    for r in text.split("\"$ref\":\"#/components/schemas/").skip(1) {
        let name = &r[..r.find('"').unwrap()];
        assert!(schemas[name].is_object(), "dangling $ref {name}");
    }
}

#[tokio::test]
async fn protocols_are_described_from_the_registry() {
    let s = store().await;
    let (status, list, text) = call(&s, "GET", "/api/protocols", None).await;
    assert_eq!(status, StatusCode::OK, "{text}");
    let protocols = list["protocols"].as_array().unwrap();
    let names: Vec<&str> = protocols
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, repose_physics::registry::protocol_names());
    let tilt = protocols.iter().find(|p| p["name"] == "tilt").unwrap();
    let metrics: Vec<&str> = tilt["metrics"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        metrics,
        ["theta_r", "theta_r_line", "theta_r_endpoints", "theta_t"]
    );
    let sections = tilt["sections"].as_array().unwrap();
    let tilt_section = sections.iter().find(|x| x["key"] == "tilt").unwrap();
    assert_eq!(tilt_section["defaults"]["rate"], 10.0);
    assert_eq!(tilt["presets"]["quick"]["numerics.integrator"], "verlet");
}

#[tokio::test]
async fn a_papers_sweep_is_queued_by_its_key_and_reused_when_queued_again() {
    let s = store().await;
    let (status, studies, _) = call(&s, "GET", "/api/studies", None).await;
    assert_eq!(status, StatusCode::OK);
    let lh93 = &studies["studies"][0];
    assert_eq!(lh93["key"], "lh93");
    let figure3 = lh93["figures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["key"] == "3")
        .unwrap();
    assert_eq!(figure3["sweeps"], json!(["fig347"]));
    let body = json!({"fidelity": "quick", "reduced": true}).to_string();
    let (status, created, text) =
        call(&s, "POST", "/api/studies/lh93/sweeps/fig347", Some(&body)).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    assert_eq!(created["jobs"], 9);
    let id = created["id"].as_str().unwrap();
    let (_, sweep, _) = call(&s, "GET", &format!("/api/sweeps/{id}"), None).await;
    assert_eq!(sweep["study"], "lh93/fig347");
    assert_eq!(sweep["protocol"], "tilt");
    assert_eq!(sweep["spec"]["fidelity"], "quick");
    // The figure names the sweep it reads even before any sample is done.
    let (status, fig, text) = call(&s, "GET", "/api/studies/lh93/figures/3", None).await;
    assert_eq!(status, StatusCode::OK, "{text}");
    assert_eq!(fig["sweeps"]["fig347"], id);
    assert_eq!(
        fig["series"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|x| x["kind"] == "quoted")
            .count(),
        1
    );
    for (uri, body, status, field) in [
        (
            "/api/studies/lh93/sweeps/fig347",
            r#"{"fidelity": "slow"}"#,
            StatusCode::UNPROCESSABLE_ENTITY,
            "fidelity",
        ),
        (
            "/api/studies/lh93/sweeps/fig347",
            r#"{"samples": 0}"#,
            StatusCode::UNPROCESSABLE_ENTITY,
            "samples",
        ),
        (
            "/api/studies/lh93/sweeps/fig347",
            r#"{"colour": 1}"#,
            StatusCode::UNPROCESSABLE_ENTITY,
            "colour",
        ),
        (
            "/api/studies/lh93/sweeps/fig347",
            "{nope",
            StatusCode::BAD_REQUEST,
            "(body)",
        ),
    ] {
        let (got, json, text) = call(&s, "POST", uri, Some(body)).await;
        assert_eq!(got, status, "{body}: {text}");
        assert_eq!(json["errors"][0]["field"], field, "{body}: {text}");
    }
    let (status, _, _) = call(&s, "POST", "/api/studies/lh93/sweeps/fig99", None).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
}

#[tokio::test]
async fn a_papers_sweep_runs_a_variant_of_the_model_when_asked() {
    let s = store().await;
    let body = json!({"fidelity": "quick", "reduced": true,
        "set": {"material.limit_load": "net", "material.contact_attraction": "fading"}});
    let (status, created, text) = call(
        &s,
        "POST",
        "/api/studies/ep21/sweeps/heaps",
        Some(&body.to_string()),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    let id = created["id"].as_str().unwrap();
    let (_, sweep, _) = call(&s, "GET", &format!("/api/sweeps/{id}"), None).await;
    assert_eq!(sweep["spec"]["base"]["material"]["limit_load"], "net");
    assert_eq!(
        sweep["spec"]["base"]["material"]["contact_attraction"],
        "fading"
    );
    // The paper's own settings stay where the variant says nothing.
    assert_eq!(sweep["spec"]["base"]["material"]["rolling_friction"], 0.05);
    let name = sweep["name"].as_str().unwrap();
    assert!(
        name.ends_with(r#"[material.contact_attraction = "fading", material.limit_load = "net"]"#),
        "{name}"
    );
    for (set, field) in [
        (json!({"grains.diameter": 1e-3}), "set.grains.diameter"),
        (
            json!({"material.limit_load": "sideways"}),
            "set.material.limit_load",
        ),
        (
            json!({"material.friction.mu": 0.3}),
            "set.material.friction",
        ),
    ] {
        let body = json!({"reduced": true, "set": set}).to_string();
        let (got, json, text) =
            call(&s, "POST", "/api/studies/ep21/sweeps/heaps", Some(&body)).await;
        assert_eq!(got, StatusCode::UNPROCESSABLE_ENTITY, "{body}: {text}");
        assert_eq!(json["errors"][0]["field"], field, "{body}: {text}");
    }
}

#[tokio::test]
async fn a_study_sweep_queued_again_is_the_same_sweep_until_it_fails_or_is_cancelled() {
    let s = store().await;
    let body = json!({"fidelity": "quick", "reduced": true}).to_string();
    let post = |body: String| {
        let s = s.clone();
        async move { call(&s, "POST", "/api/studies/lh93/sweeps/fig347", Some(&body)).await }
    };
    let (status, first, text) = post(body.clone()).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    let id = first["id"].as_str().unwrap().to_string();
    // A job claimed and handed back, then the same request again: the
    // same sweep.
    let claim = s
        .claim("t", std::time::Duration::from_secs(60))
        .await
        .unwrap()
        .unwrap();
    assert!(s.release(&claim.job_id, "t").await.unwrap());
    let (status, again, text) = post(body.clone()).await;
    assert_eq!(status, StatusCode::OK, "{text}");
    assert_eq!(again["id"], id.as_str());
    assert_eq!(again["jobs"], 9);
    assert_eq!(again["queued"], 9);
    assert!(
        again["message"]
            .as_str()
            .unwrap()
            .contains("already queued"),
        "{text}"
    );
    let (_, list, _) = call(&s, "GET", "/api/sweeps", None).await;
    assert_eq!(list["sweeps"].as_array().unwrap().len(), 1, "{list}");
    // Other settings make another sweep.
    let (status, other, text) =
        post(json!({"fidelity": "quick", "reduced": true, "samples": 2}).to_string()).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    assert_ne!(other["id"], id.as_str());
    // A failed job: queueing again makes a new sweep, which runs it anew.
    let (_, _, _) = call(
        &s,
        "POST",
        &format!("/api/sweeps/{}/cancel", other["id"].as_str().unwrap()),
        None,
    )
    .await;
    let claim = s
        .claim("t", std::time::Duration::from_secs(60))
        .await
        .unwrap()
        .unwrap();
    assert_eq!(claim.sweep_id, id);
    assert!(s.fail(&claim.job_id, "t", "blew up").await.unwrap());
    let (status, renewed, text) = post(body.clone()).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    assert_ne!(renewed["id"], id.as_str());
    // Cancelled: the next request queues afresh too.
    let renewed = renewed["id"].as_str().unwrap().to_string();
    let (status, _, text) = call(&s, "POST", &format!("/api/sweeps/{renewed}/cancel"), None).await;
    assert!(status.is_success(), "{text}");
    let (status, fresh, text) = post(body).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    assert_ne!(fresh["id"], renewed.as_str());
}

#[tokio::test]
async fn a_papers_sweep_queued_cheapest_first_at_a_priority_is_claimed_ahead() {
    let s = store().await;
    let queue = |body: Value| {
        let s = s.clone();
        async move {
            let body = body.to_string();
            let (status, created, text) =
                call(&s, "POST", "/api/studies/ep21/sweeps/heaps", Some(&body)).await;
            assert_eq!(status, StatusCode::CREATED, "{text}");
            created["id"].as_str().unwrap().to_string()
        }
    };
    // Queued first, in listed order: its first job is 100 µm at the Moon's g.
    let listed = queue(json!({"fidelity": "quick", "reduced": true})).await;
    let cheapest = queue(json!({"fidelity": "quick", "reduced": true,
        "priority": 3, "order": "cheapest"}))
    .await;
    let (_, sweep, _) = call(&s, "GET", &format!("/api/sweeps/{cheapest}"), None).await;
    assert_eq!(sweep["spec"]["order"], "cheapest");
    assert_eq!(sweep["priority"], 3);
    let (_, sweep, _) = call(&s, "GET", &format!("/api/sweeps/{listed}"), None).await;
    assert!(sweep["spec"].get("order").is_none(), "{sweep}");
    // Three claims: the later sweep's three cheapest samples, the largest
    // grains under Earth's gravity first.
    let mut claimed = Vec::new();
    for _ in 0..3 {
        let c = s
            .claim("t", std::time::Duration::from_secs(60))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(c.sweep_id, cheapest);
        let scene: Value = serde_json::from_str(&c.scene).unwrap();
        let d = scene["grains"]["diameter"].as_f64().unwrap();
        let g = -scene["gravity"][2].as_f64().unwrap();
        claimed.push((d, g));
    }
    assert_eq!(claimed[0], (1e-3, 9.81));
    assert_eq!(claimed[1].0, 1e-3);
    assert!((claimed[1].1 - 9.81 * 0.165).abs() < 1e-9);
    assert_eq!(claimed[2].0, 2.5e-4);
    let body = json!({"reduced": true, "order": "fastest"}).to_string();
    let (got, json, text) = call(&s, "POST", "/api/studies/ep21/sweeps/heaps", Some(&body)).await;
    assert_eq!(got, StatusCode::UNPROCESSABLE_ENTITY, "{text}");
    assert_eq!(json["errors"][0]["field"], "order", "{text}");
}

#[tokio::test]
async fn a_slice_of_a_papers_sweep_runs_ahead_and_shares_its_samples_with_the_whole() {
    let s = store().await;
    let post = |body: Value| {
        let s = s.clone();
        async move {
            let body = body.to_string();
            call(&s, "POST", "/api/studies/ep21/sweeps/heaps", Some(&body)).await
        }
    };
    // Earth's points, the gravity written with integers: numbers are
    // matched by value and queued as the axis spells them.
    let (status, slice, text) = post(json!({"fidelity": "quick", "reduced": true,
        "priority": 5, "only": {"gravity": [[0, 0, -9.81]]}}))
    .await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    assert_eq!(slice["jobs"], 3, "three sizes on Earth: {text}");
    let slice_id = slice["id"].as_str().unwrap().to_string();
    let (_, sweep, _) = call(&s, "GET", &format!("/api/sweeps/{slice_id}"), None).await;
    assert_eq!(sweep["spec"]["axes"]["gravity"], json!([[0.0, 0.0, -9.81]]));
    assert!(
        sweep["spec"].get("study").is_none(),
        "a slice is not the study's sweep: {sweep}"
    );
    assert!(
        sweep["name"]
            .as_str()
            .unwrap()
            .ends_with("only gravity = [0.0,0.0,-9.81]"),
        "{sweep}"
    );
    let (status, whole, text) = post(json!({"fidelity": "quick", "reduced": true})).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    assert_eq!(whole["jobs"], 6, "{text}");
    // The slice is claimed first; then, with its three samples running,
    // the whole sweep's copies of them are skipped: only its points at the
    // Moon's gravity are left to claim.
    for k in 0..6 {
        let c = s
            .claim("t", std::time::Duration::from_secs(60))
            .await
            .unwrap();
        let c = c.unwrap_or_else(|| panic!("nothing left to claim after {k} claims"));
        let scene: Value = serde_json::from_str(&c.scene).unwrap();
        let g = -scene["gravity"][2].as_f64().unwrap();
        if k < 3 {
            assert_eq!((c.sweep_id.as_str(), g), (slice_id.as_str(), 9.81));
        } else {
            assert_eq!(c.sweep_id, whole["id"].as_str().unwrap());
            assert!((g - 9.81 * 0.165).abs() < 1e-9, "claim {k}: g = {g}");
        }
    }
    assert!(s
        .claim("t", std::time::Duration::from_secs(60))
        .await
        .unwrap()
        .is_none());
    for (body, field) in [
        (json!({"reduced": true, "only": {"seed": [1]}}), "only.seed"),
        (
            json!({"reduced": true, "only": {"gravity": [[0, 0, -1]]}}),
            "only.gravity",
        ),
        (
            json!({"reduced": true, "only": {"gravity": []}}),
            "only.gravity",
        ),
    ] {
        let (got, json, text) = post(body).await;
        assert_eq!(got, StatusCode::UNPROCESSABLE_ENTITY, "{text}");
        assert_eq!(json["errors"][0]["field"], field, "{text}");
    }
}

#[tokio::test]
async fn the_files_of_docs_are_served_by_name_and_nothing_else_is() {
    let s = store().await;
    let (status, _, text) = call(&s, "GET", "/docs/speed-vs-accuracy.md", None).await;
    assert_eq!(status, StatusCode::OK);
    assert!(text.starts_with("# Speed against accuracy"), "{text}");
    let (status, _, text) = call(&s, "GET", "/docs/tradeoff-heap.md", None).await;
    assert_eq!(status, StatusCode::OK);
    assert!(text.contains("poured heap"), "{text}");
    let (status, _, text) = call(&s, "GET", "/docs/reproduction-fig3.svg", None).await;
    assert_eq!(status, StatusCode::OK);
    assert!(text.starts_with("<svg"));
    let (status, _, text) = call(&s, "GET", "/docs/model-3d.md", None).await;
    assert_eq!(status, StatusCode::OK);
    assert!(text.starts_with("# The 3D model"), "{text}");
    for bad in [
        "/docs/..%2FCargo.toml",
        "/docs/..%2F..%2FCargo.toml",
        "/docs/nothing.svg",
    ] {
        let (status, json, text) = call(&s, "GET", bad, None).await;
        assert_eq!(status, StatusCode::NOT_FOUND, "{bad}: {text}");
        assert!(json["error"].is_string(), "{bad}: {text}");
    }
}

/// The relative targets of a Markdown text's links and images.
fn link_targets(markdown: &str) -> Vec<&str> {
    markdown
        .split("](")
        .skip(1)
        .filter_map(|rest| rest.split([')', '#']).next())
        .filter(|t| !t.is_empty() && !t.contains(':') && !t.starts_with('/'))
        .collect()
}

#[tokio::test]
async fn every_papers_report_is_served_with_every_file_it_links_in_docs() {
    let s = store().await;
    for paper in repose_studies::papers::PAPERS {
        let path = format!("/docs/{}.md", paper.report);
        let (status, _, report) = call(&s, "GET", &path, None).await;
        assert_eq!(status, StatusCode::OK, "{path}");
        let targets = link_targets(&report);
        assert!(
            targets.iter().any(|t| t.ends_with(".svg")),
            "{path} shows no figure"
        );
        for target in targets.into_iter().filter(|t| !t.starts_with("..")) {
            let (status, _, _) = call(&s, "GET", &format!("/docs/{target}"), None).await;
            assert_eq!(status, StatusCode::OK, "{path} links {target}");
        }
    }
}

#[tokio::test]
async fn a_sweep_reports_what_its_samples_cost() {
    let s = store().await;
    let spec = json!({"protocol": "fill_release", "base": {"box": {"width": 1.0, "height": 1.0}}, "samples": 2, "fidelity": "quick"});
    let (status, created, text) = call(&s, "POST", "/api/sweeps", Some(&spec.to_string())).await;
    assert_eq!(status, StatusCode::CREATED, "{text}");
    let id = created["id"].as_str().unwrap();
    let (_, sweep, _) = call(&s, "GET", &format!("/api/sweeps/{id}"), None).await;
    assert_eq!(sweep["cost"]["samples"], 0);
    // Run both jobs the way a worker does.
    let mut steps = 0i64;
    while let Some(job) = s
        .claim("test", std::time::Duration::from_secs(60))
        .await
        .unwrap()
    {
        let scene = repose_physics::Scene::from_toml(&job.scene, &[]).unwrap();
        let report = repose_physics::run(&scene, &mut repose_physics::Quiet).unwrap();
        steps += report.particle_steps as i64;
        let record = repose_worker::record(&report).unwrap();
        assert!(s
            .complete(&job.job_id, "test", &job.sample_hash, &record)
            .await
            .unwrap());
    }
    let (_, sweep, _) = call(&s, "GET", &format!("/api/sweeps/{id}"), None).await;
    assert_eq!(sweep["cost"]["samples"], 2);
    assert_eq!(sweep["cost"]["particle_steps"].as_i64().unwrap(), steps);
    assert!(sweep["cost"]["wall_time"].as_f64().unwrap() > 0.0);
    // The resolved scene of each job names the sweep's preset.
    let (_, samples, _) = call(&s, "GET", &format!("/api/sweeps/{id}/samples"), None).await;
    let hash = samples["samples"][0]["sample_hash"].as_str().unwrap();
    let (_, report, _) = call(&s, "GET", &format!("/api/samples/{hash}"), None).await;
    assert_eq!(report["scene"]["preset"], "quick");
    assert_eq!(report["options"]["preset"], "quick");
    assert_eq!(report["scene"]["numerics"]["dt_factor"], 0.05);
    // Points carry every metric the protocol declares; the CSV has a
    // column for each.
    let (_, points, _) = call(&s, "GET", &format!("/api/sweeps/{id}/points"), None).await;
    let metrics = points["points"][0]["metrics"].as_object().unwrap();
    let names: Vec<&String> = metrics.keys().collect();
    assert_eq!(names, ["theta_r", "theta_r_endpoints", "theta_r_line"]);
    let (status, _, csv) = call(
        &s,
        "GET",
        &format!("/api/sweeps/{id}/points?format=csv"),
        None,
    )
    .await;
    assert_eq!(status, StatusCode::OK);
    assert!(
        csv.starts_with("samples,failures,theta_r_n,theta_r_mean"),
        "{csv}"
    );
}

async fn call_as(
    app: &axum::Router,
    method: &str,
    uri: &str,
    token: Option<&str>,
    body: Option<&str>,
) -> (StatusCode, axum::http::HeaderMap) {
    let mut req = Request::builder()
        .method(method)
        .uri(uri)
        .header("content-type", "application/json");
    if let Some(t) = token {
        req = req.header("authorization", format!("Bearer {t}"));
    }
    let req = req
        .body(
            body.map(|b| Body::from(b.to_string()))
                .unwrap_or_else(Body::empty),
        )
        .unwrap();
    let resp = app.clone().oneshot(req).await.unwrap();
    (resp.status(), resp.headers().clone())
}

#[tokio::test]
async fn with_a_token_changes_need_it_and_a_private_server_guards_reading() {
    let s = store().await;
    let secret = "a-long-enough-secret-token";
    let options = |private| repose_api::Options {
        access: repose_api::Access {
            token: Some(repose_api::Token::new(secret).unwrap()),
            private,
        },
        ..Default::default()
    };
    let app = repose_api::app_with(s.clone(), options(false));
    let spec = json!({"protocol": "fill_release", "samples": 1}).to_string();
    for (token, want) in [
        (None, StatusCode::UNAUTHORIZED),
        (Some("a-long-enough-secret-toke"), StatusCode::UNAUTHORIZED),
        (Some("wrong"), StatusCode::UNAUTHORIZED),
        (Some(secret), StatusCode::CREATED),
    ] {
        let (status, headers) = call_as(&app, "POST", "/api/sweeps", token, Some(&spec)).await;
        assert_eq!(status, want, "{token:?}");
        if status == StatusCode::UNAUTHORIZED {
            assert!(headers["www-authenticate"]
                .to_str()
                .unwrap()
                .starts_with("Bearer"));
        }
    }
    let (status, _) = call_as(&app, "POST", "/api/studies/lh93/sweeps/fig2a", None, None).await;
    assert_eq!(status, StatusCode::UNAUTHORIZED);
    // Reading stays open unless the server is private.
    assert_eq!(
        call_as(&app, "GET", "/api/sweeps", None, None).await.0,
        StatusCode::OK
    );
    let private = repose_api::app_with(s.clone(), options(true));
    for (uri, token, want) in [
        ("/api/sweeps", None, StatusCode::UNAUTHORIZED),
        ("/api/sweeps", Some(secret), StatusCode::OK),
        (
            "/api/studies/lh93/figures/3",
            None,
            StatusCode::UNAUTHORIZED,
        ),
        ("/api/health", None, StatusCode::OK),
        ("/", None, StatusCode::OK),
        ("/static/app.js", None, StatusCode::OK),
    ] {
        assert_eq!(
            call_as(&private, "GET", uri, token, None).await.0,
            want,
            "{uri} {token:?}"
        );
    }
}

#[tokio::test]
async fn failed_jobs_are_queued_again_and_finished_ones_are_kept() {
    let s = store().await;
    let spec = json!({"protocol": "fill_release", "samples": 3}).to_string();
    let (_, created, _) = call(&s, "POST", "/api/sweeps", Some(&spec)).await;
    let id = created["id"].as_str().unwrap().to_string();
    // Nothing failed yet.
    let (status, body, text) = call(&s, "POST", &format!("/api/sweeps/{id}/retry"), None).await;
    assert_eq!(status, StatusCode::OK, "{text}");
    assert_eq!(body["retried"], 0);
    // One job finishes, two end failed (as when lost workers use up their attempts).
    let lease = std::time::Duration::from_secs(60);
    let first = s.claim("w", lease).await.unwrap().unwrap();
    let record = repose_store::ResultRecord {
        engine: "test".into(),
        seed: 1,
        outcome: "not_settled".into(),
        reason: Some("not settled".into()),
        metrics: Default::default(),
        counts: Default::default(),
        report: "{}".into(),
    };
    assert!(s
        .complete(&first.job_id, "w", &first.sample_hash, &record)
        .await
        .unwrap());
    for _ in 0..2 {
        let job = s.claim("w", lease).await.unwrap().unwrap();
        assert!(s
            .fail(&job.job_id, "w", "lease lost three times")
            .await
            .unwrap());
    }
    let (status, body, text) = call(&s, "POST", &format!("/api/sweeps/{id}/retry"), None).await;
    assert_eq!(status, StatusCode::OK, "{text}");
    assert_eq!(body["retried"], 2);
    let p = &body["sweep"]["progress"];
    assert_eq!(
        (
            p["queued"].as_i64(),
            p["done"].as_i64(),
            p["failed"].as_i64()
        ),
        (Some(2), Some(1), Some(0))
    );
    // The retried jobs have fresh attempts; the finished one is not claimed again.
    let again = s.claim("w", lease).await.unwrap().unwrap();
    assert_ne!(again.job_id, first.job_id);
    assert_eq!(again.attempts, 1);
    // Unknown and cancelled sweeps.
    assert_eq!(
        call(&s, "POST", "/api/sweeps/nope/retry", None).await.0,
        StatusCode::NOT_FOUND
    );
    call(&s, "POST", &format!("/api/sweeps/{id}/cancel"), None).await;
    let (status, body, _) = call(&s, "POST", &format!("/api/sweeps/{id}/retry"), None).await;
    assert_eq!(status, StatusCode::CONFLICT);
    assert!(body["error"].as_str().unwrap().contains("cancelled"));
}

#[tokio::test]
async fn another_sites_page_cannot_change_anything() {
    let s = store().await;
    let spec = json!({"protocol": "fill_release", "samples": 1}).to_string();
    let json_type = ("content-type", "application/json");
    let host = ("host", "127.0.0.1:8080");
    // A page of another site posting through the user's browser.
    let (status, body, _) = send(
        &s,
        "POST",
        "/api/sweeps",
        &[json_type, host, ("origin", "http://evil.example")],
        Some(&spec),
    )
    .await;
    assert_eq!(status, StatusCode::FORBIDDEN, "{body}");
    assert_eq!(body["errors"][0]["field"], "Origin");
    // The browser's form-like request: a text body needs no permission.
    let (status, body, _) = send(
        &s,
        "POST",
        "/api/sweeps",
        &[("content-type", "text/plain"), host],
        Some(&spec),
    )
    .await;
    assert_eq!(status, StatusCode::UNSUPPORTED_MEDIA_TYPE, "{body}");
    assert_eq!(body["errors"][0]["field"], "Content-Type");
    // Nothing was queued by either.
    let (_, list, _) = call(&s, "GET", "/api/sweeps", None).await;
    assert_eq!(list["sweeps"].as_array().unwrap().len(), 0, "{list}");
    // The server's own page (same host, behind a proxy too), and a program
    // that sends no Origin, may.
    for headers in [
        vec![json_type, host, ("origin", "http://127.0.0.1:8080")],
        vec![
            json_type,
            host,
            ("x-forwarded-host", "repose.example"),
            ("origin", "https://repose.example"),
        ],
        vec![json_type],
    ] {
        let (status, body, _) = send(&s, "POST", "/api/sweeps", &headers, Some(&spec)).await;
        assert_eq!(status, StatusCode::CREATED, "{headers:?}: {body}");
    }
    // A change without a body needs no content type.
    let (_, list, _) = call(&s, "GET", "/api/sweeps", None).await;
    let id = list["sweeps"][0]["id"].as_str().unwrap().to_string();
    let (status, body, _) = send(&s, "POST", &format!("/api/sweeps/{id}/cancel"), &[], None).await;
    assert_eq!(status, StatusCode::OK, "{body}");
    // Reading is never refused for its origin.
    let (status, _, _) = send(
        &s,
        "GET",
        "/api/sweeps",
        &[("origin", "http://evil.example")],
        None,
    )
    .await;
    assert_eq!(status, StatusCode::OK);
}

#[tokio::test]
async fn a_posted_sweep_cannot_take_a_papers_figure_and_wrong_methods_say_so() {
    let s = store().await;
    let spec =
        json!({"protocol": "fill_release", "samples": 1, "study": "lh93/fig347"}).to_string();
    let (status, body, _) = call(&s, "POST", "/api/sweeps", Some(&spec)).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{body}");
    assert_eq!(body["errors"][0]["field"], "study");
    let (_, list, _) = call(&s, "GET", "/api/sweeps", None).await;
    assert_eq!(list["sweeps"].as_array().unwrap().len(), 0, "{list}");
    let (status, body, _) = call(&s, "DELETE", "/api/health", None).await;
    assert_eq!(status, StatusCode::METHOD_NOT_ALLOWED);
    assert!(body["error"].as_str().unwrap().contains("DELETE"), "{body}");
}

//! The OpenAPI 3.1 document: the contract between the server and its
//! clients.
//!
//! It starts from what utoipa derives from the handlers and their types,
//! then [`refine`] states what the types alone cannot: the names the
//! registries accept (protocols, presets, metrics, papers, figures, report
//! files), the parameters the handlers require, the bounds they check, the
//! shape of axis values, and every status a route answers with. The test
//! `tests/contract.rs` sends requests generated from this document and
//! checks every answer against it.

mod refine;

use axum::http::header;
use axum::response::IntoResponse;
use std::sync::OnceLock;
use utoipa::OpenApi;

#[derive(OpenApi)]
#[openapi(
    info(
        title = "repose",
        description = "Parameter studies of granular piles: protocols and their metrics, sweeps of scenes, \
                       per-sample results, per-point statistics, and the papers' figures with their theory curves."
    ),
    paths(
        crate::index,
        crate::static_file,
        crate::doc_file,
        crate::health,
        crate::openapi::serve,
        crate::studies::protocols,
        crate::studies::list,
        crate::studies::show,
        crate::studies::queue,
        crate::studies::figure,
        crate::studies::comparison,
        crate::studies::sweep_figures,
        crate::studies::sweep_figure,
        crate::sweeps::create_sweep,
        crate::sweeps::list_sweeps,
        crate::sweeps::show_sweep,
        crate::sweeps::cancel_sweep,
        crate::sweeps::retry_sweep,
        crate::sweeps::samples,
        crate::sweeps::points,
        crate::sweeps::series,
        crate::sweeps::sample_report,
        crate::jobs::grains,
    )
)]
pub struct ApiDoc;

/// The document, built once.
fn built() -> &'static (serde_json::Value, String) {
    static DOC: OnceLock<(serde_json::Value, String)> = OnceLock::new();
    DOC.get_or_init(|| {
        let mut doc = serde_json::to_value(ApiDoc::openapi()).unwrap_or(serde_json::Value::Null);
        refine::apply(&mut doc);
        let text = doc.to_string();
        (doc, text)
    })
}

/// The document as JSON.
pub fn document() -> serde_json::Value {
    built().0.clone()
}

/// This document.
#[utoipa::path(get, path = "/api/openapi.json", tag = "service",
    responses((status = 200, description = "the OpenAPI 3.1 document", body = Object)))]
pub(crate) async fn serve() -> impl IntoResponse {
    (
        [(header::CONTENT_TYPE, "application/json")],
        built().1.as_str(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_document_builds_with_every_refinement_in_place() {
        let doc = document();
        assert_eq!(doc["openapi"], "3.1.0");
        let protocols = &doc["components"]["schemas"]["SweepSpec"]["properties"]["protocol"];
        let names: Vec<&str> = protocols["enum"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|v| v.as_str())
            .collect();
        assert_eq!(names, repose_physics::registry::protocol_names());
        assert!(doc["paths"]["/api/sweeps/{id}/series"]["get"]["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["name"] == "x" && p["required"] == true));
    }
}

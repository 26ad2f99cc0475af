//! The OpenAPI 3.1 document, generated from the handlers and their types.

use axum::Json;
use utoipa::OpenApi;

#[derive(OpenApi)]
#[openapi(
    info(
        title = "repose",
        description = "Parameter studies of granular piles: protocols and their metrics, sweeps of scenes, \
                       per-sample results, per-point statistics, and the papers' figures with their theory curves."
    ),
    paths(
        crate::health,
        crate::doc_file,
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
    )
)]
pub struct ApiDoc;

/// The document as JSON.
pub fn document() -> serde_json::Value {
    serde_json::to_value(ApiDoc::openapi()).unwrap_or(serde_json::Value::Null)
}

pub(crate) async fn serve() -> Json<serde_json::Value> {
    Json(document())
}

//! # repose-api
//!
//! The sweep service over HTTP (JSON). Handlers are thin: they parse,
//! call the store and the studies, and shape the answer. [`app`] builds the
//! router, so tests drive it without a network and `repose serve` mounts it
//! on a socket. The OpenAPI document at `/api/openapi.json` is generated
//! from the handlers and their types and completed from the registries
//! ([`openapi`]); `tests/contract.rs` holds the server to it with requests
//! generated from the document itself.
//!
//! ```text
//! curl -s localhost:8080/api/health
//! curl -s localhost:8080/api/protocols
//! curl -s -X POST localhost:8080/api/sweeps -H 'content-type: application/json' \
//!      -d '{"protocol":"fill_release","axes":{"contact.mu":[0.1,0.2]},"samples":4}'
//! curl -s -X POST localhost:8080/api/studies/lh93/sweeps/fig347
//! curl -s localhost:8080/api/studies/lh93/figures/3
//! ```
//!
//! Errors a client can cause are 4xx with a JSON body
//! `{"error": "...", "errors": [{"field": "...", "message": "..."}]}`;
//! an unknown sweep is 404. Only a failing database gives a 5xx.

pub mod access;
mod jobs;
pub mod openapi;
pub mod server;
mod studies;
mod sweeps;

use axum::extract::{Path, State};
use axum::http::{header, StatusCode};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use repose_physics::scene::{FieldError, SceneError};
use repose_store::Store;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Duration;
use tower_http::catch_panic::CatchPanicLayer;
use tower_http::timeout::TimeoutLayer;

pub use access::{Access, Token};

/// Attempts a job gets before it is marked failed.
pub const MAX_ATTEMPTS: i64 = repose_store::DEFAULT_MAX_ATTEMPTS;

#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    /// Where to read reports from first (see [`doc_file`]).
    pub docs: Option<PathBuf>,
    pub access: Access,
}

/// How a router serves: where its reports are, who may do what, how long
/// a request may take.
#[derive(Debug, Clone)]
pub struct Options {
    /// Read reports from this folder when it holds a newer copy
    /// (`repose serve` passes the working directory's `docs/`, which
    /// `repose tradeoff` and `repose reproduce` regenerate).
    pub docs: Option<PathBuf>,
    pub access: Access,
    /// Longest a request may take from its headers to its answer: a
    /// client that sends its body slowly gets 408 after this.
    pub request_timeout: Duration,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            docs: None,
            access: Access::default(),
            request_timeout: Duration::from_secs(60),
        }
    }
}

/// The router of the whole service, open to every request, serving the
/// reports compiled into it.
pub fn app(store: Store) -> Router {
    app_with(store, Options::default())
}

/// The router with its options. A handler that panics answers 500 instead
/// of dropping the connection.
pub fn app_with(store: Store, options: Options) -> Router {
    let state = AppState {
        store,
        docs: options.docs,
        access: options.access,
    };
    routes()
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            access::check,
        ))
        .layer(axum::middleware::from_fn(access::same_site))
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            options.request_timeout,
        ))
        .layer(CatchPanicLayer::custom(panicked))
        .with_state(state)
}

fn panicked(_: Box<dyn std::any::Any + Send + 'static>) -> Response {
    tracing::error!("a handler panicked");
    ApiError::new(
        StatusCode::INTERNAL_SERVER_ERROR,
        "the server failed on this request",
    )
    .into_response()
}

fn routes() -> Router<AppState> {
    Router::new()
        .route("/", get(index))
        .route("/static/{file}", get(static_file))
        .route("/docs/{file}", get(doc_file))
        .route("/api/health", get(health))
        .route("/api/openapi.json", get(openapi::serve))
        .route("/api/protocols", get(studies::protocols))
        .route("/api/studies", get(studies::list))
        .route("/api/studies/{paper}", get(studies::show))
        .route("/api/studies/{paper}/sweeps/{key}", post(studies::queue))
        .route(
            "/api/studies/{paper}/figures/{figure}",
            get(studies::figure),
        )
        .route("/api/studies/{paper}/comparison", get(studies::comparison))
        .route(
            "/api/sweeps",
            get(sweeps::list_sweeps).post(sweeps::create_sweep),
        )
        .route("/api/sweeps/{id}", get(sweeps::show_sweep))
        .route("/api/sweeps/{id}/cancel", post(sweeps::cancel_sweep))
        .route("/api/sweeps/{id}/retry", post(sweeps::retry_sweep))
        .route("/api/sweeps/{id}/samples", get(sweeps::samples))
        .route("/api/sweeps/{id}/points", get(sweeps::points))
        .route("/api/sweeps/{id}/series", get(sweeps::series))
        .route("/api/sweeps/{id}/figures", get(studies::sweep_figures))
        .route(
            "/api/sweeps/{id}/figures/{paper}/{figure}",
            get(studies::sweep_figure),
        )
        .route("/api/samples/{hash}", get(sweeps::sample_report))
        .route("/api/jobs/{id}/grains", get(jobs::grains))
        .fallback(not_found)
        .method_not_allowed_fallback(method_not_allowed)
}

/// One field at fault.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct ErrorField {
    /// Dotted path of the field, e.g. `base.contact.mu`.
    pub field: String,
    pub message: String,
}

/// The body of every 4xx and 5xx answer.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct ErrorBody {
    pub error: String,
    pub errors: Vec<ErrorField>,
}

/// An error answer: status, message and the fields at fault.
#[derive(Debug)]
pub struct ApiError {
    status: StatusCode,
    message: String,
    errors: Vec<FieldError>,
}

impl ApiError {
    fn new(status: StatusCode, message: impl Into<String>) -> Self {
        ApiError {
            status,
            message: message.into(),
            errors: Vec::new(),
        }
    }

    /// The same error with each field `rename` maps renamed (a field of
    /// the sweep a request was turned into, named as the request named it).
    fn renamed(mut self, rename: impl Fn(&str) -> Option<String>) -> Self {
        for e in &mut self.errors {
            if let Some(name) = rename(&e.field) {
                e.field = name;
            }
        }
        self
    }

    fn field(status: StatusCode, field: impl Into<String>, message: impl Into<String>) -> Self {
        let (field, message) = (field.into(), message.into());
        ApiError {
            status,
            message: format!("{field}: {message}"),
            errors: vec![FieldError { field, message }],
        }
    }

    fn not_found(what: &str) -> Self {
        ApiError::new(StatusCode::NOT_FOUND, format!("no {what} with that id"))
    }
}

impl From<SceneError> for ApiError {
    fn from(e: SceneError) -> Self {
        ApiError {
            status: StatusCode::UNPROCESSABLE_ENTITY,
            message: e.to_string(),
            errors: e.errors,
        }
    }
}

impl From<repose_store::StoreError> for ApiError {
    fn from(e: repose_store::StoreError) -> Self {
        tracing::error!("store: {e}");
        ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            format!("the database failed: {e}"),
        )
    }
}

/// A query string the extractor cannot read (a repeated key, say): 400
/// with the usual error body instead of axum's plain text.
impl From<axum::extract::rejection::QueryRejection> for ApiError {
    fn from(e: axum::extract::rejection::QueryRejection) -> Self {
        ApiError::field(e.status(), "(query)", e.body_text())
    }
}

/// A body that cannot be read (too large, broken off): its status with the
/// usual error body.
impl From<axum::extract::rejection::BytesRejection> for ApiError {
    fn from(e: axum::extract::rejection::BytesRejection) -> Self {
        ApiError::field(e.status(), "(body)", e.body_text())
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = ErrorBody {
            error: self.message,
            errors: self
                .errors
                .into_iter()
                .map(|e| ErrorField {
                    field: e.field,
                    message: e.message,
                })
                .collect(),
        };
        (self.status, Json(body)).into_response()
    }
}

type ApiResult<T> = Result<T, ApiError>;

/// The results browser (`web/`), compiled into the binary so a server needs
/// no files beside it and the page fetches nothing from elsewhere.
const WEB: &[(&str, &str, &str)] = &[
    (
        "app.js",
        "text/javascript; charset=utf-8",
        include_str!("../../../web/app.js"),
    ),
    (
        "plot.js",
        "text/javascript; charset=utf-8",
        include_str!("../../../web/plot.js"),
    ),
    (
        "style.css",
        "text/css; charset=utf-8",
        include_str!("../../../web/style.css"),
    ),
    (
        "heap3d.js",
        "text/javascript; charset=utf-8",
        include_str!("../../../web/heap3d.js"),
    ),
    (
        "markdown.js",
        "text/javascript; charset=utf-8",
        include_str!("../../../web/markdown.js"),
    ),
];

/// The committed `docs/` folder — the reports with their figures and data,
/// the notes on the model, the scenes and the service — compiled in.
#[derive(rust_embed::Embed)]
#[folder = "../../docs"]
struct Docs;

/// The names of the files of `docs/` the server serves, sorted.
pub(crate) fn doc_names() -> Vec<String> {
    let mut names: Vec<String> = Docs::iter().map(|n| n.into_owned()).collect();
    names.sort_unstable();
    names
}

fn content_type(file: &str) -> &'static str {
    match file.rsplit('.').next() {
        Some("md") => "text/markdown; charset=utf-8",
        Some("svg") => "image/svg+xml",
        Some("csv") => "text/csv; charset=utf-8",
        Some("json") => "application/json",
        _ => "application/octet-stream",
    }
}

/// A file of `docs/`: from the docs folder given to the server if it has
/// the file, else the copy compiled in. Only names compiled in are served,
/// so no path outside the folder can be reached.
#[utoipa::path(get, path = "/docs/{file}", tag = "reports",
    params(("file" = String, Path, description = "a file of docs/: the reports (reproduction.md, reproduction-ep21.md, speed-vs-accuracy.md, tradeoff-heap.md) with their SVG, CSV and JSON files, and the notes (model.md, model-3d.md, scene.md, service.md, benchmarks.md)")),
    responses((status = 200, description = "the file (Markdown, SVG, CSV or JSON)", content(
        (String = "text/markdown"), (String = "image/svg+xml"), (String = "text/csv"), (Object = "application/json"))),
        (status = 404, body = ErrorBody)))]
async fn doc_file(State(s): State<AppState>, Path(file): Path<String>) -> Response {
    let Some(embedded) = Docs::get(&file) else {
        return ApiError::new(StatusCode::NOT_FOUND, format!("no report file `{file}`"))
            .into_response();
    };
    let embedded = String::from_utf8_lossy(&embedded.data).into_owned();
    let body = match &s.docs {
        Some(dir) => tokio::fs::read_to_string(dir.join(&file))
            .await
            .unwrap_or(embedded),
        None => embedded,
    };
    (
        [
            (header::CONTENT_TYPE, content_type(&file)),
            (header::CACHE_CONTROL, "no-cache"),
        ],
        body,
    )
        .into_response()
}

/// The results browser.
#[utoipa::path(get, path = "/", tag = "reports",
    responses((status = 200, description = "the page", content_type = "text/html", body = String)))]
async fn index() -> Html<&'static str> {
    Html(include_str!("../../../web/index.html"))
}

/// A script or style sheet of the results browser.
#[utoipa::path(get, path = "/static/{file}", tag = "reports",
    params(("file" = String, Path, description = "a file of the page")),
    responses((status = 200, description = "the file", content(
        (String = "text/javascript"), (String = "text/css"))),
        (status = 404, body = ErrorBody)))]
async fn static_file(Path(file): Path<String>) -> Response {
    match WEB.iter().find(|(name, _, _)| *name == file) {
        Some((_, kind, body)) => (
            [
                (header::CONTENT_TYPE, *kind),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            *body,
        )
            .into_response(),
        None => ApiError::new(StatusCode::NOT_FOUND, format!("no file `{file}`")).into_response(),
    }
}

/// The service's state.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct Health {
    pub status: String,
    /// Engine name and version, stored with every result.
    pub engine: String,
    /// `sqlite` or `postgres`.
    pub database: String,
}

/// How [`Health`] names a database backend.
pub(crate) fn backend_name(backend: repose_store::Backend) -> String {
    format!("{backend:?}").to_lowercase()
}

/// Service and database status.
#[utoipa::path(get, path = "/api/health", tag = "service",
    responses((status = 200, body = Health), (status = 503, body = ErrorBody)))]
async fn health(State(s): State<AppState>) -> ApiResult<Json<Health>> {
    s.store.sweeps_count().await?;
    Ok(Json(Health {
        status: "ok".into(),
        engine: repose_physics::ENGINE.into(),
        database: backend_name(s.store.backend()),
    }))
}

/// A route asked with a method it does not take: 405 with the usual body.
async fn method_not_allowed(method: axum::http::Method, uri: axum::http::Uri) -> ApiError {
    ApiError::new(
        StatusCode::METHOD_NOT_ALLOWED,
        format!(
            "{} does not take {method}; see /api/openapi.json",
            uri.path()
        ),
    )
}

async fn not_found() -> ApiError {
    ApiError::new(
        StatusCode::NOT_FOUND,
        "no such route; see /api/openapi.json",
    )
}

//! # repose-api
//!
//! The sweep service over HTTP (JSON). Handlers are thin: they parse,
//! call the store, and shape the answer. [`app`] builds the router, so tests
//! drive it without a network and `repose serve` mounts it on a socket.
//!
//! ```text
//! curl -s localhost:8080/api/health
//! curl -s -X POST localhost:8080/api/sweeps -H 'content-type: application/json' \
//!      -d '{"protocol":"fill_release","axes":{"contact.mu":[0.1,0.2]},"samples":4}'
//! ```
//!
//! Errors a client can cause are 4xx with a JSON body
//! `{"error": "...", "errors": [{"field": "...", "message": "..."}]}`;
//! an unknown sweep is 404. Only a failing database gives a 5xx.

mod openapi;

use axum::body::Bytes;
use axum::extract::{Path, Query, State};
use axum::http::{header, StatusCode};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use repose_physics::scene::{FieldError, SceneError};
use repose_store::spec::SweepSpec;
use repose_store::{figure, Store, FIGURES, METRICS};
use serde::Deserialize;
use serde_json::{json, Value};
use std::path::PathBuf;

/// Attempts a job gets before it is marked failed.
pub const MAX_ATTEMPTS: i64 = 3;

#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    /// Where to read reports from first (see [`doc_file`]).
    pub docs: Option<PathBuf>,
}

/// The router of the whole service, serving the reports compiled into it.
pub fn app(store: Store) -> Router {
    app_with_docs(store, None)
}

/// The router, reading reports from `docs` when that folder holds a newer
/// copy (`repose serve` passes the working directory's `docs/`, which
/// `repose tradeoff` and `repose reproduce` regenerate).
pub fn app_with_docs(store: Store, docs: Option<PathBuf>) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/static/{file}", get(static_file))
        .route("/docs/{file}", get(doc_file))
        .route("/api/health", get(health))
        .route("/api/openapi.json", get(openapi))
        .route("/api/sweeps", get(list_sweeps).post(create_sweep))
        .route("/api/sweeps/{id}", get(show_sweep))
        .route("/api/sweeps/{id}/cancel", post(cancel_sweep))
        .route("/api/sweeps/{id}/samples", get(samples))
        .route("/api/sweeps/{id}/points", get(points))
        .route("/api/sweeps/{id}/series", get(series))
        .route("/api/sweeps/{id}/figures/{figure}", get(figure_series))
        .route("/api/samples/{hash}", get(sample_report))
        .route("/api/figures", get(list_figures))
        .fallback(not_found)
        .with_state(AppState { store, docs })
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

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = json!({ "error": self.message, "errors": self.errors });
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
        "markdown.js",
        "text/javascript; charset=utf-8",
        include_str!("../../../web/markdown.js"),
    ),
];

/// Lists report files of `docs/` as (name, contents).
macro_rules! docs {
    ($($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!("../../../docs/", $name)))),*]
    };
}

/// The generated reports, as committed in `docs/`.
const DOCS: &[(&str, &str)] = docs![
    "speed-vs-accuracy.md",
    "speed-vs-accuracy-repose.svg",
    "speed-vs-accuracy-tilt.svg",
    "speed-vs-accuracy.csv",
    "reproduction.md",
    "reproduction.json",
    "reproduction-fig2a.svg",
    "reproduction-fig2b.svg",
    "reproduction-fig3.svg",
    "reproduction-fig4.svg",
    "reproduction-fig5.svg",
    "reproduction-fig7a.svg",
    "reproduction-fig7b.svg",
    "reproduction-k_n.svg",
    "reproduction-gamma_n.svg",
    "reproduction-quick.md",
    "reproduction-quick.json",
    "reproduction-quick-fig2a.svg",
    "reproduction-quick-fig2b.svg",
    "reproduction-quick-fig3.svg",
    "reproduction-quick-fig4.svg",
    "reproduction-quick-fig5.svg",
    "reproduction-quick-fig7a.svg",
    "reproduction-quick-fig7b.svg",
    "reproduction-quick-k_n.svg",
    "reproduction-quick-gamma_n.svg",
];

fn content_type(file: &str) -> &'static str {
    match file.rsplit('.').next() {
        Some("md") => "text/markdown; charset=utf-8",
        Some("svg") => "image/svg+xml",
        Some("csv") => "text/csv; charset=utf-8",
        Some("json") => "application/json",
        _ => "application/octet-stream",
    }
}

/// A report file: from the docs folder given to the server if it has the
/// file, else the copy compiled in. Only the known report names are served,
/// so no path outside the folder can be reached.
async fn doc_file(State(s): State<AppState>, Path(file): Path<String>) -> Response {
    let Some((_, embedded)) = DOCS.iter().find(|(name, _)| *name == file) else {
        return ApiError::new(StatusCode::NOT_FOUND, format!("no report file `{file}`"))
            .into_response();
    };
    let body = match &s.docs {
        Some(dir) => tokio::fs::read_to_string(dir.join(&file))
            .await
            .unwrap_or_else(|_| embedded.to_string()),
        None => embedded.to_string(),
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

async fn index() -> Html<&'static str> {
    Html(include_str!("../../../web/index.html"))
}

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

async fn health(State(s): State<AppState>) -> ApiResult<Json<Value>> {
    sqlx_ping(&s.store).await?;
    Ok(Json(json!({
        "status": "ok",
        "engine": repose_physics::ENGINE,
        "database": format!("{:?}", s.store.backend()).to_lowercase(),
    })))
}

async fn sqlx_ping(store: &Store) -> ApiResult<()> {
    store.sweeps_count().await?;
    Ok(())
}

async fn openapi() -> Json<Value> {
    Json(openapi::document())
}

async fn not_found() -> ApiError {
    ApiError::new(
        StatusCode::NOT_FOUND,
        "no such route; see /api/openapi.json",
    )
}

/// Reads a sweep spec from a JSON body, naming the field of any type error.
fn parse_spec(body: &[u8]) -> ApiResult<SweepSpec> {
    let value: Value = serde_json::from_slice(body).map_err(|e| {
        ApiError::field(
            StatusCode::BAD_REQUEST,
            "(body)",
            format!("not valid JSON: {e}"),
        )
    })?;
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let field = if path.is_empty() || path == "." {
            "(body)".to_string()
        } else {
            path
        };
        ApiError::field(
            StatusCode::UNPROCESSABLE_ENTITY,
            field,
            e.inner().to_string(),
        )
    })
}

async fn create_sweep(
    State(s): State<AppState>,
    body: Bytes,
) -> ApiResult<(StatusCode, Json<Value>)> {
    let spec = parse_spec(&body)?;
    let jobs = spec.expand()?;
    let created = s.store.create_sweep(&spec, &jobs, MAX_ATTEMPTS).await?;
    let message = if created.reused > 0 {
        format!(
            "{} jobs: {} queued, {} reuse samples already computed",
            created.jobs,
            created.jobs - created.reused,
            created.reused
        )
    } else {
        format!("{} jobs queued", created.jobs)
    };
    Ok((
        StatusCode::CREATED,
        Json(json!({
            "id": created.id,
            "jobs": created.jobs,
            "reused": created.reused,
            "queued": created.jobs - created.reused,
            "message": message,
            "links": { "self": format!("/api/sweeps/{}", created.id) },
        })),
    ))
}

async fn list_sweeps(State(s): State<AppState>) -> ApiResult<Json<Value>> {
    Ok(Json(json!({ "sweeps": s.store.sweeps().await? })))
}

async fn show_sweep(State(s): State<AppState>, Path(id): Path<String>) -> ApiResult<Json<Value>> {
    let sweep = s
        .store
        .sweep(&id)
        .await?
        .ok_or_else(|| ApiError::not_found("sweep"))?;
    Ok(Json(serde_json::to_value(sweep).unwrap_or(Value::Null)))
}

async fn cancel_sweep(State(s): State<AppState>, Path(id): Path<String>) -> ApiResult<Json<Value>> {
    if !s.store.cancel_sweep(&id).await? {
        return Err(ApiError::not_found("sweep"));
    }
    let sweep = s
        .store
        .sweep(&id)
        .await?
        .ok_or_else(|| ApiError::not_found("sweep"))?;
    Ok(Json(serde_json::to_value(sweep).unwrap_or(Value::Null)))
}

#[derive(Deserialize)]
struct FormatQuery {
    format: Option<String>,
}

/// JSON by default; `?format=csv` for a CSV download.
enum Format {
    Json,
    Csv,
}

fn format_of(q: &FormatQuery) -> ApiResult<Format> {
    match q.format.as_deref() {
        None | Some("json") => Ok(Format::Json),
        Some("csv") => Ok(Format::Csv),
        Some(other) => Err(ApiError::field(
            StatusCode::BAD_REQUEST,
            "format",
            format!("`{other}` is not one of json, csv"),
        )),
    }
}

fn csv_response(name: &str, text: String) -> Response {
    (
        [
            (header::CONTENT_TYPE, "text/csv; charset=utf-8".to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{name}\""),
            ),
        ],
        text,
    )
        .into_response()
}

async fn require_sweep(store: &Store, id: &str) -> ApiResult<()> {
    match store.sweep(id).await? {
        Some(_) => Ok(()),
        None => Err(ApiError::not_found("sweep")),
    }
}

/// A listing as JSON (`{key: rows}`) or, with `?format=csv`, as a CSV download.
fn listing<T: serde::Serialize>(
    format: Format,
    key: &str,
    file: String,
    rows: &[T],
    csv: fn(&[T]) -> String,
) -> Response {
    match format {
        Format::Json => Json(json!({ key: rows })).into_response(),
        Format::Csv => csv_response(&file, csv(rows)),
    }
}

async fn samples(
    State(s): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<FormatQuery>,
) -> ApiResult<Response> {
    let format = format_of(&q)?;
    require_sweep(&s.store, &id).await?;
    let rows = s.store.samples(&id).await?;
    Ok(listing(
        format,
        "samples",
        format!("samples-{id}.csv"),
        &rows,
        repose_store::export::samples_csv,
    ))
}

async fn points(
    State(s): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<FormatQuery>,
) -> ApiResult<Response> {
    let format = format_of(&q)?;
    require_sweep(&s.store, &id).await?;
    let rows = s.store.points(&id).await?;
    Ok(listing(
        format,
        "points",
        format!("points-{id}.csv"),
        &rows,
        repose_store::export::points_csv,
    ))
}

#[derive(Deserialize)]
struct SeriesQuery {
    x: Option<String>,
    series: Option<String>,
    y: Option<String>,
}

async fn series_answer(
    store: &Store,
    id: &str,
    x: &str,
    series: Option<&str>,
    y: &str,
) -> ApiResult<Value> {
    require_sweep(store, id).await?;
    let points = store.points(id).await?;
    let rows = repose_store::series(&points, x, series, y).map_err(|e| {
        let field = match e {
            repose_store::SeriesError::Metric(_) => "y",
            repose_store::SeriesError::Axis(ref a) if Some(a.as_str()) == series => "series",
            repose_store::SeriesError::Axis(_) => "x",
        };
        ApiError::field(StatusCode::UNPROCESSABLE_ENTITY, field, e.to_string())
    })?;
    Ok(json!({ "x": x, "series": series, "y": y, "points": rows }))
}

async fn series(
    State(s): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<SeriesQuery>,
) -> ApiResult<Json<Value>> {
    let x = q.x.ok_or_else(|| {
        ApiError::field(
            StatusCode::BAD_REQUEST,
            "x",
            "required: the axis to plot along",
        )
    })?;
    let y = q.y.unwrap_or_else(|| "theta_r".to_string());
    Ok(Json(
        series_answer(&s.store, &id, &x, q.series.as_deref(), &y).await?,
    ))
}

async fn figure_series(
    State(s): State<AppState>,
    Path((id, name)): Path<(String, String)>,
) -> ApiResult<Json<Value>> {
    let f = figure(&name).ok_or_else(|| {
        let names: Vec<&str> = FIGURES.iter().map(|f| f.name).collect();
        ApiError::new(
            StatusCode::NOT_FOUND,
            format!("no figure `{name}`; figures are {}", names.join(", ")),
        )
    })?;
    let mut answer = series_answer(&s.store, &id, f.x, f.series, f.y).await?;
    answer["figure"] = json!(f.name);
    answer["title"] = json!(f.title);
    Ok(Json(answer))
}

async fn list_figures() -> Json<Value> {
    let metrics: Vec<Value> = METRICS
        .iter()
        .map(|(m, d)| json!({"name": m, "description": d}))
        .collect();
    Json(json!({ "figures": FIGURES, "metrics": metrics }))
}

async fn sample_report(
    State(s): State<AppState>,
    Path(hash): Path<String>,
) -> ApiResult<Json<Value>> {
    let report = s
        .store
        .report(&hash)
        .await?
        .ok_or_else(|| ApiError::not_found("sample"))?;
    Ok(Json(report))
}

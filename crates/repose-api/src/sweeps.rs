//! Sweeps: queue one, list them, follow one, read its samples, points and
//! series, and any sample's full report.

use crate::{ApiError, ApiResult, AppState, ErrorBody};
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, QueryRejection};
use axum::extract::{Path, Query, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::Json;
use repose_store::{
    Aggregate, Cancel, Created, NewJob, Point, Retry, Sample, SeriesPoint, Store, SweepInfo,
};
use repose_sweeps::SweepSpec;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// What queuing a sweep did.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct Queued {
    pub id: String,
    pub jobs: usize,
    /// Jobs whose sample was already computed: reused, not rerun.
    pub reused: usize,
    pub queued: usize,
    pub message: String,
    #[schema(value_type = Object)]
    pub links: Value,
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct SweepList {
    pub sweeps: Vec<SweepInfo>,
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct SampleList {
    pub samples: Vec<Sample>,
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct PointList {
    pub points: Vec<Point>,
}

/// A metric along an axis, one series per value of another axis.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct SeriesAnswer {
    pub x: String,
    pub series: Option<String>,
    pub y: String,
    pub points: Vec<SeriesPoint>,
}

/// Reads a JSON body into `T`, naming the field of any type error.
pub(crate) fn parse_body<T: serde::de::DeserializeOwned>(body: &[u8]) -> ApiResult<T> {
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

/// Expands and stores a sweep; the answer of every route that queues one.
pub(crate) async fn enqueue(
    store: &Store,
    spec: &SweepSpec,
) -> ApiResult<(StatusCode, Json<Queued>)> {
    // Each resolved scene is dropped once it is written as text.
    let new_jobs: Vec<NewJob> = spec.expand()?.into_iter().map(|j| j.to_new_job()).collect();
    let sweep = spec.new_sweep();
    if let Some(same) = store.same_sweep(&sweep, &new_jobs).await? {
        return Ok((StatusCode::OK, queued_answer(same, true)));
    }
    let created = store
        .create_sweep(&sweep, &new_jobs, crate::MAX_ATTEMPTS)
        .await?;
    Ok((StatusCode::CREATED, queued_answer(created, false)))
}

/// The answer to queueing a sweep: a new one, or the same study sweep
/// queued before (`existing`).
fn queued_answer(created: Created, existing: bool) -> Json<Queued> {
    let queued = created.jobs - created.reused;
    let message = if existing {
        format!(
            "the same sweep is already queued: {} jobs, {} done, {queued} to run",
            created.jobs, created.reused
        )
    } else if created.reused > 0 {
        format!(
            "{} jobs: {queued} queued, {} reuse samples already computed",
            created.jobs, created.reused
        )
    } else {
        format!("{} jobs queued", created.jobs)
    };
    Json(Queued {
        links: serde_json::json!({ "self": format!("/api/sweeps/{}", created.id) }),
        id: created.id,
        jobs: created.jobs,
        reused: created.reused,
        queued,
        message,
    })
}

/// Queue a sweep.
#[utoipa::path(post, path = "/api/sweeps", tag = "sweeps", request_body = SweepSpec,
    responses((status = 201, body = Queued), (status = 400, body = ErrorBody), (status = 422, body = ErrorBody)))]
pub async fn create_sweep(
    State(s): State<AppState>,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<(StatusCode, Json<Queued>)> {
    let spec: SweepSpec = parse_body(&body?)?;
    // A study's tag binds a sweep to a paper's figure; only queueing the
    // study's own sweep (`POST /api/studies/...`) sets it.
    if spec.study.is_some() {
        return Err(ApiError::field(
            StatusCode::UNPROCESSABLE_ENTITY,
            "study",
            "is set by the server when a paper's sweep is queued (POST /api/studies/{paper}/sweeps/{key}), not by a client",
        ));
    }
    enqueue(&s.store, &spec).await
}

/// Every sweep, newest first, with progress, ETA and cost.
#[utoipa::path(get, path = "/api/sweeps", tag = "sweeps", responses((status = 200, body = SweepList)))]
pub async fn list_sweeps(State(s): State<AppState>) -> ApiResult<Json<SweepList>> {
    Ok(Json(SweepList {
        sweeps: s.store.sweeps().await?,
    }))
}

pub(crate) async fn require_sweep(store: &Store, id: &str) -> ApiResult<SweepInfo> {
    store
        .sweep(id)
        .await?
        .ok_or_else(|| ApiError::not_found("sweep"))
}

/// One sweep with its progress counts and ETA.
#[utoipa::path(get, path = "/api/sweeps/{id}", tag = "sweeps", params(("id" = String, Path)),
    responses((status = 200, body = SweepInfo), (status = 404, body = ErrorBody)))]
pub async fn show_sweep(
    State(s): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<SweepInfo>> {
    Ok(Json(require_sweep(&s.store, &id).await?))
}

/// Cancel a sweep: queued jobs are dropped, running ones stop at their next heartbeat.
#[utoipa::path(post, path = "/api/sweeps/{id}/cancel", tag = "sweeps", params(("id" = String, Path)),
    responses((status = 200, body = SweepInfo), (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn cancel_sweep(
    State(s): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<SweepInfo>> {
    match s.store.cancel_sweep(&id).await? {
        Cancel::Unknown => Err(ApiError::not_found("sweep")),
        Cancel::Idle => Err(ApiError::new(
            StatusCode::CONFLICT,
            "the sweep has nothing queued or running to cancel; it is left as it is",
        )),
        Cancel::Cancelled => Ok(Json(require_sweep(&s.store, &id).await?)),
    }
}

/// What a retry queued again, and the sweep after it.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct Retried {
    /// Failed jobs queued again with fresh attempts.
    pub retried: u64,
    pub sweep: SweepInfo,
}

/// Run a sweep's failed jobs again (those whose attempts were used up by
/// lost workers); finished samples are not rerun.
#[utoipa::path(post, path = "/api/sweeps/{id}/retry", tag = "sweeps", params(("id" = String, Path)),
    responses((status = 200, body = Retried), (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn retry_sweep(
    State(s): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<Retried>> {
    let retried = match s.store.retry_failed(&id).await? {
        Retry::Unknown => return Err(ApiError::not_found("sweep")),
        Retry::Cancelled => {
            return Err(ApiError::new(
                StatusCode::CONFLICT,
                "the sweep was cancelled; queue it again instead",
            ))
        }
        Retry::Queued(n) => n,
    };
    Ok(Json(Retried {
        retried,
        sweep: require_sweep(&s.store, &id).await?,
    }))
}

#[derive(Deserialize, utoipa::IntoParams)]
#[into_params(parameter_in = Query)]
pub struct FormatQuery {
    /// `json` (the default) or `csv`; nothing else, not even an empty value.
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

/// The metrics a sweep's protocol declares, in its order.
pub(crate) fn declared(protocol: &str) -> Vec<String> {
    repose_physics::registry::find_protocol(protocol)
        .map(|p| p.metrics().iter().map(|m| m.name.to_string()).collect())
        .unwrap_or_default()
}

/// Per-sample results (JSON or CSV).
#[utoipa::path(get, path = "/api/sweeps/{id}/samples", tag = "sweeps",
    params(("id" = String, Path), FormatQuery),
    responses((status = 200, body = SampleList), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn samples(
    State(s): State<AppState>,
    Path(id): Path<String>,
    q: Result<Query<FormatQuery>, QueryRejection>,
) -> ApiResult<Response> {
    let Query(q) = q?;
    let format = format_of(&q)?;
    let sweep = require_sweep(&s.store, &id).await?;
    let rows = s.store.samples(&id).await?;
    Ok(listing(format, &format!("samples-{id}.csv"), || {
        let csv = repose_store::export::samples_csv(&rows, &declared(&sweep.protocol));
        (SampleList { samples: rows }, csv)
    }))
}

/// A listing as JSON or, with `?format=csv`, as a CSV download; `make`
/// gives both forms.
fn listing<T: Serialize>(
    format: Format,
    file: &str,
    make: impl FnOnce() -> (T, String),
) -> Response {
    let (json, csv) = make();
    match format {
        Format::Json => Json(json).into_response(),
        Format::Csv => csv_response(file, csv),
    }
}

/// A sweep's points, with every metric its protocol declares (n = 0 where
/// no sample measured it).
pub(crate) async fn points_of(store: &Store, sweep: &SweepInfo) -> ApiResult<Vec<Point>> {
    let mut points = store.points(&sweep.id).await?;
    let metrics = declared(&sweep.protocol);
    for p in &mut points {
        for m in &metrics {
            p.metrics.entry(m.clone()).or_insert(Aggregate::EMPTY);
        }
    }
    Ok(points)
}

/// Per-point n, mean, sd and sem of every metric (JSON or CSV).
#[utoipa::path(get, path = "/api/sweeps/{id}/points", tag = "sweeps",
    params(("id" = String, Path), FormatQuery),
    responses((status = 200, body = PointList), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn points(
    State(s): State<AppState>,
    Path(id): Path<String>,
    q: Result<Query<FormatQuery>, QueryRejection>,
) -> ApiResult<Response> {
    let Query(q) = q?;
    let format = format_of(&q)?;
    let sweep = require_sweep(&s.store, &id).await?;
    let rows = points_of(&s.store, &sweep).await?;
    Ok(listing(format, &format!("points-{id}.csv"), || {
        let csv = repose_store::export::points_csv(&rows, &declared(&sweep.protocol));
        (PointList { points: rows }, csv)
    }))
}

#[derive(Deserialize, utoipa::IntoParams)]
#[into_params(parameter_in = Query)]
pub struct SeriesQuery {
    /// Required: a key the sweep varies, e.g. `contact.mu` (400 without
    /// it, 422 if the sweep does not vary it).
    x: Option<String>,
    /// A second key the sweep varies: one series per value.
    series: Option<String>,
    /// A metric of the sweep's protocol (default: its headline metric; 422
    /// for a metric no sample of the sweep measured).
    y: Option<String>,
}

/// Any x / series / y choice over a sweep's axes.
#[utoipa::path(get, path = "/api/sweeps/{id}/series", tag = "sweeps",
    params(("id" = String, Path), SeriesQuery),
    responses((status = 200, body = SeriesAnswer), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody), (status = 422, body = ErrorBody)))]
pub async fn series(
    State(s): State<AppState>,
    Path(id): Path<String>,
    q: Result<Query<SeriesQuery>, QueryRejection>,
) -> ApiResult<Json<SeriesAnswer>> {
    let Query(q) = q?;
    let x = q.x.ok_or_else(|| {
        ApiError::field(
            StatusCode::BAD_REQUEST,
            "x",
            "required: the axis to plot along",
        )
    })?;
    let sweep = require_sweep(&s.store, &id).await?;
    let metrics = declared(&sweep.protocol);
    let y = q.y.or_else(|| metrics.first().cloned()).unwrap_or_default();
    let points = points_of(&s.store, &sweep).await?;
    let rows = repose_store::series(&points, &x, q.series.as_deref(), &y).map_err(|e| {
        let field = match e {
            repose_store::SeriesError::Metric(_) => "y",
            repose_store::SeriesError::Axis(ref a) if Some(a) == q.series.as_ref() => "series",
            repose_store::SeriesError::Axis(_) => "x",
        };
        ApiError::field(StatusCode::UNPROCESSABLE_ENTITY, field, e.to_string())
    })?;
    Ok(Json(SeriesAnswer {
        x,
        series: q.series,
        y,
        points: rows,
    }))
}

/// The full run report of one sample (final state, energy trace, scene),
/// in the current report shape whatever version stored it.
#[utoipa::path(get, path = "/api/samples/{hash}", tag = "sweeps", params(("hash" = String, Path)),
    responses((status = 200, description = "the run report", body = Object), (status = 404, body = ErrorBody)))]
pub async fn sample_report(
    State(s): State<AppState>,
    Path(hash): Path<String>,
) -> ApiResult<Json<Value>> {
    let report = s
        .store
        .report(&hash)
        .await?
        .ok_or_else(|| ApiError::not_found("sample"))?;
    Ok(Json(repose_physics::report::upgrade(report)))
}

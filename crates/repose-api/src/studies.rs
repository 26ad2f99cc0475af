//! The registry as the API serves it: protocols with their sections and
//! metrics, the papers' studies, their figures computed from stored data
//! with theory curves, and the comparison with each paper's results.

use crate::sweeps::{enqueue, parse_body, points_of, require_sweep, Queued};
use crate::{ApiError, ApiResult, AppState, ErrorBody};
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, QueryRejection};
use axum::extract::{Path, Query, State};
use axum::http::StatusCode;
use axum::Json;
use repose_physics::Preset;
use repose_physics::{protocols, registry};
use repose_store::{Store, SweepInfo};
use repose_studies::compare::Comparison;
use repose_studies::data::{StudyData, SweepData};
use repose_studies::paper::{Paper, PaperSummary, Queue};
use repose_studies::papers;
use repose_studies::FigureData;
use repose_sweeps::Order;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// One metric a protocol measures.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct MetricInfo {
    pub name: String,
    pub label: String,
    pub unit: String,
    pub description: String,
    pub phase: String,
}

/// One scene section a protocol or model owns, with its defaults.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct SectionInfo {
    pub key: String,
    pub about: String,
    #[schema(value_type = Object)]
    pub defaults: Value,
}

/// A registered protocol.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct ProtocolInfo {
    pub name: String,
    pub about: String,
    pub dimensions: Vec<usize>,
    pub models: Vec<String>,
    /// Its own sections and those of its default model.
    pub sections: Vec<SectionInfo>,
    /// The metrics it reports, the headline first.
    pub metrics: Vec<MetricInfo>,
    /// What each fidelity preset sets, by dotted key.
    #[schema(value_type = HashMap<String, Object>)]
    pub presets: BTreeMap<String, Value>,
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct ProtocolList {
    pub protocols: Vec<ProtocolInfo>,
}

fn describe(p: &dyn protocols::Protocol) -> ProtocolInfo {
    let model = registry::find_model(p.default_model(p.dimensions()[0]));
    let decls = model
        .map(|m| m.sections())
        .unwrap_or_default()
        .into_iter()
        .chain(p.sections());
    ProtocolInfo {
        name: p.name().into(),
        about: p.about().into(),
        dimensions: p.dimensions().to_vec(),
        models: p.models().iter().map(|m| m.to_string()).collect(),
        sections: decls
            .map(|d| SectionInfo {
                key: d.key.into(),
                about: d.about.into(),
                defaults: d.defaults(),
            })
            .collect(),
        metrics: p
            .metrics()
            .iter()
            .map(|m| MetricInfo {
                name: m.name.into(),
                label: m.label.into(),
                unit: m.unit.into(),
                description: m.description.into(),
                phase: m.phase.into(),
            })
            .collect(),
        presets: Preset::ALL
            .iter()
            .map(|pr| {
                let settings: serde_json::Map<String, Value> = p
                    .preset(*pr)
                    .into_iter()
                    .map(|(k, v)| (k.to_string(), v))
                    .collect();
                (pr.name().to_string(), Value::Object(settings))
            })
            .collect(),
    }
}

/// The protocols the engine runs: sections, metrics and presets.
#[utoipa::path(get, path = "/api/protocols", tag = "registry", responses((status = 200, body = ProtocolList)))]
pub async fn protocols() -> Json<ProtocolList> {
    Json(ProtocolList {
        protocols: registry::protocols().iter().map(|p| describe(*p)).collect(),
    })
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct StudyList {
    pub studies: Vec<PaperSummary>,
}

/// The papers' studies: their sweeps and figures.
#[utoipa::path(get, path = "/api/studies", tag = "studies", responses((status = 200, body = StudyList)))]
pub async fn list() -> Json<StudyList> {
    Json(StudyList {
        studies: papers::PAPERS.iter().map(|p| p.summary()).collect(),
    })
}

fn paper(key: &str) -> ApiResult<&'static Paper> {
    papers::find(key).ok_or_else(|| {
        let keys: Vec<&str> = papers::PAPERS.iter().map(|p| p.key).collect();
        ApiError::new(
            StatusCode::NOT_FOUND,
            format!("no study `{key}`; studies are {}", keys.join(", ")),
        )
    })
}

/// One paper's study.
#[utoipa::path(get, path = "/api/studies/{paper}", tag = "studies", params(("paper" = String, Path)),
    responses((status = 200, body = PaperSummary), (status = 404, body = ErrorBody)))]
pub async fn show(Path(key): Path<String>) -> ApiResult<Json<PaperSummary>> {
    Ok(Json(paper(&key)?.summary()))
}

/// How to queue a study sweep (every field optional).
#[derive(Debug, Default, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct QueueRequest {
    /// `quick`, `standard` (the default) or `paper`.
    #[schema(value_type = Option<String>)]
    pub fidelity: Option<Preset>,
    /// Samples a point, if not the paper's count.
    pub samples: Option<u32>,
    /// The small version of the sweep (tests, previews).
    #[serde(default)]
    pub reduced: bool,
    /// A variant of the model: dotted scene paths and the value each
    /// scene of the sweep takes, e.g. `{"material.limit_load": "net"}`.
    #[serde(default)]
    #[schema(value_type = Object)]
    pub set: BTreeMap<String, Value>,
    /// The claim priority (higher runs first), if not the study sweep's own.
    pub priority: Option<i64>,
    /// `listed` (the default: point by point) or `cheapest` (the samples
    /// the protocol estimates cheapest first).
    #[serde(default)]
    pub order: Order,
    /// A slice of the sweep to run ahead: for an axis, the values to queue
    /// (each one of the axis's own), e.g. `{"gravity": [[0, 0, -9.81]]}`.
    /// A slice is not the study's sweep (the figures read the whole one);
    /// the whole sweep, queued before or after, shares its samples.
    #[serde(default)]
    #[schema(value_type = Object)]
    pub only: BTreeMap<String, Vec<Value>>,
}

/// Queue the sweep behind a paper's figures: the same sweep the page's
/// buttons and `repose reproduce` queue.
#[utoipa::path(post, path = "/api/studies/{paper}/sweeps/{key}", tag = "studies",
    params(("paper" = String, Path), ("key" = String, Path, description = "the study sweep, e.g. fig347")),
    request_body(content = QueueRequest, description = "optional: an empty body queues the paper's sweep at the standard fidelity"),
    responses((status = 201, body = Queued, description = "queued"), (status = 200, body = Queued, description = "the same sweep, queued before with the same settings and samples and none failed: returned, not doubled"), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody), (status = 422, body = ErrorBody)))]
pub async fn queue(
    State(s): State<AppState>,
    Path((paper_key, key)): Path<(String, String)>,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult<(StatusCode, Json<Queued>)> {
    let body = body?;
    let p = paper(&paper_key)?;
    let sweep = p.sweep(&key).ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            format!("no sweep `{key}` in study {paper_key}"),
        )
    })?;
    let request: QueueRequest = if body.iter().all(u8::is_ascii_whitespace) {
        QueueRequest::default()
    } else {
        parse_body(&body)?
    };
    let queue = Queue {
        fidelity: request.fidelity.unwrap_or_default(),
        samples: request.samples,
        reduced: request.reduced,
        set: request.set.into_iter().collect(),
        priority: request.priority,
        order: request.order,
        only: request.only,
    };
    let spec = sweep
        .spec(p.key, &queue)
        .map_err(|e| ApiError::field(StatusCode::UNPROCESSABLE_ENTITY, e.field, e.message))?;
    // A scene the variant makes invalid names the setting it came from.
    enqueue(&s.store, &spec).await.map_err(|e| {
        e.renamed(|field| {
            let key = field.strip_prefix("base.")?;
            let set = queue.set.iter().any(|(k, _)| k == key);
            set.then(|| format!("set.{key}"))
        })
    })
}

#[derive(Debug, Deserialize, utoipa::IntoParams)]
#[into_params(parameter_in = Query)]
pub struct Bindings {
    /// Which sweep to read for each study sweep, as `key:id,key:id`;
    /// by default the newest sweep queued for it (400 if not written so,
    /// 404 if a named sweep does not exist).
    sweeps: Option<String>,
}

/// Everything stored for one sweep that a figure or comparison may read.
async fn sweep_data(store: &Store, sweep: &SweepInfo, report: bool) -> ApiResult<SweepData> {
    let points = points_of(store, sweep).await?;
    let samples = store.samples(&sweep.id).await?;
    let report = match (report, samples.first()) {
        (true, Some(first)) => store
            .report(&first.sample_hash)
            .await?
            .map(repose_physics::report::upgrade),
        _ => None,
    };
    Ok(SweepData {
        id: sweep.id.clone(),
        points,
        samples,
        report,
    })
}

/// The data of the given study sweeps, each bound to the sweep named in
/// `bindings` or to the newest one queued for it.
async fn study_data(
    store: &Store,
    p: &Paper,
    keys: &[String],
    bindings: &Bindings,
    needs_report: impl Fn(&str) -> bool,
) -> ApiResult<StudyData> {
    let mut named: BTreeMap<String, String> = BTreeMap::new();
    for pair in bindings.sweeps.iter().flat_map(|s| s.split(',')) {
        let (k, id) = pair.split_once(':').ok_or_else(|| {
            ApiError::field(
                StatusCode::BAD_REQUEST,
                "sweeps",
                "written as key:id,key:id",
            )
        })?;
        named.insert(k.trim().to_string(), id.trim().to_string());
    }
    let mut data = StudyData::default();
    for key in keys {
        let id = match named.get(key) {
            Some(id) => Some(id.clone()),
            None => store.latest_for_study(&format!("{}/{key}", p.key)).await?,
        };
        let Some(id) = id else { continue };
        let sweep = require_sweep(store, &id).await?;
        data.sweeps.insert(
            key.clone(),
            sweep_data(store, &sweep, needs_report(key)).await?,
        );
    }
    Ok(data)
}

/// A paper's figure from the newest sweeps queued for it (or those named),
/// with its theory curves and the values the paper quotes.
#[utoipa::path(get, path = "/api/studies/{paper}/figures/{figure}", tag = "studies",
    params(("paper" = String, Path), ("figure" = String, Path), Bindings),
    responses((status = 200, body = FigureData), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn figure(
    State(s): State<AppState>,
    Path((paper_key, key)): Path<(String, String)>,
    bindings: Result<Query<Bindings>, QueryRejection>,
) -> ApiResult<Json<FigureData>> {
    let Query(bindings) = bindings?;
    let p = paper(&paper_key)?;
    let fig = p.figure(&key).ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            format!("no figure `{key}` in study {paper_key}"),
        )
    })?;
    let data = study_data(&s.store, p, &fig.sweeps(), &bindings, |k| {
        fig.needs_report(k)
    })
    .await?;
    Ok(Json(fig.data(p, &data)))
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct ComparisonAnswer {
    /// The sweep each study key was read from.
    pub sweeps: BTreeMap<String, String>,
    pub comparison: Vec<Comparison>,
}

/// The paper's stated results against ours, from the newest sweeps (or those named).
#[utoipa::path(get, path = "/api/studies/{paper}/comparison", tag = "studies",
    params(("paper" = String, Path), Bindings),
    responses((status = 200, body = ComparisonAnswer), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn comparison(
    State(s): State<AppState>,
    Path(paper_key): Path<String>,
    bindings: Result<Query<Bindings>, QueryRejection>,
) -> ApiResult<Json<ComparisonAnswer>> {
    let Query(bindings) = bindings?;
    let p = paper(&paper_key)?;
    let keys: Vec<String> = (p.sweeps)().iter().map(|s| s.key.to_string()).collect();
    let figures = (p.figures)();
    let data = study_data(&s.store, p, &keys, &bindings, |k| {
        figures.iter().any(|f| f.needs_report(k))
    })
    .await?;
    Ok(Json(ComparisonAnswer {
        sweeps: data
            .sweeps
            .iter()
            .map(|(k, d)| (k.clone(), d.id.clone()))
            .collect(),
        comparison: (p.compare)(&data),
    }))
}

/// A figure a sweep can be drawn as.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct FigureRef {
    pub paper: String,
    pub figure: String,
    pub title: String,
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct FigureRefs {
    pub figures: Vec<FigureRef>,
}

/// The papers' figures this sweep can be drawn as (its axes and metrics fit).
#[utoipa::path(get, path = "/api/sweeps/{id}/figures", tag = "sweeps", params(("id" = String, Path)),
    responses((status = 200, body = FigureRefs), (status = 404, body = ErrorBody)))]
pub async fn sweep_figures(
    State(s): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<FigureRefs>> {
    let sweep = require_sweep(&s.store, &id).await?;
    let data = sweep_data(&s.store, &sweep, false).await?;
    let mut figures = Vec::new();
    for p in papers::PAPERS {
        for f in (p.figures)() {
            // Figures of one measured layer on one sweep only.
            if f.sweeps().len() == 1 && f.axes().is_some() && f.fits(p.quantities, &data).is_ok() {
                figures.push(FigureRef {
                    paper: p.key.into(),
                    figure: f.key.into(),
                    title: f.title.into(),
                });
            }
        }
    }
    Ok(Json(FigureRefs { figures }))
}

/// One sweep drawn as a paper's figure, with its theory curves.
#[utoipa::path(get, path = "/api/sweeps/{id}/figures/{paper}/{figure}", tag = "sweeps",
    params(("id" = String, Path), ("paper" = String, Path), ("figure" = String, Path)),
    responses((status = 200, body = FigureData), (status = 404, body = ErrorBody), (status = 422, body = ErrorBody)))]
pub async fn sweep_figure(
    State(s): State<AppState>,
    Path((id, paper_key, key)): Path<(String, String, String)>,
) -> ApiResult<Json<FigureData>> {
    let sweep = require_sweep(&s.store, &id).await?;
    let p = paper(&paper_key)?;
    let fig = p.figure(&key).ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            format!("no figure `{key}` in study {paper_key}"),
        )
    })?;
    let needs = fig.sweeps().iter().any(|k| fig.needs_report(k));
    let data = sweep_data(&s.store, &sweep, needs).await?;
    fig.from_sweep(p, data).map(Json).map_err(|e| {
        let field = match e {
            repose_studies::figure::FigureError::Axis(_) => "x",
            repose_studies::figure::FigureError::Metric(_) => "y",
        };
        ApiError::field(StatusCode::UNPROCESSABLE_ENTITY, field, e.to_string())
    })
}

//! Jobs: what a sample still running looks like, read from its latest
//! checkpoint without resuming it.

use crate::{ApiError, ApiResult, AppState, ErrorBody};
use axum::extract::{Path, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use repose_physics::protocols::resume::saved_grains;
use repose_physics::Scene;
use std::fmt::Write;

/// The grains of a job's sample at its furthest checkpoint, one a line:
/// `x y z radius` in m (`x y radius` in 2D), after two `#` lines naming
/// the checkpoint. `repose measure-heap` reads a heap's metrics from it.
#[utoipa::path(get, path = "/api/jobs/{id}/grains", tag = "sweeps", params(("id" = String, Path)),
    responses((status = 200, description = "the grains as text, one a line", content_type = "text/plain", body = String),
        (status = 404, body = ErrorBody)))]
pub async fn grains(State(s): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    let (scene, checkpoint) = s
        .store
        .job_progress(&id)
        .await?
        .ok_or_else(|| ApiError::not_found("job"))?;
    let checkpoint = checkpoint.ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            "the job's sample has no checkpoint (not started, not long enough to save, \
             or finished: a finished sample's grains are in its report, /api/samples/{hash})",
        )
    })?;
    let unreadable = |why: String| {
        ApiError::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("the checkpoint cannot be read: {why}"),
        )
    };
    let dimension = Scene::from_stored_text(&scene)
        .map_err(|e| unreadable(e.to_string()))?
        .dimension;
    let grains = saved_grains(&checkpoint.state, dimension).map_err(unreadable)?;
    let mut text = format!(
        "# job {id}: checkpoint at {} s simulated, step {}\n# {} radius (m)\n",
        checkpoint.sim_time,
        checkpoint.iteration,
        ["x", "y", "z"][..dimension].join(" ")
    );
    for (centre, radius) in &grains {
        for c in centre {
            let _ = write!(text, "{c:e} ");
        }
        let _ = writeln!(text, "{radius:e}");
    }
    Ok(([(header::CONTENT_TYPE, "text/plain; charset=utf-8")], text).into_response())
}

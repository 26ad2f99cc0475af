//! # repose-worker
//!
//! A worker loops: claim a job → run its scene on a blocking thread →
//! record the report. While the scene runs, the worker renews its lease on
//! a timer; the heartbeat also learns when the sweep was cancelled or the
//! lease was lost, and the run is then stopped at its next equilibrium
//! check (a few milliseconds of simulated time). A shutdown request (SIGTERM)
//! stops the current run the same way and hands its job back to the queue,
//! so no job is ever left half-written: either its result and its `done`
//! state are written together, or the job returns to the queue.
//!
//! A long sample (a heap, a packing or a free run) saves a checkpoint every
//! `checkpoint_every` while it runs; the worker writes it to the store
//! under its lease. A worker that claims a job whose sample has a
//! checkpoint (its first worker died, or another sweep's job of the same
//! sample stopped) continues from the furthest one, and the result is the
//! one the first worker would have written, bit for bit. A job whose
//! sample another job is running waits, and ends done with that job's
//! result (claims take turns, so two claims in the same instant cannot
//! both take it).
//! A worker asked to shut down lets a run that can resume go on to its
//! next resumable point (a minute at most) and saves it there before it
//! hands the job back.
//!
//! A run that ends without a result (not settled, blow-up) is still a
//! result: its outcome and reason are stored like any other. Only a scene
//! that cannot even be read marks the job failed.
//!
//! The workers of one process may share their cores ([`Cores`]): while
//! some find nothing to claim, the samples the others run take their
//! cores as extra threads at their next check, and give them back once
//! every worker is busy again. A sample's numbers are the same on any
//! number of threads, so this changes only how soon the last samples of
//! a sweep finish.

use repose_physics::{Checkpoint, Observer, Progress, RunReport, Scene, SceneError};
use repose_store::{Claim, Lease, ResultRecord, RunCounts, Store};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::watch;

/// How a worker talks to the queue.
#[derive(Debug, Clone)]
pub struct WorkerConfig {
    /// Name recorded as the lease owner (host, process, index).
    pub owner: String,
    /// Lease length; a worker that stops renewing loses its job after this long.
    pub lease: Duration,
    /// Heartbeat period (well below the lease).
    pub heartbeat: Duration,
    /// Wait between claims while the queue is empty.
    pub idle: Duration,
    /// Stop once the queue is empty instead of waiting for more work.
    pub exit_when_idle: bool,
    /// Time between checkpoints of a resumable sample (none: never).
    pub checkpoint_every: Option<Duration>,
    /// The cores this worker shares with the other workers of its process
    /// (none: its samples keep the threads their scenes ask for).
    pub cores: Option<Arc<Cores>>,
}

/// The cores of a process's workers, one each: a worker with nothing to
/// run lends its core to the samples the others are running.
#[derive(Debug)]
pub struct Cores {
    workers: usize,
    busy: AtomicUsize,
    /// The most threads handed to one sample so far.
    most: AtomicUsize,
}

impl Cores {
    /// Cores for `workers` workers, none of them busy yet.
    pub fn new(workers: usize) -> Arc<Cores> {
        Arc::new(Cores {
            workers: workers.max(1),
            busy: AtomicUsize::new(0),
            most: AtomicUsize::new(0),
        })
    }

    /// The threads a running sample whose scene asks for `threads` may use
    /// now: its share of the cores, the idle workers' included.
    pub fn threads_for(&self, threads: usize) -> usize {
        let busy = self.busy.load(Ordering::Relaxed).max(1);
        let now = threads.max(1) * (self.workers / busy).max(1);
        self.most.fetch_max(now, Ordering::Relaxed);
        now
    }

    /// The most threads handed to one sample so far (0 before the first).
    pub fn most_threads(&self) -> usize {
        self.most.load(Ordering::Relaxed)
    }

    /// Marks one more worker busy until the returned guard is dropped.
    fn take(self: &Arc<Cores>) -> Busy {
        self.busy.fetch_add(1, Ordering::Relaxed);
        Busy(self.clone())
    }
}

/// A worker's claim on its core while it runs a job.
struct Busy(Arc<Cores>);

impl Drop for Busy {
    fn drop(&mut self) {
        self.0.busy.fetch_sub(1, Ordering::Relaxed);
    }
}

impl WorkerConfig {
    pub fn new(owner: impl Into<String>) -> Self {
        WorkerConfig {
            owner: owner.into(),
            lease: Duration::from_secs(60),
            heartbeat: Duration::from_secs(10),
            idle: Duration::from_millis(500),
            exit_when_idle: false,
            checkpoint_every: Some(Duration::from_secs(600)),
            cores: None,
        }
    }
}

/// What a worker did before it stopped.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    /// Results written.
    pub completed: u64,
    /// Jobs handed back (shutdown, cancelled sweep).
    pub released: u64,
    /// Results not written because the lease was lost.
    pub lost: u64,
    /// Jobs whose scene could not be read.
    pub failed: u64,
}

/// How long a run asked to hand its job back may go on to reach a point
/// where it can save its state (a heap saves once per insertion).
const HAND_BACK_GRACE: Duration = Duration::from_secs(60);

/// What the run on the blocking thread shares with the worker: a flag
/// that stops it, one that asks it to save and then stop (the worker shuts
/// down), the checkpoint to continue from, and the latest checkpoint it
/// saved (the worker writes it to the store).
struct JobObserver {
    job: String,
    stop: Arc<AtomicBool>,
    hand_back: Arc<AtomicBool>,
    /// When the run first saw `hand_back`, and whether it saved since.
    handing_back: Option<Instant>,
    saved_to_hand_back: bool,
    /// Whether the protocol can resume (it asked for a checkpoint).
    resumable: bool,
    every: Option<Duration>,
    last: Instant,
    resume: Option<Checkpoint>,
    saved: watch::Sender<Option<Checkpoint>>,
    /// The threads the scene asks for, and the cores to take more from.
    lend: Option<(usize, Arc<Cores>)>,
    /// The most threads the run was handed.
    most_threads: usize,
}

impl Observer for JobObserver {
    fn progress(&mut self, _update: &Progress) -> bool {
        if self.stop.load(Ordering::Relaxed) {
            return false;
        }
        if !self.hand_back.load(Ordering::Relaxed) {
            return true;
        }
        // Handing back: a run that saves goes on to its next resumable
        // point and stops once it has saved there, for a while at most.
        if !self.resumable || self.every.is_none() || self.saved_to_hand_back {
            return false;
        }
        let since = *self.handing_back.get_or_insert_with(Instant::now);
        since.elapsed() < HAND_BACK_GRACE
    }

    fn checkpoint_due(&mut self) -> bool {
        let handing_back = self.hand_back.load(Ordering::Relaxed);
        self.every
            .is_some_and(|every| handing_back || self.last.elapsed() >= every)
    }

    fn save(&mut self, checkpoint: Checkpoint) {
        self.last = Instant::now();
        self.saved.send_replace(Some(checkpoint));
        self.saved_to_hand_back = self.hand_back.load(Ordering::Relaxed);
    }

    fn saved(&mut self) -> Option<Checkpoint> {
        self.resumable = true;
        self.resume.take()
    }

    fn threads(&mut self) -> Option<usize> {
        let (threads, cores) = self.lend.as_ref()?;
        let now = cores.threads_for(*threads);
        if now > self.most_threads {
            tracing::info!(job = %self.job, threads = now, "running on the cores of idle workers too");
            self.most_threads = now;
        }
        Some(now)
    }

    fn resumed(&mut self, result: Result<u64, String>) {
        match result {
            Ok(step) => tracing::info!(job = %self.job, step, "continuing from the checkpoint"),
            Err(why) => {
                tracing::warn!(job = %self.job, "checkpoint set aside, starting over: {why}")
            }
        }
    }
}

/// How one job ended for this worker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ending {
    Completed,
    Released,
    Lost,
    Failed,
}

impl Tally {
    fn add(&mut self, ending: Ending) {
        match ending {
            Ending::Completed => self.completed += 1,
            Ending::Released => self.released += 1,
            Ending::Lost => self.lost += 1,
            Ending::Failed => self.failed += 1,
        }
    }
}

/// Runs jobs until `shutdown` turns true (or, with `exit_when_idle`, until
/// the queue is empty).
pub async fn run_worker(
    store: Store,
    config: WorkerConfig,
    mut shutdown: watch::Receiver<bool>,
) -> Tally {
    let mut tally = Tally::default();
    loop {
        if *shutdown.borrow() {
            return tally;
        }
        let claim = match store.claim(&config.owner, config.lease).await {
            Ok(c) => c,
            Err(e) => {
                tracing::warn!(owner = %config.owner, "claim failed: {e}");
                None
            }
        };
        let Some(job) = claim else {
            if config.exit_when_idle {
                return tally;
            }
            tokio::select! {
                _ = tokio::time::sleep(config.idle) => {}
                _ = shutdown.changed() => {}
            }
            continue;
        };
        tracing::info!(owner = %config.owner, job = %job.job_id, attempt = job.attempts, "claimed");
        let busy = config.cores.as_ref().map(Cores::take);
        tally.add(work(&store, &config, &job, &mut shutdown).await);
        drop(busy);
    }
}

/// Ends a job without a result, saying why.
async fn give_up(store: &Store, config: &WorkerConfig, job: &Claim, reason: String) -> Ending {
    let _ = store.fail(&job.job_id, &config.owner, &reason).await;
    Ending::Failed
}

/// Runs one claimed job to its end: a stored result, a job handed back, a
/// lost lease, or a failure with its reason.
async fn work(
    store: &Store,
    config: &WorkerConfig,
    job: &Claim,
    shutdown: &mut watch::Receiver<bool>,
) -> Ending {
    let scene = match Scene::from_stored_text(&job.scene) {
        Ok(s) => s,
        Err(reason) => {
            return give_up(store, config, job, format!("unreadable scene: {reason}")).await
        }
    };
    let (outcome, stopped, lease) = run_leased(store, config, job, scene, shutdown).await;
    let report = match outcome {
        Ok(Ok(report)) => report,
        Ok(Err(invalid)) => {
            return give_up(store, config, job, format!("invalid scene: {invalid}")).await
        }
        Err(panic) => {
            return give_up(store, config, job, format!("the engine panicked: {panic}")).await
        }
    };
    if stopped || matches!(report.outcome, repose_physics::Outcome::Cancelled { .. }) {
        tracing::info!(job = %job.job_id, "handed back");
        let released = lease != Lease::Lost
            && store
                .release(&job.job_id, &config.owner)
                .await
                .unwrap_or(false);
        return if released {
            Ending::Released
        } else {
            Ending::Lost
        };
    }
    let record = match record(&report) {
        Ok(r) => r,
        Err(e) => return give_up(store, config, job, format!("unwritable report: {e}")).await,
    };
    let ending = store_result(store, config, job, &record).await;
    if ending == Ending::Completed {
        // A sweep that chases a standard error may want more samples now.
        let max_attempts = repose_store::DEFAULT_MAX_ATTEMPTS;
        match repose_sweeps::topup::top_up(store, &job.sweep_id, max_attempts).await {
            Ok(0) => {}
            Ok(n) => tracing::info!(sweep = %job.sweep_id, "{n} samples added for target_sem"),
            Err(e) => tracing::warn!(sweep = %job.sweep_id, "could not add samples: {e}"),
        }
    }
    ending
}

/// Longest wait between two attempts to store a result.
const MAX_BACKOFF: Duration = Duration::from_secs(5);

/// Writes a result. While the database cannot be reached, tries again
/// with growing waits for as long as the lease holds (renewing it when the
/// database answers again), instead of throwing the run away.
async fn store_result(
    store: &Store,
    config: &WorkerConfig,
    job: &Claim,
    record: &ResultRecord,
) -> Ending {
    // The lease was renewed at most one heartbeat ago.
    let held_for = config.lease.saturating_sub(config.heartbeat);
    let mut deadline = tokio::time::Instant::now() + held_for;
    let mut wait = Duration::from_millis(100);
    loop {
        let error = match store
            .complete(&job.job_id, &config.owner, &job.sample_hash, record)
            .await
        {
            Ok(true) => return Ending::Completed,
            Ok(false) => {
                tracing::warn!(job = %job.job_id, "lease lost before completion; result not written");
                return Ending::Lost;
            }
            Err(e) => e,
        };
        if tokio::time::Instant::now() + wait >= deadline {
            tracing::warn!(job = %job.job_id, "could not store the result before the lease ran out: {error}");
            return Ending::Lost;
        }
        tracing::warn!(job = %job.job_id, "could not store the result ({error}); retrying in {wait:?}");
        tokio::time::sleep(wait).await;
        wait = (wait * 2).min(MAX_BACKOFF);
        match store
            .heartbeat(&job.job_id, &config.owner, config.lease)
            .await
        {
            Ok(Lease::Held) => deadline = tokio::time::Instant::now() + held_for,
            Ok(_) => {
                tracing::warn!(job = %job.job_id, "lease lost while the database was away");
                return Ending::Lost;
            }
            Err(_) => {}
        }
    }
}

/// The engine's answer for a job.
type RunAnswer = Result<Result<RunReport, SceneError>, tokio::task::JoinError>;

/// Runs the scene on a blocking thread while renewing the lease; stops it
/// when the lease is lost, the sweep cancelled or the worker asked to shut
/// down. Returns the engine's answer, whether it was stopped, and the lease.
async fn run_leased(
    store: &Store,
    config: &WorkerConfig,
    job: &Claim,
    scene: Scene,
    shutdown: &mut watch::Receiver<bool>,
) -> (RunAnswer, bool, Lease) {
    let stop = Arc::new(AtomicBool::new(false));
    let hand_back = Arc::new(AtomicBool::new(false));
    let (saved, mut checkpoints) = watch::channel(None);
    let mut observer = JobObserver {
        job: job.job_id.clone(),
        stop: stop.clone(),
        hand_back: hand_back.clone(),
        handing_back: None,
        saved_to_hand_back: false,
        resumable: false,
        every: config.checkpoint_every,
        last: Instant::now(),
        resume: stored_checkpoint(store, job).await,
        saved,
        lend: config
            .cores
            .clone()
            .map(|cores| (scene.numerics.threads, cores)),
        most_threads: scene.numerics.threads,
    };
    let mut simulation =
        tokio::task::spawn_blocking(move || repose_physics::run(&scene, &mut observer));
    let mut beat = tokio::time::interval(config.heartbeat);
    beat.tick().await;
    let mut lease = Lease::Held;
    let mut saving = true;
    let outcome = loop {
        tokio::select! {
            done = &mut simulation => break done,
            changed = checkpoints.changed(), if saving => match changed {
                Ok(()) => {
                    // `changed` has marked it seen.
                    let latest = checkpoints.borrow().clone();
                    if let Some(c) = latest {
                        write_checkpoint(store, config, job, &c).await;
                    }
                }
                Err(_) => saving = false,
            },
            _ = beat.tick() => {
                match store.heartbeat(&job.job_id, &config.owner, config.lease).await {
                    Ok(Lease::Held) => {}
                    Ok(other) => { lease = other; stop.store(true, Ordering::Relaxed); }
                    Err(e) => tracing::warn!(job = %job.job_id, "heartbeat failed: {e}"),
                }
            }
            _ = shutdown.changed(), if !hand_back.load(Ordering::Relaxed) => {
                if *shutdown.borrow() {
                    hand_back.store(true, Ordering::Relaxed);
                }
            }
        }
    };
    // The state the run saved on its way out (handing back) is not lost,
    // though the run has ended and closed the channel.
    let unseen = {
        let latest = checkpoints.borrow_and_update();
        if latest.has_changed() {
            latest.clone()
        } else {
            None
        }
    };
    if let Some(c) = unseen {
        write_checkpoint(store, config, job, &c).await;
    }
    // A run handed back ends cancelled; one that finished meanwhile is kept.
    (outcome, stop.load(Ordering::Relaxed), lease)
}

/// The furthest checkpoint saved for the job's sample, if any: by an
/// earlier worker of this job, or of the same sample queued by another sweep.
async fn stored_checkpoint(store: &Store, job: &Claim) -> Option<Checkpoint> {
    match store.furthest_checkpoint(&job.sample_hash).await {
        Ok(found) => found.map(|c| Checkpoint {
            time: c.sim_time,
            iteration: u64::try_from(c.iteration).unwrap_or(0),
            state: c.state,
        }),
        Err(e) => {
            tracing::warn!(job = %job.job_id, "could not read the checkpoint, starting over: {e}");
            None
        }
    }
}

/// Writes a checkpoint under the lease; a failed write only costs the
/// work since the previous one.
async fn write_checkpoint(store: &Store, config: &WorkerConfig, job: &Claim, c: &Checkpoint) {
    match store
        .save_checkpoint(&job.job_id, &config.owner, c.time, c.iteration, &c.state)
        .await
    {
        Ok(true) => {
            tracing::debug!(job = %job.job_id, step = c.iteration, bytes = c.state.len(), "checkpoint saved")
        }
        Ok(false) => tracing::warn!(job = %job.job_id, "lease lost: checkpoint not saved"),
        Err(e) => tracing::warn!(job = %job.job_id, "could not save the checkpoint: {e}"),
    }
}

/// What the store keeps of a report: its outcome, metrics and cost, and
/// the report itself as a document.
pub fn record(report: &RunReport) -> Result<ResultRecord, serde_json::Error> {
    let count = |n: usize| i64::try_from(n).unwrap_or(i64::MAX);
    Ok(ResultRecord {
        engine: report.engine.clone(),
        seed: report.seed,
        outcome: report.outcome.status().to_string(),
        reason: report.outcome.reason(),
        metrics: report.metrics.clone(),
        counts: RunCounts {
            grains_initial: count(report.grains.initial),
            grains_final: count(report.grains.remaining),
            grains_lost: count(report.grains.lost),
            iterations: i64::try_from(report.iterations).unwrap_or(i64::MAX),
            simulated_time: report.simulated_time,
            wall_time: report.wall_time,
            particle_steps: i64::try_from(report.particle_steps).unwrap_or(i64::MAX),
        },
        report: serde_json::to_string(report)?,
    })
}

/// A shutdown channel that turns true on SIGTERM or Ctrl-C.
pub fn shutdown_on_signals() -> watch::Receiver<bool> {
    let (tx, rx) = watch::channel(false);
    tokio::spawn(async move {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{signal, SignalKind};
            let mut term = match signal(SignalKind::terminate()) {
                Ok(s) => s,
                Err(_) => return,
            };
            tokio::select! {
                _ = term.recv() => {}
                _ = tokio::signal::ctrl_c() => {}
            }
        }
        #[cfg(not(unix))]
        {
            let _ = tokio::signal::ctrl_c().await;
        }
        tracing::info!("shutting down: finishing or handing back the current jobs");
        let _ = tx.send(true);
    });
    rx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_idle_workers_core_goes_to_the_busy_ones_and_comes_back() {
        let cores = Cores::new(2);
        let first = cores.take();
        assert_eq!(cores.threads_for(1), 2, "one of two workers idle");
        let second = cores.take();
        assert_eq!(cores.threads_for(1), 1, "both busy");
        assert_eq!(cores.threads_for(2), 2, "a scene's own threads are kept");
        drop(first);
        assert_eq!(cores.threads_for(1), 2);
        drop(second);
        assert_eq!(cores.busy.load(Ordering::Relaxed), 0);
        assert_eq!(cores.most_threads(), 2);
        // Four workers, three idle: the one running takes all four cores;
        // two running take two each.
        let four = Cores::new(4);
        let a = four.take();
        assert_eq!(four.threads_for(1), 4);
        let b = four.take();
        assert_eq!(four.threads_for(1), 2);
        let c = four.take();
        assert_eq!(four.threads_for(1), 1);
        drop((a, b, c));
        assert_eq!(Cores::new(1).threads_for(1), 1);
    }
}

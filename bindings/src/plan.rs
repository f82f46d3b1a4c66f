//! Planning: the request and result records, the progress listener (implemented in
//! Kotlin) and the planning call object, which another thread may cancel.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use trailprint::plan::{Algorithm, Control, Observer, PlanSettings, Progress};
use trailprint::store::StorePlanRequest;
use trailprint::team::SurveyorTask;

use crate::model::SurveyorProfile;
use crate::store::{PlanSummary, TrailprintStore};
use crate::{Result, TrailprintError};

/// The planning algorithms (`auto` is the recommended default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, uniffi::Enum)]
pub enum PlanAlgorithm {
    /// Greedy first, a genetic search seeded with its walk, local search, and an exact
    /// search when the floor is small enough; stops at 2 s unless the request sets a
    /// time limit.
    Auto,
    /// The paper's Algorithm 1: ratio greedy over Steiner TSP paths.
    Greedy,
    /// The paper's genetic algorithm (section IV-B).
    Genetic,
    /// Chekuri and Pal's recursive greedy.
    RecursiveGreedy,
    /// Edge-based random orienteering.
    Ero,
    /// Branch and bound: the walk is proved optimal when it finishes within the time
    /// limit (`termination` = `optimal`).
    Exact,
    /// The systematic walk (nearest unwalked edge first): the baseline.
    Coverage,
}

impl From<PlanAlgorithm> for Algorithm {
    fn from(a: PlanAlgorithm) -> Self {
        match a {
            PlanAlgorithm::Auto => Algorithm::Auto,
            PlanAlgorithm::Greedy => Algorithm::Greedy,
            PlanAlgorithm::Genetic => Algorithm::Genetic,
            PlanAlgorithm::RecursiveGreedy => Algorithm::RecursiveGreedy,
            PlanAlgorithm::Ero => Algorithm::Ero,
            PlanAlgorithm::Exact => Algorithm::Exact,
            PlanAlgorithm::Coverage => Algorithm::Coverage,
        }
    }
}

impl From<Algorithm> for PlanAlgorithm {
    fn from(a: Algorithm) -> Self {
        match a {
            Algorithm::Auto => PlanAlgorithm::Auto,
            Algorithm::Greedy => PlanAlgorithm::Greedy,
            Algorithm::Genetic => PlanAlgorithm::Genetic,
            Algorithm::RecursiveGreedy => PlanAlgorithm::RecursiveGreedy,
            Algorithm::Ero => PlanAlgorithm::Ero,
            Algorithm::Exact => PlanAlgorithm::Exact,
            Algorithm::Coverage => PlanAlgorithm::Coverage,
        }
    }
}

/// What to plan: a walk of a stored building from `start` to `end` within `budget_m`.
#[derive(Debug, Clone, uniffi::Record)]
pub struct PlanRequest {
    /// Store id of the building (`BuildingSummary.id`).
    pub building_id: i64,
    /// Start vertex id.
    pub start: String,
    /// End vertex id (may equal the start).
    pub end: String,
    /// Distance budget, metres (the app converts minutes with the walking speed).
    pub budget_m: f64,
    /// Who walks: sets where the scans fall and how noisy their labels are, so the walk
    /// is planned for it; saved with the plan.
    pub surveyor: SurveyorProfile,
    /// The planner (`AUTO` unless comparing).
    pub algorithm: PlanAlgorithm,
    /// Seed of every random choice.
    pub seed: u64,
    /// Stop with the best walk so far after this many seconds (null: the algorithm's
    /// default, 2 s for `auto`, none for the others).
    pub time_limit_s: Option<f64>,
    /// Most memory the plan may use, MiB (null: 512). A request that would need more is
    /// refused with `InvalidRequest` naming the size, before anything is allocated.
    #[uniffi(default)]
    pub memory_budget_mb: Option<u64>,
}

/// A progress report of a running plan.
#[derive(Debug, Clone, uniffi::Record)]
pub struct PlanProgress {
    /// The algorithm reporting: under `AUTO`, the phase running now.
    pub algorithm: PlanAlgorithm,
    /// Estimated fraction of the work done, 0 to 1.
    pub fraction: f64,
    /// Utility of the best walk so far, nats.
    pub best_utility_nats: Option<f64>,
    /// Length of the best walk so far, metres.
    pub best_length_m: Option<f64>,
    /// A short note (`generation 3/5`).
    pub message: String,
}

impl From<&Progress> for PlanProgress {
    fn from(p: &Progress) -> Self {
        PlanProgress {
            algorithm: p.algorithm.into(),
            fraction: p.fraction,
            best_utility_nats: p.best_utility,
            best_length_m: p.best_length,
            message: p.message.clone(),
        }
    }
}

/// Receives progress reports while a plan runs. Called on the planning thread (or a worker
/// thread): keep it cheap, and hop to the UI thread yourself.
#[uniffi::export(with_foreign)]
pub trait PlanListener: Send + Sync {
    fn on_progress(&self, progress: PlanProgress);
}

struct ListenerObserver(Arc<dyn PlanListener>);

impl Observer for ListenerObserver {
    fn progress(&self, p: &Progress) {
        self.0.on_progress(p.into());
    }
}

/// One planning call: made by [`TrailprintStore::new_plan`], run once with
/// [`PlanJob::run`] (blocking; call it off the main thread), cancelled from any thread
/// with [`PlanJob::cancel`], which makes `run` return promptly with the best walk found so
/// far (`termination` = `cancelled`), saved like any other plan.
#[derive(uniffi::Object)]
pub struct PlanJob {
    store: Arc<TrailprintStore>,
    request: PlanRequest,
    job: JobControl,
}

impl PlanJob {
    pub(crate) fn new(store: Arc<TrailprintStore>, request: PlanRequest) -> Self {
        PlanJob {
            store,
            request,
            job: JobControl::default(),
        }
    }
}

/// What a planning call object ([`PlanJob`], [`crate::team::TeamPlanJob`]) holds to run
/// once and be cancelled from any thread.
#[derive(Default)]
pub(crate) struct JobControl {
    cancel: Arc<AtomicBool>,
    ran: Mutex<bool>,
}

impl JobControl {
    /// The control of the one run: fails with `InvalidRequest` naming `what` when the
    /// call has run before; progress goes to `listener`.
    pub(crate) fn start(
        &self,
        what: &str,
        listener: Option<Arc<dyn PlanListener>>,
    ) -> Result<Control> {
        let mut ran = self.ran.lock().unwrap_or_else(PoisonError::into_inner);
        if *ran {
            return Err(TrailprintError::InvalidRequest(format!(
                "this {what} call has already run; make a new one"
            )));
        }
        *ran = true;
        let control = Control::new().with_cancel_token(self.cancel.clone());
        Ok(match listener {
            Some(l) => control.with_observer(Arc::new(ListenerObserver(l))),
            None => control,
        })
    }

    pub(crate) fn cancel(&self) {
        self.cancel.store(true, Ordering::SeqCst);
    }

    pub(crate) fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::SeqCst)
    }
}

#[uniffi::export]
impl PlanJob {
    /// The request this call plans.
    pub fn request(&self) -> PlanRequest {
        self.request.clone()
    }

    /// Plans, reporting progress to `listener`, and saves the plan in the store. After
    /// [`cancel`](Self::cancel) it returns the best walk so far (`termination` =
    /// `cancelled`); fails with `InvalidRequest` when run a second time.
    pub fn run(&self, listener: Option<Arc<dyn PlanListener>>) -> Result<PlanSummary> {
        // The time limit counts from here: the store's kernel fit and loading the
        // building are part of what the app waits for.
        let control = self
            .job
            .start("plan", listener)?
            .with_clock_from(std::time::Instant::now());
        self.store.run_plan(&self.request, &control)
    }

    /// Asks the running (or future) `run` to stop; safe from any thread, idempotent.
    pub fn cancel(&self) {
        self.job.cancel();
    }

    pub fn is_cancelled(&self) -> bool {
        self.job.is_cancelled()
    }
}

/// The core's planner settings of a request (the kernel is the store's to choose).
pub(crate) fn core_settings(
    surveyor: SurveyorProfile,
    algorithm: PlanAlgorithm,
    seed: u64,
    time_limit_s: Option<f64>,
    memory_budget_mb: Option<u64>,
) -> Result<PlanSettings> {
    let mut s = PlanSettings {
        model: surveyor.into(),
        algorithm: algorithm.into(),
        seed,
        ..PlanSettings::default()
    };
    if let Some(mb) = memory_budget_mb {
        s.memory_budget = mb.saturating_mul(1 << 20);
    }
    s.time_limit = match time_limit_s {
        None => None,
        Some(t) if t.is_finite() && t > 0.0 => Some(std::time::Duration::from_secs_f64(t)),
        Some(t) => {
            return Err(TrailprintError::InvalidRequest(format!(
                "time limit must be a positive number of seconds, got {t}"
            )));
        }
    };
    Ok(s)
}

impl TrailprintStore {
    /// Plans and saves (the body of [`PlanJob::run`]): `Store::plan_and_save`.
    pub(crate) fn run_plan(&self, r: &PlanRequest, control: &Control) -> Result<PlanSummary> {
        let request = StorePlanRequest {
            route: SurveyorTask {
                start: r.start.clone(),
                end: r.end.clone(),
                budget: r.budget_m,
            },
            settings: core_settings(
                r.surveyor,
                r.algorithm,
                r.seed,
                r.time_limit_s,
                r.memory_budget_mb,
            )?,
            kernel: None,
        };
        let saved = self.inner.plan_and_save(r.building_id, &request, control)?;
        let mut summary: PlanSummary = saved.stored.into();
        summary.termination = Some(saved.result.termination.name().to_string());
        Ok(summary)
    }
}

#[uniffi::export]
impl TrailprintStore {
    /// A planning call for `request`, to run with [`PlanJob::run`].
    pub fn new_plan(self: Arc<Self>, request: PlanRequest) -> Arc<PlanJob> {
        Arc::new(PlanJob::new(self, request))
    }
}

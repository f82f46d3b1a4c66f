//! The run state of one plan: the caller's [`Control`] (cancel token, progress
//! [`Observer`]), the deadline from the time limit, the best walk offered so far and the
//! progress reports ([`Progress`]), monotone in fraction and best value.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::{Error, Result};

use super::{Algorithm, better};

/// A progress report.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// The algorithm reporting (for `auto`, the phase's algorithm).
    pub algorithm: Algorithm,
    /// Estimated fraction of the work done, in `[0, 1]` (a time fraction under a limit).
    pub fraction: f64,
    /// Utility of the best walk so far, nats, if there is one.
    pub best_utility: Option<f64>,
    /// Length of the best walk so far, metres, if there is one.
    pub best_length: Option<f64>,
    /// A short human-readable note (`generation 3/5`, `1234 nodes`).
    pub message: String,
}

/// Receives progress reports; called from the planning thread (or a rayon worker), so it
/// must be cheap and thread-safe.
pub trait Observer: Send + Sync {
    fn progress(&self, p: &Progress);
}

/// An observer that ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoObserver;

impl Observer for NoObserver {
    fn progress(&self, _: &Progress) {}
}

/// How the caller steers a running plan: a cancel token another thread may set, an
/// optional progress observer, and optionally when the caller's clock started.
#[derive(Clone, Default)]
pub struct Control {
    pub(crate) cancel: Arc<AtomicBool>,
    pub(crate) observer: Option<Arc<dyn Observer>>,
    pub(crate) started: Option<Instant>,
}

impl std::fmt::Debug for Control {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Control")
            .field("cancelled", &self.is_cancelled())
            .field("observer", &self.observer.is_some())
            .field("started", &self.started)
            .finish()
    }
}

impl Control {
    /// No observer, a fresh cancel token.
    pub fn new() -> Self {
        Self::default()
    }

    /// Uses `token` as the cancel token (set it to `true` to cancel).
    pub fn with_cancel_token(mut self, token: Arc<AtomicBool>) -> Self {
        self.cancel = token;
        self
    }

    /// Sends progress reports to `observer`.
    pub fn with_observer(mut self, observer: Arc<dyn Observer>) -> Self {
        self.observer = Some(observer);
        self
    }

    /// Counts the time limit from `started` instead of from the call to the planner: a
    /// caller that loads the building or fits the kernel first (the command line, the
    /// store) passes when it began, so that its set-up counts against the limit too
    /// (issue 13: "honoured ... set-up included").
    pub fn with_clock_from(mut self, started: Instant) -> Self {
        self.started = Some(started);
        self
    }

    /// When the plan's clock starts: [`Control::with_clock_from`]'s instant, else now.
    pub fn clock_start(&self) -> Instant {
        self.started.unwrap_or_else(Instant::now)
    }

    /// The cancel token, to hand to another thread.
    pub fn cancel_token(&self) -> Arc<AtomicBool> {
        self.cancel.clone()
    }

    /// Asks the running plan to stop; it returns [`Error::Cancelled`] promptly.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Whether cancellation was requested.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// The best walk a run has found so far: what a cancelled or timed-out plan returns.
#[derive(Debug, Clone, Default)]
pub(crate) struct Incumbent {
    pub(crate) walk: Vec<usize>,
    pub(crate) utility: f64,
    /// What the walk is ranked by (see [`Problem::objective`](super::Problem::objective)).
    pub(crate) score: f64,
}

/// The run state shared by a solver's threads: control, start time, deadline and the
/// best walk so far (solvers [`offer`](Run::offer) theirs as they go).
#[derive(Debug, Clone)]
pub struct Run {
    pub(crate) control: Control,
    pub(crate) started: Instant,
    pub(crate) deadline: Option<Instant>,
    pub(crate) best: Arc<std::sync::Mutex<Option<Incumbent>>>,
    /// Length of the best walk so far, for progress reports (f64 bits; NaN: none).
    pub(crate) best_length: Arc<std::sync::atomic::AtomicU64>,
    /// The algorithm the user asked for: every report carries it, whichever stage or
    /// sub-search sends it (set by [`plan_with_prior`]).
    pub(crate) algorithm: Option<Algorithm>,
    /// Highest fraction and best utility reported so far (f64 bits): what a progress bar
    /// shows never goes back, though stages and parallel subtrees report out of order.
    pub(crate) reported: Arc<std::sync::Mutex<(f64, Option<f64>)>>,
}

impl Run {
    /// Starts the clock now.
    pub fn new(control: Control, time_limit: Option<Duration>) -> Self {
        Self::starting_at(control, time_limit, Instant::now())
    }

    /// Starts the clock at `started` (when the request arrived, so that set-up counts
    /// against the time limit).
    pub fn starting_at(control: Control, time_limit: Option<Duration>, started: Instant) -> Self {
        Run {
            control,
            started,
            deadline: time_limit.map(|t| started + t),
            best: Arc::default(),
            best_length: Arc::new(std::sync::atomic::AtomicU64::new(f64::NAN.to_bits())),
            algorithm: None,
            reported: Arc::new(std::sync::Mutex::new((0.0, None))),
        }
    }

    /// Reports of this run name `algorithm`, whatever stage sends them.
    pub fn for_algorithm(mut self, algorithm: Algorithm) -> Self {
        self.algorithm = Some(algorithm);
        self
    }

    /// Offers a feasible walk (start to end, within budget) with its exact utility and
    /// the score it is ranked by (its utility, less a share per reversal for a person:
    /// [`Problem::objective`](super::Problem::objective)); the run keeps the best offered
    /// by score (ties: see [`better`]) and returns it if the plan is cancelled or runs out
    /// of time before the solver returns.
    pub fn offer(&self, walk: &[usize], utility: f64, score: f64, length: f64) {
        let Ok(mut g) = self.best.lock() else {
            return;
        };
        let replace = match &*g {
            None => true,
            Some(b) => better((walk, score), (&b.walk, b.score)),
        };
        if replace && utility.is_finite() && score.is_finite() {
            *g = Some(Incumbent {
                walk: walk.to_vec(),
                utility,
                score,
            });
            self.best_length.store(length.to_bits(), Ordering::Relaxed);
        }
    }

    /// The best walk offered so far and its utility.
    pub fn incumbent(&self) -> Option<(Vec<usize>, f64)> {
        self.best
            .lock()
            .ok()
            .and_then(|g| g.as_ref().map(|b| (b.walk.clone(), b.utility)))
    }

    /// The same control with an earlier deadline (for a phase of `auto`).
    pub fn with_deadline(&self, deadline: Option<Instant>) -> Self {
        let deadline = match (self.deadline, deadline) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        Run {
            control: self.control.clone(),
            started: self.started,
            deadline,
            best: self.best.clone(),
            best_length: self.best_length.clone(),
            algorithm: self.algorithm,
            reported: self.reported.clone(),
        }
    }

    /// `Err(Cancelled)` if the caller cancelled.
    pub fn check(&self) -> Result<()> {
        if self.control.is_cancelled() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }

    /// Whether the caller cancelled.
    pub fn control_cancelled(&self) -> bool {
        self.control.is_cancelled()
    }

    /// Whether the deadline has passed.
    pub fn out_of_time(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    /// Whether to stop now (cancelled or out of time).
    pub fn should_stop(&self) -> bool {
        self.control.is_cancelled() || self.out_of_time()
    }

    /// The time limit (deadline minus start), if any.
    pub fn time_limit(&self) -> Option<Duration> {
        self.deadline
            .map(|d| d.saturating_duration_since(self.started))
    }

    /// The deadline, if any.
    pub fn deadline(&self) -> Option<Instant> {
        self.deadline
    }

    /// Time since the start.
    pub fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    /// Fraction of the time limit used, if there is one.
    pub fn time_fraction(&self) -> Option<f64> {
        self.deadline.map(|d| {
            let total = d.saturating_duration_since(self.started).as_secs_f64();
            if total <= 0.0 {
                1.0
            } else {
                (self.started.elapsed().as_secs_f64() / total).min(1.0)
            }
        })
    }

    /// Sends a progress report to the observer, if any.
    ///
    /// What the observer sees is consistent whatever the stage: the requested algorithm,
    /// a fraction that never goes back, and the best utility so far (the larger of the
    /// stage's own figure, the best walk offered, and what was reported before).
    pub fn report(&self, algorithm: Algorithm, fraction: f64, best: Option<f64>, msg: String) {
        if let Some(o) = &self.control.observer {
            // The report is made and delivered under one lock: parallel workers (the
            // recursive greedy's splits) took it only to make theirs, and one preempted
            // between the two delivered a lower fraction and best after a later report
            // (seen once in CI: "fraction went back from 0.4 to 0.3").
            let mut r = self.reported.lock().unwrap_or_else(|e| e.into_inner());
            let len = f64::from_bits(self.best_length.load(Ordering::Relaxed));
            let offered = self.incumbent().map(|(_, u)| u);
            r.0 = r.0.max(fraction.clamp(0.0, 1.0));
            for u in [best, offered].into_iter().flatten() {
                r.1 = Some(r.1.map_or(u, |b: f64| b.max(u)));
            }
            let (fraction, best) = *r;
            o.progress(&Progress {
                algorithm: self.algorithm.unwrap_or(algorithm),
                fraction,
                best_utility: best,
                best_length: (best.is_some() && len.is_finite()).then_some(len),
                message: msg,
            });
            drop(r);
        }
    }
}

//! Planning at building scale: what `auto` does on buildings of hundreds of vertices and
//! budgets of hundreds of metres, where an exact evaluation of one walk costs tens of
//! milliseconds and a search cannot afford many.
//!
//! # The surrogate ([`Surrogate`], `surrogate.rs`)
//! A search judges candidate walks by a cheaper stand-in for `f_D`: each vertex's
//! conditional entropy given only its nearest observations and earlier vertices (a
//! Vecchia approximation), about 1 ms for a 500 m robot walk on a 565-vertex building
//! where `f_D` costs 29 ms. When an exact evaluation costs no more than a surrogate one
//! (a person's sparse samples on a building of a few hundred vertices), the search
//! judges by `f_D` itself. Decision record `docs/decisions/0003-search-surrogate.md` has
//! the measured error and speed.
//!
//! The utility that `auto` reports, saves and compares is always the exact `f_D` of
//! SPEC 3: the surrogate only ranks candidates inside the search.
//!
//! # The search ([`plan_large`])
//! 1. **Constructions.** Spread coverage walks ([`super::coverage::leg`]) for twelve
//!    novelty radii ([`CONSTRUCTION_RADII`]) and both tie rules ([`super::coverage::Leg::open_ties`]), each using
//!    the whole budget; the best by the surrogate is evaluated
//!    exactly and offered at once, so a cancelled or timed-out plan returns a walk that
//!    already uses the budget well.
//! 2. **Large-neighbourhood search.** Destroy a random stretch of the current walk (5% to
//!    35% of its vertices, at most [`STRETCH_MAX_VERTICES`]) and rebuild it with a randomised spread leg that counts the rest
//!    of the walk as walked, its novelty radius drawn from [`MOVE_RADII`] or
//!    [`FINE_MOVE_RADII`]; half the moves first cut a closed excursion out of the walk
//!    (a second visit to a room), so that its budget can be spent where the stretch is
//!    rebuilt. Candidates are drawn with the seeded generator and evaluated in parallel
//!    in batches (a candidate scored before in the phase, or the walk itself, keeps its
//!    score: [`Seen`]); the best of a batch replaces the current walk when its surrogate value
//!    is higher, or when it is at most 2% below the best walk seen (record-to-record
//!    travel, the 2% shrinking to nothing over the window; the best walk is kept apart).
//!    Both halves of a move are incremental on the walk it is drawn from: its leg starts
//!    from that walk's edge marks less the steps the move removes
//!    ([`super::coverage::Marks`]), and it is scored from that walk's surrogate frame,
//!    conditioning again only the vertices its changed stretch comes near
//!    ([`Surrogate::value_near`]); the one candidate the search would move to is scored
//!    whole first.
//!    Where the window affords many batches per vertex of the walk (small buildings and
//!    budgets), 50 batches without a new best walk are taken as convergence: the search
//!    moves on from a rebuild of 30% to 60% of the best walk (a kick, [`KICK_STALE`]).
//!    For the human model every walk has its reversals (walking straight back at a vertex
//!    that is not a dead end) repaired where the budget allows
//!    ([`super::coverage::unpace`]), and the score loses 1% per reversal left. When one exact evaluation is cheap beside the search window (it affords at
//!    least 40 batches in its last 80%; office-sized buildings and short walks), that last
//!    part judges candidates by exact `f_D` instead, from the best walk known exactly:
//!    the surrogate finds the basin, exact scores find the best walk in it. Each
//!    candidate is scored from the factorisation of the walk it was drawn from
//!    ([`crate::utility::UtilityEngine::utility_near`]): only the rows from its first
//!    changed sample are computed. For a
//!    person a quarter of that part's moves walk a closed sub-walk the other way
//!    ([`closed_subwalk`]): the same edges and length, the samples elsewhere. When whole
//!    batches of exact evaluations are too dear but one per batch is not, the last fifth
//!    of the window ([`SCREENED_PHASE_SHARE`]) is screened instead: the surrogate ranks each batch and its best
//!    candidate is accepted only when its exact score beats the current walk's.
//! 3. **Exact comparison.** The best construction and the plain `coverage` walk are
//!    evaluated exactly before the search (in parallel; that also measures what one
//!    exact evaluation costs here), and the search stops early enough to leave the time
//!    for the exact evaluation of its own walk. The walks the search offered on the way
//!    (evaluated exactly) are finalists too: the surrogate may lead on to a walk that is
//!    worse by `f_D`, and a plan never ends below what its progress has shown. The best
//!    of them by exact `f_D` is returned, so `auto` never returns less than the systematic walk it is judged
//!    against (for a person: less the 1% per reversal). The exception is an exact
//!    evaluation that is dear beside the time limit (more than [`DEFER_SHARE`] of it,
//!    estimated by timing a prefix of the walk: a 2,000 m robot walk on a 565-vertex
//!    building costs 0.73 s here): then nothing is evaluated before the search, which
//!    gets that time, and the search's walk is the one finalist, evaluated at the end
//!    (the search stops when the time left is what that evaluation needs, scaled to the
//!    walk of the moment).

use std::time::{Duration, Instant};

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::coverage::{
    Leg, Marks, distinct_radii, leg, leg_marked, reversals, tabled_radii, unpace,
};
pub use super::surrogate::{Frame, Surrogate};
use super::{Algorithm, Outcome, Problem, Run, Termination, better};
use crate::samples::Surveyor;
use crate::{Error, Result};

/// Candidates per batch of the large-neighbourhood search (evaluated in parallel).
const BATCH: usize = 8;

/// Novelty radii of the spread constructions, in units of the kernel's length scale
/// (the moves of the search draw theirs from [`MOVE_RADII`] and [`FINE_MOVE_RADII`]).
///
/// A construction's utility is not smooth in its radius: on the generated mall, person
/// 2,036 m, 216.2 nats at 0.04 against 198.5 at 0.125 and 177.6 at 0.16; robot 1,018 m
/// 345.2 at 0.09 against 334.0 at 0.125 (`examples/construct_probe.rs`); the surrogate
/// ranks them as `f_D` does. With these twelve instead of the moves' five (2 s, one core,
/// seeds 1-4, mean utility against the five): the benchmark's 18 office, campus and mall
/// rows and huge-3k person 3,116 m mean 1.004; mall person 509 m +2.7%, 2,036 m +2.3%,
/// campus person 891 m +1.5%, mall robot 2,036 m +1.3%, huge-3k and mall person 1,018 m
/// unchanged; lowest campus person 446 m -1.5%, mall robot 1,018 m -0.8%.
const CONSTRUCTION_RADII: [f64; 12] = [
    0.0, 0.04, 0.0625, 0.09, 0.11, 0.125, 0.14, 0.16, 0.19, 0.22, 0.25, 0.5,
];

/// Novelty radii of the search's moves, in units of the kernel's length scale: half the
/// moves draw one of these (and every kick, [`KICK_STALE`]), half one of
/// [`FINE_MOVE_RADII`].
const MOVE_RADII: [f64; 5] = [0.0, 0.125, 0.25, 0.5, 1.0];

/// The other half of the moves' novelty radii: the constructions' radii between those of
/// [`MOVE_RADII`] ([`CONSTRUCTION_RADII`]). A move's leg is random only in its first
/// target and tie rule, so from one walk the moves of five radii build a few hundred
/// distinct candidates (office robot 101 m: 762 of 20,000 moves), which a converged
/// search soon has all scored ([`Seen`]); more radii make more distinct candidates.
/// Measured at 2 s, one core, mean utility against the five radii alone (both with
/// [`Seen`]): all thirteen drawn alike, `docs/benchmark-scale.md`'s 18 office, campus and
/// mall rows and huge-3k person 3,116 m, +0.42% (seeds 1-4) and +0.42% (seeds 5-8): mall
/// robot 1,018 m +1.7%, office robot 402 m +1.9%, mall person 509 m +1.2%, campus
/// person 223 m +1.1%; lowest campus person 446 m -0.9%; 36 rows of sweep 59's
/// buildings (seeds 1-2) +0.27%, but -1.3% to -2.0% on two of its 398-vertex floors.
/// Half the moves on these and half on the five, against all thirteen alike: +0.16%
/// over those 34 rows (seeds 1-2), the two floors' rows +0.2% to +1.9%.
const FINE_MOVE_RADII: [f64; 8] = [0.04, 0.0625, 0.09, 0.11, 0.14, 0.16, 0.19, 0.22];

/// Share of the search window (or of the batches, without a time limit) judged by exact
/// `f_D` when exact evaluations are cheap enough (see [`EXACT_PHASE_BATCHES`]).
const EXACT_PHASE_SHARE: f64 = 0.8;

/// Fewest batches the exact or the screened phase must afford to run at all.
const EXACT_PHASE_BATCHES: usize = 40;

/// Share of the search window screened by exact `f_D` (the surrogate's best candidate of
/// each batch evaluated exactly) when whole batches of exact evaluations are too dear.
/// Measured at 2 s, one core, seeds 4-6, against no screened phase: campus robot 446 m
/// 168.26 -> 174.24 nats (+3.6%), campus human 891 m 127.33 -> 128.24 (+0.7%), mall human
/// 2,036 m 198.48 -> 200.27 (+0.9%), mall human 1,018 m 144.24 -> 144.30; no change where
/// it does not run (the mall's robot walks, campus robot 891 m).
///
/// A fifth rather than the half it was (2026-12-06): a screened batch costs about five
/// unscreened ones (mall human 2,036 m: one exact evaluation 9.5 ms against 2.5 ms for a
/// batch of eight surrogate moves), and with the Vecchia surrogate the unscreened moves
/// are worth more. 2 s, one core, mean nats 0.2 against 0.5: mall human 2,036 m +2.3%
/// (seeds 1-5, 220.4 -> 225.5) and +3.3% (seeds 1-2 in a second run), campus human 891 m
/// +1.1%, a 1,011-vertex floor's person on 3,304 m (sweep 51's b3) +0.9%, mall human
/// 1,018 m +0.9% and -0.6% in two runs; the 18 office, campus and mall rows of
/// `docs/benchmark-scale.md` (seeds 1-2) mean 1.0001, the rows without a screened phase
/// within their run-to-run noise (0.3%). 0.1 and 0.3 measured within 0.2% of 0.2; none
/// at all 0.4% below it.
const SCREENED_PHASE_SHARE: f64 = 0.2;

/// Least share of the time limit that the exact evaluations of the finalists before the
/// search leave to the search, on fewer threads than finalists. Without it a longer limit
/// could mean less search: mall robot 2,036 m (one exact evaluation 0.73 s on one core)
/// ran 8-10 batches at 2 s, none at 2.7 s and 3.5 s (all 443.1 nats, seeds 1 and 2: the
/// time went to finalists), and 82 batches at 3.5 s with this rule (449.78 and 449.88
/// nats; 462.06 for seed 2 in another run).
const SEARCH_KEEP: f64 = 0.5;

/// What one surrogate evaluation costs in the units of [`super::auto::eval_units`]
/// (about 1.6e10 a second on one core here, for both): about 0.8 µs per vertex and
/// 0.2 µs per sample (`examples/surrogate_error.rs`, one core: campus, 290 vertices,
/// human 223 m 0.22 ms; mall, 565 vertices, human 509 m 0.50 ms, robot 509 m 0.67 ms).
pub(super) fn surrogate_units(p: &Problem) -> f64 {
    let n = p.building.pilot.len() as f64 + p.budget / p.engine.model().spacing() + 1.0;
    13_000.0 * p.building.len() as f64 + 3_000.0 * n
}

/// Largest share of the time limit one exact evaluation may take for the finalists to be
/// evaluated before the search (and the search's walk offered exactly as it improves).
/// Beyond it they are not: the search's walk is evaluated once, at the end, and the
/// search gets the time. Mall robot 2,036 m (one exact evaluation 0.73 s on one core
/// here) had about 0.2 s of search at 2 s otherwise.
///
/// Measured at 2 s, one core, seeds 1-4, mean utility: with a share of 0.1 against none,
/// mall robot 2,036 m 477.86 -> 524.04 nats (+9.7%), the other 17 rows of
/// `docs/benchmark-scale.md`'s office, campus and mall within -0.9% to +0.6% (mean of
/// all 18 1.0052); 0.03 against 0.1 (robot rows of campus and mall), mall robot 1,018 m
/// 362.05 -> 366.49 (+1.2%, an exact evaluation of 0.17 s); 0.01 against 0.03, campus
/// robot 891 m 312.91 -> 317.61 (+1.5%) and 446 m +0.7%; 0.003 against 0.01, all 18
/// rows within -0.2% to +1.2% (mean 1.0009). A walk the search has not improved on
/// (the best construction) is returned without an exact comparison against the
/// systematic walk: the surrogate ranked the construction above it.
const DEFER_SHARE: f64 = 0.01;

/// Margin on the estimated time of the deferred final evaluation ([`DEFER_SHARE`]) that
/// the search leaves before the deadline (besides 50 ms). The estimate is within about
/// 10% either way (one core here: huge-3k person 3,116 m 250 ms estimated, 268 ms taken;
/// 6,232 m 542 and 565 ms; mall robot 2,036 m 763 and 739 ms, 1,018 m 160 and 163 ms;
/// campus robot 891 m 31 and 24 ms). With a margin of 1.15 and the earlier estimate,
/// mall robot 2,036 m returned after 1.70 s of its 2 s.
const DEFER_MARGIN: f64 = 1.05;

/// Multiply-adds per second of the time limit below which a walk's exact evaluation is
/// cheap on any device this runs on (a phone does a few billion a second, this machine
/// about 2e10), so [`exact_time_estimate`] does not time one.
const CHEAP_WORK_PER_SECOND: f64 = 1e8;

/// What one exact evaluation costs on this thread: a fixed part (copying the prior's
/// factor, the kernel rows) and a part per multiply-add of its factorisations
/// ([`crate::utility::UtilityEngine::utility_work`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::plan) struct ExactCost {
    fixed: f64,
    per_work: f64,
}

impl ExactCost {
    /// The line through two timed evaluations `(work, seconds)`, the second the larger,
    /// when they make one with a positive slope and a fixed part that is not negative;
    /// else the second's rate alone, as if nothing were fixed (timing noise, or a first
    /// evaluation slowed by growing its buffers), which overstates the time of a larger
    /// evaluation rather than understating it.
    fn through((w1, t1): (f64, f64), (w2, t2): (f64, f64)) -> Self {
        let slope = (t2 - t1) / (w2 - w1);
        if w2 > w1 && slope > 0.0 && t1 - slope * w1 >= 0.0 {
            ExactCost {
                fixed: t1 - slope * w1,
                per_work: slope,
            }
        } else {
            ExactCost {
                fixed: 0.0,
                per_work: t2 / w2,
            }
        }
    }

    /// Seconds for an evaluation of `work` multiply-adds.
    pub(in crate::plan) fn time(&self, work: f64) -> Duration {
        Duration::from_secs_f64(self.fixed + self.per_work * work)
    }
}

/// What one exact evaluation of `walk` costs on this thread, when it may be dear beside
/// `limit` (`None` when it is certainly cheap, see [`CHEAP_WORK_PER_SECOND`]): the
/// estimated time and the cost model it comes from, timed on the problem's first dear
/// walk and kept ([`Problem::exact_cost`]) for the others. Two prefixes of `walk`, with about a
/// 64th and a quarter of its work, are evaluated and timed, and the line through the two
/// points gives the fixed part and the part per multiply-add; timing them costs about
/// 27% of an evaluation. A model alone would be off by the device's speed (several times
/// on a phone). Measured here, one core (time of prefixes of 1/64 to all of the work):
/// the time per multiply-add falls with the work on the generated 3,161-vertex floor
/// (huge-3k, person 3,116 m: 63 ms for 1/64 of the work, 268 ms for all of it: the fixed
/// part is copying the prior's factor of 3,161 vertices), is flat on the campus (robot
/// 891 m, 4.3e-11 s throughout) and rises by a third between 1/8 and 1/4 of the work on
/// mall robot 1,018 m (the matrix outgrows the cache). So the larger prefix is a quarter,
/// past that step. One prefix of an eighth scaled by the ratio of the works (how this was
/// estimated before) counted the fixed part eight times: huge-3k person 3,116 m, 702 ms
/// estimated against 272 ms taken, which left its 2 s plan no search at all.
pub(in crate::plan) fn exact_time_estimate(
    p: &Problem,
    walk: &[usize],
    limit: Duration,
) -> Result<Option<(Duration, ExactCost)>> {
    let full = p.engine.utility_work(walk)?;
    if full < CHEAP_WORK_PER_SECOND * limit.as_secs_f64() || walk.len() < 3 {
        return Ok(None);
    }
    // Timed once per problem (and its clones): the model is the device's, not the walk's.
    if let Some(cost) = p.exact_cost.get() {
        return Ok(Some((cost.time(full), *cost)));
    }
    // The largest k with work(walk[..k]) <= target (at least one vertex).
    let prefix_for = |target: f64| -> Result<usize> {
        let (mut lo, mut hi) = (1usize, walk.len());
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if p.engine.utility_work(&walk[..mid])? <= target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(lo)
    };
    let timed = |k: usize| -> Result<(f64, f64)> {
        let prefix = &walk[..k];
        let work = p.engine.utility_work(prefix)?.max(1.0);
        let t0 = Instant::now();
        p.utility(prefix)?;
        Ok((work, t0.elapsed().as_secs_f64()))
    };
    // The matrix the evaluations use, allocated before they are timed (when the plan
    // keeps it: `KeepScratch`), as it is for every evaluation after the first.
    p.engine.warm_scratch(walk)?;
    let k2 = prefix_for(full / 4.0)?;
    let k1 = prefix_for(full / 64.0)?.min(k2.saturating_sub(1)).max(1);
    let cost = ExactCost::through(timed(k1)?, timed(k2)?);
    let cost = *p.exact_cost.get_or_init(|| cost);
    Ok(Some((cost.time(full), cost)))
}

/// How far past its time limit a plan may return (issue 13: "within max(10%, 0.2 s)").
pub(in crate::plan) fn limit_allowance(limit: Duration) -> Duration {
    (limit / 10).max(Duration::from_millis(200))
}

/// Refuses a plan whose final exact evaluation cannot end within the time limit and its
/// [`limit_allowance`]: `t` is that evaluation's estimated time for `walk` (a walk that
/// uses the budget), `cost` the model it came from. The utility a plan reports is SPEC
/// 3's exact one, and on a large floor with a robot's sample every 0.5 m one evaluation
/// of a long walk takes seconds (1,070 vertices, robot 2,768 m: 5,532 samples, about
/// 2 s on one core here), so no walk that uses the budget can be returned in time:
/// rather than overrun the limit by that much, the plan stops here, at once, with what
/// it needs and what to change. The budget named is the one whose walk's evaluation
/// takes at most a quarter of the limit (the rest for set-up and search), where that is
/// a tenth of the budget or more; the limit named is 1.5 times the time needed plus the
/// limit asked for.
fn refuse_if_too_slow(
    p: &Problem,
    run: &Run,
    walk: &[usize],
    t: Duration,
    cost: ExactCost,
) -> Result<()> {
    let (Some(deadline), Some(limit)) = (run.deadline(), run.time_limit()) else {
        return Ok(());
    };
    let now = Instant::now();
    let finish = now + t.mul_f64(DEFER_MARGIN);
    if finish <= deadline + limit_allowance(limit) {
        return Ok(());
    }
    let needed = finish.saturating_duration_since(deadline - limit);
    // The longest prefix of the walk whose evaluation the limit affords.
    let (mut lo, mut hi) = (1usize, walk.len());
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if cost.time(p.engine.utility_work(&walk[..mid])?) <= limit / 4 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let fits = p.length(&walk[..lo]);
    // A budget is worth naming only where the limit affords a useful part of this one.
    let smaller = if fits >= 0.1 * p.budget {
        format!(", or plan a budget of about {:.0} m", fits.floor())
    } else {
        String::new()
    };
    let samples = (p.length(walk) / p.engine.model().spacing()).floor() as u64 + 1;
    Err(Error::TimeLimitTooShort {
        needed,
        message: format!(
            "planning on {:?} ({} vertices, budget {:.1} m) needs about {:.1} s on this \
             device, more than the time limit of {:.1} s: the utility of a walk that uses \
             the budget ({samples} samples) is one dense factorisation, about {:.1} s here, \
             which grows with the cube of the samples; raise the time limit (--time-limit, \
             PlanRequest.time_limit) to {:.0} s or more{smaller} (or plan one floor or part \
             of the building: {})",
            p.building.name,
            p.building.len(),
            p.budget,
            needed.as_secs_f64(),
            limit.as_secs_f64(),
            t.as_secs_f64(),
            // Half as much again as the estimate, so that a busier moment does not refuse
            // the retry, and the limit itself for the search.
            (needed.mul_f64(1.5) + limit).as_secs_f64().ceil(),
            super::part_hint(&p.building, p.start, p.end, p.budget, p.engine.kernel().ell),
        ),
    })
}

/// A walk as a person gets it: reversals repaired ([`unpace`]) for the human model.
fn for_surveyor(p: &Problem, walk: Vec<usize>) -> Vec<usize> {
    if matches!(p.engine.model(), Surveyor::Human { .. }) {
        unpace(p, &walk)
    } else {
        walk
    }
}

/// The search score: the surrogate value, penalised per reversal for a person.
fn score(p: &Problem, s: &Surrogate, walk: &[usize]) -> Result<f64> {
    Ok(p.objective(walk, s.value(walk)?))
}

/// The spread construction of a whole walk (start to end, the whole budget), nearest edge
/// first, avoiding reversals for a person.
pub(in crate::plan) fn whole_walk(p: &Problem) -> Leg {
    Leg {
        from: p.start,
        prev: None,
        to: p.end,
        budget: p.budget,
        radius: 0.0,
        any_fit: true,
        avoid_reversals: matches!(p.engine.model(), Surveyor::Human { .. }),
        open_ties: false,
    }
}

/// The best of the spread constructions for novelty radii `radii_ell` (in units of the
/// kernel's length scale) by exact utility, offered to `run`: a walk of the whole budget
/// (reversals repaired for a person), the small-building portfolio's first incumbent.
pub fn best_construction(p: &Problem, run: &Run, radii_ell: &[f64]) -> Result<(Vec<usize>, f64)> {
    let ell = p.engine.kernel().ell;
    let base = whole_walk(p);
    let radii: Vec<f64> = radii_ell.iter().map(|r| r * ell).collect();
    let radii = distinct_radii(p, &radii);
    let built: Vec<(Vec<usize>, Result<f64>)> = radii
        .par_iter()
        .map(|&r| {
            let w = for_surveyor(p, leg(p, &Leg { radius: r, ..base }, &[], None, run));
            let u = p.utility(&w);
            (w, u)
        })
        .collect();
    let mut best: Option<(Vec<usize>, f64, f64)> = None;
    for (w, u) in built {
        let u = u?;
        p.offer(run, &w, u);
        let s = p.objective(&w, u);
        if best
            .as_ref()
            .is_none_or(|(bw, _, bs)| better((&w, s), (bw, *bs)))
        {
            best = Some((w, u, s));
        }
    }
    match best {
        Some((w, u, _)) => Ok((w, u)),
        None => {
            let w = p.shortest_walk();
            let u = p.utility(&w)?;
            Ok((w, u))
        }
    }
}

/// Statistics of a large-building search, for progress messages and the benchmark.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stats {
    pub batches: usize,
    pub accepted: usize,
    pub surrogate_evals: usize,
    /// Candidates of the exact phase (judged by exact `f_D`).
    pub exact_evals: usize,
    /// The batch at which the search switched to exact scores, if it did.
    pub exact_from_batch: Option<usize>,
    /// Kicks: moves on from a large rebuild of the best walk after a long stall.
    pub kicks: usize,
    /// Whether the finalists' exact evaluations were deferred ([`DEFER_SHARE`]).
    pub deferred: bool,
    /// Candidates that were the walk they were drawn from, or a walk scored before in
    /// the same phase, and took that score instead of an evaluation ([`Seen`]).
    pub known: usize,
}

/// How the search of [`plan_large_with`] divides its work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Schedule {
    /// By the run's time limit: phases at shares of the window, the search until the time
    /// left is what the final exact evaluation needs (`auto` on a large building).
    Clock,
    /// By a bounded number of batches, as without a time limit, so that the same seed
    /// gives the same walk on any machine; the run's deadline and cancel still stop it
    /// (a stage of `auto`'s small-building portfolio).
    Batches,
}

/// `auto` on a large building (see the module doc). `seed` drives every random choice.
pub fn plan_large(p: &Problem, run: &Run, seed: u64) -> Result<(Outcome, Stats)> {
    plan_large_with(p, run, seed, Schedule::Clock)
}

/// [`plan_large`] with its work divided by `schedule`.
pub fn plan_large_with(
    p: &Problem,
    run: &Run,
    seed: u64,
    schedule: Schedule,
) -> Result<(Outcome, Stats)> {
    let mut stats = Stats::default();
    // This thread's exact evaluations (the timed prefixes, the finalists) reuse one
    // matrix until the plan ends.
    let _scratch = crate::utility::KeepScratch::new();
    // The limit and deadline the search plans its phases by (none for `Batches`, whose
    // work does not depend on a clock); `run` still stops it at its deadline.
    let (time_limit, deadline) = match schedule {
        Schedule::Clock => (run.time_limit(), run.deadline()),
        Schedule::Batches => (None, None),
    };
    let human = matches!(p.engine.model(), Surveyor::Human { .. });
    // Progress shows the exact utility of the best walk offered so far (none before the
    // first exact evaluation). As a stage of a portfolio (`Batches`) the search reports
    // no fraction of its own: the portfolio's stages do.
    let report = |f: f64, m: String| {
        let best = run.incumbent().map(|(_, u)| u);
        let f = if schedule == Schedule::Clock { f } else { 0.0 };
        run.report(Algorithm::Auto, f, best, m)
    };
    let sur = Surrogate::new(p)?;
    let ell = p.engine.kernel().ell;

    // The moves' novelty radii ([`MOVE_RADII`], [`FINE_MOVE_RADII`]): those the
    // near-edge table answers for (a radius beyond it marks by scanning every edge, see
    // `tabled_radii`). `radii` holds both lists; a walk's marks are kept per radius.
    let scaled = |fs: &[f64]| -> Vec<f64> { fs.iter().map(|f| f * ell).collect() };
    let coarse = tabled_radii(p, &scaled(&MOVE_RADII));
    let fine = tabled_radii(p, &scaled(&FINE_MOVE_RADII));
    let radii: Vec<f64> = coarse.iter().chain(&fine).copied().collect();
    // 1. Constructions for twelve novelty radii, each with both tie rules (lowest edge
    //    index, and the edge the walk can carry on from: see `Leg::open_ties`), judged by
    //    the surrogate; a radius that marks what a smaller one does would build the same
    //    walks, and is left out.
    let base = whole_walk(p);
    let build_radii: Vec<f64> = CONSTRUCTION_RADII.iter().map(|f| f * ell).collect();
    let build_radii = distinct_radii(p, &build_radii);
    let variants: Vec<(f64, bool)> = [false, true]
        .iter()
        .flat_map(|&o| build_radii.iter().map(move |&r| (r, o)))
        .collect();
    let walks: Vec<Vec<usize>> = variants
        .par_iter()
        .map(|&(r, open_ties)| {
            let spec = Leg {
                radius: r,
                open_ties,
                ..base
            };
            for_surveyor(p, leg(p, &spec, &[], None, run))
        })
        .collect();
    // Different marks may still build the same walk (huge-3k person 3,116 m: 9 distinct
    // walks of 14): each is scored once.
    let first_of: Vec<usize> = (0..walks.len())
        .map(|i| walks[..i].iter().position(|w| *w == walks[i]).unwrap_or(i))
        .collect();
    let scores: Vec<Option<f64>> = walks
        .par_iter()
        .enumerate()
        .map(|(i, w)| (first_of[i] == i).then(|| score(p, &sur, w).unwrap_or(f64::NEG_INFINITY)))
        .collect();
    stats.surrogate_evals += scores.iter().flatten().count();
    let built: Vec<(Vec<usize>, f64)> = walks
        .into_iter()
        .zip(&first_of)
        .map(|(w, &j)| {
            let s = scores[j].unwrap_or(f64::NEG_INFINITY);
            (w, s)
        })
        .collect();
    let (mut cur, mut cur_s) =
        built
            .iter()
            .cloned()
            .fold((Vec::new(), f64::NEG_INFINITY), |a, b| {
                if b.1 > a.1 { b } else { a }
            });
    // The finalists other than the search's walk are known now: the best construction
    // (and the best of the other tie rule) and the systematic walk (for a person also with its reversals repaired). Evaluate
    // them exactly at once, in parallel: that offers a full-budget walk before the search
    // starts (what a cancel or a time-out returns) and *measures* what one exact
    // evaluation costs, so the search leaves the final one exactly the time it needs.
    let coverage = leg(
        p,
        &Leg {
            any_fit: false,
            avoid_reversals: false,
            ..base
        },
        &[],
        None,
        run,
    );
    // The best construction of the other tie rule is a finalist too, second: the
    // surrogate ranks the two rules' walks poorly against each other on big floors
    // (mall robot 2,036 m: it prefers a 432.8-nat walk to the open-ties one of 440.7).
    let half = build_radii.len();
    let best_of = |from: usize| {
        built[from..from + half]
            .iter()
            .fold(None::<&(Vec<usize>, f64)>, |a, b| match a {
                Some(a) if a.1 >= b.1 => Some(a),
                _ => Some(b),
            })
            .map(|(w, _)| w.clone())
    };
    let other = if built.len() == 2 * half {
        [best_of(0), best_of(half)]
            .into_iter()
            .flatten()
            .find(|w| *w != cur)
    } else {
        None
    };
    let mut fixed = vec![cur.clone()];
    fixed.extend(other);
    fixed.push(coverage.clone());
    if human {
        fixed.push(unpace(p, &coverage));
    }
    let timed_utility = |w: &Vec<usize>| {
        let t0 = Instant::now();
        (p.utility(w), t0.elapsed())
    };
    // When one exact evaluation is dear beside the time limit (more than DEFER_SHARE of
    // it), the finalists are not evaluated before the search: the search gets that time,
    // and its walk is the one finalist evaluated, at the end (see DEFER_SHARE).
    let estimate = match time_limit {
        Some(limit) => exact_time_estimate(p, &cur, limit)?
            .filter(|(t, _)| t.as_secs_f64() > DEFER_SHARE * limit.as_secs_f64()),
        None => None,
    };
    let deferred: Option<Duration> = estimate.map(|(t, _)| t);
    stats.deferred = deferred.is_some();
    // The cost model of an exact evaluation, when deferred: the final evaluation's time
    // is computed from it for the search's walk of the moment (one with fewer coincident
    // samples costs more: mall robot 2,036 m, 1.35e10 multiply-adds for the best
    // construction, 1.60e10 for the search's walk).
    let rate = estimate.map(|(_, cost)| cost);
    if let Some((t, cost)) = estimate {
        refuse_if_too_slow(p, run, &cur, t, cost)?;
    }
    if deferred.is_some() {
        fixed.clear();
    }
    let timed: Vec<(Result<f64>, Duration)> = if deferred.is_some() {
        Vec::new()
    } else if rayon::current_num_threads() >= fixed.len() {
        fixed.par_iter().map(timed_utility).collect()
    } else {
        // Fewer threads than finalists (one core): the best construction first, then the
        // others only while the time left affords them, the final evaluation and at least
        // SEARCH_KEEP of the limit for the search, so that a walk whose exact evaluation
        // costs seconds neither overshoots the limit by several of them nor leaves the
        // search no time. A finalist left out is not offered (its surrogate rank stands).
        let mut out = vec![timed_utility(&fixed[0])];
        let t1 = out[0].1;
        let keep = time_limit.unwrap_or_default().mul_f64(SEARCH_KEEP);
        for w in &fixed[1..] {
            let affordable = deadline.is_none_or(|d| Instant::now() + t1.mul_f64(2.2) + keep <= d);
            if !affordable || run.should_stop() {
                break;
            }
            out.push(timed_utility(w));
        }
        out
    };
    fixed.truncate(timed.len());
    // Deferred: the estimate stands for the measurement.
    let mut t_exact = deferred.unwrap_or_default();
    // The cheapest of them: the first evaluation also builds the engine's lazy state, so
    // the longest overstates what one costs in the search.
    let mut t_eval: Option<Duration> = deferred;
    let mut fixed_u = Vec::with_capacity(fixed.len());
    for (w, (u, t)) in fixed.iter().zip(timed) {
        let u = u?;
        p.offer(run, w, u);
        fixed_u.push(u);
        t_exact = t_exact.max(t);
        t_eval = Some(t_eval.map_or(t, |e| e.min(t)));
    }
    let first = cur.clone();
    // Exact evaluations during the search when they are cheap beside the limit (at most a
    // tenth of it each): the current walk whenever its surrogate value has grown by 1%,
    // so that progress and a cancel show exact figures.
    let limit = time_limit.unwrap_or(Duration::from_secs(3600));
    let exact_offers = t_exact < limit / 10 && deferred.is_none();
    let mut offered_s = cur_s;
    // The best walk of the search evaluated exactly so far (an offered walk): the
    // surrogate may later prefer a walk that is worse by `f_D`, and the plan must never
    // end below what it has already shown.
    let mut offered: Option<(Vec<usize>, f64)> = None;
    report(0.1, format!("spread construction, {:.0} m", p.length(&cur)));

    // 2. Large-neighbourhood search until the time left is what the final exact
    //    evaluation of the search's walk needs (measured above, with a margin for a busy
    //    machine), or a bounded number of batches without a time limit.
    let reserve = |walk: &[usize]| -> Result<Duration> {
        Ok(match rate {
            Some(c) => c.time(p.engine.utility_work(walk)?).mul_f64(DEFER_MARGIN),
            None => t_exact.mul_f64(1.3),
        } + Duration::from_millis(50))
    };
    let stop_for = |walk: &[usize]| -> Result<Option<Instant>> {
        let r = reserve(walk)?;
        Ok(deadline.map(|d| d.checked_sub(r).unwrap_or(d)))
    };
    let mut stop_at = stop_for(&cur)?;
    let max_batches = if stop_at.is_some() { usize::MAX } else { 400 };
    // 2b. When exact evaluations are cheap beside the search window (it affords at least
    //     EXACT_PHASE_BATCHES batches of them in its last EXACT_PHASE_SHARE), that last
    //     part judges candidates by exact `f_D` instead of the surrogate, which polishes
    //     the surrogate's optimum into an exact one (office robot 201 m, 2 s: 86.55 ->
    //     90.41 nats). Without a time limit, the last EXACT_PHASE_SHARE of the batches.
    let threads = rayon::current_num_threads().clamp(1, BATCH) as f64;
    let batch_exact = t_eval
        .unwrap_or(t_exact)
        .mul_f64((BATCH as f64 / threads).ceil());
    let exact_from: Option<Instant> = stop_at.and_then(|t| {
        let window = t.checked_duration_since(Instant::now())?;
        let share = window.mul_f64(EXACT_PHASE_SHARE);
        (batch_exact.mul_f64(EXACT_PHASE_BATCHES as f64) <= share).then(|| t - share)
    });
    // Without a time limit the choice must not depend on a clock (same seed, same walk):
    // it is made by auto's deterministic cost model, 40 batches of exact evaluations
    // within one second's worth of its units.
    let exact_from_batch = (stop_at.is_none()
        && super::auto::eval_units(p) * (BATCH * EXACT_PHASE_BATCHES) as f64
            <= super::auto::UNITS_PER_SECOND)
        .then_some((max_batches as f64 * (1.0 - EXACT_PHASE_SHARE)) as usize);
    // 2d. When an exact evaluation costs no more than a surrogate one (a person's walks,
    //     a sample every 4.8 m, on buildings of a few hundred vertices), the whole search
    //     judges by exact `f_D`.
    let exact_only = super::auto::eval_units(p) <= surrogate_units(p);
    // 2c. Else, when one exact evaluation per batch is affordable (EXACT_PHASE_BATCHES of
    //     them in the last SCREENED_PHASE_SHARE of the window), that part is *screened*:
    //     the surrogate still ranks each batch, and its best candidate is evaluated
    //     exactly and accepted only when that beats the current walk's exact score.
    let screen_from: Option<Instant> = if exact_from.is_none() && !exact_only {
        stop_at.and_then(|t| {
            let window = t.checked_duration_since(Instant::now())?;
            let share = window.mul_f64(SCREENED_PHASE_SHARE);
            (t_eval
                .unwrap_or(t_exact)
                .mul_f64(EXACT_PHASE_BATCHES as f64)
                <= share)
                .then(|| t - share)
        })
    } else {
        None
    };
    let mut screened = false;
    let mut exact_phase = false;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5ca1_ab1e);
    let mut stale = 0usize;
    // The walk the search moves from: `cur` is the best it has seen; `walk` may be up to
    // `drift` worse than it (record-to-record travel), the drift shrinking to nothing
    // over the search window.
    let (mut walk, mut walk_s) = (cur.clone(), cur_s);
    // The surrogate's frame of `walk`: a move's candidate is scored by the vertices its
    // changed stretch comes near ([`Surrogate::value_near`]), a 25th to a 35th of a whole
    // evaluation on the mall. A candidate the search would move to is scored whole
    // before it does, so every score it keeps (`cur_s`, `walk_s`) is a whole walk's.
    let mut frame: Option<Frame> = None;
    // `walk`'s marks for each radius of `radii` (built when a move first needs them).
    let mut marks: Vec<Option<Marks>> = vec![None; radii.len()];
    let mut marks_of: Option<Vec<usize>> = None;
    // In the exact phase (unscreened), `walk`'s factorisation: each candidate of a batch
    // is drawn from `walk` and computes only the rows from its first changed sample
    // ([`UtilityEngine::utility_near`](crate::utility::UtilityEngine::utility_near)).
    let mut near: Option<crate::utility::NearBase> = None;
    // Off once a base keeps nothing to start from (see `NearBase::reuses`).
    let mut near_off = false;
    let mut seen = Seen::default();
    let search_start = Instant::now();
    while stats.batches < max_batches && !run.should_stop() {
        if stop_at.is_some_and(|t| Instant::now() >= t) {
            break;
        }
        if !exact_phase
            && (exact_only
                || exact_from.is_some_and(|t| Instant::now() >= t)
                || screen_from.is_some_and(|t| Instant::now() >= t)
                || exact_from_batch.is_some_and(|b| stats.batches >= b))
        {
            screened = screen_from.is_some();
            // Switch to exact scores: start from the best walk known exactly (the
            // search's walk, an offered one or a fixed finalist), judged as at the end.
            exact_phase = true;
            // The scores kept so far are the surrogate's (unscreened, exact ones follow).
            if !screened {
                seen.clear();
            }
            stats.exact_from_batch = Some(stats.batches);
            let u = p.utility(&cur)?;
            p.offer(run, &cur, u);
            let mut start = (cur.clone(), u, p.objective(&cur, u));
            let known = fixed.iter().zip(&fixed_u).map(|(w, &u)| (w, u));
            for (w, u) in known.chain(offered.as_ref().map(|(w, u)| (w, *u))) {
                let s = p.objective(w, u);
                if better((w, s), (&start.0, start.2)) {
                    start = (w.clone(), u, s);
                }
            }
            (cur, cur_s) = (start.0.clone(), start.2);
            (walk, walk_s) = (cur.clone(), cur_s);
            if offered.as_ref().is_none_or(|(_, bu)| start.1 > *bu) {
                offered = Some((start.0, start.1));
            }
            stale = 0;
        }
        stats.batches += 1;
        // Draw the batch's moves sequentially (deterministic), evaluate in parallel.
        // In the exact phase (candidates judged by exact `f_D`), a person's moves are
        // sometimes a closed sub-walk walked the other way ([`closed_subwalk`]).
        let reversing = human && exact_phase && !screened;
        let moves: Vec<Move> = (0..BATCH)
            .map(|_| {
                if reversing
                    && rng.random_bool(REVERSE_SHARE)
                    && let Some(r) = closed_subwalk(&walk, &mut rng)
                {
                    return Move {
                        reverse: Some(r),
                        ..Move::default()
                    };
                }
                let cut = if rng.random_bool(CUT_SHARE) {
                    excursion(&walk, &mut rng)
                } else {
                    None
                };
                let n = walk.len() - cut.map_or(0, |(a, b)| b - a);
                // 5% to 35% of the walk, but at most STRETCH_MAX_VERTICES (and from at most
                // STRETCH_MIN_VERTICES) vertices: long walks take local moves.
                let hi = 0.35f64.min(STRETCH_MAX_VERTICES / n.max(1) as f64);
                let lo = 0.05f64
                    .min(STRETCH_MIN_VERTICES / n.max(1) as f64)
                    .min(0.5 * hi);
                let frac = rng.random_range(lo..hi);
                let i = rng.random_range(0..n.max(1));
                let span = ((n as f64 * frac).ceil() as usize).max(1);
                let j = (i + span).min(n - 1);
                // Half the moves take a coarse radius, half a fine one.
                let radius = if fine.is_empty() || rng.random_bool(0.5) {
                    coarse[rng.random_range(0..coarse.len())]
                } else {
                    fine[rng.random_range(0..fine.len())]
                };
                Move {
                    cut,
                    i,
                    j,
                    radius,
                    seed: rng.random(),
                    reverse: None,
                }
            })
            .collect();
        let by_surrogate = !exact_phase || screened;
        if by_surrogate && frame.as_ref().is_none_or(|f| f.walk() != walk.as_slice()) {
            frame = Some(sur.frame(&walk)?);
            stats.surrogate_evals += 1;
        }
        // The walk's marks for each radius a move of this batch takes: those of the
        // walk before, moved by the steps that changed (a stretch or two), unless that
        // is most of the walk.
        if let Some(old) = marks_of.as_deref()
            && old != walk.as_slice()
        {
            let (o, n) = super::coverage::changed_spans(old, &walk);
            if o.len() + n.len() > walk.len() {
                marks.iter_mut().for_each(|m| *m = None);
            } else {
                for m in marks.iter_mut().flatten() {
                    m.rewalk(old, &walk);
                }
            }
        }
        if marks_of.as_deref() != Some(walk.as_slice()) {
            marks_of = Some(walk.clone());
        }
        for m in &moves {
            let k = radii.iter().position(|&r| r == m.radius).unwrap_or(0);
            if marks[k].is_none() {
                let mut mk = Marks::new(p, radii[k]);
                mk.walk_all(&walk, 1);
                marks[k] = Some(mk);
            }
        }
        let exact_near = exact_phase && !screened && !near_off;
        if exact_near && near.as_ref().is_none_or(|b| b.walk() != walk.as_slice()) {
            let b = p.engine.near_base(&walk, p.near_base_max)?;
            stats.exact_evals += 1;
            near_off = !b.reuses();
            near = Some(b);
        }
        let exact_near = exact_near && !near_off;
        let nb = near.as_ref().filter(|_| exact_near);
        let fr = frame.as_ref();
        // (walk, score, exact utility when the score is exact, whether the score was
        // known): a candidate that is the walk itself, or one scored before in this
        // phase, takes its known score instead of another evaluation (see `Seen`).
        let seen_now = &seen;
        let walk_ref = &walk;
        // The walk's own score as this batch judges: its surrogate value where the batch
        // is ranked by the surrogate (in the screened phase `walk_s` is exact), else
        // `walk_s`.
        let walk_score = match fr {
            Some(f) if by_surrogate => p.objective(&walk, f.value()),
            _ => walk_s,
        };
        let cands: Vec<(Vec<usize>, f64, Option<f64>, bool)> = moves
            .par_iter()
            .filter_map(|m| {
                let k = radii.iter().position(|&r| r == m.radius);
                let mk = k.and_then(|k| marks[k].as_ref());
                let w = m.apply_marked(p, walk_ref, mk, human, run);
                if w == *walk_ref {
                    return Some((w, walk_score, None, true));
                }
                if let Some((sc, u)) = seen_now.get(&w) {
                    return Some((w, sc, u, true));
                }
                let (w, sc, u) = match fr {
                    Some(f) if by_surrogate => {
                        let sc = p.objective(&w, sur.value_near(f, &w).ok()?);
                        (w, sc, None)
                    }
                    _ => {
                        let u = match nb {
                            Some(b) => p.engine.utility_near(b, &w).ok()?,
                            None => p.utility(&w).ok()?,
                        };
                        let sc = p.objective(&w, u);
                        (w, sc, Some(u))
                    }
                };
                Some((w, sc, u, false))
            })
            .collect();
        let fresh = cands.iter().filter(|c| !c.3).count();
        stats.known += cands.len() - fresh;
        if exact_phase {
            stats.exact_evals += fresh;
        } else {
            stats.surrogate_evals += fresh;
        }
        for (w, sc, u, known) in &cands {
            if !known {
                seen.insert(w, *sc, *u);
            }
        }
        let cands = cands.into_iter().map(|(w, sc, u, _)| (w, sc, u));
        let mut best =
            cands
                .into_iter()
                .fold(None::<(Vec<usize>, f64, Option<f64>)>, |a, b| match a {
                    Some(a) if !better((&b.0, b.1), (&a.0, a.1)) => Some(a),
                    _ => Some(b),
                });
        if screened && let Some((w, sc, u)) = best.as_mut() {
            let x = p.utility(w)?;
            stats.exact_evals += 1;
            *u = Some(x);
            *sc = p.objective(w, x);
        }
        let frac = match stop_at {
            Some(t) => {
                let total = t.saturating_duration_since(search_start).as_secs_f64();
                search_start.elapsed().as_secs_f64() / total.max(1e-9)
            }
            None => stats.batches as f64 / max_batches.min(400) as f64,
        };
        let drift = DRIFT * (1.0 - frac).max(0.0);
        // A candidate scored by `value_near` that the search would accept or move to is
        // scored whole first (its frame is then the next batch's).
        let mut next_frame: Option<Frame> = None;
        if let Some((w, sc, None)) = best.as_mut()
            && (*sc > cur_s * (1.0 + 1e-9)
                || (*w != walk && (*sc > walk_s * (1.0 + 1e-9) || *sc >= cur_s * (1.0 - drift))))
        {
            let f = sur.frame(w)?;
            stats.surrogate_evals += 1;
            *sc = p.objective(w, f.value());
            next_frame = Some(f);
        }
        if let Some((w, s, u)) = best.clone()
            && s > cur_s * (1.0 + 1e-9)
        {
            // A walk scored from `walk`'s factorisation is offered with its whole
            // evaluation (the same to rounding), which is the next batch's base.
            let u = match u {
                Some(_) if exact_near => {
                    let b = p.engine.near_base(&w, p.near_base_max)?;
                    stats.exact_evals += 1;
                    let x = b.utility();
                    near = Some(b);
                    Some(x)
                }
                u => u,
            };
            if let Some(u) = u {
                p.offer(run, &w, u);
                if offered.as_ref().is_none_or(|(_, bu)| u > *bu) {
                    offered = Some((w.clone(), u));
                }
            }
            cur = w.clone();
            cur_s = s;
            (walk, walk_s) = (w, s);
            stats.accepted += 1;
            if rate.is_some() {
                stop_at = stop_for(&cur)?;
            }
            stale = 0;
        } else {
            // A person's walk drifts only to walks with no more reversals than the best
            // one: the score's 1% per reversal is smaller than the drift, and a search
            // that drifts through reversals ends with them (office, 201 m: 1.5 per 100 m
            // without this rule, none before the drift).
            if let Some((w, s, _)) = best
                && w != walk
                && (s > walk_s * (1.0 + 1e-9) || s >= cur_s * (1.0 - drift))
                && (!human || reversals(p, &w) <= reversals(p, &cur))
            {
                (walk, walk_s) = (w, s);
            }
            stale += 1;
            // A kick: the search has gone KICK_STALE batches without a new best walk, on
            // a building and walk small enough for the window to afford many batches per
            // vertex, so it has most likely converged on the best walk's basin. It moves
            // on from a large rebuild of the best walk (the best walk itself is kept).
            if stale.is_multiple_of(KICK_STALE)
                && cur.len() > 3
                && cur.len() as f64 <= KICK_MAX_VERTICES
            {
                let elapsed = search_start.elapsed().as_secs_f64();
                let affords = match stop_at {
                    Some(t) if elapsed > 0.0 => {
                        let window = t.saturating_duration_since(search_start).as_secs_f64();
                        stats.batches as f64 * window / elapsed
                    }
                    Some(_) => 0.0,
                    None => max_batches.min(400) as f64,
                };
                if affords >= KICK_BATCHES_PER_VERTEX * cur.len() as f64 {
                    let m = kick(cur.len(), &coarse, &mut rng);
                    let w = m.apply(p, &cur, human, run);
                    let s = if exact_phase {
                        stats.exact_evals += 1;
                        p.objective(&w, p.utility(&w)?)
                    } else {
                        stats.surrogate_evals += 1;
                        score(p, &sur, &w)?
                    };
                    (walk, walk_s) = (w, s);
                    stats.kicks += 1;
                }
            }
        }
        if let Some(f) = next_frame
            && f.walk() == walk.as_slice()
        {
            frame = Some(f);
        }
        if !exact_phase
            && exact_offers
            && cur_s > offered_s * 1.01
            && stats.batches.is_multiple_of(4)
        {
            let u = p.utility(&cur)?;
            p.offer(run, &cur, u);
            offered_s = cur_s;
            if offered.as_ref().is_none_or(|(_, bu)| u > *bu) {
                offered = Some((cur.clone(), u));
            }
        }
        if stats.batches.is_multiple_of(8) {
            let frac = run.time_fraction().unwrap_or(stats.batches as f64 / 400.0);
            report(
                0.1 + 0.8 * frac,
                format!(
                    "search: batch {}, {} accepted, best walk {:.0} m",
                    stats.batches,
                    stats.accepted,
                    p.length(&cur)
                ),
            );
        }
        if stop_at.is_none() && stale >= 60 {
            break;
        }
    }

    // 3. Exact comparison of the finalists (only the search's walk when cancelled: the
    //    caller wants an answer now).
    if run.control_cancelled() {
        let (walk, u) = match offered {
            Some((w, u)) if w == cur => (w, u),
            known => {
                let u = p.utility(&cur)?;
                p.offer(run, &cur, u);
                match known {
                    Some((w, ku)) if p.objective(&w, ku) > p.objective(&cur, u) => (w, ku),
                    _ => (cur, u),
                }
            }
        };
        return Ok((Outcome::new(walk, u, Termination::Cancelled), stats));
    }
    // The search's walk is the one finalist not yet evaluated exactly; every finalist is
    // judged by its exact utility, penalised per reversal for a person.
    let mut finalists: Vec<(Vec<usize>, f64)> = fixed.into_iter().zip(fixed_u).collect();
    let cur_known = offered.as_ref().is_some_and(|(w, _)| *w == cur);
    if let Some(o) = offered {
        finalists.push(o);
    }
    if (cur != first || deferred.is_some()) && !cur_known {
        let u = p.utility(&cur)?;
        p.offer(run, &cur, u);
        finalists.push((cur, u));
    }
    let mut out: Option<(Vec<usize>, f64, f64)> = None; // walk, utility, penalised
    for (w, u) in finalists {
        let s = p.objective(&w, u);
        if out
            .as_ref()
            .is_none_or(|(bw, _, bs)| better((&w, s), (bw, *bs)))
        {
            out = Some((w, u, s));
        }
    }
    // `finalists` always holds the best construction, or the search's walk when the
    // finalists were deferred.
    let (walk, utility, _) = out.expect("at least one finalist");
    let term = if run.out_of_time() {
        Termination::TimeLimit
    } else {
        Termination::Completed
    };
    report(1.0, "done".into());
    Ok((Outcome::new(walk, utility, term), stats))
}

/// The scores of the candidates a search phase has evaluated, by walk.
///
/// A move's rebuild is a spread leg that is random only in its first target and tie rule,
/// so moves drawn from one walk often build the same candidate again, or the walk itself:
/// at 2 s on one core, 57% of office robot 101 m's exact candidates were the walk they
/// were drawn from and 79% had been evaluated before; campus person 223 m 20% and 47%;
/// mall person 509 m 21% and 30%; mall robot 1,018 m (surrogate) 23% and 24%. Such a
/// candidate takes the score it had (the walk's own for the walk itself) instead of an
/// evaluation, so the search makes the same choices as if it had evaluated it, sooner.
///
/// Keyed by a 64-bit hash of the walk and its length. A known score never makes a walk
/// offered or returned without a fresh exact evaluation: in the exact phase the best
/// walk's score is at least every score the phase has kept, so a known candidate is
/// never a new best; in the surrogate and screened phases a walk is evaluated exactly
/// before it is offered (the screened phase's best candidate of each batch, and the
/// finalists), whatever its surrogate score. The cache is emptied when the exact phase
/// starts.
#[derive(Debug, Default)]
struct Seen {
    scores: std::collections::HashMap<(u64, usize), (f64, Option<f64>)>,
}

/// Most scores [`Seen`] keeps (about 40 bytes each) before it starts again.
const SEEN_MAX: usize = 1 << 20;

impl Seen {
    fn key(walk: &[usize]) -> (u64, usize) {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        walk.hash(&mut h);
        (h.finish(), walk.len())
    }

    /// The score and exact utility (if the score is exact) `walk` was given.
    fn get(&self, walk: &[usize]) -> Option<(f64, Option<f64>)> {
        self.scores.get(&Self::key(walk)).copied()
    }

    fn insert(&mut self, walk: &[usize], score: f64, utility: Option<f64>) {
        if self.scores.len() >= SEEN_MAX {
            self.scores.clear();
        }
        self.scores.insert(Self::key(walk), (score, utility));
    }

    fn clear(&mut self) {
        self.scores.clear();
    }
}

/// Most vertices of the walk that one move of the search rebuilds (the stretch is 5% to
/// 35% of the walk, capped by this). On long walks a fraction made every move a large
/// perturbation, almost always worse, and the few batches of a 2 s window found little.
/// Measured at 2 s, one core, seeds 1-4, against no cap (mean utility with / without,
/// `docs/benchmark-scale.md`'s 18 planned rows of office, campus and mall): mean 1.0136,
/// campus robot 891 m (413 walk vertices) 1.062, mall robot 1,018 m 1.039 and 2,036 m
/// 1.042, mall human 1,018 m 1.049; lowest mall robot 509 m 0.993. Caps of 90, 60, 40 and
/// 15 vertices gave 1.0049, 1.0103, 1.0125 and 1.0126 (15: mall robot 509 m 0.980).
const STRETCH_MAX_VERTICES: f64 = 25.0;

/// The shortest stretch a move may rebuild is 5% of the walk or this many vertices,
/// whichever is less (see [`STRETCH_MAX_VERTICES`]).
const STRETCH_MIN_VERTICES: f64 = 4.0;

/// Share of the search's moves that first cut a closed excursion out of the walk
/// ([`Move`]). With [`DRIFT`], measured at 2 s, one core, seeds 1-8, against neither:
/// +1.2% on the 12 office and campus rows of `docs/benchmark-scale.md` (office robot
/// 402 m 131.32 -> 134.47 nats, office human 201 m 46.47 -> 47.92; lowest row campus human
/// 891 m, -0.05%), the mall's six rows within their seed-to-seed spread (mean +0.04%).
/// The cut alone gave about half of it.
const CUT_SHARE: f64 = 0.5;

/// Share of a person's moves in the exact phase that walk a closed sub-walk the other
/// way ([`closed_subwalk`]) instead of rebuilding a stretch. A person's samples fall
/// every 4.8 m, and where they fall inside a loop matters to `f_D`
/// (`examples/phase_probe.rs`: a hill climb on these reversals alone took the 2 s plan of
/// campus person 891 m from 137.11 to 138.49 nats). Measured at 2 s, one core, seeds 1-3,
/// the nine office, campus and mall person rows of `docs/benchmark-scale.md`, against
/// none: mean +0.76%, from -0.9% (office 101 m) to +1.6% (office 201 m; campus 891 m
/// +1.3%, mall 1,018 m +1.5%); a share of 0.5 against 0.25, mean +0.00%. Huge-3k person
/// 3,116 m and a 1,478-vertex floor's person rows, where the exact phase is short, within
/// -0.4% to +0.1%.
const REVERSE_SHARE: f64 = 0.25;

/// How much worse than the best walk seen the walk the search moves from may be, at the
/// start of the window (record-to-record travel); it shrinks linearly to nothing at the
/// window's end. A strict climb stalls on a walk whose every rebuilt stretch is worse;
/// 2% lets it cross to a neighbouring basin. 5% was worse on the campus (-0.4%).
const DRIFT: f64 = 0.02;

/// Batches without a new best walk after which the search moves on from a large rebuild
/// of the best walk (a kick), when the window affords at least
/// [`KICK_BATCHES_PER_VERTEX`] batches per vertex of the walk. Small walks on small
/// buildings converge in a fraction of a second and then sit in one basin until the time
/// is up: office robot 101 m, 2 s, seeds 1-8, ended at 54.94 to 55.56 nats, and its 60 s
/// plans at 55.08 to 55.56 (seeds 1-5).
///
/// Measured at 2 s, one core, against no kick (mean utility, kick / none): office human
/// 101 m 1.033 (seeds 1-8) and 1.023 (seeds 9-16), office robot 101 m 1.0035 and 1.0027;
/// the 18 rows of `docs/benchmark-scale.md` 1.0005 (seeds 1-8), the 12 office and campus
/// rows 1.0019 (seeds 9-16), every other row within its seed-to-seed spread. Without the
/// per-vertex condition (a kick after every 50 stale batches on every building) the
/// campus person rows lost 2-3%: there a stall of 50 batches is not convergence.
const KICK_STALE: usize = 50;

/// Fewest batches per vertex of the best walk the search window must afford for a kick
/// ([`KICK_STALE`]). The benchmark's office rows at 101 m and 201 m and campus rows at
/// 223 m (robot and person) qualify at 2 s on one core; the mall's rows do not.
const KICK_BATCHES_PER_VERTEX: f64 = 20.0;

/// Longest best walk (vertices) that is kicked ([`KICK_STALE`]). With moves scored from
/// a frame the search affords the kick's batches per vertex on long walks too at long
/// limits, and there a rebuild of a third to three fifths of the walk costs more than
/// the search regains: 60 s, one core, seed 1, kicks against none: mall robot 1,018 m
/// (481 walk vertices) 371.74 against 387.86 nats (its 2 s plan: 382.27), mall robot
/// 509 m (247) 211.98 against 214.02. Shorter walks keep them: a cap of 100 vertices
/// cost office robot 402 m 2.4% at 2 s (seeds 1-4, 147.61 -> 144.13), though at 60 s
/// (seed 1) that row reached 151.16 without kicks and 147.45 with them; no row over 200
/// vertices kicks at 2 s.
const KICK_MAX_VERTICES: f64 = 200.0;

/// A kick ([`KICK_STALE`]): rebuild a random stretch of 30% to 60% of a walk of `n`
/// vertices, without a cut.
fn kick(n: usize, radii: &[f64], rng: &mut ChaCha8Rng) -> Move {
    let span = ((n as f64 * rng.random_range(0.3..0.6)).ceil() as usize).clamp(1, n - 1);
    let i = rng.random_range(0..n - span);
    Move {
        cut: None,
        i,
        j: i + span,
        radius: radii[rng.random_range(0..radii.len())],
        seed: rng.random(),
        reverse: None,
    }
}

/// One move of the large-neighbourhood search: cut the closed excursion `walk[a..b]`
/// (`walk[a] == walk[b]`) out of the walk when `cut` says so, then rebuild the stretch
/// `i..=j` of what remains with the budget left ([`rebuild`]). The cut is what lets the
/// search merge two visits to one room: a stretch rebuilt alone cannot drop the other
/// visit, so the budget it holds stays where it is.
///
/// Or, when `reverse` says so, only walk the closed sub-walk `walk[a..=b]` the other way.
#[derive(Debug, Clone, Copy, Default)]
struct Move {
    cut: Option<(usize, usize)>,
    i: usize,
    j: usize,
    radius: f64,
    seed: u64,
    reverse: Option<(usize, usize)>,
}

impl Move {
    fn apply(&self, p: &Problem, walk: &[usize], human: bool, run: &Run) -> Vec<usize> {
        self.apply_marked(p, walk, None, human, run)
    }

    /// [`Move::apply`], given `walk`'s marks for the move's radius when the caller has
    /// them: the rebuilt stretch's context is then those marks less the steps the move
    /// removes, instead of every other step of the walk marked again.
    fn apply_marked(
        &self,
        p: &Problem,
        walk: &[usize],
        marks: Option<&Marks>,
        human: bool,
        run: &Run,
    ) -> Vec<usize> {
        if let Some((a, b)) = self.reverse {
            let mut w = walk.to_vec();
            w[a..=b].reverse();
            return w;
        }
        let mut marks = marks.cloned();
        let cut;
        let w = match self.cut {
            Some((a, b)) => {
                if let Some(m) = marks.as_mut() {
                    m.unwalk_all(&walk[a..=b]);
                }
                let mut w = walk[..=a].to_vec();
                w.extend_from_slice(&walk[b + 1..]);
                cut = w;
                &cut
            }
            None => walk,
        };
        if let Some(m) = marks.as_mut() {
            m.unwalk_all(&w[self.i..=self.j]);
        }
        let spec = Rebuild {
            i: self.i,
            j: self.j,
            radius: self.radius,
            human,
            seed: self.seed,
        };
        rebuild(p, w, &spec, marks, run)
    }
}

/// What [`rebuild`] rebuilds: the stretch `i..=j` of a walk, by a randomised spread leg of
/// novelty radius `radius` (its tie rule drawn from `seed`), avoiding reversals for a
/// person (`human`).
#[derive(Debug, Clone, Copy)]
struct Rebuild {
    i: usize,
    j: usize,
    radius: f64,
    human: bool,
    seed: u64,
}

/// A closed excursion of `walk`, `(a, b)` with `a < b - 1` and `walk[a] == walk[b]`,
/// drawn at random: from a random position, the next return to the same vertex within an
/// eighth of the walk (a third cut too much at once on the mall: -2% to -3% there), and
/// not where the cut would leave `x, v, x` (walking straight back). `None` when a few
/// draws find none.
fn excursion(walk: &[usize], rng: &mut ChaCha8Rng) -> Option<(usize, usize)> {
    let n = walk.len();
    if n < 4 {
        return None;
    }
    let reach = (n / 8).max(3);
    for _ in 0..8 {
        let a = rng.random_range(0..n - 2);
        let end = (a + reach).min(n - 1);
        if let Some(k) = walk[a + 2..=end].iter().position(|&v| v == walk[a]) {
            let b = a + 2 + k;
            // Not where the cut would join `x, v, x`: walking straight back.
            if a == 0 || b + 1 == n || walk[a - 1] != walk[b + 1] {
                return Some((a, b));
            }
        }
    }
    None
}

/// A closed sub-walk `walk[a..=b]` (`walk[a] == walk[b]`, `b >= a + 2`) whose reverse is
/// another walk, drawn at random (at most eight tries), for a move that walks it the
/// other way: the same edges and length, so the same coverage and budget, but a person's
/// samples (every 4.8 m) fall elsewhere inside it. Not one whose reverse walks straight
/// back at either end (`x, v, .., v, x` turned into a reversal at `v`).
fn closed_subwalk(walk: &[usize], rng: &mut ChaCha8Rng) -> Option<(usize, usize)> {
    let n = walk.len();
    if n < 4 {
        return None;
    }
    for _ in 0..8 {
        let a = rng.random_range(0..n - 2);
        let later: Vec<usize> = (a + 2..n).filter(|&b| walk[b] == walk[a]).collect();
        if later.is_empty() {
            continue;
        }
        let b = later[rng.random_range(0..later.len())];
        let palindrome = (0..=(b - a) / 2).all(|k| walk[a + k] == walk[b - k]);
        // After the reverse, `walk[a - 1]` is followed by `walk[a]` then `walk[b - 1]`,
        // and `walk[a + 1]` by `walk[b]` then `walk[b + 1]`.
        let turns_back =
            (a > 0 && walk[a - 1] == walk[b - 1]) || (b + 1 < n && walk[a + 1] == walk[b + 1]);
        if !palindrome && !turns_back {
            return Some((a, b));
        }
    }
    None
}

/// `walk` with its stretch `walk[spec.i..=spec.j]` rebuilt by a randomised spread leg
/// that counts the rest of the walk as walked and uses the budget left (its tie rule,
/// [`Leg::open_ties`], drawn from the seed). `marks`: the rest of the walk's marks for
/// the radius, when the caller has them.
fn rebuild(
    p: &Problem,
    walk: &[usize],
    spec: &Rebuild,
    marks: Option<Marks>,
    run: &Run,
) -> Vec<usize> {
    let &Rebuild {
        i,
        j,
        radius,
        human,
        seed,
    } = spec;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (head, tail) = (&walk[..=i], &walk[j..]);
    let fixed = p.length(head) + p.length(tail);
    let spec = Leg {
        from: walk[i],
        prev: i.checked_sub(1).map(|k| walk[k]),
        to: walk[j],
        budget: (p.budget - fixed).max(0.0),
        radius,
        any_fit: true,
        avoid_reversals: human,
        // Either tie rule, by a fair coin of the move's own seed.
        open_ties: seed & 1 == 1,
    };
    let mid = match marks {
        Some(m) => leg_marked(p, &spec, m, Some(&mut rng), run),
        None => {
            // The tail counts as walked too, joined to the head through a step that
            // marks the edge between them, if there is one.
            let mut context: Vec<usize> = head.to_vec();
            context.extend_from_slice(tail);
            leg(p, &spec, &context, Some(&mut rng), run)
        }
    };
    let mut out = head.to_vec();
    out.extend_from_slice(&mid[1..]);
    out.extend_from_slice(&tail[1..]);
    if human { unpace(p, &out) } else { out }
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::coverage::tests::{lattice, problem};
    use super::*;
    use crate::plan::Control;

    #[test]
    fn an_excursion_is_a_closed_loop_of_at_most_an_eighth_of_the_walk() {
        // Out and back along the lattice's rows, again and again: many vertices recur.
        let round = [0, 1, 2, 3, 2, 1, 0, 4, 8, 9, 5, 4, 0];
        let walk: Vec<usize> = round
            .iter()
            .cycle()
            .take(4 * round.len())
            .copied()
            .collect();
        let reach = (walk.len() / 8).max(3);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut found = 0;
        for _ in 0..200 {
            if let Some((a, b)) = excursion(&walk, &mut rng) {
                assert_eq!(walk[a], walk[b], "({a}, {b})");
                assert!(b >= a + 2 && b - a <= reach, "({a}, {b}), reach {reach}");
                // The cut never joins `x, v, x` (1 -> 2 -> 1 in `round` is one to avoid).
                assert!(
                    a == 0 || b + 1 == walk.len() || walk[a - 1] != walk[b + 1],
                    "({a}, {b}) leaves a reversal"
                );
                found += 1;
            }
        }
        assert!(found > 100, "{found} of 200 draws found an excursion");
        // A walk that never returns to a vertex has none.
        let simple = [0, 1, 2, 3, 7, 11, 10, 9, 8];
        assert_eq!(excursion(&simple, &mut rng), None);
    }

    /// The edges `w` walks, each as (lower, higher) vertex, sorted, with repeats.
    fn walked_edges(w: &[usize]) -> Vec<(usize, usize)> {
        let mut e: Vec<(usize, usize)> = w
            .windows(2)
            .map(|x| (x[0].min(x[1]), x[0].max(x[1])))
            .collect();
        e.sort_unstable();
        e
    }

    #[test]
    fn a_closed_subwalk_reversed_keeps_the_edges_and_adds_no_reversal() {
        let b = lattice();
        let p = problem(&b, 200.0);
        // Two laps of the lattice's outer ring with a visit down the middle column: `0`,
        // `1`, `5` and the ring's corners recur.
        let walk = [
            0, 1, 5, 9, 10, 11, 7, 3, 2, 1, 0, 4, 8, 9, 5, 1, 2, 3, 7, 11, 10, 9, 8, 4, 0,
        ];
        p.check(&walk).expect("feasible");
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut seen = std::collections::BTreeSet::new();
        for _ in 0..300 {
            let Some((a, b)) = closed_subwalk(&walk, &mut rng) else {
                continue;
            };
            assert!(walk[a] == walk[b] && b >= a + 2, "({a}, {b})");
            let m = Move {
                reverse: Some((a, b)),
                ..Move::default()
            };
            let w = m.apply(&p, &walk, true, &Run::new(Control::new(), None));
            assert_ne!(w.as_slice(), walk.as_slice(), "({a}, {b}) is a palindrome");
            p.check(&w).expect("feasible");
            assert_eq!(walked_edges(&w), walked_edges(&walk), "({a}, {b})");
            assert!(
                reversals(&p, &w) <= reversals(&p, &walk),
                "({a}, {b}): {w:?}"
            );
            seen.insert((a, b));
        }
        assert!(
            seen.len() > 10,
            "only {} distinct reversals drawn",
            seen.len()
        );
        // A walk that never returns to a vertex has no closed sub-walk.
        assert_eq!(closed_subwalk(&[0, 1, 2, 3, 7, 11], &mut rng), None);
    }

    #[test]
    fn a_kick_rebuilds_a_third_to_three_fifths_of_the_walk_inside_it() {
        let radii = [0.0, 1.0, 2.0];
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for n in [4usize, 9, 50, 301] {
            for _ in 0..200 {
                let m = kick(n, &radii, &mut rng);
                let span = m.j - m.i;
                assert!(m.cut.is_none() && m.j < n, "{m:?} of {n}");
                assert!(
                    span >= (0.3 * n as f64).ceil() as usize && span < n,
                    "{m:?}"
                );
                assert!(span <= (0.6 * n as f64).ceil() as usize, "{m:?} of {n}");
                assert!(radii.contains(&m.radius));
            }
        }
    }

    #[test]
    fn a_converged_search_kicks_and_still_returns_the_best_walk_it_offered() {
        // The lattice at 16 m: a walk of about ten vertices, thousands of batches in a
        // second, so the search converges and kicks.
        let b = lattice();
        let p = problem(&b, 16.0);
        let run = Run::new(Control::new(), Some(Duration::from_millis(1500)));
        let (out, stats) = plan_large(&p, &run, 5).expect("plan");
        assert!(stats.kicks > 0, "{stats:?}");
        // Converged, most candidates are walks scored before: they keep their scores.
        assert!(stats.known > stats.exact_evals, "{stats:?}");
        p.check(&out.walk).expect("feasible");
        let (_, best) = run.incumbent().expect("offered walks");
        assert!(
            out.utility >= best - 1e-12,
            "returned {} below the best offered {best}",
            out.utility
        );
        assert!((p.utility(&out.walk).expect("utility") - out.utility).abs() < 1e-9);
    }

    #[test]
    fn seen_keeps_one_score_per_walk_until_cleared() {
        let mut seen = Seen::default();
        let (a, b) = (vec![0, 1, 2, 1, 0], vec![0, 1, 2, 3, 0]);
        seen.insert(&a, 3.5, Some(3.6));
        seen.insert(&b, 2.0, None);
        assert_eq!(seen.get(&a), Some((3.5, Some(3.6))));
        assert_eq!(seen.get(&b), Some((2.0, None)));
        assert_eq!(seen.get(&[0, 1, 2, 1]), None);
        assert_eq!(seen.get(&[0, 3, 2, 1, 0]), None);
        seen.insert(&a, 4.0, None);
        assert_eq!(seen.get(&a), Some((4.0, None)));
        seen.clear();
        assert_eq!(seen.get(&a), None);
    }

    #[test]
    fn a_move_that_cuts_an_excursion_spends_its_budget_where_it_rebuilds() {
        let b = lattice();
        // Two visits from vertex 0: along row 0 and back, then up column 0 and back
        // (16 m of the 16 m budget).
        let walk = vec![0, 1, 2, 1, 0, 4, 8, 4, 0];
        let p = problem(&b, 16.0);
        assert!((p.length(&walk) - 16.0).abs() < 1e-9);
        let run = Run::new(Control::new(), None);
        let distinct = |w: &[usize]| {
            let mut e = walked_edges(w);
            e.dedup();
            e.len()
        };
        assert_eq!(distinct(&walk), 4);
        // Without a cut, the stretch 1 -> 2 -> 1 is rebuilt within its own 4 m: the
        // second visit stays as it was.
        let plain = Move {
            cut: None,
            i: 1,
            j: 3,
            radius: 0.0,
            seed: 3,
            reverse: None,
        };
        let kept = plain.apply(&p, &walk, false, &run);
        p.check(&kept).expect("feasible");
        assert!(kept.ends_with(&[0, 4, 8, 4, 0]), "{kept:?}");
        // Cutting the first visit ([0, 1, 2, 1, 0]) frees 8 m, and the rebuilt stretch of
        // what remains (4 -> 8 -> 4) spends them on edges not walked before.
        let cutting = Move {
            cut: Some((0, 4)),
            ..plain
        };
        let cut = cutting.apply(&p, &walk, false, &run);
        p.check(&cut).expect("feasible");
        assert_eq!((cut[0], *cut.last().expect("walk")), (0, 0));
        assert!(
            p.length(&cut) > 16.0 - 2.0 - 1e-9,
            "{cut:?} is {} m",
            p.length(&cut)
        );
        assert!(distinct(&cut) > 4, "{cut:?}");
    }

    /// A 10 x 10 grid of corridors 4 m apart (100 vertices, 720 m of edges), pilot data
    /// at two corners.
    fn grid() -> std::sync::Arc<crate::building::Building> {
        let mut v = Vec::new();
        let mut e = Vec::new();
        for r in 0..10 {
            for c in 0..10 {
                v.push(format!(
                    r#"{{"id":"g{r}-{c}","x":{},"y":{}}}"#,
                    4 * c,
                    4 * r
                ));
                if c > 0 {
                    e.push(format!(r#"{{"a":"g{r}-{}","b":"g{r}-{c}"}}"#, c - 1));
                }
                if r > 0 {
                    e.push(format!(r#"{{"a":"g{}-{c}","b":"g{r}-{c}"}}"#, r - 1));
                }
            }
        }
        let text = format!(
            r#"{{"format":"survey-building/1","name":"grid","vertices":[{}],"edges":[{}],
               "pilot":[{{"x":0,"y":0,"rss":{{"a":-50}}}},{{"x":36,"y":36,"rss":{{"a":-70}}}}]}}"#,
            v.join(","),
            e.join(",")
        );
        std::sync::Arc::new(crate::building::Building::from_json(&text, "grid").expect("valid"))
    }

    pub(in crate::plan) fn grid_problem(budget: f64) -> Problem {
        let k = crate::gp::Kernel {
            sf2: 10.0,
            ell: 6.0,
            sn2: 0.5,
        };
        Problem::new(grid(), k, Surveyor::robot(), 0, 0, budget).expect("problem")
    }

    /// A cost model under which an evaluation of `work` multiply-adds takes `secs`.
    pub(in crate::plan) fn cost_of(secs: f64, work: f64) -> ExactCost {
        ExactCost {
            fixed: 0.0,
            per_work: secs / work,
        }
    }

    #[test]
    fn the_exact_time_is_estimated_only_where_it_may_be_dear() {
        let p = grid_problem(300.0);
        let run = Run::new(Control::new(), None);
        let walk = leg(&p, &whole_walk(&p), &[], None, &run);
        // About 700 rows (600 samples and 100 vertices): 5.7e7 multiply-adds, cheap on
        // any device beside a minute, worth timing beside 0.1 s.
        let work = p.engine.utility_work(&walk).expect("work");
        assert!(
            work > 1e7 && work < 60.0 * CHEAP_WORK_PER_SECOND,
            "{work:e}"
        );
        let never = exact_time_estimate(&p, &walk, Duration::from_secs(60)).expect("estimate");
        assert!(never.is_none(), "{never:?}");
        let (t, cost) = exact_time_estimate(&p, &walk, Duration::from_millis(100))
            .expect("estimate")
            .expect("timed");
        assert_eq!(cost.time(work), t);
        assert!(t > Duration::ZERO && t < Duration::from_secs(5), "{t:?}");
        // The work grows with the samples: a walk of half the budget is well under half.
        let half = grid_problem(150.0);
        let short = leg(&half, &whole_walk(&half), &[], None, &run);
        let w2 = p.engine.utility_work(&short).expect("work");
        assert!(w2 < 0.5 * work, "{w2:e} against {work:e}");
    }

    /// The cost model is timed on a problem's first dear walk and kept, for its clones
    /// too: another walk's estimate is that model's time for its work.
    #[test]
    fn the_exact_cost_is_timed_once_per_problem() {
        let p = grid_problem(300.0);
        let run = Run::new(Control::new(), None);
        let limit = Duration::from_millis(100);
        let walk = leg(&p, &whole_walk(&p), &[], None, &run);
        assert!(p.exact_cost.get().is_none());
        let (_, cost) = exact_time_estimate(&p, &walk, limit)
            .expect("estimate")
            .expect("timed");
        assert_eq!(p.exact_cost.get(), Some(&cost));
        let q = p.with_ends(0, 0, 250.0);
        let other = leg(&q, &whole_walk(&q), &[], None, &run);
        assert_ne!(other, walk);
        let work = q.engine.utility_work(&other).expect("work");
        let (t, kept) = exact_time_estimate(&q, &other, limit)
            .expect("estimate")
            .expect("dear");
        assert_eq!(kept, cost);
        assert_eq!(t, cost.time(work));
    }

    /// A plan whose final exact evaluation cannot end within the limit and its allowance
    /// is refused, naming the time it needs, a limit that would do and a budget whose
    /// walk the limit affords; one that can is not. The cost models are given (a device
    /// 1,000 times slower than any, and a free one), so the verdict does not depend on
    /// this machine.
    #[test]
    fn a_limit_that_cannot_hold_the_final_evaluation_is_refused_with_what_would_do() {
        let p = grid_problem(300.0);
        let run = Run::new(Control::new(), Some(Duration::from_secs(1)));
        let walk = leg(&p, &whole_walk(&p), &[], None, &run);
        let work = p.engine.utility_work(&walk).expect("work");
        let slow = ExactCost {
            fixed: 0.0,
            per_work: 5.0 / work,
        };
        let e = refuse_if_too_slow(&p, &run, &walk, slow.time(work), slow)
            .expect_err("5 s of evaluation under a 1 s limit");
        let Error::TimeLimitTooShort { needed, message } = e else {
            panic!("not a time refusal: {e}");
        };
        assert!(needed >= Duration::from_secs(5), "{needed:?}");
        let parts = [
            "\"grid\"",
            "budget 300.0 m",
            "limit of 1.0 s",
            "raise the time",
        ];
        for part in parts {
            assert!(message.contains(part), "{part:?} not in {message}");
        }
        // The budget named is a prefix of the walk whose evaluation takes a quarter of
        // the limit: here (work grows with the cube of the samples) well under 300 m.
        let named: f64 = message
            .rsplit("plan a budget of about ")
            .next()
            .and_then(|t| t.split(' ').next())
            .and_then(|n| n.parse().ok())
            .expect("a budget in the message");
        assert!(named > 10.0 && named < 200.0, "{named} m: {message}");
        let k = (1..walk.len())
            .take_while(|&k| p.length(&walk[..k]) <= named + 1e-9)
            .last()
            .expect("a prefix");
        let w = p.engine.utility_work(&walk[..k]).expect("work");
        assert!(
            slow.time(w) <= Duration::from_millis(250),
            "{:?}",
            slow.time(w)
        );
        // Within the allowance (max(10%, 0.2 s)), or free: no refusal.
        let tight = ExactCost {
            fixed: 0.0,
            per_work: 0.9 / work,
        };
        assert!(refuse_if_too_slow(&p, &run, &walk, tight.time(work), tight).is_ok());
        let free = ExactCost {
            fixed: 0.0,
            per_work: 0.0,
        };
        assert!(refuse_if_too_slow(&p, &run, &walk, Duration::ZERO, free).is_ok());
        // Without a time limit there is nothing to refuse.
        let unlimited = Run::new(Control::new(), None);
        assert!(refuse_if_too_slow(&p, &unlimited, &walk, slow.time(work), slow).is_ok());
    }

    #[test]
    fn the_cost_of_an_exact_evaluation_is_the_line_through_two_timings() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        // 60 ms fixed and 5e-11 s a multiply-add (huge-3k's figures): found again, and a
        // 4e9 evaluation costs 260 ms, not the 8 x 60 ms + ... of one prefix scaled.
        let c = ExactCost::through((1e8, 0.065), (1e9, 0.11));
        assert!(close(c.fixed, 0.06) && close(c.per_work, 5e-11), "{c:?}");
        assert!(close(c.time(4e9).as_secs_f64(), 0.26));
        // A first timing slowed (a negative fixed part, or a falling line): the larger
        // one's rate alone, so a larger evaluation is not underestimated.
        for small in [(1e8, 0.001), (1e8, 0.2)] {
            let c = ExactCost::through(small, (1e9, 0.11));
            assert_eq!(c.fixed, 0.0);
            assert!(close(c.per_work, 1.1e-10), "{c:?}");
        }
    }

    #[test]
    fn a_deferred_plan_evaluates_only_its_final_walk_and_reports_it_exactly() {
        // 50 ms: one exact evaluation of a 300 m robot walk here (about 700 rows) takes
        // far more than 1% of it on any device, so the finalists are deferred.
        let p = grid_problem(300.0);
        let run = Run::new(Control::new(), Some(Duration::from_millis(50)));
        let (out, stats) = plan_large(&p, &run, 2).expect("plan");
        assert!(stats.deferred, "{stats:?}");
        p.check(&out.walk).expect("feasible");
        assert!(
            p.length(&out.walk) >= 0.95 * 300.0,
            "{} m",
            p.length(&out.walk)
        );
        let exact = p.utility(&out.walk).expect("utility");
        assert!((exact - out.utility).abs() <= 1e-9 * exact);
        // The one walk offered is the one returned.
        let (w, u) = run.incumbent().expect("offered");
        assert_eq!(w, out.walk);
        assert_eq!(u, out.utility);
        // Without a time limit nothing depends on a clock: nothing is deferred.
        let (_, stats) = plan_large(&p, &Run::new(Control::new(), None), 2).expect("plan");
        assert!(!stats.deferred);
    }
}

//! `auto`, the default planner. On buildings of more than [`LARGE_VERTICES`] vertices it
//! runs the large-building search of [`super::scale`]; on smaller ones, a portfolio whose stages each start from the best walk
//! so far, sized by a deterministic work budget and capped by the time limit (2 s by
//! default).
//!
//! 0. **Spread constructions** ([`super::scale::best_construction`]): walks that use the
//!    whole budget, spread over the building, judged exactly and offered at once, so a
//!    plan stopped early (time limit on a busy phone, cancel) still returns a walk of the
//!    full budget.
//!    For a robot, also the large-building search of [`super::scale`] on its
//!    deterministic schedule of batches ([`super::scale::Schedule::Batches`]): on long
//!    walks of small floors it reaches walks the stages below do not.
//! 1. **Greedy**, the feasible-candidates variant of the paper's Algorithm 1 (the
//!    paper's rule stops as soon as the best-ratio vertex does not fit, which on a closed
//!    walk can be the very first round).
//! 2. **Local search** ([`LocalSearch`]) from the greedy walk, the spread walk and the
//!    large-building search's walk:
//!    detour insert, segment
//!    replace, re-route, shortcut and 2-opt moves, evaluated in parallel from the shared
//!    prefix.
//!    Then, on small buildings (at most [`SIMPLE_NODE_CAP`] nodes), the best *simple*
//!    walk (no vertex twice) by the branch and bound of [`Exact`] restricted to them.
//! 3. **Genetic** search with the paper's operators, its initial population seeded with
//!    the walks of stages 1 and 2 (so it can only improve on them). Its population is the
//!    request's (200) when the work budget allows, smaller on large instances.
//! 4. **Local search** from the best few distinct members of the final population.
//! 5. **Iterated local search**: kick the current walk with a few random moves, search
//!    locally again; the current walk may drift to slightly worse local optima and
//!    returns to the best after a few kicks without progress; until the work budget or
//!    the deadline is used up.
//! 6. **Exact** branch and bound seeded with the best walk when a quick count shows the
//!    search tree is small (at most [`EXACT_NODE_CAP`] nodes under the feasibility rule):
//!    if it finishes, the walk is proved optimal (`optimal: true`).
//!
//! Every stage's walk is judged by [`Problem::objective`]: the exact utility, less 1% of
//! it per reversal for a person (walking straight back along the edge just walked, not at
//! a dead end), the rule of the large-building search too; for a robot, the utility. The
//! local searches rank their moves by it; greedy, genetic and branch and bound rank by
//! utility (they are the paper's planners), and `auto` takes the best of their walks by
//! objective. A walk is reported `optimal` when branch and bound proves that no walk has
//! more utility than its objective (always for a robot; for a person, when it has no
//! reversal).
//!
//! The work budget counts walk evaluations weighted by their cost model
//! `(|D| + B/d)^2 |V|` (the engine's cost of a walk of full budget), scaled by the time
//! limit, so the same seed and time limit give the same walk unless the machine is too
//! slow for the limit (then `termination: time_limit`).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::exact::Exact;
use super::genetic::Genetic;
use super::greedy::Greedy;
use super::local_search::{LocalSearch, perturb};
use super::scale::Schedule;
use super::{Algorithm, Outcome, Params, Problem, Run, Solver, Termination, better};
use crate::Result;
use crate::samples::Surveyor;

/// Largest feasibility-pruned tree for which `auto` runs the exact search.
pub const EXACT_NODE_CAP: u64 = 200_000;

/// Largest simple-walk tree for which `auto` searches all simple walks.
pub const SIMPLE_NODE_CAP: u64 = 20_000;

/// Number of nodes of the simple-walk tree (no vertex twice, the end vertex only as the
/// last step) under the feasibility rule, counting up to `cap`.
pub fn count_simple(p: &Problem, cap: u64) -> u64 {
    fn rec(p: &Problem, v: usize, len: f64, on: &mut [bool], count: &mut u64, cap: u64) {
        *count += 1;
        if *count > cap || (v == p.end && len > 0.0) {
            return;
        }
        for &(w, e) in p.building.neighbours(v) {
            let l = len + p.building.edges[e].length;
            if p.fits(l + p.metric.dist(w, p.end)) && (w == p.end || !on[w]) {
                on[w] = true;
                rec(p, w, l, on, count, cap);
                on[w] = w == p.start;
                if *count > cap {
                    return;
                }
            }
        }
    }
    let mut on = vec![false; p.building.len()];
    on[p.start] = true;
    let mut count = 0;
    rec(p, p.start, 0.0, &mut on, &mut count, cap);
    count
}

/// Cost-model units of work per second of time limit, calibrated so that the default 2 s
/// suffice on a loaded two-core machine with the first engine (about 1.6e9 units per
/// second per thread). The dense whole-walk path (decision 0002) does about 1.5e10 on an
/// idle core, so `auto` now finishes well inside its limit here, and a phone several
/// times slower still does: the walk stays the same on both, which a larger figure would
/// not guarantee.
pub const UNITS_PER_SECOND: f64 = 2.5e9;

/// Buildings with more vertices than this take the large-building search of
/// [`super::scale`] (spread constructions, then a large-neighbourhood search on a
/// surrogate); smaller ones the staged portfolio above, which proves the paper's Area One
/// optimal.
pub const LARGE_VERTICES: usize = 100;

/// The `auto` solver.
#[derive(Debug, Clone)]
pub struct Auto {
    pub params: Params,
    pub seed: u64,
    /// Local-search restarts from other members of the genetic population.
    pub restarts: usize,
}

impl Auto {
    pub fn new(params: Params, seed: u64) -> Self {
        Auto {
            params,
            seed,
            restarts: 3,
        }
    }
}

/// Number of nodes of the walk tree under the feasibility rule alone, counting up to
/// `cap` (returns `cap + 1` if there are more).
pub fn count_nodes(p: &Problem, cap: u64) -> u64 {
    fn rec(p: &Problem, v: usize, len: f64, count: &mut u64, cap: u64) {
        *count += 1;
        if *count > cap {
            return;
        }
        for &(w, e) in p.building.neighbours(v) {
            let l = len + p.building.edges[e].length;
            if p.fits(l + p.metric.dist(w, p.end)) {
                rec(p, w, l, count, cap);
                if *count > cap {
                    return;
                }
            }
        }
    }
    let mut count = 0;
    rec(p, p.start, 0.0, &mut count, cap);
    count
}

/// Most walk evaluations `auto` spends, however long its time limit: beyond this the
/// iterated local search has long converged on the buildings we know.
pub const MAX_EVALS: usize = 20_000;

/// Cost-model units of one evaluation of a walk of full budget: `(|D| + B/d)^2 |V|`
/// plus a fixed overhead for generating and bookkeeping the move.
pub fn eval_units(p: &Problem) -> f64 {
    let n = p.building.pilot.len() as f64 + p.budget / p.engine.model().spacing() + 1.0;
    n * n * p.building.len() as f64 + 20_000.0
}

impl Solver for Auto {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Auto
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        if p.building.len() > LARGE_VERTICES {
            return super::scale::plan_large(p, run, self.seed).map(|(o, _)| o);
        }
        // From the configured limit, not the time left, so that the work is deterministic.
        let secs = run.time_limit().map_or(2.0, |d| d.as_secs_f64());
        // Evaluations the work budget allows.
        let budget_evals =
            (secs * UNITS_PER_SECOND / eval_units(p)).clamp(50.0, MAX_EVALS as f64) as usize;
        let mut used = 0usize;
        let report = |f: f64, u: f64, m: &str| run.report(Algorithm::Auto, f, Some(u), m.into());
        // Every stage's walk is judged by `Problem::objective`: the utility, less a share
        // per reversal for a person, whose walks must not pace back and forth (the
        // bundled demo building, person, 120 m: 14 reversals in 116 m when judged by the
        // utility alone). For a robot that is the utility.
        let wins = |a: (&[usize], f64), b: (&[usize], f64)| {
            better((a.0, p.objective(a.0, a.1)), (b.0, p.objective(b.0, b.1)))
        };

        // 0. Spread constructions that use the whole budget, evaluated exactly and
        //    offered at once: what a time-out or a cancel returns if greedy (which grows
        //    its walk from the start outwards) is cut short on a busy phone.
        let (spread, spread_u) = super::scale::best_construction(p, run, &[0.0, 0.25, 0.5])?;
        used += 3;
        report(0.05, spread_u, "spread construction");

        // 0b. For a robot, the large-building search on its deterministic schedule of
        //     batches (a few tens of milliseconds here): it finds walks that greedy and
        //     local search do not reach (a robot on all 158 m of a 77-vertex tree-shaped
        //     floor: 61.7 nats against the portfolio's 59.8 without it). A person's
        //     walks (a sample every 4.8 m) gained and lost alike from it.
        let robot = matches!(p.engine.model(), Surveyor::Robot { .. });
        let (large, large_u) = if !robot {
            (spread.clone(), spread_u)
        } else {
            let (o, st) = super::scale::plan_large_with(p, run, self.seed, Schedule::Batches)?;
            // Its surrogate evaluations in exact ones by the two cost models (whole ones:
            // most are cheaper, scored near a move's stretch only).
            let per = super::scale::surrogate_units(p) / eval_units(p);
            used += (st.surrogate_evals as f64 * per).ceil() as usize + st.exact_evals;
            (o.walk, o.utility)
        };
        report(0.08, spread_u.max(large_u), "large-neighbourhood search");

        // 1. Greedy.
        let g = Greedy::feasible().solve(p, run)?;
        let (mut walk, mut util) = (g.walk, g.utility);
        used += p.building.len() * 4;
        report(0.1, util.max(spread_u), "greedy");

        // 2. Local search from the greedy walk, then from the spread walk (a different
        //    basin: it reaches the far side of the building from the first step).
        let (w, u, n) = LocalSearch::new(self.seed).by_objective().improve_counted(
            p,
            run,
            walk.clone(),
            util,
        )?;
        used += n;
        let greedy_walk = walk.clone();
        if wins((&w, u), (&walk, util)) {
            walk = w;
            util = u;
        }
        let mut from_spread = vec![(spread.clone(), spread_u), (large.clone(), large_u)];
        if spread != greedy_walk && !run.should_stop() {
            let ls = LocalSearch::new(self.seed ^ 0x5eed_5eed).by_objective();
            let (w, u, n) = ls.improve_counted(p, run, spread, spread_u)?;
            used += n;
            from_spread.push((w, u));
        }
        if large != greedy_walk && !run.should_stop() {
            let ls = LocalSearch::new(self.seed ^ 0x1a29_e5ea).by_objective();
            let (w, u, n) = ls.improve_counted(p, run, large, large_u)?;
            used += n;
            from_spread.push((w, u));
        }
        // The spread walk competes even when the time is up (a greedy walk cut short
        // by the limit is a stub near the start).
        for (w, u) in from_spread {
            if wins((&w, u), (&walk, util)) {
                walk = w;
                util = u;
            }
        }
        report(0.2, util, "local search");

        // 2b. Best simple walk, when there are few (small buildings).
        if !run.should_stop() && count_simple(p, SIMPLE_NODE_CAP) <= SIMPLE_NODE_CAP {
            let ex = Exact::simple_walks(SIMPLE_NODE_CAP * 2)
                .with_incumbent(walk.clone())
                .solve(p, run)?;
            used += (SIMPLE_NODE_CAP / 8) as usize;
            if wins((&ex.walk, ex.utility), (&walk, util)) {
                walk = ex.walk;
                util = ex.utility;
            }
        }

        // 3. Genetic, seeded, sized to about 40% of the work budget.
        let mut pop = Vec::new();
        if !run.should_stop() {
            let mut prm = self.params;
            let gens = prm.generations.max(1);
            let afford = (budget_evals as f64 * 0.4 / (gens + 1) as f64) as usize;
            prm.population = prm.population.min(afford).max(20);
            let ga = Genetic::new(prm, self.seed).with_seeds(vec![walk.clone(), greedy_walk]);
            let (pp, _) = ga.evolve(p, run)?;
            used += prm.population * (gens + 1);
            // The population is ranked by utility; `auto` takes its best by objective.
            let best = pp
                .iter()
                .fold(None::<&super::genetic::Individual>, |a, b| match a {
                    Some(a) if !wins((&b.walk, b.utility), (&a.walk, a.utility)) => Some(a),
                    _ => Some(b),
                });
            if let Some(b) = best
                && wins((&b.walk, b.utility), (&walk, util))
            {
                walk = b.walk.clone();
                util = b.utility;
            }
            pop = pp;
            report(0.5, util, "genetic");
        }

        // 4. Local search from the best distinct members of the population.
        for (k, ind) in pop.iter().take(self.restarts).enumerate() {
            if run.should_stop() || used >= budget_evals {
                break;
            }
            let ls = LocalSearch::new(self.seed.wrapping_add(k as u64 + 1)).by_objective();
            let (w, u, n) = ls.improve_counted(p, run, ind.walk.clone(), ind.utility)?;
            used += n;
            if wins((&w, u), (&walk, util)) {
                walk = w;
                util = u;
            }
        }
        report(0.7, util, "restarts");

        // 5. Iterated local search: kicks of 2 to 5 random moves; the current walk may
        //    drift to a local optimum up to 0.3% worse; back to the best after 8 kicks
        //    without a new best.
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ 0x9e37_79b9_7f4a_7c15);
        let (mut cur, mut cur_s) = (walk.clone(), p.objective(&walk, util));
        let mut kick = 0u64;
        let mut stale = 0;
        while used < budget_evals && !run.should_stop() {
            kick += 1;
            let start = perturb(p, &cur, 2 + (kick % 4) as usize, &mut rng);
            let su = p.utility(&start)?;
            let ls = LocalSearch::new(self.seed.wrapping_add(1000 + kick)).by_objective();
            let (w, u, n) = ls.improve_counted(p, run, start, su)?;
            used += n + 1;
            stale += 1;
            if wins((&w, u), (&walk, util)) {
                walk = w.clone();
                util = u;
                stale = 0;
            }
            if p.objective(&w, u) >= cur_s - 0.003 * cur_s.abs() {
                cur_s = p.objective(&w, u);
                cur = w;
            }
            if stale >= 8 {
                cur = walk.clone();
                cur_s = p.objective(&walk, util);
                stale = 0;
            }
        }
        report(0.9, util, "iterated local search");
        run.check()?;

        // 6. Exact, when the tree is small.
        let mut out = Outcome::new(walk.clone(), util, Termination::Completed);
        if !run.should_stop() && count_nodes(p, EXACT_NODE_CAP) <= EXACT_NODE_CAP {
            let ex = Exact::new().with_incumbent(walk.clone()).solve(p, run)?;
            let proved = ex.optimal == Some(true);
            let best_u = ex.utility;
            if wins((&ex.walk, ex.utility), (&walk, util)) {
                out.walk = ex.walk;
                out.utility = ex.utility;
            }
            // Branch and bound proves the most utility any walk has. The walk returned is
            // optimal by objective too when its objective reaches that (a robot's always
            // does; a person's when it has no reversal, as every other walk's objective
            // is at most its utility).
            if proved && p.objective(&out.walk, out.utility) >= best_u * (1.0 - 1e-9) {
                out.optimal = Some(true);
                out.nodes = ex.nodes;
            }
        }
        if run.out_of_time() && out.optimal != Some(true) {
            out.termination = Termination::TimeLimit;
        }
        report(1.0, out.utility, "done");
        Ok(out)
    }
}

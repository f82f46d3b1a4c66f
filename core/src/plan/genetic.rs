//! The paper's genetic planner (Wei, Frincu, Zheng, section IV-B).
//!
//! * **Initial walks**: a random walk from `v_s` over half the budget (never stepping
//!   where `v_t` could no longer be reached), then the shortest path to `v_t`, then the
//!   unvisited vertices in random order, each inserted at its cheapest position (as a
//!   detour along shortest paths) while the budget allows.
//! * **Selection**: tournaments of size `k`.
//! * **Crossover**: single point, at a random vertex common to both parents other than
//!   the ends (a random occurrence in each); the two tails are swapped. Offspring over the
//!   budget die; parents without a common vertex have no offspring.
//! * **Mutation** ("local extension"), with probability `mutation`: between two adjacent
//!   intermediate vertices `a`, `b` insert a common neighbour, else go through a neighbour
//!   of each (joined by a shortest path if they are not adjacent). Only a feasible result
//!   replaces the offspring.
//! * **Replacement**: parents and offspring are merged, duplicates dropped, the best
//!   `population` kept.
//!
//! Fitness is evaluated in parallel (rayon) and memoised: a walk is never evaluated twice.
//! Paper defaults: population 200, tournament 10, mutation 0.9, 5 generations.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::scale::{ExactCost, exact_time_estimate};
use super::{Algorithm, Outcome, Params, Problem, Run, Solver, Termination, better};
use crate::Result;

/// The genetic solver.
#[derive(Debug, Clone)]
pub struct Genetic {
    pub params: Params,
    pub seed: u64,
    /// Walks put in the initial population before the random ones (for example the greedy
    /// walk, in `auto`). Infeasible ones are ignored.
    pub seeds: Vec<Vec<usize>>,
}

/// A member of the population.
#[derive(Debug, Clone)]
pub struct Individual {
    pub walk: Vec<usize>,
    pub length: f64,
    pub utility: f64,
}

impl Genetic {
    pub fn new(params: Params, seed: u64) -> Self {
        Genetic {
            params,
            seed,
            seeds: Vec::new(),
        }
    }

    /// Adds walks to the initial population.
    pub fn with_seeds(mut self, seeds: Vec<Vec<usize>>) -> Self {
        self.seeds = seeds;
        self
    }
}

/// Random initial walk of the paper.
pub fn random_walk(p: &Problem, rng: &mut ChaCha8Rng) -> Vec<usize> {
    random_walk_until(p, rng, &|| false).expect("never stopped")
}

/// Vertices inserted between two calls of `stop` in [`random_walk_until`].
const INSERTS_PER_CHECK: usize = 32;

/// [`random_walk`], given up (`None`) when `stop` says so, asked before the first and
/// then every [`INSERTS_PER_CHECK`] vertices to insert. Inserting every vertex at its cheapest
/// position scans the walk for each: on a building of thousands of vertices one walk
/// takes a large part of a second (sweep 81's 3,138-vertex floor, person on 2,092 m),
/// and genetic, which asked for the time only between walks, returned 0.05 to 0.34 s
/// past a 2 s limit there. The generator draws the same numbers as [`random_walk`]
/// until the walk is given up.
pub fn random_walk_until(
    p: &Problem,
    rng: &mut ChaCha8Rng,
    stop: &dyn Fn() -> bool,
) -> Option<Vec<usize>> {
    let b = &p.building;
    let m = &p.metric;
    let half = p.budget / 2.0;
    let mut walk = vec![p.start];
    let mut len = 0.0;
    let mut opts: Vec<(usize, f64)> = Vec::new();
    while len < half {
        let v = *walk.last().unwrap_or(&p.start);
        let Some((w, l)) = p.random_step(v, rng, &mut opts, |w, l| {
            len + l <= half + super::BUDGET_EPS && p.fits(len + l + m.dist(w, p.end))
        }) else {
            break;
        };
        walk.push(w);
        len += l;
    }
    m.extend_path(&mut walk, p.end);
    let mut len = p.length(&walk);
    // Insert the unvisited vertices in random order at their cheapest position.
    let n = b.len();
    let mut on = vec![false; n];
    for &v in &walk {
        on[v] = true;
    }
    let mut rest: Vec<usize> = (0..n).filter(|&v| !on[v]).collect();
    // Fisher-Yates with the seeded generator.
    for i in (1..rest.len()).rev() {
        let j = rng.random_range(0..=i);
        rest.swap(i, j);
    }
    for (k, v) in rest.into_iter().enumerate() {
        if k % INSERTS_PER_CHECK == 0 && stop() {
            return None;
        }
        if on[v] {
            continue;
        }
        if let Some((w, l)) = insert_detour(p, &walk, len, v) {
            for &x in &w {
                on[x] = true;
            }
            walk = w;
            len = l;
        }
    }
    Some(walk)
}

/// `walk` with a detour through `v` at its cheapest position, if that fits the budget.
pub fn insert_detour(p: &Problem, walk: &[usize], len: f64, v: usize) -> Option<(Vec<usize>, f64)> {
    let m = &p.metric;
    let b = &p.building;
    let mut best = (f64::INFINITY, 0);
    for i in 0..walk.len().saturating_sub(1) {
        let el = b
            .edge_between(walk[i], walk[i + 1])
            .map_or(0.0, |e| e.length);
        let c = m.dist(walk[i], v) + m.dist(v, walk[i + 1]) - el;
        if c < best.0 {
            best = (c, i);
        }
    }
    if walk.len() == 1 {
        best = (m.dist(walk[0], v) * 2.0, 0);
    }
    if !best.0.is_finite() || !p.fits(len + best.0) {
        return None;
    }
    let i = best.1;
    let mut w: Vec<usize> = walk[..=i].to_vec();
    m.extend_path(&mut w, v);
    let back = if walk.len() == 1 {
        walk[0]
    } else {
        walk[i + 1]
    };
    m.extend_path(&mut w, back);
    if walk.len() > 1 {
        w.extend_from_slice(&walk[i + 2..]);
    }
    let l = p.length(&w);
    p.fits(l).then_some((w, l))
}

/// Single-point crossover at a random common intermediate vertex; `None` when there is
/// none. Offspring are returned whether or not they fit.
pub fn crossover(
    a: &[usize],
    b: &[usize],
    rng: &mut ChaCha8Rng,
) -> Option<(Vec<usize>, Vec<usize>)> {
    if a.len() < 3 || b.len() < 3 {
        return None;
    }
    let inner_b = &b[1..b.len() - 1];
    let mut common: Vec<usize> = a[1..a.len() - 1]
        .iter()
        .copied()
        .filter(|v| inner_b.contains(v))
        .collect();
    common.sort_unstable();
    common.dedup();
    if common.is_empty() {
        return None;
    }
    let v = common[rng.random_range(0..common.len())];
    let pos = |w: &[usize], rng: &mut ChaCha8Rng| {
        let occ: Vec<usize> = (1..w.len() - 1).filter(|&i| w[i] == v).collect();
        occ[rng.random_range(0..occ.len())]
    };
    let i = pos(a, rng);
    let j = pos(b, rng);
    let mut c1 = a[..i].to_vec();
    c1.extend_from_slice(&b[j..]);
    let mut c2 = b[..j].to_vec();
    c2.extend_from_slice(&a[i..]);
    Some((c1, c2))
}

/// The paper's "local extension" mutation; `None` if the walk is too short or the result
/// does not fit.
pub fn mutate(p: &Problem, walk: &[usize], rng: &mut ChaCha8Rng) -> Option<Vec<usize>> {
    if walk.len() < 4 {
        return None;
    }
    let b = &p.building;
    // a = walk[i], c = walk[i + 1], both intermediate: 1 <= i, i + 1 <= len - 2.
    let i = rng.random_range(1..walk.len() - 2);
    let (x, y) = (walk[i], walk[i + 1]);
    let nx: Vec<usize> = b.neighbours(x).iter().map(|&(w, _)| w).collect();
    let ny: Vec<usize> = b.neighbours(y).iter().map(|&(w, _)| w).collect();
    let common: Vec<usize> = nx
        .iter()
        .copied()
        .filter(|w| *w != x && *w != y && ny.contains(w))
        .collect();
    let mut out: Vec<usize> = walk[..=i].to_vec();
    if !common.is_empty() {
        out.push(common[rng.random_range(0..common.len())]);
    } else {
        let ax: Vec<usize> = nx.into_iter().filter(|&w| w != y).collect();
        let ay: Vec<usize> = ny.into_iter().filter(|&w| w != x).collect();
        if ax.is_empty() || ay.is_empty() {
            return None;
        }
        let u = ax[rng.random_range(0..ax.len())];
        let v = ay[rng.random_range(0..ay.len())];
        out.push(u);
        p.metric.extend_path(&mut out, v);
    }
    out.extend_from_slice(&walk[i + 1..]);
    p.fits(p.length(&out)).then_some(out)
}

/// Memoised parallel fitness.
pub struct Fitness<'p> {
    p: &'p Problem,
    cache: HashMap<Vec<usize>, f64>,
    /// The most seconds per multiply-add of an evaluation so far
    /// ([`crate::utility::UtilityEngine::utility_work`]; 0 before the first): a walk whose
    /// evaluation would end past the deadline at that rate is not started. One evaluation
    /// of a long walk cannot be interrupted (0.7 s for a 2,036 m robot walk on the
    /// generated 565-vertex mall), and starting one just before the deadline overshot a
    /// 1 s limit by 0.33-0.42 s there. (f64 bits: for values that are not negative the
    /// bits order as the numbers do, so `fetch_max` keeps the largest; the walks of a
    /// chunk are evaluated in parallel.)
    rate: AtomicU64,
    /// What an evaluation is estimated to cost before the first one is timed
    /// ([`super::scale::exact_time_estimate`], set by [`Fitness::estimate`]): the first
    /// evaluation of a long walk would otherwise start whenever the deadline has not
    /// passed (mall robot 2,036 m, a 2 s limit: returned after 2.3-2.8 s).
    prior: Option<ExactCost>,
}

impl<'p> Fitness<'p> {
    pub fn new(p: &'p Problem) -> Self {
        Fitness {
            p,
            cache: HashMap::new(),
            rate: AtomicU64::new(0),
            prior: None,
        }
    }

    /// Estimates what evaluating the dearest of `walks` costs, when `run` has a time
    /// limit and that evaluation may be dear beside it, by timing two prefixes of it
    /// (about a quarter of its evaluation): until an evaluation has been timed, a walk is
    /// started only when that estimate ends before the deadline.
    pub fn estimate(&mut self, walks: &[Vec<usize>], run: &Run) -> Result<()> {
        let Some(limit) = run.time_limit() else {
            return Ok(());
        };
        let mut dearest: Option<(&Vec<usize>, f64)> = None;
        for w in walks {
            let work = self.p.engine.utility_work(w)?;
            if dearest.is_none_or(|(_, d)| work > d) {
                dearest = Some((w, work));
            }
        }
        if let Some((w, _)) = dearest
            && !run.should_stop()
        {
            self.prior = exact_time_estimate(self.p, w, limit)?.map(|(_, cost)| cost);
        }
        Ok(())
    }

    /// `f_D` of `w`, or `None` if `run` stops first or the
    /// evaluation would end past its deadline at [`Fitness::rate`].
    fn timed(&self, w: &[usize], run: &Run) -> Option<Result<f64>> {
        if run.should_stop() {
            return None;
        }
        let work = match self.p.engine.utility_work(w) {
            Ok(x) => x.max(1.0),
            Err(e) => return Some(Err(e)),
        };
        let t0 = Instant::now();
        let rate = f64::from_bits(self.rate.load(Ordering::Relaxed));
        let secs = match self.prior {
            Some(cost) if rate == 0.0 => cost.time(work),
            _ => Duration::from_secs_f64(rate * work),
        };
        if let Some(deadline) = run.deadline()
            && t0 + secs > deadline
        {
            return None;
        }
        Some(self.p.utility(w).inspect(|_| {
            let secs = t0.elapsed().as_secs_f64();
            self.rate
                .fetch_max((secs / work).to_bits(), Ordering::Relaxed);
        }))
    }

    /// Number of distinct walks evaluated.
    pub fn evaluations(&self) -> usize {
        self.cache.len()
    }

    /// Evaluates every walk (in parallel chunks, checking for cancellation between them).
    /// Returns `None` for the walks skipped because time ran out.
    pub fn eval(&mut self, walks: &[Vec<usize>], run: &Run) -> Result<Vec<Option<f64>>> {
        let mut todo: Vec<&Vec<usize>> = walks
            .iter()
            .filter(|w| !self.cache.contains_key(*w))
            .collect();
        todo.sort_unstable();
        todo.dedup();
        // Chunks of two walks per thread, and every walk checks for a stop before it is
        // evaluated: on a large building one walk costs tens of milliseconds, and where the
        // thread pool is larger than the cores a process really gets (a CPU quota), a whole
        // chunk can take far longer than its walks' sum. So a cancel waits for at most the
        // one walk each thread is evaluating.
        let chunk_len = (2 * rayon::current_num_threads()).max(2);
        for chunk in todo.chunks(chunk_len) {
            run.check()?;
            if run.out_of_time() {
                break;
            }
            let us: Vec<Option<Result<f64>>> =
                chunk.par_iter().map(|w| self.timed(w, run)).collect();
            for (w, u) in chunk.iter().zip(us) {
                if let Some(u) = u {
                    self.cache.insert((*w).clone(), u?);
                }
            }
        }
        run.check()?;
        Ok(walks.iter().map(|w| self.cache.get(w).copied()).collect())
    }
}

fn tournament<'a>(pop: &'a [Individual], k: usize, rng: &mut ChaCha8Rng) -> &'a Individual {
    let mut best = &pop[rng.random_range(0..pop.len())];
    for _ in 1..k {
        let c = &pop[rng.random_range(0..pop.len())];
        if better((&c.walk, c.utility), (&best.walk, best.utility)) {
            best = c;
        }
    }
    best
}

/// Sorts best first, drops duplicate walks, keeps `size`.
fn select(mut pop: Vec<Individual>, size: usize) -> Vec<Individual> {
    pop.sort_by(|a, b| {
        if better((&a.walk, a.utility), (&b.walk, b.utility)) {
            std::cmp::Ordering::Less
        } else if better((&b.walk, b.utility), (&a.walk, a.utility)) {
            std::cmp::Ordering::Greater
        } else {
            std::cmp::Ordering::Equal
        }
    });
    pop.dedup_by(|a, b| a.walk == b.walk);
    pop.truncate(size);
    pop
}

impl Genetic {
    /// Runs the algorithm and returns the final population, best first.
    pub fn evolve(&self, p: &Problem, run: &Run) -> Result<(Vec<Individual>, Termination)> {
        let prm = &self.params;
        let size = prm.population.max(2);
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut fit = Fitness::new(p);
        let mut walks: Vec<Vec<usize>> = self
            .seeds
            .iter()
            .filter(|w| p.check(w).is_ok())
            .cloned()
            .collect();
        let mut attempts = 0;
        // What an evaluation costs, before the population is drawn (a second on a large
        // building: mall robot 2,036 m, 200 random walks in 1.0 s), so that a 2 s limit
        // does not see its last half second spent estimating: from the seeds, else from
        // the first random walk.
        let stop = || run.should_stop();
        if walks.is_empty() {
            attempts += 1;
            walks.extend(random_walk_until(p, &mut rng, &stop));
        }
        fit.estimate(&walks, run)?;
        while walks.len() < size && attempts < size * 4 {
            attempts += 1;
            // A random walk inserts every vertex at its cheapest position, a large part
            // of a second on thousands of vertices: it asks for the time as it inserts.
            let Some(w) = random_walk_until(p, &mut rng, &stop) else {
                break;
            };
            if !walks.contains(&w) {
                walks.push(w);
            }
        }
        if walks.is_empty() {
            walks.push(p.shortest_walk());
        }
        let us = fit.eval(&walks, run)?;
        let mut pop: Vec<Individual> = walks
            .into_iter()
            .zip(us)
            .filter_map(|(w, u)| {
                u.map(|u| Individual {
                    length: p.length(&w),
                    walk: w,
                    utility: u,
                })
            })
            .collect();
        if pop.is_empty() {
            // Out of time before a single evaluation: fall back to the shortest walk.
            let w = p.shortest_walk();
            let u = p.utility(&w)?;
            return Ok((
                vec![Individual {
                    length: p.length(&w),
                    walk: w,
                    utility: u,
                }],
                Termination::TimeLimit,
            ));
        }
        pop = select(pop, size);
        for g in 0..prm.generations {
            run.check()?;
            if run.out_of_time() {
                return Ok((pop, Termination::TimeLimit));
            }
            let mut kids: Vec<Vec<usize>> = Vec::with_capacity(size);
            let mut tries = 0;
            while kids.len() < size && tries < size * 4 {
                tries += 1;
                if tries % 4 == 0 && run.should_stop() {
                    break;
                }
                let a = tournament(&pop, prm.tournament, &mut rng);
                let b = tournament(&pop, prm.tournament, &mut rng);
                let Some((c1, c2)) = crossover(&a.walk, &b.walk, &mut rng) else {
                    continue;
                };
                for c in [c1, c2] {
                    if !p.fits(p.length(&c)) {
                        continue;
                    }
                    let c = if rng.random_bool(prm.mutation) {
                        mutate(p, &c, &mut rng).unwrap_or(c)
                    } else {
                        c
                    };
                    kids.push(c);
                }
            }
            let us = fit.eval(&kids, run)?;
            for (w, u) in kids.into_iter().zip(us) {
                if let Some(u) = u {
                    pop.push(Individual {
                        length: p.length(&w),
                        walk: w,
                        utility: u,
                    });
                }
            }
            pop = select(pop, size);
            p.offer(run, &pop[0].walk, pop[0].utility);
            run.report(
                Algorithm::Genetic,
                (g + 1) as f64 / prm.generations.max(1) as f64,
                Some(pop[0].utility),
                format!(
                    "generation {}/{}, {} walks evaluated",
                    g + 1,
                    prm.generations,
                    fit.evaluations()
                ),
            );
        }
        let term = if run.out_of_time() {
            Termination::TimeLimit
        } else {
            Termination::Completed
        };
        Ok((pop, term))
    }
}

impl Solver for Genetic {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Genetic
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        let (pop, term) = self.evolve(p, run)?;
        let best = &pop[0];
        Ok(Outcome::new(best.walk.clone(), best.utility, term))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::Control;
    use crate::plan::scale::tests::{cost_of, grid_problem};

    /// A random walk asked to stop is given up part way; one never asked is the walk
    /// [`random_walk`] draws from the same seed, and leaves the generator where it does.
    #[test]
    fn a_random_walk_is_given_up_when_asked_and_else_is_the_papers() {
        let p = grid_problem(300.0);
        let (mut a, mut b) = (ChaCha8Rng::seed_from_u64(3), ChaCha8Rng::seed_from_u64(3));
        let asked = std::cell::Cell::new(0);
        let never = || {
            asked.set(asked.get() + 1);
            false
        };
        assert_eq!(
            random_walk_until(&p, &mut a, &never),
            Some(random_walk(&p, &mut b))
        );
        assert!(asked.get() > 1, "asked {} times", asked.get());
        assert_eq!(a.random::<u64>(), b.random::<u64>());
        // Stop at the third question: the walk is not finished.
        let calls = std::cell::Cell::new(0);
        let third = || {
            calls.set(calls.get() + 1);
            calls.get() >= 3
        };
        assert_eq!(random_walk_until(&p, &mut a, &third), None);
        assert_eq!(calls.get(), 3);
    }

    /// Before any evaluation has been timed, a walk whose evaluation the cost estimate
    /// says ends past the deadline is not started (one of thousands of robot samples
    /// cannot be interrupted, and started just before a 2 s deadline it returned the
    /// plan 0.3 s late); one that fits is, and so is any without a time limit.
    #[test]
    fn an_evaluation_estimated_to_end_past_the_deadline_is_not_started() {
        let p = grid_problem(300.0);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let walk = random_walk(&p, &mut rng);
        let work = p.engine.utility_work(&walk).expect("work");
        let exact = p.utility(&walk).expect("utility");
        let walks = [walk];
        let limited = Run::new(Control::new(), Some(Duration::from_secs(1)));
        for (secs, run, started) in [
            (5.0, &limited, false),
            (1e-3, &limited, true),
            (5.0, &Run::new(Control::new(), None), true),
        ] {
            let mut fit = Fitness::new(&p);
            fit.prior = Some(cost_of(secs, work));
            let got = fit.eval(&walks, run).expect("eval");
            assert_eq!(got, [started.then_some(exact)], "{secs} s estimated");
            assert_eq!(fit.evaluations(), usize::from(started));
        }
    }
}

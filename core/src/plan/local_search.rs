//! Local search on a walk: randomised best-of-batch improvement.
//!
//! Moves (all along shortest paths of the metric closure, all kept within the budget):
//! * **detour insert**: visit a vertex between two consecutive vertices, at the position
//!   where it costs least (or at a random position);
//! * **segment replace** (remove + insert, a "swap"): cut the sub-walk between positions
//!   `i < j` and go from `W[i]` to `W[j]` through another vertex instead;
//! * **bulge move**: shortcut a sub-walk and spend the freed length on a detour
//!   elsewhere;
//! * **shortcut**: replace the sub-walk between `i < j` by a shortest path (frees budget
//!   for a later insert);
//! * **re-route**: replace the sub-walk between `i < j` by a random walk between the
//!   same two vertices that fits the budget slack;
//! * **2-opt**: reverse the sub-walk `W[i..=j]`, reconnecting its ends by shortest paths
//!   (changes the visiting order of the covered vertices).
//!
//! Each round draws a batch of feasible moves with the seeded generator, evaluates them in
//! parallel, and takes the best if it improves. Evaluations share the unchanged prefix of
//! the walk: the engine's state after every prefix is saved ([`WalkState::mark`]), so a
//! move only pays for the samples after its first change.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::{Problem, Run};
use crate::Result;
use crate::utility::{Mark, WalkState};

/// Local search settings.
#[derive(Debug, Clone, Copy)]
pub struct LocalSearch {
    pub seed: u64,
    /// Moves evaluated per round.
    pub batch: usize,
    /// Stop after this many rounds without improvement.
    pub patience: usize,
    /// Stop after this many rounds in all.
    pub max_rounds: usize,
    /// Rank walks by [`Problem::objective`] (a person's reversals cost a share of the
    /// utility) instead of the utility alone: `auto`'s rule. The baselines that use
    /// local search (branch and bound's first incumbent) rank by utility.
    pub objective: bool,
}

impl LocalSearch {
    pub fn new(seed: u64) -> Self {
        LocalSearch {
            seed,
            batch: 16,
            patience: 16,
            max_rounds: 10_000,
            objective: false,
        }
    }

    /// The same search ranking walks by [`Problem::objective`] (see
    /// [`objective`](Self::objective)).
    pub fn by_objective(mut self) -> Self {
        self.objective = true;
        self
    }
}

/// The engine state after every prefix of a walk.
struct Prefixes<'e> {
    full: WalkState<'e>,
    marks: Vec<Mark>,
}

impl<'e> Prefixes<'e> {
    fn new(p: &'e Problem, walk: &[usize]) -> Result<Self> {
        let mut st = p.engine.start(walk[0])?;
        let mut marks = Vec::with_capacity(walk.len());
        marks.push(st.mark());
        for &v in &walk[1..] {
            st.push(v)?;
            marks.push(st.mark());
        }
        Ok(Prefixes { full: st, marks })
    }

    /// Utility of `walk[..=keep]` followed by `rest`.
    fn eval(&self, keep: usize, rest: &[usize]) -> Result<f64> {
        let mut st = self.full.clone();
        st.rewind(&self.marks[keep]);
        for &v in rest {
            st.push(v)?;
        }
        st.utility()
    }
}

/// A candidate: the new walk and the index of the last unchanged vertex.
struct Move {
    walk: Vec<usize>,
    keep: usize,
}

fn splice(p: &Problem, w: &[usize], i: usize, via: &[usize], j: usize) -> Vec<usize> {
    // w[..=i] -> via... -> w[j] -> w[j+1..]
    let mut out = w[..=i].to_vec();
    for &v in via {
        p.metric.extend_path(&mut out, v);
    }
    p.metric.extend_path(&mut out, w[j]);
    out.extend_from_slice(&w[j + 1..]);
    out
}

/// A random vertex `v` such that going `w[i] -> v -> w[j]` instead of `w[i..=j]` fits
/// the budget and changes the walk.
fn reachable(p: &Problem, w: &[usize], i: usize, j: usize, rng: &mut ChaCha8Rng) -> Option<usize> {
    let m = &p.metric;
    let allowed = p.budget - p.length(w) + p.length(&w[i..=j]) + super::BUDGET_EPS;
    let cands: Vec<usize> = (0..p.building.len())
        .filter(|&v| m.dist(w[i], v) + m.dist(v, w[j]) <= allowed && !w[i..=j].contains(&v))
        .collect();
    if cands.is_empty() {
        None
    } else {
        Some(cands[rng.random_range(0..cands.len())])
    }
}

/// Draws one random move; `None` if it does not fit or changes nothing.
fn random_move(p: &Problem, w: &[usize], rng: &mut ChaCha8Rng) -> Option<Move> {
    random_move_at(p, w, rng, 0)
}

fn random_move_at(p: &Problem, w: &[usize], rng: &mut ChaCha8Rng, depth: usize) -> Option<Move> {
    let n = p.building.len();
    let len = w.len();
    let kind = rng.random_range(0..100u32);
    let new = if len < 2 || kind < 30 {
        // Cheapest-position detour through a random vertex.
        let v = rng.random_range(0..n);
        let (nw, _) = super::genetic::insert_detour(p, w, p.length(w), v)?;
        nw
    } else if kind < 40 {
        // Detour at a random position, through a vertex the slack can reach.
        let i = rng.random_range(0..len - 1);
        let v = reachable(p, w, i, i + 1, rng)?;
        splice(p, w, i, &[v], i + 1)
    } else if kind < 55 {
        // Move a bulge: shortcut the segment i..j, then spend the freed length on a
        // detour at another random position.
        let i = rng.random_range(0..len - 1);
        let j = (i + rng.random_range(2..=10usize)).min(len - 1);
        let cut = splice(p, w, i, &[], j);
        if cut.len() < 2 {
            return None;
        }
        if depth > 0 || rng.random_bool(0.5) {
            let k = rng.random_range(0..cut.len() - 1);
            let v = reachable(p, &cut, k, k + 1, rng)?;
            splice(p, &cut, k, &[v], k + 1)
        } else {
            // Or any other move on the shortened walk (a replace or re-route can now use
            // the freed length).
            random_move_at(p, &cut, rng, depth + 1)?.walk
        }
    } else if kind < 75 {
        // Replace the segment i..j by a detour through a vertex that fits.
        let i = rng.random_range(0..len - 1);
        let j = (i + rng.random_range(1..=8usize)).min(len - 1);
        let v = reachable(p, w, i, j, rng)?;
        splice(p, w, i, &[v], j)
    } else if kind < 82 {
        // Replace the segment i..j by a detour through two vertices.
        let i = rng.random_range(0..len - 1);
        let j = (i + rng.random_range(1..=12usize)).min(len - 1);
        let a = rng.random_range(0..n);
        let b = rng.random_range(0..n);
        splice(p, w, i, &[a, b], j)
    } else if kind < 84 {
        // Shortcut.
        let i = rng.random_range(0..len - 1);
        let j = (i + rng.random_range(2..=10usize)).min(len - 1);
        splice(p, w, i, &[], j)
    } else if kind < 92 {
        // Re-route: replace w[i..=j] by a random walk from w[i] to w[j] that fits.
        let i = rng.random_range(0..len - 1);
        let j = (i + rng.random_range(1..=8usize)).min(len - 1);
        let slack = p.budget - p.length(w);
        let allowed = p.length(&w[i..=j]) + slack;
        let mut seg = vec![w[i]];
        let mut l = 0.0;
        let mut opts: Vec<(usize, f64)> = Vec::new();
        loop {
            let v = *seg.last().unwrap_or(&w[i]);
            if v == w[j] && rng.random_bool(0.5) {
                break;
            }
            let Some((x, el)) = p.random_step(v, rng, &mut opts, |x, el| {
                l + el + p.metric.dist(x, w[j]) <= allowed + super::BUDGET_EPS
            }) else {
                break;
            };
            seg.push(x);
            l += el;
        }
        p.metric.extend_path(&mut seg, w[j]);
        let mut out = w[..i].to_vec();
        out.extend_from_slice(&seg);
        out.extend_from_slice(&w[j + 1..]);
        out
    } else {
        // 2-opt: reverse w[i..=j], 1 <= i < j <= len - 2.
        if len < 4 {
            return None;
        }
        let i = rng.random_range(1..len - 2);
        let j = rng.random_range(i + 1..len - 1);
        let mut out = w[..i].to_vec();
        p.metric.extend_path(&mut out, w[j]);
        out.extend(w[i..j].iter().rev());
        p.metric.extend_path(&mut out, w[j + 1]);
        out.extend_from_slice(&w[j + 2..]);
        out
    };
    if new == w || !p.fits(p.length(&new)) || p.building.check_walk(&new).is_err() {
        return None;
    }
    let keep = new
        .iter()
        .zip(w)
        .take_while(|(a, b)| a == b)
        .count()
        .saturating_sub(1);
    Some(Move { walk: new, keep })
}

impl LocalSearch {
    /// Improves `walk` (of utility `utility`) until no batch improves `patience` times in
    /// a row, the round limit, or the deadline. Returns the best walk and its utility
    /// (best by [`Problem::objective`] when [`objective`](Self::objective) is set).
    pub fn improve(
        &self,
        p: &Problem,
        run: &Run,
        walk: Vec<usize>,
        utility: f64,
    ) -> Result<(Vec<usize>, f64)> {
        self.improve_counted(p, run, walk, utility)
            .map(|(w, u, _)| (w, u))
    }

    /// [`improve`](Self::improve), also returning the number of walks evaluated.
    pub fn improve_counted(
        &self,
        p: &Problem,
        run: &Run,
        walk: Vec<usize>,
        utility: f64,
    ) -> Result<(Vec<usize>, f64, usize)> {
        let mut evals = 0;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let score = |w: &[usize], u: f64| if self.objective { p.objective(w, u) } else { u };
        let (mut walk, mut utility) = (walk, utility);
        let mut walk_score = score(&walk, utility);
        let mut pre = Prefixes::new(p, &walk)?;
        let mut idle = 0;
        for _ in 0..self.max_rounds {
            run.check()?;
            if run.out_of_time() || idle >= self.patience {
                break;
            }
            let mut moves = Vec::with_capacity(self.batch);
            let mut tries = 0;
            while moves.len() < self.batch && tries < self.batch * 20 {
                tries += 1;
                if let Some(m) = random_move(p, &walk, &mut rng) {
                    moves.push(m);
                }
            }
            if moves.is_empty() {
                break;
            }
            evals += moves.len();
            // After a cancel the batch's remaining moves are skipped (a batch is tens of
            // milliseconds on a large building, several times that on a loaded machine),
            // and so are they once the deadline has passed (they count as no gain): a
            // robot's 320 m on a 98-vertex floor ended 0.1 s after its 2 s limit, one
            // batch late, on one core here.
            let us: Vec<Result<f64>> = moves
                .par_iter()
                .map(|m| {
                    run.check()?;
                    if run.out_of_time() {
                        return Ok(f64::NEG_INFINITY);
                    }
                    pre.eval(m.keep, &m.walk[m.keep + 1..])
                })
                .collect();
            run.check()?;
            let mut best: Option<(usize, f64, f64)> = None;
            for (k, u) in us.into_iter().enumerate() {
                let u = u?;
                let sc = score(&moves[k].walk, u);
                if sc > walk_score + 1e-12 && best.is_none_or(|b| sc > b.2) {
                    best = Some((k, u, sc));
                }
            }
            match best {
                Some((k, u, sc)) => {
                    walk = std::mem::take(&mut moves[k].walk);
                    utility = u;
                    walk_score = sc;
                    p.offer(run, &walk, utility);
                    pre = Prefixes::new(p, &walk)?;
                    idle = 0;
                }
                None => idle += 1,
            }
        }
        Ok((walk, utility, evals))
    }
}

/// Applies `strength` random feasible moves to `walk`, whatever they do to the utility
/// (the kick of an iterated local search).
pub fn perturb(p: &Problem, walk: &[usize], strength: usize, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let mut w = walk.to_vec();
    let mut done = 0;
    let mut tries = 0;
    while done < strength && tries < strength * 50 {
        tries += 1;
        if let Some(m) = random_move(p, &w, rng) {
            w = m.walk;
            done += 1;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::super::coverage::reversals;
    use super::super::coverage::tests::{lattice, problem};
    use super::*;
    use crate::plan::{Control, Problem};
    use crate::surveyor::Surveyor;

    /// The lattice problem of `coverage`'s tests for a person.
    fn person(budget: f64) -> Problem {
        let p = problem(&lattice(), budget);
        Problem::new(
            p.building.clone(),
            *p.engine.kernel(),
            Surveyor::human(),
            0,
            0,
            budget,
        )
        .expect("problem")
    }

    #[test]
    fn a_reversal_costs_a_person_one_percent_and_a_robot_nothing() {
        let p = person(20.0);
        // 0 -> 1 -> 0 turns back at vertex 1 (three neighbours): one reversal.
        let walk = [0, 1, 0];
        assert_eq!(reversals(&p, &walk), 1);
        let u = p.utility(&walk).expect("utility");
        assert!((p.objective(&walk, u) - 0.99 * u).abs() < 1e-12);
        let robot = problem(&lattice(), 20.0);
        assert_eq!(robot.objective(&walk, u), u);
    }

    #[test]
    fn the_run_keeps_the_walk_with_the_best_objective_not_the_most_utility() {
        let p = person(20.0);
        let run = Run::new(Control::new(), None);
        // A loop round the first square (no reversal), then a walk there and back along
        // one edge (one reversal) credited with 0.5% more utility: a person is better off
        // with the loop, so the run keeps it.
        let looped = [0, 1, 5, 4, 0];
        let paced = [0, 1, 0];
        let u = p.utility(&looped).expect("utility");
        p.offer(&run, &looped, u);
        p.offer(&run, &paced, u * 1.005);
        assert_eq!(run.incumbent().expect("offered").0, looped.to_vec());
        // More than 1% more wins.
        p.offer(&run, &paced, u * 1.02);
        assert_eq!(run.incumbent().expect("offered").0, paced.to_vec());
    }

    #[test]
    fn by_objective_the_search_never_ends_below_its_start() {
        // A person's walk that paces: out and back along the first row.
        let p = person(24.0);
        let walk = vec![0, 1, 2, 3, 2, 1, 0];
        let u = p.utility(&walk).expect("utility");
        let run = Run::new(Control::new(), None);
        for seed in 0..4 {
            let (w, wu) = LocalSearch::new(seed)
                .by_objective()
                .improve(&p, &run, walk.clone(), u)
                .expect("search");
            assert!(p.check(&w).is_ok());
            assert!(
                p.objective(&w, wu) >= p.objective(&walk, u),
                "seed {seed}: {} < {}",
                p.objective(&w, wu),
                p.objective(&walk, u)
            );
            assert!((p.utility(&w).expect("utility") - wu).abs() <= 1e-9 * wu.abs());
        }
    }
}

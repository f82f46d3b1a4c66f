//! Exact planning by branch and bound over walks.
//!
//! A depth-first search extends the walk one edge at a time with the incremental engine
//! ([`WalkState::mark`] / [`WalkState::rewind`]); every visit of `v_t` is a candidate.
//! The incumbent starts as the best heuristic walk (given, or the feasible greedy walk).
//! Subtrees below a few levels run in parallel (rayon) and share the incumbent.
//!
//! # Pruning, and why each rule is safe
//! 1. **Feasibility**: step to `w` only if `C + l(v, w) + d(w, v_t) <= B + BUDGET_EPS`.
//! 2. **Utility bound** (robot model): let `S` be the samples so far (plus the pilot
//!    data) and `F = (p_1, ..., p_M)` the samples any completion can still add, in walk
//!    order; `M` is at most the number of sample arcs `k d` left in `(C, B]`. By the chain
//!    rule `f(S ∪ F) = f(S) + I(y_V; y_F | y_S)`. The samples `y_F` depend on `y_V` only
//!    through the latent field `f`, so `I(y_V; y_F | y_S) <= I(f; y_F | y_S)
//!    = H(y_F | y_S) - sum_i H(e_i)`. Entropy is subadditive and conditioning never
//!    raises it, so `H(y_F | y_S) <= sum_i H(y_{p_i} | y_{q_i})` with `q_i` the sample just
//!    before `p_i` on the walk (in `S` or in `F`). Consecutive samples are at most `d`
//!    apart (an edge is never shorter than the straight line), so each term is at most
//!    `c = 1/2 ln((sf2 + sn2 - sf2^2 e^{-2d/ell} / (sf2 + sn2)) / sn2)` (with
//!    `1/2 ln((sf2 + sn2)/sn2)` when an edge joins floors). Hence
//!    `f(S ∪ F) <= f(S) + M c` for every completion, and a node with
//!    `f(S) + M c <= incumbent` cannot lead to a better walk. Note that this bound does
//!    **not** use submodularity: `f_D` is not submodular in general (a sample between two
//!    vertices can be worth more once a third sample has explained away the nuisance part
//!    of its signal), so "current utility plus the sum of marginal gains" would not be
//!    admissible.
//! 3. **Transpositions** (robot model, every edge length a multiple of the sample spacing
//!    `d`): then every vertex is reached at an arc length that is a multiple of `d`, an
//!    edge traversal always adds the same interior sample points plus the vertex it
//!    arrives at, and the arrivals at each vertex are fixed by the edge multiset
//!    (`(deg(v) + [v = v_t] - [v = v_s]) / 2`). So the sample multiset, hence the
//!    utility of the walk and of every completion, depends only on the end vertex and the
//!    multiset of traversed edges: a second prefix with the same end vertex and edge
//!    multiset is skipped. States are keyed by a 128-bit Zobrist-style hash (two
//!    independent 64-bit sums of per-edge random keys); a false match has probability
//!    about `states^2 / 2^129`, below `1e-20` for the sizes searched here.
//!
//! No rule forbids U-turns or revisits: a dead end or a parity constraint (closed walks
//! on a bipartite grid) can make them necessary.
//!
//! With the human model only rule 1 applies (label noise depends on the turns, and the
//! noise of the sample at the current vertex is only fixed by the next step).
//!
//! # Complexity
//! Exponential in `B / (shortest edge)` in the worst case; each node costs one edge's
//! samples plus an `O(|V|^3)` factorisation for the bound.

use std::collections::HashSet;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::greedy::Greedy;
use super::local_search::LocalSearch;
use super::{Algorithm, Outcome, Problem, Run, Solver, Termination, better};
use crate::surveyor::Surveyor;
use crate::utility::WalkState;
use crate::{Error, Result};

/// The branch-and-bound solver.
#[derive(Debug, Clone)]
pub struct Exact {
    /// Starting incumbent; when `None` the feasible greedy walk refined by local search.
    pub incumbent: Option<Vec<usize>>,
    /// Use the utility bound (rule 2; robot model only).
    pub bound: bool,
    /// Use the transposition table (rule 3; only where it is valid).
    pub transpositions: bool,
    /// Most states kept in the transposition table.
    pub table_cap: usize,
    /// Restrict the search to simple walks (no vertex twice, except the end vertex as
    /// the last step). Not exact any more: `auto` uses it as a cheap heuristic stage.
    pub simple: bool,
    /// Stop after this many nodes (then `optimal: false`).
    pub node_cap: Option<u64>,
}

impl Default for Exact {
    fn default() -> Self {
        Exact {
            incumbent: None,
            bound: true,
            transpositions: true,
            table_cap: 16_000_000,
            simple: false,
            node_cap: None,
        }
    }
}

impl Exact {
    pub fn new() -> Self {
        Self::default()
    }

    /// Plain enumeration (feasibility pruning only): the yardstick of the tests.
    pub fn brute_force() -> Self {
        Exact {
            incumbent: None,
            bound: false,
            transpositions: false,
            table_cap: 0,
            simple: false,
            node_cap: None,
        }
    }

    /// The best simple walk (see [`Exact::simple`]), within `node_cap` nodes.
    pub fn simple_walks(node_cap: u64) -> Self {
        Exact {
            simple: true,
            node_cap: Some(node_cap),
            ..Exact::default()
        }
    }

    /// Starts from this incumbent walk.
    pub fn with_incumbent(mut self, walk: Vec<usize>) -> Self {
        self.incumbent = Some(walk);
        self
    }
}

/// Per-sample information bound `c` of rule 2, nats, or `None` when the model is not
/// the robot.
pub fn per_sample_bound(p: &Problem) -> Option<(f64, f64)> {
    let Surveyor::Robot { interval_m: d, .. } = *p.engine.model() else {
        return None;
    };
    let k = p.engine.kernel();
    let multi_floor = p
        .building
        .edges
        .iter()
        .any(|e| p.building.vertices[e.a].pos.floor != p.building.vertices[e.b].pos.floor);
    let total = k.sf2 + k.sn2;
    let var = if multi_floor {
        total
    } else {
        let kd = k.sf2 * (-d / k.ell).exp();
        total - kd * kd / total
    };
    Some((0.5 * (var / k.sn2).ln(), d))
}

/// Whether rule 3 holds: robot model and every edge a whole number of sample spacings.
pub fn lattice(p: &Problem) -> bool {
    let Surveyor::Robot { interval_m: d, .. } = *p.engine.model() else {
        return false;
    };
    p.building.edges.iter().all(|e| {
        let r = e.length / d;
        (r - r.round()).abs() < 1e-9 * r.max(1.0) && r.round() >= 1.0
    })
}

struct Shared<'a> {
    p: &'a Problem,
    run: &'a Run,
    best: Mutex<(Vec<usize>, f64)>,
    best_bits: AtomicU64,
    nodes: AtomicU64,
    timed_out: AtomicBool,
    table: Option<Vec<Mutex<HashSet<u128>>>>,
    table_len: AtomicUsize,
    table_cap: usize,
    bound: Option<(f64, f64)>,
    last_sample: f64,
    simple: bool,
    node_cap: u64,
    z: Vec<(u64, u64)>,
    zv: Vec<(u64, u64)>,
}

/// A subtree root: a prefix walk and its hash.
struct Task {
    walk: Vec<usize>,
    h: (u64, u64),
}

impl Shared<'_> {
    fn incumbent(&self) -> f64 {
        f64::from_bits(self.best_bits.load(Ordering::Relaxed))
    }

    fn offer(&self, walk: &[usize], u: f64) {
        if u < self.incumbent() {
            return;
        }
        if let Ok(mut g) = self.best.lock()
            && better((walk, u), (&g.0, g.1))
        {
            *g = (walk.to_vec(), u);
            self.best_bits.store(u.to_bits(), Ordering::Relaxed);
            self.p.offer(self.run, walk, u);
        }
    }

    /// Whether the state is new (and records it).
    fn first_visit(&self, v: usize, h: (u64, u64)) -> bool {
        let Some(t) = &self.table else { return true };
        let a = h.0 ^ self.zv[v].0;
        let b = h.1 ^ self.zv[v].1;
        let key = ((a as u128) << 64) | b as u128;
        let shard = &t[(a as usize) % t.len()];
        let Ok(mut s) = shard.lock() else { return true };
        if s.contains(&key) {
            return false;
        }
        if self.table_len.load(Ordering::Relaxed) < self.table_cap {
            s.insert(key);
            self.table_len.fetch_add(1, Ordering::Relaxed);
        }
        true
    }

    fn dfs(
        &self,
        st: &mut WalkState<'_>,
        h: (u64, u64),
        depth: usize,
        split: Option<usize>,
        tasks: &mut Vec<Task>,
        local: &mut u64,
    ) -> Result<()> {
        if split == Some(depth) {
            tasks.push(Task {
                walk: st.walk().to_vec(),
                h,
            });
            return Ok(());
        }
        *local += 1;
        // Every 256 nodes on small buildings; every node on large ones, where one node's
        // evaluation costs milliseconds and 256 of them would overrun the time limit.
        if *local >= 256 || self.p.building.len() > super::auto::LARGE_VERTICES {
            self.nodes.fetch_add(*local, Ordering::Relaxed);
            *local = 0;
            self.run.check()?;
            if self.run.out_of_time() || self.nodes.load(Ordering::Relaxed) > self.node_cap {
                self.timed_out.store(true, Ordering::Relaxed);
            }
        }
        if self.timed_out.load(Ordering::Relaxed) {
            return Ok(());
        }
        let p = self.p;
        let v = st.last();
        if !self.first_visit(v, h) {
            return Ok(());
        }
        if v == p.end || self.bound.is_some() {
            let u = st.utility()?;
            if v == p.end {
                self.offer(st.walk(), u);
            }
            if let Some((c, _)) = self.bound {
                let future = ((self.last_sample + 1.0) - st.samples() as f64).max(0.0);
                if u + future * c <= self.incumbent() + 1e-12 {
                    return Ok(());
                }
            }
        }
        let len = st.length();
        let b = &p.building;
        if self.simple && v == p.end && st.walk().len() > 1 {
            return Ok(());
        }
        for &(w, e) in b.neighbours(v) {
            let l = len + b.edges[e].length;
            if !p.fits(l + p.metric.dist(w, p.end)) {
                continue;
            }
            if self.simple && w != p.end && st.walk().contains(&w) {
                continue;
            }
            let mark = st.mark();
            st.push(w)?;
            let nh = (h.0.wrapping_add(self.z[e].0), h.1.wrapping_add(self.z[e].1));
            self.dfs(st, nh, depth + 1, split, tasks, local)?;
            st.rewind(&mark);
        }
        Ok(())
    }
}

impl Solver for Exact {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Exact
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        // Incumbent.
        let inc = match &self.incumbent {
            Some(w) if p.check(w).is_ok() => w.clone(),
            _ if !self.bound && !self.transpositions => p.shortest_walk(),
            _ => {
                let g = Greedy::feasible().solve(p, run)?;
                LocalSearch::new(0).improve(p, run, g.walk, g.utility)?.0
            }
        };
        let inc_u = p.utility(&inc)?;
        p.offer(run, &inc, inc_u);
        let bound = if self.bound {
            per_sample_bound(p)
        } else {
            None
        };
        let use_table = self.transpositions && lattice(p);
        let last_sample = match *p.engine.model() {
            Surveyor::Robot {
                interval_m: interval,
                ..
            } => ((p.budget + 2e-9) / interval + 1e-9).floor(),
            _ => 0.0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(0x05ee_db0b);
        let z: Vec<(u64, u64)> = (0..p.building.edges.len())
            .map(|_| (rng.random(), rng.random()))
            .collect();
        let zv: Vec<(u64, u64)> = (0..p.building.len())
            .map(|_| (rng.random(), rng.random()))
            .collect();
        let sh = Shared {
            p,
            run,
            best: Mutex::new((inc.clone(), inc_u)),
            best_bits: AtomicU64::new(inc_u.to_bits()),
            nodes: AtomicU64::new(0),
            timed_out: AtomicBool::new(false),
            table: use_table.then(|| (0..64).map(|_| Mutex::new(HashSet::new())).collect()),
            table_len: AtomicUsize::new(0),
            table_cap: self.table_cap,
            bound,
            last_sample,
            simple: self.simple,
            node_cap: self.node_cap.unwrap_or(u64::MAX),
            z,
            zv,
        };
        // Split the tree a few levels down, then search the subtrees in parallel.
        let mut tasks = Vec::new();
        let mut local = 0;
        let mut st = p.engine.start(p.start)?;
        let split = if rayon::current_num_threads() > 1 {
            Some(4)
        } else {
            None
        };
        sh.dfs(&mut st, (0, 0), 0, split, &mut tasks, &mut local)?;
        sh.nodes.fetch_add(local, Ordering::Relaxed);
        let total = tasks.len().max(1);
        let done = AtomicUsize::new(0);
        let results: Vec<Result<()>> = tasks
            .par_iter()
            .map(|t| {
                // A subtree starts with no node counted, so its first check would come
                // only after 256 nodes: after a cancel or the limit, every subtree still
                // queued would search that far first (hundreds of milliseconds on a
                // loaded machine). Check before starting one.
                run.check()?;
                if sh.timed_out.load(Ordering::Relaxed) || run.out_of_time() {
                    sh.timed_out.store(true, Ordering::Relaxed);
                    return Ok(());
                }
                let mut st = p.engine.start(p.start)?;
                for &v in &t.walk[1..] {
                    st.push(v)?;
                }
                let mut local = 0;
                let mut none = Vec::new();
                let r = sh.dfs(&mut st, t.h, 0, None, &mut none, &mut local);
                sh.nodes.fetch_add(local, Ordering::Relaxed);
                let k = done.fetch_add(1, Ordering::Relaxed) + 1;
                run.report(
                    Algorithm::Exact,
                    k as f64 / total as f64,
                    Some(sh.incumbent()),
                    format!("{} nodes", sh.nodes.load(Ordering::Relaxed)),
                );
                r
            })
            .collect();
        for r in results {
            r?;
        }
        run.check()?;
        let (walk, u) = sh
            .best
            .into_inner()
            .map_err(|_| Error::Numerical("exact search: poisoned lock".into()))?;
        let finished = !sh.timed_out.load(Ordering::Relaxed);
        Ok(Outcome {
            walk,
            utility: u,
            termination: if finished {
                Termination::Optimal
            } else {
                Termination::TimeLimit
            },
            optimal: Some(finished),
            nodes: Some(sh.nodes.load(Ordering::Relaxed)),
        })
    }
}

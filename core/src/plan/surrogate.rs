//! The search surrogate of the large-building planner ([`super::scale`]): a cheap stand-in
//! for `f_D` that ranks candidate walks the way `f_D` does.
//!
//! # Local conditioning (a Vecchia approximation)
//! `f_D = H(y_V) - H(y_V | y_S)`, and by the chain rule
//! `H(y_V | y_S) = sum_i H(y_vi | y_S, y_v1 .. y_v(i-1))`. Under the exponential kernel of
//! SPEC 2 a point is nearly independent of far observations once its near ones are known
//! (screening), so each term is approximated by conditioning on the [`OBS_NEIGHBOURS`]
//! observations (walk samples, pilot locations, prior observations) and the
//! [`VERTEX_NEIGHBOURS`] earlier vertices nearest to `v_i`: a Cholesky of at most 10 x 10
//! per vertex instead of one of the whole walk. `H(y_V)` is approximated the same way
//! (earlier vertices only) so that the value is on the scale of `f_D`; it does not depend
//! on the walk.
//!
//! Why this and not the coarser model it replaced (pseudo-samples merged over 4 m, about
//! 240 vertices kept): with the exponential kernel and the fitted `sf2 / sn2` of the
//! generated buildings (about 200), `f_D` is earned by passing close to many vertices,
//! and both approximations lost exactly that. On the generated mall (565 vertices) at
//! 509 m the old surrogate rated a 204.36-nat walk 44.64 and a 184.40-nat walk 51.71, and
//! the search could not leave the worse one; this surrogate rates them 204.96 and 183.20.
//! Decision record `docs/decisions/0003-search-surrogate.md` has the measured rank
//! agreement and speed.
//!
//! The utility `auto` reports, saves and compares is always the exact `f_D` of SPEC 3.

use std::sync::Arc;

use super::Problem;
use crate::Result;
use crate::building::Building;
use crate::gp::{Extent, Kernel, Point};
use crate::samples::{Checkpoint, Surveyor, WalkSampler, sample_walk_checkpoints};

/// Observations each vertex is conditioned on.
pub const OBS_NEIGHBOURS: usize = 6;

/// Earlier vertices each vertex is conditioned on.
pub const VERTEX_NEIGHBOURS: usize = 4;

/// Largest conditioning set ([`Surrogate::with`] keeps at most 16 of each kind).
const MAX_SET: usize = 32;

/// The search surrogate (see the module doc).
#[derive(Debug, Clone)]
pub struct Surrogate {
    building: Arc<Building>,
    kernel: Kernel,
    model: Surveyor,
    /// Observations every walk adds to: pilot locations and prior observations, as
    /// (position, noise variance).
    fixed: Vec<(Point, f64)>,
    /// Each vertex's earlier neighbours and what does not depend on the walk.
    vertex_part: Vec<VertexPart>,
    obs_k: usize,
    vertex_k: usize,
    /// `sum_i 1/2 ln Var(y_vi | earlier neighbours)`: the approximate `H(y_V)` less its
    /// constant.
    prior: f64,
}

impl Surrogate {
    /// The search's surrogate for `p` (same building, kernel, model and observations as
    /// its engine).
    pub fn new(p: &Problem) -> Result<Self> {
        Self::with(p, OBS_NEIGHBOURS, VERTEX_NEIGHBOURS)
    }

    /// A surrogate conditioning each vertex on `obs_k` observations and `vertex_k` earlier
    /// vertices (at most 16 each). [`Surrogate::new`] is the search's choice; this is for
    /// measuring others (`examples/surrogate_error.rs`).
    pub fn with(p: &Problem, obs_k: usize, vertex_k: usize) -> Result<Self> {
        let b = p.engine.building().clone();
        let kernel = *p.engine.kernel();
        let (obs_k, vertex_k) = (obs_k.clamp(1, 16), vertex_k.min(16));
        let mut fixed: Vec<(Point, f64)> =
            b.pilot.iter().map(|f| (f.point(), kernel.sn2)).collect();
        fixed.extend(
            p.engine
                .prior_observations()
                .iter()
                .map(|o| (o.pos, kernel.sn2 + o.extra_noise)),
        );
        let pos: Vec<Point> = b.vertices.iter().map(|v| v.pos).collect();
        let vertex_part: Vec<VertexPart> = earlier_neighbours(&pos, vertex_k)
            .into_iter()
            .enumerate()
            .map(|(v, prev)| VertexPart::new(&kernel, &pos, v, prev))
            .collect();
        let prior = vertex_part.iter().map(|v| 0.5 * v.var.ln()).sum();
        Ok(Surrogate {
            building: b,
            kernel,
            model: *p.engine.model(),
            fixed,
            vertex_part,
            obs_k,
            vertex_k,
            prior,
        })
    }

    /// Observations each vertex is conditioned on.
    pub fn observations(&self) -> usize {
        self.obs_k
    }

    /// Earlier vertices each vertex is conditioned on (at most).
    pub fn earlier_vertices(&self) -> usize {
        self.vertex_k
    }

    /// The surrogate value of a walk: an approximation of `f_D` in nats, for ranking
    /// walks of one problem.
    pub fn value(&self, walk: &[usize]) -> Result<f64> {
        Ok(self.frame(walk)?.value)
    }

    /// The surrogate value of `walk` with what it does not depend on kept ([`Frame`]),
    /// for scoring walks that differ from it in one stretch ([`Surrogate::value_near`]).
    pub fn frame(&self, walk: &[usize]) -> Result<Frame> {
        // The walk's samples, and the sampler's state at each vertex (for `value_near`).
        let (samples, checkpoints) =
            sample_walk_checkpoints(&self.building, walk, &self.model, &self.kernel)?;
        let mut obs = self.fixed.clone();
        obs.extend(
            samples
                .iter()
                .map(|s| (s.pos, self.kernel.sn2 + s.extra_noise)),
        );
        // One tree per floor.
        let mut floors: Vec<i64> = obs.iter().map(|o| o.0.floor).collect();
        floors.sort_unstable();
        floors.dedup();
        let trees: Vec<(i64, Tree)> = floors.iter().map(|&f| (f, Tree::new(&obs, f))).collect();
        let mut scratch = Scratch::new();
        let mut knn = Knn::new(self.obs_k);
        let mut near = Vec::with_capacity(self.building.len());
        let mut total = 0.0;
        for (i, v) in self.building.vertices.iter().enumerate() {
            knn.clear();
            if let Some((_, t)) = trees.iter().find(|(f, _)| *f == v.pos.floor) {
                t.nearest(v.pos.x, v.pos.y, [NOTHING; 2], 0, &mut knn);
            }
            let set = knn.items().iter().map(|&(_, j)| obs[j as usize]);
            let term = self.term(i, set, &mut scratch);
            total += term;
            near.push(Near::new(&knn, term));
        }
        Ok(Frame {
            walk: walk.to_vec(),
            arcs: vertex_arcs(&self.building, walk),
            sample_arcs: samples.iter().map(|s| s.arc).collect(),
            checkpoints,
            fixed: self.fixed.len(),
            obs,
            trees,
            near,
            total,
            value: self.prior - total,
        })
    }

    /// The surrogate value of `walk`, a walk that shares a first and a last stretch with
    /// the frame's walk (a move of the search): only the vertices whose nearest
    /// observations change are conditioned again.
    ///
    /// The samples of the shared first stretch are the frame's exactly; those of the
    /// changed stretch are `walk`'s own; those of the shared last stretch are taken as the
    /// frame's, though in `walk` they lie up to one sample spacing further on or back
    /// (samples are placed by arc length from the start) and a person's label noise there
    /// may differ after a changed turn. Where the changed stretch has the frame's length
    /// the value is [`Surrogate::value`]'s for the robot, to rounding and to the choice
    /// among observations at the same distance from a vertex.
    pub fn value_near(&self, frame: &Frame, walk: &[usize]) -> Result<f64> {
        let base = &frame.walk;
        let (nb, nw) = (base.len(), walk.len());
        let a = base.iter().zip(walk).take_while(|(x, y)| x == y).count();
        if a == nb && a == nw {
            return Ok(frame.value);
        }
        // One walk may run on from the other's end (a loop added at the end): the last
        // shared vertex is then also the first of the shared last stretch.
        let a = a.min(nb.min(nw) - 1);
        let z = base
            .iter()
            .rev()
            .zip(walk.iter().rev())
            .take_while(|(x, y)| x == y)
            .count()
            .min(nb.min(nw) - a);
        if a == 0 || z == 0 {
            // Not a walk from the frame's start to its end: nothing is shared.
            return self.value(walk);
        }
        // The changed stretches run from vertex a - 1 to vertex n - z of each walk, or,
        // where the two middles share a run of vertices (a move that cuts an excursion
        // in one place and rebuilds a stretch in another), from vertex a - 1 to the
        // run's start and from its end to vertex n - z.
        let shared = longest_common_run(&base[a..nb - z], &walk[a..nw - z]);
        let (rb, rw): (Stretches, Stretches) = match shared {
            Some((sb, sw, len)) if len >= MIN_SHARED_RUN => (
                [(a - 1, a + sb), (a + sb + len - 1, nb - z)],
                [(a - 1, a + sw), (a + sw + len - 1, nw - z)],
            ),
            _ => ([(a - 1, nb - z), (0, 0)], [(a - 1, nw - z), (0, 0)]),
        };
        // `walk`'s samples and vertex arcs from vertex `a - 1`, where the changes begin
        // (the shared first stretch is the frame's), to the last changed vertex: the
        // frame's sampler state there, then `walk`'s own vertices.
        let from = a - 1;
        let last = rw[0].1.max(rw[1].1);
        let mut samples = Vec::new();
        let mut sampler = WalkSampler::resume(&frame.checkpoints[from], self.model, self.kernel);
        let mut arcs = Vec::with_capacity(last + 1 - from);
        let mut arc = frame.arcs[from];
        arcs.push(arc);
        for w in walk[from..=last].windows(2) {
            sampler.push(&self.building, w[1], &mut samples)?;
            arc += self.building.walk_length(w);
            arcs.push(arc);
        }
        // Arc at vertex `i` of `walk` (from `from` on).
        let arc_at = |i: usize| arcs[i - from];
        // Samples strictly inside a stretch (by arc length; those at its end vertices
        // are the shared ones).
        const EPS: f64 = 1e-6;
        let inside = |sample_arcs: &dyn Fn(f64, bool) -> usize, from: f64, to: f64| {
            let lo = sample_arcs(from + EPS, true);
            (lo, sample_arcs(to - EPS, false).max(lo))
        };
        let base_at = |x: f64, le: bool| {
            frame
                .sample_arcs
                .partition_point(|&s| if le { s <= x } else { s < x })
        };
        let walk_at =
            |x: f64, le: bool| samples.partition_point(|s| if le { s.arc <= x } else { s.arc < x });
        let mut skip = [NOTHING; 2];
        let mut added: Vec<(Point, f64)> = Vec::new();
        for k in 0..2 {
            let ((b0, b1), (w0, w1)) = (rb[k], rw[k]);
            if b1 > b0 {
                let (lo, hi) = inside(&base_at, frame.arcs[b0], frame.arcs[b1]);
                skip[k] = ((frame.fixed + lo) as u32, (frame.fixed + hi) as u32);
            }
            if w1 > w0 {
                let (lo, hi) = inside(&walk_at, arc_at(w0), arc_at(w1));
                added.extend(
                    samples[lo..hi]
                        .iter()
                        .map(|s| (s.pos, self.kernel.sn2 + s.extra_noise)),
                );
            }
        }
        // The added samples' extent and tree per floor, for a quick test of which
        // vertices they may come near.
        let mut floors: Vec<i64> = added.iter().map(|(q, _)| q.floor).collect();
        floors.sort_unstable();
        floors.dedup();
        let boxes: Vec<(i64, Extent, Tree)> = floors
            .iter()
            .map(|&f| {
                let on_f = added.iter().filter(|(q, _)| q.floor == f);
                (
                    f,
                    Extent::of(on_f.map(|(q, _)| (q.x, q.y))),
                    Tree::new(&added, f),
                )
            })
            .collect();
        let mut scratch = Scratch::new();
        let mut knn = Knn::new(self.obs_k);
        let mut one = Knn::new(1);
        let mut total = frame.total;
        let base_ids = frame.obs.len() as u32;
        for (i, v) in self.building.vertices.iter().enumerate() {
            let nv = &frame.near[i];
            let here = boxes
                .iter()
                .find(|(f, b, _)| *f == v.pos.floor && b.distance2(v.pos.x, v.pos.y) < nv.r2);
            let lost = nv
                .ids()
                .iter()
                .any(|&j| skip.iter().any(|&(lo, hi)| j >= lo && j < hi));
            let gained = !lost
                && here.is_some_and(|(_, _, t)| {
                    one.clear();
                    t.nearest(v.pos.x, v.pos.y, [NOTHING; 2], 0, &mut one);
                    one.bound() < nv.r2
                });
            if !lost && !gained {
                continue;
            }
            knn.clear();
            if let Some((_, t)) = frame.trees.iter().find(|(f, _)| *f == v.pos.floor) {
                t.nearest(v.pos.x, v.pos.y, skip, 0, &mut knn);
            }
            if let Some((_, _, t)) = boxes.iter().find(|(f, _, _)| *f == v.pos.floor) {
                t.nearest(v.pos.x, v.pos.y, [NOTHING; 2], base_ids, &mut knn);
            }
            let set = knn.items().iter().map(|&(_, j)| {
                if j < base_ids {
                    frame.obs[j as usize]
                } else {
                    added[(j - base_ids) as usize]
                }
            });
            total += self.term(i, set, &mut scratch) - nv.term;
        }
        Ok(self.prior - total)
    }

    /// `1/2 ln Var(y_vi | earlier neighbours, set)` for the observations `set`, nearest
    /// first.
    ///
    /// The conditioning set of `v_i` lists its earlier neighbours first, so the leading
    /// block of the Cholesky factor, which does not depend on the walk, is the one
    /// [`Surrogate::with`] stored; only the rows of the observations are computed here.
    fn term(&self, i: usize, set: impl Iterator<Item = (Point, f64)>, sc: &mut Scratch) -> f64 {
        let k = &self.kernel;
        let v = &self.building.vertices[i];
        let pv = &self.vertex_part[i];
        let q = pv.prev.len();
        let lp = &pv.factor;
        sc.set.clear();
        sc.set.extend(set);
        let (l, z, set) = (&mut sc.l, &mut sc.z, &sc.set);
        z[..q].copy_from_slice(&pv.z);
        let mut var = pv.var;
        // Rows of the observations: `row[t][..q + t + 1]` of the factor, `q` earlier
        // vertices first.
        let m = q + set.len();
        for (t, o) in set.iter().enumerate() {
            let r = q + t;
            let row = r * m;
            for c in 0..q {
                l[row + c] = cov(k, &o.0, &self.building.vertices[pv.prev[c] as usize].pos);
            }
            for c in 0..t {
                l[row + q + c] = cov(k, &o.0, &set[c].0);
            }
            l[row + r] = k.sf2 + o.1;
            // Row r of the factor: columns before q against the stored block, the rest
            // against the rows just computed.
            for c in 0..=r {
                let mut x = l[row + c];
                if c < q {
                    for u in 0..c {
                        x -= l[row + u] * lp[c * q + u];
                    }
                    l[row + c] = x / lp[c * q + c];
                } else {
                    for u in 0..c {
                        x -= l[row + u] * l[c * m + u];
                    }
                    if c == r {
                        // Positive definite (noise on the diagonal); guard rounding.
                        l[row + r] = x.max(1e-12 * k.sf2).sqrt();
                    } else {
                        l[row + c] = x / l[c * m + c];
                    }
                }
            }
            let mut x = cov(k, &o.0, &v.pos);
            for u in 0..r {
                x -= l[row + u] * z[u];
            }
            z[r] = x / l[row + r];
            var -= z[r] * z[r];
        }
        0.5 * var.max(1e-12 * k.sn2).ln()
    }
}

/// What [`Surrogate::frame`] keeps of a walk: its observations and their trees, and each
/// vertex's nearest observations and term.
#[derive(Debug)]
pub struct Frame {
    walk: Vec<usize>,
    /// Arc length at each vertex of the walk.
    arcs: Vec<f64>,
    /// Arc length of each sample of the walk.
    sample_arcs: Vec<f64>,
    /// The sampler's state at each vertex of the walk: a walk that shares the first
    /// vertices is sampled from where it leaves them.
    checkpoints: Vec<Checkpoint>,
    /// Observations before the samples in `obs` (pilot and prior).
    fixed: usize,
    obs: Vec<(Point, f64)>,
    trees: Vec<(i64, Tree)>,
    near: Vec<Near>,
    /// Sum of the vertices' terms.
    total: f64,
    value: f64,
}

impl Frame {
    /// The walk's surrogate value ([`Surrogate::value`]).
    pub fn value(&self) -> f64 {
        self.value
    }

    /// The walk.
    pub fn walk(&self) -> &[usize] {
        &self.walk
    }
}

/// One vertex's nearest observations in a [`Frame`] (indices into its `obs`), the squared
/// distance a new observation must beat to be among them, and its term.
#[derive(Debug, Clone, Copy)]
struct Near {
    ids: [u32; 16],
    len: u8,
    r2: f64,
    term: f64,
}

impl Near {
    fn new(knn: &Knn, term: f64) -> Self {
        let mut ids = [0u32; 16];
        for (d, &(_, j)) in ids.iter_mut().zip(knn.items()) {
            *d = j;
        }
        Near {
            ids,
            len: knn.items().len() as u8,
            r2: knn.bound(),
            term,
        }
    }

    fn ids(&self) -> &[u32] {
        &self.ids[..self.len as usize]
    }
}

/// Working space of [`Surrogate::term`].
struct Scratch {
    set: Vec<(Point, f64)>,
    l: Box<[f64; MAX_SET * MAX_SET]>,
    z: [f64; MAX_SET],
}

impl Scratch {
    fn new() -> Self {
        Scratch {
            set: Vec::with_capacity(MAX_SET),
            l: Box::new([0.0; MAX_SET * MAX_SET]),
            z: [0.0; MAX_SET],
        }
    }
}

/// Arc length from the start at each vertex of `walk`.
fn vertex_arcs(b: &Building, walk: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(walk.len());
    let mut arc = 0.0;
    out.push(0.0);
    for w in walk.windows(2) {
        arc += b.walk_length(w);
        out.push(arc);
    }
    out
}

/// Up to two changed stretches of a walk, as (first, last) vertex positions; `(0, 0)` is
/// none.
type Stretches = [(usize, usize); 2];

/// An empty range of observation indices: nothing skipped.
const NOTHING: (u32, u32) = (0, 0);

/// Shortest run of vertices two changed middles must share for [`Surrogate::value_near`]
/// to keep its samples.
const MIN_SHARED_RUN: usize = 3;

/// The longest run of consecutive vertices that `a` and `b` share: `(start in a, start in
/// b, length)`; on ties the run whose last vertex comes first in `a`, then in `b`; `None`
/// when they share no vertex.
///
/// Each run is followed from its start only (a pair of equal vertices not preceded by
/// one), found through `a`'s positions sorted by vertex, so the work is about the number
/// of equal pairs: a vertex recurs a few times in a walk. The quadratic table this
/// replaced was skipped beyond 512 x 512 vertices, and then a move that cut a loop in one
/// place and rebuilt a stretch far away was scored as one change of everything between:
/// on a person's 3,972 m walk of 1,478 vertices 377 vertices a candidate lost a nearest
/// observation and were conditioned again, a third of the plan's time.
fn longest_common_run(a: &[usize], b: &[usize]) -> Option<(usize, usize, usize)> {
    let mut at: Vec<(usize, u32)> = a.iter().enumerate().map(|(i, &v)| (v, i as u32)).collect();
    at.sort_unstable();
    let mut best: Option<(usize, usize, usize)> = None;
    let mut best_end = (usize::MAX, usize::MAX);
    for (j, &y) in b.iter().enumerate() {
        let from = at.partition_point(|&(v, _)| v < y);
        for &(v, i) in &at[from..] {
            if v != y {
                break;
            }
            let i = i as usize;
            if i > 0 && j > 0 && a[i - 1] == b[j - 1] {
                continue; // inside a run followed from its start
            }
            let len = a[i..]
                .iter()
                .zip(&b[j..])
                .take_while(|(x, y)| x == y)
                .count();
            let end = (i + len - 1, j + len - 1);
            if best.is_none_or(|(_, _, bl)| len > bl || (len == bl && end < best_end)) {
                best = Some((i, j, len));
                best_end = end;
            }
        }
    }
    best
}

/// `k(a, b)` of SPEC 2 (what [`Kernel::k`] computes, with a plain square root instead of
/// `hypot`, which was a fifth of the surrogate's time).
#[inline]
fn cov(k: &Kernel, a: &Point, b: &Point) -> f64 {
    if a.floor != b.floor {
        return 0.0;
    }
    let (dx, dy) = (a.x - b.x, a.y - b.y);
    k.sf2 * (-(dx * dx + dy * dy).sqrt() / k.ell).exp()
}

/// What the surrogate keeps of one vertex's earlier neighbours: the Cholesky factor `L`
/// of their covariance (noise included), `z = L^-1 k(prev, v)`, and
/// `Var(y_v | prev) = sf2 + sn2 - |z|^2`.
#[derive(Debug, Clone)]
struct VertexPart {
    prev: Vec<u32>,
    /// Row-major `q x q`, lower triangle.
    factor: Vec<f64>,
    z: Vec<f64>,
    var: f64,
}

impl VertexPart {
    fn new(k: &Kernel, pos: &[Point], v: usize, prev: Vec<u32>) -> Self {
        let q = prev.len();
        let at = |a: usize| &pos[prev[a] as usize];
        let mut factor = vec![0.0; q * q];
        let mut z = vec![0.0; q];
        let mut var = k.sf2 + k.sn2;
        for r in 0..q {
            for c in 0..=r {
                let mut x = if c == r {
                    k.sf2 + k.sn2
                } else {
                    cov(k, at(r), at(c))
                };
                for u in 0..c {
                    x -= factor[r * q + u] * factor[c * q + u];
                }
                factor[r * q + c] = if c == r {
                    x.sqrt()
                } else {
                    x / factor[c * q + c]
                };
            }
            let mut x = cov(k, at(r), &pos[v]);
            for u in 0..r {
                x -= factor[r * q + u] * z[u];
            }
            z[r] = x / factor[r * q + r];
            var -= z[r] * z[r];
        }
        VertexPart {
            prev,
            factor,
            z,
            var,
        }
    }
}

/// For each vertex, the (at most `k`) nearest vertices of the same floor that come before
/// it in the building's order.
fn earlier_neighbours(pos: &[Point], k: usize) -> Vec<Vec<u32>> {
    let mut near = Knn::new(k.max(1));
    pos.iter()
        .enumerate()
        .map(|(i, p)| {
            if k == 0 {
                return Vec::new();
            }
            near.clear();
            for (j, q) in pos[..i].iter().enumerate() {
                if q.floor == p.floor {
                    let (dx, dy) = (p.x - q.x, p.y - q.y);
                    near.offer(dx * dx + dy * dy, j as u32);
                }
            }
            near.items().iter().map(|&(_, j)| j).collect()
        })
        .collect()
}

/// The `k` nearest items offered so far (squared distance, index), nearest first.
struct Knn {
    k: usize,
    len: usize,
    /// `bound` caches the squared distance an item must beat: the k-th nearest so far.
    bound: f64,
    items: [(f64, u32); 16],
}

impl Knn {
    fn new(k: usize) -> Self {
        Knn {
            k: k.clamp(1, 16),
            len: 0,
            bound: f64::INFINITY,
            items: [(0.0, 0); 16],
        }
    }

    fn clear(&mut self) {
        self.len = 0;
        self.bound = f64::INFINITY;
    }

    fn items(&self) -> &[(f64, u32)] {
        &self.items[..self.len]
    }

    /// The squared distance an item must beat to be kept.
    #[inline]
    fn bound(&self) -> f64 {
        self.bound
    }

    /// Keeps `(d2, j)` if it is among the `k` nearest so far (an insertion by hand: a
    /// `Vec::insert` here was a call to `memmove` per offer, 7% of a plan's time).
    #[inline(always)]
    fn offer(&mut self, d2: f64, j: u32) {
        if d2 >= self.bound {
            return;
        }
        let mut at = self.len.min(self.k - 1);
        while at > 0 && self.items[at - 1].0 > d2 {
            self.items[at] = self.items[at - 1];
            at -= 1;
        }
        self.items[at] = (d2, j);
        self.len = (self.len + 1).min(self.k);
        if self.len == self.k {
            self.bound = self.items[self.k - 1].0;
        }
    }
}

/// A 2-d tree of the observations of one floor: `nodes` is a balanced tree stored in
/// place (each slice's median is its root, split alternately by x and y).
#[derive(Debug)]
struct Tree {
    nodes: Vec<([f64; 2], u32)>,
}

impl Tree {
    fn new(obs: &[(Point, f64)], floor: i64) -> Self {
        let mut nodes: Vec<([f64; 2], u32)> = obs
            .iter()
            .enumerate()
            .filter(|(_, o)| o.0.floor == floor)
            .map(|(j, o)| ([o.0.x, o.0.y], j as u32))
            .collect();
        build(&mut nodes, 0);
        Tree { nodes }
    }

    /// The nearest observations to `(x, y)` into `out`, leaving out the indices in
    /// the ranges `skip`, with `offset` added to every index offered.
    fn nearest(&self, x: f64, y: f64, skip: [(u32, u32); 2], offset: u32, out: &mut Knn) {
        search(&self.nodes, 0, [x, y], (skip, offset), out);
    }
}

/// Slices of at most this many observations are leaves, scanned whole.
const LEAF: usize = 8;

fn build(nodes: &mut [([f64; 2], u32)], axis: usize) {
    if nodes.len() <= LEAF {
        return;
    }
    let mid = nodes.len() / 2;
    nodes.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    let (lo, hi) = nodes.split_at_mut(mid);
    build(lo, 1 - axis);
    build(&mut hi[1..], 1 - axis);
}

fn search(
    nodes: &[([f64; 2], u32)],
    axis: usize,
    q: [f64; 2],
    ids: ([(u32, u32); 2], u32),
    out: &mut Knn,
) {
    let ([(lo, hi), (lo2, hi2)], offset) = ids;
    let kept = |j: u32| (j < lo || j >= hi) && (j < lo2 || j >= hi2);
    if nodes.len() <= LEAF {
        for &(p, j) in nodes {
            if kept(j) {
                let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
                out.offer(dx * dx + dy * dy, j + offset);
            }
        }
        return;
    }
    let mid = nodes.len() / 2;
    let (p, j) = nodes[mid];
    if kept(j) {
        let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
        out.offer(dx * dx + dy * dy, j + offset);
    }
    let diff = q[axis] - p[axis];
    let (near, far) = if diff < 0.0 {
        (&nodes[..mid], &nodes[mid + 1..])
    } else {
        (&nodes[mid + 1..], &nodes[..mid])
    };
    search(near, 1 - axis, q, ids, out);
    if diff * diff < out.bound() {
        search(far, 1 - axis, q, ids, out);
    }
}

#[cfg(test)]
mod tests {
    use super::super::coverage::tests::{lattice, lattice_at, problem};
    use super::*;

    #[test]
    fn with_every_observation_and_earlier_vertex_as_neighbours_it_is_f_d() {
        // The chain rule conditioned on everything is exact: 12 vertices (11 earlier at
        // most) and at most 16 observations (the pilot and the walk's samples).
        let b = lattice();
        let robot = problem(&b, 20.0);
        let human = Problem::new(
            b.clone(),
            *robot.engine.kernel(),
            Surveyor::human(),
            0,
            0,
            40.0,
        )
        .expect("problem");
        let walks: [(&Problem, &[usize]); 4] = [
            (&robot, &[0, 1, 2, 3]),
            (&robot, &[0, 4, 5]),
            (&robot, &[0, 1, 5, 9]),
            (
                &human,
                &[0, 1, 2, 3, 7, 11, 10, 9, 8, 4, 0, 1, 2, 3, 7, 6, 5, 4, 0],
            ),
        ];
        for (p, w) in walks {
            let s = Surrogate::with(p, 16, 16).expect("surrogate");
            let (exact, approx) = (p.utility(w).expect("f_D"), s.value(w).expect("value"));
            assert!(
                (approx - exact).abs() <= 1e-9 * exact,
                "walk {w:?}: surrogate {approx}, f_D {exact}"
            );
        }
    }

    /// The lattice of `coverage::tests::lattice` with uneven column and row spacings: the
    /// two ways around a cell are still equally long, but few observations are at the
    /// same distance from a vertex (on the even lattice many are, and which of them a
    /// vertex takes is arbitrary).
    fn uneven() -> Arc<Building> {
        lattice_at([0.0, 2.1, 4.3, 6.2], [0.0, 2.3, 4.9])
    }

    #[test]
    fn a_walk_near_the_frames_is_scored_as_a_whole_walk_would_be() {
        let b = uneven();
        let p = problem(&b, 40.0);
        let s = Surrogate::new(&p).expect("surrogate");
        let base = [0, 1, 2, 6, 10, 9, 8, 4, 0];
        let frame = s.frame(&base).expect("frame");
        assert_eq!(frame.value(), s.value(&base).expect("value"));
        assert_eq!(s.value_near(&frame, &base).expect("same"), frame.value());
        // `walk` scored from `f` is within `tol` (relative) of its whole value, which it
        // returns.
        let close = |f: &Frame, walk: &[usize], tol: f64| {
            let near = s.value_near(f, walk).expect("near");
            let whole = s.value(walk).expect("whole");
            assert!(
                (near - whole).abs() <= tol * whole,
                "{walk:?}: {near} against {whole}"
            );
            near
        };
        // 1 -> 5 -> 6 instead of 1 -> 2 -> 6: the same length, so every sample after the
        // change is where the frame has it, and the value is the whole walk's.
        let near = close(&frame, &[0, 1, 5, 6, 10, 9, 8, 4, 0], 1e-9);
        assert!(
            (near - frame.value()).abs() > 1e-3,
            "the change must matter"
        );
        // A longer detour moves the later samples by less than a spacing: close, not equal.
        close(&frame, &[0, 1, 5, 9, 10, 6, 7, 11, 10, 9, 8, 4, 0], 0.02);
        // Two changes with a shared run between them (6, 10, 9), each of the same
        // length: two changed stretches, the samples between them kept.
        let twice = [0, 1, 5, 6, 10, 9, 5, 4, 0];
        assert_eq!(
            longest_common_run(&base[2..7], &twice[2..7]),
            Some((1, 1, 3))
        );
        close(&frame, &twice, 1e-9);
        // A loop added after the frame's walk ends, and one taken away: one walk runs on
        // from the other's end.
        let on: Vec<usize> = base.iter().copied().chain([1, 0]).collect();
        close(&frame, &on, 0.02);
        close(&s.frame(&on).expect("frame"), &base, 0.02);
        // A walk to another end shares nothing at the end: scored whole.
        close(&frame, &[0, 1, 2, 6, 10, 9, 8], 0.0);
        // A change at the very end.
        close(&frame, &[0, 1, 2, 6, 10, 9, 5, 4, 0], 1e-9);
    }

    /// The longest common run by the quadratic table (the first run to reach the greatest
    /// length, row by row): what [`longest_common_run`] must return.
    fn common_run_by_table(a: &[usize], b: &[usize]) -> Option<(usize, usize, usize)> {
        let mut prev = vec![0usize; b.len() + 1];
        let mut run = vec![0usize; b.len() + 1];
        let mut best = (0, 0, 0);
        for (i, x) in a.iter().enumerate() {
            for (j, y) in b.iter().enumerate() {
                run[j + 1] = if x == y { prev[j] + 1 } else { 0 };
                if run[j + 1] > best.2 {
                    best = (i + 1 - run[j + 1], j + 1 - run[j + 1], run[j + 1]);
                }
            }
            std::mem::swap(&mut prev, &mut run);
        }
        (best.2 > 0).then_some(best)
    }

    #[test]
    fn the_longest_common_run_is_the_tables_on_random_walks() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..3000 {
            let k = rng.random_range(1..8usize);
            let draw = |rng: &mut rand_chacha::ChaCha8Rng, n: usize| -> Vec<usize> {
                (0..n).map(|_| rng.random_range(0..k)).collect()
            };
            let n = rng.random_range(0..40usize);
            let a = draw(&mut rng, n);
            let b = if rng.random_bool(0.5) {
                // A walk and one changed from it: a cut and a rebuilt stretch.
                let mut b = a.clone();
                if b.len() > 4 {
                    let c = rng.random_range(0..b.len() - 2);
                    b.drain(c..c + 2);
                    let at = rng.random_range(0..b.len());
                    let mid = draw(&mut rng, 3);
                    b.splice(at..at, mid);
                }
                b
            } else {
                let n = rng.random_range(0..40usize);
                draw(&mut rng, n)
            };
            assert_eq!(
                longest_common_run(&a, &b),
                common_run_by_table(&a, &b),
                "{a:?} {b:?}"
            );
        }
    }

    #[test]
    fn any_two_walks_score_near_each_other_without_failing() {
        // Random walks on the uneven lattice, each scored from the frame of another: every
        // shape of overlap (none, prefix only, one walk running on from the other's end,
        // several changed stretches) must give a value.
        use rand::{RngExt, SeedableRng};
        let b = uneven();
        let p = problem(&b, 60.0);
        let s = Surrogate::new(&p).expect("surrogate");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let walk = |rng: &mut rand_chacha::ChaCha8Rng| {
            let mut w = vec![0usize];
            for _ in 0..rng.random_range(0..14) {
                let nb = b.neighbours(*w.last().expect("walk"));
                w.push(nb[rng.random_range(0..nb.len())].0);
            }
            w
        };
        let walks: Vec<Vec<usize>> = (0..40).map(|_| walk(&mut rng)).collect();
        for f in walks.iter().take(8) {
            let frame = s.frame(f).expect("frame");
            for w in &walks {
                let (near, whole) = (
                    s.value_near(&frame, w).expect("near"),
                    s.value(w).expect("whole"),
                );
                // Unrelated walks share little, and what they share sits up to a
                // spacing off: a sanity bound, not the search's accuracy (see
                // examples/surrogate_near.rs for that).
                assert!(
                    near.is_finite() && (near - whole).abs() <= 0.5 * whole.abs().max(1.0),
                    "{f:?} then {w:?}: {near} against {whole}"
                );
            }
        }
    }

    /// Needs the building generator (`research` feature, on by default).
    #[cfg(feature = "research")]
    mod generated {
        use super::*;
        use crate::gp::fit_kernel;
        use crate::plan::coverage::{Leg, leg};
        use crate::plan::{Control, Run};
        use crate::synth::{SynthParams, generate};
        use rand::SeedableRng;
        use rand_chacha::ChaCha8Rng;

        #[test]
        fn it_orders_walks_as_f_d_does_on_a_generated_office() {
            // Randomised spread walks of a quarter of the edge length, as the search draws
            // them: every pair whose utilities differ by more than 2% must be ordered the
            // same way by the search's surrogate, and its values stay within 10% of `f_D`.
            let params = SynthParams {
                rooms_per_side: 3,
                corridor_length_m: 30.0,
                ..SynthParams::default()
            };
            let b = Arc::new(
                crate::building::Building::from_file(
                    generate(&params).expect("synth").file,
                    "office",
                )
                .expect("building"),
            );
            let k = fit_kernel(&b.pilot).expect("fit").kernel;
            let budget = 0.25 * b.total_edge_length();
            let p = Problem::new(b.clone(), k, Surveyor::robot(), 0, 0, budget).expect("problem");
            let s = Surrogate::new(&p).expect("surrogate");
            let run = Run::new(Control::new(), None);
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            let walks: Vec<Vec<usize>> = (0..24)
                .map(|i| {
                    // The search's own construction, randomised (start = end = 0).
                    let spec = Leg {
                        radius: [0.0, 0.25, 0.5, 1.0][i % 4] * k.ell,
                        open_ties: i % 2 == 1,
                        ..crate::plan::scale::whole_walk(&p)
                    };
                    leg(&p, &spec, &[], Some(&mut rng), &run)
                })
                .collect();
            let e: Vec<f64> = walks.iter().map(|w| p.utility(w).expect("f_D")).collect();
            let v: Vec<f64> = walks.iter().map(|w| s.value(w).expect("value")).collect();
            let mut apart = 0;
            for i in 0..walks.len() {
                assert!(
                    (v[i] - e[i]).abs() < 0.1 * e[i],
                    "walk {i}: {} against {}",
                    v[i],
                    e[i]
                );
                for j in 0..i {
                    if (e[i] - e[j]).abs() > 0.02 * e[i].max(e[j]) {
                        apart += 1;
                        assert!(
                            (v[i] - v[j]) * (e[i] - e[j]) > 0.0,
                            "walks {i} and {j}: f_D {} and {}, surrogate {} and {}",
                            e[i],
                            e[j],
                            v[i],
                            v[j]
                        );
                    }
                }
            }
            assert!(apart >= 50, "only {apart} pairs more than 2% apart");
        }
    }

    fn pts(v: &[(f64, f64)]) -> Vec<(Point, f64)> {
        v.iter().map(|&(x, y)| (Point::new(x, y, 0), 1.0)).collect()
    }

    #[test]
    fn the_tree_finds_the_same_nearest_observations_as_a_scan() {
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 100.0
        };
        let obs = pts(&(0..500).map(|_| (rnd(), rnd())).collect::<Vec<_>>());
        let t = Tree::new(&obs, 0);
        for _ in 0..200 {
            let (x, y) = (rnd(), rnd());
            let mut a = Knn::new(6);
            t.nearest(x, y, [NOTHING; 2], 0, &mut a);
            let mut b = Knn::new(6);
            for (j, o) in obs.iter().enumerate() {
                b.offer((o.0.x - x).powi(2) + (o.0.y - y).powi(2), j as u32);
            }
            let da: Vec<f64> = a.items().iter().map(|i| i.0).collect();
            let db: Vec<f64> = b.items().iter().map(|i| i.0).collect();
            assert_eq!(da, db);
        }
    }

    #[test]
    fn a_tree_holds_only_its_floor() {
        let mut obs = pts(&[(0.0, 0.0), (1.0, 0.0)]);
        obs.push((Point::new(0.0, 0.0, 1), 1.0));
        let t = Tree::new(&obs, 1);
        let mut k = Knn::new(3);
        t.nearest(0.0, 0.0, [NOTHING; 2], 0, &mut k);
        assert_eq!(k.items(), &[(0.0, 2)]);
    }
}

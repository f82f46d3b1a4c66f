//! The metric closure of a building: all-pairs shortest path lengths and the paths.
//!
//! Steiner TSP paths and all the planners work on this closure: a "jump" from `u` to `v`
//! stands for the shortest walk between them, expanded by [`Metric::path`].

use std::collections::BinaryHeap;

use rayon::prelude::*;

use crate::building::Building;

/// All-pairs shortest paths.
///
/// `dist[u * n + v]` is the length of a shortest walk from `u` to `v`; `next[u * n + v]`
/// is the neighbour of `u` on one (ties broken by the lower vertex index, so paths are
/// deterministic).
///
/// # Complexity
/// `O(n (m + n) log n)` time (one Dijkstra per vertex, in parallel), `O(n^2)` memory:
/// 12 bytes per pair, 48 MB for 2,000 vertices.
#[derive(Debug, Clone)]
pub struct Metric {
    n: usize,
    dist: Vec<f64>,
    next: Vec<u32>,
}

/// A heap entry of Dijkstra: the distance's bits above the vertex index, so that one
/// integer comparison orders by distance, then by index (distances are never negative,
/// and the bits of non-negative doubles order as the doubles do). Wrapped in `Reverse`
/// for a min-heap; a compare of two doubles with the tie-break cost a sixth of the
/// closure's time on 3,000 vertices. A radix heap on the distances' bits was no faster
/// (2026-12-06, `examples/metric_timing.rs`, one core, least of 5: the generated
/// 3,161-vertex floor 366 ms against 356, the 565-vertex mall 8.0 against 6.7): the
/// frontier of these floors is a few hundred vertices. Where the edges allow, the closure
/// takes no heap at all ([`Buckets`]).
type Item = std::cmp::Reverse<u128>;

#[inline]
fn item(d: f64, v: usize) -> Item {
    debug_assert!(d >= 0.0);
    std::cmp::Reverse(((d.to_bits() as u128) << 32) | v as u128)
}

#[inline]
fn unitem(i: Item) -> (f64, usize) {
    (
        f64::from_bits((i.0 >> 32) as u64),
        (i.0 & 0xffff_ffff) as usize,
    )
}

/// Dijkstra from `root`: the walking distance of every vertex to `root` and its parent on
/// the shortest-path tree, i.e. its next hop towards `root` (`root`'s parent is itself;
/// `u32::MAX` for a vertex that cannot reach it). Among equally short ways the parent is
/// the smallest vertex index, so the tree, and every walk built from it, is the same on
/// every run and machine. The one shortest-path search of the crate: the metric closure
/// and the session's replanning both use it.
pub fn shortest_path_tree(b: &Building, root: usize) -> (Vec<f64>, Vec<u32>) {
    shortest_path_tree_within(b, root, &|_| true)
}

/// [`shortest_path_tree`] through the vertices `keep` accepts only, as if the others and
/// their edges were not there (they stay at `INFINITY` and `u32::MAX`; so does everything
/// when `keep` refuses `root`). A part of a building (`Building::part`) keeps what is
/// within walking distance of a vertex on the floors it keeps.
pub fn shortest_path_tree_within(
    b: &Building,
    root: usize,
    keep: &dyn Fn(usize) -> bool,
) -> (Vec<f64>, Vec<u32>) {
    let n = b.len();
    let mut d = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    if keep(root) {
        let adj = Adjacency::within(b, keep);
        shortest_path_tree_into(&adj, root, &mut d, &mut parent, &mut BinaryHeap::new());
    }
    (d, parent)
}

/// The building's adjacency lists packed for Dijkstra: each vertex's neighbours and edge
/// lengths side by side in one array, in the building's neighbour order (so ties break as
/// they would on the building itself). Reading an edge's length through the edge list
/// costs a cache miss per relaxation on a large building.
struct Adjacency {
    /// `start[v]..start[v + 1]` indexes `to` and `len` for `v`'s neighbours.
    start: Vec<usize>,
    to: Vec<u32>,
    len: Vec<f64>,
}

impl Adjacency {
    fn new(b: &Building) -> Self {
        Self::within(b, &|_| true)
    }

    /// The edges between two vertices `keep` accepts only.
    fn within(b: &Building, keep: &dyn Fn(usize) -> bool) -> Self {
        let n = b.len();
        let mut start = Vec::with_capacity(n + 1);
        let mut to = Vec::new();
        let mut len = Vec::new();
        start.push(0);
        for v in 0..n {
            if keep(v) {
                for &(w, e) in b.neighbours(v) {
                    if keep(w) {
                        to.push(w as u32);
                        len.push(b.edges[e].length);
                    }
                }
            }
            start.push(to.len());
        }
        Adjacency { start, to, len }
    }
}

/// [`shortest_path_tree`] into caller-owned slices (`n` long, every entry `INFINITY` and
/// `u32::MAX`), with a reusable heap.
fn shortest_path_tree_into(
    adj: &Adjacency,
    root: usize,
    d: &mut [f64],
    parent: &mut [u32],
    heap: &mut BinaryHeap<Item>,
) {
    heap.clear();
    d[root] = 0.0;
    parent[root] = root as u32;
    heap.push(item(0.0, root));
    while let Some(top) = heap.pop() {
        let (du, u) = unitem(top);
        if du > d[u] {
            continue;
        }
        relax(adj, u, du, d, parent, |w, nd| heap.push(item(nd, w)));
    }
}

/// Relaxes the edges of `u`, settled at distance `du`: a neighbour reached by a shorter
/// way takes it (and `push` is told its new distance), and one reached by an equally short
/// way from a smaller index takes that as its parent. Every vertex that reaches `w` by a
/// shortest way is settled before `w` in any label-setting order, so the parent is the
/// least such index whatever the order within equal distances.
#[inline(always)]
fn relax(
    adj: &Adjacency,
    u: usize,
    du: f64,
    d: &mut [f64],
    parent: &mut [u32],
    mut push: impl FnMut(usize, f64),
) {
    for k in adj.start[u]..adj.start[u + 1] {
        let w = adj.to[k] as usize;
        let nd = du + adj.len[k];
        if nd < d[w] || (nd == d[w] && (u as u32) < parent[w]) {
            let improved = nd < d[w];
            d[w] = nd;
            parent[w] = u as u32;
            if improved {
                push(w, nd);
            }
        }
    }
}

/// Dial's buckets for the closure's many Dijkstras: a ring of vertex lists, bucket `i`
/// holding the vertices whose tentative distance lies in `[i h, (i + 1) h)`, with `h` half
/// the shortest edge. A vertex settled in bucket `i` reaches its neighbours at `(i + 2) h`
/// or more, so when the sweep comes to a bucket every vertex in it already has its final
/// distance (the way to it through a vertex of the same bucket would be shorter than an
/// edge) and the bucket is settled in any order, with no heap (the parents do not depend
/// on that order, see [`relax`]). The sweep visits every bucket up to the root's
/// eccentricity, so it is used only where that is a few buckets per vertex
/// ([`Buckets::fit`]). The generated 3,161-vertex floor's closure takes 210 ms against
/// 429 ms with the heap, the 565-vertex mall 5.7 ms against 9.5 (one core, least of 5,
/// `examples/metric_timing.rs`).
#[derive(Debug, Clone)]
struct Buckets {
    /// `1 / h`.
    inv: f64,
    ring: Vec<Vec<u32>>,
    settled: Vec<bool>,
}

impl Buckets {
    /// Most buckets in the ring: edges more than this many half-shortest edges long take
    /// the heap instead.
    const RING_MAX: usize = 4096;

    /// Buckets for `adj` when they pay: [`Self::new`], and a sweep of at most four
    /// buckets per vertex for a root whose eccentricity is `ecc` (every other root's is
    /// at most twice it on a connected building).
    fn fit(adj: &Adjacency, ecc: f64) -> Option<Self> {
        let n = adj.start.len() - 1;
        let q = Self::new(adj)?;
        let sweep = 2.0 * ecc * q.inv;
        (sweep.is_finite() && sweep <= 4.0 * n as f64).then_some(q)
    }

    /// Buckets for `adj`, whatever the sweep costs: `None` when the ring would need more
    /// than [`Self::RING_MAX`] buckets (an edge more than 2,046 times the shortest).
    fn new(adj: &Adjacency) -> Option<Self> {
        let n = adj.start.len() - 1;
        let shortest = adj.len.iter().copied().fold(f64::INFINITY, f64::min);
        let longest = adj.len.iter().copied().fold(0.0, f64::max);
        if !(shortest > 0.0 && shortest.is_finite()) {
            return None;
        }
        let inv = 2.0 / shortest;
        // A power of two, so that a bucket's slot is a mask, not a division.
        let ring = (longest * inv).ceil() + 3.0;
        (ring <= Self::RING_MAX as f64).then(|| Buckets {
            inv,
            ring: vec![Vec::new(); (ring as usize).next_power_of_two()],
            settled: vec![false; n],
        })
    }

    /// [`shortest_path_tree_into`] by the buckets: the same distances and parents.
    fn tree_into(&mut self, adj: &Adjacency, root: usize, d: &mut [f64], parent: &mut [u32]) {
        self.settled.fill(false);
        let (inv, mask) = (self.inv, self.ring.len() as u64 - 1);
        d[root] = 0.0;
        parent[root] = root as u32;
        self.ring[0].push(root as u32);
        let mut pending = 1usize;
        let mut i = 0u64;
        while pending > 0 {
            let slot = (i & mask) as usize;
            let bucket = std::mem::take(&mut self.ring[slot]);
            pending -= bucket.len();
            for &u in &bucket {
                let u = u as usize;
                if std::mem::replace(&mut self.settled[u], true) {
                    continue; // an entry left behind when `u` came closer
                }
                let ring = &mut self.ring;
                relax(adj, u, d[u], d, parent, |w, nd| {
                    ring[((nd * inv) as u64 & mask) as usize].push(w as u32);
                    pending += 1;
                });
            }
            // Nothing lands in the bucket being settled (the ring spans the longest
            // edge and two buckets more), so its list goes back empty, keeping its room.
            debug_assert!(self.ring[slot].is_empty());
            let mut bucket = bucket;
            bucket.clear();
            self.ring[slot] = bucket;
            i += 1;
        }
    }
}

/// The metric closure of the building planned last, kept for the next plan on the same
/// building while that building lives: a session's replans plan again and again on one
/// building, and on a floor of thousands of vertices the closure is a large share of a
/// replan's second (207 ms on one core for the generated 3,161-vertex floor, where a
/// replan's limit is 1 s). Keyed by the building's
/// `Arc` (the same allocation, not an equal building), so a building changed or rebuilt
/// gets its own closure; holding one closure at a time, it keeps no more memory than a
/// plan on that building takes anyway.
#[derive(Default)]
pub struct SharedMetric {
    last: std::sync::Mutex<Option<(std::sync::Weak<Building>, std::sync::Arc<Metric>)>>,
}

impl SharedMetric {
    /// The closure of `b`: the one kept when it is `b`'s, else a new one, which is kept.
    pub fn for_building(&self, b: &std::sync::Arc<Building>) -> std::sync::Arc<Metric> {
        let mut last = self
            .last
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some((kept, m)) = last.as_ref()
            && kept
                .upgrade()
                .is_some_and(|k| std::sync::Arc::ptr_eq(&k, b))
        {
            return m.clone();
        }
        // The old closure goes before the new one is built: two at once would be twice
        // the memory a plan's estimate counts.
        *last = None;
        let m = std::sync::Arc::new(Metric::new(b));
        *last = Some((std::sync::Arc::downgrade(b), m.clone()));
        m
    }
}

impl std::fmt::Debug for SharedMetric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self
            .last
            .lock()
            .map(|l| l.as_ref().map(|(_, m)| m.len()))
            .unwrap_or(None);
        f.debug_struct("SharedMetric")
            .field("vertices", &n)
            .finish()
    }
}

impl Metric {
    /// Computes the closure of `b`.
    pub fn new(b: &Building) -> Self {
        let adj = Adjacency::new(b);
        // Dial's buckets where they pay ([`Buckets::fit`]), judged by the eccentricity of
        // vertex 0; a heap otherwise.
        let buckets = (!b.is_empty())
            .then(|| {
                let (d, _) = shortest_path_tree(b, 0);
                let ecc = d
                    .iter()
                    .copied()
                    .filter(|x| x.is_finite())
                    .fold(0.0, f64::max);
                Buckets::fit(&adj, ecc)
            })
            .flatten();
        Self::with(b, adj, buckets)
    }

    /// The closure by Dijkstra with `buckets`, or with a heap.
    fn with(b: &Building, adj: Adjacency, buckets: Option<Buckets>) -> Self {
        let n = b.len();
        // Dijkstra from each target t: parent[u] on the tree rooted at t is u's next hop
        // towards t, so each run gives column t of the table. The runs go in groups of
        // `GROUP` columns, each group copied in before the next starts: holding every
        // run's result until the end would need as much memory again as the table (120
        // MB more on 3,161 vertices), and a group writes `GROUP` adjacent entries of each
        // row rather than one entry per row (a cache miss each).
        const GROUP: usize = 64;
        // Every entry is written below (each column's run sets every vertex, INFINITY and
        // u32::MAX where unreachable), so the table starts as zeroed memory, which the
        // allocator takes fresh from the system without a pass over it.
        let mut dist = vec![0.0f64; n * n];
        let mut next = vec![0u32; n * n];
        // One group's columns, reused by every group (fresh ones per group cost page
        // faults that two threads took turns on: the closure of the generated
        // 3,161-vertex floor took 377 ms on two cores against 316 ms on one).
        let mut col_d = vec![0.0f64; GROUP.min(n) * n];
        let mut col_p = vec![0u32; GROUP.min(n) * n];
        let mut t0 = 0;
        while t0 < n {
            let t1 = (t0 + GROUP).min(n);
            let g = t1 - t0;
            col_d[..g * n]
                .par_chunks_mut(n)
                .zip(col_p[..g * n].par_chunks_mut(n))
                .enumerate()
                // One piece of the group a thread, so that each thread sets up its heap
                // or buckets (a ring of up to `RING_MAX` lists) once a group, not once a
                // column.
                .with_min_len(g.div_ceil(rayon::current_num_threads()))
                .for_each_init(
                    || (BinaryHeap::new(), buckets.clone()),
                    |(heap, buckets), (k, (d, p))| {
                        d.fill(f64::INFINITY);
                        p.fill(u32::MAX);
                        match buckets {
                            Some(q) => q.tree_into(&adj, t0 + k, d, p),
                            None => shortest_path_tree_into(&adj, t0 + k, d, p, heap),
                        }
                    },
                );
            // Row by row, in parallel too: each row takes `g` adjacent entries.
            let (cd, cp) = (&col_d, &col_p);
            dist.par_chunks_mut(n)
                .zip(next.par_chunks_mut(n))
                .enumerate()
                .for_each(|(u, (dr, nr))| {
                    for k in 0..g {
                        dr[t0 + k] = cd[k * n + u];
                        nr[t0 + k] = cp[k * n + u];
                    }
                });
            t0 = t1;
        }
        Metric { n, dist, next }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the building has no vertex (never, for a validated building).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Shortest distance from `u` to `v`, metres.
    #[inline]
    pub fn dist(&self, u: usize, v: usize) -> f64 {
        self.dist[u * self.n + v]
    }

    /// The neighbour of `u` on the shortest path to `v` (`u` itself when `u == v`).
    #[inline]
    pub fn next_hop(&self, u: usize, v: usize) -> usize {
        self.next[u * self.n + v] as usize
    }

    /// The shortest walk from `u` to `v`, both included.
    pub fn path(&self, u: usize, v: usize) -> Vec<usize> {
        let mut out = vec![u];
        self.extend_path(&mut out, v);
        out
    }

    /// Appends the shortest walk from `walk.last()` to `v`, without repeating the last
    /// vertex. Does nothing on an empty walk.
    pub fn extend_path(&self, walk: &mut Vec<usize>, v: usize) {
        let Some(&mut mut u) = walk.last_mut() else {
            return;
        };
        let mut guard = 0;
        while u != v && guard <= self.n {
            let h = self.next_hop(u, v);
            if h >= self.n {
                return; // unreachable; a validated building is connected
            }
            walk.push(h);
            u = h;
            guard += 1;
        }
    }

    /// The walk `s -> order[0] -> ... -> t` along shortest paths.
    pub fn expand(&self, s: usize, order: &[usize], t: usize) -> Vec<usize> {
        let mut w = vec![s];
        for &v in order {
            self.extend_path(&mut w, v);
        }
        self.extend_path(&mut w, t);
        w
    }

    /// Length of `s -> order -> t` in the closure.
    pub fn tour_cost(&self, s: usize, order: &[usize], t: usize) -> f64 {
        let mut c = 0.0;
        let mut u = s;
        for &v in order {
            c += self.dist(u, v);
            u = v;
        }
        c + self.dist(u, t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dijkstra by selection (the nearest unsettled vertex each round, no heap), and each
    /// vertex's parent by the documented rule: the least index among its neighbours on a
    /// shortest way to the root.
    fn reference_tree(b: &Building, root: usize) -> (Vec<f64>, Vec<u32>) {
        let n = b.len();
        let mut d = vec![f64::INFINITY; n];
        let mut done = vec![false; n];
        d[root] = 0.0;
        while let Some(u) = (0..n)
            .filter(|&u| !done[u] && d[u].is_finite())
            .min_by(|&x, &y| d[x].total_cmp(&d[y]))
        {
            done[u] = true;
            for &(w, e) in b.neighbours(u) {
                d[w] = d[w].min(d[u] + b.edges[e].length);
            }
        }
        let parent = (0..n)
            .map(|w| {
                if w == root {
                    return root as u32;
                }
                b.neighbours(w)
                    .iter()
                    .filter(|&&(u, e)| d[u] + b.edges[e].length == d[w])
                    .map(|&(u, _)| u as u32)
                    .min()
                    .unwrap_or(u32::MAX)
            })
            .collect();
        (d, parent)
    }

    /// A building of these vertex and edge objects (JSON text).
    fn graph(vertices: &[String], edges: &[String]) -> Building {
        let text = format!(
            r#"{{"format":"survey-building/1","name":"g","vertices":[{}],"edges":[{}]}}"#,
            vertices.join(","),
            edges.join(",")
        );
        Building::from_json(&text, "g").expect("valid")
    }

    #[test]
    fn every_tree_is_the_references_on_random_graphs_with_ties() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for case in 0..60 {
            // Every tenth graph has more vertices than a group of columns (64), so the
            // table is filled over several groups, the last one partial.
            let n = if case % 10 == 9 {
                rng.random_range(65..200usize)
            } else {
                rng.random_range(2..40usize)
            };
            let vertices: Vec<String> = (0..n)
                // Close together: every edge is longer than the straight line.
                .map(|i| format!(r#"{{"id":"v{i}","x":{},"y":0}}"#, 0.001 * i as f64))
                .collect();
            // A spanning path (connected) and random chords, lengths from a few values
            // (many equal sums: ties) or, in every third case, random ones.
            let mut edges = Vec::new();
            let length = |rng: &mut rand_chacha::ChaCha8Rng| {
                if case % 3 == 0 {
                    rng.random_range(0.1..5.0)
                } else {
                    [0.5, 1.0, 1.5, 2.0][rng.random_range(0..4usize)]
                }
            };
            for i in 1..n {
                let l = length(&mut rng);
                edges.push(format!(r#"{{"a":"v{}","b":"v{i}","length":{l}}}"#, i - 1));
            }
            let mut joined = std::collections::HashSet::new();
            for _ in 0..rng.random_range(0..2 * n) {
                let (a, c) = (rng.random_range(0..n), rng.random_range(0..n));
                if a + 1 < c && joined.insert((a, c)) {
                    let l = length(&mut rng);
                    edges.push(format!(r#"{{"a":"v{a}","b":"v{c}","length":{l}}}"#));
                }
            }
            let b = graph(&vertices, &edges);
            let m = Metric::new(&b);
            let adj = Adjacency::new(&b);
            let mut q = Buckets::new(&adj).expect("positive lengths, a short ring");
            for root in 0..n {
                let (d, p) = shortest_path_tree(&b, root);
                let (rd, rp) = reference_tree(&b, root);
                assert_eq!(d, rd, "case {case}, root {root}");
                assert_eq!(p, rp, "case {case}, root {root}");
                let (mut bd, mut bp) = (vec![f64::INFINITY; n], vec![u32::MAX; n]);
                q.tree_into(&adj, root, &mut bd, &mut bp);
                assert_eq!(bd, rd, "buckets, case {case}, root {root}");
                assert_eq!(bp, rp, "buckets, case {case}, root {root}");
                for u in 0..n {
                    assert_eq!(m.dist(u, root), rd[u]);
                    assert_eq!(m.next_hop(u, root), rp[u] as usize);
                }
            }
        }
    }

    #[test]
    fn the_closure_by_buckets_is_the_closure_by_the_heap_on_a_lattice() {
        // A 40 x 25 lattice of corridor-like edges, lengths from a few values (many equal
        // sums: ties), where the buckets pay: the whole table must be the heap's, bit for
        // bit.
        let (w, h) = (40usize, 25usize);
        let lengths = [2.5, 2.5, 2.0, 1.25, 3.75];
        let mut vertices = Vec::new();
        let mut edges = Vec::new();
        for j in 0..h {
            for i in 0..w {
                vertices.push(format!(r#"{{"id":"v{i}_{j}","x":{},"y":{}}}"#, i, j));
                let l = lengths[(i * 7 + j * 3) % lengths.len()];
                if i + 1 < w {
                    edges.push(format!(
                        r#"{{"a":"v{i}_{j}","b":"v{}_{j}","length":{l}}}"#,
                        i + 1
                    ));
                }
                if j + 1 < h && (i + j) % 4 != 1 {
                    edges.push(format!(
                        r#"{{"a":"v{i}_{j}","b":"v{i}_{}","length":{l}}}"#,
                        j + 1
                    ));
                }
            }
        }
        let b = graph(&vertices, &edges);
        let adj = Adjacency::new(&b);
        let (d, _) = shortest_path_tree(&b, 0);
        let ecc = d.iter().copied().fold(0.0, f64::max);
        assert!(
            Buckets::fit(&adj, ecc).is_some(),
            "the lattice takes the buckets"
        );
        let by_buckets = Metric::new(&b);
        let by_heap = Metric::with(&b, Adjacency::new(&b), None);
        assert!(by_buckets.dist == by_heap.dist, "distances differ");
        assert!(by_buckets.next == by_heap.next, "next hops differ");
    }

    #[test]
    fn buckets_refuse_a_ring_too_long_and_the_heap_takes_over() {
        let text = |l: f64| {
            format!(
                r#"{{"format":"survey-building/1","name":"z","vertices":[{{"id":"a","x":0,"y":0}},{{"id":"b","x":1e-7,"y":0}},{{"id":"c","x":2,"y":0}}],
                "edges":[{{"a":"a","b":"b","length":{l}}},{{"a":"b","b":"c","length":100}}]}}"#
            )
        };
        let adj = |l| Adjacency::new(&Building::from_json(&text(l), "z").expect("valid"));
        // 100 m against half of 0.01 m: 20,003 buckets; of 1 micrometre (the shortest
        // edge a building may have), 2e8.
        assert!(Buckets::new(&adj(1e-6)).is_none());
        assert!(Buckets::new(&adj(0.01)).is_none());
        assert!(Buckets::new(&adj(1.0)).is_some());
        // There the heap gives the closure.
        let m = Metric::new(&Building::from_json(&text(1e-6), "z").expect("valid"));
        assert_eq!(m.dist(0, 2), 100.0 + 1e-6);
        assert_eq!(m.path(2, 0), vec![2, 1, 0]);
    }

    #[test]
    fn a_shared_closure_is_kept_for_the_same_building_only() {
        let vertices: Vec<String> = (0..5)
            .map(|i| format!(r#"{{"id":"v{i}","x":{i},"y":0}}"#))
            .collect();
        let edges: Vec<String> = (1..5)
            .map(|i| format!(r#"{{"a":"v{}","b":"v{i}"}}"#, i - 1))
            .collect();
        let a = std::sync::Arc::new(graph(&vertices, &edges));
        let shared = SharedMetric::default();
        let first = shared.for_building(&a);
        assert!(std::sync::Arc::ptr_eq(&first, &shared.for_building(&a)));
        // An equal building in another allocation is another building (it may be
        // changed independently): its own closure, which replaces the kept one.
        let b = std::sync::Arc::new((*a).clone());
        let other = shared.for_building(&b);
        assert!(!std::sync::Arc::ptr_eq(&first, &other));
        assert_eq!(other.dist(0, 4), 4.0);
        assert!(!std::sync::Arc::ptr_eq(&first, &shared.for_building(&a)));
        // A building gone is never matched, whatever takes its place.
        drop(b);
        let c = std::sync::Arc::new(graph(&vertices[..3], &edges[..2]));
        assert_eq!(shared.for_building(&c).len(), 3);
        assert!(format!("{shared:?}").contains("Some(3)"));
    }

    #[test]
    fn shortest_paths_on_a_square_with_a_long_edge() {
        // a-b 1, b-c 1, c-d 1, a-d length 5 (longer than a-b-c-d).
        let text = r#"{"format":"survey-building/1","name":"sq",
          "vertices":[{"id":"a","x":0,"y":0},{"id":"b","x":1,"y":0},{"id":"c","x":1,"y":1},{"id":"d","x":0,"y":1}],
          "edges":[{"a":"a","b":"b"},{"a":"b","b":"c"},{"a":"c","b":"d"},{"a":"a","b":"d","length":5}]}"#;
        let b = Building::from_json(text, "sq").expect("valid");
        let m = Metric::new(&b);
        assert_eq!(m.dist(0, 3), 3.0);
        assert_eq!(m.path(0, 3), vec![0, 1, 2, 3]);
        assert_eq!(m.path(3, 0), vec![3, 2, 1, 0]);
        assert_eq!(m.path(2, 2), vec![2]);
        assert_eq!(m.expand(0, &[2], 0), vec![0, 1, 2, 1, 0]);
        assert_eq!(m.tour_cost(0, &[2], 0), 4.0);
    }
}

//! `coverage`: the systematic walk a surveyor makes without Trailprint, and the
//! spread-out constructions `auto` starts from on large buildings.
//!
//! # The baseline ([`Coverage`], algorithm `coverage`)
//! From the start, walk (by shortest path) to the nearest edge not yet walked, walk it end
//! to end, and repeat while that edge and the way back to the end still fit the budget;
//! then walk back to the end. It uses no utility at all: it is what a person does with a
//! floor plan and a tape measure, and the yardstick every planner is judged against on
//! buildings of realistic size. "Nearest" is the shortest-path distance to the nearer end
//! of the edge; ties go to the lower edge index, so the walk is deterministic. Edges walked
//! on the way to another edge count as walked.
//!
//! # Spread constructions ([`spread_walk`])
//! On a dense grid the baseline spends its budget on lanes a metre apart whose samples
//! tell nearly the same thing (the kernel correlates points within a few `ell`). The spread
//! variant skips an edge whose midpoint lies within a *radius* of an edge already walked
//! (same floor) while an edge further from everything walked can still be reached, and
//! only then falls back to the nearest unwalked edge, so the whole budget is used. It keeps
//! going with the nearest edge that fits (not only the nearest edge), so that it uses the
//! budget to the last metre. `auto` builds these walks for a few radii and keeps the best
//! by utility.
//!
//! # Complexity
//! `O(k E)` for a walk that targets `k` edges, plus the radius bookkeeping: per walked
//! edge, the edges within the radius, from a table built once per problem
//! ([`NearEdges`], a grid of edge midpoints), or `O(E)` segment distances where the table
//! would be too big. A few milliseconds on a 1,000-edge building.

use super::{Algorithm, Outcome, Problem, Run, Solver, Termination};
use crate::Result;
use crate::gp::Point;

/// The systematic-walk baseline.
#[derive(Debug, Clone, Copy, Default)]
pub struct Coverage;

impl Solver for Coverage {
    fn algorithm(&self) -> Algorithm {
        Algorithm::Coverage
    }

    fn solve(&self, p: &Problem, run: &Run) -> Result<Outcome> {
        let walk = systematic_walk(p, run);
        let utility = p.utility(&walk)?;
        p.offer(run, &walk, utility);
        run.report(
            Algorithm::Coverage,
            1.0,
            Some(utility),
            format!("{:.0} m walked", p.length(&walk)),
        );
        Ok(Outcome::new(walk, utility, Termination::Completed))
    }
}

/// The systematic walk of the baseline: nearest unwalked edge first, while the way back
/// fits.
pub(in crate::plan) fn systematic_walk(p: &Problem, run: &Run) -> Vec<usize> {
    build(p, 0.0, false, run)
}

/// The spread construction with novelty radius `radius` metres (0: nearest edge first),
/// using the budget to the last edge that fits.
pub fn spread_walk(p: &Problem, radius: f64, run: &Run) -> Vec<usize> {
    build(p, radius, true, run)
}

/// Most entries [`NearEdges`] keeps (12 bytes each, so at most 48 MiB): a building whose
/// edges have more neighbours within the length scale than that (a dense mesh with a long
/// length scale) scans every edge per walked edge instead.
const NEAR_EDGES_MAX: usize = 4 << 20;

/// For each edge `e`, the edges `k` whose midpoint lies within `cap` metres of `e`'s
/// segment on a floor of one of `e`'s ends, nearest first: what [`Marks`] marks as near
/// when `e` is walked, precomputed once per problem. Without it a construction pays a
/// scan of every edge (a segment distance each) per edge it walks, which was 37% of
/// `auto`'s search time on the 290-vertex campus.
#[derive(Debug, Clone)]
pub struct NearEdges {
    cap: f64,
    /// Edge `e`'s entries are `start[e]..start[e + 1]`.
    start: Vec<u32>,
    idx: Vec<u32>,
    dist: Vec<f64>,
}

impl NearEdges {
    /// The table for novelty radii up to `cap` metres; `None` when it would hold more
    /// than [`NEAR_EDGES_MAX`] entries or the building more than `u32::MAX` edges.
    pub fn new(b: &crate::building::Building, cap: f64) -> Option<Self> {
        Self::new_within(b, cap, NEAR_EDGES_MAX)
    }

    /// [`NearEdges::new`] with at most `max` entries.
    fn new_within(b: &crate::building::Building, cap: f64, max: usize) -> Option<Self> {
        if !(cap > 0.0 && cap.is_finite()) || b.edges.len() >= u32::MAX as usize {
            return None;
        }
        let mids: Vec<Point> = b.edges.iter().map(|e| midpoint(b, e.a, e.b)).collect();
        // Midpoints bucketed by floor and grid cell of side `cell`.
        let cell = cap.max(1.0);
        let key = |x: f64, y: f64| ((x / cell).floor() as i64, (y / cell).floor() as i64);
        let mut grid: std::collections::HashMap<(i64, i64, i64), Vec<u32>> =
            std::collections::HashMap::new();
        for (k, m) in mids.iter().enumerate() {
            let (cx, cy) = key(m.x, m.y);
            grid.entry((m.floor, cx, cy)).or_default().push(k as u32);
        }
        let mut start = Vec::with_capacity(b.edges.len() + 1);
        let (mut idx, mut dist) = (Vec::new(), Vec::new());
        let mut row: Vec<(f64, u32)> = Vec::new();
        let mut cands: Vec<u32> = Vec::new();
        for e in &b.edges {
            start.push(idx.len() as u32);
            let (pa, pb) = (&b.vertices[e.a].pos, &b.vertices[e.b].pos);
            let (x0, y0) = key(pa.x.min(pb.x) - cap, pa.y.min(pb.y) - cap);
            let (x1, y1) = key(pa.x.max(pb.x) + cap, pa.y.max(pb.y) + cap);
            cands.clear();
            let cells = (x1 - x0 + 1).saturating_mul(y1 - y0 + 1);
            if cells > mids.len() as i64 {
                // A long edge beside a short cell: every midpoint is cheaper.
                cands.extend(0..mids.len() as u32);
            } else {
                let floors = if pa.floor == pb.floor {
                    &[pa.floor][..]
                } else {
                    &[pa.floor, pb.floor][..]
                };
                for &f in floors {
                    for cx in x0..=x1 {
                        for cy in y0..=y1 {
                            if let Some(v) = grid.get(&(f, cx, cy)) {
                                cands.extend_from_slice(v);
                            }
                        }
                    }
                }
            }
            row.clear();
            for &k in &cands {
                let m = &mids[k as usize];
                if m.floor == pa.floor || m.floor == pb.floor {
                    let d = m.segment_projection(pa, pb).1;
                    if d <= cap {
                        row.push((d, k));
                    }
                }
            }
            row.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            if idx.len() + row.len() > max {
                return None;
            }
            idx.extend(row.iter().map(|&(_, k)| k));
            dist.extend(row.iter().map(|&(d, _)| d));
        }
        start.push(idx.len() as u32);
        Some(NearEdges {
            cap,
            start,
            idx,
            dist,
        })
    }

    /// The table for the largest of `cap`, `cap / 2`, `cap / 4` and `cap / 8` that it
    /// can hold ([`NEAR_EDGES_MAX`] entries), so that where the whole length scale is too
    /// many edges the smaller radii still have one. The construction radii of the
    /// large-building search are at most half the length scale; without their table a
    /// 3,282-vertex three-floor building (5,969 edges, length scale 52.8 m) spent 1.9 s
    /// of a 2 s plan on segment distances in 24 constructions and was refused for time.
    /// Where the edges are many, the count at `cap` is first estimated from a sample of
    /// edges, so that a radius far too large is not built only to be given up.
    pub fn largest(b: &crate::building::Building, cap: f64) -> Option<Self> {
        Self::largest_within(b, cap, NEAR_EDGES_MAX)
    }

    /// [`NearEdges::largest`] with at most `max` entries.
    fn largest_within(b: &crate::building::Building, cap: f64, max: usize) -> Option<Self> {
        let (mut cap, mut halvings) = (cap, 0);
        let edges = b.edges.len();
        if edges > 0 && edges.saturating_mul(edges) > max {
            let mids: Vec<Point> = b.edges.iter().map(|e| midpoint(b, e.a, e.b)).collect();
            let sample: Vec<usize> = (0..64).map(|i| i * edges / 64).collect();
            let estimate = |cap: f64| {
                let within: usize = sample
                    .iter()
                    .map(|&e| {
                        let ed = &b.edges[e];
                        let (pa, pb) = (&b.vertices[ed.a].pos, &b.vertices[ed.b].pos);
                        mids.iter()
                            .filter(|m| {
                                (m.floor == pa.floor || m.floor == pb.floor)
                                    && m.segment_projection(pa, pb).1 <= cap
                            })
                            .count()
                    })
                    .sum();
                within * edges / sample.len()
            };
            while halvings < 3 && estimate(cap) > max {
                cap /= 2.0;
                halvings += 1;
            }
        }
        loop {
            if let Some(t) = Self::new_within(b, cap, max) {
                return Some(t);
            }
            if halvings == 3 {
                return None;
            }
            cap /= 2.0;
            halvings += 1;
        }
    }

    /// The largest novelty radius the table answers for, metres.
    pub fn cap(&self) -> f64 {
        self.cap
    }

    /// How many pairs of two different edges the table holds with one's midpoint within
    /// `radius` of the other (`None` beyond [`NearEdges::cap`]). [`Marks`] of two radii
    /// with the same count mark the same edges as near a walked one, so the
    /// constructions of the two build the same walk ([`distinct_radii`]).
    pub fn pairs_within(&self, radius: f64) -> Option<usize> {
        if radius.is_nan() || radius > self.cap {
            return None;
        }
        let mut count = 0;
        for e in 0..self.start.len() - 1 {
            let r = self.start[e] as usize..self.start[e + 1] as usize;
            let dist = &self.dist[r.clone()];
            let within = dist.partition_point(|&d| d <= radius);
            // The edge's own midpoint lies on it: not a pair.
            let own = self.idx[r][..within].iter().any(|&k| k as usize == e);
            count += within - usize::from(own);
        }
        Some(count)
    }

    /// The edges within `radius` (at most [`NearEdges::cap`]) of edge `e`.
    fn within(&self, e: usize, radius: f64) -> impl Iterator<Item = usize> + '_ {
        let r = self.start[e] as usize..self.start[e + 1] as usize;
        self.idx[r.clone()]
            .iter()
            .zip(&self.dist[r])
            .take_while(move |&(_, &d)| d <= radius)
            .map(|(&k, _)| k as usize)
    }
}

/// The radii of `radii` (metres, in order) to build constructions for: all but those
/// whose [`Marks`] mark the same edges as an earlier one's, whose constructions would be
/// the same walks, and those beyond the problem's near-edge table ([`tabled_radii`]).
/// A radius of 0 marks no other edge, so it is the same as any radius within which no
/// two edges are; where there is no table every radius is kept. On the generated
/// 3,161-vertex floor (length scale 7.9 m, rooms on a grid of 1.5 to 3 m) five of the
/// twelve construction radii of the large-building search (0 to 0.5 length scales) mark
/// what a smaller one does.
pub(in crate::plan) fn distinct_radii(p: &Problem, radii: &[f64]) -> Vec<f64> {
    let table = p.near_edges();
    let mut seen: Vec<usize> = Vec::new();
    tabled_radii(p, radii)
        .into_iter()
        .filter(|&r| {
            let key = if r == 0.0 {
                Some(0)
            } else {
                table.and_then(|t| t.pairs_within(r))
            };
            match key {
                Some(k) if seen.contains(&k) => false,
                Some(k) => {
                    seen.push(k);
                    true
                }
                None => true,
            }
        })
        .collect()
}

/// The radii of `radii` that the problem's near-edge table answers for (0 always), or
/// all of them where it has none. A radius beyond the table's cap costs a scan of every
/// edge per walked edge: on a 3,282-vertex three-floor building whose table is kept for
/// half the length scale only ([`NearEdges::largest`]), the search's moves of one length
/// scale spent 40% of a 2 s plan in those scans.
pub(in crate::plan) fn tabled_radii(p: &Problem, radii: &[f64]) -> Vec<f64> {
    match p.near_edges() {
        Some(t) => radii
            .iter()
            .copied()
            .filter(|&r| r == 0.0 || r <= t.cap())
            .collect(),
        None => radii.to_vec(),
    }
}

/// Whether legs skip [`EdgeOrder`] and scan every edge: only for the test that compares
/// the two.
#[cfg(test)]
fn full_scan_only() -> bool {
    tests::FULL_SCAN.with(|f| f.get())
}

#[cfg(not(test))]
#[inline(always)]
fn full_scan_only() -> bool {
    false
}

/// Length of a vertex's list in [`EdgeOrder`].
pub const ORDER_LEN: usize = 128;

/// For each vertex, its [`ORDER_LEN`] nearest edges (by the shortest distance to their
/// nearer end, then by index), each list built on first use. A leg's step takes the
/// nearest edge of the best class ([`leg_marked`]); the list lets it stop as soon as no
/// edge further on can be better instead of reading the distances to every edge of the
/// building, and it falls back to that scan when the list runs out first.
#[derive(Debug)]
pub struct EdgeOrder {
    lists: Vec<std::sync::OnceLock<Box<[u32]>>>,
}

impl EdgeOrder {
    /// An empty table for `n` vertices.
    pub fn new(n: usize) -> Self {
        EdgeOrder {
            lists: (0..n).map(|_| std::sync::OnceLock::new()).collect(),
        }
    }

    /// Vertex `v`'s list, built on first use.
    pub fn of(&self, p: &Problem, v: usize) -> &[u32] {
        self.lists[v].get_or_init(|| {
            let m = &p.metric;
            let mut all: Vec<(f64, u32)> = p
                .building
                .edges
                .iter()
                .enumerate()
                .map(|(e, ed)| (m.dist(v, ed.a).min(m.dist(v, ed.b)), e as u32))
                .filter(|(d, _)| d.is_finite())
                .collect();
            let by = |x: &(f64, u32), y: &(f64, u32)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
            if all.len() > ORDER_LEN {
                all.select_nth_unstable_by(ORDER_LEN - 1, by);
                all.truncate(ORDER_LEN);
            }
            all.sort_unstable_by(by);
            all.into_iter().map(|(_, e)| e).collect()
        })
    }
}

/// The midpoint of the edge from `a` to `b`, on the lower of its floors.
fn midpoint(b: &crate::building::Building, a: usize, c: usize) -> Point {
    let (pa, pb) = (&b.vertices[a].pos, &b.vertices[c].pos);
    Point {
        x: 0.5 * (pa.x + pb.x),
        y: 0.5 * (pa.y + pb.y),
        floor: pa.floor.min(pb.floor),
    }
}

/// State of a construction: how often each edge is walked, and how many walked edges
/// each edge is within the radius of (itself included). Counts rather than flags, so that
/// a search can take a walk's marks and remove the steps of the stretch it rebuilds
/// ([`Marks::unwalk_all`]) instead of marking the rest of the walk again.
#[derive(Debug, Clone)]
pub(in crate::plan) struct Marks<'a> {
    p: &'a Problem,
    walked: Vec<u32>,
    near: Vec<u32>,
    /// The problem's table when it answers for `radius`, else `mids` for a scan.
    table: Option<&'a NearEdges>,
    mids: std::sync::Arc<Vec<Point>>,
    radius: f64,
    /// Edges near no walked edge (`near[e] == 0`): the edges a leg prefers.
    free: usize,
}

impl<'a> Marks<'a> {
    pub(in crate::plan) fn new(p: &'a Problem, radius: f64) -> Self {
        let b = &p.building;
        let table = if radius > 0.0 {
            p.near_edges().filter(|t| radius <= t.cap())
        } else {
            None
        };
        let mids = if radius > 0.0 && table.is_none() {
            b.edges.iter().map(|e| midpoint(b, e.a, e.b)).collect()
        } else {
            Vec::new()
        };
        Marks {
            p,
            walked: vec![0; b.edges.len()],
            near: vec![0; b.edges.len()],
            table,
            mids: std::sync::Arc::new(mids),
            radius,
            free: b.edges.len(),
        }
    }

    /// The novelty radius these marks are for.
    pub(in crate::plan) fn radius(&self) -> f64 {
        self.radius
    }

    fn is_walked(&self, e: usize) -> bool {
        self.walked[e] > 0
    }

    fn is_near(&self, e: usize) -> bool {
        self.near[e] > 0
    }

    /// Adds `by` (1 or -1) to the near count of every edge within the radius of `e`.
    fn add_near(&mut self, u: usize, v: usize, e: usize, by: i32) {
        let mut free = self.free;
        let mut step = |x: &mut u32| {
            let was = *x;
            *x = x.wrapping_add_signed(by);
            free = free + usize::from(*x == 0) - usize::from(was == 0);
        };
        step(&mut self.near[e]);
        if let Some(t) = self.table {
            for k in t.within(e, self.radius) {
                step(&mut self.near[k]);
            }
        } else if self.radius > 0.0 {
            let b = &self.p.building;
            let (pa, pb) = (&b.vertices[u].pos, &b.vertices[v].pos);
            for (k, m) in self.mids.iter().enumerate() {
                if (m.floor == pa.floor || m.floor == pb.floor)
                    && m.segment_projection(pa, pb).1 <= self.radius
                {
                    step(&mut self.near[k]);
                }
            }
        }
        self.free = free;
    }

    /// Marks the edge from `u` to its neighbour `v` as walked (once more).
    fn walk_step(&mut self, u: usize, v: usize) {
        let b = &self.p.building;
        let Some(&(_, e)) = b.neighbours(u).iter().find(|&&(w, _)| w == v) else {
            return;
        };
        self.walked[e] += 1;
        if self.walked[e] == 1 {
            self.add_near(u, v, e, 1);
        }
    }

    /// Takes back one [`Marks::walk_step`] from `u` to `v` (or from `v` to `u`).
    fn unwalk_step(&mut self, u: usize, v: usize) {
        let b = &self.p.building;
        let Some(&(_, e)) = b.neighbours(u).iter().find(|&&(w, _)| w == v) else {
            return;
        };
        if self.walked[e] == 0 {
            return;
        }
        self.walked[e] -= 1;
        if self.walked[e] == 0 {
            self.add_near(u, v, e, -1);
        }
    }

    /// Marks every step of `walk[from..]` as walked.
    pub(in crate::plan) fn walk_all(&mut self, walk: &[usize], from: usize) {
        for i in from.max(1)..walk.len() {
            self.walk_step(walk[i - 1], walk[i]);
        }
    }

    /// Takes back every step of `walk` ([`Marks::unwalk_step`]).
    pub(in crate::plan) fn unwalk_all(&mut self, walk: &[usize]) {
        for w in walk.windows(2) {
            self.unwalk_step(w[0], w[1]);
        }
    }

    /// Turns the marks of the walk `old` into those of `new` by the steps outside their
    /// common prefix and suffix, and returns how many steps that took (the caller may
    /// prefer [`Marks::walk_all`] afresh when it is most of `new`). The marks are counts,
    /// so the result is the same as marking `new` from nothing. A search that accepts a
    /// move changes a stretch or two of a long walk: marking all of it again for every
    /// radius was a third of a 2 s plan on a 1,468-vertex floor (a person, 3,678 m),
    /// where the edges near each walked edge are thousands.
    pub(in crate::plan) fn rewalk(&mut self, old: &[usize], new: &[usize]) -> usize {
        let (o, n) = changed_spans(old, new);
        // Add before taking back, so that an edge in both is not unmarked and marked again.
        self.walk_all(n, 1);
        self.unwalk_all(o);
        (o.len() + n.len()).saturating_sub(2)
    }
}

/// The stretches of `old` and `new` between their longest common prefix and suffix, each
/// with the vertex before and after it (so their steps are exactly the steps that differ).
pub(in crate::plan) fn changed_spans<'w>(
    old: &'w [usize],
    new: &'w [usize],
) -> (&'w [usize], &'w [usize]) {
    let a = old.iter().zip(new).take_while(|(x, y)| x == y).count();
    let room = old.len().min(new.len()) - a;
    let c = old
        .iter()
        .rev()
        .zip(new.iter().rev())
        .take(room)
        .take_while(|(x, y)| x == y)
        .count();
    let span = |w: &'w [usize]| -> &'w [usize] {
        if w.is_empty() {
            w
        } else {
            &w[a.saturating_sub(1)..(w.len() - c + 1).min(w.len())]
        }
    };
    (span(old), span(new))
}

/// The construction behind [`Coverage`] and [`spread_walk`]: a whole walk.
fn build(p: &Problem, radius: f64, any_fit: bool, run: &Run) -> Vec<usize> {
    let spec = Leg {
        from: p.start,
        prev: None,
        to: p.end,
        budget: p.budget,
        radius,
        any_fit,
        avoid_reversals: false,
        open_ties: false,
    };
    leg(p, &spec, &[], None, run)
}

/// What [`leg`] builds: a walk from `from` to `to` of at most `budget` metres.
#[derive(Debug, Clone, Copy)]
pub struct Leg {
    pub from: usize,
    /// The vertex walked just before `from`, if any (for reversal avoidance).
    pub prev: Option<usize>,
    pub to: usize,
    pub budget: f64,
    /// Novelty radius, metres (0: nearest edge first).
    pub radius: f64,
    /// Keep going with the nearest edge that fits (else stop at the first that does not).
    pub any_fit: bool,
    /// Prefer edges whose way there does not start by walking straight back along the
    /// edge just walked (a person finds pacing A-B-A odd), except at a dead end.
    pub avoid_reversals: bool,
    /// Among equally near edges, take the one whose far end has the most unwalked edges
    /// (the walk carries on from there) instead of the lowest index. The baseline's
    /// lowest-index rule leaves single edges behind that the walk must come back for: on
    /// the generated 565-vertex mall at 2,036 m it covers 1,384 m of distinct edges,
    /// this rule 1,491 m (420.9 against 440.7 nats).
    pub open_ties: bool,
}

/// Builds one leg of a walk: the coverage construction from `spec.from` to `spec.to`
/// within `spec.budget`, counting the edges of `context` (the rest of the walk) as walked.
/// With `rng`, the first target is drawn at random among the novel edges that fit (so that
/// repeated legs explore different parts of the building); then nearest first.
///
/// Returns the leg's vertices, `from` first and `to` last. The leg always fits when the
/// shortest path from `from` to `to` does.
pub fn leg(
    p: &Problem,
    spec: &Leg,
    context: &[usize],
    rng: Option<&mut rand_chacha::ChaCha8Rng>,
    run: &Run,
) -> Vec<usize> {
    let mut marks = Marks::new(p, spec.radius);
    marks.walk_all(context, 1);
    leg_marked(p, spec, marks, rng, run)
}

/// [`leg`] with the rest of the walk given as its marks (for `spec.radius`) instead of
/// its vertices.
pub(in crate::plan) fn leg_marked(
    p: &Problem,
    spec: &Leg,
    mut marks: Marks,
    mut rng: Option<&mut rand_chacha::ChaCha8Rng>,
    run: &Run,
) -> Vec<usize> {
    use rand::RngExt;
    let b = &p.building;
    let m = &p.metric;
    debug_assert_eq!(marks.radius(), spec.radius);
    let mut walk = vec![spec.from];
    let mut len = 0.0;
    let mut cur = spec.from;
    let mut prev = spec.prev;
    let fits = |l: f64| l <= spec.budget + super::BUDGET_EPS;
    let mut first = true;
    loop {
        // Only a cancel stops a construction, not the time limit: a leg costs
        // milliseconds, and on a building whose set-up (metric closure, engine) used up
        // the limit, a construction cut at its first step would leave a plan of nothing.
        if run.control_cancelled() {
            break;
        }
        let dead_end = b.neighbours(cur).len() <= 1;
        // Candidates ranked by (class, reach): class 0 away from everything walked, 1 any
        // unwalked edge; +2 when the way there starts by walking back (and it need not).
        let mut best: Option<(usize, f64, usize, usize, usize)> = None; // class, reach, e, x, y
        // Unwalked edges at `v` (for `open_ties`).
        let open = |marks: &Marks, v: usize| {
            b.neighbours(v)
                .iter()
                .filter(|&&(_, e)| !marks.is_walked(e))
                .count()
        };
        let mut pool: Vec<(usize, usize, usize)> = Vec::new();
        // Offers edge `e` (not walked) to `best` and, on a randomised leg's first step,
        // to `pool`.
        let consider = |e: usize,
                        best: &mut Option<(usize, f64, usize, usize, usize)>,
                        pool: &mut Vec<(usize, usize, usize)>| {
            let ed = &b.edges[e];
            let (da, db) = (m.dist(cur, ed.a), m.dist(cur, ed.b));
            let (x, y, reach) = if da <= db {
                (ed.a, ed.b, da)
            } else {
                (ed.b, ed.a, db)
            };
            if !reach.is_finite() {
                return;
            }
            let mut class = usize::from(marks.is_near(e));
            if spec.avoid_reversals
                && !dead_end
                && let Some(pv) = prev
            {
                let hop = if x == cur { y } else { m.next_hop(cur, x) };
                if hop == pv {
                    class += 2;
                }
            }
            let randomised = first && rng.is_some();
            if let Some((bc, br, ..)) = *best
                && (class > bc || (class == bc && (reach > br || (reach == br && !spec.open_ties))))
                && !randomised
            {
                return;
            }
            // From the end's row (contiguous), not `y`'s column: on the first step of a
            // randomised leg every unwalked edge gets here, and a column read is a cache
            // miss each on a building of thousands of vertices. Shortest distances are
            // symmetric (to rounding, far below BUDGET_EPS).
            let total = len + reach + ed.length + m.dist(spec.to, y);
            if spec.any_fit && !fits(total) {
                return;
            }
            if randomised && class % 2 == 0 && fits(total) {
                pool.push((e, x, y));
            }
            if best.is_none_or(|(bc, br, _, _, by)| {
                class < bc
                    || (class == bc
                        && (reach < br
                            || (spec.open_ties
                                && reach == br
                                && open(&marks, y) > open(&marks, by))))
            }) {
                *best = Some((class, reach, e, x, y));
            }
        };
        // The nearest edges first, while an edge further on could still be better: the
        // best class there can be is 0 while some edge is near no walked edge, else 1.
        // The same edge as the scan below would find (same order of ties: by distance,
        // then by index), or, when the list runs out first, the scan itself.
        let mut settled = false;
        if !(first && rng.is_some() || full_scan_only()) {
            let floor = usize::from(marks.free == 0);
            for &e in p.nearest_edges(cur) {
                let e = e as usize;
                if marks.is_walked(e) {
                    continue;
                }
                if let Some((bc, br, ..)) = best {
                    let ed = &b.edges[e];
                    let reach = m.dist(cur, ed.a).min(m.dist(cur, ed.b));
                    if bc == floor && reach > br {
                        settled = true;
                        break;
                    }
                }
                consider(e, &mut best, &mut pool);
            }
        }
        if !settled {
            best = None;
            for e in 0..b.edges.len() {
                if !marks.is_walked(e) {
                    consider(e, &mut best, &mut pool);
                }
            }
        }
        let pick = match (first, rng.as_deref_mut()) {
            (true, Some(r)) if !pool.is_empty() => {
                let (e, x, y) = pool[r.random_range(0..pool.len())];
                Some((m.dist(cur, x), e, x, y))
            }
            _ => best.map(|(_, reach, e, x, y)| (reach, e, x, y)),
        };
        first = false;
        let Some((reach, e, x, y)) = pick else {
            break;
        };
        let ed = b.edges[e];
        if !fits(len + reach + ed.length + m.dist(spec.to, y)) {
            break; // the baseline's rule: the nearest edge no longer fits
        }
        let from = walk.len();
        m.extend_path(&mut walk, x);
        walk.push(y);
        marks.walk_all(&walk, from);
        len += reach + ed.length;
        prev = walk.len().checked_sub(2).map(|i| walk[i]);
        cur = y;
    }
    m.extend_path(&mut walk, spec.to);
    walk
}

/// Number of times `walk` goes straight back along the edge it just walked at a vertex
/// that is not a dead end (pacing A-B-A): what a person following the walk notices.
pub fn reversals(p: &Problem, walk: &[usize]) -> usize {
    walk.windows(3)
        .filter(|w| w[0] == w[2] && p.building.neighbours(w[1]).len() > 1)
        .count()
}

/// Removes reversals (see [`reversals`]) from `walk` where that keeps it within the
/// budget, for a person to follow. Two repairs, tried at each reversal `A-B-A` in turn:
/// * **Drop the spur** `B-A` when the edge `A-B` is walked at least once more elsewhere
///   (the walk gets shorter and still covers every edge it covered);
/// * **Go round**: from `B` take a neighbour other than `A` and the shortest path on to
///   the vertex after the second `A` (or to the end), when that fits the budget.
///
/// A repair is kept only when it lowers the walk's reversal count, so the result never
/// has more reversals than `walk`, starts and ends where `walk` does, and fits when
/// `walk` fits.
pub fn unpace(p: &Problem, walk: &[usize]) -> Vec<usize> {
    let b = &p.building;
    let m = &p.metric;
    let mut w = walk.to_vec();
    let mut revs = reversals(p, &w);
    let mut len = p.length(&w);
    let fits = |l: f64| l <= p.budget + super::BUDGET_EPS;
    let mut k = 1;
    while revs > 0 && k + 1 < w.len() {
        let (a, bv) = (w[k - 1], w[k]);
        if w[k + 1] != a || b.neighbours(bv).len() <= 1 {
            k += 1;
            continue;
        }
        // Drop the spur when the edge stays walked.
        let uses = w
            .windows(2)
            .filter(|e| (e[0] == a && e[1] == bv) || (e[0] == bv && e[1] == a))
            .count();
        if uses >= 3 {
            let mut cand = w[..k].to_vec();
            cand.extend_from_slice(&w[k + 2..]);
            let r = reversals(p, &cand);
            if r < revs {
                len = p.length(&cand);
                w = cand;
                revs = r;
                k = k.saturating_sub(1).max(1);
                continue;
            }
        }
        // Go round: B -> x -> ... -> target, where target is the vertex after the second
        // A (or A itself when the walk ends there).
        let (target, resume) = if k + 2 < w.len() {
            (w[k + 2], k + 3)
        } else {
            (a, k + 2)
        };
        let old = p.length(&w[k..resume]);
        // Ways round: B -> x, or B -> x -> y, then the shortest path on; the one leaving
        // the fewest reversals in the whole walk wins, then the shortest.
        let mut starts: Vec<Vec<usize>> = Vec::new();
        for &(x, _) in b.neighbours(bv) {
            if x == a {
                continue;
            }
            starts.push(vec![bv, x]);
            for &(y, _) in b.neighbours(x) {
                if y != bv {
                    starts.push(vec![bv, x, y]);
                }
            }
        }
        let mut best: Option<(usize, f64, Vec<usize>)> = None;
        for mut path in starts {
            m.extend_path(&mut path, target);
            if path.last() != Some(&target) {
                continue;
            }
            let extra = p.length(&path) - old;
            if !fits(len + extra) {
                continue;
            }
            let mut cand = w[..k].to_vec();
            cand.extend_from_slice(&path);
            cand.extend_from_slice(&w[resume..]);
            let r = reversals(p, &cand);
            if best
                .as_ref()
                .is_none_or(|(br, be, _)| r < *br || (r == *br && extra < *be))
            {
                best = Some((r, extra, cand));
            }
        }
        if let Some((r, _, cand)) = best
            && r < revs
        {
            len = p.length(&cand);
            w = cand;
            revs = r;
            continue;
        }
        k += 1;
    }
    w
}

#[cfg(test)]
pub(super) mod tests {
    use std::sync::Arc;
    #[cfg(feature = "research")]
    use std::sync::OnceLock;

    use super::*;
    use crate::building::Building;
    use crate::gp::Kernel;
    use crate::plan::{Control, Run};
    use crate::surveyor::Surveyor;

    /// A 4 x 3 lattice of 2 m cells (vertex `4 r + c` at `(2 c, 2 r)`).
    pub(in crate::plan) fn lattice() -> Arc<Building> {
        lattice_at([0.0, 2.0, 4.0, 6.0], [0.0, 2.0, 4.0])
    }

    /// A 4 x 3 lattice with columns at `xs` and rows at `ys` (vertex `4 r + c` at
    /// `(xs[c], ys[r])`), pilot data at the origin.
    pub(in crate::plan) fn lattice_at(xs: [f64; 4], ys: [f64; 3]) -> Arc<Building> {
        grid_at(&xs, &ys)
    }

    /// A grid with columns at `xs` and rows at `ys` (vertex `xs.len() r + c` at
    /// `(xs[c], ys[r])`), pilot data at the origin.
    fn grid_at(xs: &[f64], ys: &[f64]) -> Arc<Building> {
        let mut v = Vec::new();
        let mut e = Vec::new();
        for (r, &y) in ys.iter().enumerate() {
            for (c, &x) in xs.iter().enumerate() {
                v.push(format!(r#"{{"id":"v{r}_{c}","x":{x},"y":{y}}}"#));
                if c > 0 {
                    e.push(format!(r#"{{"a":"v{r}_{}","b":"v{r}_{c}"}}"#, c - 1));
                }
                if r > 0 {
                    e.push(format!(r#"{{"a":"v{}_{c}","b":"v{r}_{c}"}}"#, r - 1));
                }
            }
        }
        let text = format!(
            r#"{{"format":"survey-building/1","name":"lat","vertices":[{}],"edges":[{}],
               "pilot":[{{"x":0,"y":0,"rss":{{"a":-50}}}}]}}"#,
            v.join(","),
            e.join(",")
        );
        Arc::new(Building::from_json(&text, "lat").expect("valid"))
    }

    thread_local! {
        /// Set by the test that compares a leg's nearest-edge lists with a scan.
        pub(super) static FULL_SCAN: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// A leg that reads each vertex's nearest edges in order ([`EdgeOrder`]) is the leg
    /// that scans every edge at every step, on a grid of more edges than a list holds:
    /// for novelty radii of none, within and beyond the table, both tie rules, reversal
    /// avoidance, either fit rule, randomised or not, from the middle of walks.
    #[test]
    fn a_leg_by_nearest_edge_lists_is_the_leg_by_a_scan_of_every_edge() {
        use rand::{RngExt, SeedableRng};
        let at = |n: usize| (0..n).map(|i| 2.0 * i as f64).collect::<Vec<f64>>();
        let b = grid_at(&at(16), &at(12));
        assert!(b.edges.len() > 2 * ORDER_LEN, "{}", b.edges.len());
        let k = Kernel {
            sf2: 10.0,
            ell: 6.0,
            sn2: 1.0,
        };
        let p = Problem::new(b.clone(), k, Surveyor::robot(), 0, 0, 400.0).expect("problem");
        let run = Run::new(Control::new(), None);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let mut settled_by_lists = 0;
        for case in 0..240 {
            let context = random_walk(&b, rng.random_range(0..120), &mut rng);
            let spec = Leg {
                from: context[rng.random_range(0..context.len())],
                prev: None,
                to: rng.random_range(0..b.len()),
                budget: rng.random_range(10.0..160.0),
                radius: [0.0, 3.0, 20.0][case % 3],
                any_fit: rng.random_bool(0.7),
                avoid_reversals: rng.random_bool(0.5),
                open_ties: rng.random_bool(0.5),
            };
            let spec = Leg {
                prev: b.neighbours(spec.from).first().map(|&(w, _)| w),
                ..spec
            };
            let seed: Option<u64> = rng.random_bool(0.5).then(|| rng.random());
            let build = |full: bool| {
                FULL_SCAN.with(|f| f.set(full));
                let mut r = seed.map(rand_chacha::ChaCha8Rng::seed_from_u64);
                let w = leg(&p, &spec, &context, r.as_mut(), &run);
                FULL_SCAN.with(|f| f.set(false));
                w
            };
            let (by_lists, by_scan) = (build(false), build(true));
            assert_eq!(by_lists, by_scan, "case {case}: {spec:?}");
            settled_by_lists += usize::from(by_lists.len() > 2);
            // The count of edges near nothing walked is kept right.
            let mut m = Marks::new(&p, spec.radius);
            m.walk_all(&context, 1);
            assert_eq!(m.free, m.near.iter().filter(|&&n| n == 0).count());
            m.unwalk_all(&context[..context.len() / 2]);
            assert_eq!(m.free, m.near.iter().filter(|&&n| n == 0).count());
        }
        assert!(settled_by_lists > 100, "{settled_by_lists}");
    }

    /// A robot's closed walk from vertex 0 within `budget` metres.
    pub(in crate::plan) fn problem(b: &Arc<Building>, budget: f64) -> Problem {
        let k = Kernel {
            sf2: 10.0,
            ell: 4.0,
            sn2: 1.0,
        };
        Problem::new(b.clone(), k, Surveyor::robot(), 0, 0, budget).expect("problem")
    }

    /// A random walk of `steps` steps on `b` from vertex 0.
    fn random_walk(b: &Building, steps: usize, rng: &mut rand_chacha::ChaCha8Rng) -> Vec<usize> {
        use rand::RngExt;
        let mut w = vec![0];
        for _ in 0..steps {
            let n = b.neighbours(*w.last().expect("a vertex"));
            w.push(n[rng.random_range(0..n.len())].0);
        }
        w
    }

    /// Marks moved from one walk to another by their changed steps are the marks of the
    /// other walk marked from nothing, for a radius of none, one the problem's table
    /// answers (up to `ell`) and one beyond it (a scan of every edge); and the steps taken
    /// are only those that differ.
    #[test]
    fn marks_moved_between_walks_are_the_marks_of_the_new_walk() {
        use rand::{RngExt, SeedableRng};
        let b = lattice();
        let p = problem(&b, 100.0);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for radius in [0.0, 2.5, 9.0] {
            for _ in 0..200 {
                let old = random_walk(&b, rng.random_range(0..12), &mut rng);
                // Keep a prefix and a suffix of `old`, with a random stretch between.
                let i = rng.random_range(0..=old.len());
                let j = rng.random_range(i..=old.len());
                let mut new = old[..i].to_vec();
                let mid = random_walk(&b, rng.random_range(0..6), &mut rng);
                new.extend(mid.iter().skip(usize::from(i == 0 && rng.random_bool(0.5))));
                new.extend_from_slice(&old[j..]);
                let mut moved = Marks::new(&p, radius);
                moved.walk_all(&old, 1);
                let steps = moved.rewalk(&old, &new);
                let mut fresh = Marks::new(&p, radius);
                fresh.walk_all(&new, 1);
                assert_eq!(moved.walked, fresh.walked, "r {radius}: {old:?} -> {new:?}");
                assert_eq!(moved.near, fresh.near, "r {radius}: {old:?} -> {new:?}");
                let (o, n) = changed_spans(&old, &new);
                assert_eq!(steps, (o.len() + n.len()).saturating_sub(2));
                assert!(steps <= old.len() + new.len(), "{steps}");
                if old == new {
                    assert_eq!(steps, 0);
                }
            }
        }
    }

    #[test]
    fn baseline_walks_every_edge_when_the_budget_allows_and_stays_within_it() {
        let b = lattice();
        let total = b.total_edge_length();
        let run = Run::new(Control::new(), None);
        for budget in [6.0, 10.0, 17.0, 30.0, 2.0 * total] {
            let p = problem(&b, budget);
            let w = build(&p, 0.0, false, &run);
            p.check(&w).expect("feasible");
            if budget >= 2.0 * total {
                let mut marks = Marks::new(&p, 0.0);
                marks.walk_all(&w, 1);
                assert!(marks.walked.iter().all(|&x| x > 0), "every edge walked");
            }
        }
    }

    #[test]
    fn baseline_takes_the_nearest_edge_first() {
        // From v00 the nearest unwalked edge is one of v00's own; the walk's first step
        // leaves v00 along an edge, never jumps.
        let b = lattice();
        let p = problem(&b, 8.0);
        let w = build(&p, 0.0, false, &Run::new(Control::new(), None));
        // 8 m closed walk from a corner: out along two edges and back (or a square).
        assert_eq!(w.first(), Some(&0));
        assert_eq!(w.last(), Some(&0));
        assert!((p.length(&w) - 8.0).abs() < 1e-9, "walk {w:?}");
    }

    #[test]
    fn spread_walk_uses_the_budget_and_reaches_further_than_the_baseline() {
        let b = lattice();
        let p = problem(&b, 16.0);
        let run = Run::new(Control::new(), None);
        let base = build(&p, 0.0, false, &run);
        let spread = spread_walk(&p, 2.5, &run);
        p.check(&spread).expect("feasible");
        // Uses the budget to within one edge (2 m) ...
        assert!(p.length(&spread) > 16.0 - 2.0 - 1e-9);
        // ... and its farthest vertex from the start is at least as far as the baseline's.
        let far = |w: &[usize]| w.iter().map(|&v| p.metric.dist(0, v)).fold(0.0, f64::max);
        assert!(far(&spread) >= far(&base), "{spread:?} vs {base:?}");
    }

    #[test]
    fn unpace_goes_round_instead_of_walking_back_when_the_budget_allows() {
        let b = lattice();
        // v00 -> v01 -> v02 and straight back: a reversal at v02 (which has three
        // neighbours).
        let walk = vec![0, 1, 2, 1, 0];
        let tight = problem(&b, 8.0);
        assert_eq!(reversals(&tight, &walk), 1);
        assert_eq!(unpace(&tight, &walk), walk, "no room to go round in 8 m");
        let roomy = problem(&b, 12.0);
        let w = unpace(&roomy, &walk);
        assert_eq!(reversals(&roomy, &w), 0, "{w:?}");
        assert_eq!((w[0], *w.last().expect("walk")), (0, 0));
        assert!(roomy.length(&w) <= 12.0 + 1e-9, "{w:?}");
        assert!(w.windows(2).all(|e| b.edge_between(e[0], e[1]).is_some()));
    }

    #[test]
    fn unpace_drops_a_spur_walked_again_elsewhere() {
        let b = lattice();
        // v00 -> v01 -> v00 -> v01 -> v11 -> v10 -> v00: edge v00-v01 three times.
        let walk = vec![0, 1, 0, 1, 5, 4, 0];
        let p = problem(&b, 100.0);
        assert_eq!(reversals(&p, &walk), 2);
        let w = unpace(&p, &walk);
        assert_eq!(w, vec![0, 1, 5, 4, 0]);
    }

    #[test]
    fn radii_that_mark_the_same_edges_build_the_same_walks() {
        // Uneven spacings: many different distances between an edge and a midpoint.
        let b = lattice_at([0.0, 2.1, 4.3, 6.2], [0.0, 2.3, 4.9]);
        let p = problem(&b, 30.0);
        let t = p.near_edges().expect("a table for radii up to ell");
        let mids: Vec<Point> = b.edges.iter().map(|e| midpoint(&b, e.a, e.b)).collect();
        let radii: Vec<f64> = (0..=40).map(|k| 0.1 * f64::from(k)).collect();
        // The count is the scan's: pairs of two edges, one's midpoint within the radius.
        for &r in &radii {
            let scan = (0..b.edges.len())
                .flat_map(|e| (0..mids.len()).map(move |k| (e, k)))
                .filter(|&(e, k)| {
                    let (pa, pb) = (&b.vertices[b.edges[e].a].pos, &b.vertices[b.edges[e].b].pos);
                    k != e && mids[k].segment_projection(pa, pb).1 <= r
                })
                .count();
            assert_eq!(t.pairs_within(r), Some(scan), "radius {r}");
        }
        let kept = distinct_radii(&p, &radii);
        assert_eq!(kept.first(), Some(&0.0), "radius 0 is always built");
        assert!(
            kept.len() > 3 && kept.len() < radii.len(),
            "{} of {} kept",
            kept.len(),
            radii.len()
        );
        // A radius left out builds what the last radius kept before it builds, with
        // either tie rule.
        let run = Run::new(Control::new(), None);
        let walk = |radius: f64, open_ties: bool| {
            let spec = Leg {
                from: 0,
                prev: None,
                to: 0,
                budget: 30.0,
                radius,
                any_fit: true,
                avoid_reversals: false,
                open_ties,
            };
            leg(&p, &spec, &[], None, &run)
        };
        for &r in radii.iter().filter(|r| !kept.contains(r)) {
            let last = *kept.iter().rfind(|&&k| k < r).expect("0 is kept");
            for open_ties in [false, true] {
                assert_eq!(
                    walk(r, open_ties),
                    walk(last, open_ties),
                    "radius {r} as {last}"
                );
            }
        }
        // Beyond the table's cap it counts nothing, and the radius is left out (its
        // marks would scan every edge per walked edge).
        assert_eq!(t.pairs_within(t.cap() * 1.5), None);
        let beyond = [0.0, t.cap(), t.cap() * 1.5];
        assert_eq!(distinct_radii(&p, &beyond), vec![0.0, t.cap()]);
        assert_eq!(tabled_radii(&p, &beyond), vec![0.0, t.cap()]);
    }

    // The generator is a research module (feature `research`, off in the phone's build).
    #[cfg(feature = "research")]
    /// A two-floor generated building: corridors, rooms of lattice cells, stairs.
    fn two_floors() -> Arc<Building> {
        let s = crate::synth::generate(&crate::synth::SynthParams {
            floors: 2,
            rooms_per_side: 3,
            corridor_length_m: 30.0,
            room_depth_m: 8.0,
            aps: 3,
            pilot: 5,
            test_points: 5,
            dense_spacing_m: 4.0,
            ..crate::synth::SynthParams::default()
        })
        .expect("generate");
        Arc::new(Building::from_file(s.file, "two floors").expect("valid"))
    }

    #[test]
    fn a_table_too_big_for_the_length_scale_is_kept_for_a_smaller_radius() {
        // 4 x 3 lattice, 17 edges: within 9 m every edge is near every other (289
        // entries), within 2.25 m fewer.
        let b = lattice();
        let all = NearEdges::new(&b, 9.0).expect("small");
        let n = |t: &NearEdges| t.idx.len();
        assert_eq!(n(&all), b.edges.len() * b.edges.len());
        // Room for every entry: the whole radius.
        let t = NearEdges::largest_within(&b, 9.0, n(&all)).expect("fits");
        assert_eq!(t.cap(), 9.0);
        // Room for fewer: the largest of 9 / 2, 9 / 4 and 9 / 8 whose table fits, and it
        // is that radius's table.
        let quarter = NearEdges::new(&b, 2.25).expect("small");
        let t = NearEdges::largest_within(&b, 9.0, n(&quarter)).expect("a smaller radius");
        assert_eq!(t.cap(), 2.25);
        assert_eq!(
            (&t.start, &t.idx, &t.dist),
            (&quarter.start, &quarter.idx, &quarter.dist)
        );
        // Room for less than an eighth's: none.
        let eighth = NearEdges::new(&b, 1.125).expect("small");
        assert!(NearEdges::largest_within(&b, 9.0, n(&eighth) - 1).is_none());
    }

    // The generator is a research module (feature `research`, off in the phone's build).
    #[cfg(feature = "research")]
    #[test]
    fn near_edge_table_lists_exactly_the_edges_a_scan_marks() {
        let b = two_floors();
        let t = NearEdges::new(&b, 9.0).expect("small enough to keep");
        let mids: Vec<Point> = b.edges.iter().map(|e| midpoint(&b, e.a, e.b)).collect();
        for radius in [0.5, 2.0, 4.5, 9.0] {
            for (e, ed) in b.edges.iter().enumerate() {
                let (pa, pb) = (&b.vertices[ed.a].pos, &b.vertices[ed.b].pos);
                let scan: Vec<usize> = (0..mids.len())
                    .filter(|&k| {
                        (mids[k].floor == pa.floor || mids[k].floor == pb.floor)
                            && mids[k].segment_projection(pa, pb).1 <= radius
                    })
                    .collect();
                let mut listed: Vec<usize> = t.within(e, radius).collect();
                listed.sort_unstable();
                assert_eq!(listed, scan, "edge {e}, radius {radius}");
            }
        }
        // A stair edge's list holds edges of both its floors.
        let stair = b
            .edges
            .iter()
            .position(|e| b.vertices[e.a].pos.floor != b.vertices[e.b].pos.floor)
            .expect("a stair edge");
        let floors: std::collections::BTreeSet<i64> =
            t.within(stair, 9.0).map(|k| mids[k].floor).collect();
        assert_eq!(floors.len(), 2, "{floors:?}");
    }

    // The generator is a research module (feature `research`, off in the phone's build).
    #[cfg(feature = "research")]
    #[test]
    fn spread_walks_are_the_same_with_and_without_the_near_edge_table() {
        let b = two_floors();
        let run = Run::new(Control::new(), None);
        let with = problem(&b, 0.4 * b.total_edge_length());
        assert!(with.near_edges().is_some());
        let without = Problem {
            near: Arc::new(OnceLock::from(None)),
            ..with.clone()
        };
        assert!(without.near_edges().is_none());
        // Radii up to the table's cap (the kernel's `ell`, 4 m) take the table, beyond it
        // the scan in both.
        for radius in [0.5, 1.0, 2.0, 4.0, 6.0] {
            let a = spread_walk(&with, radius, &run);
            with.check(&a).expect("feasible");
            assert_eq!(a, spread_walk(&without, radius, &run), "radius {radius}");
        }
    }
}

//! Steiner TSP paths: the shortest walk from `s` to `t` that visits every vertex of a
//! required set, on the metric closure ([`Metric`]).
//!
//! Small sets are solved exactly by the Held-Karp dynamic programme; larger ones by
//! cheapest insertion followed by 2-opt and or-opt moves (a local optimum, not
//! necessarily the optimum).
//!
//! Reference: M. Held, R. M. Karp, "A dynamic programming approach to sequencing
//! problems", J. SIAM 10(1), 1962.

use super::metric::Metric;

/// Largest required set (besides `s` and `t`) solved exactly.
pub const EXACT_LIMIT: usize = 12;

/// The required vertices of `req` without duplicates and without `s` and `t`, in first
/// appearance order.
pub fn normalise(s: usize, t: usize, req: &[usize]) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::with_capacity(req.len());
    for &v in req {
        if v != s && v != t && !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

/// The optimal visiting order of `req` (which must hold neither `s`, `t` nor
/// duplicates) and its cost, by Held-Karp.
///
/// # Complexity
/// `O(2^k k^2)` time and `O(2^k k)` memory for `k = req.len()`; use for `k <= 16`.
pub fn held_karp(m: &Metric, s: usize, t: usize, req: &[usize]) -> (Vec<usize>, f64) {
    let k = req.len();
    if k == 0 {
        return (Vec::new(), m.dist(s, t));
    }
    let full = (1usize << k) - 1;
    let mut dp = vec![f64::INFINITY; (full + 1) * k];
    let mut from = vec![u8::MAX; (full + 1) * k];
    for (i, &v) in req.iter().enumerate() {
        dp[(1 << i) * k + i] = m.dist(s, v);
    }
    let d: Vec<f64> = (0..k * k).map(|x| m.dist(req[x / k], req[x % k])).collect();
    for mask in 1..=full {
        for last in 0..k {
            if mask & (1 << last) == 0 {
                continue;
            }
            let cur = dp[mask * k + last];
            if !cur.is_finite() {
                continue;
            }
            let mut rest = full & !mask;
            while rest != 0 {
                let nx = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let nm = mask | (1 << nx);
                let c = cur + d[last * k + nx];
                if c < dp[nm * k + nx] {
                    dp[nm * k + nx] = c;
                    from[nm * k + nx] = last as u8;
                }
            }
        }
    }
    let mut best = (f64::INFINITY, 0);
    for last in 0..k {
        let c = dp[full * k + last] + m.dist(req[last], t);
        if c < best.0 {
            best = (c, last);
        }
    }
    let mut order = Vec::with_capacity(k);
    let (mut mask, mut last) = (full, best.1);
    loop {
        order.push(req[last]);
        let p = from[mask * k + last];
        mask &= !(1 << last);
        if p == u8::MAX {
            break;
        }
        last = p as usize;
    }
    order.reverse();
    (order, best.0)
}

/// Inserts `v` into `order` at the position where it adds the least length.
pub fn cheapest_insertion(m: &Metric, s: usize, t: usize, order: &mut Vec<usize>, v: usize) {
    let mut best = (f64::INFINITY, 0);
    let mut prev = s;
    for i in 0..=order.len() {
        let nx = if i < order.len() { order[i] } else { t };
        let c = m.dist(prev, v) + m.dist(v, nx) - m.dist(prev, nx);
        if c < best.0 {
            best = (c, i);
        }
        prev = nx;
    }
    order.insert(best.1, v);
}

/// Improves `order` by 2-opt (segment reversal) and or-opt (moving a segment of one to
/// three vertices, either way round) until no move shortens it by more than 1e-9 or
/// `max_rounds` rounds have passed. Returns the new cost.
///
/// # Complexity
/// `O(k^2)` per 2-opt round and `O(k^2)` per or-opt round.
pub fn improve(m: &Metric, s: usize, t: usize, order: &mut Vec<usize>, max_rounds: usize) -> f64 {
    let k = order.len();
    let at = |o: &[usize], i: usize| -> usize {
        // Position 0 is s, 1..=k the order, k + 1 is t.
        if i == 0 {
            s
        } else if i > o.len() {
            t
        } else {
            o[i - 1]
        }
    };
    for _ in 0..max_rounds {
        let mut improved = false;
        // 2-opt: reverse positions i..=j (1-based within the order).
        for i in 1..=k {
            for j in i + 1..=k {
                let (a, b, c, d) = (
                    at(order, i - 1),
                    at(order, i),
                    at(order, j),
                    at(order, j + 1),
                );
                let delta = m.dist(a, c) + m.dist(b, d) - m.dist(a, b) - m.dist(c, d);
                if delta < -1e-9 {
                    order[i - 1..j].reverse();
                    improved = true;
                }
            }
        }
        // Or-opt: move a segment of length 1..=3 elsewhere, possibly reversed.
        for len in 1..=3.min(k) {
            let mut i = 1;
            while i + len - 1 <= k {
                let (p, a, b, n) = (
                    at(order, i - 1),
                    at(order, i),
                    at(order, i + len - 1),
                    at(order, i + len),
                );
                let removed = m.dist(p, a) + m.dist(b, n) - m.dist(p, n);
                let seg: Vec<usize> = order[i - 1..i - 1 + len].to_vec();
                let mut rest: Vec<usize> = order[..i - 1].to_vec();
                rest.extend_from_slice(&order[i - 1 + len..]);
                let mut best = (-1e-9, usize::MAX, false);
                let mut prev = s;
                for q in 0..=rest.len() {
                    let nx = if q < rest.len() { rest[q] } else { t };
                    let base = m.dist(prev, nx);
                    let fwd = m.dist(prev, a) + m.dist(b, nx) - base - removed;
                    let rev = m.dist(prev, b) + m.dist(a, nx) - base - removed;
                    if fwd < best.0 {
                        best = (fwd, q, false);
                    }
                    if rev < best.0 {
                        best = (rev, q, true);
                    }
                    prev = nx;
                }
                if best.1 != usize::MAX {
                    let mut seg = seg;
                    if best.2 {
                        seg.reverse();
                    }
                    let q = best.1;
                    let mut o = rest[..q].to_vec();
                    o.extend_from_slice(&seg);
                    o.extend_from_slice(&rest[q..]);
                    *order = o;
                    improved = true;
                }
                i += 1;
            }
        }
        if !improved {
            break;
        }
    }
    m.tour_cost(s, order, t)
}

/// A good visiting order of `req` from `s` to `t`, and its cost: Held-Karp when at most
/// [`EXACT_LIMIT`] vertices are required, else cheapest insertion (in the given order)
/// improved by [`improve`].
pub fn steiner_order(m: &Metric, s: usize, t: usize, req: &[usize]) -> (Vec<usize>, f64) {
    let req = normalise(s, t, req);
    if req.len() <= EXACT_LIMIT {
        return held_karp(m, s, t, &req);
    }
    let mut order = Vec::with_capacity(req.len());
    for &v in &req {
        cheapest_insertion(m, s, t, &mut order, v);
    }
    let c = improve(m, s, t, &mut order, 50);
    (order, c)
}

/// Like [`steiner_order`], but for a large set starts from `hint` (a good order of all
/// required vertices but `extra`) and inserts `extra`: much faster when a set grows one
/// vertex at a time.
pub fn steiner_order_with(
    m: &Metric,
    s: usize,
    t: usize,
    hint: &[usize],
    extra: usize,
) -> (Vec<usize>, f64) {
    let mut req = normalise(s, t, hint);
    if extra == s || extra == t || req.contains(&extra) {
        let c = m.tour_cost(s, &req, t);
        return (req, c);
    }
    if req.len() < EXACT_LIMIT {
        req.push(extra);
        return held_karp(m, s, t, &req);
    }
    cheapest_insertion(m, s, t, &mut req, extra);
    let c = improve(m, s, t, &mut req, 50);
    (req, c)
}

/// The Steiner TSP path itself: the expanded walk `s -> req... -> t` and its length.
pub fn steiner_walk(m: &Metric, s: usize, t: usize, req: &[usize]) -> (Vec<usize>, f64) {
    let (order, c) = steiner_order(m, s, t, req);
    (m.expand(s, &order, t), c)
}

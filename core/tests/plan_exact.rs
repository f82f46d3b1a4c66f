//! The exact search against plain enumeration, and the Steiner TSP DP against brute force.

use crate::plan_common;

use plan_common::{brute_force, grid, problem};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use trailprint::plan::exact::Exact;
use trailprint::plan::steiner::{held_karp, improve, steiner_order};
use trailprint::plan::{Control, Metric, Run, Solver, Termination};

#[test]
fn exact_equals_brute_force_on_tiny_buildings() {
    // Closed and open walks, on a full grid (transposition rule valid: 2 m edges, 0.5 m
    // spacing) and on a grid with edges removed.
    let cases = [
        (grid(3, 3, 2.0, &[]), 0, 0, 12.0),
        (grid(3, 3, 2.0, &[]), 0, 8, 11.0),
        (grid(3, 2, 2.0, &[1]), 1, 4, 10.5),
        (grid(4, 2, 1.5, &[3, 5]), 0, 0, 10.0),
        (grid(3, 3, 2.0, &[]), 4, 4, 16.0),
        (grid(4, 3, 2.0, &[4]), 0, 11, 15.0),
    ];
    for (b, s, t, budget) in cases {
        let p = problem(&b, s, t, budget);
        let (bf, _) = brute_force(&p);
        let run = Run::new(Control::new(), None);
        let ex = Exact::new().solve(&p, &run).expect("exact");
        assert_eq!(ex.termination, Termination::Optimal);
        assert_eq!(ex.optimal, Some(true));
        assert!(
            (ex.utility - bf).abs() < 1e-9,
            "exact {} vs brute force {bf} (s={s}, t={t}, B={budget})",
            ex.utility
        );
        assert!((p.utility(&ex.walk).expect("u") - ex.utility).abs() < 1e-9);
        // The pruning rules do prune.
        let plain = Exact::brute_force().solve(&p, &run).expect("plain");
        assert!((plain.utility - bf).abs() < 1e-9);
        assert!(ex.nodes.expect("nodes") <= plain.nodes.expect("nodes"));
    }
}

fn perms(v: &mut Vec<usize>, k: usize, out: &mut Vec<Vec<usize>>) {
    if k == v.len() {
        out.push(v.clone());
        return;
    }
    for i in k..v.len() {
        v.swap(k, i);
        perms(v, k + 1, out);
        v.swap(k, i);
    }
}

#[test]
fn held_karp_is_optimal_against_brute_force() {
    let b = grid(5, 4, 1.0, &[2, 7, 11, 13, 17, 23]);
    let m = Metric::new(&b);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for case in 0..25 {
        let n = b.len();
        let s = rng.random_range(0..n);
        let t = rng.random_range(0..n);
        let k = 1 + case % 6;
        let mut req: Vec<usize> = Vec::new();
        while req.len() < k {
            let v = rng.random_range(0..n);
            if v != s && v != t && !req.contains(&v) {
                req.push(v);
            }
        }
        let mut all = Vec::new();
        perms(&mut req.clone(), 0, &mut all);
        let best = all
            .iter()
            .map(|o| m.tour_cost(s, o, t))
            .fold(f64::INFINITY, f64::min);
        let (order, c) = held_karp(&m, s, t, &req);
        assert!(
            (c - best).abs() < 1e-9,
            "held-karp {c} vs brute force {best}"
        );
        assert!((m.tour_cost(s, &order, t) - c).abs() < 1e-9);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        let mut want = req.clone();
        want.sort_unstable();
        assert_eq!(sorted, want);
        // The dispatcher agrees, and the heuristic never beats the optimum.
        let (_, c2) = steiner_order(&m, s, t, &req);
        assert!((c2 - best).abs() < 1e-9);
        let mut o = req.clone();
        let c3 = improve(&m, s, t, &mut o, 50);
        assert!(c3 >= best - 1e-9);
        // The expanded walk is real and as long as the tour.
        let w = m.expand(s, &order, t);
        b.check_walk(&w).expect("walk");
        assert!((b.walk_length(&w) - c).abs() < 1e-9);
    }
}

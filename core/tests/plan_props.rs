//! Every planner returns a real walk from the start to the end within the budget.

use crate::plan_common;

use plan_common::{grid, request};
use proptest::prelude::*;
use trailprint::plan::{Algorithm, Control, plan};

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    #[test]
    fn every_planner_returns_a_feasible_walk(
        w in 2usize..5, h in 2usize..4, drop in proptest::collection::vec(0usize..40, 0..4),
        s in 0usize..20, t in 0usize..20, extra in 0.0f64..12.0, seed in 0u64..1000,
    ) {
        let b = grid(w, h, 2.0, &drop);
        let n = b.len();
        let (s, t) = (s % n, t % n);
        let m = trailprint::plan::Metric::new(&b);
        let budget = m.dist(s, t) + extra + 0.5;
        for alg in Algorithm::ALL {
            let mut req = request(&b, s, t, budget, alg);
            req.seed = seed;
            if alg == Algorithm::Exact || alg == Algorithm::RecursiveGreedy {
                req.time_limit = Some(std::time::Duration::from_millis(1500));
            }
            let r = plan(b.clone(), &req, &Control::new()).expect("plan");
            let walk = &r.walk_indices;
            prop_assert_eq!(walk[0], s);
            prop_assert_eq!(*walk.last().expect("non-empty"), t);
            b.check_walk(walk).expect("real edges");
            prop_assert!(b.walk_length(walk) <= budget + 1e-9, "{alg}: {} > {budget}", b.walk_length(walk));
            prop_assert!((r.length_m - b.walk_length(walk)).abs() < 1e-9);
            prop_assert_eq!(&r.walk, &b.walk_ids(walk));
            // The reported utility is the walk's.
            let e = trailprint::utility::UtilityEngine::new(b.clone(), req.kernel, req.model).expect("engine");
            let u = e.utility(walk).expect("utility");
            prop_assert!((u - r.utility_nats).abs() < 1e-9 * u.abs().max(1.0), "{alg}: {u} vs {}", r.utility_nats);
        }
    }
}

//! Every planner returns a real walk from the start to the end within the budget.

use crate::plan_common;

use plan_common::{every_algorithm_is_sound, random_grid_case};
use proptest::prelude::*;
use trailprint::plan::Algorithm;

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    #[test]
    fn every_planner_returns_a_feasible_walk(
        w in 2usize..5, h in 2usize..4, drop in proptest::collection::vec(0usize..40, 0..4),
        s in 0usize..20, t in 0usize..20, extra in 0.0f64..12.0, seed in 0u64..1000,
    ) {
        let (b, ends, budget) = random_grid_case((w, h, &drop), (s, t), extra + 0.5);
        every_algorithm_is_sound(&b, ends, budget, seed, |alg| {
            matches!(alg, Algorithm::Exact | Algorithm::RecursiveGreedy)
                .then(|| std::time::Duration::from_millis(1500))
        });
    }
}

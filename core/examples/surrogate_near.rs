//! How well `Surrogate::value_near` (a move's candidate scored from the frame of the walk
//! it was drawn from) agrees with the whole-walk surrogate value, and what each costs:
//! the figures of decision 0003's frame addendum.
//!
//!     cargo run --release -p trailprint-core --example surrogate_near [-- human]
//!
//! On the generated campus (290 vertices, two floors) and mall (565), budgets of 25%, 50%
//! and 100% of the edge length: from the spread construction of the whole budget, 300
//! moves as the search draws them without a cut (a stretch of 2 to 25 vertices rebuilt by
//! a randomised spread leg that counts the rest of the walk as walked). For each move,
//! the change of the surrogate value by `value_near` and by a whole evaluation; printed:
//! their mean absolute difference beside the mean absolute change, the share of pairs of
//! moves whose whole changes differ by more than 0.2 nats that `value_near` orders the
//! same way, how many moves improve by each, and the time per evaluation of both.

use std::time::{Duration, Instant};

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use trailprint::plan::coverage::{Leg, leg};
use trailprint::plan::scale::Surrogate;
use trailprint::plan::{Control, Problem, Run};

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let (human, model) = cases::model_from_args();
    cases::table_head(&[
        "building",
        "model",
        "budget",
        "moves",
        "mean abs change",
        "mean abs error",
        "pairs >0.2 nats apart ordered alike",
        "improving (whole / both / near only)",
        "near us",
        "whole us",
    ]);
    for (name, b, kernel) in cases::fitted()? {
        for frac in [0.25, 0.5, 1.0] {
            let budget = frac * b.total_edge_length();
            let p = Problem::new(b.clone(), kernel, model, 0, 0, budget)?;
            let sur = Surrogate::new(&p)?;
            let run = Run::new(Control::new(), None);
            let whole_leg = Leg {
                from: 0,
                prev: None,
                to: 0,
                budget,
                radius: 0.0,
                any_fit: true,
                avoid_reversals: human,
                open_ties: true,
            };
            let base = leg(&p, &whole_leg, &[], None, &run);
            let frame = sur.frame(&base)?;
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            let (mut t_near, mut t_whole) = (Duration::ZERO, Duration::ZERO);
            let mut rows: Vec<(f64, f64)> = Vec::new();
            let n = base.len();
            for _ in 0..300 {
                let span = rng.random_range(2..25usize.min(n - 2));
                let i = rng.random_range(0..n - span - 1);
                let j = i + span;
                let (head, tail) = (&base[..=i], &base[j..]);
                let mut context = head.to_vec();
                context.extend_from_slice(tail);
                let spec = Leg {
                    from: base[i],
                    prev: i.checked_sub(1).map(|k| base[k]),
                    to: base[j],
                    budget: (budget - p.length(head) - p.length(tail)).max(0.0),
                    radius: [0.0, 0.25, 0.5, 1.0][rng.random_range(0..4)] * kernel.ell,
                    open_ties: rng.random_bool(0.5),
                    ..whole_leg
                };
                let mid = leg(&p, &spec, &context, Some(&mut rng), &run);
                let mut w = head.to_vec();
                w.extend_from_slice(&mid[1..]);
                w.extend_from_slice(&tail[1..]);
                let t0 = Instant::now();
                let near = sur.value_near(&frame, &w)?;
                t_near += t0.elapsed();
                let t0 = Instant::now();
                let whole = sur.value(&w)?;
                t_whole += t0.elapsed();
                rows.push((near - frame.value(), whole - frame.value()));
            }
            let m = rows.len() as f64;
            let change = rows.iter().map(|r| r.1.abs()).sum::<f64>() / m;
            let error = rows.iter().map(|r| (r.0 - r.1).abs()).sum::<f64>() / m;
            let (mut pairs, mut alike) = (0usize, 0usize);
            for a in 0..rows.len() {
                for c in 0..a {
                    if (rows[a].1 - rows[c].1).abs() > 0.2 {
                        pairs += 1;
                        alike +=
                            usize::from((rows[a].0 - rows[c].0) * (rows[a].1 - rows[c].1) > 0.0);
                    }
                }
            }
            let up = rows.iter().filter(|r| r.1 > 0.0).count();
            let both = rows.iter().filter(|r| r.1 > 0.0 && r.0 > 0.0).count();
            let near_only = rows.iter().filter(|r| r.1 <= 0.0 && r.0 > 0.0).count();
            println!(
                "| {name} ({} vertices) | {} | {budget:.0} m | {} | {change:.3} | {error:.3} | {:.1}% of {pairs} | {up} / {both} / {near_only} | {:.0} | {:.0} |",
                b.len(),
                if human { "human" } else { "robot" },
                rows.len(),
                100.0 * alike as f64 / pairs.max(1) as f64,
                t_near.as_secs_f64() * 1e6 / m,
                t_whole.as_secs_f64() * 1e6 / m,
            );
        }
    }
    Ok(())
}

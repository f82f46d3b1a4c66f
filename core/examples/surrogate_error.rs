//! How well the large-building search surrogate (`plan::scale::Surrogate`) ranks walks,
//! and what it costs: the figures of `docs/decisions/0003-search-surrogate.md`.
//!
//!     cargo run --release -p trailprint-core --example surrogate_error [-- human] [-- CAP:SPAN ...]
//!
//! On a generated mall (565 vertices) and a two-floor campus (290), draws 120 candidate
//! walks the way the search does (randomised spread constructions at 25% and 50% of the
//! edge length), evaluates each exactly and by the surrogate, and prints the rank
//! correlation (Spearman), the share of pairs ordered the same way (Kendall's
//! concordance), the share of pairs whose exact values differ by more than 2% that the
//! surrogate orders the same way, the mean relative error, and the time per evaluation of
//! both. Each `OBS:VERTICES` argument adds the rows of another surrogate
//! (`Surrogate::with`: each vertex conditioned on `OBS` observations and `VERTICES`
//! earlier vertices) beside the search's own.

use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use trailprint::plan::coverage::{Leg, leg};
use trailprint::plan::scale::Surrogate;
use trailprint::plan::{Control, Problem, Run};

#[path = "common/cases.rs"]
mod cases;

fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    for (k, &i) in idx.iter().enumerate() {
        r[i] = k as f64;
    }
    r
}

fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

/// The value `f` gives each walk, and the mean time it took per walk in milliseconds.
fn timed_values(
    walks: &[Vec<usize>],
    f: impl Fn(&[usize]) -> trailprint::Result<f64>,
) -> trailprint::Result<(Vec<f64>, f64)> {
    let t0 = Instant::now();
    let values = walks
        .iter()
        .map(|w| f(w.as_slice()))
        .collect::<trailprint::Result<_>>()?;
    Ok((
        values,
        t0.elapsed().as_secs_f64() * 1e3 / walks.len() as f64,
    ))
}

fn main() -> trailprint::Result<()> {
    let (human, model) = cases::model_from_args();
    // Other surrogates to measure beside the search's own: `OBS:VERTICES` arguments.
    let others: Vec<(usize, usize)> = std::env::args()
        .filter_map(|a| {
            let (c, s) = a.split_once(':')?;
            Some((c.parse().ok()?, s.parse().ok()?))
        })
        .collect();
    cases::table_head(&[
        "building",
        "surrogate",
        "model",
        "budget",
        "walks",
        "Spearman",
        "concordant pairs",
        "concordant pairs >2% apart",
        "mean relative error",
        "surrogate ms",
        "exact ms",
    ]);
    for (name, b, kernel) in cases::fitted()? {
        let total = b.total_edge_length();
        for frac in [0.25, 0.5] {
            let budget = frac * total;
            let p = Problem::new(b.clone(), kernel, model, 0, 0, budget)?;
            let run = Run::new(Control::new(), None);
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            let ell = kernel.ell;
            let walks: Vec<Vec<usize>> = (0..120)
                .map(|k| {
                    let spec = Leg {
                        from: 0,
                        prev: None,
                        to: 0,
                        budget,
                        radius: [0.0, 0.125, 0.25, 0.5, 1.0][k % 5] * ell,
                        any_fit: true,
                        avoid_reversals: human,
                        // Both tie rules, as the search draws them.
                        open_ties: k % 2 == 1,
                    };
                    leg(&p, &spec, &[], Some(&mut rng), &run)
                })
                .collect();
            let (e, te) = timed_values(&walks, |w| p.utility(w))?;
            let mut surrogates = vec![("search".to_string(), Surrogate::new(&p)?)];
            for &(o, v) in &others {
                surrogates.push((format!("{o}:{v}"), Surrogate::with(&p, o, v)?));
            }
            for (label, sur) in surrogates {
                let (s, ts) = timed_values(&walks, |w| sur.value(w))?;
                let rho = pearson(&ranks(&s), &ranks(&e));
                let (mut conc, mut pairs, mut conc2, mut pairs2) = (0usize, 0usize, 0usize, 0usize);
                for i in 0..walks.len() {
                    for j in i + 1..walks.len() {
                        let same = (s[i] - s[j]) * (e[i] - e[j]) > 0.0;
                        pairs += 1;
                        conc += usize::from(same);
                        if (e[i] - e[j]).abs() > 0.02 * e[i].max(e[j]) {
                            pairs2 += 1;
                            conc2 += usize::from(same);
                        }
                    }
                }
                let rel = s
                    .iter()
                    .zip(&e)
                    .map(|(a, b)| ((a - b) / b).abs())
                    .sum::<f64>()
                    / e.len() as f64;
                println!(
                    "| {name} ({} vertices) | {label}: {} observations, {} vertices | {} | {budget:.0} m | {} | {rho:.3} | {:.1}% | {:.1}% of {pairs2} | {:.1}% | {ts:.2} | {te:.2} |",
                    b.len(),
                    sur.observations(),
                    sur.earlier_vertices(),
                    if human { "human" } else { "robot" },
                    walks.len(),
                    100.0 * conc as f64 / pairs as f64,
                    100.0 * conc2 as f64 / pairs2.max(1) as f64,
                    100.0 * rel,
                );
            }
        }
    }
    Ok(())
}

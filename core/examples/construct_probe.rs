//! Exact and surrogate values of the spread constructions over a grid of novelty radii
//! (development aid): how much the choice of radius matters, and whether the surrogate
//! ranks the constructions as `f_D` does.
//!
//! `cargo run --release -p trailprint-core --example construct_probe -- FILE START END
//! BUDGET robot|human [RADII]` (RADII in units of the kernel's length scale, e.g.
//! `0,0.125,0.25`)
use trailprint::Error;
use trailprint::plan::coverage::{Leg, leg, unpace};
use trailprint::plan::{Control, Problem, Run};
use trailprint::samples::Surveyor;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(6, "construct_probe FILE START END BUDGET robot|human")?;
    let (b, kernel) = cases::load_with_kernel(&a[1])?;
    let model = cases::model_named(&a[5]);
    let (start, end) = (b.require_vertex(&a[2])?, b.require_vertex(&a[3])?);
    let budget: f64 = a[4]
        .parse()
        .map_err(|_| Error::InvalidRequest(format!("budget: {}", a[4])))?;
    let p = Problem::new(b.clone(), kernel, model, start, end, budget)?;
    let human = matches!(model, Surveyor::Human { .. });
    let run = Run::new(Control::new(), None);
    let sur = trailprint::plan::scale::Surrogate::new(&p)?;
    println!("ell {:.2}", kernel.ell);
    // The radii (in units of ell) from the sixth argument, comma-separated, else a grid.
    let radii: Vec<f64> = a
        .get(6)
        .map_or(
            "0,0.04,0.0625,0.09,0.11,0.125,0.14,0.16,0.19,0.22,0.25,0.5",
            |s| s,
        )
        .split(',')
        .map(|x| {
            x.parse()
                .map_err(|_| Error::InvalidRequest(format!("radius: {x}")))
        })
        .collect::<trailprint::Result<_>>()?;
    for open_ties in [false, true] {
        for &f in &radii {
            let spec = Leg {
                from: start,
                prev: None,
                to: end,
                budget,
                radius: f * kernel.ell,
                any_fit: true,
                avoid_reversals: human,
                open_ties,
            };
            let mut w = leg(&p, &spec, &[], None, &run);
            if human {
                w = unpace(&p, &w);
            }
            println!(
                "open_ties {open_ties} radius {f:5.3} ell: {:.2} nats, surrogate {:.2}, {:.1} m",
                p.utility(&w)?,
                sur.value(&w)?,
                p.length(&w)
            );
        }
    }
    Ok(())
}

//! How much of a person's planned utility depends on exactly where the samples fall
//! (development aid): the walk's utility with every sample moved `delta` further along it
//! (arcs `k d + delta` instead of `k d`, label noise from the same check-ins), for 24
//! offsets over the spacing `d`, and their mean.
//!
//! Why: a surveyor's scans do not fall at exact multiples of 4.8 m (walking speed and
//! scan timing vary), while SPEC 3 scores the planned positions exactly, and with the
//! exponential kernel a sample's information about a vertex falls steeply with its
//! distance to it. `docs/benchmark-scale.md` ("Where a person's samples fall") has the
//! figures.
//!
//! `cargo run --release -p trailprint-core --example offset_probe -- FILE PLAN.json`
//! (`PLAN.json` from `trailprint plan --model human --json`).
use trailprint::gp::kernel::Point;
use trailprint::samples::{Surveyor, is_turn_checkin, point_on_edge};
use trailprint::utility::Observation;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let a = cases::args_or_usage(3, "offset_probe FILE PLAN.json")?;
    let (p, walk) = cases::plan_problem(&a[1], &a[2], "human", 1e9)?;
    let b = p.building.clone();
    let kernel = *p.engine.kernel();
    let Surveyor::Human {
        speed_mps,
        scan_interval_s,
        step_error,
        turn_threshold_deg,
        ..
    } = *p.engine.model()
    else {
        return Ok(());
    };
    let d = speed_mps * scan_interval_s;
    let mut arcs = vec![0.0];
    let mut checkins = vec![0.0];
    for k in 0..walk.len() - 1 {
        let l = b.edge_between(walk[k], walk[k + 1]).expect("edge").length;
        arcs.push(arcs[k] + l);
        if k + 2 < walk.len()
            && (is_turn_checkin(&b, walk[k], walk[k + 1], walk[k + 2], turn_threshold_deg)
                || b.vertices[walk[k]].pos.floor != b.vertices[walk[k + 1]].pos.floor)
        {
            checkins.push(arcs[k + 1]);
        }
    }
    let total = arcs[arcs.len() - 1];
    let mut vals = Vec::new();
    for step in 0..24 {
        let delta = d * step as f64 / 24.0;
        let mut obs = Vec::new();
        let mut k = 0usize;
        let mut s = delta;
        while s <= total + 1e-9 {
            while k + 2 < arcs.len() && arcs[k + 1] < s - 1e-9 {
                k += 1;
            }
            let l = arcs[k + 1] - arcs[k];
            let f = if l > 0.0 {
                ((s - arcs[k]) / l).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let pos: Point =
                point_on_edge(&b.vertices[walk[k]].pos, &b.vertices[walk[k + 1]].pos, f);
            let last = checkins
                .iter()
                .rev()
                .find(|&&c| c <= s + 1e-9)
                .copied()
                .unwrap_or(0.0);
            obs.push(Observation {
                pos,
                extra_noise: kernel.label_noise(step_error * (s - last)),
            });
            s += d;
        }
        vals.push(p.engine.utility_of_observations(&obs)?);
    }
    let mean = vals.iter().sum::<f64>() / vals.len() as f64;
    let min = vals.iter().cloned().fold(f64::INFINITY, f64::min);
    println!(
        "{}: at 0 {:.2}, mean over 24 offsets {mean:.2}, min {min:.2}",
        a[2], vals[0]
    );
    Ok(())
}

//! Cost per scan event of a session's progress figures at 300, 3,000 and 10,000 samples:
//! the running posterior (`session::IncrementalPosterior`, what `Session::progress` reads)
//! against the from-scratch evaluation that `progress()` used to run on every call.
//!
//! Samples are a robot's, every 0.5 m along a seeded random walk on a generated 132-vertex
//! office floor (the building of issue 16), with the demo kernel. For each size it times
//! 20 scans (add one sample, then read the utility and the coverage map, as the progress
//! screen does) and one from-scratch evaluation of the same samples (dense path of the
//! utility engine). It also reports the time to build the posterior up to that size
//! sample by sample (what resuming such a session costs) and the memory the factors hold.
//!
//! A second table runs the same walk to 20,000 samples with the memory budget of a
//! session (`memory_budget_mb`, half of it for the running posterior): the default
//! 512 MiB and a phone's 128 MiB. Past the rows a budget allows, the posterior keeps one
//! sample of every `k` (`session::posterior`); the table shows `k`, the memory held, the
//! time to take all the samples at once (what resuming the session costs), the time per
//! scan after that, and the utility against the exact one of all samples (from the
//! unbounded posterior of the first table, up to 10,000 samples).
//!
//! Run: `cargo run --release -p trailprint-core --example session_progress`

use std::sync::Arc;
use std::time::Instant;

use trailprint::Building;
use trailprint::gp::{Kernel, Point};
use trailprint::session::IncrementalPosterior;
use trailprint::surveyor::Surveyor;
use trailprint::synth::{SynthParams, generate};
use trailprint::utility::UtilityEngine;

#[path = "common/cases.rs"]
mod cases;

fn main() -> trailprint::Result<()> {
    let params = SynthParams {
        name: "Office floor".into(),
        rooms_per_side: 7,
        corridor_length_m: 66.0,
        seed: 1,
        ..SynthParams::default()
    };
    let b: Arc<Building> = Arc::new(Building::from_file(generate(&params)?.file, "generated")?);
    let kernel = Kernel::new(62.6, 7.9, 4.2);
    println!(
        "building {:?}: {} vertices, {} pilot; kernel sf2={} ell={} sn2={}",
        b.name,
        b.len(),
        b.pilot.len(),
        kernel.sf2,
        kernel.ell,
        kernel.sn2
    );
    // A seeded random walk on the graph, sampled every 0.5 m.
    let (points, _) = cases::random_walk_samples(&b, 7, 20_020);
    let engine = UtilityEngine::new(b.clone(), kernel, Surveyor::robot())?;
    let mut post = IncrementalPosterior::new(&b, kernel, usize::MAX)?;
    let built = Instant::now();
    println!(
        "\n| samples | per scan: add + utility + coverage map | from scratch (one evaluation) | build to this size | factors held |"
    );
    println!("|---:|---:|---:|---:|---:|");
    // The unbounded posterior's utilities, for the second table.
    let mut exact_at: Vec<(usize, f64)> = Vec::new();
    for &n in &[300usize, 3_000, 10_000] {
        while post.samples() < n {
            post.add(points[post.samples()], 0.0)?;
        }
        exact_at.push((n, post.utility()));
        let build_s = built.elapsed().as_secs_f64();
        let per_scan_ms = time_scans(&mut post, &points)?;
        let obs = cases::observations(&points[..post.samples()]);
        let t = Instant::now();
        let scratch = engine.utility_of_observations(&obs)?;
        let scratch_ms = t.elapsed().as_secs_f64() * 1000.0;
        let rel = (scratch - post.utility()).abs() / scratch;
        assert!(
            rel < 1e-9,
            "incremental {} vs from scratch {scratch}",
            post.utility()
        );
        println!(
            "| {n} | {per_scan_ms:.3} ms | {scratch_ms:.1} ms | {build_s:.1} s | {:.0} MB |",
            post.memory_bytes() as f64 / 1e6
        );
    }
    drop(post);
    println!(
        "\n| memory_budget_mb | samples | kept: one of | factors held | resume (all samples at once) | per scan | utility | exact (all samples) |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    let obs: Vec<(Point, f64)> = points.iter().map(|&p| (p, 0.0)).collect();
    for mb in [512usize, 128] {
        for &n in &[3_000usize, 10_000, 20_000] {
            let mut post = IncrementalPosterior::new(&b, kernel, mb << 20)?;
            let t = Instant::now();
            post.add_all(&obs[..n])?;
            let resume_s = t.elapsed().as_secs_f64();
            let utility = post.utility();
            let per_scan_ms = time_scans(&mut post, &points)?;
            let exact = exact_at
                .iter()
                .find(|e| e.0 == n)
                .map_or("-".to_string(), |e| format!("{:.2} nats", e.1));
            println!(
                "| {mb} | {n} | {} | {:.0} MB | {resume_s:.2} s | {per_scan_ms:.3} ms | {utility:.2} nats | {exact} |",
                post.block(),
                post.memory_bytes() as f64 / 1e6,
            );
        }
    }
    Ok(())
}

/// Milliseconds per scan over 20 scans: add the next sample, then read the utility and
/// the coverage map, as the progress screen does.
fn time_scans(post: &mut IncrementalPosterior, points: &[Point]) -> trailprint::Result<f64> {
    let reps = 20;
    let t = Instant::now();
    let mut sink = 0.0;
    for _ in 0..reps {
        post.add(points[post.samples()], 0.0)?;
        sink += post.utility();
        sink += post.vertex_variance().iter().sum::<f64>();
    }
    std::hint::black_box(sink);
    Ok(t.elapsed().as_secs_f64() * 1000.0 / reps as f64)
}

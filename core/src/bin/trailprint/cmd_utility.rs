//! `trailprint utility`: `f_D(P)` of SPEC section 3 for one walk or a file of walks.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args as ClapArgs;
use trailprint::utility::UtilityEngine;
use trailprint::{Error, Result};

use crate::opts::{BuildingOpts, EvalOpts, json_line, split_walk};

#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    /// The walk as comma-separated vertex ids.
    #[arg(
        long,
        conflicts_with = "walks_file",
        required_unless_present = "walks_file"
    )]
    walk: Option<String>,
    /// A file with one comma-separated walk per line (blank lines and `#` comments skipped).
    #[arg(long)]
    walks_file: Option<PathBuf>,
    #[command(flatten)]
    eval: EvalOpts,
    /// One JSON object per walk.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    let b = Arc::new(a.building.load(db)?);
    let model = a.eval.model.model()?;
    let (kernel, source) = a.eval.kernel.resolve(&b)?;
    let walks: Vec<(String, Vec<String>)> = match (&a.walk, &a.walks_file) {
        (Some(w), _) => vec![("--walk".to_string(), split_walk(w))],
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
            text.lines()
                .enumerate()
                .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
                .map(|(i, l)| (format!("{}:{}", path.display(), i + 1), split_walk(l)))
                .collect()
        }
        (None, None) => return Err(Error::InvalidRequest("give --walk or --walks-file".into())),
    };
    // Resolve every walk first so that a bad line fails before any output.
    let mut resolved = Vec::with_capacity(walks.len());
    for (origin, ids) in &walks {
        let w = b
            .resolve_walk(ids)
            .map_err(|e| Error::InvalidRequest(format!("{origin}: {e}")))?;
        resolved.push(w);
    }
    let samples: Vec<usize> = resolved
        .iter()
        .map(|w| Ok(trailprint::samples::sample_walk(&b, w, &model, &kernel)?.len()))
        .collect::<Result<_>>()?;
    trailprint::utility::check_evaluation_memory(
        &b,
        samples.iter().copied().max().unwrap_or(0),
        rayon::current_num_threads().min(resolved.len()),
        a.eval.memory.bytes(),
    )?;
    let engine = UtilityEngine::new(b.clone(), kernel, model)?;
    let utilities = engine.utilities(&resolved);
    for (((walk, u), (origin, _)), &samples) in
        resolved.iter().zip(utilities).zip(&walks).zip(&samples)
    {
        let u = u?;
        let length = b.walk_length(walk);
        if a.json {
            let out = serde_json::json!({
                "walk": b.walk_ids(walk),
                "utility_nats": u,
                "samples": samples,
                "length_m": length,
                "kernel": kernel,
                "kernel_source": source,
            });
            println!("{}", json_line(&out)?);
        } else {
            println!(
                "{origin}: utility {u:.6} nats, {samples} samples, {length:.3} m (kernel sf2={:.4} ell={:.4} sn2={:.4}, {source})",
                kernel.sf2, kernel.ell, kernel.sn2
            );
        }
    }
    Ok(())
}

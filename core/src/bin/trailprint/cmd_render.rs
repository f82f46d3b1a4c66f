//! `trailprint render`: draw a building, a walk and the posterior uncertainty as SVG.

use std::path::PathBuf;

use clap::Args as ClapArgs;
use trailprint::render::{RenderOptions, Scene, render_svg};
use trailprint::samples::sample_walk;
use trailprint::{Error, Result};

use crate::opts::{BuildingOpts, KernelOpts, ModelOpts, split_walk};

/// Draw a building as one SVG, one panel per floor, with a heat map of the posterior
/// standard deviation given the pilot points and the walk's samples.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    /// A walk to draw, as comma-separated vertex ids.
    #[arg(long)]
    walk: Option<String>,
    #[command(flatten)]
    model: ModelOpts,
    #[command(flatten)]
    kernel: KernelOpts,
    /// Pixels per metre (default: about 1400 px wide).
    #[arg(long)]
    scale: Option<f64>,
    /// Write vertex ids.
    #[arg(long)]
    labels: bool,
    /// Leave out the heat map.
    #[arg(long)]
    no_heatmap: bool,
    /// Output SVG file (`-` for standard output).
    #[arg(short = 'o', long = "out")]
    out: PathBuf,
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    let b = a.building.load(db)?;
    let model = a.model.model()?;
    let walk = match &a.walk {
        Some(w) => b.resolve_walk(&split_walk(w))?,
        None => Vec::new(),
    };
    // The kernel is needed for the heat map and for the samples (a human's label noise).
    let kernel = if a.no_heatmap && walk.is_empty() {
        None
    } else {
        Some(a.kernel.resolve(&b)?.0)
    };
    let samples = match &kernel {
        Some(k) if !walk.is_empty() => sample_walk(&b, &walk, &model, k)?,
        _ => Vec::new(),
    };
    let scene = Scene {
        walk,
        samples,
        kernel: if a.no_heatmap { None } else { kernel },
    };
    let options = RenderOptions {
        scale_px_per_m: a.scale,
        labels: a.labels,
        heatmap: !a.no_heatmap,
        ..RenderOptions::default()
    };
    let svg = render_svg(&b, &scene, &options)?;
    if a.out.as_os_str() == "-" {
        print!("{svg}");
    } else {
        std::fs::write(&a.out, svg).map_err(|e| Error::io(&a.out, e))?;
    }
    Ok(())
}

//! `trailprint render`: draw a building, a walk and the posterior uncertainty as SVG.

use std::path::PathBuf;

use trailprint::eval::robot_samples;
use trailprint::render::{RenderOptions, Scene, render_svg};
use trailprint::{Building, Error, Result};

use crate::cmd_evaluate::{choose_kernel, parse_walk};

/// Draw a building as one SVG, one panel per floor. With a kernel (`--kernel` or the
/// building's) the panels carry a heat map of the posterior standard deviation given the
/// pilot points and the walk's samples.
#[derive(clap::Args)]
pub struct Args {
    /// Building file (survey-building/1).
    #[arg(long)]
    building: PathBuf,
    /// A walk to draw: comma-separated vertex ids.
    #[arg(long)]
    walk: Option<String>,
    /// Kernel hyperparameters `SF2,ELL,SN2` for the heat map (default: the building's).
    #[arg(long)]
    kernel: Option<String>,
    /// Distance between robot scans along the walk, metres.
    #[arg(long, default_value_t = 0.5)]
    interval: f64,
    /// Pixels per metre (default: fit about 1400 px).
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

pub fn run(args: Args) -> Result<()> {
    let building = Building::load(&args.building)?;
    let kernel = choose_kernel(args.kernel.as_deref(), &building)?;
    let walk = match &args.walk {
        Some(text) => parse_walk(text, &building)?,
        None => Vec::new(),
    };
    let samples = if walk.is_empty() {
        Vec::new()
    } else {
        robot_samples(&building, &walk, args.interval)?
    };
    if kernel.is_none() && !args.no_heatmap {
        eprintln!("note: no kernel (pass --kernel or fit first): drawing without the heat map");
    }
    let scene = Scene {
        walk,
        samples,
        kernel,
    };
    let options = RenderOptions {
        scale_px_per_m: args.scale,
        labels: args.labels,
        heatmap: !args.no_heatmap,
        ..RenderOptions::default()
    };
    let svg = render_svg(&building, &scene, &options)?;
    if args.out.as_os_str() == "-" {
        print!("{svg}");
    } else {
        std::fs::write(&args.out, svg).map_err(|e| Error::io(&args.out, e))?;
    }
    Ok(())
}

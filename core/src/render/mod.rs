//! SVG drawings of a building: its outlines, edges, vertices, stairs and pilot points, one
//! or more walks with direction arrows and step numbers, a session's walked track, sample
//! positions, and a heat map of the GP posterior standard deviation, with a legend and a
//! scale bar.
//!
//! One SVG holds one panel per floor, stacked top to bottom in the building's floor order
//! and drawn at the same scale over the same plan area, so that floors line up; a floor
//! much wider than tall (a corridor) is cut into rows like lines of text
//! ([`layout::Layout`]). The heat map is the latent posterior standard deviation (dB) of
//! the GP conditioned on the pilot locations plus the samples (only positions and noise
//! matter), on the grid of [`crate::eval::reference_grid`] and over the walkable outlines
//! of a floor plan, coloured over the range it takes.
//!
//! The SVG is plain string building: the drawing needs a few element kinds and no parsing,
//! so a dependency would add nothing. Every element carries a `class` (`edge`, `vertex`,
//! `pilot`, `sample`, `walk`, `arrow`, `heat`, `step`, `start`, `end`, `stairs`, `track`,
//! ...) for styling and tests. Each floor is drawn once, as a group in `<defs>`, and shown
//! through `<use>` in each of its rows. The parts: [`layout`] (area, scale, rows, label
//! placement), [`heat`], [`layers`] (the marks of one floor), [`panels`] (the floors'
//! drawings and their panels), [`legend`], [`style`].

use std::fmt::Write as _;

use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::samples::Sample;
use crate::{Error, Result};

mod heat;
mod layers;
mod layout;
mod legend;
mod panels;
mod style;

use heat::Heat;
use layout::{HEADING_PX, Layout, MARGIN_PX};
use legend::Legend;
pub(crate) use style::esc;

/// One walk to draw, with its name in the legend.
#[derive(Debug, Clone, Default)]
pub struct WalkLayer {
    /// Vertex indices.
    pub walk: Vec<usize>,
    /// Legend text ("planned walk", "surveyor 2: 118 m").
    pub name: String,
}

/// What to draw on top of the building.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// Walks (a team's one colour each); the first one's steps are numbered when it is
    /// the only one.
    pub walks: Vec<WalkLayer>,
    /// Samples ([`crate::samples::sample_walk`], or a session's collected scans); their
    /// label noise counts in the heat map.
    pub samples: Vec<Sample>,
    /// A walked track (a session's estimated positions in order), drawn dashed.
    pub track: Vec<Point>,
    /// Kernel for the heat map (`None`: no heat map).
    pub kernel: Option<Kernel>,
    /// A line under the heading (what is drawn: "plan 3, auto, 118.2 m, 61.3 nats").
    pub caption: Option<String>,
}

impl Scene {
    /// A scene of one walk.
    pub fn one_walk(walk: Vec<usize>, name: &str) -> Scene {
        Scene {
            walks: vec![WalkLayer {
                walk,
                name: name.to_string(),
            }],
            ..Scene::default()
        }
    }
}

/// Drawing options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Pixels per metre; `None` picks one so that a row is at most about 1400 px wide, a
    /// floor at most about 1000 px tall (and at most 40 px per metre).
    pub scale_px_per_m: Option<f64>,
    /// Write vertex ids next to the vertices (where there is room).
    pub labels: bool,
    /// Draw the posterior standard deviation heat map (needs a kernel in the scene).
    pub heatmap: bool,
    /// Heat-map grid spacing, metres.
    pub grid_step_m: f64,
    /// Heat-map grid: distance kept around edges, metres.
    pub grid_margin_m: f64,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            scale_px_per_m: None,
            labels: false,
            heatmap: true,
            grid_step_m: 0.5,
            grid_margin_m: 1.5,
        }
    }
}

/// Renders the building and scene as one SVG document: the heading, one panel per floor
/// (each floor drawn once in `<defs>`, shown through a clip per row) and the legend.
pub fn render_svg(building: &Building, scene: &Scene, options: &RenderOptions) -> Result<String> {
    check_inputs(building, scene, options)?;
    // Room around the vertices for the markers and the heat map's half cells (the heat
    // map covers the vertices' bounding box, SPEC section 5, and the walkable outlines).
    let lay = Layout::new(building, 0.75, options.scale_px_per_m)?;
    let heat = Heat::compute(building, scene, options)?;
    let width = lay.width_px();
    let legend = Legend::new(building, scene, width, heat.is_some(), options);
    let caption_h = if scene.caption.is_some() { 18.0 } else { 0.0 };
    let floors_top = MARGIN_PX / 2.0 + HEADING_PX + caption_h;
    let legend_top = floors_top + lay.panel_h_px() * building.floors.len() as f64;
    let height = legend_top + legend.height(heat.as_ref()) + MARGIN_PX / 2.0;

    let mut s = String::new();
    header(&mut s, building, scene, width, height);
    panels::floor_defs(&mut s, building, scene, &lay, heat.as_ref(), options);
    panels::floor_panels(&mut s, building, scene, &lay, heat.is_some(), floors_top);
    legend.draw(&mut s, legend_top, heat.as_ref(), &lay, options, width);
    s.push_str("</svg>\n");
    Ok(s)
}

/// Checks the walks (vertices of this building, consecutive ones joined by an edge) and
/// the heat-map grid step before anything is drawn.
fn check_inputs(building: &Building, scene: &Scene, options: &RenderOptions) -> Result<()> {
    for w in &scene.walks {
        building.check_walk(&w.walk)?;
        if let Some(&v) = w.walk.iter().find(|&&v| v >= building.len()) {
            return Err(Error::InvalidWalk {
                step: 0,
                message: format!("vertex #{v} is not a vertex of {:?}", building.name),
            });
        }
    }
    if !(options.grid_step_m.is_finite() && options.grid_step_m >= 0.01) {
        return Err(Error::InvalidRequest(format!(
            "render grid step must be at least 0.01 m, got {}",
            options.grid_step_m
        )));
    }
    Ok(())
}

/// The `<svg>` element's opening, the style sheet, the background, the building's name as
/// the heading and the scene's caption under it.
fn header(s: &mut String, building: &Building, scene: &Scene, width: f64, height: f64) {
    // `write!` into a String cannot fail; the results are ignored on purpose.
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.1} {height:.1}" font-family="sans-serif">"#
    );
    let _ = writeln!(s, "<title>{}</title>", esc(&building.name));
    let _ = writeln!(s, "<defs><style>{}</style></defs>", style::CSS);
    let _ = writeln!(
        s,
        r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#fafafa"/>"##
    );
    let _ = writeln!(
        s,
        r#"<text class="heading" x="{MARGIN_PX:.1}" y="{:.1}">{}</text>"#,
        MARGIN_PX / 2.0 + 20.0,
        esc(&building.name)
    );
    if let Some(c) = &scene.caption {
        let _ = writeln!(
            s,
            r#"<text class="subtitle" x="{MARGIN_PX:.1}" y="{:.1}">{}</text>"#,
            MARGIN_PX / 2.0 + HEADING_PX + 8.0,
            esc(c)
        );
    }
}

#[cfg(test)]
mod tests;

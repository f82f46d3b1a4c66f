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
//! matter), on the grid of [`crate::eval::reference_grid`], coloured over the range it
//! takes.
//!
//! The SVG is plain string building: the drawing needs a few element kinds and no parsing,
//! so a dependency would add nothing. Every element carries a `class` (`edge`, `vertex`,
//! `pilot`, `sample`, `walk`, `arrow`, `heat`, `step`, `start`, `end`, `stairs`, `track`,
//! ...) for styling and tests. Each floor is drawn once, as a group in `<defs>`, and shown
//! through `<use>` in each of its rows. The parts: [`layout`] (area, scale, rows, label
//! placement), [`heat`], [`layers`] (the marks of one floor), [`legend`], [`style`].

use std::fmt::Write as _;

use crate::building::Building;
use crate::gp::{Kernel, Point};
use crate::samples::Sample;
use crate::{Error, Result};

mod heat;
mod layers;
mod layout;
mod legend;
mod style;

use heat::Heat;
use layout::{HEADING_PX, Layout, MARGIN_PX, Placer, TITLE_PX};
use legend::Legend;
use style::esc;

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

/// "1st", "2nd", "3rd", "4th".
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (1, x) if x != 11 => "st",
        (2, x) if x != 12 => "nd",
        (3, x) if x != 13 => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// The name of a floor as a person says it: its name, else "Floor N".
fn floor_name(building: &Building, id: i64) -> String {
    building
        .floors
        .iter()
        .find(|f| f.id == id)
        .and_then(|f| f.name.clone())
        .unwrap_or_else(|| format!("Floor {id}"))
}

/// The line under a floor's title: in which order the walk visits the floors and which
/// steps are on this one ("walked 1st: steps 1-14, 30-41"), or which surveyors walk it.
fn floor_note(building: &Building, scene: &Scene, floor: i64) -> Option<String> {
    let on = |v: usize| building.vertices[v].pos.floor == floor;
    if scene.walks.len() > 1 {
        let who: Vec<String> = scene
            .walks
            .iter()
            .enumerate()
            .filter(|(_, w)| w.walk.iter().any(|&v| on(v)))
            .map(|(i, _)| (i + 1).to_string())
            .collect();
        return Some(if who.is_empty() {
            "no surveyor walks here".into()
        } else {
            format!("walked by surveyor {}", who.join(", "))
        });
    }
    let w = &scene.walks.first()?.walk;
    // Runs of consecutive steps on this floor, and the floors in order of first visit.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (i, &v) in w.iter().enumerate() {
        if on(v) {
            match runs.last_mut() {
                Some(r) if r.1 + 1 == i + 1 => r.1 = i + 1,
                _ => runs.push((i + 1, i + 1)),
            }
        }
    }
    if runs.is_empty() {
        return Some("not on the walk".into());
    }
    let mut order: Vec<i64> = Vec::new();
    for &v in w {
        let f = building.vertices[v].pos.floor;
        if !order.contains(&f) {
            order.push(f);
        }
    }
    let rank = order.iter().position(|&f| f == floor).map_or(0, |r| r + 1);
    let list: Vec<String> = runs
        .iter()
        .map(|&(a, b)| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}-{b}")
            }
        })
        .collect();
    let steps = format!(
        "step{} {}",
        if runs.len() == 1 && runs[0].0 == runs[0].1 {
            ""
        } else {
            "s"
        },
        list.join(", ")
    );
    Some(if order.len() > 1 {
        format!("walked {}: {steps}", ordinal(rank))
    } else {
        steps
    })
}

/// Renders the building and scene as one SVG document.
pub fn render_svg(building: &Building, scene: &Scene, options: &RenderOptions) -> Result<String> {
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
    // Room around the vertices for the markers and the heat map's half cells (the heat
    // map covers the vertices' bounding box, SPEC section 5).
    let lay = Layout::new(building, 0.75, options.scale_px_per_m)?;
    let heat = Heat::compute(building, scene, options)?;
    let width = lay.width_px();
    let legend = Legend::new(
        building,
        scene,
        width,
        heat.is_some(),
        options.grid_margin_m,
    );
    let caption_h = if scene.caption.is_some() { 18.0 } else { 0.0 };
    let floors_top = MARGIN_PX / 2.0 + HEADING_PX + caption_h;
    let panel_h = lay.panel_h_px();
    let legend_top = floors_top + panel_h * building.floors.len() as f64;
    let height = legend_top + legend.height(heat.as_ref()) + MARGIN_PX / 2.0;

    let mut s = String::new();
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

    // Each floor's drawing once, in its own pixels.
    let name_of = |id: i64| floor_name(building, id);
    let _ = writeln!(s, "<defs>");
    for (fi, floor) in building.floors.iter().enumerate() {
        let mut placer = Placer::new(lay.rows as f64 * lay.slice_m * lay.scale, lay.row_h_px());
        let _ = writeln!(
            s,
            r#"<g id="floor-{fi}" class="floor" data-floor="{}">"#,
            floor.id
        );
        layers::outlines(&mut s, building, floor.id, &lay);
        if let Some(h) = &heat {
            layers::heat_cells(&mut s, h, floor.id, &lay, options);
            // Room and wall lines again over the heat map, so rooms stay visible.
            layers::outline_lines(&mut s, building, floor.id, &lay);
        }
        layers::graph(&mut s, building, floor.id, &lay, &mut placer);
        layers::pilot(&mut s, building, floor.id, &lay);
        layers::walks(&mut s, building, scene, floor.id, &lay);
        layers::track(&mut s, scene, floor.id, &lay);
        layers::samples(&mut s, scene, floor.id, &lay);
        layers::markers(&mut s, building, scene, floor.id, &lay, &mut placer);
        layers::stairs(&mut s, building, floor.id, &lay, &mut placer, &name_of);
        layers::step_numbers(&mut s, building, scene, floor.id, &lay, &mut placer);
        if options.labels {
            layers::graph_labels(&mut s, building, floor.id, &lay, &mut placer);
        }
        let _ = writeln!(s, "</g>");
    }
    let _ = writeln!(s, "</defs>");

    // The panels: a title, then each row of the floor through a clip.
    for (fi, floor) in building.floors.iter().enumerate() {
        let top = floors_top + fi as f64 * panel_h;
        let mut title = name_of(floor.id);
        if let Some(note) = floor_note(building, scene, floor.id) {
            title = format!("{title}  ·  {note}");
        }
        let _ = writeln!(
            s,
            r#"<text class="title" x="{MARGIN_PX:.1}" y="{:.1}">{}</text>"#,
            top + 16.0,
            esc(&title)
        );
        for r in 0..lay.rows {
            let y = top + TITLE_PX + r as f64 * (lay.row_h_px() + 10.0);
            let (w, h) = (lay.row_w_px(), lay.row_h_px());
            let _ = writeln!(
                s,
                r#"<rect class="panel{}" x="{MARGIN_PX:.1}" y="{y:.1}" width="{w:.1}" height="{h:.1}"/>"#,
                if heat.is_some() { " unmapped" } else { "" }
            );
            let _ = writeln!(
                s,
                r#"<clipPath id="clip-{fi}-{r}"><rect x="{MARGIN_PX:.1}" y="{y:.1}" width="{w:.1}" height="{h:.1}"/></clipPath>"#
            );
            let _ = writeln!(
                s,
                r##"<g clip-path="url(#clip-{fi}-{r})"><use xlink:href="#floor-{fi}" href="#floor-{fi}" transform="translate({:.1} {y:.1})"/></g>"##,
                MARGIN_PX - lay.row_left_px(r)
            );
            if lay.rows > 1 {
                let from = lay.row_left_m(r);
                let _ = writeln!(
                    s,
                    r#"<text class="subtitle" x="{:.1}" y="{:.1}" text-anchor="end">part {} of {}: x {:.0} to {:.0} m</text>"#,
                    MARGIN_PX + w - 4.0,
                    y + h - 5.0,
                    r + 1,
                    lay.rows,
                    from,
                    from + lay.row_w_px() / lay.scale
                );
            }
        }
    }
    legend.draw(&mut s, legend_top, heat.as_ref(), &lay, options, width);
    s.push_str("</svg>\n");
    Ok(s)
}

#[cfg(test)]
mod tests;

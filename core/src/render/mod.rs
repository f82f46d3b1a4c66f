//! SVG drawings of a building: edges, vertices, pilot points, a walk with direction arrows,
//! its sample positions, and a heat map of the GP posterior standard deviation.
//!
//! One SVG holds one panel per floor, stacked top to bottom in the building's floor order
//! and drawn at the same scale over the same plan area, so that floors line up. The heat
//! map is the latent posterior standard deviation (dB) of the GP conditioned on the pilot
//! locations plus the walk's samples (only positions and noise matter), on the grid of
//! [`crate::eval::reference_grid`], coloured from 0 to `sqrt(sf2)`.
//!
//! The SVG is plain string building: the drawing needs a dozen element kinds and no
//! parsing, so a dependency would add nothing. Every element carries a `class`
//! (`edge`, `vertex`, `pilot`, `sample`, `walk`, `arrow`, `heat`, ...) for styling and tests.
//! A walk is one `polyline` per run on one floor (a single-floor walk is one polyline).

use std::fmt::Write as _;

use nalgebra::DMatrix;

use crate::building::Building;
use crate::eval::reference_grid;
use crate::gp::predict::GpModel;
use crate::gp::{Kernel, Point};
use crate::samples::Sample;
use crate::{Error, Result};

/// What to draw on top of the building.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// A walk as vertex indices (empty: no walk).
    pub walk: Vec<usize>,
    /// Samples along the walk ([`crate::samples::sample_walk`]); their label noise counts
    /// in the heat map.
    pub samples: Vec<Sample>,
    /// Kernel for the heat map (`None`: no heat map).
    pub kernel: Option<Kernel>,
}

/// Drawing options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Pixels per metre; `None` picks one so that a floor is at most about 1400 px wide
    /// (and at most 40 px per metre).
    pub scale_px_per_m: Option<f64>,
    /// Write vertex ids next to the vertices.
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

const MARGIN_PX: f64 = 30.0;
const TITLE_PX: f64 = 28.0;
const LEGEND_PX: f64 = 46.0;

/// Escapes text for XML content and attribute values.
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

/// Viridis colour map, `t` in `[0, 1]`, as `#rrggbb` (linear between 9 stops).
fn viridis(t: f64) -> String {
    const STOPS: [(f64, f64, f64); 9] = [
        (68.0, 1.0, 84.0),
        (71.0, 44.0, 122.0),
        (59.0, 81.0, 139.0),
        (44.0, 113.0, 142.0),
        (33.0, 144.0, 141.0),
        (39.0, 173.0, 129.0),
        (92.0, 200.0, 99.0),
        (170.0, 220.0, 50.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let pos = t * (STOPS.len() - 1) as f64;
    let i = (pos.floor() as usize).min(STOPS.len() - 2);
    let f = pos - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let ch = |x: f64, y: f64| (x + f * (y - x)).round().clamp(0.0, 255.0) as u8;
    format!(
        "#{:02x}{:02x}{:02x}",
        ch(a.0, b.0),
        ch(a.1, b.1),
        ch(a.2, b.2)
    )
}

/// The floor-plan outlines of one floor: building footprints, then walkable spaces (filled
/// by kind), then walls; each element has the class `outline outline-<kind>`.
fn draw_outlines(
    s: &mut String,
    building: &Building,
    floor: i64,
    px: &dyn Fn(f64) -> f64,
    py: &dyn Fn(f64) -> f64,
) {
    use crate::building::OutlineKind;
    let order = |k: OutlineKind| match k {
        OutlineKind::Building => 0,
        OutlineKind::Room | OutlineKind::Corridor | OutlineKind::Area => 1,
        OutlineKind::Wall => 2,
    };
    let mut list: Vec<_> = building
        .outlines
        .iter()
        .filter(|o| o.floor == floor)
        .collect();
    if list.is_empty() {
        return;
    }
    list.sort_by_key(|o| order(o.kind));
    let _ = writeln!(s, r#"<g class="outlines">"#);
    for o in list {
        let pts: Vec<String> = o
            .points
            .iter()
            .map(|p| format!("{:.1},{:.1}", px(p[0]), py(p[1])))
            .collect();
        let tag = if o.kind == OutlineKind::Wall {
            "polyline"
        } else {
            "polygon"
        };
        let title = o
            .name
            .as_ref()
            .map(|n| format!("<title>{}</title>", esc(n)))
            .unwrap_or_default();
        let _ = writeln!(
            s,
            r#"<{tag} class="outline outline-{}" points="{}">{title}</{tag}>"#,
            o.kind.as_str(),
            pts.join(" ")
        );
    }
    let _ = writeln!(s, "</g>");
}

/// Renders the building and scene as one SVG document.
pub fn render_svg(building: &Building, scene: &Scene, options: &RenderOptions) -> Result<String> {
    building.check_walk(&scene.walk)?;
    if !(options.grid_step_m.is_finite() && options.grid_step_m >= 0.01) {
        return Err(Error::InvalidRequest(format!(
            "render grid step must be at least 0.01 m, got {}",
            options.grid_step_m
        )));
    }

    // Plan area shared by all floors: the vertices' bounding box plus the grid margin.
    let pad = options.grid_margin_m.max(0.5);
    let (mut x0, mut y0) = (f64::INFINITY, f64::INFINITY);
    let (mut x1, mut y1) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for v in &building.vertices {
        x0 = x0.min(v.pos.x - pad);
        y0 = y0.min(v.pos.y - pad);
        x1 = x1.max(v.pos.x + pad);
        y1 = y1.max(v.pos.y + pad);
    }
    // Floor-plan outlines widen the area (a building outline around the graph).
    for o in &building.outlines {
        for p in &o.points {
            x0 = x0.min(p[0] - 0.5);
            y0 = y0.min(p[1] - 0.5);
            x1 = x1.max(p[0] + 0.5);
            y1 = y1.max(p[1] + 0.5);
        }
    }
    let (w_m, h_m) = (x1 - x0, y1 - y0);
    let scale = match options.scale_px_per_m {
        Some(s) if s.is_finite() && s > 0.0 => s,
        Some(s) => {
            return Err(Error::InvalidRequest(format!(
                "render scale must be a positive number of pixels per metre, got {s}"
            )));
        }
        None => (1400.0 / w_m).min(40.0),
    };
    let panel_h = TITLE_PX + h_m * scale + MARGIN_PX;

    // Heat map values on the grid, one GP for all floors.
    let heat = match (options.heatmap, scene.kernel) {
        (true, Some(kernel)) => {
            kernel.validate("render kernel")?;
            let grid = reference_grid(building, options.grid_step_m, options.grid_margin_m);
            let mut train = building.pilot_points();
            let mut noise = vec![kernel.sn2; train.len()];
            for smp in &scene.samples {
                train.push(smp.pos);
                noise.push(kernel.sn2 + smp.extra_noise);
            }
            let gp =
                GpModel::fit_with_noise(&kernel, &train, &noise, &DMatrix::zeros(train.len(), 0))?;
            let sd: Vec<f64> = gp.variance(&grid).iter().map(|v| v.sqrt()).collect();
            Some((grid, sd, kernel.sf2.sqrt()))
        }
        _ => None,
    };

    let legend_h = if heat.is_some() { LEGEND_PX } else { 0.0 };
    let width = w_m * scale + 2.0 * MARGIN_PX;
    let height = panel_h * building.floors.len() as f64 + MARGIN_PX + legend_h;
    let mut s = String::new();
    // `write!` into a String cannot fail; the results are ignored on purpose.
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.1} {height:.1}" font-family="sans-serif">"#
    );
    let _ = writeln!(s, "<title>{}</title>", esc(&building.name));
    let _ = writeln!(
        s,
        "<defs><style>\
         .edge{{stroke:#555;stroke-width:2;stroke-linecap:round}}\
         .vertex{{fill:#fff;stroke:#333;stroke-width:1}}\
         .stairs{{fill:none;stroke:#c0392b;stroke-width:2}}\
         .pilot{{fill:#e67e22;stroke:#fff;stroke-width:1}}\
         .sample{{fill:#1f77b4;stroke:none}}\
         .walk{{fill:none;stroke:#d62728;stroke-width:2.5;stroke-opacity:0.8;stroke-linejoin:round}}\
         .arrow{{fill:#d62728}}\
         .start{{fill:#2ca02c;stroke:#fff}}\
         .end{{fill:#000;stroke:#fff}}\
         .label{{font-size:9px;fill:#222}}\
         .title{{font-size:15px;font-weight:bold;fill:#111}}\
         .outline{{stroke:#8a8f98;stroke-width:1}}\
         .outline-building{{fill:#f0f0f0}}\
         .outline-room{{fill:#e8eef7}}\
         .outline-corridor,.outline-area{{fill:#fbf6e6}}\
         .outline-wall{{fill:none;stroke:#3c3f44;stroke-width:2.5}}\
         </style></defs>"
    );
    let _ = writeln!(
        s,
        r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#fafafa"/>"##
    );

    for (fi, floor) in building.floors.iter().enumerate() {
        let top = MARGIN_PX / 2.0 + fi as f64 * panel_h;
        let px = |x: f64| MARGIN_PX + (x - x0) * scale;
        let py = |y: f64| top + TITLE_PX + (y1 - y) * scale;
        let _ = writeln!(s, r#"<g class="floor" data-floor="{}">"#, floor.id);
        let title = match &floor.name {
            Some(n) => format!("{} - floor {} ({})", building.name, floor.id, n),
            None => format!("{} - floor {}", building.name, floor.id),
        };
        let _ = writeln!(
            s,
            r#"<text class="title" x="{:.1}" y="{:.1}">{}</text>"#,
            MARGIN_PX,
            top + 18.0,
            esc(&title)
        );

        // Floor-plan outlines first, under the heat map and the graph.
        draw_outlines(&mut s, building, floor.id, &px, &py);

        if let Some((grid, sd, max)) = &heat {
            let cell = options.grid_step_m * scale;
            let _ = writeln!(s, r#"<g class="heatmap">"#);
            for (p, v) in grid.iter().zip(sd) {
                if p.floor != floor.id {
                    continue;
                }
                let _ = writeln!(
                    s,
                    r#"<rect class="heat" x="{:.1}" y="{:.1}" width="{:.2}" height="{:.2}" fill="{}"><title>sd {:.2} dB</title></rect>"#,
                    px(p.x) - cell / 2.0,
                    py(p.y) - cell / 2.0,
                    cell + 0.3,
                    cell + 0.3,
                    viridis(v / max),
                    v
                );
            }
            let _ = writeln!(s, "</g>");
        }

        for e in &building.edges {
            let (a, b) = (building.vertices[e.a].pos, building.vertices[e.b].pos);
            if a.floor == floor.id && b.floor == floor.id {
                let _ = writeln!(
                    s,
                    r#"<line class="edge" x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/>"#,
                    px(a.x),
                    py(a.y),
                    px(b.x),
                    py(b.y)
                );
            } else if a.floor == floor.id || b.floor == floor.id {
                let (here, there) = if a.floor == floor.id { (a, b) } else { (b, a) };
                let _ = writeln!(
                    s,
                    r#"<circle class="stairs" cx="{:.1}" cy="{:.1}" r="8"><title>to floor {} ({:.1} m)</title></circle>"#,
                    px(here.x),
                    py(here.y),
                    there.floor,
                    e.length
                );
            }
        }
        for v in building.vertices.iter().filter(|v| v.pos.floor == floor.id) {
            let _ = writeln!(
                s,
                r#"<circle class="vertex" cx="{:.1}" cy="{:.1}" r="3"><title>{}</title></circle>"#,
                px(v.pos.x),
                py(v.pos.y),
                esc(&v.id)
            );
            if options.labels {
                let _ = writeln!(
                    s,
                    r#"<text class="label" x="{:.1}" y="{:.1}">{}</text>"#,
                    px(v.pos.x) + 4.0,
                    py(v.pos.y) - 4.0,
                    esc(&v.id)
                );
            }
        }
        for p in building.pilot.iter().filter(|p| p.floor == floor.id) {
            let _ = writeln!(
                s,
                r#"<rect class="pilot" x="{:.1}" y="{:.1}" width="7" height="7"><title>pilot ({}, {})</title></rect>"#,
                px(p.x) - 3.5,
                py(p.y) - 3.5,
                p.x,
                p.y
            );
        }

        // The walk: one polyline per run on this floor, an arrow at every edge's middle.
        if scene.walk.len() > 1 {
            let mut runs: Vec<Vec<Point>> = Vec::new();
            let mut current: Vec<Point> = Vec::new();
            for &v in &scene.walk {
                let p = building.vertices[v].pos;
                if p.floor == floor.id {
                    current.push(p);
                } else if !current.is_empty() {
                    runs.push(std::mem::take(&mut current));
                }
            }
            if !current.is_empty() {
                runs.push(current);
            }
            for run in runs.iter().filter(|r| r.len() > 1) {
                let pts: Vec<String> = run
                    .iter()
                    .map(|p| format!("{:.1},{:.1}", px(p.x), py(p.y)))
                    .collect();
                let _ = writeln!(s, r#"<polyline class="walk" points="{}"/>"#, pts.join(" "));
                for w in run.windows(2) {
                    let (ax, ay, bx, by) = (px(w[0].x), py(w[0].y), px(w[1].x), py(w[1].y));
                    let len = (bx - ax).hypot(by - ay);
                    if len < 8.0 {
                        continue;
                    }
                    let angle = (by - ay).atan2(bx - ax).to_degrees();
                    let _ = writeln!(
                        s,
                        r#"<path class="arrow" d="M 5 0 L -4 -4 L -4 4 Z" transform="translate({:.1} {:.1}) rotate({:.1})"/>"#,
                        (ax + bx) / 2.0,
                        (ay + by) / 2.0,
                        angle
                    );
                }
            }
        }
        for p in scene
            .samples
            .iter()
            .map(|s| s.pos)
            .filter(|p| p.floor == floor.id)
        {
            let _ = writeln!(
                s,
                r#"<circle class="sample" cx="{:.1}" cy="{:.1}" r="1.8"/>"#,
                px(p.x),
                py(p.y)
            );
        }
        for (class, v) in [("start", scene.walk.first()), ("end", scene.walk.last())] {
            if let Some(&v) = v {
                let p = building.vertices[v].pos;
                if p.floor == floor.id {
                    let _ = writeln!(
                        s,
                        r#"<circle class="{class}" cx="{:.1}" cy="{:.1}" r="5"><title>{class}: {}</title></circle>"#,
                        px(p.x),
                        py(p.y),
                        esc(&building.vertices[v].id)
                    );
                }
            }
        }
        let _ = writeln!(s, "</g>");
    }

    if let Some((_, _, max)) = &heat {
        let top = MARGIN_PX / 2.0 + building.floors.len() as f64 * panel_h;
        let bar_w = (width - 2.0 * MARGIN_PX).min(300.0);
        let _ = writeln!(s, r#"<g class="legend">"#);
        let _ = writeln!(s, r#"<defs><linearGradient id="sd-scale">"#);
        for i in 0..=8 {
            let t = i as f64 / 8.0;
            let _ = writeln!(
                s,
                r#"<stop offset="{:.3}" stop-color="{}"/>"#,
                t,
                viridis(t)
            );
        }
        let _ = writeln!(s, "</linearGradient></defs>");
        let _ = writeln!(
            s,
            r#"<rect x="{MARGIN_PX:.1}" y="{:.1}" width="{bar_w:.1}" height="10" fill="url(#sd-scale)"/>"#,
            top
        );
        let _ = writeln!(
            s,
            r#"<text class="label" x="{MARGIN_PX:.1}" y="{:.1}">0 dB</text><text class="label" x="{:.1}" y="{:.1}" text-anchor="end">{:.1} dB</text><text class="label" x="{:.1}" y="{:.1}">posterior standard deviation (pilot + samples)</text>"#,
            top + 22.0,
            MARGIN_PX + bar_w,
            top + 22.0,
            max,
            MARGIN_PX + bar_w + 10.0,
            top + 9.0
        );
        let _ = writeln!(s, "</g>");
    }
    s.push_str("</svg>\n");
    Ok(s)
}

#[cfg(test)]
mod tests;

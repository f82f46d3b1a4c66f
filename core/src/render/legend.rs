//! The legend under the floors: one entry per kind of mark the picture holds, the heat
//! map's colour scale over the range it uses, and a scale bar.

use std::fmt::Write as _;

use super::heat::{Heat, has_walkable_outlines};
use super::layers::{FloorLink, has_repeated_edge};
use super::layout::{Layout, MARGIN_PX};
use super::style::{esc, viridis, walk_colour};
use super::{RenderOptions, Scene};
use crate::building::{Building, OutlineKind};

const ENTRY_W: f64 = 270.0;
const ENTRY_H: f64 = 20.0;
const BAR_BLOCK_H: f64 = 56.0;
const SCALE_BLOCK_H: f64 = 34.0;

/// A swatch and its text.
struct Entry {
    swatch: String,
    text: String,
}

/// The legend's entries, laid out in columns that fit `width`.
pub(super) struct Legend {
    entries: Vec<Entry>,
    columns: usize,
}

impl Legend {
    /// The entries for what `render_svg` draws of `building` and `scene` with `options`
    /// (`heat_map`: a heat map is drawn): an entry for every kind of mark, and none for a
    /// mark the picture does not hold.
    pub fn new(
        building: &Building,
        scene: &Scene,
        width: f64,
        heat_map: bool,
        options: &RenderOptions,
    ) -> Legend {
        let grid_margin_m = options.grid_margin_m;
        let mut entries = Vec::new();
        let mut add = |swatch: String, text: String| entries.push(Entry { swatch, text });
        // Swatches are drawn around (0, 0), translated into place.
        add(
            r#"<line class="edge" x1="-9" y1="0" x2="9" y2="0"/><circle class="vertex" cx="0" cy="0" r="3"/>"#.into(),
            "walkable edge and vertex".into(),
        );
        if !building.pilot.is_empty() {
            add(
                r#"<rect class="pilot" x="-3.5" y="-3.5" width="7" height="7"/>"#.into(),
                format!("pilot fingerprint ({})", building.pilot.len()),
            );
        }
        for kind in FloorLink::kinds(building) {
            add(
                kind.ring(0.0, 0.0, ""),
                format!("{} to another floor (its length)", kind.noun()),
            );
        }
        if options.labels {
            add(
                r#"<text class="label" x="-9" y="3">c03</text>"#.into(),
                "vertex id (as `trailprint vertices` lists them)".into(),
            );
        }
        for (i, w) in scene.walks.iter().enumerate() {
            let c = walk_colour(i);
            add(
                format!(
                    r##"<line class="walk" stroke="{c}" x1="-10" y1="0" x2="10" y2="0"/><path class="arrow" fill="{c}" stroke="#222" stroke-width="0.5" d="M 5 0 L -4 -4 L -4 4 Z"/>"##
                ),
                w.name.clone(),
            );
        }
        if has_repeated_edge(building, scene) {
            add(
                r##"<line class="walk repeat" stroke="#e6194b" x1="-10" y1="-2.5" x2="10" y2="-2.5"/><line class="walk repeat" stroke="#e6194b" x1="-10" y1="2.5" x2="10" y2="2.5"/>"##.into(),
                if scene.walks.len() > 1 {
                    "edge walked twice (there and back, or by two surveyors)"
                } else {
                    "edge walked twice (there and back)"
                }
                .into(),
            );
        }
        let ends = |same: bool| {
            scene
                .walks
                .iter()
                .any(|w| !w.walk.is_empty() && (w.walk.first() == w.walk.last()) == same)
        };
        if ends(false) {
            add(
                r#"<circle class="start" cx="0" cy="0" r="7"/><text class="marker-text" x="0" y="0">S</text>"#.into(),
                "start of the walk".into(),
            );
            add(
                r#"<rect class="end" x="-8" y="-8" width="16" height="16"/><text class="marker-text" x="0" y="0">E</text>"#.into(),
                "end of the walk".into(),
            );
        }
        if ends(true) {
            add(
                r#"<rect class="end start-end" x="-8" y="-8" width="16" height="16"/><circle class="start start-end" cx="0" cy="0" r="6.5"/><text class="marker-text" x="0" y="0">S</text>"#.into(),
                "start = end: the walk ends where it starts".into(),
            );
        }
        if let [w] = scene.walks.as_slice()
            && w.walk.len() >= 2
        {
            add(
                r#"<text class="step" x="-6" y="4">12</text>"#.into(),
                "step number (as in `plans show`)".into(),
            );
        }
        if !scene.track.is_empty() {
            add(
                r#"<line class="track" x1="-10" y1="0" x2="10" y2="0"/>"#.into(),
                "as walked (estimated positions)".into(),
            );
        }
        if !scene.samples.is_empty() {
            add(
                r#"<circle class="sample" cx="0" cy="0" r="2.5"/>"#.into(),
                format!("sample: a Wi-Fi scan ({})", scene.samples.len()),
            );
        }
        for (kind, text) in [
            (OutlineKind::Building, "building footprint (not walkable)"),
            (OutlineKind::Room, "room"),
            (OutlineKind::Corridor, "corridor or open area"),
            (OutlineKind::Wall, "wall"),
        ] {
            if building.outlines.iter().any(|o| {
                o.kind == kind || (kind == OutlineKind::Corridor && o.kind == OutlineKind::Area)
            }) {
                let shape = if kind == OutlineKind::Wall {
                    r#"<line class="outline outline-wall" x1="-9" y1="0" x2="9" y2="0"/>"#
                        .to_string()
                } else {
                    // One swatch for corridors and open areas (one fill), with the
                    // classes of those drawn.
                    let class = if kind == OutlineKind::Corridor {
                        [OutlineKind::Corridor, OutlineKind::Area]
                            .into_iter()
                            .filter(|&k| building.outlines.iter().any(|o| o.kind == k))
                            .map(|k| format!("outline-{}", k.as_str()))
                            .collect::<Vec<_>>()
                            .join(" ")
                    } else {
                        format!("outline-{}", kind.as_str())
                    };
                    format!(
                        r#"<rect class="outline {class}" x="-9" y="-6" width="18" height="12"/>"#
                    )
                };
                add(shape, text.into());
            }
        }
        if heat_map {
            add(
                r#"<rect class="panel unmapped" x="-9" y="-6" width="18" height="12"/>"#.into(),
                if has_walkable_outlines(building) {
                    "not mapped: outside the rooms and corridors".to_string()
                } else {
                    format!("not mapped: over {grid_margin_m} m from any edge")
                },
            );
        }
        let columns = (((width - 2.0 * MARGIN_PX) / ENTRY_W).floor() as usize).max(1);
        Legend { entries, columns }
    }

    /// Height of the legend, pixels.
    pub fn height(&self, heat: Option<&Heat>) -> f64 {
        let rows = self.entries.len().div_ceil(self.columns);
        rows as f64 * ENTRY_H
            + 10.0
            + if heat.is_some() { BAR_BLOCK_H } else { 0.0 }
            + SCALE_BLOCK_H
    }

    /// Draws the legend with its top at `top`.
    pub fn draw(
        &self,
        s: &mut String,
        top: f64,
        heat: Option<&Heat>,
        lay: &Layout,
        options: &RenderOptions,
        width: f64,
    ) {
        let _ = writeln!(s, r#"<g class="legend">"#);
        for (i, e) in self.entries.iter().enumerate() {
            let (col, row) = (i % self.columns, i / self.columns);
            let x = MARGIN_PX + 12.0 + col as f64 * ENTRY_W;
            let y = top + 10.0 + row as f64 * ENTRY_H;
            let _ = writeln!(
                s,
                r#"<g class="legend-entry" transform="translate({x:.1} {y:.1})">{}<text class="legend-text" x="18" y="4">{}</text></g>"#,
                e.swatch,
                esc(&e.text)
            );
        }
        let mut y = top + 10.0 + self.entries.len().div_ceil(self.columns) as f64 * ENTRY_H;
        if let Some(h) = heat {
            let bar_w = (width - 2.0 * MARGIN_PX).min(360.0);
            let _ = writeln!(s, r#"<defs><linearGradient id="sd-scale">"#);
            for i in 0..=8 {
                let t = f64::from(i) / 8.0;
                let _ = writeln!(s, r#"<stop offset="{t:.3}" stop-color="{}"/>"#, viridis(t));
            }
            let _ = writeln!(s, "</linearGradient></defs>");
            let _ = writeln!(
                s,
                r##"<text class="legend-text" x="{MARGIN_PX:.1}" y="{:.1}">uncertainty left: posterior std. dev. of the RSS given pilot data and samples (prior {:.1} dB)</text>"##,
                y + 12.0,
                h.prior
            );
            let bar_y = y + 20.0;
            let _ = writeln!(
                s,
                r##"<rect class="heat heat-scale" x="{MARGIN_PX:.1}" y="{bar_y:.1}" width="{bar_w:.1}" height="12" fill="url(#sd-scale)" stroke="#888" stroke-width="0.5"/>"##
            );
            for (t, v) in [(0.0, h.lo), (0.5, (h.lo + h.hi) / 2.0), (1.0, h.hi)] {
                let x = MARGIN_PX + t * bar_w;
                let anchor = match t {
                    t if t <= 0.0 => "start",
                    t if t >= 1.0 => "end",
                    _ => "middle",
                };
                let _ = writeln!(
                    s,
                    r##"<line x1="{x:.1}" y1="{bar_y:.1}" x2="{x:.1}" y2="{:.1}" stroke="#333"/><text class="legend-text" x="{x:.1}" y="{:.1}" text-anchor="{anchor}">{v:.1} dB</text>"##,
                    bar_y + 16.0,
                    bar_y + 28.0
                );
            }
            let _ = writeln!(
                s,
                r##"<text class="subtitle" x="{:.1}" y="{:.1}">{} m grid, {}</text>"##,
                MARGIN_PX + bar_w + 14.0,
                bar_y + 10.0,
                options.grid_step_m,
                if h.outlines {
                    "over the rooms and corridors".to_string()
                } else {
                    format!("points within {} m of an edge", options.grid_margin_m)
                }
            );
            y += BAR_BLOCK_H;
        }
        // Scale bar: the round length (1, 2 or 5 x 10^k m) nearest to 150 px.
        let target = 150.0 / lay.scale;
        let pow = 10f64.powf(target.log10().floor());
        let metres = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * pow)
            .min_by(|a, b| (a - target).abs().total_cmp(&(b - target).abs()))
            .unwrap_or(pow);
        let len = metres * lay.scale;
        let by = y + 14.0;
        let _ = writeln!(
            s,
            r##"<g class="scale-bar"><rect x="{MARGIN_PX:.1}" y="{by:.1}" width="{:.1}" height="5" fill="#111"/><rect x="{:.1}" y="{by:.1}" width="{:.1}" height="5" fill="#fff" stroke="#111"/><text class="legend-text" x="{:.1}" y="{:.1}">{} m</text></g>"##,
            len / 2.0,
            MARGIN_PX + len / 2.0,
            len / 2.0,
            MARGIN_PX + len + 8.0,
            by + 6.0,
            metres
        );
        let _ = writeln!(s, "</g>");
    }
}

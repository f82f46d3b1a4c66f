//! The marks of one floor, in the floor drawing's own pixels (see [`Layout::px`]): outlines,
//! heat map, graph, stairs, pilot locations, walks, the walked track, samples and the start
//! and end markers. Each function appends its elements to the SVG text.

use std::collections::HashMap;
use std::fmt::Write as _;

use super::heat::Heat;
use super::layout::{Layout, Placer};
use super::style::{esc, viridis, walk_colour};
use super::{RenderOptions, Scene};
use crate::building::{Building, OutlineKind};

// `write!` into a String cannot fail; the results are ignored on purpose throughout.

/// Pixels between two traversals of one edge drawn side by side.
const LANE_PX: f64 = 4.5;
/// Walks longer than this get a step number at every k-th vertex only.
const MAX_NUMBERED: usize = 80;

/// The floor one layer draws, with what every layer reads: the building, the scene (walks,
/// track, samples), the floor's id and the drawing's layout.
#[derive(Clone, Copy)]
pub(super) struct FloorView<'a> {
    pub building: &'a Building,
    pub scene: &'a Scene,
    pub floor: i64,
    pub lay: &'a Layout,
}

/// An outline's points in the drawing's pixels, as an SVG `points` attribute.
fn svg_points(points: &[[f64; 2]], lay: &Layout) -> String {
    let pts: Vec<String> = points
        .iter()
        .map(|p| format!("{:.1},{:.1}", lay.px(p[0]), lay.py(p[1])))
        .collect();
    pts.join(" ")
}

/// The floor-plan outlines: building footprints, then walkable spaces (filled by kind),
/// then walls; each element has the class `outline outline-<kind>`.
pub(super) fn outlines(s: &mut String, view: &FloorView) {
    let (building, floor, lay) = (view.building, view.floor, view.lay);
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
        let pts = svg_points(&o.points, lay);
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
            pts
        );
    }
    let _ = writeln!(s, "</g>");
}

/// The lines of the outlines of this floor without fill (over the heat map).
pub(super) fn outline_lines(s: &mut String, view: &FloorView) {
    let (building, floor, lay) = (view.building, view.floor, view.lay);
    let list: Vec<_> = building
        .outlines
        .iter()
        .filter(|o| o.floor == floor && o.kind != OutlineKind::Building)
        .collect();
    if list.is_empty() {
        return;
    }
    let _ = writeln!(s, r#"<g class="outline-lines">"#);
    for o in list {
        let pts = svg_points(&o.points, lay);
        let (tag, class) = if o.kind == OutlineKind::Wall {
            ("polyline", "outline-wall")
        } else {
            ("polygon", "outline-line")
        };
        let _ = writeln!(s, r#"<{tag} class="{class}" points="{pts}"/>"#);
    }
    let _ = writeln!(s, "</g>");
}

/// The heat-map cells of this floor, clipped to its walkable outlines when it has any.
pub(super) fn heat_cells(s: &mut String, view: &FloorView, heat: &Heat, options: &RenderOptions) {
    let (building, floor, lay) = (view.building, view.floor, view.lay);
    let cell = options.grid_step_m * lay.scale;
    // On a floor plan, the cells are cut at the walls of the walkable outlines (cells
    // reach half a step past them, so that they meet the walls; see `heat_grid`).
    let walkable: Vec<_> = building
        .outlines
        .iter()
        .filter(|o| {
            o.floor == floor
                && o.points.len() >= 3
                && matches!(
                    o.kind,
                    OutlineKind::Room | OutlineKind::Corridor | OutlineKind::Area
                )
        })
        .collect();
    if walkable.is_empty() {
        let _ = writeln!(s, r#"<g class="heatmap">"#);
    } else {
        let _ = write!(s, r#"<clipPath id="walkable-{floor}">"#);
        for o in walkable {
            let _ = write!(s, r#"<polygon points="{}"/>"#, svg_points(&o.points, lay));
        }
        let _ = writeln!(s, "</clipPath>");
        let _ = writeln!(
            s,
            r#"<g class="heatmap" clip-path="url(#walkable-{floor})">"#
        );
    }
    for (p, v) in heat.grid.iter().zip(&heat.sd) {
        if p.floor != floor {
            continue;
        }
        let _ = writeln!(
            s,
            r#"<rect class="heat" x="{:.1}" y="{:.1}" width="{:.2}" height="{:.2}" fill="{}"><title>sd {:.2} dB</title></rect>"#,
            lay.px(p.x) - cell / 2.0,
            lay.py(p.y) - cell / 2.0,
            cell + 0.3,
            cell + 0.3,
            viridis(heat.t(*v)),
            v
        );
    }
    let _ = writeln!(s, "</g>");
}

/// Edges and vertices of this floor (the vertices block label space).
pub(super) fn graph(s: &mut String, view: &FloorView, placer: &mut Placer) {
    let (building, floor, lay) = (view.building, view.floor, view.lay);
    for e in &building.edges {
        let (a, b) = (building.vertices[e.a].pos, building.vertices[e.b].pos);
        if a.floor == floor && b.floor == floor {
            let _ = writeln!(
                s,
                r#"<line class="edge" x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/>"#,
                lay.px(a.x),
                lay.py(a.y),
                lay.px(b.x),
                lay.py(b.y)
            );
        }
    }
    for v in building.vertices.iter().filter(|v| v.pos.floor == floor) {
        let (x, y) = (lay.px(v.pos.x), lay.py(v.pos.y));
        let _ = writeln!(
            s,
            r#"<circle class="vertex" cx="{x:.1}" cy="{y:.1}" r="3"><title>{}</title></circle>"#,
            esc(&v.id)
        );
        placer.block(x - 3.0, y - 3.0, 6.0, 6.0);
    }
}

/// Vertex ids of this floor, where there is room for them (placed last: markers, stairs
/// and step numbers matter more).
pub(super) fn graph_labels(s: &mut String, view: &FloorView, placer: &mut Placer) {
    let (building, floor, lay) = (view.building, view.floor, view.lay);
    for v in building.vertices.iter().filter(|v| v.pos.floor == floor) {
        let (x, y) = (lay.px(v.pos.x), lay.py(v.pos.y));
        if let Some((tx, ty)) = placer.place(x, y, v.id.chars().count(), 9.0) {
            let _ = writeln!(
                s,
                r#"<text class="label" x="{tx:.1}" y="{ty:.1}">{}</text>"#,
                esc(&v.id)
            );
        }
    }
}

/// What joins two floors, as the vertices' labels say (an import labels its stops
/// `elevator` and `stairs`; hand-written buildings may say nothing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum FloorLink {
    Elevator,
    Stairs,
    Unknown,
}

impl FloorLink {
    /// The link of an edge between floors, from its ends' labels.
    pub fn of(building: &Building, a: usize, b: usize) -> FloorLink {
        let says = |words: &[&str]| {
            [a, b].iter().any(|&v| {
                building.vertices[v]
                    .label
                    .as_deref()
                    .map(str::to_lowercase)
                    .is_some_and(|l| words.iter().any(|w| l.contains(w)))
            })
        };
        if says(&["elevator", "lift"]) {
            FloorLink::Elevator
        } else if says(&["stair", "steps", "escalator", "ramp"]) {
            FloorLink::Stairs
        } else {
            FloorLink::Unknown
        }
    }

    /// Every kind of link the building has, in this order: elevator, stairs, unknown.
    pub fn kinds(building: &Building) -> Vec<FloorLink> {
        let mut out = Vec::new();
        for k in [FloorLink::Elevator, FloorLink::Stairs, FloorLink::Unknown] {
            if building.edges.iter().any(|e| {
                building.vertices[e.a].pos.floor != building.vertices[e.b].pos.floor
                    && FloorLink::of(building, e.a, e.b) == k
            }) {
                out.push(k);
            }
        }
        out
    }

    /// What the map calls it ("elevator to Level 1").
    pub fn noun(self) -> &'static str {
        match self {
            FloorLink::Elevator => "elevator",
            FloorLink::Stairs => "stairs",
            FloorLink::Unknown => "stairs or lift",
        }
    }

    /// The ring drawn at each end, centred on (`x`, `y`), with a title: a square ring for an
    /// elevator (class `stairs lift`), a round one for stairs.
    pub fn ring(self, x: f64, y: f64, title: &str) -> String {
        let title = if title.is_empty() {
            String::new()
        } else {
            format!("<title>{}</title>", esc(title))
        };
        match self {
            FloorLink::Elevator => format!(
                r#"<rect class="stairs lift" x="{:.1}" y="{:.1}" width="15" height="15" rx="2">{title}</rect>"#,
                x - 7.5,
                y - 7.5
            ),
            _ => {
                format!(r#"<circle class="stairs" cx="{x:.1}" cy="{y:.1}" r="8">{title}</circle>"#)
            }
        }
    }
}

/// Whether some edge is drawn more than once (walked there and back, or by two
/// surveyors): the walks' traversals of edges within one floor, counted over all walks.
pub(super) fn has_repeated_edge(building: &Building, scene: &Scene) -> bool {
    let mut seen = std::collections::HashSet::new();
    scene.walks.iter().any(|w| {
        w.walk.windows(2).any(|p| {
            building.vertices[p[0]].pos.floor == building.vertices[p[1]].pos.floor
                && !seen.insert((p[0].min(p[1]), p[0].max(p[1])))
        })
    })
}

/// The ends of stairs and lifts on this floor: a ring (square for an elevator), and
/// "stairs to First (4 m)" or "elevator to First (18 m)" where there is room for it.
pub(super) fn stairs(
    s: &mut String,
    view: &FloorView,
    placer: &mut Placer,
    floor_name: &dyn Fn(i64) -> String,
) {
    let (building, floor, lay) = (view.building, view.floor, view.lay);
    for e in &building.edges {
        let (a, b) = (building.vertices[e.a].pos, building.vertices[e.b].pos);
        if (a.floor == floor) == (b.floor == floor) {
            continue;
        }
        let (here, there) = if a.floor == floor { (a, b) } else { (b, a) };
        let (x, y) = (lay.px(here.x), lay.py(here.y));
        let kind = FloorLink::of(building, e.a, e.b);
        let text = format!(
            "{} to {} ({:.0} m)",
            kind.noun(),
            floor_name(there.floor),
            e.length
        );
        let _ = writeln!(s, "{}", kind.ring(x, y, &text));
        placer.block(x - 8.0, y - 8.0, 16.0, 16.0);
        if let Some((tx, ty)) = placer.place(x + 6.0, y, text.chars().count(), 10.0) {
            let _ = writeln!(
                s,
                r#"<text class="stairs-text" x="{tx:.1}" y="{ty:.1}">{}</text>"#,
                esc(&text)
            );
        }
    }
}

/// Pilot locations of this floor (orange squares).
pub(super) fn pilot(s: &mut String, view: &FloorView) {
    let (building, floor, lay) = (view.building, view.floor, view.lay);
    for p in building.pilot.iter().filter(|p| p.floor == floor) {
        let _ = writeln!(
            s,
            r#"<rect class="pilot" x="{:.1}" y="{:.1}" width="7" height="7"><title>pilot ({}, {})</title></rect>"#,
            lay.px(p.x) - 3.5,
            lay.py(p.y) - 3.5,
            p.x,
            p.y
        );
    }
}

/// The walks of this floor: every traversal of an edge is its own segment with a direction
/// arrow at its middle; traversals of the same edge (there and back, or two surveyors) are
/// drawn side by side, `LANE_PX` apart, so walking back and forth shows as two lines with
/// opposite arrows. A walk's segments have the classes `walk walk-<i>`, plus `repeat` on an
/// edge walked more than once.
pub(super) fn walks(s: &mut String, view: &FloorView) {
    let (building, scene, floor, lay) = (view.building, view.scene, view.floor, view.lay);
    let on = |v: usize| building.vertices[v].pos.floor == floor;
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    let mut count: HashMap<(usize, usize), usize> = HashMap::new();
    for w in &scene.walks {
        for p in w.walk.windows(2) {
            if on(p[0]) && on(p[1]) {
                *count.entry(key(p[0], p[1])).or_default() += 1;
            }
        }
    }
    let mut lane: HashMap<(usize, usize), usize> = HashMap::new();
    for (wi, w) in scene.walks.iter().enumerate() {
        let colour = walk_colour(wi);
        let _ = writeln!(s, r#"<g class="walk-layer" data-walk="{wi}">"#);
        for p in w.walk.windows(2) {
            if !(on(p[0]) && on(p[1])) {
                continue;
            }
            let k = key(p[0], p[1]);
            let m = count.get(&k).copied().unwrap_or(1);
            let slot = lane.entry(k).or_default();
            let off = (*slot as f64 - (m as f64 - 1.0) / 2.0) * LANE_PX;
            *slot += 1;
            // The normal of the edge's canonical direction (low index to high), so that
            // the lanes of one edge are the same whichever way each traversal goes.
            let (c0, c1) = (building.vertices[k.0].pos, building.vertices[k.1].pos);
            let (dx, dy) = (lay.px(c1.x) - lay.px(c0.x), lay.py(c1.y) - lay.py(c0.y));
            let len = dx.hypot(dy).max(1e-9);
            let (nx, ny) = (-dy / len * off, dx / len * off);
            let (a, b) = (building.vertices[p[0]].pos, building.vertices[p[1]].pos);
            let (ax, ay) = (lay.px(a.x) + nx, lay.py(a.y) + ny);
            let (bx, by) = (lay.px(b.x) + nx, lay.py(b.y) + ny);
            let _ = writeln!(
                s,
                r#"<line class="walk walk-{wi}{}" stroke="{colour}" x1="{ax:.1}" y1="{ay:.1}" x2="{bx:.1}" y2="{by:.1}"/>"#,
                if m > 1 { " repeat" } else { "" }
            );
            if (bx - ax).hypot(by - ay) >= 8.0 {
                let angle = (by - ay).atan2(bx - ax).to_degrees();
                let _ = writeln!(
                    s,
                    r##"<path class="arrow" fill="{colour}" stroke="#222" stroke-width="0.5" d="M 5 0 L -4 -4 L -4 4 Z" transform="translate({:.1} {:.1}) rotate({angle:.1})"/>"##,
                    (ax + bx) / 2.0,
                    (ay + by) / 2.0,
                );
            }
        }
        let _ = writeln!(s, "</g>");
    }
}

/// The walked track of a session (estimated positions in order), dashed.
pub(super) fn track(s: &mut String, view: &FloorView) {
    let (scene, floor, lay) = (view.scene, view.floor, view.lay);
    let mut runs: Vec<Vec<String>> = vec![Vec::new()];
    for p in &scene.track {
        if p.floor == floor {
            if let Some(r) = runs.last_mut() {
                r.push(format!("{:.1},{:.1}", lay.px(p.x), lay.py(p.y)));
            }
        } else if runs.last().is_some_and(|r| !r.is_empty()) {
            runs.push(Vec::new());
        }
    }
    for r in runs.iter().filter(|r| r.len() > 1) {
        let _ = writeln!(s, r#"<polyline class="track" points="{}"/>"#, r.join(" "));
    }
}

/// Sample positions of this floor.
pub(super) fn samples(s: &mut String, view: &FloorView) {
    let (scene, floor, lay) = (view.scene, view.floor, view.lay);
    for p in scene
        .samples
        .iter()
        .map(|s| s.pos)
        .filter(|p| p.floor == floor)
    {
        let _ = writeln!(
            s,
            r#"<circle class="sample" cx="{:.1}" cy="{:.1}" r="2"/>"#,
            lay.px(p.x),
            lay.py(p.y)
        );
    }
}

/// Start (green disc, "S") and end (dark square, "E") of every walk on this floor; when a
/// walk starts and ends at the same vertex the square sits behind the disc with its
/// corners showing, labelled "start = end". A team numbers them: "S1", "E1".
pub(super) fn markers(s: &mut String, view: &FloorView, placer: &mut Placer) {
    let (building, scene, floor, lay) = (view.building, view.scene, view.floor, view.lay);
    let team = scene.walks.len() > 1;
    for (wi, w) in scene.walks.iter().enumerate() {
        let (Some(&first), Some(&last)) = (w.walk.first(), w.walk.last()) else {
            continue;
        };
        let tag = if team {
            format!("{}", wi + 1)
        } else {
            String::new()
        };
        let e = building.vertices[last].pos;
        if e.floor == floor {
            let (x, y) = (lay.px(e.x), lay.py(e.y));
            let _ = writeln!(
                s,
                r#"<rect class="end{}" x="{:.1}" y="{:.1}" width="16" height="16"><title>end: {}</title></rect>"#,
                if first == last { " start-end" } else { "" },
                x - 8.0,
                y - 8.0,
                esc(&building.vertices[last].id)
            );
            if first != last {
                let _ = writeln!(
                    s,
                    r#"<text class="marker-text" x="{x:.1}" y="{y:.1}">E{tag}</text>"#
                );
            }
            placer.block(x - 9.0, y - 9.0, 18.0, 18.0);
        }
        let p = building.vertices[first].pos;
        if p.floor == floor {
            let (x, y) = (lay.px(p.x), lay.py(p.y));
            let r = if first == last { 6.5 } else { 7.5 };
            let _ = writeln!(
                s,
                r#"<circle class="start{}" cx="{x:.1}" cy="{y:.1}" r="{r}"><title>start: {}</title></circle>"#,
                if first == last { " start-end" } else { "" },
                esc(&building.vertices[first].id)
            );
            let _ = writeln!(
                s,
                r#"<text class="marker-text" x="{x:.1}" y="{y:.1}">S{tag}</text>"#
            );
            placer.block(x - 9.0, y - 9.0, 18.0, 18.0);
            if first == last {
                let text = format!(
                    "start = end{}",
                    if team {
                        format!(" ({})", wi + 1)
                    } else {
                        String::new()
                    }
                );
                if let Some((tx, ty)) = placer.place(x + 6.0, y, text.chars().count(), 10.0) {
                    let _ = writeln!(
                        s,
                        r#"<text class="step" x="{tx:.1}" y="{ty:.1}">{text}</text>"#
                    );
                }
            }
        }
    }
}

/// Step numbers along the first walk: each vertex gets the numbers of the steps that
/// reach it ("4,10" for a vertex walked through twice); a walk of more than
/// `MAX_NUMBERED` vertices is numbered at every k-th step, start and end always.
pub(super) fn step_numbers(s: &mut String, view: &FloorView, placer: &mut Placer) {
    let (building, scene, floor, lay) = (view.building, view.scene, view.floor, view.lay);
    let Some(w) = scene.walks.first() else {
        return;
    };
    if scene.walks.len() > 1 || w.walk.len() < 2 {
        return;
    }
    let n = w.walk.len();
    let every = n.div_ceil(MAX_NUMBERED).max(1);
    let mut at: Vec<(usize, Vec<usize>)> = Vec::new();
    for (i, &v) in w.walk.iter().enumerate() {
        if building.vertices[v].pos.floor != floor {
            continue;
        }
        if !(i % every == 0 || i + 1 == n) {
            continue;
        }
        match at.iter_mut().find(|(u, _)| *u == v) {
            Some((_, steps)) => steps.push(i + 1),
            None => at.push((v, vec![i + 1])),
        }
    }
    let _ = writeln!(s, r#"<g class="steps">"#);
    for (v, steps) in at {
        let mut text: Vec<String> = steps.iter().take(4).map(usize::to_string).collect();
        if steps.len() > 4 {
            text.push("…".into());
        }
        let text = text.join(",");
        let p = building.vertices[v].pos;
        if let Some((tx, ty)) = placer.place(lay.px(p.x), lay.py(p.y), text.chars().count(), 10.0) {
            let _ = writeln!(
                s,
                r#"<text class="step" x="{tx:.1}" y="{ty:.1}"><title>step {} at {}</title>{text}</text>"#,
                steps
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", "),
                esc(&building.vertices[v].id)
            );
        }
    }
    let _ = writeln!(s, "</g>");
}

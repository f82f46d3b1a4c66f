//! The floors: each floor's drawing, once, as a group in `<defs>` (the layers in drawing
//! order), and its panel: a title with the floor's place in the walk, then each row of the
//! floor through a clip.

use std::fmt::Write as _;

use super::heat::Heat;
use super::layers;
use super::layout::{Layout, MARGIN_PX, Placer, TITLE_PX};
use super::style::esc;
use super::{RenderOptions, Scene};
use crate::building::Building;

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

/// Each floor's drawing once, in its own pixels: `<g id="floor-N">` in `<defs>`.
pub(super) fn floor_defs(
    s: &mut String,
    building: &Building,
    scene: &Scene,
    lay: &Layout,
    heat: Option<&Heat>,
    options: &RenderOptions,
) {
    let name_of = |id: i64| floor_name(building, id);
    let _ = writeln!(s, "<defs>");
    for (fi, floor) in building.floors.iter().enumerate() {
        let mut placer = Placer::new(lay.rows as f64 * lay.slice_m * lay.scale, lay.row_h_px());
        let _ = writeln!(
            s,
            r#"<g id="floor-{fi}" class="floor" data-floor="{}">"#,
            floor.id
        );
        let view = layers::FloorView {
            building,
            scene,
            floor: floor.id,
            lay,
        };
        layers::outlines(s, &view);
        if let Some(h) = heat {
            layers::heat_cells(s, &view, h, options);
            // Room and wall lines again over the heat map, so rooms stay visible.
            layers::outline_lines(s, &view);
        }
        layers::graph(s, &view, &mut placer);
        layers::pilot(s, &view);
        layers::walks(s, &view);
        layers::track(s, &view);
        layers::samples(s, &view);
        layers::markers(s, &view, &mut placer);
        layers::stairs(s, &view, &mut placer, &name_of);
        layers::step_numbers(s, &view, &mut placer);
        if options.labels {
            layers::graph_labels(s, &view, &mut placer);
        }
        let _ = writeln!(s, "</g>");
    }
    let _ = writeln!(s, "</defs>");
}

/// The panels, stacked from `floors_top`: a floor's title, then each of its rows showing
/// the floor's group through a clip (`unmapped` panels when a heat map is drawn).
pub(super) fn floor_panels(
    s: &mut String,
    building: &Building,
    scene: &Scene,
    lay: &Layout,
    heat: bool,
    floors_top: f64,
) {
    for (fi, floor) in building.floors.iter().enumerate() {
        let top = floors_top + fi as f64 * lay.panel_h_px();
        let mut title = floor_name(building, floor.id);
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
                if heat { " unmapped" } else { "" }
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
}

//! `trailprint vertices NAME [--json]`: a building's vertices (id, label, floor, position,
//! neighbours), so that a user can pick a start and an end.

use std::path::Path;

use trailprint::Result;

use crate::opts::json_line;
use crate::store_cli::{column_width, label_cell, load_building, printable};
use crate::walk_text::floor_name;

#[derive(clap::Args)]
pub struct Args {
    /// A building of the database (name or id) or a survey-building/1 file.
    building: String,
    /// Only the vertices whose id or label contains this text (ignoring case).
    #[arg(long, value_name = "TEXT")]
    grep: Option<String>,
    /// Print a JSON array instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(serde::Serialize)]
struct Row {
    id: String,
    label: Option<String>,
    floor: i64,
    floor_name: String,
    x: f64,
    y: f64,
    /// Ids of the vertices joined to this one by an edge.
    neighbours: Vec<String>,
}

pub fn run(a: &Args, db: Option<&Path>) -> Result<()> {
    let b = load_building(&a.building, db)?;
    let needle = a.grep.as_ref().map(|g| g.to_lowercase());
    let rows: Vec<Row> = b
        .vertices
        .iter()
        .enumerate()
        .filter(|(_, v)| {
            needle.as_ref().is_none_or(|n| {
                v.id.to_lowercase().contains(n)
                    || v.label
                        .as_ref()
                        .is_some_and(|l| l.to_lowercase().contains(n))
            })
        })
        .map(|(i, v)| Row {
            id: v.id.clone(),
            label: v.label.clone(),
            floor: v.pos.floor,
            floor_name: floor_name(&b, v.pos.floor),
            x: v.pos.x,
            y: v.pos.y,
            neighbours: b
                .neighbours(i)
                .iter()
                .map(|&(n, _)| b.vertices[n].id.clone())
                .collect(),
        })
        .collect();
    if a.json {
        println!("{}", json_line(&rows)?);
        return Ok(());
    }
    println!(
        "{}: {} vertices{}",
        printable(&b.name),
        b.len(),
        if rows.len() < b.len() {
            format!(", {} shown", rows.len())
        } else {
            String::new()
        }
    );
    let idw = column_width(rows.iter().map(|r| printable(&r.id)), 2);
    let labels = rows
        .iter()
        .map(|r| r.label.as_deref().map_or(String::new(), printable));
    let lw = column_width(labels, 5).min(30);
    let fw = column_width(rows.iter().map(|r| &r.floor_name), 5);
    println!(
        "{:<idw$}  {:<lw$}  {:<fw$}  {:>9} {:>9}  neighbours",
        "id", "label", "floor", "x_m", "y_m"
    );
    for r in &rows {
        let label = label_cell(r.label.as_deref(), lw);
        println!(
            "{:<idw$}  {:<lw$}  {:<fw$}  {:>9.2} {:>9.2}  {}",
            printable(&r.id),
            label,
            r.floor_name,
            r.x,
            r.y,
            r.neighbours
                .iter()
                .map(|n| printable(n))
                .collect::<Vec<_>>()
                .join(",")
        );
    }
    Ok(())
}

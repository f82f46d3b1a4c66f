//! IMDF (Indoor Mapping Data Format, an OGC community standard): a folder of GeoJSON files
//! (`level.geojson`, `unit.geojson`, `opening.geojson`, `amenity.geojson`,
//! `relationship.geojson`, `venue.geojson`, ...), or a zip archive of one.
//!
//! - `level`: one floor per `ordinal`; its outline is drawn as the building outline;
//! - `unit`: a walkable space by `category`: `walkway`, `footbridge`, `ramp` and
//!   `movingwalkway` are corridors; `lobby`, `unenclosedarea`, `platform`, `terrace` and
//!   `waitingroom` open areas; `elevator`, `stairs`, `steps` and `escalator` shafts; the
//!   structural and closed categories (`structure`, `nonpublic`, `opentobelow`, `column`,
//!   the wall materials, `vegetation`, `road`) are left out; every other category is a room;
//! - `opening`: a door in the middle of its line;
//! - `relationship` of category `elevator`, `stairs`, `escalator` or `ramp` joins the
//!   levels of its origin, intermediaries and destination (units, openings or amenities);
//!   an `amenity` of such a category whose `unit_ids` lie on several levels does too, and
//!   shaft units stacked above each other with no relationship are joined all the same.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use geo::{Coord, InteriorPoint};
use geojson::Feature;
use serde_json::Value;

use super::osm::{Shapes, read_features, stack_shafts};
use super::{
    Connector, ConnectorKind, Door, LocalFrame, Plan, Space, SpaceKind, Warnings, floors_of_levels,
    level_key, origin_of,
};
use crate::{Error, Result};

/// Largest member of an IMDF archive read, bytes.
const MAX_MEMBER_BYTES: u64 = 256 * 1024 * 1024;

/// The files of an IMDF data set, by name (`unit.geojson`), as text.
fn files_of(path: &Path) -> Result<HashMap<String, String>> {
    let mut out = HashMap::new();
    if path.is_dir() {
        let entries = std::fs::read_dir(path).map_err(|e| Error::io(path, e))?;
        for e in entries {
            let e = e.map_err(|e| Error::io(path, e))?;
            let name = e.file_name().to_string_lossy().to_lowercase();
            if name.ends_with(".geojson") || name == "manifest.json" {
                out.insert(name, super::read_text(&e.path())?);
            }
        }
        return Ok(out);
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    files_of_zip(file, path)
}

/// The IMDF files of a zip archive (`path` names it in errors).
pub(crate) fn files_of_zip<R: Read + std::io::Seek>(
    reader: R,
    path: &Path,
) -> Result<HashMap<String, String>> {
    let mut out = HashMap::new();
    let mut zip = zip::ZipArchive::new(reader).map_err(|e| {
        Error::invalid(
            &path.display().to_string(),
            "$",
            format!("not an IMDF folder or zip archive: {e}"),
        )
    })?;
    for i in 0..zip.len() {
        let mut member = zip.by_index(i).map_err(|e| {
            Error::invalid(
                &path.display().to_string(),
                format!("member {i}"),
                e.to_string(),
            )
        })?;
        // IMDF archives hold the files at the top; some tools add a folder around them.
        let full = member.name().map(|n| n.into_owned()).map_err(|e| {
            Error::invalid(
                &path.display().to_string(),
                format!("member {i}"),
                e.to_string(),
            )
        })?;
        let name = full.rsplit('/').next().unwrap_or_default().to_lowercase();
        if !(name.ends_with(".geojson") || name == "manifest.json") {
            continue;
        }
        if member.size() > MAX_MEMBER_BYTES {
            return Err(Error::invalid(
                &path.display().to_string(),
                &name,
                format!(
                    "member is {} bytes, over the limit of {MAX_MEMBER_BYTES}",
                    member.size()
                ),
            ));
        }
        let mut text = String::new();
        member
            .by_ref()
            .take(MAX_MEMBER_BYTES + 1)
            .read_to_string(&mut text)
            .map_err(|e| Error::io(path.join(&name), e))?;
        out.insert(name, text);
    }
    Ok(out)
}

/// The first label of an IMDF LABELS object (English first), or a plain string.
fn label(v: Option<&Value>) -> Option<String> {
    match v? {
        Value::String(s) => Some(s.clone()),
        Value::Object(m) => m
            .get("en")
            .or_else(|| m.values().next())
            .and_then(Value::as_str)
            .map(str::to_string),
        _ => None,
    }
}

fn prop<'a>(f: &'a Feature, key: &str) -> Option<&'a Value> {
    f.properties.as_ref()?.get(key)
}

fn fid(f: &Feature, i: usize) -> String {
    match &f.id {
        Some(geojson::feature::Id::String(s)) => s.clone(),
        Some(geojson::feature::Id::Number(n)) => n.to_string(),
        None => format!("features[{i}]"),
    }
}

fn unit_kind(category: &str) -> Option<SpaceKind> {
    Some(match category {
        "walkway" | "walkway.island" | "footbridge" | "ramp" | "movingwalkway" => {
            SpaceKind::Corridor
        }
        "lobby" | "unenclosedarea" | "platform" | "terrace" | "waitingroom" => SpaceKind::Area,
        "elevator" => SpaceKind::Elevator,
        "stairs" | "steps" | "escalator" => SpaceKind::Stairs,
        "structure" | "nonpublic" | "opentobelow" | "column" | "brick" | "concrete" | "drywall"
        | "glass" | "wood" | "vegetation" | "road" => return None,
        _ => SpaceKind::Room,
    })
}

/// The feature files of an IMDF data set the importer reads (as [`read_files`] takes
/// them; `level` and `unit` are required, the others optional). Other files of an
/// archive are ignored.
pub const LAYERS: [&str; 7] = [
    "level.geojson",
    "unit.geojson",
    "opening.geojson",
    "amenity.geojson",
    "relationship.geojson",
    "venue.geojson",
    "building.geojson",
];

/// Reads an IMDF folder or zip into a plan in metres.
pub(crate) fn read(path: &Path) -> Result<Plan> {
    read_files(&files_of(path)?, &path.display().to_string())
}

/// Reads an IMDF data set given as its files (`unit.geojson` -> text) into a plan in
/// metres; `origin` names the data set in errors.
pub(crate) fn read_files(files: &HashMap<String, String>, origin: &str) -> Result<Plan> {
    let origin = origin.to_string();
    let mut warnings = Warnings::default();
    let layer = |name: &str, required: bool, w: &mut Warnings| -> Result<Vec<(usize, Feature)>> {
        match files.get(name) {
            Some(text) => read_features(text, &format!("{origin}/{name}"), w),
            None if required => Err(Error::invalid(
                &origin,
                name,
                format!("an IMDF data set needs {name}; it is not in {origin}"),
            )),
            None => Ok(Vec::new()),
        }
    };
    let levels = layer("level.geojson", true, &mut warnings)?;
    let units = layer("unit.geojson", true, &mut warnings)?;
    let openings = layer("opening.geojson", false, &mut warnings)?;
    let amenities = layer("amenity.geojson", false, &mut warnings)?;
    let relationships = layer("relationship.geojson", false, &mut warnings)?;
    let venues = layer("venue.geojson", false, &mut warnings)?;
    let buildings = layer("building.geojson", false, &mut warnings)?;

    let mut all = Vec::new();
    for (_, f) in levels
        .iter()
        .chain(&units)
        .chain(&openings)
        .chain(&amenities)
    {
        if let Some(g) = &f.geometry {
            collect(&g.value, &mut all);
        }
    }
    if all.is_empty() {
        return Err(Error::invalid(
            &origin,
            "unit.geojson",
            "nothing walkable: no unit or level has coordinates",
        ));
    }
    let geo = origin_of(&all, &origin)?;
    let frame = LocalFrame::new(geo);

    // Levels: ordinal -> floor.
    let mut level_ordinal: HashMap<String, f64> = HashMap::new();
    let mut level_names: HashMap<u64, String> = HashMap::new();
    for (i, f) in &levels {
        let id = fid(f, *i);
        match prop(f, "ordinal").and_then(Value::as_f64) {
            Some(o) => {
                level_ordinal.insert(id, o);
                if let Some(n) = label(prop(f, "short_name")).or_else(|| label(prop(f, "name"))) {
                    level_names.entry(level_key(o)).or_insert(n);
                }
            }
            None => warnings.add("levels without an ordinal (skipped)", id),
        }
    }
    if level_ordinal.is_empty() {
        return Err(Error::invalid(
            &origin,
            "level.geojson",
            "nothing walkable: no level has an `ordinal`",
        ));
    }
    let ordinals: Vec<f64> = level_ordinal.values().copied().collect();
    let (mut floors, level_map) = floors_of_levels(&ordinals, &mut warnings);
    for (k, &fid_) in &level_map {
        if let Some(n) = level_names.get(k)
            && let Some(fl) = floors.iter_mut().find(|fl| fl.id == fid_)
        {
            fl.name = Some(n.clone());
        }
    }
    let floor_of_level = |level_id: Option<&Value>| -> Option<i64> {
        let o = level_ordinal.get(level_id?.as_str()?)?;
        level_map.get(&level_key(*o)).copied()
    };

    let mut shapes = Shapes {
        frame,
        warnings: &mut warnings,
    };
    let mut outlines = Vec::new();
    for (i, f) in &levels {
        let Some(fl) = floor_of_level(Some(&Value::String(fid(f, *i)))) else {
            continue;
        };
        if let Some(g) = &f.geometry {
            for p in shapes.polygons(&g.value, &fid(f, *i)) {
                outlines.push((fl, p));
            }
        }
    }

    let mut spaces = Vec::new();
    // Where each unit, opening and amenity is, for the relationships.
    let mut places: HashMap<String, Vec<(i64, Coord<f64>)>> = HashMap::new();
    for (i, f) in &units {
        let id = fid(f, *i);
        let category = prop(f, "category")
            .and_then(Value::as_str)
            .unwrap_or("unspecified");
        let Some(fl) = floor_of_level(prop(f, "level_id")) else {
            shapes
                .warnings
                .add("units on an unknown level (skipped)", id);
            continue;
        };
        let Some(g) = &f.geometry else {
            shapes.warnings.add("units without geometry (skipped)", id);
            continue;
        };
        let polys = shapes.polygons(&g.value, &id);
        if let Some(p) = polys.first().and_then(|p| p.interior_point()) {
            places.entry(id.clone()).or_default().push((fl, p.0));
        }
        let Some(kind) = unit_kind(category) else {
            continue;
        };
        let name = label(prop(f, "name"));
        for (k, polygon) in polys.into_iter().enumerate() {
            spaces.push(Space {
                source: if k == 0 {
                    id.clone()
                } else {
                    format!("{id}#{k}")
                },
                name: name.clone(),
                kind,
                floor: fl,
                polygon,
            });
        }
    }
    let mut doors = Vec::new();
    for (i, f) in &openings {
        let id = fid(f, *i);
        let Some(fl) = floor_of_level(prop(f, "level_id")) else {
            shapes
                .warnings
                .add("openings on an unknown level (skipped)", id);
            continue;
        };
        match f
            .geometry
            .as_ref()
            .and_then(|g| shapes.point(&g.value, &id))
        {
            Some(pos) => {
                places.entry(id.clone()).or_default().push((fl, pos));
                doors.push(Door {
                    source: id,
                    pos,
                    floors: Some(vec![fl]),
                });
            }
            None => shapes
                .warnings
                .add("openings without a readable line (skipped)", id),
        }
    }
    let vertical = |c: &str| match c {
        "elevator" => Some(ConnectorKind::Elevator),
        "stairs" | "escalator" | "ramp" | "steps" => Some(ConnectorKind::Stairs),
        _ => None,
    };
    let mut connectors = Vec::new();
    for (i, f) in &amenities {
        let id = fid(f, *i);
        let Some(pos) = f
            .geometry
            .as_ref()
            .and_then(|g| shapes.point(&g.value, &id))
        else {
            continue;
        };
        let unit_floors: Vec<i64> = prop(f, "unit_ids")
            .and_then(Value::as_array)
            .map(|ids| {
                ids.iter()
                    .filter_map(Value::as_str)
                    .filter_map(|u| places.get(u))
                    .flat_map(|p| p.iter().map(|q| q.0))
                    .collect()
            })
            .unwrap_or_default();
        places
            .entry(id.clone())
            .or_default()
            .extend(unit_floors.iter().map(|&fl| (fl, pos)));
        let category = prop(f, "category").and_then(Value::as_str).unwrap_or("");
        if let Some(kind) = vertical(category) {
            let mut stops: Vec<(i64, Coord<f64>)> =
                unit_floors.iter().map(|&fl| (fl, pos)).collect();
            stops.sort_by_key(|s| s.0);
            stops.dedup_by_key(|s| s.0);
            if stops.len() >= 2 {
                connectors.push(Connector {
                    source: id,
                    kind,
                    stops,
                });
            }
        }
    }
    for (i, f) in &relationships {
        let id = fid(f, *i);
        let category = prop(f, "category").and_then(Value::as_str).unwrap_or("");
        let Some(kind) = vertical(category) else {
            continue;
        };
        let mut refs: Vec<&Value> = Vec::new();
        refs.extend(prop(f, "origin"));
        if let Some(Value::Array(list)) = prop(f, "intermediary") {
            refs.extend(list.iter());
        }
        refs.extend(prop(f, "destination"));
        let mut stops: Vec<(i64, Coord<f64>)> = Vec::new();
        for r in refs {
            let Some(rid) = r.get("id").and_then(Value::as_str) else {
                continue;
            };
            match places.get(rid) {
                Some(ps) => {
                    for &(fl, p) in ps {
                        if !stops.iter().any(|s| s.0 == fl) {
                            stops.push((fl, p));
                        }
                    }
                }
                None => shapes.warnings.add(
                    "relationships naming a feature that is not in the data set (that end left out)",
                    format!("{id} -> {rid}"),
                ),
            }
        }
        connectors.push(Connector {
            source: id,
            kind,
            stops,
        });
    }
    let name = venues
        .iter()
        .chain(&buildings)
        .find_map(|(_, f)| label(prop(f, "name")));
    let mut plan = Plan {
        name,
        geo,
        floors: {
            floors.sort_by_key(|f| f.id);
            floors
        },
        spaces,
        doors,
        walls: Vec::new(),
        connectors,
        outlines,
        warnings,
    };
    stack_shafts(&mut plan);
    Ok(plan)
}

fn collect(g: &geojson::GeometryValue, out: &mut Vec<(f64, f64)>) {
    super::osm::positions(g, out);
}

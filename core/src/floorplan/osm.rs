//! OpenStreetMap indoor data as GeoJSON (Simple Indoor Tagging), as Overpass exports it.
//!
//! What is read (tags either flat in `properties`, as overpass turbo writes them, or under
//! `properties.tags`, as osmtogeojson does):
//! - `indoor=room|corridor|area` polygons: walkable spaces (a closed way that came out as a
//!   LineString is taken as a polygon; an unclosed one is closed, with a warning);
//! - `indoor=wall` lines: walls, which edges cross only at doors;
//! - `door=*`, `entrance=*` and `indoor=door` nodes: doors;
//! - `highway=elevator` (a node or a shaft polygon), `highway=steps` (a way from one level to
//!   the next, going up in its direction unless `incline=down`), `stairs=yes` polygons and
//!   `indoor=area|corridor` polygons whose `level` spans several levels: vertical connections;
//! - `building=*` and `indoor=level` outlines: drawn only.
//!
//! `level` (and `repeat_on`) may be a number, a list (`0;1`) or a range (`0-2`, `-1--3`).
//! A feature without a level is put on level 0 (a door without a level joins whatever it
//! touches on any level), with a warning.

use std::collections::BTreeMap;

use geo::{Coord, InteriorPoint, LineString, Polygon, Validation};
use geojson::{Feature, GeometryValue, Position};
use serde_json::{Map, Value};

use super::{
    Connector, ConnectorKind, Door, LocalFrame, Plan, Space, SpaceKind, Wall, Warnings,
    floors_of_levels, level_key, origin_of,
};
use crate::{Error, Result};

/// Parses a level tag: numbers separated by `;`, each possibly a range `a-b`.
pub fn parse_levels(s: &str) -> Option<Vec<f64>> {
    let mut out = Vec::new();
    for part in s.split(';') {
        let part = part.trim();
        if part.is_empty() {
            continue;
        }
        if let Ok(v) = part.parse::<f64>() {
            if !v.is_finite() {
                return None;
            }
            out.push(v);
            continue;
        }
        let bytes = part.as_bytes();
        let mut found = None;
        for i in 1..bytes.len() {
            if bytes[i] == b'-'
                && let (Ok(a), Ok(b)) = (
                    part[..i].trim().parse::<f64>(),
                    part[i + 1..].trim().parse::<f64>(),
                )
                && a.is_finite()
                && b.is_finite()
            {
                found = Some((a.min(b), a.max(b)));
                break;
            }
        }
        let (a, b) = found?;
        if a.fract() == 0.0 && b.fract() == 0.0 && b - a <= 200.0 {
            let mut l = a;
            while l <= b {
                out.push(l);
                l += 1.0;
            }
        } else {
            out.push(a);
            out.push(b);
        }
    }
    out.sort_by(f64::total_cmp);
    out.dedup();
    (!out.is_empty()).then_some(out)
}

/// The tags of a feature: `properties.tags` (osmtogeojson) over flat `properties`.
fn tags_of(f: &Feature) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let Some(props) = &f.properties else {
        return out;
    };
    let mut put = |m: &Map<String, Value>| {
        for (k, v) in m {
            let s = match v {
                Value::String(s) => s.clone(),
                Value::Number(n) => n.to_string(),
                Value::Bool(b) => if *b { "yes" } else { "no" }.to_string(),
                _ => continue,
            };
            out.insert(k.clone(), s);
        }
    };
    put(props);
    if let Some(Value::Object(t)) = props.get("tags") {
        put(t);
    }
    out
}

fn id_of(f: &Feature, tags: &BTreeMap<String, String>, i: usize) -> String {
    match &f.id {
        Some(geojson::feature::Id::String(s)) => s.clone(),
        Some(geojson::feature::Id::Number(n)) => n.to_string(),
        None => tags
            .get("@id")
            .or_else(|| tags.get("id"))
            .cloned()
            .unwrap_or_else(|| format!("features[{i}]")),
    }
}

/// All positions of a geometry, as (lon, lat).
pub(crate) fn positions(g: &GeometryValue, out: &mut Vec<(f64, f64)>) {
    let mut push = |p: &Position| {
        let s = p.as_slice();
        if s.len() >= 2 {
            out.push((s[0], s[1]));
        }
    };
    match g {
        GeometryValue::Point { coordinates } => push(coordinates),
        GeometryValue::MultiPoint { coordinates } | GeometryValue::LineString { coordinates } => {
            coordinates.iter().for_each(push)
        }
        GeometryValue::MultiLineString { coordinates } | GeometryValue::Polygon { coordinates } => {
            coordinates.iter().flatten().for_each(push)
        }
        GeometryValue::MultiPolygon { coordinates } => {
            coordinates.iter().flatten().flatten().for_each(push)
        }
        GeometryValue::GeometryCollection { geometries } => {
            for g in geometries {
                positions(&g.value, out);
            }
        }
    }
}

/// Reads GeoJSON text into a list of features, each readable one on its own: a broken
/// feature is a warning, not the end of the import.
pub(crate) fn read_features(
    text: &str,
    origin: &str,
    warnings: &mut Warnings,
) -> Result<Vec<(usize, Feature)>> {
    let value: Value = serde_json::from_str(text).map_err(|e| Error::Parse {
        origin: origin.to_string(),
        path: "$".into(),
        message: format!(
            "not a GeoJSON floor plan: {} (`import-floorplan` reads OpenStreetMap indoor \
             GeoJSON, a FeatureCollection, or an IMDF folder or .zip; pilot fingerprints are \
             added with `trailprint pilot add NAME FILE.json`)",
            crate::building::not_json_object(text)
                .unwrap_or_else(|| format!("its JSON does not parse ({e})"))
        ),
    })?;
    let list = match &value {
        Value::Object(m) if m.get("type").and_then(Value::as_str) == Some("FeatureCollection") => {
            match m.get("features") {
                Some(Value::Array(a)) => a.clone(),
                _ => {
                    return Err(Error::Parse {
                        origin: origin.to_string(),
                        path: "features".into(),
                        message: "a FeatureCollection needs a `features` array".into(),
                    });
                }
            }
        }
        Value::Object(m) if m.get("type").and_then(Value::as_str) == Some("Feature") => {
            vec![value.clone()]
        }
        _ => {
            return Err(Error::Parse {
                origin: origin.to_string(),
                path: "$".into(),
                message: "expected a GeoJSON FeatureCollection (an object with \"type\": \
                          \"FeatureCollection\")"
                    .into(),
            });
        }
    };
    let mut out = Vec::with_capacity(list.len());
    for (i, v) in list.into_iter().enumerate() {
        match serde_json::from_value::<Feature>(v) {
            Ok(f) => out.push((i, f)),
            Err(e) => warnings.add(
                "unreadable features (skipped)",
                format!("features[{i}]: {e}"),
            ),
        }
    }
    Ok(out)
}

/// Converts GeoJSON rings to polygons in metres, repairing what can be repaired.
pub(crate) struct Shapes<'a> {
    pub frame: LocalFrame,
    pub warnings: &'a mut Warnings,
}

impl Shapes<'_> {
    fn coord(&self, p: &Position) -> Option<Coord<f64>> {
        let s = p.as_slice();
        if s.len() < 2
            || !s[0].is_finite()
            || !s[1].is_finite()
            || s[0].abs() > 180.0
            || s[1].abs() > 90.0
        {
            return None;
        }
        let (x, y) = self.frame.to_local(s[0], s[1]);
        Some(Coord { x, y })
    }

    /// A ring of positions in metres: `None` (with a warning) when it has fewer than 3
    /// distinct points or a bad coordinate. `warn_open`: say so when it is not closed.
    fn ring(&mut self, ring: &[Position], id: &str, warn_open: bool) -> Option<LineString<f64>> {
        let mut pts: Vec<Coord<f64>> = Vec::with_capacity(ring.len());
        for p in ring {
            match self.coord(p) {
                Some(c) => {
                    if pts.last() != Some(&c) {
                        pts.push(c);
                    }
                }
                None => {
                    self.warnings.add(
                        "features with coordinates that are not longitude/latitude (skipped)",
                        id,
                    );
                    return None;
                }
            }
        }
        let closed = pts.len() > 1 && pts.first() == pts.last();
        if closed {
            pts.pop();
        } else if warn_open && pts.len() >= 3 {
            self.warnings.add("unclosed rings (closed)", id);
        }
        let mut distinct = pts.clone();
        distinct.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        distinct.dedup();
        if distinct.len() < 3 {
            self.warnings
                .add("outlines with fewer than 3 distinct points (skipped)", id);
            return None;
        }
        Some(LineString::from(pts))
    }

    /// The polygons of a geometry (a LineString that is, or nearly is, a ring counts).
    pub(crate) fn polygons(&mut self, g: &GeometryValue, id: &str) -> Vec<Polygon<f64>> {
        let mut out = Vec::new();
        let mut one = |s: &mut Self, rings: &[Vec<Position>], warn_open: bool| {
            let Some(first) = rings.first() else { return };
            let Some(ext) = s.ring(first, id, warn_open) else {
                return;
            };
            let holes: Vec<LineString<f64>> = rings[1..]
                .iter()
                .filter_map(|r| s.ring(r, id, warn_open))
                .collect();
            let poly = Polygon::new(ext, holes);
            if geo::Area::unsigned_area(&poly) < 0.01 {
                s.warnings.add("outlines with no area (skipped)", id);
                return;
            }
            if !poly.is_valid() {
                s.warnings.add(
                    "self-intersecting or otherwise invalid outlines (used as drawn)",
                    id,
                );
            }
            out.push(poly);
        };
        match g {
            GeometryValue::Polygon { coordinates } => one(self, coordinates, true),
            GeometryValue::MultiPolygon { coordinates } => {
                for p in coordinates {
                    one(self, p, true);
                }
            }
            GeometryValue::LineString { coordinates } => {
                one(self, std::slice::from_ref(coordinates), true)
            }
            _ => {}
        }
        out
    }

    /// The lines of a geometry (a polygon's rings count, closed).
    pub(crate) fn lines(&mut self, g: &GeometryValue, id: &str) -> Vec<LineString<f64>> {
        let mut out = Vec::new();
        let line = |s: &Self, pts: &[Position]| {
            let cs: Option<Vec<Coord<f64>>> = pts.iter().map(|p| s.coord(p)).collect();
            match cs {
                Some(cs) if cs.len() >= 2 => Some(LineString::from(cs)),
                _ => None,
            }
        };
        match g {
            GeometryValue::LineString { coordinates } => out.extend(line(self, coordinates)),
            GeometryValue::MultiLineString { coordinates }
            | GeometryValue::Polygon { coordinates } => {
                out.extend(coordinates.iter().filter_map(|c| line(self, c)))
            }
            GeometryValue::MultiPolygon { coordinates } => {
                out.extend(coordinates.iter().flatten().filter_map(|c| line(self, c)))
            }
            _ => {}
        }
        if out.is_empty() {
            self.warnings
                .add("walls without a readable line (skipped)", id);
        }
        out
    }

    /// A representative point: the point itself, a line's middle vertex, a polygon's
    /// interior point.
    pub(crate) fn point(&mut self, g: &GeometryValue, id: &str) -> Option<Coord<f64>> {
        match g {
            GeometryValue::Point { coordinates } => self.coord(coordinates),
            GeometryValue::LineString { coordinates } if !coordinates.is_empty() => {
                let a = self.coord(&coordinates[0])?;
                let b = self.coord(&coordinates[coordinates.len() - 1])?;
                Some((a + b) / 2.0)
            }
            GeometryValue::Polygon { .. } | GeometryValue::MultiPolygon { .. } => self
                .polygons(g, id)
                .first()
                .and_then(|p| p.interior_point())
                .map(|p| p.0),
            _ => None,
        }
    }
}

/// What a feature is.
enum Role {
    Space(SpaceKind),
    Wall,
    Door,
    Elevator,
    Steps,
    Outline,
}

fn role_of(tags: &BTreeMap<String, String>, g: &GeometryValue) -> Option<Role> {
    let t = |k: &str| tags.get(k).map(String::as_str);
    let is_point = matches!(g, GeometryValue::Point { .. });
    let is_line = matches!(
        g,
        GeometryValue::LineString { .. } | GeometryValue::MultiLineString { .. }
    );
    let is_area = matches!(
        g,
        GeometryValue::Polygon { .. } | GeometryValue::MultiPolygon { .. }
    ) || matches!(g, GeometryValue::LineString { coordinates } if coordinates.len() >= 4
            && coordinates.first() == coordinates.last());
    let elevator = t("highway") == Some("elevator");
    let steps = t("highway") == Some("steps")
        || t("stairs") == Some("yes")
        || tags.contains_key("conveying");
    let indoor = t("indoor");
    if elevator {
        return Some(if is_point {
            Role::Elevator
        } else {
            Role::Space(SpaceKind::Elevator)
        });
    }
    if indoor == Some("door")
        || (is_point && (tags.contains_key("door") || tags.contains_key("entrance")))
    {
        return Some(Role::Door);
    }
    if t("highway") == Some("steps") && is_line && !is_area {
        return Some(Role::Steps);
    }
    match indoor {
        Some("room") | Some("corridor") | Some("area") if !is_point => {
            if steps {
                return Some(Role::Space(SpaceKind::Stairs));
            }
            Some(Role::Space(match indoor {
                Some("corridor") => SpaceKind::Corridor,
                Some("area") => SpaceKind::Area,
                _ => SpaceKind::Room,
            }))
        }
        Some("wall") if !is_point => Some(Role::Wall),
        Some("level") | Some("building") if is_area => Some(Role::Outline),
        _ if steps && is_area => Some(Role::Space(SpaceKind::Stairs)),
        _ if tags.get("building").is_some_and(|b| b != "no") && is_area => Some(Role::Outline),
        _ => None,
    }
}

/// Reads OSM indoor GeoJSON text into a plan in metres.
pub(crate) fn parse(text: &str, origin: &str) -> Result<Plan> {
    let mut warnings = Warnings::default();
    let features = read_features(text, origin, &mut warnings)?;
    let mut all = Vec::new();
    for (_, f) in &features {
        if let Some(g) = &f.geometry {
            positions(&g.value, &mut all);
        }
    }
    if all.is_empty() {
        return Err(Error::invalid(
            origin,
            "features",
            "nothing walkable: the file has no feature with coordinates",
        ));
    }
    let geo = origin_of(&all, origin)?;
    let frame = LocalFrame::new(geo);

    // First pass: roles and levels.
    struct Raw {
        id: String,
        tags: BTreeMap<String, String>,
        role: Role,
        levels: Option<Vec<f64>>,
        geometry: GeometryValue,
    }
    let mut raws = Vec::new();
    let mut level_values: Vec<f64> = Vec::new();
    let mut name = None;
    for (i, f) in features {
        let tags = tags_of(&f);
        let id = id_of(&f, &tags, i);
        let Some(geometry) = f.geometry.map(|g| g.value) else {
            warnings.add("features without geometry (skipped)", id);
            continue;
        };
        let Some(role) = role_of(&tags, &geometry) else {
            if tags.keys().all(|k| k.starts_with('@') || k == "id") {
                warnings.add("untagged features (ignored)", id);
            } else {
                warnings.add("features without indoor tagging (ignored)", id);
            }
            continue;
        };
        let mut levels = None;
        for key in ["level", "repeat_on"] {
            if let Some(v) = tags.get(key) {
                match parse_levels(v) {
                    Some(ls) => levels.get_or_insert_with(Vec::new).extend(ls),
                    None => warnings.add(
                        "unreadable level values (assumed level 0)",
                        format!("{id}: {key}={v}"),
                    ),
                }
            }
        }
        if let Some(ls) = &mut levels {
            ls.sort_by(f64::total_cmp);
            ls.dedup();
            level_values.extend(ls.iter().copied());
        }
        if matches!(role, Role::Outline) && name.is_none() {
            name = tags.get("name").cloned();
        }
        raws.push(Raw {
            id,
            tags,
            role,
            levels,
            geometry,
        });
    }
    let needs_default = raws
        .iter()
        .any(|r| r.levels.is_none() && !matches!(r.role, Role::Door | Role::Outline));
    if needs_default || level_values.is_empty() {
        level_values.push(0.0);
    }
    let (floors, level_map) = floors_of_levels(&level_values, &mut warnings);
    let floor_of = |l: f64| level_map.get(&level_key(l)).copied().unwrap_or(0);

    let shapes = &mut Shapes {
        frame,
        warnings: &mut warnings,
    };
    let mut spaces = Vec::new();
    let mut doors = Vec::new();
    let mut walls = Vec::new();
    let mut connectors = Vec::new();
    let mut outlines = Vec::new();
    for r in raws {
        let levels: Vec<i64> = match &r.levels {
            Some(ls) => ls.iter().map(|&l| floor_of(l)).collect(),
            None => {
                if !matches!(r.role, Role::Door | Role::Outline) {
                    shapes
                        .warnings
                        .add("features without a level (assumed level 0)", r.id.clone());
                }
                vec![floor_of(0.0)]
            }
        };
        let name = r.tags.get("name").or_else(|| r.tags.get("ref")).cloned();
        match r.role {
            Role::Space(kind) => {
                let polys = shapes.polygons(&r.geometry, &r.id);
                let multi = levels.len() > 1;
                let kind = match kind {
                    SpaceKind::Area | SpaceKind::Corridor if multi => SpaceKind::Stairs,
                    SpaceKind::Room if multi => {
                        shapes.warnings.add(
                            "rooms spanning several levels without stairs or elevator tags (not joined vertically)",
                            r.id.clone(),
                        );
                        SpaceKind::Room
                    }
                    k => k,
                };
                for (k, poly) in polys.into_iter().enumerate() {
                    let source = if k == 0 {
                        r.id.clone()
                    } else {
                        format!("{}#{k}", r.id)
                    };
                    if multi && matches!(kind, SpaceKind::Stairs | SpaceKind::Elevator) {
                        let p = poly.interior_point().map_or(poly.exterior().0[0], |p| p.0);
                        connectors.push(Connector {
                            source: source.clone(),
                            kind: if kind == SpaceKind::Elevator {
                                ConnectorKind::Elevator
                            } else {
                                ConnectorKind::Stairs
                            },
                            stops: levels.iter().map(|&f| (f, p)).collect(),
                        });
                    }
                    for &f in &levels {
                        spaces.push(Space {
                            source: source.clone(),
                            name: name.clone(),
                            kind,
                            floor: f,
                            polygon: poly.clone(),
                        });
                    }
                }
            }
            Role::Wall => {
                for line in shapes.lines(&r.geometry, &r.id) {
                    for &f in &levels {
                        walls.push(Wall {
                            floor: f,
                            line: line.clone(),
                        });
                    }
                }
            }
            Role::Door => match shapes.point(&r.geometry, &r.id) {
                Some(pos) => {
                    if r.levels.is_none() {
                        shapes.warnings.add(
                            "doors without a level (joined on every level they touch)",
                            r.id.clone(),
                        );
                    }
                    doors.push(Door {
                        source: r.id.clone(),
                        pos,
                        floors: r.levels.as_ref().map(|_| levels.clone()),
                    });
                }
                None => shapes
                    .warnings
                    .add("doors without a readable position (skipped)", r.id.clone()),
            },
            Role::Elevator => match shapes.point(&r.geometry, &r.id) {
                Some(p) => connectors.push(Connector {
                    source: r.id.clone(),
                    kind: ConnectorKind::Elevator,
                    stops: levels.iter().map(|&f| (f, p)).collect(),
                }),
                None => shapes.warnings.add(
                    "elevators without a readable position (skipped)",
                    r.id.clone(),
                ),
            },
            Role::Steps => {
                let lines = shapes.lines(&r.geometry, &r.id);
                let Some(line) = lines.first() else { continue };
                if levels.len() < 2 {
                    continue; // steps within one level: part of the walkable space
                }
                let (first, last) = (line.0[0], line.0[line.0.len() - 1]);
                let down = r
                    .tags
                    .get("incline")
                    .is_some_and(|v| v == "down" || v.starts_with('-'));
                let (lo, hi) = (levels[0], levels[levels.len() - 1]);
                let stops = if down {
                    vec![(hi, first), (lo, last)]
                } else {
                    vec![(lo, first), (hi, last)]
                };
                connectors.push(Connector {
                    source: r.id.clone(),
                    kind: ConnectorKind::Stairs,
                    stops,
                });
            }
            Role::Outline => {
                // A building outline without a level stands on every floor.
                let on: Vec<i64> = match &r.levels {
                    Some(_) => levels.clone(),
                    None => floors.iter().map(|f| f.id).collect(),
                };
                for poly in shapes.polygons(&r.geometry, &r.id) {
                    for &f in &on {
                        outlines.push((f, poly.clone()));
                    }
                }
            }
        }
    }
    let mut plan = Plan {
        name,
        geo,
        floors,
        spaces,
        doors,
        walls,
        connectors,
        outlines,
        warnings,
    };
    stack_shafts(&mut plan);
    Ok(plan)
}

/// Elevator and stair shafts drawn once per level (separate polygons, one above the other)
/// that no connection joins yet become one connection each: shafts of one kind on
/// different floors whose inner points lie in each other's outline.
pub(crate) fn stack_shafts(plan: &mut Plan) {
    use geo::Contains;
    let joined: Vec<(i64, Coord<f64>)> = plan
        .connectors
        .iter()
        .flat_map(|c| c.stops.iter().copied())
        .collect();
    let shafts: Vec<usize> = (0..plan.spaces.len())
        .filter(|&i| matches!(plan.spaces[i].kind, SpaceKind::Elevator | SpaceKind::Stairs))
        .filter(|&i| {
            let s = &plan.spaces[i];
            !joined
                .iter()
                .any(|(f, p)| *f == s.floor && s.polygon.contains(&geo::Point(*p)))
        })
        .collect();
    let mut used = vec![false; plan.spaces.len()];
    for &a in &shafts {
        if used[a] {
            continue;
        }
        let sa = &plan.spaces[a];
        let pa = sa
            .polygon
            .interior_point()
            .map_or(sa.polygon.exterior().0[0], |p| p.0);
        let mut group = vec![(sa.floor, pa)];
        used[a] = true;
        for &b in &shafts {
            let sb = &plan.spaces[b];
            if used[b] || sb.kind != sa.kind || group.iter().any(|g| g.0 == sb.floor) {
                continue;
            }
            let pb = sb
                .polygon
                .interior_point()
                .map_or(sb.polygon.exterior().0[0], |p| p.0);
            if sa.polygon.contains(&geo::Point(pb)) || sb.polygon.contains(&geo::Point(pa)) {
                group.push((sb.floor, pb));
                used[b] = true;
            }
        }
        if group.len() >= 2 {
            plan.connectors.push(Connector {
                source: sa.source.clone(),
                kind: if sa.kind == SpaceKind::Elevator {
                    ConnectorKind::Elevator
                } else {
                    ConnectorKind::Stairs
                },
                stops: group,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::parse_levels;

    #[test]
    fn level_lists_and_ranges() {
        assert_eq!(parse_levels("0"), Some(vec![0.0]));
        assert_eq!(parse_levels("0;1"), Some(vec![0.0, 1.0]));
        assert_eq!(parse_levels("0-2"), Some(vec![0.0, 1.0, 2.0]));
        assert_eq!(parse_levels("-1--3"), Some(vec![-3.0, -2.0, -1.0]));
        assert_eq!(parse_levels("-1;0.5"), Some(vec![-1.0, 0.5]));
        assert_eq!(parse_levels("ground"), None);
    }
}

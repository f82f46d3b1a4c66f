//! The walkable network of a [`Plan`]: what a surveyor can walk, as a building graph.
//!
//! Per floor:
//! 1. every walkable space gets a grid ([`geom::grid_points`]: rows and columns along its
//!    walls, about `spacing` apart, at least [`CLEARANCE_M`] from the walls), joined to its
//!    four neighbours where the segment stays inside; places the grid missed (a narrow arm
//!    off the grid's rows) are filled with the point of most clearance, and parts of one
//!    space that the grid left apart are bridged by their closest pair in sight. Shafts
//!    (elevators, stairs) and spaces too small for a grid point get one vertex inside.
//! 2. every door gets a vertex on the boundary, joined to the nearest vertices in sight of
//!    each space it touches (within [`DOOR_SNAP_M`]);
//! 3. a room, shaft or stairwell without a tagged door is joined to each corridor or open
//!    area it borders through a vertex in the middle of the longest boundary they share;
//!    corridors and areas that border each other are joined along their shared boundary
//!    (its middle, and every two spacings along a long one).
//!
//! No edge leaves its space (checked every 5 cm, [`JOIN_TOL_M`] of slack at doors and
//! shared boundaries) or crosses a wall line except within [`JOIN_TOL_M`] of a door or
//! joint. Floors are joined at stairs (consecutive levels, [`super::STAIRS_M_PER_LEVEL`]
//! per level) and elevators (every pair of levels served, [`super::ELEVATOR_BASE_M`] plus
//! [`super::ELEVATOR_M_PER_LEVEL`] per level). Last, the largest connected part is kept
//! and every other part is described in [`DroppedPart`]s.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};

use geo::{Area, BooleanOps, BoundingRect, Contains, Coord, InteriorPoint, Point, Polygon, Rect};

use super::geom::{
    self, boundary_distance, covers, dist, nearest_boundary_point, segment_within, shared_runs,
};
use super::{
    ConnectorKind, DroppedPart, ELEVATOR_BASE_M, ELEVATOR_M_PER_LEVEL, FloorplanImport, Format,
    ImportStats, Plan, STAIRS_M_PER_LEVEL, SpaceKind, Wall,
};
use crate::building::{
    Building, BuildingFile, EdgeSpec, FORMAT, FloorSpec, MAX_COORDINATE, Outline, OutlineKind,
    VertexSpec,
};
use crate::{Error, Result};

/// Grid points keep at least this distance from walls, metres.
pub const CLEARANCE_M: f64 = 0.3;
/// Most grid cells the walkable network tries over all spaces: 100,000, 0.4 km² of floor at
/// the default 2 m spacing (four floors of a mall 316 m square). That is 20 times the
/// largest network the planner takes under its default memory budget (about 5,000
/// vertices, `plan::DEFAULT_MEMORY_BUDGET`), so a plan that needs more is not a building
/// anyone can plan at this spacing: it is refused before any cell is laid, naming the
/// space, and a larger `--spacing` imports it. (It was 1,000,000 until the OSM fuzzer
/// found 11 KB plans that grew 261,506 vertices and took 8 s and 490 MB to import.)
pub const MAX_GRID_CELLS: usize = 100_000;
/// A door joins the spaces whose outline passes within this distance, metres.
pub const DOOR_SNAP_M: f64 = 0.5;
/// Slack of an edge at a door or a shared boundary, and of a wall crossing at a door, metres.
pub const JOIN_TOL_M: f64 = 0.1;
/// Two outlines closer than this share a boundary, metres.
pub const SHARED_TOL_M: f64 = 0.15;
/// A stair or elevator stop outside walkable space is moved onto the nearest space within
/// this distance, metres.
const STOP_SNAP_M: f64 = 3.0;
/// Storey height assumed for a long flight of steps, metres.
const STOREY_M: f64 = 3.0;

#[derive(Debug, Clone)]
struct NetVertex {
    id: String,
    floor: i64,
    pos: Coord<f64>,
    label: Option<String>,
    /// What it belongs to, for the report of dropped parts.
    what: String,
}

#[derive(Default)]
struct Net {
    verts: Vec<NetVertex>,
    at: HashMap<(i64, i64, i64), usize>,
    edges: Vec<(usize, usize, Option<f64>)>,
    pairs: HashSet<(usize, usize)>,
    /// Vertices of each space (by space index).
    space_verts: HashMap<usize, Vec<usize>>,
    /// Door and joint positions per floor: where edges may cross walls.
    portals: HashMap<i64, Vec<Coord<f64>>>,
}

fn floor_tag(f: i64) -> String {
    if f < 0 {
        format!("fm{}", -f)
    } else {
        format!("f{f}")
    }
}

/// Rounds to the millimetre, the precision of the written file.
fn mm(c: Coord<f64>) -> Coord<f64> {
    Coord {
        x: (c.x * 1000.0).round() / 1000.0,
        y: (c.y * 1000.0).round() / 1000.0,
    }
}

impl Net {
    /// Adds a vertex, or returns the one already at this millimetre of this floor.
    fn vertex(
        &mut self,
        floor: i64,
        pos: Coord<f64>,
        id: String,
        label: Option<String>,
        what: String,
    ) -> usize {
        let pos = mm(pos);
        let key = (
            floor,
            (pos.x * 1000.0).round() as i64,
            (pos.y * 1000.0).round() as i64,
        );
        if let Some(&v) = self.at.get(&key) {
            return v;
        }
        let v = self.verts.len();
        self.verts.push(NetVertex {
            id,
            floor,
            pos,
            label,
            what,
        });
        self.at.insert(key, v);
        v
    }

    fn edge(&mut self, a: usize, b: usize, length: Option<f64>) -> bool {
        if a == b || !self.pairs.insert((a.min(b), a.max(b))) {
            return false;
        }
        self.edges.push((a, b, length));
        true
    }

    fn has_edge(&self, a: usize, b: usize) -> bool {
        self.pairs.contains(&(a.min(b), a.max(b)))
    }
}

/// Everything the checks of one floor need.
struct FloorCtx<'a> {
    floor: i64,
    walls: Vec<&'a geo::LineString<f64>>,
}

impl<'a> FloorCtx<'a> {
    /// Floor `floor` with the walls of that floor.
    fn new(floor: i64, walls: &'a [Wall]) -> Self {
        FloorCtx {
            floor,
            walls: walls
                .iter()
                .filter(|w| w.floor == floor)
                .map(|w| &w.line)
                .collect(),
        }
    }

    /// Whether the segment crosses no wall except within [`JOIN_TOL_M`] of a portal.
    fn walls_ok(&self, net: &Net, a: Coord<f64>, b: Coord<f64>) -> bool {
        if self.walls.is_empty() {
            return true;
        }
        let portals = net.portals.get(&self.floor);
        geom::wall_crossings(a, b, &self.walls)
            .into_iter()
            .all(|c| portals.is_some_and(|ps| ps.iter().any(|p| dist(*p, c) <= JOIN_TOL_M)))
    }
}

/// Joins vertex `v` (on the boundary of or inside `space`) to up to `k` of the space's
/// nearest vertices in sight. Returns how many it joined.
fn connect_into(
    net: &mut Net,
    ctx: &FloorCtx<'_>,
    poly: &Polygon<f64>,
    space: usize,
    v: usize,
    k: usize,
) -> usize {
    let pv = net.verts[v].pos;
    let mut cands: Vec<(f64, usize)> = net
        .space_verts
        .get(&space)
        .map(|list| {
            list.iter()
                .filter(|&&w| w != v)
                .map(|&w| (dist(pv, net.verts[w].pos), w))
                .collect()
        })
        .unwrap_or_default();
    cands.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut joined = 0;
    for (_, w) in cands {
        if joined >= k {
            break;
        }
        let pw = net.verts[w].pos;
        if net.has_edge(v, w) {
            joined += 1;
            continue;
        }
        if segment_within(poly, pv, pw, JOIN_TOL_M) && ctx.walls_ok(net, pv, pw) {
            net.edge(v, w, None);
            joined += 1;
        }
    }
    joined
}

fn rect_gap(a: &Rect<f64>, b: &Rect<f64>) -> f64 {
    let dx = (a.min().x - b.max().x).max(b.min().x - a.max().x).max(0.0);
    let dy = (a.min().y - b.max().y).max(b.min().y - a.max().y).max(0.0);
    dx.hypot(dy)
}

/// Lays the network of `plan` and writes the building.
pub(crate) fn build(
    plan: Plan,
    format: Format,
    spacing: f64,
    max_cells: usize,
    name: String,
    origin: &str,
) -> Result<FloorplanImport> {
    let Plan {
        name: _,
        geo,
        floors,
        spaces,
        doors,
        walls,
        connectors,
        outlines: building_outlines,
        mut warnings,
    } = plan;
    if spaces.is_empty() {
        return Err(Error::invalid(
            origin,
            "$",
            match format {
                Format::OsmIndoor => {
                    "nothing walkable: no polygon tagged indoor=room, indoor=corridor or \
                     indoor=area (Simple Indoor Tagging) with a readable outline"
                }
                Format::Imdf => {
                    "nothing walkable: no unit with a walkable category and a readable outline"
                }
            },
        ));
    }
    // The grid's size before laying it: a space a degree across (a typo in a coordinate, a
    // feature in the wrong place) would otherwise take hours and all the memory there is.
    let mut cells = 0.0;
    for sp in &spaces {
        // A space placed beyond the building format's coordinate range (a mutated
        // latitude puts it thousands of kilometres from the rest): its vertices would be
        // refused by the validator anyway, after seconds of gridding at coordinates where
        // millimetre geometry no longer holds (found by `floorplan_osm`: 12 s).
        if let Some(r) = sp.polygon.bounding_rect() {
            let far = [r.min().x, r.min().y, r.max().x, r.max().y]
                .into_iter()
                .map(f64::abs)
                .fold(0.0, f64::max);
            if far.is_nan() || far > MAX_COORDINATE {
                return Err(Error::invalid(
                    origin,
                    "$",
                    format!(
                        "{} on floor {} lies {far:.3e} m from the plan's origin, beyond the \
                         building format's limit of {MAX_COORDINATE:e} m: check its coordinates",
                        sp.describe(),
                        sp.floor
                    ),
                ));
            }
        }
        if matches!(sp.kind, SpaceKind::Elevator | SpaceKind::Stairs) {
            continue;
        }
        let (n, w, h) = geom::grid_cells(&sp.polygon, spacing);
        cells += n;
        if cells > max_cells as f64 {
            return Err(Error::invalid(
                origin,
                "$",
                format!(
                    "the walkable network would need {cells:.3e} grid cells at {spacing} m \
                     spacing, over the limit of {max_cells} ({} is {w:.0} m by {h:.0} m \
                     on floor {}): check its coordinates, or import with a larger spacing",
                    sp.describe(),
                    sp.floor
                ),
            ));
        }
    }
    let rank: BTreeMap<i64, usize> = floors.iter().enumerate().map(|(i, f)| (f.id, i)).collect();
    let mut net = Net::default();
    // Pairs `bridge` may still measure in this import (shared by every space).
    let mut bridge_budget = BRIDGE_MAX_PAIRS;
    let mut spaces_with_vertices = BTreeSet::new();
    let mut doors_used = 0usize;
    let mut door_touched = vec![false; doors.len()];
    let bboxes: Vec<Option<Rect<f64>>> = spaces.iter().map(|s| s.polygon.bounding_rect()).collect();

    for floor in &floors {
        let f = floor.id;
        let ft = floor_tag(f);
        let ctx = FloorCtx::new(f, &walls);
        // Doors given for this floor count as portals from the start (grid edges may pass
        // a wall there).
        for d in &doors {
            if d.floors.as_ref().is_none_or(|fl| fl.contains(&f)) {
                net.portals.entry(f).or_default().push(d.pos);
            }
        }
        let on_floor: Vec<usize> = (0..spaces.len())
            .filter(|&i| spaces[i].floor == f)
            .collect();

        // 1. The grid of each space.
        for &si in &on_floor {
            let sp = &spaces[si];
            let poly = &sp.polygon;
            let what = sp.describe();
            let mut k = 0usize;
            let new_id = |k: &mut usize| {
                *k += 1;
                format!("{ft}-s{si}-{k}")
            };
            let mut mine: Vec<usize> = Vec::new();
            let grid = if matches!(sp.kind, SpaceKind::Elevator | SpaceKind::Stairs) {
                Vec::new()
            } else {
                geom::grid_points(poly, spacing, CLEARANCE_M)
            };
            let mut cell: HashMap<(usize, usize), usize> = HashMap::new();
            for g in &grid {
                let v = net.vertex(f, g.pos, new_id(&mut k), sp.name.clone(), what.clone());
                cell.insert((g.row, g.col), v);
                mine.push(v);
            }
            for g in &grid {
                let v = cell[&(g.row, g.col)];
                for (dr, dc) in [(0, 1), (1, 0)] {
                    if let Some(&w) = cell.get(&(g.row + dr, g.col + dc)) {
                        let (a, b) = (net.verts[v].pos, net.verts[w].pos);
                        if segment_within(poly, a, b, 0.0) && ctx.walls_ok(&net, a, b) {
                            net.edge(v, w, None);
                        }
                    }
                }
            }
            if mine.is_empty() {
                let p = poly
                    .interior_point()
                    .map(|p| p.0)
                    .unwrap_or_else(|| poly.exterior().0[0]);
                // A shaft's vertex says what it is (its name stays on the outline).
                let label = match sp.kind {
                    SpaceKind::Elevator | SpaceKind::Stairs => Some(sp.kind.as_str().to_string()),
                    _ => sp.name.clone(),
                };
                mine.push(net.vertex(f, p, new_id(&mut k), label, what.clone()));
            } else {
                fill_gaps(
                    &mut net,
                    &ctx,
                    poly,
                    spacing,
                    &mut mine,
                    &mut || new_id(&mut k),
                    sp.name.clone(),
                    &what,
                );
            }
            net.space_verts.insert(si, mine.clone());
            bridge(&mut net, &ctx, poly, &mine, spacing, &mut bridge_budget);
            spaces_with_vertices.insert(si);
        }

        // 2. Doors.
        let mut door_pairs: HashSet<(usize, usize)> = HashSet::new();
        let mut has_door: HashSet<usize> = HashSet::new();
        for (di, d) in doors.iter().enumerate() {
            if d.floors.as_ref().is_some_and(|fl| !fl.contains(&f)) {
                continue;
            }
            let mut touching: Vec<(f64, usize)> = on_floor
                .iter()
                .map(|&si| (boundary_distance(&spaces[si].polygon, d.pos), si))
                .filter(|&(dd, si)| dd <= DOOR_SNAP_M || spaces[si].polygon.contains(&Point(d.pos)))
                .collect();
            if touching.is_empty() {
                continue;
            }
            door_touched[di] = true;
            touching.sort_by(|a, b| a.0.total_cmp(&b.0));
            // A door on the wall two spaces share is theirs alone: a neighbouring room
            // whose corner is within DOOR_SNAP_M is not behind it (and, were it counted,
            // would lose its shared-boundary joint to a door it cannot be entered by).
            let on_wall = |&(dd, si): &(f64, usize)| {
                dd <= SHARED_TOL_M || spaces[si].polygon.contains(&Point(d.pos))
            };
            if touching.iter().filter(|t| on_wall(t)).count() >= 2 {
                touching.retain(on_wall);
            }
            let nearest = touching[0].1;
            let pos = if spaces[nearest].polygon.contains(&Point(d.pos)) && touching.len() == 1 {
                d.pos
            } else {
                nearest_boundary_point(&spaces[nearest].polygon, d.pos)
            };
            net.portals.entry(f).or_default().push(mm(pos));
            let v = net.vertex(
                f,
                pos,
                format!("{ft}-d{di}"),
                Some("door".into()),
                format!("door {}", d.source),
            );
            let mut joined: Vec<usize> = Vec::new();
            for &(_, si) in &touching {
                if connect_into(&mut net, &ctx, &spaces[si].polygon, si, v, 2) > 0 {
                    joined.push(si);
                    has_door.insert(si);
                } else {
                    warnings.add(
                        "doors with no vertex of a space they touch in sight",
                        format!("{} / {}", d.source, spaces[si].describe()),
                    );
                }
            }
            // Only spaces the door really joins skip their shared-boundary joint.
            for (i, &a) in joined.iter().enumerate() {
                for &b in &joined[i + 1..] {
                    door_pairs.insert((a.min(b), a.max(b)));
                }
            }
            if !joined.is_empty() {
                doors_used += 1;
            }
        }

        // 3. Shared boundaries.
        for (i, &a) in on_floor.iter().enumerate() {
            for &b in &on_floor[i + 1..] {
                let (sa, sb) = (&spaces[a], &spaces[b]);
                let (Some(ra), Some(rb)) = (bboxes[a], bboxes[b]) else {
                    continue;
                };
                if rect_gap(&ra, &rb) > SHARED_TOL_M {
                    continue;
                }
                if sa.kind.is_open() || sb.kind.is_open() {
                    let overlap = sa.polygon.intersection(&sb.polygon).unsigned_area();
                    if overlap > 0.5 {
                        warnings.add(
                            "overlapping walkable polygons (joined where they overlap)",
                            format!("{} / {}", sa.source, sb.source),
                        );
                    }
                } else {
                    continue; // two rooms: only a door joins them
                }
                if door_pairs.contains(&(a.min(b), a.max(b))) {
                    continue;
                }
                // Sample along the room's (or the smaller space's) outline.
                let (room, other) = match (sa.kind.is_open(), sb.kind.is_open()) {
                    (false, true) => (a, b),
                    (true, false) => (b, a),
                    _ => {
                        if sa.polygon.unsigned_area() <= sb.polygon.unsigned_area() {
                            (a, b)
                        } else {
                            (b, a)
                        }
                    }
                };
                let open_pair = spaces[room].kind.is_open();
                if !open_pair && has_door.contains(&room) {
                    continue; // the room's own door is its way in
                }
                let runs = shared_runs(&spaces[room].polygon, &spaces[other].polygon, SHARED_TOL_M);
                let mut points: Vec<Coord<f64>> = Vec::new();
                if open_pair {
                    for run in runs.iter().filter(|r| r.length >= 0.5) {
                        let step = 2.0 * spacing;
                        let n = (run.length / step).floor().max(0.0) as usize + 1;
                        let first = (run.length - (n - 1) as f64 * step) / 2.0;
                        points.extend((0..n).map(|j| run.at(first + j as f64 * step)));
                    }
                } else if let Some(run) = runs.first().filter(|r| r.length >= 0.3) {
                    points.push(run.middle());
                }
                for (j, p) in points.into_iter().enumerate() {
                    net.portals.entry(f).or_default().push(mm(p));
                    let v = net.vertex(
                        f,
                        p,
                        format!("{ft}-j{room}-{other}-{j}"),
                        Some("opening".into()),
                        format!("opening {} / {}", spaces[room].source, spaces[other].source),
                    );
                    let n1 = connect_into(&mut net, &ctx, &spaces[room].polygon, room, v, 2);
                    let n2 = connect_into(&mut net, &ctx, &spaces[other].polygon, other, v, 2);
                    if n1 == 0 || n2 == 0 {
                        warnings.add(
                            "shared boundaries with no vertex in sight on one side",
                            format!("{} / {}", spaces[room].source, spaces[other].source),
                        );
                    }
                }
            }
        }
    }

    for (d, touched) in doors.iter().zip(&door_touched) {
        if !touched {
            warnings.add(
                "doors on the outline of no walkable space (ignored)",
                d.source.clone(),
            );
        }
    }

    // 4. Vertical connections.
    let mut connectors_used = 0usize;
    for (ci, c) in connectors.iter().enumerate() {
        let mut stops: Vec<(usize, i64, usize)> = Vec::new(); // (rank, floor, vertex)
        for &(f, p) in &c.stops {
            let Some(&r) = rank.get(&f) else { continue };
            let ctx = FloorCtx::new(f, &walls);
            // The smallest space on that floor that holds the stop (the shaft itself).
            let holding = (0..spaces.len())
                .filter(|&si| spaces[si].floor == f && covers(&spaces[si].polygon, p, JOIN_TOL_M))
                .min_by(|&x, &y| {
                    spaces[x]
                        .polygon
                        .unsigned_area()
                        .total_cmp(&spaces[y].polygon.unsigned_area())
                });
            let (si, pos) = match holding {
                Some(si) => (si, p),
                None => {
                    let near = (0..spaces.len())
                        .filter(|&si| spaces[si].floor == f)
                        .map(|si| (boundary_distance(&spaces[si].polygon, p), si))
                        .filter(|&(d, _)| d <= STOP_SNAP_M)
                        .min_by(|x, y| x.0.total_cmp(&y.0));
                    match near {
                        Some((_, si)) => {
                            warnings.add(
                                "stair and elevator stops outside walkable space (moved onto the nearest space within 3 m)",
                                format!("{} level {f}", c.source),
                            );
                            let q = nearest_boundary_point(&spaces[si].polygon, p);
                            // Step 0.2 m inside, towards the space's inner point.
                            let inner = spaces[si].polygon.interior_point().map_or(q, |ip| ip.0);
                            let d = dist(q, inner);
                            let pos = if d > 0.2 {
                                q + (inner - q) * (0.2 / d)
                            } else {
                                q
                            };
                            (si, pos)
                        }
                        None => {
                            warnings.add(
                                "stair and elevator stops with no walkable space on their level (left out)",
                                format!("{} level {f}", c.source),
                            );
                            continue;
                        }
                    }
                }
            };
            let (tag, label) = match c.kind {
                ConnectorKind::Elevator => ("e", "elevator"),
                ConnectorKind::Stairs => ("t", "stairs"),
            };
            let v = net.vertex(
                f,
                pos,
                format!("{}-{tag}{ci}", floor_tag(f)),
                Some(label.into()),
                format!("{label} {}", c.source),
            );
            if connect_into(&mut net, &ctx, &spaces[si].polygon, si, v, 2) == 0
                && net.space_verts.get(&si).is_none_or(|l| !l.contains(&v))
            {
                warnings.add(
                    "stair and elevator stops with no vertex in sight",
                    format!("{} level {f}", c.source),
                );
            }
            if !stops.iter().any(|s| s.1 == f) {
                stops.push((r, f, v));
            }
        }
        stops.sort_unstable();
        if stops.len() < 2 {
            warnings.add(
                "stairs and elevators reaching fewer than two levels (not joined)",
                c.source.clone(),
            );
            continue;
        }
        match c.kind {
            ConnectorKind::Elevator => {
                for (i, a) in stops.iter().enumerate() {
                    for b in &stops[i + 1..] {
                        let levels = (b.0 - a.0) as f64;
                        net.edge(
                            a.2,
                            b.2,
                            Some(ELEVATOR_BASE_M + ELEVATOR_M_PER_LEVEL * levels),
                        );
                    }
                }
            }
            ConnectorKind::Stairs => {
                for w in stops.windows(2) {
                    let levels = (w[1].0 - w[0].0) as f64;
                    let run = dist(net.verts[w[0].2].pos, net.verts[w[1].2].pos);
                    let len = (STAIRS_M_PER_LEVEL * levels).max(run.hypot(STOREY_M * levels));
                    net.edge(w[0].2, w[1].2, Some(len));
                }
            }
        }
        connectors_used += 1;
    }

    // 5. Keep the largest connected part.
    let n = net.verts.len();
    let mut adj = vec![Vec::new(); n];
    for &(a, b, _) in &net.edges {
        adj[a].push(b);
        adj[b].push(a);
    }
    let mut comp = vec![usize::MAX; n];
    let mut comps: Vec<Vec<usize>> = Vec::new();
    for s in 0..n {
        if comp[s] != usize::MAX {
            continue;
        }
        let c = comps.len();
        comp[s] = c;
        let mut stack = vec![s];
        let mut members = Vec::new();
        while let Some(v) = stack.pop() {
            members.push(v);
            for &w in &adj[v] {
                if comp[w] == usize::MAX {
                    comp[w] = c;
                    stack.push(w);
                }
            }
        }
        members.sort_unstable();
        comps.push(members);
    }
    let keep = (0..comps.len())
        .max_by(|&a, &b| comps[a].len().cmp(&comps[b].len()).then(b.cmp(&a)))
        .unwrap_or(0);
    let mut dropped = Vec::new();
    for (ci, members) in comps.iter().enumerate() {
        if ci == keep {
            continue;
        }
        let floors: BTreeSet<i64> = members.iter().map(|&v| net.verts[v].floor).collect();
        let mut what: Vec<String> = Vec::new();
        for &v in members {
            let w = &net.verts[v].what;
            if !what.contains(w) {
                what.push(w.clone());
            }
        }
        if what.len() > 8 {
            let more = what.len() - 8;
            what.truncate(8);
            what.push(format!("and {more} more"));
        }
        dropped.push(DroppedPart {
            vertices: members.len(),
            floors: floors.into_iter().collect(),
            spaces: what,
        });
    }
    dropped.sort_by_key(|d| std::cmp::Reverse(d.vertices));
    let kept: HashSet<usize> = comps
        .get(keep)
        .map(|m| m.iter().copied().collect())
        .unwrap_or_default();

    // 6. The building file.
    let kept_floors: BTreeSet<i64> = kept.iter().map(|&v| net.verts[v].floor).collect();
    let floor_specs: Vec<FloorSpec> = floors
        .iter()
        .filter(|f| kept_floors.contains(&f.id))
        .cloned()
        .collect();
    let vertices: Vec<VertexSpec> = (0..n)
        .filter(|v| kept.contains(v))
        .map(|v| {
            let nv = &net.verts[v];
            VertexSpec {
                id: nv.id.clone(),
                x: nv.pos.x,
                y: nv.pos.y,
                floor: nv.floor,
                label: nv.label.clone(),
            }
        })
        .collect();
    let edges: Vec<EdgeSpec> = net
        .edges
        .iter()
        .filter(|(a, _, _)| kept.contains(a))
        .map(|&(a, b, length)| EdgeSpec {
            a: net.verts[a].id.clone(),
            b: net.verts[b].id.clone(),
            length,
        })
        .collect();
    let mut outlines = Vec::new();
    let ring = |ls: &geo::LineString<f64>| -> Vec<[f64; 2]> {
        let mut pts: Vec<[f64; 2]> = Vec::new();
        for c in ls.coords() {
            let c = mm(*c);
            if pts.last() != Some(&[c.x, c.y]) {
                pts.push([c.x, c.y]);
            }
        }
        pts
    };
    let closed_ring = |ls: &geo::LineString<f64>| -> Option<Vec<[f64; 2]>> {
        let mut pts = ring(ls);
        if pts.len() > 1 && pts.first() == pts.last() {
            pts.pop();
        }
        let distinct: BTreeSet<(u64, u64)> = pts
            .iter()
            .map(|p| (p[0].to_bits(), p[1].to_bits()))
            .collect();
        (distinct.len() >= 3).then_some(pts)
    };
    // A wall (a hole of a space, or a wall line) is drawn when it has two points.
    let push_wall = |out: &mut Vec<Outline>, floor: i64, points: Vec<[f64; 2]>| {
        if points.len() >= 2 {
            out.push(Outline {
                floor,
                kind: OutlineKind::Wall,
                name: None,
                points,
            });
        }
    };
    for (f, poly) in &building_outlines {
        if !kept_floors.contains(f) {
            continue;
        }
        if let Some(points) = closed_ring(poly.exterior()) {
            outlines.push(Outline {
                floor: *f,
                kind: OutlineKind::Building,
                name: None,
                points,
            });
        }
    }
    for sp in &spaces {
        if !kept_floors.contains(&sp.floor) {
            continue;
        }
        let kind = match sp.kind {
            SpaceKind::Corridor => OutlineKind::Corridor,
            SpaceKind::Area => OutlineKind::Area,
            SpaceKind::Room | SpaceKind::Elevator | SpaceKind::Stairs => OutlineKind::Room,
        };
        if let Some(points) = closed_ring(sp.polygon.exterior()) {
            outlines.push(Outline {
                floor: sp.floor,
                kind,
                name: sp.name.clone(),
                points,
            });
        }
        for hole in sp.polygon.interiors() {
            push_wall(&mut outlines, sp.floor, ring(hole));
        }
    }
    for w in walls.iter().filter(|w| kept_floors.contains(&w.floor)) {
        push_wall(&mut outlines, w.floor, ring(&w.line));
    }

    let file = BuildingFile {
        format: FORMAT.into(),
        name,
        floors: Some(floor_specs),
        vertices,
        edges,
        pilot: Vec::new(),
        test_points: Vec::new(),
        dense_survey: Vec::new(),
        kernel: None,
        geo: Some(geo),
        outlines,
    };
    // The network is built to pass; this is the importer checking itself.
    let b = Building::from_file(file.clone(), origin)?;
    let stats = ImportStats {
        floors: b.floors.len(),
        spaces: spaces_with_vertices
            .iter()
            .filter(|si| {
                net.space_verts
                    .get(si)
                    .is_some_and(|l| l.iter().any(|v| kept.contains(v)))
            })
            .count(),
        doors: doors_used,
        connectors: connectors_used,
        vertices: b.vertices.len(),
        edges: b.edges.len(),
    };
    Ok(FloorplanImport {
        file,
        format,
        warnings: warnings.into_list(),
        dropped,
        stats,
    })
}

/// Adds a vertex wherever a point of the space with room to stand is farther than
/// `spacing` from every vertex of the space (the grid's rows missed it), the point of most
/// clearance first, and joins it to the space's vertices within 1.5 spacings in sight.
#[allow(clippy::too_many_arguments)]
fn fill_gaps(
    net: &mut Net,
    ctx: &FloorCtx<'_>,
    poly: &Polygon<f64>,
    spacing: f64,
    mine: &mut Vec<usize>,
    new_id: &mut dyn FnMut() -> String,
    label: Option<String>,
    what: &str,
) {
    let Some(bb) = poly.bounding_rect() else {
        return;
    };
    let step = spacing / 2.0;
    let mut cands: Vec<(Coord<f64>, f64)> = Vec::new();
    let nx = ((bb.width() / step).floor() as usize).min(4000);
    let ny = ((bb.height() / step).floor() as usize).min(4000);
    for j in 0..=ny {
        for i in 0..=nx {
            let p = Coord {
                x: bb.min().x + (i as f64 + 0.5) * step,
                y: bb.min().y + (j as f64 + 0.5) * step,
            };
            if !poly.contains(&Point(p)) {
                continue;
            }
            let clear = boundary_distance(poly, p);
            if clear >= CLEARANCE_M {
                cands.push((p, clear));
            }
        }
    }
    // Buckets of `spacing` metres: every query below is a radius of at most 1.5 spacings,
    // so it reads the 5 x 5 buckets around a point, not every vertex of the space (the scan
    // of every pair was quadratic: 51 s for a 400 m hall of 40,000 vertices, found by the
    // `floorplan_imdf` fuzz target as timeouts).
    let key = |p: Coord<f64>| {
        (
            (p.x / spacing).floor() as i64,
            (p.y / spacing).floor() as i64,
        )
    };
    let around = |p: Coord<f64>| {
        let (kx, ky) = key(p);
        (-2..=2).flat_map(move |dx| (-2..=2).map(move |dy| (kx + dx, ky + dy)))
    };
    // The space's vertices, each with its place in `mine` (edges are added in that order).
    let mut verts: HashMap<(i64, i64), Vec<(usize, usize)>> = HashMap::new();
    for (i, &v) in mine.iter().enumerate() {
        verts.entry(key(net.verts[v].pos)).or_default().push((i, v));
    }
    let mut in_mine: HashSet<usize> = mine.iter().copied().collect();
    let mut cand_at: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (j, c) in cands.iter().enumerate() {
        cand_at.entry(key(c.0)).or_default().push(j);
    }
    let mut covered: Vec<bool> = cands
        .iter()
        .map(|(p, _)| {
            around(*p).any(|k| {
                verts.get(&k).is_some_and(|vs| {
                    vs.iter()
                        .any(|&(_, v)| dist(*p, net.verts[v].pos) <= spacing)
                })
            })
        })
        .collect();
    // The point of most clearance first (ties: the first in scan order). Covering only
    // ever grows, so taking them in this order is the same as picking the best uncovered
    // point again after every vertex added.
    let mut order: Vec<usize> = (0..cands.len()).collect();
    order.sort_by(|&a, &b| cands[b].1.total_cmp(&cands[a].1).then(a.cmp(&b)));
    for i in order {
        if covered[i] {
            continue;
        }
        let p = cands[i].0;
        let v = net.vertex(ctx.floor, p, new_id(), label.clone(), what.to_string());
        for k in around(p) {
            for &j in cand_at.get(&k).into_iter().flatten() {
                if dist(cands[j].0, p) <= spacing {
                    covered[j] = true;
                }
            }
        }
        let mut near: Vec<(usize, usize)> = around(p)
            .flat_map(|k| verts.get(&k).into_iter().flatten().copied())
            .filter(|&(_, w)| w != v && dist(net.verts[w].pos, p) <= 1.5 * spacing)
            .collect();
        near.sort_unstable();
        for (_, w) in near {
            let pw = net.verts[w].pos;
            if segment_within(poly, p, pw, 0.0) && ctx.walls_ok(net, p, pw) {
                net.edge(v, w, None);
            }
        }
        if in_mine.insert(v) {
            verts.entry(key(p)).or_default().push((mine.len(), v));
            mine.push(v);
        }
    }
}

/// Most vertex pairs [`bridge`] measures in one import, over all its spaces and joins:
/// 50,000,000 (one join of two halves of a 14,000-vertex space, a hall of about 5 hectares
/// at 2 m; about 0.25 s). A space in so many parts that joining them would take more (a
/// sliver kilometres long from a typo in a coordinate: found by the `floorplan_imdf` fuzz
/// target, over 120 s) keeps the parts not yet joined; those no door joins later are
/// dropped and reported ([`DroppedPart`]) like any other part. The budget was per space
/// until `floorplan_osm` found an 11 KB plan of many such slivers: each spent its own
/// 50,000,000 and the import took 0.7 s in release (22 s under the sanitizer) for 200
/// vertices.
pub(crate) const BRIDGE_MAX_PAIRS: usize = 50_000_000;

/// Joins the parts of one space's network that the grid left apart, in two passes.
///
/// 1. Near pass ([`join_near`]): the pairs of vertices in different parts at most
///    [`NEAR_CELLS`] spacings apart, from each vertex outside the largest part its
///    [`NEAR_KEPT`] closest, are tried closest first, and each one in sight joins its two
///    parts (Kruskal's order: the shortest bridges of the space). Its work is linear in the
///    space's vertices.
/// 2. What is left apart: each time the closest pair in sight (up to 400 pairs tried per
///    join) between the part of the space's first vertex and the rest, until one part is
///    left, no pair in sight joins, or [`BRIDGE_MAX_PAIRS`] pairs have been measured.
///
/// (Pass 2 alone did all the joining until 3 December: a space in hundreds of parts, the
/// spikes of a mutated outline, spent the whole pair budget, and each of its joins tried
/// pairs hundreds of metres long, sampled along their length; found by `floorplan_osm`,
/// 3 s for a plan of 1,434 vertices under the sanitizer.)
fn bridge(
    net: &mut Net,
    ctx: &FloorCtx<'_>,
    poly: &Polygon<f64>,
    mine: &[usize],
    spacing: f64,
    budget: &mut usize,
) {
    /// Pairs tried per join, closest first.
    const TRIED: usize = 400;
    if mine.len() < 2 {
        return;
    }
    let local: HashMap<usize, usize> = mine.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    // Parts of the space's vertices over its edges so far; each join below merges two (the
    // edges were read again for every join, which a space in thousands of parts made
    // quadratic in the whole floor's edges).
    let mut parent: Vec<usize> = (0..mine.len()).collect();
    for &(a, b, _) in &net.edges {
        if let (Some(&ia), Some(&ib)) = (local.get(&a), local.get(&b)) {
            let (ra, rb) = (find(&mut parent, ia), find(&mut parent, ib));
            parent[ra] = rb;
        }
    }
    join_near(net, ctx, poly, mine, spacing, &mut parent);
    loop {
        let root0 = find(&mut parent, 0);
        let inside: Vec<bool> = (0..mine.len())
            .map(|i| find(&mut parent, i) == root0)
            .collect();
        let n_in = inside.iter().filter(|&&x| x).count();
        let pairs = n_in * (mine.len() - n_in);
        if pairs == 0 || pairs > *budget {
            return;
        }
        *budget -= pairs;
        // The `TRIED` closest pairs, ties in the order (i, j), without sorting every pair:
        // candidates gather in a buffer of `4 TRIED`; when it is full the `TRIED` smallest
        // are selected (linear time) and the rest dropped, so memory stays at `4 TRIED`.
        // (A bounded heap spent half the import in `sift_down` on a sliver whose pairs come
        // closer one after the other, each replacing the top.)
        let mut best: Vec<(ByDist, usize, usize)> = Vec::with_capacity(4 * TRIED);
        // The two sides listed once: filtering all of `mine` for each `i` cost
        // `n_in * mine.len()` however few the pairs (a part of 28,000 vertices with a few
        // outside took minutes; found by `floorplan_osm`).
        let (ins, outs): (Vec<usize>, Vec<usize>) = (0..mine.len()).partition(|&i| inside[i]);
        // Positions of the outside side, contiguous, for the inner loop.
        let out_pos: Vec<(f64, f64)> = outs
            .iter()
            .map(|&j| (net.verts[mine[j]].pos.x, net.verts[mine[j]].pos.y))
            .collect();
        // Squared distance of the `TRIED`-th closest pair kept at the last selection: a pair
        // no closer cannot be among the `TRIED` closest. Pairs come in increasing `(i, j)`,
        // so one at exactly that distance ranks after it anyway. (Coordinates are finite, so
        // no distance is NaN.)
        let mut worst = f64::INFINITY;
        for &i in &ins {
            let pi = net.verts[mine[i]].pos;
            for (&j, &(xj, yj)) in outs.iter().zip(&out_pos) {
                // Squared distance: the same order as the distance, without a `hypot`
                // per pair (a third of the time of a large join).
                let (dx, dy) = (pi.x - xj, pi.y - yj);
                let d2 = dx * dx + dy * dy;
                if d2 >= worst {
                    continue;
                }
                best.push((ByDist(d2), i, j));
                if best.len() == 4 * TRIED {
                    best.select_nth_unstable(TRIED - 1);
                    best.truncate(TRIED);
                    worst = best[TRIED - 1].0.0;
                }
            }
        }
        best.sort_unstable();
        best.truncate(TRIED);
        let mut joined = None;
        for (_, i, j) in best {
            let (a, b) = (net.verts[mine[i]].pos, net.verts[mine[j]].pos);
            if segment_within(poly, a, b, 0.0) && ctx.walls_ok(net, a, b) {
                net.edge(mine[i], mine[j], None);
                joined = Some((i, j));
                break;
            }
        }
        let Some((i, j)) = joined else {
            return;
        };
        let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
        parent[ri] = rj;
    }
}

/// Root of `x` in the union-find forest `p` (halving the path on the way).
fn find(p: &mut [usize], mut x: usize) -> usize {
    while p[x] != x {
        p[x] = p[p[x]];
        x = p[x];
    }
    x
}

/// Farthest apart, in spacings (grid cells each way), two vertices that [`join_near`] pairs.
const NEAR_CELLS: i64 = 4;
/// Closest vertices of other parts [`join_near`] keeps per vertex.
const NEAR_KEPT: usize = 8;

/// The near pass of [`bridge`]: joins parts of the space (`parent`, a union-find forest
/// over `mine`'s indices) by their short bridges, shortest first, each if in sight.
///
/// The vertices go into a grid of `spacing` cells over their bounding box (no larger than
/// the space's grid, which the cell limit bounded). Each vertex outside the largest part
/// looks through the cells within [`NEAR_CELLS`] of its own for vertices of other parts
/// (every pair across parts has an end outside the largest part, so none is missed) and
/// keeps its [`NEAR_KEPT`] closest within `NEAR_CELLS` spacings. The pairs, closest first
/// (ties by index), join their parts when still apart, in sight and clear of walls.
fn join_near(
    net: &mut Net,
    ctx: &FloorCtx<'_>,
    poly: &Polygon<f64>,
    mine: &[usize],
    spacing: f64,
    parent: &mut [usize],
) {
    let n = mine.len();
    let mut size = vec![0usize; n];
    for i in 0..n {
        size[find(parent, i)] += 1;
    }
    // The largest part (the lowest root among equals).
    let Some(big) = (0..n).max_by_key(|&r| (size[r], std::cmp::Reverse(r))) else {
        return;
    };
    if size[big] == n || spacing.is_nan() || spacing <= 0.0 {
        return;
    }
    let pos: Vec<Coord<f64>> = mine.iter().map(|&v| net.verts[v].pos).collect();
    let (mut lo, mut hi) = (pos[0], pos[0]);
    for p in &pos {
        (lo.x, lo.y, hi.x, hi.y) = (lo.x.min(p.x), lo.y.min(p.y), hi.x.max(p.x), hi.y.max(p.y));
    }
    let cols = ((hi.x - lo.x) / spacing).floor() + 1.0;
    let rows = ((hi.y - lo.y) / spacing).floor() + 1.0;
    // Vertices lie in the space, whose cells the limit bounded; a box far larger than that
    // (vertices along a sliver's outline) is left to the second pass.
    if cols.is_nan() || rows.is_nan() || cols * rows > (4 * MAX_GRID_CELLS) as f64 {
        return;
    }
    let (cols, rows) = (cols as usize, rows as usize);
    let cell_of = |p: Coord<f64>| -> (usize, usize) {
        let c = (((p.x - lo.x) / spacing).floor() as usize).min(cols - 1);
        let r = (((p.y - lo.y) / spacing).floor() as usize).min(rows - 1);
        (r, c)
    };
    // The vertices by cell, as one array and the start of each cell in it.
    let mut start = vec![0usize; rows * cols + 1];
    let cells: Vec<usize> = pos
        .iter()
        .map(|&p| {
            let (r, c) = cell_of(p);
            r * cols + c
        })
        .collect();
    for &k in &cells {
        start[k + 1] += 1;
    }
    for k in 0..rows * cols {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut by_cell = vec![0usize; n];
    for (i, &k) in cells.iter().enumerate() {
        by_cell[fill[k]] = i;
        fill[k] += 1;
    }
    let reach2 = (NEAR_CELLS as f64 * spacing).powi(2);
    let mut pairs: Vec<(ByDist, usize, usize)> = Vec::new();
    let mut mine_near: Vec<(ByDist, usize)> = Vec::new();
    for i in 0..n {
        let ri = find(parent, i);
        if ri == big {
            continue;
        }
        let (r, c) = cell_of(pos[i]);
        let (r0, r1) = (
            r.saturating_sub(NEAR_CELLS as usize),
            (r + NEAR_CELLS as usize).min(rows - 1),
        );
        let (c0, c1) = (
            c.saturating_sub(NEAR_CELLS as usize),
            (c + NEAR_CELLS as usize).min(cols - 1),
        );
        mine_near.clear();
        for rr in r0..=r1 {
            for k in rr * cols + c0..=rr * cols + c1 {
                for &j in &by_cell[start[k]..start[k + 1]] {
                    let (dx, dy) = (pos[j].x - pos[i].x, pos[j].y - pos[i].y);
                    let d2 = dx * dx + dy * dy;
                    if d2 <= reach2 && find(parent, j) != ri {
                        mine_near.push((ByDist(d2), j));
                    }
                }
            }
        }
        if mine_near.len() > NEAR_KEPT {
            mine_near.select_nth_unstable(NEAR_KEPT - 1);
            mine_near.truncate(NEAR_KEPT);
        }
        pairs.extend(mine_near.iter().map(|&(d, j)| (d, i.min(j), i.max(j))));
    }
    pairs.sort_unstable();
    pairs.dedup();
    for (_, i, j) in pairs {
        let (ri, rj) = (find(parent, i), find(parent, j));
        if ri == rj {
            continue;
        }
        if segment_within(poly, pos[i], pos[j], 0.0) && ctx.walls_ok(net, pos[i], pos[j]) {
            net.edge(mine[i], mine[j], None);
            parent[ri] = rj;
        }
    }
}

/// A (squared) distance ordered by [`f64::total_cmp`], for the pairs of [`bridge`].
#[derive(Clone, Copy, Debug)]
struct ByDist(f64);

impl PartialEq for ByDist {
    fn eq(&self, other: &Self) -> bool {
        self.0.total_cmp(&other.0).is_eq()
    }
}

impl Eq for ByDist {}

impl PartialOrd for ByDist {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for ByDist {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

//! Buildings: the `survey-building/1` exchange format (SPEC section 7) and the validated
//! building graph the rest of the core works on (SPEC section 1).
//!
//! [`BuildingFile`] mirrors the JSON exactly (serde); [`Building::from_file`] checks every
//! rule and builds a petgraph graph whose node index equals the vertex index. Vertex ids
//! are the stable names; indices never leave the process.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use petgraph::graph::{NodeIndex, UnGraph};
use petgraph::visit::EdgeRef;
use serde::{Deserialize, Serialize};

use crate::gp::{Kernel, Point};
use crate::{Error, Result};

mod part;
pub use part::{EVALUATION_MARGIN_M, PartSpec};

/// The only format version this code reads and writes.
pub const FORMAT: &str = "survey-building/1";

/// Shortest allowed edge, metres (SPEC section 1).
pub const MIN_EDGE_LENGTH: f64 = 1e-6;

/// Largest allowed |x| and |y| of a vertex or a fingerprint, metres (SPEC section 7). A
/// building a thousand kilometres across is not a building; the bound keeps every distance,
/// edge length and walk length finite (1e308 would make an edge of infinite length).
pub const MAX_COORDINATE: f64 = 1e6;

/// Longest allowed edge, metres: ten times the largest coordinate, room for any detour an
/// explicit length describes, while the total of a file's edges stays far from overflow.
pub const MAX_EDGE_LENGTH: f64 = 1e7;

/// Strongest RSS a fingerprint may hold, dBm (SPEC section 7; the same rule as a scan).
pub const MAX_RSS_DBM: f64 = crate::session::MAX_RSS_DBM;

/// Weakest RSS a fingerprint may hold, dBm.
pub const MIN_RSS_DBM: f64 = crate::session::MIN_RSS_DBM;

/// Serde helpers that hold the format to its JSON shape: a record is a JSON object (serde's
/// derive would also read a struct from a positional array such as `["a", 0.0, 0.0, 0]`),
/// and an optional field is absent or a value, never `null`.
pub(crate) mod shape {
    use std::fmt;
    use std::marker::PhantomData;

    use serde::de::{Deserialize, Deserializer, MapAccess, Visitor, value::MapAccessDeserializer};

    /// `T` read from a JSON object only.
    pub struct Object<T>(pub T);

    impl<'de, T: Deserialize<'de>> Deserialize<'de> for Object<T> {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V<T>(PhantomData<T>);
            impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
                type Value = T;
                fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                    f.write_str("a JSON object")
                }
                fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
                    T::deserialize(MapAccessDeserializer::new(map))
                }
            }
            d.deserialize_map(V(PhantomData)).map(Object)
        }
    }

    /// An object only (the top-level document, a bundle's building).
    pub fn object<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
        Object::deserialize(d).map(|o| o.0)
    }

    /// A list of objects.
    pub fn objects<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Vec<T>, D::Error> {
        let list: Vec<Object<T>> = Vec::deserialize(d)?;
        Ok(list.into_iter().map(|o| o.0).collect())
    }

    /// An optional list of objects: absent is `None` (with `#[serde(default)]`), `null` is
    /// refused.
    pub fn some_objects<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<Vec<T>>, D::Error> {
        objects(d).map(Some)
    }

    /// An optional object: absent is `None`, `null` is refused.
    pub fn some_object<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<T>, D::Error> {
        object(d).map(Some)
    }

    /// An optional value: absent is `None`, `null` is refused.
    pub fn some<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<T>, D::Error> {
        T::deserialize(d).map(Some)
    }
}

/// A floor as written in the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FloorSpec {
    pub id: i64,
    #[serde(
        default,
        deserialize_with = "shape::some",
        skip_serializing_if = "Option::is_none"
    )]
    pub name: Option<String>,
}

/// A vertex as written in the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VertexSpec {
    pub id: String,
    pub x: f64,
    pub y: f64,
    #[serde(default)]
    pub floor: i64,
    #[serde(
        default,
        deserialize_with = "shape::some",
        skip_serializing_if = "Option::is_none"
    )]
    pub label: Option<String>,
}

/// An undirected edge as written in the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeSpec {
    pub a: String,
    pub b: String,
    #[serde(
        default,
        deserialize_with = "shape::some",
        skip_serializing_if = "Option::is_none"
    )]
    pub length: Option<f64>,
}

/// A fingerprint: a position and the RSS (dBm) of the access points heard there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fingerprint {
    pub x: f64,
    pub y: f64,
    #[serde(default)]
    pub floor: i64,
    #[serde(default)]
    pub rss: BTreeMap<String, f64>,
}

impl Fingerprint {
    pub fn point(&self) -> Point {
        Point::new(self.x, self.y, self.floor)
    }
}

/// WGS84 position of the local origin (SPEC 7 `geo`): `x` points east and `y` north, in
/// metres on a local tangent plane. Buildings made from floor plans carry it so that exports
/// can give longitude and latitude.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeoOrigin {
    /// Latitude, degrees north, in [-90, 90].
    pub lat: f64,
    /// Longitude, degrees east, in [-180, 180].
    pub lon: f64,
}

/// What an outline outlines (SPEC 7). `room`, `corridor` and `area` are walkable spaces,
/// `wall` is an open line, `building` the building's footprint or a level's outline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutlineKind {
    Room,
    Corridor,
    Area,
    Wall,
    Building,
}

impl OutlineKind {
    /// Whether the kind is a walkable space (room, corridor, area).
    pub fn is_walkable(self) -> bool {
        matches!(
            self,
            OutlineKind::Room | OutlineKind::Corridor | OutlineKind::Area
        )
    }

    /// The name used in the file.
    pub fn as_str(self) -> &'static str {
        match self {
            OutlineKind::Room => "room",
            OutlineKind::Corridor => "corridor",
            OutlineKind::Area => "area",
            OutlineKind::Wall => "wall",
            OutlineKind::Building => "building",
        }
    }
}

/// A polygon (closed ring, first point not repeated) or, for `wall`, an open line, kept from
/// a floor plan for drawing. Never used for planning.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Outline {
    #[serde(default)]
    pub floor: i64,
    pub kind: OutlineKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// `[x, y]` in metres.
    pub points: Vec<[f64; 2]>,
}

/// The JSON document `survey-building/1`, field for field. Records are JSON objects and
/// optional fields are absent or a value, never `null` (the `shape` helpers).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildingFile {
    pub format: String,
    pub name: String,
    #[serde(
        default,
        deserialize_with = "shape::some_objects",
        skip_serializing_if = "Option::is_none"
    )]
    pub floors: Option<Vec<FloorSpec>>,
    #[serde(deserialize_with = "shape::objects")]
    pub vertices: Vec<VertexSpec>,
    #[serde(deserialize_with = "shape::objects")]
    pub edges: Vec<EdgeSpec>,
    #[serde(
        default,
        deserialize_with = "shape::objects",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub pilot: Vec<Fingerprint>,
    #[serde(
        default,
        deserialize_with = "shape::objects",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub test_points: Vec<Fingerprint>,
    #[serde(
        default,
        deserialize_with = "shape::objects",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub dense_survey: Vec<Fingerprint>,
    #[serde(
        default,
        deserialize_with = "shape::some_object",
        skip_serializing_if = "Option::is_none"
    )]
    pub kernel: Option<Kernel>,
    #[serde(
        default,
        deserialize_with = "shape::some_object",
        skip_serializing_if = "Option::is_none"
    )]
    pub geo: Option<GeoOrigin>,
    #[serde(
        default,
        deserialize_with = "shape::objects",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub outlines: Vec<Outline>,
}

impl BuildingFile {
    /// Parses JSON text; `origin` names the source in errors. Type errors carry the JSON
    /// path of the offending value (`vertices[3].x`). The text must be exactly one JSON
    /// object: an array, or anything after the document (a second document, stray text), is
    /// refused rather than silently dropped.
    pub fn parse(text: &str, origin: &str) -> Result<Self> {
        if let Some(what) = not_json_object(text) {
            return Err(Error::Parse {
                origin: origin.to_string(),
                path: "$".into(),
                message: format!(
                    "not a JSON survey-building/1 file: {what} (a building file is one JSON \
                     object, `{{\"format\": \"survey-building/1\", ...}}`; floor plans are \
                     read by `trailprint import-floorplan`)"
                ),
            });
        }
        let de = &mut serde_json::Deserializer::from_str(text);
        let file: Self = serde_path_to_error::deserialize(&mut *de)
            .map(|o: shape::Object<Self>| o.0)
            .map_err(|e| {
                let path = e.path().to_string();
                let inner = e.into_inner();
                Error::Parse {
                    origin: origin.to_string(),
                    path: if path == "." { "$".into() } else { path },
                    message: inner.to_string(),
                }
            })?;
        de.end().map_err(|e| Error::Parse {
            origin: origin.to_string(),
            path: "$".into(),
            message: format!("unexpected data after the JSON document ({e})"),
        })?;
        Ok(file)
    }

    /// Reads and parses a file.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Pretty JSON text of the document.
    pub fn to_json(&self) -> String {
        // Serialising plain data with string keys cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

/// A floor of a validated building.
#[derive(Debug, Clone, PartialEq)]
pub struct Floor {
    pub id: i64,
    pub name: Option<String>,
}

/// A vertex of a validated building.
#[derive(Debug, Clone, PartialEq)]
pub struct Vertex {
    pub id: String,
    pub pos: Point,
    pub label: Option<String>,
}

/// An edge of a validated building, between vertex indices `a < b` or in file order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    pub a: usize,
    pub b: usize,
    pub length: f64,
    /// Whether the length was given in the file (kept for a faithful export).
    pub explicit_length: bool,
}

/// A validated building: the graph, its geometry and its survey data.
#[derive(Debug, Clone)]
pub struct Building {
    pub name: String,
    pub floors: Vec<Floor>,
    pub vertices: Vec<Vertex>,
    pub edges: Vec<Edge>,
    /// The graph for graph algorithms (node index = vertex index; node weight: vertex index;
    /// edge weight: edge index into `edges`). Validation finds the connected components on
    /// it; shortest paths have their own search (`plan::metric`), see decision 0004.
    pub graph: UnGraph<usize, usize>,
    pub pilot: Vec<Fingerprint>,
    pub test_points: Vec<Fingerprint>,
    pub dense_survey: Vec<Fingerprint>,
    pub kernel: Option<Kernel>,
    /// WGS84 position of the local origin, for buildings made from floor plans.
    pub geo: Option<GeoOrigin>,
    /// Floor-plan outlines, drawn under the graph; never used for planning.
    pub outlines: Vec<Outline>,
    index: HashMap<String, usize>,
    /// `adjacency[v]`: (neighbour, edge index), sorted by neighbour.
    adjacency: Vec<Vec<(usize, usize)>>,
}

impl Building {
    /// Reads, parses and validates a building file.
    pub fn load(path: &Path) -> Result<Self> {
        let origin = path.display().to_string();
        let file = BuildingFile::read(path)?;
        Self::from_file(file, &origin)
    }

    /// Parses and validates JSON text; `origin` names the source in errors.
    pub fn from_json(text: &str, origin: &str) -> Result<Self> {
        Self::from_file(BuildingFile::parse(text, origin)?, origin)
    }

    /// Validates a parsed file against every rule of SPEC sections 1 and 7.
    pub fn from_file(file: BuildingFile, origin: &str) -> Result<Self> {
        let bad = |path: String, msg: String| Error::invalid(origin, path, msg);
        if file.format != FORMAT {
            return Err(bad(
                "format".into(),
                format!(
                    "unknown format version {:?}, expected {FORMAT:?}",
                    file.format
                ),
            ));
        }
        if file.name.trim().is_empty() {
            return Err(bad("name".into(), "must not be empty".into()));
        }
        let floors: Vec<Floor> = match &file.floors {
            None => vec![Floor { id: 0, name: None }],
            Some(list) => {
                if list.is_empty() {
                    return Err(bad("floors".into(), "must list at least one floor".into()));
                }
                let mut seen = HashMap::new();
                for (i, f) in list.iter().enumerate() {
                    if let Some(j) = seen.insert(f.id, i) {
                        return Err(bad(
                            format!("floors[{i}].id"),
                            format!("duplicate floor id {} (also floors[{j}])", f.id),
                        ));
                    }
                }
                list.iter()
                    .map(|f| Floor {
                        id: f.id,
                        name: f.name.clone(),
                    })
                    .collect()
            }
        };
        let floor_ok = |f: i64| floors.iter().any(|fl| fl.id == f);

        if file.vertices.is_empty() {
            return Err(bad(
                "vertices".into(),
                "must list at least one vertex".into(),
            ));
        }
        let mut index: HashMap<String, usize> = HashMap::new();
        let mut positions: HashMap<(i64, u64, u64), usize> = HashMap::new();
        let mut vertices = Vec::with_capacity(file.vertices.len());
        for (i, v) in file.vertices.iter().enumerate() {
            if v.id.is_empty() {
                return Err(bad(format!("vertices[{i}].id"), "must not be empty".into()));
            }
            if let Some(&j) = index.get(&v.id) {
                return Err(bad(
                    format!("vertices[{i}].id"),
                    format!("duplicate vertex id {:?} (first at vertices[{j}])", v.id),
                ));
            }
            for (name, val) in [("x", v.x), ("y", v.y)] {
                if !coordinate_ok(val) {
                    return Err(bad(
                        format!("vertices[{i}].{name}"),
                        format!(
                            "vertex {:?}: {name} must be a finite number of metres with \
                             |{name}| <= {MAX_COORDINATE:e}, got {val:e}",
                            v.id
                        ),
                    ));
                }
            }
            if !floor_ok(v.floor) {
                return Err(bad(
                    format!("vertices[{i}].floor"),
                    format!(
                        "vertex {:?} is on floor {}, which is not in `floors`",
                        v.id, v.floor
                    ),
                ));
            }
            // +0.0 folds -0.0 into 0.0 so that both spell one position.
            let key = (v.floor, (v.x + 0.0).to_bits(), (v.y + 0.0).to_bits());
            if let Some(&j) = positions.get(&key) {
                return Err(bad(
                    format!("vertices[{i}]"),
                    format!(
                        "duplicate position: vertex {:?} and vertex {:?} are both at ({}, {}) on floor {}",
                        v.id, file.vertices[j].id, v.x, v.y, v.floor
                    ),
                ));
            }
            positions.insert(key, i);
            index.insert(v.id.clone(), i);
            vertices.push(Vertex {
                id: v.id.clone(),
                pos: Point::new(v.x, v.y, v.floor),
                label: v.label.clone(),
            });
        }

        let mut graph: UnGraph<usize, usize> =
            UnGraph::with_capacity(vertices.len(), file.edges.len());
        for i in 0..vertices.len() {
            graph.add_node(i);
        }
        let mut pairs: HashMap<(usize, usize), usize> = HashMap::new();
        let mut edges = Vec::with_capacity(file.edges.len());
        let mut adjacency = vec![Vec::new(); vertices.len()];
        for (i, e) in file.edges.iter().enumerate() {
            let a = *index
                .get(&e.a)
                .ok_or_else(|| bad(format!("edges[{i}].a"), format!("unknown vertex {:?}", e.a)))?;
            let b = *index
                .get(&e.b)
                .ok_or_else(|| bad(format!("edges[{i}].b"), format!("unknown vertex {:?}", e.b)))?;
            if a == b {
                return Err(bad(
                    format!("edges[{i}]"),
                    format!("self-loop at vertex {:?}", e.a),
                ));
            }
            let key = (a.min(b), a.max(b));
            if let Some(j) = pairs.insert(key, i) {
                return Err(bad(
                    format!("edges[{i}]"),
                    format!(
                        "vertices {:?} and {:?} are already joined by edges[{j}]",
                        e.a, e.b
                    ),
                ));
            }
            let (pa, pb) = (vertices[a].pos, vertices[b].pos);
            let euclid = pa.planar_distance(&pb);
            let length = match e.length {
                Some(l) => {
                    if !l.is_finite() || l < 0.0 {
                        return Err(bad(
                            format!("edges[{i}].length"),
                            format!(
                                "edge {:?}-{:?}: length must be a finite non-negative number, got {l}",
                                e.a, e.b
                            ),
                        ));
                    }
                    if l > MAX_EDGE_LENGTH {
                        return Err(bad(
                            format!("edges[{i}].length"),
                            format!(
                                "edge {:?}-{:?}: length {l:e} m is longer than {MAX_EDGE_LENGTH:e} m",
                                e.a, e.b
                            ),
                        ));
                    }
                    if l < MIN_EDGE_LENGTH {
                        return Err(bad(
                            format!("edges[{i}].length"),
                            format!(
                                "edge {:?}-{:?}: length {l} m is shorter than {MIN_EDGE_LENGTH} m",
                                e.a, e.b
                            ),
                        ));
                    }
                    if pa.floor == pb.floor && l < euclid * (1.0 - 1e-9) - 1e-9 {
                        return Err(bad(
                            format!("edges[{i}].length"),
                            format!(
                                "edge {:?}-{:?}: length {l} m is shorter than the straight-line distance {euclid:.6} m",
                                e.a, e.b
                            ),
                        ));
                    }
                    l
                }
                None => {
                    if pa.floor != pb.floor {
                        return Err(bad(
                            format!("edges[{i}].length"),
                            format!(
                                "edge {:?}-{:?} joins floors {} and {} and needs an explicit length",
                                e.a, e.b, pa.floor, pb.floor
                            ),
                        ));
                    }
                    if euclid < MIN_EDGE_LENGTH {
                        return Err(bad(
                            format!("edges[{i}]"),
                            format!(
                                "edge {:?}-{:?} is shorter than {MIN_EDGE_LENGTH} m",
                                e.a, e.b
                            ),
                        ));
                    }
                    euclid
                }
            };
            graph.add_edge(NodeIndex::new(a), NodeIndex::new(b), edges.len());
            adjacency[a].push((b, edges.len()));
            adjacency[b].push((a, edges.len()));
            edges.push(Edge {
                a,
                b,
                length,
                explicit_length: e.length.is_some(),
            });
        }
        for adj in &mut adjacency {
            adj.sort_unstable();
        }

        // Connectivity: name every component's size and one vertex of it.
        let comps = components(&graph);
        if comps.len() > 1 {
            let mut desc: Vec<String> = comps
                .iter()
                .map(|c| format!("{} vertices including {:?}", c.len(), vertices[c[0]].id))
                .collect();
            desc.truncate(10);
            return Err(bad(
                "edges".into(),
                format!(
                    "the graph is disconnected: {} components ({})",
                    comps.len(),
                    desc.join("; ")
                ),
            ));
        }

        for (field, list) in [
            ("pilot", &file.pilot),
            ("test_points", &file.test_points),
            ("dense_survey", &file.dense_survey),
        ] {
            for (i, fp) in list.iter().enumerate() {
                for (name, val) in [("x", fp.x), ("y", fp.y)] {
                    if !coordinate_ok(val) {
                        return Err(bad(
                            format!("{field}[{i}].{name}"),
                            format!(
                                "must be a finite number of metres with |{name}| <= \
                                 {MAX_COORDINATE:e}, got {val:e}"
                            ),
                        ));
                    }
                }
                if !floor_ok(fp.floor) {
                    return Err(bad(
                        format!("{field}[{i}].floor"),
                        format!("floor {} is not in `floors`", fp.floor),
                    ));
                }
                for (ap, &rss) in &fp.rss {
                    if !rss_ok(rss) {
                        return Err(bad(
                            format!("{field}[{i}].rss.{ap}"),
                            format!(
                                "RSS must be a finite dBm value in [{MIN_RSS_DBM}, {MAX_RSS_DBM}], got {rss}"
                            ),
                        ));
                    }
                }
            }
        }
        if let Some(k) = &file.kernel {
            for (name, val) in [("sf2", k.sf2), ("ell", k.ell), ("sn2", k.sn2)] {
                if !val.is_finite() || val <= 0.0 {
                    return Err(bad(
                        format!("kernel.{name}"),
                        format!("must be a finite positive number, got {val}"),
                    ));
                }
            }
        }

        if let Some(g) = &file.geo {
            if !(g.lat.is_finite() && (-90.0..=90.0).contains(&g.lat)) {
                return Err(bad(
                    "geo.lat".into(),
                    format!("latitude must be in [-90, 90] degrees, got {}", g.lat),
                ));
            }
            if !(g.lon.is_finite() && (-180.0..=180.0).contains(&g.lon)) {
                return Err(bad(
                    "geo.lon".into(),
                    format!("longitude must be in [-180, 180] degrees, got {}", g.lon),
                ));
            }
        }
        for (i, o) in file.outlines.iter().enumerate() {
            validate_outline(i, o, &floor_ok).map_err(|(path, msg)| bad(path, msg))?;
        }

        Ok(Building {
            name: file.name,
            floors,
            vertices,
            edges,
            graph,
            pilot: file.pilot,
            test_points: file.test_points,
            dense_survey: file.dense_survey,
            kernel: file.kernel,
            geo: file.geo,
            outlines: file.outlines,
            index,
            adjacency,
        })
    }

    /// Back to the exchange format (lengths written only where the file gave them).
    pub fn to_file(&self) -> BuildingFile {
        let single_default =
            self.floors.len() == 1 && self.floors[0].id == 0 && self.floors[0].name.is_none();
        BuildingFile {
            format: FORMAT.into(),
            name: self.name.clone(),
            floors: if single_default {
                None
            } else {
                Some(
                    self.floors
                        .iter()
                        .map(|f| FloorSpec {
                            id: f.id,
                            name: f.name.clone(),
                        })
                        .collect(),
                )
            },
            vertices: self
                .vertices
                .iter()
                .map(|v| VertexSpec {
                    id: v.id.clone(),
                    x: v.pos.x,
                    y: v.pos.y,
                    floor: v.pos.floor,
                    label: v.label.clone(),
                })
                .collect(),
            edges: self
                .edges
                .iter()
                .map(|e| EdgeSpec {
                    a: self.vertices[e.a].id.clone(),
                    b: self.vertices[e.b].id.clone(),
                    length: e.explicit_length.then_some(e.length),
                })
                .collect(),
            pilot: self.pilot.clone(),
            test_points: self.test_points.clone(),
            dense_survey: self.dense_survey.clone(),
            kernel: self.kernel,
            geo: self.geo,
            outlines: self.outlines.clone(),
        }
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Always false: a validated building has at least one vertex.
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Index of the vertex with this id.
    pub fn vertex_index(&self, id: &str) -> Option<usize> {
        self.index.get(id).copied()
    }

    /// Index of the vertex with this id, or an error naming it.
    pub fn require_vertex(&self, id: &str) -> Result<usize> {
        self.vertex_index(id).ok_or_else(|| {
            Error::InvalidRequest(format!(
                "unknown vertex {id:?} in building {:?}{}",
                self.name,
                self.did_you_mean(id)
            ))
        })
    }

    /// The vertex ids nearest to `id`, best first (at most three), for the "did you mean"
    /// tail of an "unknown vertex" message; empty when no id is close.
    ///
    /// Ids are compared ignoring case, and also without a floor prefix (`f0-`: the
    /// generator's and the floor-plan importer's ids are `f0-c00`, `f1-s1-23`, so `c0`
    /// means `f0-c00`), and by their shape: the same letters with the same numbers
    /// (`c0` and `c00`, `b5` and `b05`) is the nearest there is. A typo of one or two
    /// characters, or of a third of the id, is close; among ids equally close those whose
    /// numbers are nearest come first (`c16` gives `c15`), then labelled ones. A vertex
    /// whose label is `id` is close too, and so are the vertices of a group: `r2` for
    /// `f0-r2-door`, `f0-r2-000`.
    pub fn similar_vertex_ids(&self, id: &str) -> Vec<&str> {
        let want = IdShape::new(id);
        let limit = (want.local.len() / 3).max(2);
        let mut scored: Vec<(usize, u64, bool, &str)> = self
            .vertices
            .iter()
            .filter_map(|v| {
                let have = IdShape::new(&v.id);
                let label = v
                    .label
                    .as_deref()
                    .is_some_and(|l| l.trim().eq_ignore_ascii_case(id.trim()));
                // "r2" for the vertices "f0-r2-000", "f0-r2-door" of room r2.
                let group = have.local.len() > want.local.len()
                    && have.local.starts_with(&want.local)
                    && have.local[want.local.len()] == '-';
                let d = if have.same_shape(&want) || label {
                    0
                } else if group {
                    1
                } else {
                    let full = edit_distance(&want.full, &have.full);
                    let local = edit_distance(&want.local, &have.local);
                    // Replacing the whole id is no near miss ("q" is not a typo of "a").
                    let whole = local >= want.local.len().max(have.local.len());
                    if whole { usize::MAX } else { full.min(local) }
                };
                // Ties: the nearest numbers, then labelled vertices (a room's door).
                (d <= limit).then(|| (d, want.number_gap(&have), v.label.is_none(), v.id.as_str()))
            })
            .collect();
        scored.sort();
        let best = scored.first().map_or(0, |s| s.0);
        let near: Vec<(u64, &str)> = scored
            .into_iter()
            .filter(|&(d, ..)| d == best)
            .map(|(_, gap, _, v)| (gap, v))
            .collect();
        // Many ids equally far away and none of the same letters (every "b.." of a
        // corridor two edits from "c0") is no suggestion at all.
        if near.len() > 3 && best > 1 && near.iter().all(|&(gap, _)| gap == u64::MAX) {
            return Vec::new();
        }
        near.into_iter().take(3).map(|(_, v)| v).collect()
    }

    fn did_you_mean(&self, id: &str) -> String {
        let near = self.similar_vertex_ids(id);
        let quoted: Vec<String> = near.iter().map(|v| format!("{v:?}")).collect();
        // Ids of the same letters ("c99" in a corridor "f0-c00" ... "f0-c15"): their
        // range, unless a suggestion is the id itself but for zeros or the floor prefix.
        let want = IdShape::new(id);
        let exact = near.iter().any(|v| IdShape::new(v).same_shape(&want));
        let mut alike: Vec<(Vec<u64>, &str)> = self
            .vertices
            .iter()
            .filter_map(|v| {
                let have = IdShape::new(&v.id);
                (have.letters == want.letters).then_some((have.numbers, v.id.as_str()))
            })
            .collect();
        alike.sort();
        let range = match (alike.first(), alike.last()) {
            _ if exact => None,
            (Some(a), Some(b)) if alike.len() > 1 => Some(format!(
                "the {} ids like it run from {:?} to {:?} (`trailprint vertices` lists them all)",
                alike.len(),
                a.1,
                b.1
            )),
            (Some(a), _) => Some(format!("the one id like it is {:?}", a.1)),
            _ => None,
        };
        match (quoted.as_slice(), range) {
            ([], Some(r)) => format!("; {r}"),
            ([], None) => match (self.vertices.first(), self.vertices.last()) {
                (Some(a), Some(b)) if self.len() > 1 => format!(
                    "; its {} vertex ids run from {:?} to {:?}",
                    self.len(),
                    a.id,
                    b.id
                ),
                _ => String::new(),
            },
            ([one], r) => format!(
                "; did you mean {one}?{}",
                r.map(|r| format!(" ({r})")).unwrap_or_default()
            ),
            ([init @ .., last], r) => format!(
                "; did you mean {} or {last}?{}",
                init.join(", "),
                r.map(|r| format!(" ({r})")).unwrap_or_default()
            ),
        }
    }

    /// Neighbours of `v` with the joining edge index, sorted by neighbour index.
    pub fn neighbours(&self, v: usize) -> &[(usize, usize)] {
        &self.adjacency[v]
    }

    /// The edge joining `a` and `b`, if any.
    pub fn edge_between(&self, a: usize, b: usize) -> Option<&Edge> {
        let adj = &self.adjacency[a];
        adj.binary_search_by_key(&b, |&(n, _)| n)
            .ok()
            .map(|i| &self.edges[adj[i].1])
    }

    /// Positions of all vertices, in index order (the set `V` of the utility).
    pub fn vertex_points(&self) -> Vec<Point> {
        self.vertices.iter().map(|v| v.pos).collect()
    }

    /// Positions of the pilot locations (the set `D`).
    pub fn pilot_points(&self) -> Vec<Point> {
        self.pilot.iter().map(Fingerprint::point).collect()
    }

    /// Total length of all edges, metres.
    pub fn total_edge_length(&self) -> f64 {
        self.edges.iter().map(|e| e.length).sum()
    }

    /// Resolves a walk given by vertex ids, checking that consecutive vertices share an
    /// edge. Errors name the step (0-based) and the ids.
    pub fn resolve_walk<S: AsRef<str>>(&self, ids: &[S]) -> Result<Vec<usize>> {
        if ids.is_empty() {
            return Err(Error::InvalidWalk {
                step: 0,
                message: "the walk is empty".into(),
            });
        }
        let mut walk = Vec::with_capacity(ids.len());
        for (step, id) in ids.iter().enumerate() {
            let id = id.as_ref().trim();
            let v = self.vertex_index(id).ok_or_else(|| Error::InvalidWalk {
                step,
                message: format!("unknown vertex {id:?}{}", self.did_you_mean(id)),
            })?;
            if let Some(&prev) = walk.last()
                && self.edge_between(prev, v).is_none()
            {
                return Err(Error::InvalidWalk {
                    step,
                    message: format!("no edge between {:?} and {:?}", self.vertices[prev].id, id),
                });
            }
            walk.push(v);
        }
        Ok(walk)
    }

    /// Checks a walk of indices (consecutive vertices joined by edges).
    pub fn check_walk(&self, walk: &[usize]) -> Result<()> {
        for (step, w) in walk.windows(2).enumerate() {
            if w[0] >= self.len() || w[1] >= self.len() || self.edge_between(w[0], w[1]).is_none() {
                return Err(Error::InvalidWalk {
                    step: step + 1,
                    message: format!("no edge between vertex #{} and vertex #{}", w[0], w[1]),
                });
            }
        }
        Ok(())
    }

    /// Length `C(P)` of a walk of indices; the walk must be valid.
    pub fn walk_length(&self, walk: &[usize]) -> f64 {
        walk.windows(2)
            .map(|w| {
                self.edge_between(w[0], w[1])
                    .map_or(f64::INFINITY, |e| e.length)
            })
            .sum()
    }

    /// Vertex ids of a walk of indices.
    pub fn walk_ids(&self, walk: &[usize]) -> Vec<String> {
        walk.iter().map(|&v| self.vertices[v].id.clone()).collect()
    }
}

/// Whether a coordinate is finite and within [`MAX_COORDINATE`] of the origin.
fn coordinate_ok(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_COORDINATE
}

/// A vertex id as [`Building::similar_vertex_ids`] compares it: lower case, whole and
/// without its floor prefix (`f0-`), and its shape: the letters with each run of digits
/// replaced by `#`, and the numbers of those runs.
struct IdShape {
    full: Vec<char>,
    local: Vec<char>,
    letters: String,
    numbers: Vec<u64>,
    /// The floor of the prefix `f<n>-`, if the id has one.
    floor: Option<u64>,
}

impl IdShape {
    fn new(id: &str) -> IdShape {
        let lower = id.trim().to_lowercase();
        let local = strip_floor_prefix(&lower);
        let mut letters = String::new();
        let mut numbers = Vec::new();
        let mut run = String::new();
        for c in local.chars().chain(std::iter::once(' ')) {
            if c.is_ascii_digit() {
                run.push(c);
                continue;
            }
            if !run.is_empty() {
                letters.push('#');
                numbers.push(run.parse::<u64>().unwrap_or(u64::MAX));
                run.clear();
            }
            if c.is_alphanumeric() {
                letters.push(c);
            }
        }
        // "f12-c00" -> "12": what the prefix holds between its 'f' and its '-'.
        let floor = (lower.len() - local.len())
            .checked_sub(1)
            .and_then(|end| lower.get(1..end))
            .and_then(|n| n.parse().ok());
        IdShape {
            full: lower.chars().collect(),
            local: local.chars().collect(),
            letters,
            numbers,
            floor,
        }
    }

    /// The same letters and the same numbers (`c0` and `f0-c00`): the same id but for
    /// leading zeros, separators or the floor prefix.
    fn same_shape(&self, other: &IdShape) -> bool {
        let floors = match (self.floor, other.floor) {
            (Some(a), Some(b)) => a == b,
            _ => true,
        };
        floors
            && !self.numbers.is_empty()
            && self.letters == other.letters
            && self.numbers == other.numbers
    }

    /// How far apart the numbers of two ids of the same letters are (the sum of the
    /// differences), `u64::MAX` for ids of other letters.
    fn number_gap(&self, other: &IdShape) -> u64 {
        if self.letters != other.letters {
            return u64::MAX;
        }
        self.numbers
            .iter()
            .zip(&other.numbers)
            .map(|(a, b)| a.abs_diff(*b))
            .fold(0u64, u64::saturating_add)
    }
}

/// `id` without a leading floor prefix `f<digits>-` (the generator's and the importer's
/// ids), or `id` itself.
fn strip_floor_prefix(id: &str) -> &str {
    let Some(rest) = id.strip_prefix('f') else {
        return id;
    };
    let digits = rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
    match rest[digits..].strip_prefix('-') {
        Some(local) if digits > 0 && !local.is_empty() => local,
        _ => id,
    }
}

/// Levenshtein distance of two strings (as characters).
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Why `text` cannot be a JSON file at first sight (empty, or its first character cannot
/// start a JSON document: CSV, Markdown, plain text), or `None` when JSON parsing should
/// judge it (a `[` or `{` document; its errors carry a JSON path). Building files, floor
/// plans and pilot lists are refused with it.
pub fn not_json_object(text: &str) -> Option<String> {
    let trimmed = text.trim_start_matches(['\u{feff}', ' ', '\t', '\r', '\n']);
    if trimmed.is_empty() {
        return Some("the file is empty".into());
    }
    if trimmed.starts_with(['{', '[']) {
        return None;
    }
    let first: String = trimmed
        .lines()
        .next()
        .unwrap_or("")
        .chars()
        .take(40)
        .collect();
    Some(format!("it begins with {first:?}"))
}

/// Whether an RSS value is a finite dBm value in [[`MIN_RSS_DBM`], [`MAX_RSS_DBM`]], the one
/// rule for building files, scans and bundles.
pub fn rss_ok(rss: f64) -> bool {
    rss.is_finite() && (MIN_RSS_DBM..=MAX_RSS_DBM).contains(&rss)
}

/// Checks one outline of SPEC 7; the error is `(JSON path, message)`.
fn validate_outline(
    i: usize,
    o: &Outline,
    floor_ok: &dyn Fn(i64) -> bool,
) -> std::result::Result<(), (String, String)> {
    let what = match &o.name {
        Some(n) => format!("{} outline {n:?}", o.kind.as_str()),
        None => format!("{} outline", o.kind.as_str()),
    };
    if !floor_ok(o.floor) {
        return Err((
            format!("outlines[{i}].floor"),
            format!("{what} is on floor {}, which is not in `floors`", o.floor),
        ));
    }
    for (j, p) in o.points.iter().enumerate() {
        for (k, name) in ["x", "y"].iter().enumerate() {
            let v = p[k];
            if !coordinate_ok(v) {
                return Err((
                    format!("outlines[{i}].points[{j}][{k}]"),
                    format!(
                        "{what}: {name} must be a finite number of metres with |{name}| <= {MAX_COORDINATE:e}, got {v:e}"
                    ),
                ));
            }
        }
    }
    if o.kind == OutlineKind::Wall {
        if o.points.len() < 2 {
            return Err((
                format!("outlines[{i}].points"),
                format!(
                    "{what} is a line and needs at least 2 points, got {}",
                    o.points.len()
                ),
            ));
        }
        return Ok(());
    }
    let mut distinct: Vec<[u64; 2]> = o
        .points
        .iter()
        .map(|p| [(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()])
        .collect();
    if o.points.len() >= 2 && distinct.first() == distinct.last() {
        return Err((
            format!("outlines[{i}].points"),
            format!(
                "{what}: the last point repeats the first; rings are closed implicitly (leave the repeat out)"
            ),
        ));
    }
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() < 3 {
        return Err((
            format!("outlines[{i}].points"),
            format!(
                "{what} is a closed ring and needs at least 3 distinct points, got {}",
                distinct.len()
            ),
        ));
    }
    Ok(())
}

/// Connected components as lists of vertex indices, each list sorted, largest first (ties:
/// the component with the lower first vertex first, so messages are deterministic).
///
/// petgraph's union-find over the graph's edges: no recursion and no stack proportional to
/// the graph, so a 20,000-vertex corridor is as safe as a small floor.
fn components(graph: &UnGraph<usize, usize>) -> Vec<Vec<usize>> {
    let mut sets = petgraph::unionfind::UnionFind::<usize>::new(graph.node_count());
    for e in graph.edge_references() {
        sets.union(e.source().index(), e.target().index());
    }
    let mut by_root: HashMap<usize, Vec<usize>> = HashMap::new();
    for (v, root) in sets.into_labeling().into_iter().enumerate() {
        by_root.entry(root).or_default().push(v);
    }
    // Vertices were pushed in increasing order, so every list is already sorted.
    let mut out: Vec<Vec<usize>> = by_root.into_values().collect();
    out.sort_by(|a, b| b.len().cmp(&a.len()).then(a[0].cmp(&b[0])));
    out
}

#[cfg(test)]
#[path = "building_tests.rs"]
mod tests;

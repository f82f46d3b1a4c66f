//! Floor plans in: OpenStreetMap indoor GeoJSON (Simple Indoor Tagging) and IMDF to a
//! `survey-building/1` building whose graph is what a surveyor can walk.
//!
//! The import runs in two stages:
//!
//! 1. a reader ([`osm`] or [`imdf`]) turns the features into a [`Plan`] in metres: walkable
//!    spaces (corridors, open areas, rooms, elevator and stair shafts) per floor, doors,
//!    walls and vertical connections, counting everything it had to repair or leave out;
//! 2. [`network`] lays the walkable network: a grid of about `spacing` metres inside every
//!    walkable polygon (aligned with the polygon's walls, so a narrow corridor gets its
//!    centre line and a hall a lattice), door vertices joining the spaces a door touches,
//!    a vertex in the middle of the longest shared boundary where a room has no tagged door,
//!    and edges between floors at stairs and elevators with the explicit lengths
//!    [`STAIRS_M_PER_LEVEL`], [`ELEVATOR_BASE_M`] and [`ELEVATOR_M_PER_LEVEL`]. The largest
//!    connected part is kept; what was dropped is said.
//!
//! Geometry is done with the `geo` crate (containment, distances, intersections, areas) and
//! GeoJSON read with the `geojson` crate; the projection to metres is [`LocalFrame`].
//! Real data is messy: unclosed rings, overlapping polygons, features without a level or
//! without indoor tags give counted [`Warning`]s and a building all the same. Only a plan
//! with nothing walkable is refused.

pub mod frame;
pub(crate) mod geom;
pub mod imdf;
pub(crate) mod network;
pub mod osm;

use std::collections::BTreeMap;
use std::path::Path;

use geo::{Coord, LineString, Polygon};
use serde::Serialize;

pub use frame::LocalFrame;
pub use network::MAX_GRID_CELLS;

use crate::building::{BuildingFile, FloorSpec, GeoOrigin};
use crate::{Error, Result};

/// Walking length charged for stairs, metres per storey climbed: two flights of nine
/// 28 cm treads (about 5 m on the slope for a 3 m storey) plus the landing and the turns.
pub const STAIRS_M_PER_LEVEL: f64 = 8.0;
/// Fixed walking-equivalent length of an elevator ride, metres: about 12 s of waiting and
/// doors at the 1.2 m/s walking speed of SPEC 4.
pub const ELEVATOR_BASE_M: f64 = 15.0;
/// Added per storey travelled in an elevator, metres (about 2.5 s per storey at 1.2 m/s).
pub const ELEVATOR_M_PER_LEVEL: f64 = 3.0;
/// Default grid spacing of the walkable network, metres.
pub const DEFAULT_SPACING_M: f64 = 2.0;

/// Which reader.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// OpenStreetMap indoor data as GeoJSON (Simple Indoor Tagging; Overpass exports).
    OsmIndoor,
    /// IMDF (OGC community standard): a folder of GeoJSON files, or a zip of one.
    Imdf,
}

/// Options of an import.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportOptions {
    /// `None`: guessed from the input (a folder or a `.zip` is IMDF, so is a GeoJSON file
    /// whose features carry `feature_type`; anything else is OSM indoor).
    pub format: Option<Format>,
    /// Building name; default the venue or building name of the plan, else the file name.
    pub name: Option<String>,
    /// Grid spacing of the walkable network, metres (0.5 to 20).
    pub spacing_m: f64,
    /// Most grid cells the walkable network may try over all spaces: [`MAX_GRID_CELLS`]
    /// unless lowered. A plan that needs more is refused before any cell is laid, naming
    /// the space. A caller short of memory lowers it, and so do the fuzz targets: at the
    /// default a 10 KB plan legitimately grows 28,000 vertices, 0.3 s in release but over
    /// 20 s under the sanitizer with the targets' store round trip, which libFuzzer counts
    /// as timeouts and which leaves little time for the mutations that find bugs.
    pub max_grid_cells: usize,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            format: None,
            name: None,
            spacing_m: DEFAULT_SPACING_M,
            max_grid_cells: MAX_GRID_CELLS,
        }
    }
}

/// Something the import repaired or left out, with how often and a few feature ids.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// What happened, as a short phrase ("unclosed rings closed").
    pub what: String,
    pub count: usize,
    /// Up to five examples (feature ids, names).
    pub examples: Vec<String>,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.what, self.count)?;
        if !self.examples.is_empty() {
            let more = if self.count > self.examples.len() {
                ", ..."
            } else {
                ""
            };
            write!(f, " ({}{more})", self.examples.join(", "))?;
        }
        Ok(())
    }
}

/// A part of the walkable network that was not connected to the largest part.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DroppedPart {
    pub vertices: usize,
    pub floors: Vec<i64>,
    /// The spaces it covered (kind, name or feature id).
    pub spaces: Vec<String>,
}

impl std::fmt::Display for DroppedPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let floors: Vec<String> = self.floors.iter().map(i64::to_string).collect();
        write!(
            f,
            "{} vertices on floor {}: {}",
            self.vertices,
            floors.join(", "),
            self.spaces.join(", ")
        )
    }
}

/// Counts of what was imported.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ImportStats {
    pub floors: usize,
    /// Walkable spaces (per floor) that got at least one vertex.
    pub spaces: usize,
    pub doors: usize,
    /// Vertical connections (stairs, elevators) that joined at least two floors.
    pub connectors: usize,
    pub vertices: usize,
    pub edges: usize,
}

/// The result of an import: the building and what was repaired or dropped on the way.
#[derive(Debug, Clone)]
pub struct FloorplanImport {
    pub file: BuildingFile,
    pub format: Format,
    pub warnings: Vec<Warning>,
    pub dropped: Vec<DroppedPart>,
    pub stats: ImportStats,
}

/// Reads a floor plan (a GeoJSON file, an IMDF folder or zip) and lays its walkable network.
pub fn import_path(path: &Path, options: &ImportOptions) -> Result<FloorplanImport> {
    check_spacing(options.spacing_m)?;
    let format = match options.format {
        Some(f) => f,
        None => guess_format(path)?,
    };
    let plan = match format {
        Format::Imdf => imdf::read(path)?,
        Format::OsmIndoor => {
            let text = read_text(path)?;
            osm::parse(&text, &path.display().to_string())?
        }
    };
    let fallback = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "floor plan".into());
    finish(
        plan,
        format,
        options,
        &fallback,
        &path.display().to_string(),
    )
}

/// Imports OSM indoor GeoJSON text; `origin` names it in errors and is the fallback name.
pub fn import_osm_text(
    text: &str,
    origin: &str,
    options: &ImportOptions,
) -> Result<FloorplanImport> {
    import_with(Format::OsmIndoor, options, origin, || {
        osm::parse(text, origin)
    })
}

/// Imports an IMDF data set given as its files in memory (`"unit.geojson"` -> text, names
/// in lower case); `origin` names it in errors and is the fallback name.
pub fn import_imdf_files(
    files: &std::collections::HashMap<String, String>,
    origin: &str,
    options: &ImportOptions,
) -> Result<FloorplanImport> {
    import_with(Format::Imdf, options, origin, || {
        imdf::read_files(files, origin)
    })
}

/// Imports an IMDF zip archive given as bytes; `origin` names it in errors and is the
/// fallback name.
pub fn import_imdf_zip(
    bytes: &[u8],
    origin: &str,
    options: &ImportOptions,
) -> Result<FloorplanImport> {
    import_with(Format::Imdf, options, origin, || {
        let files = imdf::files_of_zip(std::io::Cursor::new(bytes), Path::new(origin))?;
        imdf::read_files(&files, origin)
    })
}

/// An in-memory import: the spacing checked before anything is read, then `read`'s plan
/// laid out, `origin` naming it in errors and standing in for a missing name.
fn import_with(
    format: Format,
    options: &ImportOptions,
    origin: &str,
    read: impl FnOnce() -> Result<Plan>,
) -> Result<FloorplanImport> {
    check_spacing(options.spacing_m)?;
    finish(read()?, format, options, origin, origin)
}

fn finish(
    plan: Plan,
    format: Format,
    options: &ImportOptions,
    fallback_name: &str,
    origin: &str,
) -> Result<FloorplanImport> {
    let name = options
        .name
        .clone()
        .or_else(|| plan.name.clone())
        .filter(|n| !n.trim().is_empty())
        .unwrap_or_else(|| fallback_name.to_string());
    network::build(
        plan,
        format,
        options.spacing_m,
        options.max_grid_cells,
        name,
        origin,
    )
}

fn check_spacing(s: f64) -> Result<()> {
    if s.is_finite() && (0.5..=20.0).contains(&s) {
        Ok(())
    } else {
        Err(Error::InvalidRequest(format!(
            "--spacing must be between 0.5 and 20 metres, got {s}"
        )))
    }
}

/// Largest floor-plan file read: 256 MiB (a large OSM extract of a campus is a few MiB).
pub const MAX_PLAN_BYTES: u64 = 256 * 1024 * 1024;

pub(crate) fn read_text(path: &Path) -> Result<String> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_file() && meta.len() > MAX_PLAN_BYTES {
        return Err(Error::invalid(
            &path.display().to_string(),
            "$",
            format!(
                "the file is {:.0} MiB, over the floor-plan limit of {} MiB",
                meta.len() as f64 / 1048576.0,
                MAX_PLAN_BYTES / 1048576
            ),
        ));
    }
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

fn guess_format(path: &Path) -> Result<Format> {
    if path.is_dir()
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("zip"))
    {
        return Ok(Format::Imdf);
    }
    let text = read_text(path)?;
    // IMDF features carry a top-level `feature_type` member; OSM exports never do.
    if text.contains("\"feature_type\"") {
        Ok(Format::Imdf)
    } else {
        Ok(Format::OsmIndoor)
    }
}

// ---- the plan in metres, shared by the readers and the network ----

/// What a walkable space is, for the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum SpaceKind {
    Corridor,
    Area,
    Room,
    Elevator,
    Stairs,
}

impl SpaceKind {
    /// Corridors and open areas: joined to their neighbours through any shared boundary.
    pub(crate) fn is_open(self) -> bool {
        matches!(self, SpaceKind::Corridor | SpaceKind::Area)
    }

    pub(crate) fn as_str(self) -> &'static str {
        match self {
            SpaceKind::Corridor => "corridor",
            SpaceKind::Area => "area",
            SpaceKind::Room => "room",
            SpaceKind::Elevator => "elevator",
            SpaceKind::Stairs => "stairs",
        }
    }
}

/// A walkable polygon on one floor.
#[derive(Debug, Clone)]
pub(crate) struct Space {
    /// Feature id (`way/12`, an IMDF uuid).
    pub source: String,
    pub name: Option<String>,
    pub kind: SpaceKind,
    pub floor: i64,
    pub polygon: Polygon<f64>,
}

impl Space {
    /// `room "Office 101" (way/12)`.
    pub(crate) fn describe(&self) -> String {
        match &self.name {
            Some(n) => format!("{} {n:?} ({})", self.kind.as_str(), self.source),
            None => format!("{} {}", self.kind.as_str(), self.source),
        }
    }
}

/// A door or opening: a point on the boundary between spaces.
#[derive(Debug, Clone)]
pub(crate) struct Door {
    pub source: String,
    pub pos: Coord<f64>,
    /// Floors it is on; `None`: any floor where it touches a space (no level given).
    pub floors: Option<Vec<i64>>,
}

/// A wall line: edges never cross it except at a door.
#[derive(Debug, Clone)]
pub(crate) struct Wall {
    pub floor: i64,
    pub line: LineString<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ConnectorKind {
    Elevator,
    Stairs,
}

/// A vertical connection: where it stops on each floor.
#[derive(Debug, Clone)]
pub(crate) struct Connector {
    pub source: String,
    pub kind: ConnectorKind,
    pub stops: Vec<(i64, Coord<f64>)>,
}

/// A floor plan in metres, as the readers leave it for the network.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    pub name: Option<String>,
    pub geo: GeoOrigin,
    pub floors: Vec<FloorSpec>,
    pub spaces: Vec<Space>,
    pub doors: Vec<Door>,
    pub walls: Vec<Wall>,
    pub connectors: Vec<Connector>,
    /// Building footprints and level outlines, for drawing.
    pub outlines: Vec<(i64, Polygon<f64>)>,
    pub warnings: Warnings,
}

/// Counted warnings, keyed by what happened.
#[derive(Debug, Clone, Default)]
pub(crate) struct Warnings {
    map: BTreeMap<String, (usize, Vec<String>)>,
}

impl Warnings {
    pub(crate) fn add(&mut self, what: &str, example: impl Into<String>) {
        let e = self.map.entry(what.to_string()).or_default();
        e.0 += 1;
        if e.1.len() < 5 {
            e.1.push(example.into());
        }
    }

    pub(crate) fn into_list(self) -> Vec<Warning> {
        self.map
            .into_iter()
            .map(|(what, (count, examples))| Warning {
                what,
                count,
                examples,
            })
            .collect()
    }
}

/// The origin of a set of WGS84 positions: the south-west corner of their bounding box,
/// rounded down to 1e-6 degree (about 0.1 m) so that every coordinate is small and positive.
/// Errors when most positions are not longitude/latitude (a projected file).
pub(crate) fn origin_of(positions: &[(f64, f64)], origin: &str) -> Result<GeoOrigin> {
    let ok = |&&(lon, lat): &&(f64, f64)| {
        lon.is_finite() && lat.is_finite() && lon.abs() <= 180.0 && lat.abs() <= 90.0
    };
    let good: Vec<&(f64, f64)> = positions.iter().filter(ok).collect();
    if good.is_empty() || good.len() * 2 < positions.len() {
        return Err(Error::invalid(
            origin,
            "$",
            format!(
                "{} of {} positions are not WGS84 longitude/latitude; GeoJSON and IMDF \
                 coordinates are degrees (EPSG:4326), not projected metres",
                positions.len() - good.len(),
                positions.len()
            ),
        ));
    }
    let lon = good.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let lat = good.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    Ok(GeoOrigin {
        lat: (lat * 1e6).floor() / 1e6,
        lon: (lon * 1e6).floor() / 1e6,
    })
}

/// Floors from the level values met: floor id = the level when every level is a whole
/// number, else the rank of the level (with a warning); names say the level.
pub(crate) fn floors_of_levels(
    levels: &[f64],
    warnings: &mut Warnings,
) -> (Vec<FloorSpec>, BTreeMap<u64, i64>) {
    let mut sorted: Vec<f64> = levels.iter().copied().filter(|l| l.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let integral = sorted.iter().all(|l| l.fract() == 0.0 && l.abs() < 1e9);
    let mut map = BTreeMap::new();
    let mut floors = Vec::new();
    for (rank, &l) in sorted.iter().enumerate() {
        let id = if integral { l as i64 } else { rank as i64 };
        if !integral && l.fract() != 0.0 {
            warnings.add(
                "fractional levels numbered by rank (floor id = position from the lowest)",
                format!("level {l} -> floor {id}"),
            );
        }
        map.insert(level_key(l), id);
        floors.push(FloorSpec {
            id,
            name: Some(format!("level {l}")),
        });
    }
    (floors, map)
}

/// A map key for a level value (-0.0 folded into 0.0).
pub(crate) fn level_key(l: f64) -> u64 {
    (l + 0.0).to_bits()
}

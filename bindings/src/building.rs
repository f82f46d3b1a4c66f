//! Buildings: parse and validate `survey-building/1` text, and describe it for the app.

use trailprint::Building;

use crate::Result;

/// A vertex of a building: a walkable point.
#[derive(Debug, Clone, uniffi::Record)]
pub struct VertexInfo {
    /// Vertex id: what walks, check-ins and plan requests name it by.
    pub id: String,
    /// Metres, in the building's own frame.
    pub x: f64,
    /// Metres, in the building's own frame.
    pub y: f64,
    /// Floor id (a `FloorInfo.id`).
    pub floor: i64,
    /// A name to show for it (a room, a door), if the file gives one.
    pub label: Option<String>,
}

/// An undirected edge between two vertices (by id), with its walking length in metres.
#[derive(Debug, Clone, uniffi::Record)]
pub struct EdgeInfo {
    /// Vertex id of one end.
    pub a: String,
    /// Vertex id of the other end.
    pub b: String,
    /// Walking length, m: as the file gives it, else the straight distance between the
    /// ends (an edge between floors always has one in the file).
    pub length_m: f64,
}

/// A floor of a building.
#[derive(Debug, Clone, uniffi::Record)]
pub struct FloorInfo {
    /// Floor id, as vertices and positions name it.
    pub id: i64,
    /// A name to show for it, if the file gives one.
    pub name: Option<String>,
}

/// The kernel hyperparameters `(sf2, ell, sn2)` of SPEC section 2.
#[derive(Debug, Clone, Copy, PartialEq, uniffi::Record)]
pub struct KernelParams {
    /// Signal variance, dB².
    pub sf2: f64,
    /// Length scale, metres.
    pub ell: f64,
    /// Observation noise variance, dB².
    pub sn2: f64,
}

impl From<trailprint::gp::Kernel> for KernelParams {
    fn from(k: trailprint::gp::Kernel) -> Self {
        KernelParams {
            sf2: k.sf2,
            ell: k.ell,
            sn2: k.sn2,
        }
    }
}

impl From<KernelParams> for trailprint::gp::Kernel {
    fn from(k: KernelParams) -> Self {
        trailprint::gp::Kernel::new(k.sf2, k.ell, k.sn2)
    }
}

/// A building's geometry, as the app draws it.
#[derive(Debug, Clone, uniffi::Record)]
pub struct BuildingMap {
    /// The building's name.
    pub name: String,
    /// Its floors in file order; one floor with id 0 when the file lists none.
    pub floors: Vec<FloorInfo>,
    /// Its vertices in file order.
    pub vertices: Vec<VertexInfo>,
    /// Its edges in file order.
    pub edges: Vec<EdgeInfo>,
    /// Number of pilot fingerprints.
    pub pilot_count: u32,
    /// The kernel given in the file, if any (otherwise it is fitted on the pilot data).
    pub kernel: Option<KernelParams>,
}

impl From<&Building> for BuildingMap {
    fn from(b: &Building) -> Self {
        BuildingMap {
            name: b.name.clone(),
            floors: b
                .floors
                .iter()
                .map(|f| FloorInfo {
                    id: f.id,
                    name: f.name.clone(),
                })
                .collect(),
            vertices: b
                .vertices
                .iter()
                .map(|v| VertexInfo {
                    id: v.id.clone(),
                    x: v.pos.x,
                    y: v.pos.y,
                    floor: v.pos.floor,
                    label: v.label.clone(),
                })
                .collect(),
            edges: b
                .edges
                .iter()
                .map(|e| EdgeInfo {
                    a: b.vertices[e.a].id.clone(),
                    b: b.vertices[e.b].id.clone(),
                    length_m: e.length,
                })
                .collect(),
            pilot_count: u32::try_from(b.pilot.len()).unwrap_or(u32::MAX),
            kernel: b.kernel.map(Into::into),
        }
    }
}

/// Parses and validates `survey-building/1` JSON text; `origin` names the source in error
/// messages (a file name, or "<clipboard>").
#[uniffi::export]
pub fn parse_building(json: String, origin: String) -> Result<BuildingMap> {
    let b = Building::from_json(&json, &origin)?;
    Ok(BuildingMap::from(&b))
}

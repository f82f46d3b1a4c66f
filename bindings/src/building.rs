//! Buildings: parse and validate `survey-building/1` text, and describe it for the app.

use trailprint::Building;

use crate::Result;

/// A vertex of a building: a walkable point.
#[derive(Debug, Clone, uniffi::Record)]
pub struct VertexInfo {
    pub id: String,
    pub x: f64,
    pub y: f64,
    pub floor: i64,
    pub label: Option<String>,
}

/// An undirected edge between two vertices (by id), with its walking length in metres.
#[derive(Debug, Clone, uniffi::Record)]
pub struct EdgeInfo {
    pub a: String,
    pub b: String,
    pub length_m: f64,
}

/// A floor of a building.
#[derive(Debug, Clone, uniffi::Record)]
pub struct FloorInfo {
    pub id: i64,
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
    pub name: String,
    pub floors: Vec<FloorInfo>,
    pub vertices: Vec<VertexInfo>,
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

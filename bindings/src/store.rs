//! The store object: one SQLite database of buildings, fits, plans and survey sessions.

use std::path::Path;
use std::sync::Arc;

use trailprint::building::PartSpec;
use trailprint::store::{self, BuildingInfo, ImportOptions, Store};

use crate::Result;
use crate::building::{BuildingMap, KernelParams};
use crate::model::FitSummary;
use crate::model::SurveyorProfile;

/// A stored building's summary.
#[derive(Debug, Clone, uniffi::Record)]
pub struct BuildingSummary {
    /// Store id: what every other call takes as `buildingId`.
    pub id: i64,
    /// The name in its file; one building per name in a store.
    pub name: String,
    /// Where it was imported from (file name or origin).
    pub source: Option<String>,
    /// When it was imported, ms since the Unix epoch.
    pub imported_ms: i64,
    /// Number of floors (1 for a file that lists none).
    pub floors: u64,
    /// Number of vertices of the walkable graph.
    pub vertices: u64,
    /// Number of edges of the walkable graph.
    pub edges: u64,
    /// Access points the store knows in it: heard in its pilot, test or dense-survey
    /// fingerprints or in collected scans.
    pub access_points: u64,
    /// Pilot fingerprints stored for it (what the kernel is fitted on).
    pub pilot: u64,
    /// Whether the building file gave a kernel (else it is fitted on the pilot data).
    pub has_kernel: bool,
    /// Kernel fits recorded for it.
    pub fits: u64,
    /// Saved plans, replans and team plans included.
    pub plans: u64,
    /// Survey sessions, imported ones included.
    pub sessions: u64,
    /// Fingerprints collected in its sessions.
    pub collected: u64,
}

impl From<BuildingInfo> for BuildingSummary {
    fn from(b: BuildingInfo) -> Self {
        BuildingSummary {
            id: b.id,
            name: b.name,
            source: b.source,
            imported_ms: b.imported_ms,
            floors: b.floors,
            vertices: b.vertices,
            edges: b.edges,
            access_points: b.access_points,
            pilot: b.pilot,
            has_kernel: b.has_kernel,
            fits: b.fits,
            plans: b.plans,
            sessions: b.sessions,
            collected: b.collected,
        }
    }
}

/// A saved plan.
#[derive(Debug, Clone, uniffi::Record)]
pub struct PlanSummary {
    /// Store id of the plan (what `startSession` takes).
    pub id: i64,
    /// Store id of its building.
    pub building_id: i64,
    /// Start vertex id.
    pub start: String,
    /// End vertex id.
    pub end: String,
    /// Where the walk came from: an algorithm's name (`auto`, `greedy`, `genetic`,
    /// `recursive-greedy`, `ero`, `exact`, `coverage`), `session-greedy` for a session's
    /// replan by its own greedy replanner, or `given` for a walk that was not planned.
    pub algorithm: String,
    /// Vertex ids from start to end.
    pub walk: Vec<String>,
    /// Length of the walk, m.
    pub length_m: f64,
    /// The distance budget it was planned within, m (for a replan, what was left less the
    /// reserve it keeps).
    pub budget_m: f64,
    /// Number of places along the walk where the surveyor scans.
    pub samples: u64,
    /// What the walk's scans tell about the building's fingerprints (mutual information),
    /// nats; higher is better. A replan's is given what was collected before it.
    pub utility_nats: f64,
    /// How long the planner ran, ms.
    pub elapsed_ms: u64,
    /// The planner's seed; null for a walk that was not planned.
    pub seed: Option<u64>,
    /// The kernel the utility was computed with.
    pub kernel: KernelParams,
    /// The surveyor the plan was made for (null for a walk handed to a session rather
    /// than planned).
    pub surveyor: Option<SurveyorProfile>,
    /// When it was planned, ms since the Unix epoch.
    pub created_ms: i64,
    /// Why the planner stopped (`completed`, `optimal`, `time_limit`, `cancelled`), for
    /// the plan a `PlanJob.run` just made; null for plans read back from the store.
    #[uniffi(default)]
    pub termination: Option<String>,
}

impl From<trailprint::store::StoredPlan> for PlanSummary {
    fn from(p: trailprint::store::StoredPlan) -> Self {
        let r = p.record;
        PlanSummary {
            id: p.id,
            building_id: p.building_id,
            surveyor: r.surveyor.map(Into::into),
            start: r.start,
            end: r.end,
            algorithm: r.algorithm.name().to_string(),
            walk: r.walk,
            length_m: r.length_m,
            budget_m: r.budget_m,
            samples: r.samples,
            utility_nats: r.utility_nats,
            elapsed_ms: r.elapsed_ms,
            seed: r.seed,
            kernel: r.kernel.into(),
            created_ms: r.created_ms,
            termination: None,
        }
    }
}

/// The database: open it once per file and share it; every method may be called from any
/// thread (the core serialises writes on one connection).
#[derive(uniffi::Object)]
pub struct TrailprintStore {
    pub(crate) inner: Arc<Store>,
}

#[uniffi::export]
impl TrailprintStore {
    /// Opens (or creates) the database file at `path`, upgrading its schema.
    #[uniffi::constructor]
    pub fn open(path: String) -> Result<Arc<Self>> {
        Ok(Arc::new(TrailprintStore {
            inner: Arc::new(Store::open(&path)?),
        }))
    }

    /// A fresh database in memory (tests, previews).
    #[uniffi::constructor]
    pub fn open_in_memory() -> Result<Arc<Self>> {
        Ok(Arc::new(TrailprintStore {
            inner: Arc::new(Store::open_in_memory()?),
        }))
    }

    /// Imports `survey-building/1` JSON text; `origin` names it in errors and is kept as
    /// its source. A building of the same name is replaced when `replace`, else an error.
    pub fn import_building_json(
        &self,
        json: String,
        origin: String,
        replace: bool,
    ) -> Result<BuildingSummary> {
        let opts = ImportOptions {
            replace,
            ..Default::default()
        };
        let report = self.inner.import_json(&json, &origin, &opts)?;
        Ok(self.inner.building_info(report.id)?.into())
    }

    /// Imports a building file.
    pub fn import_building_file(&self, path: String, replace: bool) -> Result<BuildingSummary> {
        let text = store::read_import_text(Path::new(&path))?;
        self.import_building_json(text, path, replace)
    }

    /// Imports a part of a stored building as a building of its own: the floors in
    /// `floors` (all when empty) and, with `around` and `radius_m`, only what lies within
    /// that walking distance of the vertex `around`. A building refused for memory or time
    /// is planned by parts: every vertex a walk from `start` within a budget of `B` metres
    /// can reach lies within `B` of `start`. `name`: the part's (default: the building's
    /// followed by what was kept). A building of the same name is replaced when `replace`.
    pub fn import_building_part(
        &self,
        building_id: i64,
        floors: Vec<i64>,
        around: Option<String>,
        radius_m: Option<f64>,
        name: Option<String>,
        replace: bool,
    ) -> Result<BuildingSummary> {
        let around = match (around, radius_m) {
            (Some(v), Some(r)) => vec![(v, r)],
            (None, None) => Vec::new(),
            _ => {
                return Err(trailprint::Error::InvalidRequest(
                    "a part around a vertex needs both the vertex and the radius".into(),
                )
                .into());
            }
        };
        let spec = PartSpec {
            floors,
            around,
            name,
        };
        let opts = ImportOptions {
            replace,
            ..Default::default()
        };
        let report = self.inner.import_part(building_id, &spec, &opts)?;
        Ok(self.inner.building_info(report.id)?.into())
    }

    /// Every building, by name.
    pub fn list_buildings(&self) -> Result<Vec<BuildingSummary>> {
        Ok(self
            .inner
            .list_buildings()?
            .into_iter()
            .map(Into::into)
            .collect())
    }

    /// A building's geometry for the map.
    pub fn building_map(&self, building_id: i64) -> Result<BuildingMap> {
        Ok(BuildingMap::from(&self.inner.get_building(building_id)?))
    }

    /// Deletes a building with its fits, plans and sessions.
    pub fn delete_building(&self, building_id: i64) -> Result<()> {
        self.inner.delete_building(building_id)?;
        Ok(())
    }

    /// Fits the kernel on the building's pilot data and records the fit.
    pub fn fit(&self, building_id: i64) -> Result<FitSummary> {
        Ok(self.inner.fit_and_record(building_id)?.0.into())
    }

    /// The kernel plans of this building use (the core's policy, `Store::planning_kernel`):
    /// the file's, else the latest fit, else null (the next plan fits and records one).
    pub fn kernel(&self, building_id: i64) -> Result<Option<KernelParams>> {
        Ok(self
            .inner
            .known_planning_kernel(building_id, None)?
            .map(|k| k.kernel.into()))
    }

    /// The plans of a building, oldest first.
    pub fn list_plans(&self, building_id: i64) -> Result<Vec<PlanSummary>> {
        Ok(self
            .inner
            .list_plans(building_id)?
            .into_iter()
            .map(Into::into)
            .collect())
    }

    /// One plan.
    pub fn get_plan(&self, plan_id: i64) -> Result<PlanSummary> {
        Ok(self.inner.load_plan(plan_id)?.into())
    }
}

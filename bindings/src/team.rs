//! Several surveyors: team planning and survey bundles (export on one phone, import on
//! another or on a desktop).

use std::sync::Arc;

use trailprint::plan::Control;
use trailprint::store::{self as core_store, ExportOptions, StoreTeamRequest};
use trailprint::team::SurveyorTask;

use crate::plan::{JobControl, PlanAlgorithm, PlanListener, core_settings};
use crate::store::TrailprintStore;
use crate::{Result, TrailprintError};

/// One member of a team: where they start and end, and how far they may walk.
#[derive(Debug, Clone, uniffi::Record)]
pub struct TeamMember {
    /// Start vertex id.
    pub start: String,
    /// End vertex id (may equal the start).
    pub end: String,
    /// This member's distance budget, m.
    pub budget_m: f64,
}

/// A team planning request on a stored building.
#[derive(Debug, Clone, uniffi::Record)]
pub struct TeamPlanRequest {
    /// Store id of the building.
    pub building_id: i64,
    /// The members, in the order the summary lists their plans.
    pub members: Vec<TeamMember>,
    /// One surveyor profile for every member.
    pub surveyor: crate::model::SurveyorProfile,
    /// The planner of each member's walk.
    pub algorithm: PlanAlgorithm,
    /// Seed of the first member; member i plans with seed + i.
    pub seed: u64,
    /// Time limit of each single-walk planning call, of which a team plan makes several
    /// per member, s (null: the algorithm's default, 2 s for `AUTO`).
    pub time_limit_s: Option<f64>,
    /// Plan each member alone (for comparison) instead of as a team.
    pub independent: bool,
    /// Most memory each member's planning may use, MiB (null: 512), as
    /// `PlanRequest.memoryBudgetMb`: a request that would need more is refused with
    /// `InvalidRequest` naming the size, before anything is allocated.
    #[uniffi(default)]
    pub memory_budget_mb: Option<u64>,
}

/// The team's plans, saved in the store (one per member, in order): each member starts a
/// session from their own plan id.
#[derive(Debug, Clone, uniffi::Record)]
pub struct TeamPlanSummary {
    /// Store ids of the saved plans, one per member, in order.
    pub plan_ids: Vec<i64>,
    /// Each member's walk, vertex ids from start to end.
    pub walks: Vec<Vec<String>>,
    /// Each walk's utility on its own, nats.
    pub utilities_nats: Vec<f64>,
    /// All the members' samples together, nats.
    pub team_utility_nats: f64,
    /// The plan was cancelled ([`TeamPlanJob::cancel`]): the walks are what it had then,
    /// a member not yet planned has the systematic walk.
    pub cancelled: bool,
    /// How each member's planning ended (`completed`, `time_limit`, `cancelled`, ...).
    pub terminations: Vec<String>,
}

/// One team planning call: made by [`TrailprintStore::new_team_plan`], run once with
/// [`TeamPlanJob::run`] (blocking; call it off the main thread), cancelled from any thread
/// with [`TeamPlanJob::cancel`], which makes `run` return promptly with a walk for every
/// member (the planning under way stops with its best walk so far, a member not yet
/// planned gets the systematic walk), saved like any team plan.
#[derive(uniffi::Object)]
pub struct TeamPlanJob {
    store: Arc<TrailprintStore>,
    request: TeamPlanRequest,
    job: JobControl,
}

#[uniffi::export]
impl TeamPlanJob {
    /// The request this call plans.
    pub fn request(&self) -> TeamPlanRequest {
        self.request.clone()
    }

    /// Plans and saves the team's walks, reporting each planning run's progress to
    /// `listener` (its message names the member and the run: `surveyor 2/3, in turn: ...`).
    /// Fails with `InvalidRequest` when run a second time.
    pub fn run(&self, listener: Option<Arc<dyn PlanListener>>) -> Result<TeamPlanSummary> {
        let control = self.job.start("team plan", listener)?;
        self.store.run_team_plan(&self.request, &control)
    }

    /// Asks the running (or future) `run` to stop; safe from any thread, idempotent.
    pub fn cancel(&self) {
        self.job.cancel();
    }

    pub fn is_cancelled(&self) -> bool {
        self.job.is_cancelled()
    }
}

/// What importing a bundle did.
#[derive(Debug, Clone, uniffi::Record)]
pub struct BundleImportSummary {
    /// The bundle's checksum (SHA-256 of its content), which identifies it.
    pub bundle_id: String,
    /// Name of the building its sessions belong to.
    pub building: String,
    /// The building was not in this store and was created from the bundle.
    pub building_created: bool,
    /// Sessions new to this store.
    pub sessions_added: u64,
    /// Sessions already here that the bundle carried further (events appended).
    pub sessions_extended: u64,
    /// Sessions already here with nothing new in the bundle.
    pub sessions_unchanged: u64,
    /// Events appended, over all the sessions.
    pub events_added: u64,
}

impl From<core_store::BundleImportReport> for BundleImportSummary {
    fn from(r: core_store::BundleImportReport) -> Self {
        BundleImportSummary {
            bundle_id: r.bundle_id,
            building: r.building,
            building_created: r.building_created,
            sessions_added: r.sessions_added,
            sessions_extended: r.sessions_extended,
            sessions_unchanged: r.sessions_unchanged,
            events_added: r.events_added,
        }
    }
}

impl TrailprintStore {
    /// Plans and saves a team (the body of [`TrailprintStore::plan_team`] and
    /// [`TeamPlanJob::run`]): `Store::plan_team_and_save`.
    fn run_team_plan(
        &self,
        request: &TeamPlanRequest,
        control: &Control,
    ) -> Result<TeamPlanSummary> {
        let req = StoreTeamRequest {
            members: request
                .members
                .iter()
                .map(|m| SurveyorTask {
                    start: m.start.clone(),
                    end: m.end.clone(),
                    budget: m.budget_m,
                })
                .collect(),
            settings: core_settings(
                request.surveyor,
                request.algorithm,
                request.seed,
                request.time_limit_s,
                request.memory_budget_mb,
            )?,
            kernel: None,
            independent: request.independent,
            rounds: 1,
            condition_on_collected: true,
        };
        let saved = self
            .inner
            .plan_team_and_save(request.building_id, &req, control)?;
        Ok(TeamPlanSummary {
            plan_ids: saved.plan_ids,
            walks: saved.team.plans.iter().map(|p| p.walk.clone()).collect(),
            utilities_nats: saved.team.plans.iter().map(|p| p.utility_nats).collect(),
            team_utility_nats: saved.team.team_utility_nats,
            cancelled: saved.team.cancelled,
            terminations: saved
                .team
                .plans
                .iter()
                .map(|p| p.termination.name().to_string())
                .collect(),
        })
    }
}

#[uniffi::export]
impl TrailprintStore {
    /// Plans walks for several surveyors that complement each other (conditioned on
    /// everything already collected in the building) and saves one plan per member.
    /// Blocking: call it off the main thread ([`TeamPlanJob`] for progress and cancel).
    pub fn plan_team(&self, request: TeamPlanRequest) -> Result<TeamPlanSummary> {
        self.run_team_plan(&request, &Control::new())
    }

    /// A team planning call for `request`, to run with [`TeamPlanJob::run`].
    pub fn new_team_plan(self: Arc<Self>, request: TeamPlanRequest) -> Arc<TeamPlanJob> {
        Arc::new(TeamPlanJob {
            store: self,
            request,
            job: JobControl::default(),
        })
    }

    /// A bundle (JSON text) of the building's survey sessions, with this device's and
    /// surveyor's names as provenance, to share with another phone or a desktop.
    pub fn export_bundle(
        &self,
        building_id: i64,
        device: Option<String>,
        surveyor_name: Option<String>,
    ) -> Result<String> {
        Ok(self.inner.export_bundle(
            building_id,
            &ExportOptions {
                device,
                surveyor_name,
                sessions: Vec::new(),
            },
        )?)
    }

    /// A bundle (JSON text) of exactly the sessions `session_ids` (say, the surveys a
    /// surveyor picks from the finished ones), with the same provenance as
    /// [`TrailprintStore::export_bundle`]. A bundle holds one building, so the sessions
    /// must all be of one building; an empty list, an id not in the store or a session of
    /// another building is an error naming it (the core would read an empty list as
    /// "every session"). Ids given twice count once.
    pub fn export_sessions_bundle(
        &self,
        session_ids: Vec<i64>,
        device: Option<String>,
        surveyor_name: Option<String>,
    ) -> Result<String> {
        let Some(&first) = session_ids.first() else {
            return Err(TrailprintError::InvalidRequest(
                "export_sessions_bundle: no session ids given".into(),
            ));
        };
        // Where each session lives: the store lists sessions per building.
        let mut building_of = std::collections::HashMap::new();
        for b in self.inner.list_buildings()? {
            for s in self.inner.list_sessions(b.id)? {
                building_of.insert(s.id, (b.id, b.name.clone()));
            }
        }
        let find = |id: i64| {
            building_of.get(&id).ok_or_else(|| {
                TrailprintError::NotFound(format!("session {id} is not in the store"))
            })
        };
        let (building, name) = find(first)?.clone();
        let mut sessions = Vec::with_capacity(session_ids.len());
        for &id in &session_ids {
            let (b, other) = find(id)?;
            if *b != building {
                return Err(TrailprintError::InvalidRequest(format!(
                    "session {id} is of building \"{other}\", session {first} of \"{name}\": \
                     a bundle holds the sessions of one building"
                )));
            }
            if !sessions.contains(&id) {
                sessions.push(id);
            }
        }
        Ok(self.inner.export_bundle(
            building,
            &ExportOptions {
                device,
                surveyor_name,
                sessions,
            },
        )?)
    }

    /// Merges a bundle (JSON text; `origin` names it in errors). Importing the same bundle
    /// again changes nothing; a corrupt or truncated bundle, or one over the core's limit
    /// (`MAX_BUNDLE_BYTES`, 256 MiB), fails with `InvalidBuilding` and imports nothing.
    pub fn import_bundle(&self, json: String, origin: String) -> Result<BundleImportSummary> {
        Ok(self.inner.import_bundle(&json, &origin)?.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sessions_bundle_refuses_an_empty_list_and_names_an_unknown_session() {
        let store = TrailprintStore::open_in_memory().unwrap();
        let empty = store.export_sessions_bundle(Vec::new(), None, None);
        assert!(
            matches!(&empty, Err(TrailprintError::InvalidRequest(m)) if m.contains("no session ids")),
            "{empty:?}"
        );
        let unknown = store.export_sessions_bundle(vec![42], None, None);
        assert!(
            matches!(&unknown, Err(TrailprintError::NotFound(m)) if m.contains("session 42")),
            "{unknown:?}"
        );
    }
}

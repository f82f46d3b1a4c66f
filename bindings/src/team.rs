//! Several surveyors: team planning and survey bundles (export on one phone, import on
//! another or on a desktop).

use trailprint::plan::Control;
use trailprint::store::{self as core_store, ExportOptions, StoreTeamRequest};
use trailprint::team::SurveyorTask;

use crate::Result;
use crate::plan::{PlanAlgorithm, core_settings};
use crate::store::TrailprintStore;

/// One member of a team: where they start and end, and how far they may walk.
#[derive(Debug, Clone, uniffi::Record)]
pub struct TeamMember {
    pub start: String,
    pub end: String,
    pub budget_m: f64,
}

/// A team planning request on a stored building.
#[derive(Debug, Clone, uniffi::Record)]
pub struct TeamPlanRequest {
    pub building_id: i64,
    pub members: Vec<TeamMember>,
    pub surveyor: crate::model::SurveyorProfile,
    pub algorithm: PlanAlgorithm,
    pub seed: u64,
    pub time_limit_s: Option<f64>,
    /// Plan each member alone (for comparison) instead of as a team.
    pub independent: bool,
}

/// The team's plans, saved in the store (one per member, in order): each member starts a
/// session from their own plan id.
#[derive(Debug, Clone, uniffi::Record)]
pub struct TeamPlanSummary {
    pub plan_ids: Vec<i64>,
    pub walks: Vec<Vec<String>>,
    /// Each walk's utility on its own, nats.
    pub utilities_nats: Vec<f64>,
    /// All the members' samples together, nats.
    pub team_utility_nats: f64,
}

/// What importing a bundle did.
#[derive(Debug, Clone, uniffi::Record)]
pub struct BundleImportSummary {
    pub bundle_id: String,
    pub building: String,
    pub building_created: bool,
    pub sessions_added: u64,
    pub sessions_extended: u64,
    pub sessions_unchanged: u64,
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

#[uniffi::export]
impl TrailprintStore {
    /// Plans walks for several surveyors that complement each other (conditioned on
    /// everything already collected in the building) and saves one plan per member.
    /// Blocking: call it off the main thread.
    pub fn plan_team(&self, request: TeamPlanRequest) -> Result<TeamPlanSummary> {
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
                None,
            )?,
            kernel: None,
            independent: request.independent,
            rounds: 1,
            condition_on_collected: true,
        };
        let saved = self
            .inner
            .plan_team_and_save(request.building_id, &req, &Control::new())?;
        Ok(TeamPlanSummary {
            plan_ids: saved.plan_ids,
            walks: saved.team.plans.iter().map(|p| p.walk.clone()).collect(),
            utilities_nats: saved.team.plans.iter().map(|p| p.utility_nats).collect(),
            team_utility_nats: saved.team.team_utility_nats,
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

    /// Merges a bundle (JSON text; `origin` names it in errors). Importing the same bundle
    /// again changes nothing; a corrupt or truncated bundle, or one over the core's limit
    /// (`MAX_BUNDLE_BYTES`, 256 MiB), fails with `InvalidBuilding` and imports nothing.
    pub fn import_bundle(&self, json: String, origin: String) -> Result<BundleImportSummary> {
        Ok(self.inner.import_bundle(&json, &origin)?.into())
    }
}

//! Planning a stored building: the one kernel policy, and plan-then-save, which the phone
//! library and the command line both call so that they plan the same building the same way.
//!
//! # The kernel policy
//!
//! The kernel a plan of a building is made with is, in order:
//!
//! 1. the kernel the caller gives (`--kernel` on the command line; the phone never gives
//!    one), because the user said so;
//! 2. the building file's `kernel`, because whoever measured the building chose it;
//! 3. the building's latest stored fit (the one a phone's "fit" or an earlier plan
//!    recorded), so that every plan of the building, on any device, uses one kernel and
//!    their utilities compare;
//! 4. a new fit on the building's pilot data, **recorded**, so that step 3 finds it next
//!    time. Fewer than three pilot locations cannot be fitted: that is an
//!    [`Error::Fit`] naming the building and saying what would do.
//!
//! A building read from a file rather than a store ([`unstored_planning_kernel`]) skips
//! step 3 and does not record step 4: it has nowhere to keep a fit. The fit is
//! deterministic, so it gives the kernel a store would record for the same pilot data.
//!
//! A fit describes the pilot data it was made on; [`Store::add_pilot`] records a new fit
//! when the pilot data it leaves can be fitted, so the latest fit is the current one.

use std::sync::Arc;

use super::{BuildingRef, FitRecord, PlanRecord, Store, StoredPlan, now_ms};
use crate::building::Building;
use crate::gp::{Kernel, fit_kernel};
use crate::plan::{Control, PlanRequest, PlanResult, PlanSettings, plan_with_prior};
use crate::team::{SurveyorTask, TeamPlan, TeamRequest, plan_team};
use crate::{Error, Result};

/// Where a planning kernel came from (step of the policy in the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KernelSource {
    /// Given by the caller.
    Given,
    /// The building file's kernel.
    File,
    /// The building's latest stored fit, by id.
    StoredFit { fit_id: i64 },
    /// Fitted now on the pilot data and recorded under this id.
    NewFit { fit_id: i64 },
    /// Fitted now on the pilot data, not recorded (a building outside any store).
    UnrecordedFit,
}

impl std::fmt::Display for KernelSource {
    /// `option`, `file`, `stored fit 3`, `new fit 4 (recorded)` or `fit`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KernelSource::Given => write!(f, "option"),
            KernelSource::File => write!(f, "file"),
            KernelSource::StoredFit { fit_id } => write!(f, "stored fit {fit_id}"),
            KernelSource::NewFit { fit_id } => write!(f, "new fit {fit_id} (recorded)"),
            KernelSource::UnrecordedFit => write!(f, "fit"),
        }
    }
}

/// The kernel the policy chose, and which step chose it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanningKernel {
    pub kernel: Kernel,
    pub source: KernelSource,
}

/// Steps 1 and 2 of the policy: the caller's kernel, else the file's.
fn given_or_file(b: &Building, given: Option<Kernel>) -> Result<Option<PlanningKernel>> {
    if let Some(kernel) = given {
        kernel.validate("kernel")?;
        return Ok(Some(PlanningKernel {
            kernel,
            source: KernelSource::Given,
        }));
    }
    Ok(b.kernel.map(|kernel| PlanningKernel {
        kernel,
        source: KernelSource::File,
    }))
}

/// Step 4's fit, with the error a building without enough pilot data gets.
fn fit_pilot(b: &Building) -> Result<crate::gp::fit::FitResult> {
    if b.pilot.len() < 3 {
        return Err(Error::Fit(format!(
            "building {:?} has {} pilot fingerprint(s) and no kernel: give a kernel, or add \
             pilot data at 3 locations or more",
            b.name,
            b.pilot.len()
        )));
    }
    fit_kernel(&b.pilot)
}

/// The policy for a building outside any store (read from a file): the caller's kernel,
/// else the file's, else a fit on its pilot data, not recorded.
pub fn unstored_planning_kernel(b: &Building, given: Option<Kernel>) -> Result<PlanningKernel> {
    if let Some(k) = given_or_file(b, given)? {
        return Ok(k);
    }
    Ok(PlanningKernel {
        kernel: fit_pilot(b)?.kernel,
        source: KernelSource::UnrecordedFit,
    })
}

/// A walk to plan on a stored building.
#[derive(Debug, Clone, PartialEq)]
pub struct StorePlanRequest {
    /// Where the walk starts and ends, and its budget.
    pub route: SurveyorTask,
    pub settings: PlanSettings,
    /// A kernel that overrides the store's (step 1 of the policy); `None` on the phone.
    pub kernel: Option<Kernel>,
}

/// A plan made and saved by [`Store::plan_and_save`].
#[derive(Debug, Clone)]
pub struct SavedPlan {
    /// The plan as stored (its id, record and building).
    pub stored: StoredPlan,
    /// The planner's result (with its termination, which the store does not keep).
    pub result: PlanResult,
    pub kernel: PlanningKernel,
    /// How many collected fingerprints the plan was conditioned on.
    pub conditioned_on: usize,
}

/// Several surveyors' walks to plan on a stored building.
#[derive(Debug, Clone, PartialEq)]
pub struct StoreTeamRequest {
    pub members: Vec<SurveyorTask>,
    /// Shared by all members (member `i` uses the seed plus `i`).
    pub settings: PlanSettings,
    /// A kernel that overrides the store's (step 1 of the policy).
    pub kernel: Option<Kernel>,
    /// Plan each member alone, ignoring the others (for comparison).
    pub independent: bool,
    /// Refinement rounds (see [`crate::team`]).
    pub rounds: usize,
    /// Condition on the fingerprints already collected in the building (the default on
    /// the phone; the command line's `--ignore-collected` turns it off).
    pub condition_on_collected: bool,
}

/// A team plan made and saved by [`Store::plan_team_and_save`].
#[derive(Debug, Clone)]
pub struct SavedTeamPlan {
    /// One saved plan id per member, in order.
    pub plan_ids: Vec<i64>,
    pub team: TeamPlan,
    pub kernel: PlanningKernel,
    pub conditioned_on: usize,
}

impl Store {
    /// The kernel plans of `building` use now, without fitting: steps 1 to 3 of the policy
    /// (module docs). `None` when only a new fit would give one.
    pub fn known_planning_kernel<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        given: Option<Kernel>,
    ) -> Result<Option<PlanningKernel>> {
        let building = building.into();
        let b = self.get_building(building)?;
        self.known_kernel_of(building, &b, given)
    }

    fn known_kernel_of(
        &self,
        building: BuildingRef<'_>,
        b: &Building,
        given: Option<Kernel>,
    ) -> Result<Option<PlanningKernel>> {
        if let Some(k) = given_or_file(b, given)? {
            return Ok(Some(k));
        }
        Ok(self.latest_fit(building)?.map(|f| PlanningKernel {
            kernel: f.record.kernel,
            source: KernelSource::StoredFit { fit_id: f.id },
        }))
    }

    /// The kernel to plan `building` with: the whole policy of the module docs, recording
    /// a new fit when it makes one.
    pub fn planning_kernel<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        given: Option<Kernel>,
    ) -> Result<PlanningKernel> {
        let building = building.into();
        let b = self.get_building(building)?;
        self.planning_kernel_of(building, &b, given)
    }

    fn planning_kernel_of(
        &self,
        building: BuildingRef<'_>,
        b: &Building,
        given: Option<Kernel>,
    ) -> Result<PlanningKernel> {
        if let Some(k) = self.known_kernel_of(building, b, given)? {
            return Ok(k);
        }
        let (fit, fit_id) = self.fit_and_record_of(building, b)?;
        Ok(PlanningKernel {
            kernel: fit.kernel,
            source: KernelSource::NewFit { fit_id },
        })
    }

    /// Fits the kernel on the building's pilot data and records the fit; returns the fit
    /// and its id.
    pub fn fit_and_record<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
    ) -> Result<(crate::gp::fit::FitResult, i64)> {
        let building = building.into();
        let b = self.get_building(building)?;
        self.fit_and_record_of(building, &b)
    }

    fn fit_and_record_of(
        &self,
        building: BuildingRef<'_>,
        b: &Building,
    ) -> Result<(crate::gp::fit::FitResult, i64)> {
        let fit = fit_pilot(b)?;
        let id = self.record_fit(building, &FitRecord::from_fit(&fit, now_ms()))?;
        Ok((fit, id))
    }

    /// Plans a walk of a stored building and saves it: the kernel by the policy (module
    /// docs), conditioned on everything already collected in the building (a new walk goes
    /// where the data is thinnest), saved with its request. A cancelled plan (through
    /// `control`) is saved with the best walk found so far, like any other.
    pub fn plan_and_save<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        request: &StorePlanRequest,
        control: &Control,
    ) -> Result<SavedPlan> {
        let building = building.into();
        let b = Arc::new(self.get_building(building)?);
        let kernel = self.planning_kernel_of(building, &b, request.kernel)?;
        let route = &request.route;
        let req = PlanRequest::with_settings(
            &route.start,
            &route.end,
            route.budget,
            kernel.kernel,
            &request.settings,
        );
        let prior = self.collected_observations(building, &kernel.kernel)?;
        let result = plan_with_prior(b, &req, &prior, control)?;
        let record = PlanRecord::from_plan(&req, &result, now_ms());
        let id = self.save_plan(building, &record)?;
        Ok(SavedPlan {
            stored: self.load_plan(id)?,
            result,
            kernel,
            conditioned_on: prior.len(),
        })
    }

    /// Plans walks for several surveyors of a stored building that complement each other
    /// ([`crate::team::plan_team`]) and saves one plan per member, in order, all in one
    /// transaction: a team is saved whole or not at all.
    pub fn plan_team_and_save<'a>(
        &self,
        building: impl Into<BuildingRef<'a>>,
        request: &StoreTeamRequest,
        control: &Control,
    ) -> Result<SavedTeamPlan> {
        let building = building.into();
        let b = Arc::new(self.get_building(building)?);
        let kernel = self.planning_kernel_of(building, &b, request.kernel)?;
        let prior = if request.condition_on_collected {
            self.collected_observations(building, &kernel.kernel)?
        } else {
            Vec::new()
        };
        let req = TeamRequest {
            surveyors: request.members.clone(),
            kernel: kernel.kernel,
            settings: request.settings,
            independent: request.independent,
            rounds: request.rounds,
        };
        let team = plan_team(b, &req, &prior, control)?;
        let now = now_ms();
        let records: Vec<PlanRecord> = req
            .requests()
            .iter()
            .zip(&team.plans)
            .map(|(r, res)| PlanRecord::from_plan(r, res, now))
            .collect();
        let plan_ids = self.save_plans(building, &records)?;
        Ok(SavedTeamPlan {
            plan_ids,
            team,
            kernel,
            conditioned_on: prior.len(),
        })
    }
}

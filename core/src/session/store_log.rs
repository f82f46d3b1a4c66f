//! The SQLite store as a [`SessionLog`]: plans in `plans`/`plan_steps`, the session row in
//! `survey_sessions` (its `surveyor` column holds the [`SessionSettings`](super::SessionSettings)
//! JSON), events in `session_events` with the store's per-session `seq`, and every scan's
//! fingerprint in `collected_fingerprints`, so that `trailprint export --collected` needs no
//! replay. Each append is one committed transaction (WAL, `synchronous = FULL`): once
//! [`SessionLog::append`] returns, the event survives a kill.

use std::sync::Arc;

use super::log::{LogEntry, PlanData, SessionLog, SessionRow};
use crate::building::Building;
use crate::store::{BuildingRef, SessionEvent, Store};
use crate::{Error, Result};

impl SessionLog for Store {
    fn building(&self, building_id: i64) -> Result<Arc<Building>> {
        Ok(Arc::new(self.get_building(BuildingRef::Id(building_id))?))
    }

    fn load_plan(&self, plan_id: i64) -> Result<PlanData> {
        let p = Store::load_plan(self, plan_id)?;
        Ok(PlanData {
            building_id: p.building_id,
            record: p.record,
        })
    }

    fn save_plan(&self, plan: &PlanData) -> Result<i64> {
        Store::save_plan(self, BuildingRef::Id(plan.building_id), &plan.record)
    }

    fn create_session(
        &self,
        building_id: i64,
        plan_id: i64,
        settings: &serde_json::Value,
        created_ms: i64,
    ) -> Result<i64> {
        Store::create_session(
            self,
            BuildingRef::Id(building_id),
            Some(plan_id),
            Some(settings),
            created_ms,
        )
    }

    fn session(&self, session_id: i64) -> Result<SessionRow> {
        let h = self.session_header(session_id)?;
        let (building_id, plan_id, settings) = (h.building_id, h.plan_id, h.surveyor);
        let bad = |m: String| Error::Session {
            session: session_id,
            message: m,
        };
        let plan_id = plan_id
            .ok_or_else(|| bad("the session has no plan to walk (plan_id is NULL)".into()))?;
        let settings = settings
            .ok_or_else(|| bad("the session has no surveyor settings".into()))
            .and_then(|s| {
                serde_json::from_str(&s)
                    .map_err(|e| bad(format!("stored surveyor settings are not JSON: {e}")))
            })?;
        Ok(SessionRow {
            building_id,
            plan_id,
            settings,
        })
    }

    fn append(&self, session_id: i64, t_ms: i64, event: &SessionEvent) -> Result<i64> {
        self.append_event(session_id, t_ms, event)
    }

    fn events(&self, session_id: i64) -> Result<Vec<LogEntry>> {
        Ok(self
            .list_events(session_id, 0)?
            .into_iter()
            .map(|e| LogEntry {
                seq: e.seq,
                t_ms: e.at_ms,
                event: e.event,
            })
            .collect())
    }
}

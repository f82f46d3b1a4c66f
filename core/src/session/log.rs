//! What a session needs from storage, as a small trait: saved plans, the session row and its
//! append-only event log. [`MemoryLog`] keeps it all in memory (tests, `simulate` without
//! `--db`); the SQLite store implements it for the app.

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use serde::{Deserialize, Serialize};

use crate::building::Building;
use crate::store::{PlanRecord, SessionEvent};
use crate::{Error, Result};

/// A saved plan as a session reads and writes it: the store's plan record (request, walk
/// and figures) and the building it belongs to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanData {
    /// Store id of the building.
    pub building_id: i64,
    #[serde(flatten)]
    pub record: PlanRecord,
}

/// The session row: which plan it started from and its settings (surveyor and options, as
/// JSON the session code defines).
#[derive(Debug, Clone, PartialEq)]
pub struct SessionRow {
    pub building_id: i64,
    pub plan_id: i64,
    pub settings: serde_json::Value,
}

/// A logged event with its place and time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogEntry {
    pub seq: i64,
    pub t_ms: i64,
    /// The event as the store keeps it: a scan carries the position it was labelled with
    /// (derived data that replay recomputes, kept so that exports need no replay); a robot
    /// pose from the session has `sigma_m` 0 (SLAM).
    pub event: SessionEvent,
}

/// Storage for sessions. `append` must be durable when it returns: the session
/// acknowledges an event only after it.
pub trait SessionLog: Send + Sync {
    /// The building of a store id.
    fn building(&self, building_id: i64) -> Result<Arc<Building>>;
    /// A saved plan.
    fn load_plan(&self, plan_id: i64) -> Result<PlanData>;
    /// Saves a plan; returns its id.
    fn save_plan(&self, plan: &PlanData) -> Result<i64>;
    /// Creates a session row; returns its id.
    fn create_session(
        &self,
        building_id: i64,
        plan_id: i64,
        settings: &serde_json::Value,
        created_ms: i64,
    ) -> Result<i64>;
    /// The session row.
    fn session(&self, session_id: i64) -> Result<SessionRow>;
    /// Appends an event; returns its seq (1, 2, ...). Durable on return.
    fn append(&self, session_id: i64, t_ms: i64, event: &SessionEvent) -> Result<i64>;
    /// All events of a session, in seq order.
    fn events(&self, session_id: i64) -> Result<Vec<LogEntry>>;
}

#[derive(Debug, Default)]
struct MemoryInner {
    buildings: Vec<Arc<Building>>,
    plans: Vec<PlanData>,
    sessions: Vec<SessionRow>,
    events: Vec<Vec<LogEntry>>,
}

/// A [`SessionLog`] in memory. Ids start at 1.
#[derive(Debug, Default)]
pub struct MemoryLog {
    inner: Mutex<MemoryInner>,
}

impl MemoryLog {
    pub fn new() -> Self {
        Self::default()
    }

    fn lock(&self) -> MutexGuard<'_, MemoryInner> {
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Adds a building; returns its id.
    pub fn add_building(&self, building: Arc<Building>) -> i64 {
        let mut g = self.lock();
        g.buildings.push(building);
        g.buildings.len() as i64
    }
}

fn index(id: i64, len: usize, what: &str) -> Result<usize> {
    usize::try_from(id - 1)
        .ok()
        .filter(|&i| i < len)
        .ok_or_else(|| Error::NotFound(format!("{what} {id} is not in the database")))
}

impl SessionLog for MemoryLog {
    fn building(&self, building_id: i64) -> Result<Arc<Building>> {
        let g = self.lock();
        let i = index(building_id, g.buildings.len(), "building id")?;
        Ok(g.buildings[i].clone())
    }

    fn load_plan(&self, plan_id: i64) -> Result<PlanData> {
        let g = self.lock();
        let i = index(plan_id, g.plans.len(), "plan")?;
        Ok(g.plans[i].clone())
    }

    fn save_plan(&self, plan: &PlanData) -> Result<i64> {
        let mut g = self.lock();
        index(plan.building_id, g.buildings.len(), "building id")?;
        g.plans.push(plan.clone());
        Ok(g.plans.len() as i64)
    }

    fn create_session(
        &self,
        building_id: i64,
        plan_id: i64,
        settings: &serde_json::Value,
        _created_ms: i64,
    ) -> Result<i64> {
        let mut g = self.lock();
        index(plan_id, g.plans.len(), "plan")?;
        g.sessions.push(SessionRow {
            building_id,
            plan_id,
            settings: settings.clone(),
        });
        g.events.push(Vec::new());
        Ok(g.sessions.len() as i64)
    }

    fn session(&self, session_id: i64) -> Result<SessionRow> {
        let g = self.lock();
        let i = index(session_id, g.sessions.len(), "session")?;
        Ok(g.sessions[i].clone())
    }

    fn append(&self, session_id: i64, t_ms: i64, event: &SessionEvent) -> Result<i64> {
        let mut g = self.lock();
        let i = index(session_id, g.sessions.len(), "session")?;
        let seq = g.events[i].len() as i64 + 1;
        g.events[i].push(LogEntry {
            seq,
            t_ms,
            event: event.clone(),
        });
        Ok(seq)
    }

    fn events(&self, session_id: i64) -> Result<Vec<LogEntry>> {
        let g = self.lock();
        let i = index(session_id, g.sessions.len(), "session")?;
        Ok(g.events[i].clone())
    }
}

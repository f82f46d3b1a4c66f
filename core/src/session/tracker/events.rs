//! Event validation ([`Tracker::check`]: whether an event can be accepted, with an error
//! that names what is wrong) and the form an event takes in the log.

use super::Tracker;
use crate::Result;
use crate::building::Building;
use crate::session::types::{
    Event, MAX_EVENT_T_MS, MAX_READINGS, MAX_RSS_DBM, MAX_STEPS_PER_EVENT, MIN_RSS_DBM,
    SessionStatus,
};
use crate::store::{CollectedFingerprint, SessionEvent};

impl Tracker {
    /// Whether `ev` can be accepted now; changes nothing. The error names what is wrong.
    pub fn check(&self, b: &Building, ev: &Event) -> Result<()> {
        match self.status {
            SessionStatus::Finished | SessionStatus::Aborted => {
                return Err(self.err(format!(
                    "the session is {}: no more events are accepted (got {})",
                    if self.status == SessionStatus::Finished {
                        "finished"
                    } else {
                        "aborted"
                    },
                    ev.kind()
                )));
            }
            SessionStatus::Paused
                if matches!(
                    ev,
                    Event::Step { .. }
                        | Event::Scan { .. }
                        | Event::CheckIn { .. }
                        | Event::Pose { .. }
                ) =>
            {
                return Err(self.err(format!(
                    "the session is paused: record a resume event before this {} event",
                    ev.kind()
                )));
            }
            _ => {}
        }
        let t = ev.t_ms();
        if !(0..=MAX_EVENT_T_MS).contains(&t) {
            return Err(self.err(format!(
                "{} event: t_ms must be a device time from 0 to {MAX_EVENT_T_MS} ms since the \
                 Unix epoch (MAX_EVENT_T_MS, the year 2070), got {t}",
                ev.kind()
            )));
        }
        if let Some(last) = self.t_last
            && t < last
        {
            return Err(self.err(format!(
                "{} event at t_ms {t} goes back in time: the previous event was at t_ms {last}",
                ev.kind()
            )));
        }
        match ev {
            Event::Step { steps, .. } => {
                if !self.surveyor.is_human() {
                    return Err(self.err(
                        "step events are for human surveyors; a robot reports poses".to_string(),
                    ));
                }
                if *steps == 0 || *steps > MAX_STEPS_PER_EVENT {
                    return Err(self.err(format!(
                        "a step event counts 1 to {MAX_STEPS_PER_EVENT} steps, got {steps}"
                    )));
                }
            }
            Event::Scan { readings, .. } => {
                if readings.len() > MAX_READINGS {
                    return Err(self.err(format!(
                        "a scan holds at most {MAX_READINGS} readings, got {}",
                        readings.len()
                    )));
                }
                let mut seen = std::collections::HashSet::new();
                for (i, r) in readings.iter().enumerate() {
                    if r.bssid.trim().is_empty() {
                        return Err(self.err(format!("scan reading {i}: empty BSSID")));
                    }
                    if !r.rss_dbm.is_finite() || !(MIN_RSS_DBM..=MAX_RSS_DBM).contains(&r.rss_dbm) {
                        return Err(self.err(format!(
                            "scan reading {i} ({}): RSS must be a finite dBm value in \
                             [{MIN_RSS_DBM}, {MAX_RSS_DBM}], got {}",
                            r.bssid, r.rss_dbm
                        )));
                    }
                    if !seen.insert(r.bssid.as_str()) {
                        return Err(self.err(format!(
                            "scan reading {i}: BSSID {} appears twice in one scan",
                            r.bssid
                        )));
                    }
                }
            }
            Event::CheckIn { vertex, .. } => {
                if b.vertex_index(vertex).is_none() {
                    return Err(self.err(format!(
                        "check-in at unknown vertex {vertex:?}: building {:?} has no such vertex",
                        b.name
                    )));
                }
            }
            Event::Pose { x, y, floor, .. } => {
                if self.surveyor.is_human() {
                    return Err(self.err(
                        "pose events are for robots; a human surveyor reports steps and check-ins"
                            .to_string(),
                    ));
                }
                for (name, v) in [("x", *x), ("y", *y)] {
                    if !v.is_finite() || v.abs() > 1e7 {
                        return Err(self.err(format!(
                            "pose: {name} must be a finite number of metres, got {v}"
                        )));
                    }
                }
                if !b.floors.iter().any(|f| f.id == *floor) {
                    return Err(self.err(format!(
                        "pose on floor {floor}, which is not a floor of building {:?}",
                        b.name
                    )));
                }
            }
            Event::Pause { .. } => {
                if self.status != SessionStatus::Active {
                    return Err(self.err("pause: the session is already paused".to_string()));
                }
            }
            Event::Resume { .. } => {
                if self.status != SessionStatus::Paused {
                    return Err(self.err("resume: the session is not paused".to_string()));
                }
            }
            Event::Finish { .. } | Event::Abort { .. } => {}
        }
        Ok(())
    }

    /// The event as it goes to the log (a scan with the label it gets now).
    pub fn log_event(&self, b: &Building, ev: &Event) -> SessionEvent {
        match ev {
            Event::Step { steps, .. } => SessionEvent::Step {
                steps: *steps,
                distance_m: *steps as f64 * self.step_len,
            },
            Event::Scan { readings, .. } => {
                let (p, u, s, _) = self.label(b);
                SessionEvent::Scan(CollectedFingerprint {
                    x: p.x,
                    y: p.y,
                    floor: p.floor,
                    sigma_m: s,
                    since_checkin_m: u,
                    rss: readings
                        .iter()
                        .map(|r| (r.bssid.clone(), r.rss_dbm))
                        .collect(),
                })
            }
            Event::CheckIn { vertex, .. } => SessionEvent::CheckIn {
                vertex: vertex.clone(),
            },
            Event::Pose { x, y, floor, .. } => SessionEvent::Pose {
                x: *x,
                y: *y,
                floor: *floor,
                sigma_m: 0.0,
            },
            Event::Pause { .. } => SessionEvent::Pause,
            Event::Resume { .. } => SessionEvent::Resume,
            Event::Finish { .. } => SessionEvent::Finish,
            Event::Abort { reason, .. } => SessionEvent::Abort {
                reason: reason.clone(),
            },
        }
    }
}

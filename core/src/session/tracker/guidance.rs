//! Guidance: the next waypoint on the walk, the turn there and the sentence the surveyor
//! reads (shared with the printed turn-by-turn sheet).

use super::{ARC_TOL, OffRoute, Tracker};
use crate::building::Building;
use crate::gp::Point;
use crate::samples::turn_angle_deg;
use crate::session::types::{Guidance, SessionStatus, Turn, Waypoint};

/// The sentence a surveyor reads for the next waypoint: "In 12 m at c33 (corridor): turn
/// left; check in there." Shared by the live guidance of a session and the printed
/// turn-by-turn sheet of `trailprint plan --instructions`, so both say the same thing.
pub fn guidance_sentence(
    distance_m: f64,
    vertex: &str,
    label: Option<&str>,
    turn: Turn,
    check_in: bool,
) -> String {
    let name = match label {
        Some(l) => format!("{vertex} ({l})"),
        None => vertex.to_string(),
    };
    let what = match turn {
        Turn::Straight => "go straight on",
        Turn::Left => "turn left",
        Turn::Right => "turn right",
        Turn::TurnBack => "turn back",
        Turn::ChangeFloor => "change floor",
        Turn::Arrive => "that is the end of the walk",
    };
    format!(
        "In {distance_m:.0} m at {name}: {what}{}.",
        if check_in { "; check in there" } else { "" }
    )
}

/// The turn at `b` coming from `a`, going on to `c`.
pub fn classify_turn(a: &Point, b: &Point, c: &Point) -> Turn {
    if a.floor != b.floor || b.floor != c.floor {
        return Turn::ChangeFloor;
    }
    let angle = turn_angle_deg(a, b, c);
    if angle <= 30.0 {
        Turn::Straight
    } else if angle >= 150.0 {
        Turn::TurnBack
    } else {
        let cross = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
        if cross > 0.0 { Turn::Left } else { Turn::Right }
    }
}

impl Tracker {
    /// Route index of the next waypoint (on-route), `None` at the end.
    fn next_index(&self) -> Option<usize> {
        let a = self.pos_arc();
        let n = self.route.len();
        if self.surveyor.is_human() {
            (self.anchor + 1..n).find(|&k| self.arc[k] >= a - ARC_TOL)
        } else {
            (self.anchor..n).find(|&k| self.arc[k] > a + ARC_TOL)
        }
    }

    /// The vertices still ahead on the walk, with their distances (empty off-route).
    pub fn route_ahead(&self, b: &Building) -> Vec<Waypoint> {
        if self.off.is_some() {
            return Vec::new();
        }
        let a = self.pos_arc();
        let Some(j) = self.next_index() else {
            return Vec::new();
        };
        (j..self.route.len())
            .map(|k| {
                let v = &b.vertices[self.route[k]];
                Waypoint {
                    vertex: v.id.clone(),
                    label: v.label.clone(),
                    check_in: self.surveyor.is_human() && self.required[k],
                    distance_m: (self.arc[k] - a).max(0.0),
                }
            })
            .collect()
    }

    /// What to do next.
    pub fn guidance(&self, b: &Building) -> Guidance {
        let mut g = Guidance {
            status: self.status,
            off_route: self.off.is_some(),
            next_vertex: None,
            next_label: None,
            distance_m: 0.0,
            turn: Turn::Arrive,
            check_in_at_next: false,
            next_check_in: None,
            distance_to_check_in_m: 0.0,
            message: String::new(),
        };
        match self.status {
            SessionStatus::Finished => {
                g.message = "The session is finished.".into();
                return g;
            }
            SessionStatus::Aborted => {
                g.message = "The session was aborted.".into();
                return g;
            }
            SessionStatus::Paused => {
                g.message = "Paused: resume to continue the walk.".into();
                return g;
            }
            SessionStatus::Active => {}
        }
        match self.off {
            Some(OffRoute::Lost) => {
                g.message = "Off route: check in at the nearest vertex.".into();
                return g;
            }
            Some(OffRoute::At(v)) => {
                g.message = format!(
                    "Off route at {}: replan, or walk back to the planned walk and check in.",
                    b.vertices[v].id
                );
                return g;
            }
            None => {}
        }
        let a = self.pos_arc();
        let Some(j) = self.next_index() else {
            g.message = format!(
                "You have arrived at {}: finish the session.",
                b.vertices[self.end].id
            );
            return g;
        };
        let n = self.route.len();
        let v = &b.vertices[self.route[j]];
        g.next_vertex = Some(v.id.clone());
        g.next_label = v.label.clone();
        g.distance_m = (self.arc[j] - a).max(0.0);
        g.turn = if j + 1 >= n {
            Turn::Arrive
        } else {
            classify_turn(
                &b.vertices[self.route[j - 1]].pos,
                &v.pos,
                &b.vertices[self.route[j + 1]].pos,
            )
        };
        let human = self.surveyor.is_human();
        g.check_in_at_next = human && self.required[j];
        if human && let Some(k) = (j..n).find(|&k| self.required[k]) {
            g.next_check_in = Some(b.vertices[self.route[k]].id.clone());
            g.distance_to_check_in_m = (self.arc[k] - a).max(0.0);
        }
        g.message = guidance_sentence(
            g.distance_m,
            &v.id,
            v.label.as_deref(),
            g.turn,
            g.check_in_at_next,
        );
        g
    }
}

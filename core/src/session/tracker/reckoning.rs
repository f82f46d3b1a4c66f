//! Dead reckoning of a human surveyor: `u = steps x L` metres past the last check-in, held
//! at the check-in that is due; check-ins re-anchor the estimate and calibrate `L`.

use super::{OffRoute, Tracker};
use crate::building::Building;
use crate::gp::Point;
use crate::samples::point_on_edge;
use crate::session::types::Surveyor;

impl Tracker {
    /// Dead-reckoned distance since the last check-in, metres.
    pub(super) fn dr(&self) -> f64 {
        self.steps_since as f64 * self.step_len
    }

    /// Route index of the next check-in due after route index `from` (the end if none).
    pub(super) fn next_required(&self, from: usize) -> usize {
        (from + 1..self.route.len())
            .find(|&k| self.required[k])
            .unwrap_or(self.route.len() - 1)
    }

    /// Arc length of the current position estimate along the route.
    pub(super) fn pos_arc(&self) -> f64 {
        if self.surveyor.is_human() {
            let nr = self.next_required(self.anchor);
            (self.arc[self.anchor] + self.dr()).min(self.arc[nr])
        } else {
            self.robot_arc
        }
    }

    /// The point at arc length `a` of the route.
    pub(super) fn point_at(&self, b: &Building, a: f64) -> Point {
        let n = self.route.len();
        let idx = self.arc.partition_point(|&x| x < a);
        if idx == 0 {
            return b.vertices[self.route[0]].pos;
        }
        if idx >= n {
            return b.vertices[self.route[n - 1]].pos;
        }
        if self.arc[idx] == a {
            return b.vertices[self.route[idx]].pos;
        }
        let (pa, pb) = (
            b.vertices[self.route[idx - 1]].pos,
            b.vertices[self.route[idx]].pos,
        );
        let start = self.arc[idx - 1];
        let len = self.arc[idx] - start;
        let frac = ((a - start) / len).clamp(0.0, 1.0);
        point_on_edge(&pa, &pb, frac)
    }

    /// Counts `steps` more steps; returns whether they took the surveyor off-route (more
    /// than the slack past the check-in that is due).
    pub(super) fn human_steps(&mut self, steps: u32) -> bool {
        self.steps_since += u64::from(steps);
        self.steps_total += u64::from(steps);
        if self.off.is_some() {
            return false;
        }
        let nr = self.next_required(self.anchor);
        let leg = self.arc[nr] - self.arc[self.anchor];
        let slack = self.options.off_route_slack_m + self.options.off_route_slack_fraction * leg;
        if self.arc[self.anchor] + self.dr() <= self.arc[nr] + slack {
            return false;
        }
        self.off = Some(OffRoute::Lost);
        self.off_route_events += 1;
        // Replanning needs a known vertex: it waits for the next check-in.
        self.replan_due = false;
        true
    }

    /// A human check-in at vertex `v`; returns whether it took the surveyor off-route.
    pub(super) fn human_check_in(&mut self, v: usize) -> bool {
        let walked = self.dr();
        let found = if self.off.is_none() {
            let nr = self.next_required(self.anchor);
            (self.anchor + 1..=nr).find(|&k| self.route[k] == v)
        } else {
            // Back on the walk anywhere ahead of the last on-route check-in.
            (self.anchor..self.route.len()).find(|&k| self.route[k] == v)
        };
        match found {
            Some(k) => {
                let leg = self.arc[k] - self.arc[self.anchor];
                if self.off.is_none() {
                    if self.steps_since > 0 && leg > 0.0 {
                        // The last step of a leg ends at the vertex, half a step short on
                        // average: a leg of n counted steps is n - 1/2 strides long.
                        self.calib_m += leg;
                        self.calib_steps += self.steps_since as f64 - 0.5;
                        if let Surveyor::Human { step_length_m, .. } = self.surveyor {
                            let w = self.options.calibration_weight_steps;
                            self.step_len =
                                (w * step_length_m + self.calib_m) / (w + self.calib_steps);
                        }
                    }
                    self.confirmed_m += leg;
                } else {
                    self.confirmed_m += walked;
                }
                self.anchor = k;
                self.steps_since = 0;
                self.off = None;
                self.replan_due = false;
                false
            }
            None if self.off.is_none() && self.route[self.anchor] == v => {
                // Checked in again where the last check-in was.
                self.confirmed_m += walked;
                self.steps_since = 0;
                false
            }
            None => {
                self.confirmed_m += walked;
                self.steps_since = 0;
                self.go_off(OffRoute::At(v))
            }
        }
    }
}

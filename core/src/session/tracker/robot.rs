//! Robot position tracking: each pose is projected onto the walk (the first nearby segment
//! ahead, never going back by more than the tolerance); a pose farther than the tolerance
//! from the walk puts the robot off-route, at the nearest vertex.

use super::{ARC_TOL, OffRoute, ROBOT_LOOKAHEAD_INTERVALS, Tracker};
use crate::building::Building;
use crate::gp::Point;

impl Tracker {
    fn move_pose(&mut self, p: Point) {
        if let Some(prev) = self.pose {
            self.robot_walked_m += prev.planar_distance(&p);
        }
        self.pose = Some(p);
    }

    /// A robot check-in at vertex `v`.
    pub(super) fn robot_check_in(&mut self, b: &Building, v: usize) -> bool {
        self.move_pose(b.vertices[v].pos);
        let from = self.anchor;
        let found = if self.off.is_none() {
            // On-route: the vertex must be where the robot is along the walk, give or take
            // the tolerance and one scan interval (the last pose may lag behind).
            let reach = self.tol() + self.surveyor.spacing();
            (from..self.route.len()).find(|&k| {
                self.route[k] == v
                    && self.arc[k] >= self.robot_arc - self.tol()
                    && self.arc[k] <= self.robot_arc + reach
            })
        } else {
            (from..self.route.len()).find(|&k| self.route[k] == v)
        };
        match found {
            Some(k) => {
                self.anchor = k.min(self.route.len().saturating_sub(2));
                self.robot_arc = self.arc[k];
                self.off = None;
                self.replan_due = false;
                false
            }
            None => self.go_off(OffRoute::At(v)),
        }
    }

    fn tol(&self) -> f64 {
        self.options.robot_tolerance_m
    }

    /// Projects a pose onto the route ahead: `(segment, arc)`.
    fn project(&self, b: &Building, p: &Point) -> Option<(usize, f64)> {
        let n = self.route.len();
        let tol = self.tol();
        if n == 1 {
            let v = b.vertices[self.route[0]].pos;
            return (v.floor == p.floor && v.planar_distance(p) <= tol).then_some((0, 0.0));
        }
        // Ahead (or level): the nearest segment, the earliest on a tie (a U-turn retraces
        // the same line). Behind by less than the tolerance: the latest (pose noise).
        let mut forward: Option<(usize, f64, f64)> = None;
        let mut backward: Option<(usize, f64)> = None;
        let lookahead = (ROBOT_LOOKAHEAD_INTERVALS * self.surveyor.spacing()).max(2.0);
        for k in self.anchor..n - 1 {
            if self.arc[k] > self.robot_arc + lookahead + tol {
                break;
            }
            let (pa, pb) = (
                b.vertices[self.route[k]].pos,
                b.vertices[self.route[k + 1]].pos,
            );
            let (t, d) = if pa.floor == pb.floor {
                if p.floor != pa.floor {
                    continue;
                }
                p.segment_projection(&pa, &pb)
            } else if p.floor == pa.floor {
                (0.0, p.planar_distance(&pa))
            } else if p.floor == pb.floor {
                (1.0, p.planar_distance(&pb))
            } else {
                continue;
            };
            if d > tol {
                continue;
            }
            let a = self.arc[k] + t * (self.arc[k + 1] - self.arc[k]);
            if a >= self.robot_arc - ARC_TOL {
                if forward.is_none_or(|(_, fa, fd)| d < fd - 1e-9 || (d <= fd + 1e-9 && a < fa)) {
                    forward = Some((k, a, d));
                }
            } else if a >= self.robot_arc - tol && backward.is_none_or(|(_, ba)| a > ba) {
                backward = Some((k, a));
            }
        }
        forward.map(|(k, a, _)| (k, a)).or(backward)
    }

    fn nearest_vertex(b: &Building, p: &Point) -> usize {
        let mut best = (f64::INFINITY, 0);
        for (i, v) in b.vertices.iter().enumerate() {
            let d = v.pos.planar_distance(p) + if v.pos.floor == p.floor { 0.0 } else { 1e6 };
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1
    }

    /// A robot pose; returns whether it took the robot off-route. The distance walked
    /// between two on-route poses is the longer of the distance along the walk (corners
    /// and turns are not cut) and the straight line (a detour within the tolerance
    /// counts); otherwise the straight line.
    pub(super) fn robot_pose(&mut self, b: &Building, p: Point) -> bool {
        let projected = self.project(b, &p);
        match (self.off, self.pose, projected) {
            (None, Some(prev), Some((_, a))) => {
                self.robot_walked_m += (a - self.robot_arc).abs().max(prev.planar_distance(&p));
                self.pose = Some(p);
            }
            _ => self.move_pose(p),
        }
        match projected {
            Some((k, a)) => {
                self.anchor = k;
                self.robot_arc = a;
                self.off = None;
                self.replan_due = false;
                false
            }
            None => self.go_off(OffRoute::At(Self::nearest_vertex(b, &p))),
        }
    }
}

//! Sample positions `R(P)` along a walk and their label noise (SPEC section 4).
//!
//! Positions are placed by arc length from the start of the walk, every `d` metres, and
//! interpolated linearly along each edge by the fraction of that edge's length. A robot
//! (the paper's model) labels its samples by SLAM, without extra noise. A human surveyor
//! labels them with a step counter whose error grows with the distance walked since the
//! last check-in; that error becomes extra observation noise through
//! [`Kernel::label_noise`].
//!
//! [`WalkSampler`] produces the samples edge by edge, so that the incremental utility
//! engine and the whole-walk function [`sample_walk`] share one piece of arithmetic and
//! agree to the last bit.

use serde::{Deserialize, Serialize};

use crate::building::Building;
use crate::gp::{Kernel, Point};
pub use crate::surveyor::Surveyor;
use crate::{Error, Result};

/// Arc-length tolerance of SPEC sections 3 and 4.
pub const ARC_EPS: f64 = 1e-9;

/// One sample of a walk.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Where the sample is taken (true position).
    pub pos: Point,
    /// Arc length from the start of the walk, metres.
    pub arc: f64,
    /// Distance walked since the last check-in, metres (0 for a robot).
    pub since_checkin: f64,
    /// Extra observation noise of the label, dB² (0 for a robot).
    pub extra_noise: f64,
}

/// The point a fraction `frac` (0 to 1) of the way along the edge from `pa` to `pb`. On
/// a stair (ends on different floors) the floor is the nearer end's, the lower one exactly
/// at the middle. The sampler, the session tracker and the simulated surveyor all place
/// points with this one function, so a session's labels agree with the planned samples.
pub fn point_on_edge(pa: &Point, pb: &Point, frac: f64) -> Point {
    let floor = if pa.floor == pb.floor || frac < 0.5 {
        pa.floor
    } else if frac > 0.5 {
        pb.floor
    } else {
        pa.floor.min(pb.floor)
    };
    Point::new(
        pa.x + frac * (pb.x - pa.x),
        pa.y + frac * (pb.y - pa.y),
        floor,
    )
}

/// Turn angle at `b` between the directions `a -> b` and `b -> c`, degrees in [0, 180].
pub fn turn_angle_deg(a: &Point, b: &Point, c: &Point) -> f64 {
    let (x1, y1) = (b.x - a.x, b.y - a.y);
    let (x2, y2) = (c.x - b.x, c.y - b.y);
    let n = (x1 * x1 + y1 * y1).sqrt() * (x2 * x2 + y2 * y2).sqrt();
    if n == 0.0 {
        // A purely vertical move (a lift); treated as a check-in by the floor rule anyway.
        return 180.0;
    }
    ((x1 * x2 + y1 * y2) / n)
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// Where the surveyor checks in along `walk` (SPEC section 4): the start, the end and, for
/// a human (`turn_threshold_deg` given), every vertex where [`is_turn_checkin`] holds. A
/// robot (`None`) needs no check-in between the ends. Shared by the session tracker and the
/// printed walk, so that the sheet asks for the check-ins the session expects.
pub fn check_in_flags(
    building: &Building,
    walk: &[usize],
    turn_threshold_deg: Option<f64>,
) -> Vec<bool> {
    let n = walk.len();
    let mut out = vec![false; n];
    if n == 0 {
        return out;
    }
    out[0] = true;
    out[n - 1] = true;
    if let Some(threshold) = turn_threshold_deg {
        for i in 1..n - 1 {
            out[i] = is_turn_checkin(building, walk[i - 1], walk[i], walk[i + 1], threshold);
        }
    }
    out
}

/// Whether the surveyor checks in at `walk[i]` (`0 < i < len - 1`): the walk turns by
/// more than the threshold there, or the floor changes on either side.
pub fn is_turn_checkin(
    building: &Building,
    prev: usize,
    at: usize,
    next: usize,
    threshold_deg: f64,
) -> bool {
    let (a, b, c) = (
        building.vertices[prev].pos,
        building.vertices[at].pos,
        building.vertices[next].pos,
    );
    if a.floor != b.floor || b.floor != c.floor {
        return true;
    }
    turn_angle_deg(&a, &b, &c) > threshold_deg
}

/// A [`WalkSampler`]'s state at one vertex of a walk ([`WalkSampler::checkpoint`]).
#[derive(Debug, Clone, Copy)]
pub struct Checkpoint {
    prev: Option<usize>,
    at: usize,
    length: f64,
    next_k: u64,
    last_checkin: f64,
    pending: Option<Sample>,
}

/// Incremental sample placement along a growing walk.
///
/// Feed vertices with [`push`](Self::push); each call returns the samples that became
/// final. A sample within [`ARC_EPS`] of the current end vertex stays pending until the
/// next vertex tells whether that vertex is a check-in; [`pending`](Self::pending) gives
/// it with the noise it has if the walk ends there.
#[derive(Debug, Clone)]
pub struct WalkSampler {
    model: Surveyor,
    kernel: Kernel,
    spacing: f64,
    /// Vertices so far (only the last two matter, the rest is kept for callers).
    walk: Vec<usize>,
    /// Arc length at the current end vertex.
    length: f64,
    /// Index `k` of the next sample to place, at arc `k * spacing`.
    next_k: u64,
    /// Arc length of the last confirmed check-in.
    last_checkin: f64,
    /// A sample at the current end vertex awaiting that vertex's check-in status.
    pending: Option<Sample>,
}

impl WalkSampler {
    /// Starts a walk at `start`; the start is a check-in and the first sample is there.
    pub fn new(building: &Building, start: usize, model: Surveyor, kernel: Kernel) -> Self {
        let spacing = model.spacing();
        let pos = building.vertices[start].pos;
        WalkSampler {
            model,
            kernel,
            spacing,
            walk: vec![start],
            length: 0.0,
            next_k: 1,
            last_checkin: 0.0,
            pending: Some(Sample {
                pos,
                arc: 0.0,
                since_checkin: 0.0,
                extra_noise: 0.0,
            }),
        }
    }

    /// The vertices walked so far.
    pub fn walk(&self) -> &[usize] {
        &self.walk
    }

    /// Length of the walk so far, metres.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The sample at the current end vertex, if one falls there.
    pub fn pending(&self) -> Option<Sample> {
        self.pending
    }

    /// The surveyor model in use.
    pub fn model(&self) -> Surveyor {
        self.model
    }

    fn noise_for(&self, u: f64) -> f64 {
        match self.model {
            Surveyor::Robot { .. } => 0.0,
            Surveyor::Human { step_error, .. } => self.kernel.label_noise(step_error * u),
        }
    }

    fn make(&self, pos: Point, arc: f64) -> Sample {
        let u = match self.model {
            Surveyor::Robot { .. } => 0.0,
            Surveyor::Human { .. } => {
                if arc <= self.last_checkin + ARC_EPS {
                    0.0
                } else {
                    arc - self.last_checkin
                }
            }
        };
        Sample {
            pos,
            arc,
            since_checkin: u,
            extra_noise: self.noise_for(u),
        }
    }

    /// Extends the walk to `next`, which must be a neighbour of the current end. Appends
    /// the samples that became final to `out`.
    pub fn push(&mut self, building: &Building, next: usize, out: &mut Vec<Sample>) -> Result<()> {
        let at = *self.walk.last().ok_or_else(|| Error::InvalidWalk {
            step: 0,
            message: "empty walk".into(),
        })?;
        let edge = building
            .edge_between(at, next)
            .ok_or_else(|| Error::InvalidWalk {
                step: self.walk.len(),
                message: format!(
                    "no edge between {:?} and {:?}",
                    building.vertices[at].id, building.vertices[next].id
                ),
            })?;
        // Is the current end vertex a check-in? (The start already is.)
        if self.walk.len() >= 2 {
            let prev = self.walk[self.walk.len() - 2];
            if let Surveyor::Human {
                turn_threshold_deg, ..
            } = self.model
                && is_turn_checkin(building, prev, at, next, turn_threshold_deg)
            {
                self.last_checkin = self.length;
            }
        }
        // The pending sample at `at` is now final, with the check-in status known.
        if let Some(p) = self.pending.take() {
            out.push(self.make(p.pos, p.arc));
        }
        let start_arc = self.length;
        let len = edge.length;
        let end_arc = start_arc + len;
        let (pa, pb) = (building.vertices[at].pos, building.vertices[next].pos);
        loop {
            let s = self.next_k as f64 * self.spacing;
            if s > end_arc + ARC_EPS {
                break;
            }
            let frac = ((s - start_arc) / len).clamp(0.0, 1.0);
            let pos = point_on_edge(&pa, &pb, frac);
            self.next_k += 1;
            if s >= end_arc - ARC_EPS {
                // At the new end vertex: its check-in status is not known yet.
                self.pending = Some(Sample {
                    pos,
                    arc: s,
                    since_checkin: 0.0,
                    extra_noise: 0.0,
                });
            } else {
                out.push(self.make(pos, s));
            }
        }
        self.length = end_arc;
        self.walk.push(next);
        Ok(())
    }

    /// The sampler's state at the current end vertex: enough to go on from there
    /// ([`WalkSampler::resume`]) without walking the vertices before it again.
    pub fn checkpoint(&self) -> Checkpoint {
        let n = self.walk.len();
        Checkpoint {
            prev: n.checked_sub(2).map(|i| self.walk[i]),
            at: self.walk[n - 1],
            length: self.length,
            next_k: self.next_k,
            last_checkin: self.last_checkin,
            pending: self.pending,
        }
    }

    /// A sampler in the state `cp` was taken in: pushing the same vertices from there
    /// gives the same samples, bit for bit, as the sampler `cp` came from. Its
    /// [`WalkSampler::walk`] holds the checkpoint's last two vertices only.
    pub fn resume(cp: &Checkpoint, model: Surveyor, kernel: Kernel) -> Self {
        WalkSampler {
            model,
            kernel,
            spacing: model.spacing(),
            walk: cp.prev.into_iter().chain([cp.at]).collect(),
            length: cp.length,
            next_k: cp.next_k,
            last_checkin: cp.last_checkin,
            pending: cp.pending,
        }
    }

    /// The pending sample with the noise it has if the walk ends at the current vertex.
    pub fn pending_final(&self) -> Option<Sample> {
        self.pending.map(|p| self.make(p.pos, p.arc))
    }
}

/// All samples of a walk, in order (SPEC section 4).
///
/// # Errors
/// An empty walk, a step without an edge, or a surveyor model that fails
/// [`Surveyor::validate`] (checked first: a spacing that is not positive has no end).
pub fn sample_walk(
    building: &Building,
    walk: &[usize],
    model: &Surveyor,
    kernel: &Kernel,
) -> Result<Vec<Sample>> {
    sample_walk_into(building, walk, model, kernel, None)
}

/// [`sample_walk`], with the sampler's state at each vertex of the walk (what a walk
/// that shares the first vertices can be sampled on from: [`WalkSampler::resume`]).
///
/// # Errors
/// As [`sample_walk`].
pub fn sample_walk_checkpoints(
    building: &Building,
    walk: &[usize],
    model: &Surveyor,
    kernel: &Kernel,
) -> Result<(Vec<Sample>, Vec<Checkpoint>)> {
    let mut cps = Vec::with_capacity(walk.len());
    let samples = sample_walk_into(building, walk, model, kernel, Some(&mut cps))?;
    Ok((samples, cps))
}

fn sample_walk_into(
    building: &Building,
    walk: &[usize],
    model: &Surveyor,
    kernel: &Kernel,
    mut checkpoints: Option<&mut Vec<Checkpoint>>,
) -> Result<Vec<Sample>> {
    let Some(&start) = walk.first() else {
        return Err(Error::InvalidWalk {
            step: 0,
            message: "the walk is empty".into(),
        });
    };
    // A spacing that is not positive would place samples without end (a walking speed of
    // -1 m/s filled 24 GB before this check).
    model.validate()?;
    let mut sampler = WalkSampler::new(building, start, *model, *kernel);
    let mut out = Vec::new();
    if let Some(c) = checkpoints.as_mut() {
        c.push(sampler.checkpoint());
    }
    for &v in &walk[1..] {
        sampler.push(building, v, &mut out)?;
        if let Some(c) = checkpoints.as_mut() {
            c.push(sampler.checkpoint());
        }
    }
    out.extend(sampler.pending_final());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line() -> Building {
        // a(0,0) - b(2,0) - c(2,1.5) ; b - d(4,0) straight on.
        let text = r#"{"format":"survey-building/1","name":"L",
          "vertices":[{"id":"a","x":0,"y":0},{"id":"b","x":2,"y":0},{"id":"c","x":2,"y":1.5},{"id":"d","x":4,"y":0}],
          "edges":[{"a":"a","b":"b"},{"a":"b","b":"c"},{"a":"b","b":"d"}]}"#;
        Building::from_json(text, "line").expect("valid")
    }

    /// A sampler resumed at any vertex's checkpoint and fed the rest of the walk gives
    /// the whole walk's samples from that vertex on, bit for bit, for both models (a
    /// person's label noise depends on the last check-in, which the checkpoint carries).
    #[test]
    fn a_sampler_resumed_at_a_checkpoint_gives_the_rest_of_the_walks_samples() {
        let b = line();
        let walk = b
            .resolve_walk(&["a", "b", "c", "b", "d", "b", "a", "b", "c"])
            .expect("walk");
        let k = Kernel::new(20.0, 5.0, 2.0);
        let slow = match Surveyor::human() {
            Surveyor::Human {
                step_length_m,
                scan_interval_s,
                step_error,
                turn_threshold_deg,
                ..
            } => Surveyor::Human {
                step_length_m,
                speed_mps: 0.35,
                scan_interval_s,
                step_error,
                turn_threshold_deg,
            },
            robot => robot,
        };
        for model in [Surveyor::robot(), Surveyor::human(), slow] {
            let (all, cps) = sample_walk_checkpoints(&b, &walk, &model, &k).expect("samples");
            assert_eq!(all, sample_walk(&b, &walk, &model, &k).expect("samples"));
            assert_eq!(cps.len(), walk.len());
            for (i, cp) in cps.iter().enumerate() {
                let mut s = WalkSampler::resume(cp, model, k);
                let mut out = Vec::new();
                for &v in &walk[i + 1..] {
                    s.push(&b, v, &mut out).expect("push");
                }
                out.extend(s.pending_final());
                let from = all.partition_point(|x| x.arc < cp.length - ARC_EPS);
                assert_eq!(out, all[from..], "{model:?} from vertex {i}");
            }
        }
    }

    /// A walking speed of -1 m/s (the bindings pass a profile as given) was sampled
    /// without end: 24 GB before the out-of-memory killer. It is refused, naming it.
    #[test]
    fn a_model_with_a_spacing_that_is_not_positive_is_refused_before_sampling() {
        let b = line();
        let walk = b.resolve_walk(&["a", "b", "d"]).expect("walk");
        let Surveyor::Human {
            step_length_m,
            scan_interval_s,
            step_error,
            turn_threshold_deg,
            ..
        } = Surveyor::human()
        else {
            unreachable!("human() is a human")
        };
        let model = Surveyor::Human {
            step_length_m,
            speed_mps: -1.0,
            scan_interval_s,
            step_error,
            turn_threshold_deg,
        };
        let e = sample_walk(&b, &walk, &model, &Kernel::new(20.0, 5.0, 2.0)).expect_err("refused");
        assert!(e.to_string().contains("speed"), "{e}");
    }

    #[test]
    fn a_point_on_a_stair_takes_the_nearer_floor_and_the_lower_one_at_the_middle() {
        let (low, high) = (Point::new(0.0, 0.0, 2), Point::new(4.0, 2.0, 1));
        let at = |f: f64| point_on_edge(&low, &high, f);
        assert_eq!(at(0.25), Point::new(1.0, 0.5, 2));
        assert_eq!(at(0.75), Point::new(3.0, 1.5, 1));
        // Exactly at the middle of a stair: the lower floor, from either end.
        assert_eq!(at(0.5).floor, 1);
        assert_eq!(point_on_edge(&high, &low, 0.5).floor, 1);
        assert_eq!(at(0.0), low);
        assert_eq!(at(1.0), high);
    }

    #[test]
    fn robot_samples_on_a_walk_with_revisits() {
        let b = line();
        let k = Kernel::new(1.0, 1.0, 1.0);
        // a -> b -> c -> b : 2 + 1.5 + 1.5 = 5 m, every 0.75 m: arcs 0, .75, ..., 4.5 (7 samples).
        let walk = b.resolve_walk(&["a", "b", "c", "b"]).expect("walk");
        let s = sample_walk(&b, &walk, &Surveyor::robot_every(0.75), &k).expect("samples");
        assert_eq!(s.len(), 7);
        let expect = [
            (0.0, 0.0),
            (0.75, 0.0),
            (1.5, 0.0),
            (2.0, 0.25),
            (2.0, 1.0),
            (2.0, 1.25),
            (2.0, 0.5),
        ];
        for (got, want) in s.iter().zip(expect) {
            assert!(
                (got.pos.x - want.0).abs() < 1e-12 && (got.pos.y - want.1).abs() < 1e-12,
                "{got:?} vs {want:?}"
            );
            assert_eq!(got.extra_noise, 0.0);
        }
        // Exactly at the end: 5 m with a 1.25 m interval gives 5 samples, the last at b.
        let s = sample_walk(&b, &walk, &Surveyor::robot_every(1.25), &k).expect("samples");
        assert_eq!(s.len(), 5);
        assert!((s[4].pos.x - 2.0).abs() < 1e-12 && s[4].pos.y.abs() < 1e-12);
    }

    #[test]
    fn human_noise_restarts_at_checkins() {
        let b = line();
        let k = Kernel::new(10.0, 5.0, 1.0);
        let model = Surveyor::Human {
            step_length_m: 0.7,
            speed_mps: 1.0,
            scan_interval_s: 0.5,
            step_error: 0.1,
            turn_threshold_deg: 30.0,
        };
        // a -> b -> d is straight: no check-in at b; a -> b -> c turns 90 degrees at b.
        let sample = |ids: &[&str]| {
            sample_walk(&b, &b.resolve_walk(ids).expect("w"), &model, &k).expect("s")
        };
        let straight = sample(&["a", "b", "d"]);
        let turning = sample(&["a", "b", "c"]);
        assert_eq!(straight[0].extra_noise, 0.0, "the start is a check-in");
        assert!((straight[6].since_checkin - 3.0).abs() < 1e-12);
        assert!((straight[6].extra_noise - k.label_noise(0.3)).abs() < 1e-15);
        // The sample exactly at b (arc 2) has u = 0 when b is a check-in, u = 2 otherwise.
        assert!((straight[4].since_checkin - 2.0).abs() < 1e-12);
        assert_eq!(turning[4].since_checkin, 0.0);
        assert_eq!(turning[4].extra_noise, 0.0);
        assert!((turning[6].since_checkin - 1.0).abs() < 1e-12);
        // Noise grows with the distance since the last check-in.
        for w in straight.windows(2) {
            assert!(w[1].extra_noise > w[0].extra_noise);
        }
    }

    #[test]
    fn u_turn_is_a_checkin_and_floor_of_a_stair_sample_is_the_nearer_end() {
        let text = r#"{"format":"survey-building/1","name":"S","floors":[{"id":0},{"id":1}],
          "vertices":[{"id":"a","x":0,"y":0},{"id":"b","x":1,"y":0},{"id":"c","x":1,"y":0,"floor":1}],
          "edges":[{"a":"a","b":"b"},{"a":"b","b":"c","length":4}]}"#;
        let b = Building::from_json(text, "s").expect("valid");
        let k = Kernel::new(1.0, 1.0, 1.0);
        let s = sample_walk(&b, &[0, 1, 2], &Surveyor::robot_every(1.0), &k).expect("s");
        // arcs 0..5: on the stair (1..5) the fractions are 0, .25, .5, .75, 1.
        let floors: Vec<i64> = s.iter().map(|s| s.pos.floor).collect();
        assert_eq!(floors, vec![0, 0, 0, 0, 1, 1]);
        assert!(
            (turn_angle_deg(&b.vertices[0].pos, &b.vertices[1].pos, &b.vertices[0].pos) - 180.0)
                .abs()
                < 1e-9
        );
    }
}

//! Robot sample positions along a walk (SPEC section 4, the paper's model).
//!
//! A small local version for the `evaluate` and `render` commands until the lead's
//! `trailprint::samples` module lands; prefer that one once it exists.

use crate::building::Building;
use crate::gp::Point;
use crate::{Error, Result};

/// Positions of a robot's scans along `walk` (vertex indices): arc lengths `k * interval`
/// for `k = 0, 1, ...` while `k * interval <= C(P) + 1e-9`, interpolated linearly along
/// each edge by the fraction of its length. A sample on an edge between floors takes the
/// floor of the nearer end (the lower floor exactly at the middle).
pub fn robot_samples(building: &Building, walk: &[usize], interval: f64) -> Result<Vec<Point>> {
    if !interval.is_finite() || interval <= 0.0 {
        return Err(Error::InvalidRequest(format!(
            "sample interval must be a finite positive number of metres, got {interval}"
        )));
    }
    building.check_walk(walk)?;
    let Some(&start) = walk.first() else {
        return Err(Error::InvalidWalk {
            step: 0,
            message: "the walk is empty".into(),
        });
    };
    let lengths: Vec<f64> = walk
        .windows(2)
        .map(|w| building.edge_between(w[0], w[1]).map_or(0.0, |e| e.length))
        .collect();
    let total: f64 = lengths.iter().sum();
    let count = ((total + 1e-9) / interval).floor() as usize + 1;
    let mut out = Vec::with_capacity(count);
    let mut edge = 0usize;
    let mut edge_start = 0.0;
    for k in 0..count {
        let s = k as f64 * interval;
        while edge + 1 < lengths.len() && s > edge_start + lengths[edge] {
            edge_start += lengths[edge];
            edge += 1;
        }
        if lengths.is_empty() {
            out.push(building.vertices[start].pos);
            continue;
        }
        let a = building.vertices[walk[edge]].pos;
        let b = building.vertices[walk[edge + 1]].pos;
        let t = ((s - edge_start) / lengths[edge]).clamp(0.0, 1.0);
        let floor = if a.floor == b.floor || t < 0.5 {
            a.floor
        } else if t > 0.5 {
            b.floor
        } else {
            a.floor.min(b.floor)
        };
        out.push(Point::new(
            a.x + t * (b.x - a.x),
            a.y + t * (b.y - a.y),
            floor,
        ));
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::expect_used)] // tests state what they expect
mod tests {
    use super::*;

    fn building() -> Building {
        let text = serde_json::json!({
            "format": "survey-building/1",
            "name": "T",
            "floors": [{"id": 0}, {"id": 1}],
            "vertices": [
                {"id": "a", "x": 0.0, "y": 0.0},
                {"id": "b", "x": 2.0, "y": 0.0},
                {"id": "c", "x": 2.0, "y": 0.0, "floor": 1}
            ],
            "edges": [{"a": "a", "b": "b"}, {"a": "b", "b": "c", "length": 4.0}]
        })
        .to_string();
        Building::from_json(&text, "t").expect("valid")
    }

    #[test]
    fn samples_every_interval_including_both_ends_when_they_fit() {
        let b = building();
        let s = robot_samples(&b, &[0, 1, 0], 0.5).expect("samples");
        assert_eq!(s.len(), 9); // 0, 0.5, ..., 4.0
        assert_eq!(s[0], Point::new(0.0, 0.0, 0));
        assert_eq!(s[4], Point::new(2.0, 0.0, 0));
        assert_eq!(s[5], Point::new(1.5, 0.0, 0));
        assert_eq!(s[8], Point::new(0.0, 0.0, 0));
        let s = robot_samples(&b, &[0, 1], 0.75).expect("samples");
        assert_eq!(s.len(), 3); // 0, 0.75, 1.5
        assert_eq!(robot_samples(&b, &[0], 0.5).expect("one").len(), 1);
    }

    #[test]
    fn stairs_take_the_floor_of_the_nearer_end() {
        let b = building();
        let s = robot_samples(&b, &[1, 2], 1.0).expect("samples");
        let floors: Vec<i64> = s.iter().map(|p| p.floor).collect();
        assert_eq!(floors, vec![0, 0, 0, 1, 1]); // middle (2 m of 4) is the lower floor
    }
}

//! A synthetic radio world: log-distance path loss, wall and floor attenuation, correlated
//! shadowing and measurement noise. It gives the RSS of every access point at any
//! position, which makes it the "synthetic propagation model" world model of SPEC
//! section 5 as well as the source of a generated building's fingerprints.
//!
//! Mean RSS of access point `a` at position `p` (dBm):
//!
//! ```text
//! rss = P0_a - 10 n_a log10(max(d, 1 m)) - wall_loss * walls(a, p)
//!       - floor_loss * |floor(a) - floor(p)| + shadow_{a, floor(p)}(p)
//! ```
//!
//! with `d` the 3-D distance (floors `floor_height` apart) and `walls` the number of wall
//! segments the straight line from the access point to `p` crosses in plan view. The
//! shadowing is a zero-mean, approximately Gaussian random field with the exponential
//! covariance `sigma² exp(-|p - q| / ell)`, one independent field per access point and
//! floor, drawn as random Fourier features: the frequencies of the exponential kernel in
//! two dimensions follow a bivariate Cauchy law (`w = z / (ell |g|)`, `z` a standard normal
//! pair, `g` a standard normal), so the covariance is the exponential kernel in
//! expectation, and the field can be evaluated exactly at any position.
//! A measurement adds `N(0, noise_sigma²)`, is rounded to 0.01 dB, and is "not heard"
//! below the threshold.

use std::collections::BTreeMap;

use rand::Rng;

use super::random::{normal, stream_rng, uniform};
use crate::gp::Point;
use crate::{Error, Result};

/// Number of random Fourier features per shadowing field.
const FEATURES: usize = 256;

/// Parameters of the radio model.
#[derive(Debug, Clone, PartialEq)]
pub struct PropagationParams {
    /// Range of the transmit reference power `P0` at 1 m, dBm (drawn per access point).
    pub p0_dbm: (f64, f64),
    /// Range of the path-loss exponent `n` (drawn per access point).
    pub exponent: (f64, f64),
    /// Loss per wall crossed, dB.
    pub wall_loss_db: f64,
    /// Loss per floor between access point and receiver, dB.
    pub floor_loss_db: f64,
    /// Height of a storey, metres.
    pub floor_height_m: f64,
    /// Standard deviation of the shadowing field, dB.
    pub shadow_sigma_db: f64,
    /// Correlation length of the shadowing field (exponential kernel), metres.
    pub shadow_ell_m: f64,
    /// Standard deviation of the measurement noise, dB.
    pub noise_sigma_db: f64,
    /// Readings below this are "not heard", dBm.
    pub threshold_dbm: f64,
}

impl Default for PropagationParams {
    fn default() -> Self {
        PropagationParams {
            p0_dbm: (-40.0, -30.0),
            exponent: (2.2, 3.2),
            wall_loss_db: 4.0,
            floor_loss_db: 15.0,
            floor_height_m: 3.5,
            shadow_sigma_db: 4.0,
            shadow_ell_m: 6.0,
            noise_sigma_db: 2.0,
            threshold_dbm: -100.0,
        }
    }
}

impl PropagationParams {
    /// Checks every value; errors name the parameter.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, v: f64, what: &str| {
            Err(Error::InvalidRequest(format!(
                "propagation parameter {name} = {v}: {what}"
            )))
        };
        for (name, (lo, hi)) in [("p0_dbm", self.p0_dbm), ("exponent", self.exponent)] {
            if !lo.is_finite() || !hi.is_finite() || lo > hi {
                return bad(name, lo, "range must be finite with low <= high");
            }
        }
        if self.exponent.0 <= 0.0 {
            return bad("exponent", self.exponent.0, "must be positive");
        }
        if let Some((name, v)) = crate::error::first_negative([
            ("wall_loss_db", self.wall_loss_db),
            ("floor_loss_db", self.floor_loss_db),
            ("shadow_sigma_db", self.shadow_sigma_db),
            ("noise_sigma_db", self.noise_sigma_db),
        ]) {
            return bad(name, v, "must be finite and >= 0");
        }
        for (name, v) in [
            ("floor_height_m", self.floor_height_m),
            ("shadow_ell_m", self.shadow_ell_m),
        ] {
            if !v.is_finite() || v <= 0.0 {
                return bad(name, v, "must be finite and > 0");
            }
        }
        if !self.threshold_dbm.is_finite() {
            return bad("threshold_dbm", self.threshold_dbm, "must be finite");
        }
        Ok(())
    }
}

/// An access point of the model.
#[derive(Debug, Clone, PartialEq)]
pub struct AccessPoint {
    pub id: String,
    pub pos: Point,
    /// RSS at 1 m, dBm.
    pub p0_dbm: f64,
    /// Path-loss exponent.
    pub exponent: f64,
}

/// A wall segment in plan view; it stands on every floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    pub a: (f64, f64),
    pub b: (f64, f64),
}

/// One shadowing field: `amp * sum_j cos(w_j . x + b_j)`.
#[derive(Debug, Clone, PartialEq)]
struct Field {
    w: Vec<(f64, f64)>,
    phase: Vec<f64>,
    amp: f64,
}

impl Field {
    fn draw<R: Rng>(rng: &mut R, sigma: f64, ell: f64) -> Self {
        let mut w = Vec::with_capacity(FEATURES);
        let mut phase = Vec::with_capacity(FEATURES);
        for _ in 0..FEATURES {
            let (zx, zy) = (normal(rng), normal(rng));
            // |g| = 0 has probability zero, but keep the frequency finite regardless.
            let g = normal(rng).abs().max(1e-12);
            w.push((zx / (ell * g), zy / (ell * g)));
            phase.push(uniform(rng, 0.0, 2.0 * std::f64::consts::PI));
        }
        Field {
            w,
            phase,
            amp: sigma * libm::sqrt(2.0 / FEATURES as f64),
        }
    }

    fn at(&self, x: f64, y: f64) -> f64 {
        let s: f64 = self
            .w
            .iter()
            .zip(&self.phase)
            .map(|(&(wx, wy), &b)| libm::cos(wx * x + wy * y + b))
            .sum();
        self.amp * s
    }
}

/// The synthetic world: access points, walls and shadowing fields.
#[derive(Debug, Clone, PartialEq)]
pub struct PropagationModel {
    params: PropagationParams,
    aps: Vec<AccessPoint>,
    walls: Vec<Wall>,
    floors: Vec<i64>,
    /// `shadow[a][f]`: field of access point `a` on `floors[f]`.
    shadow: Vec<Vec<Field>>,
}

impl PropagationModel {
    /// Builds the model; the shadowing fields are drawn from `seed` (one field per access
    /// point and floor, in that order).
    pub fn new(
        aps: Vec<AccessPoint>,
        walls: Vec<Wall>,
        floors: &[i64],
        params: PropagationParams,
        seed: u64,
    ) -> Result<Self> {
        params.validate()?;
        let mut rng = stream_rng(seed, super::STREAM_SHADOW);
        let shadow = aps
            .iter()
            .map(|_| {
                floors
                    .iter()
                    .map(|_| Field::draw(&mut rng, params.shadow_sigma_db, params.shadow_ell_m))
                    .collect()
            })
            .collect();
        Ok(PropagationModel {
            params,
            aps,
            walls,
            floors: floors.to_vec(),
            shadow,
        })
    }

    /// The radio parameters.
    pub fn params(&self) -> &PropagationParams {
        &self.params
    }

    /// The access points, in id order as generated.
    pub fn access_points(&self) -> &[AccessPoint] {
        &self.aps
    }

    /// The walls (plan view, on every floor).
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// Number of walls the segment from `a` to `b` crosses (plan view). Touching a wall at
    /// an end point (a door vertex on the wall line) does not count.
    pub fn walls_crossed(&self, a: (f64, f64), b: (f64, f64)) -> usize {
        self.walls
            .iter()
            .filter(|w| segments_cross(a, b, w.a, w.b))
            .count()
    }

    /// Mean (noise-free) RSS of access point `ap` at `p`, dBm; may be below the threshold.
    pub fn mean_rss(&self, ap: usize, p: &Point) -> f64 {
        let a = &self.aps[ap];
        let prm = &self.params;
        let floors_apart = (a.pos.floor - p.floor).unsigned_abs() as f64;
        let dz = floors_apart * prm.floor_height_m;
        let dx = p.x - a.pos.x;
        let dy = p.y - a.pos.y;
        let d = libm::sqrt(dx * dx + dy * dy + dz * dz).max(1.0);
        let walls = self.walls_crossed((a.pos.x, a.pos.y), (p.x, p.y)) as f64;
        let shadow = self
            .floors
            .iter()
            .position(|&f| f == p.floor)
            .map_or(0.0, |f| self.shadow[ap][f].at(p.x, p.y));
        a.p0_dbm
            - 10.0 * a.exponent * libm::log10(d)
            - prm.wall_loss_db * walls
            - prm.floor_loss_db * floors_apart
            + shadow
    }

    /// Mean RSS of every access point at `p`, in access-point order.
    pub fn mean_rss_all(&self, p: &Point) -> Vec<f64> {
        (0..self.aps.len()).map(|a| self.mean_rss(a, p)).collect()
    }

    /// One noisy measurement at `p`: mean plus noise, rounded to 0.01 dB, saturating at
    /// 0 dBm (a receiver reports no more), access points below the threshold or below
    /// -120 dBm left out: every value lies in the range building files accept (SPEC 7).
    /// Draws exactly one normal per access point.
    pub fn measure<R: Rng>(&self, p: &Point, rng: &mut R) -> BTreeMap<String, f64> {
        use crate::building::{MAX_RSS_DBM, MIN_RSS_DBM};
        let mut out = BTreeMap::new();
        for (i, a) in self.aps.iter().enumerate() {
            let v = self.mean_rss(i, p) + self.params.noise_sigma_db * normal(rng);
            let v = ((v * 100.0).round() / 100.0).min(MAX_RSS_DBM);
            if v >= self.params.threshold_dbm && v >= MIN_RSS_DBM {
                out.insert(a.id.clone(), v);
            }
        }
        out
    }
}

/// Whether segment `p1 p2` crosses segment `q1 q2` at a point strictly inside `p1 p2`.
fn segments_cross(p1: (f64, f64), p2: (f64, f64), q1: (f64, f64), q2: (f64, f64)) -> bool {
    let r = (p2.0 - p1.0, p2.1 - p1.1);
    let s = (q2.0 - q1.0, q2.1 - q1.1);
    let den = r.0 * s.1 - r.1 * s.0;
    if den.abs() < 1e-12 {
        return false; // parallel or collinear: running along a wall is not crossing it
    }
    let qp = (q1.0 - p1.0, q1.1 - p1.1);
    let t = (qp.0 * s.1 - qp.1 * s.0) / den;
    let u = (qp.0 * r.1 - qp.1 * r.0) / den;
    const EPS: f64 = 1e-9;
    t > EPS && t < 1.0 - EPS && (-EPS..=1.0 + EPS).contains(&u)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(shadow: f64) -> PropagationModel {
        let params = PropagationParams {
            shadow_sigma_db: shadow,
            ..PropagationParams::default()
        };
        PropagationModel::new(
            vec![AccessPoint {
                id: "ap-01".into(),
                pos: Point::new(0.0, 0.0, 0),
                p0_dbm: -35.0,
                exponent: 2.0,
            }],
            vec![Wall {
                a: (5.0, -10.0),
                b: (5.0, 10.0),
            }],
            &[0, 1],
            params,
            3,
        )
        .expect("valid")
    }

    #[test]
    fn path_loss_walls_and_floors() {
        let m = model(0.0);
        // 10 m away, one wall: -35 - 20 - 4.
        let v = m.mean_rss(0, &Point::new(10.0, 0.0, 0));
        assert!((v - (-35.0 - 20.0 - 4.0)).abs() < 1e-9, "{v}");
        // Within 1 m: P0.
        assert!((m.mean_rss(0, &Point::new(0.5, 0.0, 0)) + 35.0).abs() < 1e-9);
        // One floor up, straight above: 3.5 m and 15 dB.
        let up = m.mean_rss(0, &Point::new(0.0, 0.0, 1));
        let expect = -35.0 - 20.0 * 3.5f64.log10() - 15.0;
        assert!((up - expect).abs() < 1e-9, "{up} vs {expect}");
        assert_eq!(
            m.walls_crossed((0.0, 0.0), (5.0, 0.0)),
            0,
            "ending on a wall"
        );
        assert_eq!(m.walls_crossed((0.0, 0.0), (4.0, 20.0)), 0);
    }

    #[test]
    fn shadowing_has_the_exponential_covariance_roughly() {
        // Average over many independent fields: variance sigma² at lag 0, and
        // sigma² exp(-h/ell) at lag h.
        let (sigma, ell) = (4.0, 6.0);
        let mut rng = stream_rng(11, 0);
        let lags = [0.0, 3.0, 6.0, 12.0];
        let mut acc = [0.0; 4];
        let n = 400;
        for _ in 0..n {
            let f = Field::draw(&mut rng, sigma, ell);
            let f0 = f.at(1.0, 2.0);
            for (i, h) in lags.iter().enumerate() {
                acc[i] += f0 * f.at(1.0 + h, 2.0);
            }
        }
        for (i, h) in lags.iter().enumerate() {
            let cov = acc[i] / n as f64;
            let expect = sigma * sigma * (-h / ell).exp();
            assert!(
                (cov - expect).abs() < 0.2 * sigma * sigma,
                "lag {h}: {cov} vs {expect}"
            );
        }
    }

    #[test]
    fn measurement_is_thresholded_and_deterministic() {
        let m = model(4.0);
        let far = Point::new(3000.0, 0.0, 0);
        assert!(m.measure(&far, &mut stream_rng(1, 0)).is_empty());
        let p = Point::new(3.0, 1.0, 0);
        let a = m.measure(&p, &mut stream_rng(1, 0));
        let b = m.measure(&p, &mut stream_rng(1, 0));
        assert_eq!(a, b);
        assert_eq!(a.len(), 1);
    }

    #[test]
    fn measurements_stay_in_the_rss_range_of_building_files() {
        // An access point far louder than any real one, and a threshold below -120 dBm.
        let params = PropagationParams {
            threshold_dbm: -300.0,
            ..PropagationParams::default()
        };
        let m = PropagationModel::new(
            vec![AccessPoint {
                id: "ap-01".into(),
                pos: Point::new(0.0, 0.0, 0),
                p0_dbm: 30.0,
                exponent: 4.0,
            }],
            vec![],
            &[0],
            params,
            3,
        )
        .expect("valid");
        let near = m.measure(&Point::new(0.5, 0.0, 0), &mut stream_rng(1, 0));
        assert_eq!(near.get("ap-01"), Some(&0.0), "saturates at 0 dBm");
        let far = m.measure(&Point::new(1e6, 0.0, 0), &mut stream_rng(1, 0));
        assert!(far.is_empty(), "below -120 dBm is not heard: {far:?}");
    }
}

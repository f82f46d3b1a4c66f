//! The exponential covariance kernel of SPEC section 2.

use serde::{Deserialize, Serialize};

/// A position in the building: metres on one floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    pub floor: i64,
}

impl Point {
    pub fn new(x: f64, y: f64, floor: i64) -> Self {
        Point { x, y, floor }
    }

    /// Euclidean distance in the plane (ignores floors).
    pub fn planar_distance(&self, other: &Point) -> f64 {
        (self.x - other.x).hypot(self.y - other.y)
    }

    /// The point of the segment `a b` nearest to this one, in the plane (floors ignored):
    /// its fraction `t` of the way from `a` (in `[0, 1]`; 0 for a zero-length segment) and
    /// the distance to it.
    pub fn segment_projection(&self, a: &Point, b: &Point) -> (f64, f64) {
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let l2 = dx * dx + dy * dy;
        let t = if l2 > 0.0 {
            (((self.x - a.x) * dx + (self.y - a.y) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (t, (self.x - (a.x + t * dx)).hypot(self.y - (a.y + t * dy)))
    }
}

/// The smallest axis-aligned rectangle that holds some points, metres: the extent of a
/// floor's vertices, a walk's samples or a floor plan, for grids, drawings and quick
/// tests of nearness. Empty (no point added) it has `x0 > x1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extent {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl Extent {
    /// The extent of no point.
    pub const EMPTY: Extent = Extent {
        x0: f64::INFINITY,
        y0: f64::INFINITY,
        x1: f64::NEG_INFINITY,
        y1: f64::NEG_INFINITY,
    };

    /// The extent of `points` (`(x, y)` pairs).
    pub fn of(points: impl IntoIterator<Item = (f64, f64)>) -> Extent {
        let mut e = Extent::EMPTY;
        for (x, y) in points {
            e.add(x, y);
        }
        e
    }

    /// Grows the extent to hold `(x, y)`.
    #[inline]
    pub fn add(&mut self, x: f64, y: f64) {
        self.x0 = self.x0.min(x);
        self.y0 = self.y0.min(y);
        self.x1 = self.x1.max(x);
        self.y1 = self.y1.max(y);
    }

    /// Whether no point was added.
    pub fn is_empty(&self) -> bool {
        !(self.x0 <= self.x1 && self.y0 <= self.y1)
    }

    /// The extent widened by `m` metres on every side.
    pub fn widened(&self, m: f64) -> Extent {
        Extent {
            x0: self.x0 - m,
            y0: self.y0 - m,
            x1: self.x1 + m,
            y1: self.y1 + m,
        }
    }

    /// Whether `(x, y)` lies inside or on the border.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x >= self.x0 && y >= self.y0 && x <= self.x1 && y <= self.y1
    }

    /// The squared distance from `(x, y)` to the rectangle (0 inside).
    #[inline]
    pub fn distance2(&self, x: f64, y: f64) -> f64 {
        let dx = (self.x0 - x).max(x - self.x1).max(0.0);
        let dy = (self.y0 - y).max(y - self.y1).max(0.0);
        dx * dx + dy * dy
    }

    /// The length of its diagonal.
    pub fn diagonal(&self) -> f64 {
        (self.x1 - self.x0).hypot(self.y1 - self.y0)
    }
}

/// Hyperparameters `(sf2, ell, sn2)` of `k(p, q) = sf2 * exp(-|p - q| / ell)` with
/// observation noise `sn2`. Points on different floors are independent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Kernel {
    /// Signal variance, dB².
    pub sf2: f64,
    /// Length scale, metres.
    pub ell: f64,
    /// Observation noise variance, dB².
    pub sn2: f64,
}

impl Kernel {
    pub fn new(sf2: f64, ell: f64, sn2: f64) -> Self {
        Kernel { sf2, ell, sn2 }
    }

    /// Checks that all three values are finite and positive; `what` names the source in
    /// the error (for example `--kernel` or `kernel` of a building file).
    pub fn validate(&self, what: &str) -> crate::Result<()> {
        for (name, v) in [("sf2", self.sf2), ("ell", self.ell), ("sn2", self.sn2)] {
            if !v.is_finite() || v <= 0.0 {
                return Err(crate::Error::InvalidRequest(format!(
                    "{what}: {name} must be a finite positive number, got {v}"
                )));
            }
        }
        Ok(())
    }

    /// Covariance of the latent function at `p` and `q` (no noise).
    #[inline]
    pub fn k(&self, p: &Point, q: &Point) -> f64 {
        if p.floor != q.floor {
            return 0.0;
        }
        self.sf2 * (-p.planar_distance(q) / self.ell).exp()
    }

    /// The extra label noise of a sample whose position label has a Gaussian error of
    /// standard deviation `s` metres (SPEC section 4): the variance of
    /// `f(p + delta) - f(p)` for `delta ~ N(0, s^2)`.
    ///
    /// `x = 2 sf2 (1 - exp(s²/(2 ell²)) erfc(s / (ell sqrt 2)))`, computed through the scaled
    /// complementary error function so that it stays finite for any `s`.
    pub fn label_noise(&self, s: f64) -> f64 {
        if s <= 0.0 {
            return 0.0;
        }
        let z = s / (self.ell * std::f64::consts::SQRT_2);
        2.0 * self.sf2 * (1.0 - erfcx(z))
    }
}

/// Scaled complementary error function `exp(z²) erfc(z)` for `z >= 0`.
pub fn erfcx(z: f64) -> f64 {
    if z < 25.0 {
        // exp(625) and erfc(25) ~ 1e-274 are both comfortably inside f64's range.
        (z * z).exp() * libm::erfc(z)
    } else {
        // Asymptotic series; at z >= 25 the first omitted term is below 1e-12 relative.
        let t = 1.0 / (2.0 * z * z);
        (1.0 - t * (1.0 - 3.0 * t * (1.0 - 5.0 * t * (1.0 - 7.0 * t))))
            / (z * std::f64::consts::PI.sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_is_zero_across_floors_and_sf2_at_zero_distance() {
        let k = Kernel::new(40.0, 6.0, 9.0);
        let p = Point::new(1.0, 2.0, 0);
        assert_eq!(k.k(&p, &p), 40.0);
        assert_eq!(k.k(&p, &Point::new(1.0, 2.0, 1)), 0.0);
        let q = Point::new(4.0, 6.0, 0);
        assert!((k.k(&p, &q) - 40.0 * (-5.0f64 / 6.0).exp()).abs() < 1e-12);
    }

    #[test]
    fn label_noise_is_zero_at_zero_and_grows_towards_twice_sf2() {
        let k = Kernel::new(10.0, 5.0, 1.0);
        assert_eq!(k.label_noise(0.0), 0.0);
        let mut last = 0.0;
        for i in 1..200 {
            let x = k.label_noise(i as f64 * 0.5);
            assert!(x > last, "label noise must grow with s");
            assert!(x < 20.0);
            last = x;
        }
        // Far beyond the length scale the two positions are independent: 2 sf2.
        assert!((k.label_noise(1e6) - 20.0).abs() < 1e-3);
        // Small s: f(p+d)-f(p) has variance ~ 2 sf2 * E|d| / ell = 2 sf2 s sqrt(2/pi) / ell.
        let s = 1e-4;
        let approx = 2.0 * 10.0 * s * (2.0 / std::f64::consts::PI).sqrt() / 5.0;
        assert!((k.label_noise(s) - approx).abs() / approx < 1e-3);
    }

    #[test]
    fn erfcx_is_continuous_at_the_switch() {
        let z = 25.0f64 - 1e-12;
        let a = (z * z).exp() * libm::erfc(z);
        assert!((erfcx(25.0) - a).abs() / a < 1e-11);
    }

    #[test]
    fn an_extent_holds_its_points_and_measures_the_way_to_it() {
        assert!(Extent::of([]).is_empty());
        let e = Extent::of([(1.0, 2.0), (4.0, -2.0), (3.0, 6.0)]);
        assert_eq!((e.x0, e.y0, e.x1, e.y1), (1.0, -2.0, 4.0, 6.0));
        assert!(!e.is_empty() && e.contains(1.0, 6.0) && !e.contains(0.99, 0.0));
        assert_eq!(e.diagonal(), 3.0f64.hypot(8.0));
        // Inside: 0; beside an edge: the gap squared; beyond a corner: both gaps.
        assert_eq!(e.distance2(2.0, 0.0), 0.0);
        assert_eq!(e.distance2(7.0, 0.0), 9.0);
        assert_eq!(e.distance2(-2.0, 10.0), 9.0 + 16.0);
        let w = e.widened(1.0);
        assert_eq!((w.x0, w.y0, w.x1, w.y1), (0.0, -3.0, 5.0, 7.0));
        assert!(w.contains(0.0, 7.0) && !e.contains(0.0, 7.0));
    }
}

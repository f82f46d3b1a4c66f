//! The local tangent plane of a building: WGS84 longitude and latitude to metres east and
//! north of an origin, and back.
//!
//! At building size (a few hundred metres) an equirectangular projection with the WGS84
//! radii of curvature at the origin's latitude is exact to well under a centimetre: the
//! error grows with the square of the distance over the Earth's radius.

use crate::building::GeoOrigin;

/// WGS84 semi-major axis, metres.
const A: f64 = 6_378_137.0;
/// WGS84 first eccentricity squared.
const E2: f64 = 6.694_379_990_14e-3;

/// A local east-north frame at a WGS84 origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    origin: GeoOrigin,
    /// Metres per degree of latitude (meridional radius of curvature).
    m_per_deg_lat: f64,
    /// Metres per degree of longitude (prime-vertical radius times cos(latitude)).
    m_per_deg_lon: f64,
}

impl LocalFrame {
    /// The frame whose origin is `origin`.
    pub fn new(origin: GeoOrigin) -> Self {
        let phi = origin.lat.to_radians();
        let w = (1.0 - E2 * phi.sin().powi(2)).sqrt();
        let meridional = A * (1.0 - E2) / (w * w * w);
        let prime_vertical = A / w;
        let deg = std::f64::consts::PI / 180.0;
        LocalFrame {
            origin,
            m_per_deg_lat: meridional * deg,
            m_per_deg_lon: prime_vertical * phi.cos() * deg,
        }
    }

    /// The origin.
    pub fn origin(&self) -> GeoOrigin {
        self.origin
    }

    /// Metres east and north of the origin.
    pub fn to_local(&self, lon: f64, lat: f64) -> (f64, f64) {
        (
            (lon - self.origin.lon) * self.m_per_deg_lon,
            (lat - self.origin.lat) * self.m_per_deg_lat,
        )
    }

    /// Longitude and latitude (degrees) of a point `x` metres east and `y` north.
    pub fn to_wgs84(&self, x: f64, y: f64) -> (f64, f64) {
        (
            self.origin.lon + x / self.m_per_deg_lon,
            self.origin.lat + y / self.m_per_deg_lat,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_scale() {
        let f = LocalFrame::new(GeoOrigin {
            lat: 48.8763,
            lon: 2.3591,
        });
        let (x, y) = f.to_local(2.3601, 48.8773);
        // 0.001 degree of latitude is about 111.2 m at 49 N; of longitude about 73.3 m.
        assert!((y - 111.2).abs() < 0.2, "{y}");
        assert!((x - 73.3).abs() < 0.2, "{x}");
        let (lon, lat) = f.to_wgs84(x, y);
        assert!((lon - 2.3601).abs() < 1e-12 && (lat - 48.8773).abs() < 1e-12);
    }
}

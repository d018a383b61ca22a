//! WGS-84 geodetic to local NED around an anchor (the first valid fix).
//!
//! Flat-earth tangent plane with the ellipsoid's meridian and prime-vertical
//! radii at the anchor: under 1 cm error per km of distance, which is below
//! GPS noise for any UAV flight area.

use serde::{Deserialize, Serialize};
use nalgebra::Vector3;

use crate::sample::Sample;

const A: f64 = 6_378_137.0; // WGS-84 semi-major axis, m
const E2: f64 = 6.694_379_990_14e-3; // first eccentricity squared

/// Local frame origin.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Anchor {
    /// Geodetic origin (deg, deg, m), or None when the log gives NED directly.
    pub lla: Option<(f64, f64, f64)>,
    /// Metres per radian of latitude / longitude at the anchor.
    rn: f64,
    re: f64,
}

impl Anchor {
    /// The tangent frame at latitude, longitude (deg) and altitude (m).
    pub fn at(lat: f64, lon: f64, alt: f64) -> Self {
        let phi = lat.to_radians();
        let s = libm::sin(phi);
        let w = (1.0 - E2 * s * s).sqrt();
        let rm = A * (1.0 - E2) / (w * w * w); // meridian radius
        let rp = A / w; // prime vertical radius
        Anchor { lla: Some((lat, lon, alt)), rn: rm + alt, re: (rp + alt) * libm::cos(phi) }
    }

    /// Anchor from a row with a fix (lat/lon/alt preferred over pn/pe/pd).
    pub fn from_sample(s: &Sample) -> Self {
        if s.lat.is_finite() && s.lon.is_finite() && s.alt.is_finite() {
            Anchor::at(s.lat, s.lon, s.alt)
        } else {
            Anchor { lla: None, rn: 0.0, re: 0.0 }
        }
    }

    /// NED position (m) of a geodetic point.
    pub fn lla_to_ned(&self, lat: f64, lon: f64, alt: f64) -> Vector3<f64> {
        match self.lla {
            Some((lat0, lon0, alt0)) => {
                let mut dlon = lon - lon0;
                // Wrap across the antimeridian.
                if dlon > 180.0 {
                    dlon -= 360.0;
                } else if dlon < -180.0 {
                    dlon += 360.0;
                }
                Vector3::new((lat - lat0).to_radians() * self.rn, dlon.to_radians() * self.re, alt0 - alt)
            }
            None => Vector3::new(f64::NAN, f64::NAN, f64::NAN),
        }
    }

    /// NED position of a row with a fix.
    pub fn to_ned(&self, s: &Sample) -> Vector3<f64> {
        if self.lla.is_some() && s.lat.is_finite() && s.lon.is_finite() && s.alt.is_finite() {
            self.lla_to_ned(s.lat, s.lon, s.alt)
        } else if s.pn.is_finite() {
            Vector3::new(s.pn, s.pe, s.pd)
        } else {
            // lat/lon row after a pn/pe/pd anchor: cannot mix frames.
            Vector3::new(s.pn, s.pe, s.pd)
        }
    }

    /// Inverse of [`Anchor::lla_to_ned`].
    pub fn ned_to_lla(&self, p: &Vector3<f64>) -> Option<(f64, f64, f64)> {
        let (lat0, lon0, alt0) = self.lla?;
        Some((lat0 + (p[0] / self.rn).to_degrees(), lon0 + (p[1] / self.re).to_degrees(), alt0 - p[2]))
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    #[test]
    fn one_arcsecond_at_the_equator() {
        // 1" of latitude ≈ 30.715 m, of longitude ≈ 30.922 m at the equator (WGS-84).
        let a = Anchor::at(0.0, 0.0, 0.0);
        let p = a.lla_to_ned(1.0 / 3600.0, 1.0 / 3600.0, 10.0);
        assert_abs_diff_eq!(p[0], 30.715, epsilon = 0.01);
        assert_abs_diff_eq!(p[1], 30.922, epsilon = 0.01);
        assert_abs_diff_eq!(p[2], -10.0);
    }

    #[test]
    fn round_trip_at_mid_latitude() {
        let a = Anchor::at(47.3977, 8.5456, 488.0);
        let p = Vector3::new(812.5, -431.25, -55.0);
        let (la, lo, al) = a.ned_to_lla(&p).unwrap();
        let q = a.lla_to_ned(la, lo, al);
        assert_abs_diff_eq!((p - q).norm(), 0.0, epsilon = 1e-6);
        // 0.001° of longitude at 47.4° ≈ 75.4 m.
        assert_abs_diff_eq!(a.lla_to_ned(47.3977, 8.5466, 488.0)[1], 75.45, epsilon = 0.1);
    }
}

/// The snapshot codec of this file's state types ([`crate::codec`]): each
/// struct's fields in declaration order (a field left out does not compile;
/// `skip`: not saved, rebuilt on restore).
mod codec_impls {
    use super::*;
    use crate::codec::impl_codec;

    impl_codec!(Anchor { lla, rn, re });
}

//! GPS-like satellite constellation, the local site frame, visibility and DOP.
//!
//! Circular MEO orbits (radius 26 559.7 km, inclination 55°) in 6 planes
//! 60° apart in right ascension, 24–31 satellites. Positions are computed in
//! an Earth-centred inertial frame and rotated into ECEF by the Earth rotation
//! angle; the receiver works in a NED tangent frame fixed at the site (a rigid
//! transform of ECEF, so ranges are preserved exactly). Signal travel time and
//! the Sagnac term are not modelled: the simulator and the filter share this
//! geometry, so leaving them out introduces no model error.

use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use super::TightError;

/// Earth gravitational parameter, m³/s².
pub const MU: f64 = 3.986_004_418e14;
/// Earth rotation rate, rad/s.
pub const OMEGA_E: f64 = 7.292_115_146_7e-5;
/// GPS orbit radius, m (semi-major axis of a 11 h 58 min orbit).
pub const ORBIT_RADIUS: f64 = 26_559_700.0;
/// GPS orbit inclination, rad (55°).
pub const INCLINATION: f64 = 55.0 * core::f64::consts::PI / 180.0;
const WGS84_A: f64 = 6_378_137.0;
const WGS84_E2: f64 = 6.694_379_990_14e-3;

/// One circular orbit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Orbit {
    /// Satellite id (1-based, like a GPS PRN).
    pub prn: u8,
    /// Right ascension of the ascending node, rad.
    pub raan: f64,
    /// Inclination, rad.
    pub inclination: f64,
    /// Orbit radius, m.
    pub radius: f64,
    /// Argument of latitude at t = 0, rad.
    pub phase0: f64,
}

impl Orbit {
    /// ECEF position (m) at time `t` (s since the constellation epoch).
    pub fn position_ecef(&self, t: f64) -> Vector3<f64> {
        let n = libm::sqrt(MU / (self.radius * self.radius * self.radius));
        let u = self.phase0 + n * t;
        let (su, cu) = (libm::sin(u), libm::cos(u));
        let (so, co) = (libm::sin(self.raan), libm::cos(self.raan));
        let (si, ci) = (libm::sin(self.inclination), libm::cos(self.inclination));
        let r = self.radius;
        let x = r * (cu * co - su * ci * so);
        let y = r * (cu * so + su * ci * co);
        let z = r * su * si;
        // ECI -> ECEF: rotate by the Earth rotation angle.
        let th = OMEGA_E * t;
        let (st, ct) = (libm::sin(th), libm::cos(th));
        Vector3::new(ct * x + st * y, -st * x + ct * y, z)
    }
}

/// A set of orbits.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Constellation {
    /// One orbit per satellite, in PRN order.
    pub orbits: Vec<Orbit>,
}

impl Constellation {
    /// `n` satellites (24..=31) in 6 planes: plane k holds `n/6` satellites,
    /// one more for the first `n % 6` planes; slots are evenly spaced and
    /// successive planes are offset by 15° so that planes do not align.
    pub fn gps_like(n: usize) -> Result<Self, TightError> {
        if !(24..=31).contains(&n) {
            return Err(TightError::new("n_sats", format!("must be 24..=31, got {n}")));
        }
        let two_pi = 2.0 * core::f64::consts::PI;
        let mut orbits = Vec::with_capacity(n);
        let mut prn = 1u8;
        for k in 0..6 {
            let m = n / 6 + usize::from(k < n % 6);
            for j in 0..m {
                orbits.push(Orbit {
                    prn,
                    raan: two_pi * k as f64 / 6.0,
                    inclination: INCLINATION,
                    radius: ORBIT_RADIUS,
                    phase0: two_pi * j as f64 / m as f64 + k as f64 * 15f64.to_radians(),
                });
                prn += 1;
            }
        }
        Ok(Constellation { orbits })
    }

    /// The orbit of a PRN.
    pub fn orbit(&self, prn: u8) -> Option<&Orbit> {
        self.orbits.iter().find(|o| o.prn == prn)
    }

    /// Satellite positions in the site's NED frame (m) at time `t`.
    pub fn positions_ned(&self, site: &Site, t: f64) -> Vec<(u8, Vector3<f64>)> {
        self.orbits.iter().map(|o| (o.prn, site.ecef_to_ned(&o.position_ecef(t)))).collect()
    }

    /// Satellites above `mask` (rad) seen from NED point `p` at time `t`,
    /// highest first.
    pub fn visible(&self, site: &Site, p: &Vector3<f64>, t: f64, mask: f64) -> Vec<SatView> {
        let mut v: Vec<SatView> = self
            .positions_ned(site, t)
            .into_iter()
            .filter_map(|(prn, s)| {
                let (el, az) = elevation_azimuth(p, &s);
                (el >= mask).then_some(SatView { prn, elevation: el, azimuth: az, pos_ned: s })
            })
            .collect();
        v.sort_by(|a, b| b.elevation.total_cmp(&a.elevation));
        v
    }
}

/// A visible satellite.
#[derive(Clone, Debug, PartialEq)]
pub struct SatView {
    /// Satellite id.
    pub prn: u8,
    /// Elevation above the local horizontal, rad.
    pub elevation: f64,
    /// Azimuth from north towards east, rad.
    pub azimuth: f64,
    /// Satellite position in the site NED frame, m.
    pub pos_ned: Vector3<f64>,
}

/// The receiver site: origin of the NED navigation frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Site {
    /// Geodetic latitude, longitude (deg) and ellipsoidal height (m).
    pub lla: (f64, f64, f64),
    /// Site position in ECEF, m.
    pub ecef: Vector3<f64>,
    /// Rotation ECEF -> NED.
    pub c_ne: Matrix3<f64>,
}

impl Site {
    /// The site at latitude, longitude (deg) and altitude (m); an error names a bad value.
    pub fn new(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Result<Self, TightError> {
        if !(lat_deg.is_finite() && (-90.0..=90.0).contains(&lat_deg)) {
            return Err(TightError::new("lat", format!("must be in [-90, 90] deg, got {lat_deg}")));
        }
        if !(lon_deg.is_finite() && (-180.0..=360.0).contains(&lon_deg)) {
            return Err(TightError::new("lon", format!("must be in [-180, 360] deg, got {lon_deg}")));
        }
        if !(alt_m.is_finite() && alt_m.abs() < 1.0e5) {
            return Err(TightError::new("alt", format!("must be finite and |alt| < 100 km, got {alt_m}")));
        }
        let (phi, lam) = (lat_deg.to_radians(), lon_deg.to_radians());
        let (sp, cp, sl, cl) = (libm::sin(phi), libm::cos(phi), libm::sin(lam), libm::cos(lam));
        let rn = WGS84_A / libm::sqrt(1.0 - WGS84_E2 * sp * sp);
        let ecef = Vector3::new((rn + alt_m) * cp * cl, (rn + alt_m) * cp * sl, (rn * (1.0 - WGS84_E2) + alt_m) * sp);
        #[rustfmt::skip]
        let c_ne = Matrix3::new(
            -sp * cl, -sp * sl,  cp,
            -sl,       cl,       0.0,
            -cp * cl, -cp * sl, -sp,
        );
        Ok(Site { lla: (lat_deg, lon_deg, alt_m), ecef, c_ne })
    }

    /// ECEF position (m) to the site's NED frame (m).
    pub fn ecef_to_ned(&self, e: &Vector3<f64>) -> Vector3<f64> {
        self.c_ne * (e - self.ecef)
    }

    /// Site NED position (m) to ECEF (m).
    pub fn ned_to_ecef(&self, n: &Vector3<f64>) -> Vector3<f64> {
        self.c_ne.transpose() * n + self.ecef
    }
}

/// Elevation and azimuth (rad) of satellite `s` seen from `p` (both NED, m).
/// Uses the site's vertical: for a UAV within tens of km of the site the
/// difference from the local vertical is below 0.5°.
pub fn elevation_azimuth(p: &Vector3<f64>, s: &Vector3<f64>) -> (f64, f64) {
    let d = s - p;
    let r = d.norm();
    if r <= 0.0 {
        return (0.0, 0.0);
    }
    (libm::asin(-d[2] / r), libm::atan2(d[1], d[0]))
}

/// Dilution of precision.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dop {
    /// Geometric DOP.
    pub gdop: f64,
    /// Position DOP.
    pub pdop: f64,
    /// Horizontal DOP.
    pub hdop: f64,
    /// Vertical DOP.
    pub vdop: f64,
    /// Time DOP.
    pub tdop: f64,
}

/// DOP from receiver-to-satellite unit vectors (geometry rows `[u', 1]`);
/// `None` with fewer than 4 satellites or a singular geometry.
pub fn dop(los: &[Vector3<f64>]) -> Option<Dop> {
    if los.len() < 4 {
        return None;
    }
    let mut gtg = Matrix4::<f64>::zeros();
    for u in los {
        let g = Vector4::new(u[0], u[1], u[2], 1.0);
        gtg += g * g.transpose();
    }
    let q = gtg.try_inverse()?;
    let d = |i: usize| q[(i, i)];
    if (0..4).any(|i| !(d(i) > 0.0 && d(i).is_finite())) || d(0) + d(1) + d(2) > 1.0e8 {
        return None;
    }
    Some(Dop {
        gdop: libm::sqrt(d(0) + d(1) + d(2) + d(3)),
        pdop: libm::sqrt(d(0) + d(1) + d(2)),
        hdop: libm::sqrt(d(0) + d(1)),
        vdop: libm::sqrt(d(2)),
        tdop: libm::sqrt(d(3)),
    })
}

/// Unit vectors from `p` to each satellite.
pub fn los_vectors(p: &Vector3<f64>, sats: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    sats.iter().map(|s| (s - p) / (s - p).norm()).collect()
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn site() -> Site {
        Site::new(31.94, 118.79, 20.0).unwrap()
    }

    #[test]
    fn orbit_radius_and_period() {
        let c = Constellation::gps_like(27).unwrap();
        assert_eq!(c.orbits.len(), 27);
        let o = &c.orbits[0];
        // Inertial radius is constant; ECEF norm equals it (rotation about z).
        for t in [0.0, 1000.0, 20000.0] {
            assert_relative_eq!(o.position_ecef(t).norm(), ORBIT_RADIUS, max_relative = 1e-12);
        }
        // Period 2π sqrt(a³/μ) ≈ 11 h 58 min.
        let period = 2.0 * core::f64::consts::PI * (ORBIT_RADIUS.powi(3) / MU).sqrt();
        assert!((period - 43_080.0).abs() < 60.0, "period {period}");
        // Satellite speed ≈ 3.87 km/s in inertial space.
        let v = 2.0 * core::f64::consts::PI * ORBIT_RADIUS / period;
        assert_relative_eq!(v, 3874.0, epsilon = 5.0);
    }

    #[test]
    fn plane_sizes() {
        assert!(Constellation::gps_like(23).is_err());
        assert!(Constellation::gps_like(32).is_err());
        for n in 24..=31 {
            let c = Constellation::gps_like(n).unwrap();
            assert_eq!(c.orbits.len(), n);
            let planes: std::collections::BTreeSet<u64> = c.orbits.iter().map(|o| o.raan.to_bits()).collect();
            assert_eq!(planes.len(), 6);
        }
    }

    #[test]
    fn site_frame_round_trip() {
        let s = site();
        assert_relative_eq!(s.ecef_to_ned(&s.ecef).norm(), 0.0, epsilon = 1e-9);
        let p = Vector3::new(1234.0, -567.0, -89.0);
        assert_relative_eq!(s.ecef_to_ned(&s.ned_to_ecef(&p)), p, epsilon = 1e-6);
        // Zenith direction in ECEF maps to -down.
        let up = s.ecef / s.ecef.norm();
        let n = s.c_ne * up;
        assert!(n[2] < -0.99, "{n}");
    }

    #[test]
    fn visible_counts_are_gps_like() {
        // 31 satellites: 6..=12 above 10° at any time, about 8.5 on average
        // (roughly 28 % of a MEO constellation is above a 10° mask).
        let c = Constellation::gps_like(31).unwrap();
        let s = site();
        let p = Vector3::zeros();
        let mut total = 0usize;
        let mut n_epochs = 0usize;
        for k in 0..144 {
            let t = k as f64 * 600.0;
            let v = c.visible(&s, &p, t, 10f64.to_radians());
            assert!((6..=12).contains(&v.len()), "t={t}: {} visible", v.len());
            // Higher mask, fewer satellites.
            let v30 = c.visible(&s, &p, t, 30f64.to_radians());
            assert!(v30.len() <= v.len());
            // Sorted by elevation, all above the mask.
            assert!(v.windows(2).all(|w| w[0].elevation >= w[1].elevation));
            assert!(v.iter().all(|x| x.elevation >= 10f64.to_radians()));
            total += v.len();
            n_epochs += 1;
        }
        let mean = total as f64 / n_epochs as f64;
        assert!((7.5..=10.0).contains(&mean), "mean visible {mean}");
    }

    #[test]
    fn pdop_sanity() {
        // Hand case: 3 satellites on the horizon 120° apart plus one at zenith.
        let s30 = 3f64.sqrt() / 2.0;
        let los = vec![
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(-0.5, s30, 0.0),
            Vector3::new(-0.5, -s30, 0.0),
            Vector3::new(0.0, 0.0, -1.0),
        ];
        let d = dop(&los).unwrap();
        // G'G = diag(1.5, 1.5, 1, 4) + coupling between z and clock (z=-1, clk=1):
        // the z/clock block is [[1,-1],[-1,4]], inverse [[4,1],[1,1]]/3.
        assert_relative_eq!(d.hdop, (2.0 / 1.5f64).sqrt(), epsilon = 1e-12);
        assert_relative_eq!(d.vdop, (4.0f64 / 3.0).sqrt(), epsilon = 1e-12);
        assert_relative_eq!(d.tdop, (1.0f64 / 3.0).sqrt(), epsilon = 1e-12);
        assert_relative_eq!(d.pdop, (2.0 / 1.5 + 4.0 / 3.0f64).sqrt(), epsilon = 1e-12);
        // Fewer than 4 or coplanar with the clock column: no DOP.
        assert!(dop(&los[..3]).is_none());
        let flat = vec![Vector3::new(1.0, 0.0, 0.0); 5];
        assert!(dop(&flat).is_none());
        // Real sky: PDOP of all satellites above 10° is between 1 and 5, and
        // dropping satellites never improves it.
        let c = Constellation::gps_like(31).unwrap();
        let s = site();
        for k in 0..48 {
            let t = k as f64 * 1800.0;
            let v = c.visible(&s, &Vector3::zeros(), t, 10f64.to_radians());
            let sats: Vec<_> = v.iter().map(|x| x.pos_ned).collect();
            let all = dop(&los_vectors(&Vector3::zeros(), &sats)).unwrap();
            assert!(all.pdop > 1.0 && all.pdop < 5.0, "t={t} pdop {}", all.pdop);
            let fewer = dop(&los_vectors(&Vector3::zeros(), &sats[..sats.len() - 1])).unwrap();
            assert!(fewer.pdop >= all.pdop - 1e-12);
        }
    }
}

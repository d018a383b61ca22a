//! One row of a navigation log: the contract's navlog CSV columns (§1).
//!
//! Every field is `f64` and `NaN` means "absent in this row", the same
//! convention as the columnar JS API, so a row costs no allocation.

use crate::decimal::Shortest;

/// A navlog row. Units follow the contract: s, deg, m, m/s, m/s², rad/s.
///
/// Its methods are `#[inline]`: the detector's row path calls them, and
/// this crate is built for size in the core wasm module (inline functions
/// are compiled in the calling crate, at its opt-level).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time, s (required, non-decreasing).
    pub t: f64,
    /// GPS latitude, WGS-84 deg.
    pub lat: f64,
    /// GPS longitude, deg.
    pub lon: f64,
    /// GPS altitude, m AMSL.
    pub alt: f64,
    /// GPS north, when the fix is already in a local NED frame, m.
    pub pn: f64,
    /// GPS east, local NED, m.
    pub pe: f64,
    /// GPS down, local NED, m.
    pub pd: f64,
    /// GPS velocity north, m/s.
    pub vn: f64,
    /// GPS velocity east, m/s.
    pub ve: f64,
    /// GPS velocity down, m/s.
    pub vd: f64,
    /// Fix type (0 none, 2 2D, 3 3D, >3 DGPS/RTK).
    pub fix: f64,
    /// Satellites used.
    pub sats: f64,
    /// Horizontal accuracy estimate, m.
    pub eph: f64,
    /// Vertical accuracy estimate, m.
    pub epv: f64,
    /// Specific force, body forward, m/s².
    pub ax: f64,
    /// Specific force, body right, m/s².
    pub ay: f64,
    /// Specific force, body down, m/s².
    pub az: f64,
    /// Gyro rate about body forward, rad/s.
    pub gx: f64,
    /// Gyro rate about body right, rad/s.
    pub gy: f64,
    /// Gyro rate about body down, rad/s.
    pub gz: f64,
    /// Attitude quaternion body FRD -> NED (Hamilton), scalar part.
    pub qw: f64,
    /// Attitude quaternion x.
    pub qx: f64,
    /// Attitude quaternion y.
    pub qy: f64,
    /// Attitude quaternion z.
    pub qz: f64,
    /// Barometric altitude, m, positive up.
    pub baro: f64,
    /// Ground truth for evaluation (1 = fault); never read by detectors.
    pub label: f64,
    /// The receiver's own time of this fix, s, on any epoch (GPS seconds,
    /// time of week, UTC seconds): only its rate against `t` is used, to
    /// measure how fast the log's boot clock runs (see `detector::ClockRate`).
    pub gps_time: f64,
    /// The receiver's speed accuracy claim, m/s (u-blox `sAcc`, ArduPilot
    /// `GPA.SAcc`/`UBX3.sAcc`, PX4 `s_variance_m_s`): only its ratio to the
    /// receiver's usual claim is used, to scale the velocity test (see
    /// `detector::ReceiverQuality`).
    pub sacc: f64,
}

impl Default for Sample {
    #[inline]
    fn default() -> Self {
        Self::at(f64::NAN)
    }
}

/// Column names in contract order; `Sample::get`/`set` index into this.
/// `gps_time` and `sacc` extend the contract's columns (unknown columns to
/// a reader that predates them), so they come last.
pub const COLUMNS: [&str; 28] = [
    "t", "lat", "lon", "alt", "pn", "pe", "pd", "vn", "ve", "vd", "fix", "sats", "eph", "epv",
    "ax", "ay", "az", "gx", "gy", "gz", "qw", "qx", "qy", "qz", "baro", "label", "gps_time", "sacc",
];

impl Sample {
    /// An empty row at time `t` (s).
    #[inline]
    pub const fn at(t: f64) -> Self {
        let n = f64::NAN;
        Sample {
            t, lat: n, lon: n, alt: n, pn: n, pe: n, pd: n, vn: n, ve: n, vd: n, fix: n,
            sats: n, eph: n, epv: n, ax: n, ay: n, az: n, gx: n, gy: n, gz: n, qw: n, qx: n,
            qy: n, qz: n, baro: n, label: n, gps_time: n, sacc: n,
        }
    }

    /// Field by column index (see [`COLUMNS`]).
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        match i {
            0 => self.t, 1 => self.lat, 2 => self.lon, 3 => self.alt, 4 => self.pn,
            5 => self.pe, 6 => self.pd, 7 => self.vn, 8 => self.ve, 9 => self.vd,
            10 => self.fix, 11 => self.sats, 12 => self.eph, 13 => self.epv, 14 => self.ax,
            15 => self.ay, 16 => self.az, 17 => self.gx, 18 => self.gy, 19 => self.gz,
            20 => self.qw, 21 => self.qx, 22 => self.qy, 23 => self.qz, 24 => self.baro,
            25 => self.label, 26 => self.gps_time, 27 => self.sacc, _ => f64::NAN,
        }
    }

    /// Row `j` of the columns in [`COLUMNS`] order; a column shorter than
    /// `j + 1` reads as NaN (absent).
    #[inline]
    pub fn from_columns(c: &[&[f64]; COLUMNS.len()], j: usize) -> Self {
        let g = |i: usize| c[i].get(j).copied().unwrap_or(f64::NAN);
        Sample {
            t: g(0),
            lat: g(1),
            lon: g(2),
            alt: g(3),
            pn: g(4),
            pe: g(5),
            pd: g(6),
            vn: g(7),
            ve: g(8),
            vd: g(9),
            fix: g(10),
            sats: g(11),
            eph: g(12),
            epv: g(13),
            ax: g(14),
            ay: g(15),
            az: g(16),
            gx: g(17),
            gy: g(18),
            gz: g(19),
            qw: g(20),
            qx: g(21),
            qy: g(22),
            qz: g(23),
            baro: g(24),
            label: g(25),
            gps_time: g(26),
            sacc: g(27),
        }
    }

    /// Set a field by column index (see [`COLUMNS`]); out-of-range is ignored.
    #[inline]
    pub fn set(&mut self, i: usize, v: f64) {
        let slot = match i {
            0 => &mut self.t, 1 => &mut self.lat, 2 => &mut self.lon, 3 => &mut self.alt,
            4 => &mut self.pn, 5 => &mut self.pe, 6 => &mut self.pd, 7 => &mut self.vn,
            8 => &mut self.ve, 9 => &mut self.vd, 10 => &mut self.fix, 11 => &mut self.sats,
            12 => &mut self.eph, 13 => &mut self.epv, 14 => &mut self.ax, 15 => &mut self.ay,
            16 => &mut self.az, 17 => &mut self.gx, 18 => &mut self.gy, 19 => &mut self.gz,
            20 => &mut self.qw, 21 => &mut self.qx, 22 => &mut self.qy, 23 => &mut self.qz,
            24 => &mut self.baro, 25 => &mut self.label, 26 => &mut self.gps_time, 27 => &mut self.sacc,
            _ => return,
        };
        *slot = v;
    }

    /// Column index of a contract column name.
    #[inline]
    pub fn column_index(name: &str) -> Option<usize> {
        COLUMNS.iter().position(|c| *c == name)
    }

    /// Does the row carry a position (lat/lon/alt or pn/pe/pd, all three)?
    #[inline]
    pub fn has_position(&self) -> bool {
        (self.lat.is_finite() && self.lon.is_finite() && self.alt.is_finite())
            || (self.pn.is_finite() && self.pe.is_finite() && self.pd.is_finite())
    }

    /// Contract §1: a row "has a GPS fix" when a full position is present and
    /// `fix` is absent or >= 2.
    #[inline]
    pub fn has_fix(&self) -> bool {
        self.has_position() && (self.fix.is_nan() || self.fix >= 2.0)
    }

    /// A receiver report of "no fix" at this instant (an outage sample):
    /// `fix` < 2 present, or a position present with `fix` < 2.
    #[inline]
    pub fn reports_no_fix(&self) -> bool {
        self.fix.is_finite() && self.fix < 2.0
    }

    /// GPS velocity present (all three axes).
    #[inline]
    pub fn has_velocity(&self) -> bool {
        self.vn.is_finite() && self.ve.is_finite() && self.vd.is_finite()
    }

    /// Accelerometer present (all three axes).
    #[inline]
    pub fn has_accel(&self) -> bool {
        self.ax.is_finite() && self.ay.is_finite() && self.az.is_finite()
    }

    /// Attitude quaternion present (all four components).
    #[inline]
    pub fn has_attitude(&self) -> bool {
        self.qw.is_finite() && self.qx.is_finite() && self.qy.is_finite() && self.qz.is_finite()
    }

    /// Barometric altitude present.
    #[inline]
    pub fn has_baro(&self) -> bool {
        self.baro.is_finite()
    }
}

/// Valid ranges per column: a value outside is an input error (the
/// detector's checks; here so that the cold field-by-field checks,
/// [`Sample::first_invalid`], compile in this crate, which the core wasm
/// module builds for size).
pub const fn range_of(i: usize) -> (f64, f64) {
    match i {
        0 => (-1e12, 1e12),           // t, s
        1 => (-90.0, 90.0),           // lat
        2 => (-180.0, 180.0),         // lon
        3 => (-2000.0, 1e5),          // alt, m
        4..=6 => (-1e7, 1e7),         // pn/pe/pd, m
        7..=9 => (-2000.0, 2000.0),   // velocity, m/s
        10 => (0.0, 100.0),           // fix
        11 => (0.0, 1000.0),          // sats
        12 | 13 => (0.0, 1e12),       // eph/epv, m
        14..=16 => (-2000.0, 2000.0), // accel, m/s²
        17..=19 => (-200.0, 200.0),   // gyro, rad/s
        20..=23 => (-2.0, 2.0),       // quaternion
        24 => (-2000.0, 1e5),         // baro, m
        26 => (-1e12, 1e12),          // gps_time, s
        27 => (0.0, 1e12),            // sacc, m/s
        _ => (f64::NEG_INFINITY, f64::INFINITY),
    }
}

/// Column groups that must be all present or all absent in a row: the
/// GPS position (lat/lon/alt and pn/pe/pd), velocity, accelerometer, gyro,
/// attitude quaternion.
pub const GROUPS_ALL_OR_NONE: [&[usize]; 6] = [&[1, 2, 3], &[4, 5, 6], &[7, 8, 9], &[14, 15, 16], &[17, 18, 19], &[20, 21, 22, 23]];

impl Sample {
    /// The first field that fails the row checks, with why: `t` present and
    /// finite, every value in its range ([`range_of`]), each group of
    /// [`GROUPS_ALL_OR_NONE`] complete. `None` when all pass (the
    /// quaternion's norm is the detector's to check). Cold: the detector
    /// calls it only for a row its fast check refused, for the message.
    pub fn first_invalid(&self) -> Option<(&'static str, String)> {
        if !self.t.is_finite() {
            return Some(("t", format!("required and must be finite, got {}", Shortest(self.t))));
        }
        for (i, name) in COLUMNS.iter().enumerate() {
            let v = self.get(i);
            if v.is_nan() {
                continue;
            }
            let (lo, hi) = range_of(i);
            if !v.is_finite() || v < lo || v > hi {
                return Some((name, format!("value {} outside [{}, {}]", Shortest(v), Shortest(lo), Shortest(hi))));
            }
        }
        for g in GROUPS_ALL_OR_NONE {
            let present = g.iter().filter(|&&i| !self.get(i).is_nan()).count();
            if present != 0 && present != g.len() {
                let missing = g.iter().find(|&&i| self.get(i).is_nan()).copied().unwrap_or(g[0]);
                let have = g.iter().find(|&&i| !self.get(i).is_nan()).copied().unwrap_or(g[0]);
                return Some((COLUMNS[missing], format!("missing (NaN) while '{}' is present", COLUMNS[have])));
            }
        }
        None
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn from_columns_reads_every_field_in_column_order() {
        let cols: Vec<Vec<f64>> = (0..COLUMNS.len())
            .map(|i| vec![100.0 + i as f64, 200.0 + i as f64])
            .collect();
        let mut c: [&[f64]; COLUMNS.len()] = core::array::from_fn(|i| cols[i].as_slice());
        let s = Sample::from_columns(&c, 1);
        for i in 0..COLUMNS.len() {
            assert_eq!(s.get(i), 200.0 + i as f64, "column {}", COLUMNS[i]);
        }
        // A short column is absent, not a panic.
        c[24] = &[];
        assert!(Sample::from_columns(&c, 1).baro.is_nan());
        // get and set agree on every index, and past the end both do nothing.
        let mut r = Sample::at(0.0);
        for i in 0..COLUMNS.len() {
            r.set(i, 1000.0 + i as f64);
        }
        r.set(COLUMNS.len(), 5.0);
        for i in 0..COLUMNS.len() {
            assert_eq!(r.get(i), 1000.0 + i as f64, "column {}", COLUMNS[i]);
        }
        assert!(r.get(COLUMNS.len()).is_nan());
        assert_eq!(Sample::column_index("gps_time"), Some(26));
        assert_eq!(Sample::column_index("sacc"), Some(27));
    }

    #[test]
    fn first_invalid_names_the_field_and_value() {
        let mut s = Sample::at(1.0);
        assert_eq!(s.first_invalid(), None);
        s.lat = 91.0;
        assert_eq!(s.first_invalid(), Some(("lat", "value 91 outside [-90, 90]".to_string())));
        s.lat = f64::NAN;
        s.ax = 1.0;
        assert_eq!(s.first_invalid(), Some(("ay", "missing (NaN) while 'ax' is present".to_string())));
        s.t = f64::INFINITY;
        assert_eq!(s.first_invalid(), Some(("t", "required and must be finite, got inf".to_string())));
    }
}

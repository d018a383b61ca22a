//! The row types of the tightly coupled lab (time, IMU, per-satellite
//! pseudo-ranges) and their CSV form (see `docs/tight.md`). Shared by the
//! streaming detector ([`super::stream`]) and the simulator
//! ([`super::scenario`]), which writes rows the detector reads.

use serde::{Deserialize, Serialize};

use super::TightError;

/// One pseudo-range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PrObs {
    /// Satellite id (1..=n_sats).
    pub prn: u8,
    /// Pseudo-range, m.
    pub pr: f64,
}

/// One input row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpochRow {
    /// Time, s.
    pub t: f64,
    /// Gyro, rad/s, body frame.
    pub gyro: [f64; 3],
    /// Specific force, m/s², body frame.
    pub accel: [f64; 3],
    /// Pseudo-ranges of this row (empty: IMU-only row).
    #[serde(default)]
    pub pr: Vec<PrObs>,
}

/// Known initial state (e.g. from the autopilot); without it the detector
/// waits for a row with ≥ 4 pseudo-ranges and starts from a least-squares
/// fix, level attitude with `initial_yaw_deg` and `initial_velocity_ned`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitialState {
    /// Time of this state, s (rows must come after it).
    pub t: f64,
    /// Position in the site NED frame, m.
    pub position_ned: [f64; 3],
    /// Velocity, NED, m/s.
    pub velocity_ned: [f64; 3],
    /// Roll, pitch, yaw (deg).
    pub roll_pitch_yaw_deg: [f64; 3],
    /// Receiver clock bias, m.
    pub clock_bias_m: f64,
    /// Receiver clock drift, m/s.
    pub clock_drift_mps: f64,
}

const IMU_COLS: [&str; 7] = ["t", "gx", "gy", "gz", "ax", "ay", "az"];

/// Parse CSV rows. Two layouts, chosen by the header:
///
/// * wide: `t,gx,gy,gz,ax,ay,az,pr_<prn>...`, one row per IMU sample;
/// * long: `t,gx,gy,gz,ax,ay,az,sat_id,pr`, one row per satellite; rows
///   with the same `t` (consecutive) form one epoch and must repeat the
///   same IMU values; a row with empty `sat_id` and `pr` is IMU-only.
///
/// Blank lines and lines starting with `#` are skipped. Errors name the
/// line, the column and the bad value.
pub fn parse_csv(text: &str) -> Result<Vec<EpochRow>, TightError> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (_, header) = lines.next().ok_or_else(|| TightError::new("header", "empty input: no header line"))?;
    let cols: Vec<&str> = header.split(',').map(|c| c.trim()).collect();
    if cols.contains(&"sat_id") {
        return parse_long(&cols, lines);
    }
    let mut imu_idx = [usize::MAX; 7];
    let mut pr_cols: Vec<(usize, u8)> = Vec::new();
    for (i, c) in cols.iter().enumerate() {
        if let Some(k) = IMU_COLS.iter().position(|x| x == c) {
            if imu_idx[k] != usize::MAX {
                return Err(TightError::new(*c, "column appears twice in the header"));
            }
            imu_idx[k] = i;
        } else if let Some(n) = c.strip_prefix("pr_") {
            let prn: u8 = n.parse().map_err(|_| TightError::new(*c, format!("satellite id must be an integer 1..=255, got {n:?}")))?;
            if prn == 0 {
                return Err(TightError::new(*c, "satellite id must be >= 1, got 0"));
            }
            if pr_cols.iter().any(|&(_, p)| p == prn) {
                return Err(TightError::new(*c, "column appears twice in the header"));
            }
            pr_cols.push((i, prn));
        } else {
            return Err(TightError::new(*c, "unknown column (expected t, gx, gy, gz, ax, ay, az, pr_<prn>)"));
        }
    }
    if let Some(k) = imu_idx.iter().position(|&i| i == usize::MAX) {
        return Err(TightError::new(IMU_COLS[k], "required column missing from the header"));
    }
    let mut rows = Vec::new();
    for (ln, line) in lines {
        let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
        let lno = ln + 1;
        if cells.len() != cols.len() {
            return Err(TightError::new(format!("line {lno}"), format!("{} cells, header has {}", cells.len(), cols.len())));
        }
        let num = |i: usize| -> Result<f64, TightError> {
            let s = cells[i];
            s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| TightError::new(format!("line {lno}: {}", cols[i]), format!("must be a finite number, got {s:?}")))
        };
        let mut v = [0.0; 7];
        for k in 0..7 {
            v[k] = num(imu_idx[k])?;
        }
        let mut pr = Vec::new();
        for &(i, prn) in &pr_cols {
            let s = cells[i];
            if s.is_empty() || s.eq_ignore_ascii_case("nan") {
                continue;
            }
            pr.push(PrObs { prn, pr: num(i)? });
        }
        rows.push(EpochRow { t: v[0], gyro: [v[1], v[2], v[3]], accel: [v[4], v[5], v[6]], pr });
    }
    Ok(rows)
}

fn parse_long<'a>(cols: &[&str], lines: impl Iterator<Item = (usize, &'a str)>) -> Result<Vec<EpochRow>, TightError> {
    let want = ["t", "gx", "gy", "gz", "ax", "ay", "az", "sat_id", "pr"];
    for c in cols {
        if !want.contains(c) {
            return Err(TightError::new(*c, "unknown column (long layout: t, gx, gy, gz, ax, ay, az, sat_id, pr)"));
        }
    }
    let mut idx = [usize::MAX; 9];
    for (k, w) in want.iter().enumerate() {
        let found: Vec<usize> = cols.iter().enumerate().filter(|(_, c)| *c == w).map(|(i, _)| i).collect();
        match found.as_slice() {
            [i] => idx[k] = *i,
            [] => return Err(TightError::new(*w, "required column missing from the header")),
            _ => return Err(TightError::new(*w, "column appears twice in the header")),
        }
    }
    let mut rows: Vec<EpochRow> = Vec::new();
    for (ln, line) in lines {
        let lno = ln + 1;
        let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
        if cells.len() != cols.len() {
            return Err(TightError::new(format!("line {lno}"), format!("{} cells, header has {}", cells.len(), cols.len())));
        }
        let num = |k: usize| -> Result<f64, TightError> {
            let s = cells[idx[k]];
            s.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| TightError::new(format!("line {lno}: {}", want[k]), format!("must be a finite number, got {s:?}")))
        };
        let mut v = [0.0; 7];
        for (k, x) in v.iter_mut().enumerate() {
            *x = num(k)?;
        }
        let (sid, prs) = (cells[idx[7]], cells[idx[8]]);
        let obs = if sid.is_empty() && (prs.is_empty() || prs.eq_ignore_ascii_case("nan")) {
            None
        } else {
            let prn: u8 = sid
                .parse()
                .ok()
                .filter(|p| *p >= 1)
                .ok_or_else(|| TightError::new(format!("line {lno}: sat_id"), format!("must be an integer 1..=255, got {sid:?}")))?;
            if prs.is_empty() || prs.eq_ignore_ascii_case("nan") {
                None
            } else {
                Some(PrObs { prn, pr: num(8)? })
            }
        };
        match rows.last_mut() {
            Some(last) if last.t == v[0] => {
                if last.gyro != [v[1], v[2], v[3]] || last.accel != [v[4], v[5], v[6]] {
                    return Err(TightError::new(format!("line {lno}: gx..az"), format!("IMU values differ from the previous row of the same epoch t = {}", v[0])));
                }
                if let Some(o) = obs {
                    last.pr.push(o);
                }
            }
            _ => rows.push(EpochRow { t: v[0], gyro: [v[1], v[2], v[3]], accel: [v[4], v[5], v[6]], pr: obs.into_iter().collect() }),
        }
    }
    Ok(rows)
}

/// Write rows in the `pr_<prn>` CSV format (columns for every satellite
/// that appears; empty cell where a row has no pseudo-range for it).
pub fn to_csv(rows: &[EpochRow]) -> String {
    let mut prns: Vec<u8> = rows.iter().flat_map(|r| r.pr.iter().map(|o| o.prn)).collect();
    prns.sort_unstable();
    prns.dedup();
    let mut s = String::from("t,gx,gy,gz,ax,ay,az");
    for p in &prns {
        s.push_str(&format!(",pr_{p}"));
    }
    s.push('\n');
    for r in rows {
        s.push_str(&format!("{},{},{},{},{},{},{}", r.t, r.gyro[0], r.gyro[1], r.gyro[2], r.accel[0], r.accel[1], r.accel[2]));
        for p in &prns {
            match r.pr.iter().find(|o| o.prn == *p) {
                Some(o) => s.push_str(&format!(",{}", o.pr)),
                None => s.push(','),
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_and_absent_values() {
        let text = "# comment\nt,gx,gy,gz,ax,ay,az,pr_3,pr_17\n0.05,0,0,0.01,0,0,-9.8,,\n1.0,0,0,0,0.1,0,-9.8,20000000.5,NaN\n";
        let rows = parse_csv(text).unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows[0].pr.is_empty());
        assert_eq!(rows[1].pr, vec![PrObs { prn: 3, pr: 20000000.5 }]);
        assert_eq!(rows[1].accel, [0.1, 0.0, -9.8]);
        let again = parse_csv(&to_csv(&rows)).unwrap();
        assert_eq!(again, rows);
    }

    #[test]
    fn long_layout_with_sat_id() {
        let text = "t,gx,gy,gz,ax,ay,az,sat_id,pr\n0.05,0,0,0,0,0,-9.8,,\n1,0,0,0,0,0,-9.8,3,20000000.5\n1,0,0,0,0,0,-9.8,17,21000000\n1,0,0,0,0,0,-9.8,9,NaN\n";
        let rows = parse_csv(text).unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows[0].pr.is_empty());
        assert_eq!(rows[1].pr, vec![PrObs { prn: 3, pr: 20000000.5 }, PrObs { prn: 17, pr: 21000000.0 }]);
        // Same as the wide layout.
        let wide = parse_csv("t,gx,gy,gz,ax,ay,az,pr_3,pr_17\n0.05,0,0,0,0,0,-9.8,,\n1,0,0,0,0,0,-9.8,20000000.5,21000000\n").unwrap();
        assert_eq!(rows, wide);
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,sat_id,pr\n1,0,0,0,0,0,-9.8,3,2e7\n1,0,0,0,0.5,0,-9.8,4,2e7\n").unwrap_err();
        assert!(e.field.contains("line 3"), "{e}");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,sat_id,pr\n1,0,0,0,0,0,-9.8,G7,2e7\n").unwrap_err();
        assert_eq!(e.field, "line 2: sat_id");
        assert!(e.message.contains("\"G7\""));
    }

    #[test]
    fn csv_errors_name_field_and_value() {
        let e = parse_csv("t,gx,gy,gz,ax,ay,pr_3\n").unwrap_err();
        assert_eq!(e.field, "az");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,pr_x\n").unwrap_err();
        assert_eq!(e.field, "pr_x");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,speed\n").unwrap_err();
        assert_eq!(e.field, "speed");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az,pr_3\n0,0,0,0,0,0,-9.8,abc\n").unwrap_err();
        assert_eq!(e.field, "line 2: pr_3");
        assert!(e.message.contains("\"abc\""), "{e}");
        let e = parse_csv("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0\n").unwrap_err();
        assert!(e.message.contains("6 cells"), "{e}");
        assert!(parse_csv("").is_err());
    }
}

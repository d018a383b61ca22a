//! Navlog CSV reader (contract §1).
//!
//! `#` lines before the header are comments; column order is free; unknown
//! columns are ignored with a warning; an empty cell is "absent" (NaN). The
//! reader is incremental ([`CsvReader::read_chunk`] takes any chunk of bytes), so a
//! file larger than memory can be streamed; [`read_csv`] is the whole-buffer
//! convenience.

use super::LogData;
use crate::error::{LogError, LogPos};
use crate::sample::{Sample, COLUMNS};

/// A cell's number: std's parse, or with the feature `compact-floats`
/// (the core wasm module) the same results through `decimal::parse_f64`,
/// without std's 10.4 KB table.
#[inline]
fn parse_f64(cell: &str) -> Option<f64> {
    #[cfg(feature = "compact-floats")]
    return crate::decimal::parse_f64(cell);
    #[cfg(not(feature = "compact-floats"))]
    return cell.parse().ok();
}

/// Incremental navlog CSV parser.
#[derive(Clone, Debug, Default)]
pub struct CsvReader {
    /// Column index in `Sample` per CSV field (None = unknown column).
    map: Option<Vec<Option<usize>>>,
    partial: Vec<u8>,
    line_no: u64,
    /// What the reader coped with (unknown columns ignored).
    pub warnings: Vec<String>,
    /// `#` comment lines before the header (at most 64, 256 characters each).
    pub comments: Vec<String>,
}

impl CsvReader {
    /// A reader at the start of a file.
    pub fn new() -> Self {
        Self::default()
    }

    /// What the log says beside its rows: a navlog CSV's `eph` column is the
    /// receiver's accuracy in metres (contract §1); no modes, messages or UTC.
    pub fn extras(&self) -> super::extras::Extras {
        let eph = crate::sample::COLUMNS.iter().position(|c| *c == "eph");
        let has_eph = self.map.as_ref().is_some_and(|m| m.iter().any(|c| c.is_some() && *c == eph));
        super::extras::Extras { eph_source: if has_eph { super::extras::EphSource::Eph } else { super::extras::EphSource::None }, ..Default::default() }
    }

    /// Header columns known so far (after the header line was read).
    pub fn has_header(&self) -> bool {
        self.map.is_some()
    }

    /// Feed a chunk; complete lines become rows appended to `out`.
    pub fn read_chunk(&mut self, chunk: &[u8], out: &mut Vec<Sample>) -> Result<(), LogError> {
        let mut start = 0;
        for (i, b) in chunk.iter().enumerate() {
            if *b == b'\n' {
                if self.partial.is_empty() {
                    self.line(&chunk[start..i], out)?;
                } else {
                    self.partial.extend_from_slice(&chunk[start..i]);
                    let line = core::mem::take(&mut self.partial);
                    self.line(&line, out)?;
                }
                start = i + 1;
            }
        }
        if start < chunk.len() {
            if self.partial.len() + (chunk.len() - start) > 1 << 20 {
                return Err(LogError::csv(LogPos::Line(self.line_no + 1), None, "longer than 1 MiB (not a navlog CSV?)"));
            }
            self.partial.extend_from_slice(&chunk[start..]);
        }
        Ok(())
    }

    /// End of input: parse a last line without a newline.
    pub fn read_end(&mut self, out: &mut Vec<Sample>) -> Result<(), LogError> {
        if !self.partial.is_empty() {
            let line = core::mem::take(&mut self.partial);
            self.line(&line, out)?;
        }
        if self.map.is_none() {
            return Err(LogError::csv(LogPos::File, None, "no header row found (empty file or only comments)"));
        }
        Ok(())
    }

    fn line(&mut self, raw: &[u8], out: &mut Vec<Sample>) -> Result<(), LogError> {
        self.line_no += 1;
        let ln = self.line_no;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let text = core::str::from_utf8(raw).map_err(|_| LogError::csv(LogPos::Line(ln), None, "not UTF-8 text (binary file?)"))?;
        let text = if ln == 1 { text.trim_start_matches('\u{feff}') } else { text };
        if text.trim().is_empty() {
            return Ok(());
        }
        let Some(map) = &self.map else {
            if let Some(c) = text.strip_prefix('#') {
                // Bounded like ULog info strings: comments go into the report.
                if self.comments.len() < 64 {
                    self.comments.push(c.trim().chars().take(256).collect());
                }
                return Ok(());
            }
            return self.header(text);
        };
        let mut s = Sample::default();
        let mut n = 0;
        for (j, cell) in text.split(',').enumerate() {
            n = j + 1;
            let Some(Some(idx)) = map.get(j) else { continue };
            let cell = cell.trim();
            if cell.is_empty() {
                continue;
            }
            let v = parse_f64(cell).ok_or_else(|| {
                LogError::csv(LogPos::Line(ln), COLUMNS.get(*idx).copied(), format!("cannot parse \"{}\" as a number", truncate(cell)))
            })?;
            s.set(*idx, v);
        }
        if n != map.len() {
            return Err(LogError::csv(LogPos::Line(ln), None, format!("{n} fields, header has {}", map.len())));
        }
        if s.t.is_nan() {
            return Err(LogError::csv(LogPos::Line(ln), Some("t"), "required on every row"));
        }
        out.push(s);
        Ok(())
    }

    fn header(&mut self, text: &str) -> Result<(), LogError> {
        let mut map = Vec::new();
        let mut unknown = Vec::new();
        let mut seen = [false; COLUMNS.len()];
        for name in text.split(',') {
            let name = name.trim();
            match Sample::column_index(name) {
                Some(i) => {
                    if seen[i] {
                        return Err(LogError::csv(LogPos::Header, Some(name), "appears twice"));
                    }
                    seen[i] = true;
                    map.push(Some(i));
                }
                None => {
                    unknown.push(name.to_string());
                    map.push(None);
                }
            }
        }
        if !seen[0] {
            let hint = if text.contains(';') || text.contains('\t') { " (the delimiter must be a comma)" } else { "" };
            return Err(LogError::csv(LogPos::Header, None, format!("no 't' column{hint}")));
        }
        if !unknown.is_empty() {
            self.warnings.push(format!("unknown columns ignored: {}", unknown.join(", ")));
        }
        self.map = Some(map);
        Ok(())
    }
}

fn truncate(s: &str) -> String {
    s.chars().take(32).collect()
}

/// Parse a whole navlog CSV.
pub fn read_csv(bytes: &[u8]) -> Result<LogData, LogError> {
    let mut r = CsvReader::new();
    let mut rows = Vec::new();
    r.read_chunk(bytes, &mut rows)?;
    r.read_end(&mut rows)?;
    let mut missing = vec![];
    if !rows.iter().any(|s| s.has_position() || s.reports_no_fix()) {
        missing.push("gps".to_string());
    }
    if !rows.iter().any(|s| s.has_accel()) {
        missing.push("imu".to_string());
    }
    if !rows.iter().any(|s| s.has_attitude()) {
        missing.push("attitude".to_string());
    }
    if !rows.iter().any(|s| s.has_baro()) {
        missing.push("baro".to_string());
    }
    let meta = r.comments.iter().take(8).enumerate().map(|(i, c)| (format!("comment{i}"), c.clone())).collect();
    let extras = r.extras();
    Ok(LogData { format: "csv", samples: rows, meta, warnings: r.warnings, missing, topic_counts: vec![], extras })
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn reads_mixed_rows_comments_and_unknown_columns() {
        let text = "# a comment\n#another\nt,lat,lon,alt,ax,ay,az,foo\n0.0,1.5,2.5,10,,,,x\n0.02,,,,0.1,0.2,-9.8,y\r\n0.04,1.5,2.5,10,0.1,0.2,-9.8,";
        let d = read_csv(text.as_bytes()).unwrap();
        assert_eq!(d.samples.len(), 3);
        assert!(d.samples[0].has_fix() && !d.samples[0].has_accel());
        assert!(!d.samples[1].has_position() && d.samples[1].has_accel());
        assert_eq!(d.samples[1].az, -9.8);
        assert!(d.warnings[0].contains("foo"));
        assert!(d.missing.contains(&"baro".to_string()));
    }

    #[test]
    fn chunked_feed_equals_whole() {
        let text = "t,pn,pe,pd\n0,1,2,3\n0.1,1.1,2.1,3.1\n0.2,1.2,2.2,3.2\n";
        let whole = read_csv(text.as_bytes()).unwrap().samples;
        for cut in 1..text.len() {
            let mut r = CsvReader::new();
            let mut rows = vec![];
            r.read_chunk(&text.as_bytes()[..cut], &mut rows).unwrap();
            r.read_chunk(&text.as_bytes()[cut..], &mut rows).unwrap();
            r.read_end(&mut rows).unwrap();
            let bits = |v: &[Sample]| -> Vec<Vec<u64>> { v.iter().map(|s| (0..COLUMNS.len()).map(|i| s.get(i).to_bits()).collect()).collect() };
            assert_eq!(bits(&rows), bits(&whole), "cut at {cut}");
        }
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = read_csv(b"t,lat\n0,abc\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("'lat'") && e.contains("abc"), "{e}");
        let e = read_csv(b"t;lat;lon\n0;1;2\n").unwrap_err().to_string();
        assert!(e.contains("delimiter"), "{e}");
        assert!(read_csv(b"").unwrap_err().to_string().contains("no header"));
        assert!(read_csv(b"# only\n").unwrap_err().to_string().contains("no header"));
        let e = read_csv(b"t,lat\n0,1,2\n").unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
        assert!(read_csv(&[0xff, 0xfe, 0x00, 0x12]).is_err());
        let e = read_csv(b"t,lat\n,1\n").unwrap_err().to_string();
        assert!(e.contains("'t'"), "{e}");
    }

    /// The error names the line and column as data, and its text is the
    /// one-line message users saw before errors were typed.
    #[test]
    fn log_errors_carry_line_column_and_message() {
        let e = read_csv(b"# c\nt,lat\n0,1\n0.1,abc\n").unwrap_err();
        assert_eq!((e.format, e.pos, e.column.as_deref(), e.line()), ("csv", LogPos::Line(4), Some("lat"), Some(4)));
        assert_eq!(e.to_string(), "line 4, column 'lat': cannot parse \"abc\" as a number");
        let e = read_csv(b"t,lat\n0,1,2\n").unwrap_err();
        assert_eq!((e.pos, e.column.as_deref()), (LogPos::Line(2), None));
        assert_eq!(e.to_string(), "line 2: 3 fields, header has 2");
        let e = read_csv(b"t,lat,lat\n").unwrap_err();
        assert_eq!((e.pos, e.column.as_deref()), (LogPos::Header, Some("lat")));
        assert_eq!(e.to_string(), "header: column 'lat' appears twice");
        let e = read_csv(b"t,lat\n,1\n").unwrap_err();
        assert_eq!(e.to_string(), "line 2, column 't': required on every row");
        let e = read_csv(b"a;b\n").unwrap_err();
        assert_eq!(e.to_string(), "header: no 't' column (the delimiter must be a comma)");
        assert_eq!(read_csv(b"").unwrap_err(), LogError::csv(LogPos::File, None, "no header row found (empty file or only comments)"));
        // A line that never ends names the line it is on.
        let mut r = CsvReader::new();
        let e = r.read_chunk(&vec![b'x'; (1 << 20) + 1], &mut vec![]).unwrap_err();
        assert_eq!(e.to_string(), "line 1: longer than 1 MiB (not a navlog CSV?)");
    }
}

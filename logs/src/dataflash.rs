//! ArduPilot DataFlash (`.bin`) log reader.
//!
//! # Format
//! A DataFlash log is a flat stream of messages, each `0xA3 0x95 <type u8>`
//! followed by a fixed-size little-endian payload. The layout of every type
//! is declared in-band by `FMT` messages (type 128, 89 bytes: Type `B`,
//! Length `B` incl. the 3-byte header, Name `n`, Format `N`, Columns `Z`).
//! Newer logs add `FMTU` (unit and multiplier ids per column).
//!
//! Format characters (size in bytes, decoded value):
//! `b` i8, `B` u8, `M` flight mode u8, `h` i16, `H` u16, `i` i32, `I` u32,
//! `q` i64, `Q` u64, `f` f32, `d` f64, `g` f16, `c` i16/100, `C` u16/100,
//! `e` i32/100, `E` u32/100, `L` i32/1e7 (deg), `n` char[4], `N` char[16],
//! `Z` char[64], `a` i16[32].
//!
//! # Speed
//! On each `FMT` the byte offsets of the few columns we map are computed once;
//! a message of any other type is only counted and skipped, so the hot loop
//! touches 3 header bytes per unmapped message.
//!
//! # Mapping to [`Sample`] rows (one row per message, `t` = boot clock, s)
//! * `GPS` (instance 0) -> `fix` (= Status: 0 no GPS, 1 no fix, 2 2D, 3 3D,
//!   4 DGPS, 5/6 RTK), `sats`, and only when Status >= 2: `lat`/`lon` (deg),
//!   `alt` (m AMSL), `vn = Spd cos(GCrs)`, `ve = Spd sin(GCrs)` (m/s),
//!   `vd = VZ` (m/s, **positive down**: ArduPilot logs `velocity.z` of its NED
//!   velocity; on `Loiter_RTL.bin` VZ correlates at about -0.85 with the rate
//!   of change of GPS altitude), `eph` (see below). A row with Status < 2 keeps
//!   position and velocity NaN: it means "no fix at this instant".
//! * `eph`: `GPA.HAcc` (m) when a `GPA` message accompanies the fix (newer
//!   logs), or `UBX3.hAcc` when a `UBX3` record of the same time precedes it
//!   (2014-era logs with a u-blox receiver); otherwise HDop is used as a
//!   proxy in metres, i.e. a user range error of 1 m (`eph = HDop * 1 m`).
//!   HDop 99.99 ("unknown") passes through as a large eph; HDop 0 gives NaN.
//!   `epv` only from `GPA.VAcc` / `UBX3.vAcc`, `sacc` (m/s) only from
//!   `GPA.SAcc` / `UBX3.sAcc`.
//! * `IMU` (instance 0; older logs name further IMUs `IMU2`, `IMU3`, which
//!   are only counted) -> `ax..az` (AccX..Z, m/s², body FRD) and `gx..gz`
//!   (GyrX..Z, rad/s).
//! * `ATT` Roll/Pitch/Yaw (deg; `c`/`C` centidegrees in the log) -> a
//!   Hamilton quaternion body FRD -> NED, ZYX order, canonical sign `qw >= 0`.
//!   No row of its own: the newest attitude at or before an IMU row's time,
//!   if at most 0.5 s old, is put on that row.
//! * `BARO` (instance 0) `Alt` -> `baro` (m above the boot calibration level).
//!
//! # Time
//! `TimeUS` (µs) in current logs, `TimeMS` (ms) in 2014-era logs. The old
//! `GPS` message is the exception: there `TimeMS` is the **GPS time of
//! week**, and the boot time is the field `T` (ms), which is what we use.
//! A GPS message with neither `TimeUS` nor `T` is stamped with the boot time
//! of the preceding mapped message (messages are written in time order), and
//! a warning says so.
//!
//! # Robustness
//! No input panics: all reads are bounds-checked, lengths use checked
//! arithmetic, allocation is proportional to the input size. A bad header
//! makes the reader scan for the next `0xA3 0x95` whose type is known and
//! whose successor also starts with a valid header; the skipped bytes are
//! reported in a warning. A log cut inside a message keeps everything before
//! it and says where it was cut.
//!
//! # Limitations
//! `MULT` messages are not read: `FMTU` multiplier ids are resolved with
//! ArduPilot's fixed table, and only applied to mapped integer columns that
//! carry no scale in their format character. Multi-instance GPS/IMU/BARO
//! only use instance 0. Attitude is not interpolated.

use crate::extras::{gps_to_unix, EphSource, Extras};
use crate::{LogData, LogError, LogSummary, Reorder, RowSink, Window, FEED_CHUNK, REORDER_ROWS};
use crate::decimal::{Fixed, Shortest};
use crate::sample::Sample;

const HEAD1: u8 = 0xA3;
const HEAD2: u8 = 0x95;
/// First bytes of every DataFlash log (the header of its first `FMT`).
pub(crate) const HEADER: [u8; 3] = [HEAD1, HEAD2, FMT_TYPE];
/// Message names counted separately at most (real logs: about 100); the
/// counts of further names are summed under "(other)".
const MAX_NAMES: usize = 4096;
/// Reorder ranks at equal time: attitude first (it applies to IMU rows at its
/// own time), then rows in file order, as the former whole-file stable sort.
const RANK_ATT: u8 = 0;
const RANK_ROW: u8 = 1;
const HEADER_LEN: usize = 3;
/// Message type of `FMT`, fixed by the format.
const FMT_TYPE: u8 = 128;
/// Length of an `FMT` message including its header.
const FMT_LEN: usize = 89;
/// Attitude older than this (s) is not put on an IMU row.
const ATT_MAX_AGE_S: f64 = 0.5;
/// GPA and GPS written together carry the same time stamp; tolerance, s.
const GPA_MATCH_S: f64 = 0.0015;
/// Keep fuzzed inputs from growing the warning list without bound.
const MAX_WARNINGS: usize = 32;

/// True when the bytes look like a DataFlash log: they start with the
/// `0xA3 0x95` header of an `FMT` message (type 128).
pub fn is_dataflash(bytes: &[u8]) -> bool {
    matches!(bytes, [HEAD1, HEAD2, FMT_TYPE, ..])
}

/// Parse a DataFlash log into samples sorted by boot time (see the module
/// doc for the mapping). `Err` (one line) only when no sample row can be read.
pub fn read_dataflash(bytes: &[u8]) -> Result<LogData, LogError> {
    let mut rows = Vec::new();
    let summary = read_dataflash_into(bytes, &mut rows)?;
    Ok(summary.with_rows(rows))
}

/// [`read_dataflash`] with the rows going to `sink`.
pub fn read_dataflash_into(bytes: &[u8], sink: &mut dyn RowSink) -> Result<LogSummary, LogError> {
    let mut s = DataflashStream::new();
    for c in bytes.chunks(FEED_CHUNK) {
        s.feed(c, sink);
    }
    s.finish(sink)
}

/// An incremental DataFlash reader: [`DataflashStream::feed`] the file in
/// chunks of any size (one pass), then [`DataflashStream::finish`]. Rows
/// reach the sink in time order through a bounded reorder buffer; it holds
/// only the bytes of the message being parsed (at most 255) or being
/// resynchronised on, so memory does not grow with the file.
pub struct DataflashStream {
    win: Window,
    pos: u64,
    types: Vec<Option<Layout>>,
    out: Out,
    /// Resync in progress: (where the bad bytes began, scan position).
    scan: Option<(u64, u64)>,
    stopped: bool,
}

impl Default for DataflashStream {
    fn default() -> Self {
        Self::new()
    }
}

impl DataflashStream {
    /// A reader at the start of a file (only the built-in `FMT` is known).
    pub fn new() -> Self {
        let mut types: Vec<Option<Layout>> = (0..256).map(|_| None).collect();
        if let Some(slot) = types.get_mut(usize::from(FMT_TYPE)) {
            *slot = Some(Layout::fmt_builtin());
        }
        let out = Out { counts: vec![0; 256], ..Out::default() };
        DataflashStream { win: Window::default(), pos: 0, types, out, scan: None, stopped: false }
    }

    /// Bytes fed so far.
    pub fn bytes(&self) -> u64 {
        self.win.end()
    }

    /// Bytes the reader holds now in its input window and reorder buffer:
    /// what must not grow with the file.
    pub fn held_bytes(&self) -> usize {
        self.win.held_bytes() + self.out.emit.held_bytes()
    }

    /// The next chunk of the file (any size); rows that are final go to `sink`.
    pub fn feed(&mut self, chunk: &[u8], sink: &mut dyn RowSink) {
        self.win.push(chunk);
        self.run(false, sink);
    }

    /// End of input: the rows still buffered go to `sink`.
    pub fn finish(mut self, sink: &mut dyn RowSink) -> Result<LogSummary, LogError> {
        self.run(true, sink);
        let n = self.win.end();
        self.out.finish(&self.types, n, sink)
    }

    fn run(&mut self, eof: bool, sink: &mut dyn RowSink) {
        while !self.stopped && self.step(eof, sink) {}
        let keep = self.scan.map_or(self.pos, |(_, p)| p);
        self.win.consume(keep);
    }

    /// Type of a valid header at `pos` whose type has a layout; `Err` when
    /// the 3 header bytes are not all in yet.
    fn known_header(&self, pos: u64) -> Result<Option<u8>, ()> {
        match *self.win.get(pos, pos + HEADER_LEN as u64) {
            [HEAD1, HEAD2, ty] if self.types.get(usize::from(ty)).is_some_and(Option::is_some) => Ok(Some(ty)),
            [_, _, _] => Ok(None),
            _ => Err(()),
        }
    }

    /// One message; false when more bytes are needed or the input is done.
    fn step(&mut self, eof: bool, sink: &mut dyn RowSink) -> bool {
        if let Some((start, p)) = self.scan {
            let Some(next) = self.resync(p, eof) else {
                return false;
            };
            self.scan = None;
            self.out.skip((next - start) as usize);
            self.pos = next;
            return true;
        }
        let n = self.win.end();
        let pos = self.pos;
        if pos >= n {
            return false;
        }
        let rest = n - pos;
        if rest < HEADER_LEN as u64 {
            if !eof {
                return false;
            }
            let b = self.win.get(pos, n);
            let partial_header = b.first() == Some(&HEAD1) && (rest == 1 || b.get(1) == Some(&HEAD2));
            if partial_header {
                self.out.warn(format!(
                    "truncated at byte {n} in the middle of a message header (starts at byte {pos})"
                ));
            } else {
                self.out.skip(rest as usize);
            }
            self.stopped = true;
            return false;
        }
        let Ok(Some(ty)) = self.known_header(pos) else {
            self.scan = Some((pos, pos + 1));
            return true;
        };
        let Some(len) = self.types.get(usize::from(ty)).and_then(Option::as_ref).map(|l| l.len as u64) else {
            self.stopped = true; // unreachable: known_header checked it
            return false;
        };
        let end = pos + len;
        if end > n {
            if eof {
                let name = self.types.get(usize::from(ty)).and_then(Option::as_ref).map_or("", |l| l.name.as_str());
                let w = format!(
                    "truncated at byte {n} in the middle of a {name} message (starts at byte {pos}, {len} bytes long)"
                );
                self.out.warn(w);
                self.stopped = true;
            }
            return false;
        }
        let msg = self.win.get(pos, end);
        if let Some(c) = self.out.counts.get_mut(usize::from(ty)) {
            *c += 1;
        }
        self.out.messages += 1;
        let Some(layout) = self.types.get(usize::from(ty)).and_then(Option::as_ref) else {
            return false;
        };
        match layout.kind {
            Kind::Fmt => on_fmt(msg, &mut self.types, &mut self.out),
            Kind::Fmtu => on_fmtu(msg, ty, &mut self.types),
            Kind::Gps => self.out.on_gps(layout, msg, sink),
            Kind::Gpa => self.out.on_gpa(layout, msg),
            Kind::Ubx3 => self.out.on_ubx3(layout, msg),
            Kind::Imu => self.out.on_imu(layout, msg, sink),
            Kind::Att => self.out.on_att(layout, msg, sink),
            Kind::Baro => self.out.on_baro(layout, msg, sink),
            Kind::Msg => self.out.on_msg(layout, msg),
            Kind::Mode => self.out.on_mode(layout, msg),
            Kind::Err => self.out.on_err(layout, msg),
            Kind::Ev => self.out.on_ev(layout, msg),
            Kind::Other => {}
        }
        self.pos = end;
        true
    }

    /// Position of the next plausible message at or after `from`, or the
    /// end of input; `None` (with the scan position saved) when more bytes
    /// are needed to decide. A candidate needs a known type and, unless it
    /// reaches the end, a valid header right after it: `0xA3 0x95` also
    /// occurs inside payloads. Scanning only moves forward, so resyncing is
    /// linear in the input size.
    fn resync(&mut self, from: u64, eof: bool) -> Option<u64> {
        let n = self.win.end();
        let mut p = from;
        loop {
            if p >= n {
                return self.wait(p, n, eof);
            }
            let Some(i) = self.win.get(p, n).windows(2).position(|w| w == [HEAD1, HEAD2]) else {
                // The last byte may be the start of a header.
                return self.wait(n.saturating_sub(1).max(p), n, eof);
            };
            let c = p + i as u64;
            match self.known_header(c) {
                Err(()) if !eof => return self.wait(c, n, eof),
                Ok(Some(ty)) => {
                    let len = self.types.get(usize::from(ty)).and_then(Option::as_ref).map_or(0, |l| l.len as u64);
                    let next = c + len;
                    if next + HEADER_LEN as u64 > n {
                        if eof {
                            return Some(c); // reaches the end: truncation is reported later
                        }
                        return self.wait(c, n, eof);
                    }
                    if matches!(self.known_header(next), Ok(Some(_))) {
                        return Some(c);
                    }
                }
                _ => {}
            }
            p = c + 1;
        }
    }

    /// Resync needs bytes from `p` on: at the end of input there are none
    /// (resume at the end), else remember where to scan from.
    fn wait(&mut self, p: u64, n: u64, eof: bool) -> Option<u64> {
        if eof {
            return Some(n);
        }
        if let Some(s) = self.scan.as_mut() {
            s.1 = p;
        }
        None
    }
}

// ---------------------------------------------------------------------------
// Message layouts

/// What we do with a message type, decided from its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Fmt,
    Fmtu,
    Gps,
    Gpa,
    Ubx3,
    Imu,
    Att,
    Baro,
    Msg,
    Mode,
    Err,
    Ev,
    Other,
}

fn kind_of(name: &str) -> Kind {
    match name {
        "FMT" => Kind::Fmt,
        "FMTU" => Kind::Fmtu,
        "GPS" => Kind::Gps,
        "GPA" => Kind::Gpa,
        "UBX3" => Kind::Ubx3,
        "IMU" => Kind::Imu,
        "ATT" => Kind::Att,
        "BARO" => Kind::Baro,
        "MSG" => Kind::Msg,
        "MODE" => Kind::Mode,
        "ERR" => Kind::Err,
        "EV" => Kind::Ev,
        _ => Kind::Other,
    }
}

// Role indices into `Layout::roles`, per kind.
const GPS_STATUS: usize = 0;
const GPS_LAT: usize = 1;
const GPS_LNG: usize = 2;
const GPS_ALT: usize = 3;
const GPS_NSATS: usize = 4;
const GPS_HDOP: usize = 5;
const GPS_SPD: usize = 6;
const GPS_GCRS: usize = 7;
const GPS_VZ: usize = 8;
/// GPS time: week and ms of week (`GWk`/`GMS`; old logs `Week`/`TimeMS`,
/// their boot clock being `T`).
const GPS_WEEK: usize = 9;
const GPS_MS: usize = 10;
const MODE_MODE: usize = 0;
const ERR_SUBSYS: usize = 0;
const ERR_ECODE: usize = 1;
const EV_ID: usize = 0;
const GPA_HACC: usize = 0;
const GPA_VACC: usize = 1;
const GPA_VV: usize = 2;
const GPA_SACC: usize = 3;
const UBX3_HACC: usize = 0;
const UBX3_VACC: usize = 1;
const UBX3_SACC: usize = 2;
const IMU_ACCX: usize = 0;
const IMU_GYRX: usize = 3;
const ATT_ROLL: usize = 0;
const ATT_PITCH: usize = 1;
const ATT_YAW: usize = 2;
const BARO_ALT: usize = 0;
const MSG_TEXT: usize = 0;
const FMTU_TYPE: usize = 0;
const FMTU_MULTS: usize = 1;
const MAX_ROLES: usize = 11;

/// Column names (with accepted alternatives) of each role, in role order.
fn role_names(kind: Kind) -> &'static [&'static [&'static str]] {
    match kind {
        Kind::Gps => &[
            &["Status"],
            &["Lat"],
            &["Lng", "Lon"],
            &["Alt"],
            &["NSats", "NSat", "nSat"],
            &["HDop", "HDOP"],
            &["Spd"],
            &["GCrs"],
            &["VZ"],
            &["GWk", "Week"],
            &["GMS", "TimeMS"],
        ],
        Kind::Gpa => &[&["HAcc"], &["VAcc"], &["VV"], &["SAcc"]],
        Kind::Ubx3 => &[&["hAcc"], &["vAcc"], &["sAcc"]],
        Kind::Imu => &[
            &["AccX"],
            &["AccY"],
            &["AccZ"],
            &["GyrX"],
            &["GyrY"],
            &["GyrZ"],
        ],
        Kind::Att => &[&["Roll"], &["Pitch"], &["Yaw"]],
        Kind::Baro => &[&["Alt"]],
        Kind::Msg => &[&["Message"]],
        Kind::Mode => &[&["Mode"]],
        Kind::Err => &[&["Subsys"], &["ECode"]],
        Kind::Ev => &[&["Id"]],
        Kind::Fmtu => &[&["FmtType"], &["MultIds"]],
        Kind::Fmt | Kind::Other => &[],
    }
}

/// Size in bytes of a format character's field, `None` if unknown.
fn char_size(ch: u8) -> Option<usize> {
    Some(match ch {
        b'b' | b'B' | b'M' => 1,
        b'h' | b'H' | b'c' | b'C' | b'g' => 2,
        b'i' | b'I' | b'f' | b'e' | b'E' | b'L' | b'n' => 4,
        b'd' | b'q' | b'Q' => 8,
        b'N' => 16,
        b'Z' | b'a' => 64,
        _ => return None,
    })
}

/// Integer characters without a built-in scale: the only ones an `FMTU`
/// multiplier applies to (`c C e E L` already carry theirs).
fn is_unscaled_int(ch: u8) -> bool {
    matches!(ch, b'b' | b'B' | b'h' | b'H' | b'i' | b'I' | b'q' | b'Q')
}

/// ArduPilot's fixed multiplier table (`AP_Logger/LogStructure.h`).
fn mult_of(id: u8) -> Option<f64> {
    Some(match id {
        b'2' => 1e2,
        b'1' => 1e1,
        b'0' => 1.0,
        b'A' => 1e-1,
        b'B' => 1e-2,
        b'C' => 1e-3,
        b'D' => 1e-4,
        b'E' => 1e-5,
        b'F' => 1e-6,
        b'G' => 1e-7,
        b'I' => 1e-9,
        _ => return None, // '-' none, '?' unknown, '!' '/' unit conversions
    })
}

/// One column: byte offset in the message (header included), format char.
#[derive(Clone, Debug, PartialEq)]
struct Col {
    name: String,
    off: usize,
    ch: u8,
}

/// A mapped column, with the extra `FMTU` multiplier (1 when none applies).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Field {
    off: usize,
    ch: u8,
    col: usize,
    mult: f64,
}

impl Field {
    fn num(&self, msg: &[u8]) -> f64 {
        match read_num(msg, self.off, self.ch) {
            Some(v) if v.is_finite() => v * self.mult,
            _ => f64::NAN,
        }
    }
}

/// Layout of one message type, from its `FMT`.
#[derive(Clone, Debug)]
struct Layout {
    name: String,
    /// Message length in bytes, header included (>= 3).
    len: usize,
    /// Every column up to the first unknown format character. The reader
    /// only needs `roles`; the full table serves tests and future mappings.
    #[cfg_attr(not(test), allow(dead_code))]
    cols: Vec<Col>,
    kind: Kind,
    /// Boot-clock field and units per second (1e6 TimeUS, 1e3 TimeMS / T).
    time: Option<(Field, f64)>,
    /// Instance column `I` of newer GPS/GPA/IMU/BARO messages.
    inst: Option<Field>,
    roles: [Option<Field>; MAX_ROLES],
}

impl Layout {
    /// `FMT` describes itself; we never let a log redefine it.
    fn fmt_builtin() -> Layout {
        let names = ["Type", "Length", "Name", "Format", "Columns"];
        let chars = b"BBnNZ";
        let mut cols = Vec::with_capacity(names.len());
        let mut off = HEADER_LEN;
        for (name, &ch) in names.iter().zip(chars.iter()) {
            cols.push(Col {
                name: (*name).to_string(),
                off,
                ch,
            });
            off += char_size(ch).unwrap_or(0);
        }
        Layout {
            name: "FMT".to_string(),
            len: FMT_LEN,
            cols,
            kind: Kind::Fmt,
            time: None,
            inst: None,
            roles: [None; MAX_ROLES],
        }
    }

    /// Build a layout from an `FMT` message (header included). Returns the
    /// defined type, the layout and a warning, or `None` if unusable.
    fn from_fmt(msg: &[u8]) -> Option<(u8, Layout, Option<String>)> {
        let ty = *msg.get(3)?;
        let len = usize::from(*msg.get(4)?);
        if len < HEADER_LEN {
            return None; // could not even be skipped
        }
        let name = cstr(msg.get(5..9)?);
        let format = msg.get(9..25)?.split(|&b| b == 0).next().unwrap_or(&[]);
        let columns = cstr(msg.get(25..89)?);
        let mut names = columns.split(',');
        let mut cols = Vec::with_capacity(format.len());
        let mut off = HEADER_LEN;
        let mut warning = None;
        for &ch in format {
            let Some(size) = char_size(ch) else {
                warning = Some(format!(
                    "{name}: unknown format character {}; its later columns are not read",
                    crate::text::quoted_char(char::from(ch))
                ));
                break;
            };
            let col = names.next().unwrap_or("").trim().to_string();
            cols.push(Col { name: col, off, ch });
            off = off.checked_add(size)?;
        }
        if warning.is_none() && off != len {
            warning = Some(format!(
                "{name}: FMT says {len} bytes but format {} needs {off}; fields beyond the length are not read",
                crate::text::quoted(&String::from_utf8_lossy(format))
            ));
        }
        let kind = kind_of(&name);
        let find = |label: &str| -> Option<Field> {
            let (i, c) = cols.iter().enumerate().find(|(_, c)| c.name == label)?;
            let end = c.off.checked_add(char_size(c.ch)?)?;
            (end <= len).then_some(Field {
                off: c.off,
                ch: c.ch,
                col: i,
                mult: 1.0,
            })
        };
        // Old GPS messages: TimeMS is GPS time of week, T is the boot clock.
        let time = match (find("TimeUS"), kind) {
            (Some(f), _) => Some((f, 1e6)),
            (None, Kind::Gps) => find("T").map(|f| (f, 1e3)),
            (None, _) => find("TimeMS").map(|f| (f, 1e3)),
        };
        let inst = match kind {
            Kind::Gps | Kind::Gpa | Kind::Imu | Kind::Baro => find("I"),
            _ => None,
        };
        let mut roles = [None; MAX_ROLES];
        for (slot, alts) in roles.iter_mut().zip(role_names(kind)) {
            *slot = alts.iter().find_map(|a| find(a));
        }
        let layout = Layout {
            name,
            len,
            cols,
            kind,
            time,
            inst,
            roles,
        };
        Some((ty, layout, warning))
    }

    fn role(&self, i: usize) -> Option<&Field> {
        self.roles.get(i).and_then(Option::as_ref)
    }

    /// Numeric value of a role, NaN if absent or not finite.
    fn num(&self, msg: &[u8], role: usize) -> f64 {
        self.role(role).map_or(f64::NAN, |f| f.num(msg))
    }

    /// True unless the message carries an instance number other than 0.
    fn instance0(&self, msg: &[u8]) -> bool {
        self.inst
            .is_none_or(|f| read_num(msg, f.off, f.ch) == Some(0.0))
    }
}

// ---------------------------------------------------------------------------
// Field decoding

fn arr<const N: usize>(msg: &[u8], off: usize) -> Option<[u8; N]> {
    msg.get(off..off.checked_add(N)?)?.try_into().ok()
}

/// Decode a numeric field at byte `off` with format character `ch`, scaled
/// as the character says. `None` for strings, arrays, unknown characters
/// and reads past the end.
fn read_num(msg: &[u8], off: usize, ch: u8) -> Option<f64> {
    Some(match ch {
        b'b' => f64::from(i8::from_le_bytes(arr(msg, off)?)),
        b'B' | b'M' => f64::from(u8::from_le_bytes(arr(msg, off)?)),
        b'h' => f64::from(i16::from_le_bytes(arr(msg, off)?)),
        b'H' => f64::from(u16::from_le_bytes(arr(msg, off)?)),
        b'i' => f64::from(i32::from_le_bytes(arr(msg, off)?)),
        b'I' => f64::from(u32::from_le_bytes(arr(msg, off)?)),
        b'q' => i64::from_le_bytes(arr(msg, off)?) as f64,
        b'Q' => u64::from_le_bytes(arr(msg, off)?) as f64,
        b'f' => f64::from(f32::from_le_bytes(arr(msg, off)?)),
        b'd' => f64::from_le_bytes(arr(msg, off)?),
        b'g' => f16_to_f64(u16::from_le_bytes(arr(msg, off)?)),
        // Dividing (not multiplying by 0.01 / 1e-7) gives the nearest double.
        b'c' => f64::from(i16::from_le_bytes(arr(msg, off)?)) / 100.0,
        b'C' => f64::from(u16::from_le_bytes(arr(msg, off)?)) / 100.0,
        b'e' => f64::from(i32::from_le_bytes(arr(msg, off)?)) / 100.0,
        b'E' => f64::from(u32::from_le_bytes(arr(msg, off)?)) / 100.0,
        b'L' => f64::from(i32::from_le_bytes(arr(msg, off)?)) / 1e7,
        _ => return None,
    })
}

/// Decode a text field (`n`, `N`, `Z`): up to the first NUL, lossy UTF-8.
fn read_str(msg: &[u8], off: usize, ch: u8) -> Option<String> {
    match ch {
        b'n' | b'N' | b'Z' => Some(cstr(msg.get(off..off.checked_add(char_size(ch)?)?)?)),
        _ => None,
    }
}

/// Decode an `a` field: 32 little-endian i16 (no mapped column uses it yet).
#[cfg_attr(not(test), allow(dead_code))]
fn read_i16_array(msg: &[u8], off: usize) -> Option<[i16; 32]> {
    let raw: [u8; 64] = arr(msg, off)?;
    let mut out = [0i16; 32];
    for (o, pair) in out.iter_mut().zip(raw.chunks_exact(2)) {
        if let [a, b] = pair {
            *o = i16::from_le_bytes([*a, *b]);
        }
    }
    Some(out)
}

fn cstr(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(b.get(..end).unwrap_or(b)).into_owned()
}

/// IEEE 754 half precision to f64 (format character `g`).
fn f16_to_f64(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f64::from(h & 0x3ff);
    match exp {
        0 => sign * frac * 2f64.powi(-24),
        31 if frac == 0.0 => sign * f64::INFINITY,
        31 => f64::NAN,
        e => sign * (1.0 + frac / 1024.0) * 2f64.powi(e - 15),
    }
}

// ---------------------------------------------------------------------------
// Framing

fn on_fmt(msg: &[u8], types: &mut [Option<Layout>], out: &mut Out) {
    let Some((ty, layout, warning)) = Layout::from_fmt(msg) else {
        out.warn_once("an FMT message with a length below 3 bytes was ignored".to_string());
        return;
    };
    if ty == FMT_TYPE {
        return; // FMT's own definition is fixed by the format
    }
    if let Some(w) = warning {
        out.warn_once(w);
    }
    let Some(slot) = types.get_mut(usize::from(ty)) else {
        return;
    };
    if let Some(old) = slot.as_ref() {
        if old.name != layout.name {
            out.flush_count(ty, &old.name);
        }
    }
    *slot = Some(layout);
}

fn on_fmtu(msg: &[u8], fmtu_ty: u8, types: &mut [Option<Layout>]) {
    let (target, mults) = {
        let Some(l) = types.get(usize::from(fmtu_ty)).and_then(Option::as_ref) else {
            return;
        };
        let (Some(tf), Some(mf)) = (l.role(FMTU_TYPE), l.role(FMTU_MULTS)) else {
            return;
        };
        let Some(target) = read_num(msg, tf.off, tf.ch) else {
            return;
        };
        let Some(mults) = read_str(msg, mf.off, mf.ch) else {
            return;
        };
        (target, mults)
    };
    if !(0.0..=255.0).contains(&target) || target as u8 == FMT_TYPE {
        return;
    }
    let Some(layout) = types.get_mut(target as usize).and_then(Option::as_mut) else {
        return;
    };
    let ids = mults.as_bytes();
    for f in layout.roles.iter_mut().flatten() {
        if is_unscaled_int(f.ch) {
            if let Some(m) = ids.get(f.col).copied().and_then(mult_of) {
                f.mult = m;
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Output

/// What goes through the reorder buffer.
enum Item {
    Row(Sample),
    /// An IMU row: gets the latest attitude.
    Imu(Sample),
    /// (t s, quaternion w x y z)
    Att(f64, [f64; 4]),
}

#[derive(Default)]
struct Out {
    /// Rows and attitudes on their way to the sink, in time order.
    emit: Reorder<Item>,
    /// Latest attitude handed on: (t s, quaternion).
    att: Option<(f64, [f64; 4])>,
    /// IMU rows handed on with an attitude.
    with_att: u64,
    /// Time of the first and last row handed on, s.
    span: Option<(f64, f64)>,
    /// The last GPS row and its place in the reorder order, held back until
    /// its GPA companion may have come.
    pending_gps: Option<(Sample, u64)>,
    /// Time of the last GPS row, for its GPA companion.
    last_gps_t: Option<f64>,
    /// The last `UBX3` (t s, hAcc m, vAcc m, sAcc m/s): 2014-era logs write
    /// the u-blox accuracies just before the `GPS` message of the same time.
    ubx3: Option<(f64, [f64; 3])>,
    /// Boot time of the last mapped message, for GPS without a boot clock.
    last_boot_t: Option<f64>,
    /// Messages by name, in name order (as a `BTreeMap` iterates them):
    /// a sorted `Vec` searched by bisection, so the core wasm module
    /// carries no B-tree code (3 KB). A name is inserted once (at most
    /// [`MAX_NAMES`] + 1 of them), found in O(log n) at every later flush.
    counts_by_name: Vec<(String, u64)>,
    counts: Vec<u64>,
    messages: u64,
    n_gps: u64,
    n_imu: u64,
    n_baro: u64,
    used_us: bool,
    used_ms: bool,
    firmware: Option<String>,
    /// Modes, messages, UTC time; GPS rows whose eph is HDOP / GPA HAcc.
    extras: Extras,
    eph_hdop: u64,
    eph_hacc: u64,
    warnings: Vec<String>,
    suppressed: usize,
    skipped: usize,
    skip_runs: usize,
}

impl Out {
    /// A row or an attitude into the reorder buffer (file order = arrival).
    fn push(&mut self, t: f64, rank: u8, item: Item, sink: &mut dyn RowSink) {
        let seq = self.emit.take_seq();
        self.emit_at(t, rank, seq, item, sink);
    }

    fn emit_at(&mut self, t: f64, rank: u8, seq: u64, item: Item, sink: &mut dyn RowSink) {
        // The held GPS row goes in before it would be overtaken.
        if let Some((g, gseq)) = self.pending_gps {
            if self.emit.len() >= REORDER_ROWS && self.emit.precedes_all(g.t, RANK_ROW, gseq) {
                self.pending_gps = None;
                self.emit_at(g.t, RANK_ROW, gseq, Item::Row(g), sink);
            }
        }
        let Out { emit, att, with_att, span, .. } = self;
        emit.push_at(t, rank, seq, item, &mut |i| Self::out(att, with_att, span, i, sink));
    }

    fn out(att: &mut Option<(f64, [f64; 4])>, with_att: &mut u64, span: &mut Option<(f64, f64)>, item: Item, sink: &mut dyn RowSink) {
        let row = match item {
            Item::Att(t, q) => {
                *att = Some((t, q));
                return;
            }
            Item::Row(row) => row,
            Item::Imu(mut row) => {
                // Attitude onto IMU rows: newest ATT at or before the row, if fresh.
                if let Some((ta, q)) = *att {
                    if row.t - ta <= ATT_MAX_AGE_S {
                        [row.qw, row.qx, row.qy, row.qz] = q;
                        *with_att += 1;
                    }
                }
                row
            }
        };
        *span = Some(span.map_or((row.t, row.t), |(a, _)| (a, row.t)));
        sink.row(&row);
    }

    /// Hand on the held GPS row (a new one came, or the end).
    fn flush_gps(&mut self, sink: &mut dyn RowSink) {
        if let Some((g, seq)) = self.pending_gps.take() {
            self.emit_at(g.t, RANK_ROW, seq, Item::Row(g), sink);
        }
    }

    fn warn(&mut self, w: String) {
        if self.warnings.len() < MAX_WARNINGS {
            self.warnings.push(w);
        } else {
            self.suppressed += 1;
        }
    }

    fn warn_once(&mut self, w: String) {
        if !self.warnings.contains(&w) {
            self.warn(w);
        }
    }

    fn skip(&mut self, n: usize) {
        if n > 0 {
            self.skipped = self.skipped.saturating_add(n);
            self.skip_runs += 1;
        }
    }

    fn flush_count(&mut self, ty: u8, name: &str) {
        if let Some(c) = self.counts.get_mut(usize::from(ty)) {
            if *c > 0 {
                let find = |k: &str| self.counts_by_name.binary_search_by(|(n, _)| n.as_str().cmp(k));
                let key = if self.counts_by_name.len() < MAX_NAMES || find(name).is_ok() { name } else { "(other)" };
                match find(key) {
                    Ok(i) => {
                        if let Some(e) = self.counts_by_name.get_mut(i) {
                            e.1 += *c;
                        }
                    }
                    Err(i) => self.counts_by_name.insert(i, (key.to_string(), *c)),
                }
                *c = 0;
            }
        }
    }

    /// Boot time (s) of a message, from its layout's time column.
    fn time(&mut self, l: &Layout, msg: &[u8]) -> Option<f64> {
        let (f, per_s) = l.time?;
        // Division gives the nearest double (900000 us -> exactly 0.9 s).
        let t = read_num(msg, f.off, f.ch)? / per_s;
        if !t.is_finite() {
            return None;
        }
        if per_s > 1e4 {
            self.used_us = true;
        } else {
            self.used_ms = true;
        }
        self.last_boot_t = Some(t);
        Some(t)
    }

    fn time_or_warn(&mut self, l: &Layout, msg: &[u8]) -> Option<f64> {
        let t = self.time(l, msg);
        if t.is_none() && l.time.is_none() {
            self.warn_once(format!(
                "{} messages have no TimeUS/TimeMS column; ignored",
                l.name
            ));
        }
        t
    }

    fn on_gps(&mut self, l: &Layout, msg: &[u8], sink: &mut dyn RowSink) {
        if !l.instance0(msg) {
            return;
        }
        let t = if l.time.is_some() {
            self.time(l, msg)
        } else {
            self.warn_once(
                "GPS messages have no boot-time column (TimeMS there is GPS time of week); \
                 stamped with the preceding message's boot time"
                    .to_string(),
            );
            self.last_boot_t
        };
        let Some(t) = t else { return };
        let mut s = Sample::at(t);
        let status = l.num(msg, GPS_STATUS);
        s.fix = status;
        s.sats = l.num(msg, GPS_NSATS);
        if status.is_nan() || status >= 2.0 {
            let (lat, lon) = (l.num(msg, GPS_LAT), l.num(msg, GPS_LNG));
            // 0/0 is what the autopilot writes when it has no position.
            let valid = lat.abs() <= 90.0 && lon.abs() <= 180.0 && (lat != 0.0 || lon != 0.0);
            if valid {
                s.lat = lat;
                s.lon = lon;
                s.alt = l.num(msg, GPS_ALT);
            }
            let (spd, crs) = (l.num(msg, GPS_SPD), l.num(msg, GPS_GCRS).to_radians());
            s.vn = spd * libm::cos(crs);
            s.ve = spd * libm::sin(crs);
            s.vd = l.num(msg, GPS_VZ);
            let hdop = l.num(msg, GPS_HDOP);
            if let Some((_, acc)) = self.ubx3.take().filter(|(tu, _)| (tu - t).abs() <= GPA_MATCH_S) {
                self.accuracies(&mut s, acc);
            }
            if s.eph.is_nan() && hdop > 0.0 {
                s.eph = hdop; // HDop x 1 m user range error, see module doc
                self.eph_hdop += 1;
            }
            let (week, ms) = (l.num(msg, GPS_WEEK), l.num(msg, GPS_MS));
            if week > 0.0 && ms >= 0.0 && (status.is_nan() || status >= 3.0) {
                self.extras.utc(t, gps_to_unix(week, ms));
            }
            // The receiver's time, GPS s (time of week alone without a week).
            if ms >= 0.0 {
                s.gps_time = if week > 0.0 { week * 604_800.0 } else { 0.0 } + ms * 1e-3;
            }
        }
        self.flush_gps(sink);
        self.last_gps_t = Some(t);
        self.n_gps += 1;
        let seq = self.emit.take_seq();
        self.pending_gps = Some((s, seq));
    }

    fn on_gpa(&mut self, l: &Layout, msg: &[u8]) {
        if !l.instance0(msg) {
            return;
        }
        let Some(t) = self.time(l, msg) else { return };
        let Some(tg) = self.last_gps_t else { return };
        if (t - tg).abs() > GPA_MATCH_S {
            return;
        }
        // Gone only if more than a reorder buffer of rows came in between.
        let Some(mut row) = self.pending_gps.map(|(s, _)| s) else {
            return;
        };
        if row.fix < 2.0 {
            return;
        }
        self.accuracies(&mut row, [l.num(msg, GPA_HACC), l.num(msg, GPA_VACC), l.num(msg, GPA_SACC)]);
        if l.num(msg, GPA_VV) == 0.0 {
            row.vd = f64::NAN; // receiver has no vertical velocity; VZ is a filler 0
        }
        if let Some((s, _)) = self.pending_gps.as_mut() {
            *s = row;
        }
    }

    /// The receiver's accuracy claims `[hAcc m, vAcc m, sAcc m/s]` (a
    /// non-positive or missing one is not a claim) onto a fix's row.
    fn accuracies(&mut self, s: &mut Sample, [hacc, vacc, sacc]: [f64; 3]) {
        if hacc > 0.0 {
            s.eph = hacc;
            self.eph_hacc += 1;
        }
        if vacc > 0.0 {
            s.epv = vacc;
        }
        if sacc > 0.0 {
            s.sacc = sacc;
        }
    }

    /// A `UBX3` record: held for the `GPS` message of the same time.
    fn on_ubx3(&mut self, l: &Layout, msg: &[u8]) {
        let Some(t) = self.time(l, msg) else { return };
        self.ubx3 = Some((t, [l.num(msg, UBX3_HACC), l.num(msg, UBX3_VACC), l.num(msg, UBX3_SACC)]));
    }

    fn on_imu(&mut self, l: &Layout, msg: &[u8], sink: &mut dyn RowSink) {
        if !l.instance0(msg) {
            return;
        }
        let Some(t) = self.time_or_warn(l, msg) else {
            return;
        };
        let mut s = Sample::at(t);
        s.ax = l.num(msg, IMU_ACCX);
        s.ay = l.num(msg, IMU_ACCX + 1);
        s.az = l.num(msg, IMU_ACCX + 2);
        s.gx = l.num(msg, IMU_GYRX);
        s.gy = l.num(msg, IMU_GYRX + 1);
        s.gz = l.num(msg, IMU_GYRX + 2);
        self.n_imu += 1;
        self.push(t, RANK_ROW, Item::Imu(s), sink);
    }

    fn on_att(&mut self, l: &Layout, msg: &[u8], sink: &mut dyn RowSink) {
        let Some(t) = self.time_or_warn(l, msg) else {
            return;
        };
        let (r, p, y) = (
            l.num(msg, ATT_ROLL),
            l.num(msg, ATT_PITCH),
            l.num(msg, ATT_YAW),
        );
        if r.is_finite() && p.is_finite() && y.is_finite() {
            self.push(t, RANK_ATT, Item::Att(t, euler_deg_to_quat(r, p, y)), sink);
        }
    }

    fn on_baro(&mut self, l: &Layout, msg: &[u8], sink: &mut dyn RowSink) {
        if !l.instance0(msg) {
            return;
        }
        let Some(t) = self.time_or_warn(l, msg) else {
            return;
        };
        let mut s = Sample::at(t);
        s.baro = l.num(msg, BARO_ALT);
        self.n_baro += 1;
        self.push(t, RANK_ROW, Item::Row(s), sink);
    }

    fn on_msg(&mut self, l: &Layout, msg: &[u8]) {
        let Some(f) = l.role(MSG_TEXT) else { return };
        let Some(text) = read_str(msg, f.off, f.ch) else {
            return;
        };
        let t = self.stamp(l, msg);
        self.extras.message(t, "info", &text);
        if self.firmware.is_none() && vehicle_type(&text).is_some() {
            self.firmware = Some(text.trim().to_string());
        }
    }

    /// Boot time (s) of a message that is not a sensor row (a mode, a text):
    /// its own time column, else the preceding message's boot time (old
    /// logs write MODE, MSG, ERR and EV without one), else NaN (before any
    /// time is known: put at the log's start by `finish`). Leaves the
    /// time-base bookkeeping of sensor rows alone.
    fn stamp(&self, l: &Layout, msg: &[u8]) -> f64 {
        l.time
            .and_then(|(f, per_s)| read_num(msg, f.off, f.ch).map(|v| v / per_s))
            .filter(|t| t.is_finite())
            .or(self.last_boot_t)
            .unwrap_or(f64::NAN)
    }

    /// `MODE`: the mode by name (a number in the vehicle's mode table).
    fn on_mode(&mut self, l: &Layout, msg: &[u8]) {
        let Some(f) = l.role(MODE_MODE) else { return };
        let name = match read_str(msg, f.off, f.ch) {
            Some(text) => text.trim().to_string(),
            None => {
                let n = f.num(msg);
                if !n.is_finite() {
                    return;
                }
                let vehicle = self.firmware.as_deref().and_then(vehicle_type);
                mode_name(vehicle, n).map_or_else(|| format!("mode {}", Shortest(n)), str::to_string)
            }
        };
        let t = self.stamp(l, msg);
        self.extras.mode(t, name);
    }

    /// `ERR`: subsystem and error code (0 = the error cleared).
    fn on_err(&mut self, l: &Layout, msg: &[u8]) {
        let (sub, code) = (l.num(msg, ERR_SUBSYS), l.num(msg, ERR_ECODE));
        if !sub.is_finite() || !code.is_finite() {
            return;
        }
        let name = err_subsystem(sub).map_or_else(|| format!("subsystem {}", Shortest(sub)), str::to_string);
        let (level, text) = if code == 0.0 { ("info", format!("ERR {name}: cleared")) } else { ("error", format!("ERR {name}: code {}", Shortest(code))) };
        let t = self.stamp(l, msg);
        self.extras.message(t, level, &text);
    }

    /// `EV`: an event by name (arming, landing, ...).
    fn on_ev(&mut self, l: &Layout, msg: &[u8]) {
        let id = l.num(msg, EV_ID);
        if !id.is_finite() {
            return;
        }
        let text = event_name(id).map_or_else(|| format!("event {}", Shortest(id)), str::to_string);
        let t = self.stamp(l, msg);
        self.extras.message(t, "event", &text);
    }

    fn finish(mut self, types: &[Option<Layout>], n_bytes: u64, sink: &mut dyn RowSink) -> Result<LogSummary, LogError> {
        self.flush_gps(sink);
        {
            let Out { emit, att, with_att, span, .. } = &mut self;
            emit.drain(&mut |i| Self::out(att, with_att, span, i, sink));
        }
        for (ty, l) in types.iter().enumerate() {
            if let (Some(l), Ok(ty)) = (l, u8::try_from(ty)) {
                self.flush_count(ty, &l.name);
            }
        }
        if self.n_gps + self.n_imu + self.n_baro == 0 {
            let why = if self.messages == 0 {
                "not a DataFlash log: no message with a 0xA3 0x95 header and a known type"
                    .to_string()
            } else {
                format!(
                    "DataFlash log has no GPS, IMU or BARO rows ({} messages in {n_bytes} bytes)",
                    self.messages
                )
            };
            let first = self
                .warnings
                .first()
                .map(|w| format!("; {w}"))
                .unwrap_or_default();
            return Err(LogError::file("dataflash", format!("{why}{first}")));
        }

        if self.skipped > 0 {
            let w = format!(
                "skipped {} unreadable bytes in {} places (resynchronised on the next 0xA3 0x95 header)",
                self.skipped, self.skip_runs
            );
            self.warnings.insert(0, w);
        }
        if self.suppressed > 0 {
            self.warnings
                .push(format!("{} more warnings suppressed", self.suppressed));
        }

        let mut meta = vec![("sys_name".to_string(), "ArduPilot".to_string())];
        if let Some(fw) = &self.firmware {
            meta.push(("firmware".to_string(), fw.clone()));
            if let Some(v) = vehicle_type(fw) {
                meta.push(("vehicle_type".to_string(), v.to_string()));
            }
        }
        let base = match (self.used_us, self.used_ms) {
            (true, false) => "TimeUS",
            (false, true) => "TimeMS",
            _ => "TimeUS+TimeMS",
        };
        meta.push(("time_base".to_string(), base.to_string()));
        let (t0, t1) = self.span.unwrap_or((0.0, 0.0));
        meta.push(("duration".to_string(), Fixed(t1 - t0, 3).to_string()));
        meta.push(("messages".to_string(), self.messages.to_string()));

        let mut missing = Vec::new();
        for (name, n) in [
            ("gps", self.n_gps),
            ("imu", self.n_imu),
            ("attitude", self.with_att),
            ("baro", self.n_baro),
        ] {
            if n == 0 {
                missing.push(name.to_string());
            }
        }

        if self.emit.late > 0 {
            self.warnings.push(format!("{} rows dropped: more than {REORDER_ROWS} rows out of time order", self.emit.late));
        }
        let mut extras = self.extras;
        // Messages before any boot time: at the log's start.
        for m in &mut extras.messages {
            if m.t.is_nan() {
                m.t = t0;
            }
        }
        for m in &mut extras.modes {
            if m.t.is_nan() {
                m.t = t0;
            }
        }
        extras.sort();
        extras.eph_source = match (self.eph_hdop, self.eph_hacc) {
            (0, 0) => EphSource::None,
            // Most fixes carry GPA's accuracy in metres.
            (h, a) if 2 * a >= h => EphSource::Eph,
            _ => EphSource::Hdop,
        };
        Ok(LogSummary {
            format: "dataflash",
            meta,
            warnings: self.warnings,
            missing,
            topic_counts: self.counts_by_name,
            extras,
        })
    }
}

/// A mode number's name in the vehicle's table (ArduPilot's `mode.h`,
/// `Plane::Mode::Number`, `Rover::Mode::Number`).
fn mode_name(vehicle: Option<&str>, n: f64) -> Option<&'static str> {
    const COPTER: [&str; 28] = [
        "STABILIZE", "ACRO", "ALT_HOLD", "AUTO", "GUIDED", "LOITER", "RTL", "CIRCLE", "", "LAND", "", "DRIFT", "", "SPORT",
        "FLIP", "AUTOTUNE", "POSHOLD", "BRAKE", "THROW", "AVOID_ADSB", "GUIDED_NOGPS", "SMART_RTL", "FLOWHOLD", "FOLLOW",
        "ZIGZAG", "SYSTEMID", "AUTOROTATE", "AUTO_RTL",
    ];
    const PLANE: [&str; 26] = [
        "MANUAL", "CIRCLE", "STABILIZE", "TRAINING", "ACRO", "FBWA", "FBWB", "CRUISE", "AUTOTUNE", "", "AUTO", "RTL",
        "LOITER", "TAKEOFF", "AVOID_ADSB", "GUIDED", "", "QSTABILIZE", "QHOVER", "QLOITER", "QLAND", "QRTL", "QAUTOTUNE",
        "QACRO", "THERMAL", "LOITER_ALT_QLAND",
    ];
    const ROVER: [&str; 16] = [
        "MANUAL", "ACRO", "", "STEERING", "HOLD", "LOITER", "FOLLOW", "SIMPLE", "DOCK", "CIRCLE", "AUTO", "RTL", "SMART_RTL",
        "", "", "GUIDED",
    ];
    let table: &[&'static str] = match vehicle {
        Some("copter") => &COPTER,
        Some("plane") => &PLANE,
        Some("rover") => &ROVER,
        _ => return None,
    };
    if n.fract() != 0.0 || n < 0.0 {
        return None;
    }
    table.get(n as usize).copied().filter(|s| !s.is_empty())
}

/// ArduPilot's `LogErrorSubsystem` names.
fn err_subsystem(n: f64) -> Option<&'static str> {
    const NAMES: [&str; 30] = [
        "", "MAIN", "RADIO", "COMPASS", "OPTFLOW", "FAILSAFE_RADIO", "FAILSAFE_BATT", "FAILSAFE_GPS", "FAILSAFE_GCS",
        "FAILSAFE_FENCE", "FLIGHT_MODE", "GPS", "CRASH_CHECK", "FLIP", "AUTOTUNE", "PARACHUTES", "EKFCHECK",
        "FAILSAFE_EKFINAV", "BARO", "CPU", "FAILSAFE_ADSB", "TERRAIN", "NAVIGATION", "FAILSAFE_TERRAIN", "EKF_PRIMARY",
        "THRUST_LOSS_CHECK", "FAILSAFE_SENSORS", "FAILSAFE_LEAK", "PILOT_INPUT", "FAILSAFE_VIBE",
    ];
    if n.fract() != 0.0 || n < 0.0 {
        return None;
    }
    NAMES.get(n as usize).copied().filter(|s| !s.is_empty())
}

/// ArduPilot's `LogEvent` names (the common ones).
fn event_name(n: f64) -> Option<&'static str> {
    Some(match n as i64 {
        _ if n.fract() != 0.0 => return None,
        10 => "ARMED",
        11 => "DISARMED",
        15 => "AUTO_ARMED",
        17 => "LAND_COMPLETE_MAYBE",
        18 => "LAND_COMPLETE",
        19 => "LOST_GPS",
        21 => "FLIP_START",
        22 => "FLIP_END",
        25 => "SET_HOME",
        26 => "SET_SIMPLE_ON",
        27 => "SET_SIMPLE_OFF",
        28 => "NOT_LANDED",
        29 => "SET_SUPERSIMPLE_ON",
        30 => "AUTOTUNE_INITIALISED",
        31 => "AUTOTUNE_OFF",
        32 => "AUTOTUNE_RESTART",
        33 => "AUTOTUNE_SUCCESS",
        34 => "AUTOTUNE_FAILED",
        35 => "AUTOTUNE_REACHED_LIMIT",
        36 => "AUTOTUNE_PILOT_TESTING",
        37 => "AUTOTUNE_SAVEDGAINS",
        38 => "SAVE_TRIM",
        39 => "SAVEWP_ADD_WP",
        41 => "FENCE_ENABLE",
        42 => "FENCE_DISABLE",
        43 => "ACRO_TRAINER_OFF",
        44 => "ACRO_TRAINER_LEVELING",
        45 => "ACRO_TRAINER_LIMITED",
        46 => "GRIPPER_GRAB",
        47 => "GRIPPER_RELEASE",
        49 => "PARACHUTE_DISABLED",
        50 => "PARACHUTE_ENABLED",
        51 => "PARACHUTE_RELEASED",
        52 => "LANDING_GEAR_DEPLOYED",
        53 => "LANDING_GEAR_RETRACTED",
        54 => "MOTORS_EMERGENCY_STOPPED",
        55 => "MOTORS_EMERGENCY_STOP_CLEARED",
        56 => "MOTORS_INTERLOCK_DISABLED",
        57 => "MOTORS_INTERLOCK_ENABLED",
        58 => "ROTOR_RUNUP_COMPLETE",
        59 => "ROTOR_SPEED_BELOW_CRITICAL",
        60 => "EKF_ALT_RESET",
        61 => "LAND_CANCELLED_BY_PILOT",
        62 => "EKF_YAW_RESET",
        _ => return None,
    })
}

/// Vehicle type from a firmware banner such as "ArduCopter V3.3-dev (c3349c61)".
fn vehicle_type(text: &str) -> Option<&'static str> {
    const PREFIXES: [(&str, &str); 12] = [
        ("ArduCopter", "copter"),
        ("APM:Copter", "copter"),
        ("ArduHeli", "copter"),
        ("ArduPlane", "plane"),
        ("APM:Plane", "plane"),
        ("ArduRover", "rover"),
        ("APMrover2", "rover"),
        ("APM:Rover", "rover"),
        ("ArduSub", "sub"),
        ("AntennaTracker", "tracker"),
        ("ArduTracker", "tracker"),
        ("Blimp", "blimp"),
    ];
    let text = text.trim_start();
    PREFIXES
        .iter()
        .find(|(p, _)| text.starts_with(p))
        .map(|(_, v)| *v)
}

/// Euler angles (deg; ZYX order: yaw about down, then pitch, then roll) to
/// the Hamilton quaternion `[w, x, y, z]` rotating body FRD into NED.
/// The sign is chosen with `w >= 0` so that yaw wrapping 359.9° -> 0.1°
/// does not flip the quaternion.
fn euler_deg_to_quat(roll: f64, pitch: f64, yaw: f64) -> [f64; 4] {
    // libm, not std: native and wasm must give identical bits.
    let (sr, cr) = libm::sincos(roll.to_radians() / 2.0);
    let (sp, cp) = libm::sincos(pitch.to_radians() / 2.0);
    let (sy, cy) = libm::sincos(yaw.to_radians() / 2.0);
    let q = [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ];
    if q[0] < 0.0 {
        q.map(|v| -v)
    } else {
        q
    }
}

// ---------------------------------------------------------------------------

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    const LOITER: &[u8] = include_bytes!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/ardupilot/Loiter_RTL.bin"
    ));
    const PLANE: &[u8] = include_bytes!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/ardupilot/truncated_plane.BIN"
    ));

    fn close(a: f64, b: f64, eps: f64) -> bool {
        (a - b).abs() <= eps
    }

    macro_rules! assert_close {
        ($a:expr, $b:expr, $eps:expr) => {{
            let (a, b): (f64, f64) = ($a, $b);
            assert!(
                close(a, b, $eps),
                "{} = {a} vs {} = {b} (eps {})",
                stringify!($a),
                stringify!($b),
                $eps
            );
        }};
    }

    fn count(d: &LogData, name: &str) -> u64 {
        d.topic_counts
            .iter()
            .find(|(n, _)| n == name)
            .map_or(0, |(_, c)| *c)
    }

    fn meta<'a>(d: &'a LogData, key: &str) -> Option<&'a str> {
        d.meta
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    fn loiter() -> LogData {
        read_dataflash(LOITER).expect("Loiter_RTL.bin parses")
    }

    /// Loiter_RTL.bin (no GPA): eph is HDOP; UTC from the first fix (GPS
    /// week 1817, 403369800 ms at boot 20.674 s, pymavlink), 16 leap
    /// seconds; the MODE numbers as copter modes; MSG, ERR and EV listed.
    #[test]
    fn loiter_extras() {
        use crate::extras::{iso_utc, EphSource};
        let d = loiter();
        let x = &d.extras;
        assert_eq!(x.eph_source, EphSource::Hdop);
        let t0 = d.samples[0].t;
        assert_eq!(t0, 20.664);
        assert_eq!(iso_utc(x.utc_at_boot.unwrap() + t0), "2014-11-06T16:02:33.790Z");
        let modes: Vec<(f64, &str)> = x.modes.iter().map(|m| (m.t, m.mode.as_str())).collect();
        assert_eq!(
            modes,
            [(20.664, "ALT_HOLD"), (41.074, "LOITER"), (44.644, "LAND"), (51.564, "ALT_HOLD"), (96.008, "LOITER"), (101.99, "LAND"), (114.79, "ALT_HOLD"), (126.389, "LOITER"), (227.23, "RTL")]
        );
        // 2 MSG + 5 ERR + 137 EV (pymavlink's counts).
        assert_eq!(x.messages.len(), 144);
        assert_eq!(x.messages[0].text, "ArduCopter V3.3-dev (c3349c61)");
        assert_eq!(x.messages.iter().filter(|m| m.text.starts_with("ERR ")).count(), 5);
        assert_eq!(x.messages.iter().filter(|m| m.level == "event").count(), 137);
        assert!(x.messages.iter().any(|m| m.level == "error" && m.text == "ERR CRASH_CHECK: code 1"));
        assert!(x.messages.windows(2).all(|w| w[0].t <= w[1].t));
    }

    /// The plane log's MODE numbers are plane modes; its u-blox `UBX3`
    /// records and the newer truncated plane log's GPA give eph in metres.
    #[test]
    fn plane_modes_and_gpa_eph() {
        use crate::extras::EphSource;
        let b = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/ardupilot/erle_plane_4-12-2014_329.BIN")).unwrap();
        let d = read_dataflash(&b).unwrap();
        let names: Vec<&str> = d.extras.modes.iter().map(|m| m.mode.as_str()).collect();
        assert_eq!(names, ["MANUAL", "CIRCLE", "MANUAL", "FBWA", "RTL", "MANUAL", "FBWA", "FBWB", "FBWA"]);
        assert_eq!(d.extras.eph_source, EphSource::Eph);
        let t = read_dataflash(PLANE).unwrap();
        assert_eq!(t.extras.eph_source, EphSource::Eph);
        assert_eq!(t.extras.modes.iter().map(|m| m.mode.as_str()).collect::<Vec<_>>(), ["MANUAL"]);
    }

    /// 2014-era logs write the u-blox accuracies (`UBX3`: hAcc, vAcc m,
    /// sAcc m/s) just before the `GPS` message of the same boot time; they
    /// become the fix's `eph`, `epv` and `sacc` (values from pymavlink). A
    /// fix without one keeps HDop as its eph (Loiter_RTL, `EphSource::Hdop`).
    #[test]
    fn ubx3_accuracies_go_onto_their_fix() {
        use crate::extras::EphSource;
        let cases = [
            ("erle_copter_26-11-2014_181.BIN", [(35.299, [1.315000057220459, 2.0820000171661377, 0.23999999463558197]), (35.379, [1.311000108718872, 2.076000213623047, 0.28999999165534973])]),
            ("erle_plane_4-12-2014_329.BIN", [(16.738, [3.434000253677368, 4.314000129699707, 0.6200000047683716]), (16.938, [3.3990001678466797, 4.265000343322754, 0.5199999809265137])]),
        ];
        for (name, fixes) in cases {
            let b = std::fs::read(format!("{}/../../shared/data/ardupilot/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
            let d = read_dataflash(&b).unwrap();
            assert_eq!(d.extras.eph_source, EphSource::Eph, "{name}");
            let mut gps = d.samples.iter().filter(|s| s.has_position());
            for (t, [h, v, sa]) in fixes {
                let s = gps.next().unwrap();
                assert_close!(s.t, t, 1e-9);
                assert_eq!([s.eph, s.epv, s.sacc], [h, v, sa], "{name} at {t} s");
            }
            // Every fix has its record: the receiver writes one per solution.
            assert!(d.samples.iter().filter(|s| s.has_position()).all(|s| s.sacc > 0.0), "{name}");
        }
        let b = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/ardupilot/Loiter_RTL.bin")).unwrap();
        let d = read_dataflash(&b).unwrap();
        assert_eq!(d.extras.eph_source, EphSource::Hdop);
        assert!(d.samples.iter().all(|s| s.sacc.is_nan()));
    }

    // ---- Euler -> quaternion -------------------------------------------

    #[test]
    fn quaternion_hand_cases() {
        let h = std::f64::consts::FRAC_1_SQRT_2; // cos 45° = sin 45°
        let cases: [([f64; 3], [f64; 4]); 6] = [
            ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]),
            ([0.0, 0.0, 90.0], [h, 0.0, 0.0, h]),
            ([90.0, 0.0, 0.0], [h, h, 0.0, 0.0]),
            ([0.0, 90.0, 0.0], [h, 0.0, h, 0.0]),
            // yaw 90 then roll 90: qz(90) * qx(90) = (½, ½, ½, ½)
            ([90.0, 0.0, 90.0], [0.5, 0.5, 0.5, 0.5]),
            // yaw 180: (0, 0, 0, 1)
            ([0.0, 0.0, 180.0], [0.0, 0.0, 0.0, 1.0]),
        ];
        for ([r, p, y], want) in cases {
            let q = euler_deg_to_quat(r, p, y);
            for (a, b) in q.iter().zip(want) {
                assert_close!(*a, b, 1e-12);
            }
        }
        // Yaw 359.9° is canonicalised next to yaw 0.1°, not to its negative.
        let a = euler_deg_to_quat(0.0, 0.0, 359.9);
        let b = euler_deg_to_quat(0.0, 0.0, 0.1);
        assert!(a[0] > 0.99 && b[0] > 0.99);
        assert_close!(a[3], -b[3], 1e-12);
    }

    #[test]
    fn quaternion_rotates_body_x_to_east_at_yaw_90() {
        // v_ned = q v_body q*; body x (forward) with yaw 90° points east.
        let [w, x, y, z] = euler_deg_to_quat(0.0, 0.0, 90.0);
        let r00 = 1.0 - 2.0 * (y * y + z * z);
        let r10 = 2.0 * (x * y + w * z);
        let r20 = 2.0 * (x * z - w * y);
        assert_close!(r00, 0.0, 1e-12);
        assert_close!(r10, 1.0, 1e-12);
        assert_close!(r20, 0.0, 1e-12);
        // Pitch up 30°: body x gets a negative down component (climbs).
        let [w, x, y, z] = euler_deg_to_quat(0.0, 30.0, 0.0);
        assert_close!(2.0 * (x * z - w * y), -0.5, 1e-12);
    }

    // ---- Real logs ---------------------------------------------------------

    /// Counts cross-checked with pymavlink 2.4.50:
    /// `DFReader.DFReader_binary(path).recv_msg()` until None, by get_type().
    #[test]
    fn loiter_counts_match_pymavlink() {
        let d = loiter();
        assert_eq!(d.format, "dataflash");
        assert_eq!(count(&d, "GPS"), 992);
        assert_eq!(count(&d, "IMU"), 11775);
        assert_eq!(count(&d, "ATT"), 2356);
        assert_eq!(count(&d, "BARO"), 2357);
        assert_eq!(count(&d, "FMT"), 42);
        assert_eq!(count(&d, "PARM"), 392);
        assert_eq!(count(&d, "MSG"), 2);
        assert_eq!(count(&d, "ERR"), 5);
        let names: Vec<&str> = d.topic_counts.iter().map(|(n, _)| n.as_str()).collect();
        let mut sorted = names.clone();
        sorted.sort_unstable();
        assert_eq!(names, sorted);
        assert_eq!(d.topic_counts.len(), 25);
        // One row per GPS, IMU and BARO message; ATT has no rows.
        assert_eq!(d.samples.len(), 992 + 11775 + 2357);
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        assert!(d.missing.is_empty(), "{:?}", d.missing);
    }

    #[test]
    fn loiter_meta_and_time_base() {
        let d = loiter();
        assert_eq!(meta(&d, "firmware"), Some("ArduCopter V3.3-dev (c3349c61)"));
        assert_eq!(meta(&d, "vehicle_type"), Some("copter"));
        assert_eq!(meta(&d, "time_base"), Some("TimeMS"));
        // First row: IMU at 20.664 s boot; last: IMU at 278.590 s.
        assert_close!(d.samples[0].t, 20.664, 1e-9);
        assert_close!(d.samples[d.samples.len() - 1].t, 278.590, 1e-9);
        let dur: f64 = meta(&d, "duration")
            .and_then(|v| v.parse().ok())
            .unwrap_or(f64::NAN);
        assert_close!(dur, 257.926, 1e-6);
        assert!(d.samples.windows(2).all(|w| w[0].t <= w[1].t));
    }

    #[test]
    fn loiter_gps_uses_boot_time_t_not_time_of_week() {
        let d = loiter();
        let gps: Vec<&Sample> = d.samples.iter().filter(|s| s.fix.is_finite()).collect();
        assert_eq!(gps.len(), 992);
        // T runs 20.674 .. 277.419 s; TimeMS (GPS week ms) would be ~403369 s.
        assert_close!(gps[0].t, 20.674, 1e-9);
        assert_close!(gps[gps.len() - 1].t, 277.419, 1e-9);
        // About 5.6 Hz: the median interval is 0.18 s.
        let mut dt: Vec<f64> = gps.windows(2).map(|w| w[1].t - w[0].t).collect();
        dt.sort_by(f64::total_cmp);
        let median = dt[dt.len() / 2];
        assert_close!(1.0 / median, 5.6, 0.1);
    }

    #[test]
    fn loiter_first_fix_matches_pymavlink() {
        let d = loiter();
        let s = d
            .samples
            .iter()
            .find(|s| s.has_fix())
            .copied()
            .unwrap_or_default();
        // pymavlink: Status 3, NSats 7, HDop 2.54, Lat 42.845769,
        // Lng -2.6885322, Alt 521.31, Spd 0.26, GCrs 330.59, VZ -0.1, T 20674.
        assert_close!(s.t, 20.674, 1e-9);
        assert_close!(s.fix, 3.0, 0.0);
        assert_close!(s.sats, 7.0, 0.0);
        assert_close!(s.lat, 42.845769, 1e-9);
        assert_close!(s.lon, -2.6885322, 1e-9);
        assert_close!(s.alt, 521.31, 1e-9);
        assert_close!(s.eph, 2.54, 1e-9);
        assert!(s.epv.is_nan());
        assert_close!(s.vn, 0.22649331, 1e-7);
        assert_close!(s.ve, -0.12767451, 1e-7);
        assert_close!(s.vd, -0.1, 1e-6);
        assert!(s.ax.is_nan() && s.baro.is_nan() && s.qw.is_nan());
    }

    #[test]
    fn loiter_gps_outage_97_to_103_4() {
        let d = loiter();
        let gps = || d.samples.iter().filter(|s| s.fix.is_finite());
        assert_eq!(
            gps()
                .filter(|s| s.t > 98.0 && s.t < 103.0 && s.has_fix())
                .count(),
            0
        );
        assert!(gps().any(|s| s.t > 96.0 && s.t < 96.5 && s.has_fix()));
        assert!(gps().any(|s| s.t > 104.0 && s.t < 104.5 && s.has_fix()));
        // The receiver reported the outage: Status 0 at 98.217, 1 at 103.399,
        // without a position; and nothing else between 97.0 and 103.6 s.
        let inside: Vec<&Sample> = gps().filter(|s| s.t > 97.0 && s.t < 103.6).collect();
        assert_eq!(inside.len(), 2);
        assert_close!(inside[0].t, 98.217, 1e-9);
        assert_close!(inside[0].fix, 0.0, 0.0);
        assert_close!(inside[1].t, 103.399, 1e-9);
        assert_close!(inside[1].fix, 1.0, 0.0);
        assert!(inside
            .iter()
            .all(|s| s.reports_no_fix() && !s.has_position() && !s.has_velocity()));
        // Every other GPS row has a 3D fix.
        assert_eq!(gps().filter(|s| s.fix == 3.0 && s.has_fix()).count(), 990);
    }

    #[test]
    fn loiter_logging_pause_has_no_rows() {
        // The README's 30.7-53.1 s is counted from the first IMU sample
        // (20.664 s boot); in boot time the pause is 51.564 .. 73.788 s.
        let d = loiter();
        assert_eq!(
            d.samples
                .iter()
                .filter(|s| s.t > 51.6 && s.t < 73.78)
                .count(),
            0
        );
        assert!(d.samples.iter().any(|s| s.t > 51.4 && s.t <= 51.6));
        assert!(d.samples.iter().any(|s| s.t >= 73.78 && s.t < 74.0));
        let t0 = d.samples[0].t;
        assert_eq!(
            d.samples
                .iter()
                .filter(|s| s.t - t0 > 31.0 && s.t - t0 < 53.1)
                .count(),
            0
        );
    }

    #[test]
    fn loiter_imu_and_attitude() {
        let d = loiter();
        let imu: Vec<&Sample> = d.samples.iter().filter(|s| s.has_accel()).collect();
        assert_eq!(imu.len(), 11775);
        // pymavlink first IMU: AccZ -9.757428, GyrX 0.0029209.
        assert_close!(imu[0].az, -9.757428169250488, 1e-9);
        assert_close!(imu[0].gx, 0.002920900471508503, 1e-12);
        // First ATT (20.664 s, same time as that IMU row): roll 0.27, pitch 0.58, yaw 0.58 deg.
        let q = euler_deg_to_quat(0.27, 0.58, 0.58);
        assert_close!(imu[0].qw, q[0], 1e-12);
        assert_close!(imu[0].qz, q[3], 1e-12);
        // ATT is 10 Hz, so every IMU row gets an attitude at most 0.1 s old.
        let with = imu.iter().filter(|s| s.has_attitude()).count();
        assert_eq!(with, imu.len());
        for s in &imu {
            let n = s.qw * s.qw + s.qx * s.qx + s.qy * s.qy + s.qz * s.qz;
            assert_close!(n, 1.0, 1e-12);
            assert!(s.qw >= 0.0);
        }
        // No attitude on GPS or BARO rows.
        assert!(d
            .samples
            .iter()
            .filter(|s| !s.has_accel())
            .all(|s| s.qw.is_nan()));
        // BARO rows: 2357, first Alt 0.0439 m.
        let baro: Vec<&Sample> = d.samples.iter().filter(|s| s.has_baro()).collect();
        assert_eq!(baro.len(), 2357);
        assert_close!(baro[0].baro, 0.043892595916986465, 1e-9);
    }

    #[test]
    fn loiter_vz_is_positive_down() {
        // Correlate VZ with the rate of change of GPS altitude (positive up).
        let d = loiter();
        let fixes: Vec<&Sample> = d.samples.iter().filter(|s| s.has_fix()).collect();
        let mut pairs = Vec::new();
        for w in fixes.windows(3) {
            let dt = w[2].t - w[0].t;
            if dt > 0.0 && dt < 1.0 {
                pairs.push((w[1].vd, (w[2].alt - w[0].alt) / dt));
            }
        }
        let n = pairs.len() as f64;
        let (ma, mb) = pairs
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
        let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
        for (a, b) in &pairs {
            sab += (a - ma) * (b - mb);
            saa += (a - ma) * (a - ma);
            sbb += (b - mb) * (b - mb);
        }
        let corr = sab / (saa * sbb).sqrt();
        assert!(corr < -0.7, "corr(vd, dAlt/dt) = {corr}");
    }

    #[test]
    fn truncated_plane_reads_partially() {
        let d = read_dataflash(PLANE).expect("partial read is Ok");
        assert!(
            d.warnings
                .iter()
                .any(|w| w.contains("truncated at byte 65536 in the middle of a")),
            "{:?}",
            d.warnings
        );
        assert_eq!(meta(&d, "time_base"), Some("TimeUS"));
        assert_eq!(
            meta(&d, "firmware"),
            Some("ArduPlane V3.8.2-dev (8178ab40)")
        );
        assert_eq!(meta(&d, "vehicle_type"), Some("plane"));
        // pymavlink 2.4.50 on the same file.
        assert_eq!(count(&d, "IMU"), 45);
        assert_eq!(count(&d, "IMU2"), 45);
        assert_eq!(count(&d, "GPS"), 5);
        assert_eq!(count(&d, "ATT"), 24);
        assert_eq!(count(&d, "BARO"), 8);
        assert_eq!(count(&d, "FMT"), 132);
        assert_eq!(count(&d, "PARM"), 809);
        assert_eq!(d.samples.iter().filter(|s| s.has_accel()).count(), 45);
        // First IMU: TimeUS 81794643, AccZ -9.780994.
        let imu = d
            .samples
            .iter()
            .find(|s| s.has_accel())
            .copied()
            .unwrap_or_default();
        assert_close!(imu.t, 81.794643, 1e-9);
        assert_close!(imu.az, -9.780994415283203, 1e-9);
        // First GPS: TimeUS 81855471, Lat -35.3626277, Lng 149.1653034, Alt 588.82.
        let g = d
            .samples
            .iter()
            .find(|s| s.has_fix())
            .copied()
            .unwrap_or_default();
        assert_close!(g.t, 81.855471, 1e-9);
        assert_close!(g.lat, -35.3626277, 1e-9);
        assert_close!(g.lon, 149.1653034, 1e-9);
        assert_close!(g.alt, 588.82, 1e-9);
        assert_close!(g.vd, 0.35, 1e-6);
        assert!(d.missing.is_empty(), "{:?}", d.missing);
    }

    // ---- Robustness ------------------------------------------------------

    use crate::TestRng as Rng;

    #[test]
    fn truncation_at_many_offsets_never_panics() {
        let head = &LOITER[..LOITER.len().min(60_000)];
        for cut in (0..head.len()).step_by(97).chain(0..200) {
            let _ = read_dataflash(&head[..cut]);
        }
        for cut in (0..PLANE.len()).step_by(61) {
            let _ = read_dataflash(&PLANE[..cut]);
        }
        // A cut inside a message of the full log is reported with its offset.
        let cut = &LOITER[..LOITER.len() - 5];
        let d = read_dataflash(cut).expect("ok");
        let want = format!("truncated at byte {}", cut.len());
        assert!(
            d.warnings.iter().any(|w| w.starts_with(&want)),
            "{:?}",
            d.warnings
        );
    }

    #[test]
    fn random_byte_flips_never_panic() {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        let base = &LOITER[..LOITER.len().min(40_000)];
        for round in 0..150 {
            let mut buf = if round % 2 == 0 {
                base.to_vec()
            } else {
                PLANE.to_vec()
            };
            for _ in 0..1 + rng.index(40) {
                let i = rng.index(buf.len());
                if let Some(b) = buf.get_mut(i) {
                    *b = rng.next() as u8;
                }
            }
            let _ = read_dataflash(&buf);
        }
        // Pure noise, and noise seeded with headers.
        for _ in 0..30 {
            let mut buf: Vec<u8> = (0..4000).map(|_| rng.next() as u8).collect();
            for _ in 0..200 {
                let i = rng.index(buf.len() - 3);
                buf[i] = HEAD1;
                buf[i + 1] = HEAD2;
                buf[i + 2] = if rng.index(2) == 0 {
                    FMT_TYPE
                } else {
                    rng.next() as u8
                };
            }
            let _ = read_dataflash(&buf);
        }
    }

    /// Message start offsets, walking the lengths declared by FMT.
    fn boundaries(bytes: &[u8]) -> Vec<usize> {
        let mut lens = [0usize; 256];
        lens[usize::from(FMT_TYPE)] = FMT_LEN;
        let (mut out, mut pos) = (Vec::new(), 0);
        while pos + HEADER_LEN <= bytes.len() {
            let ty = bytes[pos + 2];
            let l = lens[usize::from(ty)];
            if l == 0 || pos + l > bytes.len() {
                break;
            }
            if ty == FMT_TYPE {
                if let Some((t, lay, _)) = Layout::from_fmt(&bytes[pos..]) {
                    lens[usize::from(t)] = lay.len;
                }
            }
            out.push(pos);
            pos += l;
        }
        out
    }

    #[test]
    fn resyncs_over_garbage_and_counts_it() {
        let d0 = loiter();
        let total = |d: &LogData| d.topic_counts.iter().map(|(_, c)| c).sum::<u64>();
        let b = boundaries(LOITER);
        assert_eq!(b.len() as u64, total(&d0)); // the walk agrees with the reader
                                                // 1000 bytes of noise (no 0xA3 in it) inserted at a message boundary.
        let at = b[b.len() / 3];
        let mut rng = Rng(7);
        let mut buf = LOITER[..at].to_vec();
        buf.extend((0..1000).map(|_| (rng.next() as u8) & 0x7f));
        buf.extend_from_slice(&LOITER[at..]);
        let d = read_dataflash(&buf).expect("ok");
        assert_eq!(
            d.warnings,
            vec!["skipped 1000 unreadable bytes in 1 places (resynchronised on the next 0xA3 0x95 header)"]
        );
        // Same rows bit for bit (NaN != NaN, so compare the bits).
        let bits = |d: &LogData| -> Vec<u64> {
            d.samples
                .iter()
                .flat_map(|s| (0..26).map(move |i| s.get(i).to_bits()))
                .collect()
        };
        assert_eq!(d.samples.len(), d0.samples.len());
        assert!(bits(&d) == bits(&d0));
        // A broken header costs exactly that message.
        let mut buf = LOITER.to_vec();
        buf[b[b.len() / 2]] = 0;
        let d = read_dataflash(&buf).expect("ok");
        assert!(
            d.warnings.iter().any(|w| w.starts_with("skipped")),
            "{:?}",
            d.warnings
        );
        assert_eq!(total(&d) + 1, total(&d0));
    }

    #[test]
    fn detection_and_errors() {
        assert!(is_dataflash(LOITER));
        assert!(is_dataflash(PLANE));
        assert!(!is_dataflash(b""));
        assert!(!is_dataflash(&[0xA3, 0x95]));
        assert!(!is_dataflash(b"ULog\x01\x12\x35"));
        assert!(read_dataflash(b"").is_err());
        assert!(read_dataflash(b"t,lat,lon\n0,1,2\n").is_err());
        // FMT messages only: readable but nothing usable.
        let e = read_dataflash(&LOITER[..FMT_LEN * 3]).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("no GPS, IMU or BARO rows"), "{e}");
        assert!(!e.contains('\n'));
        // The error is the whole file's, with the counts that say how much was read.
        let e = read_dataflash(&LOITER[..FMT_LEN * 3]).unwrap_err();
        assert_eq!((e.format, e.pos, e.unrecognised), ("dataflash", crate::error::LogPos::File, false));
        assert_eq!(e.message, format!("DataFlash log has no GPS, IMU or BARO rows (3 messages in {} bytes)", FMT_LEN * 3));
        assert_eq!(e.to_string(), e.message);
    }

    // ---- Synthetic logs ----------------------------------------------------

    fn fmt_msg(ty: u8, len: u8, name: &str, format: &str, columns: &str) -> Vec<u8> {
        let mut m = vec![HEAD1, HEAD2, FMT_TYPE, ty, len];
        let mut put = |s: &str, n: usize| {
            let mut b = s.as_bytes().to_vec();
            b.resize(n, 0);
            m.extend_from_slice(&b);
        };
        put(name, 4);
        put(format, 16);
        put(columns, 64);
        assert_eq!(m.len(), FMT_LEN);
        m
    }

    fn layout_of(fmt: &[u8]) -> Layout {
        Layout::from_fmt(fmt).map(|(_, l, _)| l).expect("layout")
    }

    fn col<'a>(l: &'a Layout, name: &str) -> &'a Col {
        l.cols.iter().find(|c| c.name == name).expect("column")
    }

    #[test]
    fn every_format_char_decodes() {
        // Two types (16 format characters at most per FMT).
        let f1 = fmt_msg(
            10,
            3 + 1 + 1 + 2 + 2 + 4 + 4 + 4 + 8 + 2 + 2 + 4 + 4 + 4 + 1 + 8 + 8,
            "NUM",
            "bBhHiIfdcCeELMqQ",
            "b,B,h,H,i,I,f,d,c,C,e,E,L,M,q,Q",
        );
        let l = layout_of(&f1);
        assert_eq!(l.cols.len(), 16);
        let mut m = vec![HEAD1, HEAD2, 10];
        m.extend_from_slice(&(-5i8).to_le_bytes());
        m.extend_from_slice(&250u8.to_le_bytes());
        m.extend_from_slice(&(-30000i16).to_le_bytes());
        m.extend_from_slice(&60000u16.to_le_bytes());
        m.extend_from_slice(&(-2_000_000_000i32).to_le_bytes());
        m.extend_from_slice(&4_000_000_000u32.to_le_bytes());
        m.extend_from_slice(&1.5f32.to_le_bytes());
        m.extend_from_slice(&(-2.25e100f64).to_le_bytes());
        m.extend_from_slice(&(-1234i16).to_le_bytes()); // c: -12.34
        m.extend_from_slice(&35999u16.to_le_bytes()); // C: 359.99
        m.extend_from_slice(&52131i32.to_le_bytes()); // e: 521.31
        m.extend_from_slice(&4_000_000_000u32.to_le_bytes()); // E: 4e7
        m.extend_from_slice(&428457690i32.to_le_bytes()); // L: 42.845769
        m.extend_from_slice(&5u8.to_le_bytes()); // M: mode 5
        m.extend_from_slice(&(-9_000_000_000i64).to_le_bytes());
        m.extend_from_slice(&81_794_643u64.to_le_bytes());
        assert_eq!(m.len(), l.len);
        let want = [
            -5.0, 250.0, -30000.0, 60000.0, -2e9, 4e9, 1.5, -2.25e100, -12.34, 359.99, 521.31, 4e7,
            42.845769, 5.0, -9e9, 81794643.0,
        ];
        for (c, w) in l.cols.iter().zip(want) {
            assert_eq!(read_num(&m, c.off, c.ch), Some(w), "column {}", c.name);
        }

        let f2 = fmt_msg(11, 3 + 4 + 16 + 64 + 64 + 2, "TXT", "nNZag", "n,N,Z,a,g");
        let l = layout_of(&f2);
        let mut m = vec![HEAD1, HEAD2, 11];
        m.extend_from_slice(b"GPS\0");
        let mut n16 = b"SYSID_SW_MREV".to_vec();
        n16.resize(16, 0);
        m.extend_from_slice(&n16);
        let mut z = b"ArduCopter V3.3-dev (c3349c61)".to_vec();
        z.resize(64, 0);
        m.extend_from_slice(&z);
        for i in 0..32i16 {
            m.extend_from_slice(&(i * 1000 - 16000).to_le_bytes());
        }
        m.extend_from_slice(&0x3E00u16.to_le_bytes()); // half 1.5
        assert_eq!(m.len(), l.len);
        assert_eq!(read_str(&m, col(&l, "n").off, b'n').as_deref(), Some("GPS"));
        assert_eq!(
            read_str(&m, col(&l, "N").off, b'N').as_deref(),
            Some("SYSID_SW_MREV")
        );
        assert_eq!(
            read_str(&m, col(&l, "Z").off, b'Z').as_deref(),
            Some("ArduCopter V3.3-dev (c3349c61)")
        );
        let a = read_i16_array(&m, col(&l, "a").off).unwrap_or([0; 32]);
        assert_eq!((a[0], a[31]), (-16000, 15000));
        assert_eq!(read_num(&m, col(&l, "a").off, b'a'), None);
        assert_eq!(read_num(&m, col(&l, "g").off, b'g'), Some(1.5));
        assert_eq!(f16_to_f64(0xC000), -2.0);
        assert_eq!(f16_to_f64(0x0001), 2f64.powi(-24));
        assert!(f16_to_f64(0x7C00).is_infinite() && f16_to_f64(0x7E00).is_nan());
        // Reads past the message end are refused, never panic.
        assert_eq!(read_num(&m[..10], 8, b'i'), None);
        assert_eq!(read_str(&m, usize::MAX - 2, b'Z'), None);
        assert_eq!(read_num(&m, usize::MAX, b'Q'), None);
    }

    #[test]
    fn fmt_edge_cases() {
        // Unknown char: later columns dropped, a warning.
        let (_, l, w) = Layout::from_fmt(&fmt_msg(12, 9, "ODD", "IxB", "T,X,B")).expect("parsed");
        assert_eq!(l.cols.len(), 1);
        assert!(w.unwrap_or_default().contains("unknown format character"));
        // Length disagreeing with the format: fields past the length unmapped.
        let (_, l, w) = Layout::from_fmt(&fmt_msg(
            13,
            9,
            "IMU",
            "Iffffff",
            "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ",
        ))
        .expect("parsed");
        assert!(w.unwrap_or_default().contains("needs 31"));
        assert!(l.time.is_some() && l.role(IMU_ACCX).is_none());
        // Length below a header: unusable.
        assert!(Layout::from_fmt(&fmt_msg(14, 2, "BAD", "", "")).is_none());
        // GPS: T, not TimeMS, is the clock; IMU: TimeMS is.
        let l = layout_of(&fmt_msg(
            130,
            45,
            "GPS",
            "BIHBcLLeeEefI",
            "Status,TimeMS,Week,NSats,HDop,Lat,Lng,RelAlt,Alt,Spd,GCrs,VZ,T",
        ));
        assert_eq!(l.time.map(|(f, u)| (f.off, u)), Some((41, 1e3)));
    }

    /// A synthetic TimeUS-era log: GPS + GPA with instances, IMU instances,
    /// ATT, BARO, FMTU, a no-fix GPS and a message cut at the end.
    #[test]
    fn synthetic_timeus_log() {
        let mut log = Vec::new();
        log.extend(fmt_msg(
            130,
            3 + 8 + 1 + 1 + 4 + 2 + 1 + 2 + 4 + 4 + 4 + 4 + 4 + 4 + 4 + 1,
            "GPS",
            "QBBIHBcLLeffffB",
            "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,Alt,Spd,GCrs,VZ,Yaw,U",
        ));
        log.extend(fmt_msg(
            131,
            3 + 8 + 1 + 2 + 2 + 2 + 2 + 4 + 1 + 4 + 2,
            "GPA",
            "QBCCCCfBIH",
            "TimeUS,I,VDop,HAcc,VAcc,SAcc,YAcc,VV,SMS,Delta",
        ));
        log.extend(fmt_msg(
            132,
            3 + 8 + 1 + 24,
            "IMU",
            "QBffffff",
            "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ",
        ));
        log.extend(fmt_msg(
            133,
            3 + 8 + 8,
            "ATT",
            "Qcccc",
            "TimeUS,DesRoll,Roll,DesPitch,Pitch",
        ));
        log.extend(fmt_msg(134, 3 + 8 + 1 + 4, "BARO", "QBi", "TimeUS,I,Alt"));
        log.extend(fmt_msg(
            135,
            3 + 8 + 1 + 16 + 16,
            "FMTU",
            "QBNN",
            "TimeUS,FmtType,UnitIds,MultIds",
        ));
        log.extend(fmt_msg(
            136,
            3 + 8 + 8 + 4,
            "ATT",
            "QcccccC",
            "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw",
        ));
        // FMTU: BARO Alt is an int32 in cm ('B' = 1e-2).
        let mut u = vec![HEAD1, HEAD2, 135];
        u.extend_from_slice(&0u64.to_le_bytes());
        u.push(134);
        u.extend_from_slice(b"s#m\0\0\0\0\0\0\0\0\0\0\0\0\0");
        u.extend_from_slice(b"F-B\0\0\0\0\0\0\0\0\0\0\0\0\0");
        log.extend(u);
        let gps = |t_us: u64, inst: u8, status: u8, lat: i32| {
            let mut m = vec![HEAD1, HEAD2, 130];
            m.extend_from_slice(&t_us.to_le_bytes());
            m.push(inst);
            m.push(status);
            m.extend_from_slice(&123_456u32.to_le_bytes());
            m.extend_from_slice(&2000u16.to_le_bytes());
            m.push(12);
            m.extend_from_slice(&77u16.to_le_bytes()); // HDop 0.77
            m.extend_from_slice(&lat.to_le_bytes());
            m.extend_from_slice(&1_491_653_034i32.to_le_bytes());
            m.extend_from_slice(&58_882i32.to_le_bytes());
            m.extend_from_slice(&2.0f32.to_le_bytes()); // Spd
            m.extend_from_slice(&90.0f32.to_le_bytes()); // GCrs: east
            m.extend_from_slice(&(-0.5f32).to_le_bytes()); // VZ: climbing
            m.extend_from_slice(&0.0f32.to_le_bytes());
            m.push(1);
            m
        };
        let imu = |t_us: u64, inst: u8, az: f32| {
            let mut m = vec![HEAD1, HEAD2, 132];
            m.extend_from_slice(&t_us.to_le_bytes());
            m.push(inst);
            for v in [0.01f32, 0.02, 0.03, 0.1, 0.2, az] {
                m.extend_from_slice(&v.to_le_bytes());
            }
            m
        };
        // ATT redefined with type 136 (Yaw present); 133 stays a second ATT type.
        let mut att = vec![HEAD1, HEAD2, 136];
        att.extend_from_slice(&1_000_000u64.to_le_bytes());
        for v in [0i16, 0, 0, 0, 0] {
            att.extend_from_slice(&v.to_le_bytes());
        }
        att.extend_from_slice(&9000u16.to_le_bytes()); // yaw 90°
        log.extend(att);
        log.extend(imu(1_000_000, 0, -9.8));
        log.extend(imu(1_000_000, 1, -9.7)); // instance 1: ignored
        log.extend(imu(1_600_000, 0, -9.81)); // attitude 0.6 s old: none
        log.extend(gps(1_100_000, 0, 3, -353_626_277));
        let mut gpa = vec![HEAD1, HEAD2, 131];
        gpa.extend_from_slice(&1_100_000u64.to_le_bytes());
        gpa.push(0);
        for v in [120u16, 150, 230, 40] {
            gpa.extend_from_slice(&v.to_le_bytes());
        }
        gpa.extend_from_slice(&0.0f32.to_le_bytes());
        gpa.push(1);
        gpa.extend_from_slice(&1100u32.to_le_bytes());
        gpa.extend_from_slice(&200u16.to_le_bytes());
        log.extend(gpa);
        log.extend(gps(1_100_000, 1, 3, -353_626_277)); // instance 1: ignored
        log.extend(gps(1_300_000, 0, 1, 0)); // no fix
        let mut baro = vec![HEAD1, HEAD2, 134];
        baro.extend_from_slice(&900_000u64.to_le_bytes());
        baro.push(0);
        baro.extend_from_slice(&1234i32.to_le_bytes());
        log.extend(baro);
        let full = log.len();
        log.extend(&imu(2_000_000, 0, -9.8)[..10]); // cut

        assert!(is_dataflash(&log));
        let d = read_dataflash(&log).expect("ok");
        assert_eq!(meta(&d, "time_base"), Some("TimeUS"));
        assert_eq!(
            d.warnings,
            vec![format!(
                "truncated at byte {} in the middle of a IMU message (starts at byte {full}, 36 bytes long)",
                log.len()
            )]
        );
        assert!(d.missing.is_empty(), "{:?}", d.missing);
        let t: Vec<f64> = d.samples.iter().map(|s| s.t).collect();
        assert_eq!(t, vec![0.9, 1.0, 1.1, 1.3, 1.6]);
        let [b, i0, g, nf, i1] = [0, 1, 2, 3, 4].map(|i| d.samples[i]);
        assert_close!(b.baro, 12.34, 1e-12); // FMTU multiplier applied
        assert_close!(i0.az, -9.8f32 as f64, 0.0);
        assert_close!(i0.qw, std::f64::consts::FRAC_1_SQRT_2, 1e-12);
        assert_close!(i0.qz, std::f64::consts::FRAC_1_SQRT_2, 1e-12);
        assert!(!i1.has_attitude());
        assert_close!(g.lat, -35.3626277, 1e-12);
        assert_close!(g.lon, 149.1653034, 1e-12);
        assert_close!(g.alt, 588.82, 1e-12);
        assert_close!(g.vn, 0.0, 1e-12);
        assert_close!(g.ve, 2.0, 1e-12);
        assert_close!(g.vd, -0.5, 0.0);
        assert_close!(g.eph, 1.5, 1e-12); // GPA HAcc wins over HDop
        assert_close!(g.epv, 2.3, 1e-12);
        assert_close!(g.sacc, 0.4, 1e-12); // GPA SAcc, m/s
        assert_close!(g.sats, 12.0, 0.0);
        assert_close!(nf.fix, 1.0, 0.0);
        assert!(nf.reports_no_fix() && !nf.has_position() && !nf.has_velocity() && nf.eph.is_nan() && nf.sacc.is_nan());
        assert_eq!(count(&d, "ATT"), 1);
        assert_eq!(count(&d, "IMU"), 3);
        assert_eq!(count(&d, "GPS"), 3);
    }

    /// Old (TimeMS-era) GPS without `T`: stamped from the preceding message.
    #[test]
    fn old_gps_without_boot_clock_uses_preceding_time() {
        let mut log = Vec::new();
        log.extend(fmt_msg(1, 3 + 4 + 4, "BARO", "If", "TimeMS,Alt"));
        log.extend(fmt_msg(
            2,
            3 + 1 + 4 + 1 + 4 + 4,
            "GPS",
            "BIBLL",
            "Status,TimeMS,NSats,Lat,Lng",
        ));
        let mut m = vec![HEAD1, HEAD2, 1];
        m.extend_from_slice(&5000u32.to_le_bytes());
        m.extend_from_slice(&3.5f32.to_le_bytes());
        log.extend(m);
        let mut m = vec![HEAD1, HEAD2, 2, 3];
        m.extend_from_slice(&400_000_000u32.to_le_bytes());
        m.push(9);
        m.extend_from_slice(&100_000_000i32.to_le_bytes());
        m.extend_from_slice(&200_000_000i32.to_le_bytes());
        log.extend(m);
        let d = read_dataflash(&log).expect("ok");
        assert_eq!(meta(&d, "time_base"), Some("TimeMS"));
        assert_eq!(d.samples.len(), 2);
        assert_close!(d.samples[1].t, 5.0, 0.0);
        assert_close!(d.samples[1].lat, 10.0, 0.0);
        assert!(d.samples[1].alt.is_nan());
        assert!(d.warnings.iter().any(|w| w.contains("time of week")));
        assert_eq!(d.missing, vec!["imu".to_string(), "attitude".to_string()]);
    }

    /// Parse throughput; run with
    /// `cargo test --release -- --ignored --nocapture throughput`.
    #[test]
    #[ignore]
    fn throughput() {
        let reps = 50;
        let start = std::time::Instant::now();
        let mut rows = 0;
        for _ in 0..reps {
            rows += read_dataflash(std::hint::black_box(LOITER)).map_or(0, |d| d.samples.len());
        }
        let s = start.elapsed().as_secs_f64();
        let mb = (LOITER.len() * reps) as f64 / 1e6;
        println!(
            "throughput: {:.1} MB/s ({rows} rows, {:.2} ms per parse)",
            mb / s,
            s * 1e3 / reps as f64
        );
    }
}

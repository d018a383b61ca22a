//! PX4 ULog reader: turns a `.ulg` file into fused navlog [`Sample`] rows.
//!
//! Follows the PX4 "ULog File Format" spec: a 16-byte header (magic, version,
//! start timestamp in µs), then messages `[u16 size][u8 type][payload]`, all
//! little-endian. Handled types: `B` flag bits (incl. appended-data offsets),
//! `F` formats (nested types, arrays, `_padding` fields), `I` info, `M`
//! multi-info, `P`/`Q` parameters and defaults, `A`/`R` (un)subscribe with
//! `multi_id`, `D` data, `L`/`C` (tagged) logging, `S` sync, `O` dropout.
//! Unknown types are skipped; implausible headers trigger a resync on the next
//! sync marker (as pyulog does).
//!
//! Design, because it runs in wasm on files of any size and is fuzzed:
//! - Streamed ([`UlogStream`]): the file comes in chunks of any size and
//!   only the bytes of the message being parsed are held (plus, while
//!   resynchronising, at most [`RESYNC_WINDOW`] bytes). Rows reach the sink in
//!   time order through a bounded [`Reorder`] buffer. The choice of GPS and
//!   baro source depends on the whole file, so a file is read twice: a first
//!   pass ([`UlogStream::plan`]) that only notes which topics have data, then
//!   the pass that emits rows. Nothing kept grows with the file: formats,
//!   topics, info strings and log lines are capped, and anything dropped at a
//!   cap is counted in the warnings.
//! - Never panics: all reads go through `get`, sizes use checked arithmetic,
//!   and no allocation is sized from an untrusted length.
//! - Fast: each subscription gets its field offsets once (at its `A`
//!   message), so a data message costs a table look-up, a size check, a
//!   counter increment and, only for the few mapped topics, a handful of
//!   fixed-offset reads.
//! - Linear on hostile files: a format redefinition invalidates the cached
//!   layouts (so later subscriptions always see the current format), and the
//!   work of computing layouts is bounded by a budget that grows with the
//!   bytes read ([`LAYOUT_WORK_PER_BYTE`]); a subscription over budget is
//!   ignored and counted in the warnings.
//!
//! Mapping (one [`Sample`] per message, `t` = the message's `timestamp` / 1e6, s):
//! - GPS: `vehicle_gps_position` (preferred) or `sensor_gps`, `multi_id` 0.
//! - IMU: `sensor_combined` -> ax..az, gx..gz, with the latest
//!   `vehicle_attitude` quaternion (if at most 0.5 s old) on each IMU row.
//! - Baro: `vehicle_air_data.baro_alt_meter`, else `sensor_baro.baro_alt_meter`,
//!   else (old logs) `sensor_combined.baro_alt_meter` on the IMU rows.
//!
//! Choices worth knowing:
//! - Row time is the publication `timestamp`, not `timestamp_sample`. For
//!   IMU rows that is the gyro sample; the accel sample is
//!   `accelerometer_timestamp_relative` µs away (a few ms) and is not shifted,
//!   only dropped when that offset is `RELATIVE_TIMESTAMP_INVALID`.
//! - A GPS row with fix_type < 2 keeps fix/sats/eph/epv/sacc but leaves position
//!   and velocity NaN ("no fix at this instant").
//! - Only `multi_id` 0 instances are mapped; all instances are counted in
//!   `topic_counts` ("topic", "topic/N"), which match pyulog's counts.
//! - Rows with timestamp 0 (never set by the publisher) are dropped.
//! - Unknown incompatible flag bits: the spec says refuse; we warn and read on.
//! - `meta`: ulog_version, duration_s (last data timestamp - header
//!   timestamp), every `I` info (perf dumps skipped, values cut at 256 bytes),
//!   timestamp), `I` info (perf dumps skipped, values cut at 256 bytes, at
//!   most [`MAX_INFO`] entries), `M` keys, parameter/log counts, gps_topic,
//!   warning-or-worse log lines.

use std::collections::HashMap;
use std::rc::Rc;

use super::extras::{EphSource, Extras};
use super::{LogData, LogError, LogSummary, NoRows, Reorder, RowSink, Window, FEED_CHUNK, REORDER_ROWS};
use crate::decimal::{Fixed, Shortest};
use crate::sample::Sample;

/// First 7 header bytes of every ULog file ("ULog" + 0x01 0x12 0x35).
pub(crate) const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// Payload of a sync (`S`) message; also what we scan for after corruption.
const SYNC_MAGIC: [u8; 8] = [0x2f, 0x73, 0x13, 0x20, 0x25, 0x0c, 0xbb, 0x12];
/// Magic (7) + version (1) + start timestamp (8).
const HEADER_LEN: usize = 16;
/// `*_timestamp_relative` value meaning "this sub-sample is invalid".
const RELATIVE_TIMESTAMP_INVALID: f64 = 2_147_483_647.0;
/// An attitude older than this (s) is not put on an IMU row.
const ATTITUDE_MAX_AGE_S: f64 = 0.5;
/// Nested-type depth limit: real logs nest 2-3 deep; this stops cycles.
const MAX_NESTING: u32 = 16;
/// Unknown message types larger than this (bytes), or of type/size 0, are
/// taken as corruption rather than a newer message type (pyulog's rule).
const MAX_PLAUSIBLE_UNKNOWN_SIZE: usize = 10_000;
/// At most this many warning-or-worse log lines go into `meta`.
const MAX_LOG_LINES: usize = 64;
/// Info (`I`) value kept per key, bytes.
const MAX_INFO_BYTES: usize = 256;
/// Info (`I`) entries kept in `meta` (real logs: 20 to 40). Keeps the report
/// small whatever the file: a file of 200,000 info messages gives a warning,
/// not a JSON report past the JS string limit.
pub const MAX_INFO: usize = 256;
/// How far past a corrupt header the reader looks for a sync marker, bytes.
/// Without one in that window it crawls byte by byte (pyulog's fallback);
/// the window bounds the bytes held while looking.
pub const RESYNC_WINDOW: u64 = 4 << 20;
/// Bytes of format definitions kept (real logs: 100-200 KB).
const MAX_FORMAT_BYTES: usize = 8 << 20;
/// Distinct (topic, multi_id) instances kept (real logs: a few hundred).
const MAX_TOPICS: usize = 1 << 14;
/// Layout computation allowed per byte read (field visits), on top of
/// [`LAYOUT_WORK_BASE`]: real logs use well under 1 per byte.
const LAYOUT_WORK_PER_BYTE: u64 = 16;
const LAYOUT_WORK_BASE: u64 = 1 << 22;
/// Reorder ranks at equal time: GPS rows, then attitude (applies to IMU rows
/// at its own time), then IMU rows, then baro rows: the order of the former
/// whole-file stable sort.
const RANK_GPS: u8 = 0;
const RANK_ATT: u8 = 1;
const RANK_IMU: u8 = 2;
const RANK_BARO: u8 = 3;

/// true when the bytes start with the ULog magic.
pub fn is_ulog(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// Parse a whole ULog file. Err only when nothing usable can be read
/// (too short, bad magic, no message after the header), with a one-line reason.
pub fn read_ulog(bytes: &[u8]) -> Result<LogData, LogError> {
    let mut rows = Vec::new();
    let summary = read_ulog_into(bytes, &mut rows)?;
    Ok(summary.with_rows(rows))
}

/// [`read_ulog`] with the rows going to `sink` (both passes over `bytes`).
pub fn read_ulog_into(bytes: &[u8], sink: &mut dyn RowSink) -> Result<LogSummary, LogError> {
    let mut scan = UlogStream::plan();
    for c in bytes.chunks(FEED_CHUNK) {
        scan.feed(c, &mut NoRows);
    }
    let mut s = scan.second_pass()?;
    for c in bytes.chunks(FEED_CHUNK) {
        s.feed(c, sink);
    }
    s.finish(sink)
}

/// Which sources have rows: found by the first pass, used by the second.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Seen {
    vgp: bool,
    sensor_gps: bool,
    air: bool,
    sensor_baro: bool,
}

/// An incremental ULog reader. Feed the file in chunks of any size
/// ([`UlogStream::feed`]), twice: the first stream ([`UlogStream::plan`])
/// emits nothing and only finds which topics have data; its
/// [`UlogStream::second_pass`] is fed the same bytes again and emits every
/// row; [`UlogStream::finish`] then gives the metadata and warnings. Memory is
/// bounded whatever the file's size.
pub struct UlogStream {
    win: Window,
    /// Absolute position of the next message.
    pos: u64,
    /// (version, start µs) once the 16-byte header is in.
    header: Option<(u8, u64)>,
    /// `None` in the first pass.
    plan: Option<Seen>,
    /// File length (second pass: what the first pass saw).
    total: Option<u64>,
    /// Set once parsing stopped for good (truncated last message).
    stopped: bool,
    /// Resync scan in progress: (from, scanned up to), absolute.
    scan: Option<(u64, u64)>,
    p: Parser,
}

impl UlogStream {
    /// The first pass.
    pub fn plan() -> Self {
        Self::with(None, None)
    }

    fn with(plan: Option<Seen>, total: Option<u64>) -> Self {
        UlogStream { win: Window::default(), pos: HEADER_LEN as u64, header: None, plan, total, stopped: false, scan: None, p: Parser::new(plan) }
    }

    /// Bytes fed so far.
    pub fn bytes(&self) -> u64 {
        self.win.end()
    }

    /// Bytes the reader holds now in its input window and reorder buffer
    /// (not counting formats and metadata, which are capped): what must
    /// not grow with the file.
    pub fn held_bytes(&self) -> usize {
        self.win.held_bytes() + self.p.emit.reorder.held_bytes()
    }

    /// True for the first pass (no rows yet).
    pub fn is_planning(&self) -> bool {
        self.plan.is_none()
    }

    /// End of the first pass: a fresh reader to be fed the same bytes again.
    /// Err when the file has no usable header or message.
    pub fn second_pass(mut self) -> Result<UlogStream, LogError> {
        self.run(true, &mut NoRows);
        self.check()?;
        let seen = self.p.seen;
        Ok(Self::with(Some(seen), Some(self.win.end())))
    }

    fn check(&self) -> Result<(), LogError> {
        if self.header.is_none() {
            if !self.win.get(0, 7).starts_with(&MAGIC) {
                return Err(LogError::file("ulog", "not a ULog file (bad magic)"));
            }
            return Err(LogError::file("ulog", format!("ULog header truncated ({} of 16 bytes)", self.win.end())));
        }
        if self.p.messages == 0 {
            return Err(LogError::file("ulog", "ULog file has no readable message after the header"));
        }
        Ok(())
    }

    /// The next chunk of the file.
    pub fn feed(&mut self, chunk: &[u8], sink: &mut dyn RowSink) {
        self.win.push(chunk);
        self.run(false, sink);
    }

    /// End of the second pass: rows still buffered go to `sink`; the
    /// metadata, warnings and counts.
    pub fn finish(mut self, sink: &mut dyn RowSink) -> Result<LogSummary, LogError> {
        self.run(true, sink);
        self.check()?;
        let (version, start_us) = self.header.unwrap_or((0, 0));
        Ok(self.p.finish(version, start_us, sink))
    }

    /// Parse what is held; at `eof`, to the end. Every iteration either
    /// advances `pos`, consumes an appended offset or returns, so it ends.
    fn run(&mut self, eof: bool, sink: &mut dyn RowSink) {
        if self.header.is_none() {
            let h = self.win.get(0, HEADER_LEN as u64);
            if h.len() < HEADER_LEN || !h.starts_with(&MAGIC) {
                return;
            }
            let version = h.get(7).copied().unwrap_or(0);
            let start_us = le::<8>(h, 8).map_or(0, u64::from_le_bytes);
            self.header = Some((version, start_us));
        }
        while !self.stopped && self.step(eof, sink) {}
        // Keep only what the next message (or the resync scan) still needs.
        let keep = self.scan.map_or(self.pos, |(from, _)| from.saturating_sub(1).min(self.pos));
        self.win.consume(keep);
    }

    /// One message; false when more bytes are needed (or the end is reached).
    fn step(&mut self, eof: bool, sink: &mut dyn RowSink) -> bool {
        let pos = self.pos;
        let pending = self.p.appended.get(self.p.next_appended).copied();
        if let Some(off) = pending {
            if pos >= off {
                self.p.next_appended += 1;
                return true;
            }
        }
        let avail = self.win.end();
        if pos >= avail {
            return false;
        }
        let rest_len = avail - pos;
        if rest_len < 3 && !eof {
            return false;
        }
        let (size, ty) = match *self.win.get(pos, pos + 3) {
            [s0, s1, ty] => (u64::from(u16::from_le_bytes([s0, s1])), ty),
            _ => (u64::MAX, 0),
        };
        let end = pos.saturating_add(3).saturating_add(size);
        // Appended data: a message running past the next offset was cut
        // when the log stopped; parsing restarts at the offset (spec).
        if let Some(off) = pending {
            if end > off {
                self.pos = off;
                self.p.next_appended += 1;
                return true;
            }
        }
        if end > avail {
            if eof {
                self.p.warnings.push(format!("file truncated: last message at byte {pos} incomplete ({rest_len} bytes ignored)"));
                self.stopped = true;
            }
            return false;
        }
        self.p.layout_allow = LAYOUT_WORK_BASE.saturating_add(pos.saturating_mul(LAYOUT_WORK_PER_BYTE));
        let payload = self.win.get(pos + 3, end);
        let known = self.p.handle(pos, ty, payload, self.total, sink);
        if known {
            self.p.messages += 1;
            self.pos = end;
        } else if ty == 0 || size == 0 || size > MAX_PLAUSIBLE_UNKNOWN_SIZE as u64 {
            // Implausible header: resync on the next sync marker, or
            // crawl byte by byte if there is none near (pyulog's way).
            let from = pos + 1;
            let found = if self.p.has_sync {
                match self.find_sync(from, eof) {
                    Scan::Found(next) => Some(next),
                    Scan::None => None,
                    Scan::More => return false,
                }
            } else {
                None
            };
            self.scan = None;
            self.p.resyncs += 1;
            match found {
                Some(next) => {
                    self.p.skipped_bytes += next - pos;
                    self.pos = next;
                }
                None => {
                    self.p.has_sync = false;
                    self.p.skipped_bytes += 1;
                    self.pos = from;
                }
            }
        } else {
            // A message type newer than this reader: skip it.
            self.p.unknown_types += 1;
            self.pos = end;
        }
        true
    }

    /// Position just after the next sync marker within [`RESYNC_WINDOW`]
    /// bytes of `from`, scanning only bytes not scanned before.
    fn find_sync(&mut self, from: u64, eof: bool) -> Scan {
        let limit = from.saturating_add(RESYNC_WINDOW);
        let start = match self.scan {
            Some((f, done)) if f == from => done,
            _ => from,
        };
        let end = self.win.end().min(limit);
        let hay = self.win.get(start, end);
        if let Some(i) = hay.windows(SYNC_MAGIC.len()).position(|w| w == SYNC_MAGIC) {
            return Scan::Found(start + i as u64 + SYNC_MAGIC.len() as u64);
        }
        if eof || end >= limit {
            return Scan::None;
        }
        // Resume where a marker could still start.
        let done = end.saturating_sub(SYNC_MAGIC.len() as u64 - 1).max(start);
        self.scan = Some((from, done));
        Scan::More
    }
}

enum Scan {
    Found(u64),
    None,
    More,
}

// ---------------------------------------------------------------------------
// Primitive types and field locations

/// ULog basic field types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Basic {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Bool,
    Char,
}

impl Basic {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "int8_t" => Basic::I8,
            "uint8_t" => Basic::U8,
            "int16_t" => Basic::I16,
            "uint16_t" => Basic::U16,
            "int32_t" => Basic::I32,
            "uint32_t" => Basic::U32,
            "int64_t" => Basic::I64,
            "uint64_t" => Basic::U64,
            "float" => Basic::F32,
            "double" => Basic::F64,
            "bool" => Basic::Bool,
            "char" => Basic::Char,
            _ => return None,
        })
    }

    /// Size in bytes.
    fn size(self) -> usize {
        match self {
            Basic::I8 | Basic::U8 | Basic::Bool | Basic::Char => 1,
            Basic::I16 | Basic::U16 => 2,
            Basic::I32 | Basic::U32 | Basic::F32 => 4,
            Basic::I64 | Basic::U64 | Basic::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Basic::F32 | Basic::F64)
    }

    /// Value at byte `off` as f64; NaN when out of range. (u64/i64 beyond
    /// 2^53 lose precision, irrelevant for µs timestamps of real logs.)
    #[inline]
    fn read(self, data: &[u8], off: usize) -> f64 {
        let v = match self {
            Basic::I8 => le::<1>(data, off).map(|b| f64::from(i8::from_le_bytes(b))),
            Basic::U8 | Basic::Bool | Basic::Char => {
                le::<1>(data, off).map(|b| f64::from(u8::from_le_bytes(b)))
            }
            Basic::I16 => le::<2>(data, off).map(|b| f64::from(i16::from_le_bytes(b))),
            Basic::U16 => le::<2>(data, off).map(|b| f64::from(u16::from_le_bytes(b))),
            Basic::I32 => le::<4>(data, off).map(|b| f64::from(i32::from_le_bytes(b))),
            Basic::U32 => le::<4>(data, off).map(|b| f64::from(u32::from_le_bytes(b))),
            Basic::I64 => le::<8>(data, off).map(|b| i64::from_le_bytes(b) as f64),
            Basic::U64 => le::<8>(data, off).map(|b| u64::from_le_bytes(b) as f64),
            Basic::F32 => le::<4>(data, off).map(|b| f64::from(f32::from_le_bytes(b))),
            Basic::F64 => le::<8>(data, off).map(f64::from_le_bytes),
        };
        v.unwrap_or(f64::NAN)
    }
}

/// `N` bytes at `off`, or None past the end (never panics).
#[inline]
fn le<const N: usize>(data: &[u8], off: usize) -> Option<[u8; N]> {
    let end = off.checked_add(N)?;
    data.get(off..end)?.try_into().ok()
}

/// Where a mapped value lives in a data message payload (after the msg_id),
/// and the divisor turning the raw number into contract units (a division by
/// 1e7 rounds `473977421` to exactly `47.3977421`, a product by 1e-7 doesn't).
#[derive(Clone, Copy, Debug)]
struct Loc {
    off: usize,
    ty: Basic,
    div: f64,
}

/// Value of an optional location, NaN when the field does not exist.
#[inline]
fn val(loc: Option<Loc>, data: &[u8]) -> f64 {
    match loc {
        Some(l) => l.ty.read(data, l.off) / l.div,
        None => f64::NAN,
    }
}

/// Bytes up to the first NUL (strings in ULog may be NUL-padded).
fn trim_nul(b: &[u8]) -> &[u8] {
    match b.iter().position(|&c| c == 0) {
        Some(i) => b.get(..i).unwrap_or(b),
        None => b,
    }
}

// ---------------------------------------------------------------------------
// Format definitions

/// One field of an `F` message: `type[len] name` (len 1 for scalars).
#[derive(Clone, Debug, PartialEq, Eq)]
struct Field {
    ty: String,
    len: usize,
    name: String,
}

/// Parse an `F` payload `"name:type field;type[n] field;..."`.
fn parse_format(payload: &[u8]) -> Option<(&str, Vec<Field>)> {
    let s = std::str::from_utf8(trim_nul(payload)).ok()?;
    let (name, rest) = s.split_once(':')?;
    let mut fields = Vec::new();
    for part in rest.split(';') {
        let part = part.trim();
        if part.is_empty() {
            continue;
        }
        let (ty, fname) = part.split_once(' ')?;
        let (ty, len) = match ty.split_once('[') {
            Some((base, arr)) => (base, arr.strip_suffix(']')?.parse::<usize>().ok()?),
            None => (ty, 1),
        };
        fields.push(Field {
            ty: ty.to_string(),
            len,
            name: fname.trim().to_string(),
        });
    }
    Some((name.trim(), fields))
}

/// All format definitions, with memoised type sizes and topic templates.
#[derive(Default)]
struct Defs {
    formats: HashMap<String, (Rc<Vec<Field>>, usize)>,
    /// Bytes of the `F` payloads in `formats`.
    format_bytes: usize,
    /// Cached results by type or topic name ([`Memo`]).
    memo: HashMap<String, Memo>,
    /// Some cached result is None (maybe a forward reference).
    cached_failure: bool,
    /// Field visits spent on layouts so far, and the current allowance.
    work: u64,
    allow: u64,
    /// Formats not kept: over [`MAX_FORMAT_BYTES`].
    dropped: u64,
    /// Subscriptions not resolved because the layout budget ran out.
    over_budget: u64,
}

/// What [`Defs`] has worked out for one name: `None` until asked. One map
/// for both (one hash table's code in the core wasm module, not two).
#[derive(Default)]
struct Memo {
    /// Size (bytes) of the type of this name as a nested type; `Some(None)`
    /// = unresolvable.
    size: Option<Option<usize>>,
    /// Subscription template of the topic of this name (layout + role for
    /// multi_id 0), so that repeated `A` messages for one topic cost a hash
    /// look-up; `Some(None)` = unresolvable.
    template: Option<Option<Template>>,
}

/// What an `A` message for a topic resolves to (see [`Sub`]).
#[derive(Clone)]
struct Template {
    min: usize,
    full: usize,
    ts: Loc,
    /// Shared with the subscriptions made from it: a cache hit copies a
    /// pointer, not the maps (a deep clone was 1.9 KB of wasm).
    role: Rc<Role>,
}

impl Defs {
    /// A new or redefined format (`bytes`: its `F` payload size).
    fn add(&mut self, name: &str, fields: Vec<Field>, bytes: usize) {
        let old = self.formats.get(name).map(|(f, b)| (f.as_ref() == &fields, *b));
        if old.is_some_and(|(same, _)| same) {
            return; // identical redefinition: nothing cached changes
        }
        let freed = old.map_or(0, |(_, b)| b);
        if self.format_bytes - freed + bytes > MAX_FORMAT_BYTES {
            self.dropped += 1;
            return;
        }
        self.format_bytes = self.format_bytes - freed + bytes;
        self.formats.insert(name.to_string(), (Rc::new(fields), bytes));
        // A redefinition, or a late definition that a failed look-up may have
        // been waiting for, can change any cached result: drop them all, so a
        // later subscription always gets the current layout. The budget in
        // `template` keeps a hostile F/A/F/A... file linear.
        if old.is_some() || self.cached_failure {
            self.memo.clear();
            self.cached_failure = false;
        }
    }

    /// Subscription template of topic `name` (cached).
    fn template(&mut self, name: &str) -> Option<Template> {
        if let Some(t) = self.memo.get(name).and_then(|m| m.template.as_ref()) {
            return t.clone();
        }
        if self.work > self.allow {
            self.over_budget += 1;
            return None;
        }
        let t = self.layout(name).and_then(|l| {
            let ts = l.loc("timestamp", 0, 1e6, 1e6)?;
            Some(Template {
                min: l.min,
                full: l.full,
                ts,
                role: Rc::new(role_for(name, &l)),
            })
        });
        self.cached_failure |= t.is_none();
        self.remember(name).template = Some(t.clone());
        t
    }

    /// The memo of `name`, made empty if there is none yet.
    fn remember(&mut self, name: &str) -> &mut Memo {
        self.memo.entry(name.to_string()).or_default()
    }

    /// Size in bytes of a basic or nested type. Memoised so that adversarial
    /// formats (each type using the next one many times) stay linear.
    fn type_size(&mut self, ty: &str, depth: u32) -> Option<usize> {
        if let Some(b) = Basic::parse(ty) {
            return Some(b.size());
        }
        if let Some(s) = self.memo.get(ty).and_then(|m| m.size) {
            return s;
        }
        let fields = Rc::clone(&self.formats.get(ty)?.0);
        let mut total = Some(0usize);
        if depth > MAX_NESTING {
            total = None;
        }
        for f in fields.iter() {
            let Some(t) = total else { break };
            self.work += 1;
            total = self
                .type_size(&f.ty, depth + 1)
                .and_then(|s| s.checked_mul(f.len))
                .and_then(|s| t.checked_add(s));
        }
        self.remember(ty).size = Some(total);
        self.cached_failure |= total.is_none();
        total
    }

    /// Top-level layout of a topic: field offsets, full and minimum size.
    fn layout(&mut self, name: &str) -> Option<Layout> {
        let fields = Rc::clone(&self.formats.get(name)?.0);
        let mut out = Vec::with_capacity(fields.len());
        let (mut off, mut min) = (0usize, 0usize);
        for f in fields.iter() {
            self.work += 1;
            let size = self.type_size(&f.ty, 1)?.checked_mul(f.len)?;
            out.push(LField {
                name: f.name.clone(),
                off,
                basic: Basic::parse(&f.ty),
                len: f.len,
            });
            off = off.checked_add(size)?;
            // The logger drops trailing padding, so messages may be shorter.
            if !f.name.starts_with("_padding") {
                min = off;
            }
        }
        Some(Layout {
            fields: out,
            full: off,
            min,
        })
    }
}

/// A top-level field placed in the message.
struct LField {
    name: String,
    off: usize,
    basic: Option<Basic>,
    len: usize,
}

/// Flattened top level of a topic's format.
struct Layout {
    fields: Vec<LField>,
    /// Payload size with all fields, bytes.
    full: usize,
    /// Payload size without trailing `_padding` fields, bytes.
    min: usize,
}

impl Layout {
    /// Element `idx` of basic field `name`; raw value divided by `int_div`
    /// for integer types or `float_div` for float types.
    fn loc(&self, name: &str, idx: usize, int_div: f64, float_div: f64) -> Option<Loc> {
        let f = self.fields.iter().find(|f| f.name == name)?;
        let ty = f.basic?;
        if idx >= f.len || ty == Basic::Char {
            return None;
        }
        let off = f.off.checked_add(ty.size().checked_mul(idx)?)?;
        let div = if ty.is_float() { float_div } else { int_div };
        Some(Loc { off, ty, div })
    }

    fn loc1(&self, name: &str) -> Option<Loc> {
        self.loc(name, 0, 1.0, 1.0)
    }

    fn vec3(&self, names: &[&str]) -> [Option<Loc>; 3] {
        let f = names
            .iter()
            .find(|n| self.loc1(n).is_some())
            .copied()
            .unwrap_or("");
        [0, 1, 2].map(|i| self.loc(f, i, 1.0, 1.0))
    }
}

// ---------------------------------------------------------------------------
// Topic mappings

/// GPS fields. lat/lon: int32 1e-7 deg or double deg; alt: int32 mm or
/// double m (PX4 >= 1.14 renamed them `latitude_deg`, `altitude_msl_m`, ...).
#[derive(Clone)]
struct GpsMap {
    lat: Option<Loc>,
    lon: Option<Loc>,
    alt: Option<Loc>,
    vel: [Option<Loc>; 3],
    eph: Option<Loc>,
    epv: Option<Loc>,
    /// `s_variance_m_s`: despite its name, the receiver's speed accuracy
    /// (m/s, u-blox sAcc).
    sacc: Option<Loc>,
    sats: Option<Loc>,
    fix: Option<Loc>,
    /// `time_utc_usec`: UTC of the fix, µs since 1970 (0 when unknown).
    utc: Option<Loc>,
}

impl GpsMap {
    fn new(l: &Layout) -> Self {
        GpsMap {
            lat: l.loc1("latitude_deg").or_else(|| l.loc("lat", 0, 1e7, 1.0)),
            lon: l
                .loc1("longitude_deg")
                .or_else(|| l.loc("lon", 0, 1e7, 1.0)),
            alt: l
                .loc1("altitude_msl_m")
                .or_else(|| l.loc("alt", 0, 1e3, 1.0)),
            vel: [
                l.loc1("vel_n_m_s"),
                l.loc1("vel_e_m_s"),
                l.loc1("vel_d_m_s"),
            ],
            eph: l.loc1("eph"),
            epv: l.loc1("epv"),
            sacc: l.loc1("s_variance_m_s"),
            sats: l.loc1("satellites_used"),
            fix: l.loc1("fix_type"),
            utc: l.loc1("time_utc_usec"),
        }
    }

    /// One GPS row. Without a fix (fix_type < 2) the receiver's position and
    /// velocity are placeholders (often zeros), so they stay NaN: the row then
    /// says "no fix at this instant".
    fn decode(&self, t: f64, d: &[u8]) -> Sample {
        let mut s = Sample::at(t);
        s.fix = val(self.fix, d);
        s.sats = val(self.sats, d);
        s.eph = val(self.eph, d);
        s.epv = val(self.epv, d);
        s.sacc = val(self.sacc, d);
        if !s.reports_no_fix() {
            s.lat = val(self.lat, d);
            s.lon = val(self.lon, d);
            s.alt = val(self.alt, d);
            s.vn = val(self.vel[0], d);
            s.ve = val(self.vel[1], d);
            s.vd = val(self.vel[2], d);
        }
        // The receiver's UTC, s (0 when it has none).
        let utc = val(self.utc, d);
        if utc > 0.0 {
            s.gps_time = utc / 1e6;
        }
        s
    }
}

/// `sensor_combined` fields (m/s², rad/s; relative timestamps in µs).
#[derive(Clone)]
struct ImuMap {
    acc: [Option<Loc>; 3],
    gyro: [Option<Loc>; 3],
    /// `accelerometer_timestamp_relative`: accel time minus `timestamp`, µs.
    acc_rel: Option<Loc>,
    /// Old logs (PX4 <= 1.6) carry the baro inside sensor_combined, m.
    baro: Option<Loc>,
    baro_rel: Option<Loc>,
}

impl ImuMap {
    fn new(l: &Layout) -> Self {
        ImuMap {
            acc: l.vec3(&["accelerometer_m_s2"]),
            gyro: l.vec3(&["gyro_rad", "gyro_rad_s"]),
            acc_rel: l.loc1("accelerometer_timestamp_relative"),
            baro: l.loc1("baro_alt_meter"),
            baro_rel: l.loc1("baro_timestamp_relative"),
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum GpsSrc {
    VehicleGpsPosition,
    SensorGps,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum BaroSrc {
    AirData,
    SensorBaro,
}

/// What to do with a subscription's data messages.
#[derive(Clone)]
enum Role {
    /// Count only.
    Other,
    Gps(GpsSrc, Box<GpsMap>),
    Imu(Box<ImuMap>),
    /// `q[4]`, scalar first, body FRD -> NED.
    Att([Option<Loc>; 4]),
    /// Barometric altitude, m.
    Baro(BaroSrc, Loc),
    /// `vehicle_status.nav_state`: the flight mode.
    Status(Loc),
}

/// Role of a topic's `multi_id` 0 instance (other instances are counted only).
fn role_for(name: &str, l: &Layout) -> Role {
    match name {
        "vehicle_gps_position" => Role::Gps(GpsSrc::VehicleGpsPosition, Box::new(GpsMap::new(l))),
        "sensor_gps" => Role::Gps(GpsSrc::SensorGps, Box::new(GpsMap::new(l))),
        "sensor_combined" => Role::Imu(Box::new(ImuMap::new(l))),
        "vehicle_attitude" => {
            let q = [0, 1, 2, 3].map(|i| l.loc("q", i, 1.0, 1.0));
            if q.iter().all(Option::is_some) {
                Role::Att(q)
            } else {
                Role::Other
            }
        }
        "vehicle_air_data" | "sensor_baro" => match l.loc1("baro_alt_meter") {
            Some(loc) if name == "vehicle_air_data" => Role::Baro(BaroSrc::AirData, loc),
            Some(loc) => Role::Baro(BaroSrc::SensorBaro, loc),
            None => Role::Other,
        },
        "vehicle_status" => l.loc1("nav_state").map_or(Role::Other, Role::Status),
        _ => Role::Other,
    }
}

/// One `A` subscription.
struct Sub {
    /// Index into `Parser::topics`.
    topic: usize,
    /// Accepted payload sizes (without msg_id), bytes.
    min: usize,
    full: usize,
    /// `timestamp`, read in s (µs / 1e6).
    ts: Loc,
    role: Rc<Role>,
}

// ---------------------------------------------------------------------------
// Parser

const NO_SUB: u32 = u32::MAX;
/// Bound on subscription entries (real logs: a few hundred); only reachable
/// by a file that unsubscribes and resubscribes ids over and over.
const MAX_SUBS: usize = 1 << 17;
/// PX4 `vehicle_status.nav_state` names by value (`vehicle_status.msg`;
/// 6, 7 and 16 are old states since removed).
const NAV_STATES: [&str; 24] = [
    "MANUAL", "ALTCTL", "POSCTL", "AUTO_MISSION", "AUTO_LOITER", "AUTO_RTL", "AUTO_RCRECOVER", "AUTO_RTGS",
    "AUTO_LANDENGFAIL", "AUTO_LANDGPSFAIL", "ACRO", "", "DESCEND", "TERMINATION", "OFFBOARD", "STAB", "RATTITUDE",
    "AUTO_TAKEOFF", "AUTO_LAND", "AUTO_FOLLOW_TARGET", "AUTO_PRECLAND", "ORBIT", "AUTO_VTOL_TAKEOFF", "EXTERNAL1",
];
const LOG_LEVELS: [&str; 8] = [
    "EMERG", "ALERT", "CRIT", "ERR", "WARNING", "NOTICE", "INFO", "DEBUG",
];

/// What goes through the reorder buffer.
enum Item {
    Row(Sample),
    /// An IMU row: gets the latest attitude.
    Imu(Sample),
    /// (t s, quaternion w x y z)
    Att(f64, [f64; 4]),
}

/// The rows of the second pass, in time order: attitude is put on IMU rows
/// as they come out of the reorder buffer.
struct Emit {
    reorder: Reorder<Item>,
    /// Latest attitude at or before the rows handed on: (t s, quaternion).
    att: Option<(f64, [f64; 4])>,
}

impl Emit {
    fn push(&mut self, t: f64, rank: u8, item: Item, sink: &mut dyn RowSink) {
        let att = &mut self.att;
        self.reorder.push(t, rank, item, &mut |i| Self::out(att, i, sink));
    }

    fn drain(&mut self, sink: &mut dyn RowSink) {
        let att = &mut self.att;
        self.reorder.drain(&mut |i| Self::out(att, i, sink));
    }

    fn out(att: &mut Option<(f64, [f64; 4])>, item: Item, sink: &mut dyn RowSink) {
        match item {
            Item::Att(t, q) => *att = Some((t, q)),
            Item::Row(row) => sink.row(&row),
            Item::Imu(mut row) => {
                if let Some((ta, [w, x, y, z])) = *att {
                    if row.t - ta <= ATTITUDE_MAX_AGE_S {
                        (row.qw, row.qx, row.qy, row.qz) = (w, x, y, z);
                    }
                }
                sink.row(&row);
            }
        }
    }
}

/// Rows per source seen in the second pass (for the end-of-file warnings).
#[derive(Default)]
struct Counts {
    gps: u64,
    gps_fix: u64,
    imu: u64,
    imu_baro: u64,
    att: u64,
    baro: u64,
}

struct Parser {
    defs: Defs,
    /// `None` in the first pass: rows are only noted in `seen`.
    plan: Option<Seen>,
    seen: Seen,
    emit: Emit,
    counts: Counts,
    /// msg_id -> index into `subs` (NO_SUB if none); grows to the largest id seen.
    sub_by_id: Vec<u32>,
    subs: Vec<Sub>,
    /// (topic name, multi_id, data message count).
    topics: Vec<(Rc<str>, u8, u64)>,
    topic_idx: HashMap<(Rc<str>, u8), usize>,
    /// Appended-data offsets (ascending, within the file) and the next one.
    appended: Vec<u64>,
    next_appended: usize,
    /// Absolute time (µs) of the last sensor_combined baro sub-sample.
    last_sc_baro_us: f64,
    /// Field-visit allowance for layouts at the current message.
    layout_allow: u64,

    // bookkeeping
    messages: u64,
    last_t: f64,
    in_data: bool,
    info: Vec<(String, String)>,
    info_dropped: u64,
    multi_info_keys: Vec<String>,
    multi_info_count: u64,
    params_initial: u64,
    params_changed: u64,
    params_default: u64,
    log_count: u64,
    tagged_log_count: u64,
    log_lines: Vec<(String, String)>,
    /// Modes, messages, UTC time; GPS rows with an eph.
    extras: Extras,
    eph_rows: u64,
    syncs: u64,
    dropouts: u64,
    dropout_ms: u64,
    unknown_types: u64,
    no_sub_data: u64,
    bad_size_data: u64,
    unresolved_subs: u64,
    topics_dropped: u64,
    bad_formats: u64,
    misplaced_flags: u64,
    resyncs: u64,
    skipped_bytes: u64,
    /// false once a forward search found no sync marker (avoid O(n²) rescans).
    has_sync: bool,
    warnings: Vec<String>,
}

impl Parser {
    fn new(plan: Option<Seen>) -> Self {
        Parser {
            defs: Defs::default(),
            plan,
            seen: Seen::default(),
            emit: Emit { reorder: Reorder::new(REORDER_ROWS), att: None },
            counts: Counts::default(),
            sub_by_id: Vec::new(),
            subs: Vec::new(),
            topics: Vec::new(),
            topic_idx: HashMap::new(),
            appended: Vec::new(),
            next_appended: 0,
            last_sc_baro_us: f64::NAN,
            layout_allow: LAYOUT_WORK_BASE,
            messages: 0,
            last_t: f64::NAN,
            in_data: false,
            info: Vec::new(),
            info_dropped: 0,
            multi_info_keys: Vec::new(),
            multi_info_count: 0,
            params_initial: 0,
            params_changed: 0,
            params_default: 0,
            log_count: 0,
            tagged_log_count: 0,
            log_lines: Vec::new(),
            extras: Extras::default(),
            eph_rows: 0,
            syncs: 0,
            dropouts: 0,
            dropout_ms: 0,
            unknown_types: 0,
            no_sub_data: 0,
            bad_size_data: 0,
            unresolved_subs: 0,
            topics_dropped: 0,
            bad_formats: 0,
            misplaced_flags: 0,
            resyncs: 0,
            skipped_bytes: 0,
            has_sync: true,
            warnings: Vec::new(),
        }
    }

    /// Handle one message; false when its type is unknown. `total`: the file
    /// length when known (to check appended-data offsets).
    fn handle(&mut self, pos: u64, ty: u8, p: &[u8], total: Option<u64>, sink: &mut dyn RowSink) -> bool {
        match ty {
            b'D' => self.data(p, sink),
            b'F' => match parse_format(p) {
                Some((name, fields)) => self.defs.add(name, fields, p.len()),
                None => self.bad_formats += 1,
            },
            b'A' => {
                self.in_data = true;
                self.defs.allow = self.layout_allow;
                self.subscribe(p);
            }
            b'R' => {
                if let Some(id) = le::<2>(p, 0).map(u16::from_le_bytes) {
                    if let Some(slot) = self.sub_by_id.get_mut(usize::from(id)) {
                        *slot = NO_SUB;
                    }
                }
            }
            b'B' => self.flag_bits(pos, p, total),
            b'I' => {
                // Old logs put perf-counter dumps in `I` messages: not metadata.
                if let Some((k, mut v)) = key_value(p).filter(|(k, _)| !k.starts_with("perf_")) {
                    if self.info.len() < MAX_INFO {
                        truncate_utf8(&mut v, MAX_INFO_BYTES);
                        self.info.push((k.to_string(), v));
                    } else {
                        self.info_dropped += 1;
                    }
                }
            }
            b'M' => self.multi_info(p),
            b'P' => {
                if self.in_data {
                    self.params_changed += 1;
                } else {
                    self.params_initial += 1;
                }
            }
            b'Q' => self.params_default += 1,
            b'L' => {
                self.in_data = true;
                self.log_count += 1;
                self.log_line(p.first().copied(), p.get(1..9), p.get(9..));
            }
            b'C' => {
                self.in_data = true;
                self.tagged_log_count += 1;
                self.log_line(p.first().copied(), p.get(3..11), p.get(11..));
            }
            b'S' => {
                if p.starts_with(&SYNC_MAGIC) {
                    self.syncs += 1;
                }
            }
            b'O' => {
                self.dropouts += 1;
                self.dropout_ms += le::<2>(p, 0).map_or(0, |b| u64::from(u16::from_le_bytes(b)));
            }
            _ => return false,
        }
        true
    }

    /// The hot path: one data message.
    #[inline]
    fn data(&mut self, p: &[u8], sink: &mut dyn RowSink) {
        self.in_data = true;
        let Some(id) = le::<2>(p, 0).map(u16::from_le_bytes) else {
            self.bad_size_data += 1;
            return;
        };
        let d = p.get(2..).unwrap_or(&[]);
        let idx = self
            .sub_by_id
            .get(usize::from(id))
            .copied()
            .unwrap_or(NO_SUB);
        let Some(sub) = self.subs.get(idx as usize) else {
            self.no_sub_data += 1;
            return;
        };
        // Same acceptance rule as pyulog: shorter than the format without its
        // trailing padding, or longer than the full format, is corruption.
        if d.len() < sub.min || d.len() > sub.full {
            self.bad_size_data += 1;
            return;
        }
        if let Some(c) = self.topics.get_mut(sub.topic) {
            c.2 += 1;
        }
        // Raw µs (exact in f64 up to 2^53), then s.
        let t_us = sub.ts.ty.read(d, sub.ts.off);
        let t = t_us / 1e6;
        if self.last_t.is_nan() || t > self.last_t {
            self.last_t = t;
        }
        // Timestamp 0 = never set by the publisher: no usable row.
        if t.is_nan() || t <= 0.0 {
            return;
        }
        let Some(plan) = self.plan else {
            match &*sub.role {
                Role::Gps(GpsSrc::VehicleGpsPosition, _) => self.seen.vgp = true,
                Role::Gps(GpsSrc::SensorGps, _) => self.seen.sensor_gps = true,
                Role::Baro(BaroSrc::AirData, _) => self.seen.air = true,
                Role::Baro(BaroSrc::SensorBaro, _) => self.seen.sensor_baro = true,
                _ => {}
            }
            return;
        };
        match &*sub.role {
            Role::Other => {}
            Role::Gps(src, m) => {
                // vehicle_gps_position (the selected receiver) when it has data.
                if (*src == GpsSrc::VehicleGpsPosition) == plan.vgp {
                    let row = m.decode(t, d);
                    if row.has_fix() {
                        self.extras.utc(t, val(m.utc, d) / 1e6);
                    }
                    self.eph_rows += u64::from(row.eph.is_finite());
                    self.counts.gps += 1;
                    self.counts.gps_fix += u64::from(row.has_fix());
                    self.emit.push(t, RANK_GPS, Item::Row(row), sink);
                }
            }
            Role::Imu(m) => {
                // Row time = `timestamp` (the gyro sample); the accel sample
                // is `accelerometer_timestamp_relative` µs away (a few ms) and
                // is only used to tell whether the accel values are valid.
                let mut s = Sample::at(t);
                s.gx = val(m.gyro[0], d);
                s.gy = val(m.gyro[1], d);
                s.gz = val(m.gyro[2], d);
                if val(m.acc_rel, d) != RELATIVE_TIMESTAMP_INVALID {
                    s.ax = val(m.acc[0], d);
                    s.ay = val(m.acc[1], d);
                    s.az = val(m.acc[2], d);
                }
                // Old embedded baro: repeated at IMU rate, so keep only new
                // sub-samples (absolute baro time changed).
                if m.baro.is_some() {
                    let rel = val(m.baro_rel, d);
                    if rel != RELATIVE_TIMESTAMP_INVALID {
                        let abs_us = t_us + if rel.is_nan() { 0.0 } else { rel };
                        if abs_us != self.last_sc_baro_us {
                            self.last_sc_baro_us = abs_us;
                            s.baro = val(m.baro, d);
                        }
                    }
                }
                self.counts.imu += 1;
                self.counts.imu_baro += u64::from(s.has_baro());
                // A dedicated baro topic replaces the embedded one.
                if plan.air || plan.sensor_baro {
                    s.baro = f64::NAN;
                }
                self.emit.push(t, RANK_IMU, Item::Imu(s), sink);
            }
            Role::Att(q) => {
                let q = q.map(|l| val(l, d));
                // Skip uninitialised (zero) or garbage quaternions.
                let n2: f64 = q.iter().map(|v| v * v).sum();
                if (0.8..1.2).contains(&n2) {
                    self.counts.att += 1;
                    self.emit.push(t, RANK_ATT, Item::Att(t, q), sink);
                }
            }
            Role::Baro(src, loc) => {
                if (*src == BaroSrc::AirData) == plan.air {
                    let mut s = Sample::at(t);
                    s.baro = val(Some(*loc), d);
                    self.counts.baro += 1;
                    self.emit.push(t, RANK_BARO, Item::Row(s), sink);
                }
            }
            Role::Status(loc) => {
                let n = val(Some(*loc), d);
                if n.is_finite() {
                    let name = NAV_STATES.get(n as usize).filter(|s| n >= 0.0 && !s.is_empty());
                    self.extras.mode(t, name.map_or_else(|| format!("nav_state {}", Shortest(n)), |s| (*s).to_string()));
                }
            }
        }
    }

    /// `A`: `[u8 multi_id][u16 msg_id][name]`.
    fn subscribe(&mut self, p: &[u8]) {
        let (Some(&multi_id), Some(id)) = (p.first(), le::<2>(p, 1).map(u16::from_le_bytes)) else {
            return;
        };
        let Some(name) = p
            .get(3..)
            .and_then(|n| std::str::from_utf8(trim_nul(n)).ok())
        else {
            self.unresolved_subs += 1;
            return;
        };
        let Some(tpl) = self.defs.template(name) else {
            // Like pyulog: without a format (or a timestamp) the topic's data
            // cannot be checked; its messages count as unsubscribed.
            self.unresolved_subs += 1;
            return;
        };
        let key: (Rc<str>, u8) = (Rc::from(name), multi_id);
        let topic = match self.topic_idx.get(&key) {
            Some(&i) => i,
            None if self.topics.len() >= MAX_TOPICS => {
                self.topics_dropped += 1;
                return;
            }
            None => {
                self.topics.push((Rc::clone(&key.0), multi_id, 0));
                self.topic_idx.insert(key, self.topics.len() - 1);
                self.topics.len() - 1
            }
        };
        let role = if multi_id == 0 { tpl.role } else { Rc::new(Role::Other) };
        let sub = Sub {
            topic,
            min: tpl.min,
            full: tpl.full,
            ts: tpl.ts,
            role,
        };
        let id = usize::from(id);
        if self.sub_by_id.len() <= id {
            self.sub_by_id.resize(id + 1, NO_SUB); // at most 65536 entries
        }
        let Some(slot) = self.sub_by_id.get_mut(id) else {
            return;
        };
        // Re-subscribing an id replaces its entry: `subs` stays <= 65536 long.
        if let Some(old) = self.subs.get_mut(*slot as usize) {
            *old = sub;
        } else if self.subs.len() >= MAX_SUBS {
            self.unresolved_subs += 1;
        } else if let Ok(i) = u32::try_from(self.subs.len()) {
            *slot = i;
            self.subs.push(sub);
        }
    }

    /// `B`: `[u8 compat[8]][u8 incompat[8]][u64 appended_offsets[3]]`; only
    /// valid as the first message. `total`: file length when known.
    fn flag_bits(&mut self, pos: u64, p: &[u8], total: Option<u64>) {
        if pos != HEADER_LEN as u64 {
            self.misplaced_flags += 1;
            return;
        }
        let incompat = le::<8>(p, 8).unwrap_or([0; 8]);
        let appended_bit = incompat.first().is_some_and(|b| b & 1 != 0);
        let unknown = incompat
            .iter()
            .enumerate()
            .any(|(i, b)| if i == 0 { b & !1 != 0 } else { *b != 0 });
        if unknown {
            // The spec says to refuse; we read on and say so instead.
            self.warnings
                .push("unknown incompatible ULog flags set: data may be misread".to_string());
        }
        if !appended_bit {
            return;
        }
        let mut last = pos;
        for i in 0..3 {
            let off = le::<8>(p, 16 + 8 * i).map_or(0, u64::from_le_bytes);
            if off == 0 {
                break;
            }
            if off > last && total.is_none_or(|n| off <= n) {
                self.appended.push(off);
                last = off;
            } else {
                self.warnings.push(format!("bad appended-data offset {off} ignored"));
            }
        }
    }

    /// `M`: `[u8 is_continued][u8 key_len][key][value]`. The values are
    /// bulky text (perf dumps, boot console), so only the keys are kept.
    fn multi_info(&mut self, p: &[u8]) {
        let Some((name, _)) = p.get(1..).and_then(key_value) else {
            return;
        };
        self.multi_info_count += 1;
        // Bounded so a hostile file cannot make this quadratic.
        if self.multi_info_keys.len() < 32 && !self.multi_info_keys.iter().any(|k| k == name) {
            self.multi_info_keys.push(name.to_string());
        }
    }

    /// `L`/`C`: keep warning-or-worse lines (levels are ASCII '0'..'7').
    fn log_line(&mut self, level: Option<u8>, ts: Option<&[u8]>, msg: Option<&[u8]>) {
        let (Some(level), Some(ts), Some(msg)) = (level, ts, msg) else {
            return;
        };
        let lvl = usize::from(if level >= b'0' { level - b'0' } else { level });
        let t = le::<8>(ts, 0).map_or(0, u64::from_le_bytes) as f64 * 1e-6;
        let mut text = String::from_utf8_lossy(trim_nul(msg)).trim_end().to_string();
        // Every line up to INFO goes to the report's message list (DEBUG is
        // developer chatter); the first warning-or-worse ones also to meta.
        let kind = match lvl {
            0..=3 => Some("error"),
            4 => Some("warning"),
            5 | 6 => Some("info"),
            _ => None,
        };
        if let Some(kind) = kind {
            self.extras.message(t, kind, &text);
        }
        if lvl > 4 || self.log_lines.len() >= MAX_LOG_LINES {
            return;
        }
        let name = LOG_LEVELS.get(lvl).copied().unwrap_or("?");
        truncate_utf8(&mut text, MAX_INFO_BYTES);
        self.log_lines.push((
            "log".to_string(),
            format!("t={}s {name}: {text}", Fixed(t, 3)),
        ));
    }

    /// Drain the rows and assemble the report.
    fn finish(mut self, version: u8, start_us: u64, sink: &mut dyn RowSink) -> LogSummary {
        self.emit.drain(sink);
        let plan = self.plan.unwrap_or_default();
        let c = &self.counts;
        let mut warnings = std::mem::take(&mut self.warnings);
        let mut missing = Vec::new();
        let mut meta = vec![("ulog_version".to_string(), version.to_string())];
        let start_s = start_us as f64 * 1e-6;
        let duration = if self.last_t > start_s {
            self.last_t - start_s
        } else {
            0.0
        };
        meta.push(("duration_s".to_string(), Fixed(duration, 3).to_string()));
        meta.append(&mut self.info);
        if !self.multi_info_keys.is_empty() {
            meta.push((
                "multi_info_keys".to_string(),
                self.multi_info_keys.join(", "),
            ));
            meta.push((
                "multi_info_count".to_string(),
                self.multi_info_count.to_string(),
            ));
        }
        meta.push(("param_count".to_string(), self.params_initial.to_string()));
        meta.push(("param_changes".to_string(), self.params_changed.to_string()));
        meta.push((
            "param_default_count".to_string(),
            self.params_default.to_string(),
        ));
        meta.push(("log_message_count".to_string(), self.log_count.to_string()));
        meta.push((
            "tagged_log_message_count".to_string(),
            self.tagged_log_count.to_string(),
        ));
        meta.push(("sync_count".to_string(), self.syncs.to_string()));

        // GPS: vehicle_gps_position (the selected receiver) if it had data.
        if c.gps == 0 {
            missing.push("gps".to_string());
            warnings
                .push("no GPS topic (vehicle_gps_position or sensor_gps) with data".to_string());
        } else {
            let gps_name = if plan.vgp { "vehicle_gps_position" } else { "sensor_gps" };
            meta.push(("gps_topic".to_string(), gps_name.to_string()));
            if c.gps_fix == 0 {
                warnings.push(
                    "GPS unavailable: GPS never had a fix (fix_type < 2 throughout)".to_string(),
                );
            }
        }
        if c.imu == 0 {
            missing.push("imu".to_string());
            warnings.push("no IMU topic (sensor_combined) with data".to_string());
        }
        if c.att == 0 {
            missing.push("attitude".to_string());
            warnings.push("no attitude topic (vehicle_attitude) with data".to_string());
        }
        // Baro: dedicated topic if any, else what sensor_combined carried.
        if c.baro == 0 && c.imu_baro == 0 {
            missing.push("baro".to_string());
            warnings.push("no baro topic (vehicle_air_data or sensor_baro) with data".to_string());
        }

        if self.dropouts > 0 {
            warnings.push(format!(
                "{} logging dropouts, {} s of data lost in total",
                self.dropouts,
                Fixed(self.dropout_ms as f64 * 1e-3, 3)
            ));
        }
        let counted = [
            (self.resyncs, format!("corrupt data: {} resyncs, {} bytes skipped", self.resyncs, self.skipped_bytes)),
            (self.unknown_types, format!("{} messages of unknown type skipped", self.unknown_types)),
            (self.no_sub_data, format!("{} data messages without a subscription skipped", self.no_sub_data)),
            (self.bad_size_data, format!("{} data messages of the wrong size skipped", self.bad_size_data)),
            (self.unresolved_subs, format!("{} subscriptions with an unknown or unresolvable format ignored", self.unresolved_subs)),
            (self.bad_formats, format!("{} unparsable format definitions ignored", self.bad_formats)),
            (self.misplaced_flags, format!("{} flag-bits messages not at the start ignored", self.misplaced_flags)),
            (self.defs.over_budget, format!("{} of those subscriptions not resolved because format redefinitions passed the layout work limit", self.defs.over_budget)),
            (self.defs.dropped, format!("{} format definitions ignored: over the {} MiB limit on formats", self.defs.dropped, MAX_FORMAT_BYTES >> 20)),
            (self.topics_dropped, format!("{} subscriptions ignored: over the limit of {MAX_TOPICS} topic instances", self.topics_dropped)),
            (self.emit.reorder.late, format!("{} rows dropped: more than {REORDER_ROWS} rows out of time order", self.emit.reorder.late)),
            (self.info_dropped, format!("{} info messages not kept in meta (at most {MAX_INFO} are)", self.info_dropped)),
        ];
        for (n, w) in counted {
            if n > 0 {
                warnings.push(w);
            }
        }
        meta.append(&mut self.log_lines);

        let mut topic_counts: Vec<(String, u64)> = self
            .topics
            .iter()
            .filter(|t| t.2 > 0)
            .map(|(name, mid, n)| {
                let key = if *mid == 0 {
                    name.to_string()
                } else {
                    format!("{name}/{mid}")
                };
                (key, *n)
            })
            .collect();
        crate::extras::sort_stable_by(&mut topic_counts, |a, b| a < b);

        let mut extras = std::mem::take(&mut self.extras);
        extras.sort();
        extras.eph_source = if self.eph_rows > 0 { EphSource::Eph } else { EphSource::None };
        LogSummary {
            format: "ulog",
            meta,
            warnings,
            missing,
            topic_counts,
            extras,
        }
    }
}

/// `I`/`P`-style `[u8 key_len]["type name"][value]` -> (name, value as text).
fn key_value(p: &[u8]) -> Option<(&str, String)> {
    let klen = usize::from(*p.first()?);
    let key = std::str::from_utf8(p.get(1..1 + klen)?).ok()?;
    let value = p.get(1 + klen..)?;
    let (ty, name) = key.split_once(' ')?;
    let base = ty.split_once('[').map_or(ty, |(b, _)| b);
    let text = match Basic::parse(base)? {
        Basic::Char => String::from_utf8_lossy(trim_nul(value)).into_owned(),
        b => {
            let v = b.read(value, 0);
            if v.is_nan() && !b.is_float() {
                return None; // value bytes missing
            }
            Shortest(v).to_string()
        }
    };
    Some((name, text))
}

/// Cut a string to at most `max` bytes on a char boundary.
fn truncate_utf8(s: &mut String, max: usize) {
    if s.len() > max {
        let mut i = max;
        while !s.is_char_boundary(i) {
            i -= 1;
        }
        s.truncate(i);
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    //! Expected counts come from pyulog 1.3.0 (`pip install pyulog`), with
    //! `ULog(path)` and, per `d in ulog.data_list`, `len(d.data['timestamp'])`
    //! keyed by `(d.name, d.multi_id)`; for all six files every topic count
    //! matched this reader exactly when the tests were written. Reference
    //! values (first fix, first IMU sample, ...) were read the same way.
    use super::*;

    /// Path of a PX4 test log; `../shared` is a sibling of the crate root.
    macro_rules! px4 {
        ($f:literal) => {
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/px4/", $f)
        };
    }

    fn load(path: &str) -> Vec<u8> {
        std::fs::read(path).unwrap_or_else(|e| panic!("test log {path} missing: {e}"))
    }

    fn parse(path: &str) -> LogData {
        read_ulog(&load(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    /// vehicle_status.nav_state as modes, logging messages with times,
    /// UTC from time_utc_usec, eph in metres. sample_px4_events.ulg is a
    /// simulation whose boot clock is Unix time: its UTC offset is 0.
    #[test]
    fn modes_messages_and_utc() {
        use crate::extras::{iso_utc, EphSource};
        let d = parse(px4!("sample_px4_events.ulg"));
        let x = &d.extras;
        assert_eq!(x.eph_source, EphSource::Eph);
        let modes: Vec<&str> = x.modes.iter().map(|m| m.mode.as_str()).collect();
        assert_eq!(modes, ["AUTO_LOITER", "AUTO_TAKEOFF", "AUTO_LOITER", "AUTO_RTL", "AUTO_LOITER"]);
        assert_eq!(x.messages.len(), 18);
        assert_eq!(x.messages[0].text, "[px4] Startup script returned successfully");
        assert!(x.messages.iter().any(|m| m.level == "warning" && m.text == "[health_and_arming_checks] Preflight: GPS fix too low"));
        assert!(x.utc_at_boot.unwrap().abs() < 1.0, "{:?}", x.utc_at_boot);
        assert_eq!(&iso_utc(x.utc_at_boot.unwrap() + d.samples[0].t)[..19], "2024-03-18T14:49:10");
        let q = parse(px4!("quadrotor_local.ulg"));
        assert_eq!(q.extras.utc_at_boot, None, "no time_utc_usec in a local-position log");
        assert!(q.extras.messages.iter().any(|m| m.level == "error" && m.text == "[health_and_arming_checks] Low battery"));
        assert_eq!(parse(px4!("sample.ulg")).extras.eph_source, EphSource::None);
    }

    fn count(d: &LogData, key: &str) -> u64 {
        d.topic_counts
            .iter()
            .find(|(k, _)| k == key)
            .map_or(0, |(_, n)| *n)
    }

    fn meta<'d>(d: &'d LogData, key: &str) -> Option<&'d str> {
        d.meta
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    fn has_warning(d: &LogData, text: &str) -> bool {
        d.warnings.iter().any(|w| w.contains(text))
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    const ALL: [&str; 6] = [
        px4!("sample.ulg"),
        px4!("sample_log_small.ulg"),
        px4!("sample_px4_events.ulg"),
        px4!("sample_logging_tagged_and_default_params.ulg"),
        px4!("sample_appended_multiple.ulg"),
        px4!("quadrotor_local.ulg"),
    ];

    #[test]
    fn topic_counts_match_pyulog() {
        // (file, number of topic instances with data, selected counts)
        type Expect<'e> = (&'e str, usize, &'e [(&'e str, u64)]);
        let table: [Expect; 6] = [
            (
                px4!("sample.ulg"),
                15,
                &[
                    ("sensor_combined", 17070),
                    ("vehicle_attitude", 6461),
                    ("ekf2_innovations", 3271),
                    ("sensor_preflight", 17072),
                    ("cpuload", 69),
                ],
            ),
            (
                px4!("sample_log_small.ulg"),
                70,
                &[
                    ("vehicle_gps_position", 32),
                    ("sensor_combined", 1298),
                    ("sensor_accel/2", 6),
                    ("vehicle_air_data", 120),
                    ("sensor_baro/1", 6),
                    ("vehicle_attitude", 1298),
                ],
            ),
            (
                px4!("sample_px4_events.ulg"),
                69,
                &[
                    ("vehicle_gps_position", 583),
                    ("sensor_gps", 31),
                    ("sensor_combined", 7783),
                    ("vehicle_attitude", 622),
                    ("vehicle_air_data", 623),
                    ("telemetry_status/3", 31),
                ],
            ),
            (
                px4!("sample_logging_tagged_and_default_params.ulg"),
                96,
                &[
                    ("estimator_attitude", 21),
                    ("estimator_attitude/1", 21),
                    ("estimator_attitude/2", 21),
                    ("estimator_gps_status", 190),
                    ("estimator_gps_status/1", 10),
                    ("estimator_gps_status/2", 10),
                    ("estimator_status", 1279),
                    ("estimator_status/1", 53),
                    ("estimator_status/2", 53),
                    ("estimator_sensor_bias/1", 38),
                    ("telemetry_status/3", 10),
                    ("sensor_combined", 2028),
                    ("vehicle_gps_position", 190),
                    ("sensor_gps", 11),
                ],
            ),
            (
                px4!("sample_appended_multiple.ulg"),
                20,
                &[
                    ("sensor_combined", 2373),
                    ("ekf2_timestamps", 2373),
                    ("vehicle_attitude", 306),
                    ("actuator_outputs", 95),
                    ("actuator_outputs/1", 96),
                    ("task_stack_info", 20),
                    ("vehicle_land_detected", 1),
                ],
            ),
            (
                px4!("quadrotor_local.ulg"),
                98,
                &[
                    ("sensor_combined", 20236),
                    ("vehicle_gps_position", 926),
                    ("sensor_gps", 92),
                    ("vehicle_attitude", 1851),
                    ("vehicle_air_data", 464),
                    ("actuator_outputs/1", 1),
                    ("estimator_status/1", 464),
                ],
            ),
        ];
        for (path, n_topics, expect) in table {
            let d = parse(path);
            assert_eq!(d.format, "ulog");
            assert_eq!(d.topic_counts.len(), n_topics, "{path}");
            for (key, n) in expect {
                assert_eq!(count(&d, key), *n, "{path}: {key}");
            }
            let keys: Vec<&str> = d.topic_counts.iter().map(|(k, _)| k.as_str()).collect();
            assert!(
                keys.windows(2).all(|w| w[0] < w[1]),
                "{path}: counts sorted by name"
            );
        }
    }

    #[test]
    fn every_log_parses_with_sorted_rows_and_meta() {
        for path in ALL {
            let d = parse(path);
            assert!(!d.samples.is_empty(), "{path}");
            assert!(
                d.samples.windows(2).all(|w| w[0].t <= w[1].t),
                "{path}: rows sorted"
            );
            assert_eq!(meta(&d, "sys_name"), Some("PX4"), "{path}");
            assert!(meta(&d, "ulog_version").is_some() && meta(&d, "duration_s").is_some());
            assert!(
                !has_warning(&d, "truncated") && !has_warning(&d, "corrupt"),
                "{path}: {:?}",
                d.warnings
            );
        }
    }

    #[test]
    fn sample_ulg_has_no_gps_but_imu_and_attitude() {
        let d = parse(px4!("sample.ulg"));
        assert!(d.missing.contains(&"gps".to_string()));
        assert!(has_warning(&d, "no GPS topic"));
        // The embedded sensor_combined baro is always invalid here ("no barometer found").
        assert!(d.missing.contains(&"baro".to_string()));
        assert!(
            !d.missing.contains(&"imu".to_string()) && !d.missing.contains(&"attitude".to_string())
        );
        assert_eq!(d.samples.iter().filter(|s| s.has_accel()).count(), 17070);
        assert_eq!(d.samples.iter().filter(|s| s.has_attitude()).count(), 17070);
        // pyulog: first sensor_combined at 112614307 us, accel (1.1071417, -0.48647752, -9.630395);
        // attitude at 112574307 us (40 ms before) q = (0.9545906, 0.041478634, 0.0481749, -0.29105952).
        let s = d.samples[0];
        assert_eq!(s.t, 112.614307);
        assert!(
            close(s.ax, 1.1071417, 1e-6)
                && close(s.ay, -0.48647752, 1e-6)
                && close(s.az, -9.630395, 1e-5)
        );
        assert!(close(s.gx, -0.0019249436, 1e-8));
        assert!(close(s.qw, 0.9545906, 1e-6) && close(s.qz, -0.29105952, 1e-6));
        assert_eq!(meta(&d, "ulog_version"), Some("0"));
        assert_eq!(meta(&d, "ver_hw"), Some("AUAV_X21"));
        assert_eq!(meta(&d, "duration_s"), Some("68.993")); // (181493506 - 112500176) us
        assert_eq!(meta(&d, "param_count"), Some("493"));
        assert_eq!(meta(&d, "param_changes"), Some("6"));
        // pyulog: 4 dropouts of 0, 26, 31 and 62 ms.
        assert!(
            has_warning(&d, "4 logging dropouts, 0.119 s"),
            "{:?}",
            d.warnings
        );
    }

    #[test]
    fn quadrotor_local_gps_never_has_a_fix() {
        let d = parse(px4!("quadrotor_local.ulg"));
        let gps: Vec<&Sample> = d.samples.iter().filter(|s| s.fix.is_finite()).collect();
        assert_eq!(gps.len(), 926); // vehicle_gps_position, preferred over sensor_gps (92)
        assert!(gps
            .iter()
            .all(|s| s.reports_no_fix() && s.lat.is_nan() && s.vn.is_nan()));
        assert!(!d.samples.iter().any(Sample::has_fix));
        assert!(has_warning(&d, "GPS unavailable"));
        assert!(!d.missing.contains(&"gps".to_string()));
        assert_eq!(meta(&d, "gps_topic"), Some("vehicle_gps_position"));
        assert_eq!(meta(&d, "ver_hw"), Some("PX4_FMU_V6C"));
        assert_eq!(meta(&d, "ver_sw_release"), Some("17826240"));
        assert_eq!(
            meta(&d, "sys_uuid"),
            Some("0006000000003535323734325116003d0021")
        );
        // vehicle_air_data: 464 rows, first at 104920069 us, baro_alt_meter -25.239437 m.
        let baro: Vec<&Sample> = d.samples.iter().filter(|s| s.has_baro()).collect();
        assert_eq!(baro.len(), 464);
        assert_eq!(baro[0].t, 104.920069);
        assert!(close(baro[0].baro, -25.239437, 1e-5));
        assert_eq!(d.samples.iter().filter(|s| s.has_accel()).count(), 20236);
    }

    #[test]
    fn px4_events_gps_fixes_at_19_hz_and_attitude_on_imu() {
        let d = parse(px4!("sample_px4_events.ulg"));
        assert!(d.missing.is_empty(), "{:?}", d.missing);
        assert!(!has_warning(&d, "GPS unavailable"));
        let gps: Vec<&Sample> = d.samples.iter().filter(|s| s.fix.is_finite()).collect();
        assert_eq!(gps.len(), 583);
        let fixes: Vec<&Sample> = gps.iter().copied().filter(|s| s.has_fix()).collect();
        assert_eq!(fixes.len(), 437);
        let span = fixes[fixes.len() - 1].t - fixes[0].t;
        let rate = (fixes.len() - 1) as f64 / span;
        assert!(close(rate, 19.23, 0.05), "rate {rate}");
        // pyulog: first fix (index 146) at 1710773358798000 us,
        // lat 47.3977420, lon 8.5455938 deg, alt 488.014 m, 10 sats, eph 3.96 m,
        // s_variance_m_s 0.25 m/s (the speed accuracy; 0.25 on every record).
        let f = fixes[0];
        assert!(gps.iter().all(|s| s.sacc == 0.25));
        assert!(close(f.t, 1_710_773_358.798, 1e-6));
        assert!(close(f.lat, 47.3977420, 1e-7) && close(f.lon, 8.5455938, 1e-7));
        assert!(close(f.alt, 488.014, 1e-3));
        assert_eq!((f.fix, f.sats), (2.0, 10.0));
        assert!(close(f.eph, 3.96, 1e-5) && f.has_velocity());
        // IMU: 7783 rows; all but the first ones (before the first attitude,
        // 80 ms later) carry a unit quaternion.
        let imu: Vec<&Sample> = d.samples.iter().filter(|s| s.has_accel()).collect();
        assert_eq!(imu.len(), 7783);
        let with_att = imu.iter().filter(|s| s.has_attitude()).count();
        assert!((7700..7783).contains(&with_att), "{with_att}");
        for s in imu.iter().filter(|s| s.has_attitude()) {
            let n = s.qw * s.qw + s.qx * s.qx + s.qy * s.qy + s.qz * s.qz;
            assert!(close(n, 1.0, 1e-3));
        }
        assert!(close(imu[0].ax, 0.06176303, 1e-7) && close(imu[0].az, -9.821814, 1e-5));
        let baro = d.samples.iter().find(|s| s.has_baro()).map(|s| s.baro);
        assert!(close(baro.unwrap_or(f64::NAN), 488.06058, 1e-4));
        assert_eq!(meta(&d, "log_message_count"), Some("18"));
    }

    #[test]
    fn tagged_logging_default_params_and_multi_instances() {
        let d = parse(px4!("sample_logging_tagged_and_default_params.ulg"));
        assert_eq!(meta(&d, "log_message_count"), Some("4"));
        assert_eq!(meta(&d, "tagged_log_message_count"), Some("3"));
        assert_eq!(meta(&d, "param_count"), Some("696"));
        assert_eq!(meta(&d, "param_default_count"), Some("44"));
        // Only multi_id 0 is mapped; vehicle_gps_position wins over sensor_gps.
        let gps = d.samples.iter().filter(|s| s.fix.is_finite()).count();
        assert_eq!(gps, 190);
        let fix = d
            .samples
            .iter()
            .find(|s| s.has_fix())
            .copied()
            .unwrap_or_default();
        // pyulog: first fix at 8808000 us, lat 473977421e-7, lon 85455938e-7, alt 488005 mm.
        assert_eq!(
            (fix.t, fix.lat, fix.lon, fix.alt),
            (8.808, 47.3977421, 8.5455938, 488.005)
        );
        assert_eq!(d.samples.iter().filter(|s| s.has_fix()).count(), 44);
    }

    #[test]
    fn appended_data_is_read() {
        let bytes = load(px4!("sample_appended_multiple.ulg"));
        let d = read_ulog(&bytes).unwrap_or_default();
        assert_eq!(count(&d, "sensor_combined"), 2373);
        assert_eq!(count(&d, "vehicle_attitude"), 306);
        assert_eq!(meta(&d, "ver_hw"), Some("PX4FMU_V4PRO"));
        // Old log: baro only inside sensor_combined; new sub-samples only
        // (pyulog: 656 changes of timestamp + baro_timestamp_relative).
        let baro: Vec<&Sample> = d.samples.iter().filter(|s| s.has_baro()).collect();
        assert_eq!(baro.len(), 656);
        assert!(close(baro[0].baro, 328.78915, 1e-4));
        assert!(d.missing == ["gps"], "{:?}", d.missing);
        // The three appended sections (offsets 434369, 451825, 469281) each
        // hold one `M` hardfault_plain message (pyulog: 3 series).
        assert_eq!(meta(&d, "multi_info_keys"), Some("hardfault_plain"));
        assert_eq!(meta(&d, "multi_info_count"), Some("3"));
        assert!(d.warnings == ["no GPS topic (vehicle_gps_position or sensor_gps) with data"]);

        // Here the logged data ends on a message boundary. Simulate the real
        // case (log cut mid-message, then data appended): insert a partial
        // 200-byte message before the first offset and shift the offsets
        // (pyulog 1.3.0 reads that file with the same counts).
        let off = 434_369;
        let mut cut = bytes[..off].to_vec();
        cut.extend_from_slice(&[200, 0, b'D']);
        cut.extend_from_slice(&[0; 50]);
        cut.extend_from_slice(&bytes[off..]);
        for i in 0..3 {
            let at = 16 + 3 + 16 + 8 * i;
            let v = u64::from_le_bytes(cut[at..at + 8].try_into().unwrap()) + 53;
            cut[at..at + 8].copy_from_slice(&v.to_le_bytes());
        }
        let c = read_ulog(&cut).unwrap();
        assert_eq!(c.topic_counts, d.topic_counts);
        assert_eq!(c.warnings, d.warnings);
        assert_eq!(meta(&c, "multi_info_count"), Some("3"));
        // Ignoring the offsets (clear the incompat "data appended" bit,
        // byte 16+3+8) reads the partial message into the appended data.
        cut[27] &= !1;
        let p = read_ulog(&cut).unwrap();
        assert!(
            has_warning(&p, "truncated") && has_warning(&p, "corrupt"),
            "{:?}",
            p.warnings
        );
        assert_ne!(meta(&p, "multi_info_count"), Some("3"));
    }

    #[test]
    fn small_log_gps_matches_pyulog() {
        let d = parse(px4!("sample_log_small.ulg"));
        let gps: Vec<&Sample> = d.samples.iter().filter(|s| s.fix.is_finite()).collect();
        assert_eq!(gps.len(), 32);
        assert!(gps.iter().all(|s| s.has_fix()));
        // pyulog: first at 20471648 us, lat 63.4170622, lon 10.4082151, alt 66.814 m, 15 sats.
        let g = gps[0];
        assert_eq!(
            (g.t, g.lat, g.lon, g.alt, g.sats),
            (20.471648, 63.4170622, 10.4082151, 66.814, 15.0)
        );
        assert!(has_warning(&d, "1 logging dropouts, 0.030 s"));
    }

    // --- synthetic files ---------------------------------------------------

    fn msg(ty: u8, payload: &[u8]) -> Vec<u8> {
        let mut m = (payload.len() as u16).to_le_bytes().to_vec();
        m.push(ty);
        m.extend_from_slice(payload);
        m
    }

    fn header() -> Vec<u8> {
        let mut h = MAGIC.to_vec();
        h.push(1);
        h.extend_from_slice(&1_000_000u64.to_le_bytes());
        h
    }

    #[test]
    fn nested_types_arrays_and_padding() {
        let mut f = header();
        // Outer defined before the nested type it uses; trailing padding.
        f.extend(msg(
            b'F',
            b"sensor_combined:uint64_t timestamp;pair_t[2] pairs;float[3] gyro_rad;\
int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;uint8_t[4] _padding0;",
        ));
        // pair_t: 4 + 2*2 + 1 + 3 padding = 12 bytes
        f.extend(msg(
            b'F',
            b"pair_t:float a;int16_t[2] b;uint8_t flag;uint8_t[3] _padding0;",
        ));
        f.extend(msg(b'I', b"\x10char[3] sys_nameabc"));
        f.extend(msg(b'A', b"\x00\x07\x00sensor_combined"));
        // full size 8 + 24 + 12 + 4 + 12 + 4 = 64 bytes, 60 without padding
        let body = |t: u64, rel: i32, k: f32| {
            let mut p = 7u16.to_le_bytes().to_vec();
            p.extend_from_slice(&t.to_le_bytes());
            p.extend_from_slice(&[0xAA; 24]);
            for i in 0..3 {
                p.extend_from_slice(&(k + i as f32).to_le_bytes());
            }
            p.extend_from_slice(&rel.to_le_bytes());
            for i in 0..3 {
                p.extend_from_slice(&(10.0 * k + i as f32).to_le_bytes());
            }
            p
        };
        f.extend(msg(b'D', &body(2_000_000, 100, 1.0))); // 60 bytes: padding dropped
        let mut padded = body(2_500_000, i32::MAX, 2.0);
        padded.extend_from_slice(&[0; 4]);
        f.extend(msg(b'D', &padded)); // 64 bytes, accel invalid
        let mut short = body(3_000_000, 0, 3.0);
        short.pop();
        f.extend(msg(b'D', &short)); // 59 bytes: corrupt, skipped
        f.extend(msg(b'D', b"\x09\x00\x01\x02")); // unknown msg_id
        f.extend(msg(b'X', b"\x01\x02\x03")); // unknown type: skipped
        f.extend(msg(b'O', &250u16.to_le_bytes()));

        let d = read_ulog(&f).unwrap_or_default();
        assert_eq!(d.topic_counts, vec![("sensor_combined".to_string(), 2)]);
        assert_eq!(d.samples.len(), 2);
        let (a, b) = (d.samples[0], d.samples[1]);
        assert_eq!((a.t, a.gx, a.gy, a.gz), (2.0, 1.0, 2.0, 3.0));
        assert_eq!((a.ax, a.ay, a.az), (10.0, 11.0, 12.0));
        assert_eq!((b.t, b.gx, b.gz), (2.5, 2.0, 4.0));
        assert!(b.ax.is_nan(), "RELATIVE_TIMESTAMP_INVALID accel is dropped");
        assert_eq!(meta(&d, "sys_name"), Some("abc"));
        assert!(has_warning(&d, "1 data messages of the wrong size"));
        assert!(has_warning(&d, "1 data messages without a subscription"));
        assert!(has_warning(&d, "1 messages of unknown type"));
        assert!(has_warning(&d, "1 logging dropouts, 0.250 s"));
        assert!(d.missing.iter().any(|m| m == "gps") && d.missing.iter().any(|m| m == "attitude"));
    }

    #[test]
    fn gps_int_and_float_variants_and_no_fix_rows() {
        let mut f = header();
        f.extend(msg(b'F', b"vehicle_gps_position:uint64_t timestamp;int32_t lat;int32_t lon;int32_t alt;\
float vel_n_m_s;float vel_e_m_s;float vel_d_m_s;float eph;float epv;uint8_t fix_type;uint8_t satellites_used;"));
        f.extend(msg(b'A', b"\x00\x01\x00vehicle_gps_position"));
        let gps = |t: u64, fix: u8| {
            let mut p = 1u16.to_le_bytes().to_vec();
            p.extend_from_slice(&t.to_le_bytes());
            for v in [473_977_421i32, 85_455_938, 488_005] {
                p.extend_from_slice(&v.to_le_bytes());
            }
            for v in [1.5f32, -0.5, 0.25, 2.0, 3.0] {
                p.extend_from_slice(&v.to_le_bytes());
            }
            p.extend_from_slice(&[fix, 9]);
            p
        };
        f.extend(msg(b'D', &gps(3_000_000, 3)));
        f.extend(msg(b'D', &gps(2_000_000, 1))); // out of order: rows get sorted
        let d = read_ulog(&f).unwrap_or_default();
        assert_eq!(d.samples.len(), 2);
        let (nofix, fix) = (d.samples[0], d.samples[1]);
        assert!(
            nofix.reports_no_fix() && nofix.lat.is_nan() && nofix.alt.is_nan() && nofix.sats == 9.0
        );
        assert_eq!(
            (fix.lat, fix.lon, fix.alt),
            (47.3977421, 8.5455938, 488.005)
        );
        assert_eq!(
            (fix.vn, fix.ve, fix.vd, fix.eph, fix.epv),
            (1.5, -0.5, 0.25, 2.0, 3.0)
        );
        assert!(fix.has_fix());
    }

    #[test]
    fn rejects_non_ulog_input() {
        assert!(read_ulog(b"").is_err());
        assert!(read_ulog(b"ULog").is_err());
        assert!(read_ulog(b"not a ulog file at all, just text").is_err());
        assert!(read_ulog(&header()[..12]).is_err());
        assert!(read_ulog(&header()).is_err(), "header only: nothing usable");
        assert!(is_ulog(&header()) && !is_ulog(b"ULo"));
    }

    // --- robustness --------------------------------------------------------

    /// xorshift64: deterministic "random" bytes without a dependency.
    fn rng(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    #[test]
    fn truncation_never_panics() {
        for path in [
            px4!("sample_appended_multiple.ulg"),
            px4!("sample_logging_tagged_and_default_params.ulg"),
        ] {
            let bytes = load(path);
            let n = bytes.len();
            let mut cuts = vec![
                0,
                1,
                7,
                15,
                16,
                17,
                18,
                19,
                60,
                100,
                1000,
                5000,
                n / 3,
                n / 2,
                n - 2,
                n - 1,
            ];
            let mut s = 0x9e37_79b9_7f4a_7c15u64;
            cuts.extend((0..40).map(|_| (rng(&mut s) % n as u64) as usize));
            for cut in cuts {
                match read_ulog(&bytes[..cut]) {
                    Ok(d) => assert!(!d.warnings.is_empty(), "{path} cut at {cut}: no warning"),
                    Err(e) => assert!(cut < 20_000, "{path} cut at {cut}: {e}"),
                }
            }
            // A cut in the middle of the data keeps what was read.
            let half = read_ulog(&bytes[..n / 2]).unwrap_or_default();
            assert!(has_warning(&half, "truncated"), "{:?}", half.warnings);
            assert!(!half.samples.is_empty());
        }
    }

    #[test]
    fn byte_flips_and_garbage_never_panic() {
        let bytes = load(px4!("sample_appended_multiple.ulg"));
        let mut s = 0x1234_5678_9abc_def1u64;
        for round in 0..300 {
            let mut b = bytes.clone();
            // Mostly a few flips; sometimes many, sometimes in the definitions.
            let flips = if round % 10 == 0 { 500 } else { 1 + round % 8 };
            let span = if round % 3 == 0 { 60_000 } else { b.len() };
            for _ in 0..flips {
                let i = (rng(&mut s) % span as u64) as usize;
                b[i] ^= 1 << (rng(&mut s) % 8);
            }
            if let Ok(d) = read_ulog(&b) {
                assert!(d.samples.windows(2).all(|w| w[0].t <= w[1].t));
            }
        }
        // Random bytes after a valid header, and a valid header + random formats.
        for len in [1usize, 3, 100, 10_000, 200_000] {
            let mut b = header();
            b.extend((0..len).map(|_| rng(&mut s) as u8));
            let _ = read_ulog(&b);
        }
        let mut b = header();
        for i in 0..2000u32 {
            let r = rng(&mut s);
            let ty = [b'F', b'A', b'D', b'R', b'I', b'M', b'S', b'O'][(r % 8) as usize];
            let len = (r >> 8) % 40;
            let mut p: Vec<u8> = (0..len).map(|_| rng(&mut s) as u8).collect();
            if ty == b'F' {
                p = format!(
                    "t{}:uint64_t timestamp;t{} x;float[{}] y;",
                    i % 7,
                    (i + 1) % 7,
                    r % 5
                )
                .into_bytes();
            }
            b.extend(msg(ty, &p));
        }
        let _ = read_ulog(&b);
    }

    /// Throughput: `cargo test --release -- --ignored --nocapture throughput`.
    #[test]
    #[ignore]
    fn throughput() {
        for path in [px4!("sample.ulg"), px4!("quadrotor_local.ulg")] {
            let bytes = load(path);
            let reps = 50;
            let t0 = std::time::Instant::now();
            let mut rows = 0;
            for _ in 0..reps {
                rows += read_ulog(std::hint::black_box(&bytes)).map_or(0, |d| d.samples.len());
            }
            let secs = t0.elapsed().as_secs_f64();
            let mb = (bytes.len() * reps) as f64 / 1e6;
            println!("{path}: {:.0} MB/s ({rows} rows)", mb / secs);
        }
    }
}

//! Flight-log readers. Each turns a file into fused [`Sample`] rows (one row
//! per sensor message, sorted by boot time), plus metadata and warnings.
//!
//! The binary readers ([`ulog::UlogStream`], [`dataflash::DataflashStream`])
//! are incremental: they take the file in chunks of any size and hand each
//! row, in time order, to a [`RowSink`] as soon as it is final, so memory does
//! not grow with the file. Rows are put in time order by a bounded
//! [`Reorder`] buffer instead of a whole-file sort; the whole-bytes readers
//! ([`read_any`]) run the same code with a `Vec` as the sink.

//!
//! This is its own crate (`navguard-logs`, re-exported by navguard as
//! `navguard::logs`, with [`sample`] as `navguard::sample`) so that the
//! core wasm module can build it for size (`opt-level = "z"` in the
//! `wasm-core` profile): cargo sets the opt-level per crate, and the
//! readers are cold next to the detector's row path. It holds the row type
//! ([`Sample`]) and the readers' error ([`LogError`]) because the readers
//! make both; it depends on nothing of navguard's.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

pub use crate::error::{LogError, LogPos};
use crate::sample::Sample;

pub mod error;
pub mod sample;

pub mod csv;
pub mod decimal;
pub mod dataflash;
pub mod extras;
pub mod text;
pub mod ulog;

/// xorshift64*: the crate's tests' small deterministic generator.
#[cfg(test)]
pub(crate) struct TestRng(pub u64);

#[cfg(test)]
impl TestRng {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform-ish in `0..n` (`0` when `n` is 0).
    pub(crate) fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }

    /// [`TestRng::below`] for an index.
    pub(crate) fn index(&mut self, n: usize) -> usize {
        self.below(n as u64) as usize
    }
}

/// What a reader made of a log.
#[derive(Clone, Debug, Default)]
pub struct LogData {
    /// "csv", "ulog" or "dataflash".
    pub format: &'static str,
    /// Fused samples, sorted by `t` (s, the log's own boot clock).
    pub samples: Vec<Sample>,
    /// Vehicle and log metadata (key, value), e.g. ("sys_name", "PX4").
    pub meta: Vec<(String, String)>,
    /// Things the reader coped with: truncation, dropouts, unknown columns.
    pub warnings: Vec<String>,
    /// Detector inputs the log lacks: any of "gps", "imu", "attitude", "baro".
    pub missing: Vec<String>,
    /// Message counts per topic or message type (ULog: "topic" or "topic/multi_id").
    pub topic_counts: Vec<(String, u64)>,
    /// Receiver-quality kind, UTC time, flight modes, autopilot messages.
    pub extras: extras::Extras,
}

/// Everything a streaming reader reports at the end: a [`LogData`] without
/// its rows (they went to the sink).
#[derive(Clone, Debug, Default)]
pub struct LogSummary {
    /// "csv", "ulog" or "dataflash".
    pub format: &'static str,
    /// Vehicle and log metadata (key, value).
    pub meta: Vec<(String, String)>,
    /// Things the reader coped with.
    pub warnings: Vec<String>,
    /// Detector inputs the log lacks: any of "gps", "imu", "attitude", "baro".
    pub missing: Vec<String>,
    /// Message counts per topic or message type.
    pub topic_counts: Vec<(String, u64)>,
    /// Receiver-quality kind, UTC time, flight modes, autopilot messages.
    pub extras: extras::Extras,
}

impl LogSummary {
    fn with_rows(self, samples: Vec<Sample>) -> LogData {
        let LogSummary { format, meta, warnings, missing, topic_counts, extras } = self;
        LogData { format, samples, meta, warnings, missing, topic_counts, extras }
    }
}

/// Where a streaming reader puts its rows, in time order.
pub trait RowSink {
    /// Take the next row (rows come in time order).
    fn row(&mut self, s: &Sample);
}

impl RowSink for Vec<Sample> {
    fn row(&mut self, s: &Sample) {
        self.push(*s);
    }
}

/// A sink that drops every row (a reader's first, planning pass).
pub struct NoRows;

impl RowSink for NoRows {
    fn row(&mut self, _: &Sample) {}
}

/// Rows a [`Reorder`] buffer holds at most. A row that arrives this many rows
/// late (behind rows already handed on) cannot be put in order and is dropped,
/// with a count in the warnings. Real logs are at most a few hundred rows out
/// of order (topics published with some lag); this is minutes of data at IMU
/// rate, and 65,536 × 208 bytes = 13.6 MB at most.
pub const REORDER_ROWS: usize = 1 << 16;

/// Bytes fed to a reader per call by the whole-bytes entry points: the same
/// chunked path as a file streamed from disk.
pub const FEED_CHUNK: usize = 1 << 20;

/// Order key: time (s; -0 folded into +0 so that events compare as numbers),
/// then a reader-defined rank (what comes first at equal time), then arrival.
#[derive(Clone, Copy, Debug)]
struct Key {
    t: f64,
    rank: u8,
    seq: u64,
}

impl Key {
    fn cmp(&self, o: &Key) -> Ordering {
        self.t.total_cmp(&o.t).then(self.rank.cmp(&o.rank)).then(self.seq.cmp(&o.seq))
    }
}

/// Heap entry: key and slot of the item (items stay put; only keys move).
struct Entry(Key, u32);

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.0.cmp(&o.0) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    /// Reversed: `BinaryHeap` is a max-heap, we pop the smallest key.
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.cmp(&self.0)
    }
}

/// A bounded reorder buffer: items go in in arrival order and come out
/// sorted by (time, rank, arrival), exactly as a stable whole-file sort would
/// put them, as long as no item is more than [`REORDER_ROWS`] items late.
/// A later item is dropped and counted in [`Reorder::late`].
pub struct Reorder<T> {
    heap: BinaryHeap<Entry>,
    slots: Vec<Option<T>>,
    free: Vec<u32>,
    cap: usize,
    seq: u64,
    last: Option<Key>,
    /// Items dropped because they arrived after later ones were handed on.
    pub late: u64,
}

impl<T> Default for Reorder<T> {
    fn default() -> Self {
        Self::new(REORDER_ROWS)
    }
}

impl<T> Reorder<T> {
    /// An empty buffer that holds at most `cap` rows.
    pub fn new(cap: usize) -> Self {
        Reorder { heap: BinaryHeap::new(), slots: Vec::new(), free: Vec::new(), cap: cap.max(1), seq: 0, last: None, late: 0 }
    }


    /// True when an item of time `t` and `rank` with arrival `seq` would come
    /// out no later than everything held now.
    pub fn precedes_all(&self, t: f64, rank: u8, seq: u64) -> bool {
        let k = Key { t: t + 0.0, rank, seq };
        self.heap.peek().is_none_or(|e| k.cmp(&e.0) != Ordering::Greater)
    }

    /// Take the next arrival number, for an item pushed now or later with
    /// [`Reorder::push_at`].
    pub fn take_seq(&mut self) -> u64 {
        self.seq += 1;
        self.seq - 1
    }

    /// Add an item; when the buffer is over capacity, the smallest goes to `out`.
    pub fn push(&mut self, t: f64, rank: u8, item: T, out: &mut impl FnMut(T)) {
        let seq = self.take_seq();
        self.push_at(t, rank, seq, item, out);
    }

    /// [`Reorder::push`] with an arrival number reserved earlier.
    pub fn push_at(&mut self, t: f64, rank: u8, seq: u64, item: T, out: &mut impl FnMut(T)) {
        let key = Key { t: t + 0.0, rank, seq };
        if self.last.is_some_and(|l| key.cmp(&l) == Ordering::Less) {
            self.late += 1;
            return;
        }
        if self.heap.len() >= self.cap {
            // Full: the smallest of what is held and the new item goes on.
            if self.precedes_all(key.t, key.rank, key.seq) {
                self.last = Some(key);
                out(item);
                return;
            }
            self.pop(out);
        }
        let slot = match self.free.pop() {
            Some(i) => {
                if let Some(s) = self.slots.get_mut(i as usize) {
                    *s = Some(item);
                }
                i
            }
            None => {
                // Grow by doubling, but never past the capacity.
                if self.slots.len() == self.slots.capacity() {
                    let more = self.slots.len().max(16).min(self.cap.saturating_sub(self.slots.len()).max(1));
                    self.slots.reserve_exact(more);
                    self.heap.reserve_exact(self.slots.capacity().saturating_sub(self.heap.len()));
                }
                self.slots.push(Some(item));
                u32::try_from(self.slots.len() - 1).unwrap_or(u32::MAX)
            }
        };
        self.heap.push(Entry(key, slot));
    }

    fn pop(&mut self, out: &mut impl FnMut(T)) -> bool {
        let Some(Entry(key, slot)) = self.heap.pop() else {
            return false;
        };
        self.last = Some(key);
        if let Some(item) = self.slots.get_mut(slot as usize).and_then(Option::take) {
            self.free.push(slot);
            out(item);
        }
        true
    }

    /// Hand on everything held (end of input).
    pub fn drain(&mut self, out: &mut impl FnMut(T)) {
        while self.pop(out) {}
    }

    /// Bytes held: item slots (used or free) and heap entries.
    pub fn held_bytes(&self) -> usize {
        self.slots.capacity() * core::mem::size_of::<Option<T>>() + self.heap.capacity() * core::mem::size_of::<Entry>() + self.free.capacity() * 4
    }

    /// Items held now.
    pub fn len(&self) -> usize {
        self.heap.len()
    }

    /// Nothing held.
    pub fn is_empty(&self) -> bool {
        self.heap.is_empty()
    }
}

/// The pending bytes of a chunked binary reader: `buf[0]` is byte `base` of
/// the file. Readers parse from it by absolute position and [`Window::consume`]
/// what they are done with, so it holds at most one chunk plus the bytes a
/// message or a resync scan still needs.
#[derive(Default)]
struct Window {
    buf: Vec<u8>,
    base: u64,
}

impl Window {
    fn push(&mut self, chunk: &[u8]) {
        self.buf.extend_from_slice(chunk);
    }

    /// Bytes allocated for the window.
    fn held_bytes(&self) -> usize {
        self.buf.capacity()
    }

    /// Absolute end of the bytes held.
    fn end(&self) -> u64 {
        self.base + self.buf.len() as u64
    }

    /// Bytes from absolute `from` to absolute `to` (clamped to what is held).
    fn get(&self, from: u64, to: u64) -> &[u8] {
        let a = from.saturating_sub(self.base).min(self.buf.len() as u64) as usize;
        let b = to.saturating_sub(self.base).min(self.buf.len() as u64) as usize;
        self.buf.get(a..b.max(a)).unwrap_or(&[])
    }

    /// Forget everything before absolute `pos`.
    fn consume(&mut self, pos: u64) {
        let n = pos.saturating_sub(self.base).min(self.buf.len() as u64);
        self.buf.drain(..n as usize);
        self.base += n;
        if self.buf.capacity() > 4 * FEED_CHUNK.max(self.buf.len()) {
            self.buf.shrink_to(FEED_CHUNK.max(self.buf.len()));
        }
    }
}

/// Read any supported log, recognised by content (not by file name).
pub fn read_any(bytes: &[u8]) -> Result<LogData, LogError> {
    if ulog::is_ulog(bytes) {
        return ulog::read_ulog(bytes);
    }
    if dataflash::is_dataflash(bytes) {
        return dataflash::read_dataflash(bytes);
    }
    csv::read_csv(bytes).map_err(LogError::unrecognised)
}

/// What a file is, from its first bytes; `None` while too few bytes are in
/// to tell (fewer than the 7 of the ULog magic, and not at the end).
pub fn sniff(head: &[u8], at_end: bool) -> Option<Format> {
    if ulog::is_ulog(head) {
        return Some(Format::Ulog);
    }
    if head.len() < 7 && !at_end && ulog::MAGIC.starts_with(head) {
        return None;
    }
    if dataflash::is_dataflash(head) {
        return Some(Format::Dataflash);
    }
    if head.len() < 3 && !at_end && dataflash::HEADER.starts_with(head) {
        return None;
    }
    Some(Format::Csv)
}

/// The three input formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A navlog CSV (contract §1).
    Csv,
    /// A PX4 ULog file.
    Ulog,
    /// An ArduPilot DataFlash (`.bin`) log.
    Dataflash,
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    /// Items at most `cap` places out of order come out exactly as a stable
    /// sort by (time, rank) puts them; one later than that is counted late.
    #[test]
    fn reorder_equals_a_stable_sort_within_its_capacity() {
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut rnd = move |n: u64| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x % n
        };
        for cap in [1usize, 2, 7, 64] {
            // Sorted (time, rank) pairs with many ties, shuffled within
            // blocks of `cap`: no item is `cap` or more places out of order.
            let mut keys: Vec<(f64, u8)> = (0..2000).map(|i| ((i / 5) as f64, rnd(3) as u8)).collect();
            keys.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for block in keys.chunks_mut(cap) {
                for i in (1..block.len()).rev() {
                    block.swap(i, rnd(i as u64 + 1) as usize);
                }
            }
            let items: Vec<(f64, u8, usize)> = keys.iter().enumerate().map(|(i, k)| (k.0, k.1, i)).collect();
            let mut want = items.clone();
            want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut r = Reorder::new(cap);
            let mut got = Vec::new();
            for it in &items {
                r.push(it.0, it.1, *it, &mut |v| got.push(v));
            }
            r.drain(&mut |v| got.push(v));
            assert_eq!(r.late, 0, "cap {cap}");
            assert_eq!(got, want, "cap {cap}");
            assert!(r.slots.capacity() <= cap.max(16), "cap {cap}: {} slots", r.slots.capacity());
        }
        let mut r = Reorder::new(2);
        let mut got = Vec::new();
        for t in [5.0, 6.0, 7.0, 1.0, 8.0] {
            r.push(t, 0, t, &mut |v| got.push(v));
        }
        r.drain(&mut |v| got.push(v));
        assert_eq!(got, [5.0, 6.0, 7.0, 8.0]);
        assert_eq!(r.late, 1);
    }
}

//! ULog reader: any bytes must give `Ok` (with warnings) or `Err`, never a
//! panic, hang or huge allocation; and the streaming reader, fed the same
//! bytes in chunks cut where the input says, must give exactly the same
//! rows, metadata and warnings (or error) as the whole-bytes read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::logs::{ulog, NoRows};

#[path = "common/same.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let whole = ulog::read_ulog(data);
    // Chunk size from the last byte: 1..=64 bytes, so messages, headers and
    // sync markers are split at every offset over the corpus.
    let step = 1 + usize::from(data.last().copied().unwrap_or(0) % 64);
    let mut s = ulog::UlogStream::plan();
    for c in data.chunks(step) {
        s.feed(c, &mut NoRows);
    }
    let mut rows = Vec::new();
    let streamed = s.second_pass().and_then(|mut s2| {
        for c in data.chunks(step) {
            s2.feed(c, &mut rows);
        }
        s2.finish(&mut rows)
    });
    common::same(whole, streamed, &rows, step);
});

//! ArduPilot DataFlash reader: any bytes must give `Ok` (with warnings) or
//! `Err`, never a panic, hang or huge allocation; and the streaming reader,
//! fed the same bytes in chunks cut where the input says, must give exactly
//! the same rows, metadata and warnings (or error) as the whole-bytes read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::logs::dataflash;

#[path = "common/same.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let whole = dataflash::read_dataflash(data);
    let step = 1 + usize::from(data.last().copied().unwrap_or(0) % 64);
    let mut s = dataflash::DataflashStream::new();
    let mut rows = Vec::new();
    for c in data.chunks(step) {
        s.feed(c, &mut rows);
    }
    let streamed = s.finish(&mut rows);
    common::same(whole, streamed, &rows, step);
});

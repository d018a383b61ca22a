//! ArduPilot DataFlash reader: any bytes must give `Ok` (with warnings) or
//! `Err`, never a panic, hang or huge allocation; and the streaming reader,
//! fed the same bytes in chunks cut where the input says, must give exactly
//! the same rows, metadata and warnings (or error) as the whole-bytes read.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::logs::dataflash;
use navguard::sample::{Sample, COLUMNS};

fn bits(rows: &[Sample]) -> Vec<u64> {
    rows.iter().flat_map(|s| (0..COLUMNS.len()).map(|i| s.get(i).to_bits())).collect()
}

fuzz_target!(|data: &[u8]| {
    let whole = dataflash::read_dataflash(data);
    if let Ok(d) = &whole {
        assert_eq!(d.format, "dataflash");
        assert!(d.samples.windows(2).all(|w| !(w[1].t < w[0].t)), "samples not sorted by t");
    }
    let step = 1 + usize::from(data.last().copied().unwrap_or(0) % 64);
    let mut s = dataflash::DataflashStream::new();
    let mut rows = Vec::new();
    for c in data.chunks(step) {
        s.feed(c, &mut rows);
    }
    match (whole, s.finish(&mut rows)) {
        (Ok(d), Ok(sum)) => {
            assert_eq!(bits(&d.samples), bits(&rows), "rows differ with {step}-byte chunks");
            assert_eq!(d.meta, sum.meta);
            assert_eq!(d.warnings, sum.warnings);
            assert_eq!(d.topic_counts, sum.topic_counts);
            assert_eq!(d.missing, sum.missing);
        }
        (Err(a), Err(b)) => assert_eq!(a, b),
        (a, b) => panic!("whole {:?} vs streamed {:?}", a.err(), b.err()),
    }
});

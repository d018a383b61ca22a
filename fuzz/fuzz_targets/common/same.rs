//! Shared by the reader targets: a streamed read must equal the whole read.
use navguard::logs::{LogData, LogError, LogSummary};
use navguard::sample::{Sample, COLUMNS};

fn bits(rows: &[Sample]) -> Vec<u64> {
    rows.iter().flat_map(|s| (0..COLUMNS.len()).map(|i| s.get(i).to_bits())).collect()
}

/// Same rows (bit for bit), metadata, warnings and counts, or the same error.
pub fn same(whole: Result<LogData, LogError>, streamed: Result<LogSummary, LogError>, rows: &[Sample], step: usize) {
    match (whole, streamed) {
        (Ok(d), Ok(sum)) => {
            assert!(d.samples.windows(2).all(|w| !(w[1].t < w[0].t)), "samples not sorted by t");
            assert_eq!(bits(&d.samples), bits(rows), "rows differ with {step}-byte chunks");
            assert_eq!(d.format, sum.format);
            assert_eq!(d.meta, sum.meta);
            assert_eq!(d.warnings, sum.warnings);
            assert_eq!(d.topic_counts, sum.topic_counts);
            assert_eq!(d.missing, sum.missing);
        }
        (Err(a), Err(b)) => assert_eq!(a, b),
        (a, b) => panic!("whole {:?} vs streamed {:?}", a.err(), b.err()),
    }
}

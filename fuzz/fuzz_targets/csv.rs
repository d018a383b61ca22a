//! Navlog CSV reader: the whole-buffer `read_csv`, `read_any`, and the
//! incremental `CsvReader` fed in two chunks must agree and never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::logs::{csv, read_any};
use navguard::sample::COLUMNS;
use navguard::Sample;

fn bits(v: &[Sample]) -> Vec<u64> {
    v.iter().flat_map(|s| (0..COLUMNS.len()).map(|i| s.get(i).to_bits())).collect()
}

fuzz_target!(|data: &[u8]| {
    let whole = csv::read_csv(data);
    let _ = read_any(data);
    // Split point from the first byte; the chunked parse must equal the whole.
    let Some((&k, _)) = data.split_first() else { return };
    let cut = (k as usize * data.len()) / 256;
    let mut r = csv::CsvReader::new();
    let mut rows = Vec::new();
    let chunked = r
        .read_chunk(&data[..cut], &mut rows)
        .and_then(|()| r.read_chunk(&data[cut..], &mut rows))
        .and_then(|()| r.read_end(&mut rows));
    match (&whole, &chunked) {
        (Ok(d), Ok(())) => assert_eq!(bits(&d.samples), bits(&rows), "chunked parse differs (cut {cut})"),
        (Err(a), Err(b)) => assert_eq!(a, b, "chunked parse error differs (cut {cut})"),
        _ => panic!("whole {:?} vs chunked {:?} (cut {cut})", whole.as_ref().map(|d| d.samples.len()), chunked),
    }
});

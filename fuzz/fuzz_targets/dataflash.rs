//! ArduPilot DataFlash reader: any bytes must give `Ok` (with warnings) or
//! `Err`, never a panic, hang or huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::logs::dataflash;

fuzz_target!(|data: &[u8]| {
    if let Ok(d) = dataflash::read_dataflash(data) {
        assert_eq!(d.format, "dataflash");
        assert!(d.samples.windows(2).all(|w| !(w[1].t < w[0].t)), "samples not sorted by t");
    }
});

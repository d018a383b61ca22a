//! ULog reader: any bytes must give `Ok` (with warnings) or `Err`, never a
//! panic, hang or huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use navguard::logs::ulog;

fuzz_target!(|data: &[u8]| {
    if let Ok(d) = ulog::read_ulog(data) {
        assert_eq!(d.format, "ulog");
        assert!(d.samples.windows(2).all(|w| !(w[1].t < w[0].t)), "samples not sorted by t");
    }
});

//! Print a fingerprint of the native audit of each file: rows, flagged rows,
//! and an FNV-1a hash over every row's status and F bits. The Node test
//! `tests/node/determinism.test.mjs` compares it with the wasm build's.
//! `cargo run --release --example verdicts -- FILE...`
use navguard::audit::audit;
use navguard::config::Config;
use navguard::logs::read_any;

fn main() {
    for path in std::env::args().skip(1) {
        let Ok(bytes) = std::fs::read(&path) else {
            println!("{path}\terror\tunreadable");
            continue;
        };
        let log = match read_any(&bytes) {
            Ok(l) => l,
            Err(e) => {
                println!("{path}\terror\t{e}");
                continue;
            }
        };
        let Ok((_, cols)) = audit(&log, &Config::default()) else {
            println!("{path}\terror\taudit");
            continue;
        };
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut mix = |b: u8| {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        };
        for (s, f) in cols.status.iter().zip(&cols.f) {
            mix(*s);
            for b in f.to_bits().to_le_bytes() {
                mix(b);
            }
        }
        let flagged = cols.status.iter().filter(|s| **s == 1).count();
        println!("{path}\t{}\t{flagged}\t{h:016x}", cols.t.len());
    }
}

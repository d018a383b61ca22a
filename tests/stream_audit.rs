//! The streamed (chunked, bounded-memory) audit gives the same report and
//! per-row outputs as the whole-file audit, whatever the chunk boundaries,
//! for navlog CSV, ULog and DataFlash.

use navguard::audit::{audit, audit_bytes, Columns, StreamAudit};
use navguard::logs::read_any;
use navguard::sim::{simulate, to_csv, Scenario};
use navguard::Config;

fn whole(bytes: &[u8], cfg: &Config) -> (serde_json::Value, Columns) {
    let log = read_any(bytes).unwrap();
    let (rep, cols) = audit(&log, cfg).unwrap();
    (serde_json::to_value(&rep).unwrap(), cols)
}

/// Stream `bytes` in chunks of the given sizes (cycled), collecting outputs.
fn streamed(bytes: &[u8], cfg: &Config, sizes: &[usize]) -> (serde_json::Value, Columns) {
    let mut run = StreamAudit::new(cfg, true).unwrap();
    let mut all = Columns::default();
    loop {
        let mut pos = 0;
        for size in sizes.iter().cycle() {
            if pos >= bytes.len() {
                break;
            }
            let end = (pos + size).min(bytes.len());
            run.feed(&bytes[pos..end]).unwrap();
            all.append(run.outputs());
            pos = end;
        }
        if !run.end_pass().unwrap() {
            break;
        }
    }
    let (rep, last) = run.finish().unwrap();
    all.append(&last);
    (serde_json::to_value(&rep).unwrap(), all)
}

fn same_columns(a: &Columns, b: &Columns) {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.t), bits(&b.t));
    assert_eq!(a.status, b.status);
    assert_eq!(bits(&a.f), bits(&b.f));
    assert_eq!(bits(&a.r), bits(&b.r));
    assert_eq!(a.kind, b.kind);
    for k in 0..7 {
        assert_eq!(bits(&a.resid[k]), bits(&b.resid[k]), "residual column {k}");
    }
}

#[test]
fn streamed_equals_whole_on_a_simulated_flight_with_labels() {
    let sc = Scenario::preset("paper", 2).unwrap();
    let csv = to_csv(&sc, &simulate(&sc).unwrap());
    let cfg = Config::default();
    let (rw, cw) = whole(csv.as_bytes(), &cfg);
    assert!(rw["metrics"]["tp"].as_u64().unwrap() > 250, "labelled metrics must be computed: {}", rw["metrics"]);
    for sizes in [&[1 << 20][..], &[7, 4093, 65536, 1][..], &[csv.len()][..]] {
        let (rs, cs) = streamed(csv.as_bytes(), &cfg, sizes);
        assert_eq!(rs, rw, "chunks {sizes:?}");
        same_columns(&cs, &cw);
    }
}

#[test]
fn streamed_equals_whole_on_the_real_csv_log() {
    let bytes = std::fs::read("../shared/data/csv/ansfl_phantom4_rtk_clean.csv").expect("shared data");
    let cfg = Config::default();
    let (rw, cw) = whole(&bytes, &cfg);
    assert!(rw["gpsEpochs"].as_u64().unwrap() > 1000);
    let (rs, cs) = streamed(&bytes, &cfg, &[65_521]);
    assert_eq!(rs, rw);
    same_columns(&cs, &cw);
}

#[test]
fn bad_rows_and_bad_lines_stream_like_whole_files() {
    // A row failing validation is skipped with a warning naming its index;
    // a line that does not parse is an error naming the line, as whole.
    let text = "t,lat,lon,alt\n0,10,20,5\n0.1,95,20,5\n0.2,10,20,5\n";
    let cfg = Config::default();
    let (rw, _) = whole(text.as_bytes(), &cfg);
    let (rs, _) = streamed(text.as_bytes(), &cfg, &[5]);
    assert_eq!(rs, rw);
    let w = rs["warnings"].to_string();
    assert!(w.contains("row 1") && w.contains("lat"), "{w}");
    let mut run = StreamAudit::new(&cfg, false).unwrap();
    run.feed(b"t,lat\n0,1\n").unwrap();
    let e = run.feed(b"0.1,abc\n").unwrap_err();
    assert!(e.contains("line 3") && e.contains("abc"), "{e}");
    let e = StreamAudit::new(&cfg, false).unwrap().finish().err().unwrap();
    assert!(e.contains("no header"), "{e}");
}

/// Every shared flight log (ULog, DataFlash, CSV): streamed in odd chunks and
/// through `audit_bytes`, the report and every output equal the whole-file
/// audit's. (Bit-identical verdicts are what `audit DIR` and the CLI promise.)
#[test]
fn streamed_equals_whole_on_every_shared_log() {
    let cfg = Config::default();
    let mut n = 0;
    for dir in ["../shared/data/px4", "../shared/data/ardupilot", "../shared/data/csv"] {
        for e in std::fs::read_dir(dir).expect("shared data") {
            let path = e.unwrap().path();
            let bytes = std::fs::read(&path).unwrap();
            let (rw, cw) = whole(&bytes, &cfg);
            assert!(cw.t.len() > 50, "{path:?}");
            for sizes in [&[3, 65_537, 1000][..], &[1 << 20][..]] {
                let (rs, cs) = streamed(&bytes, &cfg, sizes);
                assert_eq!(rs, rw, "{path:?} chunks {sizes:?}");
                same_columns(&cs, &cw);
            }
            let (rb, cb) = audit_bytes(&bytes, &cfg, true).unwrap();
            assert_eq!(serde_json::to_value(&rb).unwrap(), rw, "{path:?}");
            same_columns(&cb, &cw);
            n += 1;
        }
    }
    assert_eq!(n, 13);
}

#[test]
fn a_ulog_stream_needs_its_second_pass() {
    let bytes = std::fs::read("../shared/data/px4/sample_log_small.ulg").expect("shared data");
    let mut run = StreamAudit::new(&Config::default(), false).unwrap();
    run.feed(&bytes).unwrap();
    assert_eq!(run.rows(), 0, "the first pass only plans");
    let e = run.finish().err().unwrap();
    assert!(e.contains("two passes"), "{e}");
}

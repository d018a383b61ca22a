//! Regression tests for the streaming binary readers (issue 17): memory that
//! does not grow with the file, format redefinitions, capped metadata, rows
//! out of order. The logs are generated here, message by message.

use navguard::audit::audit_bytes;
use navguard::logs::dataflash::DataflashStream;
use navguard::logs::ulog::{UlogStream, MAX_INFO};
use navguard::logs::{read_any, RowSink, REORDER_ROWS};
use navguard::sample::Sample;
use navguard::Config;

fn ulog_header() -> Vec<u8> {
    let mut v = vec![0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 0x01];
    v.extend_from_slice(&0u64.to_le_bytes());
    v
}

fn msg(ty: u8, payload: &[u8]) -> Vec<u8> {
    let mut v = (payload.len() as u16).to_le_bytes().to_vec();
    v.push(ty);
    v.extend_from_slice(payload);
    v
}

fn add(multi: u8, id: u16, name: &str) -> Vec<u8> {
    let mut p = vec![multi];
    p.extend_from_slice(&id.to_le_bytes());
    p.extend_from_slice(name.as_bytes());
    msg(b'A', &p)
}

fn data(id: u16, body: &[u8]) -> Vec<u8> {
    let mut p = id.to_le_bytes().to_vec();
    p.extend_from_slice(body);
    msg(b'D', &p)
}

/// Counts rows and checks they come in time order.
#[derive(Default)]
struct Count {
    rows: u64,
    last_t: f64,
    out_of_order: u64,
}

impl RowSink for Count {
    fn row(&mut self, s: &Sample) {
        if s.t < self.last_t {
            self.out_of_order += 1;
        }
        self.last_t = s.t;
        self.rows += 1;
    }
}

/// A ULog of `n` 9-byte IMU messages (uint32 timestamps, 200 µs apart),
/// made in pieces of about 1 MB.
fn tiny_ulog_pieces(n: u32) -> impl Iterator<Item = Vec<u8>> {
    let mut head = ulog_header();
    head.extend(msg(b'F', b"sensor_combined:uint32_t timestamp"));
    head.extend(add(0, 0, "sensor_combined"));
    let per = 100_000u32;
    std::iter::once(head).chain((0..n.div_ceil(per)).map(move |k| {
        let mut v = Vec::with_capacity(per as usize * 9);
        for i in k * per + 1..=((k + 1) * per).min(n) {
            v.extend(data(0, &(i * 200).to_le_bytes()));
        }
        v
    }))
}

#[test]
fn a_large_tiny_message_ulog_streams_in_flat_memory() {
    // 3 M rows (27 MB): as a Vec<Sample> that would be 624 MB.
    let n = 3_000_000;
    for pass in 0..2 {
        let mut r = UlogStream::plan();
        let mut sink = Count::default();
        let mut peak = 0;
        for piece in tiny_ulog_pieces(n) {
            r.feed(&piece, &mut sink);
            peak = peak.max(r.held_bytes());
        }
        if pass == 0 {
            assert_eq!(sink.rows, 0, "the first pass emits nothing");
            continue;
        }
        let mut r2 = r.second_pass().unwrap();
        for piece in tiny_ulog_pieces(n) {
            r2.feed(&piece, &mut sink);
            peak = peak.max(r2.held_bytes());
        }
        let sum = r2.finish(&mut sink).unwrap();
        assert_eq!(sink.rows, u64::from(n));
        assert_eq!(sink.out_of_order, 0);
        // The reorder buffer (65,536 rows) plus one piece of input, whatever n.
        let bound = REORDER_ROWS * (std::mem::size_of::<Sample>() + 64) + (4 << 20);
        assert!(peak < bound, "held {peak} bytes, bound {bound}");
        assert!(peak > REORDER_ROWS * std::mem::size_of::<Sample>(), "the buffer fills: {peak}");
        assert!(sum.topic_counts.contains(&("sensor_combined".to_string(), u64::from(n))));
    }
}

#[test]
fn a_large_tiny_message_dataflash_streams_in_flat_memory() {
    let mut fmt = vec![0xa3, 0x95, 128, 10, 11];
    fmt.extend_from_slice(b"IMU\0");
    let mut f = [0u8; 16];
    f[0] = b'Q';
    fmt.extend_from_slice(&f);
    let mut c = [0u8; 64];
    c[..6].copy_from_slice(b"TimeUS");
    fmt.extend_from_slice(&c);
    let mut first = vec![0xa3, 0x95, 128, 128, 89];
    first.extend_from_slice(b"FMT\0");
    let mut f = [0u8; 16];
    f[..5].copy_from_slice(b"BBnNZ");
    first.extend_from_slice(&f);
    first.extend_from_slice(&[0u8; 64]);
    let n = 2_000_000u64;
    let mut r = DataflashStream::new();
    let mut sink = Count::default();
    r.feed(&first, &mut sink);
    r.feed(&fmt, &mut sink);
    let mut peak = 0;
    for k in 0..n / 100_000 {
        let mut v = Vec::with_capacity(1_100_000);
        for i in k * 100_000 + 1..=(k + 1) * 100_000 {
            v.extend_from_slice(&[0xa3, 0x95, 10]);
            v.extend_from_slice(&(i * 200).to_le_bytes());
        }
        r.feed(&v, &mut sink);
        peak = peak.max(r.held_bytes());
    }
    let sum = r.finish(&mut sink).unwrap();
    assert_eq!(sink.rows, n);
    assert_eq!(sink.out_of_order, 0);
    let bound = REORDER_ROWS * (std::mem::size_of::<Sample>() + 64) + (4 << 20);
    assert!(peak < bound, "held {peak} bytes, bound {bound}");
    assert!(sum.topic_counts.contains(&("IMU".to_string(), n)), "{:?}", sum.topic_counts);
}

#[test]
fn a_format_redefined_200_times_is_read_with_the_current_layout() {
    // Each round redefines sensor_combined with a different trailing field
    // (so a different message size), subscribes it under a new id and logs
    // 1000 messages of the new size. With a stale layout they would be
    // dropped as "wrong size" (the red team's 171k of 200k).
    let mut f = ulog_header();
    let rounds = 200u32;
    let mut t = 0u64;
    for r in 0..rounds {
        let extra = 1 + r % 5; // 1..5 extra float fields
        let fields: String = (0..extra).map(|k| format!("float x{k};")).collect();
        f.extend(msg(b'F', format!("sensor_combined:uint64_t timestamp;float[3] gyro_rad;{fields}").as_bytes()));
        f.extend(add(0, r as u16, "sensor_combined"));
        for _ in 0..1000 {
            t += 1000;
            let mut body = t.to_le_bytes().to_vec();
            body.extend(std::iter::repeat_n(0u8, 12 + 4 * extra as usize));
            f.extend(data(r as u16, &body));
        }
    }
    let log = read_any(&f).unwrap();
    assert_eq!(log.samples.len(), 200_000);
    assert!(!log.warnings.iter().any(|w| w.contains("wrong size")), "{:?}", log.warnings);
    assert!(log.topic_counts.contains(&("sensor_combined".to_string(), 200_000)));
}

#[test]
fn dropped_data_messages_are_counted_in_the_warnings() {
    // Messages longer than their format are dropped, and said so.
    let mut f = ulog_header();
    f.extend(msg(b'F', b"sensor_combined:uint64_t timestamp;float[3] gyro_rad"));
    f.extend(add(0, 0, "sensor_combined"));
    for i in 1..=10u64 {
        let mut body = (i * 1000).to_le_bytes().to_vec();
        body.extend(std::iter::repeat_n(0u8, if i % 2 == 0 { 16 } else { 12 }));
        f.extend(data(0, &body));
    }
    let log = read_any(&f).unwrap();
    assert_eq!(log.samples.len(), 5);
    assert!(log.warnings.iter().any(|w| w == "5 data messages of the wrong size skipped"), "{:?}", log.warnings);
}

#[test]
fn hostile_format_churn_stays_within_the_layout_budget_and_says_so() {
    // A 2,000-field topic over a nested type that is redefined before every
    // subscription: each one recomputes the layout. The work is capped in
    // proportion to the bytes read, and the ignored subscriptions counted.
    let mut f = ulog_header();
    f.extend(msg(b'F', b"x:uint8_t a"));
    let fields: String = (0..2000).map(|k| format!("x f{k};")).collect();
    f.extend(msg(b'F', format!("big:uint64_t timestamp;{fields}").as_bytes()));
    for r in 0..20_000u32 {
        f.extend(msg(b'F', if r % 2 == 0 { b"x:uint16_t a".as_slice() } else { b"x:uint8_t a".as_slice() }));
        f.extend(add(0, 0, "big"));
    }
    let log = read_any(&f).unwrap();
    let w = log.warnings.join("\n");
    assert!(w.contains("layout work limit"), "{w}");
    assert!(w.contains("subscriptions with an unknown or unresolvable format ignored"), "{w}");
}

#[test]
fn info_messages_are_capped_with_a_warning() {
    // 5,000 info messages full of control characters (the JSON output bomb).
    let mut f = ulog_header();
    f.extend(msg(b'F', b"sensor_combined:uint64_t timestamp;float[3] gyro_rad"));
    for i in 0..5000 {
        let key = format!("char[200] k{i}");
        let mut p = vec![key.len() as u8];
        p.extend_from_slice(key.as_bytes());
        p.extend(std::iter::repeat_n(0x01u8, 200));
        f.extend(msg(b'I', &p));
    }
    f.extend(add(0, 0, "sensor_combined"));
    for i in 1..=100u64 {
        let mut body = (i * 4000).to_le_bytes().to_vec();
        body.extend([0u8; 12]);
        f.extend(data(0, &body));
    }
    let log = read_any(&f).unwrap();
    let infos = log.meta.iter().filter(|(k, _)| k.starts_with('k')).count();
    assert_eq!(infos, MAX_INFO);
    let want = format!("{} info messages not kept in meta (at most {MAX_INFO} are)", 5000 - MAX_INFO);
    assert!(log.warnings.contains(&want), "{:?}", log.warnings);
    // The JSON report stays small: 256 entries of 200 escaped bytes.
    let (rep, _) = audit_bytes(&f, &Config::default(), false).unwrap();
    let json = serde_json::to_string(&rep).unwrap();
    assert!(json.len() < 2_000_000, "{} bytes", json.len());
    assert!(rep.warnings.contains(&want));
}

#[test]
fn rows_more_than_the_reorder_buffer_late_are_dropped_and_counted() {
    // One GPS row stamped before 70,000 IMU rows that precede it in the file.
    let mut f = ulog_header();
    f.extend(msg(b'F', b"sensor_combined:uint32_t timestamp"));
    f.extend(msg(b'F', b"sensor_gps:uint64_t timestamp;uint8_t fix_type"));
    f.extend(add(0, 0, "sensor_combined"));
    f.extend(add(0, 1, "sensor_gps"));
    for i in 1..=70_000u32 {
        f.extend(data(0, &(1_000_000 + i * 100).to_le_bytes()));
    }
    let mut g = 500_000u64.to_le_bytes().to_vec();
    g.push(0);
    f.extend(data(1, &g));
    let log = read_any(&f).unwrap();
    assert_eq!(log.samples.len(), 70_000);
    assert!(log.warnings.iter().any(|w| w == &format!("1 rows dropped: more than {REORDER_ROWS} rows out of time order")), "{:?}", log.warnings);
    assert!(log.samples.windows(2).all(|w| w[0].t <= w[1].t));
}

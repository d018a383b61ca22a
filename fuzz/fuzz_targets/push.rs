//! The streaming detector: an arbitrary config (built field by field, sent
//! through `ConfigInput::from_json` as the JS API does) and a sequence of
//! `Detector::push` calls with arbitrary `Sample` rows. `push` must return
//! `Ok` or an `InputError`, never panic, and its outputs must stay sane.
#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use navguard::detector::{kind, Model};
use navguard::sample::COLUMNS;
use navguard::{ConfigInput, Detector, Sample};

/// A number: mostly plausible (a base value plus a scaled small integer) so
/// rows get past validation, sometimes anything at all.
#[derive(Debug, Clone, Copy)]
enum Num {
    Absent,
    Near(i16),
    Raw(f64),
}

impl<'a> Arbitrary<'a> for Num {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        // Mostly plausible values, so that rows get past validation.
        Ok(match u8::arbitrary(u)? {
            0..=23 => Num::Absent,
            24..=239 => Num::Near(i16::arbitrary(u)?),
            _ => Num::Raw(f64::arbitrary(u)?),
        })
    }
}

/// Plausible base and step per column (contract order, see `COLUMNS`).
const BASE: [(f64, f64); 28] = [
    (0.0, 1e-3),                                    // t (a step, see below)
    (47.0, 1e-6), (8.0, 1e-6), (500.0, 0.01),       // lat lon alt
    (0.0, 0.05), (0.0, 0.05), (0.0, 0.05),          // pn pe pd
    (0.0, 0.01), (0.0, 0.01), (0.0, 0.01),          // vn ve vd
    (3.0, 1.0), (10.0, 1.0), (1.0, 0.01), (1.5, 0.01), // fix sats eph epv
    (0.0, 0.01), (0.0, 0.01), (-9.81, 0.01),        // ax ay az
    (0.0, 0.001), (0.0, 0.001), (0.0, 0.001),       // gx gy gz
    (1.0, 1e-4), (0.0, 1e-4), (0.0, 1e-4), (0.0, 1e-4), // qw qx qy qz
    (500.0, 0.01), (0.0, 1.0),                      // baro label
    (1.3e9, 0.2),                                   // gps_time
    (0.3, 0.01),                                    // sacc
];

impl Num {
    fn value(self, col: usize) -> f64 {
        let (base, step) = BASE[col];
        match self {
            Num::Absent => f64::NAN,
            Num::Near(k) => base + step * f64::from(k),
            Num::Raw(x) => x,
        }
    }
    fn cfg(self, scale: f64) -> Option<f64> {
        match self {
            Num::Absent => None,
            Num::Near(k) => Some(scale * f64::from(k)),
            Num::Raw(x) => Some(x),
        }
    }
}

/// Which sensor groups a row carries (bit set), and the values.
#[derive(Arbitrary, Debug)]
struct Row {
    /// Time step to the previous row in ms (or a raw time).
    dt: Num,
    groups: u8,
    vals: [Num; 28],
    /// Emit the row this many more times (0..=63), each `dt` later and with
    /// the position moved by `drift` steps: long flights from short inputs.
    repeat: u8,
    drift: i8,
}

#[derive(Arbitrary, Debug)]
struct Cfg {
    tc: Num,
    q: Num,
    window: Num,
    threshold: Num,
    retrain: Option<bool>,
    sigmas: [Num; 6],
    outage_timeout: Num,
    max_coast: Num,
    data_gap: Num,
    /// Replace the embedded model by a perturbed copy.
    model: Option<ModelEdit>,
}

#[derive(Arbitrary, Debug)]
struct ModelEdit {
    centre: [[i8; 3]; 2],
    sigma: [[i8; 3]; 2],
    conseq: Vec<(u8, u8, i16)>,
    d1: Vec<[i8; 2]>,
    d2: Vec<[i8; 2]>,
}

/// Column indices per group bit: GPS LLA, NED pos, vel, fix/sats/eph/epv/gps_time/sacc, accel, gyro, quat, baro+label.
const GROUPS: [&[usize]; 8] = [&[1, 2, 3], &[4, 5, 6], &[7, 8, 9], &[10, 11, 12, 13, 26, 27], &[14, 15, 16], &[17, 18, 19], &[20, 21, 22, 23], &[24, 25]];

fn config_json(c: &Cfg, u: &mut Unstructured) -> String {
    let mut m = serde_json::Map::new();
    let mut put = |k: &str, v: Option<f64>| {
        if let Some(x) = v {
            // serde_json writes a non-finite f64 as null: a type error, which is fine.
            m.insert(k.into(), serde_json::json!(x));
        }
    };
    put("tc", c.tc.cfg(1.0).map(f64::abs));
    put("q", c.q.cfg(1.0).map(f64::abs));
    put("window", c.window.cfg(1.0).map(f64::abs));
    put("threshold", c.threshold.cfg(0.01));
    let names = ["gpsPosSigma", "gpsAltSigma", "gpsVelSigma", "baroSigma", "accelNoise", "cvAccelNoise"];
    for (n, s) in names.iter().zip(c.sigmas) {
        put(n, s.cfg(0.01));
    }
    put("outageTimeout", c.outage_timeout.cfg(0.01));
    put("maxCoast", c.max_coast.cfg(0.1));
    put("dataGap", c.data_gap.cfg(0.01));
    if let Some(r) = c.retrain {
        m.insert("retrain".into(), r.into());
    }
    if let Some(e) = &c.model {
        let mut model = Model::embedded().expect("embedded model");
        for i in 0..2 {
            for j in 0..3 {
                model.anfis.centre[i][j] += f64::from(e.centre[i][j]) * 0.05;
                model.anfis.sigma[i][j] += f64::from(e.sigma[i][j]) * 0.01;
            }
        }
        let rules = model.anfis.conseq.len();
        for &(r, p, v) in e.conseq.iter().take(16) {
            let row = &mut model.anfis.conseq[usize::from(r) % rules];
            let n = row.len();
            row[usize::from(p) % n] += f64::from(v) * 0.01;
        }
        let pt = |x: &[i8; 2]| [f64::from(x[0]) * 0.05, f64::from(x[1]) / 128.0];
        model.d1.extend(e.d1.iter().take(256).map(pt));
        model.d2.extend(e.d2.iter().take(256).map(pt));
        m.insert("model".into(), serde_json::to_value(&model).expect("model serialises"));
    }
    if u.arbitrary::<bool>().unwrap_or(false) {
        m.insert("method".into(), "anfis".into());
    }
    serde_json::Value::Object(m).to_string()
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let Ok(cfg_in) = Cfg::arbitrary(&mut u) else { return };
    let json = config_json(&cfg_in, &mut u);
    let cfg = match ConfigInput::from_json(&json) {
        Ok(c) => c,
        Err(e) => {
            assert!(e.to_string().starts_with("config"), "config error without its prefix: {e}");
            navguard::Config::default()
        }
    };
    // Bound the work per input: retraining costs O(q) per fault epoch.
    let mut det = Detector::new(cfg).expect("a checked config builds a detector");
    let mut t = 0.0f64;
    let mut rows = 0u32;
    // `arbitrary` pads an exhausted input with zeros: stop at its end instead.
    while rows < 2000 && !u.is_empty() {
        let Ok(r) = Row::arbitrary(&mut u) else { break };
        let copies = 1 + u32::from(r.repeat % 64);
        for k in 0..copies {
            if rows >= 2000 {
                break;
            }
            rows += 1;
            t = match r.dt {
                Num::Absent => t,
                Num::Near(ms) => t + f64::from(ms.unsigned_abs()) * 1e-3,
                Num::Raw(x) => x,
            };
            let mut s = Sample::at(t);
            for (g, cols) in GROUPS.iter().enumerate() {
                if r.groups & (1 << g) != 0 {
                    for &c in cols.iter() {
                        let mut v = r.vals[c].value(c);
                        if (1..=6).contains(&c) {
                            v += f64::from(r.drift) * f64::from(k) * BASE[c].1;
                        }
                        if c == 26 {
                            v += f64::from(k) * BASE[c].1; // the receiver's time advances
                        }
                        s.set(c, v);
                    }
                }
            }
            let before = det.stats();
            match det.push(&s) {
                Ok(o) => {
                    assert!(o.status <= 1 && o.kind <= kind::UPSET, "{o:?}");
                    assert!(o.t == s.t, "output time {} for row time {}", o.t, s.t);
                    assert!(!o.f.is_nan() || o.kind == kind::NO_GPS, "F is NaN on a verdict row: {o:?} for {s:?}");
                }
                Err(e) => {
                    assert!(COLUMNS.contains(&e.field), "{e}");
                    assert_eq!(before, det.stats(), "a rejected row changed the detector");
                }
            }
        }
    }
});

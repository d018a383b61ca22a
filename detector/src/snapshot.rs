//! Snapshot and restore of a [`Detector`]: the whole streaming state (filter,
//! indicator windows, databases D1/D2 and D0, ANFIS parameters, counters,
//! config) as bytes, so a ground station can reload mid-flight and resume
//! with outputs bit-identical to a run that never stopped.
//!
//! Layout: a header `{format, version, crate_version, checksum}` followed by
//! the body, both written by [`crate::codec`] (postcard's bytes: compact,
//! every f64 bit-exact, NaN included, which JSON cannot; hand-written per
//! type, so the core wasm module carries no serde for it). The header is read
//! first, so a snapshot from another format version is refused by name
//! before its body is parsed. The checksum (FNV-1a 64 over the body) catches
//! storage corruption; the body is then checked against a fresh detector of
//! its config, so a damaged or forged snapshot is an error, never a panic
//! on a later push.

use serde::Serialize;

use crate::codec::{self, impl_codec, Codec, Reader};
use crate::detector::Detector;

/// A snapshot that cannot be written or read back: not a snapshot, another
/// format version, damaged (checksum) or forged (inconsistent state).
/// Displays as `snapshot: <message>`.
#[derive(Clone, Debug, PartialEq)]
pub struct SnapshotError {
    /// What was wrong.
    pub message: String,
}

impl SnapshotError {
    fn new(message: impl Into<String>) -> Self {
        SnapshotError { message: message.into() }
    }
}

impl core::fmt::Display for SnapshotError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "snapshot: {}", self.message)
    }
}

impl std::error::Error for SnapshotError {}

/// Format tag at the start of every snapshot.
pub const FORMAT: &str = "navguard-snapshot";
/// Bumped whenever the detector's state layout changes; older snapshots are
/// then refused with a message naming both versions. 3: the detector's
/// fields grouped into per-stage sub-states (postcard writes fields in
/// declaration order, so the byte layout moved). 4: each indicator axis
/// counts the epochs its σ_Δ learnt from, and the position–velocity test
/// its two scales (fast start). 5: the receiver clock keeps the last new
/// fix's fields (a frozen receiver's repeats are not epochs), and the
/// detector learns the receiver's usual accuracy claim. 6: the boot-clock
/// rate's fit against the receiver's own time (`gps_time`). 7: a
/// position episode keeps the offset it re-anchored onto when it coasted
/// out. 8: the baro's level against the GPS altitude and the integrated
/// GPS vertical velocity. 9: the receiver's own declaration of a degraded
/// fix (`kind::DEGRADED`) and the run of usual fixes that lifts it. 10:
/// the baro's drift test over 30 s against both GPS references
/// (`drift::DriftTest`). 11: the position's ramp test off its velocity
/// track (`ramp::RampTest`). 12: the two share one window (`window::Window`).
/// 13: their statistics are no longer kept between epochs. 14: the
/// horizontal drag-off's end confirmation (`dragend::DragEnd`), the
/// vehicle-upset gate (`kind::UPSET`) and the IMU's sample interval. 15:
/// the baro's flatline test (`flatline::Flatline`). 16: the position's
/// ramp test knows a restart from its first start and which arm called
/// (`ramp::RampTest`). 17: the tracks carry the motion and the baro
/// levels' error model (`track::VelocityTrack`). 18: the tracks keep where
/// they began (`track::VelocityTrack::back_to_origin`). 19: the tracks learn
/// their epoch-to-epoch change (`VelocityTrack::ms_step`), the scale a
/// return jump is measured on. 20: a drag-off's end is confirmed on the
/// vertical too (`dragend::DragEnds`). 21: the receiver's usual speed
/// accuracy claim (`ReceiverQuality::speed`) and the epoch's claim scale in
/// the indicator engine. 22: the withheld baro's departure from its levels
/// (`Consistency::baro_held`). 23: the baro drift test's peak statistic
/// and when it last grew (`DriftTest::peak`, `t_grew`). 24: a drag-off's
/// end ruled out (`DragEnd::ruled_out`), the episode's long coast
/// (`Episode::long_coast`), the GPS track's quick origin
/// (`VelocityTrack::quick_origin`). 25: the drag-off's end confirmation's
/// short shape (`dragend::ShiftRms`, one per shape). 26: the baro's
/// jump remembered (`barojump::BaroJump`). 27: the ramp test's fast arm
/// (`ramp::RampTest::fast_stat`). 28: the IMU tests' learning bound
/// (`LagTest::learn_below`) and the bias estimate an IMU episode rolls the
/// filter back to (`Detector::bias_calm`). 29: a position episode opened
/// on a step's onset (`Episode::fresh`). 30: the horizontal ground
/// velocity in the baro drift test's motion (`window::Motion::v_ne`) and
/// its pending GPS return (`DriftTest::near_before`). 31: the IMU test
/// judged by its window's slope (`LagTest::push_by_slope`). 32: the
/// tracks' short mean (`VelocityTrack::dm`, `ms_mean`, `since_calm`) and
/// the episode's hold on it (`Episode::mean_hold`). 33: the motion at the
/// baro's remembered jump (`barojump::BaroJump::motion`).
pub const VERSION: u32 = 33;

#[derive(Clone)]
struct Header {
    format: String,
    version: u32,
    crate_version: String,
    checksum: u64,
}
impl_codec!(Header { format, version, crate_version, checksum });

/// What a snapshot says about itself (readable without restoring it).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Info {
    /// Snapshot format version ([`VERSION`] when this build can read it).
    pub version: u32,
    /// The navguard version that wrote it.
    pub crate_version: String,
    /// Size of the snapshot, bytes.
    pub bytes: usize,
}

#[inline]
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

#[inline]
fn header(bytes: &[u8]) -> Result<(Header, &[u8]), SnapshotError> {
    let mut r = Reader::new(bytes);
    let h = Header::decode(&mut r);
    let body = r.rest();
    r.finish().map_err(|e| SnapshotError::new(format!("not a navguard snapshot ({e}, {} bytes)", bytes.len())))?;
    if h.format != FORMAT {
        return Err(SnapshotError::new(format!("format \"{}\" is not \"{FORMAT}\"", h.format)));
    }
    if h.version != VERSION {
        return Err(SnapshotError::new(format!(
            "version {} (written by navguard {}) cannot be read by navguard {}, which reads version {VERSION}",
            h.version,
            h.crate_version,
            env!("CARGO_PKG_VERSION")
        )));
    }
    if fnv1a(body) != h.checksum {
        return Err(SnapshotError::new(format!("checksum mismatch ({} body bytes): the snapshot is damaged", body.len())));
    }
    Ok((h, body))
}

/// Read a snapshot's header (and verify its checksum) without restoring it.
#[inline]
pub fn info(bytes: &[u8]) -> Result<Info, SnapshotError> {
    let (h, _) = header(bytes)?;
    Ok(Info { version: h.version, crate_version: h.crate_version, bytes: bytes.len() })
}

impl Detector {
    /// The detector's whole state as bytes (see the module docs).
    #[inline]
    pub fn snapshot(&self) -> Result<Vec<u8>, SnapshotError> {
        let body = codec::to_bytes(self);
        let h = Header {
            format: FORMAT.into(),
            version: VERSION,
            crate_version: env!("CARGO_PKG_VERSION").into(),
            checksum: fnv1a(&body),
        };
        let mut out = codec::to_bytes(&h);
        out.extend_from_slice(&body);
        Ok(out)
    }

    /// A detector resumed from [`Detector::snapshot`] bytes: it continues
    /// exactly where the snapshotted one stood.
    #[inline]
    pub fn restore(bytes: &[u8]) -> Result<Detector, SnapshotError> {
        let (_, body) = header(bytes)?;
        let mut r = Reader::new(body);
        let mut det = Detector::decode(&mut r);
        let rest = r.rest().len();
        r.finish().map_err(|e| SnapshotError::new(format!("body does not parse: {e}")))?;
        if rest > 0 {
            return Err(SnapshotError::new(format!("{rest} unexpected bytes after the body")));
        }
        det.check_restored().map_err(|e| SnapshotError::new(e.to_string()))?;
        Ok(det)
    }
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::detector::Output;
    use navguard::sim;
    use proptest::prelude::*;

    fn run(det: &mut Detector, rows: &[crate::sample::Sample]) -> Vec<Output> {
        rows.iter().map(|s| det.push(s).expect("simulated rows are valid")).collect()
    }

    /// Outputs compared bit for bit (NaN == NaN by bits).
    fn same(a: &[Output], b: &[Output]) -> Result<(), String> {
        if a.len() != b.len() {
            return Err(format!("{} vs {} outputs", a.len(), b.len()));
        }
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            let bits = |o: &Output| (o.t.to_bits(), o.status, o.f.to_bits(), o.r.to_bits(), o.c.to_bits(), o.kind, o.gps_epoch, o.driver);
            if bits(x) != bits(y) {
                return Err(format!("row {i}: {x:?} vs {y:?}"));
            }
        }
        Ok(())
    }

    fn scenario() -> Vec<crate::sample::Sample> {
        sim::simulate(&sim::Scenario::preset("paper", 3).unwrap()).unwrap()
    }

    #[test]
    fn round_trip_mid_stream_is_bit_identical() {
        let rows = scenario();
        let cfg = Config::default();
        let mut whole = Detector::new(cfg.clone()).unwrap();
        let all = run(&mut whole, &rows);
        // Split inside an outage (30–40 s) with retraining under way.
        let cut = rows.iter().position(|s| s.t >= 35.0).unwrap();
        let mut a = Detector::new(cfg).unwrap();
        let mut out = run(&mut a, &rows[..cut]);
        let snap = a.snapshot().unwrap();
        drop(a);
        let mut b = Detector::restore(&snap).unwrap();
        out.extend(run(&mut b, &rows[cut..]));
        same(&all, &out).unwrap();
        assert_eq!(b.stats(), whole.stats());
        assert!(whole.stats().retrains > 0, "the scenario must exercise retraining");
        assert_eq!(info(&snap).unwrap().version, VERSION);
    }

    #[test]
    fn damaged_or_foreign_snapshots_are_errors() {
        let rows = scenario();
        let mut d = Detector::new(Config::default()).unwrap();
        run(&mut d, &rows[..2000]);
        let snap = d.snapshot().unwrap();
        let e = Detector::restore(&[]).unwrap_err();
        assert!(e.message.starts_with("not a navguard snapshot"), "{e:?}");
        assert_eq!(e.to_string(), format!("snapshot: {}", e.message));
        assert!(Detector::restore(b"hello world").unwrap_err().to_string().contains("snapshot"));
        let mut bad = snap.clone();
        let n = bad.len();
        bad[n / 2] ^= 0x40;
        assert!(Detector::restore(&bad).unwrap_err().to_string().contains("checksum"));
        assert!(Detector::restore(&snap[..n - 7]).unwrap_err().to_string().contains("checksum"));
        // Another format version is refused by name.
        let (h, body) = header(&snap).unwrap();
        let other = Header { version: VERSION + 1, ..h.clone() };
        let mut v2 = codec::to_bytes(&other);
        v2.extend_from_slice(body);
        let e = Detector::restore(&v2).unwrap_err().to_string();
        assert!(e.contains(&format!("version {}", VERSION + 1)) && e.contains(&format!("reads version {VERSION}")), "{e}");
        // So is an older one (version 4: the layout before the receiver
        // clock kept the last fix's fields), before its body is parsed.
        let older = Header { version: 4, ..h };
        let mut v_old = codec::to_bytes(&older);
        v_old.extend_from_slice(body);
        let e = Detector::restore(&v_old).unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "snapshot: version 4 (written by navguard {}) cannot be read by navguard {}, which reads version {VERSION}",
                env!("CARGO_PKG_VERSION"),
                env!("CARGO_PKG_VERSION")
            )
        );
        // A forged body with a valid checksum: an out-of-range ring head is
        // caught by the shape check, not by a panic on the next push.
        let mut forged = d.clone();
        forged.forge_ring_head_for_test(usize::MAX / 2);
        let e = Detector::restore(&forged.snapshot().unwrap()).unwrap_err().to_string();
        assert!(e.contains("database D1"), "{e}");
    }

    /// `Debug` text with the fields a snapshot does not keep (the learning
    /// stage's scratch buffers and cost counters, and the episode's dating
    /// for the reconciled verdict) cut out: each up to the comma or the
    /// closing bracket that ends it.
    fn without_skipped(debug: &str) -> String {
        let mut s = debug.to_string();
        for field in ["train_x: ", "train_y: ", "cost: ", "dating: "] {
            let Some(start) = s.find(field) else { panic!("no {field} in the Debug text") };
            let mut depth = 0;
            let mut end = s.len();
            for (i, c) in s[start..].char_indices() {
                match c {
                    '[' | '{' | '(' => depth += 1,
                    ']' | '}' | ')' if depth == 0 => {
                        end = start + i;
                        break;
                    }
                    ']' | '}' | ')' => depth -= 1,
                    ',' if depth == 0 => {
                        end = start + i;
                        break;
                    }
                    _ => {}
                }
            }
            s.replace_range(start..end, "");
        }
        s
    }

    /// The codec writes exactly what postcard wrote from serde's derives of
    /// the same structs (the format before the codec): a field the
    /// codec's lists reorder shows here, for every method, mid-run and after
    /// a long run (every Option filled, rings wrapped, retrains done). A
    /// field they leave out does not compile. The restored detector is the
    /// same state, field by field (Debug prints every field).
    #[test]
    fn codec_writes_postcard_of_the_serde_derives() {
        let check = |d: &Detector| {
            let ours = codec::to_bytes(d);
            assert!(ours == postcard::to_allocvec(d).unwrap(), "codec and serde+postcard differ");
            let back = Detector::restore(&d.snapshot().unwrap()).unwrap();
            let (x, y) = (without_skipped(&format!("{back:?}")), without_skipped(&format!("{d:?}")));
            assert!(x == y, "restored state differs: {}", &x[(0..x.len()).find(|&i| x[i..].bytes().next() != y[i..].bytes().next()).unwrap_or(0)..].chars().take(200).collect::<String>());
        };
        let kinds = ["paper", "step", "noise", "baro-stuck"];
        for (i, &method) in crate::methods::Method::ALL.iter().enumerate() {
            let rows = sim::simulate(&sim::Scenario::preset(kinds[i % kinds.len()], 3).unwrap()).unwrap();
            let mut d = Detector::new(Config { tc: 20, method, ..Config::default() }).unwrap();
            let half = rows.len() / 2;
            run(&mut d, &rows[..half]);
            check(&d);
            run(&mut d, &rows[half..]);
            check(&d);
            assert!(d.stats().retrains > 0 || method != crate::methods::Method::Anfis);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]
        /// A forged body (bytes changed, cut or added, with a valid
        /// checksum, so the decoder itself is the only guard): restore is an
        /// error or a detector that takes rows, never a panic or a huge
        /// allocation.
        #[test]
        fn forged_bodies_never_panic(at in 0.0f64..1.0, byte in any::<u8>(), cut in 0usize..40, extra in proptest::collection::vec(any::<u8>(), 0..12)) {
            let rows = scenario();
            let mut d = Detector::new(Config { method: crate::methods::Method::Knee, ..Config::default() }).unwrap();
            run(&mut d, &rows[..1500]);
            let snap = d.snapshot().unwrap();
            let (h, body) = header(&snap).unwrap();
            let mut body = body.to_vec();
            let i = ((at * body.len() as f64) as usize).min(body.len() - 1);
            body[i] = byte;
            body.truncate(body.len().saturating_sub(cut));
            body.extend_from_slice(&extra);
            let forged = Header { checksum: fnv1a(&body), ..h };
            let mut bytes = codec::to_bytes(&forged);
            bytes.extend_from_slice(&body);
            if let Ok(mut back) = Detector::restore(&bytes) {
                for s in &rows[1500..1600] {
                    let _ = back.push(s);
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]
        /// Any split point, any scenario kind: snapshot, restore and continue
        /// give the same statuses and F values, bit for bit.
        #[test]
        fn split_anywhere(kind in 0usize..4, seed in 1u64..50, frac in 0.0f64..1.0, frac2 in 0.0f64..1.0) {
            let name = ["paper", "step", "noise", "baro-stuck"][kind];
            let rows = sim::simulate(&sim::Scenario::preset(name, seed).unwrap()).unwrap();
            // Every method's state must survive too (windows, pools).
            let method = crate::methods::Method::ALL[(seed as usize) % crate::methods::Method::ALL.len()];
            let cfg = Config { tc: 20, method, ..Config::default() };
            let mut whole = Detector::new(cfg.clone()).unwrap();
            let all = run(&mut whole, &rows);
            let (c1, c2) = {
                let a = (frac * rows.len() as f64) as usize;
                let b = (frac2 * rows.len() as f64) as usize;
                (a.min(b), a.max(b))
            };
            // Two restores in one run: the restored detector snapshots too.
            let mut d = Detector::new(cfg).unwrap();
            let mut out = run(&mut d, &rows[..c1]);
            let mut d = Detector::restore(&d.snapshot().unwrap()).unwrap();
            out.extend(run(&mut d, &rows[c1..c2]));
            let mut d = Detector::restore(&d.snapshot().unwrap()).unwrap();
            out.extend(run(&mut d, &rows[c2..]));
            prop_assert!(same(&all, &out).is_ok(), "{:?}", same(&all, &out));
        }
    }
}

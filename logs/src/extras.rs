//! What a log says beside its sensor rows, for the person reading a report:
//! what the receiver-quality column holds (metres or HDOP), the wall-clock
//! (UTC) time of the log, the flight modes and the autopilot's own messages.
//! None of it feeds the detector; every list is bounded.

use serde::Serialize;

/// Flight-mode changes kept at most (real logs: a few to a few dozen).
pub const MAX_MODES: usize = 256;
/// Autopilot messages kept at most (real logs: a few to a few hundred).
pub const MAX_MESSAGES: usize = 256;
/// Bytes of one message's text kept at most.
const MAX_TEXT_BYTES: usize = 200;

/// What the receiver-quality column (`eph`) holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum EphSource {
    /// No receiver-quality value in the log.
    #[default]
    None,
    /// The receiver's horizontal accuracy estimate, m.
    Eph,
    /// Horizontal dilution of precision (unitless), used where the log has
    /// no accuracy in metres (DataFlash without `GPA`).
    Hdop,
}

/// One flight-mode change: from `t` (boot-clock s) the vehicle is in `mode`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModeChange {
    /// Boot-clock s.
    pub t: f64,
    /// The mode's name as the autopilot spells it (e.g. "AUTO_LOITER", "RTL").
    pub mode: String,
}

/// One message of the autopilot's own (a text line, an error, an event).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LogMessage {
    /// Boot-clock s.
    pub t: f64,
    /// "error", "warning", "info" or "event".
    pub level: &'static str,
    /// The message text.
    pub text: String,
}

/// The extras a reader collects.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Extras {
    /// What the log's receiver-quality column holds.
    pub eph_source: EphSource,
    /// UTC (Unix s) at boot-clock 0, from the first GPS report that carries
    /// UTC time; `None` when the log has none.
    pub utc_at_boot: Option<f64>,
    /// Flight-mode changes, in time order.
    pub modes: Vec<ModeChange>,
    /// The autopilot's own messages, in time order.
    pub messages: Vec<LogMessage>,
    /// Modes and messages over the caps, not kept.
    pub dropped: u64,
}

impl Extras {
    /// Note a mode at `t` (NaN: not known yet, the reader fills it in); a
    /// repeat of the current mode is not a change.
    pub fn mode(&mut self, t: f64, mode: String) {
        if t.is_infinite() || self.modes.last().is_some_and(|m| m.mode == mode) {
            return;
        }
        if self.modes.len() >= MAX_MODES {
            self.dropped += 1;
            return;
        }
        self.modes.push(ModeChange { t, mode });
    }

    /// Note a message at `t` (NaN as for [`Extras::mode`]; text cut to 200 bytes).
    pub fn message(&mut self, t: f64, level: &'static str, text: &str) {
        let text = text.trim();
        if t.is_infinite() || text.is_empty() {
            return;
        }
        if self.messages.len() >= MAX_MESSAGES {
            self.dropped += 1;
            return;
        }
        let mut end = text.len().min(MAX_TEXT_BYTES);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        self.messages.push(LogMessage { t, level, text: text.get(..end).unwrap_or("").to_string() });
    }

    /// Note UTC (Unix s) seen at boot time `t` (s), if none is known yet.
    /// Times before 2000 are a receiver without time (week 0), not a date.
    pub fn utc(&mut self, t: f64, unix_s: f64) {
        if self.utc_at_boot.is_none() && t.is_finite() && unix_s > 946_684_800.0 && unix_s < 4_102_444_800.0 {
            self.utc_at_boot = Some(unix_s - t);
        }
    }

    /// Modes and messages in time order (a reader may see them out of order).
    pub fn sort(&mut self) {
        sort_stable_by(&mut self.modes, |a, b| a.t.total_cmp(&b.t).is_lt());
        sort_stable_by(&mut self.messages, |a, b| a.t.total_cmp(&b.t).is_lt());
    }
}

/// GPS time (week, ms of week) to Unix seconds (UTC), with the leap seconds
/// in force at that date (GPS - UTC: 15 s from 2009, 16 from 2012-07,
/// 17 from 2015-07, 18 from 2017).
pub fn gps_to_unix(week: f64, ms: f64) -> f64 {
    /// 1980-01-06T00:00:00Z, the GPS epoch, in Unix s.
    const GPS_EPOCH: f64 = 315_964_800.0;
    let gps = GPS_EPOCH + week * 604_800.0 + ms / 1000.0;
    let leap = if gps >= 1_483_228_800.0 + 18.0 {
        18.0
    } else if gps >= 1_435_708_800.0 + 17.0 {
        17.0
    } else if gps >= 1_341_100_800.0 + 16.0 {
        16.0
    } else {
        15.0
    };
    gps - leap
}

/// Unix seconds as ISO 8601 UTC with milliseconds, e.g.
/// "2014-10-09T14:03:05.200Z" (civil-from-days, proleptic Gregorian).
pub fn iso_utc(unix_s: f64) -> String {
    let ms_total = (unix_s * 1000.0).round() as i64;
    let days = ms_total.div_euclid(86_400_000);
    let ms_day = ms_total.rem_euclid(86_400_000);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    let (h, mi, s, ms) = (ms_day / 3_600_000, ms_day / 60_000 % 60, ms_day / 1000 % 60, ms_day % 1000);
    format!("{y:04}-{m:02}-{d:02}T{h:02}:{mi:02}:{s:02}.{ms:03}Z")
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;

    #[test]
    fn iso_dates_and_gps_time() {
        assert_eq!(iso_utc(0.0), "1970-01-01T00:00:00.000Z");
        assert_eq!(iso_utc(951_782_400.5), "2000-02-29T00:00:00.500Z");
        assert_eq!(iso_utc(1_700_000_000.0), "2023-11-14T22:13:20.000Z");
        // GPS week 1817, 403377000 ms (Loiter_RTL.bin's first fix): 16 leap
        // seconds in October 2014 -> 2014-11-06 16:02:41 UTC.
        assert_eq!(iso_utc(gps_to_unix(1817.0, 403_377_000.0)), "2014-11-06T16:02:41.000Z");
        // 2020: 18 leap seconds.
        assert_eq!(gps_to_unix(2100.0, 0.0), 315_964_800.0 + 2100.0 * 604_800.0 - 18.0);
    }

    #[test]
    fn modes_collapse_repeats_and_lists_are_capped() {
        let mut x = Extras::default();
        x.mode(1.0, "LOITER".into());
        x.mode(2.0, "LOITER".into());
        x.mode(3.0, "RTL".into());
        assert_eq!(x.modes.iter().map(|m| m.t).collect::<Vec<_>>(), [1.0, 3.0]);
        for i in 0..MAX_MESSAGES + 5 {
            x.message(i as f64, "info", "hello");
        }
        x.message(0.0, "info", &"é".repeat(150));
        assert_eq!(x.messages.len(), MAX_MESSAGES);
        assert_eq!(x.dropped, 6);
        let mut y = Extras::default();
        y.message(0.0, "info", &"é".repeat(150));
        assert_eq!(y.messages[0].text.len(), 200);
        y.utc(5.0, 0.0);
        assert_eq!(y.utc_at_boot, None, "week 0 is no date");
        y.utc(5.0, 1_500_000_005.0);
        y.utc(6.0, 1_600_000_000.0);
        assert_eq!(y.utc_at_boot, Some(1_500_000_000.0));
    }
}

/// The order that sorts `n` items stably by `less` (a strict order: `less(i,
/// j)` when item `i` goes before item `j`): a bottom-up merge sort over
/// indices. The readers' few sorts (modes, messages, topic counts, once per
/// log) share this one function instead of the standard library's stable
/// sort instantiated for each item type (about 3 KB each in the core wasm
/// module). Ties keep their order, as `slice::sort_by` keeps them, so the
/// result is the same.
pub(crate) fn stable_order(n: usize, less: &dyn Fn(usize, usize) -> bool) -> Vec<usize> {
    let mut a: Vec<usize> = (0..n).collect();
    let mut b = a.clone();
    let mut w = 1;
    while w < n {
        let mut lo = 0;
        while lo < n {
            let mid = lo.saturating_add(w).min(n);
            let hi = lo.saturating_add(2 * w).min(n);
            let (mut i, mut j) = (lo, mid);
            for slot in &mut b[lo..hi] {
                // From the right run only when strictly before: stable.
                if j < hi && (i >= mid || less(a[j], a[i])) {
                    *slot = a[j];
                    j += 1;
                } else {
                    *slot = a[i];
                    i += 1;
                }
            }
            lo = hi;
        }
        std::mem::swap(&mut a, &mut b);
        w = w.saturating_mul(2);
    }
    a
}

/// `v` sorted stably by `less` (see [`stable_order`]).
pub(crate) fn sort_stable_by<T>(v: &mut Vec<T>, less: impl Fn(&T, &T) -> bool) {
    let order = stable_order(v.len(), &|i, j| less(&v[i], &v[j]));
    let mut slots: Vec<Option<T>> = v.drain(..).map(Some).collect();
    v.extend(order.iter().filter_map(|&i| slots.get_mut(i).and_then(Option::take)));
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod sort_tests {
    use super::sort_stable_by;

    #[test]
    fn the_merge_sort_orders_as_the_standard_stable_sort() {
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        for n in [0usize, 1, 2, 3, 5, 8, 13, 100, 257, 1000] {
            for ties in [1u64, 3, 50, 1 << 40] {
                let items: Vec<(u64, usize)> = (0..n)
                    .map(|i| {
                        x ^= x << 13;
                        x ^= x >> 7;
                        x ^= x << 17;
                        (x % ties, i)
                    })
                    .collect();
                let mut want = items.clone();
                want.sort_by(|a, b| a.0.cmp(&b.0));
                let mut got = items.clone();
                sort_stable_by(&mut got, |a, b| a.0 < b.0);
                assert_eq!(got, want, "n {n}, ties {ties}");
            }
        }
    }
}

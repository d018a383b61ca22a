//! Detection metrics exactly as the contract (and Sun et al. 2017) define them.
//!
//! Over labelled rows: accuracy = correct / all; false alarm rate =
//! FP / (TP + FP) (the paper's definition: the share of alarms that are
//! false); misdetection rate = FN / (TP + FN); precision, recall, F2; and the
//! detection delay of each labelled fault interval: time from its first
//! labelled row to the first flagged row inside it.

use serde::Serialize;

/// Confusion counts and derived rates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Metrics {
    /// Fault epochs flagged (true positives).
    pub tp: u64,
    /// Normal epochs flagged (false positives).
    pub fp: u64,
    /// Normal epochs not flagged.
    pub tn: u64,
    /// Fault epochs missed (false negatives).
    pub r#fn: u64,
    /// (TP + TN) / all.
    pub accuracy: f64,
    /// FP / (FP + TN).
    pub false_alarm_rate: f64,
    /// FN / (TP + FN).
    pub misdetection_rate: f64,
    /// TP / (TP + FP).
    pub precision: f64,
    /// TP / (TP + FN).
    pub recall: f64,
    /// F-beta score with β = 2 (recall weighted over precision).
    pub f2: f64,
    /// Mean detection delay over detected fault intervals, s (NaN if none).
    pub mean_detection_delay: f64,
    /// Fault intervals in the labels.
    pub fault_intervals: u64,
    /// Of those, flagged at least once.
    pub detected_intervals: u64,
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 {
        0.0
    } else {
        a as f64 / b as f64
    }
}

/// Metrics accumulated row by row (for streamed audits; [`compute`] uses it
/// too, so both agree exactly).
#[derive(Clone, Copy, Debug, Default)]
pub struct Accumulator {
    m: Metrics,
    in_fault: bool,
    start: f64,
    detected: bool,
    delays: f64,
    /// Whether any labelled row was seen.
    pub any_label: bool,
}

impl Accumulator {
    /// One row: time (s), label (NaN = unlabelled), status.
    pub fn push(&mut self, t: f64, label: f64, status: u8) {
        if label.is_nan() {
            return;
        }
        self.any_label = true;
        let m = &mut self.m;
        let truth = label >= 0.5;
        let flag = status != 0;
        match (truth, flag) {
            (true, true) => m.tp += 1,
            (true, false) => m.r#fn += 1,
            (false, true) => m.fp += 1,
            (false, false) => m.tn += 1,
        }
        if truth && !self.in_fault {
            self.in_fault = true;
            self.start = t;
            self.detected = false;
            m.fault_intervals += 1;
        } else if !truth {
            self.in_fault = false;
        }
        if truth && flag && !self.detected {
            self.detected = true;
            m.detected_intervals += 1;
            self.delays += t - self.start;
        }
    }

    /// The rates from the counts so far.
    pub fn metrics(&self) -> Metrics {
        let mut m = self.m;
        let all = m.tp + m.fp + m.tn + m.r#fn;
        m.accuracy = ratio(m.tp + m.tn, all);
        m.false_alarm_rate = ratio(m.fp, m.tp + m.fp);
        m.misdetection_rate = ratio(m.r#fn, m.tp + m.r#fn);
        m.precision = ratio(m.tp, m.tp + m.fp);
        m.recall = ratio(m.tp, m.tp + m.r#fn);
        let (p, r) = (m.precision, m.recall);
        m.f2 = if p + r > 0.0 { 5.0 * p * r / (4.0 * p + r) } else { 0.0 };
        m.mean_detection_delay = if m.detected_intervals > 0 { self.delays / m.detected_intervals as f64 } else { f64::NAN };
        m
    }
}

/// Compute metrics from per-row time, label (NaN = unlabelled) and status.
pub fn compute(t: &[f64], label: &[f64], status: &[u8]) -> Metrics {
    let mut acc = Accumulator::default();
    for ((t, l), s) in t.iter().zip(label).zip(status) {
        acc.push(*t, *l, *s);
    }
    acc.metrics()
}

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    #[test]
    fn paper_table1_tc100_counts_give_paper_rates() {
        // Sun et al. Table 1, TC=100: TP 286, FN 14, FP 43, TN 2157.
        let mut label = vec![];
        let mut status = vec![];
        for (l, s, n) in [(1.0, 1u8, 286), (1.0, 0, 14), (0.0, 1, 43), (0.0, 0, 2157)] {
            for _ in 0..n {
                label.push(l);
                status.push(s);
            }
        }
        let t: Vec<f64> = (0..label.len()).map(|i| i as f64 * 0.1).collect();
        let m = compute(&t, &label, &status);
        assert_abs_diff_eq!(m.accuracy, 0.977, epsilon = 5e-4);
        assert_abs_diff_eq!(m.false_alarm_rate, 0.1307, epsilon = 5e-4);
        assert_abs_diff_eq!(m.misdetection_rate, 0.0467, epsilon = 5e-4);
    }

    #[test]
    fn delay_f2_and_unlabelled_rows() {
        let t = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7];
        let label = [0.0, 1.0, 1.0, 1.0, f64::NAN, 0.0, 1.0, 1.0];
        let status = [0u8, 0, 1, 1, 1, 1, 0, 0];
        let m = compute(&t, &label, &status);
        assert_eq!((m.tp, m.fp, m.tn, m.r#fn), (2, 1, 1, 3));
        assert_eq!((m.fault_intervals, m.detected_intervals), (2, 1));
        assert_abs_diff_eq!(m.mean_detection_delay, 0.1, epsilon = 1e-12);
        let (p, r) = (2.0 / 3.0, 2.0 / 5.0);
        assert_abs_diff_eq!(m.f2, 5.0 * p * r / (4.0 * p + r), epsilon = 1e-12);
    }
}

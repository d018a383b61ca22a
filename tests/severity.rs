//! Issue 14 item 8: every fault interval carries its severity (peak offset
//! against the filter's prediction, its unit, duration, grade), and the
//! audit reports the causal intervals reconciled over the whole log.
#![cfg(not(target_arch = "wasm32"))]

use navguard::audit::{audit_bytes, reconcile, severity, FaultInterval};
use navguard::{config::Config, sim::*};

fn interval(start: f64, end: f64, kind: &'static str, offset: Option<f64>, unit: &'static str) -> FaultInterval {
    FaultInterval {
        start,
        end,
        kind,
        peak_f: 1.0,
        driver: if kind == "gps_outage" { "none" } else { "gps_position" },
        indicator: "R",
        rows: 1,
        peak_offset: offset,
        offset_unit: unit,
        duration_s: end - start,
        severity: severity(kind, unit, offset, end - start),
    }
}

#[test]
fn severity_grades_offset_and_duration() {
    assert_eq!(severity("residual", "m", Some(2.0), 1.0), "low");
    assert_eq!(severity("residual", "m", Some(3.5), 1.0), "medium");
    assert_eq!(severity("residual", "m", Some(12.0), 1.0), "high");
    assert_eq!(severity("residual", "m/s", Some(0.6), 1.0), "medium");
    assert_eq!(severity("residual", "m/s", Some(2.5), 1.0), "high");
    assert_eq!(severity("residual", "m", Some(1.0), 6.0), "medium");
    assert_eq!(severity("residual", "m", Some(1.0), 31.0), "high");
    // An outage is graded by its length alone.
    assert_eq!(severity("gps_outage", "", None, 4.0), "low");
    assert_eq!(severity("gps_outage", "", None, 12.0), "medium");
    assert_eq!(severity("gps_outage", "", None, 45.0), "high");
}

#[test]
fn reconcile_joins_flicker_of_one_kind_only() {
    let causal = [
        interval(10.0, 12.0, "residual", Some(4.0), "m"),
        interval(13.5, 20.0, "residual", Some(11.0), "m"),
        // 5 s later: a new interval.
        interval(25.0, 26.0, "residual", Some(2.0), "m"),
        // Adjacent but another kind: kept apart.
        interval(26.5, 40.0, "gps_outage", None, ""),
    ];
    let r = reconcile(&causal, &[], 0.2);
    assert_eq!(r.len(), 3, "{r:?}");
    assert_eq!((r[0].start, r[0].end, r[0].rows), (10.0, 20.0, 2));
    assert_eq!(r[0].peak_offset, Some(11.0));
    assert_eq!((r[0].duration_s, r[0].severity), (10.0, "high"));
    assert_eq!((r[1].start, r[1].severity), (25.0, "low"));
    assert_eq!((r[2].kind, r[2].severity), ("gps_outage", "medium"));
    // At 1 Hz GPS the gap allowed is 3 periods.
    assert_eq!(reconcile(&causal[..3], &[], 2.0).len(), 1);
    // A frozen receiver whose records also drop: a stale fix and no fix
    // alternating at every epoch are one interval, of the first's kind.
    let frozen: Vec<_> = (0..10).map(|i| interval(50.0 + 0.2 * i as f64, 50.1 + 0.2 * i as f64, if i % 2 == 0 { "gps_stale" } else { "gps_outage" }, None, "")).collect();
    let r = reconcile(&frozen, &[], 0.2);
    assert_eq!(r.len(), 1, "{r:?}");
    assert_eq!((r[0].start, r[0].kind, r[0].rows), (50.0, "gps_stale", 10));
    assert!((r[0].end - 51.9).abs() < 1e-9);
}

#[test]
fn reconcile_joins_a_dated_span_to_the_intervals_it_overlaps() {
    // A drag-off dated from 5 s at its end, 30 s (rows 0: judged before it
    // was dated), over a causal blip at 8-9 s and touching the interval its
    // return opened, of another kind: one interval from 5 to 31 s. An
    // outage 10 s later stays apart.
    let causal = [
        interval(8.0, 9.0, "residual", Some(1.0), "m"),
        interval(30.0, 31.0, "gps_degraded", Some(3.0), "m"),
        interval(41.0, 45.0, "gps_outage", None, ""),
    ];
    let mut dated = interval(5.0, 30.0, "residual", Some(24.0), "m");
    dated.rows = 0;
    let r = reconcile(&causal, &[dated], 0.2);
    assert_eq!(r.len(), 2, "{r:?}");
    assert_eq!((r[0].start, r[0].end, r[0].rows), (5.0, 31.0, 2));
    assert_eq!((r[0].peak_offset, r[0].duration_s, r[0].severity), (Some(24.0), 26.0, "high"));
    assert_eq!((r[1].start, r[1].kind), (41.0, "gps_outage"));
}

#[test]
fn a_dated_silence_takes_its_rows_from_the_verdict_they_carried() {
    // Real log 09-10 at 60-68 s: a residual interval whose last second is
    // rows after the last fix, carrying its verdict, then the outage called
    // at 62.6 s once the silence lasted an outage's timeout. The silence
    // is dated from 61.5 s: the outage begins there, the residual interval
    // ends there, and the outage's causal interval joins it.
    let causal = [
        interval(60.1, 62.6, "residual", Some(3.0), "m"),
        interval(62.6, 67.8, "gps_outage", None, ""),
    ];
    let mut silence = interval(61.5, 62.6, "gps_outage", None, "");
    silence.rows = 0;
    let r = reconcile(&causal, &[silence], 0.2);
    assert_eq!(r.len(), 2, "{r:?}");
    assert_eq!((r[0].start, r[0].end, r[0].kind), (60.1, 61.5, "residual"));
    assert!((r[0].duration_s - 1.4).abs() < 1e-9, "{r:?}");
    assert_eq!((r[1].start, r[1].end, r[1].kind, r[1].rows), (61.5, 67.8, "gps_outage", 1));
    // A silence that covers the whole interval before it replaces it.
    let mut silence = interval(60.0, 62.6, "gps_outage", None, "");
    silence.rows = 0;
    let r = reconcile(&causal, &[silence], 0.2);
    assert_eq!(r.len(), 1, "{r:?}");
    assert_eq!((r[0].start, r[0].end, r[0].kind), (60.0, 67.8, "gps_outage"));
}

#[test]
fn a_15_m_step_reports_its_offset_in_metres() {
    let sc = Scenario::with_fault(FaultKind::Step, 15.0, 100.0, 20.0, 1);
    let rows = simulate(&sc).unwrap();
    let csv = to_csv(&sc, &rows);
    let (report, _) = audit_bytes(csv.as_bytes(), &Config::default(), false).unwrap();
    let iv = report.faults.iter().find(|f| f.start >= 99.0 && f.start < 102.0).expect("the step is flagged");
    assert_eq!((iv.kind, iv.driver, iv.offset_unit), ("residual", "gps_position", "m"));
    let off = iv.peak_offset.unwrap();
    // The step is 15 m; the GPS noise and the coast's drift move it a little.
    assert!((13.0..19.0).contains(&off), "peak offset {off} m");
    assert_eq!(iv.severity, "high");
    assert!((iv.duration_s - (iv.end - iv.start)).abs() < 1e-12);
    // Every reconciled interval spans causal ones; none is shorter.
    assert!(report.reconciled.len() <= report.faults.len());
    for r in &report.reconciled {
        assert!(report.faults.iter().any(|f| f.start == r.start));
        assert!(report.faults.iter().any(|f| f.end == r.end));
    }
}

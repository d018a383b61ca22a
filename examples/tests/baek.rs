//! Reduced Baek & Jo 2018 evaluation (4 repetitions instead of 50) on the
//! simulated Jackal UGV: what our reproduction supports and what it does not
//! (see `docs/baek-jo.md`). The paper's claim is AT < KT < RT in both FNR
//! and FPR; on our plant only the FPR side against RT reproduces. The FNR
//! ordering is reversed (RT misses least), and AT vs KT is a near tie in FNR
//! with KT ahead in FPR; the last test pins that reversal so that a change
//! which restores the paper's ordering has to update the documentation.
#![cfg(not(target_arch = "wasm32"))]

use std::sync::OnceLock;

use navguard_examples::ugv::{evaluate, EvalConfig, Report};

fn report() -> &'static Report {
    static R: OnceLock<Report> = OnceLock::new();
    R.get_or_init(|| evaluate(&EvalConfig { reps: 4, ..Default::default() }).expect("evaluation runs"))
}

#[test]
fn reduced_evaluation_is_deterministic() {
    let again = evaluate(&EvalConfig { reps: 4, ..Default::default() }).unwrap();
    assert_eq!(&again, report());
    assert_eq!(report().table1.len(), 4);
    assert_eq!(report().table2.len(), 12);
}

#[test]
fn table1_thresholds_are_near_the_papers() {
    for t in &report().table1 {
        let near = |ours: f64, paper: f64, f: f64| ours >= paper / f && ours <= paper * f;
        assert!(near(t.rt_mean_rms, t.paper_rt, 1.4), "RT at {}: {} vs {}", t.speed, t.rt_mean_rms, t.paper_rt);
        assert!(near(t.kt.0, t.paper_kt.0, 1.6), "KT rho at {}: {} vs {}", t.speed, t.kt.0, t.paper_kt.0);
        assert!(near(t.at.0, t.paper_at.0, 1.6), "AT rho at {}: {} vs {}", t.speed, t.at.0, t.paper_at.0);
        assert!(!t.at_clamped, "AT equilibrium clamped at {}", t.speed);
    }
}

#[test]
fn rt_has_by_far_the_highest_false_positive_rate() {
    let o = &report().ordering;
    // The paper's FPR (FP/(TP+FP)): RT about 0.64 there, AT and KT near 0.
    assert!(o.mean_fpr[2] > 0.6, "RT {:?}", o.mean_fpr);
    assert!(o.mean_fpr[2] > 1.8 * o.mean_fpr[0].max(o.mean_fpr[1]), "{:?}", o.mean_fpr);
    for row in &report().table2 {
        let [at, kt, rt] = row.ours;
        assert!(at.fpr < rt.fpr && kt.fpr < rt.fpr, "{} {:?}: {:?}", row.speed, row.fault, row.ours);
        // Conventional FP/(FP+TN): two-stage methods alarm on < 5 % of normal samples, RT on > 10 %.
        assert!(at.fpr_conventional < 0.05 && kt.fpr_conventional < 0.05, "{} {:?}: {:?}", row.speed, row.fault, row.ours);
        assert!(rt.fpr_conventional > 0.10, "{} {:?}: {:?}", row.speed, row.fault, row.ours);
    }
}

#[test]
fn noise_faults_are_missed_least_by_every_method() {
    // Paper: the noise faults are the largest, every method's lowest FNR.
    for chunk in report().table2.chunks(3) {
        for m in 0..3 {
            let noise = chunk[2].ours[m].fnr;
            assert!(noise < chunk[0].ours[m].fnr && noise < chunk[1].ours[m].fnr, "{}: {:?}", chunk[0].speed, chunk);
        }
    }
}

#[test]
fn paper_fnr_ordering_does_not_reproduce_rt_misses_least() {
    let o = &report().ordering;
    assert!(!o.fnr_means_ordered, "AT <= KT <= RT in FNR now holds: update docs/baek-jo.md ({:?})", o.mean_fnr);
    assert!(o.mean_fnr[2] < o.mean_fnr[0].min(o.mean_fnr[1]), "{:?}", o.mean_fnr);
}

//! The paper scenario (degraded outages) over seeds 1–5 with the default
//! config: metrics per seed, then the false alarms, misses and hits summed.
//! `cargo run --release -p navguard-examples --example paper`
use navguard::{config::Config, detector::Detector, metrics, sim::*};
fn main() {
    let mut tot = (0, 0, 0);
    for seed in 1..=5 {
        let rows = simulate(&Scenario::paper(OutageMode::Degraded, seed)).unwrap();
        let mut det = Detector::new(Config::default()).unwrap();
        let (mut t, mut l, mut st) = (vec![], vec![], vec![]);
        for s in &rows {
            let o = det.push(s).unwrap();
            t.push(s.t);
            l.push(s.label);
            st.push(o.status);
        }
        let m = metrics::compute(&t, &l, &st);
        println!(
            "seed {seed}: acc {:.4} far {:.4} mdr {:.4}",
            m.accuracy, m.false_alarm_rate, m.misdetection_rate
        );
        tot.0 += m.fp;
        tot.1 += m.r#fn;
        tot.2 += m.tp;
    }
    println!("fp {} fn {} tp {}", tot.0, tot.1, tot.2);
}

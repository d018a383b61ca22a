use navguard::{sim::*, detector::Detector, config::Config, metrics};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(|s| s.as_str()).unwrap_or("paper");
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let oracle = args.get(3).map(|s| s == "oracle").unwrap_or(false);
    let sc = Scenario::preset(name, seed).unwrap();
    let rows = simulate(&sc).unwrap();
    let cfg = navguard::config::ConfigInput::from_json(&std::env::var("CFG").unwrap_or_default()).unwrap();
    let mut det = Detector::new(cfg).unwrap();
    det.set_oracle(oracle);
    let (mut t, mut l, mut st) = (vec![], vec![], vec![]);
    for s in &rows {
        let o = det.push(s).unwrap();
        if !s.label.is_nan() && (args.len() > 4) && o.gps_epoch && ((s.t*10.0).round() as i64 % 5 == 0 || s.label==1.0) {
            println!("{:7.2} lab {} st {} k {} f {:6.3} r {:7.2} c {:5.2} rg {:?} cg {:?}", s.t, s.label, o.status, o.kind, o.f, o.r, o.c, det.indicators().r_group.map(|v| (v*100.0).round()/100.0), det.indicators().c_group.map(|v| (v*100.0).round()/100.0));
        }
        t.push(s.t); l.push(s.label); st.push(o.status);
    }
    let m = metrics::compute(&t, &l, &st);
    println!("{name} seed {seed}: acc {:.4} far {:.4} mdr {:.4} tp {} fp {} fn {} tn {} delay {:.2} stats {:?}", m.accuracy, m.false_alarm_rate, m.misdetection_rate, m.tp, m.fp, m.r#fn, m.tn, m.mean_detection_delay, det.stats());
}

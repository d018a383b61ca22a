//! Invariants of the randomised battery generator (src/battery.rs) and a
//! guard that the older simulator's presets stay bit-identical. These test
//! the generator, not any detector's performance.
#![cfg(not(target_arch = "wasm32"))]

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use navguard::battery::{self, Axis, FaultKind, Flight, ImuGrade, NoiseFamily, Path, PathKind, Split, EVAL_BASE, SPLIT_LEN, TUNE_BASE};
use navguard::Sample;

fn gps(rows: &[Sample]) -> Vec<&Sample> {
    rows.iter().filter(|s| !s.label.is_nan()).collect()
}

fn bits(rows: &[&Sample]) -> Vec<u64> {
    rows.iter().flat_map(|s| (0..26).map(move |i| s.get(i).to_bits())).collect()
}

fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3))
}

#[test]
fn older_simulator_presets_are_bit_identical() {
    // FNV-1a of sim::to_csv for seed 1, recorded before the battery changed sim.rs.
    let want = [
        ("paper", 0x97dae9dff12a8e14u64),
        ("paper-silent", 0xe09e794e87c51633),
        ("clean-aggressive", 0xdfc2685e60722876),
        ("clean-survey", 0xed0073c09be051b7),
        ("clean-paper", 0x3826eb57ce1a71d1),
        ("gps-only", 0x837e8ef4b2a71287),
        ("step", 0xd004a4c8a5b07c61),
        ("ramp", 0x18f57d75c3fcd0ed),
        ("noise", 0x41e286eaf3358f1b),
        ("frozen", 0x9335f0b13ad43549),
        ("zero-velocity", 0x95e59d6ff3198e2a),
        ("baro-stuck", 0xc5996b7bc47bac51),
        ("accel-bias", 0x581af0bff850f3ab),
    ];
    assert_eq!(want.len(), navguard::sim::preset_names().len());
    for (name, h) in want {
        let sc = navguard::sim::Scenario::preset(name, 1).unwrap();
        let csv = navguard::sim::to_csv(&sc, &navguard::sim::simulate(&sc).unwrap());
        assert_eq!(fnv(&csv), h, "preset {name}");
    }
}

#[test]
fn deterministic_per_seed_and_different_across_seeds() {
    for i in [0, 3] {
        let a = battery::simulate(&Flight::draw(Split::Eval, i));
        let b = battery::simulate(&Flight::draw(Split::Eval, i));
        assert_eq!(a.len(), b.len());
        let ra: Vec<&Sample> = a.iter().collect();
        let rb: Vec<&Sample> = b.iter().collect();
        assert!(bits(&ra) == bits(&rb), "flight {i} differs between runs");
        assert_eq!(Flight::draw(Split::Eval, i), Flight::draw(Split::Eval, i));
    }
    assert_ne!(Flight::draw(Split::Eval, 1), Flight::draw(Split::Eval, 2));
    assert_ne!(Flight::draw(Split::Tune, 1), Flight::draw(Split::Eval, 1));
}

#[test]
fn splits_use_disjoint_seeds_and_eval_only_conditions() {
    assert!(Split::Tune.seed(SPLIT_LEN - 1) < Split::Eval.seed(0));
    assert_eq!((Split::Tune.seed(0), Split::Eval.seed(0)), (TUNE_BASE, EVAL_BASE));
    let tune: Vec<Flight> = (0..300).map(|i| Flight::draw(Split::Tune, i)).collect();
    let eval: Vec<Flight> = (0..300).map(|i| Flight::draw(Split::Eval, i)).collect();
    assert!(tune.iter().all(|f| f.gps.rate < 20.0 && f.gps.family != NoiseFamily::Mixed));
    let n20 = eval.iter().filter(|f| f.gps.rate == 20.0).count();
    let nmix = eval.iter().filter(|f| f.gps.family == NoiseFamily::Mixed).count();
    // 1/5 and 1/3 expected: 60 and 100 of 300.
    assert!((35..=85).contains(&n20), "20 Hz flights {n20}");
    assert!((70..=130).contains(&nmix), "mixed-noise flights {nmix}");
}

#[test]
fn drawn_values_stay_in_their_ranges() {
    let flights: Vec<Flight> = (0..400).map(|i| Flight::draw(Split::Eval, i)).collect();
    let mut kinds = std::collections::BTreeSet::new();
    let (mut early, mut faults, mut clean, mut vertical) = (0, 0, 0, 0);
    for f in &flights {
        assert!([1.0, 2.0, 5.0, 10.0, 20.0].contains(&f.gps.rate));
        assert!([50.0, 100.0, 200.0, 400.0].contains(&f.imu.rate));
        assert!((0.3..=3.0).contains(&f.gps.sigma_h), "{}", f.gps.sigma_h);
        assert!((1.6..=2.4).contains(&(f.gps.sigma_v / f.gps.sigma_h)));
        // eph follows σ: the scale is 0.8–1.5.
        assert!((0.8..=1.5).contains(&f.gps.eph_scale));
        assert!((0.92..=1.0).contains(&f.clock.rate));
        assert!(f.liftoff > 0.0 && f.touchdown < f.path.duration && f.liftoff < f.touchdown);
        for g in &f.gps.gaps {
            assert!((0.3..=1.2).contains(&(g[1] - g[0])));
        }
        if f.path.kind == PathKind::Aggressive {
            assert!((25.0..=55.0).contains(&f.max_tilt_deg), "tilt {}", f.max_tilt_deg);
            assert!((4.0..=6.5).contains(&f.max_accel_h), "accel {}", f.max_accel_h);
        }
        clean += f.faults.is_empty() as usize;
        for ft in &f.faults {
            faults += 1;
            kinds.insert(ft.kind.name());
            let d = ft.duration();
            assert!((3.0 - 1e-9..=120.0 + 1e-9).contains(&d), "duration {d}");
            assert!(ft.end <= f.path.duration);
            let (lo, hi) = ft.kind.magnitude_range();
            assert!(ft.magnitude >= lo && ft.magnitude <= hi, "{:?} magnitude {}", ft.kind, ft.magnitude);
            early += (ft.start < 20.0) as usize;
            vertical += (ft.axis == Axis::Vertical) as usize;
            assert!(ft.start >= 5.0);
        }
        for (a, b) in f.faults.iter().zip(f.faults.iter().skip(1)) {
            assert!(b.start >= a.end + 30.0, "faults too close: {a:?} {b:?}");
        }
    }
    assert_eq!(kinds.len(), FaultKind::ALL.len());
    assert!((50..=110).contains(&clean), "clean flights {clean}");
    assert!(early * 100 >= faults * 15, "early {early} of {faults}");
    assert!(vertical * 100 >= faults * 8, "vertical {vertical} of {faults}");
}

#[test]
fn labels_mark_exactly_the_fault_span() {
    let mut seen = 0;
    for i in 0..30 {
        let f = Flight::draw(Split::Eval, i);
        let rows = battery::simulate(&f);
        let g = gps(&rows);
        for s in &g {
            let inside = f.faults.iter().any(|ft| s.t >= ft.start_log && s.t < ft.end_log);
            assert_eq!(s.label == 1.0, inside, "flight {i} t {}", s.t);
            let outage = f.faults.iter().any(|ft| ft.kind == FaultKind::Outage && s.t >= ft.start_log && s.t < ft.end_log);
            assert_eq!(s.fix == 0.0, outage, "flight {i} t {}: fix {}", s.t, s.fix);
            assert_eq!(s.lat.is_nan(), outage);
        }
        // Only GPS rows carry labels; every fault holds epochs unless dropped.
        assert!(rows.iter().filter(|s| !s.label.is_nan()).all(|s| s.ax.is_nan() && s.baro.is_nan()));
        for ft in &f.faults {
            let n = g.iter().filter(|s| s.t >= ft.start_log && s.t < ft.end_log).count() as f64;
            let expect = ft.duration() * f.gps.rate;
            let dropped = f.gps.gaps.iter().map(|g| (g[1].min(ft.end) - g[0].max(ft.start)).max(0.0)).sum::<f64>() * f.gps.rate;
            assert!(n <= expect + 1.0 && n >= (expect - dropped) * (1.0 - 2.0 * f.gps.drop_prob) - 2.0 - 3.0 * expect.sqrt() * f.gps.drop_prob.sqrt(), "flight {i}: {n} epochs for {expect}");
            seen += 1;
        }
    }
    assert!(seen >= 20);
}

#[test]
fn imu_rate_variants_share_truth_gps_and_baro() {
    for i in 0..3 {
        let flights = battery::imu_rate_flights(i);
        let rows: Vec<Vec<Sample>> = flights.iter().map(battery::simulate).collect();
        let non_imu = |r: &[Sample]| -> Vec<u64> { bits(&r.iter().filter(|s| s.ax.is_nan()).collect::<Vec<_>>()) };
        let base = non_imu(&rows[0]);
        for (f, r) in flights.iter().zip(&rows).skip(1) {
            assert!(non_imu(r) == base, "GPS/baro rows differ at IMU {} Hz", f.imu.rate);
            let pa = Path::build(&flights[0]);
            let pb = Path::build(f);
            for k in 0..200 {
                let t = k as f64 * f.path.duration / 200.0;
                assert_eq!(pa.position(t), pb.position(t));
                assert_eq!(pa.attitude(t), pb.attitude(t));
            }
        }
        // IMU rows: rate × duration of them; the 50 Hz times are every 8th 400 Hz time.
        for (f, r) in flights.iter().zip(&rows) {
            let n = r.iter().filter(|s| !s.ax.is_nan()).count() as f64;
            assert!((n - f.imu.rate * f.path.duration).abs() <= 1.0, "{n} IMU rows at {} Hz", f.imu.rate);
        }
        let t50: Vec<f64> = rows[0].iter().filter(|s| !s.ax.is_nan()).map(|s| s.t).collect();
        let t400: Vec<f64> = rows[3].iter().filter(|s| !s.ax.is_nan()).map(|s| s.t).step_by(8).collect();
        let n = t50.len().min(t400.len());
        assert!(n + 1 >= t50.len().max(t400.len()) && t50[..n] == t400[..n], "50 Hz times are not every 8th 400 Hz time");
    }
}

#[test]
fn boot_clock_drift_scales_log_time() {
    let f = (0..50).map(|i| Flight::draw(Split::Tune, i)).find(|f| f.clock.rate < 0.95).unwrap();
    let rows = battery::simulate(&f);
    let imu: Vec<f64> = rows.iter().filter(|s| !s.ax.is_nan()).map(|s| s.t).collect();
    assert!((imu[0] - f.clock.boot).abs() < 1e-6);
    let span = imu[imu.len() - 1] - imu[0];
    let true_span = (imu.len() - 1) as f64 / f.imu.rate;
    assert!((span / true_span - f.clock.rate).abs() < 1e-6, "log/true {} vs drawn {}", span / true_span, f.clock.rate);
    let t: Vec<f64> = rows.iter().map(|s| s.t).collect();
    assert!(t.windows(2).all(|w| w[1] >= w[0]), "time goes backwards");
}

#[test]
fn imu_integrates_to_the_truth_velocity() {
    // A tactical IMU without vibration: integrating the logged specific
    // force with the logged attitude over 2 s windows must reproduce the
    // truth velocity change (snapshot samples, so only the rectangle rule's
    // error remains).
    for i in 0..12 {
        let mut f = Flight::draw(Split::Tune, i);
        f.imu.grade = ImuGrade::Tactical;
        f.imu.vibration = 0.0;
        f.imu.accel_density = 1e-5;
        f.imu.accel_bias = [0.0; 3];
        f.imu.tilt_sigma_deg = 0.0;
        f.imu.wander_sigma_deg = 0.0;
        f.imu.heading_sigma_deg = 0.0;
        f.imu.rate = 200.0;
        f.faults.clear();
        let rows = battery::simulate(&f);
        let path = Path::build(&f);
        let imu: Vec<&Sample> = rows.iter().filter(|s| !s.ax.is_nan()).collect();
        let dt = 1.0 / f.imu.rate;
        let mut worst: f64 = 0.0;
        for w in imu.chunks(400).take(100) {
            let t0 = (w[0].t - f.clock.boot) / f.clock.rate;
            let mut dv = Vector3::zeros();
            for s in w {
                let q = UnitQuaternion::from_quaternion(Quaternion::new(s.qw, s.qx, s.qy, s.qz));
                dv += (q.transform_vector(&Vector3::new(s.ax, s.ay, s.az)) + Vector3::new(0.0, 0.0, 9.80665)) * dt;
            }
            let truth = path.velocity(t0 + w.len() as f64 * dt) - path.velocity(t0);
            worst = worst.max((dv - truth).norm());
        }
        assert!(worst < 0.05, "flight {i} ({:?}): worst 2 s velocity error {worst} m/s", f.path.kind);
    }
}

#[test]
fn flights_start_and_end_at_rest_on_the_ground() {
    for i in 0..40 {
        let f = Flight::draw(Split::Tune, i);
        let p = Path::build(&f);
        for t in [0.0, f.liftoff - 0.5, f.touchdown + 0.5, f.path.duration] {
            assert!(p.height(t).abs() < 1e-9, "flight {i}: height {} at {t}", p.height(t));
        }
        assert!(p.velocity(0.0).norm() < 1e-12);
        assert!(p.velocity(f.path.duration).norm() < 1e-9, "flight {i} {:?} still moving", f.path.kind);
        assert!(f.max_height >= 8.0);
    }
}

#[test]
fn faults_change_the_sensor_they_name() {
    // Same flight with and without each fault: only the named sensor's rows change.
    let base = battery::CHECKS[0].flight(0, 0);
    let clean = Flight { faults: vec![], ..base.clone() };
    let rc = battery::simulate(&clean);
    for kind in FaultKind::ALL {
        let mut f = clean.clone();
        let (lo, hi) = kind.magnitude_range();
        f.add_fault(kind, Axis::Horizontal, 0.5 * (lo + hi), 1.0, 70.0, 30.0);
        let rf = battery::simulate(&f);
        assert_eq!(rf.len(), rc.len());
        let changed = |pick: fn(&Sample) -> f64| rc.iter().zip(&rf).any(|(a, b)| pick(a).to_bits() != pick(b).to_bits());
        let gps_changed = changed(|s| s.lat) || changed(|s| s.alt) || changed(|s| s.fix) || changed(|s| s.vn);
        let imu_changed = changed(|s| s.ax) || changed(|s| s.ay);
        let baro_changed = changed(|s| s.baro);
        let is_gps = !matches!(kind, FaultKind::AccelBias | FaultKind::BaroStep | FaultKind::BaroStuck | FaultKind::BaroDrift);
        let got = (gps_changed, imu_changed, baro_changed);
        assert_eq!(got, (is_gps, kind == FaultKind::AccelBias, kind.name().starts_with("baro")), "{kind:?}");
        // Outside the fault nothing changes (no shifted random stream).
        let after = f.log_time(101.0);
        assert!(rc.iter().zip(&rf).filter(|(a, _)| a.t > after).all(|(a, b)| a.label.to_bits() == b.label.to_bits() && a.lat.to_bits() == b.lat.to_bits() && a.baro.to_bits() == b.baro.to_bits()), "{kind:?}");
    }
}

#[test]
fn csv_round_trips_through_the_reader() {
    let f = Flight::draw(Split::Eval, 5);
    let rows = battery::simulate(&f);
    let text = battery::to_csv(&f, &rows);
    assert!(text.lines().nth(1).is_some_and(|l| l.starts_with("# battery: {")));
    let back = navguard::logs::csv::read_csv(text.as_bytes()).unwrap();
    assert_eq!(back.samples.len(), rows.len());
    let lab = |r: &[Sample]| r.iter().filter(|s| s.label == 1.0).count();
    assert_eq!(lab(&back.samples), lab(&rows));
}

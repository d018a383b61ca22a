//! Invariants of the randomised battery generator (src/battery.rs) and a
//! guard that the older simulator's presets stay bit-identical. These test
//! the generator, not any detector's performance.
#![cfg(not(target_arch = "wasm32"))]

use nalgebra::{UnitQuaternion, Quaternion, Vector3};
use navguard::battery::{self, Axis, Flight, FaultKind, ImuGrade, Path, PathKind, Split, EVAL_BASE, TUNE_BASE};
use navguard::Sample;

fn gps(rows: &[Sample]) -> Vec<&Sample> {
    rows.iter().filter(|s| !s.label.is_nan()).collect()
}

fn bits(rows: &[&Sample]) -> Vec<u64> {
    rows.iter().flat_map(|s| (0..26).map(move |i| s.get(i).to_bits())).collect()
}

#[test]
fn imu_integrates_to_the_truth_velocity() {
    // A tactical IMU without vibration: integrating the logged specific
    // force with the logged attitude over 2 s windows must reproduce the
    // truth velocity change (snapshot samples, so only the rectangle rule's
    // error and the small attitude error remain).
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

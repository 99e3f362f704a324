//! End-to-end (issue 18): the quadrotor truth of `fathom-traj` against the reduced
//! mechanization of `fathom-ins`. The two crates do not depend on each other, so the
//! checks that need both live in this workspace test binary (no new crate edge).
//!
//! - An error-free IMU generated from the flown `buildings` square (100 m legs at
//!   20 m, hover at the corners, one yaw turn in place, gusty wind, > 300 s) and fed
//!   to the reduced mechanization reproduces the truth: < 1 cm in position and
//!   < 0.01 deg in attitude at every 100 Hz sample.
//! - The ADIS16448 at rest during the flight's stationary start: the gyro bias
//!   estimated by averaging matches the true bias within the white-noise bound.

use fathom_ins::ImuIncrement;
use fathom_ins::local_level::{
    LocalLevelMechanization, LocalTruthSample, local_imu_from_truth, stationary_gyro_bias,
};
use fathom_sensors::allan_imu::AllanImuParams;
use fathom_traj::Trajectory;
use fathom_traj::quadrotor::{
    FlownTrajectory, PathParams, QuadrotorParams, WindParams, fly_on_truth,
};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const IMU_DT: f64 = 0.01;

/// The `buildings` flight: 10 s rest on the ground, climb to 20 m, a 100 m square at
/// 3 m/s with 28 s hovers (the far corner with a 90 deg turn in place), in a 2 m/s
/// wind with 0.5 m/s gusts.
fn buildings_flight(seed: u64) -> (FlownTrajectory, f64) {
    let quad = QuadrotorParams {
        wind: WindParams {
            mean_in_nav: Vector3::new(1.5, -1.3, 0.0),
            gust_sigma_mps: Vector3::new(0.5, 0.5, 0.2),
            gust_correlation_time_s: 3.0,
        },
        ..QuadrotorParams::default()
    }
    .check()
    .unwrap();
    let path = PathParams::buildings_square(Vector3::zeros(), 100.0, 20.0, 3.0, 28.0)
        .check()
        .unwrap();
    let traj = fly_on_truth(&quad, &path, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap();
    (traj, quad.vehicle.gravity())
}

fn truth_samples(traj: &FlownTrajectory, dt: f64) -> Vec<LocalTruthSample> {
    let n = (traj.end_time() / dt).floor() as usize;
    (0..=n)
        .map(|k| {
            let q = traj.quad_state_at(k as f64 * dt).unwrap();
            LocalTruthSample {
                time: q.time,
                pos_in_nav: q.body.pos_in_nav,
                vel_in_nav: q.body.vel_in_nav,
                nav_from_body: q.body.nav_from_body,
            }
        })
        .collect()
}

/// Acceptance: error-free IMU + reduced mechanization reproduce the 300 s buildings
/// flight to < 1 cm and < 0.01 deg; the increments are the physical body rate and
/// specific force of the truth. Negative control: gravity 1e-4 m/s^2 off in the
/// mechanization misses the 1 cm bound.
#[test]
fn error_free_imu_reproduces_the_buildings_flight() {
    let (traj, g) = buildings_flight(7);
    assert!(traj.end_time() >= 300.0, "flight {} s", traj.end_time());
    let truth = truth_samples(&traj, IMU_DT);
    let incs = local_imu_from_truth(&truth, g).unwrap();
    let mut mech = LocalLevelMechanization::new(truth[0].to_state(), g).unwrap();
    let (mut max_p, mut max_v, mut max_att): (f64, f64, f64) = (0.0, 0.0, 0.0);
    let (mut max_w, mut max_f): (f64, f64) = (0.0, 0.0);
    for (k, inc) in incs.iter().enumerate() {
        mech.step(inc).unwrap();
        let t = &truth[k + 1];
        let s = mech.state();
        max_p = max_p.max((s.pos_in_nav - t.pos_in_nav).norm());
        max_v = max_v.max((s.vel_in_nav - t.vel_in_nav).norm());
        max_att = max_att.max(s.nav_from_body.angle_to(&t.nav_from_body));
        let mid = traj.quad_state_at((k as f64 + 0.5) * IMU_DT).unwrap();
        max_w = max_w.max((inc.mean_angular_rate() - mid.body.omega_body).norm());
        max_f = max_f.max((inc.mean_specific_force() - mid.specific_force_in_body).norm());
    }
    let travelled: f64 = truth
        .windows(2)
        .map(|w| (w[1].pos_in_nav - w[0].pos_in_nav).norm())
        .sum();
    eprintln!(
        "buildings flight {:.1} s ({travelled:.0} m): mechanized error-free IMU vs truth: max position \
         {max_p:.2e} m, velocity {max_v:.2e} m/s, attitude {:.2e} deg; increments vs mid-interval \
         truth: body rate {max_w:.2e} rad/s, specific force {max_f:.2e} m/s^2",
        traj.end_time(),
        max_att.to_degrees()
    );
    assert!(travelled > 400.0);
    assert!(max_p < 0.01);
    assert!(max_att.to_degrees() < 0.01);
    assert!(max_v < 1e-6);
    // a 100 Hz increment is the interval mean; the mid-point value differs by O(dt^2)
    assert!(max_w < 5e-3 && max_f < 5e-2, "{max_w} {max_f}");

    let mut wrong = LocalLevelMechanization::new(truth[0].to_state(), g + 1e-4).unwrap();
    for inc in &incs {
        wrong.step(inc).unwrap();
    }
    let miss = (wrong.state().pos_in_nav - truth.last().unwrap().pos_in_nav).norm();
    assert!(miss > 0.01, "negative control {miss}");
}

/// The stationary start: the ADIS16448 (Table 1 upper bounds, plus a 0.1 deg/s
/// turn-on gyro bias, a setting) at rest for the flight's 10 s; the gyro bias
/// estimated by averaging equals the true bias averaged over the rest within
/// 4.5 ARW / sqrt(T) per axis (the mean of the white noise). Negative control: not
/// calibrating (estimate 0) misses that bound.
#[test]
fn gyro_bias_is_calibrated_at_rest() {
    let (traj, g) = buildings_flight(8);
    let imu = AllanImuParams {
        gyro_turn_on_bias_deg_per_hr: 360.0,
        ..AllanImuParams::adis16448()
    }
    .check()
    .unwrap();
    let rest_s = 10.0;
    let truth = truth_samples(&traj, imu.dt());
    let incs = local_imu_from_truth(&truth, g).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut errors = imu.error_spec().draw(&mut rng);
    let mut measured = Vec::new();
    let mut true_bias_sum = Vector3::zeros();
    for inc in &incs {
        if measured.len() as f64 * imu.dt() >= rest_s - 1e-9 {
            break;
        }
        // at rest the truth is exactly still: no rotation, -g specific force
        assert_eq!(inc.delta_theta, Vector3::zeros());
        let (dth, dv) = errors
            .corrupt(inc.dt, &inc.delta_theta, &inc.delta_v, &mut rng)
            .unwrap();
        true_bias_sum += errors.gyro_bias();
        measured.push(ImuIncrement::new(inc.dt, dth, dv));
    }
    let true_bias = true_bias_sum / measured.len() as f64;
    let est = stationary_gyro_bias(&measured).unwrap();
    let bound = 4.5 * imu.arw() / rest_s.sqrt();
    let err = est - true_bias;
    eprintln!(
        "gyro bias at rest ({} samples): true {:?} deg/h, estimated {:?} deg/h, error {:?} deg/h, \
         bound {:.1} deg/h",
        measured.len(),
        (true_bias * 3600.0).map(f64::to_degrees).as_slice(),
        (est * 3600.0).map(f64::to_degrees).as_slice(),
        (err * 3600.0).map(f64::to_degrees).as_slice(),
        (bound * 3600.0).to_degrees()
    );
    assert_eq!(measured.len(), 1000);
    assert!(err.amax() < bound);
    assert!(true_bias.amax() > bound, "negative control");
}

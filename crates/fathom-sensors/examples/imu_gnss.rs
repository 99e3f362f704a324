//! An IMU and a GNSS receiver on a simulated track, with `fathom-sensors` and
//! `fathom-traj` alone: a vehicle drives a figure of eight at the surface; its IMU
//! (the ADIS16448 figures) and a GPS receiver (nominal 24-satellite constellation,
//! open sky) are sampled from the truth, and the GNSS fixes are solved by
//! single-point positioning.
//!
//! Run with `cargo run -p fathom-sensors --example imu_gnss`.

use fathom_core::{RayCaster, RayHit, frames::nav_from_body};
use fathom_sensors::allan_imu::AllanImuParams;
use fathom_sensors::gnss::{GnssParams, solve_spp};
use fathom_traj::{CubicSpline3, SplineTrajectory, Trajectory};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// No buildings: every satellite above the mask is in line of sight.
struct OpenSky;

impl RayCaster for OpenSky {
    fn cast(&self, _: &Vector3<f64>, _: &Vector3<f64>, _: f64) -> Option<RayHit> {
        None
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Truth: a figure of eight through 9 knots, 20 s apart, at the surface.
    let times: Vec<f64> = (0..9).map(|k| 20.0 * k as f64).collect();
    let knots: Vec<Vector3<f64>> = times
        .iter()
        .map(|t| {
            let a = 2.0 * std::f64::consts::PI * t / 160.0;
            Vector3::new(60.0 * a.sin(), 30.0 * (2.0 * a).sin(), 0.0)
        })
        .collect();
    let truth = SplineTrajectory::new(CubicSpline3::new(&times, &knots)?);
    let mut rng = ChaCha8Rng::seed_from_u64(2024);

    // IMU: increments at its rate, errors drawn once per run (bias, scale factor)
    // and per sample (white noise, bias instability).
    let imu = AllanImuParams::adis16448().check()?;
    let mut imu_errors = imu.error_spec().draw(&mut rng);
    let dt = imu.dt();
    let gravity = Vector3::new(0.0, 0.0, 9.806_65);
    let (mut n, mut gyro_err_sq, mut accel_err_sq) = (0usize, 0.0, 0.0);
    let mut t = truth.start_time();
    while t + dt <= truth.end_time() {
        // Error-free increments over [t, t + dt], from the state at the midpoint.
        let s = truth.state_at(t + 0.5 * dt)?;
        let specific_force = nav_from_body(&s.attitude).transpose() * (s.acc_in_nav - gravity);
        let (d_theta, d_v) = (s.omega_body * dt, specific_force * dt);
        let (d_theta_meas, d_v_meas) = imu_errors.corrupt(dt, &d_theta, &d_v, &mut rng)?;
        gyro_err_sq += ((d_theta_meas - d_theta) / dt).norm_squared();
        accel_err_sq += ((d_v_meas - d_v) / dt).norm_squared();
        n += 1;
        t += dt;
    }
    let gyro_rms = (gyro_err_sq / n as f64).sqrt().to_degrees() * 3600.0;
    let accel_rms = (accel_err_sq / n as f64).sqrt();
    println!(
        "IMU: {n} samples at {:.0} Hz; rate error RMS {gyro_rms:.0} deg/h, specific-force error RMS {accel_rms:.4} m/s^2",
        imu.rate_hz()
    );
    assert!(n > 10_000 && gyro_rms > 0.0 && accel_rms < 0.5);

    // GNSS: one fix per second from the pseudoranges of the satellites in view.
    let gnss = GnssParams::default().check()?;
    let mut horizontal_sq = 0.0;
    let mut fixes = 0usize;
    for k in 0..160 {
        let t = k as f64;
        let s = truth.state_at(t)?;
        let obs = gnss.observe(&OpenSky, t, &s.pos_in_nav, &s.vel_in_nav, &mut rng);
        let pairs: Vec<_> = obs
            .iter()
            .filter_map(|o| o.pseudorange_m.map(|rho| (o.state.pos_ecef, rho)))
            .collect();
        let fix = solve_spp(gnss.frame(), &pairs)?;
        let err = fix.pos_in_nav - s.pos_in_nav;
        horizontal_sq += err.x * err.x + err.y * err.y;
        fixes += 1;
        if k % 40 == 0 {
            println!(
                "t = {t:5.1} s: {} satellites, HDOP {:.2}, horizontal error {:.2} m",
                fix.used,
                fix.dop.hdop,
                err.xy().norm()
            );
        }
    }
    let horizontal_rms = (horizontal_sq / fixes as f64).sqrt();
    println!(
        "GNSS: {fixes} fixes, horizontal RMS error {horizontal_rms:.2} m (sigma 3 m per pseudorange)"
    );
    assert!(horizontal_rms > 0.5 && horizontal_rms < 10.0);
    Ok(())
}

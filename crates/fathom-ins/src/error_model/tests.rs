//! Tests of the error-state model: the discretised `F` against the nonlinear
//! strapdown for small errors, parameter checks and state-error round trips.

use super::*;
use crate::imu_from_truth::{TruthSample, imu_from_truth, stationary_truth};
use crate::route::TurningRoute;
use crate::state::ImuIncrement;
use crate::strapdown::Strapdown;
use approx::{assert_abs_diff_eq, assert_relative_eq};
use nalgebra::{SVector, UnitQuaternion};

fn constant_biases() -> ImuErrorModel {
    ImuErrorParams {
        accel_vrw: 0.0,
        gyro_arw: 0.0,
        accel_bias: BiasModel::Constant,
        gyro_bias: BiasModel::Constant,
    }
    .check()
    .unwrap()
}

/// Runs the nonlinear strapdown from `truth[0]` perturbed by `psi0`, with constant IMU
/// errors `b_a`, `b_g` added to the error-free increments, and the linear model
/// `x_{k+1} = Phi_k x_k` (F at the truth every 0.1 s, second order). Returns the
/// horizontal position errors (nonlinear, linear) at the end.
fn compare(
    truth: &[TruthSample],
    incs: &[ImuIncrement],
    psi0: Vector3<f64>,
    b_a: Vector3<f64>,
    b_g: Vector3<f64>,
    tamper: impl Fn(&mut ErrorMatrix),
) -> (Vector3<f64>, Vector3<f64>) {
    let model = constant_biases();
    let mut s0 = truth[0].to_ins_state();
    s0.nav_from_body = quat_from_rotation_vector(&psi0) * s0.nav_from_body;
    let mut ins = Strapdown::new(s0).unwrap();
    for inc in incs {
        let mut m = *inc;
        m.delta_v += b_a * inc.dt;
        m.delta_theta += b_g * inc.dt;
        ins.step(&m).unwrap();
    }
    let nl = nav_error(ins.state(), &truth[incs.len()].to_ins_state());

    let mut x = SVector::<f64, N_STATES>::zeros();
    x.fixed_rows_mut::<3>(ATT).copy_from(&psi0);
    x.fixed_rows_mut::<3>(ACCEL_BIAS).copy_from(&b_a);
    x.fixed_rows_mut::<3>(GYRO_BIAS).copy_from(&b_g);
    let sub = 10;
    for k in (0..incs.len()).step_by(sub) {
        let dt: f64 = incs[k..k + sub].iter().map(|i| i.dt).sum();
        let mut f = error_dynamics(
            &truth[k].to_ins_state(),
            &incs[k].mean_specific_force(),
            &model,
        );
        tamper(&mut f);
        x = transition_matrix(&f, dt, Discretization::SecondOrder) * x;
    }
    (nl.pos_in_nav, x.fixed_rows::<3>(POS).into_owned())
}

fn rel_horizontal_mismatch(nl: &Vector3<f64>, lin: &Vector3<f64>) -> f64 {
    (nl - lin).xy().norm() / nl.xy().norm()
}

fn stationary_600s() -> (Vec<TruthSample>, Vec<ImuIncrement>) {
    let pos = Geodetic::new(35f64.to_radians(), 129f64.to_radians(), -50.0);
    let att = UnitQuaternion::from_euler_angles(0.02, -0.01, 30f64.to_radians());
    let truth = stationary_truth(pos, att, 0.01, 60_001).unwrap();
    let incs = imu_from_truth(&truth).unwrap();
    (truth, incs)
}

/// Acceptance: for a stationary INS the discretised F reproduces the nonlinear
/// position error after 600 s (tilt, accelerometer bias, gyro bias separately) within
/// 10 %.
#[test]
fn linear_model_matches_nonlinear_strapdown_stationary() {
    let (truth, incs) = stationary_600s();
    let g = 9.806_65;
    let cases = [
        (
            "tilt",
            Vector3::new(1e-4, -5e-5, 2e-4),
            Vector3::zeros(),
            Vector3::zeros(),
        ),
        (
            "accel bias",
            Vector3::zeros(),
            Vector3::new(1e-4 * g, -5e-5 * g, 2e-5 * g),
            Vector3::zeros(),
        ),
        (
            "gyro bias",
            Vector3::zeros(),
            Vector3::zeros(),
            Vector3::new(1.0, -0.5, 0.3) * (1f64.to_radians() / 3600.0),
        ),
    ];
    for (name, psi0, b_a, b_g) in cases {
        let (nl, lin) = compare(&truth, &incs, psi0, b_a, b_g, |_| {});
        let mismatch = rel_horizontal_mismatch(&nl, &lin);
        eprintln!(
            "{name}: nonlinear dr = [{:.3}, {:.3}] m, linear dr = [{:.3}, {:.3}] m, mismatch {:.2e}",
            nl.x, nl.y, lin.x, lin.y, mismatch
        );
        assert!(nl.xy().norm() > 1.0, "{name}: error must be noticeable");
        assert!(mismatch < 0.1, "{name}: mismatch {mismatch}");
    }
    // Negative control: flipping the sign of the specific-force coupling -[f x] breaks
    // the agreement.
    let (nl, lin) = compare(&truth, &incs, cases[0].1, cases[0].2, cases[0].3, |f| {
        let blk = f.fixed_view::<3, 3>(VEL, ATT).into_owned();
        f.fixed_view_mut::<3, 3>(VEL, ATT).copy_from(&(-blk));
    });
    let mismatch = rel_horizontal_mismatch(&nl, &lin);
    eprintln!("negative control (flipped -[f x]): mismatch {mismatch:.2e}");
    assert!(mismatch > 0.1);
}

/// The velocity- and transport-rate-dependent terms, on a manoeuvring vehicle.
#[test]
fn linear_model_matches_nonlinear_strapdown_moving() {
    let route = TurningRoute::vkf_default();
    let truth = route.sample(0.01, 60_001, 2).unwrap();
    let incs = imu_from_truth(&truth).unwrap();
    let (nl, lin) = compare(
        &truth,
        &incs,
        Vector3::new(5e-5, 5e-5, 1e-3),
        Vector3::new(2e-4, -1e-4, 0.0),
        Vector3::new(0.3, 0.2, -0.5) * (1f64.to_radians() / 3600.0),
        |_| {},
    );
    let mismatch = rel_horizontal_mismatch(&nl, &lin);
    eprintln!(
        "moving: nonlinear dr = [{:.3}, {:.3}] m, linear [{:.3}, {:.3}] m, mismatch {mismatch:.2e}",
        nl.x, nl.y, lin.x, lin.y
    );
    assert!(mismatch < 0.1);
}

#[test]
fn params_are_checked_and_psd_built() {
    let p = ImuErrorParams {
        accel_vrw: 3.3e-5,
        gyro_arw: 1e-6,
        accel_bias: BiasModel::GaussMarkov {
            sigma: 1e-4,
            tau: 3600.0,
        },
        gyro_bias: BiasModel::RandomWalk { sigma_rate: 1e-9 },
    };
    let m = p.check().unwrap();
    let q = m.noise_psd();
    assert_relative_eq!(q[(0, 0)], 3.3e-5 * 3.3e-5);
    assert_relative_eq!(q[(5, 5)], 1e-12);
    assert_relative_eq!(q[(8, 8)], 2.0 * 1e-8 / 3600.0);
    assert_relative_eq!(q[(11, 11)], 1e-18);
    let s = InsState::new(
        Geodetic::new(0.6, 2.2, -50.0),
        Vector3::zeros(),
        UnitQuaternion::identity(),
    );
    let f = error_dynamics(&s, &Vector3::new(0.0, 0.0, -9.8), &m);
    assert_relative_eq!(f[(ACCEL_BIAS, ACCEL_BIAS)], -1.0 / 3600.0);
    assert_eq!(f[(GYRO_BIAS, GYRO_BIAS)], 0.0);
    // Vertical channel: d(dv_D)/d(dr_D) = +2g/R > 0 (unstable).
    assert!(f[(VEL + 2, POS + 2)] > 3.0e-6);
    // Discretisation and Q_d.
    let phi = transition_matrix(&f, 0.1, Discretization::FirstOrder);
    assert_relative_eq!(phi, ErrorMatrix::identity() + f * 0.1);
    let g = noise_input(&s);
    let qd = discrete_process_noise(&phi, &g, &q, 0.1);
    assert_relative_eq!(qd, qd.transpose());
    assert_relative_eq!(qd[(VEL, VEL)], 3.3e-5 * 3.3e-5 * 0.1, max_relative = 1e-3);

    for bad in [
        ImuErrorParams {
            accel_vrw: -1.0,
            ..p
        },
        ImuErrorParams {
            gyro_arw: f64::NAN,
            ..p
        },
        ImuErrorParams {
            accel_bias: BiasModel::GaussMarkov {
                sigma: 1e-4,
                tau: 0.0,
            },
            ..p
        },
        ImuErrorParams {
            gyro_bias: BiasModel::RandomWalk { sigma_rate: -1e-9 },
            ..p
        },
    ] {
        assert!(bad.check().is_err());
    }
}

#[test]
fn nav_error_and_correction_round_trip() {
    let truth = InsState::new(
        Geodetic::new(0.61, 2.25, -50.0),
        Vector3::new(5.0, -1.0, 0.1),
        UnitQuaternion::from_euler_angles(0.1, -0.05, 2.0),
    );
    let err = NavError {
        pos_in_nav: Vector3::new(120.0, -80.0, 3.0),
        vel_in_nav: Vector3::new(0.1, -0.2, 0.01),
        attitude: Vector3::new(1e-3, -2e-3, 5e-3),
    };
    // Build an estimate with that error, then measure and remove it.
    let mut est = truth;
    est.h -= err.pos_in_nav.z;
    est.lat += err.pos_in_nav.x / (earth::meridian_radius(truth.lat) + truth.h);
    est.lon +=
        err.pos_in_nav.y / ((earth::transverse_radius(truth.lat) + truth.h) * truth.lat.cos());
    est.vel_in_nav += err.vel_in_nav;
    est.nav_from_body = quat_from_rotation_vector(&err.attitude) * truth.nav_from_body;
    let measured = nav_error(&est, &truth);
    assert_abs_diff_eq!(measured.pos_in_nav, err.pos_in_nav, epsilon = 1e-2);
    assert_abs_diff_eq!(measured.vel_in_nav, err.vel_in_nav, epsilon = 1e-12);
    assert_abs_diff_eq!(measured.attitude, err.attitude, epsilon = 1e-12);
    let back = correct_state(&est, &measured);
    let residual = nav_error(&back, &truth);
    assert_abs_diff_eq!(residual.pos_in_nav, Vector3::zeros(), epsilon = 1e-6);
    assert_abs_diff_eq!(residual.vel_in_nav, Vector3::zeros(), epsilon = 1e-12);
    assert_abs_diff_eq!(residual.attitude, Vector3::zeros(), epsilon = 1e-12);
    // Sign convention: a positive psi_D is a heading too large.
    let e = nav_error(
        &InsState {
            nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, 0.01),
            ..truth
        },
        &InsState {
            nav_from_body: UnitQuaternion::identity(),
            ..truth
        },
    );
    assert_abs_diff_eq!(e.attitude.z, 0.01, epsilon = 1e-12);
}

//! A constant-velocity tracker with `fathom-estimators` alone, next to the same
//! filter in FilterPy's style.
//!
//! A target moves in the plane at constant velocity with small random accelerations;
//! noisy position fixes (sigma 3 m) arrive every second, and every 25th fix is a
//! wild one (60 m off). The tracker is a 4-state `[x, vx, y, vy]` Kalman filter with
//! a chi-square gate at 99.9 %, which must throw out exactly the wild fixes and
//! track the target to well inside the fix noise.
//!
//! The same filter with FilterPy (Python), for comparison:
//!
//! ```text
//! from filterpy.kalman import KalmanFilter
//! from filterpy.common import Q_discrete_white_noise
//! from scipy.linalg import block_diag
//! from scipy.stats import chi2
//!
//! kf = KalmanFilter(dim_x=4, dim_z=2)
//! kf.x = np.zeros(4); kf.P = np.eye(4) * 500.0
//! f1 = np.array([[1.0, dt], [0.0, 1.0]])
//! kf.F = block_diag(f1, f1)
//! q1 = Q_discrete_white_noise(dim=2, dt=dt, var=0.1**2)
//! kf.Q = block_diag(q1, q1)
//! kf.H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
//! kf.R = np.eye(2) * 3.0**2
//! gate = chi2.ppf(0.999, 2)
//! for z in fixes:
//!     kf.predict()
//!     y = z - kf.H @ kf.x
//!     S = kf.H @ kf.P @ kf.H.T + kf.R
//!     if y @ np.linalg.solve(S, y) <= gate:   # FilterPy has no gate: done by hand
//!         kf.update(z)
//! ```
//!
//! Run with `cargo run -p fathom-estimators --example cv_tracker`.

use fathom_core::Gaussian;
use fathom_estimators::{GateThreshold, KalmanFilter, MeasurementNoise, ProcessNoise, models};
use nalgebra::{Matrix2, Matrix4, SMatrix, Vector2, Vector4};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dt = 1.0;
    let (accel_sigma, fix_sigma): (f64, f64) = (0.1, 3.0);

    // F and Q: the 1D constant-velocity blocks for x and y (FilterPy's
    // `Q_discrete_white_noise(dim=2, dt, var)` is `cv_discrete_white_accel_q_1d`).
    let (f1, q1) = (
        models::cv_transition_1d(dt)?,
        models::cv_discrete_white_accel_q_1d(dt, accel_sigma)?,
    );
    let mut f = Matrix4::zeros();
    let mut q = Matrix4::zeros();
    for axis in 0..2 {
        f.fixed_view_mut::<2, 2>(2 * axis, 2 * axis).copy_from(&f1);
        q.fixed_view_mut::<2, 2>(2 * axis, 2 * axis).copy_from(&q1);
    }
    // Q and R are checked once here (symmetric, PSD / PD), not at every step.
    let q = ProcessNoise::new(q)?;
    let r = MeasurementNoise::new(Matrix2::identity() * fix_sigma.powi(2))?;
    let h = SMatrix::<f64, 2, 4>::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    let gate = GateThreshold::from_chi_square_probability(0.999, 2)?;

    let prior = Gaussian::new(Vector4::zeros(), Matrix4::identity() * 500.0)?;
    let mut kf = KalmanFilter::new(prior, 0.0)?;

    // The truth and its fixes, from one seeded stream.
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let (accel, fix_noise) = (Normal::new(0.0, accel_sigma)?, Normal::new(0.0, fix_sigma)?);
    let mut truth = Vector4::new(0.0, 8.0, 0.0, -3.0);
    let (mut rejected, mut sq_err, mut sq_fix, mut n, mut n_fix) = (Vec::new(), 0.0, 0.0, 0, 0);
    for k in 1..=200 {
        let t = k as f64 * dt;
        let a = Vector2::new(accel.sample(&mut rng), accel.sample(&mut rng));
        truth =
            f * truth + Vector4::new(0.5 * a.x * dt * dt, a.x * dt, 0.5 * a.y * dt * dt, a.y * dt);
        let mut z =
            h * truth + Vector2::new(fix_noise.sample(&mut rng), fix_noise.sample(&mut rng));
        if k % 25 == 0 {
            z.x += 60.0; // a wild fix
        }

        kf.predict_with_noise(&f, &q, t)?;
        let gated = kf.update_gated(&z, &h, r.matrix(), gate)?;
        if !gated.is_accepted() {
            rejected.push(k);
        }
        if k > 20 {
            let e = h * (kf.state() - truth);
            sq_err += e.norm_squared();
            n += 1;
            if k % 25 != 0 {
                sq_fix += (z - h * truth).norm_squared();
                n_fix += 1;
            }
        }
        if (k + 10) % 50 == 0 {
            let x = kf.state();
            println!(
                "t = {t:5.0} s: position ({:8.1}, {:8.1}) m, velocity ({:5.2}, {:5.2}) m/s, NIS {:.2}",
                x[0],
                x[2],
                x[1],
                x[3],
                gated.nis()
            );
        }
    }
    let rms_est = (sq_err / f64::from(n)).sqrt();
    let rms_fix = (sq_fix / f64::from(n_fix)).sqrt();
    println!("rejected fixes at k = {rejected:?}");
    println!("position RMS error after 20 s: {rms_est:.2} m (the good fixes: {rms_fix:.2} m)");
    assert_eq!(rejected, (1..=8).map(|i| 25 * i).collect::<Vec<_>>());
    assert!(rms_est < 0.6 * rms_fix);
    let v = kf.state();
    let v_err = ((v[1] - truth[1]).powi(2) + (v[3] - truth[3]).powi(2)).sqrt();
    assert!(v_err < 0.5, "velocity error {v_err} m/s");
    Ok(())
}

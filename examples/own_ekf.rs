//! A user's own EKF written against `fathom-estimators` alone: a planar robot with a
//! unicycle motion model (speed and turn rate as inputs) and range measurements to
//! two known landmarks, with chi-square gating of each range.
//!
//! Run with `cargo run --example own_ekf`. It simulates a short drive with one
//! corrupted range and prints the final error and which ranges the gate rejected.

use fathom::core::Gaussian;
use fathom::estimators::ekf::{Ekf, GroupItem, MotionModel, Propagation, ScalarModel};
use fathom::estimators::{EstimatorError, GateThreshold};
use nalgebra::{Matrix3, RowVector3, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// State `(x, y, heading)`; input `(speed m/s, turn rate rad/s)` held between samples.
#[derive(Debug, Clone, Copy)]
struct Unicycle {
    /// Process noise PSD on the speed, (m/s)^2 s.
    speed_psd: f64,
    /// Process noise PSD on the turn rate, (rad/s)^2 s.
    turn_psd: f64,
}

impl MotionModel<3> for Unicycle {
    type Input = [f64; 2];
    type InputSample = [f64; 2];

    fn apply_sample(&self, input: &mut [f64; 2], sample: &[f64; 2]) {
        *input = *sample;
    }

    fn propagate(
        &self,
        x: &Vector3<f64>,
        u: &[f64; 2],
        dt: f64,
    ) -> Result<Propagation<3>, EstimatorError> {
        let (v, w) = (u[0], u[1]);
        let mid = x[2] + 0.5 * w * dt;
        let (s, c) = mid.sin_cos();
        let x_pred = Vector3::new(x[0] + v * dt * c, x[1] + v * dt * s, x[2] + w * dt);
        let f_jacobian = Matrix3::new(1.0, 0.0, -v * dt * s, 0.0, 1.0, v * dt * c, 0.0, 0.0, 1.0);
        // Input noise mapped into the state: G diag(q_v, q_w) G^T dt.
        let g = nalgebra::Matrix3x2::new(dt * c, 0.0, dt * s, 0.0, 0.0, dt);
        let q_in = nalgebra::Matrix2::new(self.speed_psd / dt, 0.0, 0.0, self.turn_psd / dt);
        let q = g * q_in * g.transpose();
        Ok(Propagation {
            x_pred,
            f_jacobian,
            q,
        })
    }
}

/// Range to a landmark at a known position.
#[derive(Debug, Clone, Copy)]
struct RangeTo(Vector2<f64>);

impl ScalarModel<3> for RangeTo {
    fn evaluate(&self, x: &Vector3<f64>) -> Result<(f64, RowVector3<f64>), EstimatorError> {
        let d = Vector2::new(x[0], x[1]) - self.0;
        let r = d.norm();
        if r < 1e-9 {
            return Err(EstimatorError::OutOfRange {
                what: "range to a landmark".into(),
                value: r,
                expected: "> 0 (the Jacobian is undefined at the landmark)",
            });
        }
        Ok((r, RowVector3::new(d.x / r, d.y / r, 0.0)))
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let landmarks = [
        RangeTo(Vector2::new(20.0, 0.0)),
        RangeTo(Vector2::new(0.0, 20.0)),
    ];
    let model = Unicycle {
        speed_psd: 0.01,
        turn_psd: 0.001,
    };
    let prior = Gaussian::new(
        Vector3::new(0.5, -0.5, 0.05),
        Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 0.01)),
    )?;
    let mut ekf = Ekf::new(prior, 0.0, model, [1.0, 0.1])?;
    // 99 % chi-square gate on each scalar range (1 dof).
    let gate = GateThreshold::from_chi_square_probability(0.99, 1)?;

    // The truth drives the same commands without noise, from the origin.
    let mut truth = Vector3::<f64>::zeros();
    let dt = 0.1;
    let mut rejected = Vec::new();
    let sigma = 0.05;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for k in 1..=200 {
        let t = k as f64 * dt;
        let mid = truth[2] + 0.05 * 0.1;
        truth += Vector3::new(0.1 * mid.cos(), 0.1 * mid.sin(), 0.01);
        ekf.predict_to(t)?;
        if k % 5 == 0 {
            let items: Vec<GroupItem<'_, RangeTo>> = landmarks
                .iter()
                .map(|lm| {
                    let noise: f64 = rng.sample(StandardNormal);
                    let mut z = (Vector2::new(truth[0], truth[1]) - lm.0).norm() + sigma * noise;
                    if k == 100 && lm.0.x > 0.0 {
                        z += 5.0; // one gross outlier
                    }
                    GroupItem {
                        value: z,
                        model: lm,
                        variance: sigma * sigma,
                        gate: Some(gate),
                    }
                })
                .collect();
            for (i, o) in ekf.update_sequential(&items)?.iter().enumerate() {
                if !o.accepted {
                    rejected.push((t, i, o.nis));
                }
            }
        }
    }
    let err = (ekf.state().xy() - truth.xy()).norm();
    println!("final position error {err:.3} m after {} s", 200.0 * dt);
    for (t, i, nis) in &rejected {
        println!("rejected: range to landmark {i} at t = {t:.1} s (NIS {nis:.1})");
    }
    Ok(())
}

//! Statistical consistency (NEES / NIS) tests of the Kalman filter on a simulated
//! linear constant-velocity system, with a negative control.

use crate::{KalmanFilter, models};
use fathom_core::Gaussian;
use nalgebra::{Matrix1, Matrix2, SMatrix, Vector1, Vector2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use statrs::distribution::{ChiSquared, ContinuousCDF};

const RUNS: usize = 50;
const STEPS: usize = 100;
const DT: f64 = 1.0;
const Q_PSD: f64 = 0.05;
const R_POS: f64 = 1.0;

/// Per-step averages over the runs of NEES (dof 2) and NIS (dof 1).
struct Averages {
    nees: Vec<f64>,
    nis: Vec<f64>,
}

fn std_normal2(rng: &mut ChaCha8Rng) -> Vector2<f64> {
    Vector2::new(rng.sample(StandardNormal), rng.sample(StandardNormal))
}

/// Simulates `RUNS` independent runs of the truth with the true `Q`, filters them
/// with `Q * filter_q_scale`, and averages NEES/NIS over the runs at each step.
fn simulate(filter_q_scale: f64, seed: u64) -> Averages {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let f = models::cv_transition_1d(DT).unwrap();
    let q_true = models::cv_white_accel_q_1d(DT, Q_PSD).unwrap();
    let q_filter = q_true * filter_q_scale;
    let l_q = q_true.cholesky().unwrap().unpack();
    let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
    let r = Matrix1::new(R_POS);
    let x0_hat = Vector2::new(0.0, 1.0);
    let p0 = Matrix2::new(4.0, 0.0, 0.0, 0.25);
    let l_p0 = p0.cholesky().unwrap().unpack();

    let mut nees = vec![0.0; STEPS];
    let mut nis = vec![0.0; STEPS];
    for _ in 0..RUNS {
        let mut truth = x0_hat + l_p0 * std_normal2(&mut rng);
        let mut kf = KalmanFilter::new(Gaussian::new(x0_hat, p0).unwrap(), 0.0).unwrap();
        for k in 0..STEPS {
            truth = f * truth + l_q * std_normal2(&mut rng);
            let v: f64 = rng.sample(StandardNormal);
            let z = Vector1::new(truth[0] + R_POS.sqrt() * v);
            kf.predict(&f, &q_filter, (k + 1) as f64 * DT).unwrap();
            let info = kf.update(&z, &h, &r).unwrap();
            nis[k] += info.nis / RUNS as f64;
            nees[k] += kf.estimate().mahalanobis_sq(&truth).unwrap() / RUNS as f64;
        }
    }
    Averages { nees, nis }
}

/// Two-sided 95 % bounds of the run-average of a chi-square(dof) statistic over
/// `RUNS` runs: `RUNS * avg ~ chi2(RUNS * dof)`.
fn bounds(dof: usize) -> (f64, f64) {
    let chi2 = ChiSquared::new((RUNS * dof) as f64).unwrap();
    (
        chi2.inverse_cdf(0.025) / RUNS as f64,
        chi2.inverse_cdf(0.975) / RUNS as f64,
    )
}

fn fraction_inside(values: &[f64], (lo, hi): (f64, f64)) -> f64 {
    values.iter().filter(|&&v| v >= lo && v <= hi).count() as f64 / values.len() as f64
}

/// Bar-Shalom's Monte Carlo consistency test: at each step the NEES averaged over
/// 50 independent runs, times 50, is chi2(50 * 2) for a consistent filter, so it lies
/// in the 95 % interval with probability 0.95 at each step. The steps of the same
/// runs are correlated in time, so the count of steps inside is not binomial; we
/// require >= 90 % inside (nominal 95 %). Same for the NIS (dof 1).
#[test]
fn nees_and_nis_within_chi_square_bounds() {
    let avg = simulate(1.0, 2024);
    let (lo, hi) = bounds(2);
    assert!(
        (lo - 1.48).abs() < 0.02 && (hi - 2.59).abs() < 0.02,
        "{lo} {hi}"
    );
    let frac_nees = fraction_inside(&avg.nees, (lo, hi));
    let frac_nis = fraction_inside(&avg.nis, bounds(1));
    eprintln!("consistent filter: NEES inside {frac_nees}, NIS inside {frac_nis}");
    assert!(frac_nees >= 0.90, "NEES fraction inside {frac_nees}");
    assert!(frac_nis >= 0.90, "NIS fraction inside {frac_nis}");
    // overall mean NEES near its expectation 2 (loose, the steps are correlated)
    let mean = avg.nees.iter().sum::<f64>() / STEPS as f64;
    assert!((mean - 2.0).abs() < 0.3, "mean NEES {mean}");
}

/// Negative control: the same data filtered with Q 100x too small makes the filter
/// overconfident; the per-step NEES leaves the bounds for most steps.
#[test]
fn nees_negative_control_q_too_small_fails() {
    let avg = simulate(0.01, 2024);
    let frac = fraction_inside(&avg.nees, bounds(2));
    eprintln!("Q/100 filter: NEES inside {frac}");
    assert!(frac < 0.5, "NEES fraction inside {frac}");
    let (_, hi) = bounds(2);
    let above = avg.nees.iter().filter(|&&v| v > hi).count();
    assert!(above > STEPS / 2, "{above} steps above the upper bound");
}

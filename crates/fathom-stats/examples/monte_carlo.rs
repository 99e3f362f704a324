//! Monte Carlo statistics of a user's own estimator, with `fathom-stats` alone.
//!
//! The toy estimators: a beacon at a fixed position is located from noisy 3D fixes
//! (sigma 2 m per axis). `running-mean` averages every fix so far and reports the
//! covariance `sigma^2 / k I` after `k` fixes; `window-10` averages only the last 10
//! fixes but reports the same covariance (an overconfident filter). 200 seeded runs
//! of 100 fixes each give per-run error statistics, their Monte Carlo means with
//! 95 % intervals, a BCa bootstrap interval and a median interval, the paired
//! difference of the two estimators on the same fixes, and the NEES consistency test,
//! which the running mean passes and the window fails.
//!
//! Run with `cargo run -p fathom-stats --example monte_carlo`.

use fathom_stats::{
    Aggregator, ChiSquareBounds, RunStats, bootstrap_bca_mean, distance_series_3d, median_ci, nees,
    paired_mean_ci,
};
use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const RUNS: usize = 200;
const FIXES: usize = 100;
const SIGMA: f64 = 2.0;

/// One run: the estimates after each fix of a mean over the last `window` fixes, and
/// the NEES of the last one under the claimed covariance `sigma^2 / k I`.
fn run(seed: u64, truth: Vector3<f64>, window: usize) -> (Vec<Vector3<f64>>, f64) {
    // One independent, reproducible stream per run (the same for both estimators).
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, SIGMA).unwrap();
    let fixes: Vec<Vector3<f64>> = (0..FIXES)
        .map(|_| truth + Vector3::from_fn(|_, _| noise.sample(&mut rng)))
        .collect();
    let estimates: Vec<Vector3<f64>> = (1..=FIXES)
        .map(|k| {
            let used = &fixes[k.saturating_sub(window)..k];
            used.iter().sum::<Vector3<f64>>() / used.len() as f64
        })
        .collect();
    let cov = Matrix3::identity() * (SIGMA * SIGMA / FIXES as f64);
    let last = estimates[FIXES - 1] - truth;
    (estimates, nees(&last, &cov).unwrap())
}

fn main() -> Result<(), fathom_stats::StatsError> {
    let truth = Vector3::new(120.0, -40.0, 35.0);
    let truths = vec![truth; FIXES];
    let mut agg = Aggregator::new();
    let mut final_errors = [Vec::new(), Vec::new()];
    let mut nees_sum = [0.0; 2];
    for r in 0..RUNS {
        for (i, (name, window)) in [("running-mean", FIXES), ("window-10", 10)]
            .into_iter()
            .enumerate()
        {
            // Both estimators see the same fixes (same seed): a paired comparison.
            let (est, nees_last) = run(1000 + r as u64, truth, window);
            let errors = distance_series_3d(&est, &truths)?;
            let stats = RunStats::of(&errors[FIXES / 2..])?; // the second half of the run
            agg.push_run_stats(name, &stats, "_3d")?;
            final_errors[i].push(errors[FIXES - 1]);
            nees_sum[i] += nees_last;
        }
    }

    println!("{RUNS} runs of {FIXES} fixes (sigma {SIGMA} m per axis)");
    for row in agg.summarize()? {
        let [lo, hi] = row.stats.ci95.expect("more than one run");
        println!(
            "  {:12} {:8}: {:.4} m, 95 % CI [{lo:.4}, {hi:.4}]",
            row.method, row.metric, row.stats.mean
        );
    }

    // The running mean's final 3D error: its mean (BCa bootstrap) and its median.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let [blo, bhi] = bootstrap_bca_mean(&final_errors[0], 0.95, 2000, &mut rng)?;
    let med = median_ci(&final_errors[0], 0.95)?;
    println!(
        "  final error: mean in [{blo:.3}, {bhi:.3}] m (BCa), median {:.3} m",
        med.median
    );
    // E|e| for e ~ N(0, s^2 I3) is s * sqrt(8 / pi), s = sigma / sqrt(FIXES).
    let expected = SIGMA / (FIXES as f64).sqrt() * (8.0 / std::f64::consts::PI).sqrt();
    assert!(
        blo < expected && expected < bhi,
        "{expected} outside [{blo}, {bhi}]"
    );

    // Paired difference of the final errors, window - running mean, run by run.
    let d = paired_mean_ci(&final_errors[1], &final_errors[0])?;
    let [dlo, dhi] = d.ci95.expect("more than one run");
    println!(
        "  window-10 - running-mean final error: {:.3} m, 95 % CI [{dlo:.3}, {dhi:.3}]",
        d.mean
    );
    assert!(dlo > 0.0, "the window is worse");

    // NEES: the average over runs against the 95 % band of a consistent filter.
    let bounds = ChiSquareBounds::average_nees(3, RUNS)?;
    let avg = nees_sum.map(|s| s / RUNS as f64);
    println!(
        "  average NEES: running-mean {:.2}, window-10 {:.2}; consistent in [{:.2}, {:.2}]",
        avg[0], avg[1], bounds.lo, bounds.hi
    );
    assert!(bounds.contains(avg[0]), "the running mean is consistent");
    assert!(avg[1] > bounds.hi, "the overconfident window is caught");
    Ok(())
}

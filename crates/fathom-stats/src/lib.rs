//! Evaluation statistics of fathom: distance-error series, per-run statistics
//! (mean, population std, max, RMSE), Monte Carlo means with Student-t confidence
//! intervals, sample covariances with per-entry intervals, histograms, and filter
//! consistency tests (NEES / NIS with chi-square bounds), and the overlapping Allan
//! variance of inertial-sensor records with its noise-figure readings ([`allan`]).
//!
//! Conventions (spec README): the distance error is the Euclidean norm of
//! (estimated - true position) per instant, 3D over x, y, z or 2D over x, y; a run
//! is summarized by mean, population std (1/n over time samples), max and RMSE;
//! across Monte Carlo runs the mean of each per-run statistic is reported with its
//! 95 % confidence interval (`ci95`, `None`/null only for a single value).
//!
//! ```
//! use fathom_stats::{
//!     consistency::{nees, ChiSquareBounds},
//!     distance_series_3d, Aggregator, RunStats,
//! };
//! use nalgebra::{Matrix2, Vector2, Vector3};
//!
//! // One run: per-instant 3D distance errors and their statistics.
//! let truth = vec![Vector3::new(0.0, 0.0, 10.0); 3];
//! let est = vec![
//!     Vector3::new(3.0, 4.0, 10.0),
//!     Vector3::new(0.0, 0.0, 12.0),
//!     Vector3::new(1.0, 0.0, 10.0),
//! ];
//! let errors = distance_series_3d(&est, &truth)?;
//! let run = RunStats::of(&errors)?;
//! assert_eq!(run.max, 5.0);
//! assert!((run.rmse.powi(2) - (run.mean.powi(2) + run.std.powi(2))).abs() < 1e-12);
//!
//! // Monte Carlo: accumulate per-run statistics, then mean and 95 % CI per key.
//! let mut agg = Aggregator::new();
//! for (k, mean) in [2.31, 2.25, 2.40, 2.28].into_iter().enumerate() {
//!     agg.push("MF", "mean_3d", mean)?;
//!     agg.push("EFF", "mean_3d", 1.1 + 0.01 * k as f64)?;
//! }
//! let rows = agg.summarize()?;
//! assert_eq!(rows[0].method, "MF"); // insertion order, deterministic
//! let [lo, hi] = rows[0].stats.ci95.unwrap();
//! assert!(lo < rows[0].stats.mean && rows[0].stats.mean < hi);
//!
//! // Consistency: NEES and the 95 % bounds of its average over 50 runs (dof 2).
//! let e = nees(&Vector2::new(1.0, 1.0), &Matrix2::new(1.0, 0.0, 0.0, 1.0))?;
//! assert_eq!(e, 2.0);
//! let bounds = ChiSquareBounds::average_nees(2, 50)?;
//! assert!((bounds.hi - 129.5612 / 50.0).abs() < 1e-5 && bounds.contains(2.0));
//! # Ok::<(), fathom_stats::StatsError>(())
//! ```
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod allan;
pub mod bootstrap;
pub mod consistency;
pub mod covariance;
pub mod equivalence;
pub mod error;
pub mod error_series;
pub mod histogram;
pub mod metric_summary;
pub mod monte_carlo;
pub mod proportion;
pub mod quantile;
pub mod run_stats;
pub mod sample;

#[cfg(test)]
mod coverage_tests;

pub use allan::{AllanPoint, RateNoise, overlapping_allan_variance, white_noise_coefficient};
pub use bootstrap::{bootstrap_bca_mean, bootstrap_percentile_mean};
pub use consistency::{ChiSquareBounds, nees, nis};
pub use covariance::{
    CiMethod, CovarianceCi, MaxDeviation, MeanMode, covariance, covariance_ci_batch_means,
    covariance_ci_normal, max_relative_deviation, sample_covariance, zero_mean_covariance,
};
pub use equivalence::{Equivalence, Verdict, equivalence};
pub use error::StatsError;
pub use error_series::{
    DistanceSeries, distance_2d, distance_3d, distance_series, distance_series_2d,
    distance_series_3d,
};
pub use histogram::Histogram;
pub use metric_summary::{
    Divergence, IntervalMethod, MetricKind, MetricSummary, SummarySettings, row_seed,
    summarize_metric,
};
pub use monte_carlo::{
    AggregateRow, Aggregator, CiBand, MeanCi, MeanInterval, mean_and_ci95, mean_ci,
    mean_curve_ci95, mean_interval,
};
pub use proportion::{MedianCi, Proportion, clopper_pearson, median_ci};
pub use quantile::{chi2_cdf, chi2_quantile, normal_cdf, normal_quantile, student_t_quantile};
pub use run_stats::RunStats;
pub use sample::{Quartiles, median, paired_mean_ci, quantile, rms};

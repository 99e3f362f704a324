//! Range errors of a Plaza log against its ground truth: a description of the data for
//! the report only (the filters never see it).

use fathom_data::plaza::{BeaconSite, PlazaLog, PoseRecord};
use fathom_sim::SimError;

/// Range errors measured against ground truth. Used only to describe the data in the
/// report; the filters never see it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RangeAnalysis {
    /// Ranges inside the ground-truth time span.
    pub n: usize,
    /// Mean of `range - true distance`, m.
    pub mean: f64,
    /// Population std, m.
    pub std: f64,
    /// Median, m.
    pub median: f64,
    /// 1.4826 x median absolute deviation from the median, m.
    pub robust_sigma: f64,
    /// Smallest and largest error, m.
    pub min_max: (f64, f64),
    /// Least-squares fit `error = a + b d`: `(a, b)`.
    pub fit: (f64, f64),
    /// Std of the fit residuals, m.
    pub fit_std: f64,
    /// Kurtosis of the fit residuals (3 for a Gaussian).
    pub fit_kurtosis: f64,
    /// Fraction of fit residuals beyond 3 fit-stds.
    pub fit_beyond_3sigma: f64,
    /// Median error per beacon: `(id, count, median)`, survey order.
    pub per_beacon: Vec<(i64, usize, f64)>,
    /// `(time - t0, true distance, error, beacon row)` per range.
    pub samples: Vec<(f64, f64, f64, usize)>,
}

/// Linear interpolation of the ground-truth position at `t` (inside its span).
pub fn truth_at(gt: &[PoseRecord], t: f64) -> Option<(f64, f64)> {
    let i = gt.partition_point(|p| p.time <= t);
    if i == 0 || i >= gt.len() {
        return (i > 0 && gt[i - 1].time == t).then(|| (gt[i - 1].x, gt[i - 1].y));
    }
    let (a, b) = (gt[i - 1], gt[i]);
    let u = (t - a.time) / (b.time - a.time);
    Some((a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)))
}

fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if !n.is_multiple_of(2) {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    }
}

/// Analyses the range errors of `log` against its ground truth.
///
/// # Errors
/// [`SimError::InvalidArgument`] when fewer than 3 ranges fall in the ground-truth span.
pub fn analyse_ranges(log: &PlazaLog) -> Result<RangeAnalysis, SimError> {
    let t0 = log.ground_truth[0].time;
    let samples: Vec<(f64, f64, f64, usize)> = log
        .ranges
        .iter()
        .filter_map(|r| {
            let (x, y) = truth_at(&log.ground_truth, r.time)?;
            let b: &BeaconSite = &log.beacons[r.beacon];
            let d = (x - b.x).hypot(y - b.y);
            Some((r.time - t0, d, r.range - d, r.beacon))
        })
        .collect();
    let n = samples.len();
    if n < 3 {
        return Err(SimError::invalid_argument(
            "range analysis",
            format!("only {n} ranges inside the ground-truth time span"),
        ));
    }
    let nf = n as f64;
    let errs: Vec<f64> = samples.iter().map(|s| s.2).collect();
    let mean = errs.iter().sum::<f64>() / nf;
    let std = (errs.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / nf).sqrt();
    let mut sorted = errs.clone();
    sorted.sort_by(f64::total_cmp);
    let med = median(&sorted);
    let mut dev: Vec<f64> = sorted.iter().map(|e| (e - med).abs()).collect();
    dev.sort_by(f64::total_cmp);
    let robust_sigma = 1.4826 * median(&dev);
    let dm = samples.iter().map(|s| s.1).sum::<f64>() / nf;
    let sxx = samples.iter().map(|s| (s.1 - dm).powi(2)).sum::<f64>();
    let sxy = samples
        .iter()
        .map(|s| (s.1 - dm) * (s.2 - mean))
        .sum::<f64>();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let a = mean - b * dm;
    let res: Vec<f64> = samples.iter().map(|s| s.2 - a - b * s.1).collect();
    let fit_std = (res.iter().map(|r| r * r).sum::<f64>() / nf).sqrt();
    let fit_kurtosis = if fit_std > 0.0 {
        res.iter().map(|r| r.powi(4)).sum::<f64>() / nf / fit_std.powi(4)
    } else {
        0.0
    };
    let fit_beyond_3sigma = res.iter().filter(|r| r.abs() > 3.0 * fit_std).count() as f64 / nf;
    let per_beacon = log
        .beacons
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let mut e: Vec<f64> = samples.iter().filter(|s| s.3 == k).map(|s| s.2).collect();
            e.sort_by(f64::total_cmp);
            let m = if e.is_empty() { 0.0 } else { median(&e) };
            (b.id, e.len(), m)
        })
        .collect();
    Ok(RangeAnalysis {
        n,
        mean,
        std,
        median: med,
        robust_sigma,
        min_max: (sorted[0], sorted[n - 1]),
        fit: (a, b),
        fit_std,
        fit_kurtosis,
        fit_beyond_3sigma,
        per_beacon,
        samples,
    })
}

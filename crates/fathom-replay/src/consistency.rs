//! What a replay without ground truth can say about a filter: its tested scalar
//! measurements ([`Innovation`]) and the normalized innovation squared (NIS) of its
//! measurements against the chi-square distribution a consistent filter gives
//! (Bar-Shalom, Li, Kirubarajan 2001, §5.4: the time-averaged NIS of `K` independent
//! `m`-dimensional innovations times `K` is chi-square with `K m` degrees of freedom).

use fathom_estimators::schemes::{Decision, Disposition};
use fathom_stats::ChiSquareBounds;
use fathom_stats::chi2_quantile;

/// One tested scalar measurement (a range, a depth): its innovation and NIS.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Innovation {
    /// Filter time it was processed at, `t - t0`, s.
    pub time: f64,
    /// Beacon row (channel), or the number of beacons for depth.
    pub channel: usize,
    /// Row of the measurement in its file (0-based, data rows only).
    pub row: usize,
    /// The measured value, m.
    pub value: f64,
    /// `z - h(x)` at the prior, m.
    pub innovation: f64,
    /// `nu^2 / S`.
    pub nis: f64,
    /// Accepted or rejected.
    pub disposition: Disposition,
}

impl Innovation {
    /// The innovation of a decision that was tested (has a NIS and an innovation).
    pub fn of_decision(d: &Decision) -> Option<Self> {
        let (Some(nis), Some(innovation)) = (d.nis, d.innovation) else {
            return None;
        };
        Some(Innovation {
            time: d.applied_at,
            channel: d.channel,
            row: d.tag,
            value: d.value,
            innovation,
            nis,
            disposition: d.disposition,
        })
    }

    /// `sqrt(S)`, the innovation's standard deviation as the filter predicted it
    /// (`|nu| / sqrt(NIS)`), when it is determined (a non-zero, finite NIS).
    pub fn sigma(&self) -> Option<f64> {
        let s = self.innovation.abs() / self.nis.sqrt();
        (self.nis > 0.0 && s.is_finite()).then_some(s)
    }

    /// Whether the filter applied it.
    pub fn accepted(&self) -> bool {
        self.disposition == Disposition::Accepted
    }
}

/// The NIS of a set of innovations of `dof` components each.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NisSummary {
    /// Components per innovation (1 for a range, 3 for a DVL velocity).
    pub dof: usize,
    /// Number of innovations.
    pub count: usize,
    /// Mean NIS (`dof` for a consistent filter).
    pub mean: f64,
    /// Median NIS.
    pub median: f64,
    /// 95 % interval of the mean NIS of a consistent filter with `count` independent
    /// innovations.
    pub bounds: (f64, f64),
    /// Fraction of innovations whose NIS exceeds the chi-square 95 % quantile (0.05
    /// for a consistent filter).
    pub beyond_95: f64,
}

impl NisSummary {
    /// The summary of `nis` (non-finite values are ignored); `None` when there is no
    /// finite value.
    pub fn of(nis: &[f64], dof: usize) -> Option<Self> {
        let mut v: Vec<f64> = nis.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() || dof == 0 {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        let b = ChiSquareBounds::time_average(dof, n).ok()?;
        let q95 = chi2_quantile(0.95, dof as f64).ok()?;
        let beyond = v.iter().filter(|&&x| x > q95).count() as f64 / n as f64;
        Some(Self {
            dof,
            count: n,
            mean,
            median,
            bounds: (b.lo, b.hi),
            beyond_95: beyond,
        })
    }

    /// Whether the mean NIS lies inside the 95 % interval of a consistent filter.
    pub fn consistent(&self) -> bool {
        self.bounds.0 <= self.mean && self.mean <= self.bounds.1
    }

    /// `mean 1.02 (95 % interval 0.93-1.08 for 412 ranges), 5.1 % beyond the 95 %
    /// quantile`.
    pub fn describe(&self, what: &str) -> String {
        format!(
            "mean NIS {:.3} (a consistent filter: {:.3}-{:.3} for {} {what}), median {:.3}, \
             {:.1} % beyond the chi-square 95 % quantile",
            self.mean,
            self.bounds.0,
            self.bounds.1,
            self.count,
            self.median,
            100.0 * self.beyond_95
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn consistent_innovations_pass_and_scaled_ones_fail() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let nu: Vec<f64> = (0..2000).map(|_| StandardNormal.sample(&mut rng)).collect();
        let good: Vec<f64> = nu.iter().map(|x: &f64| x * x).collect();
        let s = NisSummary::of(&good, 1).unwrap();
        assert!(s.consistent(), "{s:?}");
        // 5 % beyond the 95 % quantile, within a binomial 99.9 % band for n = 2000.
        assert!((s.beyond_95 - 0.05).abs() < 0.017, "{s:?}");
        // Negative control: innovations 1.3 times larger than the filter predicts.
        let big: Vec<f64> = good.iter().map(|x| x * 1.69).collect();
        assert!(!NisSummary::of(&big, 1).unwrap().consistent());
        assert!(NisSummary::of(&[f64::NAN], 1).is_none());
        assert!(s.describe("ranges").contains("2000 ranges"));
    }
}

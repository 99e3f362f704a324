//! Summary rows from run values: the mean with the interval its metric calls for,
//! the median with its order-statistic interval, the divergence count, the unit
//! (`fathom_stats::metric_summary`), and claims judged by equivalence with a paper's
//! value (`fathom_stats::equivalence`).

use fathom_report::output::{Claim, Row, RowDivergence};
use fathom_stats::{MetricKind, MetricSummary, SummarySettings, summarize_metric};

use super::Analysis;
use crate::SimError;
use crate::statistics::StatisticsParams;

/// The `summary.json` row of `method` / `metric` for a summary over runs.
pub fn row_of_summary(method: &str, metric: &str, s: &MetricSummary) -> Row {
    let mut row = Row::new(method, metric, s.mean);
    if let Some([lo, hi]) = s.ci95 {
        row = row.with_ci95(lo, hi, s.ci_method.name());
    }
    row.median = Some(s.median);
    row.median_ci95 = s.median_ci95;
    row.divergence = s.divergence.map(|d| RowDivergence {
        threshold: d.threshold,
        runs: d.runs,
        fraction: d.fraction,
    });
    row
}

/// A claim that the reproduced `interval` equals the paper's value `paper` within
/// `tolerance`: its verdict by equivalence (`agrees` only when the whole interval
/// lies inside `[paper - tolerance, paper + tolerance]`), its band, and `detail`
/// followed by the band and the verdict.
///
/// # Errors
/// Non-finite numbers, a negative tolerance or an unordered interval.
pub fn equivalence_claim(
    id: &str,
    text: &str,
    interval: [f64; 2],
    paper: f64,
    tolerance: f64,
    detail: &str,
) -> Result<Claim, SimError> {
    let e = fathom_stats::equivalence(interval, paper, tolerance)?;
    let v = e.verdict.name();
    let detail = format!(
        "{detail}; interval [{:.4}, {:.4}] against the band [{:.4}, {:.4}]: {v}",
        interval[0], interval[1], e.band[0], e.band[1]
    );
    Ok(Claim::equivalence(id, text, v, e.band, detail))
}

impl Analysis {
    /// An empty analysis whose rows summarize runs with `statistics`.
    pub fn with_statistics(statistics: SummarySettings) -> Self {
        Self {
            statistics: Some(statistics),
            ..Self::default()
        }
    }

    /// Declares `metric` signed (a paired difference, a bias): its rows get the
    /// Student-t interval and no divergence count. Every other metric is
    /// non-negative, and a negative run value of it is an error.
    pub fn signed(&mut self, metric: impl Into<String>) {
        self.signed.insert(metric.into());
    }

    /// The kind of `metric` as declared.
    pub fn kind_of(&self, metric: &str) -> MetricKind {
        if self.signed.contains(metric) {
            MetricKind::Signed
        } else {
            MetricKind::NonNegative
        }
    }

    fn settings(&self) -> Result<SummarySettings, SimError> {
        match self.statistics {
            Some(s) => Ok(s),
            None => StatisticsParams::default().check(0, "<defaults>"),
        }
    }

    /// The summary over runs of `values` for the row `method` / `metric`, without
    /// adding a row (for claims and report text).
    ///
    /// # Errors
    /// No value, a non-finite value, or a negative value of a non-negative metric.
    pub fn summarize(
        &self,
        method: &str,
        metric: &str,
        values: &[f64],
    ) -> Result<MetricSummary, SimError> {
        let settings = self.settings()?;
        Ok(summarize_metric(
            values,
            self.kind_of(metric),
            &settings,
            method,
            metric,
        )?)
    }

    /// Adds the row `method` / `metric` summarizing the run `values` and returns it
    /// (to set the paper's number).
    ///
    /// # Errors
    /// As [`Analysis::summarize`].
    pub fn runs_row(
        &mut self,
        method: &str,
        metric: &str,
        values: &[f64],
    ) -> Result<&mut Row, SimError> {
        let s = self.summarize(method, metric, values)?;
        self.rows.push(row_of_summary(method, metric, &s));
        Ok(self.rows.last_mut().expect("a row was just pushed"))
    }

    /// Refuses a row whose interval reaches below zero unless its metric is declared
    /// signed: no interval of a non-negative metric has a negative end, whichever way
    /// the row was built.
    ///
    /// # Errors
    /// [`SimError::InvalidArgument`] naming the row.
    pub fn check_non_negative_intervals(&self) -> Result<(), SimError> {
        for r in &self.rows {
            let below = [r.ci95, r.median_ci95]
                .iter()
                .flatten()
                .any(|[lo, _]| *lo < 0.0);
            if below && self.kind_of(&r.metric) == MetricKind::NonNegative {
                return Err(SimError::invalid_argument(
                    format!("summary row `{}` / `{}`", r.method, r.metric),
                    format!(
                        "an interval of a non-negative metric reaches below zero ({:?}, {}); \
                         declare the metric signed if it can be negative",
                        r.ci95,
                        r.ci_method.as_deref().unwrap_or("no method")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Sets each row's unit from the declarations ([`Analysis::unit`]) where the row
    /// has none; the summary's check refuses a row left without one.
    pub fn fill_units(&mut self) {
        for r in &mut self.rows {
            if r.unit.is_empty()
                && let Some(u) = self.units.get(&r.metric)
            {
                r.unit.clone_from(u);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_carry_their_method_median_divergence_and_unit() {
        let mut a = Analysis::new();
        a.unit("rmse_3d", "m");
        a.unit("diff_rmse_3d", "m");
        a.signed("diff_rmse_3d");
        let mut v: Vec<f64> = (0..20).map(|i| 0.1 + 0.001 * f64::from(i)).collect();
        v.push(30.0);
        a.runs_row("GREKF", "rmse_3d", &v).unwrap().paper = Some(0.297);
        a.runs_row("A-B", "diff_rmse_3d", &[-0.1, 0.2, 0.05])
            .unwrap();
        assert!(a.runs_row("GREKF", "rmse_3d", &[-1.0, 1.0]).is_err());
        a.fill_units();
        let r = &a.rows()[0];
        assert_eq!(r.ci_method.as_deref(), Some("bootstrap-bca"));
        assert!(r.ci95.unwrap()[0] >= 0.0);
        assert_eq!(r.divergence.unwrap().runs, 1);
        assert_eq!((r.unit.as_str(), r.paper), ("m", Some(0.297)));
        assert!(r.median.unwrap() < 0.12);
        let d = &a.rows()[1];
        assert_eq!(d.ci_method.as_deref(), Some("student-t"));
        assert!(d.divergence.is_none());
        r.check().unwrap();
        a.check_non_negative_intervals().unwrap();
        // A Student-t row of a non-negative metric reaching below zero is refused.
        a.row(Row::new("T", "rmse_3d", 0.5).with_ci95(-0.1, 1.1, "student-t"));
        let e = a.check_non_negative_intervals().unwrap_err().to_string();
        assert!(e.contains("`T` / `rmse_3d`"), "{e}");
    }

    #[test]
    fn equivalence_claims_hold_only_when_they_agree() {
        let agrees = equivalence_claim("c", "t", [0.28, 0.31], 0.297, 0.05, "x").unwrap();
        assert!(agrees.holds);
        assert_eq!(agrees.verdict.as_deref(), Some("agrees"));
        // Two diverged runs widen the interval: inconclusive, never agrees.
        let wide = equivalence_claim("c", "t", [0.28, 2.9], 0.297, 0.05, "x").unwrap();
        assert!(!wide.holds);
        assert_eq!(wide.verdict.as_deref(), Some("inconclusive"));
        wide.check().unwrap();
    }

    /// From runs: 50 runs near the paper's value agree; the same runs with diverged
    /// ones added (1 to 5 runs at 5 m) never agree, whatever the count.
    #[test]
    fn diverging_runs_never_make_a_claim_agree() {
        let a = Analysis::new();
        let paper = 0.297;
        let runs: Vec<f64> = (0..50).map(|i| 0.29 + 0.0003 * f64::from(i % 30)).collect();
        let judge = |v: &[f64]| {
            let s = a.summarize("bridge/GREKF", "rmse_3d", v).unwrap();
            equivalence_claim("c", "t", s.ci95.unwrap(), paper, 0.25 * paper, "x").unwrap()
        };
        assert_eq!(judge(&runs).verdict.as_deref(), Some("agrees"));
        for k in 1..=5 {
            let mut v = runs.clone();
            v.extend(std::iter::repeat_n(5.0, k));
            let c = judge(&v);
            assert_ne!(c.verdict.as_deref(), Some("agrees"), "{k} diverged: {c:?}");
            assert!(!c.holds);
        }
    }
}

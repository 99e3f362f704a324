//! The realtime degradation study: the same runs (seed, run index) flown in lockstep
//! and in real time, the per-run errors side by side and, per metric, the mean of
//! each pacing with its BCa bootstrap interval, median and divergence count (the
//! errors are non-negative and heavy-tailed when a run diverges), and the paired
//! difference realtime - lockstep with its Student-t interval over the runs (the two
//! pacings of a run share its flight, sensors and initial error, so the pairs remove
//! that spread). See `fathom_stats::metric_summary`.

use fathom_report::output::{Row, RowDivergence, Summary, csv_string};
use fathom_stats::{MetricKind, MetricSummary, SummarySettings, summarize_metric};
use serde::Serialize;

use crate::PilsError;
use crate::report::{ErrorStats, SEED_DOC, unit};
use crate::settings::Settings;

/// One run flown both ways.
#[derive(Debug, Clone, Serialize)]
pub struct RunPair {
    /// Run index (the settings' `run` plus the pair's number).
    pub run: u64,
    /// Errors of the lockstep session.
    pub lockstep: ErrorStats,
    /// Errors of the realtime session (its solutions that arrived).
    pub realtime: ErrorStats,
    /// Whether the lockstep solutions equal the offline MAVLink-quantized run.
    pub lockstep_equal_offline: bool,
    /// Steps of the run.
    pub steps: u64,
    /// Solutions that arrived in real time.
    pub realtime_solutions: usize,
    /// Answers received in real time (solutions, and `quality = -1` answers before
    /// the navigation started; duplicates of a step each).
    pub realtime_answers: usize,
    /// Of the answers, late ones (more than one step after their step was sent).
    pub realtime_late: u64,
    /// Realtime solution latency, median and 95th percentile, ms.
    pub realtime_latency_ms: [f64; 2],
}

/// One metric over the runs.
#[derive(Debug, Clone, Serialize)]
pub struct MetricCi {
    /// Metric name (`ErrorStats::metrics`).
    pub metric: &'static str,
    /// Lockstep: mean with its bootstrap 95 % CI, median, divergence count.
    pub lockstep: MetricSummary,
    /// Realtime: as `lockstep`.
    pub realtime: MetricSummary,
    /// Paired difference realtime - lockstep: mean with its Student-t 95 % CI.
    pub difference: MetricSummary,
}

/// The study's result.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// Per run.
    pub runs: Vec<RunPair>,
    /// Per metric.
    pub metrics: Vec<MetricCi>,
    /// Late answers over all realtime answers (pooled).
    pub late_fraction: f64,
    /// Realtime solutions over steps (pooled).
    pub solution_fraction: f64,
}

impl Comparison {
    /// Aggregates the runs (at least 2, for an interval); the bootstrap draws from
    /// streams seeded by `seed` (the study's seed) and each row's key.
    ///
    /// # Errors
    /// [`PilsError::Setting`] for fewer than 2 runs; [`PilsError::Model`] when a
    /// statistic is not finite (a run without solutions).
    pub fn new(runs: Vec<RunPair>, seed: u64) -> Result<Self, PilsError> {
        if runs.len() < 2 {
            return Err(PilsError::setting(
                "runs",
                runs.len(),
                "must be >= 2 (a confidence interval needs a spread)",
            ));
        }
        let settings = SummarySettings::new(STUDY_RESAMPLES, STUDY_DIVERGENCE_FACTOR, seed)
            .map_err(|e| PilsError::model("statistics", e))?;
        let names = runs[0].lockstep.metrics().map(|(n, _)| n);
        let mut metrics = Vec::with_capacity(names.len());
        for (i, name) in names.into_iter().enumerate() {
            let l: Vec<f64> = runs.iter().map(|r| r.lockstep.metrics()[i].1).collect();
            let rt: Vec<f64> = runs.iter().map(|r| r.realtime.metrics()[i].1).collect();
            let d: Vec<f64> = rt.iter().zip(&l).map(|(a, b)| a - b).collect();
            let err = |e: fathom_stats::StatsError| PilsError::model(name, e);
            let summary = |label: &str, kind: MetricKind, v: &[f64]| {
                summarize_metric(v, kind, &settings, label, name).map_err(err)
            };
            metrics.push(MetricCi {
                metric: name,
                lockstep: summary("lockstep", MetricKind::NonNegative, &l)?,
                realtime: summary("realtime", MetricKind::NonNegative, &rt)?,
                difference: summary("realtime-lockstep", MetricKind::Signed, &d)?,
            });
        }
        let sols: usize = runs.iter().map(|r| r.realtime_solutions).sum();
        let answers: usize = runs.iter().map(|r| r.realtime_answers).sum();
        let late: u64 = runs.iter().map(|r| r.realtime_late).sum();
        let steps: u64 = runs.iter().map(|r| r.steps).sum();
        Ok(Self {
            late_fraction: late as f64 / answers.max(1) as f64,
            solution_fraction: sols as f64 / steps.max(1) as f64,
            runs,
            metrics,
        })
    }

    /// The per-run table as CSV (fathom-report's CSV writer).
    ///
    /// # Errors
    /// [`PilsError::Model`] if the CSV cannot be formatted (it is written in memory).
    pub fn runs_csv(&self) -> Result<String, PilsError> {
        let names = self.runs[0].lockstep.metrics().map(|(n, _)| n);
        let mut header: Vec<String> = [
            "run",
            "steps",
            "realtime_solutions",
            "realtime_answers",
            "realtime_late",
            "latency_p50_ms",
            "latency_p95_ms",
            "lockstep_equal_offline",
        ]
        .map(String::from)
        .to_vec();
        for p in ["lockstep", "realtime"] {
            header.extend(names.iter().map(|n| format!("{p}_{n}")));
        }
        csv_string(|w| {
            w.record(&header)?;
            for r in &self.runs {
                w.display(r.run)?;
                w.display(r.steps)?;
                w.display(r.realtime_solutions)?;
                w.display(r.realtime_answers)?;
                w.display(r.realtime_late)?;
                w.float(r.realtime_latency_ms[0])?;
                w.float(r.realtime_latency_ms[1])?;
                w.display(r.lockstep_equal_offline)?;
                for st in [&r.lockstep, &r.realtime] {
                    for (_, v) in st.metrics() {
                        w.float(v)?;
                    }
                }
                w.end_record()?;
            }
            Ok(())
        })
        .map_err(|e| PilsError::model("runs.csv", e))
    }

    /// The study's `summary.json` (the shared contract): `runs` pairs from the
    /// settings' `seed`, rows `lockstep/<method>`, `realtime/<method>` and
    /// `realtime-lockstep/<method>` (the paired difference) per metric, with their
    /// 95 % intervals.
    pub fn summary(&self, method: &str, seed: u64) -> Summary {
        let mut summary = Summary::new("pils", SEED_DOC, self.runs.len(), seed);
        for mc in &self.metrics {
            for (label, v) in [
                ("lockstep", &mc.lockstep),
                ("realtime", &mc.realtime),
                ("realtime-lockstep", &mc.difference),
            ] {
                summary.push_row(row(&format!("{label}/{method}"), mc.metric, v));
            }
        }
        summary
    }
}

/// Bootstrap resamples of the study's intervals.
pub const STUDY_RESAMPLES: usize = 2000;
/// A run diverged when its error exceeds this factor times the median.
pub const STUDY_DIVERGENCE_FACTOR: f64 = 10.0;

/// The `summary.json` row of a summary over runs.
fn row(method: &str, metric: &str, s: &MetricSummary) -> Row {
    let mut row = Row::new(method, metric, s.mean).with_unit(unit(metric));
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

impl Comparison {
    /// The study's text files (name, content): `runs.csv` ([`Comparison::runs_csv`]),
    /// `report.md` ([`Comparison::markdown`] under [`title`]), `comparison.json`
    /// (everything) and `summary.json` ([`Comparison::summary`]); `flown` names the
    /// scene and method (`bridge/GREKF`). The figures are
    /// `crate::figures::study_figures`; the caller writes both.
    ///
    /// # Errors
    /// [`PilsError::Model`] if a file cannot be formatted.
    pub fn files(
        &self,
        s: &Settings,
        flown: &str,
    ) -> Result<Vec<(&'static str, String)>, PilsError> {
        let json = serde_json::to_string_pretty(self)
            .map_err(|e| PilsError::model("comparison.json", e))?;
        let summary = self
            .summary(flown, s.seed)
            .to_json_pretty()
            .map_err(|e| PilsError::model("summary.json", e))?;
        Ok(vec![
            ("runs.csv", self.runs_csv()?),
            ("report.md", self.markdown(&title(s, flown))),
            ("comparison.json", json),
            ("summary.json", summary),
        ])
    }

    /// The report: per-run table and per-metric intervals, Markdown.
    pub fn markdown(&self, title: &str) -> String {
        let mut s = format!("# {title}\n\n## Per run\n\n");
        s += "| run | steps | realtime solutions | late answers | latency p50 / p95 (ms) | \
              rmse_3d lockstep (m) | rmse_3d realtime (m) | difference (m) |\n\
              | --- | --- | --- | --- | --- | --- | --- | --- |\n";
        for r in &self.runs {
            s += &format!(
                "| {} | {} | {} | {} | {:.1} / {:.1} | {:.3} | {:.3} | {:+.3} |\n",
                r.run,
                r.steps,
                r.realtime_solutions,
                r.realtime_late,
                r.realtime_latency_ms[0],
                r.realtime_latency_ms[1],
                r.lockstep.rmse_3d,
                r.realtime.rmse_3d,
                r.realtime.rmse_3d - r.lockstep.rmse_3d
            );
        }
        s += &format!(
            "\n## Over {} runs (mean [95 % CI]: BCa bootstrap per pacing, Student t for the \
             paired difference; median [distribution-free 95 % CI from order statistics, \
             from six runs on]; runs beyond 10x the median; for the difference, the runs \
             where realtime was worse)\n\n\
             | metric | lockstep | realtime | realtime - lockstep (paired) |\n\
             | --- | --- | --- | --- |\n",
            self.runs.len()
        );
        let fmt = |m: &MetricSummary, extra: String| {
            let [lo, hi] = m.ci95.unwrap_or([m.mean; 2]);
            let median_ci = m
                .median_ci95
                .map_or(String::new(), |[a, b]| format!(" [{a:.3}, {b:.3}]"));
            let diverged = m.divergence.map_or(String::new(), |d| {
                format!("; {} of {} diverged", d.runs, m.n)
            });
            format!(
                "{:.3} [{lo:.3}, {hi:.3}] (median {:.3}{median_ci}{diverged}{extra})",
                m.mean, m.median
            )
        };
        for (i, m) in self.metrics.iter().enumerate() {
            let worse = self
                .runs
                .iter()
                .filter(|r| r.realtime.metrics()[i].1 > r.lockstep.metrics()[i].1)
                .count();
            s += &format!(
                "| {} ({}) | {} | {} | {} |\n",
                m.metric,
                unit(m.metric),
                fmt(&m.lockstep, String::new()),
                fmt(&m.realtime, String::new()),
                fmt(
                    &m.difference,
                    format!("; worse in {worse} of {} runs", self.runs.len())
                )
            );
        }
        s += &format!(
            "\nRealtime: {:.1} % of the steps got a solution back; {:.1} % of the answers \
             arrived late (more than one 10 ms step after their step was sent).\n",
            100.0 * self.solution_fraction,
            100.0 * self.late_fraction
        );
        s
    }
}

/// The study's title: what was flown (`scene/method`) and the realtime link's faults.
pub fn title(s: &Settings, flown: &str) -> String {
    let f = &s.file.link.faults;
    format!(
        "PILS {flown}: realtime (loss {:.0} %, latency {:.0} +- {:.0} ms) vs lockstep",
        100.0 * f.loss,
        1e3 * f.latency_s,
        1e3 * f.jitter_s
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Error statistics with `rmse_3d` (and its kin) as given (test fixture).
    pub(crate) fn stats(rmse_3d: f64) -> ErrorStats {
        ErrorStats {
            samples: 10,
            rmse_h: rmse_3d,
            rmse_3d,
            rmse_vel: 0.1,
            rmse_roll: 0.1,
            rmse_pitch: 0.1,
            rmse_yaw: 1.0,
            mean_3d: rmse_3d,
            p95_3d: rmse_3d,
            time_map_aided_s: 0.0,
        }
    }

    /// A run pair with lockstep and realtime RMSEs `l`, `r` (test fixture).
    pub(crate) fn pair(run: u64, l: f64, r: f64) -> RunPair {
        RunPair {
            run,
            lockstep: stats(l),
            realtime: stats(r),
            lockstep_equal_offline: true,
            steps: 100,
            realtime_solutions: 90,
            realtime_answers: 90,
            realtime_late: 9,
            realtime_latency_ms: [20.0, 40.0],
        }
    }

    /// The paired difference is the t-interval of the per-run differences: with
    /// differences 0.1, 0.2, 0.3 the mean is 0.2 and the half width is
    /// t(0.975, 2) * 0.1 / sqrt(3) = 4.302653 * 0.057735 = 0.248414.
    #[test]
    fn paired_difference_interval() {
        let c = Comparison::new(
            vec![pair(0, 1.0, 1.1), pair(1, 2.0, 2.2), pair(2, 3.0, 3.3)],
            5,
        )
        .unwrap();
        let m = c.metrics.iter().find(|m| m.metric == "rmse_3d").unwrap();
        assert!((m.difference.mean - 0.2).abs() < 1e-12);
        let [lo, hi] = m.difference.ci95.unwrap();
        assert!((hi - 0.2 - 0.248_414).abs() < 1e-5, "{hi}");
        assert!((0.2 - lo - 0.248_414).abs() < 1e-5, "{lo}");
        // Unpaired, the spread of the runs (1, 2, 3) swamps the difference.
        let [llo, lhi] = m.lockstep.ci95.unwrap();
        assert!(lhi - llo > 2.0 * (hi - lo), "{llo} {lhi}");
        assert!((c.late_fraction - 0.1).abs() < 1e-12);
        assert!((c.solution_fraction - 0.9).abs() < 1e-12);
        let md = c.markdown("t");
        assert!(md.contains("| rmse_3d (m) | 2.000 ["), "{md}");
        assert!(md.contains("; worse in 3 of 3 runs) |"), "{md}");
        // Six runs give the order-statistic interval of the median (x_(1), x_(6)).
        let six: Vec<RunPair> = (0..6)
            .map(|i| pair(i, 1.0, 1.0 + [0.3, -0.1, 0.2, 0.4, -0.2, 0.1][i as usize]))
            .collect();
        let md6 = Comparison::new(six, 5).unwrap().markdown("t");
        let line = md6.lines().find(|l| l.starts_with("| rmse_3d")).unwrap();
        assert!(line.contains("[-0.200, 0.400]"), "{line}");
        assert!(line.contains("; worse in 4 of 6 runs) |"), "{line}");
        let csv = c.runs_csv().unwrap();
        assert_eq!(csv.lines().count(), 4);
        assert!(csv.starts_with("run,steps,realtime_solutions,"), "{csv}");
        assert!(csv.contains("\n1,100,90,90,9,20,40,true,"), "{csv}");
        let s = c.summary("MGPMF", 5);
        assert_eq!((s.runs, s.base_seed), (3, 5));
        let d = s.row("realtime-lockstep/MGPMF", "rmse_3d").unwrap();
        assert!((d.value - 0.2).abs() < 1e-12 && d.ci95.is_some());
        assert_eq!(d.ci_method.as_deref(), Some("student-t"));
        let l = s.row("lockstep/MGPMF", "rmse_3d").unwrap();
        assert_eq!(
            (l.ci_method.as_deref(), l.unit.as_str()),
            (Some("bootstrap-bca"), "m")
        );
        assert!(l.ci95.unwrap()[0] >= 0.0);
        s.check().unwrap();
    }

    #[test]
    fn one_run_or_no_solutions_is_refused() {
        assert!(Comparison::new(vec![pair(0, 1.0, 1.1)], 0).is_err());
        let mut p = pair(1, 1.0, f64::NAN);
        p.realtime.rmse_3d = f64::NAN;
        assert!(Comparison::new(vec![pair(0, 1.0, 1.1), p], 0).is_err());
    }
}

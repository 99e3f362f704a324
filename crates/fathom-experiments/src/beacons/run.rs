//! One `beacons` Monte Carlo run: the motion, the initial estimation error, and per
//! case the sensor data and the selected schemes' results (`methods`, default all three).

use fathom_estimators::schemes::ChannelCounts;
use fathom_sensors::{BeaconSuiteData, simulate_beacon_suite};
use fathom_stats::RunStats;
use fathom_traj::velocity_command::VelocityCommandMotion;
use rand_chacha::ChaCha8Rng;

use super::detail::{FigureDetail, figure_detail};
use super::filter::{SchemeRun, events, run_scheme_on};
use super::scenario::{Case, Checked};
use crate::common::generate_motion;
use fathom_sim::SimError;

/// One run: the motion and, per case, the data and the three schemes' results.
pub(super) struct RunDetail {
    pub(super) motion: VelocityCommandMotion,
    pub(super) cases: Vec<(BeaconSuiteData, Vec<SchemeRun>)>,
}

pub(super) fn simulate_run(checked: &Checked, rng: &mut ChaCha8Rng) -> Result<RunDetail, SimError> {
    simulate_cases(checked, &checked.cases, rng)
}

/// [`simulate_run`] on `cases` (the scenario's, or one beacon layout of the geometry
/// sensitivity): the same motion, initial error and noise streams for every case.
fn simulate_cases(
    checked: &Checked,
    cases_to_run: &[Case],
    rng: &mut ChaCha8Rng,
) -> Result<RunDetail, SimError> {
    let motion = generate_motion(&checked.motion, rng)?;
    // The initial error uses P0 of the first case (P0 does not depend on the case).
    let initial_error = checked.cases[0].setup.draw_initial_error(rng);
    let mut cases = Vec::with_capacity(cases_to_run.len());
    for case in cases_to_run {
        let mut case_rng = rng.clone();
        let data = simulate_beacon_suite(&motion, &case.config, &mut case_rng)
            .map_err(|e| SimError::model(format!("sensor suite, case {}", case.name), e))?;
        let ev = events(&data, &case.setup.beacons);
        let runs = checked
            .schemes
            .iter()
            .map(|&s| run_scheme_on(&motion, &data, &ev, &case.setup, s, &initial_error))
            .collect::<Result<Vec<_>, _>>()?;
        cases.push((data, runs));
    }
    Ok(RunDetail { motion, cases })
}

/// What one run contributes to the statistics, per case and scheme.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SchemeStats {
    pub(super) stats: RunStats,
    pub(super) nees_mean: f64,
    pub(super) recall: f64,
    pub(super) rejected: usize,
    pub(super) untested: usize,
    pub(super) false_rejections: usize,
    /// Clean range samples that went through the gate.
    pub(super) clean_tested: usize,
    pub(super) injected: usize,
    pub(super) counts: Vec<ChannelCounts>,
    pub(super) errors: Vec<f64>,
    /// The RTS-smoothed run (`smooth = true`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) smoothed: Option<SmoothedStats>,
}

/// A smoothed run's error statistics and time-averaged NEES.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SmoothedStats {
    pub(super) stats: RunStats,
    pub(super) nees_mean: f64,
}

pub(super) fn one_run(
    checked: &Checked,
    index: usize,
    rng: &mut ChaCha8Rng,
) -> Result<RunRecord, SimError> {
    let run = simulate_run(checked, rng)?;
    // The figure run keeps what its figures draw (the detail run).
    let figure = if index == checked.figure_run {
        Some(Box::new(figure_detail(checked, &run.motion, &run.cases)?))
    } else {
        None
    };
    Ok(RunRecord {
        stats: stats_of(run)?,
        figure,
    })
}

/// What one run returns: per case and scheme its statistics, and for the figure run
/// its figure detail.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RunRecord {
    pub(super) stats: Vec<Vec<SchemeStats>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) figure: Option<Box<FigureDetail>>,
}

/// One run of the main case under beacon layout `layout` of the geometry sensitivity.
pub(super) fn one_layout_run(
    checked: &Checked,
    layout: usize,
    rng: &mut ChaCha8Rng,
) -> Result<RunRecord, SimError> {
    let case = std::slice::from_ref(&checked.layouts[layout].case);
    Ok(RunRecord {
        stats: stats_of(simulate_cases(checked, case, rng)?)?,
        figure: None,
    })
}

/// What the analysis keeps of one scheme on one case of one run (the per-run scalars
/// of the CIs, the paired differences and the per-run CSV).
#[derive(Debug, Clone, PartialEq)]
pub struct KeptStats {
    pub(super) stats: RunStats,
    pub(super) nees_mean: f64,
    pub(super) recall: f64,
    pub(super) rejected: usize,
    pub(super) false_rejections: usize,
    /// Boxed: 8 bytes a kept run when `smooth` is off (campaign memory).
    pub(super) smoothed: Option<Box<SmoothedStats>>,
}

/// Sums over a batch's runs of one scheme on one case, in run order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SchemeSums {
    /// Runs folded.
    pub(super) runs: usize,
    /// Per evaluation instant, the sum of the 3D errors.
    pub(super) errors: Vec<f64>,
    pub(super) untested: f64,
    pub(super) injected: f64,
    pub(super) clean_tested: f64,
    /// Injected outliers that passed the gate.
    pub(super) passed: usize,
    pub(super) pooled_rejected: u64,
    pub(super) pooled_injected: u64,
    /// Per channel, the dispositions summed over runs.
    pub(super) counts: Vec<ChannelCounts>,
}

/// A batch's sums: `cases[case][scheme]`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BatchSums {
    pub(super) cases: Vec<Vec<SchemeSums>>,
    /// The figure run's detail (main batch only).
    pub(super) figure: Option<Box<FigureDetail>>,
}

/// Folds one run's record into `sums` and returns what the analysis keeps of it.
pub(super) fn fold_run(record: RunRecord, sums: &mut BatchSums) -> Vec<Vec<KeptStats>> {
    if record.figure.is_some() {
        sums.figure = record.figure;
    }
    let record = record.stats;
    if sums.cases.is_empty() {
        sums.cases = record
            .iter()
            .map(|c| vec![SchemeSums::default(); c.len()])
            .collect();
    }
    // Built with exact capacities, not collected in place: an in-place collect would
    // keep the record's larger allocation alive for every kept run.
    let mut kept = Vec::with_capacity(record.len());
    for (case, case_sums) in record.into_iter().zip(&mut sums.cases) {
        let mut kept_case = Vec::with_capacity(case.len());
        kept_case.extend(case.into_iter().zip(case_sums.iter_mut()).map(|(s, acc)| {
            if acc.runs == 0 {
                acc.errors = s.errors.clone();
                acc.counts = s.counts.clone();
            } else {
                for (a, e) in acc.errors.iter_mut().zip(&s.errors) {
                    *a += e;
                }
                for (a, c) in acc.counts.iter_mut().zip(&s.counts) {
                    *a = ChannelCounts::total(&[*a, *c]);
                }
            }
            acc.runs += 1;
            acc.untested += s.untested as f64;
            acc.injected += s.injected as f64;
            acc.clean_tested += s.clean_tested as f64;
            acc.passed += s.injected - s.rejected - s.untested;
            acc.pooled_rejected += s.rejected as u64;
            acc.pooled_injected += s.injected as u64;
            KeptStats {
                stats: s.stats,
                nees_mean: s.nees_mean,
                recall: s.recall,
                rejected: s.rejected,
                false_rejections: s.false_rejections,
                smoothed: s.smoothed.map(Box::new),
            }
        }));
        kept.push(kept_case);
    }
    kept
}

fn stats_of(detail: RunDetail) -> Result<Vec<Vec<SchemeStats>>, SimError> {
    detail
        .cases
        .into_iter()
        .map(|(_, runs)| {
            runs.into_iter()
                .map(|r| {
                    let stats = RunStats::of(&r.errors_3d)
                        .map_err(|e| SimError::model("run statistics", e))?;
                    let nees_mean = r.nees.iter().sum::<f64>() / r.nees.len().max(1) as f64;
                    let smoothed = r
                        .smoothed
                        .as_ref()
                        .map(|s| -> Result<SmoothedStats, SimError> {
                            Ok(SmoothedStats {
                                stats: RunStats::of(&s.errors_3d)
                                    .map_err(|e| SimError::model("smoothed run statistics", e))?,
                                nees_mean: s.nees.iter().sum::<f64>() / s.nees.len().max(1) as f64,
                            })
                        })
                        .transpose()?;
                    Ok(SchemeStats {
                        stats,
                        nees_mean,
                        recall: if r.outliers_injected > 0 {
                            r.outliers_rejected as f64 / r.outliers_injected as f64
                        } else {
                            f64::NAN
                        },
                        rejected: r.outliers_rejected,
                        untested: r.outliers_untested,
                        clean_tested: r.counts[..r.counts.len() - 1]
                            .iter()
                            .map(|c| c.accepted + c.rejected)
                            .sum::<usize>()
                            - r.outliers_rejected
                            - r.outliers_accepted,
                        false_rejections: r.false_rejections,
                        injected: r.outliers_injected,
                        counts: r.counts,
                        errors: r.errors_3d,
                        smoothed,
                    })
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::beacons::scenario::BeaconsScenario;
    use fathom_sim::montecarlo::run_rng;

    fn scenario_text() -> String {
        std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/beacons.toml"),
        )
        .unwrap()
    }

    #[test]
    fn preset_parses_and_checks() {
        let s: BeaconsScenario =
            fathom_sim::scenario::parse_toml(&scenario_text(), "beacons.toml").unwrap();
        let c = s.check("beacons.toml").unwrap();
        assert_eq!(c.cases.len(), 4);
        assert!(c.runs >= 100);
        assert!(c.cases.iter().any(|c| c.config.is_synchronous()));
    }

    #[test]
    fn bad_values_name_the_key() {
        let text = scenario_text().replace("gate_sigma = 2.5", "gate_sigma = -2.5");
        let s: BeaconsScenario = fathom_sim::scenario::parse_toml(&text, "beacons.toml").unwrap();
        let err = s.check("beacons.toml").unwrap_err().to_string();
        assert!(err.contains("ekf.gate_sigma"), "{err}");
        let text = scenario_text().replace("timing = \"sync\"", "timing = \"sometimes\"");
        assert!(
            fathom_sim::scenario::parse_toml::<BeaconsScenario>(&text, "beacons.toml").is_err()
        );
        let text =
            scenario_text().replace("gate_sigma = 2.5", "gate_sigma = 2.5\ngate_sigmaa = 3.0");
        let err = fathom_sim::scenario::parse_toml::<BeaconsScenario>(&text, "beacons.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("gate_sigmaa"), "{err}");
    }

    #[test]
    fn any_number_of_beacons_checks_and_runs() {
        let six = "positions = [[20.0, 0.0, 0.0], [10.0, 17.3, 40.0], [-10.0, 17.3, 0.0], \
                   [-20.0, 0.0, 40.0], [-10.0, -17.3, 0.0], [10.0, -17.3, 40.0]]";
        let preset = scenario_text();
        let line = preset
            .lines()
            .find(|l| l.starts_with("positions = "))
            .unwrap();
        for (k, positions) in [(6, six), (1, "positions = [[20.0, 0.0, 0.0]]")] {
            let text = preset
                .replace(line, positions)
                .replace("duration_s = 180.0", "duration_s = 20.0")
                .replace("outlier_count = 276", "outlier_count = 30");
            let s: BeaconsScenario = fathom_sim::scenario::parse_toml(&text, "b.toml").unwrap();
            let mut s = s;
            s.runs = 2;
            let mut c = s.check("b.toml").unwrap();
            c.cases.truncate(1);
            assert_eq!(c.cases[0].config.beacon_count(), k);
            assert_eq!(c.cases[0].setup.channel_cov.nrows(), k + 1);
            let d = simulate_run(&c, &mut run_rng(5, 0)).unwrap();
            let (data, runs) = &d.cases[0];
            assert_eq!(data.ranges.len(), k);
            for r in runs {
                assert_eq!(r.counts.len(), k + 1);
                assert!(r.errors_3d.iter().all(|e| e.is_finite()));
                assert_eq!(
                    r.outliers_rejected + r.outliers_accepted + r.outliers_untested,
                    30
                );
            }
        }
        // More outliers than range samples: a check error naming the key, not a
        // failure in the middle of the run.
        let text = preset
            .replace(line, "positions = [[20.0, 0.0, 0.0]]")
            .replace("duration_s = 180.0", "duration_s = 20.0");
        let s: BeaconsScenario = fathom_sim::scenario::parse_toml(&text, "b.toml").unwrap();
        let e = s.check("b.toml").unwrap_err().to_string();
        assert!(
            e.starts_with(
                "b.toml: key `noise.outlier_count`: 276 outliers do not fit into the 200"
            ),
            "{e}"
        );
    }

    #[test]
    fn one_run_localizes_and_catches_outliers() {
        let s: BeaconsScenario =
            fathom_sim::scenario::parse_toml(&scenario_text(), "beacons.toml").unwrap();
        let mut s = s;
        s.runs = 2;
        let mut c = s.check("beacons.toml").unwrap();
        c.cases.truncate(1);
        let mut rng = run_rng(5, 0);
        let d = simulate_run(&c, &mut rng).unwrap();
        let (data, runs) = &d.cases[0];
        assert_eq!(data.outliers.len(), 276);
        for r in runs {
            let st = RunStats::of(&r.errors_3d).unwrap();
            assert!(st.mean < 0.5, "mean error {}", st.mean);
            assert!(r.outliers_rejected > 220, "{}", r.outliers_rejected);
            assert_eq!(
                r.outliers_rejected + r.outliers_accepted + r.outliers_untested,
                276
            );
            assert_eq!(r.errors_3d.len(), 1800);
        }
    }
}

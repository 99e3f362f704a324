//! The `beacons` analysis: per case and scheme, the Monte Carlo means of the per-run
//! error statistics, outlier recall and false rejections (the rows), and the claims.

use fathom_estimators::schemes::UpdateScheme;
use fathom_stats::mean_and_ci95;

use super::paper::{PAPER_INJECTED, PAPER_TABLE13, PAPER_TABLE14};
use super::run::SchemeStats;
use super::scenario::Checked;
use super::{MAIN_CASE, figures, method, report};
use crate::SimError;
use crate::experiment::Analysis;
use crate::output::{Claim, Row, fixed as f};

/// A Monte Carlo mean and its 95 % CI.
#[derive(Debug, Clone, Copy)]
pub(super) struct Agg {
    pub(super) mean: f64,
    pub(super) ci: [f64; 2],
}

fn agg(values: &[f64]) -> Result<Agg, SimError> {
    let (mean, ci) = mean_and_ci95(values)?;
    Ok(Agg { mean, ci })
}

/// The aggregated statistics of one scheme on one case.
#[derive(Debug, Clone, Copy)]
pub(super) struct SchemeTable {
    /// Mean, std, max, RMSE of the 3D error, outlier recall, false rejections.
    pub(super) stats: [Agg; 6],
    /// Averages over runs: time-averaged NEES, outliers rejected, untested, injected.
    pub(super) nees: f64,
    pub(super) rejected: f64,
    pub(super) untested: f64,
    pub(super) injected: f64,
}

/// `table[case][scheme]`.
pub(super) type Table = Vec<Vec<SchemeTable>>;

/// Index of the main case (the check guarantees it exists).
pub(super) fn main_case(checked: &Checked) -> usize {
    checked
        .cases
        .iter()
        .position(|c| c.name == MAIN_CASE)
        .unwrap_or(0)
}

/// Computes the rows, the claims, the figures and the report.
pub(super) fn analyse(
    checked: &Checked,
    per_run: &[Vec<Vec<SchemeStats>>],
    out: &mut Analysis,
) -> Result<(), SimError> {
    let schemes = UpdateScheme::ALL;
    let mut table: Table = Vec::new();
    for (ci, case) in checked.cases.iter().enumerate() {
        let mut row_c = Vec::new();
        for (si, &scheme) in schemes.iter().enumerate() {
            let get = |g: &dyn Fn(&SchemeStats) -> f64| -> Vec<f64> {
                per_run.iter().map(|r| g(&r[ci][si])).collect()
            };
            let mean = agg(&get(&|s| s.stats.mean))?;
            let std = agg(&get(&|s| s.stats.std))?;
            let max = agg(&get(&|s| s.stats.max))?;
            let rmse = agg(&get(&|s| s.stats.rmse))?;
            let recall_vals = get(&|s| s.recall);
            let recall = if recall_vals.iter().all(|v| v.is_finite()) {
                agg(&recall_vals)?
            } else {
                Agg {
                    mean: f64::NAN,
                    ci: [f64::NAN; 2],
                }
            };
            let fr = agg(&get(&|s| s.false_rejections as f64))?;
            let main = case.name == MAIN_CASE;
            let paper13 = main
                .then(|| {
                    PAPER_TABLE13
                        .iter()
                        .find(|p| p.0 == scheme.short_name())
                        .map(|p| p.1)
                })
                .flatten();
            let paper14 = main
                .then(|| {
                    PAPER_TABLE14
                        .iter()
                        .find(|p| p.0 == scheme.short_name())
                        .map(|p| p.1 / PAPER_INJECTED)
                })
                .flatten();
            let m = method(scheme, &case.name);
            for (k, (metric, a)) in [
                ("mean", &mean),
                ("std", &std),
                ("max", &max),
                ("rmse", &rmse),
            ]
            .iter()
            .enumerate()
            {
                out.row(
                    Row::new(&m, *metric, a.mean)
                        .with_paper(paper13.map(|p| p[k]))
                        .with_ci95(a.ci[0], a.ci[1]),
                );
            }
            if recall.mean.is_finite() {
                out.row(
                    Row::new(&m, "outlier_recall", recall.mean)
                        .with_paper(paper14)
                        .with_ci95(recall.ci[0], recall.ci[1]),
                );
            }
            out.row(Row::new(&m, "false_rejections", fr.mean).with_ci95(fr.ci[0], fr.ci[1]));
            let avg =
                |g: &dyn Fn(&SchemeStats) -> f64| get(g).iter().sum::<f64>() / checked.runs as f64;
            row_c.push(SchemeTable {
                stats: [mean, std, max, rmse, recall, fr],
                nees: avg(&|s| s.nees_mean),
                rejected: avg(&|s| s.rejected as f64),
                untested: avg(&|s| s.untested as f64),
                injected: avg(&|s| s.injected as f64),
            });
        }
        table.push(row_c);
    }

    claims(checked, &table, out);
    figures::write(checked, per_run, out)?;
    report::write(checked, &table, per_run, out);
    Ok(())
}

fn claims(checked: &Checked, table: &Table, out: &mut Analysis) {
    let case_index = |name: &str| checked.cases.iter().position(|c| c.name == name);
    let main = main_case(checked);
    let best_of = |ci: usize, k: usize| -> (bool, String) {
        let v: Vec<f64> = (0..3).map(|si| table[ci][si].stats[k].mean).collect();
        let holds = v[1] < v[0] && v[1] < v[2];
        (
            holds,
            format!(
                "AS {} · SC {} · SI {} m",
                f(v[0], 4),
                f(v[1], 4),
                f(v[2], 4)
            ),
        )
    };
    let (h, d) = best_of(main, 0);
    out.claim(Claim::new(
        "sc_best_mean_high_corr",
        "with high range correlation SC has the lowest mean 3D position error",
        h,
        format!("mean error, case {MAIN_CASE}: {d}"),
    ));
    let (h, d) = best_of(main, 1);
    out.claim(Claim::new(
        "sc_best_std_high_corr",
        "with high range correlation SC has the lowest error standard deviation",
        h,
        format!("error std, case {MAIN_CASE}: {d}"),
    ));
    if let Some(low) = case_index("low") {
        let mean = |ci: usize, si: usize| table[ci][si].stats[0].mean;
        let adv = |ci: usize| mean(ci, 2) - mean(ci, 1);
        let (a_hi, a_lo) = (adv(main), adv(low));
        out.claim(Claim::new(
            "sc_advantage_shrinks_low_corr",
            "SC's advantage over SI (mean error SI - SC) is smaller with low correlation than with high",
            a_lo < a_hi,
            format!(
                "SI - SC: high {} m, low {} m (vs AS: high {} m, low {} m)",
                f(a_hi, 4),
                f(a_lo, 4),
                f(mean(main, 0) - mean(main, 1), 4),
                f(mean(low, 0) - mean(low, 1), 4)
            ),
        ));
    }
    let threshold = 264.0 / 276.0;
    let recalls: Vec<f64> = (0..3).map(|si| table[main][si].stats[4].mean).collect();
    out.claim(Claim::new(
        "outlier_recall_ge_95",
        "every scheme detects at least 95.7 % (264/276) of the injected outliers",
        recalls.iter().all(|r| *r >= threshold),
        format!(
            "recall, case {MAIN_CASE}: AS {} · SC {} · SI {} (threshold {})",
            f(recalls[0], 4),
            f(recalls[1], 4),
            f(recalls[2], 4),
            f(threshold, 4)
        ),
    ));
}

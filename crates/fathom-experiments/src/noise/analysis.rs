//! The `noise` analysis: per-entry statistics of the Monte Carlo covariances against
//! the design, the long run's convergence, the rows and the claims.

use fathom_sensors::design_covariance;
use fathom_stats::mean_interval;
use nalgebra::DMatrix;

use super::paper::paper_matrix;
use super::run::LongRun;
use super::scenario::Checked;
use fathom_report::output::{Claim, Row, fixed as f};
use fathom_sim::SimError;
use fathom_sim::experiment::{Analysis, row_of_summary};

/// Per-entry statistics over runs.
#[derive(Debug, Clone, Copy)]
pub(super) struct EntryStats {
    pub(super) mean: f64,
    pub(super) ci95: [f64; 2],
    pub(super) simultaneous: [f64; 2],
    /// 2.5 % and 97.5 % quantiles of the single-run estimates.
    pub(super) single_run: [f64; 2],
}

/// The statistics of one entry; `ci95` is the interval of its row (`summary`).
fn entry_stats(
    values: &[f64],
    summary: &fathom_stats::MetricSummary,
    simultaneous_level: f64,
) -> Result<EntryStats, SimError> {
    let sim = mean_interval(values, simultaneous_level)?;
    Ok(EntryStats {
        mean: summary.mean,
        ci95: summary.ci95.unwrap_or([summary.mean; 2]),
        simultaneous: sim.interval.unwrap_or([sim.mean, sim.mean]),
        single_run: [
            fathom_stats::quantile(values, 0.025)?,
            fathom_stats::quantile(values, 0.975)?,
        ],
    })
}

fn covers(interval: [f64; 2], x: f64) -> bool {
    interval[0] <= x && x <= interval[1]
}

/// One upper-triangle entry of one case.
#[derive(Debug, Clone)]
pub(super) struct EntryRow {
    pub(super) i: usize,
    pub(super) j: usize,
    pub(super) design: f64,
    pub(super) paper: Option<f64>,
    pub(super) stats: EntryStats,
}

/// Everything computed for one case.
pub(super) struct CaseResult {
    pub(super) mean_cov: DMatrix<f64>,
    pub(super) design: DMatrix<f64>,
    pub(super) paper: Option<[[f64; 5]; 5]>,
    /// Upper-triangle entries, row-major.
    pub(super) entries: Vec<EntryRow>,
    /// Largest spread of the 16 range-block entries within one run (correlation-only
    /// cases).
    pub(super) block_spread: Option<f64>,
    pub(super) long: LongRun,
}

/// Computes the rows and the claims, and returns the per-case results the figures
/// and the report are drawn from.
pub(super) fn analyse(
    checked: &Checked,
    long_runs: &[LongRun],
    per_run: &[Vec<DMatrix<f64>>],
    out: &mut Analysis,
) -> Result<Vec<CaseResult>, SimError> {
    let n_cases = checked.cases.len();
    // Distinct entries (upper triangle) over all cases: the family for the
    // simultaneous (Bonferroni) intervals used by the claim.
    let family = n_cases * 15;
    let simultaneous_level = 1.0 - 0.05 / family as f64;

    let mut all_sim_covered = true;
    // Entries whose per-run values are identical in every run (the range block of a
    // correlation-only case) are one event, counted once.
    let mut n_ci95_uncovered = 0usize;
    let mut n_ci95_total = 0usize;
    let mut n_entries = 0usize;
    let mut long_ok = true;
    let mut long_details = Vec::new();
    let mut paper_inside = 0usize;
    let mut paper_total = 0usize;
    let mut paper_outside: Vec<String> = Vec::new();
    let mut results = Vec::with_capacity(n_cases);

    for (ci, case) in checked.cases.iter().enumerate() {
        let design = design_covariance(&case.config);
        let paper = paper_matrix(&case.name);
        let mut mean_cov = DMatrix::<f64>::zeros(5, 5);
        let mut entries = Vec::new();
        // Distinct per-run value vectors of the upper triangle: (bits, CI missed).
        let mut groups: Vec<(Vec<u64>, bool)> = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                let values: Vec<f64> = per_run.iter().map(|covs| covs[ci][(i, j)]).collect();
                let metric = format!("cov_{}{}", i + 1, j + 1);
                // Four ranges and the depth, all in m: covariances in m². A variance
                // (diagonal) is non-negative; a covariance has either sign.
                out.unit(metric.clone(), "m²");
                if i != j {
                    out.signed(metric.clone());
                }
                let p = paper.map(|m| m[i][j]);
                let summary = out.summarize(&case.name, &metric, &values)?;
                out.row(row_of_summary(&case.name, &metric, &summary).with_paper(p));
                let st = entry_stats(&values, &summary, simultaneous_level)?;
                mean_cov[(i, j)] = st.mean;
                let d = design[(i, j)];
                if j >= i {
                    n_entries += 1;
                    let bits: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
                    let missed = !covers(st.ci95, d);
                    match groups.iter_mut().find(|g| g.0 == bits) {
                        Some(g) => g.1 |= missed,
                        None => groups.push((bits, missed)),
                    }
                    if !covers(st.simultaneous, d) {
                        all_sim_covered = false;
                    }
                    if let Some(p) = p {
                        paper_total += 1;
                        // Rounded to the paper's 4 decimals.
                        if covers([st.single_run[0] - 5e-5, st.single_run[1] + 5e-5], p) {
                            paper_inside += 1;
                        } else {
                            paper_outside.push(format!(
                                "{} cov_{}{} = {p} (single run 95 % range {}..{})",
                                case.name,
                                i + 1,
                                j + 1,
                                f(st.single_run[0], 4),
                                f(st.single_run[1], 4)
                            ));
                        }
                    }
                    entries.push(EntryRow {
                        i,
                        j,
                        design: d,
                        paper: p,
                        stats: st,
                    });
                }
            }
        }

        n_ci95_total += groups.len();
        n_ci95_uncovered += groups.iter().filter(|g| g.1).count();

        // Within one run of a correlation-only case the four ranges carry the same
        // noise, so the whole range block of that run's matrix must be one number.
        let block_spread = (!case.config.params().switches.gaussian).then(|| {
            per_run
                .iter()
                .map(|covs| {
                    let block = covs[ci].view((0, 0), (4, 4));
                    block.max() - block.min()
                })
                .fold(0.0_f64, f64::max)
        });

        let long = long_runs[ci].clone();
        out.unit("long_run_max_rel_dev", "1");
        out.row(Row::new(
            &case.name,
            "long_run_max_rel_dev",
            long.max_rel_dev,
        ));
        long_ok &= long.max_rel_dev <= checked.long_max_rel_dev;
        long_details.push(format!(
            "{} {:.2} % (worst cov_{}{})",
            case.name,
            100.0 * long.max_rel_dev,
            long.worst.0 + 1,
            long.worst.1 + 1
        ));
        results.push(CaseResult {
            mean_cov,
            design,
            paper,
            entries,
            block_spread,
            long,
        });
    }

    out.claim(Claim::new(
        "generator_cov_matches_design",
        "every entry's CI covers the design value, and the long run is within the limit of the design",
        all_sim_covered && long_ok,
        format!(
            "simultaneous {:.4} % intervals over {} entries: {}; per-entry 95 % CIs missing \
             the design: {} of {} distinct estimates ({} entries; entries equal in every run, \
             as the range block of a correlation-only case, count once; about 5 % expected by \
             chance); long run: {}",
            100.0 * simultaneous_level,
            family,
            if all_sim_covered { "all cover the design" } else { "some miss the design" },
            n_ci95_uncovered,
            n_ci95_total,
            n_entries,
            long_details.join(", ")
        ),
    ));
    if paper_total > 0 {
        out.claim(Claim::new(
            "paper_values_within_single_run_spread",
            "every printed paper entry lies within the 95 % range of a single paper-length run",
            paper_outside.is_empty(),
            format!(
                "{paper_inside} of {paper_total} printed entries inside{}",
                if paper_outside.is_empty() {
                    String::new()
                } else {
                    format!("; outside: {}", paper_outside.join("; "))
                }
            ),
        ));
    }

    Ok(results)
}

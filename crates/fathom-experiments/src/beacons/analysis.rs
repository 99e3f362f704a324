//! The `beacons` analysis: per case and scheme, the Monte Carlo means of the per-run
//! error statistics, outlier recall and false rejections (the rows), and the claims.

use fathom_estimators::schemes::UpdateScheme;
use fathom_stats::{MetricSummary, clopper_pearson};

use super::paper::{PAPER_INJECTED, PAPER_TABLE13, PAPER_TABLE14};
use super::run::{BatchSums, KeptStats};
use super::scenario::Checked;
use super::{MAIN_CASE, method};
use fathom_report::output::{Claim, Row, fixed as f};
use fathom_sim::SimError;
use fathom_sim::experiment::{Analysis, row_of_summary};

/// A Monte Carlo mean and its 95 % CI, with the whole summary of its row.
#[derive(Debug, Clone, Copy)]
pub(super) struct Agg {
    pub(super) mean: f64,
    pub(super) ci: [f64; 2],
    summary: Option<MetricSummary>,
}

/// The summary of the row `m` / `metric` over the run `values`.
fn agg(out: &Analysis, m: &str, metric: &str, values: &[f64]) -> Result<Agg, SimError> {
    let s = out.summarize(m, metric, values)?;
    Ok(Agg {
        mean: s.mean,
        ci: s.ci95.unwrap_or([s.mean; 2]),
        summary: Some(s),
    })
}

impl Agg {
    /// The row of `m` / `metric` (a value without runs has no interval).
    fn row(&self, m: &str, metric: &str) -> Row {
        self.summary.map_or_else(
            || Row::new(m, metric, self.mean),
            |s| row_of_summary(m, metric, &s),
        )
    }
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
    /// Injected outliers rejected, pooled over runs, with the 95 % Clopper-Pearson
    /// interval (`None` without outliers).
    pub(super) pooled_recall: Option<fathom_stats::Proportion>,
}

/// `table[case][scheme]`.
pub(super) type Table = Vec<Vec<SchemeTable>>;

/// The aggregated statistics of scheme `si` on case `ci` of `per_run`, the rows'
/// method name being `m`.
fn aggregate(
    out: &Analysis,
    m: &str,
    per_run: &[Vec<Vec<KeptStats>>],
    sums: &BatchSums,
    ci: usize,
    si: usize,
) -> Result<SchemeTable, SimError> {
    let get = |g: &dyn Fn(&KeptStats) -> f64| -> Vec<f64> {
        per_run.iter().map(|r| g(&r[ci][si])).collect()
    };
    let recall_vals = get(&|s| s.recall);
    let recall = if recall_vals.iter().all(|v| v.is_finite()) {
        agg(out, m, "outlier_recall", &recall_vals)?
    } else {
        Agg {
            mean: f64::NAN,
            ci: [f64::NAN; 2],
            summary: None,
        }
    };
    let avg = |g: &dyn Fn(&KeptStats) -> f64| get(g).iter().sum::<f64>() / per_run.len() as f64;
    let acc = &sums.cases[ci][si];
    let n = per_run.len() as f64;
    let (pooled_rejected, pooled_injected) = (acc.pooled_rejected, acc.pooled_injected);
    Ok(SchemeTable {
        stats: [
            agg(out, m, "mean", &get(&|s| s.stats.mean))?,
            agg(out, m, "std", &get(&|s| s.stats.std))?,
            agg(out, m, "max", &get(&|s| s.stats.max))?,
            agg(out, m, "rmse", &get(&|s| s.stats.rmse))?,
            recall,
            agg(
                out,
                m,
                "false_rejections",
                &get(&|s| s.false_rejections as f64),
            )?,
        ],
        nees: avg(&|s| s.nees_mean),
        rejected: avg(&|s| s.rejected as f64),
        untested: acc.untested / n,
        injected: acc.injected / n,
        pooled_recall: (pooled_injected > 0)
            .then(|| clopper_pearson(pooled_rejected, pooled_injected, 0.95))
            .transpose()?,
    })
}

/// Paper Table 13 (`[mean, std, max, rmse]`) and Table 14 (recall) of a scheme.
fn paper_of(scheme: UpdateScheme) -> (Option<[f64; 4]>, Option<f64>) {
    (
        PAPER_TABLE13
            .iter()
            .find(|p| p.0 == scheme.short_name())
            .map(|p| p.1),
        PAPER_TABLE14
            .iter()
            .find(|p| p.0 == scheme.short_name())
            .map(|p| p.1 / PAPER_INJECTED),
    )
}

/// Pushes the rows of one scheme's aggregated statistics under method name `m`.
fn push_rows(out: &mut Analysis, m: &str, t: &SchemeTable, paper: (Option<[f64; 4]>, Option<f64>)) {
    let [mean, std, max, rmse, recall, fr] = &t.stats;
    // 3D position error, m; recall a fraction; false rejections per run.
    for metric in ["mean", "std", "max", "rmse"] {
        out.unit(metric, "m");
    }
    out.unit("outlier_recall", "1");
    out.unit("false_rejections", "count/run");
    for (k, (metric, a)) in [("mean", mean), ("std", std), ("max", max), ("rmse", rmse)]
        .iter()
        .enumerate()
    {
        out.row(a.row(m, metric).with_paper(paper.0.map(|p| p[k])));
    }
    if recall.mean.is_finite() {
        out.row(recall.row(m, "outlier_recall").with_paper(paper.1));
    }
    out.row(fr.row(m, "false_rejections"));
}

/// What the figures and the report are drawn from, besides the runs.
pub(super) struct Analysed {
    /// Per case and scheme, the aggregated statistics.
    pub(super) table: Table,
    /// Per geometry layout and scheme (main case).
    pub(super) layout_tables: Table,
    /// The report section of the RTS-smoothed rows (empty without `smooth`).
    pub(super) smoothed_md: String,
    /// Every update scheme ran (the claims and the full report need all three).
    pub(super) all_schemes: bool,
}

/// Computes the rows and the claims; `layouts[k]` holds the runs of layout `k` of the
/// geometry sensitivity (main case only).
pub(super) fn analyse(
    checked: &Checked,
    per_run: &[Vec<Vec<KeptStats>>],
    sums: &BatchSums,
    layouts: &[(&[Vec<Vec<KeptStats>>], &BatchSums)],
    out: &mut Analysis,
) -> Result<Analysed, SimError> {
    let schemes = &checked.schemes;
    let mut table: Table = Vec::new();
    for (ci, case) in checked.cases.iter().enumerate() {
        let mut row_c = Vec::new();
        for (si, &scheme) in schemes.iter().enumerate() {
            let m = method(scheme, &case.name);
            let t = aggregate(out, &m, per_run, sums, ci, si)?;
            let paper = if case.name == MAIN_CASE {
                paper_of(scheme)
            } else {
                (None, None)
            };
            push_rows(out, &m, &t, paper);
            row_c.push(t);
        }
        table.push(row_c);
    }
    // The geometry sensitivity: the main case under further beacon layouts.
    let mut layout_tables = Vec::with_capacity(layouts.len());
    for (layout, (runs, layout_sums)) in checked.layouts.iter().zip(layouts) {
        let mut row = Vec::new();
        for (si, &scheme) in schemes.iter().enumerate() {
            let m = format!("{}@{}", method(scheme, MAIN_CASE), layout.name);
            let t = aggregate(out, &m, runs, layout_sums, 0, si)?;
            push_rows(out, &m, &t, paper_of(scheme));
            row.push(t);
        }
        layout_tables.push(row);
    }

    let smoothed_md = if checked.smooth {
        smoothed_rows(checked, per_run, out)?
    } else {
        String::new()
    };
    let all_schemes = checked.schemes.len() == UpdateScheme::ALL.len();
    if all_schemes {
        claims(checked, &table, per_run, out)?;
    }
    Ok(Analysed {
        table,
        layout_tables,
        smoothed_md,
        all_schemes,
    })
}

/// Method name of a smoothed scheme on a case (`SC+RTS/high`).
pub(super) fn smoothed_method(scheme: UpdateScheme, case: &str) -> String {
    format!("{}+RTS/{case}", scheme.short_name())
}

/// `smooth = true`: per case and scheme, the RTS-smoothed error statistics and NEES
/// with their 95 % CIs over runs (rows), the paired claim on the main case, and the
/// report section (returned).
fn smoothed_rows(
    checked: &Checked,
    per_run: &[Vec<Vec<KeptStats>>],
    out: &mut Analysis,
) -> Result<String, SimError> {
    let mut table = Vec::new();
    out.unit("nees", "1");
    for (ci, case) in checked.cases.iter().enumerate() {
        for (si, &scheme) in checked.schemes.iter().enumerate() {
            let sm: Vec<_> = per_run
                .iter()
                .map(|r| r[ci][si].smoothed.as_deref().copied())
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| {
                    SimError::invalid_argument("beacons smooth", "a run has no smoothed record")
                })?;
            let m = smoothed_method(scheme, &case.name);
            let metrics: [(&str, Vec<f64>); 5] = [
                ("mean", sm.iter().map(|s| s.stats.mean).collect()),
                ("std", sm.iter().map(|s| s.stats.std).collect()),
                ("max", sm.iter().map(|s| s.stats.max).collect()),
                ("rmse", sm.iter().map(|s| s.stats.rmse).collect()),
                ("nees", sm.iter().map(|s| s.nees_mean).collect()),
            ];
            let mut aggs = Vec::with_capacity(metrics.len());
            for (metric, v) in &metrics {
                let a = agg(out, &m, metric, v)?;
                out.row(a.row(&m, metric));
                aggs.push(a);
            }
            // Paired: smoothed minus filtered mean error, per run.
            let filtered: Vec<f64> = per_run.iter().map(|r| r[ci][si].stats.mean).collect();
            let d = fathom_stats::paired_mean_ci(&metrics[0].1, &filtered)?;
            let filtered_mean = filtered.iter().sum::<f64>() / filtered.len() as f64;
            table.push((ci, scheme, m, aggs, filtered_mean, d.mean, d.bounds()));
        }
    }
    let main = checked.main_case();
    let on_main: Vec<_> = table.iter().filter(|t| t.0 == main).collect();
    out.claim(Claim::new(
        "smoothing_lowers_mean_error",
        "the RTS smoother lowers every scheme's mean 3D error on the main case",
        on_main.iter().all(|t| t.6[1] < 0.0),
        on_main
            .iter()
            .map(|t| {
                format!(
                    "{} {} m vs filtered {} m, difference {:+.4} [{:+.4}, {:+.4}]",
                    t.2,
                    f(t.3[0].mean, 4),
                    f(t.4, 4),
                    t.5,
                    t.6[0],
                    t.6[1]
                )
            })
            .collect::<Vec<_>>()
            .join(" · ")
            + " (paired 95 % CIs over runs; holds when every upper bound lies below 0)",
    ));
    let rows: Vec<Vec<String>> = table
        .iter()
        .map(|(_, _, m, a, filtered, d, c)| {
            let ci = |a: &Agg| format!("{} [{}, {}]", f(a.mean, 4), f(a.ci[0], 4), f(a.ci[1], 4));
            vec![
                m.clone(),
                f(*filtered, 4),
                ci(&a[0]),
                ci(&a[2]),
                ci(&a[3]),
                format!("{:+.4} [{:+.4}, {:+.4}]", d, c[0], c[1]),
                ci(&a[4]),
            ]
        })
        .collect();
    let mut md = String::from(
        "\n### Post-processing: RTS smoother (`smooth = true`)\n\nEach scheme's forward pass \
         (transition Jacobian, predicted and filtered moments per step) is smoothed backwards \
         by the fixed-interval Rauch-Tung-Striebel smoother (`fathom_estimators::smoother`), \
         with the filter's settings; gated-out ranges stay out. Means over runs with 95 % \
         CIs; the difference to the filter is paired per run. The smoothed NEES has 4 \
         degrees of freedom (expected 4 for a consistent smoother).\n\n",
    );
    md.push_str(&fathom_report::output::md_table(
        &[
            "smoothed",
            "filtered mean [m]",
            "mean [m]",
            "max [m]",
            "RMSE [m]",
            "smoothed - filtered mean [m]",
            "NEES",
        ],
        &rows,
    ));
    Ok(md)
}

/// Paired 95 % CI of scheme `a` minus scheme `b` on case `ci`, statistic `g`.
fn paired(
    per_run: &[Vec<Vec<KeptStats>>],
    ci: usize,
    a: usize,
    b: usize,
    g: fn(&KeptStats) -> f64,
) -> Result<(f64, [f64; 2]), SimError> {
    let va: Vec<f64> = per_run.iter().map(|r| g(&r[ci][a])).collect();
    let vb: Vec<f64> = per_run.iter().map(|r| g(&r[ci][b])).collect();
    let d = fathom_stats::paired_mean_ci(&va, &vb)?;
    Ok((d.mean, d.bounds()))
}

fn claims(
    checked: &Checked,
    table: &Table,
    per_run: &[Vec<Vec<KeptStats>>],
    out: &mut Analysis,
) -> Result<(), SimError> {
    let case_index = |name: &str| checked.cases.iter().position(|c| c.name == name);
    let main = checked.main_case();
    // "SC is best": the paired 95 % CIs of SC - AS and SC - SI both below zero.
    let best = |k: usize, g: fn(&KeptStats) -> f64| -> Result<(bool, String), SimError> {
        let v: Vec<f64> = (0..3).map(|si| table[main][si].stats[k].mean).collect();
        let (d_as, c_as) = paired(per_run, main, 1, 0, g)?;
        let (d_si, c_si) = paired(per_run, main, 1, 2, g)?;
        Ok((
            c_as[1] < 0.0 && c_si[1] < 0.0,
            format!(
                "AS {} · SC {} · SI {} m; SC - AS {:+.4} [{:+.4}, {:+.4}], SC - SI {:+.4} \
                 [{:+.4}, {:+.4}] (paired 95 % CIs; holds when both lie below 0)",
                f(v[0], 4),
                f(v[1], 4),
                f(v[2], 4),
                d_as,
                c_as[0],
                c_as[1],
                d_si,
                c_si[0],
                c_si[1]
            ),
        ))
    };
    let (h, d) = best(0, |s| s.stats.mean)?;
    out.claim(Claim::new(
        "sc_best_mean_high_corr",
        "the paper's text: with high range correlation SC has the lowest mean 3D position error (its own Table 13 has AS lower)",
        h,
        format!("mean error, case {MAIN_CASE}: {d}"),
    ));
    let (h, d) = best(1, |s| s.stats.std)?;
    out.claim(Claim::new(
        "sc_best_std_high_corr",
        "with high range correlation SC has the lowest error standard deviation",
        h,
        format!("error std, case {MAIN_CASE}: {d}"),
    ));
    if let Some(low) = case_index("low") {
        // Per run: (SI - SC) with high correlation minus (SI - SC) with low.
        let adv = |r: &Vec<Vec<KeptStats>>, ci: usize| r[ci][2].stats.mean - r[ci][1].stats.mean;
        let shrink: Vec<f64> = per_run.iter().map(|r| adv(r, main) - adv(r, low)).collect();
        let (d, c) = fathom_stats::mean_and_ci95(&shrink)?;
        out.claim(Claim::new(
            "sc_advantage_shrinks_low_corr",
            "SC's advantage over SI (mean error SI - SC) is smaller with low correlation than with high",
            c[0] > 0.0,
            format!(
                "(SI - SC) high minus (SI - SC) low: {:+.4} m, paired 95 % CI [{:+.4}, {:+.4}] \
                 (holds when above 0); SI - SC: high {} m, low {} m",
                d,
                c[0],
                c[1],
                f(table[main][2].stats[0].mean - table[main][1].stats[0].mean, 4),
                f(table[low][2].stats[0].mean - table[low][1].stats[0].mean, 4),
            ),
        ));
    }
    // Recall pooled over runs, Clopper-Pearson 95 % intervals.
    let threshold = 264.0 / 276.0;
    let pooled: Vec<_> = (0..3).map(|si| table[main][si].pooled_recall).collect();
    let describe = |si: usize| -> String {
        pooled[si].map_or("no outliers".to_string(), |p| {
            format!(
                "{} {}/{} = {} [{}, {}]",
                UpdateScheme::ALL[si].short_name(),
                p.k,
                p.n,
                f(p.value, 4),
                f(p.interval[0], 4),
                f(p.interval[1], 4)
            )
        })
    };
    out.claim(Claim::new(
        "outlier_recall_ge_95",
        "every scheme detects at least 95.7 % (264/276) of the injected outliers",
        pooled
            .iter()
            .all(|p| p.is_some_and(|p| p.interval[0] >= threshold)),
        format!(
            "case {MAIN_CASE}, pooled over runs with 95 % Clopper-Pearson intervals: {}; holds \
             when every lower bound is at least {}",
            (0..3).map(describe).collect::<Vec<_>>().join(" · "),
            f(threshold, 4)
        ),
    ));
    for (si, scheme) in UpdateScheme::ALL.iter().enumerate() {
        let (_, paper) = paper_of(*scheme);
        let (Some(p), Some(paper)) = (pooled[si], paper) else {
            continue;
        };
        let name = scheme.short_name();
        out.claim(Claim::new(
            format!("outlier_recall_matches_paper_{}", name.to_lowercase()),
            format!(
                "{name} detects the share of injected outliers the paper reports ({}/{})",
                f(paper * PAPER_INJECTED, 0),
                f(PAPER_INJECTED, 0)
            ),
            p.interval[0] <= paper && paper <= p.interval[1],
            format!(
                "{}; holds when the paper's {} lies inside the interval",
                describe(si),
                f(paper, 4)
            ),
        ));
    }
    Ok(())
}

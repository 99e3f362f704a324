//! The `noise` figures (heat maps of the mean, design and printed covariances, the
//! long run's convergence, the sample-time diagram) and the per-run CSV file.

use nalgebra::DMatrix;

use super::LABELS;
use super::analysis::CaseResult;
use super::run::SAMPLE_WINDOW;
use super::scenario::Checked;
use fathom_report::plot::{HeatMap, LinePlot, Series, Timeline};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

fn labels() -> Vec<String> {
    LABELS.iter().map(|s| (*s).to_owned()).collect()
}

fn matrix_rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|r| (0..m.ncols()).map(|c| m[(r, c)]).collect())
        .collect()
}

fn heat_map(title: String, rows: Vec<Vec<f64>>) -> HeatMap {
    let mut hm = HeatMap::new(title, labels(), labels(), rows);
    hm.decimals = 4;
    hm.value_label = "m²".into();
    hm
}

/// Adds every figure and the CSV file to `out`.
pub(super) fn write(
    checked: &Checked,
    per_run: &[Vec<DMatrix<f64>>],
    results: &[CaseResult],
    sample_rows: Option<&[(String, Vec<f64>)]>,
    out: &mut Analysis,
) -> Result<(), SimError> {
    let mut convergence_series = Vec::new();
    let mut csv_cols: Vec<Vec<f64>> = Vec::new();
    let mut csv_headers: Vec<String> = Vec::new();
    for (ci, (case, r)) in checked.cases.iter().zip(results).enumerate() {
        convergence_series.push(Series::new(case.name.clone(), r.long.convergence.clone()));
        out.figure(
            &format!("cov_{}.svg", case.name),
            &heat_map(
                format!(
                    "noise covariance, case {} (mean of {} runs, m²)",
                    case.name, checked.runs
                ),
                matrix_rows(&r.mean_cov),
            ),
        )?;
        out.figure(
            &format!("cov_{}_design.svg", case.name),
            &heat_map(
                format!("design covariance, case {} (m²)", case.name),
                matrix_rows(&r.design),
            ),
        )?;
        if let Some(p) = r.paper {
            out.figure(
                &format!("cov_{}_paper.svg", case.name),
                &heat_map(
                    format!("paper's printed covariance, case {} (m²)", case.name),
                    p.iter().map(|row| row.to_vec()).collect(),
                ),
            )?;
        }
        // CSV: per-run values of the diagonal and of cov_12.
        for (i, j) in [(0, 0), (1, 1), (2, 2), (3, 3), (4, 4), (0, 1)] {
            csv_headers.push(format!("{}_cov_{}{}_m2", case.name, i + 1, j + 1));
            csv_cols.push(per_run.iter().map(|covs| covs[ci][(i, j)]).collect());
        }
    }

    let mut conv = LinePlot::new(
        "convergence of the long run to the design",
        "run length (s)",
        "max relative deviation from design",
    );
    conv.series = convergence_series;
    conv.series.push(Series::new(
        "limit",
        vec![
            (checked.motion.duration, checked.long_max_rel_dev),
            (checked.long_motion.duration, checked.long_max_rel_dev),
        ],
    ));
    out.figure("convergence.svg", &conv)?;
    if let Some(rows) = sample_rows {
        out.figure("sample_times.svg", &sample_time_diagram(rows))?;
    }

    let run_col: Vec<f64> = (0..checked.runs).map(|r| r as f64).collect();
    let mut headers = vec!["run"];
    headers.extend(csv_headers.iter().map(String::as_str));
    let mut cols: Vec<&[f64]> = vec![&run_col];
    cols.extend(csv_cols.iter().map(Vec::as_slice));
    out.csv_columns("per_run_covariance.csv", &headers, &cols)
}

/// The sample-time diagram: synchronous vs asynchronous clocks over one second, from
/// the clocks drawn when the experiment was prepared.
fn sample_time_diagram(rows: &[(String, Vec<f64>)]) -> Timeline {
    Timeline::new(
        "sensor sample times: synchronous vs asynchronous (Table 3)",
        "time (s)",
        rows.to_vec(),
        Some(SAMPLE_WINDOW),
    )
}

//! The `fusion` analysis of a run of some of the methods (`methods = [...]`): per
//! selected method the metrics over runs with 95 % CIs (the rows, with the paper's
//! values where it has them), the mean 2D and 3D error versus time, and a report that
//! says what was left out (the claims, the other `v_DVL` reading and the sensitivity
//! sweeps, which compare the methods).

use super::Prepared;
use super::analysis::{METRICS, RunResult, UNITS, paper_values, values};
use super::figures::mean_series;
use super::sim::Method;
use fathom_report::output::{fixed as f, md_table};
use fathom_report::plot::{LinePlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// Rows, figures, CSV and report of the main batch of a subset run.
pub(super) fn analyse(
    p: &Prepared,
    mut records: Vec<Vec<RunResult>>,
    out: &mut Analysis,
) -> Result<(), SimError> {
    let setup = &p.setup;
    let results = records.first_mut().map(std::mem::take).unwrap_or_default();
    for (metric, unit) in UNITS {
        out.unit(metric, unit);
    }
    let mut table = Vec::new();
    for &m in &setup.methods {
        let paper = paper_values(m);
        let mut cells = vec![m.name().to_string()];
        for (k, metric) in METRICS.iter().enumerate() {
            let row = out.runs_row(m.name(), metric, &values(&results, m, metric))?;
            row.paper = paper.and_then(|p| p.get(k).copied());
            let [lo, hi] = row.ci95.unwrap_or([row.value; 2]);
            cells.push(format!("{} [{}, {}]", f(row.value, 3), f(lo, 3), f(hi, 3)));
        }
        table.push(cells);
    }
    if setup.methods.contains(&Method::Eff) {
        // The INS integrator under EFF feedback, as in the full analysis.
        let per_run = |g: fn(&[f64]) -> f64| -> Vec<f64> {
            results
                .iter()
                .map(|r| g(&r.output.ins_err_with_feedback))
                .collect()
        };
        out.runs_row(
            "EFF",
            "ins_integrator_mean_err",
            &per_run(|s| s.iter().sum::<f64>() / s.len().max(1) as f64),
        )?;
        out.runs_row(
            "EFF",
            "ins_integrator_max_err",
            &per_run(|s| s.iter().copied().fold(0.0, f64::max)),
        )?;
    }
    out.extra(
        "course_changes_s",
        serde_json::json!(p.mission.course_changes()),
    );

    // Mean error versus time of the selected methods, and its CSV.
    let times: Vec<f64> = (1..=setup.run.n_steps)
        .map(|k| k as f64 * setup.run.step)
        .collect();
    let mut headers = vec!["time_s".to_string()];
    let mut cols = vec![times.clone()];
    for (dim, title) in [(2, "2D (x-y)"), (3, "3D")] {
        let mut plot = LinePlot::new(
            format!("{title} distance error, mean of {} runs", results.len()),
            "time (s)",
            format!("{dim}D error (m)"),
        );
        for &m in &setup.methods {
            let i = m.index();
            let mean = if dim == 2 {
                mean_series(&results, |r| &r.output.err_2d[i])
            } else {
                mean_series(&results, |r| &r.output.err_3d[i])
            };
            plot.series.push(Series::from_xy(m.name(), &times, &mean)?);
            headers.push(format!("{}_mean_err{dim}d_m", m.slug()));
            cols.push(mean);
        }
        plot.markers_x = p.mission.course_changes().to_vec();
        plot.markers_label = "course change".into();
        out.figure(&format!("err{dim}d_selected.svg"), &plot)?;
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.csv_owned_columns("error_series.csv", &h, cols)?;

    let names: Vec<&str> = setup.methods.iter().map(|m| m.name()).collect();
    let mut s = format!(
        "### Selected methods: {}\n\n`methods` selects {} of the {} methods, so only the \
         main batch ran ({} runs, tuning reading `{}`). The paper's claims (EFF against MF \
         and T2T), the other `v_DVL` reading and the sensitivity sweeps compare the \
         methods and are left out. Means over runs with 95 % CIs:\n\n",
        names.join(", "),
        names.len(),
        Method::ALL.len(),
        setup.runs,
        setup.run.tuning.reading.name()
    );
    s.push_str(&md_table(
        &[
            "method",
            "mean 3D (m)",
            "std 3D (m)",
            "mean 2D (m)",
            "std 2D (m)",
            "turn ratio 3D",
        ],
        &table,
    ));
    out.report(&s);
    Ok(())
}

//! The `vkf` analysis of a run of some of the methods (`methods = [...]`): per
//! selected method the horizontal-error metrics over runs with 95 % CIs, the mean
//! horizontal error versus time with its CI band, and a report that says what was
//! left out (the claims, the literal-bias batch and the smoothed rows, which compare
//! or need the methods together).

use fathom_stats::median_ci;

use super::Prepared;
use super::analysis::{METHOD_UNITS, mean_series, metrics};
use super::figures::shade;
use super::sim::{METHODS, RunOutput};
use fathom_report::output::{Row, fixed as f, md_table};
use fathom_report::plot::{LinePlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// Rows, figure, CSV and report of the main batch of a subset run.
pub(super) fn analyse(
    p: &Prepared,
    runs: &[RunOutput],
    out: &mut Analysis,
) -> Result<(), SimError> {
    let c = &p.c;
    for (metric, unit) in METHOD_UNITS {
        out.unit(metric, unit);
    }
    let mut table = Vec::new();
    for &m in &c.methods {
        let name = METHODS[m];
        let mm = metrics(runs, m);
        let mut cells = vec![name.to_string()];
        for (metric, values) in [
            ("final_h", &mm.final_h),
            ("rms_h", &mm.rms_h),
            ("rms_vel", &mm.rms_vel),
        ] {
            let row = out.runs_row(name, metric, values)?;
            let (mean, [lo, hi]) = (row.value, row.ci95.unwrap_or([row.value; 2]));
            cells.push(format!("{} [{}, {}]", f(mean, 2), f(lo, 2), f(hi, 2)));
        }
        let med = median_ci(&mm.final_h, 0.95)?;
        let mut row = Row::new(name, "final_h_median", med.median);
        if let Some([lo, hi]) = med.interval {
            row = row.with_ci95(lo, hi, "order-statistic");
        }
        out.row(row);
        cells.push(med.interval.map_or_else(
            || format!("{} (too few runs for an interval)", f(med.median, 2)),
            |[lo, hi]| format!("{} [{}, {}]", f(med.median, 2), f(lo, 2), f(hi, 2)),
        ));
        let beyond = mm
            .final_h
            .iter()
            .filter(|&&v| v > c.final_h_threshold)
            .count();
        out.row(Row::new(
            name,
            "runs_final_h_beyond_threshold",
            beyond as f64,
        ));
        cells.push(format!("{beyond} of {}", runs.len()));
        table.push(cells);
    }

    // Mean horizontal error versus time of the selected methods, its CI band, and CSV.
    let Some(first) = runs.first() else {
        return Err(SimError::invalid_argument("vkf", "no run to analyse"));
    };
    let n = first.err_h[c.methods[0]].len();
    let tt: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let mut plot = LinePlot::new(
        format!("horizontal error, mean of {} runs", runs.len()),
        "time (s)",
        "horizontal error (m)",
    );
    let mut headers = vec!["time_s".to_string()];
    let mut cols = vec![tt.clone()];
    for (i, &m) in c.methods.iter().enumerate() {
        let per_run: Vec<&[f64]> = runs.iter().map(|r| r.err_h[m].as_slice()).collect();
        let (_, band) = fathom_stats::mean_curve_ci95(&tt, &per_run)?;
        let mean = mean_series(runs, m);
        plot = plot
            .with_series(Series::from_xy(METHODS[m], &tt, &mean)?)
            .with_band(i, band);
        headers.push(format!(
            "{}_mean_err_h_m",
            METHODS[m].to_lowercase().replace('-', "_")
        ));
        cols.push(mean);
    }
    out.figure(
        "horizontal_error_selected.svg",
        &shade(plot, &p.shared.invalid),
    )?;
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.csv_owned_columns("mean_horizontal_error.csv", &h, cols)?;

    let names: Vec<&str> = c.methods.iter().map(|&m| METHODS[m]).collect();
    let mut s = format!(
        "### Selected methods: {}\n\n`methods` selects {} of the {} methods, so only the \
         main batch ran ({} runs). The paper's claims, the literal-bias batch and the \
         smoothed rows compare or need the methods together and are left out. The figure \
         `horizontal_error_selected.svg` shades the DVL-invalid intervals. Means over runs \
         with 95 % CIs; the median with its order-statistics interval; runs whose final \
         horizontal error exceeds {} m:\n\n",
        names.join(", "),
        names.len(),
        METHODS.len(),
        runs.len(),
        c.final_h_threshold
    );
    s.push_str(&md_table(
        &[
            "method",
            "final_h (m)",
            "rms_h (m)",
            "rms_vel (m/s)",
            "final_h median (m)",
            "runs beyond",
        ],
        &table,
    ));
    out.report(&s);
    Ok(())
}

//! Figures (SVG) and per-time series (CSV) of the `fusion` experiment.

use fathom_traj::{FusionMission, Trajectory};

use super::analysis::{RunResult, SWEEP_METHODS, SweepResult};
use super::scenario::FusionSetup;
use super::sim::{Method, Reading};
use fathom_report::output::CsvCell;
use fathom_report::plot::{Histogram, LinePlot, PlanPlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// The filters (methods that have a path and an error figure of their own).
pub(super) const FILTERS: [Method; 7] = [
    Method::Mf,
    Method::T2t,
    Method::Eff,
    Method::EffNoFeedback,
    Method::EffNoEqualization,
    Method::T2tBc,
    Method::T2tCi,
];

/// Mean over runs of a per-time series, summed in run order (deterministic).
pub(super) fn mean_series(results: &[RunResult], get: impl Fn(&RunResult) -> &[f64]) -> Vec<f64> {
    let n = results.first().map_or(0, |r| get(r).len());
    let mut acc = vec![0.0; n];
    for r in results {
        for (a, v) in acc.iter_mut().zip(get(r)) {
            *a += v;
        }
    }
    let k = results.len().max(1) as f64;
    acc.iter().map(|a| a / k).collect()
}

fn xy(times: &[f64], ys: &[f64]) -> Vec<(f64, f64)> {
    times.iter().copied().zip(ys.iter().copied()).collect()
}

/// Writes every figure and CSV file.
pub(super) fn write_all(
    out: &mut Analysis,
    setup: &FusionSetup,
    mission: &FusionMission,
    results: &[RunResult],
    run0: &RunResult,
    sweeps: &[&SweepResult],
) -> Result<(), SimError> {
    let times = &run0.output.times;
    let cc = mission.course_changes();
    let (zc, zh) = setup.zoom;
    let hw = setup.turn_half_window;
    let traj = mission.trajectory();

    // --- Fig. 6: the mission -------------------------------------------------
    let mut truth_t = vec![traj.start_time()];
    truth_t.extend_from_slice(times);
    let mut truth_plan = Vec::with_capacity(truth_t.len());
    let mut depth = Vec::with_capacity(truth_t.len());
    for &t in &truth_t {
        let p = traj
            .state_at(t)
            .map_err(|e| SimError::model("truth for figures", e))?
            .pos_in_nav;
        truth_plan.push((p.y, p.x));
        depth.push((t, p.z));
    }
    let mut cc_pts = Vec::new();
    for &t in cc {
        let p = traj
            .state_at(t)
            .map_err(|e| SimError::model("course change position", e))?
            .pos_in_nav;
        cc_pts.push((p.y, p.x));
    }
    out.figure(
        "mission_plan.svg",
        &PlanPlot::new(
            "fusion mission, plan view (course changes marked)",
            "east (m)",
            "north (m)",
        )
        .with_path(Series::new("true path", truth_plan.clone()))
        .with_markers(Series::new("course change", cc_pts)),
    )?;
    let mut dp = LinePlot::new(
        "fusion mission, depth versus time (course changes marked)",
        "time (s)",
        "depth (m)",
    )
    .with_series(Series::new("depth", depth));
    dp.markers_x = cc.to_vec();
    dp.markers_label = "course change".into();
    out.figure("mission_depth.svg", &dp)?;

    // --- Figs. 7-12: paths, errors, histograms per filter --------------------
    let paths = run0
        .output
        .paths
        .as_ref()
        .ok_or_else(|| SimError::invalid_argument("figures", "run 0 was run without paths"))?;
    let true_path = run0
        .output
        .true_path
        .as_ref()
        .ok_or_else(|| SimError::invalid_argument("figures", "run 0 has no true path"))?;
    let in_zoom = |t: f64| (t - zc).abs() <= zh;
    for m in FILTERS {
        let est = &paths[m.index()];
        let est_plan: Vec<(f64, f64)> = est.iter().map(|p| (p.y, p.x)).collect();
        out.figure(
            &format!("path_{}.svg", m.slug()),
            &PlanPlot::new(
                format!("{}: estimated vs true path (run 0)", m.name()),
                "east (m)",
                "north (m)",
            )
            .with_path(Series::new("true", truth_plan.clone()))
            .with_path(Series::new(m.name(), est_plan)),
        )?;
        let zoom_true: Vec<(f64, f64)> = times
            .iter()
            .zip(true_path)
            .filter(|(t, _)| in_zoom(**t))
            .map(|(_, p)| (p.y, p.x))
            .collect();
        let zoom_est: Vec<(f64, f64)> = times
            .iter()
            .zip(est)
            .filter(|(t, _)| in_zoom(**t))
            .map(|(_, p)| (p.y, p.x))
            .collect();
        if !zoom_true.is_empty() {
            let mut zp = PlanPlot::new(
                format!(
                    "{}: path at t = {zc} ± {zh} s (run 0, 1 s samples)",
                    m.name()
                ),
                "east (m)",
                "north (m)",
            )
            .with_path(Series::new("true", zoom_true.clone()))
            .with_path(Series::new(m.name(), zoom_est.clone()));
            // The samples in their path's colour.
            zp = zp
                .with_markers(Series::new("true samples", zoom_true).with_color(0))
                .with_markers(Series::new(format!("{} samples", m.name()), zoom_est).with_color(1));
            out.figure(&format!("path_{}_zoom.svg", m.slug()), &zp)?;
        }
        let i = m.index();
        let mean3 = mean_series(results, |r| &r.output.err_3d[i]);
        let mut ep = LinePlot::new(
            format!(
                "{}: 3D distance error (course changes marked, ± {hw} s shaded)",
                m.name()
            ),
            "time (s)",
            "3D error (m)",
        )
        .with_series(Series::new("run 0", xy(times, &run0.output.err_3d[i])))
        .with_series(Series::new(
            format!("mean of {} runs", results.len()),
            xy(times, &mean3),
        ));
        let per_run: Vec<&[f64]> = results
            .iter()
            .map(|r| r.output.err_3d[i].as_slice())
            .collect();
        let (_, band) = fathom_stats::mean_curve_ci95(times, &per_run)?;
        ep = ep.with_band(1, band);
        ep.markers_x = cc.to_vec();
        ep.shaded_x = cc.iter().map(|c| (c - hw, c + hw)).collect();
        ep.shaded_label = format!("course change ± {hw} s");
        out.figure(&format!("err3d_{}.svg", m.slug()), &ep)?;

        let pooled: Vec<f64> = results
            .iter()
            .flat_map(|r| r.output.err_3d[i].iter().copied())
            .collect();
        let h = fathom_stats::Histogram::new(&pooled, setup.histogram_bins)
            .map_err(|e| SimError::model("error histogram", e))?;
        let total = h.total().max(1) as f64;
        out.figure(
            &format!("hist3d_{}.svg", m.slug()),
            &Histogram::new(
                format!("{}: 3D error histogram (all runs, all times)", m.name()),
                "3D error (m)",
                "fraction of samples",
                h.edges.clone(),
                h.counts.iter().map(|&c| c as f64 / total).collect(),
            ),
        )?;
    }

    // --- Fig. 13: 2D errors; all 3D errors; INS drift ------------------------
    let mut p2 = LinePlot::new(
        format!("2D (x-y) distance error, mean of {} runs", results.len()),
        "time (s)",
        "2D error (m)",
    );
    let mut p3 = LinePlot::new(
        format!("3D distance error, mean of {} runs", results.len()),
        "time (s)",
        "3D error (m)",
    );
    for m in FILTERS.iter().copied().chain([Method::DvlDr]) {
        let i = m.index();
        p2.series.push(Series::new(
            m.name(),
            xy(times, &mean_series(results, |r| &r.output.err_2d[i])),
        ));
        p3.series.push(Series::new(
            m.name(),
            xy(times, &mean_series(results, |r| &r.output.err_3d[i])),
        ));
    }
    p2.markers_x = cc.to_vec();
    p3.markers_x = cc.to_vec();
    p2.markers_label = "course change".into();
    p3.markers_label = "course change".into();
    out.figure("err2d.svg", &p2)?;
    out.figure("err3d_all.svg", &p3)?;

    let ins_fb = mean_series(results, |r| &r.output.ins_err_with_feedback);
    out.figure("ins_drift.svg", &LinePlot::new(
        format!(
            "sensor position errors, mean of {} runs (INS integrator with and without EFF feedback)",
            results.len()
        ),
        "time (s)",
        "3D error (m)",
    )
    .with_series(Series::new(
        "INS-only (open loop)",
        xy(times, &mean_series(results, |r| &r.output.err_3d[Method::InsOnly.index()])),
    ))
    .with_series(Series::new(
        "DVL-DR",
        xy(times, &mean_series(results, |r| &r.output.err_3d[Method::DvlDr.index()])),
    ))
    .with_series(Series::new("INS under EFF feedback", xy(times, &ins_fb)))
    )?;

    // --- Sensitivity ----------------------------------------------------------
    let mut sens_records = Vec::new();
    for s in sweeps {
        let mut plot = LinePlot::new(
            format!(
                "mean 3D error vs {} ({} reading, {} runs each)",
                s.label,
                match s.reading {
                    Reading::BarShalom => "Bar-Shalom",
                    Reading::AsPrinted => "as-printed",
                },
                setup.sensitivity_runs
            ),
            format!("log10 {}", s.label),
            "mean 3D error (m)",
        );
        for (j, m) in SWEEP_METHODS.iter().enumerate() {
            let pts = s
                .values
                .iter()
                .zip(&s.means)
                .map(|(v, row)| (v.log10(), row[j].0))
                .collect();
            plot.series.push(Series::new(m.name(), pts));
            for (v, row) in s.values.iter().zip(&s.means) {
                sens_records.push(vec![
                    CsvCell::from(s.reading.name()),
                    CsvCell::from(s.key),
                    CsvCell::from(*v),
                    CsvCell::from(m.name()),
                    CsvCell::from(row[j].0),
                    CsvCell::from(row[j].1[0]),
                    CsvCell::from(row[j].1[1]),
                ]);
            }
        }
        out.figure(
            &format!("sensitivity_{}_{}.svg", s.key, s.reading.name()),
            &plot,
        )?;
    }
    out.csv_records(
        "sensitivity.csv",
        &[
            "reading",
            "sweep",
            "value",
            "method",
            "mean_3d_m",
            "ci95_lo_m",
            "ci95_hi_m",
        ],
        &sens_records,
    )?;

    // --- CSV: per-time means, run-0 paths, per-run metrics ---------------------
    let mut headers = vec!["time_s".to_string()];
    let mut cols: Vec<Vec<f64>> = vec![times.clone()];
    for m in Method::ALL {
        let i = m.index();
        headers.push(format!("{}_mean_err3d_m", m.slug()));
        cols.push(mean_series(results, |r| &r.output.err_3d[i]));
        headers.push(format!("{}_mean_err2d_m", m.slug()));
        cols.push(mean_series(results, |r| &r.output.err_2d[i]));
    }
    headers.push("ins_under_eff_feedback_mean_err3d_m".into());
    cols.push(ins_fb);
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    out.csv_columns("error_series.csv", &h, &c)?;

    let mut headers = vec!["time_s".to_string()];
    let mut cols: Vec<Vec<f64>> = vec![times.clone()];
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        headers.push(format!("true_{name}_m"));
        cols.push(true_path.iter().map(|p| p[axis]).collect());
    }
    for m in Method::ALL {
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            headers.push(format!("{}_{name}_m", m.slug()));
            cols.push(paths[m.index()].iter().map(|p| p[axis]).collect());
        }
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    out.csv_columns("run0_paths.csv", &h, &c)?;

    let mut records = Vec::new();
    for (run, r) in results.iter().enumerate() {
        for m in Method::ALL {
            if let Some(mm) = &r.metrics[m.index()] {
                records.push(vec![
                    CsvCell::from(run),
                    CsvCell::from(m.name()),
                    CsvCell::from(mm.mean_3d),
                    CsvCell::from(mm.std_3d),
                    CsvCell::from(mm.mean_2d),
                    CsvCell::from(mm.std_2d),
                    CsvCell::from(mm.turn_ratio_3d),
                    CsvCell::from(mm.max_3d),
                    CsvCell::from(mm.final_3d),
                ]);
            }
        }
    }
    out.csv_records(
        "per_run_metrics.csv",
        &[
            "run",
            "method",
            "mean_3d_m",
            "std_3d_m",
            "mean_2d_m",
            "std_2d_m",
            "turn_ratio_3d",
            "max_3d_m",
            "final_3d_m",
        ],
        &records,
    )?;
    Ok(())
}

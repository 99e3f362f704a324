//! The `beacons` figures and CSV files: mean error versus time per case, per-run
//! statistics, and the single-run figures of the figure run (paths, estimate versus
//! truth, sample times).

use fathom_traj::velocity_command::VelocityCommandMotion;

use super::detail::SAMPLE_WINDOW;
use super::run::{BatchSums, KeptStats};
use super::scenario::Checked;
use super::{MAIN_CASE, method};
use fathom_report::plot::{LinePlot, PlanPlot, Series, Timeline};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// Adds every figure and CSV file to `out`.
pub(super) fn write(
    checked: &Checked,
    per_run: &[Vec<Vec<KeptStats>>],
    sums: &BatchSums,
    out: &mut Analysis,
) -> Result<(), SimError> {
    let schemes = &checked.schemes;
    // Mean error vs time over runs, every case and scheme.
    let n_t = sums.cases[0][0].errors.len();
    let period = checked.cases[0].setup.settings.epoch_period;
    let times: Vec<f64> = (1..=n_t).map(|j| j as f64 * period).collect();
    let mut headers = vec!["time_s".to_owned()];
    let mut cols: Vec<Vec<f64>> = vec![times.clone()];
    for (ci, case) in checked.cases.iter().enumerate() {
        let mut plot = LinePlot::new(
            format!(
                "3D position error vs time, mean over {} runs (case {})",
                checked.runs, case.name
            ),
            "time (s)",
            "3D position error (m)",
        );
        for (si, s) in schemes.iter().enumerate() {
            let acc = &sums.cases[ci][si];
            let mean: Vec<f64> = acc.errors.iter().map(|e| e / acc.runs as f64).collect();
            plot.series
                .push(Series::from_xy(s.short_name(), &times, &mean)?);
            headers.push(format!(
                "{}_mean_error_m",
                method(*s, &case.name).replace('/', "_")
            ));
            cols.push(mean);
        }
        out.figure(&format!("error_vs_time_{}.svg", case.name), &plot)?;
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    out.csv_columns("error_vs_time.csv", &h, &c)?;

    // Per-run statistics.
    let mut headers = vec!["run".to_owned()];
    let mut cols: Vec<Vec<f64>> = vec![(0..per_run.len()).map(|r| r as f64).collect()];
    for (ci, case) in checked.cases.iter().enumerate() {
        for (si, s) in schemes.iter().enumerate() {
            let m = method(*s, &case.name).replace('/', "_");
            for (name, g) in [
                (
                    "mean",
                    &(|x: &KeptStats| x.stats.mean) as &dyn Fn(&KeptStats) -> f64,
                ),
                ("std", &|x: &KeptStats| x.stats.std),
                ("max", &|x: &KeptStats| x.stats.max),
                ("rmse", &|x: &KeptStats| x.stats.rmse),
                ("outliers_rejected", &|x: &KeptStats| x.rejected as f64),
                ("false_rejections", &|x: &KeptStats| {
                    x.false_rejections as f64
                }),
                ("nees_time_avg", &|x: &KeptStats| x.nees_mean),
            ] {
                headers.push(format!("{m}_{name}"));
                cols.push(per_run.iter().map(|r| g(&r[ci][si])).collect());
            }
        }
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.csv_owned_columns("per_run_stats.csv", &h, cols)?;

    // Single-run figures: the figure run's detail, from its own record.
    let detail = sums.figure.as_deref().ok_or_else(|| {
        SimError::invalid_argument(
            "beacons figures",
            format!("run {} carried no figure detail", checked.figure_run),
        )
    })?;
    let main = checked.main_case();
    let commanded = VelocityCommandMotion::commanded(
        &checked
            .motion
            .check()
            .map_err(|e| SimError::model("motion parameters", e))?,
    )
    .map_err(|e| SimError::model("commanded motion", e))?;
    let commanded_ned: Vec<[f64; 4]> = commanded
        .samples()
        .iter()
        .map(|s| [s.time, s.pos_in_nav.x, s.pos_in_nav.y, s.pos_in_nav.z])
        .collect();
    let en = |m: &[[f64; 4]]| -> Vec<(f64, f64)> { m.iter().map(|s| (s[2], s[1])).collect() };
    let beacons: Vec<(f64, f64)> = checked.cases[main]
        .setup
        .beacons
        .iter()
        .map(|b| (b.y, b.x))
        .collect();
    let plan = PlanPlot::new(
        format!(
            "commanded vs actual path (run {}), plan view",
            checked.figure_run
        ),
        "east (m)",
        "north (m)",
    )
    .with_path(Series::new("commanded", en(&commanded_ned)))
    .with_path(Series::new("actual", en(&detail.actual)))
    .with_markers(Series::new("beacons", beacons));
    out.figure("path_plan.svg", &plan)?;
    let depth = |m: &[[f64; 4]]| -> Vec<(f64, f64)> { m.iter().map(|s| (s[0], s[3])).collect() };
    let mut p = LinePlot::new("commanded vs actual depth", "time (s)", "depth (m)");
    p.series
        .push(Series::new("commanded", depth(&commanded_ned)));
    p.series.push(Series::new("actual", depth(&detail.actual)));
    out.figure("path_depth.svg", &p)?;

    // The single-run estimate figures show SC (or the first scheme run without it).
    let runs = &detail.schemes;
    let (sc, fig_name) = (&runs[detail.shown], schemes[detail.shown].short_name());
    let truth_pts = &detail.truth_at_eval;
    let plan = PlanPlot::new(
        format!(
            "{fig_name} estimate vs truth (case {MAIN_CASE}, run {})",
            checked.figure_run
        ),
        "east (m)",
        "north (m)",
    )
    .with_path(Series::new(
        "truth",
        truth_pts.iter().map(|s| (s[1], s[0])).collect(),
    ))
    .with_path(Series::new(
        format!("{fig_name} estimate"),
        sc.estimates.iter().map(|x| (x[1], x[0])).collect(),
    ));
    let fig_file = fig_name.to_lowercase();
    out.figure(&format!("{fig_file}_estimate_vs_truth_plan.svg"), &plan)?;
    let mut p = LinePlot::new(
        format!(
            "{fig_name} estimate vs truth: depth (case {MAIN_CASE}, run {})",
            checked.figure_run
        ),
        "time (s)",
        "depth (m)",
    );
    p.series.push(Series::new(
        "truth",
        sc.times
            .iter()
            .zip(truth_pts)
            .map(|(t, s)| (*t, s[2]))
            .collect(),
    ));
    p.series.push(Series::new(
        format!("{fig_name} estimate"),
        sc.times
            .iter()
            .zip(&sc.estimates)
            .map(|(t, x)| (*t, x[2]))
            .collect(),
    ));
    out.figure(&format!("{fig_file}_estimate_vs_truth_depth.svg"), &p)?;
    let mut p = LinePlot::new(
        format!(
            "3D position error vs time (case {MAIN_CASE}, run {})",
            checked.figure_run
        ),
        "time (s)",
        "3D position error (m)",
    );
    for (s, r) in schemes.iter().zip(runs) {
        p.series
            .push(Series::from_xy(s.short_name(), &r.times, &r.errors_3d)?);
    }
    out.figure("error_vs_time_single_run.svg", &p)?;
    let mut cols: Vec<Vec<f64>> = vec![sc.times.clone()];
    for k in 0..4 {
        cols.push(truth_pts.iter().map(|s| s[k]).collect());
    }
    let mut headers = vec![
        "time_s",
        "true_north_m",
        "true_east_m",
        "true_down_m",
        "true_yaw_rad",
    ]
    .into_iter()
    .map(String::from)
    .collect::<Vec<_>>();
    for (s, r) in schemes.iter().zip(runs) {
        for (i, n) in ["north_m", "east_m", "down_m", "yaw_rad"]
            .iter()
            .enumerate()
        {
            headers.push(format!("{}_{n}", s.short_name()));
            cols.push(r.estimates.iter().map(|x| x[i]).collect());
        }
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    out.csv_columns("single_run_estimates.csv", &h, &c)?;

    // Sample-time diagram from the figure run's actual data: async (main case) and
    // sync (the sync case, if any), with the SC/SI epochs.
    let window = SAMPLE_WINDOW;
    let mut rows = detail.sample_rows.clone();
    let period = checked.cases[main].setup.settings.epoch_period;
    rows.push((
        "SC/SI epochs".into(),
        (1..)
            .map(|j| j as f64 * period)
            .take_while(|t| *t <= window.1 + 1e-9)
            .collect(),
    ));
    let timeline = Timeline::new(
        format!(
            "sensor sample times (run {}): asynchronous vs synchronous",
            checked.figure_run
        ),
        "time (s)",
        rows,
        Some(window),
    );
    out.figure("sample_times.svg", &timeline)
}

//! The `urban` analysis: per scenario and method the Monte Carlo means of the per-run
//! statistics with 95 % CIs (the paper column where it prints a number), the paired
//! differences the claims read, the GNSS shadowing per scenario, the ablations
//! against the main batch's runs of the same index, then claims, figures and report.

use super::check::Checked;
use super::claims::{DIFFERENCES, claims, diff_row, method_row};
use super::nav::Method;
use super::paper::paper_value;
use super::record::{BatchFold, KeptRun};
use super::trace::MethodStats;
use super::world::Prepared;
use fathom_report::output::{CsvCell, Row};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// Index of a metric in [`MethodStats::METRICS`].
pub(super) fn metric_index(metric: &str) -> Option<usize> {
    MethodStats::METRICS.iter().position(|m| *m == metric)
}

/// The per-run values of `metric` of method index `m` in scenario `s`.
pub(super) fn values(kept: &[KeptRun], s: usize, m: usize, metric: usize) -> Vec<f64> {
    kept.iter()
        .map(|r| r[s].stats[m].values()[metric])
        .collect()
}

/// The row of the paired difference `a - b` of `metric` (a signed metric
/// `diff_<metric>`: Student-t interval).
fn diff(
    out: &mut Analysis,
    method: &str,
    metric: &str,
    a: &[f64],
    b: &[f64],
) -> Result<(), SimError> {
    let name = format!("diff_{metric}");
    out.signed(name.clone());
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    out.runs_row(method, &name, &d)?;
    Ok(())
}

/// The unit of every metric of the rows.
fn declare_units(out: &mut Analysis) {
    for (metric, unit) in [
        ("rmse_h", "m"),
        ("rmse_3d", "m"),
        ("rmse_vel", "m/s"),
        ("rmse_roll", "deg"),
        ("rmse_pitch", "deg"),
        ("rmse_yaw", "deg"),
        ("mean_3d", "m"),
        ("p95_3d", "m"),
        ("max_att", "deg"),
        ("time_map_aided_s", "s"),
        ("nees_mean", "1"),
        ("diff_rmse_h", "m"),
        ("diff_rmse_3d", "m"),
        ("diff_rmse_yaw", "deg"),
        ("rmse_3d_open", "m"),
        ("diff_rmse_3d_open", "m"),
        ("los_satellites_mean", "1"),
        ("shadowed_fraction", "1"),
        ("flight_duration_s", "s"),
        ("satellites_used", "count"),
        ("runs_beyond_1m", "count"),
        ("worst_rmse_3d", "m"),
        ("switches", "count/run"),
        ("switches_min", "count"),
        ("lost_lock", "count/run"),
        ("gps_reacquired", "count/run"),
        ("time_gps_ins_s", "s"),
    ] {
        out.unit(metric, unit);
    }
}

/// Computes the rows, the claims and the per-run CSV file.
pub(super) fn analyse(
    prep: &Prepared,
    kept: &[Vec<KeptRun>],
    folds: &[BatchFold],
    out: &mut Analysis,
) -> Result<(), SimError> {
    let c: &Checked = &prep.checked;
    let (Some(main), Some(_)) = (kept.first(), folds.first()) else {
        return Err(SimError::invalid_argument("urban", "no main batch"));
    };
    declare_units(out);
    for (s, spec) in c.scenes.iter().enumerate() {
        for (m, method) in c.methods.iter().enumerate() {
            let name = method_row(&spec.name, *method);
            for (k, metric) in MethodStats::METRICS.iter().enumerate() {
                out.runs_row(&name, metric, &values(main, s, m, k))?.paper =
                    paper_value(spec.paper, *method, metric);
            }
        }
        for (a, b, metric) in DIFFERENCES {
            // A difference needs both methods (`methods` may select fewer).
            let (Some(ia), Some(ib)) = (c.index_of(a), c.index_of(b)) else {
                continue;
            };
            let k = metric_index(metric).unwrap_or(0);
            diff(
                out,
                &diff_row(&spec.name, a, b),
                metric,
                &values(main, s, ia, k),
                &values(main, s, ib, k),
            )?;
        }
        open_sky_rows(c, main, s, out)?;
        switching_rows(c, main, s, out)?;
        let g = format!("{}/GNSS", spec.name);
        out.row(Row::new(
            &g,
            "satellites_used",
            prep.receiver.orbits().len() as f64,
        ));
        let per = |f: fn(&super::record::KeptScene) -> f64| -> Vec<f64> {
            main.iter().map(|r| f(&r[s])).collect()
        };
        out.runs_row(&g, "los_satellites_mean", &per(|k| k.los_mean))?;
        out.runs_row(&g, "shadowed_fraction", &per(|k| k.shadowed_fraction))?;
        out.runs_row(&g, "flight_duration_s", &per(|k| k.duration_s))?;
    }
    // ablations: the same metrics, and paired differences against the main batch's
    // runs of the same index
    for (b, a) in c.ablations.iter().enumerate() {
        let runs = &kept[b + 1];
        // `check` keeps only the ablations of selected methods.
        let Some(m) = c.index_of(a.method) else {
            continue;
        };
        let base = format!(
            "{}@{}",
            method_row(&c.scenes[a.scene].name, a.method),
            a.label()
        );
        for (k, metric) in MethodStats::METRICS.iter().enumerate() {
            let v: Vec<f64> = runs.iter().map(|r| r[0].stats[0].values()[k]).collect();
            out.runs_row(&base, metric, &v)?;
        }
        let k3 = metric_index("rmse_3d").unwrap_or(0);
        let rmse: Vec<f64> = runs.iter().map(|r| r[0].stats[0].values()[k3]).collect();
        let beyond = rmse.iter().filter(|v| **v > BEYOND_M).count();
        out.row(Row::new(&base, "runs_beyond_1m", beyond as f64));
        let worst = rmse.iter().copied().fold(0.0, f64::max);
        out.row(Row::new(&base, "worst_rmse_3d", worst));
        for metric in ["rmse_h", "rmse_3d", "rmse_yaw"] {
            let k = metric_index(metric).unwrap_or(0);
            let v: Vec<f64> = runs.iter().map(|r| r[0].stats[0].values()[k]).collect();
            let paired = &values(main, a.scene, m, k)[..v.len()];
            diff(out, &format!("{base}-vs-main"), metric, &v, paired)?;
        }
    }
    // The claims compare the methods: made only when every method ran.
    if c.all_methods() {
        for claim in claims(out.rows(), c.table2_tolerance) {
            out.claim(claim);
        }
    }
    per_run_csv(c, main, out)
}

/// The open-sky rows of a scenario: `rmse_3d_open` of every method and the paired
/// differences of [`OPEN_SKY_DIFFERENCES`], when every run has open-sky epochs
/// (a world without open sky has none: the report says so).
fn open_sky_rows(
    c: &Checked,
    main: &[KeptRun],
    s: usize,
    out: &mut Analysis,
) -> Result<(), SimError> {
    let spec = &c.scenes[s];
    let open = |m: usize| -> Option<Vec<f64>> {
        main.iter().map(|r| r[s].stats[m].rmse_3d_open).collect()
    };
    for (m, method) in c.methods.iter().enumerate() {
        if let Some(v) = open(m) {
            out.runs_row(&method_row(&spec.name, *method), "rmse_3d_open", &v)?;
        }
    }
    for (a, b) in OPEN_SKY_DIFFERENCES {
        let (Some(ia), Some(ib)) = (c.index_of(a), c.index_of(b)) else {
            continue;
        };
        if let (Some(va), Some(vb)) = (open(ia), open(ib)) {
            diff(out, &diff_row(&spec.name, a, b), "rmse_3d_open", &va, &vb)?;
        }
    }
    Ok(())
}

/// The paired open-sky differences `a - b` of `rmse_3d_open`.
pub(super) const OPEN_SKY_DIFFERENCES: [(Method, Method); 2] = [
    (Method::GpsIns, Method::InsOnly),
    (Method::GpsIns, Method::GpsInsAllSats),
];

/// A 3-D RMSE above this counts a run in `runs_beyond_1m`, m.
pub(super) const BEYOND_M: f64 = 1.0;

/// The per-scenario switching and divergence rows of every method: `switches` (mean
/// per run, 95 % CI) and `switches_min` (fewest in any run) and `lost_lock` (mean) of
/// the switching methods, `time_gps_ins_s` (mean), `runs_beyond_1m` (runs whose
/// rmse_3d exceeds 1 m) of every method, and `gps_reacquired` (mean) of every GPS
/// method when re-acquisition is on.
fn switching_rows(
    c: &Checked,
    main: &[KeptRun],
    s: usize,
    out: &mut Analysis,
) -> Result<(), SimError> {
    let spec = &c.scenes[s];
    let k3 = metric_index("rmse_3d").unwrap_or(0);
    let km = metric_index("time_map_aided_s").unwrap_or(0);
    for (m, method) in c.methods.iter().enumerate() {
        let name = method_row(&spec.name, *method);
        let beyond = values(main, s, m, k3)
            .iter()
            .filter(|v| **v > BEYOND_M)
            .count();
        out.row(Row::new(&name, "runs_beyond_1m", beyond as f64));
        let counts: Vec<_> = main.iter().map(|r| r[s].counts[m]).collect();
        if *method != Method::InsOnly && c.filter.gps.reacquire_after() > 0 {
            let re: Vec<f64> = counts.iter().map(|n| n.gps_reacquired as f64).collect();
            out.runs_row(&name, "gps_reacquired", &re)?;
        }
        if !method.is_switching() {
            continue;
        }
        let switches: Vec<f64> = counts.iter().map(|n| n.switches as f64).collect();
        out.runs_row(&name, "switches", &switches)?;
        let fewest = switches.iter().copied().fold(f64::INFINITY, f64::min);
        out.row(Row::new(&name, "switches_min", fewest));
        let lost: Vec<f64> = counts.iter().map(|n| n.lost_lock as f64).collect();
        out.runs_row(&name, "lost_lock", &lost)?;
        let gps: Vec<f64> = main
            .iter()
            .map(|r| {
                let nav_s = (r[s].duration_s - c.rest_s).max(0.0);
                (nav_s - r[s].stats[m].values()[km]).max(0.0)
            })
            .collect();
        out.runs_row(&name, "time_gps_ins_s", &gps)?;
    }
    Ok(())
}

/// `per_run.csv`: every run's statistics per scenario and method.
fn per_run_csv(c: &Checked, main: &[KeptRun], out: &mut Analysis) -> Result<(), SimError> {
    let mut headers = vec!["run", "scenario", "method"];
    let units = [
        "rmse_h_m",
        "rmse_3d_m",
        "rmse_vel_mps",
        "rmse_roll_deg",
        "rmse_pitch_deg",
        "rmse_yaw_deg",
        "mean_3d_m",
        "p95_3d_m",
        "max_att_deg",
        "time_map_aided_s",
        "nees_mean",
    ];
    headers.extend(units);
    headers.extend([
        "gps_updates",
        "map_updates",
        "map_failed",
        "map_left_out",
        "switches",
        "lost_lock",
        "relocks",
        "gps_reacquired",
        "beams_nonlinear",
    ]);
    let mut records = Vec::new();
    for (i, run) in main.iter().enumerate() {
        for (s, spec) in c.scenes.iter().enumerate() {
            for (m, method) in c.methods.iter().enumerate() {
                let mut rec = vec![
                    CsvCell::Int(i as i64),
                    CsvCell::Text(spec.name.clone()),
                    CsvCell::Text(method.name().into()),
                ];
                rec.extend(run[s].stats[m].values().iter().map(|v| CsvCell::Num(*v)));
                let n = run[s].counts[m];
                rec.extend(
                    [
                        n.gps_updates,
                        n.map_updates,
                        n.map_failed,
                        n.map_left_out,
                        n.switches,
                        n.lost_lock,
                        n.relocks,
                        n.gps_reacquired,
                        n.beams_nonlinear,
                    ]
                    .map(|x| CsvCell::Int(x as i64)),
                );
                records.push(rec);
            }
        }
    }
    out.csv_records("per_run.csv", &headers, &records)
}

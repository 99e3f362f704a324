//! The Plaza figures (those every replay draws: estimate vs truth, error with 3σ,
//! innovations, NIS; then errors, ablation, range errors, calibration) and CSV files
//! (estimates, ranges with each scheme's decision).

use fathom_estimators::schemes::Disposition;

use super::analysis::{MAIN_METHODS, smoothed_name};
use fathom_replay::figures::{
    ErrorTrack, InnovationTrack, Path, Tested, error_3sigma, innovations, nis, plan_view, thin,
};
use fathom_replay::plaza::{Calibration, MethodRun, PlazaReplay};
use fathom_report::output::{CsvCell, fixed as f};
use fathom_report::plot::{Histogram, LinePlot, PlanPlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// Adds every figure and CSV file to `out`.
pub(super) fn write(r: &PlazaReplay, out: &mut Analysis) -> Result<(), SimError> {
    write_csv(r, out)?;
    write_figures(r, out)
}

fn decision_word(d: Option<Disposition>) -> &'static str {
    match d {
        None => "",
        Some(Disposition::Accepted) => "accepted",
        Some(Disposition::Rejected) => "rejected",
        Some(Disposition::Stale) => "stale",
        Some(Disposition::Superseded) => "superseded",
        Some(Disposition::NonFinite) => "non-finite",
    }
}

fn write_csv(r: &PlazaReplay, out: &mut Analysis) -> Result<(), SimError> {
    let p = &r.prepared;
    let time: Vec<f64> = p.eval.iter().map(|e| e.0).collect();
    let tx: Vec<f64> = p.eval.iter().map(|e| e.1).collect();
    let ty: Vec<f64> = p.eval.iter().map(|e| e.2).collect();
    let mut headers: Vec<String> = vec!["time_s".into(), "true_x_m".into(), "true_y_m".into()];
    let mut cols: Vec<Vec<f64>> = vec![time, tx, ty];
    for m in &r.methods {
        headers.push(format!("{}_x_m", m.name));
        cols.push(m.est.iter().map(|e| e[0]).collect());
        headers.push(format!("{}_y_m", m.name));
        cols.push(m.est.iter().map(|e| e[1]).collect());
        headers.push(format!("{}_err_m", m.name));
        cols.push(m.err.clone());
        if m.variant.as_ref().is_some_and(|v| !v.ablation) {
            headers.push(format!("{}_sigma_pos_m", m.name));
            cols.push(m.pos_sigma.clone());
            headers.push(format!("{}_range_offset_m", m.name));
            cols.push(m.calibration.iter().map(|c| c[0]).collect());
            headers.push(format!("{}_range_scale", m.name));
            cols.push(m.calibration.iter().map(|c| c[1]).collect());
        }
        if let Some(sm) = &m.smoothed {
            let name = smoothed_name(&m.name);
            headers.push(format!("{name}_x_m"));
            cols.push(sm.est.iter().map(|e| e[0]).collect());
            headers.push(format!("{name}_y_m"));
            cols.push(sm.est.iter().map(|e| e[1]).collect());
            headers.push(format!("{name}_err_m"));
            cols.push(sm.err.clone());
            headers.push(format!("{name}_sigma_pos_m"));
            cols.push(sm.pos_sigma.clone());
        }
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    out.csv_columns("estimates.csv", &h, &c)?;

    let mains: Vec<&MethodRun> = r
        .methods
        .iter()
        .filter(|m| m.variant.as_ref().is_some_and(|v| !v.ablation))
        .collect();
    let mut headers: Vec<String> = [
        "time_s",
        "beacon_id",
        "range_m",
        "true_distance_m",
        "error_m",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for m in &mains {
        headers.push(format!("{}_decision", m.name));
    }
    let mut records = Vec::new();
    let t0 = p.t0;
    // Analysis samples are in log order (same as the decisions' index) for ranges in
    // the ground-truth span.
    let mut k = 0;
    for (index, rr) in r.ranges_in_log().iter().enumerate() {
        let rel = rr.0 - t0;
        let (dist, err) = match r.analysis.samples.get(k) {
            Some(s) if s.0 == rel && s.3 == rr.1 => {
                k += 1;
                (CsvCell::Num(s.1), CsvCell::Num(s.2))
            }
            _ => (CsvCell::Text(String::new()), CsvCell::Text(String::new())),
        };
        let mut rec = vec![
            CsvCell::Num(rel),
            CsvCell::Int(r.beacons[rr.1].id),
            CsvCell::Num(rr.2),
            dist,
            err,
        ];
        for m in &mains {
            rec.push(decision_word(m.decisions.get(index).copied().flatten()).into());
        }
        records.push(rec);
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.csv_records("ranges.csv", &h, &records)
}

/// The methods of the plan view and the error figures, in drawing order.
const SHOWN: [&str; 4] = ["DR", "AS", "SC", "SI"];

/// The figures every replay draws ([`fathom_replay::figures`]): the plan view, the
/// error with each filter's 3σ, and the main methods' range innovations and NIS.
fn write_replay_figures(r: &PlazaReplay, out: &mut Analysis) -> Result<(), SimError> {
    let p = &r.prepared;
    let shown: Vec<(usize, &MethodRun)> = SHOWN
        .iter()
        .filter_map(|n| r.method(n))
        .enumerate()
        .collect();
    let paths: Vec<Path<'_>> = shown
        .iter()
        .map(|(k, m)| Path {
            name: &m.name,
            color: *k,
            points: m.est.iter().map(|e| (e[0], e[1])).collect(),
        })
        .collect();
    let truth: Vec<(f64, f64)> = p.eval.iter().map(|e| (e.1, e.2)).collect();
    let beacons = Series::new("beacons", r.beacons.iter().map(|b| (b.x, b.y)).collect());
    plan_view(
        out,
        "estimate_vs_truth.svg",
        &format!("{}: estimated and true path", r.data_name),
        ("x (m)", "y (m)"),
        &truth,
        &paths,
        Some(beacons),
    )?;
    let time: Vec<f64> = p.eval.iter().map(|e| e.0).collect();
    let tracks: Vec<ErrorTrack<'_>> = shown
        .iter()
        .map(|(k, m)| ErrorTrack {
            name: &m.name,
            color: *k,
            errors: &m.err,
            sigma: (m.pos_sigma.len() == m.err.len()).then_some(&m.pos_sigma[..]),
        })
        .collect();
    error_3sigma(
        out,
        "error_3sigma.svg",
        &format!("{}: 2D position error with the filter's 3σ", r.data_name),
        &time,
        &tracks,
    )?;
    let tested: Vec<InnovationTrack<'_>> = shown
        .iter()
        .filter(|(_, m)| !m.innovations.is_empty())
        .map(|(k, m)| InnovationTrack {
            name: &m.name,
            color: *k,
            tested: m
                .innovations
                .iter()
                .map(|i| Tested {
                    time: i.time,
                    innovation: Some(i.innovation),
                    sigma: i.sigma(),
                    nis: i.nis,
                })
                .collect(),
        })
        .collect();
    innovations(
        out,
        "innovations.svg",
        &format!("{}: range innovations", r.data_name),
        "innovation (m)",
        &tested,
    )?;
    nis(
        out,
        "nis.svg",
        &format!("{}: range NIS", r.data_name),
        1,
        &tested,
    )?;
    Ok(())
}

fn write_figures(r: &PlazaReplay, out: &mut Analysis) -> Result<(), SimError> {
    write_replay_figures(r, out)?;
    let p = &r.prepared;
    let step = thin(p.eval.len());
    let time: Vec<f64> = p.eval.iter().map(|e| e.0).collect();
    let err_series = |m: &MethodRun| {
        Series::new(
            m.name.clone(),
            time.iter()
                .zip(&m.err)
                .step_by(step)
                .map(|(t, e)| (*t, *e))
                .collect(),
        )
    };
    let mut plot = LinePlot::new(
        format!("{}: 2D position error", r.data_name),
        "time since start (s)",
        "error (m)",
    );
    for name in SHOWN {
        if let Some(m) = r.method(name) {
            plot = plot.with_series(err_series(m));
        }
    }
    out.figure("error_vs_time.svg", &plot)?;

    // `smooth = true`: filtered against smoothed error of the main methods.
    let smoothed: Vec<&MethodRun> = MAIN_METHODS
        .iter()
        .filter_map(|n| r.method(n))
        .filter(|m| m.smoothed.is_some())
        .collect();
    if !smoothed.is_empty() {
        let mut sp = LinePlot::new(
            format!("{}: filtered and RTS-smoothed 2D error", r.data_name),
            "time since start (s)",
            "error (m)",
        );
        for m in smoothed {
            sp = sp.with_series(err_series(m));
            if let Some(sm) = &m.smoothed {
                sp = sp.with_series(Series::new(
                    smoothed_name(&m.name),
                    time.iter()
                        .zip(&sm.err)
                        .step_by(step)
                        .map(|(t, e)| (*t, *e))
                        .collect(),
                ));
            }
        }
        out.figure("smoothed_error.svg", &sp)?;
    }

    let base = r.settings.ablation_scheme.short_name();
    let mut ab = LinePlot::new(
        format!("Ablation ({base}): error without the range-bias states or the robust gate"),
        "time since start (s)",
        "error (m)",
    );
    for m in r
        .methods
        .iter()
        .filter(|m| m.name == base || m.variant.as_ref().is_some_and(|v| v.ablation))
    {
        ab = ab.with_series(err_series(m));
    }
    out.figure("ablation_error.svg", &ab)?;

    // Range errors against ground truth versus true distance, with the LS line.
    let a = &r.analysis;
    let dmax = a.samples.iter().map(|s| s.1).fold(0.0, f64::max);
    let mut scatter = PlanPlot::new(
        "Range error against ground truth",
        "true distance (m)",
        "range - true distance (m)",
    )
    .with_path(Series::new(
        format!("LS fit {} + {} d", f(a.fit.0, 2), f(a.fit.1, 4)),
        vec![(0.0, a.fit.0), (dmax, a.fit.0 + a.fit.1 * dmax)],
    ))
    .with_markers(Series::new(
        "ranges",
        a.samples.iter().map(|s| (s.1, s.2)).collect(),
    ));
    scatter.equal_aspect = false;
    scatter.size = (900, 560);
    out.figure("range_error_vs_distance.svg", &scatter)?;

    let res: Vec<f64> = a
        .samples
        .iter()
        .map(|s| s.2 - a.fit.0 - a.fit.1 * s.1)
        .collect();
    let lo = res.iter().copied().fold(f64::INFINITY, f64::min).floor();
    let hi = res.iter().copied().fold(f64::NEG_INFINITY, f64::max).ceil();
    let bins = (((hi - lo) / 0.1).round() as usize).clamp(1, 400);
    let w = (hi - lo) / bins as f64;
    let mut counts = vec![0.0; bins];
    for v in &res {
        let k = (((v - lo) / w) as usize).min(bins - 1);
        counts[k] += 1.0;
    }
    let hist = Histogram::new(
        "Range error after the affine fit",
        "residual (m)",
        "count",
        (0..=bins).map(|k| lo + k as f64 * w).collect(),
        counts,
    );
    out.figure("range_residual_hist.svg", &hist)?;

    if let Some(m) = r.method(base).filter(|m| {
        m.variant
            .as_ref()
            .is_some_and(|v| v.calibration != Calibration::None)
    }) {
        // Offset (m) and scale error (%) on axes of their own: one axis for both
        // would mix units.
        let cal = LinePlot::new(
            format!("{base}: estimated range offset"),
            "time since start (s)",
            "offset o (m)",
        )
        .with_series(Series::new(
            "offset o",
            time.iter()
                .zip(&m.calibration)
                .step_by(step)
                .map(|(t, c)| (*t, c[0]))
                .collect(),
        ));
        out.figure("calibration.svg", &cal)?;
        if m.variant.as_ref().map(|v| v.calibration) == Some(Calibration::Affine) {
            let scale = LinePlot::new(
                format!("{base}: estimated range scale error"),
                "time since start (s)",
                "scale error s (%)",
            )
            .with_series(Series::new(
                "scale error s",
                time.iter()
                    .zip(&m.calibration)
                    .step_by(step)
                    .map(|(t, c)| (*t, 100.0 * c[1]))
                    .collect(),
            ));
            out.figure("calibration_scale.svg", &scale)?;
        }
    }
    Ok(())
}

//! Outputs of a Plaza replay: per-time CSV series, SVG figures, the `summary.json` rows
//! and claims, and the report text (shared by the `plaza` experiment and
//! `fathom replay plaza`).

use std::path::{Path, PathBuf};

use crate::SimError;
use crate::experiments::common::f;
use crate::output::{
    Claim, CsvCell, Row, Summary, claims_md_table, md_table, summary_md_table, write_csv_columns,
    write_csv_records, write_summary_json, write_text,
};
use crate::plot::{Histogram, LinePlot, PlanPlot, Series};
use crate::replay::plaza::{Calibration, MethodRun, OutlierHandling, PlazaReplay};
use fathom_estimators::schemes::Disposition;

/// Experiment name of the Plaza replay in summaries.
pub const EXPERIMENT_NAME: &str = "plaza";
/// The `seed_doc` of the Plaza replay: the data set's README (real data, no paper).
pub const SEED_DOC: &str = "data/plaza1/README.md";
/// Required reduction of the mean error against dead reckoning.
pub const REQUIRED_REDUCTION: f64 = 0.35;
/// Largest acceptable maximum error of a scheme, m.
pub const MAX_ERROR_LIMIT_M: f64 = 4.0;
/// The main methods, in report order.
pub const MAIN_METHODS: [&str; 3] = ["AS", "SC", "SI"];

/// Summary and report text of a replay.
#[derive(Debug, Clone, PartialEq)]
pub struct PlazaOutputs {
    /// `summary.json` content.
    pub summary: Summary,
    /// The report section (Markdown, `###` headings).
    pub report_section: String,
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

/// Writes the CSV series and SVG figures into `dir` and builds the summary and the
/// report section.
///
/// # Errors
/// I/O, CSV and plot errors.
pub fn write_outputs(r: &PlazaReplay, dir: &Path) -> Result<PlazaOutputs, SimError> {
    std::fs::create_dir_all(dir).map_err(|e| SimError::io("create directory", dir, e))?;
    write_csv(r, dir)?;
    write_figures(r, dir)?;
    Ok(PlazaOutputs {
        summary: summary(r),
        report_section: report_section(r),
    })
}

fn write_csv(r: &PlazaReplay, dir: &Path) -> Result<(), SimError> {
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
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    write_csv_columns(dir.join("estimates.csv"), &h, &c)?;

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
    write_csv_records(dir.join("ranges.csv"), &h, &records)
}

fn xy_series(name: &str, pts: impl Iterator<Item = (f64, f64)>) -> Series {
    Series::new(name, pts.collect())
}

fn thin(n: usize) -> usize {
    (n / 2500).max(1)
}

fn write_figures(r: &PlazaReplay, dir: &Path) -> Result<(), SimError> {
    let p = &r.prepared;
    let step = thin(p.eval.len());
    let truth = xy_series(
        "ground truth",
        p.eval.iter().step_by(step).map(|e| (e.1, e.2)),
    );
    let beacons = Series::new("beacons", r.beacons.iter().map(|b| (b.x, b.y)).collect());
    let mut plan = PlanPlot::new(
        format!("{}: estimated and true path", r.data_name),
        "x [m]",
        "y [m]",
    )
    .with_path(truth);
    for name in ["DR", "AS", "SC", "SI"] {
        if let Some(m) = r.method(name) {
            plan = plan.with_path(xy_series(
                name,
                m.est.iter().step_by(step).map(|e| (e[0], e[1])),
            ));
        }
    }
    plan.with_markers(beacons).write_svg(dir.join("path.svg"))?;

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
        "time since start [s]",
        "error [m]",
    );
    for name in ["DR", "AS", "SC", "SI"] {
        if let Some(m) = r.method(name) {
            plot = plot.with_series(err_series(m));
        }
    }
    plot.write_svg(dir.join("error_vs_time.svg"))?;

    let base = r.settings.ablation_scheme.short_name();
    let mut ab = LinePlot::new(
        format!("Ablation ({base}): what the bias and outlier handling buy"),
        "time since start [s]",
        "error [m]",
    );
    for m in r
        .methods
        .iter()
        .filter(|m| m.name == base || m.variant.as_ref().is_some_and(|v| v.ablation))
    {
        ab = ab.with_series(err_series(m));
    }
    ab.write_svg(dir.join("ablation_error.svg"))?;

    // Range errors against ground truth versus true distance, with the LS line.
    let a = &r.analysis;
    let dmax = a.samples.iter().map(|s| s.1).fold(0.0, f64::max);
    let mut scatter = PlanPlot::new(
        "Range error against ground truth",
        "true distance [m]",
        "range - true distance [m]",
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
    scatter.write_svg(dir.join("range_error_vs_distance.svg"))?;

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
    Histogram::new(
        "Range error after the affine fit",
        "residual [m]",
        "count",
        (0..=bins).map(|k| lo + k as f64 * w).collect(),
        counts,
    )
    .write_svg(dir.join("range_residual_hist.svg"))?;

    if let Some(m) = r.method(base).filter(|m| {
        m.variant
            .as_ref()
            .is_some_and(|v| v.calibration != Calibration::None)
    }) {
        let mut cal = LinePlot::new(
            format!("{base}: estimated range calibration"),
            "time since start [s]",
            "offset [m] / scale error [%]",
        )
        .with_series(Series::new(
            "offset o [m]",
            time.iter()
                .zip(&m.calibration)
                .step_by(step)
                .map(|(t, c)| (*t, c[0]))
                .collect(),
        ));
        if m.variant.as_ref().map(|v| v.calibration) == Some(Calibration::Affine) {
            cal = cal.with_series(Series::new(
                "scale error s [%]",
                time.iter()
                    .zip(&m.calibration)
                    .step_by(step)
                    .map(|(t, c)| (*t, 100.0 * c[1]))
                    .collect(),
            ));
        }
        cal.write_svg(dir.join("calibration.svg"))?;
    }
    Ok(())
}

/// The `summary.json` content: per method `mean`, `std`, `max`, `rmse` of the 2D
/// position error and `rejected`; the range analysis; the claims.
pub fn summary(r: &PlazaReplay) -> Summary {
    let mut s = Summary::new(EXPERIMENT_NAME, SEED_DOC, 1, 0);
    for m in &r.methods {
        s.push_row(Row::new(&m.name, "mean", m.stats.mean));
        s.push_row(Row::new(&m.name, "std", m.stats.std));
        s.push_row(Row::new(&m.name, "max", m.stats.max));
        s.push_row(Row::new(&m.name, "rmse", m.stats.rmse));
        s.push_row(Row::new(&m.name, "rejected", m.rejected as f64));
    }
    let a = &r.analysis;
    let g = "ranges-vs-GT";
    s.push_row(Row::new(g, "error_mean", a.mean));
    s.push_row(Row::new(g, "error_std", a.std));
    s.push_row(Row::new(g, "fit_offset", a.fit.0));
    s.push_row(Row::new(g, "fit_scale", a.fit.1));
    s.push_row(Row::new(g, "fit_residual_std", a.fit_std));
    s.push_row(Row::new(g, "fit_residual_kurtosis", a.fit_kurtosis));
    for c in claims(r) {
        s.push_claim(c);
    }
    s
}

fn claims(r: &PlazaReplay) -> Vec<Claim> {
    let mut out = Vec::new();
    let Some(dr) = r.method("DR") else {
        return out;
    };
    let mains: Vec<&MethodRun> = MAIN_METHODS.iter().filter_map(|n| r.method(n)).collect();
    let reduction = |m: &MethodRun| 1.0 - m.stats.mean / dr.stats.mean;
    out.push(Claim::new(
        "schemes_35pct_below_dr",
        "every scheme's mean 2D error is at least 35 % below dead reckoning's",
        mains.len() == 3 && mains.iter().all(|m| reduction(m) >= REQUIRED_REDUCTION),
        format!(
            "DR {} m; {}",
            f(dr.stats.mean, 3),
            mains
                .iter()
                .map(|m| format!(
                    "{} {} m ({} % below)",
                    m.name,
                    f(m.stats.mean, 3),
                    f(100.0 * reduction(m), 1)
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    ));
    out.push(Claim::new(
        "schemes_max_below_4m",
        "no scheme's maximum 2D error exceeds 4 m",
        mains.len() == 3 && mains.iter().all(|m| m.stats.max <= MAX_ERROR_LIMIT_M),
        mains
            .iter()
            .map(|m| format!("{} {} m", m.name, f(m.stats.max, 3)))
            .collect::<Vec<_>>()
            .join(", "),
    ));
    let base = r.settings.ablation_scheme.short_name();
    if let (Some(full), Some(nobias)) = (r.method(base), r.method(&format!("{base}-no-bias"))) {
        out.push(Claim::new(
            "range_calibration_helps",
            format!("estimating the range calibration lowers {base}'s mean error"),
            full.stats.mean < nobias.stats.mean,
            format!(
                "{base} {} m, {base}-no-bias {} m",
                f(full.stats.mean, 3),
                f(nobias.stats.mean, 3)
            ),
        ));
    }
    if let (Some(full), Some(hard)) = (
        r.method(&format!("{base}-no-bias")),
        r.method(&format!("{base}-no-bias-hard-gate")),
    ) {
        out.push(Claim::new(
            "robust_handling_helps_without_calibration",
            format!(
                "with uncalibrated (biased) ranges, robust down-weighting with recovery beats \
                 hard gating on {base}'s mean error"
            ),
            full.stats.mean < hard.stats.mean,
            format!(
                "{base}-no-bias {} m (rejected {}), {base}-no-bias-hard-gate {} m (rejected {})",
                f(full.stats.mean, 3),
                full.rejected,
                f(hard.stats.mean, 3),
                hard.rejected
            ),
        ));
    }
    if let Some(m) = r.method(base)
        && m.variant.as_ref().map(|v| v.calibration) == Some(Calibration::Affine)
        && let Some(last) = m.calibration.last()
    {
        let a = &r.analysis;
        // The filter's calibration at the end against the LS fit on ground truth: the
        // predicted range error at the median true distance.
        let mut d: Vec<f64> = a.samples.iter().map(|s| s.1).collect();
        d.sort_by(f64::total_cmp);
        let dm = d[d.len() / 2];
        let est = last[0] + last[1] * dm;
        let fit = a.fit.0 + a.fit.1 * dm;
        out.push(Claim::new(
            "calibration_learned",
            format!(
                "{base}'s final range calibration predicts the range error at the median \
                 distance within 0.5 m of the fit against ground truth"
            ),
            (est - fit).abs() <= 0.5,
            format!(
                "at d = {} m: filter o + s d = {} + {} d = {} m, ground-truth fit {} m",
                f(dm, 1),
                f(last[0], 3),
                f(last[1], 4),
                f(est, 3),
                f(fit, 3)
            ),
        ));
    }
    out
}

fn outlier_words(o: OutlierHandling) -> String {
    match o {
        OutlierHandling::Robust => "Huber + recovery".into(),
        OutlierHandling::HardGate(g) => format!("hard gate {g} sigma"),
    }
}

/// The report section: data, treatment of range bias and outliers, time handling,
/// method and ablation tables with their interpretation.
pub fn report_section(r: &PlazaReplay) -> String {
    let s = &r.settings;
    let a = &r.analysis;
    let p = &r.prepared;
    let mut md = String::new();
    md.push_str(&format!(
        "### Data\n\n`{}`: {} odometry rows, {} ranges to {} beacons (ids {}), {} ground-truth \
         rows; start t0 = {} s (first ground-truth row); the run is {} s long. \
         Initial position from the first ground-truth row, initial heading {} rad from the \
         first row of `DRp`.\n\n",
        r.data_name,
        r.rows.0,
        r.rows.1,
        r.beacons.len(),
        r.beacons
            .iter()
            .map(|b| b.id.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        r.rows.2,
        f(p.t0, 3),
        f(p.eval.last().map_or(0.0, |e| e.0), 1),
        f(p.start[2], 6),
    ));
    if r.range_order_breaks.is_empty() {
        md.push_str("The range file is in time order.\n\n");
    } else {
        md.push_str(&format!(
            "The range file is **not** in time order: time goes backwards at line(s) {} (a \
             later block of the log overlaps times already logged). The ranges are sorted \
             stably by time (`[data] range_order = \"{}\"`); their errors against ground \
             truth at their own stamps look like those of every other block, so the stamps \
             are taken as correct and only the order is repaired.\n\n",
            r.range_order_breaks
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", "),
            match s.range_order {
                crate::data::plaza::RangeOrder::Sort => "sort",
                crate::data::plaza::RangeOrder::Strict => "strict",
            }
        ));
    }
    if p.skipped_odometry + p.skipped_ranges > 0 {
        md.push_str(&format!(
            "Rows at or before t0 are skipped: {} odometry, {} ranges.\n\n",
            p.skipped_odometry, p.skipped_ranges
        ));
    }

    md.push_str("### What the ranges are like (measured against ground truth)\n\n");
    md.push_str(&format!(
        "Over the {} ranges inside the ground-truth span, `range - true distance` has mean \
         {} m, std {} m, median {} m, robust sigma (1.4826 MAD) {} m, min {} m, max {} m. \
         Against a constant bias this looks like a wide, skewed error. It is not: the error \
         grows with distance. A least-squares line gives `error = {} + {} d` (a {} % scale \
         error, almost no constant offset), and around that line the residuals have std \
         {} m, kurtosis {} (3 for a Gaussian) and {} % of them lie beyond 3 std. Per beacon \
         the median error is {}. So this log's ranges are mostly *scaled*, and the apparent \
         heavy tail of the error against a constant offset comes from the spread of \
         distances, not from outliers. The filters never see these numbers: they are \
         only used here to judge what the filters learn.\n\n",
        a.n,
        f(a.mean, 3),
        f(a.std, 3),
        f(a.median, 3),
        f(a.robust_sigma, 3),
        f(a.min_max.0, 2),
        f(a.min_max.1, 2),
        f(a.fit.0, 3),
        f(a.fit.1, 4),
        f(100.0 * a.fit.1, 2),
        f(a.fit_std, 3),
        f(a.fit_kurtosis, 2),
        f(100.0 * a.fit_beyond_3sigma, 2),
        a.per_beacon
            .iter()
            .map(|(id, n, m)| format!("id {id}: {} m (n = {n})", f(*m, 2)))
            .collect::<Vec<_>>()
            .join(", "),
    ));

    md.push_str("### Range bias: calibration states\n\n");
    md.push_str(&format!(
        "The filter state is `(x, y, heading, o, s)` with the range model \
         `h = (1 + s) |p - b| + o` (`[ranges] calibration = \"{}\"`). Both calibration \
         states start at **0** with wide priors (sigma {} m and {}) and follow slow random \
         walks ({} m/sqrt(s), {} /sqrt(s)); nothing is initialised from this file. They are \
         observable because the robot sees several beacons at different distances while \
         it moves. An offset-only state (the textbook \"range bias\") is run as an \
         ablation: it can only fit the mean error and leaves a distance-dependent error of \
         about +/- {} m over the distances seen.\n\n",
        s.calibration.name(),
        f(s.offset_prior_sigma, 1),
        f(s.scale_prior_sigma, 2),
        s.offset_random_walk,
        s.scale_random_walk,
        f(
            0.5 * a.fit.1
                * (a.samples.iter().map(|x| x.1).fold(0.0, f64::max)
                    - a.samples.iter().map(|x| x.1).fold(f64::INFINITY, f64::min)),
            1
        ),
    ));
    md.push_str("### Outliers: robust down-weighting that cannot lock out\n\n");
    md.push_str(&format!(
        "Each range's normalized innovation `e = nu / sqrt(S)` (`S = H P H^T + R` at the \
         prior) decides its treatment: `|e| <= {k}`: a normal update; `{k} < |e| <= {rj}`: \
         Huber down-weighting, the update uses the variance `R |e| / {k}`, so a wrong range \
         moves the state by a bounded amount instead of being either swallowed or thrown \
         away; `|e| > {rj}`: rejected (gross errors only). A filter that is wrong and too \
         confident would reject everything from then on (lock-out), or let ranges through \
         only with tiny weights while each of them still shrinks `P` (a crawl back). Here \
         every run of {n} consecutive ranges that are rejected or down-weighted, overall or \
         from one beacon (a lock-out can be partial: beacons that do not see the error keep \
         agreeing), multiplies the state covariance by {inf}, so the gate widens until the \
         ranges are accepted again. For a consistent filter such a run has probability \
         about P(|N(0,1)| > {k})^{n}, so it practically never fires when nothing is wrong. \
         The unit test `robust::tests::hard_gating_locks_out_and_recovery_does_not` starts \
         a filter 8 m off with a tiny covariance: the hard gate alone rejects every range \
         and stays 8 m off, the robust filter recovers to centimetres. The hard-gate \
         ablation uses paper B's gate alone (reject beyond {hg} sigma, nothing else).\n\n",
        k = f(s.huber_k, 1),
        rj = f(s.reject_sigma, 1),
        n = s.recovery_after,
        inf = f(s.recovery_inflation, 1),
        hg = f(s.hard_gate_sigma, 1),
    ));
    md.push_str(&format!(
        "### Time and ids\n\nAll computations use times relative to t0 = the first \
         ground-truth stamp: odometry rates are increments over stamp differences, the \
         SC/SI epochs are `k x {} s` after t0, the evaluation instants are ground-truth \
         stamps minus t0. Absolute stamps never enter the filter, so shifting the whole \
         clock changes nothing but the rounding of the shifted stamps (about 1e-12 s at \
         t ~ 1e4 s). Beacons are filter channels by their row in `TL`; ids are only used \
         to look ranges up, so renumbering the beacons changes nothing. The end-to-end test \
         checks both on a modified copy of the data.\n\n",
        s.epoch
    ));

    md.push_str("### Methods and ablation\n\n");
    let dr_mean = r.method("DR").map_or(f64::NAN, |m| m.stats.mean);
    let rows: Vec<Vec<String>> = r
        .methods
        .iter()
        .map(|m| {
            let (cal, out) = match &m.variant {
                None => ("-".to_string(), "-".to_string()),
                Some(v) => (v.calibration.name().to_string(), outlier_words(v.outliers)),
            };
            vec![
                m.name.clone(),
                cal,
                out,
                f(m.stats.mean, 3),
                f(m.stats.std, 3),
                f(m.stats.max, 3),
                f(m.stats.rmse, 3),
                format!("{} %", f(100.0 * (1.0 - m.stats.mean / dr_mean), 1)),
                m.accepted.to_string(),
                m.downweighted.to_string(),
                m.rejected.to_string(),
                m.dropped.to_string(),
                m.recoveries.to_string(),
            ]
        })
        .collect();
    md.push_str(&md_table(
        &[
            "method",
            "calibration",
            "outliers",
            "mean [m]",
            "std [m]",
            "max [m]",
            "RMSE [m]",
            "below DR",
            "accepted",
            "down-weighted",
            "rejected",
            "superseded",
            "recoveries",
        ],
        &rows,
    ));
    md.push('\n');
    md.push_str(&ablation_text(r));
    md.push_str(&format!(
        "\nSC uses the full range covariance with common-mode sigma {} m; with the \
         calibration states carrying the common error this is set to 0 and SC's stacked \
         update equals SI's sequential one. On this log ranges arrive one at a time (about \
         {} per second, a beacon every ~{} s), so an epoch of {} s rarely holds more than \
         one range and the three schemes differ mainly in when a range is applied (its own \
         stamp for AS, the next epoch for SC/SI). \"superseded\" counts SC/SI ranges replaced by a \
         newer range of the same beacon in the same epoch window (paper B's rule: the newest \
         sample per sensor and epoch).\n",
        s.correlation_sigma,
        f(
            p.ranges.len() as f64 / p.eval.last().map_or(1.0, |e| e.0),
            2
        ),
        f(
            p.eval.last().map_or(1.0, |e| e.0) / p.ranges.len().max(1) as f64,
            2
        ),
        s.epoch,
    ));
    md
}

fn ablation_text(r: &PlazaReplay) -> String {
    let base = r.settings.ablation_scheme.short_name();
    let get = |suffix: &str| {
        if suffix.is_empty() {
            r.method(base)
        } else {
            r.method(&format!("{base}-{suffix}"))
        }
    };
    let mut md = String::from("What each piece buys (ablations of ");
    md.push_str(base);
    md.push_str("):\n\n");
    if let (Some(full), Some(nb)) = (get(""), get("no-bias")) {
        md.push_str(&format!(
            "- **Range calibration.** Without calibration states the filter believes ranges \
             that are metres too long: mean error {} m, max {} m, against {} m / {} m with \
             them.\n",
            f(nb.stats.mean, 3),
            f(nb.stats.max, 3),
            f(full.stats.mean, 3),
            f(full.stats.max, 3),
        ));
    }
    if let (Some(full), Some(off)) = (get(""), get("offset-only")) {
        md.push_str(&format!(
            "- **Scale state.** With an offset only: mean {} m, max {} m; the offset \
             settles near the distance-averaged error and the distance-dependent part \
             stays in the position.{}\n",
            f(off.stats.mean, 3),
            f(off.stats.max, 3),
            if off.stats.mean > full.stats.mean {
                " Adding the scale state removes it."
            } else {
                " On this log the scale state does not improve the mean error."
            }
        ));
    }
    if let (Some(full), Some(hg)) = (get(""), get("hard-gate")) {
        md.push_str(&format!(
            "- **Robust handling, calibrated ranges.** Hard gating only: mean {} m, max {} m, \
             {} ranges rejected; robust: {} m / {} m, {} rejected, {} down-weighted. Once \
             the calibration is learned the residuals are close to Gaussian, so both treat \
             almost all ranges alike.\n",
            f(hg.stats.mean, 3),
            f(hg.stats.max, 3),
            hg.rejected,
            f(full.stats.mean, 3),
            f(full.stats.max, 3),
            full.rejected,
            full.downweighted,
        ));
    }
    if let (Some(nb), Some(nbhg)) = (get("no-bias"), get("no-bias-hard-gate")) {
        md.push_str(&format!(
            "- **Robust handling, biased ranges.** Without calibration the ranges disagree \
             with the state by metres, and the hard gate rejects {} ranges (mean error {} m, \
             max {} m); the robust filter down-weights {} and rejects {} ({} recoveries), \
             mean {} m, max {} m. This is the situation robust handling is for: a model that \
             does not fit (or a filter that has drifted) must still take information from \
             the measurements instead of locking itself out.\n",
            nbhg.rejected,
            f(nbhg.stats.mean, 3),
            f(nbhg.stats.max, 3),
            nb.downweighted,
            nb.rejected,
            nb.recoveries,
            f(nb.stats.mean, 3),
            f(nb.stats.max, 3),
        ));
    }
    md
}

/// A stand-alone `report.md` (for `fathom replay`): header, the summary table, the
/// claims, the report section and links to the figures in `dir`.
pub fn standalone_report(
    outputs: &PlazaOutputs,
    data_dir: &Path,
    config_label: &str,
    figures: &[PathBuf],
) -> String {
    let s = &outputs.summary;
    let mut md = format!(
        "# {}: range-beacon localization replay\n\nData: `{}` · settings: `{}`\n\n",
        s.experiment,
        data_dir.display(),
        config_label
    );
    md.push_str("## Results\n\n");
    md.push_str(&summary_md_table(s, 4));
    md.push_str("\n## Claims\n\n");
    md.push_str(&claims_md_table(s));
    md.push_str("\n## Notes\n\n");
    md.push_str(outputs.report_section.trim());
    md.push_str("\n\n## Figures\n\n");
    for p in figures {
        if let Some(n) = p.file_name().map(|n| n.to_string_lossy().into_owned()) {
            md.push_str(&format!("- [{n}]({n})\n"));
        }
    }
    md
}

/// Writes `summary.json` and a stand-alone `report.md` into `dir` (the experiment
/// driver writes its own).
///
/// # Errors
/// I/O and summary-check errors.
pub fn write_standalone(
    outputs: &PlazaOutputs,
    dir: &Path,
    data_dir: &Path,
    config_label: &str,
) -> Result<(), SimError> {
    write_summary_json(dir.join("summary.json"), &outputs.summary)?;
    let mut figures: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| SimError::io("list directory", dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().and_then(|x| x.to_str()) == Some("svg"))
        .collect();
    figures.sort();
    write_text(
        dir.join("report.md"),
        &standalone_report(outputs, data_dir, config_label, &figures),
    )
}

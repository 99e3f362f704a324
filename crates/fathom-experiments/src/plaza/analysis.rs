//! The Plaza rows and claims (one deterministic replay: no Monte Carlo, no CIs; the
//! only reference numbers are the GTSAM batch smoother's, on the smoothed rows).

use fathom_replay::plaza::{Calibration, MethodRun, PlazaReplay};
use fathom_report::output::{Claim, Row, fixed as f};
use fathom_sim::experiment::Analysis;

/// Required reduction of the mean error against dead reckoning.
pub const REQUIRED_REDUCTION: f64 = 0.35;
/// Largest acceptable maximum error of a scheme, m.
pub const MAX_ERROR_LIMIT_M: f64 = 4.0;
/// The main methods, in report order.
pub const MAIN_METHODS: [&str; 3] = ["AS", "SC", "SI"];

/// The GTSAM batch smoother on Plaza1 with known beacons and a range offset/scale
/// calibration (issue #24): mean, max and RMSE of the 2D error, m. A reference for the
/// smoothed rows (their `paper` column), never an output.
pub const GTSAM_BATCH_M: [(&str, f64); 3] = [("mean", 0.164), ("max", 0.889), ("rmse", 0.205)];
/// Target of the smoothed mean 2D error with the filter's settings, m.
pub const SMOOTHED_TARGET_M: f64 = 0.20;

/// The method name of a smoothed run (`AS+RTS`).
pub fn smoothed_name(method: &str) -> String {
    format!("{method}+RTS")
}

/// The `summary.json` rows (per method `mean`, `std`, `max`, `rmse` of the 2D position
/// error and `rejected`; the range analysis) and the claims.
pub(super) fn rows_and_claims(r: &PlazaReplay, s: &mut Analysis) {
    for (metric, unit) in [
        ("mean", "m"),
        ("std", "m"),
        ("max", "m"),
        ("rmse", "m"),
        ("rejected", "count"),
        ("error_mean", "m"),
        ("error_std", "m"),
        ("fit_offset", "m"),
        ("fit_scale", "1"),
        ("fit_residual_std", "m"),
        ("fit_residual_kurtosis", "1"),
    ] {
        s.unit(metric, unit);
    }
    for m in &r.methods {
        s.row(Row::new(&m.name, "mean", m.stats.mean));
        s.row(Row::new(&m.name, "std", m.stats.std));
        s.row(Row::new(&m.name, "max", m.stats.max));
        s.row(Row::new(&m.name, "rmse", m.stats.rmse));
        s.row(Row::new(&m.name, "rejected", m.rejected as f64));
    }
    // The RTS-smoothed runs (`smooth = true`): the same statistics; the main methods
    // (calibrated, robust) carry the GTSAM batch smoother's numbers as reference.
    for m in &r.methods {
        if let Some(sm) = &m.smoothed {
            let name = smoothed_name(&m.name);
            let main = MAIN_METHODS.contains(&m.name.as_str());
            let reference = |metric: &str| {
                GTSAM_BATCH_M
                    .iter()
                    .find(|(k, _)| main && *k == metric)
                    .map(|(_, v)| *v)
            };
            s.row(Row::new(&name, "mean", sm.stats.mean).with_paper(reference("mean")));
            s.row(Row::new(&name, "std", sm.stats.std));
            s.row(Row::new(&name, "max", sm.stats.max).with_paper(reference("max")));
            s.row(Row::new(&name, "rmse", sm.stats.rmse).with_paper(reference("rmse")));
        }
    }
    let a = &r.analysis;
    let g = "ranges-vs-GT";
    s.row(Row::new(g, "error_mean", a.mean));
    s.row(Row::new(g, "error_std", a.std));
    s.row(Row::new(g, "fit_offset", a.fit.0));
    s.row(Row::new(g, "fit_scale", a.fit.1));
    s.row(Row::new(g, "fit_residual_std", a.fit_std));
    s.row(Row::new(g, "fit_residual_kurtosis", a.fit_kurtosis));
    for c in claims(r) {
        s.claim(c);
    }
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
    let smoothed: Vec<(&MethodRun, f64)> = mains
        .iter()
        .filter_map(|m| m.smoothed.as_ref().map(|sm| (*m, sm.stats.mean)))
        .collect();
    if !smoothed.is_empty() {
        out.push(Claim::new(
            "smoothed_mean_at_most_0_20m",
            format!(
                "the RTS-smoothed mean 2D error of every scheme is at most {} m (same settings \
                 as the filter; GTSAM batch reference {} m)",
                f(SMOOTHED_TARGET_M, 2),
                f(GTSAM_BATCH_M[0].1, 3)
            ),
            smoothed.iter().all(|(_, v)| *v <= SMOOTHED_TARGET_M),
            smoothed
                .iter()
                .map(|(m, v)| {
                    format!(
                        "{} {} m (filtered {} m)",
                        smoothed_name(&m.name),
                        f(*v, 3),
                        f(m.stats.mean, 3)
                    )
                })
                .collect::<Vec<_>>()
                .join(", "),
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

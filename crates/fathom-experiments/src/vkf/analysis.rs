//! The `vkf` analysis: per-method horizontal-error metrics over runs, the VKF's
//! scale-factor and bias errors, the INS-DVL error growth, the literal-bias batch,
//! the rows and the claims.

use fathom_stats::{Quartiles, mean_and_ci95, median_ci, paired_mean_ci, rms};

use super::Prepared;
use super::sim::{GATED, INS_DVL, METHODS, PINS, RunOutput, VKF};
use fathom_report::output::{Claim, Row, fixed as f};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

/// RMS of a series (0 for an empty one).
fn rms_of(v: &[f64]) -> f64 {
    rms(v).unwrap_or(0.0)
}

/// RMS over runs of the VKF bias error at the first invalid interval (NaN when there
/// is none).
fn first_interval_bias_rms(runs: &[RunOutput]) -> f64 {
    let b: Vec<f64> = runs
        .iter()
        .filter_map(|r| r.bias_error.first().copied())
        .collect();
    rms(&b).unwrap_or(f64::NAN)
}

/// Whether a per-run statistic is too heavy-tailed for the Student-t interval of its
/// mean to mean much: the mean exceeds twice the median, or the interval reaches
/// below zero although every value is non-negative.
pub(super) fn is_heavy_tailed(values: &[f64]) -> Result<bool, SimError> {
    let (mean, ci) = mean_and_ci95(values)?;
    let median = fathom_stats::median(values)?;
    Ok(mean > 2.0 * median || (ci[0] < 0.0 && values.iter().all(|&v| v >= 0.0)))
}

/// What the gated INS-DVL did.
pub(super) struct GatedStats {
    /// Mean share of the DVL outputs without bottom lock it rejected.
    pub(super) rejected_invalid: f64,
    /// Mean share of the valid DVL outputs it rejected.
    pub(super) rejected_valid: f64,
    /// Runs in which it rejected more than half of the valid outputs.
    pub(super) lockouts: usize,
    /// Quartiles of its per-run `final_h`.
    pub(super) final_h: Quartiles,
    /// Mean of its per-run `final_h`.
    pub(super) final_h_mean: f64,
}

/// The tables and numbers the report prints.
pub(super) struct Tables {
    pub(super) table: Vec<Vec<String>>,
    pub(super) sfb_table: Vec<Vec<String>>,
    pub(super) literal_table: Vec<Vec<String>>,
    /// Per method: mean `final_h` with the default and with the literal bias, over the
    /// literal batch's runs.
    pub(super) lit_finals: Vec<(f64, f64)>,
    /// RMS of the VKF bias error at the first interval, literal batch.
    pub(super) lit_b_rms: f64,
    /// The same in the main batch.
    pub(super) default_b_rms: f64,
    pub(super) literal_runs: usize,
    pub(super) gated: GatedStats,
}

/// Per-run scalar metrics of one method.
pub(super) struct MethodMetrics {
    pub(super) final_h: Vec<f64>,
    pub(super) rms_h: Vec<f64>,
    pub(super) rms_vel: Vec<f64>,
}

pub(super) fn metrics(runs: &[RunOutput], m: usize) -> MethodMetrics {
    MethodMetrics {
        final_h: runs
            .iter()
            .map(|r| *r.err_h[m].last().unwrap_or(&0.0))
            .collect(),
        rms_h: runs.iter().map(|r| rms_of(&r.err_h[m])).collect(),
        rms_vel: runs.iter().map(|r| rms_of(&r.err_v[m])).collect(),
    }
}

/// Mean over runs of a per-time series.
pub(super) fn mean_series(runs: &[RunOutput], m: usize) -> Vec<f64> {
    let n = runs[0].err_h[m].len();
    (0..n)
        .map(|i| runs.iter().map(|r| r.err_h[m][i]).sum::<f64>() / runs.len() as f64)
        .collect()
}

/// Error growth (m/s) of `series` (1 Hz, from t = 0) inside and outside the
/// intervals: sum of `e(end) - e(start)` over the segments / their total length.
fn growth_rates(series: &[f64], invalid: &[(f64, f64)], duration: f64) -> (f64, f64) {
    let at = |t: f64| series[(t.round() as usize).min(series.len() - 1)];
    let mut bounds = vec![0.0];
    for &(a, b) in invalid {
        bounds.push(a);
        bounds.push(b);
    }
    bounds.push(duration);
    let (mut g_in, mut t_in, mut g_out, mut t_out) = (0.0, 0.0, 0.0, 0.0);
    for (i, w) in bounds.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        if b <= a {
            continue;
        }
        if i % 2 == 1 {
            g_in += at(b) - at(a);
            t_in += b - a;
        } else {
            g_out += at(b) - at(a);
            t_out += b - a;
        }
    }
    (
        if t_in > 0.0 { g_in / t_in } else { 0.0 },
        if t_out > 0.0 { g_out / t_out } else { 0.0 },
    )
}

/// Paired difference `a - b` per run: mean and 95 % CI.
fn paired(a: &[f64], b: &[f64]) -> Result<(f64, [f64; 2]), SimError> {
    let m = paired_mean_ci(a, b)?;
    Ok((m.mean, m.bounds()))
}

/// The unit of each per-method metric of the rows.
pub(super) const METHOD_UNITS: [(&str, &str); 5] = [
    ("final_h", "m"),
    ("rms_h", "m"),
    ("rms_vel", "m/s"),
    ("final_h_median", "m"),
    ("runs_final_h_beyond_threshold", "count"),
];

/// Computes the rows and the claims, and returns the tables the report is written from.
pub(super) fn analyse(
    p: &Prepared,
    runs: &[RunOutput],
    literal: &[RunOutput],
    out: &mut Analysis,
) -> Result<Tables, SimError> {
    let (c, shared) = (&p.c, &p.shared);
    for (metric, unit) in METHOD_UNITS.into_iter().chain([
        ("growth_rate_invalid", "m/s"),
        ("growth_rate_valid", "m/s"),
        ("final_h_minus_default", "m"),
    ]) {
        out.unit(metric, unit);
    }
    // Errors with a sign (the VKF's scale-factor and bias errors), growth rates (the
    // error may shrink) and paired differences.
    for metric in [
        "growth_rate_invalid",
        "growth_rate_valid",
        "final_h_minus_default",
    ] {
        out.signed(metric);
    }

    let all: Vec<MethodMetrics> = (0..METHODS.len()).map(|m| metrics(runs, m)).collect();
    let mut table = Vec::new();
    for (m, name) in METHODS.iter().enumerate() {
        let mut cells = vec![(*name).to_string()];
        for (metric, values) in [
            ("final_h", &all[m].final_h),
            ("rms_h", &all[m].rms_h),
            ("rms_vel", &all[m].rms_vel),
        ] {
            let row = out.runs_row(name, metric, values)?;
            let (mean, ci) = (row.value, row.ci95.unwrap_or([row.value; 2]));
            cells.push(format!("{} [{}, {}]", f(mean, 2), f(ci[0], 2), f(ci[1], 2)));
        }
        // The per-run final error is heavy-tailed for a method that loses lock in some
        // runs: its median with the order-statistics interval, and how many runs end
        // beyond the threshold, say more than the mean's t-interval.
        let med = median_ci(&all[m].final_h, 0.95)?;
        let mut row = Row::new(*name, "final_h_median", med.median);
        if let Some([lo, hi]) = med.interval {
            row = row.with_ci95(lo, hi, "order-statistic");
        }
        out.row(row);
        let beyond = all[m]
            .final_h
            .iter()
            .filter(|&&v| v > c.final_h_threshold)
            .count();
        out.row(Row::new(
            *name,
            "runs_final_h_beyond_threshold",
            beyond as f64,
        ));
        let heavy = is_heavy_tailed(&all[m].final_h)?;
        cells.push(if heavy {
            format!(
                "median {} {}; {beyond} of {} runs > {} m",
                f(med.median, 2),
                med.interval.map_or(
                    "(too few runs for a 95 % interval)".to_string(),
                    |[lo, hi]| { format!("[{}, {}]", f(lo, 2), f(hi, 2)) }
                ),
                all[m].final_h.len(),
                c.final_h_threshold
            )
        } else {
            "—".to_string()
        });
        table.push(cells);
    }

    // VKF sf / bias errors at the start of each invalid interval.
    let mut sfb_table = Vec::new();
    for i in 0..shared.invalid.len() {
        // Scale-factor error in % of the true k_rpm (the absolute value is ~1e-5
        // m/s per rpm, invisible at the table's 4 decimals).
        let sf: Vec<f64> = runs
            .iter()
            .filter_map(|r| r.sf_error.get(i).map(|e| 100.0 * e / c.rpm.k()))
            .collect();
        let b: Vec<f64> = runs
            .iter()
            .filter_map(|r| r.bias_error.get(i).copied())
            .collect();
        if sf.len() < 2 {
            continue;
        }
        let (sf_name, b_name) = (
            format!("sf_error_pct_{}", i + 1),
            format!("bias_error_{}", i + 1),
        );
        out.unit(sf_name.clone(), "%");
        out.unit(b_name.clone(), "m/s");
        out.signed(sf_name.clone());
        out.signed(b_name.clone());
        let sf_m = out.runs_row("VKF", &sf_name, &sf)?.value;
        let b_m = out.runs_row("VKF", &b_name, &b)?.value;
        sfb_table.push(vec![
            format!(
                "{} ({:.0}-{:.0} s)",
                i + 1,
                shared.invalid[i].0,
                shared.invalid[i].1
            ),
            format!("{:.4} %", sf_m),
            format!("{:.4} %", rms_of(&sf)),
            f(b_m, 4),
            f(rms_of(&b), 4),
        ]);
    }

    // INS-DVL error growth inside / outside the invalid intervals.
    let rates: Vec<(f64, f64)> = runs
        .iter()
        .map(|r| growth_rates(&r.err_h[INS_DVL], &shared.invalid, c.duration))
        .collect();
    let r_in: Vec<f64> = rates.iter().map(|r| r.0).collect();
    let r_out: Vec<f64> = rates.iter().map(|r| r.1).collect();
    let rin_m = out.runs_row("INS-DVL", "growth_rate_invalid", &r_in)?.value;
    let rout_m = out.runs_row("INS-DVL", "growth_rate_valid", &r_out)?.value;

    // Literal-bias configuration.
    let mut literal_table = Vec::new();
    let mut lit_finals: Vec<(f64, f64)> = Vec::new();
    let mut lit_b_rms = f64::NAN;
    if !literal.is_empty() {
        for (m, name) in METHODS.iter().enumerate() {
            let lm = metrics(literal, m);
            let dm = metrics(&runs[..literal.len()], m);
            let label = format!("{name} [b=0.5 m/s]");
            let interval = |r: &Row| (r.value, r.ci95.unwrap_or([r.value; 2]));
            let (fm, fci) = interval(out.runs_row(&label, "final_h", &lm.final_h)?);
            let (rm, rci) = interval(out.runs_row(&label, "rms_h", &lm.rms_h)?);
            // Same run streams in both batches: the change is a paired difference.
            let d: Vec<f64> = lm
                .final_h
                .iter()
                .zip(&dm.final_h)
                .map(|(a, b)| a - b)
                .collect();
            let (dd, dci) = interval(out.runs_row(&label, "final_h_minus_default", &d)?);
            let (dfm, _) = mean_and_ci95(&dm.final_h)?;
            let (drm, _) = mean_and_ci95(&dm.rms_h)?;
            lit_finals.push((dfm, fm));
            literal_table.push(vec![
                (*name).to_string(),
                f(dfm, 1),
                format!("{} [{}, {}]", f(fm, 1), f(fci[0], 1), f(fci[1], 1)),
                format!("{:+.1} [{:+.1}, {:+.1}]", dd, dci[0], dci[1]),
                f(drm, 1),
                format!("{} [{}, {}]", f(rm, 1), f(rci[0], 1), f(rci[1], 1)),
            ]);
        }
        let b: Vec<f64> = literal
            .iter()
            .filter_map(|r| r.bias_error.first().copied())
            .collect();
        if b.len() >= 2 {
            lit_b_rms = rms_of(&b);
            out.signed("bias_error_1");
            out.runs_row("VKF [b=0.5 m/s]", "bias_error_1", &b)?;
        }
    }

    // Claims.
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (d_final, d_final_ci) = paired(&all[VKF].final_h, &all[INS_DVL].final_h)?;
    let (_, d_rms_ci) = paired(&all[VKF].rms_h, &all[INS_DVL].rms_h)?;
    out.claim(Claim::new(
        "vkf_beats_ins_dvl",
        "VKF-aided navigation has a lower final and RMS horizontal error than INS-DVL",
        d_final_ci[1] < 0.0 && d_rms_ci[1] < 0.0,
        format!(
            "final: VKF {} m vs INS-DVL {} m (paired diff {} m, 95 % CI [{}, {}]); RMS: {} m vs {} m (diff CI [{}, {}])",
            f(mean(&all[VKF].final_h), 2),
            f(mean(&all[INS_DVL].final_h), 2),
            f(d_final, 2),
            f(d_final_ci[0], 2),
            f(d_final_ci[1], 2),
            f(mean(&all[VKF].rms_h), 2),
            f(mean(&all[INS_DVL].rms_h), 2),
            f(d_rms_ci[0], 2),
            f(d_rms_ci[1], 2)
        ),
    ));
    let (_, p_final_ci) = paired(&all[VKF].final_h, &all[PINS].final_h)?;
    let (_, p_rms_ci) = paired(&all[VKF].rms_h, &all[PINS].rms_h)?;
    out.claim(Claim::new(
        "vkf_beats_pins",
        "VKF-aided navigation has a lower final and RMS horizontal error than pure INS",
        p_final_ci[1] < 0.0 && p_rms_ci[1] < 0.0,
        format!(
            "final: VKF {} m vs PINS {} m; RMS: {} m vs {} m (paired-difference CIs below zero: {}, {})",
            f(mean(&all[VKF].final_h), 2),
            f(mean(&all[PINS].final_h), 1),
            f(mean(&all[VKF].rms_h), 2),
            f(mean(&all[PINS].rms_h), 1),
            p_final_ci[1] < 0.0,
            p_rms_ci[1] < 0.0
        ),
    ));
    let ratio = if rout_m > 0.0 {
        rin_m / rout_m
    } else {
        f64::INFINITY
    };
    out.claim(Claim::new(
        "ins_dvl_degrades_when_invalid",
        "INS-DVL's horizontal error grows at least 5x faster in the invalid intervals than elsewhere",
        rin_m > 0.0 && ratio >= 5.0,
        format!(
            "growth {} m/s inside vs {} m/s outside the invalid intervals (ratio {}; mean over runs of per-run rates)",
            f(rin_m, 4),
            f(rout_m, 5),
            if ratio.is_finite() { f(ratio, 1) } else { "inf".into() }
        ),
    ));
    let pins_mean = mean_series(runs, PINS);
    let mid = pins_mean[pins_mean.len() / 2];
    let pins_final = mean(&all[PINS].final_h);
    let others_max = (1..METHODS.len())
        .map(|m| mean(&all[m].final_h))
        .fold(0.0_f64, f64::max);
    out.claim(Claim::new(
        "pins_diverges",
        "pure INS error keeps growing (final > 2x mid-run) and ends worse than every aided method",
        pins_final > 2.0 * mid && pins_final > others_max,
        format!(
            "PINS mean horizontal error {} m at mid-run, {} m at the end; worst aided final {} m",
            f(mid, 1),
            f(pins_final, 1),
            f(others_max, 1)
        ),
    ));

    let gated = GatedStats {
        rejected_invalid: mean(
            &runs
                .iter()
                .map(|r| r.gated_rejected_invalid)
                .collect::<Vec<_>>(),
        ),
        rejected_valid: mean(
            &runs
                .iter()
                .map(|r| r.gated_rejected_valid)
                .collect::<Vec<_>>(),
        ),
        lockouts: runs.iter().filter(|r| r.gated_rejected_valid > 0.5).count(),
        final_h: Quartiles::of(&all[GATED].final_h)?,
        final_h_mean: mean(&all[GATED].final_h),
    };
    Ok(Tables {
        table,
        sfb_table,
        literal_table,
        lit_finals,
        lit_b_rms,
        default_b_rms: first_interval_bias_rms(runs),
        literal_runs: literal.len(),
        gated,
    })
}

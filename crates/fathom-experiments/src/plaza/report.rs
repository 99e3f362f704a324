//! The Plaza report text: the data, what the ranges are like, the treatment of range
//! bias and outliers, time and ids, the methods and ablations. Every number and every
//! conclusion comes from the replay.

use super::analysis::{GTSAM_BATCH_M, MAIN_METHODS, SMOOTHED_TARGET_M, smoothed_name};
use fathom_replay::plaza::{OutlierHandling, PlazaReplay};
use fathom_report::output::{fixed as f, md_table};

fn outlier_words(o: OutlierHandling) -> String {
    match o {
        OutlierHandling::Robust => "Huber + recovery".into(),
        OutlierHandling::HardGate(g) => format!("hard gate {g} sigma"),
    }
}

/// The report section: data, treatment of range bias and outliers, time handling,
/// method and ablation tables with their interpretation.
pub(super) fn report_section(r: &PlazaReplay) -> String {
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
                fathom_data::plaza::RangeOrder::Sort => "sort",
                fathom_data::plaza::RangeOrder::Strict => "strict",
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
    // The two parts of the fitted range error at the median true distance.
    let mut dists: Vec<f64> = a.samples.iter().map(|x| x.1).collect();
    dists.sort_by(f64::total_cmp);
    let d_median = dists.get(dists.len() / 2).copied().unwrap_or(0.0);
    let scale_part = a.fit.1 * d_median;
    let mostly_scaled = scale_part.abs() > a.fit.0.abs();
    let gaussian_residuals = a.fit_kurtosis < 4.0;
    md.push_str(&format!(
        "Over the {} ranges inside the ground-truth span, `range - true distance` has mean \
         {} m, std {} m, median {} m, robust sigma (1.4826 MAD) {} m, min {} m, max {} m. A \
         least-squares line gives `error = {} + {} d` (a {} % scale error): at the median \
         true distance {} m the scale part is {} m and the constant part {} m, so the error \
         is mostly {}. Around that line the residuals have std {} m, kurtosis {} (3 for a \
         Gaussian) and {} % of them lie beyond 3 std{}. Per beacon the median error is {}. \
         The filters never see these numbers: they are only used here to judge what the \
         filters learn.\n\n",
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
        f(d_median, 1),
        f(scale_part, 3),
        f(a.fit.0, 3),
        if mostly_scaled {
            "a scale error"
        } else {
            "a constant offset"
        },
        f(a.fit_std, 3),
        f(a.fit_kurtosis, 2),
        f(100.0 * a.fit_beyond_3sigma, 2),
        if gaussian_residuals {
            ": close to Gaussian once the line is removed, so the apparent heavy tail of the \
             error against a constant offset comes from the spread of distances"
        } else {
            ": heavier-tailed than a Gaussian even after the line is removed (outliers)"
        },
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
    let span = p.eval.last().map_or(1.0, |e| e.0);
    let per_second = p.ranges.len() as f64 / span;
    let per_epoch = per_second * s.epoch;
    md.push_str(&format!(
        "\nSC uses the full range covariance with common-mode sigma {} m (0 makes SC's \
         stacked update equal SI's sequential one). On this log ranges arrive at about {} per \
         second, {} per {} s epoch on average, so the schemes differ {} (its own stamp for \
         AS, the next epoch for SC/SI). \"superseded\" counts SC/SI ranges replaced by a \
         newer range of the same beacon in the same epoch window (paper B's rule: the newest \
         sample per sensor and epoch).\n",
        s.correlation_sigma,
        f(per_second, 2),
        f(per_epoch, 2),
        s.epoch,
        if per_epoch < 1.0 {
            "mainly in when a range is applied"
        } else {
            "in how the ranges of an epoch are combined and when they are applied"
        },
    ));
    md.push_str(&smoothing_text(r));
    md
}

/// The post-processing section (`smooth = true`): filtered and RTS-smoothed errors side
/// by side, the GTSAM batch reference, the memory of the forward pass. Empty when
/// smoothing is off.
fn smoothing_text(r: &PlazaReplay) -> String {
    let smoothed: Vec<_> = r
        .methods
        .iter()
        .filter_map(|m| m.smoothed.as_ref().map(|s| (m, s)))
        .collect();
    if smoothed.is_empty() {
        return String::new();
    }
    let reference = |metric: &str| {
        GTSAM_BATCH_M
            .iter()
            .find(|(k, _)| *k == metric)
            .map_or(f64::NAN, |(_, v)| *v)
    };
    let rows: Vec<Vec<String>> = smoothed
        .iter()
        .map(|(m, s)| {
            let main = MAIN_METHODS.contains(&m.name.as_str());
            let gtsam = |metric: &str| {
                if main {
                    f(reference(metric), 3)
                } else {
                    "-".to_string()
                }
            };
            vec![
                m.name.clone(),
                f(m.stats.mean, 3),
                f(m.stats.max, 3),
                f(m.stats.rmse, 3),
                smoothed_name(&m.name),
                f(s.stats.mean, 3),
                f(s.stats.max, 3),
                f(s.stats.rmse, 3),
                gtsam("mean"),
                gtsam("max"),
                gtsam("rmse"),
                format!("{} %", f(100.0 * (1.0 - s.stats.mean / m.stats.mean), 1)),
            ]
        })
        .collect();
    let mut md = String::from(
        "\n### Post-processing: RTS smoother (`smooth = true`)\n\nEach filter's forward \
         pass (transition Jacobian, predicted and filtered mean and covariance per step) \
         is smoothed backwards by the fixed-interval Rauch-Tung-Striebel smoother \
         (`fathom_estimators::smoother`): every estimate then uses every range of the log. \
         Same settings as the filter, no relinearization; rejected ranges stay rejected. \
         The GTSAM columns are the numbers of a GTSAM batch smoother with known beacons and \
         a range offset/scale calibration on Plaza1 (issue #24; a reference only, for the \
         calibrated robust schemes).\n\n",
    );
    md.push_str(&md_table(
        &[
            "filter",
            "mean [m]",
            "max [m]",
            "RMSE [m]",
            "smoothed",
            "mean [m]",
            "max [m]",
            "RMSE [m]",
            "GTSAM mean [m]",
            "GTSAM max [m]",
            "GTSAM RMSE [m]",
            "smoothing gain",
        ],
        &rows,
    ));
    let mains: Vec<f64> = smoothed
        .iter()
        .filter(|(m, _)| MAIN_METHODS.contains(&m.name.as_str()))
        .map(|(_, s)| s.stats.mean)
        .collect();
    if !mains.is_empty() {
        let worst = mains.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        md.push_str(&format!(
            "\nThe schemes' smoothed mean 2D error is at most {} m, {} the {} m target \
             (GTSAM batch: {} m).\n",
            f(worst, 3),
            if worst <= SMOOTHED_TARGET_M {
                "within"
            } else {
                "above"
            },
            f(SMOOTHED_TARGET_M, 2),
            f(reference("mean"), 3),
        ));
    }
    if let Some((_, s)) = smoothed.first() {
        md.push_str(&format!(
            "\nMemory: the forward pass of {} holds {} B per step (`8 (1 + 2 N + 3 N^2)` B for \
             `N` states); {} steps here (every prediction, update epoch and evaluation \
             instant), {} MB per filter.\n",
            smoothed[0].0.name,
            s.bytes_per_step,
            s.steps,
            f((s.steps * s.bytes_per_step) as f64 / 1e6, 1),
        ));
    }
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
             {} ranges rejected; robust: {} m / {} m, {} rejected, {} down-weighted; the \
             robust filter's mean error is {} the hard gate's.\n",
            f(hg.stats.mean, 3),
            f(hg.stats.max, 3),
            hg.rejected,
            f(full.stats.mean, 3),
            f(full.stats.max, 3),
            full.rejected,
            full.downweighted,
            if full.stats.mean < hg.stats.mean {
                "below"
            } else {
                "not below"
            },
        ));
    }
    if let (Some(nb), Some(nbhg)) = (get("no-bias"), get("no-bias-hard-gate")) {
        md.push_str(&format!(
            "- **Robust handling, biased ranges.** Without calibration the ranges disagree \
             with the state by metres, and the hard gate rejects {} ranges (mean error {} m, \
             max {} m); the robust filter down-weights {} and rejects {} ({} recoveries), \
             mean {} m, max {} m: with a model that does not fit, robust handling {} than \
             hard gating here.\n",
            nbhg.rejected,
            f(nbhg.stats.mean, 3),
            f(nbhg.stats.max, 3),
            nb.downweighted,
            nb.rejected,
            nb.recoveries,
            f(nb.stats.mean, 3),
            f(nb.stats.max, 3),
            if nb.stats.mean < nbhg.stats.mean {
                "does better"
            } else {
                "does not do better"
            },
        ));
    }
    md
}

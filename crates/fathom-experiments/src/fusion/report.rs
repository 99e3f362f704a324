//! The report section of the `fusion` experiment: both readings of the paper's tuning
//! side by side (Tables 2 and 3, where the error comes from, ablations, course
//! changes, sensitivity), the outcome chosen from the numbers of both, the
//! interpretation decisions and the paper's inconsistencies.

use fathom_stats::mean_and_ci95;
use fathom_traj::FusionMission;

use super::analysis::{
    ReadingRuns, RunResult, SWEEP_METHODS, SweepResult, paired, paper_values, values,
};
use super::figures::FILTERS;
use super::scenario::FusionSetup;
use super::sim::{Method, Reading};
use fathom_report::output::{fixed as f, md_table};
use fathom_sim::SimError;

fn ci_str(c: [f64; 2], d: usize) -> String {
    format!("[{}, {}]", f(c[0], d), f(c[1], d))
}

fn signed_ci(mean: f64, c: [f64; 2]) -> String {
    format!("{:+.2e} [{:+.2e}, {:+.2e}]", mean, c[0], c[1])
}

/// Largest `|a - b|` of the sweep means over the sweep values.
fn max_gap(sw: &SweepResult, a: Method, b: Method) -> f64 {
    let ja = SWEEP_METHODS.iter().position(|&x| x == a);
    let jb = SWEEP_METHODS.iter().position(|&x| x == b);
    match (ja, jb) {
        (Some(ja), Some(jb)) => sw
            .means
            .iter()
            .map(|row| (row[ja].0 - row[jb].0).abs())
            .fold(0.0, f64::max),
        _ => f64::NAN,
    }
}

/// Mean over runs of a metric.
fn mean(results: &[RunResult], m: Method, metric: &str) -> Result<f64, SimError> {
    Ok(mean_and_ci95(&values(results, m, metric))?.0)
}

/// What a reading makes of the paper's letters, in words and numbers.
fn tuning_words(r: &ReadingRuns<'_>) -> String {
    let t = &r.cfg.tuning;
    match r.reading {
        Reading::BarShalom => format!(
            "`R_INS = {}^2`, `R_DVL = {}^2` m^2; discrete white-noise-acceleration `Q` with \
             acceleration std {} m/s^2 (INS filter) and {} m/s^2 (DVL filter); MF: {} m/s^2",
            t.w_ins, t.w_dvl, t.v_ins, t.v_dvl, t.mf_accel_sigma
        ),
        Reading::AsPrinted => format!(
            "`Q = w^2 I6` with w_INS = {} m, w_DVL = {} m; `R = v^2 I3` with v_INS = {} m, \
             v_DVL = {} m (m/s^2 read as m); MF: `Q = {}^2 I6`",
            t.w_ins, t.w_dvl, t.v_ins, t.v_dvl, t.w_mf
        ),
    }
}

/// Paper A's Tables 2 and 3 with both readings side by side.
fn tables(readings: &[ReadingRuns<'_>]) -> Result<String, SimError> {
    let mut s = String::new();
    for (title, mean_key, std_key, pidx) in [
        (
            "Table 2 (3D distance error, m)",
            "mean_3d",
            "std_3d",
            0usize,
        ),
        (
            "Table 3 (2D x-y distance error, m)",
            "mean_2d",
            "std_2d",
            2usize,
        ),
    ] {
        s.push_str(&format!(
            "### {title}: paper | each reading (mean [95 % CI])\n\n"
        ));
        let mut headers = vec!["method".to_string(), "mean (paper)".into()];
        for r in readings {
            headers.push(format!("mean, {}", r.reading.name()));
        }
        headers.push("std (paper)".into());
        for r in readings {
            headers.push(format!("std, {}", r.reading.name()));
        }
        let mut rows = Vec::new();
        for m in Method::ALL {
            let p = paper_values(m);
            let ps = |k: usize| p.map_or("—".to_string(), |p| f(p[k], 2));
            let mut row = vec![m.name().to_string(), ps(pidx)];
            for r in readings {
                let (mm, mc) = mean_and_ci95(&values(r.results, m, mean_key))?;
                row.push(format!("{} {}", f(mm, 3), ci_str(mc, 3)));
            }
            row.push(ps(pidx + 1));
            for r in readings {
                let (sm, sc) = mean_and_ci95(&values(r.results, m, std_key))?;
                row.push(format!("{} {}", f(sm, 3), ci_str(sc, 3)));
            }
            rows.push(row);
        }
        let h: Vec<&str> = headers.iter().map(String::as_str).collect();
        s.push_str(&md_table(&h, &rows));
        s.push('\n');
    }
    Ok(s)
}

/// Where each method's error comes from, under one reading.
fn error_sources(r: &ReadingRuns<'_>) -> Result<String, SimError> {
    let results = r.results;
    let t = &r.cfg.tuning;
    let dvl = mean(results, Method::DvlDr, "mean_3d")?;
    let ins = mean(results, Method::InsOnly, "mean_3d")?;
    let mut s = format!(
        "#### Reading `{}` ({})\n\n",
        r.reading.name(),
        tuning_words(r)
    );
    let mut rows = Vec::new();
    let mut largest_gap = 0.0_f64;
    for m in FILTERS {
        let (d, dc) = paired(results, m, Method::DvlDr, "mean_3d")?;
        largest_gap = largest_gap.max(d.abs());
        rows.push(vec![
            m.name().to_string(),
            f(mean(results, m, "mean_3d")?, 4),
            signed_ci(d, dc),
            f(mean(results, m, "final_3d")?, 3),
            f(mean(results, m, "max_3d")?, 3),
        ]);
    }
    s.push_str(&md_table(
        &[
            "method",
            "mean 3D (m)",
            "minus DVL-DR, paired (m) [95 % CI]",
            "last 10 % mean 3D (m)",
            "max 3D (m)",
        ],
        &rows,
    ));
    // The INS weight of the equalization and the DVL track's steady gain.
    let (r_ins, r_dvl) = match t.reading {
        Reading::BarShalom => (t.w_ins.powi(2), t.w_dvl.powi(2)),
        Reading::AsPrinted => (t.v_ins.powi(2), t.v_dvl.powi(2)),
    };
    let w_ins = r_dvl / (r_ins + r_dvl);
    s.push_str(&format!(
        "\nThe unaided INS drifts to a mean 3D error of {} m and the DVL dead reckoning to \
         {} m. The equalization weight of the INS is `R_DVL / (R_INS + R_DVL)` = {:.2e}. \
         The largest paired difference between a filter's mean 3D error and the DVL dead \
         reckoning's is {} m ({} % of the DVL's): {}.\n\n",
        f(ins, 2),
        f(dvl, 3),
        w_ins,
        f(largest_gap, 4),
        f(100.0 * largest_gap / dvl, 1),
        if largest_gap < 0.1 * dvl {
            "every filter's error is the DVL dead reckoning's plus a small correction, so the \
             structure of the fusion changes the result only at the level of column *minus \
             DVL-DR*"
        } else {
            "the fusion structure changes the result well beyond the DVL dead reckoning's \
             error (column *minus DVL-DR*)"
        },
    ));
    Ok(s)
}

/// `a` against `b` on the mean 3D error, in words, with the paired CI.
fn verdict(results: &[RunResult], a: Method, b: Method) -> Result<String, SimError> {
    let (d, c) = paired(results, a, b, "mean_3d")?;
    Ok(if c[1] < 0.0 {
        format!(
            "{} is lower than {} by {:.2e} m (paired CI [{:+.2e}, {:+.2e}])",
            a.name(),
            b.name(),
            -d,
            c[0],
            c[1]
        )
    } else if c[0] > 0.0 {
        format!(
            "{} is higher than {} by {:.2e} m (paired CI [{:+.2e}, {:+.2e}])",
            a.name(),
            b.name(),
            d,
            c[0],
            c[1]
        )
    } else {
        format!(
            "{} and {} do not differ significantly ({:+.2e} m, CI [{:+.2e}, {:+.2e}])",
            a.name(),
            b.name(),
            d,
            c[0],
            c[1]
        )
    })
}

/// Which step of EFF matters, under one reading.
fn ablation(r: &ReadingRuns<'_>) -> Result<String, SimError> {
    let results = r.results;
    let mut s = format!("#### Reading `{}`\n\n", r.reading.name());
    let mut rows = Vec::new();
    for (m, eq, fb) in [
        (Method::Eff, "yes", "yes"),
        (Method::EffNoFeedback, "yes", "no"),
        (Method::EffNoEqualization, "no", "yes"),
        (Method::T2t, "no", "no"),
    ] {
        let diff = if m == Method::Eff {
            "—".to_string()
        } else {
            let (d, c) = paired(results, m, Method::Eff, "mean_3d")?;
            signed_ci(d, c)
        };
        rows.push(vec![
            m.name().to_string(),
            eq.into(),
            fb.into(),
            f(mean(results, m, "mean_3d")?, 4),
            f(mean(results, m, "std_3d")?, 4),
            f(mean(results, m, "mean_2d")?, 4),
            f(mean(results, m, "turn_ratio_3d")?, 3),
            diff,
        ]);
    }
    s.push_str(&md_table(
        &[
            "variant",
            "equalize",
            "feedback",
            "mean 3D (m)",
            "std 3D (m)",
            "mean 2D (m)",
            "turn ratio",
            "mean 3D minus EFF, paired [95 % CI]",
        ],
        &rows,
    ));
    s.push_str(&format!(
        "\nEqualization alone (EFF-no-feedback vs T2T): {}. Feedback alone \
         (EFF-no-equalization vs T2T): {}. Both (EFF vs T2T): {}. Extra rules: {}; {}.\n\n",
        verdict(results, Method::EffNoFeedback, Method::T2t)?,
        verdict(results, Method::EffNoEqualization, Method::T2t)?,
        verdict(results, Method::Eff, Method::T2t)?,
        verdict(results, Method::T2tBc, Method::T2t)?,
        verdict(results, Method::T2tCi, Method::T2t)?,
    ));
    Ok(s)
}

/// The filters whose mean turn ratio exceeds the limit, under one reading.
fn spiking(setup: &FusionSetup, r: &ReadingRuns<'_>) -> Result<Vec<String>, SimError> {
    let mut out = Vec::new();
    for m in FILTERS {
        let v = mean(r.results, m, "turn_ratio_3d")?;
        if v > setup.turn_ratio_limit {
            out.push(format!("{} {}", m.name(), f(v, 3)));
        }
    }
    Ok(out)
}

fn course_changes(
    setup: &FusionSetup,
    mission: &FusionMission,
    readings: &[ReadingRuns<'_>],
) -> Result<String, SimError> {
    let cc = mission.course_changes();
    let mut s = String::from("### Course-change analysis\n\n");
    s.push_str(&format!(
        "Detected course changes (heading change > {} deg, spline heading sampled every {} s): \
         {} s. The paper reports error spikes for MF near t = 210, 412, 430, 630, 810 s and for \
         T2T near t = 200, 257, 420, 435, 605, 629, 770, 808 s. `turn_ratio_3d` = mean 3D error \
         within +/- {} s of a course change divided by the mean elsewhere (per run, then \
         averaged).\n\n",
        f(setup.mission.params().min_course_change.to_degrees(), 0),
        setup.run.step,
        cc.iter().map(|c| f(*c, 1)).collect::<Vec<_>>().join(", "),
        setup.turn_half_window
    ));
    let mut headers = vec!["method".to_string()];
    for r in readings {
        headers.push(format!("turn ratio, {} [95 % CI]", r.reading.name()));
    }
    let mut rows = Vec::new();
    for m in Method::ALL {
        let mut row = vec![m.name().to_string()];
        for r in readings {
            let (v, c) = mean_and_ci95(&values(r.results, m, "turn_ratio_3d"))?;
            row.push(format!("{} {}", f(v, 3), ci_str(c, 3)));
        }
        rows.push(row);
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    s.push_str(&md_table(&h, &rows));
    s.push('\n');
    for r in readings {
        let spikes = spiking(setup, r)?;
        s.push_str(&format!(
            "Filters whose mean turn ratio exceeds the limit {} under `{}`: {} (DVL dead \
             reckoning: {}).\n",
            setup.turn_ratio_limit,
            r.reading.name(),
            if spikes.is_empty() {
                "none".to_string()
            } else {
                spikes.join(", ")
            },
            f(mean(r.results, Method::DvlDr, "turn_ratio_3d")?, 3),
        ));
    }
    s.push_str(
        "\nA constant-velocity filter lags at a turn when it trusts its motion model more than \
         its measurement; the DVL dead reckoning's ratio is set by where along the mission \
         the turns fall (its error grows with time, not with the manoeuvre).\n\n",
    );
    Ok(s)
}

fn sensitivity(r: &ReadingRuns<'_>) -> Result<String, SimError> {
    let mut s = format!("#### Reading `{}`\n\n", r.reading.name());
    for sw in &r.sweeps {
        s.push_str(&format!("Sweep of the {}:\n\n", sw.label));
        let mut headers = vec!["value".to_string()];
        headers.extend(SWEEP_METHODS.iter().map(|m| m.name().to_string()));
        let h: Vec<&str> = headers.iter().map(String::as_str).collect();
        let rows: Vec<Vec<String>> = sw
            .values
            .iter()
            .zip(&sw.means)
            .map(|(v, row)| {
                let mut r = vec![format!("{v}")];
                r.extend(row.iter().map(|(m, _)| f(*m, 3)));
                r
            })
            .collect();
        s.push_str(&md_table(&h, &rows));
        s.push('\n');
    }
    if let Some(sv) = r.sweeps.iter().find(|sw| sw.key == "filter_v_dvl") {
        let get = |row: &Vec<(f64, [f64; 2])>, m: Method| {
            SWEEP_METHODS
                .iter()
                .position(|&x| x == m)
                .map_or(f64::NAN, |j| row[j].0)
        };
        let paper_order: Vec<String> = sv
            .values
            .iter()
            .zip(&sv.means)
            .filter(|(_, row)| {
                get(row, Method::Eff) < get(row, Method::T2t)
                    && get(row, Method::T2t) < get(row, Method::Mf)
            })
            .map(|(v, row)| {
                format!(
                    "v_DVL = {v} (EFF {}, T2T {}, MF {})",
                    f(get(row, Method::Eff), 3),
                    f(get(row, Method::T2t), 3),
                    f(get(row, Method::Mf), 3)
                )
            })
            .collect();
        let nofb_mf = max_gap(sv, Method::EffNoFeedback, Method::Mf);
        let nofb_eff = max_gap(sv, Method::EffNoFeedback, Method::Eff);
        let noeq_eff = max_gap(sv, Method::EffNoEqualization, Method::Eff);
        let step = if noeq_eff < nofb_eff {
            "the feedback changes the result more than the equalization"
        } else if nofb_eff < noeq_eff {
            "the equalization changes the result more than the feedback"
        } else {
            "the two steps change the result equally"
        };
        s.push_str(&format!(
            "Largest gaps of the mean 3D error over the `v_DVL` sweep: EFF-no-feedback vs MF \
             {} m, EFF-no-feedback vs EFF {} m (what the feedback changes), \
             EFF-no-equalization vs EFF {} m (what the equalization changes): {}. The \
             paper's ordering EFF < T2T < MF appears {}.\n\n",
            f(nofb_mf, 3),
            f(nofb_eff, 3),
            f(noeq_eff, 3),
            step,
            if paper_order.is_empty() {
                "at no value of the sweep".to_string()
            } else {
                format!("at {}", paper_order.join("; "))
            },
        ));
    }
    Ok(s)
}

/// The ordering of MF, T2T and EFF under a reading, lowest first.
fn ordering(r: &ReadingRuns<'_>) -> Result<Vec<(&'static str, f64)>, SimError> {
    let mut order = vec![
        ("MF", mean(r.results, Method::Mf, "mean_3d")?),
        ("T2T", mean(r.results, Method::T2t, "mean_3d")?),
        ("EFF", mean(r.results, Method::Eff, "mean_3d")?),
    ];
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    Ok(order)
}

fn outcome(setup: &FusionSetup, readings: &[ReadingRuns<'_>]) -> Result<String, SimError> {
    let paper = |m: Method| paper_values(m).map_or(f64::NAN, |p| p[0]);
    let (pe, pt, pm) = (paper(Method::Eff), paper(Method::T2t), paper(Method::Mf));
    let mut s = format!(
        "### Outcome\n\nPaper (Table 2, mean 3D): EFF {pe} < T2T {pt} < MF {pm} m, MF / EFF = \
         {}.\n\n",
        f(pm / pe, 2)
    );
    let mut matching = Vec::new();
    for r in readings {
        let order = ordering(r)?;
        let same = order.iter().map(|o| o.0).collect::<Vec<_>>() == ["EFF", "T2T", "MF"];
        if same {
            matching.push(r.reading.name());
        }
        let get = |n: &str| order.iter().find(|o| o.0 == n).map_or(f64::NAN, |o| o.1);
        let spikes = spiking(setup, r)?;
        s.push_str(&format!(
            "- `{}`: {} m; the order {} the paper's; MF / EFF = {}; filters spiking at course \
             changes (turn ratio > {}): {}.\n",
            r.reading.name(),
            order
                .iter()
                .map(|(n, v)| format!("{n} {}", f(*v, 3)))
                .collect::<Vec<_>>()
                .join(" <= "),
            if same { "matches" } else { "does not match" },
            f(get("MF") / get("EFF"), 2),
            setup.turn_ratio_limit,
            if spikes.is_empty() {
                "none".to_string()
            } else {
                spikes.join(", ")
            },
        ));
    }
    s.push_str(&format!(
        "\nReadings under which the reproduced ordering matches the paper's: {}. The claims \
         above (scenario reading `{}`) state with paired 95 % intervals whether each \
         ordering is statistically resolved.\n\n",
        if matching.is_empty() {
            "none".to_string()
        } else {
            matching.join(", ")
        },
        setup.run.tuning.reading.name(),
    ));
    Ok(s)
}

fn decisions(setup: &FusionSetup, n: usize) -> String {
    let t = &setup.run.tuning;
    format!(
        "### Interpretation decisions\n\n\
         - Sensor models are not given by the paper (spec A defaults): INS double-integrates \
         `a + b_a + n_a` (bias std {} m/s^2 per run, noise std {} m/s^2 per sample); DVL \
         integrates `(1 + s) v + n_v` (`s ~ U(-{h}, {h})`, noise std {} m/s). Both start at the \
         true position and velocity and output positions at 1 Hz.\n\
         - State `[x, vx, y, vy, z, vz]`, constant-velocity `A` (T = {} s), `H` selects the \
         position. The printed tuning (w_INS = {} m, w_DVL = {} m, v_INS = {}, v_DVL = {}) is \
         read two ways, both run on the same seeds: `bar_shalom` (the notation of the \
         paper's references, Bar-Shalom and Li-Jilkov: `v` the white-acceleration process \
         noise in m/s^2, `w` the position measurement noise in m; every printed unit is \
         consistent) and `as_printed` (`Q = w^2 I6`, `R = v^2 I3`, with m/s^2 read as m and a \
         metre std on the velocity states). The scenario's reading is `{}`; its rows keep the \
         contract names, the other reading's rows carry the suffix `[reading]`.\n\
         - Filters start at the true initial state with `P0 = diag({}^2, {}^2, ...)` (position, \
         velocity); the paper gives no `P0`.\n\
         - EFF step 1 fuses the integrator states at k-1: INS position and velocity, DVL \
         position and its latest measured velocity, per axis with the scalar R weights \
         (eq. 9); step 2 sets both filters' state to `x_E` and keeps their `P`; step 4 resets \
         the INS integrator's position and velocity (bias and last acceleration sample kept).\n\
         - T2T-BC propagates the cross-covariance with the common-noise rule from the two \
         tracks' `Q`; T2T-CI minimizes the trace of the fused covariance.\n\
         - One mission (trajectory seed {}), {} noise realizations per reading; all methods \
         of a run see the same sensor noise (common random numbers), so differences between \
         methods are judged with paired 95 % CIs. A claim \"X is best\" (or \"X beats Y\") \
         holds only when the paired 95 % CI of X minus each competitor lies entirely below \
         -{} x the competitor's value (`analysis.min_relative_improvement`). The turn-ratio \
         claim compares the mean ratios with the limit {}.\n\
         - The {} +/- {} s zoom window shows run 0; histograms pool every run and time.\n\n",
        setup.ins_params.accel_bias_sigma,
        setup.ins_params.accel_noise_sigma,
        setup.dvl_params.vel_noise_sigma,
        setup.run.step,
        t.w_ins,
        t.w_dvl,
        t.v_ins,
        t.v_dvl,
        t.reading.name(),
        t.p0_pos,
        t.p0_vel,
        setup.trajectory_seed,
        n,
        setup.min_relative_improvement,
        setup.turn_ratio_limit,
        setup.zoom.0,
        setup.zoom.1,
        h = setup.dvl_params.scale_half_width,
    )
}

fn paper_inconsistencies() -> String {
    let mut s = String::from("### The paper's inconsistencies\n\n");
    s.push_str(
        "- The text gives EFF 1.34 m / 0.31 m (3D mean / std), Table 2 gives 1.38 m / 0.32 m; \
         the table is used as the reference.\n",
    );
    if let (Some(mf), Some(eff)) = (paper_values(Method::Mf), paper_values(Method::Eff)) {
        s.push_str(&format!(
            "- The \"% reduction\" figures are ratios, not reductions: {} -> {} m is a {} % \
             reduction, printed as \"37 %\" ({} / {} = {}).\n",
            mf[0],
            eff[0],
            f(100.0 * (1.0 - eff[0] / mf[0]), 0),
            eff[0],
            mf[0],
            f(eff[0] / mf[0], 3),
        ));
    }
    for m in Method::ALL {
        if let Some(p) = paper_values(m).filter(|p| p[2] > p[0]) {
            s.push_str(&format!(
                "- {}'s 2D mean ({} m, Table 3) exceeds its 3D mean ({} m, Table 2): impossible \
                 for one estimate, since the 2D error of an estimate never exceeds its 3D \
                 error.\n",
                m.name(),
                p[2],
                p[0]
            ));
        }
    }
    s.push_str(
        "- Eq. (1) defines a 9-state position-velocity-acceleration vector, but `A` is 6x6 \
         (position and velocity per axis); the 6-state model is implemented.\n\
         - The printed `H` (`[1 1 0 0 0 0; ...]`) adds position and velocity; it is read as a \
         position measurement (`H` selects x, y, z), as the sensors output positions.\n\
         - The tuning letters: printed in m/s^2 (\"1 g\" for `v_INS`) and m, consistent only \
         in the notation of the cited references (the `bar_shalom` reading).\n",
    );
    s
}

/// The whole report section.
pub(super) fn section(
    setup: &FusionSetup,
    mission: &FusionMission,
    readings: &[ReadingRuns<'_>],
) -> Result<String, SimError> {
    let n = readings.first().map_or(0, |r| r.results.len());
    let mut s = tables(readings)?;
    s.push_str(&format!(
        "Per run: mean and population std over the {} one-second samples t = {}..{} s; then \
         mean over {n} runs with a Student-t 95 % CI. `INS-only` and `DVL-DR` are the raw \
         integrated sensors (no filter), listed as references.\n\n",
        setup.run.n_steps,
        setup.run.step,
        setup.run.step * setup.run.n_steps as f64
    ));
    s.push_str("### Where each method's error comes from\n\n");
    for r in readings {
        s.push_str(&error_sources(r)?);
    }
    s.push_str("### Ablation: which step of EFF matters\n\n");
    for r in readings {
        s.push_str(&ablation(r)?);
    }
    s.push_str(&course_changes(setup, mission, readings)?);
    s.push_str(&format!(
        "### Sensitivity (mean 3D error, m; {} runs per value, same seeds for every value)\n\n",
        setup.sensitivity_runs
    ));
    for r in readings {
        s.push_str(&sensitivity(r)?);
    }
    s.push_str(&outcome(setup, readings)?);
    s.push_str(&decisions(setup, n));
    s.push_str(&paper_inconsistencies());
    Ok(s)
}

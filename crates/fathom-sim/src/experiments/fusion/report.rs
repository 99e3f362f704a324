//! The report section of the `fusion` experiment: the paper's tables side by side
//! with the reproduced ones, the ablation, the course-change analysis, the
//! sensitivity sweep, the explanation of the outcome, the interpretation decisions
//! and the paper's inconsistencies.

use fathom_traj::FusionMission;

use super::analysis::{RunResult, SWEEP_METHODS, SweepResult, paired, paper_values, values};
use super::figures::FILTERS;
use super::scenario::FusionSetup;
use super::sim::Method;
use fathom_stats::mean_and_ci95;

use crate::SimError;
use crate::output::fixed as f;
use crate::output::md_table;

fn ci_str(c: [f64; 2], d: usize) -> String {
    format!("[{}, {}]", f(c[0], d), f(c[1], d))
}

fn signed_ci(mean: f64, c: [f64; 2]) -> String {
    format!("{:+.2e} [{:+.2e}, {:+.2e}]", mean, c[0], c[1])
}

/// The sweeps as JSON (`summary.json` extra key `sensitivity`).
pub(super) fn sweeps_json(sweeps: &[&SweepResult]) -> serde_json::Value {
    let mut out = serde_json::Map::new();
    for s in sweeps {
        let mut per_method = serde_json::Map::new();
        for (j, m) in SWEEP_METHODS.iter().enumerate() {
            let means: Vec<f64> = s.means.iter().map(|row| row[j].0).collect();
            per_method.insert(m.name().into(), serde_json::json!(means));
        }
        out.insert(
            s.key.into(),
            serde_json::json!({"values": s.values, "mean_3d": per_method}),
        );
    }
    serde_json::Value::Object(out)
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

pub(super) fn section(
    setup: &FusionSetup,
    mission: &FusionMission,
    results: &[RunResult],
    sweeps: &[&SweepResult],
) -> Result<String, SimError> {
    let mut s = String::new();
    let n = results.len();
    let t = &setup.run.tuning;

    // --- Tables 2 and 3 ------------------------------------------------------
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
        s.push_str(&format!("### {title}: paper | reproduced | 95 % CI\n\n"));
        let mut rows = Vec::new();
        for m in Method::ALL {
            let p = paper_values(m);
            let (mm, mc) = mean_and_ci95(&values(results, m, mean_key))?;
            let (sm, sc) = mean_and_ci95(&values(results, m, std_key))?;
            let ps = |k: usize| p.map_or("—".to_string(), |p| f(p[k], 2));
            rows.push(vec![
                m.name().to_string(),
                ps(pidx),
                f(mm, 3),
                ci_str(mc, 3),
                ps(pidx + 1),
                f(sm, 3),
                ci_str(sc, 3),
            ]);
        }
        s.push_str(&md_table(
            &[
                "method",
                "mean (paper)",
                "mean (reproduced)",
                "95 % CI",
                "std (paper)",
                "std (reproduced)",
                "95 % CI",
            ],
            &rows,
        ));
        s.push('\n');
    }
    s.push_str(&format!(
        "Per run: mean and population std over the {} one-second samples t = {}..{} s; then \
         mean over {n} runs with a Student-t 95 % CI. `INS-only` and `DVL-DR` are the raw \
         integrated sensors (no filter), listed as references.\n\n",
        setup.run.n_steps,
        setup.run.step,
        setup.run.step * setup.run.n_steps as f64
    ));

    // --- Where the error comes from -----------------------------------------
    let dvl = mean(results, Method::DvlDr, "mean_3d")?;
    let ins = mean(results, Method::InsOnly, "mean_3d")?;
    let ins_final = mean(results, Method::InsOnly, "final_3d")?;
    let dvl_final = mean(results, Method::DvlDr, "final_3d")?;
    s.push_str("### Where each method's error comes from\n\n");
    let mut rows = Vec::new();
    for m in FILTERS {
        let (d, dc) = paired(results, m, Method::DvlDr, "mean_3d")?;
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
    let w_ins = t.v_dvl.powi(2) / (t.v_ins.powi(2) + t.v_dvl.powi(2));
    let ins_fb_mean = mean_and_ci95(
        &results
            .iter()
            .map(|r| {
                let e = &r.output.ins_err_with_feedback;
                e.iter().sum::<f64>() / e.len().max(1) as f64
            })
            .collect::<Vec<_>>(),
    )?
    .0;
    let ins_fb_max = results
        .iter()
        .flat_map(|r| r.output.ins_err_with_feedback.iter().copied())
        .fold(0.0, f64::max);
    // How far the filters stay from the DVL dead reckoning (paired differences).
    let mut largest_gap = 0.0_f64;
    for m in FILTERS {
        let (d, _) = paired(results, m, Method::DvlDr, "mean_3d")?;
        largest_gap = largest_gap.max(d.abs());
    }
    let dvl_gain = t.w_dvl.powi(2) / (t.w_dvl.powi(2) + t.v_dvl.powi(2));
    s.push_str(&format!(
        "\nThe raw sensors: the unaided INS drifts to a mean 3D error of {} m (last 10 % of the \
         mission: {} m; accelerometer bias, `b t^2 / 2`), the DVL dead reckoning to {} m \
         (last 10 %: {} m; scale factor times distance travelled plus the random walk of the \
         integrated velocity noise). Under EFF feedback the INS integrator's error (before \
         each reset) has a mean of {} m and a largest value over all runs of {} m, {} the \
         unaided INS's mean error.\n\n\
         With this tuning (`R_INS = {}^2`, `R_DVL = {}^2` m^2) the equalization weight of the \
         INS is `R_DVL / (R_INS + R_DVL)` = {:.2e}, and the DVL track's position gain is at \
         least `P/(P + R_DVL)` with `P >= w_DVL^2 = {}` m^2, i.e. >= {:.5}. The largest \
         paired difference between a filter's mean 3D error and the DVL dead reckoning's is \
         {} m ({} % of the DVL's {} m): {}.\n\n",
        f(ins, 2),
        f(ins_final, 2),
        f(dvl, 3),
        f(dvl_final, 3),
        f(ins_fb_mean, 3),
        f(ins_fb_max, 3),
        if ins_fb_max < ins {
            "below"
        } else {
            "not below"
        },
        t.v_ins,
        t.v_dvl,
        w_ins,
        t.w_dvl.powi(2),
        dvl_gain,
        f(largest_gap, 4),
        f(100.0 * largest_gap / dvl, 1),
        f(dvl, 3),
        if largest_gap < 0.1 * dvl {
            "every filter's error is the DVL dead reckoning's plus a small correction, so the \
             structure of the fusion changes the result only at the level of column *minus \
             DVL-DR*"
        } else {
            "the fusion structure changes the result well beyond the DVL dead reckoning's \
             error (column *minus DVL-DR*)"
        },
    ));

    // --- Ablation ------------------------------------------------------------
    s.push_str("### Ablation: which step of EFF matters\n\n");
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
    let verdict = |a: Method, b: Method| -> Result<String, SimError> {
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
    };
    s.push_str(&format!(
        "\nEqualization alone (EFF-no-feedback vs T2T): {}. Feedback alone \
         (EFF-no-equalization vs T2T): {}. Both (EFF vs T2T): {}. Extra rules: {}; {}.\n\n",
        verdict(Method::EffNoFeedback, Method::T2t)?,
        verdict(Method::EffNoEqualization, Method::T2t)?,
        verdict(Method::Eff, Method::T2t)?,
        verdict(Method::T2tBc, Method::T2t)?,
        verdict(Method::T2tCi, Method::T2t)?,
    ));

    // --- Course changes -------------------------------------------------------
    let cc = mission.course_changes();
    s.push_str("### Course-change analysis\n\n");
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
    let mut rows = Vec::new();
    for m in Method::ALL {
        let (r, c) = mean_and_ci95(&values(results, m, "turn_ratio_3d"))?;
        rows.push(vec![m.name().to_string(), f(r, 3), ci_str(c, 3)]);
    }
    s.push_str(&md_table(&["method", "turn ratio (3D)", "95 % CI"], &rows));
    let rdvl = mean(results, Method::DvlDr, "turn_ratio_3d")?;
    let mut spiking = Vec::new();
    for m in FILTERS {
        let r = mean(results, m, "turn_ratio_3d")?;
        if r > setup.turn_ratio_limit {
            spiking.push(format!("{} {}", m.name(), f(r, 3)));
        }
    }
    s.push_str(&format!(
        "\nFilters whose mean turn ratio exceeds the limit {}: {}. The DVL dead reckoning's \
         ratio is {}: it is set by where along the mission the turns fall (the \
         dead-reckoning error grows with time, not with the manoeuvre). A constant-velocity \
         filter lags at a turn when it trusts its motion model more than its measurement \
         (here `R_DVL` = {}^2 m^2 against `Q` >= {} m^2).\n\n",
        setup.turn_ratio_limit,
        if spiking.is_empty() {
            "none".to_string()
        } else {
            spiking.join(", ")
        },
        f(rdvl, 3),
        t.v_dvl,
        t.w_dvl.powi(2).min(t.w_mf.powi(2)),
    ));

    // --- Sensitivity ------------------------------------------------------------
    s.push_str(&format!(
        "### Sensitivity (mean 3D error, m; {} runs per value, same seeds for every value)\n\n",
        setup.sensitivity_runs
    ));
    for sw in sweeps {
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
    if let Some(sv) = sweeps.iter().find(|sw| sw.key == "filter_v_dvl_m") {
        let last = sv.means.len() - 1;
        let at = |m: Method| {
            SWEEP_METHODS
                .iter()
                .position(|&x| x == m)
                .map_or(f64::NAN, |j| sv.means[last][j].0)
        };
        let fb_best = at(Method::Eff).min(at(Method::EffNoEqualization));
        let open_best = at(Method::Mf)
            .min(at(Method::T2t))
            .min(at(Method::EffNoFeedback));
        s.push_str(&format!(
            "At the largest `v_DVL` ({} m) the filters must weigh the INS against the DVL: \
             MF {} m, T2T {} m, EFF {} m, EFF-no-feedback {} m, EFF-no-equalization {} m; \
             the raw DVL dead reckoning stays at {} m. The structures without \
             feedback pull the estimate toward the drifting INS (open-loop INS error {} m on \
             average); with feedback the INS measurement is the fused estimate propagated one \
             second by accurate accelerations, so the INS stops drifting and the feedback \
             variants are {} than the best open-loop structure ({} vs {} m). {}\n\n",
            sv.values[last],
            f(at(Method::Mf), 3),
            f(at(Method::T2t), 3),
            f(at(Method::Eff), 3),
            f(at(Method::EffNoFeedback), 3),
            f(at(Method::EffNoEqualization), 3),
            f(at(Method::DvlDr), 3),
            f(ins, 1),
            if fb_best < open_best {
                "better"
            } else {
                "not better"
            },
            f(fb_best, 3),
            f(open_best, 3),
            if fb_best > at(Method::DvlDr) {
                "No fusion structure beats the DVL alone once its `R` is mistuned this far: \
                 the filters then average a good sensor with a worse one."
            } else {
                "Here the fused estimate is better than the DVL alone."
            },
        ));
        let paper_order: Vec<String> = sv
            .values
            .iter()
            .zip(&sv.means)
            .filter(|(_, row)| {
                let g = |m: Method| {
                    SWEEP_METHODS
                        .iter()
                        .position(|&x| x == m)
                        .map_or(f64::NAN, |j| row[j].0)
                };
                g(Method::Eff) < g(Method::T2t) && g(Method::T2t) < g(Method::Mf)
            })
            .map(|(v, row)| {
                let g = |m: Method| {
                    SWEEP_METHODS
                        .iter()
                        .position(|&x| x == m)
                        .map_or(f64::NAN, |j| row[j].0)
                };
                format!(
                    "v_DVL = {v} m (EFF {}, T2T {}, MF {})",
                    f(g(Method::Eff), 3),
                    f(g(Method::T2t), 3),
                    f(g(Method::Mf), 3)
                )
            })
            .collect();
        let nofb_mf = max_gap(sv, Method::EffNoFeedback, Method::Mf);
        let nofb_eff = max_gap(sv, Method::EffNoFeedback, Method::Eff);
        let noeq_eff = max_gap(sv, Method::EffNoEqualization, Method::Eff);
        let noeq_better_at_last = at(Method::EffNoEqualization) < at(Method::Eff);
        let conclusion = if noeq_eff < nofb_eff && nofb_mf < nofb_eff {
            format!(
                "the feedback is the step that matters: without it EFF behaves like MF; the \
                 equalization changes far less{}",
                if noeq_better_at_last {
                    " (and at the largest v_DVL the variant without it is the better one)"
                } else {
                    ""
                }
            )
        } else {
            "neither step alone explains the difference".to_string()
        };
        s.push_str(&format!(
            "Which step of EFF helps, across the sweep (largest gaps of the mean 3D error over \
             the sweep values): EFF-no-feedback vs MF {} m, EFF-no-feedback vs EFF {} m, \
             EFF-no-equalization vs EFF {} m; so {}. The paper's ordering EFF < T2T < MF \
             appears {}.\n\n",
            f(nofb_mf, 3),
            f(nofb_eff, 3),
            f(noeq_eff, 3),
            conclusion,
            if paper_order.is_empty() {
                "at no value of the sweep".to_string()
            } else {
                format!("where the INS carries weight: {}", paper_order.join("; "))
            },
        ));
    }

    // --- Outcome ------------------------------------------------------------------
    let (e, m_, t2) = (
        mean(results, Method::Eff, "mean_3d")?,
        mean(results, Method::Mf, "mean_3d")?,
        mean(results, Method::T2t, "mean_3d")?,
    );
    let mut order = [("MF", m_), ("T2T", t2), ("EFF", e)];
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    s.push_str("### Outcome\n\n");
    let paper = |m: Method| paper_values(m).map_or(f64::NAN, |p| p[0]);
    let (pe, pt, pm) = (paper(Method::Eff), paper(Method::T2t), paper(Method::Mf));
    let same_order = order.iter().map(|o| o.0).collect::<Vec<_>>() == ["EFF", "T2T", "MF"];
    s.push_str(&format!(
        "Reproduced ordering of the 3D mean error (lowest first, m): {} (paper: EFF {pe} < \
         T2T {pt} < MF {pm}); the reproduced order {} the paper's. The ratio MF / EFF is {} \
         here and {} in the paper. The claims above state, with paired 95 % intervals, \
         whether each ordering is statistically resolved; the sensitivity sweep shows how \
         the ordering changes when the INS carries more weight.\n\n",
        order
            .iter()
            .map(|(n, v)| format!("{n} {v:.6}"))
            .collect::<Vec<_>>()
            .join(" <= "),
        if same_order {
            "matches"
        } else {
            "does not match"
        },
        f(m_ / e, 2),
        f(pm / pe, 2),
    ));

    // --- Decisions and inconsistencies -------------------------------------------
    s.push_str("### Interpretation decisions\n\n");
    s.push_str(&format!(
        "- Sensor models are not given by the paper (spec A defaults): INS double-integrates \
         `a + b_a + n_a` (bias std {} m/s^2 per run, noise std {} m/s^2 per sample); DVL \
         integrates `(1 + s) v + n_v` (`s ~ U(-{h}, {h})`, noise std {} m/s). Both start at the \
         true position and velocity and output positions at 1 Hz.\n\
         - State `[x, vx, y, vy, z, vz]`, constant-velocity `A` (T = {} s), `H` selects the \
         position. Tuning as printed: `Q = w^2 I6`, `R = v^2 I3` with w_INS = {} m, w_DVL = {} m, \
         v_INS = {} m, v_DVL = {} m; the printed units of v (m/s^2) are read as metres, since \
         `R` weighs a position measurement. MF uses `Q = {}^2 I6` (a setting).\n\
         - Filters start at the true initial state with `P0 = diag({}^2, {}^2, ...)` (position, \
         velocity); the paper gives no `P0`.\n\
         - EFF step 1 fuses the integrator states at k-1: INS position and velocity, DVL \
         position and its latest measured velocity, per axis with the scalar R weights \
         (eq. 9); step 2 sets both filters' state to `x_E` and keeps their `P`; step 4 resets \
         the INS integrator's position and velocity (bias and last acceleration sample kept). \
         The feedback reaches the integrator through the estimators' `FeedbackSink` trait, \
         implemented by a small adapter in the experiment layer.\n\
         - T2T-BC propagates the cross-covariance with `Q12 = w_INS w_DVL I6` (one common \
         process disturbance seen with the two tunings); T2T-CI minimizes the trace of the \
         fused covariance.\n\
         - One mission (trajectory seed {}), {} noise realizations; all methods of a run see \
         the same sensor noise (common random numbers), so differences between methods are \
         judged with paired 95 % CIs. A claim \"X is best\" (or \"X beats Y\") holds only \
         when the paired 95 % CI of X minus each competitor lies entirely below \
         -{} x the competitor's value (`analysis.min_relative_improvement`): the paper \
         claims improvements of 25..60 %, not differences of micrometres. The turn-ratio \
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
        t.w_mf,
        t.p0_pos,
        t.p0_vel,
        setup.trajectory_seed,
        n,
        setup.min_relative_improvement,
        setup.turn_ratio_limit,
        setup.zoom.0,
        setup.zoom.1,
        h = setup.dvl_params.scale_half_width,
    ));
    s.push_str("### The paper's inconsistencies\n\n");
    s.push_str(
        "- The text gives EFF 1.34 m / 0.31 m (3D mean / std), Table 2 gives 1.38 m / 0.32 m; \
         the table is used as the reference.\n\
         - The \"% reduction\" figures are ratios, not reductions: 3.67 -> 1.38 m is a 62 % \
         reduction, printed as \"37 %\" (1.38 / 3.67 = 0.376).\n\
         - Eq. (1) defines a 9-state position-velocity-acceleration vector, but `A` is 6x6 \
         (position and velocity per axis); the 6-state model is implemented.\n\
         - The printed `H` (`[1 1 0 0 0 0; ...]`) adds position and velocity; it is read as a \
         position measurement (`H` selects x, y, z), as the sensors output positions.\n\
         - The measurement noise stds are printed in m/s^2 (\"1 g\" for the INS) although `R` \
         weighs position measurements.\n",
    );
    Ok(s)
}

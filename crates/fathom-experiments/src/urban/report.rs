//! The `urban` report text: the scenarios as flown, the results per scenario and
//! method with 95 % CIs, the paper's numbers beside ours, every claim with its
//! numbers (and in words which do not hold), the ablations, the paper's
//! inconsistencies found on the way and the settings the paper does not give. Every
//! number comes from the rows of this run or from the scenario.

use fathom_estimators::map_aided::PAPER_FINDINGS;
use fathom_traj::quadrotor::{EQ21_EQ22_FINDINGS, eq22_discrepancies};

use super::analysis::{BEYOND_M, metric_index, values};
use super::claims::{claims, diff_row, method_row};
use super::nav::Method;
use super::record::KeptRun;
use super::world::Prepared;
use fathom_report::output::{Row, fixed as f, md_table};
use fathom_sim::experiment::Analysis;

/// The metrics of the results table, with their decimals.
const TABLE: [(&str, usize); 10] = [
    ("rmse_h", 3),
    ("rmse_3d", 3),
    ("rmse_vel", 3),
    ("rmse_roll", 3),
    ("rmse_pitch", 3),
    ("rmse_yaw", 3),
    ("p95_3d", 3),
    ("max_att", 3),
    ("time_map_aided_s", 1),
    ("nees_mean", 1),
];

fn find<'a>(rows: &'a [Row], method: &str, metric: &str) -> Option<&'a Row> {
    rows.iter()
        .find(|r| r.method == method && r.metric == metric)
}

/// `mean [lo, hi]` of a row, or `-`.
pub(super) fn cell(r: Option<&Row>, d: usize) -> String {
    match r {
        Some(Row {
            value,
            ci95: Some([lo, hi]),
            ..
        }) => format!("{} [{}, {}]", f(*value, d), f(*lo, d), f(*hi, d)),
        Some(r) => f(r.value, d),
        None => "-".into(),
    }
}

/// "lower than", "higher than" or "not distinguishable from" for a paired row.
fn relation(r: Option<&Row>) -> &'static str {
    match r.and_then(|r| r.ci95) {
        Some([_, hi]) if hi < 0.0 => "lower than",
        Some([lo, _]) if lo > 0.0 => "higher than",
        _ => "not distinguishable from",
    }
}

/// Adds the report text to `out`.
pub(super) fn write(prep: &Prepared, main: &[KeptRun], out: &mut Analysis) {
    let c = &prep.checked;
    let rows = out.rows().to_vec();
    let mut md = String::new();
    md.push_str("## Scenarios as flown\n\n");
    let mut t = Vec::new();
    for (s, spec) in c.scenes.iter().enumerate() {
        let g = format!("{}/GNSS", spec.name);
        t.push(vec![
            spec.name.clone(),
            prep.scenes[s].source.clone(),
            format!("{:?}", spec.ranging).to_lowercase(),
            cell(find(&rows, &g, "flight_duration_s"), 1),
            cell(find(&rows, &g, "los_satellites_mean"), 2),
            cell(find(&rows, &g, "shadowed_fraction"), 3),
        ]);
    }
    md.push_str(&md_table(
        &[
            "scenario",
            "world",
            "ranging",
            "flight s",
            "true-LOS satellites (mean)",
            "GNSS epochs below the switching threshold",
        ],
        &t,
    ));
    md.push_str(&format!(
        "\n{} Monte Carlo runs; every method runs on the same sensor data of a run. \
         Values are means over runs with 95 % CIs; errors are evaluated from the end of \
         the {} s rest (gyro-bias calibration) to the end of the flight.\n\n",
        c.runs, c.rest_s
    ));
    for spec in &c.scenes {
        md.push_str(&format!("## Results: {}\n\n", spec.name));
        let mut headers = vec!["method"];
        headers.extend(TABLE.iter().map(|(m, _)| *m));
        let t: Vec<Vec<String>> = c
            .methods
            .iter()
            .map(|m| {
                let name = method_row(&spec.name, *m);
                let mut r = vec![m.name().to_string()];
                r.extend(TABLE.iter().map(|(k, d)| cell(find(&rows, &name, k), *d)));
                r
            })
            .collect();
        md.push_str(&md_table(&headers, &t));
        md.push('\n');
        let paper: Vec<Vec<String>> = rows
            .iter()
            .filter(|r| r.paper.is_some() && r.method.starts_with(&format!("{}/", spec.name)))
            .map(|r| {
                vec![
                    r.method.clone(),
                    r.metric.clone(),
                    f(r.paper.unwrap_or(f64::NAN), 4),
                    cell(Some(r), 4),
                ]
            })
            .collect();
        if !paper.is_empty() && out.paper_extras() {
            md.push_str("Paper against this run (reference only):\n\n");
            md.push_str(&md_table(&["row", "metric", "paper", "reproduced"], &paper));
            md.push('\n');
        }
    }
    // The paper's claims, its numbers and its errata belong to its setup: a user's
    // variant (a world of their own) is reported as theirs.
    if out.paper_extras() {
        md.push_str("## Claims\n\n");
        if !c.all_methods() {
            let names: Vec<&str> = c.methods.iter().map(|m| m.name()).collect();
            md.push_str(&format!(
                "`methods` selects {} of the {} methods ({}): the paper's claims compare the \
                 methods and are not evaluated{}. The tables above are this run's own results.\n\n",
                names.len(),
                Method::ALL.len(),
                names.join(", "),
                if c.ablations_skipped > 0 {
                    format!(
                        "; {} ablation(s) of methods not selected did not run",
                        c.ablations_skipped
                    )
                } else {
                    String::new()
                }
            ));
        }
        let verdicts = if c.all_methods() {
            claims(&rows, c.table2_tolerance)
        } else {
            Vec::new()
        };
        for cl in &verdicts {
            md.push_str(&format!(
                "- `{}` **{}**: {}\n",
                cl.id,
                cl.verdict
                    .as_deref()
                    .unwrap_or(if cl.holds { "holds" } else { "does not hold" }),
                cl.detail
            ));
        }
        let failed: Vec<&str> = verdicts
            .iter()
            .filter(|c| !c.holds)
            .map(|c| c.id.as_str())
            .collect();
        if verdicts.is_empty() {
            // No claim was evaluated (a subset of the methods, said above).
        } else if failed.is_empty() {
            md.push_str("\nEvery claim holds in this run.\n\n");
        } else {
            md.push_str(&format!(
                "\nNot reproduced here: {} (numbers above).\n\n",
                failed
                    .iter()
                    .map(|s| format!("`{s}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
    md.push_str(&switching_text(c, &rows));
    md.push_str(&spread_text(prep, main));
    md.push_str(&consistency_text(c, &rows));
    md.push_str(&shadowing_text(c, &rows));
    md.push_str(&ablation_text(prep, &rows));
    if out.paper_extras() {
        md.push_str("## The paper's inconsistencies found on the way\n\n");
        for finding in PAPER_FINDINGS {
            md.push_str(&format!("- eq. {}: {}\n", finding.equation, finding.text));
        }
        let v = &c.quad.vehicle;
        let eq22 = eq22_discrepancies(v.arm_length(), v.kappa());
        md.push_str(&format!(
            "- eq. (21)/(22), checked for this vehicle (l = {} m, kappa = {} m): {} coefficients of the printed eq. (22) differ from the inverse of eq. (21)",
            f(v.arm_length(), 3),
            f(v.kappa(), 4),
            eq22.as_ref().map_or("(not invertible)".to_string(), |d| d.len().to_string())
        ));
        for finding in EQ21_EQ22_FINDINGS {
            md.push_str(&format!("; {finding}"));
        }
        md.push_str(".\n\n");
    }
    md.push_str("## Settings the paper does not give (this scenario's values)\n\n");
    for (k, val) in &c.unstated {
        md.push_str(&format!("- `{k}`: {val}\n"));
    }
    out.report(&md);
}

/// Runs whose 3-D RMSE exceeds this multiple of the median run count as diverged.
const DIVERGED_FACTOR: f64 = 10.0;

/// The median and the diverged runs per scenario and map-aided method: a mean over
/// runs is dominated by a few lost tracks, which the median shows.
fn spread_text(prep: &Prepared, main: &[KeptRun]) -> String {
    let c = &prep.checked;
    let Some(k) = metric_index("rmse_3d") else {
        return String::new();
    };
    let mut md = format!(
        "## Spread over runs (rmse_3d: median, and runs above {DIVERGED_FACTOR} x the median)\n\n"
    );
    let mut t = Vec::new();
    for (s, spec) in c.scenes.iter().enumerate() {
        for (m, method) in c.methods.iter().enumerate() {
            if main.is_empty() || main[0].len() <= s {
                continue;
            }
            let mut v = values(main, s, m, k);
            v.sort_by(f64::total_cmp);
            let median = v[v.len() / 2];
            let worst = (0..main.len())
                .max_by(|a, b| {
                    main[*a][s].stats[m].values()[k].total_cmp(&main[*b][s].stats[m].values()[k])
                })
                .unwrap_or(0);
            let beyond = v.iter().filter(|x| **x > BEYOND_M).count();
            let diverged: Vec<String> = (0..main.len())
                .filter(|i| main[*i][s].stats[m].values()[k] > DIVERGED_FACTOR * median)
                .map(|i| i.to_string())
                .collect();
            t.push(vec![
                method_row(&spec.name, *method),
                f(median, 3),
                format!("{} (run {worst})", f(v[v.len() - 1], 3)),
                format!("{beyond} of {}", v.len()),
                format!("{} of {}", diverged.len(), v.len()),
                diverged.join(" "),
            ]);
        }
    }
    md.push_str(&md_table(
        &[
            "row",
            "median m",
            "worst m (run)",
            "runs above 1 m",
            "diverged",
            "runs",
        ],
        &t,
    ));
    md.push('\n');
    md
}

/// What the GNSS shadowing did to the GPS-only methods.
fn shadowing_text(c: &super::check::Checked, rows: &[Row]) -> String {
    if c.index_of(Method::GpsIns).is_none() || c.index_of(Method::GpsInsAllSats).is_none() {
        return String::new();
    }
    let mut md = String::from("## GNSS shadowing and the LOS test\n\n");
    for spec in &c.scenes {
        let n = &spec.name;
        let d = find(
            rows,
            &format!("{n}/GPS/INS-vs-GPS/INS-all-sats"),
            "diff_rmse_3d",
        );
        md.push_str(&format!(
            "- {n}: GPS/INS with the LOS test has rmse_3d {} m, with every satellite {} m; the paired difference {} m is {} zero. The shadowed fraction of GNSS epochs is {}.\n",
            cell(find(rows, &method_row(n, Method::GpsIns), "rmse_3d"), 2),
            cell(find(rows, &method_row(n, Method::GpsInsAllSats), "rmse_3d"), 2),
            cell(d, 2),
            relation(d),
            cell(find(rows, &format!("{n}/GNSS"), "shadowed_fraction"), 3),
        ));
    }
    md.push('\n');
    md
}

/// The 95 % band of one epoch's 9-dof NEES (chi-square 2.5 % and 97.5 % quantiles).
const NEES9_BAND: [f64; 2] = [2.700, 19.023];

/// Where a NEES value lies against a band, in words.
fn band_words(v: f64, band: [f64; 2], what: &str) -> String {
    let [lo, hi] = band;
    let b = format!("{what} [{}, {}]", f(lo, 2), f(hi, 2));
    if v < lo {
        format!("below {b} by a factor {} (conservative)", f(lo / v, 1))
    } else if v > hi {
        format!("above {b} by a factor {} (over-confident)", f(v / hi, 1))
    } else {
        format!("inside {b}")
    }
}

/// Mode switching per scenario, from the rows: the thresholds, the switches of every
/// switching method (mean, fewest), its time in each mode and its lost locks; a method
/// that never ran map-aided, and a scenario where nothing switched, are said so.
fn switching_text(c: &super::check::Checked, rows: &[Row]) -> String {
    let sw = &c.filter.switch;
    let mut md = format!(
        "## Mode switching\n\nThe switching methods leave GPS/INS when fewer than {} satellites \
         are in line of sight (tested from the estimated position against the map) and \
         re-enter it at {} or more (at least {} s in a mode); the figures draw both counts.\n\n",
        sw.leave_gps_below(),
        sw.enter_gps_at(),
        c.switch_dwell_s,
    );
    let switching: Vec<Method> = c
        .methods
        .iter()
        .copied()
        .filter(|m| m.is_switching())
        .collect();
    for spec in &c.scenes {
        let n = &spec.name;
        let g = format!("{n}/GNSS");
        let value = |m: &str, k: &str| find(rows, m, k).map(|r| r.value);
        md.push_str(&format!(
            "- `{n}`: {} satellites used; true-LOS count {} on average, {} of the GNSS epochs below {}.\n",
            value(&g, "satellites_used").map_or("-".into(), |v| f(v, 0)),
            cell(find(rows, &g, "los_satellites_mean"), 2),
            cell(find(rows, &g, "shadowed_fraction"), 3),
            sw.leave_gps_below(),
        ));
        let open_diff = find(
            rows,
            &diff_row(n, Method::GpsIns, Method::InsOnly),
            "diff_rmse_3d_open",
        );
        match find(rows, &method_row(n, Method::GpsIns), "rmse_3d_open") {
            Some(r) => md.push_str(&format!(
                "  - Open sky (epochs with at least {} satellites in true line of sight): GPS/INS rmse_3d {} m; minus INS-only {} m ({} zero).\n",
                sw.enter_gps_at(),
                cell(Some(r), 3),
                cell(open_diff, 3),
                relation(open_diff),
            )),
            None => md.push_str(&format!(
                "  - No run of `{n}` has an open-sky epoch (at least {} satellites in true line of sight): no open-sky rows.\n",
                sw.enter_gps_at(),
            )),
        }
        let mut none = true;
        for m in &switching {
            let name = method_row(n, *m);
            let mean = value(&name, "switches").unwrap_or(0.0);
            let fewest = value(&name, "switches_min").unwrap_or(0.0);
            let map_s = value(&name, "time_map_aided_s").unwrap_or(0.0);
            none &= mean == 0.0;
            if map_s == 0.0 {
                md.push_str(&format!(
                    "  - {} never ran map-aided in `{n}`: its rows are GPS/INS rows.\n",
                    m.name()
                ));
                continue;
            }
            md.push_str(&format!(
                "  - {}: {} switches per run (fewest {} in a run), {} s map-aided and {} s on GPS/INS, {} lost locks per run, {} GPS re-acquisitions per run.\n",
                m.name(),
                cell(find(rows, &name, "switches"), 2),
                f(fewest, 0),
                cell(find(rows, &name, "time_map_aided_s"), 1),
                cell(find(rows, &name, "time_gps_ins_s"), 1),
                cell(find(rows, &name, "lost_lock"), 2),
                cell(find(rows, &name, "gps_reacquired"), 2),
            ));
        }
        if none && !switching.is_empty() {
            md.push_str(&format!(
                "  - In `{n}` no switching method switched in any run: the map-aided methods are GPS/INS here.\n"
            ));
        }
    }
    md.push('\n');
    md
}

/// The paper's method of each preset scenario against the paper's numbers and its NEES
/// against the chi-square band, in words from the rows.
fn consistency_text(c: &super::check::Checked, rows: &[Row]) -> String {
    let mut md = String::from("## Consistency (NEES) and the paper's bridge numbers\n\n");
    for spec in &c.scenes {
        for m in &c.methods {
            if !m.is_switching() {
                continue;
            }
            let name = method_row(&spec.name, *m);
            let Some(nees) = find(rows, &name, "nees_mean") else {
                continue;
            };
            let where_ = band_words(nees.value, NEES9_BAND, "the one-epoch 95 % band");
            let runs = c.runs.max(1) as f64;
            let dof = 9.0 * runs;
            let mean_band = match (
                fathom_stats::quantile::chi2_quantile(0.025, dof),
                fathom_stats::quantile::chi2_quantile(0.975, dof),
            ) {
                (Ok(lo), Ok(hi)) => format!(
                    "; {}",
                    band_words(
                        nees.value,
                        [lo / runs, hi / runs],
                        &format!("the 95 % band of a mean over {} runs", c.runs)
                    )
                ),
                _ => String::new(),
            };
            let where_ = format!("{where_}{mean_band}");
            md.push_str(&format!(
                "- `{name}`: time-averaged 9-state NEES {} (9 expected), {where_}.\n",
                cell(Some(nees), 2)
            ));
        }
    }
    let bridge = method_row("bridge", Method::Grekf);
    if let (Some(r), Some(a)) = (
        find(rows, &bridge, "rmse_3d"),
        find(rows, &bridge, "max_att"),
    ) {
        md.push_str(&format!(
            "\n`bridge/GREKF` rmse_3d {} m over the whole flight (GPS/INS in open sky, GREKF under the deck) against the paper's {} m (reference); largest attitude error per run {} deg against the paper's bound of {} deg; {} of the runs have rmse_3d above 1 m.\n",
            cell(Some(r), 3),
            super::paper::BRIDGE_GREKF_RMS_3D_M,
            cell(Some(a), 3),
            super::paper::BRIDGE_ATT_BOUND_DEG,
            find(rows, &bridge, "runs_beyond_1m").map_or("-".into(), |b| f(b.value, 0)),
        ));
    }
    md.push('\n');
    md
}

/// The ablations in words, from their paired rows.
fn ablation_text(prep: &Prepared, rows: &[Row]) -> String {
    let c = &prep.checked;
    if c.ablations.is_empty() {
        return String::new();
    }
    let mut md = format!(
        "## Ablations ({} runs each, paired with the main batch's runs of the same index)\n\n",
        c.ablation_runs
    );
    for a in &c.ablations {
        let base = format!(
            "{}@{}",
            method_row(&c.scenes[a.scene].name, a.method),
            a.label()
        );
        let d = find(rows, &format!("{base}-vs-main"), "diff_rmse_3d");
        let what = match a.label().as_str() {
            "gaussian_ranges" => {
                "Gaussian range noise only (glass like opaque, every incidence returns: the paper's simulation)"
            }
            "glass_incidence" => {
                "glass extra noise and detection falling with the incidence angle (the main batch: Gaussian ranges)"
            }
            "control_on_estimate" => "the controller flying on the estimate",
            "posterior_information" => {
                "the MGPMF's posterior covariance in information form (discretization cancelled)"
            }
            "posterior_interpolated" => {
                "the MGPMF's posterior covariance as the paper's eq. (18) with the interpolation term"
            }
            _ => "another lidar step",
        };
        md.push_str(&format!(
            "- `{base}`, {what}: rmse_3d {} m (worst run {} m, {} runs above 1 m), rmse_yaw {} deg; minus the main batch: rmse_3d {} m ({} zero), rmse_yaw {} deg.\n",
            cell(find(rows, &base, "rmse_3d"), 3),
            find(rows, &base, "worst_rmse_3d").map_or("-".into(), |r| f(r.value, 3)),
            find(rows, &base, "runs_beyond_1m").map_or("-".into(), |r| f(r.value, 0)),
            cell(find(rows, &base, "rmse_yaw"), 3),
            cell(d, 3),
            relation(d),
            cell(find(rows, &format!("{base}-vs-main"), "diff_rmse_yaw"), 3),
        ));
    }
    md.push('\n');
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relation_reads_the_ci() {
        let r = |lo, hi| Row::new("a", "b", 0.5 * (lo + hi)).with_ci95(lo, hi, "student-t");
        assert_eq!(relation(Some(&r(-2.0, -1.0))), "lower than");
        assert_eq!(relation(Some(&r(1.0, 2.0))), "higher than");
        assert_eq!(relation(Some(&r(-1.0, 2.0))), "not distinguishable from");
        assert_eq!(relation(None), "not distinguishable from");
        assert_eq!(cell(Some(&r(1.0, 2.0)), 1), "1.5 [1.0, 2.0]");
    }
}

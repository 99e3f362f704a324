//! The `urban` claims, computed from the rows alone (values and 95 % CIs): a row
//! changed changes the verdict. A claim whose rows are absent (a scenario file
//! without the paper's scenario) is not evaluated.
//!
//! | claim | row(s) | holds when |
//! | --- | --- | --- |
//! | `grekf_bridge_rms_le_0_3` | `bridge/GREKF` `rmse_3d` | the CI's upper end ≤ 0.3 m |
//! | `grekf_bridge_att_lt_0_5` | `bridge/GREKF` `max_att` | the CI's upper end < 0.5° |
//! | `mgpmf_buildings_table2_<metric>` | `buildings/MGPMF` Table 2 rows, `mean_3d`, `p95_3d` | equivalence: the whole CI lies inside the band paper value ± tolerance × paper value (`agrees`; `differs` when wholly outside, else `inconclusive`) |
//! | `mgpmf_buildings_table2` | the same | every entry agrees |
//! | `los_check_improves_gps` | `buildings/GPS/INS-vs-GPS/INS-all-sats` `diff_rmse_3d` | the paired CI lies below 0 |
//! | `map_aided_beats_ins_only` | `bridge/GREKF-vs-INS-only`, `buildings/MGPMF-vs-INS-only` `diff_rmse_3d` | both paired CIs lie below 0 |
//! | `mgpmf_beats_grekf_near_walls` | `buildings/MGPMF-vs-GREKF` `diff_rmse_h` | the paired CI lies below 0 |
//! | `gps_ins_beats_ins_only_in_open_sky` | `<scene>/GPS/INS-vs-INS-only` `diff_rmse_3d_open` of every scenario that has it | every paired CI lies below 0 (a check of the simulation: GPS must help where the sky is open) |

use super::nav::Method;
use super::paper::{ACCURACY_M, BRIDGE_ATT_BOUND_DEG, PRECISION_2SIGMA_M, TABLE2};
use fathom_report::output::{Claim, Row, fixed as f};

/// The row name of a method in a scenario (`bridge/GREKF`).
pub fn method_row(scene: &str, method: Method) -> String {
    format!("{scene}/{}", method.name())
}

/// The row name of a paired difference `a - b` in a scenario.
pub fn diff_row(scene: &str, a: Method, b: Method) -> String {
    format!("{scene}/{}-vs-{}", a.name(), b.name())
}

/// The paired differences the analysis adds: `(a, b, metric)`.
pub const DIFFERENCES: [(Method, Method, &str); 8] = [
    (Method::GpsIns, Method::GpsInsAllSats, "rmse_3d"),
    (Method::GpsIns, Method::InsOnly, "rmse_3d"),
    (Method::Grekf, Method::InsOnly, "rmse_3d"),
    (Method::Mgpmf, Method::InsOnly, "rmse_3d"),
    (Method::Particle, Method::InsOnly, "rmse_3d"),
    (Method::Mgpmf, Method::Grekf, "rmse_h"),
    (Method::Mgpmf, Method::Grekf, "rmse_3d"),
    (Method::Particle, Method::Mgpmf, "rmse_h"),
];

fn find<'a>(rows: &'a [Row], method: &str, metric: &str) -> Option<&'a Row> {
    rows.iter()
        .find(|r| r.method == method && r.metric == metric)
}

fn upper(r: &Row) -> f64 {
    r.ci95.map_or(r.value, |c| c[1])
}

fn ci_text(r: &Row, d: usize) -> String {
    match r.ci95 {
        Some([lo, hi]) => format!("{} [{}, {}]", f(r.value, d), f(lo, d), f(hi, d)),
        None => f(r.value, d),
    }
}

/// The equivalence of the row's CI with the band `p ± tol * |p|` (`None` for a
/// non-finite number, which a checked row never has).
fn judge(r: &Row, p: f64, tol: f64) -> Option<fathom_stats::Equivalence> {
    fathom_stats::equivalence(r.ci95.unwrap_or([r.value, r.value]), p, tol * p.abs()).ok()
}

/// The claims of the rows; `tolerance` is the Table 2 tolerance (a fraction of the
/// paper value).
pub fn claims(rows: &[Row], tolerance: f64) -> Vec<Claim> {
    let mut out = Vec::new();
    let bridge = method_row("bridge", Method::Grekf);
    if let Some(r) = find(rows, &bridge, "rmse_3d") {
        out.push(Claim::new(
            "grekf_bridge_rms_le_0_3",
            "under the bridge the GREKF with the lidar keeps the 3-axis RMS position error within 0.3 m (paper: 0.2972 m)",
            upper(r) <= 0.3,
            format!(
                "bridge/GREKF rmse_3d {} m (mean over runs, 95 % CI); holds when the CI's upper end is at most 0.3 m",
                ci_text(r, 4)
            ),
        ));
    }
    if let Some(r) = find(rows, &bridge, "max_att") {
        out.push(Claim::new(
            "grekf_bridge_att_lt_0_5",
            "under the bridge the GREKF keeps the attitude errors within 0.5 deg",
            upper(r) < BRIDGE_ATT_BOUND_DEG,
            format!(
                "bridge/GREKF largest roll / pitch / yaw error per run {} deg (95 % CI); holds when the CI's upper end is below 0.5 deg",
                ci_text(r, 3)
            ),
        ));
    }
    let buildings = method_row("buildings", Method::Mgpmf);
    let entries: Vec<(&str, f64)> = TABLE2
        .iter()
        .copied()
        .chain([("mean_3d", ACCURACY_M), ("p95_3d", PRECISION_2SIGMA_M)])
        .collect();
    let mut all = Vec::new();
    for (metric, p) in entries {
        let Some(r) = find(rows, &buildings, metric) else {
            continue;
        };
        let Some(e) = judge(r, p, tolerance) else {
            continue;
        };
        all.push((metric, e.verdict));
        out.push(Claim::equivalence(
            format!("mgpmf_buildings_table2_{metric}"),
            format!("around the buildings the MGPMF's {metric} matches the paper's {p}"),
            e.verdict.name(),
            e.band,
            format!(
                "buildings/MGPMF {metric} {} ({}) against the band [{}, {}] (the paper's {p} ± {} %): {}",
                ci_text(r, 4),
                r.ci_method.as_deref().unwrap_or("95 % CI"),
                f(e.band[0], 4),
                f(e.band[1], 4),
                f(100.0 * tolerance, 0),
                e.verdict.name()
            ),
        ));
    }
    if !all.is_empty() {
        let with = |v: fathom_stats::Verdict| -> String {
            let names: Vec<&str> = all.iter().filter(|e| e.1 == v).map(|e| e.0).collect();
            if names.is_empty() {
                "none".into()
            } else {
                names.join(", ")
            }
        };
        out.push(Claim::new(
            "mgpmf_buildings_table2",
            "around the buildings the MGPMF reproduces Table 2 (RMSE of horizontal, 3-D position, velocity, roll, pitch, yaw; accuracy 1.18 m, precision 2.12 m)",
            all.iter().all(|e| e.1 == fathom_stats::Verdict::Agrees),
            format!(
                "agrees: {}; differs: {}; inconclusive: {} (per-entry claims mgpmf_buildings_table2_<metric>; holds when every entry agrees)",
                with(fathom_stats::Verdict::Agrees),
                with(fathom_stats::Verdict::Differs),
                with(fathom_stats::Verdict::Inconclusive)
            ),
        ));
    }
    let los = |scene: &str| {
        find(
            rows,
            &diff_row(scene, Method::GpsIns, Method::GpsInsAllSats),
            "diff_rmse_3d",
        )
    };
    if let Some(r) = los("buildings") {
        let other = los("bridge").map_or(String::new(), |b| {
            format!("; under the bridge {} m", ci_text(b, 3))
        });
        out.push(Claim::new(
            "los_check_improves_gps",
            "removing the satellites the map shows in non-line-of-sight improves GPS/INS (Fig. 6)",
            upper(r) < 0.0,
            format!(
                "around the buildings rmse_3d GPS/INS minus GPS/INS-all-sats {} m (paired 95 % CI; holds when below 0){other}",
                ci_text(r, 3)
            ),
        ));
    }
    let vs_ins = [("bridge", Method::Grekf), ("buildings", Method::Mgpmf)].map(|(s, m)| {
        (
            s,
            m,
            find(rows, &diff_row(s, m, Method::InsOnly), "diff_rmse_3d"),
        )
    });
    let present: Vec<_> = vs_ins
        .iter()
        .filter_map(|(s, m, r)| r.map(|r| (s, m, r)))
        .collect();
    if !present.is_empty() {
        out.push(Claim::new(
            "map_aided_beats_ins_only",
            "the map-aided INS (GREKF under the bridge, MGPMF around the buildings) is more accurate than the INS alone",
            present.iter().all(|(_, _, r)| upper(r) < 0.0),
            present
                .iter()
                .map(|(s, m, r)| {
                    format!(
                        "{s}: rmse_3d {} minus INS-only {} m",
                        m.name(),
                        ci_text(r, 3)
                    )
                })
                .collect::<Vec<_>>()
                .join(" · ")
                + " (paired 95 % CIs; holds when all lie below 0)",
        ));
    }
    let open: Vec<(&str, &Row)> = rows
        .iter()
        .filter(|r| r.metric == "diff_rmse_3d_open")
        .filter_map(|r| {
            let scene = r
                .method
                .strip_suffix(&diff_row("", Method::GpsIns, Method::InsOnly))?;
            Some((scene, r))
        })
        .collect();
    if !open.is_empty() {
        out.push(Claim::new(
            "gps_ins_beats_ins_only_in_open_sky",
            "where the sky is open GPS/INS is more accurate than the INS alone (a check of the simulation, not a claim of the paper)",
            open.iter().all(|(_, r)| upper(r) < 0.0),
            open.iter()
                .map(|(s, r)| {
                    format!(
                        "{s}: rmse_3d over the open-sky epochs, GPS/INS minus INS-only {} m",
                        ci_text(r, 3)
                    )
                })
                .collect::<Vec<_>>()
                .join(" · ")
                + " (paired 95 % CIs; holds when all lie below 0)",
        ));
    }
    if let Some(r) = find(
        rows,
        &diff_row("buildings", Method::Mgpmf, Method::Grekf),
        "diff_rmse_h",
    ) {
        out.push(Claim::new(
            "mgpmf_beats_grekf_near_walls",
            "near walls the MGPMF is more accurate than the GREKF (the paper's reason for the point-mass filter)",
            upper(r) < 0.0,
            format!(
                "around the buildings rmse_h MGPMF minus GREKF {} m (paired 95 % CI; holds when below 0)",
                ci_text(r, 4)
            ),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, metric: &str, v: f64, ci: [f64; 2]) -> Row {
        Row::new(method, metric, v).with_ci95(ci[0], ci[1], "bootstrap-bca")
    }

    fn rows() -> Vec<Row> {
        let mut r = vec![
            row("bridge/GREKF", "rmse_3d", 0.25, [0.24, 0.26]),
            row("bridge/GREKF", "max_att", 0.4, [0.38, 0.42]),
            row(
                "buildings/GPS/INS-vs-GPS/INS-all-sats",
                "diff_rmse_3d",
                -1.0,
                [-1.2, -0.8],
            ),
            row(
                "bridge/GREKF-vs-INS-only",
                "diff_rmse_3d",
                -10.0,
                [-11.0, -9.0],
            ),
            row(
                "buildings/MGPMF-vs-INS-only",
                "diff_rmse_3d",
                -10.0,
                [-11.0, -9.0],
            ),
            row(
                "buildings/MGPMF-vs-GREKF",
                "diff_rmse_h",
                -0.1,
                [-0.2, -0.05],
            ),
            row(
                "bridge/GPS/INS-vs-INS-only",
                "diff_rmse_3d_open",
                -3.0,
                [-4.0, -2.0],
            ),
            row(
                "buildings/GPS/INS-vs-INS-only",
                "diff_rmse_3d_open",
                -3.0,
                [-4.0, -2.0],
            ),
        ];
        for (m, p) in TABLE2
            .iter()
            .copied()
            .chain([("mean_3d", ACCURACY_M), ("p95_3d", PRECISION_2SIGMA_M)])
        {
            r.push(row("buildings/MGPMF", m, p, [0.95 * p, 1.05 * p]));
        }
        r
    }

    /// A row changed: `(method, metric, value, CI, the claims that must flip)`.
    type Flip<'a> = (&'a str, &'a str, f64, [f64; 2], &'a [&'a str]);

    fn verdict(c: &[Claim], id: &str) -> bool {
        c.iter().find(|c| c.id == id).unwrap().holds
    }

    /// Every claim holds on rows built to satisfy it, and flipping one row flips the
    /// claim that reads it (and only it).
    #[test]
    fn claims_follow_the_rows() {
        let base = claims(&rows(), 0.25);
        let ids = [
            "grekf_bridge_rms_le_0_3",
            "grekf_bridge_att_lt_0_5",
            "mgpmf_buildings_table2",
            "mgpmf_buildings_table2_rmse_yaw",
            "los_check_improves_gps",
            "map_aided_beats_ins_only",
            "mgpmf_beats_grekf_near_walls",
            "gps_ins_beats_ins_only_in_open_sky",
        ];
        for id in ids {
            assert!(verdict(&base, id), "{id}: {base:?}");
        }
        let flips: [Flip<'_>; 7] = [
            (
                "buildings/GPS/INS-vs-INS-only",
                "diff_rmse_3d_open",
                0.5,
                [-0.5, 1.5],
                &["gps_ins_beats_ins_only_in_open_sky"],
            ),
            (
                "bridge/GREKF",
                "rmse_3d",
                0.29,
                [0.28, 0.31],
                &["grekf_bridge_rms_le_0_3"],
            ),
            (
                "bridge/GREKF",
                "max_att",
                0.49,
                [0.47, 0.51],
                &["grekf_bridge_att_lt_0_5"],
            ),
            (
                "buildings/MGPMF",
                "rmse_yaw",
                5.0,
                [4.5, 5.5],
                &["mgpmf_buildings_table2", "mgpmf_buildings_table2_rmse_yaw"],
            ),
            (
                "buildings/GPS/INS-vs-GPS/INS-all-sats",
                "diff_rmse_3d",
                -0.1,
                [-0.3, 0.1],
                &["los_check_improves_gps"],
            ),
            (
                "bridge/GREKF-vs-INS-only",
                "diff_rmse_3d",
                1.0,
                [0.5, 1.5],
                &["map_aided_beats_ins_only"],
            ),
            (
                "buildings/MGPMF-vs-GREKF",
                "diff_rmse_h",
                0.1,
                [0.05, 0.2],
                &["mgpmf_beats_grekf_near_walls"],
            ),
        ];
        for (method, metric, v, ci, flipped) in flips {
            let mut r = rows();
            let k = r
                .iter()
                .position(|x| x.method == method && x.metric == metric)
                .unwrap();
            r[k] = row(method, metric, v, ci);
            let c = claims(&r, 0.25);
            for id in ids {
                assert_eq!(
                    verdict(&c, id),
                    !flipped.contains(&id),
                    "{method} {metric} -> {id}: {c:?}"
                );
            }
        }
        // the tolerance is a setting: 0 % agrees with nothing but a point on the paper
        let mut r = rows();
        for x in &mut r {
            if x.method == "buildings/MGPMF" && x.metric == "rmse_h" {
                *x = row("buildings/MGPMF", "rmse_h", 0.8, [0.75, 0.85]);
            }
        }
        assert!(verdict(&claims(&r, 0.25), "mgpmf_buildings_table2_rmse_h"));
        assert!(!verdict(&claims(&r, 0.0), "mgpmf_buildings_table2_rmse_h"));
        // More divergence widens the interval: the verdict turns inconclusive, never
        // agrees (the old rule, "the CI widened by the tolerance contains the paper",
        // held here).
        let p = TABLE2[0].1;
        for hi in [1.3 * p, 3.0 * p, 30.0 * p] {
            let mut r = rows();
            for x in &mut r {
                if x.method == "buildings/MGPMF" && x.metric == TABLE2[0].0 {
                    *x = row("buildings/MGPMF", TABLE2[0].0, p, [0.95 * p, hi]);
                }
            }
            let c = claims(&r, 0.25);
            let e = c
                .iter()
                .find(|c| c.id == format!("mgpmf_buildings_table2_{}", TABLE2[0].0))
                .unwrap();
            assert_eq!(e.verdict.as_deref(), Some("inconclusive"), "{e:?}");
            assert!(!e.holds);
            assert!(!verdict(&c, "mgpmf_buildings_table2"));
        }
        // absent rows: the claim is not evaluated
        assert!(claims(&[], 0.25).is_empty());
    }
}

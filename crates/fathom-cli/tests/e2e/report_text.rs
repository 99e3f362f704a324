//! The reports state what the run computed: each test changes a scenario setting or
//! reads the run's own rows, and checks that a sentence of `report.md` that used to
//! be fixed text now follows the numbers.

use fathom_report::output::Summary;

use crate::support::{preset, run_experiment, scratch, write_scenario};

/// Runs `name` from `text` in a scratch workspace; the summary and `report.md`.
fn run(tag: &str, name: &str, text: &str) -> (Summary, String) {
    let root = scratch(tag);
    write_scenario(&root, &format!("{name}.toml"), text);
    let result = run_experiment(&root, name, Some(2)).unwrap();
    crate::support::assert_every_row_has_a_unit(&result.experiments[0]);
    let report = std::fs::read_to_string(root.join("out").join(name).join("report.md")).unwrap();
    (result.experiments[0].summary.clone(), report)
}

fn value(s: &Summary, method: &str, metric: &str) -> f64 {
    s.row(method, metric)
        .unwrap_or_else(|| panic!("no row {method} / {metric}"))
        .value
}

#[test]
fn beacons_report_follows_t_gap_layout_and_the_computed_winner() {
    let text = preset("beacons.toml")
        .replace("runs = 100", "runs = 4")
        .replace("duration_s = 180.0", "duration_s = 30.0")
        .replace("outlier_count = 276", "outlier_count = 20")
        .replace("corr_gap_s = 1.0", "corr_gap_s = 2.5")
        .replace(
            "positions = [[15.0, 15.0, 0.0], [-15.0, 15.0, 40.0], [-15.0, -15.0, 0.0], [15.0, -15.0, 40.0]]",
            "positions = [[30.0, -15.0, 0.0], [45.0, 15.0, 40.0], [30.0, 15.0, 0.0], [45.0, -15.0, 40.0]]",
        );
    assert!(text.contains("corr_gap_s = 2.5") && text.contains("[45.0, 15.0, 40.0]"));
    let (s, report) = run("report-beacons", "beacons", &text);
    assert!(report.contains("`t_gap` = 2.5 s"), "{report}");
    assert!(!report.contains("`t_gap` = 1 s"), "{report}");
    assert!(
        report.contains("(45, 15, 40)"),
        "the beacon layout is the scenario's"
    );
    // The winner named per case is the scheme with the lowest computed mean.
    for case in ["high", "low", "none", "sync"] {
        let best = ["AS", "SC", "SI"]
            .into_iter()
            .min_by(|a, b| {
                value(&s, &format!("{a}/{case}"), "mean").total_cmp(&value(
                    &s,
                    &format!("{b}/{case}"),
                    "mean",
                ))
            })
            .unwrap();
        assert!(
            report.contains(&format!("{case}: {best}")),
            "case {case}: expected winner {best}\n{report}"
        );
    }
}

#[test]
fn beacons_geometry_statement_follows_the_rows() {
    let text = preset("beacons.toml")
        .replace("runs = 100", "runs = 4")
        .replace("duration_s = 180.0", "duration_s = 30.0")
        .replace("outlier_count = 276", "outlier_count = 20");
    let (s, report) = run("report-geometry", "beacons", &text);
    // A layout is consistent with Table 13 when every scheme's paper mean lies in the
    // reproduced 95 % CI (the rows carry the paper value and the CI).
    let consistent = |suffix: &str| {
        ["AS", "SC", "SI"].iter().all(|scheme| {
            let row = s.row(&format!("{scheme}/high{suffix}"), "mean").unwrap();
            let [lo, hi] = row.ci95.unwrap();
            let p = row.paper.unwrap();
            lo <= p && p <= hi
        })
    };
    let mut expected: Vec<String> = Vec::new();
    if consistent("") {
        expected.push("`scenario`".into());
    }
    for layout in ["one_sided", "coplanar", "far"] {
        if consistent(&format!("@{layout}")) {
            expected.push(format!("`{layout}`"));
        }
    }
    let expected = if expected.is_empty() {
        "none".to_string()
    } else {
        expected.join(", ")
    };
    assert!(
        report.contains(&format!(
            "Layouts whose 95 % CIs contain all three: {expected}."
        )),
        "expected {expected}\n{report}"
    );
}

#[test]
fn noise_report_states_the_scenarios_t_gap_and_bias() {
    let text = preset("noise.toml")
        .replace("runs = 200", "runs = 4")
        .replace("duration_s = 180.0", "duration_s = 60.0")
        .replace("duration_s = 36000.0", "duration_s = 600.0")
        .replace("corr_gap_s = 1.0", "corr_gap_s = 3.0");
    let (_, report) = run("report-noise", "noise", &text);
    // sigma_c^2 t_gap / T = 3 / 60 = 5 %.
    assert!(
        report.contains("(5.00 % for a 60 s run with t_gap = 3 s)"),
        "{report}"
    );
}

#[test]
fn fusion_report_names_the_filters_above_the_turn_ratio_limit() {
    let text = preset("fusion.toml")
        .replace("runs = 200", "runs = 4")
        .replace("duration_s = 1000.0", "duration_s = 520.0")
        .replace("turn_ratio_limit = 1.1", "turn_ratio_limit = 0.5");
    let text = text
        .lines()
        .map(|l| {
            if l.starts_with("n_course_changes") {
                "n_course_changes = 4".to_string()
            } else if l.starts_with("leg_speeds_kt") {
                "leg_speeds_kt = [3.0, 4.0, 2.5, 4.5, 3.0]".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let (s, report) = run("report-fusion", "fusion", &text);
    let line = report
        .lines()
        .find(|l| {
            l.starts_with("Filters whose mean turn ratio exceeds the limit 0.5 under `bar_shalom`:")
        })
        .unwrap_or_else(|| panic!("{report}"));
    for m in ["MF", "T2T", "EFF"] {
        let above = value(&s, m, "turn_ratio_3d") > 0.5;
        assert_eq!(
            line.contains(&format!(" {m} ")),
            above,
            "{m}: ratio {}; {line}",
            value(&s, m, "turn_ratio_3d")
        );
    }
}

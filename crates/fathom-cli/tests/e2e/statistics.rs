//! The statistics of every summary row through the real `fathom` binary (issue 32):
//! each row names its unit, each interval its method; the mean of a non-negative
//! metric has a bootstrap interval that never reaches below zero; a row over runs has
//! its median and divergence count.

use fathom_report::output::read_summary_json;

use crate::support::{fathom, repo_root, scratch};

#[test]
fn every_row_has_a_unit_a_named_interval_and_no_negative_end_on_a_non_negative_metric() {
    let dir = scratch("statistics-rows");
    let preset = repo_root().join("scenarios/beacons.toml");
    let ran = fathom(
        &dir,
        &[
            "run",
            &preset.to_string_lossy(),
            "--runs",
            "20",
            "--seed",
            "3",
            "--out",
            "out",
        ],
    );
    assert_eq!(ran.code, 0, "{}", ran.stderr);
    let s = read_summary_json(dir.join("out/summary.json")).unwrap();
    let mut bootstrap = 0;
    for r in &s.rows {
        let name = format!("{} / {}", r.method, r.metric);
        assert!(!r.unit.is_empty(), "{name}: no unit");
        if let Some([lo, _]) = r.ci95 {
            let method = r.ci_method.as_deref().unwrap_or_else(|| panic!("{name}"));
            // Only a signed metric (a difference) may have a negative end, and only
            // with the Student-t interval.
            if lo < 0.0 {
                assert_eq!(method, "student-t", "{name}: {lo}");
            }
            if method == "bootstrap-bca" {
                bootstrap += 1;
                assert!(r.median.is_some() && r.median_ci95.is_some(), "{name}");
            }
        }
    }
    let rmse = s.row("SC/high", "rmse").unwrap();
    assert_eq!(rmse.ci_method.as_deref(), Some("bootstrap-bca"));
    assert!(rmse.divergence.is_some());
    assert!(bootstrap > 10, "{bootstrap} bootstrap rows");
    let report = std::fs::read_to_string(dir.join("out/report.md")).unwrap();
    assert!(report.contains("| median | diverged |"), "{report}");
    assert!(
        report.contains("`bootstrap-bca`: BCa bootstrap"),
        "{report}"
    );
}

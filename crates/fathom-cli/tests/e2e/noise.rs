//! End-to-end tests of the `noise` experiment on a reduced scenario.

use crate::support::{chain, preset, run_experiment, scratch, write_scenario};

/// The preset with few runs, a 60 s paper-length run and a 1200 s long run.
fn reduced() -> String {
    preset("noise.toml")
        .replace("runs = 200", "runs = 6")
        .replace("duration_s = 180.0", "duration_s = 60.0")
        .replace("duration_s = 36000.0", "duration_s = 1200.0")
}

#[test]
fn reduced_noise_run_writes_the_contract_outputs() {
    let root = scratch("noise-contract");
    write_scenario(&root, "noise.toml", &reduced());
    let result = run_experiment(&root, "noise", Some(2)).unwrap();
    let summary = &result.experiments[0].summary;
    assert_eq!(summary.experiment, "noise");
    assert_eq!(summary.runs, 6);

    for case in ["gaussian", "corr_high", "corr_low", "both_high", "both_low"] {
        for i in 1..=5 {
            for j in 1..=5 {
                let row = summary
                    .row(case, &format!("cov_{i}{j}"))
                    .unwrap_or_else(|| panic!("missing {case} cov_{i}{j}"));
                let ci = row.ci95.expect("every cov row has a CI");
                assert!(ci[0] <= row.value && row.value <= ci[1]);
                assert!(row.paper.is_some(), "{case} cov_{i}{j} has the paper value");
            }
        }
        let dev = summary.row(case, "long_run_max_rel_dev").unwrap().value;
        // 1200 s holds 1200 common-mode draws: a few percent, far below 50 %.
        assert!(dev.is_finite() && dev < 0.5, "{case}: {dev}");
    }
    // Design values: white depth noise 0.04 m^2, correlation-only cases none.
    let depth = summary.row("gaussian", "cov_55").unwrap().value;
    assert!((depth - 0.04).abs() < 0.01, "{depth}");
    assert_eq!(summary.row("corr_high", "cov_55").unwrap().value, 0.0);

    let claim = summary
        .claims
        .iter()
        .find(|c| c.id == "generator_cov_matches_design")
        .expect("the claim is evaluated");
    assert!(claim.detail.contains("long run"));

    let dir = root.join("out").join("noise");
    for file in [
        "summary.json",
        "report.md",
        "sample_times.svg",
        "convergence.svg",
        "cov_both_high.svg",
        "per_run_covariance.csv",
    ] {
        assert!(dir.join(file).is_file(), "missing {file}");
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("inconsistencies"));
    assert!(root.join("out").join("REPORT.md").is_file());
}

#[test]
fn noise_summary_is_identical_for_one_and_two_threads() {
    let mut texts = Vec::new();
    for threads in [1, 2] {
        let root = scratch(&format!("noise-threads-{threads}"));
        write_scenario(&root, "noise.toml", &reduced());
        run_experiment(&root, "noise", Some(threads)).unwrap();
        texts.push(std::fs::read(root.join("out/noise/summary.json")).unwrap());
    }
    assert_eq!(texts[0], texts[1]);
}

#[test]
fn malformed_noise_scenarios_name_the_key() {
    let cases = [
        (
            "unknown key",
            reduced().replace("corr_gap_s = 1.0", "corr_gap_s = 1.0\nrange_sigma = 0.1"),
            "range_sigma",
        ),
        (
            "negative sigma",
            reduced().replace("depth_sigma_m = 0.2", "depth_sigma_m = -0.2"),
            "noise.depth_sigma_m",
        ),
        (
            "missing field",
            reduced().replace("jitter_sigma_s = 0.001", ""),
            "jitter_sigma_s",
        ),
        (
            "wrong type",
            reduced().replace("period_s = 0.1", "period_s = \"fast\""),
            "timing.period_s",
        ),
    ];
    for (what, text, key) in cases {
        let root = scratch(&format!("noise-bad-{}", what.replace(' ', "-")));
        write_scenario(&root, "noise.toml", &text);
        let err = run_experiment(&root, "noise", Some(1)).expect_err(what);
        let msg = chain(&err);
        assert!(msg.contains(key), "{what}: {msg}");
        assert!(msg.contains("noise.toml"), "{what}: {msg}");
    }
}

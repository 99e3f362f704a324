//! End-to-end tests of `smooth = true` (issue #24, the RTS smoother as post-processing):
//! on the whole CMU Plaza1 log (the repository's copy, `data/plaza1`) the smoothed rows sit beside the filtered ones with the GTSAM batch reference,
//! the filtered results are unchanged by recording, and the acceptance target holds; on
//! reduced `beacons` and `vkf` scenarios the smoothed rows with CIs are added and every
//! filtered row stays as it was.

use fathom_experiments::plaza::{GTSAM_BATCH_M, MAIN_METHODS, SMOOTHED_TARGET_M, smoothed_name};
use fathom_replay::plaza::{PlazaReplay, parse_settings, replay};

use crate::support::{preset, repo_root, run_experiment, scratch, write_scenario};

/// The preset with `smooth` set and the data folder (the repository's copy) made
/// absolute.
fn plaza_scenario(smooth: bool) -> String {
    let dir = repo_root().join("data/plaza1");
    let text = preset("plaza.toml");
    assert!(
        text.contains("\nsmooth = false\n"),
        "the preset does not smooth"
    );
    text.replace("\nsmooth = false\n", &format!("\nsmooth = {smooth}\n"))
        .replace(
            "dir = \"data/plaza1\"",
            &format!("dir = {:?}", dir.to_str().unwrap()),
        )
}

fn replay_with(text: &str) -> PlazaReplay {
    let settings = parse_settings(text, "plaza.toml").unwrap();
    let log = fathom_data::plaza::PlazaLog::read_dir(
        std::path::Path::new(&settings.data_dir),
        settings.range_order,
    )
    .unwrap();
    replay(&log, &settings).unwrap()
}

#[test]
fn plaza_smoothing_leaves_the_filters_alone_and_beats_them() {
    let (off, on) = (plaza_scenario(false), plaza_scenario(true));
    let a = replay_with(&off);
    let b = replay_with(&on);
    assert_eq!(a.methods.len(), b.methods.len());
    for (ma, mb) in a.methods.iter().zip(&b.methods) {
        // Recording the forward pass changes nothing of the filter (bit for bit).
        assert_eq!(ma.est, mb.est, "{}", ma.name);
        assert_eq!(ma.stats, mb.stats, "{}", ma.name);
        assert_eq!(ma.decisions, mb.decisions, "{}", ma.name);
        assert!(ma.smoothed.is_none());
        // Dead reckoning has nothing to smooth; every filter has.
        assert_eq!(mb.smoothed.is_some(), mb.variant.is_some(), "{}", mb.name);
    }
    for name in MAIN_METHODS {
        let m = b.method(name).unwrap();
        let s = m.smoothed.as_ref().unwrap();
        assert_eq!(s.err.len(), m.err.len());
        // The smoother uses the future ranges: clearly better, not merely different.
        assert!(
            s.stats.mean < 0.9 * m.stats.mean && s.stats.rmse < m.stats.rmse,
            "{name}: smoothed {:?} filtered {:?}",
            s.stats,
            m.stats
        );
        // Acceptance (#24): at most 0.20 m with the filter's settings.
        assert!(
            s.stats.mean <= SMOOTHED_TARGET_M,
            "{name}: {}",
            s.stats.mean
        );
        // The smoothed covariance is never above the filtered one.
        for (k, (ps, pf)) in s.pos_sigma.iter().zip(&m.pos_sigma).enumerate() {
            assert!(*ps <= pf * (1.0 + 1e-9), "{name} step {k}: {ps} > {pf}");
        }
    }
}

#[test]
fn plaza_smoothed_rows_report_and_files() {
    let on = plaza_scenario(true);
    let root = scratch("smoother-plaza");
    write_scenario(&root, "plaza.toml", &on);
    let result = run_experiment(&root, "plaza", Some(1)).unwrap();
    let summary = &result.experiments[0].summary;
    for name in ["AS", "SC", "SI", "SC-no-bias", "SC-hard-gate"] {
        let sname = smoothed_name(name);
        for metric in ["mean", "std", "max", "rmse"] {
            let row = summary
                .row(&sname, metric)
                .unwrap_or_else(|| panic!("missing {sname} {metric}"));
            assert!(row.value.is_finite() && row.value >= 0.0);
            assert!(row.ci95.is_none());
            let reference = GTSAM_BATCH_M.iter().find(|(k, _)| *k == metric);
            let expect = reference.filter(|_| MAIN_METHODS.contains(&name));
            assert_eq!(row.paper, expect.map(|(_, v)| *v), "{sname} {metric}");
        }
        // The filtered row is still there, without a reference.
        assert!(summary.row(name, "mean").unwrap().paper.is_none());
    }
    assert!(summary.row("DR+RTS", "mean").is_none());
    let claim = summary
        .claims
        .iter()
        .find(|c| c.id == "smoothed_mean_at_most_0_20m")
        .unwrap();
    assert!(claim.holds, "{}", claim.detail);
    let dir = root.join("out").join("plaza");
    assert!(dir.join("smoothed_error.svg").is_file());
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(report.contains("Post-processing: RTS smoother"), "{report}");
    assert!(report.contains("GTSAM mean [m]"), "{report}");
    assert!(report.contains("B per step"), "{report}");
    let csv = std::fs::read_to_string(dir.join("estimates.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(header.contains("SC+RTS_err_m"), "{header}");
    assert!(header.contains("SC+RTS_sigma_pos_m"), "{header}");
}

/// `text` with `smooth = true` as a top-level key (before the first table).
fn with_smooth(text: &str) -> String {
    let i = text.find("\n[").unwrap();
    format!("{}\nsmooth = true{}", &text[..i], &text[i..])
}

/// Runs experiment `name` from `text` in a scratch workspace; returns the summary.
fn run_summary(tag: &str, name: &str, text: &str) -> fathom_report::output::Summary {
    let root = scratch(tag);
    write_scenario(&root, &format!("{name}.toml"), text);
    let result = run_experiment(&root, name, Some(2)).unwrap();
    result.experiments[0].summary.clone()
}

/// Every row of `off` is in `on` unchanged (smoothing only adds rows).
fn filtered_rows_unchanged(
    off: &fathom_report::output::Summary,
    on: &fathom_report::output::Summary,
) {
    for row in &off.rows {
        assert_eq!(on.row(&row.method, &row.metric), Some(row), "{row:?}");
    }
    assert!(on.rows.len() > off.rows.len());
}

#[test]
fn beacons_smoothed_rows_with_cis_beside_the_filtered_ones() {
    let reduced = preset("beacons.toml")
        .replace("runs = 100", "runs = 5")
        .replace("duration_s = 180.0", "duration_s = 20.0")
        .replace("outlier_count = 276", "outlier_count = 30");
    let off = run_summary("smoother-beacons-off", "beacons", &reduced);
    let on = run_summary("smoother-beacons-on", "beacons", &with_smooth(&reduced));
    filtered_rows_unchanged(&off, &on);
    for case in ["high", "low", "none", "sync"] {
        for scheme in ["AS", "SC", "SI"] {
            let m = format!("{scheme}+RTS/{case}");
            for metric in ["mean", "std", "max", "rmse", "nees"] {
                let row = on
                    .row(&m, metric)
                    .unwrap_or_else(|| panic!("missing {m} {metric}"));
                let [lo, hi] = row.ci95.unwrap();
                assert!(lo <= row.value && row.value <= hi, "{row:?}");
                assert!(row.paper.is_none());
            }
            // Smoothing uses later ranges: the mean error drops.
            let filtered = on.row(&format!("{scheme}/{case}"), "mean").unwrap().value;
            assert!(on.row(&m, "mean").unwrap().value < filtered, "{m}");
        }
    }
    let claim = on
        .claims
        .iter()
        .find(|c| c.id == "smoothing_lowers_mean_error")
        .unwrap();
    assert!(claim.holds, "{}", claim.detail);
    assert!(off.claims.iter().all(|c| c.id != claim.id));
}

#[test]
fn vkf_smoothed_rows_inside_the_dvl_invalid_intervals() {
    let short = crate::vkf::short_scenario()
        .replace("literal_bias_runs = 50", "literal_bias_runs = 0")
        .replace("runs = 50", "runs = 3");
    let off = run_summary("smoother-vkf-off", "vkf", &short);
    let on = run_summary("smoother-vkf-on", "vkf", &with_smooth(&short));
    filtered_rows_unchanged(&off, &on);
    for name in ["VKF", "ESKF"] {
        for metric in ["rms_h_invalid", "max_h_invalid"] {
            let row = on.row(name, metric).unwrap();
            assert!(row.value > 0.0 && row.ci95.is_some(), "{row:?}");
        }
        for metric in ["rms_h", "rms_h_invalid", "max_h_invalid"] {
            let row = on.row(&format!("{name}+RTS"), metric).unwrap();
            assert!(row.value.is_finite() && row.value > 0.0, "{row:?}");
            assert!(row.ci95.is_some());
        }
        // The smoother changes the estimate (it is not the filter read twice), but
        // by a bounded amount.
        let f = on.row(name, "rms_h_invalid").unwrap().value;
        let s = on
            .row(&format!("{name}+RTS"), "rms_h_invalid")
            .unwrap()
            .value;
        assert!(s != f && (s - f).abs() < 0.5 * f, "{name}: {s} vs {f}");
    }
    assert!(
        on.claims
            .iter()
            .any(|c| c.id == "smoothing_lowers_error_when_dvl_invalid")
    );
}

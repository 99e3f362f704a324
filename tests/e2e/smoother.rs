//! End-to-end tests of `smooth = true` (issue #24, the RTS smoother as post-processing):
//! on the whole CMU Plaza1 log (from `../shared/data/plaza1`; skipped with a message when
//! absent) the smoothed rows sit beside the filtered ones with the GTSAM batch reference,
//! the filtered results are unchanged by recording, and the acceptance target holds.

use fathom::sim::experiments::plaza::{
    GTSAM_BATCH_M, MAIN_METHODS, SMOOTHED_TARGET_M, find_data_dir, smoothed_name,
};
use fathom::sim::replay::plaza::{PlazaReplay, parse_settings, replay};

use crate::support::{preset, repo_root, run_experiment, scratch, write_scenario};

/// The preset with `smooth` set and the data folder made absolute (`None`: no data).
fn plaza_scenario(smooth: bool) -> Option<String> {
    let Some(dir) = find_data_dir(&repo_root(), "shared/data/plaza1") else {
        eprintln!("skipped: shared/data/plaza1 not found beside the repository");
        return None;
    };
    let text = preset("plaza.toml");
    assert!(
        text.contains("\nsmooth = false\n"),
        "the preset does not smooth"
    );
    Some(
        text.replace("\nsmooth = false\n", &format!("\nsmooth = {smooth}\n"))
            .replace(
                "dir = \"shared/data/plaza1\"",
                &format!("dir = {:?}", dir.to_str().unwrap()),
            ),
    )
}

fn replay_with(text: &str) -> PlazaReplay {
    let settings = parse_settings(text, "plaza.toml").unwrap();
    let log = fathom::sim::data::plaza::PlazaLog::read_dir(
        std::path::Path::new(&settings.data_dir),
        settings.range_order,
    )
    .unwrap();
    replay(&log, &settings).unwrap()
}

#[test]
fn plaza_smoothing_leaves_the_filters_alone_and_beats_them() {
    let (Some(off), Some(on)) = (plaza_scenario(false), plaza_scenario(true)) else {
        return;
    };
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
    let Some(on) = plaza_scenario(true) else {
        return;
    };
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

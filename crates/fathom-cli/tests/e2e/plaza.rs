//! End-to-end tests of the `plaza` replay on real data, on copies of Plaza1 made at test
//! time from the repository's `data/plaza1` into a temporary folder (edited copies are
//! never committed): the experiment's contract outputs on a truncated copy (600 s), and
//! on whole-log copies the acceptance numbers and the invariance of every error to
//! renumbered beacons and a clock shifted by +10000 s.

use std::path::{Path, PathBuf};

use fathom_data::matv5::{NamedMatrix, write_mat_v5};
use fathom_data::plaza::{PlazaFiles, PlazaLog, read_mat};
use fathom_replay::plaza::{PlazaReplay, parse_settings, replay};

use crate::support::{preset, repo_root, run_experiment, scratch, write_scenario};

/// The repository's copy of Plaza1 (data/plaza1).
fn plaza1() -> PathBuf {
    let dir = repo_root().join("data/plaza1");
    assert!(dir.is_dir(), "{} is missing", dir.display());
    dir
}

/// How to modify the copy.
#[derive(Clone, Copy)]
struct Edit {
    /// Keep rows with `t < t_start + seconds` (infinite: the whole log).
    seconds: f64,
    /// Added to every time stamp.
    shift: f64,
    /// Beacon id map (old -> new), or none.
    renumber: Option<&'static [(i64, i64)]>,
}

fn map_id(edit: Edit, id: f64) -> f64 {
    match edit.renumber {
        None => id,
        Some(m) => m
            .iter()
            .find(|(old, _)| *old as f64 == id)
            .map_or(id, |(_, new)| *new as f64),
    }
}

/// Writes a modified copy of the Plaza data in `src` into `dst`, in the native formats
/// (text files line by line; the `.mat` with `GT`, `TL`, `DRp`).
fn make_copy(src: &Path, dst: &Path, edit: Edit) {
    std::fs::create_dir_all(dst).unwrap();
    let files = PlazaFiles::find(src).unwrap();
    let mat = read_mat(&files.mat).unwrap();
    let t_start = mat.ground_truth[0].time;
    let end = t_start + edit.seconds;
    let copy_text = |from: &Path, name: &str, id_column: Option<usize>| {
        let text = std::fs::read_to_string(from).unwrap();
        let mut out = String::new();
        for line in text.lines() {
            let mut f: Vec<f64> = line
                .split_whitespace()
                .map(|v| v.parse().unwrap())
                .collect();
            if f.is_empty() || f[0] >= end {
                continue;
            }
            f[0] += edit.shift;
            if let Some(c) = id_column {
                f[c] = map_id(edit, f[c]);
            }
            let cells: Vec<String> = f.iter().map(|v| format!("{v:e}")).collect();
            out.push_str(&cells.join("\t"));
            out.push_str("\r\n");
        }
        std::fs::write(dst.join(name), out).unwrap();
    };
    copy_text(&files.odometry, "Copy_DR.txt", None);
    copy_text(&files.ranges, "Copy_TD.txt", Some(2));
    let poses = |p: &[fathom_data::plaza::PoseRecord]| -> Vec<Vec<f64>> {
        p.iter()
            .filter(|r| r.time < end)
            .map(|r| vec![r.time + edit.shift, r.x, r.y, r.heading])
            .collect()
    };
    write_mat_v5(
        dst.join("Copy_.mat"),
        &[
            NamedMatrix::new("GT", poses(&mat.ground_truth)),
            NamedMatrix::new(
                "TL",
                mat.beacons
                    .iter()
                    .map(|b| vec![map_id(edit, b.id as f64), b.x, b.y])
                    .collect(),
            ),
            NamedMatrix::new("DRp", poses(&mat.dr_path)),
        ],
    )
    .unwrap();
}

fn replay_dir(dir: &Path) -> PlazaReplay {
    let settings = parse_settings(&preset("plaza.toml"), "plaza.toml").unwrap();
    let log = PlazaLog::read_dir(dir, settings.range_order).unwrap();
    replay(&log, &settings).unwrap()
}

#[test]
fn experiment_runs_on_a_truncated_copy_and_writes_the_contract_outputs() {
    let src = plaza1();
    let root = scratch("plaza-contract");
    let data = root.join("data").join("plaza1-600s");
    make_copy(
        &src,
        &data,
        Edit {
            seconds: 600.0,
            shift: 0.0,
            renumber: None,
        },
    );
    let scenario = preset("plaza.toml").replace(
        "dir = \"data/plaza1\"",
        &format!("dir = {:?}", data.to_str().unwrap()),
    );
    write_scenario(&root, "plaza.toml", &scenario);
    let result = run_experiment(&root, "plaza", Some(1)).unwrap();
    crate::support::assert_every_row_has_a_unit(&result.experiments[0]);
    let summary = &result.experiments[0].summary;
    assert_eq!(summary.experiment, "plaza");
    assert_eq!(summary.runs, 1);
    for method in ["DR", "AS", "SC", "SI", "SC-no-bias", "SC-hard-gate"] {
        for metric in ["mean", "std", "max", "rmse", "rejected"] {
            let row = summary
                .row(method, metric)
                .unwrap_or_else(|| panic!("missing {method} {metric}"));
            assert!(row.value.is_finite() && row.value >= 0.0);
            assert!(row.paper.is_none() && row.ci95.is_none());
        }
        let m = summary.row(method, "mean").unwrap().value;
        let rmse = summary.row(method, "rmse").unwrap().value;
        assert!(rmse >= m);
    }
    // Ten minutes of driving: every scheme stays within a few metres.
    for method in ["AS", "SC", "SI"] {
        let max = summary.row(method, "max").unwrap().value;
        assert!(max < 6.0, "{method} max {max}");
    }
    let dir = root.join("out").join("plaza");
    for file in [
        "summary.json",
        "report.md",
        "estimates.csv",
        "ranges.csv",
        "estimate_vs_truth.svg",
        "error_3sigma.svg",
        "innovations.svg",
        "nis.svg",
        "error_vs_time.svg",
        "ablation_error.svg",
        "range_error_vs_distance.svg",
        "calibration.svg",
    ] {
        assert!(dir.join(file).is_file(), "missing {file}");
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for needle in [
        "Range bias",
        "Huber",
        "lock",
        "relative to t0",
        "SC-no-bias",
    ] {
        assert!(report.contains(needle), "report lacks {needle:?}");
    }
    // The ablation sentence follows the numbers of this log.
    let mean = |m: &str| summary.row(m, "mean").unwrap().value;
    let scale_helps = mean("SC-offset-only") > mean("SC");
    assert_eq!(
        report.contains("Adding the scale state removes it."),
        scale_helps,
        "{report}"
    );
    assert_eq!(
        report.contains("On this log the scale state does not improve the mean error."),
        !scale_helps,
        "{report}"
    );
    let csv = std::fs::read_to_string(dir.join("estimates.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(
        header.starts_with("time_s,true_x_m,true_y_m,DR_x_m"),
        "{header}"
    );
    assert!(header.contains("SC_range_scale"), "{header}");
}

#[test]
fn renumbered_beacons_and_shifted_clock_give_identical_errors() {
    let src = plaza1();
    let root = scratch("plaza-invariance");
    let plain = root.join("plain");
    let moved = root.join("moved");
    // The whole log (a replay takes well under a second): the acceptance numbers are
    // checked on both copies too.
    let seconds = f64::INFINITY;
    make_copy(
        &src,
        &plain,
        Edit {
            seconds,
            shift: 0.0,
            renumber: None,
        },
    );
    make_copy(
        &src,
        &moved,
        Edit {
            seconds,
            shift: 10_000.0,
            renumber: Some(&[(0, 17), (1, 5), (5, 1), (6, 42)]),
        },
    );
    let a = replay_dir(&plain);
    let b = replay_dir(&moved);
    // The copy really differs: other ids, other clock.
    assert_ne!(
        a.beacons.iter().map(|x| x.id).collect::<Vec<_>>(),
        b.beacons.iter().map(|x| x.id).collect::<Vec<_>>()
    );
    assert!((b.prepared.t0 - a.prepared.t0 - 10_000.0).abs() < 1e-6);
    assert_eq!(a.methods.len(), b.methods.len());
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-3);
    for (ma, mb) in a.methods.iter().zip(&b.methods) {
        assert_eq!(ma.name, mb.name);
        for (what, x, y) in [
            ("mean", ma.stats.mean, mb.stats.mean),
            ("std", ma.stats.std, mb.stats.std),
            ("max", ma.stats.max, mb.stats.max),
            ("rmse", ma.stats.rmse, mb.stats.rmse),
        ] {
            assert!(close(x, y), "{} {what}: {x} vs {y}", ma.name);
        }
        assert_eq!(ma.rejected, mb.rejected, "{}", ma.name);
        assert_eq!(ma.downweighted, mb.downweighted, "{}", ma.name);
        assert_eq!(ma.err.len(), mb.err.len());
        for (k, (x, y)) in ma.err.iter().zip(&mb.err).enumerate() {
            assert!(close(*x, *y), "{} error {k}: {x} vs {y}", ma.name);
        }
    }
    for r in [&a, &b] {
        let dr = r.method("DR").unwrap().stats.mean;
        for name in ["AS", "SC", "SI"] {
            let m = r.method(name).unwrap().stats;
            assert!(m.mean <= 0.65 * dr, "{name}: mean {} vs DR {dr}", m.mean);
            assert!(m.max <= 4.0, "{name}: max {}", m.max);
        }
    }
    // Negative control: a real change (one beacon moved by 1 m) is detected.
    let shifted = root.join("beacon-moved");
    make_copy(
        &src,
        &shifted,
        Edit {
            seconds,
            shift: 0.0,
            renumber: None,
        },
    );
    let files = PlazaFiles::find(&shifted).unwrap();
    let mut mat = read_mat(&files.mat).unwrap();
    mat.beacons[0].x += 1.0;
    write_mat_v5(&files.mat, &mat.to_matrices()).unwrap();
    let c = replay_dir(&shifted);
    let sc_a = a.method("SC").unwrap().stats.mean;
    let sc_c = c.method("SC").unwrap().stats.mean;
    assert!(!close(sc_a, sc_c), "moving a beacon must change the errors");
}

/// The data ships in the repository: `cargo xtask paper` refuses a missing data
/// folder (naming the key) instead of skipping the experiment.
#[test]
fn missing_data_folder_is_refused_not_skipped() {
    let root = scratch("plaza-missing");
    let scenario =
        preset("plaza.toml").replace("dir = \"data/plaza1\"", "dir = \"no/such/plaza/folder\"");
    write_scenario(&root, "plaza.toml", &scenario);
    let e = run_experiment(&root, "plaza", Some(1)).unwrap_err();
    assert!(e.is_user_error());
    let s = crate::support::chain(&e);
    assert!(
        s.contains("data.dir") && s.contains("no/such/plaza/folder"),
        "{s}"
    );
    assert!(!root.join("out/plaza/summary.json").exists());
}

#[test]
fn bad_settings_are_named() {
    let root = scratch("plaza-bad");
    let scenario = preset("plaza.toml").replace("huber_k = 2.0", "huber_k = -2.0");
    write_scenario(&root, "plaza.toml", &scenario);
    let e = run_experiment(&root, "plaza", Some(1)).unwrap_err();
    let s = crate::support::chain(&e);
    assert!(
        s.contains("robust.huber_k") && s.contains("must be > 0"),
        "{s}"
    );
}

//! The README's walkthrough through the real `fathom` binary: check the preset, copy
//! `scenarios/beacons.toml`, replace the beacons by the README's six (and by 3 and 1),
//! run `fathom run`, get results and plots; bad edits give one-line errors with
//! exit 2. (The mission is shortened to 30 s and the runs to 6 to stay fast.)

use std::path::Path;

use crate::support::{fathom, preset, read, repo_root, scratch};

/// The README's six-beacon `[beacons]` table, taken from README.md itself (the
/// indented ```toml block starting with `[beacons]`), so the walkthrough cannot drift.
fn readme_beacons_table() -> String {
    let readme = std::fs::read_to_string(repo_root().join("README.md")).unwrap();
    for cmd in [
        "fathom check scenarios/beacons.toml",
        "cp scenarios/beacons.toml my_beacons.toml",
        "fathom run my_beacons.toml --runs 20 --out fathom-out/my_beacons",
        "cargo build --release -p fathom-cli",
    ] {
        assert!(readme.contains(cmd), "README lost the step `{cmd}`");
    }
    let lines: Vec<&str> = readme.lines().collect();
    let start = (0..lines.len() - 1)
        .find(|&i| lines[i].trim() == "```toml" && lines[i + 1].trim() == "[beacons]")
        .expect("README has a ```toml block with the [beacons] table");
    let indent = lines[start].len() - lines[start].trim_start().len();
    let mut table = String::new();
    for line in &lines[start + 1..] {
        if line.trim() == "```" {
            return table;
        }
        table.push_str(line.get(indent..).unwrap_or(line.trim_start()));
        table.push('\n');
    }
    panic!("unterminated ```toml block in README.md")
}

/// Three beacons, non-collinear, one deep.
const THREE: &str = "positions = [[20.0, 0.0, 0.0], [-10.0, 17.3, 40.0], [-10.0, -17.3, 0.0]]";

/// The preset with its `[beacons]` table (header and `positions` line) replaced by
/// `table`, on a 30 s mission (fewer outliers to match): a user's edit, made fast.
fn edited_table(table: &str) -> String {
    let text = preset("beacons.toml");
    let line = text
        .lines()
        .find(|l| l.starts_with("positions = "))
        .expect("the preset has a positions line");
    let old = format!("[beacons]\n{line}\n");
    assert!(text.contains(&old), "the preset's [beacons] table moved");
    text.replace(&old, table)
        .replace("duration_s = 180.0", "duration_s = 30.0")
        .replace("outlier_count = 276", "outlier_count = 40")
}

/// [`edited_table`] with a one-line `positions = ...`.
fn edited(positions: &str) -> String {
    edited_table(&format!("[beacons]\n{positions}\n"))
}

/// Runs `fathom check` and `fathom run` on `text` as `my_beacons.toml` and checks the
/// outputs of a `k`-beacon run.
fn walkthrough(tag: &str, text: &str, k: usize) {
    let preset_check = fathom(&repo_root(), &["check", "scenarios/beacons.toml"]);
    assert_eq!(preset_check.code, 0, "{preset_check:?}");
    assert!(
        preset_check.stdout.contains("[beacons]"),
        "{preset_check:?}"
    );
    let dir = scratch(tag);
    std::fs::write(dir.join("my_beacons.toml"), text).unwrap();
    let check = fathom(&dir, &["check", "my_beacons.toml"]);
    assert_eq!(check.code, 0, "{check:?}");
    assert!(
        check
            .stdout
            .starts_with("# OK my_beacons.toml: experiment `beacons`"),
        "{check:?}"
    );
    let ran = fathom(
        &dir,
        &[
            "run",
            "my_beacons.toml",
            "--runs",
            "6",
            "--out",
            "out/my_beacons",
        ],
    );
    assert_eq!(ran.code, 0, "{ran:?}");
    // Not a terminal: no progress bar on stderr.
    assert!(ran.stderr.is_empty(), "{ran:?}");
    assert!(ran.stdout.starts_with("beacons ("), "{}", ran.stdout);
    // The user's scenario is reported as theirs: not the paper's seed file, none of
    // the paper's layout batches or claims, a short table with the rest counted.
    assert!(
        ran.stdout
            .starts_with("beacons (your scenario my_beacons.toml)")
            && !ran.stdout.contains("003_")
            && !ran.stdout.contains("layout")
            && !ran.stdout.contains("claims")
            && ran.stdout.contains("more rows in report.md"),
        "{}",
        ran.stdout
    );
    assert!(
        ran.stdout.contains("outputs: out/my_beacons"),
        "{}",
        ran.stdout
    );

    let out = dir.join("out/my_beacons");
    for file in [
        "summary.json",
        "report.md",
        "run_info.json",
        "scenario.toml",
        "scenario.resolved.toml",
        "error_vs_time.csv",
        "per_run_stats.csv",
        "single_run_estimates.csv",
        "path_plan.svg",
        "sample_times.svg",
        "error_vs_time_high.svg",
        "error_vs_time_single_run.svg",
        "sc_estimate_vs_truth_plan.svg",
    ] {
        let meta = std::fs::metadata(out.join(file)).unwrap_or_else(|_| panic!("missing {file}"));
        assert!(meta.len() > 100, "{file} is nearly empty");
    }
    sane_results(&out, k);
}

fn sane_results(out: &Path, k: usize) {
    let summary: serde_json::Value = serde_json::from_str(&read(out, "summary.json")).unwrap();
    assert_eq!(summary["runs"], 6);
    assert_eq!(
        summary["claims"].as_array().map(Vec::len),
        Some(0),
        "{summary}"
    );
    let rows = summary["rows"].as_array().unwrap();
    for scheme in ["AS", "SC", "SI"] {
        let value = |metric: &str| {
            rows.iter()
                .find(|r| r["method"] == format!("{scheme}/high") && r["metric"] == metric)
                .and_then(|r| r["value"].as_f64())
                .unwrap_or_else(|| panic!("no {scheme}/high {metric}"))
        };
        // The 4-beacon preset localizes to ~0.15 m; dead reckoning alone drifts
        // further. Any sane K-beacon fix stays well inside 0.5 m on a 30 s mission.
        let mean = value("mean");
        assert!(
            mean.is_finite() && mean > 0.0 && mean < 0.5,
            "{scheme}: {mean}"
        );
        assert!(value("max") >= mean && value("rmse") >= mean, "{scheme}");
        let recall = value("outlier_recall");
        assert!((0.8..=1.0).contains(&recall), "{scheme}: recall {recall}");
    }
    // One entry per beacon in the report's gate table and the sample-time figure; none
    // beyond K.
    let report = read(out, "report.md");
    assert!(report.contains(&format!("- {k} beacons")), "{report}");
    let timeline = read(out, "sample_times.svg");
    for b in 1..=k {
        assert!(report.contains(&format!("| AS | range{b} |")), "range{b}");
        assert!(timeline.contains(&format!("range{b}")), "range{b}");
    }
    let next = format!("range{}", k + 1);
    assert!(!report.contains(&format!("| AS | {next} |")));
    assert!(!timeline.contains(&next));
    // The plan view marks every beacon.
    let plan = read(out, "path_plan.svg");
    assert!(plan.contains("beacons"));
}

#[test]
fn six_beacons_from_an_edited_preset_run_end_to_end() {
    walkthrough(
        "user-six-beacons",
        &edited_table(&readme_beacons_table()),
        6,
    );
}

/// `--paper-extras` runs the paper's layout batches and judges its claims on a user's
/// scenario (the negative control of the walkthrough's "reported as yours").
#[test]
fn paper_extras_on_a_user_scenario_run_the_layouts_and_claims() {
    let dir = scratch("user-paper-extras");
    let text = edited_table(&readme_beacons_table());
    std::fs::write(dir.join("my_beacons.toml"), &text).unwrap();
    let ran = fathom(
        &dir,
        &[
            "run",
            "my_beacons.toml",
            "--runs",
            "4",
            "--out",
            "out",
            "--paper-extras",
        ],
    );
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(
        ran.stdout.contains("layout one_sided") && ran.stdout.contains("claims on your scenario"),
        "{}",
        ran.stdout
    );
    let summary: serde_json::Value =
        serde_json::from_str(&read(&dir.join("out"), "summary.json")).unwrap();
    assert!(!summary["claims"].as_array().unwrap().is_empty());
    let resolved = read(&dir.join("out"), "scenario.resolved.toml");
    assert!(resolved.contains("[[geometry]]"), "{resolved}");
}

#[test]
fn three_beacons_run_end_to_end() {
    walkthrough("user-three-beacons", &edited(THREE), 3);
}

/// A single beacon is accepted (documented: fewer than 3 leave the horizontal
/// position weakly observable, the run still works); no beacon, a malformed position
/// and more outliers than range samples are one-line usage errors (exit 2).
#[test]
fn few_beacons_and_bad_beacon_edits() {
    let dir = scratch("user-bad-beacons");
    let one = edited("positions = [[20.0, 0.0, 0.0]]");
    std::fs::write(dir.join("one.toml"), &one).unwrap();
    let ran = fathom(&dir, &["run", "one.toml", "--runs", "2", "--out", "one"]);
    assert_eq!(ran.code, 0, "{ran:?}");

    for (file, text, expected) in [
        (
            "none.toml",
            edited("positions = []"),
            "none.toml: key `beacons.positions`: needs at least one beacon",
        ),
        (
            "two_coords.toml",
            edited("positions = [[20.0, 0.0], [1.0, 2.0, 3.0]]"),
            "two_coords.toml: key `beacons.positions",
        ),
        (
            "too_many_outliers.toml",
            one.replace("outlier_count = 40", "outlier_count = 400"),
            "too_many_outliers.toml: key `noise.outlier_count`: 400 outliers do not fit into \
             the 300 range samples",
        ),
    ] {
        std::fs::write(dir.join(file), &text).unwrap();
        for args in [vec!["check", file], vec!["run", file, "--out", "o"]] {
            let ran = fathom(&dir, &args);
            assert_eq!(ran.code, 2, "{args:?}: {ran:?}");
            let line = ran.stderr.trim_end();
            assert_eq!(line.lines().count(), 1, "{ran:?}");
            assert!(line.starts_with("error: "), "{ran:?}");
            assert!(line.contains(expected), "{args:?}: {line}");
            assert!(!line.contains("panicked"), "{line}");
        }
    }
}

/// `text` with the top-level line `line` added after its `runs` key.
fn with_top_level(text: &str, line: &str) -> String {
    let runs = text
        .lines()
        .find(|l| l.starts_with("runs = "))
        .expect("the preset has a runs line");
    text.replacen(runs, &format!("{runs}\n{line}"), 1)
}

/// `methods = [...]` runs, reports and plots only the selected schemes (the paper's
/// scheme comparisons are left out with a note); an unknown name is a one-line usage
/// error naming the key and listing what `beacons` accepts; `fathom list` names them.
#[test]
fn methods_select_the_schemes_run() {
    let dir = scratch("user-methods");
    let text = with_top_level(&edited(THREE), "methods = [\"SI\", \"AS\"]");
    std::fs::write(dir.join("two.toml"), &text).unwrap();
    let ran = fathom(&dir, &["run", "two.toml", "--runs", "3", "--out", "two"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let out = dir.join("two");
    let summary: serde_json::Value = serde_json::from_str(&read(&out, "summary.json")).unwrap();
    let methods: std::collections::BTreeSet<String> = summary["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["method"].as_str().unwrap().to_string())
        .collect();
    assert!(
        methods.contains("AS/high") && methods.contains("SI/high"),
        "{methods:?}"
    );
    assert!(!methods.iter().any(|m| m.starts_with("SC")), "{methods:?}");
    // The claims compare all three schemes: none is made with two.
    assert_eq!(
        summary["claims"].as_array().map_or(0, Vec::len),
        0,
        "{summary}"
    );
    let report = read(&out, "report.md");
    assert!(report.contains("Selected schemes: AS, SI"), "{report}");
    assert!(!report.contains("| SC/high"), "{report}");
    let csv = read(&out, "error_vs_time.csv");
    assert!(
        csv.starts_with("time_s,AS_high_mean_error_m,SI_high_mean_error_m"),
        "{csv}"
    );
    assert!(out.join("as_estimate_vs_truth_plan.svg").exists());
    assert!(!out.join("sc_estimate_vs_truth_plan.svg").exists());
    // An SVG legend entry is `<text ...>\nSC\n</text>`.
    assert!(!read(&out, "error_vs_time_high.svg").contains("\nSC\n</text>"));

    // Negative control: without the key all three schemes run.
    std::fs::write(dir.join("all.toml"), edited(THREE)).unwrap();
    let ran = fathom(&dir, &["run", "all.toml", "--runs", "3", "--out", "all"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(read(&dir.join("all"), "summary.json").contains("\"SC/high\""));
    assert!(read(&dir.join("all"), "error_vs_time_high.svg").contains("\nSC\n</text>"));

    let bad = with_top_level(&edited(THREE), "methods = [\"AS\", \"UKF\"]");
    std::fs::write(dir.join("bad.toml"), bad).unwrap();
    for args in [
        &["check", "bad.toml"][..],
        &["run", "bad.toml", "--out", "bad"],
    ] {
        let r = fathom(&dir, args);
        assert_eq!(r.code, 2, "{r:?}");
        let line = r.stderr.trim_end();
        assert_eq!(line.lines().count(), 1, "{line}");
        for w in ["`methods[1]`", "\"UKF\"", "AS, SC, SI"] {
            assert!(line.contains(w), "`{w}` not in {line}");
        }
    }
    assert!(!dir.join("bad").exists());
    let list = fathom(&dir, &["list"]);
    assert!(
        list.stdout.contains("methods = [\"AS\", \"SC\", \"SI\"]"),
        "{}",
        list.stdout
    );
    assert!(
        list.stdout.contains("\"EFF-no-feedback\""),
        "{}",
        list.stdout
    );
}

/// `fusion` with `methods = ["EFF", "MF"]` runs only the main batch of those two: its
/// rows name no other method, its report says what was left out; an unknown name is
/// a one-line usage error listing the accepted names.
#[test]
fn fusion_methods_select_the_methods_run() {
    let dir = scratch("user-fusion-methods");
    let text = with_top_level(&preset("fusion.toml"), "methods = [\"EFF\", \"MF\"]");
    std::fs::write(dir.join("two.toml"), &text).unwrap();
    let ran = fathom(&dir, &["run", "two.toml", "--runs", "2", "--out", "two"]);
    assert_eq!(ran.code, 0, "{ran:?}");
    let out = dir.join("two");
    let summary: serde_json::Value = serde_json::from_str(&read(&out, "summary.json")).unwrap();
    let methods: std::collections::BTreeSet<&str> = summary["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert_eq!(methods.into_iter().collect::<Vec<_>>(), ["EFF", "MF"]);
    assert_eq!(
        summary["claims"].as_array().map_or(0, Vec::len),
        0,
        "{summary}"
    );
    let report = read(&out, "report.md");
    assert!(report.contains("Selected methods: MF, EFF"), "{report}");
    assert!(report.contains("sensitivity sweeps"), "{report}");
    assert!(out.join("err3d_selected.svg").exists());
    assert!(!out.join("err3d_all.svg").exists());

    let bad = with_top_level(&preset("fusion.toml"), "methods = [\"EKF\"]");
    std::fs::write(dir.join("bad.toml"), bad).unwrap();
    let r = fathom(&dir, &["check", "bad.toml"]);
    assert_eq!(r.code, 2, "{r:?}");
    let line = r.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    for w in ["`methods[0]`", "\"EKF\"", "MF, T2T, EFF", "DVL-DR"] {
        assert!(line.contains(w), "`{w}` not in {line}");
    }
}

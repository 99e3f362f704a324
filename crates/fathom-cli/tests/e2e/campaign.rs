//! Sharded campaigns through the real binary: `fathom run --shard K/M` and `fathom
//! merge` give the same set of files as one process, byte-identical (4 even shards, 3 uneven ones,
//! shards given in any order), and every broken merge (a missing or duplicated shard,
//! shards of different scenarios or versions, a corrupted record file) is refused with
//! exit code 2 and one line, leaving nothing in the output folder.

use std::path::Path;

use crate::support::{fathom, preset, scratch};

/// The beacons preset cut to a 20 s mission.
fn reduced_beacons() -> String {
    preset("beacons.toml")
        .replace("duration_s = 180.0", "duration_s = 20.0")
        .replace("outlier_count = 276", "outlier_count = 30")
}

fn ok(dir: &Path, args: &[&str]) {
    let ran = fathom(dir, args);
    assert_eq!(ran.code, 0, "fathom {args:?}: {ran:?}");
}

/// Runs `shards` shards of `file` with `runs` runs into `prefix-K`.
fn shards(dir: &Path, file: &str, runs: &str, count: usize, prefix: &str) -> Vec<String> {
    (0..count)
        .map(|k| {
            let out = format!("{prefix}-{k}");
            let shard = format!("{k}/{count}");
            ok(
                dir,
                &[
                    "run", file, "--runs", runs, "--shard", &shard, "--out", &out,
                ],
            );
            out
        })
        .collect()
}

/// The names of the files in `dir`, sorted.
fn file_set(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The merge writes exactly the single run's set of files (the scenario as given and
/// resolved included), and every file but `run_info.json` is byte-identical.
fn same_outputs(dir: &Path, single: &str, merged: &str) {
    let files = file_set(&dir.join(merged));
    assert_eq!(files, file_set(&dir.join(single)), "{merged} vs {single}");
    for f in ["scenario.toml", "scenario.resolved.toml", "run_info.json"] {
        assert!(files.iter().any(|x| x == f), "{f} not in {files:?}");
    }
    let mut compared = 0;
    for entry in std::fs::read_dir(dir.join(merged)).unwrap() {
        let name = entry.unwrap().file_name();
        // `run_info.json` records the command (`run` / `merge`) and the wall-clock
        // time: it differs by design.
        if name == "run_info.json" {
            continue;
        }
        let a = std::fs::read(dir.join(single).join(&name)).unwrap();
        let b = std::fs::read(dir.join(merged).join(&name)).unwrap();
        assert!(
            a == b,
            "{} differs between {single} and {merged}",
            name.to_string_lossy()
        );
        compared += 1;
    }
    assert!(compared >= 5, "only {compared} files compared");
}

fn check_experiment(name: &str, text: &str) {
    let dir = scratch(&format!("campaign-{name}"));
    let file = format!("{name}.toml");
    std::fs::write(dir.join(&file), text).unwrap();
    ok(&dir, &["run", &file, "--runs", "40", "--out", "single"]);
    let four = shards(&dir, &file, "40", 4, "four");
    let mut args = vec!["merge"];
    args.extend(four.iter().rev().map(String::as_str));
    args.extend(["--out", "merged4"]);
    ok(&dir, &args);
    same_outputs(&dir, "single", "merged4");
    let three = shards(&dir, &file, "40", 3, "three");
    ok(
        &dir,
        &["merge", &three[1], &three[2], &three[0], "--out", "merged3"],
    );
    same_outputs(&dir, "single", "merged3");
}

#[test]
fn beacons_shards_merge_to_the_bytes_of_one_process() {
    check_experiment("beacons", &reduced_beacons());
}

#[test]
fn vkf_shards_merge_to_the_bytes_of_one_process() {
    // The 400 s mission of the vkf end-to-end test: one interval without bottom lock.
    let mut out = String::new();
    let mut skip = false;
    for line in preset("vkf.toml").lines() {
        if line.starts_with("knots = ") {
            out.push_str(
                "knots = [[0.0, 110.0], [140.0, 110.0], [160.0, 190.0], [240.0, 190.0], \
                 [260.0, 110.0], [400.0, 110.0]]\n",
            );
            skip = !line.trim_end().ends_with("]]");
            continue;
        }
        if skip {
            skip = !line.trim_end().ends_with("]]");
            continue;
        }
        out.push_str(&line.replace("duration_s = 1620.0", "duration_s = 400.0"));
        out.push('\n');
    }
    check_experiment("vkf", &out);
}

/// Copies the files of the shard folder `from` into `to` (the records of every batch
/// the scenario ran, whatever their number).
fn copy_files(from: &std::path::Path, to: &std::path::Path) {
    for e in std::fs::read_dir(from).unwrap().flatten() {
        if e.path().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

#[test]
fn broken_merges_are_refused_with_one_line_and_nothing_written() {
    let dir = scratch("campaign-broken");
    std::fs::write(dir.join("b.toml"), reduced_beacons()).unwrap();
    let other = reduced_beacons().replace("corr_gap_s = 1.0", "corr_gap_s = 2.0");
    std::fs::write(dir.join("other.toml"), other).unwrap();
    let s = shards(&dir, "b.toml", "8", 2, "s");
    let o = shards(&dir, "other.toml", "8", 2, "o");
    // A copy of shard 1 claiming another fathom version.
    std::fs::create_dir_all(dir.join("v")).unwrap();
    copy_files(&dir.join(&s[1]), &dir.join("v"));
    let m = std::fs::read_to_string(dir.join("v/manifest.json")).unwrap();
    std::fs::write(
        dir.join("v/manifest.json"),
        m.replacen("\"fathom_version\": \"", "\"fathom_version\": \"9", 1),
    )
    .unwrap();
    // A copy of shard 0 with a corrupted record line.
    std::fs::create_dir_all(dir.join("c")).unwrap();
    copy_files(&dir.join(&s[0]), &dir.join("c"));
    let r = std::fs::read_to_string(dir.join("c/records-0.jsonl")).unwrap();
    let first = r.lines().next().unwrap();
    let cut = &first[..first.len() / 2];
    std::fs::write(dir.join("c/records-0.jsonl"), r.replacen(first, cut, 1)).unwrap();
    // A copy of shard 0 whose resolved scenario was edited after the run: its records
    // were made with other settings.
    std::fs::create_dir_all(dir.join("e")).unwrap();
    copy_files(&dir.join(&s[0]), &dir.join("e"));
    let m = std::fs::read_to_string(dir.join("e/manifest.json")).unwrap();
    assert!(m.contains("corr_gap_s = 1.0"), "{m}");
    std::fs::write(
        dir.join("e/manifest.json"),
        m.replace("corr_gap_s = 1.0", "corr_gap_s = 2.0"),
    )
    .unwrap();
    // A copy of shard 0 whose manifest lost a field (exit 2 like a truncated one).
    std::fs::create_dir_all(dir.join("f")).unwrap();
    copy_files(&dir.join(&s[0]), &dir.join("f"));
    let m = std::fs::read_to_string(dir.join("f/manifest.json")).unwrap();
    let line = m
        .lines()
        .find(|l| l.trim_start().starts_with("\"fathom_version\""))
        .unwrap();
    std::fs::write(
        dir.join("f/manifest.json"),
        m.replacen(&format!("{line}\n"), "", 1),
    )
    .unwrap();
    for (args, needle) in [
        (vec!["f", s[1].as_str()], "missing field `fathom_version`"),
        (vec!["e", s[1].as_str()], "`scenario_sha256`"),
        (vec!["e", s[1].as_str()], "shard `e`"),
        (vec![s[0].as_str()], "missing shard"),
        (
            vec![s[0].as_str(), s[1].as_str(), s[1].as_str()],
            "duplicated shard",
        ),
        (vec![s[0].as_str(), o[1].as_str()], "corr_gap_s"),
        (vec![s[0].as_str(), "v"], "fathom version"),
        (vec!["c", s[1].as_str()], "records-0.jsonl:1"),
    ] {
        let mut all = vec!["merge"];
        all.extend(args.iter().copied());
        all.extend(["--out", "bad"]);
        let ran = fathom(&dir, &all);
        assert_eq!(ran.code, 2, "{all:?}: {ran:?}");
        assert_eq!(
            ran.stderr.trim().lines().count(),
            1,
            "{all:?}: {}",
            ran.stderr
        );
        assert!(ran.stderr.contains(needle), "{all:?}: {}", ran.stderr);
        assert!(!dir.join("bad").exists(), "{all:?} left an output folder");
    }
}

/// The merge's output folder is never a shard folder, inside one or above one: its
/// replacement would take the records with it.
#[test]
fn merge_out_apart_from_the_shards() {
    let dir = scratch("campaign-out");
    std::fs::write(dir.join("b.toml"), reduced_beacons()).unwrap();
    let s = shards(&dir, "b.toml", "4", 2, "s");
    let inside = format!("{}/merged", s[1]);
    for (out, needle) in [
        (s[0].as_str(), "is the shard folder"),
        (inside.as_str(), "is inside the shard folder"),
        (".", "holds the shard folder"),
    ] {
        let args = ["merge", &s[0], &s[1], "--out", out, "--force"];
        let ran = fathom(&dir, &args);
        assert_eq!(ran.code, 2, "{args:?}: {ran:?}");
        assert_eq!(ran.stderr.trim().lines().count(), 1, "{}", ran.stderr);
        assert!(ran.stderr.contains("--out"), "{args:?}: {}", ran.stderr);
        assert!(ran.stderr.contains(needle), "{args:?}: {}", ran.stderr);
        assert!(!dir.join(&inside).exists(), "{args:?}");
        for shard in &s {
            assert!(dir.join(shard).join("records-0.jsonl").exists(), "{args:?}");
        }
    }
    // Negative control: beside the shards, the merge is written.
    ok(&dir, &["merge", &s[0], &s[1], "--out", "merged"]);
}

/// `campaign slurm` refuses a run count its shards cannot run, naming `--runs`.
#[test]
fn slurm_campaign_refuses_run_counts_its_shards_cannot_run() {
    let dir = scratch("campaign-slurm-runs");
    std::fs::write(dir.join("b.toml"), reduced_beacons()).unwrap();
    // Fewer runs than shards; one run, which the experiment refuses (no interval).
    for (shards, needle) in [
        ("2", "--runs 1 is fewer than --shards 2"),
        ("1", "--runs: needs at least 2"),
    ] {
        let args = [
            "campaign", "slurm", "b.toml", "--runs", "1", "--shards", shards, "--dir", "c",
        ];
        let ran = fathom(&dir, &args);
        assert_eq!(ran.code, 2, "{ran:?}");
        assert_eq!(ran.stderr.trim().lines().count(), 1, "{}", ran.stderr);
        assert!(ran.stderr.contains(needle), "{}", ran.stderr);
        assert!(!dir.join("c").exists());
    }
    let ran = fathom(
        &dir,
        &[
            "campaign", "slurm", "b.toml", "--runs", "40", "--shards", "2", "--dir", "c",
        ],
    );
    assert_eq!(ran.code, 0, "{ran:?}");
    assert!(dir.join("c/campaign.sh").exists());
    // The estimate comes from a sample shard of 2 runs of the campaign.
    assert!(
        ran.stdout.contains("a sample shard of 2 runs")
            && ran.stdout.contains("s per run")
            && ran.stdout.contains("per run, about"),
        "{}",
        ran.stdout
    );
}

/// A shard prints its cost estimate before it runs and, without a terminal, a progress
/// line every tenth of a batch.
#[test]
fn a_shard_prints_its_estimate_and_progress_lines() {
    let dir = scratch("campaign-shard-progress");
    std::fs::write(dir.join("b.toml"), reduced_beacons()).unwrap();
    let ran = fathom(
        &dir,
        &[
            "run", "b.toml", "--runs", "20", "--shard", "0/2", "--out", "s",
        ],
    );
    assert_eq!(ran.code, 0, "{ran:?}");
    let first = ran.stdout.lines().next().unwrap_or("");
    assert!(
        first.starts_with("beacons shard 0/2: runs 0..10 of 20") && first.contains("estimate"),
        "{}",
        ran.stdout
    );
    let progress = ran
        .stdout
        .lines()
        .filter(|l| l.contains("runs of batch 1"))
        .count();
    assert!(progress >= 5, "{}", ran.stdout);
}

//! Determinism through the real `fathom` binary: the same scenario and seed give a
//! byte-identical `summary.json` across runs and thread counts (1, 2, 3); `--seed`
//! replaces the scenario's `base_seed` everywhere and is recorded so the resolved
//! scenario reproduces the run; another seed changes the results (negative control).

use std::path::Path;

use crate::support::{fathom, preset, read, scratch};

/// The beacons preset cut to a 20 s mission (every case, scheme, figure and CSV).
fn reduced_beacons() -> String {
    preset("beacons.toml")
        .replace("runs = 100", "runs = 5")
        .replace("duration_s = 180.0", "duration_s = 20.0")
        .replace("outlier_count = 276", "outlier_count = 30")
}

/// The noise preset cut to a 30 s generation and a 300 s long run (the long run and
/// the sample-time diagram draw from their own streams of the base seed).
fn reduced_noise() -> String {
    preset("noise.toml")
        .replace("runs = 200", "runs = 4")
        .replace("duration_s = 180.0", "duration_s = 30.0")
        .replace("duration_s = 36000.0", "duration_s = 300.0")
}

/// `fathom run <file> <args> --out <out>` in `dir`, which must succeed; returns the
/// bytes of `summary.json`.
fn run_ok(dir: &Path, file: &str, out: &str, args: &[&str]) -> Vec<u8> {
    let mut all = vec!["run", file, "--out", out];
    all.extend_from_slice(args);
    let ran = fathom(dir, &all);
    assert_eq!(ran.code, 0, "fathom {all:?}: {ran:?}");
    std::fs::read(dir.join(out).join("summary.json")).unwrap()
}

fn json(dir: &Path, file: &str) -> serde_json::Value {
    serde_json::from_str(&read(dir, file)).unwrap()
}

/// One experiment: runs with `--seed 17` on 1, 2, 3 threads and again on 2 must give
/// the same `summary.json` bytes; the seed is in `summary.json`, `run_info.json` and
/// the resolved scenario, and running the resolved scenario without `--seed`
/// reproduces the bytes; `--seed 18` must change them.
fn check_experiment(name: &str, text: &str) {
    let dir = scratch(&format!("determinism-{name}"));
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let base = run_ok(&dir, "s.toml", "t1", &["--seed", "17", "--threads", "1"]);
    for (out, threads) in [("t2", "2"), ("t3", "3"), ("t2-again", "2")] {
        let other = run_ok(&dir, "s.toml", out, &["--seed", "17", "--threads", threads]);
        assert!(
            base == other,
            "{name}: summary.json differs between 1 thread and {out} ({threads} threads)"
        );
    }

    let summary = json(&dir, "t1/summary.json");
    assert_eq!(summary["base_seed"], 17, "{name}");
    let info = json(&dir, "t1/run_info.json");
    assert_eq!(info["seed"], 17, "{name}: {info}");
    assert_eq!(info["base_seed"], 17, "{name}: {info}");
    assert!(info["elapsed_s"].as_f64().is_some(), "{name}: {info}");
    let resolved = read(&dir, "t1/scenario.resolved.toml");
    assert!(
        resolved.contains("\nbase_seed = 17\n"),
        "{name}: {resolved}"
    );
    // The scenario as given is kept unchanged next to it.
    assert_eq!(read(&dir, "t1/scenario.toml"), text);

    // The resolved scenario alone (no --seed) reproduces the run.
    std::fs::copy(dir.join("t1/scenario.resolved.toml"), dir.join("r.toml")).unwrap();
    let again = run_ok(&dir, "r.toml", "resolved", &["--threads", "2"]);
    assert!(
        base == again,
        "{name}: the resolved scenario does not reproduce summary.json"
    );

    // Negative control: another seed gives other numbers (so the comparison above can
    // fail), and without --seed the scenario's own base_seed is used.
    let other_seed = run_ok(&dir, "s.toml", "s18", &["--seed", "18", "--threads", "2"]);
    assert!(
        base != other_seed,
        "{name}: --seed 18 gave the same summary.json as --seed 17"
    );
    let scenario_seed = run_ok(&dir, "s.toml", "own", &["--threads", "2"]);
    assert!(base != scenario_seed, "{name}: --seed was ignored");
    let own = json(&dir, "own/run_info.json");
    assert_eq!(own["seed"], serde_json::Value::Null, "{name}: {own}");
    assert_eq!(
        own["base_seed"],
        json(&dir, "own/summary.json")["base_seed"],
        "{name}"
    );
}

#[test]
fn beacons_summary_is_byte_identical_for_a_seed_across_runs_and_threads() {
    check_experiment("beacons", &reduced_beacons());
}

#[test]
fn noise_summary_is_byte_identical_for_a_seed_across_runs_and_threads() {
    check_experiment("noise", &reduced_noise());
}

/// `plaza` is deterministic (no base seed): `--seed` is a usage error, for `fathom
/// run` and for `fathom replay plaza`, not silently ignored.
#[test]
fn seed_on_the_deterministic_plaza_replay_is_a_usage_error() {
    let dir = scratch("determinism-plaza");
    let ran = fathom(
        &dir,
        &[
            "run",
            &crate::support::repo_root()
                .join("scenarios/plaza.toml")
                .display()
                .to_string(),
            "--seed",
            "3",
        ],
    );
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(
        ran.stderr.contains("--seed") && ran.stderr.contains("deterministic"),
        "{ran:?}"
    );
    assert_eq!(ran.stderr.lines().count(), 1, "{ran:?}");
    assert!(!dir.join("fathom-out").exists(), "nothing is written");

    let ran = fathom(&dir, &["replay", "plaza", "data", "--seed", "3"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.stderr.contains("--seed"), "{ran:?}");
    assert!(!ran.stderr.contains("panicked"), "{ran:?}");
}

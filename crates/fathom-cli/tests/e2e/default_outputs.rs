//! The one output convention, through the real binary: without `--out` every command
//! writes into `fathom-out/<name>/` of the current directory (`run`, `run --shard`,
//! `merge`, `replay plaza|range-beacon|ins-dvl`, `log example`, `log from-plaza`,
//! `pils`, `pils sim|nav|offline`; `pils compare` in `pils.rs`), and nothing else
//! appears beside it.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::support::{Ran, fathom, fathom_bin, preset, repo_root, scratch};

fn ok(dir: &Path, args: &[&str]) -> Ran {
    let r = fathom(dir, args);
    assert_eq!(r.code, 0, "fathom {args:?}: {}{}", r.stdout, r.stderr);
    r
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// `root` holds only `keep` and `fathom-out`, and `fathom-out` exactly `want`.
fn only_fathom_out(root: &Path, keep: &[&str], want: &[&str]) {
    let mut expected: Vec<String> = keep.iter().map(|s| s.to_string()).collect();
    expected.push("fathom-out".into());
    expected.sort();
    assert_eq!(names(root), expected, "{}", root.display());
    assert_eq!(names(&root.join("fathom-out")), want, "{}", root.display());
}

/// The beacons preset cut to a 20 s mission.
fn reduced_beacons() -> String {
    preset("beacons.toml")
        .replace("duration_s = 180.0", "duration_s = 20.0")
        .replace("outlier_count = 276", "outlier_count = 30")
}

#[test]
fn run_writes_into_fathom_out_experiment() {
    let root = scratch("default-out-run");
    std::fs::write(root.join("b.toml"), reduced_beacons()).unwrap();
    let r = ok(&root, &["run", "b.toml", "--runs", "2"]);
    assert!(r.stdout.contains("fathom-out/beacons"), "{}", r.stdout);
    assert!(root.join("fathom-out/beacons/summary.json").is_file());
    only_fathom_out(&root, &["b.toml", "scenarios"], &["beacons"]);
}

#[test]
fn shards_and_merge_write_into_fathom_out() {
    let root = scratch("default-out-merge");
    std::fs::write(root.join("b.toml"), reduced_beacons()).unwrap();
    for k in ["0/2", "1/2"] {
        ok(&root, &["run", "b.toml", "--runs", "4", "--shard", k]);
    }
    let shards = ["beacons-shard-0-of-2", "beacons-shard-1-of-2"];
    for s in shards {
        assert!(
            root.join("fathom-out")
                .join(s)
                .join("manifest.json")
                .is_file()
        );
    }
    let r = ok(
        &root,
        &[
            "merge",
            "fathom-out/beacons-shard-1-of-2",
            "fathom-out/beacons-shard-0-of-2",
        ],
    );
    // The merge writes where the single run of the same experiment would.
    assert!(r.stdout.contains("fathom-out/beacons"), "{}", r.stdout);
    assert!(root.join("fathom-out/beacons/summary.json").is_file());
    only_fathom_out(
        &root,
        &["b.toml", "scenarios"],
        &["beacons", shards[0], shards[1]],
    );
}

#[test]
fn logs_and_their_replays_write_into_fathom_out() {
    let root = scratch("default-out-logs");
    for kind in ["range-beacon", "ins-dvl"] {
        let r = ok(&root, &["log", "example", kind, "--duration", "60"]);
        let log = format!("fathom-out/{kind}-log");
        assert!(r.stdout.contains(&log), "{}", r.stdout);
        assert!(root.join(&log).join("log.toml").is_file(), "{log}");
        let r = ok(&root, &["replay", kind, &log]);
        assert!(r.stdout.contains(&log), "{}", r.stdout);
        let out = root.join(format!("fathom-out/{kind}-replay"));
        assert!(out.join("summary.json").is_file(), "{}", out.display());
    }
    only_fathom_out(
        &root,
        &["scenarios"],
        &[
            "ins-dvl-log",
            "ins-dvl-replay",
            "range-beacon-log",
            "range-beacon-replay",
        ],
    );
}

/// With the data folder of the settings (`data/plaza1`, here a copy of the
/// repository's) found from the current directory, `replay plaza` and `log
/// from-plaza` need no argument.
#[test]
fn plaza_replay_and_conversion_write_into_fathom_out() {
    let root = scratch("default-out-plaza");
    let data = root.join("data/plaza1");
    std::fs::create_dir_all(&data).unwrap();
    for f in ["Plaza1_DR.txt", "Plaza1_TD.txt", "Plaza1_.mat"] {
        std::fs::copy(repo_root().join("data/plaza1").join(f), data.join(f)).unwrap();
    }
    let r = ok(&root, &["replay", "plaza"]);
    assert!(r.stdout.contains("fathom-out/plaza-replay"), "{}", r.stdout);
    assert!(root.join("fathom-out/plaza-replay/summary.json").is_file());
    let r = ok(&root, &["log", "from-plaza"]);
    assert!(r.stdout.contains("fathom-out/plaza-log"), "{}", r.stdout);
    assert!(root.join("fathom-out/plaza-log/log.toml").is_file());
    only_fathom_out(
        &root,
        &["data", "scenarios"],
        &["plaza-log", "plaza-replay"],
    );
}

/// PILS settings flying `urban.toml` (a short bridge: about 30 s simulated) with the
/// GREKF, lockstep.
const PILS: &str = "experiment = \"pils\"\nscenario = \"urban.toml\"\nscene = \"bridge\"\n\
                    method = \"GREKF\"\n[link]\ntimeout_s = 3.0\nretransmit_s = 0.02\n";

#[test]
fn pils_sessions_write_into_fathom_out() {
    let root = scratch("default-out-pils");
    std::fs::write(root.join("p.toml"), PILS).unwrap();
    std::fs::write(
        root.join("urban.toml"),
        crate::pils::short_urban(40.0, 20.0),
    )
    .unwrap();
    ok(&root, &["pils", "p.toml"]);
    assert!(root.join("fathom-out/pils/sim/pils.json").is_file());
    assert!(root.join("fathom-out/pils/nav/nav.json").is_file());
    // A second session replaces the first's folders (they are fathom's, not the user's).
    ok(&root, &["pils", "p.toml"]);
    assert!(root.join("fathom-out/pils/sim/pils.json").is_file());
    ok(&root, &["pils", "offline", "p.toml"]);
    let csv = std::fs::read_to_string(root.join("fathom-out/pils-offline/solutions.csv")).unwrap();
    assert!(csv.lines().count() > 100, "{csv}");
    // The two sides started by hand, each with its default folder.
    let mut nav = Command::new(fathom_bin())
        .args(["pils", "nav", "p.toml"])
        .current_dir(&root)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(nav.stdout.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    // "navigation listening on ADDR"
    let addr = first.rsplit(' ').next().unwrap().to_string();
    let sim = ok(&root, &["pils", "sim", "p.toml", "--nav", &addr]);
    assert!(sim.stdout.contains("fathom-out/pils-sim"), "{}", sim.stdout);
    lines.for_each(drop);
    assert!(nav.wait().unwrap().success());
    assert!(root.join("fathom-out/pils-sim/pils.json").is_file());
    assert!(root.join("fathom-out/pils-nav/nav.json").is_file());
    only_fathom_out(
        &root,
        &["p.toml", "urban.toml", "scenarios"],
        &["pils", "pils-nav", "pils-offline", "pils-sim"],
    );
}

//! Output folders that never lose work (issue 23), through the real `fathom` binary:
//! a folder holding a file the user wrote is refused (exit 2, one line) and the file
//! kept, `--force` keeps it and replaces only fathom's files; a run killed while it
//! computes leaves the previous results byte for byte and the next run cleans up after
//! it; a run into a folder another fathom process is writing is refused, with or
//! without `--force`; an unwritable `--out` is refused before anything is computed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::support::{Ran, fathom, fathom_bin, repo_root, scratch};

/// The beacons preset (absolute path).
fn beacons() -> String {
    repo_root()
        .join("scenarios/beacons.toml")
        .to_string_lossy()
        .into_owned()
}

/// A quick run of the beacons preset into `out` with `seed`.
fn quick(dir: &Path, out: &str, seed: &str, force: bool) -> Ran {
    let b = beacons();
    let mut args = vec!["run", &b, "--runs", "2", "--seed", seed, "--out", out];
    if force {
        args.push("--force");
    }
    fathom(dir, &args)
}

/// Arguments of a run long enough to be interrupted (minutes on one thread).
fn long_args(out: &str) -> Vec<String> {
    [
        "run",
        &beacons(),
        "--runs",
        "3000",
        "--threads",
        "1",
        "--seed",
        "9",
        "--out",
        out,
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// Starts a long run into `dir/out` and waits until it has claimed the folder (its
/// temporary folder `.out.partial-<pid>` exists).
fn start_long_run(dir: &Path, out: &str) -> Child {
    let mut child = Command::new(fathom_bin())
        .args(long_args(out))
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let partial = dir.join(format!(".{out}.partial-{}", child.id()));
    let t0 = Instant::now();
    while !partial.exists() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the long run ended before claiming the folder: {status}");
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "the long run never claimed `{out}`"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child
}

/// Every file of `dir` (name -> bytes).
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

/// Names in `dir` starting with `.<out>.` other than the lock file (temporary and
/// set-aside folders).
fn leftovers(dir: &Path, out: &str) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.starts_with(&format!(".{out}.")) && !n.ends_with(".lock")
        })
        .collect()
}

fn one_line_usage_error(ran: &Ran, words: &[&str]) {
    assert_eq!(ran.code, 2, "{ran:?}");
    let line = ran.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{ran:?}");
    assert!(line.starts_with("error: invalid --out: "), "{line}");
    for w in words {
        assert!(line.contains(w), "`{w}` not in: {line}");
    }
    // Refused before computing: no batch line, no result.
    assert!(!ran.stdout.contains("batch"), "{ran:?}");
    assert!(!ran.stdout.contains("done in"), "{ran:?}");
}

#[test]
fn a_users_file_is_refused_and_kept_and_force_replaces_only_fathoms_files() {
    let dir = scratch("out-foreign");
    std::fs::create_dir_all(dir.join("out")).unwrap();
    std::fs::write(dir.join("out/notes.md"), "my own notes").unwrap();
    let b = beacons();
    let long = long_args("out");
    let long: Vec<&str> = long.iter().map(String::as_str).collect();
    let refused = fathom(&dir, &long);
    one_line_usage_error(&refused, &["`out`", "notes.md", "--force"]);
    assert_eq!(
        snapshot(&dir.join("out")).keys().collect::<Vec<_>>(),
        ["notes.md"]
    );
    assert!(leftovers(&dir, "out").is_empty());

    let forced = quick(&dir, "out", "1", true);
    assert_eq!(forced.code, 0, "{forced:?}");
    let files = snapshot(&dir.join("out"));
    assert_eq!(files["notes.md"], b"my own notes");
    assert!(files.contains_key("summary.json"));
    let info: serde_json::Value =
        serde_json::from_slice(&files["run_info.json"]).expect("run_info.json");
    let listed: Vec<&str> = info["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(listed.contains(&"summary.json"), "{listed:?}");
    assert!(!listed.contains(&"notes.md"), "{listed:?}");
    // Without --force the user's file still stops a run; with it the file survives a
    // second replacement too.
    let again = fathom(&dir, &["run", &b, "--runs", "2", "--out", "out"]);
    one_line_usage_error(&again, &["notes.md"]);
    let forced = quick(&dir, "out", "2", true);
    assert_eq!(forced.code, 0, "{forced:?}");
    assert_eq!(
        std::fs::read(dir.join("out/notes.md")).unwrap(),
        b"my own notes"
    );
    assert!(leftovers(&dir, "out").is_empty());
}

#[test]
fn a_rerun_replaces_fathoms_own_folder_without_force() {
    let dir = scratch("out-rerun");
    assert_eq!(quick(&dir, "out", "1", false).code, 0);
    let first = snapshot(&dir.join("out"));
    let second = quick(&dir, "out", "2", false);
    assert_eq!(second.code, 0, "{second:?}");
    let now = snapshot(&dir.join("out"));
    assert_eq!(
        first.keys().collect::<Vec<_>>(),
        now.keys().collect::<Vec<_>>()
    );
    assert_ne!(first["summary.json"], now["summary.json"], "seed 2 ran");
    assert!(leftovers(&dir, "out").is_empty());
}

#[test]
fn an_interrupted_run_leaves_the_previous_results_intact() {
    let dir = scratch("out-interrupted");
    assert_eq!(quick(&dir, "out", "1", false).code, 0);
    let before = snapshot(&dir.join("out"));
    assert!(before.len() > 5, "{:?}", before.keys());

    let mut child = start_long_run(&dir, "out");
    // Let it compute a little, then kill it (SIGKILL: no cleanup runs).
    std::thread::sleep(Duration::from_millis(500));
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(
        snapshot(&dir.join("out")),
        before,
        "previous results changed"
    );
    assert!(
        !leftovers(&dir, "out").is_empty(),
        "the killed run's folder"
    );

    // The next run works (the lock died with the process) and cleans up.
    let next = quick(&dir, "out", "3", false);
    assert_eq!(next.code, 0, "{next:?}");
    assert!(leftovers(&dir, "out").is_empty());
    assert_ne!(
        snapshot(&dir.join("out"))["summary.json"],
        before["summary.json"]
    );
}

#[test]
fn a_folder_another_fathom_is_writing_is_refused() {
    let dir = scratch("out-concurrent");
    let mut child = start_long_run(&dir, "out");
    for force in [false, true] {
        let second = quick(&dir, "out", "1", force);
        one_line_usage_error(&second, &["another fathom process", "pid"]);
    }
    // Another folder is fine meanwhile.
    let other = quick(&dir, "other", "1", false);
    assert_eq!(other.code, 0, "{other:?}");
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        !dir.join("out").exists(),
        "a killed first run publishes nothing"
    );
    let after = quick(&dir, "out", "1", false);
    assert_eq!(after.code, 0, "{after:?}");
}

#[test]
fn an_unwritable_out_is_refused_before_computing() {
    let dir = scratch("out-unwritable");
    std::fs::write(dir.join("a_file"), "x").unwrap();
    for (out, words) in [
        ("a_file/out", &["cannot create the folder"][..]),
        ("a_file", &["is a file"][..]),
        (".", &["is the current directory"][..]),
    ] {
        // The long run's arguments: a refusal after computing would take minutes.
        let args = long_args(out);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let ran = fathom(&dir, &args);
        one_line_usage_error(&ran, words);
    }
    assert_eq!(std::fs::read(dir.join("a_file")).unwrap(), b"x");
}

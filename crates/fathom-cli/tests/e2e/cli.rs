//! `fathom check` on a corpus of broken scenario files: every file in
//! `tests/cli_corpus/*.toml` gives exit code 2 and exactly the one-line error stored
//! in its `.expected` snapshot; every settings file in `scenarios/` (scenarios,
//! replay settings, PILS settings) checks OK through the binary once the logs the
//! replay settings name exist, and a replay whose log is missing fails `check` as it
//! fails `run`.

use std::path::{Path, PathBuf};

use fathom_experiments::registry;
use fathom_sim::user_run::{EXIT_USAGE, check_command};

use crate::support::{compare_snapshot, fathom, repo_root, scratch};

fn corpus() -> Vec<PathBuf> {
    let dir = Path::new("tests/cli_corpus");
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().and_then(|x| x.to_str()) == Some("toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn broken_scenarios_give_one_line_errors_and_exit_code_2() {
    let files = corpus();
    assert!(files.len() >= 20, "{} corpus files", files.len());
    let reg = registry();
    let mut mismatches = Vec::new();
    for f in &files {
        let (code, line) = check_command(f, &reg);
        assert_eq!(code, EXIT_USAGE, "{}: {line}", f.display());
        assert!(!line.contains('\n'), "{line}");
        assert!(line.starts_with(&f.display().to_string()), "{line}");
        assert!(
            line.contains("key `") || line.contains("missing field"),
            "{line}"
        );
        compare_snapshot(f, &f.with_extension("expected"), &line, &mut mismatches);
    }
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
}

#[test]
fn toml_errors_name_the_line() {
    let reg = registry();
    for name in ["unknown_key", "wrong_type", "bad_syntax", "missing_field"] {
        let (_, line) = check_command(
            &Path::new("tests/cli_corpus").join(format!("{name}.toml")),
            &reg,
        );
        assert!(line.contains(": line "), "{line}");
    }
}

#[test]
fn presets_check_ok() {
    let reg = registry();
    for exp in &reg {
        let (code, line) = check_command(&repo_root().join(exp.default_scenario()), &reg);
        assert_eq!(code, 0, "{line}");
        assert!(
            line.starts_with("OK ") && line.contains(exp.name()),
            "{line}"
        );
    }
    // Negative control: a missing file is an error too.
    let (code, _) = check_command(Path::new("tests/cli_corpus/no-such-file.toml"), &reg);
    assert_eq!(code, EXIT_USAGE);
}

/// Every file under `scenarios/` is a settings file `fathom check` accepts (exit 0,
/// kind detected from its `experiment` key), in a working directory holding what they
/// read: the Plaza data (`data/plaza1`) and the logs the replay settings name
/// (`fathom log example <kind>`, `fathom log from-plaza`: the README's walkthrough).
#[test]
fn every_settings_file_under_scenarios_checks_ok() {
    let root = scratch("check-every-scenario");
    // Before the logs exist, a replay's settings fail `check` exactly as `run` fails.
    let rb = repo_root().join("scenarios/range-beacon.toml");
    let rb = rb.to_str().unwrap();
    let check = fathom(&root, &["check", rb]);
    let run = fathom(&root, &["run", rb]);
    assert_eq!(check.code, 2, "{check:?}");
    assert_eq!(check.stderr, run.stderr);
    assert!(check.stderr.contains("range-beacon-log"), "{check:?}");

    let data = root.join("data/plaza1");
    std::fs::create_dir_all(&data).unwrap();
    for f in ["Plaza1_DR.txt", "Plaza1_TD.txt", "Plaza1_.mat"] {
        std::fs::copy(repo_root().join("data/plaza1").join(f), data.join(f)).unwrap();
    }
    let flight = repo_root().join("data/ulog/fmu_v3_gps.ulg");
    let flight = flight.to_str().unwrap();
    for args in [
        &["log", "example", "range-beacon"][..],
        &["log", "example", "ins-dvl"],
        &["log", "from-plaza"],
        // the log `scenarios/gnss-ins.toml` reads
        &[
            "log",
            "from-ulog",
            flight,
            "--out",
            "fathom-out/gnss-ins-log",
        ],
    ] {
        let r = fathom(&root, args);
        assert_eq!(r.code, 0, "{args:?}: {r:?}");
    }
    let mut checked = Vec::new();
    let mut stack = vec![repo_root().join("scenarios")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().and_then(|x| x.to_str()) == Some("toml") {
                let r = fathom(&root, &["check", "--quiet", path.to_str().unwrap()]);
                assert_eq!(r.code, 0, "{}: {}", path.display(), r.stderr);
                assert!(r.stdout.starts_with("OK "), "{}", r.stdout);
                checked.push(path.file_name().unwrap().to_string_lossy().into_owned());
            } else {
                // Anything else under scenarios/ is a world a scenario reads.
                assert!(dir.ends_with("worlds"), "{}", path.display());
            }
        }
    }
    checked.sort();
    for kind in ["ins-dvl.toml", "pils.toml", "plaza.toml", "urban.toml"] {
        assert!(checked.iter().any(|c| c == kind), "{checked:?}");
    }
    assert!(checked.len() >= 11, "{checked:?}");
}

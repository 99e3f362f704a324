//! `fathom check` on a corpus of broken scenario files: every file in
//! `tests/cli_corpus/*.toml` gives exit code 2 and exactly the one-line error stored
//! in its `.expected` snapshot; every preset in `scenarios/` checks OK.

use std::path::{Path, PathBuf};

use fathom_experiments::registry;
use fathom_sim::user_run::{EXIT_USAGE, check_command};

use crate::support::{compare_snapshot, repo_root};

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

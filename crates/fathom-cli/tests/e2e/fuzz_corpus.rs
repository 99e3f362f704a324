//! Replays the committed fuzz corpora (`fuzz/corpus/<target>/`) and every input that
//! once crashed a target (`fuzz/regressions/<target>/`) through the same harness
//! functions as the cargo-fuzz targets (`fuzz/src/lib.rs`, included here as a module),
//! so the fuzzers' findings stay fixed in a plain `cargo test` without cargo-fuzz.
//! Regression inputs must also give exactly the outcome stored beside them in
//! `<input>.expected` (one line per outcome: the error now returned, or `ok ...`).
//! `FATHOM_FUZZ_BLESS=1 cargo test --test e2e fuzz_corpus` writes missing snapshots
//! for new regression inputs (read them before committing).

use std::path::{Path, PathBuf};

use crate::support::{compare_snapshot, repo_root};

#[allow(dead_code)]
#[path = "../../../../fuzz/src/lib.rs"]
mod harness;

type Harness = fn(&[u8]) -> Vec<String>;

const TARGETS: [(&str, Harness); 8] = [
    ("scenario", harness::scenario),
    ("scenario_edit", harness::scenario_edit),
    ("cost", harness::cost),
    ("plaza_text", harness::plaza_text),
    ("plaza_mat", harness::plaza_mat),
    ("map_obj", harness::map_obj),
    ("map_stl", harness::map_stl),
    ("ulog", harness::ulog),
];

/// The input files in `dir` (sorted; `.expected` snapshots and dot files left out).
fn inputs(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.is_file()
                && p.extension().and_then(|x| x.to_str()) != Some("expected")
                && !p.file_name().unwrap().to_string_lossy().starts_with('.')
        })
        .collect();
    files.sort();
    files
}

#[test]
fn every_corpus_file_runs_through_its_harness_without_panic() {
    let mut total = 0;
    for (target, run) in TARGETS {
        let files = inputs(&repo_root().join("fuzz/corpus").join(target));
        assert!(!files.is_empty(), "no corpus for fuzz target `{target}`");
        for f in &files {
            let outcome = run(&std::fs::read(f).unwrap());
            assert!(!outcome.is_empty(), "{}", f.display());
        }
        total += files.len();
    }
    eprintln!("{total} corpus inputs replayed");
}

#[test]
fn every_fuzz_regression_gives_its_expected_error() {
    let mut mismatches = Vec::new();
    let mut total = 0;
    for (target, run) in TARGETS {
        for f in inputs(&repo_root().join("fuzz/regressions").join(target)) {
            total += 1;
            let got = run(&std::fs::read(&f).unwrap()).join("\n");
            let snapshot = PathBuf::from(format!("{}.expected", f.display()));
            if std::env::var_os("FATHOM_FUZZ_BLESS").is_some() && !snapshot.exists() {
                std::fs::write(&snapshot, format!("{got}\n")).unwrap();
            }
            compare_snapshot(&f, &snapshot, &got, &mut mismatches);
        }
    }
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
    eprintln!("{total} fuzz regressions replayed");
}

/// The seeds made from real Plaza1 slices are accepted (so the fuzzer starts from
/// inputs that reach past the format checks), and the preset edits start from
/// presets that check OK.
#[test]
fn seed_inputs_are_valid() {
    for seed in [
        "seed_min_plain",
        "seed_min_compressed",
        "seed_real_layout_plain",
        "seed_real_layout_compressed",
        "seed_real_tl_element",
    ] {
        let bytes = std::fs::read(repo_root().join("fuzz/corpus/plaza_mat").join(seed)).unwrap();
        let outcome = harness::plaza_mat(&bytes);
        assert!(outcome[0].starts_with("ok"), "{seed}: {outcome:?}");
    }
    let dr = std::fs::read(repo_root().join("fuzz/corpus/plaza_text/seed_dr_head")).unwrap();
    assert!(harness::plaza_text(&dr)[0].starts_with("odometry: ok"));
    let td = std::fs::read(repo_root().join("fuzz/corpus/plaza_text/seed_td_backwards")).unwrap();
    assert_eq!(
        harness::plaza_text(&td)[2],
        "ranges sort: ok, 4 ranges, 1 order breaks"
    );
    for (target, seed) in [
        ("map_obj", "seed_house.obj"),
        ("map_stl", "seed_wedge_binary.stl"),
        ("map_stl", "seed_wedge_ascii.stl"),
    ] {
        let bytes = std::fs::read(repo_root().join("fuzz/corpus").join(target).join(seed)).unwrap();
        let run = if target == "map_obj" {
            harness::map_obj
        } else {
            harness::map_stl
        };
        assert!(
            run(&bytes)[0].starts_with("ok"),
            "{seed}: {:?}",
            run(&bytes)
        );
    }
    for preset in 0..harness::presets().len() as u8 {
        let outcome = harness::scenario_edit(&[preset]);
        assert!(outcome[0].starts_with("ok"), "{outcome:?}");
    }
}

//! Tidy tests (as rust-analyzer's): ARCHITECTURE.md's invariants checked mechanically.
//!
//! - Every internal dependency edge of a workspace package (normal, build and dev
//!   dependencies, from `cargo metadata`) is listed in ARCHITECTURE.md's section
//!   "Allowed internal dependencies", and every listed edge exists.
//! - No library crate below the I/O layer ([`IO_CRATES`]) opens files, reads
//!   environment variables or prints, outside its test modules (with the exceptions listed in
//!   [`IO_EXCEPTIONS`], each documented in ARCHITECTURE.md).
//! - The layout checks of [`layout`]: module trees, import circles, sizes, the
//!   codemap, quiet test skips.
//!
//! Each check is a plain function of its inputs, so the tests also run it on a
//! deliberately broken input (negative controls).

mod layout;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Package -> the internal packages it may depend on.
type Edges = BTreeMap<String, BTreeSet<String>>;

/// Files of library crates allowed one kind of I/O, with the reason.
const IO_EXCEPTIONS: [(&str, &str, &str); 1] = [(
    "crates/fathom-estimators/src/simd.rs",
    "env::var",
    "FATHOM_SIMD=baseline keeps the SSE2 kernels (ARCHITECTURE.md, external crates: pulp)",
)];

/// Crates whose sources may do I/O: the experiment layer (and `fathom-pils` above
/// it, which reads its settings and the `urban` file they name) and the binaries.
const IO_CRATES: [&str; 9] = [
    "fathom-report",
    "fathom-data",
    "fathom-sim",
    "fathom-replay",
    "fathom-experiments",
    "fathom-pils",
    "fathom-cli",
    "fathom-py",
    "xtask",
];

/// What a library crate must not contain outside tests.
const FORBIDDEN: [&str; 8] = [
    "std::fs",
    "File::open",
    "File::create",
    "env::var",
    "println!",
    "eprintln!",
    "print!(",
    "eprint!(",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The allowed edges from ARCHITECTURE.md: lines `` - `a` -> `b`, `c` `` (or `-> none`)
/// under the heading `## Allowed internal dependencies`.
fn allowed_edges(architecture: &str) -> Edges {
    let mut out = Edges::new();
    let mut inside = false;
    for line in architecture.lines() {
        if line.starts_with("## ") {
            inside = line.trim() == "## Allowed internal dependencies";
            continue;
        }
        let Some(rest) = line.strip_prefix("- `").filter(|_| inside) else {
            continue;
        };
        let Some((from, targets)) = rest.split_once("` -> ") else {
            continue;
        };
        // A trailing `(...)` explains the line.
        let targets = targets.split(" (").next().unwrap_or("");
        let set = targets
            .split(',')
            .map(|t| t.trim().trim_matches('`').to_string())
            .filter(|t| !t.is_empty() && t != "none")
            .collect();
        out.insert(from.to_string(), set);
    }
    out
}

/// The actual internal edges from `cargo metadata` JSON.
fn actual_edges(metadata: &serde_json::Value) -> Edges {
    let members: BTreeSet<String> = metadata["packages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|p| p["name"].as_str().map(str::to_string))
        .collect();
    let mut out = Edges::new();
    for p in metadata["packages"].as_array().into_iter().flatten() {
        let Some(name) = p["name"].as_str() else {
            continue;
        };
        let deps = p["dependencies"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|d| d["name"].as_str())
            .filter(|d| members.contains(*d))
            .map(str::to_string)
            .collect();
        out.insert(name.to_string(), deps);
    }
    out
}

/// Edges present but not allowed, and allowed edges that do not exist.
fn edge_problems(allowed: &Edges, actual: &Edges) -> Vec<String> {
    let mut problems = Vec::new();
    for (from, deps) in actual {
        let Some(ok) = allowed.get(from) else {
            problems.push(format!(
                "package `{from}` is not listed in ARCHITECTURE.md's allowed dependencies"
            ));
            continue;
        };
        for d in deps.difference(ok) {
            problems.push(format!(
                "`{from}` depends on `{d}`, an edge ARCHITECTURE.md does not allow"
            ));
        }
        for d in ok.difference(deps) {
            problems.push(format!(
                "ARCHITECTURE.md lists `{from}` -> `{d}`, which does not exist"
            ));
        }
    }
    problems
}

/// The part of a source file before its first `#[cfg(test)]` (test modules may do I/O).
fn non_test_part(text: &str) -> &str {
    text.find("#[cfg(test)]").map_or(text, |i| &text[..i])
}

/// Forbidden I/O in `text` (file `path`, relative to the root), minus the exceptions.
fn io_problems(path: &str, text: &str) -> Vec<String> {
    let code = non_test_part(text);
    FORBIDDEN
        .iter()
        .filter(|needle| {
            code.lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .any(|l| l.contains(*needle))
        })
        .filter(|needle| {
            !IO_EXCEPTIONS
                .iter()
                .any(|(p, what, _)| *p == path && needle.contains(what))
        })
        .map(|needle| format!("{path}: `{needle}` in a library crate below fathom-sim"))
        .collect()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn dependency_edges_are_the_ones_architecture_md_allows() {
    let architecture = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let allowed = allowed_edges(&architecture);
    assert!(allowed.len() >= 8, "no edge list found: {allowed:?}");
    let out = std::process::Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let metadata: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let actual = actual_edges(&metadata);
    let problems = edge_problems(&allowed, &actual);
    assert!(problems.is_empty(), "{}", problems.join("\n"));

    // Negative controls: an estimator depending on the simulation layer, and a listed
    // edge that does not exist, are both found.
    let mut bad = actual.clone();
    bad.entry("fathom-estimators".into())
        .or_default()
        .insert("fathom-sim".into());
    let found = edge_problems(&allowed, &bad);
    assert!(
        found
            .iter()
            .any(|p| p.contains("`fathom-estimators` depends on `fathom-sim`")),
        "{found:?}"
    );
    let mut stale = allowed.clone();
    stale
        .entry("fathom-core".into())
        .or_default()
        .insert("fathom-stats".into());
    assert!(!edge_problems(&stale, &actual).is_empty());
}

#[test]
fn library_crates_below_fathom_sim_do_no_io() {
    let mut problems = Vec::new();
    let crates = root().join("crates");
    for entry in std::fs::read_dir(&crates).unwrap().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if IO_CRATES.contains(&name.as_str()) {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&entry.path().join("src"), &mut files);
        for f in files {
            let rel = f
                .strip_prefix(root())
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            // Test-only files: `tests.rs`, `*_tests.rs` (declared under `#[cfg(test)]`).
            if rel.ends_with("tests.rs") || rel.contains("/tests/") {
                continue;
            }
            let text = std::fs::read_to_string(&f).unwrap();
            problems.extend(io_problems(&rel, &text));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));

    // Negative control: a library file that opens a file is found; the same call in a
    // test module or a comment is not; the documented exception is accepted.
    let bad = "//! x\nfn f() { let _ = std::fs::read(\"a\"); }\n";
    assert_eq!(io_problems("crates/fathom-core/src/x.rs", bad).len(), 1);
    let in_test = "//! x\n#[cfg(test)]\nmod t { fn f() { println!(\"a\"); } }\n";
    assert!(io_problems("crates/fathom-core/src/x.rs", in_test).is_empty());
    let comment = "//! x\n// std::fs is not used here\n";
    assert!(io_problems("crates/fathom-core/src/x.rs", comment).is_empty());
    let simd = "//! x\nfn f() { std::env::var(\"FATHOM_SIMD\"); }\n";
    assert!(io_problems("crates/fathom-estimators/src/simd.rs", simd).is_empty());
}

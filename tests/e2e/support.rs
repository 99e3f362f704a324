//! Helpers shared by the end-to-end tests: scratch workspaces holding modified
//! scenario files, and running experiments through `run_paper_to`.

use std::path::{Path, PathBuf};

use fathom::sim::experiment::run_paper_to;
use fathom::sim::{PaperOptions, PaperResult, SimError};

/// The repository root (where `scenarios/` lives).
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Reads a preset scenario file from `scenarios/`.
pub fn preset(name: &str) -> String {
    std::fs::read_to_string(repo_root().join("scenarios").join(name)).unwrap()
}

/// A fresh scratch directory for one test (removed first if it exists).
pub fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fathom-e2e-{}-{test}", std::process::id()));
    if dir.exists() {
        std::fs::remove_dir_all(&dir).unwrap();
    }
    std::fs::create_dir_all(dir.join("scenarios")).unwrap();
    dir
}

/// Writes `text` as `scenarios/<file>` of the scratch workspace `root`.
pub fn write_scenario(root: &Path, file: &str, text: &str) {
    std::fs::write(root.join("scenarios").join(file), text).unwrap();
}

/// Runs one registered experiment of `root`'s scenarios into `root/out`.
pub fn run_experiment(
    root: &Path,
    name: &str,
    threads: Option<usize>,
) -> Result<PaperResult, SimError> {
    let options = PaperOptions {
        only: Some(name.to_owned()),
        runs: None,
        threads,
        workspace_root: root.to_path_buf(),
        out_root: root.join("out"),
    };
    let mut sink = Vec::new();
    run_paper_to(&options, &fathom::sim::experiments::registry(), &mut sink)
}

/// The full error chain as one string (what `cargo xtask paper` prints).
pub fn chain(e: &SimError) -> String {
    fathom::sim::error_chain(e)
}

//! Helpers shared by the end-to-end tests: scratch workspaces holding modified
//! scenario files, running experiments through `run_paper_to`, and running the real
//! `fathom` binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use fathom_sim::driver::run_paper_to;
use fathom_sim::{PaperOptions, PaperResult, SimError};

/// The repository root (where `scenarios/` lives).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
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
        force: false,
    };
    let mut sink = Vec::new();
    run_paper_to(&options, &fathom_experiments::registry(), &mut sink)
}

/// Every row of the experiment has a declared unit (the console and `report.md`
/// show it; `-` would mean a forgotten declaration).
pub fn assert_every_row_has_a_unit(e: &fathom_sim::driver::ExperimentResult) {
    for r in &e.summary.rows {
        assert!(
            e.units.contains_key(&r.metric),
            "{}: row {} / {} has no unit",
            e.name,
            r.method,
            r.metric
        );
    }
}

/// The full error chain as one string (what `cargo xtask paper` prints).
pub fn chain(e: &SimError) -> String {
    fathom_sim::error_chain(e)
}

/// The `fathom` binary cargo built for this test run (`CARGO_BIN_EXE_fathom`: the
/// binary of the current sources, with this test's profile); `FATHOM_BIN` overrides it
/// (an installed binary).
pub fn fathom_bin() -> PathBuf {
    std::env::var_os("FATHOM_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_fathom")))
}

/// What one `fathom` invocation did.
#[derive(Debug)]
pub struct Ran {
    /// Exit code (`-1` if killed by a signal).
    pub code: i32,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

/// Runs the `fathom` binary with `args` in the directory `dir` (stdin closed; stderr is
/// a pipe, so no progress bar is drawn).
pub fn fathom(dir: &Path, args: &[&str]) -> Ran {
    let out = Command::new(fathom_bin())
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    Ran {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Reads `dir/file` as text.
/// Compares `got` with the snapshot file `snapshot` (its trailing newline ignored);
/// a difference is described in `mismatches`, labelled with `input`.
pub fn compare_snapshot(input: &Path, snapshot: &Path, got: &str, mismatches: &mut Vec<String>) {
    let expected = std::fs::read_to_string(snapshot)
        .unwrap_or_else(|_| panic!("{} has no snapshot {}", input.display(), snapshot.display()));
    if got != expected.trim_end() {
        mismatches.push(format!(
            "{}:\n  got      {got}\n  expected {}",
            input.display(),
            expected.trim_end()
        ));
    }
}

pub fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file))
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.join(file).display()))
}

/// The beacons paper's velocity-command motion of `duration_s` and its sensor suite with
/// Gaussian noise on and the given correlation / outlier switches (library defaults
/// otherwise): the common fixture of the beacon EKF end-to-end tests.
pub fn beacon_mission(
    duration_s: f64,
    correlation: bool,
    outliers: bool,
) -> (
    fathom_traj::velocity_command::VelocityCommandParams,
    fathom_sensors::BeaconSuiteConfig,
) {
    let motion_params = fathom_traj::velocity_command::VelocityCommandParams {
        duration: duration_s,
        ..Default::default()
    };
    let suite = fathom_sensors::BeaconSuiteParams {
        switches: fathom_sensors::NoiseSwitches {
            gaussian: true,
            correlation,
            outliers,
        },
        ..Default::default()
    }
    .check()
    .unwrap();
    (motion_params, suite)
}

/// Runs `args`, expects exit code 2 and one error line containing every `want`.
pub fn usage_error(dir: &Path, args: &[&str], want: &[&str]) {
    let r = fathom(dir, args);
    assert_eq!(
        r.code, 2,
        "{args:?}: stdout {} stderr {}",
        r.stdout, r.stderr
    );
    let line = r.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    for w in want {
        assert!(line.contains(w), "{args:?}: `{w}` not in {line}");
    }
}

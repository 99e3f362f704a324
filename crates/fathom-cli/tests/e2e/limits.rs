//! Limits known before running (issue 23), through the real `fathom` binary: every
//! memory bomb of the issue (a duration of 1e9 s, a step of 1e-9 s, 1e10 histogram
//! bins, a 1 GHz IMU, 10^12 runs, a beacon at 1e308 m) is refused by `fathom check`
//! and by `fathom run` with exit code 2 and one line naming the key, before any
//! output folder is created or any run starts; the limits can be raised explicitly;
//! a missing data folder is an error. Durations are printed, not asserted (tests never
//! assert timings): see the report of issue 23 for the measured times.

use std::time::Instant;

use crate::support::{fathom, preset, scratch};

/// The preset `file` with the first line starting with `from` replaced by `to`.
fn edited(file: &str, from: &str, to: &str) -> String {
    let text = preset(file);
    let at = text
        .lines()
        .position(|l| l.starts_with(from))
        .unwrap_or_else(|| panic!("{file}: no line starts with `{from}`"));
    let mut lines: Vec<&str> = text.lines().collect();
    lines[at] = to;
    lines.join("\n") + "\n"
}

/// (file, preset, line start, replacement, key, words of the reason).
const BOMBS: [(&str, &str, &str, &str, &str, &str); 7] = [
    (
        "duration.toml",
        "fusion.toml",
        "duration_s =",
        "duration_s = 1e9",
        "mission.duration_s",
        "of memory",
    ),
    (
        "step.toml",
        "beacons.toml",
        "step_s =",
        "step_s = 1e-9",
        "motion.step_s",
        "of memory",
    ),
    (
        "bins.toml",
        "fusion.toml",
        "histogram_bins =",
        "histogram_bins = 10000000000",
        "analysis.histogram_bins",
        "of memory",
    ),
    (
        "imu.toml",
        "vkf.toml",
        "imu_rate_hz =",
        "imu_rate_hz = 1e9",
        "route.imu_rate_hz",
        "of memory",
    ),
    (
        "runs.toml",
        "noise.toml",
        "runs =",
        "runs = 1000000000000",
        "runs",
        "the run would",
    ),
    (
        "far_beacon.toml",
        "beacons.toml",
        "positions =",
        "positions = [[1e308, 15.0, 0.0], [-15.0, 15.0, 40.0], [-15.0, -15.0, 0.0], [15.0, -15.0, 40.0]]",
        "beacons.positions[0][0]",
        "must be at most 1e7 in magnitude, got 1.0e308",
    ),
    (
        "huge_sigma.toml",
        "beacons.toml",
        "range_sigma_m =",
        "range_sigma_m = 1e200",
        "noise.range_sigma_m",
        "must be at most 1e6",
    ),
];

#[test]
fn memory_bombs_are_refused_by_check_and_run_before_any_work() {
    let dir = scratch("limits-bombs");
    let mut times = Vec::new();
    for (file, base, from, to, key, reason) in BOMBS {
        std::fs::write(dir.join(file), edited(base, from, to)).unwrap();
        for args in [
            vec!["check", file],
            vec!["run", file, "--out", "never", "--threads", "1"],
        ] {
            let t0 = Instant::now();
            let ran = fathom(&dir, &args);
            times.push(format!("{args:?}: {:.3} s", t0.elapsed().as_secs_f64()));
            assert_eq!(ran.code, 2, "{args:?}: {ran:?}");
            let line = ran.stderr.trim_end();
            assert_eq!(line.lines().count(), 1, "{ran:?}");
            assert!(
                line.starts_with(&format!("error: {file}: key `{key}`: ")),
                "{args:?}: {line}"
            );
            assert!(line.contains(reason), "{args:?}: {line}");
            // No Rust type names, no panic.
            for bad in ["panicked", "usize", "u64", "i128", "f64"] {
                assert!(!line.contains(bad), "{line}");
            }
            // Nothing ran: no batch line, no output folder, no lock, no partial folder.
            assert!(ran.stdout.is_empty(), "{args:?}: {ran:?}");
        }
        let leftovers: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("never"))
            .collect();
        assert!(leftovers.is_empty(), "{file}: {leftovers:?}");
    }
    println!("{}", times.join("\n"));
}

#[test]
fn the_limits_can_be_raised_or_lowered_explicitly() {
    let dir = scratch("limits-raise");
    // 2000 fusion runs on a 20 000 s mission: beyond the default 4 GiB.
    let text = edited("fusion.toml", "duration_s =", "duration_s = 20000.0").replacen(
        "runs = 200 ",
        "runs = 2000 ",
        1,
    );
    std::fs::write(dir.join("big.toml"), text).unwrap();
    let refused = fathom(&dir, &["check", "big.toml"]);
    assert_eq!(refused.code, 2, "{refused:?}");
    assert!(refused.stderr.contains("(--max-memory-gb)"), "{refused:?}");
    let raised = fathom(
        &dir,
        &[
            "check",
            "big.toml",
            "--max-memory-gb",
            "10000",
            "--max-hours",
            "10000",
        ],
    );
    assert_eq!(raised.code, 0, "{raised:?}");
    assert!(raised.stdout.contains("of memory"), "{raised:?}");
    // Lowering them refuses the preset.
    let preset_path = crate::support::repo_root().join("scenarios/fusion.toml");
    let lowered = fathom(
        &dir,
        &[
            "check",
            preset_path.to_str().unwrap(),
            "--max-hours",
            "0.00001",
        ],
    );
    assert_eq!(lowered.code, 2, "{lowered:?}");
    assert!(lowered.stderr.contains("(--max-hours)"), "{lowered:?}");
    // Bad limit values are usage errors naming the option.
    for (opt, v) in [("--max-memory-gb", "0"), ("--max-hours", "-1")] {
        let bad = fathom(&dir, &["check", "big.toml", &format!("{opt}={v}")]);
        assert_eq!(bad.code, 2, "{bad:?}");
        assert!(bad.stderr.contains(opt), "{bad:?}");
    }
}

#[test]
fn a_missing_data_folder_is_a_usage_error() {
    let dir = scratch("limits-no-data");
    let text = edited("plaza.toml", "dir =", "dir = \"no_such_plaza_folder\"");
    std::fs::write(dir.join("p.toml"), text).unwrap();
    let ran = fathom(&dir, &["run", "p.toml", "--out", "o"]);
    assert_eq!(ran.code, 2, "{ran:?}");
    assert!(ran.stderr.contains("key `data.dir`"), "{ran:?}");
    assert!(!dir.join("o").exists());
}

//! The simulated example logs replayed through `fathom-replay`: with and without
//! ground truth, both log kinds (the INS / DVL log is the `vkf` mission cut to 600 s:
//! bottom lock is lost from about 300 s on), the replays run as jobs of the driver.

use std::path::{Path, PathBuf};

use fathom_data::layout::{LogKind, Manifest, write_log};
use fathom_replay::ins_dvl::{InsDvl, parse_settings, replay};
use fathom_replay::range_beacon::RangeBeacon;
use fathom_sim::SimError;
use fathom_sim::driver::{ExperimentResult, WriteOptions, execute_to};
use fathom_sim::experiment::{DynExperiment, Environment, Job};

use crate::example_log::{ins_dvl_example, range_beacon_example};

fn preset() -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ins-dvl.toml"),
    )
    .unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir()
        .join("fathom-sim-tests")
        .join(format!("own-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Replays the log in `dir` with `exp`'s built-in settings into `out`, as `fathom
/// replay` does.
fn replay_job(
    exp: &dyn DynExperiment,
    dir: &Path,
    out: &Path,
) -> Result<ExperimentResult, SimError> {
    let preset_dir = format!("dir = \"data/logs/{}-example\"", exp.name());
    assert!(exp.preset().contains(&preset_dir), "{}", exp.name());
    let text = exp
        .preset()
        .replace(&preset_dir, &format!("dir = {:?}", dir.to_str().unwrap()));
    let job = Job {
        text: &text,
        file: "preset",
        runs: None,
        seed: None,
        threads: Some(1),
        progress: None,
        env: Environment::new(dir),
    };
    let options = WriteOptions {
        force: false,
        command: "replay".into(),
        scenario_files: true,
    };
    execute_to(exp, &job, out, &options).map(|(r, _)| r)
}

fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap()
}

#[test]
fn example_logs_replay_with_and_without_truth() {
    for truth in [true, false] {
        let dir = scratch(&format!("rb-{truth}"));
        let log = range_beacon_example(120.0, 3, truth).unwrap().log;
        write_log(
            &dir,
            &Manifest::new(LogKind::RangeBeacon, "example"),
            &log.to_files(),
        )
        .unwrap();
        let out = dir.with_extension("out");
        let r = replay_job(&RangeBeacon, &dir, &out).unwrap();
        let report = read(&out, "report.md");
        assert_eq!(report.contains("Position error against"), truth, "{report}");
        assert!(r.summary.row("SC", "nis_ranges_mean").is_some(), "{report}");
        assert_eq!(r.summary.row("SC", "rmse").is_some(), truth);
        assert_eq!(r.summary.extra["with_truth"], truth);
        let est = read(&out, "estimates.csv");
        assert_eq!(est.lines().next().unwrap().contains("true_north[m]"), truth);
        // The figures of every replay; the plan view and the error only with truth.
        for (f, with) in [
            ("estimate_vs_truth.svg", truth),
            ("error_3sigma.svg", truth),
            ("innovations.svg", true),
            ("nis.svg", true),
            ("innovations_depth.svg", true),
            ("nis_depth.svg", true),
        ] {
            assert_eq!(out.join(f).is_file(), with, "{f}");
        }
        // A range-beacon folder is not an INS log: the user's error, before anything
        // is written.
        let e = replay_job(&InsDvl, &dir, &dir.with_extension("o2")).unwrap_err();
        let chain = fathom_sim::error_chain(&e);
        assert!(
            e.is_user_error() && chain.contains("range-beacon"),
            "{chain}"
        );
        assert!(!dir.with_extension("o2").exists());
    }
    let dir = scratch("ins");
    let log = ins_dvl_example(60.0, 3, false).unwrap();
    write_log(
        &dir,
        &Manifest::new(LogKind::InsDvl, "example"),
        &log.to_files(),
    )
    .unwrap();
    let out = dir.with_extension("out");
    let r = replay_job(&InsDvl, &dir, &out).unwrap();
    assert!(r.summary.row("ESKF", "nis_dvl_velocity_mean").is_some());
    assert!(r.summary.row("ESKF", "mean").is_none());
    for f in ["innovations_north.svg", "nis.svg", "nis_depth.svg"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // A missing folder is the user's error, naming the folder.
    let e = replay_job(&InsDvl, &dir.join("nope"), &dir.with_extension("o3")).unwrap_err();
    let chain = fathom_sim::error_chain(&e);
    assert!(e.is_user_error() && chain.contains("nope"), "{chain}");
}

#[test]
fn the_example_log_with_truth_scores_every_method() {
    let log = ins_dvl_example(600.0, 5, true).unwrap();
    let s = parse_settings(&preset(), "ins-dvl.toml").unwrap();
    let r = replay(&log, &s).unwrap();
    assert_eq!(r.times.len(), 600);
    let final_err = |m: &str| {
        *r.method(m)
            .unwrap()
            .errors_h
            .as_ref()
            .unwrap()
            .last()
            .unwrap()
    };
    let mean = |m: &str| r.method(m).unwrap().stats.unwrap().mean;
    // Unflagged garbage from the DVL beyond its range ruins the naive filter; the
    // switching box (VKF, ESKF) and the gate keep the error small.
    for (m, factor) in [("VKF", 0.2), ("ESKF", 0.2), ("INS-DVL-gated", 0.5)] {
        assert!(
            final_err(m) < factor * final_err("INS-DVL"),
            "{m}: {} vs {}",
            final_err(m),
            final_err("INS-DVL")
        );
        assert!(mean(m) < 20.0, "{m}: {}", mean(m));
    }
    // Aiding bounds the velocity error: the aided filters beat pure INS on average.
    let vel = |m: &str| {
        let v = r.method(m).unwrap().vel_errors_h.as_ref().unwrap();
        v.iter().sum::<f64>() / v.len() as f64
    };
    assert!(
        vel("VKF") < vel("PINS"),
        "{} vs {}",
        vel("VKF"),
        vel("PINS")
    );
    // The VKF switched to the RPM speed while the DVL was beyond its range.
    let vkf = r.method("VKF").unwrap();
    let on_rpm = vkf.trace.velocity_updates.iter().filter(|u| u.rpm).count();
    assert!(
        on_rpm > 500 && r.invalid_dvl_rows > 500,
        "{on_rpm} {}",
        r.invalid_dvl_rows
    );
    assert!(r.method("PINS").unwrap().velocity_nis.is_none());
}

#[test]
fn without_truth_the_nis_tells_the_naive_filter_from_the_switching_one() {
    let log = ins_dvl_example(600.0, 5, false).unwrap();
    let s = parse_settings(&preset(), "ins-dvl.toml").unwrap();
    let r = replay(&log, &s).unwrap();
    assert!(r.truth.is_none() && r.methods.iter().all(|m| m.stats.is_none()));
    let naive = r.method("INS-DVL").unwrap().velocity_nis.unwrap();
    let vkf = r.method("VKF").unwrap().dvl_nis.unwrap();
    // Garbage velocities (±5 m/s) against a 2.5 cm/s model: a huge NIS.
    assert!(naive.mean > 100.0 && !naive.consistent(), "{naive:?}");
    // Valid DVL rows against the same model: NIS of the order of its 3 dof.
    assert!(vkf.mean < 6.0, "{vkf:?}");
    assert_eq!(vkf.dof, 3);
    assert!(r.method("ESKF").unwrap().depth_nis.unwrap().count > 2000);
}

/// What `fathom log example <kind>` writes by default (300 s, seed 1) replayed with the
/// built-in settings: every filter is consistent (every check holds), and the robust
/// filters reject exactly the injected range outliers.
#[test]
fn default_examples_are_consistent_with_the_built_in_settings() {
    let ex = range_beacon_example(300.0, 1, true).unwrap();
    assert!(ex.outliers > 5, "{}", ex.outliers);
    let dir = scratch("rb-default");
    write_log(
        &dir,
        &Manifest::new(LogKind::RangeBeacon, "example"),
        &ex.log.to_files(),
    )
    .unwrap();
    let r = replay_job(&RangeBeacon, &dir, &dir.with_extension("out")).unwrap();
    for m in ["AS", "SC", "SI"] {
        let rejected = r.summary.row(m, "rejected").unwrap().value;
        assert_eq!(rejected, ex.outliers as f64, "{m}");
    }
    let dir = scratch("ins-default");
    let log = ins_dvl_example(300.0, 1, true).unwrap();
    write_log(
        &dir,
        &Manifest::new(LogKind::InsDvl, "example"),
        &log.to_files(),
    )
    .unwrap();
    let ri = replay_job(&InsDvl, &dir, &dir.with_extension("out")).unwrap();
    for result in [&r, &ri] {
        assert!(
            result.summary.claims.len() >= 6,
            "{:?}",
            result.summary.claims
        );
        for c in &result.summary.claims {
            assert!(c.holds, "{}: {} ({})", result.name, c.id, c.detail);
        }
    }
}

//! Tests of the INS / DVL replay on the simulated example log (the `vkf` mission cut
//! to 600 s: bottom lock is lost from about 300 s on).

use super::*;
use crate::example_log::ins_dvl_example;

fn preset() -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ins-dvl.toml"),
    )
    .unwrap()
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

#[test]
fn bad_settings_name_the_key() {
    for (from, to, key) in [
        ("filter = \"vkf\"", "filter = \"ukf\"", "methods[2].filter"),
        (
            "gate_probability = 0.999",
            "gate_probability = 1.5",
            "methods[3].gate_probability",
        ),
        (
            "filter = \"pins\"",
            "filter = \"pins\"\ngate_probability = 0.9",
            "methods[0].gate_probability",
        ),
        (
            "accel_bias_frame = \"nav\"",
            "accel_bias_frame = \"ned\"",
            "nav_filter.accel_bias_frame",
        ),
        ("timeout_s = 1.0", "timeout_s = -1.0", "dvl.timeout_s"),
        ("name = \"ESKF\"", "name = \"VKF\"", "methods[4].name"),
    ] {
        let t = preset().replacen(from, to, 1);
        assert_ne!(t, preset(), "{from}");
        let e = parse_settings(&t, "i.toml").unwrap_err().to_string();
        assert!(e.contains(key), "{key}: {e}");
    }
    let cut = &preset()[..preset().find("[[methods]]").unwrap()];
    let s = parse_settings(cut, "i.toml").unwrap();
    assert_eq!(s.methods.len(), 5);
}

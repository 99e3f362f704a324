//! Tests of the Plaza replay on a synthetic log.

use super::*;
use fathom_data::plaza::{OdometryStep, PlazaFiles, PoseRecord, RangeRecord};
use fathom_estimators::schemes::UpdateScheme;
use fathom_estimators::wheel_odometry::OdometryRate;

pub(crate) fn preset() -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/plaza.toml"),
    )
    .unwrap()
}

#[test]
fn settings_parse_and_bad_values_name_the_key() {
    let s = parse_settings(&preset(), "plaza.toml").unwrap();
    assert_eq!(s.calibration, Calibration::Affine);
    assert_eq!(s.ablation_scheme, UpdateScheme::SynchronousCollective);
    let names: Vec<String> = s.variants().into_iter().map(|v| v.name).collect();
    assert_eq!(
        names,
        [
            "AS",
            "SC",
            "SI",
            "SC-no-bias",
            "SC-offset-only",
            "SC-hard-gate",
            "SC-no-bias-hard-gate"
        ]
    );
    for (from, to, key) in [
        (
            "calibration = \"affine\"",
            "calibration = \"cubic\"",
            "ranges.calibration",
        ),
        (
            "range_order = \"sort\"",
            "range_order = \"x\"",
            "data.range_order",
        ),
        ("scheme = \"SC\"", "scheme = \"XX\"", "ablation.scheme"),
        (
            "recovery_after = 5",
            "recovery_after = 0",
            "robust.recovery_after",
        ),
        (
            "recovery_inflation = 4.0",
            "recovery_inflation = 1.0",
            "robust.recovery_inflation",
        ),
        (
            "reject_sigma = 6.0",
            "reject_sigma = 1.0",
            "robust.reject_sigma",
        ),
        ("epoch_s = 0.1", "epoch_s = 0.0", "schemes.epoch_s"),
        // an epoch of 1 ns would run a replay for days: refused, naming the key
        ("epoch_s = 0.1", "epoch_s = 1e-9", "schemes.epoch_s"),
        ("epoch_s = 0.1", "epoch_s = 0.1\nextra = 1", "schemes.extra"),
    ] {
        let text = preset().replace(from, to);
        let e = parse_settings(&text, "plaza.toml").unwrap_err().to_string();
        assert!(e.contains(key) && e.starts_with("plaza.toml"), "{key}: {e}");
    }
}

/// A synthetic log: a 60 m x 40 m loop driven at 1 m/s for 600 s, odometry with a
/// 1 % distance scale error and a heading-rate bias, ranges `1.05 d + 0.4` with a
/// deterministic +-0.3 m pattern, ground truth every odometry step.
pub(crate) fn synthetic_log() -> PlazaLog {
    let t0 = 1000.0;
    let dt = 0.2;
    let beacons = vec![
        BeaconSite {
            id: 10,
            x: -10.0,
            y: -10.0,
        },
        BeaconSite {
            id: 20,
            x: 70.0,
            y: -5.0,
        },
        BeaconSite {
            id: 30,
            x: 65.0,
            y: 50.0,
        },
        BeaconSite {
            id: 40,
            x: -5.0,
            y: 45.0,
        },
    ];
    let (mut x, mut y, mut th) = (0.0f64, 0.0f64, 0.0f64);
    let mut gt = vec![PoseRecord {
        time: t0,
        x,
        y,
        heading: th,
    }];
    let mut odometry = Vec::new();
    let mut ranges = Vec::new();
    for k in 1..=3000 {
        let t = t0 + k as f64 * dt;
        // Turn left 90 degrees over 3 s every 50 s or 30 s (a rounded rectangle).
        let phase = (k as f64 * dt) % 160.0;
        let turning = [(50.0, 53.0), (80.0, 83.0), (130.0, 133.0), (157.0, 160.0)]
            .iter()
            .any(|&(a, b)| phase >= a && phase < b);
        let dth = if turning {
            std::f64::consts::FRAC_PI_2 / 15.0
        } else {
            0.0
        };
        let dd = 1.0 * dt;
        let m = th + dth / 2.0;
        x += dd * m.cos();
        y += dd * m.sin();
        th += dth;
        gt.push(PoseRecord {
            time: t,
            x,
            y,
            heading: th,
        });
        odometry.push(OdometryStep {
            time: t,
            delta_distance: dd * 1.01,
            delta_heading: dth + 0.0005 * dt,
        });
        if k % 2 == 0 {
            let c = (k / 2) % 4;
            let b = beacons[c];
            let d = (x - b.x).hypot(y - b.y);
            let wiggle = 0.3 * ((k as f64) * 0.7).sin();
            ranges.push(RangeRecord {
                time: t + 0.05,
                sender: 2,
                beacon_id: b.id,
                beacon: c,
                range: 1.05 * d + 0.4 + wiggle,
                line: ranges.len() + 1,
            });
        }
    }
    ranges.pop(); // the last one lies after the last ground-truth row
    PlazaLog {
        files: PlazaFiles {
            odometry: "S_DR.txt".into(),
            ranges: "S_TD.txt".into(),
            mat: "S_.mat".into(),
        },
        odometry,
        ranges,
        range_order_breaks: vec![],
        dr_path: vec![gt[0]],
        ground_truth: gt,
        beacons,
    }
}

#[test]
fn prepared_log_uses_relative_time_and_interval_rates() {
    let log = synthetic_log();
    let p = PreparedLog::new(&log).unwrap();
    assert_eq!(p.t0, 1000.0);
    assert_eq!(p.inputs.len(), log.odometry.len() + 1);
    assert_eq!(p.inputs[0].0, 0.0);
    approx::assert_relative_eq!(p.inputs[1].0, 0.2, epsilon = 1e-12);
    approx::assert_relative_eq!(p.inputs[0].1.speed, 1.01, epsilon = 1e-9);
    assert_eq!(p.inputs.last().unwrap().1, OdometryRate::default());
    assert_eq!(p.eval.len(), log.ground_truth.len() - 1);
    approx::assert_relative_eq!(p.ranges[0].time, 0.45, epsilon = 1e-12);
    let ev = p.events(true);
    assert!(ev.windows(2).all(|w| w[0].0 <= w[1].0));
    assert_eq!(ev.len(), p.inputs.len() + p.eval.len() + p.ranges.len());
}

#[test]
fn synthetic_replay_beats_dead_reckoning_and_learns_the_calibration() {
    let log = synthetic_log();
    let settings = parse_settings(&preset(), "plaza.toml").unwrap();
    let r = replay(&log, &settings).unwrap();
    let dr = r.method("DR").unwrap().stats;
    for name in ["AS", "SC", "SI"] {
        let m = r.method(name).unwrap();
        assert!(
            m.stats.mean < 0.5 * dr.mean,
            "{name}: {} vs DR {}",
            m.stats.mean,
            dr.mean
        );
        assert!(m.stats.max < 1.5, "{name}: {}", m.stats.max);
        let last = m.calibration.last().unwrap();
        assert!((last[1] - 0.05).abs() < 0.01, "{name} scale {}", last[1]);
        assert!((last[0] - 0.4).abs() < 0.5, "{name} offset {}", last[0]);
    }
    // Without calibration the 5 % long ranges pull the estimate off.
    let nb = r.method("SC-no-bias").unwrap().stats;
    assert!(nb.mean > 2.0 * r.method("SC").unwrap().stats.mean);
    // The analysis recovers the synthetic range model.
    approx::assert_relative_eq!(r.analysis.fit.1, 0.05, epsilon = 0.005);
    approx::assert_relative_eq!(r.analysis.fit.0, 0.4, epsilon = 0.2);
}

#[test]
fn truth_is_interpolated_inside_the_span_only() {
    let gt = [
        PoseRecord {
            time: 1.0,
            x: 0.0,
            y: 0.0,
            heading: 0.0,
        },
        PoseRecord {
            time: 2.0,
            x: 2.0,
            y: -2.0,
            heading: 0.0,
        },
    ];
    assert_eq!(truth_at(&gt, 1.5), Some((1.0, -1.0)));
    assert_eq!(truth_at(&gt, 2.0), Some((2.0, -2.0)));
    assert_eq!(truth_at(&gt, 0.5), None);
    assert_eq!(truth_at(&gt, 2.5), None);
}

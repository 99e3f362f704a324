//! Tests of the range-beacon replay: a Plaza log through the CSV layout gives the
//! Plaza replay's numbers bit for bit; a synthetic DVL + heading log localizes; without
//! truth the innovations and NIS are reported.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::*;
use crate::plaza::tests::synthetic_log;
use fathom_data::layout::convert::range_beacon_from_plaza;
use fathom_data::layout::range_beacon::{RangeRow, Start, TruthRow};
use fathom_data::layout::{LogKind, Manifest, write_log};

fn config(name: &str) -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios")
            .join(name),
    )
    .unwrap()
}

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir()
        .join("fathom-sim-tests")
        .join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn a_plaza_log_through_the_layout_replays_to_the_plaza_numbers() {
    let plaza = synthetic_log();
    let ps = crate::plaza::parse_settings(&crate::plaza::tests::preset(), "plaza.toml").unwrap();
    let want = crate::plaza::replay(&plaza, &ps).unwrap();
    let dir = scratch("plaza-as-layout");
    let converted = range_beacon_from_plaza(&plaza);
    write_log(
        &dir,
        &Manifest::new(LogKind::RangeBeacon, "synthetic"),
        &converted.to_files(),
    )
    .unwrap();
    let log = RangeBeaconLog::read_dir(&dir).unwrap();
    assert_eq!(log, converted);
    let s = parse_settings(
        &config("range-beacon-plaza.toml"),
        "range-beacon-plaza.toml",
    )
    .unwrap();
    let got = replay(&log, &s).unwrap();
    assert_eq!(got.methods.len(), want.methods.len());
    for (g, w) in got.methods.iter().zip(&want.methods) {
        assert_eq!(g.spec.name, w.name);
        let st = g.stats.unwrap();
        for (a, b) in [
            (st.mean, w.stats.mean),
            (st.std, w.stats.std),
            (st.max, w.stats.max),
            (st.rmse, w.stats.rmse),
        ] {
            assert_eq!(a.to_bits(), b.to_bits(), "{}: {a} vs {b}", w.name);
        }
        assert_eq!(g.trace.est, w.est, "{}", w.name);
        assert_eq!(g.trace.calibration, w.calibration, "{}", w.name);
        assert_eq!(g.trace.counts.rejected, w.rejected, "{}", w.name);
        assert_eq!(g.trace.counts.accepted, w.accepted, "{}", w.name);
        assert_eq!(g.trace.downweighted, w.downweighted, "{}", w.name);
    }
    // Negative control: another tuning changes the numbers.
    let other = config("range-beacon-plaza.toml").replace("sigma_m = 1.0", "sigma_m = 2.0");
    let s2 = parse_settings(&other, "x.toml").unwrap();
    let r2 = replay(&log, &s2).unwrap();
    assert_ne!(
        r2.method("SC").unwrap().stats.unwrap().mean,
        got.method("SC").unwrap().stats.unwrap().mean
    );
}

#[test]
fn without_truth_the_replay_reports_innovations_and_nis() {
    let mut log = range_beacon_from_plaza(&synthetic_log());
    log.truth = None;
    let s = parse_settings(&config("range-beacon.toml"), "range-beacon.toml").unwrap();
    let r = replay(&log, &s).unwrap();
    // Recorded every second over the 600 s log.
    assert_eq!(r.times.len(), 600);
    assert!(r.truth.is_none());
    for m in &r.methods {
        assert!(m.errors.is_none() && m.stats.is_none());
        if m.is_filter() {
            // Every range after the start is tested once.
            let n = m.range_nis.unwrap().count;
            assert_eq!(n, m.trace.counts.accepted + m.trace.counts.rejected);
            assert!(n > 1000, "{n}");
            // The synthetic ranges wiggle by +-0.3 m; the filter assumes 1 m.
            assert!(m.range_nis.unwrap().mean < 0.5, "{:?}", m.range_nis);
        } else {
            assert!(m.range_nis.is_none() && m.trace.ranges.is_empty());
        }
    }
    // The default calibration on an odometry log is affine (by log).
    assert!(matches!(
        &r.method("SC").unwrap().spec.kind,
        MethodKind::Ekf(v) if v.calibration == crate::plaza::Calibration::Affine
    ));
}

/// A 3D log: 1 m/s on a 20 m circle at 10 m depth, DVL with a 5 % scale error and a
/// 2 cm/s lateral bias,
/// headings, four beacons, ranges with N(0, 0.3 m), depth, truth at 10 Hz.
fn dvl_log(seed: u64) -> RangeBeaconLog {
    dvl_log_with(seed, 1.05, 0.02)
}

/// [`dvl_log`] with DVL scale `scale` and lateral bias `lateral` m/s.
fn dvl_log_with(seed: u64, scale: f64, lateral: f64) -> RangeBeaconLog {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let range_noise = Normal::new(0.0, 0.3).unwrap();
    let small = Normal::new(0.0, 0.002).unwrap();
    let (r, w) = (20.0f64, 0.05f64);
    let pos = |t: f64| [r * (w * t).cos(), r * (w * t).sin(), 10.0];
    let heading = |t: f64| fathom_core::units::wrap_pi(w * t + std::f64::consts::FRAC_PI_2);
    let beacons = [
        [30.0, 30.0, 0.0],
        [-30.0, 30.0, 40.0],
        [-30.0, -30.0, 0.0],
        [30.0, -30.0, 40.0],
    ];
    let mut dvl = Vec::new();
    let mut head = Vec::new();
    let mut ranges = Vec::new();
    let mut depth = Vec::new();
    let mut truth = Vec::new();
    for k in 1..=3000 {
        let t = k as f64 * 0.1;
        let p = pos(t);
        head.push((t, heading(t) + small.sample(&mut rng)));
        truth.push(TruthRow {
            time: t,
            north_east: [p[0], p[1]],
            down: Some(p[2]),
            heading: Some(heading(t)),
        });
        if k % 2 == 0 {
            dvl.push((
                t,
                [
                    scale + small.sample(&mut rng),
                    lateral + small.sample(&mut rng),
                    0.0,
                ],
            ));
            depth.push((t, p[2] + small.sample(&mut rng)));
        }
        if k % 3 == 0 {
            let b = (k / 3) % 4;
            let d = ((p[0] - beacons[b][0]).powi(2)
                + (p[1] - beacons[b][1]).powi(2)
                + (p[2] - beacons[b][2]).powi(2))
            .sqrt();
            ranges.push(RangeRow {
                time: t + 0.05,
                beacon: b,
                range: d + range_noise.sample(&mut rng),
            });
        }
    }
    ranges.pop();
    RangeBeaconLog {
        beacons: beacons
            .iter()
            .enumerate()
            .map(|(i, b)| Beacon {
                id: 100 + i as i64,
                pos_in_nav: *b,
            })
            .collect(),
        beacons_have_down: true,
        start: Start {
            time: 0.0,
            north_east: [r, 0.0],
            down: Some(10.0),
            heading: heading(0.0),
        },
        motion: Motion::Dvl { dvl, heading: head },
        ranges,
        depth: Some(depth),
        truth: Some(truth),
    }
}

#[test]
fn a_dvl_log_localizes_in_3d_and_its_ranges_are_consistent() {
    let log = dvl_log(1);
    let text = config("range-beacon.toml")
        .replace("sigma_m = 1.0", "sigma_m = 0.3")
        .replace("sigma_m = 0.2", "sigma_m = 0.01");
    let s = parse_settings(&text, "range-beacon.toml").unwrap();
    let r = replay(&log, &s).unwrap();
    assert_eq!(r.error_dims, 3);
    let dr = r.method("DR").unwrap().stats.unwrap();
    for name in ["AS", "SC", "SI"] {
        let m = r.method(name).unwrap();
        let st = m.stats.unwrap();
        assert!(
            st.mean < 0.6 && st.mean < 0.5 * dr.mean,
            "{name}: {} vs DR {}",
            st.mean,
            dr.mean
        );
        assert!(m.depth_nis.is_some() && m.trace.depth_counts.unwrap().accepted > 1000);
    }
    // On a log without the DVL biases (which the filter does not model) the range
    // model matches the data: consistent NIS.
    let unbiased = dvl_log_with(1, 1.0, 0.0);
    let ru = replay(&unbiased, &s).unwrap();
    for name in ["AS", "SC", "SI"] {
        let nis = ru.method(name).unwrap().range_nis.unwrap();
        assert!(nis.mean > 0.6 && nis.mean < 1.5, "{name}: {nis:?}");
    }
    // Negative control: a filter told the ranges are 10 times better sees NIS far
    // beyond 1.
    let tight = parse_settings(&text.replace("sigma_m = 0.3", "sigma_m = 0.03"), "t.toml").unwrap();
    let rt = replay(&unbiased, &tight).unwrap();
    let nis = rt.method("SC").unwrap().range_nis.unwrap();
    assert!(!nis.consistent() && nis.mean > 5.0, "{nis:?}");
    // Range calibration states exist for odometry logs only.
    let cal = text.replace(
        "name = \"SC\"\nscheme = \"SC\"",
        "name = \"SC\"\nscheme = \"SC\"\ncalibration = \"offset\"",
    );
    let e = replay(&log, &parse_settings(&cal, "c.toml").unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("method `SC`") && e.contains("needs an odometry log"),
        "{e}"
    );
}

/// `[dvl] heading_sigma_rad`: with no ranges and a start heading 0.3 rad off, the
/// absolute heading update brings the EKF's heading to the truth; without it (the
/// negative control) the yaw rates keep the initial error.
#[test]
fn an_absolute_heading_update_corrects_a_wrong_start_heading() {
    let mut log = dvl_log(2);
    log.ranges.clear();
    let true_final = log
        .truth
        .as_ref()
        .and_then(|t| t.last())
        .and_then(|r| r.heading);
    let true_final = true_final.unwrap();
    // The heading sensor's first row at the start: the yaw rates telescope from it,
    // not from `initial.csv`'s heading, which is 0.3 rad off.
    let true_start = log.start.heading;
    if let Motion::Dvl { heading, .. } = &mut log.motion {
        heading.insert(0, (log.start.time, true_start));
    }
    log.start.heading += 0.3;
    let base = config("range-beacon.toml").replace("sigma_m = 0.2", "sigma_m = 0.01");
    let final_error = |text: &str| {
        let s = parse_settings(text, "h.toml").unwrap();
        let r = replay(&log, &s).unwrap();
        let est = *r.method("AS").unwrap().trace.heading.last().unwrap();
        fathom_core::units::wrap_pi(est - true_final).abs()
    };
    let rates_only = final_error(&base);
    let with_heading = final_error(&base.replace(
        "yaw_rate_sigma_rad_per_s = 0.01",
        "yaw_rate_sigma_rad_per_s = 0.01\nheading_sigma_rad = 0.01",
    ));
    assert!(rates_only > 0.25, "rates only: {rates_only}");
    assert!(with_heading < 0.02, "with absolute heading: {with_heading}");
}

#[test]
fn bad_method_tables_name_the_key() {
    let base = config("range-beacon.toml");
    let cases = [
        (
            "name = \"AS\"\nscheme = \"AS\"",
            "name = \"AS\"\nscheme = \"XS\"",
            "methods[1].scheme",
        ),
        (
            "name = \"AS\"\nscheme = \"AS\"",
            "name = \"AS\"",
            "methods[1].scheme",
        ),
        (
            "name = \"AS\"\nscheme = \"AS\"",
            "name = \"AS\"\nscheme = \"AS\"\ngate_sigma = 2.0",
            "methods[1].gate_sigma",
        ),
        (
            "name = \"AS\"\nscheme = \"AS\"",
            "name = \"AS\"\nscheme = \"AS\"\noutliers = \"gate\"",
            "methods[1].gate_sigma",
        ),
        (
            "name = \"AS\"\nscheme = \"AS\"",
            "name = \"AS\"\nscheme = \"AS\"\noutliers = \"huber\"",
            "methods[1].outliers",
        ),
        (
            "name = \"AS\"\nscheme = \"AS\"",
            "name = \"AS\"\nscheme = \"AS\"\ncalibration = \"cubic\"",
            "methods[1].calibration",
        ),
        (
            "name = \"DR\"\nfilter = \"dead-reckoning\"",
            "name = \"DR\"\nfilter = \"dead-reckoning\"\nscheme = \"AS\"",
            "methods[0].scheme",
        ),
        (
            "name = \"DR\"\nfilter = \"dead-reckoning\"",
            "name = \"DR\"\nfilter = \"ukf\"",
            "methods[0].filter",
        ),
        ("name = \"SI\"", "name = \"SC\"", "methods[3].name"),
        ("name = \"SI\"", "name = \"S I\"", "methods[3].name"),
        ("period_s = 1.0", "period_s = 0.0", "output.period_s"),
        (
            "name = \"SI\"\nscheme = \"SI\"",
            "name = \"SI\"\nscheme = \"SI\"\nsmooth = true",
            "smooth",
        ),
    ];
    for (from, to, key) in cases {
        let t = base.replacen(from, to, 1);
        assert_ne!(t, base, "{from}");
        let e = parse_settings(&t, "rb.toml").unwrap_err().to_string();
        assert!(e.contains(key) && e.starts_with("rb.toml"), "{key}: {e}");
    }
    // Without a methods list: DR, AS, SC, SI.
    let cut = &base[..base.find("[[methods]]").unwrap()];
    let s = parse_settings(cut, "rb.toml").unwrap();
    let names: Vec<&str> = s.methods.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["DR", "AS", "SC", "SI"]);
    let empty = cut.replacen(
        "experiment = \"range-beacon\"",
        "experiment = \"range-beacon\"\nmethods = []",
        1,
    );
    let e = parse_settings(&empty, "rb.toml").unwrap_err().to_string();
    assert!(e.contains("key `methods`: lists no method"), "{e}");
}

//! Tests of the ULog reader and converter on the committed PX4 logs (`data/ulog/`)
//! and on broken copies of them.

use std::path::{Path, PathBuf};

use super::*;
use crate::layout::gnss_ins::GnssInsLog;

fn log_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/ulog")
        .join(name)
}

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(log_path(name)).unwrap()
}

#[test]
fn the_sitl_log_converts_with_truth_and_ekf2() {
    let c = convert_file(&log_path("sitl_groundtruth.ulg")).unwrap();
    let log = &c.log;
    assert_eq!(c.gnss_topic, "vehicle_gps_position");
    assert_eq!(log.imu.len(), 4445);
    assert_eq!(log.gnss.len(), 260);
    assert!(log.truth.as_ref().unwrap().len() > 250);
    assert!(log.reference.as_ref().unwrap().len() > 250);
    assert!(log.baro.is_some() && log.mag.is_some() && log.range.is_none());
    // gravity along -z of the body (FRD) at rest, m/s^2
    let a = log.imu[0].accel_in_body;
    assert!((a[2] + 9.8).abs() < 0.2, "{a:?}");
    // the first fix, near SITL's home 40.7423 N, 74.1793 W
    let g = log.gnss[0];
    assert!((g.lat_lon[0].to_degrees() - 40.7423).abs() < 1e-3);
    assert!((g.lat_lon[1].to_degrees() + 74.1793).abs() < 1e-3);
    assert!((g.altitude - 28.495).abs() < 1e-9, "{}", g.altitude);
}

#[test]
fn the_hardware_log_converts_with_range_and_ekf2() {
    let c = convert_file(&log_path("fmu_v3_gps.ulg")).unwrap();
    let log = &c.log;
    assert!(log.truth.is_none());
    assert!(log.range.as_ref().is_some_and(|r| !r.is_empty()));
    assert!(log.gnss.iter().filter(|g| g.fix_type >= 3).count() > 150);
    // the same epochs streamed from a reader in 1-byte reads
    let b = bytes("fmu_v3_gps.ulg");
    struct Slow<'a>(&'a [u8]);
    impl std::io::Read for Slow<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = buf.len().min(self.0.len()).min(7);
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }
    let slow = UlogTopics::read(Slow(&b), Path::new("x.ulg")).unwrap();
    let slow = gnss_ins_from_ulog(&slow, Path::new("x.ulg")).unwrap();
    assert_eq!(slow.log, c.log);
    // the CSV files read back to the same log, bit for bit
    let files = c.log.to_files();
    let set = crate::layout::FileSet {
        dir: "log".into(),
        manifest: crate::layout::Manifest::new(crate::layout::LogKind::GnssIns, ""),
        files: files
            .iter()
            .map(|(n, t)| (*n, t.as_bytes().to_vec()))
            .collect(),
    };
    assert_eq!(GnssInsLog::parse(&set).unwrap(), c.log);
}

#[test]
fn a_log_without_gps_names_the_topic() {
    let e = convert_file(&log_path("no_gps_appended.ulg")).unwrap_err();
    assert!(matches!(e, UlogError::TopicMissing { .. }), "{e}");
    assert!(e.to_string().contains("vehicle_gps_position"), "{e}");
}

#[test]
fn broken_logs_are_errors_not_panics() {
    let good = bytes("fmu_v3_gps.ulg");
    let p = Path::new("broken.ulg");
    assert!(matches!(
        convert_bytes(&[], p).unwrap_err(),
        UlogError::Empty { .. }
    ));
    assert!(matches!(
        convert_bytes(&good[..10], p).unwrap_err(),
        UlogError::Truncated { what: "header", .. }
    ));
    let cut = convert_bytes(&good[..good.len() - 5], p).unwrap_err();
    assert!(
        matches!(cut, UlogError::Truncated { len, what: "message", .. } if len == good.len() as u64 - 5),
        "{cut}"
    );
    let mut bad_magic = good.clone();
    bad_magic[0] = b'X';
    assert!(matches!(
        convert_bytes(&bad_magic, p).unwrap_err(),
        UlogError::Malformed {
            start: 0,
            end: 16,
            ..
        }
    ));
    // single bit flips spread over the file: an error or a log, never a panic
    let mut errors = 0;
    for k in (0..good.len()).step_by(good.len() / 97) {
        let mut b = good.clone();
        b[k] ^= 0x10;
        errors += usize::from(convert_bytes(&b, p).is_err());
    }
    assert!(errors > 0);
}

/// Inputs on which `px4-ulog` 0.6.1 panicked (found by a mutation run over the logs of
/// `data/ulog`): a parameter message whose key length runs past its end. They are
/// errors naming the message's bytes.
#[test]
fn messages_the_parser_would_panic_on_are_errors() {
    let mut header = b"ULog\x01\x12\x35".to_vec();
    header.extend([1u8]); // version
    header.extend(0u64.to_le_bytes()); // time stamp
    let mut bytes = header.clone();
    bytes.extend([1u8, 0, b'P', 200]); // size 1, key length 200
    let e = convert_bytes(&bytes, Path::new("p.ulg")).unwrap_err();
    assert!(
        matches!(&e, UlogError::Malformed { start: 16, end: 20, reason, .. } if reason.contains("key length")),
        "{e}"
    );
    let mut empty_param = header;
    empty_param.extend([0u8, 0, b'P']);
    assert!(matches!(
        convert_bytes(&empty_param, Path::new("p.ulg")).unwrap_err(),
        UlogError::Malformed { .. }
    ));
}

//! A PX4 flight ([`UlogTopics`]) as a `gnss-ins` log ([`GnssInsLog`]): frames, units
//! and time converted once.
//!
//! - time: microseconds since boot to seconds since boot (`t = us / 10^6`);
//! - IMU: `sensor_combined`, body FRD as fathom's body frame (forward, right, down);
//! - GNSS: `lat`, `lon` in 10^-7 deg (older logs) or `latitude_deg`, `longitude_deg`
//!   to rad; `alt` in mm or `altitude_msl_m` to m; `eph`, `epv` as the accuracies,
//!   `s_variance_m_s` as the speed accuracy; every fix is kept with its `fix_type`
//!   (the replay uses 3D fixes and better);
//! - baro: `baro_alt_meter`; magnetometer: gauss to tesla;
//! - EKF2's estimate: `vehicle_local_position` (valid `xy`, finite reference) back to
//!   latitude, longitude and altitude `ref_alt - z` by PX4's own projection
//!   ([`super::projection`]), with the attitude of the latest `vehicle_attitude` at
//!   or before the stamp (`q` to roll, pitch, heading, ZYX);
//! - truth: `vehicle_local_position_groundtruth` the same way.
//!
//! Rows with a non-finite value, and rows repeating the previous stamp, are dropped
//! and counted in [`Conversion::dropped`] (the layout needs strictly increasing time).

use super::error::UlogError;
use super::projection::reproject;
use super::topics::{
    BARO, EKF_ATTITUDE, EKF_POSITION, GPS, IMU, MAG, RANGE, SENSOR_GPS, TRUTH_POSITION,
    TopicSeries, UlogTopics,
};
use crate::layout::gnss_ins::{GnssInsLog, GnssRow, ImuRow, RangeRow, TrackRow};
use std::path::Path;

/// The converted log and what was dropped.
#[derive(Debug, Clone, PartialEq)]
pub struct Conversion {
    /// The log.
    pub log: GnssInsLog,
    /// `(topic, rows dropped)` for every topic that lost rows.
    pub dropped: Vec<(&'static str, usize)>,
    /// The GNSS topic used.
    pub gnss_topic: &'static str,
}

impl Conversion {
    /// The manifest's description of a log converted from the ULog `file`: its file
    /// name, the GNSS topic and what was dropped (the same text whether the log is
    /// written by `fathom log from-ulog` or replayed straight from the file).
    pub fn description(&self, file: &Path) -> String {
        let mut about = format!(
            "PX4 ULog `{}` converted by fathom (GNSS from `{}`)",
            file.file_name().unwrap_or_default().to_string_lossy(),
            self.gnss_topic
        );
        for (topic, n) in &self.dropped {
            about.push_str(&format!(
                "; {n} `{topic}` row(s) dropped (non-finite or a repeated stamp)"
            ));
        }
        about
    }
}

/// The largest time stamp accepted, microseconds (10^15: 31 years since boot).
const MAX_TIME_US: u64 = 1_000_000_000_000_000;

fn seconds(us: u64) -> f64 {
    us as f64 * 1e-6
}

/// Rows of `s` turned into `T` by `f` (None: dropped), with strictly increasing
/// stamps; returns the rows and the count dropped.
fn rows<T>(s: &TopicSeries, mut f: impl FnMut(f64, &[f64]) -> Option<T>) -> (Vec<T>, usize) {
    let mut out = Vec::with_capacity(s.len());
    let mut last: Option<u64> = None;
    for k in 0..s.len() {
        let us = s.time_us[k];
        if last == Some(us) {
            continue;
        }
        let row = s.row(k);
        if let Some(r) = f(seconds(us), row) {
            out.push(r);
            last = Some(us);
        }
    }
    let dropped = s.len() - out.len();
    (out, dropped)
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Roll, pitch, heading (ZYX) of the unit quaternion `w, x, y, z`.
fn euler(q: &[f64]) -> [f64; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    [
        (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y)),
        (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin(),
        (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z)),
    ]
}

/// A local-position topic (EKF2's or the truth's) as a geodetic track.
fn track(s: &TopicSeries, attitude: Option<&TopicSeries>) -> (Vec<TrackRow>, usize) {
    let mut a = 0usize;
    rows(s, |t, v| {
        // x, y, z, vx, vy, vz, ref_lat, ref_lon, ref_alt, xy_valid
        if !finite(&v[..9]) || v[9] == 0.0 {
            return None;
        }
        let euler = match attitude {
            None => None,
            Some(att) => {
                let us = (t * 1e6).round() as u64;
                while a + 1 < att.len() && att.time_us[a + 1] <= us {
                    a += 1;
                }
                if att.is_empty() || att.time_us[a] > us || !finite(att.row(a)) {
                    return None;
                }
                Some(euler(att.row(a)))
            }
        };
        let lat_lon = reproject([v[6].to_radians(), v[7].to_radians()], v[0], v[1]);
        Some(TrackRow {
            time: t,
            lat_lon,
            altitude: v[8] - v[2],
            vel_in_nav: [v[3], v[4], v[5]],
            euler,
        })
    })
}

/// The flight as a `gnss-ins` log (module docs); `path` labels errors.
///
/// # Errors
/// [`UlogError::TopicMissing`] without `sensor_combined` or a GNSS topic,
/// [`UlogError::Unusable`] when no GNSS row has a 3D fix, fewer than two IMU rows are
/// usable, or a stamp is beyond 10^9 s.
pub fn gnss_ins_from_ulog(topics: &UlogTopics, path: &Path) -> Result<Conversion, UlogError> {
    let missing = |topic: &str, why: &str| UlogError::TopicMissing {
        path: path.to_path_buf(),
        topic: topic.into(),
        why: why.into(),
    };
    let unusable = |reason: String| UlogError::Unusable {
        path: path.to_path_buf(),
        reason,
    };
    let s = &topics.series;
    if let Some(last) = s.iter().filter_map(|t| t.time_us.last()).max()
        && *last > MAX_TIME_US
    {
        return Err(unusable(format!(
            "a time stamp of {last} us is beyond 10^9 s since boot"
        )));
    }
    if s[IMU].is_empty() {
        return Err(missing(
            "sensor_combined",
            "the IMU output the INS integrates",
        ));
    }
    let (gnss_idx, gnss_topic) = if !s[GPS].is_empty() {
        (GPS, "vehicle_gps_position")
    } else if !s[SENSOR_GPS].is_empty() {
        (SENSOR_GPS, "sensor_gps")
    } else {
        return Err(missing(
            "vehicle_gps_position` or `sensor_gps",
            "the GNSS fixes GPS/INS needs (a log without GPS cannot be replayed as gnss-ins)",
        ));
    };
    let mut dropped = Vec::new();
    let mut note = |topic: &'static str, n: usize| {
        if n > 0 {
            dropped.push((topic, n));
        }
    };
    let (imu, n) = rows(&s[IMU], |t, v| {
        finite(v).then(|| ImuRow {
            time: t,
            gyro_in_body: [v[0], v[1], v[2]],
            accel_in_body: [v[3], v[4], v[5]],
        })
    });
    note("sensor_combined", n);
    if imu.len() < 2 {
        return Err(unusable(format!(
            "`sensor_combined` has {} usable rows, fewer than two",
            imu.len()
        )));
    }
    let (gnss, n) = rows(&s[gnss_idx], |t, v| {
        // lat, latitude_deg, lon, longitude_deg, alt, altitude_msl_m, eph, epv,
        // vel_n, vel_e, vel_d, s_variance, fix_type, satellites
        let lat = if v[1].is_finite() { v[1] } else { v[0] * 1e-7 };
        let lon = if v[3].is_finite() { v[3] } else { v[2] * 1e-7 };
        let alt = if v[5].is_finite() { v[5] } else { v[4] * 1e-3 };
        let row = GnssRow {
            time: t,
            lat_lon: [lat.to_radians(), lon.to_radians()],
            altitude: alt,
            h_acc: v[6],
            v_acc: v[7],
            vel_in_nav: [v[8], v[9], v[10]],
            speed_acc: v[11],
            fix_type: v[12] as u32,
            satellites: v[13] as u32,
        };
        let ok = finite(&[lat, lon, alt])
            && finite(&v[6..14])
            && lat.abs() < 90.0
            && row.h_acc >= 0.0
            && row.v_acc >= 0.0
            && row.speed_acc >= 0.0;
        ok.then_some(row)
    });
    note(gnss_topic, n);
    if !gnss.iter().any(|g| g.fix_type >= 3) {
        return Err(unusable(format!(
            "`{gnss_topic}` has {} messages but no 3D fix (fix_type >= 3): nothing to aid the INS with",
            s[gnss_idx].len()
        )));
    }
    let baro = (!s[BARO].is_empty()).then(|| {
        let (r, n) = rows(&s[BARO], |t, v| finite(v).then_some((t, v[0])));
        note("vehicle_air_data", n);
        r
    });
    let mag = (!s[MAG].is_empty()).then(|| {
        let (r, n) = rows(&s[MAG], |t, v| {
            finite(v).then_some((t, [v[0] * 1e-4, v[1] * 1e-4, v[2] * 1e-4]))
        });
        note("vehicle_magnetometer", n);
        r
    });
    let range = (!s[RANGE].is_empty()).then(|| {
        let (r, n) = rows(&s[RANGE], |t, v| {
            (finite(v) && v[0] >= 0.0).then_some(RangeRow {
                time: t,
                distance: v[0],
                orientation: v[1] as u32,
                beam_in_body: None,
            })
        });
        note("distance_sensor", n);
        r
    });
    let reference = (!s[EKF_POSITION].is_empty()).then(|| {
        let (r, n) = track(&s[EKF_POSITION], Some(&s[EKF_ATTITUDE]));
        note("vehicle_local_position", n);
        r
    });
    let truth = (!s[TRUTH_POSITION].is_empty()).then(|| {
        let (r, n) = track(&s[TRUTH_POSITION], None);
        note("vehicle_local_position_groundtruth", n);
        r
    });
    let nonempty = |v: Option<Vec<TrackRow>>| v.filter(|r| !r.is_empty());
    Ok(Conversion {
        log: GnssInsLog {
            imu,
            gnss,
            baro: baro.filter(|r| !r.is_empty()),
            mag: mag.filter(|r| !r.is_empty()),
            range: range.filter(|r| !r.is_empty()),
            reference: nonempty(reference),
            truth: nonempty(truth),
        },
        dropped,
        gnss_topic,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quaternion_to_euler() {
        let h = 0.7f64;
        let q = [(h / 2.0).cos(), 0.0, 0.0, (h / 2.0).sin()];
        let e = euler(&q);
        assert!(e[0].abs() < 1e-15 && e[1].abs() < 1e-15 && (e[2] - h).abs() < 1e-15);
        let p = 0.3f64;
        let e = euler(&[(p / 2.0).cos(), 0.0, (p / 2.0).sin(), 0.0]);
        assert!((e[1] - p).abs() < 1e-15);
    }
}

//! The `gnss-ins` kind of the own-data layout: a drone's flight for GNSS / INS
//! navigation, one file per sensor (columns and units in `docs/own-data.md`), what
//! `fathom log from-ulog` writes from a PX4 ULog.
//!
//! | file | columns | |
//! | --- | --- | --- |
//! | `imu.csv` | `time[s], gyro_x[rad/s], gyro_y, gyro_z, accel_x[m/s^2], accel_y, accel_z` | mean rates over (previous row, this row], body forward-right-down (required) |
//! | `gnss.csv` | `time[s], latitude[rad], longitude[rad], altitude[m], h_acc[m], v_acc[m], vel_north[m/s], vel_east, vel_down, speed_acc[m/s], fix_type, satellites` | receiver fixes and accuracy (required) |
//! | `baro.csv` | `time[s], altitude[m]` | barometric altitude (optional) |
//! | `mag.csv` | `time[s], mag_x[T], mag_y[T], mag_z[T]` | magnetometer, body axes (optional) |
//! | `range.csv` | `time[s], distance[m], orientation, (beam_x, beam_y, beam_z)` | distance sensors or scan beams: PX4 orientation code, or the beam's direction in body axes (optional) |
//! | `reference.csv` | `time[s], latitude[rad], longitude[rad], altitude[m], vel_north[m/s], vel_east, vel_down, roll[rad], pitch[rad], heading[rad]` | the autopilot's estimate (optional) |
//! | `truth.csv` | `time[s], latitude[rad], longitude[rad], altitude[m], vel_north[m/s], vel_east, vel_down` | ground truth (optional) |

pub use super::specs::gnss_ins::{BARO, GNSS, IMU, MAG, RANGE, REFERENCE, SPECS, TRUTH};
use super::{FileSet, LogError, LogKind, Table, csv_text, series_text};

/// An IMU row: time, mean angular rate and mean specific force over
/// (previous row, this row], body FRD, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuRow {
    /// Time, s.
    pub time: f64,
    /// Angular rate, rad/s.
    pub gyro_in_body: [f64; 3],
    /// Specific force, m/s^2.
    pub accel_in_body: [f64; 3],
}

/// A GNSS fix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GnssRow {
    /// Time, s.
    pub time: f64,
    /// Latitude, longitude, rad.
    pub lat_lon: [f64; 2],
    /// Altitude (up), m.
    pub altitude: f64,
    /// Horizontal and vertical accuracy (1 sigma as the receiver states it), m.
    pub h_acc: f64,
    /// Vertical accuracy, m.
    pub v_acc: f64,
    /// NED velocity, m/s.
    pub vel_in_nav: [f64; 3],
    /// Speed accuracy, m/s.
    pub speed_acc: f64,
    /// Fix type (PX4: 0-1 none, 2 2D, 3 3D, 4 DGPS, 5 RTK float, 6 RTK fixed).
    pub fix_type: u32,
    /// Satellites used.
    pub satellites: u32,
}

/// One range reading: a distance sensor's sample or one beam of a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeRow {
    /// Time, s.
    pub time: f64,
    /// Measured distance, m.
    pub distance: f64,
    /// PX4's orientation code (`distance_sensor.orientation`: 0 forward, 2 right,
    /// 4 / 12 backward, 6 left, 24 upward, 25 downward, 100 custom).
    pub orientation: u32,
    /// The beam's direction in body axes (forward-right-down) when the file gives it
    /// (`beam_x, beam_y, beam_z`; need not be unit).
    pub beam_in_body: Option<[f64; 3]>,
}

impl RangeRow {
    /// The beam's direction in body axes: the file's `beam_*` columns, else the
    /// direction of the orientation code (`None` for a code without a fixed
    /// direction, e.g. 100 custom, or a zero beam).
    pub fn dir_in_body(&self) -> Option<[f64; 3]> {
        if let Some(b) = self.beam_in_body {
            let n = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
            return (n > 0.0 && n.is_finite()).then_some(b);
        }
        match self.orientation {
            0 => Some([1.0, 0.0, 0.0]),
            2 => Some([0.0, 1.0, 0.0]),
            4 | 12 => Some([-1.0, 0.0, 0.0]),
            6 => Some([0.0, -1.0, 0.0]),
            24 => Some([0.0, 0.0, -1.0]),
            25 => Some([0.0, 0.0, 1.0]),
            _ => None,
        }
    }
}

/// A pose of a track (the autopilot's estimate or the truth).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackRow {
    /// Time, s.
    pub time: f64,
    /// Latitude, longitude, rad.
    pub lat_lon: [f64; 2],
    /// Altitude (up), m.
    pub altitude: f64,
    /// NED velocity, m/s.
    pub vel_in_nav: [f64; 3],
    /// Roll, pitch, heading (ZYX), rad, when the track has attitude.
    pub euler: Option<[f64; 3]>,
}

/// A `gnss-ins` log, every value in SI.
#[derive(Debug, Clone, PartialEq)]
pub struct GnssInsLog {
    /// The IMU rows.
    pub imu: Vec<ImuRow>,
    /// The GNSS fixes.
    pub gnss: Vec<GnssRow>,
    /// Barometric altitude `(time, m)`.
    pub baro: Option<Vec<(f64, f64)>>,
    /// Magnetometer `(time, [x, y, z] T)`.
    pub mag: Option<Vec<(f64, [f64; 3])>>,
    /// Distance sensors and scan beams.
    pub range: Option<Vec<RangeRow>>,
    /// The autopilot's estimate.
    pub reference: Option<Vec<TrackRow>>,
    /// Ground truth.
    pub truth: Option<Vec<TrackRow>>,
}

fn track(t: &Table, attitude: bool) -> Vec<TrackRow> {
    (0..t.len())
        .map(|k| TrackRow {
            time: t.column("time")[k],
            lat_lon: [t.column("latitude")[k], t.column("longitude")[k]],
            altitude: t.column("altitude")[k],
            vel_in_nav: t.triple(k, ["vel_north", "vel_east", "vel_down"]),
            euler: attitude.then(|| t.triple(k, ["roll", "pitch", "heading"])),
        })
        .collect()
}

/// The rows of `range.csv`: the beam columns all three or none.
fn range_rows(t: &Table, path: std::path::PathBuf) -> Result<Vec<RangeRow>, LogError> {
    let beams = ["beam_x", "beam_y", "beam_z"];
    let present: Vec<bool> = beams.iter().map(|b| t.has(b)).collect();
    if present.iter().any(|p| *p) && !present.iter().all(|p| *p) {
        return Err(LogError::Inconsistent {
            path,
            reason: "the columns beam_x, beam_y, beam_z go together (give all three or none)"
                .into(),
        });
    }
    Ok((0..t.len())
        .map(|k| RangeRow {
            time: t.column("time")[k],
            distance: t.column("distance")[k],
            orientation: count(t.column("orientation")[k]),
            beam_in_body: present[0].then(|| t.triple(k, beams)),
        })
        .collect())
}

fn count(x: f64) -> u32 {
    // checked whole and below 10^15 by the table; counts above u32 saturate
    x.clamp(0.0, f64::from(u32::MAX)) as u32
}

impl GnssInsLog {
    /// Parses the files of `set` (a `gnss-ins` log) and checks that they fit together.
    ///
    /// # Errors
    /// [`LogError`] naming file, line and column: every error of [`super::parse_table`],
    /// a missing `imu.csv` or `gnss.csv`, an `imu.csv` with fewer than two rows.
    pub fn parse(set: &FileSet) -> Result<Self, LogError> {
        set.expect_kind(LogKind::GnssIns)?;
        let imu_t = set.required(&IMU, "the IMU output")?;
        if imu_t.len() < 2 {
            return Err(LogError::Inconsistent {
                path: set.path(IMU.file),
                reason: format!("needs at least two rows, found {}", imu_t.len()),
            });
        }
        let imu = (0..imu_t.len())
            .map(|k| ImuRow {
                time: imu_t.column("time")[k],
                gyro_in_body: imu_t.triple(k, ["gyro_x", "gyro_y", "gyro_z"]),
                accel_in_body: imu_t.triple(k, ["accel_x", "accel_y", "accel_z"]),
            })
            .collect();
        let g = set.required(&GNSS, "the GNSS fixes")?;
        let gnss = (0..g.len())
            .map(|k| GnssRow {
                time: g.column("time")[k],
                lat_lon: [g.column("latitude")[k], g.column("longitude")[k]],
                altitude: g.column("altitude")[k],
                h_acc: g.column("h_acc")[k],
                v_acc: g.column("v_acc")[k],
                vel_in_nav: g.triple(k, ["vel_north", "vel_east", "vel_down"]),
                speed_acc: g.column("speed_acc")[k],
                fix_type: count(g.column("fix_type")[k]),
                satellites: count(g.column("satellites")[k]),
            })
            .collect();
        Ok(Self {
            imu,
            gnss,
            baro: set.table(&BARO)?.map(|t| t.series("altitude")),
            mag: set.table(&MAG)?.map(|t| {
                (0..t.len())
                    .map(|k| {
                        (
                            t.column("time")[k],
                            t.triple(k, ["mag_x", "mag_y", "mag_z"]),
                        )
                    })
                    .collect()
            }),
            range: set
                .table(&RANGE)?
                .map(|t| range_rows(&t, set.path(RANGE.file)))
                .transpose()?,
            reference: set.table(&REFERENCE)?.map(|t| track(&t, true)),
            truth: set.table(&TRUTH)?.map(|t| track(&t, false)),
        })
    }

    /// Reads and parses the log in `dir`.
    ///
    /// # Errors
    /// As [`FileSet::read_dir`] and [`GnssInsLog::parse`].
    pub fn read_dir(dir: impl AsRef<std::path::Path>) -> Result<Self, LogError> {
        Self::parse(&FileSet::read_dir(dir)?)
    }

    /// The log's files as CSV texts in SI units (what [`super::write_log`] writes).
    pub fn to_files(&self) -> Vec<(&'static str, String)> {
        let mut out = vec![
            (
                IMU.file,
                csv_text(
                    &[
                        "time[s]",
                        "gyro_x[rad/s]",
                        "gyro_y[rad/s]",
                        "gyro_z[rad/s]",
                        "accel_x[m/s^2]",
                        "accel_y[m/s^2]",
                        "accel_z[m/s^2]",
                    ],
                    self.imu.iter().map(|r| {
                        let (g, a) = (r.gyro_in_body, r.accel_in_body);
                        vec![r.time, g[0], g[1], g[2], a[0], a[1], a[2]]
                    }),
                ),
            ),
            (
                GNSS.file,
                csv_text(
                    &[
                        "time[s]",
                        "latitude[rad]",
                        "longitude[rad]",
                        "altitude[m]",
                        "h_acc[m]",
                        "v_acc[m]",
                        "vel_north[m/s]",
                        "vel_east[m/s]",
                        "vel_down[m/s]",
                        "speed_acc[m/s]",
                        "fix_type",
                        "satellites",
                    ],
                    self.gnss.iter().map(|r| {
                        let v = r.vel_in_nav;
                        vec![
                            r.time,
                            r.lat_lon[0],
                            r.lat_lon[1],
                            r.altitude,
                            r.h_acc,
                            r.v_acc,
                            v[0],
                            v[1],
                            v[2],
                            r.speed_acc,
                            f64::from(r.fix_type),
                            f64::from(r.satellites),
                        ]
                    }),
                ),
            ),
        ];
        if let Some(b) = &self.baro {
            out.push((BARO.file, series_text("altitude[m]", b)));
        }
        if let Some(m) = &self.mag {
            out.push((
                MAG.file,
                csv_text(
                    &["time[s]", "mag_x[T]", "mag_y[T]", "mag_z[T]"],
                    m.iter().map(|(t, v)| vec![*t, v[0], v[1], v[2]]),
                ),
            ));
        }
        if let Some(r) = &self.range {
            let beams = r.iter().any(|b| b.beam_in_body.is_some());
            let mut header = vec!["time[s]", "distance[m]", "orientation"];
            if beams {
                header.extend(["beam_x", "beam_y", "beam_z"]);
            }
            out.push((
                RANGE.file,
                csv_text(
                    &header,
                    r.iter().map(|b| {
                        let mut row = vec![b.time, b.distance, f64::from(b.orientation)];
                        if beams {
                            row.extend(
                                b.beam_in_body
                                    .or_else(|| b.dir_in_body())
                                    .unwrap_or([0.0; 3]),
                            );
                        }
                        row
                    }),
                ),
            ));
        }
        for (spec, rows, attitude) in [
            (REFERENCE, &self.reference, true),
            (TRUTH, &self.truth, false),
        ] {
            let Some(rows) = rows else { continue };
            let mut header = vec![
                "time[s]",
                "latitude[rad]",
                "longitude[rad]",
                "altitude[m]",
                "vel_north[m/s]",
                "vel_east[m/s]",
                "vel_down[m/s]",
            ];
            if attitude {
                header.extend(["roll[rad]", "pitch[rad]", "heading[rad]"]);
            }
            out.push((
                spec.file,
                csv_text(
                    &header,
                    rows.iter().map(|r| {
                        let v = r.vel_in_nav;
                        let mut row = vec![r.time, r.lat_lon[0], r.lat_lon[1], r.altitude];
                        row.extend(v);
                        if attitude {
                            row.extend(r.euler.unwrap_or([0.0; 3]));
                        }
                        row
                    }),
                ),
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(files: &[(&'static str, &str)]) -> FileSet {
        super::super::tests::file_set(LogKind::GnssIns, files)
    }

    const IMU_CSV: &str = "time[s],gyro_x[deg/s],gyro_y[rad/s],gyro_z[rad/s],accel_x[m/s^2],accel_y[m/s^2],accel_z[g]\n1,1,0,0,0,0,-1\n1.005,0,0,0,0,0,-1\n";
    const GNSS_CSV: &str = "time[s],latitude[deg],longitude[deg],altitude[m],h_acc[m],v_acc[m],vel_north[m/s],vel_east[m/s],vel_down[m/s],speed_acc[m/s],fix_type,satellites\n1.1,47.3,8.5,420,0.5,0.8,0,0,0,0.3,3,12\n";

    #[test]
    fn a_log_parses_into_si_and_round_trips() {
        let files = [
            ("imu.csv", IMU_CSV),
            ("gnss.csv", GNSS_CSV),
            (
                "mag.csv",
                "time[s],mag_x[G],mag_y[G],mag_z[G]\n1,0.2,0,0.4\n",
            ),
            (
                "reference.csv",
                "time[s],latitude[deg],longitude[deg],altitude[m],vel_north[m/s],vel_east[m/s],vel_down[m/s],roll[rad],pitch[rad],heading[deg]\n1,47.3,8.5,420,0,0,0,0,0,90\n",
            ),
        ];
        let log = GnssInsLog::parse(&set(&files)).unwrap();
        assert!((log.imu[0].gyro_in_body[0] - 1f64.to_radians()).abs() < 1e-15);
        assert_eq!(log.imu[1].accel_in_body[2], -9.806_65);
        assert!((log.gnss[0].lat_lon[0] - 47.3f64.to_radians()).abs() < 1e-15);
        assert_eq!((log.gnss[0].fix_type, log.gnss[0].satellites), (3, 12));
        assert!((log.mag.as_ref().unwrap()[0].1[2] - 4e-5).abs() < 1e-18);
        assert!(log.truth.is_none() && log.baro.is_none());
        let files2 = log.to_files();
        let back: Vec<(&'static str, &str)> =
            files2.iter().map(|(n, t)| (*n, t.as_str())).collect();
        assert_eq!(GnssInsLog::parse(&set(&back)).unwrap(), log);
    }

    #[test]
    fn bad_logs_name_the_file_and_cell() {
        let e = |files: &[(&'static str, &str)]| {
            GnssInsLog::parse(&set(files)).unwrap_err().to_string()
        };
        assert!(e(&[("imu.csv", IMU_CSV)]).contains("gnss.csv`: missing"));
        let bad_fix = GNSS_CSV.replace(",3,12", ",3.5,12");
        let msg = e(&[("imu.csv", IMU_CSV), ("gnss.csv", &bad_fix)]);
        assert!(msg.contains("column 11 (`fix_type`)"), "{msg}");
        let one = "time[s],gyro_x[rad/s],gyro_y[rad/s],gyro_z[rad/s],accel_x[m/s^2],accel_y[m/s^2],accel_z[m/s^2]\n1,0,0,0,0,0,0\n";
        assert!(e(&[("imu.csv", one), ("gnss.csv", GNSS_CSV)]).contains("at least two rows"));
        let neg_acc = GNSS_CSV.replace(",0.5,0.8,", ",-0.5,0.8,");
        assert!(e(&[("imu.csv", IMU_CSV), ("gnss.csv", &neg_acc)]).contains("`h_acc[m]`"));
    }

    /// Scan beams: several rows per stamp, the beam columns all three or none, the
    /// orientation codes' directions, and the round trip.
    #[test]
    fn range_beams_parse_and_the_beam_columns_go_together() {
        let ranges = "time[s],distance[m],orientation,beam_x,beam_y,beam_z\n1,5,100,1,0,0\n1,7,100,0,0.6,0.8\n1.2,6,100,1,0,0\n";
        let files = [
            ("imu.csv", IMU_CSV),
            ("gnss.csv", GNSS_CSV),
            ("range.csv", ranges),
        ];
        let log = GnssInsLog::parse(&set(&files)).unwrap();
        let r = log.range.as_ref().unwrap();
        assert_eq!(r.len(), 3);
        assert_eq!(r[1].dir_in_body(), Some([0.0, 0.6, 0.8]));
        let files2 = log.to_files();
        let back: Vec<(&'static str, &str)> =
            files2.iter().map(|(n, t)| (*n, t.as_str())).collect();
        assert_eq!(GnssInsLog::parse(&set(&back)).unwrap(), log);
        let two = "time[s],distance[m],orientation,beam_x,beam_y\n1,5,100,1,0\n";
        let files = [
            ("imu.csv", IMU_CSV),
            ("gnss.csv", GNSS_CSV),
            ("range.csv", two),
        ];
        let e = GnssInsLog::parse(&set(&files)).unwrap_err().to_string();
        assert!(e.contains("range.csv") && e.contains("go together"), "{e}");
        let down = RangeRow {
            time: 0.0,
            distance: 1.0,
            orientation: 25,
            beam_in_body: None,
        };
        assert_eq!(down.dir_in_body(), Some([0.0, 0.0, 1.0]));
        let custom = RangeRow {
            orientation: 100,
            ..down
        };
        assert_eq!(custom.dir_in_body(), None);
        let zero = RangeRow {
            beam_in_body: Some([0.0; 3]),
            ..down
        };
        assert_eq!(zero.dir_in_body(), None);
    }
}

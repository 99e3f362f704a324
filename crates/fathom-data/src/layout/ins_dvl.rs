//! The `ins-dvl` kind of the own-data layout: what INS / DVL navigation needs, one
//! file per sensor (columns and units in `docs/own-data.md`).
//!
//! | file | columns | |
//! | --- | --- | --- |
//! | `initial.csv` | `time[s], latitude[deg], longitude[deg], depth[m], vel_north[m/s], vel_east[m/s], vel_down[m/s], roll[rad], pitch[rad], heading[rad]` | one row: the INS start (required) |
//! | `imu.csv` | `time[s], dtheta_x[rad], dtheta_y, dtheta_z, dv_x[m/s], dv_y, dv_z` or `time[s], gyro_x[rad/s], .., accel_x[m/s^2], ..` | body-frame increments (or mean rates) over (previous row, this row] (required) |
//! | `dvl.csv` | `time[s], u[m/s], v[m/s], w[m/s], (bottom_lock)` | DVL body velocity, optional 0/1 bottom-lock flag (required) |
//! | `depth.csv` | `time[s], depth[m]` | depth gauge (optional) |
//! | `altitude.csv` | `time[s], altitude[m]` | echo sounder: altitude above the seabed (optional) |
//! | `rpm.csv` | `time[s], rpm[rpm]` | propeller speed (optional; the VKF needs it) |
//! | `truth.csv` | `time[s], north[m], east[m], depth[m], (vel_north[m/s], vel_east[m/s], vel_down[m/s])` | ground truth: north and east from the start position, depth (optional) |

pub use super::DEPTH;
pub use super::specs::ins_dvl::{ALTITUDE, DVL, IMU, INITIAL, RPM, SPECS, TRUTH};
use super::specs::ins_dvl::{INCREMENTS, RATES};
use super::{FileSet, LogError, LogKind, single_row};

/// The INS start.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InsStart {
    /// Time, s: IMU rows at or before it are skipped.
    pub time: f64,
    /// Latitude, longitude, rad.
    pub lat_lon: [f64; 2],
    /// Depth, m (down positive).
    pub depth: f64,
    /// NED velocity, m/s.
    pub vel_in_nav: [f64; 3],
    /// Roll, pitch, heading (ZYX), rad.
    pub euler: [f64; 3],
}

/// How `imu.csv` gives the IMU output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ImuForm {
    /// Angle and velocity increments over each row's interval.
    Increments,
    /// Mean angular rate and specific force over each row's interval.
    Rates,
}

/// An IMU row: `(time, [x, y, z] angle part, [x, y, z] velocity part)` in the form
/// of [`InsDvlLog::imu_form`], SI.
pub type ImuRow = (f64, [f64; 3], [f64; 3]);

/// A DVL row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DvlRow {
    /// Time, s.
    pub time: f64,
    /// Body velocity `[u, v, w]`, m/s.
    pub vel_in_body: [f64; 3],
    /// Bottom lock, when the file has the flag.
    pub bottom_lock: Option<bool>,
}

/// A ground-truth row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsTruthRow {
    /// Time, s.
    pub time: f64,
    /// North and east from the start position (curvilinear, local NED), and depth, m.
    pub pos_in_nav: [f64; 3],
    /// NED velocity, m/s, when the file has it.
    pub vel_in_nav: Option<[f64; 3]>,
}

/// An `ins-dvl` log, every value in SI.
#[derive(Debug, Clone, PartialEq)]
pub struct InsDvlLog {
    /// The INS start.
    pub start: InsStart,
    /// How the IMU rows are given.
    pub imu_form: ImuForm,
    /// The IMU rows.
    pub imu: Vec<ImuRow>,
    /// The DVL rows.
    pub dvl: Vec<DvlRow>,
    /// Depth `(time, m)`.
    pub depth: Option<Vec<(f64, f64)>>,
    /// Echo-sounder altitude `(time, m)`.
    pub altitude: Option<Vec<(f64, f64)>>,
    /// Propeller speed `(time, rpm)`.
    pub rpm: Option<Vec<(f64, f64)>>,
    /// Ground truth.
    pub truth: Option<Vec<InsTruthRow>>,
}

impl InsDvlLog {
    /// Parses the files of `set` (an `ins-dvl` log) and checks that they fit together.
    ///
    /// # Errors
    /// [`LogError`] naming file, line and column: every error of [`super::parse_table`],
    /// a missing `initial.csv`, `imu.csv` or `dvl.csv`, an `initial.csv` without exactly
    /// one row, an `imu.csv` with fewer than two rows after the start, truth velocity
    /// columns that are not all three present.
    pub fn parse(set: &FileSet) -> Result<Self, LogError> {
        set.expect_kind(LogKind::InsDvl)?;
        let init = set.required(
            &INITIAL,
            "the INS start (time, position, velocity, attitude)",
        )?;
        single_row(&init, &set.path(INITIAL.file))?;
        let start = InsStart {
            time: init.column("time")[0],
            lat_lon: [init.column("latitude")[0], init.column("longitude")[0]],
            depth: init.column("depth")[0],
            vel_in_nav: init.triple(0, ["vel_north", "vel_east", "vel_down"]),
            euler: init.triple(0, ["roll", "pitch", "heading"]),
        };
        let imu_t = set.required(&IMU, "the IMU output")?;
        let imu_form = if imu_t.has("dtheta_x") {
            ImuForm::Increments
        } else {
            ImuForm::Rates
        };
        let cols = match imu_form {
            ImuForm::Increments => INCREMENTS,
            ImuForm::Rates => RATES,
        };
        let imu: Vec<ImuRow> = (0..imu_t.len())
            .map(|k| {
                (
                    imu_t.column("time")[k],
                    imu_t.triple(k, [cols[0], cols[1], cols[2]]),
                    imu_t.triple(k, [cols[3], cols[4], cols[5]]),
                )
            })
            .collect();
        let after = imu.iter().filter(|r| r.0 > start.time).count();
        if after < 2 {
            return Err(LogError::Inconsistent {
                path: set.path(IMU.file),
                reason: format!(
                    "needs at least two rows after the start time {} s of `initial.csv`, found {after}",
                    start.time
                ),
            });
        }
        let dvl_t = set.required(&DVL, "the DVL velocity")?;
        let lock = dvl_t.optional("bottom_lock");
        let dvl = (0..dvl_t.len())
            .map(|k| DvlRow {
                time: dvl_t.column("time")[k],
                vel_in_body: dvl_t.triple(k, ["u", "v", "w"]),
                bottom_lock: lock.map(|l| l[k] == 1.0),
            })
            .collect();
        let truth = match set.table(&TRUTH)? {
            None => None,
            Some(t) => {
                let vel = ["vel_north", "vel_east", "vel_down"];
                let n = vel.iter().filter(|c| t.has(c)).count();
                if n != 0 && n != 3 {
                    return Err(LogError::Inconsistent {
                        path: set.path(TRUTH.file),
                        reason: "has some of the velocity columns vel_north, vel_east, vel_down: \
                                 give all three or none"
                            .into(),
                    });
                }
                Some(
                    (0..t.len())
                        .map(|k| InsTruthRow {
                            time: t.column("time")[k],
                            pos_in_nav: t.triple(k, ["north", "east", "depth"]),
                            vel_in_nav: (n == 3).then(|| t.triple(k, vel)),
                        })
                        .collect(),
                )
            }
        };
        Ok(Self {
            start,
            imu_form,
            imu,
            dvl,
            depth: set.table(&DEPTH)?.map(|t| t.series("depth")),
            altitude: set.table(&ALTITUDE)?.map(|t| t.series("altitude")),
            rpm: set.table(&RPM)?.map(|t| t.series("rpm")),
            truth,
        })
    }

    /// Reads and parses the log in `dir`.
    ///
    /// # Errors
    /// As [`FileSet::read_dir`] and [`InsDvlLog::parse`].
    pub fn read_dir(dir: impl AsRef<std::path::Path>) -> Result<Self, LogError> {
        Self::parse(&FileSet::read_dir(dir)?)
    }

    /// The log's files as CSV texts in SI units (what [`super::write_log`] writes).
    pub fn to_files(&self) -> Vec<(&'static str, String)> {
        use super::{csv_text, series_text};
        let s = &self.start;
        let mut out = vec![(
            INITIAL.file,
            csv_text(
                &[
                    "time[s]",
                    "latitude[rad]",
                    "longitude[rad]",
                    "depth[m]",
                    "vel_north[m/s]",
                    "vel_east[m/s]",
                    "vel_down[m/s]",
                    "roll[rad]",
                    "pitch[rad]",
                    "heading[rad]",
                ],
                [vec![
                    s.time,
                    s.lat_lon[0],
                    s.lat_lon[1],
                    s.depth,
                    s.vel_in_nav[0],
                    s.vel_in_nav[1],
                    s.vel_in_nav[2],
                    s.euler[0],
                    s.euler[1],
                    s.euler[2],
                ]],
            ),
        )];
        let imu_header: &[&str] = match self.imu_form {
            ImuForm::Increments => &[
                "time[s]",
                "dtheta_x[rad]",
                "dtheta_y[rad]",
                "dtheta_z[rad]",
                "dv_x[m/s]",
                "dv_y[m/s]",
                "dv_z[m/s]",
            ],
            ImuForm::Rates => &[
                "time[s]",
                "gyro_x[rad/s]",
                "gyro_y[rad/s]",
                "gyro_z[rad/s]",
                "accel_x[m/s^2]",
                "accel_y[m/s^2]",
                "accel_z[m/s^2]",
            ],
        };
        out.push((
            IMU.file,
            csv_text(
                imu_header,
                self.imu
                    .iter()
                    .map(|r| vec![r.0, r.1[0], r.1[1], r.1[2], r.2[0], r.2[1], r.2[2]]),
            ),
        ));
        let lock = self.dvl.first().is_some_and(|d| d.bottom_lock.is_some());
        let mut dvl_header = vec!["time[s]", "u[m/s]", "v[m/s]", "w[m/s]"];
        if lock {
            dvl_header.push("bottom_lock");
        }
        out.push((
            DVL.file,
            csv_text(
                &dvl_header,
                self.dvl.iter().map(|d| {
                    let mut r = vec![d.time, d.vel_in_body[0], d.vel_in_body[1], d.vel_in_body[2]];
                    if lock {
                        r.push(f64::from(u8::from(d.bottom_lock == Some(true))));
                    }
                    r
                }),
            ),
        ));
        for (spec, header, rows) in [
            (DEPTH, "depth[m]", &self.depth),
            (ALTITUDE, "altitude[m]", &self.altitude),
            (RPM, "rpm[rpm]", &self.rpm),
        ] {
            if let Some(rows) = rows {
                out.push((spec.file, series_text(header, rows)));
            }
        }
        if let Some(truth) = &self.truth {
            let vel = truth.first().is_some_and(|r| r.vel_in_nav.is_some());
            let mut header = vec!["time[s]", "north[m]", "east[m]", "depth[m]"];
            if vel {
                header.extend(["vel_north[m/s]", "vel_east[m/s]", "vel_down[m/s]"]);
            }
            out.push((
                TRUTH.file,
                csv_text(
                    &header,
                    truth.iter().map(|r| {
                        let mut v = vec![r.time, r.pos_in_nav[0], r.pos_in_nav[1], r.pos_in_nav[2]];
                        if let (true, Some(u)) = (vel, r.vel_in_nav) {
                            v.extend(u);
                        }
                        v
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
        super::super::tests::file_set(LogKind::InsDvl, files)
    }

    const INIT: &str = "time[s],latitude[deg],longitude[deg],depth[m],vel_north[m/s],vel_east[m/s],vel_down[m/s],roll[deg],pitch[deg],heading[deg]\n0,35,129,50,1,0,0,0,0,90\n";

    #[test]
    fn rates_and_increments_parse_into_si() {
        let files = [
            ("initial.csv", INIT),
            (
                "imu.csv",
                "time[s],gyro_x[deg/s],gyro_y[deg/s],gyro_z[deg/h],accel_x[g],accel_y[m/s^2],accel_z[m/s^2]\n0.01,1,0,3600,0,0,-9.8\n0.02,1,0,3600,0,0,-9.8\n",
            ),
            (
                "dvl.csv",
                "time[s],u[m/s],v[m/s],w[m/s],bottom_lock\n0.2,1,0,0,1\n0.4,1,0,0,0\n",
            ),
            ("truth.csv", "time[s],north[m],east[m],depth[m]\n0,0,0,0\n"),
        ];
        let log = InsDvlLog::parse(&set(&files)).unwrap();
        assert_eq!(log.imu_form, ImuForm::Rates);
        assert!((log.start.lat_lon[0] - 35f64.to_radians()).abs() < 1e-15);
        assert!((log.imu[0].1[2] - 1f64.to_radians()).abs() < 1e-15);
        assert_eq!(log.dvl[1].bottom_lock, Some(false));
        assert!(log.rpm.is_none() && log.truth.is_some());
        let files2: Vec<(&'static str, String)> = log.to_files();
        let back: Vec<(&'static str, &str)> =
            files2.iter().map(|(n, t)| (*n, t.as_str())).collect();
        assert_eq!(InsDvlLog::parse(&set(&back)).unwrap(), log);
    }

    #[test]
    fn bad_logs_name_the_file() {
        let imu = "time[s],dtheta_x[rad],dtheta_y[rad],dtheta_z[rad],dv_x[m/s],dv_y[m/s],dv_z[m/s]\n0.01,0,0,0,0,0,0\n0.02,0,0,0,0,0,0\n";
        let dvl = "time[s],u[m/s],v[m/s],w[m/s]\n";
        let e =
            |files: &[(&'static str, &str)]| InsDvlLog::parse(&set(files)).unwrap_err().to_string();
        assert!(e(&[("imu.csv", imu), ("dvl.csv", dvl)]).contains("initial.csv`: missing"));
        let bad_lat = INIT.replace(",35,", ",90,");
        assert!(
            e(&[
                ("initial.csv", &bad_lat),
                ("imu.csv", imu),
                ("dvl.csv", dvl)
            ])
            .contains("line 2, column 2 (`latitude[deg]`): latitude 90 is not strictly between")
        );
        let short = "time[s],dtheta_x[rad],dtheta_y[rad],dtheta_z[rad],dv_x[m/s],dv_y[m/s],dv_z[m/s]\n0,0,0,0,0,0,0\n0.01,0,0,0,0,0,0\n";
        assert!(
            e(&[("initial.csv", INIT), ("imu.csv", short), ("dvl.csv", dvl)])
                .contains("needs at least two rows after the start time 0 s")
        );
        assert!(
            e(&[
                ("initial.csv", INIT),
                ("imu.csv", imu),
                (
                    "dvl.csv",
                    "time[s],u[m/s],v[m/s],w[m/s],bottom_lock\n1,0,0,0,2\n"
                )
            ])
            .contains("column 5 (`bottom_lock`): 2 is not 0 or 1")
        );
        assert!(
            e(&[
                ("initial.csv", INIT),
                ("imu.csv", imu),
                ("dvl.csv", dvl),
                (
                    "truth.csv",
                    "time[s],north[m],east[m],depth[m],vel_north[m/s]\n"
                )
            ])
            .contains("give all three or none")
        );
    }
}

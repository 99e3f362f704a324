//! The `range-beacon` kind of the own-data layout: what range-beacon localization
//! needs, one file per sensor (columns and units in `docs/own-data.md`).
//!
//! | file | columns | |
//! | --- | --- | --- |
//! | `beacons.csv` | `id, north[m], east[m], (down[m])` | the beacon table (required) |
//! | `initial.csv` | `time[s], north[m], east[m], (down[m]), heading[rad]` | one row: where and when the log starts (required) |
//! | `odometry.csv` | `time[s], distance[m], heading_change[rad]` | wheel odometry: increments over (previous row, this row] |
//! | `dvl.csv` + `heading.csv` | `time[s], u[m/s], v[m/s], w[m/s]` / `time[s], heading[rad]` | or: DVL body velocity and heading |
//! | `ranges.csv` | `time[s], beacon, range[m]` | ranges (required; may have no rows) |
//! | `depth.csv` | `time[s], depth[m]` | depth gauge (DVL motion only) |
//! | `truth.csv` | `time[s], north[m], east[m], (down[m]), (heading[rad])` | ground truth (optional) |
//!
//! Exactly one motion source: `odometry.csv` (2D: the ranges are horizontal
//! distances, the beacon table has no `down`, no depth file) or `dvl.csv` with
//! `heading.csv` (3D with depth).

use std::collections::BTreeMap;

pub use super::DEPTH;
pub use super::specs::range_beacon::{
    BEACONS, DVL, HEADING, INITIAL, ODOMETRY, RANGES, SPECS, TRUTH,
};
use super::{FileSet, LogError, LogKind, single_row};

/// A beacon of the table.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Beacon {
    /// Its id, as the range file uses it.
    pub id: i64,
    /// NED position, m (`down` 0 when the table has no `down` column).
    pub pos_in_nav: [f64; 3],
}

/// The start of the log.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Start {
    /// Time, s: rows at or before it are already in the start pose.
    pub time: f64,
    /// North, east, m.
    pub north_east: [f64; 2],
    /// Down, m (DVL motion; the 2D odometry motion has none).
    pub down: Option<f64>,
    /// Heading, rad, clockwise from north.
    pub heading: f64,
}

/// A sample `(time s, value SI)`.
pub type Sample = (f64, f64);

/// The motion source of the log.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// Wheel odometry `(time, distance m, heading change rad)`, increments over
    /// (previous row, this row].
    Odometry(Vec<(f64, f64, f64)>),
    /// DVL body velocity `(time, [u, v, w] m/s)` and heading `(time, rad)`.
    Dvl {
        /// The DVL rows.
        dvl: Vec<(f64, [f64; 3])>,
        /// The heading rows.
        heading: Vec<Sample>,
    },
}

/// A range row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeRow {
    /// Time, s.
    pub time: f64,
    /// Row of the beacon in [`RangeBeaconLog::beacons`].
    pub beacon: usize,
    /// Range, m.
    pub range: f64,
}

/// A ground-truth row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthRow {
    /// Time, s.
    pub time: f64,
    /// North, east, m.
    pub north_east: [f64; 2],
    /// Down, m, when the file has it.
    pub down: Option<f64>,
    /// Heading, rad, when the file has it.
    pub heading: Option<f64>,
}

/// A `range-beacon` log, every value in SI.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeBeaconLog {
    /// The beacon table, in file order (the filters' channels).
    pub beacons: Vec<Beacon>,
    /// Whether the beacon table has a `down` column.
    pub beacons_have_down: bool,
    /// The start.
    pub start: Start,
    /// The motion source.
    pub motion: Motion,
    /// The ranges, in file (time) order.
    pub ranges: Vec<RangeRow>,
    /// Depth `(time, m)`, if the log has a depth file.
    pub depth: Option<Vec<Sample>>,
    /// Ground truth, if the log has it.
    pub truth: Option<Vec<TruthRow>>,
}

impl RangeBeaconLog {
    /// Parses the files of `set` (a `range-beacon` log) and checks that they fit
    /// together (module docs).
    ///
    /// # Errors
    /// [`LogError`] naming file, line and column: every error of [`super::parse_table`],
    /// a missing file, two or no motion sources, a file the motion cannot use, an
    /// `initial.csv` without exactly one row, a duplicate beacon id, an unknown beacon
    /// id in `ranges.csv`.
    pub fn parse(set: &FileSet) -> Result<Self, LogError> {
        set.expect_kind(LogKind::RangeBeacon)?;
        let inconsistent = |file: &str, reason: String| LogError::Inconsistent {
            path: set.path(file),
            reason,
        };
        let beacons_t = set.required(&BEACONS, "the beacon table")?;
        let mut by_id: BTreeMap<i64, usize> = BTreeMap::new();
        let mut beacons = Vec::with_capacity(beacons_t.len());
        let has_down = beacons_t.has("down");
        for k in 0..beacons_t.len() {
            let id = beacons_t.column("id")[k] as i64;
            if by_id.insert(id, k).is_some() {
                return Err(LogError::Value {
                    path: set.path(BEACONS.file),
                    at: beacons_t.cell(k, "id"),
                    reason: format!("beacon id {id} is listed twice"),
                });
            }
            beacons.push(Beacon {
                id,
                pos_in_nav: [
                    beacons_t.column("north")[k],
                    beacons_t.column("east")[k],
                    beacons_t.optional("down").map_or(0.0, |d| d[k]),
                ],
            });
        }
        if beacons.is_empty() {
            return Err(inconsistent(BEACONS.file, "lists no beacon".into()));
        }

        let initial_t = set.required(&INITIAL, "the start of the log (time, position, heading)")?;
        single_row(&initial_t, &set.path(INITIAL.file))?;
        let start = Start {
            time: initial_t.column("time")[0],
            north_east: [initial_t.column("north")[0], initial_t.column("east")[0]],
            down: initial_t.optional("down").map(|d| d[0]),
            heading: initial_t.column("heading")[0],
        };

        let motion = match (
            set.has(ODOMETRY.file),
            set.has(DVL.file),
            set.has(HEADING.file),
        ) {
            (true, false, false) => {
                let t = set.required(&ODOMETRY, "odometry")?;
                Motion::Odometry(
                    (0..t.len())
                        .map(|k| {
                            (
                                t.column("time")[k],
                                t.column("distance")[k],
                                t.column("heading_change")[k],
                            )
                        })
                        .collect(),
                )
            }
            (false, true, true) => {
                let d = set.required(&DVL, "DVL velocity")?;
                let h = set.required(&HEADING, "heading")?;
                Motion::Dvl {
                    dvl: (0..d.len())
                        .map(|k| (d.column("time")[k], d.triple(k, ["u", "v", "w"])))
                        .collect(),
                    heading: h.series("heading"),
                }
            }
            (false, true, false) => {
                return Err(LogError::MissingFile {
                    path: set.path(HEADING.file),
                    why: "`dvl.csv` (body velocity) needs the heading to dead-reckon; its header: \
                          time[s], heading[rad]"
                        .into(),
                });
            }
            (false, false, true) => {
                return Err(LogError::MissingFile {
                    path: set.path(DVL.file),
                    why: "`heading.csv` needs the DVL body velocity to dead-reckon; its header: \
                          time[s], u[m/s], v[m/s], w[m/s]"
                        .into(),
                });
            }
            (false, false, false) => {
                return Err(LogError::MissingFile {
                    path: set.path(ODOMETRY.file),
                    why: "a motion source: `odometry.csv` (time[s], distance[m], heading_change[rad]) \
                          or `dvl.csv` + `heading.csv`"
                        .into(),
                });
            }
            (true, _, _) => {
                return Err(inconsistent(
                    ODOMETRY.file,
                    "two motion sources: a log has either `odometry.csv` or `dvl.csv` + `heading.csv`".into(),
                ));
            }
        };
        let odometry = matches!(motion, Motion::Odometry(_));
        if odometry && has_down {
            return Err(inconsistent(
                BEACONS.file,
                "has a `down` column, but the log's motion is 2D wheel odometry (its ranges are \
                 modelled as horizontal distances): remove the column, or log DVL + heading"
                    .into(),
            ));
        }
        if odometry && start.down.is_some() {
            return Err(inconsistent(
                INITIAL.file,
                "has a `down` column, but the log's motion is 2D wheel odometry".into(),
            ));
        }
        if !odometry && start.down.is_none() {
            return Err(inconsistent(
                INITIAL.file,
                "needs a `down[m]` column: the DVL motion is 3D".into(),
            ));
        }

        let ranges_t = set.required(&RANGES, "the ranges to the beacons")?;
        let mut ranges = Vec::with_capacity(ranges_t.len());
        for k in 0..ranges_t.len() {
            let id = ranges_t.column("beacon")[k] as i64;
            let Some(&beacon) = by_id.get(&id) else {
                return Err(LogError::UnknownBeacon {
                    path: set.path(RANGES.file),
                    at: ranges_t.cell(k, "beacon"),
                    id,
                    known: beacons.iter().map(|b| b.id).collect(),
                });
            };
            ranges.push(RangeRow {
                time: ranges_t.column("time")[k],
                beacon,
                range: ranges_t.column("range")[k],
            });
        }

        let depth = set.table(&DEPTH)?.map(|t| t.series("depth"));
        if odometry && depth.is_some() {
            return Err(inconsistent(
                DEPTH.file,
                "the log's motion is 2D wheel odometry, which has no depth; log DVL + heading for 3D"
                    .into(),
            ));
        }
        let truth = set.table(&TRUTH)?.map(|t| {
            (0..t.len())
                .map(|k| TruthRow {
                    time: t.column("time")[k],
                    north_east: [t.column("north")[k], t.column("east")[k]],
                    down: t.optional("down").map(|d| d[k]),
                    heading: t.optional("heading").map(|h| h[k]),
                })
                .collect::<Vec<_>>()
        });
        Ok(Self {
            beacons,
            beacons_have_down: has_down,
            start,
            motion,
            ranges,
            depth,
            truth,
        })
    }

    /// Reads and parses the log in `dir`.
    ///
    /// # Errors
    /// As [`FileSet::read_dir`] and [`RangeBeaconLog::parse`].
    pub fn read_dir(dir: impl AsRef<std::path::Path>) -> Result<Self, LogError> {
        Self::parse(&FileSet::read_dir(dir)?)
    }

    /// The log's files as CSV texts in SI units (what [`super::write_log`] writes).
    pub fn to_files(&self) -> Vec<(&'static str, String)> {
        use super::{csv_text, series_text};
        let mut out = Vec::new();
        let b_header: &[&str] = if self.beacons_have_down {
            &["id", "north[m]", "east[m]", "down[m]"]
        } else {
            &["id", "north[m]", "east[m]"]
        };
        out.push((
            BEACONS.file,
            csv_text(
                b_header,
                self.beacons.iter().map(|b| {
                    let mut r = vec![b.id as f64, b.pos_in_nav[0], b.pos_in_nav[1]];
                    if self.beacons_have_down {
                        r.push(b.pos_in_nav[2]);
                    }
                    r
                }),
            ),
        ));
        let s = &self.start;
        out.push((
            INITIAL.file,
            match s.down {
                Some(d) => csv_text(
                    &["time[s]", "north[m]", "east[m]", "down[m]", "heading[rad]"],
                    [vec![s.time, s.north_east[0], s.north_east[1], d, s.heading]],
                ),
                None => csv_text(
                    &["time[s]", "north[m]", "east[m]", "heading[rad]"],
                    [vec![s.time, s.north_east[0], s.north_east[1], s.heading]],
                ),
            },
        ));
        match &self.motion {
            Motion::Odometry(rows) => out.push((
                ODOMETRY.file,
                csv_text(
                    &["time[s]", "distance[m]", "heading_change[rad]"],
                    rows.iter().map(|r| vec![r.0, r.1, r.2]),
                ),
            )),
            Motion::Dvl { dvl, heading } => {
                out.push((
                    DVL.file,
                    csv_text(
                        &["time[s]", "u[m/s]", "v[m/s]", "w[m/s]"],
                        dvl.iter().map(|r| vec![r.0, r.1[0], r.1[1], r.1[2]]),
                    ),
                ));
                out.push((HEADING.file, series_text("heading[rad]", heading)));
            }
        }
        out.push((
            RANGES.file,
            csv_text(
                &["time[s]", "beacon", "range[m]"],
                self.ranges
                    .iter()
                    .map(|r| vec![r.time, self.beacons[r.beacon].id as f64, r.range]),
            ),
        ));
        if let Some(depth) = &self.depth {
            out.push((DEPTH.file, series_text("depth[m]", depth)));
        }
        if let Some(truth) = &self.truth {
            let down = truth.first().is_some_and(|r| r.down.is_some());
            let heading = truth.first().is_some_and(|r| r.heading.is_some());
            let mut header = vec!["time[s]", "north[m]", "east[m]"];
            if down {
                header.push("down[m]");
            }
            if heading {
                header.push("heading[rad]");
            }
            out.push((
                TRUTH.file,
                csv_text(
                    &header,
                    truth.iter().map(|r| {
                        let mut v = vec![r.time, r.north_east[0], r.north_east[1]];
                        if down {
                            v.push(r.down.unwrap_or(f64::NAN));
                        }
                        if heading {
                            v.push(r.heading.unwrap_or(f64::NAN));
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
    use super::super::{Manifest, write_log};
    use super::*;

    fn set(files: &[(&'static str, &str)]) -> FileSet {
        super::super::tests::file_set(LogKind::RangeBeacon, files)
    }

    fn odometry_log() -> Vec<(&'static str, &'static str)> {
        vec![
            ("beacons.csv", "id,north[m],east[m]\n7,10,0\n9,0,10\n"),
            (
                "initial.csv",
                "time[s],north[m],east[m],heading[deg]\n0,0,0,90\n",
            ),
            (
                "odometry.csv",
                "time[s],distance[m],heading_change[rad]\n0.5,0.5,0\n1,0.5,0.1\n",
            ),
            (
                "ranges.csv",
                "time[s],beacon,range[m]\n0.5,7,10\n0.5,9,9.5\n",
            ),
            ("truth.csv", "time[s],north[m],east[m]\n0,0,0\n1,0,1\n"),
        ]
    }

    #[test]
    fn an_odometry_log_parses_into_si_and_round_trips() {
        let log = RangeBeaconLog::parse(&set(&odometry_log())).unwrap();
        assert_eq!(log.beacons.len(), 2);
        assert_eq!(log.ranges[1].beacon, 1);
        assert!((log.start.heading - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!(matches!(&log.motion, Motion::Odometry(r) if r.len() == 2));
        assert_eq!(log.truth.as_ref().unwrap().len(), 2);
        // Written and read back: the same log, bit for bit.
        let dir = std::env::temp_dir().join(format!("fathom-rb-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        write_log(
            &dir,
            &Manifest::new(LogKind::RangeBeacon, "t"),
            &log.to_files(),
        )
        .unwrap();
        assert_eq!(RangeBeaconLog::read_dir(&dir).unwrap(), log);
    }

    #[test]
    fn a_dvl_log_needs_heading_and_3d_start() {
        let files = [
            ("beacons.csv", "id,north[m],east[m],down[m]\n1,10,0,5\n"),
            (
                "initial.csv",
                "time[s],north[m],east[m],down[m],heading[rad]\n0,0,0,2,0\n",
            ),
            ("dvl.csv", "time[s],u[kn],v[m/s],w[m/s]\n0.2,1,0,0\n"),
            ("heading.csv", "time[s],heading[deg]\n0.1,10\n"),
            ("ranges.csv", "time[s],beacon,range[m]\n"),
            ("depth.csv", "time[s],depth[m]\n0.1,2\n"),
        ];
        let log = RangeBeaconLog::parse(&set(&files)).unwrap();
        let Motion::Dvl { dvl, heading } = &log.motion else {
            panic!("not DVL")
        };
        assert!((dvl[0].1[0] - 1852.0 / 3600.0).abs() < 1e-15);
        assert!((heading[0].1 - 10f64.to_radians()).abs() < 1e-15);
        assert_eq!(log.depth.as_ref().unwrap().len(), 1);
        assert_eq!(log.beacons[0].pos_in_nav, [10.0, 0.0, 5.0]);
    }

    #[test]
    fn files_that_do_not_fit_together_are_named() {
        let base = odometry_log();
        let with = |name: &'static str, text: &'static str| {
            let mut f: Vec<_> = base.iter().filter(|(n, _)| *n != name).copied().collect();
            if !text.is_empty() {
                f.push((name, text));
            }
            RangeBeaconLog::parse(&set(&f)).unwrap_err().to_string()
        };
        let cases = [
            (
                "ranges.csv",
                "time[s],beacon,range[m]\n0.5,7,10\n0.6,8,3\n",
                "`log/ranges.csv` line 3, column 2 (`beacon`): unknown beacon id 8 (`beacons.csv` lists 7, 9)",
            ),
            (
                "beacons.csv",
                "id,north[m],east[m]\n7,0,0\n7,1,1\n",
                "`log/beacons.csv` line 3, column 1 (`id`): beacon id 7 is listed twice",
            ),
            (
                "beacons.csv",
                "id,north[m],east[m],down[m]\n7,0,0,1\n9,1,1,1\n",
                "has a `down` column, but the log's motion is 2D",
            ),
            ("beacons.csv", "id,north[m],east[m]\n", "lists no beacon"),
            (
                "beacons.csv",
                "",
                "`log/beacons.csv`: missing: the beacon table",
            ),
            (
                "initial.csv",
                "time[s],north[m],east[m],heading[rad]\n",
                "needs exactly one data row",
            ),
            (
                "odometry.csv",
                "",
                "`log/odometry.csv`: missing: a motion source",
            ),
            (
                "depth.csv",
                "time[s],depth[m]\n1,2\n",
                "2D wheel odometry, which has no depth",
            ),
            (
                "dvl.csv",
                "time[s],u[m/s],v[m/s],w[m/s]\n",
                "two motion sources",
            ),
            (
                "truth.csv",
                "time[s],north[m],east[m]\n1,0,0\n0.5,0,0\n",
                "`log/truth.csv` line 3, column 1 (`time[s]`): time 0.5 s is not after",
            ),
        ];
        for (name, text, want) in cases {
            let e = with(name, text);
            assert!(e.contains(want), "{name}: {e}");
        }
        let mut f = base.clone();
        f.retain(|(n, _)| *n != "odometry.csv");
        f.push(("dvl.csv", "time[s],u[m/s],v[m/s],w[m/s]\n"));
        let e = RangeBeaconLog::parse(&set(&f)).unwrap_err().to_string();
        assert!(
            e.contains("heading.csv") && e.contains("needs the heading"),
            "{e}"
        );
    }
}

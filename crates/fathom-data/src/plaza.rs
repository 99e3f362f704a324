//! Reader of the CMU Plaza range-only data sets in their native files (Djugash, Singh,
//! Kantor, Zhang, ICRA 2006, as redistributed with GTSAM):
//!
//! - `<name>_DR.txt`: odometry, `time_s delta_distance_m delta_heading_rad` per line;
//! - `<name>_TD.txt`: ranges, `time_s sender_id beacon_id range_m` per line;
//! - `<name>_.mat`: MATLAB v5 with `GT` (`time, x, y, heading`), `TL` (`id, x, y`),
//!   `DRp` (`time, x, y, heading`) and more (not needed here).
//!
//! Text files are whitespace separated (tabs, spaces, CRLF line ends all accepted);
//! blank lines are skipped. Every error is a [`PlazaError`] naming the file and the
//! 1-based line (text) or the matrix and its 1-based row (`.mat`): a missing file, a
//! wrong column count, a field that is not a finite number, a non-integer or unknown
//! beacon id, times that do not increase.
//!
//! Range logs of this data set are not always in time order (`Plaza1_TD.txt` jumps back
//! twice, by 64 s and 50 s, and then overlaps rows already logged). [`RangeOrder`]
//! decides: [`RangeOrder::Strict`] refuses such a file, [`RangeOrder::Sort`] sorts the
//! ranges stably by time and records the lines where time went backwards in
//! [`PlazaLog::range_order_breaks`]. Odometry and ground truth must always be strictly
//! increasing in time (odometry increments cannot be reordered meaningfully).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use fathom_core::echo::{echo_list, echo_message, echo_path};

use crate::layout::read_regular_file;
use crate::matv5::{MatArray, MatClass, read_mat_v5};

/// Where in a file an error sits.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// A 1-based line of a text file.
    Line(usize),
    /// A 1-based row of a named `.mat` matrix.
    MatRow {
        /// Matrix name (`GT`, `TL`, `DRp`).
        matrix: String,
        /// 1-based row.
        row: usize,
    },
}

impl std::fmt::Display for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Place::Line(l) => write!(f, "line {l}"),
            Place::MatRow { matrix, row } => write!(f, "matrix `{matrix}` row {row}"),
        }
    }
}

/// Everything that can be wrong with a Plaza data folder.
#[derive(Debug, thiserror::Error)]
pub enum PlazaError {
    /// The data folder does not exist or is not a directory.
    #[error(
        "data folder `{}` does not exist or is not a directory",
        echo_path(dir)
    )]
    NoFolder {
        /// The folder.
        dir: PathBuf,
    },
    /// No file with the expected suffix.
    #[error("no `*{suffix}` file in `{}`", echo_path(dir))]
    FileMissing {
        /// The folder searched.
        dir: PathBuf,
        /// The expected file-name suffix (`_DR.txt`, `_TD.txt`, `_.mat`).
        suffix: &'static str,
    },
    /// More than one file with the suffix.
    #[error(
        "more than one `*{suffix}` file in `{}`: {}",
        echo_path(dir),
        echo_list(found)
    )]
    Ambiguous {
        /// The folder searched.
        dir: PathBuf,
        /// The suffix.
        suffix: &'static str,
        /// The matching file names.
        found: Vec<String>,
    },
    /// Reading failed.
    #[error("cannot read `{}`", echo_path(path))]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A row has the wrong number of columns.
    #[error(
        "`{}` {place}: expected {expected} columns, found {found}",
        echo_path(path)
    )]
    ColumnCount {
        /// The file.
        path: PathBuf,
        /// Line or matrix row.
        place: Place,
        /// Expected column count.
        expected: usize,
        /// Found column count.
        found: usize,
    },
    /// A field is not a finite number.
    #[error(
        "`{}` {place}: column {column} (`{name}`): {}",
        echo_path(path),
        echo_message(reason)
    )]
    BadValue {
        /// The file.
        path: PathBuf,
        /// Line or matrix row.
        place: Place,
        /// 1-based column.
        column: usize,
        /// Column name (`time_s`, `range_m`, ...).
        name: &'static str,
        /// What is wrong, with the offending text.
        reason: String,
    },
    /// Time does not increase.
    #[error(
        "`{}` {place}: time {time} s is not after the previous row's {previous} s (times must increase)",
        echo_path(path)
    )]
    NonMonotonicTime {
        /// The file.
        path: PathBuf,
        /// Line or matrix row.
        place: Place,
        /// Previous row's time, s.
        previous: f64,
        /// This row's time, s.
        time: f64,
    },
    /// A range names a beacon that the survey (`TL`) does not list.
    #[error(
        "`{}` {place}: unknown beacon id {id} (surveyed beacons in `TL`: {})",
        echo_path(path),
        echo_list(known)
    )]
    UnknownBeacon {
        /// The range file.
        path: PathBuf,
        /// Its line.
        place: Place,
        /// The id read.
        id: i64,
        /// The surveyed ids.
        known: Vec<i64>,
    },
    /// The same beacon id twice in the survey.
    #[error("`{}` {place}: beacon id {id} listed twice", echo_path(path))]
    DuplicateBeacon {
        /// The `.mat` file.
        path: PathBuf,
        /// The second row.
        place: Place,
        /// The id.
        id: i64,
    },
    /// The file holds no data rows.
    #[error("`{}`{}: no data rows", echo_path(path), matrix.as_ref().map(|m| format!(" matrix `{m}`")).unwrap_or_default())]
    Empty {
        /// The file.
        path: PathBuf,
        /// The matrix, for `.mat` files.
        matrix: Option<String>,
    },
    /// The `.mat` file cannot be parsed as MATLAB v5.
    #[error(
        "`{}`: not a readable MATLAB v5 file ({})",
        echo_path(path),
        echo_message(reason)
    )]
    Mat {
        /// The file.
        path: PathBuf,
        /// The parser's message.
        reason: String,
    },
    /// A required matrix is absent from the `.mat` file.
    #[error(
        "`{}`: no matrix `{name}` (found: {})",
        echo_path(path),
        echo_list(found)
    )]
    MissingMatrix {
        /// The file.
        path: PathBuf,
        /// The matrix wanted.
        name: &'static str,
        /// The numeric matrices present.
        found: Vec<String>,
    },
    /// A matrix has the wrong shape or type.
    #[error("`{}`: matrix `{name}`: {}", echo_path(path), echo_message(reason))]
    MatrixShape {
        /// The file.
        path: PathBuf,
        /// The matrix.
        name: &'static str,
        /// What is wrong (found dimensions or class).
        reason: String,
    },
}

/// One odometry step: the distance and heading increments over `(t_prev, time]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryStep {
    /// Time stamp, s (as in the file).
    pub time: f64,
    /// Distance increment, m.
    pub delta_distance: f64,
    /// Heading increment, rad.
    pub delta_heading: f64,
}

/// One range measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeRecord {
    /// Time stamp, s (as in the file).
    pub time: f64,
    /// Id of the robot's radio.
    pub sender: i64,
    /// Id of the beacon (as in the file).
    pub beacon_id: i64,
    /// Index of the beacon in [`PlazaLog::beacons`] (survey order).
    pub beacon: usize,
    /// Measured range, m.
    pub range: f64,
    /// 1-based line in the range file.
    pub line: usize,
}

/// A 2D pose at a time (ground truth or dead-reckoned path).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseRecord {
    /// Time stamp, s (as in the file).
    pub time: f64,
    /// x, m.
    pub x: f64,
    /// y, m.
    pub y: f64,
    /// Heading, rad.
    pub heading: f64,
}

/// A surveyed beacon.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BeaconSite {
    /// Id as used in the range file.
    pub id: i64,
    /// x, m.
    pub x: f64,
    /// y, m.
    pub y: f64,
}

/// How to treat range rows whose time is earlier than the previous row's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum RangeOrder {
    /// Refuse the file ([`PlazaError::NonMonotonicTime`]).
    Strict,
    /// Sort the ranges stably by time and record where time went backwards.
    #[default]
    Sort,
}

/// The three files of one Plaza data set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlazaFiles {
    /// `*_DR.txt`.
    pub odometry: PathBuf,
    /// `*_TD.txt`.
    pub ranges: PathBuf,
    /// `*_.mat`.
    pub mat: PathBuf,
}

impl PlazaFiles {
    /// Finds the three files in `dir` by their suffixes (exactly one of each).
    ///
    /// # Errors
    /// [`PlazaError::NoFolder`], [`PlazaError::FileMissing`], [`PlazaError::Ambiguous`],
    /// [`PlazaError::Io`].
    pub fn find(dir: impl AsRef<Path>) -> Result<Self, PlazaError> {
        let dir = dir.as_ref();
        if !dir.is_dir() {
            return Err(PlazaError::NoFolder {
                dir: dir.to_path_buf(),
            });
        }
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .map_err(|source| PlazaError::Io {
                path: dir.to_path_buf(),
                source,
            })?
            .filter_map(|e| e.ok())
            .filter(|e| e.path().is_file())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        let pick = |suffix: &'static str| -> Result<PathBuf, PlazaError> {
            let found: Vec<String> = names
                .iter()
                .filter(|n| n.ends_with(suffix) && n.len() > suffix.len())
                .cloned()
                .collect();
            match found.as_slice() {
                [one] => Ok(dir.join(one)),
                [] => Err(PlazaError::FileMissing {
                    dir: dir.to_path_buf(),
                    suffix,
                }),
                _ => Err(PlazaError::Ambiguous {
                    dir: dir.to_path_buf(),
                    suffix,
                    found,
                }),
            }
        };
        Ok(PlazaFiles {
            odometry: pick("_DR.txt")?,
            ranges: pick("_TD.txt")?,
            mat: pick("_.mat")?,
        })
    }
}

/// A Plaza data set as read from its files.
#[derive(Debug, Clone, PartialEq)]
pub struct PlazaLog {
    /// The files read.
    pub files: PlazaFiles,
    /// Odometry steps, strictly increasing in time.
    pub odometry: Vec<OdometryStep>,
    /// Ranges in time order (stable sort when [`RangeOrder::Sort`]).
    pub ranges: Vec<RangeRecord>,
    /// 1-based lines of the range file whose time is earlier than the line before.
    pub range_order_breaks: Vec<usize>,
    /// Ground truth (`GT`), strictly increasing in time.
    pub ground_truth: Vec<PoseRecord>,
    /// Surveyed beacons (`TL`), in file order.
    pub beacons: Vec<BeaconSite>,
    /// The data set's own dead-reckoned path (`DRp`), strictly increasing in time.
    pub dr_path: Vec<PoseRecord>,
}

impl PlazaLog {
    /// Reads the data set in `dir` (see the module docs).
    ///
    /// # Errors
    /// Any [`PlazaError`], naming file and line / matrix row.
    pub fn read_dir(dir: impl AsRef<Path>, order: RangeOrder) -> Result<Self, PlazaError> {
        let files = PlazaFiles::find(dir)?;
        Self::read_files(files, order)
    }

    /// Reads the given files.
    ///
    /// # Errors
    /// Any [`PlazaError`].
    pub fn read_files(files: PlazaFiles, order: RangeOrder) -> Result<Self, PlazaError> {
        let mat = read_mat(&files.mat)?;
        let odometry = read_odometry(&files.odometry)?;
        let (ranges, range_order_breaks) = read_ranges(&files.ranges, &mat.beacons, order)?;
        Ok(PlazaLog {
            files,
            odometry,
            ranges,
            range_order_breaks,
            ground_truth: mat.ground_truth,
            beacons: mat.beacons,
            dr_path: mat.dr_path,
        })
    }
}

fn read_text(path: &Path) -> Result<String, PlazaError> {
    let io = |source| PlazaError::Io {
        path: path.to_path_buf(),
        source,
    };
    String::from_utf8(read_regular_file(path).map_err(io)?).map_err(|_| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        ))
    })
}

/// The non-blank lines of `text` as `(1-based line, fields)`, each with `expected`
/// fields.
fn rows<'a>(
    path: &Path,
    text: &'a str,
    expected: usize,
) -> Result<Vec<(usize, Vec<&'a str>)>, PlazaError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        if fields.len() != expected {
            return Err(PlazaError::ColumnCount {
                path: path.to_path_buf(),
                place: Place::Line(i + 1),
                expected,
                found: fields.len(),
            });
        }
        out.push((i + 1, fields));
    }
    if out.is_empty() {
        return Err(PlazaError::Empty {
            path: path.to_path_buf(),
            matrix: None,
        });
    }
    Ok(out)
}

fn number(
    path: &Path,
    place: &Place,
    column: usize,
    name: &'static str,
    text: &str,
) -> Result<f64, PlazaError> {
    let bad = |reason: String| PlazaError::BadValue {
        path: path.to_path_buf(),
        place: place.clone(),
        column,
        name,
        reason,
    };
    let v: f64 = text
        .parse()
        .map_err(|_| bad(format!("`{text}` is not a number")))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(bad(format!("`{text}` is not finite")))
    }
}

fn check_finite(
    path: &Path,
    place: &Place,
    column: usize,
    name: &'static str,
    v: f64,
) -> Result<f64, PlazaError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(PlazaError::BadValue {
            path: path.to_path_buf(),
            place: place.clone(),
            column,
            name,
            reason: format!("{v} is not finite"),
        })
    }
}

fn integer(
    path: &Path,
    place: &Place,
    column: usize,
    name: &'static str,
    v: f64,
) -> Result<i64, PlazaError> {
    if v.fract() == 0.0 && v.abs() < 9.0e15 {
        Ok(v as i64)
    } else {
        Err(PlazaError::BadValue {
            path: path.to_path_buf(),
            place: place.clone(),
            column,
            name,
            reason: format!("{v} is not a whole number"),
        })
    }
}

fn check_increasing(
    path: &Path,
    place: &Place,
    previous: Option<f64>,
    time: f64,
) -> Result<(), PlazaError> {
    match previous {
        Some(p) if time <= p => Err(PlazaError::NonMonotonicTime {
            path: path.to_path_buf(),
            place: place.clone(),
            previous: p,
            time,
        }),
        _ => Ok(()),
    }
}

/// Reads an odometry file (`time_s delta_distance_m delta_heading_rad`).
///
/// # Errors
/// [`PlazaError`] naming file and line: I/O, column count, bad number, time not
/// strictly increasing, no rows.
pub fn read_odometry(path: impl AsRef<Path>) -> Result<Vec<OdometryStep>, PlazaError> {
    let path = path.as_ref();
    parse_odometry(&read_text(path)?, path)
}

/// Parses the text of an odometry file; `label` (normally the file's path) names the
/// file in errors.
///
/// # Errors
/// As [`read_odometry`], without I/O.
pub fn parse_odometry(
    text: &str,
    label: impl AsRef<Path>,
) -> Result<Vec<OdometryStep>, PlazaError> {
    let path = label.as_ref();
    let mut out = Vec::new();
    let mut previous = None;
    for (line, f) in rows(path, text, 3)? {
        let place = Place::Line(line);
        let time = number(path, &place, 1, "time_s", f[0])?;
        let delta_distance = number(path, &place, 2, "delta_distance_m", f[1])?;
        let delta_heading = number(path, &place, 3, "delta_heading_rad", f[2])?;
        check_increasing(path, &place, previous, time)?;
        previous = Some(time);
        out.push(OdometryStep {
            time,
            delta_distance,
            delta_heading,
        });
    }
    Ok(out)
}

/// Reads a range file (`time_s sender_id beacon_id range_m`); beacon ids must be
/// among `beacons`. Returns the ranges in time order and the lines where time went
/// backwards (empty unless `order` is [`RangeOrder::Sort`]).
///
/// # Errors
/// [`PlazaError`] naming file and line: I/O, column count, bad number, non-integer or
/// unknown beacon id, negative range, time going backwards under
/// [`RangeOrder::Strict`], no rows.
pub fn read_ranges(
    path: impl AsRef<Path>,
    beacons: &[BeaconSite],
    order: RangeOrder,
) -> Result<(Vec<RangeRecord>, Vec<usize>), PlazaError> {
    let path = path.as_ref();
    parse_ranges(&read_text(path)?, path, beacons, order)
}

/// Parses the text of a range file; `label` (normally the file's path) names the file
/// in errors.
///
/// # Errors
/// As [`read_ranges`], without I/O.
pub fn parse_ranges(
    text: &str,
    label: impl AsRef<Path>,
    beacons: &[BeaconSite],
    order: RangeOrder,
) -> Result<(Vec<RangeRecord>, Vec<usize>), PlazaError> {
    let path = label.as_ref();
    let index: BTreeMap<i64, usize> = beacons.iter().enumerate().map(|(k, b)| (b.id, k)).collect();
    let mut out = Vec::new();
    let mut breaks = Vec::new();
    let mut previous: Option<f64> = None;
    for (line, f) in rows(path, text, 4)? {
        let place = Place::Line(line);
        let time = number(path, &place, 1, "time_s", f[0])?;
        let sender = number(path, &place, 2, "sender_id", f[1])?;
        let sender = integer(path, &place, 2, "sender_id", sender)?;
        let id = number(path, &place, 3, "beacon_id", f[2])?;
        let beacon_id = integer(path, &place, 3, "beacon_id", id)?;
        let range = number(path, &place, 4, "range_m", f[3])?;
        if range < 0.0 {
            return Err(PlazaError::BadValue {
                path: path.to_path_buf(),
                place,
                column: 4,
                name: "range_m",
                reason: format!("range {range} is negative"),
            });
        }
        let Some(&beacon) = index.get(&beacon_id) else {
            return Err(PlazaError::UnknownBeacon {
                path: path.to_path_buf(),
                place,
                id: beacon_id,
                known: beacons.iter().map(|b| b.id).collect(),
            });
        };
        if let Some(p) = previous
            && time < p
        {
            match order {
                RangeOrder::Strict => {
                    return Err(PlazaError::NonMonotonicTime {
                        path: path.to_path_buf(),
                        place,
                        previous: p,
                        time,
                    });
                }
                RangeOrder::Sort => breaks.push(line),
            }
        }
        previous = Some(time);
        out.push(RangeRecord {
            time,
            sender,
            beacon_id,
            beacon,
            range,
            line,
        });
    }
    // Stable: equal times keep their file order.
    out.sort_by(|a, b| a.time.total_cmp(&b.time));
    Ok((out, breaks))
}

/// The matrices of a Plaza `.mat` file that the estimators need.
#[derive(Debug, Clone, PartialEq)]
pub struct PlazaMat {
    /// `GT`.
    pub ground_truth: Vec<PoseRecord>,
    /// `TL`.
    pub beacons: Vec<BeaconSite>,
    /// `DRp`.
    pub dr_path: Vec<PoseRecord>,
}

impl PlazaMat {
    /// The matrices as [`parse_mat`] reads them (`GT` and `DRp`: `time, x, y, heading`
    /// rows; `TL`: `id, x, y` rows), for writing a data set back with
    /// [`crate::matv5::write_mat_v5`] (edited copies in tests, round trips).
    pub fn to_matrices(&self) -> Vec<crate::matv5::NamedMatrix> {
        use crate::matv5::NamedMatrix;
        let poses = |p: &[PoseRecord]| -> Vec<Vec<f64>> {
            p.iter()
                .map(|r| vec![r.time, r.x, r.y, r.heading])
                .collect()
        };
        vec![
            NamedMatrix::new("GT", poses(&self.ground_truth)),
            NamedMatrix::new(
                "TL",
                self.beacons
                    .iter()
                    .map(|b| vec![b.id as f64, b.x, b.y])
                    .collect(),
            ),
            NamedMatrix::new("DRp", poses(&self.dr_path)),
        ]
    }
}

/// A matrix of the `.mat` file as rows.
fn mat_rows(
    path: &Path,
    arrays: &[MatArray],
    name: &'static str,
    cols: usize,
) -> Result<Vec<Vec<f64>>, PlazaError> {
    let Some(array) = arrays.iter().find(|a| a.name == name) else {
        return Err(PlazaError::MissingMatrix {
            path: path.to_path_buf(),
            name,
            found: arrays
                .iter()
                .filter(|a| !matches!(a.class, MatClass::Other(_)))
                .map(|a| a.name.clone())
                .collect(),
        });
    };
    if let MatClass::Integer(class) | MatClass::Other(class) = array.class {
        return Err(PlazaError::MatrixShape {
            path: path.to_path_buf(),
            name,
            reason: format!("expected a double matrix, found MAT class {class}"),
        });
    }
    let size = &array.dims;
    if size.len() != 2 || size[1] != cols {
        return Err(PlazaError::MatrixShape {
            path: path.to_path_buf(),
            name,
            reason: format!("expected N x {cols}, found {size:?}"),
        });
    }
    let n = size[0];
    if n == 0 {
        return Err(PlazaError::Empty {
            path: path.to_path_buf(),
            matrix: Some(name.to_string()),
        });
    }
    // The reader guarantees one value per element; checked again before indexing.
    if n.checked_mul(cols) != Some(array.real.len()) {
        return Err(PlazaError::MatrixShape {
            path: path.to_path_buf(),
            name,
            reason: format!("{} values for {n} x {cols}", array.real.len()),
        });
    }
    // Column-major storage.
    Ok((0..n)
        .map(|r| (0..cols).map(|c| array.real[c * n + r]).collect())
        .collect())
}

fn poses(
    path: &Path,
    rows: &[Vec<f64>],
    matrix: &'static str,
) -> Result<Vec<PoseRecord>, PlazaError> {
    let mut out = Vec::with_capacity(rows.len());
    let mut previous = None;
    for (i, r) in rows.iter().enumerate() {
        let place = Place::MatRow {
            matrix: matrix.to_string(),
            row: i + 1,
        };
        let names = ["time_s", "x_m", "y_m", "heading_rad"];
        for (c, &v) in r.iter().enumerate() {
            check_finite(path, &place, c + 1, names[c], v)?;
        }
        check_increasing(path, &place, previous, r[0])?;
        previous = Some(r[0]);
        out.push(PoseRecord {
            time: r[0],
            x: r[1],
            y: r[2],
            heading: r[3],
        });
    }
    Ok(out)
}

/// Reads `GT`, `TL` and `DRp` from a Plaza `.mat` file.
///
/// # Errors
/// [`PlazaError`] naming file and matrix row: I/O, not MATLAB v5, missing matrix,
/// wrong shape, non-finite value, time not strictly increasing, non-integer or
/// duplicate beacon id.
pub fn read_mat(path: impl AsRef<Path>) -> Result<PlazaMat, PlazaError> {
    let path = path.as_ref();
    let bytes = read_regular_file(path).map_err(|source| PlazaError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_mat(&bytes, path)
}

/// Parses the bytes of a Plaza `.mat` file; `label` (normally the file's path) names
/// the file in errors.
///
/// # Errors
/// As [`read_mat`], without I/O.
pub fn parse_mat(bytes: &[u8], label: impl AsRef<Path>) -> Result<PlazaMat, PlazaError> {
    let path = label.as_ref();
    let mat = read_mat_v5(bytes).map_err(|e| PlazaError::Mat {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let ground_truth = poses(path, &mat_rows(path, &mat, "GT", 4)?, "GT")?;
    let dr_path = poses(path, &mat_rows(path, &mat, "DRp", 4)?, "DRp")?;
    let mut beacons: Vec<BeaconSite> = Vec::new();
    for (i, r) in mat_rows(path, &mat, "TL", 3)?.iter().enumerate() {
        let place = Place::MatRow {
            matrix: "TL".into(),
            row: i + 1,
        };
        let id = check_finite(path, &place, 1, "beacon_id", r[0])?;
        let id = integer(path, &place, 1, "beacon_id", id)?;
        let x = check_finite(path, &place, 2, "x_m", r[1])?;
        let y = check_finite(path, &place, 3, "y_m", r[2])?;
        if beacons.iter().any(|b| b.id == id) {
            return Err(PlazaError::DuplicateBeacon {
                path: path.to_path_buf(),
                place,
                id,
            });
        }
        beacons.push(BeaconSite { id, x, y });
    }
    Ok(PlazaMat {
        ground_truth,
        beacons,
        dr_path,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matv5::{NamedMatrix, write_mat_v5};

    fn dir(tag: &str) -> PathBuf {
        let d = std::env::temp_dir()
            .join("fathom-sim-tests")
            .join(format!("plaza-{}-{tag}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn mat_matrices() -> Vec<NamedMatrix> {
        vec![
            NamedMatrix::new(
                "GT",
                vec![vec![10.0, 1.0, 2.0, 0.5], vec![10.5, 1.1, 2.0, 0.5]],
            ),
            NamedMatrix::new("TL", vec![vec![3.0, 0.0, 0.0], vec![7.0, 10.0, 0.0]]),
            NamedMatrix::new(
                "DRp",
                vec![vec![10.0, 0.0, 0.0, 0.3], vec![10.2, 0.1, 0.0, 0.3]],
            ),
        ]
    }

    /// A small valid data set: CRLF and tab separated like the real files.
    fn write_valid(d: &Path) {
        std::fs::write(
            d.join("S_DR.txt"),
            "  1.0e+001\t 1.0e-001\t 0.0e+000\t\r\n  1.02e+001\t 1.0e-001\t 1.0e-002\t\r\n",
        )
        .unwrap();
        std::fs::write(
            d.join("S_TD.txt"),
            "10.1 2 3 5.5\n\n10.3 2 7 4.5\n10.2 2 3 5.0\n",
        )
        .unwrap();
        write_mat_v5(d.join("S_.mat"), &mat_matrices()).unwrap();
    }

    #[test]
    fn reads_a_small_valid_set_and_sorts_ranges() {
        let d = dir("valid");
        write_valid(&d);
        let log = PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap();
        assert_eq!(log.odometry.len(), 2);
        assert_eq!(log.odometry[1].time, 10.2);
        assert_eq!(log.odometry[1].delta_heading, 0.01);
        assert_eq!(
            log.beacons[1],
            BeaconSite {
                id: 7,
                x: 10.0,
                y: 0.0
            }
        );
        assert_eq!(log.ground_truth[0].x, 1.0);
        assert_eq!(log.dr_path[0].heading, 0.3);
        let times: Vec<f64> = log.ranges.iter().map(|r| r.time).collect();
        assert_eq!(times, [10.1, 10.2, 10.3]);
        assert_eq!(log.ranges[2].beacon, 1);
        assert_eq!(log.ranges[2].beacon_id, 7);
        assert_eq!(log.ranges[1].line, 4);
        assert_eq!(log.range_order_breaks, [4]);
    }

    fn err_text(e: PlazaError) -> String {
        e.to_string()
    }

    #[test]
    fn missing_files_and_folder_are_named() {
        let d = dir("missing");
        let e = err_text(PlazaFiles::find(d.join("nope")).unwrap_err());
        assert!(e.contains("does not exist") && e.contains("nope"), "{e}");
        write_valid(&d);
        std::fs::remove_file(d.join("S_TD.txt")).unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("no `*_TD.txt` file in"), "{e}");
        std::fs::write(d.join("A_TD.txt"), "1 2 3 4\n").unwrap();
        std::fs::write(d.join("B_TD.txt"), "1 2 3 4\n").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("A_TD.txt, B_TD.txt"), "{e}");
    }

    #[test]
    fn wrong_column_count_names_file_and_line() {
        let d = dir("cols");
        write_valid(&d);
        std::fs::write(d.join("S_DR.txt"), "10.0 0.1 0.0\n10.2 0.1\n").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(
            e.contains("S_DR.txt` line 2: expected 3 columns, found 2"),
            "{e}"
        );
        write_valid(&d);
        std::fs::write(d.join("S_TD.txt"), "10.1 2 3 5.5 9\n").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(
            e.contains("S_TD.txt` line 1: expected 4 columns, found 5"),
            "{e}"
        );
    }

    #[test]
    fn bad_numbers_are_named() {
        let d = dir("nums");
        write_valid(&d);
        std::fs::write(d.join("S_DR.txt"), "10.0 0.1 0.0\n10.2 x 0.0\n").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(
            e.contains("line 2: column 2 (`delta_distance_m`): `x` is not a number"),
            "{e}"
        );
        write_valid(&d);
        std::fs::write(d.join("S_TD.txt"), "10.1 2 3.5 5.5\n").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("`beacon_id`): 3.5 is not a whole number"), "{e}");
        std::fs::write(d.join("S_TD.txt"), "10.1 2 3 NaN\n").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("`NaN` is not finite"), "{e}");
        std::fs::write(d.join("S_TD.txt"), "").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("S_TD.txt`: no data rows"), "{e}");
    }

    #[test]
    fn non_monotonic_times_are_named() {
        let d = dir("time");
        write_valid(&d);
        std::fs::write(
            d.join("S_DR.txt"),
            "10.0 0.1 0.0\n10.2 0.1 0.0\n10.2 0.1 0.0\n",
        )
        .unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(
            e.contains("S_DR.txt` line 3: time 10.2 s is not after the previous row's 10.2 s"),
            "{e}"
        );
        write_valid(&d);
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Strict).unwrap_err());
        assert!(e.contains("S_TD.txt` line 4: time 10.2 s"), "{e}");
        let mut m = mat_matrices();
        m[0].rows[1][0] = 9.0;
        write_mat_v5(d.join("S_.mat"), &m).unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("S_.mat` matrix `GT` row 2: time 9 s"), "{e}");
    }

    #[test]
    fn unknown_and_duplicate_beacons_are_named() {
        let d = dir("beacon");
        write_valid(&d);
        std::fs::write(d.join("S_TD.txt"), "10.1 2 3 5.5\n10.3 2 4 4.5\n").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(
            e.contains("S_TD.txt` line 2: unknown beacon id 4 (surveyed beacons in `TL`: 3, 7)"),
            "{e}"
        );
        write_valid(&d);
        let mut m = mat_matrices();
        m[1].rows[1][0] = 3.0;
        write_mat_v5(d.join("S_.mat"), &m).unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(
            e.contains("matrix `TL` row 2: beacon id 3 listed twice"),
            "{e}"
        );
    }

    #[test]
    fn to_matrices_is_what_parse_mat_reads() {
        let bytes = crate::matv5::mat_v5_bytes(&mat_matrices()).unwrap();
        let mat = parse_mat(&bytes, "S_.mat").unwrap();
        assert_eq!(mat.to_matrices(), mat_matrices());
        let again = crate::matv5::mat_v5_bytes(&mat.to_matrices()).unwrap();
        assert_eq!(parse_mat(&again, "S_.mat").unwrap(), mat);
    }

    #[test]
    fn bad_mat_files_are_named() {
        let d = dir("mat");
        write_valid(&d);
        std::fs::write(d.join("S_.mat"), b"not a mat file").unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("S_.mat`: not a readable MATLAB v5 file"), "{e}");
        let m: Vec<NamedMatrix> = mat_matrices()
            .into_iter()
            .filter(|m| m.name != "TL")
            .collect();
        write_mat_v5(d.join("S_.mat"), &m).unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(e.contains("no matrix `TL` (found: GT, DRp)"), "{e}");
        let mut m = mat_matrices();
        m[0] = NamedMatrix::new("GT", vec![vec![1.0, 2.0, 3.0]]);
        write_mat_v5(d.join("S_.mat"), &m).unwrap();
        let e = err_text(PlazaLog::read_dir(&d, RangeOrder::Sort).unwrap_err());
        assert!(
            e.contains("matrix `GT`: expected N x 4, found [1, 3]"),
            "{e}"
        );
    }
}

//! One CSV file of the own-data layout, read from bytes against a [`FileSpec`]:
//! the header (`name[unit]` cells, any order), numeric rows converted into SI, and
//! the checks every file gets (missing, unknown or duplicate columns, wrong units,
//! field counts, numbers, NaN / infinite / implausible values, time order). Every
//! error names the file, the line and the column ([`LogError`]).
//!
//! Syntax: comma separated, first non-comment line is the header, lines starting
//! with `#` are comments, blank lines are skipped, spaces around fields are trimmed,
//! CRLF or LF line ends, an optional UTF-8 byte-order mark, fields may be quoted.

use std::path::Path;

use fathom_core::echo::echo;

use super::error::{Cell, LogError};
use super::units::{Quantity, Unit};

/// What a column's values must satisfy beyond being finite and within the
/// quantity's plausibility bound ([`Quantity::bound`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Check {
    /// Any plausible value.
    Any,
    /// `>= 0` (ranges, altitudes).
    NonNegative,
    /// A whole number (ids).
    Integer,
    /// `0` or `1` (flags).
    Flag,
    /// A latitude: strictly inside (-90°, 90°) (after conversion, (-π/2, π/2)).
    Latitude,
}

/// One column a file may have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ColumnSpec {
    /// The name in the header (`time`, `range`, `beacon`).
    pub name: &'static str,
    /// What it measures (decides the accepted units).
    pub quantity: Quantity,
    /// The value check.
    pub check: Check,
    /// Whether the column must be present (ignored for group members, see
    /// [`FileSpec::groups`]).
    pub required: bool,
}

impl ColumnSpec {
    /// A required column.
    pub const fn required(name: &'static str, quantity: Quantity, check: Check) -> Self {
        Self {
            name,
            quantity,
            check,
            required: true,
        }
    }

    /// An optional column.
    pub const fn optional(name: &'static str, quantity: Quantity, check: Check) -> Self {
        Self {
            name,
            quantity,
            check,
            required: false,
        }
    }
}

/// How the `time` column must be ordered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeOrder {
    /// The file has no time column (the beacon table).
    NoTime,
    /// Strictly increasing (sensors sampled one row at a time).
    Increasing,
    /// Non-decreasing (ranges: several beacons may share a stamp).
    NonDecreasing,
}

/// The columns of one file of the layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileSpec {
    /// The file name inside the log folder (`ranges.csv`).
    pub file: &'static str,
    /// Every column the file may have (the time column, if any, first).
    pub columns: &'static [ColumnSpec],
    /// Alternative column sets: when non-empty, exactly one group must be present in
    /// full and no column of another group (e.g. IMU increments or IMU rates).
    pub groups: &'static [&'static [&'static str]],
    /// The order of the `time` column.
    pub time: TimeOrder,
}

impl FileSpec {
    /// A file of one row per stamp with increasing `time` and no alternative
    /// column groups (most sensor files).
    pub const fn timed(file: &'static str, columns: &'static [ColumnSpec]) -> Self {
        Self {
            file,
            columns,
            groups: &[],
            time: TimeOrder::Increasing,
        }
    }
}

/// A file read against its [`FileSpec`]: the values of every present column in SI,
/// column-major, and the line of every row.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    spec: FileSpec,
    /// Per spec column: its header position and unit, if present.
    present: Vec<Option<(usize, Unit)>>,
    /// Per spec column: the values (empty when the column is absent).
    values: Vec<Vec<f64>>,
    /// The 1-based line of each row.
    lines: Vec<u64>,
}

impl Table {
    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// Whether the file has no data rows.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// The 1-based line of row `row`.
    pub fn line(&self, row: usize) -> u64 {
        self.lines[row]
    }

    fn index(&self, name: &str) -> usize {
        self.spec
            .columns
            .iter()
            .position(|c| c.name == name)
            .unwrap_or_else(|| panic!("column `{name}` is not in the spec of {}", self.spec.file))
    }

    /// Whether the column `name` (of the spec) is present.
    pub fn has(&self, name: &str) -> bool {
        self.present[self.index(name)].is_some()
    }

    /// The values of column `name` in SI (empty when absent).
    ///
    /// # Panics
    /// When `name` is not a column of the spec (a programming error, never data).
    pub fn column(&self, name: &str) -> &[f64] {
        &self.values[self.index(name)]
    }

    /// The values of column `name`, if present.
    pub fn optional(&self, name: &str) -> Option<&[f64]> {
        self.has(name).then(|| self.column(name))
    }

    /// Where row `row`'s cell of column `name` sits, for cross-file errors.
    pub fn cell(&self, row: usize, name: &str) -> Cell {
        let i = self.index(name);
        Cell {
            line: self.lines[row],
            column: self.present[i].map(|(pos, u)| (pos + 1, header_text(name, u.spelling))),
        }
    }

    /// The unit spelling the header declared for column `name`, if present.
    pub fn unit(&self, name: &str) -> Option<&'static str> {
        self.present[self.index(name)].map(|(_, u)| u.spelling)
    }

    /// The rows as `(time, value of column name)` in SI.
    ///
    /// # Panics
    /// As [`Table::column`] (also for a file without a `time` column).
    pub fn series(&self, name: &str) -> Vec<(f64, f64)> {
        self.column("time")
            .iter()
            .copied()
            .zip(self.column(name).iter().copied())
            .collect()
    }

    /// Row `row`'s values of the three columns `names` (a vector's components).
    ///
    /// # Panics
    /// As [`Table::column`], or for a row out of range.
    pub fn triple(&self, row: usize, names: [&str; 3]) -> [f64; 3] {
        names.map(|name| self.column(name)[row])
    }
}

fn header_text(name: &str, unit: &str) -> String {
    if unit.is_empty() {
        name.to_string()
    } else {
        format!("{name}[{unit}]")
    }
}

/// Splits a header cell into `(name, unit)`: `range[m]` -> `("range", Some("m"))`,
/// `beacon` -> `("beacon", None)`.
fn split_header(cell: &str) -> Result<(&str, Option<&str>), String> {
    let cell = cell.trim();
    match cell.find('[') {
        None => Ok((cell, None)),
        Some(open) => {
            let Some(unit) = cell[open + 1..].strip_suffix(']') else {
                return Err(format!(
                    "header `{}`: a unit is written in brackets at the end, as `range[m]`",
                    echo(cell)
                ));
            };
            Ok((cell[..open].trim(), Some(unit.trim())))
        }
    }
}

/// The 1-based line of byte `offset` (`newlines`: the offsets of every `\n`). The
/// csv reader's own line count skips comment and blank lines, so lines are counted
/// here from byte offsets.
fn line_of(newlines: &[usize], offset: u64) -> u64 {
    newlines.partition_point(|&n| (n as u64) < offset) as u64 + 1
}

/// Where the record the csv reader reports at `offset` really starts: its position is
/// the end of the previous record, so line ends, blank lines, spaces and `#` comment
/// lines in between are skipped.
fn record_start(bytes: &[u8], offset: u64) -> u64 {
    let mut i = usize::try_from(offset)
        .unwrap_or(bytes.len())
        .min(bytes.len());
    let mut line_start = i == 0 || bytes[i - 1] == b'\n';
    while i < bytes.len() {
        match bytes[i] {
            b'\n' => {
                line_start = true;
                i += 1;
            }
            b'\r' | b' ' | b'\t' => i += 1,
            b'#' if line_start => {
                i = bytes[i..]
                    .iter()
                    .position(|&b| b == b'\n')
                    .map_or(bytes.len(), |n| i + n);
            }
            _ => break,
        }
    }
    i as u64
}

fn csv_error(path: &Path, e: &csv::Error, newlines: &[usize], fallback_line: u64) -> LogError {
    let line = e
        .position()
        .map_or(fallback_line, |p| line_of(newlines, p.byte()));
    let reason = match e.kind() {
        csv::ErrorKind::Utf8 { .. } => "not valid UTF-8 text".to_string(),
        _ => e.to_string(),
    };
    LogError::Syntax {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

/// Reads `bytes` as the file `path` (used in messages) of the layout against `spec`.
///
/// # Errors
/// [`LogError`] naming the file, line and column: a missing, unknown or duplicate
/// column, a missing or wrong unit, a row with another field count, a cell that is
/// not a finite number within the quantity's bound or fails its check, a time going
/// backwards, an empty file (no header).
pub fn parse_table(bytes: &[u8], path: &Path, spec: &FileSpec) -> Result<Table, LogError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let newlines: Vec<usize> = bytes
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .map(|(i, _)| i)
        .collect();
    let line_at = |r: &csv::ByteRecord, fallback: u64| {
        r.position().map_or(fallback, |p| {
            line_of(&newlines, record_start(bytes, p.byte()))
        })
    };
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(bytes);
    let mut record = csv::ByteRecord::new();
    let header_read = reader
        .read_byte_record(&mut record)
        .map_err(|e| csv_error(path, &e, &newlines, 1))?;
    if !header_read {
        return Err(LogError::Header {
            path: path.to_path_buf(),
            at: Cell {
                line: 1,
                column: None,
            },
            reason: format!("no header line; expected {}", expected_header(spec)),
        });
    }
    let header_line = line_at(&record, 1);
    let present = read_header(&record, path, header_line, spec)?;
    let n_fields = record.len();
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); spec.columns.len()];
    let mut lines = Vec::new();
    let time = spec.columns.iter().position(|c| c.name == "time");
    let mut previous_time: Option<f64> = None;
    loop {
        let more = reader.read_byte_record(&mut record).map_err(|e| {
            csv_error(
                path,
                &e,
                &newlines,
                lines.last().copied().unwrap_or(header_line),
            )
        })?;
        if !more {
            break;
        }
        let line = line_at(&record, 0);
        if record.len() != n_fields {
            return Err(LogError::Syntax {
                path: path.to_path_buf(),
                line,
                reason: format!(
                    "{} fields, but the header has {n_fields} (every row needs a value in every column)",
                    record.len()
                ),
            });
        }
        for (i, (c, p)) in spec.columns.iter().zip(&present).enumerate() {
            let Some((pos, unit)) = p else { continue };
            let at = || Cell {
                line,
                column: Some((pos + 1, header_text(c.name, unit.spelling))),
            };
            let v = parse_value(&record[*pos], c, unit).map_err(|reason| LogError::Value {
                path: path.to_path_buf(),
                at: at(),
                reason,
            })?;
            if Some(i) == time {
                if let Some(prev) = previous_time {
                    let strict = spec.time == TimeOrder::Increasing;
                    if v < prev || (strict && v == prev) {
                        return Err(LogError::Time {
                            path: path.to_path_buf(),
                            at: at(),
                            previous: prev,
                            time: v,
                            strict,
                        });
                    }
                }
                previous_time = Some(v);
            }
            values[i].push(v);
        }
        lines.push(line);
    }
    Ok(Table {
        spec: *spec,
        present,
        values,
        lines,
    })
}

/// The header a file of `spec` needs, for messages (`time[s], beacon, range[m]`).
pub fn expected_header(spec: &FileSpec) -> String {
    spec.columns
        .iter()
        .map(|c| {
            let h = if c.quantity.has_unit() {
                format!("{}[{}]", c.name, c.quantity.si())
            } else {
                c.name.to_string()
            };
            if c.required || in_group(spec, c.name) {
                h
            } else {
                format!("({h})")
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn in_group(spec: &FileSpec, name: &str) -> bool {
    spec.groups.iter().any(|g| g.contains(&name))
}

fn read_header(
    record: &csv::ByteRecord,
    path: &Path,
    line: u64,
    spec: &FileSpec,
) -> Result<Vec<Option<(usize, Unit)>>, LogError> {
    let err = |column: Option<(usize, String)>, reason: String| LogError::Header {
        path: path.to_path_buf(),
        at: Cell { line, column },
        reason,
    };
    let mut present: Vec<Option<(usize, Unit)>> = vec![None; spec.columns.len()];
    for (pos, raw) in record.iter().enumerate() {
        let text = std::str::from_utf8(raw).map_err(|_| {
            err(
                Some((pos + 1, String::from_utf8_lossy(raw).into_owned())),
                "the header is not valid UTF-8 text".into(),
            )
        })?;
        let here = Some((pos + 1, text.to_string()));
        let (name, unit) = split_header(text).map_err(|r| err(here.clone(), r))?;
        let Some(i) = spec.columns.iter().position(|c| c.name == name) else {
            return Err(err(
                here,
                format!(
                    "unknown column `{}`; `{}` has the columns {}",
                    echo(name),
                    spec.file,
                    expected_header(spec)
                ),
            ));
        };
        if present[i].is_some() {
            return Err(err(here, format!("column `{}` appears twice", echo(name))));
        }
        let c = &spec.columns[i];
        let unit = match (c.quantity.has_unit(), unit) {
            (false, None) => Unit::none(),
            (false, Some(u)) => {
                return Err(err(
                    here,
                    format!(
                        "column `{name}` is a number without unit; write `{name}`, not `{name}[{}]`",
                        echo(u)
                    ),
                ));
            }
            (true, None) => {
                return Err(err(
                    here,
                    format!(
                        "column `{name}` needs its unit in brackets, e.g. `{name}[{}]` ({} accepted)",
                        c.quantity.si(),
                        c.quantity.accepted()
                    ),
                ));
            }
            (true, Some(u)) => c.quantity.conversion(u).ok_or_else(|| LogError::Unit {
                path: path.to_path_buf(),
                at: Cell {
                    line,
                    column: here.clone(),
                },
                unit: u.into(),
                what: c.quantity.describe(),
                accepted: c.quantity.accepted().into(),
            })?,
        };
        present[i] = Some((pos, unit));
    }
    // Required columns, and exactly one complete group of alternatives.
    for (c, p) in spec.columns.iter().zip(&present) {
        if c.required && !in_group(spec, c.name) && p.is_none() {
            return Err(err(
                None,
                format!(
                    "missing column `{}`; `{}` needs the columns {}",
                    c.name,
                    spec.file,
                    expected_header(spec)
                ),
            ));
        }
    }
    if !spec.groups.is_empty() {
        let has = |n: &str| {
            spec.columns
                .iter()
                .position(|c| c.name == n)
                .is_some_and(|i| present[i].is_some())
        };
        let touched: Vec<&&[&str]> = spec
            .groups
            .iter()
            .filter(|g| g.iter().any(|n| has(n)))
            .collect();
        let alternatives = spec
            .groups
            .iter()
            .map(|g| g.join(", "))
            .collect::<Vec<_>>()
            .join(" or ");
        match touched.as_slice() {
            [one] => {
                if let Some(missing) = one.iter().find(|n| !has(n)) {
                    return Err(err(
                        None,
                        format!(
                            "missing column `{missing}` (the columns {} go together)",
                            one.join(", ")
                        ),
                    ));
                }
            }
            [] => {
                return Err(err(
                    None,
                    format!("missing columns: `{}` needs {alternatives}", spec.file),
                ));
            }
            _ => {
                return Err(err(
                    None,
                    format!(
                        "columns of two alternatives; `{}` has either {alternatives}",
                        spec.file
                    ),
                ));
            }
        }
    }
    Ok(present)
}

fn parse_value(raw: &[u8], c: &ColumnSpec, unit: &Unit) -> Result<f64, String> {
    let text = std::str::from_utf8(raw).map_err(|_| "not valid UTF-8 text".to_string())?;
    if text.is_empty() {
        return Err("empty cell (every row needs a value in every column)".into());
    }
    let v: f64 = text
        .parse()
        .map_err(|_| format!("`{}` is not a number", echo(text)))?;
    if !v.is_finite() {
        return Err(format!("`{}` is not a finite number", echo(text)));
    }
    let si = unit.to_si(v);
    let bound = c.quantity.bound();
    if si.is_nan() || si.abs() > bound {
        return Err(format!(
            "{text}{} is beyond the plausible magnitude of {} ({bound:e} {})",
            if unit.spelling.is_empty() {
                String::new()
            } else {
                format!(" {}", unit.spelling)
            },
            c.quantity.describe(),
            c.quantity.si()
        ));
    }
    match c.check {
        Check::Any => {}
        Check::NonNegative if si < 0.0 => return Err(format!("{text} is negative")),
        Check::Integer if si.fract() != 0.0 => return Err(format!("{text} is not a whole number")),
        Check::Flag if si != 0.0 && si != 1.0 => return Err(format!("{text} is not 0 or 1")),
        Check::Latitude if si.abs() >= std::f64::consts::FRAC_PI_2 => {
            return Err(format!(
                "latitude {text} is not strictly between -90° and 90°"
            ));
        }
        _ => {}
    }
    Ok(si)
}

#[cfg(test)]
mod tests {
    use super::*;

    const RANGES: FileSpec = FileSpec {
        file: "ranges.csv",
        columns: &[
            ColumnSpec::required("time", Quantity::Time, Check::Any),
            ColumnSpec::required("beacon", Quantity::Count, Check::Integer),
            ColumnSpec::required("range", Quantity::Length, Check::NonNegative),
            ColumnSpec::optional("heading", Quantity::Angle, Check::Any),
        ],
        groups: &[],
        time: TimeOrder::NonDecreasing,
    };

    const IMU: FileSpec = FileSpec {
        file: "imu.csv",
        columns: &[
            ColumnSpec::required("time", Quantity::Time, Check::Any),
            ColumnSpec::required("gyro_x", Quantity::AngularRate, Check::Any),
            ColumnSpec::required("dtheta_x", Quantity::Angle, Check::Any),
        ],
        groups: &[&["gyro_x"], &["dtheta_x"]],
        time: TimeOrder::Increasing,
    };

    fn parse(text: &str) -> Result<Table, LogError> {
        parse_table(text.as_bytes(), Path::new("log/ranges.csv"), &RANGES)
    }

    fn err(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    #[test]
    fn reads_any_column_order_units_comments_blank_lines_and_crlf() {
        let t = parse(
            "\u{feff}# a comment\r\nrange[m], time[s],beacon, heading[deg]\r\n\r\n1.5,0.0,3,90\r\n# mid\n2.5, 0.0 ,4,180\n",
        )
        .unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(t.column("time"), &[0.0, 0.0]);
        assert_eq!(t.column("beacon"), &[3.0, 4.0]);
        assert_eq!(t.column("range"), &[1.5, 2.5]);
        assert!((t.column("heading")[1] - std::f64::consts::PI).abs() < 1e-15);
        assert_eq!(t.unit("heading"), Some("deg"));
        assert_eq!(t.line(0), 4);
        assert_eq!(t.line(1), 6);
        assert_eq!(
            t.cell(1, "beacon").to_string(),
            "line 6, column 3 (`beacon`)"
        );
        // The optional column may be absent.
        let t = parse("time[s],beacon,range[m]\n1,2,3\n").unwrap();
        assert!(!t.has("heading") && t.optional("heading").is_none());
        // A header alone is a file without rows.
        assert!(parse("time[s],beacon,range[m]\n").unwrap().is_empty());
    }

    #[test]
    fn bad_files_name_file_line_and_column() {
        let cases = [
            ("", "ranges.csv` line 1: no header line"),
            ("time[s],range[m]\n", "missing column `beacon`"),
            (
                "time[s],beacon,range[m],speed[m/s]\n",
                "column 4 (`speed[m/s]`): unknown column `speed`",
            ),
            (
                "time[s],beacon,range[m],range[m]\n",
                "column 4 (`range[m]`): column `range` appears twice",
            ),
            (
                "time[s],beacon,range[ft]\n",
                "line 1, column 3 (`range[ft]`): unit `ft` is not a length; use one of: m",
            ),
            (
                "time[s],beacon,range\n",
                "column `range` needs its unit in brackets, e.g. `range[m]`",
            ),
            (
                "time[s],beacon[m],range[m]\n",
                "column `beacon` is a number without unit",
            ),
            (
                "time[s],beacon,range[m\n",
                "a unit is written in brackets at the end",
            ),
            (
                "time[s],beacon,range[m]\n1,2\n",
                "ranges.csv` line 2: 2 fields, but the header has 3",
            ),
            (
                "time[s],beacon,range[m]\n1,2,x\n",
                "line 2, column 3 (`range[m]`): `x` is not a number",
            ),
            (
                "time[s],beacon,range[m]\n1,2,NaN\n",
                "line 2, column 3 (`range[m]`): `NaN` is not a finite number",
            ),
            (
                "time[s],beacon,range[m]\n1,2,inf\n",
                "`inf` is not a finite number",
            ),
            ("time[s],beacon,range[m]\n1,2,\n", "empty cell"),
            ("time[s],beacon,range[m]\n1,2,-1\n", "-1 is negative"),
            (
                "time[s],beacon,range[m]\n1,2.5,1\n",
                "column 2 (`beacon`): 2.5 is not a whole number",
            ),
            (
                "time[s],beacon,range[m]\n1,2,1e308\n",
                "beyond the plausible magnitude of a length",
            ),
            (
                "time[s],beacon,range[m]\n2,1,1\n\n1,1,1\n",
                "line 4, column 1 (`time[s]`): time 1 s is before the previous row's 2 s (times must not decrease)",
            ),
            ("time[s],beacon,range[m]\n1,1,\u{0}\n", "is not a number"),
        ];
        for (text, want) in cases {
            let e = err(text);
            assert!(e.starts_with("`log/ranges.csv` "), "{e}");
            assert!(e.contains(want), "{text:?}: {e}");
        }
        // Invalid UTF-8 in a cell.
        let e = parse_table(
            b"time[s],beacon,range[m]\n1,1,\xff\n",
            Path::new("r.csv"),
            &RANGES,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 2") && e.contains("UTF-8"), "{e}");
    }

    #[test]
    fn strict_time_and_groups_of_alternatives() {
        let p = |t: &str| parse_table(t.as_bytes(), Path::new("imu.csv"), &IMU);
        assert!(
            p("time[s],gyro_x[deg/s]\n0,1\n1,1\n")
                .unwrap()
                .has("gyro_x")
        );
        assert!(p("time[s],dtheta_x[rad]\n0,1\n").unwrap().has("dtheta_x"));
        let e = p("time[s],gyro_x[rad/s]\n0,1\n0,1\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 3") && e.contains("is not after") && e.contains("increase strictly"),
            "{e}"
        );
        let e = p("time[s]\n").unwrap_err().to_string();
        assert!(e.contains("needs gyro_x or dtheta_x"), "{e}");
        let e = p("time[s],gyro_x[rad/s],dtheta_x[rad]\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("two alternatives"), "{e}");
        let e = p("time[s],gyro_x[m/s]\n").unwrap_err().to_string();
        assert!(
            e.contains("unit `m/s` is not an angular rate; use one of: rad/s, deg/s, deg/h"),
            "{e}"
        );
    }
}

//! The own-data layout (version 1, `docs/own-data.md`): a log is a folder with a
//! manifest `log.toml` (format, version, kind) and one CSV file per sensor, each with
//! a header naming its columns and their units (`range[m]`, `heading[deg]`), time in
//! seconds. Three kinds exist, one per family of estimators fathom has:
//!
//! - [`range_beacon`]: range-beacon localization (wheel odometry, or DVL + heading;
//!   ranges to the beacons of a beacon table; depth; optional ground truth);
//! - [`ins_dvl`]: INS / DVL navigation (IMU increments or rates, DVL velocity, depth,
//!   echo sounder, propeller RPM; optional ground truth);
//! - [`gnss_ins`]: GNSS / INS navigation of a drone (IMU rates, GNSS fixes with their
//!   accuracy, baro, magnetometer, range sensor; the autopilot's estimate as a
//!   reference track; optional ground truth), what `fathom log from-ulog` writes.
//!
//! Reading converts every value into SI once ([`units`]) and checks it: a missing
//! file or column, a wrong unit, NaN, an implausible magnitude, time going backwards,
//! an unknown beacon id all stop with a [`LogError`] naming the file, the line and the
//! column. The parsers work on bytes ([`FileSet`]), so the fuzz target and the tests
//! need no files; [`FileSet::read_dir`] is the only place that touches the disk.
//! Writing ([`write_log`]) is what the Plaza converter and the example generator use.

pub mod convert;
pub mod error;
pub mod gnss_ins;
pub mod ins_dvl;
pub mod range_beacon;
mod specs;
pub mod table;
pub mod units;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub use error::{Cell, LogError};
pub use specs::DEPTH;
pub use table::{Check, ColumnSpec, FileSpec, Table, TimeOrder, expected_header, parse_table};
pub use units::Quantity;

/// The manifest's file name.
pub const MANIFEST: &str = "log.toml";

/// The largest data file read (a log's, the Plaza files), bytes (1 GiB): a device or
/// a runaway file is refused instead of filling the memory.
pub const MAX_FILE_BYTES: u64 = 1 << 30;
/// The `format` value of a manifest.
pub const FORMAT: &str = "fathom-log";
/// The layout version this fathom reads and writes.
pub const VERSION: u32 = 1;

/// The kinds of log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum LogKind {
    /// Range-beacon localization ([`range_beacon`]).
    #[serde(rename = "range-beacon")]
    RangeBeacon,
    /// INS / DVL navigation ([`ins_dvl`]).
    #[serde(rename = "ins-dvl")]
    InsDvl,
    /// GNSS / INS navigation of a drone ([`gnss_ins`]).
    #[serde(rename = "gnss-ins")]
    GnssIns,
}

impl LogKind {
    /// The spelling in `log.toml` and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            LogKind::RangeBeacon => "range-beacon",
            LogKind::InsDvl => "ins-dvl",
            LogKind::GnssIns => "gnss-ins",
        }
    }

    /// `a `range-beacon` log` / `an `ins-dvl` log`, for messages.
    pub fn a_log(self) -> &'static str {
        match self {
            LogKind::RangeBeacon => "a `range-beacon` log",
            LogKind::InsDvl => "an `ins-dvl` log",
            LogKind::GnssIns => "a `gnss-ins` log",
        }
    }

    /// Every file a log of this kind may hold (besides the manifest).
    pub fn files(self) -> Vec<&'static str> {
        match self {
            LogKind::RangeBeacon => range_beacon::SPECS.iter().map(|s| s.file).collect(),
            LogKind::InsDvl => ins_dvl::SPECS.iter().map(|s| s.file).collect(),
            LogKind::GnssIns => gnss_ins::SPECS.iter().map(|s| s.file).collect(),
        }
    }
}

/// `log.toml`: what the folder is.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Always `"fathom-log"`.
    pub format: String,
    /// The layout version (this fathom: 1).
    pub version: u32,
    /// `"range-beacon"`, `"ins-dvl"` or `"gnss-ins"`.
    pub kind: LogKind,
    /// Free text: where the data come from.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
}

impl Manifest {
    /// A version-1 manifest of `kind`.
    pub fn new(kind: LogKind, description: impl Into<String>) -> Self {
        Self {
            format: FORMAT.into(),
            version: VERSION,
            kind,
            description: description.into(),
        }
    }

    /// Parses and checks a manifest text (`path` labels errors).
    ///
    /// # Errors
    /// [`LogError::Manifest`] for a TOML error, another format, another version.
    pub fn parse(text: &str, path: &Path) -> Result<Self, LogError> {
        let bad = |reason: String| LogError::Manifest {
            path: path.to_path_buf(),
            reason,
        };
        let m: Manifest = toml::from_str(text).map_err(|e| {
            bad(e
                .to_string()
                .lines()
                .filter(|l| !l.trim().is_empty())
                .collect::<Vec<_>>()
                .join("; "))
        })?;
        if m.format != FORMAT {
            return Err(bad(format!(
                "key `format`: must be \"{FORMAT}\", got \"{}\"",
                fathom_core::echo::echo(&m.format)
            )));
        }
        if m.version != VERSION {
            return Err(bad(format!(
                "key `version`: this fathom reads version {VERSION} of the layout, got {}",
                m.version
            )));
        }
        Ok(m)
    }

    /// The manifest as TOML.
    pub fn to_text(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}

/// The files of a log folder in memory: the manifest and every known CSV file
/// present, as bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileSet {
    /// The folder (labels errors).
    pub dir: PathBuf,
    /// The manifest.
    pub manifest: Manifest,
    /// File name -> content, for the files of the kind that exist.
    pub files: BTreeMap<&'static str, Vec<u8>>,
}

impl FileSet {
    /// Reads the manifest and every file of its kind that exists in `dir`. A file
    /// in the folder that the kind does not know is an error (a misspelt name would
    /// otherwise be silently ignored).
    ///
    /// # Errors
    /// [`LogError::NoFolder`], [`LogError::MissingFile`] (no manifest),
    /// [`LogError::Manifest`], [`LogError::Io`], [`LogError::Inconsistent`] for an
    /// unknown CSV file.
    pub fn read_dir(dir: impl AsRef<Path>) -> Result<Self, LogError> {
        let dir = dir.as_ref();
        if !dir.is_dir() {
            return Err(LogError::NoFolder {
                dir: dir.to_path_buf(),
            });
        }
        let manifest_path = dir.join(MANIFEST);
        if !manifest_path.exists() {
            return Err(LogError::MissingFile {
                path: manifest_path,
                why: "every log folder starts with `log.toml` (format = \"fathom-log\", version = 1, \
                      kind = \"range-beacon\", \"ins-dvl\" or \"gnss-ins\"); see docs/own-data.md"
                    .into(),
            });
        }
        let text =
            String::from_utf8(read_log_file(&manifest_path)?).map_err(|_| LogError::Manifest {
                path: manifest_path.clone(),
                reason: "not valid UTF-8 text".into(),
            })?;
        let manifest = Manifest::parse(&text, &manifest_path)?;
        let known = manifest.kind.files();
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .map_err(|source| LogError::Io {
                path: dir.to_path_buf(),
                source,
            })?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.to_ascii_lowercase().ends_with(".csv"))
            .collect();
        names.sort();
        if let Some(unknown) = names.iter().find(|n| !known.contains(&n.as_str())) {
            return Err(LogError::Inconsistent {
                path: dir.join(unknown),
                reason: format!(
                    "a `{}` log has no file of this name; its files are {} (docs/own-data.md)",
                    manifest.kind.name(),
                    known.join(", ")
                ),
            });
        }
        let mut files = BTreeMap::new();
        for name in known {
            let path = dir.join(name);
            // Anything of that name is read: a FIFO or a device is refused, not skipped.
            if path.exists() {
                files.insert(name, read_log_file(&path)?);
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            manifest,
            files,
        })
    }

    /// Checks that the manifest says `kind` (what the parser of that kind reads).
    ///
    /// # Errors
    /// [`LogError::Manifest`] naming the key `kind` and both kinds.
    pub fn expect_kind(&self, kind: LogKind) -> Result<(), LogError> {
        if self.manifest.kind == kind {
            return Ok(());
        }
        Err(LogError::Manifest {
            path: self.path(MANIFEST),
            reason: format!(
                "key `kind`: this is a `{}` log, not {}",
                self.manifest.kind.name(),
                kind.a_log()
            ),
        })
    }

    /// The path of file `name` in the folder (for messages).
    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// Whether file `name` is present.
    pub fn has(&self, name: &str) -> bool {
        self.files.contains_key(name)
    }

    /// Parses file `spec.file`, if present.
    ///
    /// # Errors
    /// As [`parse_table`].
    pub fn table(&self, spec: &FileSpec) -> Result<Option<Table>, LogError> {
        self.files
            .get(spec.file)
            .map(|bytes| parse_table(bytes, &self.path(spec.file), spec))
            .transpose()
    }

    /// Parses file `spec.file`, which the log needs for `why`.
    ///
    /// # Errors
    /// [`LogError::MissingFile`] when absent, else as [`parse_table`].
    pub fn required(&self, spec: &FileSpec, why: &str) -> Result<Table, LogError> {
        self.table(spec)?.ok_or_else(|| LogError::MissingFile {
            path: self.path(spec.file),
            why: format!("{why}; its header: {}", expected_header(spec)),
        })
    }
}

/// Reads one file of a log folder as [`read_regular_file`] does.
///
/// # Errors
/// [`LogError::Io`] naming the file: unreadable, not a regular file, too large.
pub fn read_log_file(path: &Path) -> Result<Vec<u8>, LogError> {
    read_regular_file(path).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads a regular file of at most [`MAX_FILE_BYTES`]; the type is checked before the
/// file is opened, so that a FIFO cannot block the reader and a device is not read.
///
/// # Errors
/// The I/O error, or one of kind `InvalidInput` saying that the file is not a
/// regular file or is too large.
pub fn read_regular_file(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let too_large = |bytes: u64| {
        Error::new(
            ErrorKind::InvalidInput,
            format!("{bytes} bytes or more, above the limit of {MAX_FILE_BYTES} bytes"),
        )
    };
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(Error::new(ErrorKind::InvalidInput, "not a regular file"));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// Checks that `table` has exactly one row (`initial.csv`).
///
/// # Errors
/// [`LogError::Inconsistent`] naming the file and the row count.
pub fn single_row(table: &Table, path: &Path) -> Result<(), LogError> {
    if table.len() == 1 {
        Ok(())
    } else {
        Err(LogError::Inconsistent {
            path: path.to_path_buf(),
            reason: format!(
                "needs exactly one data row (the start of the log), found {}",
                table.len()
            ),
        })
    }
}

/// A number as the writer prints it: the shortest text that reads back to the same
/// `f64` (plain for ordinary magnitudes, scientific for very large or small ones).
pub fn number_text(x: f64) -> String {
    if x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A CSV text: the header cells and the rows, numbers written by [`number_text`]
/// (`csv::Writer`: `,` between cells, `\n` line ends, a header cell quoted only if it
/// holds a comma, a quote or a line break).
pub fn csv_text(header: &[&str], rows: impl IntoIterator<Item = Vec<f64>>) -> String {
    let mut out = Vec::new();
    {
        let mut w = csv::WriterBuilder::new()
            .terminator(csv::Terminator::Any(b'\n'))
            .quote_style(csv::QuoteStyle::Necessary)
            .flexible(true)
            .from_writer(&mut out);
        // Writing into memory cannot fail: no I/O, and `flexible` leaves the record
        // lengths to the caller (the tables' own checks read them back).
        let _ = w.write_record(header);
        for row in rows {
            let _ = w.write_record(row.into_iter().map(number_text));
        }
        let _ = w.flush();
    }
    // Header cells are `str` and numbers ASCII: the bytes are UTF-8.
    String::from_utf8_lossy(&out).into_owned()
}

/// The CSV text of a `(time, value)` file: header `time[s]` and `value_header`.
pub fn series_text(value_header: &str, rows: &[(f64, f64)]) -> String {
    csv_text(
        &["time[s]", value_header],
        rows.iter().map(|r| vec![r.0, r.1]),
    )
}

/// Writes a log folder: the manifest and the given `(file name, CSV text)` files.
/// Creates `dir`; refuses a folder that already holds a `log.toml` or any of the
/// files (a log is never overwritten).
///
/// # Errors
/// [`LogError::Inconsistent`] for an existing log, [`LogError::Io`] for write
/// failures.
pub fn write_log(
    dir: &Path,
    manifest: &Manifest,
    files: &[(&str, String)],
) -> Result<(), LogError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| LogError::Io { path, source }
    };
    for name in std::iter::once(MANIFEST).chain(files.iter().map(|f| f.0)) {
        if dir.join(name).exists() {
            return Err(LogError::Inconsistent {
                path: dir.join(name),
                reason: "exists already; fathom writes a log only into a new or empty folder"
                    .into(),
            });
        }
    }
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let manifest_path = dir.join(MANIFEST);
    std::fs::write(&manifest_path, manifest.to_text()).map_err(io(&manifest_path))?;
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A file set of `kind` in the folder `log` from `(file name, text)` pairs (the
    /// parsers' tests).
    pub(crate) fn file_set(kind: LogKind, files: &[(&'static str, &str)]) -> FileSet {
        FileSet {
            dir: "log".into(),
            manifest: Manifest::new(kind, ""),
            files: files
                .iter()
                .map(|(n, t)| (*n, t.as_bytes().to_vec()))
                .collect(),
        }
    }

    #[test]
    fn manifest_round_trip_and_errors_name_the_key() {
        let m = Manifest::new(LogKind::InsDvl, "sea trial");
        let text = m.to_text();
        assert_eq!(Manifest::parse(&text, Path::new("log.toml")).unwrap(), m);
        let p = Path::new("d/log.toml");
        let e = |t: &str| Manifest::parse(t, p).unwrap_err().to_string();
        assert!(
            e("format = \"fathom-log\"\nversion = 2\nkind = \"ins-dvl\"\n")
                .contains("key `version`: this fathom reads version 1 of the layout, got 2")
        );
        assert!(e("format = \"csv\"\nversion = 1\nkind = \"ins-dvl\"\n").contains("key `format`"));
        assert!(e("format = \"fathom-log\"\nversion = 1\nkind = \"gps\"\n").contains("gps"));
        assert!(e("format = \"fathom-log\"\nversion = 1\n").contains("kind"));
        assert!(
            e("format = \"fathom-log\"\nversion = 1\nkind = \"ins-dvl\"\nx = 1\n").contains("`x`")
        );
    }

    #[test]
    fn numbers_read_back_bit_for_bit() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1e-300,
            1.234_567_890_123_4e9,
            -3e20,
            5e-5,
            f64::MIN_POSITIVE,
        ] {
            let t = number_text(x);
            assert_eq!(
                t.parse::<f64>().unwrap().to_bits(),
                x.to_bits(),
                "{x} -> {t}"
            );
            assert!(t.len() < 26, "{t}");
        }
        assert_eq!(
            csv_text(&["a[m]", "b"], [vec![1.5, 2.0]]),
            "a[m],b\n1.5,2\n"
        );
        assert_eq!(
            csv_text(&["t[s]", "x"], [vec![-0.0, 1e-300], vec![f64::NAN, -3e20]]),
            "t[s],x\n-0,1e-300\nNaN,-3e20\n"
        );
    }

    #[test]
    fn read_dir_needs_a_manifest_and_refuses_unknown_files() {
        let dir = std::env::temp_dir().join(format!("fathom-layout-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert!(matches!(
            FileSet::read_dir(&dir),
            Err(LogError::NoFolder { .. })
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let e = FileSet::read_dir(&dir).unwrap_err().to_string();
        assert!(e.contains("log.toml") && e.contains("missing"), "{e}");
        write_log(
            &dir.join("a"),
            &Manifest::new(LogKind::RangeBeacon, ""),
            &[("ranges.csv", "time[s],beacon,range[m]\n".into())],
        )
        .unwrap();
        let set = FileSet::read_dir(dir.join("a")).unwrap();
        assert!(set.has("ranges.csv") && !set.has("truth.csv"));
        // Writing over an existing log is refused.
        let again = write_log(
            &dir.join("a"),
            &Manifest::new(LogKind::RangeBeacon, ""),
            &[],
        );
        assert!(again.unwrap_err().to_string().contains("exists already"));
        std::fs::write(dir.join("a/range.csv"), "x").unwrap();
        let e = FileSet::read_dir(dir.join("a")).unwrap_err().to_string();
        assert!(e.contains("range.csv") && e.contains("ranges.csv"), "{e}");
    }
}

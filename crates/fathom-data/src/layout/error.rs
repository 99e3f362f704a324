//! [`LogError`]: everything that can be wrong with a log in the own-data layout, each
//! naming the file and, where there is one, the 1-based line and column.

use std::path::PathBuf;

use fathom_core::echo::{echo, echo_list, echo_message, echo_path};

/// Where in a CSV file an error sits: the 1-based line and, when one cell is at fault,
/// the 1-based column and its header name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cell {
    /// 1-based line of the file (the header is line 1 unless comments precede it).
    pub line: u64,
    /// 1-based column and the column's name, when one cell is at fault.
    pub column: Option<(usize, String)>,
}

impl std::fmt::Display for Cell {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}", self.line)?;
        if let Some((c, name)) = &self.column {
            write!(f, ", column {c} (`{}`)", echo(name))?;
        }
        Ok(())
    }
}

/// Everything that can be wrong with a log folder in the own-data layout
/// (`docs/own-data.md`).
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The folder does not exist or is not a directory.
    #[error("log folder `{}` does not exist or is not a directory", echo_path(dir))]
    NoFolder {
        /// The folder.
        dir: PathBuf,
    },
    /// A file the log needs is absent.
    #[error("`{}`: missing: {}", echo_path(path), echo_message(why))]
    MissingFile {
        /// The file expected.
        path: PathBuf,
        /// Why the log needs it.
        why: String,
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
    /// `log.toml` is not a valid manifest.
    #[error("`{}`: {}", echo_path(path), echo_message(reason))]
    Manifest {
        /// The manifest file.
        path: PathBuf,
        /// What is wrong (key, value).
        reason: String,
    },
    /// The header names a column the file does not have, or misses one it needs.
    #[error("`{}` {at}: {}", echo_path(path), echo_message(reason))]
    Header {
        /// The file.
        path: PathBuf,
        /// The header line and the column at fault.
        at: Cell,
        /// What is wrong and what was expected.
        reason: String,
    },
    /// A column's unit is not one the layout accepts for it.
    #[error(
        "`{}` {at}: unit `{}` is not {what}; use one of: {accepted}",
        echo_path(path),
        echo(unit)
    )]
    Unit {
        /// The file.
        path: PathBuf,
        /// The header line and column.
        at: Cell,
        /// The unit written.
        unit: Box<str>,
        /// What the column measures (`an angle`).
        what: &'static str,
        /// The accepted spellings.
        accepted: Box<str>,
    },
    /// A row cannot be split into the header's fields (count, quoting, encoding).
    #[error("`{}` line {line}: {}", echo_path(path), echo_message(reason))]
    Syntax {
        /// The file.
        path: PathBuf,
        /// The 1-based line.
        line: u64,
        /// What is wrong.
        reason: String,
    },
    /// A cell is not an acceptable value (not a number, NaN, infinite, out of range,
    /// not a whole number, ...).
    #[error("`{}` {at}: {}", echo_path(path), echo_message(reason))]
    Value {
        /// The file.
        path: PathBuf,
        /// Line and column.
        at: Cell,
        /// What is wrong, with the text found.
        reason: String,
    },
    /// Time does not increase as the file requires.
    #[error(
        "`{}` {at}: time {time} s is {} the previous row's {previous} s (times must {})",
        echo_path(path),
        if *strict { "not after" } else { "before" },
        if *strict { "increase strictly" } else { "not decrease" }
    )]
    Time {
        /// The file.
        path: PathBuf,
        /// Line and the time column.
        at: Cell,
        /// The previous row's time, s.
        previous: f64,
        /// This row's time, s.
        time: f64,
        /// Whether equal stamps are refused too.
        strict: bool,
    },
    /// A range names a beacon the beacon table does not list.
    #[error(
        "`{}` {at}: unknown beacon id {id} (`beacons.csv` lists {})",
        echo_path(path),
        echo_list(known)
    )]
    UnknownBeacon {
        /// The range file.
        path: PathBuf,
        /// Line and the beacon column.
        at: Cell,
        /// The id read.
        id: i64,
        /// The ids of the beacon table.
        known: Vec<i64>,
    },
    /// The files of the folder do not fit together (e.g. two motion sources, a file
    /// the log's motion model cannot use, a row count the file must not have).
    #[error("`{}`: {}", echo_path(path), echo_message(reason))]
    Inconsistent {
        /// The file (or folder) concerned.
        path: PathBuf,
        /// What does not fit.
        reason: String,
    },
}

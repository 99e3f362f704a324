//! The error type of the output layer: writing files, refusing non-finite numbers,
//! drawing figures, claiming an output folder.

use std::path::PathBuf;

/// Everything that can go wrong while writing fathom's outputs.
///
/// Variants carry the file or the argument concerned; wrapped causes are exposed
/// through [`std::error::Error::source`].
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Reading or writing a file or directory failed.
    #[error("cannot {action} `{}`", path.display())]
    Io {
        /// What was attempted ("read", "write", "create directory", ...).
        action: &'static str,
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },

    /// A bad argument (an output folder that cannot be claimed, mismatched sizes).
    #[error("invalid {what}: {reason}")]
    InvalidArgument {
        /// Which argument or input (e.g. `--out`).
        what: String,
        /// Why it is rejected.
        reason: String,
    },

    /// An output value that must be finite is NaN or infinite (JSON cannot hold it).
    #[error("{what}: value is not finite ({value})")]
    NonFinite {
        /// Where the value sits (e.g. "summary row `MF` / `mean_3d`: value").
        what: String,
        /// The offending value.
        value: f64,
    },

    /// A plot could not be drawn (bad input data or a drawing-backend failure).
    #[error("plot `{}`: {reason}", path.display())]
    Plot {
        /// The SVG file that was to be written.
        path: PathBuf,
        /// What went wrong (e.g. "series `EFF` is empty", "series `MF` point 3 is NaN").
        reason: String,
    },

    /// Writing a CSV / Markdown output was refused (ragged columns, bad header, ...).
    #[error("output `{}`: {reason}", path.display())]
    Output {
        /// The file that was to be written.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },

    /// JSON (de)serialization failed.
    #[error("JSON `{}`", path.display())]
    Json {
        /// The JSON file concerned.
        path: PathBuf,
        /// The underlying serde_json error.
        #[source]
        source: serde_json::Error,
    },
}

impl ReportError {
    /// Whether the error is in what the user gave (an `--out` folder that cannot be
    /// claimed, a file they named that cannot be read or is not valid JSON): exit code
    /// 2 of the `fathom` command; writing an output is fathom's own failure.
    pub fn is_user_error(&self) -> bool {
        match self {
            ReportError::InvalidArgument { .. } => true,
            ReportError::Io { action, .. } => matches!(*action, "read" | "list directory"),
            ReportError::Json { source, .. } => matches!(
                source.classify(),
                serde_json::error::Category::Syntax | serde_json::error::Category::Eof
            ),
            _ => false,
        }
    }

    /// Build an [`ReportError::InvalidArgument`].
    pub fn invalid_argument(what: impl Into<String>, reason: impl Into<String>) -> Self {
        ReportError::InvalidArgument {
            what: what.into(),
            reason: reason.into(),
        }
    }

    /// Build an [`ReportError::Io`].
    pub fn io(action: &'static str, path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        ReportError::Io {
            action,
            path: path.into(),
            source,
        }
    }
}

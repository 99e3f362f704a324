//! The error type of the runner: file I/O, scenario parsing and validation, the
//! outputs' errors (wrapped), and experiment selection.

use std::path::PathBuf;

use fathom_core::CoreError;
use fathom_core::echo::{echo, echo_file, echo_list, echo_message, echo_path};

/// Everything that can go wrong in `fathom-sim` and in the jobs it runs (the paper
/// experiments of `fathom-experiments` and the replays of `fathom-replay` return it
/// from the [`Experiment`](crate::Experiment) methods they implement).
///
/// Variants carry the file, key path, row or experiment concerned. Wrapped causes are
/// exposed through [`std::error::Error::source`], so `anyhow`'s `{:#}` prints the full
/// chain (e.g. `experiment `noise` failed: cannot read `scenarios/noise.toml`: No such
/// file or directory`).
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// Reading or writing a file or directory failed.
    #[error("cannot {action} `{}`", echo_path(path))]
    Io {
        /// What was attempted ("read", "write", "create directory", ...).
        action: &'static str,
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },

    /// A TOML file could not be parsed or does not match the scenario schema
    /// (syntax error, unknown key, wrong type, missing field).
    #[error("{}", toml_message(file, key_path.as_deref(), *line, *column, message))]
    Toml {
        /// The file (or label) the text came from.
        file: String,
        /// Dotted key path (e.g. `noise.range_sigma`) when it is known.
        key_path: Option<String>,
        /// 1-based line of the offending text, when known.
        line: Option<usize>,
        /// 1-based column (in characters) of the offending text, when known.
        column: Option<usize>,
        /// The parser's / deserializer's message (e.g. "unknown field `foo`, expected ...").
        message: String,
    },

    /// A scenario value parsed fine but is not allowed
    /// (e.g. `noise.toml: key `noise.range_sigma`: must be > 0, got -0.1`).
    #[error(
        "{}: key `{}`: {}",
        echo_file(file),
        echo(key_path),
        echo_message(reason)
    )]
    Invalid {
        /// The file (or label) the value came from.
        file: String,
        /// Dotted key path of the value.
        key_path: String,
        /// Why it is rejected, including the offending value.
        reason: String,
    },

    /// A bad argument to a function of this crate (not tied to a scenario file).
    #[error("invalid {}: {}", echo_message(what), echo_message(reason))]
    InvalidArgument {
        /// Which argument or input.
        what: String,
        /// Why it is rejected.
        reason: String,
    },

    /// `--only NAME` names no registered experiment.
    #[error(
        "unknown experiment `{}`; known experiments: {}",
        echo(name),
        known_list(known)
    )]
    UnknownExperiment {
        /// The requested name.
        name: String,
        /// The registered names, in registry order.
        known: Vec<String>,
    },

    /// Writing a CSV / Markdown output was refused (ragged columns, bad header, ...).
    #[error("output `{}`: {}", echo_path(path), echo_message(reason))]
    Output {
        /// The file that was to be written.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },

    /// JSON (de)serialization failed.
    #[error("JSON `{}`", echo_path(path))]
    Json {
        /// The JSON file concerned.
        path: PathBuf,
        /// The underlying serde_json error.
        #[source]
        source: serde_json::Error,
    },

    /// Writing an output failed, or an output folder could not be claimed.
    #[error(transparent)]
    Report(#[from] fathom_report::ReportError),

    /// A statistic could not be computed (empty or non-finite input, ...).
    #[error(transparent)]
    Stats(#[from] fathom_stats::StatsError),

    /// A `fathom-core` check failed inside an experiment.
    #[error(transparent)]
    Core(#[from] CoreError),

    /// An error from a model crate (trajectory, sensors, estimators, stats), with context.
    #[error("{context}")]
    Model {
        /// What the experiment was doing (e.g. "simulating DVL for run 17").
        context: String,
        /// The underlying error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },

    /// The user's input could not be used while preparing an experiment: a data
    /// folder or file the scenario or the command line names is missing, unreadable
    /// or malformed, or the scenario's values fail a model's own checks. Counted as
    /// the user's error ([`SimError::is_user_error`]); the message is the cause's.
    #[error(transparent)]
    Input(Box<SimError>),

    /// An experiment's run function failed.
    #[error("experiment `{name}` failed")]
    Experiment {
        /// The experiment name.
        name: String,
        /// The error it returned.
        #[source]
        source: Box<SimError>,
    },
}

impl SimError {
    /// Build an [`SimError::Invalid`] (validation failure of a scenario value).
    pub fn invalid(
        file: impl Into<String>,
        key_path: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        SimError::Invalid {
            file: file.into(),
            key_path: key_path.into(),
            reason: reason.into(),
        }
    }

    /// Whether the error is in what the user wrote (flags, scenario, data path or
    /// data): exit code 2 of the `fathom` command; anything else is a failure of fathom
    /// itself (exit code 1). Reading a file the user named is the user's; writing an
    /// output after the run was checked is fathom's.
    pub fn is_user_error(&self) -> bool {
        match self {
            SimError::Toml { .. }
            | SimError::Invalid { .. }
            | SimError::InvalidArgument { .. }
            | SimError::UnknownExperiment { .. }
            | SimError::Input(_) => true,
            SimError::Io { action, .. } => matches!(*action, "read" | "list directory"),
            SimError::Experiment { source, .. } => source.is_user_error(),
            SimError::Report(e) => e.is_user_error(),
            // A file the user gave that is not valid JSON (a corrupted shard record);
            // writing JSON never fails with these categories.
            SimError::Json { source, .. } => matches!(
                source.classify(),
                serde_json::error::Category::Syntax | serde_json::error::Category::Eof
            ),
            _ => false,
        }
    }

    /// Build an [`SimError::InvalidArgument`].
    pub fn invalid_argument(what: impl Into<String>, reason: impl Into<String>) -> Self {
        SimError::InvalidArgument {
            what: what.into(),
            reason: reason.into(),
        }
    }

    /// Wrap an error from a model crate with context, for use in
    /// `.map_err(|e| SimError::model("simulating DVL", e))`.
    pub fn model(
        context: impl Into<String>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        SimError::Model {
            context: context.into(),
            source: Box::new(source),
        }
    }

    /// Build an [`SimError::Io`].
    pub fn io(action: &'static str, path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        SimError::Io {
            action,
            path: path.into(),
            source,
        }
    }
}

fn toml_message(
    file: &str,
    key_path: Option<&str>,
    line: Option<usize>,
    column: Option<usize>,
    message: &str,
) -> String {
    let mut out = echo_file(file);
    if let Some(k) = key_path {
        out.push_str(&format!(": key `{}`", echo(k)));
    }
    match (line, column) {
        (Some(l), Some(c)) => out.push_str(&format!(": line {l}, column {c}")),
        (Some(l), None) => out.push_str(&format!(": line {l}")),
        _ => {}
    }
    out.push_str(": ");
    out.push_str(&echo_message(message).to_string());
    out
}

fn known_list(known: &[String]) -> String {
    if known.is_empty() {
        "(none registered)".to_string()
    } else {
        echo_list(known).to_string()
    }
}

//! [`UlogError`]: everything that can be wrong with a PX4 ULog file, each naming the
//! file and, where there is one, the byte offset, the topic or the field.

use std::path::PathBuf;

use fathom_core::echo::{echo, echo_message, echo_path};

/// Everything that can be wrong with a ULog file.
#[derive(Debug, thiserror::Error)]
pub enum UlogError {
    /// Reading failed (or the path is not a regular file).
    #[error("cannot read `{}`", echo_path(path))]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is empty.
    #[error("`{}`: the file is empty (0 bytes), not a ULog log", echo_path(path))]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The file ends inside the header or inside a message.
    #[error(
        "`{}`: truncated: the file ends at byte {len} inside a ULog {what}",
        echo_path(path)
    )]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The file's length, bytes.
        len: u64,
        /// `header` or `message`.
        what: &'static str,
    },
    /// A message cannot be decoded (bad magic, unknown message type, a data message
    /// of a format never defined or of the wrong size, a circular format, ...).
    #[error(
        "`{}`: malformed ULog data in the bytes {start}..{end}: {}",
        echo_path(path),
        echo_message(reason)
    )]
    Malformed {
        /// The file.
        path: PathBuf,
        /// First byte of the chunk that failed to decode.
        start: u64,
        /// One past its last byte.
        end: u64,
        /// The parser's reason.
        reason: String,
    },
    /// A topic the conversion needs is not in the log.
    #[error(
        "`{}`: the log has no `{topic}` messages: {}",
        echo_path(path),
        echo_message(why)
    )]
    TopicMissing {
        /// The file.
        path: PathBuf,
        /// The topic (or the alternatives, `a` or `b`).
        topic: String,
        /// What fathom needs it for.
        why: String,
    },
    /// A topic lacks a field the conversion reads (or has it with a non-numeric type).
    #[error(
        "`{}`: topic `{topic}` has no numeric field `{}` (another PX4 version's message layout?)",
        echo_path(path),
        echo(field)
    )]
    FieldMissing {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The field (or its alternatives).
        field: String,
    },
    /// A topic's time stamps go backwards.
    #[error(
        "`{}`: topic `{topic}`: time goes backwards, {time_us} us after {previous_us} us (message {index})",
        echo_path(path)
    )]
    TimeBackwards {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// 0-based index of the message among the topic's.
        index: usize,
        /// The previous stamp, microseconds.
        previous_us: u64,
        /// This stamp, microseconds.
        time_us: u64,
    },
    /// A topic holds more messages than fathom keeps in memory.
    #[error(
        "`{}`: topic `{topic}` has more than {limit} messages, the most fathom keeps of one topic",
        echo_path(path)
    )]
    TooManyMessages {
        /// The file.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The limit.
        limit: usize,
    },
    /// The messages are there but unusable (e.g. no GNSS fix at all, a value out of range).
    #[error("`{}`: {}", echo_path(path), echo_message(reason))]
    Unusable {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

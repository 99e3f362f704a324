//! PX4 ULog flight logs (`docs/own-data.md`, "Your drone logs"): a streaming reader
//! of the topics fathom uses ([`topics`], on PX4's `px4-ulog` parser: [`stream`]) and
//! their conversion into a `gnss-ins` log of the own-data layout ([`to_gnss_ins`]),
//! with PX4's local projection ([`projection`]).
//!
//! A broken file is a [`UlogError`] naming the file and the byte offset, the topic or
//! the field; the reader never panics and keeps at most
//! [`topics::MAX_MESSAGES_PER_TOPIC`] messages of a topic (fuzzed: `fuzz/fuzz_targets/ulog.rs`).

pub mod error;
pub mod projection;
pub mod stream;
pub mod to_gnss_ins;
pub mod topics;

pub use error::UlogError;
pub use to_gnss_ins::{Conversion, gnss_ins_from_ulog};
pub use topics::UlogTopics;

/// Reads the ULog file `path` and converts it into a `gnss-ins` log.
///
/// # Errors
/// As [`UlogTopics::read_file`] and [`gnss_ins_from_ulog`].
pub fn convert_file(path: &std::path::Path) -> Result<Conversion, UlogError> {
    gnss_ins_from_ulog(&UlogTopics::read_file(path)?, path)
}

/// Converts the ULog bytes `bytes` (labelled `path`) into a `gnss-ins` log (the fuzz
/// target and the tests).
///
/// # Errors
/// As [`UlogTopics::read`] and [`gnss_ins_from_ulog`].
pub fn convert_bytes(bytes: &[u8], path: &std::path::Path) -> Result<Conversion, UlogError> {
    gnss_ins_from_ulog(&UlogTopics::read(bytes, path)?, path)
}

#[cfg(test)]
mod tests;

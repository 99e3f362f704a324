//! Readers (and a minimal writer) for real data sets in their native file formats.
//!
//! - [`plaza`]: the CMU Plaza range-only data sets (`*_DR.txt` odometry, `*_TD.txt`
//!   ranges, `*_.mat` ground truth, beacon survey and dead-reckoned path);
//! - [`matv5`]: reading the numeric matrices of a MATLAB v5 file (plain or
//!   zlib-compressed elements; bounded and panic-free on malformed files, fuzzed), and
//!   writing numeric matrices as an uncompressed MATLAB v5 file (tests and tools that
//!   need to make a modified copy of a `.mat` file).
//!
//! - [`layout`]: fathom's own CSV layout for users' logs (`docs/own-data.md`): a
//!   folder with `log.toml` and one CSV file per sensor, header with units, for
//!   range-beacon localization, INS / DVL navigation and GNSS / INS navigation.
//! - [`ulog`]: PX4 ULog flight logs, read streaming (never whole) and converted into a
//!   `gnss-ins` log.
//!
//! Every error names the file and, for text files, the 1-based line (for `.mat`
//! matrices, the matrix and its 1-based row; for the CSV layout also the column).
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod layout;
pub mod matv5;
pub mod plaza;
pub mod ulog;

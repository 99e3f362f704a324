//! Output layer of fathom: what every run, replay, campaign merge and PILS session
//! writes, in one format.
//!
//! - [`output`]: the `summary.json` contract ([`Summary`](output::Summary), rows and
//!   claims), CSV series and Markdown / console tables;
//! - [`csv_writer`]: the one CSV writer ([`CsvWriter`](csv_writer::CsvWriter), a
//!   `csv::Writer` with fathom's settings) every CSV file goes through;
//! - [`plot`]: SVG line, plan-view, histogram, heat-map and sample-time figures;
//! - [`scene`]: the self-contained 3D scene page (`scene.html`, three.js inlined);
//! - [`outdir`]: the output folder that never loses work ([`OutDir`](outdir::OutDir):
//!   claim before computing, atomic commit, `run_info.json`).
//!
//! The crate has no fathom dependency: it draws and writes numbers that the
//! statistics and the experiments computed.
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod csv_writer;
pub mod error;
pub mod outdir;
pub mod output;
pub mod plot;
pub mod scene;

pub use error::ReportError;

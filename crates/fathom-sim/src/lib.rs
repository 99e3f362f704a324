//! Experiment layer of fathom: scenario files, reproducible parallel Monte Carlo runs,
//! the `summary.json` / CSV / Markdown / SVG outputs, and the paper-experiment driver
//! behind `cargo xtask paper`. This is the only fathom library crate that does file I/O.
//!
//! ```
//! use fathom_sim::montecarlo::run_monte_carlo;
//! use fathom_sim::output::{Claim, Row, Summary, summary_md_table};
//! use rand::Rng;
//!
//! // 100 runs, base seed 1, on 2 threads: run i draws from its own ChaCha8 stream, so the
//! // results are the same for any thread count.
//! let means: Vec<f64> = run_monte_carlo(100, 1, Some(2), |_run, rng| {
//!     (0..50).map(|_| rng.random::<f64>()).sum::<f64>() / 50.0
//! });
//! assert_eq!(means, run_monte_carlo(100, 1, Some(1), |_run, rng| {
//!     (0..50).map(|_| rng.random::<f64>()).sum::<f64>() / 50.0
//! }));
//!
//! let n = means.len() as f64;
//! let mean = means.iter().sum::<f64>() / n;
//! let sd = (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
//! let half = 1.96 * sd / n.sqrt();
//!
//! let mut summary = Summary::new("demo", "none.txt", 100, 1);
//! summary.push_row(Row::new("uniform", "mean", mean).with_paper(0.5).with_ci95(mean - half, mean + half));
//! summary.push_claim(Claim::new(
//!     "ci_covers_half",
//!     "the 95 % CI covers 0.5",
//!     (mean - 0.5).abs() <= half,
//!     format!("{mean:.4} ± {half:.4}"),
//! ));
//! let json = summary.to_json_pretty().unwrap();
//! assert!(json.starts_with("{\n  \"experiment\": \"demo\""));
//! assert!(summary_md_table(&summary, 3).contains("| uniform | mean | 0.500 |"));
//! ```
//!
//! Modules:
//! - [`scenario`]: TOML scenario loading with file / key / line error messages;
//! - [`cost`]: a scenario's samples, memory and run time before it runs, and the limits;
//! - [`montecarlo`]: [`run_monte_carlo`](montecarlo::run_monte_carlo) and its seeding rule;
//! - [`output`]: [`Summary`](output::Summary) (`summary.json`), CSV and Markdown helpers;
//! - [`progress`]: the progress hook of long Monte Carlo batches (the library never prints);
//! - [`plot`]: SVG line, plan-view, histogram, heat-map and sample-time figures;
//! - [`experiment`]: the [`Experiment`] registry type and
//!   [`run_paper`];
//! - [`experiments`]: the registered paper experiments.

pub mod cost;
pub mod data;
pub mod driver;
pub mod error;
pub mod example_log;
pub mod experiment;
pub mod experiments;
pub mod method_list;
pub mod montecarlo;
pub mod output;
pub mod plot;
pub mod progress;
pub mod replay;
pub mod scenario;
pub mod scenario_docs;
pub mod user_run;

pub use driver::{PaperOptions, PaperResult, error_chain, run_paper};
pub use error::SimError;
pub use experiment::{DynExperiment, Experiment};

//! The runner of fathom: scenario files, the [`Experiment`] trait, reproducible
//! parallel Monte Carlo runs, the cost model, and the driver that takes any job
//! (a paper experiment of `fathom-experiments`, a replay of `fathom-replay`) through
//! one pipeline into `fathom-report`'s outputs, `cargo xtask paper` and sharded
//! campaigns included.
//!
//! ```
//! use fathom_sim::montecarlo::run_monte_carlo;
//! use fathom_report::output::{Claim, Row, Summary, summary_md_table};
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
//! summary.push_row(
//!     Row::new("uniform", "mean", mean)
//!         .with_unit("1")
//!         .with_paper(0.5)
//!         .with_ci95(mean - half, mean + half, "normal"),
//! );
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
//! - [`progress`]: the progress hook of long Monte Carlo batches (the library never prints);
//! - [`experiment`]: the [`Experiment`] trait and its object-safe face
//!   [`DynExperiment`];
//! - [`driver`]: the pipeline ([`run_paper`], one experiment into its output folder,
//!   campaigns);
//! - [`method_list`]: `methods = [...]` selections and method names;
//! - [`parameter_key`]: the scenario key behind a parameter check's error.
//! - [`user_run`]: `fathom run` / `fathom check` of any scenario file.

pub mod cost;
pub mod driver;
pub mod error;
pub mod experiment;
pub mod method_list;
pub mod montecarlo;
pub mod parameter_key;
pub mod progress;
pub mod scenario;
pub mod statistics;
pub mod user_run;

pub use driver::{PaperOptions, PaperResult, error_chain, run_paper};
pub use error::SimError;
pub use experiment::{DynExperiment, Experiment};
/// Bounded echoes of user input in messages (`fathom_core::echo`), for the front ends.
pub use fathom_core::echo;

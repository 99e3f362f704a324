//! Running a registered experiment from Rust and reading its summary: the `beacons`
//! preset with 4 Monte Carlo runs, in memory (nothing written to disk), then the mean
//! 3D error of each update scheme with its 95 % confidence interval and the claims.
//!
//! Run with `cargo run --release --example run_experiment` from the repository root.

use fathom::experiments::registry;
use fathom::sim::experiment::{Environment, Job};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let beacons = registry()
        .into_iter()
        .find(|e| e.name() == "beacons")
        .ok_or("no beacons experiment")?;
    let job = Job {
        text: beacons.preset(),
        file: beacons.default_scenario(),
        runs: Some(4),
        seed: Some(7),
        threads: None,
        progress: None,
        env: Environment::new(std::env::current_dir()?),
    };
    let done = beacons.execute(&job)?;
    let s = &done.summary;
    println!(
        "{}: {} runs, base seed {}",
        s.experiment, s.runs, s.base_seed
    );
    for row in s.rows.iter().filter(|r| r.metric == "mean") {
        let ci = row
            .ci95
            .map_or(String::new(), |[lo, hi]| format!(" [{lo:.4}, {hi:.4}]"));
        println!("  {:<10} mean 3D error {:.4} m{ci}", row.method, row.value);
    }
    for c in &s.claims {
        println!(
            "  [{}] {}",
            if c.holds { "holds" } else { "does not hold" },
            c.text
        );
    }
    println!(
        "{} figures and CSV files computed (write them with fathom run)",
        done.analysis.files().len()
    );
    Ok(())
}

//! `fathom`: the command-line tool. Its first subcommand replays range-beacon
//! localization on a recorded data set:
//!
//! ```text
//! fathom replay plaza <DIR> [--config FILE] [--out DIR]
//! ```
//!
//! `DIR` holds one CMU Plaza data set in its native files (`*_DR.txt`, `*_TD.txt`,
//! `*_.mat`). The command runs pure dead reckoning and the EKF under the AS, SC and SI
//! update schemes (plus ablations) and writes per-time CSV series, `summary.json`,
//! `report.md` and SVG figures into `--out` (default `plaza-replay`). Settings come
//! from `--config` or, by default, the built-in copy of `scenarios/plaza.toml`.
//!
//! Exit codes: 0 success, 2 usage or configuration error (bad arguments, unreadable or
//! invalid settings file, data folder missing), 1 a failure while running (a data file
//! that cannot be read or is malformed, an estimator or output error). Errors are
//! printed as one message with their whole cause chain.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, anyhow};
use clap::{Args, Parser, Subcommand};
use fathom_sim::data::plaza::{PlazaError, PlazaLog};
use fathom_sim::replay::plaza::{PlazaSettings, parse_settings, replay};
use fathom_sim::replay::plaza_output::{write_outputs, write_standalone};

/// The built-in settings (a copy of `scenarios/plaza.toml` at build time).
const DEFAULT_PLAZA_CONFIG: &str = include_str!("../../../scenarios/plaza.toml");

#[derive(Debug, Parser)]
#[command(
    name = "fathom",
    version,
    about = "Run, compare and evaluate navigation estimators on recorded data."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Replay estimators on a recorded data set and score them against ground truth.
    #[command(subcommand)]
    Replay(ReplayData),
}

#[derive(Debug, Subcommand)]
enum ReplayData {
    /// CMU Plaza range-only data: wheel odometry, ranges to radio beacons, ground truth.
    Plaza(PlazaArgs),
}

#[derive(Debug, Args)]
struct PlazaArgs {
    /// Folder holding the data set's `*_DR.txt`, `*_TD.txt` and `*_.mat` files.
    dir: PathBuf,
    /// Settings file (TOML, the schema of `scenarios/plaza.toml`); default: built in.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Output folder (created if needed).
    #[arg(long, value_name = "DIR", default_value = "plaza-replay")]
    out: PathBuf,
}

/// A failure and its exit code.
#[derive(Debug)]
enum Failure {
    /// Usage or configuration error: exit code 2.
    Usage(anyhow::Error),
    /// Failure while running: exit code 1.
    Run(anyhow::Error),
}

fn load_settings(config: Option<&Path>) -> Result<(PlazaSettings, String), Failure> {
    match config {
        None => {
            let label = "built-in scenarios/plaza.toml";
            parse_settings(DEFAULT_PLAZA_CONFIG, label)
                .map(|s| (s, label.to_string()))
                .map_err(|e| Failure::Usage(anyhow!(e)))
        }
        Some(path) => {
            let label = path.display().to_string();
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read settings file `{label}`"))
                .map_err(Failure::Usage)?;
            parse_settings(&text, &label)
                .map(|s| (s, label))
                .map_err(|e| Failure::Usage(anyhow!(e)))
        }
    }
}

fn replay_plaza(args: &PlazaArgs) -> Result<String, Failure> {
    let (settings, label) = load_settings(args.config.as_deref())?;
    let log = PlazaLog::read_dir(&args.dir, settings.range_order).map_err(|e| {
        let usage = matches!(e, PlazaError::NoFolder { .. });
        let e = anyhow!(e).context("cannot read the Plaza data");
        if usage {
            Failure::Usage(e)
        } else {
            Failure::Run(e)
        }
    })?;
    let result =
        replay(&log, &settings).map_err(|e| Failure::Run(anyhow!(e).context("replay failed")))?;
    let outputs = write_outputs(&result, &args.out)
        .and_then(|o| write_standalone(&o, &args.out, &args.dir, &label).map(|()| o))
        .map_err(|e| Failure::Run(anyhow!(e).context("cannot write the outputs")))?;
    let mut text = format!(
        "{}: {} odometry rows, {} ranges, {} ground-truth rows; settings: {label}\n\n",
        result.data_name, result.rows.0, result.rows.1, result.rows.2
    );
    text.push_str(&format!(
        "{:<22} {:>9} {:>9} {:>9} {:>9} {:>9}\n",
        "method", "mean [m]", "std [m]", "max [m]", "rmse [m]", "rejected"
    ));
    for m in &result.methods {
        text.push_str(&format!(
            "{:<22} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9}\n",
            m.name, m.stats.mean, m.stats.std, m.stats.max, m.stats.rmse, m.rejected
        ));
    }
    text.push('\n');
    for c in &outputs.summary.claims {
        text.push_str(&format!(
            "[{}] {}: {}\n",
            if c.holds { "holds" } else { "does not hold" },
            c.id,
            c.detail
        ));
    }
    text.push_str(&format!("\noutputs: {}\n", args.out.display()));
    Ok(text)
}

fn run(cli: &Cli) -> Result<String, Failure> {
    match &cli.command {
        Command::Replay(ReplayData::Plaza(args)) => replay_plaza(args),
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout with success; usage errors exit with 2.
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match run(&cli) {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(Failure::Usage(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_definition_is_valid() {
        Cli::command().debug_assert();
    }

    #[test]
    fn parses_replay_plaza() {
        let cli = Cli::try_parse_from([
            "fathom", "replay", "plaza", "data/p1", "--config", "c.toml", "--out", "o",
        ])
        .unwrap();
        let Command::Replay(ReplayData::Plaza(a)) = cli.command;
        assert_eq!(a.dir, PathBuf::from("data/p1"));
        assert_eq!(a.config, Some(PathBuf::from("c.toml")));
        assert_eq!(a.out, PathBuf::from("o"));
        let cli = Cli::try_parse_from(["fathom", "replay", "plaza", "d"]).unwrap();
        let Command::Replay(ReplayData::Plaza(a)) = cli.command;
        assert_eq!(a.out, PathBuf::from("plaza-replay"));
        assert!(a.config.is_none());
    }

    #[test]
    fn usage_errors_are_reported() {
        for args in [
            vec!["fathom"],
            vec!["fathom", "replay"],
            vec!["fathom", "replay", "plaza"],
            vec!["fathom", "replay", "other", "d"],
            vec!["fathom", "replay", "plaza", "d", "--fast"],
        ] {
            let e = Cli::try_parse_from(&args).unwrap_err();
            assert!(e.use_stderr(), "{args:?}");
        }
    }

    #[test]
    fn built_in_settings_parse_and_bad_settings_are_usage_errors() {
        assert!(load_settings(None).is_ok());
        let dir = std::env::temp_dir().join(format!("fathom-cli-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.toml");
        std::fs::write(
            &bad,
            DEFAULT_PLAZA_CONFIG.replace("sigma_m = 1.0", "sigma_m = -1.0"),
        )
        .unwrap();
        match load_settings(Some(&bad)) {
            Err(Failure::Usage(e)) => {
                let s = format!("{e:#}");
                assert!(
                    s.contains("ranges.sigma_m") && s.contains("bad.toml"),
                    "{s}"
                );
            }
            other => panic!("expected a usage error, got {other:?}"),
        }
        assert!(matches!(
            load_settings(Some(&dir.join("missing.toml"))),
            Err(Failure::Usage(_))
        ));
        let args = PlazaArgs {
            dir: dir.join("no-such-folder"),
            config: None,
            out: dir.join("out"),
        };
        assert!(matches!(replay_plaza(&args), Err(Failure::Usage(_))));
        std::fs::create_dir_all(dir.join("empty")).unwrap();
        let args = PlazaArgs {
            dir: dir.join("empty"),
            ..args
        };
        match replay_plaza(&args) {
            Err(Failure::Run(e)) => assert!(format!("{e:#}").contains("_DR.txt"), "{e:#}"),
            other => panic!("expected a run failure, got {other:?}"),
        }
    }
}

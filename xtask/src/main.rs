//! Project automation. `cargo xtask codegen` regenerates `docs/scenarios.md`;
//! `cargo xtask paper [--only NAME] [--runs N] [--threads T] [--out DIR] [--force]`
//! reproduces the papers' experiments into `target/paper/` (README, "Quick start":
//! the output contract); `cargo xtask bench [--compare]
//! [FILTER]` runs the benchmarks into `target/bench/bench.json` (see
//! `docs/performance.md`).

mod bench;
mod scenario_docs;
#[cfg(test)]
mod tidy;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use fathom_sim::{PaperOptions, run_paper};

const USAGE: &str = "\
usage: cargo xtask <command> [options]

commands:
  paper    run the paper experiments, write target/paper/<experiment>/ and
           target/paper/REPORT.md, print paper-versus-reproduced tables
  bench    run the criterion benchmarks (cargo bench --workspace), write
           target/bench/bench.json and print a table with the performance targets
           (`cargo xtask bench raycast --mesh city.obj`: the ray-casting benches)
  codegen  regenerate docs/scenarios.md from the scenario types' doc comments
           (a test fails when the committed file is out of date)
  help     show this message

options of `paper`:
  --only NAME     run only experiment NAME
  --runs N        override every experiment's Monte Carlo run count (N >= 1)
  --threads T     worker threads (T >= 1; default: all cores)
  --out DIR       output root instead of target/paper
  --force         write an experiment's folder even if it holds files fathom did
                  not write (they are kept; only fathom's own files are replaced)

options of `bench`:
  --compare       also time FilterPy's KalmanFilter on the same 6/3 problem
                  (needs python3 + filterpy; skipped with a message otherwise)
  --mesh FILE     an OBJ mesh in NED metres for the `raycast/mesh` bench
  FILTER          only benchmarks whose name contains FILTER (criterion filter)";

/// A parsed command line.
#[derive(Debug, PartialEq, Eq)]
enum Command {
    Help,
    Codegen,
    Bench {
        compare: bool,
        mesh: Option<PathBuf>,
        filter: Option<String>,
    },
    Paper {
        only: Option<String>,
        runs: Option<usize>,
        threads: Option<usize>,
        out: Option<PathBuf>,
        force: bool,
    },
}

/// Parse the arguments after the program name; `Err` is a usage error message.
fn parse_args(args: &[String]) -> Result<Command, String> {
    let Some((cmd, rest)) = args.split_first() else {
        return Err("missing command".into());
    };
    match cmd.as_str() {
        "help" | "-h" | "--help" => return Ok(Command::Help),
        "codegen" if rest.is_empty() => return Ok(Command::Codegen),
        "codegen" => {
            return Err(format!(
                "`codegen` takes no arguments, got `{}`",
                rest.join(" ")
            ));
        }
        "paper" => {}
        "bench" => return parse_bench(rest),
        other => return Err(format!("unknown command `{other}`")),
    }
    let (mut only, mut runs, mut threads, mut out, mut force) = (None, None, None, None, false);
    let mut i = 0;
    while i < rest.len() {
        let arg = rest[i].as_str();
        if arg == "-h" || arg == "--help" {
            return Ok(Command::Help);
        }
        if arg == "--force" {
            force = true;
            i += 1;
            continue;
        }
        // Accept both `--flag value` and `--flag=value`.
        let (flag, inline) = match arg.split_once('=') {
            Some((f, v)) if f.starts_with("--") => (f, Some(v.to_string())),
            _ => (arg, None),
        };
        if !matches!(flag, "--only" | "--runs" | "--threads" | "--out") {
            return Err(format!("unknown option `{arg}`"));
        }
        let value = match inline {
            Some(v) => v,
            None => {
                i += 1;
                rest.get(i)
                    .cloned()
                    .ok_or_else(|| format!("option `{flag}` needs a value"))?
            }
        };
        let count = |v: &str| -> Result<usize, String> {
            match v.parse::<usize>() {
                Ok(n) if n >= 1 => Ok(n),
                _ => Err(format!(
                    "option `{flag}` needs a whole number >= 1, got `{v}`"
                )),
            }
        };
        match flag {
            "--only" if value.is_empty() => return Err("option `--only` needs a name".into()),
            "--only" => only = Some(value),
            "--out" if value.is_empty() => return Err("option `--out` needs a folder".into()),
            "--out" => out = Some(PathBuf::from(value)),
            "--runs" => runs = Some(count(&value)?),
            _ => threads = Some(count(&value)?),
        }
        i += 1;
    }
    Ok(Command::Paper {
        only,
        runs,
        threads,
        out,
        force,
    })
}

/// `bench [--compare] [--mesh FILE] [FILTER]`.
fn parse_bench(rest: &[String]) -> Result<Command, String> {
    let (mut compare, mut mesh, mut filter) = (false, None, None);
    let mut args = rest.iter();
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "-h" | "--help" => return Ok(Command::Help),
            "--compare" => compare = true,
            "--mesh" => match args.next() {
                Some(f) if !f.is_empty() => mesh = Some(PathBuf::from(f)),
                _ => return Err("option `--mesh` needs a file".into()),
            },
            a if a.starts_with("--mesh=") && a.len() > 7 => mesh = Some(PathBuf::from(&a[7..])),
            a if a.starts_with('-') => return Err(format!("unknown option `{a}`")),
            a if filter.is_none() => filter = Some(a.to_string()),
            a => return Err(format!("unexpected argument `{a}` (one FILTER at most)")),
        }
    }
    Ok(Command::Bench {
        compare,
        mesh,
        filter,
    })
}

/// The workspace root: the parent of this crate's manifest directory.
fn workspace_root() -> Result<PathBuf> {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .map(Path::to_path_buf)
        .with_context(|| format!("xtask manifest dir `{}` has no parent", manifest.display()))
}

/// `cargo xtask paper`; the error is the user's (exit code 2) or fathom's (1).
fn paper(
    only: Option<String>,
    runs: Option<usize>,
    threads: Option<usize>,
    out: Option<PathBuf>,
    force: bool,
) -> Result<(), (u8, anyhow::Error)> {
    let root = workspace_root().map_err(|e| (1, e))?;
    let options = PaperOptions {
        only,
        runs,
        threads,
        out_root: out.unwrap_or_else(|| root.join("target").join("paper")),
        workspace_root: root,
        force,
    };
    let result = run_paper(options, &fathom_experiments::registry()).map_err(|e| {
        let code = if e.is_user_error() { 2 } else { 1 };
        (
            code,
            anyhow::Error::new(e).context("cargo xtask paper failed"),
        )
    })?;
    println!(
        "{} experiment(s) done; report: {}",
        result.experiments.len(),
        result.report_path.display()
    );
    Ok(())
}

/// `cargo xtask codegen`: writes docs/scenarios.md.
fn codegen() -> Result<()> {
    let path = workspace_root()?.join("docs").join("scenarios.md");
    let text = scenario_docs::render(&fathom_experiments::registry());
    std::fs::write(&path, text).with_context(|| format!("cannot write `{}`", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match parse_args(&args) {
        Err(msg) => {
            eprintln!("error: {msg}\n\n{USAGE}");
            ExitCode::from(2)
        }
        Ok(Command::Help) => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        Ok(Command::Codegen) => match codegen() {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::FAILURE
            }
        },
        Ok(Command::Bench {
            compare,
            mesh,
            filter,
        }) => {
            match workspace_root()
                .and_then(|root| bench::run(&root, compare, mesh.as_deref(), filter.as_deref()))
            {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::FAILURE
                }
            }
        }
        Ok(Command::Paper {
            only,
            runs,
            threads,
            out,
            force,
        }) => match paper(only, runs, threads, out, force) {
            Ok(()) => ExitCode::SUCCESS,
            Err((code, e)) => {
                eprintln!("error: {e:#}");
                ExitCode::from(code)
            }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Command, String> {
        let v: Vec<String> = s.split_whitespace().map(String::from).collect();
        parse_args(&v)
    }

    #[test]
    fn parses_paper_flags() {
        assert_eq!(
            parse("paper --only noise --runs 5 --threads=2 --out /tmp/p --force"),
            Ok(Command::Paper {
                only: Some("noise".into()),
                runs: Some(5),
                threads: Some(2),
                out: Some(PathBuf::from("/tmp/p")),
                force: true,
            })
        );
        assert_eq!(
            parse("paper"),
            Ok(Command::Paper {
                only: None,
                runs: None,
                threads: None,
                out: None,
                force: false,
            })
        );
        assert_eq!(parse("help"), Ok(Command::Help));
        assert_eq!(
            parse("bench --compare kf_"),
            Ok(Command::Bench {
                compare: true,
                mesh: None,
                filter: Some("kf_".into())
            })
        );
        assert_eq!(
            parse("bench"),
            Ok(Command::Bench {
                compare: false,
                mesh: None,
                filter: None
            })
        );
        for args in [
            "bench raycast --mesh city.obj",
            "bench --mesh=city.obj raycast",
        ] {
            assert_eq!(
                parse(args),
                Ok(Command::Bench {
                    compare: false,
                    mesh: Some(PathBuf::from("city.obj")),
                    filter: Some("raycast".into())
                })
            );
        }
        assert!(parse("bench --mesh").is_err());
        assert!(parse("bench --fast").is_err());
        assert!(parse("bench a b").is_err());
        assert_eq!(parse("paper --help"), Ok(Command::Help));
    }

    #[test]
    fn rejects_bad_arguments() {
        assert!(parse("").is_err());
        assert!(
            parse("build")
                .unwrap_err()
                .contains("unknown command `build`")
        );
        assert!(
            parse("paper --fast")
                .unwrap_err()
                .contains("unknown option `--fast`")
        );
        assert!(parse("paper --runs").unwrap_err().contains("needs a value"));
        assert!(parse("paper --runs 0").unwrap_err().contains(">= 1"));
        assert!(parse("paper --threads x").unwrap_err().contains("`x`"));
        assert!(parse("paper extra").is_err());
    }

    #[test]
    fn workspace_root_holds_the_workspace_manifest() {
        let root = workspace_root().unwrap();
        assert!(root.join("Cargo.toml").is_file());
        assert!(root.join("xtask").is_dir());
    }
}

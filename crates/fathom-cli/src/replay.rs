//! `fathom replay plaza|range-beacon|ins-dvl|gnss-ins [DIR]` and `fathom replay ulog
//! FILE.ulg` (the `gnss-ins` replay of a PX4 ULog converted in memory): a replay on recorded data, run as
//! a job of the driver like `fathom run` (the settings checked first, their `[data]
//! dir` replaced by `DIR` if given, then `fathom_sim::driver::execute_to` with command
//! `replay`), printed as `fathom run` prints: every row with its unit, then the checks
//! or claims.

use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow};
use clap::{Args, Subcommand};
use fathom_experiments::plaza::Plaza;
use fathom_replay::gnss_ins::GnssIns;
use fathom_replay::ins_dvl::InsDvl;
use fathom_replay::range_beacon::RangeBeacon;
use fathom_sim::driver::{WriteOptions, console_claims, console_rows, console_setup, execute_to};
use fathom_sim::experiment::{DynExperiment, Environment, Job};

use crate::{Failure, failure};

#[derive(Debug, Subcommand)]
pub(crate) enum ReplayData {
    /// CMU Plaza range-only data: wheel odometry, ranges to radio beacons, ground truth.
    Plaza(PlazaArgs),
    /// Your own range-beacon log (fathom's CSV layout, docs/own-data.md).
    RangeBeacon(RangeBeaconArgs),
    /// Your own INS / DVL log (fathom's CSV layout, docs/own-data.md).
    InsDvl(InsDvlArgs),
    /// A drone flight as a gnss-ins log (`fathom log from-ulog`): INS, GPS/INS with
    /// the 12- and 15-state filters, against PX4's EKF2 (and the truth in SITL).
    GnssIns(GnssInsArgs),
    /// A PX4 ULog flight log, converted in memory as `fathom log from-ulog` converts
    /// it, then replayed as `replay gnss-ins` replays the converted folder.
    Ulog(UlogArgs),
}

#[derive(Debug, Args)]
pub(crate) struct UlogArgs {
    /// The ULog file (`*.ulg`).
    pub(crate) file: PathBuf,
    /// Settings and methods (TOML, the schema of `scenarios/gnss-ins.toml`); default:
    /// built in.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    /// A world mesh (Wavefront OBJ or STL, the `urban` experiment's readers and
    /// limits) for the map-aided filters GREKF and MGPMF on the log's range beams
    /// (sets the settings' `[world] file`); the log must have range rows.
    #[arg(long, value_name = "FILE")]
    pub(crate) world: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) output: ReplayOut,
}

#[derive(Debug, Args)]
pub(crate) struct PlazaArgs {
    /// Folder holding the data set's `*_DR.txt`, `*_TD.txt` and `*_.mat` files
    /// (default: the settings' `[data] dir`, `data/plaza1`, looked up in the current
    /// directory and beside each of its ancestors: the repository's copy).
    pub(crate) dir: Option<PathBuf>,
    /// Settings file (TOML, the schema of `scenarios/plaza.toml`); default: built in.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    /// Output folder (default `fathom-out/plaza-replay`).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Write into a folder holding files fathom did not write (they are kept; only
    /// fathom's own files are replaced).
    #[arg(long)]
    pub(crate) force: bool,
    /// Not an option of a replay: accepted only to explain that it does not apply.
    #[arg(long, hide = true, value_name = "S")]
    pub(crate) seed: Option<String>,
}

/// Where an own-log replay writes (`--out`, `--force`).
#[derive(Debug, Args)]
pub(crate) struct ReplayOut {
    /// Output folder (default `fathom-out/<kind>-replay`, `<kind>` the replay's).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Write into a folder holding files fathom did not write (they are kept; only
    /// fathom's own files are replaced).
    #[arg(long)]
    pub(crate) force: bool,
}

/// `fathom replay range-beacon`.
#[derive(Debug, Args)]
pub(crate) struct RangeBeaconArgs {
    /// The range-beacon log folder (`log.toml`, `beacons.csv`, `initial.csv`,
    /// `ranges.csv`, the motion as `odometry.csv` or `dvl.csv` + `heading.csv`, optional
    /// `depth.csv` and `truth.csv`; docs/own-data.md); default: the settings' `[data] dir`
    /// (the repository's example log `data/logs/range-beacon-example`; `fathom log
    /// example range-beacon` and `fathom log from-plaza` write logs of this kind).
    pub(crate) dir: Option<PathBuf>,
    /// Settings and methods (TOML, the schema of `scenarios/range-beacon.toml`: range
    /// noise, gating, the AS / SC / SI schemes); default: built in.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) output: ReplayOut,
}

/// `fathom replay ins-dvl`.
#[derive(Debug, Args)]
pub(crate) struct InsDvlArgs {
    /// The INS / DVL log folder (`log.toml`, `initial.csv`, `imu.csv`, `dvl.csv`,
    /// optional `depth.csv`, `altitude.csv`, `rpm.csv` and `truth.csv`;
    /// docs/own-data.md); default: the settings' `[data] dir`
    /// (the repository's example log `data/logs/ins-dvl-example`; `fathom log example
    /// ins-dvl` writes logs of this kind).
    pub(crate) dir: Option<PathBuf>,
    /// Settings and methods (TOML, the schema of `scenarios/ins-dvl.toml`: sensor
    /// noise, the INS-DVL and RPM velocity filters); default: built in.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) output: ReplayOut,
}

/// `fathom replay gnss-ins`.
#[derive(Debug, Args)]
pub(crate) struct GnssInsArgs {
    /// The gnss-ins log folder (`log.toml`, `imu.csv`, `gnss.csv`, `reference.csv`,
    /// optional `baro.csv`, `mag.csv`, `range.csv` and `truth.csv`; `fathom log from-ulog` writes
    /// one; docs/own-data.md); default: the settings' `[data] dir` (the repository's
    /// `data/logs/gnss-ins-sitl`, a PX4 SITL flight converted from `data/ulog`).
    pub(crate) dir: Option<PathBuf>,
    /// Settings and methods (TOML, the schema of `scenarios/gnss-ins.toml`: IMU noise,
    /// GNSS floors and outages, the filters); default: built in.
    #[arg(long, value_name = "FILE")]
    pub(crate) config: Option<PathBuf>,
    /// A world mesh (Wavefront OBJ or STL, the `urban` experiment's readers and
    /// limits) for the map-aided filters GREKF and MGPMF on the log's range beams
    /// (sets the settings' `[world] file`); the log must have range rows.
    #[arg(long, value_name = "FILE")]
    pub(crate) world: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) output: ReplayOut,
}

/// What one replay command asks for.
struct Request<'a> {
    exp: &'static dyn DynExperiment,
    /// The data folder; `None`: the settings' `[data] dir`.
    dir: Option<&'a Path>,
    config: Option<&'a Path>,
    /// `--world` of the `gnss-ins` replays.
    world: Option<&'a Path>,
    out: PathBuf,
    force: bool,
}

/// `fathom replay ...`.
pub(crate) fn replay_cmd(cmd: &ReplayData) -> Result<String, Failure> {
    let request = match cmd {
        ReplayData::Plaza(a) => {
            if a.seed.is_some() {
                return Err(Failure::Usage(anyhow!(
                    "--seed does not apply to `replay plaza`: a replay on recorded data is \
                     deterministic (no random draws, no base seed)"
                )));
            }
            if let Some(dir) = a.dir.as_deref().filter(|d| !d.is_dir()) {
                return Err(Failure::Usage(anyhow!(
                    "cannot read the Plaza data: `{}` is not a folder",
                    dir.display()
                )));
            }
            Request {
                exp: &Plaza,
                dir: a.dir.as_deref(),
                config: a.config.as_deref(),
                world: None,
                out: a.out.clone().unwrap_or_else(|| replay_out(&Plaza)),
                force: a.force,
            }
        }
        ReplayData::RangeBeacon(a) => own(
            &RangeBeacon,
            a.dir.as_deref(),
            a.config.as_deref(),
            &a.output,
        ),
        ReplayData::InsDvl(a) => own(&InsDvl, a.dir.as_deref(), a.config.as_deref(), &a.output),
        ReplayData::GnssIns(a) => Request {
            world: a.world.as_deref(),
            ..own(&GnssIns, a.dir.as_deref(), a.config.as_deref(), &a.output)
        },
        ReplayData::Ulog(a) => {
            if !a.file.is_file() {
                return Err(Failure::Usage(anyhow!(
                    "cannot read the ULog `{}`: not a file",
                    a.file.display()
                )));
            }
            Request {
                exp: &GnssIns,
                dir: Some(a.file.as_path()),
                config: a.config.as_deref(),
                world: a.world.as_deref(),
                out: a.output.out.clone().unwrap_or_else(|| replay_out(&GnssIns)),
                force: a.output.force,
            }
        }
    };
    replay(&request)
}

/// The request of an own-log replay (`dir`, `config`, `output` as given).
fn own<'a>(
    exp: &'static dyn DynExperiment,
    dir: Option<&'a Path>,
    config: Option<&'a Path>,
    output: &ReplayOut,
) -> Request<'a> {
    Request {
        exp,
        dir,
        config,
        world: None,
        out: output.out.clone().unwrap_or_else(|| replay_out(exp)),
        force: output.force,
    }
}

/// The default output folder of `fathom replay <kind>`: `fathom-out/<kind>-replay`.
fn replay_out(exp: &dyn DynExperiment) -> PathBuf {
    crate::default_out(&format!("{}-replay", exp.name()))
}

/// The text and label of a settings file: `config` if given (unreadable: a usage
/// error), else the built-in `preset` labelled `preset_label`.
fn settings_text(
    config: Option<&Path>,
    preset: &str,
    preset_label: &str,
) -> Result<(String, String), Failure> {
    match config {
        None => Ok((preset.to_string(), preset_label.to_string())),
        Some(path) => {
            let label = path.display().to_string();
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read settings file `{label}`"))
                .map_err(Failure::Usage)?;
            Ok((text, label))
        }
    }
}

/// The settings text and its label: `--config` or the built-in preset, checked here
/// (before its `[data] dir` is replaced), so that a bad file is a usage error naming
/// its key and line.
fn load_settings(
    exp: &dyn DynExperiment,
    config: Option<&Path>,
    world: Option<&Path>,
) -> Result<(String, String), Failure> {
    let (text, label) = settings_text(
        config,
        exp.preset(),
        &format!("built-in {}", exp.default_scenario()),
    )?;
    let text = match world {
        Some(w) => with_world(&text, w)?,
        None => text,
    };
    exp.resolve(&text, &label, None, None).map_err(failure)?;
    Ok((text, label))
}

/// `text` with its `[world] file` set to `world` (made absolute; the table added
/// when missing).
fn with_world(text: &str, world: &Path) -> Result<String, Failure> {
    with_path(text, "world", "file", world, true)
}

/// `text` with `[table] key` set to `path` made absolute; a missing `[table]` is
/// added when `add_table`, else a usage error.
fn with_path(
    text: &str,
    table_name: &str,
    key: &str,
    path: &Path,
    add_table: bool,
) -> Result<String, Failure> {
    let mut table: toml::Table = toml::from_str(text)
        .context("settings")
        .map_err(Failure::Usage)?;
    let path = std::path::absolute(path)
        .with_context(|| format!("cannot resolve `{}`", path.display()))
        .map_err(Failure::Usage)?;
    if add_table && !table.contains_key(table_name) {
        table.insert(table_name.into(), toml::Value::Table(toml::Table::new()));
    }
    let sub = match table.get_mut(table_name) {
        None => {
            return Err(Failure::Usage(anyhow!(
                "settings: missing table `[{table_name}]`"
            )));
        }
        Some(v) => v
            .as_table_mut()
            .ok_or_else(|| Failure::Usage(anyhow!("settings: `{table_name}` is not a table")))?,
    };
    sub.insert(key.into(), toml::Value::String(path.display().to_string()));
    toml::to_string(&table)
        .context("settings")
        .map_err(Failure::Run)
}

/// The settings' `[data] dir`, as written.
fn data_dir_of(text: &str) -> Option<String> {
    let table: toml::Table = toml::from_str(text).ok()?;
    let dir = table.get("data")?.get("dir")?.as_str()?;
    Some(dir.to_string())
}

/// `text` with its `[data] dir` replaced by `dir` (made absolute).
fn with_data_dir(text: &str, dir: &Path) -> Result<String, Failure> {
    with_path(text, "data", "dir", dir, false)
}

fn replay(r: &Request<'_>) -> Result<String, Failure> {
    let (text, label) = load_settings(r.exp, r.config, r.world)?;
    let (text, data) = match r.dir {
        Some(dir) => (with_data_dir(&text, dir)?, dir.display().to_string()),
        None => {
            let data = data_dir_of(&text).unwrap_or_default();
            (text, format!("`{data}` (the settings' data.dir)"))
        }
    };
    let job = Job {
        text: &text,
        file: &label,
        runs: None,
        seed: None,
        threads: None,
        progress: None,
        env: Environment::new(crate::current_dir()?),
    };
    let options = WriteOptions {
        force: r.force,
        command: "replay".into(),
        scenario_files: true,
    };
    let (result, info) =
        execute_to(r.exp, &job, &r.out, &options).map_err(|e| match failure(e) {
            Failure::Usage(e) => Failure::Usage(e.context("replay failed")),
            Failure::Run(e) => Failure::Run(e.context("replay failed")),
        })?;
    let mut out = format!(
        "{} replay of {data} with {label}: done in {:.1} s (fathom {})\n",
        r.exp.name(),
        result.elapsed.as_secs_f64(),
        info.fathom_version
    );
    out.push_str(&console_setup(&result));
    out.push_str(&console_rows(&result));
    out.push_str(&console_claims(&result));
    out.push_str(&format!(
        "outputs: {} ({} figures, report.md, summary.json)\n",
        result.out_dir.display(),
        result.figures.len()
    ));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_sim::Experiment;

    #[test]
    fn built_in_settings_parse_and_bad_settings_are_usage_errors() {
        for exp in [
            &Plaza as &dyn DynExperiment,
            &RangeBeacon,
            &InsDvl,
            &GnssIns,
        ] {
            assert!(load_settings(exp, None, None).is_ok(), "{}", exp.name());
        }
        let dir = std::env::temp_dir().join(format!("fathom-cli-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.toml");
        std::fs::write(
            &bad,
            <Plaza as Experiment>::PRESET.replace("sigma_m = 1.0", "sigma_m = -1.0"),
        )
        .unwrap();
        match load_settings(&Plaza, Some(&bad), None) {
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
            load_settings(&Plaza, Some(&dir.join("missing.toml")), None),
            Err(Failure::Usage(_))
        ));
        let args = PlazaArgs {
            dir: Some(dir.join("no-such-folder")),
            config: None,
            out: Some(dir.join("out")),
            seed: None,
            force: false,
        };
        let plaza = |a: PlazaArgs| replay_cmd(&ReplayData::Plaza(a));
        assert!(matches!(plaza(args), Err(Failure::Usage(_))));
        std::fs::create_dir_all(dir.join("empty")).unwrap();
        let args = PlazaArgs {
            dir: Some(dir.join("empty")),
            config: None,
            out: Some(dir.join("out")),
            seed: None,
            force: false,
        };
        // A data folder without the data set is the user's input: exit code 2.
        match plaza(args) {
            Err(Failure::Usage(e)) => assert!(format!("{e:#}").contains("_DR.txt"), "{e:#}"),
            other => panic!("expected a usage error, got {other:?}"),
        }
        // A seed does not apply to a deterministic replay: a usage error, not ignored.
        let args = PlazaArgs {
            dir: Some(dir.join("empty")),
            config: None,
            out: Some(dir.join("out")),
            seed: Some("3".into()),
            force: false,
        };
        match plaza(args) {
            Err(Failure::Usage(e)) => assert!(format!("{e:#}").contains("--seed"), "{e:#}"),
            other => panic!("expected a usage error, got {other:?}"),
        }
        assert!(!dir.join("out").exists());
    }
}

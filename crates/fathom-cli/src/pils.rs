//! `fathom pils`: the processor-in-the-loop session (crate `fathom-pils`): the
//! simulator and the navigation as two processes on UDP with MAVLink 2.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, anyhow};
use clap::{Args, Subcommand};
use fathom_pils::report::SimReport;
use fathom_pils::session::Session;
use fathom_pils::settings::{Pacing, Settings};

use crate::Failure;
use crate::pils_session::{both, claim, commit, prepare, run_err, write_files};

/// `fathom pils ...`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct PilsArgs {
    #[command(subcommand)]
    side: Option<PilsSide>,
    /// An `urban` scenario file, or PILS settings (`experiment = "pils"`) naming
    /// one: both processes on loopback.
    scenario: Option<PathBuf>,
    /// Output folder.
    #[arg(long, value_name = "DIR", default_value = "fathom-out/pils")]
    out: PathBuf,
    #[command(flatten)]
    pick: Pick,
    /// Write into `--out` even if it holds files fathom did not write (they are kept).
    #[arg(long)]
    force: bool,
}

/// What is flown, overriding the file's choice.
#[derive(Debug, Clone, Default, Args)]
pub(crate) struct Pick {
    /// The scene flown (a `[[scenarios]]` name of the `urban` scenario).
    #[arg(long, value_name = "NAME")]
    pub(crate) scene: Option<String>,
    /// The navigation method (one of the scenario's `methods`).
    #[arg(long, value_name = "NAME")]
    pub(crate) method: Option<String>,
    /// The run index (run `N` of `fathom run`: its flight, noise and initial error).
    #[arg(long, value_name = "N")]
    pub(crate) run: Option<u64>,
    /// Do not write the 3D scene page `scene.html` (the simulator side writes it).
    #[arg(long)]
    pub(crate) no_scene: bool,
}

#[derive(Debug, Subcommand)]
enum PilsSide {
    /// The simulator process: sends the sensor stream to `--nav`, compares the
    /// solutions with the truth.
    Sim {
        /// Settings file.
        scenario: PathBuf,
        /// The navigation's address.
        #[arg(long, value_name = "ADDR")]
        nav: SocketAddr,
        /// Own address.
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:0")]
        bind: SocketAddr,
        #[command(flatten)]
        pick: Pick,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "fathom-out/pils-sim")]
        out: PathBuf,
        /// Write into `--out` even if it holds files fathom did not write.
        #[arg(long)]
        force: bool,
    },
    /// The navigation process: runs `--method` on what arrives at `--listen`.
    Nav {
        /// Settings file.
        scenario: PathBuf,
        /// Address to listen on (port 0: any free port; printed on stdout).
        #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:0")]
        listen: SocketAddr,
        /// Accept only this simulator address (default: the first valid sender).
        #[arg(long, value_name = "ADDR")]
        sim: Option<SocketAddr>,
        #[command(flatten)]
        pick: Pick,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "fathom-out/pils-nav")]
        out: PathBuf,
        /// Write into `--out` even if it holds files fathom did not write.
        #[arg(long)]
        force: bool,
    },
    /// The offline run of the same settings, in-process: its solutions as CSV.
    Offline {
        /// Settings file.
        scenario: PathBuf,
        /// With the MAVLink quantization of every message (what lockstep PILS sees).
        #[arg(long)]
        quantized: bool,
        #[command(flatten)]
        pick: Pick,
        /// Output folder: the solutions go into its `solutions.csv`.
        #[arg(long, value_name = "DIR", default_value = "fathom-out/pils-offline")]
        out: PathBuf,
    },
    /// Realtime vs lockstep over `--runs` runs: both processes per session, each run
    /// flown in lockstep (clean link) and in real time (the file's faults); per-run
    /// errors and the paired difference with 95 % CIs (docs/pils.md).
    Compare {
        /// Settings file.
        scenario: PathBuf,
        /// Runs (run indices `run`, `run + 1`, ...; at least 2).
        #[arg(long, value_name = "N", default_value_t = 10)]
        runs: usize,
        #[command(flatten)]
        pick: Pick,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "fathom-out/pils-compare")]
        out: PathBuf,
        /// Write into `--out` even if it holds files fathom did not write.
        #[arg(long)]
        force: bool,
    },
}

fn load(path: &Path, pick: &Pick) -> Result<Settings, Failure> {
    let mut s =
        Settings::load(path).map_err(|e| Failure::Usage(anyhow!("{}: {e}", path.display())))?;
    if pick.scene.is_some() {
        s.file.scene.clone_from(&pick.scene);
    }
    if pick.method.is_some() {
        s.file.method.clone_from(&pick.method);
    }
    if let Some(r) = pick.run {
        s.file.run = r;
    }
    s.scene_page = !pick.no_scene;
    Ok(s)
}

/// The `experiment` key of PILS settings.
pub(crate) const EXPERIMENT: &str = "pils";

/// `fathom check` of PILS settings: parsed, checked, the world built and the run
/// flown, as `fathom pils` does before touching a socket (exit 2 on any error).
pub(crate) fn check(path: &Path, quiet: bool) -> Result<String, Failure> {
    let s = load(path, &Pick::default())?;
    let p = prepare(&s, path)?;
    let line = format!(
        "OK {}: PILS settings, {}/{} run {} of {}, {} pacing; the world built and the run flown",
        path.display(),
        p.flight.scene_name(),
        p.flight.method.name(),
        p.flight.run,
        s.scenario_path.display(),
        match s.file.link.pacing {
            Pacing::Lockstep => "lockstep",
            Pacing::Realtime => "realtime",
        }
    );
    if quiet {
        return Ok(format!("{line}\n"));
    }
    let resolved = toml::to_string(&s.file)
        .map_err(|e| Failure::Run(anyhow!("printing the settings: {e}")))?;
    Ok(format!(
        "# {line}\n# resolved settings (defaults filled in):\n{resolved}"
    ))
}

/// The session's error, naming where its record is.
fn session_result<R>(s: Session<R>, out: &Path) -> Result<R, Failure> {
    match s.error {
        Some(e) => Err(Failure::Run(anyhow!(
            "{e} (what was recorded is in {})",
            out.display()
        ))),
        None => Ok(s.report),
    }
}

/// The file of `fathom pils offline` in its `--out` folder.
const OFFLINE_CSV: &str = "solutions.csv";

/// Runs a `fathom pils` command.
pub fn pils_cmd(a: &PilsArgs) -> Result<String, Failure> {
    let t0 = Instant::now();
    match &a.side {
        Some(PilsSide::Sim {
            scenario,
            nav,
            bind,
            pick,
            out,
            force,
        }) => {
            if nav.port() == 0 || nav.ip().is_unspecified() {
                return Err(Failure::Usage(anyhow!(
                    "--nav {nav}: the navigation's address needs a host and a port (e.g. 127.0.0.1:14550)"
                )));
            }
            let s = load(scenario, pick)?;
            let p = prepare(&s, scenario)?;
            let dir = claim(out, *force)?;
            let mut link = fathom_pils::session::bind_sim(&s, *bind, *nav).map_err(run_err)?;
            let addr = link.local_addr().map_err(run_err)?;
            eprintln!("simulator on {addr}, sending to {nav}");
            let r = fathom_pils::session::simulate_prepared(&mut link, &s, &p, true)
                .map_err(run_err)?;
            write_files(&r, dir.dir())?;
            commit(dir, scenario, &s, None, t0)?;
            session_result(r, out).map(|r| sim_text(&r, out))
        }
        Some(PilsSide::Nav {
            scenario,
            listen,
            sim,
            pick,
            out,
            force,
        }) => {
            let s = load(scenario, pick)?;
            // The navigation's own world (fails on the settings the simulator checks).
            let fl = fathom_pils::session::flight_of(&s)
                .map_err(|e| Failure::Usage(anyhow!("{}: {e}", scenario.display())))?;
            let dir = claim(out, *force)?;
            let mut link = fathom_pils::session::bind_nav(&s, *listen, *sim).map_err(run_err)?;
            let addr = link.local_addr().map_err(run_err)?;
            // The first line tells a parent where to send (flushed before serving).
            println!("navigation listening on {addr}");
            let r = fathom_pils::session::navigate_on(&mut link, &s, &fl).map_err(run_err)?;
            write_files(&r, dir.dir())?;
            commit(dir, scenario, &s, None, t0)?;
            session_result(r, out).map(|r| {
                format!(
                    "navigation done: {} steps, {} solutions; outputs in {}\n",
                    r.steps,
                    r.solutions,
                    out.display()
                )
            })
        }
        Some(PilsSide::Offline {
            scenario,
            quantized,
            pick,
            out,
        }) => {
            let s = load(scenario, pick)?;
            let p = prepare(&s, scenario)?;
            // The output folder is made before the run, so that a bad `--out` costs nothing.
            std::fs::create_dir_all(out)
                .with_context(|| format!("cannot create `{}` (--out)", out.display()))
                .map_err(Failure::Usage)?;
            let csv = fathom_pils::session::offline_csv(&p, *quantized).map_err(run_err)?;
            let file = out.join(OFFLINE_CSV);
            std::fs::write(&file, csv)
                .with_context(|| format!("writing {}", file.display()))
                .map_err(Failure::Run)?;
            Ok(format!("offline solutions in {}\n", file.display()))
        }
        Some(PilsSide::Compare {
            scenario,
            runs,
            pick,
            out,
            force,
        }) => {
            let s = load(scenario, pick)?;
            crate::pils_compare::compare(scenario, &s, *runs, out, *force)
        }
        None => {
            let scenario = a.scenario.as_ref().ok_or_else(|| {
                Failure::Usage(anyhow!(
                    "fathom pils: give a settings file, or `sim` / `nav` / `offline` / `compare`"
                ))
            })?;
            let s = load(scenario, &a.pick)?;
            let p = prepare(&s, scenario)?;
            let dir = claim(&a.out, a.force)?;
            let (r, addrs) = both(scenario, &s, &p, dir.dir());
            // What was recorded is kept whatever ended the session.
            commit(dir, scenario, &s, None, t0)?;
            let r = r?;
            Ok(format!(
                "{addrs}\n{}",
                sim_text(&session_result(r, &a.out.join("sim"))?, &a.out.join("sim"))
            ))
        }
    }
}

fn sim_text(r: &SimReport, out: &Path) -> String {
    let mut t = format!(
        "{} {}/{}: {} of {} steps, {} solutions ({} late), real-time factor {:.1}\n",
        r.pacing,
        r.scenario,
        r.method,
        r.steps_sent,
        r.steps_total,
        r.solutions,
        r.late_solutions,
        r.real_time_factor
    );
    if let Some(l) = &r.latency {
        t += &format!(
            "solution latency p50 {:.2} ms, p95 {:.2} ms, p99 {:.2} ms\n",
            l.p50_ms, l.p95_ms, l.p99_ms
        );
    }
    if let (Some(p), Some(o)) = (&r.pils, &r.offline) {
        t += &format!(
            "rmse_3d {:.3} m (offline {:.3} m, difference {:+.3} m)\n",
            p.rmse_3d,
            o.rmse_3d,
            p.rmse_3d - o.rmse_3d
        );
    }
    if let Some(eq) = r.equal_to_offline_quantized {
        t += &format!("equal to the offline run with MAVLink quantization: {eq}\n");
    }
    t += &format!("outputs in {}\n", out.display());
    t
}

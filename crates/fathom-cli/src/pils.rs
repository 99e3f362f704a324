//! `fathom pils`: the processor-in-the-loop session (crate `fathom-pils`): the
//! simulator and the navigation as two processes on UDP with MAVLink 2.

use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow};
use clap::{Args, Subcommand};
use fathom_pils::scenario::Method;
use fathom_pils::settings::{PilsFile, Settings};

use crate::Failure;

/// `fathom pils ...`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct PilsArgs {
    #[command(subcommand)]
    side: Option<PilsSide>,
    /// Settings file (`experiment = "pils"`): both processes on loopback.
    scenario: Option<PathBuf>,
    /// Output folder.
    #[arg(long, value_name = "DIR", default_value = "target/pils")]
    out: PathBuf,
    /// The navigation method (overrides the file's).
    #[arg(long, value_name = "NAME")]
    method: Option<String>,
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
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "target/pils/sim")]
        out: PathBuf,
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
        /// The method (overrides the file's).
        #[arg(long, value_name = "NAME")]
        method: Option<String>,
        /// Output folder.
        #[arg(long, value_name = "DIR", default_value = "target/pils/nav")]
        out: PathBuf,
    },
    /// The offline run of the same settings, in-process: its solutions as CSV.
    Offline {
        /// Settings file.
        scenario: PathBuf,
        /// With the MAVLink quantization of every message (what lockstep PILS sees).
        #[arg(long)]
        quantized: bool,
        /// The method (overrides the file's).
        #[arg(long, value_name = "NAME")]
        method: Option<String>,
        /// Output CSV.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
    },
}

fn load(path: &Path, method: Option<&str>) -> Result<Settings, Failure> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading {}", path.display()))
        .map_err(Failure::Usage)?;
    let mut s =
        PilsFile::parse(&text).map_err(|e| Failure::Usage(anyhow!("{}: {e}", path.display())))?;
    if let Some(m) = method {
        s.method = Method::from_name(m).ok_or_else(|| {
            Failure::Usage(anyhow!(
                "--method {m}: must be INS-only, GPS/INS, GREKF or MGPMF"
            ))
        })?;
    }
    Ok(s)
}

fn run_err(e: impl std::fmt::Display) -> Failure {
    Failure::Run(anyhow!("{e}"))
}

/// Writes a session's files into `out` (whatever ended it), then returns its
/// report or its error.
fn finish<R>(s: fathom_pils::session::Session<R>, out: &Path) -> Result<R, Failure> {
    std::fs::create_dir_all(out)
        .with_context(|| format!("creating {}", out.display()))
        .map_err(Failure::Run)?;
    for (name, text) in &s.files {
        let p = out.join(name);
        std::fs::write(&p, text)
            .with_context(|| format!("writing {}", p.display()))
            .map_err(Failure::Run)?;
    }
    match s.error {
        Some(e) => Err(Failure::Run(anyhow!(
            "{e} (what was recorded is in {})",
            out.display()
        ))),
        None => Ok(s.report),
    }
}

/// Runs a `fathom pils` command.
pub fn pils_cmd(a: &PilsArgs) -> Result<String, Failure> {
    match &a.side {
        Some(PilsSide::Sim {
            scenario,
            nav,
            bind,
            out,
        }) => {
            let s = load(scenario, None)?;
            let mut link = fathom_pils::session::bind_sim(&s, *bind, *nav).map_err(run_err)?;
            let addr = link.local_addr().map_err(run_err)?;
            eprintln!("simulator on {addr}, sending to {nav}");
            let r = fathom_pils::session::simulate_on(&mut link, &s, true).map_err(run_err)?;
            finish(r, out).map(|r| sim_text(&r, out))
        }
        Some(PilsSide::Nav {
            scenario,
            listen,
            sim,
            method,
            out,
        }) => {
            let s = load(scenario, method.as_deref())?;
            let mut link = fathom_pils::session::bind_nav(&s, *listen, *sim).map_err(run_err)?;
            let addr = link.local_addr().map_err(run_err)?;
            // The first line tells a parent where to send (flushed before serving).
            println!("navigation listening on {addr}");
            let r = fathom_pils::session::navigate_on(&mut link, &s, s.method).map_err(run_err)?;
            finish(r, out).map(|r| {
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
            method,
            out,
        }) => {
            let s = load(scenario, method.as_deref())?;
            let csv =
                fathom_pils::session::offline_csv(&s, s.method, *quantized).map_err(run_err)?;
            std::fs::write(out, csv)
                .with_context(|| format!("writing {}", out.display()))
                .map_err(Failure::Run)?;
            Ok(format!("offline solutions in {}\n", out.display()))
        }
        None => {
            let scenario = a.scenario.as_ref().ok_or_else(|| {
                Failure::Usage(anyhow!(
                    "fathom pils: give a settings file, or `sim` / `nav` / `offline`"
                ))
            })?;
            both(scenario, a.method.as_deref(), &a.out)
        }
    }
}

fn sim_text(r: &fathom_pils::report::SimReport, out: &Path) -> String {
    let mut t = format!(
        "{} {}: {} of {} steps, {} solutions ({} late), real-time factor {:.1}\n",
        r.pacing,
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

/// Both processes: the navigation as a child on an ephemeral loopback port, the
/// simulator here.
fn both(scenario: &Path, method: Option<&str>, out: &Path) -> Result<String, Failure> {
    let s = load(scenario, method)?;
    let exe = std::env::current_exe()
        .context("own executable")
        .map_err(Failure::Run)?;
    let sock = std::net::UdpSocket::bind("127.0.0.1:0")
        .context("bind simulator")
        .map_err(Failure::Run)?;
    let sim_addr = sock
        .local_addr()
        .context("simulator address")
        .map_err(Failure::Run)?;
    let mut child = Command::new(exe)
        .args(["pils", "nav"])
        .arg(scenario)
        .args([
            "--listen",
            "127.0.0.1:0",
            "--sim",
            &sim_addr.to_string(),
            "--method",
            s.method.name(),
            "--out",
        ])
        .arg(out.join("nav"))
        .stdout(Stdio::piped())
        .spawn()
        .context("starting the navigation process")
        .map_err(Failure::Run)?;
    let stdout = child
        .stdout
        .take()
        .ok_or_else(|| Failure::Run(anyhow!("no stdout of the navigation")))?;
    let mut lines = BufReader::new(stdout).lines();
    let first = lines.next().and_then(Result::ok).unwrap_or_default();
    let nav_addr: SocketAddr = first
        .rsplit(' ')
        .next()
        .and_then(|a| a.parse().ok())
        .ok_or_else(|| {
            Failure::Run(anyhow!(
                "the navigation did not say where it listens: {first:?}"
            ))
        })?;
    eprintln!(
        "simulator on {sim_addr}, navigation (pid {}) on {nav_addr}",
        child.id()
    );
    let mut link = fathom_pils::link::Link::from_socket(
        sock,
        fathom_pils::link::Peer::Fixed(nav_addr),
        fathom_pils::link::LinkSetup {
            system: fathom_pils::frame::SIM_SYSTEM,
            peer_system: fathom_pils::frame::NAV_SYSTEM,
            signing: s.key().map(|k| (k, 0)),
            faults: s.file.link.faults,
            fault_seed: s.file.seed ^ 0x5111_0001 ^ s.file.run.rotate_left(17),
        },
    )
    .map_err(run_err)?;
    let sim_out = out.join("sim");
    let r = fathom_pils::session::simulate_on(&mut link, &s, true).map_err(run_err);
    // The child ends on the power-off heartbeat or its own timeout.
    let deadline = Instant::now() + Duration::from_secs_f64(s.file.link.timeout_s + 2.0);
    let status = loop {
        match child.try_wait() {
            Ok(Some(st)) => break Some(st),
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(20)),
            _ => {
                let _ = child.kill();
                break child.wait().ok();
            }
        }
    };
    let r = r.and_then(|r| finish(r, &sim_out))?;
    if !status.is_some_and(|s| s.success()) {
        return Err(Failure::Run(anyhow!(
            "the navigation process ended with {status:?}"
        )));
    }
    Ok(format!(
        "simulator on {sim_addr}, navigation on {nav_addr}\n{}",
        sim_text(&r, &sim_out)
    ))
}

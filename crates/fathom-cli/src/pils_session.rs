//! The processes and files of a `fathom pils` session: the flight checked before
//! anything starts, the output folder claimed and committed, the navigation started
//! as a child process beside the simulator, and a session's files and figures
//! (`fathom_pils::figures`) written into its folder.

use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, anyhow};
use fathom_pils::report::SimReport;
use fathom_pils::session::{Prepared, Session};
use fathom_pils::settings::Settings;
use fathom_sim::driver::{OutDir, RunInfo};

use crate::{Failure, failure};

/// Checks the flight settings and flies the run before any socket, process or
/// output folder is touched: a bad file is one usage error (exit 2).
pub(crate) fn prepare(s: &Settings, path: &Path) -> Result<Prepared, Failure> {
    Prepared::new(s).map_err(|e| Failure::Usage(anyhow!("{}: {e}", path.display())))
}

/// A run failure from a library error.
pub(crate) fn run_err(e: impl std::fmt::Display) -> Failure {
    Failure::Run(anyhow!("{e}"))
}

/// Claims an output folder (lock, ownership, writability) before any work.
pub(crate) fn claim(out: &Path, force: bool) -> Result<OutDir, Failure> {
    OutDir::claim(out, force).map_err(failure)
}

/// Moves a claimed folder into place with its `run_info.json`.
pub(crate) fn commit(
    claim: OutDir,
    scenario: &Path,
    s: &Settings,
    runs: Option<usize>,
    t0: Instant,
) -> Result<(), Failure> {
    let info = RunInfo {
        fathom_version: env!("CARGO_PKG_VERSION").into(),
        command: "pils".into(),
        experiment: "pils".into(),
        scenario: scenario.display().to_string(),
        runs,
        threads: None,
        seed: None,
        base_seed: Some(s.seed),
        elapsed_s: t0.elapsed().as_secs_f64(),
        files: Vec::new(),
    };
    claim.commit(info).map(drop).map_err(failure)
}

/// Writes named texts into `dir` (created if needed).
///
/// # Errors
/// [`Failure::Run`] naming the folder or file.
pub(crate) fn write_named(dir: &Path, files: &[(&str, String)]) -> Result<(), Failure> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("creating {}", dir.display()))
        .map_err(Failure::Run)?;
    for (name, text) in files {
        let p = dir.join(name);
        std::fs::write(&p, text)
            .with_context(|| format!("writing {}", p.display()))
            .map_err(Failure::Run)?;
    }
    Ok(())
}

/// Writes a session's files and, for a simulator session, its figures into `dir`
/// (whatever ended it).
///
/// # Errors
/// [`Failure::Run`] when a file cannot be written or a figure drawn.
pub(crate) fn write_files<R>(s: &Session<R>, dir: &Path) -> Result<(), Failure> {
    write_named(dir, &s.files)?;
    if let Some(series) = &s.series {
        let figures = fathom_pils::figures::session_figures(series).map_err(run_err)?;
        write_named(dir, &figures)?;
    }
    Ok(())
}

/// Both processes of one session: the navigation as a child on an ephemeral
/// loopback port (settings file `scenario`, outputs in `dir/nav`), the simulator
/// here (outputs in `dir/sim`, written whatever ended the session). Returns the
/// simulator's session (or the failure) and the addresses line.
pub(crate) fn both(
    scenario: &Path,
    s: &Settings,
    p: &Prepared,
    dir: &Path,
) -> (Result<Session<SimReport>, Failure>, String) {
    let mut addrs = String::new();
    let r = both_inner(scenario, s, p, dir, &mut addrs);
    (r, addrs)
}

fn both_inner(
    scenario: &Path,
    s: &Settings,
    p: &Prepared,
    dir: &Path,
    addrs: &mut String,
) -> Result<Session<SimReport>, Failure> {
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
            "--scene",
            p.flight.scene_name(),
            "--method",
            p.flight.method.name(),
            "--run",
            &p.flight.run.to_string(),
            "--out",
        ])
        .arg(dir.join("nav"))
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
    let Some(nav_addr) = first
        .rsplit(' ')
        .next()
        .and_then(|a| a.parse::<SocketAddr>().ok())
    else {
        let _ = child.kill();
        let _ = child.wait();
        return Err(Failure::Run(anyhow!(
            "the navigation did not say where it listens: {first:?}"
        )));
    };
    eprintln!(
        "simulator on {sim_addr}, navigation (pid {}) on {nav_addr}",
        child.id()
    );
    *addrs = format!("simulator on {sim_addr}, navigation on {nav_addr}");
    let r = fathom_pils::link::Link::from_socket(
        sock,
        fathom_pils::link::Peer::Fixed(nav_addr),
        fathom_pils::link::LinkSetup {
            system: fathom_pils::frame::SIM_SYSTEM,
            peer_system: fathom_pils::frame::NAV_SYSTEM,
            signing: s.key().map(|k| (k, 0)),
            faults: s.file.link.faults,
            fault_seed: s.seed ^ 0x5111_0001 ^ s.file.run.rotate_left(17),
        },
    )
    .and_then(|mut link| fathom_pils::session::simulate_prepared(&mut link, s, p, true))
    .map_err(run_err);
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
    let r = r?;
    write_files(&r, &dir.join("sim"))?;
    if r.error.is_none() && !status.is_some_and(|s| s.success()) {
        return Err(Failure::Run(anyhow!(
            "the navigation process ended with {status:?}"
        )));
    }
    Ok(r)
}

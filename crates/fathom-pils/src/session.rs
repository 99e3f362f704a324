//! One side of a session from settings to files: the simulator (fly, sense, run the
//! link, evaluate, run the offline references, write the outputs) and the
//! navigation (run the method on what arrives, write its solutions and counters).
//! Outputs are written whatever ends the session; the error is returned after.

use std::net::SocketAddr;
use std::path::Path;

use serde::Serialize;

use crate::PilsError;
use crate::link::Link;
use crate::nav::{nav_link, run_nav};
use crate::report::{SimReport, evaluate, offline, solutions_csv, write_sim_outputs};
use crate::scenario::{IMU_DT, MapAidedNav, Method, Shared, SimulatedRun};
use crate::settings::{Pacing, Settings};
use crate::sim::{latency_summary, run_sim, sim_link};
use crate::stats::LinkCounters;

/// The simulator side on a bound link; writes into `out` and returns the report
/// (its `status` says whether the session failed).
///
/// # Errors
/// [`PilsError`] when the run cannot be set up or the outputs not written.
pub fn simulate_on(
    link: &mut Link,
    s: &Settings,
    out: &Path,
    offline_refs: bool,
) -> Result<SimReport, PilsError> {
    let sh = Shared::new(s.file.flight.clone())?;
    let run = SimulatedRun::new(&sh, s.file.seed, s.file.run)?;
    let o = run_sim(link, &sh, &run, s);
    let pils = (!o.solutions.is_empty()).then(|| evaluate(&run, &o.solutions));
    let (mut oq, mut of, mut equal, mut diff) = (None, None, None, Default::default());
    if offline_refs {
        let q = offline(&sh, &run, s.method, true)?;
        let f = offline(&sh, &run, s.method, false)?;
        oq = Some(evaluate(&run, &q));
        let fs = evaluate(&run, &f);
        of = Some(fs);
        if let Some(p) = &pils {
            diff = p
                .metrics()
                .iter()
                .zip(fs.metrics())
                .map(|((n, a), (_, b))| ((*n).to_string(), a - b))
                .collect();
        }
        equal = Some(o.error.is_none() && o.solutions == q);
    }
    let sim_s = o.steps_sent as f64 * IMU_DT;
    let report = SimReport {
        status: o
            .error
            .as_ref()
            .map_or_else(|| "ok".to_string(), ToString::to_string),
        method: s.method.name().into(),
        pacing: match s.file.link.pacing {
            Pacing::Lockstep => "lockstep".into(),
            Pacing::Realtime => "realtime".into(),
        },
        steps_sent: o.steps_sent,
        steps_total: (run_steps(&run)).saturating_sub(1),
        solutions: o.solutions.len(),
        late_solutions: o.late,
        retransmissions: o.retransmissions,
        latency: latency_summary(&o),
        wall_s: o.wall_s,
        sim_s,
        real_time_factor: if o.wall_s > 0.0 {
            sim_s / o.wall_s
        } else {
            0.0
        },
        link: link.counters.clone(),
        pils,
        offline_quantized: oq,
        offline: of,
        difference_to_offline: diff,
        equal_to_offline_quantized: equal,
    };
    write_sim_outputs(out, &report, &o.solutions)?;
    match o.error {
        Some(e) => Err(e),
        None => Ok(report),
    }
}

fn run_steps(r: &SimulatedRun) -> u64 {
    use crate::scenario::SensorSource;
    r.steps()
}

/// The simulator side: binds `local`, sends to `nav`.
///
/// # Errors
/// As [`simulate_on`].
pub fn simulate(
    s: &Settings,
    local: SocketAddr,
    nav: SocketAddr,
    out: &Path,
) -> Result<SimReport, PilsError> {
    let mut link = sim_link(local, nav, s)?;
    simulate_on(&mut link, s, out, true)
}

/// The navigation's record.
#[derive(Debug, Clone, Serialize)]
pub struct NavReport {
    /// `"ok"` or the error that ended the session.
    pub status: String,
    /// Method.
    pub method: String,
    /// Steps processed.
    pub steps: u64,
    /// Steps processed with parts missing, or dropped (real time).
    pub incomplete_steps: u64,
    /// Solutions sent.
    pub solutions: usize,
    /// The link counters of the navigation side.
    pub link: LinkCounters,
}

/// The navigation side on a bound link: runs `method`, writes `nav.json` and
/// `solutions.csv` (full precision) into `out`.
///
/// # Errors
/// The session's error (after the outputs are written), or [`PilsError::Io`].
pub fn navigate_on(
    link: &mut Link,
    s: &Settings,
    method: Method,
    out: &Path,
) -> Result<NavReport, PilsError> {
    let sh = Shared::new(s.file.flight.clone())?;
    let mut nav = MapAidedNav::new(&sh, method)?;
    let o = run_nav(link, &sh, &mut nav, s);
    let r = NavReport {
        status: o
            .error
            .as_ref()
            .map_or_else(|| "ok".to_string(), ToString::to_string),
        method: method.name().into(),
        steps: o.steps,
        incomplete_steps: o.incomplete_steps,
        solutions: o.solutions.len(),
        link: link.counters.clone(),
    };
    std::fs::create_dir_all(out)
        .map_err(|e| PilsError::io(format!("create {}", out.display()), e))?;
    std::fs::write(
        out.join("nav.json"),
        serde_json::to_string_pretty(&r).unwrap_or_default(),
    )
    .map_err(|e| PilsError::io("write nav.json", e))?;
    std::fs::write(out.join("solutions.csv"), solutions_csv(&o.solutions))
        .map_err(|e| PilsError::io("write solutions.csv", e))?;
    match o.error {
        Some(e) => Err(e),
        None => Ok(r),
    }
}

/// Binds the navigation's socket (to print its address before serving).
///
/// # Errors
/// As [`crate::link::Link::bind`].
pub fn bind_nav(
    s: &Settings,
    listen: SocketAddr,
    sim: Option<SocketAddr>,
) -> Result<Link, PilsError> {
    nav_link(listen, sim, s)
}

/// The offline run's solutions as CSV (`quantized`: with the MAVLink quantization).
///
/// # Errors
/// As [`offline`].
pub fn offline_csv(s: &Settings, method: Method, quantized: bool) -> Result<String, PilsError> {
    let sh = Shared::new(s.file.flight.clone())?;
    let run = SimulatedRun::new(&sh, s.file.seed, s.file.run)?;
    let sols = offline(&sh, &run, method, quantized)?;
    Ok(solutions_csv(&sols))
}

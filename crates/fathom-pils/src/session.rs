//! One side of a session from settings to output files: the simulator (fly, sense,
//! run the link, evaluate, run the offline references) and the navigation (run the
//! method on what arrives, record its solutions and counters). A session that fails
//! on the link still returns what it recorded, with its error, so that the caller
//! (the binary, which does the file I/O) writes the outputs before it reports.

use std::net::SocketAddr;

use serde::Serialize;

use crate::PilsError;
use crate::link::Link;
use crate::nav::{nav_link, run_nav};
use crate::report::{SimReport, error_3d_series, evaluate, offline, sim_files, solutions_csv};
use crate::scenario::{IMU_DT, MapAidedNav, Method, Shared, SimulatedRun};
use crate::settings::{Pacing, Settings};
use crate::sim::{latency_summary, run_sim, sim_link};
use crate::stats::LinkCounters;

/// What one side of a session produced.
#[derive(Debug)]
pub struct Session<R> {
    /// The side's record.
    pub report: R,
    /// Output files (name, content) to write into the side's folder.
    pub files: Vec<(&'static str, String)>,
    /// The error that ended the session (peer silent, socket, navigation), if any.
    pub error: Option<PilsError>,
    /// Per-step data for figures (the simulator side only).
    pub series: Option<SimSeries>,
}

/// Per-step data of a simulator session, for figures.
#[derive(Debug, Clone, Default)]
pub struct SimSeries {
    /// 3-D position error vs time, `(time s, error m)`, per solution set:
    /// `("PILS", ..)`, then, when they were run, the two offline references.
    pub error_3d: Vec<(&'static str, Vec<(f64, f64)>)>,
    /// Solution latencies (send of a step -> receipt of its solution), s.
    pub latencies_s: Vec<f64>,
}

/// The run of a session, checked and flown before any socket or process is used:
/// a bad setting is reported once, before the navigation side is started.
pub struct Prepared {
    /// The world and schedule.
    pub shared: Shared,
    /// The flight and its sensor epochs.
    pub run: SimulatedRun,
}

impl Prepared {
    /// Checks the flight settings, builds the world and flies the run.
    ///
    /// # Errors
    /// [`PilsError::Setting`] / [`PilsError::Model`] naming what is wrong.
    pub fn new(s: &Settings) -> Result<Self, PilsError> {
        let shared = Shared::new(s.file.flight.clone())?;
        let run = SimulatedRun::new(&shared, s.file.seed, s.file.run)?;
        Ok(Self { shared, run })
    }
}

/// The simulator side on a bound link (`offline_refs`: also run the two offline
/// references and compare with them, when the session completed).
///
/// # Errors
/// [`PilsError`] when the run cannot be set up or an offline reference fails; link
/// failures are in [`Session::error`].
pub fn simulate_on(
    link: &mut Link,
    s: &Settings,
    offline_refs: bool,
) -> Result<Session<SimReport>, PilsError> {
    let p = Prepared::new(s)?;
    simulate_prepared(link, s, &p, offline_refs)
}

/// [`simulate_on`] with the run already prepared.
///
/// # Errors
/// As [`simulate_on`].
pub fn simulate_prepared(
    link: &mut Link,
    s: &Settings,
    p: &Prepared,
    offline_refs: bool,
) -> Result<Session<SimReport>, PilsError> {
    let (sh, run) = (&p.shared, &p.run);
    let o = run_sim(link, sh, run, s);
    let mut series = SimSeries {
        error_3d: vec![("PILS", error_3d_series(run, &o.solutions))],
        latencies_s: o.latencies.clone(),
    };
    let pils = (!o.solutions.is_empty()).then(|| evaluate(run, &o.solutions));
    let (mut oq, mut of, mut equal, mut diff) = (None, None, None, Default::default());
    // A failed session is not compared (and ends quickly: within the timeout).
    if offline_refs && o.error.is_none() {
        let q = offline(sh, run, s.method, true)?;
        let f = offline(sh, run, s.method, false)?;
        oq = Some(evaluate(run, &q));
        let fs = evaluate(run, &f);
        series
            .error_3d
            .push(("offline, MAVLink-quantized", error_3d_series(run, &q)));
        series
            .error_3d
            .push(("offline, f64", error_3d_series(run, &f)));
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
        steps_total: (run_steps(run)).saturating_sub(1),
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
    let files = sim_files(&report, &o.solutions, s.file.seed, s.file.run)?;
    Ok(Session {
        report,
        files,
        error: o.error,
        series: Some(series),
    })
}

fn run_steps(r: &SimulatedRun) -> u64 {
    use crate::scenario::SensorSource;
    r.steps()
}

/// The simulator's link: binds `local`, sends to `nav`.
///
/// # Errors
/// As [`crate::link::Link::bind`].
pub fn bind_sim(s: &Settings, local: SocketAddr, nav: SocketAddr) -> Result<Link, PilsError> {
    sim_link(local, nav, s)
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

/// The navigation side on a bound link: runs `method`; its files are `nav.json`
/// and `solutions.csv` (full precision).
///
/// # Errors
/// [`PilsError`] when the navigation cannot be set up; link failures are in
/// [`Session::error`].
pub fn navigate_on(
    link: &mut Link,
    s: &Settings,
    method: Method,
) -> Result<Session<NavReport>, PilsError> {
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
    let files = vec![
        (
            "nav.json",
            serde_json::to_string_pretty(&r).unwrap_or_default(),
        ),
        ("solutions.csv", solutions_csv(&o.solutions)?),
    ];
    Ok(Session {
        report: r,
        files,
        error: o.error,
        series: None,
    })
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
    solutions_csv(&sols)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::PilsFile;

    /// A short flight (one 50 m leg, 1 s of rest): about 3,500 steps.
    fn settings(link: &str) -> Settings {
        PilsFile::parse(&format!(
            "experiment = \"pils\"\nmethod = \"MGPMF\"\n[flight]\nlegs = 1\nside_m = 50.0\n\
             rest_s = 1.0\nhover_s = 0.5\n[link]\ntimeout_s = 5.0\nretransmit_s = 0.02\n{link}"
        ))
        .unwrap()
    }

    /// Both sides in threads on loopback; the simulator's session.
    fn session(s: &Settings) -> Session<SimReport> {
        let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
        let mut nav_link = bind_nav(s, any, None).unwrap();
        let nav_addr = nav_link.local_addr().unwrap();
        let ns = s.clone();
        let nav = std::thread::spawn(move || navigate_on(&mut nav_link, &ns, ns.method).unwrap());
        let mut link = bind_sim(s, any, nav_addr).unwrap();
        let r = simulate_on(&mut link, s, false).unwrap();
        let n = nav.join().unwrap();
        assert!(n.error.is_none(), "{:?}", n.error);
        r
    }

    /// Lockstep over a faulty, signed link equals the in-process run of the same
    /// method on the same MAVLink-quantized data, bit for bit; the quantization
    /// matters (negative control: the `f64` offline run differs).
    #[test]
    fn lockstep_equals_offline_quantized_run_even_with_faults() {
        let s = settings(
            "signing_passphrase = \"k\"\n[link.faults]\nloss = 0.03\nreorder = 0.03\n\
             duplicate = 0.03\ncorrupt = 0.03\njunk = 0.03\n",
        );
        let r = session(&s);
        assert!(r.error.is_none(), "{:?}", r.error);
        let sh = Shared::new(s.file.flight.clone()).unwrap();
        let run = SimulatedRun::new(&sh, s.file.seed, s.file.run).unwrap();
        let q = offline(&sh, &run, s.method, true).unwrap();
        let f = offline(&sh, &run, s.method, false).unwrap();
        let csv = |name: &str| r.files.iter().find(|(n, _)| *n == name).unwrap().1.clone();
        assert_eq!(csv("solutions.csv"), solutions_csv(&q).unwrap());
        assert_ne!(solutions_csv(&q).unwrap(), solutions_csv(&f).unwrap());
        assert_eq!(r.report.solutions, q.len());
        let c = &r.report.link;
        assert!(c.datagrams_lost_injected > 0 && c.junk_sent > 0, "{c:?}");
        assert!(r.report.retransmissions > 0);
    }
}

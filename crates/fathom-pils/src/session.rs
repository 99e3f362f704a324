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
use crate::settings::{Pacing, Settings};
use crate::sim::{latency_summary, run_sim, sim_link};
use crate::source::{IMU_DT, SensorSource};
use crate::stats::LinkCounters;
use crate::urban_flight::{UrbanFlight, UrbanNav, UrbanRun};

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
    /// The scenario prepared, the scene, method and run, the stream's schedule.
    pub flight: UrbanFlight,
    /// The flight and its sensor epochs.
    pub run: UrbanRun,
}

impl Prepared {
    /// Checks the settings and the `urban` scenario, builds its world and flies the
    /// run.
    ///
    /// # Errors
    /// [`PilsError::Setting`] / [`PilsError::Model`] naming what is wrong.
    pub fn new(s: &Settings) -> Result<Self, PilsError> {
        let flight = flight_of(s)?;
        let run = UrbanRun::new(&flight)?;
        Ok(Self { flight, run })
    }
}

/// The flight the settings name (the world built, nothing flown).
///
/// # Errors
/// The scenario's errors; a scene or method the scenario does not have.
pub fn flight_of(s: &Settings) -> Result<UrbanFlight, PilsError> {
    let file = s.scenario_path.display().to_string();
    let base = s
        .scenario_path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    UrbanFlight::load(
        &s.scenario_text,
        &file,
        base,
        s.file.scene.as_deref(),
        s.file.method.as_deref(),
        s.file.run,
    )
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
    let (fl, run) = (&p.flight, &p.run);
    let o = run_sim(link, &fl.schedule, run, s);
    let mut series = SimSeries {
        error_3d: vec![("PILS", error_3d_series(run, &o.solutions))],
        latencies_s: o.latencies.clone(),
    };
    let pils = (!o.solutions.is_empty()).then(|| evaluate(run, &o.solutions));
    let (mut oq, mut of, mut equal, mut diff) = (None, None, None, Default::default());
    let mut offline_f64 = None;
    // A failed session is not compared (and ends quickly: within the timeout).
    if offline_refs && o.error.is_none() {
        let q = offline(fl, run, true)?;
        let f = offline(fl, run, false)?;
        oq = Some(evaluate(run, &q));
        let fs = evaluate(run, &f);
        series
            .error_3d
            .push(("offline, MAVLink-quantized", error_3d_series(run, &q)));
        series
            .error_3d
            .push(("offline, f64", error_3d_series(run, &f)));
        of = Some(fs);
        offline_f64 = Some(f);
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
        method: fl.method.name().into(),
        scenario: fl.scene_name().into(),
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
    let mut files = sim_files(&report, &o.solutions, fl.seed, fl.run)?;
    if s.scene_page && !o.solutions.is_empty() {
        let mut tracks = vec![("PILS", &o.solutions)];
        if let Some(f) = &offline_f64 {
            tracks.push(("offline", f));
        }
        files.push(("scene.html", crate::scene::scene_page(fl, run, &tracks)?));
    }
    Ok(Session {
        report,
        files,
        error: o.error,
        series: Some(series),
    })
}

fn run_steps(r: &UrbanRun) -> u64 {
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
    /// The scene flown (the `urban` scenario's name for it).
    pub scenario: String,
    /// Steps processed.
    pub steps: u64,
    /// Steps processed with parts missing, or dropped (real time).
    pub incomplete_steps: u64,
    /// Solutions sent.
    pub solutions: usize,
    /// The link counters of the navigation side.
    pub link: LinkCounters,
}

/// The navigation side on a bound link: runs the flight's method; its files are
/// `nav.json` and `solutions.csv` (full precision).
///
/// # Errors
/// [`PilsError`] when the navigation cannot be set up; link failures are in
/// [`Session::error`].
pub fn navigate_on(
    link: &mut Link,
    s: &Settings,
    fl: &UrbanFlight,
) -> Result<Session<NavReport>, PilsError> {
    let env = fl.env();
    let mut nav = UrbanNav::new(fl, &env);
    let o = run_nav(link, &fl.schedule, &mut nav, s);
    let r = NavReport {
        status: o
            .error
            .as_ref()
            .map_or_else(|| "ok".to_string(), ToString::to_string),
        method: fl.method.name().into(),
        scenario: fl.scene_name().into(),
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
pub fn offline_csv(p: &Prepared, quantized: bool) -> Result<String, PilsError> {
    solutions_csv(&offline(&p.flight, &p.run, quantized)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::urban_flight::tests::short_bridge;

    /// The short bridge of the `urban` preset, GREKF, with `link` settings.
    fn settings(link: &str) -> Settings {
        let mut s =
            Settings::from_text(&short_bridge(), std::path::Path::new("urban.toml")).unwrap();
        s.file.method = Some("GREKF".into());
        s.file.link =
            toml::from_str(&format!("timeout_s = 5.0\nretransmit_s = 0.02\n{link}")).unwrap();
        s.file.link.check().unwrap();
        s
    }

    /// Both sides in threads on loopback; the simulator's session.
    fn session(s: &Settings) -> Session<SimReport> {
        let any: SocketAddr = "127.0.0.1:0".parse().unwrap();
        let mut nav_link = bind_nav(s, any, None).unwrap();
        let nav_addr = nav_link.local_addr().unwrap();
        let ns = s.clone();
        let nav = std::thread::spawn(move || {
            let fl = flight_of(&ns).unwrap();
            navigate_on(&mut nav_link, &ns, &fl).unwrap()
        });
        let mut link = bind_sim(s, any, nav_addr).unwrap();
        let r = simulate_on(&mut link, s, false).unwrap();
        let n = nav.join().unwrap();
        assert!(n.error.is_none(), "{:?}", n.error);
        assert_eq!(
            (n.report.method.as_str(), n.report.scenario.as_str()),
            ("GREKF", "bridge")
        );
        r
    }

    /// Lockstep over a faulty, signed link equals the in-process run of the same
    /// method on the same MAVLink-quantized data, bit for bit; the quantization
    /// matters (negative control: the `f64` offline run differs).
    #[test]
    fn lockstep_equals_offline_quantized_run_even_with_faults() {
        let s = settings(
            "signing_passphrase = \"k\"\n[faults]\nloss = 0.03\nreorder = 0.03\n\
             duplicate = 0.03\ncorrupt = 0.03\njunk = 0.03\n",
        );
        let r = session(&s);
        assert!(r.error.is_none(), "{:?}", r.error);
        let p = Prepared::new(&s).unwrap();
        let q = offline(&p.flight, &p.run, true).unwrap();
        let f = offline(&p.flight, &p.run, false).unwrap();
        let csv = |name: &str| r.files.iter().find(|(n, _)| *n == name).unwrap().1.clone();
        assert_eq!(csv("solutions.csv"), solutions_csv(&q).unwrap());
        assert_ne!(solutions_csv(&q).unwrap(), solutions_csv(&f).unwrap());
        assert_eq!(r.report.solutions, q.len());
        assert_eq!(
            (r.report.method.as_str(), r.report.scenario.as_str()),
            ("GREKF", "bridge")
        );
        let c = &r.report.link;
        assert!(c.datagrams_lost_injected > 0 && c.junk_sent > 0, "{c:?}");
        assert!(r.report.retransmissions > 0);
    }
}

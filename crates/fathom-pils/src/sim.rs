//! The simulator process: sends each step's messages to the navigation, in lockstep
//! (waits for the step's `ODOMETRY`, resends the step after `retransmit_s`) or paced
//! to the wall clock (late solutions counted, not waited for; the initial estimate
//! repeated until the navigation has started), compares the
//! solutions with the truth, and ends with `HEARTBEAT(MAV_STATE_POWEROFF)`. Silence
//! of the navigation longer than the timeout ends the session with an error; what
//! was recorded so far is returned either way.

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use mavlink::dialects::common::{
    HEARTBEAT_DATA, MavAutopilot, MavMessage, MavModeFlag, MavState, MavType, SYSTEM_TIME_DATA,
};

use crate::PilsError;
use crate::assemble::Schedule;
use crate::codec::{decode_solution, encode_epoch, encode_initial, time_to_usec};
use crate::epoch::Solution;
use crate::frame::{NAV_SYSTEM, SIM_SYSTEM};
use crate::link::{Link, LinkSetup, Peer};
use crate::settings::{Pacing, Settings};
use crate::source::{IMU_DT, SensorSource};
use crate::stats::{Drop, latency_percentiles};

/// A `HEARTBEAT` with a system status.
pub fn heartbeat(status: MavState) -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: status,
        mavlink_version: 3,
    })
}

/// What the simulator recorded.
#[derive(Debug, Default)]
pub struct SimOutcome {
    /// Solutions by step (as received, decoded).
    pub solutions: BTreeMap<u64, Solution>,
    /// Latencies, s.
    pub latencies: Vec<f64>,
    /// Late solutions.
    pub late: u64,
    /// Retransmitted steps.
    pub retransmissions: u64,
    /// Steps sent.
    pub steps_sent: u64,
    /// Wall time, s.
    pub wall_s: f64,
    /// The error that ended the session, if any.
    pub error: Option<PilsError>,
}

/// The simulator side's link.
///
/// # Errors
/// As [`Link::bind`].
pub fn sim_link(local: SocketAddr, nav: SocketAddr, s: &Settings) -> Result<Link, PilsError> {
    Link::bind(
        local,
        Peer::Fixed(nav),
        LinkSetup {
            system: SIM_SYSTEM,
            peer_system: NAV_SYSTEM,
            signing: s.key().map(|k| (k, 0)),
            faults: s.file.link.faults,
            fault_seed: s.seed ^ 0x5111_0001 ^ s.file.run.rotate_left(17),
        },
    )
}

/// Runs the session over `link` (module docs).
pub fn run_sim(link: &mut Link, sh: &Schedule, src: &dyn SensorSource, s: &Settings) -> SimOutcome {
    let mut out = SimOutcome::default();
    let t0 = Instant::now();
    let r = match s.file.link.pacing {
        Pacing::Lockstep => lockstep(link, sh, src, s, &mut out),
        Pacing::Realtime => realtime(link, sh, src, s, &mut out),
    };
    let _ = link.flush_all();
    if r.is_ok() {
        for _ in 0..3 {
            let _ = link.send(&heartbeat(MavState::MAV_STATE_POWEROFF));
        }
        let _ = link.flush_all();
    }
    out.wall_s = t0.elapsed().as_secs_f64();
    out.error = r.err();
    out
}

/// Steps between two `HEARTBEAT`s (and the simulator's `SYSTEM_TIME`): 1 s.
pub const HEARTBEAT_EVERY: u64 = 100;

/// The simulator's `SYSTEM_TIME` at step `k`: the wall clock (0 if unknown) and the
/// simulated time since the start as the boot time.
fn system_time(k: u64) -> MavMessage {
    let unix_usec = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_micros()).unwrap_or(0));
    MavMessage::SYSTEM_TIME(SYSTEM_TIME_DATA {
        time_unix_usec: unix_usec,
        time_boot_ms: u32::try_from(time_to_usec(k as f64 * IMU_DT) / 1000).unwrap_or(u32::MAX),
    })
}

fn step_messages(sh: &Schedule, src: &dyn SensorSource, k: u64) -> Vec<MavMessage> {
    let mut v = Vec::new();
    // A standard node: a heartbeat and the clock every second.
    if k.is_multiple_of(HEARTBEAT_EVERY) {
        v.push(heartbeat(MavState::MAV_STATE_ACTIVE));
        v.push(system_time(k));
    }
    // What is flown, with every step of the rest (a copy may be lost).
    if let Some(id) = &sh.identity
        && k <= sh.start
    {
        v.push(crate::identity::encode(id));
    }
    if k == sh.start {
        v.push(MavMessage::ODOMETRY(encode_initial(src.initial())));
    }
    v.extend(encode_epoch(src.epoch(k), &sh.frame, &sh.wire));
    v
}

/// A solution's step from its stamp.
fn step_of(usec: u64) -> u64 {
    let dt = time_to_usec(IMU_DT).max(1);
    (usec + dt / 2) / dt
}

/// Handles one message from the navigation; returns the step of a solution.
fn take(link: &mut Link, m: MavMessage, out: &mut SimOutcome) -> Option<u64> {
    match m {
        MavMessage::ODOMETRY(d) => {
            let k = step_of(d.time_usec);
            if d.quality >= 0 {
                match decode_solution(&d, k) {
                    Some(sol) => {
                        out.solutions.insert(k, sol);
                    }
                    None => link.counters.count_rejected("ODOMETRY", Drop::BadContent),
                }
            }
            Some(k)
        }
        MavMessage::HEARTBEAT(_) => None,
        other => {
            link.counters
                .count_rejected(crate::frame::name_of(&other), Drop::UnexpectedType);
            None
        }
    }
}

fn lockstep(
    link: &mut Link,
    sh: &Schedule,
    src: &dyn SensorSource,
    s: &Settings,
    out: &mut SimOutcome,
) -> Result<(), PilsError> {
    let timeout = Duration::from_secs_f64(s.file.link.timeout_s);
    let retransmit = Duration::from_secs_f64(s.file.link.retransmit_s);
    for k in 1..src.steps() {
        let msgs = step_messages(sh, src, k);
        for m in &msgs {
            link.send(m)?;
        }
        out.steps_sent = k;
        let sent = Instant::now();
        let mut last_send = sent;
        let mut answered = false;
        while !answered {
            let deadline = (last_send + retransmit).min(sent + timeout);
            match link.recv(deadline)? {
                Some(m) => {
                    if let Some(j) = take(link, m, out) {
                        if j == k {
                            answered = true;
                            out.latencies.push(sent.elapsed().as_secs_f64());
                        } else {
                            link.counters.count_drop(Drop::Stale);
                        }
                    }
                }
                None if sent.elapsed() >= timeout => {
                    return Err(PilsError::PeerSilent {
                        peer: "navigation",
                        waited_s: sent.elapsed().as_secs_f64(),
                        timeout_s: s.file.link.timeout_s,
                        step: k,
                    });
                }
                None => {
                    out.retransmissions += 1;
                    for m in &msgs {
                        link.send(m)?;
                    }
                    last_send = Instant::now();
                }
            }
        }
    }
    Ok(())
}

fn realtime(
    link: &mut Link,
    sh: &Schedule,
    src: &dyn SensorSource,
    s: &Settings,
    out: &mut SimOutcome,
) -> Result<(), PilsError> {
    let timeout = Duration::from_secs_f64(s.file.link.timeout_s);
    let dt = Duration::from_secs_f64(IMU_DT);
    let t0 = Instant::now();
    let mut sent_at: BTreeMap<u64, Instant> = BTreeMap::new();
    let mut last_heard = t0;
    let drain = |link: &mut Link,
                 until: Instant,
                 out: &mut SimOutcome,
                 sent_at: &BTreeMap<u64, Instant>,
                 last_heard: &mut Instant|
     -> Result<(), PilsError> {
        while let Some(m) = link.recv(until)? {
            *last_heard = Instant::now();
            if let Some(j) = take(link, m, out)
                && let Some(at) = sent_at.get(&j)
            {
                let lat = at.elapsed();
                out.latencies.push(lat.as_secs_f64());
                if lat > dt {
                    out.late += 1;
                }
            }
        }
        Ok(())
    };
    for k in 1..src.steps() {
        let due = t0 + dt * (k as u32);
        drain(link, due, out, &sent_at, &mut last_heard)?;
        if last_heard.elapsed() > timeout {
            return Err(PilsError::PeerSilent {
                peer: "navigation",
                waited_s: last_heard.elapsed().as_secs_f64(),
                timeout_s: s.file.link.timeout_s,
                step: k,
            });
        }
        // The initial estimate goes out with every step from the start on until a
        // solution shows that the navigation has started (a lost or late one would
        // otherwise keep it from ever starting).
        if k > sh.start && out.solutions.is_empty() {
            link.send(&MavMessage::ODOMETRY(encode_initial(src.initial())))?;
        }
        for m in step_messages(sh, src, k) {
            link.send(&m)?;
        }
        sent_at.insert(k, Instant::now());
        out.steps_sent = k;
    }
    link.flush_all()?;
    let end = Instant::now() + Duration::from_millis(500).max(timeout.min(Duration::from_secs(1)));
    drain(link, end, out, &sent_at, &mut last_heard)?;
    Ok(())
}

/// Summary numbers of an outcome.
pub fn latency_summary(out: &SimOutcome) -> Option<crate::stats::Percentiles> {
    latency_percentiles(&out.latencies)
}

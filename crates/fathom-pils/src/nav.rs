//! The navigation process: gathers the messages of each step, runs the method on
//! complete steps and answers each with its `ODOMETRY` (`quality = -1` before the
//! navigation starts). In lockstep a step is processed once everything the schedule
//! says is due has arrived (retransmissions fill losses; a repeated step gets its
//! answer again); in real time a step is processed when its `HIL_SENSOR` arrives,
//! with whatever else of it is there, and older steps are stale. It ends on the
//! simulator's `HEARTBEAT(MAV_STATE_POWEROFF)`, or with an error after the timeout.

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use mavlink::dialects::common::{MavMessage, MavState, ODOMETRY_DATA};

use crate::PilsError;
use crate::assemble::Schedule;
use crate::assemble::StepParts;
use crate::codec::{encode_solution, time_to_usec};
use crate::epoch::Solution;
use crate::frame::{NAV_SYSTEM, SIM_SYSTEM};
use crate::link::{Link, LinkSetup, Peer};
use crate::settings::{Pacing, Settings};
use crate::sim::{HEARTBEAT_EVERY, heartbeat};
use crate::source::{IMU_DT, Navigator};
use crate::stats::Drop;

/// The navigation side's link: peer fixed to `sim` when given, else latched.
///
/// # Errors
/// As [`Link::bind`].
pub fn nav_link(
    local: SocketAddr,
    sim: Option<SocketAddr>,
    s: &Settings,
) -> Result<Link, PilsError> {
    Link::bind(
        local,
        sim.map_or(Peer::Latch, Peer::Fixed),
        LinkSetup {
            system: NAV_SYSTEM,
            peer_system: SIM_SYSTEM,
            signing: s.key().map(|k| (k, 1)),
            faults: s.file.link.faults,
            fault_seed: s.seed ^ 0x5111_0002 ^ s.file.run.rotate_left(17),
        },
    )
}

/// What the navigation recorded.
#[derive(Debug, Default)]
pub struct NavOutcome {
    /// Its solutions (full precision) by step.
    pub solutions: BTreeMap<u64, Solution>,
    /// Steps processed.
    pub steps: u64,
    /// Steps processed with parts missing (real time).
    pub incomplete_steps: u64,
    /// The error that ended the session, if any.
    pub error: Option<PilsError>,
}

fn step_of(usec: u64) -> u64 {
    let dt = time_to_usec(IMU_DT).max(1);
    (usec + dt / 2) / dt
}

/// The step a sensor message belongs to.
fn stamp_step(m: &MavMessage) -> Option<u64> {
    match m {
        MavMessage::HIL_SENSOR(d) => Some(step_of(d.time_usec)),
        MavMessage::HIL_GPS(d) => Some(step_of(d.time_usec)),
        MavMessage::DEBUG_FLOAT_ARRAY(d) => Some(step_of(d.time_usec)),
        MavMessage::OBSTACLE_DISTANCE(d) => Some(step_of(d.time_usec)),
        MavMessage::DISTANCE_SENSOR(d) => Some(step_of(u64::from(d.time_boot_ms) * 1000)),
        MavMessage::ODOMETRY(d) => Some(step_of(d.time_usec)),
        _ => None,
    }
}

/// Steps further ahead than this are refused (bounded memory whatever arrives).
const MAX_AHEAD: u64 = 1000;

/// Runs the navigation over `link` until the simulator ends or goes silent.
pub fn run_nav(
    link: &mut Link,
    sh: &Schedule,
    nav: &mut dyn Navigator,
    s: &Settings,
) -> NavOutcome {
    let mut out = NavOutcome::default();
    out.error = serve(link, sh, nav, s, &mut out).err();
    let _ = link.flush_all();
    out
}

fn answer(k: u64, sol: Option<&Solution>) -> MavMessage {
    match sol {
        Some(s) => MavMessage::ODOMETRY(encode_solution(s)),
        None => {
            let mut d = ODOMETRY_DATA::DEFAULT;
            d.time_usec = k * time_to_usec(IMU_DT);
            d.frame_id = mavlink::dialects::common::MavFrame::MAV_FRAME_LOCAL_NED;
            d.child_frame_id = mavlink::dialects::common::MavFrame::MAV_FRAME_LOCAL_NED;
            d.q = [1.0, 0.0, 0.0, 0.0];
            d.quality = -1;
            MavMessage::ODOMETRY(d)
        }
    }
}

fn serve(
    link: &mut Link,
    sh: &Schedule,
    nav: &mut dyn Navigator,
    s: &Settings,
    out: &mut NavOutcome,
) -> Result<(), PilsError> {
    let timeout = Duration::from_secs_f64(s.file.link.timeout_s);
    let lockstep = s.file.link.pacing == Pacing::Lockstep;
    let mut parts: BTreeMap<u64, StepParts> = BTreeMap::new();
    let mut next = 1u64;
    let mut prev_usec = 0u64;
    let mut last_answer: Option<(u64, MavMessage)> = None;
    let mut last_heard = Instant::now();
    let mut started = false;
    let mut pending_init = None;
    loop {
        let Some(m) = link.recv(last_heard + timeout)? else {
            return Err(PilsError::PeerSilent {
                peer: "simulator",
                waited_s: last_heard.elapsed().as_secs_f64(),
                timeout_s: s.file.link.timeout_s,
                step: next,
            });
        };
        last_heard = Instant::now();
        if let MavMessage::HEARTBEAT(h) = &m {
            if h.system_status == MavState::MAV_STATE_POWEROFF {
                link.send(&heartbeat(MavState::MAV_STATE_POWEROFF))?;
                return Ok(());
            }
            continue;
        }
        // The simulator's clock, for a ground station.
        if matches!(m, MavMessage::SYSTEM_TIME(_)) {
            continue;
        }
        let name = crate::frame::name_of(&m);
        if let MavMessage::STATUSTEXT(d) = &m {
            match (crate::identity::decode(d), &sh.identity) {
                (Some(theirs), Some(ours)) => {
                    let ours = crate::identity::wire_text(ours);
                    if theirs != ours {
                        return Err(PilsError::setting(
                            "scenario",
                            &theirs,
                            format!(
                                "the simulator flies this, the navigation `{ours}`: start both \
                                 with the same file, --scene, --method and --run"
                            ),
                        ));
                    }
                }
                (Some(_), None) => {}
                (None, _) => link.counters.count_rejected(name, Drop::UnexpectedType),
            }
            continue;
        }
        // Real time: the initial estimate is repeated by the simulator until the
        // navigation has started; it is kept apart from the steps (whose order jitter
        // scrambles) and used at the first step processed from the start step on.
        if !lockstep && let MavMessage::ODOMETRY(d) = &m {
            match crate::codec::decode_initial(d, 0) {
                Some(i) if !started => pending_init = Some(i),
                Some(_) => link.counters.count_rejected(name, Drop::Stale),
                None => link.counters.count_rejected(name, Drop::BadContent),
            }
            continue;
        }
        let Some(k) = stamp_step(&m) else {
            link.counters.count_rejected(name, Drop::UnexpectedType);
            continue;
        };
        if k < next {
            // A repeated step (retransmission, duplicate): answer its IMU sample again.
            link.counters.count_rejected(name, Drop::Stale);
            if let (MavMessage::HIL_SENSOR(_), Some((j, a))) = (&m, &last_answer)
                && *j == k
            {
                link.send(a)?;
            }
            continue;
        }
        if k > next + MAX_AHEAD {
            link.counters.count_rejected(name, Drop::BadContent);
            continue;
        }
        let p = parts.entry(k).or_default();
        if !p.add(&m, &sh.frame, &sh.wire) {
            link.counters.count_rejected(name, Drop::BadContent);
            continue;
        }
        loop {
            let ready = match parts.get(&next) {
                Some(p) if lockstep => p.complete(&sh.due(next)),
                _ if lockstep => false,
                // real time: the newest step with its IMU sample closes everything before
                _ => parts.range(next..).any(|(_, p)| p.imu.is_some()),
            };
            if !ready {
                break;
            }
            let k = if lockstep {
                next
            } else {
                parts
                    .range(next..)
                    .find(|(_, p)| p.imu.is_some())
                    .map_or(next, |(j, _)| *j)
            };
            // Older incomplete steps are dropped (real time).
            let older: Vec<u64> = parts.range(..k).map(|(j, _)| *j).collect();
            for j in older {
                parts.remove(&j);
                out.incomplete_steps += 1;
            }
            let Some(p) = parts.remove(&k) else {
                break;
            };
            if !p.complete(&sh.due(k)) {
                out.incomplete_steps += 1;
            }
            let init = if lockstep {
                p.init
            } else if !started && k >= sh.start {
                pending_init.take()
            } else {
                None
            };
            let Some(imu) = p.imu else {
                break;
            };
            let usec = imu.time_usec;
            let Some(e) = p.into_epoch(k, prev_usec, &sh.wire) else {
                break;
            };
            prev_usec = usec;
            let sol = nav.step(&e, init.as_ref())?;
            out.steps += 1;
            let a = answer(k, sol.as_ref());
            link.send(&a)?;
            if k.is_multiple_of(HEARTBEAT_EVERY) {
                link.send(&heartbeat(MavState::MAV_STATE_ACTIVE))?;
            }
            last_answer = Some((k, a));
            if let Some(sol) = sol {
                started = true;
                out.solutions.insert(k, sol);
            }
            next = k + 1;
        }
    }
}

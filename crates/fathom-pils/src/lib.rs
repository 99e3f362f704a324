//! Processor-in-the-loop (spec D, "Processor-in-the-loop"; issue 21): the simulator
//! and the navigation as two OS processes exchanging MAVLink 2 messages of the
//! common dialect over UDP, in lockstep (deterministic, equal to the offline run
//! with the same MAVLink quantization) or paced to the wall clock, with link faults
//! as settings, optional MAVLink 2 signing, and the link's own statistics.
//!
//! | file | job |
//! | --- | --- |
//! | [`epoch`] | what crosses the link, in SI units |
//! | [`codec`] | epochs, initial estimate, solution <-> MAVLink messages: the quantization |
//! | [`raw_gnss`] | raw GNSS measurements (satellite positions, pseudoranges) in `DEBUG_FLOAT_ARRAY` blocks |
//! | [`identity`] | what the simulator flies, said on the link and checked by the navigation |
//! | [`assemble`] | the messages of one step gathered into an epoch |
//! | [`frame`] | MAVLink 2 frames on datagrams, signing, the never-panicking parser |
//! | [`faults`] | loss, latency and jitter, reordering, duplicates, corruption, junk |
//! | [`link`] | a UDP endpoint: peer filter, faults on send, counters |
//! | [`stats`] | counters per message type and drop reason, latency percentiles |
//! | [`settings`] | the settings: the `urban` scenario flown (scene, method, run) and the link (pacing, timeout, faults, signing) |
//! | [`source`] | the two traits the sides see the run through |
//! | [`urban_flight`] | the `urban` experiment's own flight, sensors and navigation on the link |
//! | [`sim`], [`nav`] | the two processes' loops |
//! | [`report`] | evaluation, offline references, a session's output files (`summary.json` in the shared contract) |
//! | [`compare`] | lockstep vs realtime over runs: paired differences with CIs, the study's files |
//! | [`figures`] | a session's and the study's figures as SVG text |
//! | [`scene`] | a simulator session as the 3D scene page (`scene.html`) |

pub mod assemble;
pub mod codec;
pub mod compare;
pub mod epoch;
pub mod faults;
pub mod figures;
pub mod frame;
pub mod identity;
pub mod link;
pub mod nav;
pub mod raw_gnss;
pub mod report;
pub mod scene;
pub mod session;
pub mod settings;
pub mod sim;
pub mod source;
pub mod stats;
pub mod urban_flight;

/// Errors of a PILS run.
#[derive(Debug, thiserror::Error)]
pub enum PilsError {
    /// A setting out of range.
    #[error(
        "{field} = {}: {}",
        fathom_core::echo::echo(value),
        fathom_core::echo::echo_message(reason)
    )]
    Setting {
        /// The setting.
        field: String,
        /// Its value.
        value: String,
        /// What is wrong.
        reason: String,
    },
    /// A socket operation failed.
    #[error("{what}: {source}")]
    Io {
        /// What was being done.
        what: String,
        /// The error.
        source: std::io::Error,
    },
    /// The peer went silent (or died) for longer than the timeout.
    #[error("{peer} silent for {waited_s:.1} s (timeout {timeout_s} s) at step {step}")]
    PeerSilent {
        /// Which side.
        peer: &'static str,
        /// Seconds waited.
        waited_s: f64,
        /// The timeout.
        timeout_s: f64,
        /// The step waited for.
        step: u64,
    },
    /// The simulation or the navigation failed.
    #[error("{0}")]
    Model(String),
}

impl PilsError {
    /// A setting error.
    pub fn setting(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        Self::Setting {
            field: field.into(),
            // a number written out in hundreds of digits, shown as 1e300
            value: fathom_core::echo::compact_numbers(&value.to_string()),
            reason: reason.into(),
        }
    }

    /// An I/O error.
    pub fn io(what: impl Into<String>, source: std::io::Error) -> Self {
        Self::Io {
            what: what.into(),
            source,
        }
    }

    /// A model error.
    pub fn model(what: impl std::fmt::Display, e: impl std::fmt::Display) -> Self {
        Self::Model(format!("{what}: {e}"))
    }
}

//! The messages of one step gathered into an [`Epoch`]: what the navigation has
//! received for a step (IMU, GPS outputs, range beams, the initial estimate), whether
//! it is complete against what the schedule says is due, and the epoch it makes.

use fathom_sensors::gnss::LocalFrame;
use mavlink::dialects::common::MavMessage;

use crate::codec::{
    ImuReading, RangeWire, decode_distance, decode_gps, decode_imu, decode_initial, decode_scan,
    encode_epoch, epoch_from_parts, time_to_usec,
};
use crate::epoch::{Epoch, GpsReading, InitialEstimate, SatReading};

/// What is due at a step (both sides derive it from the scenario).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Due {
    /// `HIL_GPS` messages.
    pub gps: usize,
    /// The raw GNSS measurements (`GNSS_RAW` blocks, as many as their count says).
    pub raw_gnss: bool,
    /// Range messages (`DISTANCE_SENSOR` or `OBSTACLE_DISTANCE`).
    pub ranges: usize,
    /// The initial estimate.
    pub init: bool,
}

/// What both sides know of the stream before it starts: the local frame of the GPS
/// messages, the range sensor on the wire, the step at which navigation starts and
/// which steps carry which sensors.
#[derive(Debug, Clone, PartialEq)]
pub struct Schedule {
    /// The local frame of `HIL_GPS` positions.
    pub frame: LocalFrame,
    /// The range sensor as the wire describes it.
    pub wire: RangeWire,
    /// Step at which navigation starts (end of the rest).
    pub start: u64,
    /// Steps per GNSS epoch.
    pub gps_every: u64,
    /// Steps per range epoch.
    pub range_every: u64,
    /// Whether GNSS epochs carry the raw measurements (`GNSS_RAW`).
    pub raw_gnss: bool,
    /// What is flown (`crate::identity`; `None`: not said, not checked).
    pub identity: Option<String>,
}

impl Schedule {
    /// What is due at step `k`.
    pub fn due(&self, k: u64) -> Due {
        let gnss = k.is_multiple_of(self.gps_every);
        Due {
            gps: usize::from(gnss),
            raw_gnss: gnss && self.raw_gnss,
            ranges: if k.is_multiple_of(self.range_every) {
                self.wire.messages()
            } else {
                0
            },
            init: k == self.start,
        }
    }
}

/// The messages received for one step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepParts {
    /// The IMU sample.
    pub imu: Option<ImuReading>,
    /// GPS outputs by receiver id.
    pub gps: Vec<GpsReading>,
    /// Raw GNSS blocks received, by block index, with the epoch's satellite count.
    raw_blocks: std::collections::BTreeMap<usize, Vec<SatReading>>,
    raw_count: Option<usize>,
    /// Range beams received (beam order), `None` until the first range message.
    pub ranges: Option<Vec<Option<f64>>>,
    /// Range messages received (distinct).
    pub range_messages: usize,
    range_seen: Vec<bool>,
    /// The initial estimate.
    pub init: Option<InitialEstimate>,
}

impl StepParts {
    /// Adds a message; returns `false` when it does not belong to an epoch (another
    /// type, a beam index or scan block outside the sensor, an invalid initial
    /// estimate). A repeated part replaces the earlier copy (duplicates carry the
    /// same content).
    pub fn add(&mut self, m: &MavMessage, frame: &LocalFrame, wire: &RangeWire) -> bool {
        match m {
            MavMessage::HIL_SENSOR(d) => {
                self.imu = Some(decode_imu(d));
                true
            }
            MavMessage::HIL_GPS(d) => {
                let g = decode_gps(d, frame);
                self.gps.retain(|x| x.id != g.id);
                self.gps.push(g);
                self.gps.sort_by_key(|x| x.id);
                true
            }
            MavMessage::DISTANCE_SENSOR(d) => match decode_distance(d, wire) {
                Some((beam, r)) => {
                    self.put_ranges(beam, beam, &[r], wire);
                    true
                }
                None => false,
            },
            MavMessage::OBSTACLE_DISTANCE(d) => match decode_scan(d, wire) {
                Some((first, r)) => {
                    self.put_ranges(first / crate::codec::SCAN_SLOTS, first, &r, wire);
                    true
                }
                None => false,
            },
            MavMessage::DEBUG_FLOAT_ARRAY(d) => match crate::raw_gnss::decode(d) {
                Some((block, count, sats)) if self.raw_count.is_none_or(|c| c == count) => {
                    self.raw_count = Some(count);
                    self.raw_blocks.insert(block, sats);
                    true
                }
                _ => false,
            },
            MavMessage::ODOMETRY(d) => match decode_initial(d, 0) {
                Some(i) => {
                    self.init = Some(i);
                    true
                }
                None => false,
            },
            _ => false,
        }
    }

    fn put_ranges(&mut self, msg_index: usize, first: usize, r: &[Option<f64>], wire: &RangeWire) {
        let n = wire.beams();
        let ranges = self.ranges.get_or_insert_with(|| vec![None; n]);
        if self.range_seen.len() != wire.messages() {
            self.range_seen = vec![false; wire.messages()];
        }
        for (slot, v) in ranges.iter_mut().skip(first).zip(r) {
            *slot = *v;
        }
        if let Some(seen) = self.range_seen.get_mut(msg_index)
            && !*seen
        {
            *seen = true;
            self.range_messages += 1;
        }
    }

    /// The raw GNSS measurements, once every block has arrived.
    fn raw_gnss(&self) -> Option<Vec<SatReading>> {
        let n = self.raw_count?;
        (self.raw_blocks.len() == crate::raw_gnss::messages(n))
            .then(|| self.raw_blocks.values().flatten().copied().collect())
    }

    /// Whether everything `due` has arrived.
    pub fn complete(&self, due: &Due) -> bool {
        self.imu.is_some()
            && self.gps.len() >= due.gps
            && (!due.raw_gnss || self.raw_gnss().is_some())
            && self.range_messages >= due.ranges
            && (!due.init || self.init.is_some())
    }

    /// The epoch of step `step` after the IMU stamp `prev_usec` (needs the IMU).
    pub fn into_epoch(self, step: u64, prev_usec: u64, _wire: &RangeWire) -> Option<Epoch> {
        let imu = self.imu?;
        let raw = self.raw_gnss();
        Some(epoch_from_parts(
            step,
            &imu,
            prev_usec,
            self.gps,
            raw,
            self.ranges,
        ))
    }
}

/// The epochs as the navigation receives them over a lossless link:
/// `decode(encode(e))` for each, with the step lengths from the time stamps (the
/// offline run's MAVLink quantization setting).
pub fn quantize_epochs(
    epochs: &[Epoch],
    frame: &LocalFrame,
    wire: &RangeWire,
    t0: f64,
) -> Vec<Epoch> {
    let mut prev = time_to_usec(t0);
    epochs
        .iter()
        .map(|e| {
            let mut a = StepParts::default();
            for m in encode_epoch(e, frame, wire) {
                a.add(&m, frame, wire);
            }
            let out = a.into_epoch(e.step, prev, wire);
            prev = time_to_usec(e.time);
            out.unwrap_or_else(|| e.clone())
        })
        .collect()
}

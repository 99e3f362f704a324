//! The link's own statistics: messages sent / received / lost / rejected per type,
//! the reasons frames were dropped, and the solution latency percentiles.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Why a received datagram (or a frame in it) was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Drop {
    /// From an address other than the peer's.
    ForeignAddress,
    /// Bytes that do not start a MAVLink 2 frame (skipped up to the next start marker).
    Garbage,
    /// A frame shorter than its header announces.
    Truncated,
    /// Incompatibility flags this link does not handle.
    UnsupportedFlags,
    /// Checksum mismatch.
    BadCrc,
    /// A message id outside the common dialect.
    UnknownMessage,
    /// A payload the dialect cannot decode (bad enum value, size).
    Undecodable,
    /// Unsigned while signing is required.
    Unsigned,
    /// Signature wrong or replayed (timestamp not newer).
    BadSignature,
    /// A valid message of a type or from a system this side does not take.
    UnexpectedType,
    /// A valid message whose content this side refuses (non-finite field, time
    /// stamp far off, beam index out of range).
    BadContent,
    /// A message for a step already processed (duplicate or retransmission).
    Stale,
}

/// Counters of one side of the link.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LinkCounters {
    /// Datagrams handed to the socket (after faults: lost ones not counted).
    pub datagrams_sent: u64,
    /// Datagrams the fault injector dropped.
    pub datagrams_lost_injected: u64,
    /// Extra copies the fault injector sent.
    pub datagrams_duplicated_injected: u64,
    /// Datagrams the fault injector corrupted.
    pub datagrams_corrupted_injected: u64,
    /// Junk datagrams the fault injector sent.
    pub junk_sent: u64,
    /// Datagrams read from the socket.
    pub datagrams_received: u64,
    /// Messages sent per type name.
    pub sent: BTreeMap<String, u64>,
    /// Valid messages received and accepted per type name.
    pub received: BTreeMap<String, u64>,
    /// Frames / datagrams dropped per reason.
    pub dropped: BTreeMap<Drop, u64>,
    /// Valid messages dropped per type name (unexpected, bad content, stale).
    pub rejected: BTreeMap<String, u64>,
}

impl LinkCounters {
    /// Counts a sent message.
    pub fn count_sent(&mut self, name: &str) {
        *self.sent.entry(name.to_string()).or_default() += 1;
    }

    /// Counts an accepted message.
    pub fn count_received(&mut self, name: &str) {
        *self.received.entry(name.to_string()).or_default() += 1;
    }

    /// Counts a drop.
    pub fn count_drop(&mut self, why: Drop) {
        *self.dropped.entry(why).or_default() += 1;
    }

    /// Counts a drop of a valid message of type `name`.
    pub fn count_rejected(&mut self, name: &str, why: Drop) {
        self.count_drop(why);
        *self.rejected.entry(name.to_string()).or_default() += 1;
    }

    /// Drops for `why`.
    pub fn drops(&self, why: Drop) -> u64 {
        self.dropped.get(&why).copied().unwrap_or(0)
    }
}

/// Latency percentiles, ms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Percentiles {
    /// Samples.
    pub count: usize,
    /// Median, ms.
    pub p50_ms: f64,
    /// 95th percentile, ms.
    pub p95_ms: f64,
    /// 99th percentile, ms.
    pub p99_ms: f64,
    /// Largest, ms.
    pub max_ms: f64,
}

/// The `q`-quantile (`0..=1`) of sorted samples, nearest rank; `NaN` when empty.
pub fn quantile_sorted(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = (q.clamp(0.0, 1.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// The percentiles of latencies in seconds (non-finite samples ignored); `None`
/// without samples.
pub fn latency_percentiles(latencies_s: &[f64]) -> Option<Percentiles> {
    let mut ms: Vec<f64> = latencies_s
        .iter()
        .filter(|x| x.is_finite())
        .map(|x| x * 1e3)
        .collect();
    if ms.is_empty() {
        return None;
    }
    ms.sort_by(f64::total_cmp);
    Some(Percentiles {
        count: ms.len(),
        p50_ms: quantile_sorted(&ms, 0.5),
        p95_ms: quantile_sorted(&ms, 0.95),
        p99_ms: quantile_sorted(&ms, 0.99),
        max_ms: ms[ms.len() - 1],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentiles() {
        let x: Vec<f64> = (1..=100).map(|i| i as f64 * 1e-3).collect();
        let p = latency_percentiles(&x).unwrap();
        assert_eq!(p.count, 100);
        assert!((p.p50_ms - 50.0).abs() < 1e-9);
        assert!((p.p95_ms - 95.0).abs() < 1e-9);
        assert!((p.p99_ms - 99.0).abs() < 1e-9);
        assert!((p.max_ms - 100.0).abs() < 1e-9);
        assert!(latency_percentiles(&[]).is_none());
        assert!(latency_percentiles(&[f64::NAN]).is_none());
        assert_eq!(quantile_sorted(&[3.0], 0.99), 3.0);
    }

    #[test]
    fn counters_add_up() {
        let mut c = LinkCounters::default();
        c.count_sent("HIL_SENSOR");
        c.count_sent("HIL_SENSOR");
        c.count_rejected("ATTITUDE", Drop::UnexpectedType);
        c.count_drop(Drop::BadCrc);
        assert_eq!(c.sent["HIL_SENSOR"], 2);
        assert_eq!(c.drops(Drop::UnexpectedType), 1);
        assert_eq!(c.drops(Drop::BadCrc), 1);
        assert_eq!(c.drops(Drop::Garbage), 0);
        let json = serde_json::to_string(&c).unwrap();
        assert!(json.contains("\"bad_crc\":1"), "{json}");
    }
}

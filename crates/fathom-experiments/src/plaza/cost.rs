//! The cost of a `plaza` scenario ([`fathom_sim::cost`]): one deterministic replay of a
//! recorded data set. Its size is only known once the files are read, so the estimate
//! is that of the Plaza1 log (about 10⁴ odometry rows and 10⁴ ranges, replayed by
//! dead reckoning, three schemes and the ablations).

use fathom_replay::plaza::PlazaToml;
use fathom_sim::cost::{CostTerm, Held};

/// Samples of the Plaza1 log (odometry and ranges) times the replayed methods.
const SAMPLES: f64 = 2e5;
/// Single-core time per sample, s.
const SAMPLE_S: f64 = 5e-6;
/// Memory of the log and the replays' series, bytes.
const BYTES: f64 = 64e6;

/// The terms of `s` (checked).
pub(super) fn terms(_s: &PlazaToml) -> Vec<CostTerm> {
    vec![CostTerm::new(
        "one replay of a recorded data set (Plaza1-sized; the files decide)",
        SAMPLES,
        SAMPLE_S,
        BYTES,
        Held::Once,
    )]
}

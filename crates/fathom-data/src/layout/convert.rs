//! Converters from native data-set formats into the own-data layout.
//!
//! [`range_beacon_from_plaza`]: a CMU Plaza log (`*_DR.txt`, `*_TD.txt`, `*_.mat`)
//! as a `range-beacon` log: the survey `TL` becomes `beacons.csv` (x as north, y as
//! east: the 2D equations are the same), the first ground-truth row the start (its
//! heading from the data set's dead-reckoned path `DRp`, as the Plaza replay takes
//! it), `*_DR.txt` `odometry.csv`, the ranges (in the order the reader leaves them:
//! sorted by time under `range_order = "sort"`) `ranges.csv`, `GT` `truth.csv`.
//! Every number is copied bit for bit, so the `range-beacon` replay of the converted
//! log repeats the `plaza` replay exactly.

use super::range_beacon::{Beacon, Motion, RangeBeaconLog, RangeRow, Start, TruthRow};
use crate::plaza::PlazaLog;

/// The Plaza log as a `range-beacon` log (module docs).
pub fn range_beacon_from_plaza(log: &PlazaLog) -> RangeBeaconLog {
    let gt0 = log.ground_truth[0];
    RangeBeaconLog {
        beacons: log
            .beacons
            .iter()
            .map(|b| Beacon {
                id: b.id,
                pos_in_nav: [b.x, b.y, 0.0],
            })
            .collect(),
        beacons_have_down: false,
        start: Start {
            time: gt0.time,
            north_east: [gt0.x, gt0.y],
            down: None,
            heading: log.dr_path[0].heading,
        },
        motion: Motion::Odometry(
            log.odometry
                .iter()
                .map(|s| (s.time, s.delta_distance, s.delta_heading))
                .collect(),
        ),
        ranges: log
            .ranges
            .iter()
            .map(|r| RangeRow {
                time: r.time,
                beacon: r.beacon,
                range: r.range,
            })
            .collect(),
        depth: None,
        truth: Some(
            log.ground_truth
                .iter()
                .map(|g| TruthRow {
                    time: g.time,
                    north_east: [g.x, g.y],
                    down: None,
                    heading: Some(g.heading),
                })
                .collect(),
        ),
    }
}

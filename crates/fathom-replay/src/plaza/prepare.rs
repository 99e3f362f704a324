//! The Plaza log turned into filter events on relative time (see the module docs of
//! [`crate::plaza`]).

use fathom_estimators::wheel_odometry::OdometryRate;
use nalgebra::Vector2;

use fathom_data::plaza::PlazaLog;
use fathom_sim::SimError;

/// A range observation on relative time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PreparedRange {
    /// `t - t0`, s.
    pub time: f64,
    /// Channel = row of the beacon in the survey.
    pub channel: usize,
    /// Measured range, m.
    pub value: f64,
    /// Index in [`PlazaLog::ranges`].
    pub index: usize,
}

/// The log turned into filter events on relative time (module docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PreparedLog {
    /// Absolute start time `t0` (first ground-truth row), s.
    pub t0: f64,
    /// Initial pose `(x, y, heading)`: GT position, `DRp` heading.
    pub start: [f64; 3],
    /// Odometry rate changes `(t - t0, rate)`.
    pub inputs: Vec<(f64, OdometryRate)>,
    /// Ranges after `t0`.
    pub ranges: Vec<PreparedRange>,
    /// Evaluation instants `(t - t0, true x, true y)`.
    pub eval: Vec<(f64, f64, f64)>,
    /// Beacon positions by channel.
    pub beacons: Vec<Vector2<f64>>,
    /// Odometry rows skipped (at or before `t0`).
    pub skipped_odometry: usize,
    /// Ranges skipped (at or before `t0`).
    pub skipped_ranges: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Kind {
    Input(usize),
    Range(usize),
    Eval(usize),
}

impl PreparedLog {
    /// Prepares `log` (module docs).
    ///
    /// # Errors
    /// [`SimError::Model`] for an odometry row whose rate cannot be formed.
    pub fn new(log: &PlazaLog) -> Result<Self, SimError> {
        let gt0 = log.ground_truth[0];
        Self::from_rows(
            gt0.time,
            [gt0.x, gt0.y, log.dr_path[0].heading],
            log.odometry
                .iter()
                .map(|s| (s.time, s.delta_distance, s.delta_heading)),
            log.ranges.iter().map(|r| (r.time, r.beacon, r.range)),
            log.ground_truth[1..].iter().map(|g| (g.time, g.x, g.y)),
            log.beacons.iter().map(|b| Vector2::new(b.x, b.y)).collect(),
        )
    }

    /// Prepares a log given as rows on absolute time (module docs of
    /// [`crate::plaza`]): the start `t0` and pose `(x, y, heading)`, odometry
    /// `(time, distance, heading change)`, ranges `(time, beacon channel, range)` in
    /// processing order (their position is the `index`), the evaluation instants
    /// `(time, true x, true y)` (all after `t0`; NaN truth when the log has none) and
    /// the beacon positions by channel. [`PreparedLog::new`] is this on a Plaza log;
    /// the `range-beacon` replay of a CSV log calls it directly.
    ///
    /// # Errors
    /// [`SimError::Model`] for an odometry row whose rate cannot be formed.
    pub fn from_rows(
        t0: f64,
        start: [f64; 3],
        odometry: impl IntoIterator<Item = (f64, f64, f64)>,
        ranges: impl IntoIterator<Item = (f64, usize, f64)>,
        eval: impl IntoIterator<Item = (f64, f64, f64)>,
        beacons: Vec<Vector2<f64>>,
    ) -> Result<Self, SimError> {
        let odometry = odometry.into_iter();
        let mut inputs = Vec::with_capacity(odometry.size_hint().0 + 1);
        let mut prev = 0.0;
        let mut skipped_odometry = 0;
        for (time, delta_distance, delta_heading) in odometry {
            let t = time - t0;
            if t <= 0.0 {
                skipped_odometry += 1;
                continue;
            }
            let rate = OdometryRate::from_increments(delta_distance, delta_heading, t - prev)
                .map_err(|e| SimError::model(format!("odometry row at t = {time} s"), e))?;
            inputs.push((prev, rate));
            prev = t;
        }
        inputs.push((prev, OdometryRate::default()));
        let mut skipped_ranges = 0;
        let ranges = ranges
            .into_iter()
            .enumerate()
            .filter_map(|(index, (time, channel, value))| {
                let time = time - t0;
                if time <= 0.0 {
                    skipped_ranges += 1;
                    None
                } else {
                    Some(PreparedRange {
                        time,
                        channel,
                        value,
                        index,
                    })
                }
            })
            .collect();
        let eval = eval.into_iter().map(|(t, x, y)| (t - t0, x, y)).collect();
        Ok(PreparedLog {
            t0,
            start,
            inputs,
            ranges,
            eval,
            beacons,
            skipped_odometry,
            skipped_ranges,
        })
    }

    /// All events in processing order (module docs).
    pub(super) fn events(&self, with_ranges: bool) -> Vec<(f64, Kind)> {
        let mut ev: Vec<(f64, Kind)> = self
            .inputs
            .iter()
            .enumerate()
            .map(|(k, i)| (i.0, Kind::Input(k)))
            .chain(
                self.eval
                    .iter()
                    .enumerate()
                    .map(|(k, e)| (e.0, Kind::Eval(k))),
            )
            .collect();
        if with_ranges {
            ev.extend(
                self.ranges
                    .iter()
                    .enumerate()
                    .map(|(k, r)| (r.time, Kind::Range(k))),
            );
        }
        ev.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then_with(|| rank(a.1).cmp(&rank(b.1)))
                .then_with(|| a.1.cmp(&b.1))
        });
        ev
    }
}

fn rank(k: Kind) -> u8 {
    match k {
        Kind::Input(_) => 0,
        Kind::Range(_) => 1,
        Kind::Eval(_) => 2,
    }
}

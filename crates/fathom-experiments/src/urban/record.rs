//! What one `urban` run returns ([`RunRecord`], serializable for sharded campaigns),
//! what the analysis keeps of it ([`KeptRun`]: the per-run statistics) and what it
//! accumulates over a batch in run order ([`BatchFold`]: per-time error sums and
//! counts, histogram counts, and the detail of run 0 for the figures).

use fathom_ins::local_level::LocalTruthSample;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::nav::{Method, NavCounts};
use super::sense::BeamReturn;
use super::trace::{MethodStats, Trace};

/// One method's run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodRecord {
    /// The method.
    pub method: Method,
    /// The run's statistics.
    pub stats: MethodStats,
    /// Update counters.
    pub counts: NavCounts,
    /// 3-D position error per evaluation epoch, m.
    pub err_3d: Vec<f64>,
    /// 3-D velocity error per evaluation epoch, m/s.
    pub err_vel: Vec<f64>,
    /// Attitude error magnitude per evaluation epoch, deg.
    pub err_att: Vec<f64>,
    /// Counts of the 3-D errors in the histogram bins, the last entry those beyond.
    pub hist: Vec<u64>,
}

impl MethodRecord {
    /// The record of a trace; `histogram` is `(upper end m, bins)`.
    pub fn new(
        method: Method,
        stats: MethodStats,
        counts: NavCounts,
        trace: &Trace,
        histogram: (f64, usize),
    ) -> Self {
        let err_3d = trace.err_3d();
        let (hi, bins) = histogram;
        let mut hist = vec![0u64; bins + 1];
        for e in &err_3d {
            let b = ((e / hi) * bins as f64).floor();
            let k = if b >= 0.0 && b < bins as f64 {
                b as usize
            } else {
                bins
            };
            hist[k] += 1;
        }
        Self {
            method,
            stats,
            counts,
            err_vel: trace.err_vel(),
            err_att: trace.err_att(),
            err_3d,
            hist,
        }
    }
}

/// One scenario of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneRecord {
    /// The methods run (all in the main batch, one in an ablation batch).
    pub methods: Vec<MethodRecord>,
    /// Mean number of satellites in true line of sight over the GNSS epochs.
    pub los_mean: f64,
    /// Fraction of GNSS epochs with fewer true-LOS satellites than the switching
    /// threshold.
    pub shadowed_fraction: f64,
    /// Flight duration, s.
    pub duration_s: f64,
}

impl SceneRecord {
    /// A scenario record from the methods and the `(time, true LOS count)` epochs.
    pub fn new(
        methods: Vec<MethodRecord>,
        gnss: &[(f64, usize)],
        threshold: usize,
        duration_s: f64,
    ) -> Self {
        let n = gnss.len().max(1) as f64;
        Self {
            methods,
            los_mean: gnss.iter().map(|g| g.1 as f64).sum::<f64>() / n,
            shadowed_fraction: gnss.iter().filter(|g| g.1 < threshold).count() as f64 / n,
            duration_s,
        }
    }
}

/// One lidar / range-finder scan with the true pose (for the figure).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScanSnapshot {
    /// Time, s.
    pub time: f64,
    /// True position, NED, m.
    pub pos: [f64; 3],
    /// Measured return points (true pose + measured range along the beam), NED, m.
    pub hits: Vec<[f64; 3]>,
}

impl ScanSnapshot {
    /// The scan `returns` seen from the true pose `truth`.
    pub fn of(truth: &LocalTruthSample, returns: &[BeamReturn]) -> Self {
        Self {
            time: truth.time,
            pos: truth.pos_in_nav.into(),
            hits: returns
                .iter()
                .map(|r| {
                    let d = truth.nav_from_body * r.reading.dir_in_body.normalize();
                    (truth.pos_in_nav + d * r.reading.range_m).into()
                })
                .collect(),
        }
    }
}

/// The MGPMF's grid weights at one update, summed over the yaw axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridSnapshot {
    /// Time of the update, s.
    pub time: f64,
    /// North offsets of the grid rows (position-error states), m.
    pub north: Vec<f64>,
    /// East offsets of the grid columns, m.
    pub east: Vec<f64>,
    /// `weights[row][col]`, normalized over the grid.
    pub weights: Vec<Vec<f64>>,
}

impl GridSnapshot {
    /// The marginal over yaw of `points` / `weights` on a `dims` grid (north major,
    /// yaw minor, the MGPMF's order).
    pub fn of(time: f64, points: &[Vector3<f64>], weights: &[f64], dims: [usize; 3]) -> Self {
        let [g0, g1, g2] = dims;
        let ok = points.len() == g0 * g1 * g2 && weights.len() == points.len();
        if !ok {
            return Self {
                time,
                north: Vec::new(),
                east: Vec::new(),
                weights: Vec::new(),
            };
        }
        let at = |i: usize, j: usize, k: usize| (i * g1 + j) * g2 + k;
        Self {
            time,
            north: (0..g0).map(|i| points[at(i, 0, 0)].x).collect(),
            east: (0..g1).map(|j| points[at(0, j, 0)].y).collect(),
            weights: (0..g0)
                .map(|i| {
                    (0..g1)
                        .map(|j| (0..g2).map(|k| weights[at(i, j, k)]).sum())
                        .collect()
                })
                .collect(),
        }
    }
}

/// The figures' view of one scenario in run 0.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneDetail {
    /// Evaluation times, s.
    pub times: Vec<f64>,
    /// True positions at the evaluation times, NED, m.
    pub truth: Vec<[f64; 3]>,
    /// Per method (report order), estimated positions, NED, m.
    pub estimates: Vec<Vec<[f64; 3]>>,
    /// Per method, whether the map-aided mode was active.
    pub map_mode: Vec<Vec<bool>>,
    /// Per method, roll / pitch / yaw errors, deg.
    pub att: Vec<Vec<[f64; 3]>>,
    /// `(time, true LOS count)` per GNSS epoch.
    pub gnss: Vec<(f64, usize)>,
    /// One scan at mid-flight.
    pub scan: Option<ScanSnapshot>,
    /// The MGPMF grid at mid-flight.
    pub grid: Option<GridSnapshot>,
    /// Scans over the flight, thinned for the scene page (`scene.html`).
    #[serde(default)]
    pub scans: Vec<ScanSnapshot>,
    /// GNSS epochs over the flight, thinned for the scene page.
    #[serde(default)]
    pub sky: Vec<SkySnapshot>,
}

/// The satellites above the mask at one GNSS epoch, seen from the true position.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkySnapshot {
    /// Time, s.
    pub time: f64,
    /// Per satellite: unit direction from the receiver (NED) and whether the true
    /// position sees it.
    pub sats: Vec<([f64; 3], bool)>,
}

impl SceneDetail {
    /// The detail of one scenario from the truth (IMU rate), the navigation start,
    /// the evaluation step and the methods' traces.
    pub fn new(
        truth: &[LocalTruthSample],
        start: usize,
        eval: usize,
        traces: Vec<Trace>,
        gnss: Vec<(f64, usize)>,
        scan: Option<ScanSnapshot>,
        grid: Option<GridSnapshot>,
    ) -> Self {
        let times = traces.first().map(|t| t.times.clone()).unwrap_or_default();
        let truth_at: Vec<[f64; 3]> = (start + eval..truth.len())
            .step_by(eval.max(1))
            .take(times.len())
            .map(|k| truth[k].pos_in_nav.into())
            .collect();
        Self {
            times,
            truth: truth_at,
            estimates: traces
                .iter()
                .map(|t| t.est_pos.iter().map(|p| (*p).into()).collect())
                .collect(),
            map_mode: traces.iter().map(|t| t.map_mode.clone()).collect(),
            att: traces.iter().map(|t| t.att.clone()).collect(),
            gnss,
            scan,
            grid,
            scans: Vec::new(),
            sky: Vec::new(),
        }
    }
}

/// What a run returns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Per scenario (main batch), or the ablation's scenario.
    pub scenes: Vec<SceneRecord>,
    /// Run 0 of the main batch: the figures' detail per scenario.
    pub detail: Option<Vec<SceneDetail>>,
}

/// What the analysis keeps of one scenario of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct KeptScene {
    /// Per method run, its statistics.
    pub stats: Vec<MethodStats>,
    /// Per method run, its counters.
    pub counts: Vec<NavCounts>,
    /// Mean true-LOS satellite count.
    pub los_mean: f64,
    /// Fraction of shadowed GNSS epochs.
    pub shadowed_fraction: f64,
    /// Flight duration, s.
    pub duration_s: f64,
}

/// What the analysis keeps of a run.
pub type KeptRun = Vec<KeptScene>;

/// Sums over a batch's runs of one method's per-time errors and histogram.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MethodFold {
    /// Per evaluation epoch: sums of the 3-D position, velocity and attitude errors.
    pub sum_3d: Vec<f64>,
    /// Velocity error sums.
    pub sum_vel: Vec<f64>,
    /// Attitude error sums.
    pub sum_att: Vec<f64>,
    /// Runs that reached each epoch.
    pub count: Vec<u64>,
    /// Histogram counts (bins, then beyond).
    pub hist: Vec<u64>,
}

impl MethodFold {
    fn add(&mut self, r: &MethodRecord) {
        let n = r.err_3d.len();
        if self.count.len() < n {
            self.sum_3d.resize(n, 0.0);
            self.sum_vel.resize(n, 0.0);
            self.sum_att.resize(n, 0.0);
            self.count.resize(n, 0);
        }
        for k in 0..n {
            self.sum_3d[k] += r.err_3d[k];
            self.sum_vel[k] += r.err_vel[k];
            self.sum_att[k] += r.err_att[k];
            self.count[k] += 1;
        }
        if self.hist.len() < r.hist.len() {
            self.hist.resize(r.hist.len(), 0);
        }
        for (a, b) in self.hist.iter_mut().zip(&r.hist) {
            *a += b;
        }
    }

    /// The mean curves `(3-D, velocity, attitude)` over the epochs every run reached
    /// (a flight a step shorter than the others would otherwise end the curve with
    /// a mean over fewer runs).
    pub fn means(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let max = self.count.first().copied().unwrap_or(0);
        let n = self.count.iter().take_while(|c| **c == max).count();
        let m = |s: &[f64]| (0..n).map(|k| s[k] / self.count[k] as f64).collect();
        (m(&self.sum_3d), m(&self.sum_vel), m(&self.sum_att))
    }
}

/// A batch's accumulator.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BatchFold {
    /// `scenes[scene][method]`.
    pub scenes: Vec<Vec<MethodFold>>,
    /// Run 0's detail (main batch).
    pub detail: Option<Vec<SceneDetail>>,
}

/// Folds one run into `fold`; returns what the analysis keeps.
pub fn fold_run(record: RunRecord, fold: &mut BatchFold) -> KeptRun {
    if fold.scenes.len() < record.scenes.len() {
        fold.scenes.resize(record.scenes.len(), Vec::new());
    }
    for (s, f) in record.scenes.iter().zip(fold.scenes.iter_mut()) {
        if f.len() < s.methods.len() {
            f.resize(s.methods.len(), MethodFold::default());
        }
        for (m, mf) in s.methods.iter().zip(f.iter_mut()) {
            mf.add(m);
        }
    }
    if record.detail.is_some() {
        fold.detail = record.detail;
    }
    record
        .scenes
        .into_iter()
        .map(|s| KeptScene {
            stats: s.methods.iter().map(|m| m.stats).collect(),
            counts: s.methods.iter().map(|m| m.counts).collect(),
            los_mean: s.los_mean,
            shadowed_fraction: s.shadowed_fraction,
            duration_s: s.duration_s,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid marginal sums the yaw axis in the MGPMF's order (north major, yaw
    /// minor); a wrong point count gives an empty snapshot, not a panic.
    #[test]
    fn grid_snapshot_marginalizes_yaw() {
        let dims = [2, 3, 2];
        let mut points = Vec::new();
        for i in 0..2 {
            for j in 0..3 {
                for k in 0..2 {
                    points.push(Vector3::new(i as f64, 10.0 * j as f64, k as f64));
                }
            }
        }
        let weights: Vec<f64> = (0..12).map(|w| w as f64).collect();
        let g = GridSnapshot::of(1.0, &points, &weights, dims);
        assert_eq!(g.north, vec![0.0, 1.0]);
        assert_eq!(g.east, vec![0.0, 10.0, 20.0]);
        assert_eq!(g.weights[0], vec![1.0, 5.0, 9.0]);
        assert_eq!(g.weights[1], vec![13.0, 17.0, 21.0]);
        assert!(
            GridSnapshot::of(1.0, &points[1..], &weights[1..], dims)
                .weights
                .is_empty()
        );
    }

    /// The mean curves stop where a run has ended: every point is a mean over the
    /// same runs.
    #[test]
    fn fold_means_cover_the_epochs_every_run_reached() {
        let f = MethodFold {
            sum_3d: vec![4.0, 8.0, 6.0, 1.0],
            sum_vel: vec![2.0, 2.0, 2.0, 1.0],
            sum_att: vec![0.0, 0.0, 0.0, 0.0],
            count: vec![4, 4, 3, 1],
            hist: Vec::new(),
        };
        let (p, v, _) = f.means();
        assert_eq!(p, vec![1.0, 2.0]);
        assert_eq!(v, vec![0.5, 0.5]);
    }
}

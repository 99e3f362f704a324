//! GNSS / INS navigation replayed on a drone flight (kind `gnss-ins`,
//! [`fathom_data::layout::gnss_ins`], or a PX4 ULog converted in memory): the
//! methods of the settings' `[[methods]]` list side by side in one pass (`run`):
//! the strapdown INS alone, the 12-state GPS/INS filter of the `urban` experiment
//! (`fathom_estimators::map_aided::Ins12Filter`) and its 15-state extension with a
//! gyro bias (`fathom_estimators::error_state::ErrorStateFilter` with
//! `map_aided::error_model::transition_with_gyro_bias`); with a world mesh
//! (`--world`) and range beams in the log, the map-aided filters of the `urban`
//! experiment (GREKF, MGPMF) switching from GPS/INS while GNSS is away.
//!
//! References: the autopilot's estimate (`reference.csv`, PX4's EKF2) is always there
//! and every method is compared with it at its rows ("agreement with EKF2", not an
//! error: EKF2 is another estimate); with `truth.csv` (a simulator's) the methods
//! *and EKF2* are scored against the truth at the same instants (the truth
//! interpolated linearly), after aligning the truth's altitude datum to the GNSS's
//! at the first used fix (SITL's truth has its own vertical datum). NEES of the
//! position (3 dof) is reported with truth.
//!
//! [`GnssIns`] runs it as a job of the runner (`fathom replay gnss-ins DIR`,
//! `fathom replay ulog FILE.ulg`).

mod analysis;
mod figures;
mod job;
mod map_settings;
mod report;
pub mod run;
mod scene;
mod settings;

pub use job::{GnssIns, Prepared, read_log};
pub use settings::{
    FILTERS, GnssAidToml, GnssInsFilter, GnssInsImuToml, GnssInsInitialToml, GnssInsMethod,
    GnssInsMethodToml, GnssInsSettings, GnssInsToml, MapAidedSettings, MapAidedToml, OutageToml,
    WorldSettings, WorldToml, default_methods, parse_settings,
};

use fathom_data::layout::gnss_ins::{GnssInsLog, TrackRow};
use fathom_map::TriMesh;
use fathom_sim::SimError;
use nalgebra::{Matrix3, Vector3};

/// One GNSS update of a filter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FixUpdate {
    /// Time from the start of the IMU row it was applied after, s.
    pub time: f64,
    /// NIS (NaN when the update failed).
    pub nis: f64,
    /// Degrees of freedom (3: position, 6: position and velocity).
    pub dof: usize,
    /// Whether it passed the gate and was applied.
    pub accepted: bool,
    /// Whether it re-acquired the position after a run of rejected fixes (the
    /// covariance widened by the error the fix showed, then the fix applied).
    #[serde(default)]
    pub reset: bool,
}

/// What a map-aided method did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct MapCounts {
    /// Map-aided updates applied (a GREKF update counts when it used a beam).
    pub map_updates: usize,
    /// GREKF updates in which every beam was left out (gated, grazing, no hit).
    pub map_left_out: usize,
    /// Map-aided updates that failed (no predicted hit from the pose, bad geometry).
    pub map_failed: usize,
    /// Mode switches (GPS/INS to map-aided and back).
    pub switches: usize,
}

/// What one method produced at the recording instants.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MethodTrace {
    /// The method.
    pub method: GnssInsMethod,
    /// Position, local NED, m.
    pub pos_in_nav: Vec<[f64; 3]>,
    /// Velocity, NED, m/s.
    pub vel_in_nav: Vec<[f64; 3]>,
    /// Position covariance `[nn, ne, nd, ee, ed, dd]`, m² (filters).
    pub cov_pos: Option<Vec<[f64; 6]>>,
    /// Every GNSS update.
    pub updates: Vec<FixUpdate>,
    /// The map-aided methods' counters.
    pub map: Option<MapCounts>,
    /// The map-aided methods' mode at the instants (true: map-aided).
    #[serde(default)]
    pub map_mode: Option<Vec<bool>>,
}

impl MethodTrace {
    fn new(method: GnssInsMethod) -> Self {
        Self {
            method,
            pos_in_nav: Vec::new(),
            vel_in_nav: Vec::new(),
            cov_pos: None,
            updates: Vec::new(),
            map: None,
            map_mode: None,
        }
    }

    /// The method's name.
    pub fn name(&self) -> &str {
        &self.method.name
    }

    /// `sqrt(P_nn + P_ee)` at the instants (filters), m.
    pub fn sigma_h(&self) -> Option<Vec<f64>> {
        self.cov_pos
            .as_ref()
            .map(|c| c.iter().map(|p| (p[0] + p[3]).max(0.0).sqrt()).collect())
    }
}

/// Differences of a track from a reference at the instants.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Diff {
    /// Horizontal distance, m.
    pub h: Vec<f64>,
    /// 3D distance, m.
    pub d3: Vec<f64>,
}

impl Diff {
    fn of(a: &[[f64; 3]], b: &[[f64; 3]]) -> Self {
        let h = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x[0] - y[0]).hypot(x[1] - y[1]))
            .collect();
        let d3 = a
            .iter()
            .zip(b)
            .map(|(x, y)| {
                ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
            })
            .collect();
        Self { h, d3 }
    }

    /// RMS of the horizontal distances.
    pub fn rms_h(&self) -> f64 {
        rms(&self.h)
    }

    /// RMS of the 3D distances.
    pub fn rms_3d(&self) -> f64 {
        rms(&self.d3)
    }
}

/// Root mean square (NaN when empty).
pub fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// One method's result.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MethodResult {
    /// What it produced.
    pub trace: MethodTrace,
    /// Against EKF2.
    pub vs_ekf2: Diff,
    /// Against the truth.
    pub vs_truth: Option<Diff>,
    /// Mean position NEES per dof against the truth (filters).
    pub nees_pos: Option<f64>,
}

/// A GNSS fix as the report shows it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FixInfo {
    /// Time from the start, s.
    pub time: f64,
    /// North, east in the local frame, m.
    pub north_east: [f64; 2],
    /// Horizontal accuracy, m.
    pub h_acc: f64,
    /// Satellites used.
    pub satellites: u32,
    /// Fix type.
    pub fix_type: u32,
    /// Whether the filters used it (fix type, outages).
    pub used: bool,
}

/// Everything a GNSS / INS replay produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GnssInsReplay {
    /// Start time (EKF2's first row inside the IMU data), s.
    pub t0: f64,
    /// Recording instants (EKF2's rows after the start), s from the start.
    pub times: Vec<f64>,
    /// EKF2's position at the instants, local NED, m.
    pub ekf2: Vec<[f64; 3]>,
    /// The truth at the instants (altitude datum aligned), local NED, m.
    pub truth: Option<Vec<[f64; 3]>>,
    /// The truth's altitude datum shift (GNSS minus truth at the first used fix), m.
    pub truth_datum_shift: Option<f64>,
    /// EKF2 against the truth.
    pub ekf2_vs_truth: Option<Diff>,
    /// The methods, in the settings' order.
    pub methods: Vec<MethodResult>,
    /// Every GNSS fix after the start.
    pub fixes: Vec<FixInfo>,
    /// Outage windows, s from the start.
    pub outages: Vec<[f64; 2]>,
    /// The world the map-aided methods used (what was read), if any.
    pub world: Option<String>,
    /// Where the world's origin lies in the local frame (NED, m), with a world.
    #[serde(default)]
    pub world_shift: Option<[f64; 3]>,
    /// `gnss.reacquire_after_rejections` (0: no re-acquisition).
    #[serde(default)]
    pub reacquire_after: usize,
    /// Rows read: IMU, GNSS, baro, magnetometer, range, reference, truth.
    pub rows: [usize; 7],
}

/// The truth row interpolated linearly at `t` (inside the rows' span).
fn track_at(rows: &[TrackRow], t: f64) -> Option<([f64; 2], f64)> {
    let i = rows.partition_point(|r| r.time <= t);
    if i == 0 {
        return None;
    }
    let a = rows[i - 1];
    if a.time == t {
        return Some((a.lat_lon, a.altitude));
    }
    let b = *rows.get(i)?;
    let u = (t - a.time) / (b.time - a.time);
    Some((
        [
            a.lat_lon[0] + u * (b.lat_lon[0] - a.lat_lon[0]),
            a.lat_lon[1] + u * (b.lat_lon[1] - a.lat_lon[1]),
        ],
        a.altitude + u * (b.altitude - a.altitude),
    ))
}

fn nees(trace: &MethodTrace, truth: &[[f64; 3]]) -> Option<f64> {
    let cov = trace.cov_pos.as_ref()?;
    let mut sum = 0.0;
    let mut n = 0usize;
    for ((p, g), c) in trace.pos_in_nav.iter().zip(truth).zip(cov) {
        let m = Matrix3::new(c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5]);
        let e = Vector3::new(p[0] - g[0], p[1] - g[1], p[2] - g[2]);
        if let Some(inv) = m.try_inverse() {
            sum += (e.transpose() * inv * e)[0];
            n += 1;
        }
    }
    (n > 0).then(|| sum / (3.0 * n as f64))
}

/// Replays every method of `settings` on `log` (`world`: the mesh of the settings'
/// `[world]`, for the map-aided methods).
///
/// # Errors
/// [`SimError::InvalidArgument`] for a log without `reference.csv`, without EKF2
/// rows inside the IMU data, or with a truth that does not cover the instants, or a
/// map-aided method without a world; [`SimError::Model`] naming the method and time
/// of a failing step.
pub fn replay(
    log: &GnssInsLog,
    settings: &GnssInsSettings,
    world: Option<&TriMesh>,
) -> Result<GnssInsReplay, SimError> {
    let pass = run::run(log, settings, world)?;
    let (frame, t0) = (pass.frame, pass.t0);
    let fixes: Vec<FixInfo> = log
        .gnss
        .iter()
        .filter(|g| g.time > t0)
        .map(|g| {
            let p = frame.ned(g.lat_lon, g.altitude);
            FixInfo {
                time: g.time - t0,
                north_east: [p[0], p[1]],
                h_acc: g.h_acc,
                satellites: g.satellites,
                fix_type: g.fix_type,
                used: g.fix_type >= settings.min_fix_type && !settings.in_outage(g.time - t0),
            }
        })
        .collect();
    let (truth, shift) = match &log.truth {
        None => (None, None),
        Some(rows) => {
            let first = log
                .gnss
                .iter()
                .find(|g| g.fix_type >= settings.min_fix_type && track_at(rows, g.time).is_some())
                .ok_or_else(|| {
                    SimError::invalid_argument(
                        "log `truth.csv`",
                        "covers no GNSS fix of the log: its altitude datum cannot be aligned",
                    )
                })?;
            let shift = first.altitude - track_at(rows, first.time).map_or(0.0, |a| a.1);
            let mut out = Vec::with_capacity(pass.times.len());
            for t in &pass.times {
                let (ll, alt) = track_at(rows, t + t0).ok_or_else(|| {
                    SimError::invalid_argument(
                        "log `truth.csv`",
                        format!("does not cover the instant {} s of `reference.csv`", t + t0),
                    )
                })?;
                out.push(frame.ned(ll, alt + shift));
            }
            (Some(out), Some(shift))
        }
    };
    let methods = pass
        .traces
        .into_iter()
        .map(|trace| {
            let vs_truth = truth.as_ref().map(|g| Diff::of(&trace.pos_in_nav, g));
            let nees_pos = truth.as_ref().and_then(|g| nees(&trace, g));
            MethodResult {
                vs_ekf2: Diff::of(&trace.pos_in_nav, &pass.ekf2),
                vs_truth,
                nees_pos,
                trace,
            }
        })
        .collect();
    Ok(GnssInsReplay {
        t0,
        ekf2_vs_truth: truth.as_ref().map(|g| Diff::of(&pass.ekf2, g)),
        times: pass.times,
        ekf2: pass.ekf2,
        truth,
        truth_datum_shift: shift,
        methods,
        fixes,
        outages: settings.outages.clone(),
        world: None,
        world_shift: pass.world_shift,
        reacquire_after: settings.reacquire_after,
        rows: [
            log.imu.len(),
            log.gnss.len(),
            log.baro.as_ref().map_or(0, Vec::len),
            log.mag.as_ref().map_or(0, Vec::len),
            log.range.as_ref().map_or(0, Vec::len),
            log.reference.as_ref().map_or(0, Vec::len),
            log.truth.as_ref().map_or(0, Vec::len),
        ],
    })
}

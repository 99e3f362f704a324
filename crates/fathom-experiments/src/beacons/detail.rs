//! The detail run of `beacons`: what the single-run figures draw of the figure run
//! (`[figures] run`), taken from that Monte Carlo run itself and carried in its record,
//! so that no figure simulates a run again.

use fathom_sensors::BeaconSuiteData;
use fathom_traj::Trajectory;
use fathom_traj::velocity_command::VelocityCommandMotion;

use super::filter::SchemeRun;
use super::scenario::Checked;
use fathom_sim::SimError;

/// The window of the sample-time diagram, s.
pub(super) const SAMPLE_WINDOW: (f64, f64) = (0.0, 1.0);

/// One scheme's estimate on the main case of the figure run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(super) struct SchemeTrack {
    /// Evaluation instants, s.
    pub(super) times: Vec<f64>,
    /// 3D position error at each instant, m.
    pub(super) errors_3d: Vec<f64>,
    /// Estimate `(north, east, down, yaw)` at each instant (m, rad).
    pub(super) estimates: Vec<[f64; 4]>,
}

/// The figure run, reduced to what the figures and `single_run_estimates.csv` show.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(super) struct FigureDetail {
    /// The actual motion's samples `(time, north, east, down)` (s, m).
    pub(super) actual: Vec<[f64; 4]>,
    /// Index into the scheme list of the scheme the estimate figures show (SC, or the
    /// first scheme run without it).
    pub(super) shown: usize,
    /// The truth `(north, east, down, yaw)` at the shown scheme's evaluation instants.
    pub(super) truth_at_eval: Vec<[f64; 4]>,
    /// Every scheme run on the main case, in scheme order.
    pub(super) schemes: Vec<SchemeTrack>,
    /// Sensor sample times within [`SAMPLE_WINDOW`], one row per sensor: the main
    /// (asynchronous) case, then the synchronous case if any.
    pub(super) sample_rows: Vec<(String, Vec<f64>)>,
}

/// The figure detail of a simulated run: its `motion` and, per case, the sensor data
/// and the schemes' results.
///
/// # Errors
/// A truth sample outside the motion (not expected: the evaluation instants are inside
/// it).
pub(super) fn figure_detail(
    checked: &Checked,
    motion: &VelocityCommandMotion,
    cases: &[(BeaconSuiteData, Vec<SchemeRun>)],
) -> Result<FigureDetail, SimError> {
    let main = checked.main_case();
    let (data, runs) = &cases[main];
    let shown = checked
        .schemes
        .iter()
        .position(|s| s.short_name() == "SC")
        .unwrap_or(0);
    let actual = motion
        .samples()
        .iter()
        .map(|s| [s.time, s.pos_in_nav.x, s.pos_in_nav.y, s.pos_in_nav.z])
        .collect();
    let mut truth_at_eval = Vec::with_capacity(runs[shown].times.len());
    for &t in &runs[shown].times {
        let s = motion
            .state_at(t)
            .map_err(|e| SimError::model("truth", e))?;
        truth_at_eval.push([
            s.pos_in_nav.x,
            s.pos_in_nav.y,
            s.pos_in_nav.z,
            s.attitude.yaw,
        ]);
    }
    let schemes = runs
        .iter()
        .map(|r| SchemeTrack {
            times: r.times.clone(),
            errors_3d: r.errors_3d.clone(),
            estimates: r
                .estimates
                .iter()
                .map(|x| [x[0], x[1], x[2], x[3]])
                .collect(),
        })
        .collect();
    let mut sample_rows = Vec::new();
    sample_rows_of(data, "async: ", &mut sample_rows);
    if let Some(si) = checked.cases.iter().position(|c| c.config.is_synchronous()) {
        let d = &cases[si].0;
        sample_rows.push((
            "sync: all sensors".into(),
            in_window(d.depth.iter().map(|m| m.sample_time)),
        ));
    }
    Ok(FigureDetail {
        actual,
        shown,
        truth_at_eval,
        schemes,
        sample_rows,
    })
}

fn in_window(times: impl Iterator<Item = f64>) -> Vec<f64> {
    times.filter(|t| *t <= SAMPLE_WINDOW.1 + 1e-9).collect()
}

/// The sample times of every sensor of `d` within the window, labelled `prefix<sensor>`.
fn sample_rows_of(d: &BeaconSuiteData, prefix: &str, rows: &mut Vec<(String, Vec<f64>)>) {
    rows.push((
        format!("{prefix}DVL"),
        in_window(d.dvl.iter().map(|m| m.sample_time)),
    ));
    rows.push((
        format!("{prefix}AHRS"),
        in_window(d.ahrs_rate.iter().map(|m| m.sample_time)),
    ));
    for (k, r) in d.ranges.iter().enumerate() {
        rows.push((
            format!("{prefix}range{}", k + 1),
            in_window(r.iter().map(|m| m.sample_time)),
        ));
    }
    rows.push((
        format!("{prefix}depth"),
        in_window(d.depth.iter().map(|m| m.sample_time)),
    ));
}

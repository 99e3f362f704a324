//! Evaluation of the solutions against the truth (the rows `fathom run` writes for a
//! method), the offline reference runs, and the output files of both sides.

use std::collections::BTreeMap;

use fathom_core::frames::euler_from_nav_from_body;
use fathom_core::units::wrap_pi;
use serde::Serialize;

use crate::PilsError;
use crate::assemble::quantize_epochs;
use crate::codec::{quantize_initial, quantize_solution};
use crate::epoch::Solution;
use crate::scenario::{IMU_DT, MapAidedNav, Method, Navigator, SensorSource, Shared, SimulatedRun};
use crate::stats::{LinkCounters, Percentiles};

/// Per-run error statistics of one method (evaluated at every step with a solution
/// after the start).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ErrorStats {
    /// Solutions evaluated.
    pub samples: usize,
    /// Horizontal position RMSE, m.
    pub rmse_h: f64,
    /// 3-D position RMSE, m.
    pub rmse_3d: f64,
    /// Velocity RMSE, m/s.
    pub rmse_vel: f64,
    /// Roll RMSE, deg.
    pub rmse_roll: f64,
    /// Pitch RMSE, deg.
    pub rmse_pitch: f64,
    /// Yaw RMSE, deg.
    pub rmse_yaw: f64,
    /// Mean 3-D error, m.
    pub mean_3d: f64,
    /// 95th percentile of the 3-D error, m.
    pub p95_3d: f64,
    /// Time in map-aided mode, s.
    pub time_map_aided_s: f64,
}

impl ErrorStats {
    /// Metric names and values.
    pub fn metrics(&self) -> [(&'static str, f64); 9] {
        [
            ("rmse_h", self.rmse_h),
            ("rmse_3d", self.rmse_3d),
            ("rmse_vel", self.rmse_vel),
            ("rmse_roll", self.rmse_roll),
            ("rmse_pitch", self.rmse_pitch),
            ("rmse_yaw", self.rmse_yaw),
            ("mean_3d", self.mean_3d),
            ("p95_3d", self.p95_3d),
            ("time_map_aided_s", self.time_map_aided_s),
        ]
    }
}

/// The statistics of solutions (by step) against the truth.
pub fn evaluate(src: &dyn SensorSource, sols: &BTreeMap<u64, Solution>) -> ErrorStats {
    let mut s = [0.0f64; 6];
    let mut e3 = Vec::new();
    let mut map_steps = 0usize;
    for (&k, sol) in sols {
        let t = src.truth(k);
        let dp = sol.pos_in_nav - t.pos_in_nav;
        let dv = sol.vel_in_nav - t.vel_in_nav;
        let ee = euler_from_nav_from_body(&sol.nav_from_body.to_rotation_matrix());
        let et = euler_from_nav_from_body(&t.nav_from_body.to_rotation_matrix());
        let da = [
            wrap_pi(ee.roll - et.roll).to_degrees(),
            wrap_pi(ee.pitch - et.pitch).to_degrees(),
            wrap_pi(ee.yaw - et.yaw).to_degrees(),
        ];
        s[0] += dp.x * dp.x + dp.y * dp.y;
        s[1] += dp.norm_squared();
        s[2] += dv.norm_squared();
        for i in 0..3 {
            s[3 + i] += da[i] * da[i];
        }
        e3.push(dp.norm());
        map_steps += usize::from(sol.map_aided);
    }
    let n = e3.len().max(1) as f64;
    let mean_3d = e3.iter().sum::<f64>() / n;
    e3.sort_by(f64::total_cmp);
    let p95 = crate::stats::quantile_sorted(&e3, 0.95);
    ErrorStats {
        samples: e3.len(),
        rmse_h: (s[0] / n).sqrt(),
        rmse_3d: (s[1] / n).sqrt(),
        rmse_vel: (s[2] / n).sqrt(),
        rmse_roll: (s[3] / n).sqrt(),
        rmse_pitch: (s[4] / n).sqrt(),
        rmse_yaw: (s[5] / n).sqrt(),
        mean_3d,
        p95_3d: p95,
        time_map_aided_s: map_steps as f64 * IMU_DT,
    }
}

/// The 3-D position error of each solution against the truth, `(time s, error m)`.
pub fn error_3d_series(src: &dyn SensorSource, sols: &BTreeMap<u64, Solution>) -> Vec<(f64, f64)> {
    sols.iter()
        .map(|(&k, sol)| {
            let t = src.truth(k);
            (t.time, (sol.pos_in_nav - t.pos_in_nav).norm())
        })
        .collect()
}

/// Runs `method` offline on the simulated run: with `quantized`, every measurement,
/// the initial estimate and every solution go through the MAVLink encode / decode
/// functions (what the lockstep PILS run sees); without, the `f64` values.
///
/// # Errors
/// [`PilsError::Model`] when the navigation fails.
pub fn offline(
    sh: &Shared,
    run: &SimulatedRun,
    method: Method,
    quantized: bool,
) -> Result<BTreeMap<u64, Solution>, PilsError> {
    let epochs = if quantized {
        quantize_epochs(run.epochs(), &sh.frame, &sh.wire, 0.0)
    } else {
        run.epochs().to_vec()
    };
    let init = if quantized {
        quantize_initial(run.initial())
    } else {
        *run.initial()
    };
    let mut nav = MapAidedNav::new(sh, method)?;
    let mut out = BTreeMap::new();
    for e in &epochs {
        let i = (e.step == sh.start).then_some(&init);
        if let Some(s) = nav.step(e, i)? {
            out.insert(e.step, if quantized { quantize_solution(&s) } else { s });
        }
    }
    Ok(out)
}

/// The simulator's record of a session.
#[derive(Debug, Clone, Serialize)]
pub struct SimReport {
    /// `"ok"` or the error that ended the session.
    pub status: String,
    /// Method flown.
    pub method: String,
    /// Pacing.
    pub pacing: String,
    /// Steps sent.
    pub steps_sent: u64,
    /// Steps of the run.
    pub steps_total: u64,
    /// Solutions received (distinct steps).
    pub solutions: usize,
    /// Answers (`ODOMETRY`, also the `quality = -1` ones before the navigation
    /// started) that arrived more than one step after their step was sent (realtime).
    pub late_solutions: u64,
    /// Steps resent (lockstep retransmissions).
    pub retransmissions: u64,
    /// Solution latency (send of the step's `HIL_SENSOR` to receipt of its `ODOMETRY`).
    pub latency: Option<Percentiles>,
    /// Wall time of the link run, s.
    pub wall_s: f64,
    /// Simulated time covered, s.
    pub sim_s: f64,
    /// Real-time factor (simulated / wall time).
    pub real_time_factor: f64,
    /// The link counters of the simulator side.
    pub link: LinkCounters,
    /// Errors of the PILS solutions.
    pub pils: Option<ErrorStats>,
    /// Errors of the offline run fed the MAVLink-quantized measurements.
    pub offline_quantized: Option<ErrorStats>,
    /// Errors of the offline run in `f64`.
    pub offline: Option<ErrorStats>,
    /// PILS minus offline (`f64`), per metric.
    pub difference_to_offline: BTreeMap<String, f64>,
    /// Whether every PILS solution equals the quantized offline one bit for bit.
    pub equal_to_offline_quantized: Option<bool>,
}

/// `summary.json` rows in the project's shape (`method`, `metric`, `value`).
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// `pils/<method>`, `offline/<method>`, ...
    pub method: String,
    /// Metric name.
    pub metric: String,
    /// Paper value (none for PILS).
    pub paper: Option<f64>,
    /// Measured value.
    pub value: f64,
    /// No Monte Carlo interval for one run.
    pub ci95: Option<[f64; 2]>,
}

/// The simulator's output files (name, content): `summary.json` (rows in the
/// shape `fathom run` writes), `pils.json` (the whole report) and `solutions.csv`
/// (the decoded solutions). The caller writes them (no file I/O in this crate).
pub fn sim_files(r: &SimReport, sols: &BTreeMap<u64, Solution>) -> Vec<(&'static str, String)> {
    let mut rows = Vec::new();
    for (label, st) in [
        ("pils", &r.pils),
        ("offline_quantized", &r.offline_quantized),
        ("offline", &r.offline),
    ] {
        if let Some(st) = st {
            for (m, v) in st.metrics() {
                rows.push(Row {
                    method: format!("{label}/{}", r.method),
                    metric: m.into(),
                    paper: None,
                    value: v,
                    ci95: None,
                });
            }
        }
    }
    let summary = serde_json::json!({
        "experiment": "pils",
        "seed_doc": "004_a46751abbc309235.txt",
        "runs": 1,
        "rows": rows,
        "claims": [],
    });
    vec![
        (
            "summary.json",
            serde_json::to_string_pretty(&summary).unwrap_or_default(),
        ),
        (
            "pils.json",
            serde_json::to_string_pretty(r).unwrap_or_default(),
        ),
        ("solutions.csv", solutions_csv(sols)),
    ]
}

/// Solutions as CSV with round-trip `f64` text.
pub fn solutions_csv(sols: &BTreeMap<u64, Solution>) -> String {
    let mut s = String::from("step,time,n,e,d,vn,ve,vd,qw,qx,qy,qz,map_aided\n");
    for (k, x) in sols {
        let q = x.nav_from_body.quaternion();
        s.push_str(&format!(
            "{k},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            x.time,
            x.pos_in_nav.x,
            x.pos_in_nav.y,
            x.pos_in_nav.z,
            x.vel_in_nav.x,
            x.vel_in_nav.y,
            x.vel_in_nav.z,
            q.w,
            q.i,
            q.j,
            q.k,
            u8::from(x.map_aided)
        ));
    }
    s
}

//! Evaluation of the solutions against the truth (the rows `fathom run` writes for a
//! method), the offline reference runs, and the output files of both sides.

use std::collections::BTreeMap;

use fathom_core::frames::euler_from_nav_from_body;
use fathom_core::units::wrap_pi;
use fathom_report::output::{CsvWriter, Row, Summary, csv_string};
use serde::Serialize;

use crate::PilsError;
use crate::assemble::Schedule;
use crate::assemble::quantize_epochs;
use crate::codec::{quantize_initial, quantize_solution};
use crate::epoch::{Epoch, InitialEstimate, Solution};
use crate::source::{IMU_DT, Navigator, SensorSource};
use crate::stats::{LinkCounters, Percentiles};
use crate::urban_flight::{UrbanFlight, UrbanNav, UrbanRun};

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

/// The unit of a metric of [`ErrorStats::metrics`].
pub fn unit(metric: &str) -> &'static str {
    match metric {
        "rmse_vel" => "m/s",
        "rmse_roll" | "rmse_pitch" | "rmse_yaw" => "deg",
        "time_map_aided_s" => "s",
        _ => "m",
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

/// Runs the flight's method offline on the simulated run: with `quantized`, every measurement,
/// the initial estimate and every solution go through the MAVLink encode / decode
/// functions (what the lockstep PILS run sees); without, the `f64` values.
///
/// # Errors
/// [`PilsError::Model`] when the navigation fails.
pub fn offline(
    fl: &UrbanFlight,
    run: &UrbanRun,
    quantized: bool,
) -> Result<BTreeMap<u64, Solution>, PilsError> {
    let env = fl.env();
    let mut nav = UrbanNav::new(fl, &env);
    offline_with(
        &fl.schedule,
        run.epochs(),
        run.initial(),
        &mut nav,
        quantized,
    )
}

/// Runs the navigator `nav` offline over `epochs` (step 1 onward) with the initial
/// estimate `init` at the schedule's start step; with `quantized`, the measurements,
/// the initial estimate and the solutions go through the MAVLink encode / decode
/// functions (what a lockstep session sees).
///
/// # Errors
/// [`PilsError::Model`] when the navigation fails.
pub fn offline_with(
    schedule: &Schedule,
    epochs: &[Epoch],
    init: &InitialEstimate,
    nav: &mut dyn Navigator,
    quantized: bool,
) -> Result<BTreeMap<u64, Solution>, PilsError> {
    let epochs = if quantized {
        quantize_epochs(epochs, &schedule.frame, &schedule.wire, 0.0)
    } else {
        epochs.to_vec()
    };
    let init = if quantized {
        quantize_initial(init)
    } else {
        *init
    };
    let mut out = BTreeMap::new();
    for e in &epochs {
        let i = (e.step == schedule.start).then_some(&init);
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
    /// The scene flown (the `urban` scenario's name for it).
    pub scenario: String,
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

/// The seed paper of the map-aided flight that PILS flies (`summary.json`'s
/// `seed_doc`).
pub const SEED_DOC: &str = "004_a46751abbc309235.txt";

/// The simulator's `summary.json`: the shared contract ([`Summary`], read back by
/// `fathom_report::output::read_summary_json`) of one run (`runs` 1, `base_seed` the
/// settings' `seed`), rows `<pils|offline_quantized|offline>/<method>` x
/// [`ErrorStats::metrics`] (no paper value, no interval for one run), no claims, and
/// the extra keys `method`, `scenario` (the scene), `pacing`, `run` (the settings' run index), `status` and
/// `equal_to_offline_quantized` (`null` when the references were not run). JSON has
/// no NaN: a metric that is not finite (a diverged navigation) gets no row and is
/// named in the extra key `non_finite` instead.
pub fn sim_summary(r: &SimReport, seed: u64, run: u64) -> Summary {
    let mut s = Summary::new("pils", SEED_DOC, 1, seed);
    let mut non_finite = Vec::new();
    for (label, st) in [
        ("pils", &r.pils),
        ("offline_quantized", &r.offline_quantized),
        ("offline", &r.offline),
    ] {
        for (m, v) in st.iter().flat_map(ErrorStats::metrics) {
            let method = format!("{label}/{}/{}", r.scenario, r.method);
            if v.is_finite() {
                s.push_row(Row::new(method, m, v).with_unit(unit(m)));
            } else {
                non_finite.push(format!("{method} {m}"));
            }
        }
    }
    let extra = [
        ("method", serde_json::json!(r.method)),
        ("scenario", serde_json::json!(r.scenario)),
        ("pacing", serde_json::json!(r.pacing)),
        ("run", serde_json::json!(run)),
        ("status", serde_json::json!(r.status)),
        (
            "equal_to_offline_quantized",
            serde_json::json!(r.equal_to_offline_quantized),
        ),
    ];
    for (k, v) in extra {
        s.extra.insert(k.into(), v);
    }
    if !non_finite.is_empty() {
        s.extra
            .insert("non_finite".into(), serde_json::json!(non_finite));
    }
    s
}

/// The simulator's output files (name, content): `summary.json` ([`sim_summary`]),
/// `pils.json` (the whole report) and `solutions.csv` (the decoded solutions). The
/// caller writes them (no file I/O in this crate).
///
/// # Errors
/// [`PilsError::Model`] if the summary or the CSV cannot be formatted.
pub fn sim_files(
    r: &SimReport,
    sols: &BTreeMap<u64, Solution>,
    seed: u64,
    run: u64,
) -> Result<Vec<(&'static str, String)>, PilsError> {
    let summary = sim_summary(r, seed, run)
        .to_json_pretty()
        .map_err(|e| PilsError::model("summary.json", e))?;
    Ok(vec![
        ("summary.json", summary),
        (
            "pils.json",
            serde_json::to_string_pretty(r).unwrap_or_default(),
        ),
        ("solutions.csv", solutions_csv(sols)?),
    ])
}

/// The header of `solutions.csv`.
const SOLUTIONS_HEADER: [&str; 13] = [
    "step",
    "time",
    "n",
    "e",
    "d",
    "vn",
    "ve",
    "vd",
    "qw",
    "qx",
    "qy",
    "qz",
    "map_aided",
];

/// Solutions as CSV with round-trip `f64` text (fathom-report's CSV writer).
///
/// # Errors
/// [`PilsError::Model`] if the CSV cannot be formatted (it is written in memory).
pub fn solutions_csv(sols: &BTreeMap<u64, Solution>) -> Result<String, PilsError> {
    csv_string(|w| {
        w.record(SOLUTIONS_HEADER)?;
        for (k, x) in sols {
            solution_record(w, *k, x)?;
        }
        Ok(())
    })
    .map_err(|e| PilsError::model("solutions.csv", e))
}

/// One solution's record of `solutions.csv`.
fn solution_record(w: &mut CsvWriter<Vec<u8>>, step: u64, x: &Solution) -> std::io::Result<()> {
    let q = x.nav_from_body.quaternion();
    w.display(step)?;
    for v in [
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
    ] {
        w.float(v)?;
    }
    w.display(u8::from(x.map_aided))?;
    w.end_record()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, UnitQuaternion, Vector3};

    fn stats(rmse_3d: f64) -> ErrorStats {
        ErrorStats {
            samples: 10,
            rmse_h: 0.5,
            rmse_3d,
            rmse_vel: 0.1,
            rmse_roll: 0.2,
            rmse_pitch: 0.3,
            rmse_yaw: 1.5,
            mean_3d: 0.9,
            p95_3d: 2.0,
            time_map_aided_s: 12.5,
        }
    }

    fn report() -> SimReport {
        SimReport {
            status: "ok".into(),
            method: "MGPMF".into(),
            scenario: "buildings".into(),
            pacing: "lockstep".into(),
            steps_sent: 100,
            steps_total: 100,
            solutions: 90,
            late_solutions: 0,
            retransmissions: 0,
            latency: None,
            wall_s: 1.0,
            sim_s: 1.0,
            real_time_factor: 1.0,
            link: LinkCounters::default(),
            pils: Some(stats(1.25)),
            offline_quantized: Some(stats(1.25)),
            offline: None,
            difference_to_offline: BTreeMap::new(),
            equal_to_offline_quantized: Some(true),
        }
    }

    /// `summary.json` is the shared contract: it reads back as a `Summary` (what
    /// `read_summary_json` does) with the settings' seed as `base_seed`, one row per
    /// evaluated method and metric, and the session's facts as extra keys.
    #[test]
    fn sim_summary_is_the_shared_contract() {
        let sol = Solution {
            step: 7,
            time: 0.01,
            pos_in_nav: Vector3::new(1.0, -2.5, 0.1),
            vel_in_nav: Vector3::new(0.0, 1e-7, -0.5),
            nav_from_body: UnitQuaternion::identity(),
            omega_body: Vector3::zeros(),
            pos_cov: Matrix3::identity(),
            att_cov: Matrix3::identity(),
            pos_att_cov: Matrix3::zeros(),
            vel_cov: Matrix3::identity(),
            map_aided: true,
        };
        let sols = BTreeMap::from([(7u64, sol)]);
        let files = sim_files(&report(), &sols, 42, 3).unwrap();
        let text = &files.iter().find(|f| f.0 == "summary.json").unwrap().1;
        let back: Summary = serde_json::from_str(text).unwrap();
        assert_eq!(
            (back.experiment.as_str(), back.runs, back.base_seed),
            ("pils", 1, 42)
        );
        assert_eq!(back.seed_doc, SEED_DOC);
        assert_eq!(back.rows.len(), 18);
        assert_eq!(
            back.row("pils/buildings/MGPMF", "rmse_3d").unwrap().value,
            1.25
        );
        assert!(back.row("offline/buildings/MGPMF", "rmse_3d").is_none());
        assert!(back.claims.is_empty());
        assert_eq!(back.extra["run"], 3);
        assert_eq!(back.extra["pacing"], "lockstep");
        assert_eq!(back.extra["equal_to_offline_quantized"], true);
        assert!(!back.extra.contains_key("non_finite"));
        let csv = &files.iter().find(|f| f.0 == "solutions.csv").unwrap().1;
        assert_eq!(
            csv,
            "step,time,n,e,d,vn,ve,vd,qw,qx,qy,qz,map_aided\n\
             7,0.01,1,-2.5,0.1,0,0.0000001,-0.5,1,0,0,0,1\n"
        );
        // A diverged metric has no row (JSON has no NaN) and is named instead.
        let mut r = report();
        r.pils = Some(stats(f64::NAN));
        let s = sim_summary(&r, 42, 3);
        assert!(s.row("pils/buildings/MGPMF", "rmse_3d").is_none());
        assert_eq!(s.extra["non_finite"][0], "pils/buildings/MGPMF rmse_3d");
        assert!(s.to_json_pretty().is_ok());
    }
}

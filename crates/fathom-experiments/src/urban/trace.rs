//! Evaluation of one method in one run: the errors at every evaluation epoch (the
//! estimate after the epoch's updates against the truth), and the run's statistics.
//!
//! Errors are estimated minus true: position and velocity in NED, roll / pitch / yaw
//! differences (wrapped to ±180°), and the 9-state NEES of position, velocity and
//! attitude (`psi = log(C_hat C^T)`, the filter's attitude error) with the filter's
//! covariance block.

use fathom_core::frames::euler_from_nav_from_body;
use fathom_core::units::wrap_pi;
use fathom_estimators::map_aided::{Matrix12, NominalNav};
use fathom_ins::local_level::LocalTruthSample;
use nalgebra::{SMatrix, SVector, Vector3};
use serde::{Deserialize, Serialize};

use fathom_sim::SimError;

/// The per-run statistics of one method (the rows' per-run values).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MethodStats {
    /// Horizontal position RMSE, m.
    pub rmse_h: f64,
    /// 3-D position RMSE, m.
    pub rmse_3d: f64,
    /// 3-D velocity RMSE, m/s.
    pub rmse_vel: f64,
    /// Roll RMSE, deg.
    pub rmse_roll: f64,
    /// Pitch RMSE, deg.
    pub rmse_pitch: f64,
    /// Yaw RMSE, deg.
    pub rmse_yaw: f64,
    /// Mean 3-D position error, m.
    pub mean_3d: f64,
    /// 95th percentile of the 3-D position error over the run, m.
    pub p95_3d: f64,
    /// Largest roll, pitch or yaw error, deg.
    pub max_att: f64,
    /// Time in map-aided mode, s.
    pub time_map_aided_s: f64,
    /// Time average of the 9-state NEES.
    pub nees_mean: f64,
    /// 3-D position RMSE over the open-sky epochs (at least as many satellites in
    /// true line of sight as GPS/INS needs to be re-entered), m; `None` when the
    /// flight has no such epoch. Not in [`MethodStats::METRICS`].
    #[serde(default)]
    pub rmse_3d_open: Option<f64>,
}

impl MethodStats {
    /// The metric names, in row order.
    pub const METRICS: [&'static str; 11] = [
        "rmse_h",
        "rmse_3d",
        "rmse_vel",
        "rmse_roll",
        "rmse_pitch",
        "rmse_yaw",
        "mean_3d",
        "p95_3d",
        "max_att",
        "time_map_aided_s",
        "nees_mean",
    ];

    /// The values in the order of [`MethodStats::METRICS`].
    pub fn values(&self) -> [f64; 11] {
        [
            self.rmse_h,
            self.rmse_3d,
            self.rmse_vel,
            self.rmse_roll,
            self.rmse_pitch,
            self.rmse_yaw,
            self.mean_3d,
            self.p95_3d,
            self.max_att,
            self.time_map_aided_s,
            self.nees_mean,
        ]
    }
}

/// The errors at the evaluation epochs of one method.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trace {
    /// Epoch times, s.
    pub times: Vec<f64>,
    /// Position errors, NED, m.
    pub pos: Vec<Vector3<f64>>,
    /// Velocity errors, NED, m/s.
    pub vel: Vec<Vector3<f64>>,
    /// Roll, pitch, yaw errors, deg.
    pub att: Vec<[f64; 3]>,
    /// 9-state NEES (`None` where the covariance block is not positive definite).
    pub nees: Vec<Option<f64>>,
    /// Whether the map-aided mode was active.
    pub map_mode: Vec<bool>,
    /// Whether the sky was open (true LOS count at least the GPS re-entry count).
    pub open_sky: Vec<bool>,
    /// Estimated positions, NED, m.
    pub est_pos: Vec<Vector3<f64>>,
    /// Time spent in map-aided mode, s.
    pub map_time_s: f64,
}

impl Trace {
    /// Adds the epoch of `nav` (with covariance `cov`) against `truth`; `map`: the
    /// map-aided mode was active, `open_sky`: the sky was open.
    pub fn push(
        &mut self,
        nav: &NominalNav,
        cov: &Matrix12,
        truth: &LocalTruthSample,
        map: bool,
        open_sky: bool,
    ) {
        let dp = nav.pos_in_nav - truth.pos_in_nav;
        let dv = nav.vel_in_nav - truth.vel_in_nav;
        let psi = (nav.nav_from_body * truth.nav_from_body.inverse()).scaled_axis();
        let e_est = euler_from_nav_from_body(&nav.nav_from_body.to_rotation_matrix());
        let e_true = euler_from_nav_from_body(&truth.nav_from_body.to_rotation_matrix());
        let att = [
            wrap_pi(e_est.roll - e_true.roll).to_degrees(),
            wrap_pi(e_est.pitch - e_true.pitch).to_degrees(),
            wrap_pi(e_est.yaw - e_true.yaw).to_degrees(),
        ];
        let mut e9 = SVector::<f64, 9>::zeros();
        e9.fixed_rows_mut::<3>(0).copy_from(&dp);
        e9.fixed_rows_mut::<3>(3).copy_from(&dv);
        e9.fixed_rows_mut::<3>(6).copy_from(&psi);
        let p9: SMatrix<f64, 9, 9> = cov.fixed_view::<9, 9>(0, 0).into_owned();
        let nees = p9
            .cholesky()
            .map(|c| e9.dot(&c.solve(&e9)))
            .filter(|v| v.is_finite());
        self.times.push(truth.time);
        self.pos.push(dp);
        self.vel.push(dv);
        self.att.push(att);
        self.nees.push(nees);
        self.map_mode.push(map);
        self.open_sky.push(open_sky);
        self.est_pos.push(nav.pos_in_nav);
    }

    /// 3-D position errors, m.
    pub fn err_3d(&self) -> Vec<f64> {
        self.pos.iter().map(|p| p.norm()).collect()
    }

    /// 3-D velocity errors, m/s.
    pub fn err_vel(&self) -> Vec<f64> {
        self.vel.iter().map(|v| v.norm()).collect()
    }

    /// Attitude error magnitudes `sqrt(roll² + pitch² + yaw²)`, deg.
    pub fn err_att(&self) -> Vec<f64> {
        self.att
            .iter()
            .map(|a| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt())
            .collect()
    }

    /// The run's statistics.
    ///
    /// # Errors
    /// [`SimError::InvalidArgument`] for a trace without epochs or with non-finite
    /// errors (a diverged method).
    pub fn stats(&self) -> Result<MethodStats, SimError> {
        let n = self.pos.len();
        if n == 0 {
            return Err(SimError::invalid_argument(
                "urban trace",
                "no evaluation epoch",
            ));
        }
        let nf = n as f64;
        let rms =
            |f: &dyn Fn(usize) -> f64| ((0..n).map(|i| f(i).powi(2)).sum::<f64>() / nf).sqrt();
        let e3 = self.err_3d();
        let p95 = fathom_stats::sample::quantile(&e3, 0.95)?;
        let nees: Vec<f64> = self.nees.iter().flatten().copied().collect();
        let open: Vec<f64> = e3
            .iter()
            .zip(&self.open_sky)
            .filter(|(_, o)| **o)
            .map(|(e, _)| e * e)
            .collect();
        let rmse_3d_open =
            (!open.is_empty()).then(|| (open.iter().sum::<f64>() / open.len() as f64).sqrt());
        let stats = MethodStats {
            rmse_h: rms(&|i| self.pos[i].xy().norm()),
            rmse_3d: rms(&|i| e3[i]),
            rmse_vel: rms(&|i| self.vel[i].norm()),
            rmse_roll: rms(&|i| self.att[i][0]),
            rmse_pitch: rms(&|i| self.att[i][1]),
            rmse_yaw: rms(&|i| self.att[i][2]),
            mean_3d: e3.iter().sum::<f64>() / nf,
            p95_3d: p95,
            max_att: self
                .att
                .iter()
                .flat_map(|a| a.iter().map(|v| v.abs()))
                .fold(0.0, f64::max),
            time_map_aided_s: self.map_time_s,
            nees_mean: if nees.is_empty() {
                0.0
            } else {
                nees.iter().sum::<f64>() / nees.len() as f64
            },
            rmse_3d_open,
        };
        if stats.values().iter().all(|v| v.is_finite())
            && stats.rmse_3d_open.is_none_or(f64::is_finite)
        {
            Ok(stats)
        } else {
            Err(SimError::invalid_argument(
                "urban trace",
                format!("non-finite statistics {stats:?}"),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    fn truth(t: f64) -> LocalTruthSample {
        LocalTruthSample {
            time: t,
            pos_in_nav: Vector3::new(1.0, 2.0, -3.0),
            vel_in_nav: Vector3::new(0.5, 0.0, 0.0),
            nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, 3.1),
        }
    }

    /// Known errors give the statistics by hand; the yaw difference wraps across ±180°.
    #[test]
    fn statistics_of_known_errors() {
        let mut tr = Trace::default();
        let cov = Matrix12::identity();
        for (k, dx) in [3.0, 4.0].iter().enumerate() {
            let t = truth(k as f64);
            let nav = NominalNav {
                pos_in_nav: t.pos_in_nav + Vector3::new(*dx, 0.0, 0.0),
                vel_in_nav: t.vel_in_nav,
                nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, 3.1 + 0.1)
                    * UnitQuaternion::identity(),
                accel_bias_in_body: Vector3::zeros(),
            };
            tr.push(&nav, &cov, &t, k == 1, k == 0);
        }
        tr.map_time_s = 1.0;
        let s = tr.stats().unwrap();
        assert!((s.rmse_3d - (12.5f64).sqrt()).abs() < 1e-12);
        assert!((s.mean_3d - 3.5).abs() < 1e-12);
        assert!((s.rmse_yaw - 0.1f64.to_degrees()).abs() < 1e-9, "{s:?}");
        assert!((s.max_att - 0.1f64.to_degrees()).abs() < 1e-9);
        // identity covariance: NEES = |dp|^2 + |psi|^2
        assert!((s.nees_mean - (12.5 + 0.01)).abs() < 1e-9, "{s:?}");
        assert_eq!(s.time_map_aided_s, 1.0);
        // only the first epoch (3 m off) was in open sky
        assert_eq!(s.rmse_3d_open, Some(3.0));
        tr.open_sky = vec![false, false];
        assert_eq!(tr.stats().unwrap().rmse_3d_open, None);
        assert!(Trace::default().stats().is_err());
    }
}

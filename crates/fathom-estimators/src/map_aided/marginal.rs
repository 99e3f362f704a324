//! The marginalization of eq. (15)/(19) shared by the MGPMF and the particle filter:
//! the split of the 12 error states into the nonlinear part `n` (horizontal position
//! error and yaw error, sampled by grid points or particles) and the linear part `l`
//! (the other nine), the Gaussian conditional `p(l | n)`, and the Kalman update of
//! `l` conditioned on `n` that, with the posterior Gaussian of `n`, gives the joint
//! posterior.
//!
//! # The conditional update (eq. 15, 19)
//!
//! Prior: `n ~ N(mu_n, P_nn)`, `l | n ~ N(mu_l + A (n - mu_n), P_l|n)` with
//! `A = P_ln P_nn^-1`, `P_l|n = P_ll - A P_nl`. The posterior of `n` comes from the
//! points, `N(n*, P_n+)`. The ranges, linearized at `(n*, l* = mu_l + A (n* - mu_n))`,
//! read `z = h(n*, l*) + H_n (n - n*) + H_l (l - l*) + v` (eq. 16), so the Kalman
//! filter of `l` given `n` has an affine mean `c + B (n - n*)`: starting from `c = l*`,
//! `B = A`, `P = P_l|n`, each accepted scalar row updates
//!
//! ```text
//! s = h_l P h_l^T + r,  k = P h_l^T / s
//! c += k (nu - h_l (c - l*)),  B -= k (h_n + h_l B),  P = (I - k h_l) P (I - k h_l)^T + k r k^T
//! ```
//!
//! and the joint posterior is `mean = (n*, c)`, `P_nn = P_n+`, `P_ln = B P_n+`,
//! `P_ll = P + B P_n+ B^T`. Rows failing the chi-square gate on the initial
//! `s = h_l P_l|n h_l^T + r` (the residual after the grid fixed `n`) are left out.

use fathom_core::{Gaussian, Ray, RayCaster, RayHit};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::error::MapAidedError;
use super::ins12::{Ins12Filter, NominalNav};
use super::params::RangeSettings;
use super::range_model::{BaroHeight, BeamGeometry, RangeBeam, baro_row12};
use super::{ACCEL_BIAS, ATT, ErrorVector12, Matrix12, POS, VEL};

/// Indices of the nonlinear states `n` in the 12-vector: north and east position
/// error, yaw error.
pub const NONLINEAR: [usize; 3] = [POS, POS + 1, ATT + 2];
/// Indices of the linear states `l` in the 12-vector.
pub const LINEAR: [usize; 9] = [
    POS + 2,
    VEL,
    VEL + 1,
    VEL + 2,
    ATT,
    ATT + 1,
    ACCEL_BIAS,
    ACCEL_BIAS + 1,
    ACCEL_BIAS + 2,
];
/// Positions in `l` of the linear states that move the pose: down position error,
/// roll-axis and pitch-axis (north, east) attitude errors.
pub(crate) const L_POSE: [usize; 3] = [0, 4, 5];

/// A 9-vector of linear states.
pub type LinearVector = SVector<f64, 9>;

/// The prior split into `n` and `l | n`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Partition {
    pub mu_n: Vector3<f64>,
    pub mu_l: LinearVector,
    pub p_nn: Matrix3<f64>,
    /// `P_nn^-1`.
    pub p_nn_inv: Matrix3<f64>,
    /// `A = P_ln P_nn^-1` (9 x 3).
    pub a: SMatrix<f64, 9, 3>,
    /// `P_l|n`.
    pub p_l_given_n: SMatrix<f64, 9, 9>,
}

impl Partition {
    /// The split of `N(mean, p)`; `None` if `P_nn` is not positive definite (not
    /// possible for the filter's positive definite `P`).
    pub fn new(mean: &ErrorVector12, p: &Matrix12) -> Option<Self> {
        let mu_n = Vector3::from_fn(|i, _| mean[NONLINEAR[i]]);
        let mu_l = LinearVector::from_fn(|i, _| mean[LINEAR[i]]);
        let p_nn = Matrix3::from_fn(|i, j| p[(NONLINEAR[i], NONLINEAR[j])]);
        let p_ln = SMatrix::<f64, 9, 3>::from_fn(|i, j| p[(LINEAR[i], NONLINEAR[j])]);
        let p_ll = SMatrix::<f64, 9, 9>::from_fn(|i, j| p[(LINEAR[i], LINEAR[j])]);
        let chol = p_nn.cholesky()?;
        let p_nn_inv = chol.inverse();
        let a = p_ln * p_nn_inv;
        let p_l_given_n = p_ll - a * p_ln.transpose();
        let p_l_given_n = (p_l_given_n + p_l_given_n.transpose()) * 0.5;
        Some(Self {
            mu_n,
            mu_l,
            p_nn,
            p_nn_inv,
            a,
            p_l_given_n,
        })
    }

    /// `E[l | n] = mu_l + A (n - mu_n)`.
    pub fn linear_mean(&self, n: &Vector3<f64>) -> LinearVector {
        self.mu_l + self.a * (n - self.mu_n)
    }

    /// The 12-vector of `(n, l)`.
    pub fn join(n: &Vector3<f64>, l: &LinearVector) -> ErrorVector12 {
        let mut x = ErrorVector12::zeros();
        for i in 0..3 {
            x[NONLINEAR[i]] = n[i];
        }
        for i in 0..9 {
            x[LINEAR[i]] = l[i];
        }
        x
    }

    /// The pose-moving linear states `(dp_D, psi_N, psi_E)` at `E[l | n]` as an affine
    /// map `n -> base + slope (n - mu_n)`, and their conditional covariance.
    pub fn pose_part(&self) -> (Vector3<f64>, Matrix3<f64>, Matrix3<f64>) {
        let base = Vector3::from_fn(|i, _| self.mu_l[L_POSE[i]]);
        let slope = Matrix3::from_fn(|i, j| self.a[(L_POSE[i], j)]);
        let cov = Matrix3::from_fn(|i, j| self.p_l_given_n[(L_POSE[i], L_POSE[j])]);
        (base, slope, cov)
    }
}

/// One scalar row of the linear step: `z - h(n*, l*) = h_n (n - n*) + h_l (l - l*) + v`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct LinearRow {
    h_n: Vector3<f64>,
    h_l: LinearVector,
    nu: f64,
    r: f64,
}

impl LinearRow {
    fn from_row12(h: &nalgebra::RowSVector<f64, 12>, nu: f64, r: f64) -> Self {
        Self {
            h_n: Vector3::from_fn(|i, _| h[NONLINEAR[i]]),
            h_l: LinearVector::from_fn(|i, _| h[LINEAR[i]]),
            nu,
            r,
        }
    }
}

/// What the linear step did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinearStepReport {
    /// Beams used in the conditional Kalman update.
    pub beams_used: usize,
    /// Beams without a predicted hit at the posterior mean pose.
    pub no_hit: usize,
    /// Beams beyond the largest incidence angle there.
    pub grazing: usize,
    /// Rows (beams and baro) rejected by the gate.
    pub gated: usize,
    /// Whether the barometer row was used.
    pub baro_used: bool,
}

/// Buffers of the linear step (reused across updates).
#[derive(Debug, Clone, Default)]
pub(crate) struct LinearStep {
    rays: Vec<Ray>,
    hits: Vec<Option<RayHit>>,
    rows: Vec<LinearRow>,
}

impl LinearStep {
    /// The conditional update (module docs) at the posterior `N(n_star, p_n_post)` of
    /// `n`, then the joint posterior committed to `filter`. `unit_dirs` are the beams'
    /// unit body directions.
    ///
    /// # Errors
    /// [`MapAidedError::Filter`] if the joint posterior is not a valid covariance (the
    /// filter is then unchanged).
    #[allow(clippy::too_many_arguments)]
    pub fn update_and_commit(
        &mut self,
        filter: &mut Ins12Filter,
        part: &Partition,
        nominal: &NominalNav,
        beams: &[RangeBeam],
        unit_dirs: &[Vector3<f64>],
        baro: Option<&BaroHeight>,
        n_star: &Vector3<f64>,
        p_n_post: &Matrix3<f64>,
        settings: &RangeSettings,
        caster: &dyn RayCaster,
    ) -> Result<LinearStepReport, MapAidedError> {
        let l_star = part.linear_mean(n_star);
        let pose = nominal.corrected(&Partition::join(n_star, &l_star));
        let c = pose.nav_from_body.to_rotation_matrix().into_inner();
        self.rays.clear();
        self.rays.extend(
            unit_dirs
                .iter()
                .map(|d| Ray::new(pose.pos_in_nav, c * d, settings.max_range)),
        );
        self.hits.clear();
        self.hits.resize(self.rays.len(), None);
        let _ = caster.cast_batch(&self.rays, &mut self.hits);

        let mut report = LinearStepReport::default();
        self.rows.clear();
        let p0 = &part.p_l_given_n;
        let gate_ok = |row: &LinearRow| {
            let s = row.h_l.dot(&(p0 * row.h_l)) + row.r;
            row.nu * row.nu / s <= settings.gate
        };
        for ((beam, ray), hit) in beams.iter().zip(&self.rays).zip(&self.hits) {
            let Some(hit) = hit else {
                report.no_hit += 1;
                continue;
            };
            let geom = BeamGeometry::from_hit(hit, ray.dir_in_nav);
            if geom.cos_incidence() < settings.min_cos_incidence {
                report.grazing += 1;
                continue;
            }
            let row = LinearRow::from_row12(
                &geom.row12(),
                beam.range_m - geom.range,
                beam.sigma_m * beam.sigma_m,
            );
            if gate_ok(&row) {
                self.rows.push(row);
            } else {
                report.gated += 1;
            }
        }
        report.beams_used = self.rows.len();
        if let Some(b) = baro {
            let row = LinearRow::from_row12(
                &baro_row12(),
                b.height_m + pose.pos_in_nav.z,
                b.sigma_m * b.sigma_m,
            );
            if gate_ok(&row) {
                self.rows.push(row);
                report.baro_used = true;
            } else {
                report.gated += 1;
            }
        }

        let mut c_mean = l_star;
        let mut b = part.a;
        let mut p = *p0;
        let eye = SMatrix::<f64, 9, 9>::identity();
        for row in &self.rows {
            let ph = p * row.h_l;
            let s = row.h_l.dot(&ph) + row.r;
            let k = ph / s;
            let innov = row.nu - row.h_l.dot(&(c_mean - l_star));
            c_mean += k * innov;
            let hb = row.h_n.transpose() + row.h_l.transpose() * b;
            b -= k * hb;
            let ikh = eye - k * row.h_l.transpose();
            p = ikh * p * ikh.transpose() + k * k.transpose() * row.r;
            p = (p + p.transpose()) * 0.5;
        }

        let mean = Partition::join(n_star, &c_mean);
        let p_ln = b * p_n_post;
        let p_ll = p + b * p_n_post * b.transpose();
        let mut cov = Matrix12::zeros();
        for i in 0..3 {
            for j in 0..3 {
                cov[(NONLINEAR[i], NONLINEAR[j])] = p_n_post[(i, j)];
            }
        }
        for i in 0..9 {
            for j in 0..3 {
                cov[(LINEAR[i], NONLINEAR[j])] = p_ln[(i, j)];
                cov[(NONLINEAR[j], LINEAR[i])] = p_ln[(i, j)];
            }
            for j in 0..9 {
                cov[(LINEAR[i], LINEAR[j])] = p_ll[(i, j)];
            }
        }
        let cov = (cov + cov.transpose()) * 0.5;
        filter
            .kf_mut()
            .set_estimate(Gaussian::new_unchecked(mean, cov))?;
        Ok(report)
    }
}

/// Weighted mean and covariance of `points` with weights `w` (not normalized; the
/// sum must be > 0): eq. (17)-(18).
pub(crate) fn weighted_moments(points: &[Vector3<f64>], w: &[f64]) -> (Vector3<f64>, Matrix3<f64>) {
    let total: f64 = w.iter().sum();
    let mut mean = Vector3::zeros();
    for (x, wi) in points.iter().zip(w) {
        mean += x * *wi;
    }
    mean /= total;
    let mut cov = Matrix3::zeros();
    for (x, wi) in points.iter().zip(w) {
        if *wi > 0.0 {
            let d = x - mean;
            cov += d * d.transpose() * *wi;
        }
    }
    (mean, cov / total)
}

/// `exp(log_w - max)` into `w`, returning the effective sample size
/// `(sum w)^2 / sum w^2`; `None` if no log-weight is finite.
pub(crate) fn normalize_log_weights(log_w: &[f64], w: &mut Vec<f64>) -> Option<f64> {
    let max = log_w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !max.is_finite() {
        return None;
    }
    w.clear();
    w.extend(log_w.iter().map(|l| (l - max).exp()));
    let (s1, s2) = w.iter().fold((0.0, 0.0), |(a, b), x| (a + x, b + x * x));
    Some(s1 * s1 / s2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_spd(seed: u64) -> Matrix12 {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let a = Matrix12::from_fn(|_, _| rng.random::<f64>() - 0.5);
        a * a.transpose() + Matrix12::identity() * 0.1
    }

    /// With no rows, the conditional update returns the prior exactly (the joint of
    /// `N(mu_n, P_nn)` and `p(l | n)` is the original Gaussian).
    #[test]
    fn partition_and_join_reproduce_the_prior() {
        let p = random_spd(3);
        let mean = ErrorVector12::from_fn(|i, _| i as f64 * 0.1);
        let part = Partition::new(&mean, &p).unwrap();
        let x = Partition::join(&part.mu_n, &part.linear_mean(&part.mu_n));
        assert!((x - mean).amax() < 1e-15);
        // rebuild P from the pieces as update_and_commit does with no rows
        let b = part.a;
        let p_ln = b * part.p_nn;
        let p_ll = part.p_l_given_n + b * part.p_nn * b.transpose();
        for i in 0..9 {
            for j in 0..3 {
                assert!((p_ln[(i, j)] - p[(LINEAR[i], NONLINEAR[j])]).abs() < 1e-12);
            }
            for j in 0..9 {
                assert!((p_ll[(i, j)] - p[(LINEAR[i], LINEAR[j])]).abs() < 1e-12);
            }
        }
        let (base, slope, cov) = part.pose_part();
        assert_eq!(base[0], mean[POS + 2]);
        assert_eq!(slope[(1, 2)], part.a[(4, 2)]);
        assert_eq!(cov[(2, 2)], part.p_l_given_n[(5, 5)]);
    }

    #[test]
    fn moments_and_weights() {
        let pts = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(2.0, 0.0, 0.0)];
        let (m, c) = weighted_moments(&pts, &[1.0, 1.0]);
        assert_eq!(m, Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(c[(0, 0)], 1.0);
        let mut w = Vec::new();
        let ess = normalize_log_weights(&[-1000.0, -1000.0, -1000.0], &mut w).unwrap();
        assert!((ess - 3.0).abs() < 1e-12 && w == [1.0, 1.0, 1.0]);
        assert!(normalize_log_weights(&[f64::NEG_INFINITY], &mut w).is_none());
    }
}

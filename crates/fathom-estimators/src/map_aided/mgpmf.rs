//! MGPMF (section 2.3, refs 11-12): the marginalized Gaussian point-mass update of the
//! 12-state filter.
//!
//! 1. The prior `N(mu, P)` of the filter is split (eq. 15, [`super::marginal`]) into
//!    the nonlinear states `n = (dp_N, dp_E, psi_D)` and the linear rest `l | n`.
//! 2. A regular grid of `N_N x N_E x N_psi` points spans `mu_n +- k sigma` on each
//!    axis (`sigma` the marginal standard deviations; an axis-aligned box, so the
//!    cells are equal and the interpolation below is exact on it).
//! 3. Each point's beams are ray cast from its candidate pose and weighted by the
//!    robust range likelihood ([`super::likelihood`], averaged over the point's
//!    interpolation kernel) times the Gaussian prior of `n`.
//! 4. The posterior of `n` is the Gaussian of eq. (17)-(18) with the paper's linear
//!    interpolation between points against sparsity: the moments of the
//!    piecewise-linear interpolant of the weights, i.e. the mean of eq. (17) and the
//!    covariance of eq. (18) plus `diag(spacing^2 / 6)` (the variance of each point's
//!    hat function), which stays positive definite even when one point carries all
//!    the weight.
//! 5. The linear states are updated by a Kalman filter conditioned on `n`
//!    (eq. 15/19), linearized at the posterior mean, and the joint Gaussian replaces
//!    the filter's estimate.
//!
//! The grid points, weights and ray buffers are allocated once and reused by every
//! update; [`Mgpmf::last_grid`] keeps the last update's points and normalized
//! weights (e.g. for the figure of the grid weights).

use fathom_core::RayCaster;
use nalgebra::{Matrix3, Vector3};

use super::cast_order::grid_order;
use super::error::MapAidedError;
use super::ins12::{Ins12Filter, NominalNav};
use super::likelihood::{LikelihoodWorkers, model};
use super::marginal::{
    LinearStep, LinearStepReport, Partition, normalize_log_weights, weighted_moments,
};
use super::params::{GridPosterior, MgpmfSettings};
use super::range_model::{BaroHeight, RangeBeam, check_update_inputs};

/// What one MGPMF update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MgpmfReport {
    /// Grid points evaluated.
    pub points: usize,
    /// Rays cast for the grid (points x beams) plus the linear step's.
    pub rays_cast: usize,
    /// Fraction of the grid's rays with a predicted hit.
    pub hit_fraction: f64,
    /// Effective number of points `(sum w)^2 / sum w^2`.
    pub effective_points: f64,
    /// Grid spacing per axis (north m, east m, yaw rad).
    pub spacing: Vector3<f64>,
    /// Posterior mean of `n = (dp_N, dp_E, psi_D)`.
    pub n_mean: Vector3<f64>,
    /// [`GridPosterior::Information`] gave the covariance (false: the interpolated
    /// grid covariance, by setting or as its fallback).
    pub information_used: bool,
    /// The linear step.
    pub linear: LinearStepReport,
}

/// The MGPMF update (module docs) with its reused grid.
#[derive(Debug, Clone)]
pub struct Mgpmf {
    settings: MgpmfSettings,
    points: Vec<Vector3<f64>>,
    log_w: Vec<f64>,
    weights: Vec<f64>,
    dirs: Vec<Vector3<f64>>,
    /// The order the grid points are evaluated in ([`grid_order`]).
    cast_order: Vec<u32>,
    workers: LikelihoodWorkers,
    linear: LinearStep,
}

impl Mgpmf {
    /// An MGPMF with checked settings; the grid storage is allocated here.
    pub fn new(settings: MgpmfSettings) -> Self {
        let n = settings.num_points();
        Self {
            cast_order: grid_order(settings.grid_points),
            settings,
            points: Vec::with_capacity(n),
            log_w: Vec::with_capacity(n),
            weights: Vec::with_capacity(n),
            dirs: Vec::new(),
            workers: LikelihoodWorkers::default(),
            linear: LinearStep::default(),
        }
    }

    /// The number of threads the likelihood of the grid points is evaluated on (1, the
    /// default, is the calling thread only).
    pub fn threads(&self) -> usize {
        self.workers.threads()
    }

    /// Evaluates the likelihood of the grid points on `threads` scoped threads
    /// (contiguous ranges of them, [`super::likelihood`]): the result is bit-identical
    /// for every thread count, only faster where cores are free. The Monte Carlo
    /// runner already runs one run per core, so this is for single runs (a replay, the
    /// navigation process of PILS).
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] (`threads`) outside `1..=`[`super::likelihood::MAX_THREADS`].
    pub fn set_threads(&mut self, threads: usize) -> Result<(), MapAidedError> {
        self.workers.set_threads("threads", threads)
    }

    /// The settings.
    pub fn settings(&self) -> &MgpmfSettings {
        &self.settings
    }

    /// The last update's grid points `n` and their normalized weights (empty before
    /// the first update; after a failed update, possibly that update's partial grid).
    pub fn last_grid(&self) -> (&[Vector3<f64>], &[f64]) {
        (&self.points, &self.weights)
    }

    /// Updates `filter` at its current time (module docs).
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a bad beam, baro or nominal state;
    /// [`MapAidedError::PoseOutsideMap`] when no ray of any grid point hits the map;
    /// [`MapAidedError::Filter`] if the posterior is not a valid covariance. All with
    /// the filter time; the filter is unchanged on error.
    pub fn update(
        &mut self,
        filter: &mut Ins12Filter,
        nominal: &NominalNav,
        beams: &[RangeBeam],
        baro: Option<&BaroHeight>,
        caster: &dyn RayCaster,
    ) -> Result<MgpmfReport, MapAidedError> {
        let t = filter.time();
        check_update_inputs(nominal, beams, baro, t, &mut self.dirs)?;
        let part = Partition::new(filter.error_mean(), filter.covariance()).ok_or_else(|| {
            MapAidedError::Filter(crate::EstimatorError::NotPositiveDefinite {
                what: "covariance of the grid states".into(),
                time: t,
            })
        })?;
        let s = &self.settings;
        let sigma = Vector3::from_fn(|i, _| part.p_nn[(i, i)].sqrt());
        let spacing =
            Vector3::from_fn(|i, _| 2.0 * s.k_sigma * sigma[i] / (s.grid_points[i] - 1) as f64);
        let [g0, g1, g2] = s.grid_points;
        self.points.clear();
        for i in 0..g0 {
            for j in 0..g1 {
                for k in 0..g2 {
                    let u = Vector3::new(i as f64, j as f64, k as f64)
                        - Vector3::new(g0 - 1, g1 - 1, g2 - 1).cast::<f64>() * 0.5;
                    self.points.push(part.mu_n + u.component_mul(&spacing));
                }
            }
        }
        self.log_w.clear();
        self.log_w.resize(self.points.len(), 0.0);
        let lik = model(
            nominal,
            &self.dirs,
            beams,
            baro,
            s.range.max_range,
            s.outlier_probability,
            &part,
            spacing.component_mul(&spacing) / 6.0,
        );
        let stats = lik.evaluate(
            &self.points,
            &self.cast_order,
            &mut self.log_w,
            &mut self.workers,
            caster,
        );
        if !beams.is_empty() && stats.hits == 0 {
            return Err(MapAidedError::PoseOutsideMap {
                rays: stats.rays,
                time: t,
            });
        }
        for (x, lw) in self.points.iter().zip(self.log_w.iter_mut()) {
            let d = x - part.mu_n;
            *lw -= 0.5 * d.dot(&(part.p_nn_inv * d));
        }
        let effective_points = normalize_log_weights(&self.log_w, &mut self.weights).ok_or(
            MapAidedError::PoseOutsideMap {
                rays: stats.rays,
                time: t,
            },
        )?;
        let (n_mean, cov) = weighted_moments(&self.points, &self.weights);
        let hat = Matrix3::from_diagonal(&spacing.component_mul(&spacing)) / 6.0;
        let interpolated = cov + hat;
        let (n_cov, information_used) = match s.posterior {
            GridPosterior::Interpolated => (interpolated, false),
            GridPosterior::Information => {
                let prior_cov = prior_grid_covariance(&self.points, &part) + hat;
                information_posterior(&part.p_nn_inv, &interpolated, &prior_cov)
                    .map_or((interpolated, false), |c| (c, true))
            }
        };
        let linear = self.linear.update_and_commit(
            filter, &part, nominal, beams, &self.dirs, baro, &n_mean, &n_cov, &s.range, caster,
        )?;
        let total: f64 = self.weights.iter().sum();
        for w in &mut self.weights {
            *w /= total;
        }
        Ok(MgpmfReport {
            points: self.points.len(),
            rays_cast: stats.rays + beams.len(),
            hit_fraction: if stats.rays > 0 {
                stats.hits as f64 / stats.rays as f64
            } else {
                0.0
            },
            effective_points,
            spacing,
            n_mean,
            information_used,
            linear,
        })
    }
}

/// Covariance of the grid's points weighted by the prior `N(mu_n, P_nn)` alone (no
/// likelihood): what the discretization makes of the prior. The grid is symmetric
/// about `mu_n`, so that is its weighted mean.
fn prior_grid_covariance(points: &[Vector3<f64>], part: &Partition) -> Matrix3<f64> {
    let mut total = 0.0;
    let mut cov = Matrix3::zeros();
    for x in points {
        let d = x - part.mu_n;
        let w = (-0.5 * d.dot(&(part.p_nn_inv * d))).exp();
        total += w;
        cov += d * d.transpose() * w;
    }
    cov / total
}

/// `(P_nn^-1 + C_post^-1 - C_prior^-1)^-1` ([`GridPosterior::Information`]);
/// `None` when the information is not positive definite.
fn information_posterior(
    p_nn_inv: &Matrix3<f64>,
    c_post: &Matrix3<f64>,
    c_prior: &Matrix3<f64>,
) -> Option<Matrix3<f64>> {
    let post_inv = c_post.cholesky()?.inverse();
    let prior_inv = c_prior.cholesky()?.inverse();
    let info = p_nn_inv + post_inv - prior_inv;
    let info = (info + info.transpose()) * 0.5;
    let cov = info.cholesky()?.inverse();
    let cov = (cov + cov.transpose()) * 0.5;
    cov.cholesky().map(|_| cov)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::grekf::Grekf;
    use crate::map_aided::params::{Ins12Params, MgpmfParams, RangeParams};
    use crate::map_aided::test_support::{Planes, nominal, seven_dirs};
    use crate::map_aided::{ATT, POS};
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn measure(
        map: &Planes,
        truth: &NominalNav,
        dirs: &[Vector3<f64>],
        sigma: f64,
        rng: &mut impl rand::Rng,
    ) -> Vec<RangeBeam> {
        let noise = Normal::new(0.0, sigma).unwrap();
        dirs.iter()
            .filter_map(|d| {
                map.cast(&truth.pos_in_nav, &(truth.nav_from_body * d), 60.0)
                    .map(|h| RangeBeam {
                        dir_in_body: *d,
                        range_m: h.range + noise.sample(rng),
                        sigma_m: sigma,
                    })
            })
            .collect()
    }

    fn filter(sigma_pos: f64, sigma_yaw: f64, t: f64) -> Ins12Filter {
        let mut p0 = Ins12Filter::diagonal_covariance([sigma_pos, 0.1, 0.01, 0.01]);
        p0[(ATT + 2, ATT + 2)] = sigma_yaw * sigma_yaw;
        Ins12Filter::new(&p0, t, Ins12Params::default().check().unwrap()).unwrap()
    }

    /// Where the problem is nearly linear (small prior, corridor, ranges of 0.3 m noise
    /// so the grid is fine against the posterior), the MGPMF gives the GREKF's
    /// posterior: mean within 1 cm / 0.05 deg, variances within 10 %.
    #[test]
    fn agrees_with_the_ekf_where_the_problem_is_linear() {
        let map = Planes::corridor(5.0);
        let truth = nominal(Vector3::new(0.0, 1.0, -2.0), 0.2);
        let est = nominal(Vector3::new(0.05, 1.08, -2.0), 0.21);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let beams = measure(&map, &truth, &seven_dirs(), 0.3, &mut rng);
        let mut f_ekf = filter(0.1, 0.02, 0.0);
        let mut f_pmf = f_ekf.clone();
        Grekf::new(RangeParams::default().check().unwrap())
            .update(&mut f_ekf, &est, &beams, None, &map)
            .unwrap();
        let mut m = Mgpmf::new(
            MgpmfParams {
                grid_points: [41, 41, 41],
                k_sigma: 4.0,
                outlier_probability: 0.0,
                ..MgpmfParams::default()
            }
            .check()
            .unwrap(),
        );
        let rep = m.update(&mut f_pmf, &est, &beams, None, &map).unwrap();
        assert_eq!(rep.points, 41 * 41 * 41);
        let (a, b) = (f_ekf.error_mean(), f_pmf.error_mean());
        assert!(
            (a[POS + 1] - b[POS + 1]).abs() < 0.01,
            "{} {}",
            a[POS + 1],
            b[POS + 1]
        );
        assert!((a[ATT + 2] - b[ATT + 2]).abs() < 0.05f64.to_radians());
        for i in [POS + 1, POS + 2, ATT + 2] {
            let (pa, pb) = (f_ekf.covariance()[(i, i)], f_pmf.covariance()[(i, i)]);
            assert!((pa / pb - 1.0).abs() < 0.1, "state {i}: {pa} vs {pb}");
        }
        // the along-corridor position is unobserved by both
        let i = POS;
        assert!((f_pmf.covariance()[(i, i)] / 0.01 - 1.0).abs() < 0.05);
        let (pts, w) = m.last_grid();
        assert_eq!(pts.len(), w.len());
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    /// On a coarse grid (9 x 9 x 3 over +-3 sigma) the paper's interpolated
    /// covariance inflates the axis the ranges do not see (along the corridor) at
    /// every update; the information form keeps that axis at its prior, and both
    /// agree on the observed cross-corridor axis.
    #[test]
    fn information_posterior_does_not_inflate_an_unobserved_axis() {
        let map = Planes::corridor(5.0);
        let truth = nominal(Vector3::new(0.0, 1.0, -2.0), 0.2);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let beams = measure(&map, &truth, &seven_dirs(), 0.3, &mut rng);
        let run = |posterior| {
            let mut f = filter(0.1, 0.02, 0.0);
            let mut m = Mgpmf::new(
                MgpmfParams {
                    grid_points: [9, 9, 3],
                    posterior,
                    ..MgpmfParams::default()
                }
                .check()
                .unwrap(),
            );
            let mut used = 0;
            for _ in 0..10 {
                let rep = m.update(&mut f, &truth, &beams, None, &map).unwrap();
                used += usize::from(rep.information_used);
                let _ = f.take_correction();
            }
            (
                f.covariance()[(POS, POS)],
                f.covariance()[(POS + 1, POS + 1)],
                used,
            )
        };
        let (along_paper, cross_paper, used_paper) = run(GridPosterior::Interpolated);
        let (along_info, cross_info, used_info) = run(GridPosterior::Information);
        assert_eq!((used_paper, used_info), (0, 10));
        // prior variance 0.01 m^2 along the corridor: 10 updates of the paper's
        // covariance multiply it (negative control), the information form keeps it
        assert!(along_paper > 0.02, "{along_paper}");
        assert!((along_info / 0.01 - 1.0).abs() < 0.05, "{along_info}");
        assert!(
            cross_info < 0.01 && cross_paper < 0.01,
            "{cross_info} {cross_paper}"
        );
    }

    /// Started 3 m off (sigma 3 m) in a corner, one MGPMF update brings the estimate
    /// within 0.5 m; bad input and a pose outside the map are typed errors with the
    /// time, and the filter is unchanged.
    #[test]
    fn corner_convergence_and_bad_input() {
        let map = Planes::corner();
        let truth = nominal(Vector3::new(-4.0, -5.0, -3.0), 0.4);
        let est = nominal(Vector3::new(-6.0, -2.8, -3.0), 0.42);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let beams = measure(&map, &truth, &seven_dirs(), 0.05, &mut rng);
        let baro = BaroHeight {
            height_m: 3.0,
            sigma_m: 0.3,
        };
        let mut f = filter(3.0, 0.05, 7.0);
        let mut m = Mgpmf::new(MgpmfParams::default().check().unwrap());
        let before = f.clone();
        let mut bad = beams.clone();
        bad[0].range_m = f64::NAN;
        let e = m.update(&mut f, &est, &bad, Some(&baro), &map).unwrap_err();
        assert!(matches!(e, MapAidedError::InvalidInput { index: 0, time, .. } if time == 7.0));
        bad[0].range_m = 3.0;
        bad[1].sigma_m = -1.0;
        assert!(m.update(&mut f, &est, &bad, Some(&baro), &map).is_err());
        // far outside the room looking away from it: no grid point sees a wall
        let away = nominal(Vector3::new(50.0, 50.0, -3.0), 0.0);
        let up = [RangeBeam {
            dir_in_body: -Vector3::z(),
            range_m: 5.0,
            sigma_m: 0.1,
        }];
        let e = m.update(&mut f, &away, &up, None, &map).unwrap_err();
        assert!(
            matches!(e, MapAidedError::PoseOutsideMap { time, .. } if time == 7.0),
            "{e}"
        );
        assert_eq!(f, before);

        let f_prior = f.clone();
        let rep = m.update(&mut f, &est, &beams, Some(&baro), &map).unwrap();
        let (grid, weights) = (m.last_grid().0.to_vec(), m.last_grid().1.to_vec());
        let fixed = f.take_correction().apply(&est);
        let err = (fixed.pos_in_nav - truth.pos_in_nav).norm();
        assert!(err < 0.5, "error {err} m, report {rep:?}");
        assert!(rep.effective_points >= 1.0 && rep.hit_fraction > 0.1);

        // the same update on 2, 3 and 8 threads (15,129 points: 60 chunks) is
        // bit-identical; a different prior is not (the comparison can fail)
        for threads in [2, 3, 8] {
            let mut m_t = Mgpmf::new(MgpmfParams::default().check().unwrap());
            m_t.set_threads(threads).unwrap();
            assert_eq!(m_t.threads(), threads);
            let mut f_t = f_prior.clone();
            let rep_t = m_t
                .update(&mut f_t, &est, &beams, Some(&baro), &map)
                .unwrap();
            assert_eq!(rep_t, rep, "{threads} threads");
            assert_eq!(m_t.last_grid().1, &weights[..], "{threads} threads");
            assert_eq!(m_t.last_grid().0, &grid[..], "{threads} threads");
            assert_eq!(
                f_t.take_correction().apply(&est),
                fixed,
                "{threads} threads"
            );
        }
        let mut m_2 = Mgpmf::new(MgpmfParams::default().check().unwrap());
        m_2.set_threads(2).unwrap();
        let mut f_other = filter(2.9, 0.05, 7.0);
        let rep_other = m_2
            .update(&mut f_other, &est, &beams, Some(&baro), &map)
            .unwrap();
        assert_ne!(rep_other, rep);
        for bad_threads in [0, 257] {
            let e = m_2.set_threads(bad_threads).unwrap_err();
            assert!(
                matches!(&e, MapAidedError::InvalidParameter { field, .. } if field == "threads"),
                "{e}"
            );
        }
        assert_eq!(m_2.threads(), 2);
    }
}

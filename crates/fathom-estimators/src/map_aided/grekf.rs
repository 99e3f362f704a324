//! GREKF (section 2.2): the geometry-based range EKF update of the 12-state filter.
//!
//! Per beam, the predicted range is the ray cast from the current estimate of the
//! pose through the map; the row comes from the hit plane's normal
//! ([`super::range_model`], eq. 7-10, with the corrected signs). The barometric
//! height adds the row of eq. (11)-(13). Beams without a predicted hit, with a hit
//! beyond the largest incidence angle (the row grows without bound at grazing), or
//! failing the per-beam chi-square gate are left out and counted; the rest and the
//! baro make one stacked update (eq. 13-14, faer for the dynamic size, Joseph form).
//!
//! Beyond the paper ([`GrekfSettings`], [`GrekfParams`](super::GrekfParams)):
//!
//! - **Gate**: each beam's NIS is taken against its predicted innovation variance
//!   `S = h P h^T + (k sigma)^2`, `P` the predicted covariance and `k` the σ
//!   inflation the update itself uses (the gate and the update agree on `S`).
//! - **Iterated update** (Gauss-Newton, the iterated EKF): with `iterations > 1` the
//!   rays are cast again from the pose the update gives, each beam relinearized there
//!   (`nu_i = z - h(x_i) + H_i (dx_i - dx_prior)`) and the update redone from the
//!   prior, until the correction stops moving (1e-6) or the iterations end; the last
//!   linearization gives the posterior covariance.
//! - **σ inflation**: every beam's σ times `k >= 1`, for the errors the beams share
//!   (one facet seen by many beams, the faceted map against a smooth sensor model, the
//!   attitude), which a stacked update of independent beams would otherwise count as
//!   many independent measurements.
//! - **Lost lock**: an update in which beams were given and every one was left out
//!   uses no beam (the baro alone may still update the height); after
//!   `lock_loss_updates` such updates in a row the filter has lost lock
//!   ([`GrekfReport::lock_lost`]), and the position, velocity and attitude covariance
//!   is multiplied by `relock_inflation` (the gate widens), again after every further
//!   run of as many, until an update uses a beam again ([`GrekfReport::relocked`]).
//!   An update with a beam left out by the linearity check does not count towards
//!   a lost lock (an uncertain pose is not a lost one).
//! - **Linearity check** (`linearity_sigmas = k > 0`): before the first iteration
//!   each beam is cast again from the prior pose moved by `± k sigma` along north,
//!   east (the position σ of `P`) and yaw (the yaw σ); along a plane the range is
//!   linear in the shift, so the second difference `r+ + r- - 2 r0` is ~0 there and
//!   large where the span crosses an edge or a gap (a building corner, a cross
//!   street), where the row of the predicted hit says nothing about the pose the
//!   filter is unsure of. A beam whose second difference exceeds 3 of its (inflated)
//!   σ on any axis, or whose shifted ray misses, is left out
//!   ([`GrekfReport::nonlinear`]): one wrong row there can move the estimate by
//!   metres and shrink its covariance.

use fathom_core::{Ray, RayCaster, RayHit};
use nalgebra::{DMatrix, DVector, RowSVector, Vector3};

use super::error::MapAidedError;
use super::ins12::{Ins12Filter, NominalNav};
use super::params::GrekfSettings;
use super::range_model::{BaroHeight, BeamGeometry, RangeBeam, baro_row12, check_update_inputs};
use super::{ErrorVector12, N_STATES};

/// What one GREKF update did (the counts of the last iteration).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GrekfReport {
    /// Beams given.
    pub beams: usize,
    /// Beams used in the stacked update.
    pub used: usize,
    /// Beams without a predicted hit (within the maximum range).
    pub no_hit: usize,
    /// Beams whose predicted hit is beyond the largest incidence angle.
    pub grazing: usize,
    /// Beams (and the baro) rejected by the chi-square gate.
    pub gated: usize,
    /// Beams left out by the linearity check (module docs).
    pub nonlinear: usize,
    /// Whether the barometer row was used.
    pub baro_used: bool,
    /// NIS of the stacked update (0 when nothing was used).
    pub nis: f64,
    /// Rays cast (all iterations).
    pub rays_cast: usize,
    /// Iterations done.
    pub iterations: usize,
    /// Beams were given and none was used (the update is not a map update).
    pub all_beams_left_out: bool,
    /// This update lost the lock (module docs).
    pub lock_lost: bool,
    /// The covariance was inflated by the lost-lock rule in this update.
    pub inflated: bool,
    /// This update used beams again after a lost lock.
    pub relocked: bool,
}

/// One row of the stacked update: `(h, nu, r)`.
type Row = (RowSVector<f64, N_STATES>, f64, f64);

/// The GREKF update (module docs), with its buffers and lock state kept across
/// updates.
#[derive(Debug, Clone)]
pub struct Grekf {
    settings: GrekfSettings,
    dirs: Vec<Vector3<f64>>,
    rays: Vec<Ray>,
    hits: Vec<Option<RayHit>>,
    rows: Vec<Row>,
    /// Per beam: left out by the linearity check of this update.
    nonlinear: Vec<bool>,
    /// Consecutive updates without a used beam.
    left_out_run: usize,
    /// Whether the lock is lost (until a beam is used again).
    lost: bool,
}

impl Grekf {
    /// A GREKF update with checked settings (a [`super::RangeSettings`] alone gives
    /// the paper's update: one iteration, nominal σ, no lost-lock rule).
    pub fn new(settings: impl Into<GrekfSettings>) -> Self {
        Self {
            settings: settings.into(),
            dirs: Vec::new(),
            rays: Vec::new(),
            hits: Vec::new(),
            rows: Vec::new(),
            nonlinear: Vec::new(),
            left_out_run: 0,
            lost: false,
        }
    }

    /// The settings.
    pub fn settings(&self) -> &GrekfSettings {
        &self.settings
    }

    /// Whether the lock is lost (module docs).
    pub fn lock_lost(&self) -> bool {
        self.lost
    }

    /// Forgets the lock state (a new map-aided stretch starts locked).
    pub fn reset(&mut self) {
        self.left_out_run = 0;
        self.lost = false;
    }

    /// The rows seen from `est` (the pose of `dx_i`), relinearized around the prior
    /// error mean `dx0` (module docs), into `self.rows`; counts into `report`.
    #[allow(clippy::too_many_arguments)]
    fn rows_at(
        &mut self,
        est: &NominalNav,
        dx_i: &ErrorVector12,
        dx0: &ErrorVector12,
        p: &nalgebra::SMatrix<f64, N_STATES, N_STATES>,
        beams: &[RangeBeam],
        baro: Option<&BaroHeight>,
        caster: &dyn RayCaster,
        report: &mut GrekfReport,
    ) {
        let range = &self.settings.range;
        let c = est.nav_from_body.to_rotation_matrix().into_inner();
        self.rays.clear();
        self.rays.extend(
            self.dirs
                .iter()
                .map(|d| Ray::new(est.pos_in_nav, c * d, range.max_range)),
        );
        self.hits.clear();
        self.hits.resize(self.rays.len(), None);
        // lengths equal by construction
        let _ = caster.cast_batch(&self.rays, &mut self.hits);
        report.rays_cast += beams.len();
        report.no_hit = 0;
        report.grazing = 0;
        report.gated = 0;
        report.baro_used = false;
        self.rows.clear();
        let shift = dx_i - dx0;
        let k2 = self.settings.sigma_inflation.powi(2);
        for (k, ((beam, ray), hit)) in beams.iter().zip(&self.rays).zip(&self.hits).enumerate() {
            let Some(hit) = hit else {
                report.no_hit += 1;
                continue;
            };
            if self.nonlinear.get(k).copied().unwrap_or(false) {
                continue;
            }
            let geom = BeamGeometry::from_hit(hit, ray.dir_in_nav);
            if geom.cos_incidence() < range.min_cos_incidence {
                report.grazing += 1;
                continue;
            }
            let h = geom.row12();
            let r = k2 * beam.sigma_m * beam.sigma_m;
            let nu = beam.range_m - geom.range + (h * shift)[0];
            let s = (h * p * h.transpose())[0] + r;
            // a NaN NIS fails the gate
            if nu * nu / s <= range.gate {
                self.rows.push((h, nu, r));
            } else {
                report.gated += 1;
            }
        }
        report.used = self.rows.len();
        if let Some(b) = baro {
            let h = baro_row12();
            let r = b.sigma_m * b.sigma_m;
            let nu = b.height_m - (-est.pos_in_nav.z) + (h * shift)[0];
            let s = (h * p * h.transpose())[0] + r;
            if nu * nu / s <= range.gate {
                self.rows.push((h, nu, r));
                report.baro_used = true;
            } else {
                report.gated += 1;
            }
        }
    }

    /// The linearity check at the prior pose `est` with covariance `p` (module docs)
    /// into `self.nonlinear`; returns the count of beams left out and the rays cast.
    fn check_linearity(
        &mut self,
        est: &NominalNav,
        p: &nalgebra::SMatrix<f64, N_STATES, N_STATES>,
        beams: &[RangeBeam],
        caster: &dyn RayCaster,
    ) -> (usize, usize) {
        self.nonlinear.clear();
        self.nonlinear.resize(beams.len(), false);
        let k = self.settings.linearity_sigmas;
        if k <= 0.0 {
            return (0, 0);
        }
        let max = self.settings.range.max_range;
        let c = est.nav_from_body.to_rotation_matrix().into_inner();
        let o = est.pos_in_nav;
        let sig = |i: usize| p[(i, i)].max(0.0).sqrt() * k;
        let (dn, de, dyaw) = (sig(super::POS), sig(super::POS + 1), sig(super::ATT + 2));
        let range = |o: &Vector3<f64>, d: &Vector3<f64>| caster.cast(o, d, max).map(|h| h.range);
        let (mut count, mut rays) = (0, 0);
        for (i, (beam, dir)) in beams.iter().zip(&self.dirs).enumerate() {
            let d = c * dir;
            rays += 1;
            let Some(r0) = range(&o, &d) else {
                continue;
            };
            rays += 6;
            let tol = 3.0 * self.settings.sigma_inflation * beam.sigma_m;
            let second = |rp: Option<f64>, rm: Option<f64>| match (rp, rm) {
                (Some(a), Some(b)) => (a + b - 2.0 * r0).abs() > tol,
                _ => true,
            };
            let yaw = |a: f64| nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), a) * d;
            let bad = second(
                range(&(o + Vector3::x() * dn), &d),
                range(&(o - Vector3::x() * dn), &d),
            ) || second(
                range(&(o + Vector3::y() * de), &d),
                range(&(o - Vector3::y() * de), &d),
            ) || second(range(&o, &yaw(dyaw)), range(&o, &yaw(-dyaw)));
            if bad {
                self.nonlinear[i] = true;
                count += 1;
            }
        }
        (count, rays)
    }

    /// Updates `filter` at its current time with the beams and the optional baro,
    /// seen from `nominal` corrected by the filter's error mean (module docs).
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a bad beam, baro or nominal state (NaN
    /// range, variance `<= 0`, zero direction); [`MapAidedError::PoseOutsideMap`] when
    /// beams were given and none has a predicted hit from the prior pose;
    /// [`MapAidedError::Filter`] from the stacked update or the lost-lock inflation.
    /// All with the filter time; the filter and the lock state are unchanged on error.
    pub fn update(
        &mut self,
        filter: &mut Ins12Filter,
        nominal: &NominalNav,
        beams: &[RangeBeam],
        baro: Option<&BaroHeight>,
        caster: &dyn RayCaster,
    ) -> Result<GrekfReport, MapAidedError> {
        let t = filter.time();
        check_update_inputs(nominal, beams, baro, t, &mut self.dirs)?;
        let dx0 = *filter.error_mean();
        let p = *filter.covariance();
        let mut report = GrekfReport {
            beams: beams.len(),
            ..GrekfReport::default()
        };
        let (nonlinear, check_rays) =
            self.check_linearity(&nominal.corrected(&dx0), &p, beams, caster);
        report.nonlinear = nonlinear;
        report.rays_cast += check_rays;
        let mut dx_i = dx0;
        // the last iteration that used rows: its filter and counts
        let mut post: Option<(Ins12Filter, GrekfReport)> = None;
        for it in 0..self.settings.iterations {
            let est = nominal.corrected(&dx_i);
            self.rows_at(&est, &dx_i, &dx0, &p, beams, baro, caster, &mut report);
            if it == 0 && !beams.is_empty() && report.no_hit == beams.len() {
                return Err(MapAidedError::PoseOutsideMap {
                    rays: beams.len(),
                    time: t,
                });
            }
            report.iterations = it + 1;
            if self.rows.is_empty() {
                break;
            }
            let rows = &self.rows;
            let m = rows.len();
            let h = DMatrix::from_fn(m, N_STATES, |i, j| rows[i].0[j]);
            let nu = DVector::from_fn(m, |i, _| rows[i].1);
            let r = DMatrix::from_fn(m, m, |i, j| if i == j { rows[i].2 } else { 0.0 });
            let mut f = filter.clone();
            let info = f.kf_mut().update_stacked_with_innovation(&nu, &h, &r)?;
            report.nis = info.nis;
            let next = *f.error_mean();
            post = Some((f, report));
            if (next - dx_i).norm() < 1e-6 {
                break;
            }
            dx_i = next;
        }
        let (mut f, used_report) = match post {
            Some((f, r)) => (f, r),
            None => (filter.clone(), report),
        };
        let rays_cast = report.rays_cast;
        let iterations = report.iterations;
        let mut report = GrekfReport {
            rays_cast,
            iterations,
            ..used_report
        };
        if post_used_beams(&report, beams) {
            report.relocked = self.lost;
            self.lost = false;
            self.left_out_run = 0;
            *filter = f;
            return Ok(report);
        }
        report.all_beams_left_out = !beams.is_empty();
        // beams left out as nonlinear say the pose is uncertain, not that it is lost
        if beams.is_empty() || report.nonlinear > 0 {
            *filter = f;
            return Ok(report);
        }
        let n = self.settings.lock_loss_updates;
        let run = self.left_out_run + 1;
        if n > 0 && run >= n {
            f.inflate_navigation_covariance(self.settings.relock_inflation)?;
            report.inflated = true;
            report.lock_lost = !self.lost;
            self.lost = true;
            self.left_out_run = 0;
        } else {
            self.left_out_run = run;
        }
        *filter = f;
        Ok(report)
    }
}

/// Whether the update used at least one beam.
fn post_used_beams(report: &GrekfReport, beams: &[RangeBeam]) -> bool {
    !beams.is_empty() && report.used > 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::params::{Ins12Params, RangeParams};
    use crate::map_aided::test_support::{Planes, nominal};
    use crate::map_aided::{ATT, POS};

    fn beams_around(n: usize, range_of: impl Fn(&Vector3<f64>) -> f64) -> Vec<RangeBeam> {
        (0..n)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / n as f64;
                let d = Vector3::new(a.cos(), a.sin(), 0.3);
                RangeBeam {
                    dir_in_body: d,
                    range_m: range_of(&d),
                    sigma_m: 0.05,
                }
            })
            .collect()
    }

    fn filter(t: f64) -> Ins12Filter {
        let p0 = Ins12Filter::diagonal_covariance([1.0, 0.1, 0.02, 0.01]);
        Ins12Filter::new(&p0, t, Ins12Params::default().check().unwrap()).unwrap()
    }

    /// In the corner, a nominal 0.5 m off east and 0.05 rad off in yaw: exact ranges
    /// from the truth; iterating the update (Gauss-Newton: closed loop, the same prior
    /// covariance each time) recovers the truth, which is its fixed point.
    #[test]
    fn closed_loop_updates_recover_the_truth_in_a_corner() {
        let map = Planes::corner();
        let truth = nominal(Vector3::new(-4.0, -5.0, -3.0), 0.4);
        let mut est = nominal(Vector3::new(-4.0, -4.5, -3.0), 0.45);
        let mut f = filter(0.0);
        let mut g = Grekf::new(RangeParams::default().check().unwrap());
        let ranges = |d: &Vector3<f64>| {
            map.cast(&truth.pos_in_nav, &(truth.nav_from_body * d), 60.0)
                .map_or(f64::NAN, |h| h.range)
        };
        let beams: Vec<_> = beams_around(12, ranges)
            .into_iter()
            .filter(|b| b.range_m.is_finite())
            .collect();
        assert!(beams.len() >= 6);
        let baro = BaroHeight {
            height_m: 3.0,
            sigma_m: 0.5,
        };
        for _ in 0..6 {
            f = filter(0.0);
            let rep = g.update(&mut f, &est, &beams, Some(&baro), &map).unwrap();
            assert_eq!(rep.no_hit + rep.grazing + rep.gated + rep.used, rep.beams);
            est = f.take_correction().apply(&est);
        }
        assert!(
            (est.pos_in_nav - truth.pos_in_nav).norm() < 1e-6,
            "{}",
            est.pos_in_nav
        );
        assert!(est.nav_from_body.angle_to(&truth.nav_from_body) < 1e-6);
        // the covariance shrank where the geometry observes
        assert!(f.covariance()[(POS, POS)] < 0.01 && f.covariance()[(ATT + 2, ATT + 2)] < 1e-4);
    }

    /// Bad input and a pose outside the map: typed errors with the time stamp; the
    /// filter is unchanged. A beam without a predicted hit is counted, not an error.
    #[test]
    fn bad_input_and_no_hits() {
        let map = Planes::corridor(5.0);
        let est = nominal(Vector3::new(0.0, 0.0, -2.0), 0.0);
        let mut f = filter(3.0);
        let before = f.clone();
        let mut g = Grekf::new(RangeParams::default().check().unwrap());
        let good = RangeBeam {
            dir_in_body: Vector3::y(),
            range_m: 5.0,
            sigma_m: 0.05,
        };
        let along = RangeBeam {
            dir_in_body: Vector3::x(),
            ..good
        };
        let cases = [
            RangeBeam {
                range_m: f64::NAN,
                ..good
            },
            RangeBeam {
                sigma_m: -0.05,
                ..good
            },
        ];
        for bad in cases {
            let e = g
                .update(&mut f, &est, &[good, bad], None, &map)
                .unwrap_err();
            assert!(
                matches!(&e, MapAidedError::InvalidInput { index: 1, time, .. } if *time == 3.0),
                "{e}"
            );
        }
        let e = g
            .update(&mut f, &est, &[along, along], None, &map)
            .unwrap_err();
        assert_eq!(e, MapAidedError::PoseOutsideMap { rays: 2, time: 3.0 });
        let bad_baro = BaroHeight {
            height_m: 2.0,
            sigma_m: f64::NAN,
        };
        assert!(
            g.update(&mut f, &est, &[good], Some(&bad_baro), &map)
                .is_err()
        );
        assert_eq!(f, before);
        let rep = g.update(&mut f, &est, &[good, along], None, &map).unwrap();
        assert_eq!((rep.used, rep.no_hit), (1, 1));
        // a 10 m outlier is gated and counted
        let mut f2 = filter(3.0);
        let outlier = RangeBeam {
            range_m: 15.0,
            ..good
        };
        let rep = g.update(&mut f2, &est, &[outlier], None, &map).unwrap();
        assert_eq!((rep.used, rep.gated), (0, 1));
        assert_eq!(f2, before);
    }

    /// The linearity check, in a corner (walls north = 0 and east = 0, pose 4 m and
    /// 5 m from them, 1 m position σ, 2 σ spans): a beam into the corner changes wall
    /// within the east span (a kink: left out), a beam square to the north wall is
    /// linear (kept); the paper's update (k = 0) checks nothing and uses both.
    #[test]
    fn linearity_check_leaves_out_beams_across_an_edge() {
        use crate::map_aided::params::GrekfParams;
        let map = Planes::corner();
        let est = nominal(Vector3::new(-4.0, -5.0, -3.0), 0.0);
        let range_of = |d: Vector3<f64>| map.cast(&est.pos_in_nav, &d, 60.0).unwrap().range;
        let square = Vector3::x();
        let into_corner = Vector3::new(1.0, 1.0, 0.0).normalize();
        let beams = [square, into_corner].map(|d| RangeBeam {
            dir_in_body: d,
            range_m: range_of(d),
            sigma_m: 0.05,
        });
        let with = |k: f64| {
            Grekf::new(
                GrekfParams {
                    linearity_sigmas: k,
                    ..GrekfParams::default()
                }
                .check()
                .unwrap(),
            )
        };
        let mut g = with(2.0);
        let mut f = filter(3.0);
        let rep = g.update(&mut f, &est, &beams, None, &map).unwrap();
        assert_eq!((rep.nonlinear, rep.used), (1, 1), "{rep:?}");
        assert_eq!(g.nonlinear, vec![false, true]);
        // 7 rays per beam for the check, one per beam per iteration
        assert_eq!(rep.rays_cast, 2 * 7 + 2 * rep.iterations);
        let mut plain = with(0.0);
        let mut f = filter(3.0);
        let rep = plain.update(&mut f, &est, &beams, None, &map).unwrap();
        assert_eq!((rep.nonlinear, rep.used), (0, 2), "{rep:?}");
        // beams all left out as nonlinear never count towards a lost lock
        let mut g = GrekfParams {
            linearity_sigmas: 2.0,
            lock_loss_updates: 1,
            ..GrekfParams::default()
        }
        .check()
        .map(Grekf::new)
        .unwrap();
        let mut f = filter(3.0);
        for _ in 0..3 {
            let r = g.update(&mut f, &est, &beams[1..], None, &map).unwrap();
            assert!(r.all_beams_left_out && !r.lock_lost && !r.inflated, "{r:?}");
        }
    }

    /// Issue 33: an update with every beam gated is no map update; after
    /// `lock_loss_updates` of them the lock is lost (counted once), the covariance
    /// inflated, and the first update that uses a beam again re-locks. The iterated
    /// update converges in fewer steps than it may take.
    #[test]
    fn lost_lock_inflates_and_relocks() {
        use crate::map_aided::params::GrekfParams;
        let map = Planes::corridor(5.0);
        let est = nominal(Vector3::new(0.0, 0.0, -2.0), 0.0);
        let settings = GrekfParams {
            iterations: 4,
            lock_loss_updates: 2,
            relock_inflation: 4.0,
            ..GrekfParams::default()
        }
        .check()
        .unwrap();
        let mut g = Grekf::new(settings);
        let mut f = filter(3.0);
        let p_east = f.covariance()[(1, 1)];
        let outlier = [RangeBeam {
            dir_in_body: Vector3::y(),
            range_m: 15.0,
            sigma_m: 0.05,
        }];
        let first = g.update(&mut f, &est, &outlier, None, &map).unwrap();
        assert!(first.all_beams_left_out && !first.lock_lost && !first.inflated);
        assert_eq!(f.covariance()[(1, 1)], p_east);
        let second = g.update(&mut f, &est, &outlier, None, &map).unwrap();
        assert!(second.lock_lost && second.inflated && g.lock_lost());
        assert!((f.covariance()[(1, 1)] - 4.0 * p_east).abs() < 1e-12);
        // still lost: inflated again after another run, not counted again
        g.update(&mut f, &est, &outlier, None, &map).unwrap();
        let fourth = g.update(&mut f, &est, &outlier, None, &map).unwrap();
        assert!(fourth.inflated && !fourth.lock_lost);
        let good = [RangeBeam {
            range_m: 5.2,
            ..outlier[0]
        }];
        let back = g.update(&mut f, &est, &good, None, &map).unwrap();
        assert!(back.relocked && !back.all_beams_left_out && !g.lock_lost());
        assert!(back.iterations >= 1 && back.iterations <= 4);
        assert_eq!(back.rays_cast, back.iterations);
        // the paper's update (a RangeSettings alone) never inflates
        let mut plain = Grekf::new(RangeParams::default().check().unwrap());
        let mut f2 = filter(3.0);
        for _ in 0..10 {
            let r = plain.update(&mut f2, &est, &outlier, None, &map).unwrap();
            assert!(!r.inflated);
        }
        assert_eq!(f2.covariance()[(1, 1)], p_east);
    }
}

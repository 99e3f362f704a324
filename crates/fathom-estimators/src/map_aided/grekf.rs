//! GREKF (section 2.2): the geometry-based range EKF update of the 12-state filter.
//!
//! Per beam, the predicted range is the ray cast from the current estimate of the
//! pose through the map; the row comes from the hit plane's normal
//! ([`super::range_model`], eq. 7-10, with the corrected signs). The barometric
//! height adds the row of eq. (11)-(13). Beams without a predicted hit, with a hit
//! beyond the largest incidence angle (the row grows without bound at grazing), or
//! failing the per-beam chi-square gate are left out and counted; the rest and the
//! baro make one stacked update (eq. 13-14, faer for the dynamic size, Joseph form).

use fathom_core::{Ray, RayCaster, RayHit};
use nalgebra::{DMatrix, DVector, Vector3};

use super::N_STATES;
use super::error::MapAidedError;
use super::ins12::{Ins12Filter, NominalNav};
use super::params::RangeSettings;
use super::range_model::{BaroHeight, BeamGeometry, RangeBeam, baro_row12, check_update_inputs};

/// What one GREKF update did.
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
    /// Whether the barometer row was used.
    pub baro_used: bool,
    /// NIS of the stacked update (0 when nothing was used).
    pub nis: f64,
    /// Rays cast.
    pub rays_cast: usize,
}

/// The GREKF update (module docs), with its buffers reused across updates.
#[derive(Debug, Clone)]
pub struct Grekf {
    settings: RangeSettings,
    dirs: Vec<Vector3<f64>>,
    rays: Vec<Ray>,
    hits: Vec<Option<RayHit>>,
}

impl Grekf {
    /// A GREKF update with checked settings.
    pub fn new(settings: RangeSettings) -> Self {
        Self {
            settings,
            dirs: Vec::new(),
            rays: Vec::new(),
            hits: Vec::new(),
        }
    }

    /// The settings.
    pub fn settings(&self) -> &RangeSettings {
        &self.settings
    }

    /// Updates `filter` at its current time with the beams and the optional baro,
    /// seen from `nominal` corrected by the filter's error mean.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a bad beam, baro or nominal state (NaN
    /// range, variance `<= 0`, zero direction); [`MapAidedError::PoseOutsideMap`] when
    /// beams were given and none has a predicted hit; [`MapAidedError::Filter`] from the
    /// stacked update. All with the filter time; the filter is unchanged on error.
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
        let est = nominal.corrected(filter.error_mean());
        let c = est.nav_from_body.to_rotation_matrix().into_inner();
        self.rays.clear();
        self.rays.extend(
            self.dirs
                .iter()
                .map(|d| Ray::new(est.pos_in_nav, c * d, self.settings.max_range)),
        );
        self.hits.clear();
        self.hits.resize(self.rays.len(), None);
        // lengths equal by construction
        let _ = caster.cast_batch(&self.rays, &mut self.hits);

        let p = filter.covariance();
        let mut report = GrekfReport {
            beams: beams.len(),
            rays_cast: beams.len(),
            ..GrekfReport::default()
        };
        let mut rows: Vec<(nalgebra::RowSVector<f64, N_STATES>, f64, f64)> =
            Vec::with_capacity(beams.len() + 1);
        for ((beam, ray), hit) in beams.iter().zip(&self.rays).zip(&self.hits) {
            let Some(hit) = hit else {
                report.no_hit += 1;
                continue;
            };
            let geom = BeamGeometry::from_hit(hit, ray.dir_in_nav);
            if geom.cos_incidence() < self.settings.min_cos_incidence {
                report.grazing += 1;
                continue;
            }
            let h = geom.row12();
            let r = beam.sigma_m * beam.sigma_m;
            let nu = beam.range_m - geom.range;
            let s = (h * p * h.transpose())[0] + r;
            // a NaN NIS fails the gate
            if nu * nu / s <= self.settings.gate {
                rows.push((h, nu, r));
            } else {
                report.gated += 1;
            }
        }
        if !beams.is_empty() && report.no_hit == beams.len() {
            return Err(MapAidedError::PoseOutsideMap {
                rays: beams.len(),
                time: t,
            });
        }
        report.used = rows.len();
        if let Some(b) = baro {
            let h = baro_row12();
            let r = b.sigma_m * b.sigma_m;
            let nu = b.height_m - (-est.pos_in_nav.z);
            let s = (h * p * h.transpose())[0] + r;
            if nu * nu / s <= self.settings.gate {
                rows.push((h, nu, r));
                report.baro_used = true;
            } else {
                report.gated += 1;
            }
        }
        if rows.is_empty() {
            return Ok(report);
        }
        let m = rows.len();
        let h = DMatrix::from_fn(m, N_STATES, |i, j| rows[i].0[j]);
        let nu = DVector::from_fn(m, |i, _| rows[i].1);
        let r = DMatrix::from_fn(m, m, |i, j| if i == j { rows[i].2 } else { 0.0 });
        let info = filter
            .kf_mut()
            .update_stacked_with_innovation(&nu, &h, &r)?;
        report.nis = info.nis;
        Ok(report)
    }
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
}

//! Track-to-track fusion: one Kalman filter per sensor, the two corrected estimates
//! fused every step (paper A, "T2T"; eq. (10) by default). Nothing flows back into the
//! tracks: each keeps its own estimate, the fused one is an output.

use super::{ArchitectureError, TrackModel, rules::FusionRule};
use crate::{KalmanFilter, fuse_information};
use fathom_core::{Gaussian, Time, error::ensure_finite};
use nalgebra::{SMatrix, SVector};

use super::rules::{fuse_bar_shalom_campo, fuse_covariance_intersection};

/// The state of both tracks and the fused estimate after a step.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackSnapshot<const N: usize> {
    /// Main track (e.g. INS) after its correction.
    pub main: Gaussian<N>,
    /// Assistance track (e.g. DVL) after its correction.
    pub aux: Gaussian<N>,
    /// The fused estimate.
    pub fused: Gaussian<N>,
    /// The covariance-intersection weight of the main track (`None` for other rules).
    pub ci_weight: Option<f64>,
}

/// Two tracks (a main sensor with `M1`-dimensional measurements, an assistance sensor
/// with `M2`) and a [`FusionRule`].
///
/// Each [`TrackToTrack::step`]: both filters predict to the new time with their own
/// `F`, `Q`; each corrects with its own sensor's measurement (`H`, `R`); for the
/// Bar-Shalom–Campo rule the cross-covariance is propagated,
/// `P12 <- (I - K1 H1) (F1 P12 F2^T + Q12) (I - K2 H2)^T`; the two corrected
/// estimates are fused.
///
/// Bad input: a non-finite measurement is an [`ArchitectureError::Filter`] naming the
/// track, the index and the step time; loss of positive definiteness is a filter or
/// [`ArchitectureError::Fusion`] error with the time; unchanged on error.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackToTrack<const N: usize, const M1: usize, const M2: usize> {
    main: KalmanFilter<N>,
    aux: KalmanFilter<N>,
    main_model: TrackModel<N, M1>,
    aux_model: TrackModel<N, M2>,
    rule: FusionRule<N>,
    cross_cov: SMatrix<f64, N, N>,
    fused: Gaussian<N>,
    ci_weight: Option<f64>,
}

impl<const N: usize, const M1: usize, const M2: usize> TrackToTrack<N, M1, M2> {
    /// Two tracks starting at `t0` from their priors; `initial_cross_cov` is
    /// `E[(x_main - x)(x_aux - x)^T]` at `t0` (used only by Bar-Shalom–Campo; e.g. the
    /// prior covariance when both start from the same initial estimate, zero for
    /// independent initializations). The initial fused estimate uses the rule.
    ///
    /// # Errors
    /// [`ArchitectureError::Filter`] for invalid priors or time,
    /// [`ArchitectureError::InvalidConfig`] for a non-finite cross-covariance,
    /// [`ArchitectureError::Fusion`] if the priors cannot be fused.
    pub fn new(
        main_prior: Gaussian<N>,
        aux_prior: Gaussian<N>,
        initial_cross_cov: SMatrix<f64, N, N>,
        t0: Time,
        main_model: TrackModel<N, M1>,
        aux_model: TrackModel<N, M2>,
        rule: FusionRule<N>,
    ) -> Result<Self, ArchitectureError> {
        let main = KalmanFilter::new(main_prior, t0).map_err(ArchitectureError::filter("main"))?;
        let aux = KalmanFilter::new(aux_prior, t0).map_err(ArchitectureError::filter("aux"))?;
        ensure_finite("initial cross-covariance", initial_cross_cov.iter()).map_err(|e| {
            ArchitectureError::InvalidConfig {
                what: "track-to-track".into(),
                reason: e.to_string(),
            }
        })?;
        if let FusionRule::BarShalomCampo { process_cross_cov } = &rule {
            ensure_finite("process cross-covariance Q12", process_cross_cov.iter()).map_err(
                |e| ArchitectureError::InvalidConfig {
                    what: "Bar-Shalom-Campo rule".into(),
                    reason: e.to_string(),
                },
            )?;
        }
        let (fused, ci_weight) = fuse_with(
            &rule,
            &main.estimate(),
            &aux.estimate(),
            &initial_cross_cov,
            t0,
        )?;
        Ok(Self {
            main,
            aux,
            main_model,
            aux_model,
            rule,
            cross_cov: initial_cross_cov,
            fused,
            ci_weight,
        })
    }

    /// One step to `time`: predict both tracks, correct each with its measurement,
    /// fuse (see the type docs). Returns the fused estimate.
    ///
    /// # Errors
    /// [`ArchitectureError::Filter`] (which track, with the filter's error),
    /// [`ArchitectureError::Fusion`]; the architecture is unchanged on error.
    pub fn step(
        &mut self,
        time: Time,
        z_main: &SVector<f64, M1>,
        z_aux: &SVector<f64, M2>,
    ) -> Result<&Gaussian<N>, ArchitectureError> {
        let next = self.advanced(time, None, z_main, z_aux)?;
        *self = next;
        Ok(&self.fused)
    }

    /// The step on a copy, with an optional common prior state (the EFF
    /// equalization, which replaces both tracks' states but keeps their `P`).
    pub(crate) fn advanced(
        &self,
        time: Time,
        common_prior_state: Option<&SVector<f64, N>>,
        z_main: &SVector<f64, M1>,
        z_aux: &SVector<f64, M2>,
    ) -> Result<Self, ArchitectureError> {
        let mut next = self.clone();
        if let Some(x) = common_prior_state {
            next.main
                .set_state(*x)
                .map_err(ArchitectureError::filter("main"))?;
            next.aux
                .set_state(*x)
                .map_err(ArchitectureError::filter("aux"))?;
        }
        let (mm, am) = (&self.main_model, &self.aux_model);
        next.main
            .predict(mm.f(), mm.q(), time)
            .map_err(ArchitectureError::filter("main"))?;
        next.aux
            .predict(am.f(), am.q(), time)
            .map_err(ArchitectureError::filter("aux"))?;
        let p_main_pred = *next.main.covariance();
        let p_aux_pred = *next.aux.covariance();
        let info_main = next
            .main
            .update(z_main, mm.h(), mm.r())
            .map_err(ArchitectureError::filter("main"))?;
        let info_aux = next
            .aux
            .update(z_aux, am.h(), am.r())
            .map_err(ArchitectureError::filter("aux"))?;
        if let FusionRule::BarShalomCampo { process_cross_cov } = &self.rule {
            let k_main = gain(
                &p_main_pred,
                mm.h(),
                &info_main.innovation_cov,
                time,
                "main",
            )?;
            let k_aux = gain(&p_aux_pred, am.h(), &info_aux.innovation_cov, time, "aux")?;
            let id = SMatrix::<f64, N, N>::identity();
            let pred = mm.f() * self.cross_cov * am.f().transpose() + process_cross_cov;
            next.cross_cov = (id - k_main * mm.h()) * pred * (id - k_aux * am.h()).transpose();
        }
        let (fused, ci_weight) = fuse_with(
            &self.rule,
            &next.main.estimate(),
            &next.aux.estimate(),
            &next.cross_cov,
            time,
        )?;
        next.fused = fused;
        next.ci_weight = ci_weight;
        Ok(next)
    }

    /// The latest fused estimate.
    pub fn fused(&self) -> &Gaussian<N> {
        &self.fused
    }

    /// The main track's filter.
    pub fn main(&self) -> &KalmanFilter<N> {
        &self.main
    }

    /// The assistance track's filter.
    pub fn aux(&self) -> &KalmanFilter<N> {
        &self.aux
    }

    /// The propagated cross-covariance `P12` (only maintained by Bar-Shalom–Campo;
    /// otherwise the initial value).
    pub fn cross_cov(&self) -> &SMatrix<f64, N, N> {
        &self.cross_cov
    }

    /// The fusion rule.
    pub fn rule(&self) -> &FusionRule<N> {
        &self.rule
    }

    /// Both tracks and the fused estimate.
    pub fn snapshot(&self) -> TrackSnapshot<N> {
        TrackSnapshot {
            main: self.main.estimate(),
            aux: self.aux.estimate(),
            fused: self.fused.clone(),
            ci_weight: self.ci_weight,
        }
    }

    /// Time of the estimates, s.
    pub fn time(&self) -> Time {
        self.main.time()
    }
}

/// `K = P H^T S^-1` (the gain the filter applied, recomputed from its `S`).
fn gain<const N: usize, const M: usize>(
    p_pred: &SMatrix<f64, N, N>,
    h: &SMatrix<f64, M, N>,
    s: &SMatrix<f64, M, M>,
    time: Time,
    track: &'static str,
) -> Result<SMatrix<f64, N, M>, ArchitectureError> {
    let chol = s.cholesky().ok_or(ArchitectureError::Filter {
        track,
        source: crate::EstimatorError::NotPositiveDefinite {
            what: "innovation covariance S (cross-covariance recursion)".into(),
            time,
        },
    })?;
    // K^T = S^-1 H P.
    Ok(chol.solve(&(h * p_pred)).transpose())
}

fn fuse_with<const N: usize>(
    rule: &FusionRule<N>,
    a: &Gaussian<N>,
    b: &Gaussian<N>,
    cross_cov: &SMatrix<f64, N, N>,
    time: Time,
) -> Result<(Gaussian<N>, Option<f64>), ArchitectureError> {
    let wrap = |source| ArchitectureError::Fusion {
        rule: rule.name(),
        time,
        source,
    };
    match rule {
        FusionRule::Independent => Ok((fuse_information(a, b).map_err(wrap)?, None)),
        FusionRule::BarShalomCampo { .. } => {
            Ok((fuse_bar_shalom_campo(a, b, cross_cov).map_err(wrap)?, None))
        }
        FusionRule::CovarianceIntersection => {
            let (g, w) = fuse_covariance_intersection(a, b).map_err(wrap)?;
            Ok((g, Some(w)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix1, Matrix2, RowVector2, Vector1, Vector2};

    fn model(w2: f64, r: f64) -> TrackModel<2, 1> {
        TrackModel::new(
            Matrix2::new(1.0, 1.0, 0.0, 1.0),
            Matrix2::identity() * w2,
            RowVector2::new(1.0, 0.0),
            Matrix1::new(r),
        )
        .unwrap()
    }

    fn prior() -> Gaussian<2> {
        Gaussian::new(Vector2::new(0.0, 1.0), Matrix2::identity()).unwrap()
    }

    fn t2t(rule: FusionRule<2>) -> TrackToTrack<2, 1, 1> {
        TrackToTrack::new(
            prior(),
            prior(),
            Matrix2::zeros(),
            0.0,
            model(4.0, 9.0),
            model(1.0, 0.25),
            rule,
        )
        .unwrap()
    }

    /// Bad input (crate docs): a non-finite measurement is a filter error naming the
    /// track, the index and the time; a process noise that makes `P` indefinite is a
    /// positive-definiteness error at the step time; the tracks are unchanged.
    #[test]
    fn bad_input_names_track_index_and_time() {
        let mut f = t2t(FusionRule::Independent);
        let before = f.clone();
        for (z_main, z_aux, track) in [(f64::NAN, 1.0, "main"), (1.0, f64::INFINITY, "aux")] {
            match f.step(2.0, &Vector1::new(z_main), &Vector1::new(z_aux)) {
                Err(ArchitectureError::Filter {
                    track: t,
                    source: crate::EstimatorError::NonFinite { index, time, .. },
                }) => assert_eq!((t, index, time), (track, 0, 2.0)),
                other => panic!("unexpected {other:?}"),
            }
            assert_eq!(f, before);
        }
        let indefinite = TrackModel::new(
            Matrix2::new(1.0, 1.0, 0.0, 1.0),
            Matrix2::new(0.0, 50.0, 50.0, 0.0),
            RowVector2::new(1.0, 0.0),
            Matrix1::new(1.0),
        )
        .unwrap();
        let mut g = TrackToTrack::new(
            prior(),
            prior(),
            Matrix2::zeros(),
            0.0,
            model(4.0, 9.0),
            indefinite,
            FusionRule::Independent,
        )
        .unwrap();
        let before = g.clone();
        let e = g
            .step(1.5, &Vector1::new(1.0), &Vector1::new(1.0))
            .unwrap_err();
        assert!(
            matches!(&e, ArchitectureError::Filter { track: "aux", source: crate::EstimatorError::NotPositiveDefinite { time, .. } } if *time == 1.5),
            "{e}"
        );
        assert_eq!(g, before);
    }

    #[test]
    fn one_step_matches_independent_filters_and_eq_10() {
        let mut arch = t2t(FusionRule::Independent);
        let fused = arch
            .step(1.0, &Vector1::new(2.0), &Vector1::new(0.8))
            .unwrap()
            .clone();
        // Two stand-alone filters doing the same.
        let mut a = KalmanFilter::new(prior(), 0.0).unwrap();
        let mut b = a.clone();
        let (ma, mb) = (model(4.0, 9.0), model(1.0, 0.25));
        a.predict(ma.f(), ma.q(), 1.0).unwrap();
        a.update(&Vector1::new(2.0), ma.h(), ma.r()).unwrap();
        b.predict(mb.f(), mb.q(), 1.0).unwrap();
        b.update(&Vector1::new(0.8), mb.h(), mb.r()).unwrap();
        assert_eq!(arch.main(), &a);
        assert_eq!(arch.aux(), &b);
        // eq. (10) with explicit inverses.
        let ia = a.covariance().try_inverse().unwrap();
        let ib = b.covariance().try_inverse().unwrap();
        let p = (ia + ib).try_inverse().unwrap();
        let x = p * (ia * a.state() + ib * b.state());
        assert_relative_eq!(*fused.mean(), x, epsilon = 1e-12);
        assert_relative_eq!(*fused.cov(), p, epsilon = 1e-12);
        assert_eq!(arch.time(), 1.0);
    }

    #[test]
    fn bar_shalom_campo_with_zero_cross_terms_equals_eq_10() {
        let mut ind = t2t(FusionRule::Independent);
        let mut bc = t2t(FusionRule::BarShalomCampo {
            process_cross_cov: Matrix2::zeros(),
        });
        for k in 1..=20 {
            let t = k as f64;
            let (za, zb) = (Vector1::new(t + 0.3 * t.sin()), Vector1::new(t - 0.1));
            let fi = ind.step(t, &za, &zb).unwrap().clone();
            let fb = bc.step(t, &za, &zb).unwrap().clone();
            assert_eq!(bc.cross_cov(), &Matrix2::zeros());
            assert_relative_eq!(*fi.mean(), *fb.mean(), epsilon = 1e-12);
            assert_relative_eq!(*fi.cov(), *fb.cov(), epsilon = 1e-12);
        }
    }

    #[test]
    fn cross_covariance_recursion_by_hand() {
        // Scalar random walk F = 1, Q1 = 4, Q2 = 1, Q12 = 2, H = 1, R1 = 4, R2 = 1,
        // P1 = P2 = 1, P12 = 0.5 at t0.
        let m1 = TrackModel::new(
            Matrix1::new(1.0),
            Matrix1::new(4.0),
            Matrix1::new(1.0),
            Matrix1::new(4.0),
        )
        .unwrap();
        let m2 = TrackModel::new(
            Matrix1::new(1.0),
            Matrix1::new(1.0),
            Matrix1::new(1.0),
            Matrix1::new(1.0),
        )
        .unwrap();
        let p0 = Gaussian::new(Vector1::new(0.0), Matrix1::new(1.0)).unwrap();
        let mut arch = TrackToTrack::new(
            p0.clone(),
            p0,
            Matrix1::new(0.5),
            0.0,
            m1,
            m2,
            FusionRule::BarShalomCampo {
                process_cross_cov: Matrix1::new(2.0),
            },
        )
        .unwrap();
        arch.step(1.0, &Vector1::new(1.0), &Vector1::new(2.0))
            .unwrap();
        // P1- = 5, K1 = 5/9; P2- = 2, K2 = 2/3; P12- = 0.5 + 2 = 2.5;
        // P12+ = (4/9) 2.5 (1/3) = 10/27.
        assert_relative_eq!(arch.cross_cov()[(0, 0)], 10.0 / 27.0, epsilon = 1e-12);
        // Tracks: x1 = 5/9, P1 = 20/9; x2 = 4/3, P2 = 2/3.
        assert_relative_eq!(arch.main().state()[0], 5.0 / 9.0, epsilon = 1e-12);
        assert_relative_eq!(arch.aux().state()[0], 4.0 / 3.0, epsilon = 1e-12);
        // U = 20/9 + 2/3 - 20/27 = 58/27; K = (20/9 - 10/27)/U = (50/27)/(58/27) = 25/29.
        let k = 25.0 / 29.0;
        let x = 5.0 / 9.0 + k * (4.0 / 3.0 - 5.0 / 9.0);
        assert_relative_eq!(arch.fused().mean()[0], x, epsilon = 1e-12);
        let p = 20.0 / 9.0 - (50.0 / 27.0) * (50.0 / 27.0) / (58.0 / 27.0);
        assert_relative_eq!(arch.fused().cov()[(0, 0)], p, epsilon = 1e-12);
    }

    #[test]
    fn covariance_intersection_reports_weight_and_failure_leaves_state() {
        let mut ci = t2t(FusionRule::CovarianceIntersection);
        ci.step(1.0, &Vector1::new(1.0), &Vector1::new(1.2))
            .unwrap();
        let snap = ci.snapshot();
        let w = snap.ci_weight.unwrap();
        assert!((0.0..=1.0).contains(&w));
        let before = ci.clone();
        assert!(matches!(
            ci.step(2.0, &Vector1::new(f64::NAN), &Vector1::new(1.0)),
            Err(ArchitectureError::Filter { track: "main", .. })
        ));
        assert!(
            ci.step(0.5, &Vector1::new(1.0), &Vector1::new(1.0))
                .is_err()
        );
        assert_eq!(ci, before);
    }
}

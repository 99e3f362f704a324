//! The equalize-fuse-feedback (EFF) structure proposed by paper A (Lee & Yoon 2011,
//! Fig. 2), built on [`TrackToTrack`]. Each step `k`:
//!
//! 1. **equalize** (eq. 9): fuse the two sensors' own states at `k-1` with the
//!    measurement-noise weights, `R_E = (R_I^-1 + R_D^-1)^-1`,
//!    `x_E = R_E R_I^-1 s_I + R_E R_D^-1 s_D`. `R` is `M x M` in measurement space; the
//!    [`Equalization`] expands its weights to the state with a [`StateComponent`]
//!    layout (each measurement axis' weights apply to that axis' position and
//!    velocity);
//! 2. both tracks take `x_E` as their prior state at `k-1` (each keeps its own `P`),
//!    predict to `k` and correct with their own sensor's measurement at `k`;
//! 3. **fuse** the two corrected estimates with the track-to-track rule (eq. 10 in
//!    the paper);
//! 4. **feedback**: hand the fused estimate to the main sensor through a
//!    [`FeedbackSink`] (e.g. reset the INS integrator's position and velocity).
//!
//! Steps 1 and 4 are switched by [`EffSwitches`]: with both off, the step is exactly
//! [`TrackToTrack::step`] (same code path, bit-identical results).

use super::{ArchitectureError, FeedbackSink, TrackToTrack};
use fathom_core::{Gaussian, Time, error::ensure_finite};
use nalgebra::{SMatrix, SVector};

/// Where a state component sits: its measurement axis and its derivative order
/// (0 = position, 1 = velocity, ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateComponent {
    /// Measurement-space axis (row of `R`) the component belongs to.
    pub axis: usize,
    /// Derivative order of the component.
    pub order: usize,
}

/// The paper-A layout `[x, vx, y, vy, z, vz]`.
pub fn cv_layout_3d() -> [StateComponent; 6] {
    let c = |axis, order| StateComponent { axis, order };
    [c(0, 0), c(0, 1), c(1, 0), c(1, 1), c(2, 0), c(2, 1)]
}

/// Step 1 of EFF: `x_E = W_main s_main + W_aux s_aux` (state space, `N x N` weights).
#[derive(Debug, Clone, PartialEq)]
pub struct Equalization<const N: usize> {
    main_weight: SMatrix<f64, N, N>,
    aux_weight: SMatrix<f64, N, N>,
}

impl<const N: usize> Equalization<N> {
    /// Equalization with explicit state-space weights.
    ///
    /// # Errors
    /// [`ArchitectureError::InvalidConfig`] for non-finite weights.
    pub fn new(
        main_weight: SMatrix<f64, N, N>,
        aux_weight: SMatrix<f64, N, N>,
    ) -> Result<Self, ArchitectureError> {
        for (what, w) in [("main weight", &main_weight), ("aux weight", &aux_weight)] {
            ensure_finite(what, w.iter()).map_err(|e| ArchitectureError::InvalidConfig {
                what: "equalization".into(),
                reason: e.to_string(),
            })?;
        }
        Ok(Self {
            main_weight,
            aux_weight,
        })
    }

    /// Paper A eq. (9): measurement-space weights `K_main = R_E R_main^-1`,
    /// `K_aux = R_E R_aux^-1` with `R_E = (R_main^-1 + R_aux^-1)^-1`, expanded to the
    /// state: `W[i][j] = K[axis_i][axis_j]` when components `i` and `j` have the same
    /// derivative order, 0 otherwise. For diagonal `R` each axis' position and
    /// velocity get the scalar weights `r_aux / (r_main + r_aux)` and
    /// `r_main / (r_main + r_aux)`; `W_main + W_aux = I`.
    ///
    /// # Errors
    /// [`ArchitectureError::InvalidConfig`] when an `R` is not SPD or a layout axis is
    /// `>= M`.
    pub fn from_measurement_noise<const M: usize>(
        r_main: &SMatrix<f64, M, M>,
        r_aux: &SMatrix<f64, M, M>,
        layout: &[StateComponent; N],
    ) -> Result<Self, ArchitectureError> {
        let cfg = |reason: String| ArchitectureError::InvalidConfig {
            what: "equalization".into(),
            reason,
        };
        if let Some((i, c)) = layout.iter().enumerate().find(|(_, c)| c.axis >= M) {
            return Err(cfg(format!(
                "state component {i} refers to axis {} of a {M}-dimensional measurement",
                c.axis
            )));
        }
        let inv = |r: &SMatrix<f64, M, M>, name: &str| {
            fathom_core::gaussian::check_covariance(name, r).map_err(|e| cfg(e.to_string()))?;
            r.cholesky()
                .map(|c| c.inverse())
                .ok_or_else(|| cfg(format!("{name} is not positive definite")))
        };
        let ri_main = inv(r_main, "R main")?;
        let ri_aux = inv(r_aux, "R aux")?;
        let r_e = (ri_main + ri_aux)
            .cholesky()
            .map(|c| c.inverse())
            .ok_or_else(|| cfg("R_main^-1 + R_aux^-1 is not positive definite".into()))?;
        let (k_main, k_aux) = (r_e * ri_main, r_e * ri_aux);
        let expand = |k: &SMatrix<f64, M, M>| {
            SMatrix::<f64, N, N>::from_fn(|i, j| {
                if layout[i].order == layout[j].order {
                    k[(layout[i].axis, layout[j].axis)]
                } else {
                    0.0
                }
            })
        };
        Self::new(expand(&k_main), expand(&k_aux))
    }

    /// `x_E = W_main s_main + W_aux s_aux`.
    pub fn apply(&self, s_main: &SVector<f64, N>, s_aux: &SVector<f64, N>) -> SVector<f64, N> {
        self.main_weight * s_main + self.aux_weight * s_aux
    }

    /// `W_main`.
    pub fn main_weight(&self) -> &SMatrix<f64, N, N> {
        &self.main_weight
    }

    /// `W_aux`.
    pub fn aux_weight(&self) -> &SMatrix<f64, N, N> {
        &self.aux_weight
    }
}

/// Which optional EFF steps run (the fusion, step 3, always does).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EffSwitches {
    /// Step 1 + the equalized prior of step 2.
    pub equalize: bool,
    /// Step 4.
    pub feedback: bool,
}

impl EffSwitches {
    /// The paper's structure: both on.
    pub const FULL: Self = Self {
        equalize: true,
        feedback: true,
    };
    /// Ablation `EFF-no-feedback`.
    pub const NO_FEEDBACK: Self = Self {
        equalize: true,
        feedback: false,
    };
    /// Ablation `EFF-no-equalization` (= track-to-track + feedback).
    pub const NO_EQUALIZATION: Self = Self {
        equalize: false,
        feedback: true,
    };
    /// Both off: plain track-to-track fusion.
    pub const NONE: Self = Self {
        equalize: false,
        feedback: false,
    };
}

/// What one EFF step produced.
#[derive(Debug, Clone, PartialEq)]
pub struct EffOutput<const N: usize> {
    /// The equalized prior `x_E` (step 1), `None` when equalization is off.
    pub equalized: Option<SVector<f64, N>>,
    /// The fused estimate (step 3), also what was fed back (step 4).
    pub fused: Gaussian<N>,
    /// Whether the fused estimate was handed to the feedback sink.
    pub fed_back: bool,
}

/// The EFF architecture (see the module docs).
///
/// Bad input: a non-finite sensor state or measurement is an
/// [`ArchitectureError::Filter`] naming the track, quantity and index with the step
/// time; loss of positive definiteness is a filter or fusion error with the time;
/// the architecture (and the feedback sink) is untouched on error.
#[derive(Debug, Clone, PartialEq)]
pub struct EqualizeFuseFeedback<const N: usize, const M1: usize, const M2: usize> {
    tracks: TrackToTrack<N, M1, M2>,
    equalization: Equalization<N>,
    switches: EffSwitches,
}

impl<const N: usize, const M1: usize, const M2: usize> EqualizeFuseFeedback<N, M1, M2> {
    /// EFF over the two tracks of `tracks` (their models, priors and fusion rule; the
    /// paper uses [`super::FusionRule::Independent`]).
    pub fn new(
        tracks: TrackToTrack<N, M1, M2>,
        equalization: Equalization<N>,
        switches: EffSwitches,
    ) -> Self {
        Self {
            tracks,
            equalization,
            switches,
        }
    }

    /// One EFF step to `time` (module docs). `main_state_prev` and `aux_state_prev`
    /// are the sensors' own states at the previous step (e.g. the INS integrator's
    /// position and velocity, the DVL dead reckoning's position and measured velocity,
    /// in the filter's state layout); they are used only when equalization is on.
    /// `z_main`, `z_aux` are the sensors' measurements at `time`. `sink` is called with
    /// the fused estimate when feedback is on.
    ///
    /// # Errors
    /// [`ArchitectureError::Filter`] for a non-finite equalized state or a failing
    /// filter step, [`ArchitectureError::Fusion`], [`ArchitectureError::Feedback`] when
    /// the sink refuses. The architecture is unchanged on error.
    pub fn step<S: FeedbackSink<N>>(
        &mut self,
        time: Time,
        main_state_prev: &SVector<f64, N>,
        aux_state_prev: &SVector<f64, N>,
        z_main: &SVector<f64, M1>,
        z_aux: &SVector<f64, M2>,
        sink: &mut S,
    ) -> Result<EffOutput<N>, ArchitectureError> {
        if self.switches.equalize {
            for (track, state) in [("main", main_state_prev), ("aux", aux_state_prev)] {
                if let Some(index) = state.iter().position(|v| !v.is_finite()) {
                    return Err(ArchitectureError::Filter {
                        track,
                        source: crate::EstimatorError::NonFinite {
                            what: format!("{track} sensor state (equalization input)"),
                            index,
                            value: state[index],
                            time,
                        },
                    });
                }
            }
        }
        let equalized = self
            .switches
            .equalize
            .then(|| self.equalization.apply(main_state_prev, aux_state_prev));
        let next = self
            .tracks
            .advanced(time, equalized.as_ref(), z_main, z_aux)?;
        let fused = next.fused().clone();
        if self.switches.feedback {
            sink.feed_back(time, &fused)
                .map_err(|e| ArchitectureError::Feedback {
                    time,
                    source: Box::new(e),
                })?;
        }
        self.tracks = next;
        Ok(EffOutput {
            equalized,
            fused,
            fed_back: self.switches.feedback,
        })
    }

    /// The two tracks (their filters, the fused estimate).
    pub fn tracks(&self) -> &TrackToTrack<N, M1, M2> {
        &self.tracks
    }

    /// The switches.
    pub fn switches(&self) -> EffSwitches {
        self.switches
    }

    /// The equalization weights.
    pub fn equalization(&self) -> &Equalization<N> {
        &self.equalization
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::architectures::{FusionRule, NoFeedback, TrackModel};
    use approx::assert_relative_eq;
    use nalgebra::{Matrix1, Matrix2, Matrix3, RowVector2, Vector1, Vector2, Vector3, Vector6};

    fn model(w: f64, r: f64) -> TrackModel<2, 1> {
        TrackModel::new(
            Matrix2::new(1.0, 1.0, 0.0, 1.0),
            Matrix2::identity() * (w * w),
            RowVector2::new(1.0, 0.0),
            Matrix1::new(r),
        )
        .unwrap()
    }

    fn tracks() -> TrackToTrack<2, 1, 1> {
        let prior = Gaussian::new(Vector2::new(0.0, 1.0), Matrix2::identity()).unwrap();
        TrackToTrack::new(
            prior.clone(),
            prior,
            Matrix2::zeros(),
            0.0,
            model(2.0, 4.0),
            model(1.0, 1.0),
            FusionRule::Independent,
        )
        .unwrap()
    }

    fn layout_1d() -> [StateComponent; 2] {
        [
            StateComponent { axis: 0, order: 0 },
            StateComponent { axis: 0, order: 1 },
        ]
    }

    /// Records what was fed back.
    #[derive(Default)]
    struct Recorder(Vec<(f64, Vector2<f64>)>);

    impl FeedbackSink<2> for Recorder {
        type Error = std::convert::Infallible;
        fn feed_back(&mut self, time: Time, fused: &Gaussian<2>) -> Result<(), Self::Error> {
            self.0.push((time, *fused.mean()));
            Ok(())
        }
    }

    #[test]
    fn one_step_by_hand() {
        let eq = Equalization::from_measurement_noise(
            &Matrix1::new(4.0),
            &Matrix1::new(1.0),
            &layout_1d(),
        )
        .unwrap();
        let mut eff = EqualizeFuseFeedback::new(tracks(), eq, EffSwitches::FULL);
        let mut sink = Recorder::default();
        let out = eff
            .step(
                1.0,
                &Vector2::new(2.0, 1.5),
                &Vector2::new(0.5, 1.0),
                &Vector1::new(2.5),
                &Vector1::new(1.7),
                &mut sink,
            )
            .unwrap();
        // 1. R_E = (1/4 + 1)^-1 = 0.8; weights 0.2 (main), 0.8 (aux):
        //    x_E = [0.2*2 + 0.8*0.5, 0.2*1.5 + 0.8*1] = [0.8, 1.1].
        assert_relative_eq!(
            out.equalized.unwrap(),
            Vector2::new(0.8, 1.1),
            epsilon = 1e-15
        );
        // 2. both predict from x_E: x- = [1.9, 1.1].
        //    main: P- = [[2,1],[1,1]] + 4I = [[6,1],[1,5]], S = 10, K = [0.6, 0.1],
        //          nu = 2.5 - 1.9 = 0.6 -> x = [2.26, 1.16], P = P- - K S K^T = [[2.4,0.4],[0.4,4.9]].
        //    aux:  P- = [[3,1],[1,2]], S = 4, K = [0.75, 0.25], nu = -0.2
        //          -> x = [1.75, 1.05], P = [[0.75,0.25],[0.25,1.75]].
        let t = eff.tracks();
        assert_relative_eq!(*t.main().state(), Vector2::new(2.26, 1.16), epsilon = 1e-12);
        assert_relative_eq!(
            *t.main().covariance(),
            Matrix2::new(2.4, 0.4, 0.4, 4.9),
            epsilon = 1e-12
        );
        assert_relative_eq!(*t.aux().state(), Vector2::new(1.75, 1.05), epsilon = 1e-12);
        assert_relative_eq!(
            *t.aux().covariance(),
            Matrix2::new(0.75, 0.25, 0.25, 1.75),
            epsilon = 1e-12
        );
        // 3. eq. (10): P_I^-1 = [[4.9,-0.4],[-0.4,2.4]]/11.6,
        //    P_D^-1 = [[1.75,-0.25],[-0.25,0.75]]/1.25.
        let ia = Matrix2::new(4.9, -0.4, -0.4, 2.4) / 11.6;
        let ib = Matrix2::new(1.75, -0.25, -0.25, 0.75) / 1.25;
        let p = (ia + ib).try_inverse().unwrap();
        let x = p * (ia * Vector2::new(2.26, 1.16) + ib * Vector2::new(1.75, 1.05));
        assert_relative_eq!(*out.fused.mean(), x, epsilon = 1e-12);
        assert_relative_eq!(*out.fused.cov(), p, epsilon = 1e-12);
        // 4. the fused estimate went to the main sensor, once, at t = 1.
        assert_eq!(sink.0.len(), 1);
        assert_eq!(sink.0[0].0, 1.0);
        assert_relative_eq!(sink.0[0].1, x, epsilon = 1e-12);
        assert!(out.fed_back);
    }

    #[test]
    fn both_switches_off_is_track_to_track_exactly() {
        let eq = Equalization::from_measurement_noise(
            &Matrix1::new(4.0),
            &Matrix1::new(1.0),
            &layout_1d(),
        )
        .unwrap();
        let mut eff = EqualizeFuseFeedback::new(tracks(), eq, EffSwitches::NONE);
        let mut t2t = tracks();
        let mut sink = Recorder::default();
        for k in 1..=50 {
            let t = k as f64;
            let za = Vector1::new(t + (0.7 * t).sin());
            let zb = Vector1::new(t - 0.3 * (0.2 * t).cos());
            // The sensor states are garbage on purpose: they must not be used.
            let out = eff
                .step(
                    t,
                    &Vector2::new(1e9, -1e9),
                    &Vector2::new(f64::MAX, 0.0),
                    &za,
                    &zb,
                    &mut sink,
                )
                .unwrap();
            let fused = t2t.step(t, &za, &zb).unwrap();
            assert_eq!(&out.fused, fused);
            assert!(out.equalized.is_none() && !out.fed_back);
        }
        assert_eq!(eff.tracks(), &t2t);
        assert!(sink.0.is_empty());
    }

    #[test]
    fn paper_layout_weights() {
        let ri = Matrix3::identity() * 9.8 * 9.8;
        let rd = Matrix3::identity() * 0.02 * 0.02;
        let eq = Equalization::from_measurement_noise(&ri, &rd, &cv_layout_3d()).unwrap();
        let wi = 0.0004 / (96.04 + 0.0004);
        assert_relative_eq!(eq.main_weight()[(0, 0)], wi, epsilon = 1e-15);
        assert_relative_eq!(eq.main_weight()[(3, 3)], wi, epsilon = 1e-15);
        assert_eq!(eq.main_weight()[(0, 1)], 0.0);
        assert_relative_eq!(
            eq.main_weight() + eq.aux_weight(),
            nalgebra::Matrix6::identity(),
            epsilon = 1e-14
        );
        let s_i = Vector6::new(10.0, 1.0, 20.0, 2.0, 30.0, 3.0);
        let s_d = Vector6::zeros();
        assert_relative_eq!(eq.apply(&s_i, &s_d), s_i * wi, epsilon = 1e-15);
        // Axis out of range.
        let bad = [StateComponent { axis: 3, order: 0 }; 6];
        assert!(Equalization::from_measurement_noise(&ri, &rd, &bad).is_err());
        let _ = Vector3::<f64>::zeros();
    }

    #[derive(Debug, thiserror::Error)]
    #[error("integrator refuses")]
    struct Refuse;

    struct Refusing;
    impl FeedbackSink<2> for Refusing {
        type Error = Refuse;
        fn feed_back(&mut self, _: Time, _: &Gaussian<2>) -> Result<(), Refuse> {
            Err(Refuse)
        }
    }

    /// Bad input (crate docs): a non-finite sensor state (equalization input) is an
    /// error naming the sensor, the component and the step time; unchanged.
    #[test]
    fn non_finite_sensor_state_is_an_error_with_the_step_time() {
        let eq = Equalization::new(Matrix2::identity(), Matrix2::zeros()).unwrap();
        let mut eff = EqualizeFuseFeedback::new(tracks(), eq, EffSwitches::FULL);
        let before = eff.clone();
        let s = Vector2::new(0.0, 1.0);
        let nan = Vector2::new(0.0, f64::NAN);
        let z = Vector1::new(1.0);
        for (main, aux, track) in [(&nan, &s, "main"), (&s, &nan, "aux")] {
            let mut rec = Recorder::default();
            match eff.step(1.0, main, aux, &z, &z, &mut rec) {
                Err(ArchitectureError::Filter {
                    track: t,
                    source:
                        crate::EstimatorError::NonFinite {
                            what, index, time, ..
                        },
                }) => {
                    assert!(what.contains("sensor state"), "{what}");
                    assert_eq!((t, index, time), (track, 1, 1.0));
                }
                other => panic!("unexpected {other:?}"),
            }
            assert!(rec.0.is_empty());
            assert_eq!(eff, before);
        }
        let e = eff
            .step(1.0, &s, &s, &Vector1::new(f64::NAN), &z, &mut NoFeedback)
            .unwrap_err();
        assert!(e.to_string().contains("t = 1 s"), "{e}");
        assert_eq!(eff, before);
    }

    #[test]
    fn refused_feedback_is_an_error_and_changes_nothing() {
        let eq = Equalization::new(Matrix2::identity(), Matrix2::zeros()).unwrap();
        let mut eff = EqualizeFuseFeedback::new(tracks(), eq, EffSwitches::FULL);
        let before = eff.clone();
        let s = Vector2::new(0.0, 1.0);
        let e = eff
            .step(
                1.0,
                &s,
                &s,
                &Vector1::new(1.0),
                &Vector1::new(1.0),
                &mut Refusing,
            )
            .unwrap_err();
        assert!(matches!(e, ArchitectureError::Feedback { time, .. } if time == 1.0));
        assert!(e.to_string().contains("t = 1 s"));
        assert_eq!(eff, before);
        // NoFeedback never refuses; a NaN sensor state is a filter error.
        let mut eff2 = EqualizeFuseFeedback::new(
            tracks(),
            before.equalization().clone(),
            EffSwitches::NO_FEEDBACK,
        );
        let nan = Vector2::new(f64::NAN, 0.0);
        assert!(matches!(
            eff2.step(
                1.0,
                &nan,
                &s,
                &Vector1::new(1.0),
                &Vector1::new(1.0),
                &mut NoFeedback
            ),
            Err(ArchitectureError::Filter { .. })
        ));
        assert!(
            eff2.step(
                1.0,
                &s,
                &s,
                &Vector1::new(1.0),
                &Vector1::new(1.0),
                &mut NoFeedback
            )
            .is_ok()
        );
    }
}

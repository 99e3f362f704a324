//! Measurement-update schemes of paper B (seed 003, section 5) as one policy over the
//! same [`Ekf`]: asynchronous (AS), synchronous collective (SC) and synchronous
//! individual (SI), with per-channel chi-square gating and an explicit rule for
//! stale and superseded measurements.
//!
//! A [`SchemeFilter`] consumes a stream of [`Event`]s in arrival order: input samples
//! (e.g. DVL velocity, AHRS yaw rate) and scalar [`Observation`]s on numbered
//! *channels* (e.g. range to beacon 1..4, depth). The filter time only moves forward.
//!
//! # Inputs (all schemes)
//! An input stamped `s` first brings the filter to `s` (SC/SI: firing the epochs
//! before `s`, then predicting) with the input held so far, then replaces it. An input
//! stamped before the filter time is applied from the current time on and counted as
//! late ([`SchemeFilter::late_inputs`]); the past is never re-predicted.
//!
//! # Asynchronous (AS)
//! Each measurement is processed at its own stamp `s`: predict to `s`, then a scalar
//! update with its diagonal variance `R_cc`. Measurements arriving with the **same**
//! stamp form one group, processed as sequential scalars linearized at the state
//! predicted to `s` (exactly the SI update; [`crate::ekf`] module docs). Time rule:
//! - `s > t` (filter time): predict to `s` and process;
//! - `t - tolerance <= s <= t`: processed at the current time `t` (`applied_at = t`);
//! - `s < t - tolerance`: **stale**: not applied, logged as [`Disposition::Stale`] and
//!   counted per channel. Default tolerance 0: only exactly-current stamps are
//!   accepted late.
//!
//! # Synchronous (SC, SI)
//! Epochs at `t_k = t0 + k T` (`k = 1, 2, ...`, `T` = epoch period). A measurement
//! stamped `s` belongs to the epoch window `(t_{k-1}, t_k]`. At each epoch the newest
//! unprocessed sample of each channel in its window is treated as taken at `t_k`:
//! - SC: one stacked update with the full channel covariance restricted to the present
//!   channels (including cross-channel terms such as the common-mode range
//!   correlation), rejected components removed first;
//! - SI: sequential scalar updates in channel order with the diagonal variances.
//!
//! Older samples of the same channel in the same window are **superseded** (logged,
//! never applied). A sample whose stamp lies in an already-fired window
//! (`s <= t_{k-1}`, only possible with out-of-order arrival) is **stale**. An epoch
//! fires when an event stamped after it arrives or on [`SchemeFilter::advance_to`];
//! events stamped exactly `t_k` still belong to epoch `k`.
//!
//! Every measurement ends in exactly one [`Decision`] (accepted, rejected, stale,
//! superseded, non-finite), so rejected measurements are reported, not lost.
//!
//! # Bad data (non-finite values and stamps)
//! The scheme filter is built to skip bad data: a measurement whose value or stamp is
//! NaN or infinite is **dropped**: logged as [`Disposition::NonFinite`] at the current
//! filter time, counted per channel ([`ChannelCounts::non_finite`]) and never applied
//! (it does not close an AS group, fire an epoch or supersede a pending sample). An
//! input sample with a non-finite component or stamp is dropped and counted
//! ([`SchemeFilter::non_finite_inputs`]); the held input stays the previous one. An
//! unknown channel is a configuration error, not bad data. A covariance that stops
//! being positive definite is an [`EstimatorError`] carrying the filter time of the
//! failing step; the EKF keeps its last good estimate and the measurements of the
//! failing group stay pending.
//!
//! # Robust handling (optional)
//! With [`SchemeFilter::with_robust`] every group (AS same-stamp group, SC/SI epoch) is
//! gated on the normalized innovation at the prior (`S = H P H^T + R_cc`, the channel
//! gate), the accepted measurements are Huber down-weighted by inflating their
//! variances (SC: `R' = D R D`, `D = diag(sqrt(factor))`; SI/AS: the sequential update
//! with the inflated diagonal variances), and runs of consecutive rejected or
//! down-weighted measurements (overall or per channel) inflate the state covariance so the filter cannot lock
//! itself out ([`crate::robust`]).

use crate::{
    EstimatorError, GateThreshold, ScalarOutcome,
    ekf::{Ekf, GroupItem, MotionModel, ScalarModel},
    robust::{LockoutMonitor, RobustPolicy},
};
use fathom_core::{CoreError, Time, gaussian::SYMMETRY_TOLERANCE};
use nalgebra::DMatrix;

/// Which update scheme a [`SchemeFilter`] uses (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum UpdateScheme {
    /// AS: every measurement at its own time stamp.
    Asynchronous,
    /// SC: stacked update at sync epochs with the full `R`.
    SynchronousCollective,
    /// SI: sequential scalar updates at sync epochs with a diagonal `R`.
    SynchronousIndividual,
}

impl UpdateScheme {
    /// All three, in the paper's order AS, SC, SI.
    pub const ALL: [UpdateScheme; 3] = [
        UpdateScheme::Asynchronous,
        UpdateScheme::SynchronousCollective,
        UpdateScheme::SynchronousIndividual,
    ];

    /// The paper's abbreviation (`AS`, `SC`, `SI`).
    pub fn short_name(self) -> &'static str {
        match self {
            UpdateScheme::Asynchronous => "AS",
            UpdateScheme::SynchronousCollective => "SC",
            UpdateScheme::SynchronousIndividual => "SI",
        }
    }

    /// Whether the scheme updates at sync epochs.
    pub fn is_synchronous(self) -> bool {
        !matches!(self, UpdateScheme::Asynchronous)
    }
}

/// Unchecked configuration of a [`SchemeFilter`].
#[derive(Debug, Clone, PartialEq)]
pub struct SchemeParams {
    /// The update scheme.
    pub scheme: UpdateScheme,
    /// Sync epoch period `T`, s (> 0; used by SC/SI).
    pub epoch_period: f64,
    /// AS: how far before the filter time a stamp may lie and still be applied (at the
    /// filter time), s (>= 0; default 0).
    pub stale_tolerance: f64,
    /// Channel noise covariance (`C x C`, symmetric positive definite): diagonal =
    /// each channel's variance, off-diagonal = correlation between channels sampled
    /// together (used by SC only).
    pub channel_cov: DMatrix<f64>,
    /// Gate per channel (`None` = never rejected); length `C`.
    pub gates: Vec<Option<GateThreshold>>,
}

/// Checked [`SchemeParams`].
#[derive(Debug, Clone, PartialEq)]
pub struct SchemeConfig(SchemeParams);

impl SchemeParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] for a bad period or tolerance,
    /// [`EstimatorError::DimensionMismatch`] for inconsistent sizes, or a covariance
    /// error naming "channel covariance".
    pub fn check(self) -> Result<SchemeConfig, EstimatorError> {
        if !(self.epoch_period.is_finite() && self.epoch_period > 0.0) {
            return Err(EstimatorError::OutOfRange {
                what: "epoch period".into(),
                value: self.epoch_period,
                expected: "> 0",
            });
        }
        if !(self.stale_tolerance.is_finite() && self.stale_tolerance >= 0.0) {
            return Err(EstimatorError::OutOfRange {
                what: "stale tolerance".into(),
                value: self.stale_tolerance,
                expected: ">= 0",
            });
        }
        let c = self.channel_cov.nrows();
        if c == 0 || self.channel_cov.ncols() != c {
            return Err(EstimatorError::DimensionMismatch {
                what: "channel covariance columns".into(),
                expected: c.max(1),
                got: self.channel_cov.ncols(),
            });
        }
        if self.gates.len() != c {
            return Err(EstimatorError::DimensionMismatch {
                what: "gates per channel".into(),
                expected: c,
                got: self.gates.len(),
            });
        }
        let cov = &self.channel_cov;
        let scale = cov
            .diagonal()
            .iter()
            .fold(f64::MIN_POSITIVE, |a, b| a.max(b.abs()));
        for i in 0..c {
            for j in 0..c {
                let v = cov[(i, j)];
                if !v.is_finite() {
                    return Err(EstimatorError::Core(CoreError::NonFinite {
                        what: "channel covariance".into(),
                        index: i * c + j,
                        value: v,
                    }));
                }
                if (v - cov[(j, i)]).abs() > SYMMETRY_TOLERANCE * scale {
                    return Err(EstimatorError::Core(CoreError::NotSymmetric {
                        what: "channel covariance".into(),
                        row: i,
                        col: j,
                        diff: (v - cov[(j, i)]).abs(),
                    }));
                }
            }
        }
        if cov.clone().cholesky().is_none() {
            return Err(EstimatorError::Core(CoreError::NotPositiveDefinite {
                what: "channel covariance".into(),
            }));
        }
        Ok(SchemeConfig(self))
    }
}

impl SchemeConfig {
    /// The checked parameters.
    pub fn params(&self) -> &SchemeParams {
        &self.0
    }

    /// Number of measurement channels.
    pub fn channels(&self) -> usize {
        self.0.gates.len()
    }
}

/// A scalar measurement on a channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation<S> {
    /// Channel index (`< C`).
    pub channel: usize,
    /// Reported time stamp, s.
    pub stamp: Time,
    /// Measured value.
    pub value: f64,
    /// Measurement model.
    pub model: S,
    /// Caller's identifier, echoed in the [`Decision`] (e.g. the sample index).
    pub tag: usize,
}

/// One item of the stream consumed by a [`SchemeFilter`].
#[derive(Debug, Clone, PartialEq)]
pub enum Event<I, S> {
    /// An input sample for the motion model.
    Input {
        /// Time stamp, s.
        stamp: Time,
        /// The sample.
        sample: I,
    },
    /// A scalar measurement.
    Measurement(Observation<S>),
}

impl<I, S> Event<I, S> {
    /// The event's time stamp, s.
    pub fn stamp(&self) -> Time {
        match self {
            Event::Input { stamp, .. } => *stamp,
            Event::Measurement(o) => o.stamp,
        }
    }
}

/// What happened to a measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Disposition {
    /// Passed the gate and was applied.
    Accepted,
    /// Failed the gate (not applied).
    Rejected,
    /// Older than the filter allows (module docs); not applied.
    Stale,
    /// A newer sample of the same channel in the same epoch window replaced it (SC/SI).
    Superseded,
    /// Its value or stamp is NaN or infinite: dropped, never applied (module docs).
    NonFinite,
}

/// The fate of one measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// Channel.
    pub channel: usize,
    /// The observation's tag.
    pub tag: usize,
    /// Its time stamp, s.
    pub stamp: Time,
    /// The filter time it was processed at (epoch for SC/SI), or the filter time when it
    /// was dropped, s.
    pub applied_at: Time,
    /// The measured value.
    pub value: f64,
    /// Outcome.
    pub disposition: Disposition,
    /// The gating statistic `nu^2 / S` when it was computed.
    pub nis: Option<f64>,
    /// The innovation `nu = z - h(x)` (residual of the measurement model) when it was
    /// computed, with `nis`: what a replay without ground truth reports.
    pub innovation: Option<f64>,
}

/// Per-channel counts of the dispositions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ChannelCounts {
    /// Applied.
    pub accepted: usize,
    /// Rejected by the gate.
    pub rejected: usize,
    /// Dropped as stale.
    pub stale: usize,
    /// Superseded within an epoch window.
    pub superseded: usize,
    /// Dropped because the value or the stamp is not finite.
    pub non_finite: usize,
}

impl ChannelCounts {
    /// The sum over channels.
    pub fn total(counts: &[ChannelCounts]) -> ChannelCounts {
        counts
            .iter()
            .fold(ChannelCounts::default(), |a, c| ChannelCounts {
                accepted: a.accepted + c.accepted,
                rejected: a.rejected + c.rejected,
                stale: a.stale + c.stale,
                superseded: a.superseded + c.superseded,
                non_finite: a.non_finite + c.non_finite,
            })
    }
}

/// An [`Ekf`] run under an [`UpdateScheme`] (module docs).
///
/// Bad input: non-finite measurements (value or stamp) and input samples are dropped
/// and counted ([`ChannelCounts::non_finite`], [`SchemeFilter::non_finite_inputs`]);
/// loss of positive definiteness is an error with the filter time (module docs).
#[derive(Debug, Clone)]
pub struct SchemeFilter<const N: usize, M: MotionModel<N>, S> {
    ekf: Ekf<N, M>,
    config: SchemeConfig,
    t0: Time,
    /// AS: the open same-stamp group and the time it is applied at.
    group: Vec<Observation<S>>,
    group_stamp: Option<(Time, Time)>,
    /// SC/SI: newest pending sample per channel, last fired epoch and the next index.
    pending: Vec<Option<Observation<S>>>,
    last_epoch: Time,
    next_epoch: u64,
    decisions: Vec<Decision>,
    counts: Vec<ChannelCounts>,
    late_inputs: usize,
    non_finite_inputs: usize,
    /// Optional robust handling, its lock-out monitor and the down-weighted count.
    robust: Option<RobustPolicy>,
    lockout: LockoutMonitor,
    downweighted: usize,
}

impl<const N: usize, M: MotionModel<N>, S: ScalarModel<N> + Clone> SchemeFilter<N, M, S> {
    /// Wraps `ekf`; epochs count from the EKF's current time.
    pub fn new(ekf: Ekf<N, M>, config: SchemeConfig) -> Self {
        let c = config.channels();
        let t0 = ekf.time();
        Self {
            ekf,
            config,
            t0,
            group: Vec::new(),
            group_stamp: None,
            pending: vec![None; c],
            last_epoch: t0,
            next_epoch: 1,
            decisions: Vec::new(),
            counts: vec![ChannelCounts::default(); c],
            late_inputs: 0,
            non_finite_inputs: 0,
            robust: None,
            lockout: LockoutMonitor::default(),
            downweighted: 0,
        }
    }

    /// Turns on robust handling (module docs): Huber down-weighting and lock-out
    /// recovery by covariance inflation, gates as configured per channel.
    pub fn with_robust(mut self, policy: RobustPolicy) -> Self {
        self.robust = Some(policy);
        self
    }

    /// Records the forward pass for smoothing ([`Ekf::start_recording`], from the
    /// current estimate): every prediction, epoch or group update and covariance
    /// inflation becomes a step; rejected, stale and superseded measurements change
    /// nothing, so the smoother ignores them as the filter did. Read the step of the
    /// estimate at an evaluation instant with
    /// `filter.ekf().forward_pass().map(|p| p.last_index())` and smooth with
    /// [`Ekf::smooth`] at the end.
    pub fn with_recording(mut self) -> Self {
        self.ekf.start_recording();
        self
    }

    /// Measurements applied with an inflated variance (robust handling).
    pub fn downweighted(&self) -> usize {
        self.downweighted
    }

    /// Covariance inflations after runs of rejections (robust handling).
    pub fn recoveries(&self) -> usize {
        self.lockout.recoveries()
    }

    /// The EKF (state, covariance, time).
    pub fn ekf(&self) -> &Ekf<N, M> {
        &self.ekf
    }

    /// The configuration.
    pub fn config(&self) -> &SchemeConfig {
        &self.config
    }

    /// Every decision so far, in processing order.
    pub fn decisions(&self) -> &[Decision] {
        &self.decisions
    }

    /// Counts per channel.
    pub fn counts(&self) -> &[ChannelCounts] {
        &self.counts
    }

    /// Inputs that arrived stamped before the filter time.
    pub fn late_inputs(&self) -> usize {
        self.late_inputs
    }

    /// Input samples dropped because a component or the stamp is not finite.
    pub fn non_finite_inputs(&self) -> usize {
        self.non_finite_inputs
    }

    /// Measurements dropped because the value or the stamp is not finite, all channels.
    pub fn non_finite_measurements(&self) -> usize {
        self.counts.iter().map(|c| c.non_finite).sum()
    }

    fn scheme(&self) -> UpdateScheme {
        self.config.0.scheme
    }

    fn epoch_time(&self, k: u64) -> Time {
        self.t0 + k as f64 * self.config.0.epoch_period
    }

    /// Processes one event (module docs). Non-finite values and stamps are dropped
    /// and counted (module docs, "Bad data"), not errors.
    ///
    /// # Errors
    /// [`EstimatorError::OutOfRange`] for an unknown channel, and the EKF's errors
    /// (carrying the filter time of the failing step).
    pub fn process(&mut self, event: Event<M::InputSample, S>) -> Result<(), EstimatorError> {
        match event {
            Event::Input { stamp, sample } => {
                if !stamp.is_finite() || self.ekf.model().non_finite_in_sample(&sample).is_some() {
                    self.non_finite_inputs += 1;
                    return Ok(());
                }
                if self.scheme().is_synchronous() {
                    self.fire_epochs_before(stamp)?;
                } else if self.group_stamp.is_some_and(|(s, _)| stamp != s) {
                    self.flush_group()?;
                }
                if stamp >= self.ekf.time() {
                    self.ekf.predict_to(stamp)?;
                } else {
                    self.late_inputs += 1;
                }
                self.ekf.apply_input(&sample);
                Ok(())
            }
            Event::Measurement(obs) => {
                if obs.channel >= self.config.channels() {
                    return Err(EstimatorError::OutOfRange {
                        what: format!("observation channel (tag {})", obs.tag),
                        value: obs.channel as f64,
                        expected: "< number of channels",
                    });
                }
                if !(obs.value.is_finite() && obs.stamp.is_finite()) {
                    let t = self.ekf.time();
                    self.log(&obs, t, Disposition::NonFinite, None);
                    return Ok(());
                }
                if self.scheme().is_synchronous() {
                    self.accept_sync(obs)
                } else {
                    self.accept_async(obs)
                }
            }
        }
    }

    /// Drives the filter through a log: for each evaluation instant `t` of
    /// `evaluation_times` (ascending), processes every event of `events` stamped `<= t`
    /// (in the iterator's order, which must be by stamp), brings the filter to `t`
    /// ([`SchemeFilter::advance_to`]) and calls `at_evaluation(k, t, filter)` for the
    /// `k`-th instant. Events stamped after the last instant stay in `events` for the
    /// caller; an event with a NaN stamp is processed where it stands in the stream
    /// (the filter drops and counts it). Filter errors go through `filter_error`.
    ///
    /// # Errors
    /// The first error of the filter (mapped) or of `at_evaluation`.
    pub fn run_to_evaluations<E, It>(
        &mut self,
        events: &mut std::iter::Peekable<It>,
        evaluation_times: impl IntoIterator<Item = Time>,
        filter_error: impl Fn(EstimatorError) -> E,
        mut at_evaluation: impl FnMut(usize, Time, &Self) -> Result<(), E>,
    ) -> Result<(), E>
    where
        It: Iterator<Item = Event<M::InputSample, S>>,
    {
        for (k, t) in evaluation_times.into_iter().enumerate() {
            // `!(stamp > t)`: a NaN stamp goes to the filter, which drops and counts it.
            #[allow(clippy::neg_cmp_op_on_partial_ord)]
            while let Some(event) = events.next_if(|e| !(e.stamp() > t)) {
                self.process(event).map_err(&filter_error)?;
            }
            self.advance_to(t).map_err(&filter_error)?;
            at_evaluation(k, t, self)?;
        }
        Ok(())
    }

    /// Brings the filter to `time`: closes the open AS group, fires every epoch
    /// `<= time` (SC/SI) and predicts to `time`. Call it after all events stamped
    /// `<= time` have been processed.
    ///
    /// # Errors
    /// [`EstimatorError::TimeBackwards`] for `time` before the filter time, and the
    /// EKF's errors.
    pub fn advance_to(&mut self, time: Time) -> Result<(), EstimatorError> {
        if self.scheme().is_synchronous() {
            if time.is_finite() {
                while self.epoch_time(self.next_epoch) <= time {
                    self.fire_epoch()?;
                }
            }
        } else {
            self.flush_group()?;
        }
        self.ekf.predict_to(time)
    }

    fn log(
        &mut self,
        obs: &Observation<S>,
        applied_at: Time,
        d: Disposition,
        stat: Option<(f64, f64)>,
    ) {
        let c = &mut self.counts[obs.channel];
        match d {
            Disposition::Accepted => c.accepted += 1,
            Disposition::Rejected => c.rejected += 1,
            Disposition::Stale => c.stale += 1,
            Disposition::Superseded => c.superseded += 1,
            Disposition::NonFinite => c.non_finite += 1,
        }
        self.decisions.push(Decision {
            channel: obs.channel,
            tag: obs.tag,
            stamp: obs.stamp,
            applied_at,
            value: obs.value,
            disposition: d,
            nis: stat.map(|s| s.0),
            innovation: stat.map(|s| s.1),
        });
    }

    fn log_outcomes(&mut self, obs: &[Observation<S>], at: Time, outcomes: &[ScalarOutcome]) {
        for (o, out) in obs.iter().zip(outcomes) {
            let d = if out.accepted {
                Disposition::Accepted
            } else {
                Disposition::Rejected
            };
            self.log(o, at, d, Some((out.nis, out.innovation)));
        }
    }

    // ----- AS -------------------------------------------------------------------

    fn accept_async(&mut self, obs: Observation<S>) -> Result<(), EstimatorError> {
        let s = obs.stamp;
        if let Some((gs, _)) = self.group_stamp {
            if s == gs {
                self.group.push(obs);
                return Ok(());
            }
            self.flush_group()?;
        }
        let t = self.ekf.time();
        let at = if s > t {
            self.ekf.predict_to(s)?;
            s
        } else if s >= t - self.config.0.stale_tolerance {
            t
        } else {
            self.log(&obs, t, Disposition::Stale, None);
            return Ok(());
        };
        self.group_stamp = Some((s, at));
        self.group.push(obs);
        Ok(())
    }

    fn flush_group(&mut self) -> Result<(), EstimatorError> {
        let Some((stamp, at)) = self.group_stamp.take() else {
            return Ok(());
        };
        let mut group = std::mem::take(&mut self.group);
        let outcomes = match self.update_individual(&group) {
            Ok(o) => o,
            Err(e) => {
                // Keep the group pending: the EKF is unchanged by the failed update.
                self.group = group;
                self.group_stamp = Some((stamp, at));
                return Err(e);
            }
        };
        self.log_outcomes(&group, at, &outcomes);
        group.clear();
        self.group = group; // keep the allocation
        Ok(())
    }

    fn update_individual(
        &mut self,
        obs: &[Observation<S>],
    ) -> Result<Vec<ScalarOutcome>, EstimatorError> {
        if let Some(policy) = self.robust {
            return self.update_robust(obs, false, policy);
        }
        let p = &self.config.0;
        let items: Vec<GroupItem<'_, S>> = obs
            .iter()
            .map(|o| GroupItem {
                value: o.value,
                model: &o.model,
                variance: p.channel_cov[(o.channel, o.channel)],
                gate: p.gates[o.channel],
            })
            .collect();
        self.ekf.update_sequential(&items)
    }

    /// Robust group update (module docs): gate at the prior, Huber variance
    /// inflation, stacked (`stacked`) or sequential update of the accepted items, then
    /// lock-out monitoring in item order.
    fn update_robust(
        &mut self,
        obs: &[Observation<S>],
        stacked: bool,
        policy: RobustPolicy,
    ) -> Result<Vec<ScalarOutcome>, EstimatorError> {
        let x = *self.ekf.state();
        let p = *self.ekf.covariance();
        let t = self.ekf.time();
        let cfg = &self.config.0;
        let mut outcomes = Vec::with_capacity(obs.len());
        let mut factors = Vec::with_capacity(obs.len());
        for o in obs {
            let (h0, h_row) = o.model.evaluate(&x)?;
            let nu = o.model.residual(o.value, h0);
            let s = (h_row * p * h_row.transpose())[0] + cfg.channel_cov[(o.channel, o.channel)];
            if !(nu.is_finite() && s.is_finite() && s > 0.0) {
                return Err(EstimatorError::NotPositiveDefinite {
                    what: format!(
                        "innovation covariance S (channel {}, tag {})",
                        o.channel, o.tag
                    ),
                    time: t,
                });
            }
            let nis = nu * nu / s;
            let accepted = cfg.gates[o.channel].is_none_or(|g| g.accepts(nis));
            outcomes.push(ScalarOutcome {
                innovation: nu,
                innovation_var: s,
                nis,
                accepted,
            });
            factors.push(policy.variance_factor(nis.sqrt()));
        }
        let keep: Vec<usize> = (0..obs.len()).filter(|&i| outcomes[i].accepted).collect();
        if !keep.is_empty() {
            let items: Vec<GroupItem<'_, S>> = keep
                .iter()
                .map(|&i| GroupItem {
                    value: obs[i].value,
                    model: &obs[i].model,
                    variance: cfg.channel_cov[(obs[i].channel, obs[i].channel)] * factors[i],
                    gate: None,
                })
                .collect();
            if stacked {
                let r = DMatrix::from_fn(keep.len(), keep.len(), |a, b| {
                    let (i, j) = (keep[a], keep[b]);
                    cfg.channel_cov[(obs[i].channel, obs[j].channel)]
                        * (factors[i] * factors[j]).sqrt()
                });
                self.ekf.update_stacked(&items, &r)?;
            } else {
                self.ekf.update_sequential(&items)?;
            }
            self.downweighted += keep.iter().filter(|&&i| factors[i] > 1.0).count();
        }
        for ((o, factor), ob) in outcomes.iter().zip(&factors).zip(obs) {
            let consistent = o.accepted && *factor <= 1.0;
            if let Some(factor) = self.lockout.record(ob.channel, consistent, &policy) {
                self.ekf.inflate_covariance(factor)?;
            }
        }
        Ok(outcomes)
    }

    // ----- SC / SI --------------------------------------------------------------

    fn accept_sync(&mut self, obs: Observation<S>) -> Result<(), EstimatorError> {
        self.fire_epochs_before(obs.stamp)?;
        // Its window was already fired (or it predates the first window, `<= t0`).
        if obs.stamp <= self.last_epoch {
            let t = self.ekf.time();
            self.log(&obs, t, Disposition::Stale, None);
            return Ok(());
        }
        let c = obs.channel;
        let t = self.ekf.time();
        match self.pending[c].take() {
            Some(old) if old.stamp > obs.stamp => {
                self.log(&obs, t, Disposition::Superseded, None);
                self.pending[c] = Some(old);
            }
            Some(old) => {
                self.log(&old, t, Disposition::Superseded, None);
                self.pending[c] = Some(obs);
            }
            None => self.pending[c] = Some(obs),
        }
        Ok(())
    }

    fn fire_epochs_before(&mut self, stamp: Time) -> Result<(), EstimatorError> {
        while self.epoch_time(self.next_epoch) < stamp {
            self.fire_epoch()?;
        }
        Ok(())
    }

    fn fire_epoch(&mut self) -> Result<(), EstimatorError> {
        let te = self.epoch_time(self.next_epoch);
        if te > self.ekf.time() {
            self.ekf.predict_to(te)?;
        }
        let at = self.ekf.time();
        let group: Vec<Observation<S>> = self.pending.iter_mut().filter_map(Option::take).collect();
        if !group.is_empty() {
            match self.update_epoch_group(&group) {
                Ok(outcomes) => self.log_outcomes(&group, at, &outcomes),
                Err(e) => {
                    // Keep the samples pending: the EKF is unchanged by the failed update.
                    for o in group {
                        let c = o.channel;
                        self.pending[c] = Some(o);
                    }
                    return Err(e);
                }
            }
        }
        self.last_epoch = te;
        self.next_epoch += 1;
        Ok(())
    }

    /// The SC / SI update of one epoch's samples.
    fn update_epoch_group(
        &mut self,
        group: &[Observation<S>],
    ) -> Result<Vec<ScalarOutcome>, EstimatorError> {
        match (self.scheme(), self.robust) {
            (UpdateScheme::SynchronousCollective, Some(policy)) => {
                self.update_robust(group, true, policy)
            }
            (UpdateScheme::SynchronousCollective, None) => {
                let cov = &self.config.0.channel_cov;
                let r = DMatrix::from_fn(group.len(), group.len(), |a, b| {
                    cov[(group[a].channel, group[b].channel)]
                });
                let items: Vec<GroupItem<'_, S>> = group
                    .iter()
                    .map(|o| GroupItem {
                        value: o.value,
                        model: &o.model,
                        variance: cov[(o.channel, o.channel)],
                        gate: self.config.0.gates[o.channel],
                    })
                    .collect();
                self.ekf.update_stacked(&items, &r)
            }
            _ => self.update_individual(group),
        }
    }
}

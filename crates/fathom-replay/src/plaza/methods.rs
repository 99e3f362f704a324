//! The methods run on a prepared Plaza log: pure dead reckoning and the wheel-odometry
//! EKF under an update scheme, with calibration states and robust or hard gating.

use fathom_core::Gaussian;
use fathom_estimators::{
    GateThreshold,
    ekf::Ekf,
    robust::{RecoveryParams, RobustParams},
    schemes::{
        ChannelCounts, Decision, Disposition, Event, Observation, SchemeFilter, SchemeParams,
    },
    wheel_odometry::{CalibratedRange, OdometryRate, WheelOdometry, WheelOdometryParams},
};
use fathom_stats::RunStats;
use nalgebra::{DMatrix, SMatrix, SVector};

use super::prepare::{Kind, PreparedLog};
use super::settings::{Calibration, OutlierHandling, PlazaSettings, Variant};
use crate::consistency::Innovation;
use fathom_sim::SimError;

/// The result of one method on the log.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MethodRun {
    /// Method name (`DR`, `AS`, `SC-no-bias`, ...).
    pub name: String,
    /// The variant (`None` for dead reckoning).
    pub variant: Option<Variant>,
    /// Estimated `(x, y)` at the evaluation instants.
    pub est: Vec<[f64; 2]>,
    /// 2D position error at the evaluation instants, m.
    pub err: Vec<f64>,
    /// Statistics of `err`.
    pub stats: RunStats,
    /// `sqrt(P_xx + P_yy)` at the evaluation instants, m.
    pub pos_sigma: Vec<f64>,
    /// Estimated range offset and scale error at the evaluation instants (0 when not
    /// estimated).
    pub calibration: Vec<[f64; 2]>,
    /// Ranges applied.
    pub accepted: usize,
    /// Ranges rejected by the gate.
    pub rejected: usize,
    /// Ranges superseded or stale (SC / SI: an older sample of the same beacon in the
    /// same epoch window).
    pub dropped: usize,
    /// Ranges dropped because the value or the stamp is not finite (never applied;
    /// the filter's bad-data policy, `fathom_estimators` crate docs "Bad input").
    pub non_finite: usize,
    /// Ranges applied with an inflated variance (Huber).
    pub downweighted: usize,
    /// Covariance inflations after runs of rejected or down-weighted ranges.
    pub recoveries: usize,
    /// Per range of the log (index as in `PlazaLog::ranges`): the decision, if the
    /// range was processed.
    pub decisions: Vec<Option<Disposition>>,
    /// Every tested range in processing order, with its innovation and NIS (empty for
    /// dead reckoning).
    #[serde(default)]
    pub innovations: Vec<Innovation>,
    /// The RTS-smoothed estimates of the same filter (`smooth = true`; `None` for dead
    /// reckoning or when smoothing is off).
    #[serde(default)]
    pub smoothed: Option<SmoothedRun>,
}

/// A filter's fixed-interval RTS-smoothed estimates at the evaluation instants.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SmoothedRun {
    /// Smoothed `(x, y)`.
    pub est: Vec<[f64; 2]>,
    /// 2D position error, m.
    pub err: Vec<f64>,
    /// Statistics of `err`.
    pub stats: RunStats,
    /// Smoothed `sqrt(P_xx + P_yy)`, m.
    pub pos_sigma: Vec<f64>,
    /// Steps of the forward pass (the backward pass's length).
    pub steps: usize,
    /// Bytes the forward pass holds per step
    /// ([`fathom_estimators::smoother::ForwardStep::BYTES`] for the filter's state size).
    pub bytes_per_step: usize,
}

/// What a method produced at the evaluation instants, before it is scored against
/// ground truth: shared by the Plaza replay ([`run_dead_reckoning`], [`run_variant`])
/// and the `range-beacon` replay of a CSV log, which may have no truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Estimated `(x, y)` at the evaluation instants, m.
    pub est: Vec<[f64; 2]>,
    /// Estimated heading at the evaluation instants, rad.
    pub heading: Vec<f64>,
    /// `sqrt(P_xx + P_yy)` at the evaluation instants, m.
    pub pos_sigma: Vec<f64>,
    /// Estimated range offset and scale error at the evaluation instants (0 when not
    /// estimated).
    pub calibration: Vec<[f64; 2]>,
    /// Dispositions of the ranges, summed over the channels (zero for dead reckoning).
    pub counts: ChannelCounts,
    /// Ranges applied with an inflated variance (Huber).
    pub downweighted: usize,
    /// Covariance inflations after runs of rejected or down-weighted ranges.
    pub recoveries: usize,
    /// Every range decision in processing order, with its innovation and NIS (empty
    /// for dead reckoning).
    pub decisions: Vec<Decision>,
    /// The RTS-smoothed estimates (`smooth = true`; `None` for dead reckoning).
    pub smoothed: Option<SmoothedRun>,
}

fn finish(
    name: String,
    variant: Option<Variant>,
    prep: &PreparedLog,
    est: Vec<[f64; 2]>,
    pos_sigma: Vec<f64>,
    calibration: Vec<[f64; 2]>,
) -> Result<MethodRun, SimError> {
    let err: Vec<f64> = est
        .iter()
        .zip(&prep.eval)
        .map(|(e, g)| (e[0] - g.1).hypot(e[1] - g.2))
        .collect();
    let stats = RunStats::of(&err)
        .map_err(|e| SimError::model(format!("error statistics of `{name}`"), e))?;
    Ok(MethodRun {
        name,
        variant,
        est,
        err,
        stats,
        pos_sigma,
        calibration,
        accepted: 0,
        rejected: 0,
        dropped: 0,
        non_finite: 0,
        downweighted: 0,
        recoveries: 0,
        decisions: Vec::new(),
        innovations: Vec::new(),
        smoothed: None,
    })
}

fn prior<const N: usize>(
    prep: &PreparedLog,
    s: &PlazaSettings,
    cal: Calibration,
) -> Result<Gaussian<N>, SimError> {
    let mut mean = SVector::<f64, N>::zeros();
    mean[0] = prep.start[0];
    mean[1] = prep.start[1];
    mean[2] = prep.start[2];
    let mut cov = SMatrix::<f64, N, N>::zeros();
    cov[(0, 0)] = s.position_sigma.powi(2);
    cov[(1, 1)] = s.position_sigma.powi(2);
    cov[(2, 2)] = s.heading_sigma.powi(2);
    if cal.states() >= 1 {
        cov[(3, 3)] = s.offset_prior_sigma.powi(2);
    }
    if cal.states() >= 2 {
        cov[(4, 4)] = s.scale_prior_sigma.powi(2);
    }
    Gaussian::new(mean, cov).map_err(SimError::from)
}

fn motion(s: &PlazaSettings, cal: Calibration) -> Result<WheelOdometry, SimError> {
    let rw = [s.offset_random_walk, s.scale_random_walk];
    WheelOdometryParams {
        calibration_random_walk: rw[..cal.states()].to_vec(),
        ..s.odometry.clone()
    }
    .check()
    .map_err(|e| SimError::model("odometry parameters", e))
}

/// Pure dead reckoning: the wheel-odometry prediction without any update.
///
/// # Errors
/// [`SimError::Model`] wrapping estimator errors.
pub fn run_dead_reckoning(prep: &PreparedLog, s: &PlazaSettings) -> Result<MethodRun, SimError> {
    let t = trace_dead_reckoning(prep, s)?;
    finish("DR".into(), None, prep, t.est, t.pos_sigma, t.calibration)
}

/// [`run_dead_reckoning`] before scoring: the trace at the evaluation instants.
///
/// # Errors
/// [`SimError::Model`] wrapping estimator errors.
pub fn trace_dead_reckoning(prep: &PreparedLog, s: &PlazaSettings) -> Result<Trace, SimError> {
    let ctx = |e| SimError::model("dead reckoning", e);
    let mut ekf = Ekf::<3, _>::new(
        prior::<3>(prep, s, Calibration::None)?,
        0.0,
        motion(s, Calibration::None)?,
        OdometryRate::default(),
    )
    .map_err(ctx)?;
    let mut est = Vec::with_capacity(prep.eval.len());
    let mut sig = Vec::with_capacity(prep.eval.len());
    let mut heading = Vec::with_capacity(prep.eval.len());
    for (t, kind) in prep.events(false) {
        ekf.predict_to(t).map_err(ctx)?;
        match kind {
            Kind::Input(k) => ekf.apply_input(&prep.inputs[k].1),
            Kind::Eval(_) => {
                let (x, p) = (ekf.state(), ekf.covariance());
                est.push([x[0], x[1]]);
                heading.push(x[2]);
                sig.push((p[(0, 0)] + p[(1, 1)]).sqrt());
            }
            Kind::Range(_) => {}
        }
    }
    let n = est.len();
    Ok(Trace {
        est,
        heading,
        pos_sigma: sig,
        calibration: vec![[0.0, 0.0]; n],
        counts: ChannelCounts::default(),
        downweighted: 0,
        recoveries: 0,
        decisions: Vec::new(),
        smoothed: None,
    })
}

fn run_filter<const N: usize>(
    prep: &PreparedLog,
    s: &PlazaSettings,
    v: &Variant,
) -> Result<Trace, SimError> {
    let ctx = |e| SimError::model(format!("filter `{}`", v.name), e);
    let cal = v.calibration;
    let ekf = Ekf::<N, _>::new(
        prior::<N>(prep, s, cal)?,
        0.0,
        motion(s, cal)?,
        OdometryRate::default(),
    )
    .map_err(ctx)?;
    let c = prep.beacons.len();
    let var = s.range_sigma.powi(2);
    let cov = s.correlation_sigma.powi(2);
    let channel_cov = DMatrix::from_fn(c, c, |i, j| if i == j { var + cov } else { cov });
    let gate_sigma = match v.outliers {
        OutlierHandling::Robust => s.reject_sigma,
        OutlierHandling::HardGate(g) => g,
    };
    let gate = GateThreshold::from_sigma_distance(gate_sigma).map_err(ctx)?;
    let config = SchemeParams {
        scheme: v.scheme,
        epoch_period: s.epoch,
        stale_tolerance: 0.0,
        channel_cov,
        gates: vec![Some(gate); c],
    }
    .check()
    .map_err(ctx)?;
    let mut filter = SchemeFilter::new(ekf, config);
    if v.outliers == OutlierHandling::Robust {
        let policy = RobustParams {
            huber_k: Some(s.huber_k),
            recovery: Some(RecoveryParams {
                after_rejections: s.recovery_after,
                inflation: s.recovery_inflation,
            }),
        }
        .check()
        .map_err(ctx)?;
        filter = filter.with_robust(policy);
    }
    if s.smooth {
        filter = filter.with_recording();
    }
    let (offset_state, scale_state) = match cal {
        Calibration::None => (None, None),
        Calibration::Offset => (Some(3), None),
        Calibration::Affine => (Some(3), Some(4)),
    };
    let mut est = Vec::with_capacity(prep.eval.len());
    let mut sig = Vec::with_capacity(prep.eval.len());
    let mut heading = Vec::with_capacity(prep.eval.len());
    let mut calib = Vec::with_capacity(prep.eval.len());
    let mut steps = Vec::new();
    let mut events = prep
        .events(true)
        .into_iter()
        .filter_map(|(t, kind)| match kind {
            Kind::Input(k) => Some(Event::Input {
                stamp: t,
                sample: prep.inputs[k].1,
            }),
            Kind::Range(k) => {
                let r = prep.ranges[k];
                Some(Event::Measurement(Observation {
                    channel: r.channel,
                    stamp: t,
                    value: r.value,
                    model: CalibratedRange {
                        beacon: prep.beacons[r.channel],
                        offset_state,
                        scale_state,
                    },
                    tag: r.index,
                }))
            }
            Kind::Eval(_) => None,
        })
        .peekable();
    filter.run_to_evaluations(
        &mut events,
        prep.eval.iter().map(|e| e.0),
        ctx,
        |_, _, f| {
            let (x, p) = (f.ekf().state(), f.ekf().covariance());
            est.push([x[0], x[1]]);
            heading.push(x[2]);
            sig.push((p[(0, 0)] + p[(1, 1)]).sqrt());
            calib.push([
                offset_state.map_or(0.0, |i| x[i]),
                scale_state.map_or(0.0, |i| x[i]),
            ]);
            if let Some(pass) = f.ekf().forward_pass() {
                steps.push(pass.last_index());
            }
            Ok(())
        },
    )?;
    // Ranges and inputs after the last ground-truth row are processed too (they count
    // in the decisions).
    for event in events {
        filter.process(event).map_err(ctx)?;
    }
    let smoothed = if s.smooth {
        Some(smoothed_run(&filter, &steps, prep)?)
    } else {
        None
    };
    Ok(Trace {
        est,
        heading,
        pos_sigma: sig,
        calibration: calib,
        counts: ChannelCounts::total(filter.counts()),
        downweighted: filter.downweighted(),
        recoveries: filter.recoveries(),
        decisions: filter.decisions().to_vec(),
        smoothed,
    })
}

/// The RTS smoother over `filter`'s recorded pass, read at the evaluation steps.
fn smoothed_run<const N: usize, M, S>(
    filter: &SchemeFilter<N, M, S>,
    steps: &[usize],
    prep: &PreparedLog,
) -> Result<SmoothedRun, SimError>
where
    M: fathom_estimators::ekf::MotionModel<N>,
    S: fathom_estimators::ekf::ScalarModel<N> + Clone,
{
    let ctx = |e| SimError::model("RTS smoother", e);
    let smoothed = filter.ekf().smooth().map_err(ctx)?;
    let mut est = Vec::with_capacity(steps.len());
    let mut pos_sigma = Vec::with_capacity(steps.len());
    for &i in steps {
        let s = &smoothed[i];
        est.push([s.mean[0], s.mean[1]]);
        pos_sigma.push((s.cov[(0, 0)] + s.cov[(1, 1)]).sqrt());
    }
    let err: Vec<f64> = est
        .iter()
        .zip(&prep.eval)
        .map(|(e, g)| (e[0] - g.1).hypot(e[1] - g.2))
        .collect();
    let stats = RunStats::of(&err).map_err(|e| SimError::model("smoothed error statistics", e))?;
    Ok(SmoothedRun {
        est,
        err,
        stats,
        pos_sigma,
        steps: smoothed.len(),
        bytes_per_step: fathom_estimators::smoother::ForwardStep::<N>::BYTES,
    })
}

/// Runs one variant.
///
/// # Errors
/// [`SimError::Model`] wrapping estimator errors.
pub fn run_variant(
    prep: &PreparedLog,
    s: &PlazaSettings,
    v: &Variant,
    n_log_ranges: usize,
) -> Result<MethodRun, SimError> {
    let t = trace_variant(prep, s, v)?;
    let mut run = finish(
        v.name.clone(),
        Some(v.clone()),
        prep,
        t.est,
        t.pos_sigma,
        t.calibration,
    )?;
    run.accepted = t.counts.accepted;
    run.rejected = t.counts.rejected;
    run.dropped = t.counts.stale + t.counts.superseded;
    run.non_finite = t.counts.non_finite;
    let mut decisions = vec![None; n_log_ranges];
    for d in &t.decisions {
        if let Some(slot) = decisions.get_mut(d.tag) {
            *slot = Some(d.disposition);
        }
    }
    run.decisions = decisions;
    run.innovations = t
        .decisions
        .iter()
        .filter_map(Innovation::of_decision)
        .collect();
    run.downweighted = t.downweighted;
    run.recoveries = t.recoveries;
    run.smoothed = t.smoothed;
    Ok(run)
}

/// [`run_variant`] before scoring: the trace at the evaluation instants and every
/// range decision.
///
/// # Errors
/// [`SimError::Model`] wrapping estimator errors.
pub fn trace_variant(
    prep: &PreparedLog,
    s: &PlazaSettings,
    v: &Variant,
) -> Result<Trace, SimError> {
    match v.calibration {
        Calibration::None => run_filter::<3>(prep, s, v),
        Calibration::Offset => run_filter::<4>(prep, s, v),
        Calibration::Affine => run_filter::<5>(prep, s, v),
    }
}

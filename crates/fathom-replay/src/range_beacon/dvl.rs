//! The DVL + heading path of the range-beacon replay: the 4-state EKF of
//! [`fathom_estimators::beacon_ekf`] (`x, y, z, psi`) dead-reckoning on the DVL body
//! velocity and the yaw rate formed from consecutive headings, corrected by 3D ranges
//! and depth under an update scheme, on relative time `t - t0`.
//!
//! Inputs: a DVL row stamped `t` is held from `t` on (the first row at or before the
//! start is the initial input). Consecutive headings `(t_a, psi_a)`, `(t_b, psi_b)`
//! give the yaw rate `wrap(psi_b - psi_a) / (t_b - t_a)` held over `(t_a, t_b]`, an
//! input stamped `t_a` (the first interval starts at the last heading at or before
//! the start, or at the start with `initial.csv`'s heading), as the Plaza replay
//! turns odometry increments into rates. With `[dvl] heading_sigma_rad`, each heading
//! row is also an absolute heading measurement (its own channel, wrapped residual).
//! Ties: inputs, then ranges, then depth and headings.
//! Process noise: each input's σ held for the median interval of its file
//! ([`fathom_estimators::beacon_ekf::DvlAhrsMotionParams`]).

use fathom_core::Gaussian;
use fathom_core::units::wrap_pi;
use fathom_estimators::{
    GateThreshold,
    beacon_ekf::{BeaconMeasurement, DvlAhrsInput, DvlAhrsMotionParams, DvlAhrsSample},
    ekf::Ekf,
    robust::{RecoveryParams, RobustParams},
    schemes::{ChannelCounts, Event, Observation, SchemeFilter, SchemeParams, UpdateScheme},
};
use nalgebra::{DMatrix, Matrix4, Vector3, Vector4};

use super::settings::{MethodKind, MethodSpec, RangeBeaconSettings};
use super::{EvalPlan, MethodTrace};
use crate::plaza::{Calibration, OutlierHandling};
use fathom_data::layout::range_beacon::{Motion, RangeBeaconLog};
use fathom_sim::SimError;

type Ev = Event<DvlAhrsSample, BeaconMeasurement>;

/// Median of the positive differences of consecutive stamps, s.
fn median_interval(times: impl Iterator<Item = f64>) -> Option<f64> {
    let t: Vec<f64> = times.collect();
    let mut d: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    if d.is_empty() {
        return None;
    }
    d.sort_by(f64::total_cmp);
    Some(d[d.len() / 2])
}

/// The inputs, ranges and depth as events on relative time, sorted (module docs),
/// and the initial input.
fn events(
    log: &RangeBeaconLog,
    with_measurements: bool,
    absolute_heading: bool,
) -> (Vec<Ev>, DvlAhrsInput) {
    let Motion::Dvl { dvl, heading } = &log.motion else {
        return (Vec::new(), DvlAhrsInput::default());
    };
    let t0 = log.start.time;
    let mut initial = DvlAhrsInput::default();
    let mut ev: Vec<(f64, u8, Ev)> = Vec::new();
    for (t, v) in dvl {
        let vel = Vector3::from(*v);
        if *t <= t0 {
            initial.vel_in_body = vel;
        } else {
            ev.push((
                t - t0,
                0,
                Event::Input {
                    stamp: t - t0,
                    sample: DvlAhrsSample::Velocity(vel),
                },
            ));
        }
    }
    let mut prev = (t0, log.start.heading);
    for &(t, psi) in heading {
        if t <= t0 {
            prev = (t, psi);
            continue;
        }
        let rate = wrap_pi(psi - prev.1) / (t - prev.0);
        let stamp = (prev.0 - t0).max(0.0);
        if stamp == 0.0 {
            initial.yaw_rate = rate;
        } else {
            ev.push((
                stamp,
                0,
                Event::Input {
                    stamp,
                    sample: DvlAhrsSample::YawRate(rate),
                },
            ));
        }
        prev = (t, psi);
    }
    if with_measurements {
        let k = log.beacons.len();
        for (tag, r) in log.ranges.iter().enumerate() {
            if r.time <= t0 {
                continue;
            }
            let b = log.beacons[r.beacon].pos_in_nav;
            ev.push((
                r.time - t0,
                1,
                Event::Measurement(Observation {
                    channel: r.beacon,
                    stamp: r.time - t0,
                    value: r.range,
                    model: BeaconMeasurement::Range {
                        beacon_in_nav: Vector3::from(b),
                    },
                    tag,
                }),
            ));
        }
        for (tag, &(t, d)) in log.depth.iter().flatten().enumerate() {
            if t <= t0 {
                continue;
            }
            ev.push((
                t - t0,
                2,
                Event::Measurement(Observation {
                    channel: k,
                    stamp: t - t0,
                    value: d,
                    model: BeaconMeasurement::Depth,
                    tag,
                }),
            ));
        }
    }
    if with_measurements && absolute_heading {
        let channel = log.beacons.len() + 1;
        for (tag, &(t, psi)) in heading.iter().enumerate() {
            if t <= t0 {
                continue;
            }
            ev.push((
                t - t0,
                2,
                Event::Measurement(Observation {
                    channel,
                    stamp: t - t0,
                    value: psi,
                    model: BeaconMeasurement::Heading,
                    tag,
                }),
            ));
        }
    }
    ev.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    (ev.into_iter().map(|e| e.2).collect(), initial)
}

/// The motion noise of a DVL + heading log: the settings' sigmas held over the median
/// interval of each file.
///
/// # Errors
/// [`SimError::InvalidArgument`] for an odometry log, or too few DVL / heading rows to
/// know their interval.
fn motion_params(
    log: &RangeBeaconLog,
    s: &RangeBeaconSettings,
) -> Result<DvlAhrsMotionParams, SimError> {
    let Motion::Dvl { dvl, heading } = &log.motion else {
        return Err(SimError::invalid_argument(
            "DVL replay",
            "the log's motion is odometry",
        ));
    };
    let hold = |what: &str, times: Vec<f64>| {
        median_interval(times.into_iter()).ok_or_else(|| {
            SimError::invalid_argument(
                format!("log `{what}`"),
                "needs at least two rows with different times (their interval is the hold time of the motion noise)",
            )
        })
    };
    Ok(DvlAhrsMotionParams {
        vel_sigma: s.dvl_velocity_sigma,
        vel_hold: hold("dvl.csv", dvl.iter().map(|r| r.0).collect())?,
        yaw_rate_sigma: s.yaw_rate_sigma,
        yaw_rate_hold: hold("heading.csv", heading.iter().map(|r| r.0).collect())?,
    })
}

/// What [`run_method`] refuses before it runs: a DVL + heading log with too few rows
/// to know the motion noise's hold times, or a method asking for range calibration
/// states, which the 3D EKF does not have.
///
/// # Errors
/// [`SimError::InvalidArgument`] naming the file or the method.
pub fn check_method(
    log: &RangeBeaconLog,
    s: &RangeBeaconSettings,
    method: &MethodSpec,
) -> Result<(), SimError> {
    motion_params(log, s)?;
    match &method.kind {
        MethodKind::Ekf(v) if v.calibration != Calibration::None => {
            Err(SimError::invalid_argument(
                format!("method `{}`", method.name),
                format!(
                    "calibration = \"{}\" needs an odometry log: the DVL + heading EKF has no \
                     range calibration states; use calibration = \"none\"",
                    v.calibration.name()
                ),
            ))
        }
        _ => Ok(()),
    }
}

/// Runs `method` on a DVL + heading log, recording at `plan`'s instants.
///
/// # Errors
/// As [`check_method`]; [`SimError::Model`] wrapping estimator errors with the
/// method's name.
pub fn run_method(
    log: &RangeBeaconLog,
    s: &RangeBeaconSettings,
    method: &MethodSpec,
    plan: &EvalPlan,
) -> Result<MethodTrace, SimError> {
    check_method(log, s, method)?;
    let params = motion_params(log, s)?;
    let e = &s.engine;
    let ctx = |e| SimError::model(format!("method `{}`", method.name), e);
    let motion = params.check().map_err(ctx)?;
    let (scheme, gate_sigma, robust) = match &method.kind {
        MethodKind::DeadReckoning => (UpdateScheme::Asynchronous, None, false),
        MethodKind::Ekf(v) => match v.outliers {
            OutlierHandling::Robust => (v.scheme, Some(e.reject_sigma), true),
            OutlierHandling::HardGate(g) => (v.scheme, Some(g), false),
        },
    };
    let st = &log.start;
    let x0 = Vector4::new(
        st.north_east[0],
        st.north_east[1],
        st.down.unwrap_or(0.0),
        wrap_pi(st.heading),
    );
    let pp = e.position_sigma.powi(2);
    let p0 = Matrix4::from_diagonal(&Vector4::new(pp, pp, pp, e.heading_sigma.powi(2)));
    let prior = Gaussian::new(x0, p0).map_err(|e| SimError::model("EKF prior", e))?;
    let with_measurements = !matches!(method.kind, MethodKind::DeadReckoning);
    let (ev, initial) = events(log, with_measurements, s.heading_sigma.is_some());
    let ekf = Ekf::new(prior, 0.0, motion, initial).map_err(ctx)?;
    let k = log.beacons.len();
    let var = e.range_sigma.powi(2);
    let cov = e.correlation_sigma.powi(2);
    let d2 = s.depth_sigma.powi(2);
    // Channels: the k beacons (correlated), depth, and the absolute heading if used
    // (both independent of the rest).
    let h2 = s.heading_sigma.map(|v| v * v);
    let channels = k + 1 + usize::from(h2.is_some());
    let channel_cov = DMatrix::from_fn(channels, channels, |i, j| match (i, j) {
        _ if i >= k || j >= k => {
            if i != j {
                0.0
            } else if i == k {
                d2
            } else {
                h2.unwrap_or(0.0)
            }
        }
        _ if i == j => var + cov,
        _ => cov,
    });
    let gate = gate_sigma
        .map(|g| GateThreshold::from_sigma_distance(g).map_err(ctx))
        .transpose()?;
    let mut gates = vec![gate; k];
    gates.resize(channels, None);
    let config = SchemeParams {
        scheme,
        epoch_period: e.epoch,
        stale_tolerance: 0.0,
        channel_cov,
        gates,
    }
    .check()
    .map_err(ctx)?;
    let mut filter = SchemeFilter::new(ekf, config);
    if robust {
        let policy = RobustParams {
            huber_k: Some(e.huber_k),
            recovery: Some(RecoveryParams {
                after_rejections: e.recovery_after,
                inflation: e.recovery_inflation,
            }),
        }
        .check()
        .map_err(ctx)?;
        filter = filter.with_robust(policy);
    }
    let n = plan.times.len();
    let mut trace = MethodTrace::with_capacity(n, true);
    let mut events = ev.into_iter().peekable();
    filter.run_to_evaluations(&mut events, plan.times.iter().copied(), ctx, |_, _, f| {
        let (x, p) = (f.ekf().state(), f.ekf().covariance());
        trace.est.push([x[0], x[1]]);
        if let Some(d) = trace.down.as_mut() {
            d.push(x[2]);
        }
        trace.heading.push(x[3]);
        trace.pos_sigma.push((p[(0, 0)] + p[(1, 1)]).sqrt());
        trace.calibration.push([0.0, 0.0]);
        Ok(())
    })?;
    for event in events {
        filter.process(event).map_err(ctx)?;
    }
    let counts = filter.counts();
    trace.counts = ChannelCounts::total(&counts[..k]);
    trace.depth_counts = Some(counts[k]);
    trace.downweighted = filter.downweighted();
    trace.recoveries = filter.recoveries();
    trace.set_decisions(filter.decisions(), k);
    Ok(trace)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_interval_ignores_repeats() {
        assert_eq!(
            median_interval([0.0, 0.1, 0.2, 0.2, 0.5].into_iter()),
            Some(0.1)
        );
        assert_eq!(median_interval([1.0].into_iter()), None);
    }
}

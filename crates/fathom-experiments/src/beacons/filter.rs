//! The `beacons` filter glue: the EKF set up from a sensor suite's configuration, the
//! event stream of one run's data, and one update scheme run over it against the
//! truth. Public so that the end-to-end consistency test (NEES) runs exactly the code
//! of the experiment.

use std::collections::HashSet;

use fathom_core::Gaussian;
use fathom_estimators::{
    GateThreshold,
    beacon_ekf::{
        BeaconMeasurement, DvlAhrsInput, DvlAhrsMotion, DvlAhrsMotionParams, DvlAhrsSample,
    },
    ekf::{Ekf, MotionModel},
    schemes::{
        ChannelCounts, Disposition, Event, Observation, SchemeFilter, SchemeParams, UpdateScheme,
    },
};
use fathom_sensors::{BeaconSuiteConfig, BeaconSuiteData, Timing, design_covariance};
use fathom_traj::{
    Trajectory,
    velocity_command::{VelocityCommandMotion, VelocityCommandParams},
};
use nalgebra::{DMatrix, Matrix4, Vector3, Vector4};
use rand::Rng;
use rand_distr::StandardNormal;

use fathom_sim::SimError;

/// Filter settings (checked form of `[ekf]`).
#[derive(Debug, Clone, PartialEq)]
pub struct EkfSettings {
    /// SC/SI epoch period (also the evaluation period), s.
    pub epoch_period: f64,
    /// Gate distance `d`.
    pub gate_sigma: f64,
    /// AS stale tolerance, s.
    pub stale_tolerance: f64,
    /// Initial position sigma, m.
    pub init_pos_sigma: f64,
    /// Initial heading sigma, rad.
    pub init_yaw_sigma: f64,
    /// Input error = sensor noise (+ motion noise when true).
    pub include_motion_noise: bool,
    /// Factor on the process-noise sigmas (1 = as designed).
    pub process_noise_scale: f64,
    /// Record the forward pass and smooth it (RTS) after the run
    /// ([`SchemeRun::smoothed`]).
    pub smooth: bool,
}

impl Default for EkfSettings {
    fn default() -> Self {
        Self {
            epoch_period: 0.1,
            gate_sigma: 2.5,
            stale_tolerance: 0.0,
            init_pos_sigma: 0.1,
            init_yaw_sigma: 0.05,
            include_motion_noise: true,
            process_noise_scale: 1.0,
            smooth: false,
        }
    }
}

/// Everything the filter needs besides the data: built from the sensor suite's
/// configuration (the filter knows the sensor noise levels, the beacons and the
/// timing, nothing else).
#[derive(Debug, Clone, PartialEq)]
pub struct FilterSetup {
    pub(super) beacons: Vec<Vector3<f64>>,
    motion: DvlAhrsMotion,
    params: DvlAhrsMotionParams,
    pub(super) channel_cov: DMatrix<f64>,
    pub(super) gate: GateThreshold,
    pub(super) settings: EkfSettings,
    p0: Matrix4<f64>,
    initial_input: DvlAhrsInput,
}

impl FilterSetup {
    /// The filter for data from `suite`, on the motion `motion` (its command is the
    /// input held before the first DVL/AHRS sample; its per-step noise enters the
    /// process noise when `settings.include_motion_noise`).
    ///
    /// Process noise: per input, `sigma = scale * sqrt(sigma_sensor^2 + sigma_motion^2)`
    /// held for the sensor period (see [`fathom_estimators::beacon_ekf`]). `R`: the
    /// design covariance of `[range1..K, depth]` ([`design_covariance`]).
    ///
    /// # Errors
    /// [`SimError::Model`] for invalid settings (non-positive periods, gate, sigmas).
    pub fn new(
        settings: &EkfSettings,
        suite: &BeaconSuiteConfig,
        motion: &VelocityCommandParams,
    ) -> Result<Self, SimError> {
        let sp = suite.params();
        let gain = if sp.switches.gaussian { 1.0 } else { 0.0 };
        let m = if settings.include_motion_noise {
            1.0
        } else {
            0.0
        };
        let s = settings.process_noise_scale;
        let sig = |k: usize| {
            s * ((gain * sp.velocity_sigma[k]).powi(2) + (m * motion.motion_sigma[k]).powi(2))
                .sqrt()
        };
        let (vel_hold, yaw_rate_hold) = match sp.timing {
            Timing::Synchronous { period } => (period, period),
            Timing::Asynchronous { dvl, ahrs, .. } => (dvl, ahrs),
        };
        let params = DvlAhrsMotionParams {
            vel_sigma: [sig(0), sig(1), sig(2)],
            vel_hold,
            yaw_rate_sigma: sig(5),
            yaw_rate_hold,
        };
        let motion_model = params
            .check()
            .map_err(|e| SimError::model("EKF motion model", e))?;
        let gate = GateThreshold::from_sigma_distance(settings.gate_sigma)
            .map_err(|e| SimError::model("EKF gate", e))?;
        for (what, v) in [
            ("EKF init_pos_sigma", settings.init_pos_sigma),
            ("EKF init_yaw_sigma", settings.init_yaw_sigma),
            ("EKF epoch_period", settings.epoch_period),
        ] {
            fathom_core::error::ensure_positive(what, v)
                .map_err(|e| SimError::model("EKF settings", e))?;
        }
        let (pp, py) = (
            settings.init_pos_sigma.powi(2),
            settings.init_yaw_sigma.powi(2),
        );
        Ok(Self {
            beacons: sp.beacons_in_nav.clone(),
            motion: motion_model,
            params,
            channel_cov: design_covariance(suite),
            gate,
            settings: settings.clone(),
            p0: Matrix4::from_diagonal(&Vector4::new(pp, pp, pp, py)),
            initial_input: DvlAhrsInput {
                vel_in_body: Vector3::new(motion.command[0], motion.command[1], motion.command[2]),
                yaw_rate: motion.command[5],
            },
        })
    }

    /// The process-noise parameters the filter uses.
    pub fn motion_params(&self) -> &DvlAhrsMotionParams {
        &self.params
    }

    /// Draws an initial estimation error `~ N(0, P0)` (4 standard normals).
    pub fn draw_initial_error(&self, rng: &mut impl Rng) -> Vector4<f64> {
        Vector4::from_fn(|i, _| {
            let n: f64 = rng.sample(StandardNormal);
            n * self.p0[(i, i)].sqrt()
        })
    }
}

/// The result of one scheme on one run's data.
#[derive(Debug, Clone, PartialEq)]
pub struct SchemeRun {
    /// Evaluation instants, s.
    pub times: Vec<f64>,
    /// 3D position error at each instant, m.
    pub errors_3d: Vec<f64>,
    /// NEES of the full state `(x, y, z, psi)` at each instant (4 dof).
    pub nees: Vec<f64>,
    /// State estimates at each instant.
    pub estimates: Vec<Vector4<f64>>,
    /// Dispositions per channel (`range1..K`, depth); non-finite samples are
    /// dropped and counted in [`ChannelCounts::non_finite`] (the scheme filter's
    /// bad-data policy).
    pub counts: Vec<ChannelCounts>,
    /// DVL / AHRS samples dropped because a component or the stamp is not finite.
    pub non_finite_inputs: usize,
    /// Injected outliers.
    pub outliers_injected: usize,
    /// Injected outliers rejected by the gate.
    pub outliers_rejected: usize,
    /// Injected outliers that passed the gate and were applied.
    pub outliers_accepted: usize,
    /// Injected outliers never tested by the gate (superseded within an epoch, stale,
    /// or stamped after the end of the evaluation).
    pub outliers_untested: usize,
    /// Clean range samples rejected by the gate.
    pub false_rejections: usize,
    /// The RTS-smoothed errors at the same instants (`settings.smooth`).
    pub smoothed: Option<SmoothedErrors>,
}

/// The fixed-interval RTS-smoothed estimates of a scheme run at its evaluation instants.
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothedErrors {
    /// 3D position error, m.
    pub errors_3d: Vec<f64>,
    /// NEES of the smoothed state against the smoothed covariance (4 dof).
    pub nees: Vec<f64>,
    /// Steps of the forward pass.
    pub steps: usize,
}

/// Builds the time-ordered event stream of one run's data: DVL velocity and AHRS yaw
/// rate as inputs, ranges (channels `0..K`, tag = sample index) and depth (channel
/// `K`) as measurements; stable-sorted by stamp (ties: DVL, AHRS, ranges, depth).
pub fn events(
    data: &BeaconSuiteData,
    beacons: &[Vector3<f64>],
) -> Vec<Event<DvlAhrsSample, BeaconMeasurement>> {
    let k = data.ranges.len();
    let mut ev = Vec::new();
    for m in &data.dvl {
        ev.push(Event::Input {
            stamp: m.stamp,
            sample: DvlAhrsSample::Velocity(m.value),
        });
    }
    for m in &data.ahrs_rate {
        ev.push(Event::Input {
            stamp: m.stamp,
            sample: DvlAhrsSample::YawRate(m.value.z),
        });
    }
    for (b, list) in data.ranges.iter().enumerate() {
        for (i, m) in list.iter().enumerate() {
            ev.push(Event::Measurement(Observation {
                channel: b,
                stamp: m.stamp,
                value: m.value,
                model: BeaconMeasurement::Range {
                    beacon_in_nav: beacons[b],
                },
                tag: i,
            }));
        }
    }
    for (i, m) in data.depth.iter().enumerate() {
        ev.push(Event::Measurement(Observation {
            channel: k,
            stamp: m.stamp,
            value: m.value,
            model: BeaconMeasurement::Depth,
            tag: i,
        }));
    }
    let stamp = |e: &Event<DvlAhrsSample, BeaconMeasurement>| match e {
        Event::Input { stamp, .. } => *stamp,
        Event::Measurement(o) => o.stamp,
    };
    ev.sort_by(|a, b| stamp(a).total_cmp(&stamp(b)));
    ev
}

/// Runs `scheme` over one run's data and evaluates it against the truth every
/// epoch period (see the module docs). The filter starts at the truth's start time
/// from `truth + initial_error` with covariance `P0`.
///
/// Non-finite samples in `data` (value or stamp) are dropped and counted
/// ([`SchemeRun::counts`], [`SchemeRun::non_finite_inputs`]), never applied.
///
/// # Errors
/// [`SimError::Model`] wrapping filter, trajectory or statistics errors; a filter
/// error (e.g. a covariance that stops being positive definite) names the scheme and
/// carries the filter time of the failing step.
pub fn run_scheme(
    truth: &VelocityCommandMotion,
    data: &BeaconSuiteData,
    setup: &FilterSetup,
    scheme: UpdateScheme,
    initial_error: &Vector4<f64>,
) -> Result<SchemeRun, SimError> {
    let ev = events(data, &setup.beacons);
    run_scheme_on(truth, data, &ev, setup, scheme, initial_error)
}

/// [`run_scheme`] on a prebuilt event stream (`events(data, ..)`), shared by schemes.
pub(super) fn run_scheme_on(
    truth: &VelocityCommandMotion,
    data: &BeaconSuiteData,
    ev: &[Event<DvlAhrsSample, BeaconMeasurement>],
    setup: &FilterSetup,
    scheme: UpdateScheme,
    initial_error: &Vector4<f64>,
) -> Result<SchemeRun, SimError> {
    let k = data.ranges.len();
    if setup.beacons.len() != k || setup.channel_cov.nrows() != k + 1 {
        return Err(SimError::invalid_argument(
            "beacons filter setup",
            format!("set up for {} beacons, data have {k}", setup.beacons.len()),
        ));
    }
    let t0 = truth.start_time();
    let s0 = truth
        .state_at(t0)
        .map_err(|e| SimError::model("truth", e))?;
    let x_true0 = Vector4::new(
        s0.pos_in_nav.x,
        s0.pos_in_nav.y,
        s0.pos_in_nav.z,
        s0.attitude.yaw,
    );
    let mut x0 = x_true0 + initial_error;
    setup.motion.normalize(&mut x0);
    let prior = Gaussian::new(x0, setup.p0).map_err(|e| SimError::model("EKF prior", e))?;
    let ekf = Ekf::new(prior, t0, setup.motion, setup.initial_input)
        .map_err(|e| SimError::model("EKF", e))?;
    let mut gates = vec![Some(setup.gate); k];
    gates.push(None);
    let config = SchemeParams {
        scheme,
        epoch_period: setup.settings.epoch_period,
        stale_tolerance: setup.settings.stale_tolerance,
        channel_cov: setup.channel_cov.clone(),
        gates,
    }
    .check()
    .map_err(|e| SimError::model("update scheme", e))?;
    let mut filter = SchemeFilter::new(ekf, config);
    if setup.settings.smooth {
        filter = filter.with_recording();
    }
    // Per evaluation instant: the forward-pass step and the true state.
    let mut steps: Vec<(usize, Vector4<f64>)> = Vec::new();

    let n_eval = ((truth.end_time() - t0) / setup.settings.epoch_period + 1e-9).floor() as usize;
    let mut out = SchemeRun {
        times: Vec::with_capacity(n_eval),
        errors_3d: Vec::with_capacity(n_eval),
        nees: Vec::with_capacity(n_eval),
        estimates: Vec::with_capacity(n_eval),
        counts: Vec::new(),
        non_finite_inputs: 0,
        outliers_injected: data.outliers.len(),
        outliers_rejected: 0,
        outliers_accepted: 0,
        outliers_untested: 0,
        false_rejections: 0,
        smoothed: None,
    };
    let fail = |e| SimError::model(format!("{} filter", scheme.short_name()), e);
    let period = setup.settings.epoch_period;
    let mut events = ev.iter().cloned().peekable();
    filter.run_to_evaluations(
        &mut events,
        (1..=n_eval).map(|j| t0 + j as f64 * period),
        fail,
        |_, t, filter| {
            let st = truth.state_at(t).map_err(|e| SimError::model("truth", e))?;
            let x_true = Vector4::new(
                st.pos_in_nav.x,
                st.pos_in_nav.y,
                st.pos_in_nav.z,
                st.attitude.yaw,
            );
            let x = *filter.ekf().state();
            let err = setup.motion.difference(&x, &x_true);
            out.times.push(t);
            out.errors_3d.push(err.xyz().norm());
            out.nees
                .push(fathom_stats::nees(&err, filter.ekf().covariance())?);
            out.estimates.push(x);
            if let Some(pass) = filter.ekf().forward_pass() {
                steps.push((pass.last_index(), x_true));
            }
            Ok(())
        },
    )?;
    if setup.settings.smooth {
        let smoothed = filter.ekf().smooth().map_err(fail)?;
        let mut s = SmoothedErrors {
            errors_3d: Vec::with_capacity(steps.len()),
            nees: Vec::with_capacity(steps.len()),
            steps: smoothed.len(),
        };
        for (i, x_true) in &steps {
            let st = &smoothed[*i];
            let err = setup.motion.difference(&st.mean, x_true);
            s.errors_3d.push(err.xyz().norm());
            s.nees.push(fathom_stats::nees(&err, &st.cov)?);
        }
        out.smoothed = Some(s);
    }
    let injected: HashSet<(usize, usize)> =
        data.outliers.iter().map(|o| (o.beacon, o.sample)).collect();
    for d in filter.decisions() {
        if d.channel >= k {
            continue;
        }
        let is_outlier = injected.contains(&(d.channel, d.tag));
        match (d.disposition, is_outlier) {
            (Disposition::Rejected, true) => out.outliers_rejected += 1,
            (Disposition::Rejected, false) => out.false_rejections += 1,
            (Disposition::Accepted, true) => out.outliers_accepted += 1,
            _ => {}
        }
    }
    // Superseded, stale, or stamped after the last evaluation instant (never fed).
    out.outliers_untested = out.outliers_injected - out.outliers_rejected - out.outliers_accepted;
    out.counts = filter.counts().to_vec();
    out.non_finite_inputs = filter.non_finite_inputs();
    Ok(out)
}

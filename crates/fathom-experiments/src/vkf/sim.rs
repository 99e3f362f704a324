//! One Monte Carlo run of the `vkf` experiment: truth and error-free IMU increments
//! (shared by all runs), sensor simulation, and the five navigation methods side by
//! side on the same IMU and sensor data.

use fathom_estimators::error_state::{self as es, ErrorStateFilter};
use fathom_estimators::integrated_nav::IntegratedNavFilter;
use fathom_estimators::velocity_filter::{VelocityFilter, VelocitySource};
use fathom_ins::earth::{Geodetic, curvilinear_offset};
use fathom_ins::error_model::{
    self as em, BiasModel, Discretization, ImuErrorModel, ImuErrorParams, NavError,
};
use fathom_ins::{ImuIncrement, InsState, Strapdown, TruthSample, VerticalChannel, imu_from_truth};
use fathom_sensors::noise::gauss;
use fathom_sensors::underwater::BottomLockDvlModel;
use nalgebra::{Matrix3, Vector3};
use rand_chacha::ChaCha8Rng;

use super::scenario::Checked;
use fathom_sim::SimError;

pub use super::scenario::{ESKF, GATED, INS_DVL, METHODS, PINS, VKF};

/// Everything that does not depend on the run: truth at the IMU rate, the error-free
/// IMU increments, the "flat" true position (true NED velocity integrated like the
/// 9-state filter integrates its own), true altitude and forward speed, and the
/// intervals without bottom lock.
#[derive(Debug, Clone)]
pub struct Shared {
    pub truth: Vec<TruthSample>,
    pub increments: Vec<ImuIncrement>,
    pub true_flat: Vec<Vector3<f64>>,
    pub altitude: Vec<f64>,
    pub forward_speed: Vec<f64>,
    /// `(start, end)` of each interval where the true altitude exceeds the DVL range, s.
    pub invalid: Vec<(f64, f64)>,
}

/// Builds the shared truth (once for all runs and configurations).
///
/// # Errors
/// [`SimError::Model`] from the route, the IMU inversion or the seabed profile.
pub fn build_shared(c: &Checked) -> Result<Shared, SimError> {
    let truth = c
        .route
        .sample(c.dt, c.n_steps + 1, 4)
        .map_err(|e| SimError::model("vkf route", e))?;
    let increments = imu_from_truth(&truth).map_err(|e| SimError::model("IMU from truth", e))?;
    let mut true_flat = Vec::with_capacity(truth.len());
    let mut p = Vector3::new(0.0, 0.0, -truth[0].h);
    true_flat.push(p);
    for w in truth.windows(2) {
        p += (w[0].vel_in_nav + w[1].vel_in_nav) * (0.5 * (w[1].time - w[0].time));
        true_flat.push(p);
    }
    let mut altitude = Vec::with_capacity(truth.len());
    let mut forward_speed = Vec::with_capacity(truth.len());
    for s in &truth {
        altitude.push(
            c.seabed
                .altitude_at(s.time, -s.h)
                .map_err(|e| SimError::model("seabed", e))?,
        );
        forward_speed.push((s.nav_from_body.inverse() * s.vel_in_nav).x);
    }
    let range = c.dvl.params().range;
    let mut invalid = Vec::new();
    let mut start = None;
    for (k, a) in altitude.iter().enumerate() {
        let t = truth[k].time;
        match (start, *a > range) {
            (None, true) => start = Some(t),
            (Some(t0), false) => {
                invalid.push((t0, t));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(t0) = start {
        invalid.push((t0, truth[truth.len() - 1].time));
    }
    Ok(Shared {
        truth,
        increments,
        true_flat,
        altitude,
        forward_speed,
        invalid,
    })
}

/// Run-0 series for the figures.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Detail {
    // 1 Hz
    pub t1: Vec<f64>,
    /// North/east of the truth (flat frame) and of each method, m.
    pub ne: [Vec<(f64, f64)>; 6],
    pub truth_euler_deg: [Vec<f64>; 3],
    pub pins_euler_deg: [Vec<f64>; 3],
    pub gyro_deg_s: [Vec<f64>; 3],
    pub accel_mps2: [Vec<f64>; 3],
    // Sensor epochs
    pub t5: Vec<f64>,
    pub alt_true: Vec<f64>,
    pub alt_meas: Vec<f64>,
    pub rpm: Vec<f64>,
    pub dvl_ne: [Vec<f64>; 2],
    pub rpm_ne: [Vec<f64>; 2],
    pub true_ne: [Vec<f64>; 2],
    pub dvl_fwd: Vec<f64>,
    pub rpm_fwd: Vec<f64>,
    pub sf: Vec<f64>,
    pub b: Vec<f64>,
    pub sf_sigma: Vec<f64>,
    pub b_sigma: Vec<f64>,
    pub vkf_source_rpm: Vec<f64>,
}

/// Per-run results.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RunOutput {
    /// Horizontal position error per method at 1 Hz, m.
    pub err_h: [Vec<f64>; 5],
    /// Horizontal velocity error per method at 1 Hz, m/s.
    pub err_v: [Vec<f64>; 5],
    /// VKF `sf - k_true` at the start of each invalid interval.
    pub sf_error: Vec<f64>,
    /// VKF `b - b_true` at the start of each invalid interval, m/s.
    pub bias_error: Vec<f64>,
    /// The run's DVL scale factor and forward-axis-free bias magnitude (for the report).
    pub dvl_scale_factor: f64,
    /// Fraction of sensor epochs in invalid intervals that `INS-DVL-gated` rejected.
    pub gated_rejected_invalid: f64,
    /// Fraction of valid-DVL epochs that `INS-DVL-gated` rejected.
    pub gated_rejected_valid: f64,
    /// Figure series (run 0 only).
    pub detail: Option<Box<Detail>>,
    /// The RTS-smoothed horizontal errors at 1 Hz (`smooth = true`, main batch).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smoothed: Option<SmoothedErrors>,
}

/// Horizontal position errors of the RTS-smoothed filters at the 1 Hz instants, m.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SmoothedErrors {
    /// The VKF-aided 9-state filter.
    pub vkf: Vec<f64>,
    /// The 15-state ESKF (smoothed error applied to the nominal trajectory).
    pub eskf: Vec<f64>,
    /// Steps of the ESKF's forward pass.
    pub eskf_steps: usize,
    /// Steps of the 9-state filter's forward pass.
    pub nav_steps: usize,
}

fn model_err<E: std::error::Error + Send + Sync + 'static>(
    what: &'static str,
) -> impl Fn(E) -> SimError {
    move |e| SimError::model(what, e)
}

/// The INS error model the ESKF assumes: the IMU's white noises, and bias random
/// walks with the bias-instability driving noise.
fn eskf_error_model(c: &Checked) -> Result<ImuErrorModel, SimError> {
    let s = &c.imu;
    ImuErrorParams {
        accel_vrw: s.accel_vrw,
        gyro_arw: s.gyro_arw,
        accel_bias: BiasModel::RandomWalk {
            sigma_rate: s.accel_bias_instability * (2.0 / s.accel_bias_tau).sqrt(),
        },
        gyro_bias: BiasModel::RandomWalk {
            sigma_rate: s.gyro_bias_instability * (2.0 / s.gyro_bias_tau).sqrt(),
        },
    }
    .check()
    .map_err(model_err("ESKF error model"))
}

fn horizontal_offset(from: &Geodetic, to: &Geodetic) -> Vector3<f64> {
    curvilinear_offset(from, to)
}

/// One run. The RNG draws, in order: IMU errors, DVL constants, then per IMU step
/// the IMU noise and per sensor epoch DVL, echo sounder, RPM and depth noise; so two
/// DVL configurations with the same stream see the same noise.
///
/// # Errors
/// [`SimError::Model`] naming the failing component and, through the filter's error
/// or the context, the time stamp (the caller adds the run index).
pub fn one_run(
    c: &Checked,
    sh: &Shared,
    dvl_model: &BottomLockDvlModel,
    rng: &mut ChaCha8Rng,
    keep_detail: bool,
    smooth: bool,
) -> Result<RunOutput, SimError> {
    let mut imu = c.imu.draw(rng);
    let dvl = dvl_model.draw(rng).map_err(model_err("DVL"))?;
    let truth0 = &sh.truth[0];
    let start = truth0.position();
    let t0 = truth0.time;

    // PINS (vertical channel held at the start depth; horizontal compared).
    let mut pins = Strapdown::new(truth0.to_ins_state())
        .and_then(|s| s.with_vertical_channel(VerticalChannel::Hold { h: truth0.h }))
        .map_err(model_err("PINS"))?;

    // The three 9-state filters (same INS input, different velocity aiding).
    let pos0 = Vector3::new(0.0, 0.0, -truth0.h);
    let mut nav: Vec<IntegratedNavFilter> = (0..3)
        .map(|_| IntegratedNavFilter::new(&c.nav, &pos0, &truth0.vel_in_nav, t0))
        .collect::<Result<_, _>>()
        .map_err(model_err("9-state filter"))?;
    let nav_method = [INS_DVL, VKF, GATED];

    // VKF (shared by the VKF method and the ESKF's switching box).
    let mut vkf = VelocityFilter::new(&c.vkf, t0).map_err(model_err("VKF"))?;

    // ESKF.
    let eskf_model = eskf_error_model(c)?;
    let q_c = eskf_model.noise_psd();
    let s = &c.imu;
    let mut eskf = ErrorStateFilter::new(
        &ErrorStateFilter::diagonal_covariance([
            c.nav.params().sigma0[0],
            c.nav.params().sigma0[1],
            c.eskf_sigma0_att,
            s.accel_bias.hypot(s.accel_bias_instability),
            s.gyro_bias.hypot(s.gyro_bias_instability),
        ]),
        t0,
    )
    .map_err(model_err("ESKF"))?;
    let mut eskf_ins = Strapdown::new(truth0.to_ins_state()).map_err(model_err("ESKF INS"))?;
    // Smoothing: per 1 Hz instant, the forward-pass steps of the VKF-aided filter and
    // the ESKF, the ESKF's corrected nominal state and the true position.
    let mut marks: Vec<(usize, usize, InsState, Geodetic, Vector3<f64>)> = Vec::new();
    if smooth {
        nav[1].start_recording();
        eskf.start_recording();
    }
    // The ESKF is the costly method: skipped when not selected (it draws nothing, so
    // the other methods' results do not change).
    let run_eskf = c.selected(ESKF) || smooth;
    let mut est_ba = Vector3::zeros();
    let mut est_bg = Vector3::zeros();
    let mut f_sum = Vector3::zeros();

    let n_rec = c.n_steps / c.record_every + 1;
    let mut err_h: [Vec<f64>; 5] = std::array::from_fn(|_| Vec::with_capacity(n_rec));
    let mut err_v: [Vec<f64>; 5] = std::array::from_fn(|_| Vec::with_capacity(n_rec));
    let mut sf_error = Vec::new();
    let mut bias_error = Vec::new();
    let mut next_interval = 0usize;
    let mut detail = keep_detail.then(|| Box::new(Detail::default()));
    let (mut rej_inv, mut n_inv, mut rej_val, mut n_val) = (0usize, 0usize, 0usize, 0usize);

    let r_dvl = Matrix3::identity() * c.filter_dvl_sigma.powi(2);
    let r_depth = c.depth_sigma * c.depth_sigma;
    let cov_dt = c.cov_every as f64 * c.dt;

    for k in 0..=c.n_steps {
        let truth = &sh.truth[k];
        let t = truth.time;
        let mut last_meas: Option<(Vector3<f64>, Vector3<f64>)> = None;
        if k > 0 {
            let inc = &sh.increments[k - 1];
            let (dth, dv) = imu
                .corrupt(inc.dt, &inc.delta_theta, &inc.delta_v, rng)
                .map_err(model_err("IMU"))?;
            last_meas = Some((dth, dv));
            let meas = ImuIncrement::new(inc.dt, dth, dv);

            // PINS and the 9-state filters' input.
            let v_old = pins.state().vel_in_nav;
            pins.step(&meas)
                .map_err(|e| SimError::model(format!("PINS at t = {t} s"), e))?;
            let dv_nav = pins.state().vel_in_nav - v_old;
            let c_nb = *pins.state().nav_from_body.to_rotation_matrix().matrix();
            for f in &mut nav {
                f.propagate(&dv_nav, &c_nb, inc.dt)
                    .map_err(model_err("9-state propagate"))?;
            }

            // ESKF INS with the fed-back IMU error estimates.
            if run_eskf {
                let corrected =
                    ImuIncrement::new(inc.dt, dth - est_bg * inc.dt, dv - est_ba * inc.dt);
                eskf_ins
                    .step(&corrected)
                    .map_err(|e| SimError::model(format!("ESKF INS at t = {t} s"), e))?;
                f_sum += corrected.delta_v;
            }

            if k % c.cov_every == 0 {
                for f in &mut nav {
                    f.propagate_covariance()
                        .map_err(model_err("9-state covariance"))?;
                }
            }
            if run_eskf && k % c.cov_every == 0 {
                let st = eskf_ins.state();
                let f_mean = f_sum / cov_dt;
                f_sum = Vector3::zeros();
                let fm = em::error_dynamics(st, &f_mean, &eskf_model);
                let phi = em::transition_matrix(&fm, cov_dt, Discretization::SecondOrder);
                let g = em::noise_input(st);
                // First-order Q_d = G Q_c G^T T (Groves eq. 3.46): at 5-10 Hz the
                // trapezoidal form changes nothing visible and costs two more 15^3
                // products per step.
                let gqg = g * q_c * g.transpose();
                let qd = (gqg + gqg.transpose()) * (0.5 * cov_dt);
                eskf.predict(&phi, &qd, t)
                    .map_err(model_err("ESKF predict"))?;
            }
        }

        // Sensor epoch.
        if k > 0 && k % c.sensor_every == 0 {
            if next_interval < sh.invalid.len() && t >= sh.invalid[next_interval].0 {
                sf_error.push(vkf.scale_factor() - c.rpm.k());
                bias_error.push(vkf.bias() - c.rpm.b());
                next_interval += 1;
            }
            let alt_true = sh.altitude[k];
            let reading = dvl
                .measure(&truth.vel_in_nav, alt_true, rng)
                .map_err(model_err("DVL"))?;
            let alt_meas = c.echo.measure(alt_true, rng);
            let rpm = c.rpm.measure(sh.forward_speed[k], rng);
            let depth = -truth.h + gauss(rng, c.depth_sigma);
            let valid = c.switch.dvl_valid(alt_meas);

            // VKF with the PINS attitude.
            let c_pins = *pins.state().nav_from_body.to_rotation_matrix().matrix();
            let dvl_fwd = (c_pins.transpose() * reading.vel_in_nav).x;
            vkf.step(rpm, valid.then_some(dvl_fwd), t)
                .map_err(model_err("VKF"))?;
            let rpm_speed = vkf.rpm_speed(rpm);

            // INS-DVL: raw DVL always.
            nav[0]
                .update_velocity(&reading.vel_in_nav, &r_dvl, None)
                .map_err(model_err("INS-DVL update"))?;
            // VKF: the switching box.
            let aid = c
                .switch
                .select(alt_meas, &reading.vel_in_nav, &r_dvl, rpm_speed, &c_pins);
            nav[1]
                .update_velocity(&aid.vel_in_nav, &aid.cov, None)
                .map_err(model_err("VKF update"))?;
            // INS-DVL-gated: raw DVL, chi-square gate.
            let gated = nav[2]
                .update_velocity(&reading.vel_in_nav, &r_dvl, Some(c.gate))
                .map_err(model_err("INS-DVL-gated update"))?;
            if reading.bottom_lock {
                n_val += 1;
                rej_val += usize::from(!gated.is_accepted());
            } else {
                n_inv += 1;
                rej_inv += usize::from(!gated.is_accepted());
            }
            for f in &mut nav {
                f.update_depth(depth, r_depth)
                    .map_err(model_err("9-state depth update"))?;
            }

            // ESKF: same switching with its own attitude, then feedback.
            if run_eskf {
                let st = *eskf_ins.state();
                let c_eskf = *st.nav_from_body.to_rotation_matrix().matrix();
                let aid_e =
                    c.switch
                        .select(alt_meas, &reading.vel_in_nav, &r_dvl, rpm_speed, &c_eskf);
                eskf.update_velocity(&st.vel_in_nav, &aid_e.vel_in_nav, &aid_e.cov, None)
                    .map_err(model_err("ESKF velocity update"))?;
                eskf.update_depth(-st.h, depth, r_depth)
                    .map_err(model_err("ESKF depth update"))?;
                let dx = eskf.take_correction().map_err(model_err("ESKF"))?;
                let err = NavError {
                    pos_in_nav: dx.fixed_rows::<3>(es::POS).into_owned(),
                    vel_in_nav: dx.fixed_rows::<3>(es::VEL).into_owned(),
                    attitude: dx.fixed_rows::<3>(es::ATT).into_owned(),
                };
                eskf_ins
                    .set_state(em::correct_state(&st, &err))
                    .map_err(|e| SimError::model(format!("ESKF feedback at t = {t} s"), e))?;
                est_ba += dx.fixed_rows::<3>(es::ACCEL_BIAS);
                est_bg += dx.fixed_rows::<3>(es::GYRO_BIAS);
            }

            if let Some(d) = detail.as_mut() {
                let rpm_vel = c_pins * Vector3::new(rpm_speed.0, 0.0, 0.0);
                d.t5.push(t);
                d.alt_true.push(alt_true);
                d.alt_meas.push(alt_meas);
                d.rpm.push(rpm);
                for i in 0..2 {
                    d.dvl_ne[i].push(reading.vel_in_nav[i]);
                    d.rpm_ne[i].push(rpm_vel[i]);
                    d.true_ne[i].push(truth.vel_in_nav[i]);
                }
                d.dvl_fwd.push(dvl_fwd);
                d.rpm_fwd.push(rpm_speed.0);
                d.sf.push(vkf.scale_factor());
                d.b.push(vkf.bias());
                let sig = vkf.sigmas();
                d.sf_sigma.push(sig[1]);
                d.b_sigma.push(sig[2]);
                d.vkf_source_rpm
                    .push(f64::from(u8::from(aid.source == VelocitySource::Rpm)));
            }
        }

        // Record at 1 Hz.
        if k % c.record_every == 0 {
            let tp = truth.position();
            let true_v = truth.vel_in_nav;
            let geo = |p: &Geodetic| horizontal_offset(&tp, p).xy().norm();
            err_h[PINS].push(geo(&pins.state().position()));
            err_v[PINS].push((pins.state().vel_in_nav - true_v).xy().norm());
            for (f, &m) in nav.iter().zip(&nav_method) {
                err_h[m].push((f.position() - sh.true_flat[k]).xy().norm());
                err_v[m].push((f.velocity() - true_v).xy().norm());
            }
            if run_eskf {
                err_h[ESKF].push(geo(&eskf_ins.state().position()));
                err_v[ESKF].push((eskf_ins.state().vel_in_nav - true_v).xy().norm());
            }
            if let (Some(pn), Some(pe)) = (nav[1].forward_pass(), eskf.forward_pass()) {
                marks.push((
                    pn.last_index(),
                    pe.last_index(),
                    *eskf_ins.state(),
                    tp,
                    sh.true_flat[k],
                ));
            }
            if let Some(d) = detail.as_mut() {
                d.t1.push(t);
                let flat = sh.true_flat[k];
                d.ne[0].push((flat.x, flat.y));
                let off = |p: &Geodetic| {
                    let o = horizontal_offset(&start, p);
                    (o.x, o.y)
                };
                d.ne[1 + PINS].push(off(&pins.state().position()));
                for (f, &m) in nav.iter().zip(&nav_method) {
                    let p = f.position();
                    d.ne[1 + m].push((p.x, p.y));
                }
                if run_eskf {
                    d.ne[1 + ESKF].push(off(&eskf_ins.state().position()));
                }
                let te = truth.to_ins_state().euler().to_vector();
                let pe = pins.state().euler().to_vector();
                for i in 0..3 {
                    d.truth_euler_deg[i].push(te[i].to_degrees());
                    d.pins_euler_deg[i].push(pe[i].to_degrees());
                }
                let (dth, dv) =
                    last_meas.unwrap_or((sh.increments[0].delta_theta, sh.increments[0].delta_v));
                for i in 0..3 {
                    d.gyro_deg_s[i].push((dth[i] / c.dt).to_degrees());
                    d.accel_mps2[i].push(dv[i] / c.dt);
                }
            }
        }
    }
    let smoothed = if smooth {
        Some(smoothed_errors(&nav[1], &eskf, &marks)?)
    } else {
        None
    };
    let frac = |a: usize, n: usize| if n == 0 { 0.0 } else { a as f64 / n as f64 };
    Ok(RunOutput {
        err_h,
        err_v,
        sf_error,
        bias_error,
        dvl_scale_factor: dvl.scale_factor(),
        gated_rejected_invalid: frac(rej_inv, n_inv),
        gated_rejected_valid: frac(rej_val, n_val),
        detail,
        smoothed,
    })
}

/// The RTS smoother over the recorded passes, read at the 1 Hz instants `marks`
/// (9-state step, ESKF step, ESKF corrected nominal, true position, true flat
/// position). The ESKF's smoothed error relative to its corrected nominal is
/// `x_{k|n} - x_{k|k}` (`fathom_estimators::smoother`, "Error-state filters").
fn smoothed_errors(
    nav: &IntegratedNavFilter,
    eskf: &ErrorStateFilter,
    marks: &[(usize, usize, InsState, Geodetic, Vector3<f64>)],
) -> Result<SmoothedErrors, SimError> {
    let sn = nav.smooth().map_err(model_err("9-state RTS smoother"))?;
    let se = eskf.smooth().map_err(model_err("ESKF RTS smoother"))?;
    let pe = eskf
        .forward_pass()
        .ok_or_else(|| SimError::invalid_argument("ESKF smoother", "nothing recorded"))?;
    let mut out = SmoothedErrors {
        vkf: Vec::with_capacity(marks.len()),
        eskf: Vec::with_capacity(marks.len()),
        eskf_steps: se.len(),
        nav_steps: sn.len(),
    };
    for (i_nav, i_eskf, nominal, true_pos, true_flat) in marks {
        let p = sn[*i_nav].mean.fixed_rows::<3>(0).into_owned();
        out.vkf.push((p - true_flat).xy().norm());
        let dx = se[*i_eskf].mean - pe.steps()[*i_eskf].filtered_mean;
        let err = NavError {
            pos_in_nav: dx.fixed_rows::<3>(es::POS).into_owned(),
            vel_in_nav: Vector3::zeros(),
            attitude: Vector3::zeros(),
        };
        let smoothed = em::correct_state(nominal, &err);
        out.eskf.push(
            horizontal_offset(true_pos, &smoothed.position())
                .xy()
                .norm(),
        );
    }
    Ok(out)
}

//! One pass over an `ins-dvl` log with every method side by side (as the `vkf`
//! experiment runs them on simulated data), on relative time `t - t0`.
//!
//! Timeline, ties in this order: IMU rows (every row after the start steps the
//! strapdowns and the 9-state filters' states over `(previous row, this row]`),
//! echo-sounder altitudes and RPM rows (held until the next), DVL rows, depth rows,
//! recording instants. Measurements are applied after the last IMU row at or before
//! their stamp (at most one IMU interval late).
//!
//! - An aiding epoch is every DVL row, and every RPM row while the DVL has been
//!   silent for longer than `dvl.timeout_s` (it counts as lost). The DVL of an epoch
//!   is valid when the row exists, its `bottom_lock` flag (if any) is 1 and the latest
//!   altitude (if any) is within `dvl.range_m`. Its body velocity is rotated into NED
//!   with each filter's own attitude (the 9-state filters use the PINS attitude).
//! - `pins`: the strapdown with the depth held at the start; every 9-state filter and
//!   the VKF take their inputs from it.
//! - `ins-dvl`: every DVL row, valid or not (the naive reference of seed 002), gated
//!   if the method has a gate.
//! - `vkf`, `eskf`: the switching box: the DVL when valid, else the VKF's RPM speed
//!   along the body x axis (`rpm.csv`; without it, no velocity update then). The VKF
//!   steps at every epoch with the latest RPM and, when valid, the DVL forward speed.
//! - Depth rows update every 9-state filter and ESKF.
//! - Covariances are propagated every `nav_filter.covariance_period_s` of IMU data
//!   and before every update; the ESKF feeds its estimate back after each update.

use fathom_core::frames::Euler;
use fathom_estimators::error_state::{self as es, ErrorStateFilter};
use fathom_estimators::integrated_nav::IntegratedNavFilter;
use fathom_estimators::velocity_filter::VelocityFilter;
use fathom_estimators::{Gate, GateThreshold};
use fathom_ins::earth::{Geodetic, curvilinear_offset};
use fathom_ins::error_model::{self as em, Discretization, NavError};
use fathom_ins::{ImuIncrement, InsState, Strapdown, VerticalChannel};
use nalgebra::{Matrix3, Vector3};

use super::settings::{InsDvlSettings, InsFilter};
use super::{InsMethodTrace, Update};
use fathom_data::layout::ins_dvl::{ImuForm, InsDvlLog};
use fathom_sim::SimError;

/// A method's filter state.
enum Filter {
    Pins,
    Nav(Box<IntegratedNavFilter>),
    Eskf(Box<EskfState>),
}

struct EskfState {
    ins: Strapdown,
    kf: ErrorStateFilter,
    accel_bias: Vector3<f64>,
    gyro_bias: Vector3<f64>,
    f_sum: Vector3<f64>,
    acc_t: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Imu(usize),
    Altitude(usize),
    Rpm(usize),
    Dvl(usize),
    Depth(usize),
    Record(usize),
}

fn rank(k: Kind) -> u8 {
    match k {
        Kind::Imu(_) => 0,
        Kind::Altitude(_) => 1,
        Kind::Rpm(_) => 2,
        Kind::Dvl(_) => 3,
        Kind::Depth(_) => 4,
        Kind::Record(_) => 5,
    }
}

fn model_err<E: std::error::Error + Send + Sync + 'static>(
    what: String,
) -> impl FnOnce(E) -> SimError {
    move |e| SimError::model(what, e)
}

impl EskfState {
    /// `P = Phi P Phi^T + Q_d` over the IMU time accumulated since the last step.
    fn predict(&mut self, s: &InsDvlSettings, t: f64) -> Result<(), SimError> {
        if self.acc_t <= 0.0 {
            return Ok(());
        }
        let st = self.ins.state();
        let f_mean = self.f_sum / self.acc_t;
        let fm = em::error_dynamics(st, &f_mean, &s.imu_model);
        let phi = em::transition_matrix(&fm, self.acc_t, Discretization::SecondOrder);
        let g = em::noise_input(st);
        let gqg = g * s.imu_model.noise_psd() * g.transpose();
        let qd = (gqg + gqg.transpose()) * (0.5 * self.acc_t);
        self.kf
            .predict(&phi, &qd, t)
            .map_err(model_err(format!("ESKF prediction at t = {t} s")))?;
        self.f_sum = Vector3::zeros();
        self.acc_t = 0.0;
        Ok(())
    }

    /// Removes the estimated error from the INS and the IMU.
    fn feedback(&mut self, t: f64) -> Result<(), SimError> {
        let dx = self
            .kf
            .take_correction()
            .map_err(model_err(format!("ESKF at t = {t} s")))?;
        let st = *self.ins.state();
        let err = NavError {
            pos_in_nav: dx.fixed_rows::<3>(es::POS).into_owned(),
            vel_in_nav: dx.fixed_rows::<3>(es::VEL).into_owned(),
            attitude: dx.fixed_rows::<3>(es::ATT).into_owned(),
        };
        self.ins
            .set_state(em::correct_state(&st, &err))
            .map_err(model_err(format!("ESKF feedback at t = {t} s")))?;
        self.accel_bias += dx.fixed_rows::<3>(es::ACCEL_BIAS);
        self.gyro_bias += dx.fixed_rows::<3>(es::GYRO_BIAS);
        Ok(())
    }
}

fn record_gate(gate: Gate<3>, time: f64, source_rpm: bool) -> Update {
    match gate {
        Gate::Accepted(info) => Update {
            time,
            nis: info.nis,
            innovation: Some(info.innovation.into()),
            innovation_sigma: Some(std::array::from_fn(|i| {
                info.innovation_cov[(i, i)].max(0.0).sqrt()
            })),
            accepted: true,
            rpm: source_rpm,
        },
        Gate::Rejected { nis } => Update {
            time,
            nis,
            innovation: None,
            innovation_sigma: None,
            accepted: false,
            rpm: source_rpm,
        },
    }
}

/// Runs every method of `s` over `log`, recording at `record` (relative times,
/// increasing). Returns the traces and the relative times actually recorded at (the
/// last IMU row at or before each instant).
///
/// # Errors
/// [`SimError::Model`] naming the method, the component and the time of a failing
/// step (a non-finite increment, a covariance that stops being positive definite).
pub fn run(
    log: &InsDvlLog,
    s: &InsDvlSettings,
    record: &[f64],
) -> Result<(Vec<InsMethodTrace>, Vec<f64>), SimError> {
    let st = &log.start;
    let t0 = st.time;
    let start_geo = Geodetic::new(st.lat_lon[0], st.lat_lon[1], -st.depth);
    let vel0 = Vector3::from(st.vel_in_nav);
    let state0 = InsState::from_euler(
        start_geo,
        vel0,
        &Euler::new(st.euler[0], st.euler[1], st.euler[2]),
    );
    state0
        .check()
        .map_err(model_err("the start of `initial.csv`".into()))?;
    let mut pins = Strapdown::new(state0)
        .and_then(|p| p.with_vertical_channel(VerticalChannel::Hold { h: -st.depth }))
        .map_err(model_err("PINS".into()))?;
    let pos0 = Vector3::new(0.0, 0.0, st.depth);
    let p0_eskf = ErrorStateFilter::diagonal_covariance([
        s.nav.params().sigma0[0],
        s.nav.params().sigma0[1],
        s.sigma0_att,
        s.bias_sigma0[0],
        s.bias_sigma0[1],
    ]);
    let mut filters: Vec<Filter> = s
        .methods
        .iter()
        .map(|m| -> Result<Filter, SimError> {
            Ok(match m.filter {
                InsFilter::Pins => Filter::Pins,
                InsFilter::InsDvl | InsFilter::Vkf => Filter::Nav(Box::new(
                    IntegratedNavFilter::new(&s.nav, &pos0, &vel0, 0.0)
                        .map_err(model_err(format!("method `{}`", m.name)))?,
                )),
                InsFilter::Eskf => Filter::Eskf(Box::new(EskfState {
                    ins: Strapdown::new(state0)
                        .map_err(model_err(format!("method `{}`", m.name)))?,
                    kf: ErrorStateFilter::new(&p0_eskf, 0.0)
                        .map_err(model_err(format!("method `{}`", m.name)))?,
                    accel_bias: Vector3::zeros(),
                    gyro_bias: Vector3::zeros(),
                    f_sum: Vector3::zeros(),
                    acc_t: 0.0,
                })),
            })
        })
        .collect::<Result<_, _>>()?;
    let gates: Vec<Option<GateThreshold>> = s
        .methods
        .iter()
        .map(|m| {
            m.gate_probability
                .map(|p| GateThreshold::from_chi_square_probability(p, 3))
                .transpose()
                .map_err(model_err(format!("method `{}` gate", m.name)))
        })
        .collect::<Result<_, _>>()?;
    let needs_vkf = s
        .methods
        .iter()
        .any(|m| matches!(m.filter, InsFilter::Vkf | InsFilter::Eskf));
    let speed0 = (state0.nav_from_body.inverse() * vel0).x;
    let mut vkf = match (needs_vkf, &log.rpm) {
        (true, Some(_)) => {
            let params =
                fathom_estimators::velocity_filter::VelocityFilterParams { speed0, ..s.vkf };
            let cfg = params.check().map_err(model_err("VKF".into()))?;
            Some(VelocityFilter::new(&cfg, 0.0).map_err(model_err("VKF".into()))?)
        }
        _ => None,
    };

    // The timeline (module docs).
    let mut ev: Vec<(f64, Kind)> = Vec::new();
    let after = |t: f64| t > t0;
    ev.extend(
        log.imu
            .iter()
            .enumerate()
            .filter(|r| after(r.1.0))
            .map(|(k, r)| (r.0 - t0, Kind::Imu(k))),
    );
    let mut altitude: Option<f64> = None;
    let mut rpm: Option<f64> = None;
    for (k, r) in log.altitude.iter().flatten().enumerate() {
        if after(r.0) {
            ev.push((r.0 - t0, Kind::Altitude(k)));
        } else {
            altitude = Some(r.1);
        }
    }
    for (k, r) in log.rpm.iter().flatten().enumerate() {
        if after(r.0) {
            ev.push((r.0 - t0, Kind::Rpm(k)));
        } else {
            rpm = Some(r.1);
        }
    }
    ev.extend(
        log.dvl
            .iter()
            .enumerate()
            .filter(|r| after(r.1.time))
            .map(|(k, r)| (r.time - t0, Kind::Dvl(k))),
    );
    ev.extend(
        log.depth
            .iter()
            .flatten()
            .enumerate()
            .filter(|r| after(r.1.0))
            .map(|(k, r)| (r.0 - t0, Kind::Depth(k))),
    );
    ev.extend(
        record
            .iter()
            .enumerate()
            .map(|(k, &t)| (t, Kind::Record(k))),
    );
    ev.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then(rank(a.1).cmp(&rank(b.1)))
            .then(a.1.cmp(&b.1))
    });

    let n = record.len();
    let mut traces: Vec<InsMethodTrace> = s
        .methods
        .iter()
        .map(|m| InsMethodTrace::with_capacity(m.clone(), n, vkf.is_some()))
        .collect();
    let mut recorded_at = Vec::with_capacity(n);
    let r_dvl = Matrix3::identity() * s.dvl_sigma.powi(2);
    let r_depth = s.depth_sigma.powi(2);
    let mut t_imu = 0.0;
    let mut cov_acc = 0.0;
    let mut last_dvl = 0.0;
    let mut prev_imu_t = t0;

    for (t, kind) in ev {
        match kind {
            Kind::Imu(k) => {
                let (ta, a, b) = log.imu[k];
                let dt = ta - prev_imu_t;
                prev_imu_t = ta;
                let (dth, dv) = match log.imu_form {
                    ImuForm::Increments => (Vector3::from(a), Vector3::from(b)),
                    ImuForm::Rates => (Vector3::from(a) * dt, Vector3::from(b) * dt),
                };
                let inc = ImuIncrement::new(dt, dth, dv);
                let v_old = pins.state().vel_in_nav;
                pins.step(&inc)
                    .map_err(model_err(format!("PINS at the IMU row at t = {ta} s")))?;
                let dv_nav = pins.state().vel_in_nav - v_old;
                let c_nb = *pins.state().nav_from_body.to_rotation_matrix().matrix();
                t_imu = t;
                cov_acc += dt;
                let cov_step = cov_acc >= s.covariance_period * (1.0 - 1e-9);
                for (f, m) in filters.iter_mut().zip(&s.methods) {
                    let name = &m.name;
                    match f {
                        Filter::Pins => {}
                        Filter::Nav(nav) => {
                            nav.propagate(&dv_nav, &c_nb, dt)
                                .map_err(model_err(format!("method `{name}`")))?;
                            if cov_step {
                                nav.propagate_covariance()
                                    .map_err(model_err(format!("method `{name}`")))?;
                            }
                        }
                        Filter::Eskf(e) => {
                            let corrected = ImuIncrement::new(
                                dt,
                                dth - e.gyro_bias * dt,
                                dv - e.accel_bias * dt,
                            );
                            e.ins.step(&corrected).map_err(model_err(format!(
                                "method `{name}` INS at the IMU row at t = {ta} s"
                            )))?;
                            e.f_sum += corrected.delta_v;
                            e.acc_t += dt;
                            if cov_step {
                                e.predict(s, t).map_err(|er| {
                                    SimError::model(format!("method `{name}`"), er)
                                })?;
                            }
                        }
                    }
                }
                if cov_step {
                    cov_acc = 0.0;
                }
            }
            Kind::Altitude(k) => altitude = log.altitude.as_ref().map(|a| a[k].1),
            Kind::Rpm(k) => {
                rpm = log.rpm.as_ref().map(|r| r[k].1);
                if t - last_dvl > s.dvl_timeout {
                    epoch(
                        s,
                        &mut filters,
                        &gates,
                        &mut traces,
                        &mut vkf,
                        &pins,
                        None,
                        altitude,
                        rpm,
                        t_imu,
                        &r_dvl,
                    )?;
                }
            }
            Kind::Dvl(k) => {
                last_dvl = t;
                epoch(
                    s,
                    &mut filters,
                    &gates,
                    &mut traces,
                    &mut vkf,
                    &pins,
                    Some(&log.dvl[k]),
                    altitude,
                    rpm,
                    t_imu,
                    &r_dvl,
                )?;
            }
            Kind::Depth(k) => {
                let d = log.depth.as_ref().map_or(0.0, |v| v[k].1);
                for ((f, tr), m) in filters.iter_mut().zip(&mut traces).zip(&s.methods) {
                    let ctx = || format!("method `{}` depth update at t = {t_imu} s", m.name);
                    match f {
                        Filter::Pins => {}
                        Filter::Nav(nav) => {
                            let info = nav.update_depth(d, r_depth).map_err(model_err(ctx()))?;
                            tr.depth_updates.push(Update::depth(
                                t_imu,
                                info.innovation[0],
                                info.innovation_cov[(0, 0)],
                                info.nis,
                            ));
                        }
                        Filter::Eskf(e) => {
                            e.predict(s, t_imu)?;
                            let h = e.ins.state().h;
                            let info =
                                e.kf.update_depth(-h, d, r_depth)
                                    .map_err(model_err(ctx()))?;
                            // The ESKF innovation is INS minus sensor: report sensor minus INS.
                            tr.depth_updates.push(Update::depth(
                                t_imu,
                                -info.innovation[0],
                                info.innovation_cov[(0, 0)],
                                info.nis,
                            ));
                            e.feedback(t_imu)?;
                        }
                    }
                }
            }
            Kind::Record(_) => {
                recorded_at.push(t_imu);
                for ((f, tr), _) in filters.iter().zip(&mut traces).zip(&s.methods) {
                    let (ne, down, vel, sigma) = match f {
                        Filter::Pins => {
                            let p = pins.state();
                            let o = curvilinear_offset(&start_geo, &p.position());
                            ([o.x, o.y], -p.h, p.vel_in_nav, None)
                        }
                        Filter::Nav(nav) => {
                            let p = nav.position();
                            let c = nav.covariance();
                            (
                                [p.x, p.y],
                                p.z,
                                nav.velocity(),
                                Some((c[(0, 0)] + c[(1, 1)]).sqrt()),
                            )
                        }
                        Filter::Eskf(e) => {
                            let p = e.ins.state();
                            let o = curvilinear_offset(&start_geo, &p.position());
                            let c = e.kf.covariance();
                            (
                                [o.x, o.y],
                                -p.h,
                                p.vel_in_nav,
                                Some((c[(0, 0)] + c[(1, 1)]).sqrt()),
                            )
                        }
                    };
                    tr.north_east.push(ne);
                    tr.depth.push(down);
                    tr.vel_in_nav.push(vel.into());
                    if let (Some(v), Some(x)) = (tr.sigma_h.as_mut(), sigma) {
                        v.push(x);
                    }
                }
                if let Some(v) = &vkf {
                    for tr in &mut traces {
                        if let Some(c) = tr.vkf_calibration.as_mut() {
                            c.push([v.scale_factor(), v.bias()]);
                        }
                    }
                }
            }
        }
    }
    Ok((traces, recorded_at))
}

/// One aiding epoch (module docs); `dvl` is the DVL row of the epoch, if any.
#[allow(clippy::too_many_arguments)]
fn epoch(
    s: &InsDvlSettings,
    filters: &mut [Filter],
    gates: &[Option<GateThreshold>],
    traces: &mut [InsMethodTrace],
    vkf: &mut Option<VelocityFilter>,
    pins: &Strapdown,
    dvl: Option<&fathom_data::layout::ins_dvl::DvlRow>,
    altitude: Option<f64>,
    rpm: Option<f64>,
    t: f64,
    r_dvl: &Matrix3<f64>,
) -> Result<(), SimError> {
    let valid = dvl.is_some_and(|d| {
        d.bottom_lock != Some(false) && altitude.is_none_or(|a| s.switch.dvl_valid(a))
    });
    let v_body = dvl.map(|d| Vector3::from(d.vel_in_body));
    let mut rpm_speed = None;
    if let (Some(f), Some(r)) = (vkf.as_mut(), rpm) {
        let fwd = v_body.filter(|_| valid).map(|v| v.x);
        f.step(r, fwd, t)
            .map_err(model_err(format!("VKF at t = {t} s")))?;
        rpm_speed = Some(f.rpm_speed(r));
    }
    let c_pins = *pins.state().nav_from_body.to_rotation_matrix().matrix();
    // The switching box's aid with the attitude `c`: the DVL when valid, else the RPM
    // speed along body x (an altitude beyond any range selects it).
    let aid = |c: &Matrix3<f64>| -> Option<(Vector3<f64>, Matrix3<f64>, bool)> {
        match (valid, v_body, rpm_speed) {
            (true, Some(v), _) => Some((c * v, *r_dvl, false)),
            (false, _, Some(rs)) => {
                let a = s
                    .switch
                    .select(f64::INFINITY, &Vector3::zeros(), r_dvl, rs, c);
                Some((a.vel_in_nav, a.cov, true))
            }
            _ => None,
        }
    };
    for (((f, tr), m), gate) in filters
        .iter_mut()
        .zip(traces.iter_mut())
        .zip(&s.methods)
        .zip(gates)
    {
        let ctx = || format!("method `{}` velocity update at t = {t} s", m.name);
        match (f, m.filter) {
            (Filter::Pins, _) => {}
            (Filter::Nav(nav), InsFilter::InsDvl) => {
                if let Some(v) = v_body {
                    let g = nav
                        .update_velocity(&(c_pins * v), r_dvl, *gate)
                        .map_err(model_err(ctx()))?;
                    tr.velocity_updates.push(record_gate(g, t, false));
                }
            }
            (Filter::Nav(nav), _) => {
                if let Some((z, r, from_rpm)) = aid(&c_pins) {
                    let g = nav
                        .update_velocity(&z, &r, *gate)
                        .map_err(model_err(ctx()))?;
                    tr.velocity_updates.push(record_gate(g, t, from_rpm));
                }
            }
            (Filter::Eskf(e), _) => {
                let c_e = *e.ins.state().nav_from_body.to_rotation_matrix().matrix();
                if let Some((z, r, from_rpm)) = aid(&c_e) {
                    e.predict(s, t)?;
                    let ins_v = e.ins.state().vel_in_nav;
                    let g =
                        e.kf.update_velocity(&ins_v, &z, &r, *gate)
                            .map_err(model_err(ctx()))?;
                    // The ESKF innovation is INS minus aid: report aid minus INS.
                    let mut u = record_gate(g, t, from_rpm);
                    u.innovation = u.innovation.map(|i| [-i[0], -i[1], -i[2]]);
                    tr.velocity_updates.push(u);
                    e.feedback(t)?;
                }
            }
        }
    }
    Ok(())
}

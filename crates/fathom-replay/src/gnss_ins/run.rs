//! One pass over a `gnss-ins` log with every method side by side: the local frame
//! (PX4's projection about EKF2's first pose, [`LocalFrame`]), the start (EKF2's
//! pose, velocity and attitude at its first row inside the IMU data), the strapdown
//! mechanization per method, the filters' prediction per IMU row, the GNSS updates
//! after the IMU row at or after each fix (fixes below `min_fix_type` or inside an
//! outage window skipped), and the recording at every EKF2 row after the start and
//! inside the IMU data (and inside the truth's span when the log has truth: the state
//! of the last IMU row, moved to the instant with its velocity).

use fathom_data::layout::gnss_ins::{GnssInsLog, GnssRow, TrackRow};
use fathom_data::ulog::projection::project;
use fathom_estimators::GateThreshold;
use fathom_estimators::error_state::{ACCEL_BIAS, ErrorStateFilter, GYRO_BIAS};
use fathom_estimators::map_aided::error_model::transition_with_gyro_bias;
use fathom_estimators::map_aided::{GpsFix, GpsParams, GpsVelocity, Ins12Filter, NominalNav};
use fathom_ins::ImuIncrement;
use fathom_ins::earth::normal_gravity;
use fathom_ins::local_level::{LocalLevelMechanization, LocalLevelState};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::settings::{GnssInsFilter, GnssInsMethod, GnssInsSettings};
use super::{FixUpdate, MethodTrace};
use fathom_sim::SimError;

/// The replay's local NED frame: north and east by PX4's projection about `origin`,
/// down `alt0 - altitude`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    /// Latitude, longitude of the origin, rad.
    pub origin: [f64; 2],
    /// Altitude of the origin, m.
    pub alt0: f64,
}

impl LocalFrame {
    /// NED position of a geodetic point.
    pub fn ned(&self, lat_lon: [f64; 2], altitude: f64) -> [f64; 3] {
        let [n, e] = project(self.origin, lat_lon);
        [n, e, self.alt0 - altitude]
    }
}

/// The start: EKF2's first row at or after the first IMU row (index into
/// `reference`).
pub fn start_row(log: &GnssInsLog) -> Result<(usize, &[TrackRow]), SimError> {
    let reference = log.reference.as_deref().ok_or_else(|| {
        SimError::invalid_argument(
            "log `reference.csv`",
            "is missing: the replay starts from the autopilot's pose, velocity and attitude \
             (PX4's EKF2 estimate, which `fathom log from-ulog` writes)",
        )
    })?;
    let t_imu = log.imu[0].time;
    let last_imu = log.imu[log.imu.len() - 1].time;
    let k = reference.partition_point(|r| r.time < t_imu);
    if k + 1 >= reference.len() || reference[k].time >= last_imu {
        return Err(SimError::invalid_argument(
            "log `reference.csv`",
            format!("has fewer than two rows inside the IMU data ({t_imu} s to {last_imu} s)"),
        ));
    }
    Ok((k, reference))
}

fn model(what: String, e: impl std::error::Error + Send + Sync + 'static) -> SimError {
    SimError::model(what, e)
}

/// A GNSS fix in the local frame with its covariances.
struct Fix {
    pos: Vector3<f64>,
    pos_cov: Matrix3<f64>,
    vel: Vector3<f64>,
    vel_cov: Matrix3<f64>,
}

fn fix_of(frame: &LocalFrame, g: &GnssRow, s: &GnssInsSettings) -> Fix {
    let p = frame.ned(g.lat_lon, g.altitude);
    let sh = g.h_acc.max(s.min_sigma[0]);
    let sv = g.v_acc.max(s.min_sigma[0]);
    let ss = g.speed_acc.max(s.min_sigma[1]);
    Fix {
        pos: Vector3::from(p),
        pos_cov: Matrix3::from_diagonal(&Vector3::new(sh * sh, sh * sh, sv * sv)),
        vel: Vector3::from(g.vel_in_nav),
        vel_cov: Matrix3::identity() * (ss * ss),
    }
}

enum Filter {
    None,
    Ekf12(Box<Ins12Filter>),
    Ekf15(Box<ErrorStateFilter>),
}

/// One method running.
struct Runner {
    method: GnssInsMethod,
    mech: LocalLevelMechanization,
    accel_bias: Vector3<f64>,
    gyro_bias: Vector3<f64>,
    filter: Filter,
    trace: MethodTrace,
}

impl Runner {
    fn nominal(&self) -> NominalNav {
        let s = self.mech.state();
        NominalNav {
            pos_in_nav: s.pos_in_nav,
            vel_in_nav: s.vel_in_nav,
            nav_from_body: s.nav_from_body,
            accel_bias_in_body: self.accel_bias,
        }
    }

    fn pos_cov(&self) -> Option<Matrix3<f64>> {
        match &self.filter {
            Filter::None => None,
            Filter::Ekf12(f) => Some(f.covariance().fixed_view::<3, 3>(0, 0).into()),
            Filter::Ekf15(f) => Some(f.covariance().fixed_view::<3, 3>(0, 0).into()),
        }
    }

    fn step(
        &mut self,
        s: &GnssInsSettings,
        t: f64,
        dt: f64,
        gyro: Vector3<f64>,
        accel: Vector3<f64>,
    ) -> Result<(), SimError> {
        let name = &self.method.name;
        let dth = (gyro - self.gyro_bias) * dt;
        let dv = (accel - self.accel_bias) * dt;
        let q_start = self.mech.state().nav_from_body;
        self.mech
            .step(&ImuIncrement::new(dt, dth, dv))
            .map_err(|e| model(format!("`{name}` mechanization at t = {t} s"), e))?;
        let f = dv / dt;
        match &mut self.filter {
            Filter::None => {}
            Filter::Ekf12(k) => k
                .predict(&q_start, &f, t)
                .map_err(|e| model(format!("`{name}` prediction at t = {t} s"), e))?,
            Filter::Ekf15(k) => {
                let (phi, qd) =
                    transition_with_gyro_bias(&q_start, &f, &s.noise, s.gyro_bias_psd, dt);
                k.predict(&phi, &qd, t)
                    .map_err(|e| model(format!("`{name}` prediction at t = {t} s"), e))?;
            }
        }
        Ok(())
    }

    /// The GNSS update at the filter time `t` (`rel` from the start).
    fn update(&mut self, s: &GnssInsSettings, fix: &Fix, rel: f64, t: f64) -> Result<(), SimError> {
        let name = self.method.name.clone();
        let nominal = self.nominal();
        let dof = if s.use_velocity { 6 } else { 3 };
        let (accepted, nis) = match &mut self.filter {
            Filter::None => return Ok(()),
            Filter::Ekf12(k) => {
                let aiding = GpsParams {
                    gate_probability: s.gate_probability,
                    reacquire_after_rejections: 0,
                }
                .check()
                .map_err(|e| model(format!("`{name}` gate"), e))?;
                let gps = GpsFix {
                    pos_in_nav: fix.pos,
                    pos_cov: fix.pos_cov,
                    velocity: s.use_velocity.then_some(GpsVelocity {
                        vel_in_nav: fix.vel,
                        cov: fix.vel_cov,
                    }),
                };
                match k.update_gps(&nominal, &gps, &aiding) {
                    Ok(o) => (o.accepted, o.nis),
                    Err(_) => (false, f64::NAN),
                }
            }
            Filter::Ekf15(k) => {
                let gate = GateThreshold::from_chi_square_probability(s.gate_probability, 3)
                    .map_err(|e| model(format!("`{name}` gate"), e))?;
                let p = k.update_position(&nominal.pos_in_nav, &fix.pos, &fix.pos_cov, Some(gate));
                match p {
                    Ok(g) if g.is_accepted() => {
                        let mut nis = g.nis();
                        if s.use_velocity {
                            // sequential velocity update (block-diagonal R)
                            let v = k.update_velocity(
                                &nominal.vel_in_nav,
                                &fix.vel,
                                &fix.vel_cov,
                                Some(gate),
                            );
                            nis += v.as_ref().map_or(f64::NAN, |g| g.nis());
                        }
                        (true, nis)
                    }
                    Ok(g) => (false, g.nis()),
                    Err(_) => (false, f64::NAN),
                }
            }
        };
        self.trace.updates.push(FixUpdate {
            time: rel,
            nis,
            dof,
            accepted,
        });
        if accepted {
            self.feedback(t)?;
        }
        Ok(())
    }

    /// Takes the filter's error estimate into the mechanization and the biases.
    fn feedback(&mut self, t: f64) -> Result<(), SimError> {
        let nominal = self.nominal();
        let (nav, dbg) = match &mut self.filter {
            Filter::None => return Ok(()),
            Filter::Ekf12(k) => (k.take_correction().apply(&nominal), Vector3::zeros()),
            Filter::Ekf15(k) => {
                let dx = k
                    .take_correction()
                    .map_err(|e| model(format!("`{}` feedback", self.method.name), e))?;
                let c = fathom_estimators::map_aided::Correction {
                    dpos_in_nav: dx.fixed_rows::<3>(0).into(),
                    dvel_in_nav: dx.fixed_rows::<3>(3).into(),
                    datt_in_nav: dx.fixed_rows::<3>(6).into(),
                    daccel_bias_in_body: dx.fixed_rows::<3>(ACCEL_BIAS).into(),
                };
                (c.apply(&nominal), dx.fixed_rows::<3>(GYRO_BIAS).into())
            }
        };
        self.mech
            .set_state(LocalLevelState {
                pos_in_nav: nav.pos_in_nav,
                vel_in_nav: nav.vel_in_nav,
                nav_from_body: nav.nav_from_body,
            })
            .map_err(|e| model(format!("`{}` feedback at t = {t} s", self.method.name), e))?;
        self.accel_bias = nav.accel_bias_in_body;
        self.gyro_bias += dbg;
        Ok(())
    }

    fn record(&mut self, dt_to_instant: f64) {
        let s = self.mech.state();
        let pos = s.pos_in_nav + s.vel_in_nav * dt_to_instant;
        self.trace.pos_in_nav.push(pos.into());
        self.trace.vel_in_nav.push(s.vel_in_nav.into());
        if let Some(p) = self.pos_cov() {
            self.trace.cov_pos.get_or_insert_with(Vec::new).push([
                p[(0, 0)],
                p[(0, 1)],
                p[(0, 2)],
                p[(1, 1)],
                p[(1, 2)],
                p[(2, 2)],
            ]);
        }
    }
}

/// What [`run`] returns: the frame, the start time, the instants (`t - t0`) and the
/// traces in the settings' order.
pub struct Pass {
    /// The local frame.
    pub frame: LocalFrame,
    /// Start time, s.
    pub t0: f64,
    /// Recording instants, s from the start.
    pub times: Vec<f64>,
    /// EKF2's position at the instants (its rows).
    pub ekf2: Vec<[f64; 3]>,
    /// The methods' traces.
    pub traces: Vec<MethodTrace>,
    /// Fixes used (3D or better, outside the outages).
    pub fixes_used: usize,
}

/// Runs every method over the log (module docs).
///
/// # Errors
/// As [`start_row`]; [`SimError::Model`] naming the method and time of a failing
/// step.
pub fn run(log: &GnssInsLog, s: &GnssInsSettings) -> Result<Pass, SimError> {
    let (k0, reference) = start_row(log)?;
    let r0 = reference[k0];
    let frame = LocalFrame {
        origin: r0.lat_lon,
        alt0: r0.altitude,
    };
    let t0 = r0.time;
    let e = r0.euler.unwrap_or([0.0; 3]);
    let start = LocalLevelState {
        pos_in_nav: Vector3::from(frame.ned(r0.lat_lon, r0.altitude)),
        vel_in_nav: Vector3::from(r0.vel_in_nav),
        nav_from_body: UnitQuaternion::from_euler_angles(e[0], e[1], e[2]),
    };
    let gravity = normal_gravity(r0.lat_lon[0], r0.altitude);
    let [sp, sv, sa, sba, sbg] = s.sigma0;
    let mut runners = Vec::with_capacity(s.methods.len());
    for m in &s.methods {
        let mech = LocalLevelMechanization::new(start, gravity)
            .map_err(|e| model(format!("`{}` start", m.name), e))?;
        let filter = match m.filter {
            GnssInsFilter::Ins => Filter::None,
            GnssInsFilter::Ekf12 => Filter::Ekf12(Box::new(
                Ins12Filter::new(
                    &Ins12Filter::diagonal_covariance([sp, sv, sa, sba]),
                    t0,
                    s.noise,
                )
                .map_err(|e| model(format!("`{}` start", m.name), e))?,
            )),
            GnssInsFilter::Ekf15 => Filter::Ekf15(Box::new(
                ErrorStateFilter::new(
                    &ErrorStateFilter::diagonal_covariance([sp, sv, sa, sba, sbg]),
                    t0,
                )
                .map_err(|e| model(format!("`{}` start", m.name), e))?,
            )),
        };
        runners.push(Runner {
            method: m.clone(),
            mech,
            accel_bias: Vector3::zeros(),
            gyro_bias: Vector3::zeros(),
            filter,
            trace: MethodTrace::new(m.clone()),
        });
    }
    let last_imu = log.imu[log.imu.len() - 1].time;
    // with truth, only the instants it covers (it is interpolated there)
    let covered = log
        .truth
        .as_deref()
        .map_or((f64::NEG_INFINITY, f64::INFINITY), |t| {
            (
                t.first().map_or(f64::INFINITY, |r| r.time),
                t.last().map_or(f64::NEG_INFINITY, |r| r.time),
            )
        });
    let instants: Vec<&TrackRow> = reference[k0 + 1..]
        .iter()
        .filter(|r| r.time <= last_imu && r.time >= covered.0 && r.time <= covered.1)
        .collect();
    let mut gnss = log.gnss.iter().filter(|g| g.time > t0).peekable();
    let mut next_instant = instants.iter().peekable();
    let mut t_prev = t0;
    let mut fixes_used = 0;
    let mut times = Vec::with_capacity(instants.len());
    let mut ekf2 = Vec::with_capacity(instants.len());
    for row in log.imu.iter().filter(|r| r.time > t0) {
        // record the instants before this row at the previous row's state
        while let Some(r) = next_instant.peek() {
            if r.time >= row.time {
                break;
            }
            for run in &mut runners {
                run.record(r.time - t_prev);
            }
            times.push(r.time - t0);
            ekf2.push(frame.ned(r.lat_lon, r.altitude));
            next_instant.next();
        }
        let t = row.time;
        let dt = t - t_prev;
        let (g, a) = (
            Vector3::from(row.gyro_in_body),
            Vector3::from(row.accel_in_body),
        );
        for run in &mut runners {
            run.step(s, t, dt, g, a)?;
        }
        while let Some(fix) = gnss.peek() {
            if fix.time > t {
                break;
            }
            let rel = fix.time - t0;
            if fix.fix_type >= s.min_fix_type && !s.in_outage(rel) {
                fixes_used += 1;
                let f = fix_of(&frame, fix, s);
                for run in &mut runners {
                    run.update(s, &f, t - t0, t)?;
                }
            }
            gnss.next();
        }
        t_prev = t;
    }
    for r in next_instant {
        for run in &mut runners {
            run.record(r.time - t_prev);
        }
        times.push(r.time - t0);
        ekf2.push(frame.ned(r.lat_lon, r.altitude));
    }
    Ok(Pass {
        frame,
        t0,
        times,
        ekf2,
        traces: runners.into_iter().map(|r| r.trace).collect(),
        fixes_used,
    })
}

//! One pass over a `gnss-ins` log with every method side by side: the local frame
//! (PX4's projection about EKF2's first pose, [`LocalFrame`]), the start (EKF2's
//! pose, velocity and attitude at its first row inside the IMU data), the strapdown
//! mechanization per method, the filters' prediction per IMU row, the GNSS updates
//! after the IMU row at or after each fix (fixes below `min_fix_type` or inside an
//! outage window skipped), and the recording at every EKF2 row after the start and
//! inside the IMU data (and inside the truth's span when the log has truth: the state
//! of the last IMU row, moved to the instant with its velocity).
//!
//! The map-aided methods (`grekf`, `mgpmf`, with a world) are the 12-state filter
//! with a mode switch ([`fathom_estimators::map_aided::ModeSwitch`]): at every GNSS row
//! it sees the row's satellite count if the replay uses the fix, else 0 (an outage, a
//! poor fix type); in GPS/INS mode the fix updates the filter, in map-aided mode
//! each range epoch (the `range.csv` rows of one stamp, after the IMU row at or after
//! it) does, with the barometric height, through the world
//! ([`fathom_core::RayCaster`]).

use fathom_core::RayCaster;
use fathom_data::layout::gnss_ins::{GnssInsLog, GnssRow, RangeRow, TrackRow};
use fathom_data::ulog::projection::project;
use fathom_estimators::GateThreshold;
use fathom_estimators::error_state::{ACCEL_BIAS, ErrorStateFilter, GYRO_BIAS, POS, VEL};
use fathom_estimators::map_aided::error_model::transition_with_gyro_bias;
use fathom_estimators::map_aided::{
    BaroHeight, GpsFix, GpsParams, GpsReacquire, GpsVelocity, Grekf, Ins12Filter, Mgpmf,
    ModeSwitch, NavMode, NominalNav, RangeBeam,
};
use fathom_ins::ImuIncrement;
use fathom_ins::earth::normal_gravity;
use fathom_ins::local_level::{LocalLevelMechanization, LocalLevelState};
use fathom_map::{BvhCaster, TriMesh};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

use super::settings::{GnssInsFilter, GnssInsMethod, GnssInsSettings, MapAidedSettings};
use super::{FixUpdate, MapCounts, MethodTrace};
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

/// The 15-state filter's GNSS update: position, then (with `use_velocity`, after an
/// accepted position) velocity, both gated; returns whether the position passed and
/// the summed NIS.
fn update15(
    k: &mut ErrorStateFilter,
    nominal: &NominalNav,
    fix: &Fix,
    use_velocity: bool,
    gate: GateThreshold,
) -> (bool, f64) {
    match k.update_position(&nominal.pos_in_nav, &fix.pos, &fix.pos_cov, Some(gate)) {
        Ok(g) if g.is_accepted() => {
            let mut nis = g.nis();
            if use_velocity {
                // sequential velocity update (block-diagonal R)
                let v = k.update_velocity(&nominal.vel_in_nav, &fix.vel, &fix.vel_cov, Some(gate));
                nis += v.as_ref().map_or(f64::NAN, |g| g.nis());
            }
            (true, nis)
        }
        Ok(g) => (false, g.nis()),
        Err(_) => (false, f64::NAN),
    }
}

/// The 15-state filter's re-acquisition (the 12-state filter's
/// `map_aided::GpsReacquire` rule): the position (and with `use_velocity` the
/// velocity) covariance widened by the outer product of the error the fix shows, then
/// the fix applied to a copy; the copy and its NIS when the fix now passes the gate
/// (the estimate jumps to the fix), else `None` (the filter is kept).
fn reacquire15(
    k: &ErrorStateFilter,
    nominal: &NominalNav,
    fix: &Fix,
    use_velocity: bool,
    gate: GateThreshold,
) -> Option<(ErrorStateFilter, f64)> {
    let mut k2 = k.clone();
    let dp = fix.pos - nominal.pos_in_nav;
    k2.widen_covariance_block(POS, &(dp * dp.transpose()))
        .ok()?;
    if use_velocity {
        let dv = fix.vel - nominal.vel_in_nav;
        k2.widen_covariance_block(VEL, &(dv * dv.transpose()))
            .ok()?;
    }
    let (accepted, nis) = update15(&mut k2, nominal, fix, use_velocity, gate);
    accepted.then_some((k2, nis))
}

enum Aider {
    Grekf(Box<Grekf>),
    Mgpmf(Box<Mgpmf>),
}

/// The map-aided part of a `grekf` / `mgpmf` method.
struct MapAid {
    switch: ModeSwitch,
    aider: Aider,
    range_epochs: usize,
    beams: Vec<RangeBeam>,
}

impl MapAid {
    fn map_mode(&self) -> bool {
        self.switch.mode() == NavMode::MapAided
    }
}

/// A range epoch of the log: the beams with a direction, within the longest range.
struct RangeEpoch {
    beams: Vec<RangeBeam>,
    baro: Option<BaroHeight>,
}

/// One method running.
struct Runner {
    method: GnssInsMethod,
    mech: LocalLevelMechanization,
    accel_bias: Vector3<f64>,
    gyro_bias: Vector3<f64>,
    filter: Filter,
    map: Option<MapAid>,
    /// Fixes the 12-state filter rejected in a row (its re-acquisition).
    reacquire12: GpsReacquire,
    /// Fixes the 15-state filter rejected in a row.
    rejected_in_a_row: usize,
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

    /// The mode switch of a map-aided method sees a GNSS row at `t` with `satellites`
    /// (0: not used); entering the map-aided mode restarts the GREKF's lock.
    fn observe_gnss(&mut self, t: f64, satellites: usize) -> Result<(), SimError> {
        let Some(m) = &mut self.map else {
            return Ok(());
        };
        let before = m.switch.mode();
        let after = m.switch.observe(t, satellites).map_err(|e| {
            model(
                format!("`{}` mode switch at t = {t} s", self.method.name),
                e,
            )
        })?;
        if before != after
            && after == NavMode::MapAided
            && let Aider::Grekf(g) = &mut m.aider
        {
            g.reset();
        }
        let c = self.trace.map.get_or_insert_with(MapCounts::default);
        c.switches = m.switch.switches();
        Ok(())
    }

    /// The map-aided update of a range epoch at the filter time `t` (map-aided mode
    /// only); a failing update is counted, not an error.
    fn map_update(
        &mut self,
        ma: &MapAidedSettings,
        epoch: &RangeEpoch,
        world: &dyn RayCaster,
        t: f64,
    ) -> Result<(), SimError> {
        let nominal = self.nominal();
        let (Some(m), Filter::Ekf12(k)) = (&mut self.map, &mut self.filter) else {
            return Ok(());
        };
        m.range_epochs += 1;
        if !m.map_mode() {
            return Ok(());
        }
        let c = self.trace.map.get_or_insert_with(MapCounts::default);
        let grid = matches!(m.aider, Aider::Mgpmf(_));
        if grid && !(m.range_epochs - 1).is_multiple_of(ma.grid_every) {
            return Ok(());
        }
        let stride = if grid { ma.grid_beam_stride } else { 1 };
        m.beams.clear();
        m.beams.extend(epoch.beams.iter().step_by(stride).copied());
        if m.beams.is_empty() && epoch.baro.is_none() {
            return Ok(());
        }
        let baro = epoch.baro.as_ref();
        let ok = match &mut m.aider {
            Aider::Grekf(g) => match g.update(k, &nominal, &m.beams, baro, world) {
                Ok(rep) => {
                    if rep.all_beams_left_out {
                        c.map_left_out += 1;
                    } else {
                        c.map_updates += 1;
                    }
                    true
                }
                Err(_) => false,
            },
            Aider::Mgpmf(g) => {
                let ok = g.update(k, &nominal, &m.beams, baro, world).is_ok();
                c.map_updates += usize::from(ok);
                ok
            }
        };
        if ok {
            self.feedback(t)?;
        } else {
            c.map_failed += 1;
        }
        Ok(())
    }

    /// The GNSS update at the filter time `t` (`rel` from the start), with the
    /// re-acquisition after `gnss.reacquire_after_rejections` fixes rejected in a row
    /// ([`reacquire15`]; the 12-state filter: `map_aided::GpsReacquire`).
    fn update(&mut self, s: &GnssInsSettings, fix: &Fix, rel: f64, t: f64) -> Result<(), SimError> {
        if self.map.as_ref().is_some_and(MapAid::map_mode) {
            return Ok(());
        }
        let name = self.method.name.clone();
        let nominal = self.nominal();
        let dof = if s.use_velocity { 6 } else { 3 };
        let (accepted, nis, reset) = match &mut self.filter {
            Filter::None => return Ok(()),
            Filter::Ekf12(k) => {
                let aiding = GpsParams {
                    gate_probability: s.gate_probability,
                    reacquire_after_rejections: s.reacquire_after,
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
                match self.reacquire12.update(k, &nominal, &gps, &aiding) {
                    Ok(o) => (o.accepted, o.nis, o.reacquired),
                    Err(_) => (false, f64::NAN, false),
                }
            }
            Filter::Ekf15(k) => {
                let gate = GateThreshold::from_chi_square_probability(s.gate_probability, 3)
                    .map_err(|e| model(format!("`{name}` gate"), e))?;
                let (accepted, nis) = update15(k, &nominal, fix, s.use_velocity, gate);
                if accepted {
                    self.rejected_in_a_row = 0;
                    (true, nis, false)
                } else {
                    self.rejected_in_a_row += 1;
                    let n = s.reacquire_after;
                    match (n > 0 && self.rejected_in_a_row >= n)
                        .then(|| reacquire15(k, &nominal, fix, s.use_velocity, gate))
                        .flatten()
                    {
                        Some((k2, nis2)) => {
                            **k = k2;
                            self.rejected_in_a_row = 0;
                            (true, nis2, true)
                        }
                        None => (false, nis, false),
                    }
                }
            }
        };
        self.trace.updates.push(FixUpdate {
            time: rel,
            nis,
            dof,
            accepted,
            reset,
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
        if let Some(m) = &self.map {
            let mode = m.map_mode();
            self.trace.map_mode.get_or_insert_with(Vec::new).push(mode);
        }
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
    /// Where the world's origin lies in the frame (NED, m), with a world.
    pub world_shift: Option<[f64; 3]>,
}

/// Where the world's origin lies in the replay's frame: at `origin` (latitude,
/// longitude rad, altitude m) or, without one, at the frame's origin.
fn world_shift(frame: &LocalFrame, origin: Option<[f64; 3]>) -> [f64; 3] {
    origin.map_or([0.0; 3], |o| frame.ned([o[0], o[1]], o[2]))
}

/// The world mesh moved by `shift` (NED, m) into the replay's frame.
///
/// # Errors
/// [`SimError::Model`] for a vertex the mesh refuses after the move.
pub fn moved_mesh(mesh: &TriMesh, shift: [f64; 3]) -> Result<TriMesh, SimError> {
    let shift = Vector3::from(shift);
    let vertices = mesh.vertices().iter().map(|v| v + shift).collect();
    let (moved, _) = TriMesh::new(
        vertices,
        mesh.triangles().to_vec(),
        mesh.materials().to_vec(),
    )
    .map_err(|e| model("the world moved into the replay's frame".into(), e))?;
    Ok(moved)
}

/// The range epochs after `t0`: rows of one stamp with a beam direction and a
/// distance in (0, max range]; the barometric height of the latest `baro.csv` row at
/// or before the stamp, shifted by `baro_offset` (EKF2's altitude at the start minus
/// the baro's) and referred to `alt0`.
fn range_epochs(
    log: &GnssInsLog,
    ma: &MapAidedSettings,
    t0: f64,
    alt0: f64,
    baro_offset: Option<f64>,
) -> Vec<(f64, RangeEpoch)> {
    let rows: &[RangeRow] = log.range.as_deref().unwrap_or(&[]);
    let baro: &[(f64, f64)] = log.baro.as_deref().unwrap_or(&[]);
    let mut out: Vec<(f64, RangeEpoch)> = Vec::new();
    for r in rows.iter().filter(|r| r.time > t0) {
        if out.last().is_none_or(|(t, _)| *t != r.time) {
            let k = baro.partition_point(|b| b.0 <= r.time);
            let baro = match (baro_offset, k) {
                (Some(off), k) if k > 0 => Some(BaroHeight {
                    height_m: baro[k - 1].1 + off - alt0,
                    sigma_m: ma.baro_sigma,
                }),
                _ => None,
            };
            out.push((
                r.time,
                RangeEpoch {
                    beams: Vec::new(),
                    baro,
                },
            ));
        }
        if let (Some(d), Some(e)) = (r.dir_in_body(), out.last_mut())
            && r.distance > 0.0
            && r.distance <= ma.max_range
        {
            e.1.beams.push(RangeBeam {
                dir_in_body: Vector3::from(d),
                range_m: r.distance,
                sigma_m: ma.range_sigma,
            });
        }
    }
    out
}

/// Runs every method over the log (module docs); `world` is the mesh of the
/// map-aided methods (in the file's frame: moved here into the replay's).
///
/// # Errors
/// As [`start_row`]; [`SimError::Model`] naming the method and time of a failing
/// step.
pub fn run(
    log: &GnssInsLog,
    s: &GnssInsSettings,
    world: Option<&TriMesh>,
) -> Result<Pass, SimError> {
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
    let shift = s.world.as_ref().map(|w| world_shift(&frame, w.origin));
    let caster = match (world, shift) {
        (Some(mesh), Some(shift)) => Some(BvhCaster::new(&moved_mesh(mesh, shift)?)),
        _ => None,
    };
    let baro_offset = log.baro.as_deref().and_then(|b| {
        let k = b.partition_point(|x| x.0 <= t0);
        b.get(k.saturating_sub(1)).map(|x| r0.altitude - x.1)
    });
    let epochs = if caster.is_some() {
        range_epochs(log, &s.map_aided, t0, frame.alt0, baro_offset)
    } else {
        Vec::new()
    };
    let [sp, sv, sa, sba, sbg] = s.sigma0;
    let mut runners = Vec::with_capacity(s.methods.len());
    for m in &s.methods {
        let mech = LocalLevelMechanization::new(start, gravity)
            .map_err(|e| model(format!("`{}` start", m.name), e))?;
        let filter = match m.filter {
            GnssInsFilter::Ins => Filter::None,
            GnssInsFilter::Ekf12 | GnssInsFilter::Grekf | GnssInsFilter::Mgpmf => {
                Filter::Ekf12(Box::new(
                    Ins12Filter::new(
                        &Ins12Filter::diagonal_covariance([sp, sv, sa, sba]),
                        t0,
                        s.noise,
                    )
                    .map_err(|e| model(format!("`{}` start", m.name), e))?,
                ))
            }
            GnssInsFilter::Ekf15 => Filter::Ekf15(Box::new(
                ErrorStateFilter::new(
                    &ErrorStateFilter::diagonal_covariance([sp, sv, sa, sba, sbg]),
                    t0,
                )
                .map_err(|e| model(format!("`{}` start", m.name), e))?,
            )),
        };
        let aider = match m.filter {
            GnssInsFilter::Grekf => Some(Aider::Grekf(Box::new(Grekf::new(s.map_aided.grekf)))),
            GnssInsFilter::Mgpmf => Some(Aider::Mgpmf(Box::new(Mgpmf::new(s.map_aided.mgpmf)))),
            _ => None,
        };
        let map = match aider {
            Some(aider) if caster.is_some() => Some(MapAid {
                switch: ModeSwitch::new(s.map_aided.switch, NavMode::GpsIns, t0)
                    .map_err(|e| model(format!("`{}` mode switch", m.name), e))?,
                aider,
                range_epochs: 0,
                beams: Vec::new(),
            }),
            Some(_) => {
                return Err(SimError::invalid_argument(
                    format!("method `{}`", m.name),
                    "a map-aided filter needs a world (`--world FILE`)",
                ));
            }
            None => None,
        };
        let mut trace = MethodTrace::new(m.clone());
        if map.is_some() {
            trace.map = Some(MapCounts::default());
        }
        runners.push(Runner {
            method: m.clone(),
            mech,
            accel_bias: Vector3::zeros(),
            gyro_bias: Vector3::zeros(),
            filter,
            map,
            reacquire12: GpsReacquire::default(),
            rejected_in_a_row: 0,
            trace,
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
    let mut next_epoch = epochs.iter().peekable();
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
            let used = fix.fix_type >= s.min_fix_type && !s.in_outage(rel);
            let satellites = if used { fix.satellites as usize } else { 0 };
            for run in &mut runners {
                run.observe_gnss(fix.time, satellites)?;
            }
            if used {
                fixes_used += 1;
                let f = fix_of(&frame, fix, s);
                for run in &mut runners {
                    run.update(s, &f, t - t0, t)?;
                }
            }
            gnss.next();
        }
        if let Some(world) = &caster {
            while let Some((te, epoch)) = next_epoch.peek() {
                if *te > t {
                    break;
                }
                for run in &mut runners {
                    run.map_update(&s.map_aided, epoch, world, t)?;
                }
                next_epoch.next();
            }
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
        world_shift: caster.is_some().then_some(shift).flatten(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 15-state re-acquisition: a filter 50 m off rejects the fix; widened by
    /// the error the fix shows, the fix passes and the correction takes the estimate
    /// onto it; a consistent fix needs no re-acquisition.
    #[test]
    fn the_15_state_reacquisition_jumps_onto_the_fix() {
        let p0 = ErrorStateFilter::diagonal_covariance([1.0, 0.5, 0.05, 0.2, 0.01]);
        let mut k = ErrorStateFilter::new(&p0, 0.0).unwrap();
        let nominal = NominalNav {
            pos_in_nav: Vector3::zeros(),
            vel_in_nav: Vector3::zeros(),
            nav_from_body: UnitQuaternion::identity(),
            accel_bias_in_body: Vector3::zeros(),
        };
        let fix = Fix {
            pos: Vector3::new(30.0, -40.0, 2.0),
            pos_cov: Matrix3::identity(),
            vel: Vector3::new(1.0, 0.0, 0.0),
            vel_cov: Matrix3::identity() * 0.1,
        };
        let gate = GateThreshold::from_chi_square_probability(0.9999, 3).unwrap();
        let before = k.clone();
        assert!(!update15(&mut k, &nominal, &fix, true, gate).0);
        assert_eq!(k, before, "a rejected fix leaves the filter");
        let (mut k2, nis) = reacquire15(&k, &nominal, &fix, true, gate).unwrap();
        assert!(nis.is_finite() && nis < 2.0, "{nis}");
        let dx = k2.take_correction().unwrap();
        // estimated minus true: the nominal is (-30, 40, -2) from the fix
        assert!(
            (dx[0] + 30.0).abs() < 0.5 && (dx[1] - 40.0).abs() < 0.5,
            "{dx}"
        );
        let near = Fix {
            pos: Vector3::new(0.5, -0.5, 0.0),
            ..fix
        };
        let mut k3 = before.clone();
        assert!(update15(&mut k3, &nominal, &near, false, gate).0);
    }
}

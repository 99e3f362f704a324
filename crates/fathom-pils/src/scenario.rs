//! The run a PILS session flies, behind two small traits so the sides do not care
//! where the data comes from: [`SensorSource`] (the simulator: truth and the sensor
//! epochs) and [`Navigator`] (the navigation: epochs in, solutions out).
//!
//! [`MapAidedRun`] implements both on the library pieces, as `crates/fathom-cli/tests/e2e/map_aided.rs`
//! chains them: the quadrotor flies the `buildings` square (`fathom-traj`), the
//! ADIS16448 IMU (`fathom-sensors`), a GPS fix with the line-of-sight count of nine
//! fixed sky directions cast against the map, the paper's seven range finders or
//! the UST-20LX lidar (`fathom-sensors::map_range`), the barometer of eq. 20; the
//! navigation is the reduced mechanization with the 12-state filter and, per
//! method, GPS/INS, switching GREKF or switching MGPMF (`fathom-estimators`).
//! When the `urban` experiment's run is available its scenario replaces this one
//! behind the same traits.

use fathom_core::Material;
use fathom_estimators::map_aided::{
    BaroHeight, ErrorVector12, GpsFix, GpsParams, Grekf, Ins12Filter, Ins12Params, MapAider,
    Matrix12, Mgpmf, MgpmfParams, ModeSwitch, NavMode, NominalNav, RangeBeam, RangeParams,
    SwitchParams, SwitchingFilter,
};
use fathom_ins::ImuIncrement;
use fathom_ins::local_level::{
    LocalImuFromTruth, LocalLevelMechanization, LocalLevelState, LocalTruthSample,
};
use fathom_map::{BvhCaster, presets::BuildingsParams};
use fathom_sensors::allan_imu::AllanImuParams;
use fathom_sensors::barometer::{height_from_pressure, pressure_from_height};
use fathom_sensors::gnss::{LocalFrame, LocalFrameParams};
use fathom_sensors::inertial::ImuErrors;
use fathom_sensors::map_range::{LidarParams, RangeSensor, RangeSensorParams};
use fathom_traj::Trajectory;
use fathom_traj::quadrotor::{FlightParams, PathParams, QuadrotorParams, fly_on_truth};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::PilsError;
use crate::assemble::Due;
use crate::codec::RangeWire;
use crate::epoch::{Epoch, GpsFixReading, GpsReading, InitialEstimate, Solution};

/// The navigation methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// No aiding.
    #[serde(rename = "INS-only")]
    InsOnly,
    /// GPS/INS.
    #[serde(rename = "GPS/INS")]
    GpsIns,
    /// Switching GPS/INS and GREKF.
    #[serde(rename = "GREKF")]
    Grekf,
    /// Switching GPS/INS and MGPMF.
    #[serde(rename = "MGPMF")]
    Mgpmf,
}

impl Method {
    /// Every method.
    pub const ALL: [Method; 4] = [
        Method::InsOnly,
        Method::GpsIns,
        Method::Grekf,
        Method::Mgpmf,
    ];

    /// The name.
    pub fn name(self) -> &'static str {
        match self {
            Method::InsOnly => "INS-only",
            Method::GpsIns => "GPS/INS",
            Method::Grekf => "GREKF",
            Method::Mgpmf => "MGPMF",
        }
    }

    /// The method of a name.
    pub fn from_name(s: &str) -> Option<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
    }
}

/// The range sensor flown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ranging {
    /// Six horizontal beams at 60 deg and one down (`DISTANCE_SENSOR`).
    Rangefinders,
    /// The UST-20LX lidar, 109 beams (`OBSTACLE_DISTANCE`).
    Lidar,
}

/// Flight and sensor settings of a PILS run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunParams {
    /// Legs of the square flown (1 to 4; short runs for tests).
    pub legs: usize,
    /// Side of the square, m.
    pub side_m: f64,
    /// Flight height, m.
    pub height_m: f64,
    /// Cruise speed, m/s.
    pub speed_mps: f64,
    /// Hover at each corner, s.
    pub hover_s: f64,
    /// Rest on the ground before take-off (gyro calibration), s.
    pub rest_s: f64,
    /// IMU steps per GPS epoch (100 Hz IMU).
    pub gps_every: u64,
    /// IMU steps per range epoch.
    pub range_every: u64,
    /// Range epochs per map-aided update of the MGPMF.
    pub grid_every: u64,
    /// MGPMF grid points (north, east, yaw).
    pub grid_points: [usize; 3],
    /// Range sensor.
    pub ranging: Ranging,
    /// GPS position noise, m (1 sigma, per axis).
    pub gps_sigma_m: f64,
    /// Barometer height noise, m.
    pub baro_sigma_m: f64,
    /// Height of the NED origin above the ellipsoid (and sea level), m.
    pub origin_height_m: f64,
}

impl Default for RunParams {
    fn default() -> Self {
        Self {
            legs: 4,
            side_m: 100.0,
            height_m: 20.0,
            speed_mps: 3.0,
            hover_s: 2.0,
            rest_s: 5.0,
            gps_every: 20,
            range_every: 10,
            grid_every: 2,
            grid_points: [21, 21, 5],
            ranging: Ranging::Rangefinders,
            gps_sigma_m: 1.5,
            baro_sigma_m: 0.5,
            origin_height_m: 50.0,
        }
    }
}

/// IMU step, s (100 Hz).
pub const IMU_DT: f64 = 0.01;

/// The simulator side: truth and sensor epochs, step by step.
pub trait SensorSource {
    /// Steps of the run (the last step's index + 1).
    fn steps(&self) -> u64;
    /// The truth at step `k`.
    fn truth(&self, k: u64) -> &LocalTruthSample;
    /// The sensor epoch of step `k >= 1`.
    fn epoch(&self, k: u64) -> &Epoch;
    /// The initial estimate (sent at its step).
    fn initial(&self) -> &InitialEstimate;
}

/// The navigation side: epochs in time order, a solution per epoch once started.
pub trait Navigator {
    /// Processes one epoch (`init` at the start step); returns the solution after it.
    ///
    /// # Errors
    /// [`PilsError::Model`] when the mechanization diverges.
    fn step(
        &mut self,
        e: &Epoch,
        init: Option<&InitialEstimate>,
    ) -> Result<Option<Solution>, PilsError>;
}

/// What both sides share: the world, the frames, the schedule.
pub struct Shared {
    /// Settings.
    pub params: RunParams,
    /// The map (truth and estimators).
    pub map: BvhCaster,
    /// The GNSS local frame.
    pub frame: LocalFrame,
    /// The range sensor.
    pub sensor: RangeSensor,
    /// Its description on the wire.
    pub wire: RangeWire,
    /// Step at which navigation starts (end of the rest).
    pub start: u64,
}

fn model(what: &str) -> impl Fn(String) -> PilsError + '_ {
    move |e| PilsError::model(what, e)
}

impl Shared {
    /// Checks the settings and builds the world.
    ///
    /// # Errors
    /// [`PilsError::Setting`] / [`PilsError::Model`] naming what is wrong.
    pub fn new(params: RunParams) -> Result<Self, PilsError> {
        if !(1..=4).contains(&params.legs) {
            return Err(PilsError::setting(
                "run.legs",
                params.legs,
                "must be 1 to 4",
            ));
        }
        for (f, v) in [
            ("run.gps_every", params.gps_every),
            ("run.range_every", params.range_every),
            ("run.grid_every", params.grid_every),
        ] {
            if v == 0 {
                return Err(PilsError::setting(f, v, "must be >= 1"));
            }
        }
        let b = BuildingsParams {
            path_side_m: params.side_m,
            path_height_m: params.height_m,
            ..BuildingsParams::default()
        }
        .check()
        .map_err(|e| model("buildings")(e.to_string()))?;
        let mesh = b
            .mesh()
            .map_err(|e| model("buildings mesh")(e.to_string()))?;
        let map = BvhCaster::new(&mesh);
        let frame = LocalFrameParams {
            height_m: params.origin_height_m,
            ..LocalFrameParams::default()
        }
        .check()
        .map_err(|e| model("frame")(e.to_string()))?;
        let (sensor, wire) = match params.ranging {
            Ranging::Rangefinders => {
                let s = RangeSensorParams::paper_rangefinders()
                    .check()
                    .map_err(|e| model("range finders")(e.to_string()))?;
                let w = RangeWire::Beams {
                    dirs: s.beams().iter().map(|b| b.dir_in_body).collect(),
                    max_range_m: s.max_range(),
                };
                (s, w)
            }
            Ranging::Lidar => {
                let l = LidarParams::default();
                let s = l.check().map_err(|e| model("lidar")(e.to_string()))?;
                let w = RangeWire::Scan {
                    first_deg: l.first_deg,
                    step_deg: l.step_deg,
                    beams: s.beams().len(),
                    max_range_m: s.max_range(),
                };
                (s, w)
            }
        };
        let start = (params.rest_s / IMU_DT).round() as u64;
        Ok(Self {
            params,
            map,
            frame,
            sensor,
            wire,
            start,
        })
    }

    /// What is due at step `k`.
    pub fn due(&self, k: u64) -> Due {
        Due {
            gps: usize::from(k.is_multiple_of(self.params.gps_every)),
            ranges: if k.is_multiple_of(self.params.range_every) {
                self.wire.messages()
            } else {
                0
            },
            init: k == self.start,
        }
    }

    /// The filters' initial covariance.
    pub fn p0() -> Matrix12 {
        let mut d = ErrorVector12::zeros();
        for i in 0..3 {
            d[i] = 1.0;
            d[3 + i] = 0.1f64.powi(2);
            d[9 + i] = (2e-3 * 9.81f64).powi(2);
        }
        d[6] = 0.5f64.to_radians().powi(2);
        d[7] = 0.5f64.to_radians().powi(2);
        d[8] = 2f64.to_radians().powi(2);
        Matrix12::from_diagonal(&d)
    }
}

/// The simulated run (truth, epochs, initial estimate).
pub struct SimulatedRun {
    truth: Vec<LocalTruthSample>,
    epochs: Vec<Epoch>,
    initial: InitialEstimate,
}

impl SimulatedRun {
    /// Flies and senses run `run` of seed `seed`.
    ///
    /// # Errors
    /// [`PilsError::Model`] when the flight or a sensor refuses.
    pub fn new(sh: &Shared, seed: u64, run: u64) -> Result<Self, PilsError> {
        let p = &sh.params;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(run);
        let mut next = || ChaCha8Rng::seed_from_u64(rng.random());
        let (mut wind, mut init, mut imu_rng, mut gps_rng, mut range_rng, mut baro_rng) =
            (next(), next(), next(), next(), next(), next());
        let quad = QuadrotorParams {
            flight: FlightParams {
                rest_duration_s: p.rest_s,
                ..FlightParams::default()
            },
            ..QuadrotorParams::default()
        }
        .check()
        .map_err(|e| model("quadrotor")(e.to_string()))?;
        let mut path = PathParams::buildings_square(
            Vector3::zeros(),
            p.side_m,
            p.height_m,
            p.speed_mps,
            p.hover_s,
        );
        path.waypoints.truncate(2 + p.legs);
        let path = path.check().map_err(|e| model("path")(e.to_string()))?;
        let traj =
            fly_on_truth(&quad, &path, &mut wind).map_err(|e| model("flight")(e.to_string()))?;
        let n = (traj.end_time() / IMU_DT).floor() as u64;
        let mut truth = Vec::with_capacity(n as usize + 1);
        for k in 0..=n {
            let q = traj
                .quad_state_at(k as f64 * IMU_DT)
                .map_err(|e| model("truth")(e.to_string()))?;
            truth.push(LocalTruthSample {
                time: k as f64 * IMU_DT,
                pos_in_nav: q.body.pos_in_nav,
                vel_in_nav: q.body.vel_in_nav,
                nav_from_body: q.body.nav_from_body,
            });
        }
        let g = quad.vehicle.gravity();
        let mut inverter = LocalImuFromTruth::new(g).map_err(|e| model("IMU")(e.to_string()))?;
        let allan = AllanImuParams::adis16448()
            .check()
            .map_err(|e| model("IMU")(e.to_string()))?;
        let mut errors: ImuErrors = allan.error_spec().draw(&mut imu_rng);
        let sky = fathom_sensors::gnss::fixed_sky_directions();
        let mut epochs = Vec::with_capacity(truth.len());
        for (k, t) in truth.iter().enumerate() {
            let Some(inc) = inverter.push(t).map_err(|e| model("IMU")(e.to_string()))? else {
                continue;
            };
            let (dth, dv) = errors
                .corrupt(inc.dt, &inc.delta_theta, &inc.delta_v, &mut imu_rng)
                .map_err(|e| model("IMU errors")(e.to_string()))?;
            let k = k as u64;
            let due = sh.due(k);
            let mut gps = Vec::new();
            if due.gps > 0 {
                let los = fathom_sensors::gnss::los_count(&sh.map, &t.pos_in_nav, &sky);
                let noise = Vector3::from_fn(|_, _| p.gps_sigma_m * rng_normal(&mut gps_rng));
                gps.push(GpsReading {
                    id: 0,
                    fix: (los >= 4).then(|| GpsFixReading {
                        pos_in_nav: t.pos_in_nav + noise,
                        hdop: 1.0,
                        vdop: 1.0,
                    }),
                    los_count: los as u8,
                });
            }
            let (ranges, pressure) = if due.ranges > 0 {
                let scan = sh.sensor.scan(
                    &sh.map,
                    &t.pos_in_nav,
                    &t.nav_from_body.to_rotation_matrix(),
                    &mut range_rng,
                );
                let h =
                    p.origin_height_m - t.pos_in_nav.z + p.baro_sigma_m * rng_normal(&mut baro_rng);
                (
                    Some(scan.iter().map(|r| r.range_m).collect()),
                    Some(pressure_from_height(h)),
                )
            } else {
                (None, None)
            };
            epochs.push(Epoch {
                step: k,
                time: t.time,
                dt: inc.dt,
                delta_theta: dth,
                delta_v: dv,
                pressure_pa: pressure,
                gps,
                ranges,
            });
        }
        let s = &truth[(sh.start as usize).min(truth.len() - 1)];
        let l = Shared::p0()
            .cholesky()
            .ok_or_else(|| PilsError::Model("P0 not PD".into()))?
            .l();
        let dx = l * ErrorVector12::from_fn(|_, _| rng_normal(&mut init));
        let initial = InitialEstimate {
            step: sh.start,
            time: s.time,
            pos_in_nav: s.pos_in_nav + dx.fixed_rows::<3>(0),
            vel_in_nav: s.vel_in_nav + dx.fixed_rows::<3>(3),
            nav_from_body: UnitQuaternion::from_scaled_axis(Vector3::new(dx[6], dx[7], dx[8]))
                * s.nav_from_body,
        };
        Ok(Self {
            truth,
            epochs,
            initial,
        })
    }

    /// The epochs (step 1 onward).
    pub fn epochs(&self) -> &[Epoch] {
        &self.epochs
    }
}

fn rng_normal(rng: &mut ChaCha8Rng) -> f64 {
    rng.sample(StandardNormal)
}

impl SensorSource for SimulatedRun {
    fn steps(&self) -> u64 {
        self.truth.len() as u64
    }
    fn truth(&self, k: u64) -> &LocalTruthSample {
        &self.truth[(k as usize).min(self.truth.len() - 1)]
    }
    fn epoch(&self, k: u64) -> &Epoch {
        &self.epochs[(k.max(1) as usize - 1).min(self.epochs.len() - 1)]
    }
    fn initial(&self) -> &InitialEstimate {
        &self.initial
    }
}

enum Filter {
    Plain(Box<Ins12Filter>),
    Switching(Box<SwitchingFilter>),
}

/// The navigation of a method on the shared world (module docs).
pub struct MapAidedNav<'a> {
    sh: &'a Shared,
    method: Method,
    gyro_sum: Vector3<f64>,
    gyro_time: f64,
    gyro_bias: Vector3<f64>,
    accel_bias: Vector3<f64>,
    mech: Option<LocalLevelMechanization>,
    filter: Option<Filter>,
    baro: Option<BaroHeight>,
    range_epochs: u64,
    gravity: f64,
}

impl<'a> MapAidedNav<'a> {
    /// The navigation of `method`.
    ///
    /// # Errors
    /// [`PilsError::Model`] for settings the libraries refuse.
    pub fn new(sh: &'a Shared, method: Method) -> Result<Self, PilsError> {
        let g = QuadrotorParams::default()
            .check()
            .map_err(|e| model("quadrotor")(e.to_string()))?
            .vehicle
            .gravity();
        Ok(Self {
            sh,
            method,
            gyro_sum: Vector3::zeros(),
            gyro_time: 0.0,
            gyro_bias: Vector3::zeros(),
            accel_bias: Vector3::zeros(),
            mech: None,
            filter: None,
            baro: None,
            range_epochs: 0,
            gravity: g,
        })
    }

    fn start(&mut self, i: &InitialEstimate, los: Option<usize>) -> Result<(), PilsError> {
        self.gyro_bias = self.gyro_sum / self.gyro_time.max(1e-12);
        let state = LocalLevelState {
            pos_in_nav: i.pos_in_nav,
            vel_in_nav: i.vel_in_nav,
            nav_from_body: i.nav_from_body,
        };
        self.mech = Some(
            LocalLevelMechanization::new(state, self.gravity)
                .map_err(|e| model("mechanization")(e.to_string()))?,
        );
        let noise = Ins12Params::default()
            .check()
            .map_err(|e| model("noise")(e.to_string()))?;
        let f = Ins12Filter::new(&Shared::p0(), i.time, noise)
            .map_err(|e| model("filter")(e.to_string()))?;
        let sw = SwitchParams::default()
            .check()
            .map_err(|e| model("switch")(e.to_string()))?;
        let gps = GpsParams::default()
            .check()
            .map_err(|e| model("gps")(e.to_string()))?;
        let mode = match los {
            Some(n) if n < sw.leave_gps_below() => NavMode::MapAided,
            _ => NavMode::GpsIns,
        };
        let aider = match self.method {
            Method::Grekf => Some(MapAider::Grekf(Grekf::new(
                RangeParams::default()
                    .check()
                    .map_err(|e| model("range")(e.to_string()))?,
            ))),
            Method::Mgpmf => Some(MapAider::Mgpmf(Box::new(Mgpmf::new(
                MgpmfParams {
                    grid_points: self.sh.params.grid_points,
                    ..MgpmfParams::default()
                }
                .check()
                .map_err(|e| model("mgpmf")(e.to_string()))?,
            )))),
            _ => None,
        };
        self.filter = Some(match aider {
            Some(a) => Filter::Switching(Box::new(SwitchingFilter::new(
                f,
                ModeSwitch::new(sw, mode, i.time).map_err(|e| model("switch")(e.to_string()))?,
                gps,
                a,
            ))),
            None => Filter::Plain(Box::new(f)),
        });
        Ok(())
    }

    fn nominal(&self, mech: &LocalLevelMechanization) -> NominalNav {
        let s = mech.state();
        NominalNav {
            pos_in_nav: s.pos_in_nav,
            vel_in_nav: s.vel_in_nav,
            nav_from_body: s.nav_from_body,
            accel_bias_in_body: self.accel_bias,
        }
    }
}

impl Navigator for MapAidedNav<'_> {
    fn step(
        &mut self,
        e: &Epoch,
        init: Option<&InitialEstimate>,
    ) -> Result<Option<Solution>, PilsError> {
        if e.dt <= 0.0 || !e.dt.is_finite() {
            return Ok(None);
        }
        if let Some(p) = e.pressure_pa {
            self.baro = Some(BaroHeight {
                height_m: height_from_pressure(p) - self.sh.params.origin_height_m,
                sigma_m: self.sh.params.baro_sigma_m,
            });
        }
        if self.mech.is_none() {
            self.gyro_sum += e.delta_theta;
            self.gyro_time += e.dt;
            if let Some(i) = init {
                self.start(i, e.gps.first().map(|g| usize::from(g.los_count)))?;
            }
            return Ok(None);
        }
        let (Some(mech), Some(filter)) = (self.mech.as_mut(), self.filter.as_mut()) else {
            return Ok(None);
        };
        let t = e.time;
        let dth = e.delta_theta - self.gyro_bias * e.dt;
        let dv = e.delta_v - self.accel_bias * e.dt;
        let q0 = mech.state().nav_from_body;
        mech.step(&ImuIncrement::new(e.dt, dth, dv))
            .map_err(|x| PilsError::model(format!("mechanization at t = {t} s"), x))?;
        let f = dv / e.dt;
        match filter {
            Filter::Plain(fl) => fl.predict(&q0, &f, t),
            Filter::Switching(s) => s.predict(&q0, &f, t),
        }
        .map_err(|x| PilsError::model(format!("prediction at t = {t} s"), x))?;
        let s = mech.state();
        let nominal = NominalNav {
            pos_in_nav: s.pos_in_nav,
            vel_in_nav: s.vel_in_nav,
            nav_from_body: s.nav_from_body,
            accel_bias_in_body: self.accel_bias,
        };
        let mut updated = false;
        let gps = GpsParams::default()
            .check()
            .map_err(|x| model("gps")(x.to_string()))?;
        for g in &e.gps {
            let fix = g.fix.map(|f| GpsFix {
                pos_in_nav: f.pos_in_nav,
                pos_cov: Matrix3::from_diagonal(&Vector3::new(
                    f.hdop * f.hdop,
                    f.hdop * f.hdop,
                    f.vdop * f.vdop,
                )) * self.sh.params.gps_sigma_m.powi(2),
                velocity: None,
            });
            match filter {
                Filter::Plain(fl) if self.method == Method::GpsIns => {
                    if let Some(fx) = &fix {
                        updated |= fl.update_gps(&nominal, fx, &gps).is_ok_and(|o| o.accepted);
                    }
                }
                Filter::Plain(_) => {}
                Filter::Switching(sf) => {
                    sf.observe_los(t, usize::from(g.los_count))
                        .map_err(|x| model("switch")(x.to_string()))?;
                    if let Some(fx) = &fix {
                        updated |= matches!(sf.update_gps(&nominal, fx), Ok(Some(o)) if o.accepted);
                    }
                }
            }
        }
        if let (Some(r), Filter::Switching(sf)) = (&e.ranges, &mut *filter) {
            self.range_epochs += 1;
            let grid = self.method == Method::Mgpmf;
            if !grid || (self.range_epochs - 1).is_multiple_of(self.sh.params.grid_every) {
                let beams: Vec<RangeBeam> = r
                    .iter()
                    .zip(self.sh.sensor.beams())
                    .filter_map(|(r, b)| {
                        r.map(|range| RangeBeam {
                            dir_in_body: b.dir_in_body,
                            range_m: range,
                            sigma_m: self.sh.sensor.sigma(range, Material::Opaque).max(1e-3),
                        })
                    })
                    .collect();
                if let Ok(Some(_)) =
                    sf.update_map(&nominal, &beams, self.baro.as_ref(), &self.sh.map)
                {
                    updated = true;
                }
            }
        }
        if updated {
            let c = match filter {
                Filter::Plain(fl) => fl.take_correction(),
                Filter::Switching(sf) => sf.take_correction(),
            };
            let nav = c.apply(&nominal);
            mech.set_state(LocalLevelState {
                pos_in_nav: nav.pos_in_nav,
                vel_in_nav: nav.vel_in_nav,
                nav_from_body: nav.nav_from_body,
            })
            .map_err(|x| PilsError::model(format!("feedback at t = {t} s"), x))?;
            self.accel_bias = nav.accel_bias_in_body;
        }
        let (Some(mech), Some(filter)) = (self.mech.as_ref(), self.filter.as_ref()) else {
            return Ok(None);
        };
        let (p, map_aided) = match filter {
            Filter::Plain(fl) => (fl.covariance(), false),
            Filter::Switching(sf) => (sf.filter().covariance(), sf.mode() == NavMode::MapAided),
        };
        let n = self.nominal(mech);
        Ok(Some(Solution {
            step: e.step,
            time: t,
            pos_in_nav: n.pos_in_nav,
            vel_in_nav: n.vel_in_nav,
            nav_from_body: n.nav_from_body,
            omega_body: dth / e.dt,
            pos_cov: p.fixed_view::<3, 3>(0, 0).into_owned(),
            att_cov: p.fixed_view::<3, 3>(6, 6).into_owned(),
            pos_att_cov: p.fixed_view::<3, 3>(0, 6).into_owned(),
            vel_cov: p.fixed_view::<3, 3>(3, 3).into_owned(),
            map_aided,
        }))
    }
}

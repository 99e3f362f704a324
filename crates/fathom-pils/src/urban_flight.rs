//! An `urban` scenario flown through the link: one scene of the scenario, flown and
//! sensed by the `urban` experiment's own simulation (`fathom_experiments::urban`),
//! and one of its methods navigated by the same [`Navigation`] its offline Monte
//! Carlo runs use. [`UrbanFlight`] is what both sides share (the prepared scenario
//! and the stream's [`Schedule`]); [`UrbanRun`] is the simulator's truth and epochs
//! ([`SensorSource`]); [`UrbanNav`] is the navigation ([`Navigator`]).
//!
//! The epochs on the wire carry what the sensors measured: the IMU increments, the
//! barometer's pressure at the range epochs, every satellite above the mask with its
//! pseudorange (`GNSS_RAW`; the navigation tests the line of sight against its own
//! map, as offline), the receiver's fix from every received satellite (`HIL_GPS`,
//! for a ground station) and the ranges per beam. The navigation rebuilds the
//! offline run's sensor epoch from them with the scenario's sensor model (beam
//! directions, the σ at the measured range, the barometer's conversion): without
//! quantization that rebuild is exact, so run `i` of the flight navigates exactly
//! as run `i` of `fathom run` (tested).

use std::path::Path;

use fathom_core::Material;
use fathom_estimators::map_aided::{BaroHeight, ErrorVector12, RangeBeam};
use fathom_experiments::urban::Urban;
use fathom_experiments::urban::nav::{Method, NavEnv, NavStart};
use fathom_experiments::urban::run::{fly_and_sense, initial_error, nav_env};
use fathom_experiments::urban::runner::{Fed, Navigation, range_every, sensor_of, start_sample};
use fathom_experiments::urban::scenario::Ranging;
use fathom_experiments::urban::sense::{
    BeamReturn, GnssEpoch, RangeEpoch, SatMeasurement, SensorEpoch, Streams, baro_height,
};
use fathom_experiments::urban::world::Prepared;
use fathom_ins::ImuIncrement;
use fathom_ins::local_level::LocalTruthSample;
use fathom_sensors::gnss::geodesy::geodetic_from_ecef;
use fathom_sensors::gnss::solve_spp;
use fathom_sensors::magnetic::{Dipole, field_in_body};
use fathom_sensors::map_range::RangeSensor;
use fathom_sim::experiment::{Environment, prepare_typed};
use fathom_sim::montecarlo::run_rng;
use nalgebra::Vector3;
use rand_chacha::ChaCha8Rng;
use sha2::{Digest, Sha256};

use crate::PilsError;
use crate::assemble::Schedule;
use crate::codec::RangeWire;
use crate::epoch::{Epoch, GpsFixReading, GpsReading, InitialEstimate, SatReading, Solution};
use crate::source::{IMU_DT, Navigator, SensorSource};

/// What both sides of a session share: the prepared `urban` scenario, the scene and
/// method flown, the run, and the stream's schedule.
pub struct UrbanFlight {
    /// The prepared scenario (worlds built, satellites chosen).
    pub prep: Prepared,
    /// Index of the scene flown.
    pub scene: usize,
    /// The method navigated.
    pub method: Method,
    /// The scenario's base seed.
    pub seed: u64,
    /// The run index (its own random streams, as run `run` of `fathom run`).
    pub run: u64,
    /// The frame, the wire and the schedule of the stream.
    pub schedule: Schedule,
}

fn setting(field: &str, value: impl std::fmt::Display, reason: impl Into<String>) -> PilsError {
    PilsError::setting(field, value, reason)
}

fn model(what: &str, e: impl std::fmt::Display) -> PilsError {
    PilsError::model(what, e)
}

impl UrbanFlight {
    /// Reads, checks and prepares the `urban` scenario `text` (as `fathom run` does,
    /// data looked up from `base_dir`) and picks the scene and method (`None`: the
    /// first scene, the scenario's first map-aided method or else its first).
    ///
    /// # Errors
    /// The scenario's errors; a scene or method the scenario does not have; an IMU
    /// rate other than the link's 100 Hz.
    pub fn load(
        text: &str,
        file: &str,
        base_dir: &Path,
        scene: Option<&str>,
        method: Option<&str>,
        run: u64,
    ) -> Result<Self, PilsError> {
        let (prep, resolved) = prepare_typed(&Urban, text, file, &Environment::new(base_dir))
            .map_err(|e| model(file, e))?;
        let c = &prep.checked;
        let scene = match scene {
            None => 0,
            Some(name) => c
                .scenes
                .iter()
                .position(|s| s.name == name)
                .ok_or_else(|| {
                    let names: Vec<&str> = c.scenes.iter().map(|s| s.name.as_str()).collect();
                    setting(
                        "scene",
                        name,
                        format!("the scenario's scenes are {names:?}"),
                    )
                })?,
        };
        let method = match method {
            None => c
                .methods
                .iter()
                .copied()
                .find(|m| m.is_switching())
                .or_else(|| c.methods.first().copied())
                .ok_or_else(|| setting("methods", "[]", "the scenario runs no method"))?,
            Some(name) => Method::from_name(name)
                .filter(|m| c.methods.contains(m))
                .ok_or_else(|| {
                    let names: Vec<&str> = c.methods.iter().map(|m| m.name()).collect();
                    setting(
                        "method",
                        name,
                        format!("the scenario's methods are {names:?}"),
                    )
                })?,
        };
        let seed = resolved.base_seed.unwrap_or(0);
        let mut fl = Self::new(prep, seed, scene, method, run)?;
        let hash = Sha256::digest(resolved.toml.as_bytes());
        let hex: String = hash.iter().take(4).map(|b| format!("{b:02x}")).collect();
        fl.schedule.identity = Some(format!(
            "{}/{} run {run} #{hex}",
            fl.scene_name(),
            fl.method.name()
        ));
        Ok(fl)
    }

    /// The flight of scene `scene` and `method` in run `run` of a prepared scenario
    /// (no identity on the link: [`UrbanFlight::load`] sets it from the scenario).
    ///
    /// # Errors
    /// A scene index out of range; an IMU rate other than the link's 100 Hz.
    pub fn new(
        prep: Prepared,
        seed: u64,
        scene: usize,
        method: Method,
        run: u64,
    ) -> Result<Self, PilsError> {
        let c = &prep.checked;
        let Some(spec) = c.scenes.get(scene) else {
            return Err(setting("scene", scene, "out of range"));
        };
        if (c.imu.dt() - IMU_DT).abs() > 1e-12 {
            return Err(setting(
                "imu.rate_hz",
                c.imu.rate_hz(),
                "the link's steps are 10 ms: processor-in-the-loop needs 100 Hz",
            ));
        }
        let sensor = sensor_of(&prep, spec.ranging);
        let wire = wire_of(sensor, spec.ranging);
        let schedule = Schedule {
            frame: *prep.receiver.frame(),
            wire,
            start: start_sample(&prep) as u64,
            gps_every: c.steps.gnss as u64,
            range_every: range_every(&prep, spec.ranging) as u64,
            raw_gnss: true,
            identity: None,
        };
        Ok(Self {
            prep,
            scene,
            method,
            seed,
            run,
            schedule,
        })
    }

    /// The scene's name.
    pub fn scene_name(&self) -> &str {
        &self.prep.checked.scenes[self.scene].name
    }

    /// The navigation environment of the scene (the map, the frame, the filters).
    pub fn env(&self) -> NavEnv<'_> {
        let spec = &self.prep.checked.scenes[self.scene];
        nav_env(&self.prep, &self.prep.scenes[self.scene], spec.ranging)
    }

    /// The scene's range sensor.
    pub fn sensor(&self) -> &RangeSensor {
        sensor_of(&self.prep, self.prep.checked.scenes[self.scene].ranging)
    }

    /// The run's per-sensor random streams (as `fathom run` seeds run `run`).
    fn streams(&self) -> Streams {
        Streams::from_run(&mut run_rng(self.seed, self.run as usize))
    }
}

/// The wire's description of the scene's range sensor: the range finders beam by
/// beam, the lidar as a planar scan (first azimuth and step from its beams).
fn wire_of(sensor: &RangeSensor, ranging: Ranging) -> RangeWire {
    let beams = sensor.beams();
    match ranging {
        Ranging::Rangefinders => RangeWire::Beams {
            dirs: beams.iter().map(|b| b.dir_in_body).collect(),
            max_range_m: sensor.max_range(),
        },
        Ranging::Lidar => {
            let az = |i: usize| {
                beams
                    .get(i)
                    .map_or(0.0, |b| b.dir_in_body.y.atan2(b.dir_in_body.x).to_degrees())
            };
            RangeWire::Scan {
                first_deg: az(0),
                step_deg: if beams.len() > 1 { az(1) - az(0) } else { 0.0 },
                beams: beams.len(),
                max_range_m: sensor.max_range(),
            }
        }
    }
}

/// The simulator's side of a flight: the truth, the offline run's sensor epochs and
/// their wire form, the initial estimate.
pub struct UrbanRun {
    truth: Vec<LocalTruthSample>,
    sensed: Vec<SensorEpoch>,
    epochs: Vec<Epoch>,
    initial: InitialEstimate,
}

impl UrbanRun {
    /// Flies and senses the flight's run, as `fathom run` does for that run index.
    ///
    /// # Errors
    /// A flight or truth the models refuse.
    pub fn new(fl: &UrbanFlight) -> Result<Self, PilsError> {
        let prep = &fl.prep;
        let mut streams = fl.streams();
        let dx0: ErrorVector12 =
            initial_error(prep, &mut streams.init).map_err(|e| model("initial error", e))?;
        let spec = &prep.checked.scenes[fl.scene];
        let flown = fly_and_sense(
            prep,
            &prep.scenes[fl.scene],
            spec.ranging,
            fl.sensor(),
            &streams,
        )
        .map_err(|e| model("urban flight", e))?;
        let field = site_field_gauss(&fl.schedule.frame);
        let epochs = flown
            .epochs
            .iter()
            .enumerate()
            .map(|(i, e)| to_wire(fl, i as u64 + 1, &flown.truth[i + 1], &field, e))
            .collect();
        let start = fl.schedule.start as usize;
        let Some(at_start) = flown.truth.get(start) else {
            return Err(setting(
                "vehicle.rest_s",
                prep.checked.rest_s,
                "the flight ends before the navigation starts",
            ));
        };
        let s = NavStart::from_truth(at_start, &dx0);
        Ok(Self {
            initial: InitialEstimate {
                step: start as u64,
                time: s.time,
                pos_in_nav: s.pos_in_nav,
                vel_in_nav: s.vel_in_nav,
                nav_from_body: s.nav_from_body,
            },
            truth: flown.truth,
            sensed: flown.epochs,
            epochs,
        })
    }

    /// The epochs on the wire (step 1 onward).
    pub fn epochs(&self) -> &[Epoch] {
        &self.epochs
    }

    /// The offline run's sensor epochs (`sensed()[k - 1]` is step `k`'s).
    pub fn sensed(&self) -> &[SensorEpoch] {
        &self.sensed
    }
}

impl SensorSource for UrbanRun {
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

/// The magnetic field at the frame's origin (IGRF-13 dipole), NED, gauss.
fn site_field_gauss(frame: &fathom_sensors::gnss::LocalFrame) -> Vector3<f64> {
    let (lat, lon, h) = geodetic_from_ecef(&frame.origin_ecef());
    Dipole::IGRF13_2020.field_ned_nt(lat, lon, h) * 1e-5
}

/// The wire form of step `k`'s sensor epoch, with the truth at its end (for the
/// magnetometer) and the site's field (NED, gauss).
fn to_wire(
    fl: &UrbanFlight,
    k: u64,
    truth: &LocalTruthSample,
    field_nav_gauss: &Vector3<f64>,
    e: &SensorEpoch,
) -> Epoch {
    let t = truth.time;
    let frame = &fl.schedule.frame;
    let (gps, raw_gnss) = match &e.gnss {
        Some(g) => {
            let received: Vec<_> = g
                .sats
                .iter()
                .filter_map(|s| s.pseudorange_m.map(|rho| (s.pos_ecef, rho)))
                .collect();
            let fix = (received.len() >= 4)
                .then(|| solve_spp(frame, &received).ok())
                .flatten()
                .map(|sol| GpsFixReading {
                    pos_in_nav: sol.pos_in_nav,
                    hdop: sol.dop.hdop,
                    vdop: sol.dop.vdop,
                });
            let reading = GpsReading {
                id: 0,
                fix,
                los_count: received.len().min(255) as u8,
            };
            let sats = g
                .sats
                .iter()
                .map(|s| SatReading {
                    pos_ecef: s.pos_ecef,
                    pseudorange_m: s.pseudorange_m,
                })
                .collect();
            (vec![reading], Some(sats))
        }
        None => (Vec::new(), None),
    };
    let ranges = e.ranges.as_ref().map(|r| {
        let mut v = vec![None; fl.sensor().beams().len()];
        for b in &r.returns {
            if let Some(slot) = v.get_mut(b.beam) {
                *slot = Some(b.reading.range_m);
            }
        }
        v
    });
    Epoch {
        step: k,
        time: t,
        dt: e.imu.dt,
        delta_theta: e.imu.delta_theta,
        delta_v: e.imu.delta_v,
        pressure_pa: e.ranges.as_ref().map(|r| r.pressure_pa),
        mag_body_gauss: Some(field_in_body(&truth.nav_from_body, field_nav_gauss)),
        gps,
        raw_gnss,
        ranges,
    }
}

/// The offline run's sensor epoch rebuilt from the wire form with the scenario's
/// sensor model; `pressure_pa` is the latest pressure received (ranges without one
/// are dropped).
fn from_wire(fl: &UrbanFlight, e: &Epoch, pressure_pa: Option<f64>) -> SensorEpoch {
    let c = &fl.prep.checked;
    let sensor = fl.sensor();
    let gnss = e.raw_gnss.as_ref().map(|sats| GnssEpoch {
        sats: sats
            .iter()
            .map(|s| SatMeasurement {
                pos_ecef: s.pos_ecef,
                pseudorange_m: s.pseudorange_m,
                true_los: false,
            })
            .collect(),
    });
    let ranges = e.ranges.as_ref().zip(pressure_pa).map(|(r, p)| RangeEpoch {
        returns: r
            .iter()
            .zip(sensor.beams())
            .enumerate()
            .filter_map(|(i, (r, b))| {
                r.map(|range| BeamReturn {
                    beam: i,
                    reading: RangeBeam {
                        dir_in_body: b.dir_in_body,
                        range_m: range,
                        sigma_m: sensor.sigma(range, Material::Opaque).max(1e-3),
                    },
                })
            })
            .collect(),
        baro: BaroHeight {
            height_m: baro_height(&c.baro, p),
            sigma_m: c.baro.filter_sigma,
        },
        pressure_pa: p,
    });
    SensorEpoch {
        imu: ImuIncrement::new(e.dt, e.delta_theta, e.delta_v),
        gnss,
        ranges,
    }
}

/// The navigation side of a flight: the `urban` method on the epochs as they arrive.
pub struct UrbanNav<'e> {
    fl: &'e UrbanFlight,
    navigation: Navigation<'e>,
    pressure_pa: Option<f64>,
}

impl<'e> UrbanNav<'e> {
    /// The flight's method on the scene's environment `env` (from [`UrbanFlight::env`]).
    pub fn new(fl: &'e UrbanFlight, env: &'e NavEnv<'e>) -> Self {
        let particle: ChaCha8Rng = fl.streams().particle;
        Self {
            fl,
            navigation: Navigation::new(env, fl.method, fl.schedule.start as usize, &particle),
            pressure_pa: None,
        }
    }
}

impl Navigator for UrbanNav<'_> {
    fn step(
        &mut self,
        e: &Epoch,
        init: Option<&InitialEstimate>,
    ) -> Result<Option<Solution>, PilsError> {
        if !(e.dt > 0.0 && e.dt.is_finite()) {
            return Ok(None);
        }
        if e.pressure_pa.is_some() {
            self.pressure_pa = e.pressure_pa;
        }
        let epoch = from_wire(self.fl, e, self.pressure_pa);
        let start = init.map(|i| NavStart {
            time: i.time,
            pos_in_nav: i.pos_in_nav,
            vel_in_nav: i.vel_in_nav,
            nav_from_body: i.nav_from_body,
        });
        let fed = self
            .navigation
            .feed(e.step as usize, e.time, &epoch, start.as_ref())
            .map_err(|x| model(self.fl.method.name(), x))?;
        if !matches!(fed, Fed::Stepped { .. }) {
            return Ok(None);
        }
        let Some(nav) = self.navigation.nav() else {
            return Ok(None);
        };
        let n = nav.nominal();
        let p = nav.covariance();
        Ok(Some(Solution {
            step: e.step,
            time: e.time,
            pos_in_nav: n.pos_in_nav,
            vel_in_nav: n.vel_in_nav,
            nav_from_body: n.nav_from_body,
            omega_body: nav.control_state().omega_body,
            pos_cov: p.fixed_view::<3, 3>(0, 0).into_owned(),
            att_cov: p.fixed_view::<3, 3>(6, 6).into_owned(),
            pos_att_cov: p.fixed_view::<3, 3>(0, 6).into_owned(),
            vel_cov: p.fixed_view::<3, 3>(3, 3).into_owned(),
            map_aided: nav.map_aided(),
        }))
    }
}

#[cfg(test)]
#[path = "urban_flight_tests.rs"]
pub(crate) mod tests;

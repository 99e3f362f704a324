//! The sensors of one `urban` run, generated sample by sample from the truth: the
//! IMU increments (ADIS16448 errors), GNSS observations with the line of sight cast
//! against the map, range-finder or lidar scans, and the barometer (eq. 20).
//!
//! Every sensor draws from its own stream (seeded from the run's RNG in a fixed
//! order), so a change in one sensor (the lidar step, glass treated as opaque) leaves
//! the others' numbers unchanged, and every method of a run sees the same data
//! (common random numbers). The same generator serves the offline runs (truth flown
//! first) and the closed loop (truth flown on an estimate, one sample at a time).

use fathom_core::{Material, RayCaster};
use fathom_estimators::map_aided::{BaroHeight, RangeBeam};
use fathom_ins::ImuIncrement;
use fathom_ins::local_level::{LocalImuFromTruth, LocalTruthSample};
use fathom_sensors::barometer::pressure_from_height;
use fathom_sensors::gnss::GnssReceiver;
use fathom_sensors::inertial::ImuErrors;
use fathom_sensors::map_range::RangeSensor;
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::check::{BaroConversion, BaroSetup, Checked};
use fathom_sim::SimError;

/// One satellite above the mask at a GNSS epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatMeasurement {
    /// Satellite position, ECEF, m.
    pub pos_ecef: Vector3<f64>,
    /// Pseudorange when a signal is received (LOS, or NLOS reflected), m.
    pub pseudorange_m: Option<f64>,
    /// Whether the true receiver position sees the satellite (for the figures).
    pub true_los: bool,
}

/// A GNSS epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct GnssEpoch {
    /// The satellites above the mask.
    pub sats: Vec<SatMeasurement>,
}

impl GnssEpoch {
    /// Satellites the true position sees.
    pub fn true_los_count(&self) -> usize {
        self.sats.iter().filter(|s| s.true_los).count()
    }
}

/// One returned beam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamReturn {
    /// Beam index in the sensor.
    pub beam: usize,
    /// The beam as the filters take it (body direction, measured range, the σ the
    /// filter assumes: the sensor's opaque-surface model at the measured range).
    pub reading: RangeBeam,
}

/// A range-sensor epoch with the barometer read at the same instant.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeEpoch {
    /// The beams that returned, in beam order.
    pub returns: Vec<BeamReturn>,
    /// Baro height above the NED origin as the filter converts it.
    pub baro: BaroHeight,
    /// The static pressure the barometer read, Pa (what a processor-in-the-loop
    /// link carries; `baro` is its conversion).
    pub pressure_pa: f64,
}

/// What the sensors give at one IMU sample (after the first).
#[derive(Debug, Clone, PartialEq)]
pub struct SensorEpoch {
    /// The measured increment over the last IMU interval.
    pub imu: ImuIncrement,
    /// A GNSS epoch at this instant.
    pub gnss: Option<GnssEpoch>,
    /// A range epoch at this instant.
    pub ranges: Option<RangeEpoch>,
}

/// The per-sensor random streams of a run.
#[derive(Debug, Clone)]
pub struct Streams {
    /// Wind gusts of the flight.
    pub wind: ChaCha8Rng,
    /// Initial estimation error.
    pub init: ChaCha8Rng,
    /// IMU errors.
    pub imu: ChaCha8Rng,
    /// GNSS.
    pub gnss: ChaCha8Rng,
    /// Range sensor.
    pub range: ChaCha8Rng,
    /// Barometer.
    pub baro: ChaCha8Rng,
    /// The particle filter's resampling.
    pub particle: ChaCha8Rng,
}

impl Streams {
    /// Seeds every stream from `rng`, in a fixed order.
    pub fn from_run(rng: &mut ChaCha8Rng) -> Self {
        let mut next = || ChaCha8Rng::seed_from_u64(rng.random());
        Self {
            wind: next(),
            init: next(),
            imu: next(),
            gnss: next(),
            range: next(),
            baro: next(),
            particle: next(),
        }
    }
}

/// The filter's height above the origin from a pressure.
pub fn baro_height(baro: &BaroSetup, pressure: f64) -> f64 {
    let above_sea = match baro.conversion {
        BaroConversion::Linear(cal) => cal.height(pressure),
        BaroConversion::Exact => fathom_sensors::barometer::height_from_pressure(pressure),
    };
    above_sea - baro.origin_height
}

/// The sensor generator of a run (module docs).
pub struct Sensing<'a> {
    checked: &'a Checked,
    map: &'a dyn RayCaster,
    receiver: &'a GnssReceiver,
    ranging: &'a RangeSensor,
    range_every: usize,
    imu_errors: ImuErrors,
    inverter: LocalImuFromTruth,
    imu_rng: ChaCha8Rng,
    gnss_rng: ChaCha8Rng,
    range_rng: ChaCha8Rng,
    baro_rng: ChaCha8Rng,
    samples: usize,
}

impl<'a> Sensing<'a> {
    /// A generator for one run; `ranging` is the scenario's range sensor (possibly
    /// changed by an ablation) sampled every `range_every` IMU steps.
    ///
    /// # Errors
    /// [`SimError::Model`] for a non-finite gravity (not expected).
    pub fn new(
        checked: &'a Checked,
        map: &'a dyn RayCaster,
        receiver: &'a GnssReceiver,
        ranging: &'a RangeSensor,
        range_every: usize,
        streams: &Streams,
    ) -> Result<Self, SimError> {
        let mut imu_rng = streams.imu.clone();
        let imu_errors = checked.imu.error_spec().draw(&mut imu_rng);
        Ok(Self {
            checked,
            map,
            receiver,
            ranging,
            range_every,
            imu_errors,
            inverter: LocalImuFromTruth::new(checked.quad.vehicle.gravity())
                .map_err(|e| SimError::model("IMU from truth", e))?,
            imu_rng,
            gnss_rng: streams.gnss.clone(),
            range_rng: streams.range.clone(),
            baro_rng: streams.baro.clone(),
            samples: 0,
        })
    }

    /// The current true accelerometer bias (body, m/s²).
    pub fn true_accel_bias(&self) -> Vector3<f64> {
        self.imu_errors.accel_bias()
    }

    /// Takes the next truth sample (IMU rate, time order); `None` for the first, then
    /// the increment since the previous sample and the events at this one.
    ///
    /// # Errors
    /// [`SimError::Model`] for a truth the IMU inversion refuses.
    pub fn push(&mut self, truth: &LocalTruthSample) -> Result<Option<SensorEpoch>, SimError> {
        let index = self.samples;
        self.samples += 1;
        let Some(inc) = self
            .inverter
            .push(truth)
            .map_err(|e| SimError::model(format!("IMU from truth at t = {} s", truth.time), e))?
        else {
            return Ok(None);
        };
        let (dth, dv) = self
            .imu_errors
            .corrupt(inc.dt, &inc.delta_theta, &inc.delta_v, &mut self.imu_rng)
            .map_err(|e| SimError::model("IMU errors", e))?;
        let steps = &self.checked.steps;
        let gnss = index
            .is_multiple_of(steps.gnss)
            .then(|| self.gnss_epoch(truth));
        let ranges = index
            .is_multiple_of(self.range_every)
            .then(|| self.range_epoch(truth));
        Ok(Some(SensorEpoch {
            imu: ImuIncrement::new(inc.dt, dth, dv),
            gnss,
            ranges,
        }))
    }

    fn gnss_epoch(&mut self, truth: &LocalTruthSample) -> GnssEpoch {
        let obs = self.receiver.observe(
            self.map,
            truth.time,
            &truth.pos_in_nav,
            &truth.vel_in_nav,
            &mut self.gnss_rng,
        );
        GnssEpoch {
            sats: obs
                .iter()
                .map(|o| SatMeasurement {
                    pos_ecef: o.state.pos_ecef,
                    pseudorange_m: o.pseudorange_m,
                    true_los: o.los,
                })
                .collect(),
        }
    }

    fn range_epoch(&mut self, truth: &LocalTruthSample) -> RangeEpoch {
        let sensor = self.ranging;
        let rot = truth.nav_from_body.to_rotation_matrix();
        let scan = sensor.scan(self.map, &truth.pos_in_nav, &rot, &mut self.range_rng);
        let returns = scan
            .iter()
            .filter_map(|r| {
                let range = r.range_m?;
                Some(BeamReturn {
                    beam: r.beam,
                    reading: RangeBeam {
                        dir_in_body: sensor.beams()[r.beam].dir_in_body,
                        range_m: range,
                        sigma_m: sensor.sigma(range, Material::Opaque).max(1e-3),
                    },
                })
            })
            .collect();
        let baro = &self.checked.baro;
        let z: f64 = self.baro_rng.sample(StandardNormal);
        let h_true = baro.origin_height - truth.pos_in_nav.z;
        let p = pressure_from_height(h_true + baro.sigma * z);
        RangeEpoch {
            returns,
            baro: BaroHeight {
                height_m: baro_height(baro, p),
                sigma_m: baro.filter_sigma,
            },
            pressure_pa: p,
        }
    }
}

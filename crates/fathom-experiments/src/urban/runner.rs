//! One method stepped over a run's sensor epochs (`Runner`: gyro calibration over
//! the rest, the start of navigation, one IMU step and its sensor events at a time,
//! the evaluation), shared by the truth-controlled run ([`super::run`]) and the
//! control-on-estimate flight ([`super::closed_loop`]).

use fathom_estimators::map_aided::{ErrorVector12, NavMode};
use fathom_ins::local_level::LocalTruthSample;
use nalgebra::Vector3;
use rand_chacha::ChaCha8Rng;

use super::nav::{Method, Nav, NavCounts, NavEnv, NavStart, los_satellites};
use super::record::{GridSnapshot, MethodRecord};
use super::scenario::Ranging;
use super::sense::{SensorEpoch, Streams};
use super::trace::Trace;
use super::world::Prepared;
use fathom_sim::SimError;
/// IMU steps per range epoch of a scenario's sensor.
pub fn range_every(prep: &Prepared, ranging: Ranging) -> usize {
    match ranging {
        Ranging::Lidar => prep.checked.steps.lidar,
        Ranging::Rangefinders => prep.checked.steps.rangefinders,
    }
}

/// What feeding one sample did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fed {
    /// Not started: at rest (the gyro calibration took the sample), or waiting for the
    /// initial estimate.
    Calibrating,
    /// The navigation started at this sample.
    Started,
    /// One navigation step; whether a map-aided update was applied.
    Stepped {
        /// A map-aided update was applied.
        map_updated: bool,
    },
}

/// One method's navigation over a run's sensor epochs, without the truth: the gyro
/// calibration over the rest, the start from an initial estimate at its end, then
/// one step per sample. The offline runs (`Runner`) and the navigation process of
/// the processor-in-the-loop (`fathom-pils`) both run it.
pub struct Navigation<'e> {
    env: &'e NavEnv<'e>,
    method: Method,
    start: usize,
    particle_rng: ChaCha8Rng,
    gyro_sum: Vector3<f64>,
    gyro_time: f64,
    nav: Option<Nav>,
}

impl<'e> Navigation<'e> {
    /// `method` on the scenario `env`, starting at sample `start` (the end of the
    /// rest); `particle_rng` is the particle filter's stream.
    pub fn new(
        env: &'e NavEnv<'e>,
        method: Method,
        start: usize,
        particle_rng: &ChaCha8Rng,
    ) -> Self {
        Self {
            env,
            method,
            start,
            particle_rng: particle_rng.clone(),
            gyro_sum: Vector3::zeros(),
            gyro_time: 0.0,
            nav: None,
        }
    }

    /// The sample at which the navigation starts.
    pub fn start_sample(&self) -> usize {
        self.start
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The running method (after the start).
    pub fn nav(&self) -> Option<&Nav> {
        self.nav.as_ref()
    }

    /// Sample `j` (time order, `j >= 1`) at time `t` with the sensor data since sample
    /// `j - 1`; `init` is the initial estimate. The gyro bias is the mean rate of the
    /// samples up to the start sample; the navigation starts at the first sample from
    /// the start sample on that comes with an initial estimate (offline: the start
    /// sample itself; over a real-time link the start sample or the estimate may come
    /// late, and the samples in between are skipped).
    ///
    /// # Errors
    /// A failing mechanization or prediction, naming the method and time.
    pub fn feed(
        &mut self,
        j: usize,
        t: f64,
        epoch: &SensorEpoch,
        init: Option<&NavStart>,
    ) -> Result<Fed, SimError> {
        let Some(nav) = self.nav.as_mut() else {
            return self.calibrate_or_start(j, epoch, init);
        };
        let map_updated = nav.step(
            self.env,
            &epoch.imu,
            t,
            epoch.gnss.as_ref(),
            epoch.ranges.as_ref(),
        )?;
        Ok(Fed::Stepped { map_updated })
    }

    /// Before the start: sample `j` into the gyro calibration (up to the start
    /// sample), and the start from `init` at or after the start sample.
    fn calibrate_or_start(
        &mut self,
        j: usize,
        epoch: &SensorEpoch,
        init: Option<&NavStart>,
    ) -> Result<Fed, SimError> {
        if j <= self.start {
            self.gyro_sum += epoch.imu.delta_theta;
            self.gyro_time += epoch.imu.dt;
        }
        let (true, Some(init)) = (j >= self.start, init) else {
            return Ok(Fed::Calibrating);
        };
        let gyro_bias = self.gyro_sum / self.gyro_time.max(1e-12);
        let mode = match &epoch.gnss {
            Some(g)
                if los_satellites(self.env, &init.pos_in_nav, g).1
                    < self.env.filter.switch.leave_gps_below() =>
            {
                NavMode::MapAided
            }
            Some(_) => NavMode::GpsIns,
            None => NavMode::MapAided,
        };
        self.nav = Some(Nav::new(
            self.method,
            self.env,
            init,
            gyro_bias,
            mode,
            &self.particle_rng,
        )?);
        Ok(Fed::Started)
    }

    /// The counters of the method.
    pub fn counts(&self) -> NavCounts {
        self.nav.as_ref().map(Nav::counts).unwrap_or_default()
    }
}

/// Feeds one method the samples of a run ([`Navigation`], started from the truth
/// displaced by the run's initial error) and evaluates it every `eval` steps.
pub(super) struct Runner<'e> {
    navigation: Navigation<'e>,
    eval: usize,
    dt: f64,
    dx0: ErrorVector12,
    /// True LOS count of the last GNSS epoch.
    true_los: Option<usize>,
    /// The evaluation so far.
    pub trace: Trace,
    /// Keep the MGPMF grid of the first map-aided update at or after this time.
    pub grid_after: Option<f64>,
    /// The grid kept.
    pub grid: Option<GridSnapshot>,
}

impl<'e> Runner<'e> {
    /// A runner starting navigation at the end of the rest.
    pub fn new(
        prep: &Prepared,
        env: &'e NavEnv<'e>,
        method: Method,
        dx0: ErrorVector12,
        streams: &Streams,
    ) -> Self {
        let c = &prep.checked;
        Self {
            navigation: Navigation::new(env, method, start_sample(prep), &streams.particle),
            eval: c.steps.eval,
            dt: c.imu.dt(),
            dx0,
            true_los: None,
            trace: Trace::default(),
            grid_after: None,
            grid: None,
        }
    }

    /// The running method (after the start).
    pub fn nav(&self) -> Option<&Nav> {
        self.navigation.nav()
    }

    /// Sample `j` (time order, `j >= 1`) with the sensor data since sample `j - 1`.
    ///
    /// # Errors
    /// A failing mechanization or prediction, naming the method and time.
    pub fn feed(
        &mut self,
        j: usize,
        truth: &LocalTruthSample,
        epoch: &SensorEpoch,
    ) -> Result<(), SimError> {
        if let Some(g) = &epoch.gnss {
            self.true_los = Some(g.true_los_count());
        }
        let init =
            (j == self.navigation.start_sample()).then(|| NavStart::from_truth(truth, &self.dx0));
        let Fed::Stepped { map_updated } =
            self.navigation.feed(j, truth.time, epoch, init.as_ref())?
        else {
            return Ok(());
        };
        let start = self.navigation.start_sample();
        let env = self.navigation.env;
        let Some(nav) = self.navigation.nav() else {
            return Ok(());
        };
        if nav.map_aided() {
            self.trace.map_time_s += self.dt;
        }
        if map_updated
            && self.grid.is_none()
            && self.grid_after.is_some_and(|t| truth.time >= t)
            && let Some((points, weights)) = nav.last_grid()
        {
            self.grid = Some(GridSnapshot::of(
                truth.time,
                points,
                weights,
                env.filter.mgpmf.grid_points(),
            ));
        }
        if (j - start).is_multiple_of(self.eval) {
            let map = nav.map_aided();
            let open = self
                .true_los
                .is_some_and(|n| n >= env.filter.switch.enter_gps_at());
            self.trace
                .push(&nav.nominal(), nav.covariance(), truth, map, open);
        }
        Ok(())
    }

    /// The counters of the method.
    pub fn counts(&self) -> NavCounts {
        self.navigation.counts()
    }
}

/// The sample at which navigation starts: the end of the rest.
pub fn start_sample(prep: &Prepared) -> usize {
    let c = &prep.checked;
    (c.rest_s * c.imu.rate_hz()).round() as usize
}

/// The record of one method's run.
pub(super) fn method_record(
    prep: &Prepared,
    method: Method,
    runner: &Runner<'_>,
) -> Result<MethodRecord, SimError> {
    let stats = runner.trace.stats().map_err(|e| {
        SimError::model(
            format!("evaluating {}", method.name()),
            Box::new(std::io::Error::other(e.to_string())),
        )
    })?;
    Ok(MethodRecord::new(
        method,
        stats,
        runner.counts(),
        &runner.trace,
        prep.checked.histogram,
    ))
}

/// The sensor of a scenario.
pub fn sensor_of(prep: &Prepared, ranging: Ranging) -> &fathom_sensors::map_range::RangeSensor {
    match ranging {
        Ranging::Lidar => &prep.checked.lidar,
        Ranging::Rangefinders => &prep.checked.rangefinders,
    }
}

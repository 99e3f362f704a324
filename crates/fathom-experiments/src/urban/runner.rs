//! One method stepped over a run's sensor epochs ([`Runner`]: gyro calibration over
//! the rest, the start of navigation, one IMU step and its sensor events at a time,
//! the evaluation), shared by the truth-controlled run ([`super::run`]) and the
//! control-on-estimate flight ([`super::closed_loop`]).

use fathom_estimators::map_aided::{ErrorVector12, NavMode};
use fathom_ins::local_level::LocalTruthSample;
use nalgebra::Vector3;
use rand_chacha::ChaCha8Rng;

use super::nav::{Method, Nav, NavCounts, NavEnv, los_satellites};
use super::record::{GridSnapshot, MethodRecord};
use super::scenario::Ranging;
use super::sense::{SensorEpoch, Streams};
use super::trace::Trace;
use super::world::Prepared;
use fathom_sim::SimError;
/// IMU steps per range epoch of a scenario's sensor.
pub(super) fn range_every(prep: &Prepared, ranging: Ranging) -> usize {
    match ranging {
        Ranging::Lidar => prep.checked.steps.lidar,
        Ranging::Rangefinders => prep.checked.steps.rangefinders,
    }
}

/// Feeds one method the samples of a run: gyro calibration over the rest, start at
/// its end, then one step per sample with evaluation every `eval` steps.
pub(super) struct Runner<'e> {
    env: &'e NavEnv<'e>,
    method: Method,
    start: usize,
    eval: usize,
    dt: f64,
    dx0: ErrorVector12,
    particle_rng: ChaCha8Rng,
    gyro_sum: Vector3<f64>,
    gyro_time: f64,
    nav: Option<Nav>,
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
    /// A runner starting navigation at sample `start`.
    pub fn new(
        prep: &Prepared,
        env: &'e NavEnv<'e>,
        method: Method,
        dx0: ErrorVector12,
        streams: &Streams,
    ) -> Self {
        let c = &prep.checked;
        Self {
            env,
            method,
            start: (c.rest_s * c.imu.rate_hz()).round() as usize,
            eval: c.steps.eval,
            dt: c.imu.dt(),
            dx0,
            particle_rng: streams.particle.clone(),
            gyro_sum: Vector3::zeros(),
            gyro_time: 0.0,
            nav: None,
            true_los: None,
            trace: Trace::default(),
            grid_after: None,
            grid: None,
        }
    }

    /// The running method (after the start).
    pub fn nav(&self) -> Option<&Nav> {
        self.nav.as_ref()
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
        if j <= self.start {
            self.gyro_sum += epoch.imu.delta_theta;
            self.gyro_time += epoch.imu.dt;
            if j == self.start {
                let gyro_bias = self.gyro_sum / self.gyro_time.max(1e-12);
                let est = truth.pos_in_nav + self.dx0.fixed_rows::<3>(0);
                let mode = match &epoch.gnss {
                    Some(g)
                        if los_satellites(self.env, &est, g).1
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
                    truth,
                    &self.dx0,
                    gyro_bias,
                    mode,
                    &self.particle_rng,
                )?);
            }
            return Ok(());
        }
        let Some(nav) = self.nav.as_mut() else {
            return Ok(());
        };
        let map_updated = nav.step(
            self.env,
            &epoch.imu,
            truth.time,
            epoch.gnss.as_ref(),
            epoch.ranges.as_ref(),
        )?;
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
                self.env.filter.mgpmf.grid_points(),
            ));
        }
        if (j - self.start).is_multiple_of(self.eval) {
            let map = nav.map_aided();
            let open = self
                .true_los
                .is_some_and(|n| n >= self.env.filter.switch.enter_gps_at());
            self.trace
                .push(&nav.nominal(), nav.covariance(), truth, map, open);
        }
        Ok(())
    }

    /// The counters of the method.
    pub fn counts(&self) -> NavCounts {
        self.nav.as_ref().map(Nav::counts).unwrap_or_default()
    }
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
pub(super) fn sensor_of(
    prep: &Prepared,
    ranging: Ranging,
) -> &fathom_sensors::map_range::RangeSensor {
    match ranging {
        Ranging::Lidar => &prep.checked.lidar,
        Ranging::Rangefinders => &prep.checked.rangefinders,
    }
}

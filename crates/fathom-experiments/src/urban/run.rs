//! One `urban` Monte Carlo run: per scenario, fly the path on the truth, simulate
//! the sensors once, run every method on the same data and evaluate it; or, in an
//! ablation batch, one method on one scenario with the ablation's change.
//!
//! The run's RNG seeds one stream per sensor ([`Streams`]), drawn in a fixed order,
//! so a run index gives the same flight, IMU, GNSS, range and baro numbers in every
//! batch (paired ablations). The initial error is drawn from `P0` once per run and
//! shared by the methods and scenarios.

use fathom_estimators::map_aided::ErrorVector12;
use fathom_ins::local_level::LocalTruthSample;
use fathom_traj::Trajectory;
use fathom_traj::quadrotor::fly_on_truth;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::check::{Ablation, AblationKind, FilterSetup};
use super::closed_loop;
use super::nav::{Method, NavEnv};
use super::record::{RunRecord, ScanSnapshot, SceneDetail, SceneRecord};
use super::runner::{Runner, method_record, range_every, sensor_of};
use super::scenario::Ranging;
use super::sense::{Sensing, SensorEpoch, Streams};
use super::world::{Prepared, PreparedScene};
use fathom_sim::SimError;

/// The initial estimation error drawn from `P0` (position, velocity, attitude; the
/// bias estimate starts at zero).
pub fn initial_error(prep: &Prepared, rng: &mut ChaCha8Rng) -> Result<ErrorVector12, SimError> {
    let l = prep
        .checked
        .filter
        .p0
        .cholesky()
        .ok_or_else(|| SimError::invalid_argument("urban P0", "not positive definite"))?
        .l();
    let mut z = ErrorVector12::from_fn(|_, _| StandardNormal.sample(rng));
    for i in 9..12 {
        z[i] = 0.0;
    }
    let mut dx = l * z;
    dx.fixed_rows_mut::<3>(9).fill(0.0);
    Ok(dx)
}

/// The navigation environment of a scenario.
pub fn nav_env<'a>(prep: &'a Prepared, scene: &'a PreparedScene, ranging: Ranging) -> NavEnv<'a> {
    let c = &prep.checked;
    let sensor_steps = match ranging {
        Ranging::Lidar => c.steps.lidar,
        Ranging::Rangefinders => c.steps.rangefinders,
    };
    let sensor_rate = c.imu.rate_hz() / sensor_steps as f64;
    NavEnv {
        map: &scene.caster,
        frame: prep.receiver.frame(),
        pseudorange_sigma: c.gnss.params.pseudorange_sigma_m,
        filter: &c.filter,
        grid_every: (sensor_rate / c.filter.grid_rate_hz).round().max(1.0) as usize,
        grid_stride: match ranging {
            Ranging::Lidar => c.filter.lidar_beam_stride,
            Ranging::Rangefinders => 1,
        },
        gravity: c.quad.vehicle.gravity(),
    }
}

/// The truth at the IMU rate over the whole flight.
fn sample_truth(
    prep: &Prepared,
    scene: &PreparedScene,
    streams: &Streams,
) -> Result<Vec<LocalTruthSample>, SimError> {
    let c = &prep.checked;
    let traj = fly_on_truth(&c.quad, &scene.path, &mut streams.wind.clone())
        .map_err(|e| SimError::model("quadrotor flight", e))?;
    let dt = c.imu.dt();
    let n = (traj.end_time() / dt + 1e-9).floor() as usize;
    (0..=n)
        .map(|k| {
            let q = traj
                .quad_state_at((k as f64 * dt).min(traj.end_time()))
                .map_err(|e| SimError::model("quadrotor truth", e))?;
            Ok(LocalTruthSample {
                time: k as f64 * dt,
                pos_in_nav: q.body.pos_in_nav,
                vel_in_nav: q.body.vel_in_nav,
                nav_from_body: q.body.nav_from_body,
            })
        })
        .collect()
}

/// A scenario flown on the truth: the samples and the sensor data since each.
pub struct Flown {
    /// The truth at the IMU rate, sample 0 first.
    pub truth: Vec<LocalTruthSample>,
    /// `epochs[j - 1]`: the data of sample `j`.
    pub epochs: Vec<SensorEpoch>,
}

/// Flies a scenario on the truth and simulates its sensors (the run's streams).
///
/// # Errors
/// A flight or truth the models refuse.
pub fn fly_and_sense(
    prep: &Prepared,
    scene: &PreparedScene,
    ranging: Ranging,
    sensor: &fathom_sensors::map_range::RangeSensor,
    streams: &Streams,
) -> Result<Flown, SimError> {
    let truth = sample_truth(prep, scene, streams)?;
    let mut sensing = Sensing::new(
        &prep.checked,
        &scene.caster,
        &prep.receiver,
        sensor,
        range_every(prep, ranging),
        streams,
    )?;
    let mut epochs = Vec::with_capacity(truth.len());
    for t in &truth {
        if let Some(e) = sensing.push(t)? {
            epochs.push(e);
        }
    }
    Ok(Flown { truth, epochs })
}

fn run_method<'e>(
    prep: &Prepared,
    env: &'e NavEnv<'e>,
    method: Method,
    flown: &Flown,
    dx0: ErrorVector12,
    streams: &Streams,
    grid_after: Option<f64>,
) -> Result<Runner<'e>, SimError> {
    let mut r = Runner::new(prep, env, method, dx0, streams);
    r.grid_after = grid_after;
    for (j, epoch) in flown.epochs.iter().enumerate() {
        r.feed(j + 1, &flown.truth[j + 1], epoch)?;
    }
    Ok(r)
}

/// Run `index` of the main batch.
pub(super) fn main_run(
    prep: &Prepared,
    index: usize,
    rng: &mut ChaCha8Rng,
) -> Result<RunRecord, SimError> {
    let mut streams = Streams::from_run(rng);
    let dx0 = initial_error(prep, &mut streams.init)?;
    let detail = index == 0;
    let mut scenes = Vec::with_capacity(prep.scenes.len());
    let mut details = Vec::new();
    for (spec, scene) in prep.checked.scenes.iter().zip(&prep.scenes) {
        let sensor = sensor_of(prep, spec.ranging);
        let flown = fly_and_sense(prep, scene, spec.ranging, sensor, &streams)?;
        let env = nav_env(prep, scene, spec.ranging);
        let start = (prep.checked.rest_s * prep.checked.imu.rate_hz()).round() as usize;
        let t_end = flown.truth.last().map_or(0.0, |t| t.time);
        let mid = 0.5 * (flown.truth[start.min(flown.truth.len() - 1)].time + t_end);
        let mut methods = Vec::new();
        let mut traces = Vec::new();
        let mut grid = None;
        for &method in &prep.checked.methods {
            let grid_after = (detail && method == Method::Mgpmf).then_some(mid);
            let r = run_method(prep, &env, method, &flown, dx0, &streams, grid_after)?;
            methods.push(method_record(prep, method, &r)?);
            if detail {
                if r.grid.is_some() {
                    grid = r.grid.clone();
                }
                traces.push(r.trace);
            }
        }
        let gnss: Vec<(f64, usize)> = flown
            .truth
            .iter()
            .skip(1)
            .zip(&flown.epochs)
            .filter_map(|(t, e)| e.gnss.as_ref().map(|g| (t.time, g.true_los_count())))
            .filter(|(t, _)| *t >= flown.truth[start.min(flown.truth.len() - 1)].time)
            .collect();
        let threshold = prep.checked.filter.switch.leave_gps_below();
        scenes.push(SceneRecord::new(methods, &gnss, threshold, t_end));
        if detail {
            let scan = flown
                .truth
                .iter()
                .skip(1)
                .zip(&flown.epochs)
                .find(|(t, e)| t.time >= mid && e.ranges.is_some())
                .map(|(t, e)| {
                    ScanSnapshot::of(t, e.ranges.as_ref().map_or(&[][..], |r| &r.returns))
                });
            let mut d = SceneDetail::new(
                &flown.truth,
                start,
                prep.checked.steps.eval,
                traces,
                gnss,
                scan,
                grid,
            );
            if prep.scene_page {
                let from = d.times.first().copied().unwrap_or(0.0);
                d.scans = super::scene_page::scans(&flown.truth, &flown.epochs, from);
                d.sky = super::scene_page::sky(prep, &flown.truth, &flown.epochs, from);
            }
            details.push(d);
        }
    }
    Ok(RunRecord {
        scenes,
        detail: detail.then_some(details),
    })
}

/// Run `index` of ablation `ablation`: the ablation's method on its scenario.
pub(super) fn ablation_run(
    prep: &Prepared,
    ablation: &Ablation,
    rng: &mut ChaCha8Rng,
) -> Result<RunRecord, SimError> {
    let mut streams = Streams::from_run(rng);
    let dx0 = initial_error(prep, &mut streams.init)?;
    let spec = &prep.checked.scenes[ablation.scene];
    let scene = &prep.scenes[ablation.scene];
    let env = nav_env(prep, scene, spec.ranging);
    let record = match &ablation.kind {
        AblationKind::RangeModel(sensor, _) | AblationKind::LidarStep(sensor, _) => {
            let flown = fly_and_sense(prep, scene, spec.ranging, sensor, &streams)?;
            let r = run_method(prep, &env, ablation.method, &flown, dx0, &streams, None)?;
            method_record(prep, ablation.method, &r)?
        }
        AblationKind::ControlOnEstimate => {
            closed_loop::fly_on_estimate(prep, &env, ablation, dx0, &streams)?
        }
        AblationKind::GridPosterior(posterior) => {
            let sensor = sensor_of(prep, spec.ranging);
            let flown = fly_and_sense(prep, scene, spec.ranging, sensor, &streams)?;
            let filter = FilterSetup {
                mgpmf: prep.checked.filter.mgpmf.with_posterior(*posterior),
                ..prep.checked.filter
            };
            let env = NavEnv {
                filter: &filter,
                ..env
            };
            let r = run_method(prep, &env, ablation.method, &flown, dx0, &streams, None)?;
            method_record(prep, ablation.method, &r)?
        }
    };
    Ok(RunRecord {
        scenes: vec![SceneRecord::new(vec![record], &[], 0, 0.0)],
        detail: None,
    })
}

//! The control-on-estimate ablation: the quadrotor's controller and guidance act on
//! one method's estimate instead of the truth (as on the real vehicle), so the
//! truth is flown one IMU step at a time, interleaved with the sensors and the
//! filter. During the rest and until the navigation starts the vehicle is held (no
//! control), as in the truth-controlled flight.
//!
//! A flight whose guidance does not finish within twice the truth-controlled
//! flight's length (plus a minute) is stopped there; the evaluation covers what was
//! flown.

use fathom_estimators::map_aided::ErrorVector12;
use fathom_ins::local_level::LocalTruthSample;
use fathom_traj::quadrotor::Flight;

use super::check::Ablation;
use super::nav::NavEnv;
use super::record::MethodRecord;
use super::runner::{Runner, method_record, range_every, sensor_of};
use super::sense::{Sensing, Streams};
use super::world::Prepared;
use fathom_sim::SimError;

fn sample(flight: &Flight, time: f64) -> LocalTruthSample {
    let s = flight.truth();
    LocalTruthSample {
        time,
        pos_in_nav: s.pos_in_nav,
        vel_in_nav: s.vel_in_nav,
        nav_from_body: s.nav_from_body,
    }
}

/// One run of `ablation.method` flying on its own estimate.
///
/// # Errors
/// A diverged flight or a failing mechanization / prediction.
pub(super) fn fly_on_estimate(
    prep: &Prepared,
    env: &NavEnv<'_>,
    ablation: &Ablation,
    dx0: ErrorVector12,
    streams: &Streams,
) -> Result<MethodRecord, SimError> {
    let c = &prep.checked;
    let spec = &c.scenes[ablation.scene];
    let scene = &prep.scenes[ablation.scene];
    let sensor = sensor_of(prep, spec.ranging);
    let mut wind = streams.wind.clone();
    let mut flight = Flight::new(&c.quad, &scene.path, &mut wind);
    let mut sensing = Sensing::new(
        c,
        &scene.caster,
        &prep.receiver,
        sensor,
        range_every(prep, spec.ranging),
        streams,
    )?;
    let mut runner = Runner::new(prep, env, ablation.method, dx0, streams);
    let dt = c.imu.dt();
    sensing.push(&sample(&flight, 0.0))?;
    // the truth-controlled flight's length bounds the closed loop's
    let nominal =
        fathom_traj::quadrotor::fly_on_truth(&c.quad, &scene.path, &mut streams.wind.clone())
            .map_err(|e| SimError::model("quadrotor flight", e))?;
    let limit = 2.0 * fathom_traj::Trajectory::end_time(&nominal) + 60.0;
    let mut j = 0usize;
    while !flight.is_finished() && (j as f64) * dt < limit {
        let estimate = runner.nav().map(|n| n.control_state());
        for _ in 0..c.steps.control_per_imu {
            flight
                .step(estimate.as_ref(), &mut wind)
                .map_err(|e| SimError::model("closed-loop flight", e))?;
        }
        j += 1;
        let truth = sample(&flight, j as f64 * dt);
        if let Some(epoch) = sensing.push(&truth)? {
            runner.feed(j, &truth, &epoch)?;
        }
    }
    method_record(prep, ablation.method, &runner)
}

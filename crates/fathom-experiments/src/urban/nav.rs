//! The navigation methods of `urban`, each the reduced mechanization
//! (`fathom_ins::local_level`) with the 12-state error-state filter
//! (`fathom_estimators::map_aided`) in closed loop, fed one IMU step and the sensor
//! events of its end at a time:
//!
//! | method | aiding |
//! | --- | --- |
//! | `INS-only` | none (gyro bias calibrated at rest, like every method) |
//! | `GPS/INS` | position fix from the satellites the estimate sees in line of sight (rays cast against the map from the estimated position) |
//! | `GPS/INS-all-sats` | position fix from every received satellite (NLOS reflections included) |
//! | `GREKF`, `MGPMF`, `PF` | switching: the LOS-checked GPS/INS while at least `switch.min_los_satellites` satellites are in line of sight, else the map-aided update with the range sensor and the barometer |
//!
//! A fix is the least-squares single-point solution (`fathom_sensors::gnss::solve_spp`)
//! with covariance `sigma_rho^2 diag(HDOP^2 / 2, HDOP^2 / 2, VDOP^2)`; it needs 4
//! satellites. The particle filter draws from its own stream.

use fathom_core::RayCaster;
use fathom_estimators::map_aided::{
    ErrorVector12, GpsFix, GpsReacquire, Grekf, Ins12Filter, Matrix12, Mgpmf, ModeSwitch, NavMode,
    NominalNav, ParticleFilter, RangeBeam,
};
use fathom_ins::ImuIncrement;
use fathom_ins::local_level::{LocalLevelMechanization, LocalLevelState, LocalTruthSample};
use fathom_sensors::gnss::{LocalFrame, solve_spp};
use fathom_traj::quadrotor::ControlState;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::check::FilterSetup;
use super::sense::{GnssEpoch, RangeEpoch};
use fathom_sim::SimError;

pub use super::method::Method;

/// What the methods share in a scenario.
pub struct NavEnv<'a> {
    /// The map (the estimators' copy of the world: the same mesh as the truth's).
    pub map: &'a dyn RayCaster,
    /// The local frame of the GNSS origin.
    pub frame: &'a LocalFrame,
    /// Pseudorange σ the fixes assume, m.
    pub pseudorange_sigma: f64,
    /// Filter settings.
    pub filter: &'a FilterSetup,
    /// Range epochs per point-mass / particle update.
    pub grid_every: usize,
    /// Beam stride of the point-mass / particle filters.
    pub grid_stride: usize,
    /// Gravity of the mechanization (the truth's).
    pub gravity: f64,
}

enum Aider {
    None,
    Grekf(Grekf),
    Mgpmf(Box<Mgpmf>),
    Particle(Box<ParticleFilter>, Box<ChaCha8Rng>),
}

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct NavCounts {
    /// GPS updates applied (accepted by the gate).
    pub gps_updates: usize,
    /// GPS fixes rejected by the gate.
    pub gps_rejected: usize,
    /// Map-aided updates applied (a GREKF update counts only when it used a beam).
    pub map_updates: usize,
    /// Map-aided updates that failed (no predicted hit, bad geometry).
    pub map_failed: usize,
    /// GREKF updates in which every beam was left out (gated, grazing or no hit):
    /// not map updates.
    pub map_left_out: usize,
    /// Mode switches (GPS/INS to map-aided and back).
    pub switches: usize,
    /// Times the GREKF lost lock (its lost-lock rule fired).
    pub lost_lock: usize,
    /// Times it re-locked (used beams again after a lost lock).
    pub relocks: usize,
    /// Times a GPS fix re-acquired the position after a run of rejected fixes.
    #[serde(default)]
    pub gps_reacquired: usize,
    /// Beams the GREKF's linearity check left out (all updates).
    #[serde(default)]
    pub beams_nonlinear: usize,
}

/// The initial estimate a method starts from (the surveyed start point and the
/// alignment, with the run's initial error).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavStart {
    /// Time of the start, s.
    pub time: f64,
    /// Position, NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Velocity, NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude.
    pub nav_from_body: UnitQuaternion<f64>,
}

impl NavStart {
    /// The truth `start` displaced by the initial error `dx0` (position, velocity,
    /// attitude as a small rotation about N, E, D).
    pub fn from_truth(start: &LocalTruthSample, dx0: &ErrorVector12) -> Self {
        Self {
            time: start.time,
            pos_in_nav: start.pos_in_nav + dx0.fixed_rows::<3>(0),
            vel_in_nav: start.vel_in_nav + dx0.fixed_rows::<3>(3),
            nav_from_body: UnitQuaternion::from_scaled_axis(Vector3::new(dx0[6], dx0[7], dx0[8]))
                * start.nav_from_body,
        }
    }
}

/// One method running (module docs).
pub struct Nav {
    method: Method,
    mech: LocalLevelMechanization,
    accel_bias: Vector3<f64>,
    gyro_bias: Vector3<f64>,
    omega_body: Vector3<f64>,
    filter: Ins12Filter,
    switch: Option<ModeSwitch>,
    gps: GpsReacquire,
    aider: Aider,
    range_epochs: usize,
    counts: NavCounts,
    beams: Vec<RangeBeam>,
}

fn model(what: &str, e: impl std::error::Error + Send + Sync + 'static) -> SimError {
    SimError::model(what.to_string(), e)
}

/// The satellites an estimated position sees: `(ECEF position, pseudorange)` of the
/// received ones with a free line of sight, and the count of all with one.
pub fn los_satellites(
    env: &NavEnv<'_>,
    pos_in_nav: &Vector3<f64>,
    epoch: &GnssEpoch,
) -> (Vec<(Vector3<f64>, f64)>, usize) {
    let rx = env.frame.ecef_from_ned(pos_in_nav);
    let mut pairs = Vec::new();
    let mut count = 0;
    for s in &epoch.sats {
        let u = env.frame.ned_from_ecef() * (s.pos_ecef - rx);
        if env.map.cast(pos_in_nav, &u, f64::INFINITY).is_some() {
            continue;
        }
        count += 1;
        if let Some(rho) = s.pseudorange_m {
            pairs.push((s.pos_ecef, rho));
        }
    }
    (pairs, count)
}

/// Every received satellite.
fn all_satellites(epoch: &GnssEpoch) -> Vec<(Vector3<f64>, f64)> {
    epoch
        .sats
        .iter()
        .filter_map(|s| s.pseudorange_m.map(|rho| (s.pos_ecef, rho)))
        .collect()
}

/// A position fix from at least four satellites (module docs).
fn fix_of(env: &NavEnv<'_>, pairs: &[(Vector3<f64>, f64)]) -> Option<GpsFix> {
    if pairs.len() < 4 {
        return None;
    }
    let sol = solve_spp(env.frame, pairs).ok()?;
    let s2 = env.pseudorange_sigma.powi(2);
    let (h, v) = (sol.dop.hdop, sol.dop.vdop);
    let cov = Matrix3::from_diagonal(&Vector3::new(h * h / 2.0, h * h / 2.0, v * v)) * s2;
    (sol.pos_in_nav.iter().all(|c| c.is_finite()) && cov.iter().all(|c| c.is_finite())).then_some(
        GpsFix {
            pos_in_nav: sol.pos_in_nav,
            pos_cov: cov,
            velocity: None,
        },
    )
}

impl Nav {
    /// `method` started from the initial estimate `start` (the accelerometer-bias
    /// estimate starts at 0), with the gyro bias from the calibration at rest, in
    /// `initial_mode`.
    ///
    /// # Errors
    /// [`SimError::Model`] for settings the libraries refuse.
    pub fn new(
        method: Method,
        env: &NavEnv<'_>,
        start: &NavStart,
        gyro_bias: Vector3<f64>,
        initial_mode: NavMode,
        particle_rng: &ChaCha8Rng,
    ) -> Result<Self, SimError> {
        let f = env.filter;
        let state = LocalLevelState {
            pos_in_nav: start.pos_in_nav,
            vel_in_nav: start.vel_in_nav,
            nav_from_body: start.nav_from_body,
        };
        let mech = LocalLevelMechanization::new(state, env.gravity)
            .map_err(|e| model("mechanization start", e))?;
        let filter = Ins12Filter::new(&f.p0, start.time, f.noise)
            .map_err(|e| model("12-state filter", e))?;
        let switch = method
            .is_switching()
            .then(|| ModeSwitch::new(f.switch, initial_mode, start.time))
            .transpose()
            .map_err(|e| model("mode switch", e))?;
        let aider = match method {
            Method::Grekf => Aider::Grekf(Grekf::new(f.grekf)),
            Method::Mgpmf => Aider::Mgpmf(Box::new(Mgpmf::new(f.mgpmf))),
            Method::Particle => Aider::Particle(
                Box::new(ParticleFilter::new(f.particle)),
                Box::new(particle_rng.clone()),
            ),
            _ => Aider::None,
        };
        Ok(Self {
            method,
            mech,
            accel_bias: Vector3::zeros(),
            gyro_bias,
            omega_body: Vector3::zeros(),
            filter,
            switch,
            gps: GpsReacquire::default(),
            aider,
            range_epochs: 0,
            counts: NavCounts::default(),
            beams: Vec::new(),
        })
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The nominal (corrected) state.
    pub fn nominal(&self) -> NominalNav {
        let s = self.mech.state();
        NominalNav {
            pos_in_nav: s.pos_in_nav,
            vel_in_nav: s.vel_in_nav,
            nav_from_body: s.nav_from_body,
            accel_bias_in_body: self.accel_bias,
        }
    }

    /// The error covariance.
    pub fn covariance(&self) -> &Matrix12 {
        self.filter.covariance()
    }

    /// Whether the map-aided mode is active (switching methods only).
    pub fn map_aided(&self) -> bool {
        self.switch
            .as_ref()
            .is_some_and(|s| s.mode() == NavMode::MapAided)
    }

    /// The counters.
    pub fn counts(&self) -> NavCounts {
        self.counts
    }

    /// The MGPMF's last grid (points `n` and weights), if this is the MGPMF.
    pub fn last_grid(&self) -> Option<(&[Vector3<f64>], &[f64])> {
        match &self.aider {
            Aider::Mgpmf(m) => Some(m.last_grid()),
            _ => None,
        }
    }

    /// The estimate as the flight controller's state (the gyro rate corrected by the
    /// calibrated bias).
    pub fn control_state(&self) -> ControlState {
        let s = self.mech.state();
        ControlState {
            pos_in_nav: s.pos_in_nav,
            vel_in_nav: s.vel_in_nav,
            nav_from_body: s.nav_from_body,
            omega_body: self.omega_body,
        }
    }

    /// One IMU step to `t` and the events at `t`; returns whether a map-aided update
    /// was applied.
    ///
    /// # Errors
    /// [`SimError::Model`] when the mechanization or the prediction fails (a diverged
    /// state); failing updates are counted instead.
    pub fn step(
        &mut self,
        env: &NavEnv<'_>,
        inc: &ImuIncrement,
        t: f64,
        gnss: Option<&GnssEpoch>,
        ranges: Option<&RangeEpoch>,
    ) -> Result<bool, SimError> {
        let dt = inc.dt;
        let dth = inc.delta_theta - self.gyro_bias * dt;
        let dv = inc.delta_v - self.accel_bias * dt;
        self.omega_body = dth / dt;
        let q_start = self.mech.state().nav_from_body;
        self.mech
            .step(&ImuIncrement::new(dt, dth, dv))
            .map_err(|e| {
                model(
                    &format!("{} mechanization at t = {t} s", self.method.name()),
                    e,
                )
            })?;
        self.filter.predict(&q_start, &(dv / dt), t).map_err(|e| {
            model(
                &format!("{} prediction at t = {t} s", self.method.name()),
                e,
            )
        })?;
        let mut updated = false;
        let mut map_updated = false;
        if let Some(epoch) = gnss {
            updated |= self.gnss_update(env, t, epoch)?;
        }
        if let Some(r) = ranges {
            self.range_epochs += 1;
            if self.map_aided() {
                map_updated = self.map_update(env, r);
                updated |= map_updated;
            }
        }
        if updated {
            let c = self.filter.take_correction();
            let nav = c.apply(&self.nominal());
            self.mech
                .set_state(LocalLevelState {
                    pos_in_nav: nav.pos_in_nav,
                    vel_in_nav: nav.vel_in_nav,
                    nav_from_body: nav.nav_from_body,
                })
                .map_err(|e| model(&format!("{} feedback at t = {t} s", self.method.name()), e))?;
            self.accel_bias = nav.accel_bias_in_body;
        }
        Ok(map_updated)
    }

    fn gnss_update(
        &mut self,
        env: &NavEnv<'_>,
        t: f64,
        epoch: &GnssEpoch,
    ) -> Result<bool, SimError> {
        let pos = self.mech.state().pos_in_nav;
        let pairs = match self.method {
            Method::InsOnly => return Ok(false),
            Method::GpsInsAllSats => all_satellites(epoch),
            Method::GpsIns => los_satellites(env, &pos, epoch).0,
            _ => {
                let (pairs, count) = los_satellites(env, &pos, epoch);
                if let Some(s) = self.switch.as_mut() {
                    let before = s.mode();
                    let after = s.observe(t, count).map_err(|e| model("mode switch", e))?;
                    self.counts.switches = s.switches();
                    if before != after && after == NavMode::MapAided {
                        self.enter_map_mode();
                    }
                }
                if self.map_aided() {
                    return Ok(false);
                }
                pairs
            }
        };
        let Some(fix) = fix_of(env, &pairs) else {
            return Ok(false);
        };
        let nominal = self.nominal();
        // only a fix from as many satellites as GPS/INS is re-entered with may
        // re-acquire (fewer: likelier the reflections a wrong LOS test let in)
        let outcome = if pairs.len() >= env.filter.switch.enter_gps_at() {
            self.gps
                .update(&mut self.filter, &nominal, &fix, &env.filter.gps)
        } else {
            self.filter.update_gps(&nominal, &fix, &env.filter.gps)
        };
        match outcome {
            Ok(o) if o.accepted => {
                self.counts.gps_updates += 1;
                self.counts.gps_reacquired += usize::from(o.reacquired);
                Ok(true)
            }
            Ok(_) => {
                self.counts.gps_rejected += 1;
                Ok(false)
            }
            Err(_) => {
                self.counts.gps_rejected += 1;
                Ok(false)
            }
        }
    }

    /// A new map-aided stretch: the GREKF starts locked, the particle filter draws
    /// its particles from the filter's (GPS/INS-converged) Gaussian.
    fn enter_map_mode(&mut self) {
        match &mut self.aider {
            Aider::Grekf(g) => g.reset(),
            Aider::Particle(p, _) => p.reset(),
            _ => {}
        }
    }

    /// The map-aided update of a range epoch; returns whether the filter changed (to
    /// be fed back). Counted as a map update only when it used the ranges.
    fn map_update(&mut self, env: &NavEnv<'_>, epoch: &RangeEpoch) -> bool {
        let nominal = self.nominal();
        let grid = matches!(self.aider, Aider::Mgpmf(_) | Aider::Particle(..));
        if grid && !(self.range_epochs - 1).is_multiple_of(env.grid_every) {
            return false;
        }
        self.beams.clear();
        let stride = if grid { env.grid_stride } else { 1 };
        self.beams.extend(
            epoch
                .returns
                .iter()
                .filter(|r| r.beam.is_multiple_of(stride))
                .map(|r| r.reading),
        );
        let baro = Some(&epoch.baro);
        let ok = match &mut self.aider {
            Aider::None => return false,
            Aider::Grekf(g) => {
                match g.update(&mut self.filter, &nominal, &self.beams, baro, env.map) {
                    Ok(rep) => {
                        self.counts.beams_nonlinear += rep.nonlinear;
                        self.counts.lost_lock += usize::from(rep.lock_lost);
                        self.counts.relocks += usize::from(rep.relocked);
                        if rep.all_beams_left_out {
                            self.counts.map_left_out += 1;
                            // the baro may have updated the height, the inflation the
                            // covariance: fed back, not counted as a map update
                            return true;
                        }
                        true
                    }
                    Err(_) => false,
                }
            }
            Aider::Mgpmf(m) => m
                .update(&mut self.filter, &nominal, &self.beams, baro, env.map)
                .is_ok(),
            Aider::Particle(p, rng) => p
                .update(
                    &mut self.filter,
                    &nominal,
                    &self.beams,
                    baro,
                    env.map,
                    &mut **rng,
                )
                .is_ok(),
        };
        if ok {
            self.counts.map_updates += 1;
        } else {
            self.counts.map_failed += 1;
        }
        ok
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn method_names_round_trip() {
        for m in Method::ALL {
            assert_eq!(Method::from_name(m.name()), Some(m));
        }
        assert_eq!(Method::from_name("EKF"), None);
        assert_eq!(Method::GpsInsAllSats.slug(), "gps_ins_all_sats");
        assert_eq!(Method::ALL.iter().filter(|m| m.is_switching()).count(), 3);
    }
}

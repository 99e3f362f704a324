//! The GNSS receiver against the map (spec D, "Sensors", GPS): per epoch, every
//! satellite above the elevation mask gets a line-of-sight test (a ray from the
//! receiver towards it, cast against the map), a pseudorange and a range rate
//! (Doppler).
//!
//! Model: `rho = |r_sat - r_rx| + b(t) + e`, `b(t) = b0 + b_dot t` the receiver clock
//! bias in metres, `e ~ N(0, sigma_rho^2)`; a blocked (NLOS) satellite is received
//! with probability `nlos_reception_probability`, and then carries an excess path
//! delay uniform in `[nlos_delay_min_m, nlos_delay_max_m]` (a reflection);
//! `rho_dot = u . (v_sat - v_rx) + b_dot + e_dot`, `u` the unit vector from the
//! receiver to the satellite, and the Doppler shift is `-rho_dot / lambda_L1`.
//! The geometric range is taken at the receive time (no signal transit time, no
//! Sagnac term, no atmosphere): what is simulated and what the SPP solves share the
//! model, so a noise-free solution is exact. Draws: four per satellite in
//! constellation order (reception uniform, delay uniform, two standard normals),
//! whether visible or not.

use fathom_core::RayCaster;
use nalgebra::Vector3;
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::SensorError;
use crate::error::{check_finite, check_sigma};
use crate::gnss::geodesy::{LocalFrame, LocalFrameParams};
use crate::gnss::orbit::{KeplerElements, Orbit, SatState, nominal_gps24};

/// Speed of light, m/s.
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;
/// GPS L1 wavelength, m.
pub const L1_WAVELENGTH_M: f64 = SPEED_OF_LIGHT / 1_575.42e6;

/// Unchecked receiver and constellation parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GnssParams {
    /// The scenario origin (the map's NED frame).
    pub frame: LocalFrameParams,
    /// The satellites. Default: the nominal 24-slot GPS constellation.
    pub satellites: Vec<KeplerElements>,
    /// Time of the scenario's `t = 0` after the elements' epoch, s (turns the
    /// geometry). Default 0.
    pub epoch_offset_s: f64,
    /// Elevation mask, deg. Default 5.
    pub elevation_mask_deg: f64,
    /// Pseudorange noise std, m. Default 3.
    pub pseudorange_sigma_m: f64,
    /// Range-rate noise std, m/s. Default 0.05.
    pub range_rate_sigma_mps: f64,
    /// Receiver clock bias at `t = 0`, m. Default 100.
    pub clock_bias_m: f64,
    /// Receiver clock drift, m/s. Default 0.5.
    pub clock_drift_mps: f64,
    /// Probability that a blocked satellite's signal is received (reflected). Default 0.5.
    pub nlos_reception_probability: f64,
    /// Smallest excess path delay of a received NLOS signal, m. Default 5.
    pub nlos_delay_min_m: f64,
    /// Largest excess path delay, m. Default 60.
    pub nlos_delay_max_m: f64,
    /// Fix rate, Hz (for the caller's schedule). Default 5.
    pub rate_hz: f64,
}

impl Default for GnssParams {
    fn default() -> Self {
        Self {
            frame: LocalFrameParams::default(),
            satellites: nominal_gps24(),
            epoch_offset_s: 0.0,
            elevation_mask_deg: 5.0,
            pseudorange_sigma_m: 3.0,
            range_rate_sigma_mps: 0.05,
            clock_bias_m: 100.0,
            clock_drift_mps: 0.5,
            nlos_reception_probability: 0.5,
            nlos_delay_min_m: 5.0,
            nlos_delay_max_m: 60.0,
            rate_hz: 5.0,
        }
    }
}

/// Most satellites a receiver model may have.
pub const MAX_SATELLITES: usize = 1000;

impl GnssParams {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the field, [`SensorError::Empty`]
    /// without satellites.
    pub fn check(&self) -> Result<GnssReceiver, SensorError> {
        if self.satellites.is_empty() {
            return Err(SensorError::Empty {
                what: "GNSS satellites".into(),
            });
        }
        let bad = |field: &str, value: f64, reason| SensorError::InvalidParameter {
            field: field.into(),
            value,
            reason,
        };
        if self.satellites.len() > MAX_SATELLITES {
            return Err(bad(
                "satellites",
                self.satellites.len() as f64,
                "more than 1000 satellites",
            ));
        }
        let orbits = self
            .satellites
            .iter()
            .map(KeplerElements::check)
            .collect::<Result<Vec<_>, _>>()?;
        let mask = check_finite("elevation_mask_deg", self.elevation_mask_deg)?;
        if !(-90.0..=90.0).contains(&mask) {
            return Err(bad("elevation_mask_deg", mask, "must be within +-90 deg"));
        }
        let p = self.nlos_reception_probability;
        if !(0.0..=1.0).contains(&p) {
            return Err(bad("nlos_reception_probability", p, "must be in [0, 1]"));
        }
        let lo = check_sigma("nlos_delay_min_m", self.nlos_delay_min_m)?;
        let hi = check_sigma("nlos_delay_max_m", self.nlos_delay_max_m)?;
        if hi < lo {
            return Err(bad("nlos_delay_max_m", hi, "must be >= nlos_delay_min_m"));
        }
        let epoch = check_finite("epoch_offset_s", self.epoch_offset_s)?;
        if epoch.abs() > 1e9 {
            return Err(bad("epoch_offset_s", epoch, "must be within +-1e9 s"));
        }
        Ok(GnssReceiver {
            frame: self.frame.check()?,
            orbits,
            epoch_offset: epoch,
            sin_mask: mask.to_radians().sin(),
            sigma_rho: check_sigma("pseudorange_sigma_m", self.pseudorange_sigma_m)?,
            sigma_rate: check_sigma("range_rate_sigma_mps", self.range_rate_sigma_mps)?,
            bias0: check_finite("clock_bias_m", self.clock_bias_m)?,
            drift: check_finite("clock_drift_mps", self.clock_drift_mps)?,
            p_nlos: p,
            delay: (lo, hi),
            rate_hz: crate::error::check_positive("rate_hz", self.rate_hz)?,
        })
    }
}

/// One satellite's observation at an epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatObservation {
    /// Index in the constellation.
    pub sat: usize,
    /// Satellite position and velocity, ECEF.
    pub state: SatState,
    /// Elevation seen from the receiver, rad.
    pub elevation_rad: f64,
    /// Azimuth from north towards east, rad.
    pub azimuth_rad: f64,
    /// Unit vector from the receiver to the satellite, NED.
    pub los_in_nav: Vector3<f64>,
    /// Whether the ray towards the satellite is free of the map.
    pub los: bool,
    /// Whether a signal is received (LOS, or NLOS and reflected).
    pub received: bool,
    /// Geometric range, m.
    pub true_range_m: f64,
    /// Excess path delay (0 for LOS), m.
    pub excess_delay_m: f64,
    /// Pseudorange, m (when received).
    pub pseudorange_m: Option<f64>,
    /// Pseudorange rate, m/s (when received).
    pub range_rate_mps: Option<f64>,
}

impl SatObservation {
    /// Doppler shift on L1, Hz (when received).
    pub fn doppler_hz(&self) -> Option<f64> {
        self.range_rate_mps.map(|r| -r / L1_WAVELENGTH_M)
    }
}

/// Checked GNSS receiver model.
#[derive(Debug, Clone, PartialEq)]
pub struct GnssReceiver {
    frame: LocalFrame,
    orbits: Vec<Orbit>,
    epoch_offset: f64,
    sin_mask: f64,
    sigma_rho: f64,
    sigma_rate: f64,
    bias0: f64,
    drift: f64,
    p_nlos: f64,
    delay: (f64, f64),
    rate_hz: f64,
}

impl GnssReceiver {
    /// The local frame of the scenario origin.
    pub fn frame(&self) -> &LocalFrame {
        &self.frame
    }

    /// The satellites' orbits.
    pub fn orbits(&self) -> &[Orbit] {
        &self.orbits
    }

    /// Fix rate, Hz.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Receiver clock bias at `t`, m.
    pub fn clock_bias_m(&self, t: f64) -> f64 {
        self.bias0 + self.drift * t
    }

    /// Every satellite's ECEF state at scenario time `t`, s.
    pub fn satellites_at(&self, t: f64) -> Vec<SatState> {
        self.orbits
            .iter()
            .map(|o| o.state_at(t + self.epoch_offset))
            .collect()
    }

    /// Observes the constellation at scenario time `t` from the true receiver
    /// position and velocity (NED): the satellites above the mask, in constellation
    /// order (four draws per satellite, module doc).
    pub fn observe(
        &self,
        map: &(impl RayCaster + ?Sized),
        t: f64,
        pos_in_nav: &Vector3<f64>,
        vel_in_nav: &Vector3<f64>,
        rng: &mut impl Rng,
    ) -> Vec<SatObservation> {
        let sats = self.satellites_at(t);
        self.observe_satellites(map, t, &sats, pos_in_nav, vel_in_nav, rng)
    }

    /// As [`GnssReceiver::observe`] with given satellite states (index = `sat`).
    pub fn observe_satellites(
        &self,
        map: &(impl RayCaster + ?Sized),
        t: f64,
        sats: &[SatState],
        pos_in_nav: &Vector3<f64>,
        vel_in_nav: &Vector3<f64>,
        rng: &mut impl Rng,
    ) -> Vec<SatObservation> {
        let rx = self.frame.ecef_from_ned(pos_in_nav);
        let v_rx = self.frame.ecef_vector(vel_in_nav);
        let bias = self.clock_bias_m(t);
        let mut out = Vec::new();
        for (sat, s) in sats.iter().enumerate() {
            let u_reception: f64 = rng.random();
            let u_delay: f64 = rng.random();
            let z_rho: f64 = rng.sample(StandardNormal);
            let z_rate: f64 = rng.sample(StandardNormal);
            let d = s.pos_ecef - rx;
            let range = d.norm();
            let u = d / range;
            let los_in_nav = self.frame.ned_from_ecef() * u;
            let sin_el = -los_in_nav.z;
            if !range.is_finite() || sin_el < self.sin_mask {
                continue;
            }
            let los = map.cast(pos_in_nav, &los_in_nav, f64::INFINITY).is_none();
            let received = los || u_reception < self.p_nlos;
            let excess = if los {
                0.0
            } else {
                self.delay.0 + u_delay * (self.delay.1 - self.delay.0)
            };
            let rate = u.dot(&(s.vel_ecef - v_rx)) + self.drift;
            out.push(SatObservation {
                sat,
                state: *s,
                elevation_rad: sin_el.clamp(-1.0, 1.0).asin(),
                azimuth_rad: los_in_nav.y.atan2(los_in_nav.x),
                los_in_nav,
                los,
                received,
                true_range_m: range,
                excess_delay_m: excess,
                pseudorange_m: received.then_some(range + bias + excess + self.sigma_rho * z_rho),
                range_rate_mps: received.then_some(rate + self.sigma_rate * z_rate),
            });
        }
        out
    }
}

//! Mode switching (section 3.1): GPS/INS while enough satellites are in line of sight,
//! map-aided range/INS otherwise, with hysteresis on the count and on the time in a
//! mode. Both modes update the one 12-state filter, so a switch carries the full state
//! and covariance over: nothing is re-initialized.
//!
//! [`ModeSwitch`] is the decision alone (LOS count in, mode out);
//! [`SwitchingFilter`] owns the filter, the decision and a map-aided update (GREKF or
//! MGPMF) and routes each measurement to the active mode.

use fathom_core::{RayCaster, Time};

use super::error::{MapAidedError, finite_input};
use super::gps::{GpsFix, GpsOutcome};
use super::grekf::{Grekf, GrekfReport};
use super::ins12::{Correction, Ins12Filter, NominalNav};
use super::mgpmf::{Mgpmf, MgpmfReport};
use super::params::{GpsAiding, SwitchSettings};
use super::range_model::{BaroHeight, RangeBeam};
use crate::EstimatorError;
use nalgebra::{UnitQuaternion, Vector3};

/// The navigation mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NavMode {
    /// Loosely coupled GPS/INS.
    GpsIns,
    /// Map-aided range/INS (GREKF or MGPMF).
    MapAided,
}

/// The switching decision with hysteresis (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ModeSwitch {
    settings: SwitchSettings,
    mode: NavMode,
    since: Time,
    last: Time,
    switches: usize,
}

impl ModeSwitch {
    /// A decision starting in `mode` at `t0`.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a non-finite `t0`.
    pub fn new(settings: SwitchSettings, mode: NavMode, t0: Time) -> Result<Self, MapAidedError> {
        finite_input("mode switch start time", &[t0], t0)?;
        Ok(Self {
            settings,
            mode,
            since: t0,
            last: t0,
            switches: 0,
        })
    }

    /// The current mode.
    pub fn mode(&self) -> NavMode {
        self.mode
    }

    /// Number of switches so far.
    pub fn switches(&self) -> usize {
        self.switches
    }

    /// Takes the LOS satellite count at `t` and returns the mode from now on: GPS/INS
    /// goes map-aided when the count drops below `min_los_satellites`; map-aided
    /// returns to GPS/INS when it reaches `min_los_satellites + hysteresis`; no switch
    /// within `min_dwell_s` of the last one.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a non-finite `t`,
    /// [`EstimatorError::TimeBackwards`] for `t` before the last call; the decision
    /// is then unchanged.
    pub fn observe(&mut self, t: Time, los_satellites: usize) -> Result<NavMode, MapAidedError> {
        finite_input("LOS epoch time", &[t], self.last)?;
        if t < self.last {
            return Err(EstimatorError::TimeBackwards {
                what: "mode switch".into(),
                prev: self.last,
                next: t,
            }
            .into());
        }
        self.last = t;
        let dwell_ok = t - self.since >= self.settings.min_dwell;
        let next = match self.mode {
            NavMode::GpsIns if los_satellites < self.settings.leave_gps_below => NavMode::MapAided,
            NavMode::MapAided if los_satellites >= self.settings.enter_gps_at => NavMode::GpsIns,
            m => m,
        };
        if next != self.mode && dwell_ok {
            self.mode = next;
            self.since = t;
            self.switches += 1;
        }
        Ok(self.mode)
    }
}

/// The map-aided update used in map-aided mode.
#[derive(Debug, Clone)]
pub enum MapAider {
    /// The GREKF (bridge scenario of the paper).
    Grekf(Grekf),
    /// The MGPMF (buildings scenario of the paper).
    Mgpmf(Box<Mgpmf>),
}

/// What a map-aided update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MapReport {
    /// GREKF report.
    Grekf(GrekfReport),
    /// MGPMF report.
    Mgpmf(MgpmfReport),
}

/// The 12-state filter with mode switching (module docs).
#[derive(Debug, Clone)]
pub struct SwitchingFilter {
    filter: Ins12Filter,
    switch: ModeSwitch,
    gps: GpsAiding,
    aider: MapAider,
}

impl SwitchingFilter {
    /// Combines a filter, a decision, the GPS settings and the map-aided update.
    pub fn new(filter: Ins12Filter, switch: ModeSwitch, gps: GpsAiding, aider: MapAider) -> Self {
        Self {
            filter,
            switch,
            gps,
            aider,
        }
    }

    /// The filter.
    pub fn filter(&self) -> &Ins12Filter {
        &self.filter
    }

    /// The current mode.
    pub fn mode(&self) -> NavMode {
        self.switch.mode()
    }

    /// The decision.
    pub fn switch(&self) -> &ModeSwitch {
        &self.switch
    }

    /// [`Ins12Filter::predict`].
    ///
    /// # Errors
    /// As [`Ins12Filter::predict`].
    pub fn predict(
        &mut self,
        nav_from_body: &UnitQuaternion<f64>,
        specific_force_in_body: &Vector3<f64>,
        t: Time,
    ) -> Result<(), MapAidedError> {
        self.filter
            .predict(nav_from_body, specific_force_in_body, t)
    }

    /// [`ModeSwitch::observe`]: the LOS count at `t`; the filter is untouched.
    ///
    /// # Errors
    /// As [`ModeSwitch::observe`].
    pub fn observe_los(
        &mut self,
        t: Time,
        los_satellites: usize,
    ) -> Result<NavMode, MapAidedError> {
        self.switch.observe(t, los_satellites)
    }

    /// The GPS update in GPS/INS mode (`None` in map-aided mode: not applied).
    ///
    /// # Errors
    /// As [`Ins12Filter::update_gps`].
    pub fn update_gps(
        &mut self,
        nominal: &NominalNav,
        fix: &GpsFix,
    ) -> Result<Option<GpsOutcome>, MapAidedError> {
        if self.switch.mode() != NavMode::GpsIns {
            return Ok(None);
        }
        self.filter.update_gps(nominal, fix, &self.gps).map(Some)
    }

    /// The map-aided update in map-aided mode (`None` in GPS/INS mode: not applied).
    ///
    /// # Errors
    /// As [`Grekf::update`] / [`Mgpmf::update`].
    pub fn update_map(
        &mut self,
        nominal: &NominalNav,
        beams: &[RangeBeam],
        baro: Option<&BaroHeight>,
        caster: &dyn RayCaster,
    ) -> Result<Option<MapReport>, MapAidedError> {
        if self.switch.mode() != NavMode::MapAided {
            return Ok(None);
        }
        Ok(Some(match &mut self.aider {
            MapAider::Grekf(g) => {
                MapReport::Grekf(g.update(&mut self.filter, nominal, beams, baro, caster)?)
            }
            MapAider::Mgpmf(m) => {
                MapReport::Mgpmf(m.update(&mut self.filter, nominal, beams, baro, caster)?)
            }
        }))
    }

    /// [`Ins12Filter::take_correction`].
    pub fn take_correction(&mut self) -> Correction {
        self.filter.take_correction()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::params::{GpsParams, Ins12Params, RangeParams, SwitchParams};
    use crate::map_aided::test_support::Planes;
    use nalgebra::Matrix3;

    /// Hysteresis on the count and on time; bad times are typed errors that leave the
    /// decision unchanged.
    #[test]
    fn hysteresis_on_count_and_dwell() {
        let s = SwitchParams {
            min_los_satellites: 5,
            hysteresis_satellites: 2,
            min_dwell_s: 1.0,
        }
        .check()
        .unwrap();
        let mut m = ModeSwitch::new(s, NavMode::GpsIns, 0.0).unwrap();
        let seq = [
            (1.0, 5, NavMode::GpsIns),
            (2.0, 4, NavMode::MapAided),
            (2.5, 9, NavMode::MapAided), // within the dwell
            (3.5, 6, NavMode::MapAided), // 6 < 5 + 2
            (4.0, 7, NavMode::GpsIns),
            (4.5, 3, NavMode::GpsIns), // dwell
            (5.0, 5, NavMode::GpsIns), // 5 is enough to stay
            (6.0, 4, NavMode::MapAided),
        ];
        for (t, n, want) in seq {
            assert_eq!(m.observe(t, n).unwrap(), want, "t = {t}");
        }
        assert_eq!(m.switches(), 3);
        let before = m.clone();
        let e = m.observe(5.0, 9).unwrap_err();
        assert_eq!(e.time(), Some(5.0));
        assert!(m.observe(f64::NAN, 9).is_err());
        assert_eq!(m, before);
    }

    /// A switch touches neither the state nor the covariance, and each mode's update
    /// starts from what the other left; measurements of the inactive mode are not
    /// applied.
    #[test]
    fn switching_carries_state_and_covariance_over() {
        let p0 = Ins12Filter::diagonal_covariance([2.0, 0.2, 0.01, 0.01]);
        let f = Ins12Filter::new(&p0, 0.0, Ins12Params::default().check().unwrap()).unwrap();
        let sw = ModeSwitch::new(
            SwitchParams {
                min_dwell_s: 0.0,
                ..SwitchParams::default()
            }
            .check()
            .unwrap(),
            NavMode::GpsIns,
            0.0,
        )
        .unwrap();
        let mut sf = SwitchingFilter::new(
            f,
            sw,
            GpsParams::default().check().unwrap(),
            MapAider::Grekf(Grekf::new(RangeParams::default().check().unwrap())),
        );
        let nav = NominalNav {
            pos_in_nav: Vector3::new(0.0, 1.0, -2.0),
            vel_in_nav: Vector3::zeros(),
            nav_from_body: UnitQuaternion::identity(),
            accel_bias_in_body: Vector3::zeros(),
        };
        let fix = GpsFix {
            pos_in_nav: Vector3::new(0.5, 1.2, -2.0),
            pos_cov: Matrix3::identity(),
            velocity: None,
        };
        let map = Planes::corridor(5.0);
        let beam = [RangeBeam {
            dir_in_body: Vector3::y(),
            range_m: 3.9,
            sigma_m: 0.05,
        }];
        assert!(sf.update_map(&nav, &beam, None, &map).unwrap().is_none());
        assert!(sf.update_gps(&nav, &fix).unwrap().unwrap().accepted);
        let after_gps = sf.filter().clone();
        assert_eq!(sf.observe_los(1.0, 2).unwrap(), NavMode::MapAided);
        assert_eq!(sf.filter(), &after_gps);
        assert!(sf.update_gps(&nav, &fix).unwrap().is_none());
        assert_eq!(sf.filter(), &after_gps);
        // the GREKF starts from the GPS-updated estimate: the prior variance of the
        // east error is the post-GPS one (about 0.8), not the initial 4
        let p_east = after_gps.covariance()[(1, 1)];
        assert!(p_east < 1.0);
        let rep = sf.update_map(&nav, &beam, None, &map).unwrap().unwrap();
        assert!(matches!(rep, MapReport::Grekf(r) if r.used == 1));
        assert!(sf.filter().covariance()[(1, 1)] < 0.01);
        let c = sf.take_correction();
        assert!(c.dpos_in_nav.y.abs() > 0.0);
        sf.predict(
            &UnitQuaternion::identity(),
            &Vector3::new(0.0, 0.0, -9.8),
            1.1,
        )
        .unwrap();
    }
}

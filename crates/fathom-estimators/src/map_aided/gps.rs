//! GPS/INS: the loosely coupled update of the 12-state filter with a GPS position fix
//! (and velocity, when the receiver gives it), chi-square gated.
//!
//! Measurement model (error convention of [`super`]): `z_p = p + v_p = p_hat - dp + v_p`,
//! so `H = [-I 0 0 0]`; with velocity, `z_v = v_hat - dv + v_v`, `H = [0 -I 0 0]`.
//! The innovation is taken at the current estimate, `z - h(x_hat (-) dx_hat)`.
//!
//! A filter that diverged while GPS was away (in a GNSS shadow) rejects every fix
//! when it comes back: its covariance is too small for the error the fix shows.
//! [`GpsReacquire`] counts the fixes rejected in a row and, after
//! [`GpsAiding::reacquire_after`] of them, widens the position (and velocity)
//! covariance by the outer product of the innovation before applying the next fix:
//! with `S' = S + nu nu^T` the NIS is `a / (1 + a) < 1` (`a = nu^T S^-1 nu`), so the
//! fix passes the gate and the estimate jumps to it, as an autopilot's estimator
//! resets to GNSS after a run of failed innovation checks.

use fathom_core::Time;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::error::{MapAidedError, finite_input};
use super::ins12::{Ins12Filter, NominalNav};
use super::params::GpsAiding;
use super::{N_STATES, POS, VEL};
use crate::{Gate, GateThreshold};

/// A GPS velocity with its covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsVelocity {
    /// Velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Its covariance, (m/s)^2.
    pub cov: Matrix3<f64>,
}

/// A GPS fix in the local NED frame (e.g. BESTPOS or a single-point solution).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsFix {
    /// Position in NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Its covariance, m^2.
    pub pos_cov: Matrix3<f64>,
    /// Velocity, when the receiver gives it.
    pub velocity: Option<GpsVelocity>,
}

/// What a GPS update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsOutcome {
    /// Whether the fix passed the gate and was applied.
    pub accepted: bool,
    /// Its NIS (3 or 6 dof).
    pub nis: f64,
    /// The dimension of the fix (3: position, 6: with velocity).
    pub dof: usize,
    /// The fix re-acquired the position after a run of rejections ([`GpsReacquire`]).
    pub reacquired: bool,
}

fn outcome<const M: usize>(g: &Gate<M>) -> GpsOutcome {
    GpsOutcome {
        accepted: g.is_accepted(),
        nis: g.nis(),
        dof: M,
        reacquired: false,
    }
}

fn check_fix(fix: &GpsFix, time: Time) -> Result<(), MapAidedError> {
    finite_input("gps pos_in_nav", fix.pos_in_nav.as_slice(), time)?;
    finite_input("gps pos_cov", fix.pos_cov.as_slice(), time)?;
    if let Some(v) = &fix.velocity {
        finite_input("gps vel_in_nav", v.vel_in_nav.as_slice(), time)?;
        finite_input("gps vel cov", v.cov.as_slice(), time)?;
    }
    Ok(())
}

impl Ins12Filter {
    /// The loosely coupled GPS update at the filter time (module docs). A fix failing
    /// the gate is not applied (the filter is unchanged) and reported.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidInput`] for a non-finite nominal state or fix;
    /// [`MapAidedError::Filter`] for a covariance that is not symmetric positive
    /// definite (e.g. a negative variance), with the time stamp. The filter is
    /// unchanged on error.
    pub fn update_gps(
        &mut self,
        nominal: &NominalNav,
        fix: &GpsFix,
        aiding: &GpsAiding,
    ) -> Result<GpsOutcome, MapAidedError> {
        let t = self.time();
        nominal.check(t)?;
        check_fix(fix, t)?;
        let est = nominal.corrected(self.error_mean());
        match &fix.velocity {
            None => {
                let mut h = SMatrix::<f64, 3, N_STATES>::zeros();
                h.fixed_view_mut::<3, 3>(0, POS)
                    .copy_from(&(-Matrix3::identity()));
                let nu = fix.pos_in_nav - est.pos_in_nav;
                let gate = GateThreshold::from_squared_distance(aiding.gate_position)?;
                let g = self
                    .kf_mut()
                    .update_with_innovation_gated(&nu, &h, &fix.pos_cov, gate)?;
                Ok(outcome(&g))
            }
            Some(v) => {
                let mut h = SMatrix::<f64, 6, N_STATES>::zeros();
                h.fixed_view_mut::<3, 3>(0, POS)
                    .copy_from(&(-Matrix3::identity()));
                h.fixed_view_mut::<3, 3>(3, VEL)
                    .copy_from(&(-Matrix3::identity()));
                let mut nu = SVector::<f64, 6>::zeros();
                nu.fixed_rows_mut::<3>(0)
                    .copy_from(&(fix.pos_in_nav - est.pos_in_nav));
                nu.fixed_rows_mut::<3>(3)
                    .copy_from(&(v.vel_in_nav - est.vel_in_nav));
                let mut r = SMatrix::<f64, 6, 6>::zeros();
                r.fixed_view_mut::<3, 3>(0, 0).copy_from(&fix.pos_cov);
                r.fixed_view_mut::<3, 3>(3, 3).copy_from(&v.cov);
                let gate = GateThreshold::from_squared_distance(aiding.gate_position_velocity)?;
                let g = self
                    .kf_mut()
                    .update_with_innovation_gated(&nu, &h, &r, gate)?;
                Ok(outcome(&g))
            }
        }
    }
}

/// GPS updates with re-acquisition after a run of rejected fixes (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GpsReacquire {
    rejected_in_a_row: usize,
}

impl GpsReacquire {
    /// Fixes rejected in a row so far.
    pub fn rejected_in_a_row(&self) -> usize {
        self.rejected_in_a_row
    }

    /// [`Ins12Filter::update_gps`], and after `aiding.reacquire_after()` rejections
    /// in a row the re-acquisition (module docs); [`GpsOutcome::reacquired`] says
    /// when it happened.
    ///
    /// # Errors
    /// As [`Ins12Filter::update_gps`]; the filter and the count are unchanged on
    /// error.
    pub fn update(
        &mut self,
        filter: &mut Ins12Filter,
        nominal: &NominalNav,
        fix: &GpsFix,
        aiding: &GpsAiding,
    ) -> Result<GpsOutcome, MapAidedError> {
        let out = filter.update_gps(nominal, fix, aiding)?;
        if out.accepted {
            self.rejected_in_a_row = 0;
            return Ok(out);
        }
        let run = self.rejected_in_a_row + 1;
        let n = aiding.reacquire_after();
        if n == 0 || run < n {
            self.rejected_in_a_row = run;
            return Ok(out);
        }
        let est = nominal.corrected(filter.error_mean());
        let mut f = filter.clone();
        let dp = fix.pos_in_nav - est.pos_in_nav;
        f.widen_covariance_block(POS, &(dp * dp.transpose()))?;
        if let Some(v) = &fix.velocity {
            let dv = v.vel_in_nav - est.vel_in_nav;
            f.widen_covariance_block(VEL, &(dv * dv.transpose()))?;
        }
        let again = f.update_gps(nominal, fix, aiding)?;
        if again.accepted {
            *filter = f;
            self.rejected_in_a_row = 0;
            return Ok(GpsOutcome {
                reacquired: true,
                ..again
            });
        }
        self.rejected_in_a_row = run;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::params::{GpsParams, Ins12Params};
    use nalgebra::UnitQuaternion;

    fn setup() -> (Ins12Filter, NominalNav, GpsAiding) {
        let p0 = Ins12Filter::diagonal_covariance([2.0, 0.5, 0.01, 0.01]);
        let f = Ins12Filter::new(&p0, 5.0, Ins12Params::default().check().unwrap()).unwrap();
        let nav = NominalNav {
            pos_in_nav: Vector3::new(10.0, 20.0, -30.0),
            vel_in_nav: Vector3::new(1.0, 0.0, 0.0),
            nav_from_body: UnitQuaternion::identity(),
            accel_bias_in_body: Vector3::zeros(),
        };
        (f, nav, GpsParams::default().check().unwrap())
    }

    /// A fix 1 m north of the nominal: the error estimate says the nominal is 1 m too
    /// far south (dp_N < 0, gain 4 / (4 + 1)); applying the correction moves it north.
    #[test]
    fn position_fix_estimates_the_error_with_the_right_sign() {
        let (mut f, nav, aid) = setup();
        let fix = GpsFix {
            pos_in_nav: nav.pos_in_nav + Vector3::new(1.0, 0.0, 0.0),
            pos_cov: Matrix3::identity(),
            velocity: None,
        };
        let out = f.update_gps(&nav, &fix, &aid).unwrap();
        assert!(out.accepted && out.dof == 3);
        assert!((f.error_mean()[POS] + 0.8).abs() < 1e-12);
        let c = f.take_correction();
        assert!((c.apply(&nav).pos_in_nav.x - 10.8).abs() < 1e-12);
        // with velocity: 6 dof
        let fix = GpsFix {
            velocity: Some(GpsVelocity {
                vel_in_nav: Vector3::new(1.5, 0.0, 0.0),
                cov: Matrix3::identity() * 0.01,
            }),
            ..fix
        };
        let out = f.update_gps(&c.apply(&nav), &fix, &aid).unwrap();
        assert!(out.accepted && out.dof == 6);
        assert!(f.error_mean()[VEL] < -0.4);
    }

    /// The gate rejects a 100 m jump (filter unchanged); bad input is a typed error
    /// with the time stamp and leaves the filter unchanged.
    #[test]
    fn gating_and_bad_input() {
        let (mut f, nav, aid) = setup();
        let before = f.clone();
        let jump = GpsFix {
            pos_in_nav: nav.pos_in_nav + Vector3::new(100.0, 0.0, 0.0),
            pos_cov: Matrix3::identity(),
            velocity: None,
        };
        let out = f.update_gps(&nav, &jump, &aid).unwrap();
        assert!(!out.accepted && out.nis > 1000.0);
        assert_eq!(f, before);
        let nan = GpsFix {
            pos_in_nav: Vector3::new(f64::NAN, 0.0, 0.0),
            ..jump
        };
        let e = f.update_gps(&nav, &nan, &aid).unwrap_err();
        assert_eq!(e.time(), Some(5.0));
        let neg = GpsFix {
            pos_in_nav: nav.pos_in_nav,
            pos_cov: -Matrix3::identity(),
            velocity: None,
        };
        let e = f.update_gps(&nav, &neg, &aid).unwrap_err();
        assert_eq!(e.time(), Some(5.0), "{e}");
        assert_eq!(f, before);
    }

    /// A filter 100 m off: without re-acquisition every fix is rejected for ever;
    /// with `reacquire_after = 3` the third rejected fix re-acquires and the estimate
    /// lands within a metre of the fix; a consistent fix resets the count.
    #[test]
    fn reacquisition_after_a_run_of_rejections() {
        let (f0, nav, _) = setup();
        let fix = GpsFix {
            pos_in_nav: nav.pos_in_nav + Vector3::new(100.0, -50.0, 0.0),
            pos_cov: Matrix3::identity(),
            velocity: None,
        };
        let never = GpsParams::default().check().unwrap();
        let mut f = f0.clone();
        let mut r = GpsReacquire::default();
        for _ in 0..20 {
            let o = r.update(&mut f, &nav, &fix, &never).unwrap();
            assert!(!o.accepted && !o.reacquired);
        }
        assert_eq!(f, f0);
        assert_eq!(r.rejected_in_a_row(), 20);
        let after3 = GpsParams {
            reacquire_after_rejections: 3,
            ..GpsParams::default()
        }
        .check()
        .unwrap();
        let mut f = f0.clone();
        let mut r = GpsReacquire::default();
        for k in 1..=3 {
            let o = r.update(&mut f, &nav, &fix, &after3).unwrap();
            assert_eq!(o.reacquired, k == 3, "fix {k}");
            assert_eq!(o.accepted, k == 3);
        }
        assert_eq!(r.rejected_in_a_row(), 0);
        let c = f.take_correction();
        let moved = c.apply(&nav).pos_in_nav;
        assert!((moved - fix.pos_in_nav).norm() < 1.0, "{moved}");
        // a consistent fix is accepted and keeps the count at 0
        let o = r.update(&mut f, &c.apply(&nav), &fix, &after3).unwrap();
        assert!(o.accepted && !o.reacquired);
    }
}

//! The INS navigation state and the IMU increment that drives it.

use fathom_core::frames::{Euler, euler_from_nav_from_body};
use nalgebra::{UnitQuaternion, Vector3};

use crate::earth::Geodetic;
use crate::error::{InsError, check_finite};

/// Navigation state of a local-level NED strapdown INS on WGS-84.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsState {
    /// Geodetic latitude `L`, rad.
    pub lat: f64,
    /// Longitude `lambda`, rad.
    pub lon: f64,
    /// Height above the ellipsoid `h`, m (up positive; depth = `-h`).
    pub h: f64,
    /// Velocity with respect to the Earth resolved in NED, `[v_N, v_E, v_D]`, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Attitude `C_b^n` as a unit quaternion (rotates body vectors into NED).
    pub nav_from_body: UnitQuaternion<f64>,
}

impl InsState {
    /// State from a geodetic position, NED velocity and attitude quaternion.
    pub fn new(
        pos: Geodetic,
        vel_in_nav: Vector3<f64>,
        nav_from_body: UnitQuaternion<f64>,
    ) -> Self {
        Self {
            lat: pos.lat,
            lon: pos.lon,
            h: pos.h,
            vel_in_nav,
            nav_from_body,
        }
    }

    /// State from a geodetic position, NED velocity and ZYX Euler angles.
    pub fn from_euler(pos: Geodetic, vel_in_nav: Vector3<f64>, att: &Euler) -> Self {
        Self::new(
            pos,
            vel_in_nav,
            UnitQuaternion::from_euler_angles(att.roll, att.pitch, att.yaw),
        )
    }

    /// The position as a [`Geodetic`].
    pub fn position(&self) -> Geodetic {
        Geodetic::new(self.lat, self.lon, self.h)
    }

    /// Roll/pitch/yaw (ZYX) of `nav_from_body`.
    pub fn euler(&self) -> Euler {
        euler_from_nav_from_body(&self.nav_from_body.to_rotation_matrix())
    }

    /// Checks that every field is finite and the latitude is strictly inside
    /// (-pi/2, pi/2).
    ///
    /// # Errors
    /// [`InsError::NonFinite`] naming the field, or [`InsError::LatitudeOutOfRange`].
    pub fn check(&self) -> Result<(), InsError> {
        check_finite("position [lat, lon, h]", &[self.lat, self.lon, self.h])?;
        check_finite("vel_in_nav", self.vel_in_nav.as_slice())?;
        check_finite(
            "nav_from_body",
            self.nav_from_body.as_ref().coords.as_slice(),
        )?;
        if self.lat.abs() >= std::f64::consts::FRAC_PI_2 {
            return Err(InsError::LatitudeOutOfRange { lat: self.lat });
        }
        Ok(())
    }
}

/// One IMU output interval: the integrated angular rate and specific force over `dt`
/// (the "delta-theta / delta-v" outputs of a strapdown IMU), both in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuIncrement {
    /// Interval length, s (> 0).
    pub dt: f64,
    /// Integrated inertial angular rate `int omega_ib^b dt`, rad.
    pub delta_theta: Vector3<f64>,
    /// Integrated specific force `int f_ib^b dt`, m/s.
    pub delta_v: Vector3<f64>,
}

impl ImuIncrement {
    /// An increment from its parts (not checked; see [`ImuIncrement::check`]).
    pub fn new(dt: f64, delta_theta: Vector3<f64>, delta_v: Vector3<f64>) -> Self {
        Self {
            dt,
            delta_theta,
            delta_v,
        }
    }

    /// Average angular rate over the interval, `delta_theta / dt`, rad/s.
    pub fn mean_angular_rate(&self) -> Vector3<f64> {
        self.delta_theta / self.dt
    }

    /// Average specific force over the interval, `delta_v / dt`, m/s^2.
    pub fn mean_specific_force(&self) -> Vector3<f64> {
        self.delta_v / self.dt
    }

    /// Checks finiteness and `dt > 0`.
    ///
    /// # Errors
    /// [`InsError::NonPositiveDt`] or [`InsError::NonFinite`] naming the field.
    pub fn check(&self) -> Result<(), InsError> {
        check_finite("dt", &[self.dt])?;
        if self.dt <= 0.0 {
            return Err(InsError::NonPositiveDt { dt: self.dt });
        }
        check_finite("delta_theta", self.delta_theta.as_slice())?;
        check_finite("delta_v", self.delta_v.as_slice())?;
        Ok(())
    }
}

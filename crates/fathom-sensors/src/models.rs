//! Sensor models of the beacons paper (B, Tables 4-6, eqs. 1-3): DVL body
//! velocity, AHRS angular rate and attitude, range to a beacon, depth.
//!
//! Each model computes the noise-free value from the true state at the exact
//! sample time (`traj.state_at(sample_time)`) and adds white Gaussian noise. A zero
//! sigma (on any axis) is valid and means no noise there; the draw is still
//! consumed. RNG draw order per measurement: vector sensors draw three standard
//! normals in axis order (x, y, z / roll, pitch, yaw), scalar sensors one.

use fathom_core::{Measurement, SensorId, Time, frames::Euler};
use fathom_traj::{Trajectory, TrueState};
use nalgebra::Vector3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::{
    SensorError,
    error::{check_finite3, check_sigma, check_sigma3},
    noise::gauss,
    schedule::SampleTimes,
};

/// Default beacon positions (NED, m): non-coplanar so that 3D position is observable.
pub const DEFAULT_BEACONS_IN_NAV: [[f64; 3]; 4] = [
    [15.0, 15.0, 0.0],
    [-15.0, 15.0, 40.0],
    [-15.0, -15.0, 0.0],
    [15.0, -15.0, 40.0],
];

/// The default beacon positions as vectors.
pub fn default_beacons_in_nav() -> Vec<Vector3<f64>> {
    DEFAULT_BEACONS_IN_NAV
        .iter()
        .map(|b| Vector3::new(b[0], b[1], b[2]))
        .collect()
}

/// A sensor that measures a function of the true state with additive noise.
pub trait SensorModel {
    /// The measured quantity.
    type Value: Clone;

    /// Which sensor this is.
    fn id(&self) -> SensorId;

    /// The noise-free value at the given true state.
    fn true_value(&self, state: &TrueState) -> Self::Value;

    /// Adds one realization of the sensor noise to `true_value`.
    fn add_noise(&self, true_value: &Self::Value, rng: &mut impl Rng) -> Self::Value;

    /// Measures the given true state; `sample_time` is `state.time`.
    fn measure_state(
        &self,
        state: &TrueState,
        stamp: Time,
        rng: &mut impl Rng,
    ) -> Measurement<Self::Value> {
        let true_value = self.true_value(state);
        Measurement {
            sensor: self.id(),
            sample_time: state.time,
            stamp,
            value: self.add_noise(&true_value, rng),
            true_value,
        }
    }

    /// Measures the trajectory at `sample_time`, reporting `stamp`.
    ///
    /// # Errors
    /// [`SensorError::Traj`] when the trajectory cannot be evaluated there.
    fn measure(
        &self,
        traj: &impl Trajectory,
        sample_time: Time,
        stamp: Time,
        rng: &mut impl Rng,
    ) -> Result<Measurement<Self::Value>, SensorError> {
        let state = traj.state_at(sample_time)?;
        Ok(self.measure_state(&state, stamp, rng))
    }

    /// Measures the trajectory at every sample of `times`, in order.
    ///
    /// # Errors
    /// [`SensorError::Traj`] when a sample time is outside the trajectory.
    fn measure_all(
        &self,
        traj: &impl Trajectory,
        times: &SampleTimes,
        rng: &mut impl Rng,
    ) -> Result<Vec<Measurement<Self::Value>>, SensorError> {
        times
            .iter()
            .map(|(t, stamp)| self.measure(traj, t, stamp, rng))
            .collect()
    }
}

fn noisy3(v: &Vector3<f64>, sigma: &Vector3<f64>, rng: &mut impl Rng) -> Vector3<f64> {
    let nx = gauss(rng, sigma.x);
    let ny = gauss(rng, sigma.y);
    let nz = gauss(rng, sigma.z);
    v + Vector3::new(nx, ny, nz)
}

/// Unchecked DVL parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DvlParams {
    /// Noise sigma per body axis `(u, v, w)`, m/s. Default `(0.1, 0, 0.1)` (Table 10).
    pub sigma: Vector3<f64>,
}

impl Default for DvlParams {
    fn default() -> Self {
        Self {
            sigma: Vector3::new(0.1, 0.0, 0.1),
        }
    }
}

impl DvlParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative or non-finite sigma.
    pub fn check(&self) -> Result<Dvl, SensorError> {
        Ok(Dvl {
            sigma: check_sigma3("dvl.sigma", &self.sigma)?,
        })
    }
}

/// DVL: body-frame velocity `u_s = C_n^b v_n + n_u` (eq. 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dvl {
    sigma: Vector3<f64>,
}

impl Dvl {
    /// Noise sigma per axis.
    pub fn sigma(&self) -> Vector3<f64> {
        self.sigma
    }
}

impl SensorModel for Dvl {
    type Value = Vector3<f64>;
    fn id(&self) -> SensorId {
        SensorId::Dvl
    }
    fn true_value(&self, state: &TrueState) -> Vector3<f64> {
        state.vel_in_body()
    }
    fn add_noise(&self, v: &Vector3<f64>, rng: &mut impl Rng) -> Vector3<f64> {
        noisy3(v, &self.sigma, rng)
    }
}

/// Unchecked AHRS angular-rate parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AhrsRateParams {
    /// Noise sigma per body rate `(p, q, r)`, rad/s. Default `(0, 0, 0.1)` (Table 10).
    pub sigma: Vector3<f64>,
}

impl Default for AhrsRateParams {
    fn default() -> Self {
        Self {
            sigma: Vector3::new(0.0, 0.0, 0.1),
        }
    }
}

impl AhrsRateParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative or non-finite sigma.
    pub fn check(&self) -> Result<AhrsRate, SensorError> {
        Ok(AhrsRate {
            sigma: check_sigma3("ahrs_rate.sigma", &self.sigma)?,
        })
    }
}

/// AHRS angular rate: body rates `(p, q, r) + n` (eq. 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AhrsRate {
    sigma: Vector3<f64>,
}

impl AhrsRate {
    /// Noise sigma per axis.
    pub fn sigma(&self) -> Vector3<f64> {
        self.sigma
    }
}

impl SensorModel for AhrsRate {
    type Value = Vector3<f64>;
    fn id(&self) -> SensorId {
        SensorId::Ahrs
    }
    fn true_value(&self, state: &TrueState) -> Vector3<f64> {
        state.omega_body
    }
    fn add_noise(&self, v: &Vector3<f64>, rng: &mut impl Rng) -> Vector3<f64> {
        noisy3(v, &self.sigma, rng)
    }
}

/// Unchecked AHRS attitude parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct AhrsAttitudeParams {
    /// Noise sigma per Euler angle `(roll, pitch, yaw)`, rad. Default zero.
    pub sigma: Vector3<f64>,
}

impl AhrsAttitudeParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative or non-finite sigma.
    pub fn check(&self) -> Result<AhrsAttitude, SensorError> {
        Ok(AhrsAttitude {
            sigma: check_sigma3("ahrs_attitude.sigma", &self.sigma)?,
        })
    }
}

/// AHRS attitude: Euler angles plus independent noise per angle (angles are not
/// re-wrapped after the noise is added).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AhrsAttitude {
    sigma: Vector3<f64>,
}

impl SensorModel for AhrsAttitude {
    type Value = Euler;
    fn id(&self) -> SensorId {
        SensorId::Ahrs
    }
    fn true_value(&self, state: &TrueState) -> Euler {
        state.attitude
    }
    fn add_noise(&self, v: &Euler, rng: &mut impl Rng) -> Euler {
        Euler::from_vector(&noisy3(&v.to_vector(), &self.sigma, rng))
    }
}

/// Unchecked range-sensor parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RangeParams {
    /// Zero-based beacon index (becomes [`SensorId::Range`]).
    pub beacon_index: usize,
    /// Beacon position in NED, m.
    pub beacon_in_nav: Vector3<f64>,
    /// White noise sigma, m. Default 0.1.
    pub sigma: f64,
}

impl RangeParams {
    /// Range to the given beacon with the default sigma 0.1 m.
    pub fn new(beacon_index: usize, beacon_in_nav: Vector3<f64>) -> Self {
        Self {
            beacon_index,
            beacon_in_nav,
            sigma: 0.1,
        }
    }

    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a non-finite beacon position or a
    /// negative / non-finite sigma.
    pub fn check(&self) -> Result<RangeSensor, SensorError> {
        Ok(RangeSensor {
            beacon_index: self.beacon_index,
            beacon_in_nav: check_finite3(
                &format!("beacon[{}]", self.beacon_index),
                &self.beacon_in_nav,
            )?,
            sigma: check_sigma("range.sigma", self.sigma)?,
        })
    }
}

/// Range to a beacon: `r_s = |B_k - p| + n_r` (Table 5, eq. 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeSensor {
    beacon_index: usize,
    beacon_in_nav: Vector3<f64>,
    sigma: f64,
}

impl RangeSensor {
    /// Beacon position, NED, m.
    pub fn beacon_in_nav(&self) -> Vector3<f64> {
        self.beacon_in_nav
    }

    /// Noise sigma, m.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Geometric distance from `pos_in_nav` to the beacon.
    pub fn true_range(&self, pos_in_nav: &Vector3<f64>) -> f64 {
        (self.beacon_in_nav - pos_in_nav).norm()
    }
}

impl SensorModel for RangeSensor {
    type Value = f64;
    fn id(&self) -> SensorId {
        SensorId::Range(self.beacon_index)
    }
    fn true_value(&self, state: &TrueState) -> f64 {
        self.true_range(&state.pos_in_nav)
    }
    fn add_noise(&self, v: &f64, rng: &mut impl Rng) -> f64 {
        v + gauss(rng, self.sigma)
    }
}

/// Unchecked depth-sensor parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthParams {
    /// White noise sigma, m. Default 0.2.
    pub sigma: f64,
}

impl Default for DepthParams {
    fn default() -> Self {
        Self { sigma: 0.2 }
    }
}

impl DepthParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative or non-finite sigma.
    pub fn check(&self) -> Result<DepthSensor, SensorError> {
        Ok(DepthSensor {
            sigma: check_sigma("depth.sigma", self.sigma)?,
        })
    }
}

/// Depth gauge: `d = z + n_d` (Table 6, eq. 3; z is NED down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthSensor {
    sigma: f64,
}

impl DepthSensor {
    /// Noise sigma, m.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
}

impl SensorModel for DepthSensor {
    type Value = f64;
    fn id(&self) -> SensorId {
        SensorId::Depth
    }
    fn true_value(&self, state: &TrueState) -> f64 {
        state.pos_in_nav.z
    }
    fn add_noise(&self, v: &f64, rng: &mut impl Rng) -> f64 {
        v + gauss(rng, self.sigma)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::noise::tests::zero_mean_var_ok;
    use approx::assert_abs_diff_eq;
    use fathom_core::frames::nav_from_body;
    use fathom_traj::TrajError;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Horizontal circle of radius `radius` at constant depth rate, heading along
    /// the path (a helix), for tests.
    #[derive(Debug, Clone, Copy)]
    pub(crate) struct Helix {
        pub radius: f64,
        pub omega: f64,
        pub w: f64,
        pub t_end: f64,
    }

    impl Trajectory for Helix {
        fn start_time(&self) -> Time {
            0.0
        }
        fn end_time(&self) -> Time {
            self.t_end
        }
        fn state_at(&self, t: Time) -> Result<TrueState, TrajError> {
            if !(t.is_finite() && (0.0..=self.t_end).contains(&t)) {
                return Err(TrajError::OutOfRange {
                    t,
                    start: 0.0,
                    end: self.t_end,
                });
            }
            let (r, om) = (self.radius, self.omega);
            let (s, c) = (om * t).sin_cos();
            Ok(TrueState {
                time: t,
                pos_in_nav: Vector3::new(r * s, r * (1.0 - c), self.w * t),
                vel_in_nav: Vector3::new(r * om * c, r * om * s, self.w),
                acc_in_nav: Vector3::new(-r * om * om * s, r * om * om * c, 0.0),
                attitude: Euler::new(0.0, 0.0, om * t),
                omega_body: Vector3::new(0.0, 0.0, om),
            })
        }
    }

    pub(crate) fn helix() -> Helix {
        Helix {
            radius: 1.0,
            omega: 0.5,
            w: 0.2,
            t_end: 200.0,
        }
    }

    #[test]
    fn true_values_come_from_the_state_at_sample_time() {
        let traj = helix();
        let mut rng = ChaCha8Rng::seed_from_u64(20);
        let t = 3.37;
        let st = traj.state_at(t).unwrap();
        let dvl = DvlParams::default().check().unwrap();
        let m = dvl.measure(&traj, t, t + 0.01, &mut rng).unwrap();
        assert_eq!(m.sensor, SensorId::Dvl);
        assert_eq!((m.sample_time, m.stamp), (t, t + 0.01));
        // Heading along the path: body velocity is (r omega, 0, w).
        assert_abs_diff_eq!(m.true_value, Vector3::new(0.5, 0.0, 0.2), epsilon = 1e-12);
        assert_abs_diff_eq!(
            nav_from_body(&st.attitude) * m.true_value,
            st.vel_in_nav,
            epsilon = 1e-12
        );
        // Zero sigma on v: no noise on that axis.
        assert_eq!(m.value.y, m.true_value.y);
        assert_ne!(m.value.x, m.true_value.x);

        let ahrs = AhrsRateParams::default().check().unwrap();
        let m = ahrs.measure(&traj, t, t, &mut rng).unwrap();
        assert_eq!(m.true_value, Vector3::new(0.0, 0.0, 0.5));
        assert_eq!(m.value.xy(), m.true_value.xy());

        let att = AhrsAttitudeParams::default().check().unwrap();
        let m = att.measure(&traj, t, t, &mut rng).unwrap();
        assert_eq!(m.value, st.attitude);

        let b = Vector3::new(15.0, -15.0, 40.0);
        let range = RangeParams::new(3, b).check().unwrap();
        let m = range.measure(&traj, t, t, &mut rng).unwrap();
        assert_eq!(m.sensor, SensorId::Range(3));
        assert_abs_diff_eq!(m.true_value, (b - st.pos_in_nav).norm(), epsilon = 1e-12);

        let depth = DepthParams::default().check().unwrap();
        let m = depth.measure(&traj, t, t, &mut rng).unwrap();
        assert_eq!(m.true_value, st.pos_in_nav.z);
        assert!(depth.measure(&traj, 201.0, 201.0, &mut rng).is_err());
    }

    #[test]
    fn noise_variance_matches_sigma() {
        let traj = helix();
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let times = SampleTimes::exact(fathom_core::time::uniform_grid(0.0, 200.0, 0.01)).unwrap();
        let depth = DepthParams::default().check().unwrap();
        let noise: Vec<f64> = depth
            .measure_all(&traj, &times, &mut rng)
            .unwrap()
            .iter()
            .map(Measurement::noise)
            .collect();
        assert!(zero_mean_var_ok(&noise, 0.04, 1.0));
        assert!(!zero_mean_var_ok(&noise, 0.04 * 1.1, 1.0));
        let dvl = DvlParams::default().check().unwrap();
        let ms = dvl.measure_all(&traj, &times, &mut rng).unwrap();
        let nx: Vec<f64> = ms.iter().map(|m| m.value.x - m.true_value.x).collect();
        assert!(zero_mean_var_ok(&nx, 0.01, 1.0));
        assert!(ms.iter().all(|m| m.value.y == m.true_value.y));
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(
            DvlParams {
                sigma: Vector3::new(0.1, -0.1, 0.0)
            }
            .check()
            .is_err()
        );
        assert!(
            RangeParams::new(0, Vector3::new(f64::NAN, 0.0, 0.0))
                .check()
                .is_err()
        );
        assert!(DepthParams { sigma: f64::NAN }.check().is_err());
        assert!(
            AhrsRateParams {
                sigma: Vector3::new(0.0, f64::INFINITY, 0.0)
            }
            .check()
            .is_err()
        );
    }
}

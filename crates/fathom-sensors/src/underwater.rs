//! Velocity and altitude sensors of the `vkf` experiment (spec C, paper §3.2):
//! a DVL that loses bottom lock beyond its range, an echo sounder, and the propeller
//! RPM.
//!
//! - **Bottom-lock DVL**, velocity resolved in NED by the DVL's own attitude sensors:
//!   `v_dvl = (1 + sf) v + b + w`, `sf` drawn once per run, `b` once per run per
//!   axis, `w ~ N(0, sigma^2)` per axis; when the true altitude exceeds the range,
//!   `U(-g, g)` is added to each component (the paper's "garbage" model: bottom lock
//!   lost, output not flagged).
//! - **Echo sounder**: `alt_meas = alt + N(0, sigma^2)`.
//! - **Propeller RPM**: `rpm = (V_fwd - b_rpm) / k_rpm + n`, `n ~ N(0, sigma^2)`, so
//!   that `V_fwd = k_rpm rpm + b_rpm` up to noise (the VKF's `sf` and `b`).

use nalgebra::Vector3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::SensorError;
use crate::error::{check_finite, check_positive, check_sigma};
use crate::noise::{RunConstantDist, gauss};

/// Unchecked bottom-lock DVL parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BottomLockDvlParams {
    /// Scale-factor error distribution (one draw per run, common to the axes).
    pub scale_factor: RunConstantDist,
    /// Bias distribution, m/s (one draw per run and axis).
    pub bias: RunConstantDist,
    /// White noise sigma per axis, m/s.
    pub sigma: f64,
    /// Bottom-lock range (largest altitude with valid output), m.
    pub range: f64,
    /// Half width `g` of the uniform error added per component beyond the range, m/s.
    pub garbage_half_width: f64,
}

impl Default for BottomLockDvlParams {
    /// The spec C defaults: `sf ~ U(+-0.2 %)`, `b ~ U(+-0.005 m/s)`, sigma 0.02 m/s,
    /// range 100 m, garbage `U(+-5 m/s)`.
    fn default() -> Self {
        Self {
            scale_factor: RunConstantDist::Uniform { half_width: 0.002 },
            bias: RunConstantDist::Uniform { half_width: 0.005 },
            sigma: 0.02,
            range: 100.0,
            garbage_half_width: 5.0,
        }
    }
}

impl BottomLockDvlParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<BottomLockDvlModel, SensorError> {
        Ok(BottomLockDvlModel {
            params: Self {
                scale_factor: self.scale_factor.check()?,
                bias: self.bias.check()?,
                sigma: check_sigma("dvl.sigma", self.sigma)?,
                range: check_positive("dvl.range", self.range)?,
                garbage_half_width: check_sigma("dvl.garbage_half_width", self.garbage_half_width)?,
            },
        })
    }
}

/// Validated bottom-lock DVL parameters; [`BottomLockDvlModel::draw`] gives one
/// run's sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BottomLockDvlModel {
    params: BottomLockDvlParams,
}

impl BottomLockDvlModel {
    /// The validated parameters.
    pub fn params(&self) -> &BottomLockDvlParams {
        &self.params
    }

    /// Draws the run constants: scale factor, then the three biases.
    ///
    /// # Errors
    /// As [`RunConstantDist::draw`].
    pub fn draw(&self, rng: &mut impl Rng) -> Result<BottomLockDvl, SensorError> {
        let sf = self.params.scale_factor.draw(rng)?;
        let bx = self.params.bias.draw(rng)?;
        let by = self.params.bias.draw(rng)?;
        let bz = self.params.bias.draw(rng)?;
        Ok(BottomLockDvl {
            params: self.params,
            scale_factor: sf,
            bias: Vector3::new(bx, by, bz),
        })
    }
}

/// One DVL output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DvlReading {
    /// Measured velocity in NED, m/s.
    pub vel_in_nav: Vector3<f64>,
    /// Whether the DVL really had bottom lock (true altitude within range). This is
    /// truth, for analysis only: the DVL does not flag lost lock.
    pub bottom_lock: bool,
}

/// One run's bottom-lock DVL (run constants drawn).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BottomLockDvl {
    params: BottomLockDvlParams,
    scale_factor: f64,
    bias: Vector3<f64>,
}

impl BottomLockDvl {
    /// The run's scale-factor error.
    pub fn scale_factor(&self) -> f64 {
        self.scale_factor
    }

    /// The run's bias per axis, m/s.
    pub fn bias(&self) -> Vector3<f64> {
        self.bias
    }

    /// The bottom-lock range, m.
    pub fn range(&self) -> f64 {
        self.params.range
    }

    /// Measures the true NED velocity at true altitude `altitude`. Always consumes
    /// three standard normals and three uniforms (the latter used only without bottom
    /// lock), so the draws do not depend on the altitude.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a non-finite velocity or altitude.
    pub fn measure(
        &self,
        true_vel_in_nav: &Vector3<f64>,
        altitude: f64,
        rng: &mut impl Rng,
    ) -> Result<DvlReading, SensorError> {
        for i in 0..3 {
            check_finite("dvl true velocity", true_vel_in_nav[i])?;
        }
        check_finite("dvl true altitude", altitude)?;
        let bottom_lock = altitude <= self.params.range;
        let g = self.params.garbage_half_width;
        let mut v = Vector3::zeros();
        for i in 0..3 {
            let white = gauss(rng, self.params.sigma);
            let u: f64 = rng.random();
            let garbage = if bottom_lock {
                0.0
            } else {
                g * (2.0 * u - 1.0)
            };
            v[i] = (1.0 + self.scale_factor) * true_vel_in_nav[i] + self.bias[i] + white + garbage;
        }
        Ok(DvlReading {
            vel_in_nav: v,
            bottom_lock,
        })
    }
}

/// Echo sounder: altitude above the seabed with white noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EchoSounder {
    sigma: f64,
}

impl EchoSounder {
    /// An echo sounder with noise sigma `sigma` m.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative or non-finite sigma.
    pub fn new(sigma: f64) -> Result<Self, SensorError> {
        Ok(Self {
            sigma: check_sigma("echo_sounder.sigma", sigma)?,
        })
    }

    /// Noise sigma, m.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// `altitude + N(0, sigma^2)` (one standard normal).
    pub fn measure(&self, altitude: f64, rng: &mut impl Rng) -> f64 {
        altitude + gauss(rng, self.sigma)
    }
}

/// Propeller revolutions: `rpm = (V_fwd - b) / k + n`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PropellerRpm {
    k: f64,
    b: f64,
    sigma: f64,
}

impl PropellerRpm {
    /// A propeller with speed constant `k` (m/s per rpm, > 0), speed offset `b`
    /// (m/s) and rpm noise sigma `sigma` (rpm).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the bad value.
    pub fn new(k: f64, b: f64, sigma: f64) -> Result<Self, SensorError> {
        Ok(Self {
            k: check_positive("rpm.k", k)?,
            b: check_finite("rpm.b", b)?,
            sigma: check_sigma("rpm.sigma", sigma)?,
        })
    }

    /// The true speed constant `k`, m/s per rpm.
    pub fn k(&self) -> f64 {
        self.k
    }

    /// The true speed offset `b`, m/s.
    pub fn b(&self) -> f64 {
        self.b
    }

    /// Noise sigma, rpm.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The noise-free revolutions for a forward speed through the water.
    pub fn true_rpm(&self, forward_speed: f64) -> f64 {
        (forward_speed - self.b) / self.k
    }

    /// Measured revolutions (one standard normal).
    pub fn measure(&self, forward_speed: f64, rng: &mut impl Rng) -> f64 {
        self.true_rpm(forward_speed) + gauss(rng, self.sigma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn dvl_model_and_garbage() {
        let model = BottomLockDvlParams {
            sigma: 0.0,
            ..BottomLockDvlParams::default()
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let dvl = model.draw(&mut rng).unwrap();
        assert!(dvl.scale_factor().abs() <= 0.002);
        assert!(dvl.bias().amax() <= 0.005);
        let v = Vector3::new(3.0, -4.0, 0.1);
        let ok = dvl.measure(&v, 60.0, &mut rng).unwrap();
        assert!(ok.bottom_lock);
        let expected = v * (1.0 + dvl.scale_factor()) + dvl.bias();
        assert_abs_diff_eq!(ok.vel_in_nav, expected, epsilon = 1e-12);
        // Beyond range: garbage up to 5 m/s per component, sometimes large.
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let r = dvl.measure(&v, 101.0, &mut rng).unwrap();
            assert!(!r.bottom_lock);
            let d = (r.vel_in_nav - expected).amax();
            assert!(d <= 5.0);
            worst = worst.max(d);
        }
        assert!(worst > 4.0);
        // Draw count does not depend on the altitude.
        let mut a = ChaCha8Rng::seed_from_u64(5);
        let mut b = a.clone();
        dvl.measure(&v, 10.0, &mut a).unwrap();
        dvl.measure(&v, 500.0, &mut b).unwrap();
        assert_eq!(a.random::<u64>(), b.random::<u64>());
        assert!(dvl.measure(&v, f64::NAN, &mut rng).is_err());
        assert!(
            BottomLockDvlParams {
                range: 0.0,
                ..BottomLockDvlParams::default()
            }
            .check()
            .is_err()
        );
    }

    #[test]
    fn rpm_inverts_to_speed() {
        let p = PropellerRpm::new(0.01, 0.05, 0.0).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let rpm = p.measure(5.144, &mut rng);
        assert_abs_diff_eq!(p.k() * rpm + p.b(), 5.144, epsilon = 1e-12);
        assert!(PropellerRpm::new(0.0, 0.0, 1.0).is_err());
        let es = EchoSounder::new(0.5).unwrap();
        assert!((es.measure(60.0, &mut rng) - 60.0).abs() < 2.5);
        assert!(EchoSounder::new(-0.5).is_err());
    }
}

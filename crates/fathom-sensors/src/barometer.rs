//! Barometric altimeter of seed 004: the standard-atmosphere pressure of eq. (20)
//! with noise on the height, its exact inverse, and the paper's linear calibration
//! between two reference heights, eq. (11).
//!
//! ```text
//! p = 101325 (1 - 2.25577e-5 (h + n))^5.25588,   n ~ N(0, sigma_h^2)         (20)
//! h = (1 - (p / 101325)^(1 / 5.25588)) / 2.25577e-5                        (exact inverse)
//! h_baro = (h_max - h_min) / (p(h_max) - p(h_min)) (p - p(h_min)) + h_min      (11)
//! ```
//!
//! `h` is the height above mean sea level, m; the vehicle's height is
//! `origin_height - z` (NED `z` down from the local origin). Eq. (20) is defined for
//! `h < 1 / 2.25577e-5 = 44 331 m`; beyond, the pressure is NaN. The linear
//! calibration replaces the slightly convex pressure-height curve by its chord;
//! [`linear_calibration_error`] measures what that costs over a height band.

use fathom_core::SensorId;
use fathom_traj::TrueState;
use rand::Rng;

use crate::SensorError;
use crate::error::{check_finite, check_sigma};
use crate::models::SensorModel;
use crate::noise::gauss;

/// Sea-level pressure of eq. (20), Pa.
pub const SEA_LEVEL_PRESSURE_PA: f64 = 101_325.0;
/// Height coefficient of eq. (20), 1/m (`L / T0` of the standard atmosphere).
pub const HEIGHT_COEFFICIENT_PER_M: f64 = 2.255_77e-5;
/// Exponent of eq. (20) (`g M / (R L)`).
pub const PRESSURE_EXPONENT: f64 = 5.255_88;

/// Pressure at height `h` above sea level, eq. (20) without noise, Pa.
pub fn pressure_from_height(h: f64) -> f64 {
    SEA_LEVEL_PRESSURE_PA * (1.0 - HEIGHT_COEFFICIENT_PER_M * h).powf(PRESSURE_EXPONENT)
}

/// Height above sea level of pressure `p` (Pa), the exact inverse of
/// [`pressure_from_height`], m. NaN for a negative pressure.
pub fn height_from_pressure(p: f64) -> f64 {
    (1.0 - (p / SEA_LEVEL_PRESSURE_PA).powf(1.0 / PRESSURE_EXPONENT)) / HEIGHT_COEFFICIENT_PER_M
}

/// Unchecked barometer parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarometerParams {
    /// Standard deviation of the height noise `n` of eq. (20), m (the paper gives no
    /// value; a setting).
    pub height_noise_sigma_m: f64,
    /// Height of the NED origin above sea level, m.
    pub origin_height_m: f64,
}

impl Default for BarometerParams {
    fn default() -> Self {
        Self {
            height_noise_sigma_m: 0.5,
            origin_height_m: 0.0,
        }
    }
}

impl BarometerParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative or non-finite sigma, or an
    /// origin height that is not finite or outside [-500, 40 000] m.
    pub fn check(&self) -> Result<Barometer, SensorError> {
        let sigma = check_sigma("baro.height_noise_sigma_m", self.height_noise_sigma_m)?;
        let origin = check_finite("baro.origin_height_m", self.origin_height_m)?;
        if !(-500.0..=40_000.0).contains(&origin) {
            return Err(SensorError::InvalidParameter {
                field: "baro.origin_height_m".into(),
                value: origin,
                reason: "must be within [-500, 40000] m (eq. 20 holds below 44 km)",
            });
        }
        Ok(Barometer { sigma, origin })
    }
}

/// A checked barometer: measures static pressure (Pa) by eq. (20).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Barometer {
    sigma: f64,
    origin: f64,
}

impl Barometer {
    /// Height above sea level of a true state, `origin_height - z`, m.
    pub fn height_of(&self, state: &TrueState) -> f64 {
        self.origin - state.pos_in_nav.z
    }

    /// Height above the NED origin (`-z`) of a measured pressure by the exact inverse, m.
    pub fn height_above_origin(&self, pressure: f64) -> f64 {
        height_from_pressure(pressure) - self.origin
    }

    /// Height noise sigma, m.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
}

impl SensorModel for Barometer {
    type Value = f64;

    fn id(&self) -> SensorId {
        SensorId::Barometer
    }

    /// Noise-free pressure at the state's height, Pa.
    fn true_value(&self, state: &TrueState) -> f64 {
        pressure_from_height(self.height_of(state))
    }

    /// Eq. (20): the noise enters on the height, `p(h + n)`; one standard normal.
    fn add_noise(&self, true_value: &f64, rng: &mut impl Rng) -> f64 {
        let h = height_from_pressure(*true_value);
        pressure_from_height(h + gauss(rng, self.sigma))
    }
}

/// The linear calibration of eq. (11): heights from pressure along the chord between
/// two reference heights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearBaroCalibration {
    h_min: f64,
    h_max: f64,
    p_at_h_min: f64,
    p_at_h_max: f64,
}

impl LinearBaroCalibration {
    /// The calibration through the pressures of eq. (20) at the reference heights
    /// `h_min < h_max` (m above sea level), as a calibration at rest on two known
    /// heights would record them without noise.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for non-finite heights, `h_min >= h_max`, or a
    /// height at or above 44 km.
    pub fn from_reference_heights(h_min: f64, h_max: f64) -> Result<Self, SensorError> {
        let h_min = check_finite("baro_calibration.h_min", h_min)?;
        let h_max = check_finite("baro_calibration.h_max", h_max)?;
        if h_max <= h_min {
            return Err(SensorError::InvalidParameter {
                field: "baro_calibration.h_max".into(),
                value: h_max,
                reason: "must be above h_min",
            });
        }
        Self::from_reference_pressures(
            h_min,
            pressure_from_height(h_min),
            h_max,
            pressure_from_height(h_max),
        )
    }

    /// The calibration through measured pressures at the reference heights.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for non-finite values, `h_min >= h_max`, or
    /// equal pressures (no slope).
    pub fn from_reference_pressures(
        h_min: f64,
        p_at_h_min: f64,
        h_max: f64,
        p_at_h_max: f64,
    ) -> Result<Self, SensorError> {
        check_finite("baro_calibration.h_min", h_min)?;
        check_finite("baro_calibration.h_max", h_max)?;
        check_finite("baro_calibration.p_at_h_min", p_at_h_min)?;
        check_finite("baro_calibration.p_at_h_max", p_at_h_max)?;
        if h_max <= h_min {
            return Err(SensorError::InvalidParameter {
                field: "baro_calibration.h_max".into(),
                value: h_max,
                reason: "must be above h_min",
            });
        }
        if p_at_h_max == p_at_h_min {
            return Err(SensorError::InvalidParameter {
                field: "baro_calibration.p_at_h_max".into(),
                value: p_at_h_max,
                reason: "must differ from p_at_h_min",
            });
        }
        Ok(Self {
            h_min,
            h_max,
            p_at_h_min,
            p_at_h_max,
        })
    }

    /// Height of pressure `p` by eq. (11), m (same datum as the reference heights).
    pub fn height(&self, p: f64) -> f64 {
        (self.h_max - self.h_min) / (self.p_at_h_max - self.p_at_h_min) * (p - self.p_at_h_min)
            + self.h_min
    }
}

/// The error of the linear calibration against the exact inverse over a height band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationError {
    /// Largest `|h_linear - h|` over the band, m.
    pub max_abs_m: f64,
    /// Height at which it occurs, m.
    pub at_height_m: f64,
    /// Root mean square of `h_linear - h` over the evaluated heights, m.
    pub rms_m: f64,
    /// Number of heights evaluated.
    pub n: usize,
}

/// Evaluates `h_linear(p(h)) - h` of `cal` at `n` evenly spaced heights from `h_from`
/// to `h_to` (inclusive): the error eq. (11) adds to a noise-free barometer.
///
/// # Errors
/// [`SensorError::InvalidParameter`] for non-finite bounds, `h_to < h_from`, or
/// `n < 2`.
pub fn linear_calibration_error(
    cal: &LinearBaroCalibration,
    h_from: f64,
    h_to: f64,
    n: usize,
) -> Result<CalibrationError, SensorError> {
    check_finite("calibration_error.h_from", h_from)?;
    check_finite("calibration_error.h_to", h_to)?;
    if h_to < h_from || n < 2 {
        return Err(SensorError::InvalidParameter {
            field: "calibration_error.n".into(),
            value: n as f64,
            reason: "needs n >= 2 heights and h_to >= h_from",
        });
    }
    let (mut max_abs, mut at, mut sum_sq) = (0.0f64, h_from, 0.0);
    for k in 0..n {
        let h = h_from + (h_to - h_from) * k as f64 / (n - 1) as f64;
        let e = cal.height(pressure_from_height(h)) - h;
        sum_sq += e * e;
        if e.abs() > max_abs {
            (max_abs, at) = (e.abs(), h);
        }
    }
    Ok(CalibrationError {
        max_abs_m: max_abs,
        at_height_m: at,
        rms_m: (sum_sq / n as f64).sqrt(),
        n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::frames::Euler;
    use nalgebra::Vector3;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn at_height_above_origin(h: f64) -> TrueState {
        TrueState {
            time: 0.0,
            pos_in_nav: Vector3::new(3.0, -4.0, -h),
            vel_in_nav: Vector3::zeros(),
            acc_in_nav: Vector3::zeros(),
            attitude: Euler::default(),
            omega_body: Vector3::zeros(),
        }
    }

    /// Acceptance: pressure -> height round trip within 1e-9 m from below sea level
    /// to 10 km. Negative control: a 1 Pa error is metres off.
    #[test]
    fn exact_inverse_round_trips() {
        let mut worst: f64 = 0.0;
        for k in 0..=2100 {
            let h = -500.0 + 5.0 * k as f64;
            let back = height_from_pressure(pressure_from_height(h));
            worst = worst.max((back - h).abs());
        }
        assert!(worst < 1e-9, "worst round trip {worst:e} m");
        assert_eq!(pressure_from_height(0.0), SEA_LEVEL_PRESSURE_PA);
        // ~12 Pa per metre near sea level
        let dp = pressure_from_height(0.0) - pressure_from_height(1.0);
        assert!((dp - 12.01).abs() < 0.05, "{dp}");
        let off = height_from_pressure(pressure_from_height(50.0) + 1.0) - 50.0;
        assert!(off.abs() > 0.05, "negative control {off}");
        assert!(pressure_from_height(50_000.0).is_nan());
    }

    /// The linear calibration between 0 and 100 m is exact at both ends; in between
    /// its error is one-signed (the height-pressure curve is convex) and its maximum
    /// is the chord error `|h''(p)| dp^2 / 8` at mid-band (second order), with
    /// `h''(p) = -(1/c)(1/n)(1/n - 1) r^(1/n - 2) / p0^2`, `r = p / p0`. A ten times
    /// wider band costs a hundred times more. The numbers are reported by the
    /// experiment through [`linear_calibration_error`].
    #[test]
    fn linear_calibration_error_over_0_to_100_m() {
        let cal = LinearBaroCalibration::from_reference_heights(0.0, 100.0).unwrap();
        assert!(cal.height(pressure_from_height(0.0)).abs() < 1e-9);
        assert!((cal.height(pressure_from_height(100.0)) - 100.0).abs() < 1e-9);
        let e = linear_calibration_error(&cal, 0.0, 100.0, 1001).unwrap();
        eprintln!(
            "linear calibration 0-100 m: max |error| {:.3e} m at {:.1} m, rms {:.3e} m",
            e.max_abs_m, e.at_height_m, e.rms_m
        );
        let (c, n, p0) = (
            HEIGHT_COEFFICIENT_PER_M,
            PRESSURE_EXPONENT,
            SEA_LEVEL_PRESSURE_PA,
        );
        let p_mid = pressure_from_height(50.0);
        let h2 =
            -(1.0 / c) * (1.0 / n) * (1.0 / n - 1.0) * (p_mid / p0).powf(1.0 / n - 2.0) / (p0 * p0);
        let dp = pressure_from_height(0.0) - pressure_from_height(100.0);
        let chord = h2.abs() * dp * dp / 8.0;
        assert!(
            (e.max_abs_m / chord - 1.0).abs() < 0.01,
            "{} vs {chord}",
            e.max_abs_m
        );
        assert!((e.at_height_m - 50.0).abs() < 1.0);
        let signs: Vec<f64> = (1..100)
            .map(|h| cal.height(pressure_from_height(f64::from(h))) - f64::from(h))
            .collect();
        assert!(signs.iter().all(|s| s.signum() == signs[0].signum()));
        let wide = LinearBaroCalibration::from_reference_heights(0.0, 1000.0).unwrap();
        let ew = linear_calibration_error(&wide, 0.0, 1000.0, 1001).unwrap();
        assert!((ew.max_abs_m / e.max_abs_m / 100.0 - 1.0).abs() < 0.1);
        assert!(linear_calibration_error(&cal, 1.0, 0.0, 10).is_err());
        assert!(linear_calibration_error(&cal, 0.0, 1.0, 1).is_err());
    }

    #[test]
    fn measurement_noise_is_on_the_height() {
        let baro = BarometerParams {
            height_noise_sigma_m: 0.5,
            origin_height_m: 120.0,
        }
        .check()
        .unwrap();
        let state = at_height_above_origin(20.0);
        assert!((baro.height_above_origin(baro.true_value(&state)) - 20.0).abs() < 1e-9);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let n = 20_000;
        let (mut sum, mut sum_sq) = (0.0, 0.0);
        for _ in 0..n {
            let m = baro.measure_state(&state, 0.0, &mut rng);
            assert_eq!(m.sensor, SensorId::Barometer);
            let e = baro.height_above_origin(m.value) - 20.0;
            sum += e;
            sum_sq += e * e;
        }
        let mean = sum / n as f64;
        let var = sum_sq / n as f64 - mean * mean;
        // 5-sigma bands: mean sd 0.5/sqrt(n), variance rel. sd sqrt(2/n)
        assert!(mean.abs() < 5.0 * 0.5 / (n as f64).sqrt(), "{mean}");
        assert!(
            (var / 0.25 - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt(),
            "{var}"
        );
        assert!((var / 0.3 - 1.0).abs() > 5.0 * (2.0 / n as f64).sqrt());
    }

    #[test]
    fn bad_parameters_name_the_field() {
        let e = BarometerParams {
            height_noise_sigma_m: -1.0,
            ..BarometerParams::default()
        }
        .check()
        .unwrap_err();
        assert!(e.to_string().contains("baro.height_noise_sigma_m"), "{e}");
        let e = BarometerParams {
            origin_height_m: f64::NAN,
            ..BarometerParams::default()
        }
        .check()
        .unwrap_err();
        assert!(e.to_string().contains("baro.origin_height_m"), "{e}");
        assert!(LinearBaroCalibration::from_reference_heights(10.0, 10.0).is_err());
        assert!(LinearBaroCalibration::from_reference_pressures(0.0, 1.0, 1.0, 1.0).is_err());
    }
}

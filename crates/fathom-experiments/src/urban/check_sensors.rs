//! The sensor and count settings of an `urban` scenario checked into the library
//! crates' parameter types (used by [`super::check`]).

use fathom_sensors::map_range::{DetectionParams, LidarParams, RangeSensorParams};

use super::check_scene::model_err;
use super::scenario::{DetectionToml, LidarToml, RangefindersToml};
use fathom_sim::SimError;
use fathom_sim::scenario::{require_in_range, require_non_negative, require_positive};

/// Events every `rate` Hz on the IMU clock: the whole number of IMU steps.
pub(super) fn every(file: &str, key: &str, imu_rate: f64, rate: f64) -> Result<usize, SimError> {
    require_positive(file, key, rate)?;
    let n = imu_rate / rate;
    if (n - n.round()).abs() > 1e-9 || n.round() < 1.0 || n > 1e6 {
        return Err(SimError::invalid(
            file,
            key,
            format!("{rate} Hz must divide imu.rate_hz = {imu_rate} Hz a whole number of times"),
        ));
    }
    Ok(n.round() as usize)
}

pub(super) fn detection(
    file: &str,
    key: &str,
    d: &DetectionToml,
) -> Result<DetectionParams, SimError> {
    require_in_range(file, &format!("{key}.p_max"), d.p_max, 0.0, 1.0)?;
    require_in_range(
        file,
        &format!("{key}.full_until_deg"),
        d.full_until_deg,
        0.0,
        90.0,
    )?;
    require_in_range(
        file,
        &format!("{key}.zero_from_deg"),
        d.zero_from_deg,
        d.full_until_deg,
        90.0,
    )?;
    Ok(DetectionParams {
        p_max: d.p_max,
        full_until_deg: d.full_until_deg,
        zero_from_deg: d.zero_from_deg,
    })
}

/// The paper's simulated ranges: Gaussian noise only (no glass extra noise, every
/// surface returns at any incidence).
pub fn gaussian_only(mut p: RangeSensorParams) -> RangeSensorParams {
    p.glass_extra_sigma_m = 0.0;
    p.opaque_detection = DetectionParams::ALWAYS;
    p.glass_detection = DetectionParams::ALWAYS;
    p
}

/// The range-finder parameters of `[rangefinders]`.
pub fn rangefinder_params(file: &str, r: &RangefindersToml) -> Result<RangeSensorParams, SimError> {
    let mut p = RangeSensorParams::paper_rangefinders();
    p.max_range_m = require_positive(file, "rangefinders.max_range_m", r.max_range_m)?;
    p.sigma_floor_m = require_non_negative(file, "rangefinders.sigma_floor_m", r.sigma_floor_m)?;
    p.sigma_per_m = require_non_negative(file, "rangefinders.sigma_per_m", r.sigma_per_m)?;
    p.glass_extra_sigma_m = require_non_negative(
        file,
        "rangefinders.glass_extra_sigma_m",
        r.glass_extra_sigma_m,
    )?;
    p.opaque_detection = detection(file, "rangefinders.opaque_detection", &r.opaque_detection)?;
    p.glass_detection = detection(file, "rangefinders.glass_detection", &r.glass_detection)?;
    p.rate_hz = require_positive(file, "rangefinders.rate_hz", r.rate_hz)?;
    Ok(p)
}

/// The lidar parameters of `[lidar]`.
pub fn lidar_params(file: &str, l: &LidarToml) -> Result<LidarParams, SimError> {
    let p = LidarParams {
        first_deg: l.first_deg,
        last_deg: l.last_deg,
        step_deg: require_positive(file, "lidar.step_deg", l.step_deg)?,
        rate_hz: require_positive(file, "lidar.rate_hz", l.rate_hz)?,
        max_range_m: require_positive(file, "lidar.max_range_m", l.max_range_m)?,
        sigma_m: require_non_negative(file, "lidar.sigma_m", l.sigma_m)?,
        glass_extra_sigma_m: require_non_negative(
            file,
            "lidar.glass_extra_sigma_m",
            l.glass_extra_sigma_m,
        )?,
        opaque_detection: detection(file, "lidar.opaque_detection", &l.opaque_detection)?,
        glass_detection: detection(file, "lidar.glass_detection", &l.glass_detection)?,
    };
    p.azimuths_rad().map_err(|e| model_err(file, "lidar", e))?;
    Ok(p)
}

/// `n` when inside `range`, else the error naming `key`.
pub(super) fn count_in(
    file: &str,
    key: &str,
    n: usize,
    range: std::ops::RangeInclusive<usize>,
) -> Result<usize, SimError> {
    if range.contains(&n) {
        Ok(n)
    } else {
        Err(SimError::invalid(
            file,
            key,
            format!("must be {} ... {}, got {n}", range.start(), range.end()),
        ))
    }
}

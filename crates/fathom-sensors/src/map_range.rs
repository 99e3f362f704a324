//! Map-aware range sensors (spec D, "Sensors"): body-fixed beams cast against the
//! map through [`fathom_core::RayCaster`], with range-dependent noise, extra noise
//! on glass, a detection probability that falls with the incidence angle (glass
//! returns only near normal incidence) and a maximum range. The same model serves
//! the paper's range finders (6 horizontal beams at 60 deg and 1 down) and the
//! Hokuyo UST-20LX lidar ([`LidarParams`]).
//!
//! The sensor takes the true pose as plain values (`pos_in_nav`, `nav_from_body`),
//! so it does not care how the truth was made. Per beam, in beam order, exactly two
//! draws are consumed (a uniform for the detection, a standard normal for the
//! noise), hit or not: a change of geometry does not shift the draws of other beams
//! (common random numbers across methods and maps).

use fathom_core::{Material, RayCaster, units::deg_to_rad};
use nalgebra::{Rotation3, Vector3};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::SensorError;
use crate::error::{check_finite3, check_positive, check_sigma};

/// One beam: where it starts on the body and where it points (body frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Beam {
    /// Start of the beam relative to the body origin, body frame, m.
    pub origin_in_body: Vector3<f64>,
    /// Direction, body frame (normalized when checked).
    pub dir_in_body: Vector3<f64>,
}

/// Detection probability versus incidence angle, piecewise linear: `p_max` up to
/// `full_until_deg`, falling linearly to 0 at `zero_from_deg`, 0 beyond.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetectionParams {
    /// Probability of a return at (near) normal incidence, in `[0, 1]`.
    pub p_max: f64,
    /// Incidence angle up to which `p_max` holds, deg.
    pub full_until_deg: f64,
    /// Incidence angle from which no return comes, deg (`>= full_until_deg`, `<= 90`).
    pub zero_from_deg: f64,
}

impl DetectionParams {
    /// Always detected at any incidence (noise-free tests, ideal sensors).
    pub const ALWAYS: DetectionParams = DetectionParams {
        p_max: 1.0,
        full_until_deg: 90.0,
        zero_from_deg: 90.0,
    };

    fn check(&self, field: &str) -> Result<Detection, SensorError> {
        let bad = |name: &str, value: f64, reason| SensorError::InvalidParameter {
            field: format!("{field}.{name}"),
            value,
            reason,
        };
        if !(0.0..=1.0).contains(&self.p_max) {
            return Err(bad("p_max", self.p_max, "must be in [0, 1]"));
        }
        if !(0.0..=90.0).contains(&self.full_until_deg) {
            return Err(bad(
                "full_until_deg",
                self.full_until_deg,
                "must be in [0, 90]",
            ));
        }
        if !(self.full_until_deg..=90.0).contains(&self.zero_from_deg) {
            return Err(bad(
                "zero_from_deg",
                self.zero_from_deg,
                "must be in [full_until_deg, 90]",
            ));
        }
        Ok(Detection {
            p_max: self.p_max,
            full: deg_to_rad(self.full_until_deg),
            zero: deg_to_rad(self.zero_from_deg),
        })
    }
}

/// Checked [`DetectionParams`] in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Detection {
    p_max: f64,
    full: f64,
    zero: f64,
}

impl Detection {
    /// The probability of a return at incidence `incidence_rad`.
    pub fn probability(&self, incidence_rad: f64) -> f64 {
        if incidence_rad <= self.full {
            self.p_max
        } else if incidence_rad >= self.zero {
            0.0
        } else {
            self.p_max * (self.zero - incidence_rad) / (self.zero - self.full)
        }
    }
}

/// Unchecked parameters of a set of body-fixed range beams.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeSensorParams {
    /// The beams, in output order.
    pub beams: Vec<Beam>,
    /// Largest range returned, m.
    pub max_range_m: f64,
    /// Noise std at zero range (the floor), m.
    pub sigma_floor_m: f64,
    /// Noise std per metre of range (proportional part), m/m.
    pub sigma_per_m: f64,
    /// Extra noise std on glass, m, added to the std ([`RangeSensor::sigma`]).
    pub glass_extra_sigma_m: f64,
    /// Detection on opaque (and `Other`) surfaces.
    pub opaque_detection: DetectionParams,
    /// Detection on glass.
    pub glass_detection: DetectionParams,
    /// Sample rate, Hz (for the caller's schedule).
    pub rate_hz: f64,
}

impl RangeSensorParams {
    /// The paper's range finders (spec D): 6 horizontal beams at 0, 60, ..., 300 deg
    /// azimuth from the nose plus 1 pointing down, from the body origin; 40 m max
    /// range, std `0.02 m + 1 % of range`, glass `+0.10 m`, detection on opaque
    /// surfaces 0.99 up to 60 deg falling to 0 at 85 deg, on glass 0.9 up to 5 deg
    /// falling to 0 at 15 deg; 10 Hz. (The paper gives the model's form, not its
    /// numbers: these are settings.)
    pub fn paper_rangefinders() -> Self {
        let mut beams: Vec<Beam> = (0..6)
            .map(|k| {
                let az = deg_to_rad(60.0 * f64::from(k));
                Beam {
                    origin_in_body: Vector3::zeros(),
                    dir_in_body: Vector3::new(az.cos(), az.sin(), 0.0),
                }
            })
            .collect();
        beams.push(Beam {
            origin_in_body: Vector3::zeros(),
            dir_in_body: Vector3::new(0.0, 0.0, 1.0),
        });
        Self {
            beams,
            max_range_m: 40.0,
            sigma_floor_m: 0.02,
            sigma_per_m: 0.01,
            glass_extra_sigma_m: 0.10,
            opaque_detection: DetectionParams {
                p_max: 0.99,
                full_until_deg: 60.0,
                zero_from_deg: 85.0,
            },
            glass_detection: DetectionParams {
                p_max: 0.9,
                full_until_deg: 5.0,
                zero_from_deg: 15.0,
            },
            rate_hz: 10.0,
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] naming the field (non-finite or zero beam
    /// direction, non-positive max range or rate, negative sigma, probabilities or
    /// angles out of range), [`SensorError::Empty`] without beams.
    pub fn check(&self) -> Result<RangeSensor, SensorError> {
        if self.beams.is_empty() {
            return Err(SensorError::Empty {
                what: "range sensor beams".into(),
            });
        }
        let mut beams = Vec::with_capacity(self.beams.len());
        for (i, b) in self.beams.iter().enumerate() {
            check_finite3(&format!("beams[{i}].origin_in_body"), &b.origin_in_body)?;
            let d = check_finite3(&format!("beams[{i}].dir_in_body"), &b.dir_in_body)?;
            let n = d.norm();
            let usable = n > 1e-12; // false for NaN
            if !usable {
                return Err(SensorError::InvalidParameter {
                    field: format!("beams[{i}].dir_in_body"),
                    value: n,
                    reason: "must not be zero",
                });
            }
            beams.push(Beam {
                origin_in_body: b.origin_in_body,
                dir_in_body: d / n,
            });
        }
        Ok(RangeSensor {
            beams,
            max_range: check_positive("max_range_m", self.max_range_m)?,
            sigma_floor: check_sigma("sigma_floor_m", self.sigma_floor_m)?,
            sigma_per_m: check_sigma("sigma_per_m", self.sigma_per_m)?,
            glass_extra: check_sigma("glass_extra_sigma_m", self.glass_extra_sigma_m)?,
            opaque: self.opaque_detection.check("opaque_detection")?,
            glass: self.glass_detection.check("glass_detection")?,
            rate_hz: check_positive("rate_hz", self.rate_hz)?,
        })
    }
}

/// The lidar after the Hokuyo UST-20LX (spec D): beams in the body's horizontal plane
/// from `-135` to `135` deg (positive towards starboard) every `step_deg`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LidarParams {
    /// First beam azimuth, deg. Default -135.
    pub first_deg: f64,
    /// Last beam azimuth, deg (included when on the step grid). Default 135.
    pub last_deg: f64,
    /// Azimuth step, deg. Default 2.5 (the paper's; the device resolves 0.25).
    pub step_deg: f64,
    /// Scan rate, Hz. Default 5 (the paper's; the device runs at up to 40).
    pub rate_hz: f64,
    /// Max range, m. Default 60 (data sheet).
    pub max_range_m: f64,
    /// Range noise std, m. Default 0.02: the data sheet's accuracy of +-40 mm read as
    /// a two-sigma bound.
    pub sigma_m: f64,
    /// Extra noise std on glass, m. Default 0.05.
    pub glass_extra_sigma_m: f64,
    /// Detection on opaque surfaces. Default: 1 up to 80 deg, 0 from 89 deg.
    pub opaque_detection: DetectionParams,
    /// Detection on glass. Default: 0.9 up to 5 deg, 0 from 15 deg.
    pub glass_detection: DetectionParams,
}

impl Default for LidarParams {
    fn default() -> Self {
        Self {
            first_deg: -135.0,
            last_deg: 135.0,
            step_deg: 2.5,
            rate_hz: 5.0,
            max_range_m: 60.0,
            sigma_m: 0.02,
            glass_extra_sigma_m: 0.05,
            opaque_detection: DetectionParams {
                p_max: 1.0,
                full_until_deg: 80.0,
                zero_from_deg: 89.0,
            },
            glass_detection: DetectionParams {
                p_max: 0.9,
                full_until_deg: 5.0,
                zero_from_deg: 15.0,
            },
        }
    }
}

/// Most beams a lidar may have (a bound against absurd steps).
pub const MAX_LIDAR_BEAMS: usize = 100_000;

impl LidarParams {
    /// The beam azimuths, rad: `first + k step` for `k = 0, 1, ...` while `<= last`
    /// (within 1e-9 deg). The default gives 109 beams.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a non-finite or non-positive step,
    /// `last < first`, or more than [`MAX_LIDAR_BEAMS`] beams.
    pub fn azimuths_rad(&self) -> Result<Vec<f64>, SensorError> {
        let step = check_positive("lidar.step_deg", self.step_deg)?;
        let span = self.last_deg - self.first_deg;
        let ordered = span >= 0.0 && span.is_finite() && self.first_deg.is_finite();
        if !ordered {
            return Err(SensorError::InvalidParameter {
                field: "lidar.last_deg".into(),
                value: self.last_deg,
                reason: "must be finite and >= first_deg",
            });
        }
        let n = (span / step + 1e-9).floor() + 1.0;
        if n > MAX_LIDAR_BEAMS as f64 {
            return Err(SensorError::InvalidParameter {
                field: "lidar.step_deg".into(),
                value: step,
                reason: "gives more than 100000 beams",
            });
        }
        Ok((0..n as usize)
            .map(|k| deg_to_rad(self.first_deg + k as f64 * step))
            .collect())
    }

    /// As range-sensor parameters (beams from the body origin).
    ///
    /// # Errors
    /// As [`LidarParams::azimuths_rad`].
    pub fn to_range_params(&self) -> Result<RangeSensorParams, SensorError> {
        Ok(RangeSensorParams {
            beams: self
                .azimuths_rad()?
                .into_iter()
                .map(|az| Beam {
                    origin_in_body: Vector3::zeros(),
                    dir_in_body: Vector3::new(az.cos(), az.sin(), 0.0),
                })
                .collect(),
            max_range_m: self.max_range_m,
            sigma_floor_m: self.sigma_m,
            sigma_per_m: 0.0,
            glass_extra_sigma_m: self.glass_extra_sigma_m,
            opaque_detection: self.opaque_detection,
            glass_detection: self.glass_detection,
            rate_hz: self.rate_hz,
        })
    }

    /// Checks the parameters into a range sensor.
    ///
    /// # Errors
    /// As [`LidarParams::azimuths_rad`] and [`RangeSensorParams::check`].
    pub fn check(&self) -> Result<RangeSensor, SensorError> {
        self.to_range_params()?.check()
    }
}

/// What a beam met: the true range, the surface, the incidence angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamHit {
    /// True range to the surface, m.
    pub true_range_m: f64,
    /// The surface's material.
    pub material: Material,
    /// Incidence angle between the beam and the surface normal, rad (0 head-on).
    pub incidence_rad: f64,
    /// Triangle index in the map.
    pub triangle: u32,
}

/// One beam's reading in a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamReading {
    /// Beam index.
    pub beam: usize,
    /// The surface within max range, if any (also when it gave no return).
    pub hit: Option<BeamHit>,
    /// The measured range, m: `Some` when the beam returned (a hit, detected).
    pub range_m: Option<f64>,
}

/// Checked body-fixed range beams against a map.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeSensor {
    beams: Vec<Beam>,
    max_range: f64,
    sigma_floor: f64,
    sigma_per_m: f64,
    glass_extra: f64,
    opaque: Detection,
    glass: Detection,
    rate_hz: f64,
}

impl RangeSensor {
    /// The beams (directions unit).
    pub fn beams(&self) -> &[Beam] {
        &self.beams
    }

    /// Max range, m.
    pub fn max_range(&self) -> f64 {
        self.max_range
    }

    /// Sample rate, Hz.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Noise std at true range `r` on `material`:
    /// `sigma_floor + sigma_per_m r (+ glass_extra on glass)`.
    pub fn sigma(&self, r: f64, material: Material) -> f64 {
        let glass = if material.is_glass() {
            self.glass_extra
        } else {
            0.0
        };
        self.sigma_floor + self.sigma_per_m * r + glass
    }

    /// Probability of a return at `incidence_rad` on `material`.
    pub fn detection_probability(&self, incidence_rad: f64, material: Material) -> f64 {
        if material.is_glass() {
            self.glass.probability(incidence_rad)
        } else {
            self.opaque.probability(incidence_rad)
        }
    }

    /// One scan from the true pose: every beam cast against `map` (two draws per
    /// beam, module doc). Ranges are positive: a noisy value below zero is clamped to 0.
    pub fn scan(
        &self,
        map: &(impl RayCaster + ?Sized),
        pos_in_nav: &Vector3<f64>,
        nav_from_body: &Rotation3<f64>,
        rng: &mut impl Rng,
    ) -> Vec<BeamReading> {
        self.beams
            .iter()
            .enumerate()
            .map(|(beam, b)| {
                let u: f64 = rng.random();
                let z: f64 = rng.sample(StandardNormal);
                let origin = pos_in_nav + nav_from_body * b.origin_in_body;
                let dir = nav_from_body * b.dir_in_body;
                let hit = map.cast(&origin, &dir, self.max_range).map(|h| BeamHit {
                    true_range_m: h.range,
                    material: h.material,
                    incidence_rad: h.incidence(&dir),
                    triangle: h.triangle,
                });
                let range_m = hit.and_then(|h| {
                    let p = self.detection_probability(h.incidence_rad, h.material);
                    (u < p).then(|| {
                        (h.true_range_m + self.sigma(h.true_range_m, h.material) * z).max(0.0)
                    })
                });
                BeamReading { beam, hit, range_m }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detection_is_piecewise_linear() {
        let d = DetectionParams {
            p_max: 0.8,
            full_until_deg: 30.0,
            zero_from_deg: 60.0,
        }
        .check("d")
        .unwrap();
        assert_eq!(d.probability(0.0), 0.8);
        assert!((d.probability(deg_to_rad(45.0)) - 0.4).abs() < 1e-12);
        assert_eq!(d.probability(deg_to_rad(60.0)), 0.0);
        assert_eq!(d.probability(deg_to_rad(89.0)), 0.0);
        let a = DetectionParams::ALWAYS.check("a").unwrap();
        assert_eq!(a.probability(std::f64::consts::FRAC_PI_2), 1.0);
    }

    #[test]
    fn defaults_and_bad_parameters() {
        let paper = RangeSensorParams::paper_rangefinders().check().unwrap();
        assert_eq!(paper.beams().len(), 7);
        assert_eq!(paper.beams()[6].dir_in_body, Vector3::new(0.0, 0.0, 1.0));
        let lidar = LidarParams::default();
        assert_eq!(lidar.azimuths_rad().unwrap().len(), 109);
        assert_eq!(lidar.check().unwrap().max_range(), 60.0);
        let bad = [
            LidarParams {
                step_deg: 0.0,
                ..lidar
            },
            LidarParams {
                step_deg: 1e-9,
                ..lidar
            },
            LidarParams {
                last_deg: -200.0,
                ..lidar
            },
            LidarParams {
                sigma_m: -1.0,
                ..lidar
            },
            LidarParams {
                max_range_m: f64::NAN,
                ..lidar
            },
            LidarParams {
                glass_detection: DetectionParams {
                    p_max: 1.5,
                    ..lidar.glass_detection
                },
                ..lidar
            },
            LidarParams {
                opaque_detection: DetectionParams {
                    zero_from_deg: 10.0,
                    ..lidar.opaque_detection
                },
                ..lidar
            },
        ];
        for b in bad {
            assert!(b.check().is_err(), "{b:?}");
        }
        let mut p = RangeSensorParams::paper_rangefinders();
        p.beams[2].dir_in_body = Vector3::zeros();
        assert!(p.check().unwrap_err().to_string().contains("beams[2]"));
        p.beams.clear();
        assert!(p.check().is_err());
    }
}

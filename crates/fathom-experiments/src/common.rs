//! Scenario pieces shared by several experiments (robot motion, beacons, timing),
//! with their conversion into the checked parameter types of the library crates.

use fathom_traj::velocity_command::{VelocityCommandMotion, VelocityCommandParams};
use nalgebra::Vector3;
use rand::Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use fathom_sim::SimError;
use fathom_sim::scenario::{require_non_negative, require_positive};

/// `[motion]`: the velocity-command kinematic motion of the beacons paper
/// (Tables 1 and 9).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MotionToml {
    /// Run length (paper: 180).
    ///
    /// Unit: s. Range: > 0, at least one step.
    pub duration_s: f64,
    /// Motion integration step (paper: 0.01).
    ///
    /// Unit: s. Range: > 0.
    pub step_s: f64,
    /// Commanded body velocity `(u, v, w, p, q, r)` (Table 1: 0.5, 0, 0.2, 0, 0, 0.5);
    /// in `beacons`, `(u, v, w)` and `r` are also the filter's input before the first
    /// DVL/AHRS sample.
    ///
    /// Unit: m/s, rad/s. Range: finite.
    pub command: [f64; 6],
    /// Per-step Gaussian noise on each command component: the actual velocity is
    /// command + N(0, σ²) (Table 9); in `beacons` it enters the filter's process noise
    /// when `ekf.include_motion_noise`.
    ///
    /// Unit: m/s, rad/s. Range: each ≥ 0.
    pub motion_sigma: [f64; 6],
}

impl MotionToml {
    /// Checks the values and converts them into the trajectory crate's parameters;
    /// `file` and `table` name the place for error messages.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn to_params(&self, file: &str, table: &str) -> Result<VelocityCommandParams, SimError> {
        require_positive(file, &format!("{table}.duration_s"), self.duration_s)?;
        require_positive(file, &format!("{table}.step_s"), self.step_s)?;
        for (k, v) in self.command.iter().enumerate() {
            if !v.is_finite() {
                return Err(SimError::invalid(
                    file,
                    format!("{table}.command[{k}]"),
                    format!("must be finite, got {v}"),
                ));
            }
        }
        for (k, v) in self.motion_sigma.iter().enumerate() {
            require_non_negative(file, &format!("{table}.motion_sigma[{k}]"), *v)?;
        }
        Ok(VelocityCommandParams {
            duration: self.duration_s,
            dt: self.step_s,
            command: self.command,
            motion_sigma: self.motion_sigma,
            ..VelocityCommandParams::default()
        })
    }
}

/// Generates the motion for one run from checked parameters.
///
/// # Errors
/// [`SimError::Model`] wrapping the trajectory crate's error.
pub fn generate_motion(
    params: &VelocityCommandParams,
    rng: &mut impl Rng,
) -> Result<VelocityCommandMotion, SimError> {
    let checked = params
        .check()
        .map_err(|e| SimError::model("motion parameters", e))?;
    VelocityCommandMotion::generate(&checked, rng).map_err(|e| SimError::model("motion", e))
}

/// `[beacons]`: beacon positions in NED, m.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeaconsToml {
    /// Beacon positions `[north, east, down]` (not given by the paper; keep them
    /// non-coplanar, or the ranges cannot fix the 3D position). `noise` needs exactly
    /// four (the paper's matrices are 5×5); `beacons` takes any number.
    ///
    /// Unit: m (NED). Range: finite; at least one beacon (`noise`: exactly 4).
    pub positions: Vec<[f64; 3]>,
}

impl BeaconsToml {
    /// Checks there is at least one beacon and every coordinate is finite.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key and index.
    pub fn to_positions(&self, file: &str, table: &str) -> Result<Vec<Vector3<f64>>, SimError> {
        if self.positions.is_empty() {
            return Err(SimError::invalid(
                file,
                format!("{table}.positions"),
                "needs at least one beacon",
            ));
        }
        self.positions
            .iter()
            .enumerate()
            .map(|(k, p)| {
                if p.iter().all(|v| v.is_finite()) {
                    Ok(Vector3::new(p[0], p[1], p[2]))
                } else {
                    Err(SimError::invalid(
                        file,
                        format!("{table}.positions[{k}]"),
                        format!("coordinates must be finite, got {p:?}"),
                    ))
                }
            })
            .collect()
    }
}

/// Checks a sampling period against the timing jitter σ: more than 4 σ, so that
/// sample times always increase (the sensor schedules' own rule), blamed on the
/// period's key.
///
/// # Errors
/// [`SimError::Invalid`] naming `key` and `timing.jitter_sigma_s`.
pub fn require_period_over_jitter(
    file: &str,
    key: &str,
    period: f64,
    jitter_sigma: f64,
) -> Result<(), SimError> {
    if period > 4.0 * jitter_sigma {
        return Ok(());
    }
    Err(SimError::invalid(
        file,
        key,
        format!(
            "must be more than 4 x timing.jitter_sigma_s = {} s so that sample times \
             increase, got {period} s",
            4.0 * jitter_sigma
        ),
    ))
}

/// Formats a number for Markdown with `decimals` decimals.
pub fn f(x: f64, decimals: usize) -> String {
    format!("{x:.decimals$}")
}

/// Checks the name of the case at `cases[index]`: a non-empty name of
/// `[A-Za-z0-9_-]` (it becomes part of method names and file names) that no earlier
/// case uses.
///
/// # Errors
/// [`SimError::Invalid`] naming `cases[index].name`.
pub fn check_case_name<'a>(
    file: &str,
    index: usize,
    name: &str,
    earlier: impl IntoIterator<Item = &'a str>,
) -> Result<(), SimError> {
    let key = format!("cases[{index}].name");
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        return Err(SimError::invalid(
            file,
            key,
            format!("must be a non-empty name of [a-z0-9_-], got {name:?}"),
        ));
    }
    if earlier.into_iter().any(|e| e == name) {
        return Err(SimError::invalid(
            file,
            key,
            format!("duplicate case name {name:?}"),
        ));
    }
    Ok(())
}

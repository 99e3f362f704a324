//! The `[world]` and `[map_aided]` tables of the `gnss-ins` settings: the user's
//! world mesh (read like the `urban` experiment's world files) and where it lies,
//! and the map-aided filters' tuning, checked into [`WorldSettings`] and
//! [`MapAidedSettings`] (library types; errors name the key).

use fathom_estimators::map_aided::{
    GrekfParams, GrekfSettings, MgpmfParams, MgpmfSettings, RangeParams, SwitchParams,
    SwitchSettings,
};
use fathom_map::{AxisConvention, ImportSettings};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use fathom_sim::SimError;
use fathom_sim::scenario::{require_in_range, require_non_negative, require_positive};

/// `[world]`: the world mesh the map-aided filters cast their beams against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WorldToml {
    /// A Wavefront OBJ or STL file (relative: from the working directory); `fathom
    /// replay gnss-ins DIR --world FILE` sets it.
    pub file: String,
    /// The file's axes: `"enu_z_up"` (default: x east, y north, z up), `"ned"`,
    /// `"y_up_right_handed"` (Blender / glTF) or `"y_up_left_handed"` (Unity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<String>,
    /// Metres per file unit (default 1).
    ///
    /// Range: > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Subtracted from every file point first, in file axes and units (default 0).
    ///
    /// Range: finite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin_offset: Option<[f64; 3]>,
    /// Where the file's origin (after `origin_offset`) is: latitude, longitude and
    /// altitude (the GNSS altitude datum). Default: the replay's start (EKF2's first
    /// position in the IMU data).
    ///
    /// Unit: deg, deg, m. Range: latitude strictly inside ±90, longitude within
    /// ±180.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin_lat_lon_alt: Option<[f64; 3]>,
}

/// A checked `[world]`.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldSettings {
    /// The file as written.
    pub file: String,
    /// How to read it into NED metres (the `urban` experiment's import limits).
    pub import: ImportSettings,
    /// The file origin's latitude, longitude (rad) and altitude (m), if given.
    pub origin: Option<[f64; 3]>,
}

impl WorldToml {
    /// Checks the table.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<WorldSettings, SimError> {
        if self.file.trim().is_empty() {
            return Err(SimError::invalid(file, "world.file", "must not be empty"));
        }
        let mut import = ImportSettings::default();
        if let Some(a) = &self.axes {
            import.axes = match a.as_str() {
                "enu_z_up" => AxisConvention::EnuZUp,
                "ned" => AxisConvention::Ned,
                "y_up_right_handed" => AxisConvention::YUpRightHanded,
                "y_up_left_handed" => AxisConvention::YUpLeftHanded,
                other => {
                    return Err(SimError::invalid(
                        file,
                        "world.axes",
                        format!(
                            "unknown axes \"{}\"; use one of: enu_z_up, ned, y_up_right_handed, \
                             y_up_left_handed",
                            fathom_core::echo::echo(other)
                        ),
                    ));
                }
            };
        }
        if let Some(s) = self.scale {
            import.scale = require_positive(file, "world.scale", s)?;
        }
        if let Some(o) = self.origin_offset {
            for (k, v) in o.iter().enumerate() {
                if !v.is_finite() {
                    return Err(SimError::invalid(
                        file,
                        format!("world.origin_offset[{k}]"),
                        format!("must be finite, got {v}"),
                    ));
                }
            }
            import.origin_offset = o;
        }
        let origin = match self.origin_lat_lon_alt {
            None => None,
            Some([lat, lon, alt]) => {
                if !(lat.is_finite() && lat.abs() < 90.0) {
                    return Err(SimError::invalid(
                        file,
                        "world.origin_lat_lon_alt[0]",
                        format!("must be a latitude strictly inside ±90 deg, got {lat}"),
                    ));
                }
                require_in_range(file, "world.origin_lat_lon_alt[1]", lon, -180.0, 180.0)?;
                require_in_range(file, "world.origin_lat_lon_alt[2]", alt, -1e4, 1e5)?;
                Some([lat.to_radians(), lon.to_radians(), alt])
            }
        };
        Ok(WorldSettings {
            file: self.file.clone(),
            import,
            origin,
        })
    }
}

/// `[map_aided]`: the GREKF and MGPMF of the `urban` experiment on the log's range
/// beams, and when they take over from GPS/INS. Defaults: the `urban` preset's
/// tuning (library defaults for the rest: the GREKF's lost lock after 5 updates with
/// every beam left out, covariance x 4; the MGPMF's ±3σ grid and 5 % outliers).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MapAidedToml {
    /// σ of a range the filters assume (a log holds no σ per beam).
    ///
    /// Unit: m. Range: > 0.
    pub range_sigma_m: f64,
    /// σ of the barometric height (`baro.csv`, aligned to EKF2's altitude at the
    /// start); without `baro.csv` no height update.
    ///
    /// Unit: m. Range: > 0.
    pub baro_sigma_m: f64,
    /// Longest range used; a longer reading, or a predicted ray longer than this, is
    /// no hit.
    ///
    /// Unit: m. Range: > 0.
    pub max_range_m: f64,
    /// Largest incidence angle of a predicted hit whose row is used.
    ///
    /// Unit: deg. Range: 0 to 90 (exclusive).
    pub max_incidence_deg: f64,
    /// Probability that a consistent beam passes the per-beam chi-square gate.
    ///
    /// Range: 0 to 1 (exclusive).
    pub gate_probability: f64,
    /// Iterations of the GREKF's iterated update.
    ///
    /// Range: 1 to 20.
    pub grekf_iterations: usize,
    /// The MGPMF's grid points along north, east and yaw.
    ///
    /// Range: 3 to 101 each.
    pub grid_points: [usize; 3],
    /// The MGPMF updates on every `grid_every`-th range epoch.
    ///
    /// Range: 1 to 1000.
    pub grid_every: usize,
    /// The MGPMF uses every `grid_beam_stride`-th beam of an epoch.
    ///
    /// Range: 1 to 1000.
    pub grid_beam_stride: usize,
    /// GPS/INS while the used fixes have at least this many satellites; a fix the
    /// replay does not use (below `gnss.min_fix_type`, in an outage) counts 0.
    ///
    /// Range: 1 to 64.
    pub min_satellites: usize,
    /// Shortest time in a mode before the next switch.
    ///
    /// Unit: s. Range: >= 0.
    pub min_dwell_s: f64,
}

impl Default for MapAidedToml {
    fn default() -> Self {
        Self {
            range_sigma_m: 0.06,
            baro_sigma_m: 0.3,
            max_range_m: 60.0,
            max_incidence_deg: 45.0,
            gate_probability: 0.999,
            grekf_iterations: 3,
            grid_points: [15, 15, 5],
            grid_every: 2,
            grid_beam_stride: 9,
            min_satellites: 5,
            min_dwell_s: 1.0,
        }
    }
}

/// A checked `[map_aided]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapAidedSettings {
    /// Range σ, m.
    pub range_sigma: f64,
    /// Baro σ, m.
    pub baro_sigma: f64,
    /// Longest range used, m.
    pub max_range: f64,
    /// The GREKF.
    pub grekf: GrekfSettings,
    /// The MGPMF.
    pub mgpmf: MgpmfSettings,
    /// The mode switch.
    pub switch: SwitchSettings,
    /// MGPMF update every this many range epochs.
    pub grid_every: usize,
    /// MGPMF beam stride.
    pub grid_beam_stride: usize,
}

impl MapAidedToml {
    /// Checks every value.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<MapAidedSettings, SimError> {
        let key = |k: &str| format!("map_aided.{k}");
        let range_sigma = require_positive(file, &key("range_sigma_m"), self.range_sigma_m)?;
        let baro_sigma = require_positive(file, &key("baro_sigma_m"), self.baro_sigma_m)?;
        let max_range = require_positive(file, &key("max_range_m"), self.max_range_m)?;
        let inc = self.max_incidence_deg;
        if !(inc > 0.0 && inc < 90.0) {
            return Err(SimError::invalid(
                file,
                key("max_incidence_deg"),
                format!("must be strictly between 0 and 90 deg, got {inc}"),
            ));
        }
        let p = self.gate_probability;
        if !(p > 0.0 && p < 1.0) {
            return Err(SimError::invalid(
                file,
                key("gate_probability"),
                format!("must be strictly between 0 and 1, got {p}"),
            ));
        }
        let count = |k: &str, v: usize, lo: usize, hi: usize| {
            if (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(SimError::invalid(
                    file,
                    key(k),
                    format!("must be {lo} to {hi}, got {v}"),
                ))
            }
        };
        let iterations = count("grekf_iterations", self.grekf_iterations, 1, 20)?;
        for (i, n) in self.grid_points.iter().enumerate() {
            count(&format!("grid_points[{i}]"), *n, 3, 101)?;
        }
        let grid_every = count("grid_every", self.grid_every, 1, 1000)?;
        let grid_beam_stride = count("grid_beam_stride", self.grid_beam_stride, 1, 1000)?;
        let min_sats = count("min_satellites", self.min_satellites, 1, 64)?;
        let dwell = require_non_negative(file, &key("min_dwell_s"), self.min_dwell_s)?;
        let range = RangeParams {
            max_range_m: max_range,
            max_incidence_deg: inc,
            gate_probability: p,
        };
        let lib = |e: fathom_estimators::map_aided::MapAidedError| {
            SimError::invalid(file, "map_aided", e.to_string())
        };
        let grekf = GrekfParams {
            range,
            iterations,
            ..GrekfParams::default()
        }
        .check()
        .map_err(lib)?;
        let mgpmf = MgpmfParams {
            grid_points: self.grid_points,
            range,
            ..MgpmfParams::default()
        }
        .check()
        .map_err(lib)?;
        let switch = SwitchParams {
            min_los_satellites: min_sats,
            hysteresis_satellites: 0,
            min_dwell_s: dwell,
        }
        .check()
        .map_err(lib)?;
        Ok(MapAidedSettings {
            range_sigma,
            baro_sigma,
            max_range,
            grekf,
            mgpmf,
            switch,
            grid_every,
            grid_beam_stride,
        })
    }
}

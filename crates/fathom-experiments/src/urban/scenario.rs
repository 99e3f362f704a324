//! The `urban` scenario file (`scenarios/urban.toml`): its schema. The conversion
//! into checked library types is in [`super::check`].

use fathom_map::presets::{BridgeParams, BuildingsParams};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Map-aided navigation near structures.
///
/// Paper D (Koh, Ryu, Sung 2020, seed 004): a quadrotor flies under a bridge and
/// around tall buildings; an INS (ADIS16448) is aided by GPS where enough satellites
/// are in line of sight and by range sensors or a lidar against the 3-D map where
/// they are not. Per Monte Carlo run every method (INS-only, GPS/INS with and without
/// the line-of-sight test, and the switching GREKF, MGPMF and particle filter) runs on
/// the same sensor data. Each `[[scenarios]]` entry is a world (a preset or your own
/// OBJ / STL file) with a path; the rows are `<scenario>/<method>`. Preset:
/// `scenarios/urban.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct UrbanScenario {
    /// The experiment this file is for.
    ///
    /// Range: `"urban"`.
    pub experiment: String,
    /// Monte Carlo runs of the main batch (spec: ≥ 50); `--runs` overrides.
    ///
    /// Range: ≥ 2.
    pub runs: usize,
    /// Run `i` of every batch uses ChaCha stream `i` of this seed.
    ///
    /// Range: 0 … 2⁶⁴−1.
    pub base_seed: u64,
    /// The methods to run, report and plot. With a subset the paper's claims (which
    /// compare the methods) and the ablations of methods not selected are left out
    /// (the report says so); each selected method's results equal those of the full
    /// run with the same seed.
    ///
    /// Range: a list of `"INS-only"`, `"GPS/INS"`, `"GPS/INS-all-sats"`, `"GREKF"`,
    /// `"MGPMF"`, `"PF"`. Default: all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub methods: Option<Vec<String>>,
    /// The range sensors' model in the main batch: `"none"`, Gaussian noise only
    /// (every beam returns at any incidence, glass ranges like opaque ones: the paper's
    /// simulation, section 4.2), or `"glass_incidence"`, the glass extra noise and the
    /// detection probability falling with the incidence angle of `[rangefinders]` and
    /// `[lidar]`. Absent: `"glass_incidence"`.
    ///
    /// Range: `"none"` or `"glass_incidence"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range_effects: Option<String>,
    /// The quadrotor's flight (truth): clock, speeds, wind.
    pub vehicle: VehicleToml,
    /// The IMU (ADIS16448, Table 1), in data-sheet units.
    pub imu: ImuToml,
    /// GNSS: constellation, receiver, line of sight against the map.
    pub gnss: GnssToml,
    /// The barometer, eq. (20), and the filter's pressure-to-height conversion.
    pub baro: BaroToml,
    /// The paper's range finders: 6 horizontal beams 60° apart and one down.
    pub rangefinders: RangefindersToml,
    /// The lidar (Hokuyo UST-20LX).
    pub lidar: LidarToml,
    /// The 12-state INS filter, GPS/INS and GREKF settings.
    pub filter: FilterToml,
    /// The marginalized Gaussian point-mass filter.
    pub mgpmf: MgpmfToml,
    /// The bootstrap particle filter (same ray budget as the MGPMF).
    pub particle: ParticleToml,
    /// Switching between GPS/INS and map-aided range/INS.
    pub switch: SwitchToml,
    /// How the runs are evaluated.
    pub evaluation: EvaluationToml,
    /// The worlds and paths, one entry each (the paper: `bridge` and `buildings`).
    pub scenarios: Vec<SceneToml>,
    /// Ablations the paper motivates (extra batches on one scenario and method); none
    /// when absent.
    #[serde(default)]
    pub ablations: AblationsToml,
    /// `[statistics]`: how the runs of each row are summarized (bootstrap resamples,
    /// divergence factor); defaults when absent.
    #[serde(default)]
    pub statistics: fathom_sim::statistics::StatisticsParams,
}

fathom_sim::monte_carlo_scenario!(UrbanScenario);

/// `[vehicle]`: the quadrotor flight (defaults of `fathom_traj::quadrotor` for the
/// rigid body and the controller gains).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VehicleToml {
    /// Rest at the first waypoint before take-off; the gyro bias is calibrated by
    /// averaging over it (the paper) and navigation starts at its end.
    ///
    /// Unit: s. Range: ≥ 1.
    pub rest_s: f64,
    /// Horizontal speed along a leg.
    ///
    /// Unit: m/s. Range: > 0.
    pub cruise_speed_mps: f64,
    /// Vertical speed along a leg (climb, descent).
    ///
    /// Unit: m/s. Range: > 0.
    pub vertical_speed_mps: f64,
    /// Hover at every waypoint after the first.
    ///
    /// Unit: s. Range: ≥ 0.
    pub hover_s: f64,
    /// Controller rate (RK4 at twice this rate); a whole multiple of `imu.rate_hz`.
    ///
    /// Unit: Hz. Range: > 0.
    pub control_rate_hz: f64,
    /// Mean wind `[north, east, down]`.
    ///
    /// Unit: m/s. Range: finite.
    pub wind_mean_mps: [f64; 3],
    /// Gust standard deviation per axis (Gauss-Markov, drawn per run).
    ///
    /// Unit: m/s. Range: ≥ 0.
    pub gust_sigma_mps: [f64; 3],
    /// Gust correlation time.
    ///
    /// Unit: s. Range: > 0.
    pub gust_correlation_time_s: f64,
}

/// `[imu]`: the Allan-variance figures of Table 1 (default: the measured upper bounds).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ImuToml {
    /// Gyro angle random walk (Table 1: 0.67-0.83 measured, 0.66 data sheet).
    ///
    /// Unit: deg/√h. Range: ≥ 0.
    pub arw_deg_per_sqrt_hr: f64,
    /// Accelerometer velocity random walk (Table 1: 0.12-0.14, data sheet 0.11).
    ///
    /// Unit: m/s/√h. Range: ≥ 0.
    pub vrw_mps_per_sqrt_hr: f64,
    /// Gyro bias instability (Table 1: 15-17, data sheet 14.5; printed in deg/√h).
    ///
    /// Unit: deg/h. Range: ≥ 0.
    pub gyro_bias_instability_deg_per_hr: f64,
    /// Accelerometer bias instability (Table 1: 0.09-0.12, data sheet 0.25).
    ///
    /// Unit: mg. Range: ≥ 0.
    pub accel_bias_instability_mg: f64,
    /// Gyro turn-on bias, 1 σ per axis and run (not in the paper; removed by the
    /// calibration at rest up to the averaged noise).
    ///
    /// Unit: deg/h. Range: ≥ 0.
    pub gyro_turn_on_bias_deg_per_hr: f64,
    /// Accelerometer turn-on bias, 1 σ per axis and run (not in the paper; a filter
    /// state).
    ///
    /// Unit: mg. Range: ≥ 0.
    pub accel_turn_on_bias_mg: f64,
    /// Output rate (paper: 100).
    ///
    /// Unit: Hz. Range: > 0; `vehicle.control_rate_hz` a whole multiple of it.
    pub rate_hz: f64,
}

/// `[gnss]`: a GPS-like constellation seen from the scenario origin, each
/// satellite's line of sight tested against the map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct GnssToml {
    /// Latitude of the NED origin (not in the paper).
    ///
    /// Unit: deg. Range: [-89, 89].
    pub lat_deg: f64,
    /// Longitude of the NED origin.
    ///
    /// Unit: deg. Range: [-180, 180].
    pub lon_deg: f64,
    /// Height of the NED origin above the ellipsoid (also the baro's origin height).
    ///
    /// Unit: m. Range: [-500, 40000].
    pub height_m: f64,
    /// Satellites kept: the highest ones above the mask at `t = 0` of the nominal
    /// 24-slot GPS constellation (paper: 9).
    ///
    /// Range: 4 … 24.
    pub satellites: usize,
    /// Time of `t = 0` after the constellation epoch (turns the sky).
    ///
    /// Unit: s. Range: finite, |·| ≤ 1e9.
    pub epoch_offset_s: f64,
    /// Elevation mask.
    ///
    /// Unit: deg. Range: [0, 60].
    pub elevation_mask_deg: f64,
    /// Pseudorange noise σ (LOS).
    ///
    /// Unit: m. Range: > 0.
    pub pseudorange_sigma_m: f64,
    /// Probability that a blocked satellite's signal arrives anyway (reflected, NLOS).
    ///
    /// Range: [0, 1].
    pub nlos_reception_probability: f64,
    /// Smallest excess path delay of a received NLOS signal.
    ///
    /// Unit: m. Range: ≥ 0.
    pub nlos_delay_min_m: f64,
    /// Largest excess path delay.
    ///
    /// Unit: m. Range: ≥ `nlos_delay_min_m`.
    pub nlos_delay_max_m: f64,
    /// Fix rate; `imu.rate_hz` a whole multiple of it.
    ///
    /// Unit: Hz. Range: > 0.
    pub rate_hz: f64,
}

/// How the filter turns pressure into height.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum BaroInverse {
    /// Eq. (11): the chord between the two calibration heights.
    Linear,
    /// The exact inverse of eq. (20).
    Exact,
}

/// `[baro]`: `p = 101325 (1 - 2.25577e-5 (h + n))^5.25588`, eq. (20).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BaroToml {
    /// Height noise σ of eq. (20) (not in the paper).
    ///
    /// Unit: m. Range: > 0.
    pub height_noise_sigma_m: f64,
    /// The filter's conversion of pressure into height.
    pub inverse: BaroInverse,
    /// Eq. (11)'s two reference heights above the NED origin.
    ///
    /// Unit: m. Range: finite, increasing.
    pub calibration_heights_m: [f64; 2],
    /// Height σ the filter assumes.
    ///
    /// Unit: m. Range: > 0.
    pub filter_sigma_m: f64,
}

/// Detection probability versus incidence angle: `p_max` up to `full_until_deg`,
/// falling linearly to 0 at `zero_from_deg`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DetectionToml {
    /// Probability of a return near normal incidence.
    ///
    /// Range: [0, 1].
    pub p_max: f64,
    /// Incidence up to which `p_max` holds.
    ///
    /// Unit: deg. Range: [0, 90].
    pub full_until_deg: f64,
    /// Incidence from which nothing returns.
    ///
    /// Unit: deg. Range: [`full_until_deg`, 90].
    pub zero_from_deg: f64,
}

/// `[rangefinders]`: 6 horizontal beams at 0, 60, …, 300° from the nose and one
/// down (the paper's layout; the noise model's numbers are settings).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RangefindersToml {
    /// Largest range returned.
    ///
    /// Unit: m. Range: > 0.
    pub max_range_m: f64,
    /// Noise σ at zero range.
    ///
    /// Unit: m. Range: ≥ 0.
    pub sigma_floor_m: f64,
    /// Noise σ per metre of range.
    ///
    /// Unit: m/m. Range: ≥ 0.
    pub sigma_per_m: f64,
    /// Extra noise σ on glass.
    ///
    /// Unit: m. Range: ≥ 0.
    pub glass_extra_sigma_m: f64,
    /// Detection on opaque surfaces.
    pub opaque_detection: DetectionToml,
    /// Detection on glass (returns only near normal incidence).
    pub glass_detection: DetectionToml,
    /// Sample rate; `imu.rate_hz` a whole multiple of it.
    ///
    /// Unit: Hz. Range: > 0.
    pub rate_hz: f64,
}

/// `[lidar]`: beams in the body's horizontal plane from `first_deg` to `last_deg`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LidarToml {
    /// First beam azimuth (UST-20LX: -135).
    ///
    /// Unit: deg. Range: finite.
    pub first_deg: f64,
    /// Last beam azimuth (UST-20LX: 135).
    ///
    /// Unit: deg. Range: ≥ `first_deg`.
    pub last_deg: f64,
    /// Azimuth step (paper: 2.5, 109 beams; the device resolves 0.25).
    ///
    /// Unit: deg. Range: > 0.
    pub step_deg: f64,
    /// Scan rate (paper: 5); `imu.rate_hz` a whole multiple of it.
    ///
    /// Unit: Hz. Range: > 0.
    pub rate_hz: f64,
    /// Largest range (data sheet: 60).
    ///
    /// Unit: m. Range: > 0.
    pub max_range_m: f64,
    /// Range noise σ (data sheet ±40 mm read as 2 σ).
    ///
    /// Unit: m. Range: ≥ 0.
    pub sigma_m: f64,
    /// Extra noise σ on glass.
    ///
    /// Unit: m. Range: ≥ 0.
    pub glass_extra_sigma_m: f64,
    /// Detection on opaque surfaces.
    pub opaque_detection: DetectionToml,
    /// Detection on glass.
    pub glass_detection: DetectionToml,
}

/// `[filter]`: the 12-state error-state INS (eq. 1-5), GPS/INS and the GREKF.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FilterToml {
    /// Initial position error σ per axis (drawn per run, the same for every method).
    ///
    /// Unit: m. Range: > 0.
    pub initial_position_sigma_m: f64,
    /// Initial velocity error σ per axis.
    ///
    /// Unit: m/s. Range: > 0.
    pub initial_velocity_sigma_mps: f64,
    /// Initial roll and pitch error σ.
    ///
    /// Unit: deg. Range: > 0.
    pub initial_roll_pitch_sigma_deg: f64,
    /// Initial yaw error σ.
    ///
    /// Unit: deg. Range: > 0.
    pub initial_yaw_sigma_deg: f64,
    /// Initial accelerometer-bias σ of the filter.
    ///
    /// Unit: mg. Range: > 0.
    pub initial_accel_bias_sigma_mg: f64,
    /// Accelerometer white noise the filter assumes.
    ///
    /// Unit: m/s/√h. Range: ≥ 0.
    pub vrw_mps_per_sqrt_hr: f64,
    /// Gyro white noise the filter assumes (inflate it for the uncalibrated gyro bias
    /// drift: no gyro-bias state).
    ///
    /// Unit: deg/√h. Range: ≥ 0.
    pub arw_deg_per_sqrt_hr: f64,
    /// Accelerometer-bias random walk of the filter (0: the paper's constant bias).
    ///
    /// Unit: mg/√s. Range: ≥ 0.
    pub accel_bias_random_walk_mg_per_sqrt_s: f64,
    /// Probability that a consistent GPS fix passes the chi-square gate.
    ///
    /// Range: (0, 1).
    pub gps_gate_probability: f64,
    /// GPS fixes rejected by the gate in a row after which the next fix re-acquires
    /// the position (the covariance widened by the error the fix shows, as an
    /// autopilot resets to GNSS): a filter that drifted in the shadow takes the fixes
    /// again when the sky opens. 0: never (the paper's filter). Absent: 0.
    ///
    /// Range: 0 … 1000.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gps_reacquire_after_rejections: Option<usize>,
    /// Probability that a consistent range passes the GREKF's per-beam gate.
    ///
    /// Range: (0, 1).
    pub range_gate_probability: f64,
    /// Largest incidence of a predicted hit whose row is used (GREKF and the linear
    /// step of the grid filters). It must not exceed the incidence from which the
    /// scenarios' range sensors return nothing on an opaque surface
    /// (`opaque_detection.zero_from_deg`): a row there has no measurement to match.
    ///
    /// Unit: deg. Range: (0, 90).
    pub max_incidence_deg: f64,
    /// Iterations of the GREKF update (iterated EKF: the rays cast again from the
    /// updated pose; 1 is the paper's single update). Absent: 1.
    ///
    /// Range: 1 … 20.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grekf_iterations: Option<usize>,
    /// Factor on every beam's range σ in the GREKF update and gate, for the errors
    /// the beams share (one facet seen by many beams, the faceted map, the attitude).
    /// Absent: 1 (the beams independent).
    ///
    /// Range: 1 … 100.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range_sigma_inflation: Option<f64>,
    /// Consecutive GREKF updates with every beam left out after which it has lost
    /// lock and inflates its position, velocity and attitude covariance by
    /// `relock_inflation` (repeated until a beam is used again); 0 never. Absent: 5.
    ///
    /// Range: 0 … 1000.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lock_loss_updates: Option<usize>,
    /// The covariance factor of a lost lock. Absent: 4.
    ///
    /// Range: (1, 100].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relock_inflation: Option<f64>,
    /// The GREKF's linearity check: each beam is cast again from the prior pose
    /// moved by ± this many standard deviations along north, east and yaw, and left
    /// out where its range is not linear over that span (a corner or a gap within
    /// the filter's uncertainty). 0: no check (the paper's update). Absent: 0.
    ///
    /// Range: 0 … 10.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grekf_linearity_sigmas: Option<f64>,
}

/// `[mgpmf]`: grid, likelihood and rate of the point-mass filter (section 2.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MgpmfToml {
    /// Grid points along north, east and yaw error (the library default 41 × 41 × 9
    /// costs ~20 ms per update: see the preset's note).
    ///
    /// Range: each 2 … 1000, ≤ 1e6 in all.
    pub grid_points: [usize; 3],
    /// Half-width of the grid in predicted standard deviations.
    ///
    /// Range: (0, 10].
    pub k_sigma: f64,
    /// Outlier probability of the robust range likelihood.
    ///
    /// Range: [0, 1).
    pub outlier_probability: f64,
    /// Update rate of the point-mass and particle filters; the range sensor's rate a
    /// whole multiple of it.
    ///
    /// Unit: Hz. Range: > 0.
    pub rate_hz: f64,
    /// With the lidar, the point-mass and particle filters use every `k`-th beam
    /// (the GREKF uses all).
    ///
    /// Range: ≥ 1.
    pub lidar_beam_stride: usize,
    /// How the weighted grid becomes the posterior covariance: `"interpolated"`, the
    /// paper's eq. (18) plus the hat-function variance of its linear interpolation
    /// (broader than the prior on an axis the ranges do not inform, so it can grow
    /// without bound on a coarse grid), or `"information"`, the information the grid
    /// adds to the prior with the discretization cancelled (docs/reproduction.md).
    /// Absent: `"interpolated"`.
    ///
    /// Range: `"interpolated"` or `"information"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub posterior: Option<String>,
}

/// `[particle]`: the bootstrap particle filter, as many particles as grid points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ParticleToml {
    /// Roughening constant after resampling (Gordon et al. 1993).
    ///
    /// Range: [0, 10].
    pub roughening: f64,
    /// The jitter after resampling: `"roughening"` (Gordon et al. 1993, std
    /// `roughening × spread × N^(-1/3)` per axis) or `"regularized"` (the regularized
    /// particle filter: a Gaussian kernel on the posterior covariance with the
    /// optimal bandwidth; `roughening` unused). Absent: `"roughening"`.
    ///
    /// Range: `"roughening"` or `"regularized"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kernel: Option<String>,
}

/// `[switch]`: GPS/INS while enough satellites are in line of sight, map-aided
/// otherwise (the paper gives no threshold).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SwitchToml {
    /// GPS/INS while at least this many satellites are in line of sight (tested from
    /// the estimated position against the map).
    ///
    /// Range: 4 … 64.
    pub min_los_satellites: usize,
    /// Extra satellites needed to return to GPS/INS.
    ///
    /// Range: 0 … 64.
    pub hysteresis_satellites: usize,
    /// Shortest time in a mode.
    ///
    /// Unit: s. Range: ≥ 0.
    pub min_dwell_s: f64,
}

/// `[evaluation]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EvaluationToml {
    /// Error evaluation rate; `imu.rate_hz` a whole multiple of it.
    ///
    /// Unit: Hz. Range: > 0.
    pub rate_hz: f64,
    /// Upper end of the error histograms (errors beyond it are counted apart).
    ///
    /// Unit: m. Range: > 0.
    pub histogram_max_m: f64,
    /// Bins of the error histograms.
    ///
    /// Range: 2 … 1000.
    pub histogram_bins: usize,
    /// Relative tolerance of the Table 2 comparison: an entry agrees when the 95 % CI
    /// widened by this fraction of the paper value on each side contains it.
    ///
    /// Range: [0, 10].
    pub table2_tolerance: f64,
}

/// Which range sensor a scenario flies with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Ranging {
    /// The lidar (the paper's bridge flight).
    Lidar,
    /// The 6 + 1 range finders (the paper's buildings flight).
    Rangefinders,
}

/// The preset worlds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum PresetWorld {
    /// A deck over two rows of cylindrical piers.
    Bridge,
    /// A block of tall buildings around a square path.
    Buildings,
}

/// A mesh file's axis convention.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AxesToml {
    /// `x` north, `y` east, `z` down.
    Ned,
    /// `x` east, `y` north, `z` up (GIS, city models).
    EnuZUp,
    /// `x` east, `y` up, `z` south (Blender / glTF OBJ export).
    YUpRightHanded,
    /// `x` east, `y` up, `z` north (Unity).
    YUpLeftHanded,
}

/// `[[scenarios]]`: one world and path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SceneToml {
    /// Name (the first part of the row names, `bridge/GREKF`); the paper's numbers
    /// are attached to `bridge` and `buildings` on their preset worlds.
    ///
    /// Range: non-empty, `[A-Za-z0-9_-]`, unique.
    pub name: String,
    /// The range sensor of this scenario (paper: lidar under the bridge, range
    /// finders around the buildings).
    pub ranging: Ranging,
    /// The world.
    pub world: WorldToml,
    /// The path; without `waypoints` on a preset world, the preset's path.
    pub path: PathToml,
}

/// `[scenarios.world]`: a preset, or your own mesh file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WorldToml {
    /// A preset world (exactly one of `preset` and `file`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<PresetWorld>,
    /// A Wavefront OBJ (`usemtl opaque` / `usemtl glass`) or STL file, relative to
    /// the working directory (`fathom run`) or the workspace (`cargo xtask paper`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// The file's axes (default `enu_z_up`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<AxesToml>,
    /// Metres per file unit (default 1).
    ///
    /// Range: > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Subtracted from every file point (and waypoint) first, in file axes and units
    /// (default 0).
    ///
    /// Range: finite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin_offset: Option<[f64; 3]>,
    /// Dimensions of the `bridge` preset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bridge: Option<BridgeParams>,
    /// Dimensions of the `buildings` preset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub buildings: Option<BuildingsParams>,
}

/// `[scenarios.path]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PathToml {
    /// Waypoints in the world's frame (a file world: the file's axes, units and
    /// offset, like its vertices), flown in order along straight legs; the vehicle
    /// rests at the first. Required for a file world; a preset world without them
    /// flies the preset's path, which starts at rest in open sky (bridge: 40 m south
    /// of the deck, at most 80 % of the ground margin; then at the path height under
    /// the deck between the pier rows to as far beyond its north end; buildings: at
    /// twice the clearance south-west of the square's first corner, then the square,
    /// turning 90° in place at the far corner). Every waypoint must lie within
    /// the mesh's plan bounds and not below it, and no leg may pass through the mesh.
    ///
    /// Unit: file units (m for presets). Range: ≥ 2 waypoints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub waypoints: Option<Vec<[f64; 3]>>,
    /// Height of the start above the ground for the preset paths (the sensors sit
    /// this high when the vehicle rests).
    ///
    /// Unit: m. Range: > 0.
    pub start_height_m: f64,
}

/// `[ablations]`: extra batches of `runs` runs on one scenario and method, each run
/// drawing the same random numbers as the main batch's run of the same index (paired
/// differences).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AblationsToml {
    /// Runs of each ablation batch.
    ///
    /// Range: 2 … `runs` (after `--runs`, capped at it) when an ablation is listed.
    /// Default: 0 (no ablation).
    #[serde(default)]
    pub runs: usize,
    /// Range noise Gaussian only (glass treated as opaque: no extra noise, no
    /// incidence cut-off) against the main batch's glass effects (the paper calls
    /// its simulation optimistic for this reason).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gaussian_ranges: Option<AblationTargetToml>,
    /// Range effects on (glass extra noise, detection falling with the incidence angle,
    /// as `[rangefinders]` and `[lidar]` give them) against a main batch with
    /// `range_effects = "none"` (the paper's Gaussian ranges).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glass_incidence: Option<AblationTargetToml>,
    /// Another lidar step (the paper: 2.5°; the device resolves 0.25°).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lidar_step: Option<LidarStepToml>,
    /// The controller flies on the method's estimate instead of the truth (the
    /// processor in the loop).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control_on_estimate: Option<AblationTargetToml>,
    /// The MGPMF with the other `mgpmf.posterior` than the main batch's (the paper's
    /// interpolated covariance against the information form). The method must be
    /// `MGPMF`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mgpmf_posterior: Option<AblationTargetToml>,
}

/// The scenario and method of an ablation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AblationTargetToml {
    /// A `[[scenarios]]` name.
    pub scenario: String,
    /// A method: `INS-only`, `GPS/INS`, `GPS/INS-all-sats`, `GREKF`, `MGPMF`, `PF`.
    pub method: String,
}

/// `[ablations.lidar_step]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LidarStepToml {
    /// A `[[scenarios]]` name (its ranging must be `lidar`).
    pub scenario: String,
    /// A method (as in the other ablations).
    pub method: String,
    /// The lidar step of the ablation.
    ///
    /// Unit: deg. Range: > 0.
    pub step_deg: f64,
}

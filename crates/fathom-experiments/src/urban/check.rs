//! The `urban` scenario checked into the library crates' types ([`Checked`]); fast
//! and free of I/O (a world file is read by [`super::world`] when preparing).

use fathom_core::echo::echo;
use fathom_core::units::{
    deg_per_sqrt_hour_to_rad_per_sqrt_s, deg_to_rad, milli_g_to_mps2, per_sqrt_hour_to_per_sqrt_s,
};
use fathom_estimators::map_aided::{
    GpsAiding, GpsParams, GrekfParams, GrekfSettings, GridPosterior, ImuNoise, Ins12Filter,
    Ins12Params, Matrix12, MgpmfParams, MgpmfSettings, ParticleKernel, ParticleParams,
    ParticleSettings, RangeParams, RangeSettings, SwitchParams, SwitchSettings,
};
use fathom_sensors::allan_imu::{AllanImu, AllanImuParams};
use fathom_sensors::barometer::LinearBaroCalibration;
use fathom_sensors::map_range::{LidarParams, RangeSensor, RangeSensorParams};
use fathom_traj::quadrotor::{FlightParams, Quadrotor, QuadrotorParams, WindParams};
use nalgebra::Vector3;

use super::check_scene::model_err;
pub use super::check_scene::{SceneSpec, WorldSource};
use super::check_sensors::{count_in, every};
pub use super::check_sensors::{gaussian_only, lidar_params, rangefinder_params};
use super::method::Method;
use super::scenario::{BaroInverse, Ranging, UrbanScenario};
use fathom_sim::SimError;
use fathom_sim::method_list::select;
use fathom_sim::parameter_key::parameter_invalid;
use fathom_sim::scenario::{
    require_experiment, require_in_range, require_non_negative, require_positive,
};

/// How the filter turns pressure into height above the NED origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BaroConversion {
    /// Eq. (11).
    Linear(LinearBaroCalibration),
    /// The exact inverse of eq. (20).
    Exact,
}

/// The barometer and the filter's view of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaroSetup {
    /// Height noise σ of eq. (20), m.
    pub sigma: f64,
    /// Height of the NED origin above sea level, m.
    pub origin_height: f64,
    /// The filter's conversion.
    pub conversion: BaroConversion,
    /// Eq. (11)'s reference heights above the origin, m.
    pub calibration_heights: [f64; 2],
    /// Height σ the filter assumes, m.
    pub filter_sigma: f64,
}

/// The GNSS settings (the satellites are chosen when preparing).
#[derive(Debug, Clone, PartialEq)]
pub struct GnssSetup {
    /// Receiver parameters with the full nominal constellation.
    pub params: fathom_sensors::gnss::GnssParams,
    /// How many satellites to keep.
    pub satellites: usize,
}

/// The filters' settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilterSetup {
    /// Initial covariance (also the distribution of the initial errors).
    pub p0: Matrix12,
    /// IMU noise of the prediction.
    pub noise: ImuNoise,
    /// GPS gate.
    pub gps: GpsAiding,
    /// Ray casting and gate of the grid filters' linear step.
    pub range: RangeSettings,
    /// The GREKF: ray casting, gate, iterations, σ inflation, lost lock.
    pub grekf: GrekfSettings,
    /// The MGPMF.
    pub mgpmf: MgpmfSettings,
    /// The particle filter.
    pub particle: ParticleSettings,
    /// The mode switch.
    pub switch: SwitchSettings,
    /// Point-mass / particle update rate, Hz.
    pub grid_rate_hz: f64,
    /// With the lidar, the grid filters use every `k`-th beam.
    pub lidar_beam_stride: usize,
}

/// What an ablation changes.
#[derive(Debug, Clone, PartialEq)]
pub enum AblationKind {
    /// Another range model (the sensor of the ablation): Gaussian ranges
    /// (`gaussian_ranges`) or glass and incidence effects (`glass_incidence`).
    RangeModel(Box<RangeSensor>, &'static str),
    /// Another lidar step: the sensor and its step in degrees.
    LidarStep(Box<RangeSensor>, f64),
    /// The controller flies on the method's estimate.
    ControlOnEstimate,
    /// The MGPMF with this posterior covariance instead of the main batch's.
    GridPosterior(GridPosterior),
}

/// One ablation batch.
#[derive(Debug, Clone, PartialEq)]
pub struct Ablation {
    /// What changes.
    pub kind: AblationKind,
    /// Index into [`Checked::scenes`].
    pub scene: usize,
    /// The method run.
    pub method: Method,
}

impl Ablation {
    /// Short name used in row names (`buildings/MGPMF@gaussian_ranges`).
    pub fn label(&self) -> String {
        match &self.kind {
            AblationKind::RangeModel(_, label) => (*label).into(),
            AblationKind::LidarStep(_, step) => format!("lidar_step_{step}deg"),
            AblationKind::ControlOnEstimate => "control_on_estimate".into(),
            AblationKind::GridPosterior(GridPosterior::Interpolated) => {
                "posterior_interpolated".into()
            }
            AblationKind::GridPosterior(GridPosterior::Information) => {
                "posterior_information".into()
            }
        }
    }
}

/// Whole multiples between the rates (IMU steps per event).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Steps {
    /// Control steps per IMU step.
    pub control_per_imu: usize,
    /// IMU steps per GNSS epoch.
    pub gnss: usize,
    /// IMU steps per range-finder epoch.
    pub rangefinders: usize,
    /// IMU steps per lidar scan.
    pub lidar: usize,
    /// IMU steps per evaluation epoch.
    pub eval: usize,
}

/// The checked `urban` scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Checked {
    /// The scenario file's label (for errors found when preparing).
    pub file: String,
    /// Main-batch runs.
    pub runs: usize,
    /// `methods`: the methods run, in [`Method::ALL`] order.
    pub methods: Vec<Method>,
    /// Ablations left out because their method is not in `methods`.
    pub ablations_skipped: usize,
    /// Base seed.
    pub base_seed: u64,
    /// The quadrotor.
    pub quad: Quadrotor,
    /// Rest at the start, s.
    pub rest_s: f64,
    /// Path speeds (horizontal, vertical), m/s, and hover, s.
    pub speeds: (f64, f64, f64),
    /// The IMU.
    pub imu: AllanImu,
    /// The event clocks.
    pub steps: Steps,
    /// GNSS.
    pub gnss: GnssSetup,
    /// Barometer.
    pub baro: BaroSetup,
    /// Range finders.
    pub rangefinders: RangeSensor,
    /// Lidar.
    pub lidar: RangeSensor,
    /// Filters.
    pub filter: FilterSetup,
    /// Upper end of the histograms, m, and their bins.
    pub histogram: (f64, usize),
    /// Relative tolerance of the Table 2 comparison.
    pub table2_tolerance: f64,
    /// The scenarios.
    pub scenes: Vec<SceneSpec>,
    /// Runs of each ablation batch.
    pub ablation_runs: usize,
    /// The ablations.
    pub ablations: Vec<Ablation>,
    /// The settings the paper does not give, `(scenario key, value)`, for the report.
    pub unstated: Vec<(String, String)>,
    /// Shortest time in a mode, s (for the report).
    pub switch_dwell_s: f64,
}

impl Checked {
    /// Whether `methods` selects every method (the paper's full experiment).
    pub fn all_methods(&self) -> bool {
        self.methods.len() == Method::ALL.len()
    }

    /// The index of `m` in the records of a run (its place in `methods`).
    pub fn index_of(&self, m: Method) -> Option<usize> {
        self.methods.iter().position(|x| *x == m)
    }
}

fn target(
    file: &str,
    key: &str,
    scenario: &str,
    method: &str,
    scenes: &[SceneSpec],
) -> Result<(usize, Method), SimError> {
    let scene = scenes
        .iter()
        .position(|s| s.name == scenario)
        .ok_or_else(|| {
            SimError::invalid(
                file,
                format!("{key}.scenario"),
                format!("no [[scenarios]] entry is named \"{}\"", echo(scenario)),
            )
        })?;
    let method = Method::from_name(method).ok_or_else(|| {
        SimError::invalid(
            file,
            format!("{key}.method"),
            format!(
                "unknown method \"{}\", expected one of {}",
                echo(method),
                Method::ALL.map(|m| format!("{:?}", m.name())).join(", ")
            ),
        )
    })?;
    Ok((scene, method))
}

impl UrbanScenario {
    /// Validates the scenario (`file` labels errors).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key.
    pub fn check(&self, file: &str) -> Result<Checked, SimError> {
        require_experiment(file, &self.experiment, "urban")?;
        let v = &self.vehicle;
        let rest_s = require_in_range(file, "vehicle.rest_s", v.rest_s, 1.0, 3600.0)?;
        let cruise = require_positive(file, "vehicle.cruise_speed_mps", v.cruise_speed_mps)?;
        let vertical = require_positive(file, "vehicle.vertical_speed_mps", v.vertical_speed_mps)?;
        let hover = require_non_negative(file, "vehicle.hover_s", v.hover_s)?;
        let wind = WindParams {
            mean_in_nav: Vector3::from(v.wind_mean_mps),
            gust_sigma_mps: Vector3::from(v.gust_sigma_mps),
            gust_correlation_time_s: require_positive(
                file,
                "vehicle.gust_correlation_time_s",
                v.gust_correlation_time_s,
            )?,
        };
        let quad = QuadrotorParams {
            wind,
            flight: FlightParams {
                // the physics runs at twice this rate and needs at least 200 Hz
                control_rate_hz: require_in_range(
                    file,
                    "vehicle.control_rate_hz",
                    v.control_rate_hz,
                    100.0,
                    10_000.0,
                )?,
                physics_substeps: 2,
                rest_duration_s: rest_s,
                max_duration_s: 3600.0,
            },
            ..QuadrotorParams::default()
        }
        .check()
        .map_err(|e| parameter_invalid(file, "vehicle", v, &e))?;

        let i = &self.imu;
        let imu_rate = require_positive(file, "imu.rate_hz", i.rate_hz)?;
        let imu = AllanImuParams {
            arw_deg_per_sqrt_hr: i.arw_deg_per_sqrt_hr,
            vrw_mps_per_sqrt_hr: i.vrw_mps_per_sqrt_hr,
            gyro_bias_instability_deg_per_hr: i.gyro_bias_instability_deg_per_hr,
            accel_bias_instability_mg: i.accel_bias_instability_mg,
            gyro_turn_on_bias_deg_per_hr: i.gyro_turn_on_bias_deg_per_hr,
            accel_turn_on_bias_mg: i.accel_turn_on_bias_mg,
            rate_hz: imu_rate,
            ..AllanImuParams::adis16448()
        }
        .check()
        .map_err(|e| parameter_invalid(file, "imu", i, &e))?;
        let control_per_imu = every(file, "imu.rate_hz", v.control_rate_hz, imu_rate)?;

        let g = &self.gnss;
        let satellites = g.satellites;
        if !(4..=24).contains(&satellites) {
            return Err(SimError::invalid(
                file,
                "gnss.satellites",
                format!("must be 4 ... 24 (of the nominal constellation), got {satellites}"),
            ));
        }
        require_in_range(file, "gnss.lat_deg", g.lat_deg, -89.0, 89.0)?;
        require_in_range(file, "gnss.lon_deg", g.lon_deg, -180.0, 180.0)?;
        require_in_range(file, "gnss.height_m", g.height_m, -500.0, 40_000.0)?;
        require_in_range(file, "gnss.epoch_offset_s", g.epoch_offset_s, -1e9, 1e9)?;
        require_in_range(
            file,
            "gnss.elevation_mask_deg",
            g.elevation_mask_deg,
            0.0,
            60.0,
        )?;
        require_positive(file, "gnss.pseudorange_sigma_m", g.pseudorange_sigma_m)?;
        require_in_range(
            file,
            "gnss.nlos_reception_probability",
            g.nlos_reception_probability,
            0.0,
            1.0,
        )?;
        require_non_negative(file, "gnss.nlos_delay_min_m", g.nlos_delay_min_m)?;
        require_in_range(
            file,
            "gnss.nlos_delay_max_m",
            g.nlos_delay_max_m,
            g.nlos_delay_min_m,
            1e6,
        )?;
        let gnss_params = fathom_sensors::gnss::GnssParams {
            frame: fathom_sensors::gnss::LocalFrameParams {
                lat_deg: g.lat_deg,
                lon_deg: g.lon_deg,
                height_m: g.height_m,
            },
            epoch_offset_s: g.epoch_offset_s,
            elevation_mask_deg: g.elevation_mask_deg,
            pseudorange_sigma_m: g.pseudorange_sigma_m,
            nlos_reception_probability: g.nlos_reception_probability,
            nlos_delay_min_m: g.nlos_delay_min_m,
            nlos_delay_max_m: g.nlos_delay_max_m,
            rate_hz: g.rate_hz,
            ..fathom_sensors::gnss::GnssParams::default()
        };
        gnss_params
            .check()
            .map_err(|e| parameter_invalid(file, "gnss", g, &e))?;

        let b = &self.baro;
        let [h0, h1] = b.calibration_heights_m;
        let conversion = match b.inverse {
            BaroInverse::Exact => BaroConversion::Exact,
            BaroInverse::Linear => BaroConversion::Linear(
                LinearBaroCalibration::from_reference_heights(h0 + g.height_m, h1 + g.height_m)
                    .map_err(|e| model_err(file, "baro.calibration_heights_m", e))?,
            ),
        };
        if !(h0.is_finite() && h1.is_finite() && h1 > h0) {
            return Err(SimError::invalid(
                file,
                "baro.calibration_heights_m",
                format!("must be finite and increasing, got [{h0}, {h1}]"),
            ));
        }
        let baro = BaroSetup {
            sigma: require_positive(file, "baro.height_noise_sigma_m", b.height_noise_sigma_m)?,
            origin_height: g.height_m,
            conversion,
            calibration_heights: [h0, h1],
            filter_sigma: require_positive(file, "baro.filter_sigma_m", b.filter_sigma_m)?,
        };

        let gaussian_main = match self.range_effects.as_deref() {
            None | Some("glass_incidence") => false,
            Some("none") => true,
            Some(other) => {
                return Err(SimError::invalid(
                    file,
                    "range_effects",
                    format!(
                        "must be \"none\" or \"glass_incidence\", got \"{}\"",
                        echo(other)
                    ),
                ));
            }
        };
        let model = |p: RangeSensorParams, gaussian: bool| {
            if gaussian { gaussian_only(p) } else { p }
        };
        let rangefinders = model(rangefinder_params(file, &self.rangefinders)?, gaussian_main)
            .check()
            .map_err(|e| model_err(file, "rangefinders", e))?;
        let lidar_range_params = lidar_params(file, &self.lidar)?
            .to_range_params()
            .map_err(|e| model_err(file, "lidar", e))?;
        let lidar = if gaussian_main {
            gaussian_only(lidar_range_params.clone())
                .check()
                .map_err(|e| model_err(file, "lidar", e))?
        } else {
            lidar_params(file, &self.lidar)?
                .check()
                .map_err(|e| model_err(file, "lidar", e))?
        };

        let f = &self.filter;
        let mut p0 = Ins12Filter::diagonal_covariance([
            require_positive(
                file,
                "filter.initial_position_sigma_m",
                f.initial_position_sigma_m,
            )?,
            require_positive(
                file,
                "filter.initial_velocity_sigma_mps",
                f.initial_velocity_sigma_mps,
            )?,
            deg_to_rad(require_positive(
                file,
                "filter.initial_roll_pitch_sigma_deg",
                f.initial_roll_pitch_sigma_deg,
            )?),
            milli_g_to_mps2(require_positive(
                file,
                "filter.initial_accel_bias_sigma_mg",
                f.initial_accel_bias_sigma_mg,
            )?),
        ]);
        p0[(8, 8)] = deg_to_rad(require_positive(
            file,
            "filter.initial_yaw_sigma_deg",
            f.initial_yaw_sigma_deg,
        )?)
        .powi(2);
        let noise = Ins12Params {
            velocity_random_walk_mps_per_sqrt_s: per_sqrt_hour_to_per_sqrt_s(require_non_negative(
                file,
                "filter.vrw_mps_per_sqrt_hr",
                f.vrw_mps_per_sqrt_hr,
            )?),
            angle_random_walk_rad_per_sqrt_s: deg_per_sqrt_hour_to_rad_per_sqrt_s(
                require_non_negative(file, "filter.arw_deg_per_sqrt_hr", f.arw_deg_per_sqrt_hr)?,
            ),
            accel_bias_random_walk_mps2_per_sqrt_s: milli_g_to_mps2(require_non_negative(
                file,
                "filter.accel_bias_random_walk_mg_per_sqrt_s",
                f.accel_bias_random_walk_mg_per_sqrt_s,
            )?),
        }
        .check()
        .map_err(|e| parameter_invalid(file, "filter", f, &e))?;
        let reacquire = count_in(
            file,
            "filter.gps_reacquire_after_rejections",
            f.gps_reacquire_after_rejections.unwrap_or(0),
            0..=1000,
        )?;
        let gps = GpsParams {
            gate_probability: f.gps_gate_probability,
            reacquire_after_rejections: reacquire,
        }
        .check()
        .map_err(|e| model_err(file, "filter.gps_gate_probability", e))?;
        let range_params = RangeParams {
            max_range_m: lidar.max_range().max(rangefinders.max_range()),
            max_incidence_deg: f.max_incidence_deg,
            gate_probability: f.range_gate_probability,
        };
        let range = range_params
            .check()
            .map_err(|e| parameter_invalid(file, "filter", f, &e))?;
        let zero_from = self
            .lidar
            .opaque_detection
            .zero_from_deg
            .min(self.rangefinders.opaque_detection.zero_from_deg);
        if f.max_incidence_deg > zero_from {
            return Err(SimError::invalid(
                file,
                "filter.max_incidence_deg",
                format!(
                    "{} deg is beyond the incidence from which the range sensors return nothing \
                     on an opaque surface ({zero_from} deg, opaque_detection.zero_from_deg): \
                     the filter would use rows no sensor can measure",
                    f.max_incidence_deg
                ),
            ));
        }
        let grekf = GrekfParams {
            range: range_params,
            iterations: count_in(
                file,
                "filter.grekf_iterations",
                f.grekf_iterations.unwrap_or(1),
                1..=20,
            )?,
            sigma_inflation: require_in_range(
                file,
                "filter.range_sigma_inflation",
                f.range_sigma_inflation.unwrap_or(1.0),
                1.0,
                100.0,
            )?,
            lock_loss_updates: count_in(
                file,
                "filter.lock_loss_updates",
                f.lock_loss_updates.unwrap_or(5),
                0..=1000,
            )?,
            relock_inflation: f.relock_inflation.unwrap_or(4.0),
            linearity_sigmas: require_in_range(
                file,
                "filter.grekf_linearity_sigmas",
                f.grekf_linearity_sigmas.unwrap_or(0.0),
                0.0,
                10.0,
            )?,
        };
        if let Some(k) = f.relock_inflation
            && !(k > 1.0 && k <= 100.0)
        {
            return Err(SimError::invalid(
                file,
                "filter.relock_inflation",
                format!("must be in (1, 100], got {k}"),
            ));
        }
        let grekf = grekf
            .check()
            .map_err(|e| parameter_invalid(file, "filter", f, &e))?;
        let m = &self.mgpmf;
        let posterior = match m.posterior.as_deref() {
            None | Some("interpolated") => GridPosterior::Interpolated,
            Some("information") => GridPosterior::Information,
            Some(other) => {
                return Err(SimError::invalid(
                    file,
                    "mgpmf.posterior",
                    format!(
                        "must be \"interpolated\" or \"information\", got \"{}\"",
                        echo(other)
                    ),
                ));
            }
        };
        let mgpmf_params = MgpmfParams {
            grid_points: m.grid_points,
            k_sigma: m.k_sigma,
            outlier_probability: m.outlier_probability,
            posterior,
            range: range_params,
        };
        let mgpmf = mgpmf_params
            .check()
            .map_err(|e| parameter_invalid(file, "mgpmf", m, &e))?;
        let kernel = match self.particle.kernel.as_deref() {
            None | Some("roughening") => ParticleKernel::Roughening,
            Some("regularized") => ParticleKernel::Regularized,
            Some(other) => {
                return Err(SimError::invalid(
                    file,
                    "particle.kernel",
                    format!(
                        "must be \"roughening\" or \"regularized\", got \"{}\"",
                        echo(other)
                    ),
                ));
            }
        };
        let particle = ParticleParams {
            roughening: self.particle.roughening,
            kernel,
            ..ParticleParams::with_grid_budget(&mgpmf_params)
        }
        .check()
        .map_err(|e| parameter_invalid(file, "particle", &self.particle, &e))?;
        let s = &self.switch;
        if !(4..=64).contains(&s.min_los_satellites) {
            return Err(SimError::invalid(
                file,
                "switch.min_los_satellites",
                format!(
                    "must be 4 ... 64 (a fix needs 4), got {}",
                    s.min_los_satellites
                ),
            ));
        }
        let switch = SwitchParams {
            min_los_satellites: s.min_los_satellites,
            hysteresis_satellites: s.hysteresis_satellites,
            min_dwell_s: s.min_dwell_s,
        }
        .check()
        .map_err(|e| parameter_invalid(file, "switch", s, &e))?;
        if m.lidar_beam_stride == 0 || m.lidar_beam_stride > lidar.beams().len() {
            return Err(SimError::invalid(
                file,
                "mgpmf.lidar_beam_stride",
                format!(
                    "must be 1 ... {} (the lidar's beams), got {}",
                    lidar.beams().len(),
                    m.lidar_beam_stride
                ),
            ));
        }
        let rangefinder_steps = every(
            file,
            "rangefinders.rate_hz",
            imu_rate,
            rangefinders.rate_hz(),
        )?;
        let lidar_steps = every(file, "lidar.rate_hz", imu_rate, lidar.rate_hz())?;
        for (key, sensor_rate) in [
            ("rangefinders.rate_hz", rangefinders.rate_hz()),
            ("lidar.rate_hz", lidar.rate_hz()),
        ] {
            require_positive(file, "mgpmf.rate_hz", m.rate_hz)?;
            let n = sensor_rate / m.rate_hz;
            if (n - n.round()).abs() > 1e-9 || n.round() < 1.0 {
                return Err(SimError::invalid(
                    file,
                    "mgpmf.rate_hz",
                    format!(
                        "{} Hz must divide {key} = {sensor_rate} Hz a whole number of times",
                        m.rate_hz
                    ),
                ));
            }
        }
        let filter = FilterSetup {
            p0,
            noise,
            gps,
            range,
            grekf,
            mgpmf,
            particle,
            switch,
            grid_rate_hz: m.rate_hz,
            lidar_beam_stride: m.lidar_beam_stride,
        };

        let e = &self.evaluation;
        let gnss_steps = every(file, "gnss.rate_hz", imu_rate, g.rate_hz)?;
        let rest_steps = rest_s * imu_rate;
        if (rest_steps - rest_steps.round()).abs() > 1e-6
            || !(rest_steps.round() as usize).is_multiple_of(gnss_steps)
        {
            return Err(SimError::invalid(
                file,
                "vehicle.rest_s",
                format!(
                    "must be a whole number of GNSS periods (1 / gnss.rate_hz), got {rest_s} s"
                ),
            ));
        }
        let steps = Steps {
            control_per_imu,
            gnss: gnss_steps,
            rangefinders: rangefinder_steps,
            lidar: lidar_steps,
            eval: every(file, "evaluation.rate_hz", imu_rate, e.rate_hz)?,
        };
        let histogram_max =
            require_positive(file, "evaluation.histogram_max_m", e.histogram_max_m)?;
        if !(2..=1000).contains(&e.histogram_bins) {
            return Err(SimError::invalid(
                file,
                "evaluation.histogram_bins",
                format!("must be 2 ... 1000, got {}", e.histogram_bins),
            ));
        }
        let table2_tolerance = require_in_range(
            file,
            "evaluation.table2_tolerance",
            e.table2_tolerance,
            0.0,
            10.0,
        )?;

        if self.scenarios.is_empty() {
            return Err(SimError::invalid(
                file,
                "scenarios",
                "needs at least one scenario",
            ));
        }
        let mut scenes: Vec<SceneSpec> = Vec::new();
        for (k, s) in self.scenarios.iter().enumerate() {
            let spec = super::check_scene::scene(file, k, s, &scenes)?;
            scenes.push(spec);
        }

        let a = &self.ablations;
        let mut ablations = Vec::new();
        for (key, target_toml, gaussian, label) in [
            (
                "ablations.gaussian_ranges",
                &a.gaussian_ranges,
                true,
                "gaussian_ranges",
            ),
            (
                "ablations.glass_incidence",
                &a.glass_incidence,
                false,
                "glass_incidence",
            ),
        ] {
            let Some(t) = target_toml else {
                continue;
            };
            let (scene, method) = target(file, key, &t.scenario, &t.method, &scenes)?;
            let params = match scenes[scene].ranging {
                Ranging::Rangefinders => rangefinder_params(file, &self.rangefinders)?,
                Ranging::Lidar => lidar_range_params.clone(),
            };
            let sensor = model(params, gaussian)
                .check()
                .map_err(|e| model_err(file, key, e))?;
            ablations.push(Ablation {
                kind: AblationKind::RangeModel(Box::new(sensor), label),
                scene,
                method,
            });
        }
        if let Some(t) = &a.lidar_step {
            let (scene, method) = target(
                file,
                "ablations.lidar_step",
                &t.scenario,
                &t.method,
                &scenes,
            )?;
            if scenes[scene].ranging != Ranging::Lidar {
                return Err(SimError::invalid(
                    file,
                    "ablations.lidar_step.scenario",
                    format!("scenario {:?} does not fly the lidar", t.scenario),
                ));
            }
            let step = require_positive(file, "ablations.lidar_step.step_deg", t.step_deg)?;
            let stepped = LidarParams {
                step_deg: step,
                ..lidar_params(file, &self.lidar)?
            };
            let bad_step = |e| model_err(file, "ablations.lidar_step.step_deg", e);
            let sensor = if gaussian_main {
                gaussian_only(stepped.to_range_params().map_err(bad_step)?)
                    .check()
                    .map_err(bad_step)?
            } else {
                stepped.check().map_err(bad_step)?
            };
            if sensor.beams().len() > 20_000 {
                return Err(SimError::invalid(
                    file,
                    "ablations.lidar_step.step_deg",
                    format!("gives {} beams (at most 20000)", sensor.beams().len()),
                ));
            }
            ablations.push(Ablation {
                kind: AblationKind::LidarStep(Box::new(sensor), step),
                scene,
                method,
            });
        }
        if let Some(t) = &a.control_on_estimate {
            let (scene, method) = target(
                file,
                "ablations.control_on_estimate",
                &t.scenario,
                &t.method,
                &scenes,
            )?;
            ablations.push(Ablation {
                kind: AblationKind::ControlOnEstimate,
                scene,
                method,
            });
        }
        if let Some(t) = &a.mgpmf_posterior {
            let key = "ablations.mgpmf_posterior";
            let (scene, method) = target(file, key, &t.scenario, &t.method, &scenes)?;
            if method != Method::Mgpmf {
                return Err(SimError::invalid(
                    file,
                    format!("{key}.method"),
                    format!("must be \"MGPMF\", got {:?}", t.method),
                ));
            }
            let other = match mgpmf.posterior() {
                GridPosterior::Interpolated => GridPosterior::Information,
                GridPosterior::Information => GridPosterior::Interpolated,
            };
            ablations.push(Ablation {
                kind: AblationKind::GridPosterior(other),
                scene,
                method,
            });
        }
        if !ablations.is_empty() && a.runs < 2 {
            return Err(SimError::invalid(
                file,
                "ablations.runs",
                format!("needs at least 2 runs, got {}", a.runs),
            ));
        }
        let methods = select(
            file,
            "urban",
            self.methods.as_deref(),
            &Method::ALL,
            Method::name,
        )?;
        let before = ablations.len();
        ablations.retain(|a: &Ablation| methods.contains(&a.method));
        Ok(Checked {
            file: file.to_string(),
            runs: self.runs,
            ablations_skipped: before - ablations.len(),
            methods,
            base_seed: self.base_seed,
            quad,
            rest_s,
            speeds: (cruise, vertical, hover),
            imu,
            steps,
            gnss: GnssSetup {
                params: gnss_params,
                satellites,
            },
            baro,
            rangefinders,
            lidar,
            filter,
            histogram: (histogram_max, e.histogram_bins),
            table2_tolerance,
            scenes,
            ablation_runs: a.runs.min(self.runs),
            ablations,
            unstated: self.unstated(),
            switch_dwell_s: self.switch.min_dwell_s,
        })
    }
}

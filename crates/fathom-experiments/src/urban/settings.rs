//! The settings of an `urban` scenario that seed 004 does not give (each with the
//! file's value), listed by the report.

use super::scenario::UrbanScenario;

impl UrbanScenario {
    /// The settings the paper does not give, with this file's values.
    pub(super) fn unstated(&self) -> Vec<(String, String)> {
        let v = &self.vehicle;
        let g = &self.gnss;
        let r = &self.rangefinders;
        let m = &self.mgpmf;
        let s = &self.switch;
        let f = &self.filter;
        [
            (
                "switch.min_los_satellites",
                format!(
                    "{} (hysteresis {}, dwell {} s)",
                    s.min_los_satellites, s.hysteresis_satellites, s.min_dwell_s
                ),
            ),
            ("vehicle.rest_s", format!("{} s", v.rest_s)),
            (
                "vehicle.cruise_speed_mps",
                format!("{} m/s", v.cruise_speed_mps),
            ),
            (
                "vehicle.wind_mean_mps / gust_sigma_mps",
                format!("{:?} / {:?} m/s", v.wind_mean_mps, v.gust_sigma_mps),
            ),
            (
                "gnss.pseudorange_sigma_m",
                format!("{} m", g.pseudorange_sigma_m),
            ),
            (
                "gnss.nlos_reception_probability, delay",
                format!(
                    "{}, {} ... {} m",
                    g.nlos_reception_probability, g.nlos_delay_min_m, g.nlos_delay_max_m
                ),
            ),
            ("gnss.rate_hz", format!("{} Hz", g.rate_hz)),
            (
                "rangefinders noise",
                format!(
                    "{} m + {} x range, glass +{} m, max {} m, {} Hz",
                    r.sigma_floor_m, r.sigma_per_m, r.glass_extra_sigma_m, r.max_range_m, r.rate_hz
                ),
            ),
            (
                "mgpmf.grid_points",
                format!(
                    "{:?}, k_sigma {}, {} Hz",
                    m.grid_points, m.k_sigma, m.rate_hz
                ),
            ),
            (
                "mgpmf.lidar_beam_stride",
                format!("{}", m.lidar_beam_stride),
            ),
            (
                "filter.arw_deg_per_sqrt_hr (filter tuning)",
                format!("{}", f.arw_deg_per_sqrt_hr),
            ),
            (
                "filter initial sigmas",
                format!(
                    "{} m, {} m/s, roll/pitch {} deg, yaw {} deg",
                    f.initial_position_sigma_m,
                    f.initial_velocity_sigma_mps,
                    f.initial_roll_pitch_sigma_deg,
                    f.initial_yaw_sigma_deg
                ),
            ),
            (
                "imu turn-on biases",
                format!(
                    "gyro {} deg/h, accel {} mg",
                    self.imu.gyro_turn_on_bias_deg_per_hr, self.imu.accel_turn_on_bias_mg
                ),
            ),
            (
                "baro.height_noise_sigma_m",
                format!("{} m", self.baro.height_noise_sigma_m),
            ),
            (
                "evaluation.table2_tolerance",
                format!("{}", self.evaluation.table2_tolerance),
            ),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }
}

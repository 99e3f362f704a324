//! Settings of the quadrotor truth (vehicle, controller gains, wind, flight clock,
//! path) as plain `Params` structs in SI units, each validated into a checked type;
//! every error names the offending field (`vehicle.mass_kg`,
//! `path.waypoints[2].hover_time_s`, ...). The paper (seed 004) gives none of these
//! numbers: the defaults describe a 1.6 kg, 450 mm-class quadrotor and are settings.

use fathom_core::units::STANDARD_GRAVITY;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::TrajError;

fn invalid(field: impl Into<String>, reason: impl Into<String>) -> TrajError {
    TrajError::InvalidParameter {
        field: field.into(),
        reason: reason.into(),
    }
}

fn finite(field: &str, v: f64) -> Result<f64, TrajError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(invalid(field, format!("must be finite, got {v}")))
    }
}

fn positive(field: &str, v: f64) -> Result<f64, TrajError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(field, format!("must be finite and > 0, got {v}")))
    }
}

fn non_negative(field: &str, v: f64) -> Result<f64, TrajError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(invalid(field, format!("must be finite and >= 0, got {v}")))
    }
}

fn finite3(field: &str, v: &Vector3<f64>) -> Result<Vector3<f64>, TrajError> {
    for (i, x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(invalid(
                format!("{field}[{i}]"),
                format!("must be finite, got {x}"),
            ));
        }
    }
    Ok(*v)
}

fn positive3(field: &str, v: &Vector3<f64>) -> Result<Vector3<f64>, TrajError> {
    for (i, &x) in v.iter().enumerate() {
        positive(&format!("{field}[{i}]"), x)?;
    }
    Ok(*v)
}

fn non_negative3(field: &str, v: &Vector3<f64>) -> Result<Vector3<f64>, TrajError> {
    for (i, &x) in v.iter().enumerate() {
        non_negative(&format!("{field}[{i}]"), x)?;
    }
    Ok(*v)
}

/// Rigid body, rotors and air of the quadrotor (SI units). Validate with
/// [`VehicleParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleParams {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertia tensor about the centre of mass in body axes, kg m^2 (symmetric
    /// positive definite).
    pub inertia_kg_m2: Matrix3<f64>,
    /// Lever arm `l` of eq. (21): distance of every rotor from the body's x axis (roll)
    /// and y axis (pitch), m. For an X frame with arm length `a`, `l = a / sqrt(2)`.
    pub arm_length_m: f64,
    /// Yaw-moment coefficient `kappa` of eq. (21): rotor drag torque per newton of
    /// thrust, m.
    pub yaw_moment_coefficient_m: f64,
    /// Smallest thrust of one rotor (idle), N.
    pub thrust_min_n: f64,
    /// Largest thrust of one rotor, N (must exceed the hover thrust `m g / 4`).
    pub thrust_max_n: f64,
    /// Time constant of the first-order motor lag `dT/dt = (T_cmd - T) / tau`, s (0 =
    /// thrust follows the command instantly).
    pub motor_time_constant_s: f64,
    /// Linear drag per body axis, `F_drag^b = -D C_n^b (v - w)`, N/(m/s).
    pub drag_n_per_mps: Vector3<f64>,
    /// Gravity, m/s^2 (constant, down; the reduced mechanization uses the same value).
    pub gravity_mps2: f64,
}

impl Default for VehicleParams {
    /// 1.6 kg, `J = diag(0.03, 0.03, 0.05)` kg m^2, `l = 0.16` m (0.225 m arms in an X),
    /// `kappa = 0.016` m, thrust 0..7.85 N per rotor (thrust-to-weight 2), motor lag
    /// 0.03 s, drag (0.25, 0.25, 0.40) N/(m/s), standard gravity.
    fn default() -> Self {
        Self {
            mass_kg: 1.6,
            inertia_kg_m2: Matrix3::from_diagonal(&Vector3::new(0.03, 0.03, 0.05)),
            arm_length_m: 0.16,
            yaw_moment_coefficient_m: 0.016,
            thrust_min_n: 0.0,
            thrust_max_n: 7.85,
            motor_time_constant_s: 0.03,
            drag_n_per_mps: Vector3::new(0.25, 0.25, 0.40),
            gravity_mps2: STANDARD_GRAVITY,
        }
    }
}

impl VehicleParams {
    /// Validates the vehicle.
    ///
    /// # Errors
    /// [`TrajError::InvalidParameter`] naming the field: a non-positive or non-finite
    /// mass, arm, `kappa` or gravity; an inertia that is not finite, not symmetric or
    /// singular / indefinite (smallest eigenvalue not above 1e-9 times the largest); a
    /// negative time constant, drag or minimum thrust; a minimum thrust at or above
    /// the hover thrust or a maximum thrust at or below it.
    pub fn check(&self) -> Result<Vehicle, TrajError> {
        let p = self;
        let mass = positive("vehicle.mass_kg", p.mass_kg)?;
        let gravity = positive("vehicle.gravity_mps2", p.gravity_mps2)?;
        positive("vehicle.arm_length_m", p.arm_length_m)?;
        positive(
            "vehicle.yaw_moment_coefficient_m",
            p.yaw_moment_coefficient_m,
        )?;
        non_negative("vehicle.motor_time_constant_s", p.motor_time_constant_s)?;
        non_negative3("vehicle.drag_n_per_mps", &p.drag_n_per_mps)?;
        let j = &p.inertia_kg_m2;
        for (i, x) in j.iter().enumerate() {
            if !x.is_finite() {
                return Err(invalid(
                    "vehicle.inertia_kg_m2",
                    format!("entry {i} is not finite ({x})"),
                ));
            }
        }
        let scale = j.amax();
        if (j - j.transpose()).amax() > 1e-12 * scale {
            return Err(invalid("vehicle.inertia_kg_m2", "must be symmetric"));
        }
        let eig = SymmetricEigen::new(*j).eigenvalues;
        if !(eig.min() > 1e-9 * eig.max() && eig.max() > 0.0) {
            return Err(invalid(
                "vehicle.inertia_kg_m2",
                format!(
                    "must be positive definite (eigenvalues {:.3e}, {:.3e}, {:.3e}: singular or indefinite)",
                    eig[0], eig[1], eig[2]
                ),
            ));
        }
        let inertia_inv = j
            .try_inverse()
            .ok_or_else(|| invalid("vehicle.inertia_kg_m2", "is singular"))?;
        let hover = mass * gravity / 4.0;
        let t_min = non_negative("vehicle.thrust_min_n", p.thrust_min_n)?;
        let t_max = finite("vehicle.thrust_max_n", p.thrust_max_n)?;
        if t_max <= hover {
            return Err(invalid(
                "vehicle.thrust_max_n",
                format!("{t_max} N is not above the hover thrust m g / 4 = {hover:.4} N"),
            ));
        }
        if t_min >= hover {
            return Err(invalid(
                "vehicle.thrust_min_n",
                format!("{t_min} N is not below the hover thrust m g / 4 = {hover:.4} N"),
            ));
        }
        Ok(Vehicle {
            params: *p,
            inertia_inv,
        })
    }
}

/// A checked [`VehicleParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vehicle {
    params: VehicleParams,
    inertia_inv: Matrix3<f64>,
}

impl Vehicle {
    /// The validated parameters.
    pub fn params(&self) -> &VehicleParams {
        &self.params
    }
    /// Mass, kg.
    pub fn mass(&self) -> f64 {
        self.params.mass_kg
    }
    /// Inertia tensor, kg m^2.
    pub fn inertia(&self) -> &Matrix3<f64> {
        &self.params.inertia_kg_m2
    }
    /// Inverse inertia tensor, 1/(kg m^2).
    pub fn inertia_inv(&self) -> &Matrix3<f64> {
        &self.inertia_inv
    }
    /// Lever arm `l` of eq. (21), m.
    pub fn arm_length(&self) -> f64 {
        self.params.arm_length_m
    }
    /// Yaw-moment coefficient `kappa` of eq. (21), m.
    pub fn kappa(&self) -> f64 {
        self.params.yaw_moment_coefficient_m
    }
    /// Minimum rotor thrust, N.
    pub fn thrust_min(&self) -> f64 {
        self.params.thrust_min_n
    }
    /// Maximum rotor thrust, N.
    pub fn thrust_max(&self) -> f64 {
        self.params.thrust_max_n
    }
    /// Motor time constant, s.
    pub fn motor_time_constant(&self) -> f64 {
        self.params.motor_time_constant_s
    }
    /// Linear body drag, N/(m/s).
    pub fn drag(&self) -> &Vector3<f64> {
        &self.params.drag_n_per_mps
    }
    /// Gravity, m/s^2.
    pub fn gravity(&self) -> f64 {
        self.params.gravity_mps2
    }
    /// Gravity vector in NED, `[0, 0, g]`.
    pub fn gravity_in_nav(&self) -> Vector3<f64> {
        Vector3::new(0.0, 0.0, self.params.gravity_mps2)
    }
    /// Thrust of each rotor in hover, `m g / 4`, N.
    pub fn hover_thrust_per_rotor(&self) -> f64 {
        self.params.mass_kg * self.params.gravity_mps2 / 4.0
    }
}

/// Gains and limits of the cascaded controller (per axis: north/east/down for the
/// translational loops, body x/y/z for the rotational ones). Validate with
/// [`ControllerParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerParams {
    /// Position gain `v_cmd = K_p (p_ref - p)`, 1/s.
    pub position_gain: Vector3<f64>,
    /// Velocity gain `a_cmd = K_v (v_cmd - v) + integral`, 1/s.
    pub velocity_gain: Vector3<f64>,
    /// Velocity-error integral gain, 1/s^2 (removes the steady error of drag and wind).
    pub velocity_integral_gain: Vector3<f64>,
    /// Bound on each component of the integral term, m/s^2 (anti-windup).
    pub velocity_integral_limit_mps2: f64,
    /// Attitude gain: body-rate command per rad of attitude error, 1/s.
    pub attitude_gain: Vector3<f64>,
    /// Body-rate gain: angular acceleration per rad/s of rate error, 1/s.
    pub rate_gain: Vector3<f64>,
    /// Largest tilt of the thrust vector from vertical, rad.
    pub max_tilt_rad: f64,
    /// Largest commanded body rates, rad/s.
    pub max_rate_rad_s: Vector3<f64>,
    /// Largest commanded horizontal speed, m/s.
    pub max_horizontal_speed_mps: f64,
    /// Largest commanded vertical speed, m/s.
    pub max_vertical_speed_mps: f64,
}

impl Default for ControllerParams {
    /// Position 0.6/0.6/0.8 1/s, velocity 2.4/2.4/3.0 1/s, integral 0.3/0.3/0.5 1/s^2
    /// (limit 2 m/s^2); attitude 6/6/2.5 1/s, rate 24/24/10 1/s (critically damped
    /// attitude loops at 12 and 5 rad/s); tilt 30 deg, rates 200/200/45 deg/s; speeds
    /// 6 m/s horizontal, 2 m/s vertical.
    fn default() -> Self {
        Self {
            position_gain: Vector3::new(0.6, 0.6, 0.8),
            velocity_gain: Vector3::new(2.4, 2.4, 3.0),
            velocity_integral_gain: Vector3::new(0.3, 0.3, 0.5),
            velocity_integral_limit_mps2: 2.0,
            attitude_gain: Vector3::new(6.0, 6.0, 2.5),
            rate_gain: Vector3::new(24.0, 24.0, 10.0),
            max_tilt_rad: 30f64.to_radians(),
            max_rate_rad_s: Vector3::new(
                200f64.to_radians(),
                200f64.to_radians(),
                45f64.to_radians(),
            ),
            max_horizontal_speed_mps: 6.0,
            max_vertical_speed_mps: 2.0,
        }
    }
}

impl ControllerParams {
    /// Validates the gains.
    ///
    /// # Errors
    /// [`TrajError::InvalidParameter`] naming the field: non-positive or non-finite
    /// gains (the integral gain may be 0), a tilt outside (0, 80] deg, non-positive
    /// rate or speed limits.
    pub fn check(&self) -> Result<ControllerGains, TrajError> {
        let p = self;
        positive3("controller.position_gain", &p.position_gain)?;
        positive3("controller.velocity_gain", &p.velocity_gain)?;
        non_negative3(
            "controller.velocity_integral_gain",
            &p.velocity_integral_gain,
        )?;
        non_negative(
            "controller.velocity_integral_limit_mps2",
            p.velocity_integral_limit_mps2,
        )?;
        positive3("controller.attitude_gain", &p.attitude_gain)?;
        positive3("controller.rate_gain", &p.rate_gain)?;
        positive3("controller.max_rate_rad_s", &p.max_rate_rad_s)?;
        positive(
            "controller.max_horizontal_speed_mps",
            p.max_horizontal_speed_mps,
        )?;
        positive(
            "controller.max_vertical_speed_mps",
            p.max_vertical_speed_mps,
        )?;
        let tilt = positive("controller.max_tilt_rad", p.max_tilt_rad)?;
        if tilt > 80f64.to_radians() {
            return Err(invalid(
                "controller.max_tilt_rad",
                format!("{tilt} rad is above 80 deg"),
            ));
        }
        Ok(ControllerGains(*p))
    }
}

/// Checked [`ControllerParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerGains(ControllerParams);

impl ControllerGains {
    /// The validated gains.
    pub fn params(&self) -> &ControllerParams {
        &self.0
    }
}

/// Wind: a constant mean plus gusts, each NED axis an independent first-order
/// Gauss-Markov process (a Dryden-like low-pass turbulence), held over a control
/// step. Validate with [`WindParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WindParams {
    /// Mean wind velocity in NED, m/s (the air moves this way).
    pub mean_in_nav: Vector3<f64>,
    /// Standard deviation of the gust velocity per axis, m/s (0 = no gusts, and no
    /// random draws).
    pub gust_sigma_mps: Vector3<f64>,
    /// Correlation time of the gusts, s.
    pub gust_correlation_time_s: f64,
}

impl WindParams {
    /// Still air.
    pub fn calm() -> Self {
        Self {
            gust_correlation_time_s: 2.0,
            ..Self::default()
        }
    }

    /// Validates the wind.
    ///
    /// # Errors
    /// [`TrajError::InvalidParameter`] naming the field for a non-finite mean, a
    /// negative or non-finite gust sigma, or (with gusts) a non-positive correlation
    /// time.
    pub fn check(&self) -> Result<Wind, TrajError> {
        finite3("wind.mean_in_nav", &self.mean_in_nav)?;
        non_negative3("wind.gust_sigma_mps", &self.gust_sigma_mps)?;
        if self.gust_sigma_mps.amax() > 0.0 {
            positive("wind.gust_correlation_time_s", self.gust_correlation_time_s)?;
        }
        Ok(Wind(*self))
    }
}

/// Checked [`WindParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wind(WindParams);

impl Wind {
    /// The validated wind.
    pub fn params(&self) -> &WindParams {
        &self.0
    }
    /// Whether gusts are simulated (and random numbers drawn).
    pub fn has_gusts(&self) -> bool {
        self.0.gust_sigma_mps.amax() > 0.0
    }
}

/// The flight clock. Validate with [`FlightParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightParams {
    /// Controller rate, Hz (commands are held between control instants).
    pub control_rate_hz: f64,
    /// RK4 steps per control period (physics rate = control rate x substeps; must be
    /// >= 200 Hz).
    pub physics_substeps: usize,
    /// The vehicle rests at the first waypoint for this long before the controller
    /// starts (held still, as on the ground; the IMU's gyro-bias calibration), s.
    pub rest_duration_s: f64,
    /// A flight not done by then is an error (path unreachable), s.
    pub max_duration_s: f64,
}

impl Default for FlightParams {
    /// 200 Hz control, 2 substeps (RK4 at 400 Hz), 10 s rest, 3600 s at most.
    fn default() -> Self {
        Self {
            control_rate_hz: 200.0,
            physics_substeps: 2,
            rest_duration_s: 10.0,
            max_duration_s: 3600.0,
        }
    }
}

impl FlightParams {
    /// Validates the clock.
    ///
    /// # Errors
    /// [`TrajError::InvalidParameter`] naming the field: non-positive rate, zero
    /// substeps or more than 1000, a physics rate below 200 Hz, a negative rest, a
    /// maximum duration not above the rest or above 1e6 s.
    pub fn check(&self) -> Result<FlightSettings, TrajError> {
        let rate = positive("flight.control_rate_hz", self.control_rate_hz)?;
        if !(1..=1000).contains(&self.physics_substeps) {
            return Err(invalid(
                "flight.physics_substeps",
                format!("must be in 1..=1000, got {}", self.physics_substeps),
            ));
        }
        let physics = rate * self.physics_substeps as f64;
        if physics < 200.0 {
            return Err(invalid(
                "flight.physics_substeps",
                format!("physics rate {physics} Hz is below 200 Hz"),
            ));
        }
        let rest = non_negative("flight.rest_duration_s", self.rest_duration_s)?;
        let max = positive("flight.max_duration_s", self.max_duration_s)?;
        if max <= rest || max > 1e6 {
            return Err(invalid(
                "flight.max_duration_s",
                format!("{max} s must be above the rest ({rest} s) and at most 1e6 s"),
            ));
        }
        Ok(FlightSettings(*self))
    }
}

/// Checked [`FlightParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightSettings(FlightParams);

impl FlightSettings {
    /// The validated clock.
    pub fn params(&self) -> &FlightParams {
        &self.0
    }
    /// Control period, s.
    pub fn control_dt(&self) -> f64 {
        1.0 / self.0.control_rate_hz
    }
    /// RK4 step, s.
    pub fn physics_dt(&self) -> f64 {
        self.control_dt() / self.0.physics_substeps as f64
    }
}

/// Everything about the vehicle and its flight except the path.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct QuadrotorParams {
    /// Rigid body, rotors, air.
    pub vehicle: VehicleParams,
    /// Controller gains and limits.
    pub controller: ControllerParams,
    /// Wind.
    pub wind: WindParams,
    /// Flight clock.
    pub flight: FlightParams,
}

impl QuadrotorParams {
    /// Validates all parts.
    ///
    /// # Errors
    /// The first part's [`TrajError::InvalidParameter`], naming the field.
    pub fn check(&self) -> Result<Quadrotor, TrajError> {
        Ok(Quadrotor {
            vehicle: self.vehicle.check()?,
            gains: self.controller.check()?,
            wind: self.wind.check()?,
            flight: self.flight.check()?,
        })
    }
}

/// Checked [`QuadrotorParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadrotor {
    /// The vehicle.
    pub vehicle: Vehicle,
    /// The controller gains.
    pub gains: ControllerGains,
    /// The wind.
    pub wind: Wind,
    /// The flight clock.
    pub flight: FlightSettings,
}

/// One waypoint of a path: fly there, hover, optionally turn in place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waypoint {
    /// Position in NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Time to hover after arriving, s; with a yaw command the vehicle also stays
    /// until the turn in place is done (the two run together).
    pub hover_time_s: f64,
    /// Yaw to turn to at this waypoint, rad (`None`: keep the current yaw).
    pub yaw_rad: Option<f64>,
}

impl Waypoint {
    /// A waypoint with hover time and no yaw command.
    pub fn new(pos_in_nav: Vector3<f64>, hover_time_s: f64) -> Self {
        Self {
            pos_in_nav,
            hover_time_s,
            yaw_rad: None,
        }
    }

    /// The same waypoint with a yaw command.
    pub fn with_yaw(self, yaw_rad: f64) -> Self {
        Self {
            yaw_rad: Some(yaw_rad),
            ..self
        }
    }
}

/// A path: waypoints flown in order along straight legs (seed 004, section 3.3).
/// The vehicle starts at rest at the first waypoint. Validate with
/// [`PathParams::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct PathParams {
    /// The waypoints (at least one).
    pub waypoints: Vec<Waypoint>,
    /// Along-leg speed, horizontal part, m/s.
    pub cruise_speed_mps: f64,
    /// Along-leg speed, vertical part (climb / descent), m/s.
    pub vertical_speed_mps: f64,
    /// Acceleration of the along-leg speed profile (ramp up, braking), m/s^2.
    pub along_acceleration_mps2: f64,
    /// Gain of the velocity correction perpendicular to the leg toward it, 1/s.
    pub cross_track_gain: f64,
    /// Distance to a waypoint that counts as arrived, m.
    pub capture_radius_m: f64,
    /// Yaw error below which a turn in place is done, rad.
    pub yaw_tolerance_rad: f64,
}

impl PathParams {
    /// A path through `waypoints` with the default speeds: 3 m/s cruise, 1.5 m/s
    /// vertical, 1 m/s^2 along-leg acceleration, cross-track gain 0.8 1/s, capture
    /// radius 0.3 m, yaw tolerance 1 deg.
    pub fn new(waypoints: Vec<Waypoint>) -> Self {
        Self {
            waypoints,
            cruise_speed_mps: 3.0,
            vertical_speed_mps: 1.5,
            along_acceleration_mps2: 1.0,
            cross_track_gain: 0.8,
            capture_radius_m: 0.3,
            yaw_tolerance_rad: 1f64.to_radians(),
        }
    }

    /// The `buildings` flight of spec D: from the ground at `start`, climb to
    /// `height_m`, fly a square of `side_m` legs (north, east, south, west) at
    /// `cruise_speed_mps`, hovering `hover_s` at each corner; at the second corner
    /// (the far one) turn in place by +90 deg and fly the rest of the square with that
    /// yaw; end hovering above the start.
    pub fn buildings_square(
        start: Vector3<f64>,
        side_m: f64,
        height_m: f64,
        cruise_speed_mps: f64,
        hover_s: f64,
    ) -> Self {
        let up = start - Vector3::new(0.0, 0.0, height_m);
        let corner = |n: f64, e: f64| up + Vector3::new(n, e, 0.0);
        let turn = std::f64::consts::FRAC_PI_2;
        let mut p = Self::new(vec![
            Waypoint::new(start, 0.0).with_yaw(0.0),
            Waypoint::new(up, hover_s),
            Waypoint::new(corner(side_m, 0.0), hover_s),
            Waypoint::new(corner(side_m, side_m), hover_s).with_yaw(turn),
            Waypoint::new(corner(0.0, side_m), hover_s),
            Waypoint::new(up, hover_s),
        ]);
        p.cruise_speed_mps = cruise_speed_mps;
        p
    }

    /// Validates the path.
    ///
    /// # Errors
    /// [`TrajError::InvalidParameter`] naming the field: an empty waypoint list, a
    /// non-finite position or yaw, a negative hover time, non-positive speeds, gain,
    /// acceleration, capture radius or yaw tolerance.
    pub fn check(&self) -> Result<Path, TrajError> {
        if self.waypoints.is_empty() {
            return Err(invalid("path.waypoints", "must not be empty"));
        }
        for (i, w) in self.waypoints.iter().enumerate() {
            finite3(&format!("path.waypoints[{i}].pos_in_nav"), &w.pos_in_nav)?;
            non_negative(&format!("path.waypoints[{i}].hover_time_s"), w.hover_time_s)?;
            if let Some(y) = w.yaw_rad {
                finite(&format!("path.waypoints[{i}].yaw_rad"), y)?;
            }
        }
        positive("path.cruise_speed_mps", self.cruise_speed_mps)?;
        positive("path.vertical_speed_mps", self.vertical_speed_mps)?;
        positive("path.along_acceleration_mps2", self.along_acceleration_mps2)?;
        positive("path.cross_track_gain", self.cross_track_gain)?;
        positive("path.capture_radius_m", self.capture_radius_m)?;
        positive("path.yaw_tolerance_rad", self.yaw_tolerance_rad)?;
        Ok(Path(self.clone()))
    }
}

/// Checked [`PathParams`].
#[derive(Debug, Clone, PartialEq)]
pub struct Path(PathParams);

impl Path {
    /// The validated path.
    pub fn params(&self) -> &PathParams {
        &self.0
    }
    /// The waypoints (never empty).
    pub fn waypoints(&self) -> &[Waypoint] {
        &self.0.waypoints
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field_of(e: TrajError) -> String {
        match e {
            TrajError::InvalidParameter { field, .. } => field,
            other => panic!("unexpected error {other}"),
        }
    }

    /// Acceptance: bad parameters give a clear error naming the field.
    #[test]
    fn bad_parameters_name_the_field() {
        let v = VehicleParams::default();
        let cases: Vec<(VehicleParams, &str)> = vec![
            (VehicleParams { mass_kg: -1.6, ..v }, "vehicle.mass_kg"),
            (
                VehicleParams {
                    mass_kg: f64::NAN,
                    ..v
                },
                "vehicle.mass_kg",
            ),
            (
                VehicleParams {
                    inertia_kg_m2: Matrix3::from_diagonal(&Vector3::new(0.03, 0.03, 0.0)),
                    ..v
                },
                "vehicle.inertia_kg_m2",
            ),
            (
                VehicleParams {
                    inertia_kg_m2: Matrix3::new(0.03, 0.01, 0.0, 0.0, 0.03, 0.0, 0.0, 0.0, 0.05),
                    ..v
                },
                "vehicle.inertia_kg_m2",
            ),
            (
                VehicleParams {
                    inertia_kg_m2: Matrix3::from_element(f64::NAN),
                    ..v
                },
                "vehicle.inertia_kg_m2",
            ),
            (
                VehicleParams {
                    thrust_max_n: 3.9,
                    ..v
                },
                "vehicle.thrust_max_n",
            ),
            (
                VehicleParams {
                    thrust_min_n: 4.0,
                    ..v
                },
                "vehicle.thrust_min_n",
            ),
            (
                VehicleParams {
                    arm_length_m: 0.0,
                    ..v
                },
                "vehicle.arm_length_m",
            ),
            (
                VehicleParams {
                    motor_time_constant_s: -0.1,
                    ..v
                },
                "vehicle.motor_time_constant_s",
            ),
            (
                VehicleParams {
                    drag_n_per_mps: Vector3::new(0.1, -0.1, 0.1),
                    ..v
                },
                "vehicle.drag_n_per_mps[1]",
            ),
        ];
        for (p, field) in cases {
            let e = p.check().unwrap_err();
            assert!(e.to_string().contains(field), "{e}");
            assert_eq!(field_of(e), field);
        }
        let e = VehicleParams {
            thrust_max_n: 3.9,
            ..v
        }
        .check()
        .unwrap_err();
        assert!(e.to_string().contains("hover thrust"), "{e}");

        let e = PathParams::new(vec![]).check().unwrap_err();
        assert_eq!(field_of(e), "path.waypoints");
        let mut path = PathParams::buildings_square(Vector3::zeros(), 100.0, 20.0, 3.0, 5.0);
        path.waypoints[2].pos_in_nav.y = f64::NAN;
        assert_eq!(
            field_of(path.check().unwrap_err()),
            "path.waypoints[2].pos_in_nav[1]"
        );
        let mut path = PathParams::buildings_square(Vector3::zeros(), 100.0, 20.0, 3.0, 5.0);
        path.waypoints[3].hover_time_s = -1.0;
        assert_eq!(
            field_of(path.check().unwrap_err()),
            "path.waypoints[3].hover_time_s"
        );
        path.waypoints[3].hover_time_s = 1.0;
        path.waypoints[1].yaw_rad = Some(f64::INFINITY);
        assert_eq!(
            field_of(path.check().unwrap_err()),
            "path.waypoints[1].yaw_rad"
        );

        let c = ControllerParams::default();
        let e = ControllerParams {
            velocity_gain: Vector3::new(1.0, f64::NAN, 1.0),
            ..c
        }
        .check()
        .unwrap_err();
        assert_eq!(field_of(e), "controller.velocity_gain[1]");
        let e = ControllerParams {
            max_tilt_rad: 1.5,
            ..c
        }
        .check()
        .unwrap_err();
        assert_eq!(field_of(e), "controller.max_tilt_rad");

        let f = FlightParams::default();
        let e = FlightParams {
            control_rate_hz: 50.0,
            physics_substeps: 2,
            ..f
        }
        .check()
        .unwrap_err();
        assert_eq!(field_of(e), "flight.physics_substeps");
        assert!(
            FlightParams {
                rest_duration_s: -1.0,
                ..f
            }
            .check()
            .is_err()
        );
        let e = WindParams {
            gust_sigma_mps: Vector3::new(1.0, 1.0, 0.0),
            gust_correlation_time_s: 0.0,
            ..WindParams::calm()
        }
        .check()
        .unwrap_err();
        assert_eq!(field_of(e), "wind.gust_correlation_time_s");

        // Negative control: the defaults pass.
        assert!(QuadrotorParams::default().check().is_ok());
        assert!(
            PathParams::buildings_square(Vector3::zeros(), 100.0, 20.0, 3.0, 5.0)
                .check()
                .is_ok()
        );
    }

    #[test]
    fn checked_vehicle_accessors() {
        let v = VehicleParams::default().check().unwrap();
        assert_eq!(v.hover_thrust_per_rotor(), 1.6 * STANDARD_GRAVITY / 4.0);
        assert!((v.inertia() * v.inertia_inv() - Matrix3::identity()).amax() < 1e-12);
        let s = FlightParams::default().check().unwrap();
        assert_eq!(s.control_dt(), 0.005);
        assert_eq!(s.physics_dt(), 0.0025);
    }
}

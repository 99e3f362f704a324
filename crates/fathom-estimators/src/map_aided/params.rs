//! The settings of the map-aided estimators as plain `Params` structs (SI units, the
//! defaults stated) and their `check()` into checked types; errors name the field.
//! The estimators take only the checked types.

use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::error::MapAidedError;

/// Largest number of grid points / particles accepted (a bound against absurd
/// settings: 1e6 points x 7 beams is already 7e6 ray casts per update).
pub const MAX_POINTS: usize = 1_000_000;

fn invalid(field: &str, value: f64, expected: &'static str) -> MapAidedError {
    MapAidedError::InvalidParameter {
        field: field.into(),
        value,
        expected,
    }
}

fn non_negative(field: &str, v: f64) -> Result<f64, MapAidedError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(invalid(field, v, "finite and >= 0"))
    }
}

fn positive(field: &str, v: f64) -> Result<f64, MapAidedError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(field, v, "finite and > 0"))
    }
}

fn probability_open(field: &str, p: f64) -> Result<f64, MapAidedError> {
    if p > 0.0 && p < 1.0 {
        Ok(p)
    } else {
        Err(invalid(field, p, "0 < p < 1"))
    }
}

/// The chi-square quantile `chi2_inv(p; dof)` (the gate on a NIS of `dof` dimensions).
pub(crate) fn chi_square_gate(p: f64, dof: usize) -> f64 {
    // dof >= 1 and 0 < p < 1 are checked by every caller
    ChiSquared::new(dof as f64)
        .map(|c| c.inverse_cdf(p))
        .unwrap_or(f64::INFINITY)
}

/// IMU noise of the 12-state error model (eq. 2-5): white accelerometer and gyro
/// noise (the paper's `w_acc`, `w_gyro`) and, beyond the paper's eq. (3) (where the
/// bias is constant), an optional random walk of the accelerometer bias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ins12Params {
    /// Velocity random walk (accelerometer white noise), m/s/sqrt(s). Default: the
    /// ADIS16448 upper bound of Table 1, 0.14 m/s/sqrt(h) = 2.33e-3 m/s/sqrt(s).
    pub velocity_random_walk_mps_per_sqrt_s: f64,
    /// Angle random walk (gyro white noise), rad/sqrt(s). Default: 0.83 deg/sqrt(h)
    /// = 2.41e-4 rad/sqrt(s).
    pub angle_random_walk_rad_per_sqrt_s: f64,
    /// Accelerometer-bias random walk, m/s^2/sqrt(s). Default 0 (the paper's
    /// constant bias).
    pub accel_bias_random_walk_mps2_per_sqrt_s: f64,
}

impl Default for Ins12Params {
    fn default() -> Self {
        Self {
            velocity_random_walk_mps_per_sqrt_s: 0.14 / 60.0,
            angle_random_walk_rad_per_sqrt_s: 0.83f64.to_radians() / 60.0,
            accel_bias_random_walk_mps2_per_sqrt_s: 0.0,
        }
    }
}

/// Checked [`Ins12Params`] as power spectral densities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuNoise {
    /// Accelerometer white-noise PSD, (m/s^2)^2 s.
    pub accel_psd: f64,
    /// Gyro white-noise PSD, rad^2/s.
    pub gyro_psd: f64,
    /// Accelerometer-bias random-walk PSD, (m/s^2)^2 / s.
    pub accel_bias_psd: f64,
}

impl Ins12Params {
    /// Checks the figures (finite, `>= 0`) and squares them into PSDs.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<ImuNoise, MapAidedError> {
        let vrw = non_negative(
            "ins12.velocity_random_walk_mps_per_sqrt_s",
            self.velocity_random_walk_mps_per_sqrt_s,
        )?;
        let arw = non_negative(
            "ins12.angle_random_walk_rad_per_sqrt_s",
            self.angle_random_walk_rad_per_sqrt_s,
        )?;
        let brw = non_negative(
            "ins12.accel_bias_random_walk_mps2_per_sqrt_s",
            self.accel_bias_random_walk_mps2_per_sqrt_s,
        )?;
        Ok(ImuNoise {
            accel_psd: vrw * vrw,
            gyro_psd: arw * arw,
            accel_bias_psd: brw * brw,
        })
    }
}

/// GPS/INS aiding settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsParams {
    /// Probability that a consistent fix passes the chi-square gate (3 dof for a
    /// position fix, 6 with velocity). Default 0.999.
    pub gate_probability: f64,
    /// After this many fixes in a row rejected by the gate, the next fix re-acquires
    /// the position ([`super::GpsReacquire`]: the covariance is widened by the error
    /// the fix shows, then the fix is applied). 0 (the default, the paper's filter):
    /// never; a diverged filter then rejects every fix for ever.
    pub reacquire_after_rejections: usize,
}

impl Default for GpsParams {
    fn default() -> Self {
        Self {
            gate_probability: 0.999,
            reacquire_after_rejections: 0,
        }
    }
}

/// Checked [`GpsParams`]: the NIS thresholds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsAiding {
    pub(crate) gate_position: f64,
    pub(crate) gate_position_velocity: f64,
    pub(crate) reacquire_after: usize,
}

impl GpsAiding {
    /// NIS threshold of a position fix (3 dof).
    pub fn gate_position(&self) -> f64 {
        self.gate_position
    }

    /// NIS threshold of a position + velocity fix (6 dof).
    pub fn gate_position_velocity(&self) -> f64 {
        self.gate_position_velocity
    }

    /// Rejected fixes in a row after which the next fix re-acquires (0: never).
    pub fn reacquire_after(&self) -> usize {
        self.reacquire_after
    }
}

impl GpsParams {
    /// Checks the gate probability (`0 < p < 1`).
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] naming `gps.gate_probability`.
    pub fn check(&self) -> Result<GpsAiding, MapAidedError> {
        let p = probability_open("gps.gate_probability", self.gate_probability)?;
        Ok(GpsAiding {
            gate_position: chi_square_gate(p, 3),
            gate_position_velocity: chi_square_gate(p, 6),
            reacquire_after: self.reacquire_after_rejections,
        })
    }
}

/// How predicted ranges are formed and screened (GREKF, and the linear step of the
/// MGPMF and the particle filter).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeParams {
    /// Largest range of the sensor, m: a predicted ray longer than this is no hit.
    /// Default 60 (UST-20LX).
    pub max_range_m: f64,
    /// Largest incidence angle of a predicted hit whose row is used, deg (the row
    /// `o / (o . C d)` grows without bound at grazing incidence). Default 80.
    pub max_incidence_deg: f64,
    /// Probability that a consistent beam passes the per-beam chi-square gate (1 dof).
    /// Default 0.999.
    pub gate_probability: f64,
}

impl Default for RangeParams {
    fn default() -> Self {
        Self {
            max_range_m: 60.0,
            max_incidence_deg: 80.0,
            gate_probability: 0.999,
        }
    }
}

/// Checked [`RangeParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeSettings {
    pub(crate) max_range: f64,
    /// `cos(max incidence)`: a hit is used when `-o . u >= min_cos_incidence`.
    pub(crate) min_cos_incidence: f64,
    /// Per-beam NIS threshold (1 dof).
    pub(crate) gate: f64,
}

impl RangeSettings {
    /// Largest range, m.
    pub fn max_range(&self) -> f64 {
        self.max_range
    }

    /// Per-beam NIS threshold.
    pub fn gate(&self) -> f64 {
        self.gate
    }
}

impl RangeParams {
    /// Checks the settings (`prefix` names the owner in errors, e.g. `grekf`).
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] naming the field.
    pub fn check_as(&self, prefix: &str) -> Result<RangeSettings, MapAidedError> {
        let max_range = positive(&format!("{prefix}.max_range_m"), self.max_range_m)?;
        let inc = self.max_incidence_deg;
        if !(inc > 0.0 && inc < 90.0) {
            return Err(invalid(
                &format!("{prefix}.max_incidence_deg"),
                inc,
                "0 < deg < 90",
            ));
        }
        let p = probability_open(&format!("{prefix}.gate_probability"), self.gate_probability)?;
        Ok(RangeSettings {
            max_range,
            min_cos_incidence: inc.to_radians().cos(),
            gate: chi_square_gate(p, 1),
        })
    }

    /// [`RangeParams::check_as`] with the prefix `range`.
    ///
    /// # Errors
    /// As [`RangeParams::check_as`].
    pub fn check(&self) -> Result<RangeSettings, MapAidedError> {
        self.check_as("range")
    }
}

/// The GREKF's robustness beyond the paper's single stacked update: an iterated
/// update (Gauss-Newton on the ray casts), an inflation of the range noise for the
/// errors the beams share (the map, the attitude, one pier seen by many beams), and
/// the lost-lock rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrekfParams {
    /// Ray casting, incidence limit and per-beam gate.
    pub range: RangeParams,
    /// Iterations of the iterated EKF: the rays are cast again from the updated pose
    /// and the update relinearized there (1: the paper's single update). Default 1.
    pub iterations: usize,
    /// Factor on every beam's range σ in the update and in the gate (1: the beams
    /// independent at their nominal σ). Default 1.
    pub sigma_inflation: f64,
    /// Consecutive updates in which every beam was gated after which the filter has
    /// lost lock: the position, velocity and attitude covariance is multiplied by
    /// `relock_inflation` (widening the gate), again after every further run of as
    /// many, until an update uses beams again (re-lock). 0: never. Default 5.
    pub lock_loss_updates: usize,
    /// The covariance factor of a lost lock (> 1). Default 4.
    pub relock_inflation: f64,
    /// The linearity check ([`super::grekf`] docs): each beam is cast again from the
    /// prior pose shifted by ± this many standard deviations along north, east and
    /// yaw; a beam whose range is not linear over that span (a second difference
    /// beyond 3 of its σ, or a ray that misses) is left out. 0: no check (the
    /// paper's update). Default 0.
    pub linearity_sigmas: f64,
}

impl Default for GrekfParams {
    fn default() -> Self {
        Self {
            range: RangeParams::default(),
            iterations: 1,
            sigma_inflation: 1.0,
            lock_loss_updates: 5,
            relock_inflation: 4.0,
            linearity_sigmas: 0.0,
        }
    }
}

/// Checked [`GrekfParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrekfSettings {
    pub(crate) range: RangeSettings,
    pub(crate) iterations: usize,
    pub(crate) sigma_inflation: f64,
    pub(crate) lock_loss_updates: usize,
    pub(crate) relock_inflation: f64,
    pub(crate) linearity_sigmas: f64,
}

impl GrekfSettings {
    /// The range settings.
    pub fn range(&self) -> &RangeSettings {
        &self.range
    }

    /// Iterations of the iterated update.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// The range σ factor.
    pub fn sigma_inflation(&self) -> f64 {
        self.sigma_inflation
    }

    /// Fully gated updates before a lost lock (0: never).
    pub fn lock_loss_updates(&self) -> usize {
        self.lock_loss_updates
    }

    /// The covariance factor of a lost lock.
    pub fn relock_inflation(&self) -> f64 {
        self.relock_inflation
    }

    /// The span of the linearity check in standard deviations (0: none).
    pub fn linearity_sigmas(&self) -> f64 {
        self.linearity_sigmas
    }
}

impl From<RangeSettings> for GrekfSettings {
    /// The paper's GREKF: one update, nominal σ, no lost-lock rule.
    fn from(range: RangeSettings) -> Self {
        Self {
            range,
            iterations: 1,
            sigma_inflation: 1.0,
            lock_loss_updates: 0,
            relock_inflation: 4.0,
            linearity_sigmas: 0.0,
        }
    }
}

impl GrekfParams {
    /// Checks the settings: iterations 1 ... 20, σ factor ≥ 1 and finite, lost-lock
    /// inflation > 1 and finite, the range settings (prefix `grekf.range`).
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<GrekfSettings, MapAidedError> {
        if !(1..=20).contains(&self.iterations) {
            return Err(invalid(
                "grekf.iterations",
                self.iterations as f64,
                "1 ... 20",
            ));
        }
        let k = self.sigma_inflation;
        if !(k.is_finite() && k >= 1.0) {
            return Err(invalid("grekf.sigma_inflation", k, "finite and >= 1"));
        }
        let f = self.relock_inflation;
        if !(f.is_finite() && f > 1.0) {
            return Err(invalid("grekf.relock_inflation", f, "finite and > 1"));
        }
        let l = self.linearity_sigmas;
        if !(l.is_finite() && (0.0..=10.0).contains(&l)) {
            return Err(invalid("grekf.linearity_sigmas", l, "0 ... 10"));
        }
        Ok(GrekfSettings {
            range: self.range.check_as("grekf.range")?,
            iterations: self.iterations,
            sigma_inflation: k,
            lock_loss_updates: self.lock_loss_updates,
            relock_inflation: f,
            linearity_sigmas: l,
        })
    }
}

/// The robust range likelihood of the grid / particle weights:
/// `(1 - eps) N(r - r_hat; 0, s^2) + eps / max_range`, the second term for returns the
/// map does not explain (glass, clutter, people).
fn check_outlier(field: &str, eps: f64) -> Result<f64, MapAidedError> {
    if eps.is_finite() && (0.0..1.0).contains(&eps) {
        Ok(eps)
    } else {
        Err(invalid(field, eps, "0 <= eps < 1"))
    }
}

/// MGPMF settings (section 2.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MgpmfParams {
    /// Grid points along north, east and yaw error. Default 41 x 41 x 9.
    pub grid_points: [usize; 3],
    /// Half-width of the grid in predicted standard deviations (`mean +- k sigma` per
    /// axis). Default 3.
    pub k_sigma: f64,
    /// Outlier probability `eps` of the robust likelihood. Default 0.05.
    pub outlier_probability: f64,
    /// How the grid's moments become the posterior covariance of `n`. Default
    /// [`GridPosterior::Interpolated`] (the paper's).
    pub posterior: GridPosterior,
    /// Ray casting and the linear step's gate.
    pub range: RangeParams,
}

/// How the MGPMF turns the weighted grid into the posterior covariance of the
/// nonlinear states.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GridPosterior {
    /// The paper's eq. (18) with its linear interpolation: the weighted covariance
    /// of the points plus each point's hat-function variance `spacing^2 / 6`. On an
    /// axis the ranges do not inform, this is broader than the prior by the
    /// discretization (e.g. 1.5x the prior variance per update with 3 points over
    /// +-3 sigma), so repeated updates can inflate `P` without bound.
    #[default]
    Interpolated,
    /// The same grid moments used only for the information the ranges add: the
    /// posterior information is `P_nn^-1 + (C_post^-1 - C_prior^-1)`, where `C_post`
    /// and `C_prior` are the interpolated grid covariances with and without the
    /// likelihood, so the discretization cancels and a flat likelihood returns the
    /// prior exactly. Where that information is not positive definite (a likelihood
    /// that spreads the weight beyond the prior) it falls back to `C_post`.
    Information,
}

impl Default for MgpmfParams {
    fn default() -> Self {
        Self {
            grid_points: [41, 41, 9],
            k_sigma: 3.0,
            outlier_probability: 0.05,
            posterior: GridPosterior::Interpolated,
            range: RangeParams::default(),
        }
    }
}

/// Checked [`MgpmfParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MgpmfSettings {
    pub(crate) grid_points: [usize; 3],
    pub(crate) k_sigma: f64,
    pub(crate) outlier_probability: f64,
    pub(crate) posterior: GridPosterior,
    pub(crate) range: RangeSettings,
}

impl MgpmfSettings {
    /// Grid points per axis (north, east, yaw).
    pub fn grid_points(&self) -> [usize; 3] {
        self.grid_points
    }

    /// Total number of grid points.
    pub fn num_points(&self) -> usize {
        self.grid_points.iter().product()
    }

    /// The range settings.
    pub fn range(&self) -> &RangeSettings {
        &self.range
    }

    /// How the grid becomes the posterior covariance.
    pub fn posterior(&self) -> GridPosterior {
        self.posterior
    }

    /// The same settings with another posterior covariance (it has no constraint).
    pub fn with_posterior(self, posterior: GridPosterior) -> Self {
        Self { posterior, ..self }
    }
}

impl MgpmfParams {
    /// Checks the settings: every axis 2..=1000 points, at most [`MAX_POINTS`] in
    /// all, `0 < k <= 10`, `0 <= eps < 1`, the range settings.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] naming the field (e.g.
    /// `mgpmf.grid_points[2]`, `mgpmf.k_sigma`).
    pub fn check(&self) -> Result<MgpmfSettings, MapAidedError> {
        for (i, &n) in self.grid_points.iter().enumerate() {
            if !(2..=1000).contains(&n) {
                return Err(invalid(
                    &format!("mgpmf.grid_points[{i}]"),
                    n as f64,
                    "2..=1000 points",
                ));
            }
        }
        let total: usize = self.grid_points.iter().product();
        if total > MAX_POINTS {
            return Err(invalid(
                "mgpmf.grid_points",
                total as f64,
                "at most 1e6 points in all",
            ));
        }
        let k = self.k_sigma;
        if !(k > 0.0 && k <= 10.0) {
            return Err(invalid("mgpmf.k_sigma", k, "0 < k <= 10"));
        }
        Ok(MgpmfSettings {
            grid_points: self.grid_points,
            k_sigma: k,
            posterior: self.posterior,
            outlier_probability: check_outlier(
                "mgpmf.outlier_probability",
                self.outlier_probability,
            )?,
            range: self.range.check_as("mgpmf.range")?,
        })
    }
}

/// Particle-filter settings (the reference of the MGPMF at equal ray budget).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleParams {
    /// Number of particles. Default 41 x 41 x 9 = 15129 (the default grid's rays).
    pub particles: usize,
    /// Roughening constant `K` of Gordon et al. (1993): after resampling each
    /// particle is jittered with std `K E N^(-1/3)` per axis, `E` the spread of the
    /// particles on that axis. Default 0.2.
    pub roughening: f64,
    /// Outlier probability `eps` of the robust likelihood (as the MGPMF). Default 0.05.
    pub outlier_probability: f64,
    /// Ray casting and the linear step's gate.
    pub range: RangeParams,
    /// The jitter after resampling. Default [`ParticleKernel::Roughening`].
    pub kernel: ParticleKernel,
}

/// The jitter of the particles after resampling ([`super::particle`] docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ParticleKernel {
    /// Gordon et al. (1993): std `K E_j N^(-1/3)` per axis, `E_j` the spread of the
    /// prior particles, `K` = [`ParticleParams::roughening`].
    #[default]
    Roughening,
    /// The regularized particle filter (Musso, Oudjane & Le Gland 2001): a Gaussian
    /// kernel with covariance `h_opt^2 Sigma`, `Sigma` the weighted posterior
    /// covariance plus the particle set's resolution `(E_j N^(-1/3))^2 / 12` per
    /// axis, `h_opt = (4 / (N (d + 2)))^(1 / (d + 4))`, `d = 3`
    /// (`roughening` unused).
    Regularized,
}

impl Default for ParticleParams {
    fn default() -> Self {
        Self {
            particles: 41 * 41 * 9,
            kernel: ParticleKernel::Roughening,
            roughening: 0.2,
            outlier_probability: 0.05,
            range: RangeParams::default(),
        }
    }
}

impl ParticleParams {
    /// Settings with as many particles as `grid` has points (equal ray budget) and
    /// the same likelihood.
    pub fn with_grid_budget(grid: &MgpmfParams) -> Self {
        Self {
            particles: grid.grid_points.iter().product(),
            outlier_probability: grid.outlier_probability,
            range: grid.range,
            ..Self::default()
        }
    }

    /// Checks the settings: 2..=[`MAX_POINTS`] particles, `0 <= K <= 10`, `eps`, range.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<ParticleSettings, MapAidedError> {
        if !(2..=MAX_POINTS).contains(&self.particles) {
            return Err(invalid(
                "particle.particles",
                self.particles as f64,
                "2..=1e6",
            ));
        }
        let k = self.roughening;
        if !(k.is_finite() && (0.0..=10.0).contains(&k)) {
            return Err(invalid("particle.roughening", k, "0 <= K <= 10"));
        }
        Ok(ParticleSettings {
            particles: self.particles,
            roughening: k,
            kernel: self.kernel,
            outlier_probability: check_outlier(
                "particle.outlier_probability",
                self.outlier_probability,
            )?,
            range: self.range.check_as("particle.range")?,
        })
    }
}

/// Checked [`ParticleParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleSettings {
    pub(crate) particles: usize,
    pub(crate) roughening: f64,
    pub(crate) kernel: ParticleKernel,
    pub(crate) outlier_probability: f64,
    pub(crate) range: RangeSettings,
}

impl ParticleSettings {
    /// Number of particles.
    pub fn particles(&self) -> usize {
        self.particles
    }
}

/// Mode switching between GPS/INS and map-aided range/INS (spec D: the threshold is a
/// setting, the paper gives none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwitchParams {
    /// GPS/INS is used while at least this many satellites are in line of sight.
    /// Default 5 (4 for a fix plus one for a residual check).
    pub min_los_satellites: usize,
    /// Extra satellites needed to return to GPS/INS after leaving it (hysteresis on
    /// the count). Default 1.
    pub hysteresis_satellites: usize,
    /// Shortest time in a mode before the next switch, s (hysteresis in time).
    /// Default 1.
    pub min_dwell_s: f64,
}

impl Default for SwitchParams {
    fn default() -> Self {
        Self {
            min_los_satellites: 5,
            hysteresis_satellites: 1,
            min_dwell_s: 1.0,
        }
    }
}

/// Checked [`SwitchParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwitchSettings {
    pub(crate) enter_gps_at: usize,
    pub(crate) leave_gps_below: usize,
    pub(crate) min_dwell: f64,
}

impl SwitchSettings {
    /// LOS count at or above which map-aided mode returns to GPS/INS.
    pub fn enter_gps_at(&self) -> usize {
        self.enter_gps_at
    }

    /// LOS count below which GPS/INS mode goes map-aided.
    pub fn leave_gps_below(&self) -> usize {
        self.leave_gps_below
    }
}

impl SwitchParams {
    /// Checks the settings: `1 <= min_los <= 64`, hysteresis `<= 64`, dwell finite
    /// and `>= 0`.
    ///
    /// # Errors
    /// [`MapAidedError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<SwitchSettings, MapAidedError> {
        if !(1..=64).contains(&self.min_los_satellites) {
            return Err(invalid(
                "switch.min_los_satellites",
                self.min_los_satellites as f64,
                "1..=64",
            ));
        }
        if self.hysteresis_satellites > 64 {
            return Err(invalid(
                "switch.hysteresis_satellites",
                self.hysteresis_satellites as f64,
                "0..=64",
            ));
        }
        Ok(SwitchSettings {
            enter_gps_at: self.min_los_satellites + self.hysteresis_satellites,
            leave_gps_below: self.min_los_satellites,
            min_dwell: non_negative("switch.min_dwell_s", self.min_dwell_s)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(e: MapAidedError) -> String {
        match e {
            MapAidedError::InvalidParameter { field, .. } => field,
            other => panic!("unexpected {other}"),
        }
    }

    /// Every setting is checked, and the error names the field.
    #[test]
    fn bad_settings_name_the_field() {
        assert!(Ins12Params::default().check().is_ok());
        let e = Ins12Params {
            angle_random_walk_rad_per_sqrt_s: -1.0,
            ..Ins12Params::default()
        }
        .check()
        .unwrap_err();
        assert_eq!(field(e), "ins12.angle_random_walk_rad_per_sqrt_s");
        let e = Ins12Params {
            velocity_random_walk_mps_per_sqrt_s: f64::NAN,
            ..Ins12Params::default()
        };
        assert_eq!(
            field(e.check().unwrap_err()),
            "ins12.velocity_random_walk_mps_per_sqrt_s"
        );

        for p in [0.0, 1.0, f64::NAN] {
            let e = GpsParams {
                gate_probability: p,
                ..GpsParams::default()
            };
            assert_eq!(field(e.check().unwrap_err()), "gps.gate_probability");
        }
        let g = GpsParams::default().check().unwrap();
        assert!((g.gate_position() - 16.266).abs() < 1e-3, "{g:?}");

        let mut m = MgpmfParams::default();
        assert_eq!(m.check().unwrap().num_points(), 41 * 41 * 9);
        m.k_sigma = 0.0;
        assert_eq!(field(m.check().unwrap_err()), "mgpmf.k_sigma");
        m.k_sigma = -1.0;
        assert_eq!(field(m.check().unwrap_err()), "mgpmf.k_sigma");
        m = MgpmfParams {
            grid_points: [41, 0, 9],
            ..MgpmfParams::default()
        };
        assert_eq!(field(m.check().unwrap_err()), "mgpmf.grid_points[1]");
        m.grid_points = [1000, 1000, 9];
        assert_eq!(field(m.check().unwrap_err()), "mgpmf.grid_points");
        m = MgpmfParams {
            outlier_probability: 1.0,
            ..MgpmfParams::default()
        };
        assert_eq!(field(m.check().unwrap_err()), "mgpmf.outlier_probability");
        m = MgpmfParams::default();
        m.range.max_incidence_deg = 90.0;
        assert_eq!(
            field(m.check().unwrap_err()),
            "mgpmf.range.max_incidence_deg"
        );
        m.range = RangeParams {
            max_range_m: 0.0,
            ..RangeParams::default()
        };
        assert_eq!(field(m.check().unwrap_err()), "mgpmf.range.max_range_m");

        let p = ParticleParams::with_grid_budget(&MgpmfParams::default());
        assert_eq!(p.check().unwrap().particles(), 15129);
        let e = ParticleParams { particles: 1, ..p };
        assert_eq!(field(e.check().unwrap_err()), "particle.particles");
        let e = ParticleParams {
            roughening: f64::INFINITY,
            ..p
        };
        assert_eq!(field(e.check().unwrap_err()), "particle.roughening");

        let s = SwitchParams::default().check().unwrap();
        assert_eq!((s.enter_gps_at(), s.leave_gps_below()), (6, 5));
        let e = SwitchParams {
            min_los_satellites: 0,
            ..SwitchParams::default()
        };
        assert_eq!(field(e.check().unwrap_err()), "switch.min_los_satellites");
        let e = SwitchParams {
            min_dwell_s: -1.0,
            ..SwitchParams::default()
        };
        assert_eq!(field(e.check().unwrap_err()), "switch.min_dwell_s");
        let r = RangeParams::default().check().unwrap();
        assert!((r.gate() - 10.828).abs() < 1e-3 && r.max_range() == 60.0);
    }
}

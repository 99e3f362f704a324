//! Map-aided navigation near structures (seed 004, spec D "Estimators"): the 12-state
//! error-state INS and the updates that aid it — GPS/INS, the geometry-based range EKF
//! (GREKF), the marginalized Gaussian point-mass filter (MGPMF), a bootstrap particle
//! filter as the MGPMF's reference, and the switching between GPS/INS and map-aided
//! modes.
//!
//! The estimators see the map only through [`fathom_core::RayCaster`] (`&dyn`), and
//! the INS only through plain values (the nominal state [`NominalNav`], the attitude
//! and specific force of a step): this crate depends on neither the map, the INS nor
//! the sensor crates.
//!
//! | file | job |
//! | --- | --- |
//! | [`error_model`] | `F`, `G` of eq. (3)-(4) and their exact discretization |
//! | [`ins12`] | the filter: state layout, prediction, closed-loop feedback ([`Correction`]) |
//! | [`gps`] | loosely coupled GPS position (+ velocity) update, chi-square gated |
//! | [`range_model`] | beams and baro as inputs, eq. (7)-(13) rows from the hit normal |
//! | [`grekf`] | GREKF: per-beam ray cast, gating, one stacked update (faer) |
//! | [`marginal`] | the `n` / `l` split of eq. (15), the conditional Kalman step, eq. (19) |
//! | [`likelihood`] | the robust range likelihood of candidate poses (batch ray casts) |
//! | [`mgpmf`] | MGPMF: grid, weights, eq. (17)-(18) with interpolation, linear step |
//! | [`particle`] | bootstrap particle filter on the same substate and likelihood |
//! | [`switching`] | GPS/INS vs map-aided mode with hysteresis, one filter for both |
//! | [`params`] | every setting as `Params` + `check()` (errors name the field) |
//! | [`findings`] | the paper's misprints and sign conventions, as a printable list |
//!
//! # State and conventions (eq. 1, 6)
//!
//! `dx = [dp (0..3), dv (3..6), psi (6..9), db_a (9..12)]` in the local NED frame:
//!
//! - `dp = p_hat - p`, `dv = v_hat - v` (estimated minus true, eq. 6:
//!   `x = x_hat - dx`);
//! - `psi`: attitude error, `C_hat = exp([psi x]) C` (`C = C_b^n`), so
//!   `psi = log(C_hat C^T)`; the convention of `fathom_ins::error_model`;
//! - `db_a`: the residual accelerometer error, measured minus true after the current
//!   bias estimate is subtracted (it enters `dv` with `+C`, eq. 3);
//! - no gyro-bias state (calibrated at rest), no Earth rate (reduced mechanization).
//!
//! Every measurement `z = h(x) + v` is linearized as `z - h(x_hat) = H dx + v` with
//! `H = d h(x_hat (-) dx) / d dx`; the correction is applied as `x_hat (-) dx_hat`
//! ([`Correction::apply`]).
//!
//! # Bad input
//!
//! Settings are checked once (`Params::check`, errors name the field). At run time a
//! NaN range or height, a standard deviation or variance `<= 0`, a zero beam
//! direction, a non-finite nominal state, a time going backwards, or a pose from which
//! no ray hits the map is a typed [`MapAidedError`] with the filter time; every failing
//! step leaves the filter (and the particles) unchanged.

mod cast_order;
pub mod error;
pub mod error_model;
pub mod findings;
pub mod gps;
pub mod grekf;
pub mod ins12;
pub mod likelihood;
pub mod marginal;
pub mod mgpmf;
pub mod params;
#[cfg(feature = "particle-filter")]
pub mod particle;
pub mod range_model;
pub mod switching;

#[cfg(test)]
pub(crate) mod test_support;

use nalgebra::{SMatrix, SVector};

pub use error::MapAidedError;
pub use findings::{PAPER_FINDINGS, PaperFinding};
pub use gps::{GpsFix, GpsOutcome, GpsReacquire, GpsVelocity};
pub use grekf::{Grekf, GrekfReport};
pub use ins12::{Correction, Ins12Filter, NominalNav};
pub use mgpmf::{Mgpmf, MgpmfReport};
pub use params::{
    GpsAiding, GpsParams, GrekfParams, GrekfSettings, GridPosterior, ImuNoise, Ins12Params,
    MgpmfParams, MgpmfSettings, ParticleKernel, ParticleParams, ParticleSettings, RangeParams,
    RangeSettings, SwitchParams, SwitchSettings,
};
#[cfg(feature = "particle-filter")]
pub use particle::{ParticleFilter, ParticleReport};
pub use range_model::{BaroHeight, BeamGeometry, RangeBeam};
pub use switching::{MapAider, MapReport, ModeSwitch, NavMode, SwitchingFilter};

/// Number of error states.
pub const N_STATES: usize = 12;
/// Number of continuous noise inputs (`w_acc`, `w_gyro`, `w_ba`).
pub const N_NOISE: usize = 9;
/// Index of the first position-error state.
pub const POS: usize = 0;
/// Index of the first velocity-error state.
pub const VEL: usize = 3;
/// Index of the first attitude-error state `psi`.
pub const ATT: usize = 6;
/// Index of the first accelerometer-bias state.
pub const ACCEL_BIAS: usize = 9;

/// A 12-vector of the error state.
pub type ErrorVector12 = SVector<f64, N_STATES>;
/// A 12 x 12 matrix (`F`, `Phi`, `Q_d`, `P`).
pub type Matrix12 = SMatrix<f64, N_STATES, N_STATES>;

//! Wind: a constant mean plus gusts, each NED axis an independent first-order
//! Gauss-Markov process with standard deviation `sigma_i` and correlation time `T`,
//! stepped exactly once per control step and held over it:
//!
//! ```text
//! g_k = exp(-dt/T) g_{k-1} + sigma sqrt(1 - exp(-2 dt/T)) z_k,   g_0 ~ N(0, sigma^2)
//! ```
//!
//! Random draws (only when some `sigma_i > 0`): 3 standard normals at the start
//! (stationary initial gusts, axis order north, east, down) and 3 per step.

use nalgebra::Vector3;
use rand::Rng;
use rand_distr::StandardNormal;

use super::params::Wind;

/// The evolving gust velocity of one flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindState {
    gust_in_nav: Vector3<f64>,
}

fn normal3(rng: &mut impl Rng) -> Vector3<f64> {
    let x: f64 = rng.sample(StandardNormal);
    let y: f64 = rng.sample(StandardNormal);
    let z: f64 = rng.sample(StandardNormal);
    Vector3::new(x, y, z)
}

impl Wind {
    /// The gusts at the start of a flight (stationary distribution).
    pub fn start(&self, rng: &mut impl Rng) -> WindState {
        let gust_in_nav = if self.has_gusts() {
            normal3(rng).component_mul(&self.params().gust_sigma_mps)
        } else {
            Vector3::zeros()
        };
        WindState { gust_in_nav }
    }

    /// Advances the gusts by `dt` (no draw without gusts).
    pub fn step(&self, state: &mut WindState, dt: f64, rng: &mut impl Rng) {
        if !self.has_gusts() {
            return;
        }
        let p = self.params();
        let phi = (-dt / p.gust_correlation_time_s).exp();
        let w = (-(-2.0 * dt / p.gust_correlation_time_s).exp_m1()).sqrt();
        state.gust_in_nav =
            state.gust_in_nav * phi + normal3(rng).component_mul(&p.gust_sigma_mps) * w;
    }

    /// The wind velocity (mean plus gust) in NED, m/s.
    pub fn velocity(&self, state: &WindState) -> Vector3<f64> {
        self.params().mean_in_nav + state.gust_in_nav
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrotor::params::WindParams;
    use rand::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn calm_wind_draws_nothing() {
        let w = WindParams {
            mean_in_nav: Vector3::new(2.0, -1.0, 0.0),
            ..WindParams::calm()
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut s = w.start(&mut rng);
        w.step(&mut s, 0.005, &mut rng);
        assert_eq!(w.velocity(&s), Vector3::new(2.0, -1.0, 0.0));
        assert_eq!(rng.next_u64(), ChaCha8Rng::seed_from_u64(1).next_u64());
    }

    /// Gust variance stays at sigma^2 and the lag-1 correlation is exp(-dt/T), within
    /// 5 sigma of their sampling errors (AR(1) inflation). Negative control: a 20 %
    /// larger sigma is rejected.
    #[test]
    fn gusts_are_stationary_gauss_markov() {
        let (sigma, t_c, dt) = (1.5, 2.0, 0.05);
        let w = WindParams {
            mean_in_nav: Vector3::zeros(),
            gust_sigma_mps: Vector3::new(sigma, sigma, 0.0),
            gust_correlation_time_s: t_c,
        }
        .check()
        .unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let mut s = w.start(&mut rng);
        let n = 200_000;
        let (mut sum_sq, mut sum_lag) = (0.0, 0.0);
        let mut prev = w.velocity(&s).x;
        for _ in 0..n {
            w.step(&mut s, dt, &mut rng);
            let x = w.velocity(&s).x;
            sum_sq += x * x;
            sum_lag += x * prev;
            prev = x;
            assert_eq!(w.velocity(&s).z, 0.0);
        }
        let rho = (-dt / t_c).exp();
        let var = sum_sq / n as f64;
        let rel_sd = (2.0 / n as f64 * (1.0 + rho * rho) / (1.0 - rho * rho)).sqrt();
        assert!((var / (sigma * sigma) - 1.0).abs() < 5.0 * rel_sd, "{var}");
        assert!((var / (1.44 * sigma * sigma) - 1.0).abs() > 5.0 * rel_sd);
        let r1 = sum_lag / sum_sq;
        assert!((r1 - rho).abs() < 0.01, "{r1} vs {rho}");
    }
}

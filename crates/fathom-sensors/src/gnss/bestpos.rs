//! The paper's BESTPOS model (spec D, GPS): the receiver's position solution as the
//! truth plus noise recorded from a static receiver, modelled as a first-order
//! Gauss-Markov process per NED axis (the paper gives the method, not the numbers:
//! the std and correlation time are settings).

use nalgebra::Vector3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::SensorError;
use crate::noise::GaussMarkov;

/// Unchecked BESTPOS noise parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BestposParams {
    /// Stationary std per axis (north, east, down), m. Default (1.0, 1.0, 2.0).
    pub sigma_m: [f64; 3],
    /// Correlation time, s. Default 60.
    pub tau_s: f64,
}

impl Default for BestposParams {
    fn default() -> Self {
        Self {
            sigma_m: [1.0, 1.0, 2.0],
            tau_s: 60.0,
        }
    }
}

impl BestposParams {
    /// Starts the noise processes (stationary: three standard normals drawn).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative sigma or non-positive tau.
    pub fn start(&self, rng: &mut impl Rng) -> Result<Bestpos, SensorError> {
        Ok(Bestpos {
            axes: [
                GaussMarkov::new(self.sigma_m[0], self.tau_s, rng)?,
                GaussMarkov::new(self.sigma_m[1], self.tau_s, rng)?,
                GaussMarkov::new(self.sigma_m[2], self.tau_s, rng)?,
            ],
        })
    }
}

/// The running BESTPOS noise.
#[derive(Debug, Clone)]
pub struct Bestpos {
    axes: [GaussMarkov; 3],
}

impl Bestpos {
    /// The current fix for the true position (no draw).
    pub fn fix(&self, true_pos_in_nav: &Vector3<f64>) -> Vector3<f64> {
        true_pos_in_nav + self.noise()
    }

    /// The current noise, NED, m.
    pub fn noise(&self) -> Vector3<f64> {
        Vector3::new(
            self.axes[0].value(),
            self.axes[1].value(),
            self.axes[2].value(),
        )
    }

    /// Advances the noise by `dt` seconds (three draws) and returns the new fix.
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] for a negative or non-finite `dt`.
    pub fn step(
        &mut self,
        dt: f64,
        true_pos_in_nav: &Vector3<f64>,
        rng: &mut impl Rng,
    ) -> Result<Vector3<f64>, SensorError> {
        for a in &mut self.axes {
            a.step(dt, rng)?;
        }
        Ok(self.fix(true_pos_in_nav))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn noise_is_stationary_and_correlated() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let p = BestposParams {
            sigma_m: [1.0, 2.0, 3.0],
            tau_s: 10.0,
        };
        let mut b = p.start(&mut rng).unwrap();
        let truth = Vector3::new(5.0, 6.0, -7.0);
        let (n, dt) = (100_000, 0.2);
        let mut sum2 = Vector3::zeros();
        let mut lag = 0.0;
        let mut prev = b.noise();
        for _ in 0..n {
            let fix = b.step(dt, &truth, &mut rng).unwrap();
            let e = fix - truth;
            sum2 += e.component_mul(&e);
            lag += e.x * prev.x;
            prev = e;
        }
        let var = sum2 / f64::from(n);
        // AR(1) with rho = exp(-0.02): effective samples n (1 - rho) / (1 + rho) ~ 1000,
        // relative std of a variance estimate ~ sqrt(2/1000) = 4.5 %: 5 sigma bounds
        for (k, s) in [1.0, 2.0, 3.0].iter().enumerate() {
            assert!((var[k] / (s * s) - 1.0).abs() < 0.23, "{k}: {}", var[k]);
        }
        let rho = lag / f64::from(n) / var.x;
        assert!((rho - (-dt / 10.0f64).exp()).abs() < 0.01, "{rho}");
        assert!(b.step(-1.0, &truth, &mut rng).is_err());
        assert!(BestposParams { tau_s: 0.0, ..p }.start(&mut rng).is_err());
    }
}

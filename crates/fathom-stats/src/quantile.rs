//! Quantiles and CDFs of the normal, Student-t and chi-square distributions, with
//! checked arguments (errors instead of the panics of the underlying `statrs` calls).

use crate::error::{StatsError, ensure_level};
use statrs::distribution::{ChiSquared, Continuous, ContinuousCDF, Normal, StudentsT};

fn check_dof(what: &str, dof: f64) -> Result<(), StatsError> {
    if !(dof.is_finite() && dof > 0.0) {
        return Err(StatsError::OutOfRange {
            what: format!("{what} degrees of freedom"),
            value: dof,
            expected: "finite and > 0",
        });
    }
    Ok(())
}

fn chi_squared(dof: f64) -> Result<ChiSquared, StatsError> {
    check_dof("chi-square", dof)?;
    ChiSquared::new(dof).map_err(|e| StatsError::Distribution {
        what: format!("chi-square({dof})"),
        detail: e.to_string(),
    })
}

/// Quantile of the standard normal distribution, `Phi^-1(p)`.
///
/// # Errors
/// [`StatsError::OutOfRange`] unless `0 < p < 1`.
pub fn normal_quantile(p: f64) -> Result<f64, StatsError> {
    ensure_level("normal quantile probability", p)?;
    let n = Normal::new(0.0, 1.0).map_err(|e| StatsError::Distribution {
        what: "standard normal".into(),
        detail: e.to_string(),
    })?;
    Ok(n.inverse_cdf(p))
}

/// CDF of the standard normal distribution, `Phi(x)` (`0` at `-inf`, `1` at `+inf`;
/// NaN for NaN).
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(-x / std::f64::consts::SQRT_2)
}

/// Quantile of the Student-t distribution with `dof` degrees of freedom.
///
/// # Errors
/// [`StatsError::OutOfRange`] unless `0 < p < 1` and `dof > 0`.
pub fn student_t_quantile(p: f64, dof: f64) -> Result<f64, StatsError> {
    ensure_level("student-t quantile probability", p)?;
    check_dof("student-t", dof)?;
    let t = StudentsT::new(0.0, 1.0, dof).map_err(|e| StatsError::Distribution {
        what: format!("student-t({dof})"),
        detail: e.to_string(),
    })?;
    Ok(t.inverse_cdf(p))
}

/// CDF of the chi-square distribution with `dof` degrees of freedom at `x`
/// (`0` for `x <= 0`).
///
/// # Errors
/// [`StatsError::OutOfRange`] if `dof <= 0`; [`StatsError::NonFinite`] if `x` is NaN.
pub fn chi2_cdf(x: f64, dof: f64) -> Result<f64, StatsError> {
    if x.is_nan() {
        return Err(StatsError::NonFinite {
            what: "chi-square cdf argument".into(),
            index: 0,
            value: x,
        });
    }
    let d = chi_squared(dof)?;
    if x <= 0.0 {
        return Ok(0.0);
    }
    if x == f64::INFINITY {
        return Ok(1.0);
    }
    Ok(d.cdf(x))
}

/// Quantile of the chi-square distribution, `chi2inv(p, dof)`.
///
/// `statrs`' own inverse stops after a fixed small number of iterations, which is
/// not accurate enough for large `dof` (e.g. `M * n = 600` in an average-NEES test),
/// so this refines it with a safeguarded Newton iteration on the CDF, keeping a
/// bracket `[lo, hi]` and falling back to bisection whenever Newton leaves it.
/// Converges to ~1e-13 relative. Limitation: `statrs` returns a CDF of exactly 0
/// for arguments below ~1e-15, so quantiles smaller than that (extreme lower tails
/// with `dof < 1` only, e.g. `p = 1e-6, dof = 0.5`) are not resolved.
///
/// # Errors
/// [`StatsError::OutOfRange`] unless `0 < p < 1` and `dof > 0`.
pub fn chi2_quantile(p: f64, dof: f64) -> Result<f64, StatsError> {
    ensure_level("chi-square quantile probability", p)?;
    let d = chi_squared(dof)?;
    // Bracket the root of cdf(x) - p.
    let mut lo = 0.0_f64;
    let mut hi = dof.max(1.0);
    let mut guard = 0;
    while d.cdf(hi) < p {
        lo = hi;
        hi *= 2.0;
        guard += 1;
        if guard > 2000 || !hi.is_finite() {
            return Err(StatsError::Degenerate {
                what: format!("chi-square({dof}) quantile at p = {p}"),
                reason: "could not bracket the quantile",
            });
        }
    }
    // Start from the Wilson-Hilferty approximation, clipped into the bracket.
    let z = normal_quantile(p)?;
    let a = 2.0 / (9.0 * dof);
    let mut x = dof * (1.0 - a + z * a.sqrt()).powi(3);
    if !(x > lo && x < hi) {
        x = 0.5 * (lo + hi);
    }
    for _ in 0..300 {
        let f = d.cdf(x) - p;
        if f == 0.0 {
            return Ok(x);
        }
        if f < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let pdf = d.pdf(x);
        let mut next = x - f / pdf;
        if !(next.is_finite() && next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let step = (next - x).abs();
        x = next;
        if step <= 1e-14 * x.abs() || hi - lo <= 1e-15 * hi {
            break;
        }
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn chi2_quantiles_match_tables() {
        // Reference values: standard chi-square tables (R qchisq).
        assert_relative_eq!(
            chi2_quantile(0.975, 2.0).unwrap(),
            7.377_759,
            epsilon = 1e-6
        );
        assert_relative_eq!(
            chi2_quantile(0.025, 2.0).unwrap(),
            0.050_635_6,
            epsilon = 1e-7
        );
        assert_relative_eq!(
            chi2_quantile(0.025, 100.0).unwrap(),
            74.221_93,
            epsilon = 1e-4
        );
        assert_relative_eq!(
            chi2_quantile(0.975, 100.0).unwrap(),
            129.561_2,
            epsilon = 1e-4
        );
        assert_relative_eq!(chi2_quantile(0.95, 1.0).unwrap(), 3.841_459, epsilon = 1e-6);
        assert_relative_eq!(
            chi2_quantile(0.025, 1.0).unwrap(),
            9.820_691e-4,
            epsilon = 1e-9
        );
        assert_relative_eq!(chi2_quantile(0.99, 3.0).unwrap(), 11.344_87, epsilon = 1e-5);
        // Large dof (qchisq(0.975, 10000) = 10278.0...).
        let q = chi2_quantile(0.975, 10_000.0).unwrap();
        assert_relative_eq!(chi2_cdf(q, 10_000.0).unwrap(), 0.975, epsilon = 1e-10);
    }

    #[test]
    fn quantile_inverts_cdf() {
        for &dof in &[0.5, 1.0, 3.0, 7.5, 60.0, 600.0] {
            for &p in &[1e-6, 0.025, 0.5, 0.975, 0.999_999] {
                if dof < 1.0 && p < 1e-3 {
                    // Quantile ~1e-24: below what statrs' CDF resolves (see docs).
                    continue;
                }
                let x = chi2_quantile(p, dof).unwrap();
                assert_relative_eq!(chi2_cdf(x, dof).unwrap(), p, max_relative = 1e-9);
            }
        }
    }

    #[test]
    fn normal_and_t_quantiles() {
        assert_relative_eq!(normal_quantile(0.975).unwrap(), 1.959_964, epsilon = 1e-6);
        assert_relative_eq!(
            student_t_quantile(0.975, 9.0).unwrap(),
            2.262_157,
            epsilon = 1e-6
        );
        assert_relative_eq!(
            student_t_quantile(0.975, 1.0).unwrap(),
            12.706_20,
            epsilon = 1e-4
        );
        assert_relative_eq!(
            student_t_quantile(0.025, 30.0).unwrap(),
            -2.042_272,
            epsilon = 1e-6
        );
    }

    #[test]
    fn bad_arguments_are_errors() {
        assert!(chi2_quantile(0.0, 2.0).is_err());
        assert!(chi2_quantile(1.0, 2.0).is_err());
        assert!(chi2_quantile(f64::NAN, 2.0).is_err());
        assert!(chi2_quantile(0.5, 0.0).is_err());
        assert!(chi2_quantile(0.5, f64::INFINITY).is_err());
        assert!(student_t_quantile(0.5, -1.0).is_err());
        assert!(normal_quantile(1.5).is_err());
        assert!(chi2_cdf(f64::NAN, 1.0).is_err());
        assert_eq!(chi2_cdf(-1.0, 1.0).unwrap(), 0.0);
    }
}

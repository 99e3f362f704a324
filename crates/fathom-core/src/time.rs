//! Time stamps: `f64` seconds from the start of a run, and the monotonicity check.

use crate::CoreError;

/// Time in seconds from the start of the run.
pub type Time = f64;

/// Checks that `times` are finite and strictly increasing.
///
/// # Errors
/// [`CoreError::NonFinite`] or [`CoreError::NonIncreasingTime`] naming `what` and
/// the offending index.
pub fn ensure_strictly_increasing(what: &str, times: &[Time]) -> Result<(), CoreError> {
    crate::error::ensure_finite(what, times.iter())?;
    for (index, pair) in times.windows(2).enumerate() {
        if pair[1] <= pair[0] {
            return Err(CoreError::NonIncreasingTime {
                what: what.to_owned(),
                index: index + 1,
                prev: pair[0],
                next: pair[1],
            });
        }
    }
    Ok(())
}

/// Evenly spaced instants `t0, t0 + dt, ...` up to and including `t_end` (within
/// half a step), computed by multiplication so that no rounding error accumulates.
///
/// Returns an empty vector when `dt` is not positive or the bounds are not finite.
pub fn uniform_grid(t0: Time, t_end: Time, dt: Time) -> Vec<Time> {
    if !(dt > 0.0 && t0.is_finite() && t_end.is_finite()) || t_end < t0 {
        return Vec::new();
    }
    let n = ((t_end - t0) / dt + 0.5).floor() as usize;
    (0..=n).map(|k| t0 + k as f64 * dt).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotonic_check() {
        assert!(ensure_strictly_increasing("t", &[0.0, 1.0, 2.0]).is_ok());
        let err = ensure_strictly_increasing("t", &[0.0, 1.0, 1.0]).unwrap_err();
        assert_eq!(
            err,
            CoreError::NonIncreasingTime {
                what: "t".into(),
                index: 2,
                prev: 1.0,
                next: 1.0
            }
        );
        assert!(ensure_strictly_increasing("t", &[0.0, f64::NAN]).is_err());
    }

    #[test]
    fn grid_has_no_drift() {
        let g = uniform_grid(0.0, 180.0, 0.01);
        assert_eq!(g.len(), 18_001);
        assert_eq!(*g.last().unwrap(), 180.0);
        assert!(uniform_grid(0.0, 1.0, 0.0).is_empty());
    }
}

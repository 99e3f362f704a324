//! Seabed depth under a vehicle's track, for echo-sounder altitude and DVL
//! bottom-lock simulation (spec C, `vkf` experiment, paper §3.2).
//!
//! The profile is the seabed depth (NED down, m) directly below the vehicle as a
//! function of mission time, i.e. along the vehicle's track: piecewise linear between
//! knots `(t_i, d_i)` with strictly increasing times, held constant outside the knot
//! range. The altitude of a vehicle at depth `z` is `d(t) - z`.

use fathom_core::Time;

use crate::TrajError;

/// Seabed depth along the track, piecewise linear in time (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SeabedProfile {
    times: Vec<Time>,
    depths: Vec<f64>,
}

impl SeabedProfile {
    /// A profile through the knots `(time s, seabed depth m)`.
    ///
    /// # Errors
    /// [`TrajError::TooFewKnots`] for fewer than two knots,
    /// [`TrajError::InvalidParameter`] naming the knot for a non-finite value, a
    /// negative depth or non-increasing times.
    pub fn new(knots: &[(Time, f64)]) -> Result<Self, TrajError> {
        if knots.len() < 2 {
            return Err(TrajError::TooFewKnots { got: knots.len() });
        }
        for (i, &(t, d)) in knots.iter().enumerate() {
            if !t.is_finite() || !d.is_finite() || d < 0.0 {
                return Err(TrajError::InvalidParameter {
                    field: format!("seabed knot {i}"),
                    reason: format!("needs finite time and finite depth >= 0, got ({t}, {d})"),
                });
            }
            if i > 0 && t <= knots[i - 1].0 {
                return Err(TrajError::InvalidParameter {
                    field: format!("seabed knot {i}"),
                    reason: format!(
                        "times must increase strictly, got {t} s after {} s",
                        knots[i - 1].0
                    ),
                });
            }
        }
        Ok(Self {
            times: knots.iter().map(|k| k.0).collect(),
            depths: knots.iter().map(|k| k.1).collect(),
        })
    }

    /// The `vkf` default: seabed 110 m deep (60 m below a vehicle at 50 m), dropping
    /// to 190 m (altitude 140 m) over 20 s ramps centred on 300 s, 480 s, 900 s and
    /// 960 s, so the altitude exceeds the DVL's 100 m range exactly during
    /// 5-8 min and 15-16 min (paper §3.2, Fig. 8-9), over 1620 s.
    pub fn vkf_default() -> Self {
        let knots = [
            (0.0, 110.0),
            (290.0, 110.0),
            (310.0, 190.0),
            (470.0, 190.0),
            (490.0, 110.0),
            (890.0, 110.0),
            (910.0, 190.0),
            (950.0, 190.0),
            (970.0, 110.0),
            (1620.0, 110.0),
        ];
        // Constant knots, valid by construction (checked in the tests).
        Self {
            times: knots.iter().map(|k| k.0).collect(),
            depths: knots.iter().map(|k| k.1).collect(),
        }
    }

    /// The knots `(time, depth)`.
    pub fn knots(&self) -> impl Iterator<Item = (Time, f64)> + '_ {
        self.times.iter().copied().zip(self.depths.iter().copied())
    }

    /// Seabed depth at time `t` (held constant before the first and after the last
    /// knot).
    ///
    /// # Errors
    /// [`TrajError::OutOfRange`] when `t` is not finite.
    pub fn depth_at(&self, t: Time) -> Result<f64, TrajError> {
        let n = self.times.len();
        if !t.is_finite() {
            return Err(TrajError::OutOfRange {
                t,
                start: self.times[0],
                end: self.times[n - 1],
            });
        }
        if t <= self.times[0] {
            return Ok(self.depths[0]);
        }
        if t >= self.times[n - 1] {
            return Ok(self.depths[n - 1]);
        }
        let i = self.times.partition_point(|&k| k <= t) - 1;
        let (t0, t1) = (self.times[i], self.times[i + 1]);
        let (d0, d1) = (self.depths[i], self.depths[i + 1]);
        Ok(d0 + (d1 - d0) * (t - t0) / (t1 - t0))
    }

    /// Altitude above the seabed of a vehicle at depth `vehicle_depth` at time `t`:
    /// `d(t) - vehicle_depth`.
    ///
    /// # Errors
    /// As [`SeabedProfile::depth_at`].
    pub fn altitude_at(&self, t: Time, vehicle_depth: f64) -> Result<f64, TrajError> {
        Ok(self.depth_at(t)? - vehicle_depth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    #[test]
    fn default_profile_exceeds_range_in_the_paper_intervals() {
        let s = SeabedProfile::vkf_default();
        let alt = |t: f64| s.altitude_at(t, 50.0).unwrap();
        assert_abs_diff_eq!(alt(0.0), 60.0);
        assert_abs_diff_eq!(alt(300.0), 100.0, epsilon = 1e-12);
        assert_abs_diff_eq!(alt(480.0), 100.0, epsilon = 1e-12);
        assert_abs_diff_eq!(alt(900.0), 100.0, epsilon = 1e-12);
        assert_abs_diff_eq!(alt(960.0), 100.0, epsilon = 1e-12);
        // Above 100 m exactly inside (300, 480) and (900, 960): 4 minutes in all.
        let above: usize = (0..=16_200)
            .filter(|k| alt(*k as f64 * 0.1) > 100.0)
            .count();
        assert_eq!(above, 1799 + 599);
        assert_abs_diff_eq!(alt(1e6), 60.0);
        assert_abs_diff_eq!(alt(-5.0), 60.0);
        assert!(s.depth_at(f64::NAN).is_err());
        let knots: Vec<_> = s.knots().collect();
        assert_eq!(SeabedProfile::new(&knots).unwrap(), s);
    }

    #[test]
    fn bad_knots_are_rejected() {
        assert!(SeabedProfile::new(&[(0.0, 1.0)]).is_err());
        let e = SeabedProfile::new(&[(0.0, 1.0), (0.0, 2.0)]).unwrap_err();
        assert!(e.to_string().contains("knot 1"), "{e}");
        assert!(SeabedProfile::new(&[(0.0, -1.0), (1.0, 2.0)]).is_err());
        assert!(SeabedProfile::new(&[(0.0, f64::NAN), (1.0, 2.0)]).is_err());
    }
}

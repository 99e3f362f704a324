//! Natural cubic splines through knots at arbitrary strictly increasing times:
//! a scalar [`CubicSpline`] and a 3-vector [`CubicSpline3`] (one spline per axis).
//!
//! # Math
//!
//! With knots `(t_i, y_i)`, `i = 0..n-1`, step `h_i = t_{i+1} - t_i` and unknown
//! second derivatives `M_i = S''(t_i)`, C2 continuity at the interior knots gives the
//! tridiagonal system (natural end conditions `M_0 = M_{n-1} = 0`)
//!
//! ```text
//! h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1}
//!     = 6 [ (y_{i+1} - y_i) / h_i - (y_i - y_{i-1}) / h_{i-1} ],   i = 1..n-2
//! ```
//!
//! solved in O(n) by the Thomas algorithm (the matrix is strictly diagonally
//! dominant, so no pivoting is needed). On `[t_i, t_{i+1}]`, with `a = t_{i+1} - t`,
//! `b = t - t_i`, `h = h_i`:
//!
//! ```text
//! S(t)   = M_i a^3/(6h) + M_{i+1} b^3/(6h) + (y_i/h - M_i h/6) a + (y_{i+1}/h - M_{i+1} h/6) b
//! S'(t)  = -M_i a^2/(2h) + M_{i+1} b^2/(2h) - (y_i/h - M_i h/6) + (y_{i+1}/h - M_{i+1} h/6)
//! S''(t) = M_i a/h + M_{i+1} b/h
//! ```
//!
//! Evaluation is checked: a time outside `[t_0, t_{n-1}]` (or not finite) is a
//! [`TrajError::OutOfRange`]; the spline is never extrapolated.

use fathom_core::{Time, error::ensure_finite, time::ensure_strictly_increasing};
use nalgebra::Vector3;

use crate::TrajError;

/// Value, first and second derivative of a scalar spline at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplinePoint {
    /// `S(t)`.
    pub value: f64,
    /// `S'(t)`, per second.
    pub d1: f64,
    /// `S''(t)`, per second squared.
    pub d2: f64,
}

/// Value, first and second derivative of a 3-vector spline at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplinePoint3 {
    /// `S(t)`.
    pub value: Vector3<f64>,
    /// `S'(t)`, per second.
    pub d1: Vector3<f64>,
    /// `S''(t)`, per second squared.
    pub d2: Vector3<f64>,
}

/// Natural cubic spline of a scalar through knots `(t_i, y_i)`.
#[derive(Debug, Clone, PartialEq)]
pub struct CubicSpline {
    times: Vec<Time>,
    values: Vec<f64>,
    /// Second derivatives at the knots, `M_i`.
    second: Vec<f64>,
}

impl CubicSpline {
    /// Builds the natural cubic spline through `(times[i], values[i])`.
    ///
    /// # Errors
    /// [`TrajError::TooFewKnots`] for fewer than 2 knots, [`TrajError::LengthMismatch`]
    /// when the slices differ in length, [`TrajError::Core`] when a time or value is
    /// not finite or the times do not strictly increase.
    pub fn new(times: &[Time], values: &[f64]) -> Result<Self, TrajError> {
        if times.len() != values.len() {
            return Err(TrajError::LengthMismatch {
                times: times.len(),
                values: values.len(),
            });
        }
        if times.len() < 2 {
            return Err(TrajError::TooFewKnots { got: times.len() });
        }
        ensure_strictly_increasing("spline knot times", times)?;
        ensure_finite("spline knot values", values.iter())?;
        let second = natural_second_derivatives(times, values);
        Ok(Self {
            times: times.to_vec(),
            values: values.to_vec(),
            second,
        })
    }

    /// Knot times, s.
    pub fn times(&self) -> &[Time] {
        &self.times
    }

    /// Knot values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Second derivatives at the knots (`M_i`; the first and last are 0).
    pub fn second_derivatives(&self) -> &[f64] {
        &self.second
    }

    /// First knot time, s.
    pub fn start_time(&self) -> Time {
        self.times[0]
    }

    /// Last knot time, s.
    pub fn end_time(&self) -> Time {
        self.times[self.times.len() - 1]
    }

    /// Value and analytic first/second derivatives at `t`.
    ///
    /// # Errors
    /// [`TrajError::OutOfRange`] when `t` is not finite or outside
    /// `[start_time, end_time]`.
    pub fn eval(&self, t: Time) -> Result<SplinePoint, TrajError> {
        let seg = self.segment(t)?;
        Ok(self.eval_segment(seg, t))
    }

    /// `S(t)`; see [`CubicSpline::eval`] for errors.
    ///
    /// # Errors
    /// As [`CubicSpline::eval`].
    pub fn value(&self, t: Time) -> Result<f64, TrajError> {
        self.eval(t).map(|p| p.value)
    }

    /// `S'(t)`; see [`CubicSpline::eval`] for errors.
    ///
    /// # Errors
    /// As [`CubicSpline::eval`].
    pub fn derivative(&self, t: Time) -> Result<f64, TrajError> {
        self.eval(t).map(|p| p.d1)
    }

    /// `S''(t)`; see [`CubicSpline::eval`] for errors.
    ///
    /// # Errors
    /// As [`CubicSpline::eval`].
    pub fn second_derivative(&self, t: Time) -> Result<f64, TrajError> {
        self.eval(t).map(|p| p.d2)
    }

    /// Index `i` of the segment `[t_i, t_{i+1}]` holding `t` (the last segment
    /// holds the end time).
    fn segment(&self, t: Time) -> Result<usize, TrajError> {
        let (start, end) = (self.start_time(), self.end_time());
        if !(t >= start && t <= end) {
            return Err(TrajError::OutOfRange { t, start, end });
        }
        // Number of knots <= t, minus one, clamped to the last segment.
        let n_le = self.times.partition_point(|&k| k <= t);
        Ok((n_le.max(1) - 1).min(self.times.len() - 2))
    }

    /// Evaluates the cubic of segment `seg` at `t` (no range check; `t` may lie
    /// outside the segment, which gives the polynomial's continuation).
    fn eval_segment(&self, seg: usize, t: Time) -> SplinePoint {
        let (t0, t1) = (self.times[seg], self.times[seg + 1]);
        let (y0, y1) = (self.values[seg], self.values[seg + 1]);
        let (m0, m1) = (self.second[seg], self.second[seg + 1]);
        let h = t1 - t0;
        let a = t1 - t;
        let b = t - t0;
        let c0 = y0 / h - m0 * h / 6.0;
        let c1 = y1 / h - m1 * h / 6.0;
        SplinePoint {
            value: m0 * a * a * a / (6.0 * h) + m1 * b * b * b / (6.0 * h) + c0 * a + c1 * b,
            d1: -m0 * a * a / (2.0 * h) + m1 * b * b / (2.0 * h) - c0 + c1,
            d2: (m0 * a + m1 * b) / h,
        }
    }
}

/// Solves the natural-spline tridiagonal system for the knot second derivatives
/// (Thomas algorithm, O(n)). Inputs are already checked (n >= 2, increasing times).
fn natural_second_derivatives(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = t.len();
    let mut m = vec![0.0; n];
    if n < 3 {
        return m;
    }
    // Unknowns M_1..M_{n-2}; k indexes them from 0.
    let k_len = n - 2;
    let mut sub = vec![0.0; k_len]; // sub-diagonal (a_k multiplies M_{k-1})
    let mut diag = vec![0.0; k_len];
    let mut sup = vec![0.0; k_len]; // super-diagonal (c_k multiplies M_{k+1})
    let mut rhs = vec![0.0; k_len];
    for k in 0..k_len {
        let i = k + 1;
        let h0 = t[i] - t[i - 1];
        let h1 = t[i + 1] - t[i];
        sub[k] = h0;
        diag[k] = 2.0 * (h0 + h1);
        sup[k] = h1;
        rhs[k] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
    }
    // Forward sweep.
    for k in 1..k_len {
        let w = sub[k] / diag[k - 1];
        diag[k] -= w * sup[k - 1];
        rhs[k] -= w * rhs[k - 1];
    }
    // Back substitution.
    let mut x = vec![0.0; k_len];
    x[k_len - 1] = rhs[k_len - 1] / diag[k_len - 1];
    for k in (0..k_len - 1).rev() {
        x[k] = (rhs[k] - sup[k] * x[k + 1]) / diag[k];
    }
    m[1..n - 1].copy_from_slice(&x);
    m
}

/// Natural cubic spline of a 3-vector: one independent [`CubicSpline`] per axis
/// over the same knot times.
#[derive(Debug, Clone, PartialEq)]
pub struct CubicSpline3 {
    axes: [CubicSpline; 3],
}

impl CubicSpline3 {
    /// Builds the per-axis natural cubic splines through `(times[i], points[i])`.
    ///
    /// # Errors
    /// As [`CubicSpline::new`]; a non-finite coordinate is reported with the knot
    /// index and the axis in the `what` text.
    pub fn new(times: &[Time], points: &[Vector3<f64>]) -> Result<Self, TrajError> {
        if times.len() != points.len() {
            return Err(TrajError::LengthMismatch {
                times: times.len(),
                values: points.len(),
            });
        }
        let axis = |a: usize, name: &str| -> Result<CubicSpline, TrajError> {
            let vals: Vec<f64> = points.iter().map(|p| p[a]).collect();
            ensure_finite(&format!("spline knot values ({name} axis)"), vals.iter())?;
            CubicSpline::new(times, &vals)
        };
        Ok(Self {
            axes: [axis(0, "x")?, axis(1, "y")?, axis(2, "z")?],
        })
    }

    /// The scalar spline of axis `0`, `1` or `2` (x, y, z); `None` for other indices.
    pub fn axis(&self, index: usize) -> Option<&CubicSpline> {
        self.axes.get(index)
    }

    /// Knot times, s.
    pub fn times(&self) -> &[Time] {
        self.axes[0].times()
    }

    /// Knot points.
    pub fn points(&self) -> Vec<Vector3<f64>> {
        (0..self.axes[0].values().len())
            .map(|i| {
                Vector3::new(
                    self.axes[0].values()[i],
                    self.axes[1].values()[i],
                    self.axes[2].values()[i],
                )
            })
            .collect()
    }

    /// First knot time, s.
    pub fn start_time(&self) -> Time {
        self.axes[0].start_time()
    }

    /// Last knot time, s.
    pub fn end_time(&self) -> Time {
        self.axes[0].end_time()
    }

    /// Value and analytic first/second derivatives of all three axes at `t`.
    ///
    /// # Errors
    /// [`TrajError::OutOfRange`] when `t` is not finite or outside the knot range.
    pub fn eval(&self, t: Time) -> Result<SplinePoint3, TrajError> {
        let seg = self.axes[0].segment(t)?;
        let p = [
            self.axes[0].eval_segment(seg, t),
            self.axes[1].eval_segment(seg, t),
            self.axes[2].eval_segment(seg, t),
        ];
        Ok(SplinePoint3 {
            value: Vector3::new(p[0].value, p[1].value, p[2].value),
            d1: Vector3::new(p[0].d1, p[1].d1, p[2].d1),
            d2: Vector3::new(p[0].d2, p[1].d2, p[2].d2),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::{assert_abs_diff_eq, assert_relative_eq};
    use fathom_core::CoreError;

    fn sample() -> CubicSpline {
        let t = [0.0, 0.7, 2.0, 2.5, 4.1, 6.0];
        let y = [1.0, -2.0, 0.5, 3.0, 2.2, -1.0];
        CubicSpline::new(&t, &y).unwrap()
    }

    #[test]
    fn passes_through_every_knot() {
        let s = sample();
        for (&t, &y) in s.times().iter().zip(s.values()) {
            assert_relative_eq!(s.value(t).unwrap(), y, epsilon = 1e-12);
        }
    }

    #[test]
    fn c2_at_interior_knots() {
        let s = sample();
        for i in 1..s.times().len() - 1 {
            let t = s.times()[i];
            let left = s.eval_segment(i - 1, t);
            let right = s.eval_segment(i, t);
            assert_abs_diff_eq!(left.value, right.value, epsilon = 1e-12);
            assert_abs_diff_eq!(left.d1, right.d1, epsilon = 1e-12);
            assert_abs_diff_eq!(left.d2, right.d2, epsilon = 1e-12);
        }
    }

    #[test]
    fn natural_ends_have_zero_curvature() {
        let s = sample();
        assert_abs_diff_eq!(s.second_derivative(0.0).unwrap(), 0.0, epsilon = 1e-14);
        assert_abs_diff_eq!(s.second_derivative(6.0).unwrap(), 0.0, epsilon = 1e-14);
        // And the interior is genuinely curved (the test could fail).
        assert!(s.second_derivatives()[2].abs() > 0.1);
    }

    #[test]
    fn reproduces_linear_function_exactly() {
        let t = [0.0, 1.0, 1.5, 4.0, 7.25];
        let y: Vec<f64> = t.iter().map(|&t| 3.0 - 0.5 * t).collect();
        let s = CubicSpline::new(&t, &y).unwrap();
        for k in 0..=100 {
            let tt = 7.25 * k as f64 / 100.0;
            let p = s.eval(tt).unwrap();
            assert_abs_diff_eq!(p.value, 3.0 - 0.5 * tt, epsilon = 1e-12);
            assert_abs_diff_eq!(p.d1, -0.5, epsilon = 1e-12);
            assert_abs_diff_eq!(p.d2, 0.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn two_knots_is_a_line() {
        let s = CubicSpline::new(&[1.0, 3.0], &[2.0, 6.0]).unwrap();
        let p = s.eval(2.5).unwrap();
        assert_relative_eq!(p.value, 5.0, epsilon = 1e-14);
        assert_relative_eq!(p.d1, 2.0, epsilon = 1e-14);
        assert_abs_diff_eq!(p.d2, 0.0, epsilon = 1e-14);
    }

    #[test]
    fn derivatives_match_central_differences() {
        let s = sample();
        let h = 1e-5;
        for &t in &[0.3, 1.1, 2.2, 3.0, 5.5] {
            let p = s.eval(t).unwrap();
            let fd1 = (s.value(t + h).unwrap() - s.value(t - h).unwrap()) / (2.0 * h);
            let fd2 = (s.derivative(t + h).unwrap() - s.derivative(t - h).unwrap()) / (2.0 * h);
            assert_relative_eq!(p.d1, fd1, epsilon = 1e-6, max_relative = 1e-6);
            assert_relative_eq!(p.d2, fd2, epsilon = 1e-6, max_relative = 1e-6);
        }
    }

    #[test]
    fn vector_spline_matches_scalar_splines() {
        let t = [0.0, 1.0, 2.0, 3.5];
        let pts = [
            Vector3::new(0.0, 1.0, 2.0),
            Vector3::new(1.0, -1.0, 2.5),
            Vector3::new(3.0, 0.0, 2.0),
            Vector3::new(2.0, 4.0, 1.0),
        ];
        let s3 = CubicSpline3::new(&t, &pts).unwrap();
        let sy = CubicSpline::new(&t, &[1.0, -1.0, 0.0, 4.0]).unwrap();
        let p = s3.eval(2.7).unwrap();
        let q = sy.eval(2.7).unwrap();
        assert_relative_eq!(p.value.y, q.value, epsilon = 1e-14);
        assert_relative_eq!(p.d1.y, q.d1, epsilon = 1e-14);
        assert_relative_eq!(p.d2.y, q.d2, epsilon = 1e-14);
        assert_eq!(s3.points(), pts.to_vec());
    }

    #[test]
    fn construction_errors() {
        assert_eq!(
            CubicSpline::new(&[1.0], &[2.0]).unwrap_err(),
            TrajError::TooFewKnots { got: 1 }
        );
        assert_eq!(
            CubicSpline::new(&[0.0, 1.0], &[2.0]).unwrap_err(),
            TrajError::LengthMismatch {
                times: 2,
                values: 1
            }
        );
        assert!(matches!(
            CubicSpline::new(&[0.0, 1.0, 1.0], &[0.0, 1.0, 2.0]).unwrap_err(),
            TrajError::Core(CoreError::NonIncreasingTime { index: 2, .. })
        ));
        assert!(matches!(
            CubicSpline::new(&[0.0, 2.0, 1.0], &[0.0, 1.0, 2.0]).unwrap_err(),
            TrajError::Core(CoreError::NonIncreasingTime { index: 2, .. })
        ));
        assert!(matches!(
            CubicSpline::new(&[0.0, f64::NAN], &[0.0, 1.0]).unwrap_err(),
            TrajError::Core(CoreError::NonFinite { index: 1, .. })
        ));
        assert!(matches!(
            CubicSpline::new(&[0.0, 1.0], &[f64::INFINITY, 1.0]).unwrap_err(),
            TrajError::Core(CoreError::NonFinite { index: 0, .. })
        ));
        let bad = [Vector3::zeros(), Vector3::new(0.0, 0.0, f64::NAN)];
        let err = CubicSpline3::new(&[0.0, 1.0], &bad).unwrap_err();
        assert!(err.to_string().contains("z axis"), "{err}");
        assert!(matches!(
            CubicSpline3::new(&[0.0, 1.0], &[Vector3::zeros()]).unwrap_err(),
            TrajError::LengthMismatch { .. }
        ));
    }

    #[test]
    fn evaluation_outside_range_is_an_error() {
        let s = sample();
        for t in [-1e-9, 6.0 + 1e-9, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                s.eval(t).unwrap_err(),
                TrajError::OutOfRange {
                    start: 0.0,
                    end: 6.0,
                    ..
                }
            ));
        }
        assert!(s.eval(0.0).is_ok());
        assert!(s.eval(6.0).is_ok());
    }
}

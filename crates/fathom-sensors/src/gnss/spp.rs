//! Least-squares single-point positioning (SPP) from pseudoranges, with the dilution
//! of precision.
//!
//! Unknowns: the receiver's ECEF position and clock bias (m). Gauss-Newton on
//! `rho_k = |s_k - x| + b` from the scenario origin: `H = [-u_k^T 1]`,
//! `dx = (H^T H)^-1 H^T (rho - rho_hat)`, until the step is below 1e-6 m (at most 20
//! iterations; convergence is quadratic, so the error left is far smaller). DOP from `Q = (H^T H)^-1` with `H` in local NED at the solution:
//! `GDOP = sqrt(tr Q)`, `PDOP = sqrt(Q_nn + Q_ee + Q_dd)`, `HDOP = sqrt(Q_nn + Q_ee)`,
//! `VDOP = sqrt(Q_dd)`, `TDOP = sqrt(Q_bb)`.

use nalgebra::{Matrix4, Vector3, Vector4};

use crate::SensorError;
use crate::gnss::geodesy::LocalFrame;

/// Dilution of precision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dop {
    /// Geometric.
    pub gdop: f64,
    /// Position (3-D).
    pub pdop: f64,
    /// Horizontal.
    pub hdop: f64,
    /// Vertical.
    pub vdop: f64,
    /// Time (clock).
    pub tdop: f64,
}

impl Dop {
    /// DOP of unit line-of-sight vectors (receiver to satellite, NED).
    ///
    /// # Errors
    /// [`SensorError::InvalidParameter`] when fewer than 4 vectors are given or the
    /// geometry is singular.
    pub fn from_los(los_in_nav: &[Vector3<f64>]) -> Result<Self, SensorError> {
        let q = cofactor(los_in_nav)?;
        Ok(Self {
            gdop: q.trace().sqrt(),
            pdop: (q[(0, 0)] + q[(1, 1)] + q[(2, 2)]).sqrt(),
            hdop: (q[(0, 0)] + q[(1, 1)]).sqrt(),
            vdop: q[(2, 2)].sqrt(),
            tdop: q[(3, 3)].sqrt(),
        })
    }
}

/// `(H^T H)^-1` with rows `[-u^T, 1]`.
fn cofactor(los: &[Vector3<f64>]) -> Result<Matrix4<f64>, SensorError> {
    if los.len() < 4 {
        return Err(SensorError::InvalidParameter {
            field: "spp.satellites".into(),
            value: los.len() as f64,
            reason: "at least 4 pseudoranges are needed",
        });
    }
    let mut hth = Matrix4::zeros();
    for u in los {
        let h = Vector4::new(-u.x, -u.y, -u.z, 1.0);
        hth += h * h.transpose();
    }
    hth.try_inverse()
        .filter(|q| q.iter().all(|x| x.is_finite()) && (0..4).all(|i| q[(i, i)] > 0.0))
        .ok_or_else(|| SensorError::InvalidParameter {
            field: "spp.geometry".into(),
            value: los.len() as f64,
            reason: "the satellite geometry is singular",
        })
}

/// A single-point solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SppSolution {
    /// Position, ECEF, m.
    pub pos_ecef: Vector3<f64>,
    /// Position, local NED, m.
    pub pos_in_nav: Vector3<f64>,
    /// Receiver clock bias, m.
    pub clock_bias_m: f64,
    /// Dilution of precision at the solution.
    pub dop: Dop,
    /// Pseudoranges used.
    pub used: usize,
    /// Gauss-Newton iterations.
    pub iterations: usize,
    /// RMS of the post-fit residuals, m.
    pub residual_rms_m: f64,
}

/// Solves for position and clock from `(satellite ECEF position, pseudorange)` pairs,
/// starting at the frame's origin.
///
/// # Errors
/// [`SensorError::InvalidParameter`] with fewer than 4 pairs, non-finite inputs, a
/// singular geometry, or no convergence in 20 iterations.
pub fn solve_spp(
    frame: &LocalFrame,
    pairs: &[(Vector3<f64>, f64)],
) -> Result<SppSolution, SensorError> {
    if pairs
        .iter()
        .any(|(s, rho)| !rho.is_finite() || s.iter().any(|c| !c.is_finite()))
    {
        return Err(SensorError::InvalidParameter {
            field: "spp.pseudoranges".into(),
            value: f64::NAN,
            reason: "satellite positions and pseudoranges must be finite",
        });
    }
    let mut x = frame.origin_ecef();
    let mut b = 0.0;
    for iteration in 1..=20 {
        let los: Vec<Vector3<f64>> = pairs.iter().map(|(s, _)| (s - x).normalize()).collect();
        let q = cofactor(&los)?;
        let mut hty = Vector4::zeros();
        for ((s, rho), u) in pairs.iter().zip(&los) {
            let y = rho - ((s - x).norm() + b);
            hty += Vector4::new(-u.x, -u.y, -u.z, 1.0) * y;
        }
        let dx = q * hty;
        x += dx.xyz();
        b += dx.w;
        if dx.xyz().norm() < 1e-6 && dx.w.abs() < 1e-6 {
            let los_nav: Vec<Vector3<f64>> = pairs
                .iter()
                .map(|(s, _)| frame.ned_from_ecef() * (s - x).normalize())
                .collect();
            let ss: f64 = pairs
                .iter()
                .map(|(s, rho)| (rho - (s - x).norm() - b).powi(2))
                .sum();
            return Ok(SppSolution {
                pos_ecef: x,
                pos_in_nav: frame.ned_from_ecef_point(&x),
                clock_bias_m: b,
                dop: Dop::from_los(&los_nav)?,
                used: pairs.len(),
                iterations: iteration,
                residual_rms_m: (ss / pairs.len() as f64).sqrt(),
            });
        }
    }
    Err(SensorError::InvalidParameter {
        field: "spp.iterations".into(),
        value: 20.0,
        reason: "least squares did not converge",
    })
}

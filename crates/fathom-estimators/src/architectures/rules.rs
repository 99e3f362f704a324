//! Track-to-track fusion rules for two estimates of the same state:
//!
//! - [`FusionRule::Independent`]: paper A eq. (10), cross-covariance ignored
//!   ([`crate::fuse_information`]);
//! - [`FusionRule::BarShalomCampo`]: the optimal linear combination for a known
//!   cross-covariance `P12` (Bar-Shalom & Campo 1986), with `P12` propagated by the
//!   track-to-track architecture;
//! - [`FusionRule::CovarianceIntersection`]: consistent for any unknown
//!   cross-covariance (Julier & Uhlmann 1997), weight chosen to minimise `trace P`.

use crate::EstimatorError;
use fathom_core::{
    CoreError, Gaussian,
    error::ensure_finite,
    gaussian::{check_covariance, symmetrize},
};
use nalgebra::SMatrix;

/// How [`crate::architectures::TrackToTrack`] combines its two corrected estimates.
#[derive(Debug, Clone, PartialEq)]
pub enum FusionRule<const N: usize> {
    /// Paper A eq. (10): `P = (P1^-1 + P2^-1)^-1`, `x = P (P1^-1 x1 + P2^-1 x2)`;
    /// the tracks are treated as independent.
    Independent,
    /// Bar-Shalom–Campo fusion with the cross-covariance propagated by the
    /// recursion `P12 <- (I - K1 H1) (F1 P12 F2^T + Q12) (I - K2 H2)^T`.
    BarShalomCampo {
        /// `Q12`: cross-covariance of the two tracks' process noises (both model the
        /// same motion). For scaled-identity tunings `Q_i = w_i^2 I`, the choice
        /// `Q12 = w1 w2 I` treats the process noise as one common disturbance seen
        /// with two scales (see [`FusionRule::bar_shalom_campo_common_noise`]).
        process_cross_cov: SMatrix<f64, N, N>,
    },
    /// Covariance intersection, `P^-1 = w P1^-1 + (1 - w) P2^-1`, with `w` in `[0, 1]`
    /// minimising `trace P`.
    CovarianceIntersection,
}

impl<const N: usize> FusionRule<N> {
    /// Short name of the rule (for messages and tables).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Independent => "eq. (10)",
            Self::BarShalomCampo { .. } => "Bar-Shalom-Campo",
            Self::CovarianceIntersection => "covariance intersection",
        }
    }

    /// Bar-Shalom–Campo with `Q12 = sqrt(Q1) sqrt(Q2)` entrywise on the diagonal
    /// (`Q12_ii = sqrt(Q1_ii Q2_ii)`, zero elsewhere): one common process disturbance
    /// seen by both tracks with their own scales. Exact for diagonal `Q1`, `Q2`; the
    /// joint process covariance `[Q1 Q12; Q12 Q2]` is then positive semi-definite.
    pub fn bar_shalom_campo_common_noise(q1: &SMatrix<f64, N, N>, q2: &SMatrix<f64, N, N>) -> Self {
        let mut q12 = SMatrix::<f64, N, N>::zeros();
        for i in 0..N {
            q12[(i, i)] = (q1[(i, i)].max(0.0) * q2[(i, i)].max(0.0)).sqrt();
        }
        Self::BarShalomCampo {
            process_cross_cov: q12,
        }
    }
}

/// Bar-Shalom–Campo fusion of `a` and `b` with cross-covariance
/// `p_ab = E[(x_a - x)(x_b - x)^T]`:
///
/// `U = P_a + P_b - P_ab - P_ab^T`, `K = (P_a - P_ab) U^-1`, `x = x_a + K (x_b - x_a)`,
/// and `P` the exact covariance of `(I - K) x_a + K x_b`:
/// `P = (I-K) P_a (I-K)^T + K P_b K^T + (I-K) P_ab K^T + K P_ab^T (I-K)^T`
/// (equal to `P_a - (P_a - P_ab) U^-1 (P_a - P_ab)^T`, but positive semi-definite by
/// construction). With `p_ab = 0` this is eq. (10).
///
/// # Errors
/// [`EstimatorError::Core`]: non-finite inputs, input covariances not SPD, `U` not
/// positive definite (the estimates are fully correlated), or a fused covariance
/// that is not positive definite.
pub fn fuse_bar_shalom_campo<const N: usize>(
    a: &Gaussian<N>,
    b: &Gaussian<N>,
    p_ab: &SMatrix<f64, N, N>,
) -> Result<Gaussian<N>, EstimatorError> {
    ensure_finite("fusion input a mean", a.mean().iter())?;
    ensure_finite("fusion input b mean", b.mean().iter())?;
    ensure_finite("fusion cross-covariance P_ab", p_ab.iter())?;
    check_covariance("fusion input a covariance", a.cov())?;
    check_covariance("fusion input b covariance", b.cov())?;
    let (pa, pb) = (a.cov(), b.cov());
    let u = symmetrize(&(pa + pb - p_ab - p_ab.transpose()));
    let chol = u.cholesky().ok_or_else(|| CoreError::NotPositiveDefinite {
        what: "Bar-Shalom-Campo U = Pa + Pb - Pab - Pba".into(),
    })?;
    // K^T = U^-1 (Pa - Pab)^T.
    let k = chol.solve(&(pa - p_ab).transpose()).transpose();
    let x = a.mean() + k * (b.mean() - a.mean());
    let i_k = SMatrix::<f64, N, N>::identity() - k;
    let cross = i_k * p_ab * k.transpose();
    let p = symmetrize(
        &(i_k * pa * i_k.transpose() + k * pb * k.transpose() + cross + cross.transpose()),
    );
    Ok(Gaussian::new(x, p).map_err(|e| match e {
        CoreError::NotPositiveDefinite { .. } => CoreError::NotPositiveDefinite {
            what: "Bar-Shalom-Campo fused covariance".into(),
        },
        other => other,
    })?)
}

/// Covariance-intersection fusion of `a` and `b`: `P^-1 = w P_a^-1 + (1 - w) P_b^-1`,
/// `x = P (w P_a^-1 x_a + (1 - w) P_b^-1 x_b)`, with `w` in `[0, 1]` minimising
/// `trace P` (trace in closed form from one generalized eigendecomposition, then a
/// golden-section search, [`CI_ITERATIONS`] iterations, i.e. `w` to about 1e-12,
/// and the endpoints are compared; fully deterministic). Returns the fused
/// estimate and `w`; `w = 1` gives `a`, `w = 0` gives `b` exactly.
///
/// # Errors
/// [`EstimatorError::Core`] for non-finite inputs or covariances that are not SPD.
pub fn fuse_covariance_intersection<const N: usize>(
    a: &Gaussian<N>,
    b: &Gaussian<N>,
) -> Result<(Gaussian<N>, f64), EstimatorError> {
    ensure_finite("fusion input a mean", a.mean().iter())?;
    ensure_finite("fusion input b mean", b.mean().iter())?;
    check_covariance("fusion input a covariance", a.cov())?;
    check_covariance("fusion input b covariance", b.cov())?;
    let info = |g: &Gaussian<N>, what: &str| {
        g.cov()
            .cholesky()
            .map(|c| symmetrize(&c.inverse()))
            .ok_or_else(|| CoreError::NotPositiveDefinite { what: what.into() })
    };
    let (ia, ib) = (info(a, "fusion input a")?, info(b, "fusion input b")?);
    // P(w) via the Cholesky factor of the fused information matrix.
    let fused_cov = |w: f64| -> Option<SMatrix<f64, N, N>> {
        symmetrize(&(ia * w + ib * (1.0 - w)))
            .cholesky()
            .map(|c| c.inverse())
    };
    // trace P(w) in closed form: with I_b = L L^T and L^-1 I_a L^-T = V diag(l) V^T,
    // P(w) = L^-T V diag(1 / (1 + w (l_i - 1))) V^T L^-1, so
    // trace P(w) = sum_i c_i / (1 + w (l_i - 1)) with c_i = |L^-T v_i|^2.
    let lb = ib
        .cholesky()
        .ok_or_else(|| CoreError::NotPositiveDefinite {
            what: "fusion input b information".into(),
        })?
        .l();
    let lb_inv_ia =
        lb.solve_lower_triangular(&ia)
            .ok_or_else(|| CoreError::NotPositiveDefinite {
                what: "covariance-intersection whitening".into(),
            })?;
    let m = lb
        .solve_lower_triangular(&lb_inv_ia.transpose())
        .ok_or_else(|| CoreError::NotPositiveDefinite {
            what: "covariance-intersection whitening".into(),
        })?;
    // Dynamic-size eigendecomposition (nalgebra's fixed-size one needs typenum
    // bounds a const-generic N cannot express); once per fusion, N x N.
    let eig =
        nalgebra::DMatrix::from_iterator(N, N, symmetrize(&m).iter().copied()).symmetric_eigen();
    let vectors = SMatrix::<f64, N, N>::from_iterator(eig.eigenvectors.iter().copied());
    let lt_inv_v = lb
        .transpose()
        .solve_upper_triangular(&vectors)
        .ok_or_else(|| CoreError::NotPositiveDefinite {
            what: "covariance-intersection whitening".into(),
        })?;
    let coef: Vec<(f64, f64)> = (0..N)
        .map(|i| (lt_inv_v.column(i).norm_squared(), eig.eigenvalues[i]))
        .collect();
    let cost = |w: f64| -> f64 {
        if w >= 1.0 {
            a.cov().trace()
        } else if w <= 0.0 {
            b.cov().trace()
        } else {
            coef.iter()
                .map(|(c, l)| c / (1.0 + w * (l - 1.0)))
                .sum::<f64>()
        }
    };
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    let mut c = hi - ratio * (hi - lo);
    let mut d = lo + ratio * (hi - lo);
    let (mut fc, mut fd) = (cost(c), cost(d));
    for _ in 0..CI_ITERATIONS {
        if fc <= fd {
            hi = d;
            d = c;
            fd = fc;
            c = hi - ratio * (hi - lo);
            fc = cost(c);
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + ratio * (hi - lo);
            fd = cost(d);
        }
    }
    let mut best = (0.5 * (lo + hi), cost(0.5 * (lo + hi)));
    for w in [0.0, 1.0] {
        let cw = cost(w);
        if cw < best.1 {
            best = (w, cw);
        }
    }
    let w = best.0;
    if w >= 1.0 {
        return Ok((a.clone(), 1.0));
    }
    if w <= 0.0 {
        return Ok((b.clone(), 0.0));
    }
    let p = fused_cov(w).ok_or_else(|| CoreError::NotPositiveDefinite {
        what: "covariance-intersection information matrix".into(),
    })?;
    let p = symmetrize(&p);
    let x = p * (ia * a.mean() * w + ib * b.mean() * (1.0 - w));
    Ok((Gaussian::new(x, p)?, w))
}

/// Golden-section iterations of [`fuse_covariance_intersection`] (`0.618^60` is
/// about `3e-13` of the unit interval).
pub const CI_ITERATIONS: usize = 60;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fuse_information;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix2, Vector2};

    fn g(x: Vector2<f64>, p: Matrix2<f64>) -> Gaussian<2> {
        Gaussian::new(x, p).unwrap()
    }

    #[test]
    fn bar_shalom_campo_with_zero_cross_cov_is_eq_10() {
        let a = g(Vector2::new(1.0, -1.0), Matrix2::new(2.0, 0.5, 0.5, 1.0));
        let b = g(Vector2::new(2.0, 0.5), Matrix2::new(1.0, -0.3, -0.3, 4.0));
        let bc = fuse_bar_shalom_campo(&a, &b, &Matrix2::zeros()).unwrap();
        let eq10 = fuse_information(&a, &b).unwrap();
        assert_relative_eq!(*bc.mean(), *eq10.mean(), epsilon = 1e-12);
        assert_relative_eq!(*bc.cov(), *eq10.cov(), epsilon = 1e-12);
    }

    #[test]
    fn bar_shalom_campo_scalar_by_hand() {
        // Pa = 4, Pb = 1, Pab = 1: U = 4 + 1 - 2 = 3, K = (4 - 1)/3 = 1,
        // x = xa + (xb - xa) = xb, P = Pa - (Pa - Pab)^2 / U = 4 - 9/3 = 1.
        // Pab = 0.5: U = 4, K = 3.5/4 = 0.875, P = 4 - 3.5^2/4 = 0.9375.
        let a = Gaussian::new(nalgebra::Vector1::new(0.0), nalgebra::Matrix1::new(4.0)).unwrap();
        let b = Gaussian::new(nalgebra::Vector1::new(8.0), nalgebra::Matrix1::new(1.0)).unwrap();
        let f = fuse_bar_shalom_campo(&a, &b, &nalgebra::Matrix1::new(0.5)).unwrap();
        assert_relative_eq!(f.mean()[0], 7.0, epsilon = 1e-12);
        assert_relative_eq!(f.cov()[(0, 0)], 0.9375, epsilon = 1e-12);
        // Correlation lowers the gain of the better track less than eq. (10) would
        // suggest: eq. (10) gives P = 0.8, BC honestly reports more.
        let eq10 = fuse_information(&a, &b).unwrap();
        assert!(f.cov()[(0, 0)] > eq10.cov()[(0, 0)]);
        // Fully correlated equal estimates: U is singular, an error.
        let same = fuse_bar_shalom_campo(&a, &a, &nalgebra::Matrix1::new(4.0));
        assert!(same.is_err());
    }

    #[test]
    fn covariance_intersection_properties() {
        let a = g(Vector2::new(1.0, 0.0), Matrix2::new(1.0, 0.0, 0.0, 9.0));
        let b = g(Vector2::new(0.0, 1.0), Matrix2::new(9.0, 0.0, 0.0, 1.0));
        let (f, w) = fuse_covariance_intersection(&a, &b).unwrap();
        // Symmetric problem: w = 1/2, P^-1 = diag(5/9, 5/9), P = 1.8 I.
        assert_relative_eq!(w, 0.5, epsilon = 1e-6);
        assert_relative_eq!(*f.cov(), Matrix2::identity() * 1.8, epsilon = 1e-6);
        assert_relative_eq!(*f.mean(), Vector2::new(0.9, 0.9), epsilon = 1e-6);
        // CI is never more confident than eq. (10).
        let eq10 = fuse_information(&a, &b).unwrap();
        assert!(f.cov().trace() > eq10.cov().trace());
        // A dominant estimate: CI picks it alone (w = 1).
        let tiny = g(Vector2::new(5.0, 5.0), Matrix2::identity() * 1e-4);
        let (f, w) = fuse_covariance_intersection(&tiny, &b).unwrap();
        assert!(w > 0.99, "{w}");
        assert!((f.mean() - tiny.mean()).norm() < 1e-3);
        // Correlated inputs: the optimum matches a brute-force scan of trace P(w).
        let c = g(Vector2::new(0.0, 0.0), Matrix2::new(2.0, 0.7, 0.7, 1.0));
        let d = g(Vector2::new(1.0, 2.0), Matrix2::new(1.5, -0.4, -0.4, 3.0));
        let (fcd, w) = fuse_covariance_intersection(&c, &d).unwrap();
        let tr = |w: f64| {
            let i = c.cov().try_inverse().unwrap() * w + d.cov().try_inverse().unwrap() * (1.0 - w);
            i.try_inverse().unwrap().trace()
        };
        let best = (1..1000)
            .map(|k| tr(k as f64 / 1000.0))
            .fold(f64::INFINITY, f64::min);
        assert!(fcd.cov().trace() <= best + 1e-9);
        assert_relative_eq!(fcd.cov().trace(), tr(w), epsilon = 1e-10);
        let bad = Gaussian::new_unchecked(Vector2::zeros(), Matrix2::new(1.0, 2.0, 2.0, 1.0));
        assert!(fuse_covariance_intersection(&a, &bad).is_err());
    }

    #[test]
    fn common_noise_cross_cov() {
        let q1 = Matrix2::identity() * 100.0;
        let q2 = Matrix2::identity();
        let FusionRule::BarShalomCampo { process_cross_cov } =
            FusionRule::bar_shalom_campo_common_noise(&q1, &q2)
        else {
            panic!("wrong variant")
        };
        assert_relative_eq!(process_cross_cov, Matrix2::identity() * 10.0);
        assert_eq!(FusionRule::<2>::Independent.name(), "eq. (10)");
    }
}

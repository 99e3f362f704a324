//! Fixed-size kernels of the Kalman core (no allocation): the symmetric covariance
//! prediction `F P F^T + Q`, the Joseph-form update computed for one triangle, and a
//! lean Cholesky positive-definiteness test.
//!
//! Costs (multiply-adds, `N` states, `M` measurements): prediction `N^3 + N^3/2`
//! (`F P`, then the upper triangle of `(F P) F^T`); Joseph update `2 N^2 M + N M^2 +
//! N^2 M / 2`; positive-definiteness test `N^3 / 6` plus `N` square roots. The loops
//! over a column are written as independent multiply-adds (axpy) so that they
//! vectorize; see `docs/performance.md`.

use nalgebra::{SMatrix, SVector};

/// `F P F^T + (Q + Q^T) / 2`: `F P`, then the upper triangle of `(F P) F^T`
/// accumulated column by column and mirrored, so the result is exactly symmetric
/// (the same numbers, to rounding, as symmetrizing the full product).
#[inline]
pub(crate) fn propagate_covariance<const N: usize>(
    f: &SMatrix<f64, N, N>,
    p: &SMatrix<f64, N, N>,
    q: &SMatrix<f64, N, N>,
) -> SMatrix<f64, N, N> {
    let mut out = f * p * f.transpose();
    for j in 0..N {
        for i in 0..=j {
            let v = out[(i, j)] + 0.5 * (q[(i, j)] + q[(j, i)]);
            out[(i, j)] = v;
            out[(j, i)] = v;
        }
    }
    out
}

/// Joseph-form update `P+ = (I - K H) P (I - K H)^T + K R K^T` (Bucy & Joseph;
/// Bar-Shalom et al. eq. 5.2.3-18) in its expanded form
///
/// ```text
/// P+ = P - K (P H^T)^T - (P H^T) K^T + K S K^T = P - K U^T - W K^T,
/// U = P H^T,  W = U - K S,  S = H P H^T + R
/// ```
///
/// which is the same matrix in exact arithmetic for any gain `K`, so it keeps the
/// Joseph form's insensitivity to gain errors (with `K = K* + dK`, the error of `P+`
/// is `dK S dK^T`, second order; `W` is exactly the residual of the gain equation
/// `K S = P H^T`), at `N M^2 + N^2 M` multiply-adds (upper triangle only, mirrored:
/// exactly symmetric) instead of `2 N^3 + ...` for the product form.
#[inline]
pub(crate) fn joseph_update<const N: usize, const M: usize>(
    p: &SMatrix<f64, N, N>,
    pht: &SMatrix<f64, N, M>,
    k: &SMatrix<f64, N, M>,
    s: &SMatrix<f64, M, M>,
) -> SMatrix<f64, N, N> {
    let w = pht - k * s;
    let (ps, us, ks, ws) = (p.as_slice(), pht.as_slice(), k.as_slice(), w.as_slice());
    let mut out = SMatrix::<f64, N, N>::zeros();
    let o = out.as_mut_slice();
    for j in 0..N {
        let mut acc = [0.0_f64; N];
        acc[..=j].copy_from_slice(&ps[j * N..j * N + j + 1]);
        for m in 0..M {
            let (ujm, kjm) = (us[m * N + j], ks[m * N + j]);
            let (kcol, wcol) = (&ks[m * N..m * N + j + 1], &ws[m * N..m * N + j + 1]);
            for ((c, &kv), &wv) in acc[..=j].iter_mut().zip(kcol).zip(wcol) {
                *c -= kv * ujm + wv * kjm;
            }
        }
        for i in 0..=j {
            o[j * N + i] = acc[i];
            o[i * N + j] = acc[i];
        }
    }
    out
}

/// Scalar Joseph update (`M = 1`: row `h`, innovation variance `s`, `pht = P h^T`,
/// gain `k`): [`joseph_update`] with vectors, `O(N^2)`.
#[inline]
pub(crate) fn joseph_update_scalar<const N: usize>(
    p: &SMatrix<f64, N, N>,
    pht: &SVector<f64, N>,
    k: &SVector<f64, N>,
    s: f64,
) -> SMatrix<f64, N, N> {
    let w = pht - k * s;
    let (ps, us, ks, ws) = (p.as_slice(), pht.as_slice(), k.as_slice(), w.as_slice());
    let mut out = SMatrix::<f64, N, N>::zeros();
    let o = out.as_mut_slice();
    for j in 0..N {
        let (uj, kj) = (us[j], ks[j]);
        let mut acc = [0.0_f64; N];
        for i in 0..=j {
            acc[i] = ps[j * N + i] - (ks[i] * uj + ws[i] * kj);
        }
        for i in 0..=j {
            o[j * N + i] = acc[i];
            o[i * N + j] = acc[i];
        }
    }
    out
}

/// Inverse of a symmetric positive-definite `S` (`M x M`, lower triangle read) by an
/// `L D L^T` factorization, exactly symmetric; `None` if a pivot is not `> 0`
/// (or NaN): `S` is not positive definite.
pub(crate) fn spd_inverse<const M: usize>(s: &SMatrix<f64, M, M>) -> Option<SMatrix<f64, M, M>> {
    let (l, d) = ldl(s)?;
    // L^-1 (unit lower), column by column.
    let mut li = [[0.0_f64; M]; M]; // li[i][j], i >= j
    for j in 0..M {
        li[j][j] = 1.0;
        for i in (j + 1)..M {
            let mut v = 0.0;
            for k in j..i {
                v -= l[i][k] * li[k][j];
            }
            li[i][j] = v;
        }
    }
    // S^-1 = L^-T D^-1 L^-1: (i, j) = sum_{k >= max(i, j)} li[k][i] li[k][j] / d_k.
    let mut out = SMatrix::<f64, M, M>::zeros();
    for j in 0..M {
        for i in 0..=j {
            let mut v = 0.0;
            for k in j..M {
                v += li[k][i] * li[k][j] / d[k];
            }
            out[(i, j)] = v;
            out[(j, i)] = v;
        }
    }
    Some(out)
}

/// `S = L D L^T` (unit lower `L` row-major, pivots `D`), `None` unless every pivot
/// is finite and `> 0`.
fn ldl<const N: usize>(a: &SMatrix<f64, N, N>) -> Option<([[f64; N]; N], [f64; N])> {
    let mut l = [[0.0_f64; N]; N];
    let mut d = [0.0_f64; N];
    for j in 0..N {
        let mut v = [0.0_f64; N]; // v_k = l_jk d_k
        let mut dj = a[(j, j)];
        for k in 0..j {
            v[k] = l[j][k] * d[k];
            dj -= l[j][k] * v[k];
        }
        if !(dj > 0.0 && dj.is_finite()) {
            return None;
        }
        d[j] = dj;
        l[j][j] = 1.0;
        let inv = 1.0 / dj;
        for i in (j + 1)..N {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= l[i][k] * v[k];
            }
            l[i][j] = s * inv;
        }
    }
    Some((l, d))
}

/// Whether the symmetric matrix `a` (lower triangle read) is positive definite:
/// Gaussian elimination without pivoting (right-looking `L D L^T`, no square roots)
/// with every pivot `> 0` (a NaN fails). `N^3 / 6` multiply-adds in independent
/// column updates, one division per column, no allocation.
#[inline]
pub(crate) fn is_positive_definite<const N: usize>(a: &SMatrix<f64, N, N>) -> bool {
    let mut w = *a;
    let ws = w.as_mut_slice();
    for j in 0..N {
        let d = ws[j * N + j];
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let inv = 1.0 / d;
        // Trailing lower triangle: a[r, c] -= a[r, j] a[c, j] / d, c > j, r >= c.
        let (head, tail) = ws.split_at_mut((j + 1) * N);
        let col_j = &head[j * N..];
        for c in (j + 1)..N {
            let f = col_j[c] * inv;
            let dst = &mut tail[(c - j - 1) * N + c..(c - j) * N];
            for (x, &l) in dst.iter_mut().zip(&col_j[c..]) {
                *x -= l * f;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix2, Matrix3, RowSVector};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random<const R: usize, const C: usize>(rng: &mut ChaCha8Rng) -> SMatrix<f64, R, C> {
        SMatrix::from_fn(|_, _| rng.random_range(-1.0..1.0))
    }

    fn spd<const K: usize>(rng: &mut ChaCha8Rng) -> SMatrix<f64, K, K> {
        let a = random::<K, K>(rng);
        a * a.transpose() + SMatrix::<f64, K, K>::identity() * 0.1
    }

    #[test]
    fn prediction_matches_the_full_product() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..20 {
            let (f, p, q) = (
                random::<7, 7>(&mut rng),
                spd::<7>(&mut rng),
                spd::<7>(&mut rng),
            );
            let full = f * p * f.transpose() + q;
            let fast = propagate_covariance(&f, &p, &q);
            assert_eq!(fast, fast.transpose());
            assert_relative_eq!(fast, (full + full.transpose()) * 0.5, epsilon = 1e-12);
        }
    }

    #[test]
    fn joseph_grouping_matches_the_product_form_for_any_gain() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..20 {
            let p = spd::<6>(&mut rng);
            let h = random::<3, 6>(&mut rng);
            let r = spd::<3>(&mut rng);
            // an arbitrary (suboptimal) gain: the Joseph form holds for any K
            let k = random::<6, 3>(&mut rng);
            let pht = p * h.transpose();
            let a = SMatrix::<f64, 6, 6>::identity() - k * h;
            let product = a * p * a.transpose() + k * r * k.transpose();
            let s = h * pht + r;
            let fast = joseph_update(&p, &pht, &k, &s);
            assert_eq!(fast, fast.transpose());
            assert_relative_eq!(fast, product, epsilon = 1e-11);
            // scalar flavour
            let hr: RowSVector<f64, 6> = h.row(0).into_owned();
            let ks: SVector<f64, 6> = k.column(0).into_owned();
            let phts = p * hr.transpose();
            let a1 = SMatrix::<f64, 6, 6>::identity() - ks * hr;
            let prod1 = a1 * p * a1.transpose() + ks * ks.transpose() * 0.7;
            let s1 = (hr * phts)[0] + 0.7;
            let fast1 = joseph_update_scalar(&p, &phts, &ks, s1);
            assert_eq!(fast1, fast1.transpose());
            assert_relative_eq!(fast1, prod1, epsilon = 1e-11);
        }
    }

    #[test]
    fn inverse_matches_nalgebra() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..20 {
            let s = spd::<3>(&mut rng);
            let inv = spd_inverse(&s).unwrap();
            assert_eq!(inv, inv.transpose());
            assert_relative_eq!(
                inv,
                s.try_inverse().unwrap(),
                epsilon = 1e-9,
                max_relative = 1e-9
            );
        }
        assert!(spd_inverse(&Matrix2::new(1.0, 2.0, 2.0, 1.0)).is_none());
    }

    #[test]
    fn positive_definiteness_test_agrees_with_nalgebra() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..200 {
            let a = random::<4, 4>(&mut rng);
            let s = (a + a.transpose()) * 0.5 + SMatrix::<f64, 4, 4>::identity() * 0.8;
            assert_eq!(is_positive_definite(&s), s.cholesky().is_some(), "{s}");
        }
        assert!(is_positive_definite(&Matrix3::<f64>::identity()));
        assert!(!is_positive_definite(&Matrix2::new(4.0, 4.0, 4.0, 4.0))); // singular
        assert!(!is_positive_definite(&Matrix2::new(1.0, 2.0, 2.0, 1.0))); // indefinite
        assert!(!is_positive_definite(&Matrix2::new(
            1.0,
            0.0,
            0.0,
            f64::NAN
        )));
        assert!(!is_positive_definite(&Matrix2::new(
            1.0,
            f64::INFINITY,
            f64::INFINITY,
            1.0
        )));
    }
}

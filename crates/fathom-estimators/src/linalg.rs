//! Fixed-size kernels of the Kalman core (no allocation): the symmetric covariance
//! prediction `F P F^T + Q`, the innovation covariance `S = H P H^T + R` with its
//! solver (closed-form `S^-1` for `M <= 3`, else `L D L^T`: gain and NIS), the
//! Joseph-form update computed for one triangle, the positive-definiteness test, and
//! validity predicates for `Q` and `R` (the exact error is searched for only when a
//! predicate fails, see [`crate::kalman`]). Results that the next step reads are
//! written into the caller's buffer one whole column at a time.
//!
//! The column loops run on explicit vector chunks ([`crate::lanes::Seg`]) of the
//! instruction set the caller was dispatched to ([`crate::simd::dispatch`]).
//!
//! Costs (multiply-adds, `N` states, `M` measurements): prediction `N^3 + N^2 (N + 1)
//! / 2` (`F P`, then the upper triangle of `(F P) F^T`); innovation `N^2 M + N M^2`;
//! gain `N M^2` (product with `adj S`, then `N M` scalings by `1 / det S`; two
//! triangular solves for `M > 3`);
//! Joseph update `N M^2 + N (N + 1) M`; positive-definiteness test `N^3 / 6` and `N /
//! 2` divisions. Matrices are read through their column arrays (`[[f64;
//! rows]; cols]`, nalgebra's storage); loops over whole columns have compile-time
//! lengths and the triangular ones are written out per column (`unrolled_for!`),
//! so the compiler unrolls and vectorizes them. See `docs/performance.md`.

use crate::lanes::{Isa, Seg, blocks};
use fathom_core::gaussian::SYMMETRY_TOLERANCE;
use nalgebra::{ArrayStorage, SMatrix, SVector};

/// (Loops bounded by `$j` are written `0..j + 1`, not `0..=j`: the inclusive range
/// keeps an exhaustion flag that stopped the compiler from unrolling them for `N = 9`.)
///
/// `for $j in 0..$n $body` with the iterations written out one by one (`$j` a
/// literal in each copy) when `$n <= 16`, a plain loop above. Inside, loops bounded
/// by `$j` then have constant trip counts, so the compiler unrolls them and keeps
/// the small arrays in registers; the triangular kernels below (positive-definiteness
/// test, one-triangle products) would otherwise stay generic loops with run-time
/// trip counts (measured: ~4x the instructions of the unrolled test for `N = 6`).
macro_rules! unrolled_for {
    ($j:ident in 0..$n:expr, $body:block) => {
        if $n <= 16 {
            unrolled_for!(@copies $j, $n, $body, 0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15)
        } else {
            for $j in 0..$n $body
        }
    };
    (@copies $j:ident, $n:expr, $body:block, $($k:literal)*) => {{
        $(
            if $k < $n {
                let $j: usize = $k;
                $body
            }
        )*
    }};
}

/// Column-major storage of an `R x C` matrix: `C` columns of length `R`.
type Cols<const R: usize, const C: usize> = [[f64; R]; C];

#[inline(always)]
fn cols<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> &Cols<R, C> {
    &m.data.0
}

#[inline(always)]
fn matrix<const R: usize, const C: usize>(c: Cols<R, C>) -> SMatrix<f64, R, C> {
    SMatrix::from_data(ArrayStorage(c))
}

/// `a x`.
#[inline(always)]
fn scaled<const R: usize>(a: f64, x: &[f64; R]) -> [f64; R] {
    let mut y = [0.0; R];
    for i in 0..R {
        y[i] = a * x[i];
    }
    y
}

/// `y += a x`.
#[inline(always)]
fn axpy<const R: usize>(y: &mut [f64; R], a: f64, x: &[f64; R]) {
    for i in 0..R {
        y[i] += a * x[i];
    }
}

/// `y -= a x`.
#[inline(always)]
fn axmy<const R: usize>(y: &mut [f64; R], a: f64, x: &[f64; R]) {
    for i in 0..R {
        y[i] -= a * x[i];
    }
}

/// `A B` for column arrays: column `j` is `sum_k A[:, k] B[k, j]`, accumulated in
/// `k` order (the order nalgebra's `gemv` uses), one column segment at a time.
#[inline(always)]
fn mul<const R: usize, const K: usize, const C: usize>(
    isa: Isa,
    a: &Cols<R, K>,
    b: &Cols<K, C>,
) -> Cols<R, C> {
    let mut out = [[0.0; R]; C];
    for j in 0..C {
        for rows in blocks(R) {
            let mut col = Seg::mul(isa, &a[0], b[j][0], rows);
            for k in 1..K {
                col.add_mul(isa, &a[k], b[j][k], rows);
            }
            col.store(&mut out[j], rows);
        }
    }
    out
}

/// `A x`, accumulated over the columns of `A` in order.
#[inline(always)]
pub(crate) fn mat_vec<const R: usize, const C: usize>(
    a: &SMatrix<f64, R, C>,
    x: &SVector<f64, C>,
) -> SVector<f64, R> {
    let (a, x) = (cols(a), &cols(x)[0]);
    let mut y = scaled(x[0], &a[0]);
    for k in 1..C {
        axpy(&mut y, x[k], &a[k]);
    }
    matrix([y])
}

/// Innovation `z - H x`, each row accumulated over the columns of `H` in order (the
/// order nalgebra's product uses).
#[inline(always)]
pub(crate) fn innovation_of<const M: usize, const N: usize>(
    z: &SVector<f64, M>,
    h: &SMatrix<f64, M, N>,
    x: &SVector<f64, N>,
) -> SVector<f64, M> {
    let hx = cols(&mat_vec(h, x))[0];
    let mut nu = cols(z)[0];
    for i in 0..M {
        nu[i] -= hx[i];
    }
    matrix([nu])
}

/// Whether every entry is finite: a branch-free reduction (`v * 0` is `+-0` for a
/// finite `v` and NaN for an infinite or NaN one, and a NaN survives every sum),
/// with four independent partial sums.
#[inline(always)]
pub(crate) fn all_finite(data: &[f64]) -> bool {
    let mut acc = [0.0_f64; 4];
    let mut chunks = data.chunks_exact(4);
    for c in &mut chunks {
        for i in 0..4 {
            acc[i] += c[i] * 0.0;
        }
    }
    for (a, &v) in acc.iter_mut().zip(chunks.remainder()) {
        *a += v * 0.0;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) == 0.0
}

/// Predicted covariance `F P F^T + (Q + Q^T) / 2`, written to `p_pred`, and whether
/// `Q` passes the process-noise test of [`crate::kalman`] (non-negative diagonal,
/// symmetric within [`SYMMETRY_TOLERANCE`] relative to the largest diagonal entry;
/// finiteness is not tested here). A bitwise symmetric `Q` (the usual case, found
/// with one integer comparison per pair) is added as it is, which is the same bits
/// as its mean: `0.5 (u + u) = u`; only a `Q` that is not takes the tolerance test
/// and the mean (measured: the 6-state prediction 69 -> 59 ns; the scalar averaged
/// copy was read back as vectors). With `check_q = false` (a
/// [`crate::ProcessNoise`], checked and exactly symmetric) the test is skipped.
///
/// `A = F P`, then only the upper triangle of `A F^T` (column `j`, rows `0..=j`:
/// `sum_k A[:, k] F[j, k]`), mirrored: the result is exactly symmetric. A non-finite
/// entry `F[i, j]` makes the diagonal entry `(i, i)` non-finite (it contains the
/// term `A[i, j] F[i, j]`, and `A[i, j]` the term `F[i, j] P[j, j]` with `P[j, j] >
/// 0`), and a non-finite `Q` entry makes its (upper) entry non-finite, so a
/// positive-definiteness test of the result also rejects non-finite `F` or `Q`.
#[inline(always)]
pub(crate) fn propagate_covariance<const N: usize>(
    isa: Isa,
    f: &SMatrix<f64, N, N>,
    p: &SMatrix<f64, N, N>,
    q: &SMatrix<f64, N, N>,
    check_q: bool,
    p_pred: &mut SMatrix<f64, N, N>,
) -> bool {
    let (fc, qc) = (cols(f), cols(q));
    let a = mul(isa, fc, cols(p));
    // Q as it is when it is checked already or bitwise symmetric (the usual case:
    // one integer comparison per pair, no copy); else the upper triangle of
    // (Q + Q^T) / 2
    let mut q_ok = true;
    let q_mean: Cols<N, N>;
    let mut q_add = qc;
    if check_q {
        let mut exact = true;
        for j in 0..N {
            q_ok &= qc[j][j] >= 0.0;
            for i in 0..j {
                exact &= qc[j][i].to_bits() == qc[i][j].to_bits();
            }
        }
        if !exact {
            let symmetric;
            (q_mean, symmetric) = mean_within_tolerance(qc);
            q_ok &= symmetric;
            q_add = &q_mean;
        }
    }
    let mut upper = [[0.0; N]; N];
    unrolled_for!(j in 0..N, {
        // rows 0..=j of column j of A F^T: sum_k A[:, k] F[j, k] (F[j, k] = fc[k][j])
        for rows in blocks(j + 1) {
            let mut col = Seg::mul(isa, &a[0], fc[0][j], rows);
            for k in 1..N {
                col.add_mul(isa, &a[k], fc[k][j], rows);
            }
            col.add(isa, &q_add[j], rows);
            col.store(&mut upper[j], rows);
        }
    });
    store_symmetric(&upper, &mut p_pred.data.0);
    q_ok
}

/// `(Q + Q^T) / 2` in the upper triangle (the lower one is left as `Q`'s, the
/// kernel reads only the upper; the diagonal of `Q` as it is: `0.5 (d + d) = d`; a
/// `d` so large that `d + d` overflows is not a variance anyway), and whether `Q` is symmetric within [`SYMMETRY_TOLERANCE`]
/// ([`symmetric_within_tolerance`]; its scale, the largest `|diagonal|` entry, is
/// the largest diagonal entry whenever the caller's sign test passes). Taken only
/// for a `Q` that is not bitwise symmetric.
#[cold]
#[inline(never)]
fn mean_within_tolerance<const N: usize>(qc: &Cols<N, N>) -> (Cols<N, N>, bool) {
    let mut mean = *qc;
    for j in 0..N {
        for i in 0..j {
            mean[j][i] = 0.5 * (qc[j][i] + qc[i][j]);
        }
    }
    (mean, symmetric_within_tolerance(qc))
}

/// Writes the symmetric matrix whose upper triangle is that of `upper` (column `j`,
/// rows `0..=j`) into `out`, one whole column at a time: the mirrored entries are
/// gathered by loads, not scattered by stores, so the next kernel's column loads
/// are served by single stores (a load that spans several smaller stores cannot
/// take its data from the store buffer and waits for them to retire).
#[inline(always)]
fn store_symmetric<const N: usize>(upper: &Cols<N, N>, out: &mut Cols<N, N>) {
    unrolled_for!(j in 0..N, {
        let mut col = upper[j];
        for i in (j + 1)..N {
            col[i] = upper[i][j];
        }
        out[j] = col;
    });
}

/// `U = P H^T` (`N x M`) and the innovation covariance `S = H U + (R + R^T) / 2`
/// (upper triangle of `H U`, mirrored: exactly symmetric).
///
/// A non-finite `H[m, c]` makes `U[c, m]` (term `P[c, c] H[m, c]`) and then
/// `S[m, m]` (term `H[m, c] U[c, m]`) non-finite; a non-finite `R` entry makes its
/// `S` entry non-finite: [`SpdSolver::new`] then fails.
#[inline(always)]
pub(crate) fn innovation<const N: usize, const M: usize>(
    isa: Isa,
    p: &SMatrix<f64, N, N>,
    h: &SMatrix<f64, M, N>,
    r: &SMatrix<f64, M, M>,
) -> (SMatrix<f64, N, M>, SMatrix<f64, M, M>) {
    let (pc, hc, rc) = (cols(p), cols(h), cols(r));
    // U[:, m] = sum_k P[:, k] H[m, k]
    let mut u = [[0.0; N]; M];
    for m in 0..M {
        for rows in blocks(N) {
            let mut col = Seg::mul(isa, &pc[0], hc[0][m], rows);
            for k in 1..N {
                col.add_mul(isa, &pc[k], hc[k][m], rows);
            }
            col.store(&mut u[m], rows);
        }
    }
    let mut s = mul(isa, hc, &u);
    for j in 0..M {
        for i in 0..j + 1 {
            let v = s[j][i] + 0.5 * (rc[j][i] + rc[i][j]);
            s[j][i] = v;
            s[i][j] = v;
        }
    }
    (matrix(u), matrix(s))
}

/// Solver for the innovation covariance `S` (symmetric positive definite, `M x M`),
/// used for the gain `K = U S^-1` and the NIS `nu^T S^-1 nu`:
///
/// - `M <= 3`: `S^-1 = adj(S) / det S` in closed form, kept as `adj(S)` and `1 / det
///   S` (gain `(U adj S) / det S`, NIS `(nu^T adj S nu) / det S`). Positive definiteness by
///   Sylvester's criterion (leading minors `s_00`, `s_00 s_11 - s_01^2`, `det S`
///   all `> 0` and finite). The minors and cofactors are products of entries of
///   `S`, so the one division waits for them only, not for a chain of pivots (the
///   three pivots of `L D L^T` are three divisions in a row on the critical path
///   of a Kalman step, ~50 cycles). A non-finite entry makes `det S` non-finite
///   (every entry is a factor of a term of the determinant), which fails the test.
///   The gain's rounding error is first order in `cond(S)` as for any solver, and
///   the Joseph-form update is insensitive to it to first order.
/// - `M > 3`: `S = L D L^T` (unit lower `L`, pivots `D > 0`, right-looking, one
///   division per pivot), gain by triangular solves, no explicit inverse.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SpdSolver<const M: usize> {
    /// `M <= 3`: the adjugate of `S` (`S^-1 = adj / det`), column-major. Unused
    /// otherwise.
    adj: Cols<M, M>,
    /// `M <= 3`: `1 / det S`. Unused otherwise.
    det_inv: f64,
    /// `M > 3`: column-major unit lower factor, `l[c][r] = L[r, c]` for `r > c`.
    l: Cols<M, M>,
    /// `M > 3`: `1 / D`.
    d_inv: [f64; M],
}

/// Whether `v` is `> 0` and finite (NaN fails every comparison).
#[inline(always)]
fn positive_finite(v: f64) -> bool {
    v > 0.0 && v <= f64::MAX
}

impl<const M: usize> SpdSolver<M> {
    /// Prepares the solves with `s` (lower triangle read); `None` unless `s` is
    /// positive definite (criteria above).
    #[inline(always)]
    pub(crate) fn new(s: &SMatrix<f64, M, M>) -> Option<Self> {
        let sc = cols(s);
        let mut out = Self {
            adj: [[0.0; M]; M],
            det_inv: 0.0,
            l: [[0.0; M]; M],
            d_inv: [0.0; M],
        };
        // lower triangle: lo(i, j) = S[i, j], i >= j
        let lo = |i: usize, j: usize| sc[j][i];
        match M {
            0 => {}
            1 => {
                let a = lo(0, 0);
                if !positive_finite(a) {
                    return None;
                }
                out.adj[0][0] = 1.0;
                out.det_inv = 1.0 / a;
            }
            2 => {
                let (a, b, d) = (lo(0, 0), lo(1, 0), lo(1, 1));
                let det = a * d - b * b;
                if !(positive_finite(a) && positive_finite(det)) {
                    return None;
                }
                out.adj[0][0] = d;
                out.adj[1][1] = a;
                out.adj[0][1] = -b;
                out.adj[1][0] = -b;
                out.det_inv = 1.0 / det;
            }
            3 => {
                let (a, b, c) = (lo(0, 0), lo(1, 0), lo(2, 0));
                let (d, e, f) = (lo(1, 1), lo(2, 1), lo(2, 2));
                // cofactors (S symmetric: the adjugate is symmetric too)
                let c00 = d * f - e * e;
                let c01 = c * e - b * f;
                let c02 = b * e - c * d;
                let c11 = a * f - c * c;
                let c12 = b * c - a * e;
                let c22 = a * d - b * b;
                let det = a * c00 + b * c01 + c * c02;
                if !(positive_finite(a) && positive_finite(c22) && positive_finite(det)) {
                    return None;
                }
                out.det_inv = 1.0 / det;
                let adj = [[c00, c01, c02], [c01, c11, c12], [c02, c12, c22]];
                for j in 0..3 {
                    for i in 0..3 {
                        out.adj[j][i] = adj[j][i];
                    }
                }
            }
            _ => {
                let mut w = *sc;
                unrolled_for!(j in 0..M, {
                    let d = w[j][j];
                    if !positive_finite(d) {
                        return None;
                    }
                    let inv = 1.0 / d;
                    out.d_inv[j] = inv;
                    // trailing lower triangle: a[r, c] -= a[r, j] a[c, j] / d, c > j, r >= c
                    for c in (j + 1)..M {
                        let f = w[j][c] * inv;
                        for r in c..M {
                            w[c][r] -= w[j][r] * f;
                        }
                    }
                    for r in (j + 1)..M {
                        w[j][r] *= inv;
                    }
                });
                out.l = w;
            }
        }
        Some(out)
    }

    /// `nu^T S^-1 nu` (`M <= 3`: `(nu^T adj S nu) / det S`; `M > 3`: `|D^-1/2 L^-1 nu|^2` by
    /// forward substitution).
    #[inline(always)]
    pub(crate) fn quad_form(&self, nu: &SVector<f64, M>) -> f64 {
        let nu = cols(nu)[0];
        if M <= 3 {
            // (nu^T adj S nu) / det S
            let mut form = 0.0;
            for j in 0..M {
                let mut row = 0.0;
                for i in 0..M {
                    row += self.adj[j][i] * nu[i];
                }
                form += nu[j] * row;
            }
            return form * self.det_inv;
        }
        let mut y = nu;
        let mut nis = 0.0;
        for j in 0..M {
            let yj = y[j];
            nis += yj * yj * self.d_inv[j];
            for r in (j + 1)..M {
                y[r] -= self.l[j][r] * yj;
            }
        }
        nis
    }

    /// `K = U S^-1` (`N x M`), i.e. the solution of `K S = U`. `M <= 3`: `(U adj S)
    /// / det S`, so that the `N M^2` products run while the division is still on its
    /// way and only `N M` multiplications wait for it (on the critical path of a
    /// Kalman step). `M > 3`: `Y = U L^-T` (columns in increasing order), `Z = Y
    /// D^-1`, `K = Z L^-1` (columns in decreasing order). Both `N M^2` multiply-adds.
    #[inline(always)]
    pub(crate) fn solve_right<const N: usize>(
        &self,
        isa: Isa,
        u: &SMatrix<f64, N, M>,
    ) -> SMatrix<f64, N, M> {
        if M <= 3 {
            // (U adj S) / det S: the products do not wait for the division
            let u_adj = mul(isa, cols(u), &self.adj);
            let mut k = [[0.0; N]; M];
            for j in 0..M {
                for rows in blocks(N) {
                    Seg::mul(isa, &u_adj[j], self.det_inv, rows).store(&mut k[j], rows);
                }
            }
            return matrix(k);
        }
        let mut k = *cols(u);
        // Y L^T = U: Y[:, j] = U[:, j] - sum_{i < j} L[j, i] Y[:, i]
        for j in 0..M {
            for i in 0..j {
                let (done, rest) = k.split_at_mut(j);
                axmy(&mut rest[0], self.l[i][j], &done[i]);
            }
        }
        // Z = Y D^-1
        for j in 0..M {
            k[j] = scaled(self.d_inv[j], &k[j]);
        }
        // K L = Z: K[:, j] = Z[:, j] - sum_{i > j} L[i, j] K[:, i]
        for j in (0..M).rev() {
            for i in (j + 1)..M {
                let (head, done) = k.split_at_mut(j + 1);
                axmy(&mut head[j], self.l[j][i], &done[i - j - 1]);
            }
        }
        matrix(k)
    }
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
/// `K S = P H^T`), at `N M^2 + N (N + 1) M` multiply-adds (upper triangle only,
/// mirrored: exactly symmetric) instead of `2 N^3 + ...` for the product form.
#[inline(always)]
pub(crate) fn joseph_update<const N: usize, const M: usize>(
    isa: Isa,
    p: &SMatrix<f64, N, N>,
    pht: &SMatrix<f64, N, M>,
    k: &SMatrix<f64, N, M>,
    s: &SMatrix<f64, M, M>,
    p_new: &mut SMatrix<f64, N, N>,
) {
    let (pc, uc, kc, sc) = (cols(p), cols(pht), cols(k), cols(s));
    // W = U - K S
    let mut w = [[0.0; N]; M];
    for j in 0..M {
        for rows in blocks(N) {
            let mut col = Seg::load(&uc[j], rows);
            for i in 0..M {
                col.sub_mul(isa, &kc[i], sc[j][i], rows);
            }
            col.store(&mut w[j], rows);
        }
    }
    // rows 0..=j of column j of P - K U^T - W K^T:
    // P[:, j] - sum_m (K[:, m] U[j, m] + W[:, m] K[j, m])
    let mut upper = [[0.0; N]; N];
    unrolled_for!(j in 0..N, {
        for rows in blocks(j + 1) {
            let mut col = Seg::load(&pc[j], rows);
            for m in 0..M {
                col.sub_mul2(isa, (&kc[m], uc[m][j]), (&w[m], kc[m][j]), rows);
            }
            col.store(&mut upper[j], rows);
        }
    });
    store_symmetric(&upper, &mut p_new.data.0);
}

/// Whether the symmetric matrix `a` (lower triangle read) is positive definite, by
/// block `L D L^T` elimination with `2 x 2` pivot blocks (and a final `1 x 1` pivot
/// when `N` is odd), no pivoting, early exit, no allocation:
///
/// ```text
/// a = [D  B^T]     D = [p q]   a is positive definite  <=>  D is (p > 0, det D > 0)
///     [B  C  ],        [q t],  and so is the Schur complement C - B D^-1 B^T
/// ```
///
/// with `D^-1 = adj(D) / det D`, `adj(D) = [t -q; -q p]`: the trailing update is
/// `a[r, c] -= (a[r, j] y0 + a[r, j + 1] y1) / det D` with `y = adj(D) (a[c, j],
/// a[c, j + 1])`, so the products do not wait for the division (one division per
/// two columns; measured ~13 ns less per 6/3 step than one `1 x 1` pivot per column).
/// In exact arithmetic this accepts exactly the positive-definite matrices (the
/// pivots are those of any symmetric Gaussian elimination); a NaN fails every
/// comparison and a non-finite entry of the lower triangle reaches a pivot, so a
/// non-finite matrix fails.
#[inline(always)]
pub(crate) fn is_positive_definite<const N: usize>(a: &SMatrix<f64, N, N>) -> bool {
    let a = cols(a);
    // The Schur complements; entry (c, r) is written before it is read, so `a` is
    // never copied (a copy of the whole matrix was a `memcpy` call): the first pivot
    // block and the first trailing update read `a` itself (`j` is a literal in each
    // unrolled copy, so the choice is made at compile time).
    let mut w = [[0.0; N]; N];
    unrolled_for!(j in 0..N, {
        if j.is_multiple_of(2) {
            let at = |w: &Cols<N, N>, c: usize, r: usize| if j == 0 { a[c][r] } else { w[c][r] };
            if j + 1 < N {
                let (p, q, t) = (at(&w, j, j), at(&w, j, j + 1), at(&w, j + 1, j + 1));
                let det = p * t - q * q;
                // p > 0 and det > 0, both finite (NaN fails every comparison)
                if !(positive_finite(p) && positive_finite(det)) {
                    return false;
                }
                let inv = 1.0 / det;
                for c in (j + 2)..N {
                    let (b0, b1) = (at(&w, j, c), at(&w, j + 1, c));
                    let (y0, y1) = (b0 * t - b1 * q, b1 * p - b0 * q);
                    for r in c..N {
                        let v = at(&w, c, r) - (at(&w, j, r) * y0 + at(&w, j + 1, r) * y1) * inv;
                        w[c][r] = v;
                    }
                }
            } else {
                let d = at(&w, j, j);
                if !positive_finite(d) {
                    return false;
                }
            }
        }
    });
    true
}

/// A sufficient test for `check_covariance` of `fathom_core` to accept `r`: `true`
/// implies that `r` is finite, symmetric within [`SYMMETRY_TOLERANCE`] relative to the
/// largest `|diagonal|` (the same comparisons), and that nalgebra's Cholesky
/// factorization of `r` succeeds; `false` means "run `check_covariance`" (which then
/// returns the error, or accepts a nearly singular `r` this test declined). No square
/// root or division for `M <= 3`:
///
/// Finiteness: for `M = 2, 3` the diagonal's range test rejects a non-finite diagonal
/// entry, a non-finite lower entry makes its `2 x 2` minor `-inf` or NaN, and a
/// non-finite upper entry fails the symmetry test (the same bits pass it, but then
/// the lower entry is non-finite too); `M = 1` and `M >= 4` test it directly.
///
/// - `M = 1`: `r > 0` (and finite), exactly nalgebra's criterion.
/// - `M = 2, 3`: every diagonal entry in `[1e-100, 1e100]` (so products of three are
///   normal numbers), every `2 x 2` principal minor `r_ii r_jj - r_ij^2 > tau r_ii
///   r_jj` and (`M = 3`) `det r > tau r_00 r_11 r_22`, `tau = 1e-8`. The minors then
///   bound `|r_ij| < sqrt(r_ii r_jj)`, so the six products of the determinant are
///   at most `r_00 r_11 r_22` and its rounding error is below `1e-13 r_00 r_11 r_22`:
///   the exact minors are positive (Sylvester), `r` is positive definite, and its
///   correlation matrix `H = D^-1/2 r D^-1/2` has `lambda_min(H) >= det H /
///   lambda_max(H)^2 >= (tau - 1e-13) / 9 > 1e-9`. Cholesky in floating point runs to
///   completion whenever `lambda_min(H) > M gamma_(M+1) / (1 - (M+1) gamma_(M+1))`,
///   about `1.3e-15` for `M = 3` (Demmel; Higham, *Accuracy and Stability of
///   Numerical Algorithms*, 2nd ed., Thm. 10.7), whatever the order of its inner
///   products, so nalgebra's factorization succeeds.
/// - `M >= 4`: nalgebra's factorization repeated operation by operation (left-looking,
///   `col_j[j..] -= L[j, k] col_k[j..]`, pivot `> 0`, division by its square root),
///   which accepts exactly the same matrices.
///
/// The square roots and divisions of a Cholesky factorization made this test ~15 ns
/// of a 6/3 step (a dependency chain of ~100 cycles); the minors are a few products.
#[inline(always)]
pub(crate) fn covariance_surely_valid<const M: usize>(r: &SMatrix<f64, M, M>) -> bool {
    const TAU: f64 = 1e-8;
    let rc = cols(r);
    // symmetric: bitwise (the usual case, one integer comparison per pair), else
    // within the tolerance
    let mut ok = true;
    for j in 0..M {
        for i in 0..j {
            ok &= rc[j][i].to_bits() == rc[i][j].to_bits();
        }
    }
    if !ok {
        ok = symmetric_within_tolerance(rc);
    }
    // lower triangle, as the Cholesky factorization reads it: l(i, j) = r[i, j], i >= j
    let l = |i: usize, j: usize| rc[j][i];
    match M {
        0 => ok,
        1 => ok && positive_finite(l(0, 0)),
        2 | 3 => {
            for i in 0..M {
                ok &= (1e-100..=1e100).contains(&l(i, i));
            }
            for i in 0..M {
                for j in 0..i {
                    let dd = l(i, i) * l(j, j);
                    ok &= dd - l(i, j) * l(i, j) > TAU * dd;
                }
            }
            if M == 3 {
                let (a, b, c) = (l(0, 0), l(1, 0), l(2, 0));
                let (d, e, f) = (l(1, 1), l(2, 1), l(2, 2));
                let det = a * (d * f - e * e) - b * (b * f - c * e) + c * (b * e - c * d);
                ok &= det > TAU * (a * d * f);
            }
            ok
        }
        _ => ok && all_finite(r.as_slice()) && cholesky_succeeds(rc),
    }
}

/// Whether `rc` is symmetric within [`SYMMETRY_TOLERANCE`] relative to its largest
/// `|diagonal|` entry (the comparisons of `check_covariance`; a NaN fails), for a
/// matrix that is not bitwise symmetric (`R` here, `Q` in [`mean_within_tolerance`]).
#[cold]
#[inline(never)]
fn symmetric_within_tolerance<const M: usize>(rc: &Cols<M, M>) -> bool {
    let mut scale = 0.0_f64;
    for j in 0..M {
        let d = rc[j][j].abs();
        scale = if d > scale { d } else { scale };
    }
    let threshold = SYMMETRY_TOLERANCE * scale.max(f64::MIN_POSITIVE);
    let mut ok = true;
    for j in 0..M {
        for i in 0..j {
            ok &= (rc[j][i] - rc[i][j]).abs() <= threshold;
        }
    }
    ok
}

/// nalgebra's `Cholesky::new` success criterion, operation by operation.
#[inline]
fn cholesky_succeeds<const M: usize>(a: &Cols<M, M>) -> bool {
    let mut w = *a;
    for j in 0..M {
        for k in 0..j {
            let factor = w[k][j];
            for row in j..M {
                w[j][row] -= factor * w[k][row];
            }
        }
        let diag = w[j][j];
        // nalgebra: `diag.is_zero()` or no square root (`diag < 0`, NaN) fails
        if diag.is_nan() || diag <= 0.0 {
            return false;
        }
        let denom = diag.sqrt();
        w[j][j] = denom;
        for row in (j + 1)..M {
            w[j][row] /= denom;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Matrix1, Matrix2, Matrix3, RowSVector};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random<const R: usize, const C: usize>(rng: &mut ChaCha8Rng) -> SMatrix<f64, R, C> {
        SMatrix::from_fn(|_, _| rng.random_range(-1.0..1.0))
    }

    /// [`propagate_covariance`] returning the matrix.
    fn propagated<const N: usize>(
        f: &SMatrix<f64, N, N>,
        p: &SMatrix<f64, N, N>,
        q: &SMatrix<f64, N, N>,
    ) -> (SMatrix<f64, N, N>, bool) {
        // a non-zero start: every entry must be overwritten
        let mut out = SMatrix::repeat(f64::NAN);
        let ok = propagate_covariance(Isa::Portable, f, p, q, true, &mut out);
        (out, ok)
    }

    /// [`joseph_update`] returning the matrix.
    fn joseph<const N: usize, const M: usize>(
        p: &SMatrix<f64, N, N>,
        pht: &SMatrix<f64, N, M>,
        k: &SMatrix<f64, N, M>,
        s: &SMatrix<f64, M, M>,
    ) -> SMatrix<f64, N, N> {
        let mut out = SMatrix::repeat(f64::NAN);
        joseph_update(Isa::Portable, p, pht, k, s, &mut out);
        out
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
            let (fast, q_ok) = propagated(&f, &p, &q);
            assert!(q_ok);
            assert_eq!(fast, fast.transpose());
            assert_relative_eq!(fast, (full + full.transpose()) * 0.5, epsilon = 1e-12);
        }
    }

    #[test]
    fn process_noise_predicate() {
        let (f, p) = (Matrix2::identity(), Matrix2::identity());
        let ok = |q: Matrix2<f64>| propagated(&f, &p, &q).1;
        assert!(ok(Matrix2::zeros()));
        assert!(ok(Matrix2::new(1.0, 0.5, 0.5, 2.0)));
        assert!(ok(Matrix2::new(1.0, 0.5, 0.5 + 1e-10, 2.0))); // within tolerance
        assert!(!ok(Matrix2::new(1.0, 0.5, 0.5 + 1e-8, 2.0)));
        assert!(!ok(Matrix2::new(1.0, 0.0, 0.0, -1e-300)));
    }

    /// A `Q` within the symmetry tolerance but not exactly symmetric is replaced by
    /// `(Q + Q^T) / 2` (fails if its upper triangle were taken as it is); an exactly
    /// symmetric one is added as it is, which is the same number.
    #[test]
    fn a_nearly_symmetric_q_is_averaged() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (f, p, q) = (
            random::<6, 6>(&mut rng),
            spd::<6>(&mut rng),
            spd::<6>(&mut rng),
        );
        let mut q_near = q;
        q_near[(1, 4)] += 1e-12; // an upper entry
        let mean = (q_near + q_near.transpose()) * 0.5;
        let (got, ok) = propagated(&f, &p, &q_near);
        assert!(ok);
        let (want, mean_ok) = propagated(&f, &p, &mean);
        assert!(mean_ok);
        assert_eq!(got, want);
        let mut q_upper = q_near;
        q_upper[(4, 1)] = q_upper[(1, 4)];
        assert_ne!(got, propagated(&f, &p, &q_upper).0);
    }

    /// The kernels against plain nalgebra products for sizes below, at and above one
    /// segment (16 rows, so 17 and 20 take two), on every instruction set.
    fn kernels_case<const N: usize, const M: usize>(rng: &mut ChaCha8Rng) {
        for isa in crate::lanes::isas() {
            let (f, p, q) = (random::<N, N>(rng), spd::<N>(rng), spd::<N>(rng));
            let (h, r) = (random::<M, N>(rng), spd::<M>(rng));
            let mut pred = SMatrix::<f64, N, N>::repeat(f64::NAN);
            assert!(propagate_covariance(isa, &f, &p, &q, true, &mut pred));
            let full = f * p * f.transpose() + q;
            assert_eq!(pred, pred.transpose());
            assert_relative_eq!(pred, full, epsilon = 1e-10, max_relative = 1e-12);
            let (u, s) = innovation(isa, &p, &h, &r);
            assert_relative_eq!(u, p * h.transpose(), epsilon = 1e-11, max_relative = 1e-12);
            assert_relative_eq!(
                s,
                h * p * h.transpose() + r,
                epsilon = 1e-10,
                max_relative = 1e-12
            );
            let solver = SpdSolver::new(&s).unwrap();
            let k = solver.solve_right(isa, &u);
            let k_ref = u * s.try_inverse().unwrap();
            assert_relative_eq!(k, k_ref, epsilon = 1e-9, max_relative = 1e-9);
            let mut joseph_p = SMatrix::<f64, N, N>::repeat(f64::NAN);
            joseph_update(isa, &p, &u, &k, &s, &mut joseph_p);
            let a = SMatrix::<f64, N, N>::identity() - k * h;
            let product = a * p * a.transpose() + k * r * k.transpose();
            assert_eq!(joseph_p, joseph_p.transpose());
            assert_relative_eq!(joseph_p, product, epsilon = 1e-9, max_relative = 1e-9);
        }
    }

    #[test]
    fn kernels_match_nalgebra_for_every_size_and_instruction_set() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        kernels_case::<1, 1>(&mut rng);
        kernels_case::<2, 1>(&mut rng);
        kernels_case::<5, 2>(&mut rng);
        kernels_case::<6, 3>(&mut rng);
        kernels_case::<9, 3>(&mut rng);
        kernels_case::<15, 4>(&mut rng);
        kernels_case::<16, 3>(&mut rng);
        kernels_case::<17, 3>(&mut rng);
        kernels_case::<20, 5>(&mut rng);
    }

    #[test]
    fn innovation_matches_the_products() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for _ in 0..20 {
            let (p, h, r) = (
                spd::<6>(&mut rng),
                random::<3, 6>(&mut rng),
                spd::<3>(&mut rng),
            );
            let (u, s) = innovation(Isa::Portable, &p, &h, &r);
            assert_relative_eq!(u, p * h.transpose(), epsilon = 1e-13);
            assert_eq!(s, s.transpose());
            assert_relative_eq!(s, h * p * h.transpose() + r, epsilon = 1e-12);
            let x = SVector::<f64, 6>::from_fn(|i, _| i as f64 - 2.5);
            assert_relative_eq!(mat_vec(&h, &x), h * x, epsilon = 1e-13);
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
            let fast = joseph(&p, &pht, &k, &s);
            assert_eq!(fast, fast.transpose());
            assert_relative_eq!(fast, product, epsilon = 1e-11);
            // scalar flavour
            let hr: RowSVector<f64, 6> = h.row(0).into_owned();
            let ks: SVector<f64, 6> = k.column(0).into_owned();
            let phts = p * hr.transpose();
            let a1 = SMatrix::<f64, 6, 6>::identity() - ks * hr;
            let prod1 = a1 * p * a1.transpose() + ks * ks.transpose() * 0.7;
            let s1 = (hr * phts)[0] + 0.7;
            let fast1 = joseph(&p, &phts, &ks, &Matrix1::new(s1));
            assert_eq!(fast1, fast1.transpose());
            assert_relative_eq!(fast1, prod1, epsilon = 1e-11);
        }
    }

    #[test]
    fn spd_solver_matches_the_inverse() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..20 {
            let s = spd::<3>(&mut rng);
            let inv = s.try_inverse().unwrap();
            let ldl = SpdSolver::new(&s).unwrap();
            // S^-1 itself as the solution of K S = I
            assert_relative_eq!(
                ldl.solve_right(Isa::Portable, &Matrix3::identity()),
                inv,
                epsilon = 1e-9,
                max_relative = 1e-9
            );
            let u = random::<6, 3>(&mut rng);
            assert_relative_eq!(ldl.solve_right(Isa::Portable, &u), u * inv, epsilon = 1e-9);
            let nu = random::<3, 1>(&mut rng);
            assert_relative_eq!(
                ldl.quad_form(&nu),
                nu.dot(&(inv * nu)),
                max_relative = 1e-12
            );
        }
        assert!(SpdSolver::new(&Matrix2::new(1.0, 2.0, 2.0, 1.0)).is_none());
        assert!(SpdSolver::new(&Matrix2::new(1.0, 0.0, 0.0, f64::NAN)).is_none());
        assert!(SpdSolver::new(&Matrix2::new(1.0, f64::INFINITY, f64::INFINITY, 1.0)).is_none());
    }

    #[test]
    fn positive_definiteness_test_agrees_with_nalgebra() {
        fn agree<const N: usize>(rng: &mut ChaCha8Rng, shift: f64) -> usize {
            let mut pd = 0;
            for _ in 0..200 {
                let a = random::<N, N>(rng);
                let s = (a + a.transpose()) * 0.5 + SMatrix::<f64, N, N>::identity() * shift;
                let expected = s.cholesky().is_some();
                assert_eq!(is_positive_definite(&s), expected, "{s}");
                pd += usize::from(expected);
            }
            pd
        }
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        // even and odd sizes (2 x 2 pivot blocks and a final 1 x 1 pivot), both outcomes
        for (pd, n) in [
            (agree::<1>(&mut rng, 0.3), 1),
            (agree::<2>(&mut rng, 0.6), 2),
            (agree::<3>(&mut rng, 0.7), 3),
            (agree::<4>(&mut rng, 0.8), 4),
            (agree::<5>(&mut rng, 1.0), 5),
            (agree::<7>(&mut rng, 1.6), 7),
        ] {
            assert!(
                pd > 20 && pd < 180,
                "N = {n}: {pd} of 200 positive definite"
            );
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

    /// `covariance_surely_valid` never accepts what `check_covariance` rejects, and
    /// declines only nearly singular matrices; `cholesky_succeeds` (the `M >= 4`
    /// path) agrees with nalgebra exactly.
    fn covariance_predicate_case<const M: usize>(r: &SMatrix<f64, M, M>) -> (bool, bool) {
        use fathom_core::gaussian::check_covariance;
        let official = check_covariance("R", r).is_ok();
        let fast = covariance_surely_valid(r);
        assert!(
            !fast || official,
            "accepted a matrix check_covariance rejects: {r}"
        );
        if r.iter().all(|v| v.is_finite()) {
            assert_eq!(cholesky_succeeds(cols(r)), r.cholesky().is_some(), "{r}");
        }
        (fast, official)
    }

    fn covariance_predicate_sweep<const M: usize>(seed: u64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut rejected, mut declined) = (0, 0);
        for i in 0..3000 {
            let a = random::<M, M>(&mut rng);
            let mut r = (a + a.transpose()) * 0.5 + SMatrix::<f64, M, M>::identity() * 0.6;
            let scale = (0..M).map(|k| r[(k, k)].abs()).fold(0.0, f64::max);
            match i % 6 {
                // straddles the symmetry tolerance
                0 => r[(0, M - 1)] += SYMMETRY_TOLERANCE * scale * rng.random_range(0.9..1.1),
                // a non-finite lower, upper or symmetric pair of entries
                1 => {
                    let v = [f64::NAN, f64::INFINITY, -f64::INFINITY][(i / 6) % 3];
                    match (i / 18) % 3 {
                        0 => r[(M - 1, 0)] = v,
                        1 => r[(0, M - 1)] = v,
                        _ => (r[(M - 1, 0)], r[(0, M - 1)]) = (v, v),
                    }
                }
                2 => r[(M - 1, M - 1)] = 0.0,
                // nearly singular: a rank-one-deficient matrix plus a tiny multiple of I
                3 => {
                    let v = random::<M, 1>(&mut rng);
                    let b = random::<M, M>(&mut rng);
                    let mut g = b * b.transpose();
                    g -= (g * v)
                        * (v.transpose() * g * v).try_inverse().unwrap()
                        * (v.transpose() * g);
                    r = (g + g.transpose()) * 0.5
                        + SMatrix::<f64, M, M>::identity()
                            * 10f64.powf(rng.random_range(-17.0..-6.0));
                }
                // scaled entries (products of three must stay normal)
                4 => r *= 10f64.powf(rng.random_range(-150.0..150.0)),
                _ => {}
            }
            let (fast, official) = covariance_predicate_case(&r);
            rejected += usize::from(!official);
            declined += usize::from(official && !fast);
        }
        assert!(rejected > 500 && rejected < 2500, "{rejected}");
        // the test declines only nearly singular or extremely scaled matrices
        assert!(declined < 1000, "{declined}");
    }

    #[test]
    fn covariance_predicate_implies_check_covariance() {
        covariance_predicate_sweep::<1>(12);
        covariance_predicate_sweep::<2>(13);
        covariance_predicate_sweep::<3>(14);
        covariance_predicate_sweep::<4>(15);
        assert!(covariance_surely_valid(&Matrix3::new(
            0.25, 0.02, 0.0, 0.02, 0.25, 0.01, 0.0, 0.01, 0.5
        )));
        assert!(!covariance_surely_valid(&Matrix2::new(4.0, 4.0, 4.0, 4.0)));
        assert!(!covariance_surely_valid(&Matrix2::new(
            f64::INFINITY,
            0.0,
            0.0,
            1.0
        )));
    }

    #[test]
    fn finite_reduction() {
        assert!(all_finite(&[]));
        assert!(all_finite(&[1.0, -0.0, f64::MAX, f64::MIN_POSITIVE, 3.0]));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for len in 1..10 {
                for pos in 0..len {
                    let mut v = vec![1.5; len];
                    v[pos] = bad;
                    assert!(!all_finite(&v), "{len} {pos}");
                }
            }
        }
    }
}

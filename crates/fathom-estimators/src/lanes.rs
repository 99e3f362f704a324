//! Explicit vector lanes for the fixed-size Kalman kernels of [`crate::linalg`].
//!
//! A column segment of `len` rows ([`Seg`]) is held as `len / 4` 4-vectors, then one
//! 2-vector when `len % 4 >= 2`, then one scalar when `len` is odd, and every operation
//! on it is one vector instruction per chunk, the chunks of one operation next to each
//! other; a column longer than 16 rows is done in blocks of 16 ([`blocks`]). Left to
//! itself the compiler vectorized the kernels' 6-row columns mostly as
//! 2-vectors and spread one column's pieces over the whole kernel, keeping the
//! broadcast scalars alive in between (stack spills); with the chunks spelled out, the
//! 6-state prediction is ~10 % faster (`docs/performance.md`, fourth round).
//!
//! [`Isa`] is the instruction set the kernels were dispatched to
//! ([`crate::simd::dispatch`]): `Avx2` does each chunk with one `pulp` AVX2 operation,
//! `Portable` lane by lane. Both do the same IEEE operation on every lane (no fused
//! multiply-add), so the results are bit-identical; the dispatched closure is compiled
//! once per variant with the variant a constant, so the `match` in each operation is
//! resolved at compile time.

use pulp::{f64x2, f64x4};

/// The instruction set of one dispatched kernel call (see the module docs).
#[derive(Debug, Clone, Copy)]
pub(crate) enum Isa {
    /// Lane by lane (SSE2 on x86-64, whatever the target has elsewhere).
    Portable,
    /// AVX2, 4-wide (x86-64 CPUs that have it).
    #[cfg(target_arch = "x86_64")]
    Avx2(pulp::x86::V3),
}

macro_rules! lane_op {
    ($(#[$doc:meta])* $name:ident, $ty:ident, $op:tt, $pulp:ident, $($lane:tt),+) => {
        $(#[$doc])*
        #[inline(always)]
        fn $name(self, a: $ty, b: $ty) -> $ty {
            match self {
                Isa::Portable => $ty($(a.$lane $op b.$lane),+),
                #[cfg(target_arch = "x86_64")]
                Isa::Avx2(simd) => simd.$pulp(a, b),
            }
        }
    };
}

impl Isa {
    lane_op!(/// `a + b`.
        add4, f64x4, +, add_f64x4, 0, 1, 2, 3);
    lane_op!(/// `a - b`.
        sub4, f64x4, -, sub_f64x4, 0, 1, 2, 3);
    lane_op!(/// `a * b`.
        mul4, f64x4, *, mul_f64x4, 0, 1, 2, 3);
    lane_op!(/// `a + b`.
        add2, f64x2, +, add_f64x2, 0, 1);
    lane_op!(/// `a - b`.
        sub2, f64x2, -, sub_f64x2, 0, 1);
    lane_op!(/// `a * b`.
        mul2, f64x2, *, mul_f64x2, 0, 1);
}

/// Rows `i..i + 4` of `x`.
#[inline(always)]
fn ld4<const R: usize>(x: &[f64; R], i: usize) -> f64x4 {
    f64x4(x[i], x[i + 1], x[i + 2], x[i + 3])
}

/// Rows `i..i + 2` of `x`.
#[inline(always)]
fn ld2<const R: usize>(x: &[f64; R], i: usize) -> f64x2 {
    f64x2(x[i], x[i + 1])
}

#[inline(always)]
fn splat4(v: f64) -> f64x4 {
    f64x4(v, v, v, v)
}

#[inline(always)]
fn splat2(v: f64) -> f64x2 {
    f64x2(v, v)
}

/// Rows `off..off + len` of a column, `len <= 16` (see [`blocks`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rows {
    /// First row.
    pub(crate) off: usize,
    /// Number of rows, at most [`Seg::MAX_ROWS`].
    pub(crate) len: usize,
}

/// Rows `0..n` in blocks of [`Seg::MAX_ROWS`] (one block when `n <= 16`, which the
/// compiler then sees as constants).
#[inline(always)]
pub(crate) fn blocks(n: usize) -> impl Iterator<Item = Rows> {
    // a plain range of block numbers (`step_by` kept the 9-state kernels rolled)
    (0..n.div_ceil(Seg::MAX_ROWS)).map(move |b| {
        let off = b * Seg::MAX_ROWS;
        Rows {
            off,
            len: (n - off).min(Seg::MAX_ROWS),
        }
    })
}

/// Some rows of a column ([`Rows`]) as vector chunks (see the module docs). Every
/// method of one segment takes the same `rows`, constants once the kernels are
/// unrolled.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Seg {
    v4: [f64x4; 4],
    v2: f64x2,
    v1: f64,
}

impl Seg {
    /// The most rows one segment holds.
    pub(crate) const MAX_ROWS: usize = 16;

    /// Applies `f4` to each 4-row chunk, `f2` to the 2-row chunk and `f1` to the last
    /// row, as `rows` has them (`i` is the chunk's first row in the column).
    #[inline(always)]
    fn each(
        &mut self,
        rows: Rows,
        mut f4: impl FnMut(usize, &mut f64x4),
        f2: impl FnOnce(usize, &mut f64x2),
        f1: impl FnOnce(usize, &mut f64),
    ) {
        let Rows { off, len } = rows;
        assert!(len <= Self::MAX_ROWS, "a segment holds at most 16 rows");
        let n4 = len / 4;
        for (c, v) in self.v4.iter_mut().enumerate().take(n4) {
            f4(off + 4 * c, v);
        }
        if len % 4 >= 2 {
            f2(off + 4 * n4, &mut self.v2);
        }
        if len % 2 == 1 {
            f1(off + len - 1, &mut self.v1);
        }
    }

    #[inline(always)]
    fn zero() -> Seg {
        Seg {
            v4: [splat4(0.0); 4],
            v2: splat2(0.0),
            v1: 0.0,
        }
    }

    /// Its rows of `x`.
    #[inline(always)]
    pub(crate) fn load<const R: usize>(x: &[f64; R], rows: Rows) -> Seg {
        let mut out = Seg::zero();
        out.each(
            rows,
            |i, v| *v = ld4(x, i),
            |i, v| *v = ld2(x, i),
            |i, v| *v = x[i],
        );
        out
    }

    /// `x s` on its rows (each lane `x_i * s`).
    #[inline(always)]
    pub(crate) fn mul<const R: usize>(isa: Isa, x: &[f64; R], s: f64, rows: Rows) -> Seg {
        let mut out = Seg::zero();
        out.each(
            rows,
            |i, v| *v = isa.mul4(ld4(x, i), splat4(s)),
            |i, v| *v = isa.mul2(ld2(x, i), splat2(s)),
            |i, v| *v = x[i] * s,
        );
        out
    }

    /// `self += x s` (each lane `y + x_i * s`).
    #[inline(always)]
    pub(crate) fn add_mul<const R: usize>(&mut self, isa: Isa, x: &[f64; R], s: f64, rows: Rows) {
        self.each(
            rows,
            |i, v| *v = isa.add4(*v, isa.mul4(ld4(x, i), splat4(s))),
            |i, v| *v = isa.add2(*v, isa.mul2(ld2(x, i), splat2(s))),
            |i, v| *v += x[i] * s,
        );
    }

    /// `self -= s x` (each lane `y - s * x_i`).
    #[inline(always)]
    pub(crate) fn sub_mul<const R: usize>(&mut self, isa: Isa, x: &[f64; R], s: f64, rows: Rows) {
        self.each(
            rows,
            |i, v| *v = isa.sub4(*v, isa.mul4(splat4(s), ld4(x, i))),
            |i, v| *v = isa.sub2(*v, isa.mul2(splat2(s), ld2(x, i))),
            |i, v| *v -= s * x[i],
        );
    }

    /// `self -= x s + y t` (each lane `z - (x_i * s + y_i * t)`).
    #[inline(always)]
    pub(crate) fn sub_mul2<const R: usize>(
        &mut self,
        isa: Isa,
        (x, s): (&[f64; R], f64),
        (y, t): (&[f64; R], f64),
        rows: Rows,
    ) {
        self.each(
            rows,
            |i, v| {
                let p = isa.add4(
                    isa.mul4(ld4(x, i), splat4(s)),
                    isa.mul4(ld4(y, i), splat4(t)),
                );
                *v = isa.sub4(*v, p);
            },
            |i, v| {
                let p = isa.add2(
                    isa.mul2(ld2(x, i), splat2(s)),
                    isa.mul2(ld2(y, i), splat2(t)),
                );
                *v = isa.sub2(*v, p);
            },
            |i, v| *v -= x[i] * s + y[i] * t,
        );
    }

    /// `self += y`.
    #[inline(always)]
    pub(crate) fn add<const R: usize>(&mut self, isa: Isa, y: &[f64; R], rows: Rows) {
        self.each(
            rows,
            |i, v| *v = isa.add4(*v, ld4(y, i)),
            |i, v| *v = isa.add2(*v, ld2(y, i)),
            |i, v| *v += y[i],
        );
    }

    /// Writes its rows of `y` (the other rows are left as they are).
    #[inline(always)]
    pub(crate) fn store<const R: usize>(self, y: &mut [f64; R], rows: Rows) {
        let Rows { off, len } = rows;
        assert!(len <= Self::MAX_ROWS, "a segment holds at most 16 rows");
        let n4 = len / 4;
        for (c, &f64x4(a, b, c2, d)) in self.v4.iter().enumerate().take(n4) {
            let i = off + 4 * c;
            y[i..i + 4].copy_from_slice(&[a, b, c2, d]);
        }
        if len % 4 >= 2 {
            let f64x2(a, b) = self.v2;
            let i = off + 4 * n4;
            y[i..i + 2].copy_from_slice(&[a, b]);
        }
        if len % 2 == 1 {
            y[off + len - 1] = self.v1;
        }
    }
}

/// Every instruction set this CPU can run (tests).
#[cfg(test)]
pub(crate) fn isas() -> Vec<Isa> {
    let mut out = vec![Isa::Portable];
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        out.push(Isa::Avx2(simd));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column(seed: u64) -> [f64; 24] {
        // irrational-looking values, so a wrong lane or operation changes the bits
        std::array::from_fn(|i| ((i as f64 + 1.0) * 0.713 + seed as f64 * 1.37).sin() * 3.0)
    }

    /// Every segment operation, every block of 1-16 rows at offsets 0-8 of a 24-row
    /// column, both instruction sets: the same bits as the scalar formula row by row,
    /// and the rows outside the block untouched.
    #[test]
    fn segment_operations_match_the_scalar_formulas() {
        let (x, y, z) = (column(1), column(2), column(3));
        let (s, t) = (0.37, -1.91);
        for isa in isas() {
            for off in 0..=8 {
                for len in 1..=Seg::MAX_ROWS {
                    let rows = Rows { off, len };
                    let check = |seg: Seg, want: &dyn Fn(usize) -> f64, what: &str| {
                        let mut out = [f64::NAN; 24];
                        seg.store(&mut out, rows);
                        for (i, &got) in out.iter().enumerate() {
                            if (off..off + len).contains(&i) {
                                assert_eq!(
                                    got.to_bits(),
                                    want(i).to_bits(),
                                    "{what} {isa:?} {rows:?} row {i}"
                                );
                            } else {
                                assert!(got.is_nan(), "{what} {isa:?} {rows:?} wrote row {i}");
                            }
                        }
                    };
                    check(Seg::load(&x, rows), &|i| x[i], "load");
                    check(Seg::mul(isa, &x, s, rows), &|i| x[i] * s, "mul");
                    let mut seg = Seg::load(&z, rows);
                    seg.add_mul(isa, &x, s, rows);
                    check(seg, &|i| z[i] + x[i] * s, "add_mul");
                    let mut seg = Seg::load(&z, rows);
                    seg.sub_mul(isa, &x, s, rows);
                    check(seg, &|i| z[i] - s * x[i], "sub_mul");
                    let mut seg = Seg::load(&z, rows);
                    seg.sub_mul2(isa, (&x, s), (&y, t), rows);
                    check(seg, &|i| z[i] - (x[i] * s + y[i] * t), "sub_mul2");
                    let mut seg = Seg::load(&z, rows);
                    seg.add(isa, &y, rows);
                    check(seg, &|i| z[i] + y[i], "add");
                }
            }
        }
    }

    #[test]
    fn blocks_cover_the_rows_once() {
        for n in 0..=50 {
            let mut next = 0;
            for rows in blocks(n) {
                assert_eq!(rows.off, next);
                assert!(rows.len >= 1 && rows.len <= Seg::MAX_ROWS);
                next += rows.len;
            }
            assert_eq!(next, n);
        }
        assert_eq!(blocks(16).count(), 1);
        assert_eq!(blocks(17).count(), 2);
    }
}

//! How `fathom.KalmanFilter`'s run-time sizes map onto the Kalman core of
//! `fathom-estimators`:
//!
//! - state size `n <= MAX_FIXED_N` (12): the fixed-size [`KalmanFilter<N>`], one
//!   instance per `N`; its updates with `m <= MAX_FIXED_M` (6) measurements use the
//!   fixed-size `update::<M>` (the code path the benchmarks measure), larger `m` the
//!   stacked faer update of the same filter (`update_stacked`);
//! - `n > MAX_FIXED_N`: [`DynKalmanFilter`] (faer, same checks and messages).
//!
//! Matrices cross this boundary as row-major `f64` slices whose sizes the caller has
//! already checked.

use fathom_core::Gaussian;
use fathom_estimators::{DynKalmanFilter, EstimatorError, KalmanFilter};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

/// Largest state size served by a fixed-size filter.
pub const MAX_FIXED_N: usize = 12;
/// Largest measurement size served by a fixed-size update.
pub const MAX_FIXED_M: usize = 6;

/// What an update reports: innovation `y`, its covariance `S` (row-major) and the NIS.
#[derive(Debug, Clone, PartialEq)]
pub struct Innovation {
    /// `y = z - H x`.
    pub y: Vec<f64>,
    /// `S = H P H^T + R`, row-major `m x m`.
    pub s: Vec<f64>,
    /// `y^T S^-1 y`.
    pub nis: f64,
}

/// The object-safe face of a filter of any size.
pub trait Core: Send + Sync {
    /// State size `n`.
    fn dim(&self) -> usize;
    /// Which core serves this size (for `repr` and the docs).
    fn kind(&self) -> String;
    /// `x`.
    fn state(&self) -> Vec<f64>;
    /// `P`, row-major.
    fn covariance(&self) -> Vec<f64>;
    /// The filter time.
    fn time(&self) -> f64;
    /// Replaces `x` and `P` (checked by the core: "state x", "covariance P").
    ///
    /// # Errors
    /// The core's error; the filter is unchanged.
    fn set_estimate(&mut self, x: &[f64], p: &[f64]) -> Result<(), EstimatorError>;
    /// `x = x_pred` (or `F x` when `None`), `P = F P F^T + Q`, time `new_time`.
    ///
    /// # Errors
    /// The core's error; the filter is unchanged.
    fn predict(
        &mut self,
        x_pred: Option<&[f64]>,
        f: &[f64],
        q: &[f64],
        new_time: f64,
    ) -> Result<(), EstimatorError>;
    /// Update with `m = z.len()` measurements, `H` row-major `m x n`, `R` `m x m`.
    ///
    /// # Errors
    /// The core's error; the filter is unchanged.
    fn update(&mut self, z: &[f64], h: &[f64], r: &[f64]) -> Result<Innovation, EstimatorError>;
}

/// A fixed-size filter.
struct Fixed<const N: usize> {
    kf: KalmanFilter<N>,
}

fn row_major<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>) -> Vec<f64> {
    let mut out = Vec::with_capacity(R * C);
    for i in 0..R {
        for j in 0..C {
            out.push(a[(i, j)]);
        }
    }
    out
}

fn d_row_major(a: &DMatrix<f64>) -> Vec<f64> {
    let mut out = Vec::with_capacity(a.len());
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            out.push(a[(i, j)]);
        }
    }
    out
}

impl<const N: usize> Fixed<N> {
    fn new(x: &[f64], p: &[f64], time: f64) -> Result<Self, EstimatorError> {
        let prior =
            Gaussian::new_unchecked(SVector::from_column_slice(x), SMatrix::from_row_slice(p));
        Ok(Self {
            kf: KalmanFilter::new(prior, time)?,
        })
    }

    fn update_fixed<const M: usize>(
        &mut self,
        z: &[f64],
        h: &[f64],
        r: &[f64],
    ) -> Result<Innovation, EstimatorError> {
        let info = self.kf.update(
            &SVector::<f64, M>::from_column_slice(z),
            &SMatrix::<f64, M, N>::from_row_slice(h),
            &SMatrix::<f64, M, M>::from_row_slice(r),
        )?;
        Ok(Innovation {
            y: info.innovation.as_slice().to_vec(),
            s: row_major(&info.innovation_cov),
            nis: info.nis,
        })
    }
}

impl<const N: usize> Core for Fixed<N> {
    fn dim(&self) -> usize {
        N
    }

    fn kind(&self) -> String {
        format!("fixed<{N}>")
    }

    fn state(&self) -> Vec<f64> {
        self.kf.state().as_slice().to_vec()
    }

    fn covariance(&self) -> Vec<f64> {
        row_major(self.kf.covariance())
    }

    fn time(&self) -> f64 {
        self.kf.time()
    }

    fn set_estimate(&mut self, x: &[f64], p: &[f64]) -> Result<(), EstimatorError> {
        self.kf.set_estimate(Gaussian::new_unchecked(
            SVector::from_column_slice(x),
            SMatrix::from_row_slice(p),
        ))
    }

    fn predict(
        &mut self,
        x_pred: Option<&[f64]>,
        f: &[f64],
        q: &[f64],
        new_time: f64,
    ) -> Result<(), EstimatorError> {
        let f = SMatrix::<f64, N, N>::from_row_slice(f);
        let q = SMatrix::<f64, N, N>::from_row_slice(q);
        match x_pred {
            None => self.kf.predict(&f, &q, new_time),
            Some(x) => self
                .kf
                .predict_nonlinear(&SVector::from_column_slice(x), &f, &q, new_time),
        }
    }

    fn update(&mut self, z: &[f64], h: &[f64], r: &[f64]) -> Result<Innovation, EstimatorError> {
        match z.len() {
            1 => self.update_fixed::<1>(z, h, r),
            2 => self.update_fixed::<2>(z, h, r),
            3 => self.update_fixed::<3>(z, h, r),
            4 => self.update_fixed::<4>(z, h, r),
            5 => self.update_fixed::<5>(z, h, r),
            6 => self.update_fixed::<6>(z, h, r),
            m => {
                let info = self.kf.update_stacked(
                    &DVector::from_column_slice(z),
                    &DMatrix::from_row_slice(m, N, h),
                    &DMatrix::from_row_slice(m, m, r),
                )?;
                Ok(Innovation {
                    y: info.innovation.as_slice().to_vec(),
                    s: d_row_major(&info.innovation_cov),
                    nis: info.nis,
                })
            }
        }
    }
}

/// A filter of run-time size.
struct Dynamic {
    kf: DynKalmanFilter,
}

impl Core for Dynamic {
    fn dim(&self) -> usize {
        self.kf.dim()
    }

    fn kind(&self) -> String {
        "dynamic".into()
    }

    fn state(&self) -> Vec<f64> {
        self.kf.state().as_slice().to_vec()
    }

    fn covariance(&self) -> Vec<f64> {
        d_row_major(self.kf.covariance())
    }

    fn time(&self) -> f64 {
        self.kf.time()
    }

    fn set_estimate(&mut self, x: &[f64], p: &[f64]) -> Result<(), EstimatorError> {
        let n = self.dim();
        self.kf.set_estimate(
            DVector::from_column_slice(x),
            DMatrix::from_row_slice(n, n, p),
        )
    }

    fn predict(
        &mut self,
        x_pred: Option<&[f64]>,
        f: &[f64],
        q: &[f64],
        new_time: f64,
    ) -> Result<(), EstimatorError> {
        let n = self.dim();
        let f = DMatrix::from_row_slice(n, n, f);
        let q = DMatrix::from_row_slice(n, n, q);
        match x_pred {
            None => self.kf.predict(&f, &q, new_time),
            Some(x) => self
                .kf
                .predict_nonlinear(&DVector::from_column_slice(x), &f, &q, new_time),
        }
    }

    fn update(&mut self, z: &[f64], h: &[f64], r: &[f64]) -> Result<Innovation, EstimatorError> {
        let (n, m) = (self.dim(), z.len());
        let info = self.kf.update(
            &DVector::from_column_slice(z),
            &DMatrix::from_row_slice(m, n, h),
            &DMatrix::from_row_slice(m, m, r),
        )?;
        Ok(Innovation {
            y: info.innovation.as_slice().to_vec(),
            s: d_row_major(&info.innovation_cov),
            nis: info.nis,
        })
    }
}

/// A filter of state size `x.len()` starting from `x`, `P` (row-major) at `time`.
///
/// # Errors
/// The core's checks of the prior ("initial state x0", "initial covariance P0").
pub fn new_core(x: &[f64], p: &[f64], time: f64) -> Result<Box<dyn Core>, EstimatorError> {
    macro_rules! fixed {
        ($($n:literal)*) => {
            match x.len() {
                $($n => return Ok(Box::new(Fixed::<$n>::new(x, p, time)?)),)*
                _ => {}
            }
        };
    }
    fixed!(1 2 3 4 5 6 7 8 9 10 11 12);
    let n = x.len();
    Ok(Box::new(Dynamic {
        kf: DynKalmanFilter::new(
            DVector::from_column_slice(x),
            DMatrix::from_row_slice(n, n, p),
            time,
        )?,
    }))
}

//! `fathom.KalmanFilter`: FilterPy's `KalmanFilter` interface (`x`, `P`, `F`, `Q`,
//! `H`, `R`, `B`; `predict(u, B, F, Q)`, `update(z, R, H)`; `y`, `S`, `SI`, `K`, the
//! NIS, `mahalanobis`, `log_likelihood`, `x_prior` ... `P_post`) backed by the Kalman
//! core of `fathom-estimators` ([`crate::kalman_core`] maps the run-time sizes).
//!
//! Storage follows FilterPy's habits: the model matrices `F`, `Q`, `H`, `R`, `B` are
//! numpy arrays held by the filter (assigning a float64 array of the right shape keeps
//! that very array, so `kf.F[0, 3] = dt` works) and are checked by the core each time
//! they are used; `x` and `P` live in the core (every step and every assignment is
//! checked there: a non-positive-definite or NaN `P` raises `ValueError` with the
//! core's message and the filter is unchanged). Reading `kf.x` / `kf.P` gives an
//! array that in-place edits write back: they are checked and loaded into the core
//! at the next step; after a step, `kf.x` / `kf.P` are new arrays (as in FilterPy).
//!
//! The core keeps a time stamp: each `predict()` advances it by `dt` (default 1), and
//! error messages carry it (`at t = 3 s` is the third prediction with `dt = 1`).

// FilterPy's attribute names (`P`, `F`, `S`, `P_prior`, ...) are upper case.
#![allow(non_snake_case)]

use fathom_estimators::EstimatorError;
use nalgebra::DMatrix;
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::arrays::{any_shape, matrix, shape_text};
use crate::kalman_core::{Core, Innovation, new_core};

/// The core's message as `ValueError`.
fn core_err(e: EstimatorError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A row-major `rows x cols` float64 array.
fn array2<'py>(
    py: Python<'py>,
    v: &[f64],
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_slice(py, v).reshape([rows, cols])
}

/// A column vector `(n, 1)` or a 1-D `(n,)` array.
fn vector<'py>(py: Python<'py>, v: &[f64], ndim: usize) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let shape: Vec<usize> = if ndim == 1 {
        vec![v.len()]
    } else {
        vec![v.len(), 1]
    };
    PyArray1::from_slice(py, v).reshape(shape)
}

/// `obj` as a float64 `(rows, cols)` array: the object itself when it already is one
/// (FilterPy keeps the assigned array), else a converted copy.
fn model_matrix(
    py: Python<'_>,
    name: &str,
    obj: &Bound<'_, PyAny>,
    rows: usize,
    cols: usize,
) -> PyResult<Py<PyArray2<f64>>> {
    if let Ok(a) = obj.cast::<PyArray2<f64>>()
        && a.shape() == [rows, cols]
    {
        return Ok(a.clone().unbind());
    }
    let values = matrix(name, obj, rows, cols)?;
    Ok(array2(py, &values, rows, cols)?.unbind())
}

/// The values of a held float64 matrix, row-major.
fn read2(a: &Py<PyArray2<f64>>, py: Python<'_>) -> PyResult<Vec<f64>> {
    let a = a.bind(py).try_readonly()?;
    Ok(match a.as_slice() {
        Ok(s) => s.to_vec(),
        Err(_) => a.as_array().iter().copied().collect(),
    })
}

/// A vector argument of `n` values: shape `(n,)`, `(n, 1)`, `(1, n)`, or a scalar for
/// `n = 1`.
fn vector_arg(name: &str, obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<f64>> {
    let (shape, values) = any_shape(name, obj)?;
    let ok = match shape.as_slice() {
        [] => n == 1,
        [k] => *k == n,
        [r, c] => (*r == n && *c == 1) || (*r == 1 && *c == n),
        _ => false,
    };
    if !ok {
        return Err(PyValueError::new_err(format!(
            "{name}: expected {n} values, shape ({n},) or ({n}, 1), got {}",
            shape_text(&shape)
        )));
    }
    Ok(values)
}

/// A noise argument: an `(n, n)` matrix, or a scalar `s` meaning `s I` (FilterPy).
fn noise_arg(name: &str, obj: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<f64>> {
    if let Ok(s) = obj.extract::<f64>() {
        let mut m = vec![0.0; n * n];
        for i in 0..n {
            m[i * n + i] = s;
        }
        return Ok(m);
    }
    matrix(name, obj, n, n)
}

/// A Kalman filter with FilterPy's interface on fathom's Kalman core.
#[pyclass(module = "fathom", name = "KalmanFilter")]
pub struct KalmanFilter {
    core: Box<dyn Core>,
    dim_x: usize,
    dim_z: usize,
    dim_u: usize,
    /// 2 (column vectors, FilterPy's default) or 1: the shape of the last `x` given.
    x_ndim: usize,
    f: Py<PyArray2<f64>>,
    q: Py<PyArray2<f64>>,
    h: Py<PyArray2<f64>>,
    r: Py<PyArray2<f64>>,
    b: Option<Py<PyAny>>,
    /// The arrays handed out for `x` and `P` since the last step (in-place edits are
    /// read back at the next step).
    x_out: Option<Py<PyArrayDyn<f64>>>,
    p_out: Option<Py<PyArray2<f64>>>,
    /// Time step added by each `predict()`.
    dt: f64,
    /// Last update: measurement, innovation, `S`, NIS, and `P^-`, `H` for `K`.
    z: Option<Vec<f64>>,
    last: Option<Innovation>,
    gain_inputs: Option<(Vec<f64>, Vec<f64>)>,
    x_prior: Vec<f64>,
    p_prior: Vec<f64>,
    x_post: Vec<f64>,
    p_post: Vec<f64>,
}

impl KalmanFilter {
    /// Loads in-place edits of the handed-out `x` / `P` arrays into the core.
    fn sync(&mut self, py: Python<'_>) -> PyResult<()> {
        let n = self.dim_x;
        let mut x = None;
        let mut p = None;
        if let Some(a) = &self.x_out {
            let values: Vec<f64> = a
                .bind(py)
                .try_readonly()?
                .as_array()
                .iter()
                .copied()
                .collect();
            if values.len() == n && values != self.core.state() {
                x = Some(values);
            }
        }
        if let Some(a) = &self.p_out {
            let values = read2(a, py)?;
            if values.len() == n * n && values != self.core.covariance() {
                p = Some(values);
            }
        }
        if x.is_some() || p.is_some() {
            let x = x.unwrap_or_else(|| self.core.state());
            let p = p.unwrap_or_else(|| self.core.covariance());
            self.core.set_estimate(&x, &p).map_err(core_err)?;
        }
        Ok(())
    }

    /// Forgets the handed-out arrays after a step (the next read gives new arrays).
    fn stepped(&mut self) {
        self.x_out = None;
        self.p_out = None;
    }

    fn measurement_shape(&self) -> usize {
        self.last.as_ref().map_or(self.dim_z, |l| l.y.len())
    }
}

#[pymethods]
impl KalmanFilter {
    /// A filter with `dim_x` states and `dim_z` measurements: `x = 0`, `P = I`,
    /// `F = I`, `Q = I`, `H = 0`, `R = I` (FilterPy's defaults).
    #[new]
    #[pyo3(signature = (dim_x, dim_z, dim_u=0))]
    fn new(py: Python<'_>, dim_x: usize, dim_z: usize, dim_u: usize) -> PyResult<Self> {
        const LIMIT: usize = fathom_estimators::dynamic::MAX_DYN_DIM;
        for (name, v) in [("dim_x", dim_x), ("dim_z", dim_z)] {
            if v == 0 || v > LIMIT {
                return Err(PyValueError::new_err(format!(
                    "{name} must be in 1 ..= {LIMIT}, got {v}"
                )));
            }
        }
        if dim_u > LIMIT {
            return Err(PyValueError::new_err(format!(
                "dim_u must be in 0 ..= {LIMIT}, got {dim_u}"
            )));
        }
        let eye = |n: usize| {
            let mut m = vec![0.0; n * n];
            for i in 0..n {
                m[i * n + i] = 1.0;
            }
            m
        };
        let x = vec![0.0; dim_x];
        let p = eye(dim_x);
        let core = new_core(&x, &p, 0.0).map_err(core_err)?;
        Ok(Self {
            core,
            dim_x,
            dim_z,
            dim_u,
            x_ndim: 2,
            f: array2(py, &eye(dim_x), dim_x, dim_x)?.unbind(),
            q: array2(py, &eye(dim_x), dim_x, dim_x)?.unbind(),
            h: array2(py, &vec![0.0; dim_z * dim_x], dim_z, dim_x)?.unbind(),
            r: array2(py, &eye(dim_z), dim_z, dim_z)?.unbind(),
            b: None,
            x_out: None,
            p_out: None,
            dt: 1.0,
            z: None,
            last: None,
            gain_inputs: None,
            x_prior: x.clone(),
            p_prior: p.clone(),
            x_post: x,
            p_post: p,
        })
    }

    /// Number of states.
    #[getter]
    fn dim_x(&self) -> usize {
        self.dim_x
    }

    /// Number of measurements (of `H` and `R`).
    #[getter]
    fn dim_z(&self) -> usize {
        self.dim_z
    }

    /// Number of control inputs.
    #[getter]
    fn dim_u(&self) -> usize {
        self.dim_u
    }

    /// Which core serves this size: `fixed<N>` or `dynamic`.
    #[getter]
    fn core(&self) -> String {
        self.core.kind()
    }

    /// State estimate, shape `(dim_x, 1)` (or `(dim_x,)` after a 1-D assignment).
    #[getter]
    fn get_x<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        self.sync(py)?;
        let a = vector(py, &self.core.state(), self.x_ndim)?;
        self.x_out = Some(a.clone().unbind());
        Ok(a)
    }

    #[setter]
    fn set_x(&mut self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let x = vector_arg("x", value, self.dim_x)?;
        // a pending in-place edit of the old `x` is replaced, not loaded
        self.x_out = None;
        self.sync(py)?;
        let p = self.core.covariance();
        self.core.set_estimate(&x, &p).map_err(core_err)?;
        self.x_ndim = if any_shape("x", value)?.0.len() == 1 {
            1
        } else {
            2
        };
        self.x_out = None;
        Ok(())
    }

    /// State covariance, `(dim_x, dim_x)`.
    #[getter]
    fn get_P<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.sync(py)?;
        let a = array2(py, &self.core.covariance(), self.dim_x, self.dim_x)?;
        self.p_out = Some(a.clone().unbind());
        Ok(a)
    }

    #[setter]
    fn set_P(&mut self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = matrix("P", value, self.dim_x, self.dim_x)?;
        // a pending in-place edit of the old `P` is replaced, not loaded
        self.p_out = None;
        self.sync(py)?;
        let x = self.core.state();
        self.core.set_estimate(&x, &p).map_err(core_err)?;
        self.p_out = None;
        Ok(())
    }

    /// State transition matrix, `(dim_x, dim_x)`.
    #[getter]
    fn get_F(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.f.clone_ref(py)
    }

    #[setter]
    fn set_F(&mut self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.f = model_matrix(py, "F", value, self.dim_x, self.dim_x)?;
        Ok(())
    }

    /// Process noise covariance, `(dim_x, dim_x)`.
    #[getter]
    fn get_Q(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.q.clone_ref(py)
    }

    #[setter]
    fn set_Q(&mut self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.q = model_matrix(py, "Q", value, self.dim_x, self.dim_x)?;
        Ok(())
    }

    /// Measurement matrix, `(dim_z, dim_x)`.
    #[getter]
    fn get_H(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.h.clone_ref(py)
    }

    #[setter]
    fn set_H(&mut self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.h = model_matrix(py, "H", value, self.dim_z, self.dim_x)?;
        Ok(())
    }

    /// Measurement noise covariance, `(dim_z, dim_z)`; checked on assignment by the
    /// core's covariance check (finite, symmetric, positive definite).
    #[getter]
    fn get_R(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.r.clone_ref(py)
    }

    #[setter]
    fn set_R(&mut self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let r = model_matrix(py, "R", value, self.dim_z, self.dim_z)?;
        let values = read2(&r, py)?;
        fathom_estimators::dynamic::check_covariance(
            "measurement noise R",
            &DMatrix::from_row_slice(self.dim_z, self.dim_z, &values),
            self.core.time(),
        )
        .map_err(core_err)?;
        self.r = r;
        Ok(())
    }

    /// Control matrix `(dim_x, dim_u)` or `None`.
    #[getter]
    fn get_B(&self, py: Python<'_>) -> Option<Py<PyAny>> {
        self.b.as_ref().map(|b| b.clone_ref(py))
    }

    #[setter]
    fn set_B(&mut self, py: Python<'_>, value: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        self.b = match value {
            None => None,
            Some(v) if v.is_none() => None,
            Some(v) => Some(model_matrix(py, "B", v, self.dim_x, self.dim_u.max(1))?.into_any()),
        };
        Ok(())
    }

    /// Time added to the core's time stamp by each `predict()` (default 1).
    #[getter]
    fn get_dt(&self) -> f64 {
        self.dt
    }

    #[setter]
    fn set_dt(&mut self, dt: f64) -> PyResult<()> {
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(PyValueError::new_err(format!(
                "dt must be finite and >= 0, got {dt}"
            )));
        }
        self.dt = dt;
        Ok(())
    }

    /// The core's time stamp (the sum of `dt` over the predictions).
    #[getter]
    fn t(&self) -> f64 {
        self.core.time()
    }

    /// Predict: `x = F x (+ B u)`, `P = F P F^T + Q`. `B`, `F`, `Q` override the
    /// filter's for this call (`Q` may be a scalar `q`: `q I`). Raises `ValueError`
    /// with the core's message on bad input; the filter is then unchanged.
    #[pyo3(signature = (u=None, B=None, F=None, Q=None))]
    #[allow(non_snake_case)]
    fn predict(
        &mut self,
        py: Python<'_>,
        u: Option<&Bound<'_, PyAny>>,
        B: Option<&Bound<'_, PyAny>>,
        F: Option<&Bound<'_, PyAny>>,
        Q: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let n = self.dim_x;
        self.sync(py)?;
        let f = match F {
            Some(f) => matrix("F", f, n, n)?,
            None => read2(&self.f, py)?,
        };
        let q = match Q {
            Some(q) => noise_arg("Q", q, n)?,
            None => read2(&self.q, py)?,
        };
        let b_obj = match B {
            Some(b) => Some(b.clone()),
            None => self.b.as_ref().map(|b| b.bind(py).clone()),
        };
        let x_pred = match (u, b_obj) {
            (Some(u), Some(b)) if !u.is_none() => {
                let du = self.dim_u.max(1);
                let u = vector_arg("u", u, du)?;
                let b = matrix("B", &b, n, du)?;
                let x = self.core.state();
                Some(
                    (0..n)
                        .map(|i| {
                            (0..n).map(|j| f[i * n + j] * x[j]).sum::<f64>()
                                + (0..du).map(|j| b[i * du + j] * u[j]).sum::<f64>()
                        })
                        .collect::<Vec<f64>>(),
                )
            }
            _ => None,
        };
        let new_time = self.core.time() + self.dt;
        self.core
            .predict(x_pred.as_deref(), &f, &q, new_time)
            .map_err(core_err)?;
        self.stepped();
        self.x_prior = self.core.state();
        self.p_prior = self.core.covariance();
        Ok(())
    }

    /// Update with the measurement `z` (shape `(dim_z,)`, `(dim_z, 1)` or a scalar
    /// for `dim_z = 1`); `R` (matrix or scalar `r`: `r I`) and `H` override the
    /// filter's for this call. `z = None` skips the update (FilterPy). Raises
    /// `ValueError` with the core's message on bad input; the filter is then unchanged.
    #[pyo3(signature = (z, R=None, H=None))]
    #[allow(non_snake_case)]
    fn update(
        &mut self,
        py: Python<'_>,
        z: Option<&Bound<'_, PyAny>>,
        R: Option<&Bound<'_, PyAny>>,
        H: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let n = self.dim_x;
        self.sync(py)?;
        let Some(z) = z.filter(|z| !z.is_none()) else {
            self.z = None;
            self.last = None;
            self.gain_inputs = None;
            self.x_post = self.core.state();
            self.p_post = self.core.covariance();
            return Ok(());
        };
        let (h, m) = match H {
            Some(h) => {
                let (shape, values) = any_shape("H", h)?;
                let m = match shape.as_slice() {
                    [m, c] if *c == n => *m,
                    [c] if *c == n => 1,
                    _ => {
                        return Err(PyValueError::new_err(format!(
                            "H: expected shape (m, {n}), got {}",
                            shape_text(&shape)
                        )));
                    }
                };
                (values, m)
            }
            None => (read2(&self.h, py)?, self.dim_z),
        };
        let z = vector_arg("z", z, m)?;
        let r = match R {
            Some(r) => noise_arg("R", r, m)?,
            None if m == self.dim_z => read2(&self.r, py)?,
            None => {
                return Err(PyValueError::new_err(format!(
                    "R: H has {m} rows but the filter's R is {0} x {0}; pass R",
                    self.dim_z
                )));
            }
        };
        let p_before = self.core.covariance();
        let info = self.core.update(&z, &h, &r).map_err(core_err)?;
        self.stepped();
        self.z = Some(z);
        self.last = Some(info);
        self.gain_inputs = Some((p_before, h));
        self.x_post = self.core.state();
        self.p_post = self.core.covariance();
        Ok(())
    }

    /// Innovation `y = z - H x` of the last update (zeros before the first).
    #[getter]
    fn y<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        match &self.last {
            Some(l) => vector(py, &l.y, self.x_ndim),
            None => vector(py, &vec![0.0; self.dim_z], self.x_ndim),
        }
    }

    /// Innovation covariance `S = H P H^T + R` of the last update.
    #[getter]
    fn S<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.measurement_shape();
        match &self.last {
            Some(l) => array2(py, &l.s, m, m),
            None => array2(py, &vec![0.0; m * m], m, m),
        }
    }

    /// `S^-1` of the last update.
    #[getter]
    fn SI<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.measurement_shape();
        let si = self
            .last
            .as_ref()
            .and_then(|l| DMatrix::from_row_slice(m, m, &l.s).try_inverse())
            .unwrap_or_else(|| DMatrix::zeros(m, m));
        array2(py, si.transpose().as_slice(), m, m)
    }

    /// Kalman gain `K = P^- H^T S^-1` of the last update.
    #[getter]
    fn K<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (n, m) = (self.dim_x, self.measurement_shape());
        let k = match (&self.last, &self.gain_inputs) {
            (Some(l), Some((p, h))) => {
                let p = DMatrix::from_row_slice(n, n, p);
                let h = DMatrix::from_row_slice(m, n, h);
                let s = DMatrix::from_row_slice(m, m, &l.s);
                // K = P H^T S^-1, from S K^T = H P (S and P symmetric)
                s.cholesky()
                    .map(|c| c.solve(&(h * p)).transpose())
                    .unwrap_or_else(|| DMatrix::zeros(n, m))
            }
            _ => DMatrix::zeros(n, m),
        };
        array2(py, k.transpose().as_slice(), n, m)
    }

    /// The last measurement (`None` before the first update or after `update(None)`).
    #[getter]
    fn z<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArrayDyn<f64>>>> {
        self.z
            .as_ref()
            .map(|z| vector(py, z, self.x_ndim))
            .transpose()
    }

    /// Normalized innovation squared `y^T S^-1 y` of the last update (the core's).
    #[getter]
    fn nis(&self) -> Option<f64> {
        self.last.as_ref().map(|l| l.nis)
    }

    /// Mahalanobis distance of the last innovation, `sqrt(nis)` (FilterPy).
    #[getter]
    fn mahalanobis(&self) -> Option<f64> {
        self.last.as_ref().map(|l| l.nis.sqrt())
    }

    /// Gaussian log-likelihood of the last innovation,
    /// `-(m ln 2 pi + ln det S + nis) / 2`.
    #[getter]
    fn log_likelihood(&self) -> Option<f64> {
        let m = self.measurement_shape();
        self.last.as_ref().map(|l| {
            let det = DMatrix::from_row_slice(m, m, &l.s).determinant();
            -0.5 * ((m as f64) * (2.0 * std::f64::consts::PI).ln() + det.ln() + l.nis)
        })
    }

    /// `exp(log_likelihood)`, at least the smallest positive float (FilterPy).
    #[getter]
    fn likelihood(&self) -> Option<f64> {
        self.log_likelihood()
            .map(|l| l.exp().max(f64::MIN_POSITIVE))
    }

    /// `x` after the last `predict()`.
    #[getter]
    fn x_prior<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        vector(py, &self.x_prior, self.x_ndim)
    }

    /// `P` after the last `predict()`.
    #[getter]
    fn P_prior<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        array2(py, &self.p_prior, self.dim_x, self.dim_x)
    }

    /// `x` after the last `update()`.
    #[getter]
    fn x_post<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        vector(py, &self.x_post, self.x_ndim)
    }

    /// `P` after the last `update()`.
    #[getter]
    fn P_post<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        array2(py, &self.p_post, self.dim_x, self.dim_x)
    }

    fn __repr__(&self) -> String {
        format!(
            "fathom.KalmanFilter(dim_x={}, dim_z={}, dim_u={}, core={}, t={})",
            self.dim_x,
            self.dim_z,
            self.dim_u,
            self.core.kind(),
            self.core.time()
        )
    }

    /// FilterPy's fading-memory factor is not supported (the core's prediction has
    /// none): reading it gives 1.
    #[getter]
    fn alpha(&self) -> f64 {
        1.0
    }

    #[setter]
    fn set_alpha(&mut self, value: f64) -> PyResult<()> {
        if value == 1.0 {
            Ok(())
        } else {
            Err(PyTypeError::new_err(
                "fathom.KalmanFilter has no fading memory: alpha must stay 1",
            ))
        }
    }
}

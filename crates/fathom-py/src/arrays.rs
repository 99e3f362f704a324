//! Reading numpy arrays (or anything numpy can convert) into Rust with shape and
//! finiteness checks that name the argument, and writing results back.

use numpy::{AllowTypeChange, PyArrayLike1, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `obj` as a float64 matrix of exactly `rows x cols` (row-major values); a 1-D input
/// is accepted for a single row or column.
pub(crate) fn matrix(
    name: &str,
    obj: &Bound<'_, PyAny>,
    rows: usize,
    cols: usize,
) -> PyResult<Vec<f64>> {
    let (shape, values) = any_shape(name, obj)?;
    let ok = match shape.as_slice() {
        [r, c] => *r == rows && *c == cols,
        [n] => *n == rows * cols && (rows == 1 || cols == 1),
        [] => rows == 1 && cols == 1,
        _ => false,
    };
    if !ok {
        return Err(PyValueError::new_err(format!(
            "{name}: expected shape ({rows}, {cols}), got {}",
            shape_text(&shape)
        )));
    }
    Ok(values)
}

/// `obj` (any shape) as float64 values in row-major order and its shape.
pub(crate) fn any_shape(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<f64>)> {
    if let Ok(a) = obj.extract::<PyArrayLike2<'_, f64, AllowTypeChange>>() {
        let shape = a.shape().to_vec();
        return Ok((shape, a.as_array().iter().copied().collect()));
    }
    if let Ok(a) = obj.extract::<PyArrayLike1<'_, f64, AllowTypeChange>>() {
        let shape = a.shape().to_vec();
        return Ok((shape, a.as_array().iter().copied().collect()));
    }
    if let Ok(v) = obj.extract::<f64>() {
        return Ok((Vec::new(), vec![v]));
    }
    Err(PyValueError::new_err(format!(
        "{name}: expected a real number or a 1-D or 2-D array of real numbers"
    )))
}

/// `(a, b)` for a shape.
pub(crate) fn shape_text(shape: &[usize]) -> String {
    match shape {
        [] => "() (a scalar)".into(),
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// An `(n, 3)` float array as points, every entry finite.
pub(crate) fn points(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 3]>> {
    let a = obj
        .extract::<PyArrayLike2<'_, f64, AllowTypeChange>>()
        .map_err(|_| {
            PyValueError::new_err(format!("{name}: expected an (N, 3) array of real numbers"))
        })?;
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name}: expected shape (N, 3), got {}",
            shape_text(shape)
        )));
    }
    let view = a.as_array();
    let mut out = Vec::with_capacity(shape[0]);
    // contiguous rows (the usual case) are read as one slice
    let flat: Vec<f64>;
    let values: &[f64] = match view.as_slice() {
        Some(s) => s,
        None => {
            flat = view.iter().copied().collect();
            &flat
        }
    };
    for (i, row) in values.chunks_exact(3).enumerate() {
        let p = [row[0], row[1], row[2]];
        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
            let v = p
                .iter()
                .find(|v| !v.is_finite())
                .copied()
                .unwrap_or(f64::NAN);
            return Err(PyValueError::new_err(format!(
                "{name}: row {i} is not finite ({v})"
            )));
        }
        out.push(p);
    }
    Ok(out)
}

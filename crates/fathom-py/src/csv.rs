//! A run's CSV series as numpy arrays: the columns of each CSV file the analysis made
//! (`fathom_sim::experiment::FileContent::csv_columns`), taken as values: a column of
//! numbers becomes a float64 numpy array, a column with a text cell a list of str (the
//! cells as the file shows them). No CSV text is rendered or read back.

use fathom_sim::experiment::ColumnValues;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// The columns of one CSV file as a dict: header -> float64 array or list of str, in
/// the file's column order.
pub(crate) fn columns<'py>(
    py: Python<'py>,
    columns: Vec<(&str, ColumnValues)>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (header, values) in columns {
        match values {
            ColumnValues::Numbers(v) => dict.set_item(header, PyArray1::from_vec(py, v))?,
            ColumnValues::Text(cells) => dict.set_item(header, PyList::new(py, cells)?)?,
        }
    }
    Ok(dict)
}

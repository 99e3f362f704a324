//! The CSV files of a run (`fathom_report::output`'s format: one header row, `\n` line
//! ends, RFC 4180 quoting of text cells) as columns: a column whose every cell is a
//! number (`NaN` and `inf` included) becomes a float64 numpy array, any other column a
//! list of strings.

use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// The records of `text` (cells unquoted); `name` labels errors.
fn records(name: &str, text: &str) -> PyResult<Vec<Vec<String>>> {
    let mut out = Vec::new();
    let mut record = Vec::new();
    let mut cell = String::new();
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    let mut line = 1usize;
    while let Some(c) = chars.next() {
        if quoted {
            match c {
                '"' if chars.peek() == Some(&'"') => {
                    chars.next();
                    cell.push('"');
                }
                '"' => quoted = false,
                _ => {
                    if c == '\n' {
                        line += 1;
                    }
                    cell.push(c);
                }
            }
            continue;
        }
        match c {
            '"' if cell.is_empty() => quoted = true,
            ',' => record.push(std::mem::take(&mut cell)),
            '\r' => {}
            '\n' => {
                record.push(std::mem::take(&mut cell));
                out.push(std::mem::take(&mut record));
                line += 1;
            }
            _ => cell.push(c),
        }
    }
    if quoted {
        return Err(PyValueError::new_err(format!(
            "{name}: unterminated quoted cell at line {line}"
        )));
    }
    if !cell.is_empty() || !record.is_empty() {
        record.push(cell);
        out.push(record);
    }
    Ok(out)
}

/// The columns of the CSV `text` as a dict: header -> float64 array or list of str.
pub(crate) fn columns<'py>(
    py: Python<'py>,
    name: &str,
    text: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let mut rows = records(name, text)?.into_iter();
    let headers = rows
        .next()
        .ok_or_else(|| PyValueError::new_err(format!("{name}: no header row")))?;
    let rows: Vec<Vec<String>> = rows.collect();
    for (i, r) in rows.iter().enumerate() {
        if r.len() != headers.len() {
            return Err(PyValueError::new_err(format!(
                "{name}: record {i} has {} cells, the header has {}",
                r.len(),
                headers.len()
            )));
        }
    }
    let dict = PyDict::new(py);
    for (j, h) in headers.iter().enumerate() {
        let numbers: Option<Vec<f64>> = rows.iter().map(|r| r[j].parse::<f64>().ok()).collect();
        match numbers {
            Some(v) => dict.set_item(h, PyArray1::from_vec(py, v))?,
            None => dict.set_item(h, PyList::new(py, rows.iter().map(|r| r[j].as_str()))?)?,
        }
    }
    Ok(dict)
}

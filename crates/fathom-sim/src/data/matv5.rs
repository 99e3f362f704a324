//! A minimal MATLAB v5 (Level 5 MAT-file) writer for real `double` matrices.
//!
//! Only what is needed to produce a file that MATLAB, SciPy and the `matfile` crate
//! read back: the 128-byte header (little-endian, `IM` endian indicator) and one
//! uncompressed `miMATRIX` element per matrix (array flags with class
//! `mxDOUBLE_CLASS`, dimensions, name, real part in column-major order).

use std::path::Path;

use crate::SimError;

const MI_INT8: u32 = 1;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MX_DOUBLE_CLASS: u32 = 6;

/// A named real matrix stored row by row (`rows.len()` rows of equal length).
#[derive(Debug, Clone, PartialEq)]
pub struct NamedMatrix {
    /// Variable name (ASCII letters, digits and `_`, starting with a letter).
    pub name: String,
    /// The rows.
    pub rows: Vec<Vec<f64>>,
}

impl NamedMatrix {
    /// A matrix from its name and rows.
    pub fn new(name: impl Into<String>, rows: Vec<Vec<f64>>) -> Self {
        NamedMatrix {
            name: name.into(),
            rows,
        }
    }
}

fn push_tag(out: &mut Vec<u8>, data_type: u32, n_bytes: usize) {
    out.extend_from_slice(&data_type.to_le_bytes());
    // Sizes are checked by the caller to fit in u32.
    out.extend_from_slice(&(n_bytes as u32).to_le_bytes());
}

fn pad8(out: &mut Vec<u8>) {
    while !out.len().is_multiple_of(8) {
        out.push(0);
    }
}

/// The bytes of a MAT v5 file holding `matrices`.
///
/// # Errors
/// [`SimError::InvalidArgument`] for a bad name, ragged rows or a matrix too large
/// for a v5 element (`> 2^31` bytes).
pub fn mat_v5_bytes(matrices: &[NamedMatrix]) -> Result<Vec<u8>, SimError> {
    let mut out = Vec::new();
    let mut header = b"MATLAB 5.0 MAT-file, written by fathom".to_vec();
    header.resize(116, b' ');
    out.extend_from_slice(&header);
    out.extend_from_slice(&[0u8; 8]); // no subsystem data
    out.extend_from_slice(&0x0100u16.to_le_bytes());
    out.extend_from_slice(b"IM");
    for m in matrices {
        let ok_name = m
            .name
            .chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic())
            && m.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !ok_name {
            return Err(SimError::invalid_argument(
                "MAT matrix name",
                format!("`{}` is not a MATLAB variable name", m.name),
            ));
        }
        let n_rows = m.rows.len();
        let n_cols = m.rows.first().map_or(0, Vec::len);
        if let Some((i, r)) = m.rows.iter().enumerate().find(|(_, r)| r.len() != n_cols) {
            return Err(SimError::invalid_argument(
                format!("MAT matrix `{}`", m.name),
                format!("row {} has {} values, row 1 has {n_cols}", i + 1, r.len()),
            ));
        }
        let data_bytes = 8 * n_rows * n_cols;
        if data_bytes > (i32::MAX as usize) / 2 {
            return Err(SimError::invalid_argument(
                format!("MAT matrix `{}`", m.name),
                "too large for a MAT v5 element",
            ));
        }
        let mut body = Vec::new();
        push_tag(&mut body, MI_UINT32, 8);
        body.extend_from_slice(&MX_DOUBLE_CLASS.to_le_bytes());
        body.extend_from_slice(&0u32.to_le_bytes());
        push_tag(&mut body, MI_INT32, 8);
        body.extend_from_slice(&(n_rows as i32).to_le_bytes());
        body.extend_from_slice(&(n_cols as i32).to_le_bytes());
        push_tag(&mut body, MI_INT8, m.name.len());
        body.extend_from_slice(m.name.as_bytes());
        pad8(&mut body);
        push_tag(&mut body, MI_DOUBLE, data_bytes);
        for c in 0..n_cols {
            for r in &m.rows {
                body.extend_from_slice(&r[c].to_le_bytes());
            }
        }
        pad8(&mut body);
        push_tag(&mut out, MI_MATRIX, body.len());
        out.extend_from_slice(&body);
    }
    Ok(out)
}

/// Write `matrices` as a MAT v5 file at `path`.
///
/// # Errors
/// As [`mat_v5_bytes`], and [`SimError::Io`] on write failure.
pub fn write_mat_v5(path: impl AsRef<Path>, matrices: &[NamedMatrix]) -> Result<(), SimError> {
    let path = path.as_ref();
    let bytes = mat_v5_bytes(matrices)?;
    std::fs::write(path, bytes).map_err(|e| SimError::io("write", path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_the_matfile_crate() {
        let bytes = mat_v5_bytes(&[
            NamedMatrix::new("TL", vec![vec![1.0, 2.5, -3.0], vec![4.0, 5.0, 6.0]]),
            NamedMatrix::new("x", vec![vec![0.1]]),
        ])
        .unwrap();
        let mat = matfile::MatFile::parse(bytes.as_slice()).unwrap();
        let tl = mat.find_by_name("TL").unwrap();
        assert_eq!(tl.size(), &vec![2, 3]);
        match tl.data() {
            matfile::NumericData::Double { real, .. } => {
                assert_eq!(real, &vec![1.0, 4.0, 2.5, 5.0, -3.0, 6.0]);
            }
            other => panic!("unexpected {other:?}"),
        }
        assert!(mat.find_by_name("x").is_some());
    }

    #[test]
    fn rejects_bad_names_and_ragged_rows() {
        assert!(mat_v5_bytes(&[NamedMatrix::new("1x", vec![vec![1.0]])]).is_err());
        assert!(mat_v5_bytes(&[NamedMatrix::new("a", vec![vec![1.0], vec![]])]).is_err());
    }
}

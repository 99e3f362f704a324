//! A minimal MATLAB v5 (Level 5 MAT-file) writer for real `double` matrices, and a
//! reader of the numeric matrices in such a file.
//!
//! Writing: only what is needed to produce a file that MATLAB, SciPy and the `matfile`
//! crate read back: the 128-byte header (little-endian, `IM` endian indicator) and one
//! uncompressed `miMATRIX` element per matrix (array flags with class
//! `mxDOUBLE_CLASS`, dimensions, name, real part in column-major order).
//!
//! Reading ([`read_mat_v5`]): little- and big-endian files, `miMATRIX` elements plain
//! or inside `miCOMPRESSED` (zlib) elements, small and long data-element tags, numeric
//! classes stored as any numeric MAT type (MATLAB stores whole-number doubles as
//! `miUINT8` and the like), converted to `f64`. Cell, struct, object, char and sparse
//! arrays are listed by name but not decoded. The reader is meant for untrusted files
//! (it is fuzzed, see docs/fuzzing.md): every length is checked against the bytes
//! present before anything is allocated, dimension products are checked for overflow,
//! inflated data is capped at [`MAX_INFLATED_BYTES`] per file, and every problem is a
//! [`MatError`] naming the byte offset, never a panic.

use std::io::Read;
use std::path::Path;

// MAT v5 data types (`mi*`) and the array class the writer uses (`mx*`).
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
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
/// [`MatWriteError::Invalid`] for a bad name, ragged rows or a matrix too large
/// for a v5 element (`> 2^31` bytes).
pub fn mat_v5_bytes(matrices: &[NamedMatrix]) -> Result<Vec<u8>, MatWriteError> {
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
            return Err(MatWriteError::invalid(
                "MAT matrix name",
                format!("`{}` is not a MATLAB variable name", m.name),
            ));
        }
        let n_rows = m.rows.len();
        let n_cols = m.rows.first().map_or(0, Vec::len);
        if let Some((i, r)) = m.rows.iter().enumerate().find(|(_, r)| r.len() != n_cols) {
            return Err(MatWriteError::invalid(
                format!("MAT matrix `{}`", m.name),
                format!("row {} has {} values, row 1 has {n_cols}", i + 1, r.len()),
            ));
        }
        let data_bytes = 8 * n_rows * n_cols;
        if data_bytes > (i32::MAX as usize) / 2 {
            return Err(MatWriteError::invalid(
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
/// As [`mat_v5_bytes`], and [`MatWriteError::Io`] on write failure.
pub fn write_mat_v5(path: impl AsRef<Path>, matrices: &[NamedMatrix]) -> Result<(), MatWriteError> {
    let path = path.as_ref();
    let bytes = mat_v5_bytes(matrices)?;
    std::fs::write(path, bytes).map_err(|source| MatWriteError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Most bytes [`read_mat_v5`] inflates from the `miCOMPRESSED` elements of one file
/// (64 MiB; a Plaza data set inflates to about 1.3 MB). Bounds the memory a small
/// malicious file can make the reader use.
pub const MAX_INFLATED_BYTES: usize = 64 << 20;

/// Why a MAT v5 file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum MatWriteError {
    /// A matrix cannot be written (bad name, ragged rows, too large).
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// Which matrix.
        what: String,
        /// Why it is refused.
        reason: String,
    },
    /// Writing the file failed.
    #[error("cannot write `{}`", fathom_core::echo::echo_path(path))]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

impl MatWriteError {
    fn invalid(what: impl Into<String>, reason: impl Into<String>) -> Self {
        MatWriteError::Invalid {
            what: what.into(),
            reason: reason.into(),
        }
    }
}

/// Everything that can be wrong with a MAT v5 file. `element` is the byte offset of
/// the top-level data element in the file; `at` the offset inside that element's data
/// (inflated data for a compressed element).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MatError {
    /// The 128-byte header is missing or not a MAT v5 header.
    #[error("header: {reason}")]
    Header {
        /// What is wrong.
        reason: String,
    },
    /// A tag or data runs past the end of the bytes present.
    #[error(
        "element at byte {element}, offset {at}: {what} needs {needed} bytes, {available} left"
    )]
    Truncated {
        /// Top-level element offset in the file.
        element: usize,
        /// Offset inside the element's data.
        at: usize,
        /// What was being read.
        what: &'static str,
        /// Bytes needed.
        needed: u64,
        /// Bytes left.
        available: usize,
    },
    /// A sub-element has an unexpected data type, size or value.
    #[error("element at byte {element}, offset {at}: {what}: {reason}")]
    Invalid {
        /// Top-level element offset in the file.
        element: usize,
        /// Offset inside the element's data.
        at: usize,
        /// What was being read (`array flags`, `dimensions`, ...).
        what: &'static str,
        /// What is wrong, with the values read.
        reason: String,
    },
    /// A compressed element does not inflate.
    #[error("element at byte {element}: compressed data: {reason}")]
    Inflate {
        /// Top-level element offset in the file.
        element: usize,
        /// The decompressor's message, or the size limit exceeded.
        reason: String,
    },
}

/// The class of a MAT array (`mxCLASS`), with the numeric ones decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatClass {
    /// `mxDOUBLE_CLASS`.
    Double,
    /// `mxSINGLE_CLASS`.
    Single,
    /// An integer class: `mxINT8_CLASS` ... `mxUINT64_CLASS` (the MAT class number).
    Integer(u8),
    /// Cell, struct, object, char, sparse or another class whose data is not decoded
    /// (the MAT class number).
    Other(u8),
}

/// One array of a MAT v5 file.
#[derive(Debug, Clone, PartialEq)]
pub struct MatArray {
    /// Variable name (lossy UTF-8).
    pub name: String,
    /// Class.
    pub class: MatClass,
    /// Dimensions (empty when the class is [`MatClass::Other`]).
    pub dims: Vec<usize>,
    /// Real part, column-major, converted to `f64` (empty for [`MatClass::Other`];
    /// 64-bit integers beyond 2^53 are rounded).
    pub real: Vec<f64>,
    /// Whether the array also has an imaginary part (read and checked, not kept).
    pub complex: bool,
}

#[derive(Clone, Copy)]
struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
    element: usize,
}

impl<'a> Reader<'a> {
    fn truncated(&self, what: &'static str, needed: u64) -> MatError {
        MatError::Truncated {
            element: self.element,
            at: self.pos,
            what,
            needed,
            available: self.data.len() - self.pos,
        }
    }

    fn invalid(&self, at: usize, what: &'static str, reason: String) -> MatError {
        MatError::Invalid {
            element: self.element,
            at,
            what,
            reason,
        }
    }

    fn left(&self) -> usize {
        self.data.len() - self.pos
    }

    fn bytes(&mut self, n: u64, what: &'static str) -> Result<&'a [u8], MatError> {
        let n_usize = usize::try_from(n).ok().filter(|&n| n <= self.left());
        let Some(n) = n_usize else {
            return Err(self.truncated(what, n));
        };
        let out = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, MatError> {
        let b: [u8; 4] = self.bytes(4, what)?.try_into().expect("4 bytes");
        Ok(if self.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }

    /// Skips padding up to the next multiple of 8 of the element data, or to the end.
    fn pad8(&mut self) {
        let target = self.pos.next_multiple_of(8).min(self.data.len());
        self.pos = target;
    }

    /// A data-element tag and its data: `(type, data)`; small elements (data in the tag)
    /// and long ones (data padded to 8 bytes).
    fn element(&mut self, what: &'static str) -> Result<(u32, &'a [u8]), MatError> {
        let first = self.u32(what)?;
        if first >> 16 != 0 {
            let n = first >> 16;
            if n > 4 {
                return Err(self.invalid(
                    self.pos - 4,
                    what,
                    format!("small data element of {n} bytes (at most 4)"),
                ));
            }
            let four = self.bytes(4, what)?;
            return Ok((first & 0xFFFF, &four[..n as usize]));
        }
        let n = self.u32(what)?;
        let data = self.bytes(u64::from(n), what)?;
        self.pad8();
        Ok((first, data))
    }
}

/// Size in bytes of one value of numeric MAT data type `t`.
fn numeric_size(t: u32) -> Option<usize> {
    match t {
        MI_INT8 | MI_UINT8 => Some(1),
        MI_INT16 | MI_UINT16 => Some(2),
        MI_INT32 | MI_UINT32 | MI_SINGLE => Some(4),
        MI_DOUBLE | MI_INT64 | MI_UINT64 => Some(8),
        _ => None,
    }
}

/// `data` of numeric type `t` as `f64`.
fn to_f64(t: u32, data: &[u8], big_endian: bool) -> Vec<f64> {
    macro_rules! conv {
        ($ty:ty, $n:expr) => {
            data.chunks_exact($n)
                .map(|c| {
                    let b: [u8; $n] = c.try_into().expect("chunk");
                    let v = if big_endian {
                        <$ty>::from_be_bytes(b)
                    } else {
                        <$ty>::from_le_bytes(b)
                    };
                    v as f64
                })
                .collect()
        };
    }
    match t {
        MI_INT8 => conv!(i8, 1),
        MI_UINT8 => conv!(u8, 1),
        MI_INT16 => conv!(i16, 2),
        MI_UINT16 => conv!(u16, 2),
        MI_INT32 => conv!(i32, 4),
        MI_UINT32 => conv!(u32, 4),
        MI_SINGLE => conv!(f32, 4),
        MI_DOUBLE => conv!(f64, 8),
        MI_INT64 => conv!(i64, 8),
        _ => conv!(u64, 8),
    }
}

/// One numeric part (real or imaginary) holding `count` values.
fn numeric_part(
    r: &mut Reader<'_>,
    count: usize,
    what: &'static str,
) -> Result<Vec<f64>, MatError> {
    let at = r.pos;
    let (t, data) = r.element(what)?;
    let Some(size) = numeric_size(t) else {
        return Err(r.invalid(at, what, format!("data type {t} is not numeric")));
    };
    if data.len() % size != 0 || data.len() / size != count {
        return Err(r.invalid(
            at,
            what,
            format!(
                "{} bytes of type {t} for {count} values of {size} bytes",
                data.len()
            ),
        ));
    }
    Ok(to_f64(t, data, r.big_endian))
}

/// The body of one `miMATRIX` element.
fn matrix(r: &mut Reader<'_>) -> Result<MatArray, MatError> {
    let at = r.pos;
    let (t, flags) = r.element("array flags")?;
    if t != MI_UINT32 || flags.len() != 8 {
        return Err(r.invalid(
            at,
            "array flags",
            format!(
                "type {t} with {} bytes (expected miUINT32, 8 bytes)",
                flags.len()
            ),
        ));
    }
    let word: [u8; 4] = flags[..4].try_into().expect("4 bytes");
    let word = if r.big_endian {
        u32::from_be_bytes(word)
    } else {
        u32::from_le_bytes(word)
    };
    let class_id = (word & 0xFF) as u8;
    let complex = word & 0x0800 != 0;
    let class = match class_id {
        6 => MatClass::Double,
        7 => MatClass::Single,
        8..=15 => MatClass::Integer(class_id),
        other => MatClass::Other(other),
    };
    let at = r.pos;
    let (t, dims_data) = r.element("dimensions")?;
    if t != MI_INT32 || dims_data.len() < 8 || dims_data.len() % 4 != 0 {
        return Err(r.invalid(
            at,
            "dimensions",
            format!(
                "type {t} with {} bytes (expected miINT32, at least 2 dimensions)",
                dims_data.len()
            ),
        ));
    }
    let at = r.pos;
    let (t, name) = r.element("array name")?;
    if t != MI_INT8 {
        return Err(r.invalid(at, "array name", format!("type {t} (expected miINT8)")));
    }
    let name = String::from_utf8_lossy(name).into_owned();
    if let MatClass::Other(_) = class {
        return Ok(MatArray {
            name,
            class,
            dims: Vec::new(),
            real: Vec::new(),
            complex,
        });
    }
    let mut dims = Vec::with_capacity(dims_data.len() / 4);
    for d in to_f64(MI_INT32, dims_data, r.big_endian) {
        if d < 0.0 {
            return Err(r.invalid(at, "dimensions", format!("negative dimension {d}")));
        }
        dims.push(d as usize);
    }
    let Some(count) = dims.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d)) else {
        return Err(r.invalid(
            at,
            "dimensions",
            format!("{dims:?} overflow the element count"),
        ));
    };
    let real = numeric_part(r, count, "real part")?;
    if complex {
        numeric_part(r, count, "imaginary part")?;
    }
    Ok(MatArray {
        name,
        class,
        dims,
        real,
        complex,
    })
}

/// The top-level elements in `data` (a file body, or the inflated data of a compressed
/// element when `inside` is that element's offset), appended to `out`.
fn elements(
    data: &[u8],
    base: usize,
    inside: Option<usize>,
    big_endian: bool,
    inflated: &mut usize,
    max_inflated: usize,
    out: &mut Vec<MatArray>,
) -> Result<(), MatError> {
    let mut pos = 0;
    while pos < data.len() {
        let element = inside.unwrap_or(base + pos);
        let mut r = Reader {
            data,
            pos,
            big_endian,
            element,
        };
        let (t, body) = r.element("data element")?;
        match t {
            MI_MATRIX => {
                let mut m = Reader {
                    data: body,
                    pos: 0,
                    big_endian,
                    element,
                };
                out.push(matrix(&mut m)?);
            }
            MI_COMPRESSED if inside.is_none() => {
                let limit = max_inflated - *inflated;
                let inflate_err = |reason: String| MatError::Inflate { element, reason };
                let mut buf = Vec::new();
                libflate::zlib::Decoder::new(body)
                    .map_err(|e| inflate_err(e.to_string()))?
                    .take(limit as u64 + 1)
                    .read_to_end(&mut buf)
                    .map_err(|e| inflate_err(e.to_string()))?;
                if buf.len() > limit {
                    return Err(inflate_err(format!(
                        "inflates past the reader's limit of {max_inflated} bytes per file"
                    )));
                }
                *inflated += buf.len();
                elements(
                    &buf,
                    0,
                    Some(element),
                    big_endian,
                    inflated,
                    max_inflated,
                    out,
                )?;
            }
            MI_COMPRESSED => {
                return Err(r.invalid(
                    pos,
                    "data element",
                    "compressed element inside a compressed element".into(),
                ));
            }
            // Other top-level data types carry no variable: skipped.
            _ => {}
        }
        // Compressed elements are not padded (MATLAB writes them back to back).
        pos = if t == MI_COMPRESSED {
            pos + 8 + body.len()
        } else {
            r.pos
        };
    }
    Ok(())
}

/// The arrays of a MAT v5 file, in file order.
///
/// # Errors
/// A [`MatError`] naming the byte offset: no MAT v5 header (MAT v7.3 files are HDF5
/// and not read), a tag or data running past the end, an unexpected sub-element type
/// or size, a dimension product that overflows or does not match the data, data that
/// does not inflate or inflates past [`MAX_INFLATED_BYTES`].
pub fn read_mat_v5(bytes: &[u8]) -> Result<Vec<MatArray>, MatError> {
    read_mat_v5_limited(bytes, MAX_INFLATED_BYTES)
}

/// [`read_mat_v5`] with another cap on the inflated bytes.
fn read_mat_v5_limited(bytes: &[u8], max_inflated: usize) -> Result<Vec<MatArray>, MatError> {
    let header_err = |reason: String| MatError::Header { reason };
    if bytes.len() < 128 {
        return Err(header_err(format!(
            "{} bytes, a MAT v5 file starts with a 128-byte header",
            bytes.len()
        )));
    }
    let big_endian = match &bytes[126..128] {
        b"IM" => false,
        b"MI" => true,
        other => {
            return Err(header_err(format!(
                "endian indicator {other:?} (expected \"IM\" or \"MI\")"
            )));
        }
    };
    let v = [bytes[124], bytes[125]];
    let version = if big_endian {
        u16::from_be_bytes(v)
    } else {
        u16::from_le_bytes(v)
    };
    if version != 0x0100 {
        return Err(header_err(format!(
            "version {version:#06x} (expected 0x0100; 0x0200 is MAT v7.3, HDF5, not read)"
        )));
    }
    let mut out = Vec::new();
    let mut inflated = 0;
    elements(
        &bytes[128..],
        128,
        None,
        big_endian,
        &mut inflated,
        max_inflated,
        &mut out,
    )?;
    Ok(out)
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

    fn deflate(data: &[u8]) -> Vec<u8> {
        use std::io::Write;
        let mut e = libflate::zlib::Encoder::new(Vec::new()).unwrap();
        e.write_all(data).unwrap();
        e.finish().into_result().unwrap()
    }

    /// `bytes` (a file from [`mat_v5_bytes`]) with every element compressed.
    fn compressed(bytes: &[u8]) -> Vec<u8> {
        let mut out = bytes[..128].to_vec();
        let mut pos = 128;
        while pos < bytes.len() {
            let n = u32::from_le_bytes(bytes[pos + 4..pos + 8].try_into().unwrap()) as usize;
            let z = deflate(&bytes[pos..pos + 8 + n]);
            out.extend_from_slice(&MI_COMPRESSED.to_le_bytes());
            out.extend_from_slice(&(z.len() as u32).to_le_bytes());
            out.extend_from_slice(&z);
            pos += 8 + n;
        }
        out
    }

    fn two_matrices() -> Vec<u8> {
        mat_v5_bytes(&[
            NamedMatrix::new("TL", vec![vec![1.0, 2.5, -3.0], vec![4.0, 5.0, 6.0]]),
            NamedMatrix::new("x", vec![vec![0.1]]),
        ])
        .unwrap()
    }

    #[test]
    fn reads_back_what_it_writes_plain_and_compressed() {
        for bytes in [two_matrices(), compressed(&two_matrices())] {
            let arrays = read_mat_v5(&bytes).unwrap();
            assert_eq!(arrays.len(), 2);
            assert_eq!(arrays[0].name, "TL");
            assert_eq!(arrays[0].class, MatClass::Double);
            assert_eq!(arrays[0].dims, [2, 3]);
            assert_eq!(arrays[0].real, [1.0, 4.0, 2.5, 5.0, -3.0, 6.0]);
            assert_eq!(arrays[1].real, [0.1]);
        }
    }

    /// A hand-made big-endian file: a 1 x 2 double matrix stored as `miUINT8` values,
    /// with small-format tags for the name and the data (as MATLAB writes them).
    #[test]
    fn reads_big_endian_small_tags_and_narrow_types() {
        let mut f = vec![b' '; 116];
        f.extend_from_slice(&[0; 8]);
        f.extend_from_slice(&0x0100u16.to_be_bytes());
        f.extend_from_slice(b"MI");
        let mut body = Vec::new();
        for w in [MI_UINT32, 8, MX_DOUBLE_CLASS, 0, MI_INT32, 8, 1, 2] {
            body.extend_from_slice(&w.to_be_bytes());
        }
        body.extend_from_slice(&((1u32 << 16) | MI_INT8).to_be_bytes());
        body.extend_from_slice(b"a\0\0\0");
        body.extend_from_slice(&((2u32 << 16) | MI_UINT8).to_be_bytes());
        body.extend_from_slice(&[7, 200, 0, 0]);
        f.extend_from_slice(&MI_MATRIX.to_be_bytes());
        f.extend_from_slice(&(body.len() as u32).to_be_bytes());
        f.extend_from_slice(&body);
        let arrays = read_mat_v5(&f).unwrap();
        assert_eq!(arrays[0].name, "a");
        assert_eq!(arrays[0].dims, [1, 2]);
        assert_eq!(arrays[0].real, [7.0, 200.0]);
    }

    #[test]
    fn malformed_files_are_errors_naming_the_offset() {
        let good = two_matrices();
        let e = read_mat_v5(&good[..100]).unwrap_err();
        assert!(e.to_string().contains("128-byte header"), "{e}");
        let e = read_mat_v5(&good[..good.len() - 3]).unwrap_err();
        assert!(
            matches!(e, MatError::Truncated { element, .. } if element > 128),
            "{e}"
        );
        // Dimensions (2^31-1) x (2^31-1) for 6 values: a mismatch, not a wrapped
        // product or an attempt to allocate 2^62 values.
        let mut bad = good.clone();
        let dims_at = 128 + 8 + 16 + 8;
        bad[dims_at..dims_at + 4].copy_from_slice(&i32::MAX.to_le_bytes());
        bad[dims_at + 4..dims_at + 8].copy_from_slice(&i32::MAX.to_le_bytes());
        let e = read_mat_v5(&bad).unwrap_err();
        assert!(e.to_string().contains("real part"), "{e}");
        bad[dims_at..dims_at + 4].copy_from_slice(&(-2i32).to_le_bytes());
        let e = read_mat_v5(&bad).unwrap_err();
        assert!(e.to_string().contains("negative dimension -2"), "{e}");
        // A long tag claiming 4 GiB of data.
        let mut bad = good.clone();
        bad[132..136].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = read_mat_v5(&bad).unwrap_err();
        assert!(
            e.to_string()
                .contains("data element needs 4294967295 bytes"),
            "{e}"
        );
        let mut bad = good.clone();
        bad[124] = 0;
        bad[125] = 2;
        let e = read_mat_v5(&bad).unwrap_err();
        assert!(e.to_string().contains("MAT v7.3"), "{e}");
    }

    #[test]
    fn inflated_size_is_capped() {
        let bytes = compressed(&two_matrices());
        assert!(read_mat_v5_limited(&bytes, 1 << 10).is_ok());
        let e = read_mat_v5_limited(&bytes, 100).unwrap_err();
        assert!(e.to_string().contains("limit of 100 bytes"), "{e}");
        let mut bad = bytes.clone();
        let last = bad.len() - 1;
        bad[last] ^= 0xFF;
        assert!(matches!(
            read_mat_v5(&bad).unwrap_err(),
            MatError::Inflate { .. }
        ));
    }

    /// On the real Plaza1 file (the repository's copy, `data/plaza1`): the same arrays
    /// as the independent `matfile` reader.
    #[test]
    fn agrees_with_the_matfile_crate_on_real_data() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/plaza1/Plaza1_.mat");
        let bytes = std::fs::read(&path).unwrap();
        let ours = read_mat_v5(&bytes).unwrap();
        let theirs = matfile::MatFile::parse(bytes.as_slice()).unwrap();
        assert_eq!(ours.len(), theirs.arrays().len());
        for (a, b) in ours.iter().zip(theirs.arrays()) {
            assert_eq!(a.name, b.name());
            assert_eq!(&a.dims, b.size());
            match b.data() {
                matfile::NumericData::Double { real, .. } => assert_eq!(&a.real, real),
                other => panic!("unexpected {other:?}"),
            }
        }
    }
}

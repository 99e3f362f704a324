//! Errors of the map crate: malformed mesh files (naming the line or face), invalid
//! meshes and invalid parameters. Nothing in the crate panics on bad input.

use fathom_core::echo::{echo, echo_file, echo_message};

/// Errors of `fathom-map`; every variant names the element that failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MapError {
    /// An OBJ file could not be read at a line (1-based).
    #[error("OBJ line {line}: {}", echo_message(reason))]
    ObjLine {
        /// 1-based line number.
        line: usize,
        /// What is wrong there.
        reason: String,
    },
    /// An OBJ file is malformed in a way no single line can be blamed for.
    #[error("OBJ: {}", echo_message(reason))]
    Obj {
        /// What is wrong.
        reason: String,
    },
    /// `usemtl` names a material the material table does not map.
    #[error(
        "OBJ line {line}: unknown material `{}` (map it in the import settings' material table)",
        echo(name)
    )]
    UnknownMaterial {
        /// The material name as written.
        name: String,
        /// 1-based line number of the first `usemtl` naming it.
        line: usize,
    },
    /// Faces come before any `usemtl` and no default material is set.
    #[error(
        "OBJ line {line}: face without a material (no `usemtl` before it and no default material)"
    )]
    MissingMaterial {
        /// 1-based line number of the first such face.
        line: usize,
    },
    /// An STL file is malformed at a face (0-based).
    #[error("STL face {face}: {}", echo_message(reason))]
    StlFace {
        /// 0-based face index.
        face: usize,
        /// What is wrong there.
        reason: String,
    },
    /// An STL file is malformed before its first face (header, size).
    #[error("STL: {}", echo_message(reason))]
    Stl {
        /// What is wrong.
        reason: String,
    },
    /// The input is larger than the import settings allow.
    #[error("input of {bytes} bytes exceeds the limit of {limit} bytes (`max_bytes`)")]
    TooLarge {
        /// Size of the input (or the bytes read before stopping), bytes.
        bytes: u64,
        /// The limit.
        limit: u64,
    },
    /// The input could not be read.
    #[error("reading the input failed: {}", echo_message(.0))]
    Io(String),
    /// A vertex is not finite or beyond [`crate::mesh::MAX_COORD`].
    #[error("vertex {index}: {value} is not finite or beyond +-{max} m")]
    BadVertex {
        /// 0-based vertex index.
        index: usize,
        /// The offending coordinate.
        value: f64,
        /// The bound, m.
        max: f64,
    },
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle}: vertex index {index} out of range ({vertices} vertices)")]
    IndexOutOfRange {
        /// 0-based triangle index.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// Per-triangle materials and triangles differ in number.
    #[error("{triangles} triangles but {materials} materials")]
    MaterialCount {
        /// Number of triangles.
        triangles: usize,
        /// Number of materials.
        materials: usize,
    },
    /// More triangles or vertices than a `u32` index can address.
    #[error("{what}: {count} exceeds the u32 index range")]
    TooManyElements {
        /// Vertices or triangles.
        what: &'static str,
        /// How many.
        count: usize,
    },
    /// A parameter is out of its valid range.
    #[error("invalid parameter `{}` = {value}: {reason}", echo(field))]
    InvalidParameter {
        /// The parameter's name.
        field: String,
        /// The offending value.
        value: f64,
        /// What was expected.
        reason: &'static str,
    },
}

impl MapError {
    /// This error as met reading the file `file` (the readers take bytes; the caller
    /// that opened the file names it).
    pub fn in_file(self, file: impl Into<String>) -> FileError {
        FileError {
            file: file.into(),
            error: self,
        }
    }
}

/// A [`MapError`] with the name of the file it came from: `` `file`: error ``.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{}`: {error}", echo_file(file))]
pub struct FileError {
    /// The file's name or path, as the caller gave it.
    pub file: String,
    /// What went wrong.
    #[source]
    pub error: MapError,
}

/// Checks that `value` is finite and `> 0`.
pub(crate) fn check_positive(field: &str, value: f64) -> Result<f64, MapError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(MapError::InvalidParameter {
            field: field.to_owned(),
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// Smallest dimension of a preset world's feature, m: 10 cm. Below it a feature is
/// thinner than the sensors modelled resolve and than the vehicle's own size, and a
/// path that close to a surface grazes it.
pub const MIN_FEATURE_M: f64 = 0.1;

/// Checks a preset world's dimension: finite and at least [`MIN_FEATURE_M`].
pub(crate) fn check_feature(field: &str, value: f64) -> Result<f64, MapError> {
    if value.is_finite() && value >= MIN_FEATURE_M {
        Ok(value)
    } else {
        Err(MapError::InvalidParameter {
            field: field.to_owned(),
            value,
            reason: "must be finite and at least 0.1 m (MIN_FEATURE_M)",
        })
    }
}

/// Checks that `value` is finite.
pub(crate) fn check_finite(field: &str, value: f64) -> Result<f64, MapError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(MapError::InvalidParameter {
            field: field.to_owned(),
            value,
            reason: "must be finite",
        })
    }
}

impl fathom_core::ParameterError for MapError {
    fn parameter(&self) -> Option<std::borrow::Cow<'_, str>> {
        match self {
            MapError::InvalidParameter { field, .. } => Some(field.as_str().into()),
            _ => None,
        }
    }
}

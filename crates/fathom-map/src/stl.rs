//! STL import (binary and ASCII) with `stl_io`: facets into a [`TriMesh`] in local
//! NED metres, every face of the settings' default material (STL has no materials).
//!
//! Which format: a file of exactly `84 + 50 n` bytes, `n` the count in its binary
//! header, is binary, even when its header starts with `solid` (many exporters write
//! that; `stl_io` would take it for ASCII, so those five header bytes are blanked for
//! it); otherwise a file starting with `solid` is ASCII (a bare `solid` first line is
//! given a name for `stl_io`), and anything else is binary with a wrong size, an
//! error naming the first incomplete face. Errors name the 0-based face. Facet
//! normals in the file are ignored (the ray caster computes its own); an ASCII file
//! ends at its first `endsolid`.

use std::borrow::Cow;
use std::io::{Cursor, Read};

use crate::import::read_bounded;
use crate::mesh::MAX_COORD;
use crate::{ImportReport, ImportSettings, MapError, MeshBuilder, TriMesh};

/// Reads an STL file from `reader` (at most `settings.max_bytes`).
///
/// # Errors
/// As [`parse_stl`], and [`MapError::Io`] / [`MapError::TooLarge`] from reading.
pub fn read_stl(
    reader: impl Read,
    settings: &ImportSettings,
) -> Result<(TriMesh, ImportReport), MapError> {
    settings.check()?;
    let bytes = read_bounded(reader, settings.max_bytes)?;
    parse_stl(&bytes, settings)
}

/// Which kind of STL the bytes are (module rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StlKind {
    /// Binary with a consistent size.
    Binary,
    /// ASCII (`solid ...`).
    Ascii,
}

/// Parses the bytes of an STL file.
///
/// # Errors
/// [`MapError::Stl`] (header, size), [`MapError::StlFace`] naming the face (truncated,
/// malformed, non-finite or too large vertex), [`MapError::Stl`] when no default
/// material is set, [`MapError::TooLarge`], [`MapError::InvalidParameter`].
pub fn parse_stl(
    bytes: &[u8],
    settings: &ImportSettings,
) -> Result<(TriMesh, ImportReport), MapError> {
    settings.check()?;
    if bytes.len() as u64 > settings.max_bytes {
        return Err(MapError::TooLarge {
            bytes: bytes.len() as u64,
            limit: settings.max_bytes,
        });
    }
    let material = settings.default_material.ok_or_else(|| MapError::Stl {
        reason: "STL has no materials: the import settings need a default material".into(),
    })?;
    let (kind, input) = prepare(bytes)?;
    let mut cursor = Cursor::new(input.as_ref());
    let faces = stl_io::create_stl_reader(&mut cursor).map_err(|e| MapError::Stl {
        reason: format!("{kind:?} header: {e}"),
    })?;
    let mut builder = MeshBuilder::new();
    let mut read = 0;
    for (face, t) in faces.enumerate() {
        let t = t.map_err(|e| MapError::StlFace {
            face,
            reason: e.to_string(),
        })?;
        let mut corners = [nalgebra::Vector3::zeros(); 3];
        for (k, v) in t.vertices.iter().enumerate() {
            let p = settings.to_ned(&[f64::from(v[0]), f64::from(v[1]), f64::from(v[2])]);
            if let Some(bad) = p.iter().find(|c| c.is_nan() || c.abs() > MAX_COORD) {
                return Err(MapError::StlFace {
                    face,
                    reason: format!(
                        "vertex {k}: coordinate {bad} (NED, m) is not finite or beyond +-{MAX_COORD} m"
                    ),
                });
            }
            corners[k] = p;
        }
        builder.triangle_at(corners[0], corners[1], corners[2], material);
        read += 1;
    }
    let (mesh, report) = builder.build()?;
    Ok((
        mesh,
        ImportReport {
            faces_read: read,
            mesh: report,
            ..ImportReport::default()
        },
    ))
}

/// The kind of the file and the bytes to give `stl_io` (module rule).
fn prepare(bytes: &[u8]) -> Result<(StlKind, Cow<'_, [u8]>), MapError> {
    let declared = (bytes.len() >= 84)
        .then(|| u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64);
    let needed = declared.map(|n| 84 + 50 * n);
    if needed == Some(bytes.len() as u64) {
        if bytes.starts_with(b"solid") {
            let mut owned = bytes.to_vec();
            owned[..5].copy_from_slice(b"     ");
            return Ok((StlKind::Binary, Cow::Owned(owned)));
        }
        return Ok((StlKind::Binary, Cow::Borrowed(bytes)));
    }
    if bytes.starts_with(b"solid") {
        let first_end = bytes
            .iter()
            .position(|&b| b == b'\n')
            .unwrap_or(bytes.len());
        let first = std::str::from_utf8(&bytes[..first_end]).unwrap_or("");
        if first.trim_end() == "solid" {
            let mut owned = b"solid unnamed".to_vec();
            owned.extend_from_slice(&bytes[first_end..]);
            return Ok((StlKind::Ascii, Cow::Owned(owned)));
        }
        return Ok((StlKind::Ascii, Cow::Borrowed(bytes)));
    }
    match (declared, needed) {
        (Some(n), Some(needed)) if (bytes.len() as u64) < needed => Err(MapError::StlFace {
            face: (bytes.len() - 84) / 50,
            reason: format!(
                "binary STL truncated: {n} faces declared need {needed} bytes, the file has {}",
                bytes.len()
            ),
        }),
        (Some(n), Some(needed)) => Err(MapError::Stl {
            reason: format!(
                "binary STL of {} bytes, but its {n} declared faces need {needed} bytes",
                bytes.len()
            ),
        }),
        _ => Err(MapError::Stl {
            reason: format!(
                "{} bytes: neither ASCII (`solid ...`) nor a binary STL (84-byte header)",
                bytes.len()
            ),
        }),
    }
}

/// The kind [`parse_stl`] would read the bytes as, or its error.
///
/// # Errors
/// As the size checks of [`parse_stl`].
pub fn stl_kind(bytes: &[u8]) -> Result<StlKind, MapError> {
    prepare(bytes).map(|(k, _)| k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fathom_core::Material;

    /// A binary STL of the given triangles (header text, corners).
    pub(crate) fn binary(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut out = vec![b' '; 80];
        out[..header.len()].copy_from_slice(header);
        out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
        for t in tris {
            out.extend_from_slice(&[0u8; 12]);
            for v in t {
                for c in v {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
            out.extend_from_slice(&[0u8; 2]);
        }
        out
    }

    const T: [[f32; 3]; 3] = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]];
    const U: [[f32; 3]; 3] = [[0., 0., 1.], [1., 0., 1.], [0., 1., 1.]];

    fn ned() -> ImportSettings {
        ImportSettings {
            axes: crate::AxisConvention::Ned,
            ..ImportSettings::default()
        }
    }

    #[test]
    fn binary_even_with_a_solid_header() {
        for header in [&b"fathom"[..], &b"solid exported by a CAD tool"[..]] {
            let bytes = binary(header, &[T, U]);
            assert_eq!(stl_kind(&bytes).unwrap(), StlKind::Binary);
            let (mesh, r) = parse_stl(&bytes, &ned()).unwrap();
            assert_eq!((mesh.len(), r.faces_read), (2, 2));
            assert!(mesh.materials().iter().all(|&m| m == Material::Opaque));
        }
    }

    #[test]
    fn ascii_with_and_without_a_name() {
        let body = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n";
        for first in ["solid x\n", "solid\n", "solid\r\n"] {
            let text = format!("{first}{body}");
            let (mesh, _) = parse_stl(text.as_bytes(), &ned()).unwrap();
            assert_eq!(mesh.len(), 1, "{first:?}");
        }
    }

    #[test]
    fn malformed_files_name_the_face() {
        let s = ned();
        let mut bytes = binary(b"", &[T, U, T]);
        bytes.truncate(84 + 50 + 20);
        bytes[80] = 3;
        let e = parse_stl(&bytes, &s).unwrap_err().to_string();
        assert!(
            e.starts_with("STL face 1: binary STL truncated: 3 faces"),
            "{e}"
        );
        let mut nan = binary(b"", &[T, U]);
        nan[84 + 50 + 12 + 4..84 + 50 + 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = parse_stl(&nan, &s).unwrap_err().to_string();
        assert!(e.starts_with("STL face 1: vertex 0: coordinate NaN"), "{e}");
        let e = parse_stl(b"abc", &s).unwrap_err().to_string();
        assert!(e.contains("neither ASCII"), "{e}");
        let ascii = "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 x\n";
        let e = parse_stl(ascii.as_bytes(), &s).unwrap_err().to_string();
        assert!(e.starts_with("STL face 1:"), "{e}");
        let none = ImportSettings {
            default_material: None,
            ..ned()
        };
        assert!(parse_stl(&binary(b"", &[T]), &none).is_err());
    }
}

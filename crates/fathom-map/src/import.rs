//! Import settings shared by the OBJ and STL readers: the file's axis convention,
//! unit, origin offset and material names, converted once into local NED metres;
//! and the bounded read of a reader into memory.
//!
//! A file point `p` (file axes, file units) becomes `R (s (p - p0))` in NED metres:
//! the origin offset `p0` is subtracted first, in `f64` (GIS exports carry offsets of
//! 10^5-10^7 m, so the subtraction must come before any rounding), then the unit
//! scale `s` (metres per file unit) and the axis permutation `R` of
//! [`AxisConvention`].

use std::collections::BTreeMap;
use std::io::Read;

use fathom_core::Material;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::{check_finite, check_positive};
use crate::{MapError, MeshReport};

/// How a file's axes relate to local NED (north, east, down).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisConvention {
    /// Already NED: `x` north, `y` east, `z` down.
    Ned,
    /// Z-up east-north-up map frame (GIS, city models): `x` east, `y` north, `z` up;
    /// NED = `(y, x, -z)`.
    #[default]
    EnuZUp,
    /// Y-up right-handed (Blender's and glTF's OBJ export): `x` east, `y` up, `z` south
    /// (towards the viewer); NED = `(-z, x, -y)`.
    YUpRightHanded,
    /// Y-up left-handed (Unity): `x` east, `y` up, `z` north; NED = `(z, x, -y)`.
    YUpLeftHanded,
}

impl AxisConvention {
    /// A vector in file axes as NED.
    pub fn to_ned(self, p: &Vector3<f64>) -> Vector3<f64> {
        match self {
            AxisConvention::Ned => *p,
            AxisConvention::EnuZUp => Vector3::new(p.y, p.x, -p.z),
            AxisConvention::YUpRightHanded => Vector3::new(-p.z, p.x, -p.y),
            AxisConvention::YUpLeftHanded => Vector3::new(p.z, p.x, -p.y),
        }
    }
}

/// Material names of a file (OBJ `usemtl`) mapped to materials. Names are compared
/// without regard to ASCII case. The default table maps `opaque` and `glass`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MaterialTable {
    names: BTreeMap<String, Material>,
}

impl Default for MaterialTable {
    fn default() -> Self {
        let mut t = Self::empty();
        t.insert("opaque", Material::Opaque);
        t.insert("glass", Material::Glass);
        t
    }
}

impl MaterialTable {
    /// A table that maps no name.
    pub fn empty() -> Self {
        Self {
            names: BTreeMap::new(),
        }
    }

    /// Maps `name` (any case) to `material`, replacing an earlier mapping.
    pub fn insert(&mut self, name: &str, material: Material) -> &mut Self {
        self.names.insert(name.to_ascii_lowercase(), material);
        self
    }

    /// The material of `name`, if mapped.
    pub fn get(&self, name: &str) -> Option<Material> {
        self.names.get(&name.to_ascii_lowercase()).copied()
    }
}

/// How to read a mesh file into local NED metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImportSettings {
    /// The file's axis convention. Default: Z-up ENU map frame.
    pub axes: AxisConvention,
    /// Metres per file unit (> 0). Default 1.
    pub scale: f64,
    /// Subtracted from every file point before anything else, in file axes and file
    /// units (e.g. the UTM coordinates of the scenario origin). Default 0.
    pub origin_offset: [f64; 3],
    /// OBJ `usemtl` names to materials; an unmapped name is an error.
    pub materials: MaterialTable,
    /// Material of OBJ faces before any `usemtl` and of every STL face (STL has no
    /// materials); `None` makes such OBJ faces an error. Default `Some(Opaque)`.
    pub default_material: Option<Material>,
    /// Largest input accepted, bytes (reading stops there). Default 1 GiB.
    pub max_bytes: u64,
}

impl Default for ImportSettings {
    fn default() -> Self {
        Self {
            axes: AxisConvention::default(),
            scale: 1.0,
            origin_offset: [0.0; 3],
            materials: MaterialTable::default(),
            default_material: Some(Material::Opaque),
            max_bytes: 1 << 30,
        }
    }
}

impl ImportSettings {
    /// Checks the numbers (scale finite and > 0, offset finite).
    ///
    /// # Errors
    /// [`MapError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<(), MapError> {
        check_positive("scale", self.scale)?;
        for (i, &o) in self.origin_offset.iter().enumerate() {
            check_finite(&format!("origin_offset[{i}]"), o)?;
        }
        Ok(())
    }

    /// A file point as local NED metres (module formula).
    pub fn to_ned(&self, p: &[f64; 3]) -> Vector3<f64> {
        let local = Vector3::new(
            p[0] - self.origin_offset[0],
            p[1] - self.origin_offset[1],
            p[2] - self.origin_offset[2],
        ) * self.scale;
        self.axes.to_ned(&local)
    }
}

/// What an import read and what it skipped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ImportReport {
    /// Faces in the file (OBJ: polygons and triangles, before triangulation; STL:
    /// facets).
    pub faces_read: usize,
    /// Polygons with more than three corners, split into triangles (OBJ).
    pub polygons_triangulated: usize,
    /// Points and lines ignored (OBJ `p` and `l`).
    pub ignored_elements: usize,
    /// The mesh cleaning (degenerate and duplicate faces skipped, welded vertices,
    /// non-manifold and boundary edges).
    pub mesh: MeshReport,
}

/// Reads all of `reader` into memory, stopping with [`MapError::TooLarge`] past
/// `max_bytes`.
pub(crate) fn read_bounded(mut reader: impl Read, max_bytes: u64) -> Result<Vec<u8>, MapError> {
    let mut buf = Vec::new();
    let n = reader
        .by_ref()
        .take(max_bytes.saturating_add(1))
        .read_to_end(&mut buf)
        .map_err(|e| MapError::Io(e.to_string()))?;
    if n as u64 > max_bytes {
        return Err(MapError::TooLarge {
            bytes: n as u64,
            limit: max_bytes,
        });
    }
    Ok(buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_conventions_map_north_east_up() {
        // in each convention: the file's north, east and up unit vectors
        let cases = [
            (
                AxisConvention::Ned,
                [1., 0., 0.],
                [0., 1., 0.],
                [0., 0., -1.],
            ),
            (
                AxisConvention::EnuZUp,
                [0., 1., 0.],
                [1., 0., 0.],
                [0., 0., 1.],
            ),
            (
                AxisConvention::YUpRightHanded,
                [0., 0., -1.],
                [1., 0., 0.],
                [0., 1., 0.],
            ),
            (
                AxisConvention::YUpLeftHanded,
                [0., 0., 1.],
                [1., 0., 0.],
                [0., 1., 0.],
            ),
        ];
        for (c, n, e, u) in cases {
            assert_eq!(
                c.to_ned(&Vector3::from(n)),
                Vector3::new(1., 0., 0.),
                "{c:?}"
            );
            assert_eq!(
                c.to_ned(&Vector3::from(e)),
                Vector3::new(0., 1., 0.),
                "{c:?}"
            );
            assert_eq!(
                c.to_ned(&Vector3::from(u)),
                Vector3::new(0., 0., -1.),
                "{c:?}"
            );
        }
    }

    #[test]
    fn offset_is_subtracted_before_scaling() {
        let s = ImportSettings {
            scale: 0.001, // millimetres
            origin_offset: [4_500_000_000.0, 600_000_000.0, 0.0],
            ..ImportSettings::default()
        };
        s.check().unwrap();
        let p = s.to_ned(&[4_500_000_123.0, 600_000_456.0, 7_000.0]);
        assert_eq!(p, Vector3::new(0.456, 0.123, -7.0));
        let bad = ImportSettings {
            scale: f64::NAN,
            ..ImportSettings::default()
        };
        assert!(bad.check().is_err());
        let bad = ImportSettings {
            origin_offset: [0.0, f64::INFINITY, 0.0],
            ..ImportSettings::default()
        };
        assert!(
            bad.check()
                .unwrap_err()
                .to_string()
                .contains("origin_offset[1]")
        );
    }

    #[test]
    fn material_names_ignore_case_and_reads_are_bounded() {
        let mut t = MaterialTable::default();
        t.insert("Window", Material::Glass);
        assert_eq!(t.get("WINDOW"), Some(Material::Glass));
        assert_eq!(t.get("Opaque"), Some(Material::Opaque));
        assert_eq!(t.get("steel"), None);
        assert_eq!(read_bounded(&b"abc"[..], 3).unwrap(), b"abc");
        assert!(matches!(
            read_bounded(&b"abcd"[..], 3),
            Err(MapError::TooLarge { limit: 3, .. })
        ));
    }
}

//! The static triangle mesh of the world: vertices in local NED metres, triangles as
//! vertex-index triples, one [`Material`] per triangle; built through
//! [`TriMesh::new`], which validates and cleans it and reports what it skipped.
//!
//! Cleaning rules (the same for files and primitives):
//!
//! - vertices with bitwise-equal coordinates are welded into one;
//! - a triangle is *degenerate* when, after welding, two of its corners coincide or
//!   its area is negligible: `|e1 x e2| <= 1e-12 * l_max^2` (`l_max` its longest
//!   edge, so the rule does not depend on the unit); it is skipped;
//! - a triangle is a *duplicate* when an earlier kept triangle has the same three
//!   (welded) corners in any order; it is skipped (the first one's material wins);
//! - edges shared by more than two kept triangles (non-manifold) and edges of only one
//!   (holes, open borders) are counted, not changed: ray casting does not need a
//!   closed or manifold surface.
//!
//! Kept triangles keep their input order; their index is the hit's `triangle`.

use std::collections::HashMap;

use fathom_core::Material;
use nalgebra::Vector3;

use crate::MapError;

/// Largest absolute coordinate accepted, m (keeps every product in the ray test far
/// from overflow; the Earth's radius is 6.4e6 m).
pub const MAX_COORD: f64 = 1e9;

/// What cleaning did to a mesh (see the module rules).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MeshReport {
    /// Triangles given (after the triangulation of polygons, for files).
    pub triangles_in: usize,
    /// Triangles kept.
    pub triangles_kept: usize,
    /// Degenerate triangles skipped.
    pub degenerate_skipped: usize,
    /// Duplicate triangles skipped.
    pub duplicate_skipped: usize,
    /// Vertices merged into an earlier bitwise-equal one.
    pub vertices_welded: usize,
    /// Edges of more than two kept triangles.
    pub non_manifold_edges: usize,
    /// Edges of exactly one kept triangle (holes and open borders).
    pub boundary_edges: usize,
}

/// A validated triangle mesh in local NED metres with a material per triangle.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    vertices: Vec<Vector3<f64>>,
    triangles: Vec<[u32; 3]>,
    materials: Vec<Material>,
}

impl TriMesh {
    /// Validates and cleans a mesh (module rules).
    ///
    /// # Errors
    /// [`MapError::BadVertex`] (non-finite or beyond [`MAX_COORD`]),
    /// [`MapError::IndexOutOfRange`], [`MapError::MaterialCount`],
    /// [`MapError::TooManyElements`].
    pub fn new(
        vertices: Vec<Vector3<f64>>,
        triangles: Vec<[u32; 3]>,
        materials: Vec<Material>,
    ) -> Result<(Self, MeshReport), MapError> {
        if materials.len() != triangles.len() {
            return Err(MapError::MaterialCount {
                triangles: triangles.len(),
                materials: materials.len(),
            });
        }
        if u32::try_from(vertices.len()).is_err() {
            return Err(MapError::TooManyElements {
                what: "vertices",
                count: vertices.len(),
            });
        }
        if u32::try_from(triangles.len()).is_err() {
            return Err(MapError::TooManyElements {
                what: "triangles",
                count: triangles.len(),
            });
        }
        for (index, v) in vertices.iter().enumerate() {
            for &value in v.iter() {
                let in_range = value.abs() <= MAX_COORD; // false for NaN
                if !in_range {
                    return Err(MapError::BadVertex {
                        index,
                        value,
                        max: MAX_COORD,
                    });
                }
            }
        }
        for (triangle, t) in triangles.iter().enumerate() {
            for &index in t {
                if index as usize >= vertices.len() {
                    return Err(MapError::IndexOutOfRange {
                        triangle,
                        index,
                        vertices: vertices.len(),
                    });
                }
            }
        }
        Ok(clean(vertices, &triangles, &materials))
    }

    /// An empty mesh (every ray misses).
    pub fn empty() -> Self {
        Self::default()
    }

    /// The vertices, NED, m.
    pub fn vertices(&self) -> &[Vector3<f64>] {
        &self.vertices
    }

    /// The triangles (indices into [`TriMesh::vertices`]).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The material of each triangle.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there is no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The three corners of triangle `i` (panics if `i >= len()`, like indexing).
    pub fn corners(&self, i: usize) -> [Vector3<f64>; 3] {
        let [a, b, c] = self.triangles[i];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Axis-aligned bounds `(min, max)` of the vertices used by triangles, or `None`
    /// for an empty mesh.
    pub fn bounds(&self) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let mut it = self.triangles.iter().flatten();
        let first = self.vertices[*it.next()? as usize];
        let (mut lo, mut hi) = (first, first);
        for &i in it {
            let v = self.vertices[i as usize];
            lo = lo.inf(&v);
            hi = hi.sup(&v);
        }
        Some((lo, hi))
    }
}

/// Whether a triangle with these corners is degenerate (module rule).
pub fn is_degenerate(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> bool {
    let (e1, e2, e3) = (b - a, c - a, c - b);
    let l2 = e1
        .norm_squared()
        .max(e2.norm_squared())
        .max(e3.norm_squared());
    let area2 = e1.cross(&e2).norm();
    let proper = area2 > 1e-12 * l2; // false for NaN
    !proper
}

fn clean(
    vertices: Vec<Vector3<f64>>,
    triangles: &[[u32; 3]],
    materials: &[Material],
) -> (TriMesh, MeshReport) {
    let mut report = MeshReport {
        triangles_in: triangles.len(),
        ..MeshReport::default()
    };
    // weld bitwise-equal vertices (-0.0 and 0.0 are made equal first)
    let key = |v: &Vector3<f64>| v.map(|c| (c + 0.0).to_bits());
    let mut canonical: HashMap<Vector3<u64>, u32> = HashMap::with_capacity(vertices.len());
    let mut remap = Vec::with_capacity(vertices.len());
    let mut welded = Vec::with_capacity(vertices.len());
    for v in &vertices {
        let next = welded.len() as u32;
        let id = *canonical.entry(key(v)).or_insert(next);
        if id == next {
            welded.push(*v);
        } else {
            report.vertices_welded += 1;
        }
        remap.push(id);
    }
    let mut seen: HashMap<[u32; 3], ()> = HashMap::with_capacity(triangles.len());
    let mut kept = Vec::with_capacity(triangles.len());
    let mut kept_materials = Vec::with_capacity(triangles.len());
    for (t, m) in triangles.iter().zip(materials) {
        let w = t.map(|i| remap[i as usize]);
        let [a, b, c] = w.map(|i| welded[i as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] || is_degenerate(&a, &b, &c) {
            report.degenerate_skipped += 1;
            continue;
        }
        let mut sorted = w;
        sorted.sort_unstable();
        if seen.insert(sorted, ()).is_some() {
            report.duplicate_skipped += 1;
            continue;
        }
        kept.push(w);
        kept_materials.push(*m);
    }
    let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(kept.len() * 2);
    for t in &kept {
        for (i, j) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((i.min(j), i.max(j))).or_insert(0) += 1;
        }
    }
    report.non_manifold_edges = edges.values().filter(|&&n| n > 2).count();
    report.boundary_edges = edges.values().filter(|&&n| n == 1).count();
    report.triangles_kept = kept.len();
    (
        TriMesh {
            vertices: welded,
            triangles: kept,
            materials: kept_materials,
        },
        report,
    )
}

/// Collects triangles (from primitives or a file reader) and builds a [`TriMesh`].
#[derive(Debug, Clone, Default)]
pub struct MeshBuilder {
    vertices: Vec<Vector3<f64>>,
    triangles: Vec<[u32; 3]>,
    materials: Vec<Material>,
}

impl MeshBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a vertex, returning its index.
    pub fn vertex(&mut self, v: Vector3<f64>) -> u32 {
        self.vertices.push(v);
        (self.vertices.len() - 1) as u32
    }

    /// Adds the triangle `a, b, c` (vertex indices) of `material`.
    pub fn triangle(&mut self, a: u32, b: u32, c: u32, material: Material) {
        self.triangles.push([a, b, c]);
        self.materials.push(material);
    }

    /// Adds the triangle with these corners.
    pub fn triangle_at(
        &mut self,
        a: Vector3<f64>,
        b: Vector3<f64>,
        c: Vector3<f64>,
        material: Material,
    ) {
        let (a, b, c) = (self.vertex(a), self.vertex(b), self.vertex(c));
        self.triangle(a, b, c, material);
    }

    /// Adds the planar quad `a, b, c, d` (in order around it) as two triangles.
    pub fn quad_at(&mut self, corners: [Vector3<f64>; 4], material: Material) {
        let [a, b, c, d] = corners.map(|v| self.vertex(v));
        self.triangle(a, b, c, material);
        self.triangle(a, c, d, material);
    }

    /// Appends every triangle of `mesh`.
    pub fn append(&mut self, mesh: &TriMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(mesh.vertices());
        for (t, m) in mesh.triangles().iter().zip(mesh.materials()) {
            self.triangle(t[0] + base, t[1] + base, t[2] + base, *m);
        }
    }

    /// Number of triangles added so far.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether no triangle was added.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Validates and cleans the collected triangles ([`TriMesh::new`]).
    ///
    /// # Errors
    /// As [`TriMesh::new`].
    pub fn build(self) -> Result<(TriMesh, MeshReport), MapError> {
        TriMesh::new(self.vertices, self.triangles, self.materials)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    #[test]
    fn cleaning_counts_what_it_skips() {
        let mut b = MeshBuilder::new();
        let m = Material::Opaque;
        // a closed tetrahedron
        let p = [v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.), v(0., 0., 1.)];
        for [i, j, k] in [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]] {
            b.triangle_at(p[i], p[j], p[k], m);
        }
        assert_eq!(b.clone().build().unwrap().1.boundary_edges, 0);
        // duplicate (other order, other material), degenerate (collinear, repeated corner)
        b.triangle_at(p[1], p[0], p[2], Material::Glass);
        b.triangle_at(v(0., 0., 0.), v(1., 1., 1.), v(2., 2., 2.), m);
        b.triangle_at(p[0], p[0], p[1], m);
        // a fin on edge 0-1: non-manifold
        b.triangle_at(p[0], p[1], v(0.5, -1.0, 0.0), m);
        let (mesh, r) = b.build().unwrap();
        assert_eq!(r.triangles_in, 8);
        assert_eq!(r.triangles_kept, 5);
        assert_eq!(r.degenerate_skipped, 2);
        assert_eq!(r.duplicate_skipped, 1);
        assert_eq!(r.non_manifold_edges, 1);
        assert_eq!(r.boundary_edges, 2);
        assert_eq!(mesh.vertices().len(), 7); // unused vertices are kept
        assert!(mesh.materials().iter().all(|&x| x == Material::Opaque));
        let (lo, hi) = mesh.bounds().unwrap();
        assert_eq!((lo, hi), (v(0., -1., 0.), v(1., 1., 1.)));
    }

    #[test]
    fn bad_input_is_an_error() {
        let t = vec![[0, 1, 2]];
        let m = vec![Material::Opaque];
        let good = vec![v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)];
        let mut nan = good.clone();
        nan[1].y = f64::NAN;
        assert!(matches!(
            TriMesh::new(nan, t.clone(), m.clone()),
            Err(MapError::BadVertex { index: 1, .. })
        ));
        let mut far = good.clone();
        far[2].z = 2e9;
        assert!(TriMesh::new(far, t.clone(), m.clone()).is_err());
        assert!(matches!(
            TriMesh::new(good.clone(), vec![[0, 1, 3]], m.clone()),
            Err(MapError::IndexOutOfRange { index: 3, .. })
        ));
        assert!(TriMesh::new(good.clone(), t.clone(), vec![]).is_err());
        assert!(TriMesh::new(good, t, m).is_ok());
        assert!(TriMesh::empty().bounds().is_none());
    }

    #[test]
    fn degeneracy_is_scale_free() {
        for s in [1e-6, 1.0, 1e6] {
            assert!(!is_degenerate(&v(0., 0., 0.), &v(s, 0., 0.), &v(0., s, 0.)));
            assert!(is_degenerate(
                &v(0., 0., 0.),
                &v(s, 0., 0.),
                &v(2.0 * s, 1e-13 * s, 0.)
            ));
        }
    }
}

//! The brute-force caster: every triangle tested for every ray. It is the test oracle
//! of the BVH caster (same triangle test and selection rule, no pruning) and is fine
//! for maps of a few hundred triangles.

use fathom_core::{RayCaster, RayHit};
use nalgebra::Vector3;

use crate::TriMesh;
use crate::triangle::{Best, PreparedMesh};

/// Casts rays by testing every triangle (O(n) per ray).
#[derive(Debug, Clone, Default)]
pub struct BruteForceCaster {
    mesh: PreparedMesh,
}

impl BruteForceCaster {
    /// Prepares `mesh` for casting.
    pub fn new(mesh: &TriMesh) -> Self {
        Self {
            mesh: PreparedMesh::new(mesh),
        }
    }
}

impl RayCaster for BruteForceCaster {
    fn cast(
        &self,
        origin_in_nav: &Vector3<f64>,
        dir_in_nav: &Vector3<f64>,
        max_range: f64,
    ) -> Option<RayHit> {
        let (o, d, max_range) = PreparedMesh::ray(origin_in_nav, dir_in_nav, max_range)?;
        let mut best = Best::new(max_range);
        for (i, tri) in self.mesh.triangles.iter().enumerate() {
            best.offer(tri, i as u32, &o, &d);
        }
        self.mesh.hit_record(&best, &d)
    }
}

//! The BVH caster: closest-hit ray casting on a bounding-volume hierarchy.
//!
//! The tree comes from `parry3d-f64` (its `Bvh`: one triangle per leaf, built by
//! binned SAH or PLOC) and is traversed with parry's `find_best` (depth first, nearer
//! child first, pruning boxes that start beyond the best hit). The box test and the
//! triangle test are fathom's own (`triangle.rs`): the box test is conservative and
//! the triangle test and selection rule are those of the brute-force oracle, so both
//! casters return the same triangle and range (tested with proptest).

use std::cell::Cell;

use fathom_core::{RayCaster, RayHit};
use nalgebra::{Point3, Vector3};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhNode};

use crate::TriMesh;
use crate::triangle::{Best, PreparedMesh, RayBoxTest};

/// How the hierarchy is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhBuild {
    /// Binned surface-area heuristic (Wald 2007): fast to build.
    #[default]
    Binned,
    /// Locally-ordered clustering (Meister and Bittner 2018): slower to build.
    Ploc,
}

/// Casts rays on a BVH over the triangles of a [`TriMesh`].
#[derive(Clone)]
pub struct BvhCaster {
    mesh: PreparedMesh,
    bvh: Bvh,
}

impl std::fmt::Debug for BvhCaster {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BvhCaster")
            .field("triangles", &self.mesh.triangles.len())
            .finish()
    }
}

impl BvhCaster {
    /// Builds the hierarchy over `mesh` with the default (binned SAH) build.
    pub fn new(mesh: &TriMesh) -> Self {
        Self::with_build(mesh, BvhBuild::default())
    }

    /// Builds the hierarchy over `mesh` with the given build.
    pub fn with_build(mesh: &TriMesh, build: BvhBuild) -> Self {
        let strategy = match build {
            BvhBuild::Binned => BvhBuildStrategy::Binned,
            BvhBuild::Ploc => BvhBuildStrategy::Ploc,
        };
        let leaves = (0..mesh.len()).map(|i| {
            let [a, b, c] = mesh.corners(i);
            let lo = a.inf(&b).inf(&c);
            let hi = a.sup(&b).sup(&c);
            (i, Aabb::new(Point3::from(lo), Point3::from(hi)))
        });
        Self {
            mesh: PreparedMesh::new(mesh),
            bvh: Bvh::from_iter(strategy, leaves),
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.mesh.triangles.len()
    }

    /// Whether the map has no triangle.
    pub fn is_empty(&self) -> bool {
        self.mesh.triangles.is_empty()
    }
}

#[inline(always)]
fn node_entry(test: &RayBoxTest, node: &BvhNode) -> f64 {
    let (lo, hi) = (node.mins(), node.maxs());
    test.entry(&[lo.x, lo.y, lo.z], &[hi.x, hi.y, hi.z])
}

impl RayCaster for BvhCaster {
    fn cast(
        &self,
        origin_in_nav: &Vector3<f64>,
        dir_in_nav: &Vector3<f64>,
        max_range: f64,
    ) -> Option<RayHit> {
        let (o, d, max_range) = PreparedMesh::ray(origin_in_nav, dir_in_nav, max_range)?;
        if self.mesh.triangles.is_empty() {
            return None;
        }
        let test = RayBoxTest::new(&o, &d);
        let best = Cell::new(Best::new(max_range));
        // parry prunes a box when its cost is not below its best cost; the cost is
        // the widened entry range, strictly below any hit inside, so a triangle tied
        // with the best hit is still tested and the lower index can win
        let _ = self.bvh.find_best(
            max_range,
            |node: &BvhNode, _| node_entry(&test, node),
            |leaf, _| {
                let mut b = best.get();
                b.offer(&self.mesh.triangles[leaf as usize], leaf, &o, &d);
                best.set(b);
                (b.triangle == leaf).then_some(b.t)
            },
        );
        self.mesh.hit_record(&best.get(), &d)
    }
}

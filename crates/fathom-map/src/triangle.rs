//! The one ray-triangle test both casters use (the BVH caster and the brute-force
//! oracle), the hit selection rule, and the conservative ray-box test of the BVH.
//!
//! Ray-triangle: Moeller-Trumbore in `f64`, edges and corners included
//! (`u >= 0, v >= 0, u + v <= 1`); a ray parallel to the triangle's plane
//! (`det == 0`) misses it; every comparison is written so that NaN means "miss".
//! A hit counts when `MIN_RANGE < t <= limit` and the hit point `o + t d` lies in the
//! triangle's bounding box widened by `1e-10 (1 + |c|)` (a ray nearly in the plane
//! gets a `t` of rounding noise; this keeps such hits on the triangle). Selection: the smallest `t` wins, ties
//! at exactly equal `t` go to the lower triangle index ([`Best::offer`]). Because both
//! casters run this same code on the same triangles, they agree exactly as long as
//! the BVH never prunes a box that holds a hit: its boxes are widened in space
//! ([`widen_box`]) well beyond the band where this test accepts hit points, and its
//! ray-box test is conservative (`bvh.rs`).

use fathom_core::raycast::{MIN_RANGE, Ray};
use fathom_core::{Material, RayHit};
use nalgebra::Vector3;

use crate::TriMesh;

/// Widening of a triangle's box for the hit-point check of [`PreparedTriangle::hit`]:
/// a tenth of [`BOX_SLACK`], the rest is margin for the rounding of `o + t d` (enough
/// for ray origins within about `4e6 (1 + |c|)` m of a box coordinate `c`).
const HIT_SLACK: f64 = 1e-10;

/// A triangle prepared for the ray test: first corner and the two edges from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PreparedTriangle {
    v0: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
}

/// `lo <= x <= hi`, false when any is NaN.
#[inline(always)]
fn within(x: f64, lo: f64, hi: f64) -> bool {
    x >= lo && x <= hi
}

/// `a < b ? a : b`.
#[inline(always)]
fn least(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// `a > b ? a : b`.
#[inline(always)]
fn greatest(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

#[inline(always)]
fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl PreparedTriangle {
    /// From the three corners.
    pub(crate) fn new(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Self {
        let v0 = [a.x, a.y, a.z];
        Self {
            v0,
            e1: sub(&[b.x, b.y, b.z], &v0),
            e2: sub(&[c.x, c.y, c.z], &v0),
        }
    }

    /// The range `t` of the hit of `o + t d` (`d` unit), if `MIN_RANGE < t <= limit`.
    #[inline(always)]
    pub(crate) fn hit(&self, o: &[f64; 3], d: &[f64; 3], limit: f64) -> Option<f64> {
        let p = cross(d, &self.e2);
        let det = dot(&self.e1, &p);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = sub(o, &self.v0);
        let u = dot(&s, &p) * inv;
        if !within(u, 0.0, 1.0) {
            return None;
        }
        let q = cross(&s, &self.e1);
        let v = dot(d, &q) * inv;
        let inside = v >= 0.0 && u + v <= 1.0; // false for NaN
        if !inside {
            return None;
        }
        let t = dot(&self.e2, &q) * inv;
        let in_range = t > MIN_RANGE && t <= limit; // false for NaN
        if !in_range {
            return None;
        }
        // a ray (nearly) in the triangle's plane gets a `t` made of rounding noise:
        // the hit point must lie in the triangle's box, widened by a tenth of the BVH
        // boxes' widening, so that the BVH never culls a hit this test accepts
        for k in 0..3 {
            let (a, b, c) = (self.v0[k], self.v0[k] + self.e1[k], self.v0[k] + self.e2[k]);
            // compare-and-select: the corners are finite (`TriMesh`), so this is
            // `f64::min` / `f64::max` without their NaN rule
            let (lo, hi) = (least(least(a, b), c), greatest(greatest(a, b), c));
            let p = o[k] + t * d[k];
            if !within(
                p,
                lo - HIT_SLACK * (1.0 + lo.abs()),
                hi + HIT_SLACK * (1.0 + hi.abs()),
            ) {
                return None;
            }
        }
        Some(t)
    }
}

impl PreparedTriangle {
    /// [`Best::offer`] of this triangle to `N` rays at once, lane by lane: ray `l` has
    /// origin `o[k][l]`, unit direction `d[k][l]` and best hit so far
    /// (`best_t[l]`, `best_triangle[l]`). The operations of [`Self::hit`] in the same
    /// order on every lane, without branches (a loop the compiler vectorizes across
    /// rays), so each lane's result is that of `offer`, bit for bit. A lane with
    /// `best_t < 0` never takes a hit (an unused lane).
    #[inline(always)]
    pub(crate) fn offer_lanes<const N: usize>(
        &self,
        index: u32,
        o: &[[f64; N]; 3],
        d: &[[f64; N]; 3],
        best_t: &mut [f64; N],
        best_triangle: &mut [u32; N],
    ) {
        // the triangle's box of the hit-point check, as in `hit`
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for k in 0..3 {
            let (a, b, c) = (self.v0[k], self.v0[k] + self.e1[k], self.v0[k] + self.e2[k]);
            let (l, h) = (least(least(a, b), c), greatest(greatest(a, b), c));
            lo[k] = l - HIT_SLACK * (1.0 + l.abs());
            hi[k] = h + HIT_SLACK * (1.0 + h.abs());
        }
        for l in 0..N {
            let dl = [d[0][l], d[1][l], d[2][l]];
            let ol = [o[0][l], o[1][l], o[2][l]];
            let p = cross(&dl, &self.e2);
            let det = dot(&self.e1, &p);
            let inv = 1.0 / det;
            let s = sub(&ol, &self.v0);
            let u = dot(&s, &p) * inv;
            let q = cross(&s, &self.e1);
            let v = dot(&dl, &q) * inv;
            let t = dot(&self.e2, &q) * inv;
            let limit = best_t[l];
            // `&`, not `&&`: no branch per condition
            let mut ok = (det != 0.0)
                & within(u, 0.0, 1.0)
                & (v >= 0.0)
                & (u + v <= 1.0)
                & (t > MIN_RANGE)
                & (t <= limit);
            for k in 0..3 {
                ok &= within(ol[k] + t * dl[k], lo[k], hi[k]);
            }
            let better = ok & ((t < limit) | (index < best_triangle[l]));
            best_t[l] = if better { t } else { limit };
            best_triangle[l] = if better { index } else { best_triangle[l] };
        }
    }
}

/// The closest hit found so far (module selection rule).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Best {
    /// Range of the best hit, or the ray's `max_range` while there is none.
    pub(crate) t: f64,
    /// Triangle of the best hit, `u32::MAX` while there is none.
    pub(crate) triangle: u32,
}

impl Best {
    /// No hit yet; hits up to `max_range` count.
    #[inline(always)]
    pub(crate) fn new(max_range: f64) -> Self {
        Self {
            t: max_range,
            triangle: u32::MAX,
        }
    }

    /// Tests triangle `index` and keeps it if it is the better hit.
    #[inline(always)]
    pub(crate) fn offer(&mut self, tri: &PreparedTriangle, index: u32, o: &[f64; 3], d: &[f64; 3]) {
        if let Some(t) = tri.hit(o, d, self.t)
            && (t < self.t || index < self.triangle)
        {
            self.t = t;
            self.triangle = index;
        }
    }

    /// The hit, if any.
    pub(crate) fn found(&self) -> Option<(f64, u32)> {
        (self.triangle != u32::MAX).then_some((self.t, self.triangle))
    }
}

/// A mesh prepared for casting: the triangles, their unit normals and materials.
#[derive(Debug, Clone, Default)]
pub(crate) struct PreparedMesh {
    pub(crate) triangles: Vec<PreparedTriangle>,
    normals: Vec<Vector3<f64>>,
    materials: Vec<Material>,
}

impl PreparedMesh {
    pub(crate) fn new(mesh: &TriMesh) -> Self {
        let mut triangles = Vec::with_capacity(mesh.len());
        let mut normals = Vec::with_capacity(mesh.len());
        for i in 0..mesh.len() {
            let [a, b, c] = mesh.corners(i);
            triangles.push(PreparedTriangle::new(&a, &b, &c));
            // not degenerate (TriMesh's rule), so the cross product is non-zero
            normals.push((b - a).cross(&(c - a)).normalize());
        }
        Self {
            triangles,
            normals,
            materials: mesh.materials().to_vec(),
        }
    }

    /// The checked ray as arrays (origin, unit direction, max range), or `None` for an
    /// invalid ray (fathom_core::raycast rules).
    #[inline(always)]
    pub(crate) fn ray(
        origin: &Vector3<f64>,
        dir: &Vector3<f64>,
        max_range: f64,
    ) -> Option<([f64; 3], [f64; 3], f64)> {
        let d = Ray::new(*origin, *dir, max_range).unit_dir()?;
        Some(([origin.x, origin.y, origin.z], [d.x, d.y, d.z], max_range))
    }

    /// The hit record of the selected triangle.
    #[inline(always)]
    pub(crate) fn hit_record(&self, best: &Best, d: &[f64; 3]) -> Option<RayHit> {
        let (range, triangle) = best.found()?;
        let n = self.normals[triangle as usize];
        let facing = if n.x * d[0] + n.y * d[1] + n.z * d[2] > 0.0 {
            -n
        } else {
            n
        };
        Some(RayHit {
            range,
            triangle,
            material: self.materials[triangle as usize],
            normal_in_nav: facing,
        })
    }
}

/// Relative widening of the BVH boxes in space ([`widen_box`]).
pub(crate) const BOX_SLACK: f64 = 1e-9;

/// Widens `[lo, hi]` in space by `1e-9 (1 + |c|)` per coordinate `c`: ten times the
/// band in which [`PreparedTriangle::hit`] accepts a hit point around its triangle's
/// box, so the hit of any accepted triangle lies strictly inside every box above it.
pub(crate) fn widen_box(lo: &Vector3<f64>, hi: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    (
        lo.map(|c| c - BOX_SLACK * (1.0 + c.abs())),
        hi.map(|c| c + BOX_SLACK * (1.0 + c.abs())),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> PreparedTriangle {
        PreparedTriangle::new(
            &Vector3::new(0.0, 0.0, 5.0),
            &Vector3::new(1.0, 0.0, 5.0),
            &Vector3::new(0.0, 1.0, 5.0),
        )
    }

    #[test]
    fn hits_inside_edges_and_corners_and_misses_outside() {
        let d = [0.0, 0.0, 1.0];
        assert_eq!(tri().hit(&[0.2, 0.2, 0.0], &d, 10.0), Some(5.0));
        assert_eq!(tri().hit(&[0.5, 0.5, 0.0], &d, 10.0), Some(5.0)); // hypotenuse
        assert_eq!(tri().hit(&[0.0, 0.0, 0.0], &d, 10.0), Some(5.0)); // corner
        assert_eq!(tri().hit(&[0.6, 0.6, 0.0], &d, 10.0), None);
        assert_eq!(tri().hit(&[0.2, 0.2, 0.0], &d, 4.0), None); // beyond limit
        assert_eq!(tri().hit(&[0.2, 0.2, 6.0], &d, 10.0), None); // behind
        assert_eq!(tri().hit(&[0.2, 0.2, 5.0], &d, 10.0), None); // starts on it
        assert_eq!(tri().hit(&[0.2, 0.2, 0.0], &[1.0, 0.0, 0.0], 10.0), None); // parallel
        assert_eq!(tri().hit(&[f64::NAN, 0.2, 0.0], &d, 10.0), None);
    }

    #[test]
    fn ties_go_to_the_lower_index() {
        let mut b = Best::new(10.0);
        let (o, d) = ([0.2, 0.2, 0.0], [0.0, 0.0, 1.0]);
        b.offer(&tri(), 7, &o, &d);
        b.offer(&tri(), 3, &o, &d);
        b.offer(&tri(), 5, &o, &d);
        assert_eq!(b.found(), Some((5.0, 3)));
        assert_eq!(Best::new(1.0).found(), None);
    }
}

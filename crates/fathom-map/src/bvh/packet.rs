//! The coherent path of the BVH caster: packets of up to [`PACKET`] similar rays
//! (near origins, near directions; e.g. one beam cast from neighbouring grid points)
//! traverse the tree together.
//!
//! A node's child boxes are tested once for the whole packet, against the packet's
//! interval bounds (the box of the rays' `f32` origins and the interval of their
//! reciprocal directions per axis), instead of once per ray; only a node that holds
//! triangles the packet may hit is tested ray by ray ([`BvhCaster::entries`]), and
//! each ray tests its own triangles with the oracle's test and selection rule.
//!
//! Same hits as the single-ray path, bit for bit: the packet test is conservative for
//! every ray of the packet (below), so no ray loses a box it enters; and the
//! selection rule ([`Best::offer`]: smallest range, ties to the lower triangle index)
//! does not depend on the order in which triangles are offered.
//!
//! Why the packet test is conservative. A ray's slab range of a lower plane `l` on
//! axis `k` is `fl(fl(l - lo_k) * i_k)` ([`RayF32`]). Rounding is monotone, so
//! `fl(l - x)` falls as `x` grows and `fl(d * i)` is monotone in `d` for a fixed `i`
//! and in `i` for a fixed `d`: over the box `lo_k in [lo_min, lo_max]`,
//! `i_k in [i_min, i_max]` its value lies between the least and the greatest of the
//! four corner values, computed with the same operations. The entry `max_k min(a, b)`
//! and the exit `min_k max(a, b)` are monotone in every slab range, so the corners'
//! lows bound every ray's entry from below and their highs every exit from above;
//! with the same widening by `F32_SLACK`, a box some ray of the packet enters with an
//! entry not beyond its own limit passes the packet test with the packet's largest
//! limit. A node is skipped only when its packet entry exceeds every ray's limit.

use fathom_core::{Ray, RayHit};

use super::{
    BvhCaster, F32_SLACK, RayF32, Stack, Visitor, WIDTH, WideNode, decode, gather, max, min,
    round_up, step,
};
use crate::triangle::{Best, PreparedMesh, PreparedTriangle};

/// Rays per packet.
pub const PACKET: usize = fathom_core::raycast::COHERENT_GROUP;

/// The interval bounds of a packet's rays (see the module docs).
#[derive(Debug, Clone, Copy)]
struct Bounds {
    /// Least and greatest origin for the lower planes, per axis.
    lo_min: [f32; 3],
    lo_max: [f32; 3],
    /// Least and greatest origin for the upper planes, per axis.
    hi_min: [f32; 3],
    hi_max: [f32; 3],
    /// Least and greatest reciprocal direction, per axis.
    inv_min: [f32; 3],
    inv_max: [f32; 3],
}

impl Bounds {
    /// The bounds of `rays` (at least one).
    fn new(rays: &[RayF32]) -> Self {
        let mut b = Bounds {
            lo_min: [f32::INFINITY; 3],
            lo_max: [f32::NEG_INFINITY; 3],
            hi_min: [f32::INFINITY; 3],
            hi_max: [f32::NEG_INFINITY; 3],
            inv_min: [f32::INFINITY; 3],
            inv_max: [f32::NEG_INFINITY; 3],
        };
        for r in rays {
            for k in 0..3 {
                b.lo_min[k] = b.lo_min[k].min(r.lo[k]);
                b.lo_max[k] = b.lo_max[k].max(r.lo[k]);
                b.hi_min[k] = b.hi_min[k].min(r.hi[k]);
                b.hi_max[k] = b.hi_max[k].max(r.hi[k]);
                b.inv_min[k] = b.inv_min[k].min(r.inv[k]);
                b.inv_max[k] = b.inv_max[k].max(r.inv[k]);
            }
        }
        b
    }
}

/// The least and the greatest of `fl(fl(plane - x) * i)` over
/// `x in [x_min, x_max]`, `i in [i_min, i_max]` (the four corners).
#[inline(always)]
fn corners(plane: f32, x_min: f32, x_max: f32, i_min: f32, i_max: f32) -> (f32, f32) {
    let d_low = plane - x_max;
    let d_high = plane - x_min;
    let p0 = d_low * i_min;
    let p1 = d_low * i_max;
    let p2 = d_high * i_min;
    let p3 = d_high * i_max;
    (min(min(p0, p1), min(p2, p3)), max(max(p0, p1), max(p2, p3)))
}

/// A packet's traversal state: its bounds and, by axis and slot, its rays and best
/// hits (unused slots have a negative best range, so they take no hit).
struct Packet {
    bounds: Bounds,
    o: [[f64; PACKET]; 3],
    d: [[f64; PACKET]; 3],
    best_t: [f64; PACKET],
    best_triangle: [u32; PACKET],
}

impl Visitor for Packet {
    #[inline(always)]
    fn test(&self, node: &WideNode, limit: f32) -> ([f32; WIDTH], u32) {
        BvhCaster::packet_entries(node, &self.bounds, limit)
    }

    /// Each triangle tested for every ray of the packet at once.
    #[inline(always)]
    fn offer(&mut self, tri: &PreparedTriangle, index: u32) {
        tri.offer_lanes(
            index,
            &self.o,
            &self.d,
            &mut self.best_t,
            &mut self.best_triangle,
        );
    }

    /// The largest ray's best range, as an f32 not below it.
    #[inline(always)]
    fn limit(&self) -> f32 {
        round_up(
            self.best_t
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max),
        )
    }
}

impl BvhCaster {
    /// Lower bounds of the entry ranges of `node`'s child boxes over the packet, and
    /// the mask of the boxes some ray of the packet may enter within `limit` (the
    /// packet's largest limit).
    #[inline(always)]
    fn packet_entries(node: &WideNode, b: &Bounds, limit: f32) -> ([f32; WIDTH], u32) {
        let [g0, g1, g2] = node.origin;
        let [t0, t1, t2] = node.exp.map(step);
        let mut near = [0.0f32; WIDTH];
        let mut hit = [0u8; WIDTH];
        for lane in 0..WIDTH {
            // the entry's low and the exit's high bound of the slab of axis `k`
            let slab = |k: usize, g: f32, t: f32| {
                let (a_low, a_high) = corners(
                    decode(g, t, node.lo[k][lane]),
                    b.lo_min[k],
                    b.lo_max[k],
                    b.inv_min[k],
                    b.inv_max[k],
                );
                let (b_low, b_high) = corners(
                    decode(g, t, node.hi[k][lane]),
                    b.hi_min[k],
                    b.hi_max[k],
                    b.inv_min[k],
                    b.inv_max[k],
                );
                (min(a_low, b_low), max(a_high, b_high))
            };
            let (nx, fx) = slab(0, g0, t0);
            let (ny, fy) = slab(1, g1, t1);
            let (nz, fz) = slab(2, g2, t2);
            let n = max(max(nx, ny), nz);
            let f = min(min(fx, fy), fz);
            let n = max(n, 0.0) * (1.0 - F32_SLACK);
            near[lane] = n;
            hit[lane] = u8::from(n <= min(f * (1.0 + F32_SLACK), limit));
        }
        (near, gather(hit) & u32::from(node.used))
    }

    /// Casts `rays` (at most [`PACKET`]) together, writing `hits[i]` for `rays[i]`.
    #[inline(always)]
    pub(super) fn cast_packet(&self, stack: &mut Stack, rays: &[Ray], hits: &mut [Option<RayHit>]) {
        debug_assert!(rays.len() <= PACKET && rays.len() == hits.len());
        // the valid rays in slots 0..count (`slot_of[s]`: the ray's index), by axis;
        // unused slots have a negative best range, so they take no hit
        let mut o = [[0.0f64; PACKET]; 3];
        let mut d = [[1.0f64; PACKET]; 3];
        let mut best_t = [-1.0f64; PACKET];
        let best_triangle = [u32::MAX; PACKET];
        let mut prepared = [RayF32 {
            lo: [0.0; 3],
            hi: [0.0; 3],
            inv: [0.0; 3],
        }; PACKET];
        let mut slot_of = [0usize; PACKET];
        let mut count = 0;
        for (i, (ray, hit)) in rays.iter().zip(hits.iter_mut()).enumerate() {
            *hit = None;
            let Some((oi, di, max_range)) =
                PreparedMesh::ray(&ray.origin_in_nav, &ray.dir_in_nav, ray.max_range)
            else {
                continue;
            };
            for k in 0..3 {
                o[k][count] = oi[k];
                d[k][count] = di[k];
            }
            best_t[count] = max_range;
            prepared[count] = RayF32::new(&oi, &di, &self.center);
            slot_of[count] = i;
            count += 1;
        }
        if count == 0 || self.nodes.is_empty() {
            return;
        }
        let mut packet = Packet {
            bounds: Bounds::new(&prepared[..count]),
            o,
            d,
            best_t,
            best_triangle,
        };
        self.walk(stack, &mut packet);
        let Packet {
            d,
            best_t,
            best_triangle,
            ..
        } = packet;
        for s in 0..count {
            let best = Best {
                t: best_t[s],
                triangle: best_triangle[s],
            };
            let ds = [d[0][s], d[1][s], d[2][s]];
            hits[slot_of[s]] = self.mesh.hit_record(&best, &ds);
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Rotation3, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::bvh::tests::{FORCE_BASELINE, random_mesh};
    use crate::presets::{BridgeParams, BuildingsParams};
    use crate::{BruteForceCaster, TriMesh};
    use fathom_core::RayCaster;

    /// Eight random child boxes (some flat) of side up to `scale` around `offset`.
    fn random_node(rng: &mut ChaCha8Rng, scale: f64, offset: f64) -> WideNode {
        let boxes: Vec<([f64; 3], [f64; 3])> = (0..WIDTH)
            .map(|_| {
                let lo: [f64; 3] = std::array::from_fn(|_| offset + scale * rng.random::<f64>());
                let hi = lo.map(|l| {
                    if rng.random::<f64>() < 0.2 {
                        l
                    } else {
                        l + scale * rng.random::<f64>()
                    }
                });
                (lo, hi)
            })
            .collect();
        let mut node = WideNode::EMPTY;
        node.used = u8::MAX;
        node.quantize(|axis| boxes.iter().map(|b| (b.0[axis], b.1[axis])).collect());
        node
    }

    /// Eight rays aimed into the node's region: near-parallel from nearby origins
    /// (a beam from grid points), or any (origins and directions at random; axis
    /// parallel directions included).
    fn random_packet(rng: &mut ChaCha8Rng, scale: f64, offset: f64) -> [RayF32; PACKET] {
        let coherent = rng.random::<bool>();
        let base_o = Vector3::from_fn(|_, _| offset + scale * (3.0 * rng.random::<f64>() - 1.0));
        let target = Vector3::from_fn(|_, _| offset + scale * rng.random::<f64>());
        let base_d = (target - base_o).normalize();
        std::array::from_fn(|_| {
            let (o, mut d) = if coherent {
                let o = base_o + Vector3::from_fn(|_, _| 0.05 * scale * rng.random::<f64>());
                let tilt = Vector3::from_fn(|_, _| 0.02 * (rng.random::<f64>() - 0.5));
                (o, Rotation3::from_scaled_axis(tilt) * base_d)
            } else {
                let o = Vector3::from_fn(|_, _| offset + scale * (3.0 * rng.random::<f64>() - 1.0));
                (o, (target - o).normalize())
            };
            if rng.random::<f64>() < 0.1 {
                d[rng.random_range(0..3)] = 0.0;
            }
            let d = d.try_normalize(0.0).unwrap_or(Vector3::x());
            RayF32::new(&[o.x, o.y, o.z], &[d.x, d.y, d.z], &Vector3::zeros())
        })
    }

    /// How often the packet test of bounds built from `bounds_of` fails to hold a
    /// ray's own test (a box the ray enters that the packet test culls, or a packet
    /// entry beyond the ray's), over random nodes and packets.
    fn packet_test_misses(bounds_of: impl Fn(&[RayF32; PACKET]) -> Bounds) -> (usize, usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let (mut misses, mut checked) = (0, 0);
        for round in 0..2000 {
            let scale = [1e-3, 1.0, 50.0, 3e3][round % 4];
            let offset = [0.0, 0.0, 1e4, -2e5][(round / 4) % 4];
            let node = random_node(&mut rng, scale, offset);
            let rays = random_packet(&mut rng, scale, offset);
            let limits: [f32; PACKET] = std::array::from_fn(|_| {
                if rng.random::<f64>() < 0.3 {
                    f32::INFINITY
                } else {
                    (5.0 * scale * rng.random::<f64>()) as f32
                }
            });
            let limit = limits.iter().copied().fold(f32::NEG_INFINITY, max);
            let (near, mask) = BvhCaster::packet_entries(&node, &bounds_of(&rays), limit);
            for (ray, own_limit) in rays.iter().zip(limits) {
                let (own_near, own) = BvhCaster::entries(&node, ray, own_limit);
                for lane in 0..WIDTH {
                    if own & (1 << lane) != 0 {
                        checked += 1;
                        if mask & (1 << lane) == 0 || near[lane] > own_near[lane] {
                            misses += 1;
                        }
                    }
                }
            }
        }
        (misses, checked)
    }

    #[test]
    fn the_packet_test_holds_every_ray_test() {
        let (misses, checked) = packet_test_misses(|rays| Bounds::new(rays));
        assert_eq!(misses, 0);
        assert!(checked > 20_000, "{checked}");
        // negative control: bounds of half the packet do lose boxes of the other half
        let (misses, _) = packet_test_misses(|rays| Bounds::new(&rays[..PACKET / 2]));
        assert!(misses > 100, "{misses}");
    }

    /// Groups of eight rays: one beam from a 4 x 2 patch of a 0.5 m grid with small
    /// attitude differences (as the point-mass filter casts them), random rays, and
    /// invalid rays among valid ones; `count` rays in all (not a multiple of 8).
    fn mixed_rays(mesh: &TriMesh, count: usize, seed: u64) -> Vec<Ray> {
        let (lo, hi) = mesh.bounds().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut rays = Vec::with_capacity(count);
        while rays.len() < count {
            let o = lo + (hi - lo).component_mul(&Vector3::from_fn(|_, _| rng.random::<f64>()));
            let d = Vector3::from_fn(|_, _| rng.random::<f64>() - 0.5);
            match rng.random_range(0..4) {
                0 | 1 => {
                    for k in 0..PACKET {
                        let step = Vector3::new((k % 4) as f64 * 0.5, (k / 4) as f64 * 0.5, 0.0);
                        let tilt = Vector3::from_fn(|_, _| 0.01 * (rng.random::<f64>() - 0.5));
                        rays.push(Ray::new(
                            o + step,
                            Rotation3::from_scaled_axis(tilt) * d,
                            60.0,
                        ));
                    }
                }
                2 => rays.push(Ray::new(o, d, f64::INFINITY)),
                _ => {
                    let bad = [
                        Ray::new(o, Vector3::zeros(), 10.0),
                        Ray::new(Vector3::repeat(f64::NAN), d, 10.0),
                        Ray::new(o, d, 0.0),
                        Ray::new(o, d, f64::NAN),
                    ];
                    rays.push(bad[rng.random_range(0..bad.len())]);
                }
            }
        }
        rays.truncate(count);
        rays
    }

    fn coherent_equals_batch(caster: &BvhCaster, rays: &[Ray]) -> Vec<Option<RayHit>> {
        let mut batch = vec![None; rays.len()];
        caster.cast_batch(rays, &mut batch).unwrap();
        let mut coherent = vec![None; rays.len()];
        caster.cast_coherent(rays, &mut coherent).unwrap();
        for (i, (c, b)) in coherent.iter().zip(&batch).enumerate() {
            assert_eq!(
                c.map(|h| (h.triangle, h.range.to_bits(), h.normal_in_nav, h.material)),
                b.map(|h| (h.triangle, h.range.to_bits(), h.normal_in_nav, h.material)),
                "ray {i}: {:?}",
                rays[i]
            );
        }
        coherent
    }

    #[test]
    fn coherent_casts_equal_single_casts_and_the_oracle() {
        let city = BuildingsParams::default().check().unwrap().mesh().unwrap();
        let bridge = BridgeParams::default().check().unwrap().mesh().unwrap();
        let meshes = [
            city,
            bridge,
            random_mesh(11, 2000, 10.0, 1.0, 0.0),
            random_mesh(12, 2000, 10.0, 0.5, 1e6),
        ];
        for (m, mesh) in meshes.iter().enumerate() {
            let caster = BvhCaster::new(mesh);
            let rays = mixed_rays(mesh, 3001, m as u64);
            let hits = coherent_equals_batch(&caster, &rays);
            let n_hits = hits.iter().filter(|h| h.is_some()).count();
            assert!(n_hits > 200, "mesh {m}: {n_hits} hits");
            if mesh.len() <= 5000 {
                let oracle = BruteForceCaster::new(mesh);
                for (r, h) in rays.iter().zip(&hits).step_by(3) {
                    let e = oracle.cast_ray(r);
                    assert_eq!(
                        h.map(|h| (h.triangle, h.range.to_bits())),
                        e.map(|e| (e.triangle, e.range.to_bits()))
                    );
                }
            }
        }
        // the AVX2 and the baseline build of the packet path agree
        let bridge = &meshes[1];
        let caster = BvhCaster::new(bridge);
        let rays = mixed_rays(bridge, 2000, 99);
        let fast = coherent_equals_batch(&caster, &rays);
        FORCE_BASELINE.with(|c| c.set(true));
        let base = coherent_equals_batch(&caster, &rays);
        FORCE_BASELINE.with(|c| c.set(false));
        assert_eq!(fast, base);
        let mut short = vec![None; 3];
        assert!(caster.cast_coherent(&rays, &mut short).is_err());
    }
}

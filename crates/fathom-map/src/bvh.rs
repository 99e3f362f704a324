//! The BVH caster: closest-hit ray casting on a bounding-volume hierarchy.
//!
//! The hierarchy is built by `parry3d-f64` (its `Bvh`, one triangle per leaf, binned
//! SAH or PLOC). For casting, that binary tree is read once (through parry's public
//! `traverse`, whose visiting order the reader mirrors to recover the topology) and
//! collapsed into a flat 8-wide tree: each node is one cache line holding the boxes
//! of up to eight children (widened as `triangle::widen_box` says), each plane
//! quantized to 8 bits on the node's own grid and rounded outwards; a node's inner
//! children are consecutive nodes and its triangles consecutive slots in leaf order
//! (with their mesh index), found from a small side record (`Links`). The choice was
//! measured on a 120k-triangle city against parry's own closure-based `find_best`
//! traversal on its 2-wide `f64` nodes and against the `bvh` crate
//! (docs/performance.md, "Ray casting").
//!
//! Traversal: depth first, children pushed far to near, a node skipped when its
//! conservative entry range exceeds the best hit; the triangle test and the
//! selection rule are the brute-force oracle's (`triangle.rs`), so both casters
//! return the same triangle and range (tested with proptest).

use fathom_core::raycast::BatchLengthMismatch;
use fathom_core::{Ray, RayCaster, RayHit};
use nalgebra::{Point3, Vector3};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhNode, TraversalAction};

use crate::TriMesh;
use crate::triangle::{Best, PreparedMesh, PreparedTriangle, widen_box};

mod packet;

pub use packet::PACKET;

/// How the hierarchy is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BvhBuild {
    /// Binned surface-area heuristic (Wald 2007), parry's default.
    #[default]
    Binned,
    /// Locally-ordered clustering (Meister and Bittner 2018).
    Ploc,
}

/// Children per node (8 measured faster than 4: docs/performance.md, "Ray
/// casting").
const WIDTH: usize = 8;

/// A node of the wide tree in one cache line: the boxes of up to eight children,
/// each plane quantized to 8 bits on a grid of the node's own (an origin and a
/// power-of-two step per axis) and rounded outwards (as in Ylitie et al. 2017).
/// Where the children are is in the node's [`Links`].
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct WideNode {
    /// Grid origin per axis, relative to the tree's center.
    origin: [f32; 3],
    /// Grid step per axis as its `f32` exponent field (`2^(exp - 127)`, [`step`]).
    exp: [u8; 3],
    /// Lane `i` (bit `i`) holds a child.
    used: u8,
    /// Lower planes of the child boxes as `[axis][lane]`, in grid steps ([`decode`]).
    lo: [[u8; WIDTH]; 3],
    /// Upper planes of the child boxes as `[axis][lane]`, in grid steps.
    hi: [[u8; WIDTH]; 3],
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 64);

impl WideNode {
    const EMPTY: WideNode = WideNode {
        origin: [0.0; 3],
        exp: [0; 3],
        used: 0,
        lo: [[0; WIDTH]; 3],
        hi: [[0; WIDTH]; 3],
    };
}

/// Where the children of a node are: its inner children are the consecutive nodes
/// from `first_node` in lane order, its triangles the consecutive slots (leaf order)
/// from `first_triangle`; lane `i` is the `k`-th of its kind, `k` the number of
/// lanes of that kind below `i`.
#[derive(Debug, Clone, Copy, Default)]
struct Links {
    first_node: u32,
    first_triangle: u32,
    /// Lane `i` (bit `i`) is a triangle; the other used lanes are inner nodes.
    leaf: u8,
}

/// The grid step `2^(exp - 127)` (`exp` in `1..=254`: a normal `f32`).
#[inline(always)]
fn step(exp: u8) -> f32 {
    f32::from_bits(u32::from(exp) << 23)
}

/// The plane `q` steps from `origin`: `q * step` is exact (8 by 24 bits, a power of
/// two), the sum is rounded once; the build checks these very values against the
/// exact boxes, and the traversal computes them with the same operations.
#[inline(always)]
fn decode(origin: f32, step: f32, q: u8) -> f32 {
    origin + f32::from(q) * step
}

impl WideNode {
    /// Sets the planes of every axis from its children's intervals
    /// (`intervals(axis)`, one per lane, relative to the tree's centre) by
    /// [`quantize_axis`].
    fn quantize(&mut self, intervals: impl Fn(usize) -> Vec<(f64, f64)>) {
        for axis in 0..3 {
            let (origin, exp, planes) = quantize_axis(&intervals(axis));
            self.origin[axis] = origin;
            self.exp[axis] = exp;
            for (lane, (ql, qh)) in planes.into_iter().enumerate() {
                self.lo[axis][lane] = ql;
                self.hi[axis][lane] = qh;
            }
        }
    }
}

/// The grid of one axis for the child intervals `kids` (`lo <= hi`, relative to the
/// center): the origin, the step's exponent, and each interval's planes in steps with
/// `decode(lo) <= lo` and `decode(hi) >= hi`.
fn quantize_axis(kids: &[(f64, f64)]) -> (f32, u8, Vec<(u8, u8)>) {
    let lo_n = kids.iter().map(|k| k.0).fold(f64::INFINITY, f64::min);
    let hi_n = kids.iter().map(|k| k.1).fold(f64::NEG_INFINITY, f64::max);
    let origin = round_down(lo_n);
    let extent = hi_n - f64::from(origin);
    // the smallest step with 255 steps covering the extent, or one more when the
    // rounding of the sum asks for it
    let mut exp = ((extent / 255.0).log2().ceil() as i32).clamp(-126, 127);
    loop {
        let s = step((exp + 127) as u8);
        let mut planes = Vec::with_capacity(kids.len());
        let mut fits = true;
        for &(lo, hi) in kids {
            let mut ql = ((lo - f64::from(origin)) / f64::from(s))
                .floor()
                .clamp(0.0, 255.0) as u8;
            while ql > 0 && f64::from(decode(origin, s, ql)) > lo {
                ql -= 1;
            }
            let mut qh = ((hi - f64::from(origin)) / f64::from(s))
                .ceil()
                .clamp(0.0, 255.0) as u8;
            while qh < 255 && f64::from(decode(origin, s, qh)) < hi {
                qh += 1;
            }
            // `decode(0) = origin <= lo` always; the top of the grid at the largest
            // step is infinite
            fits &= f64::from(decode(origin, s, qh)) >= hi;
            planes.push((ql, qh));
        }
        if fits || exp == 127 {
            return (origin, (exp + 127) as u8, planes);
        }
        exp += 1;
    }
}

/// Casts rays on an 8-wide BVH over the triangles of a [`TriMesh`].
#[derive(Debug, Clone)]
pub struct BvhCaster {
    nodes: Vec<WideNode>,
    /// Where each node's children are (by node index).
    links: Vec<Links>,
    /// The boxes are stored relative to this point (the mesh's bounds' center).
    center: Vector3<f64>,
    /// Triangles in leaf order, with their mesh index (one fetch per leaf).
    leaf_triangles: Vec<(PreparedTriangle, u32)>,
    /// Normals and materials by mesh index.
    mesh: PreparedMesh,
}

/// A node of the binary tree read from parry.
#[derive(Debug, Clone, Copy)]
struct BinNode {
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    /// Triangle index for a leaf.
    leaf: Option<u32>,
    children: [usize; 2],
}

impl BinNode {
    fn area(&self) -> f64 {
        let e = self.hi - self.lo;
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

impl BvhCaster {
    /// Builds the hierarchy over `mesh` with the default (binned SAH) build.
    pub fn new(mesh: &TriMesh) -> Self {
        Self::with_build(mesh, BvhBuild::default())
    }

    /// Builds the hierarchy over `mesh` with the given build.
    pub fn with_build(mesh: &TriMesh, build: BvhBuild) -> Self {
        let prepared = PreparedMesh::new(mesh);
        let (bin, _mirrored) = binary_tree(mesh, build);
        let center = mesh
            .bounds()
            .map_or(Vector3::zeros(), |(lo, hi)| (lo + hi) / 2.0);
        let mut caster = Self {
            nodes: Vec::new(),
            links: Vec::new(),
            center,
            leaf_triangles: Vec::with_capacity(mesh.len()),
            mesh: prepared,
        };
        if !bin.is_empty() {
            caster.collapse(&bin, mesh);
        }
        caster
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.leaf_triangles.len()
    }

    /// Whether the map has no triangle.
    pub fn is_empty(&self) -> bool {
        self.leaf_triangles.is_empty()
    }

    /// Collapses the binary tree (root at index 0) into wide nodes, depth first.
    fn collapse(&mut self, bin: &[BinNode], mesh: &TriMesh) {
        self.nodes.push(WideNode::EMPTY);
        self.links.push(Links::default());
        let mut work = vec![(0usize, 0usize)];
        while let Some((b, n)) = work.pop() {
            // the children of `b`, opening the largest inner child until there are
            // `WIDTH`
            let mut kids: Vec<usize> = match bin[b].leaf {
                Some(_) => vec![b],
                None => bin[b].children.to_vec(),
            };
            while kids.len() < WIDTH {
                let open = kids
                    .iter()
                    .enumerate()
                    .filter(|(_, k)| bin[**k].leaf.is_none())
                    .max_by(|x, y| bin[*x.1].area().total_cmp(&bin[*y.1].area()));
                let Some((slot, &k)) = open else { break };
                kids.splice(slot..=slot, bin[k].children);
            }
            let boxes: Vec<_> = kids
                .iter()
                .map(|&k| {
                    let (lo, hi) = widen_box(&bin[k].lo, &bin[k].hi);
                    // relative to the center; the f64 rounding of the difference
                    // (1e-16 relative) is far inside the widening (1e-9)
                    (lo - self.center, hi - self.center)
                })
                .collect();
            let mut node = WideNode::EMPTY;
            node.quantize(|axis| boxes.iter().map(|b| (b.0[axis], b.1[axis])).collect());
            let mut links = Links {
                first_node: self.nodes.len() as u32,
                first_triangle: self.leaf_triangles.len() as u32,
                leaf: 0,
            };
            let mut inner = Vec::new();
            for (lane, &k) in kids.iter().enumerate() {
                node.used |= 1 << lane;
                match bin[k].leaf {
                    Some(t) => {
                        let [a, b, c] = mesh.corners(t as usize);
                        self.leaf_triangles
                            .push((PreparedTriangle::new(&a, &b, &c), t));
                        links.leaf |= 1 << lane;
                    }
                    None => {
                        self.nodes.push(WideNode::EMPTY);
                        self.links.push(Links::default());
                        inner.push((k, self.nodes.len() - 1));
                    }
                }
            }
            self.links[n] = links;
            self.nodes[n] = node;
            // first inner child on top of the stack: depth-first layout
            work.extend(inner.into_iter().rev());
        }
    }
}

fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x { f.next_down() } else { f }
}

fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x { f.next_up() } else { f }
}

/// parry's binary tree over the triangles' boxes, read back as [`BinNode`]s (root
/// first), and whether it was read back (`false`: the fallback tree); a single
/// triangle is a lone leaf, no triangle an empty vector.
fn binary_tree(mesh: &TriMesh, build: BvhBuild) -> (Vec<BinNode>, bool) {
    let boxes: Vec<(Vector3<f64>, Vector3<f64>)> = (0..mesh.len())
        .map(|i| {
            let [a, b, c] = mesh.corners(i);
            (a.inf(&b).inf(&c), a.sup(&b).sup(&c))
        })
        .collect();
    match boxes.len() {
        0 => return (Vec::new(), true),
        1 => {
            let lone = BinNode {
                lo: boxes[0].0,
                hi: boxes[0].1,
                leaf: Some(0),
                children: [0; 2],
            };
            return (vec![lone], true);
        }
        _ => {}
    }
    let strategy = match build {
        BvhBuild::Binned => BvhBuildStrategy::Binned,
        BvhBuild::Ploc => BvhBuildStrategy::Ploc,
    };
    let bvh = Bvh::from_iter(
        strategy,
        boxes
            .iter()
            .enumerate()
            .map(|(i, (lo, hi))| (i, Aabb::new(Point3::from(*lo), Point3::from(*hi)))),
    );
    // The root holds the two top children; parry's `traverse` then visits the
    // children of each node as a pair (left, right) and continues with the left's
    // pair if it is inner, else the right's, else the most recently deferred right.
    let root = bvh.root_aabb();
    let mut nodes = vec![BinNode {
        lo: root.mins.coords,
        hi: root.maxs.coords,
        leaf: None,
        children: [usize::MAX; 2],
    }];
    let mut parent = 0usize;
    let mut deferred: Vec<usize> = Vec::new();
    let mut left: Option<usize> = None;
    let mut done = false;
    bvh.traverse(|node: &BvhNode| {
        if done {
            return TraversalAction::EarlyExit;
        }
        let id = nodes.len();
        nodes.push(BinNode {
            lo: node.mins().coords,
            hi: node.maxs().coords,
            leaf: node.leaf_data(),
            children: [usize::MAX; 2],
        });
        match left.take() {
            None => {
                nodes[parent].children[0] = id;
                left = Some(id);
            }
            Some(l) => {
                nodes[parent].children[1] = id;
                let (go_l, go_r) = (nodes[l].leaf.is_none(), nodes[id].leaf.is_none());
                parent = match (go_l, go_r) {
                    (true, true) => {
                        deferred.push(id);
                        l
                    }
                    (true, false) => l,
                    (false, true) => id,
                    (false, false) => match deferred.pop() {
                        Some(d) => d,
                        None => {
                            done = true;
                            0
                        }
                    },
                };
            }
        }
        TraversalAction::Continue
    });
    if tree_is_complete(&nodes, mesh.len()) {
        (nodes, true)
    } else {
        // parry visited in another order than mirrored: fall back to a balanced tree
        // in index order (correct, slower; the unit test fails on it)
        (flat_tree(&boxes), false)
    }
}

/// Every inner node has two children inside its box, and every triangle is exactly
/// one leaf.
fn tree_is_complete(nodes: &[BinNode], triangles: usize) -> bool {
    let mut seen = vec![false; triangles];
    for n in nodes {
        match n.leaf {
            Some(t) => {
                let Some(s) = seen.get_mut(t as usize) else {
                    return false;
                };
                if *s {
                    return false;
                }
                *s = true;
            }
            None => {
                for &c in &n.children {
                    let Some(child) = nodes.get(c) else {
                        return false;
                    };
                    let inside = (0..3).all(|k| child.lo[k] >= n.lo[k] && child.hi[k] <= n.hi[k]);
                    if !inside {
                        return false;
                    }
                }
            }
        }
    }
    seen.iter().all(|&s| s)
}

/// A balanced tree over the triangles in index order (the fallback of `binary_tree`).
fn flat_tree(boxes: &[(Vector3<f64>, Vector3<f64>)]) -> Vec<BinNode> {
    fn build(
        nodes: &mut Vec<BinNode>,
        boxes: &[(Vector3<f64>, Vector3<f64>)],
        first: usize,
        len: usize,
    ) -> usize {
        let id = nodes.len();
        let (mut lo, mut hi) = boxes[first];
        for b in &boxes[first..first + len] {
            lo = lo.inf(&b.0);
            hi = hi.sup(&b.1);
        }
        nodes.push(BinNode {
            lo,
            hi,
            leaf: (len == 1).then_some(first as u32),
            children: [0; 2],
        });
        if len > 1 {
            let l = build(nodes, boxes, first, len / 2);
            let r = build(nodes, boxes, first + len / 2, len - len / 2);
            nodes[id].children = [l, r];
        }
        id
    }
    let mut nodes = Vec::with_capacity(2 * boxes.len());
    build(&mut nodes, boxes, 0, boxes.len());
    nodes
}

/// Entries of the traversal stack held in place.
const INLINE: usize = 32;

/// The traversal stack: [`INLINE`] entries in place (few enough that zeroing them
/// for each ray is a handful of vector stores, not a `memset` call), spilling to the
/// heap beyond (deep trees only). An entry packs a node index and its entry range as
/// `f32` bits.
struct Stack {
    items: [u64; INLINE],
    len: usize,
    spill: Vec<u64>,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Self {
            items: [0; INLINE],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline(always)]
    fn clear(&mut self) {
        self.len = 0;
        self.spill.clear();
    }

    #[inline(always)]
    fn push(&mut self, node: u32, entry: f32) {
        let item = (u64::from(entry.to_bits()) << 32) | u64::from(node);
        if self.len < self.items.len() {
            self.items[self.len] = item;
            self.len += 1;
        } else {
            self.spill.push(item);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        let item = if let Some(s) = self.spill.pop() {
            s
        } else if self.len > 0 {
            self.len -= 1;
            self.items[self.len]
        } else {
            return None;
        };
        Some((item as u32, f32::from_bits((item >> 32) as u32)))
    }
}

/// Bit `i` set when `flags[i]` is 1 (`flags` all 0 or 1): the eight bytes gathered
/// into the top byte by one multiplication (byte `i` times byte `7 - i` of the
/// constant lands on bit `56 + i`; no two partial products share a bit).
#[inline(always)]
fn gather(flags: [u8; WIDTH]) -> u32 {
    (u64::from_le_bytes(flags).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u32
}

/// The AVX2 token when this CPU has AVX2, found at first use.
#[cfg(target_arch = "x86_64")]
fn avx2() -> Option<pulp::x86::V3> {
    static AVX2: std::sync::OnceLock<Option<pulp::x86::V3>> = std::sync::OnceLock::new();
    #[cfg(test)]
    if tests::FORCE_BASELINE.with(std::cell::Cell::get) {
        return None;
    }
    *AVX2.get_or_init(pulp::x86::V3::try_new)
}

/// Runs `f` compiled a second time with AVX2 enabled when the CPU has it (through
/// `pulp`, as the Kalman kernels do): the lane loop of the box test then uses 8-wide
/// registers. Same IEEE operations in the same order on both paths (no fused
/// multiply-add, min / max as compare-and-select), so the hits are identical.
#[inline(always)]
fn dispatch<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = avx2() {
        return simd.vectorize(f);
    }
    f()
}

/// `a < b ? a : b`: one `minps` (unlike `f32::min`, whose NaN rule costs several
/// instructions). The box test never produces NaN (see [`RayF32`]).
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// `a > b ? a : b` (see [`min`]).
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// Relative widening of the `f32` range intervals: the subtraction, the product, the
/// reciprocal and the widening product itself are rounded once each at `2^-24`
/// (2.4e-7 relative together); 1e-6 covers it.
const F32_SLACK: f32 = 1e-6;

/// A ray prepared for the `f32` box tests, relative to the tree's center.
///
/// Conservative: the range of a lower plane `l` on axis `k` is computed from an origin
/// moved up by `e`, `(l - lo_k) i_k`, that of an upper plane `h` from an origin moved
/// down by `e`, `(h - hi_k) i_k`, with `lo_k >= o_k + e` and `hi_k <= o_k - e` rounded
/// outwards from the exact `f64` origin, and `e = 2^-23 max|o_k| + 1e-6` m. Whatever
/// the sign of `i_k`, that widens the exact slab interval by `e |i_k|` on both ends;
/// the relative rounding of the subtraction, of the product and of `i_k` (`2^-24`
/// each) is covered by [`F32_SLACK`]. A zero direction component gets the reciprocal
/// `+-1e30` instead of infinity, so the products are never `0 * inf` (no NaN), and the
/// widening `e 1e30` leaves that axis unrestricted for an origin inside the slab.
/// Overflow gives infinities, which compare correctly.
#[derive(Debug, Clone, Copy)]
struct RayF32 {
    /// The origin for the lower planes: at least `e` above the exact one.
    lo: [f32; 3],
    /// The origin for the upper planes: at least `e` below the exact one.
    hi: [f32; 3],
    inv: [f32; 3],
}

impl RayF32 {
    #[inline(always)]
    fn new(o: &[f64; 3], d: &[f64; 3], center: &Vector3<f64>) -> Self {
        let rel = [o[0] - center.x, o[1] - center.y, o[2] - center.z];
        let e = 2f64.powi(-23) * rel[0].abs().max(rel[1].abs()).max(rel[2].abs()) + 1e-6;
        let inv = |x: f64| -> f64 {
            if x.abs() > 1e-30 {
                1.0 / x
            } else {
                1e30f64.copysign(x)
            }
        };
        Self {
            // the f64 sums round at 2^-53 relative, far inside `e`
            lo: rel.map(|x| round_up(x + e)),
            hi: rel.map(|x| round_down(x - e)),
            inv: [inv(d[0]), inv(d[1]), inv(d[2])].map(|x| x as f32),
        }
    }
}

impl BvhCaster {
    /// Entry ranges (conservative lower bounds, at least 0) of the child boxes of
    /// `node`, and the mask of the boxes hit with an entry not beyond `limit`.
    #[inline(always)]
    fn entries(node: &WideNode, ray: &RayF32, limit: f32) -> ([f32; WIDTH], u32) {
        let [l0, l1, l2] = ray.lo;
        let [h0, h1, h2] = ray.hi;
        let [i0, i1, i2] = ray.inv;
        let [g0, g1, g2] = node.origin;
        let [t0, t1, t2] = node.exp.map(step);
        let mut near = [0.0f32; WIDTH];
        let mut hit = [0u8; WIDTH];
        // one lane per iteration, all three axes inside: a loop the compiler
        // vectorizes across lanes
        for lane in 0..WIDTH {
            let ax = (decode(g0, t0, node.lo[0][lane]) - l0) * i0;
            let bx = (decode(g0, t0, node.hi[0][lane]) - h0) * i0;
            let ay = (decode(g1, t1, node.lo[1][lane]) - l1) * i1;
            let by = (decode(g1, t1, node.hi[1][lane]) - h1) * i1;
            let az = (decode(g2, t2, node.lo[2][lane]) - l2) * i2;
            let bz = (decode(g2, t2, node.hi[2][lane]) - h2) * i2;
            let n = max(max(min(ax, bx), min(ay, by)), min(az, bz));
            let f = min(min(max(ax, bx), max(ay, by)), max(az, bz));
            // widened by `F32_SLACK`: only the entry's non-negative part and the
            // exit's non-negative values matter below, so one product each does
            let n = max(n, 0.0) * (1.0 - F32_SLACK);
            near[lane] = n;
            // `n <= f && f >= 0 && n <= limit` without a branch (a negative limit
            // culls all, as no hit can count then)
            hit[lane] = u8::from(n <= min(f * (1.0 + F32_SLACK), limit));
        }
        (near, gather(hit) & u32::from(node.used))
    }
}

impl BvhCaster {
    /// The inner children of `node` in `hit` (entries `ent`), far to near: the nearest
    /// is returned to be visited next, the others within `limit` pushed so that the
    /// nearer are popped first.
    #[inline(always)]
    fn visit_children(
        &self,
        node: &WideNode,
        links: &Links,
        ent: &[f32; WIDTH],
        hit: u32,
        limit: f32,
        stack: &mut Stack,
    ) -> Option<(u32, f32)> {
        let inner_lanes = u32::from(node.used) & !u32::from(links.leaf);
        let mut inner: [(f32, u32); WIDTH] = [(0.0, 0); WIDTH];
        let mut count = 0;
        let mut lanes = hit & inner_lanes;
        while lanes != 0 {
            let lane = lanes.trailing_zeros();
            lanes &= lanes - 1;
            let child = links.first_node + (inner_lanes & ((1 << lane) - 1)).count_ones();
            let e = ent[lane as usize];
            // insertion into the far-to-near order
            let mut j = count;
            while j > 0 && inner[j - 1].0 < e {
                inner[j] = inner[j - 1];
                j -= 1;
            }
            inner[j] = (e, child);
            count += 1;
        }
        let (&(e, c), farther) = inner[..count].split_last()?;
        for &(e, c) in farther {
            if e <= limit {
                stack.push(c, e);
                // touch the node now: its load overlaps with the work before it is
                // popped (a software prefetch without `unsafe`)
                std::hint::black_box(self.nodes[c as usize].used);
            }
        }
        Some((c, e))
    }
}

/// What a traversal tests: one ray ([`OneRay`]) or a packet (`packet.rs`).
trait Visitor {
    /// Entries and hit mask of `node`'s children within `limit` ([`BvhCaster::entries`]).
    fn test(&self, node: &WideNode, limit: f32) -> ([f32; WIDTH], u32);
    /// Tests triangle `index`, keeping it where it is the better hit.
    fn offer(&mut self, tri: &PreparedTriangle, index: u32);
    /// The node pruning bound: the best range as an `f32` not below it (for a packet,
    /// its largest).
    fn limit(&self) -> f32;
}

/// One ray's traversal state.
struct OneRay {
    ray: RayF32,
    o: [f64; 3],
    d: [f64; 3],
    best: Best,
}

impl Visitor for OneRay {
    #[inline(always)]
    fn test(&self, node: &WideNode, limit: f32) -> ([f32; WIDTH], u32) {
        BvhCaster::entries(node, &self.ray, limit)
    }

    #[inline(always)]
    fn offer(&mut self, tri: &PreparedTriangle, index: u32) {
        self.best.offer(tri, index, &self.o, &self.d);
    }

    #[inline(always)]
    fn limit(&self) -> f32 {
        round_up(self.best.t)
    }
}

impl BvhCaster {
    /// Depth-first traversal for `visitor`: a node is skipped when its entry exceeds
    /// the limit; a node's triangles are offered, then the limit renewed; the nearest
    /// inner child is visited next ([`Self::visit_children`]).
    #[inline(always)]
    fn walk(&self, stack: &mut Stack, visitor: &mut impl Visitor) {
        let mut limit = visitor.limit();
        stack.clear();
        // the node to visit next without going through the stack (the nearest child
        // of the last node), else the top of the stack
        let mut next = Some((0u32, f32::NEG_INFINITY));
        while let Some((n, entry)) = next.take().or_else(|| stack.pop()) {
            if entry > limit {
                continue;
            }
            let node = &self.nodes[n as usize];
            let links = &self.links[n as usize];
            let (ent, hit) = visitor.test(node, limit);
            let leaf = u32::from(links.leaf);
            let mut leaves = hit & leaf;
            if leaves != 0 {
                while leaves != 0 {
                    let lane = leaves.trailing_zeros();
                    leaves &= leaves - 1;
                    let slot = links.first_triangle + (leaf & ((1 << lane) - 1)).count_ones();
                    let (tri, index) = &self.leaf_triangles[slot as usize];
                    visitor.offer(tri, *index);
                }
                limit = visitor.limit();
            }
            next = self.visit_children(node, links, &ent, hit, limit, stack);
        }
    }
}

impl BvhCaster {
    /// [`RayCaster::cast`] with a caller's traversal stack (left empty).
    #[inline(always)]
    fn cast_with(
        &self,
        stack: &mut Stack,
        origin_in_nav: &Vector3<f64>,
        dir_in_nav: &Vector3<f64>,
        max_range: f64,
    ) -> Option<RayHit> {
        let (o, d, max_range) = PreparedMesh::ray(origin_in_nav, dir_in_nav, max_range)?;
        if self.nodes.is_empty() {
            return None;
        }
        let mut one = OneRay {
            ray: RayF32::new(&o, &d, &self.center),
            o,
            d,
            best: Best::new(max_range),
        };
        self.walk(stack, &mut one);
        let best = one.best;
        self.mesh.hit_record(&best, &d)
    }
}

impl RayCaster for BvhCaster {
    fn cast(
        &self,
        origin_in_nav: &Vector3<f64>,
        dir_in_nav: &Vector3<f64>,
        max_range: f64,
    ) -> Option<RayHit> {
        dispatch(
            #[inline(always)]
            || self.cast_with(&mut Stack::new(), origin_in_nav, dir_in_nav, max_range),
        )
    }

    /// One traversal stack for the whole batch.
    fn cast_batch(
        &self,
        rays: &[Ray],
        hits: &mut [Option<RayHit>],
    ) -> Result<(), BatchLengthMismatch> {
        BatchLengthMismatch::check(rays, hits)?;
        dispatch(
            #[inline(always)]
            || {
                let mut stack = Stack::new();
                for (r, h) in rays.iter().zip(hits.iter_mut()) {
                    *h = self.cast_with(&mut stack, &r.origin_in_nav, &r.dir_in_nav, r.max_range);
                }
            },
        );
        Ok(())
    }

    /// Each group of [`PACKET`] consecutive rays traverses the tree as one packet
    /// (`bvh/packet.rs`); same hits as [`RayCaster::cast_batch`].
    fn cast_coherent(
        &self,
        rays: &[Ray],
        hits: &mut [Option<RayHit>],
    ) -> Result<(), BatchLengthMismatch> {
        BatchLengthMismatch::check(rays, hits)?;
        dispatch(
            #[inline(always)]
            || {
                let mut stack = Stack::new();
                for (r, h) in rays.chunks(PACKET).zip(hits.chunks_mut(PACKET)) {
                    self.cast_packet(&mut stack, r, h);
                }
            },
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::BuildingsParams;

    thread_local! {
        /// Makes [`super::dispatch`] run the baseline version on this thread.
        pub(super) static FORCE_BASELINE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    #[test]
    fn avx2_and_baseline_paths_give_the_same_hits() {
        let mesh = crate::presets::BridgeParams::default()
            .check()
            .unwrap()
            .mesh()
            .unwrap();
        let caster = BvhCaster::new(&mesh);
        let (lo, hi) = mesh.bounds().unwrap();
        // a deterministic spread of rays: origins on a grid, directions on a spiral
        let rays: Vec<Ray> = (0..4000)
            .map(|k| {
                let f = |i: usize, n: usize| (i % n) as f64 / (n - 1) as f64;
                let o = lo
                    + (hi - lo).component_mul(&Vector3::new(
                        f(k, 17),
                        f(k / 17, 13),
                        f(k / 221, 7),
                    ));
                let z = 1.0 - 2.0 * (k as f64 + 0.5) / 4000.0;
                let a = k as f64 * 2.399_963;
                let r = (1.0 - z * z).sqrt();
                Ray::new(o, Vector3::new(r * a.cos(), r * a.sin(), z), f64::INFINITY)
            })
            .collect();
        let mut fast = vec![None; rays.len()];
        caster.cast_batch(&rays, &mut fast).unwrap();
        FORCE_BASELINE.with(|c| c.set(true));
        let mut base = vec![None; rays.len()];
        caster.cast_batch(&rays, &mut base).unwrap();
        let single: Vec<_> = rays.iter().map(|r| caster.cast_ray(r)).collect();
        FORCE_BASELINE.with(|c| c.set(false));
        assert_eq!(fast, base);
        assert_eq!(fast, single);
        assert!(fast.iter().filter(|h| h.is_some()).count() > 1000);
    }

    #[test]
    fn the_read_back_tree_is_complete() {
        let city = BuildingsParams::default().check().unwrap().mesh().unwrap();
        let bridge = crate::presets::BridgeParams::default()
            .check()
            .unwrap()
            .mesh()
            .unwrap();
        for (mesh, build) in [
            (&city, BvhBuild::Binned),
            (&city, BvhBuild::Ploc),
            (&bridge, BvhBuild::Binned),
        ] {
            let (bin, mirrored) = binary_tree(mesh, build);
            // parry's visiting order is the one mirrored (no fallback), complete
            assert!(mirrored, "{build:?}");
            assert!(tree_is_complete(&bin, mesh.len()));
            let caster = BvhCaster::with_build(mesh, build);
            assert_eq!(caster.len(), mesh.len());
            let mut leaves: Vec<u32> = caster.leaf_triangles.iter().map(|t| t.1).collect();
            leaves.sort_unstable();
            assert_eq!(leaves, (0..mesh.len() as u32).collect::<Vec<_>>());
        }
        assert!(tree_is_complete(
            &flat_tree(&[(Vector3::zeros(), Vector3::zeros()); 5]),
            5
        ));
    }

    /// The union of the widened boxes of the triangles below node `n`, relative to
    /// the center, after checking that every used lane's quantized box holds the
    /// union below that lane.
    fn check_node(caster: &BvhCaster, mesh: &TriMesh, n: usize) -> (Vector3<f64>, Vector3<f64>) {
        let (node, links) = (&caster.nodes[n], &caster.links[n]);
        let mut union = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        let (mut next_node, mut next_triangle) = (links.first_node, links.first_triangle);
        for lane in 0..WIDTH {
            if node.used & (1 << lane) == 0 {
                continue;
            }
            let (lo, hi) = if links.leaf & (1 << lane) != 0 {
                let index = caster.leaf_triangles[next_triangle as usize].1;
                next_triangle += 1;
                let [a, b, c] = mesh.corners(index as usize);
                let (lo, hi) = widen_box(&a.inf(&b).inf(&c), &a.sup(&b).sup(&c));
                (lo - caster.center, hi - caster.center)
            } else {
                next_node += 1;
                check_node(caster, mesh, next_node as usize - 1)
            };
            for axis in 0..3 {
                let s = step(node.exp[axis]);
                let q_lo = decode(node.origin[axis], s, node.lo[axis][lane]);
                let q_hi = decode(node.origin[axis], s, node.hi[axis][lane]);
                assert!(
                    f64::from(q_lo) <= lo[axis] && f64::from(q_hi) >= hi[axis],
                    "node {n} lane {lane} axis {axis}: [{q_lo}, {q_hi}] does not hold [{}, {}]",
                    lo[axis],
                    hi[axis]
                );
            }
            union = (union.0.inf(&lo), union.1.sup(&hi));
        }
        union
    }

    /// Random triangles of size `size` in a cube of side `spread` around `offset`.
    pub(super) fn random_mesh(
        seed: u64,
        count: usize,
        spread: f64,
        size: f64,
        offset: f64,
    ) -> TriMesh {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut b = crate::MeshBuilder::new();
        for _ in 0..count {
            let p = Vector3::from_fn(|_, _| offset + spread * rng.random::<f64>());
            let mut corner = || p + Vector3::from_fn(|_, _| size * (rng.random::<f64>() - 0.5));
            let (q, r) = (corner(), corner());
            // some axis-aligned (flat boxes: a zero extent on one axis)
            let r = if rng.random::<f64>() < 0.3 {
                Vector3::new(r.x, r.y, p.z)
            } else {
                r
            };
            let q = if rng.random::<f64>() < 0.3 {
                Vector3::new(q.x, q.y, p.z)
            } else {
                q
            };
            b.triangle_at(p, q, r, fathom_core::Material::Opaque);
        }
        b.build().unwrap().0
    }

    #[test]
    fn quantized_boxes_hold_the_exact_boxes_and_hits_equal_the_oracle() {
        let city = BuildingsParams::default().check().unwrap().mesh().unwrap();
        let bridge = crate::presets::BridgeParams::default()
            .check()
            .unwrap()
            .mesh()
            .unwrap();
        let mut meshes = vec![city, bridge];
        // tiny and huge triangles, near and far from the origin
        for (seed, (spread, size, offset)) in [
            (1e-3, 1e-4, 0.0),
            (10.0, 1.0, 0.0),
            (100.0, 0.01, 1e6),
            (1e5, 50.0, -3e5),
            (5.0, 20.0, 1e4),
        ]
        .into_iter()
        .enumerate()
        {
            meshes.push(random_mesh(seed as u64, 3000, spread, size, offset));
        }
        for mesh in &meshes {
            let caster = BvhCaster::new(mesh);
            let oracle = crate::BruteForceCaster::new(mesh);
            check_node(&caster, mesh, 0);
            // rays from around the mesh at its vertices, edge midpoints and
            // anywhere: near-edge and grazing cases
            let (lo, hi) = mesh.bounds().unwrap();
            let mut hits = 0;
            for k in 0..400 {
                let [a, b, c] = mesh.corners((k * 7919) % mesh.len());
                let f = |i: usize, n: usize| (i % n) as f64 / (n - 1) as f64;
                let o = lo
                    + (hi - lo).component_mul(&Vector3::new(f(k, 7), f(k / 7, 5), f(k / 35, 3)))
                        * 1.2
                    - (hi - lo) * 0.1;
                let targets = [a, (a + b) / 2.0, (a + b + c) / 3.0, b + (c - b) * 1e-12];
                for t in targets {
                    for r in [
                        Ray::new(o, t - o, f64::INFINITY),
                        Ray::new(a - (b - a), b - a, f64::INFINITY),
                    ] {
                        let (h, e) = (caster.cast_ray(&r), oracle.cast_ray(&r));
                        assert_eq!(
                            h.map(|h| (h.triangle, h.range.to_bits())),
                            e.map(|e| (e.triangle, e.range.to_bits()))
                        );
                        hits += usize::from(h.is_some());
                    }
                }
            }
            assert!(hits > 400, "{hits}");
        }
    }

    /// The `f32` node test never culls a box that the exact ray enters within its
    /// limit (nor one it misses by less than 1e-9 relative), and its entry is never
    /// beyond the exact entry (or 0, for an origin inside the box): rays at corners, along edges, in face planes
    /// (grazing), parallel to axes, from near and far.
    #[test]
    fn the_node_test_never_culls_a_box_the_ray_enters() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(35);
        let mut checked = 0;
        for round in 0..300 {
            let scale = [1e-3, 1.0, 50.0, 3e3][round % 4];
            let offset = [0.0, 0.0, 1e4, -2e5][(round / 4) % 4];
            // eight boxes (some flat) in one node
            let boxes: Vec<([f64; 3], [f64; 3])> = (0..WIDTH)
                .map(|_| {
                    let lo: [f64; 3] =
                        std::array::from_fn(|_| offset + scale * rng.random::<f64>());
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
            for lane in 0..WIDTH {
                // the exact box of the lane (its planes)
                let p = |side: usize, k: usize| {
                    let q = [node.lo, node.hi][side][k][lane];
                    f64::from(decode(node.origin[k], step(node.exp[k]), q))
                };
                let (lo, hi) = (
                    Vector3::from_fn(|k, _| p(0, k)),
                    Vector3::from_fn(|k, _| p(1, k)),
                );
                for _ in 0..12 {
                    let pick = |rng: &mut rand_chacha::ChaCha8Rng| {
                        Vector3::from_fn(|k, _| match rng.random_range(0..3) {
                            0 => lo[k],
                            1 => hi[k],
                            _ => lo[k] + (hi[k] - lo[k]) * rng.random::<f64>(),
                        })
                    };
                    let target = pick(&mut rng);
                    let far = [1.0, 10.0, 1e3][rng.random_range(0..3)] * scale;
                    let mut o = target + Vector3::from_fn(|_, _| far * (rng.random::<f64>() - 0.5));
                    let mut d = target - o;
                    // grazing: in the plane of a face, or along an axis
                    match rng.random_range(0..4) {
                        0 => {
                            let k = rng.random_range(0..3);
                            o[k] = target[k];
                            d[k] = 0.0;
                        }
                        1 => {
                            let k = rng.random_range(0..3);
                            d = Vector3::zeros();
                            d[k] = if o[k] < target[k] { 1.0 } else { -1.0 };
                            for j in 0..3 {
                                if j != k {
                                    o[j] = target[j];
                                }
                            }
                        }
                        _ => {}
                    }
                    let Some(d) = d.try_normalize(0.0) else {
                        continue;
                    };
                    let (oa, da) = ([o.x, o.y, o.z], [d.x, d.y, d.z]);
                    let ray = RayF32::new(&oa, &da, &Vector3::zeros());
                    // the exact interval, in f64
                    let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
                    for k in 0..3 {
                        if d[k] == 0.0 {
                            if o[k] < lo[k] || o[k] > hi[k] {
                                enter = f64::INFINITY;
                            }
                        } else {
                            let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
                            enter = enter.max(a.min(b));
                            exit = exit.min(a.max(b));
                        }
                    }
                    let tol = 1e-9 * (1.0 + exit.abs().min(1e300));
                    let limit = round_up(enter.max(0.0) * (1.0 + 1e-9) + 1e-9);
                    let (near, mask) = BvhCaster::entries(&node, &ray, limit);
                    if enter <= exit + tol && exit >= -tol {
                        assert!(
                            mask & (1 << lane) != 0,
                            "culled: {o:?} {d:?} [{enter}, {exit}] box {lo:?} {hi:?}"
                        );
                        assert!(f64::from(near[lane]) <= enter.max(0.0) + tol);
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
    }

    #[test]
    fn gather_sets_the_bit_of_each_flag() {
        for mask in 0..256u32 {
            let flags = std::array::from_fn(|i| u8::from(mask & (1 << i) != 0));
            assert_eq!(gather(flags), mask);
        }
    }

    #[test]
    fn quantize_axis_rounds_outwards() {
        for kids in [
            vec![(0.0, 1.0), (0.25, 0.5)],
            vec![(-1e-9, 1e-9)],
            vec![(1e6, 1e6 + 1e-3), (1e6 + 5e-4, 1e6 + 2e-3)],
            vec![(-4096.1, 4096.3), (-0.1, 0.1), (4000.0, 4096.3)],
            vec![(1.0 / 3.0, 2.0 / 3.0), (0.1, 0.7)],
        ] {
            let (origin, exp, planes) = quantize_axis(&kids);
            for (&(lo, hi), &(ql, qh)) in kids.iter().zip(&planes) {
                let s = step(exp);
                assert!(f64::from(decode(origin, s, ql)) <= lo);
                assert!(f64::from(decode(origin, s, qh)) >= hi);
                // not looser than two steps per side
                assert!(
                    lo - f64::from(decode(origin, s, ql)) <= 2.0 * f64::from(s) + 1e-7 * lo.abs()
                );
            }
        }
    }

    #[test]
    fn the_stack_spills_and_rounding_is_outward() {
        let mut s = Stack::new();
        for i in 0..100u32 {
            s.push(i, i as f32);
        }
        for i in (0..100u32).rev() {
            assert_eq!(s.pop(), Some((i, i as f32)));
        }
        assert_eq!(s.pop(), None);
        for x in [0.1, -0.1, 1e9 + 0.3, -1e9 - 0.3, 0.0] {
            assert!(f64::from(round_down(x)) <= x && f64::from(round_up(x)) >= x);
        }
    }
}

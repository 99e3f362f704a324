//! The order in which the grid and particle updates evaluate their candidates: one
//! where consecutive candidates are neighbours, so that one beam cast from eight
//! consecutive candidates is a coherent group of rays
//! ([`fathom_core::RayCaster::cast_coherent`]). The order changes how fast the rays
//! are cast, never a candidate's value.

use nalgebra::Vector3;

/// The order of a `g0 x g1 x g2` grid stored north-major (`(i g1 + j) g2 + k`): one
/// yaw slice `k` at a time, its horizontal points row by row (`i`), the rows in
/// alternating directions of `j` (a boustrophedon), so that consecutive points are
/// always adjacent.
pub(crate) fn grid_order(grid: [usize; 3]) -> Vec<u32> {
    let [g0, g1, g2] = grid;
    let mut order = Vec::with_capacity(g0 * g1 * g2);
    for k in 0..g2 {
        for i in 0..g0 {
            for jj in 0..g1 {
                let j = if i % 2 == 0 { jj } else { g1 - 1 - jj };
                order.push(((i * g1 + j) * g2 + k) as u32);
            }
        }
    }
    order
}

/// Bits per axis of the space-filling curve.
const BITS: u32 = 21;

/// Spreads the low 21 bits of `x` to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Writes into `order` the indices of `points` sorted along a Morton (Z-order) curve
/// over their bounding box, each axis scaled to its own extent (`keys` is scratch).
/// Ties (equal cells) keep the index order, so the order is a function of the points
/// alone. Non-finite coordinates go to cell 0.
pub(crate) fn morton_order(
    points: &[Vector3<f64>],
    order: &mut Vec<u32>,
    keys: &mut Vec<(u64, u32)>,
) {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for p in points.iter().filter(|p| p.iter().all(|x| x.is_finite())) {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let cells = f64::from((1u32 << BITS) - 1);
    let scale = Vector3::from_fn(|k, _| {
        let extent = hi[k] - lo[k];
        if extent > 0.0 && extent.is_finite() {
            cells / extent
        } else {
            0.0
        }
    });
    keys.clear();
    keys.extend(points.iter().enumerate().map(|(i, p)| {
        let cell = |k: usize| {
            let c = ((p[k] - lo[k]) * scale[k]).clamp(0.0, cells);
            // NaN (a non-finite point) casts to 0
            c as u64
        };
        (
            spread(cell(0)) | (spread(cell(1)) << 1) | (spread(cell(2)) << 2),
            i as u32,
        )
    }));
    keys.sort_unstable();
    order.clear();
    order.extend(keys.iter().map(|&(_, i)| i));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_permutation(order: &[u32], n: usize) -> bool {
        let mut seen = vec![false; n];
        order.len() == n
            && order
                .iter()
                .all(|&i| (i as usize) < n && !std::mem::replace(&mut seen[i as usize], true))
    }

    #[test]
    fn the_grid_order_visits_every_point_through_neighbours() {
        let grid = [5, 4, 3];
        let order = grid_order(grid);
        assert!(is_permutation(&order, 60));
        let ijk = |p: u32| {
            let p = p as usize;
            ((p / 3) / 4, (p / 3) % 4, p % 3)
        };
        for w in order.windows(2) {
            let (a, b) = (ijk(w[0]), ijk(w[1]));
            let step = a.0.abs_diff(b.0) + a.1.abs_diff(b.1);
            // within a yaw slice each step moves to an adjacent point
            assert!(a.2 != b.2 || step == 1, "{a:?} -> {b:?}");
        }
    }

    #[test]
    fn the_morton_order_is_a_permutation_that_groups_neighbours() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let points: Vec<Vector3<f64>> = (0..4096)
            .map(|_| Vector3::from_fn(|_, _| rng.random::<f64>() * 10.0))
            .collect();
        let (mut order, mut keys) = (Vec::new(), Vec::new());
        morton_order(&points, &mut order, &mut keys);
        assert!(is_permutation(&order, points.len()));
        // consecutive points in groups of 8 are close: mean group spread well below
        // that of the index order (the negative control)
        let spread = |order: &[u32]| {
            order
                .chunks(8)
                .map(|g| {
                    let first = points[g[0] as usize];
                    g.iter()
                        .map(|&i| (points[i as usize] - first).norm())
                        .fold(0.0, f64::max)
                })
                .sum::<f64>()
                / (order.len() / 8) as f64
        };
        let identity: Vec<u32> = (0..points.len() as u32).collect();
        let (sorted, unsorted) = (spread(&order), spread(&identity));
        assert!(sorted < 0.25 * unsorted, "{sorted} vs {unsorted}");
        // degenerate inputs: one point, equal points, a NaN
        let mut odd = vec![Vector3::zeros(); 3];
        odd.push(Vector3::new(f64::NAN, 1.0, 2.0));
        morton_order(&odd, &mut order, &mut keys);
        assert!(is_permutation(&order, 4));
        morton_order(&[], &mut order, &mut keys);
        assert!(order.is_empty());
    }
}

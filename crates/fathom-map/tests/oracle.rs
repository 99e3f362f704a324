//! The BVH caster against the brute-force oracle (proptest): same triangle and range
//! (bit for bit: the two share the triangle test and the selection rule) on
//! random meshes and rays, including the hard cases: vertices on a coarse grid (shared
//! vertices and edges, coplanar and axis-aligned faces), rays that start on a surface,
//! aim at a vertex or along an edge (grazing), run parallel to faces, and meshes with
//! degenerate triangles (skipped by `TriMesh::new`, counted in its report).

use fathom_core::{Material, Ray, RayCaster, RayHit};
use fathom_map::{BruteForceCaster, BvhBuild, BvhCaster, MeshBuilder, TriMesh, presets};
use nalgebra::Vector3;
use proptest::prelude::*;

/// A coordinate: mostly on a grid of 0.5 m (shared vertices, coplanar faces), some
/// arbitrary.
fn coord() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => (-8i32..=8).prop_map(|k| f64::from(k) * 0.5),
        1 => -4.0f64..4.0,
    ]
}

fn point() -> impl Strategy<Value = Vector3<f64>> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vector3::new(x, y, z))
}

/// Triangles (some degenerate: collinear or repeated corners), each with a material.
fn mesh() -> impl Strategy<Value = (TriMesh, usize)> {
    let tri = prop_oneof![
        8 => (point(), point(), point()).prop_map(|(a, b, c)| [a, b, c]),
        1 => (point(), point(), 0.0f64..2.0).prop_map(|(a, b, s)| [a, b, a + (b - a) * s]),
        1 => (point(), point()).prop_map(|(a, b)| [a, a, b]),
    ];
    (prop::collection::vec((tri, 0u8..3), 1..80)).prop_map(|tris| {
        let mut b = MeshBuilder::new();
        for ([p, q, r], m) in &tris {
            let material = match m {
                0 => Material::Opaque,
                1 => Material::Glass,
                _ => Material::Other(u16::from(*m)),
            };
            b.triangle_at(*p, *q, *r, material);
        }
        let n = tris.len();
        (b.build().unwrap().0, n)
    })
}

/// A ray for `mesh`: from anywhere, from a point on a triangle, towards a vertex, along
/// an edge, along an axis; some with a finite range.
fn ray_for(mesh: &TriMesh, kind: u8, a: Vector3<f64>, u: f64, v: f64, pick: usize) -> Ray {
    let axis = |k: usize| Vector3::from_fn(|i, _| if i == k % 3 { 1.0 } else { 0.0 });
    if mesh.is_empty() {
        return Ray::new(a, axis(pick) + Vector3::new(0.1, 0.2, 0.3), f64::INFINITY);
    }
    let [p, q, r] = mesh.corners(pick % mesh.len());
    let on_surface = p + (q - p) * u * (1.0 - v) + (r - p) * v;
    let max = if pick.is_multiple_of(3) {
        3.0
    } else {
        f64::INFINITY
    };
    match kind % 6 {
        0 => Ray::new(a, on_surface - a + axis(pick) * 0.1, max),
        1 => Ray::new(on_surface, a - on_surface, max), // starts on a surface
        2 => Ray::new(a, q - a, max),                   // at a (shared) vertex
        3 => Ray::new(p - (q - p), q - p, max),         // along an edge: grazing
        4 => Ray::new(a, axis(pick), max),              // parallel to axis-aligned faces
        _ => Ray::new(a, (q + r) / 2.0 - a, max),       // at an edge midpoint
    }
}

fn same(bvh: Option<RayHit>, oracle: Option<RayHit>) -> Result<(), TestCaseError> {
    match (bvh, oracle) {
        (None, None) => Ok(()),
        (Some(h), Some(o)) => {
            prop_assert_eq!(h.triangle, o.triangle);
            prop_assert_eq!(h.range.to_bits(), o.range.to_bits());
            prop_assert_eq!(h.material, o.material);
            prop_assert_eq!(h.normal_in_nav, o.normal_in_nav);
            Ok(())
        }
        (h, o) => Err(TestCaseError::fail(format!("bvh {h:?} vs oracle {o:?}"))),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn bvh_equals_the_brute_force_oracle(
        (mesh, given) in mesh(),
        rays in prop::collection::vec((0u8..6, point(), 0.0f64..=1.0, 0.0f64..=1.0, 0usize..1000), 1..40),
    ) {
        prop_assert!(mesh.len() <= given);
        let oracle = BruteForceCaster::new(&mesh);
        for build in [BvhBuild::Binned, BvhBuild::Ploc] {
            let bvh = BvhCaster::with_build(&mesh, build);
            let rays: Vec<Ray> = rays
                .iter()
                .map(|&(k, a, u, v, i)| ray_for(&mesh, k, a, u, v, i))
                .collect();
            for r in &rays {
                same(bvh.cast_ray(r), oracle.cast_ray(r))?;
            }
            let mut out = vec![None; rays.len()];
            bvh.cast_batch(&rays, &mut out).unwrap();
            for (r, h) in rays.iter().zip(&out) {
                same(*h, oracle.cast_ray(r))?;
            }
        }
    }

    #[test]
    fn invalid_rays_never_panic(
        (mesh, _) in mesh(),
        o in prop::array::uniform3(prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(1e308), Just(-0.0), -5.0f64..5.0]),
        d in prop::array::uniform3(prop_oneof![Just(f64::NAN), Just(0.0), Just(1e-310), Just(1e308), -1.0f64..1.0]),
        max in prop_oneof![Just(f64::NAN), Just(0.0), Just(-1.0), Just(f64::INFINITY), 0.0f64..10.0],
    ) {
        let (o, d) = (Vector3::from(o), Vector3::from(d));
        let bvh = BvhCaster::new(&mesh);
        let oracle = BruteForceCaster::new(&mesh);
        same(bvh.cast(&o, &d, max), oracle.cast(&o, &d, max))?;
    }
}

/// On the presets (axis-aligned walls, faceted piers, shared edges everywhere), rays
/// from a grid of points along the axes and diagonals agree with the oracle.
#[test]
fn presets_agree_with_the_oracle_on_axis_rays() {
    let meshes = [
        presets::BridgeParams::default()
            .check()
            .unwrap()
            .mesh()
            .unwrap(),
        presets::BuildingsParams::default()
            .check()
            .unwrap()
            .mesh()
            .unwrap(),
    ];
    for mesh in &meshes {
        let (bvh, oracle) = (BvhCaster::new(mesh), BruteForceCaster::new(mesh));
        let (lo, hi) = mesh.bounds().unwrap();
        let mut n = 0;
        for i in 0..=12 {
            for j in 0..=12 {
                for k in 0..=4 {
                    let f = |a: f64, b: f64, s: f64| a + (b - a) * s;
                    let o = Vector3::new(
                        f(lo.x, hi.x, f64::from(i) / 12.0),
                        f(lo.y, hi.y, f64::from(j) / 12.0),
                        f(lo.z, hi.z, f64::from(k) / 4.0),
                    );
                    for d in [
                        Vector3::x(),
                        -Vector3::x(),
                        Vector3::y(),
                        -Vector3::y(),
                        Vector3::z(),
                        -Vector3::z(),
                        Vector3::new(1.0, 1.0, 0.0),
                        Vector3::new(-1.0, 1.0, -1.0),
                    ] {
                        let (h, o2) = (bvh.cast(&o, &d, 1e4), oracle.cast(&o, &d, 1e4));
                        assert_eq!(
                            h.map(|x| (x.triangle, x.range.to_bits())),
                            o2.map(|x| (x.triangle, x.range.to_bits())),
                            "{o:?} {d:?}"
                        );
                        n += usize::from(h.is_some());
                    }
                }
            }
        }
        assert!(n > 500, "{n} hits");
    }
}

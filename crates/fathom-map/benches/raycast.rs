//! Closest-hit ray casting, single thread, ns per ray: the `buildings` preset and,
//! when `FATHOM_RAYCAST_MESH` names an OBJ file (in NED metres, as the Embree
//! reference script of docs/performance.md writes it; `cargo xtask bench raycast --mesh FILE`
//! sets it), that mesh. Rays: origins uniform in the mesh's bounding box, directions
//! uniform on the sphere, no range limit, seeded (the reference script's
//! distribution). One iteration is one ray (cycling through 2^16 pre-drawn rays);
//! `raycast_batch/*` is the same rays through `cast_batch`, per ray.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use fathom_core::{Ray, RayCaster};
use fathom_map::{AxisConvention, BvhCaster, ImportSettings, TriMesh, obj, presets};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

const RAYS: usize = 1 << 16;

/// Origins uniform in the bounding box, directions uniform on the sphere.
fn rays(mesh: &TriMesh, seed: u64) -> Vec<Ray> {
    let (lo, hi) = mesh.bounds().expect("non-empty mesh");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..RAYS)
        .map(|_| {
            let o = lo + (hi - lo).component_mul(&Vector3::from_fn(|_, _| rng.random::<f64>()));
            let d = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal)).normalize();
            Ray::new(o, d, f64::INFINITY)
        })
        .collect()
}

fn bench_mesh(c: &mut Criterion, name: &str, mesh: &TriMesh) {
    let caster = BvhCaster::new(mesh);
    let rays = rays(mesh, 7);
    let hits = rays.iter().filter(|r| caster.cast_ray(r).is_some()).count();
    eprintln!(
        "raycast {name}: {} triangles, hit fraction {:.3}",
        mesh.len(),
        hits as f64 / RAYS as f64
    );
    let mut i = 0;
    c.bench_function(&format!("raycast/{name}"), |b| {
        b.iter(|| {
            i = (i + 1) & (RAYS - 1);
            black_box(caster.cast_ray(black_box(&rays[i])))
        })
    });
    let mut group = c.benchmark_group("raycast_batch");
    group.throughput(Throughput::Elements(RAYS as u64));
    let mut out = vec![None; RAYS];
    group.sample_size(10);
    group.bench_function(name, |b| {
        b.iter(|| caster.cast_batch(black_box(&rays), &mut out).unwrap())
    });
    group.finish();
}

fn raycast(c: &mut Criterion) {
    let city = presets::BuildingsParams::default()
        .check()
        .unwrap()
        .mesh()
        .unwrap();
    bench_mesh(c, "buildings", &city);
    if let Some(path) = std::env::var_os("FATHOM_RAYCAST_MESH") {
        let file = std::fs::File::open(&path)
            .unwrap_or_else(|e| panic!("FATHOM_RAYCAST_MESH={}: {e}", path.to_string_lossy()));
        let settings = ImportSettings {
            axes: AxisConvention::Ned,
            ..ImportSettings::default()
        };
        let (mesh, report) = obj::read_obj(std::io::BufReader::new(file), &settings)
            .unwrap_or_else(|e| panic!("{}: {e}", path.to_string_lossy()));
        eprintln!("raycast mesh: {report:?}");
        bench_mesh(c, "mesh", &mesh);
    }
}

criterion_group!(benches, raycast);
criterion_main!(benches);

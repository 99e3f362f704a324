//! The map-aided estimators of seed 004 (`fathom_estimators::map_aided`), single
//! thread, on the `fathom-map` presets: one 12-state prediction; one GREKF update with
//! a 109-beam lidar scan (UST-20LX: -135..135 deg by 2.5 deg, 60 m) in the `buildings`
//! east corridor; one MGPMF update with a 41 x 41 x 9 grid and 7 beams (6 horizontal
//! at 60 deg + 1 down) on `buildings` (target <= 25 ms); one particle-filter update at
//! the same ray count (15129 particles x 7 beams); the MGPMF update again on two
//! threads (the scaling). `map_aided_rays/*` cast the same
//! number of rays from the same kind of poses through `cast_batch` alone, so
//! `cargo xtask bench` reports the ns per ray cast inside each update and the share of
//! the update the casts take. Run with `cargo xtask bench map_aided`; see
//! `docs/performance.md`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use fathom_core::{Ray, RayCaster, RayHit};
use fathom_estimators::map_aided::{
    ATT, Grekf, Ins12Filter, Ins12Params, Mgpmf, MgpmfParams, NominalNav, ParticleFilter,
    ParticleParams, RangeBeam, RangeParams,
};
use fathom_map::{BvhCaster, presets};
use nalgebra::{UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn nominal(pos: Vector3<f64>, yaw: f64) -> NominalNav {
    NominalNav {
        pos_in_nav: pos,
        vel_in_nav: Vector3::new(3.0, 0.0, 0.0),
        nav_from_body: UnitQuaternion::from_euler_angles(0.01, -0.02, yaw),
        accel_bias_in_body: Vector3::zeros(),
    }
}

fn filter(sigma_pos: f64, sigma_yaw: f64) -> Ins12Filter {
    let mut p0 = Ins12Filter::diagonal_covariance([sigma_pos, 0.2, 0.01, 0.01]);
    p0[(ATT + 2, ATT + 2)] = sigma_yaw * sigma_yaw;
    Ins12Filter::new(&p0, 0.0, Ins12Params::default().check().unwrap()).unwrap()
}

/// Beams with their true ranges (+ noise) seen from `truth`; beams without a return
/// are dropped, as a sensor reports them.
fn measure(
    caster: &dyn RayCaster,
    truth: &NominalNav,
    dirs: &[Vector3<f64>],
    sigma: f64,
    max_range: f64,
) -> Vec<RangeBeam> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let noise = Normal::new(0.0, sigma).unwrap();
    dirs.iter()
        .filter_map(|d| {
            caster
                .cast(&truth.pos_in_nav, &(truth.nav_from_body * d), max_range)
                .map(|h| RangeBeam {
                    dir_in_body: *d,
                    range_m: h.range + noise.sample(&mut rng),
                    sigma_m: sigma,
                })
        })
        .collect()
}

fn lidar_dirs() -> Vec<Vector3<f64>> {
    (0..109)
        .map(|k| {
            let a = (-135.0 + 2.5 * k as f64).to_radians();
            Vector3::new(a.cos(), a.sin(), 0.0)
        })
        .collect()
}

fn seven_dirs() -> Vec<Vector3<f64>> {
    let mut d: Vec<_> = (0..6)
        .map(|k| {
            let a = (60.0 * k as f64).to_radians();
            Vector3::new(a.cos(), a.sin(), 0.0)
        })
        .collect();
    d.push(Vector3::z());
    d
}

/// The rays of a `g0 x g1 x g2` grid of horizontal offsets and yaw offsets around
/// `nav` (as the MGPMF casts them), `+- k sigma`.
fn grid_rays(
    nav: &NominalNav,
    dirs: &[Vector3<f64>],
    grid: [usize; 3],
    sigma: [f64; 3],
) -> Vec<Ray> {
    let mut rays = Vec::new();
    let step =
        |i: usize, n: usize, s: f64| (i as f64 - (n - 1) as f64 / 2.0) * 6.0 * s / (n - 1) as f64;
    for i in 0..grid[0] {
        for j in 0..grid[1] {
            for k in 0..grid[2] {
                let pos = nav.pos_in_nav
                    - Vector3::new(step(i, grid[0], sigma[0]), step(j, grid[1], sigma[1]), 0.0);
                let q = UnitQuaternion::from_scaled_axis(Vector3::new(
                    0.0,
                    0.0,
                    -step(k, grid[2], sigma[2]),
                )) * nav.nav_from_body;
                rays.extend(dirs.iter().map(|d| Ray::new(pos, q * d, 60.0)));
            }
        }
    }
    rays
}

/// The rays of [`grid_rays`] (point-major: `i`, `j`, `k`, beam) reordered by yaw
/// slice `k`, beam, `i`, `j`.
fn coherent_order(rays: &[Ray], grid: [usize; 3], beams: usize) -> Vec<Ray> {
    let [g0, g1, g2] = grid;
    let mut out = Vec::with_capacity(rays.len());
    for k in 0..g2 {
        for beam in 0..beams {
            for i in 0..g0 {
                for j in 0..g1 {
                    out.push(rays[((i * g1 + j) * g2 + k) * beams + beam]);
                }
            }
        }
    }
    out
}

/// Writes the mesh (`buildings.obj`, NED metres) and the rays (`grid_rays.f64`: per ray
/// origin, direction, max range as seven little-endian `f64`) into `dir`, for the
/// Embree run of the same rays (`crates/fathom-map/benches/embree_rays.py`).
fn export_rays(dir: &std::path::Path, mesh: &fathom_map::TriMesh, rays: &[Ray]) {
    use std::fmt::Write as _;
    std::fs::create_dir_all(dir).expect("FATHOM_EXPORT_GRID_RAYS: create the folder");
    let mut obj = String::new();
    for i in 0..mesh.len() {
        for v in mesh.corners(i) {
            let _ = writeln!(obj, "v {} {} {}", v.x, v.y, v.z);
        }
        let _ = writeln!(obj, "f {} {} {}", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    std::fs::write(dir.join("buildings.obj"), obj).expect("write buildings.obj");
    let bytes: Vec<u8> = rays
        .iter()
        .flat_map(|r| {
            let (o, d) = (r.origin_in_nav, r.dir_in_nav);
            [o.x, o.y, o.z, d.x, d.y, d.z, r.max_range]
        })
        .flat_map(f64::to_le_bytes)
        .collect();
    std::fs::write(dir.join("grid_rays.f64"), bytes).expect("write grid_rays.f64");
    eprintln!(
        "map_aided: {} rays and the mesh written to {}",
        rays.len(),
        dir.display()
    );
}

fn map_aided(c: &mut Criterion) {
    let mut g = c.benchmark_group("map_aided");
    g.warm_up_time(Duration::from_millis(500));

    // 12-state prediction (one 100 Hz IMU step)
    let mut f = filter(1.0, 0.02);
    let q = UnitQuaternion::from_euler_angles(0.05, -0.03, 0.7);
    let fb = Vector3::new(0.3, -0.2, -9.81);
    let mut t = 0.0;
    g.bench_function("ins12_predict", |b| {
        b.iter(|| {
            t += 0.01;
            f.predict(black_box(&q), black_box(&fb), t).unwrap();
        })
    });

    let city = presets::BuildingsParams::default()
        .check()
        .unwrap()
        .mesh()
        .unwrap();
    let caster = BvhCaster::new(&city);

    // GREKF: the lidar in the east corridor (15 m to each facade), yaw north
    let truth = nominal(Vector3::new(50.0, 100.0, -20.0), 0.0);
    let est = nominal(Vector3::new(50.3, 99.8, -20.1), 0.005);
    let scan = measure(&caster, &truth, &lidar_dirs(), 0.02, 60.0);
    eprintln!(
        "map_aided/grekf_109_beams: {} of 109 beams return",
        scan.len()
    );
    let f0 = filter(0.5, 0.01);
    let mut grekf = Grekf::new(RangeParams::default().check().unwrap());
    g.bench_function("grekf_109_beams", |b| {
        b.iter(|| {
            let mut f = f0.clone();
            black_box(
                grekf
                    .update(&mut f, &est, black_box(&scan), None, &caster)
                    .unwrap(),
            )
        })
    });

    // MGPMF and particle filter: 7 beams on the south-west leg (all 7 return at yaw 30 deg)
    let truth = nominal(Vector3::new(50.0, 0.0, -20.0), 30f64.to_radians());
    let est = nominal(Vector3::new(50.8, -0.6, -20.0), 31f64.to_radians());
    let beams = measure(&caster, &truth, &seven_dirs(), 0.1, 60.0);
    assert_eq!(beams.len(), 7, "all 7 beams must return");
    let (sigma_pos, sigma_yaw) = (2.0, 2f64.to_radians());
    let f0 = filter(sigma_pos, sigma_yaw);
    let grid = MgpmfParams::default();
    let mut mgpmf = Mgpmf::new(grid.check().unwrap());
    g.sample_size(20).measurement_time(Duration::from_secs(5));
    g.bench_function("mgpmf_41x41x9_7beams", |b| {
        b.iter(|| {
            let mut f = f0.clone();
            black_box(
                mgpmf
                    .update(&mut f, &est, black_box(&beams), None, &caster)
                    .unwrap(),
            )
        })
    });
    // the same update on two threads (`Mgpmf::set_threads`; same result): the
    // scaling, where the single-thread figure above stays the benchmark
    let mut mgpmf_2 = Mgpmf::new(grid.check().unwrap());
    mgpmf_2.set_threads(2).unwrap();
    g.bench_function("mgpmf_41x41x9_7beams_2threads", |b| {
        b.iter(|| {
            let mut f = f0.clone();
            black_box(
                mgpmf_2
                    .update(&mut f, &est, black_box(&beams), None, &caster)
                    .unwrap(),
            )
        })
    });
    let pf_settings = ParticleParams::with_grid_budget(&grid).check().unwrap();
    let mut pf = ParticleFilter::new(pf_settings);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    g.bench_function("particle_15129_7beams", |b| {
        b.iter(|| {
            // the first update of a fresh particle set (draws from the prior)
            pf.reset();
            let mut f = f0.clone();
            black_box(
                pf.update(&mut f, &est, black_box(&beams), None, &caster, &mut rng)
                    .unwrap(),
            )
        })
    });
    g.finish();

    // the ray casts alone
    let mut r = c.benchmark_group("map_aided_rays");
    r.warm_up_time(Duration::from_millis(500));
    let lidar_truth = nominal(Vector3::new(50.0, 100.0, -20.0), 0.0);
    let lidar_rays: Vec<Ray> = scan
        .iter()
        .map(|b| {
            Ray::new(
                lidar_truth.pos_in_nav,
                lidar_truth.nav_from_body * b.dir_in_body,
                60.0,
            )
        })
        .collect();
    let mut hits: Vec<Option<RayHit>> = vec![None; lidar_rays.len()];
    r.bench_function("grekf_scan", |b| {
        b.iter(|| {
            caster
                .cast_batch(black_box(&lidar_rays), &mut hits)
                .unwrap()
        })
    });
    let rays = grid_rays(
        &est,
        &seven_dirs(),
        grid.grid_points,
        [sigma_pos, sigma_pos, sigma_yaw],
    );
    assert_eq!(rays.len(), 41 * 41 * 9 * 7);
    let mut hits: Vec<Option<RayHit>> = vec![None; rays.len()];
    r.sample_size(20).measurement_time(Duration::from_secs(5));
    r.bench_function("grid_41x41x9_7beams", |b| {
        b.iter(|| caster.cast_batch(black_box(&rays), &mut hits).unwrap())
    });
    // the same rays in the order of the coherent path (yaw slice, beam, then the
    // horizontal grid: eight neighbouring points per packet), cast one by one and as
    // packets
    let coherent = coherent_order(&rays, grid.grid_points, 7);
    caster.cast_coherent(&coherent, &mut hits).unwrap();
    eprintln!(
        "map_aided_rays/grid_41x41x9_7beams: {} triangles, hit fraction {:.4}",
        city.len(),
        hits.iter().filter(|h| h.is_some()).count() as f64 / hits.len() as f64
    );
    if let Some(dir) = std::env::var_os("FATHOM_EXPORT_GRID_RAYS") {
        export_rays(std::path::Path::new(&dir), &city, &coherent);
    }
    r.bench_function("grid_41x41x9_7beams_beam_order", |b| {
        b.iter(|| caster.cast_batch(black_box(&coherent), &mut hits).unwrap())
    });
    r.bench_function("grid_41x41x9_7beams_packets", |b| {
        b.iter(|| {
            caster
                .cast_coherent(black_box(&coherent), &mut hits)
                .unwrap()
        })
    });
    r.finish();
}

criterion_group!(benches, map_aided);
criterion_main!(benches);

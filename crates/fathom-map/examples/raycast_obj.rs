//! Ray casting a user's OBJ file with `fathom-map` alone: the file is read into local
//! NED metres (Z-up map axes by default), a BVH is built, and a horizontal lidar
//! sweep (360 beams, 1 deg apart, 100 m) is cast from a point 1.5 m above the
//! ground. The closest hits are checked against the brute-force caster.
//!
//! Run with `cargo run -p fathom-map --example raycast_obj [FILE.obj [NORTH EAST]]`;
//! without a file, a small block (a ground square, a 20 m wide building 30 m north
//! with a glass front, a wall 15 m east) is written to a temporary file and read back.

use fathom_core::{Material, RayCaster};
use fathom_map::{BruteForceCaster, BvhCaster, ImportSettings, obj::read_obj};
use nalgebra::Vector3;
use std::time::Instant;

/// The default world, in Z-up map axes (x east, y north, z up), metres.
const BLOCK_OBJ: &str = "\
# ground
v -100 -100 0
v 100 -100 0
v 100 100 0
v -100 100 0
f 1 2 3 4
# a building 30 m north, 20 m wide, 12 m high, glass front
usemtl glass
v -10 30 0
v 10 30 0
v 10 30 12
v -10 30 12
f 5 6 7 8
usemtl opaque
v -10 50 0
v 10 50 0
v 10 50 12
v -10 50 12
f 9 10 11 12
f 5 9 12 8
f 6 10 11 7
f 8 7 11 12
# a wall 15 m east
v 15 -20 0
v 15 20 0
v 15 20 5
v 15 -20 5
f 13 14 15 16
";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (path, temporary) = match args.first() {
        Some(p) => (std::path::PathBuf::from(p), false),
        None => {
            let p = std::env::temp_dir().join(format!("fathom-block-{}.obj", std::process::id()));
            std::fs::write(&p, BLOCK_OBJ)?;
            (p, true)
        }
    };
    let start = Instant::now();
    let file = std::fs::File::open(&path)?;
    let (mesh, report) = read_obj(file, &ImportSettings::default())?;
    if temporary {
        std::fs::remove_file(&path)?;
    }
    let caster = BvhCaster::new(&mesh);
    println!(
        "{}: {} triangles ({} faces read, {} polygons split), BVH built in {:.1} ms",
        path.display(),
        mesh.len(),
        report.faces_read,
        report.polygons_triangulated,
        start.elapsed().as_secs_f64() * 1e3
    );

    // The sensor: 1.5 m above the ground (NED z = -1.5) at the given point.
    let north = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(0.0);
    let east = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(0.0);
    let origin = Vector3::new(north, east, -1.5);
    let oracle = BruteForceCaster::new(&mesh);
    let (mut hits, mut glass) = (0, 0);
    for deg in (0..360).step_by(1) {
        let a = f64::from(deg).to_radians();
        let dir = Vector3::new(a.cos(), a.sin(), 0.0);
        let hit = caster.cast(&origin, &dir, 100.0);
        let expected = oracle.cast(&origin, &dir, 100.0);
        assert_eq!(
            hit.map(|h| (h.triangle, h.material)),
            expected.map(|h| (h.triangle, h.material))
        );
        if let Some(h) = hit {
            hits += 1;
            glass += usize::from(h.material == Material::Glass);
            if deg % 45 == 0 {
                let incidence = h.incidence(&dir).to_degrees();
                println!(
                    "  bearing {deg:3} deg: {:6.2} m, {}, incidence {incidence:4.1} deg",
                    h.range, h.material
                );
            }
        } else if deg % 45 == 0 {
            println!("  bearing {deg:3} deg: no hit within 100 m");
        }
    }
    println!("{hits} of 360 beams hit, {glass} of them glass");
    if args.is_empty() {
        // North is the glass front at 30 m, east the wall at 15 m, south and west open.
        let n = caster.cast(&origin, &Vector3::x(), 100.0).unwrap();
        assert!((n.range - 30.0).abs() < 1e-9 && n.material == Material::Glass);
        let e = caster.cast(&origin, &Vector3::y(), 100.0).unwrap();
        assert!((e.range - 15.0).abs() < 1e-9 && e.material == Material::Opaque);
        assert!(caster.cast(&origin, &-Vector3::x(), 100.0).is_none());
        assert!(glass > 0 && hits < 360);
    }
    Ok(())
}

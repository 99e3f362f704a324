//! A fixed number of closest-hit casts for instruction counting: the rays of the
//! `raycast` bench (origins uniform in the mesh's bounding box, directions uniform on
//! the sphere, no range limit, ChaCha8 seed 7) cast one by one with
//! `BvhCaster::cast` on the OBJ file given (NED metres, as the Embree reference script
//! writes it) or, without one, on the `buildings` preset.
//!
//! ```sh
//! cargo build --release -p fathom-map --example raycast_count
//! valgrind --tool=callgrind --toggle-collect='*BvhCaster*cast*' \
//!     target/release/examples/raycast_count /tmp/city.obj 20000
//! ```
//!
//! Instructions per ray: the collected `Ir` divided by the ray count (20,000 by
//! default). The hit count printed at the end is a cross-check between versions.

use std::hint::black_box;

use fathom_core::{Ray, RayCaster};
use fathom_map::{AxisConvention, BvhCaster, ImportSettings, obj, presets};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mesh = match args.first() {
        Some(path) => {
            let settings = ImportSettings {
                axes: AxisConvention::Ned,
                ..ImportSettings::default()
            };
            obj::read_obj(
                std::io::BufReader::new(std::fs::File::open(path)?),
                &settings,
            )?
            .0
        }
        None => presets::BuildingsParams::default().check()?.mesh()?,
    };
    let n: usize = args
        .get(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(20_000);
    let caster = BvhCaster::new(&mesh);
    let (lo, hi) = mesh.bounds().ok_or("empty mesh")?;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let rays: Vec<Ray> = (0..n)
        .map(|_| {
            let o = lo + (hi - lo).component_mul(&Vector3::from_fn(|_, _| rng.random::<f64>()));
            let d = Vector3::from_fn(|_, _| rng.sample::<f64, _>(StandardNormal)).normalize();
            Ray::new(o, d, f64::INFINITY)
        })
        .collect();
    let mut hits = 0usize;
    let mut sum = 0.0f64;
    for r in &rays {
        if let Some(h) = black_box(&caster).cast_ray(black_box(r)) {
            hits += 1;
            sum += h.range + f64::from(h.triangle);
        }
    }
    println!(
        "{} triangles, {n} rays, {hits} hits, checksum {sum:.9e}",
        mesh.len()
    );
    Ok(())
}

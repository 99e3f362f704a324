//! A fixed sky for a simple line-of-sight satellite count: nine directions spread in
//! azimuth and elevation, each a satellite far away; the count of those a map does not
//! block drives the GPS <-> map-aided switch of the `buildings` runs (the map-aided
//! end-to-end test and processor-in-the-loop use the same sky).

use fathom_core::RayCaster;
use nalgebra::Vector3;

/// Azimuth (from north, clockwise) and elevation of the nine fixed satellites, deg.
pub const FIXED_SKY_AZ_EL_DEG: [(f64, f64); 9] = [
    (10.0, 75.0),
    (70.0, 20.0),
    (100.0, 45.0),
    (160.0, 30.0),
    (200.0, 60.0),
    (240.0, 15.0),
    (290.0, 35.0),
    (330.0, 50.0),
    (30.0, 25.0),
];

/// Distance of a sky point along its direction, m (far beyond any map).
pub const SKY_DISTANCE_M: f64 = 2e4;

/// Unit NED vectors from the receiver towards the nine fixed satellites.
pub fn fixed_sky_directions() -> Vec<Vector3<f64>> {
    FIXED_SKY_AZ_EL_DEG
        .iter()
        .map(|&(az, el): &(f64, f64)| {
            let (az, el) = (az.to_radians(), el.to_radians());
            Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), -el.sin())
        })
        .collect()
}

/// How many of `dirs` are in line of sight from `pos_in_nav` over `map`.
pub fn los_count(map: &dyn RayCaster, pos_in_nav: &Vector3<f64>, dirs: &[Vector3<f64>]) -> usize {
    dirs.iter()
        .filter(|d| map.line_of_sight(pos_in_nav, &(pos_in_nav + *d * SKY_DISTANCE_M)))
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_are_unit_and_above_the_horizon() {
        let d = fixed_sky_directions();
        assert_eq!(d.len(), 9);
        for v in &d {
            assert!((v.norm() - 1.0).abs() < 1e-12);
            assert!(v.z < 0.0, "up is -z in NED");
        }
        // 10 deg azimuth, 75 deg elevation: mostly up, a little north-east.
        assert!((d[0].z + 75f64.to_radians().sin()).abs() < 1e-12);
        assert!(d[0].x > d[0].y && d[0].y > 0.0);
    }
}

//! PX4's local-frame projection: the azimuthal equidistant projection on a sphere of
//! radius [`EARTH_RADIUS`] about a reference point, with which EKF2 maps GNSS fixes
//! into `vehicle_local_position` (north `x`, east `y`). [`reproject`] takes a local
//! position back to latitude and longitude (the converter, for EKF2's track and the
//! simulator's truth); [`project`] is its inverse (the replay, for every track, so
//! that EKF2's track lands back in its own frame to rounding).

/// The sphere's radius, m (PX4's `CONSTANTS_RADIUS_OF_EARTH`).
pub const EARTH_RADIUS: f64 = 6_371_000.0;

/// Latitude and longitude (rad) of the local point `north`, `east` (m) about the
/// reference `ref_lat_lon` (rad).
pub fn reproject(ref_lat_lon: [f64; 2], north: f64, east: f64) -> [f64; 2] {
    let [lat0, lon0] = ref_lat_lon;
    let (x, y) = (north / EARTH_RADIUS, east / EARTH_RADIUS);
    let c = x.hypot(y);
    if c == 0.0 {
        return ref_lat_lon;
    }
    let (sin_c, cos_c) = c.sin_cos();
    let (sin_lat0, cos_lat0) = lat0.sin_cos();
    let lat = (cos_c * sin_lat0 + x * sin_c * cos_lat0 / c)
        .clamp(-1.0, 1.0)
        .asin();
    let lon = lon0 + (y * sin_c).atan2(c * cos_lat0 * cos_c - x * sin_lat0 * sin_c);
    [lat, lon]
}

/// North and east (m) of `lat_lon` (rad) about the reference `ref_lat_lon` (rad).
pub fn project(ref_lat_lon: [f64; 2], lat_lon: [f64; 2]) -> [f64; 2] {
    let [lat0, lon0] = ref_lat_lon;
    let [lat, lon] = lat_lon;
    let (sin_lat0, cos_lat0) = lat0.sin_cos();
    let (sin_lat, cos_lat) = lat.sin_cos();
    let (sin_dlon, cos_dlon) = (lon - lon0).sin_cos();
    let cos_c = (sin_lat0 * sin_lat + cos_lat0 * cos_lat * cos_dlon).clamp(-1.0, 1.0);
    let c = cos_c.acos();
    let k = if c.abs() < 1e-12 { 1.0 } else { c / c.sin() };
    [
        k * (cos_lat0 * sin_lat - sin_lat0 * cos_lat * cos_dlon) * EARTH_RADIUS,
        k * cos_lat * sin_dlon * EARTH_RADIUS,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproject_then_project_is_the_identity() {
        let r = [47.3977f64.to_radians(), 8.5456f64.to_radians()];
        for (n, e) in [(0.0, 0.0), (12.5, -3.25), (-850.0, 1200.0), (0.001, 0.0)] {
            let ll = reproject(r, n, e);
            let back = project(r, ll);
            assert!(
                (back[0] - n).abs() < 1e-6 && (back[1] - e).abs() < 1e-6,
                "{n} {e}: {back:?}"
            );
        }
        // one arc-minute of latitude is about 1853 m on this sphere
        let north = project(r, [r[0] + (1.0f64 / 60.0).to_radians(), r[1]])[0];
        assert!((north - EARTH_RADIUS * (1.0f64 / 60.0).to_radians()).abs() < 1e-6);
    }
}

//! WGS-84 Earth model for the NED mechanization: constants, radii of curvature,
//! normal gravity (Somigliana + free-air), Earth and transport rates, position rates,
//! and conversions between (lat, lon, h) and local NED offsets in metres.
//!
//! References: NIMA TR8350.2 (WGS-84, 3rd ed.) ch. 3-4; Groves, *Principles of GNSS,
//! Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed. (2013), §2.4,
//! §2.5, §5.4; Titterton & Weston, *Strapdown Inertial Navigation Technology*, 2nd ed.
//! (2004), ch. 3.
//!
//! Conventions: latitude `L` and longitude `lambda` in radians, height `h` in metres
//! **above** the ellipsoid (up positive; a vehicle at 50 m depth has `h = -50`), NED
//! velocity `v = [v_N, v_E, v_D]`.

use nalgebra::{Matrix3, Vector3};

/// WGS-84 semi-major axis `a`, m.
pub const A: f64 = 6_378_137.0;
/// WGS-84 flattening `f`.
pub const F: f64 = 1.0 / 298.257_223_563;
/// WGS-84 semi-minor axis `b = a (1 - f)`, m.
pub const B: f64 = A * (1.0 - F);
/// First eccentricity squared `e^2 = f (2 - f)`.
pub const E2: f64 = F * (2.0 - F);
/// WGS-84 Earth rotation rate `omega_ie`, rad/s.
pub const OMEGA_IE: f64 = 7.292_115e-5;
/// WGS-84 Earth gravitational constant `GM` (including the atmosphere), m^3/s^2.
pub const GM: f64 = 3.986_004_418e14;
/// Normal gravity on the ellipsoid at the equator `gamma_e`, m/s^2 (TR8350.2 Table 3.4).
pub const GAMMA_EQUATOR: f64 = 9.780_325_335_9;
/// Normal gravity on the ellipsoid at the poles `gamma_p`, m/s^2 (TR8350.2 Table 3.4).
pub const GAMMA_POLE: f64 = 9.832_184_937_8;
/// Somigliana constant `k = (b gamma_p) / (a gamma_e) - 1`.
pub const SOMIGLIANA_K: f64 = B * GAMMA_POLE / (A * GAMMA_EQUATOR) - 1.0;
/// Geodetic parameter `m = omega^2 a^2 b / GM` used in the free-air correction.
pub const M_GEODETIC: f64 = OMEGA_IE * OMEGA_IE * A * A * B / GM;

/// Meridian radius of curvature (north-south), often written `R_M` or `R_N`:
///
/// ```text
/// R_N(L) = a (1 - e^2) / (1 - e^2 sin^2 L)^(3/2)          (Groves eq. 2.105)
/// ```
pub fn meridian_radius(lat: f64) -> f64 {
    meridian_radius_from_sin(lat.sin())
}

/// `(1 - e^2 sin^2 L, sqrt(1 - e^2 sin^2 L))` from `sin L`: the one expression of
/// every `*_from_sin` function below, written once so that the compiler computes the
/// square root once where several of them are evaluated at the same latitude (the
/// strapdown's mid-interval radii and gravity, its position update's radii).
#[inline]
fn ellipsoid_factor(s: f64) -> (f64, f64) {
    let d = 1.0 - E2 * (s * s);
    (d, d.sqrt())
}

/// [`meridian_radius`] from `sin L` (the strapdown evaluates `sin L` once per step).
#[inline]
pub(crate) fn meridian_radius_from_sin(s: f64) -> f64 {
    let (d, w) = ellipsoid_factor(s);
    A * (1.0 - E2) / (d * w)
}

/// Transverse (prime-vertical, east-west) radius of curvature, often `R_E` or `R_N`:
///
/// ```text
/// R_E(L) = a / sqrt(1 - e^2 sin^2 L)                       (Groves eq. 2.106)
/// ```
pub fn transverse_radius(lat: f64) -> f64 {
    transverse_radius_from_sin(lat.sin())
}

/// [`transverse_radius`] from `sin L`.
#[inline]
pub(crate) fn transverse_radius_from_sin(s: f64) -> f64 {
    A / ellipsoid_factor(s).1
}

/// `kappa = e^2 sin L cos L / (1 - e^2 sin^2 L)` from `(sin L, cos L)`: the
/// logarithmic derivatives of the radii, `dR_E/dL = kappa R_E` and `dR_N/dL = 3 kappa
/// R_N` (differentiate Groves eq. 2.105-2.106).
#[inline]
pub(crate) fn radius_log_derivative_from_sin_cos(s: f64, c: f64) -> f64 {
    E2 * s * c / ellipsoid_factor(s).0
}

/// The free-air factor `1 - (2/a)(1 + f + m - 2 f sin^2 L) h + (3/a^2) h^2` of
/// [`normal_gravity`].
fn free_air_factor(s2: f64, h: f64) -> f64 {
    1.0 - 2.0 / A * (1.0 + F + M_GEODETIC - 2.0 * F * s2) * h + 3.0 / (A * A) * h * h
}

/// Normal gravity on the ellipsoid surface, Somigliana's closed formula:
///
/// ```text
/// gamma_0(L) = gamma_e (1 + k sin^2 L) / sqrt(1 - e^2 sin^2 L)   (TR8350.2 eq. 4-1)
/// ```
pub fn somigliana_gravity(lat: f64) -> f64 {
    let s2 = lat.sin().powi(2);
    GAMMA_EQUATOR * (1.0 + SOMIGLIANA_K * s2) / (1.0 - E2 * s2).sqrt()
}

/// Normal gravity magnitude at latitude `lat` and height `h` above the ellipsoid,
/// Somigliana plus the second-order free-air correction (TR8350.2 eq. 4-3):
///
/// ```text
/// gamma(L, h) = gamma_0(L) [1 - (2/a)(1 + f + m - 2 f sin^2 L) h + (3/a^2) h^2]
/// ```
///
/// The normal gravity vector in NED is taken as `[0, 0, gamma]` (the tiny
/// north component of normal gravity off the ellipsoid, < 1e-5 m/s^2 at 1 km, is
/// neglected).
pub fn normal_gravity(lat: f64, h: f64) -> f64 {
    normal_gravity_from_sin(lat.sin(), h)
}

/// [`normal_gravity`] from `sin L`.
#[inline]
pub(crate) fn normal_gravity_from_sin(s: f64, h: f64) -> f64 {
    let s2 = s * s;
    let gamma_0 = GAMMA_EQUATOR * (1.0 + SOMIGLIANA_K * s2) / ellipsoid_factor(s).1;
    gamma_0 * free_air_factor(s2, h)
}

/// Derivative of [`normal_gravity`] with respect to height, `d gamma / d h`, 1/s^2
/// (about `-2 g / R`, the source of the vertical-channel instability).
pub fn normal_gravity_height_gradient(lat: f64, h: f64) -> f64 {
    let s2 = lat.sin().powi(2);
    somigliana_gravity(lat) * (-2.0 / A * (1.0 + F + M_GEODETIC - 2.0 * F * s2) + 6.0 / (A * A) * h)
}

/// Normal gravity vector in NED, `g^n = [0, 0, gamma(L, h)]`.
pub fn gravity_in_nav(lat: f64, h: f64) -> Vector3<f64> {
    Vector3::new(0.0, 0.0, normal_gravity(lat, h))
}

/// Earth rotation rate resolved in NED, `omega_ie^n = omega_ie [cos L, 0, -sin L]`
/// (Groves eq. 5.41).
pub fn earth_rate_in_nav(lat: f64) -> Vector3<f64> {
    let (s, c) = lat.sin_cos();
    Vector3::new(OMEGA_IE * c, 0.0, -OMEGA_IE * s)
}

/// Transport rate (rotation of NED with respect to the Earth) resolved in NED
/// (Groves eq. 5.44):
///
/// ```text
/// omega_en^n = [ v_E / (R_E + h), -v_N / (R_N + h), -v_E tan L / (R_E + h) ]
/// ```
pub fn transport_rate_in_nav(lat: f64, h: f64, vel_in_nav: &Vector3<f64>) -> Vector3<f64> {
    let re = transverse_radius(lat) + h;
    let rn = meridian_radius(lat) + h;
    Vector3::new(
        vel_in_nav.y / re,
        -vel_in_nav.x / rn,
        -vel_in_nav.y * lat.tan() / re,
    )
}

/// Curvilinear position rates from NED velocity (Groves eq. 5.56):
///
/// ```text
/// L_dot      = v_N / (R_N + h)
/// lambda_dot = v_E / ((R_E + h) cos L)
/// h_dot      = -v_D
/// ```
///
/// Returns `[L_dot, lambda_dot, h_dot]`.
pub fn position_rates(lat: f64, h: f64, vel_in_nav: &Vector3<f64>) -> Vector3<f64> {
    let rn = meridian_radius(lat) + h;
    let re = transverse_radius(lat) + h;
    Vector3::new(
        vel_in_nav.x / rn,
        vel_in_nav.y / (re * lat.cos()),
        -vel_in_nav.z,
    )
}

/// A geodetic position on WGS-84: latitude, longitude (rad) and height above the
/// ellipsoid (m, up positive).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Geodetic {
    /// Geodetic latitude `L`, rad.
    pub lat: f64,
    /// Longitude `lambda`, rad (east positive).
    pub lon: f64,
    /// Height above the ellipsoid `h`, m (up positive; depth is `-h`).
    pub h: f64,
}

impl Geodetic {
    /// Creates a position from latitude, longitude (rad) and height (m).
    pub fn new(lat: f64, lon: f64, h: f64) -> Self {
        Self { lat, lon, h }
    }

    /// Earth-centred Earth-fixed Cartesian coordinates (Groves eq. 2.112):
    ///
    /// ```text
    /// x = (R_E + h) cos L cos lambda
    /// y = (R_E + h) cos L sin lambda
    /// z = ((1 - e^2) R_E + h) sin L
    /// ```
    pub fn to_ecef(&self) -> Vector3<f64> {
        let re = transverse_radius(self.lat);
        let (sl, cl) = self.lat.sin_cos();
        let (so, co) = self.lon.sin_cos();
        Vector3::new(
            (re + self.h) * cl * co,
            (re + self.h) * cl * so,
            ((1.0 - E2) * re + self.h) * sl,
        )
    }

    /// Inverse of [`Geodetic::to_ecef`] by fixed-point iteration on latitude
    /// (Groves eq. 2.113-2.114); converges to < 1e-12 m near the Earth's surface in a
    /// few iterations (10 are run).
    pub fn from_ecef(r: &Vector3<f64>) -> Self {
        let p = (r.x * r.x + r.y * r.y).sqrt();
        let lon = r.y.atan2(r.x);
        let mut lat = r.z.atan2(p * (1.0 - E2));
        let mut h = 0.0;
        for _ in 0..10 {
            let re = transverse_radius(lat);
            let (sl, cl) = lat.sin_cos();
            h = if cl.abs() > 1e-3 {
                p / cl - re
            } else {
                r.z / sl - (1.0 - E2) * re
            };
            lat = r.z.atan2(p * (1.0 - E2 * re / (re + h)));
        }
        Self { lat, lon, h }
    }
}

/// Rotation taking ECEF vectors to the NED frame at `(lat, lon)`, `C_e^n`
/// (Groves eq. 2.150).
pub fn nav_from_ecef(lat: f64, lon: f64) -> Matrix3<f64> {
    let (sl, cl) = lat.sin_cos();
    let (so, co) = lon.sin_cos();
    Matrix3::new(
        -sl * co,
        -sl * so,
        cl,
        -so,
        co,
        0.0,
        -cl * co,
        -cl * so,
        -sl,
    )
}

/// A local tangent frame around a reference position, converting between
/// geodetic positions and NED offsets in metres.
///
/// Three conversions are provided:
///
/// - **flat-Earth** ([`LocalTangent::flat_ned_from_geodetic`]): radii frozen at the
///   reference, `dN = (R_N(L0) + h0) dL`, `dE = (R_E(L0) + h0) cos L0 d lambda`,
///   `dD = -(h - h0)`. Error grows like `d^2 / R` (about 1.6e-7 relative per km of
///   offset at 35 deg latitude from the `dR_N/dL` term and `tan L0 * d/R` from the
///   convergence of meridians): fine for metre-level work within tens of km.
/// - **curvilinear mid-point** ([`curvilinear_offset`]): the same formula with radii,
///   cosine and height at the mid-point of the two positions. Second-order accurate
///   (errors O(d^3/R^2)); this is what should be used to express an estimated-minus-true
///   position error in metres.
/// - **exact tangent plane** ([`LocalTangent::ned_from_geodetic`]): through ECEF,
///   `dr^n = C_e^n(L0, lambda0) (r^e - r0^e)`; exact (rectilinear coordinates in
///   the tangent plane at the reference), with an exact inverse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalTangent {
    origin: Geodetic,
    origin_ecef: Vector3<f64>,
    nav_from_ecef: Matrix3<f64>,
}

impl LocalTangent {
    /// A tangent frame with its origin at `origin`.
    pub fn new(origin: Geodetic) -> Self {
        Self {
            origin,
            origin_ecef: origin.to_ecef(),
            nav_from_ecef: nav_from_ecef(origin.lat, origin.lon),
        }
    }

    /// The reference position.
    pub fn origin(&self) -> Geodetic {
        self.origin
    }

    /// Exact NED offset of `p` in the tangent plane at the origin (via ECEF).
    pub fn ned_from_geodetic(&self, p: &Geodetic) -> Vector3<f64> {
        self.nav_from_ecef * (p.to_ecef() - self.origin_ecef)
    }

    /// Exact inverse of [`LocalTangent::ned_from_geodetic`].
    pub fn geodetic_from_ned(&self, pos_in_nav: &Vector3<f64>) -> Geodetic {
        Geodetic::from_ecef(&(self.origin_ecef + self.nav_from_ecef.transpose() * pos_in_nav))
    }

    /// Flat-Earth NED offset of `p` with radii frozen at the origin (see the type docs).
    pub fn flat_ned_from_geodetic(&self, p: &Geodetic) -> Vector3<f64> {
        let o = &self.origin;
        Vector3::new(
            (meridian_radius(o.lat) + o.h) * (p.lat - o.lat),
            (transverse_radius(o.lat) + o.h) * o.lat.cos() * (p.lon - o.lon),
            -(p.h - o.h),
        )
    }

    /// Inverse of [`LocalTangent::flat_ned_from_geodetic`].
    pub fn flat_geodetic_from_ned(&self, pos_in_nav: &Vector3<f64>) -> Geodetic {
        let o = &self.origin;
        Geodetic {
            lat: o.lat + pos_in_nav.x / (meridian_radius(o.lat) + o.h),
            lon: o.lon + pos_in_nav.y / ((transverse_radius(o.lat) + o.h) * o.lat.cos()),
            h: o.h - pos_in_nav.z,
        }
    }
}

/// NED offset `to - from` in metres using the radii, cosine and height at the mid-point
/// (curvilinear, second-order accurate; see [`LocalTangent`]):
///
/// ```text
/// dN = (R_N(L_m) + h_m) (L_to - L_from)
/// dE = (R_E(L_m) + h_m) cos L_m (lambda_to - lambda_from)
/// dD = -(h_to - h_from)
/// ```
///
/// Use it for estimated-minus-true position errors: `curvilinear_offset(&truth, &est)`.
/// The longitude difference is wrapped to (-pi, pi].
pub fn curvilinear_offset(from: &Geodetic, to: &Geodetic) -> Vector3<f64> {
    let lat_m = 0.5 * (from.lat + to.lat);
    let h_m = 0.5 * (from.h + to.h);
    let dlon = fathom_core::units::wrap_pi(to.lon - from.lon);
    Vector3::new(
        (meridian_radius(lat_m) + h_m) * (to.lat - from.lat),
        (transverse_radius(lat_m) + h_m) * lat_m.cos() * dlon,
        -(to.h - from.h),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::{assert_abs_diff_eq, assert_relative_eq};
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn normal_gravity_equator_and_pole() {
        eprintln!(
            "gamma(0) = {:.12}, gamma(90) = {:.12}, R_N(0) = {:.6}, R_E(0) = {:.6}, R(90) = {:.6}",
            normal_gravity(0.0, 0.0),
            normal_gravity(FRAC_PI_2, 0.0),
            meridian_radius(0.0),
            transverse_radius(0.0),
            meridian_radius(FRAC_PI_2)
        );
        assert_relative_eq!(
            normal_gravity(0.0, 0.0),
            9.780_325_335_9,
            max_relative = 1e-9
        );
        assert_relative_eq!(
            normal_gravity(FRAC_PI_2, 0.0),
            9.832_184_937_8,
            max_relative = 1e-9
        );
        assert_relative_eq!(
            normal_gravity(-FRAC_PI_2, 0.0),
            9.832_184_937_8,
            max_relative = 1e-9
        );
        // Independent cross-check: the International Gravity Formula series
        // gamma_e (1 + 0.005 302 4 sin^2 L - 0.000 005 8 sin^2 2L), good to ~1e-5 m/s^2.
        for deg in [10.0f64, 35.0, 45.0, 70.0] {
            let l = deg.to_radians();
            let series = GAMMA_EQUATOR
                * (1.0 + 0.005_302_4 * l.sin().powi(2) - 0.000_005_8 * (2.0 * l).sin().powi(2));
            assert_abs_diff_eq!(normal_gravity(l, 0.0), series, epsilon = 2e-5);
        }
    }

    #[test]
    fn free_air_gradient_is_about_3_086e_6_per_m() {
        let g0 = normal_gravity(0.6, 0.0);
        let g100 = normal_gravity(0.6, 100.0);
        assert_abs_diff_eq!((g0 - g100) / 100.0, 3.086e-6, epsilon = 5e-9);
        // Below the surface (h < 0) gravity of this model is larger.
        assert!(normal_gravity(0.6, -50.0) > g0);
        // Analytic height gradient matches finite differences.
        let fd = (normal_gravity(0.6, 10.5) - normal_gravity(0.6, 9.5)) / 1.0;
        assert_relative_eq!(
            normal_gravity_height_gradient(0.6, 10.0),
            fd,
            max_relative = 1e-7
        );
    }

    #[test]
    fn radii_at_equator_and_pole() {
        // Equator: R_N = a (1 - e^2) = 6 335 439.327 m, R_E = a.
        assert_abs_diff_eq!(meridian_radius(0.0), 6_335_439.327_083, epsilon = 1e-3);
        assert_abs_diff_eq!(transverse_radius(0.0), A, epsilon = 1e-9);
        // Pole: R_N = R_E = a^2 / b = 6 399 593.626 m.
        assert_abs_diff_eq!(
            meridian_radius(FRAC_PI_2),
            6_399_593.625_864,
            epsilon = 1e-3
        );
        assert_abs_diff_eq!(
            transverse_radius(FRAC_PI_2),
            6_399_593.625_864,
            epsilon = 1e-3
        );
        assert_abs_diff_eq!(B, 6_356_752.314_245, epsilon = 1e-6);
    }

    #[test]
    fn earth_rate_magnitude_and_direction() {
        let w = earth_rate_in_nav(35f64.to_radians());
        assert_relative_eq!(w.norm().to_degrees() * 3600.0, 15.041, max_relative = 1e-4);
        assert!(
            w.x > 0.0 && w.z < 0.0,
            "north and up components in the north hemisphere"
        );
    }

    #[test]
    fn transport_rate_and_position_rate_signs() {
        let lat = 35f64.to_radians();
        let north = Vector3::new(5.0, 0.0, 0.0);
        let east = Vector3::new(0.0, 5.0, 0.0);
        let rates = position_rates(lat, -50.0, &north);
        assert!(rates.x > 0.0, "moving north increases latitude");
        assert_abs_diff_eq!(rates.y, 0.0);
        assert!(
            position_rates(lat, -50.0, &east).y > 0.0,
            "moving east increases longitude"
        );
        assert!(position_rates(lat, 0.0, &Vector3::new(0.0, 0.0, 1.0)).z < 0.0);
        // Going north, the NED frame rotates about -east (pitching down to stay level).
        let w = transport_rate_in_nav(lat, 0.0, &north);
        assert!(w.y < 0.0 && w.x == 0.0 && w.z == 0.0);
        // Going east, about +north and about -down (up) in the north hemisphere.
        let w = transport_rate_in_nav(lat, 0.0, &east);
        assert!(w.x > 0.0 && w.z < 0.0);
        assert_relative_eq!(w.x, 5.0 / transverse_radius(lat), max_relative = 1e-15);
    }

    #[test]
    fn ecef_roundtrip_and_tangent_frames_agree_nearby() {
        let o = Geodetic::new(35f64.to_radians(), 129f64.to_radians(), -50.0);
        let back = Geodetic::from_ecef(&o.to_ecef());
        assert_abs_diff_eq!(back.lat, o.lat, epsilon = 1e-14);
        assert_abs_diff_eq!(back.lon, o.lon, epsilon = 1e-14);
        assert_abs_diff_eq!(back.h, o.h, epsilon = 1e-8);

        let lt = LocalTangent::new(o);
        let offset = Vector3::new(1000.0, -2000.0, 10.0);
        let p = lt.geodetic_from_ned(&offset);
        assert_relative_eq!(lt.ned_from_geodetic(&p), offset, epsilon = 1e-8);
        // Flat Earth and curvilinear agree with the exact frame to a few cm at ~2 km.
        let flat = lt.flat_ned_from_geodetic(&p);
        assert_abs_diff_eq!(flat.x, offset.x, epsilon = 0.5);
        assert_abs_diff_eq!(flat.y, offset.y, epsilon = 0.5);
        let curv = curvilinear_offset(&o, &p);
        assert_abs_diff_eq!(curv.x, offset.x, epsilon = 0.5);
        assert_abs_diff_eq!(curv.y, offset.y, epsilon = 0.5);
        // The flat conversion is exactly invertible.
        let pf = lt.flat_geodetic_from_ned(&offset);
        assert_relative_eq!(lt.flat_ned_from_geodetic(&pf), offset, epsilon = 1e-8);
        // 1 arc-second of latitude is about 30.8 m at 35 deg.
        let one_sec = Geodetic::new(o.lat + (1.0f64 / 3600.0).to_radians(), o.lon, o.h);
        assert_abs_diff_eq!(curvilinear_offset(&o, &one_sec).x, 30.82, epsilon = 0.01);
    }
}

//! The range measurement model shared by the map-aided filters: body-fixed beams and
//! barometric height as inputs, the predicted range by ray casting, and the rows of
//! eq. (7)-(13) from the hit plane's normal.
//!
//! # Geometry (eq. 6-10)
//!
//! A beam of unit body direction `d` leaves the position `p` along `u = C d`
//! (`C = C_b^n`). It hits the map at `T = p + r u` on a triangle of unit normal `o`
//! (turned to face the ray, `o . u < 0`). Locally the surface is the plane
//! `o . (x - T) = 0`, so `r = o . (T - p) / o . (C d)` (eq. 6-7 of the paper).
//!
//! With the error convention of [`super`] (`x = x_hat (-) dx`: `p = p_hat - dp`,
//! `C = exp(-[psi x]) C_hat`, eq. 6) and the innovation `z - h(x_hat) = H dx + v`:
//!
//! ```text
//! dr/d(dp)  =  o^T / (o . u)                            (eq. 7 as printed: no minus)
//! dr/d(psi) = -(r / (o . u)) (o x u)^T  = -(o.(T - p) / (o . u)^2) o^T [u x]
//! ```
//!
//! Eq. (9) prints `dr/dp = -o^T / (o . C d)`: that is the derivative with respect to
//! the true position `p` (`r` shrinks as `p` moves along `u`), the opposite sign of
//! eq. (7), which is the derivative with respect to the error `dp` (eq. 6). Eq. (10) as
//! extracted, `-(o.(T - p) / (o . C d)) o^T [x C d]`, has the denominator to the first
//! power: it equals the derivative only where `o . C d = -1` (normal incidence, where
//! both vanish since `o x u = 0`). See [`super::findings`].
//!
//! The barometer gives height `h = -p_D` (eq. 11 or the exact inverse of eq. 20,
//! done by the caller): `z = h_baro`, `H = +e_3` on `dp_D`. The paper's eq. (13)
//! stacks `-h_baro` with `H = +e_3`, the derivative with respect to the true `p_D`
//! (the convention of eq. 9).

use fathom_core::{RayHit, Time};
use nalgebra::{RowSVector, Vector3};

use super::error::{MapAidedError, finite_input, positive_input};
use super::ins12::NominalNav;
use super::{ATT, N_STATES, POS};

/// One range measurement of a body-fixed beam (range finder or one lidar beam).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeBeam {
    /// Beam direction in body axes (need not be unit; not zero).
    pub dir_in_body: Vector3<f64>,
    /// Measured range, m (finite, > 0). A beam without a return is not passed in.
    pub range_m: f64,
    /// Standard deviation of the range noise, m (> 0).
    pub sigma_m: f64,
}

/// Barometric height above the map's `z = 0` (converted from pressure by the caller).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaroHeight {
    /// Height, m (up positive: `-p_D`).
    pub height_m: f64,
    /// Standard deviation, m (> 0).
    pub sigma_m: f64,
}

/// Checks the beams (finite non-zero direction, finite positive range and sigma) and
/// returns their unit body directions in `unit_dirs` (cleared first).
///
/// # Errors
/// [`MapAidedError::InvalidInput`] naming the field and the beam index, at `time`.
pub(crate) fn check_beams(
    beams: &[RangeBeam],
    time: Time,
    unit_dirs: &mut Vec<Vector3<f64>>,
) -> Result<(), MapAidedError> {
    unit_dirs.clear();
    for (i, b) in beams.iter().enumerate() {
        finite_input(
            &format!("range beam {i} dir_in_body"),
            b.dir_in_body.as_slice(),
            time,
        )?;
        let n = b.dir_in_body.norm();
        if !(n > 0.0 && n.is_finite()) {
            return Err(MapAidedError::InvalidInput {
                what: "range beam dir_in_body (norm)".into(),
                index: i,
                value: n,
                expected: "finite and > 0",
                time,
            });
        }
        positive_input("range beam range_m", i, b.range_m, time)?;
        positive_input("range beam sigma_m", i, b.sigma_m, time)?;
        unit_dirs.push(b.dir_in_body / n);
    }
    Ok(())
}

/// Checks a barometer reading (finite height, sigma > 0).
///
/// # Errors
/// [`MapAidedError::InvalidInput`] at `time`.
pub(crate) fn check_baro(baro: &BaroHeight, time: Time) -> Result<(), MapAidedError> {
    finite_input("baro height_m", &[baro.height_m], time)?;
    positive_input("baro sigma_m", 0, baro.sigma_m, time)?;
    Ok(())
}

/// Checks every input of a map-aided update at filter time `time`: the nominal
/// state, the beams (their unit body directions into `unit_dirs`) and the barometer.
///
/// # Errors
/// [`MapAidedError::InvalidInput`] naming the first bad value, at `time`.
pub(crate) fn check_update_inputs(
    nominal: &NominalNav,
    beams: &[RangeBeam],
    baro: Option<&BaroHeight>,
    time: Time,
    unit_dirs: &mut Vec<Vector3<f64>>,
) -> Result<(), MapAidedError> {
    nominal.check(time)?;
    check_beams(beams, time, unit_dirs)?;
    if let Some(b) = baro {
        check_baro(b, time)?;
    }
    Ok(())
}

/// A predicted beam: the ray-cast hit seen from a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamGeometry {
    /// Predicted range `r`, m.
    pub range: f64,
    /// Unit ray direction `u = C d`, NED.
    pub dir_in_nav: Vector3<f64>,
    /// Unit normal `o` of the hit surface, facing the ray (`o . u <= 0`).
    pub normal_in_nav: Vector3<f64>,
}

impl BeamGeometry {
    /// The geometry of a hit along the unit direction `dir_in_nav`.
    pub fn from_hit(hit: &RayHit, dir_in_nav: Vector3<f64>) -> Self {
        Self {
            range: hit.range,
            dir_in_nav,
            normal_in_nav: hit.normal_in_nav,
        }
    }

    /// `cos` of the incidence angle, `-o . u` (1 head-on, 0 grazing).
    pub fn cos_incidence(&self) -> f64 {
        -self.normal_in_nav.dot(&self.dir_in_nav)
    }

    /// The rows of eq. (7) and (10) in the error convention (module docs):
    /// `(dr/d(dp), dr/d(psi))`. The caller keeps `cos_incidence` away from 0.
    pub fn rows(&self) -> (Vector3<f64>, Vector3<f64>) {
        let o = &self.normal_in_nav;
        let u = &self.dir_in_nav;
        let q = o.dot(u);
        let d_pos = o / q;
        let d_att = o.cross(u) * (-self.range / q);
        (d_pos, d_att)
    }

    /// The full 12-state row `H_RNG` of eq. (8).
    pub fn row12(&self) -> RowSVector<f64, N_STATES> {
        let (dp, da) = self.rows();
        let mut h = RowSVector::<f64, N_STATES>::zeros();
        for k in 0..3 {
            h[POS + k] = dp[k];
            h[ATT + k] = da[k];
        }
        h
    }
}

/// The barometer row: `d h / d(dp_D) = +1` (height `h = -p_D`, `p_D = p_hat_D - dp_D`).
pub fn baro_row12() -> RowSVector<f64, N_STATES> {
    let mut h = RowSVector::<f64, N_STATES>::zeros();
    h[POS + 2] = 1.0;
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::ErrorVector12;
    use crate::map_aided::ins12::NominalNav;
    use crate::map_aided::test_support::Planes;
    use fathom_core::RayCaster;
    use nalgebra::UnitQuaternion;
    use proptest::prelude::*;

    fn range_at(
        caster: &dyn RayCaster,
        nav: &NominalNav,
        d_body: &Vector3<f64>,
        dx: &ErrorVector12,
    ) -> f64 {
        let t = nav.corrected(dx);
        caster
            .cast(&t.pos_in_nav, &(t.nav_from_body * d_body), f64::INFINITY)
            .map_or(f64::NAN, |h| h.range)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// Acceptance (Jacobians): the GREKF range rows for position (eq. 7) and
        /// attitude (eq. 10, corrected) equal the central finite differences of the ray
        /// cast against a random plane from a random pose, perturbed through the error
        /// definition (`p = p_hat - dp`, `C = exp(-[psi x]) C_hat`). Step 1e-6 m / rad;
        /// tolerance `1e-6 (1 + |row|)` (ranges up to ~100 m at incidence <= 75 deg:
        /// truncation ~ r h^2 / cos^3 < 1e-9, rounding ~ 1e-16 r / h = 1e-8).
        #[test]
        fn range_rows_match_finite_differences(
            normal in prop::array::uniform3(-1.0f64..1.0),
            offset in 1.0f64..50.0,
            pos in prop::array::uniform3(-20.0f64..20.0),
            att in prop::array::uniform3(-3.0f64..3.0),
            dir in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let n = Vector3::from(normal);
            prop_assume!(n.norm() > 0.2);
            let d_body = Vector3::from(dir);
            prop_assume!(d_body.norm() > 0.2);
            let n = n.normalize();
            let d_body = d_body.normalize();
            let p = Vector3::from(pos);
            // the plane n . x = n . p + offset lies `offset` ahead of the pose along n
            let caster = Planes::new(vec![(n, n.dot(&p) + offset)]);
            let q = UnitQuaternion::from_euler_angles(att[0], att[1], att[2]);
            let u = q * d_body;
            // the beam must hit at a usable incidence
            prop_assume!(u.dot(&n) > 0.26);
            let nav = NominalNav {
                pos_in_nav: p,
                vel_in_nav: Vector3::zeros(),
                nav_from_body: q,
                accel_bias_in_body: Vector3::zeros(),
            };
            let hit = caster.cast(&p, &u, f64::INFINITY).unwrap();
            let geom = BeamGeometry::from_hit(&hit, u);
            prop_assert!((geom.range - offset / u.dot(&n)).abs() < 1e-9 * geom.range);
            let row = geom.row12();
            let h = 1e-6;
            for j in 0..N_STATES {
                let mut e = ErrorVector12::zeros();
                e[j] = h;
                let fd = (range_at(&caster, &nav, &d_body, &e)
                    - range_at(&caster, &nav, &d_body, &(-e)))
                    / (2.0 * h);
                let tol = 1e-6 * (1.0 + row[j].abs());
                prop_assert!((fd - row[j]).abs() < tol, "state {j}: fd {fd} row {}", row[j]);
            }
            // the paper's eq. (9) is the derivative with respect to the TRUE position:
            // the opposite sign of the error-state row
            let o = -n; // the hit normal faces the ray
            let eq9 = -o / o.dot(&u);
            for k in 0..3 {
                prop_assert!((eq9[k] + row[POS + k]).abs() < 1e-12);
            }
        }

        /// The barometer row: height `-p_D` of the corrected pose, central differences.
        #[test]
        fn baro_row_matches_finite_differences(pd in -100.0f64..0.0) {
            let nav = NominalNav {
                pos_in_nav: Vector3::new(3.0, 4.0, pd),
                vel_in_nav: Vector3::zeros(),
                nav_from_body: UnitQuaternion::identity(),
                accel_bias_in_body: Vector3::zeros(),
            };
            let row = baro_row12();
            for j in 0..N_STATES {
                let mut e = ErrorVector12::zeros();
                e[j] = 1e-4;
                let fd = (-nav.corrected(&e).pos_in_nav.z + nav.corrected(&(-e)).pos_in_nav.z) / 2e-4;
                prop_assert!((fd - row[j]).abs() < 1e-9);
            }
        }
    }

    /// The paper's eq. (10) as extracted agrees with the derivative at normal incidence
    /// only; away from it the two differ by the factor `1 / (o . u)`.
    #[test]
    fn eq10_as_printed_holds_only_at_normal_incidence() {
        let o = Vector3::new(-1.0, 0.0, 0.0);
        for (angle, agree) in [(0.0f64, true), (0.6f64, false)] {
            let u = Vector3::new(angle.cos(), angle.sin(), 0.0);
            let r = 10.0 / angle.cos();
            let g = BeamGeometry {
                range: r,
                dir_in_nav: u,
                normal_in_nav: o,
            };
            let (_, ours) = g.rows();
            // eq. (10) printed: -(o.(T-p) / (o.u)) o^T [u x] = -(r) (o x u)^T ... with
            // o.(T-p) = r (o.u)
            let printed = o.cross(&u) * (-(r * o.dot(&u)) / o.dot(&u));
            assert_eq!((ours - printed).norm() < 1e-12, agree, "{angle}");
        }
    }

    #[test]
    fn bad_beams_are_typed_errors_with_the_time() {
        let good = RangeBeam {
            dir_in_body: Vector3::x(),
            range_m: 5.0,
            sigma_m: 0.05,
        };
        let mut dirs = Vec::new();
        check_beams(&[good, good], 1.0, &mut dirs).unwrap();
        assert_eq!(dirs.len(), 2);
        for (bad, what) in [
            (
                RangeBeam {
                    range_m: f64::NAN,
                    ..good
                },
                "range_m",
            ),
            (
                RangeBeam {
                    range_m: -1.0,
                    ..good
                },
                "range_m",
            ),
            (
                RangeBeam {
                    sigma_m: -0.1,
                    ..good
                },
                "sigma_m",
            ),
            (
                RangeBeam {
                    sigma_m: 0.0,
                    ..good
                },
                "sigma_m",
            ),
            (
                RangeBeam {
                    dir_in_body: Vector3::zeros(),
                    ..good
                },
                "dir_in_body",
            ),
        ] {
            let e = check_beams(&[good, bad], 4.5, &mut dirs).unwrap_err();
            match &e {
                MapAidedError::InvalidInput {
                    what: w,
                    index,
                    time,
                    ..
                } => {
                    assert!(w.contains(what) && *index == 1, "{e}");
                    assert_eq!(*time, 4.5);
                }
                other => panic!("{other}"),
            }
        }
        assert!(
            check_baro(
                &BaroHeight {
                    height_m: 3.0,
                    sigma_m: -1.0
                },
                0.0
            )
            .is_err()
        );
        assert!(
            check_baro(
                &BaroHeight {
                    height_m: f64::NAN,
                    sigma_m: 1.0
                },
                0.0
            )
            .is_err()
        );
    }
}

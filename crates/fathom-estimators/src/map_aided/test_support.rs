//! Test-only maps: analytic infinite planes as a [`RayCaster`] (no map crate), the
//! corridor (two walls and a floor) and the corner (two walls at a right angle).

use fathom_core::raycast::MIN_RANGE;
use fathom_core::{Material, RayCaster, RayHit};
use nalgebra::{UnitQuaternion, Vector3};

use super::NominalNav;

/// A level nominal state at `pos` with heading `yaw`, at rest, without bias.
pub(crate) fn nominal(pos: Vector3<f64>, yaw: f64) -> NominalNav {
    NominalNav {
        pos_in_nav: pos,
        vel_in_nav: Vector3::zeros(),
        nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        accel_bias_in_body: Vector3::zeros(),
    }
}

/// Six horizontal beams 60 deg apart and one down (the paper's buildings sensors).
pub(crate) fn seven_dirs() -> Vec<Vector3<f64>> {
    (0..6)
        .map(|k| {
            let a = k as f64 * std::f64::consts::FRAC_PI_3 + 0.3;
            Vector3::new(a.cos(), a.sin(), 0.0)
        })
        .chain([Vector3::z()])
        .collect()
}

/// Infinite planes `n . x = c` (unit `n`); the closest hit wins.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Planes {
    planes: Vec<(Vector3<f64>, f64)>,
}

impl Planes {
    /// Planes `(n, c)`: `n . x = c`, `n` normalized here.
    pub(crate) fn new(planes: Vec<(Vector3<f64>, f64)>) -> Self {
        Self {
            planes: planes
                .into_iter()
                .map(|(n, c)| {
                    let k = n.norm();
                    (n / k, c / k)
                })
                .collect(),
        }
    }

    /// A corridor along north: walls at east = -half_width and +half_width, the floor
    /// at down = 0.
    pub(crate) fn corridor(half_width: f64) -> Self {
        Self::new(vec![
            (Vector3::y(), half_width),
            (Vector3::y(), -half_width),
            (Vector3::z(), 0.0),
        ])
    }

    /// A corner: walls at north = 0 and east = 0 (the room is north < 0, east < 0...
    /// any side works), the floor at down = 0.
    pub(crate) fn corner() -> Self {
        Self::new(vec![
            (Vector3::x(), 0.0),
            (Vector3::y(), 0.0),
            (Vector3::z(), 0.0),
        ])
    }
}

impl RayCaster for Planes {
    fn cast(&self, o: &Vector3<f64>, d: &Vector3<f64>, max_range: f64) -> Option<RayHit> {
        let d = fathom_core::Ray::new(*o, *d, max_range).unit_dir()?;
        let mut best: Option<RayHit> = None;
        for (i, (n, c)) in self.planes.iter().enumerate() {
            let nd = n.dot(&d);
            if nd == 0.0 {
                continue;
            }
            let t = (c - n.dot(o)) / nd;
            if t > MIN_RANGE && t <= max_range && best.is_none_or(|b| t < b.range) {
                best = Some(RayHit {
                    range: t,
                    triangle: i as u32,
                    material: Material::Opaque,
                    normal_in_nav: if nd < 0.0 { *n } else { -n },
                });
            }
        }
        best
    }
}

#[test]
fn planes_cast_the_closest_facing_hit() {
    let c = Planes::corridor(5.0);
    let o = Vector3::new(0.0, 1.0, -2.0);
    let h = c.cast(&o, &Vector3::y(), 100.0).unwrap();
    assert!((h.range - 4.0).abs() < 1e-12);
    assert!(h.normal_in_nav.dot(&Vector3::y()) < 0.0);
    let h = c.cast(&o, &Vector3::z(), 100.0).unwrap();
    assert!((h.range - 2.0).abs() < 1e-12);
    assert!(c.cast(&o, &Vector3::x(), 100.0).is_none());
    assert!(c.cast(&o, &-Vector3::z(), 100.0).is_none());
    assert!(c.cast(&o, &Vector3::y(), 3.0).is_none());
}

//! Primitive shapes added to a [`MeshBuilder`], in local NED metres (`z` down, so a
//! height `h` above the ground `z = 0` is `z = -h`): ground plane, axis-aligned and
//! rotated boxes with a material per face, faceted vertical cylinders, slabs.
//! Triangles are wound counter-clockwise seen from outside (outward normals), which
//! the ray caster does not need but exporters and viewers do.

use fathom_core::Material;
use nalgebra::{Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use crate::MeshBuilder;
use crate::error::{MapError, check_finite, check_positive};

/// A material per box face, named by the face's outward direction in the box's own
/// frame (for an axis-aligned box: north `+x`, south `-x`, east `+y`, west `-y`, top
/// `-z`, bottom `+z`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FaceMaterials {
    /// `+x` face.
    pub north: Material,
    /// `-x` face.
    pub south: Material,
    /// `+y` face.
    pub east: Material,
    /// `-y` face.
    pub west: Material,
    /// `-z` face (the roof).
    pub top: Material,
    /// `+z` face.
    pub bottom: Material,
}

impl FaceMaterials {
    /// Every face of `m`.
    pub fn all(m: Material) -> Self {
        Self {
            north: m,
            south: m,
            east: m,
            west: m,
            top: m,
            bottom: m,
        }
    }
}

impl Default for FaceMaterials {
    fn default() -> Self {
        Self::all(Material::Opaque)
    }
}

/// The horizontal square `[north_min, north_max] x [east_min, east_max]` at depth
/// `z_down` (two triangles, normal up).
///
/// # Errors
/// [`MapError::InvalidParameter`] for a non-finite or empty extent.
pub fn ground_plane(
    b: &mut MeshBuilder,
    north: [f64; 2],
    east: [f64; 2],
    z_down: f64,
    material: Material,
) -> Result<(), MapError> {
    check_interval("ground.north", north)?;
    check_interval("ground.east", east)?;
    check_finite("ground.z_down", z_down)?;
    let p = |n, e| Vector3::new(n, e, z_down);
    // counter-clockwise seen from above (-z): north, then west
    b.quad_at(
        [
            p(north[0], east[0]),
            p(north[0], east[1]),
            p(north[1], east[1]),
            p(north[1], east[0]),
        ],
        material,
    );
    Ok(())
}

fn check_interval(field: &str, v: [f64; 2]) -> Result<(), MapError> {
    check_finite(&format!("{field}[0]"), v[0])?;
    check_finite(&format!("{field}[1]"), v[1])?;
    if v[1] > v[0] {
        Ok(())
    } else {
        Err(MapError::InvalidParameter {
            field: format!("{field}[1]"),
            value: v[1],
            reason: "must be greater than the lower bound",
        })
    }
}

/// The box `[min, max]` (NED, m), axis-aligned, a material per face.
///
/// # Errors
/// [`MapError::InvalidParameter`] for a non-finite or empty extent.
pub fn aabb_box(
    b: &mut MeshBuilder,
    min: Vector3<f64>,
    max: Vector3<f64>,
    faces: &FaceMaterials,
) -> Result<(), MapError> {
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        check_interval(&format!("box.{axis}"), [min[k], max[k]])?;
    }
    let center = (min + max) / 2.0;
    let half = (max - min) / 2.0;
    add_box(b, &center, &half, &Rotation3::identity(), faces);
    Ok(())
}

/// The box of half extents `half` about `center`, turned by `nav_from_box` (NED, m),
/// a material per face (faces named in the box frame).
///
/// # Errors
/// [`MapError::InvalidParameter`] for a non-finite center or rotation, or a half
/// extent that is not finite and > 0.
pub fn rotated_box(
    b: &mut MeshBuilder,
    center: Vector3<f64>,
    half: Vector3<f64>,
    nav_from_box: &Rotation3<f64>,
    faces: &FaceMaterials,
) -> Result<(), MapError> {
    for k in 0..3 {
        check_finite(&format!("box.center[{k}]"), center[k])?;
        check_positive(&format!("box.half[{k}]"), half[k])?;
    }
    for (i, &r) in nav_from_box.matrix().iter().enumerate() {
        check_finite(&format!("box.rotation[{i}]"), r)?;
    }
    add_box(b, &center, &half, nav_from_box, faces);
    Ok(())
}

fn add_box(
    b: &mut MeshBuilder,
    center: &Vector3<f64>,
    half: &Vector3<f64>,
    rot: &Rotation3<f64>,
    faces: &FaceMaterials,
) {
    let corner = |sx: f64, sy: f64, sz: f64| {
        center + rot * Vector3::new(sx * half.x, sy * half.y, sz * half.z)
    };
    // each face: its four corners in order around it
    let quads = [
        (
            faces.north,
            [(1., -1., -1.), (1., -1., 1.), (1., 1., 1.), (1., 1., -1.)],
        ),
        (
            faces.south,
            [
                (-1., -1., -1.),
                (-1., 1., -1.),
                (-1., 1., 1.),
                (-1., -1., 1.),
            ],
        ),
        (
            faces.east,
            [(-1., 1., -1.), (1., 1., -1.), (1., 1., 1.), (-1., 1., 1.)],
        ),
        (
            faces.west,
            [
                (-1., -1., -1.),
                (-1., -1., 1.),
                (1., -1., 1.),
                (1., -1., -1.),
            ],
        ),
        (
            faces.top,
            [
                (-1., -1., -1.),
                (1., -1., -1.),
                (1., 1., -1.),
                (-1., 1., -1.),
            ],
        ),
        (
            faces.bottom,
            [(-1., -1., 1.), (-1., 1., 1.), (1., 1., 1.), (1., -1., 1.)],
        ),
    ];
    for (m, [p, q, r, s]) in quads {
        // listed inward-wound above; reversed to wind outward
        b.quad_at([s, r, q, p].map(|(x, y, z)| corner(x, y, z)), m);
    }
}

/// A horizontal slab (a deck, a floor): north and east extents, its top at depth
/// `z_top` and `thickness` metres thick (downwards), one material.
///
/// # Errors
/// As [`aabb_box`], and a thickness that is not finite and > 0.
pub fn slab(
    b: &mut MeshBuilder,
    north: [f64; 2],
    east: [f64; 2],
    z_top: f64,
    thickness: f64,
    material: Material,
) -> Result<(), MapError> {
    check_positive("slab.thickness", thickness)?;
    check_finite("slab.z_top", z_top)?;
    aabb_box(
        b,
        Vector3::new(north[0], east[0], z_top),
        Vector3::new(north[1], east[1], z_top + thickness),
        &FaceMaterials::all(material),
    )
}

/// A vertical cylinder (a pier) of `radius` about `(north, east)`, from depth `z_top`
/// down to `z_bottom`, approximated by a prism of `facets` sides (>= 3) whose corners
/// lie on the circle; with `caps`, closed at both ends.
///
/// # Errors
/// [`MapError::InvalidParameter`] for non-finite values, `radius <= 0`,
/// `z_bottom <= z_top` or fewer than 3 (or more than 4096) facets.
pub fn vertical_cylinder(
    b: &mut MeshBuilder,
    center_ne: [f64; 2],
    radius: f64,
    z_top: f64,
    z_bottom: f64,
    facets: usize,
    caps: bool,
    material: Material,
) -> Result<(), MapError> {
    check_finite("cylinder.north", center_ne[0])?;
    check_finite("cylinder.east", center_ne[1])?;
    check_positive("cylinder.radius", radius)?;
    check_interval("cylinder.z", [z_top, z_bottom])?;
    if !(3..=4096).contains(&facets) {
        return Err(MapError::InvalidParameter {
            field: "cylinder.facets".into(),
            value: facets as f64,
            reason: "must be between 3 and 4096",
        });
    }
    let ring = |z: f64| -> Vec<Vector3<f64>> {
        (0..facets)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / facets as f64;
                Vector3::new(
                    center_ne[0] + radius * a.cos(),
                    center_ne[1] + radius * a.sin(),
                    z,
                )
            })
            .collect()
    };
    let (top, bottom) = (ring(z_top), ring(z_bottom));
    for k in 0..facets {
        let j = (k + 1) % facets;
        b.quad_at([top[j], bottom[j], bottom[k], top[k]], material);
    }
    if caps {
        let c_top = Vector3::new(center_ne[0], center_ne[1], z_top);
        let c_bottom = Vector3::new(center_ne[0], center_ne[1], z_bottom);
        for k in 0..facets {
            let j = (k + 1) % facets;
            b.triangle_at(c_top, top[j], top[k], material);
            b.triangle_at(c_bottom, bottom[k], bottom[j], material);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BruteForceCaster, TriMesh};
    use approx::assert_relative_eq;
    use fathom_core::RayCaster;

    fn build(f: impl FnOnce(&mut MeshBuilder)) -> TriMesh {
        let mut b = MeshBuilder::new();
        f(&mut b);
        let (mesh, report) = b.build().unwrap();
        assert_eq!(report.degenerate_skipped + report.duplicate_skipped, 0);
        mesh
    }

    #[test]
    fn boxes_are_closed_with_outward_normals_and_face_materials() {
        let faces = FaceMaterials {
            east: Material::Glass,
            ..FaceMaterials::default()
        };
        let mesh = build(|b| {
            aabb_box(
                b,
                Vector3::new(0., 0., -10.),
                Vector3::new(2., 4., 0.),
                &faces,
            )
            .unwrap()
        });
        let center = Vector3::new(1.0, 2.0, -5.0);
        for i in 0..mesh.len() {
            let [a, b, c] = mesh.corners(i);
            let n = (b - a).cross(&(c - a));
            assert!(n.dot(&(a - center)) > 0.0, "triangle {i} faces inwards");
        }
        let cast = BruteForceCaster::new(&mesh);
        // from the east looking west: the glass east face at y = 4
        let hit = cast
            .cast(
                &Vector3::new(1.0, 10.0, -5.0),
                &Vector3::new(0.0, -1.0, 0.0),
                100.0,
            )
            .unwrap();
        assert_relative_eq!(hit.range, 6.0);
        assert_eq!(hit.material, Material::Glass);
        assert_relative_eq!(hit.normal_in_nav, Vector3::new(0.0, 1.0, 0.0));
        assert!(
            aabb_box(
                &mut MeshBuilder::new(),
                Vector3::zeros(),
                Vector3::zeros(),
                &faces
            )
            .is_err()
        );
    }

    #[test]
    fn rotated_box_cylinder_slab_and_ground() {
        let yaw45 = Rotation3::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_4);
        let mesh = build(|b| {
            rotated_box(
                b,
                Vector3::new(10., 0., -1.),
                Vector3::new(1., 1., 1.),
                &yaw45,
                &FaceMaterials::default(),
            )
            .unwrap();
            vertical_cylinder(b, [0.0, 10.0], 1.0, -5.0, 0.0, 64, true, Material::Opaque).unwrap();
            slab(b, [-5.0, 5.0], [-5.0, 5.0], -10.0, 1.0, Material::Opaque).unwrap();
            ground_plane(b, [-100.0, 100.0], [-100.0, 100.0], 0.0, Material::Opaque).unwrap();
        });
        let cast = BruteForceCaster::new(&mesh);
        // the rotated box's corner points south-west: along north from the origin at
        // 1 m height it is hit at 10 - sqrt(2)
        let hit = cast
            .cast(&Vector3::new(0., 0., -1.), &Vector3::new(1., 0., 0.), 50.0)
            .unwrap();
        assert_relative_eq!(hit.range, 10.0 - 2f64.sqrt(), epsilon = 1e-12);
        // the cylinder along east: between the inscribed and the true radius
        let hit = cast
            .cast(&Vector3::new(0., 0., -1.), &Vector3::new(0., 1., 0.), 50.0)
            .unwrap();
        assert!(
            hit.range >= 9.0 - 1e-12
                && hit.range <= 9.0 + 1.0 - (std::f64::consts::PI / 64.0).cos()
        );
        // up: the slab's bottom at 9 m; down: the ground
        let up = cast
            .cast(&Vector3::new(0., 0., -1.), &Vector3::new(0., 0., -1.), 50.0)
            .unwrap();
        assert_relative_eq!(up.range, 8.0, epsilon = 1e-12);
        let down = cast
            .cast(&Vector3::new(0., 0., -1.), &Vector3::new(0., 0., 1.), 50.0)
            .unwrap();
        assert_relative_eq!(down.range, 1.0, epsilon = 1e-12);
        let mut b = MeshBuilder::new();
        assert!(
            vertical_cylinder(
                &mut b,
                [0.0, 0.0],
                1.0,
                0.0,
                -1.0,
                8,
                false,
                Material::Opaque
            )
            .is_err()
        );
        assert!(
            vertical_cylinder(
                &mut b,
                [0.0, 0.0],
                1.0,
                -1.0,
                0.0,
                2,
                false,
                Material::Opaque
            )
            .is_err()
        );
        assert!(ground_plane(&mut b, [0.0, f64::NAN], [0.0, 1.0], 0.0, Material::Opaque).is_err());
    }
}

//! The two worlds of the urban experiment (spec D, "World"), their dimensions as
//! checked parameters with defaults: `bridge` (a deck over two rows of cylindrical
//! piers, the flight path between the rows under the deck) and `buildings` (a block
//! of tall buildings, some facades glass, around a square flight path). The ground is
//! the plane `z = 0` (NED, so heights are negative `z`).

use fathom_core::Material;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::{MapError, check_feature, check_positive};
use crate::primitives::{FaceMaterials, aabb_box, ground_plane, slab, vertical_cylinder};
use crate::{MeshBuilder, TriMesh};

/// Most piers per row a bridge may have (a bound against absurd parameters).
pub const MAX_PIERS_PER_ROW: usize = 10_000;

/// Dimensions of the `bridge` world (m). The deck runs north from `north = 0`; the
/// pier rows stand at `east = +-pier_row_offset_m`; the path runs north at `east = 0`.
///
/// Also the `urban` scenario's `[scenarios.world.bridge]` table (every key required,
/// no other key): with the `schemars` feature it has a JSON schema.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct BridgeParams {
    /// Deck length along north. Default 200.
    ///
    /// Unit: m. Range: > 0.
    pub deck_length_m: f64,
    /// Deck width along east. Default 20.
    ///
    /// Unit: m. Range: > 0.
    pub deck_width_m: f64,
    /// Height of the deck's underside above the ground. Default 10.
    ///
    /// Unit: m. Range: > `path_height_m`.
    pub deck_height_m: f64,
    /// Deck thickness. Default 1.5.
    ///
    /// Unit: m. Range: > 0.
    pub deck_thickness_m: f64,
    /// Pier diameter (spec: ~2). Default 2.
    ///
    /// Unit: m. Range: > 0.
    pub pier_diameter_m: f64,
    /// Pier spacing along north, the first pier at half a spacing (spec: ~20). Default
    /// 20.
    ///
    /// Unit: m. Range: > `pier_diameter_m`.
    pub pier_spacing_m: f64,
    /// East offset of each pier row from the path (rows at `+-` this). Default 6.
    ///
    /// Unit: m. Range: > the pier radius.
    pub pier_row_offset_m: f64,
    /// Facets per pier (prism sides). Default 24.
    ///
    /// Range: 3 … 4096.
    pub pier_facets: usize,
    /// Ground margin around the deck. Default 100.
    ///
    /// Unit: m. Range: > 0.
    pub ground_margin_m: f64,
    /// Flight height of the path under the deck. Default 5.
    ///
    /// Unit: m. Range: > 0.
    pub path_height_m: f64,
}

impl Default for BridgeParams {
    fn default() -> Self {
        Self {
            deck_length_m: 200.0,
            deck_width_m: 20.0,
            deck_height_m: 10.0,
            deck_thickness_m: 1.5,
            pier_diameter_m: 2.0,
            pier_spacing_m: 20.0,
            pier_row_offset_m: 6.0,
            pier_facets: 24,
            ground_margin_m: 100.0,
            path_height_m: 5.0,
        }
    }
}

/// Checked [`BridgeParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bridge {
    p: BridgeParams,
}

impl BridgeParams {
    /// Checks the dimensions: all finite and at least [`MIN_FEATURE_M`](crate::error::MIN_FEATURE_M), the path under the deck, the piers
    /// clear of the path and of each other, at most [`MAX_PIERS_PER_ROW`] per row.
    ///
    /// # Errors
    /// [`MapError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<Bridge, MapError> {
        let p = self;
        for (f, v) in [
            ("deck_length_m", p.deck_length_m),
            ("deck_width_m", p.deck_width_m),
            ("deck_height_m", p.deck_height_m),
            ("deck_thickness_m", p.deck_thickness_m),
            ("pier_diameter_m", p.pier_diameter_m),
            ("pier_spacing_m", p.pier_spacing_m),
            ("pier_row_offset_m", p.pier_row_offset_m),
            ("ground_margin_m", p.ground_margin_m),
            ("path_height_m", p.path_height_m),
        ] {
            check_feature(f, v)?;
        }
        let bad = |field: &str, value: f64, reason| {
            Err(MapError::InvalidParameter {
                field: field.into(),
                value,
                reason,
            })
        };
        if p.path_height_m >= p.deck_height_m {
            return bad(
                "path_height_m",
                p.path_height_m,
                "must be below deck_height_m",
            );
        }
        if p.pier_row_offset_m <= p.pier_diameter_m / 2.0 {
            return bad(
                "pier_row_offset_m",
                p.pier_row_offset_m,
                "must exceed the pier radius (the path runs between the rows)",
            );
        }
        if p.pier_spacing_m <= p.pier_diameter_m {
            return bad(
                "pier_spacing_m",
                p.pier_spacing_m,
                "must exceed pier_diameter_m",
            );
        }
        if p.deck_length_m / p.pier_spacing_m > MAX_PIERS_PER_ROW as f64 {
            return bad(
                "pier_spacing_m",
                p.pier_spacing_m,
                "gives too many piers per row",
            );
        }
        if !(3..=4096).contains(&p.pier_facets) {
            return bad(
                "pier_facets",
                p.pier_facets as f64,
                "must be between 3 and 4096",
            );
        }
        if p.deck_length_m.max(p.ground_margin_m) > 1e6 {
            return bad(
                "deck_length_m",
                p.deck_length_m,
                "deck and margin must be <= 1e6 m",
            );
        }
        Ok(Bridge { p: *p })
    }
}

impl Bridge {
    /// The parameters.
    pub fn params(&self) -> &BridgeParams {
        &self.p
    }

    /// North positions of the piers of one row.
    pub fn pier_norths(&self) -> Vec<f64> {
        let p = &self.p;
        let n = (p.deck_length_m / p.pier_spacing_m).floor() as usize;
        (0..n)
            .map(|k| (k as f64 + 0.5) * p.pier_spacing_m)
            .collect()
    }

    /// Start and end of the path (NED): along north under the deck at `east = 0`.
    pub fn path_in_nav(&self) -> [Vector3<f64>; 2] {
        let z = -self.p.path_height_m;
        [
            Vector3::new(0.0, 0.0, z),
            Vector3::new(self.p.deck_length_m, 0.0, z),
        ]
    }

    /// The mesh: ground, deck, piers (all opaque).
    ///
    /// # Errors
    /// Only if the checked dimensions still give an invalid primitive (not expected).
    pub fn mesh(&self) -> Result<TriMesh, MapError> {
        let p = &self.p;
        let m = Material::Opaque;
        let mut b = MeshBuilder::new();
        let g = p.ground_margin_m;
        ground_plane(&mut b, [-g, p.deck_length_m + g], [-g, g], 0.0, m)?;
        let half_w = p.deck_width_m / 2.0;
        slab(
            &mut b,
            [0.0, p.deck_length_m],
            [-half_w, half_w],
            -(p.deck_height_m + p.deck_thickness_m),
            p.deck_thickness_m,
            m,
        )?;
        for north in self.pier_norths() {
            for east in [-p.pier_row_offset_m, p.pier_row_offset_m] {
                vertical_cylinder(
                    &mut b,
                    [north, east],
                    p.pier_diameter_m / 2.0,
                    -p.deck_height_m,
                    0.0,
                    p.pier_facets,
                    false,
                    m,
                )?;
            }
        }
        Ok(b.build()?.0)
    }
}

/// Dimensions of the `buildings` world (m). The path is the square with corners
/// `(0, 0)`, `(side, 0)`, `(side, side)`, `(0, side)` (north, east) at `path_height_m`;
/// a central building fills the square less `clearance_m` on each side, and four outer
/// buildings (`outer_depth_m` deep) stand `clearance_m` outside each leg.
///
/// Also the `urban` scenario's `[scenarios.world.buildings]` table (every key
/// required, no other key): with the `schemars` feature it has a JSON schema.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schemars", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct BuildingsParams {
    /// Side of the square path (spec: ~100). Default 100.
    ///
    /// Unit: m. Range: > 2 `clearance_m`.
    pub path_side_m: f64,
    /// Flight height of the path (spec: ~20). Default 20.
    ///
    /// Unit: m. Range: > 0.
    pub path_height_m: f64,
    /// Horizontal distance from the path to every facade. Default 15.
    ///
    /// Unit: m. Range: > 0.
    pub clearance_m: f64,
    /// Depth of the outer buildings (away from the path). Default 30.
    ///
    /// Unit: m. Range: > 0.
    pub outer_depth_m: f64,
    /// Height of the central building. Default 80.
    ///
    /// Unit: m. Range: > 0.
    pub central_height_m: f64,
    /// Heights of the outer buildings north, east, south, west of the square (spec:
    /// 40-80). Default 60, 70, 40, 50.
    ///
    /// Unit: m. Range: each > 0.
    pub outer_heights_m: [f64; 4],
    /// Whether the facades marked glass are glass (else all opaque). Glass: the
    /// central building's north and east facades, the east building's facade and the
    /// south building's facade facing the path. Default true.
    pub glass_facades: bool,
    /// Ground margin around the outer buildings. Default 100.
    ///
    /// Unit: m. Range: > 0.
    pub ground_margin_m: f64,
    /// Buildings per outer side, separated by streets of `street_width_m` (cross
    /// streets give a range sensor along-track features; the gaps open the sky).
    /// Default 1: one continuous building per side.
    ///
    /// Range: 1 … 100.
    pub outer_buildings_per_side: usize,
    /// Width of the streets between the outer buildings of a side. Default 10.
    ///
    /// Unit: m. Range: > 0, the streets shorter than a side.
    pub street_width_m: f64,
}

impl Default for BuildingsParams {
    fn default() -> Self {
        Self {
            path_side_m: 100.0,
            path_height_m: 20.0,
            clearance_m: 15.0,
            outer_depth_m: 30.0,
            central_height_m: 80.0,
            outer_heights_m: [60.0, 70.0, 40.0, 50.0],
            glass_facades: true,
            ground_margin_m: 100.0,
            outer_buildings_per_side: 1,
            street_width_m: 10.0,
        }
    }
}

/// Checked [`BuildingsParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Buildings {
    p: BuildingsParams,
}

impl BuildingsParams {
    /// Checks the dimensions: all finite and at least [`MIN_FEATURE_M`](crate::error::MIN_FEATURE_M), a central building that fits
    /// (`2 clearance < side`), everything within 1e6 m.
    ///
    /// # Errors
    /// [`MapError::InvalidParameter`] naming the field.
    pub fn check(&self) -> Result<Buildings, MapError> {
        let p = self;
        for (f, v) in [
            ("path_side_m", p.path_side_m),
            ("path_height_m", p.path_height_m),
            ("clearance_m", p.clearance_m),
            ("outer_depth_m", p.outer_depth_m),
            ("central_height_m", p.central_height_m),
            ("ground_margin_m", p.ground_margin_m),
        ] {
            check_feature(f, v)?;
            if v > 1e6 {
                return Err(MapError::InvalidParameter {
                    field: f.into(),
                    value: v,
                    reason: "must be <= 1e6 m",
                });
            }
        }
        for (i, &h) in p.outer_heights_m.iter().enumerate() {
            check_positive(&format!("outer_heights_m[{i}]"), h)?;
        }
        if !(1..=100).contains(&p.outer_buildings_per_side) {
            return Err(MapError::InvalidParameter {
                field: "outer_buildings_per_side".into(),
                value: p.outer_buildings_per_side as f64,
                reason: "must be between 1 and 100",
            });
        }
        check_positive("street_width_m", p.street_width_m)?;
        let side_length = p.path_side_m + 2.0 * p.clearance_m;
        let streets = (p.outer_buildings_per_side - 1) as f64 * p.street_width_m;
        if streets >= side_length {
            return Err(MapError::InvalidParameter {
                field: "street_width_m".into(),
                value: p.street_width_m,
                reason: "the streets leave no room for the outer buildings",
            });
        }
        if 2.0 * p.clearance_m >= p.path_side_m {
            return Err(MapError::InvalidParameter {
                field: "clearance_m".into(),
                value: p.clearance_m,
                reason: "must be less than half of path_side_m (the central building must fit)",
            });
        }
        Ok(Buildings { p: *p })
    }
}

impl Buildings {
    /// The parameters.
    pub fn params(&self) -> &BuildingsParams {
        &self.p
    }

    /// The path's corners (NED), in flight order.
    pub fn path_corners_in_nav(&self) -> [Vector3<f64>; 4] {
        let (s, z) = (self.p.path_side_m, -self.p.path_height_m);
        [
            Vector3::new(0.0, 0.0, z),
            Vector3::new(s, 0.0, z),
            Vector3::new(s, s, z),
            Vector3::new(0.0, s, z),
        ]
    }

    /// The mesh: ground, the central and the four outer buildings.
    ///
    /// # Errors
    /// Only if the checked dimensions still give an invalid primitive (not expected).
    pub fn mesh(&self) -> Result<TriMesh, MapError> {
        let p = &self.p;
        let (s, c, d) = (p.path_side_m, p.clearance_m, p.outer_depth_m);
        let glass = if p.glass_facades {
            Material::Glass
        } else {
            Material::Opaque
        };
        let opaque = FaceMaterials::default();
        let mut b = MeshBuilder::new();
        let g = c + d + p.ground_margin_m;
        ground_plane(&mut b, [-g, s + g], [-g, s + g], 0.0, Material::Opaque)?;
        let block = |b: &mut MeshBuilder, n: [f64; 2], e: [f64; 2], h: f64, f: FaceMaterials| {
            aabb_box(
                b,
                Vector3::new(n[0], e[0], -h),
                Vector3::new(n[1], e[1], 0.0),
                &f,
            )
        };
        let central = FaceMaterials {
            north: glass,
            east: glass,
            ..opaque
        };
        block(&mut b, [c, s - c], [c, s - c], p.central_height_m, central)?;
        let [h_n, h_e, h_s, h_w] = p.outer_heights_m;
        // each outer side split into `outer_buildings_per_side` buildings along it
        let n = p.outer_buildings_per_side;
        let w = p.street_width_m;
        let pieces = |from: f64, to: f64| -> Vec<[f64; 2]> {
            let len = (to - from - (n - 1) as f64 * w) / n as f64;
            (0..n)
                .map(|k| {
                    let a = from + k as f64 * (len + w);
                    [a, a + len]
                })
                .collect()
        };
        for e in pieces(-c, s + c) {
            block(&mut b, [s + c, s + c + d], e, h_n, opaque)?;
        }
        let east = FaceMaterials {
            west: glass,
            ..opaque
        };
        for nn in pieces(0.0, s) {
            block(&mut b, nn, [s + c, s + c + d], h_e, east)?;
        }
        let south = FaceMaterials {
            north: glass,
            ..opaque
        };
        for e in pieces(-c, s + c) {
            block(&mut b, [-c - d, -c], e, h_s, south)?;
        }
        for nn in pieces(0.0, s) {
            block(&mut b, nn, [-c - d, -c], h_w, opaque)?;
        }
        Ok(b.build()?.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BvhCaster;
    use approx::assert_relative_eq;
    use fathom_core::RayCaster;

    #[test]
    fn bridge_path_runs_between_the_piers_under_the_deck() {
        let bridge = BridgeParams::default().check().unwrap();
        let mesh = bridge.mesh().unwrap();
        let cast = BvhCaster::new(&mesh);
        let [start, end] = bridge.path_in_nav();
        // the path itself is free, and the deck is above it, the ground below
        assert!(cast.line_of_sight(&start, &end));
        let up = cast
            .cast(&Vector3::new(50.0, 0.0, -5.0), &-Vector3::z(), 100.0)
            .unwrap();
        assert_relative_eq!(up.range, 5.0, epsilon = 1e-9);
        // looking east from a pier's north: its surface at the row offset minus the radius
        let n = bridge.pier_norths()[2];
        let hit = cast
            .cast(&Vector3::new(n, 0.0, -5.0), &Vector3::y(), 100.0)
            .unwrap();
        assert_relative_eq!(hit.range, 5.0, epsilon = 1e-9); // facet corner on the axis
        assert_eq!(bridge.pier_norths().len(), 10);
        for bad in [
            BridgeParams {
                path_height_m: 12.0,
                ..BridgeParams::default()
            },
            BridgeParams {
                pier_row_offset_m: 0.5,
                ..BridgeParams::default()
            },
            BridgeParams {
                pier_spacing_m: 1e-6,
                ..BridgeParams::default()
            },
            BridgeParams {
                deck_width_m: f64::NAN,
                ..BridgeParams::default()
            },
            BridgeParams {
                pier_facets: 2,
                ..BridgeParams::default()
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn buildings_block_the_view_with_glass_facades() {
        let city = BuildingsParams::default().check().unwrap();
        let mesh = city.mesh().unwrap();
        let cast = BvhCaster::new(&mesh);
        let [a, b, _, _] = city.path_corners_in_nav();
        assert!(cast.line_of_sight(&a, &b));
        // from the first leg (east = 0) looking east: the central building's west
        // facade (opaque) at the clearance; looking west: the west building
        let mid = (a + b) / 2.0;
        let hit = cast.cast(&mid, &Vector3::y(), 500.0).unwrap();
        assert_relative_eq!(hit.range, 15.0, epsilon = 1e-9);
        assert_eq!(hit.material, Material::Opaque);
        let hit = cast.cast(&mid, &-Vector3::y(), 500.0).unwrap();
        assert_relative_eq!(hit.range, 15.0, epsilon = 1e-9);
        // from the second leg (north = side) looking south: the central building's
        // north facade, glass
        let hit = cast
            .cast(&Vector3::new(100.0, 50.0, -20.0), &-Vector3::x(), 500.0)
            .unwrap();
        assert_eq!(hit.material, Material::Glass);
        assert!(
            BuildingsParams {
                clearance_m: 50.0,
                ..BuildingsParams::default()
            }
            .check()
            .is_err()
        );
        let all_opaque = BuildingsParams {
            glass_facades: false,
            ..BuildingsParams::default()
        };
        let mesh = all_opaque.check().unwrap().mesh().unwrap();
        assert!(mesh.materials().iter().all(|&m| m == Material::Opaque));
    }

    /// Outer sides split by cross streets: a beam along a street passes the ring,
    /// one beside it hits a building; one building per side is the default mesh.
    #[test]
    fn outer_buildings_split_by_streets() {
        let one = BuildingsParams::default();
        assert_eq!(
            BuildingsParams {
                outer_buildings_per_side: 1,
                street_width_m: 3.0,
                ..one
            }
            .check()
            .unwrap()
            .mesh()
            .unwrap(),
            one.check().unwrap().mesh().unwrap()
        );
        let three = BuildingsParams {
            outer_buildings_per_side: 3,
            ..one
        }
        .check()
        .unwrap();
        let mesh = three.mesh().unwrap();
        assert!(mesh.len() > one.check().unwrap().mesh().unwrap().len());
        let cast = BvhCaster::new(&mesh);
        // the west side (north 0..100, west of the path) in pieces of (100 - 20) / 3
        let len = 80.0 / 3.0;
        let street = len + 5.0;
        let from = Vector3::new(street, 0.0, -20.0);
        assert!(cast.cast(&from, &-Vector3::y(), 40.0).is_none());
        let hit = cast
            .cast(&Vector3::new(len / 2.0, 0.0, -20.0), &-Vector3::y(), 40.0)
            .unwrap();
        assert_relative_eq!(hit.range, 15.0, epsilon = 1e-9);
        for bad in [
            BuildingsParams {
                outer_buildings_per_side: 0,
                ..one
            },
            BuildingsParams {
                outer_buildings_per_side: 20,
                street_width_m: 10.0,
                ..one
            },
            BuildingsParams {
                street_width_m: -1.0,
                ..one
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
    }
}

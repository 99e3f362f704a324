//! The world of fathom's map-aided navigation: a static triangle mesh in local NED
//! metres with a [`Material`](fathom_core::Material) per triangle, read from real
//! files (Wavefront OBJ, STL) or built from primitives and presets, and closest-hit
//! ray casting on it (the [`fathom_core::RayCaster`] trait, implemented by the
//! [`BvhCaster`] and by the [`BruteForceCaster`] test oracle).
//!
//! Readers take bytes or a reader (no file is opened here); the import settings say
//! how the file's axes, unit and origin map into local NED metres. Malformed files
//! are errors naming the line or face, never panics.
//!
//! ```
//! use fathom_core::{Material, RayCaster};
//! use fathom_map::{BvhCaster, presets::BuildingsParams};
//! use nalgebra::Vector3;
//!
//! let city = BuildingsParams::default().check().unwrap().mesh().unwrap();
//! let caster = BvhCaster::new(&city);
//! // straight down from 20 m above the ground: the ground plane (opaque) at 20 m
//! let hit = caster
//!     .cast(&Vector3::new(-10.0, -10.0, -20.0), &Vector3::new(0.0, 0.0, 1.0), 100.0)
//!     .unwrap();
//! assert!((hit.range - 20.0).abs() < 1e-9);
//! assert_eq!(hit.material, Material::Opaque);
//! ```
//!
//! ---
//!
#![doc = include_str!("../README.md")]
#![deny(missing_docs)]

pub mod brute;
pub mod bvh;
pub mod error;
pub mod import;
pub mod mesh;
pub mod obj;
pub mod presets;
pub mod primitives;
pub mod stl;
mod triangle;

pub use brute::BruteForceCaster;
pub use bvh::{BvhBuild, BvhCaster};
pub use error::{FileError, MapError};
pub use import::{AxisConvention, ImportReport, ImportSettings, MaterialTable};
pub use mesh::{MeshBuilder, MeshReport, TriMesh};

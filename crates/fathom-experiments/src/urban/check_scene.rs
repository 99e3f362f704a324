//! The `[[scenarios]]` entries of an `urban` scenario checked: name, ranging, the
//! preset world's dimensions or the user's mesh file settings, and the waypoints.

use super::scenario::AxesToml;
use super::scenario::BridgeToml;
use super::scenario::BuildingsToml;
use super::scenario::PresetWorld;
use super::scenario::Ranging;
use super::scenario::SceneToml;
use crate::common::check_case_name;
use fathom_map::AxisConvention;
use fathom_map::ImportSettings;
use fathom_map::presets::Bridge;
use fathom_map::presets::BridgeParams;
use fathom_map::presets::Buildings;
use fathom_map::presets::BuildingsParams;
use fathom_sim::SimError;
use fathom_sim::scenario::require_positive;

/// Where a scenario's world comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum WorldSource {
    /// The bridge preset.
    Bridge(Bridge),
    /// The buildings preset.
    Buildings(Buildings),
    /// A user's OBJ or STL file.
    File {
        /// The path as written in the scenario.
        path: String,
        /// How to read it into NED metres.
        settings: ImportSettings,
    },
}

/// One checked `[[scenarios]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneSpec {
    /// Name.
    pub name: String,
    /// The range sensor.
    pub ranging: Ranging,
    /// The world.
    pub world: WorldSource,
    /// Waypoints in the world's frame (`None`: the preset's path).
    pub waypoints: Option<Vec<[f64; 3]>>,
    /// Start height above ground of a preset path, m.
    pub start_height: f64,
    /// The paper's scenario this one is (name and preset world match).
    pub paper: Option<PresetWorld>,
}

pub(super) fn model_err(file: &str, key: &str, e: impl std::fmt::Display) -> SimError {
    SimError::invalid(file, key, e.to_string())
}

fn bridge(file: &str, key: &str, b: &BridgeToml) -> Result<Bridge, SimError> {
    BridgeParams {
        deck_length_m: b.deck_length_m,
        deck_width_m: b.deck_width_m,
        deck_height_m: b.deck_height_m,
        deck_thickness_m: b.deck_thickness_m,
        pier_diameter_m: b.pier_diameter_m,
        pier_spacing_m: b.pier_spacing_m,
        pier_row_offset_m: b.pier_row_offset_m,
        pier_facets: b.pier_facets,
        ground_margin_m: b.ground_margin_m,
        path_height_m: b.path_height_m,
    }
    .check()
    .map_err(|e| model_err(file, key, e))
}

fn buildings(file: &str, key: &str, b: &BuildingsToml) -> Result<Buildings, SimError> {
    BuildingsParams {
        path_side_m: b.path_side_m,
        path_height_m: b.path_height_m,
        clearance_m: b.clearance_m,
        outer_depth_m: b.outer_depth_m,
        central_height_m: b.central_height_m,
        outer_heights_m: b.outer_heights_m,
        glass_facades: b.glass_facades,
        ground_margin_m: b.ground_margin_m,
        outer_buildings_per_side: b.outer_buildings_per_side,
        street_width_m: b.street_width_m,
    }
    .check()
    .map_err(|e| model_err(file, key, e))
}

pub(super) fn scene(
    file: &str,
    i: usize,
    s: &SceneToml,
    earlier: &[SceneSpec],
) -> Result<SceneSpec, SimError> {
    let key = |k: &str| format!("scenarios[{i}].{k}");
    check_case_name(file, i, &s.name, earlier.iter().map(|e| e.name.as_str())).map_err(|_| {
        SimError::invalid(
            file,
            key("name"),
            format!(
                "must be a non-empty, unique name of [A-Za-z0-9_-], got {:?}",
                s.name
            ),
        )
    })?;
    let w = &s.world;
    let world = match (&w.preset, &w.file) {
        (Some(_), Some(_)) | (None, None) => {
            return Err(SimError::invalid(
                file,
                key("world"),
                "give exactly one of `preset` and `file`",
            ));
        }
        (Some(PresetWorld::Bridge), None) => WorldSource::Bridge(bridge(
            file,
            &key("world.bridge"),
            &w.bridge.unwrap_or_else(default_bridge),
        )?),
        (Some(PresetWorld::Buildings), None) => WorldSource::Buildings(buildings(
            file,
            &key("world.buildings"),
            &w.buildings.unwrap_or_else(default_buildings),
        )?),
        (None, Some(path)) => {
            if path.trim().is_empty() {
                return Err(SimError::invalid(
                    file,
                    key("world.file"),
                    "must not be empty",
                ));
            }
            let mut settings = ImportSettings::default();
            if let Some(axes) = w.axes {
                settings.axes = match axes {
                    AxesToml::Ned => AxisConvention::Ned,
                    AxesToml::EnuZUp => AxisConvention::EnuZUp,
                    AxesToml::YUpRightHanded => AxisConvention::YUpRightHanded,
                    AxesToml::YUpLeftHanded => AxisConvention::YUpLeftHanded,
                };
            }
            if let Some(scale) = w.scale {
                settings.scale = require_positive(file, &key("world.scale"), scale)?;
            }
            if let Some(o) = w.origin_offset {
                for (k, v) in o.iter().enumerate() {
                    if !v.is_finite() {
                        return Err(SimError::invalid(
                            file,
                            key(&format!("world.origin_offset[{k}]")),
                            format!("must be finite, got {v}"),
                        ));
                    }
                }
                settings.origin_offset = o;
            }
            WorldSource::File {
                path: path.clone(),
                settings,
            }
        }
    };
    let preset_only = [
        ("axes", w.axes.is_some()),
        ("scale", w.scale.is_some()),
        ("origin_offset", w.origin_offset.is_some()),
    ];
    if w.preset.is_some()
        && let Some((k, _)) = preset_only.iter().find(|(_, set)| *set)
    {
        return Err(SimError::invalid(
            file,
            key(&format!("world.{k}")),
            "applies to a `file` world only",
        ));
    }
    let start_height = require_positive(file, &key("path.start_height_m"), s.path.start_height_m)?;
    if let Some(wp) = &s.path.waypoints {
        if wp.len() < 2 {
            return Err(SimError::invalid(
                file,
                key("path.waypoints"),
                format!("needs at least 2 waypoints, got {}", wp.len()),
            ));
        }
        for (k, p) in wp.iter().enumerate() {
            if p.iter().any(|v| !v.is_finite() || v.abs() > 1e9) {
                return Err(SimError::invalid(
                    file,
                    key(&format!("path.waypoints[{k}]")),
                    format!("coordinates must be finite and within 1e9, got {p:?}"),
                ));
            }
        }
    } else if matches!(world, WorldSource::File { .. }) {
        return Err(SimError::invalid(
            file,
            key("path.waypoints"),
            "a `file` world needs waypoints (in the file's frame)",
        ));
    }
    let paper = match (&world, s.name.as_str()) {
        (WorldSource::Bridge(_), "bridge") => Some(PresetWorld::Bridge),
        (WorldSource::Buildings(_), "buildings") => Some(PresetWorld::Buildings),
        _ => None,
    };
    Ok(SceneSpec {
        name: s.name.clone(),
        ranging: s.ranging,
        world,
        waypoints: s.path.waypoints.clone(),
        start_height,
        paper,
    })
}

fn default_bridge() -> BridgeToml {
    let p = BridgeParams::default();
    BridgeToml {
        deck_length_m: p.deck_length_m,
        deck_width_m: p.deck_width_m,
        deck_height_m: p.deck_height_m,
        deck_thickness_m: p.deck_thickness_m,
        pier_diameter_m: p.pier_diameter_m,
        pier_spacing_m: p.pier_spacing_m,
        pier_row_offset_m: p.pier_row_offset_m,
        pier_facets: p.pier_facets,
        ground_margin_m: p.ground_margin_m,
        path_height_m: p.path_height_m,
    }
}

fn default_buildings() -> BuildingsToml {
    let p = BuildingsParams::default();
    BuildingsToml {
        path_side_m: p.path_side_m,
        path_height_m: p.path_height_m,
        clearance_m: p.clearance_m,
        outer_depth_m: p.outer_depth_m,
        central_height_m: p.central_height_m,
        outer_heights_m: p.outer_heights_m,
        glass_facades: p.glass_facades,
        ground_margin_m: p.ground_margin_m,
        outer_buildings_per_side: p.outer_buildings_per_side,
        street_width_m: p.street_width_m,
    }
}

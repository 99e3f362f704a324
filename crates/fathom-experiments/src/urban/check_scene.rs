//! The `[[scenarios]]` entries of an `urban` scenario checked: name, ranging, the
//! preset world's dimensions or the user's mesh file settings, and the waypoints.

use super::scenario::AxesToml;
use super::scenario::PresetWorld;
use super::scenario::Ranging;
use super::scenario::SceneToml;
use crate::common::check_case_name;
use fathom_core::echo::echo;
use fathom_map::AxisConvention;
use fathom_map::ImportSettings;
use fathom_map::presets::Bridge;
use fathom_map::presets::BridgeParams;
use fathom_map::presets::Buildings;
use fathom_map::presets::BuildingsParams;
use fathom_sim::SimError;
use fathom_sim::parameter_key::parameter_invalid;
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

fn bridge(file: &str, key: &str, b: &BridgeParams) -> Result<Bridge, SimError> {
    b.check().map_err(|e| parameter_invalid(file, key, b, &e))
}

fn buildings(file: &str, key: &str, b: &BuildingsParams) -> Result<Buildings, SimError> {
    b.check().map_err(|e| parameter_invalid(file, key, b, &e))
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
                "must be a non-empty, unique name of [A-Za-z0-9_-], got \"{}\"",
                echo(&s.name)
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
            &w.bridge.unwrap_or_default(),
        )?),
        (Some(PresetWorld::Buildings), None) => WorldSource::Buildings(buildings(
            file,
            &key("world.buildings"),
            &w.buildings.unwrap_or_default(),
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

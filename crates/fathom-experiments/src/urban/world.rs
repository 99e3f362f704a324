//! What the `urban` runs share, built once: each scenario's world (a preset or the
//! user's OBJ / STL file read into NED metres), its BVH caster, the path checked
//! against the mesh, and the GNSS receiver with its satellites.
//!
//! A user's world is refused with a [`SimError::Invalid`] naming the scenario key
//! and the mesh file when the file cannot be read or has no faces, when a waypoint
//! lies outside the mesh's plan bounds (or below it), or when a leg between two
//! waypoints passes through the mesh.

use fathom_core::RayCaster;
use fathom_core::echo::echo_file;
use fathom_map::{BvhCaster, TriMesh};
use fathom_sensors::gnss::{GnssParams, GnssReceiver};
use fathom_traj::quadrotor::{Path, PathParams, Waypoint};
use nalgebra::Vector3;

use super::check::{Checked, SceneSpec, WorldSource};
use fathom_sim::SimError;
use fathom_sim::experiment::Environment;

/// How far the `bridge` preset's path starts south of the deck and ends north of it
/// (at most 80 % of the ground margin), m: the flight rests and converges on GPS/INS
/// in open sky, flies under the deck (the GNSS shadow), and comes out the other side.
pub const BRIDGE_OPEN_SKY_M: f64 = 40.0;

/// One prepared scenario.
pub struct PreparedScene {
    /// The world.
    pub mesh: TriMesh,
    /// Its caster (truth sensors and estimators alike).
    pub caster: BvhCaster,
    /// The checked path.
    pub path: Path,
    /// The waypoints in NED.
    pub waypoints: Vec<Vector3<f64>>,
    /// Where the world came from, for the report.
    pub source: String,
}

/// What all runs share.
pub struct Prepared {
    /// The checked scenario.
    pub checked: Checked,
    /// The scenarios, in the file's order.
    pub scenes: Vec<PreparedScene>,
    /// The GNSS receiver with the chosen satellites.
    pub receiver: GnssReceiver,
    /// Whether run 0 keeps its scans and satellites and the analysis writes
    /// `scene.html` (`fathom run --no-scene`: no).
    pub scene_page: bool,
}

/// Builds everything the runs share.
///
/// # Errors
/// [`SimError::Invalid`] for a world file that cannot be used or a path that does
/// not fit its world (module docs); [`SimError::Model`] for library failures.
pub fn prepare(checked: Checked, env: &Environment) -> Result<Prepared, SimError> {
    let mut scenes = Vec::with_capacity(checked.scenes.len());
    for (i, spec) in checked.scenes.iter().enumerate() {
        scenes.push(prepare_scene(&checked, i, spec, env)?);
    }
    let receiver = choose_satellites(&checked)?;
    Ok(Prepared {
        checked,
        scenes,
        receiver,
        scene_page: env.scene_page,
    })
}

/// The `n` satellites of the nominal constellation highest above the mask at `t = 0`;
/// fewer than `n` above it is an error naming `gnss.satellites` (never a silent
/// truncation).
fn choose_satellites(checked: &Checked) -> Result<GnssReceiver, SimError> {
    let all = checked
        .gnss
        .params
        .check()
        .map_err(|e| SimError::model("GNSS receiver", e))?;
    let frame = all.frame();
    let origin = frame.origin_ecef();
    let mask = checked.gnss.params.elevation_mask_deg.to_radians().sin();
    let mut up: Vec<(usize, f64)> = all
        .satellites_at(0.0)
        .iter()
        .enumerate()
        .map(|(i, s)| {
            (
                i,
                -(frame.ned_from_ecef() * (s.pos_ecef - origin).normalize()).z,
            )
        })
        .filter(|(_, sin_el)| *sin_el >= mask)
        .collect();
    up.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let wanted = checked.gnss.satellites;
    if up.len() < wanted {
        let g = &checked.gnss.params;
        return Err(SimError::invalid(
            &checked.file,
            "gnss.satellites",
            format!(
                "{wanted} satellites requested, but only {} of the nominal constellation are \
                 above the {} deg mask at t = 0 (gnss.epoch_offset_s = {} s, gnss.lat_deg = {}, \
                 gnss.lon_deg = {}): \
                 request at most {}, or choose another epoch_offset_s",
                up.len(),
                g.elevation_mask_deg,
                g.epoch_offset_s,
                g.frame.lat_deg,
                g.frame.lon_deg,
                up.len()
            ),
        ));
    }
    up.truncate(wanted);
    up.sort_by_key(|(i, _)| *i);
    let params = GnssParams {
        satellites: up
            .iter()
            .map(|(i, _)| checked.gnss.params.satellites[*i].clone())
            .collect(),
        ..checked.gnss.params.clone()
    };
    params
        .check()
        .map_err(|e| SimError::model("GNSS receiver", e))
}

fn read_world(
    checked: &Checked,
    key: &str,
    path: &str,
    settings: &fathom_map::ImportSettings,
    env: &Environment,
) -> Result<(TriMesh, String), SimError> {
    fathom_replay::world_file::read_mesh_file(&checked.file, key, path, &env.base_dir, settings)
}

fn prepare_scene(
    checked: &Checked,
    index: usize,
    spec: &SceneSpec,
    env: &Environment,
) -> Result<PreparedScene, SimError> {
    let key = |k: &str| format!("scenarios[{index}].{k}");
    let model = |e: fathom_map::MapError| SimError::model(format!("world of `{}`", spec.name), e);
    let (mesh, source, preset_path) = match &spec.world {
        WorldSource::Bridge(b) => {
            let p = b.params();
            // open sky south of the deck, under it, open sky north of it
            let (z0, z1) = (-spec.start_height, -p.path_height_m);
            let open = BRIDGE_OPEN_SKY_M.min(0.8 * p.ground_margin_m);
            let path = vec![
                Vector3::new(-open, 0.0, z0),
                Vector3::new(-open, 0.0, z1),
                Vector3::new(p.deck_length_m + open, 0.0, z1),
            ];
            (
                b.mesh().map_err(model)?,
                "preset `bridge`".to_string(),
                path,
            )
        }
        WorldSource::Buildings(b) => {
            let p = b.params();
            // rest and climb outside the block's south-west corner, then the square
            let (s, z0, z1) = (p.path_side_m, -spec.start_height, -p.path_height_m);
            let out = -(p.clearance_m * 2.0);
            let path = vec![
                Vector3::new(out, out, z0),
                Vector3::new(out, out, z1),
                Vector3::new(0.0, 0.0, z1),
                Vector3::new(s, 0.0, z1),
                Vector3::new(s, s, z1),
                Vector3::new(0.0, s, z1),
                Vector3::new(0.0, 0.0, z1),
            ];
            (
                b.mesh().map_err(model)?,
                "preset `buildings`".to_string(),
                path,
            )
        }
        WorldSource::File { path, settings } => {
            let (mesh, source) = read_world(checked, &key("world.file"), path, settings, env)?;
            (mesh, source, Vec::new())
        }
    };
    let (waypoints, file_name) = match (&spec.waypoints, &spec.world) {
        (Some(w), WorldSource::File { path, settings }) => (
            w.iter().map(|p| settings.to_ned(p)).collect::<Vec<_>>(),
            format!("`{}`", echo_file(path)),
        ),
        (Some(w), _) => (
            w.iter().map(|p| Vector3::new(p[0], p[1], p[2])).collect(),
            source.clone(),
        ),
        (None, _) => (preset_path, source.clone()),
    };
    let caster = BvhCaster::new(&mesh);
    check_path(
        checked,
        &key("path.waypoints"),
        &file_name,
        &mesh,
        &caster,
        &waypoints,
    )?;
    let (cruise, vertical, hover) = checked.speeds;
    let turn_at = matches!(spec.world, WorldSource::Buildings(_)) && spec.waypoints.is_none();
    let mut params = PathParams::new(
        waypoints
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let w = Waypoint::new(*p, if i == 0 { 0.0 } else { hover });
                match i {
                    0 => w.with_yaw(0.0),
                    // the buildings flight turns in place at the far corner (spec D)
                    4 if turn_at => w.with_yaw(std::f64::consts::FRAC_PI_2),
                    _ => w,
                }
            })
            .collect(),
    );
    params.cruise_speed_mps = cruise;
    params.vertical_speed_mps = vertical;
    let path = params
        .check()
        .map_err(|e| SimError::invalid(&checked.file, key("path"), e.to_string()))?;
    Ok(PreparedScene {
        mesh,
        caster,
        path,
        waypoints,
        source,
    })
}

/// Every waypoint inside the mesh's plan bounds and not below it; every leg free of
/// the mesh.
fn check_path(
    checked: &Checked,
    key: &str,
    file: &str,
    mesh: &TriMesh,
    caster: &BvhCaster,
    waypoints: &[Vector3<f64>],
) -> Result<(), SimError> {
    let Some((lo, hi)) = mesh.bounds() else {
        return Err(SimError::invalid(
            &checked.file,
            key,
            format!("{file} has no faces"),
        ));
    };
    for (k, w) in waypoints.iter().enumerate() {
        let inside = w.x >= lo.x && w.x <= hi.x && w.y >= lo.y && w.y <= hi.y && w.z <= hi.z;
        if !inside {
            return Err(SimError::invalid(
                &checked.file,
                format!("{key}[{k}]"),
                format!(
                    "waypoint at NED ({:.2}, {:.2}, {:.2}) m lies outside the bounds of {file} \
                     (north {:.2} ... {:.2}, east {:.2} ... {:.2}, down at most {:.2})",
                    w.x, w.y, w.z, lo.x, hi.x, lo.y, hi.y, hi.z
                ),
            ));
        }
    }
    for (k, pair) in waypoints.windows(2).enumerate() {
        let d = pair[1] - pair[0];
        let len = d.norm();
        if len <= 0.0 {
            continue;
        }
        if let Some(hit) = caster.cast(&pair[0], &d, len) {
            let p = pair[0] + d / len * hit.range;
            return Err(SimError::invalid(
                &checked.file,
                format!("{key}[{}]", k + 1),
                format!(
                    "the leg from waypoint {k} to waypoint {} passes through {file} at NED \
                     ({:.2}, {:.2}, {:.2}) m (triangle {})",
                    k + 1,
                    p.x,
                    p.y,
                    p.z,
                    hit.triangle
                ),
            ));
        }
    }
    Ok(())
}

//! The `gnss-ins` replay with a world as the scene page (`scene.html`,
//! [`fathom_report::scene`]): the world moved into the replay's frame, the reference
//! path (the truth when the log has it, else EKF2's track) and every method's
//! estimate at the recording instants, the map-aided methods with their mode. The
//! log's scans and satellites are not drawn.

use fathom_map::TriMesh;
use fathom_report::scene::{MethodTrack, Scene, ScenePage, scene_html};
use fathom_sim::SimError;

use super::GnssInsReplay;
use super::run::moved_mesh;
use crate::scene_mesh::mesh_of;

fn f32x3(p: &[f64; 3]) -> [f32; 3] {
    [p[0] as f32, p[1] as f32, p[2] as f32]
}

/// The page of a replay with a world (`mesh` in its file's frame; `title` names
/// the output).
///
/// # Errors
/// [`SimError::Model`] for a world the move refuses; [`SimError::Output`] for a page
/// the scene checks refuse.
pub(super) fn page(r: &GnssInsReplay, mesh: &TriMesh, title: &str) -> Result<String, SimError> {
    let shift = r.world_shift.unwrap_or([0.0; 3]);
    let world = moved_mesh(mesh, shift)?;
    let (reference, which) = match &r.truth {
        Some(t) => (t, "the truth"),
        None => (&r.ekf2, "EKF2's estimate (no truth in the log)"),
    };
    let truth: Vec<[f32; 3]> = reference.iter().map(f32x3).collect();
    let methods = r
        .methods
        .iter()
        .map(|m| {
            let t = &m.trace;
            let positions = t
                .pos_in_nav
                .iter()
                .zip(&truth)
                .map(|(p, g)| {
                    // a diverged (non-finite) estimate is drawn at the reference
                    if p.iter().all(|v| v.is_finite()) {
                        f32x3(p)
                    } else {
                        *g
                    }
                })
                .collect();
            let (mode, mode_names) = match &t.map_mode {
                Some(modes) => (
                    modes.iter().map(|&b| u8::from(b)).collect(),
                    vec!["GPS/INS".to_string(), "map-aided".to_string()],
                ),
                None => (vec![0; truth.len()], vec![t.name().to_string()]),
            };
            MethodTrack {
                name: t.name().to_string(),
                positions,
                mode,
                mode_names,
            }
        })
        .collect();
    let page = ScenePage {
        title: title.to_string(),
        note: format!(
            "the reference path is {which}; estimates at EKF2's rows; scans and \
             satellites not drawn"
        ),
        scenes: vec![Scene {
            name: "replay".into(),
            mesh: mesh_of(&world),
            times: r.times.clone(),
            truth,
            methods,
            scans: Vec::new(),
            sky: Vec::new(),
        }],
    };
    scene_html(&page).map_err(|e| SimError::Output {
        path: "scene.html".into(),
        reason: e.to_string(),
    })
}

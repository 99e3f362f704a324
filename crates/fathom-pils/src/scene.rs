//! A simulator session as the 3D scene page (`scene.html`): the scene's world, the
//! truth, the solutions that came over the link (and the offline reference, when it
//! ran) with the method's mode, the scans and the satellites' lines of sight, drawn
//! by [`fathom_report::scene`] as for `fathom run`.

use std::collections::BTreeMap;

use fathom_experiments::urban::scene_page::{
    f32x3, mesh_of, page_scans, page_sky, scans, sky, track,
};
use fathom_report::scene::{Scene, ScenePage, scene_html};

use crate::PilsError;
use crate::epoch::Solution;
use crate::source::SensorSource;
use crate::urban_flight::{UrbanFlight, UrbanRun};

/// The page of a session: `tracks` are `(label, solutions by step)`, drawn at the
/// steps every one of them solved.
///
/// # Errors
/// [`PilsError::Model`] when no step was solved or the page is refused.
pub fn scene_page(
    fl: &UrbanFlight,
    run: &UrbanRun,
    tracks: &[(&str, &BTreeMap<u64, Solution>)],
) -> Result<String, PilsError> {
    let steps: Vec<u64> = tracks
        .first()
        .map(|(_, sols)| {
            sols.keys()
                .copied()
                .filter(|k| tracks.iter().all(|(_, o)| o.contains_key(k)))
                .collect()
        })
        .unwrap_or_default();
    let Some(&first) = steps.first() else {
        return Err(PilsError::model("scene page", "no solution to draw"));
    };
    let truth: Vec<[f32; 3]> = steps
        .iter()
        .map(|&k| f32x3(&run.truth(k).pos_in_nav.into()))
        .collect();
    let methods = tracks
        .iter()
        .map(|(label, sols)| {
            let est: Vec<[f64; 3]> = steps.iter().map(|k| sols[k].pos_in_nav.into()).collect();
            let mode: Vec<bool> = steps.iter().map(|k| sols[k].map_aided).collect();
            let mut t = track(fl.method, &est, &mode, &truth);
            t.name = format!("{label} {}", fl.method.name());
            t
        })
        .collect();
    let all_truth: Vec<_> = (0..run.steps()).map(|k| *run.truth(k)).collect();
    let from = run.truth(first).time;
    let world = &fl.prep.scenes[fl.scene];
    let scene = Scene {
        name: fl.scene_name().to_string(),
        mesh: mesh_of(&world.mesh),
        times: steps.iter().map(|&k| run.truth(k).time).collect(),
        truth,
        methods,
        scans: page_scans(&scans(&all_truth, run.sensed(), from)),
        sky: page_sky(&sky(&fl.prep, &all_truth, run.sensed(), from)),
    };
    let page = ScenePage {
        title: format!(
            "fathom pils: {} / {}, run {}",
            fl.scene_name(),
            fl.method.name(),
            fl.run
        ),
        note: "the solutions that came over the link; paths, scans and satellites thinned \
               for display (pils.json uses every solution)"
            .into(),
        scenes: vec![scene],
    };
    scene_html(&page).map_err(|e| PilsError::model("scene page", e))
}

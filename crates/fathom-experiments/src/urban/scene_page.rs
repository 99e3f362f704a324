//! Run 0 as the scene page (`scene.html`): the scans and satellites of its flight
//! thinned while it runs ([`scans`], [`sky`]), then the worlds, the true and
//! estimated paths with each method's mode, the scans and the lines of sight handed
//! to [`fathom_report::scene`] ([`page`]).

use fathom_report::scene::decimate::{MAX_HITS, MAX_SCANS, MAX_SKY, keep};
use fathom_report::scene::{MethodTrack, Scan, Scene, ScenePage, SkyEpoch};

use super::method::Method;
use super::record::{ScanSnapshot, SceneDetail, SkySnapshot};
use super::sense::SensorEpoch;
use super::world::Prepared;
use fathom_ins::local_level::LocalTruthSample;
use fathom_sim::SimError;

/// A flight's scans from `from_s` on (`truth` at the IMU rate, `sensed[j - 1]` the
/// data of sample `j`, as `run::Flown` holds them), at most [`MAX_SCANS`] of them with
/// at most [`MAX_HITS`] returns each (the page's limits).
pub fn scans(truth: &[LocalTruthSample], sensed: &[SensorEpoch], from_s: f64) -> Vec<ScanSnapshot> {
    let all: Vec<(usize, &[super::sense::BeamReturn])> = sensed
        .iter()
        .enumerate()
        .filter(|(j, _)| truth.get(j + 1).is_some_and(|t| t.time >= from_s))
        .filter_map(|(j, e)| e.ranges.as_ref().map(|r| (j + 1, &r.returns[..])))
        .collect();
    keep(all.len(), MAX_SCANS)
        .into_iter()
        .map(|k| {
            let (j, returns) = all[k];
            let thin: Vec<_> = keep(returns.len(), MAX_HITS)
                .into_iter()
                .map(|b| returns[b])
                .collect();
            ScanSnapshot::of(&truth[j], &thin)
        })
        .collect()
}

/// A flight's GNSS epochs from `from_s` on (as [`scans`]), at most [`MAX_SKY`] of
/// them: each satellite's direction from the true position and whether that position
/// sees it.
pub fn sky(
    prep: &Prepared,
    truth: &[LocalTruthSample],
    sensed: &[SensorEpoch],
    from_s: f64,
) -> Vec<SkySnapshot> {
    let frame = prep.receiver.frame();
    let all: Vec<usize> = sensed
        .iter()
        .enumerate()
        .filter(|(j, e)| e.gnss.is_some() && truth.get(j + 1).is_some_and(|t| t.time >= from_s))
        .map(|(j, _)| j)
        .collect();
    keep(all.len(), MAX_SKY)
        .into_iter()
        .filter_map(|k| {
            let j = all[k];
            let t = truth.get(j + 1)?;
            let g = sensed[j].gnss.as_ref()?;
            let rx = frame.ecef_from_ned(&t.pos_in_nav);
            let sats = g
                .sats
                .iter()
                .filter_map(|s| {
                    let d = frame.ned_from_ecef() * (s.pos_ecef - rx);
                    let d = d.try_normalize(1e-9)?;
                    Some(([d.x, d.y, d.z], s.true_los))
                })
                .collect();
            Some(SkySnapshot { time: t.time, sats })
        })
        .collect()
}

pub use fathom_replay::scene_mesh::{mesh_of, style};

/// A point in the page's `f32`.
pub fn f32x3(p: &[f64; 3]) -> [f32; 3] {
    [p[0] as f32, p[1] as f32, p[2] as f32]
}

/// The page of run 0 (`details`, one per scenario, in the file's order).
///
/// # Errors
/// [`SimError::Output`] when the details do not match the scenarios or a scene is
/// inconsistent (a bug, not the user's input).
pub fn page(prep: &Prepared, details: &[SceneDetail], title: &str) -> Result<String, SimError> {
    let c = &prep.checked;
    if details.len() != prep.scenes.len() {
        return Err(SimError::Output {
            path: "scene.html".into(),
            reason: format!(
                "{} details for {} scenarios",
                details.len(),
                prep.scenes.len()
            ),
        });
    }
    let scenes: Vec<Scene> = c
        .scenes
        .iter()
        .zip(&prep.scenes)
        .zip(details)
        .map(|((spec, world), d)| {
            // Every series over the epochs all of them reached.
            let n = d
                .estimates
                .iter()
                .map(Vec::len)
                .fold(d.times.len().min(d.truth.len()), usize::min);
            let truth: Vec<[f32; 3]> = d.truth[..n].iter().map(f32x3).collect();
            Scene {
                name: spec.name.clone(),
                mesh: mesh_of(&world.mesh),
                times: d.times[..n].to_vec(),
                methods: c
                    .methods
                    .iter()
                    .zip(d.estimates.iter().zip(&d.map_mode))
                    .map(|(m, (est, mode))| track(*m, &est[..n], mode, &truth))
                    .collect(),
                truth,
                scans: page_scans(&d.scans),
                sky: page_sky(&d.sky),
            }
        })
        .collect();
    let page = ScenePage {
        title: title.to_string(),
        note: "run 0 of the main batch; paths, scans and satellites thinned for display \
               (the reports use every epoch)"
            .to_string(),
        scenes,
    };
    fathom_report::scene::scene_html(&page).map_err(|e| SimError::Output {
        path: "scene.html".into(),
        reason: e.to_string(),
    })
}

/// Scans in the page's form.
pub fn page_scans(scans: &[ScanSnapshot]) -> Vec<Scan> {
    scans
        .iter()
        .map(|s| Scan {
            time: s.time,
            origin: f32x3(&s.pos),
            hits: s.hits.iter().map(f32x3).collect(),
        })
        .collect()
}

/// GNSS epochs in the page's form.
pub fn page_sky(sky: &[SkySnapshot]) -> Vec<SkyEpoch> {
    sky.iter()
        .map(|e| SkyEpoch {
            time: e.time,
            sats: e.sats.iter().map(|(v, los)| (f32x3(v), *los)).collect(),
        })
        .collect()
}

/// One method's track; a diverged (non-finite) estimate is drawn at the truth, its
/// error then reads 0 on the page (the reports count the divergence).
pub fn track(
    method: Method,
    est: &[[f64; 3]],
    map_mode: &[bool],
    truth: &[[f32; 3]],
) -> MethodTrack {
    let mode_names = if method.is_switching() {
        vec!["GPS/INS".to_string(), "map-aided".to_string()]
    } else if method == Method::InsOnly {
        vec!["INS".to_string()]
    } else {
        vec!["GPS/INS".to_string()]
    };
    let n = est.len();
    MethodTrack {
        name: method.name().to_string(),
        positions: est
            .iter()
            .zip(truth)
            .map(|(p, t)| {
                let q = f32x3(p);
                if q.iter().all(|v| v.is_finite()) {
                    q
                } else {
                    *t
                }
            })
            .collect(),
        mode: (0..n)
            .map(|k| u8::from(method.is_switching() && map_mode.get(k).copied().unwrap_or(false)))
            .collect(),
        mode_names,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A method's mode is map-aided only for a switching method; a diverged estimate
    /// is drawn at the truth.
    #[test]
    fn tracks_carry_modes_and_stay_finite() {
        let est = [[1.0, 2.0, 3.0], [f64::NAN, 0.0, 0.0]];
        let truth = [[1.0, 2.0, 3.5], [4.0, 5.0, 6.0]];
        let t = track(Method::Grekf, &est, &[false, true], &truth);
        assert_eq!(t.mode, vec![0, 1]);
        assert_eq!(t.mode_names[1], "map-aided");
        assert_eq!(t.positions[1], truth[1]);
        let g = track(Method::GpsIns, &est, &[true, true], &truth);
        assert_eq!(g.mode, vec![0, 0]);
    }
}

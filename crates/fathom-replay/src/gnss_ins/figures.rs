//! The GNSS / INS replay's figures ([`crate::figures`]): the plan view of every track
//! (`tracks.svg`: EKF2, the truth when there is one, the GNSS fixes, each method),
//! the horizontal error with each filter's 3σ against the truth, else the
//! distance from EKF2 (`error_3sigma.svg`, outage windows shaded), the GNSS updates'
//! NIS (`nis_gnss.svg`) and the receiver's fix quality over time
//! (`gnss_quality.svg`: horizontal accuracy and satellites).

use fathom_report::plot::{LinePlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

use super::{GnssInsFilter, GnssInsReplay};
use crate::figures::{
    ErrorTrack, InnovationTrack, Path, Tested, error_3sigma, nis, plan_view_with,
};

/// Every figure of `r`.
///
/// # Errors
/// The figures' own errors (non-finite estimates, ...).
pub(super) fn write(r: &GnssInsReplay, out: &mut Analysis) -> Result<(), SimError> {
    let en = |p: &[[f64; 3]]| p.iter().map(|x| (x[1], x[0])).collect::<Vec<_>>();
    let mut paths: Vec<Path<'_>> = vec![Path {
        name: "GNSS fixes",
        color: 8,
        points: r
            .fixes
            .iter()
            .map(|f| (f.north_east[1], f.north_east[0]))
            .collect(),
    }];
    if r.truth.is_some() {
        paths.push(Path {
            name: "EKF2",
            color: 9,
            points: en(&r.ekf2),
        });
    }
    for (k, m) in r.methods.iter().enumerate() {
        paths.push(Path {
            name: m.trace.name(),
            color: k,
            points: en(&m.trace.pos_in_nav),
        });
    }
    let (label, reference) = match &r.truth {
        Some(t) => ("truth", en(t)),
        None => ("EKF2", en(&r.ekf2)),
    };
    plan_view_with(
        out,
        "tracks.svg",
        "Tracks in plan view",
        ("east (m)", "north (m)"),
        (label, &reference),
        &paths,
        None,
    )?;
    let sigmas: Vec<Option<Vec<f64>>> = r.methods.iter().map(|m| m.trace.sigma_h()).collect();
    let tracks: Vec<ErrorTrack<'_>> = r
        .methods
        .iter()
        .enumerate()
        .map(|(k, m)| ErrorTrack {
            name: m.trace.name(),
            color: k,
            errors: m.vs_truth.as_ref().map_or(&m.vs_ekf2.h, |d| &d.h),
            sigma: sigmas[k].as_deref(),
        })
        .collect();
    error_3sigma(
        out,
        "error_3sigma.svg",
        if r.truth.is_some() {
            "Horizontal position error against the truth, with the filter's 3σ"
        } else {
            "Horizontal distance from EKF2's estimate, with the filter's 3σ"
        },
        &r.times,
        &tracks,
    )?;
    let nis_tracks: Vec<InnovationTrack<'_>> = r
        .methods
        .iter()
        .enumerate()
        .filter(|(_, m)| m.trace.method.filter != GnssInsFilter::Ins)
        .map(|(k, m)| InnovationTrack {
            name: m.trace.name(),
            color: k,
            tested: m
                .trace
                .updates
                .iter()
                .map(|u| Tested {
                    time: u.time,
                    innovation: None,
                    sigma: None,
                    nis: u.nis,
                })
                .collect(),
        })
        .collect();
    let dof = r
        .methods
        .iter()
        .find_map(|m| m.trace.updates.first().map(|u| u.dof))
        .unwrap_or(3);
    nis(out, "nis_gnss.svg", "GNSS update NIS", dof, &nis_tracks)?;
    if !r.fixes.is_empty() {
        let mut plot = LinePlot::new(
            "GNSS fix quality (shaded: outage windows)",
            "time since start (s)",
            "horizontal accuracy (m) / satellites",
        )
        .with_series(
            Series::new(
                "horizontal accuracy (m)",
                r.fixes.iter().map(|f| (f.time, f.h_acc)).collect(),
            )
            .with_color(0),
        )
        .with_series(
            Series::new(
                "satellites",
                r.fixes
                    .iter()
                    .map(|f| (f.time, f64::from(f.satellites)))
                    .collect(),
            )
            .with_color(1),
        )
        .with_series(
            Series::new(
                "fix type",
                r.fixes
                    .iter()
                    .map(|f| (f.time, f64::from(f.fix_type)))
                    .collect(),
            )
            .with_color(2),
        );
        for w in &r.outages {
            plot = plot.with_shade(w[0], w[1]);
        }
        out.figure("gnss_quality.svg", &plot)?;
    }
    Ok(())
}

//! The INS / DVL replay's figures ([`crate::figures`]): with truth the plan view
//! (`estimate_vs_truth.svg`) and the horizontal error with each filter's 3σ
//! (`error_3sigma.svg`); always the velocity innovations, one figure per NED
//! component (`innovations_north.svg`, `innovations_east.svg`,
//! `innovations_down.svg`), their NIS (`nis.svg`, 3 dof) and, for logs with depth,
//! the depth's (`innovations_depth.svg`, `nis_depth.svg`).

use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

use super::{InsDvlReplay, Update};
use crate::figures::{
    ErrorTrack, InnovationTrack, Path, Tested, error_3sigma, innovations, nis, plan_view,
};

/// Every figure of `r`.
///
/// # Errors
/// The figures' own errors (non-finite estimates, ...).
pub(super) fn write(r: &InsDvlReplay, out: &mut Analysis) -> Result<(), SimError> {
    if let (Some(truth), Some(_)) = (&r.truth, r.methods.first()) {
        let paths: Vec<Path<'_>> = r
            .methods
            .iter()
            .enumerate()
            .map(|(k, m)| Path {
                name: m.name(),
                color: k,
                points: m.trace.north_east.iter().map(|p| (p[1], p[0])).collect(),
            })
            .collect();
        let truth: Vec<(f64, f64)> = truth.iter().map(|p| (p[1], p[0])).collect();
        plan_view(
            out,
            "estimate_vs_truth.svg",
            "Estimated and true path",
            ("east (m)", "north (m)"),
            &truth,
            &paths,
            None,
        )?;
        let tracks: Vec<ErrorTrack<'_>> = r
            .methods
            .iter()
            .enumerate()
            .filter_map(|(k, m)| {
                m.errors_h.as_deref().map(|e| ErrorTrack {
                    name: m.name(),
                    color: k,
                    errors: e,
                    sigma: m.trace.sigma_h.as_deref(),
                })
            })
            .collect();
        error_3sigma(
            out,
            "error_3sigma.svg",
            "Horizontal position error with the filter's 3σ",
            &r.times,
            &tracks,
        )?;
    }
    for (c, axis) in ["north", "east", "down"].into_iter().enumerate() {
        innovations(
            out,
            &format!("innovations_{axis}.svg"),
            &format!("Velocity innovations, {axis} (DVL or RPM aid minus filter)"),
            "innovation (m/s)",
            &tracks(r, |m| &m.velocity_updates, c),
        )?;
    }
    nis(
        out,
        "nis.svg",
        "Velocity NIS",
        3,
        &tracks(r, |m| &m.velocity_updates, 0),
    )?;
    let depth = tracks(r, |m| &m.depth_updates, 0);
    innovations(
        out,
        "innovations_depth.svg",
        "Depth innovations",
        "innovation (m)",
        &depth,
    )?;
    nis(out, "nis_depth.svg", "Depth NIS", 1, &depth)?;
    Ok(())
}

/// Every filter's updates picked by `pick`, component `c` of their innovations
/// (methods without updates are left out), each in its method's colour.
fn tracks(
    r: &InsDvlReplay,
    pick: fn(&super::InsMethodTrace) -> &Vec<Update>,
    c: usize,
) -> Vec<InnovationTrack<'_>> {
    r.methods
        .iter()
        .enumerate()
        .filter(|(_, m)| !pick(&m.trace).is_empty())
        .map(|(k, m)| InnovationTrack {
            name: m.name(),
            color: k,
            tested: pick(&m.trace)
                .iter()
                .map(|u| Tested {
                    time: u.time,
                    innovation: u.innovation.map(|v| v[c]),
                    sigma: u.innovation_sigma.map(|s| s[c]),
                    nis: u.nis,
                })
                .collect(),
        })
        .collect()
}

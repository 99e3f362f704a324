//! The range-beacon replay's figures ([`crate::figures`]): with truth the plan view
//! (`estimate_vs_truth.svg`, beacons marked) and the horizontal error with each
//! method's 3σ (`error_3sigma.svg`); always the range innovations and NIS
//! (`innovations.svg`, `nis.svg`) and, for logs with depth, the depth's
//! (`innovations_depth.svg`, `nis_depth.svg`).

use fathom_report::plot::Series;
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

use super::{MethodResult, RangeBeaconReplay};
use crate::consistency::Innovation;
use crate::figures::{
    ErrorTrack, InnovationTrack, Path, Tested, error_3sigma, innovations, nis, plan_view,
};

/// Every figure of `r`.
///
/// # Errors
/// The figures' own errors (non-finite estimates, ...).
pub(super) fn write(r: &RangeBeaconReplay, out: &mut Analysis) -> Result<(), SimError> {
    if let Some(truth) = &r.truth {
        let beacons = Series::new(
            "beacons",
            r.beacons
                .iter()
                .map(|b| (b.pos_in_nav[1], b.pos_in_nav[0]))
                .collect(),
        );
        let paths: Vec<Path<'_>> = r
            .methods
            .iter()
            .enumerate()
            .map(|(k, m)| Path {
                name: &m.spec.name,
                color: k,
                points: m.trace.est.iter().map(|p| (p[1], p[0])).collect(),
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
            Some(beacons),
        )?;
        let errors: Vec<Vec<f64>> = r
            .methods
            .iter()
            .map(|m| {
                m.trace
                    .est
                    .iter()
                    .zip(truth.iter())
                    .map(|(e, g)| (e[1] - g.0).hypot(e[0] - g.1))
                    .collect()
            })
            .collect();
        let tracks: Vec<ErrorTrack<'_>> = r
            .methods
            .iter()
            .zip(&errors)
            .enumerate()
            .map(|(k, (m, e))| ErrorTrack {
                name: &m.spec.name,
                color: k,
                errors: e,
                sigma: (m.trace.pos_sigma.len() == e.len()).then_some(&m.trace.pos_sigma[..]),
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
    for (file, what, pick) in [
        ("", "Range", ranges as fn(&MethodResult) -> &[Innovation]),
        ("_depth", "Depth", depths),
    ] {
        let tracks = tested(r, pick);
        innovations(
            out,
            &format!("innovations{file}.svg"),
            &format!("{what} innovations"),
            "innovation (m)",
            &tracks,
        )?;
        nis(
            out,
            &format!("nis{file}.svg"),
            &format!("{what} NIS"),
            1,
            &tracks,
        )?;
    }
    Ok(())
}

fn ranges(m: &MethodResult) -> &[Innovation] {
    &m.trace.ranges
}

fn depths(m: &MethodResult) -> &[Innovation] {
    &m.trace.depths
}

/// Every filter's tested measurements picked by `pick` (methods without any are left
/// out), each in its method's colour.
fn tested(
    r: &RangeBeaconReplay,
    pick: fn(&MethodResult) -> &[Innovation],
) -> Vec<InnovationTrack<'_>> {
    r.methods
        .iter()
        .enumerate()
        .filter(|(_, m)| !pick(m).is_empty())
        .map(|(k, m)| InnovationTrack {
            name: &m.spec.name,
            color: k,
            tested: pick(m)
                .iter()
                .map(|i| Tested {
                    time: i.time,
                    innovation: Some(i.innovation),
                    sigma: i.sigma(),
                    nis: i.nis,
                })
                .collect(),
        })
        .collect()
}

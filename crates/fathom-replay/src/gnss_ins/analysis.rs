//! The GNSS / INS replay's `summary.json` rows and checks and its CSV files:
//! `estimates.csv` (EKF2, the truth and every method's position at the recording
//! instants) and `gnss_updates.csv` (every filter's GNSS updates, `reset` 1 for a
//! re-acquisition).
//!
//! Rows per method: `rms_h_vs_ekf2`, `rms_3d_vs_ekf2`, `max_h_vs_ekf2` (agreement
//! with EKF2, m); with truth `rmse_h`, `rmse_3d` (m) and `nees_pos` (mean position
//! NEES per dof, filters); per outage window `k` `outage<k>_drift_h_vs_ekf2` (the
//! horizontal distance from EKF2 at the last instant of the window) and
//! `outage<k>_max_h_vs_ekf2`; the GNSS updates `gnss_accepted`, `gnss_rejected`,
//! `gnss_resets` (re-acquisitions after a run of rejected fixes) and their NIS (`nis_gnss_*`); the map-aided methods `map_updates`, `map_left_out`,
//! `map_failed` and `mode_switches`. EKF2 gets the rows `rmse_h`, `rmse_3d` with truth. With
//! truth, the check `<method>_rmse_h_within_1.5x_ekf2` compares each filter with EKF2.

use fathom_report::output::{Claim, CsvCell, Row};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;

use super::{GnssInsFilter, GnssInsReplay};
use crate::consistency::NisSummary;
use crate::own_log::rows::{nis_metric, nis_rows};

/// The name of EKF2's rows.
pub(super) const EKF2: &str = "EKF2";

/// The factor of the check against EKF2's horizontal RMSE.
pub(super) const WITHIN_EKF2: f64 = 1.5;

fn declare_units(r: &GnssInsReplay, out: &mut Analysis) {
    for (metric, unit) in [
        ("rms_h_vs_ekf2", "m"),
        ("rms_3d_vs_ekf2", "m"),
        ("max_h_vs_ekf2", "m"),
        ("rmse_h", "m"),
        ("rmse_3d", "m"),
        ("nees_pos", "1"),
        ("gnss_accepted", "count"),
        ("gnss_rejected", "count"),
        ("gnss_resets", "count"),
        ("map_updates", "count"),
        ("map_left_out", "count"),
        ("map_failed", "count"),
        ("mode_switches", "count"),
    ] {
        out.unit(metric, unit);
    }
    for k in 0..r.outages.len() {
        out.unit(format!("outage{k}_drift_h_vs_ekf2"), "m");
        out.unit(format!("outage{k}_max_h_vs_ekf2"), "m");
    }
    for (stat, unit) in [
        ("mean", "1"),
        ("median", "1"),
        ("beyond_95", "1"),
        ("count", "count"),
    ] {
        out.unit(nis_metric("gnss", stat), unit);
    }
}

/// Indices of the instants inside outage window `w`.
pub(super) fn in_window(times: &[f64], w: [f64; 2]) -> Vec<usize> {
    (0..times.len())
        .filter(|&i| times[i] >= w[0] && times[i] < w[1])
        .collect()
}

/// Every row and check (module docs).
pub(super) fn rows(r: &GnssInsReplay, out: &mut Analysis) {
    declare_units(r, out);
    if let Some(d) = &r.ekf2_vs_truth {
        out.row(Row::new(EKF2, "rmse_h", d.rms_h()));
        out.row(Row::new(EKF2, "rmse_3d", d.rms_3d()));
    }
    for m in &r.methods {
        let name = m.trace.name();
        out.row(Row::new(name, "rms_h_vs_ekf2", m.vs_ekf2.rms_h()));
        out.row(Row::new(name, "rms_3d_vs_ekf2", m.vs_ekf2.rms_3d()));
        out.row(Row::new(
            name,
            "max_h_vs_ekf2",
            m.vs_ekf2.h.iter().copied().fold(0.0, f64::max),
        ));
        if let Some(d) = &m.vs_truth {
            out.row(Row::new(name, "rmse_h", d.rms_h()));
            out.row(Row::new(name, "rmse_3d", d.rms_3d()));
        }
        if let Some(n) = m.nees_pos {
            out.row(Row::new(name, "nees_pos", n));
        }
        for (k, w) in r.outages.iter().enumerate() {
            let idx = in_window(&r.times, *w);
            if let Some(&last) = idx.last() {
                out.row(Row::new(
                    name,
                    format!("outage{k}_drift_h_vs_ekf2"),
                    m.vs_ekf2.h[last],
                ));
                out.row(Row::new(
                    name,
                    format!("outage{k}_max_h_vs_ekf2"),
                    idx.iter().map(|&i| m.vs_ekf2.h[i]).fold(0.0, f64::max),
                ));
            }
        }
        if let Some(c) = &m.trace.map {
            out.row(Row::new(name, "map_updates", c.map_updates as f64));
            out.row(Row::new(name, "map_left_out", c.map_left_out as f64));
            out.row(Row::new(name, "map_failed", c.map_failed as f64));
            out.row(Row::new(name, "mode_switches", c.switches as f64));
        }
        if m.trace.method.filter == GnssInsFilter::Ins {
            continue;
        }
        let u = &m.trace.updates;
        let accepted = u.iter().filter(|x| x.accepted).count();
        out.row(Row::new(name, "gnss_accepted", accepted as f64));
        out.row(Row::new(name, "gnss_rejected", (u.len() - accepted) as f64));
        let resets = u.iter().filter(|x| x.reset).count();
        out.row(Row::new(name, "gnss_resets", resets as f64));
        let nis: Vec<f64> = u
            .iter()
            .filter(|x| x.nis.is_finite())
            .map(|x| x.nis)
            .collect();
        if let Some(s) = u.first().and_then(|x| NisSummary::of(&nis, x.dof)) {
            nis_rows(out, name, "gnss", "GNSS updates", s);
        }
        if let (Some(d), Some(e)) = (&m.vs_truth, &r.ekf2_vs_truth) {
            let (mine, theirs) = (d.rms_h(), e.rms_h());
            out.claim(Claim::new(
                format!("{name}_rmse_h_within_1.5x_ekf2"),
                format!(
                    "`{name}`'s horizontal RMSE against the truth is at most {WITHIN_EKF2} \
                     times EKF2's at the same instants"
                ),
                mine <= WITHIN_EKF2 * theirs,
                format!(
                    "{mine:.3} m vs EKF2's {theirs:.3} m (ratio {:.2})",
                    mine / theirs
                ),
            ));
        }
    }
}

/// `estimates.csv` and `gnss_updates.csv`.
///
/// # Errors
/// The CSV writer's.
pub(super) fn csv_files(r: &GnssInsReplay, out: &mut Analysis) -> Result<(), SimError> {
    let mut headers = vec!["time[s]".to_string()];
    let mut columns = vec![r.times.clone()];
    let mut track = |prefix: &str, p: &[[f64; 3]]| {
        for (k, c) in ["north[m]", "east[m]", "down[m]"].into_iter().enumerate() {
            headers.push(format!("{prefix}_{c}"));
            columns.push(p.iter().map(|x| x[k]).collect());
        }
    };
    track("ekf2", &r.ekf2);
    if let Some(g) = &r.truth {
        track("true", g);
    }
    for m in &r.methods {
        track(m.trace.name(), &m.trace.pos_in_nav);
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.csv_owned_columns("estimates.csv", &h, columns)?;
    let mut records = Vec::new();
    for m in &r.methods {
        for u in &m.trace.updates {
            records.push(vec![
                CsvCell::Text(m.trace.name().to_string()),
                CsvCell::Num(u.time),
                CsvCell::Num(u.nis),
                CsvCell::Num(u.dof as f64),
                CsvCell::Num(f64::from(u8::from(u.accepted))),
                CsvCell::Num(f64::from(u8::from(u.reset))),
            ]);
        }
    }
    out.csv_records(
        "gnss_updates.csv",
        &["method", "time[s]", "nis", "dof", "accepted", "reset"],
        &records,
    )?;
    Ok(())
}

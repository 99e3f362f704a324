//! The GNSS / INS replay's notes in `report.md`: the log read, the methods, what the
//! rows compare (agreement with EKF2; errors against the truth), the outages, the
//! files.

use std::fmt::Write as _;

use super::analysis::{EKF2, WITHIN_EKF2};
use super::{GnssInsFilter, GnssInsReplay};
use crate::own_log::notes;

fn describe(f: GnssInsFilter) -> &'static str {
    match f {
        GnssInsFilter::Ins => "the strapdown INS alone from EKF2's start (dead reckoning)",
        GnssInsFilter::Ekf12 => {
            "GPS/INS, the 12-state error-state filter [dp, dv, psi, b_a] of the `urban` \
             experiment, closed loop"
        }
        GnssInsFilter::Ekf15 => {
            "GPS/INS, the 15-state filter [dp, dv, psi, b_a, b_g] (gyro bias), closed loop"
        }
        GnssInsFilter::Grekf => {
            "the 12-state filter switching from GPS/INS to the GREKF (geometry-based range \
             EKF: the log's beams cast against the world) while GNSS is away"
        }
        GnssInsFilter::Mgpmf => {
            "the 12-state filter switching from GPS/INS to the MGPMF (marginalized \
             point-mass filter over north, east and yaw) while GNSS is away"
        }
    }
}

/// The notes (Markdown, `###` headings).
pub(super) fn notes(r: &GnssInsReplay, about: &str) -> String {
    let mut md = format!(
        "### Log\n\n{}. Rows read: {} IMU, {} GNSS, {} baro, {} magnetometer, {} range, {} \
         EKF2 reference, {} truth. The replay starts at EKF2's first row inside the IMU \
         data ({:.6} s since boot) from EKF2's position, velocity and attitude, and records \
         every method at EKF2's {} later rows.\n\n",
        fathom_core::echo::echo_message(about),
        r.rows[0],
        r.rows[1],
        r.rows[2],
        r.rows[3],
        r.rows[4],
        r.rows[5],
        r.rows[6],
        r.t0,
        r.times.len()
    );
    md.push_str(&notes::methods(r.methods.iter().map(|m| {
        (m.trace.name(), describe(m.trace.method.filter).to_string())
    })));
    md.push_str(
        "### Agreement with EKF2\n\nPX4's own estimate (EKF2) is a reference track, not \
         the truth: `rms_h_vs_ekf2`, `rms_3d_vs_ekf2` and `max_h_vs_ekf2` (m) measure how \
         closely each method agrees with it, in the local NED frame of PX4's projection \
         about EKF2's first pose.\n\n",
    );
    if let (Some(shift), Some(d)) = (r.truth_datum_shift, &r.ekf2_vs_truth) {
        let _ = write!(
            md,
            "### Errors against the truth\n\nThe log holds the simulator's ground truth: \
             `rmse_h` and `rmse_3d` (m) score every method and `{EKF2}` at the same \
             instants (the truth interpolated linearly), `nees_pos` the filters' mean \
             position NEES per degree of freedom (1 for a consistent filter). The truth's \
             altitude was shifted by {shift:.3} m onto the GNSS altitude at the first used \
             fix (the simulator's truth has its own vertical datum). EKF2's horizontal RMSE \
             is {:.3} m; the checks `*_rmse_h_within_1.5x_ekf2` ask each filter for at most \
             {WITHIN_EKF2} times that.\n\n",
            d.rms_h()
        );
    }
    if r.reacquire_after > 0 {
        let _ = write!(
            md,
            "### GNSS re-acquisition\n\nWhen {} fixes in a row fail a filter's gate, the \
             last of them resets it onto the fixes: its position (and, with the fix \
             velocity, velocity) covariance is widened by the outer product of the error \
             the fix shows and the fix applied. `gnss_resets` counts these resets per \
             method (`gnss_updates.csv`: `reset` 1); many resets mean the filter's model \
             (its IMU noise) is too optimistic for the log.\n\n",
            r.reacquire_after
        );
    }
    if let Some(w) = &r.world {
        let _ = write!(
            md,
            "### World\n\nThe map-aided methods cast the log's range beams against the \
             world {} (moved into the replay's frame). Each switches to the map-aided \
             update when the fixes the replay uses have fewer satellites than \
             `map_aided.min_satellites` (a dropped fix counts none) and back when they \
             have enough again; `map_updates`, `map_left_out` (every beam left out), \
             `map_failed` and `mode_switches` count what they did.\n\n",
            fathom_core::echo::echo_message(w)
        );
    }
    if !r.outages.is_empty() {
        md.push_str("### GNSS outages\n\n");
        for (k, w) in r.outages.iter().enumerate() {
            let _ = writeln!(
                md,
                "- outage {k}: fixes dropped from {} s to {} s after the start; \
                 `outage{k}_drift_h_vs_ekf2` is each method's horizontal distance from EKF2 \
                 at the last instant of the window, `outage{k}_max_h_vs_ekf2` the largest.",
                w[0], w[1]
            );
        }
        md.push('\n');
    }
    md.push_str(&notes::innovations(r.truth.is_some()));
    md.push_str(
        "### Files\n\n`estimates.csv`: EKF2's, the truth's (when the log has it) and every \
         method's position at the recording instants; `gnss_updates.csv`: every filter's \
         GNSS updates with their NIS and whether they were accepted.\n",
    );
    md
}

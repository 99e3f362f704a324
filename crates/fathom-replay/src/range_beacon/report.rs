//! The range-beacon replay's notes in `report.md`: the log read, the methods, what the
//! error rows score, how to read the NIS, the CSV files.

use std::path::Path;

use super::RangeBeaconReplay;
use super::analysis::error_kind;
use crate::own_log::notes;

/// The notes (Markdown, `###` headings).
pub(super) fn notes(r: &RangeBeaconReplay, dir: &Path) -> String {
    let mut md = format!(
        "### Log\n\n`{}` (kind `range-beacon`); rows read: {} motion, {} ranges, {} depth, {} \
         truth. Motion: {}. {} beacons, {} recording instants.\n\n",
        dir.display(),
        r.rows[0],
        r.rows[1],
        r.rows[2],
        r.rows[3],
        if r.odometry {
            "wheel odometry (2D)"
        } else {
            "DVL + heading (3D with depth)"
        },
        r.beacons.len(),
        r.times.len()
    );
    md.push_str(&notes::methods(
        r.methods
            .iter()
            .map(|m| (m.spec.name.as_str(), m.spec.describe())),
    ));
    if r.truth.is_some() {
        md.push_str(&format!(
            "### Position error\n\nPosition error against `truth.csv` ({}, m): the rows \
             `mean`, `std`, `max` and `rmse` of each method over the recording instants; \
             `accepted` and `rejected` count each filter's ranges. `error_3sigma.svg` shows \
             the horizontal error against 3σ of the filter's horizontal covariance.\n\n",
            error_kind(r)
        ));
    }
    md.push_str(&notes::innovations(r.truth.is_some()));
    md.push_str(&notes::files("every tested range and depth"));
    md
}

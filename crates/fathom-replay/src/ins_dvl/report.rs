//! The INS / DVL replay's notes in `report.md`: the log read, the methods, what the
//! error rows score, how to read the NIS, the CSV files.

use std::path::Path;

use super::InsDvlReplay;
use super::analysis::describe;
use crate::own_log::notes;

/// The notes (Markdown, `###` headings).
pub(super) fn notes(r: &InsDvlReplay, dir: &Path) -> String {
    let mut md = format!(
        "### Log\n\n`{}` (kind `ins-dvl`); rows read: {} IMU, {} DVL, {} depth, {} altitude, \
         {} RPM, {} truth. IMU {}; {} recording instants; {} DVL row{} invalid (flag 0 or \
         altitude beyond the DVL's range).\n\n",
        dir.display(),
        r.rows[0],
        r.rows[1],
        r.rows[2],
        r.rows[3],
        r.rows[4],
        r.rows[5],
        if r.imu_increments {
            "increments"
        } else {
            "rates"
        },
        r.times.len(),
        r.invalid_dvl_rows,
        if r.invalid_dvl_rows == 1 { "" } else { "s" }
    );
    md.push_str(&notes::methods(
        r.methods.iter().map(|m| (m.name(), describe(m))),
    ));
    if r.truth.is_some() {
        md.push_str(
            "### Position error\n\nHorizontal position error against `truth.csv` (m): the \
             rows `mean`, `std`, `max` and `rmse` of each method over the recording \
             instants, and `vel_rmse` the horizontal velocity error's RMSE (m/s) when the \
             truth has velocity. `error_3sigma.svg` shows the error against 3σ of each \
             filter's horizontal covariance.\n\n",
        );
    }
    md.push_str(
        "`accepted` and `rejected` count each filter's velocity updates (a gated filter \
         rejects some); `nis_velocity_*` covers every velocity update (DVL or RPM aid), \
         `nis_dvl_velocity_*` those from a valid DVL only.\n\n",
    );
    md.push_str(&notes::innovations(r.truth.is_some()));
    md.push_str(&notes::files("every velocity and depth update"));
    md
}

//! The INS / DVL replay's `summary.json` rows, checks and extra keys (through
//! [`crate::own_log::rows`]) and its CSV files: `estimates.csv` (the truth and every
//! method's position and velocity at the recording instants) and `innovations.csv`
//! (every velocity and depth update).

use fathom_report::output::{CsvCell, Row};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;
use fathom_stats::RunStats;
use serde_json::{Value, json};

use super::{InsDvlReplay, InsMethodResult};
use crate::own_log::rows::{declare_units, error_rows, nis_rows};

/// What a method runs, in words (`filter `vkf``, `filter `ins-dvl`, velocity gate at
/// probability 0.999`).
pub(super) fn describe(m: &InsMethodResult) -> String {
    let method = &m.trace.method;
    format!(
        "filter `{}`{}",
        method.filter.name(),
        method.gate_probability.map_or(String::new(), |p| format!(
            ", velocity gate at probability {p}"
        ))
    )
}

/// Per method: the horizontal position error and velocity RMSE (with truth), the
/// velocity updates accepted and rejected (filters), the NIS of the velocity, valid
/// DVL velocity and depth updates with their checks; the extra keys `with_truth`,
/// `error` (`horizontal`), `instants`, `methods` (what each runs), `imu`
/// (`increments` or `rates`), `invalid_dvl_rows` and `rows_read`.
pub(super) fn rows(r: &InsDvlReplay, out: &mut Analysis) {
    declare_units(out);
    for m in &r.methods {
        let name = m.name();
        if let Some(s) = &m.stats {
            error_rows(out, name, s);
        }
        if let Some(s) = m.vel_errors_h.as_deref().and_then(|v| RunStats::of(v).ok()) {
            out.row(Row::new(name, "vel_rmse", s.rmse));
        }
        let updates = &m.trace.velocity_updates;
        if !updates.is_empty() {
            let accepted = updates.iter().filter(|u| u.accepted).count();
            out.row(Row::new(name, "accepted", accepted as f64));
            out.row(Row::new(
                name,
                "rejected",
                (updates.len() - accepted) as f64,
            ));
        }
        for (kind, what, nis) in [
            ("velocity", "velocity updates", m.velocity_nis),
            ("dvl_velocity", "DVL velocity updates", m.dvl_nis),
            ("depth", "depth updates", m.depth_nis),
        ] {
            if let Some(n) = nis {
                nis_rows(out, name, kind, what, n);
            }
        }
    }
    out.extra("with_truth", Value::Bool(r.truth.is_some()));
    out.extra("error", Value::from("horizontal"));
    out.extra("instants", Value::from(r.times.len()));
    out.extra(
        "methods",
        Value::Object(
            r.methods
                .iter()
                .map(|m| (m.name().to_string(), Value::from(describe(m))))
                .collect(),
        ),
    );
    out.extra(
        "imu",
        Value::from(if r.imu_increments {
            "increments"
        } else {
            "rates"
        }),
    );
    out.extra("invalid_dvl_rows", Value::from(r.invalid_dvl_rows));
    out.extra(
        "rows_read",
        json!({
            "imu": r.rows[0],
            "dvl": r.rows[1],
            "depth": r.rows[2],
            "altitude": r.rows[3],
            "rpm": r.rows[4],
            "truth": r.rows[5],
        }),
    );
}

/// `estimates.csv` and `innovations.csv`.
///
/// # Errors
/// Bad headers (a method name that is not a valid column name) or columns of
/// different lengths.
pub(super) fn csv_files(r: &InsDvlReplay, out: &mut Analysis) -> Result<(), SimError> {
    let mut headers = vec!["time[s]".to_string()];
    let mut columns = vec![r.times.clone()];
    if let Some(g) = &r.truth {
        for (k, h) in ["true_north[m]", "true_east[m]", "true_down[m]"]
            .into_iter()
            .enumerate()
        {
            headers.push(h.into());
            columns.push(g.iter().map(|p| p[k]).collect());
        }
    }
    for m in &r.methods {
        let (n, tr) = (m.name(), &m.trace);
        headers.extend([format!("{n}_north[m]"), format!("{n}_east[m]")]);
        columns.extend([
            tr.north_east.iter().map(|p| p[0]).collect(),
            tr.north_east.iter().map(|p| p[1]).collect(),
        ]);
        headers.push(format!("{n}_down[m]"));
        columns.push(tr.depth.clone());
        for (k, c) in ["vel_north[m/s]", "vel_east[m/s]", "vel_down[m/s]"]
            .into_iter()
            .enumerate()
        {
            headers.push(format!("{n}_{c}"));
            columns.push(tr.vel_in_nav.iter().map(|v| v[k]).collect());
        }
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.csv_owned_columns("estimates.csv", &h, columns)?;

    let cells = |v: Option<[f64; 3]>| -> [CsvCell; 3] {
        match v {
            Some(v) => v.map(CsvCell::Num),
            None => std::array::from_fn(|_| CsvCell::Text(String::new())),
        }
    };
    let mut records = Vec::new();
    for m in &r.methods {
        for (what, list) in [
            ("velocity[m/s]", &m.trace.velocity_updates),
            ("depth[m]", &m.trace.depth_updates),
        ] {
            for u in list {
                let mut rec = vec![CsvCell::from(m.name()), what.into(), u.time.into()];
                rec.extend(cells(u.innovation));
                rec.extend(cells(u.innovation_sigma));
                rec.extend([
                    u.nis.into(),
                    usize::from(u.accepted).into(),
                    usize::from(u.rpm).into(),
                ]);
                records.push(rec);
            }
        }
    }
    out.csv_records(
        "innovations.csv",
        &[
            "method",
            "measurement",
            "time[s]",
            "innovation_1",
            "innovation_2",
            "innovation_3",
            "sigma_1",
            "sigma_2",
            "sigma_3",
            "nis",
            "accepted",
            "rpm_aided",
        ],
        &records,
    )
}

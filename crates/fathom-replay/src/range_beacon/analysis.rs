//! The range-beacon replay's `summary.json` rows, checks and extra keys (through
//! [`crate::own_log::rows`]) and its CSV files: `estimates.csv` (the truth and every
//! method's estimate at the recording instants) and `innovations.csv` (every tested
//! range and depth).

use fathom_report::output::{CsvCell, Row};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;
use serde_json::{Value, json};

use super::RangeBeaconReplay;
use crate::own_log::rows::{declare_units, error_rows, nis_rows};

/// `3D` or `horizontal`: the position error the rows score.
pub(super) fn error_kind(r: &RangeBeaconReplay) -> &'static str {
    if r.error_dims == 3 {
        "3D"
    } else {
        "horizontal"
    }
}

/// Per method: the position error (with truth), the ranges accepted and rejected
/// (filters), the NIS of the accepted ranges and of the depths with their checks; the extra keys
/// `with_truth`, `error` (`3D` or `horizontal`), `instants`, `methods` (what each
/// runs) and `rows_read`.
pub(super) fn rows(r: &RangeBeaconReplay, out: &mut Analysis) {
    declare_units(out);
    for m in &r.methods {
        let name = m.spec.name.as_str();
        if let Some(s) = &m.stats {
            error_rows(out, name, s);
        }
        if m.is_filter() {
            out.row(Row::new(name, "accepted", m.trace.counts.accepted as f64));
            out.row(Row::new(name, "rejected", m.trace.counts.rejected as f64));
        }
        // The ranges the filter applied: a rejected range is beyond the model by the
        // filter's own test (counted in `rejected`), not evidence of inconsistency.
        if let Some(n) = m.accepted_nis {
            nis_rows(out, name, "ranges", "accepted ranges", n);
        }
        if let Some(n) = m.depth_nis {
            nis_rows(out, name, "depth", "depths", n);
        }
    }
    out.extra("with_truth", Value::Bool(r.truth.is_some()));
    out.extra("error", Value::from(error_kind(r)));
    out.extra("instants", Value::from(r.times.len()));
    out.extra(
        "methods",
        Value::Object(
            r.methods
                .iter()
                .map(|m| (m.spec.name.clone(), Value::from(m.spec.describe())))
                .collect(),
        ),
    );
    out.extra(
        "rows_read",
        json!({
            "motion": r.rows[0],
            "ranges": r.rows[1],
            "depth": r.rows[2],
            "truth": r.rows[3],
        }),
    );
}

/// `estimates.csv` and `innovations.csv`.
///
/// # Errors
/// Bad headers (a method name that is not a valid column name) or columns of
/// different lengths.
pub(super) fn csv_files(r: &RangeBeaconReplay, out: &mut Analysis) -> Result<(), SimError> {
    let mut headers = vec!["time[s]".to_string()];
    let mut columns = vec![r.times.clone()];
    if let Some(g) = &r.truth {
        headers.extend(["true_north[m]".into(), "true_east[m]".into()]);
        columns.extend([
            g.iter().map(|p| p[0]).collect(),
            g.iter().map(|p| p[1]).collect(),
        ]);
        if let Some(d) = &r.truth_down {
            headers.push("true_down[m]".into());
            columns.push(d.clone());
        }
    }
    for m in &r.methods {
        let (n, tr) = (&m.spec.name, &m.trace);
        headers.extend([format!("{n}_north[m]"), format!("{n}_east[m]")]);
        columns.extend([
            tr.est.iter().map(|p| p[0]).collect(),
            tr.est.iter().map(|p| p[1]).collect(),
        ]);
        if let Some(d) = &tr.down {
            headers.push(format!("{n}_down[m]"));
            columns.push(d.clone());
        }
        headers.extend([format!("{n}_heading[rad]"), format!("{n}_sigma_h[m]")]);
        columns.extend([tr.heading.clone(), tr.pos_sigma.clone()]);
    }
    let h: Vec<&str> = headers.iter().map(String::as_str).collect();
    out.csv_owned_columns("estimates.csv", &h, columns)?;

    let mut records = Vec::new();
    for m in &r.methods {
        for (what, list) in [("range", &m.trace.ranges), ("depth", &m.trace.depths)] {
            for i in list {
                records.push(vec![
                    CsvCell::from(m.spec.name.as_str()),
                    what.into(),
                    i.time.into(),
                    i.channel.into(),
                    i.row.into(),
                    i.value.into(),
                    i.innovation.into(),
                    i.nis.into(),
                    usize::from(i.accepted()).into(),
                ]);
            }
        }
    }
    out.csv_records(
        "innovations.csv",
        &[
            "method",
            "measurement",
            "time[s]",
            "beacon_row",
            "file_row",
            "value[m]",
            "innovation[m]",
            "nis",
            "accepted",
        ],
        &records,
    )
}

//! The `summary.json` rows and checks both own-log replays write, with their units:
//! per method the position error against the truth (`mean`, `std`, `max`, `rmse`: the
//! metric names of the `plaza` experiment, so a Plaza log converted into the layout
//! compares row for row), and per method and kind of measurement the NIS per degree
//! of freedom (`nis_<kind>_mean`, `_median`, `_beyond_95`, `_count`) with the check
//! that its mean lies in the 95 % interval of a consistent filter.

use fathom_report::output::{Claim, Row};
use fathom_sim::experiment::Analysis;
use fathom_stats::RunStats;

use crate::consistency::NisSummary;

/// Declares the unit of every metric the own-log replays write.
pub fn declare_units(out: &mut Analysis) {
    for (metric, unit) in [
        ("mean", "m"),
        ("std", "m"),
        ("max", "m"),
        ("rmse", "m"),
        ("vel_rmse", "m/s"),
        ("accepted", "count"),
        ("rejected", "count"),
    ] {
        out.unit(metric, unit);
    }
    for kind in NIS_KINDS {
        for (stat, unit) in NIS_STATS {
            out.unit(nis_metric(kind, stat), unit);
        }
    }
}

/// The kinds of measurement whose NIS is reported (metric names).
pub const NIS_KINDS: [&str; 4] = ["ranges", "depth", "velocity", "dvl_velocity"];

/// The NIS statistics reported per kind, with their units (mean and median per
/// degree of freedom, the fraction beyond the chi-square 95 % quantile, the count).
const NIS_STATS: [(&str, &str); 4] = [
    ("mean", "1"),
    ("median", "1"),
    ("beyond_95", "1"),
    ("count", "count"),
];

/// `nis_<kind>_<stat>`.
pub fn nis_metric(kind: &str, stat: &str) -> String {
    format!("nis_{kind}_{stat}")
}

/// The rows `mean`, `std`, `max`, `rmse` of `method`'s position error, m.
pub fn error_rows(out: &mut Analysis, method: &str, stats: &RunStats) {
    out.row(Row::new(method, "mean", stats.mean));
    out.row(Row::new(method, "std", stats.std));
    out.row(Row::new(method, "max", stats.max));
    out.row(Row::new(method, "rmse", stats.rmse));
}

/// The NIS summary per degree of freedom (what the rows and the report show: 1 for a
/// consistent filter whatever the measurement's size).
pub fn per_dof(n: NisSummary) -> NisSummary {
    let d = n.dof as f64;
    NisSummary {
        mean: n.mean / d,
        median: n.median / d,
        bounds: (n.bounds.0 / d, n.bounds.1 / d),
        ..n
    }
}

/// The NIS rows of `method`'s measurements of `kind` (one of [`NIS_KINDS`], `what`
/// in words) and the check `<method>_<kind>_nis_consistent`.
pub fn nis_rows(out: &mut Analysis, method: &str, kind: &str, what: &str, nis: NisSummary) {
    let n = per_dof(nis);
    for (stat, value) in [
        ("mean", n.mean),
        ("median", n.median),
        ("beyond_95", n.beyond_95),
        ("count", n.count as f64),
    ] {
        out.row(Row::new(method, nis_metric(kind, stat), value));
    }
    out.claim(Claim::new(
        format!("{method}_{kind}_nis_consistent"),
        format!(
            "the mean NIS of `{method}`'s {what} lies in the 95 % interval of a consistent \
             filter"
        ),
        n.consistent(),
        n.describe(what),
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nis_rows_are_per_dof_with_units_and_a_check() {
        let mut out = Analysis::new();
        declare_units(&mut out);
        // Three-component innovations whose NIS averages 3: 1 per dof, consistent.
        let nis = NisSummary::of(&[2.0, 3.0, 4.0, 3.0], 3).unwrap();
        nis_rows(&mut out, "F", "velocity", "velocity updates", nis);
        let mean = out.find_row("F", "nis_velocity_mean").unwrap().value;
        assert!((mean - 1.0).abs() < 1e-12, "{mean}");
        assert_eq!(out.find_row("F", "nis_velocity_count").unwrap().value, 4.0);
        for r in out.rows() {
            assert!(out.unit_of(&r.metric).is_some(), "{}", r.metric);
        }
    }
}

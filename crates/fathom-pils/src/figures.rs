//! The PILS figures as SVG text (`fathom_report::plot`, [`Figure::to_svg`]): a
//! simulator session's 3-D position error versus time next to the offline references
//! and its solution latency histogram; the realtime-vs-lockstep study's per-run
//! errors of both pacings, one run's error under both, and the pooled realtime
//! latencies. Each function returns `(file name, SVG text)` pairs; the caller writes
//! them (no file I/O in this crate).

use std::path::Path;

use fathom_report::plot::{Figure, Histogram, LinePlot, Series};

use crate::PilsError;
use crate::compare::Comparison;
use crate::report::unit;
use crate::session::SimSeries;

/// Latency histogram bins.
const LATENCY_BINS: usize = 40;

/// The per-run figures of the study: metric and file name.
const PER_RUN: [(&str, &str); 3] = [
    ("rmse_3d", "rmse_3d_per_run.svg"),
    ("rmse_h", "rmse_h_per_run.svg"),
    ("rmse_yaw", "rmse_yaw_per_run.svg"),
];

/// Renders `figure` as the file `name`.
fn svg(name: &'static str, figure: &impl Figure) -> Result<(&'static str, String), PilsError> {
    figure
        .to_svg(Path::new(name))
        .map(|text| (name, text))
        .map_err(|e| PilsError::model("figure", e))
}

/// The figures of one simulator session: `error_3d.svg` (3-D position error versus
/// time, PILS and the offline references; none without solutions) and `latency.svg`
/// (solution latency; none without latencies).
///
/// # Errors
/// [`PilsError::Model`] when a figure cannot be drawn.
pub fn session_figures(series: &SimSeries) -> Result<Vec<(&'static str, String)>, PilsError> {
    let mut out = Vec::new();
    let mut plot = LinePlot::new("3-D position error", "time (s)", "3-D error (m)");
    for (name, pts) in &series.error_3d {
        if !pts.is_empty() {
            plot.series.push(Series::new(*name, pts.clone()));
        }
    }
    if !plot.series.is_empty() {
        out.push(svg("error_3d.svg", &plot)?);
    }
    let ms: Vec<f64> = series
        .latencies_s
        .iter()
        .map(|s| s * 1e3)
        .filter(|v| v.is_finite())
        .collect();
    out.extend(latency_histogram(&ms, "solution latency", "latency.svg")?);
    out.extend(latency_tail(
        &ms,
        "solution latency tail",
        "latency_tail.svg",
    )?);
    Ok(out)
}

/// `(x, log10 P(latency > x))` at each finite latency `x` but the largest:
/// `P(latency > x_(i)) = (n - 1 - i) / n` for the sorted `x_(0..n)`.
fn latency_points(ms: &[f64]) -> Vec<(f64, f64)> {
    let mut sorted: Vec<f64> = ms.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len() as f64;
    sorted
        .iter()
        .enumerate()
        .take(sorted.len().saturating_sub(1))
        .map(|(i, &x)| (x, ((n - 1.0 - i as f64) / n).log10()))
        .collect()
}

/// The tail of the latencies `ms` as the file `name`: the fraction of answers later
/// than `x`, on a log10 axis (the histogram hides the rare long ones); nothing for
/// none.
fn latency_tail(
    ms: &[f64],
    title: &str,
    name: &'static str,
) -> Result<Option<(&'static str, String)>, PilsError> {
    let pts = latency_points(ms);
    if pts.is_empty() {
        return Ok(None);
    }
    let plot = LinePlot::new(
        format!("{title} ({} answers)", pts.len() + 1),
        "latency x (ms)",
        "log10 fraction of answers later than x",
    )
    .with_series(Series::new("latency", pts));
    svg(name, &plot).map(Some)
}

/// The histogram of the latencies `ms` as the file `name` (nothing for none).
fn latency_histogram(
    ms: &[f64],
    title: &str,
    name: &'static str,
) -> Result<Option<(&'static str, String)>, PilsError> {
    if ms.is_empty() {
        return Ok(None);
    }
    let counts =
        fathom_stats::Histogram::new(ms, LATENCY_BINS).map_err(|e| PilsError::model(name, e))?;
    let plot = Histogram::new(
        format!("{title} ({} answers)", ms.len()),
        "latency (ms)",
        "count",
        counts.edges,
        counts.counts.iter().map(|&c| c as f64).collect(),
    );
    svg(name, &plot).map(Some)
}

/// The figures of the realtime-vs-lockstep study: `rmse_{3d,h,yaw}_per_run.svg` (both
/// pacings per run), `error_3d_lockstep_vs_realtime.svg` (`example`: the first run's
/// 3-D error versus time per pacing; none when empty) and `latency_realtime.svg` (the
/// realtime latencies of all runs, `latencies_ms`; none when empty).
///
/// # Errors
/// [`PilsError::Model`] when a figure cannot be drawn.
pub fn study_figures(
    c: &Comparison,
    example: &[(&'static str, Vec<(f64, f64)>)],
    latencies_ms: &[f64],
) -> Result<Vec<(&'static str, String)>, PilsError> {
    let mut out = Vec::new();
    for (metric, name) in PER_RUN {
        let mut plot = LinePlot::new(
            format!("{metric} per run"),
            "run",
            format!("{metric} ({})", unit(metric)),
        );
        for label in ["lockstep", "realtime"] {
            let pts = c
                .runs
                .iter()
                .map(|r| {
                    let st = if label == "lockstep" {
                        &r.lockstep
                    } else {
                        &r.realtime
                    };
                    let v = st
                        .metrics()
                        .iter()
                        .find(|(n, _)| *n == metric)
                        .map_or(f64::NAN, |x| x.1);
                    (r.run as f64, v)
                })
                .collect();
            plot.series.push(Series::new(label, pts));
        }
        out.push(svg(name, &plot)?);
    }
    let first_run = c.runs.first().map_or(0, |r| r.run);
    let mut plot = LinePlot::new(
        format!("3-D position error, run {first_run}"),
        "time (s)",
        "3-D error (m)",
    );
    for (label, pts) in example {
        plot.series.push(Series::new(*label, pts.clone()));
    }
    if !plot.series.is_empty() {
        out.push(svg("error_3d_lockstep_vs_realtime.svg", &plot)?);
    }
    out.extend(latency_histogram(
        latencies_ms,
        "realtime solution latency, all runs",
        "latency_realtime.svg",
    )?);
    out.extend(latency_tail(
        latencies_ms,
        "realtime solution latency tail, all runs",
        "latency_tail_realtime.svg",
    )?);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::tests::pair;

    fn names(files: &[(&'static str, String)]) -> Vec<&'static str> {
        files.iter().map(|f| f.0).collect()
    }

    /// The figures come back as named SVG texts; a figure without data is left out.
    #[test]
    fn session_and_study_figures_are_svg_texts() {
        let series = SimSeries {
            error_3d: vec![
                ("PILS", vec![(0.0, 1.0), (0.01, 1.5)]),
                ("offline, f64", Vec::new()),
            ],
            latencies_s: vec![0.001, 0.002, f64::NAN, 0.0015],
        };
        let files = session_figures(&series).unwrap();
        assert_eq!(
            names(&files),
            ["error_3d.svg", "latency.svg", "latency_tail.svg"]
        );
        assert!(
            files.iter().all(|f| f.1.starts_with("<svg")),
            "{}",
            files[0].1
        );
        assert!(files[1].1.contains("3 answers"), "{}", files[1].1);
        assert!(session_figures(&SimSeries::default()).unwrap().is_empty());

        let c = Comparison::new(vec![pair(4, 1.0, 1.1), pair(5, 2.0, 2.2)], 0).unwrap();
        let example = [("lockstep", vec![(0.0, 1.0), (1.0, 2.0)])];
        let files = study_figures(&c, &example, &[20.0, 25.0, 40.0]).unwrap();
        assert_eq!(
            names(&files),
            [
                "rmse_3d_per_run.svg",
                "rmse_h_per_run.svg",
                "rmse_yaw_per_run.svg",
                "error_3d_lockstep_vs_realtime.svg",
                "latency_realtime.svg",
                "latency_tail_realtime.svg"
            ]
        );
        assert!(files[3].1.contains("run 4"));
        // The tail: 2 of 3 later than 20 ms, 1 of 3 later than 25 ms (log10 -0.18,
        // -0.48); the last has no logarithm.
        let points = latency_points(&[40.0, 20.0, 25.0]);
        assert_eq!(points.len(), 2);
        assert!(
            (points[0].0 - 20.0).abs() < 1e-12
                && (points[0].1 - (2.0f64 / 3.0).log10()).abs() < 1e-12
        );
        assert!(
            (points[1].0 - 25.0).abs() < 1e-12
                && (points[1].1 - (1.0f64 / 3.0).log10()).abs() < 1e-12
        );
        assert!(latency_points(&[5.0]).is_empty());
        assert_eq!(study_figures(&c, &[], &[]).unwrap().len(), 3);
    }
}

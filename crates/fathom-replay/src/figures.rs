//! The figures every replay writes (`fathom replay plaza | range-beacon | ins-dvl`),
//! drawn the same way for each: the estimated paths against the truth in plan view,
//! the position error over time with the filter's 3σ, the innovations over time with
//! their ±3√S, and the NIS over time against the interval of a consistent filter.
//!
//! Each replay turns its own results into the plain series here (one [`Series`] colour
//! per method, the same in every figure) and hands them to these functions, which add
//! the SVG files to the [`Analysis`]. Long series are thinned to at most
//! [`MAX_POINTS`] points per curve (the CSV files keep every value).

use fathom_report::plot::{Band, LinePlot, PlanPlot, Series};
use fathom_sim::SimError;
use fathom_sim::experiment::Analysis;
use fathom_stats::ChiSquareBounds;

/// The most points drawn per curve.
pub const MAX_POINTS: usize = 2500;

/// The palette index of the curves that are not a method's (the truth, bounds).
const GREY: usize = 7;

/// The step that keeps at most [`MAX_POINTS`] of `n` points.
pub fn thin(n: usize) -> usize {
    n.div_ceil(MAX_POINTS).max(1)
}

/// One method's estimated path in plan view.
#[derive(Debug, Clone, PartialEq)]
pub struct Path<'a> {
    /// Method name (legend).
    pub name: &'a str,
    /// Palette index of the method's colour.
    pub color: usize,
    /// `(horizontal, vertical)` points of the plot, in time order.
    pub points: Vec<(f64, f64)>,
}

/// Adds the plan view `name`: the true path (grey) and every method's path, with
/// `markers` (e.g. beacons) when given. Points are `(horizontal, vertical)`: for NED
/// pass `(east, north)` and label the axes so.
///
/// # Errors
/// The figure's own errors (empty or non-finite points).
pub fn plan_view(
    out: &mut Analysis,
    name: &str,
    title: &str,
    axes: (&str, &str),
    truth: &[(f64, f64)],
    paths: &[Path<'_>],
    markers: Option<Series>,
) -> Result<(), SimError> {
    plan_view_with(out, name, title, axes, ("truth", truth), paths, markers)
}

/// As [`plan_view`], the grey reference path labelled `reference.0` (`"truth"`, or
/// another estimate such as an autopilot's when the log has no truth).
///
/// # Errors
/// The figure's own errors (empty or non-finite points).
pub fn plan_view_with(
    out: &mut Analysis,
    name: &str,
    title: &str,
    axes: (&str, &str),
    reference: (&str, &[(f64, f64)]),
    paths: &[Path<'_>],
    markers: Option<Series>,
) -> Result<(), SimError> {
    let (label, truth) = reference;
    let step = thin(truth.len());
    let mut plan = PlanPlot::new(title, axes.0, axes.1).with_path(
        Series::new(label, truth.iter().step_by(step).copied().collect()).with_color(GREY),
    );
    for p in paths {
        let step = thin(p.points.len());
        plan = plan.with_path(
            Series::new(p.name, p.points.iter().step_by(step).copied().collect())
                .with_color(p.color),
        );
    }
    if let Some(m) = markers {
        plan = plan.with_markers(m);
    }
    out.figure(name, &plan)
}

/// One method's position error over time and, for a filter, its σ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorTrack<'a> {
    /// Method name (legend).
    pub name: &'a str,
    /// Palette index of the method's colour.
    pub color: usize,
    /// The error at the recording instants, m.
    pub errors: &'a [f64],
    /// The filter's standard deviation of the same error at the instants
    /// (`sqrt(P_nn + P_ee)` for a horizontal error), m; `None` without covariance.
    pub sigma: Option<&'a [f64]>,
}

/// The top of the error axis: the largest error, or the 95th percentile of the
/// tightest method's 3σ if that is higher, plus 10 %; so that a band much wider than
/// every error (dead reckoning's) does not flatten the others.
fn error_axis_top(tracks: &[ErrorTrack<'_>]) -> Option<f64> {
    let max_error = tracks
        .iter()
        .flat_map(|t| t.errors.iter().copied())
        .filter(|e| e.is_finite())
        .fold(0.0, f64::max);
    let tightest = tracks
        .iter()
        .filter_map(|t| t.sigma)
        .filter_map(|s| {
            let mut v: Vec<f64> = s.iter().copied().filter(|x| x.is_finite()).collect();
            v.sort_by(f64::total_cmp);
            v.get((v.len() * 95 / 100).min(v.len().saturating_sub(1)))
                .map(|x| 3.0 * x)
        })
        .reduce(f64::min)
        .unwrap_or(0.0);
    let top = 1.1 * max_error.max(tightest);
    (top > 0.0 && top.is_finite()).then_some(top)
}

/// Adds `name`: every method's error over `times` with its band `[0, 3σ]` (a
/// consistent filter's error stays inside it nearly always).
///
/// # Errors
/// Series of different lengths, or the figure's own errors.
pub fn error_3sigma(
    out: &mut Analysis,
    name: &str,
    title: &str,
    times: &[f64],
    tracks: &[ErrorTrack<'_>],
) -> Result<(), SimError> {
    let step = thin(times.len());
    let mut plot = LinePlot::new(title, "time since start (s)", "error (m)")
        .with_band_label("band: 0 to 3σ of the filter's covariance");
    for tr in tracks {
        if tr.errors.len() != times.len() || tr.sigma.is_some_and(|s| s.len() != times.len()) {
            return Err(SimError::invalid_argument(
                format!("figure `{name}`"),
                format!("method `{}`: series and times differ in length", tr.name),
            ));
        }
        let k = plot.series.len();
        let pts = times
            .iter()
            .zip(tr.errors)
            .step_by(step)
            .map(|(t, e)| (*t, *e));
        plot = plot.with_series(Series::new(tr.name, pts.collect()).with_color(tr.color));
        if let Some(sigma) = tr.sigma {
            let band: Band = times
                .iter()
                .zip(sigma)
                .step_by(step)
                .filter(|(_, s)| s.is_finite())
                .map(|(t, s)| (*t, 0.0, 3.0 * s))
                .collect();
            plot = plot.with_band(k, band);
        }
    }
    plot.y_range = error_axis_top(tracks).map(|top| (0.0, top));
    out.figure(name, &plot)
}

/// One tested measurement (or one component of a vector measurement).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tested {
    /// Time since the start, s.
    pub time: f64,
    /// Measurement minus prediction, when known (a rejected vector update has none).
    pub innovation: Option<f64>,
    /// `sqrt(S)` of the innovation, when known.
    pub sigma: Option<f64>,
    /// Normalized innovation squared of the whole measurement.
    pub nis: f64,
}

/// One method's tested measurements of one kind, in time order.
#[derive(Debug, Clone, PartialEq)]
pub struct InnovationTrack<'a> {
    /// Method name (legend).
    pub name: &'a str,
    /// Palette index of the method's colour.
    pub color: usize,
    /// The measurements.
    pub tested: Vec<Tested>,
}

/// Adds `name`: every method's innovations over time with the band ±3√S the filter
/// predicted for them. Methods without a known innovation are left out; nothing is
/// written when none has one. Returns whether the figure was added.
///
/// # Errors
/// The figure's own errors.
pub fn innovations(
    out: &mut Analysis,
    name: &str,
    title: &str,
    y_label: &str,
    tracks: &[InnovationTrack<'_>],
) -> Result<bool, SimError> {
    let mut plot = LinePlot::new(title, "time since start (s)", y_label)
        .with_band_label("band: ±3√S (the filter's prediction)");
    for tr in tracks {
        let known: Vec<(f64, f64, Option<f64>)> = tr
            .tested
            .iter()
            .filter_map(|x| {
                x.innovation
                    .filter(|v| v.is_finite())
                    .map(|v| (x.time, v, x.sigma))
            })
            .collect();
        if known.is_empty() {
            continue;
        }
        let step = thin(known.len());
        let k = plot.series.len();
        let pts = known.iter().step_by(step).map(|(t, v, _)| (*t, *v));
        plot = plot.with_series(Series::new(tr.name, pts.collect()).with_color(tr.color));
        let band: Band = known
            .iter()
            .step_by(step)
            .filter_map(|(t, _, s)| s.filter(|s| s.is_finite()).map(|s| (*t, -3.0 * s, 3.0 * s)))
            .collect();
        plot = plot.with_band(k, band);
    }
    if plot.series.is_empty() {
        return Ok(false);
    }
    out.figure(name, &plot)?;
    Ok(true)
}

/// The number of consecutive measurements whose NIS is averaged into one point of
/// [`nis`], for a method with `n` of them: about a hundred points, each the mean of
/// 10 to 200 values.
pub fn nis_window(n: usize) -> usize {
    (n / 100).clamp(10, 200).min(n).max(1)
}

/// Adds `name`: every method's NIS per degree of freedom (`dof` per measurement),
/// averaged over blocks of consecutive measurements ([`nis_window`] of the method
/// with the fewest), against the 95 % interval of that average for a consistent
/// filter (chi-square, [`ChiSquareBounds::time_average`]). Nothing is written when no
/// method has a finite NIS. Returns whether the figure was added.
///
/// # Errors
/// A zero `dof`, or the figure's own errors.
pub fn nis(
    out: &mut Analysis,
    name: &str,
    title: &str,
    dof: usize,
    tracks: &[InnovationTrack<'_>],
) -> Result<bool, SimError> {
    let finite: Vec<(&InnovationTrack<'_>, Vec<(f64, f64)>)> = tracks
        .iter()
        .map(|tr| {
            let v = tr
                .tested
                .iter()
                .filter(|x| x.nis.is_finite())
                .map(|x| (x.time, x.nis))
                .collect::<Vec<_>>();
            (tr, v)
        })
        .filter(|(_, v)| !v.is_empty())
        .collect();
    let Some(fewest) = finite.iter().map(|(_, v)| v.len()).min() else {
        return Ok(false);
    };
    let w = nis_window(fewest);
    let bounds = ChiSquareBounds::time_average(dof, w).map_err(|e| {
        SimError::model(
            format!("figure `{name}`: the consistent filter's interval"),
            e,
        )
    })?;
    let d = dof as f64;
    let mut plot = LinePlot::new(
        format!("{title} (mean of {w} consecutive, per dof)"),
        "time since start (s)",
        "NIS / dof",
    );
    let (mut t_lo, mut t_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (tr, v) in &finite {
        let pts: Vec<(f64, f64)> = v
            .chunks_exact(w)
            .map(|c| {
                let t = c[c.len() / 2].0;
                let mean = c.iter().map(|x| x.1).sum::<f64>() / (w as f64 * d);
                (t, mean)
            })
            .collect();
        if let (Some(a), Some(b)) = (pts.first(), pts.last()) {
            t_lo = t_lo.min(a.0);
            t_hi = t_hi.max(b.0);
            plot = plot.with_series(Series::new(tr.name, pts).with_color(tr.color));
        }
    }
    if plot.series.is_empty() {
        return Ok(false);
    }
    for (label, y) in [
        ("consistent filter: 2.5 %", bounds.lo / d),
        ("consistent filter: 97.5 %", bounds.hi / d),
    ] {
        plot = plot.with_series(Series::new(label, vec![(t_lo, y), (t_hi, y)]).with_color(GREY));
    }
    out.figure(name, &plot)?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(nis: &[f64]) -> InnovationTrack<'static> {
        InnovationTrack {
            name: "F",
            color: 0,
            tested: nis
                .iter()
                .enumerate()
                .map(|(k, &n)| Tested {
                    time: k as f64,
                    innovation: Some(n.sqrt()),
                    sigma: Some(1.0),
                    nis: n,
                })
                .collect(),
        }
    }

    #[test]
    fn thinning_and_windows() {
        assert_eq!(thin(0), 1);
        assert_eq!(thin(MAX_POINTS), 1);
        assert_eq!(thin(MAX_POINTS + 1), 2);
        assert_eq!(nis_window(5), 5);
        assert_eq!(nis_window(300), 10);
        assert_eq!(nis_window(5_000), 50);
        assert_eq!(nis_window(1_000_000), 200);
    }

    #[test]
    fn a_band_much_wider_than_every_error_does_not_set_the_error_axis() {
        let e = [0.1, 0.4, 0.2];
        let track = |sigma: &'static [f64]| ErrorTrack {
            name: "F",
            color: 0,
            errors: &e,
            sigma: Some(sigma),
        };
        // Dead reckoning's 3σ (90 m) is left out; the tightest filter's (2.1 m) shows.
        let top = error_axis_top(&[track(&[30.0; 3]), track(&[0.5, 0.6, 0.7])]).unwrap();
        assert!((top - 1.1 * 3.0 * 0.7).abs() < 1e-12, "{top}");
        // Without covariance the largest error sets it.
        let none = ErrorTrack {
            sigma: None,
            ..track(&[1.0])
        };
        assert!((error_axis_top(&[none]).unwrap() - 0.44).abs() < 1e-12);
    }

    #[test]
    fn figures_are_added_only_with_data() {
        let mut out = Analysis::new();
        let t = [0.0, 1.0, 2.0];
        let e = [0.1, 0.2, 0.3];
        let s = [0.1, 0.1, f64::NAN];
        error_3sigma(
            &mut out,
            "e.svg",
            "error",
            &t,
            &[ErrorTrack {
                name: "F",
                color: 0,
                errors: &e,
                sigma: Some(&s),
            }],
        )
        .unwrap();
        // Lengths that differ are an error, not a panic.
        assert!(
            error_3sigma(
                &mut out,
                "e2.svg",
                "error",
                &t[..2],
                &[ErrorTrack {
                    name: "F",
                    color: 0,
                    errors: &e,
                    sigma: None,
                }],
            )
            .is_err()
        );
        let ok = track(&[1.0; 30]);
        assert!(innovations(&mut out, "i.svg", "inn", "m", std::slice::from_ref(&ok)).unwrap());
        assert!(nis(&mut out, "n.svg", "nis", 1, &[ok]).unwrap());
        // No tested measurement (dead reckoning): no figure.
        let empty = track(&[]);
        assert!(
            !innovations(&mut out, "i2.svg", "inn", "m", std::slice::from_ref(&empty)).unwrap()
        );
        assert!(!nis(&mut out, "n2.svg", "nis", 1, &[empty]).unwrap());
        let names: Vec<&str> = out.files().iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["e.svg", "i.svg", "n.svg"]);
        assert!(nis(&mut out, "n3.svg", "nis", 0, &[track(&[1.0])]).is_err());
    }
}

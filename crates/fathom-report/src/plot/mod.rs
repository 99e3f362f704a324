//! SVG figures (plotters' SVG backend, written to files): line plots, plan-view paths,
//! histograms, heat maps and sample-time diagrams.
//!
//! All plots are described by plain structs with public fields and written with
//! `write_svg(path)`. Input is checked first: empty data, NaN / infinite values and
//! inconsistent sizes are [`ReportError::Plot`] errors naming the series and point, never
//! panics. The SVG is rendered into memory and then written (parent directories are
//! created), so I/O failures are [`ReportError::Io`] with the path.
//!
//! Text: plotters is built without a font feature, so it uses its built-in text-size
//! estimate for layout and emits real SVG `<text>` elements (font family `sans-serif`);
//! the viewer picks the font. No font file is embedded.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::ReportError;
use crate::output::write_text;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// Default figure size in pixels (width, height).
pub const DEFAULT_SIZE: (u32, u32) = (900, 560);

const FONT: &str = "sans-serif";

/// Distinct series colours (matplotlib "tab10").
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The `k`-th series colour (cycles after 10).
pub fn series_color(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// A named sequence of `(x, y)` points.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// The points, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// Palette index of its colour (default: its place in the plot), so that one
    /// method keeps one colour across figures that show different subsets.
    pub color: Option<usize>,
}

impl Series {
    /// A series from points.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            color: None,
        }
    }

    /// A series from separate x and y slices.
    ///
    /// # Errors
    /// [`ReportError::InvalidArgument`] if the lengths differ.
    pub fn from_xy(name: impl Into<String>, xs: &[f64], ys: &[f64]) -> Result<Self, ReportError> {
        let name = name.into();
        if xs.len() != ys.len() {
            return Err(ReportError::invalid_argument(
                format!("series `{name}`"),
                format!("{} x values but {} y values", xs.len(), ys.len()),
            ));
        }
        Ok(Series {
            name,
            points: xs.iter().copied().zip(ys.iter().copied()).collect(),
            color: None,
        })
    }

    /// The series drawn in palette colour `k` ([`series_color`]) wherever it stands.
    pub fn with_color(mut self, k: usize) -> Self {
        self.color = Some(k);
        self
    }

    /// Its colour when it is the `k`-th series of a plot.
    pub(crate) fn color_at(&self, k: usize) -> RGBColor {
        series_color(self.color.unwrap_or(k))
    }
}

/// A confidence band: `(x, lo, hi)` per point.
pub type Band = Vec<(f64, f64, f64)>;

/// An axis tick label: integers without a decimal point (`200`, not `200.0`), other
/// values with at most six decimals and no trailing zeros, tiny ones in scientific
/// notation, and never `-0`.
pub(crate) fn tick(v: &f64) -> String {
    let v = *v;
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_string();
    }
    if v.abs() < 1e-4 {
        return format!("{v:.2e}");
    }
    if (v - v.round()).abs() <= 1e-9 * v.abs().max(1.0) {
        return format!("{}", v.round());
    }
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

fn plot_err(path: &Path, reason: impl Into<String>) -> ReportError {
    ReportError::Plot {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Map any drawing-backend error to a string (used with `?` inside draw closures).
fn de<E: std::fmt::Display>(e: E) -> String {
    format!("drawing failed: {e}")
}

fn check_finite(path: &Path, what: &str, v: f64) -> Result<(), ReportError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(plot_err(path, format!("{what} is not finite ({v})")))
    }
}

fn check_series(path: &Path, kind: &str, series: &[Series]) -> Result<(), ReportError> {
    if series.is_empty() {
        return Err(plot_err(path, format!("no {kind} to draw")));
    }
    for s in series {
        if s.points.is_empty() {
            return Err(plot_err(path, format!("{kind} `{}` is empty", s.name)));
        }
        for (i, &(x, y)) in s.points.iter().enumerate() {
            check_finite(path, &format!("{kind} `{}` point {i} x", s.name), x)?;
            check_finite(path, &format!("{kind} `{}` point {i} y", s.name), y)?;
        }
    }
    Ok(())
}

fn check_size(path: &Path, size: (u32, u32)) -> Result<(), ReportError> {
    if size.0 < 200 || size.1 < 150 {
        return Err(plot_err(
            path,
            format!(
                "figure size {}x{} px is too small (min 200x150)",
                size.0, size.1
            ),
        ));
    }
    Ok(())
}

/// Range of values padded by 5 % (a degenerate range is widened around its value).
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let span = hi - lo;
    if span > 0.0 {
        (lo - 0.05 * span, hi + 0.05 * span)
    } else {
        let d = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
        (lo - d, hi + d)
    }
}

fn min_max(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    })
}

/// Render into memory with `draw`; `path` labels errors.
fn render(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area<'_>) -> Result<(), String>,
) -> Result<String, ReportError> {
    check_size(path, size)?;
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, de(e)))?;
        draw(&root).map_err(|e| plot_err(path, e))?;
        root.present().map_err(|e| plot_err(path, de(e)))?;
    }
    Ok(buf)
}

fn checked_range(path: &Path, what: &str, (a, b): (f64, f64)) -> Result<(f64, f64), ReportError> {
    if a.is_finite() && b.is_finite() && a < b {
        Ok((a, b))
    } else {
        Err(plot_err(
            path,
            format!("{what} ({a}, {b}) must be finite with lo < hi"),
        ))
    }
}

/// A figure that renders itself as SVG text.
pub trait Figure {
    /// The SVG text; `label` names the figure in error messages (its file name).
    ///
    /// # Errors
    /// [`ReportError::Plot`] on empty / non-finite data or a drawing failure.
    fn to_svg(&self, label: &Path) -> Result<String, ReportError>;

    /// Renders and writes the SVG file `path` (parent directories are created).
    ///
    /// # Errors
    /// As [`Figure::to_svg`], then [`ReportError::Io`].
    fn write_svg(&self, path: impl AsRef<Path>) -> Result<(), ReportError>
    where
        Self: Sized,
    {
        let path = path.as_ref();
        write_text(path, &self.to_svg(path)?)
    }
}

macro_rules! impl_figure {
    ($($ty:ty),*) => {
        $(impl Figure for $ty {
            fn to_svg(&self, label: &Path) -> Result<String, ReportError> {
                self.render_svg(label)
            }
        })*
    };
}

impl_figure!(LinePlot, PlanPlot, Histogram, HeatMap, Timeline);

fn title_style(size: u32) -> TextStyle<'static> {
    (FONT, size).into_font().into()
}

fn text_style(size: u32, h: HPos, v: VPos) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font()).pos(Pos::new(h, v))
}

mod heatmap;
mod histogram;
mod line;
mod plan;
mod timeline;

pub use heatmap::{HeatMap, heat_color};
pub use histogram::Histogram;
pub use line::LinePlot;
pub use plan::PlanPlot;
pub use timeline::Timeline;

#[cfg(test)]
mod tests {
    use super::*;

    fn dir() -> std::path::PathBuf {
        std::env::temp_dir().join("fathom-sim-tests").join("plot")
    }

    /// Whether `t` is the content of a `<text>` element (plotters puts it on its own line).
    fn has_text(svg: &str, t: &str) -> bool {
        svg.contains(&format!("\n{t}\n</text>")) || svg.contains(&format!(">{t}</text>"))
    }

    fn read_svg(p: &Path, title: &str) -> String {
        let s = std::fs::read_to_string(p).unwrap();
        assert!(
            s.trim_start().starts_with("<svg"),
            "{}",
            &s[..s.len().min(200)]
        );
        assert!(s.trim_end().ends_with("</svg>"));
        assert!(
            has_text(&s, title),
            "title `{title}` missing in {}",
            p.display()
        );
        s
    }

    fn sine(name: &str, k: f64) -> Series {
        Series::new(
            name,
            (0..100)
                .map(|i| (f64::from(i) * 0.1, (k * f64::from(i) * 0.1).sin()))
                .collect(),
        )
    }

    #[test]
    fn line_plot_writes_svg_with_legend() {
        let p = dir().join("line.svg");
        LinePlot::new("Error versus time", "time [s]", "3D error [m]")
            .with_series(sine("MF", 1.0))
            .with_series(sine("EFF", 2.0))
            .with_shade(2.0, 3.0)
            .with_marker(5.0)
            .write_svg(&p)
            .unwrap();
        let s = read_svg(&p, "Error versus time");
        assert!(has_text(&s, "MF") && has_text(&s, "EFF"), "legend missing");
        assert!(has_text(&s, "time [s]"));
    }

    #[test]
    fn line_plot_rejects_empty_and_nan() {
        let p = dir().join("bad_line.svg");
        let e = LinePlot::new("t", "x", "y").write_svg(&p).unwrap_err();
        assert!(matches!(e, ReportError::Plot { .. }), "{e}");
        let e = LinePlot::new("t", "x", "y")
            .with_series(Series::new("MF", vec![]))
            .write_svg(&p)
            .unwrap_err();
        assert!(e.to_string().contains("`MF` is empty"), "{e}");
        let e = LinePlot::new("t", "x", "y")
            .with_series(Series::new("MF", vec![(0.0, 1.0), (1.0, f64::NAN)]))
            .write_svg(&p)
            .unwrap_err();
        assert!(e.to_string().contains("`MF` point 1 y"), "{e}");
        let mut lp = LinePlot::new("t", "x", "y").with_series(sine("a", 1.0));
        lp.y_range = Some((1.0, 1.0));
        assert!(lp.write_svg(&p).is_err());
        assert!(Series::from_xy("a", &[1.0], &[]).is_err());
    }

    #[test]
    fn single_point_and_constant_series_are_drawn() {
        let p = dir().join("const.svg");
        LinePlot::new("Constant", "x", "y")
            .with_series(Series::new("c", vec![(1.0, 2.0)]))
            .write_svg(&p)
            .unwrap();
        read_svg(&p, "Constant");
    }

    #[test]
    fn plan_plot_writes_svg() {
        let p = dir().join("plan.svg");
        PlanPlot::new("Plan view", "east [m]", "north [m]")
            .with_path(Series::new(
                "truth",
                vec![(0.0, 0.0), (10.0, 5.0), (20.0, 0.0)],
            ))
            .with_path(Series::new(
                "SC",
                vec![(0.0, 0.5), (10.0, 5.5), (20.0, 0.2)],
            ))
            .with_markers(Series::new("beacons", vec![(-5.0, -5.0), (25.0, 8.0)]))
            .write_svg(&p)
            .unwrap();
        let s = read_svg(&p, "Plan view");
        assert!(has_text(&s, "beacons"));
        let e = PlanPlot::new("x", "e", "n").write_svg(&p).unwrap_err();
        assert!(matches!(e, ReportError::Plot { .. }));
        let e = PlanPlot::new("x", "e", "n")
            .with_markers(Series::new("b", vec![(f64::INFINITY, 0.0)]))
            .write_svg(&p)
            .unwrap_err();
        assert!(e.to_string().contains("`b` point 0 x"), "{e}");
    }

    #[test]
    fn histogram_writes_svg_and_checks_input() {
        let p = dir().join("hist.svg");
        Histogram::new(
            "Error histogram",
            "3D error [m]",
            "count",
            vec![0.0, 0.5, 1.0, 1.5],
            vec![3.0, 10.0, 2.0],
        )
        .write_svg(&p)
        .unwrap();
        read_svg(&p, "Error histogram");
        let h = |e: Vec<f64>, c: Vec<f64>| Histogram::new("h", "x", "n", e, c).write_svg(&p);
        assert!(h(vec![0.0], vec![]).is_err());
        assert!(h(vec![0.0, 1.0], vec![1.0, 2.0]).is_err());
        assert!(h(vec![0.0, 1.0, 1.0], vec![1.0, 2.0]).is_err());
        assert!(h(vec![0.0, 1.0], vec![f64::NAN]).is_err());
        assert!(h(vec![0.0, 1.0], vec![-1.0]).is_err());
    }

    #[test]
    fn heat_map_writes_values_and_labels() {
        let p = dir().join("heat.svg");
        let labels: Vec<String> = (1..=3).map(|i| format!("r{i}")).collect();
        let mut hm = HeatMap::new(
            "Sample covariance",
            labels.clone(),
            labels,
            vec![
                vec![1.0, 0.5, 0.25],
                vec![0.5, 1.0, 0.125],
                vec![0.25, 0.125, 2.0],
            ],
        );
        hm.value_label = "cov [m^2]".into();
        hm.write_svg(&p).unwrap();
        let s = read_svg(&p, "Sample covariance");
        assert!(
            has_text(&s, "0.125")
                && has_text(&s, "1.000")
                && has_text(&s, "r3")
                && has_text(&s, "cov [m^2]")
        );
        let mut bad = hm.clone();
        bad.values[1][2] = f64::NAN;
        assert!(
            bad.write_svg(&p)
                .unwrap_err()
                .to_string()
                .contains("(1, 2)")
        );
        let mut bad = hm.clone();
        bad.values[2].pop();
        assert!(bad.write_svg(&p).is_err());
        let mut bad = hm;
        bad.values.clear();
        assert!(bad.write_svg(&p).is_err());
    }

    #[test]
    fn timeline_writes_rows_and_checks_input() {
        let p = dir().join("timeline.svg");
        let rows = vec![
            (
                "DVL".to_string(),
                (0..20).map(|i| f64::from(i) * 0.5).collect(),
            ),
            (
                "beacon".to_string(),
                (0..10).map(|i| f64::from(i) * 1.1 + 0.3).collect(),
            ),
        ];
        Timeline::new("Sample times", "time [s]", rows.clone(), Some((0.0, 5.0)))
            .write_svg(&p)
            .unwrap();
        let s = read_svg(&p, "Sample times");
        assert!(has_text(&s, "DVL") && has_text(&s, "beacon"));
        assert!(Timeline::new("t", "x", vec![], None).write_svg(&p).is_err());
        assert!(
            Timeline::new("t", "x", rows.clone(), Some((1.0, 0.0)))
                .write_svg(&p)
                .is_err()
        );
        assert!(
            Timeline::new("t", "x", vec![("a".into(), vec![f64::NAN])], None)
                .write_svg(&p)
                .is_err()
        );
        assert!(
            Timeline::new("t", "x", vec![("a".into(), vec![])], None)
                .write_svg(&p)
                .is_err()
        );
    }

    #[test]
    fn heat_colors_span_the_map() {
        assert_eq!(heat_color(0.0), RGBColor(68, 1, 84));
        assert_eq!(heat_color(1.0), RGBColor(253, 231, 37));
        assert_eq!(heat_color(f64::NAN), heat_color(0.0));
    }

    #[test]
    fn tick_labels_drop_needless_decimals() {
        for (v, s) in [
            (200.0, "200"),
            (-0.0, "0"),
            (1e-12, "1.00e-12"),
            (0.1 + 0.2, "0.3"),
            (0.00998, "0.00998"),
            (-2.5, "-2.5"),
            (3e-6, "3.00e-6"),
        ] {
            assert_eq!(tick(&v), s, "{v}");
        }
        // Negative control: a value that is not an integer keeps its decimals.
        assert_ne!(tick(&200.5), "200");
    }

    #[test]
    fn coinciding_curves_are_named_dashed_and_bands_drawn() {
        let a = Series::new("A", vec![(0.0, 1.0), (1.0, 2.0)]);
        let b = Series::new("B", vec![(0.0, 1.0005), (1.0, 2.0)]);
        let c = Series::new("C", vec![(0.0, 1.5), (1.0, 2.0)]);
        let labels = line::legend_labels(&[a.clone(), b.clone(), c.clone()], 0.0, 0.01);
        assert_eq!(labels[0], ("A".to_string(), false));
        assert_eq!(labels[1], ("B (on A)".to_string(), true));
        // Negative control: C leaves A by 0.5 > 0.01.
        assert_eq!(labels[2], ("C".to_string(), false));
        // Nine of ten points on D: "mostly on"; five of ten: not.
        let d = Series::new("D", (0..10).map(|i| (f64::from(i), 0.0)).collect());
        let e = Series::new(
            "E",
            (0..10)
                .map(|i| (f64::from(i), if i == 9 { 1.0 } else { 0.0 }))
                .collect(),
        );
        let f = Series::new(
            "F",
            (0..10)
                .map(|i| (f64::from(i), if i < 5 { 1.0 } else { 0.0 }))
                .collect(),
        );
        let labels = line::legend_labels(&[d, e, f], 0.0, 0.01);
        assert_eq!(labels[1], ("E (mostly on D)".to_string(), true));
        assert_eq!(labels[2], ("F".to_string(), false));

        let p = dir().join("band.svg");
        let plot = LinePlot::new("t", "time (s)", "error (m)")
            .with_series(a)
            .with_series(b)
            .with_shade(0.2, 0.4)
            .with_shade_label("DVL invalid")
            .with_band(0, vec![(0.0, 0.5, 1.5), (1.0, 1.5, 2.5)]);
        std::fs::create_dir_all(dir()).unwrap();
        let svg = plot.render_svg(&p).unwrap();
        for t in ["B (on A)", "DVL invalid", "band: 95 % CI of the mean"] {
            assert!(has_text(&svg, t), "{t}");
        }
        assert!(svg.contains("<polygon"), "no band polygon");
    }
}

//! SVG figures (plotters' SVG backend, written to files): line plots, plan-view paths,
//! histograms, heat maps and sample-time diagrams.
//!
//! All plots are described by plain structs with public fields and written with
//! `write_svg(path)`. Input is checked first: empty data, NaN / infinite values and
//! inconsistent sizes are [`SimError::Plot`] errors naming the series and point, never
//! panics. The SVG is rendered into memory and then written (parent directories are
//! created), so I/O failures are [`SimError::Io`] with the path.
//!
//! Text: plotters is built without a font feature, so it uses its built-in text-size
//! estimate for layout and emits real SVG `<text>` elements (font family `sans-serif`);
//! the viewer picks the font. No font file is embedded.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::SimError;
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
}

impl Series {
    /// A series from points.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
        }
    }

    /// A series from separate x and y slices.
    ///
    /// # Errors
    /// [`SimError::InvalidArgument`] if the lengths differ.
    pub fn from_xy(name: impl Into<String>, xs: &[f64], ys: &[f64]) -> Result<Self, SimError> {
        let name = name.into();
        if xs.len() != ys.len() {
            return Err(SimError::invalid_argument(
                format!("series `{name}`"),
                format!("{} x values but {} y values", xs.len(), ys.len()),
            ));
        }
        Ok(Series {
            name,
            points: xs.iter().copied().zip(ys.iter().copied()).collect(),
        })
    }
}

fn plot_err(path: &Path, reason: impl Into<String>) -> SimError {
    SimError::Plot {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Map any drawing-backend error to a string (used with `?` inside draw closures).
fn de<E: std::fmt::Display>(e: E) -> String {
    format!("drawing failed: {e}")
}

fn check_finite(path: &Path, what: &str, v: f64) -> Result<(), SimError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(plot_err(path, format!("{what} is not finite ({v})")))
    }
}

fn check_series(path: &Path, kind: &str, series: &[Series]) -> Result<(), SimError> {
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

fn check_size(path: &Path, size: (u32, u32)) -> Result<(), SimError> {
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
) -> Result<String, SimError> {
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

/// A figure that renders itself as SVG text.
pub trait Figure {
    /// The SVG text; `label` names the figure in error messages (its file name).
    ///
    /// # Errors
    /// [`SimError::Plot`] on empty / non-finite data or a drawing failure.
    fn to_svg(&self, label: &Path) -> Result<String, SimError>;

    /// Renders and writes the SVG file `path` (parent directories are created).
    ///
    /// # Errors
    /// As [`Figure::to_svg`], then [`SimError::Io`].
    fn write_svg(&self, path: impl AsRef<Path>) -> Result<(), SimError>
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
            fn to_svg(&self, label: &Path) -> Result<String, SimError> {
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

/// Line plot of several named series with optional shaded x-intervals and vertical
/// markers (e.g. error versus time with course changes marked).
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Figure title.
    pub title: String,
    /// x-axis label (with unit, e.g. `"time [s]"`).
    pub x_label: String,
    /// y-axis label (with unit).
    pub y_label: String,
    /// The series (one colour and legend entry each).
    pub series: Vec<Series>,
    /// Shaded x-intervals `(from, to)` drawn behind the series.
    pub shaded_x: Vec<(f64, f64)>,
    /// x positions of vertical marker lines.
    pub markers_x: Vec<f64>,
    /// Fixed y range `(lo, hi)`; `None` fits the data.
    pub y_range: Option<(f64, f64)>,
    /// Fixed x range `(lo, hi)` (e.g. a zoom window); `None` fits the data.
    pub x_range: Option<(f64, f64)>,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl LinePlot {
    /// An empty plot with the default size.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        LinePlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            shaded_x: Vec::new(),
            markers_x: Vec::new(),
            y_range: None,
            x_range: None,
            size: DEFAULT_SIZE,
        }
    }

    /// Add a series.
    pub fn with_series(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Add a shaded x-interval.
    pub fn with_shade(mut self, from: f64, to: f64) -> Self {
        self.shaded_x.push((from, to));
        self
    }

    /// Add a vertical marker line.
    pub fn with_marker(mut self, x: f64) -> Self {
        self.markers_x.push(x);
        self
    }

    /// Draw the plot into an SVG file.
    ///
    /// # Errors
    /// [`SimError::Plot`] on empty / non-finite data, [`SimError::Io`] on write failure.
    fn render_svg(&self, path: &Path) -> Result<String, SimError> {
        check_series(path, "series", &self.series)?;
        for (i, &(a, b)) in self.shaded_x.iter().enumerate() {
            check_finite(path, &format!("shaded interval {i} start"), a)?;
            check_finite(path, &format!("shaded interval {i} end"), b)?;
        }
        for (i, &m) in self.markers_x.iter().enumerate() {
            check_finite(path, &format!("marker {i}"), m)?;
        }
        let pts = || self.series.iter().flat_map(|s| s.points.iter().copied());
        let (x0, x1) = match self.x_range {
            Some(r) => checked_range(path, "x_range", r)?,
            None => {
                let (a, b) = min_max(pts().map(|p| p.0));
                if b > a { (a, b) } else { padded(a, b) }
            }
        };
        let (y0, y1) = match self.y_range {
            Some(r) => checked_range(path, "y_range", r)?,
            None => {
                let in_x = pts().filter(|p| p.0 >= x0 && p.0 <= x1).map(|p| p.1);
                let (a, b) = min_max(in_x);
                if a.is_finite() {
                    padded(a, b)
                } else {
                    (0.0, 1.0)
                }
            }
        };
        render(path, self.size, |root| {
            let mut chart = ChartBuilder::on(root)
                .caption(&self.title, title_style(22))
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(de)?;
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .light_line_style(RGBColor(235, 235, 235))
                .axis_desc_style((FONT, 17))
                .label_style((FONT, 15))
                .draw()
                .map_err(de)?;
            let shade = RGBColor(120, 120, 120).mix(0.18).filled();
            chart
                .draw_series(
                    self.shaded_x
                        .iter()
                        .map(|&(a, b)| Rectangle::new([(a.max(x0), y0), (b.min(x1), y1)], shade)),
                )
                .map_err(de)?;
            let mark = RGBColor(60, 60, 60).mix(0.7).stroke_width(1);
            chart
                .draw_series(
                    self.markers_x
                        .iter()
                        .map(|&m| PathElement::new(vec![(m, y0), (m, y1)], mark)),
                )
                .map_err(de)?;
            for (k, s) in self.series.iter().enumerate() {
                let c = series_color(k);
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                    .map_err(de)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font((FONT, 14))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(de)?;
            Ok(())
        })
    }
}

fn checked_range(path: &Path, what: &str, (a, b): (f64, f64)) -> Result<(f64, f64), SimError> {
    if a.is_finite() && b.is_finite() && a < b {
        Ok((a, b))
    } else {
        Err(plot_err(
            path,
            format!("{what} ({a}, {b}) must be finite with lo < hi"),
        ))
    }
}

/// Plan-view plot of paths plus point markers (e.g. beacons).
///
/// Points are `(horizontal, vertical)`. For a NED plan view pass `(east, north)`, i.e.
/// `(pos.y, pos.x)`, so north is up, and label the axes accordingly.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanPlot {
    /// Figure title.
    pub title: String,
    /// Horizontal axis label (e.g. `"east [m]"`).
    pub x_label: String,
    /// Vertical axis label (e.g. `"north [m]"`).
    pub y_label: String,
    /// Paths drawn as lines (truth, estimates, ...).
    pub paths: Vec<Series>,
    /// Point sets drawn as markers with a legend entry each (beacons, fixes, ...).
    pub markers: Vec<Series>,
    /// Keep one metre per pixel on both axes (default `true`).
    pub equal_aspect: bool,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl PlanPlot {
    /// An empty plan-view plot (equal aspect, default size).
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        PlanPlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            paths: Vec::new(),
            markers: Vec::new(),
            equal_aspect: true,
            size: (800, 800),
        }
    }

    /// Add a path.
    pub fn with_path(mut self, s: Series) -> Self {
        self.paths.push(s);
        self
    }

    /// Add a marker set.
    pub fn with_markers(mut self, s: Series) -> Self {
        self.markers.push(s);
        self
    }

    /// Draw the plot into an SVG file.
    ///
    /// # Errors
    /// [`SimError::Plot`] if there is nothing to draw or data are empty / non-finite,
    /// [`SimError::Io`] on write failure.
    fn render_svg(&self, path: &Path) -> Result<String, SimError> {
        if self.paths.is_empty() && self.markers.is_empty() {
            return Err(plot_err(path, "no paths or markers to draw"));
        }
        if !self.paths.is_empty() {
            check_series(path, "path", &self.paths)?;
        }
        if !self.markers.is_empty() {
            check_series(path, "marker set", &self.markers)?;
        }
        let all = || {
            self.paths
                .iter()
                .chain(&self.markers)
                .flat_map(|s| s.points.iter().copied())
        };
        let (mut x0, mut x1) = padded(min_max(all().map(|p| p.0)).0, min_max(all().map(|p| p.0)).1);
        let (mut y0, mut y1) = padded(min_max(all().map(|p| p.1)).0, min_max(all().map(|p| p.1)).1);
        let (margin, title_h, xl, yl) = (12u32, 40u32, 45u32, 70u32);
        if self.equal_aspect {
            let w = f64::from(self.size.0.saturating_sub(2 * margin + yl).max(1));
            let h = f64::from(self.size.1.saturating_sub(2 * margin + xl + title_h).max(1));
            let scale = ((x1 - x0) / w).max((y1 - y0) / h);
            let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
            (x0, x1) = (cx - 0.5 * scale * w, cx + 0.5 * scale * w);
            (y0, y1) = (cy - 0.5 * scale * h, cy + 0.5 * scale * h);
        }
        render(path, self.size, |root| {
            let area = root.titled(&self.title, title_style(22)).map_err(de)?;
            let mut chart = ChartBuilder::on(&area)
                .margin(margin)
                .x_label_area_size(xl)
                .y_label_area_size(yl)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(de)?;
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .light_line_style(RGBColor(235, 235, 235))
                .axis_desc_style((FONT, 17))
                .label_style((FONT, 15))
                .draw()
                .map_err(de)?;
            for (k, s) in self.paths.iter().enumerate() {
                let c = series_color(k);
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                    .map_err(de)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    });
            }
            for (k, s) in self.markers.iter().enumerate() {
                let c = series_color(self.paths.len() + k);
                let style = c.filled();
                chart
                    .draw_series(s.points.iter().map(|&p| TriangleMarker::new(p, 8, style)))
                    .map_err(de)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 6, style));
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font((FONT, 14))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(de)?;
            Ok(())
        })
    }
}

/// Histogram drawn from bin edges and counts (or densities).
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Figure title.
    pub title: String,
    /// x-axis label (with unit).
    pub x_label: String,
    /// y-axis label ("count" or "density").
    pub y_label: String,
    /// Bin edges, strictly increasing, `counts.len() + 1` of them.
    pub edges: Vec<f64>,
    /// Bar heights, finite and `>= 0`.
    pub counts: Vec<f64>,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl Histogram {
    /// A histogram with the default size.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        edges: Vec<f64>,
        counts: Vec<f64>,
    ) -> Self {
        Histogram {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            edges,
            counts,
            size: DEFAULT_SIZE,
        }
    }

    /// Draw the histogram into an SVG file.
    ///
    /// # Errors
    /// [`SimError::Plot`] on no bins, edge/count size mismatch, non-increasing edges,
    /// non-finite or negative counts; [`SimError::Io`] on write failure.
    fn render_svg(&self, path: &Path) -> Result<String, SimError> {
        if self.counts.is_empty() {
            return Err(plot_err(path, "histogram has no bins"));
        }
        if self.edges.len() != self.counts.len() + 1 {
            return Err(plot_err(
                path,
                format!(
                    "{} edges for {} bins (need bins + 1)",
                    self.edges.len(),
                    self.counts.len()
                ),
            ));
        }
        for (i, &e) in self.edges.iter().enumerate() {
            check_finite(path, &format!("edge {i}"), e)?;
            if i > 0 && e <= self.edges[i - 1] {
                return Err(plot_err(path, format!("edge {i} ({e}) does not increase")));
            }
        }
        for (i, &c) in self.counts.iter().enumerate() {
            check_finite(path, &format!("count {i}"), c)?;
            if c < 0.0 {
                return Err(plot_err(path, format!("count {i} is negative ({c})")));
            }
        }
        let x0 = self.edges[0];
        let x1 = self.edges[self.edges.len() - 1];
        let top = self.counts.iter().copied().fold(0.0, f64::max);
        let y1 = if top > 0.0 { top * 1.08 } else { 1.0 };
        render(path, self.size, |root| {
            let mut chart = ChartBuilder::on(root)
                .caption(&self.title, title_style(22))
                .margin(12)
                .x_label_area_size(45)
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1, 0.0..y1)
                .map_err(de)?;
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .disable_x_mesh()
                .light_line_style(RGBColor(235, 235, 235))
                .axis_desc_style((FONT, 17))
                .label_style((FONT, 15))
                .draw()
                .map_err(de)?;
            let fill = series_color(0).mix(0.75).filled();
            let edge = RGBColor(20, 60, 100).stroke_width(1);
            chart
                .draw_series(self.counts.iter().enumerate().map(|(i, &c)| {
                    Rectangle::new([(self.edges[i], 0.0), (self.edges[i + 1], c)], fill)
                }))
                .map_err(de)?;
            chart
                .draw_series(self.counts.iter().enumerate().map(|(i, &c)| {
                    Rectangle::new([(self.edges[i], 0.0), (self.edges[i + 1], c)], edge)
                }))
                .map_err(de)?;
            Ok(())
        })
    }
}

/// Colour of `t in [0, 1]` on a viridis-like sequential map.
pub fn heat_color(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (STOPS.len() - 1) as f64;
    let i = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let lerp = |u: f64, v: f64| (u + f * (v - u)).round().clamp(0.0, 255.0) as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// Heat map of a small matrix with the values written in the cells, row / column
/// labels and a colour bar (e.g. sample covariance matrices).
#[derive(Debug, Clone, PartialEq)]
pub struct HeatMap {
    /// Figure title.
    pub title: String,
    /// One label per row (top to bottom).
    pub row_labels: Vec<String>,
    /// One label per column (left to right).
    pub col_labels: Vec<String>,
    /// The matrix, row-major: `values[row][col]`.
    pub values: Vec<Vec<f64>>,
    /// Decimals of the numbers written in the cells and on the colour bar.
    pub decimals: usize,
    /// Label of the colour bar (quantity and unit).
    pub value_label: String,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl HeatMap {
    /// A heat map with 3 decimals and the default size.
    pub fn new(
        title: impl Into<String>,
        row_labels: Vec<String>,
        col_labels: Vec<String>,
        values: Vec<Vec<f64>>,
    ) -> Self {
        HeatMap {
            title: title.into(),
            row_labels,
            col_labels,
            values,
            decimals: 3,
            value_label: String::new(),
            size: (760, 620),
        }
    }

    /// Draw the heat map into an SVG file.
    ///
    /// # Errors
    /// [`SimError::Plot`] on an empty or ragged matrix, label count mismatch or
    /// non-finite values; [`SimError::Io`] on write failure.
    fn render_svg(&self, path: &Path) -> Result<String, SimError> {
        let nr = self.values.len();
        if nr == 0 || self.values[0].is_empty() {
            return Err(plot_err(path, "heat map matrix is empty"));
        }
        let nc = self.values[0].len();
        for (r, row) in self.values.iter().enumerate() {
            if row.len() != nc {
                return Err(plot_err(
                    path,
                    format!("row {r} has {} values, row 0 has {nc}", row.len()),
                ));
            }
            for (c, &v) in row.iter().enumerate() {
                check_finite(path, &format!("value ({r}, {c})"), v)?;
            }
        }
        if self.row_labels.len() != nr || self.col_labels.len() != nc {
            return Err(plot_err(
                path,
                format!(
                    "{} row labels / {} column labels for a {nr}x{nc} matrix",
                    self.row_labels.len(),
                    self.col_labels.len()
                ),
            ));
        }
        let (vmin, vmax) = min_max(self.values.iter().flatten().copied());
        let span = if vmax > vmin { vmax - vmin } else { 1.0 };
        let norm = |v: f64| (v - vmin) / span;
        let dec = self.decimals;
        render(path, self.size, |root| {
            let area = root.titled(&self.title, title_style(22)).map_err(de)?;
            let (w, _) = area.dim_in_pixel();
            let (main, bar) = area.split_horizontally(w.saturating_sub(130));
            let mut chart = ChartBuilder::on(&main)
                .margin(10)
                .margin_left(90)
                .margin_top(40)
                .build_cartesian_2d(0.0..nc as f64, 0.0..nr as f64)
                .map_err(de)?;
            // Row 0 on top: row r spans y in [nr - r - 1, nr - r].
            for (r, row) in self.values.iter().enumerate() {
                let yt = (nr - r) as f64;
                for (c, &v) in row.iter().enumerate() {
                    let t = norm(v);
                    let cell = [(c as f64, yt - 1.0), (c as f64 + 1.0, yt)];
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            cell,
                            heat_color(t).filled(),
                        )))
                        .map_err(de)?;
                    chart
                        .draw_series(std::iter::once(Rectangle::new(cell, WHITE.stroke_width(1))))
                        .map_err(de)?;
                    let ink = if t > 0.6 { BLACK } else { WHITE };
                    chart
                        .draw_series(std::iter::once(Text::new(
                            format!("{v:.dec$}"),
                            (c as f64 + 0.5, yt - 0.5),
                            text_style(16, HPos::Center, VPos::Center).color(&ink),
                        )))
                        .map_err(de)?;
                }
            }
            for (r, label) in self.row_labels.iter().enumerate() {
                let (px, py) = chart.backend_coord(&(0.0, (nr - r) as f64 - 0.5));
                root.draw_text(
                    label,
                    &text_style(16, HPos::Right, VPos::Center),
                    (px - 8, py),
                )
                .map_err(de)?;
            }
            for (c, label) in self.col_labels.iter().enumerate() {
                let (px, py) = chart.backend_coord(&(c as f64 + 0.5, nr as f64));
                root.draw_text(
                    label,
                    &text_style(16, HPos::Center, VPos::Bottom),
                    (px, py - 8),
                )
                .map_err(de)?;
            }
            draw_color_bar(&bar, vmin, vmax, dec, &self.value_label)
        })
    }
}

fn draw_color_bar(
    bar: &Area<'_>,
    vmin: f64,
    vmax: f64,
    dec: usize,
    label: &str,
) -> Result<(), String> {
    let (_, h) = bar.dim_in_pixel();
    let (top, bottom) = (50i32, h as i32 - 30);
    let (left, right) = (20i32, 45i32);
    let steps = 60;
    let len = (bottom - top).max(1);
    for k in 0..steps {
        let y_a = top + len * k / steps;
        let y_b = top + len * (k + 1) / steps;
        let t = 1.0 - (f64::from(k) + 0.5) / f64::from(steps);
        bar.draw(&Rectangle::new(
            [(left, y_a), (right, y_b)],
            heat_color(t).filled(),
        ))
        .map_err(de)?;
    }
    bar.draw(&Rectangle::new(
        [(left, top), (right, bottom)],
        BLACK.stroke_width(1),
    ))
    .map_err(de)?;
    let st = text_style(14, HPos::Left, VPos::Center);
    for (frac, v) in [(0.0, vmax), (0.5, 0.5 * (vmin + vmax)), (1.0, vmin)] {
        let y = top + (f64::from(len) * frac).round() as i32;
        bar.draw(&PathElement::new(
            vec![(right, y), (right + 4, y)],
            BLACK.stroke_width(1),
        ))
        .map_err(de)?;
        bar.draw_text(&format!("{v:.dec$}"), &st, (right + 7, y))
            .map_err(de)?;
    }
    if !label.is_empty() {
        bar.draw_text(
            label,
            &text_style(13, HPos::Left, VPos::Bottom),
            (left - 10, top - 10),
        )
        .map_err(de)?;
    }
    Ok(())
}

/// Sample-time diagram: one row per sensor, one tick per sample time inside a window
/// (e.g. synchronous versus asynchronous sensors).
#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    /// Figure title.
    pub title: String,
    /// x-axis label (e.g. `"time [s]"`).
    pub x_label: String,
    /// `(sensor name, sample times in s)`, drawn top to bottom.
    pub rows: Vec<(String, Vec<f64>)>,
    /// Time window `(from, to)`; `None` spans all samples.
    pub window: Option<(f64, f64)>,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl Timeline {
    /// A timeline with the default width and a height suited to the rows.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        rows: Vec<(String, Vec<f64>)>,
        window: Option<(f64, f64)>,
    ) -> Self {
        let h = 140 + 45 * rows.len() as u32;
        Timeline {
            title: title.into(),
            x_label: x_label.into(),
            rows,
            window,
            size: (900, h.max(200)),
        }
    }

    /// Draw the diagram into an SVG file.
    ///
    /// # Errors
    /// [`SimError::Plot`] on no rows, non-finite times or a bad window (or no samples
    /// at all when no window is given); [`SimError::Io`] on write failure.
    fn render_svg(&self, path: &Path) -> Result<String, SimError> {
        if self.rows.is_empty() {
            return Err(plot_err(path, "timeline has no rows"));
        }
        for (name, times) in &self.rows {
            for (i, &t) in times.iter().enumerate() {
                check_finite(path, &format!("row `{name}` time {i}"), t)?;
            }
        }
        let (t0, t1) = match self.window {
            Some(w) => checked_range(path, "window", w)?,
            None => {
                let (a, b) = min_max(self.rows.iter().flat_map(|r| r.1.iter().copied()));
                if !a.is_finite() {
                    return Err(plot_err(path, "timeline rows hold no sample times"));
                }
                let pad = if b > a { 0.02 * (b - a) } else { 1.0 };
                (a - pad, b + pad)
            }
        };
        let n = self.rows.len();
        // Room for the row labels, drawn left of the plot area (about 8 px per
        // character at the label font size).
        let longest = self
            .rows
            .iter()
            .map(|r| r.0.chars().count())
            .max()
            .unwrap_or(0);
        let margin_left = (8 * longest as u32 + 24).max(130);
        render(path, self.size, |root| {
            let mut chart = ChartBuilder::on(root)
                .caption(&self.title, title_style(20))
                .margin(12)
                .margin_left(margin_left)
                .x_label_area_size(45)
                .build_cartesian_2d(t0..t1, 0.0..n as f64)
                .map_err(de)?;
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .disable_y_mesh()
                .disable_y_axis()
                .light_line_style(RGBColor(235, 235, 235))
                .axis_desc_style((FONT, 17))
                .label_style((FONT, 15))
                .draw()
                .map_err(de)?;
            for (r, (name, times)) in self.rows.iter().enumerate() {
                let yc = (n - r) as f64 - 0.5;
                let c = series_color(r);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(t0, yc), (t1, yc)],
                        RGBColor(200, 200, 200).stroke_width(1),
                    )))
                    .map_err(de)?;
                chart
                    .draw_series(times.iter().filter(|&&t| t >= t0 && t <= t1).map(|&t| {
                        PathElement::new(vec![(t, yc - 0.3), (t, yc + 0.3)], c.stroke_width(2))
                    }))
                    .map_err(de)?;
                let (px, py) = chart.backend_coord(&(t0, yc));
                root.draw_text(
                    name,
                    &text_style(16, HPos::Right, VPos::Center),
                    (px - 8, py),
                )
                .map_err(de)?;
            }
            Ok(())
        })
    }
}

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
        assert!(matches!(e, SimError::Plot { .. }), "{e}");
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
        assert!(matches!(e, SimError::Plot { .. }));
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
}

//! Line plots of named series with shaded intervals and markers.

use std::path::Path;

use plotters::prelude::*;

use super::*;
use crate::ReportError;

/// Line plot of several named series with optional shaded x-intervals and vertical
/// markers (e.g. error versus time with course changes marked).
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Figure title.
    pub title: String,
    /// x-axis label (unit in parentheses, e.g. `"time (s)"`).
    pub x_label: String,
    /// y-axis label (with unit).
    pub y_label: String,
    /// The series (one colour and legend entry each).
    pub series: Vec<Series>,
    /// Shaded x-intervals `(from, to)` drawn behind the series.
    pub shaded_x: Vec<(f64, f64)>,
    /// What the shaded intervals mean: their legend entry (e.g. `"DVL invalid"`).
    pub shaded_label: String,
    /// x positions of vertical marker lines.
    pub markers_x: Vec<f64>,
    /// What the marker lines mean: their legend entry (none when empty).
    pub markers_label: String,
    /// 95 % CI bands `(x, lo, hi)` of mean curves, each with the index of its series
    /// (drawn in its colour, named in the legend).
    pub bands: Vec<(usize, Band)>,
    /// What the bands are: their legend entry (default `band: 95 % CI of the mean`).
    pub band_label: String,
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
            shaded_label: "shaded: see caption".to_string(),
            markers_x: Vec::new(),
            markers_label: String::new(),
            bands: Vec::new(),
            band_label: "band: 95 % CI of the mean".to_string(),
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

    /// Name the shaded intervals in the legend.
    pub fn with_shade_label(mut self, label: impl Into<String>) -> Self {
        self.shaded_label = label.into();
        self
    }

    /// The colour of series `k` (a band takes its series' colour).
    fn color_of(&self, k: usize) -> RGBColor {
        self.series
            .get(k)
            .map_or_else(|| series_color(k), |s| s.color_at(k))
    }

    /// Add the band `(x, lo, hi)` of series `series` (the 95 % CI of a mean curve, or
    /// what [`LinePlot::with_band_label`] says); an empty band is ignored.
    pub fn with_band(mut self, series: usize, band: Band) -> Self {
        if !band.is_empty() {
            self.bands.push((series, band));
        }
        self
    }

    /// Name the bands in the legend (e.g. `band: ±3σ of the filter`), when they are
    /// not the default 95 % intervals of mean curves.
    pub fn with_band_label(mut self, label: impl Into<String>) -> Self {
        self.band_label = label.into();
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
    /// [`ReportError::Plot`] on empty / non-finite data, [`ReportError::Io`] on write failure.
    pub(crate) fn render_svg(&self, path: &Path) -> Result<String, ReportError> {
        check_series(path, "series", &self.series)?;
        for (i, &(a, b)) in self.shaded_x.iter().enumerate() {
            check_finite(path, &format!("shaded interval {i} start"), a)?;
            check_finite(path, &format!("shaded interval {i} end"), b)?;
        }
        for (i, &m) in self.markers_x.iter().enumerate() {
            check_finite(path, &format!("marker {i}"), m)?;
        }
        for (i, (_, band)) in self.bands.iter().enumerate() {
            for &(x, lo, hi) in band {
                check_finite(path, &format!("band {i}"), x + lo + hi)?;
            }
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
                let band_pts = self
                    .bands
                    .iter()
                    .flat_map(|b| b.1.iter().flat_map(|&(x, lo, hi)| [(x, lo), (x, hi)]));
                let in_x = pts()
                    .chain(band_pts)
                    .filter(|p| p.0 >= x0 && p.0 <= x1)
                    .map(|p| p.1);
                let (a, b) = min_max(in_x);
                if a.is_finite() {
                    padded(a, b)
                } else {
                    (0.0, 1.0)
                }
            }
        };
        let labels = legend_labels(&self.series, 0.0, (y1 - y0) * 2.0 / f64::from(self.size.1));
        let mut entries = series_entries(&self.series, &labels);
        if !self.shaded_x.is_empty() {
            entries.push(Entry {
                label: self.shaded_label.clone(),
                swatch: Swatch::Shade,
            });
        }
        if !self.markers_x.is_empty() && !self.markers_label.is_empty() {
            entries.push(Entry {
                label: self.markers_label.clone(),
                swatch: Swatch::Line(MARKER_GREY),
            });
        }
        if let Some((k, _)) = self.bands.first() {
            entries.push(Entry {
                label: self.band_label.clone(),
                swatch: Swatch::Band(self.color_of(*k)),
            });
        }
        render(path, self.size, |root| {
            let root = root.titled(&self.title, title_style(22)).map_err(de)?;
            // The legend in its own column right of the plot: it never covers data.
            let (plot_area, legend_area) =
                root.split_horizontally(plot_width(self.size.0, &entries));
            let mut chart = ChartBuilder::on(&plot_area)
                .margin(12)
                .margin_right(28)
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
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
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
            let mark = MARKER_GREY.stroke_width(1);
            chart
                .draw_series(
                    self.markers_x
                        .iter()
                        .map(|&m| PathElement::new(vec![(m, y0), (m, y1)], mark)),
                )
                .map_err(de)?;
            for (k, band) in &self.bands {
                let mut outline: Vec<(f64, f64)> = band.iter().map(|&(x, _, hi)| (x, hi)).collect();
                outline.extend(band.iter().rev().map(|&(x, lo, _)| (x, lo)));
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        outline,
                        self.color_of(*k).mix(0.25).filled(),
                    )))
                    .map_err(de)?;
            }
            draw_lines(&mut chart, &self.series, &labels)?;
            draw_legend(&legend_area, &entries, shade)
        })
    }
}

/// What a legend entry shows.
pub(super) enum Swatch {
    /// A series.
    Line(RGBColor),
    /// A series lying on an earlier one (drawn dashed).
    Dashed(RGBColor),
    /// The shaded x-intervals.
    Shade,
    /// A CI band in the colour of its series.
    Band(RGBColor),
    /// A set of triangle markers.
    Marker(RGBColor),
    /// A filled region (plan views: structures).
    Area(RGBColor),
    /// Highlighted stretches of a path (a wide translucent stroke under it).
    Highlight(RGBColor),
}

/// Colour of the vertical marker lines.
const MARKER_GREY: RGBColor = RGBColor(90, 90, 90);

/// Width of a highlighted stretch, px.
pub(super) const HIGHLIGHT_PX: u32 = 12;

/// One legend entry.
pub(super) struct Entry {
    pub(super) label: String,
    pub(super) swatch: Swatch,
}

/// Draws `series` as lines in their colours; one that `labels` flags as lying on an
/// earlier one is dashed, so both stay visible.
pub(super) fn draw_lines<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    series: &[Series],
    labels: &[(String, bool)],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    for (k, (s, (_, on))) in series.iter().zip(labels).enumerate() {
        let style = s.color_at(k).stroke_width(2);
        let pts = s.points.iter().copied();
        if *on {
            chart
                .draw_series(DashedLineSeries::new(pts, 7, 7, style))
                .map_err(de)?;
        } else {
            chart.draw_series(LineSeries::new(pts, style)).map_err(de)?;
        }
    }
    Ok(())
}

/// The legend entries of the series labelled by [`legend_labels`]: a line in the
/// series' colour, dashed where it lies on an earlier one.
pub(super) fn series_entries(series: &[Series], labels: &[(String, bool)]) -> Vec<Entry> {
    series
        .iter()
        .zip(labels)
        .enumerate()
        .map(|(k, (s, (l, on)))| Entry {
            label: l.clone(),
            swatch: if *on {
                Swatch::Dashed(s.color_at(k))
            } else {
                Swatch::Line(s.color_at(k))
            },
        })
        .collect()
}

/// Legend labels: a series whose points all lie within `(tol_x, tol_y)` of an earlier
/// one's (about two pixels: the curves coincide on the figure) is labelled
/// `"B (on A)"` and flagged, so coinciding curves are named and drawn dashed; one
/// with at least [`MOSTLY_ON`] of its points there is `"B (mostly on A)"`.
pub(super) fn legend_labels(series: &[Series], tol_x: f64, tol_y: f64) -> Vec<(String, bool)> {
    // The share of `s`'s points within the tolerance of `e`'s (same length only).
    let share_on = |e: &Series, s: &Series| -> f64 {
        if e.points.len() != s.points.len() || s.points.is_empty() {
            return 0.0;
        }
        let close = e
            .points
            .iter()
            .zip(&s.points)
            .filter(|(a, b)| (a.0 - b.0).abs() <= tol_x && (a.1 - b.1).abs() <= tol_y)
            .count();
        close as f64 / s.points.len() as f64
    };
    series
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let best = series[..k]
                .iter()
                .map(|e| (e, share_on(e, s)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            match best {
                Some((e, share)) if share >= 1.0 => (format!("{} (on {})", s.name, e.name), true),
                Some((e, share)) if share >= MOSTLY_ON => {
                    (format!("{} (mostly on {})", s.name, e.name), true)
                }
                _ => (s.name.clone(), false),
            }
        })
        .collect()
}

/// Share of a series' points lying on an earlier one above which it is drawn dashed
/// and named "B (mostly on A)".
const MOSTLY_ON: f64 = 0.8;

/// Width of the plot column: the figure minus a legend column wide enough for the
/// longest entry (about 8 px a character at 14 px).
pub(super) fn plot_width(total: u32, entries: &[Entry]) -> u32 {
    let chars = entries
        .iter()
        .map(|e| e.label.chars().count())
        .max()
        .unwrap_or(0) as u32;
    let legend = (chars * 8 + 44).clamp(90, total / 3);
    total.saturating_sub(legend)
}

/// Draws the legend entries top-down into `area` (a line per series, a box for the
/// shaded intervals).
pub(super) fn draw_legend(
    area: &Area<'_>,
    entries: &[Entry],
    shade: ShapeStyle,
) -> Result<(), String> {
    for (i, e) in entries.iter().enumerate() {
        let y = 30 + 22 * i as i32;
        match e.swatch {
            Swatch::Line(c) => area
                .draw(&PathElement::new(vec![(4, y), (26, y)], c.stroke_width(3)))
                .map_err(de)?,
            Swatch::Dashed(c) => {
                for x in [4, 18] {
                    area.draw(&PathElement::new(
                        vec![(x, y), (x + 8, y)],
                        c.stroke_width(3),
                    ))
                    .map_err(de)?;
                }
            }
            Swatch::Shade => area
                .draw(&Rectangle::new([(4, y - 7), (26, y + 7)], shade))
                .map_err(de)?,
            Swatch::Marker(c) => area
                .draw(&TriangleMarker::new((15, y), 6, c.filled()))
                .map_err(de)?,
            Swatch::Band(c) => area
                .draw(&Rectangle::new(
                    [(4, y - 7), (26, y + 7)],
                    c.mix(0.25).filled(),
                ))
                .map_err(de)?,
            Swatch::Area(c) => area
                .draw(&Rectangle::new([(4, y - 7), (26, y + 7)], c.filled()))
                .map_err(de)?,
            Swatch::Highlight(c) => area
                .draw(&PathElement::new(
                    vec![(4, y), (26, y)],
                    c.stroke_width(HIGHLIGHT_PX),
                ))
                .map_err(de)?,
        }
        area.draw(&Text::new(
            e.label.clone(),
            (32, y),
            text_style(14, HPos::Left, VPos::Center),
        ))
        .map_err(de)?;
    }
    Ok(())
}

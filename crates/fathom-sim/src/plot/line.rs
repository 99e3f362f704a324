//! Line plots of named series with shaded intervals and markers.

use std::path::Path;

use plotters::prelude::*;

use super::*;
use crate::error::SimError;

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
    pub(crate) fn render_svg(&self, path: &Path) -> Result<String, SimError> {
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

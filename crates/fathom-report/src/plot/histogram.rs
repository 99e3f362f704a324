//! Histograms from bin edges and counts.

use std::path::Path;

use plotters::prelude::*;

use super::*;
use crate::ReportError;

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
    /// [`ReportError::Plot`] on no bins, edge/count size mismatch, non-increasing edges,
    /// non-finite or negative counts; [`ReportError::Io`] on write failure.
    pub(crate) fn render_svg(&self, path: &Path) -> Result<String, ReportError> {
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
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
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

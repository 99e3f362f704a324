//! Sample-time diagrams: one row of ticks per sensor.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::*;
use crate::ReportError;

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
    /// [`ReportError::Plot`] on no rows, non-finite times or a bad window (or no samples
    /// at all when no window is given); [`ReportError::Io`] on write failure.
    pub(crate) fn render_svg(&self, path: &Path) -> Result<String, ReportError> {
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
                // A little room beyond the window: a sample on its edge is drawn whole.
                .build_cartesian_2d(
                    t0 - 0.015 * (t1 - t0)..t1 + 0.015 * (t1 - t0),
                    0.0..n as f64,
                )
                .map_err(de)?;
            chart
                .configure_mesh()
                .x_desc(&self.x_label)
                .disable_y_mesh()
                .disable_y_axis()
                .light_line_style(RGBColor(235, 235, 235))
                .axis_desc_style((FONT, 17))
                .label_style((FONT, 15))
                .x_label_formatter(&tick)
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

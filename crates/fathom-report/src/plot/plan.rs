//! Plan-view paths and markers (equal aspect).

use std::path::Path;

use plotters::prelude::*;

use super::line::{Entry, Swatch, draw_legend, draw_lines, plot_width, series_entries};
use super::*;
use crate::ReportError;

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
    /// Filled regions drawn under everything else (structures): each point is the
    /// centre of a filled cell of `cell = (width, height)` in data units.
    pub areas: Vec<(Series, (f64, f64))>,
    /// Stretches of a path to point out (e.g. GNSS-shadowed): each point is drawn as
    /// a wide translucent stroke under the paths, so the paths stay visible.
    pub highlights: Vec<Series>,
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
            areas: Vec::new(),
            highlights: Vec::new(),
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

    /// Add a filled region: cells of size `cell` (data units) centred on the points.
    pub fn with_area(mut self, s: Series, cell: (f64, f64)) -> Self {
        self.areas.push((s, cell));
        self
    }

    /// Add highlighted path points (drawn under the paths).
    pub fn with_highlight(mut self, s: Series) -> Self {
        self.highlights.push(s);
        self
    }

    /// Draw the plot into an SVG file.
    ///
    /// # Errors
    /// [`ReportError::Plot`] if there is nothing to draw or data are empty / non-finite,
    /// [`ReportError::Io`] on write failure.
    pub(crate) fn render_svg(&self, path: &Path) -> Result<String, ReportError> {
        if self.paths.is_empty() && self.markers.is_empty() && self.areas.is_empty() {
            return Err(plot_err(path, "no paths, markers or areas to draw"));
        }
        let areas: Vec<Series> = self.areas.iter().map(|(s, _)| s.clone()).collect();
        for set in [&areas, &self.highlights] {
            if !set.is_empty() {
                check_series(path, "area or highlight", set)?;
            }
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
                .chain(&areas)
                .chain(&self.highlights)
                .flat_map(|s| s.points.iter().copied())
        };
        let (mut x0, mut x1) = padded(min_max(all().map(|p| p.0)).0, min_max(all().map(|p| p.0)).1);
        let (mut y0, mut y1) = padded(min_max(all().map(|p| p.1)).0, min_max(all().map(|p| p.1)).1);
        let (margin, title_h, xl, yl) = (12u32, 40u32, 45u32, 70u32);
        // The legend in its own column right of the plan: it never covers a path or
        // a beacon.
        let labels = super::line::legend_labels(
            &self.paths,
            (x1 - x0) * 2.0 / f64::from(self.size.0),
            (y1 - y0) * 2.0 / f64::from(self.size.1),
        );
        let mut entries = Vec::new();
        for (k, (a, _)) in self.areas.iter().enumerate() {
            entries.push(Entry {
                label: a.name.clone(),
                swatch: Swatch::Area(area_color(k)),
            });
        }
        for (k, h) in self.highlights.iter().enumerate() {
            entries.push(Entry {
                label: h.name.clone(),
                swatch: Swatch::Highlight(highlight_color(k)),
            });
        }
        entries.extend(series_entries(&self.paths, &labels));
        for (k, m) in self.markers.iter().enumerate() {
            entries.push(Entry {
                label: m.name.clone(),
                swatch: Swatch::Marker(m.color_at(self.paths.len() + k)),
            });
        }
        let plot_w = plot_width(self.size.0, &entries);
        if self.equal_aspect {
            let w = f64::from(plot_w.saturating_sub(2 * margin + yl).max(1));
            let h = f64::from(self.size.1.saturating_sub(2 * margin + xl + title_h).max(1));
            let scale = ((x1 - x0) / w).max((y1 - y0) / h);
            let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
            (x0, x1) = (cx - 0.5 * scale * w, cx + 0.5 * scale * w);
            (y0, y1) = (cy - 0.5 * scale * h, cy + 0.5 * scale * h);
        }
        render(path, self.size, |root| {
            let area = root.titled(&self.title, title_style(22)).map_err(de)?;
            let (area, legend_area) = area.split_horizontally(plot_w);
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
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .draw()
                .map_err(de)?;
            // Areas, then highlights, under the paths and markers.
            for (k, (s, (w, h))) in self.areas.iter().enumerate() {
                let style = area_color(k).filled();
                chart
                    .draw_series(s.points.iter().map(|&(x, y)| {
                        Rectangle::new(
                            [(x - 0.5 * w, y - 0.5 * h), (x + 0.5 * w, y + 0.5 * h)],
                            style,
                        )
                    }))
                    .map_err(de)?;
            }
            for (k, s) in self.highlights.iter().enumerate() {
                let style = highlight_color(k).filled();
                let r = super::line::HIGHLIGHT_PX / 2;
                chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, r, style)))
                    .map_err(de)?;
            }
            // A path lying on an earlier one is dashed and named "B (on A)".
            draw_lines(&mut chart, &self.paths, &labels)?;
            for (k, s) in self.markers.iter().enumerate() {
                let style = s.color_at(self.paths.len() + k).filled();
                chart
                    .draw_series(s.points.iter().map(|&p| TriangleMarker::new(p, 8, style)))
                    .map_err(de)?;
            }
            let shade = RGBColor(120, 120, 120).mix(0.18).filled();
            draw_legend(&legend_area, &entries, shade)
        })
    }
}

/// Fill colour of the `k`-th area set: light greys (structures look the same in
/// every figure).
fn area_color(k: usize) -> RGBColor {
    const GREYS: [RGBColor; 3] = [
        RGBColor(190, 190, 190),
        RGBColor(150, 150, 150),
        RGBColor(215, 215, 215),
    ];
    GREYS[k % GREYS.len()]
}

/// Colour of the `k`-th highlight set (pale red first: one meaning in every
/// figure). Opaque and pale: overlapping points do not darken, the path on top
/// stays visible.
fn highlight_color(k: usize) -> RGBColor {
    const COLORS: [RGBColor; 2] = [RGBColor(250, 185, 185), RGBColor(250, 215, 150)];
    COLORS[k % COLORS.len()]
}

//! Heat maps of a matrix with a colour bar.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::*;
use crate::ReportError;

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
    /// [`ReportError::Plot`] on an empty or ragged matrix, label count mismatch or
    /// non-finite values; [`ReportError::Io`] on write failure.
    pub(crate) fn render_svg(&self, path: &Path) -> Result<String, ReportError> {
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
                            fixed_text(v, dec),
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

/// `v` with `dec` decimals, without the sign of a value that rounds to zero
/// (`0.0000`, not `-0.0000`).
fn fixed_text(v: f64, dec: usize) -> String {
    let s = format!("{v:.dec$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => s,
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
        bar.draw_text(&fixed_text(v, dec), &st, (right + 7, y))
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

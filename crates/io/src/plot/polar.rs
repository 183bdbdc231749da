//! Polar plots of densities over direction, alone or beside a line plot.

#[cfg(feature = "plots")]
use super::axes::ticks;
#[cfg(feature = "plots")]
use super::{
    plot_failure, titled_panel, write_png_of, write_svg_of, Drawn, Ticks, COLOURS, FAMILY,
};
use super::{LinePlot, Marker, Series};
#[cfg(feature = "plots")]
use crate::error::Result;
#[cfg(feature = "plots")]
use plotters::style::text_anchor::{HPos, Pos, VPos};
#[cfg(feature = "plots")]
use plotters::{coord::Shift, prelude::*};
#[cfg(feature = "plots")]
use std::path::Path;

/// A polar plot of densities over direction in the tilt convention: 0° up, +90° left
/// (counter-clockwise), with rings of equal radius labelled in the radius's unit, spokes every
/// 45° labelled in degrees (0–360), markers as labelled spokes, and the legend below the disc.
#[derive(Debug, Clone, PartialEq)]
pub struct PolarPlot {
    /// The title.
    pub title: String,
    /// What the radius is, with its unit.
    pub radius_label: String,
    /// The curves: (direction in degrees, radius ≥ 0), closed when drawn.
    pub series: Vec<Series>,
    /// Directions to mark (a labelled spoke), degrees.
    pub markers: Vec<Marker>,
    /// The palette index of each curve, so that a curve can match its colour in a
    /// neighbouring plot (curves past the list's end take the palette in order).
    pub colours: Vec<usize>,
}

/// A line plot beside a polar plot, in one picture.
#[derive(Debug, Clone, PartialEq)]
pub struct LineAndPolar {
    /// The line plot, on the left.
    pub line: LinePlot,
    /// The polar plot, on the right.
    pub polar: PolarPlot,
    /// Size in pixels of the whole figure.
    pub size: (u32, u32),
}

#[cfg(feature = "plots")]
impl PolarPlot {
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<()> {
        let fail = plot_failure(&self.title);
        let root = titled_panel(root, &self.title, 20)?;
        let (w, h) = root.dim_in_pixel();
        let legend_h = 24 * self.series.len() as u32 + 30;
        let (disc, legend) = root.split_vertically(h.saturating_sub(legend_h));
        let top = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .filter(|r| r.is_finite())
            .fold(0.0f64, f64::max);
        let (rings, _) = ticks(0.0, if top > 0.0 { top } else { 1.0 }, Ticks::Auto);
        let outer = rings
            .last()
            .copied()
            .filter(|r| *r >= top && *r > 0.0)
            .unwrap_or(top.max(1e-9));
        let r = outer * 1.32;
        let (dw, dh) = disc.dim_in_pixel();
        let side = dw.min(dh);
        let pad_x = (dw - side) / 2;
        let disc = disc.margin(0, 0, pad_x, pad_x);
        let mut chart = ChartBuilder::on(&disc)
            .margin(4)
            .build_cartesian_2d(-r..r, -r..r)
            .map_err(|e| fail(&e))?;
        let at = |deg: f64, rad: f64| {
            let t = deg.to_radians();
            (-rad * t.sin(), rad * t.cos())
        };
        let grey = RGBColor(210, 210, 210);
        let ring_font = (FAMILY, 13).into_font().color(&RGBColor(110, 110, 110));
        for &ring in rings.iter().filter(|v| **v > 0.0 && **v <= outer * 1.0001) {
            let circle: Vec<(f64, f64)> = (0..=360).map(|d| at(d as f64, ring)).collect();
            chart
                .draw_series(LineSeries::new(circle, grey.stroke_width(1)))
                .map_err(|e| fail(&e))?;
            let decimals = if ring >= 1.0 { 0 } else { 2 };
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{ring:.decimals$}"),
                    at(202.5, ring),
                    ring_font.clone(),
                )))
                .map_err(|e| fail(&e))?;
        }
        for spoke in (0..8).map(|k| 45.0 * k as f64) {
            chart
                .draw_series(LineSeries::new(
                    [(0.0, 0.0), at(spoke, outer)],
                    grey.stroke_width(1),
                ))
                .map_err(|e| fail(&e))?;
            let name = match spoke as i32 {
                0 => "0° above".to_string(),
                90 => "90° left".to_string(),
                180 => "180° below".to_string(),
                270 => "270° right".to_string(),
                d => format!("{d}°"),
            };
            let (hp, vp) = match spoke as i32 {
                0 => (HPos::Center, VPos::Bottom),
                180 => (HPos::Center, VPos::Top),
                d if d < 180 => (HPos::Right, VPos::Center),
                _ => (HPos::Left, VPos::Center),
            };
            chart
                .draw_series(std::iter::once(Text::new(
                    name,
                    at(spoke, outer * 1.04),
                    (FAMILY, 14).into_font().color(&BLACK).pos(Pos::new(hp, vp)),
                )))
                .map_err(|e| fail(&e))?;
        }
        for m in &self.markers {
            chart
                .draw_series(LineSeries::new(
                    [(0.0, 0.0), at(m.x, outer)],
                    RGBColor(90, 90, 90).stroke_width(2),
                ))
                .map_err(|e| fail(&e))?;
        }
        let colour_of =
            |i: usize| COLOURS[self.colours.get(i).copied().unwrap_or(i) % COLOURS.len()];
        for (i, s) in self.series.iter().enumerate() {
            let colour = colour_of(i);
            let mut points: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|p| p.1.is_finite())
                .map(|&(d, rad)| at(d, rad))
                .collect();
            if let Some(&first) = points.first() {
                points.push(first);
            }
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| fail(&e))?;
            if s.points.len() <= 48 {
                chart
                    .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| fail(&e))?;
            }
        }
        // The legend and the radius's unit, below the disc.
        let font = (FAMILY, 14).into_font();
        let mut y = 8;
        for (i, s) in self.series.iter().enumerate() {
            let colour = colour_of(i);
            legend
                .draw(&PathElement::new(
                    vec![(20, y + 8), (44, y + 8)],
                    colour.stroke_width(3),
                ))
                .map_err(|e| fail(&e))?;
            legend
                .draw(&Text::new(
                    s.name.clone(),
                    (52, y),
                    font.clone().color(&BLACK),
                ))
                .map_err(|e| fail(&e))?;
            y += 24;
        }
        let mut note = format!("radius: {}", self.radius_label);
        for m in &self.markers {
            note += &format!("; dark spoke: {}", m.label);
        }
        legend
            .draw(&Text::new(note, (20, y), font.color(&RGBColor(90, 90, 90))))
            .map_err(|e| fail(&e))?;
        let _ = w;
        root.present().map_err(|e| fail(&e))?;
        Ok(())
    }
}

#[cfg(feature = "plots")]
impl Drawn for LineAndPolar {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()> {
        let (w, _) = root.dim_in_pixel();
        let (left, right) = root.split_horizontally(w * 62 / 100);
        self.line.draw(left)?;
        self.polar.draw(right)
    }
}

#[cfg(feature = "plots")]
impl LineAndPolar {
    /// Writes the figure as an 8-bit PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        write_png_of(self, self.size, path)
    }

    /// Writes the figure as SVG, atomically.
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        write_svg_of(self, self.size, path)
    }
}

//! Line plots: curves, markers and intervals, with the legend beside the data.

use super::{circle_step, Ticks, MAX_LEGEND};
#[cfg(feature = "plots")]
use {
    super::{axes, plot_failure, titled_panel, write_rgb_png, PixelRect, COLOURS, FAMILY},
    crate::{self as io, error::Result},
    plotters::prelude::*,
    plotters::style::text_anchor::{HPos, Pos, VPos},
    std::path::Path,
};

/// One curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Its name in the legend; the first word is its class when curves are grouped.
    pub name: String,
    /// (x, y) points, drawn in order.
    pub points: Vec<(f64, f64)>,
}

/// A vertical marker line with a label.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Where, in x.
    pub x: f64,
    /// Its label.
    pub label: String,
}

/// A line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// The title.
    pub title: String,
    /// The x axis label, with its unit.
    pub x_label: String,
    /// The y axis label, with its unit.
    pub y_label: String,
    /// The x range shown.
    pub x_range: (f64, f64),
    /// The y range shown; `None` fits the data with a margin.
    pub y_range: Option<(f64, f64)>,
    /// The x axis's ticks.
    pub x_ticks: Ticks,
    /// The y axis's ticks.
    pub y_ticks: Ticks,
    /// A horizontal reference line (e.g. convexity 0 or P = ½).
    pub reference_y: Option<f64>,
    /// What the reference line is, written above its right end (empty: nothing written).
    pub reference_label: String,
    /// Vertical markers.
    pub markers: Vec<Marker>,
    /// The curves.
    pub series: Vec<Series>,
    /// Points with vertical intervals, drawn as dots with whiskers after the curves, in the
    /// colours that follow theirs.
    pub intervals: Vec<IntervalSeries>,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// Points with vertical intervals (e.g. proportions with their confidence intervals).
#[derive(Debug, Clone, PartialEq)]
pub struct IntervalSeries {
    /// Its name in the legend.
    pub name: String,
    /// (x, y, low, high) for each point.
    pub points: Vec<(f64, f64, f64, f64)>,
}

impl LinePlot {
    /// An empty plot of the default size (900 × 540).
    pub fn new(title: &str, x_label: &str, y_label: &str, x_range: (f64, f64)) -> LinePlot {
        LinePlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_range,
            y_range: None,
            x_ticks: Ticks::Auto,
            y_ticks: Ticks::Auto,
            reference_y: None,
            reference_label: String::new(),
            markers: Vec::new(),
            series: Vec::new(),
            intervals: Vec::new(),
            size: (900, 540),
        }
    }

    /// When every curve is sampled at angles that cover the circle once in equal steps (e.g.
    /// 0, 30, …, 330), closes each curve (its value at the first angle repeated 360° on), shows
    /// the full turn and ticks the axis in degrees; otherwise changes nothing. Returns whether
    /// it closed them.
    ///
    /// ```
    /// use shadelab_io::plot::{LinePlot, Series, Ticks};
    /// let mut plot = LinePlot::new("t", "tilt (°)", "y", (0.0, 330.0));
    /// plot.series.push(Series {
    ///     name: "a".into(),
    ///     points: (0..12).map(|i| (30.0 * i as f64, i as f64)).collect(),
    /// });
    /// assert!(plot.close_circle());
    /// assert_eq!(plot.x_range, (0.0, 360.0));
    /// assert_eq!(plot.series[0].points.last(), Some(&(360.0, 0.0)));
    /// assert_eq!(plot.x_ticks, Ticks::Degrees);
    /// ```
    pub fn close_circle(&mut self) -> bool {
        let Some(first) = self.series.first() else {
            return false;
        };
        let xs: Vec<f64> = first.points.iter().map(|p| p.0).collect();
        let same = self
            .series
            .iter()
            .all(|s| s.points.iter().map(|p| p.0).eq(xs.iter().copied()));
        if !same || circle_step(&xs).is_none() {
            return false;
        }
        for s in &mut self.series {
            let (x, y) = s.points[0];
            s.points.push((x + 360.0, y));
        }
        self.x_range = (xs[0], xs[0] + 360.0);
        self.x_ticks = Ticks::Degrees;
        true
    }

    /// The legend: each curve's colour (an index into the palette) and the entries (text and
    /// colour index). Up to [`MAX_LEGEND`] curves are named one by one; more are grouped by
    /// class (the first word of the name), "bumps (n=12)"; with more classes than colours
    /// there is no legend.
    pub fn legend(&self) -> (Vec<usize>, Vec<(String, usize)>) {
        let n = self.series.len();
        if !self.intervals.is_empty() && n + self.intervals.len() <= MAX_LEGEND {
            // Curves and interval series named one by one, intervals in the colours after.
            let names = self.series.iter().map(|s| &s.name);
            let entries = names
                .chain(self.intervals.iter().map(|s| &s.name))
                .enumerate()
                .map(|(i, name)| (name.clone(), i))
                .collect();
            return ((0..n).collect(), entries);
        }
        if n <= MAX_LEGEND {
            let entries = if n >= 2 {
                self.series
                    .iter()
                    .enumerate()
                    .map(|(i, s)| (s.name.clone(), i))
                    .collect()
            } else {
                Vec::new()
            };
            return ((0..n).collect(), entries);
        }
        let class = |s: &Series| s.name.split_whitespace().next().unwrap_or("").to_string();
        let mut classes: Vec<(String, usize)> = Vec::new();
        let colours = self
            .series
            .iter()
            .map(|s| {
                let c = class(s);
                match classes.iter().position(|(k, _)| *k == c) {
                    Some(i) => {
                        classes[i].1 += 1;
                        i
                    }
                    None => {
                        classes.push((c, 1));
                        classes.len() - 1
                    }
                }
            })
            .collect::<Vec<_>>();
        if classes.len() > 8 {
            return ((0..n).map(|i| i % 8).collect(), Vec::new());
        }
        let entries = classes
            .iter()
            .enumerate()
            .map(|(i, (c, k))| {
                let plural = if *k > 1 && !c.ends_with('s') { "s" } else { "" };
                (format!("{c}{plural} (n={k})"), i)
            })
            .collect();
        (colours, entries)
    }

    #[cfg(feature = "plots")]
    fn y_range(&self) -> (f64, f64) {
        if let Some(r) = self.y_range {
            return r;
        }
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(self.reference_y)
            .filter(|y| y.is_finite());
        let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
            (a.min(y), b.max(y))
        });
        if !lo.is_finite() {
            return (-1.0, 1.0);
        }
        let pad = ((hi - lo) * 0.08).max(1e-9);
        (lo - pad, hi + pad)
    }

    #[cfg(feature = "plots")]
    /// Draws the plot; returns the data area's pixel rectangle (x range, y range).
    pub(super) fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<PixelRect> {
        let fail = plot_failure(&self.title);
        let root = titled_panel(root, &self.title, 22)?;
        let (colours, entries) = self.legend();
        let label_font = (FAMILY, 14).into_font();
        let label_style = TextStyle::from(label_font.clone());
        let widest = entries
            .iter()
            .map(|(t, _)| root.estimate_text_size(t, &label_style).map(|s| s.0))
            .collect::<std::result::Result<Vec<u32>, _>>()
            .map_err(|e| fail(&e))?
            .into_iter()
            .max();
        let (w, _) = root.dim_in_pixel();
        // The legend's column: swatch, gap, text, padding; none when there is nothing to name.
        let legend_w = widest.map(|t| (t + 56).min(w / 2)).unwrap_or(0);
        let (chart_area, legend_area) = root.split_horizontally(w - legend_w);
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range();
        let mut builder = ChartBuilder::on(&chart_area);
        builder
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(74);
        let mut chart = axes(
            &mut builder,
            &self.title,
            (x0, x1, self.x_ticks, &self.x_label),
            (y0, y1, self.y_ticks, &self.y_label),
            true,
        )?;
        if let Some(y) = self.reference_y {
            chart
                .draw_series(LineSeries::new(
                    [(x0, y), (x1, y)],
                    RGBColor(120, 120, 120).stroke_width(1),
                ))
                .map_err(|e| fail(&e))?;
            if !self.reference_label.is_empty() {
                let style = (FAMILY, 14)
                    .into_font()
                    .color(&RGBColor(90, 90, 90))
                    .pos(Pos::new(HPos::Right, VPos::Bottom));
                chart
                    .draw_series(std::iter::once(Text::new(
                        self.reference_label.clone(),
                        (x1 - 0.01 * (x1 - x0), y + 0.01 * (y1 - y0)),
                        style,
                    )))
                    .map_err(|e| fail(&e))?;
            }
        }
        for m in &self.markers {
            let style = RGBColor(150, 150, 150).stroke_width(1);
            chart
                .draw_series(LineSeries::new([(m.x, y0), (m.x, y1)], style))
                .map_err(|e| fail(&e))?;
            chart
                .draw_series(std::iter::once(Text::new(
                    m.label.clone(),
                    // At the bottom, where curves that peak near a marker leave room.
                    (m.x, y0 + 0.06 * (y1 - y0)),
                    (FAMILY, 14).into_font().color(&RGBColor(90, 90, 90)),
                )))
                .map_err(|e| fail(&e))?;
        }
        for (s, &c) in self.series.iter().zip(&colours) {
            let colour = COLOURS[c % COLOURS.len()];
            let points: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.1.is_finite())
                .collect();
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| fail(&e))?;
            if points.len() <= 120 {
                chart
                    .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| fail(&e))?;
            }
        }
        for (i, s) in self.intervals.iter().enumerate() {
            let colour = COLOURS[(self.series.len() + i) % COLOURS.len()];
            let cap = 0.006 * (x1 - x0);
            for &(x, y, lo, hi) in &s.points {
                if !(y.is_finite() && lo.is_finite() && hi.is_finite()) {
                    continue;
                }
                for segment in [
                    [(x, lo), (x, hi)],
                    [(x - cap, lo), (x + cap, lo)],
                    [(x - cap, hi), (x + cap, hi)],
                ] {
                    chart
                        .draw_series(LineSeries::new(segment, colour.stroke_width(1)))
                        .map_err(|e| fail(&e))?;
                }
                chart
                    .draw_series(std::iter::once(Circle::new((x, y), 4, colour.filled())))
                    .map_err(|e| fail(&e))?;
            }
        }
        let (px, py) = chart.plotting_area().get_pixel_range();
        if !entries.is_empty() {
            // Beside the data area, level with its top.
            let (ox, oy) = legend_area.get_base_pixel();
            let (_, root_y) = root.get_base_pixel();
            let top = py.start - oy.max(root_y) + 2;
            let line = 22;
            let height = line * entries.len() as i32 + 10;
            let right = legend_w as i32 - 10;
            legend_area
                .draw(&Rectangle::new(
                    [(4, top), (right, top + height)],
                    RGBColor(160, 160, 160).stroke_width(1),
                ))
                .map_err(|e| fail(&e))?;
            for (i, (text, c)) in entries.iter().enumerate() {
                let colour = COLOURS[c % COLOURS.len()];
                let y = top + 16 + line * i as i32;
                legend_area
                    .draw(&PathElement::new(
                        vec![(12, y), (36, y)],
                        colour.stroke_width(3),
                    ))
                    .map_err(|e| fail(&e))?;
                legend_area
                    .draw(&Text::new(
                        text.clone(),
                        (44, y - 8),
                        label_font.clone().color(&BLACK),
                    ))
                    .map_err(|e| fail(&e))?;
            }
            let _ = ox;
        }
        root.present().map_err(|e| fail(&e))?;
        Ok((px, py))
    }

    #[cfg(feature = "plots")]
    /// The plot as an SVG document.
    pub fn svg(&self) -> Result<String> {
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, self.size).into_drawing_area();
            self.draw(root)?;
        }
        Ok(text)
    }

    #[cfg(feature = "plots")]
    /// The plot as 8-bit sRGB pixels, row-major, 3 bytes each, and the data area's pixel
    /// rectangle (columns, rows).
    pub fn rgb(&self) -> Result<(Vec<u8>, PixelRect)> {
        let (w, h) = self.size;
        let mut buf = vec![0u8; w as usize * h as usize * 3];
        let rect = {
            let root = BitMapBackend::with_buffer(&mut buf, self.size).into_drawing_area();
            self.draw(root)?
        };
        Ok((buf, rect))
    }

    #[cfg(feature = "plots")]
    /// Writes the plot as an 8-bit PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        write_rgb_png(path, &self.rgb()?.0, self.size)
    }

    #[cfg(feature = "plots")]
    /// Writes the plot as SVG, atomically.
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        io::write_text(path, &self.svg()?)
    }
}

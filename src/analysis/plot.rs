//! Figures, as PNG and SVG, drawn with `plotters`: line plots ([`LinePlot`], stacked in a
//! [`Figure`]), false-colour maps with a colour bar and named target outlines ([`MapFigure`]),
//! and captions set under pictures ([`caption_pixels`]). This is the one home of the figure
//! helpers (ticks, legends, colour bars, outlines, text) that every command's figures use.
//!
//! Line plots put their legend in a column right of the data, never over it; with more curves
//! than [`MAX_LEGEND`] the curves are grouped by class (the first word of their names, e.g.
//! "bump r1c2" → "bumps (n=12)"), one colour and one legend entry per class. Axes carry units;
//! angle axes that cover the circle run the full 0–360° with the curve closed
//! ([`LinePlot::close_circle`]); integer quantities get integer ticks ([`Ticks::Integer`]).
//!
//! Text is set in DejaVu Sans, shipped in `assets/fonts/` (Bitstream Vera licence, see
//! `assets/fonts/LICENSE-DejaVu.txt`) and compiled in, so figures look the same on every
//! machine and need no system fonts. Every file is written atomically.

use crate::colormap::Colormap;
#[cfg(feature = "plots")]
use crate::error::Error;
use crate::error::Result;
#[cfg(feature = "plots")]
use crate::grid::Grid;
use crate::grid::{Mask, RgbImage};
#[cfg(feature = "plots")]
use crate::io::{self, BitDepth};
#[cfg(feature = "plots")]
use plotters::prelude::*;
#[cfg(feature = "plots")]
use plotters::style::text_anchor::{HPos, Pos, VPos};
#[cfg(feature = "plots")]
use plotters::style::{register_font, FontStyle};
use std::path::Path;
#[cfg(feature = "plots")]
use std::sync::Once;

#[cfg(feature = "plots")]
/// The font every figure uses.
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

#[cfg(feature = "plots")]
/// The family name the font is registered under.
const FAMILY: &str = "sans-serif";

#[cfg(feature = "plots")]
static REGISTER: Once = Once::new();

#[cfg(feature = "plots")]
fn register() {
    REGISTER.call_once(|| {
        // A failure shows up as a drawing error naming the font, below.
        let _ = register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

#[cfg(feature = "plots")]
/// Colours that stay distinct for colour-blind readers (Okabe & Ito), cycled.
const COLOURS: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

/// Plots with more curves than this group them by class in the legend (one colour and one
/// entry per class) instead of naming each.
pub const MAX_LEGEND: usize = 8;

/// The colour of target outlines on maps (8-bit sRGB).
pub const OUTLINE: [u8; 3] = [255, 40, 40];

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

/// How an axis's ticks are placed and written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ticks {
    /// Round steps (1, 2 or 5 times a power of ten), with as many decimals as the step needs.
    Auto,
    /// Whole numbers only (counts: cycles, iterations), written without decimals.
    Integer,
    /// Angles in degrees: steps of 15, 30, 45 or 90 on wide axes, written without decimals.
    Degrees,
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
    /// use shadelab::analysis::plot::{LinePlot, Series, Ticks};
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
        if !same || super::prior_sweep::circle_step(&xs).is_none() {
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
    fn draw<DB: DrawingBackend>(
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

#[cfg(feature = "plots")]
/// The error of a plot titled `title` that could not be drawn.
fn plot_failure(title: &str) -> impl Fn(&dyn std::fmt::Display) -> Error + '_ {
    move |e| Error::Compute(format!("cannot draw the plot '{title}': {e}"))
}

#[cfg(feature = "plots")]
/// A panel's area filled white with `title` set above it in `size` points: what is left for
/// the plot.
fn titled_panel<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    size: u32,
) -> Result<DrawingArea<DB, plotters::coord::Shift>> {
    register();
    let fail = plot_failure(title);
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    root.titled(title, (FAMILY, size)).map_err(|e| fail(&e))
}

/// A rectangle of pixels: columns `.0`, rows `.1` (half-open).
pub type PixelRect = (std::ops::Range<i32>, std::ops::Range<i32>);

#[cfg(feature = "plots")]
/// One axis of [`axes`]: from, to, its ticks and its label.
type AxisSpec<'s> = (f64, f64, Ticks, &'s str);

#[cfg(feature = "plots")]
/// The one way every figure draws its axes: `x` and `y` with their ticks, tick labels and
/// labels, and with `grid` light grey lines at the ticks. `what` names the figure in errors.
fn axes<'a, DB: DrawingBackend>(
    builder: &mut ChartBuilder<'a, '_, DB>,
    what: &str,
    x: AxisSpec<'_>,
    y: AxisSpec<'_>,
    grid: bool,
) -> Result<ChartContext<'a, DB, Cartesian2d<TickAxis, TickAxis>>> {
    let fail =
        |e: &dyn std::fmt::Display| Error::Compute(format!("cannot draw the figure '{what}': {e}"));
    let (xt, xd) = ticks(x.0, x.1, x.2);
    let (yt, yd) = ticks(y.0, y.1, y.2);
    let mut chart = builder
        .build_cartesian_2d(TickAxis::new(x.0, x.1, xt), TickAxis::new(y.0, y.1, yt))
        .map_err(|e| fail(&e))?;
    let (fx, fy) = (
        move |v: &f64| tick_text(*v, xd),
        move |v: &f64| tick_text(*v, yd),
    );
    let mut mesh = chart.configure_mesh();
    mesh.x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_desc(x.3)
        .y_desc(y.3)
        .label_style((FAMILY, 15))
        .axis_desc_style((FAMILY, 17))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(220, 220, 220));
    if !grid {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(|e| fail(&e))?;
    Ok(chart)
}

#[cfg(feature = "plots")]
/// A linear axis from `lo` to `hi` whose ticks (and grid lines) are exactly `ticks`.
#[derive(Clone)]
struct TickAxis {
    range: plotters::coord::types::RangedCoordf64,
    ticks: Vec<f64>,
}

#[cfg(feature = "plots")]
impl TickAxis {
    fn new(lo: f64, hi: f64, ticks: Vec<f64>) -> TickAxis {
        TickAxis {
            range: (lo..hi).into(),
            ticks,
        }
    }
}

#[cfg(feature = "plots")]
impl plotters::coord::ranged1d::Ranged for TickAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.range.map(value, limit)
    }
    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.max_num_points() == 0 {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.range.range()
    }
}

#[cfg(feature = "plots")]
/// Tick positions from `lo` to `hi` and the decimals their labels need.
fn ticks(lo: f64, hi: f64, kind: Ticks) -> (Vec<f64>, usize) {
    let span = (hi - lo).abs().max(1e-12);
    let round_step = |target: f64| {
        let raw = span / target;
        let mag = 10f64.powf(raw.log10().floor());
        [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * mag)
            .find(|s| *s >= raw * 0.999)
            .unwrap_or(10.0 * mag)
    };
    let (step, decimals) = match kind {
        Ticks::Degrees if span >= 60.0 => {
            let step = [15.0, 30.0, 45.0, 90.0, 180.0]
                .into_iter()
                .find(|s| span / s <= 12.0)
                .unwrap_or(180.0);
            (step, 0)
        }
        Ticks::Integer => (round_step(8.0).max(1.0).round(), 0),
        _ => {
            let step = round_step(8.0);
            (step, (-step.log10().floor()).clamp(0.0, 8.0) as usize)
        }
    };
    let first = (lo.min(hi) / step - 1e-9).ceil() as i64;
    let last = (lo.max(hi) / step + 1e-9).floor() as i64;
    let ticks = (first..=last).map(|k| k as f64 * step).collect();
    (ticks, decimals)
}

#[cfg(feature = "plots")]
/// A tick label with `decimals` decimals, never "-0".
fn tick_text(v: f64, decimals: usize) -> String {
    let text = format!("{v:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        text.trim_start_matches('-').to_string()
    } else {
        text
    }
}

/// The range of `xs` for an axis: smallest to largest, or one unit either side of a single
/// value (or of the first, when they are all equal).
///
/// ```
/// use shadelab::analysis::plot::span;
/// assert_eq!(span(&[30.0, 0.0, 90.0]), (0.0, 90.0));
/// assert_eq!(span(&[5.0]), (4.0, 6.0));
/// ```
pub fn span(xs: &[f64]) -> (f64, f64) {
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, lo + 1.0)
    }
}

/// Several plots stacked top to bottom in one picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// The panels, top first.
    pub panels: Vec<LinePlot>,
    /// Size in pixels of the whole figure.
    pub size: (u32, u32),
}

#[cfg(feature = "plots")]
/// A figure of several panels drawn into one picture, written by [`write_png_of`] and
/// [`write_svg_of`].
trait Drawn {
    /// Size in pixels of the whole picture.
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `root`, a backend's whole area.
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, plotters::coord::Shift>)
        -> Result<()>;
}

#[cfg(feature = "plots")]
/// Draws `figure` into an RGB buffer and writes it as an 8-bit PNG, atomically.
fn write_png_of(figure: &impl Drawn, path: &Path) -> Result<()> {
    let (w, h) = figure.size();
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        figure.draw(root)?;
    }
    write_rgb_png(path, &buf, (w, h))
}

#[cfg(feature = "plots")]
/// Draws `figure` as SVG text and writes it, atomically.
fn write_svg_of(figure: &impl Drawn, path: &Path) -> Result<()> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, figure.size()).into_drawing_area();
        figure.draw(root)?;
    }
    io::write_text(path, &text)
}

#[cfg(feature = "plots")]
impl Drawn for Figure {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<()> {
        let areas = root.split_evenly((self.panels.len().max(1), 1));
        for (panel, area) in self.panels.iter().zip(areas) {
            panel.draw(area)?;
        }
        Ok(())
    }
}

impl Figure {
    #[cfg(feature = "plots")]
    /// Writes the figure as an 8-bit PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        write_png_of(self, path)
    }

    #[cfg(feature = "plots")]
    /// Writes the figure as SVG, atomically.
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        write_svg_of(self, path)
    }
}

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
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<()> {
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
        write_png_of(self, path)
    }

    /// Writes the figure as SVG, atomically.
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        write_svg_of(self, path)
    }
}

/// A colour bar: which map, the values at its two ends, and what the values are (with unit).
#[derive(Debug, Clone, PartialEq)]
pub struct ColourBar {
    /// The map.
    pub colormap: Colormap,
    /// The values at the bottom and the top of the bar.
    pub range: (f64, f64),
    /// What the values are, with their unit.
    pub label: String,
}

/// A named region outlined on a map.
#[derive(Debug, Clone, PartialEq)]
pub struct Outline {
    /// The region, in the map's pixels.
    pub mask: Mask,
    /// Its name, written beside it.
    pub name: String,
}

/// A picture of values in false colour, with axes, a colour bar with labelled ticks, and target
/// outlines with their names; PNG only.
#[derive(Debug, Clone, PartialEq)]
pub struct MapFigure {
    /// The title.
    pub title: String,
    /// The picture, linear RGB, row 0 at the top; painted with [`ColourBar::colormap`] (e.g.
    /// by [`Colormap::paint`]), possibly with marks of its own drawn in.
    pub picture: RgbImage,
    /// Display encoding of the picture and the bar: `v^(1/gamma)`, or the values as codes.
    pub gamma: Option<f64>,
    /// The x axis label, with its unit.
    pub x_label: String,
    /// The y axis label, with its unit.
    pub y_label: String,
    /// The x coordinates of the picture's left and right edges.
    pub x_range: (f64, f64),
    /// The y coordinates of the picture's bottom and top edges.
    pub y_range: (f64, f64),
    /// The colour bar.
    pub bar: ColourBar,
    /// Outlined regions.
    pub outlines: Vec<Outline>,
    /// Size in pixels.
    pub size: (u32, u32),
}

/// Outlines get their names written when there are at most this many.
pub const MAX_NAMED_OUTLINES: usize = 16;

impl MapFigure {
    /// A figure of `picture` in pixel coordinates (x right, y up, 1 unit = 1 pixel), no
    /// outlines, 900 × 720, display gamma 2.2.
    pub fn new(title: &str, picture: RgbImage, bar: ColourBar) -> MapFigure {
        let (w, h) = (picture.width() as f64, picture.height() as f64);
        MapFigure {
            title: title.into(),
            picture,
            gamma: Some(2.2),
            x_label: "x (pixels)".into(),
            y_label: "y (pixels, up)".into(),
            x_range: (0.0, w),
            y_range: (0.0, h),
            bar,
            outlines: Vec::new(),
            size: (900, 720),
        }
    }

    /// Where the map and the bar go: (map left, top, width, height) and (bar left, width).
    #[cfg(feature = "plots")]
    fn layout(&self) -> ((i32, i32, i32, i32), (i32, i32)) {
        let (w, h) = (self.size.0 as i32, self.size.1 as i32);
        let (left, top, bottom, right) = (84, 44, 62, 170);
        let (aw, ah) = ((w - left - right).max(8), (h - top - bottom).max(8));
        let (pw, ph) = (
            self.picture.width().max(1) as f64,
            self.picture.height().max(1) as f64,
        );
        let scale = (aw as f64 / pw).min(ah as f64 / ph);
        let (mw, mh) = (
            ((pw * scale).round() as i32).max(1),
            ((ph * scale).round() as i32).max(1),
        );
        let mx = left + (aw - mw) / 2;
        let my = top + (ah - mh) / 2;
        ((mx, my, mw, mh), (mx + mw + 28, 26))
    }

    #[cfg(feature = "plots")]
    /// The size in pixels at which the picture is shown (its aspect kept): a picture made at
    /// this size is shown pixel for pixel.
    pub fn map_size(&self) -> (usize, usize) {
        let ((_, _, mw, mh), _) = self.layout();
        (mw as usize, mh as usize)
    }

    #[cfg(feature = "plots")]
    /// The figure as 8-bit sRGB pixels, row-major, 3 bytes each, and the map's and the colour
    /// bar's pixel rectangles.
    pub fn rgb(&self) -> Result<(Vec<u8>, PixelRect, PixelRect)> {
        register();
        let fail = |e: &dyn std::fmt::Display| {
            Error::Compute(format!("cannot draw the figure '{}': {e}", self.title))
        };
        let (w, h) = self.size;
        let ((mx, my, mw, mh), (bx, bw)) = self.layout();
        let mut buf = vec![255u8; w as usize * h as usize * 3];
        let (map_rect, bar_rect) = {
            let root = BitMapBackend::with_buffer(&mut buf, self.size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| fail(&e))?;
            root.draw(&Text::new(
                self.title.clone(),
                (mx, 12),
                (FAMILY, 21).into_font().color(&BLACK),
            ))
            .map_err(|e| fail(&e))?;
            let (x0, x1) = self.x_range;
            let (y0, y1) = self.y_range;
            let area = root
                .clone()
                .shrink((mx - 80, my), ((mw + 80) as u32, (mh + 58) as u32));
            let mut builder = ChartBuilder::on(&area);
            builder.x_label_area_size(58).y_label_area_size(80);
            let chart = axes(
                &mut builder,
                &self.title,
                (x0, x1, Ticks::Auto, &self.x_label),
                (y0, y1, Ticks::Auto, &self.y_label),
                false,
            )?;
            let map_rect = chart.plotting_area().get_pixel_range();
            let (b0, b1) = self.bar.range;
            let (bt, bd) = ticks(b0, b1, Ticks::Auto);
            let bar_area = root
                .clone()
                .shrink((bx, my), ((bw + 140) as u32, mh as u32));
            let mut bar = ChartBuilder::on(&bar_area)
                .set_label_area_size(LabelAreaPosition::Right, 140)
                .build_cartesian_2d(0.0..1.0, TickAxis::new(b0, b1, bt))
                .map_err(|e| fail(&e))?;
            let fb = move |v: &f64| tick_text(*v, bd);
            bar.configure_mesh()
                .disable_mesh()
                .disable_x_axis()
                .y_label_formatter(&fb)
                .label_style((FAMILY, 15))
                .axis_desc_style((FAMILY, 17))
                .draw()
                .map_err(|e| fail(&e))?;
            let bar_rect = bar.plotting_area().get_pixel_range();
            root.present().map_err(|e| fail(&e))?;
            (map_rect, bar_rect)
        };
        self.paint_map(&mut buf, &map_rect);
        self.paint_bar(&mut buf, &bar_rect);
        self.annotate(&mut buf, &map_rect, &bar_rect)?;
        Ok((buf, map_rect, bar_rect))
    }

    #[cfg(feature = "plots")]
    /// Which picture pixel a figure pixel of the map shows (nearest neighbour).
    fn source(&self, rect: &PixelRect, x: i32, y: i32) -> Option<(usize, usize)> {
        let (cols, rows) = rect;
        if !cols.contains(&x) || !rows.contains(&y) {
            return None;
        }
        let (pw, ph) = (self.picture.width(), self.picture.height());
        let c = ((x - cols.start) as usize * pw) / (cols.end - cols.start) as usize;
        let r = ((y - rows.start) as usize * ph) / (rows.end - rows.start) as usize;
        Some((c.min(pw.saturating_sub(1)), r.min(ph.saturating_sub(1))))
    }

    #[cfg(feature = "plots")]
    fn paint_map(&self, buf: &mut [u8], rect: &PixelRect) {
        let (cols, rows) = rect.clone();
        let width = self.size.0 as usize;
        let inside = |m: &Mask, x: i32, y: i32| {
            self.source(rect, x, y)
                .map(|(c, r)| *m.get(c, r))
                .unwrap_or(false)
        };
        for y in rows {
            for x in cols.clone() {
                let Some((c, r)) = self.source(rect, x, y) else {
                    continue;
                };
                let mut colour = self.picture.get(c, r).map(|v| encode(v, self.gamma));
                // An outline: a region's pixel within 2 pixels of a pixel outside it.
                let edge = self.outlines.iter().any(|o| {
                    inside(&o.mask, x, y)
                        && [
                            (-2, 0),
                            (2, 0),
                            (0, -2),
                            (0, 2),
                            (-1, 0),
                            (1, 0),
                            (0, -1),
                            (0, 1),
                        ]
                        .iter()
                        .any(|&(dx, dy)| !inside(&o.mask, x + dx, y + dy))
                });
                if edge {
                    colour = OUTLINE;
                }
                let i = (y as usize * width + x as usize) * 3;
                buf[i..i + 3].copy_from_slice(&colour);
            }
        }
    }

    #[cfg(feature = "plots")]
    fn paint_bar(&self, buf: &mut [u8], rect: &PixelRect) {
        let (cols, rows) = rect.clone();
        let width = self.size.0 as usize;
        let n = (rows.end - rows.start - 1).max(1) as f64;
        for y in rows.clone() {
            // The top row is the map's end (1), the bottom row its start (0).
            let t = 1.0 - (y - rows.start) as f64 / n;
            let colour = self.bar.colormap.linear(t).map(|v| encode(v, self.gamma));
            for x in cols.clone() {
                let i = (y as usize * width + x as usize) * 3;
                buf[i..i + 3].copy_from_slice(&colour);
            }
        }
    }

    #[cfg(feature = "plots")]
    /// Frames the map and the bar, writes the bar's label beside its tick labels, and each
    /// outline's name above its region's top left corner on a white box (when there are at
    /// most [`MAX_NAMED_OUTLINES`]).
    fn annotate(&self, buf: &mut [u8], rect: &PixelRect, bar: &PixelRect) -> Result<()> {
        let fail = |e: &dyn std::fmt::Display| {
            Error::Compute(format!("cannot draw the figure '{}': {e}", self.title))
        };
        let root = BitMapBackend::with_buffer(buf, self.size).into_drawing_area();
        for (cols, rows) in [rect, bar] {
            root.draw(&Rectangle::new(
                [(cols.start - 1, rows.start - 1), (cols.end, rows.end)],
                BLACK.stroke_width(1),
            ))
            .map_err(|e| fail(&e))?;
        }
        let label = TextStyle::from((FAMILY, 17).into_font())
            .transform(FontTransform::Rotate270)
            .color(&BLACK);
        let (lw, _) = root
            .estimate_text_size(&self.bar.label, &TextStyle::from((FAMILY, 17).into_font()))
            .map_err(|e| fail(&e))?;
        let middle = (bar.1.start + bar.1.end) / 2;
        root.draw(&Text::new(
            self.bar.label.clone(),
            (bar.0.end + 62, middle + lw as i32 / 2),
            label,
        ))
        .map_err(|e| fail(&e))?;
        if self.outlines.is_empty() || self.outlines.len() > MAX_NAMED_OUTLINES {
            return root.present().map_err(|e| fail(&e));
        }
        let font = (FAMILY, 18).into_font();
        let style = TextStyle::from(font.clone());
        let (cols, rows) = rect;
        let (pw, ph) = (self.picture.width() as f64, self.picture.height() as f64);
        let sx = (cols.end - cols.start) as f64 / pw;
        let sy = (rows.end - rows.start) as f64 / ph;
        for o in &self.outlines {
            let Some((c0, r0, c1, _)) = bbox(&o.mask) else {
                continue;
            };
            let (tw, th) = root
                .estimate_text_size(&o.name, &style)
                .map_err(|e| fail(&e))?;
            let x = cols.start + ((c0 + c1 + 1) as f64 * 0.5 * sx) as i32 - tw as i32 / 2;
            let y = (rows.start + (r0 as f64 * sy) as i32 - th as i32 - 8).max(rows.start);
            root.draw(&Rectangle::new(
                [(x - 3, y - 2), (x + tw as i32 + 3, y + th as i32 + 2)],
                WHITE.mix(0.85).filled(),
            ))
            .map_err(|e| fail(&e))?;
            root.draw(&Text::new(
                o.name.clone(),
                (x, y),
                font.clone().color(&BLACK),
            ))
            .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
        Ok(())
    }

    #[cfg(feature = "plots")]
    /// Writes the figure as an 8-bit PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        write_rgb_png(path, &self.rgb()?.0, self.size)
    }
}

/// The first and last column and row of a mask's pixels.
#[cfg(feature = "plots")]
fn bbox(mask: &Mask) -> Option<(usize, usize, usize, usize)> {
    let mut b: Option<(usize, usize, usize, usize)> = None;
    for r in 0..mask.height() {
        for c in 0..mask.width() {
            if *mask.get(c, r) {
                b = Some(match b {
                    None => (c, r, c, r),
                    Some((c0, r0, c1, r1)) => (c0.min(c), r0.min(r), c1.max(c), r1.max(r)),
                });
            }
        }
    }
    b
}

/// A linear value (clamped to 0..1) as an 8-bit code, display-encoded with `v^(1/gamma)` when
/// a gamma is given: the same codes [`crate::io::write_rgb`] writes.
pub fn encode(v: f64, gamma: Option<f64>) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let v = match gamma {
        Some(g) => v.powf(1.0 / g),
        None => v,
    };
    (v * 255.0).round() as u8
}

/// Text set on a picture: where its top centre goes, the text and its size in pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct Caption {
    /// Top centre, in pixels (column, row).
    pub at: (i32, i32),
    /// The text, one line; cut with "…" when wider than `width`.
    pub text: String,
    /// Font size in pixels.
    pub size: f64,
    /// The widest the text may be, in pixels.
    pub width: u32,
}

#[cfg(feature = "plots")]
/// Sets `captions` in black on 8-bit sRGB pixels `buf` of `size` (row-major, 3 bytes each).
pub fn caption_pixels(buf: &mut [u8], size: (u32, u32), captions: &[Caption]) -> Result<()> {
    register();
    let fail = |e: &dyn std::fmt::Display| Error::Compute(format!("cannot set a caption: {e}"));
    let root = BitMapBackend::with_buffer(buf, size).into_drawing_area();
    for c in captions {
        let font = (FAMILY, c.size).into_font();
        let style = TextStyle::from(font.clone());
        let mut text = c.text.clone();
        loop {
            let (tw, _) = root
                .estimate_text_size(&text, &style)
                .map_err(|e| fail(&e))?;
            if tw <= c.width || text.chars().count() <= 2 {
                root.draw(&Text::new(
                    text.clone(),
                    (c.at.0 - tw as i32 / 2, c.at.1),
                    font.clone().color(&BLACK),
                ))
                .map_err(|e| fail(&e))?;
                break;
            }
            // One character shorter, ending in an ellipsis.
            let mut chars: Vec<char> = text.trim_end_matches('…').chars().collect();
            chars.pop();
            text = chars.into_iter().collect::<String>().trim_end().to_string() + "…";
        }
    }
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

#[cfg(feature = "plots")]
/// Writes 8-bit sRGB bytes as a PNG, unchanged, atomically.
pub fn write_rgb_png(path: &Path, buf: &[u8], (w, h): (u32, u32)) -> Result<()> {
    let image = Grid::from_vec(
        w as usize,
        h as usize,
        buf.chunks_exact(3)
            .map(|p| {
                [
                    p[0] as f64 / 255.0,
                    p[1] as f64 / 255.0,
                    p[2] as f64 / 255.0,
                ]
            })
            .collect(),
    )?;
    io::write_rgb(path, &image, BitDepth::Eight, None)
}

/// Without the `plots` feature figures are not drawn: their writers write nothing and succeed,
/// so an embedding (Python, WebAssembly) gets every number and data file without a plotting
/// library.
#[cfg(not(feature = "plots"))]
mod without_plots {
    use super::{Figure, LineAndPolar, LinePlot, MapFigure, Path, Result};

    impl LineAndPolar {
        /// Writes nothing: this build has no plots.
        pub fn write_png(&self, _path: &Path) -> Result<()> {
            Ok(())
        }
        /// Writes nothing: this build has no plots.
        pub fn write_svg(&self, _path: &Path) -> Result<()> {
            Ok(())
        }
    }

    impl LinePlot {
        /// Writes nothing: this build has no plots.
        pub fn write_png(&self, _path: &Path) -> Result<()> {
            Ok(())
        }
        /// Writes nothing: this build has no plots.
        pub fn write_svg(&self, _path: &Path) -> Result<()> {
            Ok(())
        }
    }

    impl Figure {
        /// Writes nothing: this build has no plots.
        pub fn write_png(&self, _path: &Path) -> Result<()> {
            Ok(())
        }
        /// Writes nothing: this build has no plots.
        pub fn write_svg(&self, _path: &Path) -> Result<()> {
            Ok(())
        }
    }

    impl MapFigure {
        /// Writes nothing: this build has no plots.
        pub fn write_png(&self, _path: &Path) -> Result<()> {
            Ok(())
        }
    }
}

#[cfg(all(test, feature = "plots"))]
mod tests {
    use super::*;

    fn cosine(name: &str, phase: f64) -> Series {
        Series {
            name: name.into(),
            points: (0..12)
                .map(|i| {
                    let t = i as f64 * 30.0;
                    (t, (t + phase).to_radians().cos())
                })
                .collect(),
        }
    }

    #[test]
    fn a_plot_draws_its_curve_in_colour_and_text_in_svg() {
        let mut plot = LinePlot::new("test", "tilt (°)", "convexity", (0.0, 360.0));
        plot.reference_y = Some(0.0);
        plot.series.push(cosine("disc", 0.0));
        plot.size = (320, 200);
        let (rgb, _) = plot.rgb().unwrap();
        assert_eq!(rgb.len(), 320 * 200 * 3);
        // The curve's blue is there, and text was drawn (dark pixels beside white).
        let blue = rgb.chunks_exact(3).filter(|p| p == &[0, 114, 178]).count();
        assert!(blue > 100, "{blue}");
        let dark = rgb
            .chunks_exact(3)
            .filter(|p| p.iter().all(|&v| v < 80))
            .count();
        assert!(dark > 50, "{dark}");
        let svg = plot.svg().unwrap();
        assert!(svg.contains("<svg") && svg.contains("convexity"));
    }

    #[test]
    fn a_circle_closes_and_its_axis_ends_at_360() {
        let mut plot = LinePlot::new("t", "assumed tilt (°)", "convexity", (0.0, 330.0));
        plot.series.push(cosine("a", 0.0));
        plot.series.push(cosine("b", 90.0));
        assert!(plot.close_circle());
        assert_eq!(
            plot.series[1].points[12],
            (360.0, plot.series[1].points[0].1)
        );
        let texts = svg_texts(&plot.svg().unwrap());
        assert_eq!(
            texts
                .iter()
                .filter(|t| t.parse::<f64>().is_ok())
                .max_by(|a, b| {
                    a.parse::<f64>()
                        .unwrap()
                        .total_cmp(&b.parse::<f64>().unwrap())
                }),
            Some(&"360".to_string()),
            "the last tick is 360"
        );
        assert!(texts.contains(&"0".into()) && texts.contains(&"90".into()));
        // Not a circle: left alone.
        let mut open = LinePlot::new("t", "x", "y", (0.0, 90.0));
        open.series.push(Series {
            name: "a".into(),
            points: vec![(0.0, 1.0), (90.0, 2.0)],
        });
        assert!(!open.close_circle());
        assert_eq!(open.series[0].points.len(), 2);
    }

    #[test]
    fn integer_ticks_are_whole_numbers() {
        let mut plot = LinePlot::new("conv", "cycle (count)", "y", (1.0, 4.0));
        plot.x_ticks = Ticks::Integer;
        plot.series.push(Series {
            name: "a".into(),
            points: vec![(1.0, 1.0), (2.0, 0.5), (3.0, 0.2), (4.0, 0.1)],
        });
        let texts = svg_texts(&plot.svg().unwrap());
        assert!(
            texts.contains(&"2".into()) && texts.contains(&"4".into()),
            "{texts:?}"
        );
        assert!(!texts.contains(&"2.0".into()) && !texts.contains(&"1.5".into()));
        let (t, d) = ticks(1.0, 3.0, Ticks::Integer);
        assert_eq!((t, d), (vec![1.0, 2.0, 3.0], 0));
    }

    #[test]
    fn many_curves_are_grouped_by_class_in_a_legend_beside_the_data() {
        let mut plot = LinePlot::new("many", "tilt (°)", "convexity", (0.0, 330.0));
        for i in 0..24 {
            let kind = if i % 2 == 0 { "bump" } else { "dimple" };
            let phase = if i % 2 == 0 { 0.0 } else { 180.0 };
            plot.series
                .push(cosine(&format!("{kind} r{}c{}", i / 6, i % 6), phase));
        }
        let (colours, entries) = plot.legend();
        assert_eq!(
            entries,
            vec![
                ("bumps (n=12)".to_string(), 0),
                ("dimples (n=12)".to_string(), 1)
            ]
        );
        assert!(colours.iter().enumerate().all(|(i, &c)| c == i % 2));
        let texts = svg_texts(&plot.svg().unwrap());
        assert!(texts.contains(&"bumps (n=12)".into()) && texts.contains(&"dimples (n=12)".into()));
        // The legend's swatches (3 px lines of the class colours) lie right of the data area.
        let (rgb, (cols, rows)) = plot.rgb().unwrap();
        let (w, _) = plot.size;
        let orange = [213u8, 94, 0];
        let mut in_data = 0;
        let mut right = 0;
        for (i, p) in rgb.chunks_exact(3).enumerate() {
            if p == orange {
                let x = (i % w as usize) as i32;
                if x >= cols.end + 4 {
                    right += 1;
                } else if cols.contains(&x) {
                    in_data += 1;
                }
            }
        }
        assert!(right > 40, "a swatch right of the data area: {right}");
        assert!(in_data > 100, "the dimples' curves: {in_data}");
        // The legend box's border does not reach into the data area.
        let grey: Vec<(i32, i32)> = rgb
            .chunks_exact(3)
            .enumerate()
            .filter(|(_, p)| *p == [160, 160, 160])
            .map(|(i, _)| ((i % w as usize) as i32, (i / w as usize) as i32))
            .collect();
        assert!(grey.iter().any(|&(x, _)| x >= cols.end), "a legend box");
        assert!(
            !grey
                .iter()
                .any(|&(x, y)| cols.contains(&x) && rows.contains(&y)),
            "the legend box is drawn in the data area"
        );
    }

    /// The text of every `<text>` element of an SVG, trimmed.
    fn svg_texts(svg: &str) -> Vec<String> {
        svg.split("</text>")
            .filter_map(|part| part.rsplit_once('>').map(|(_, t)| t.trim().to_string()))
            .filter(|t| !t.is_empty())
            .collect()
    }

    #[test]
    fn tick_labels_have_enough_decimals_and_no_negative_zero() {
        let (_, d) = ticks(0.0, 360.0, Ticks::Auto);
        assert_eq!(tick_text(90.0, d), "90");
        let (t, d) = ticks(-0.15, 0.15, Ticks::Auto);
        assert_eq!(tick_text(-0.0, d), "0.00");
        assert_eq!(tick_text(-0.000001, d), "0.00");
        assert!(t.iter().any(|v| tick_text(*v, d) == "0.10"), "{t:?}");
    }

    #[test]
    fn a_map_has_a_colour_bar_from_the_maps_start_to_its_end_and_outlines() {
        let values = Grid::from_fn(40, 20, |c, _| c as f64 / 39.0);
        let picture = Colormap::Viridis.paint(&values, (0.0, 1.0), None, [1.0; 3]);
        let bar = ColourBar {
            colormap: Colormap::Viridis,
            range: (0.0, 1.0),
            label: "R (linear luminance)".into(),
        };
        let mut fig = MapFigure::new("map", picture, bar);
        fig.outlines.push(Outline {
            mask: Grid::from_fn(40, 20, |c, r| (10..20).contains(&c) && (5..15).contains(&r)),
            name: "A".into(),
        });
        fig.size = (600, 400);
        let (rgb, map, bar) = fig.rgb().unwrap();
        let at = |x: i32, y: i32| {
            let i = (y as usize * 600 + x as usize) * 3;
            [rgb[i], rgb[i + 1], rgb[i + 2]]
        };
        let code = |t: f64| Colormap::Viridis.linear(t).map(|v| encode(v, Some(2.2)));
        let mid = (bar.0.start + bar.0.end) / 2;
        assert_eq!(at(mid, bar.1.start), code(1.0), "top of the bar");
        assert_eq!(at(mid, bar.1.end - 1), code(0.0), "bottom of the bar");
        // The map keeps the picture's aspect (2:1) and shows its left and right ends.
        let (mw, mh) = (map.0.end - map.0.start, map.1.end - map.1.start);
        assert!((mw - 2 * mh).abs() <= 2, "{mw} x {mh}");
        assert_eq!(at(map.0.start, map.1.end - 1), code(0.0));
        assert_eq!(at(map.0.end - 1, map.1.end - 1), code(1.0));
        // The outline is red around the region (its left edge at column 10 of 40).
        // The first figure column showing picture column 10.
        let x = map.0.start + (10 * mw + 39) / 40;
        let y = map.1.start + (10 * mh) / 20;
        assert_eq!(at(x, y), OUTLINE);
        assert_ne!(at(x + 6, y), OUTLINE, "inside the region is the map");
    }

    #[test]
    fn captions_are_drawn_and_cut_to_their_width() {
        let (w, h) = (200u32, 40u32);
        let mut buf = vec![255u8; (w * h * 3) as usize];
        caption_pixels(
            &mut buf,
            (w, h),
            &[Caption {
                at: (100, 4),
                text: "a caption far too long to fit in the narrow cell it is given".into(),
                size: 14.0,
                width: 120,
            }],
        )
        .unwrap();
        let dark: Vec<usize> = buf
            .chunks_exact(3)
            .enumerate()
            .filter(|(_, p)| p[0] < 128)
            .map(|(i, _)| i % w as usize)
            .collect();
        assert!(dark.len() > 50);
        assert!(
            dark.iter().all(|&x| (38..=162).contains(&x)),
            "cut to 120 px"
        );
    }
}

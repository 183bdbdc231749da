//! Line plots of analysis results, as PNG and SVG, drawn with `plotters`.
//!
//! Text is set in DejaVu Sans, shipped in `assets/fonts/` (Bitstream Vera licence, see
//! `assets/fonts/LICENSE-DejaVu.txt`) and compiled in, so plots look the same on every machine
//! and need no system fonts. Both files are written atomically.

#[cfg(feature = "plots")]
use crate::error::Error;
use crate::error::Result;
#[cfg(feature = "plots")]
use crate::grid::Grid;
#[cfg(feature = "plots")]
use crate::io::{self, BitDepth};
#[cfg(feature = "plots")]
use plotters::prelude::*;
#[cfg(feature = "plots")]
use plotters::style::{register_font, FontStyle};
use std::path::Path;
#[cfg(feature = "plots")]
use std::sync::Once;

#[cfg(feature = "plots")]
/// The font every plot uses.
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

#[cfg(feature = "plots")]
/// Legends with more series than this are left out (they would hide the plot).
const MAX_LEGEND: usize = 10;

/// One curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Its name in the legend.
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
    /// The x axis label.
    pub x_label: String,
    /// The y axis label.
    pub y_label: String,
    /// The x range shown.
    pub x_range: (f64, f64),
    /// The y range shown; `None` fits the data with a margin.
    pub y_range: Option<(f64, f64)>,
    /// A horizontal reference line (e.g. convexity 0 or P = ½).
    pub reference_y: Option<f64>,
    /// Vertical markers.
    pub markers: Vec<Marker>,
    /// The curves.
    pub series: Vec<Series>,
    /// Size in pixels.
    pub size: (u32, u32),
    /// Where the legend goes.
    pub legend: Legend,
}

/// Where a plot's legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Legend {
    /// Top right.
    UpperRight,
    /// Top, centred.
    UpperMiddle,
    /// The middle of the plot.
    Middle,
    /// Bottom right.
    LowerRight,
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
            reference_y: None,
            markers: Vec::new(),
            series: Vec::new(),
            size: (900, 540),
            legend: Legend::UpperRight,
        }
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
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, plotters::coord::Shift>,
    ) -> Result<()> {
        register();
        let fail = |e: &dyn std::fmt::Display| {
            Error::Compute(format!("cannot draw the plot '{}': {e}", self.title))
        };
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range();
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, (FAMILY, 22))
            .margin(14)
            .x_label_area_size(46)
            .y_label_area_size(66)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| fail(&e))?;
        let (fx, fy) = (tick_format(x1 - x0), tick_format(y1 - y0));
        chart
            .configure_mesh()
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style((FAMILY, 15))
            .axis_desc_style((FAMILY, 17))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(210, 210, 210))
            .draw()
            .map_err(|e| fail(&e))?;
        if let Some(y) = self.reference_y {
            chart
                .draw_series(LineSeries::new(
                    [(x0, y), (x1, y)],
                    RGBColor(120, 120, 120).stroke_width(1),
                ))
                .map_err(|e| fail(&e))?;
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
        let legend = self.series.len() <= MAX_LEGEND;
        for (i, s) in self.series.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.1.is_finite())
                .collect();
            let drawn = chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| fail(&e))?;
            if legend {
                drawn.label(s.name.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], colour.stroke_width(2))
                });
            }
            if points.len() <= 120 {
                chart
                    .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| fail(&e))?;
            }
        }
        if legend && !self.series.is_empty() {
            chart
                .configure_series_labels()
                .label_font((FAMILY, 14))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(160, 160, 160))
                .position(match self.legend {
                    Legend::UpperRight => SeriesLabelPosition::UpperRight,
                    Legend::UpperMiddle => SeriesLabelPosition::UpperMiddle,
                    Legend::Middle => SeriesLabelPosition::MiddleMiddle,
                    Legend::LowerRight => SeriesLabelPosition::LowerRight,
                })
                .draw()
                .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
        Ok(())
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
    /// The plot as 8-bit sRGB pixels, row-major, 3 bytes each.
    pub fn rgb(&self) -> Result<Vec<u8>> {
        let (w, h) = self.size;
        let mut buf = vec![0u8; w as usize * h as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut buf, self.size).into_drawing_area();
            self.draw(root)?;
        }
        Ok(buf)
    }

    #[cfg(feature = "plots")]
    /// Writes the plot as an 8-bit PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        write_rgb_png(path, &self.rgb()?, self.size)
    }

    #[cfg(feature = "plots")]
    /// Writes the plot as SVG, atomically.
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        io::write_text(path, &self.svg()?)
    }
}

#[cfg(feature = "plots")]
/// A tick label formatter with as many decimals as ticks about a tenth of `range` apart need,
/// never printing "-0".
fn tick_format(range: f64) -> impl Fn(&f64) -> String {
    let step = (range.abs() / 10.0).max(1e-12);
    let decimals = (-step.log10().floor()).clamp(0.0, 8.0) as usize;
    move |v: &f64| {
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

impl Figure {
    #[cfg(feature = "plots")]
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

    #[cfg(feature = "plots")]
    /// Writes the figure as an 8-bit PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let (w, h) = self.size;
        let mut buf = vec![0u8; w as usize * h as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut buf, self.size).into_drawing_area();
            self.draw(root)?;
        }
        write_rgb_png(path, &buf, self.size)
    }

    #[cfg(feature = "plots")]
    /// Writes the figure as SVG, atomically.
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, self.size).into_drawing_area();
            self.draw(root)?;
        }
        io::write_text(path, &text)
    }
}

#[cfg(feature = "plots")]
/// Writes 8-bit sRGB bytes as a PNG, unchanged, atomically.
fn write_rgb_png(path: &Path, buf: &[u8], (w, h): (u32, u32)) -> Result<()> {
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
    use super::{Figure, LinePlot, Path, Result};

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
}

#[cfg(all(test, feature = "plots"))]
mod tests {
    use super::*;

    #[test]
    fn a_plot_draws_its_curve_in_colour_and_text_in_svg() {
        let mut plot = LinePlot::new("test", "tilt (deg)", "convexity", (0.0, 360.0));
        plot.reference_y = Some(0.0);
        plot.series.push(Series {
            name: "disc".into(),
            points: (0..=36)
                .map(|i| (i as f64 * 10.0, (i as f64 * 10.0).to_radians().cos()))
                .collect(),
        });
        plot.size = (320, 200);
        let rgb = plot.rgb().unwrap();
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
        assert!(svg.contains("<svg") && svg.contains("convexity") && svg.contains("disc"));
    }

    #[test]
    fn tick_labels_have_enough_decimals_and_no_negative_zero() {
        let f = tick_format(360.0);
        assert_eq!(f(&90.0), "90");
        let f = tick_format(0.3);
        assert_eq!(f(&-0.0), "0.00");
        assert_eq!(f(&-0.000001), "0.00");
        assert_eq!(f(&0.15), "0.15");
    }
}

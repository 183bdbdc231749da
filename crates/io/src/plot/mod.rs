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

mod axes;
mod caption;
mod figure;
mod line;
mod map;
mod polar;

pub use axes::{circle_step, span, Ticks};
#[cfg(feature = "plots")]
pub use caption::caption_pixels;
pub use caption::{encode, Caption};
#[cfg(feature = "plots")]
pub use figure::write_rgb_png;
pub use figure::Figure;
pub use line::{IntervalSeries, LinePlot, Marker, Series};
pub use map::{ColourBar, MapFigure, Outline, MAX_NAMED_OUTLINES, OUTLINE};
pub use polar::{LineAndPolar, PolarPlot};

#[cfg(feature = "plots")]
use crate::error::{Error, Result};
#[cfg(feature = "plots")]
use axes::axes;
#[cfg(feature = "plots")]
use figure::{write_png_of, write_svg_of, Drawn};
#[cfg(feature = "plots")]
use plotters::prelude::*;
#[cfg(feature = "plots")]
use plotters::style::{register_font, FontStyle};
#[cfg(feature = "plots")]
use std::sync::Once;

#[cfg(feature = "plots")]
/// The font every figure uses.
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

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

/// Without the `plots` feature figures are not drawn: their writers write nothing and succeed,
/// so an embedding (Python, WebAssembly) gets every number and data file without a plotting
/// library.
#[cfg(not(feature = "plots"))]
mod without_plots {
    use super::{Figure, LineAndPolar, LinePlot, MapFigure};
    use crate::error::Result;
    use std::path::Path;

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
mod tests;

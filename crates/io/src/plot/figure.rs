//! Figures of several panels, and the writers every figure goes through.

use super::LinePlot;
#[cfg(feature = "plots")]
use {
    crate::error::Result,
    crate::grid::Grid,
    crate::{self as io, BitDepth},
    plotters::coord::Shift,
    plotters::prelude::*,
    std::path::Path,
};

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
pub(super) trait Drawn {
    /// Draws the figure on `root`, a backend's whole area.
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>;
}

#[cfg(feature = "plots")]
/// Draws `figure` into an RGB buffer of `(w, h)` pixels and writes it as an 8-bit PNG,
/// atomically.
pub(super) fn write_png_of(figure: &impl Drawn, (w, h): (u32, u32), path: &Path) -> Result<()> {
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        figure.draw(root)?;
    }
    write_rgb_png(path, &buf, (w, h))
}

#[cfg(feature = "plots")]
/// Draws `figure` as SVG text of `size` pixels and writes it, atomically.
pub(super) fn write_svg_of(figure: &impl Drawn, size: (u32, u32), path: &Path) -> Result<()> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        figure.draw(root)?;
    }
    io::write_text(path, &text)
}

#[cfg(feature = "plots")]
impl Drawn for Figure {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()> {
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
        write_png_of(self, self.size, path)
    }

    #[cfg(feature = "plots")]
    /// Writes the figure as SVG, atomically.
    pub fn write_svg(&self, path: &Path) -> Result<()> {
        write_svg_of(self, self.size, path)
    }
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

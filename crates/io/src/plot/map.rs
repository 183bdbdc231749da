//! False-colour maps with axes, a colour bar and named target outlines.

#[cfg(feature = "plots")]
use super::axes::{tick_text, ticks, TickAxis};
#[cfg(feature = "plots")]
use super::{axes, encode, register, write_rgb_png, PixelRect, Ticks, FAMILY};
use crate::colormap::Colormap;
#[cfg(feature = "plots")]
use crate::error::{Error, Result};
use crate::grid::{Mask, RgbImage};
#[cfg(feature = "plots")]
use plotters::prelude::*;
#[cfg(feature = "plots")]
use std::path::Path;

/// The colour of target outlines on maps (8-bit sRGB).
pub const OUTLINE: [u8; 3] = [255, 40, 40];

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

//! The size triple of stimupy: visual size (degrees of visual angle), resolution (pixels per
//! degree) and shape (pixels). Any two give the third.
//!
//! See [`SizeRequest`] for the order and the rule.

use crate::error::{Error, Result};
use crate::message::SizeText;
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// A resolved stimulus geometry.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels per degree of visual angle.
    pub ppd: f64,
}

impl Geometry {
    /// A square picture of `side` pixels at `ppd` pixels per degree.
    pub fn square(side: usize, ppd: f64) -> Geometry {
        Geometry {
            width: side,
            height: side,
            ppd,
        }
    }

    /// Width in degrees.
    pub fn width_deg(&self) -> f64 {
        self.width as f64 / self.ppd
    }

    /// Height in degrees.
    pub fn height_deg(&self) -> f64 {
        self.height as f64 / self.ppd
    }

    /// Its visual size, for a message ("10.0° high × 14.0° wide").
    pub fn size_text(&self) -> SizeText {
        SizeText::Degrees(self.height_deg(), self.width_deg())
    }

    /// Converts a length in degrees to pixels.
    pub fn px(&self, degrees: f64) -> f64 {
        degrees * self.ppd
    }
}

/// The largest visual size, in degrees, either side of a stimulus may have: half the visual
/// field, what a flat screen can span at most (a ppd below one pixel per 8° on a shape of
/// 100000 × 1 pixels would otherwise record 800,000°).
pub const MAX_VISUAL_DEGREES: f64 = 180.0;

/// What the user gave of the triple, in stimupy's order **(height, width)**; anything left
/// `None` is derived or defaulted.
///
/// **Order: (height, width)**, as stimupy and NumPy write it: `visual_size: (4.0, 8.0)` is 4°
/// tall and 8° wide, and `shape: (128, 256)` is 128 rows of 256 pixels. The same order holds in
/// JSON specs, sidecars and the `.mat`/`.npz` bundles; only the CLI's `--size WxH` and
/// `--visual-size WxH` name width first, explicitly (see `parse_size`).
///
/// **One rule for a shape.** A shape given without a ppd sets the output size and scales the
/// whole stimulus to fill it: the ppd is derived as the largest at which the stimulus's visual
/// size (the one given, or its default) fits the shape, so a picture of another shape shows the
/// same stimulus larger or smaller. When the shape's aspect differs from the visual size's, the
/// stimulus fits along the tighter axis and the other axis gets more field (the stimulus stays
/// centred): the resolved visual size is the shape divided by that ppd. Extra field at a fixed
/// scale is what a ppd given with the visual size or the shape gives.
///
/// ```
/// use shadelab::SizeRequest;
/// // stimupy's checkerboard(visual_size=(4, 8), ppd=32): 128 rows of 256 pixels.
/// let size = SizeRequest { visual_size: Some((4.0, 8.0)), ppd: Some(32.0), shape: None };
/// let g = size.resolve((8.0, 8.0), 16.0, 1 << 24).unwrap();
/// assert_eq!((g.height, g.width), (128, 256));
/// // A shape alone scales the default visual size (here 8° × 8°) to fill it: ppd 32.
/// let size = SizeRequest { shape: Some((256, 256)), ..Default::default() };
/// assert_eq!(size.resolve((8.0, 8.0), 16.0, 1 << 24).unwrap().ppd, 32.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct SizeRequest {
    /// (height, width) in degrees of visual angle.
    pub visual_size: Option<(f64, f64)>,
    /// Pixels per degree.
    pub ppd: Option<f64>,
    /// (height, width) in pixels: rows, then columns.
    pub shape: Option<(usize, usize)>,
}

impl SizeRequest {
    /// Sets the output size, (height, width) in pixels, so that the stimulus scales to fill it:
    /// a ppd given before is dropped (the ppd is derived), after a ppd given with a shape (as a
    /// sidecar records them) has become the visual size they made. Give a ppd after this for a
    /// fixed scale instead.
    ///
    /// ```
    /// use shadelab::SizeRequest;
    /// // A sidecar's 64 × 96 pixels at 8 ppd, asked for at twice the size: 16 ppd, same degrees.
    /// let mut size = SizeRequest { ppd: Some(8.0), shape: Some((64, 96)), ..Default::default() };
    /// size.set_shape((128, 192));
    /// assert_eq!(size.visual_size, Some((8.0, 12.0)));
    /// assert_eq!(size.resolve((1.0, 1.0), 1.0, 1 << 24).unwrap().ppd, 16.0);
    /// ```
    pub fn set_shape(&mut self, shape: (usize, usize)) {
        if let (None, Some(ppd), Some((h, w))) = (self.visual_size, self.ppd, self.shape) {
            self.visual_size = Some((h as f64 / ppd, w as f64 / ppd));
        }
        self.ppd = None;
        self.shape = Some(shape);
    }

    /// The visual size asked for, (height, width), when whole pixels made `geometry` smaller
    /// (shape from visual size and ppd, rounded down as stimupy does); `None` when it is what
    /// was asked or no visual size was given with the ppd.
    ///
    /// ```
    /// use shadelab::SizeRequest;
    /// let size = SizeRequest { visual_size: Some((3.3, 5.1)), ppd: Some(31.7), shape: None };
    /// let g = size.resolve((1.0, 1.0), 1.0, 1 << 24).unwrap();
    /// assert_eq!((g.height, g.width), (104, 161)); // stimupy's shape
    /// assert_eq!(size.rounded_visual_size(&g), Some((3.3, 5.1)));
    /// ```
    pub fn rounded_visual_size(&self, geometry: &Geometry) -> Option<(f64, f64)> {
        let (v, _) = (self.visual_size?, self.ppd?);
        let made = (geometry.height_deg(), geometry.width_deg());
        let off = |a: f64, b: f64| (a - b).abs() > 1e-9 * a.abs().max(1.0);
        (self.shape.is_none() && (off(v.0, made.0) || off(v.1, made.1))).then_some(v)
    }

    /// Resolves the triple (all pairs (height, width)). Visual size and ppd give the shape
    /// ([`whole_pixels`]: rounded down, as stimupy); ppd and shape give the visual size; a shape without a ppd
    /// takes the largest ppd at which the visual size (`default_visual_size` when none is
    /// given) fits it, the rest of the shape being field; all three must agree to within half
    /// a pixel. Without a shape, `default_ppd` and then `default_visual_size` fill in. A
    /// visual size over [`MAX_VISUAL_DEGREES`] either way, given or resolved, is refused.
    pub fn resolve(
        &self,
        default_visual_size: (f64, f64),
        default_ppd: f64,
        max_pixels: usize,
    ) -> Result<Geometry> {
        if let Some((h, w)) = self.visual_size {
            if !(h.is_finite() && w.is_finite() && h > 0.0 && w > 0.0) {
                return Err(Error::invalid(format!(
                    "visual size {} must be positive",
                    SizeText::Degrees(h, w)
                )));
            }
        }
        if let Some(ppd) = self.ppd {
            if !(ppd.is_finite() && ppd > 0.0) {
                return Err(Error::invalid(format!(
                    "ppd {ppd} must be a positive number"
                )));
            }
        }
        if let Some((h, w)) = self.shape {
            crate::grid::check_size(w, h, max_pixels)?;
        }
        let visual_or_default = self.visual_size.unwrap_or(default_visual_size);
        let (ppd, shape) = match (self.visual_size, self.ppd, self.shape) {
            (Some(v), Some(p), Some(s)) => {
                for (axis, deg, px) in [("height", v.0, s.0), ("width", v.1, s.1)] {
                    if (deg * p - px as f64).abs() > 0.5 {
                        return Err(Error::invalid(format!(
                            "inconsistent size: {axis} {deg}° × {p} ppd = {} px, not {px} px",
                            deg * p
                        )));
                    }
                }
                (p, s)
            }
            (_, None, Some(s)) => (fit_ppd(visual_or_default, s), s),
            (None, Some(p), Some(s)) => (p, s),
            (_, Some(p), None) => (p, round_shape(visual_or_default, p)?),
            (_, None, None) => (default_ppd, round_shape(visual_or_default, default_ppd)?),
        };
        crate::grid::check_size(shape.1, shape.0, max_pixels)?;
        let geometry = Geometry {
            width: shape.1,
            height: shape.0,
            ppd,
        };
        let (h, w) = (geometry.height_deg(), geometry.width_deg());
        if h > MAX_VISUAL_DEGREES || w > MAX_VISUAL_DEGREES {
            let how = match (self.visual_size, self.ppd) {
                (_, Some(_)) => "",
                (Some(_), None) => " (the ppd that fits the visual size given to the shape)",
                (None, None) => {
                    " (the ppd that fits the stimulus's default visual size to the shape)"
                }
            };
            return Err(Error::invalid(format!(
                "{} at {ppd} ppd{how} is {}: over {MAX_VISUAL_DEGREES}° either way; give a \
                 ppd or a visual size that fits",
                SizeText::Pixels(shape.0, shape.1),
                SizeText::Degrees(h, w)
            )));
        }
        Ok(geometry)
    }
}

/// The largest ppd at which `visual` (height, width) fits `shape` (height, width).
fn fit_ppd(visual: (f64, f64), shape: (usize, usize)) -> f64 {
    (shape.0 as f64 / visual.0).min(shape.1 as f64 / visual.1)
}

/// Whole pixels of `degrees` at `ppd` as stimupy makes them: the product rounded to 10
/// decimals (so that 0.29 × 100 is 29, not 28), then rounded down (3.3° × 31.7 ppd = 104.61 →
/// 104 px): a stimulus never exceeds the visual size asked for.
pub fn whole_pixels(degrees: f64, ppd: f64) -> f64 {
    let product = degrees * ppd;
    let near = product.round();
    if (product - near).abs() <= 1e-10 * near.abs().max(1.0) {
        near
    } else {
        product.floor()
    }
}

fn round_shape(visual: (f64, f64), ppd: f64) -> Result<(usize, usize)> {
    let h = whole_pixels(visual.0, ppd);
    let w = whole_pixels(visual.1, ppd);
    if !(w >= 1.0 && h >= 1.0 && w < 1e9 && h < 1e9) {
        return Err(Error::invalid(format!(
            "visual size {} at {ppd} ppd gives {h} pixels high × {w} wide",
            SizeText::Degrees(visual.0, visual.1)
        )));
    }
    Ok((h as usize, w as usize))
}

/// Parses `N` (square) or `WxH` into a (width, height) pair.
pub fn parse_pair<T: std::str::FromStr + Copy>(text: &str, what: &str) -> Result<(T, T)> {
    let bad = || Error::invalid(format!("{what} '{text}' is not N or WxH"));
    match text.split_once(['x', 'X']) {
        Some((w, h)) => Ok((
            w.trim().parse().map_err(|_| bad())?,
            h.trim().parse().map_err(|_| bad())?,
        )),
        None => {
            let v = text.trim().parse().map_err(|_| bad())?;
            Ok((v, v))
        }
    }
}

/// Parses a size written `N` (square) or `WxH` (width first, as on the command line) into the
/// library's (height, width); both sides must be positive.
///
/// ```
/// use shadelab::parse_size;
/// assert_eq!(parse_size::<usize>("256x128", "--size").unwrap(), (128, 256));
/// let zero = parse_size::<usize>("0x128", "--size").unwrap_err().to_string();
/// assert!(zero.starts_with("--size '0x128'"), "{zero}");
/// assert!(parse_size::<f64>("nan", "--visual-size").is_err());
/// ```
pub fn parse_size<T: std::str::FromStr + Copy + PartialOrd + Default>(
    text: &str,
    what: &str,
) -> Result<(T, T)> {
    let (w, h) = parse_pair(text, what)?;
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN is refused too
    if !(w > T::default() && h > T::default()) {
        return Err(Error::invalid(format!(
            "{what} '{text}': both sides must be positive"
        )));
    }
    Ok((h, w))
}

/// The picture's pixel frame as drawing code sees it: pixel-centre coordinates (x right, y up,
/// in pixels from the frame's centre), snapping to the pixel lattice, and SVG coordinates.
impl Geometry {
    /// x of column `col`'s centre.
    pub fn x(&self, col: usize) -> f64 {
        col as f64 - (self.width as f64 - 1.0) / 2.0
    }

    /// y of row `row`'s centre.
    pub fn y(&self, row: usize) -> f64 {
        (self.height as f64 - 1.0) / 2.0 - row as f64
    }

    /// The pixel corner nearest `(x, y)`. Elements centred on corners are mirror-symmetric on
    /// the pixel lattice, and every copy of an element covers the same pixel pattern.
    pub fn snap(&self, x: f64, y: f64) -> (f64, f64) {
        let (hw, hh) = (self.width as f64 / 2.0, self.height as f64 / 2.0);
        ((x + hw).round() - hw, (y + hh).round() - hh)
    }

    /// The columns whose centres may lie in `x0..=x1`.
    pub fn cols(&self, x0: f64, x1: f64) -> Range<usize> {
        let off = (self.width as f64 - 1.0) / 2.0;
        span(x0 + off, x1 + off, self.width)
    }

    /// The rows whose centres may lie in `y0..=y1` (y up).
    pub fn rows(&self, y0: f64, y1: f64) -> Range<usize> {
        let off = (self.height as f64 - 1.0) / 2.0;
        span(off - y1, off - y0, self.height)
    }

    /// SVG user coordinates (pixels from the top-left corner, y down) of the point `(x, y)`.
    pub fn svg_xy(&self, x: f64, y: f64) -> (f64, f64) {
        (x + self.width as f64 / 2.0, self.height as f64 / 2.0 - y)
    }

    /// Fails unless a disc of `radius` pixels at each of `centres` lies inside the frame.
    pub fn check_inside(&self, what: &str, centres: &[(f64, f64)], radius: f64) -> Result<()> {
        let (hw, hh) = (self.width as f64 / 2.0, self.height as f64 / 2.0);
        let fits = centres.iter().all(|&(x, y)| {
            x - radius >= -hw && x + radius <= hw && y - radius >= -hh && y + radius <= hh
        });
        if fits {
            return Ok(());
        }
        let (min_x, max_x, min_y, max_y) = centres.iter().fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
        );
        let need_w = (max_x - min_x + 2.0 * radius) / self.ppd;
        let need_h = (max_y - min_y + 2.0 * radius) / self.ppd;
        Err(Error::invalid(format!(
            "{what} need {} but the frame is {}: enlarge the visual size or make them smaller or fewer",
            SizeText::Degrees(need_h, need_w),
            self.size_text()
        )))
    }
}

fn span(lo: f64, hi: f64, n: usize) -> Range<usize> {
    let a = lo.ceil().max(0.0);
    let b = (hi.floor() + 1.0).min(n as f64);
    if a >= b {
        return 0..0;
    }
    a as usize..b as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    const MAX: usize = crate::grid::DEFAULT_MAX_PIXELS;

    #[test]
    fn any_two_give_the_third_in_height_width_order() {
        let g = SizeRequest {
            visual_size: Some((5.0, 10.0)),
            ppd: Some(32.0),
            shape: None,
        }
        .resolve((1.0, 1.0), 1.0, MAX)
        .unwrap();
        assert_eq!((g.height, g.width), (160, 320));
        let g = SizeRequest {
            visual_size: Some((10.0, 10.0)),
            ppd: None,
            shape: Some((256, 256)),
        }
        .resolve((1.0, 1.0), 1.0, MAX)
        .unwrap();
        assert_eq!(g.ppd, 25.6);
        let g = SizeRequest {
            visual_size: None,
            ppd: Some(20.0),
            shape: Some((60, 100)),
        }
        .resolve((1.0, 1.0), 1.0, MAX)
        .unwrap();
        assert_eq!((g.height_deg(), g.width_deg()), (3.0, 5.0));
    }

    #[test]
    fn a_shape_alone_scales_the_default_visual_size_to_fit() {
        let shape_only = |shape| SizeRequest {
            shape: Some(shape),
            ..Default::default()
        };
        // 7° tall, 9° wide by default at 16 ppd; 70 × 90 pixels is 10 ppd, 140 × 180 is 20.
        for (shape, ppd) in [((70, 90), 10.0), ((140, 180), 20.0)] {
            let g = shape_only(shape).resolve((7.0, 9.0), 16.0, MAX).unwrap();
            assert_eq!((g.height, g.width, g.ppd), (shape.0, shape.1, ppd));
        }
        // Another aspect: the tighter axis sets the ppd, the other gets more field.
        let g = shape_only((70, 180))
            .resolve((7.0, 9.0), 16.0, MAX)
            .unwrap();
        assert_eq!((g.ppd, g.height_deg(), g.width_deg()), (10.0, 7.0, 18.0));
        let g = shape_only((140, 90))
            .resolve((7.0, 9.0), 16.0, MAX)
            .unwrap();
        assert_eq!((g.ppd, g.height_deg(), g.width_deg()), (10.0, 14.0, 9.0));
        // A ppd given with the shape keeps the scale: a larger shape is more field.
        let g = SizeRequest {
            ppd: Some(16.0),
            shape: Some((160, 160)),
            ..Default::default()
        }
        .resolve((7.0, 9.0), 16.0, MAX)
        .unwrap();
        assert_eq!((g.ppd, g.height_deg(), g.width_deg()), (16.0, 10.0, 10.0));
        // set_shape turns a recorded ppd and shape into the visual size they made.
        let mut size = SizeRequest {
            ppd: Some(10.0),
            shape: Some((70, 90)),
            ..Default::default()
        };
        size.set_shape((35, 45));
        let g = size.resolve((1.0, 1.0), 1.0, MAX).unwrap();
        assert_eq!((g.ppd, g.height, g.width), (5.0, 35, 45));
    }

    #[test]
    fn inconsistent_or_empty_is_an_error() {
        let r = SizeRequest {
            visual_size: Some((10.0, 10.0)),
            ppd: Some(32.0),
            shape: Some((320, 300)),
        };
        assert!(r
            .resolve((1.0, 1.0), 1.0, MAX)
            .unwrap_err()
            .to_string()
            .contains("inconsistent"));
        let r = SizeRequest {
            ppd: Some(0.0),
            ..Default::default()
        };
        assert!(r.resolve((1.0, 1.0), 1.0, MAX).is_err());
        let r = SizeRequest {
            shape: Some((0, 10)),
            ..Default::default()
        };
        assert!(r.resolve((1.0, 1.0), 1.0, MAX).is_err());
        let r = SizeRequest {
            visual_size: Some((1e6, 1e6)),
            ppd: Some(100.0),
            ..Default::default()
        };
        assert!(r.resolve((1.0, 1.0), 1.0, MAX).is_err());
        // A shape of 100000 × 1 pixels fitted to 8° × 8° would be 800,000° wide.
        let wide = SizeRequest {
            shape: Some((1, 100_000)),
            ..Default::default()
        };
        let e = wide.resolve((8.0, 8.0), 16.0, MAX).unwrap_err().to_string();
        assert!(
            e.contains("1 px high × 100000 px wide at 0.125 ppd")
                && e.contains("8.0° high × 800000.0° wide")
                && e.contains("over 180°"),
            "{e}"
        );
        let at_limit = SizeRequest {
            visual_size: Some((180.0, 10.0)),
            ppd: Some(1.0),
            shape: None,
        };
        assert!(at_limit.resolve((1.0, 1.0), 1.0, MAX).is_ok());
        let over = SizeRequest {
            visual_size: Some((180.5, 10.0)),
            ppd: Some(2.0),
            shape: None,
        };
        assert!(over.resolve((1.0, 1.0), 1.0, MAX).is_err());
        assert!(parse_pair::<usize>("12x", "size").is_err());
        assert_eq!(parse_pair::<usize>("12x7", "size").unwrap(), (12, 7));
        assert_eq!(parse_size::<usize>("12x7", "size").unwrap(), (7, 12));
    }
}

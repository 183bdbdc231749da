//! The size triple of stimupy: visual size (degrees of visual angle), resolution (pixels per
//! degree) and shape (pixels). Any two give the third; all three must agree.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

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
    /// Width in degrees.
    pub fn width_deg(&self) -> f64 {
        self.width as f64 / self.ppd
    }

    /// Height in degrees.
    pub fn height_deg(&self) -> f64 {
        self.height as f64 / self.ppd
    }

    /// Converts a length in degrees to pixels.
    pub fn px(&self, degrees: f64) -> f64 {
        degrees * self.ppd
    }
}

/// What the user gave of the triple; anything left `None` is derived or defaulted.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct SizeRequest {
    /// (width, height) in degrees.
    pub visual_size: Option<(f64, f64)>,
    /// Pixels per degree.
    pub ppd: Option<f64>,
    /// (width, height) in pixels.
    pub shape: Option<(usize, usize)>,
}

impl SizeRequest {
    /// Resolves the triple: two given values fix the third (shape = round(visual size × ppd));
    /// three must agree to within half a pixel; with fewer than two, `default_ppd` and then
    /// `default_visual_size` fill in.
    pub fn resolve(
        &self,
        default_visual_size: (f64, f64),
        default_ppd: f64,
        max_pixels: usize,
    ) -> Result<Geometry> {
        if let Some((w, h)) = self.visual_size {
            if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
                return Err(Error::invalid(format!(
                    "visual size {w}x{h} degrees must be positive"
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
        if let Some((w, h)) = self.shape {
            crate::grid::check_size(w, h, max_pixels)?;
        }
        let given = self.visual_size.is_some() as u8
            + self.ppd.is_some() as u8
            + self.shape.is_some() as u8;
        let (visual, ppd, shape) = match (self.visual_size, self.ppd, self.shape) {
            (Some(v), Some(p), Some(s)) => (v, p, s),
            (Some(v), Some(p), None) => (v, p, round_shape(v, p)?),
            (Some(v), None, Some(s)) => {
                let p = s.0 as f64 / v.0;
                (v, p, s)
            }
            (None, Some(p), Some(s)) => ((s.0 as f64 / p, s.1 as f64 / p), p, s),
            (None, None, Some(s)) => (
                (s.0 as f64 / default_ppd, s.1 as f64 / default_ppd),
                default_ppd,
                s,
            ),
            (Some(v), None, None) => (v, default_ppd, round_shape(v, default_ppd)?),
            (None, Some(p), None) => (default_visual_size, p, round_shape(default_visual_size, p)?),
            (None, None, None) => (
                default_visual_size,
                default_ppd,
                round_shape(default_visual_size, default_ppd)?,
            ),
        };
        if given >= 2 {
            for (axis, deg, px) in [("width", visual.0, shape.0), ("height", visual.1, shape.1)] {
                if (deg * ppd - px as f64).abs() > 0.5 {
                    return Err(Error::invalid(format!(
                        "inconsistent size: {axis} {deg}° × {ppd} ppd = {} px, not {px} px",
                        deg * ppd
                    )));
                }
            }
        }
        crate::grid::check_size(shape.0, shape.1, max_pixels)?;
        Ok(Geometry {
            width: shape.0,
            height: shape.1,
            ppd,
        })
    }
}

fn round_shape(visual: (f64, f64), ppd: f64) -> Result<(usize, usize)> {
    let w = (visual.0 * ppd).round();
    let h = (visual.1 * ppd).round();
    if !(w >= 1.0 && h >= 1.0 && w < 1e9 && h < 1e9) {
        return Err(Error::invalid(format!(
            "visual size {}x{}° at {ppd} ppd gives {w}x{h} pixels",
            visual.0, visual.1
        )));
    }
    Ok((w as usize, h as usize))
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

#[cfg(test)]
mod tests {
    use super::*;
    const MAX: usize = crate::grid::DEFAULT_MAX_PIXELS;

    #[test]
    fn any_two_give_the_third() {
        let g = SizeRequest {
            visual_size: Some((10.0, 5.0)),
            ppd: Some(32.0),
            shape: None,
        }
        .resolve((1.0, 1.0), 1.0, MAX)
        .unwrap();
        assert_eq!((g.width, g.height), (320, 160));
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
            shape: Some((100, 60)),
        }
        .resolve((1.0, 1.0), 1.0, MAX)
        .unwrap();
        assert_eq!((g.width_deg(), g.height_deg()), (5.0, 3.0));
    }

    #[test]
    fn inconsistent_or_empty_is_an_error() {
        let r = SizeRequest {
            visual_size: Some((10.0, 10.0)),
            ppd: Some(32.0),
            shape: Some((300, 320)),
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
        assert!(parse_pair::<usize>("12x", "size").is_err());
        assert_eq!(parse_pair::<usize>("12x7", "size").unwrap(), (12, 7));
    }
}

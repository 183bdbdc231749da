//! Display codes and captions set under pictures.

#[cfg(feature = "plots")]
use super::{register, FAMILY};
#[cfg(feature = "plots")]
use crate::error::{Error, Result};
#[cfg(feature = "plots")]
use plotters::prelude::*;

/// A linear value (clamped to 0..1) as an 8-bit code, display-encoded with `v^(1/gamma)` when
/// a gamma is given: the same codes [`crate::write_rgb`] writes.
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

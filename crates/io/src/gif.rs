//! Animated GIF writing.

use crate::error::{Error, Result};
use crate::grid::RgbImage;
use std::path::Path;

/// Writes `frames` (linear 0..1, written as 8-bit codes without gamma, as shadelab writes its
/// stimuli) as a looping GIF, `delay_ms` per frame, atomically.
pub fn write_gif(path: &Path, frames: &[RgbImage], delay_ms: u32) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    use image::{Delay, Frame, RgbaImage};
    let first = frames
        .first()
        .ok_or_else(|| Error::invalid("an animation needs at least one frame"))?;
    let (w, h) = (first.width() as u32, first.height() as u32);
    crate::write_atomic(path, |out| {
        let mut encoder = GifEncoder::new_with_speed(out, 10);
        encoder
            .set_repeat(Repeat::Infinite)
            .map_err(|e| Error::format(path, format!("cannot write GIF ({e})")))?;
        for f in frames {
            let bytes: Vec<u8> = f
                .data()
                .iter()
                .flat_map(|p| {
                    let q = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
                    [q(p[0]), q(p[1]), q(p[2]), 255]
                })
                .collect();
            let rgba = RgbaImage::from_raw(w, h, bytes)
                .ok_or_else(|| Error::invalid("animation frames differ in size"))?;
            let frame = Frame::from_parts(rgba, 0, 0, Delay::from_numer_denom_ms(delay_ms, 1));
            encoder
                .encode_frame(frame)
                .map_err(|e| Error::format(path, format!("cannot write GIF ({e})")))?;
        }
        Ok(())
    })
}

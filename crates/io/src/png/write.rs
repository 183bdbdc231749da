//! PNG output: linear values display-encoded into 8- or 16-bit codes, written with a chunk
//! that says how (gamma, or linear) and who wrote the file.

use super::BitDepth;
use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Labels, Mask, RgbImage};
use std::path::Path;

/// The codes a stimulus PNG holds for linear `values` at `depth`, display-encoded with
/// v^(1/gamma) when `gamma` is given: what [`write_stimulus`] writes, for a caller that shows
/// them itself (the Python module's `codes`). Fails on a gamma outside (0, 10].
///
/// ```
/// use shadelab::{display::stimulus_codes, BitDepth};
/// assert_eq!(stimulus_codes(&[0.0, 0.5, 1.0], BitDepth::Eight, None)?, [0, 128, 255]);
/// assert_eq!(stimulus_codes(&[0.25], BitDepth::Sixteen, Some(2.0))?, [32768]);
/// # Ok::<(), shadelab::Error>(())
/// ```
pub fn stimulus_codes(values: &[f64], depth: BitDepth, gamma: Option<f64>) -> Result<Vec<u16>> {
    check_gamma(gamma)?;
    let max = match depth {
        BitDepth::Eight => 255.0,
        BitDepth::Sixteen => 65535.0,
    };
    Ok(values
        .iter()
        .map(|&v| encode(v, gamma, max) as u16)
        .collect())
}

/// Encodes a linear value 0..1 (clamped; NaN becomes 0) with an optional display gamma, as a
/// code up to `max`.
fn encode(v: f64, gamma: Option<f64>, max: f64) -> f64 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let v = match gamma {
        Some(g) => v.powf(1.0 / g),
        None => v,
    };
    (v * max).round()
}

/// `image` (linear RGB 0..1, clamped; NaN as 0) as 8-bit RGBA bytes, row-major from the top
/// row, opaque, display-encoded with v^(1/gamma) when `gamma` is given: the layout of a
/// browser's `ImageData`. Fails on a gamma outside (0, 10].
///
/// ```
/// use shadelab::{display::display_rgba8, Grid};
/// let image = Grid::from_vec(2, 1, vec![[0.0, 0.5, 1.0], [0.25; 3]])?;
/// assert_eq!(display_rgba8(&image, None)?, [0, 128, 255, 255, 64, 64, 64, 255]);
/// assert_eq!(display_rgba8(&image, Some(2.0))?[4], 128); // 0.25^(1/2) = 0.5
/// # Ok::<(), shadelab::Error>(())
/// ```
pub fn display_rgba8(image: &RgbImage, gamma: Option<f64>) -> Result<Vec<u8>> {
    check_gamma(gamma)?;
    Ok(image
        .data()
        .iter()
        .flat_map(|p| {
            let [r, g, b] = p.map(|v| encode(v, gamma, 255.0) as u8);
            [r, g, b, 255]
        })
        .collect())
}

/// What a stimulus PNG says about itself beside its pixels: how its codes encode linear
/// luminance (a gAMA chunk) and text (iTXt chunks). Figures, colour maps and masks have none:
/// their codes are display colours or labels, not light.
#[derive(Debug, Clone, Copy)]
struct SelfDescription<'a> {
    /// The display gamma the codes were encoded with (v^(1/gamma)); `None`: linear.
    gamma: Option<f64>,
    /// Keyword and text of each iTXt chunk; `None`: a picture without chunks.
    text: Option<&'a [(String, String)]>,
    /// The codes are a display's (its bits per channel): no gAMA chunk (they follow its
    /// measured response, not a power), and an sBIT chunk where its bits are fewer than the
    /// file's.
    display_bits: Option<u8>,
}

/// The gAMA chunk's value for codes encoded as v^(1/gamma): the file gamma 1/gamma, in
/// hundred-thousandths (100000 for linear codes).
pub fn png_gamma_chunk_value(gamma: Option<f64>) -> u32 {
    (100_000.0 / gamma.unwrap_or(1.0)).round() as u32
}

/// Writes `bytes` (rows from the top, 16-bit samples big-endian) as a PNG of `color`;
/// a luminance picture's gAMA and text chunks come from `described`. Deflate and filters as
/// the `image` crate's default PNG encoder (fast, adaptive): masks keep their bytes.
fn write_png(
    path: &Path,
    (w, h): (usize, usize),
    bytes: &[u8],
    (color, depth): (png::ColorType, png::BitDepth),
    described: Option<SelfDescription<'_>>,
) -> Result<()> {
    let (w32, h32) = (
        u32::try_from(w).map_err(|_| Error::invalid("image too wide for PNG"))?,
        u32::try_from(h).map_err(|_| Error::invalid("image too tall for PNG"))?,
    );
    let fail = |e: &dyn std::fmt::Display| Error::format(path, format!("cannot encode PNG ({e})"));
    crate::write_atomic(path, |out| {
        let mut encoder = png::Encoder::new(out, w32, h32);
        encoder.set_color(color);
        encoder.set_depth(depth);
        encoder.set_compression(png::Compression::Fast);
        encoder.set_filter(png::Filter::Adaptive);
        let mut sbit = None;
        if let Some(SelfDescription {
            gamma,
            text: Some(text),
            display_bits,
        }) = described
        {
            match display_bits {
                None => {
                    let value = png_gamma_chunk_value(gamma);
                    encoder.set_source_gamma(png::ScaledFloat::from_scaled(value));
                }
                Some(bits) if bits != 8 && bits != 16 => sbit = Some(bits),
                Some(_) => {}
            }
            for (keyword, text) in text {
                encoder
                    .add_itxt_chunk(keyword.clone(), text.clone())
                    .map_err(|e| fail(&e))?;
            }
        }
        let mut writer = encoder.write_header().map_err(|e| fail(&e))?;
        if let Some(bits) = sbit {
            let channels = if color == png::ColorType::Rgb { 3 } else { 1 };
            writer
                .write_chunk(png::chunk::ChunkType(*b"sBIT"), &vec![bits; channels])
                .map_err(|e| fail(&e))?;
        }
        writer.write_image_data(bytes).map_err(|e| fail(&e))?;
        writer.finish().map_err(|e| fail(&e))
    })
}

fn check_gamma(gamma: Option<f64>) -> Result<()> {
    match gamma {
        Some(g) if !(g.is_finite() && g > 0.0 && g <= 10.0) => {
            Err(Error::invalid(format!("gamma {g} must be in (0, 10]")))
        }
        _ => Ok(()),
    }
}

/// Writes a grayscale PNG of linear values 0..1 (clamped), optionally display-encoded with
/// v^(1/gamma).
pub fn write_gray(path: &Path, image: &Image, depth: BitDepth, gamma: Option<f64>) -> Result<()> {
    let plain = SelfDescription {
        gamma,
        text: None,
        display_bits: None,
    };
    write_encoded(path, image, depth, plain, png::ColorType::Grayscale)
}

/// Writes an RGB PNG of linear values 0..1 (clamped), optionally display-encoded.
pub fn write_rgb(path: &Path, image: &RgbImage, depth: BitDepth, gamma: Option<f64>) -> Result<()> {
    let plain = SelfDescription {
        gamma,
        text: None,
        display_bits: None,
    };
    write_encoded(path, image, depth, plain, png::ColorType::Rgb)
}

/// A stimulus picture for [`write_stimulus`]: one channel or three.
#[derive(Debug, Clone, Copy)]
pub enum PngPicture<'a> {
    /// Gray: luminance.
    Gray(&'a Image),
    /// Linear RGB.
    Rgb(&'a RgbImage),
}

/// Writes a stimulus as [`write_gray`] or [`write_rgb`] do, with the gAMA chunk of its
/// encoding (1.0 for linear codes, 1/gamma for display-encoded ones) and iTXt chunks
/// (keyword, text) that say what it is.
pub fn write_stimulus(
    path: &Path,
    picture: PngPicture<'_>,
    depth: BitDepth,
    gamma: Option<f64>,
    text: &[(String, String)],
) -> Result<()> {
    let described = SelfDescription {
        gamma,
        text: Some(text),
        display_bits: None,
    };
    match picture {
        PngPicture::Gray(image) => {
            write_encoded(path, image, depth, described, png::ColorType::Grayscale)
        }
        PngPicture::Rgb(image) => write_encoded(path, image, depth, described, png::ColorType::Rgb),
    }
}

/// A display's codes (see [`crate::display::Display::show`]): row-major, `channels` (1 gray,
/// 3 RGB) per pixel, each 0..2^bits − 1.
#[derive(Debug, Clone, Copy)]
pub struct DisplayCodes<'a> {
    /// The codes.
    pub codes: &'a [u16],
    /// Channels per pixel: 1 or 3.
    pub channels: usize,
    /// The display's bits per channel: 8, 10 or 16.
    pub bits: u8,
}

/// Writes a display's codes as a PNG of `size` (width, height) with iTXt chunks (keyword,
/// text): 8-bit codes in an 8-bit file, 16-bit codes in a 16-bit one, 10-bit codes in a 16-bit
/// file by PNG's bit replication (code · 64 + code / 16; round(v · 1023) of the 16-bit value
/// read back is the code) with an sBIT chunk of 10. No gAMA chunk: the codes follow the display's measured response, not a power law.
pub fn write_display_codes(
    path: &Path,
    size: (usize, usize),
    codes: DisplayCodes<'_>,
    text: &[(String, String)],
) -> Result<()> {
    let color = match codes.channels {
        1 => png::ColorType::Grayscale,
        3 => png::ColorType::Rgb,
        n => return Err(Error::invalid(format!("{n} channels of display codes"))),
    };
    let described = SelfDescription {
        gamma: None,
        text: Some(text),
        display_bits: Some(codes.bits),
    };
    let (bytes, depth): (Vec<u8>, _) = match codes.bits {
        8 => (
            codes.codes.iter().map(|&c| c.min(255) as u8).collect(),
            png::BitDepth::Eight,
        ),
        10 => (
            codes
                .codes
                .iter()
                .flat_map(|&c| {
                    let c = c.min(1023);
                    ((c << 6) | (c >> 4)).to_be_bytes()
                })
                .collect(),
            png::BitDepth::Sixteen,
        ),
        _ => (
            codes.codes.iter().flat_map(|c| c.to_be_bytes()).collect(),
            png::BitDepth::Sixteen,
        ),
    };
    write_png(path, size, &bytes, (color, depth), Some(described))
}

/// [`write_rgb`] of the `width` × `height` picture whose pixel at (column, row) is
/// `pixel(column, row)`, without building it: the same bytes as `write_rgb` of
/// `Grid::from_fn(width, height, pixel)`.
pub fn write_rgb_fn(
    path: &Path,
    (width, height): (usize, usize),
    depth: BitDepth,
    gamma: Option<f64>,
    pixel: impl Fn(usize, usize) -> [f64; 3],
) -> Result<()> {
    let pixel = &pixel;
    let values = (0..height).flat_map(|r| (0..width).flat_map(move |c| pixel(c, r)));
    let described = SelfDescription {
        gamma,
        text: None,
        display_bits: None,
    };
    let size = (width, height);
    write_values(path, size, values, depth, described, png::ColorType::Rgb)
}

/// [`write_gray`] of the `width` × `height` picture whose value at (column, row) is
/// `value(column, row)`, without building it: the same bytes as `write_gray` of
/// `Grid::from_fn(width, height, value)`.
pub fn write_gray_fn(
    path: &Path,
    (width, height): (usize, usize),
    depth: BitDepth,
    gamma: Option<f64>,
    value: impl Fn(usize, usize) -> f64,
) -> Result<()> {
    let value = &value;
    let values = (0..height).flat_map(|r| (0..width).map(move |c| value(c, r)));
    let described = SelfDescription {
        gamma,
        text: None,
        display_bits: None,
    };
    let size = (width, height);
    write_values(
        path,
        size,
        values,
        depth,
        described,
        png::ColorType::Grayscale,
    )
}

/// A pixel of linear values: one channel (gray) or three (RGB).
trait Channels {
    /// The pixel's channels, in PNG order.
    fn channels(&self) -> &[f64];
}

impl Channels for f64 {
    fn channels(&self) -> &[f64] {
        std::slice::from_ref(self)
    }
}

impl Channels for [f64; 3] {
    fn channels(&self) -> &[f64] {
        self
    }
}

/// Encodes `image` (channels interleaved, row-major) at `depth`, optionally display-encoded
/// with v^(1/gamma), and writes it as a PNG of `color` that says so.
fn write_encoded<P: Channels>(
    path: &Path,
    image: &Grid<P>,
    depth: BitDepth,
    described: SelfDescription<'_>,
    color: png::ColorType,
) -> Result<()> {
    let values = image.data().iter().flat_map(Channels::channels).copied();
    let size = (image.width(), image.height());
    write_values(path, size, values, depth, described, color)
}

/// Encodes `values` (channels interleaved, row-major, of a picture of `size` (width, height))
/// at `depth`, optionally display-encoded with v^(1/gamma), and writes them as a PNG of
/// `color` with its gAMA chunk and text.
fn write_values(
    path: &Path,
    size: (usize, usize),
    values: impl Iterator<Item = f64>,
    depth: BitDepth,
    described: SelfDescription<'_>,
    color: png::ColorType,
) -> Result<()> {
    let gamma = described.gamma;
    check_gamma(gamma)?;
    let (bytes, depth): (Vec<u8>, _) = match depth {
        BitDepth::Eight => (
            values.map(|v| encode(v, gamma, 255.0) as u8).collect(),
            png::BitDepth::Eight,
        ),
        BitDepth::Sixteen => (
            values
                .flat_map(|v| (encode(v, gamma, 65535.0) as u16).to_be_bytes())
                .collect(),
            png::BitDepth::Sixteen,
        ),
    };
    write_png(path, size, &bytes, (color, depth), Some(described))
}

/// Gray codes that are labels, not light (masks, label maps): no gAMA chunk.
const CODES_8: (png::ColorType, png::BitDepth) = (png::ColorType::Grayscale, png::BitDepth::Eight);
/// [`CODES_8`] in 16 bits.
const CODES_16: (png::ColorType, png::BitDepth) =
    (png::ColorType::Grayscale, png::BitDepth::Sixteen);

/// Writes a label map: 8-bit when every label fits, else 16-bit; the codes are the labels.
pub fn write_labels(path: &Path, labels: &Labels) -> Result<()> {
    let (w, h) = (labels.width(), labels.height());
    if labels.data().iter().all(|&l| l <= 255) {
        let bytes: Vec<u8> = labels.data().iter().map(|&l| l as u8).collect();
        write_png(path, (w, h), &bytes, CODES_8, None)
    } else {
        let bytes: Vec<u8> = labels.data().iter().flat_map(|l| l.to_be_bytes()).collect();
        write_png(path, (w, h), &bytes, CODES_16, None)
    }
}

/// Writes a mask as an 8-bit PNG (0 outside, 255 inside).
pub fn write_mask(path: &Path, mask: &Mask) -> Result<()> {
    let bytes: Vec<u8> = mask
        .data()
        .iter()
        .map(|&m| if m { 255 } else { 0 })
        .collect();
    let size = (mask.width(), mask.height());
    write_png(path, size, &bytes, CODES_8, None)
}

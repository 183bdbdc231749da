//! PNG input and output (8- and 16-bit, grayscale and RGB) through the `image` crate.

use crate::error::{Error, Result};
use crate::grid::{check_size, Grid, Image, Labels, Mask, RgbImage};
use image::{DynamicImage, ImageReader};
use serde::Serialize;
use std::path::Path;

/// How colour input becomes luminance (stated in reports): the Rec. 709 / sRGB luminance
/// weights applied to the linear channel values; alpha is ignored.
pub const LUMINANCE_FORMULA: &str = "Y = 0.2126 R + 0.7152 G + 0.0722 B (Rec. 709 weights on the linear values: the stored values scaled to 0..1, decoded only where the file's sRGB or gAMA chunk says how; alpha ignored)";

/// Bits per channel of a written PNG.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum BitDepth {
    /// 8 bits per channel (0..255).
    Eight,
    /// 16 bits per channel (0..65535).
    Sixteen,
}

impl BitDepth {
    /// Bits per channel: 8 or 16.
    pub fn bits(self) -> u8 {
        match self {
            BitDepth::Eight => 8,
            BitDepth::Sixteen => 16,
        }
    }
}

/// What was read from a PNG and how it was converted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GrayInfo {
    /// Bits per channel in the file.
    pub bit_depth: u8,
    /// Channels in the file (1 gray, 2 gray+alpha, 3 RGB, 4 RGBA).
    pub channels: u8,
    /// The conversion applied, when the file was not plain grayscale.
    pub conversion: Option<String>,
}

/// Reads the image at `path`, its signature and declared size first: a file that is not a
/// PNG or GIF is refused after 24 bytes, one declaring more than `max_pixels` before its body
/// is read, and one longer than an image of its declared size can be
/// ([`max_image_file_bytes`]) after that many bytes.
fn decode(path: &Path, max_pixels: usize) -> Result<(DynamicImage, Stored)> {
    use std::io::Read;
    let mut file = super::open_file(path)?;
    let mut bytes = Vec::new();
    (&mut file)
        .take(HEAD_BYTES as u64)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    let (w, h) = declared_size(&bytes).map_err(|m| Error::format(path, m))?;
    check_size(w as usize, h as usize, max_pixels)
        .map_err(|e| Error::format(path, e.to_string()))?;
    let cap = max_image_file_bytes(w, h);
    file.take(cap.saturating_add(1).saturating_sub(bytes.len() as u64))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(super::too_long(path, cap));
    }
    decode_bytes(&bytes, path, max_pixels)
}

/// The bytes read before anything else: enough for the PNG signature and IHDR chunk's size
/// (24), or the GIF signature and screen size (10).
const HEAD_BYTES: usize = 24;

/// The PNG signature.
const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The width and height a PNG (IHDR) or GIF (logical screen) declares in its first
/// [`HEAD_BYTES`] bytes; an error for anything else.
fn declared_size(head: &[u8]) -> std::result::Result<(u32, u32), String> {
    let be = |at: usize| u32::from_be_bytes([head[at], head[at + 1], head[at + 2], head[at + 3]]);
    if head.starts_with(PNG_SIGNATURE) {
        if head.len() < HEAD_BYTES || &head[12..16] != b"IHDR" {
            return Err("corrupt PNG: it does not begin with its header (IHDR) chunk".into());
        }
        Ok((be(16), be(20)))
    } else if head.starts_with(b"GIF87a") || head.starts_with(b"GIF89a") {
        if head.len() < 10 {
            return Err("corrupt GIF: the file ends inside its header".into());
        }
        let le = |at: usize| u32::from(u16::from_le_bytes([head[at], head[at + 1]]));
        Ok((le(6), le(8)))
    } else {
        Err("not a PNG image (the file does not start with the PNG signature)".into())
    }
}

/// The most bytes a PNG or GIF of `w`×`h` pixels is read to: twice its largest raw size
/// (RGBA at 16 bits and a filter byte a row; deflate at worst stores blocks with 5 bytes each)
/// plus 16 MiB for other chunks (text, colour profiles).
fn max_image_file_bytes(w: u32, h: u32) -> u64 {
    let raw = u64::from(w) * u64::from(h) * 8 + u64::from(h);
    raw.saturating_mul(2).saturating_add(16 << 20)
}

/// Decodes an image held in memory; `source` names it in errors. The signature and declared
/// size are checked (against `max_pixels`) before any pixel buffer is allocated.
fn decode_bytes(bytes: &[u8], source: &Path, max_pixels: usize) -> Result<(DynamicImage, Stored)> {
    declared_size(bytes).map_err(|m| Error::format(source, m))?;
    let stored = walk_png_chunks(bytes).map_err(|m| Error::format(source, m))?;
    let open = || -> Result<ImageReader<std::io::Cursor<&[u8]>>> {
        let mut reader = ImageReader::new(std::io::Cursor::new(bytes));
        // As `ImageReader::open`: the extension names the format when the content does not.
        if let Ok(format) = image::ImageFormat::from_path(source) {
            reader.set_format(format);
        }
        reader
            .with_guessed_format()
            .map_err(|e| Error::io(source, e))
    };
    let (w, h) = open()?
        .into_dimensions()
        .map_err(|e| Error::format(source, format!("not a readable image ({e})")))?;
    check_size(w as usize, h as usize, max_pixels)
        .map_err(|e| Error::format(source, e.to_string()))?;
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    // The size was checked against `max_pixels` above; the decoder's own allocation cap
    // (512 MiB by default) must not stop what `--max-pixels` allows: the largest pixel is RGBA
    // at 16 bits, 8 bytes.
    let buffer = u64::from(w) * u64::from(h) * 8;
    limits.max_alloc = Some(limits.max_alloc.unwrap_or(0).max(buffer));
    reader.limits(limits);
    let image = reader
        .decode()
        .map_err(|e| Error::format(source, format!("cannot decode image ({e})")))?;
    Ok((image, stored))
}

/// How a picture's codes (scaled to 0..1) encode linear luminance, as its PNG chunks say.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stored {
    /// No chunk says: the codes are taken as linear luminance.
    Unstated,
    /// A gAMA chunk: codes = luminance^file_gamma (1.0: linear, as shadelab writes).
    FileGamma(f64),
    /// An sRGB chunk: the sRGB transfer function.
    Srgb,
}

impl Stored {
    /// The linear value of a code scaled to 0..1.
    pub fn linear(self, v: f64) -> f64 {
        match self {
            Stored::Unstated => v,
            Stored::FileGamma(1.0) => v,
            Stored::FileGamma(g) => v.powf(1.0 / g),
            Stored::Srgb if v <= 0.04045 => v / 12.92,
            Stored::Srgb => ((v + 0.055) / 1.055).powf(2.4),
        }
    }

    /// What was done, in words, when the codes were not linear; `None` when they were.
    fn note(self) -> Option<String> {
        match self {
            Stored::FileGamma(g) if g != 1.0 => Some(format!(
                "decoded by the file's gAMA chunk ({g}): luminance = code^(1/{g})"
            )),
            Stored::Srgb => {
                Some("decoded by the file's sRGB chunk (the sRGB transfer function)".into())
            }
            _ => None,
        }
    }
}

/// Whether the PNG at `path` says how its codes encode luminance (an sRGB or gAMA chunk before
/// its pixels), so that [`read_gray`] decodes them; false for anything unreadable or not a PNG
/// (its reader reports those).
pub fn states_its_encoding(path: &Path) -> bool {
    use std::io::Read;
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    // The chunks before the pixels: header, gAMA and text come first, well inside 1 MiB.
    let mut head = Vec::new();
    if file.take(1 << 20).read_to_end(&mut head).is_err() {
        return false;
    }
    !matches!(walk_png_chunks(&head), Ok(Stored::Unstated) | Err(_))
}

/// Walks the chunks of a PNG before its pixels are decoded: reads how its codes encode
/// luminance (sRGB, then gAMA, as PNG orders them), and refuses a palette (PLTE) whose length is
/// not a positive multiple of 3 up to 768 (the `png` crate (0.18) panics expanding such a
/// palette) and a gAMA of 0. Anything else wrong with the chunks is left to the decoder.
fn walk_png_chunks(bytes: &[u8]) -> std::result::Result<Stored, String> {
    let Some(mut rest) = bytes.strip_prefix(PNG_SIGNATURE) else {
        return Ok(Stored::Unstated);
    };
    let (mut gamma, mut srgb) = (None, false);
    while rest.len() >= 8 {
        let length = u32::from_be_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        let kind = &rest[4..8];
        if kind == b"PLTE" && (length == 0 || length % 3 != 0 || length > 768) {
            return Err(format!(
                "corrupt PNG: its palette (PLTE) is {length} bytes long, which is not 3 bytes \
                 for each of 1 to 256 colours"
            ));
        }
        if kind == b"sRGB" {
            srgb = true;
        }
        if kind == b"gAMA" && length == 4 {
            if let Some(d) = rest.get(8..12) {
                let value = u32::from_be_bytes([d[0], d[1], d[2], d[3]]);
                if value == 0 {
                    return Err("corrupt PNG: its gAMA chunk says gamma 0".into());
                }
                gamma = Some(f64::from(value) / 100_000.0);
            }
        }
        if kind == b"IDAT" || kind == b"IEND" {
            break;
        }
        // Chunk: length, type, data, CRC.
        match rest.get(length.saturating_add(12)..) {
            Some(next) => rest = next,
            None => break,
        }
    }
    Ok(match (srgb, gamma) {
        (true, _) => Stored::Srgb,
        (false, Some(g)) => Stored::FileGamma(g),
        (false, None) => Stored::Unstated,
    })
}

/// Reads a PNG (or another format the `image` crate knows) as linear luminance 0..1.
/// Grayscale is scaled by its maximum code; colour becomes luminance by [`LUMINANCE_FORMULA`].
/// Codes are decoded by the file's sRGB or gAMA chunk where it has one (`Stored`): a PNG
/// shadelab wrote with `--gamma` reads back as the linear values it was made from.
pub fn read_gray(path: &Path, max_pixels: usize) -> Result<(Image, GrayInfo)> {
    let (image, stored) = decode(path, max_pixels)?;
    gray_from(image, stored)
}

/// [`read_gray`] of an image held in memory; `source` names it in errors.
pub fn read_gray_from_bytes(
    bytes: &[u8],
    source: &Path,
    max_pixels: usize,
) -> Result<(Image, GrayInfo)> {
    let (image, stored) = decode_bytes(bytes, source, max_pixels)?;
    gray_from(image, stored)
}

fn gray_from(img: DynamicImage, stored: Stored) -> Result<(Image, GrayInfo)> {
    let color = img.color();
    let channels = color.channel_count();
    let bit_depth = (color.bits_per_pixel() / channels as u16) as u8;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let linear = |code: f64, max: f64| stored.linear(code / max);
    let (data, channel_note): (Vec<f64>, Option<String>) = match img {
        DynamicImage::ImageLuma8(b) => (
            b.into_raw()
                .into_iter()
                .map(|v| linear(v.into(), 255.0))
                .collect(),
            None,
        ),
        DynamicImage::ImageLuma16(b) => (
            b.into_raw()
                .into_iter()
                .map(|v| linear(v.into(), 65535.0))
                .collect(),
            None,
        ),
        DynamicImage::ImageLumaA8(b) => (
            b.pixels().map(|p| linear(p.0[0].into(), 255.0)).collect(),
            Some("alpha ignored".into()),
        ),
        DynamicImage::ImageLumaA16(b) => (
            b.pixels().map(|p| linear(p.0[0].into(), 65535.0)).collect(),
            Some("alpha ignored".into()),
        ),
        other => {
            let rgb = other.into_rgb32f();
            (
                rgb.pixels()
                    .map(|p| crate::grid::luminance(p.0.map(|c| linear(c.into(), 1.0))))
                    .collect(),
                Some(LUMINANCE_FORMULA.to_string()),
            )
        }
    };
    let notes: Vec<String> = [stored.note(), channel_note]
        .into_iter()
        .flatten()
        .collect();
    Ok((
        Grid::from_vec(w, h, data)?,
        GrayInfo {
            bit_depth,
            channels,
            conversion: (!notes.is_empty()).then(|| notes.join("; ")),
        },
    ))
}

/// Reads a colour image as linear RGB 0..1 (gray input is copied to the three channels),
/// decoded by the file's sRGB or gAMA chunk where it has one.
pub fn read_rgb(path: &Path, max_pixels: usize) -> Result<RgbImage> {
    let (img, stored) = decode(path, max_pixels)?;
    let img = img.into_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    Grid::from_vec(
        w,
        h,
        img.pixels()
            .map(|p| p.0.map(|c| stored.linear(c.into())))
            .collect(),
    )
}

/// Reads a mask: any non-zero pixel (in any channel) is inside.
pub fn read_mask(path: &Path, max_pixels: usize) -> Result<Mask> {
    mask_from(decode(path, max_pixels)?.0)
}

/// [`read_mask`] of an image held in memory; `source` names it in errors.
pub fn read_mask_from_bytes(bytes: &[u8], source: &Path, max_pixels: usize) -> Result<Mask> {
    mask_from(decode_bytes(bytes, source, max_pixels)?.0)
}

fn mask_from(img: DynamicImage) -> Result<Mask> {
    let img = img.into_rgba16();
    let (w, h) = (img.width() as usize, img.height() as usize);
    Grid::from_vec(
        w,
        h,
        img.pixels()
            .map(|p| p.0[..3].iter().any(|&v| v > 0))
            .collect(),
    )
}

/// Reads a label map (8- or 16-bit grayscale codes 0..N).
pub fn read_labels(path: &Path, max_pixels: usize) -> Result<Labels> {
    let img = decode(path, max_pixels)?.0;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data = match img {
        DynamicImage::ImageLuma8(b) => b.into_raw().into_iter().map(u16::from).collect(),
        DynamicImage::ImageLuma16(b) => b.into_raw(),
        _ => {
            return Err(Error::format(
                path,
                "a label map must be an 8- or 16-bit grayscale PNG",
            ))
        }
    };
    Grid::from_vec(w, h, data)
}

/// Encodes a linear value 0..1 (clamped; NaN becomes 0) with an optional display gamma.
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
/// use shadelab::{io::display_rgba8, Grid};
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
    super::write_atomic(path, |out| {
        let mut encoder = png::Encoder::new(out, w32, h32);
        encoder.set_color(color);
        encoder.set_depth(depth);
        encoder.set_compression(png::Compression::Fast);
        encoder.set_filter(png::Filter::Adaptive);
        if let Some(SelfDescription {
            gamma,
            text: Some(text),
        }) = described
        {
            let value = png_gamma_chunk_value(gamma);
            encoder.set_source_gamma(png::ScaledFloat::from_scaled(value));
            for (keyword, text) in text {
                encoder
                    .add_itxt_chunk(keyword.clone(), text.clone())
                    .map_err(|e| fail(&e))?;
            }
        }
        let mut writer = encoder.write_header().map_err(|e| fail(&e))?;
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
    let plain = SelfDescription { gamma, text: None };
    write_encoded(path, image, depth, plain, png::ColorType::Grayscale)
}

/// Writes an RGB PNG of linear values 0..1 (clamped), optionally display-encoded.
pub fn write_rgb(path: &Path, image: &RgbImage, depth: BitDepth, gamma: Option<f64>) -> Result<()> {
    let plain = SelfDescription { gamma, text: None };
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
    };
    match picture {
        PngPicture::Gray(image) => {
            write_encoded(path, image, depth, described, png::ColorType::Grayscale)
        }
        PngPicture::Rgb(image) => write_encoded(path, image, depth, described, png::ColorType::Rgb),
    }
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
    let described = SelfDescription { gamma, text: None };
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
    let described = SelfDescription { gamma, text: None };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::DEFAULT_MAX_PIXELS;

    fn scratch(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("shadelab-png-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn sixteen_bit_round_trip_is_exact() {
        let d = scratch("rt16");
        let img = Grid::from_fn(7, 5, |c, r| ((c * 5 + r) as f64 * 1000.0).round() / 65535.0);
        let p = d.join("a.png");
        write_gray(&p, &img, BitDepth::Sixteen, None).unwrap();
        let (back, info) = read_gray(&p, DEFAULT_MAX_PIXELS).unwrap();
        assert_eq!((info.bit_depth, info.channels), (16, 1));
        for (a, b) in img.data().iter().zip(back.data()) {
            assert!((a - b).abs() < 1e-12);
        }
        let labels = Grid::from_fn(4, 3, |c, r| (c + 300 * r) as u16);
        write_labels(&d.join("l.png"), &labels).unwrap();
        assert_eq!(
            read_labels(&d.join("l.png"), DEFAULT_MAX_PIXELS).unwrap(),
            labels
        );
    }

    #[test]
    fn gamma_and_rgb_luminance() {
        let d = scratch("gamma");
        let img = Grid::new(2, 2, 0.25);
        write_gray(&d.join("g.png"), &img, BitDepth::Eight, Some(2.0)).unwrap();
        let (back, _) = read_gray(&d.join("g.png"), DEFAULT_MAX_PIXELS).unwrap();
        assert_eq!(back.get(0, 0) * 255.0, 128.0); // 0.25^(1/2) = 0.5 → 127.5 → 128
        let rgb = Grid::new(2, 1, [1.0, 0.0, 0.0]);
        write_rgb(&d.join("c.png"), &rgb, BitDepth::Sixteen, None).unwrap();
        let (y, info) = read_gray(&d.join("c.png"), DEFAULT_MAX_PIXELS).unwrap();
        assert!((y.get(0, 0) - 0.2126).abs() < 1e-6);
        assert!(info.conversion.unwrap().contains("0.2126"));
    }

    /// An 8-bit gray PNG of `codes` (one row) with the chunks `chunk` sets, by the `png` crate.
    fn tagged(path: &Path, codes: &[u8], chunk: impl FnOnce(&mut png::Encoder<'_, std::fs::File>)) {
        let file = std::fs::File::create(path).unwrap();
        let mut encoder = png::Encoder::new(file, codes.len() as u32, 1);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        chunk(&mut encoder);
        encoder
            .write_header()
            .unwrap()
            .write_image_data(codes)
            .unwrap();
    }

    #[test]
    fn srgb_and_gamma_chunks_decode_the_codes_and_no_chunk_leaves_them_linear() {
        let d = scratch("chunks");
        let codes = [0u8, 10, 128, 255];
        let scaled = codes.map(|c| f64::from(c) / 255.0);
        tagged(&d.join("srgb.png"), &codes, |e| {
            e.set_source_srgb(png::SrgbRenderingIntent::Perceptual)
        });
        tagged(&d.join("gama.png"), &codes, |e| {
            e.set_source_gamma(png::ScaledFloat::from_scaled(45_455))
        });
        tagged(&d.join("none.png"), &codes, |_| {});
        let read = |name: &str| read_gray(&d.join(name), DEFAULT_MAX_PIXELS).unwrap();
        // IEC 61966-2-1: linear below 0.04045 (code 10: 0.0392 / 12.92), a 2.4 power above.
        let (srgb, info) = read("srgb.png");
        assert!(info.conversion.unwrap().contains("sRGB"));
        assert_eq!(*srgb.get(0, 0), 0.0);
        assert!((srgb.get(1, 0) - scaled[1] / 12.92).abs() < 1e-12);
        assert!(
            (srgb.get(2, 0) - 0.215861).abs() < 1e-6,
            "{}",
            srgb.get(2, 0)
        );
        assert_eq!(*srgb.get(3, 0), 1.0);
        // gAMA 0.45455: code = L^0.45455, so L = code^(1/0.45455).
        let (gama, _) = read("gama.png");
        for (i, s) in scaled.iter().enumerate() {
            assert!((gama.get(i, 0) - s.powf(1.0 / 0.45455)).abs() < 1e-12);
        }
        let (none, info) = read("none.png");
        assert_eq!(none.data(), &scaled[..]);
        assert!(info.conversion.is_none());
        assert!(
            states_its_encoding(&d.join("gama.png")) && !states_its_encoding(&d.join("none.png"))
        );
    }

    #[test]
    fn the_writers_from_a_function_write_the_grids_bytes() {
        let d = scratch("fn");
        let gray = |c: usize, r: usize| (c * 7 + r * 3) as f64 / 40.0 - 0.1;
        let rgb = |c: usize, r: usize| [gray(c, r), 0.5, 1.0 - gray(c, r)];
        for depth in [BitDepth::Eight, BitDepth::Sixteen] {
            write_gray(
                &d.join("g.png"),
                &Grid::from_fn(5, 3, gray),
                depth,
                Some(2.2),
            )
            .unwrap();
            write_gray_fn(&d.join("gf.png"), (5, 3), depth, Some(2.2), gray).unwrap();
            write_rgb(&d.join("c.png"), &Grid::from_fn(5, 3, rgb), depth, None).unwrap();
            write_rgb_fn(&d.join("cf.png"), (5, 3), depth, None, rgb).unwrap();
            let bytes = |n: &str| std::fs::read(d.join(n)).unwrap();
            assert_eq!(bytes("g.png"), bytes("gf.png"));
            assert_eq!(bytes("c.png"), bytes("cf.png"));
        }
    }

    #[test]
    fn corrupt_and_oversized_files_are_errors() {
        let d = scratch("bad");
        let p = d.join("t.png");
        std::fs::write(&p, b"\x89PNG\r\n\x1a\n garbage").unwrap();
        assert!(read_gray(&p, DEFAULT_MAX_PIXELS).is_err());
        let ok = d.join("ok.png");
        write_gray(&ok, &Grid::new(40, 30, 0.5), BitDepth::Eight, None).unwrap();
        let e = read_gray(&ok, 100).unwrap_err().to_string();
        assert!(e.contains("exceeds"), "{e}");
        let bytes = std::fs::read(&ok).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
        assert!(read_gray(&p, DEFAULT_MAX_PIXELS).is_err());
        assert!(read_gray(&d, DEFAULT_MAX_PIXELS).is_err());
    }
}

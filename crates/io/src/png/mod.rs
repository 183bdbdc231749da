//! PNG input and output (8- and 16-bit, grayscale and RGB) through the `image` crate, which
//! also reads GIF, JPEG and TIFF pictures (JPEG and TIFF with the `photos` feature).

mod write;

pub use write::{
    display_rgba8, stimulus_codes, write_display_codes, write_gray, write_gray_fn, write_labels,
    write_mask, write_rgb, write_rgb_fn, write_stimulus, DisplayCodes, PngPicture,
};

use super::encoding::{Decoding, InputEncoding};
use crate::error::{Error, Result};
use crate::grid::{check_size, Grid, Image, Labels, Mask, RgbImage};
use image::{DynamicImage, ImageReader};
use serde::Serialize;
use std::path::Path;

/// How colour input becomes luminance (stated in reports): the Rec. 709 / sRGB luminance
/// weights applied to the linear channel values; alpha is ignored.
pub const LUMINANCE_FORMULA: &str = "Y = 0.2126 R + 0.7152 G + 0.0722 B (Rec. 709 weights on the linear values: the stored values scaled to 0..1, decoded as the file's chunk or the input encoding says; alpha ignored)";

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

/// Reads the picture at `path`, its signature and declared size first: a file that is not a
/// PNG, GIF, JPEG or TIFF is refused after 24 bytes, a PNG or GIF declaring more than
/// `max_pixels` before its body is read, and one longer than an image of its declared size can
/// be ([`max_image_file_bytes`]) after that many bytes. A JPEG or TIFF says its size further in
/// (after its metadata, or at its end): it is read up to the bytes of the largest picture
/// `max_pixels` allows, and its size is checked before any pixel buffer is allocated.
fn decode(path: &Path, max_pixels: usize) -> Result<(DynamicImage, Facts)> {
    let mut file = super::open_file(path)?;
    let head = read_head(&mut file, path)?;
    let bytes = read_raster_rest(head, file, path, max_pixels)?;
    decode_bytes(&bytes, path, max_pixels)
}

/// The first [`HEAD_BYTES`] bytes of `file` (fewer when it is shorter): enough to tell every
/// format shadelab reads by its signature.
pub(crate) fn read_head(file: &mut impl std::io::Read, path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    file.take(HEAD_BYTES as u64)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    Ok(bytes)
}

/// The whole of a PNG, GIF, JPEG or TIFF file whose first bytes `bytes` were read from `file`
/// (see [`decode`] for the caps; `file` is read on, never reopened, so that a pipe works).
pub(crate) fn read_raster_rest(
    mut bytes: Vec<u8>,
    file: impl std::io::Read,
    path: &Path,
    max_pixels: usize,
) -> Result<Vec<u8>> {
    use std::io::Read;
    let cap = match declared_size(&bytes, path).map_err(|m| Error::format(path, m))? {
        Some((w, h)) => {
            check_size(w as usize, h as usize, max_pixels)
                .map_err(|e| Error::format(path, e.to_string()))?;
            max_image_file_bytes(w, h)
        }
        None => largest_file_bytes(max_pixels),
    };
    file.take(cap.saturating_add(1).saturating_sub(bytes.len() as u64))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(super::too_long(path, cap));
    }
    Ok(bytes)
}

/// The bytes read before anything else: enough for the PNG signature and IHDR chunk's size
/// (24), the GIF signature and screen size (10), and the JPEG and TIFF signatures.
const HEAD_BYTES: usize = 24;

/// The PNG signature.
const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The kind of a picture file, by its signature.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Png,
    Gif,
    Jpeg,
    Tiff,
}

/// Whether `head` starts with the signature of a PNG, GIF, JPEG or TIFF.
pub(crate) fn is_raster(head: &[u8]) -> bool {
    format_of(head).is_some()
}

/// The format whose signature `head` starts with.
fn format_of(head: &[u8]) -> Option<Format> {
    if head.starts_with(PNG_SIGNATURE) {
        Some(Format::Png)
    } else if head.starts_with(b"GIF87a") || head.starts_with(b"GIF89a") {
        Some(Format::Gif)
    } else if head.starts_with(&[0xFF, 0xD8, 0xFF]) {
        Some(Format::Jpeg)
    } else if head.starts_with(b"II*\0") || head.starts_with(b"MM\0*") {
        Some(Format::Tiff)
    } else {
        None
    }
}

/// The width and height a PNG (IHDR) or GIF (logical screen) declares in its first
/// [`HEAD_BYTES`] bytes; `None` for a JPEG or TIFF (they say it further in); an error for
/// anything else, naming the format `source`'s extension promises.
fn declared_size(head: &[u8], source: &Path) -> std::result::Result<Option<(u32, u32)>, String> {
    let be = |at: usize| u32::from_be_bytes([head[at], head[at + 1], head[at + 2], head[at + 3]]);
    match format_of(head) {
        Some(Format::Png) => {
            if head.len() < HEAD_BYTES || &head[12..16] != b"IHDR" {
                return Err("corrupt PNG: it does not begin with its header (IHDR) chunk".into());
            }
            Ok(Some((be(16), be(20))))
        }
        Some(Format::Gif) => {
            if head.len() < 10 {
                return Err("corrupt GIF: the file ends inside its header".into());
            }
            let le = |at: usize| u32::from(u16::from_le_bytes([head[at], head[at + 1]]));
            Ok(Some((le(6), le(8))))
        }
        Some(Format::Jpeg | Format::Tiff) => Ok(None),
        None => Err(match super::extension(source).as_str() {
            "jpg" | "jpeg" => "not a JPEG image (the file does not start with the JPEG signature)",
            "tif" | "tiff" => "not a TIFF image (the file does not start with a TIFF signature)",
            _ => "not a PNG image (the file does not start with the PNG signature)",
        }
        .into()),
    }
}

/// The most bytes a PNG or GIF of `w`×`h` pixels is read to: twice its largest raw size
/// (RGBA at 16 bits and a filter byte a row; deflate at worst stores blocks with 5 bytes each)
/// plus 16 MiB for other chunks (text, colour profiles). A JPEG or TIFF of that size is held to
/// the same bound once its size is known.
fn max_image_file_bytes(w: u32, h: u32) -> u64 {
    let raw = u64::from(w) * u64::from(h) * 8 + u64::from(h);
    raw.saturating_mul(2).saturating_add(16 << 20)
}

/// The most bytes read of a file whose size is not in its first bytes (JPEG, TIFF): those of
/// the largest picture `max_pixels` allows, one row of `max_pixels` pixels.
fn largest_file_bytes(max_pixels: usize) -> u64 {
    max_image_file_bytes(u32::try_from(max_pixels).unwrap_or(u32::MAX), 1)
}

/// Decodes an image held in memory; `source` names it in errors. The signature and declared
/// size are checked (against `max_pixels`) before any pixel buffer is allocated.
fn decode_bytes(bytes: &[u8], source: &Path, max_pixels: usize) -> Result<(DynamicImage, Facts)> {
    declared_size(bytes, source).map_err(|m| Error::format(source, m))?;
    let facts = picture_facts(bytes, source).map_err(|m| Error::format(source, m))?;
    if !cfg!(feature = "photos") && matches!(facts.format, Format::Jpeg | Format::Tiff) {
        return Err(Error::format(
            source,
            "JPEG and TIFF pictures need shadelab built with its `photos` feature",
        ));
    }
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
    if matches!(facts.format, Format::Jpeg | Format::Tiff) {
        let cap = max_image_file_bytes(w, h);
        if bytes.len() as u64 > cap {
            return Err(super::too_long(source, cap));
        }
    }
    if facts.format == Format::Jpeg {
        check_jpeg_complete(bytes).map_err(|m| Error::format(source, m))?;
    }
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    // The size was checked against `max_pixels` above; the decoder's own allocation cap
    // (512 MiB by default) must not stop what `--max-pixels` allows: the largest pixel is RGBA
    // at 16 bits, 8 bytes (RGBA in 32-bit floats, 16, in a TIFF).
    let per_pixel = if facts.format == Format::Tiff { 16 } else { 8 };
    let buffer = u64::from(w) * u64::from(h) * per_pixel;
    limits.max_alloc = Some(limits.max_alloc.unwrap_or(0).max(buffer));
    reader.limits(limits);
    let image = reader
        .decode()
        .map_err(|e| Error::format(source, format!("cannot decode image ({e})")))?;
    Ok((image, facts))
}

/// Refuses a JPEG that ends before its end-of-image marker (a truncated download or copy):
/// the decoder would fill the missing part with gray and say nothing. Walks the marker
/// segments and the entropy-coded data of every scan to the EOI marker.
fn check_jpeg_complete(bytes: &[u8]) -> std::result::Result<(), String> {
    let truncated =
        || "corrupt JPEG: the file ends before its end-of-image marker (truncated)".to_string();
    let mut i = 2; // after SOI
    loop {
        // Bytes between segments (which decoders skip) and fill bytes before a marker code.
        while bytes.get(i).is_some_and(|&b| b != 0xFF) {
            i += 1;
        }
        while bytes.get(i + 1) == Some(&0xFF) {
            i += 1;
        }
        let Some(&code) = bytes.get(i + 1) else {
            return Err(truncated());
        };
        i += 2;
        match code {
            0xD9 => return Ok(()),
            0x00 | 0x01 | 0xD0..=0xD8 => continue,
            _ => {
                let Some(length) = bytes.get(i..i + 2) else {
                    return Err(truncated());
                };
                i += usize::from(u16::from_be_bytes([length[0], length[1]]));
                if i > bytes.len() {
                    return Err(truncated());
                }
                if code == 0xDA {
                    // A scan's data: up to the first marker that is not a stuffed 0xFF 0x00 or
                    // a restart marker.
                    loop {
                        match (bytes.get(i), bytes.get(i + 1)) {
                            (None, _) | (Some(0xFF), None) => return Err(truncated()),
                            (Some(0xFF), Some(0x00 | 0xD0..=0xD7)) => i += 2,
                            (Some(0xFF), Some(_)) => break,
                            _ => i += 1,
                        }
                    }
                }
            }
        }
    }
}

/// How a picture's codes (scaled to 0..1) encode linear luminance, as its PNG chunks say.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stored {
    /// No chunk says.
    Unstated,
    /// A gAMA chunk: codes = luminance^file_gamma (1.0: linear, as shadelab writes).
    FileGamma(f64),
    /// An sRGB chunk: the sRGB transfer function.
    Srgb,
}

/// What a picture file says of itself before its pixels: its format, how its codes encode
/// luminance (a PNG's chunks), its bits per sample (a PNG's header) and whether shadelab wrote
/// it (a PNG's `Software` text, or a shadelab sidecar beside it).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Facts {
    format: Format,
    stored: Stored,
    bits: u8,
    by_shadelab: bool,
}

/// The facts of the picture whose first bytes (at least its signature; for a PNG, all of it
/// or its chunks before the pixels) are `bytes`, read from `source`.
fn picture_facts(bytes: &[u8], source: &Path) -> std::result::Result<Facts, String> {
    let format = format_of(bytes).unwrap_or(Format::Png);
    let chunks = walk_png_chunks(bytes)?;
    Ok(Facts {
        format,
        stored: chunks.stored,
        bits: match format {
            Format::Png => chunks.bits,
            // A TIFF's depth is in its directory; its rule does not depend on it.
            Format::Gif | Format::Jpeg | Format::Tiff => 8,
        },
        by_shadelab: chunks.by_shadelab || beside_a_shadelab_sidecar(source),
    })
}

/// Whether a shadelab sidecar (`"program": "shadelab"`) lies beside `image`: a picture
/// shadelab rendered before its PNGs carried a gAMA chunk, whose codes are linear (or
/// encoded with the gamma the sidecar records, which the reader of the sidecar undoes).
fn beside_a_shadelab_sidecar(image: &Path) -> bool {
    let path = super::render_sidecar::sidecar_path(image);
    if path == image || !path.is_file() {
        return false;
    }
    super::read_bytes(&path)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .is_some_and(|v| v.get("program").and_then(serde_json::Value::as_str) == Some("shadelab"))
}

/// The decoding of a picture, its words for a report, and the note to say where the codes
/// were assumed to be sRGB.
#[derive(Debug, Clone, PartialEq)]
struct Resolved {
    decoding: Decoding,
    conversion: Option<String>,
    assumed: bool,
}

/// The words of the note when an untagged 8-bit picture is decoded as sRGB.
const ASSUMED_SRGB: &str = "8-bit picture without a gamma chunk decoded as sRGB, the web's and \
                            cameras' default (--input-gamma linear to read the codes as luminance)";

/// How the picture of `facts` is decoded under `encoding` (docs/display.md, "Photographs and
/// other pictures").
fn resolve(facts: &Facts, encoding: InputEncoding) -> Resolved {
    let said = |conversion: Option<String>, decoding| Resolved {
        decoding,
        conversion,
        assumed: false,
    };
    if let Some(decoding) = encoding.explicit() {
        let overridden = match facts.stored {
            Stored::Srgb if decoding != Decoding::Srgb => Some("the file's sRGB chunk".to_string()),
            Stored::FileGamma(g) if Decoding::Power(1.0 / g) != decoding => {
                Some(format!("the file's gAMA chunk ({g})"))
            }
            _ => None,
        };
        let what = match decoding {
            Decoding::Linear => "codes read as linear luminance (--input-gamma linear)".to_string(),
            Decoding::Srgb => "decoded as sRGB (--input-gamma srgb)".to_string(),
            Decoding::Power(g) => format!("decoded as luminance = code^{g} (--input-gamma {g})"),
        };
        let conversion = match overridden {
            Some(chunk) => Some(format!("{what}, overriding {chunk}")),
            // Linear codes read as linear: nothing was done.
            None if decoding.is_identity() => None,
            None => Some(what),
        };
        return said(conversion, decoding);
    }
    match facts.stored {
        Stored::Srgb => said(
            Some("decoded by the file's sRGB chunk (the sRGB transfer function)".into()),
            Decoding::Srgb,
        ),
        Stored::FileGamma(g) if g != 1.0 => said(
            Some(format!(
                "decoded by the file's gAMA chunk ({g}): luminance = code^(1/{g})"
            )),
            Decoding::Power(1.0 / g),
        ),
        Stored::FileGamma(_) => said(None, Decoding::Linear),
        Stored::Unstated if facts.format == Format::Tiff => said(
            Some(
                "a TIFF has no gamma chunk: its codes are read as linear luminance \
                 (--input-gamma srgb or G to decode them)"
                    .into(),
            ),
            Decoding::Linear,
        ),
        Stored::Unstated if facts.by_shadelab || facts.bits > 8 => said(None, Decoding::Linear),
        Stored::Unstated => Resolved {
            decoding: Decoding::Srgb,
            conversion: Some(ASSUMED_SRGB.into()),
            assumed: true,
        },
    }
}

/// Whether the PNG at `path` says how its codes encode luminance (an sRGB or gAMA chunk before
/// its pixels), so that [`read_gray`] decodes them; false for anything unreadable or not a PNG
/// (its reader reports those).
pub fn states_its_encoding(path: &Path) -> bool {
    use std::io::Read;
    // Only a file that can be read again: a pipe is read once, by the picture's reader.
    if !path.is_file() {
        return false;
    }
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    // The chunks before the pixels: header, gAMA and text come first, well inside 1 MiB.
    let mut head = Vec::new();
    if file.take(1 << 20).read_to_end(&mut head).is_err() {
        return false;
    }
    walk_png_chunks(&head).is_ok_and(|c| c.stored != Stored::Unstated)
}

/// What a PNG's chunks before its pixels say.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Chunks {
    /// How its codes encode luminance.
    stored: Stored,
    /// Bits per sample (IHDR); 8 for what is not a PNG.
    bits: u8,
    /// A `Software` text chunk (iTXt or tEXt) that starts with "shadelab".
    by_shadelab: bool,
}

/// Walks the chunks of a PNG before its pixels are decoded: reads how its codes encode
/// luminance (sRGB, then gAMA, as PNG orders them), its bit depth and whether shadelab wrote
/// it, and refuses a palette (PLTE) whose length is not a positive multiple of 3 up to 768 (the
/// `png` crate (0.18) panics expanding such a palette) and a gAMA of 0. Anything else wrong
/// with the chunks is left to the decoder.
fn walk_png_chunks(bytes: &[u8]) -> std::result::Result<Chunks, String> {
    let mut chunks = Chunks {
        stored: Stored::Unstated,
        bits: 8,
        by_shadelab: false,
    };
    let Some(mut rest) = bytes.strip_prefix(PNG_SIGNATURE) else {
        return Ok(chunks);
    };
    let (mut gamma, mut srgb) = (None, false);
    while rest.len() >= 8 {
        let length = u32::from_be_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        let kind = &rest[4..8];
        let data = rest.get(8..8usize.saturating_add(length));
        if kind == b"IHDR" {
            if let Some(&bits) = data.and_then(|d| d.get(8)) {
                chunks.bits = bits;
            }
        }
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
        if kind == b"iTXt" || kind == b"tEXt" {
            chunks.by_shadelab |= data.is_some_and(|d| software_is_shadelab(kind, d));
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
    chunks.stored = match (srgb, gamma) {
        (true, _) => Stored::Srgb,
        (false, Some(g)) => Stored::FileGamma(g),
        (false, None) => Stored::Unstated,
    };
    Ok(chunks)
}

/// Whether a tEXt or uncompressed iTXt chunk's `data` is the keyword `Software` with a text
/// that starts with "shadelab" (as [`write_stimulus`]'s callers write it).
fn software_is_shadelab(kind: &[u8], data: &[u8]) -> bool {
    let Some(text) = data.strip_prefix(b"Software\0") else {
        return false;
    };
    let text = if kind == b"iTXt" {
        // Compression flag and method, then the language tag and the translated keyword.
        match text {
            [0, _, rest @ ..] => {
                let mut parts = rest.splitn(3, |&b| b == 0);
                match (parts.next(), parts.next(), parts.next()) {
                    (Some(_), Some(_), Some(text)) => text,
                    _ => return false,
                }
            }
            _ => return false,
        }
    } else {
        text
    };
    text.starts_with(b"shadelab")
}

/// Reads a picture (PNG, GIF, JPEG or TIFF) as linear luminance 0..1, decoded by the default
/// rule ([`InputEncoding::Auto`]); see [`read_gray_as`].
pub fn read_gray(path: &Path, max_pixels: usize) -> Result<(Image, GrayInfo)> {
    read_gray_as(path, max_pixels, InputEncoding::Auto)
}

/// Reads a picture (PNG, GIF, JPEG or TIFF) as linear luminance 0..1, its codes decoded as
/// `encoding` says (with [`InputEncoding::Auto`]: by a PNG's sRGB or gAMA chunk; linear for a
/// 16-bit PNG, a TIFF or a picture shadelab wrote; sRGB for an 8-bit PNG or GIF without a
/// chunk and for a JPEG, said in [`GrayInfo::conversion`]). Grayscale is scaled by its maximum
/// code; colour becomes luminance by [`LUMINANCE_FORMULA`].
pub fn read_gray_as(
    path: &Path,
    max_pixels: usize,
    encoding: InputEncoding,
) -> Result<(Image, GrayInfo)> {
    encoding.validate()?;
    let (image, facts) = decode(path, max_pixels)?;
    gray_from(image, &resolve(&facts, encoding))
}

/// A PNG, GIF, JPEG or TIFF decoded from its bytes, with what it says of itself.
pub(crate) struct Raster {
    /// Its luminance, linear 0..1.
    pub gray: Image,
    /// Its linear RGB, where asked for.
    pub rgb: Option<RgbImage>,
    /// What was read and how it was converted.
    pub info: GrayInfo,
    /// Whether a chunk (sRGB, gAMA) says how its codes encode luminance.
    pub states_its_encoding: bool,
    /// Whether its codes were taken as sRGB by the default rule, with nothing saying so.
    pub assumed_srgb: bool,
    /// How its codes (scaled to 0..1) were decoded.
    pub decoding: Decoding,
}

/// Decodes the picture `bytes` (read from `path`) under `encoding`: its luminance, and its
/// linear RGB too with `colour`.
pub(crate) fn raster_picture(
    bytes: &[u8],
    path: &Path,
    max_pixels: usize,
    encoding: InputEncoding,
    colour: bool,
) -> Result<Raster> {
    encoding.validate()?;
    let (image, facts) = decode_bytes(bytes, path, max_pixels)?;
    let resolved = resolve(&facts, encoding);
    let rgb = colour
        .then(|| rgb_from(&image, resolved.decoding))
        .transpose()?;
    let (gray, info) = gray_from(image, &resolved)?;
    Ok(Raster {
        gray,
        rgb,
        info,
        states_its_encoding: facts.stored != Stored::Unstated,
        assumed_srgb: resolved.assumed,
        decoding: resolved.decoding,
    })
}

/// The note said once where a picture's codes were taken as sRGB by the default rule.
pub(crate) fn assumed_srgb_line(path: &Path) -> String {
    format!("{}: {ASSUMED_SRGB}", path.display())
}

/// [`read_gray`] of an image held in memory; `source` names it in errors.
pub fn read_gray_from_bytes(
    bytes: &[u8],
    source: &Path,
    max_pixels: usize,
) -> Result<(Image, GrayInfo)> {
    let (image, facts) = decode_bytes(bytes, source, max_pixels)?;
    gray_from(image, &resolve(&facts, InputEncoding::Auto))
}

fn gray_from(img: DynamicImage, resolved: &Resolved) -> Result<(Image, GrayInfo)> {
    let color = img.color();
    let channels = color.channel_count();
    let bit_depth = (color.bits_per_pixel() / channels as u16) as u8;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let decoding = resolved.decoding;
    let linear = |code: f64, max: f64| decoding.linear(code / max);
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
    let notes: Vec<String> = [resolved.conversion.clone(), channel_note]
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

/// Reads a colour picture as linear RGB 0..1 (gray input is copied to the three channels),
/// decoded by the default rule ([`InputEncoding::Auto`]); see [`read_rgb_as`].
pub fn read_rgb(path: &Path, max_pixels: usize) -> Result<RgbImage> {
    read_rgb_as(path, max_pixels, InputEncoding::Auto)
}

/// Reads a colour picture as linear RGB 0..1 (gray input is copied to the three channels), its
/// codes decoded as `encoding` says (see [`read_gray_as`]).
pub fn read_rgb_as(path: &Path, max_pixels: usize, encoding: InputEncoding) -> Result<RgbImage> {
    encoding.validate()?;
    let (img, facts) = decode(path, max_pixels)?;
    rgb_from(&img, resolve(&facts, encoding).decoding)
}

/// The linear RGB of a decoded picture whose codes (scaled to 0..1) `decoding` decodes.
fn rgb_from(img: &DynamicImage, decoding: Decoding) -> Result<RgbImage> {
    let img = img.to_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    Grid::from_vec(
        w,
        h,
        img.pixels()
            .map(|p| p.0.map(|c| decoding.linear(c.into())))
            .collect(),
    )
}

/// [`read_mask`](crate::read_mask) of an image held in memory; `source` names it in errors.
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

/// The label map of a raster picture's `bytes` (read from `source`): an 8- or 16-bit grayscale
/// PNG of codes 0..N.
pub(crate) fn labels_from_bytes(bytes: &[u8], source: &Path, max_pixels: usize) -> Result<Labels> {
    let img = decode_bytes(bytes, source, max_pixels)?.0;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data = match img {
        DynamicImage::ImageLuma8(b) => b.into_raw().into_iter().map(u16::from).collect(),
        DynamicImage::ImageLuma16(b) => b.into_raw(),
        _ => {
            return Err(Error::format(
                source,
                "a label map must be an 8- or 16-bit grayscale PNG",
            ))
        }
    };
    Grid::from_vec(w, h, data)
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
            crate::read_labels(&d.join("l.png"), DEFAULT_MAX_PIXELS).unwrap(),
            labels
        );
    }

    #[test]
    fn gamma_and_rgb_luminance() {
        let d = scratch("gamma");
        let img = Grid::new(2, 2, 0.25);
        write_gray(&d.join("g.png"), &img, BitDepth::Eight, Some(2.0)).unwrap();
        // A plain PNG has no chunk: its codes, read as they are.
        let linear = InputEncoding::Linear;
        let (back, _) = read_gray_as(&d.join("g.png"), DEFAULT_MAX_PIXELS, linear).unwrap();
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
    fn srgb_and_gamma_chunks_decode_the_codes_and_no_chunk_is_srgb_unless_linear_is_said() {
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
        // No chunk: an 8-bit picture shadelab did not write is sRGB by default (said), and
        // its codes as they are when asked for linear.
        let (none, info) = read("none.png");
        assert_eq!(none.data(), srgb.data());
        assert!(info
            .conversion
            .unwrap()
            .contains("without a gamma chunk decoded as sRGB"));
        let (none, info) = read_gray_as(
            &d.join("none.png"),
            DEFAULT_MAX_PIXELS,
            InputEncoding::Linear,
        )
        .unwrap();
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

//! A picture file read once: its format told by its content (the PNG, GIF, JPEG, TIFF or
//! `.npy` signature), not its name, and its bytes read through one open file, so that a pipe,
//! a FIFO or bash's `<(…)` works; then decoded into one value ([`PictureFile`]: the pixels,
//! how they were encoded and how finely) that the readers of its sidecar and its analyses are
//! handed, never opening the file again.

use super::encoding::{Decoding, InputEncoding};
use super::npy::{self, IntegerScale};
use super::png;
use super::render_sidecar::{sidecar_path, Beside, RenderSidecar};
use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Labels, Mask, RgbImage};
use serde_json::{json, Value};
use std::path::Path;
use std::sync::Arc;

/// The extensions of the pictures [`read_picture`] reads, as its error lists them.
pub const PICTURE_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "tif", "tiff", "npy"];

/// A picture file's bytes, by the format its content says.
pub(crate) enum FileBytes {
    /// A NumPy `.npy` array.
    Npy(Vec<u8>),
    /// A PNG, GIF, JPEG or TIFF.
    Raster(Vec<u8>),
}

/// The bytes of the picture at `path`, read through one open file: its first bytes say its
/// format (a file whose content says none is taken by its extension, whose reader then says
/// what is wrong), and no more is read than a picture of `max_pixels` can need.
pub(crate) fn read_file_bytes(path: &Path, max_pixels: usize) -> Result<FileBytes> {
    let mut file = super::open_file(path)?;
    let head = png::read_head(&mut file, path)?;
    let ext = super::extension(path);
    if head.starts_with(b"\x93NUMPY") || (!png::is_raster(&head) && ext == "npy") {
        return Ok(FileBytes::Npy(npy::read_npy_rest(
            head, file, path, max_pixels,
        )?));
    }
    if png::is_raster(&head) || PICTURE_EXTENSIONS.contains(&ext.as_str()) {
        return Ok(FileBytes::Raster(png::read_raster_rest(
            head, file, path, max_pixels,
        )?));
    }
    Err(Error::invalid(format!(
        "{}: the image must be a .png or .npy file, or a .jpg, .jpeg, .tif or .tiff picture \
         (its content begins with none of their signatures{})",
        path.display(),
        if ext.is_empty() {
            String::new()
        } else {
            format!(", and its name ends in '.{ext}'")
        }
    )))
}

/// The values of an H×W (or H×W×1) `.npy` label map or mask: booleans, or whole numbers
/// 0..=`top`, with its width and height; anything else is refused naming the first value
/// that is not one.
pub(crate) fn npy_levels(
    bytes: &[u8],
    path: &Path,
    max_pixels: usize,
    top: u16,
) -> Result<(usize, usize, Vec<u16>)> {
    let array = npy::read_array_from_bytes(bytes, path, max_pixels)?;
    let (h, w) = match array.shape[..] {
        [h, w] | [h, w, 1] => (h, w),
        _ => {
            return Err(Error::format(
                path,
                format!(
                    "a mask must be a 2-D H×W array, found shape {:?}",
                    array.shape
                ),
            ))
        }
    };
    crate::grid::check_size(w, h, max_pixels).map_err(|e| Error::format(path, e.to_string()))?;
    let kind = if top == 1 {
        "booleans or 0/1 values"
    } else {
        "booleans or whole numbers 0..65535 (0 = background, 1..N = targets)"
    };
    let mut levels = Vec::with_capacity(array.data.len());
    for (i, &v) in array.data.iter().enumerate() {
        if !(v >= 0.0 && v <= f64::from(top) && v.fract() == 0.0) {
            return Err(Error::format(
                path,
                format!(
                    "a mask .npy must hold {kind}; found {v} at column {}, row {} (dtype {})",
                    i % w.max(1),
                    i / w.max(1),
                    array.dtype
                ),
            ));
        }
        levels.push(v as u16);
    }
    Ok((w, h, levels))
}

/// How finely a picture's values were stored: the values it can hold near any level, so that
/// a decision about a level (is this pixel at the ambient level, in attached shadow?) is made
/// to the picture's own precision and not to the last bit of a float.
#[derive(Debug, Clone, PartialEq)]
pub enum Quantum {
    /// Floating-point values with this relative precision (2⁻⁵³ for float64, 2⁻²⁴ for
    /// float32).
    Float(f64),
    /// Integer codes: the linear value of each code, in increasing order.
    Codes(Arc<Vec<f64>>),
}

impl Default for Quantum {
    /// Float64 values, as rendered in memory.
    fn default() -> Self {
        Quantum::Float(f64::EPSILON / 2.0)
    }
}

impl Quantum {
    /// The codes 0..=`top` decoded to linear values by `linear` (of the code scaled to 0..1).
    fn codes(top: f64, linear: impl Fn(f64) -> f64) -> Quantum {
        // Beyond 16 bits a code is as fine as a float32.
        if top > 65535.0 {
            return Quantum::Float(f64::from(f32::EPSILON) / 2.0);
        }
        let n = top as usize;
        Quantum::Codes(Arc::new((0..=n).map(|c| linear(c as f64 / top)).collect()))
    }

    /// This quantum after every value went through `f` (increasing): a sidecar's display gamma
    /// or range undone.
    pub fn map(&self, f: impl Fn(f64) -> f64) -> Quantum {
        match self {
            Quantum::Float(r) => Quantum::Float(*r),
            Quantum::Codes(table) => {
                Quantum::Codes(Arc::new(table.iter().map(|&v| f(v)).collect()))
            }
        }
    }

    /// The values that the picture cannot tell from `level`: the interval (low, high] of the
    /// code nearest `level` (the values that code stands for), or `level` within two units of
    /// the float's last place on the scale of 0..1.
    pub fn bin(&self, level: f64) -> (f64, f64) {
        match self {
            Quantum::Float(r) => {
                let tol = 2.0 * r * level.abs().max(1.0);
                (level - tol, level + tol)
            }
            Quantum::Codes(table) => {
                // The edges of a code's interval: halfway to its neighbours.
                let low = |c: usize| {
                    c.checked_sub(1)
                        .map_or(f64::NEG_INFINITY, |b| (table[b] + table[c]) / 2.0)
                };
                let high = |c: usize| {
                    table
                        .get(c + 1)
                        .map_or(f64::INFINITY, |&a| (table[c] + a) / 2.0)
                };
                // The codes on either side of the level; each that could have stored it (the
                // level within its interval, to a millionth of a step: a level halfway between
                // two codes, as 0.1 is at 8 and 16 bits, is either's).
                let i = table.partition_point(|&v| v < level);
                let could = |c: usize| {
                    let slack = 1e-6 * (high(c) - low(c)).min(1.0);
                    level > low(c) - slack && level <= high(c) + slack
                };
                let below = i.checked_sub(1).filter(|&c| could(c));
                let above = Some(i).filter(|&c| c < table.len() && could(c));
                match (below, above) {
                    (Some(b), Some(a)) => (low(b), high(a)),
                    (Some(c), None) | (None, Some(c)) => (low(c), high(c)),
                    // Beyond every code (a level the picture cannot hold): itself alone.
                    (None, None) => (level, level),
                }
            }
        }
    }

    /// `image` with its shadow at `level` exactly, as when it was rendered. Where a record
    /// says which pixels the light does not reach (`unlit`, of `image`'s size: a render's
    /// attached and cast shadow), those are at `level` and every other pixel lies above it (a
    /// lit pixel whose code is the level's, as a lit 0.1001 is at 16 bits where the ambient
    /// 0.2 is a code, is the smallest value above it: one the code stands for). Without a
    /// record, every value the picture cannot tell from `level` ([`bin`](Self::bin)) is set to
    /// `level`: a rendered picture's shadow, stored as 8- or 16-bit codes or float32, is at
    /// its ambient level again, but so is a lit pixel that shares the level's code.
    pub fn settle(&self, image: &Image, level: f64, unlit: Option<&Mask>) -> Image {
        if let Some(unlit) =
            unlit.filter(|m| (m.width(), m.height()) == (image.width(), image.height()))
        {
            // Levels are never negative (an ambient level is at least 0).
            let above = if level > 0.0 {
                f64::from_bits(level.to_bits() + 1)
            } else {
                f64::MIN_POSITIVE
            };
            return Grid::from_fn(image.width(), image.height(), |c, r| {
                match (*unlit.get(c, r), *image.get(c, r)) {
                    (true, _) => level,
                    (false, v) if v <= level => above,
                    (false, v) => v,
                }
            });
        }
        let (low, high) = self.bin(level);
        image.map(|&v| if v > low && v <= high { level } else { v })
    }

    /// Whether `value`, stored in a picture of this quantum, could be the stored form of
    /// `exact`: `exact` lies in the interval of `value`'s code (for floats, within the
    /// float's last places).
    pub fn could_store(&self, value: f64, exact: f64) -> bool {
        let (low, high) = self.bin(value);
        let slack = 1e-6 * (high - low).min(1.0);
        exact > low - slack && exact <= high + slack
    }
}

/// A picture file read once and decoded.
#[derive(Debug, Clone)]
pub struct PictureFile {
    /// Its luminance, linear 0..1 (not yet checked to lie in 0..1).
    pub gray: Image,
    /// Its linear RGB, where asked for and the file is a PNG, GIF, JPEG or TIFF.
    pub rgb: Option<RgbImage>,
    /// What was read and how it was converted, for reports.
    pub info: Value,
    /// Whether the file's own chunk (sRGB, gAMA) says how its codes encode luminance.
    pub states_its_encoding: bool,
    /// The note to say once where the codes were taken as sRGB by the default rule.
    pub assumed_srgb: Option<String>,
    /// How a `.npy` picture's integers were scaled to 0..1.
    pub npy_scale: Option<IntegerScale>,
    /// How finely its values were stored.
    pub quantum: Quantum,
}

/// Reads a mask: a PNG (any non-zero pixel, in any channel, is inside) or an H×W `.npy` of
/// booleans or 0/1 values (1 inside), told apart by their content.
pub fn read_mask(path: &Path, max_pixels: usize) -> Result<Mask> {
    match read_file_bytes(path, max_pixels)? {
        FileBytes::Npy(bytes) => {
            let (w, h, data) = npy_levels(&bytes, path, max_pixels, 1)?;
            Grid::from_vec(w, h, data.into_iter().map(|v| v == 1).collect())
        }
        FileBytes::Raster(bytes) => png::read_mask_from_bytes(&bytes, path, max_pixels),
    }
}

/// Reads a label map: an 8- or 16-bit grayscale PNG of codes 0..N, or an H×W `.npy` of
/// booleans or whole numbers 0..65535, told apart by their content.
pub fn read_labels(path: &Path, max_pixels: usize) -> Result<Labels> {
    match read_file_bytes(path, max_pixels)? {
        FileBytes::Npy(bytes) => {
            let (w, h, data) = npy_levels(&bytes, path, max_pixels, 65535)?;
            Grid::from_vec(w, h, data)
        }
        FileBytes::Raster(bytes) => png::labels_from_bytes(&bytes, path, max_pixels),
    }
}

/// Reads the picture at `path` once: a PNG, GIF, JPEG or TIFF (8 or 16 bits) or an H×W (or
/// H×W×3) `.npy`, told apart by its content, decoded as `encoding` says (see
/// [`super::read_luminance_as`]); with `colour`, a PNG, GIF, JPEG or TIFF's linear RGB too.
pub fn read_picture(
    path: &Path,
    max_pixels: usize,
    encoding: InputEncoding,
    colour: bool,
) -> Result<PictureFile> {
    encoding.validate()?;
    match read_file_bytes(path, max_pixels)? {
        FileBytes::Raster(bytes) => {
            let r = png::raster_picture(&bytes, path, max_pixels, encoding, colour)?;
            let decoding = r.decoding;
            let top = 2f64.powi(i32::from(r.info.bit_depth)) - 1.0;
            Ok(PictureFile {
                quantum: Quantum::codes(top, |v| decoding.linear(v)),
                info: serde_json::to_value(&r.info).unwrap_or_default(),
                gray: r.gray,
                rgb: r.rgb,
                states_its_encoding: r.states_its_encoding,
                assumed_srgb: r.assumed_srgb.then(|| png::assumed_srgb_line(path)),
                npy_scale: None,
            })
        }
        FileBytes::Npy(bytes) => npy_picture(&bytes, path, max_pixels, encoding, colour),
    }
}

/// A `.npy` picture: floats and booleans as they are, uint8 and uint16 codes divided by their
/// largest value and then decoded as `encoding` says (an encoding other than auto or linear is
/// refused for floats), H×W×3 linear RGB made luminance and, with `colour`, kept as RGB too
/// (each channel scaled and decoded as the luminance's are).
fn npy_picture(
    bytes: &[u8],
    path: &Path,
    max_pixels: usize,
    encoding: InputEncoding,
    colour: bool,
) -> Result<PictureFile> {
    let array = npy::read_array_from_bytes(bytes, path, max_pixels)?;
    let dtype = array.dtype.clone();
    // The codes as stored, kept where they are decoded again: per channel for an explicit
    // encoding, or for the colour of an H×W×3 array.
    let colour = colour && matches!(array.shape[..], [_, _, 3]);
    let raw = (encoding.is_explicit() || colour).then(|| array.clone());
    let (mut image, scale, rgb) = npy::luminance_npy(array, path, max_pixels)?;
    let mut notes = Vec::new();
    let format = match &scale {
        Some(scale) => {
            notes.push(scale.note());
            format!("npy {}", scale.dtype)
        }
        None => "npy float".to_string(),
    };
    let mut decoding = Decoding::Linear;
    match (encoding, &scale, &raw) {
        (InputEncoding::Auto | InputEncoding::Linear, _, _) => {}
        (_, None, _) => {
            return Err(Error::format(
                path,
                format!(
                    "a float .npy holds linear values already: input gamma {encoding} applies \
                     only to integer codes (give auto or linear)"
                ),
            ))
        }
        (_, Some(scale), raw) => {
            decoding = encoding.explicit().unwrap_or(Decoding::Linear);
            image = match raw {
                // Each channel decoded, then the luminance of the linear values.
                Some(array) if rgb => {
                    let linear: Vec<f64> = array
                        .data
                        .chunks_exact(3)
                        .map(|p| {
                            crate::grid::luminance(
                                [p[0], p[1], p[2]].map(|c| decoding.linear(c / scale.max)),
                            )
                        })
                        .collect();
                    crate::grid::Grid::from_vec(image.width(), image.height(), linear)?
                }
                _ => image.map(|&v| decoding.linear(v)),
            };
            notes.push(match encoding {
                InputEncoding::Srgb => "decoded as sRGB (--input-gamma srgb)".to_string(),
                _ => format!("decoded as luminance = code^{encoding} (--input-gamma {encoding})"),
            });
        }
    }
    if rgb {
        notes.push(png::LUMINANCE_FORMULA.to_string());
    }
    let mut info = json!({ "format": format });
    if !notes.is_empty() {
        info["conversion"] = notes.join("; ").into();
    }
    let quantum = match &scale {
        Some(scale) => Quantum::codes(scale.max, |v| decoding.linear(v)),
        None if dtype.ends_with("f4") => Quantum::Float(f64::from(f32::EPSILON) / 2.0),
        // float16: 11 bits of precision.
        None if dtype.ends_with("f2") => Quantum::Float(2f64.powi(-11)),
        None => Quantum::default(),
    };
    // Each channel as the luminance was made of it: its integer codes scaled to 0..1, then
    // decoded.
    let top = scale.as_ref().map_or(1.0, |s| s.max);
    let rgb = match raw {
        Some(array) if rgb && colour => Some(crate::grid::Grid::from_vec(
            image.width(),
            image.height(),
            array
                .data
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]].map(|c| decoding.linear(c / top)))
                .collect(),
        )?),
        _ => None,
    };
    Ok(PictureFile {
        gray: image,
        rgb,
        info,
        states_its_encoding: false,
        assumed_srgb: None,
        npy_scale: scale,
        quantum,
    })
}

// A picture's record, found beside it: the part of the render sidecar's reading that needs the
// picture (whether its own chunk states its encoding, and whether the record is of it), here
// with the picture's reading so that the record's reader never opens a picture.
impl RenderSidecar {
    /// Looks beside `image` for its sidecar. A `.json` that is not valid JSON, or a shadelab
    /// sidecar with a malformed field, is an error naming the file; a JSON file of another
    /// program is [`Beside::Foreign`].
    pub fn beside(image: &Path) -> Result<Beside> {
        Self::beside_unchecked(image, || png::states_its_encoding(image))
    }

    /// [`beside`](Self::beside) of `file`, the picture read from `image`: a sidecar is taken
    /// as its record only when it records this picture. One that names another file
    /// (`files.image`) is that file's record, and is taken only for the same picture: the
    /// same size and, when that file is still there, the same values to the precision of
    /// both encodings, each file read as `encoding` says (`a.npy` beside the `a.png` it was
    /// saved with; export writes a shared record only then). A record of another picture is an error naming both files; a
    /// renamed copy (the recorded file gone) keeps its record when the size is the one
    /// recorded.
    pub fn of_picture(
        image: &Path,
        file: &PictureFile,
        encoding: InputEncoding,
        max_pixels: usize,
    ) -> Result<Beside> {
        // Checked with its gamma as recorded: each file is compared as its reader takes it.
        let mut beside = Self::beside_unchecked(image, || false)?;
        if let Beside::Ours(sidecar) = &mut beside {
            sidecar.check_records(image, file, encoding, max_pixels)?;
            if file.states_its_encoding {
                sidecar.decoded_by_file();
            }
        }
        Ok(beside)
    }

    /// Checks that this sidecar, found beside `image`, records `file` (see
    /// [`of_picture`](Self::of_picture)).
    fn check_records(
        &self,
        image: &Path,
        file: &PictureFile,
        encoding: InputEncoding,
        max_pixels: usize,
    ) -> Result<()> {
        let Some(recorded) = &self.image else {
            return Ok(());
        };
        if super::atomic::file_name_of(image) == *recorded {
            return Ok(());
        }
        let other = self.path.with_file_name(recorded);
        let refuse = |why: String| {
            Err(Error::format(
                image,
                format!(
                    "{} beside it is the record of {recorded}, {why}; give this picture without \
                     it (another name or folder), or with its own record",
                    super::atomic::file_name_of(&self.path)
                ),
            ))
        };
        let size = (file.gray.width(), file.gray.height());
        if let Some((height, width)) = self.shape {
            if (width, height) != size {
                return refuse(crate::grid::size_mismatch(
                    "a picture",
                    (width, height),
                    "this one is",
                    size,
                ));
            }
        }
        // A plain name beside it that is still there: the same picture only by its values.
        let plain = Path::new(recorded).file_name().and_then(|n| n.to_str()) == Some(recorded);
        if !plain || !other.is_file() || same_file(&other, image) {
            return Ok(());
        }
        let theirs = read_picture(&other, max_pixels, encoding, false)
            .map_err(|e| Error::format(image, format!("{}: {e}", self.path.display())))?;
        // Each file's values made linear as its reader takes them: the recorded gamma undone
        // for a file that does not state its own encoding (and for neither under an explicit
        // encoding).
        let reader = |states: bool| {
            let mut s = self.clone();
            if states || encoding.is_explicit() {
                s.gamma = None;
            }
            s
        };
        let (mine, other_reader) = (
            reader(file.states_its_encoding),
            reader(theirs.states_its_encoding),
        );
        let (my_quantum, their_quantum) = (
            file.quantum.map(|v| mine.linearise(v)),
            theirs.quantum.map(|v| other_reader.linearise(v)),
        );
        let within = |a: f64, b: f64| {
            let (a, b) = (mine.linearise(a), other_reader.linearise(b));
            let half = |q: &Quantum, v: f64| {
                let (low, high) = q.bin(v);
                let width = high - low;
                if width.is_finite() {
                    width / 2.0
                } else {
                    0.0
                }
            };
            (a - b).abs() <= half(&my_quantum, a) + half(&their_quantum, b) + 1e-12
        };
        let same = theirs.gray.width() == size.0
            && theirs.gray.height() == size.1
            && file
                .gray
                .data()
                .iter()
                .zip(theirs.gray.data())
                .all(|(&a, &b)| within(a, b));
        if same {
            Ok(())
        } else {
            refuse("another picture (its values differ from this one's by more than either file's precision)".into())
        }
    }

    /// [`beside`](Self::beside), where the picture says (when asked) whether its own chunk
    /// states its encoding, without asking whether the sidecar records it.
    fn beside_unchecked(
        image: &Path,
        states_its_encoding: impl FnOnce() -> bool,
    ) -> Result<Beside> {
        let path = sidecar_path(image);
        if path == image || !path.is_file() {
            return Ok(Beside::Nothing);
        }
        let value = super::render_sidecar::read_json(&path)?;
        if value.get("program").and_then(Value::as_str) != Some("shadelab") {
            return Ok(Beside::Foreign(path));
        }
        let mut sidecar = Self::from_value(&path, &value)?;
        // A PNG whose own chunk states its encoding (every stimulus PNG since the gAMA chunk)
        // is decoded by the reader: the recorded gamma is not undone a second time.
        if sidecar.gamma.is_some() && states_its_encoding() {
            sidecar.decoded_by_file();
        }
        Ok(Beside::Ours(Box::new(sidecar)))
    }
}

/// Whether two paths name the same file (compared as written when either cannot be resolved).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    #[test]
    fn a_level_stored_as_8_or_16_bit_codes_or_float32_is_found_again() {
        // 0.1 lies halfway between two codes at 8 bits (25.5) and at 16 bits (6553.5): the
        // render's rounding picks the upper one, and either could have stored it.
        for bits in [8, 16] {
            let top = 2f64.powi(bits) - 1.0;
            let q = Quantum::codes(top, |v| v);
            let stored = (0.1 * top).round() / top;
            let lit = stored + 1.0 / top;
            let image = Grid::from_vec(3, 1, vec![stored, lit, 0.5]).unwrap();
            assert_eq!(
                q.settle(&image, 0.1, None).data(),
                &[0.1, lit, 0.5],
                "{bits} bits"
            );
        }
        let float32 = Quantum::Float(f64::from(f32::EPSILON) / 2.0);
        let stored = f64::from(0.1f32);
        assert_ne!(stored, 0.1);
        let image = Grid::from_vec(2, 1, vec![stored, 0.1 + 1e-6]).unwrap();
        assert_eq!(float32.settle(&image, 0.1, None).data(), &[0.1, 0.1 + 1e-6]);
        // Float64: only the level itself, to its last bits.
        let image = Grid::from_vec(2, 1, vec![0.1, 0.1 + 1e-12]).unwrap();
        assert_eq!(
            Quantum::default().settle(&image, 0.1, None).data(),
            image.data()
        );
        // Codes through a display gamma: the level's code found through the decoding.
        let q = Quantum::codes(255.0, |v| v.powf(2.2));
        let code = (0.1f64.powf(1.0 / 2.2) * 255.0).round();
        let stored = (code / 255.0).powf(2.2);
        let image = Grid::from_vec(1, 1, vec![stored]).unwrap();
        assert_eq!(q.settle(&image, 0.1, None).data(), &[0.1]);
    }

    #[test]
    fn a_record_of_the_unlit_pixels_decides_what_the_codes_cannot() {
        // At 8 bits a lit 0.103 and the shadow's 0.1 share code 26: by the values both are
        // shadow; by the record only the unlit one is, and the lit one keeps its code's value.
        let q = Quantum::codes(255.0, |v| v);
        let code = |v: f64| (v * 255.0).round() / 255.0;
        let (shadow, lit) = (code(0.1), code(0.103));
        assert_eq!(shadow, lit);
        let image = Grid::from_vec(3, 1, vec![shadow, lit, 0.5]).unwrap();
        assert_eq!(q.settle(&image, 0.1, None).data(), &[0.1, 0.1, 0.5]);
        let unlit = Grid::from_vec(3, 1, vec![true, false, false]).unwrap();
        assert_eq!(q.settle(&image, 0.1, Some(&unlit)).data(), &[0.1, lit, 0.5]);
        // An ambient level that is a code: a lit pixel stored at it lies just above it, so
        // that it carries data as the render's own value does.
        let level = 51.0 / 255.0;
        let image = Grid::from_vec(2, 1, vec![level, level]).unwrap();
        let unlit = Grid::from_vec(2, 1, vec![true, false]).unwrap();
        let settled = q.settle(&image, level, Some(&unlit));
        assert_eq!(settled.data()[0], level);
        assert!(settled.data()[1] > level && settled.data()[1] - level < 1e-15);
        // A record of another size is no record of this picture.
        let other = Grid::new(1, 1, true);
        assert_eq!(
            q.settle(&image, level, Some(&other)).data(),
            &[level, level]
        );
        // Which exact values a stored one could stand for: its code's interval.
        assert!(q.could_store(lit, 0.1) && q.could_store(lit, 0.1035));
        assert!(!q.could_store(lit, 0.105));
    }
}

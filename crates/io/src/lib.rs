//! Reading and writing files: PNG (8/16-bit), float `.npy`, JSON sidecars, animated GIF, all written
//! atomically (a temporary name in the same folder, then a rename), so that no half-written file
//! is ever left where the user asked for one; outputs of several files (and folders) are
//! committed as a set ([`OutputSet`]).

#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod colormap;
pub mod display;
pub mod plot;

mod atomic;
mod csv;
mod display_file;
mod encoding;
mod gif;
mod keep;
mod npy;
mod output;
mod output_set;
mod picture;
mod png;
pub mod render_sidecar;

// The floors below, under the module names their code has always used (`crate::grid`, ...).
use shadelab_core::{cancel, error, gradient_space, grid, light};

mod sidecar;
mod temp;

pub use atomic::file_name_of;
pub use atomic::{check_overwrite, write_atomic, write_text, AtomicDir};
pub(crate) use csv::check_csv_finite;
pub use csv::{csv_delimiter, csv_field, csv_record, parse_csv, parse_csv_with};
pub use display_file::{display_from_value, read_display};
pub use encoding::{InputEncoding, INPUT_GAMMA_RANGE};
pub use gif::write_gif;
pub use keep::MANIFEST;
pub use npy::{
    encode_f64, encode_npz, encode_text, npy_file_scale, npy_scale, read_array,
    read_array_from_bytes, read_image, read_image_from_bytes, read_luminance_npy, read_normals,
    write_f32, write_image, write_normals, IntegerScale, NpyArray,
};
pub use output::Output;
pub use output_set::{remove_dead_temporaries, OutputSet};
pub use picture::{read_labels, read_mask, read_picture, PictureFile, Quantum, PICTURE_EXTENSIONS};
pub use png::{
    display_rgba8, read_gray, read_gray_as, read_gray_from_bytes, read_mask_from_bytes, read_rgb,
    read_rgb_as, stimulus_codes, write_display_codes, write_gray, write_gray_fn, write_labels,
    write_mask, write_rgb, write_rgb_fn, write_stimulus, BitDepth, DisplayCodes, GrayInfo,
    PngPicture, LUMINANCE_FORMULA,
};
pub use render_sidecar::{Beside, Declared, RenderSidecar, TrueLight, SILHOUETTE_NOTE};
pub use sidecar::{conventions_json, image_md5, write_json, Stamp, PROGRAM_VERSION};

use crate::error::{Error, Result};
use crate::grid::Image;
use std::path::Path;

/// Reads a picture file as linear luminance by the default rule ([`InputEncoding::Auto`]);
/// see [`read_luminance_as`].
pub fn read_luminance(path: &Path, max_pixels: usize) -> Result<(Image, serde_json::Value)> {
    read_luminance_as(path, max_pixels, InputEncoding::Auto)
}

/// Reads a picture file once ([`read_picture`]) as linear luminance, its codes decoded as
/// `encoding` says: an 8/16-bit PNG, a JPEG or a TIFF ([`read_gray_as`]), or an H×W `.npy`
/// ([`read_luminance_npy`]: uint8 and uint16 divided by their largest value and then decoded
/// as `encoding` says, other integers refused; a float `.npy` is linear already, and an
/// encoding other than auto or linear is refused for it), told apart by their content, with
/// what was read (the picture's [`GrayInfo`], or the `.npy` format and conversion) for
/// reports. A file whose content is none of these is refused, and so is a picture with values
/// outside 0..1 ([`check_luminance_range`]).
pub fn read_luminance_as(
    path: &Path,
    max_pixels: usize,
    encoding: InputEncoding,
) -> Result<(Image, serde_json::Value)> {
    let picture = read_picture(path, max_pixels, encoding, false)?;
    check_luminance_range(picture.gray.data(), path)?;
    Ok((picture.gray, picture.info))
}

/// Fails on the first NaN or infinity of a picture `width` pixels wide with `channels` values
/// per pixel, naming its column and row, and on values outside linear luminance 0..1
/// ([`check_luminance_range`]).
pub fn check_values(values: &[f64], channels: usize, width: usize, what: &str) -> Result<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let pixel = i / channels.max(1);
        let w = width.max(1);
        return Err(Error::invalid(format!(
            "{what}: the image has a non-finite value (NaN or Inf) at column {}, row {}",
            pixel % w,
            pixel / w
        )));
    }
    check_luminance_range(values, std::path::Path::new(what))
}

/// Checks that every value of a picture (gray, or RGB channels in turn) is linear luminance
/// in 0..1, refusing it otherwise with the count of values outside and the range found;
/// `source` names it in the error.
///
/// Values outside are refused rather than clipped: the solver and the models read every value
/// as light reflected by the surface, so clipping would turn highlights into plateaus without
/// saying so; only the user knows how the values were scaled.
///
/// ```
/// use std::path::Path;
/// let mut values = vec![0.5; 8];
/// assert!(shadelab_io::check_luminance_range(&values, Path::new("a.npy")).is_ok());
/// values[1] = 200.0;
/// let e = shadelab_io::check_luminance_range(&values, Path::new("a.npy")).unwrap_err();
/// assert_eq!(
///     e.to_string(),
///     "a.npy: 1 of 8 values are outside 0..1 (from 0.5 to 200): a picture must be linear \
///      luminance 0..1 (divide by its largest possible value)"
/// );
/// ```
pub fn check_luminance_range(values: &[f64], source: &Path) -> Result<()> {
    let outside = values.iter().filter(|v| !(0.0..=1.0).contains(*v)).count();
    if outside == 0 {
        return Ok(());
    }
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Err(Error::format(
        source,
        format!(
            "{outside} of {} values are outside 0..1 (from {lo} to {hi}): a picture must be \
             linear luminance 0..1 (divide by its largest possible value)",
            values.len()
        ),
    ))
}

/// The most bytes read from a text file (a spec, preset, sidecar, report, CSV or other JSON):
/// 64 MiB, far above any file shadelab writes, far below what would exhaust memory.
pub const MAX_TEXT_BYTES: u64 = 64 * 1024 * 1024;

/// Reads a whole text file (a spec, sidecar, report or CSV), with the path in any error;
/// refuses a file longer than [`MAX_TEXT_BYTES`] after reading no more than that.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    read_capped(path, MAX_TEXT_BYTES)
}

/// Reads a file through `Read::take(cap + 1)`: its bytes when it holds at most `cap`, else an
/// error naming the file and the cap, so that a device or a huge file (a link to
/// `/dev/urandom`) costs at most `cap + 1` bytes of memory; a regular file longer than `cap`
/// is refused by its length, before any read.
///
/// ```
/// let dir = std::env::temp_dir().join(format!("shadelab-doc-capped-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// std::fs::write(dir.join("a.json"), b"{}")?;
/// assert_eq!(shadelab_io::read_capped(&dir.join("a.json"), 2)?, b"{}");
/// let e = shadelab_io::read_capped(&dir.join("a.json"), 1).unwrap_err().to_string();
/// assert!(e.ends_with("a.json: is larger than 1 byte, the most shadelab reads from such a file"), "{e}");
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>> {
    use std::io::Read;
    let file = open_file(path)?;
    // A regular file says its length: one that is too long is refused before any read.
    if file.metadata().is_ok_and(|m| m.is_file() && m.len() > cap) {
        return Err(too_long(path, cap));
    }
    let mut bytes = Vec::new();
    file.take(cap.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(too_long(path, cap));
    }
    Ok(bytes)
}

/// Opens a file for reading, refusing a directory, with the path in any error.
pub(crate) fn open_file(path: &Path) -> Result<std::fs::File> {
    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not a file"));
    }
    std::fs::File::open(path).map_err(|e| Error::io(path, e))
}

/// The error for a file longer than the `cap` bytes shadelab reads from it.
pub(crate) fn too_long(path: &Path, cap: u64) -> Error {
    Error::format(
        path,
        format!(
            "is larger than {}, the most shadelab reads from such a file",
            crate::error::byte_size(cap)
        ),
    )
}

/// The lower-case extension of `path` ("" when none).
pub fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// `path` with `suffix` inserted before the extension and the extension replaced by `ext`:
/// `out/a.png` + `_mask`, `png` → `out/a_mask.png`. The stem is kept as the OS gave it, so a
/// name that is not UTF-8 keeps its siblings beside it.
pub fn sibling(path: &Path, suffix: &str, ext: &str) -> std::path::PathBuf {
    let mut name = path
        .file_stem()
        .map(|s| s.to_os_string())
        .unwrap_or_default();
    name.push(suffix);
    name.push(".");
    name.push(ext);
    path.with_file_name(name)
}

//! Reading and writing files: PNG (8/16-bit), float `.npy`, JSON sidecars, animated GIF, all written
//! atomically (a temporary name in the same folder, then a rename), so that no half-written file
//! is ever left where the user asked for one; outputs of several files (and folders) are
//! committed as a set ([`OutputSet`]).

mod atomic;
mod csv;
mod gif;
mod npy;
mod output_set;
mod png;
pub mod render_sidecar;
mod sidecar;

pub use atomic::{check_overwrite, write_atomic, write_text, AtomicDir};
pub use csv::{csv_field, parse_csv};
pub use gif::write_gif;
pub use npy::{
    encode_f64, encode_npz, encode_text, read_array, read_array_from_bytes, read_image,
    read_image_from_bytes, read_normals, write_f32, write_image, write_normals, NpyArray,
};
pub use output_set::{remove_dead_temporaries, OutputSet};
pub use png::{
    display_rgba8, read_gray, read_gray_from_bytes, read_labels, read_mask, read_mask_from_bytes,
    read_rgb, write_gray, write_labels, write_mask, write_rgb, BitDepth, GrayInfo,
    LUMINANCE_FORMULA,
};
pub use render_sidecar::{Beside, Declared, RenderSidecar, TrueLight};
pub use sidecar::{conventions_json, image_md5, write_json, PROGRAM_VERSION};

use crate::error::{Error, Result};
use crate::grid::Image;
use std::path::Path;

/// Reads a picture file as linear luminance: an 8/16-bit PNG ([`read_gray`]) or a float H×W
/// `.npy` ([`read_image`]), with what was read (the PNG's [`GrayInfo`], or the `.npy` format)
/// for reports. Any other extension is refused.
pub fn read_luminance(path: &Path, max_pixels: usize) -> Result<(Image, serde_json::Value)> {
    match extension(path).as_str() {
        "png" => {
            let (image, info) = read_gray(path, max_pixels)?;
            Ok((image, serde_json::to_value(info).unwrap_or_default()))
        }
        "npy" => Ok((
            read_image(path, max_pixels)?,
            serde_json::json!({ "format": "npy float" }),
        )),
        other => Err(Error::invalid(format!(
            "{}: the image must be a .png or .npy file (got '.{other}')",
            path.display()
        ))),
    }
}

/// Reads a whole file, with the path in any error.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not a file"));
    }
    std::fs::read(path).map_err(|e| Error::io(path, e))
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

//! JSON sidecars and reports: the program, its version, the conventions, and a checksum.

use crate::error::{Error, Result};
use crate::grid::Image;
use md5::{Digest, Md5};
use serde_json::{json, Value};
use std::path::Path;

/// The program version recorded in every sidecar.
pub const PROGRAM_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Who wrote a report, and as which command: the first three keys of a command's JSON report
/// (flattened into it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Stamp {
    /// Always `shadelab`.
    pub program: &'static str,
    /// The version that wrote it.
    pub version: &'static str,
    /// The command, e.g. `analyze outline`.
    pub command: &'static str,
}

impl Stamp {
    /// The stamp of `command` in this version.
    pub fn of(command: &'static str) -> Stamp {
        Stamp {
            program: "shadelab",
            version: PROGRAM_VERSION,
            command,
        }
    }
}

/// The conventions every output follows, as recorded in sidecars (see docs/conventions.md).
pub fn conventions_json() -> Value {
    json!({
        "axes": "x = image right, y = image up, z = toward the viewer; pixel row 0 is the top row",
        "gradient": "p = -dz/dx, q = -dz/dy; n = (p, q, 1)/sqrt(1+p^2+q^2)",
        "stereographic": "f = 2 n_x/(1+n_z), g = 2 n_y/(1+n_z)",
        "light": "unit vector toward the light; tilt 0 = from above, +90 = from the left; slant from the view direction",
        "luminance": "linear 0..1 unless a gamma is recorded",
    })
}

/// The md5 of an image as stimupy computes it: float64 values rounded to 8 decimals, in
/// row-major order, as little-endian bytes.
pub fn image_md5(image: &Image) -> String {
    let mut hasher = Md5::new();
    for v in image.data() {
        let r = (v * 1e8).round_ties_even() / 1e8;
        // -0.0 and 0.0 round to the same value; hash them the same.
        let r = if r == 0.0 { 0.0 } else { r };
        hasher.update(r.to_le_bytes());
    }
    hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Writes `value` as pretty JSON, atomically.
pub fn write_json(path: &Path, value: &Value) -> Result<()> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Compute(format!("cannot serialise JSON: {e}")))?;
    super::write_atomic(path, |out| {
        out.write_all(text.as_bytes())
            .and_then(|_| out.write_all(b"\n"))
            .map_err(|e| Error::io(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    #[test]
    fn md5_depends_on_values_to_eight_decimals() {
        let a = Grid::new(3, 2, 0.5);
        let mut b = a.clone();
        *b.get_mut(0, 0) = 0.5 + 1e-10;
        assert_eq!(image_md5(&a), image_md5(&b));
        *b.get_mut(0, 0) = 0.5 + 1e-7;
        assert_ne!(image_md5(&a), image_md5(&b));
        assert_eq!(image_md5(&a).len(), 32);
    }
}

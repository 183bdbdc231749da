//! MATLAB level-5 MAT-files (`.mat`), written by hand: one real double array, the format
//! Psychtoolbox scripts `load` directly.
//!
//! Layout (MathWorks, "MAT-File Format", level 5): a 128-byte header (116 bytes of text, 8
//! bytes of subsystem offset, version 0x0100, endian indicator "IM" for little-endian), then
//! one `miMATRIX` element holding array flags (class double), dimensions, the array name and
//! the real part as `miDOUBLE` in column-major order. Every sub-element is padded to 8 bytes.
//! No timestamp is written, so equal inputs give equal files.

use crate::error::{Error, Result};

const MI_INT8: u32 = 1;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MX_DOUBLE_CLASS: u32 = 6;

/// The header text (padded with spaces to 116 bytes).
const HEADER_TEXT: &str = concat!(
    "MATLAB 5.0 MAT-file, Platform: any, written by shadelab ",
    env!("CARGO_PKG_VERSION")
);

fn pad8(n: usize) -> usize {
    n.div_ceil(8) * 8
}

fn element(out: &mut Vec<u8>, kind: u32, payload: &[u8]) {
    out.extend_from_slice(&kind.to_le_bytes());
    out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    out.extend_from_slice(payload);
    out.resize(out.len() + pad8(payload.len()) - payload.len(), 0);
}

/// Encodes `data` (column-major, as MATLAB stores arrays) of dimensions `dims` (rows first) as
/// a MAT-file holding one double array called `name`.
pub fn encode(name: &str, dims: &[usize], data: &[f64]) -> Result<Vec<u8>> {
    let valid_name = name.len() <= 63
        && name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !valid_name {
        return Err(Error::invalid(format!(
            "'{name}' is not a MATLAB variable name"
        )));
    }
    if dims.len() < 2 || dims.iter().product::<usize>() != data.len() {
        return Err(Error::invalid(format!(
            "MAT-file array of {} values does not match dimensions {dims:?}",
            data.len()
        )));
    }
    let bytes = data
        .len()
        .checked_mul(8)
        .filter(|&b| b < (u32::MAX as usize) - 4096);
    let Some(_) = bytes else {
        return Err(Error::invalid(
            "array too large for a level-5 MAT-file (4 GiB per variable)",
        ));
    };
    let mut body = Vec::with_capacity(64 + data.len() * 8);
    let mut flags = Vec::with_capacity(8);
    flags.extend_from_slice(&MX_DOUBLE_CLASS.to_le_bytes());
    flags.extend_from_slice(&0u32.to_le_bytes());
    element(&mut body, MI_UINT32, &flags);
    let mut dim_bytes = Vec::with_capacity(dims.len() * 4);
    for &d in dims {
        let d = i32::try_from(d).map_err(|_| Error::invalid("MAT-file dimension too large"))?;
        dim_bytes.extend_from_slice(&d.to_le_bytes());
    }
    element(&mut body, MI_INT32, &dim_bytes);
    element(&mut body, MI_INT8, name.as_bytes());
    let mut real = Vec::with_capacity(data.len() * 8);
    for v in data {
        real.extend_from_slice(&v.to_le_bytes());
    }
    element(&mut body, MI_DOUBLE, &real);

    let mut out = Vec::with_capacity(128 + 8 + body.len());
    let mut text = HEADER_TEXT.as_bytes().to_vec();
    text.resize(116, b' ');
    out.extend_from_slice(&text);
    out.extend_from_slice(&[0u8; 8]);
    out.extend_from_slice(&0x0100u16.to_le_bytes());
    out.extend_from_slice(b"IM");
    element(&mut out, MI_MATRIX, &body);
    Ok(out)
}

/// Encodes a row-major image (`height` rows of `width` values, `channels` interleaved per
/// pixel) as an H × W (× C) MATLAB array.
pub fn encode_image(
    name: &str,
    width: usize,
    height: usize,
    channels: usize,
    row_major: &[f64],
) -> Result<Vec<u8>> {
    let mut col_major = vec![0.0; row_major.len()];
    for r in 0..height {
        for c in 0..width {
            for k in 0..channels {
                col_major[r + height * (c + width * k)] = row_major[(r * width + c) * channels + k];
            }
        }
    }
    let dims: Vec<usize> = if channels == 1 {
        vec![height, width]
    } else {
        vec![height, width, channels]
    };
    encode(name, &dims, &col_major)
}

/// A MAT-file array read back: its name, dimensions and column-major values.
#[derive(Debug, Clone, PartialEq)]
pub struct MatArray {
    /// The variable name.
    pub name: String,
    /// The dimensions, rows first.
    pub dims: Vec<usize>,
    /// The values in column-major order.
    pub data: Vec<f64>,
}

/// Reads the first variable of a level-5 MAT-file written by [`encode`] (little-endian,
/// uncompressed, real double); anything else is reported as unsupported.
pub fn decode(bytes: &[u8]) -> Result<MatArray> {
    let bad = |why: &str| Error::invalid(format!("not a MAT-file shadelab can read: {why}"));
    if bytes.len() < 136 || &bytes[126..128] != b"IM" || bytes[124..126] != [0x00, 0x01] {
        return Err(bad("no level-5 little-endian header"));
    }
    let u32_at = |at: usize| -> Result<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| bad("truncated"))
    };
    if u32_at(128)? != MI_MATRIX {
        return Err(bad("first element is not a matrix"));
    }
    let end = 136 + u32_at(132)? as usize;
    if end > bytes.len() {
        return Err(bad("truncated"));
    }
    let mut at = 136;
    let mut sub = Vec::new();
    while at + 8 <= end {
        let (kind, size) = (u32_at(at)?, u32_at(at + 4)? as usize);
        let payload = bytes
            .get(at + 8..at + 8 + size)
            .ok_or_else(|| bad("truncated"))?;
        sub.push((kind, payload));
        at += 8 + pad8(size);
    }
    let [(MI_UINT32, flags), (MI_INT32, dims), (MI_INT8, name), (MI_DOUBLE, real)] = sub[..] else {
        return Err(bad("not a real double array"));
    };
    if flags.first() != Some(&(MX_DOUBLE_CLASS as u8)) {
        return Err(bad("not of class double"));
    }
    let dims: Vec<usize> = dims
        .chunks_exact(4)
        .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]).max(0) as usize)
        .collect();
    let data: Vec<f64> = real
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
        .collect();
    if dims.iter().product::<usize>() != data.len() {
        return Err(bad("dimensions do not match the data"));
    }
    Ok(MatArray {
        name: String::from_utf8_lossy(name).into_owned(),
        dims,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_elements_follow_the_format() {
        let bytes = encode_image("stimulus", 3, 2, 1, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
        assert!(bytes.starts_with(b"MATLAB 5.0 MAT-file"));
        assert_eq!(&bytes[124..128], &[0x00, 0x01, b'I', b'M']);
        // miMATRIX of 16 (flags) + 16 (dims) + 16 (name, 8 bytes) + 8 + 48 (six doubles).
        assert_eq!(u32::from_le_bytes(bytes[128..132].try_into().unwrap()), 14);
        assert_eq!(u32::from_le_bytes(bytes[132..136].try_into().unwrap()), 104);
        assert_eq!(bytes.len(), 136 + 104);
        let a = decode(&bytes).unwrap();
        assert_eq!(a.name, "stimulus");
        assert_eq!(a.dims, [2, 3]);
        // Column-major: the first column (1, 4) comes first.
        assert_eq!(a.data, [1.0, 4.0, 2.0, 5.0, 3.0, 6.0]);
    }

    #[test]
    fn colour_images_are_h_w_3() {
        // One row of two pixels: red-ish and blue-ish.
        let px = [0.9, 0.1, 0.2, 0.3, 0.4, 0.8];
        let a = decode(&encode_image("img", 2, 1, 3, &px).unwrap()).unwrap();
        assert_eq!(a.dims, [1, 2, 3]);
        // MATLAB img(1, 2, 3) = index (0) + 1·(1) + 2·(2) = 5 → 0.8.
        assert_eq!(a.data[5], 0.8);
        assert_eq!(a.data, [0.9, 0.3, 0.1, 0.4, 0.2, 0.8]);
    }

    #[test]
    fn bad_names_and_shapes_are_refused() {
        assert!(encode("2x", &[1, 1], &[0.0]).is_err());
        assert!(encode("a b", &[1, 1], &[0.0]).is_err());
        assert!(encode("x", &[2, 2], &[0.0]).is_err());
        assert!(decode(b"not a mat file").is_err());
    }
}

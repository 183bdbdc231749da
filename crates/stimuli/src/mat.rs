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
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MX_CELL_CLASS: u32 = 1;
const MX_CHAR_CLASS: u32 = 4;
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

/// A MATLAB value of a MAT-file: what [`encode_vars`] writes and [`decode_all`] reads.
#[derive(Debug, Clone, PartialEq)]
pub enum MatValue {
    /// A real double array: dimensions (rows first) and values in column-major order.
    Double {
        /// The dimensions, rows first (at least two).
        dims: Vec<usize>,
        /// The values, column-major.
        data: Vec<f64>,
    },
    /// A 1 × n char array (a MATLAB string; `scipy.io.loadmat` gives a str).
    Char(String),
    /// A 1 × n cell array of char arrays (`loadmat` gives an object array of str).
    Cell(Vec<String>),
}

fn check_name(name: &str) -> Result<()> {
    let valid = name.len() <= 63
        && name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if valid {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "'{name}' is not a MATLAB variable name"
        )))
    }
}

/// The `miMATRIX` body (flags, dimensions, name, data) of one value.
fn matrix_body(name: &str, value: &MatValue) -> Result<Vec<u8>> {
    let (class, dims): (u32, Vec<usize>) = match value {
        MatValue::Double { dims, data } => {
            if dims.len() < 2 || dims.iter().product::<usize>() != data.len() {
                return Err(Error::invalid(format!(
                    "MAT-file array of {} values does not match dimensions {dims:?}",
                    data.len()
                )));
            }
            if data.len().saturating_mul(8) >= (u32::MAX as usize) - 4096 {
                return Err(Error::invalid(
                    "array too large for a level-5 MAT-file (4 GiB per variable)",
                ));
            }
            (MX_DOUBLE_CLASS, dims.clone())
        }
        MatValue::Char(text) => (MX_CHAR_CLASS, vec![1, text.encode_utf16().count()]),
        MatValue::Cell(items) => (MX_CELL_CLASS, vec![1, items.len()]),
    };
    let mut body = Vec::new();
    let mut flags = Vec::with_capacity(8);
    flags.extend_from_slice(&class.to_le_bytes());
    flags.extend_from_slice(&0u32.to_le_bytes());
    element(&mut body, MI_UINT32, &flags);
    let mut dim_bytes = Vec::with_capacity(dims.len() * 4);
    for &d in &dims {
        let d = i32::try_from(d).map_err(|_| Error::invalid("MAT-file dimension too large"))?;
        dim_bytes.extend_from_slice(&d.to_le_bytes());
    }
    element(&mut body, MI_INT32, &dim_bytes);
    element(&mut body, MI_INT8, name.as_bytes());
    match value {
        MatValue::Double { data, .. } => {
            let real: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
            element(&mut body, MI_DOUBLE, &real);
        }
        MatValue::Char(text) => {
            let units: Vec<u8> = text.encode_utf16().flat_map(|u| u.to_le_bytes()).collect();
            element(&mut body, MI_UINT16, &units);
        }
        MatValue::Cell(items) => {
            for item in items {
                let cell = matrix_body("", &MatValue::Char(item.clone()))?;
                element(&mut body, MI_MATRIX, &cell);
            }
        }
    }
    Ok(body)
}

/// Encodes named values as one MAT-file, in the order given (`scipy.io.loadmat`, MATLAB's and
/// Octave's `load` read them all).
///
/// ```
/// use shadelab_stimuli::mat::{decode_all, encode_vars, MatValue};
/// let vars = vec![
///     ("ppd".to_string(), MatValue::Double { dims: vec![1, 1], data: vec![32.0] }),
///     ("stimulus".to_string(), MatValue::Char("checkerboard".into())),
/// ];
/// let bytes = encode_vars(&vars).unwrap();
/// assert_eq!(decode_all(&bytes).unwrap(), vars);
/// ```
pub fn encode_vars(vars: &[(String, MatValue)]) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut text = HEADER_TEXT.as_bytes().to_vec();
    text.resize(116, b' ');
    out.extend_from_slice(&text);
    out.extend_from_slice(&[0u8; 8]);
    out.extend_from_slice(&0x0100u16.to_le_bytes());
    out.extend_from_slice(b"IM");
    let mut seen = std::collections::BTreeSet::new();
    for (name, value) in vars {
        check_name(name)?;
        if !seen.insert(name.as_str()) {
            return Err(Error::invalid(format!(
                "the MAT-file variable '{name}' is given twice"
            )));
        }
        element(&mut out, MI_MATRIX, &matrix_body(name, value)?);
    }
    Ok(out)
}

/// Encodes `data` (column-major, as MATLAB stores arrays) of dimensions `dims` (rows first) as
/// a MAT-file holding one double array called `name`.
pub fn encode(name: &str, dims: &[usize], data: &[f64]) -> Result<Vec<u8>> {
    encode_vars(&[(
        name.to_string(),
        MatValue::Double {
            dims: dims.to_vec(),
            data: data.to_vec(),
        },
    )])
}

/// Reorders C-order (row-major, last axis fastest) values of dimensions `dims` into MATLAB's
/// column-major order (first axis fastest).
pub fn to_column_major(dims: &[usize], row_major: &[f64]) -> Vec<f64> {
    let n = row_major.len();
    let mut out = vec![0.0; n];
    // Strides of the C order, per axis.
    let mut strides = vec![1usize; dims.len()];
    for k in (0..dims.len().saturating_sub(1)).rev() {
        strides[k] = strides[k + 1] * dims[k + 1];
    }
    let mut index = vec![0usize; dims.len()];
    for slot in out.iter_mut() {
        let at: usize = index.iter().zip(&strides).map(|(i, s)| i * s).sum();
        *slot = row_major.get(at).copied().unwrap_or(0.0);
        for (i, &d) in index.iter_mut().zip(dims) {
            *i += 1;
            if *i < d {
                break;
            }
            *i = 0;
        }
    }
    out
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
    let dims: Vec<usize> = if channels == 1 {
        vec![height, width]
    } else {
        vec![height, width, channels]
    };
    if dims.iter().product::<usize>() != row_major.len() {
        return Err(Error::invalid(format!(
            "MAT-file image of {} values does not match {height} x {width} x {channels}",
            row_major.len()
        )));
    }
    encode(name, &dims, &to_column_major(&dims, row_major))
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
    match decode_all(bytes)?.into_iter().next() {
        Some((name, MatValue::Double { dims, data })) => Ok(MatArray { name, dims, data }),
        _ => Err(Error::invalid(
            "not a MAT-file shadelab can read: the first variable is not a real double array",
        )),
    }
}

/// Reads every variable of a level-5 MAT-file of the kinds [`encode_vars`] writes (little-
/// endian, uncompressed; real double, char and cell-of-char arrays); anything else is reported
/// as unsupported.
pub fn decode_all(bytes: &[u8]) -> Result<Vec<(String, MatValue)>> {
    if bytes.len() < 128 || &bytes[126..128] != b"IM" || bytes[124..126] != [0x00, 0x01] {
        return Err(bad("no level-5 little-endian header"));
    }
    let mut vars = Vec::new();
    for (kind, payload) in elements(bytes, 128, bytes.len())? {
        if kind != MI_MATRIX {
            return Err(bad("a top-level element is not a matrix"));
        }
        vars.push(matrix(payload)?);
    }
    Ok(vars)
}

fn bad(why: &str) -> Error {
    Error::invalid(format!("not a MAT-file shadelab can read: {why}"))
}

/// The (type, payload) elements of `bytes[start..end]`, each padded to 8 bytes.
fn elements(bytes: &[u8], start: usize, end: usize) -> Result<Vec<(u32, &[u8])>> {
    let u32_at = |at: usize| -> Result<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| bad("truncated"))
    };
    let mut at = start;
    let mut out = Vec::new();
    while at + 8 <= end {
        let (kind, size) = (u32_at(at)?, u32_at(at + 4)? as usize);
        let payload = bytes
            .get(at + 8..at + 8 + size)
            .filter(|_| at + 8 + size <= end)
            .ok_or_else(|| bad("truncated"))?;
        out.push((kind, payload));
        at += 8 + pad8(size);
    }
    Ok(out)
}

/// One `miMATRIX` payload: its name and value.
fn matrix(payload: &[u8]) -> Result<(String, MatValue)> {
    let sub = elements(payload, 0, payload.len())?;
    let [(MI_UINT32, flags), (MI_INT32, dims), (MI_INT8, name), rest @ ..] = &sub[..] else {
        return Err(bad("a matrix without flags, dimensions and name"));
    };
    let dims: Vec<usize> = dims
        .chunks_exact(4)
        .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]).max(0) as usize)
        .collect();
    let name = String::from_utf8_lossy(name).into_owned();
    let count = dims.iter().product::<usize>();
    let value = match (flags.first().map(|&c| c as u32), rest) {
        (Some(MX_DOUBLE_CLASS), [(MI_DOUBLE, real)]) => {
            let data: Vec<f64> = real
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
                .collect();
            if data.len() != count {
                return Err(bad("dimensions do not match the data"));
            }
            MatValue::Double { dims, data }
        }
        (Some(MX_CHAR_CLASS), [(MI_UINT16, units)]) => {
            let units: Vec<u16> = units
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
                .collect();
            MatValue::Char(String::from_utf16_lossy(&units))
        }
        (Some(MX_CELL_CLASS), cells) if cells.len() == count => {
            let mut items = Vec::with_capacity(count);
            for (kind, cell) in cells {
                match (*kind, matrix(cell)?) {
                    (MI_MATRIX, (_, MatValue::Char(text))) => items.push(text),
                    _ => return Err(bad("a cell that is not a char array")),
                }
            }
            MatValue::Cell(items)
        }
        _ => return Err(bad("not a real double, char or cell array")),
    };
    Ok((name, value))
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

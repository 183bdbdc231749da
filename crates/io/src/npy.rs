//! NumPy `.npy` arrays: read any real dtype (converted to f64), write little-endian float32.

use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{check_size, Grid, Image};
use nalgebra::Vector3;
use std::path::Path;

/// An n-dimensional array read from `.npy`, in C (row-major) order.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    /// The shape, outermost axis first (H, W[, C] for images).
    pub shape: Vec<usize>,
    /// The values in C order, as stored (integers keep their values; see [`npy_scale`] for
    /// how a picture's integers become luminance).
    pub data: Vec<f64>,
    /// The NumPy dtype as the header gives it (`<f8`, `|u1`, `<i8`, `|b1`, …).
    pub dtype: String,
}

/// How the integers of a `.npy` picture become luminance 0..1: as the codes of a PNG of the
/// same bit depth, uint8 divided by 255 and uint16 by 65535 (docs/conventions.md). Other
/// integer types (signed, 32 or 64 bits) are refused as pictures ([`npy_scale`]): no bit depth
/// says what their largest value means.
#[derive(Debug, Clone, PartialEq)]
pub struct IntegerScale {
    /// The NumPy type name (`uint8` or `uint16`).
    pub dtype: String,
    /// The divisor: the type's largest value.
    pub max: f64,
}

impl IntegerScale {
    /// One line for a log and a report: what was done to the values.
    pub fn note(&self) -> String {
        format!(
            "{} values divided by {} to give luminance 0..1, as a PNG's codes",
            self.dtype, self.max
        )
    }
}

/// The scale of a NumPy dtype (`|u1`, `<u2`, …) read as a picture: `Ok(None)` for floats and
/// booleans (read as they are), the [`IntegerScale`] of uint8 and uint16, and an error saying
/// why for every other integer type.
///
/// ```
/// let scale = shadelab_io::npy_scale("|u1").unwrap().unwrap();
/// assert_eq!((scale.dtype.as_str(), scale.max), ("uint8", 255.0));
/// assert_eq!(shadelab_io::npy_scale("<u2").unwrap().unwrap().max, 65535.0);
/// assert_eq!(shadelab_io::npy_scale("<f4").unwrap(), None);
/// assert_eq!(shadelab_io::npy_scale("|b1").unwrap(), None);
/// assert!(shadelab_io::npy_scale("<i8").unwrap_err().starts_with("int64 pictures are refused"));
/// ```
pub fn npy_scale(descr: &str) -> std::result::Result<Option<IntegerScale>, String> {
    let rest = descr.trim_start_matches(['<', '>', '|', '=']);
    let Some((kind, bytes)) = rest.split_at_checked(1) else {
        return Ok(None);
    };
    let bits = bytes.parse::<u32>().unwrap_or(0) * 8;
    let name = match kind {
        "u" => format!("uint{bits}"),
        "i" => format!("int{bits}"),
        _ => return Ok(None),
    };
    match (kind, bits) {
        ("u", 8 | 16) => Ok(Some(IntegerScale {
            max: 2f64.powi(bits as i32) - 1.0,
            dtype: name,
        })),
        _ => Err(format!(
            "{name} pictures are refused: only uint8 and uint16 integers have a largest value \
             that means white (save 8- or 16-bit codes as uint8 or uint16, or luminance 0..1 \
             as float)"
        )),
    }
}

/// Reads a `.npy` file of any float, integer or boolean dtype, either memory order, refusing
/// arrays of more than `max_elements` values and files shorter than their header declares.
/// The header is read and checked first: no more of the file is read than the values it
/// declares (a file that is not a `.npy` costs 12 bytes).
pub fn read_array(path: &Path, max_elements: usize) -> Result<NpyArray> {
    read_array_from_bytes(&read_npy_file(path, max_elements)?, path, max_elements)
}

/// The bytes of a `.npy` file that its checked header declares: the preamble and header are
/// read and checked first, then at most 8 bytes for each value the header declares.
fn read_npy_file(path: &Path, max_elements: usize) -> Result<Vec<u8>> {
    read_npy_rest(Vec::new(), super::open_file(path)?, path, max_elements)
}

/// The bytes of a `.npy` file whose first bytes `head` were already read from `file` (opened
/// once, so that a pipe works): its header checked first, then at most 8 bytes for each value
/// it declares.
pub(crate) fn read_npy_rest(
    head: Vec<u8>,
    file: impl std::io::Read,
    path: &Path,
    max_elements: usize,
) -> Result<Vec<u8>> {
    use std::io::Read;
    let (mut bytes, count, file) = read_npy_header(head, file, path, max_elements)?;
    file.take(count.saturating_mul(MAX_ITEM_BYTES as u64))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    Ok(bytes)
}

/// The preamble and header of a `.npy` file (`head` already read from `file`, which is read
/// on), checked, with the number of values they declare and the file positioned at the first
/// value.
fn read_npy_header<R: std::io::Read>(
    mut bytes: Vec<u8>,
    mut file: R,
    path: &Path,
    max_elements: usize,
) -> Result<(Vec<u8>, u64, R)> {
    use std::io::Read;
    let mut read = |bytes: &mut Vec<u8>, n: u64| {
        (&mut file)
            .take(n)
            .read_to_end(bytes)
            .map_err(|e| Error::io(path, e))
    };
    let have = bytes.len() as u64;
    read(&mut bytes, 12u64.saturating_sub(have))?;
    let (start, length) = preamble(&bytes).map_err(|m| Error::format(path, m))?;
    // At most one byte past the longest header accepted: enough to tell a file that ends
    // inside its header (truncated) from one whose header is too long.
    let wanted = start + length.min(MAX_HEADER_BYTES + 1);
    let missing = wanted.saturating_sub(bytes.len());
    read(&mut bytes, missing as u64)?;
    if bytes.len() < wanted {
        return Err(Error::format(path, "the .npy header is truncated"));
    }
    if length > MAX_HEADER_BYTES {
        return Err(Error::format(path, header_too_long(length)));
    }
    let count = precheck_header(&bytes, max_elements).map_err(|m| Error::format(path, m))?;
    Ok((bytes, count, file))
}

/// The integer scale ([`npy_scale`]) of the `.npy` picture at `path`, from its header alone:
/// `None` for a float or boolean dtype, and for a file whose header cannot be read (reading
/// the picture says why).
pub fn npy_file_scale(path: &Path) -> Option<IntegerScale> {
    // Only a file that can be read again: a pipe is read once, by the picture's reader.
    if !path.is_file() {
        return None;
    }
    let file = super::open_file(path).ok()?;
    let (bytes, _, _) = read_npy_header(Vec::new(), file, path, usize::MAX).ok()?;
    let file = npyz::NpyFile::new(&bytes[..]).ok()?;
    match file.dtype() {
        npyz::DType::Plain(t) => npy_scale(&t.to_string()).ok().flatten(),
        _ => None,
    }
}

/// The largest value read: 8 bytes (float64, int64, uint64).
const MAX_ITEM_BYTES: usize = 8;

/// [`read_array`] of `.npy` bytes held in memory; `path` names them in errors.
pub fn read_array_from_bytes(bytes: &[u8], path: &Path, max_elements: usize) -> Result<NpyArray> {
    precheck_header(bytes, max_elements).map_err(|m| Error::format(path, m))?;
    let file = npyz::NpyFile::new(bytes)
        .map_err(|e| Error::format(path, format!("not a .npy file ({e})")))?;
    let shape: Vec<usize> = file.shape().iter().map(|&d| d as usize).collect();
    let count = shape
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .filter(|&n| n <= max_elements)
        .ok_or_else(|| {
            Error::format(
                path,
                format!("array shape {shape:?} exceeds the limit of {max_elements} values"),
            )
        })?;
    // The type string alone (`<f8`), not the header's quoted literal.
    let dtype = match file.dtype() {
        npyz::DType::Plain(t) => t.to_string(),
        other => other.descr(),
    };
    let item = match file.dtype() {
        npyz::DType::Plain(t) => t.num_bytes().unwrap_or(0),
        _ => 0,
    };
    if item == 0 || item > MAX_ITEM_BYTES {
        return Err(Error::format(path, format!("unsupported dtype {dtype}")));
    }
    if bytes.len() < count.saturating_mul(item) {
        return Err(Error::format(
            path,
            "file is truncated (shorter than its header declares)",
        ));
    }
    let fortran = matches!(file.order(), npyz::Order::Fortran);
    let io = |e: std::io::Error| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            Error::format(path, "file is truncated (shorter than its header declares)")
        } else {
            Error::format(path, format!("cannot read values ({e})"))
        }
    };
    // Each real type npyz knows, tried in turn: the first whose dtype matches reads the values.
    macro_rules! read_as {
        ($file:ident; $($t:ty),*) => {'read: {
            $(
                let $file = match $file.try_data::<$t>() {
                    Ok(r) => {
                        break 'read r
                            .map(|v| v.map(|v| v as f64))
                            .collect::<std::io::Result<Vec<f64>>>()
                            .map_err(io)?
                    }
                    Err(file) => file,
                };
            )*
            match $file.try_data::<bool>() {
                Ok(r) => r
                    .map(|v| v.map(|b| if b { 1.0 } else { 0.0 }))
                    .collect::<std::io::Result<Vec<f64>>>()
                    .map_err(io)?,
                Err(file) => {
                    return Err(Error::format(
                        path,
                        format!(
                            "unsupported dtype {} (need a real number type)",
                            file.dtype().descr()
                        ),
                    ))
                }
            }
        }};
    }
    let data: Vec<f64> = read_as!(file; f64, f32, i64, u64, i32, u32, i16, u16, i8, u8);
    if data.len() != count {
        return Err(Error::format(
            path,
            "file is truncated (shorter than its header declares)",
        ));
    }
    let data = if fortran && shape.len() > 1 {
        fortran_to_c(&shape, &data)
    } else {
        data
    };
    Ok(NpyArray { shape, data, dtype })
}

/// The longest `.npy` header accepted (NumPy's own reader refuses longer ones by default).
const MAX_HEADER_BYTES: usize = 10_000;

/// The deepest bracket nesting accepted in a `.npy` header.
const MAX_HEADER_NESTING: usize = 4;

/// Where the `.npy` header starts and how long it says it is, from the magic and version.
fn preamble(bytes: &[u8]) -> std::result::Result<(usize, usize), String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy file (no \\x93NUMPY magic)".into());
    }
    match bytes[6] {
        1 => Ok((10, u16::from_le_bytes([bytes[8], bytes[9]]) as usize)),
        2 | 3 if bytes.len() >= 12 => Ok((
            12,
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
        )),
        2 | 3 => Err("the .npy header is truncated".into()),
        v => Err(format!("unsupported .npy format version {v}")),
    }
}

fn header_too_long(length: usize) -> String {
    format!(
        "the .npy header is {length} bytes long (more than {MAX_HEADER_BYTES}: not an array \
         header)"
    )
}

/// Checks the preamble and the header's shape by hand before npyz parses them, so that a
/// corrupt or hostile header (a shape whose product overflows, a header longer than the file)
/// is an error rather than an overflow or a huge allocation; gives the number of values the
/// header declares.
fn precheck_header(bytes: &[u8], max_elements: usize) -> std::result::Result<u64, String> {
    let (start, length) = preamble(bytes)?;
    // A header longer than the file is reported as truncated (the more precise of the two).
    let text = bytes
        .get(start..start.saturating_add(length))
        .ok_or("the .npy header is truncated")?;
    if length > MAX_HEADER_BYTES {
        return Err(header_too_long(length));
    }
    // npyz parses the header with a backtracking grammar whose time grows exponentially with
    // the nesting of brackets; a plain array's header nests two deep ({'shape': (H, W)}).
    let mut depth = 0usize;
    for &b in text {
        match b {
            b'(' | b'[' | b'{' => {
                depth += 1;
                if depth > MAX_HEADER_NESTING {
                    return Err(format!(
                        "the .npy header nests brackets more than {MAX_HEADER_NESTING} deep \
                         (not a plain array header)"
                    ));
                }
            }
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    let text = String::from_utf8_lossy(text);
    if text.matches("shape").count() != 1 {
        return Err("the .npy header does not name one shape".into());
    }
    let tuple = text
        .split("shape")
        .nth(1)
        .and_then(|after| after.split_once('('))
        .and_then(|(_, rest)| rest.split_once(')'))
        .map(|(inside, _)| inside)
        .ok_or("the .npy header's shape is not a tuple")?;
    let dims: Vec<u64> = tuple
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.trim_end_matches('L').parse::<u64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("the .npy shape ({tuple}) is not a tuple of sizes"))?;
    match dims.iter().try_fold(1u64, |acc, &d| acc.checked_mul(d)) {
        Some(0) => Err(format!("the array is empty (shape ({tuple}))")),
        Some(n) if n <= max_elements as u64 => Ok(n),
        _ => Err(format!(
            "array shape ({tuple}) exceeds the limit of {max_elements} values"
        )),
    }
}

fn fortran_to_c(shape: &[usize], data: &[f64]) -> Vec<f64> {
    let n = data.len();
    let mut out = vec![0.0; n];
    let mut index = vec![0usize; shape.len()];
    for value in out.iter_mut() {
        // `index` runs in C order; its Fortran offset has the first axis fastest.
        let mut offset = 0;
        let mut stride = 1;
        for (i, &d) in index.iter().zip(shape) {
            offset += i * stride;
            stride *= d;
        }
        *value = data[offset];
        for axis in (0..shape.len()).rev() {
            index[axis] += 1;
            if index[axis] < shape[axis] {
                break;
            }
            index[axis] = 0;
        }
    }
    out
}

fn check_finite(path: &Path, data: &[f64], width: usize, per_pixel: usize) -> Result<()> {
    match data.iter().position(|v| !v.is_finite()) {
        Some(i) => {
            let pixel = i / per_pixel;
            Err(Error::format(
                path,
                format!(
                    "value at row {}, column {} is {} (non-finite values are not allowed)",
                    pixel / width,
                    pixel % width,
                    data[i]
                ),
            ))
        }
        None => Ok(()),
    }
}

/// Reads an H×W (or H×W×1) array as an image, rejecting NaN and Inf.
pub fn read_image(path: &Path, max_pixels: usize) -> Result<Image> {
    image_from(read_array(path, max_pixels)?, path, max_pixels)
}

/// [`read_image`] of `.npy` bytes held in memory; `path` names them in errors.
pub fn read_image_from_bytes(bytes: &[u8], path: &Path, max_pixels: usize) -> Result<Image> {
    image_from(
        read_array_from_bytes(bytes, path, max_pixels)?,
        path,
        max_pixels,
    )
}

/// Reads an H×W `.npy` picture as luminance: floats and booleans as they are, uint8 and uint16
/// divided by the largest value of their type, other integers refused ([`npy_scale`]; the
/// scale is given back). An H×W×3 array is linear RGB and becomes luminance by
/// [`LUMINANCE_FORMULA`](super::LUMINANCE_FORMULA), as an RGB PNG does (the third value says
/// so). The range is not checked here: [`read_luminance`](super::read_luminance) does it for
/// every picture.
pub fn read_luminance_npy(
    path: &Path,
    max_pixels: usize,
) -> Result<(Image, Option<IntegerScale>, bool)> {
    luminance_npy(read_array(path, max_pixels)?, path, max_pixels)
}

/// [`read_luminance_npy`] of an array already read from `path`.
pub(crate) fn luminance_npy(
    mut array: NpyArray,
    path: &Path,
    max_pixels: usize,
) -> Result<(Image, Option<IntegerScale>, bool)> {
    let scale = npy_scale(&array.dtype).map_err(|why| Error::format(path, why))?;
    if let Some(scale) = &scale {
        array.data.iter_mut().for_each(|v| *v /= scale.max);
    }
    if let [h, w, 3] = array.shape[..] {
        check_size(w, h, max_pixels).map_err(|e| Error::format(path, e.to_string()))?;
        check_finite(path, &array.data, w, 3)?;
        let luminance = array
            .data
            .chunks_exact(3)
            .map(|p| crate::grid::luminance([p[0], p[1], p[2]]))
            .collect();
        return Ok((Grid::from_vec(w, h, luminance)?, scale, true));
    }
    Ok((image_from(array, path, max_pixels)?, scale, false))
}

fn image_from(a: NpyArray, path: &Path, max_pixels: usize) -> Result<Image> {
    let (h, w) = match a.shape[..] {
        [h, w] | [h, w, 1] => (h, w),
        _ => {
            return Err(Error::format(
                path,
                format!("expected a 2-D H×W array (or H×W×3 RGB where a picture is read as luminance), found shape {:?}", a.shape),
            ))
        }
    };
    check_size(w, h, max_pixels).map_err(|e| Error::format(path, e.to_string()))?;
    check_finite(path, &a.data, w, 1)?;
    Grid::from_vec(w, h, a.data)
}

/// Reads an H×W×3 array of normals (x right, y up, z toward the viewer), normalising each;
/// rejects NaN, Inf and zero vectors.
pub fn read_normals(path: &Path, max_pixels: usize) -> Result<Grid<Normal>> {
    let a = read_array(path, max_pixels.saturating_mul(3))?;
    let (h, w) = match a.shape[..] {
        [h, w, 3] => (h, w),
        _ => {
            return Err(Error::format(
                path,
                format!("expected an H×W×3 normal map, found shape {:?}", a.shape),
            ))
        }
    };
    check_size(w, h, max_pixels).map_err(|e| Error::format(path, e.to_string()))?;
    check_finite(path, &a.data, w, 3)?;
    let mut normals = Vec::with_capacity(w * h);
    for (i, c) in a.data.chunks_exact(3).enumerate() {
        let v = Vector3::new(c[0], c[1], c[2]);
        let n = v.norm();
        if n < 1e-12 {
            return Err(Error::format(
                path,
                format!("normal {i} (row {}, col {}) is zero", i / w, i % w),
            ));
        }
        normals.push(v / n);
    }
    Grid::from_vec(w, h, normals)
}

/// The `.npy` header (magic, version 1.0, length, dict, padding to 64 bytes) of an array of
/// dtype `descr` and `shape` in C order.
fn npy_header(descr: &str, shape: &[usize]) -> Result<Vec<u8>> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape_text = match dims.len() {
        0 => "()".to_string(),
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape_text}, }}");
    // Magic (6) + version (2) + length (2) + header + '\n' is padded to a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let header_len =
        u16::try_from(header.len()).map_err(|_| Error::invalid("array has too many dimensions"))?;
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&header_len.to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    Ok(out)
}

/// Writes float32 values of `shape` (C order) as a `.npy` file, atomically.
pub fn write_f32(path: &Path, shape: &[usize], data: impl Iterator<Item = f64>) -> Result<()> {
    let header = npy_header("<f4", shape)?;
    // Streamed through a small buffer: no copy of the whole array in memory.
    super::write_atomic(path, |out| {
        let io = |e| Error::io(path, e);
        out.write_all(&header).map_err(io)?;
        let mut data = data.peekable();
        let mut buffer = Vec::with_capacity(STREAM_BYTES);
        while data.peek().is_some() {
            buffer.clear();
            buffer.extend(
                data.by_ref()
                    .take(STREAM_BYTES / 4)
                    .flat_map(|v| (v as f32).to_le_bytes()),
            );
            out.write_all(&buffer).map_err(io)?;
        }
        Ok(())
    })
}

/// Bytes of values [`write_f32`] converts before handing them to the file.
const STREAM_BYTES: usize = 1 << 16;

/// The bytes of a float64 `.npy` array of `shape` (C order; `[]` for a scalar).
pub fn encode_f64(shape: &[usize], data: &[f64]) -> Result<Vec<u8>> {
    if shape.iter().product::<usize>() != data.len() {
        return Err(Error::invalid(format!(
            ".npy array of {} values does not match shape {shape:?}",
            data.len()
        )));
    }
    let mut out = npy_header("<f8", shape)?;
    out.extend(data.iter().flat_map(|v| v.to_le_bytes()));
    Ok(out)
}

/// The bytes of a NumPy unicode (`<U`) `.npy` array: one string as a 0-d array (`shape`
/// `[]`), or several as a 1-d array; `np.load` reads it without pickles.
pub fn encode_text(shape: &[usize], texts: &[String]) -> Result<Vec<u8>> {
    if shape.iter().product::<usize>() != texts.len() {
        return Err(Error::invalid(format!(
            ".npy array of {} strings does not match shape {shape:?}",
            texts.len()
        )));
    }
    let width = texts
        .iter()
        .map(|t| t.chars().count())
        .max()
        .unwrap_or(0)
        .max(1);
    let mut out = npy_header(&format!("<U{width}"), shape)?;
    for text in texts {
        let chars = text.chars().count();
        out.extend(text.chars().flat_map(|c| (c as u32).to_le_bytes()));
        out.resize(out.len() + 4 * (width - chars), 0);
    }
    Ok(out)
}

/// The bytes of an `.npz` archive (a zip of `.npy` members, stored uncompressed with a fixed
/// timestamp so that equal arrays give equal files), as `numpy.savez` writes it: member
/// `NAME.npy` for each (name, `.npy` bytes).
///
/// The zip is written here (PKWARE's APPNOTE: a local header and the bytes of each member,
/// then the central directory and its end record); stored members need nothing more than a
/// CRC-32. Members and the archive stay under 4 GiB and 65,535 entries (no zip64).
pub fn encode_npz(members: &[(String, Vec<u8>)]) -> Result<Vec<u8>> {
    let fail = |what: String| Error::Compute(format!("cannot write .npz: {what}"));
    if members.len() > usize::from(u16::MAX) {
        return Err(fail(format!("{} arrays (at most 65535)", members.len())));
    }
    let u32_of = |n: usize, what: &str| {
        u32::try_from(n).map_err(|_| fail(format!("{what} is 4 GiB or more (no zip64)")))
    };
    // 1980-01-01 00:00:00 in MS-DOS time and date: zip's earliest timestamp.
    const DOS_TIME: u16 = 0;
    const DOS_DATE: u16 = (1 << 5) | 1;
    let mut out = Vec::new();
    let mut central = Vec::new();
    for (name, bytes) in members {
        let file_name = format!("{name}.npy");
        let name_len = u16::try_from(file_name.len())
            .map_err(|_| fail(format!("the array name '{name}' is too long")))?;
        let size = u32_of(bytes.len(), &format!("array '{name}'"))?;
        let offset = u32_of(out.len(), "the archive")?;
        let crc = crc32fast::hash(bytes);
        // Bit 11: the name is UTF-8.
        let flags: u16 = if file_name.is_ascii() { 0 } else { 1 << 11 };
        // The fields a local header shares with the central directory's entry (version 2.0
        // needed to extract, as zip writers put it).
        let mut common = Vec::with_capacity(26);
        for half in [20u16, flags, 0, DOS_TIME, DOS_DATE] {
            common.extend(half.to_le_bytes());
        }
        for word in [crc, size, size] {
            common.extend(word.to_le_bytes());
        }
        common.extend(name_len.to_le_bytes());
        common.extend(0u16.to_le_bytes()); // no extra field
        out.extend(0x0403_4b50u32.to_le_bytes());
        out.extend(&common);
        out.extend(file_name.as_bytes());
        out.extend(bytes);
        central.extend(0x0201_4b50u32.to_le_bytes());
        // Made by: Unix (3), zip 4.6.
        central.extend(0x032eu16.to_le_bytes());
        central.extend(&common);
        central.extend(0u16.to_le_bytes()); // no comment
        central.extend(0u16.to_le_bytes()); // disk 0
        central.extend(0u16.to_le_bytes()); // internal attributes
        central.extend((0o100644u32 << 16).to_le_bytes()); // a regular file, rw-r--r--
        central.extend(offset.to_le_bytes());
        central.extend(file_name.as_bytes());
    }
    let central_offset = u32_of(out.len(), "the archive")?;
    let central_size = u32_of(central.len(), "the archive's directory")?;
    out.extend(central);
    out.extend(0x0605_4b50u32.to_le_bytes());
    let entries = members.len() as u16;
    for half in [0u16, 0, entries, entries] {
        out.extend(half.to_le_bytes());
    }
    out.extend(central_size.to_le_bytes());
    out.extend(central_offset.to_le_bytes());
    out.extend(0u16.to_le_bytes()); // no comment
    Ok(out)
}

/// Writes an image as an H×W float32 `.npy`.
pub fn write_image(path: &Path, image: &Image) -> Result<()> {
    write_f32(
        path,
        &[image.height(), image.width()],
        image.data().iter().copied(),
    )
}

/// Writes normals as an H×W×3 float32 `.npy` (x right, y up, z toward the viewer).
pub fn write_normals(path: &Path, normals: &Grid<Normal>) -> Result<()> {
    write_f32(
        path,
        &[normals.height(), normals.width(), 3],
        normals.data().iter().flat_map(|n| [n.x, n.y, n.z]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("shadelab-npy-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn round_trip_and_shape_checks() {
        let d = scratch("rt");
        let img = Grid::from_fn(5, 3, |c, r| c as f64 * 0.5 - r as f64);
        write_image(&d.join("a.npy"), &img).unwrap();
        assert_eq!(read_image(&d.join("a.npy"), 1000).unwrap(), img);
        let bytes = std::fs::read(d.join("a.npy")).unwrap();
        assert_eq!((bytes.len() - 15 * 4) % 64, 0, "header is 64-byte aligned");
        let normals = Grid::from_fn(2, 2, |c, _| Vector3::new(c as f64, 0.0, 1.0).normalize());
        write_normals(&d.join("n.npy"), &normals).unwrap();
        let back = read_normals(&d.join("n.npy"), 1000).unwrap();
        assert!(back
            .data()
            .iter()
            .zip(normals.data())
            .all(|(a, b)| (a - b).norm() < 1e-7));
        assert!(read_normals(&d.join("a.npy"), 1000).is_err());
        assert!(read_image(&d.join("n.npy"), 1000).is_err());
        assert!(read_image(&d.join("a.npy"), 10).is_err());
    }

    #[test]
    fn nan_truncated_and_garbage_are_errors() {
        let d = scratch("bad");
        write_image(&d.join("nan.npy"), &Grid::new(2, 2, f64::NAN)).unwrap();
        assert!(read_image(&d.join("nan.npy"), 100)
            .unwrap_err()
            .to_string()
            .contains("NaN"));
        write_image(&d.join("t.npy"), &Grid::new(20, 20, 1.0)).unwrap();
        let bytes = std::fs::read(d.join("t.npy")).unwrap();
        std::fs::write(d.join("t.npy"), &bytes[..bytes.len() - 10]).unwrap();
        assert!(read_image(&d.join("t.npy"), 1000)
            .unwrap_err()
            .to_string()
            .contains("truncated"));
        std::fs::write(d.join("g.npy"), b"hello").unwrap();
        assert!(read_image(&d.join("g.npy"), 1000).is_err());
    }

    fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        header.push_str(&" ".repeat((64 - (11 + header.len()) % 64) % 64));
        header.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(data);
        out
    }

    #[test]
    fn hostile_headers_are_errors_not_overflows() {
        let d = scratch("hostile");
        let six: Vec<u8> = [0f32; 6].iter().flat_map(|v| v.to_le_bytes()).collect();
        let mut lying = npy("<f4", "(2, 3)", &six);
        lying[8] = 0xff;
        lying[9] = 0xff;
        let cases = [
            (
                npy("<f4", "(4294967296, 4294967296)", &six),
                "exceeds the limit",
            ),
            (
                npy("<f4", "(99999999999999999999, 1)", &six),
                "not a tuple of sizes",
            ),
            (npy("<f4", "(0, 3)", &[]), "empty"),
            (npy("<f2", "(2, 3)", &six), "dtype"),
            (npy("<f4", "(2, 3)", &six[..20]), "truncated"),
            (
                npy(
                    "<f4",
                    "(2, 3)",
                    &[0f32, 1.0, 0.0, 0.0, f32::INFINITY, 0.0]
                        .iter()
                        .flat_map(|v| v.to_le_bytes())
                        .collect::<Vec<_>>(),
                ),
                "row 1, column 1 is inf",
            ),
            (lying, "header is truncated"),
        ];
        for (bytes, expected) in cases {
            let p = d.join("x.npy");
            std::fs::write(&p, &bytes).unwrap();
            let e = read_image(&p, 1 << 20).unwrap_err().to_string();
            assert!(
                e.contains("x.npy: ") && e.contains(expected),
                "expected '{expected}' in: {e}"
            );
        }
    }

    #[test]
    fn integer_pictures_follow_one_rule() {
        let d = scratch("int");
        let codes: Vec<u16> = (0..6).map(|k| k * 13_000).collect();
        let u2: Vec<u8> = codes.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(d.join("u2.npy"), npy("<u2", "(2, 3)", &u2)).unwrap();
        // As an array, the values as stored; as a picture, divided by 65535.
        let array = read_array(&d.join("u2.npy"), 100).unwrap();
        assert_eq!((array.dtype.as_str(), array.data[5]), ("<u2", 65000.0));
        let (image, scale, _) = read_luminance_npy(&d.join("u2.npy"), 100).unwrap();
        assert_eq!(scale.unwrap().max, 65535.0);
        assert_eq!(image.data()[5], 65000.0 / 65535.0);
        assert_eq!(npy_file_scale(&d.join("u2.npy")).unwrap().dtype, "uint16");
        let u1: Vec<u8> = vec![0, 51, 102, 153, 204, 255];
        std::fs::write(d.join("u1.npy"), npy("|u1", "(2, 3)", &u1)).unwrap();
        let (image, _, _) = read_luminance_npy(&d.join("u1.npy"), 100).unwrap();
        assert_eq!(image.data(), &[0.0, 0.2, 0.4, 0.6, 0.8, 1.0]);
        let i1: Vec<u8> = vec![0, 1, 2, 3, 4, 5];
        std::fs::write(d.join("i1.npy"), npy("|i1", "(2, 3)", &i1)).unwrap();
        assert_eq!(read_array(&d.join("i1.npy"), 100).unwrap().data[5], 5.0);
        let e = read_luminance_npy(&d.join("i1.npy"), 100)
            .unwrap_err()
            .to_string();
        assert!(e.contains("i1.npy: int8 pictures are refused"), "{e}");
        // Floats: no scale, no note.
        write_image(&d.join("f.npy"), &Grid::new(3, 2, 0.5)).unwrap();
        assert_eq!(npy_file_scale(&d.join("f.npy")), None);
    }

    #[test]
    fn an_rgb_array_is_read_as_luminance_like_an_rgb_png() {
        let d = scratch("rgb");
        // 1×2 pixels: pure green, and grey 0.5.
        let values = [0.0, 1.0, 0.0, 0.5, 0.5, 0.5];
        write_f32(&d.join("c.npy"), &[1, 2, 3], values.iter().copied()).unwrap();
        let (image, scale, rgb) = read_luminance_npy(&d.join("c.npy"), 100).unwrap();
        assert!(rgb && scale.is_none());
        assert_eq!((image.width(), image.height()), (2, 1));
        assert!(
            (image.get(0, 0) - 0.7152).abs() < 1e-6,
            "{}",
            image.get(0, 0)
        );
        assert!((image.get(1, 0) - 0.5).abs() < 1e-6);
        let (_, info) = super::super::read_luminance(&d.join("c.npy"), 100).unwrap();
        assert!(info["conversion"].as_str().unwrap().contains("Rec. 709"));
        // Codes: uint8 scaled first, then weighted; a 4-channel array is still refused.
        let mut bytes = npy_header("|u1", &[1, 1, 3]).unwrap();
        bytes.extend([255u8, 255, 255]);
        std::fs::write(d.join("u.npy"), &bytes).unwrap();
        let (image, _, _) = read_luminance_npy(&d.join("u.npy"), 100).unwrap();
        assert!((image.get(0, 0) - 1.0).abs() < 1e-12);
        write_f32(&d.join("a.npy"), &[1, 1, 4], [0.0; 4].into_iter()).unwrap();
        let e = read_luminance_npy(&d.join("a.npy"), 100)
            .unwrap_err()
            .to_string();
        assert!(e.contains("H×W×3 RGB"), "{e}");
    }

    #[test]
    fn only_the_declared_values_are_read() {
        // A header declaring 2×3 float64 over a file of 48 bytes and a megabyte more: the
        // reader stops after the 48 (the tail is never read, let alone held).
        let d = scratch("tail");
        let mut bytes = npy("<f8", "(2, 3)", &[0u8; 48]);
        let declared = bytes.len();
        bytes.resize(declared + (1 << 20), 0xff);
        std::fs::write(d.join("t.npy"), &bytes).unwrap();
        assert_eq!(
            read_npy_file(&d.join("t.npy"), 100).unwrap().len(),
            declared
        );
        // Not a .npy: refused after its first 12 bytes.
        std::fs::write(d.join("z.npy"), vec![0u8; 1 << 20]).unwrap();
        let e = read_array(&d.join("z.npy"), 100).unwrap_err().to_string();
        assert!(e.contains("not a .npy file"), "{e}");
    }

    #[test]
    fn fortran_order_is_reordered() {
        // shape (2, 3) stored column-major: [[0,1,2],[3,4,5]] → 0,3,1,4,2,5.
        let out = fortran_to_c(&[2, 3], &[0.0, 3.0, 1.0, 4.0, 2.0, 5.0]);
        assert_eq!(out, vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
    }

    #[test]
    fn npz_members_read_back_with_an_independent_zip_reader() {
        use std::io::Read;
        let sets = [
            vec![],
            vec![("img".to_string(), vec![1u8, 2, 3])],
            vec![
                (
                    "a".to_string(),
                    (0..1000).map(|i| (i % 251) as u8).collect(),
                ),
                ("ü".to_string(), b"xyz".to_vec()),
                ("e".to_string(), vec![]),
            ],
        ];
        for members in sets {
            let bytes = encode_npz(&members).unwrap();
            // Equal members give equal files (a fixed timestamp).
            assert_eq!(bytes, encode_npz(&members).unwrap());
            let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
            assert_eq!(zip.len(), members.len());
            for (i, (name, data)) in members.iter().enumerate() {
                let mut f = zip.by_index(i).unwrap();
                assert_eq!(f.name(), format!("{name}.npy"));
                assert_eq!(f.compression(), zip::CompressionMethod::Stored);
                let mut back = Vec::new();
                // The reader checks each member's CRC-32 as it reads.
                f.read_to_end(&mut back).unwrap();
                assert_eq!(&back, data);
            }
        }
    }
}

//! The PLY reader: ASCII, binary little endian and binary big endian (see the parent module
//! for what is accepted and rejected).

use super::{fan_triangulate, finish, Mesh};
use crate::error::{Error, Result};
use nalgebra::Vector3;
use std::path::Path;

/// Parses PLY bytes; `source` names the file in error messages.
pub(super) fn parse(bytes: &[u8], source: &Path) -> Result<Mesh> {
    let fail = |m: String| Error::format(source, m);
    let header = PlyHeader::parse(bytes).map_err(fail)?;
    let data = &bytes[header.data_start..];
    let (vertices, triangles) = match header.encoding {
        Encoding::Ascii => {
            let mut rows = AsciiRows::new(data, header.lines);
            read_ply_body(&header, &mut rows)
        }
        Encoding::Binary { big_endian } => {
            let mut rows = BinaryRows {
                data,
                pos: 0,
                big_endian,
            };
            read_ply_body(&header, &mut rows)
        }
    }
    .map_err(fail)?;
    finish(vertices, triangles, source)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The integer range of an integer type; `None` for floats.
    fn int_range(self) -> Option<(i64, i64)> {
        Some(match self {
            Scalar::I8 => (i8::MIN as i64, i8::MAX as i64),
            Scalar::U8 => (0, u8::MAX as i64),
            Scalar::I16 => (i16::MIN as i64, i16::MAX as i64),
            Scalar::U16 => (0, u16::MAX as i64),
            Scalar::I32 => (i32::MIN as i64, i32::MAX as i64),
            Scalar::U32 => (0, u32::MAX as i64),
            Scalar::F32 | Scalar::F64 => return None,
        })
    }

    /// Decodes `bytes` (exactly `self.size()` long).
    fn decode(self, bytes: &[u8], big_endian: bool) -> f64 {
        fn take<const N: usize>(bytes: &[u8], big_endian: bool) -> [u8; N] {
            let mut a = [0; N];
            a.copy_from_slice(&bytes[..N]);
            // Normalise to little endian.
            if big_endian {
                a.reverse();
            }
            a
        }
        match self {
            Scalar::I8 => bytes[0] as i8 as f64,
            Scalar::U8 => bytes[0] as f64,
            Scalar::I16 => i16::from_le_bytes(take(bytes, big_endian)) as f64,
            Scalar::U16 => u16::from_le_bytes(take(bytes, big_endian)) as f64,
            Scalar::I32 => i32::from_le_bytes(take(bytes, big_endian)) as f64,
            Scalar::U32 => u32::from_le_bytes(take(bytes, big_endian)) as f64,
            Scalar::F32 => f32::from_le_bytes(take(bytes, big_endian)) as f64,
            Scalar::F64 => f64::from_le_bytes(take(bytes, big_endian)),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PropertyKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct Property {
    name: String,
    kind: PropertyKind,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

#[derive(Debug)]
struct PlyHeader {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first data byte.
    data_start: usize,
    /// Number of header lines (so ASCII data errors can give file line numbers).
    lines: usize,
}

impl PlyHeader {
    fn parse(bytes: &[u8]) -> std::result::Result<PlyHeader, String> {
        let mut pos = 0;
        let mut line_no = 0;
        let mut encoding = None;
        let mut elements: Vec<Element> = Vec::new();
        loop {
            if pos >= bytes.len() {
                return Err(if line_no == 0 {
                    "the file is empty".into()
                } else {
                    "the header has no end_header line (truncated or not a PLY file)".into()
                });
            }
            let rest = &bytes[pos..];
            let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            pos += end + 1;
            line_no += 1;
            let line = std::str::from_utf8(&rest[..end]).map_err(|_| {
                if line_no == 1 {
                    "not a PLY file (it does not start with 'ply')".to_string()
                } else {
                    format!("header line {line_no} is not text")
                }
            })?;
            let line = line.trim_end_matches('\r');
            if line_no == 1 {
                if line.trim() != "ply" {
                    return Err("not a PLY file (it does not start with 'ply')".into());
                }
                continue;
            }
            let words: Vec<&str> = line.split_ascii_whitespace().collect();
            let bad = |what: &str| format!("header line {line_no}: {what}: '{line}'");
            match words.first().copied() {
                None | Some("comment") | Some("obj_info") => {}
                Some("format") => {
                    if words.len() != 3 {
                        return Err(bad("expected 'format <type> 1.0'"));
                    }
                    encoding = Some(match words[1] {
                        "ascii" => Encoding::Ascii,
                        "binary_little_endian" => Encoding::Binary { big_endian: false },
                        "binary_big_endian" => Encoding::Binary { big_endian: true },
                        _ => return Err(bad("unknown PLY format")),
                    });
                    if !words[2].starts_with('1') {
                        return Err(bad("unsupported PLY version (expected 1.0)"));
                    }
                }
                Some("element") => {
                    if words.len() != 3 {
                        return Err(bad("expected 'element <name> <count>'"));
                    }
                    let count = words[2]
                        .parse::<u64>()
                        .map_err(|_| bad("element count is not a non-negative integer"))?;
                    elements.push(Element {
                        name: words[1].to_string(),
                        count,
                        properties: Vec::new(),
                    });
                }
                Some("property") => {
                    let element = elements
                        .last_mut()
                        .ok_or_else(|| bad("property before any element"))?;
                    let scalar = |name: &str| {
                        Scalar::from_name(name)
                            .ok_or_else(|| bad(&format!("unknown property type '{name}'")))
                    };
                    let property = match words.as_slice() {
                        ["property", "list", count, item, name] => {
                            let count = scalar(count)?;
                            if count.int_range().is_none() {
                                return Err(bad("a list's count type must be an integer type"));
                            }
                            Property {
                                name: name.to_string(),
                                kind: PropertyKind::List {
                                    count,
                                    item: scalar(item)?,
                                },
                            }
                        }
                        ["property", ty, name] => Property {
                            name: name.to_string(),
                            kind: PropertyKind::Scalar(scalar(ty)?),
                        },
                        _ => {
                            return Err(bad("expected 'property <type> <name>' or \
                                 'property list <count type> <item type> <name>'"))
                        }
                    };
                    element.properties.push(property);
                }
                Some("end_header") => break,
                Some(other) => return Err(bad(&format!("unknown header keyword '{other}'"))),
            }
        }
        let encoding = encoding.ok_or("the header has no 'format' line")?;
        let header = PlyHeader {
            encoding,
            elements,
            data_start: pos.min(bytes.len()),
            lines: line_no,
        };
        header.validate(bytes.len() - header.data_start)?;
        Ok(header)
    }

    fn element(&self, name: &str) -> Option<&Element> {
        self.elements.iter().find(|e| e.name == name)
    }

    /// Checks that the elements needed are there and that the data can hold the declared rows.
    fn validate(&self, data_bytes: usize) -> std::result::Result<(), String> {
        let vertex = self
            .element("vertex")
            .ok_or("the header declares no 'vertex' element")?;
        for axis in ["x", "y", "z"] {
            match vertex.properties.iter().find(|p| p.name == axis) {
                Some(Property {
                    kind: PropertyKind::Scalar(_),
                    ..
                }) => {}
                Some(_) => return Err(format!("vertex property '{axis}' is a list")),
                None => return Err(format!("the vertex element has no '{axis}' property")),
            }
        }
        if vertex.count > u32::MAX as u64 {
            return Err(format!("{} vertices are too many", vertex.count));
        }
        let face = self.element("face").ok_or(
            "the header declares no 'face' element (point clouds and triangle strips are not \
             supported)",
        )?;
        match face_list(face) {
            Some((_, PropertyKind::List { item, .. })) if item.int_range().is_some() => {}
            Some(_) => return Err("the face vertex_indices property is not an integer list".into()),
            None => return Err("the face element has no 'vertex_indices' list property".into()),
        }
        // Every row needs at least this many bytes, so the data bound the counts before any
        // allocation (ASCII: one character and one separator per value; the very last separator
        // may be missing).
        let mut needed: u128 = 0;
        for e in &self.elements {
            if e.properties.is_empty() && e.count > 0 {
                return Err(format!("element '{}' has no properties", e.name));
            }
            let row: u128 = match self.encoding {
                Encoding::Ascii => 2 * e.properties.len() as u128,
                Encoding::Binary { .. } => e
                    .properties
                    .iter()
                    .map(|p| match p.kind {
                        PropertyKind::Scalar(s) => s.size() as u128,
                        PropertyKind::List { count, .. } => count.size() as u128,
                    })
                    .sum(),
            };
            needed += e.count as u128 * row;
            let available = data_bytes as u128 + u128::from(self.encoding == Encoding::Ascii);
            if needed > available {
                return Err(format!(
                    "the header declares {} '{}' rows, but the {} bytes of data after the \
                     header cannot hold them (truncated file or wrong count)",
                    e.count, e.name, data_bytes
                ));
            }
        }
        Ok(())
    }
}

/// The face element's index list: its position among the properties and its kind.
fn face_list(face: &Element) -> Option<(usize, PropertyKind)> {
    face.properties
        .iter()
        .position(|p| p.name == "vertex_indices" || p.name == "vertex_index")
        .map(|i| (i, face.properties[i].kind))
}

/// A source of PLY values, row by row.
trait Rows {
    fn start_row(&mut self) -> std::result::Result<(), String>;
    fn value(&mut self, ty: Scalar) -> std::result::Result<f64, String>;
    fn end_row(&mut self) -> std::result::Result<(), String>;
}

struct BinaryRows<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl Rows for BinaryRows<'_> {
    fn start_row(&mut self) -> std::result::Result<(), String> {
        Ok(())
    }

    fn value(&mut self, ty: Scalar) -> std::result::Result<f64, String> {
        let bytes = self
            .data
            .get(self.pos..self.pos + ty.size())
            .ok_or("the file ends in the middle of the data (truncated)")?;
        self.pos += ty.size();
        Ok(ty.decode(bytes, self.big_endian))
    }

    fn end_row(&mut self) -> std::result::Result<(), String> {
        Ok(())
    }
}

/// ASCII PLY: one row per line, values separated by whitespace; blank lines are skipped.
struct AsciiRows<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
    tokens: std::str::SplitAsciiWhitespace<'a>,
}

impl<'a> AsciiRows<'a> {
    fn new(data: &'a [u8], header_lines: usize) -> Self {
        AsciiRows {
            data,
            pos: 0,
            line: header_lines,
            tokens: "".split_ascii_whitespace(),
        }
    }
}

impl<'a> Rows for AsciiRows<'a> {
    fn start_row(&mut self) -> std::result::Result<(), String> {
        let data: &'a [u8] = self.data;
        loop {
            if self.pos >= data.len() {
                return Err("the file ends before this row (truncated)".into());
            }
            let rest = &data[self.pos..];
            let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            self.pos += end + 1;
            self.line += 1;
            let text = std::str::from_utf8(&rest[..end])
                .map_err(|_| format!("line {} is not text", self.line))?;
            if !text.trim().is_empty() {
                self.tokens = text.split_ascii_whitespace();
                return Ok(());
            }
        }
    }

    fn value(&mut self, ty: Scalar) -> std::result::Result<f64, String> {
        let Some(token) = self.tokens.next() else {
            return Err(if self.pos >= self.data.len() {
                format!(
                    "line {}: the file ends in the middle of this row (truncated)",
                    self.line
                )
            } else {
                format!("line {}: too few values", self.line)
            });
        };
        match ty.int_range() {
            Some((lo, hi)) => match token.parse::<i64>() {
                Ok(v) if (lo..=hi).contains(&v) => Ok(v as f64),
                Ok(v) => Err(format!(
                    "line {}: {v} is outside the range of its type {ty:?}",
                    self.line
                )),
                Err(_) => Err(format!("line {}: '{token}' is not an integer", self.line)),
            },
            None => token
                .parse::<f64>()
                .map_err(|_| format!("line {}: '{token}' is not a number", self.line)),
        }
    }

    fn end_row(&mut self) -> std::result::Result<(), String> {
        match self.tokens.next() {
            None => Ok(()),
            Some(_) => Err(format!(
                "line {}: more values than the header's properties",
                self.line
            )),
        }
    }
}

type Body = (Vec<Vector3<f64>>, Vec<[u32; 3]>);

fn read_ply_body(header: &PlyHeader, rows: &mut impl Rows) -> std::result::Result<Body, String> {
    let vertex_count = header.element("vertex").map_or(0, |e| e.count);
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    let (mut vertices_read, mut faces_read) = (false, false);
    for element in &header.elements {
        // Only the first 'vertex' and 'face' elements are the mesh; anything else is skipped.
        let is_vertex = element.name == "vertex" && !vertices_read;
        let is_face = element.name == "face" && !faces_read;
        vertices_read |= is_vertex;
        faces_read |= is_face;
        let axes = ["x", "y", "z"].map(|a| element.properties.iter().position(|p| p.name == a));
        let index_list = face_list(element).map(|(i, _)| i);
        if is_vertex {
            // Bounded by the data size (checked in the header).
            vertices.reserve_exact(element.count as usize);
        }
        for row in 0..element.count {
            let context = |e: String| format!("{} {row} of {}: {e}", element.name, element.count);
            rows.start_row().map_err(context)?;
            let mut xyz = [0.0; 3];
            for (p, property) in element.properties.iter().enumerate() {
                match property.kind {
                    PropertyKind::Scalar(ty) => {
                        let v = rows.value(ty).map_err(context)?;
                        if is_vertex {
                            for (axis, slot) in axes.iter().zip(&mut xyz) {
                                if *axis == Some(p) {
                                    *slot = v;
                                }
                            }
                        }
                    }
                    PropertyKind::List { count, item } => {
                        let n = rows.value(count).map_err(context)?;
                        if n < 0.0 {
                            return Err(context(format!("list length {n} is negative")));
                        }
                        let collect = is_face && index_list == Some(p);
                        if collect {
                            corners.clear();
                        }
                        for _ in 0..n as u64 {
                            let v = rows.value(item).map_err(context)?;
                            if collect {
                                if v < 0.0 || v >= vertex_count as f64 {
                                    return Err(context(format!(
                                        "vertex index {v} is out of range (the header declares \
                                         {vertex_count} vertices)"
                                    )));
                                }
                                corners.push(v as u32);
                            }
                        }
                        if collect {
                            if corners.len() < 3 {
                                return Err(context(format!(
                                    "a face needs at least 3 corners, this one has {}",
                                    corners.len()
                                )));
                            }
                            fan_triangulate(&corners, &mut triangles);
                        }
                    }
                }
            }
            rows.end_row().map_err(context)?;
            if is_vertex {
                if !xyz.iter().all(|c| c.is_finite()) {
                    return Err(context(format!(
                        "NaN or infinite coordinate ({}, {}, {})",
                        xyz[0], xyz[1], xyz[2]
                    )));
                }
                vertices.push(Vector3::from(xyz));
            }
        }
    }
    Ok((vertices, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn src() -> &'static Path {
        Path::new("test.ply")
    }

    fn ply_err(text: &[u8]) -> String {
        let e = Mesh::from_ply(text, src()).unwrap_err().to_string();
        assert!(
            e.starts_with("test.ply: "),
            "error does not name the file: {e}"
        );
        e
    }

    const SQUARE_ASCII: &str = "ply\nformat ascii 1.0\ncomment a unit square as a quad and \
        a triangle\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
        property float confidence\nproperty list uchar float extra\nelement edge 1\n\
        property int vertex1\nproperty int vertex2\nelement face 2\n\
        property list uchar int vertex_indices\nproperty uchar flags\nend_header\n\
        0 0 0 0.5 0\n1 0 0 0.5 2 7 8\n1 1 0.5 0.5 1 3\n0 1 0 0.5 0\n0 1\n4 0 1 2 3 9\n\
        3 2 3 0 1\n";

    #[test]
    fn ascii_ply_skips_extra_properties_and_fans_polygons() {
        let m = Mesh::from_ply(SQUARE_ASCII.as_bytes(), src()).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.vertices[2], Vector3::new(1.0, 1.0, 0.5));
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [2, 3, 0]]);
    }

    /// A binary PLY of `vertices` (float or double) and polygons (`list uchar <index>`).
    fn binary_ply(
        big_endian: bool,
        double: bool,
        index_type: &str,
        vertices: &[[f64; 3]],
        faces: &[&[u32]],
    ) -> Vec<u8> {
        let order = if big_endian { "big" } else { "little" };
        let ty = if double { "double" } else { "float" };
        let mut out = format!(
            "ply\r\nformat binary_{order}_endian 1.0\r\nelement vertex {}\r\n\
             property {ty} x\r\nproperty {ty} y\r\nproperty {ty} z\r\nproperty uchar intensity\r\n\
             element face {}\r\nproperty list uchar {index_type} vertex_indices\r\nend_header\r\n",
            vertices.len(),
            faces.len()
        )
        .into_bytes();
        for v in vertices {
            for c in v {
                if double {
                    let b = if big_endian {
                        c.to_be_bytes()
                    } else {
                        c.to_le_bytes()
                    };
                    out.extend_from_slice(&b);
                } else {
                    let c = *c as f32;
                    let b = if big_endian {
                        c.to_be_bytes()
                    } else {
                        c.to_le_bytes()
                    };
                    out.extend_from_slice(&b);
                }
            }
            out.push(200);
        }
        for f in faces {
            out.push(f.len() as u8);
            for &i in *f {
                match index_type {
                    "ushort" => {
                        let i = i as u16;
                        out.extend(if big_endian {
                            i.to_be_bytes()
                        } else {
                            i.to_le_bytes()
                        });
                    }
                    _ => out.extend(if big_endian {
                        i.to_be_bytes()
                    } else {
                        i.to_le_bytes()
                    }),
                }
            }
        }
        out
    }

    const SQUARE: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.5],
        [0.0, 1.0, 0.0],
    ];

    #[test]
    fn binary_ply_in_both_byte_orders_matches_ascii() {
        let ascii = Mesh::from_ply(SQUARE_ASCII.as_bytes(), src()).unwrap();
        for big in [false, true] {
            for double in [false, true] {
                for index in ["int", "uint", "ushort"] {
                    let bytes =
                        binary_ply(big, double, index, &SQUARE, &[&[0, 1, 2, 3], &[2, 3, 0]]);
                    let m = Mesh::from_ply(&bytes, src()).unwrap();
                    assert_eq!(m, ascii, "big endian {big}, double {double}, {index}");
                }
            }
        }
    }

    #[test]
    fn truncated_binary_ply_is_an_error_at_every_cut() {
        let bytes = binary_ply(false, false, "int", &SQUARE, &[&[0, 1, 2, 3]]);
        let header_end = bytes.windows(10).position(|w| w == b"end_header").unwrap();
        for cut in 0..bytes.len() {
            let e = ply_err(&bytes[..cut]);
            if cut > header_end + 12 {
                assert!(e.contains("truncated"), "cut {cut}: {e}");
            }
        }
    }

    #[test]
    fn header_counts_beyond_the_file_size_are_rejected_before_allocating() {
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
                    property float x\nproperty float y\nproperty float z\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n";
        let e = ply_err(text.as_bytes());
        assert!(e.contains("cannot hold them"), "{e}");
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 99999999999\n\
                    property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n\
                    3 0 1 2\n";
        let e = ply_err(text.as_bytes());
        assert!(e.contains("99999999999 'face' rows"), "{e}");
    }

    fn tri_ply(vertex_lines: &str, face_lines: &str, faces: usize) -> String {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face {faces}\nproperty list uchar int vertex_indices\n\
             end_header\n{vertex_lines}{face_lines}"
        )
    }

    #[test]
    fn malformed_ply_gives_clear_errors() {
        let v = "0 0 0\n1 0 0\n0 1 0\n";
        let cases: Vec<(String, &str)> = vec![
            ("".into(), "empty"),
            ("solid cube\n".into(), "not a PLY file"),
            (
                "ply\nformat ascii 1.0\nelement vertex 3\n".into(),
                "no end_header",
            ),
            (
                "ply\nelement vertex 0\nproperty float x\nend_header\n".into(),
                "no 'format'",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex three\n".into(),
                "element count",
            ),
            (
                "ply\nformat ascii 1.0\nproperty float x\n".into(),
                "property before any element",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\n".into(),
                "unknown property type",
            ),
            (
                "ply\nformat ascii 1.0\nbogus\n".into(),
                "unknown header keyword",
            ),
            ("ply\nformat utf8 1.0\n".into(), "unknown PLY format"),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                 element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n"
                    .into(),
                "no 'z' property",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n0 0 0\n"
                    .into(),
                "no 'face' element",
            ),
            (
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                 property float z\nelement face 1\nproperty list uchar float vertex_indices\n\
                 end_header\n0 0 0\n3 0 0 0\n"
                    .into(),
                "not an integer list",
            ),
            (tri_ply(v, "3 0 1 3\n", 1), "vertex index 3 is out of range"),
            (
                tri_ply(v, "3 0 -1 2\n", 1),
                "vertex index -1 is out of range",
            ),
            (
                tri_ply(v, "2 0 1\n", 1),
                "at least 3 corners, this one has 2",
            ),
            (tri_ply(v, "300 0 1 2\n", 1), "outside the range"),
            (tri_ply(v, "3 0 1.5 2\n", 1), "'1.5' is not an integer"),
            (tri_ply(v, "3 0 1 2 7\n", 1), "more values than"),
            (tri_ply(v, "3 0 1\n\n", 1), "line 13: too few values"),
            (
                tri_ply(v, "3 0 1", 1),
                "line 13: the file ends in the middle of this row",
            ),
            (tri_ply(v, "3 0 1 2\n", 2), "truncated"),
            (
                tri_ply("0 0 0\nnan 0 0\n0 1 0\n", "3 0 1 2\n", 1),
                "NaN or infinite",
            ),
            (
                tri_ply("0 0 0\n1 inf 0\n0 1 0\n", "3 0 1 2\n", 1),
                "NaN or infinite",
            ),
            (
                tri_ply("0 0 0\n1 zero 0\n0 1 0\n", "3 0 1 2\n", 1),
                "'zero' is not a number",
            ),
            (tri_ply(v, "", 0), "no faces"),
            (tri_ply(v, "3 0 0 1\n", 1), "no faces (or only degenerate"),
        ];
        for (text, expected) in cases {
            let e = ply_err(text.as_bytes());
            assert!(e.contains(expected), "expected '{expected}' in: {e}");
        }
    }

    #[test]
    fn ply_errors_give_the_row_and_line() {
        let e = ply_err(tri_ply("0 0 0\n1 0 0\n0 1\n", "3 0 1 2\n", 1).as_bytes());
        assert!(e.contains("vertex 2 of 3: line 12: too few values"), "{e}");
    }
}

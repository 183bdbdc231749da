//! The Wavefront OBJ reader: `v` and `f` statements; everything else is ignored.

use super::{fan_triangulate, finish, Mesh};
use crate::error::{Error, Result};
use nalgebra::Vector3;
use std::path::Path;

/// Parses OBJ bytes; `source` names the file in error messages.
pub(super) fn parse(bytes: &[u8], source: &Path) -> Result<Mesh> {
    let fail = |line: usize, m: String| Error::format(source, format!("line {line}: {m}"));
    let mut vertices: Vec<Vector3<f64>> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    // Positive indices may legally point forward; the largest is checked at the end.
    let mut largest: Option<(usize, u64)> = None;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let text = String::from_utf8_lossy(raw);
        let text = text.split('#').next().unwrap_or("");
        let mut tokens = text.split_ascii_whitespace();
        match tokens.next() {
            Some("v") => {
                let mut xyz = [0.0; 3];
                for c in &mut xyz {
                    let token = tokens
                        .next()
                        .ok_or_else(|| fail(line, "a vertex needs three coordinates".into()))?;
                    *c = token.parse::<f64>().map_err(|_| {
                        fail(line, format!("vertex coordinate '{token}' is not a number"))
                    })?;
                }
                if !xyz.iter().all(|c| c.is_finite()) {
                    return Err(fail(
                        line,
                        format!(
                            "vertex {} has a NaN or infinite coordinate",
                            vertices.len() + 1
                        ),
                    ));
                }
                vertices.push(Vector3::from(xyz));
            }
            Some("f") => {
                corners.clear();
                for token in tokens {
                    let index_text = token.split('/').next().unwrap_or("");
                    let index: i64 = index_text.parse().map_err(|_| {
                        fail(line, format!("face corner '{token}' is not a vertex index"))
                    })?;
                    let resolved = if index > 0 {
                        let zero_based = (index - 1) as u64;
                        if largest.map_or(true, |(_, m)| zero_based > m) {
                            largest = Some((line, zero_based));
                        }
                        zero_based
                    } else if index < 0 {
                        let back = vertices.len() as i64 + index;
                        if back < 0 {
                            return Err(fail(
                                line,
                                format!(
                                    "relative index {index} reaches before the first vertex \
                                     ({} defined so far)",
                                    vertices.len()
                                ),
                            ));
                        }
                        back as u64
                    } else {
                        return Err(fail(
                            line,
                            "vertex index 0 is invalid (OBJ indices start at 1)".into(),
                        ));
                    };
                    let resolved = u32::try_from(resolved)
                        .map_err(|_| fail(line, format!("vertex index {index} is too large")))?;
                    corners.push(resolved);
                }
                if corners.len() < 3 {
                    return Err(fail(
                        line,
                        format!(
                            "a face needs at least 3 corners, this one has {}",
                            corners.len()
                        ),
                    ));
                }
                fan_triangulate(&corners, &mut triangles);
            }
            _ => {}
        }
    }
    if let Some((line, index)) = largest {
        if index >= vertices.len() as u64 {
            return Err(fail(
                line,
                format!(
                    "face refers to vertex {} but the file defines {} vertices",
                    index + 1,
                    vertices.len()
                ),
            ));
        }
    }
    finish(vertices, triangles, source)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj_err(text: &str) -> String {
        let e = Mesh::from_obj(text.as_bytes(), Path::new("t.obj"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.obj: "),
            "error does not name the file: {e}"
        );
        e
    }

    #[test]
    fn obj_with_negative_and_slashed_indices() {
        let text = "# a square\no square\nv 0 0 0\nv 1 0 0\nv 1 1 0.5 1.0\nv 0 1 0\n\
                    vt 0 0\nvn 0 0 1\ns off\nf 1/1/1 2//1 3/1 4\nf -2 -1 -4 # fan of the last\n";
        let m = Mesh::from_obj(text.as_bytes(), Path::new("t.obj")).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.vertices[2], Vector3::new(1.0, 1.0, 0.5));
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [2, 3, 0]]);
        // Forward references are legal in OBJ.
        let m = Mesh::from_obj(b"f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", Path::new("t.obj"));
        assert_eq!(m.unwrap().triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn malformed_obj_gives_clear_errors() {
        let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let cases = [
            (
                format!("{v}f 1 2 4\n"),
                "line 4: face refers to vertex 4 but the file defines 3",
            ),
            (format!("{v}f 0 1 2\n"), "line 4: vertex index 0 is invalid"),
            (
                format!("{v}f -1 -2 -4\n"),
                "relative index -4 reaches before the first vertex",
            ),
            (format!("{v}f 1 2\n"), "at least 3 corners, this one has 2"),
            (
                format!("{v}f 1 two 3\n"),
                "face corner 'two' is not a vertex index",
            ),
            (format!("{v}f 1 2 99999999999\n"), "too large"),
            ("v 0 0\n".to_string(), "needs three coordinates"),
            ("v 0 x 0\n".to_string(), "'x' is not a number"),
            ("v 0 NaN 0\n".to_string(), "line 1: vertex 1 has a NaN"),
            (v.to_string(), "no faces"),
            (format!("{v}f 1 1 2\n"), "no faces (or only degenerate"),
            ("f 1 2 3\n".to_string(), "file defines 0 vertices"),
            ("".to_string(), "no vertices"),
        ];
        for (text, expected) in cases {
            let e = obj_err(&text);
            assert!(e.contains(expected), "expected '{expected}' in: {e}");
        }
    }
}

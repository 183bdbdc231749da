//! A depth map as a triangle mesh in Wavefront OBJ text.

use crate::error::{Error, Result};
use crate::grid::{Image, Mask};
use crate::surface::world_xy;
use std::io::Write;
use std::path::Path;

/// The masked part of `depth` as a Wavefront OBJ mesh: one vertex per masked pixel at world
/// (x, y, z) (x right, y up, z toward the viewer, pixel units, origin at the image centre), and
/// two triangles per 2×2 block of masked pixels (one where only three are masked), wound
/// counter-clockwise as seen by the viewer so that face normals point toward +z.
pub fn mesh_obj(depth: &Image, mask: &Mask) -> Result<String> {
    let mut bytes = Vec::new();
    write_mesh_obj(depth, mask, &mut bytes, Path::new("surface.obj"))?;
    String::from_utf8(bytes)
        .map_err(|e| Error::Compute(format!("internal: OBJ text is not UTF-8: {e}")))
}

/// [`mesh_obj`] written straight to `out` (a buffered file, say), without holding the text in
/// memory: at 1024² the text is tens of megabytes. `path` names the destination in errors.
pub fn write_mesh_obj(depth: &Image, mask: &Mask, out: &mut dyn Write, path: &Path) -> Result<()> {
    if !depth.same_size(mask) {
        return Err(Error::invalid(format!(
            "depth map is {}x{} but the mask is {}x{}",
            depth.width(),
            depth.height(),
            mask.width(),
            mask.height()
        )));
    }
    let (w, h) = (depth.width(), depth.height());
    let io = |e| Error::io(path, e);
    let mut index = vec![0usize; w * h];
    writeln!(
        out,
        "# shadelab {} surface: x right, y up, z toward the viewer (pixels)",
        crate::io::PROGRAM_VERSION
    )
    .map_err(io)?;
    let mut next = 1;
    for r in 0..h {
        for c in 0..w {
            if *mask.get(c, r) {
                let (x, y) = world_xy(c, r, w, h);
                writeln!(out, "v {x} {y} {}", depth.get(c, r)).map_err(io)?;
                index[r * w + c] = next;
                next += 1;
            }
        }
    }
    for r in 0..h.saturating_sub(1) {
        for c in 0..w.saturating_sub(1) {
            // a b (row r) over cc d (row r + 1); a → cc → d and a → d → b are counter-clockwise
            // in world axes, where row r + 1 lies below row r.
            let a = index[r * w + c];
            let b = index[r * w + c + 1];
            let cc = index[(r + 1) * w + c];
            let d = index[(r + 1) * w + c + 1];
            let faces: &[[usize; 3]] = match (a > 0, b > 0, cc > 0, d > 0) {
                (true, true, true, true) => &[[a, cc, d], [a, d, b]],
                (false, true, true, true) => &[[b, cc, d]],
                (true, false, true, true) => &[[a, cc, d]],
                (true, true, false, true) => &[[a, d, b]],
                (true, true, true, false) => &[[a, cc, b]],
                _ => &[],
            };
            for f in faces {
                writeln!(out, "f {} {} {}", f[0], f[1], f[2]).map_err(io)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    /// The vertices and faces of an OBJ text.
    fn parse(text: &str) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
        let mut v = Vec::new();
        let mut f = Vec::new();
        for line in text.lines() {
            let mut parts = line.split_whitespace();
            match parts.next() {
                Some("v") => {
                    let p: Vec<f64> = parts.map(|s| s.parse().unwrap()).collect();
                    v.push([p[0], p[1], p[2]]);
                }
                Some("f") => {
                    let p: Vec<usize> = parts.map(|s| s.parse().unwrap()).collect();
                    f.push([p[0], p[1], p[2]]);
                }
                _ => {}
            }
        }
        (v, f)
    }

    #[test]
    fn faces_cover_the_mask_and_face_the_viewer() {
        let depth = Grid::from_fn(4, 3, |c, r| (c + 10 * r) as f64);
        let mut mask = Grid::new(4, 3, true);
        *mask.get_mut(3, 2) = false;
        let (v, f) = parse(&mesh_obj(&depth, &mask).unwrap());
        assert_eq!(v.len(), 11);
        // 6 blocks, one of which has 3 masked pixels: 5 × 2 + 1 triangles.
        assert_eq!(f.len(), 11);
        // The first vertex is the top-left pixel at world (−1.5, 1).
        assert_eq!(v[0], [-1.5, 1.0, 0.0]);
        for tri in &f {
            let [a, b, c] = tri.map(|i| v[i - 1]);
            let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(cross > 0.0, "triangle {tri:?} is wound clockwise");
        }
        assert!(mesh_obj(&depth, &Grid::new(3, 3, true)).is_err());
    }
}

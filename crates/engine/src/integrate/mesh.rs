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
///
/// The text is formatted in bands of rows on the worker threads and written in order, a few
/// bands at a time: the same bytes for any number of threads.
pub fn write_mesh_obj(depth: &Image, mask: &Mask, out: &mut dyn Write, path: &Path) -> Result<()> {
    depth.check_same_size("depth map is", mask, "the mask is")?;
    let (w, h) = (depth.width(), depth.height());
    let io = |e| Error::io(path, e);
    writeln!(
        out,
        "# shadelab {} surface: x right, y up, z toward the viewer (pixels)",
        crate::io::PROGRAM_VERSION
    )
    .map_err(io)?;
    // The number of the first vertex of each row (vertices are numbered from 1 in row-major
    // order over the masked pixels).
    let mut first = Vec::with_capacity(h + 1);
    let mut next = 1;
    for row in mask.data().chunks(w.max(1)).take(h) {
        first.push(next);
        next += row.iter().filter(|&&m| m).count();
    }
    first.push(next);
    let vertices = |rows: std::ops::Range<usize>| {
        let mut text = Vec::with_capacity(rows.len() * w * 40);
        for r in rows {
            for c in 0..w {
                if *mask.get(c, r) {
                    let (x, y) = world_xy(c, r, w, h);
                    text.extend_from_slice(b"v ");
                    push_number(&mut text, x);
                    text.push(b' ');
                    push_number(&mut text, y);
                    // Infallible: writing to a Vec.
                    let _ = writeln!(text, " {}", depth.get(c, r));
                }
            }
        }
        text
    };
    // The vertex numbers of row r (0 where the pixel is not in the mask).
    let numbers = |r: usize, into: &mut Vec<usize>| {
        into.clear();
        let mut n = first[r];
        into.extend(mask.data()[r * w..(r + 1) * w].iter().map(|&m| {
            if m {
                n += 1;
                n - 1
            } else {
                0
            }
        }));
    };
    let faces = |rows: std::ops::Range<usize>| {
        let mut text = Vec::with_capacity(rows.len() * w * 24);
        let (mut upper, mut lower) = (Vec::new(), Vec::new());
        for r in rows {
            numbers(r, &mut upper);
            numbers(r + 1, &mut lower);
            for c in 0..w.saturating_sub(1) {
                // a b (row r) over cc d (row r + 1); a → cc → d and a → d → b are
                // counter-clockwise in world axes, where row r + 1 lies below row r.
                let (a, b, cc, d) = (upper[c], upper[c + 1], lower[c], lower[c + 1]);
                let faces: &[[usize; 3]] = match (a > 0, b > 0, cc > 0, d > 0) {
                    (true, true, true, true) => &[[a, cc, d], [a, d, b]],
                    (false, true, true, true) => &[[b, cc, d]],
                    (true, false, true, true) => &[[a, cc, d]],
                    (true, true, false, true) => &[[a, d, b]],
                    (true, true, true, false) => &[[a, cc, b]],
                    _ => &[],
                };
                for f in faces {
                    text.push(b'f');
                    for &v in f {
                        text.push(b' ');
                        push_whole(&mut text, v as u64);
                    }
                    text.push(b'\n');
                }
            }
        }
        text
    };
    write_in_bands(h, out, &vertices).map_err(io)?;
    write_in_bands(h.saturating_sub(1), out, &faces).map_err(io)
}

/// Rows per band of [`write_mesh_obj`]'s text.
const BAND_ROWS: usize = 8;

/// Writes `text` of the bands of [`BAND_ROWS`] rows of `rows` in order, formatting two bands
/// per worker thread at a time (a few megabytes of text at 1024², whatever the image size).
fn write_in_bands(
    rows: usize,
    out: &mut dyn Write,
    text: &(dyn Fn(std::ops::Range<usize>) -> Vec<u8> + Sync),
) -> std::io::Result<()> {
    use crate::parallel::prelude::*;
    let bands: Vec<std::ops::Range<usize>> = (0..rows)
        .step_by(BAND_ROWS)
        .map(|r| r..(r + BAND_ROWS).min(rows))
        .collect();
    for group in bands.chunks(2 * crate::parallel::threads().max(1)) {
        let texts: Vec<Vec<u8>> = group.par_iter().map(|band| text(band.clone())).collect();
        for t in &texts {
            out.write_all(t)?;
        }
    }
    Ok(())
}

/// Appends the decimal digits of `n`, as `Display` writes them (without its formatting
/// machinery, which took most of the time of writing the faces).
fn push_whole(text: &mut Vec<u8>, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut at = digits.len();
    loop {
        at -= 1;
        digits[at] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    text.extend_from_slice(&digits[at..]);
}

/// Appends `v` as `Display` writes it, quickly for the whole and half numbers that pixel
/// centres' world coordinates are.
fn push_number(text: &mut Vec<u8>, v: f64) {
    let a = v.abs();
    if a < 1e15 && (2.0 * a).fract() == 0.0 {
        if v.is_sign_negative() {
            text.push(b'-');
        }
        push_whole(text, a.trunc() as u64);
        if a.fract() != 0.0 {
            text.extend_from_slice(b".5");
        }
    } else {
        let _ = write!(text, "{v}");
    }
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

    #[test]
    fn whole_numbers_are_written_as_display_writes_them() {
        for n in [0, 1, 9, 10, 99, 100, 12_345, 1_048_576, u64::MAX] {
            let mut text = b"x".to_vec();
            push_whole(&mut text, n);
            assert_eq!(String::from_utf8(text).unwrap(), format!("x{n}"));
        }
    }

    #[test]
    fn whole_and_half_numbers_are_written_as_display_writes_them() {
        for v in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            3.0,
            -3.0,
            460.5,
            -16.5,
            1e14 + 0.5,
            0.25,
            1e20,
            -7.125,
        ] {
            let mut text = Vec::new();
            push_number(&mut text, v);
            assert_eq!(String::from_utf8(text).unwrap(), format!("{v}"), "{v}");
        }
    }

    #[test]
    fn the_text_does_not_depend_on_the_bands() {
        // More rows than one band of formatting, with a ragged mask: the numbering and faces
        // carry across band boundaries.
        let (w, h) = (9, 3 * BAND_ROWS + 5);
        let depth = Grid::from_fn(w, h, |c, r| (c * c) as f64 * 0.1 - r as f64 / 3.0);
        let mask = Grid::from_fn(w, h, |c, r| (c + 2 * r) % 7 != 0);
        let (v, f) = parse(&mesh_obj(&depth, &mask).unwrap());
        assert_eq!(v.len(), mask.count());
        // Vertex k is the k-th masked pixel in row-major order.
        let masked: Vec<(usize, usize)> = (0..h)
            .flat_map(|r| (0..w).map(move |c| (c, r)))
            .filter(|&(c, r)| *mask.get(c, r))
            .collect();
        for (k, &(c, r)) in masked.iter().enumerate() {
            let (x, y) = world_xy(c, r, w, h);
            assert_eq!(v[k], [x, y, *depth.get(c, r)]);
        }
        let mut expected = 0;
        for r in 0..h - 1 {
            for c in 0..w - 1 {
                let n = [(c, r), (c + 1, r), (c, r + 1), (c + 1, r + 1)]
                    .iter()
                    .filter(|&&(c, r)| *mask.get(c, r))
                    .count();
                expected += match n {
                    4 => 2,
                    3 => 1,
                    _ => 0,
                };
            }
        }
        assert_eq!(f.len(), expected);
        for tri in &f {
            let [a, b, c] = tri.map(|i| v[i - 1]);
            let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(cross > 0.0, "triangle {tri:?} is wound clockwise");
        }
    }
}

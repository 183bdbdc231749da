//! The pixel frame of a stimulus drawn in degrees: pixel-centre coordinates, snapping to the
//! pixel lattice, layouts of repeated elements, and exact light directions.
//!
//! Coordinates follow `docs/conventions.md`: x right, y up, in pixel units from the frame's
//! centre, so pixel (col, row) sits at x = col − (W−1)/2, y = (H−1)/2 − row. Lengths given in
//! degrees become pixels through the frame's ppd.

use crate::error::{Error, Result};
use crate::random::SplitMix64;
use crate::visual_size::Geometry;

/// Centres of a `rows` × `cols` array `spacing` pixels apart, centred in the frame and snapped
/// to pixel corners, in reading order (top row first).
pub(crate) fn grid_centres(
    frame: &Geometry,
    rows: usize,
    cols: usize,
    spacing: f64,
) -> Vec<(f64, f64)> {
    let mut v = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        for c in 0..cols {
            let x = (c as f64 - (cols as f64 - 1.0) / 2.0) * spacing;
            let y = ((rows as f64 - 1.0) / 2.0 - r as f64) * spacing;
            v.push(frame.snap(x, y));
        }
    }
    v
}

/// `count` centres placed at random (seeded) so that discs of `radius` pixels lie inside the
/// frame and no two centres are closer than `min_distance`; snapped to pixel corners and
/// returned in reading order. Fails, naming the stimulus, when they cannot all be placed.
pub(crate) fn random_centres(
    what: &str,
    frame: &Geometry,
    count: usize,
    radius: f64,
    min_distance: f64,
    seed: u64,
) -> Result<Vec<(f64, f64)>> {
    let mut rng = SplitMix64::new(seed);
    let (hw, hh) = (
        frame.width as f64 / 2.0 - radius - 0.5,
        frame.height as f64 / 2.0 - radius - 0.5,
    );
    let mut placed: Vec<(f64, f64)> = Vec::with_capacity(count);
    if hw > 0.0 && hh > 0.0 {
        let mut tries = 0usize;
        // A fixed budget of draws bounds the time an impossible request can take.
        while placed.len() < count && tries < 200_000 {
            tries += 1;
            let (x, y) = frame.snap(rng.uniform(-hw, hw), rng.uniform(-hh, hh));
            let clear = placed
                .iter()
                .all(|&(px, py)| (px - x).hypot(py - y) >= min_distance);
            // The half-pixel margin in hw, hh keeps snapped discs inside the frame.
            if clear {
                placed.push((x, y));
            }
        }
    }
    if placed.len() < count {
        return Err(Error::invalid(format!(
            "{what}: cannot place {count} discs of radius {:.2}° at least {:.2}° apart in {} (placed {}): enlarge the frame or lower the count",
            radius / frame.ppd,
            min_distance / frame.ppd,
            frame.size_text(),
            placed.len()
        )));
    }
    placed.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.total_cmp(&b.0)));
    Ok(placed)
}

/// 0 below `e0`, 1 above `e1`, the smooth Hermite step between (exactly 0 and 1 outside).
pub(crate) fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    if x <= e0 {
        0.0
    } else if x >= e1 {
        1.0
    } else {
        let t = (x - e0) / (e1 - e0);
        t * t * (3.0 - 2.0 * t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: usize, h: usize) -> Geometry {
        Geometry {
            width: w,
            height: h,
            ppd: 10.0,
        }
    }

    #[test]
    fn pixel_centres_and_corners() {
        let f = frame(4, 3);
        assert_eq!((f.x(0), f.x(3)), (-1.5, 1.5));
        assert_eq!((f.y(0), f.y(2)), (1.0, -1.0));
        // Corners of a 4-wide frame are at integers, of a 3-high one at half-integers.
        assert_eq!(f.snap(0.3, 0.2), (0.0, 0.5));
        assert_eq!(f.cols(-0.6, 0.6), 1..3);
        assert_eq!(f.rows(-0.2, 1.0), 0..2);
        assert_eq!(f.cols(5.0, 6.0), 0..0);
        assert_eq!(f.svg_xy(0.0, 0.0), (2.0, 1.5));
    }

    #[test]
    fn random_layout_is_seeded_and_separated() {
        let f = frame(200, 100);
        let a = random_centres("t", &f, 8, 6.0, 20.0, 3).unwrap();
        assert_eq!(a, random_centres("t", &f, 8, 6.0, 20.0, 3).unwrap());
        assert_ne!(a, random_centres("t", &f, 8, 6.0, 20.0, 4).unwrap());
        for (i, p) in a.iter().enumerate() {
            assert!(p.0.abs() + 6.0 <= 100.0 && p.1.abs() + 6.0 <= 50.0);
            for q in &a[i + 1..] {
                assert!((p.0 - q.0).hypot(p.1 - q.1) >= 20.0);
            }
        }
        let e = random_centres("circles", &f, 500, 6.0, 20.0, 3).unwrap_err();
        assert!(e.to_string().starts_with("circles: cannot place 500"));
    }

    #[test]
    fn rotation_and_steps() {
        let g = crate::grid::Grid::from_fn(3, 2, |c, r| (c + 10 * r) as u16);
        let r = g.rotated_180();
        assert_eq!(*r.get(0, 0), 12);
        assert_eq!(r.rotated_180(), g);
        assert_eq!(smoothstep(0.0, 1.0, -1.0), 0.0);
        assert_eq!(smoothstep(0.0, 1.0, 2.0), 1.0);
        assert_eq!(smoothstep(0.0, 1.0, 0.5), 0.5);
    }
}

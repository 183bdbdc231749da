//! Filling the holes of a scanned depth map: background pixels that the object encloses.
//!
//! A range scan drops out where the scanner saw nothing (deep folds, dark spots): the Mozart
//! depth map of the 1999 survey has 37 such holes inside the face and hair, 1 to 218 pixels
//! each, stored as depth 0 like the background. Left out of the mask they would cut the face
//! into a lace of small occluding contours, each of which the occluding boundary condition
//! would pin to the limb (a normal edge-on to the viewer), which the surface there is not.
//! So a background pixel that cannot be reached from the image frame through background
//! (4-connected) is a hole: it joins the solver's domain, with its depth interpolated from
//! the surrounding surface by the discrete Laplace equation (the smoothest fill, a membrane
//! stretched over the hole). Its true depth is unknown, so it is left out of every error.

use crate::grid::{Grid, Image, Mask};
use crate::imageops::{fill_holes, parts};

/// A depth map whose enclosed holes have been filled.
#[derive(Debug, Clone, PartialEq)]
pub struct FilledDepth {
    /// The depth with every hole interpolated.
    pub depth: Image,
    /// The object's pixels and the holes: the domain to solve on.
    pub domain: Mask,
    /// The pixels that were holes.
    pub holes: Mask,
    /// The number of separate holes.
    pub hole_count: usize,
}

/// Gauss–Seidel sweeps at most; a 218-pixel hole settles to 1e-9 in a few hundred.
const MAX_SWEEPS: usize = 20_000;

/// Fills the background pixels of `mask` that the object encloses (see the module docs).
/// `depth` and `mask` must have the same size (checked by the caller).
pub fn fill_enclosed_holes(depth: &Image, mask: &Mask) -> FilledDepth {
    let (w, h) = (mask.width(), mask.height());
    // The object and the background the frame cannot reach.
    let domain = fill_holes(mask);
    let holes = Grid::from_fn(w, h, |c, r| *domain.get(c, r) && !*mask.get(c, r));
    let hole_count = parts(&holes).count();

    let mut depth = Grid::from_fn(w, h, |c, r| {
        if *mask.get(c, r) {
            *depth.get(c, r)
        } else {
            0.0
        }
    });
    let hole_pixels: Vec<(usize, usize)> = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .filter(|&(c, r)| *holes.get(c, r))
        .collect();
    // Start from the mean of the rim around each pixel's hole, approximated by the mean of
    // all object pixels bordering any hole: good enough, the sweeps do the rest.
    let (sum, n) = hole_pixels
        .iter()
        .flat_map(|&(c, r)| neighbours(c, r, w, h))
        .filter(|&(c, r)| *mask.get(c, r))
        .fold((0.0, 0usize), |(s, n), (c, r)| (s + depth.get(c, r), n + 1));
    let start = if n > 0 { sum / n as f64 } else { 0.0 };
    for &(c, r) in &hole_pixels {
        *depth.get_mut(c, r) = start;
    }
    for _ in 0..MAX_SWEEPS {
        let mut largest: f64 = 0.0;
        for &(c, r) in &hole_pixels {
            // Every neighbour of a hole pixel is in the domain (a hole is enclosed).
            let (s, k) = neighbours(c, r, w, h)
                .into_iter()
                .fold((0.0, 0usize), |(s, k), (nc, nr)| {
                    (s + depth.get(nc, nr), k + 1)
                });
            let v = s / k as f64;
            largest = largest.max((v - depth.get(c, r)).abs());
            *depth.get_mut(c, r) = v;
        }
        if largest < 1e-9 {
            break;
        }
    }
    FilledDepth {
        depth,
        domain,
        holes,
        hole_count,
    }
}

/// The 4-neighbours of (`c`, `r`) inside a `w` × `h` grid.
fn neighbours(c: usize, r: usize, w: usize, h: usize) -> Vec<(usize, usize)> {
    let mut v = Vec::with_capacity(4);
    if c > 0 {
        v.push((c - 1, r));
    }
    if c + 1 < w {
        v.push((c + 1, r));
    }
    if r > 0 {
        v.push((c, r - 1));
    }
    if r + 1 < h {
        v.push((c, r + 1));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enclosed_holes_are_filled_and_the_background_is_not() {
        // A 7×5 object on a 9×7 frame with a one-pixel hole and a two-pixel hole; the depth is
        // the plane z = col + 2·row, which the Laplace fill reproduces exactly.
        let (w, h) = (9, 7);
        let mut mask = Grid::from_fn(w, h, |c, r| (1..8).contains(&c) && (1..6).contains(&r));
        for (c, r) in [(3, 3), (5, 2), (6, 2)] {
            *mask.get_mut(c, r) = false;
        }
        let plane = |c: usize, r: usize| c as f64 + 2.0 * r as f64;
        let depth = Grid::from_fn(w, h, |c, r| if *mask.get(c, r) { plane(c, r) } else { 0.0 });
        let f = fill_enclosed_holes(&depth, &mask);
        assert_eq!(f.hole_count, 2);
        assert_eq!(f.holes.count(), 3);
        assert_eq!(f.domain.count(), 35);
        for (c, r) in [(3, 3), (5, 2), (6, 2)] {
            assert!(*f.holes.get(c, r));
            assert!((f.depth.get(c, r) - plane(c, r)).abs() < 1e-6);
        }
        assert!(!*f.domain.get(0, 0));
        // A gap open to the frame is background, not a hole.
        let mut open = mask.clone();
        *open.get_mut(1, 3) = false;
        *open.get_mut(2, 3) = false;
        *open.get_mut(3, 3) = false;
        let f = fill_enclosed_holes(&depth, &open);
        assert_eq!(f.hole_count, 1);
        assert!(!*f.domain.get(3, 3));
    }
}

//! Cropping a problem to its object: the solver's work and the pictures' size follow the
//! object, not the frame (the DiLiGenT ball fills 142 × 142 of a 612 × 512 photograph).

use crate::error::{Error, Result};
use crate::grid::{Grid, Mask};

/// A rectangle of a larger grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crop {
    /// First column.
    pub col: usize,
    /// First row.
    pub row: usize,
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
}

impl Crop {
    /// The bounding box of `mask` grown by `margin` pixels on every side, clipped to the
    /// frame. With a margin of at least 1 an object that does not touch the frame still does
    /// not, so its silhouette stays an occluding contour; one that does is still cut by the
    /// frame where it was. Fails on an empty mask.
    pub fn around(mask: &Mask, margin: usize) -> Result<Crop> {
        let (w, h) = (mask.width(), mask.height());
        let (mut c0, mut r0, mut c1, mut r1) = (usize::MAX, usize::MAX, 0, 0);
        for r in 0..h {
            for c in 0..w {
                if *mask.get(c, r) {
                    c0 = c0.min(c);
                    r0 = r0.min(r);
                    c1 = c1.max(c);
                    r1 = r1.max(r);
                }
            }
        }
        if c0 == usize::MAX {
            return Err(Error::invalid("the mask is empty: nothing to crop to"));
        }
        let (col, row) = (c0.saturating_sub(margin), r0.saturating_sub(margin));
        let (end_c, end_r) = ((c1 + margin + 1).min(w), (r1 + margin + 1).min(h));
        Ok(Crop {
            col,
            row,
            width: end_c - col,
            height: end_r - row,
        })
    }

    /// The part of `grid` inside the rectangle (which must lie inside `grid`).
    pub fn apply<T: Clone>(&self, grid: &Grid<T>) -> Grid<T> {
        Grid::from_fn(self.width, self.height, |c, r| {
            grid.get(self.col + c, self.row + r).clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_keeps_a_margin_and_clips_to_the_frame() {
        let mask = Grid::from_fn(10, 8, |c, r| (3..6).contains(&c) && (2..4).contains(&r));
        let crop = Crop::around(&mask, 1).unwrap();
        assert_eq!(
            crop,
            Crop {
                col: 2,
                row: 1,
                width: 5,
                height: 4
            }
        );
        let cut = crop.apply(&mask);
        assert_eq!(cut.count(), mask.count());
        assert!(!*cut.get(0, 0) && *cut.get(1, 1));
        let wide = Crop::around(&mask, 5).unwrap();
        assert_eq!((wide.col, wide.row, wide.width, wide.height), (0, 0, 10, 8));
        assert!(Crop::around(&Grid::new(3, 3, false), 1).is_err());
    }
}

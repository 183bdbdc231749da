//! Compositing pictures: two side by side, and a picture reduced by block averaging.

use crate::grid::{Grid, RgbImage};

/// `left` and `right` side by side, `gap` columns of `fill` between them, top-aligned (the
/// shorter one padded with `fill` below).
///
/// ```
/// use shadelab_engine::imageops::side_by_side;
/// use shadelab::Grid;
/// let (a, b) = ([1.0; 3], [0.5; 3]);
/// let left = Grid::new(1, 2, a);
/// let right = Grid::new(2, 1, b);
/// let both = side_by_side(&left, &right, 1, [0.0; 3]);
/// assert_eq!((both.width(), both.height()), (4, 2));
/// assert_eq!(both.row(0), &[a, [0.0; 3], b, b]);
/// assert_eq!(both.row(1), &[a, [0.0; 3], [0.0; 3], [0.0; 3]]);
/// ```
pub fn side_by_side(left: &RgbImage, right: &RgbImage, gap: usize, fill: [f64; 3]) -> RgbImage {
    let (w, h) = (
        left.width() + gap + right.width(),
        left.height().max(right.height()),
    );
    Grid::from_fn(w, h, |c, r| {
        if c < left.width() {
            left.checked(c as isize, r as isize)
                .copied()
                .unwrap_or(fill)
        } else if c >= left.width() + gap {
            let cc = (c - left.width() - gap) as isize;
            right.checked(cc, r as isize).copied().unwrap_or(fill)
        } else {
            fill
        }
    })
}

/// `image` reduced by an integer `factor` by averaging factor × factor blocks (edge blocks
/// average what they hold); a factor of 0 or 1 returns it unchanged.
///
/// ```
/// use shadelab_engine::imageops::shrink;
/// use shadelab::Grid;
/// let img = Grid::from_vec(3, 2, vec![[0.0; 3], [1.0; 3], [0.5; 3],
///                                     [1.0; 3], [0.0; 3], [0.25; 3]]).unwrap();
/// let small = shrink(&img, 2);
/// assert_eq!((small.width(), small.height()), (2, 1));
/// assert_eq!(small.row(0), &[[0.5; 3], [0.375; 3]]);
/// ```
pub fn shrink(image: &RgbImage, factor: usize) -> RgbImage {
    let f = factor.max(1);
    if f == 1 {
        return image.clone();
    }
    let (w, h) = (image.width().div_ceil(f), image.height().div_ceil(f));
    Grid::from_fn(w, h, |c, r| {
        let mut sum = [0.0; 3];
        let mut n = 0.0;
        for rr in r * f..((r + 1) * f).min(image.height()) {
            for cc in c * f..((c + 1) * f).min(image.width()) {
                let p = image.get(cc, rr);
                for k in 0..3 {
                    sum[k] += p[k];
                }
                n += 1.0;
            }
        }
        sum.map(|v| v / n)
    })
}

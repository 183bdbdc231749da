//! Hole filling: a mask plus every background pixel that the image frame cannot reach.

use super::parts::parts;
use crate::grid::Mask;

/// `mask` with its holes filled: a background part (4-connected) that touches no side of the
/// image is a hole and becomes part of the mask.
///
/// ```
/// use shadelab_engine::imageops::fill_holes;
/// use shadelab::Grid;
/// // A ring with a one-pixel hole, and a notch open to the frame at the top right.
/// let ring = Grid::from_vec(5, 4, vec![
///     true, true,  true, false, false,
///     true, false, true, true,  false,
///     true, true,  true, true,  false,
///     false, false, false, false, false,
/// ]).unwrap();
/// let filled = fill_holes(&ring);
/// assert!(*filled.get(1, 1));
/// assert!(!*filled.get(3, 0));
/// assert_eq!(filled.count(), ring.count() + 1);
/// ```
pub fn fill_holes(mask: &Mask) -> Mask {
    let (w, h) = (mask.width(), mask.height());
    let background = parts(&mask.map(|&m| !m));
    let mut filled = mask.clone();
    for part in background.iter() {
        let enclosed = part.iter().all(|&i| {
            let (c, r) = (i % w, i / w);
            c > 0 && r > 0 && c + 1 < w && r + 1 < h
        });
        if enclosed {
            for &i in part {
                filled.data_mut()[i] = true;
            }
        }
    }
    filled
}

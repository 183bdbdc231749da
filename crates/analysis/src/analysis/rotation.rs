//! Quarter-turn rotation of pictures, exact on the pixel lattice.
//!
//! Turning a picture counter-clockwise by 90° moves a light from above to the left: tilt t
//! becomes t + 90°. The observer relies on that (one sweep serves every rotation); these
//! rotations let a test check it against real solves of turned pictures.

use crate::grid::Grid;

/// `grid` turned counter-clockwise by `quarter_turns` × 90° (negative turns go clockwise). A
/// W × H grid becomes H × W after an odd number of turns.
pub fn rotate_quarter_turns<T: Clone>(grid: &Grid<T>, quarter_turns: i32) -> Grid<T> {
    let (w, h) = (grid.width(), grid.height());
    match quarter_turns.rem_euclid(4) {
        0 => grid.clone(),
        // Counter-clockwise: the top-right corner goes to the top-left.
        1 => Grid::from_fn(h, w, |c, r| grid.get(w - 1 - r, c).clone()),
        2 => grid.rotated_180(),
        _ => Grid::from_fn(h, w, |c, r| grid.get(r, h - 1 - c).clone()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turns_compose_and_move_corners_counter_clockwise() {
        let g = Grid::from_fn(3, 2, |c, r| r * 3 + c);
        // 0 1 2      2 5
        // 3 4 5  ->  1 4
        //            0 3
        let ccw = rotate_quarter_turns(&g, 1);
        assert_eq!((ccw.width(), ccw.height()), (2, 3));
        assert_eq!(ccw.data(), &[2, 5, 1, 4, 0, 3]);
        assert_eq!(rotate_quarter_turns(&g, 2), g.rotated_180());
        assert_eq!(rotate_quarter_turns(&ccw, 3), g);
        assert_eq!(rotate_quarter_turns(&g, -1), rotate_quarter_turns(&g, 3));
        assert_eq!(
            rotate_quarter_turns(&rotate_quarter_turns(&g, 1), 1),
            g.rotated_180()
        );
    }
}

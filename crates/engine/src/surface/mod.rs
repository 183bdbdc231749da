//! Surfaces: a heightfield on the pixel grid with its mask and unit normals.
//!
//! Pixel (col, row) of a W × H grid sits at world x = col − (W−1)/2, y = (H−1)/2 − row (pixel
//! units, y up); depth z is in pixel units toward the viewer. Normals are analytic where a
//! shape knows them, else central finite differences of the depth inside the mask.

mod mesh;
mod npy_depth;
mod shapes;

pub use mesh::{view_rotation, Mesh, MeshShading, Projection, MAX_FILL, MAX_MESH_BYTES};
pub use npy_depth::{depth_surface, load_depth_surface, read_depth_npy, DepthDomain};
pub use shapes::{ellipsoid, gaussian, sphere, vase, vase_profile};

use crate::error::{Error, Result};
use crate::gradient_space::{normal_from_pq, Normal};
use crate::grid::{Grid, Image, Mask};
use nalgebra::Vector3;

/// A visible surface: depth, unit normals and the domain where the object is.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Depth toward the viewer in pixel units (0 outside the mask).
    pub depth: Image,
    /// Unit normals ((0, 0, 1) outside the mask).
    pub normals: Grid<Normal>,
    /// Where the object is.
    pub mask: Mask,
}

/// World coordinates (x right, y up, pixel units, origin at the grid centre) of pixel
/// (`col`, `row`) in a `width` × `height` grid.
pub fn world_xy(col: usize, row: usize, width: usize, height: usize) -> (f64, f64) {
    (
        col as f64 - (width as f64 - 1.0) / 2.0,
        (height as f64 - 1.0) / 2.0 - row as f64,
    )
}

impl Surface {
    /// A surface from a function of world (x, y) returning depth and unit normal, or `None`
    /// outside the object.
    pub fn from_fn(
        width: usize,
        height: usize,
        f: impl Fn(f64, f64) -> Option<(f64, Normal)>,
    ) -> Surface {
        let mut depth = Grid::new(width, height, 0.0);
        let mut normals = Grid::new(width, height, Vector3::z());
        let mut mask = Grid::new(width, height, false);
        for row in 0..height {
            for col in 0..width {
                let (x, y) = world_xy(col, row, width, height);
                if let Some((z, n)) = f(x, y) {
                    *depth.get_mut(col, row) = z;
                    *normals.get_mut(col, row) = n;
                    *mask.get_mut(col, row) = true;
                }
            }
        }
        Surface {
            depth,
            normals,
            mask,
        }
    }

    /// A surface from a depth map and mask, normals by finite differences: central where
    /// both neighbours are inside the mask, one-sided where only one is, flat where neither.
    pub fn from_depth(depth: Image, mask: Mask) -> Result<Surface> {
        depth.check_same_size("depth map is", &mask, "its mask is")?;
        if depth.data().iter().any(|v| !v.is_finite()) {
            return Err(Error::invalid("depth map holds NaN or infinite values"));
        }
        let (w, h) = (depth.width(), depth.height());
        let inside = |c: isize, r: isize| mask.checked(c, r).copied().unwrap_or(false);
        let z = |c: isize, r: isize| *depth.get(c as usize, r as usize);
        let slope = |c: isize, r: isize, dc: isize, dr: isize| -> f64 {
            // Derivative of z along +col (dc=1) or +row (dr=1), per pixel.
            let (fwd, bwd) = (inside(c + dc, r + dr), inside(c - dc, r - dr));
            match (fwd, bwd) {
                (true, true) => (z(c + dc, r + dr) - z(c - dc, r - dr)) / 2.0,
                (true, false) => z(c + dc, r + dr) - z(c, r),
                (false, true) => z(c, r) - z(c - dc, r - dr),
                (false, false) => 0.0,
            }
        };
        let normals = Grid::from_fn(w, h, |col, row| {
            let (c, r) = (col as isize, row as isize);
            if !inside(c, r) {
                return Vector3::z();
            }
            let dz_dx = slope(c, r, 1, 0);
            // world y = −row, so ∂z/∂y = −∂z/∂row.
            let dz_dy = -slope(c, r, 0, 1);
            normal_from_pq(-dz_dx, -dz_dy)
        });
        let depth = Grid::from_fn(w, h, |c, r| {
            if *mask.get(c, r) {
                *depth.get(c, r)
            } else {
                0.0
            }
        });
        Ok(Surface {
            depth,
            normals,
            mask,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.depth.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.depth.height()
    }

    /// The same surface with depth negated (convex ↔ hollow): normals (n_x, n_y, n_z) become
    /// (−n_x, −n_y, n_z).
    pub fn negated(&self) -> Surface {
        Surface {
            depth: self.depth.map(|z| -z),
            normals: self.normals.map(|n| Vector3::new(-n.x, -n.y, n.z)),
            mask: self.mask.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_space::angle_deg;

    #[test]
    fn finite_difference_normals_of_a_plane() {
        // z = 0.5 x + 0.25 y  =>  p = −0.5, q = −0.25 everywhere.
        let (w, h) = (9, 7);
        let depth = Grid::from_fn(w, h, |c, r| {
            let (x, y) = world_xy(c, r, w, h);
            0.5 * x + 0.25 * y
        });
        let s = Surface::from_depth(depth, Grid::new(w, h, true)).unwrap();
        let expect = normal_from_pq(-0.5, -0.25);
        for n in s.normals.data() {
            assert!(angle_deg(n, &expect) < 1e-9);
        }
    }

    #[test]
    fn mismatched_or_nan_depth_is_rejected() {
        assert!(Surface::from_depth(Grid::new(3, 3, 0.0), Grid::new(3, 4, true)).is_err());
        assert!(Surface::from_depth(Grid::new(3, 3, f64::NAN), Grid::new(3, 3, true)).is_err());
    }
}

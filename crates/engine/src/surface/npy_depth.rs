//! Depth maps from NumPy `.npy` files: an H × W array of depth in pixel units toward the
//! viewer, row 0 at the top, read by [`crate::io::read_image`] (which checks the header before
//! trusting it), and the domain of the object in it.

use super::Surface;
use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Mask, DEFAULT_MAX_PIXELS};
use std::path::Path;

/// Which pixels of a depth map belong to the object.
#[derive(Debug, Clone, PartialEq)]
pub enum DepthDomain {
    /// Every pixel.
    All,
    /// Pixels whose depth is not exactly zero: zero marks the background, as in the depth maps
    /// of the shape-from-shading survey (Zhang et al. 1999).
    NonZero,
    /// The given mask, which must have the map's size.
    Mask(Mask),
}

/// Reads an H × W `.npy` depth map (any real dtype, either memory order); NaN or infinite
/// values are an error.
pub fn read_depth_npy(path: impl AsRef<Path>) -> Result<Image> {
    crate::io::read_image(path.as_ref(), DEFAULT_MAX_PIXELS)
}

/// A surface from a depth map over `domain`, normals by finite differences
/// ([`Surface::from_depth`]); an empty domain is an error.
pub fn depth_surface(depth: Image, domain: DepthDomain) -> Result<Surface> {
    let mask = match domain {
        DepthDomain::All => Grid::new(depth.width(), depth.height(), true),
        DepthDomain::NonZero => depth.map(|&z| z != 0.0),
        DepthDomain::Mask(mask) => mask,
    };
    if !mask.data().contains(&true) {
        return Err(Error::invalid(
            "the depth map's domain is empty (no pixel is inside the object)",
        ));
    }
    Surface::from_depth(depth, mask)
}

/// Reads a `.npy` depth map and makes it a surface over `domain` (see [`depth_surface`]).
pub fn load_depth_surface(path: impl AsRef<Path>, domain: DepthDomain) -> Result<Surface> {
    let path = path.as_ref();
    let depth = read_depth_npy(path)?;
    depth_surface(depth, domain).map_err(|e| Error::format(path, e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_background_and_given_masks_set_the_domain() {
        let depth = Grid::from_vec(3, 2, vec![0., 2., 0., 0., 3., 4.]).unwrap();
        let s = depth_surface(depth.clone(), DepthDomain::NonZero).unwrap();
        assert_eq!(s.mask.data(), &[false, true, false, false, true, true]);
        let s = depth_surface(depth.clone(), DepthDomain::All).unwrap();
        assert_eq!(s.mask.count(), 6);
        let given = Grid::from_vec(3, 2, vec![true, false, false, false, false, false]).unwrap();
        let s = depth_surface(depth.clone(), DepthDomain::Mask(given)).unwrap();
        assert_eq!(s.mask.count(), 1);
        assert!(depth_surface(Grid::new(3, 2, 0.0), DepthDomain::NonZero).is_err());
        assert!(depth_surface(depth, DepthDomain::Mask(Grid::new(2, 2, true))).is_err());
    }
}

//! Bilinear sampling of an image at fractional positions.

use crate::grid::Image;

/// `image` sampled at fractional (`x`, `y`) = (column, row), bilinearly between the four
/// nearest pixel centres; positions outside the image are clamped to its edge.
///
/// ```
/// use shadelab_engine::imageops::bilinear;
/// use shadelab::Grid;
/// let img = Grid::from_vec(2, 2, vec![0.0, 1.0, 2.0, 3.0]).unwrap();
/// assert_eq!(bilinear(&img, 0.5, 0.0), 0.5);
/// assert_eq!(bilinear(&img, 0.5, 0.5), 1.5);
/// assert_eq!(bilinear(&img, 1.0, 1.0), 3.0);
/// assert_eq!(bilinear(&img, -4.0, 9.0), 2.0); // clamped to the bottom-left pixel
/// ```
pub fn bilinear(image: &Image, x: f64, y: f64) -> f64 {
    let (w, h) = (image.width(), image.height());
    let x = x.clamp(0.0, (w - 1) as f64);
    let y = y.clamp(0.0, (h - 1) as f64);
    let (c0, r0) = (x.floor() as usize, y.floor() as usize);
    let (c1, r1) = ((c0 + 1).min(w - 1), (r0 + 1).min(h - 1));
    let (fx, fy) = (x - c0 as f64, y - r0 as f64);
    let top = image.get(c0, r0) * (1.0 - fx) + image.get(c1, r0) * fx;
    let bottom = image.get(c0, r1) * (1.0 - fx) + image.get(c1, r1) * fx;
    top * (1.0 - fy) + bottom * fy
}

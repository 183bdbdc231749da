//! Separable Gaussian blur with edge-replicating borders.

use crate::grid::{Grid, Image};
use crate::parallel::prelude::*;

/// `image` blurred by a Gaussian of σ `sigma_px` pixels (taps out to 4σ, normalised to unit
/// sum), rows first, then columns; the image is extended by repeating its edge pixels. A σ
/// of zero or less returns the image unchanged.
///
/// ```
/// use shadelab_engine::imageops::gaussian_blur;
/// use shadelab::Grid;
/// // A constant stays constant (the borders repeat the edge), and a blur keeps the sum of
/// // an impulse far from the edges.
/// let flat = gaussian_blur(&Grid::new(4, 3, 0.25), 1.0);
/// assert!(flat.data().iter().all(|v| (v - 0.25).abs() < 1e-15));
/// let mut dot = Grid::new(9, 9, 0.0);
/// *dot.get_mut(4, 4) = 1.0;
/// let b = gaussian_blur(&dot, 0.5);
/// assert!((b.data().iter().sum::<f64>() - 1.0).abs() < 1e-12);
/// assert!(b.get(4, 4) > b.get(3, 4) && b.get(3, 4) == b.get(5, 4));
/// assert_eq!(gaussian_blur(&dot, 0.0), dot);
/// ```
pub fn gaussian_blur(image: &Image, sigma_px: f64) -> Image {
    let (w, h) = (image.width(), image.height());
    if sigma_px <= 0.0 {
        return image.clone();
    }
    let radius = (4.0 * sigma_px).ceil() as isize;
    let taps: Vec<f64> = (-radius..=radius)
        .map(|d| (-(d * d) as f64 / (2.0 * sigma_px * sigma_px)).exp())
        .collect();
    let total: f64 = taps.iter().sum();
    let taps: Vec<f64> = taps.iter().map(|t| t / total).collect();
    let mut rows = vec![0.0; w * h];
    rows.par_chunks_mut(w).enumerate().for_each(|(r, out)| {
        let src = image.row(r);
        for (c, o) in out.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (k, t) in taps.iter().enumerate() {
                let cc = (c as isize + k as isize - radius).clamp(0, w as isize - 1) as usize;
                acc += t * src[cc];
            }
            *o = acc;
        }
    });
    let mut out = vec![0.0; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(r, o)| {
        for (k, t) in taps.iter().enumerate() {
            let rr = (r as isize + k as isize - radius).clamp(0, h as isize - 1) as usize;
            for (ov, v) in o.iter_mut().zip(&rows[rr * w..(rr + 1) * w]) {
                *ov += t * v;
            }
        }
    });
    Grid::from_fn(w, h, |c, r| out[r * w + c])
}

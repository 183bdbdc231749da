//! Colour maps for figures (gray and viridis), as linear RGB, and the one way a figure paints
//! values with them.

use crate::grid::{Grid, Image, Mask, RgbImage};

/// Viridis (van der Walt & Smith, matplotlib), sampled at 9 evenly spaced points in sRGB.
const VIRIDIS: [[f64; 3]; 9] = [
    [0.267004, 0.004874, 0.329415],
    [0.278826, 0.175490, 0.483397],
    [0.229739, 0.322361, 0.545706],
    [0.172719, 0.448791, 0.557885],
    [0.127568, 0.566949, 0.550556],
    [0.157851, 0.683765, 0.501686],
    [0.369214, 0.788888, 0.382914],
    [0.678489, 0.863742, 0.189503],
    [0.993248, 0.906157, 0.143936],
];

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The viridis colour of `t` in 0..1 (clamped), as linear RGB, so that writing it through the
/// usual display gamma reproduces the published map.
pub fn viridis(t: f64) -> [f64; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let u = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [0, 1, 2].map(|k| srgb_to_linear(a[k] + u * (b[k] - a[k])))
}

/// A colour map: how a figure shows a value between the two ends of its colour bar.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Colormap {
    /// Black (0) to white (1): the value itself as a gray level.
    Gray,
    /// Viridis: dark blue (0) through green to yellow (1).
    Viridis,
}

impl Colormap {
    /// The colour of `t` in 0..1 (clamped; NaN as 0), as linear RGB.
    ///
    /// ```
    /// use shadelab::Colormap;
    /// assert_eq!(Colormap::Gray.linear(0.25), [0.25; 3]);
    /// assert_eq!(Colormap::Gray.linear(2.0), [1.0; 3]);
    /// ```
    pub fn linear(self, t: f64) -> [f64; 3] {
        match self {
            Colormap::Gray => [if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) }; 3],
            Colormap::Viridis => viridis(t),
        }
    }

    /// `values` painted with this map, `range.0` at its start and `range.1` at its end; pixels
    /// outside `shown` (when given) are `outside`.
    pub fn paint(
        self,
        values: &Image,
        range: (f64, f64),
        shown: Option<&Mask>,
        outside: [f64; 3],
    ) -> RgbImage {
        let span = range.1 - range.0;
        Grid::from_fn(values.width(), values.height(), |c, r| {
            if shown.is_some_and(|m| !*m.get(c, r)) {
                return outside;
            }
            let t = if span != 0.0 {
                (values.get(c, r) - range.0) / span
            } else {
                0.5
            };
            self.linear(t)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_monotone_luminance() {
        let lum = crate::grid::luminance;
        let mut last = -1.0;
        for i in 0..=100 {
            let l = lum(viridis(i as f64 / 100.0));
            assert!(l > last, "viridis luminance rises");
            last = l;
        }
        assert!((viridis(1.0)[0] - srgb_to_linear(0.993248)).abs() < 1e-12);
    }

    #[test]
    fn paint_maps_the_range_ends_to_the_map_ends_and_hides_outside() {
        let values = Grid::from_vec(3, 1, vec![-1.0, 0.0, 1.0]).unwrap();
        let shown = Grid::from_vec(3, 1, vec![true, false, true]).unwrap();
        let p = Colormap::Viridis.paint(&values, (-1.0, 1.0), Some(&shown), [1.0; 3]);
        assert_eq!(*p.get(0, 0), viridis(0.0));
        assert_eq!(*p.get(1, 0), [1.0; 3]);
        assert_eq!(*p.get(2, 0), viridis(1.0));
    }
}

//! A high-pass lightness model in the style of Shapiro & Lu (2011), "Relative brightness in
//! natural images can be accounted for by removing blurry content", *Psychological Science*
//! 22(11), 1452–1459: what is left of the image once its blurry (low spatial frequency)
//! content is taken away predicts relative brightness.
//!
//! Here the blurry content is the image blurred by a Gaussian of σ [`HighPass::sigma_deg`]
//! degrees of visual angle (edges repeated), and the model's output is the image minus it:
//! positive where a region is brighter than its blurred neighbourhood. The σ is shadelab's
//! choice (2°, a few times the size of the typical target), not a value taken from the paper.

use crate::error::{Error, Result};
use crate::grid::Image;
use crate::imageops::gaussian_blur;

/// The high-pass model's one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HighPass {
    /// σ of the Gaussian whose blur is removed, in degrees of visual angle.
    pub sigma_deg: f64,
}

impl Default for HighPass {
    fn default() -> Self {
        HighPass { sigma_deg: 2.0 }
    }
}

impl HighPass {
    /// The model's output for `image` (linear luminance) at `ppd` pixels per degree: the
    /// image minus its blur, in luminance units (positive = brighter than the neighbourhood).
    ///
    /// ```
    /// use shadelab::Grid;
    /// use shadelab_analysis::lightness::HighPass;
    /// // Two equal grey patches, one on black and one on white: the one on black comes out
    /// // brighter (simultaneous contrast).
    /// let image = Grid::from_fn(16, 8, |c, r| {
    ///     let patch = (3..5).contains(&r) && ((3..5).contains(&c) || (11..13).contains(&c));
    ///     if patch { 0.5 } else if c < 8 { 0.0 } else { 1.0 }
    /// });
    /// let out = HighPass { sigma_deg: 1.0 }.apply(&image, 2.0).unwrap();
    /// assert!(out.get(3, 3) > out.get(11, 3));
    /// ```
    pub fn apply(&self, image: &Image, ppd: f64) -> Result<Image> {
        if !(ppd.is_finite() && ppd > 0.0) {
            return Err(Error::invalid(format!(
                "the high-pass model needs a positive resolution in pixels per degree, not {ppd}"
            )));
        }
        if !(self.sigma_deg.is_finite() && self.sigma_deg > 0.0) {
            return Err(Error::invalid(format!(
                "the high-pass model's σ must be positive degrees, not {}",
                self.sigma_deg
            )));
        }
        let blur = gaussian_blur(image, self.sigma_deg * ppd);
        let mut out = image.clone();
        for (o, b) in out.data_mut().iter_mut().zip(blur.data()) {
            *o -= b;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    #[test]
    fn a_uniform_image_gives_zero_and_a_ramp_is_removed() {
        // A uniform field has no detail left; a shallow ramp (an illumination gradient) is
        // almost all blurry content, so far from the borders almost nothing of it is left,
        // while a step of the same height keeps most of its size at the edge.
        let hp = HighPass { sigma_deg: 1.0 };
        let flat = hp.apply(&Grid::new(32, 16, 0.4), 4.0).unwrap();
        assert!(flat.data().iter().all(|v| v.abs() < 1e-12));
        let ramp = hp
            .apply(&Grid::from_fn(64, 8, |c, _| c as f64 / 64.0), 4.0)
            .unwrap();
        assert!(ramp.get(32, 4).abs() < 1e-9, "{}", ramp.get(32, 4));
        let step = hp
            .apply(
                &Grid::from_fn(64, 8, |c, _| if c < 32 { 0.0 } else { 1.0 }),
                4.0,
            )
            .unwrap();
        assert!(*step.get(32, 4) > 0.3 && *step.get(31, 4) < -0.3);
        assert!(hp.apply(&Grid::new(4, 4, 0.5), 0.0).is_err());
        assert!(HighPass { sigma_deg: -1.0 }
            .apply(&Grid::new(4, 4, 0.5), 4.0)
            .is_err());
    }
}

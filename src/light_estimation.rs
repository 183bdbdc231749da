//! Estimating the light direction and albedo from a single image of a Lambertian surface.
//!
//! - Tilt (Lee & Rosenfeld 1985; Zheng & Chellappa 1991): on a surface whose orientations are
//!   spread evenly, brightness grows on average toward the light, so the mean of the unit image
//!   gradients points along the light's image-plane direction.
//! - Slant and albedo (Zheng & Chellappa 1991): for normals spread evenly over the visible
//!   hemisphere, the first two moments of the brightness are μ1 = E(I) = (π/4)·ρ·cos σ and
//!   μ2 = E(I²) = (ρ²/6)(1 + 3cos²σ). With γ = √(6π²μ2 − 48μ1²) they give ρ = γ/π and
//!   cos σ = 4μ1/γ.
//!
//! The moment model is only an approximation for a real object: the image of a sphere is not
//! an even spread of normals over the hemisphere (it over-weights normals facing the viewer),
//! so the slant comes out biased, by about 10° or less for slants from 30° to 60°, more near
//! frontal (≈ 22° too oblique at 0°) and grazing light. Use it when the light is unknown, not
//! as a measurement.

use crate::error::{Error, Result};
use crate::grid::{Image, Mask};
use crate::light::Light;
use serde::Serialize;

/// An estimated light and albedo.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LightEstimate {
    /// The estimated light (unit vector toward it).
    pub light: Light,
    /// Tilt in degrees (0 = from above, +90 = from the left).
    pub tilt_deg: f64,
    /// Slant in degrees from the viewing direction.
    pub slant_deg: f64,
    /// The estimated albedo ρ.
    pub albedo: f64,
    /// Length of the mean unit gradient (0..1): how consistently the image brightens toward
    /// one side; near 0 the tilt is meaningless (frontal light, or a featureless image).
    pub tilt_confidence: f64,
}

/// The largest slant the estimate returns, so that the light stays strictly in front of the
/// surface (shape from shading needs s_z > 0).
pub const MAX_ESTIMATED_SLANT_DEG: f64 = 89.0;

/// Estimates the light and albedo from `image` on `mask`.
///
/// The tilt uses the central-difference gradients of pixels whose four neighbours are inside
/// the mask (gradients across the silhouette measure the background, not the shading); the
/// moments use every masked pixel. Fails on mismatched sizes, non-finite values, an empty mask
/// or an image that is black in the mask.
pub fn estimate_light(image: &Image, mask: &Mask) -> Result<LightEstimate> {
    if !image.same_size(mask) {
        return Err(Error::invalid(format!(
            "image is {}x{} but the mask is {}x{}",
            image.width(),
            image.height(),
            mask.width(),
            mask.height()
        )));
    }
    if image.data().iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid("image holds NaN or infinite values"));
    }
    let (w, h) = (image.width(), image.height());
    let (mut sx, mut sy, mut count) = (0.0, 0.0, 0usize);
    let inside = |c: isize, r: isize| mask.checked(c, r).copied().unwrap_or(false);
    for row in 0..h {
        for col in 0..w {
            let (c, r) = (col as isize, row as isize);
            if !(inside(c, r)
                && inside(c - 1, r)
                && inside(c + 1, r)
                && inside(c, r - 1)
                && inside(c, r + 1))
            {
                continue;
            }
            let dx = 0.5 * (image.get(col + 1, row) - image.get(col - 1, row));
            // World y points up: one row up is +y.
            let dy = 0.5 * (image.get(col, row - 1) - image.get(col, row + 1));
            let len = dx.hypot(dy);
            if len > 1e-12 {
                sx += dx / len;
                sy += dy / len;
                count += 1;
            }
        }
    }
    let (mut mu1, mut mu2, mut n) = (0.0, 0.0, 0usize);
    for (v, &m) in image.data().iter().zip(mask.data()) {
        if m {
            mu1 += v;
            mu2 += v * v;
            n += 1;
        }
    }
    if n == 0 {
        return Err(Error::invalid(
            "the mask is empty: the light cannot be estimated",
        ));
    }
    let (mu1, mu2) = (mu1 / n as f64, mu2 / n as f64);
    if mu1 <= 0.0 {
        return Err(Error::invalid(
            "the image is black (or negative) inside the mask: the light cannot be estimated",
        ));
    }
    let (mx, my) = if count > 0 {
        (sx / count as f64, sy / count as f64)
    } else {
        (0.0, 0.0)
    };
    let tilt_confidence = mx.hypot(my);
    // The light's image-plane direction is (−sin τ, cos τ): brightening toward (mx, my).
    let tilt_deg = if tilt_confidence > 1e-12 {
        (-mx).atan2(my).to_degrees()
    } else {
        0.0
    };
    let gamma2 = 6.0 * std::f64::consts::PI.powi(2) * mu2 - 48.0 * mu1 * mu1;
    let (cos_slant, albedo) = if gamma2 > 0.0 && 4.0 * mu1 < gamma2.sqrt() {
        let gamma = gamma2.sqrt();
        (4.0 * mu1 / gamma, gamma / std::f64::consts::PI)
    } else {
        // The moments are too uniform for the model (cos σ would exceed 1): frontal light,
        // with the albedo from the mean alone.
        (1.0, 4.0 * mu1 / std::f64::consts::PI)
    };
    let slant_deg = cos_slant.acos().to_degrees().min(MAX_ESTIMATED_SLANT_DEG);
    let light = Light::from_tilt_slant(tilt_deg, slant_deg)?;
    Ok(LightEstimate {
        light,
        tilt_deg,
        slant_deg,
        albedo,
        tilt_confidence,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use crate::reflectance::Lambertian;
    use crate::render::{render, RenderOptions};
    use crate::surface::sphere;

    fn sphere_image(light: Light, albedo: f64) -> (Image, Mask) {
        let s = sphere(256, 256, 115.2).unwrap();
        let map = Lambertian {
            light,
            albedo,
            ambient: 0.0,
        };
        (render(&s, &map, &RenderOptions::default()).image, s.mask)
    }

    fn tilt_difference(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(360.0);
        d.min(360.0 - d)
    }

    #[test]
    fn tilt_is_exact_and_slant_close_on_a_sphere() {
        for (tilt, slant) in [
            (0.0, 30.0),
            (90.0, 45.0),
            (180.0, 60.0),
            (-90.0, 40.0),
            (45.0, 50.0),
            (-135.0, 35.0),
        ] {
            let light = Light::from_tilt_slant(tilt, slant).unwrap();
            let (image, mask) = sphere_image(light, 0.8);
            let est = estimate_light(&image, &mask).unwrap();
            // The grid is symmetric about these tilts, so the mean gradient is exactly along
            // the light's direction.
            assert!(
                tilt_difference(est.tilt_deg, tilt) < 1e-9,
                "tilt {tilt}: got {}",
                est.tilt_deg
            );
            assert!(
                (est.slant_deg - slant).abs() <= 10.0,
                "slant {slant}: got {}",
                est.slant_deg
            );
            assert!((est.albedo - 0.8).abs() < 0.12, "albedo {}", est.albedo);
            assert!((est.light.slant_deg() - est.slant_deg).abs() < 1e-9);
        }
        // Off the grid's symmetry axes the tilt is still within a small fraction of a degree.
        let light = Light::from_tilt_slant(27.0, 45.0).unwrap();
        let est = estimate_light(&sphere_image(light, 1.0).0, &sphere_image(light, 1.0).1).unwrap();
        assert!(
            tilt_difference(est.tilt_deg, 27.0) < 0.5,
            "{}",
            est.tilt_deg
        );
    }

    #[test]
    fn albedo_scales_out_of_the_direction() {
        let light = Light::from_tilt_slant(30.0, 40.0).unwrap();
        let (a, mask) = sphere_image(light, 1.0);
        let half = a.map(|v| v * 0.5);
        let e1 = estimate_light(&a, &mask).unwrap();
        let e2 = estimate_light(&half, &mask).unwrap();
        assert!((e1.slant_deg - e2.slant_deg).abs() < 1e-9);
        assert!((e1.tilt_deg - e2.tilt_deg).abs() < 1e-9);
        assert!((e2.albedo - 0.5 * e1.albedo).abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_rejected() {
        let mask = Grid::new(8, 8, true);
        assert!(estimate_light(&Grid::new(8, 8, 0.0), &mask).is_err());
        assert!(estimate_light(&Grid::new(8, 7, 0.5), &mask).is_err());
        assert!(estimate_light(&Grid::new(8, 8, 0.5), &Grid::new(8, 8, false)).is_err());
        let mut nan = Grid::new(8, 8, 0.5);
        *nan.get_mut(2, 2) = f64::NAN;
        assert!(estimate_light(&nan, &mask).is_err());
        // A uniform image: no tilt information, frontal light.
        let flat = estimate_light(&Grid::new(8, 8, 0.5), &mask).unwrap();
        assert_eq!(flat.tilt_confidence, 0.0);
        assert!(flat.light.direction().z > 0.0);
    }
}

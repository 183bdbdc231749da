//! The albedo of a photographed object, which shape from shading needs and a photograph does
//! not give.
//!
//! A Lambertian surface of albedo ρ under a light s of unit intensity has I = ρ·max(n·s, 0) ≤ ρ,
//! with equality where the normal points at the light. An object with a smooth silhouette has
//! every visible normal somewhere, so it has such pixels, and ρ is the largest brightness.
//! Noise, interreflections and specular highlights (which on a photographed object sit near
//! those very pixels when the light is near the view direction) make the plain maximum too
//! high, so the estimate is a high quantile, [`BRIGHT_QUANTILE`] = 0.95, of the brightness on
//! the mask. On a Lambertian sphere lit from the front that quantile is where n·s = 0.975
//! (5 % of the disc has n_z above √(1 − 0.05)), so it reads 2.5 % low; in exchange a highlight
//! covering up to 5 % of the object does not reach it. The solver is sensitive to the albedo
//! (on the DiLiGenT ball, an albedo 8 % too high turns a 2° error into 6°; see
//! docs/evaluation.md), so the choice matters more than its modest look suggests.

use super::metrics::quantile_sorted;
use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask};
use crate::light::Light;

/// The quantile of the masked brightness taken as the albedo.
pub const BRIGHT_QUANTILE: f64 = 0.95;

/// The albedo from the brightest pixels: the [`BRIGHT_QUANTILE`] quantile of `image` on `mask`.
/// Fails on an empty mask or a black image.
pub fn albedo_from_brightest(image: &Image, mask: &Mask) -> Result<f64> {
    brightness_quantile(image, mask, BRIGHT_QUANTILE)
}

/// The `q`-quantile of `image` on `mask`; fails on an empty mask or a result that is not
/// positive.
pub fn brightness_quantile(image: &Image, mask: &Mask, q: f64) -> Result<f64> {
    let mut values: Vec<f64> = image
        .data()
        .iter()
        .zip(mask.data())
        .filter(|(v, &m)| m && v.is_finite())
        .map(|(v, _)| *v)
        .collect();
    if values.is_empty() {
        return Err(Error::invalid("the mask is empty: no albedo to estimate"));
    }
    values.sort_by(f64::total_cmp);
    let albedo = quantile_sorted(&values, q);
    if albedo > 0.0 {
        Ok(albedo)
    } else {
        Err(Error::invalid(
            "the image is black inside the mask: no albedo to estimate",
        ))
    }
}

/// The albedo that best explains `image` with the true `normals` (least squares of
/// I ≈ ρ·max(n·s, 0) over lit pixels of `mask`): not an estimate a user could make, but the
/// reference the estimate is judged by. `None` when no pixel is lit.
pub fn albedo_with_normals(
    image: &Image,
    normals: &Grid<Normal>,
    mask: &Mask,
    light: &Light,
) -> Option<f64> {
    let s = light.direction();
    let (num, den) = image
        .data()
        .iter()
        .zip(normals.data())
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .map(|((i, n), _)| (i, n.dot(&s).max(0.0)))
        .fold((0.0, 0.0), |(a, b), (i, c)| (a + i * c, b + c * c));
    (den > 0.0).then(|| num / den)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reflectance::{Lambertian, ReflectanceMap};
    use crate::surface::sphere;

    #[test]
    fn a_lambertian_sphere_gives_back_its_albedo() {
        let s = sphere(101, 101, 45.0).unwrap();
        let light = Light::from_tilt_slant(20.0, 25.0).unwrap();
        let map = Lambertian {
            light,
            albedo: 0.6,
            ambient: 0.0,
        };
        let image = s.normals.map(|n| map.radiance(n));
        let bright = albedo_from_brightest(&image, &s.mask).unwrap();
        // The top 5 % of a sphere's disc faces the light within about 14°.
        assert!(bright <= 0.6 && bright > 0.6 * 0.97, "{bright}");
        let fitted = albedo_with_normals(&image, &s.normals, &s.mask, &light).unwrap();
        assert!((fitted - 0.6).abs() < 1e-12);
        assert!(albedo_from_brightest(&image, &Grid::new(101, 101, false)).is_err());
        assert!(albedo_from_brightest(&Grid::new(4, 4, 0.0), &Grid::new(4, 4, true)).is_err());
    }
}

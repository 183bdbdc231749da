//! The albedo of a photographed object, which shape from shading needs and a photograph does
//! not give: the one rule that `solve --albedo estimate` and `shadelab eval` both use.
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
//!
//! The rule scales with the image: an image multiplied by any factor gives the albedo
//! multiplied by the same factor, so the shape solved with [`estimate`] does not depend on how
//! the user normalised the photograph. What is brighter than the estimate is a highlight no
//! Lambertian normal can explain: [`normalise`] divides the image by the albedo and caps it at
//! 1 (unclipped, the oblique ball photographs made the multigrid iteration diverge).
//!
//! ```
//! use shadelab::albedo::{estimate, BRIGHT_QUANTILE};
//! use shadelab::grid::Grid;
//! // A ramp 0.01..1.00 on a full mask: the 95th percentile.
//! let image = Grid::from_fn(10, 10, |c, r| (r * 10 + c + 1) as f64 / 100.0);
//! let mask = Grid::new(10, 10, true);
//! let a = estimate(&image, &mask).unwrap();
//! assert!((a.value - 0.9505).abs() < 1e-12 && a.quantile == BRIGHT_QUANTILE);
//! // Half as bright, half the albedo.
//! let half = image.map(|v| 0.5 * v);
//! assert!((estimate(&half, &mask).unwrap().value - 0.5 * a.value).abs() < 1e-12);
//! ```

use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask};
use crate::light::Light;
use serde::Serialize;

/// The quantile of the masked brightness taken as the albedo.
pub const BRIGHT_QUANTILE: f64 = 0.95;

/// An albedo estimated from an image, and how.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AlbedoEstimate {
    /// The albedo.
    pub value: f64,
    /// The quantile of the brightness on the mask it is ([`BRIGHT_QUANTILE`]).
    pub quantile: f64,
    /// Pixels of the mask brighter than it: capped by [`normalise`] before solving.
    pub brighter_pixels: usize,
    /// Pixels of the mask.
    pub mask_pixels: usize,
}

/// The albedo of `image` on `mask` by the library's rule: the [`BRIGHT_QUANTILE`] quantile of
/// the brightness. Fails on an empty mask or a black image.
pub fn estimate(image: &Image, mask: &Mask) -> Result<AlbedoEstimate> {
    let value = brightness_quantile(image, mask, BRIGHT_QUANTILE)?;
    let inside = || image.data().iter().zip(mask.data()).filter(|(_, &m)| m);
    Ok(AlbedoEstimate {
        value,
        quantile: BRIGHT_QUANTILE,
        brighter_pixels: inside().filter(|(v, _)| **v > value).count(),
        mask_pixels: inside().count(),
    })
}

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

/// `image` divided by `albedo` and capped at 1: the picture in units of the albedo, where
/// brightness no Lambertian normal of that albedo can explain (a highlight) is read as a
/// normal facing the light. Solved with albedo 1, it is the same problem whatever the image's
/// scale.
pub fn normalise(image: &Image, albedo: f64) -> Image {
    let scale = 1.0 / albedo;
    image.map(|v| (v * scale).min(1.0))
}

/// The `q`-quantile (0..1) of sorted, non-empty `values`, linearly interpolated between the
/// two nearest ranks (the median of an even count is the mean of the middle two); NaN when
/// empty.
pub fn quantile_sorted(values: &[f64], q: f64) -> f64 {
    match values.len() {
        0 => f64::NAN,
        n => {
            let at = q.clamp(0.0, 1.0) * (n - 1) as f64;
            let (lo, hi) = (at.floor() as usize, at.ceil() as usize);
            values[lo] + (at - lo as f64) * (values[hi] - values[lo])
        }
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
        let e = estimate(&image, &s.mask).unwrap();
        assert_eq!(e.value, bright);
        let unit = normalise(&image, e.value);
        assert!(unit.data().iter().all(|v| *v <= 1.0));
        let at_top = unit.data().iter().filter(|v| **v == 1.0).count();
        assert!(at_top >= e.brighter_pixels && e.brighter_pixels > 0);
    }

    #[test]
    fn quantiles_interpolate_between_ranks() {
        assert_eq!(quantile_sorted(&[1.0, 2.0, 3.0, 4.0], 0.5), 2.5);
        assert_eq!(quantile_sorted(&[5.0], 0.9), 5.0);
        assert_eq!(quantile_sorted(&[0.0, 10.0], 0.9), 9.0);
        assert!(quantile_sorted(&[], 0.5).is_nan());
    }
}

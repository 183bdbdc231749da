//! The albedo of a photographed object, which shape from shading needs and a photograph does
//! not give: the one rule that `solve --albedo estimate` and `shadelab eval` both use.
//!
//! A Lambertian surface of albedo ρ under a light s of unit intensity has I = ρ·max(n·s, 0) ≤ ρ,
//! with equality where the normal points at the light. The plain maximum is no estimate of ρ:
//! noise, interreflections and specular highlights make it too high, and a photograph the
//! user normalised by a percentile and stored in 0..1 is clipped, its brightest pixels all
//! at 1. A high quantile (the 95th, the rule until issue 20) avoids both but reads low: on a
//! matte sphere lit from the front it is where n·s = 0.975, 2.5 % below ρ.
//!
//! # The rule: the bright tail, extrapolated
//!
//! Near the brightest normal of a smooth surface n·s falls off quadratically with the distance
//! in the image, so the share of the object brighter than I falls to zero linearly as I rises
//! to ρ: on a sphere, whatever the light's slant (while the bright cap is in view), the share
//! brighter than ρ·t is (1 − t²)·c = (1 − t)(1 + t)·c, nearly a straight line over the top
//! quarter. [`estimate`] fits that line, share brighter against brightness, by least squares
//! to the pixels between the quantiles [`BRIGHT_QUANTILE`] − [`TAIL_BAND`] and
//! [`BRIGHT_QUANTILE`] (0.7 and 0.9), and reads the albedo off it at the share
//! [`TAIL_SHARE`] = 3 %, not at zero: real diffuse surfaces fall off flatter than a cosine
//! near their brightest normal (read at zero share, the DiLiGenT ball's albedo came out 1.4–3.7
//! % above the least-squares albedo of its true normals and its errors rose by up to 1.2°; at
//! 3 %, −0.5 to +1 %, its errors within 0.4° of the 95th percentile's). On a matte sphere it
//! reads 1–1.5 % low, where the 95th percentile reads 2.5–3 % low.
//!
//! What is brighter than the band plays no part but its count: a highlight of up to 10 % of
//! the object moves the line only by its share (a highlight of 2 % raises the estimate by about
//! 1 %), and an image clipped at 1 above the band gives the same line, so the same albedo in
//! its units, as the unclipped one (every pixel of the band keeps its share of brighter
//! pixels): a photograph normalised by its 90th, 95th or 99th percentile or its maximum and
//! stored in 0..1 gives the same albedo. A clipped plateau that reaches into the band (the
//! pixels tied at the image's maximum, when they are more than [`PLATEAU_SHARE`] of the mask,
//! are a plateau whose true values are unknown) moves the band below it, and its brightness is
//! the image's saturation level ([`AlbedoEstimate::plateau`], [`Saturation::Auto`]): the solve
//! leaves the pixels at it out of the data term, as it leaves out attached shadow
//! ([`crate::solver::carries_data`]), instead of pulling them all to the one orientation that
//! gives that brightness.
//!
//! The rule scales with the image: an image multiplied by any factor gives the albedo
//! multiplied by the same factor, so the shape solved with [`estimate`] does not depend on how
//! the user normalised the photograph. What is brighter than the estimate is a highlight no
//! Lambertian normal can explain: [`normalise`] divides the image by the albedo and caps it at
//! 1 (unclipped, the oblique ball photographs made the multigrid iteration diverge). The
//! solver is sensitive to the albedo (on the DiLiGenT ball, an albedo 8 % too high turns a 2°
//! error into 6°; see docs/evaluation.md).
//!
//! ```
//! use shadelab_engine::albedo::estimate;
//! use shadelab::Grid;
//! use shadelab_engine::surface::sphere;
//! // A matte sphere of albedo 0.6 lit from the front: I = 0.6·n_z.
//! let s = sphere(101, 101, 45.0)?;
//! let image = s.normals.map(|n| 0.6 * n.z.max(0.0));
//! let a = estimate(&image, &s.mask)?;
//! assert!((a.value / 0.6 - 1.0).abs() < 0.02, "{}", a.value);
//! // Half as bright, half the albedo.
//! let half = image.map(|v| 0.5 * v);
//! assert!((estimate(&half, &s.mask)?.value - 0.5 * a.value).abs() < 1e-12);
//! // Normalised by its 90th percentile and clipped at 1: the same albedo in its units.
//! let top = shadelab_engine::albedo::brightness_quantile(&image, &s.mask, 0.9)?;
//! let clipped = image.map(|v| (v / top).min(1.0));
//! let c = estimate(&clipped, &s.mask)?;
//! assert!((c.value * top / a.value - 1.0).abs() < 0.01, "{}", c.value * top);
//! # Ok::<(), shadelab::Error>(())
//! ```

use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask};
use crate::light::Light;
use serde::Serialize;
use std::str::FromStr;

/// The top of the quantile band [`estimate`] fits: what is brighter plays no part.
pub const BRIGHT_QUANTILE: f64 = 0.9;

/// The width of the quantile band [`estimate`] fits, below its top.
pub const TAIL_BAND: f64 = 0.2;

/// The share of the object the fitted tail line is read at: the albedo is the brightness the
/// line gives the brightest [`TAIL_SHARE`] of the object (module documentation).
pub const TAIL_SHARE: f64 = 0.03;

/// Pixels tied at the image's maximum, more than this share of the mask, are a clipped
/// plateau that [`estimate`] fits below.
pub const PLATEAU_SHARE: f64 = 0.002;

/// An albedo estimated from an image, and how.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AlbedoEstimate {
    /// The albedo.
    pub value: f64,
    /// The top of the quantile band fitted: [`BRIGHT_QUANTILE`], or below a clipped plateau.
    pub quantile: f64,
    /// The share of the mask tied at the image's maximum when it is a clipped plateau (more
    /// than [`PLATEAU_SHARE`]), else 0.
    pub clipped_share: f64,
    /// The brightness of the clipped plateau (the image's maximum) when there is one: the
    /// image's saturation level ([`Saturation::Auto`]).
    pub plateau: Option<f64>,
    /// Pixels of the mask brighter than the albedo: capped by [`normalise`] before solving.
    pub brighter_pixels: usize,
    /// Pixels of the mask.
    pub mask_pixels: usize,
}

/// The albedo of `image` on `mask` by the library's rule (the module documentation): the bright
/// tail's share-against-brightness line, extrapolated to zero share. Fails on an empty mask or
/// a black image.
pub fn estimate(image: &Image, mask: &Mask) -> Result<AlbedoEstimate> {
    let values = sorted_inside(image, mask)?;
    let n = values.len();
    let top = values[n - 1];
    if top <= 0.0 || top.is_nan() {
        return Err(Error::invalid(
            "the image is black inside the mask: no albedo to estimate",
        ));
    }
    let tied = n - values.partition_point(|v| *v < top);
    let clipped_share = if tied as f64 > PLATEAU_SHARE * n as f64 {
        tied as f64 / n as f64
    } else {
        0.0
    };
    // The band: the pixels from the quantile BRIGHT_QUANTILE − TAIL_BAND to BRIGHT_QUANTILE,
    // moved down below a clipped plateau that reaches into it.
    let width = ((TAIL_BAND * n as f64).round() as usize).max(2);
    let mut hi = ((BRIGHT_QUANTILE * n as f64).ceil() as usize).min(n);
    if clipped_share > 0.0 {
        hi = hi.min(n - tied);
    }
    let lo = hi.saturating_sub(width);
    let quantile = hi as f64 / n as f64;
    let floor = values[hi.max(1) - 1];
    let value = if hi - lo >= 2 {
        tail_line(&values, lo, hi).unwrap_or(floor).max(floor)
    } else {
        top
    };
    Ok(AlbedoEstimate {
        value,
        quantile,
        clipped_share,
        plateau: (clipped_share > 0.0).then_some(top),
        brighter_pixels: n - values.partition_point(|v| *v <= value),
        mask_pixels: n,
    })
}

/// The brightness where the least-squares line through (values[i], share of the pixels
/// brighter than values[i]) for i in lo..hi reaches [`TAIL_SHARE`]; `None` when the line does
/// not fall.
fn tail_line(values: &[f64], lo: usize, hi: usize) -> Option<f64> {
    let n = values.len() as f64;
    let count = (hi - lo) as f64;
    let share = |i: usize| (n - i as f64 - 0.5) / n;
    let (mut sx, mut sy) = (0.0, 0.0);
    for (i, v) in values.iter().enumerate().take(hi).skip(lo) {
        sx += v;
        sy += share(i);
    }
    let (mx, my) = (sx / count, sy / count);
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (i, v) in values.iter().enumerate().take(hi).skip(lo) {
        let dx = v - mx;
        sxx += dx * dx;
        sxy += dx * (share(i) - my);
    }
    let slope = sxy / sxx;
    (slope < 0.0 && slope.is_finite()).then(|| mx + (TAIL_SHARE - my) / slope)
}

/// The finite values of `image` on `mask`, sorted; fails on an empty mask.
fn sorted_inside(image: &Image, mask: &Mask) -> Result<Vec<f64>> {
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
    Ok(values)
}

/// The `q`-quantile of `image` on `mask`; fails on an empty mask or a result that is not
/// positive.
pub fn brightness_quantile(image: &Image, mask: &Mask, q: f64) -> Result<f64> {
    let values = sorted_inside(image, mask)?;
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
    image.map(|&v| in_albedo_units(v, albedo).min(1.0))
}

/// A brightness `value` in units of `albedo`, exactly as [`normalise`] scales the image (before
/// its cap): a saturation level given in the image's units becomes the level of the
/// normalised image, the same pixels at or above it.
pub fn in_albedo_units(value: f64, albedo: f64) -> f64 {
    value * (1.0 / albedo)
}

/// Where an image was clipped (saturated): the brightness at or above which a pixel's true
/// brightness is unknown, so that the solve leaves it out of the data term
/// ([`crate::solver::SolveOptions::saturation`]). Parsed from `auto`, `none` or a number.
///
/// ```
/// use shadelab::Saturation;
/// assert_eq!("auto".parse::<Saturation>()?, Saturation::Auto);
/// assert_eq!("0.98".parse::<Saturation>()?, Saturation::Level(0.98));
/// assert!("-1".parse::<Saturation>().is_err());
/// # Ok::<(), shadelab::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Saturation {
    /// The clipped plateau the albedo estimate finds ([`AlbedoEstimate::plateau`]: pixels
    /// tied at the image's maximum, more than [`PLATEAU_SHARE`] of the mask), when the albedo
    /// is estimated; none otherwise.
    #[default]
    Auto,
    /// No pixel is clipped.
    None,
    /// Pixels at or above this brightness, in the image's units (> 0), are clipped.
    Level(f64),
}

impl Saturation {
    /// The level in the image's units, given the albedo estimate made of the image (if any).
    pub fn level(&self, estimate: Option<&AlbedoEstimate>) -> Option<f64> {
        match self {
            Saturation::Auto => estimate.and_then(|e| e.plateau),
            Saturation::None => None,
            Saturation::Level(v) => Some(*v),
        }
    }

    /// Checks a given level: a positive number.
    pub fn validate(&self) -> Result<()> {
        match self {
            Saturation::Level(v) if !(v.is_finite() && *v > 0.0) => Err(Error::invalid(format!(
                "the saturation level {v} must be a positive number"
            ))),
            _ => Ok(()),
        }
    }
}

impl FromStr for Saturation {
    type Err = Error;
    fn from_str(text: &str) -> Result<Saturation> {
        let saturation = match text {
            "auto" => Saturation::Auto,
            "none" => Saturation::None,
            number => Saturation::Level(number.parse().map_err(|_| {
                Error::invalid(format!(
                    "saturation {number:?} is neither `auto`, `none` nor a number"
                ))
            })?),
        };
        saturation.validate()?;
        Ok(saturation)
    }
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

    /// A matte sphere's albedo within 2 % for lights from the front to 40° off, where the
    /// 95th percentile reads 2.5–3 % low; clipped at its 90th percentile (a user's
    /// normalisation stored in 0..1), the same albedo in its units within 1.5 %; a highlight of
    /// 2 % of the disc at twice the albedo raises it by less than 1.5 %.
    #[test]
    fn a_lambertian_sphere_gives_back_its_albedo() {
        let s = sphere(101, 101, 45.0).unwrap();
        for (tilt, slant) in [(0.0, 0.0), (20.0, 25.0), (-120.0, 40.0)] {
            let light = Light::from_tilt_slant(tilt, slant).unwrap();
            let map = Lambertian {
                light,
                albedo: 0.6,
                ambient: 0.0,
            };
            let image = s.normals.map(|n| map.radiance(n));
            let what = format!("tilt {tilt}, slant {slant}");
            let e = estimate(&image, &s.mask).unwrap();
            assert!((e.value / 0.6 - 1.0).abs() < 0.02, "{what}: {}", e.value);
            eprintln!("{what}: albedo {:.4} (0.6)", e.value);
            let p95 = brightness_quantile(&image, &s.mask, 0.95).unwrap();
            assert!(p95 < 0.6 * 0.976, "{what}: the 95th percentile {p95}");
            assert_eq!(e.clipped_share, 0.0);
            let fitted = albedo_with_normals(&image, &s.normals, &s.mask, &light).unwrap();
            assert!((fitted - 0.6).abs() < 1e-12);
            // Clipped at the 90th percentile.
            let top = brightness_quantile(&image, &s.mask, 0.9).unwrap();
            let clipped = image.map(|v| (v / top).min(1.0));
            let c = estimate(&clipped, &s.mask).unwrap();
            assert!(c.clipped_share > 0.09 && c.quantile < 0.9, "{what}: {c:?}");
            assert_eq!(c.plateau, Some(1.0), "{what}");
            assert_eq!(e.plateau, None, "{what}");
            assert_eq!(Saturation::Auto.level(Some(&c)), Some(1.0));
            assert_eq!(Saturation::Auto.level(Some(&e)), None);
            assert_eq!(Saturation::None.level(Some(&c)), None);
            assert_eq!(Saturation::Level(0.5).level(None), Some(0.5));
            // The level in the albedo's units picks the same pixels as the normalised image.
            let level = in_albedo_units(1.0, c.value);
            let unit = normalise(&clipped, c.value);
            for (u, v) in unit.data().iter().zip(clipped.data()) {
                assert_eq!(*u >= level, *v >= 1.0);
            }
            assert!(
                (c.value * top / e.value - 1.0).abs() < 0.015,
                "{what}: {c:?}"
            );
            // A highlight: the 2 % of the disc facing the light most, at twice the albedo.
            let s_dir = light.direction();
            let mut order: Vec<usize> = (0..image.data().len())
                .filter(|&i| s.mask.data()[i])
                .collect();
            order.sort_by(|&a, &b| {
                let d = |i: usize| s.normals.data()[i].dot(&s_dir);
                d(b).total_cmp(&d(a))
            });
            let mut shiny = image.clone();
            for &i in &order[..order.len() * 2 / 100] {
                *shiny.get_mut(i % 101, i / 101) = 1.2;
            }
            let h = estimate(&shiny, &s.mask).unwrap();
            assert!((h.value / e.value - 1.0).abs() < 0.015, "{what}: {h:?}");
            assert!(h.brighter_pixels >= order.len() * 2 / 100, "{what}: {h:?}");
            let unit = normalise(&shiny, h.value);
            assert!(unit.data().iter().all(|v| *v <= 1.0));
        }
        assert!(estimate(&Grid::new(4, 4, 0.5), &Grid::new(4, 4, false)).is_err());
        assert!(estimate(&Grid::new(4, 4, 0.0), &Grid::new(4, 4, true)).is_err());
        // A flat image has no tail: its one brightness.
        assert_eq!(
            estimate(&Grid::new(4, 4, 0.5), &Grid::new(4, 4, true))
                .unwrap()
                .value,
            0.5
        );
    }

    #[test]
    fn quantiles_interpolate_between_ranks() {
        assert_eq!(quantile_sorted(&[1.0, 2.0, 3.0, 4.0], 0.5), 2.5);
        assert_eq!(quantile_sorted(&[5.0], 0.9), 5.0);
        assert_eq!(quantile_sorted(&[0.0, 10.0], 0.9), 9.0);
        assert!(quantile_sorted(&[], 0.5).is_nan());
    }
}

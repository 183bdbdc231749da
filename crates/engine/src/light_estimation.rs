//! Estimating the light direction and albedo from a single image of a Lambertian surface.
//!
//! Three estimators, and [`estimate_light_with`] picks one by what the picture's outline is
//! and how well each model explains the picture:
//!
//! **In a band inside the limb** ([`EstimateMethod::LimbBand`], where the mask's outline is an
//! occluding contour, as for a rendered object against its background). At the limb the normal
//! is edge-on, in the image plane and pointing out of the silhouette; a few pixels inward it has
//! turned toward the viewer by an amount that depends on how sharply the surface curves there.
//! Each limb pixel casts a ray inward along its normal and samples the brightness at 0, 1, 2
//! and 3 pixels (bilinear, inside the mask, lit pixels only); along the ray the surface is taken
//! as a circular cross-section of radius R, so that at a distance d from the contour the normal
//! is (q·n_x, q·n_y, √(1 − q²)) with q = 1 − d/R. The limb pixel's centre lies half a step
//! inside the contour (d = ½·max(|n_x|, |n_y|) for the ray's first sample). The fit alternates:
//! given every ray's R, a least-squares fit I = g·n over all samples gives g = ρ·s, the scaled
//! light; given g, each ray takes the R (1.5 pixels up to the mask's size) that fits its
//! samples best. R starts at half the chord across the mask along the ray (exact for a sphere
//! and a surface of revolution seen side-on). Rays that stay more than 2.5 robust standard
//! deviations off are left out (a cut in the outline, not a limb). The tilt is atan2(−g_x, g_y), the slant
//! atan2(|g_xy|, g_z): the band's z components carry the slant, with no constant to absorb it.
//! The model is checked: where the root mean square residual exceeds [`MAX_BAND_RESIDUAL`] of
//! the albedo (an object whose cross-sections at the limb are a few pixels in radius or whose
//! normals also turn along the contour inward, as the Stanford bunny's at 128²; an outline that
//! is mostly cuts), the rim fit runs instead. The albedo is the brightest pixel;
//! the standard errors are the fit's, widened as below.
//!
//! **At the limb** ([`EstimateMethod::Limb`], the rim fit, where the band's model fails). On
//! the limb the surface turns away from
//! the viewer, so its normal is known: in the image plane, pointing out of the silhouette
//! (n_z = 0, the direction of [`crate::boundary::occluding_normals`]). There the brightness is
//! I = ρ·(n·s) = ρ·sin σ·(n_x·l_x + n_y·l_y), with l = (−sin τ, cos τ) the light's image-plane
//! direction: a linear function of the known normal. A least-squares fit
//! I = a·n_x + b·n_y + c over the lit limb pixels (I > 0; the unlit ones are the attached shadow,
//! where the clamp makes the law non-linear) gives the tilt τ = atan2(−a, b) and ρ·sin σ =
//! |(a, b)|. The constant c takes up the small part the light's z component adds: a rim pixel's
//! centre lies about half a pixel inside the silhouette, where n_z is already ≈ 1/√R on a
//! curvature radius of R pixels. The fit is trimmed (pixels more than 2.5 robust standard
//! deviations below it, or more than 1 above it, are left out and the fit repeated) so that the
//! parts of the outline that are no limb (a vase's cut rim, a corner, a mesh's open base) and
//! the pixels on cross-sections a few pixels in radius, whose normals still face the viewer,
//! do not pull it. The
//! trim is one-sided because the limb is the lower envelope of the outline's brightness: a
//! pixel whose normal has turned toward the viewer by n_z is brighter than the edge-on model by
//! ρ·(n_z·cos σ − sin σ·cos Δ·(1 − √(1 − n_z²))) > 0 (Δ the normal's angle from the light's
//! image-plane direction), for any n_z where σ ≤ 60° and for small n_z up to grazing light.
//! Without it, such pixels lift the constant c and flatten (a, b): on the Stanford bunny at
//! 128² (a tenth of its outline with n_z above 0.5) the slant came out up to 11° low,
//! against 7° with it. The albedo is the brightest pixel in the
//! mask, where the normal points at the light (I = ρ·(n·s) = ρ there), and sin σ = |(a, b)|/ρ.
//! The standard errors are the fit's: the tilt's from the covariance of (a, b) across the light's
//! direction, the slant's from its variance along it.
//!
//! The limb fits' standard errors cover their models' misfit, not only the pixels' noise: a
//! model that does not fit the object (a cross-section that is no circle, an outline partly a
//! cut) leaves residuals that run along the outline, so the fit's least-squares errors are
//! widened by √(residuals / 8) (the residuals taken as 8 independent blocks of the outline,
//! `outline_blocks`) and combined with a delete-one-eighth jackknife over the outline's
//! directions (`jackknife`). Measured on spheres, ellipsoids and vases at 64², 128² and 256²
//! under 32 lights each, the true tilt lies within ±2σ in 92 % of the estimates and the slant in
//! 96 % (docs/perception.md). The moments' tilt error is the mean gradient's sampling error
//! only, and they give no slant error.
//!
//! **From the interior statistics** ([`EstimateMethod::Moments`], for pictures without an
//! occluding outline: a relief on a plane, a region cut out of a surface):
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
//! frontal (≈ 22° too oblique at 0°) and grazing light; the tilt is biased on objects whose
//! normals are not spread evenly (30° on a vase). Its tilt standard error is the sampling error
//! of the mean unit gradient; it gives no slant error, since the model's bias is larger than
//! any sampling error. Use it when the light is unknown and there is no limb, not as a
//! measurement.

use crate::boundary::occluding_normals;
use crate::error::{Error, Result};
use crate::grid::{Image, Mask};
use crate::light::{FrontLight, Light};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;

/// Which estimator produced a [`LightEstimate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum EstimateMethod {
    /// The limb fit: tilt and ρ·sin σ from the brightness on the occluding contour, the albedo
    /// from the brightest pixel.
    #[serde(rename = "limb")]
    Limb,
    /// Zheng & Chellappa (1991): tilt from the mean unit image gradient, slant and albedo from
    /// the brightness moments.
    #[serde(rename = "moments")]
    Moments,
    /// The limb band fit: the light from the brightness in a band a few pixels wide inside the
    /// occluding contour, with normals extrapolated inward from the limb (see the module
    /// documentation); the albedo from the brightest pixel.
    #[serde(rename = "limb-band")]
    LimbBand,
    /// The limb's tilt with the moments' slant and albedo, where the limb leaves the slant
    /// uncertain (a standard error above [`MAX_LIMB_SLANT_SE_DEG`]: one side of the object lit,
    /// whose rim normals barely vary). The standard errors are the limb fit's.
    #[serde(rename = "limb+moments")]
    LimbAndMoments,
}

impl EstimateMethod {
    /// The estimator's name, as reports write it.
    pub fn name(self) -> &'static str {
        match self {
            EstimateMethod::Limb => "limb",
            EstimateMethod::LimbBand => "limb-band",
            EstimateMethod::Moments => "moments",
            EstimateMethod::LimbAndMoments => "limb+moments",
        }
    }
}

/// What the outline of the mask is, for [`estimate_light_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outline {
    /// The mask's outline (where it does not touch the image frame) is an occluding contour:
    /// use the limb where there is enough of it, the moments otherwise.
    Occluding,
    /// Nothing is known of the outline (a relief on a plane, a region of a surface): the
    /// moments.
    Unknown,
}

/// An estimated light and albedo.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LightEstimate {
    /// The estimated light (unit vector toward it), in front of the surface: the largest slant
    /// the estimators return is below 90°.
    pub light: FrontLight,
    /// Tilt in degrees (0 = from above, +90 = from the left).
    pub tilt_deg: f64,
    /// Slant in degrees from the viewing direction.
    pub slant_deg: f64,
    /// The estimated albedo ρ.
    pub albedo: f64,
    /// Length of the mean unit gradient (0..1): how consistently the image brightens toward
    /// one side; near 0 the tilt is meaningless (frontal light, or a featureless image).
    pub tilt_confidence: f64,
    /// The estimator that ran.
    pub method: EstimateMethod,
    /// Standard error of the tilt, degrees (capped at 180: no information on the tilt).
    pub tilt_se_deg: f64,
    /// Standard error of the slant, degrees (capped at 90); `None` for the moments, whose
    /// model bias (up to ≈ 22°) exceeds any sampling error.
    pub slant_se_deg: Option<f64>,
    /// Limb pixels the fit kept (0 for the moments).
    pub limb_pixels: usize,
    /// What the user should know of the estimate: [`WHOLE_FRAME_WARNING`] where the mask is
    /// the whole frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<&'static str>,
}

/// The warning of an estimate whose mask is the whole frame (no mask given, no sidecar's):
/// the estimators take every pixel as the surface's, a background included.
pub const WHOLE_FRAME_WARNING: &str = "the light was estimated over the whole frame (no mask): \
     a background, if the picture has one, was taken as surface and biases the estimate; give \
     the object's mask";

/// The largest slant the estimate returns, so that the light stays strictly in front of the
/// surface (shape from shading needs s_z > 0).
pub const MAX_ESTIMATED_SLANT_DEG: f64 = 89.0;

/// Above this standard error of the limb's slant, the slant and albedo come from the moments
/// ([`EstimateMethod::LimbAndMoments`]).
pub const MAX_LIMB_SLANT_SE_DEG: f64 = 3.0;

/// The fewest lit limb pixels the limb fit uses; with fewer the moments run.
pub const MIN_LIMB_PIXELS: usize = 16;

/// The limb band fit is used where the root mean square of its residuals is at most this
/// fraction of the albedo (its model, circular cross-sections edge-on at the contour, then
/// explains the band); otherwise the rim fit ([`EstimateMethod::Limb`]) runs.
pub const MAX_BAND_RESIDUAL: f64 = 0.03;

/// The band's samples along each limb pixel's inward normal, pixels from the limb pixel.
const BAND_STEPS: [f64; 4] = [0.0, 1.0, 2.0, 3.0];

/// The cross-section radii (pixels) the band fit chooses from, per limb pixel, up to 128;
/// [`band_radii`] continues them (1.5 and 2 times each power of two) to the size of the mask.
const BAND_RADII: [f64; 18] = [
    1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0, 24.0, 32.0, 40.0, 48.0, 64.0, 96.0,
    128.0,
];

/// The radii the band fit chooses from on a mask `width`×`height`: [`BAND_RADII`], then
/// 192, 256, 384, 512, … while below the longer side, so that a large object's limb (a sphere
/// of radius 218 pixels at 512²) is not fitted with too tight a cross-section.
fn band_radii(width: usize, height: usize) -> Vec<f64> {
    let limit = width.max(height) as f64;
    let mut radii = BAND_RADII.to_vec();
    let mut base = 128.0;
    while 1.5 * base < limit {
        radii.push(1.5 * base);
        if 2.0 * base < limit {
            radii.push(2.0 * base);
        }
        base *= 2.0;
    }
    radii
}

/// Rounds of the band fit (the light given the radii, the radii given the light).
const BAND_ROUNDS: usize = 6;

/// Limb pixels no brighter than this fraction of the brightest pixel count as unlit.
const LIT_FRACTION: f64 = 0.02;

/// The trimmed fit drops residuals beyond this many robust standard deviations.
const TRIM_SIGMAS: f64 = 2.5;

/// The rim fit also drops pixels brighter than its fit by more than this many robust standard
/// deviations: outline pixels that are no limb (a cut) or whose normals still face the viewer
/// (on a cross-section a few pixels in radius), brighter than the edge-on model (see the module
/// documentation).
const TRIM_ABOVE_SIGMAS: f64 = 1.0;

/// Estimates the light and albedo from `image` on `mask` with the interior statistics
/// ([`EstimateMethod::Moments`]): `estimate_light_with(image, mask, Outline::Unknown)`.
///
/// The tilt uses the central-difference gradients of pixels whose four neighbours are inside
/// the mask (gradients across the silhouette measure the background, not the shading); the
/// moments use every masked pixel. Fails on mismatched sizes, non-finite values, an empty mask
/// or an image that is black in the mask.
pub fn estimate_light(image: &Image, mask: &Mask) -> Result<LightEstimate> {
    estimate_light_with(image, mask, Outline::Unknown)
}

/// Estimates the light and albedo from `image` on `mask`: where `outline` says the mask's
/// outline is occluding and at least [`MIN_LIMB_PIXELS`] limb pixels are lit with normals in
/// more than one direction, by the limb band when its model explains the band, else by the rim
/// fit; without such a limb, by the moments (see the module documentation).
///
/// ```
/// use shadelab::Light;
/// use shadelab_engine::light_estimation::{estimate_light_with, EstimateMethod, Outline};
/// use shadelab::Lambertian;
/// use shadelab_engine::render::{render, RenderOptions};
/// use shadelab_engine::surface::sphere;
///
/// let s = sphere(64, 64, 28.0).unwrap();
/// let light = Light::from_tilt_slant(30.0, 35.0).unwrap();
/// let map = Lambertian { light, albedo: 0.8, ambient: 0.0 };
/// let image = render(&s, &map, &RenderOptions::default()).image;
/// let e = estimate_light_with(&image, &s.mask, Outline::Occluding).unwrap();
/// assert_eq!(e.method, EstimateMethod::LimbBand);
/// assert!((e.tilt_deg - 30.0).abs() < 2.0 && (e.slant_deg - 35.0).abs() < 2.0);
/// ```
pub fn estimate_light_with(image: &Image, mask: &Mask, outline: Outline) -> Result<LightEstimate> {
    check_inputs(image, mask)?;
    let mut estimate = estimate_on_mask(image, mask, outline)?;
    if mask.data().iter().all(|&m| m) {
        estimate.warning = Some(WHOLE_FRAME_WARNING);
    }
    Ok(estimate)
}

/// [`estimate_light_with`] without the whole-frame warning.
fn estimate_on_mask(image: &Image, mask: &Mask, outline: Outline) -> Result<LightEstimate> {
    let moments = moments_estimate(image, mask)?;
    if outline == Outline::Occluding {
        if let Some(e) = band_estimate(image, mask)? {
            return Ok(e);
        }
        if let Some((e, fit_slant_se)) = limb_estimate(image, mask)? {
            if fit_slant_se > MAX_LIMB_SLANT_SE_DEG {
                // The limb's tilt, the interior's slant and albedo.
                return Ok(LightEstimate {
                    light: FrontLight::new(Light::from_tilt_slant(e.tilt_deg, moments.slant_deg)?)?,
                    slant_deg: moments.slant_deg,
                    albedo: moments.albedo,
                    method: EstimateMethod::LimbAndMoments,
                    ..e
                });
            }
            return Ok(e);
        }
    }
    Ok(moments)
}

/// Fails on mismatched sizes or non-finite values.
fn check_inputs(image: &Image, mask: &Mask) -> Result<()> {
    image.check_same_size("image is", mask, "the mask is")?;
    if image.data().iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid("image holds NaN or infinite values"));
    }
    Ok(())
}

/// The brightest value in the mask; fails on an empty mask or one that is black.
fn brightest(image: &Image, mask: &Mask) -> Result<f64> {
    let mut max = f64::NEG_INFINITY;
    for (v, &m) in image.data().iter().zip(mask.data()) {
        if m {
            max = max.max(*v);
        }
    }
    if max == f64::NEG_INFINITY {
        return Err(Error::invalid(
            "the mask is empty: the light cannot be estimated",
        ));
    }
    if max <= 0.0 {
        return Err(Error::invalid(
            "the image is black (or negative) inside the mask: the light cannot be estimated",
        ));
    }
    Ok(max)
}

/// The limb fit and its slant's sampling standard error (degrees; what decides
/// [`EstimateMethod::LimbAndMoments`]), or `None` where the limb is too short or too straight
/// for it.
fn limb_estimate(image: &Image, mask: &Mask) -> Result<Option<(LightEstimate, f64)>> {
    let rho = brightest(image, mask)?;
    let normals = occluding_normals(mask);
    // (n_x, n_y, I) of the lit limb pixels.
    let samples: Vec<[f64; 3]> = normals
        .data()
        .iter()
        .zip(image.data())
        .filter_map(|(n, &v)| n.map(|n| [n.x, n.y, v]))
        .filter(|s| s[2] > LIT_FRACTION * rho)
        .collect();
    if samples.len() < MIN_LIMB_PIXELS || !spans_two_directions(&samples) {
        return Ok(None);
    }
    let mut keep = vec![true; samples.len()];
    let mut fit = None;
    for _ in 0..6 {
        let Some(f) = fit_limb(&samples, &keep) else {
            return Ok(None);
        };
        let residuals: Vec<f64> = samples.iter().map(|s| s[2] - f.predict(s)).collect();
        let mut abs: Vec<f64> = residuals.iter().map(|r| r.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let scale = (1.4826 * abs[abs.len() / 2]).max(1e-3 * rho);
        // One-sided: the limb is the dimmest an outline pixel can be for its normal.
        let next: Vec<bool> = residuals
            .iter()
            .map(|&r| r <= TRIM_ABOVE_SIGMAS * scale && r >= -TRIM_SIGMAS * scale)
            .collect();
        let settled = next == keep;
        fit = Some(f);
        if settled || next.iter().filter(|&&k| k).count() < MIN_LIMB_PIXELS {
            break;
        }
        keep = next;
    }
    let Some(f) = fit else {
        return Ok(None);
    };
    let (a, b) = (f.coef[0], f.coef[1]);
    let amplitude = a.hypot(b);
    let tilt_deg = if amplitude > 0.0 {
        (-a).atan2(b).to_degrees()
    } else {
        0.0
    };
    let slant_deg = limb_slant(amplitude / rho, f.coef[2] / rho)
        .to_degrees()
        .min(MAX_ESTIMATED_SLANT_DEG);
    // Variances of (a, b) across and along the light's image-plane direction.
    let (ua, ub) = if amplitude > 0.0 {
        (a / amplitude, b / amplitude)
    } else {
        (0.0, 1.0)
    };
    let quad = |x: f64, y: f64| {
        x * x * f.cov[(0, 0)] + 2.0 * x * y * f.cov[(0, 1)] + y * y * f.cov[(1, 1)]
    };
    let across = quad(-ub, ua).max(0.0).sqrt();
    let along = quad(ua, ub).max(0.0).sqrt();
    let tilt_se_deg = if amplitude > 0.0 {
        (across / amplitude).atan().to_degrees()
    } else {
        180.0
    };
    let cos_slant = slant_deg.to_radians().cos();
    let slant_se_deg = if cos_slant * rho > along {
        (along / (rho * cos_slant)).to_degrees().min(90.0)
    } else {
        90.0
    };
    let pixels = keep.iter().filter(|&&k| k).count();
    // The model's own error: how far the answer moves with each eighth of the outline's
    // directions left out.
    let left_out: Vec<(f64, f64)> = (0..JACKKNIFE_SECTORS)
        .filter_map(|k| {
            let without: Vec<bool> = samples
                .iter()
                .zip(&keep)
                .map(|(s, &kept)| kept && sector(s[0], s[1]) != k)
                .collect();
            if without == keep || without.iter().filter(|&&k| k).count() < MIN_LIMB_PIXELS {
                return None;
            }
            let f = fit_limb(&samples, &without)?;
            let (a, b) = (f.coef[0], f.coef[1]);
            let amplitude = a.hypot(b);
            (amplitude > 0.0).then(|| {
                let slant = limb_slant(amplitude / rho, f.coef[2] / rho).to_degrees();
                (
                    (-a).atan2(b).to_degrees(),
                    slant.min(MAX_ESTIMATED_SLANT_DEG),
                )
            })
        })
        .collect();
    let (tilt_jk, slant_jk) = jackknife(&left_out, (tilt_deg, slant_deg));
    let block = outline_blocks(f.count);
    let fit_slant_se = slant_se_deg;
    let tilt_se_deg = (block * tilt_se_deg).hypot(tilt_jk).min(180.0);
    let slant_se_deg = (block * slant_se_deg).hypot(slant_jk).min(90.0);
    let (tilt, slant) = ((tilt_deg, tilt_se_deg), (slant_deg, slant_se_deg));
    let e = limb_light(image, mask, EstimateMethod::Limb, tilt, slant, rho, pixels)?;
    Ok(Some((e, fit_slant_se)))
}

/// A limb fit's estimate from its tilt and slant (each in degrees with its standard error), its
/// albedo and the limb pixels it kept; the tilt confidence is the image's mean unit gradient
/// over the mask.
fn limb_light(
    image: &Image,
    mask: &Mask,
    method: EstimateMethod,
    (tilt_deg, tilt_se_deg): (f64, f64),
    (slant_deg, slant_se_deg): (f64, f64),
    albedo: f64,
    limb_pixels: usize,
) -> Result<LightEstimate> {
    Ok(LightEstimate {
        light: FrontLight::new(Light::from_tilt_slant(tilt_deg, slant_deg)?)?,
        tilt_deg,
        slant_deg,
        albedo,
        tilt_confidence: mean_unit_gradient(image, mask).length(),
        method,
        tilt_se_deg,
        slant_se_deg: Some(slant_se_deg),
        limb_pixels,
        warning: None,
    })
}

/// One limb pixel's ray into the band.
struct Ray {
    /// The outward normal in the image plane (world x, y).
    normal: [f64; 2],
    /// The lit samples along the inward normal: (distance from the contour, brightness).
    samples: Vec<(f64, f64)>,
    /// The cross-section radius, pixels (first half the chord, then fitted).
    radius: f64,
}

impl Ray {
    /// The surface normal at `distance` inside the contour of a circular cross-section of
    /// radius `radius`: edge-on at the contour, turning toward the viewer inward.
    fn normal_at(&self, distance: f64, radius: f64) -> Vector3<f64> {
        let q = (1.0 - distance / radius).clamp(0.0, 1.0);
        Vector3::new(
            q * self.normal[0],
            q * self.normal[1],
            (1.0 - q * q).max(0.0).sqrt(),
        )
    }

    /// The mean squared residual of the samples under the scaled light `g` with `radius`.
    fn misfit(&self, g: &Vector3<f64>, radius: f64) -> f64 {
        let sum: f64 = self
            .samples
            .iter()
            .map(|&(d, v)| (v - g.dot(&self.normal_at(d, radius))).powi(2))
            .sum();
        sum / self.samples.len().max(1) as f64
    }
}

/// Bilinear interpolation of `image` at pixel coordinates (`col`, `row`), where the four
/// pixels around it are in the mask.
fn sample_inside(image: &Image, mask: &Mask, col: f64, row: f64) -> Option<f64> {
    let (c0, r0) = (col.floor(), row.floor());
    let (fc, fr) = (col - c0, row - r0);
    let (c, r) = (c0 as isize, r0 as isize);
    let mut value = 0.0;
    for (dc, dr, weight) in [
        (0, 0, (1.0 - fc) * (1.0 - fr)),
        (1, 0, fc * (1.0 - fr)),
        (0, 1, (1.0 - fc) * fr),
        (1, 1, fc * fr),
    ] {
        if mask.checked(c + dc, r + dr) != Some(&true) {
            return None;
        }
        value += weight * image.get((c + dc) as usize, (r + dr) as usize);
    }
    Some(value)
}

/// The rays of the band: for each limb pixel, its lit samples at [`BAND_STEPS`] along the
/// inward normal, and half the chord across the mask along it.
fn band_rays(image: &Image, mask: &Mask, rho: f64) -> Vec<Ray> {
    let normals = occluding_normals(mask);
    let w = mask.width();
    let limit = (w + mask.height()) as f64;
    let mut rays = Vec::new();
    for (index, n) in normals.data().iter().enumerate() {
        let Some(n) = n else { continue };
        let (col, row) = ((index % w) as f64, (index / w) as f64);
        // One step inward is (−n_x, +n_y) in (column, row): world y points up.
        let at = |t: f64| (col - n.x * t, row + n.y * t);
        let mut chord = 0.0;
        while chord < limit {
            let (c, r) = at(chord + 1.0);
            if mask.checked(c.round() as isize, r.round() as isize) != Some(&true) {
                break;
            }
            chord += 1.0;
        }
        // The pixel's centre lies inside the contour by half a step on average.
        let offset = 0.5 * n.x.abs().max(n.y.abs());
        let mut samples = Vec::new();
        for t in BAND_STEPS {
            let value = if t == 0.0 {
                Some(image.data()[index])
            } else {
                let (c, r) = at(t);
                sample_inside(image, mask, c, r)
            };
            let Some(v) = value else { break };
            if v > LIT_FRACTION * rho {
                samples.push((offset + t, v));
            }
        }
        rays.push(Ray {
            normal: [n.x, n.y],
            samples,
            radius: (0.5 * (chord + 1.0)).max(1.0),
        });
    }
    rays
}

/// The least-squares fit I = g·n over the kept rays' samples (g = ρ·s).
fn fit_band(rays: &[Ray], keep: &[bool]) -> Option<LinearFit> {
    least_squares(
        rays.iter()
            .zip(keep)
            .filter(|(_, &k)| k)
            .flat_map(|(r, _)| {
                r.samples
                    .iter()
                    .map(move |&(d, v)| (r.normal_at(d, r.radius), v))
            }),
    )
}

/// The limb band fit, or `None` where the limb is too short or too straight for it or the
/// band's model does not explain the band (residuals above [`MAX_BAND_RESIDUAL`]).
fn band_estimate(image: &Image, mask: &Mask) -> Result<Option<LightEstimate>> {
    let rho = brightest(image, mask)?;
    let mut rays = band_rays(image, mask, rho);
    let directions: Vec<[f64; 3]> = rays
        .iter()
        .filter(|r| !r.samples.is_empty())
        .map(|r| [r.normal[0], r.normal[1], 0.0])
        .collect();
    if directions.len() < MIN_LIMB_PIXELS || !spans_two_directions(&directions) {
        return Ok(None);
    }
    let radii = band_radii(mask.width(), mask.height());
    let mut keep = vec![true; rays.len()];
    let mut fit = None;
    for _ in 0..BAND_ROUNDS {
        let Some(f) = fit_band(&rays, &keep) else {
            return Ok(None);
        };
        // Each ray's radius given the light, and how well it then fits.
        let mut misfits = Vec::with_capacity(rays.len());
        for ray in &mut rays {
            if ray.samples.is_empty() {
                // In the attached shadow: nothing to fit.
                misfits.push(0.0);
                continue;
            }
            let mut best = (f64::INFINITY, ray.radius);
            for &radius in &radii {
                let e = ray.misfit(&f.coef, radius);
                if e < best.0 {
                    best = (e, radius);
                }
            }
            ray.radius = best.1;
            misfits.push(best.0.sqrt());
        }
        // The scale from the rays that have samples.
        let mut sorted: Vec<f64> = misfits
            .iter()
            .zip(&rays)
            .filter(|(_, r)| !r.samples.is_empty())
            .map(|(&e, _)| e)
            .collect();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        let scale = (1.4826 * median).max(1e-3 * rho);
        keep = misfits.iter().map(|&e| e <= TRIM_SIGMAS * scale).collect();
        fit = Some(f);
    }
    let Some(LinearFit {
        coef: g,
        cov,
        rss,
        count,
    }) = fit
    else {
        return Ok(None);
    };
    let rms = (rss / count.max(1) as f64).sqrt();
    let kept = rays
        .iter()
        .zip(&keep)
        .filter(|(r, &k)| k && !r.samples.is_empty())
        .count();
    if rms > MAX_BAND_RESIDUAL * rho || kept < MIN_LIMB_PIXELS || g.norm() <= 0.0 {
        return Ok(None);
    }
    let across_plane = g[0].hypot(g[1]);
    let tilt_deg = if across_plane > 0.0 {
        (-g[0]).atan2(g[1]).to_degrees()
    } else {
        0.0
    };
    let slant_deg = across_plane
        .atan2(g[2])
        .to_degrees()
        .min(MAX_ESTIMATED_SLANT_DEG);
    // Standard errors: the tilt's from the variance of g across the light's image-plane
    // direction, the slant's from the variances of |g_xy| and g_z (linearised).
    let (ua, ub) = if across_plane > 0.0 {
        (g[0] / across_plane, g[1] / across_plane)
    } else {
        (0.0, 1.0)
    };
    let quad =
        |x: f64, y: f64| x * x * cov[(0, 0)] + 2.0 * x * y * cov[(0, 1)] + y * y * cov[(1, 1)];
    let tilt_se_deg = if across_plane > 0.0 {
        (quad(-ub, ua).max(0.0).sqrt() / across_plane)
            .atan()
            .to_degrees()
    } else {
        180.0
    };
    let norm2 = g.norm_squared();
    let (jh, jz) = (g[2] / norm2, -across_plane / norm2);
    let var_h = quad(ua, ub);
    let cov_hz = ua * cov[(0, 2)] + ub * cov[(1, 2)];
    let slant_var = jh * jh * var_h + 2.0 * jh * jz * cov_hz + jz * jz * cov[(2, 2)];
    let slant_se_deg = slant_var.max(0.0).sqrt().to_degrees().min(90.0);
    // The model's own error: how far the answer moves with each eighth of the outline's
    // directions left out (the radii as fitted).
    let left_out: Vec<(f64, f64)> = (0..JACKKNIFE_SECTORS)
        .filter_map(|k| {
            let without: Vec<bool> = rays
                .iter()
                .zip(&keep)
                .map(|(r, &kept)| kept && sector(r.normal[0], r.normal[1]) != k)
                .collect();
            if without == keep {
                return None;
            }
            let g = fit_band(&rays, &without)?.coef;
            let across = g[0].hypot(g[1]);
            (across > 0.0).then(|| {
                let slant = across.atan2(g[2]).to_degrees();
                (
                    (-g[0]).atan2(g[1]).to_degrees(),
                    slant.min(MAX_ESTIMATED_SLANT_DEG),
                )
            })
        })
        .collect();
    let (tilt_jk, slant_jk) = jackknife(&left_out, (tilt_deg, slant_deg));
    let block = outline_blocks(count);
    let tilt_se_deg = (block * tilt_se_deg).hypot(tilt_jk).min(180.0);
    let slant_se_deg = (block * slant_se_deg).hypot(slant_jk).min(90.0);
    let (tilt, slant) = ((tilt_deg, tilt_se_deg), (slant_deg, slant_se_deg));
    let method = EstimateMethod::LimbBand;
    limb_light(image, mask, method, tilt, slant, rho, kept).map(Some)
}

/// The outline is cut into this many sectors of its normals' directions for the jackknife.
const JACKKNIFE_SECTORS: usize = 8;

/// How much wider a fit's standard errors are when its `count` residuals are taken as
/// [`JACKKNIFE_SECTORS`] independent blocks along the outline rather than independent pixels:
/// √(count / sectors) (at least 1). A model's misfit runs along the outline (a cross-section
/// that is no circle, a stretch of cut), so neighbouring pixels' residuals agree, and the
/// pixel count overstates what they tell.
fn outline_blocks(count: usize) -> f64 {
    (count as f64 / JACKKNIFE_SECTORS as f64).max(1.0).sqrt()
}

/// The sector (0..[`JACKKNIFE_SECTORS`]) of the image-plane direction (`x`, `y`).
fn sector(x: f64, y: f64) -> usize {
    let turn = (y.atan2(x) + std::f64::consts::PI) / std::f64::consts::TAU;
    ((turn * JACKKNIFE_SECTORS as f64) as usize).min(JACKKNIFE_SECTORS - 1)
}

/// The delete-a-group jackknife's standard errors (degrees) of the tilt and slant, from the
/// estimates with each sector of the outline left out in turn (`left_out`, (tilt, slant)) and
/// the estimate from all of it: √((k − 1)/k · Σ(θᵢ − θ̄)²) over the k sectors, the tilts
/// unwrapped around the full estimate's. This is what the fits' own standard errors miss: they
/// assume residuals independent from pixel to pixel, while a model that does not fit the
/// object (a cross-section that is no circle, an outline that is partly a cut) leaves
/// residuals that run along the outline, and moves the answer as parts of the outline come and
/// go. Fewer than three sectors give 0 (the fit's errors alone).
fn jackknife(left_out: &[(f64, f64)], (tilt, slant): (f64, f64)) -> (f64, f64) {
    let k = left_out.len();
    if k < 3 {
        return (0.0, 0.0);
    }
    let spread = |d: Vec<f64>| {
        let mean = d.iter().sum::<f64>() / k as f64;
        let sum: f64 = d.iter().map(|v| (v - mean).powi(2)).sum();
        ((k - 1) as f64 / k as f64 * sum).sqrt()
    };
    let wrap = |d: f64| (d + 180.0).rem_euclid(360.0) - 180.0;
    (
        spread(left_out.iter().map(|e| wrap(e.0 - tilt)).collect()),
        spread(left_out.iter().map(|e| e.1 - slant).collect()),
    )
}

/// The slant σ (radians) from the limb fit's amplitude u = |(a, b)|/ρ and constant v = c/ρ.
///
/// The rim pixels' centres lie inside the silhouette, where the normal has a small mean
/// z component κ, so u = sin σ·√(1 − κ²) and v = κ·cos σ. Eliminating κ gives, for C = cos²σ,
/// C² − C·(1 + v² − u²) + v² = 0; the larger root is the one with the smaller κ (the rim lies
/// close to the limb), and the true one while κ < cos σ (below about 78° for κ = 0.2).
/// With v ≤ 0 (no light from the front on the rim) it is sin σ = u.
fn limb_slant(u: f64, v: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    if v <= 0.0 {
        return u.asin();
    }
    let p = 1.0 + v * v - u * u;
    let disc = p * p - 4.0 * v * v;
    if disc < 0.0 {
        // No κ fits both (a noisy fit): the root of the nearest case.
        return (0.5 * p).clamp(0.0, 1.0).sqrt().acos();
    }
    (0.5 * (p + disc.sqrt())).min(1.0).sqrt().acos()
}

/// Whether the limb normals point in more than one direction (the 2 × 2 covariance of the
/// normals has a smaller eigenvalue of at least 0.02, as an arc of about 30° gives).
fn spans_two_directions(samples: &[[f64; 3]]) -> bool {
    let n = samples.len() as f64;
    let (mx, my) = samples
        .iter()
        .fold((0.0, 0.0), |(x, y), s| (x + s[0] / n, y + s[1] / n));
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for s in samples {
        let (dx, dy) = (s[0] - mx, s[1] - my);
        xx += dx * dx / n;
        xy += dx * dy / n;
        yy += dy * dy / n;
    }
    let half_trace = 0.5 * (xx + yy);
    let smaller = half_trace - (0.25 * (xx - yy).powi(2) + xy * xy).sqrt();
    smaller >= 1e-4
}

/// A least-squares fit y = coef·x.
struct LinearFit {
    /// The coefficients: (a, b, c) of the rim fit, g = ρ·s of the band fit.
    coef: Vector3<f64>,
    /// Their covariance.
    cov: Matrix3<f64>,
    /// The residual sum of squares.
    rss: f64,
    /// The rows fitted.
    count: usize,
}

impl LinearFit {
    fn predict(&self, s: &[f64; 3]) -> f64 {
        self.coef[0] * s[0] + self.coef[1] * s[1] + self.coef[2]
    }
}

/// Least squares y = coef·x over the rows (x, y); `None` when they leave it undetermined.
fn least_squares(rows: impl Iterator<Item = (Vector3<f64>, f64)> + Clone) -> Option<LinearFit> {
    let mut ata = Matrix3::zeros();
    let mut atb = Vector3::zeros();
    let mut count = 0usize;
    for (x, y) in rows.clone() {
        ata += x * x.transpose();
        atb += x * y;
        count += 1;
    }
    let inverse = ata.try_inverse()?;
    let coef = inverse * atb;
    let rss: f64 = rows.map(|(x, y)| (y - coef.dot(&x)).powi(2)).sum();
    let variance = rss / (count.saturating_sub(3).max(1)) as f64;
    Some(LinearFit {
        coef,
        cov: inverse * variance,
        rss,
        count,
    })
}

/// The rim fit I = a·n_x + b·n_y + c over the kept samples (n_x, n_y, I); `None` when they
/// leave it undetermined.
fn fit_limb(samples: &[[f64; 3]], keep: &[bool]) -> Option<LinearFit> {
    least_squares(
        samples
            .iter()
            .zip(keep)
            .filter(|(_, &k)| k)
            .map(|(s, _)| (Vector3::new(s[0], s[1], 1.0), s[2])),
    )
}

/// The mean of the unit image gradients.
struct MeanGradient {
    /// Its world x and y components (x right, y up).
    x: f64,
    y: f64,
    /// The sampling standard error of its direction, radians (π with no gradients).
    direction_se: f64,
}

impl MeanGradient {
    /// Its length, 0..1.
    fn length(&self) -> f64 {
        self.x.hypot(self.y)
    }
}

/// The mean unit image gradient over the pixels whose four neighbours are in the mask.
fn mean_unit_gradient(image: &Image, mask: &Mask) -> MeanGradient {
    let (w, h) = (image.width(), image.height());
    let mut units = Vec::new();
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
                units.push((dx / len, dy / len));
            }
        }
    }
    if units.is_empty() {
        return MeanGradient {
            x: 0.0,
            y: 0.0,
            direction_se: std::f64::consts::PI,
        };
    }
    let n = units.len() as f64;
    let (mut sx, mut sy) = (0.0, 0.0);
    for u in &units {
        sx += u.0;
        sy += u.1;
    }
    let (x, y) = (sx / n, sy / n);
    let length = x.hypot(y);
    // The spread across the mean direction over √n, relative to the mean's length.
    let direction_se = if length > 1e-12 {
        let (px, py) = (-y / length, x / length);
        let across: f64 = units.iter().map(|u| (u.0 * px + u.1 * py).powi(2)).sum();
        ((across / n).sqrt() / (n.sqrt() * length)).atan()
    } else {
        std::f64::consts::PI
    };
    MeanGradient { x, y, direction_se }
}

/// The Zheng–Chellappa estimate (see the module documentation).
fn moments_estimate(image: &Image, mask: &Mask) -> Result<LightEstimate> {
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
    let g = mean_unit_gradient(image, mask);
    let tilt_confidence = g.length();
    // The light's image-plane direction is (−sin τ, cos τ): brightening toward (mx, my).
    let tilt_deg = if tilt_confidence > 1e-12 {
        (-g.x).atan2(g.y).to_degrees()
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
    let light = FrontLight::new(Light::from_tilt_slant(tilt_deg, slant_deg)?)?;
    Ok(LightEstimate {
        light,
        tilt_deg,
        slant_deg,
        albedo,
        tilt_confidence,
        method: EstimateMethod::Moments,
        tilt_se_deg: g.direction_se.to_degrees().min(180.0),
        slant_se_deg: None,
        limb_pixels: 0,
        warning: None,
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

    /// The share of estimates whose ±2σ holds the true tilt (lights of slant 20° or more) and
    /// slant, over spheres, ellipsoids and vases at `sizes`, 4 slants × 8 tilts, albedo 0.8;
    /// prints each object's figures.
    fn coverage(sizes: &[usize]) -> (f64, f64) {
        type Shape = fn(usize) -> crate::surface::Surface;
        let shapes: [(&str, Shape); 3] = [
            ("sphere", |n| sphere(n, n, 0.45 * n as f64).unwrap()),
            ("ellipsoid", |n| {
                let n_f = n as f64;
                crate::surface::ellipsoid(n, n, 0.45 * n_f, 0.3 * n_f, 0.35 * n_f).unwrap()
            }),
            ("vase", |n| crate::surface::vase(n, n).unwrap()),
        ];
        let (mut tilt_in, mut slant_in, mut total) = (0usize, 0usize, 0usize);
        for (name, make) in shapes {
            for &n in sizes {
                let s = make(n);
                let (mut t_in, mut s_in, mut count) = (0, 0, 0);
                let (mut worst_t, mut worst_s) = (0.0f64, 0.0f64);
                for slant in [20.0, 35.0, 50.0, 65.0] {
                    for tilt in [0.0, 30.0, 75.0, 120.0, 165.0, 210.0, 255.0, 300.0] {
                        let light = Light::from_tilt_slant(tilt, slant).unwrap();
                        let map = Lambertian {
                            light,
                            albedo: 0.8,
                            ambient: 0.0,
                        };
                        let image = render(&s, &map, &RenderOptions::default()).image;
                        let e = estimate_light_with(&image, &s.mask, Outline::Occluding).unwrap();
                        let se = e.slant_se_deg.unwrap_or(0.0);
                        let dt = tilt_difference(e.tilt_deg, tilt) / e.tilt_se_deg.max(1e-9);
                        let ds = (e.slant_deg - slant).abs() / se.max(1e-9);
                        worst_t = worst_t.max(dt);
                        worst_s = worst_s.max(ds);
                        t_in += usize::from(dt <= 2.0);
                        s_in += usize::from(ds <= 2.0);
                        count += 1;
                    }
                }
                eprintln!(
                    "{name} {n}²: tilt within ±2σ {t_in}/{count}, slant {s_in}/{count}; \
                     worst |error|/σ tilt {worst_t:.1}, slant {worst_s:.1}"
                );
                tilt_in += t_in;
                slant_in += s_in;
                total += count;
            }
        }
        let share = |k: usize| k as f64 / total as f64;
        eprintln!(
            "all: tilt {:.3}, slant {:.3} of {total}",
            share(tilt_in),
            share(slant_in)
        );
        (share(tilt_in), share(slant_in))
    }

    #[test]
    fn the_true_light_lies_within_two_standard_errors_in_nine_cases_of_ten() {
        let (tilt, slant) = coverage(&[64, 96]);
        assert!(tilt >= 0.9 && slant >= 0.9, "tilt {tilt}, slant {slant}");
    }

    #[test]
    fn a_whole_frame_mask_warns() {
        let light = Light::from_tilt_slant(45.0, 40.0).unwrap();
        let (image, mask) = sphere_image(light, 0.8);
        let e = estimate_light_with(&image, &mask, Outline::Occluding).unwrap();
        assert_eq!(e.warning, None);
        let whole = Grid::new(image.width(), image.height(), true);
        let e = estimate_light_with(&image, &whole, Outline::Occluding).unwrap();
        assert_eq!(e.warning, Some(WHOLE_FRAME_WARNING));
    }

    #[test]
    fn band_radii_reach_the_size_of_the_mask() {
        assert_eq!(band_radii(128, 96), BAND_RADII.to_vec());
        let radii = band_radii(300, 600);
        assert_eq!(radii[BAND_RADII.len()..], [192.0, 256.0, 384.0, 512.0]);
        assert!(radii.windows(2).all(|w| w[0] < w[1]));
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
    fn the_limb_slant_inverts_its_model() {
        // Up to the slant where κ reaches cos σ (78° for κ = 0.2): beyond it the two roots
        // trade places and the smaller-κ root is taken.
        for slant in [0.0f64, 10.0, 30.0, 45.0, 60.0, 75.0] {
            for kappa in [0.0f64, 0.1, 0.2] {
                let s = slant.to_radians();
                let (u, v) = (s.sin() * (1.0 - kappa * kappa).sqrt(), kappa * s.cos());
                let got = limb_slant(u, v).to_degrees();
                assert!((got - slant).abs() < 1e-6, "{slant} {kappa}: {got}");
            }
        }
    }

    #[test]
    fn the_band_refuses_a_picture_its_model_cannot_explain() {
        // A disc of one grey: no surface lit by one light turns edge-on at its outline and
        // stays as bright there as inside (residuals ≈ 30 % of the albedo).
        let s = sphere(64, 64, 28.0).unwrap();
        let image = s.mask.map(|&m| if m { 0.6 } else { 0.0 });
        assert!(band_estimate(&image, &s.mask).unwrap().is_none());
        let e = estimate_light_with(&image, &s.mask, Outline::Occluding).unwrap();
        assert_eq!(e.method, EstimateMethod::Limb);
        // The same disc shaded as a sphere is explained.
        let light = Light::from_tilt_slant(-60.0, 50.0).unwrap();
        let map = Lambertian {
            light,
            albedo: 0.7,
            ambient: 0.0,
        };
        let shaded = render(&s, &map, &RenderOptions::default()).image;
        let e = band_estimate(&shaded, &s.mask).unwrap().unwrap();
        assert!(tilt_difference(e.tilt_deg, -60.0) < 1.0, "{e:?}");
        assert!((e.slant_deg - 50.0).abs() < 1.5, "{e:?}");
        assert!((e.albedo - 0.7).abs() < 0.01, "{e:?}");
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

//! How far a reconstruction is from the truth: angular error of normals, depth error after the
//! unknown scale and offset are taken out, and the shading residual |R(n) − I|.

use crate::error::{Error, Result};
use crate::gradient_space::{angle_deg, Normal};
use crate::grid::{Grid, Image, Mask};
use crate::integrate::fit_scale_offset;
use crate::reflectance::ReflectanceMap;
use serde::Serialize;

/// Summary of the angle between estimated and true normals over a mask.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AngularError {
    /// Mean angle in degrees.
    pub mean_deg: f64,
    /// Median angle in degrees.
    pub median_deg: f64,
    /// The 90th percentile in degrees.
    pub p90_deg: f64,
    /// Pixels measured.
    pub pixels: usize,
}

/// The angle in degrees between `estimate` and `truth` at every pixel of `mask` (0 elsewhere).
pub fn angular_error_map(
    estimate: &Grid<Normal>,
    truth: &Grid<Normal>,
    mask: &Mask,
) -> Result<Image> {
    check_sizes(estimate, truth, mask)?;
    Ok(Grid::from_fn(mask.width(), mask.height(), |c, r| {
        if *mask.get(c, r) {
            angle_deg(estimate.get(c, r), truth.get(c, r))
        } else {
            0.0
        }
    }))
}

/// Mean, median and 90th percentile of the angle between `estimate` and `truth` over `mask`.
/// Fails on mismatched sizes or an empty mask.
pub fn angular_error(
    estimate: &Grid<Normal>,
    truth: &Grid<Normal>,
    mask: &Mask,
) -> Result<AngularError> {
    let map = angular_error_map(estimate, truth, mask)?;
    let mut angles: Vec<f64> = map
        .data()
        .iter()
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .map(|(a, _)| *a)
        .collect();
    if angles.is_empty() {
        return Err(Error::invalid("the mask is empty: no normals to compare"));
    }
    // Summed in pixel order, so the mean does not depend on how the map was computed.
    let mean_deg = angles.iter().sum::<f64>() / angles.len() as f64;
    angles.sort_by(f64::total_cmp);
    Ok(AngularError {
        mean_deg,
        median_deg: quantile_sorted(&angles, 0.5),
        p90_deg: quantile_sorted(&angles, 0.9),
        pixels: angles.len(),
    })
}

pub use crate::albedo::quantile_sorted;

/// The depth error of a reconstruction once its unknown scale and offset are fitted away.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DepthError {
    /// Root-mean-square difference after the fit, in pixels (the unit of the true depth).
    pub rms_px: f64,
    /// The same as a percentage of the true depth range on the mask.
    pub rms_percent_of_range: f64,
    /// The true depth range (largest − smallest) on the mask, in pixels.
    pub true_range_px: f64,
    /// The fitted scale: truth ≈ scale·estimate + offset.
    pub scale: f64,
    /// The fitted offset.
    pub offset: f64,
}

/// Fits truth ≈ scale·estimate + offset on `mask` by least squares
/// ([`crate::integrate::fit_scale_offset`]) and reports what is left.
pub fn depth_error(estimate: &Image, truth: &Image, mask: &Mask) -> Result<DepthError> {
    let fit = fit_scale_offset(estimate, truth, mask)?;
    let (lo, hi) =
        crate::integrate::masked_range(truth, mask).unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
    let range = hi - lo;
    Ok(DepthError {
        rms_px: fit.rmse,
        rms_percent_of_range: if range > 0.0 {
            100.0 * fit.rmse / range
        } else {
            0.0
        },
        true_range_px: range,
        scale: fit.scale,
        offset: fit.offset,
    })
}

/// Mean |R(n) − I| over `mask`: how well the recovered normals explain the image under the
/// reflectance map they were solved with (in the image's units).
pub fn shading_residual(
    normals: &Grid<Normal>,
    image: &Image,
    mask: &Mask,
    reflectance: &dyn ReflectanceMap,
) -> Result<f64> {
    check_sizes(normals, image, mask)?;
    let (sum, n) = normals
        .data()
        .iter()
        .zip(image.data())
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .fold((0.0, 0usize), |(s, n), ((normal, i), _)| {
            (s + (reflectance.radiance(normal) - i).abs(), n + 1)
        });
    if n == 0 {
        return Err(Error::invalid("the mask is empty: no residual to measure"));
    }
    Ok(sum / n as f64)
}

fn check_sizes<A, B>(a: &Grid<A>, b: &Grid<B>, mask: &Mask) -> Result<()> {
    if a.same_size(b) && a.same_size(mask) {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "sizes differ: {}, {} and a mask of {}",
            crate::message::SizeText::Pixels(a.height(), a.width()),
            crate::message::SizeText::Pixels(b.height(), b.width()),
            crate::message::SizeText::Pixels(mask.height(), mask.width())
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::Light;
    use crate::reflectance::Lambertian;
    use nalgebra::Vector3;

    #[test]
    fn identical_normals_have_no_error_and_orthogonal_ones_ninety_degrees() {
        let n = Vector3::new(0.3, -0.2, 0.9).normalize();
        let truth = Grid::new(4, 3, n);
        let mask = Grid::new(4, 3, true);
        let e = angular_error(&truth, &truth, &mask).unwrap();
        assert_eq!((e.mean_deg, e.median_deg, e.pixels), (0.0, 0.0, 12));
        let orth = Grid::new(4, 3, Vector3::new(0.9, 0.0, -0.3).normalize());
        let e = angular_error(&orth, &truth, &mask).unwrap();
        assert!((e.mean_deg - 90.0).abs() < 1e-12, "{}", e.mean_deg);
        assert!((e.median_deg - 90.0).abs() < 1e-12);
    }

    #[test]
    fn only_masked_pixels_count_and_the_median_is_the_middle() {
        let z = Vector3::z();
        let tilted = |deg: f64| {
            let a = deg.to_radians();
            Vector3::new(a.sin(), 0.0, a.cos())
        };
        let est = Grid::from_vec(4, 1, vec![tilted(10.0), tilted(20.0), tilted(60.0), z]).unwrap();
        let truth = Grid::new(4, 1, z);
        let mask = Grid::from_vec(4, 1, vec![true, true, true, false]).unwrap();
        let e = angular_error(&est, &truth, &mask).unwrap();
        assert_eq!(e.pixels, 3);
        assert!((e.mean_deg - 30.0).abs() < 1e-9);
        assert!((e.median_deg - 20.0).abs() < 1e-9);
        assert!(angular_error(&est, &truth, &Grid::new(4, 1, false)).is_err());
        assert!(angular_error(&est, &Grid::new(3, 1, z), &mask).is_err());
    }

    #[test]
    fn scale_and_offset_are_recovered_exactly() {
        let truth = Grid::from_fn(7, 5, |c, r| (c * c) as f64 + 0.5 * r as f64);
        // estimate = (truth − 3) / 2.5, so truth = 2.5·estimate + 3 exactly.
        let estimate = truth.map(|z| (z - 3.0) / 2.5);
        let mask = Grid::new(7, 5, true);
        let e = depth_error(&estimate, &truth, &mask).unwrap();
        assert!((e.scale - 2.5).abs() < 1e-12, "{}", e.scale);
        assert!((e.offset - 3.0).abs() < 1e-12, "{}", e.offset);
        assert!(e.rms_px < 1e-12);
        assert_eq!(e.true_range_px, 36.0 + 2.0);
        // A mismatch the fit cannot remove is reported, in pixels and as a share of the range.
        let mut bumped = estimate.clone();
        *bumped.get_mut(3, 2) += 1.0;
        let e = depth_error(&bumped, &truth, &mask).unwrap();
        assert!(e.rms_px > 0.1);
        assert!((e.rms_percent_of_range - 100.0 * e.rms_px / 38.0).abs() < 1e-12);
    }

    #[test]
    fn residual_is_zero_for_the_normals_that_made_the_image() {
        let light = Light::from_tilt_slant(30.0, 40.0).unwrap();
        let map = Lambertian {
            light,
            albedo: 0.7,
            ambient: 0.0,
        };
        let normals = Grid::from_fn(5, 5, |c, r| {
            Vector3::new(c as f64 * 0.1 - 0.2, 0.2 - r as f64 * 0.1, 1.0).normalize()
        });
        let image = normals.map(|n| map.radiance(n));
        let mask = Grid::new(5, 5, true);
        assert!(shading_residual(&normals, &image, &mask, &map).unwrap() < 1e-15);
        let brighter = image.map(|v| v + 0.1);
        let r = shading_residual(&normals, &brighter, &mask, &map).unwrap();
        assert!((r - 0.1).abs() < 1e-12);
    }
}

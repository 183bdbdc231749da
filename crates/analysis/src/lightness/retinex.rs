//! A Retinex lightness model in the manner of Land & McCann (1971) and Horn (1974).
//!
//! Illumination varies slowly across a scene while reflectance changes abruptly at the edges
//! of surfaces. In log luminance the two add, so the model differentiates log luminance,
//! discards every neighbour difference smaller than a threshold (taken to be illumination),
//! keeps the large ones (reflectance edges), and reintegrates the kept differences in least
//! squares with the engine's masked Poisson integrator
//! ([`crate::integrate::integrate_differences`]). The result is log reflectance up to an
//! additive constant per connected part of the mask; it is anchored so that the lightest pixel
//! is white (reflectance 1), Land's "highest luminance is white" rule.
//!
//! Least squares is linear, so the reintegrated kept differences equal log luminance minus the
//! reintegrated dropped ones; the solver is given the dropped (illumination) part, which is
//! small, often empty, and so quick to solve accurately.
//!
//! Thresholds are in natural-log units per pixel: 0.05 keeps steps of more than about 5 % in
//! luminance between neighbouring pixels. A soft shadow whose edge is spread over many pixels
//! falls below it; an anti-aliased reflectance edge, spread over one or two pixels, does not.

use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Mask};
use crate::imageops::parts::{parts, SumOrder};
use crate::integrate::{integrate_differences, Integration, PoissonOptions};

/// Retinex settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetinexOptions {
    /// Neighbour differences of log luminance with magnitude at or below this are dropped
    /// (natural-log units per pixel, ≥ 0).
    pub threshold: f64,
    /// Luminance below this is raised to it before taking logs (black pixels have no log).
    pub floor: f64,
    /// Conjugate-gradient tolerance and iteration cap of the reintegration.
    pub poisson: PoissonOptions,
}

impl Default for RetinexOptions {
    fn default() -> Self {
        RetinexOptions {
            threshold: 0.05,
            floor: 1e-4,
            poisson: PoissonOptions {
                tol: 1e-8,
                max_iter: 20_000,
            },
        }
    }
}

/// What [`retinex`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct RetinexOutput {
    /// Estimated reflectance, lightest pixel = 1 (0 outside the mask).
    pub lightness: Image,
    /// Estimated log reflectance, zero mean over each connected part of the mask.
    pub log_reflectance: Image,
    /// Fraction of neighbour differences kept as reflectance edges.
    pub kept_fraction: f64,
    /// Conjugate-gradient iterations of the reintegration.
    pub iterations: usize,
    /// Whether the reintegration reached its tolerance.
    pub converged: bool,
}

/// Runs Retinex on `image` (linear luminance) over `mask` (the whole image when `None`).
pub fn retinex(
    image: &Image,
    mask: Option<&Mask>,
    options: &RetinexOptions,
) -> Result<RetinexOutput> {
    if !(options.threshold.is_finite() && options.threshold >= 0.0) {
        return Err(Error::invalid(format!(
            "Retinex threshold {} must be a finite number ≥ 0",
            options.threshold
        )));
    }
    if !(options.floor.is_finite() && options.floor > 0.0) {
        return Err(Error::invalid(format!(
            "Retinex luminance floor {} must be positive",
            options.floor
        )));
    }
    let (w, h) = (image.width(), image.height());
    if let Some(i) = image.data().iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(format!(
            "image has a non-finite value ({}) at column {}, row {}",
            image.data()[i],
            i % w,
            i / w
        )));
    }
    let full;
    let mask = match mask {
        Some(m) => {
            m.check_same_size("mask is", image, "the image is")?;
            m
        }
        None => {
            full = Grid::new(w, h, true);
            &full
        }
    };
    let log = image.map(|&v| v.max(options.floor).ln());
    let t = options.threshold;
    let keep = |d: f64| if d.abs() > t { d } else { 0.0 };
    let mut kept = 0usize;
    let mut pairs = 0usize;
    let mut count = |d: f64| {
        pairs += 1;
        if d.abs() > t {
            kept += 1;
        }
    };
    for r in 0..h {
        for c in 0..w {
            if !*mask.get(c, r) {
                continue;
            }
            if c + 1 < w && *mask.get(c + 1, r) {
                count(log.get(c + 1, r) - log.get(c, r));
            }
            if r + 1 < h && *mask.get(c, r + 1) {
                count(log.get(c, r + 1) - log.get(c, r));
            }
        }
    }
    // Least squares is linear: integrating the kept differences gives log luminance minus
    // the integral of the dropped ones. Integrate the dropped (illumination) part: it is small
    // and often empty, so the solve is short and its error small in absolute terms.
    let dropped = |d: f64| d - keep(d);
    let right = Grid::from_fn(w, h, |c, r| {
        if c + 1 < w {
            dropped(log.get(c + 1, r) - log.get(c, r))
        } else {
            0.0
        }
    });
    let down = Grid::from_fn(w, h, |c, r| {
        if r + 1 < h {
            dropped(log.get(c, r + 1) - log.get(c, r))
        } else {
            0.0
        }
    });
    let illumination = integrate_differences(&right, &down, mask, &options.poisson)?;
    let mut depth = Grid::from_fn(w, h, |c, r| {
        if *mask.get(c, r) {
            log.get(c, r) - illumination.depth.get(c, r)
        } else {
            0.0
        }
    });
    // The offset between parts is unknown to a model that sees only differences within
    // them: each part gets zero mean, summed in the search's visiting order.
    parts(mask).subtract_means(depth.data_mut(), SumOrder::Visit);
    let solved = Integration {
        depth,
        ..illumination
    };
    let top = solved
        .depth
        .data()
        .iter()
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .map(|(v, _)| *v)
        .fold(f64::NEG_INFINITY, f64::max);
    let lightness = Grid::from_fn(w, h, |c, r| {
        if *mask.get(c, r) {
            (solved.depth.get(c, r) - top).exp()
        } else {
            0.0
        }
    });
    Ok(RetinexOutput {
        lightness,
        log_reflectance: solved.depth,
        kept_fraction: if pairs == 0 {
            0.0
        } else {
            kept as f64 / pairs as f64
        },
        iterations: solved.iterations,
        converged: solved.converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two reflectances (0.2 left, 0.8 right) under an illumination ramp from 1 down to 0.5.
    fn mondrian_under_a_ramp(w: usize, h: usize) -> (Image, Image) {
        let reflect = Grid::from_fn(w, h, |c, _| if c < w / 2 { 0.2 } else { 0.8 });
        let light = Grid::from_fn(w, h, |_, r| 1.0 - 0.5 * r as f64 / (h - 1) as f64);
        let image = Grid::from_fn(w, h, |c, r| reflect.get(c, r) * light.get(c, r));
        (image, reflect)
    }

    #[test]
    fn discounts_a_smooth_illumination_gradient() {
        let (image, reflect) = mondrian_under_a_ramp(24, 40);
        let out = retinex(&image, None, &RetinexOptions::default()).unwrap();
        assert!(out.converged);
        // The right half is white (anchored), the left half 0.2/0.8 = 0.25 of it, everywhere
        // down the ramp, although the luminance varies twofold.
        for r in 0..40 {
            for c in 0..24 {
                let want = reflect.get(c, r) / 0.8;
                let got = out.lightness.get(c, r);
                assert!((got - want).abs() < 1e-5, "({c},{r}) {got} vs {want}");
            }
        }
        // Only the edge pairs survive: 40 horizontal pairs out of 23·40 + 24·39.
        let expected = 40.0 / (23.0 * 40.0 + 24.0 * 39.0);
        assert!((out.kept_fraction - expected).abs() < 1e-12);
    }

    #[test]
    fn zero_threshold_returns_the_image_up_to_scale() {
        let (image, _) = mondrian_under_a_ramp(16, 12);
        let opts = RetinexOptions {
            threshold: 0.0,
            ..Default::default()
        };
        let out = retinex(&image, None, &opts).unwrap();
        let top = image.min_max().unwrap().1;
        for (a, b) in out.lightness.data().iter().zip(image.data()) {
            assert!((a - b / top).abs() < 1e-6);
        }
    }

    #[test]
    fn each_part_of_the_mask_has_zero_mean_log_reflectance() {
        let (image, _) = mondrian_under_a_ramp(24, 40);
        let mask = Grid::from_fn(24, 40, |c, _| !(8..16).contains(&c));
        let out = retinex(&image, Some(&mask), &RetinexOptions::default()).unwrap();
        for part in [0..8, 16..24] {
            let mut sum = 0.0;
            for r in 0..40 {
                for c in part.clone() {
                    sum += out.log_reflectance.get(c, r);
                }
            }
            assert!(sum.abs() < 1e-9, "{sum}");
        }
        // Within each part the illumination ramp is discounted: the part is uniform.
        let (lo, hi) = (out.lightness.get(2, 0), out.lightness.get(2, 39));
        assert!((lo - hi).abs() < 1e-6, "{lo} {hi}");
        assert_eq!(*out.lightness.get(10, 10), 0.0);
    }

    #[test]
    fn bad_input_is_an_error() {
        let image = Grid::new(8, 8, 0.5);
        let bad = RetinexOptions {
            threshold: -1.0,
            ..Default::default()
        };
        assert!(retinex(&image, None, &bad).is_err());
        assert!(retinex(
            &image,
            Some(&Grid::new(7, 8, true)),
            &RetinexOptions::default()
        )
        .is_err());
        let mut nan = image.clone();
        *nan.get_mut(1, 2) = f64::NAN;
        assert!(retinex(&nan, None, &RetinexOptions::default()).is_err());
        assert!(retinex(
            &image,
            Some(&Grid::new(8, 8, false)),
            &RetinexOptions::default()
        )
        .is_err());
    }
}

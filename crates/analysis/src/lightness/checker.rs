//! The checker-shadow analysis (Adelson 1995): squares A (in light) and B (in the cylinder's
//! shadow) have the same pixel values, yet B looks much lighter. The report states the pixel
//! facts and what each lightness model predicts for the two squares, whichever way it goes.

use super::{Model, Variant};
use crate::error::{Error, Result};
use crate::grid::{Image, Mask};
use serde::Serialize;

/// What the pixels of A and B are.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SquareFacts {
    /// Pixels in the square.
    pub pixels: usize,
    /// Smallest, mean and largest luminance in the square.
    pub min: f64,
    /// Mean luminance.
    pub mean: f64,
    /// Largest luminance.
    pub max: f64,
}

/// One model's prediction for A and B.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Prediction {
    /// The model's name.
    pub model: String,
    /// Mean model output over A.
    pub a: f64,
    /// Mean model output over B.
    pub b: f64,
    /// b − a: positive when the model sees B lighter, as people do.
    pub b_minus_a: f64,
    /// Whether the model agrees with the percept (B lighter than A).
    pub matches_percept: bool,
}

/// The checker-shadow report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckerReport {
    /// Square A's pixels.
    pub a: SquareFacts,
    /// Square B's pixels.
    pub b: SquareFacts,
    /// Whether every pixel of A and of B has one and the same value.
    pub identical_pixels: bool,
    /// Each model's prediction, in the order run.
    pub predictions: Vec<Prediction>,
    /// Models that could not be run on this image, with the reason.
    pub skipped: Vec<(String, String)>,
}

fn facts(image: &Image, mask: &Mask) -> SquareFacts {
    let values: Vec<f64> = image
        .data()
        .iter()
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .map(|(v, _)| *v)
        .collect();
    let n = values.len();
    SquareFacts {
        pixels: n,
        min: values.iter().cloned().fold(f64::INFINITY, f64::min),
        mean: values.iter().sum::<f64>() / n as f64,
        max: values.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
    }
}

/// The pixels of squares `a` and `b` in `image`, and whether all of them share one value.
pub fn pixel_facts(image: &Image, a: &Mask, b: &Mask) -> (SquareFacts, SquareFacts, bool) {
    let (fa, fb) = (facts(image, a), facts(image, b));
    let identical = fa.pixels > 0 && fa.min == fa.max && fb.min == fb.max && fa.min == fb.min;
    (fa, fb, identical)
}

/// A model's `output` averaged over squares `a` and `b`, and whether it sees B lighter.
pub fn predict(model: &str, output: &Image, a: &Mask, b: &Mask) -> Prediction {
    let mean = |m: &Mask| output.masked_mean(m).unwrap_or(f64::NAN);
    let (pa, pb) = (mean(a), mean(b));
    Prediction {
        model: model.to_string(),
        a: pa,
        b: pb,
        b_minus_a: pb - pa,
        matches_percept: pb > pa,
    }
}

/// Runs ODOG, LODOG, FLODOG (when the image is large enough in degrees) and Retinex on the
/// checker-shadow `image` and reports their predictions for squares `a` and `b`.
pub fn checker_shadow(image: &Image, a: &Mask, b: &Mask, ppd: f64) -> Result<CheckerReport> {
    for (name, m) in [("A", a), ("B", b)] {
        m.check_same_size(
            &format!("the mask of square {name} is"),
            image,
            "the image is",
        )?;
        if m.count() == 0 {
            return Err(Error::invalid(format!(
                "the mask of square {name} is empty"
            )));
        }
    }
    let (fa, fb, identical_pixels) = pixel_facts(image, a, b);
    let mut predictions = Vec::new();
    let mut skipped = Vec::new();
    let models = Variant::ALL
        .iter()
        .map(|v| Model::Odog(*v))
        .chain([Model::Retinex]);
    for model in models {
        match model.predict(image, Some(ppd)) {
            Ok(out) => predictions.push(predict(model.name(), &out, a, b)),
            Err(Error::Invalid(why)) => skipped.push((model.name().to_string(), why)),
            Err(e) => return Err(e),
        }
    }
    Ok(CheckerReport {
        a: fa,
        b: fb,
        identical_pixels,
        predictions,
        skipped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    /// A synthetic checker-shadow: a 4×4 checkerboard (0.8 / 0.2) of 24-pixel squares at
    /// 8 ppd (12°), lit from the top with a soft shadow (illumination 1 → 0.25 between rows
    /// 24 and 84). A is a dark square in full light, B a light square in full shadow: both 0.2.
    fn scene() -> (Image, Mask, Mask) {
        let (w, h, sq) = (96, 96, 24);
        let reflect = |c: usize, r: usize| if (c / sq + r / sq) % 2 == 0 { 0.8 } else { 0.2 };
        let light = |r: usize| {
            let t = ((r as f64 - 24.0) / 60.0).clamp(0.0, 1.0);
            1.0 - 0.75 * t * t * (3.0 - 2.0 * t)
        };
        let image = Grid::from_fn(w, h, |c, r| reflect(c, r) * light(r));
        let a = Grid::from_fn(w, h, |c, r| (26..46).contains(&c) && (2..22).contains(&r));
        let b = Grid::from_fn(w, h, |c, r| (26..46).contains(&c) && (86..94).contains(&r));
        (image, a, b)
    }

    #[test]
    fn reports_identical_pixels_and_every_model() {
        let (image, a, b) = scene();
        let report = checker_shadow(&image, &a, &b, 8.0).unwrap();
        assert!(report.identical_pixels);
        assert!((report.a.mean - 0.2).abs() < 1e-12 && (report.b.mean - 0.2).abs() < 1e-12);
        let names: Vec<&str> = report
            .predictions
            .iter()
            .map(|p| p.model.as_str())
            .collect();
        assert_eq!(names, ["odog", "lodog", "flodog", "retinex"]);
        // Retinex discounts the soft shadow: B (a light square) comes out about 4× lighter than
        // A (the checker edges inside the shadow carry a little of it).
        let retinex = &report.predictions[3];
        assert!(retinex.matches_percept);
        assert!((retinex.b / retinex.a - 4.0).abs() < 0.4, "{retinex:?}");
    }

    #[test]
    fn small_images_skip_the_filter_models_and_bad_masks_fail() {
        let (image, a, b) = scene();
        let report = checker_shadow(&image, &a, &b, 40.0).unwrap();
        assert_eq!(report.predictions.len(), 1);
        assert_eq!(report.skipped.len(), 3);
        assert!(checker_shadow(&image, &Grid::new(96, 96, false), &b, 8.0).is_err());
        assert!(checker_shadow(&image, &Grid::new(4, 4, true), &b, 8.0).is_err());
    }
}

//! Lightness and brightness models: what vision reports about surfaces, as opposed to the
//! luminance in the image. The checker-shadow and the fading disk are not shape-from-shading
//! illusions; they show that vision measures relative gradients and discounts illumination.
//!
//! - [`odog`]: the ODOG, LODOG and FLODOG filter models (multiscale oriented
//!   difference-of-Gaussians with divisive normalisation), matching the multyscale package.
//! - [`retinex`](mod@retinex): a Land–McCann / Horn Retinex (threshold small log-luminance gradients,
//!   reintegrate the rest).
//! - [`highpass`]: a high-pass model after Shapiro & Lu (2011): the image minus its blur.
//! - [`benchmark`]: scores of model predictions against human data (direction of effect,
//!   Spearman rank correlation).
//! - [`checker`]: the checker-shadow analysis (what each model predicts for squares A and B).
//! - [`fading`]: the fading (Troxler) disk: border band-pass energy and a temporal adaptation
//!   model with fixational jitter.
//!
//! [`Model`] runs any of the five models by name; [`target_means`] summarises an output per
//! target label.

pub mod benchmark;
pub mod checker;
pub mod fading;
pub mod highpass;
pub mod odog;
pub mod retinex;

pub use checker::{checker_shadow, CheckerReport};
pub use highpass::HighPass;
pub use odog::{Odog, OdogOptions, Variant};
pub use retinex::{retinex, RetinexOptions, RetinexOutput};

use crate::error::{Error, Result};
use crate::grid::{Image, Labels};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// A lightness model chosen by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// One of the ODOG family.
    Odog(Variant),
    /// Retinex with the default settings.
    Retinex,
    /// The high-pass model ([`HighPass`]) with its default σ.
    HighPass,
}

impl Model {
    /// The names accepted by [`FromStr`].
    pub const NAMES: [&'static str; 5] = ["odog", "lodog", "flodog", "retinex", "highpass"];

    /// The model's name.
    pub fn name(&self) -> &'static str {
        match self {
            Model::Odog(v) => v.name(),
            Model::Retinex => "retinex",
            Model::HighPass => "highpass",
        }
    }

    /// The name as the literature writes it, for titles and captions: ODOG, LODOG, FLODOG
    /// (Blakeslee & McCourt; Robinson, Hammon & de Sa), Retinex (Land & McCann), High-pass
    /// (Shapiro & Lu).
    pub fn title(&self) -> &'static str {
        match self {
            Model::Odog(Variant::Odog) => "ODOG",
            Model::Odog(Variant::Lodog) => "LODOG",
            Model::Odog(Variant::Flodog) => "FLODOG",
            Model::Retinex => "Retinex",
            Model::HighPass => "High-pass",
        }
    }

    /// Whether the model needs the image's resolution in pixels per degree (the filter models
    /// are defined in degrees; Retinex works on neighbouring pixels).
    pub fn needs_ppd(&self) -> bool {
        matches!(self, Model::Odog(_) | Model::HighPass)
    }

    /// Whether the output is signed about zero (the filter models) rather than a reflectance
    /// estimate in 0..1 (Retinex).
    pub fn signed(&self) -> bool {
        !matches!(self, Model::Retinex)
    }

    /// The model's output for `image` (linear luminance): arbitrary units for the ODOG family
    /// (positive = brighter), estimated reflectance with the lightest pixel 1 for Retinex,
    /// luminance minus its blur for the high-pass model.
    pub fn predict(&self, image: &Image, ppd: Option<f64>) -> Result<Image> {
        match self {
            Model::Odog(v) => {
                let ppd = ppd.ok_or_else(|| {
                    Error::invalid(format!(
                        "the {} model needs the resolution in pixels per degree",
                        v.name()
                    ))
                })?;
                Odog::new(image.width(), image.height(), ppd, *v)?.apply(image)
            }
            Model::Retinex => Ok(retinex(image, None, &RetinexOptions::default())?.lightness),
            Model::HighPass => {
                let ppd = ppd.ok_or_else(|| {
                    Error::invalid("the highpass model needs the resolution in pixels per degree")
                })?;
                HighPass::default().apply(image, ppd)
            }
        }
    }
}

impl fmt::Display for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Model {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        if s.trim().eq_ignore_ascii_case("retinex") {
            return Ok(Model::Retinex);
        }
        if s.trim().eq_ignore_ascii_case("highpass") {
            return Ok(Model::HighPass);
        }
        s.parse::<Variant>()
            .map(Model::Odog)
            .map_err(|_| Error::unknown("model", s, &Model::NAMES))
    }
}

/// The mean model output and luminance over one target label.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TargetMean {
    /// The label value (1..).
    pub label: u16,
    /// The target's name ("target N" when unnamed).
    pub name: String,
    /// Pixels with this label.
    pub pixels: usize,
    /// Mean input luminance over the target.
    pub luminance: f64,
    /// Mean model output over the target.
    pub output: f64,
}

/// Mean `output` and `image` luminance per non-zero label of `labels`, in label order; label
/// k is called `names[k − 1]` where given.
pub fn target_means(
    output: &Image,
    image: &Image,
    labels: &Labels,
    names: &[String],
) -> Result<Vec<TargetMean>> {
    labels.check_same_size("the target mask is", output, "the image is")?;
    output.check_same_size("the model output is", image, "the image is")?;
    let top = labels.data().iter().copied().max().unwrap_or(0) as usize;
    let mut sums = vec![(0.0, 0.0, 0usize); top + 1];
    for ((&l, &o), &v) in labels.data().iter().zip(output.data()).zip(image.data()) {
        let s = &mut sums[l as usize];
        s.0 += o;
        s.1 += v;
        s.2 += 1;
    }
    Ok(sums
        .iter()
        .enumerate()
        .skip(1)
        .filter(|(_, s)| s.2 > 0)
        .map(|(l, &(o, v, n))| TargetMean {
            label: l as u16,
            name: names
                .get(l - 1)
                .cloned()
                .unwrap_or_else(|| format!("target {l}")),
            pixels: n,
            luminance: v / n as f64,
            output: o / n as f64,
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    #[test]
    fn model_names_round_trip() {
        for n in Model::NAMES {
            assert_eq!(n.parse::<Model>().unwrap().name(), n);
        }
        let e = "odg".parse::<Model>().unwrap_err().to_string();
        assert!(e.contains("odog, lodog, flodog, retinex, highpass"), "{e}");
        assert!(Model::Odog(Variant::Lodog).needs_ppd() && !Model::Retinex.needs_ppd());
        let err = Model::Odog(Variant::Odog)
            .predict(&Grid::new(8, 8, 0.5), None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("pixels per degree"), "{err}");
    }

    #[test]
    fn target_means_per_label() {
        let labels = Grid::from_fn(4, 2, |c, _| if c < 2 { 1u16 } else { 3 });
        let out = Grid::from_fn(4, 2, |c, r| (c + 4 * r) as f64);
        let image = Grid::new(4, 2, 0.25);
        let m = target_means(&out, &image, &labels, &["left".into()]).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(
            (m[0].label, m[0].name.as_str(), m[0].pixels),
            (1, "left", 4)
        );
        assert_eq!(m[0].output, (0.0 + 1.0 + 4.0 + 5.0) / 4.0);
        assert_eq!((m[1].label, m[1].name.as_str()), (3, "target 3"));
        assert_eq!(m[1].luminance, 0.25);
        let err = target_means(&out, &image, &Grid::new(3, 2, 1u16), &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "the target mask is 2 px high × 3 px wide but the image is 2 px high × 4 px wide"
        );
        let err = target_means(&out, &Grid::new(4, 3, 0.25), &labels, &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "the model output is 2 px high × 4 px wide but the image is 3 px high × 4 px wide"
        );
    }
}

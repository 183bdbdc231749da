//! Where an analysed picture comes from: an image file (PNG or `.npy`) or a stimulus rendered on
//! the spot, with its resolution and target labels when they are known.

use crate::error::{Error, Result};
use crate::grid::{Image, Labels};
use crate::io;
use crate::stimulus::{self, Pixels};
use crate::visual_size::SizeRequest;
use serde_json::{json, Map, Value};
use std::path::PathBuf;

/// Plain values naming a picture: exactly one of `image` and `stimulus`.
#[derive(Debug, Clone, Default)]
pub struct PictureSource {
    /// An 8/16-bit PNG (linear values) or a float H×W `.npy`.
    pub image: Option<PathBuf>,
    /// A stimulus to render (see [`crate::stimulus::names`]), analysed with its own targets.
    pub stimulus: Option<String>,
    /// The stimulus's parameters (checked against its declarations when it is rendered).
    pub params: Map<String, Value>,
    /// The stimulus seed (default 0).
    pub seed: Option<u64>,
    /// Pixels per degree: the image's resolution, or the one to render the stimulus at.
    pub ppd: Option<f64>,
    /// Target labels: an 8/16-bit grayscale PNG, 0 = background, 1..N = targets.
    pub mask: Option<PathBuf>,
    /// The largest picture accepted or made, in pixels.
    pub max_pixels: usize,
}

/// A loaded picture with what is known about it.
#[derive(Debug, Clone)]
pub struct Picture {
    /// The pixels (gray or RGB).
    pub pixels: Pixels,
    /// Pixels per degree, when known.
    pub ppd: Option<f64>,
    /// Target labels and their names (names empty when the labels came from a file).
    pub labels: Option<(Labels, Vec<String>)>,
    /// Where it came from, for reports.
    pub origin: Value,
}

impl Picture {
    /// The luminance of the pixels (Rec. 709 weights for colour).
    pub fn luminance(&self) -> Image {
        self.pixels.luminance()
    }
}

impl PictureSource {
    /// Checks what needs no file: a positive resolution and exactly one source.
    pub fn check(&self) -> Result<()> {
        if let Some(p) = self.ppd {
            if !(p.is_finite() && p > 0.0) {
                return Err(Error::invalid(format!(
                    "ppd {p} must be a positive number of pixels per degree"
                )));
            }
        }
        match (&self.image, &self.stimulus) {
            (None, None) => Err(Error::invalid("give an image file or a stimulus name")),
            (Some(_), Some(_)) => Err(Error::invalid(
                "give an image file or a stimulus name, not both",
            )),
            _ => Ok(()),
        }
    }

    /// Reads the image or renders the stimulus; with `colour`, PNGs are read as RGB.
    pub fn load(&self, colour: bool) -> Result<Picture> {
        Ok(self.load_shaped(colour, None)?.0)
    }

    /// Like [`load`](Self::load), but a stimulus is rendered `shape` = (width, height) pixels
    /// when given, and its request (resolved parameters and geometry) comes back too (`None`
    /// for an image file).
    pub fn load_shaped(
        &self,
        colour: bool,
        shape: Option<(usize, usize)>,
    ) -> Result<(Picture, Option<stimulus::Request>)> {
        self.check()?;
        let max_pixels = self.max_pixels;
        let mut request = None;
        let mut picture = match (&self.image, &self.stimulus) {
            (Some(path), _) => {
                let pixels = if colour && io::extension(path) == "png" {
                    Pixels::Rgb(io::read_rgb(path, max_pixels)?)
                } else {
                    Pixels::Gray(io::read_luminance(path, max_pixels)?.0)
                };
                check_finite(&pixels, &path.display().to_string())?;
                Picture {
                    pixels,
                    ppd: self.ppd,
                    labels: None,
                    origin: json!({ "image": path.display().to_string() }),
                }
            }
            (None, Some(name)) => {
                let size = SizeRequest {
                    ppd: self.ppd,
                    shape: shape.map(|(w, h)| (h, w)),
                    ..Default::default()
                };
                let seed = self.seed.unwrap_or(0);
                let (made, output) =
                    stimulus::generate(name, &self.params, &size, seed, max_pixels)?;
                let picture = Picture {
                    pixels: output.pixels,
                    ppd: Some(made.geometry.ppd),
                    labels: output.targets.map(|t| (t.labels, t.names)),
                    origin: json!({
                        "stimulus": name,
                        "parameters": made.params.to_json(),
                        "seed": seed,
                        "geometry": made.geometry,
                        "notes": output.notes,
                    }),
                };
                request = Some(made);
                picture
            }
            (None, None) => return Err(Error::invalid("give an image file or a stimulus name")),
        };
        if let Some(path) = &self.mask {
            let labels = io::read_labels(path, max_pixels)?;
            let (w, h) = picture.pixels.size();
            if (labels.width(), labels.height()) != (w, h) {
                return Err(Error::invalid(format!(
                    "mask {} is {}x{} but the image is {w}x{h}",
                    path.display(),
                    labels.width(),
                    labels.height()
                )));
            }
            picture.labels = Some((labels, Vec::new()));
        }
        Ok((picture, request))
    }
}

/// Fails on the first NaN or infinity, naming its column and row.
fn check_finite(pixels: &Pixels, what: &str) -> Result<()> {
    let bad = match pixels {
        Pixels::Gray(i) => i.data().iter().position(|v| !v.is_finite()),
        Pixels::Rgb(i) => i
            .data()
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite())),
    };
    if let Some(i) = bad {
        let w = pixels.size().0;
        return Err(Error::invalid(format!(
            "{what}: the image has a non-finite value (NaN or Inf) at column {}, row {}",
            i % w,
            i / w
        )));
    }
    Ok(())
}

//! Where an analysed picture comes from: an image file (PNG or `.npy`) or a stimulus rendered on
//! the spot, with its resolution and target labels when they are known.

use crate::error::{Error, Result};
use crate::grid::{Image, Labels};
use crate::io;
use crate::stimulus::{self, Pixels};
use crate::visual_size::SizeRequest;
use serde_json::{json, Map, Value};
use std::path::PathBuf;

/// How a picture handed over in memory is named in reports and errors.
pub const IN_MEMORY: &str = "<array>";

/// Plain values naming a picture: exactly one of `image`, `stimulus` and `pixels`.
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
    /// A picture already in memory (e.g. the Python module's NumPy array), checked as a file's
    /// would be.
    pub pixels: Option<Pixels>,
    /// Target labels in memory (0 = background, 1..N = targets), instead of a `mask` file.
    pub labels: Option<Labels>,
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
        let given = [
            self.image.is_some(),
            self.stimulus.is_some(),
            self.pixels.is_some(),
        ];
        match given.iter().filter(|g| **g).count() {
            0 => Err(Error::invalid("give an image file or a stimulus name")),
            1 if self.mask.is_some() && self.labels.is_some() => Err(Error::invalid(
                "give target labels as a mask file or in memory, not both",
            )),
            1 => Ok(()),
            _ => Err(Error::invalid(
                "give an image file or a stimulus name, not both",
            )),
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
            (None, None) if self.pixels.is_some() => {
                let pixels = self.in_memory(colour)?;
                Picture {
                    pixels,
                    ppd: self.ppd,
                    labels: None,
                    origin: json!({ "image": IN_MEMORY }),
                }
            }
            (Some(path), _) => {
                let pixels = if colour && io::extension(path) == "png" {
                    Pixels::Rgb(io::read_rgb(path, max_pixels)?)
                } else {
                    Pixels::Gray(io::read_luminance(path, max_pixels)?.0)
                };
                let (values, channels) = match &pixels {
                    Pixels::Gray(i) => (i.data(), 1),
                    Pixels::Rgb(i) => (i.data().as_flattened(), 3),
                };
                check_finite(
                    values,
                    channels,
                    pixels.size().0,
                    &path.display().to_string(),
                )?;
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
        if let Some(labels) = &self.labels {
            let (w, h) = picture.pixels.size();
            if (labels.width(), labels.height()) != (w, h) {
                return Err(Error::invalid(format!(
                    "the target labels are {}x{} but the image is {w}x{h}",
                    labels.width(),
                    labels.height()
                )));
            }
            picture.labels = Some((labels.clone(), Vec::new()));
        }
        Ok((picture, request))
    }

    /// The in-memory picture, checked as a file's would be (size, finite values); gray unless
    /// `colour`.
    fn in_memory(&self, colour: bool) -> Result<Pixels> {
        let Some(pixels) = &self.pixels else {
            return Err(Error::invalid("give an image file or a stimulus name"));
        };
        let (w, h) = pixels.size();
        crate::grid::check_size(w, h, self.max_pixels)?;
        let (values, channels) = match pixels {
            Pixels::Gray(i) => (i.data(), 1),
            Pixels::Rgb(i) => (i.data().as_flattened(), 3),
        };
        check_finite(values, channels, w, IN_MEMORY)?;
        Ok(match pixels {
            Pixels::Rgb(_) if !colour => Pixels::Gray(pixels.luminance()),
            _ => pixels.clone(),
        })
    }
}

/// Fails on the first NaN or infinity of a picture `width` pixels wide with `channels` values
/// per pixel, naming its column and row.
pub(crate) fn check_finite(
    values: &[f64],
    channels: usize,
    width: usize,
    what: &str,
) -> Result<()> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let pixel = i / channels.max(1);
        let w = width.max(1);
        return Err(Error::invalid(format!(
            "{what}: the image has a non-finite value (NaN or Inf) at column {}, row {}",
            pixel % w,
            pixel / w
        )));
    }
    Ok(())
}

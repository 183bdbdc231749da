//! `shadelab analyze …`: analyses of an image or a rendered stimulus. Each analysis is a
//! subcommand in its own file; this file holds the group and the input handling they share
//! (an image file or `--stimulus NAME`, its resolution and its target labels).

mod fading;
mod lightness;
mod observer;
mod perception;
mod prior_sweep;

use super::{CliError, CliResult, Global};
use serde_json::{json, Map, Value};
use shadelab::grid::{Image, Labels};
use shadelab::io;
use shadelab::stimulus::{self, Pixels};
use shadelab::visual_size::SizeRequest;
use std::path::PathBuf;

/// Arguments of `analyze`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, clap::Subcommand)]
enum Command {
    /// Lightness models (ODOG, LODOG, FLODOG, Retinex) on an image or stimulus, with the mean
    /// output per target.
    Lightness(lightness::Args),
    /// The fading (Troxler) disk: border band-pass energy of a blurred vs a sharp disk and a
    /// temporal adaptation model with fixational jitter, as numbers and an animation.
    Fading(fading::Args),
    /// Shape from shading under each assumed light tilt: each token's convexity, residual and
    /// smoothness, and the tilts where it flips between convex and concave.
    PriorSweep(prior_sweep::Args),
    /// A Bayesian observer (von Mises light prior, convexity prior, residual likelihood):
    /// P(convex) against the picture's rotation.
    Observer(observer::Args),
}

/// Runs `analyze`.
pub fn run(args: Args, global: &Global) -> CliResult {
    match args.command {
        Command::Lightness(a) => lightness::run(a, global),
        Command::Fading(a) => fading::run(a, global),
        Command::PriorSweep(a) => prior_sweep::run(a, global),
        Command::Observer(a) => observer::run(a, global),
    }
}

/// Where the picture comes from: a file or a stimulus rendered on the spot.
#[derive(Debug, clap::Args)]
pub struct Source {
    /// The image: an 8/16-bit PNG (linear values) or a float H×W .npy. Or give --stimulus.
    pub image: Option<PathBuf>,
    /// Render this stimulus (see `shadelab list`) and analyse it with its own target mask.
    #[arg(long, value_name = "NAME", conflicts_with = "image")]
    pub stimulus: Option<String>,
    /// A stimulus parameter (repeatable; with --stimulus).
    #[arg(long = "set", value_name = "KEY=VALUE", requires = "stimulus", value_parser = super::render::utf8_text())]
    pub set: Vec<String>,
    /// The stimulus seed (with --stimulus).
    #[arg(long, requires = "stimulus", allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Pixels per degree: the image's resolution (the filter models work in degrees), or the
    /// resolution to render the stimulus at.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub ppd: Option<f64>,
    /// Target labels: an 8/16-bit grayscale PNG, 0 = background, 1..N = targets (default:
    /// the stimulus's own target mask).
    #[arg(long, value_name = "PNG")]
    pub mask: Option<PathBuf>,
}

/// A loaded picture with what is known about it.
pub struct Input {
    /// The pixels (gray or RGB).
    pub pixels: Pixels,
    /// Pixels per degree, when known.
    pub ppd: Option<f64>,
    /// Target labels and names, when known.
    pub labels: Option<(Labels, Vec<String>)>,
    /// Where it came from, for the report.
    pub origin: Value,
}

impl Input {
    /// The luminance of the pixels.
    pub fn luminance(&self) -> Image {
        self.pixels.luminance()
    }
}

impl Source {
    /// Checks the flags that need no file: --ppd and that exactly one source is given.
    pub fn check(&self) -> CliResult {
        if let Some(p) = self.ppd {
            if !(p.is_finite() && p > 0.0) {
                return Err(CliError::usage(format!(
                    "--ppd {p} must be a positive number of pixels per degree"
                )));
            }
        }
        if self.image.is_none() && self.stimulus.is_none() {
            return Err(CliError::usage(
                "give an IMAGE (.png or .npy) or --stimulus NAME",
            ));
        }
        Ok(())
    }

    /// Reads the image or renders the stimulus; with `colour`, PNGs are read as RGB.
    pub fn load(&self, colour: bool, global: &Global) -> Result<Input, CliError> {
        self.check()?;
        let mut input = match (&self.image, &self.stimulus) {
            (Some(path), _) => {
                let pixels = match io::extension(path).as_str() {
                    "png" if colour => Pixels::Rgb(io::read_rgb(path, global.max_pixels)?),
                    "png" => Pixels::Gray(io::read_gray(path, global.max_pixels)?.0),
                    "npy" => Pixels::Gray(io::read_image(path, global.max_pixels)?),
                    other => {
                        return Err(CliError::usage(format!(
                            "{}: IMAGE must be a .png or .npy file (got '.{other}')",
                            path.display()
                        )))
                    }
                };
                check_finite(&pixels, &path.display().to_string())?;
                Input {
                    pixels,
                    ppd: self.ppd,
                    labels: None,
                    origin: json!({ "image": path.display().to_string() }),
                }
            }
            (None, Some(name)) => {
                let given: Map<String, Value> = shadelab::params::Params::parse_pairs(&self.set)?;
                let size = SizeRequest {
                    ppd: self.ppd,
                    ..Default::default()
                };
                let seed = self.seed.unwrap_or(0);
                let (request, output) =
                    stimulus::generate(name, &given, &size, seed, global.max_pixels)?;
                Input {
                    pixels: output.pixels,
                    ppd: Some(request.geometry.ppd),
                    labels: output.targets.map(|t| (t.labels, t.names)),
                    origin: json!({
                        "stimulus": name,
                        "parameters": request.params.to_json(),
                        "seed": seed,
                        "geometry": request.geometry,
                        "notes": output.notes,
                    }),
                }
            }
            (None, None) => {
                return Err(CliError::usage(
                    "give an IMAGE (.png or .npy) or --stimulus NAME",
                ))
            }
        };
        if let Some(path) = &self.mask {
            let labels = io::read_labels(path, global.max_pixels)?;
            let (w, h) = input.pixels.size();
            if (labels.width(), labels.height()) != (w, h) {
                return Err(CliError::usage(format!(
                    "mask {} is {}x{} but the image is {w}x{h}",
                    path.display(),
                    labels.width(),
                    labels.height()
                )));
            }
            input.labels = Some((labels, Vec::new()));
        }
        Ok(input)
    }
}

fn check_finite(pixels: &Pixels, what: &str) -> CliResult {
    let bad = match pixels {
        Pixels::Gray(i) => i.data().iter().position(|v| !v.is_finite()),
        Pixels::Rgb(i) => i
            .data()
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite())),
    };
    if let Some(i) = bad {
        let w = pixels.size().0;
        return Err(CliError::usage(format!(
            "{what}: the image has a non-finite value (NaN or Inf) at column {}, row {}",
            i % w,
            i / w
        )));
    }
    Ok(())
}

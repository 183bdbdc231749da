//! `shadelab analyze …`: analyses of an image or a rendered stimulus. Each analysis is a
//! subcommand in its own file; this file holds the group and the input handling they share
//! (an image file or `--stimulus NAME`, its resolution and its target labels).

mod fading;
mod lightness;
mod observer;
mod outline;
mod perception;
mod prior_sweep;

use super::{CliError, CliResult, Global};
use shadelab::pipeline::PictureSource;
use std::path::PathBuf;

/// The subcommands of `analyze`.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
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
    /// The outline decides (Knill & Kersten): per target strip, the shape its outline implies,
    /// the shading that shape predicts, what it explains and what is left as paint.
    Outline(outline::Args),
}

/// Runs `analyze`: what was read with the picture (its sidecar, the note that an 8-bit picture
/// without a gamma chunk was decoded as sRGB) is said by the library as it reads it, once.
pub fn run(command: Command, global: &Global) -> CliResult {
    match command {
        Command::Lightness(a) => lightness::run(a, global),
        Command::Fading(a) => fading::run(a, global),
        Command::PriorSweep(a) => prior_sweep::run(a, global),
        Command::Observer(a) => observer::run(a, global),
        Command::Outline(a) => outline::run(a, global),
    }
}

/// The size to render a stimulus at (`--size`, with --stimulus).
#[derive(Debug, clap::Args)]
pub struct RenderSize {
    /// Size of the rendered stimulus in pixels: N (square) or WxH (with --stimulus).
    #[arg(
        long,
        value_name = "N|WxH",
        requires = "stimulus",
        allow_hyphen_values = true
    )]
    size: Option<String>,
}

impl RenderSize {
    /// The size as the library takes it, (height, width); `None` when not given.
    pub fn get(&self) -> Result<Option<(usize, usize)>, CliError> {
        match &self.size {
            Some(text) => Ok(Some(shadelab::parse_size(text, "--size")?)),
            None => Ok(None),
        }
    }
}

/// Where the picture comes from: a file or a stimulus rendered on the spot.
#[derive(Debug, clap::Args)]
pub struct Source {
    /// The image: an 8/16-bit PNG, a JPEG or a 16-bit TIFF (decoded as --input-gamma says) or an H×W .npy (float 0..1, or uint8/uint16 scaled by their largest value; H×W×3 RGB becomes luminance); a shadelab sidecar
    /// beside it (IMAGE.json) gives its target mask and names, ppd, albedo, ambient, gamma and
    /// true light (flags given win). Or give --stimulus or --spec.
    pub image: Option<PathBuf>,
    /// Render this stimulus (see `shadelab list`) and analyse it with its own target mask.
    #[arg(long, value_name = "NAME", conflicts_with_all = ["image", "spec"])]
    pub stimulus: Option<String>,
    /// Render this stimulus spec or shadelab sidecar in memory (as `render --spec`) and
    /// analyse it with its own target mask.
    #[arg(long, value_name = "JSON", conflicts_with = "image")]
    pub spec: Option<PathBuf>,
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
    #[arg(long, value_name = "auto|srgb|linear|G", default_value = "auto", help = super::flags::INPUT_GAMMA_HELP)]
    pub input_gamma: String,
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
        if self.image.is_none() && self.stimulus.is_none() && self.spec.is_none() {
            return Err(CliError::usage(
                "give an IMAGE (.png, .jpg, .tif or .npy), --stimulus NAME or --spec FILE.json",
            ));
        }
        super::flags::input_gamma(&self.input_gamma)?;
        Ok(())
    }

    /// The library's description of the picture, from the flags; says on stderr what the
    /// image's sidecar gives (unless quiet).
    pub fn to_library(&self, global: &Global) -> Result<PictureSource, CliError> {
        self.check()?;
        let source = PictureSource {
            image: self.image.clone(),
            spec: self.spec.clone(),
            stimulus: self.stimulus.clone(),
            params: shadelab::Params::parse_pairs(&self.set)?,
            seed: self.seed,
            ppd: self.ppd,
            mask: self.mask.clone(),
            max_pixels: global.max_pixels,
            input_encoding: super::flags::input_gamma(&self.input_gamma)?,
            ..Default::default()
        };
        Ok(source)
    }
}
